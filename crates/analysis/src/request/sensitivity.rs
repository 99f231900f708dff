//! A sensitivity analysis as a caller asks for it (`rvtol sensitivity`, its shards and
//! their merge, Python's `sensitivity`): its defaults (65,536 base samples, 500 bootstrap
//! resamples, 95 % intervals; Shapley effects by 600 permutations of 256 outer and 3 inner
//! draws) and its limits (at least 2 base samples, 2 to 1,000,000 resamples, at most
//! 10⁹ conditional draws, no bootstrap for a replicated design), checked before any work.

use rvtol_engine::chunk::{Sampling, SamplingMethod};
use rvtol_engine::Scenario;

use super::{Caller, Refusal};
use crate::sensitivity::{SensitivitySettings, DEFAULT_ROW_BOOTSTRAP_LIMIT};
use crate::shapley::ShapleySettings;

/// Base samples unless the caller says.
pub const DEFAULT_SAMPLES: u64 = 65_536;
/// Bootstrap resamples of a Monte Carlo analysis unless the caller says.
pub const DEFAULT_BOOTSTRAP: u64 = 500;
/// Fewest and most bootstrap resamples.
pub const BOOTSTRAP_RANGE: std::ops::RangeInclusive<u64> = 2..=1_000_000;
/// Confidence of the indices' intervals.
pub const CONFIDENCE: f64 = 0.95;
/// Shapley: permutation budget unless the caller says.
pub const DEFAULT_PERMUTATIONS: u64 = 600;
/// Shapley: outer draws per conditional-variance estimate unless the caller says.
pub const DEFAULT_OUTER: u64 = 256;
/// Shapley: inner draws per outer draw.
pub const INNER: usize = 3;
/// Most Shapley permutations × outer draws: their product sets the model evaluations.
pub const MAX_SHAPLEY_DRAWS: u64 = 1_000_000_000;

/// What a caller asks of a sensitivity analysis; `None` takes the default or the
/// scenario's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensitivityRequest {
    /// Base samples N (the models are evaluated N·(2·groups + 2) times); never the
    /// scenario's `samples`.
    pub samples: u64,
    /// Seed of the random streams.
    pub seed: Option<u64>,
    /// How the rows of A and B are drawn.
    pub sampling: Option<SamplingMethod>,
    /// Independent randomizations of an lhs or rqmc design.
    pub replicates: Option<u64>,
    /// Bootstrap resamples of a Monte Carlo analysis.
    pub bootstrap: Option<u64>,
    /// Most model values kept for the row bootstrap.
    pub row_bootstrap_limit: u64,
    /// Shapley effects too, by these draws.
    pub shapley: Option<ShapleyRequest>,
}

/// The draws of a Shapley estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShapleyRequest {
    /// Permutation budget (all orders when d! fits, repeated).
    pub permutations: u64,
    /// Outer draws per conditional-variance estimate.
    pub outer: u64,
}

impl Default for ShapleyRequest {
    fn default() -> ShapleyRequest {
        ShapleyRequest {
            permutations: DEFAULT_PERMUTATIONS,
            outer: DEFAULT_OUTER,
        }
    }
}

impl Default for SensitivityRequest {
    fn default() -> SensitivityRequest {
        SensitivityRequest {
            samples: DEFAULT_SAMPLES,
            seed: None,
            sampling: None,
            replicates: None,
            bootstrap: None,
            row_bootstrap_limit: DEFAULT_ROW_BOOTSTRAP_LIMIT,
            shapley: None,
        }
    }
}

impl SensitivityRequest {
    /// The analysis' settings for `scenario`, checked.
    pub fn settings(
        &self,
        scenario: &Scenario,
        caller: Caller,
    ) -> Result<SensitivitySettings, Refusal> {
        if self.samples < 2 {
            return Err(Refusal::option(
                caller,
                "samples",
                "sensitivity needs at least 2 base samples",
            ));
        }
        let sampling = Sampling::chosen(scenario.sampling, self.sampling, self.replicates);
        if sampling.is_replicated() && self.bootstrap.is_some() {
            return Err(Refusal::option(
                caller,
                "bootstrap",
                format!(
                    "the intervals of a replicated {} design come from its replicates, not a bootstrap; leave {} out, or give {}",
                    sampling.method.name(),
                    caller.option("bootstrap"),
                    caller.setting("sampling", "mc")
                ),
            ));
        }
        // The base samples are the request's (given or its default), never the scenario's.
        sampling
            .check(self.samples, "base samples", &scenario.input_space)
            .map_err(|err| {
                Refusal::at_option_or_scenario(
                    err,
                    caller,
                    &[
                        ("samples", true),
                        ("sampling", self.sampling.is_some()),
                        ("replicates", self.replicates.is_some()),
                    ],
                )
            })?;
        let bootstrap = self.bootstrap.unwrap_or(DEFAULT_BOOTSTRAP);
        if !BOOTSTRAP_RANGE.contains(&bootstrap) {
            return Err(Refusal::option(
                caller,
                "bootstrap",
                format!(
                    "must be between {} and {} resamples",
                    BOOTSTRAP_RANGE.start(),
                    BOOTSTRAP_RANGE.end()
                ),
            ));
        }
        if let Some(ShapleyRequest {
            permutations,
            outer,
        }) = self.shapley
        {
            if permutations.saturating_mul(outer) > MAX_SHAPLEY_DRAWS {
                return Err(Refusal::Option {
                    option: format!(
                        "{} × {}",
                        caller.option("permutations"),
                        caller.option("outer")
                    ),
                    message: format!(
                        "at most {MAX_SHAPLEY_DRAWS} conditional draws, got {permutations} × {outer}"
                    ),
                });
            }
        }
        Ok(SensitivitySettings {
            base_samples: self.samples,
            seed: self.seed.unwrap_or(scenario.seed),
            bootstrap: bootstrap as usize,
            confidence: CONFIDENCE,
            row_bootstrap_limit: self.row_bootstrap_limit,
            sampling,
        })
    }

    /// The Shapley estimate's settings with the analysis' `seed`, when asked for.
    pub fn shapley_settings(&self, seed: u64) -> Option<ShapleySettings> {
        self.shapley.map(|shapley| ShapleySettings {
            permutations: shapley.permutations as usize,
            outer: shapley.outer as usize,
            inner: INNER,
            seed,
        })
    }
}
