//! The requirement grammar: `FIGURE <= VALUE` or `FIGURE >= VALUE` on one figure of an
//! output's distribution (a percentile, the mean, the sd, Cp, Cpk, ppm out of spec). One
//! parser for `rvtol allocate --target`, the gate's requirements (`check --require`, a
//! baseline's `requirements`) and the page, so all three read a target alike.

/// A figure of an output's distribution that a target constrains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TargetFigure {
    /// The percentile at this percent (0 < p < 100).
    Percentile(f64),
    /// The mean.
    Mean,
    /// The standard deviation.
    Sd,
    /// Cp from the moments (needs both spec limits).
    Cp,
    /// Cpk from the moments (needs a spec limit).
    Cpk,
    /// Parts per million outside the spec limits.
    PpmOut,
}

impl TargetFigure {
    /// The figure's name as written in a target.
    pub fn label(self) -> String {
        match self {
            TargetFigure::Percentile(p) => format!("p{p}"),
            TargetFigure::Mean => "mean".into(),
            TargetFigure::Sd => "sd".into(),
            TargetFigure::Cp => "cp".into(),
            TargetFigure::Cpk => "cpk".into(),
            TargetFigure::PpmOut => "ppm_out".into(),
        }
    }
}

/// `figure <= value` or `figure >= value`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// The constrained figure.
    pub figure: TargetFigure,
    /// True for `<=`, false for `>=`.
    pub at_most: bool,
    /// The bound.
    pub value: f64,
}

impl Target {
    /// Parses `p99.865 <= 1.0`, `cpk >= 1.33`, `ppm_out <= 100`, `sd <= 0.01`,
    /// `mean <= 0.8`, `cp >= 1.67`, `p0.135 >= 0.1`.
    pub fn parse(text: &str) -> Result<Target, String> {
        const USAGE: &str = "expected FIGURE <= VALUE or FIGURE >= VALUE with FIGURE one of \
                             pPERCENT (e.g. p99.865), mean, sd, cp, cpk, ppm_out";
        let (lhs, at_most, rhs) = if let Some((l, r)) = text.split_once("<=") {
            (l, true, r)
        } else if let Some((l, r)) = text.split_once(">=") {
            (l, false, r)
        } else {
            return Err(format!("{text:?}: {USAGE}"));
        };
        let name = lhs.trim().to_ascii_lowercase();
        let figure = match name.as_str() {
            "mean" => TargetFigure::Mean,
            "sd" => TargetFigure::Sd,
            "cp" => TargetFigure::Cp,
            "cpk" => TargetFigure::Cpk,
            "ppm_out" | "ppm" => TargetFigure::PpmOut,
            other => {
                let percent = other
                    .strip_prefix('p')
                    .and_then(|p| p.parse::<f64>().ok())
                    .ok_or_else(|| format!("{text:?}: unknown figure {other:?}; {USAGE}"))?;
                if !(percent > 0.0 && percent < 100.0) {
                    return Err(format!(
                        "{text:?}: the percentile must lie strictly between 0 and 100"
                    ));
                }
                TargetFigure::Percentile(percent)
            }
        };
        let value: f64 = rhs
            .trim()
            .parse()
            .map_err(|_| format!("{text:?}: {:?} is not a number; {USAGE}", rhs.trim()))?;
        if !value.is_finite() {
            return Err(format!("{text:?}: the bound must be finite"));
        }
        match figure {
            TargetFigure::Cp | TargetFigure::Cpk if at_most => {
                return Err(format!(
                    "{text:?}: a capability target reads {} >= VALUE",
                    figure.label()
                ))
            }
            TargetFigure::Sd | TargetFigure::PpmOut if !at_most => {
                return Err(format!(
                    "{text:?}: a spread target reads {} <= VALUE",
                    figure.label()
                ))
            }
            TargetFigure::Sd | TargetFigure::PpmOut | TargetFigure::Cp | TargetFigure::Cpk
                if value <= 0.0 =>
            {
                return Err(format!("{text:?}: the bound must be > 0"))
            }
            _ => {}
        }
        Ok(Target {
            figure,
            at_most,
            value,
        })
    }

    /// The expression, normalised.
    pub fn expression(&self) -> String {
        format!(
            "{} {} {}",
            self.figure.label(),
            if self.at_most { "<=" } else { ">=" },
            self.value
        )
    }

    /// How far `figure` is on the wrong side of the bound (≤ 0 when met).
    pub fn excess(&self, figure: f64) -> f64 {
        if self.at_most {
            figure - self.value
        } else {
            self.value - figure
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_parse() {
        let t = Target::parse("p99.865 <= 1.0").unwrap();
        assert_eq!(t.figure, TargetFigure::Percentile(99.865));
        assert!(t.at_most);
        assert_eq!(t.value, 1.0);
        let t = Target::parse(" CPK>=1.33").unwrap();
        assert_eq!(
            (t.figure, t.at_most, t.value),
            (TargetFigure::Cpk, false, 1.33)
        );
        let t = Target::parse("ppm_out <= 100").unwrap();
        assert_eq!(t.figure, TargetFigure::PpmOut);
        assert_eq!(t.expression(), "ppm_out <= 100");
        for bad in [
            "p99.865 < 1",
            "p100 <= 1",
            "p0 <= 1",
            "q5 <= 1",
            "sd <= x",
            "cpk <= 2",
            "sd >= 1",
            "ppm_out <= 0",
            "sd <= inf",
        ] {
            assert!(Target::parse(bad).is_err(), "{bad} parsed");
        }
    }

    #[test]
    fn excess_sign() {
        let le = Target::parse("sd <= 2").unwrap();
        assert!(le.excess(1.5) < 0.0 && le.excess(2.5) > 0.0);
        let ge = Target::parse("cpk >= 1.33").unwrap();
        assert!(ge.excess(1.5) < 0.0 && ge.excess(1.0) > 0.0);
    }
}
