//! The CI gate: `rvtol baseline` records the distribution figures of every output with the
//! band a re-run may move within by Monte Carlo noise alone; `rvtol check` re-runs and
//! flags every figure outside its band.
//!
//! Gated figures per continuous output: mean, sd, the percentiles 0.135, 2.275, 50,
//! 97.725, 99.865, and ppm out of spec when the scenario sets limits; per indicator
//! output: its fraction. Bands, for a re-run with another seed and the same sample count
//! (two independent estimates, hence the factor √2 on a one-sample interval):
//!
//! - percentile p: ± √2·(X_(u) − X_(l))/2 about the estimate, from the order statistics
//!   of ranks l, u = n·p ∓ z·√(n·p·(1 − p)) (normal approximation to the binomial count of
//!   values below the true quantile). (X_(u) − X_(l))/2 is z times the sparsity estimate of
//!   the percentile's standard error √(p(1 − p)/n)/f(x_p) (Siddiqui 1960, Bofinger 1975: a
//!   central difference of the quantile function); the difference of two independent
//!   estimates is symmetric, so the band is too. (Widening each side of the one-sample
//!   interval instead would leave a narrow side where the density is high: in a tail, the
//!   side towards the body, where a re-run then fails far more often than α says.)
//! - mean: ± √2·z·sd/√n; sd: ± √2·z·sd·√((g2 + 2)/(4n)) (delta method, g2 the excess
//!   kurtosis); ppm and fractions: ± √2·z·√(p(1 − p)/n) with p at least 1/n.
//!
//! z = Φ⁻¹(1 − α/(2m)) for m gated figures and a family-wise false-alarm level α = 1 %
//! (Bonferroni), so an unchanged scenario fails with probability at most 1 %. The same seed
//! and sample count reproduce every figure exactly. A figure may instead carry an
//! absolute or relative tolerance in the baseline file, which then replaces its band.
//!
//! Memory is bounded as in `rvtol run`: beyond the exact-percentile limit the percentiles
//! come from the run's quantile sketch and each percentile's order statistics are moved out
//! by the sketch's error bound (α·|x − centre|) before the band is formed.

use rvtol_deviation::Shown;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::target::{Target, TargetFigure};
use rvtol_engine::figures::{output_figures, OrderStatistics, PERCENTS};
use rvtol_engine::format::escape_markup;
use rvtol_engine::run::{
    check_non_finite, run, ReplicateFigures, RunResult, RunSettings, DEFAULT_EXACT_PERCENTILE_LIMIT,
};
use rvtol_engine::scenario::{OutputInfo, Scenario, ScenarioError};
use rvtol_engine::stats::{
    capability_from_moments, proportion_standard_error, replicate_standard_error,
    student_t_quantile,
};
use rvtol_models::OutputKind;

/// Family-wise false-alarm level of a check.
pub const FAMILY_FALSE_ALARM: f64 = 0.01;
/// Percentiles the gate watches.
pub const GATED_PERCENTS: [(&str, f64); 5] = [
    ("p0.135", 0.135),
    ("p2.275", 2.275),
    ("p50", 50.0),
    ("p97.725", 97.725),
    ("p99.865", 99.865),
];

/// One gated figure of one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    /// Output name.
    pub output: String,
    /// Figure name: `mean`, `sd`, `p0.135` … `p99.865`, `ppm_out`, `fraction`.
    pub figure: String,
    /// Value of the baseline run: a number, or for a percentile beyond the limits
    /// ([`rvtol_engine::stats::conformity`]) "+inf" or "-inf".
    #[serde(with = "signed_infinity")]
    pub value: f64,
    /// Lowest value a re-run may give.
    #[serde(with = "signed_infinity")]
    pub lower: f64,
    /// Highest value a re-run may give.
    #[serde(with = "signed_infinity")]
    pub upper: f64,
    /// Absolute tolerance that replaces the band, when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub absolute_tolerance: Option<f64>,
    /// Relative tolerance (of |value|) that replaces the band, when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relative_tolerance: Option<f64>,
    /// The direction in which this figure gets worse: a one-sided check fails only on a
    /// move that way beyond the band (set by hand in the baseline file, or inferred by
    /// `rvtol check --one-sided`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub worse: Option<Worse>,
}

/// A baseline number that may be infinite (a percentile beyond the limits, or a band
/// that reaches into them): JSON has no infinity, so ±∞ is written "+inf" or "-inf".
mod signed_infinity {
    use serde::{de, Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(value: &f64, serializer: S) -> Result<S::Ok, S::Error> {
        match *value {
            f64::INFINITY => serializer.serialize_str("+inf"),
            f64::NEG_INFINITY => serializer.serialize_str("-inf"),
            v => serializer.serialize_f64(v),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f64, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Number {
            Finite(f64),
            Text(String),
        }
        match Number::deserialize(deserializer)? {
            Number::Finite(v) => Ok(v),
            Number::Text(text) => match text.as_str() {
                "+inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                other => Err(de::Error::custom(format!(
                    "expected a number, \"+inf\" or \"-inf\", got \"{other}\""
                ))),
            },
        }
    }
}

/// The direction in which a figure gets worse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Worse {
    /// A larger value is worse (a lost motion, an sd, a share out of spec).
    Higher,
    /// A smaller value is worse (a value with a lower spec limit only).
    Lower,
    /// Neither way is worse against the spec (the lower tail of an output with an upper
    /// limit only): the figure is reported and never fails a one-sided check.
    Neither,
}

