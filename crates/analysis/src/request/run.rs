//! A run as a caller asks for it (`rvtol run`, its shards, Python's `run`): each setting it
//! leaves out is the scenario's, the sampling method's replicates its default unless the
//! scenario's method is kept, and the settings are checked against the scenario before
//! any work; an error about a value the caller gave names its option.

use rvtol_engine::chunk::{Sampling, SamplingMethod};
use rvtol_engine::evaluate::check_table_rows;
use rvtol_engine::{RunSettings, Scenario, DEFAULT_EXACT_PERCENTILE_LIMIT};

use super::{Caller, Refusal};

/// What a caller asks of a run; `None` takes the scenario's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunRequest {
    /// Samples.
    pub samples: Option<u64>,
    /// Seed of the random streams.
    pub seed: Option<u64>,
    /// Exact percentiles while samples × outputs stays within it.
    pub exact_percentile_limit: u64,
    /// How the rows are drawn.
    pub sampling: Option<SamplingMethod>,
    /// Independent randomizations of an lhs or rqmc design.
    pub replicates: Option<u64>,
}

impl Default for RunRequest {
    fn default() -> RunRequest {
        RunRequest {
            samples: None,
            seed: None,
            exact_percentile_limit: DEFAULT_EXACT_PERCENTILE_LIMIT,
            sampling: None,
            replicates: None,
        }
    }
}

impl RunRequest {
    /// The settings for `scenario`, checked ([`RunSettings::check`]): what the request
    /// says, else the scenario's ([`Sampling::chosen`]).
    pub fn settings(&self, scenario: &Scenario, caller: Caller) -> Result<RunSettings, Refusal> {
        let settings = RunSettings {
            samples: self.samples.unwrap_or(scenario.samples),
            seed: self.seed.unwrap_or(scenario.seed),
            exact_percentile_limit: self.exact_percentile_limit,
            sampling: Sampling::chosen(scenario.sampling, self.sampling, self.replicates),
        };
        settings.check(scenario).map_err(|err| {
            Refusal::at_option_or_scenario(
                err,
                caller,
                &[
                    ("samples", self.samples.is_some()),
                    ("sampling", self.sampling.is_some()),
                    ("replicates", self.replicates.is_some()),
                ],
            )
        })?;
        Ok(settings)
    }
}

/// Refuses a table of every sample of a run of `samples` rows beyond what a sample table
/// holds (`samples_out`: the run's rows kept, written or returned).
pub fn check_samples_out(scenario: &Scenario, samples: u64, caller: Caller) -> Result<(), Refusal> {
    check_table_rows(scenario, samples).map_err(|message| {
        Refusal::option(
            caller,
            "samples_out",
            format!("{message}; run fewer samples"),
        )
    })
}

/// A sampling method named by the caller (`mc`, `lhs`, `rqmc`).
pub fn sampling_method(name: &str, caller: Caller) -> Result<SamplingMethod, Refusal> {
    SamplingMethod::parse(name).ok_or_else(|| {
        Refusal::option(
            caller,
            "sampling",
            format!(
                "unknown method {name:?}, expected one of {}",
                SamplingMethod::NAMES.join(", ")
            ),
        )
    })
}
