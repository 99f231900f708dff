//! A tolerance allocation as a caller asks for it (`rvtol allocate`, Python's `allocate`):
//! the target parsed ([`crate::target`]), the cost model named, and each setting left out
//! resolved: the scenario's seed, the verification's the next one, and enough samples for
//! the target's tail ([`default_samples`]).

use rvtol_engine::scenario::allocation::CostKind;
use rvtol_engine::Scenario;

use super::{Caller, Refusal};
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
}

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
        let settings = AllocationSettings {
            samples: self.samples.unwrap_or_else(|| default_samples(&target)),
            seed,
            verification_seed: self.verify_seed.unwrap_or(seed.wrapping_add(1)),
            cost,
        };
        Ok((target, settings))
    }
}
