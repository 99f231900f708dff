//! A tolerance allocation as a caller asks for it (`rvtol allocate`, Python's `allocate`):
//! the target parsed ([`crate::target`]), the cost model named, and each setting left out
//! resolved: the scenario's seed, the verification's the next one, and enough samples for
//! the target's tail ([`default_samples`]); with `rare`, importance sampling's precision
//! and its budget of points per sample instead.

use rvtol_engine::scenario::allocation::CostKind;
use rvtol_engine::Scenario;

use super::rare::{precision, DEFAULT_LEVEL_SAMPLES};
use super::{Caller, Refusal};
use crate::allocation::rare::RareOptions;
use crate::allocation::{default_samples, AllocationSettings};
use crate::target::Target;

/// What a caller asks of an allocation; `None` takes the default or the scenario's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllocationRequest<'a> {
    /// The target, `FIGURE <= VALUE` or `FIGURE >= VALUE`.
    pub target: &'a str,
    /// The cost model (`reciprocal`, `exponential`, `table`) when a source gives several.
    pub cost: Option<&'a str>,
    /// Samples per Monte Carlo run.
    pub samples: Option<u64>,
    /// Seed of the optimisation's runs.
    pub seed: Option<u64>,
    /// Seed of the verification run.
    pub verify_seed: Option<u64>,
    /// Estimate a ppm target by importance sampling (`--rare`).
    pub rare: bool,
    /// With `rare`: the 95 % interval's half width, as a share, a sample is built for.
    pub precision: Option<f64>,
    /// With `rare`: the points a sample may have.
    pub max_evaluations: Option<u64>,
}

/// The default budget of points of one importance-sampling sample of `allocate --rare`
/// (every evaluation of the optimisation runs the model on each of them).
pub const DEFAULT_RARE_POINTS: u64 = 500_000;

impl AllocationRequest<'_> {
    /// The target and the allocation's settings for `scenario`.
    pub fn settings(
        &self,
        scenario: &Scenario,
        caller: Caller,
    ) -> Result<(Target, AllocationSettings), Refusal> {
        let target =
            Target::parse(self.target).map_err(|err| Refusal::option(caller, "target", err))?;
        let cost = self
            .cost
            .map(|name| {
                CostKind::parse(name).ok_or_else(|| {
                    Refusal::option(
                        caller,
                        "cost",
                        format!(
                            "unknown cost model {name:?}; use reciprocal, exponential or table"
                        ),
                    )
                })
            })
            .transpose()?;
        let seed = self.seed.unwrap_or(scenario.seed);
        let rare = self.rare_options(caller)?;
        let settings = AllocationSettings {
            samples: self.samples.unwrap_or_else(|| default_samples(&target)),
            seed,
            verification_seed: self.verify_seed.unwrap_or(seed.wrapping_add(1)),
            cost,
            rare,
        };
        Ok((target, settings))
    }

    /// The importance-sampling options, when `rare` is asked; refusals of the options that
    /// belong to one estimator only.
    fn rare_options(&self, caller: Caller) -> Result<Option<RareOptions>, Refusal> {
        if !self.rare {
            let stray = [
                ("precision", self.precision.is_some()),
                ("max_evaluations", self.max_evaluations.is_some()),
            ];
            return match stray.iter().find(|(_, given)| *given) {
                Some((name, _)) => Err(Refusal::option(
                    caller,
                    name,
                    "belongs to importance sampling: add --rare (a ppm target)",
                )),
                None => Ok(None),
            };
        }
        if self.samples.is_some() {
            return Err(Refusal::option(
                caller,
                "samples",
                "not with --rare: importance sampling draws as many points as --precision needs",
            ));
        }
        let precision = precision(self.precision, caller)?;
        let max_evaluations = self.max_evaluations.unwrap_or(DEFAULT_RARE_POINTS);
        if max_evaluations < 10_000 {
            return Err(Refusal::option(
                caller,
                "max_evaluations",
                format!("{max_evaluations} points are too few for a sample (at least 10,000)"),
            ));
        }
        Ok(Some(RareOptions {
            precision,
            max_evaluations,
            level_samples: DEFAULT_LEVEL_SAMPLES,
        }))
    }
}