impl Figure {
    /// The interval a re-run must fall in.
    pub fn allowed(&self) -> (f64, f64) {
        match (self.absolute_tolerance, self.relative_tolerance) {
            // Beyond the limits: a re-run must be beyond them too (or better, one-sided).
            _ if self.value.is_infinite() => (self.value, self.value),
            (Some(a), _) => (self.value - a, self.value + a),
            (None, Some(r)) => (
                self.value - r * self.value.abs(),
                self.value + r * self.value.abs(),
            ),
            (None, None) => (self.lower, self.upper),
        }
    }
}

/// A baseline file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Baseline {
    /// Version of rvtol that wrote it.
    pub rvtol_version: String,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text the baseline ran (data files written in), hex; absent
    /// in a baseline written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenario_sha256: Option<String>,
    /// The scenario file as it was, to point at what changed.
    pub scenario_file: serde_json::Value,
    /// Seed of the baseline run.
    pub seed: u64,
    /// Samples of the baseline run.
    pub samples: u64,
    /// Exact percentiles while samples × outputs stays within this many values, a sketch
    /// beyond it: a check re-runs with the same setting.
    #[serde(default = "default_exact_percentile_limit")]
    pub exact_percentile_limit: u64,
    /// Family-wise false-alarm level the bands are built for.
    pub family_false_alarm: f64,
    /// z of every band (Bonferroni over the figures).
    pub z: f64,
    /// The figures.
    pub figures: Vec<Figure>,
    /// Absolute requirements checked with every re-run (`OUTPUT FIGURE OP VALUE`, e.g.
    /// `hysteresis_arcmin p99.865 <= 1.5`), besides those given on the command line.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub requirements: Vec<String>,
}

fn default_exact_percentile_limit() -> u64 {
    DEFAULT_EXACT_PERCENTILE_LIMIT
}

/// A baseline file that cannot be read, or that does not fit the scenario it is checked
/// against, with the JSON path of the problem in the baseline file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct BaselineError {
    /// JSON path of the offending value in the baseline file.
    pub path: String,
    /// What is wrong, in one line.
    pub message: String,
}

impl BaselineError {
    /// A new error at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        BaselineError {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Why a check against a baseline cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CheckError {
    /// The scenario's problem (its run refused, its text not JSON).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The baseline's problem.
    #[error(transparent)]
    Baseline(#[from] BaselineError),
    /// A requirement given with the check (the command line's `--require`) that does not
    /// parse.
    #[error("--require: {0}")]
    Requirement(String),
}

impl Baseline {
    /// Parses a baseline file, with the JSON path of any problem.
    pub fn from_json(text: &str) -> Result<Baseline, BaselineError> {
        // A scenario or a report given for a baseline is named as such, not by its first
        // key; a damaged baseline is left to the field-by-field messages.
        if let Ok(serde_json::Value::Object(map)) = serde_json::from_str(text) {
            let looks_like = if map.contains_key("figures") {
                None
            } else if map.contains_key("models") {
                Some("a scenario")
            } else if map.contains_key("outputs") {
                Some("a report")
            } else {
                None
            };
            if let Some(looks_like) = looks_like {
                return Err(BaselineError::new(
                    "(root)",
                    format!(
                        "not a baseline but {looks_like} (no `figures`): `rvtol baseline SCENARIO -o FILE` writes one"
                    ),
                ));
            }
        }
        let mut deserializer = serde_json::Deserializer::from_str(text);
        let baseline: Baseline =
            serde_path_to_error::deserialize(&mut deserializer).map_err(|err| {
                let path = err.path().to_string();
                let inner = err.into_inner();
                if inner.is_syntax() || inner.is_eof() {
                    BaselineError::new("JSON syntax", inner.to_string())
                } else {
                    BaselineError::new(
                        if path == "." { "(root)".into() } else { path },
                        inner.to_string(),
                    )
                }
            })?;
        if baseline.samples == 0 {
            return Err(BaselineError::new("samples", "must be at least 1"));
        }
        if !(baseline.z.is_finite() && baseline.z > 0.0) {
            return Err(BaselineError::new(
                "z",
                format!("must be a positive number, got {}", Shown(baseline.z)),
            ));
        }
        if baseline.figures.is_empty() {
            return Err(BaselineError::new(
                "figures",
                "is empty: a check against no figures would pass whatever the scenario does; write the baseline again with rvtol baseline",
            ));
        }
        for (i, figure) in baseline.figures.iter().enumerate() {
            // Infinite: a percentile beyond the limits ("+inf"/"-inf", value and band
            // alike), or a finite one whose band reaches beyond them.
            let percentile = figure.figure.starts_with('p');
            let beyond = figure.value.is_infinite();
            for (key, value) in [
                ("value", figure.value),
                ("lower", figure.lower),
                ("upper", figure.upper),
            ] {
                let allowed = value.is_finite()
                    || (percentile && !value.is_nan() && (!beyond || value == figure.value));
                if !allowed {
                    return Err(BaselineError::new(
                        format!("figures[{i}].{key}"),
                        if percentile {
                            "must be a number, or \"+inf\"/\"-inf\" beyond the limits (as the value)"
                        } else {
                            "must be a finite number"
                        },
                    ));
                }
            }
            for (key, tolerance) in [
                ("absolute_tolerance", figure.absolute_tolerance),
                ("relative_tolerance", figure.relative_tolerance),
            ] {
                if let Some(t) = tolerance {
                    if !(t.is_finite() && t >= 0.0) {
                        return Err(BaselineError::new(
                            format!("figures[{i}].{key}"),
                            format!("must be a finite number ≥ 0, got {}", Shown(t)),
                        ));
                    }
                }
            }
            if !(figure.lower <= figure.value && figure.value <= figure.upper) {
                return Err(BaselineError::new(
                    format!("figures[{i}]"),
                    "needs lower ≤ value ≤ upper",
                ));
            }
        }
        Ok(baseline)
    }

