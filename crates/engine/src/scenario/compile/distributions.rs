//! The scalar laws a variable may follow, from the file's `distribution` object to a
//! [`ScalarDistribution`]: the direct ones as written, the tolerance-style ones (a folded
//! normal, a Rayleigh, a lognormal given by limits and a capability) converted to their
//! parameters, measured values (`empirical`) with their smoothing bandwidth.

use rvtol_deviation::{EmpiricalLaw, ScalarDistribution, Shown, RAYLEIGH_QUANTILE};
use serde_json::Value;

use super::super::file::DistributionFile;
use crate::error::ScenarioError;

/// The distribution a variable's file entry describes, and the key of its object; a
/// tolerance-style parameter that cannot give a distribution (Cp ≤ 0, a median ≤ 0) is an
/// error at `path` (the variable's `distribution`).
pub(super) fn distribution(
    path: &str,
    d: &DistributionFile,
) -> Result<(ScalarDistribution, &'static str), ScenarioError> {
    let positive_cp = |kind: &str, cp: f64| {
        if cp > 0.0 {
            Ok(cp)
        } else {
            Err(ScenarioError::new(
                format!("{path}.{kind}.cp"),
                format!("process capability must be positive, got {}", Shown(cp)),
            ))
        }
    };
    Ok(match *d {
        DistributionFile::Empirical {
            ref values,
            ref csv,
            ref bandwidth,
            ..
        } => {
            let at = format!("{path}.empirical");
            if values.is_some() && csv.is_some() {
                return Err(ScenarioError::new(
                    &at,
                    "give the numbers in `values` or a CSV file in `csv` and `column`, not both (`source` may name where the values came from)",
                ));
            }
            let Some(values) = values else {
                return Err(match csv {
                    Some(_) => ScenarioError::new(
                        format!("{at}.csv"),
                        "a data file is read when the scenario is loaded from its file (its path is relative to the scenario's folder); a scenario given as text or a dict needs the numbers in `values`",
                    ),
                    None => ScenarioError::new(
                        &at,
                        "give the measured numbers in `values`, or a CSV file and its column in `csv` and `column`",
                    ),
                });
            };
            let bandwidth = match bandwidth {
                None => 0.0,
                Some(Value::String(rule)) if rule == "silverman" => {
                    EmpiricalLaw::silverman_bandwidth(values)
                }
                Some(Value::Number(h)) => h.as_f64().unwrap_or(f64::NAN),
                Some(other) => {
                    return Err(ScenarioError::new(
                        format!("{at}.bandwidth"),
                        format!("expected a number ≥ 0 (in the variable's unit) or \"silverman\", got {other}"),
                    ))
                }
            };
            (
                ScalarDistribution::Empirical(EmpiricalLaw::new(&at, values, bandwidth)?),
                "empirical",
            )
        }
        DistributionFile::Normal { mean, sd } => {
            (ScalarDistribution::Normal { mean, sd }, "normal")
        }
        DistributionFile::ToleranceBand {
            lower,
            upper,
            cp,
            mean_shift,
        } => (
            ScalarDistribution::ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            },
            "tolerance_band",
        ),
        DistributionFile::Uniform { lower, upper } => {
            (ScalarDistribution::Uniform { lower, upper }, "uniform")
        }
        DistributionFile::Triangular { lower, mode, upper } => (
            ScalarDistribution::Triangular { lower, mode, upper },
            "triangular",
        ),
        DistributionFile::TruncatedNormal {
            mean,
            sd,
            lower,
            upper,
        } => (
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            },
            "truncated_normal",
        ),
        DistributionFile::FoldedNormal {
            lower,
            upper,
            cp,
            mean_shift,
        } => {
            let cp = positive_cp("folded_normal", cp)?;
            if upper < lower {
                return Err(ScenarioError::new(
                    format!("{path}.folded_normal.upper"),
                    format!(
                        "upper limit {} is below lower limit {}",
                        Shown(upper),
                        Shown(lower)
                    ),
                ));
            }
            (
                ScalarDistribution::FoldedNormal {
                    mean: 0.5 * (lower + upper) + mean_shift,
                    sd: (upper - lower) / (6.0 * cp),
                },
                "folded_normal",
            )
        }
        DistributionFile::Rayleigh { upper, cp } => {
            let cp = positive_cp("rayleigh", cp)?;
            if upper < 0.0 {
                return Err(ScenarioError::new(
                    format!("{path}.rayleigh.upper"),
                    format!(
                        "a magnitude's upper tolerance must not be negative, got {}",
                        Shown(upper)
                    ),
                ));
            }
            (
                ScalarDistribution::Rayleigh {
                    sigma: upper / (RAYLEIGH_QUANTILE * cp),
                },
                "rayleigh",
            )
        }
        DistributionFile::Lognormal { median, upper, cp } => {
            let cp = positive_cp("lognormal", cp)?;
            if median <= 0.0 {
                return Err(ScenarioError::new(
                    format!("{path}.lognormal.median"),
                    format!("must be positive, got {}", Shown(median)),
                ));
            }
            if upper < median {
                return Err(ScenarioError::new(
                    format!("{path}.lognormal.upper"),
                    format!(
                        "the upper tolerance {} is below the median {}",
                        Shown(upper),
                        Shown(median)
                    ),
                ));
            }
            (
                ScalarDistribution::Lognormal {
                    mu: median.ln(),
                    sigma: (upper / median).ln() / (3.0 * cp),
                },
                "lognormal",
            )
        }
    })
}