    /// Checks that this baseline belongs to `scenario`: the same scenario name, and every
    /// figure names an output of it and a figure that output has. A mismatch is bad input
    /// (the wrong file), not a moved figure.
    pub fn matches(&self, scenario: &Scenario) -> Result<(), BaselineError> {
        if self.scenario != scenario.name {
            return Err(BaselineError::new(
                "scenario",
                format!(
                    "the baseline records scenario {:?}, not {:?}: check a scenario against its own baseline (rvtol baseline writes one)",
                    self.scenario, scenario.name
                ),
            ));
        }
        for (i, figure) in self.figures.iter().enumerate() {
            let Some(output) = scenario.outputs.iter().find(|o| o.name == figure.output) else {
                return Err(BaselineError::new(
                    format!("figures[{i}].output"),
                    format!(
                        "the scenario has no output {:?}; write the baseline again with rvtol baseline",
                        figure.output
                    ),
                ));
            };
            let known: Vec<&str> = match output.kind {
                OutputKind::Indicator => vec!["fraction"],
                OutputKind::Continuous => ["mean", "sd"]
                    .into_iter()
                    .chain(GATED_PERCENTS.iter().map(|(name, _)| *name))
                    .chain(output.spec.map(|_| "ppm_out"))
                    .collect(),
            };
            if !known.contains(&figure.figure.as_str()) {
                return Err(BaselineError::new(
                    format!("figures[{i}].figure"),
                    format!(
                        "{:?} is not a figure of {} (figures: {})",
                        figure.figure,
                        figure.output,
                        known.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The baseline file's text.
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("baseline serialises");
        text.push('\n');
        text
    }
}

/// Number of figures the gate watches in a scenario.
pub fn gated_figure_count(scenario: &Scenario) -> usize {
    scenario
        .outputs
        .iter()
        .map(|o| match o.kind {
            OutputKind::Indicator => 1,
            OutputKind::Continuous => 2 + GATED_PERCENTS.len() + usize::from(o.spec.is_some()),
        })
        .sum()
}

/// The band quantile for `figures` figures at the family-wise level.
pub fn band_z(figures: usize) -> f64 {
    let normal = Normal::new(0.0, 1.0).expect("standard normal");
    normal.inverse_cdf(1.0 - FAMILY_FALSE_ALARM / (2.0 * figures.max(1) as f64))
}

/// Runs the scenario and returns every gated figure with its band for a re-run at band
/// quantile `z`. Percentiles are exact order statistics while samples × outputs stays
/// within `exact_percentile_limit` values, and come from the run's quantile sketch beyond
/// it (bounded memory at any sample count); a sketch percentile's band is widened by the
/// sketch's error bound at each end.
pub fn measure(
    scenario: &Scenario,
    settings: RunSettings,
    z: f64,
    max_non_finite: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Figure>, ScenarioError> {
    Ok(measure_with_capability(scenario, settings, z, max_non_finite, progress)?.0)
}

/// [`measure`], and besides the gated figures Cp and Cpk from the moments of each output
/// with spec limits (for requirements only; not gated), with the same kind of band:
/// ± √2·z·SE, SE of Cp = Cp·SE(s)/s and of Cpk by the delta method (Bissell 1990 with the
/// excess kurtosis: Var = 1/(9n) + Cpk²·(g2 + 2)/(4n)). An index is left out when the
/// values do not show every sample out of spec (non-finite, excluded or flagged ones).
pub fn measure_with_capability(
    scenario: &Scenario,
    settings: RunSettings,
    z: f64,
    max_non_finite: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Vec<Figure>, Vec<Figure>), ScenarioError> {
    figures_of(
        scenario,
        run(scenario, settings, progress)?,
        z,
        max_non_finite,
    )
}

/// The gated figures and capability indices of [`measure_with_capability`] from a run's
/// result (a run, or the merge of its shards).
///
/// A Latin hypercube or RQMC run's rows are not independent: its mean, sd, percentiles
/// and ppm get their band from the spread of their R replicate values instead,
/// ± √2·t·s/√R with t the Student quantile (R − 1 degrees of freedom) of the same tail
/// probability as z (the figures' family false-alarm rate is kept). Where the replicates
/// agree exactly (a constant figure) the band is 0, except ppm out of spec with no
/// event in the run, which keeps its independent-rows band. Cp and Cpk keep theirs.
pub fn figures_of(
    scenario: &Scenario,
    mut result: RunResult,
    z: f64,
    max_non_finite: f64,
) -> Result<(Vec<Figure>, Vec<Figure>), ScenarioError> {
    check_non_finite(scenario, &result, max_non_finite)?;
    if let Some((info, _)) = (scenario.outputs.iter())
        .zip(&result.outputs)
        .find(|(_, acc)| acc.moments.n < 2)
    {
        return Err(ScenarioError::new(
            format!("(output {})", info.name),
            "fewer than 2 finite values: nothing to gate",
        ));
    }
    // The values of the figures are the run report's; the bands are the gate's.
    let values = output_figures(scenario, &mut result);
    let samples = result.samples;
    let bands = Bands::new(&result.replicates, z);
    let mut figures = Vec::new();
    let mut capability = Vec::new();
    for (o, ((info, acc), value)) in (scenario.outputs.iter())
        .zip(result.outputs)
        .zip(values)
        .enumerate()
    {
        let mut push = |figure: &str, value: f64, half: f64| {
            let list = if figure == "cp" || figure == "cpk" {
                &mut capability
            } else {
                &mut figures
            };
            list.push(Figure {
                output: info.name.clone(),
                figure: figure.to_string(),
                value,
                lower: value - half,
                upper: value + half,
                absolute_tolerance: None,
                relative_tolerance: None,
                worse: None,
            });
        };
        let n = acc.moments.n;
        if info.kind == OutputKind::Indicator {
            let fraction = value.fraction.unwrap_or(f64::NAN);
            let half = bands.two_sample * proportion_standard_error(fraction, n);
            push("fraction", fraction, half);
            continue;
        }
        let half = bands
            .replicate(o, &|r| r.mean)
            .unwrap_or_else(|| bands.two_sample * acc.moments.mean_standard_error());
        push("mean", value.mean, half);
        let half = bands
            .replicate(o, &|r| r.sd)
            .unwrap_or_else(|| bands.two_sample * acc.moments.sd_standard_error());
        push("sd", value.sd, half);
        let out = acc.out_of_spec(info.flagged_conform);
        let (min, max) = (acc.moments.min, acc.moments.max);
        let order = OrderStatistics::new(acc.kept, samples, info.spec, (min, max))
            .expect("the gate keeps the distribution of every continuous output");
        for (name, percent) in GATED_PERCENTS {
            let (reading, low, high) = order.percentile_with_interval(percent, z);
            let k = PERCENTS.iter().position(|p| p.1 == percent);
            let half = k
                .and_then(|k| {
                    bands
                        .replicate(o, &|r| r.percentiles[k].unwrap_or(f64::NAN))
                        .filter(|h| h.is_finite())
                })
                .unwrap_or_else(|| std::f64::consts::SQRT_2 * 0.5 * (high - low).max(0.0));
            // A percentile beyond the limits is the same beyond in a re-run that agrees;
            // one whose interval reaches beyond them has an unbounded band.
            let half = if reading.is_infinite() { 0.0 } else { half };
            let key = name.trim_start_matches('p');
            push(name, value.percentiles.get(key).unwrap_or(f64::NAN), half);
        }
        if let Some(capability) = &value.capability {
            // Out of spec among every sample drawn (non-finite, excluded and flagged ones
            // included).
            let fraction = out as f64 / samples as f64;
            let half = bands
                .replicate(o, &|r| 1e6 * r.out_of_spec_fraction)
                .filter(|_| out > 0)
                .unwrap_or_else(|| {
                    bands.two_sample * proportion_standard_error(fraction, samples) * 1e6
                });
            push("ppm_out", capability.ppm_out, half);
        }
        let hidden = acc.non_finite
            + acc.excluded
            + if info.flagged_conform {
                0
            } else {
                acc.flagged_within_spec
            };
        if let (Some(limits), 0) = (info.spec, hidden) {
            // From the mean and the sd of the figures (a replicated run's sd unbiased under
            // its design), with the band of the moments' standard errors.
            let (mean, sd) = (value.mean, value.sd);
            let indices = capability_from_moments(mean, sd, limits);
            if let Some(cp) = indices.cp {
                let half = bands.two_sample * cp * acc.moments.sd_standard_error() / sd;
                push("cp", cp, half);
            }
            if let Some(cpk) = indices.cpk {
                let (g2, nf) = (acc.moments.excess_kurtosis(), n as f64);
                let variance = 1.0 / (9.0 * nf) + cpk * cpk * (g2 + 2.0).max(0.0) / (4.0 * nf);
                push("cpk", cpk, bands.two_sample * variance.sqrt());
            }
        }
    }
    Ok((figures, capability))
}

/// The half-widths of a re-run's bands: √2·z per standard error of one run's figure, or,
/// for a replicated run, √2·t per standard error of its replicates' values.
struct Bands<'a> {
    /// √2·z.
    two_sample: f64,
    replicates: &'a [Vec<ReplicateFigures>],
    /// √2·t, t the Student quantile (R − 1 degrees of freedom) of z's tail probability.
    replicate_scale: Option<f64>,
}

impl<'a> Bands<'a> {
    fn new(replicates: &'a [Vec<ReplicateFigures>], z: f64) -> Bands<'a> {
        Bands {
            two_sample: std::f64::consts::SQRT_2 * z,
            replicates,
            replicate_scale: (!replicates.is_empty()).then(|| {
                let tail = Normal::new(0.0, 1.0).expect("standard normal").cdf(z);
                std::f64::consts::SQRT_2 * student_t_quantile(replicates.len() as f64 - 1.0, tail)
            }),
        }
    }

    /// The half-width from output `o`'s replicate values of a figure, for a replicated
    /// run.
    fn replicate(&self, o: usize, figure: &dyn Fn(&ReplicateFigures) -> f64) -> Option<f64> {
        self.replicate_scale.map(|scale| {
            let values: Vec<f64> = self.replicates.iter().map(|r| figure(&r[o])).collect();
            scale * replicate_standard_error(&values)
        })
    }
}

/// Writes a baseline: the figures of a run of `scenario` (whose file text is
/// `scenario_text`) with their bands.
pub fn baseline(
    scenario: &Scenario,
    scenario_text: &str,
    settings: RunSettings,
    max_non_finite: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Baseline, ScenarioError> {
    baseline_of(
        scenario,
        scenario_text,
        settings,
        run(scenario, settings, progress)?,
        max_non_finite,
    )
}

/// The baseline of [`baseline`] from the run's result (a run, or the merge of its shards).
pub fn baseline_of(
    scenario: &Scenario,
    scenario_text: &str,
    settings: RunSettings,
    result: RunResult,
    max_non_finite: f64,
) -> Result<Baseline, ScenarioError> {
    let z = band_z(gated_figure_count(scenario));
    let figures = figures_of(scenario, result, z, max_non_finite)?.0;
    let RunSettings {
        samples,
        seed,
        exact_percentile_limit,
        // The scenario file the baseline keeps says how its rows are drawn.
        sampling: _,
    } = settings;
    Ok(Baseline {
        rvtol_version: env!("CARGO_PKG_VERSION").to_string(),
        scenario: scenario.name.clone(),
        scenario_sha256: Some(scenario.digest.clone()),
        scenario_file: serde_json::from_str(scenario_text)
            .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?,
        seed,
        samples,
        exact_percentile_limit,
        family_false_alarm: FAMILY_FALSE_ALARM,
        z,
        figures,
        requirements: Vec::new(),
    })
}

/// One figure compared with its baseline.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Output name.
    pub output: String,
    /// Figure name.
    pub figure: String,
    /// Baseline value.
    pub baseline: f64,
    /// Value of the check run (null when the output or figure is gone).
    pub value: Option<f64>,
    /// Allowed interval.
    pub allowed: [f64; 2],
    /// The direction that fails, for a one-sided check (null: either).
    pub worse: Option<Worse>,
    /// Whether the check value lies in the allowed interval (or beyond it on the better
    /// side, for a one-sided figure).
    pub passed: bool,
}

/// One absolute requirement checked against the re-run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RequirementCheck {
    /// As written.
    pub requirement: String,
    /// Output name.
    pub output: String,
    /// Figure name.
    pub figure: String,
    /// The figure of the check run (null when it is undefined).
    pub value: Option<f64>,
    /// value ± z·SE, z the family's band quantile.
    pub interval: [f64; 2],
    /// `met` (the whole interval satisfies it), `within noise` (the interval straddles
    /// it: not shown violated, passes) or `violated` (the whole interval misses it, or
    /// the figure is undefined).
    pub status: &'static str,
    /// Whether the check passes it (not `violated`).
    pub passed: bool,
}

/// How `rvtol check` judges a re-run besides the baseline's bands.
#[derive(Debug, Clone, Default)]
pub struct CheckOptions {
    /// Fail a figure only when it moves beyond its band in the direction that is worse:
    /// the baseline's `worse`, else inferred ([`inferred_worse`]); a figure with neither
    /// stays two-sided.
    pub one_sided: bool,
    /// Requirements besides the baseline's (`[OUTPUT] FIGURE OP VALUE`).
    pub requirements: Vec<String>,
}

/// The direction in which a figure of `output` gets worse, where it follows from the
/// figure or the spec: an sd, a share out of spec and an indicator's fraction (an event
/// such as interference or preload) are worse higher. With an upper spec limit only, the
/// mean, P50 and the upper percentiles are worse higher and the lower tail (P0.135,
/// P2.275) is neither (it moves up when tolerances tighten, down when the output shifts
/// down: neither brings an assembly nearer the limit); with a lower limit only, mirrored.
/// Otherwise (no spec, or both limits) none: the figure stays two-sided.
pub fn inferred_worse(output: &OutputInfo, figure: &str) -> Option<Worse> {
    let lower_tail = matches!(figure, "p0.135" | "p2.275");
    let upper_tail = matches!(figure, "p97.725" | "p99.865");
    match figure {
        "sd" | "ppm_out" | "fraction" => Some(Worse::Higher),
        _ => match output.spec.map(|s| (s.lower, s.upper)) {
            Some((None, Some(_))) if lower_tail => Some(Worse::Neither),
            Some((None, Some(_))) => Some(Worse::Higher),
            Some((Some(_), None)) if upper_tail => Some(Worse::Neither),
            Some((Some(_), None)) => Some(Worse::Lower),
            _ => None,
        },
    }
}

/// A requirement `[OUTPUT] FIGURE OP VALUE` on `scenario`: the output (given, or the
/// scenario's only output with spec limits, or its only continuous output), the gate's
/// figure name and the target. Figures: mean, sd, p0.135, p2.275, p50, p97.725, p99.865,
/// ppm_out, cp, cpk (the last three need spec limits).
pub fn parse_requirement(
    scenario: &Scenario,
    text: &str,
) -> Result<(String, String, Target), String> {
    let trimmed = text.trim();
    let (output, rest) = match trimmed.split_once(char::is_whitespace) {
        Some((first, rest)) if scenario.outputs.iter().any(|o| o.name == first) => {
            (first.to_string(), rest.trim())
        }
        _ => {
            let with_spec: Vec<&OutputInfo> = scenario
                .outputs
                .iter()
                .filter(|o| o.spec.is_some())
                .collect();
            let continuous: Vec<&OutputInfo> = scenario
                .outputs
                .iter()
                .filter(|o| o.kind == OutputKind::Continuous)
                .collect();
            let only = match (with_spec.as_slice(), continuous.as_slice()) {
                ([one], _) | ([], [one]) => one,
                _ => {
                    return Err(format!(
                        "{text:?} names no output: write `OUTPUT {trimmed}` (outputs: {})",
                        scenario
                            .outputs
                            .iter()
                            .map(|o| o.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                }
            };
            (only.name.clone(), trimmed)
        }
    };
    let info = scenario
        .outputs
        .iter()
        .find(|o| o.name == output)
        .expect("output found above");
    if info.kind == OutputKind::Indicator {
        return Err(format!(
            "{output} is an indicator; its requirement would be on its fraction, which a spec does not give"
        ));
    }
    // The target's own message quotes what it read: the output before it, when named.
    let target = Target::parse(rest).map_err(|err| {
        if rest == trimmed {
            err
        } else {
            format!("{output}: {err}")
        }
    })?;
    let figure = match target.figure {
        TargetFigure::Percentile(p) => GATED_PERCENTS
            .iter()
            .find(|(_, q)| (q - p).abs() < 1e-9)
            .map(|(name, _)| name.to_string())
            .ok_or_else(|| {
                format!(
                    "{text:?}: a requirement on a percentile takes one the gate measures: {}",
                    GATED_PERCENTS
                        .iter()
                        .map(|(n, _)| *n)
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?,
        TargetFigure::Mean => "mean".into(),
        TargetFigure::Sd => "sd".into(),
        TargetFigure::PpmOut | TargetFigure::Cp | TargetFigure::Cpk if info.spec.is_none() => {
            return Err(format!(
                "{text:?}: {output} has no spec limits (spec_limits in the scenario)"
            ))
        }
        TargetFigure::PpmOut => "ppm_out".into(),
        TargetFigure::Cp => "cp".into(),
        TargetFigure::Cpk => "cpk".into(),
    };
    Ok((output, figure, target))
}

/// The outcome of `rvtol check`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckReport {
    /// Version of rvtol that checked.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text checked, hex.
    pub scenario_sha256: String,
    /// SHA-256 of the baseline's scenario text, when the baseline records it (a different
    /// digest: the scenario changed, `scenario_changes` says where).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub baseline_scenario_sha256: Option<String>,
    /// Seed of the check run.
    pub seed: u64,
    /// Samples of the check run.
    pub samples: u64,
    /// JSON paths where the scenario file differs from the baseline's copy.
    pub scenario_changes: Vec<String>,
    /// Whether figures were checked one-sided where their direction is known.
    pub one_sided: bool,
    /// Every gated figure.
    pub comparisons: Vec<Comparison>,
    /// Every requirement (the baseline's, then the command line's).
    pub requirements: Vec<RequirementCheck>,
    /// Whether every figure and every requirement passed.
    pub passed: bool,
}

/// JSON paths at which two documents differ (at most `limit`).
pub fn json_differences(
    old: &serde_json::Value,
    new: &serde_json::Value,
    limit: usize,
) -> Vec<String> {
    fn walk(
        path: String,
        old: &serde_json::Value,
        new: &serde_json::Value,
        out: &mut Vec<String>,
        limit: usize,
    ) {
        use serde_json::Value;
        if out.len() >= limit {
            return;
        }
        match (old, new) {
            (Value::Object(a), Value::Object(b)) => {
                let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
                for key in keys {
                    let child = if path.is_empty() {
                        key.clone()
                    } else {
                        format!("{path}.{key}")
                    };
                    match (a.get(key), b.get(key)) {
                        (Some(x), Some(y)) => walk(child, x, y, out, limit),
                        _ => out.push(child),
                    }
                }
            }
            (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
                for (i, (x, y)) in a.iter().zip(b).enumerate() {
                    walk(format!("{path}[{i}]"), x, y, out, limit);
                }
            }
            (a, b) if a == b => {}
            _ => out.push(if path.is_empty() {
                "(root)".into()
            } else {
                path
            }),
        }
    }
    let mut out = Vec::new();
    walk(String::new(), old, new, &mut out, limit);
    out
}

/// Re-runs the scenario and compares every figure with the baseline (two-sided, no
/// requirements besides the baseline's).
pub fn check(
    scenario: &Scenario,
    scenario_text: &str,
    baseline: &Baseline,
    seed: u64,
    max_non_finite: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<CheckReport, CheckError> {
    check_with(
        scenario,
        scenario_text,
        baseline,
        seed,
        max_non_finite,
        &CheckOptions::default(),
        progress,
    )
}

/// Re-runs the scenario, compares every figure with the baseline and checks every
/// requirement. With r requirements the family's z is Φ⁻¹(1 − α/(2(m + r))) for the m
/// figures too (their bands widened by that z over the baseline's), so that an unchanged
/// scenario that meets its requirements fails with probability at most α overall. A
/// requirement fails only when its whole interval value ± z·SE misses it.
pub fn check_with(
    scenario: &Scenario,
    scenario_text: &str,
    baseline: &Baseline,
    seed: u64,
    max_non_finite: f64,
    options: &CheckOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<CheckReport, CheckError> {
    check_result(
        scenario,
        scenario_text,
        baseline,
        seed,
        max_non_finite,
        options,
        &|settings| run(scenario, settings, progress),
    )
}

/// [`check_with`] on the result `result_of` gives for the run's settings (the baseline's
/// samples and percentile limit, the seed `seed`): a run, or the merge of its shards.
pub fn check_result(
    scenario: &Scenario,
    scenario_text: &str,
    baseline: &Baseline,
    seed: u64,
    max_non_finite: f64,
    options: &CheckOptions,
    result_of: &dyn Fn(RunSettings) -> Result<RunResult, ScenarioError>,
) -> Result<CheckReport, CheckError> {
    baseline.matches(scenario)?;
    let current: serde_json::Value = serde_json::from_str(scenario_text)
        .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?;
    let mut requirements = Vec::new();
    for (i, text) in baseline.requirements.iter().enumerate() {
        requirements.push(
            parse_requirement(scenario, text)
                .map(|parsed| (text.clone(), parsed))
                .map_err(|err| BaselineError::new(format!("requirements[{i}]"), err))?,
        );
    }
    for text in &options.requirements {
        requirements.push(
            parse_requirement(scenario, text)
                .map(|parsed| (text.clone(), parsed))
                .map_err(CheckError::Requirement)?,
        );
    }
    let z = band_z(baseline.figures.len() + requirements.len()).max(baseline.z);
    let widen = z / baseline.z;
    let samples = baseline.samples;
    let settings = RunSettings {
        samples,
        seed,
        exact_percentile_limit: baseline.exact_percentile_limit,
        sampling: scenario.sampling,
    };
    let (figures, capability) = figures_of(scenario, result_of(settings)?, z, max_non_finite)?;
    let comparisons: Vec<Comparison> = baseline
        .figures
        .iter()
        .map(|old| {
            let value = figures
                .iter()
                .find(|f| f.output == old.output && f.figure == old.figure)
                .map(|f| f.value);
            let (low, high) = match (old.absolute_tolerance, old.relative_tolerance) {
                (None, None) if widen > 1.0 && old.value.is_finite() => (
                    old.value - widen * (old.value - old.lower),
                    old.value + widen * (old.upper - old.value),
                ),
                _ => old.allowed(),
            };
            let worse = old.worse.or_else(|| {
                let info = scenario.outputs.iter().find(|o| o.name == old.output)?;
                options
                    .one_sided
                    .then(|| inferred_worse(info, &old.figure))
                    .flatten()
            });
            // The same seed and samples reproduce the value bit for bit; anything else must
            // fall in the band, or beyond it on the better side.
            let passed = value.is_some_and(|v| {
                v == old.value
                    || worse == Some(Worse::Neither)
                    || (low <= v && v <= high)
                    || (worse == Some(Worse::Higher) && v < low)
                    || (worse == Some(Worse::Lower) && v > high)
            });
            Comparison {
                output: old.output.clone(),
                figure: old.figure.clone(),
                baseline: old.value,
                value,
                allowed: [low, high],
                worse,
                passed,
            }
        })
        .collect();
    let requirements: Vec<RequirementCheck> = requirements
        .into_iter()
        .map(|(text, (output, figure, target))| {
            let measured = figures
                .iter()
                .chain(&capability)
                .find(|f| f.output == output && f.figure == figure);
            // The band is ± √2·z·SE (two runs); one run's interval is ± z·SE.
            let (value, interval) = match measured {
                Some(f) => {
                    let reach = if f.value.is_infinite() {
                        0.0 // beyond the limits, and so in a re-run
                    } else {
                        0.5 * (f.upper - f.lower) / std::f64::consts::SQRT_2
                    };
                    (Some(f.value), [f.value - reach, f.value + reach])
                }
                None => (None, [f64::NAN, f64::NAN]),
            };
            let meets = |x: f64| target.excess(x) <= 0.0;
            let status = match value {
                Some(_) if meets(interval[0]) && meets(interval[1]) => "met",
                Some(_) if meets(interval[0]) || meets(interval[1]) => "within noise",
                _ => "violated",
            };
            RequirementCheck {
                requirement: text,
                output,
                figure,
                value,
                interval,
                status,
                passed: status != "violated",
            }
        })
        .collect();
    Ok(CheckReport {
        rvtol_version: env!("CARGO_PKG_VERSION"),
        scenario: scenario.name.clone(),
        scenario_sha256: scenario.digest.clone(),
        baseline_scenario_sha256: baseline.scenario_sha256.clone(),
        seed,
        samples,
        scenario_changes: json_differences(&baseline.scenario_file, &current, 8),
        passed: comparisons.iter().all(|c| c.passed) && requirements.iter().all(|r| r.passed),
        one_sided: options.one_sided,
        comparisons,
        requirements,
    })
}

impl CheckReport {
    /// One line per figure that moved (empty when all passed).
    pub fn moved_lines(&self) -> Vec<String> {
        let hint = if self.scenario_changes.is_empty() {
            "scenario unchanged (different seed, samples or rvtol version)".to_string()
        } else {
            format!("scenario changed at {}", self.scenario_changes.join(", "))
        };
        self.comparisons
            .iter()
            .filter(|c| !c.passed)
            .map(|c| {
                let value = c
                    .value
                    .map_or("missing".to_string(), rvtol_engine::format::format_figure);
                let allowed = match c.allowed {
                    [low, high] if low.is_infinite() && low == high => {
                        "allowed: beyond the limits only".to_string()
                    }
                    [low, high] => format!(
                        "allowed {} .. {}",
                        rvtol_engine::format::format_sig(low),
                        rvtol_engine::format::format_sig(high)
                    ),
                };
                format!(
                    "moved: {} {}: {} -> {} ({allowed}); {hint}",
                    c.output,
                    c.figure,
                    rvtol_engine::format::format_figure(c.baseline),
                    value,
                )
            })
            .collect()
    }

    /// One line per requirement.
    pub fn requirement_lines(&self) -> Vec<String> {
        use rvtol_engine::format::format_figure;
        self.requirements
            .iter()
            .map(|r| match r.value {
                None => format!(
                    "violated: {} ({} {} is undefined: samples out of spec that its values do not show, flagged, excluded or not finite)",
                    r.requirement, r.output, r.figure
                ),
                Some(value) => format!(
                    "{}: {} ({} {}: {}, interval {} .. {}){}",
                    if r.passed { "requirement" } else { "violated" },
                    r.requirement,
                    r.output,
                    r.figure,
                    format_figure(value),
                    format_figure(r.interval[0]),
                    format_figure(r.interval[1]),
                    match r.status {
                        "met" => ": met",
                        "within noise" => {
                            ": within Monte Carlo noise of the limit, not shown violated"
                        }
                        _ => "",
                    }
                ),
            })
            .collect()
    }

    /// The summary printed by `rvtol check`.
    pub fn to_text(&self) -> String {
        let failed = self.comparisons.iter().filter(|c| !c.passed).count();
        let violated = self.requirements.iter().filter(|r| !r.passed).count();
        let mut lines = self.moved_lines();
        lines.extend(self.requirement_lines());
        let requirements = if self.requirements.is_empty() {
            String::new()
        } else {
            format!(
                ", {} of {} requirements met",
                self.requirements.len() - violated,
                self.requirements.len()
            )
        };
        lines.push(format!(
            "rvtol check {}: {} of {} figures within their baseline bands{}{requirements} ({} samples, seed {}){}",
            self.scenario,
            self.comparisons.len() - failed,
            self.comparisons.len(),
            if self.one_sided { " or better" } else { "" },
            self.samples,
            self.seed,
            if failed + violated == 0 { "" } else { ": FAILED" }
        ));
        let mut text = lines.join("\n");
        text.push('\n');
        text
    }

    /// The JSON document.
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("report serialises");
        text.push('\n');
        text
    }

    /// JUnit XML: one test case per figure.
    pub fn to_junit(&self) -> String {
        let failures = self.comparisons.iter().filter(|c| !c.passed).count()
            + self.requirements.iter().filter(|r| !r.passed).count();
        let tests = self.comparisons.len() + self.requirements.len();
        let mut xml = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        xml.push_str(&format!(
            "<testsuites name=\"rvtol check\" tests=\"{tests}\" failures=\"{failures}\">\n  <testsuite name=\"{}\" tests=\"{tests}\" failures=\"{failures}\">\n",
            escape_markup(&self.scenario),
        ));
        let lines = self.moved_lines();
        let mut moved = lines.iter();
        for c in &self.comparisons {
            let name = format!("{} {}", c.output, c.figure);
            if c.passed {
                xml.push_str(&format!(
                    "    <testcase classname=\"{}\" name=\"{}\"/>\n",
                    escape_markup(&self.scenario),
                    escape_markup(&name)
                ));
            } else {
                let message = moved.next().cloned().unwrap_or_default();
                xml.push_str(&format!(
                    "    <testcase classname=\"{}\" name=\"{}\">\n      <failure message=\"{}\"/>\n    </testcase>\n",
                    escape_markup(&self.scenario),
                    escape_markup(&name),
                    escape_markup(&message)
                ));
            }
        }
        for (r, line) in self.requirements.iter().zip(self.requirement_lines()) {
            let name = format!("requirement {}", r.requirement);
            if r.passed {
                xml.push_str(&format!(
                    "    <testcase classname=\"{}\" name=\"{}\"/>\n",
                    escape_markup(&self.scenario),
                    escape_markup(&name)
                ));
            } else {
                xml.push_str(&format!(
                    "    <testcase classname=\"{}\" name=\"{}\">\n      <failure message=\"{}\"/>\n    </testcase>\n",
                    escape_markup(&self.scenario),
                    escape_markup(&name),
                    escape_markup(&line)
                ));
            }
        }
        xml.push_str("  </testsuite>\n</testsuites>\n");
        xml
    }
}
