//! The gate's requests (`rvtol baseline`, `rvtol check`, and `merge` of a run's shards
//! into either): a baseline's run (at least 2 samples, drawn as its scenario says), a
//! check's re-run (the baseline's samples and percentile limit, another seed if asked),
//! the baseline's scenario text against the one checked, and its requirements parsed
//! against the scenario before any work.

use rvtol_engine::{RunSettings, Scenario};

use super::{Caller, Refusal};
use crate::gate::{parse_requirement, Baseline, CheckOptions};

/// What a caller asks of a baseline's run; `None` takes the scenario's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaselineRequest {
    /// Samples.
    pub samples: Option<u64>,
    /// Seed of the random streams.
    pub seed: Option<u64>,
    /// Exact percentiles while samples × outputs stays within it.
    pub exact_percentile_limit: u64,
}

impl BaselineRequest {
    /// The baseline run's settings for `scenario` (drawn as the scenario says: the file the
    /// baseline keeps says so too).
    pub fn settings(&self, scenario: &Scenario, caller: Caller) -> Result<RunSettings, Refusal> {
        let settings = RunSettings {
            samples: self.samples.unwrap_or(scenario.samples),
            seed: self.seed.unwrap_or(scenario.seed),
            exact_percentile_limit: self.exact_percentile_limit,
            sampling: scenario.sampling,
        };
        check_baseline_samples(settings.samples)
            .map_err(|message| Refusal::option(caller, "samples", message))?;
        Ok(settings)
    }
}

/// A baseline's run needs two samples at least (a band needs a spread).
pub fn check_baseline_samples(samples: u64) -> Result<(), &'static str> {
    if samples < 2 {
        return Err("a baseline needs at least 2 samples");
    }
    Ok(())
}

/// A requirement that does not parse, and where it was written.
#[derive(Debug, Clone, PartialEq)]
pub enum RequirementError {
    /// The baseline file's `requirements[index]`.
    Baseline {
        /// Its index in the file's list.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// One the caller gave (`--require`).
    Given(Refusal),
}

/// Parses every requirement a check judges against `scenario` (the baseline's, then the
/// caller's); the first that does not parse is the error.
pub fn check_requirements(
    scenario: &Scenario,
    recorded: &Baseline,
    options: &CheckOptions,
    caller: Caller,
) -> Result<(), RequirementError> {
    for (index, text) in recorded.requirements.iter().enumerate() {
        parse_requirement(scenario, text)
            .map_err(|message| RequirementError::Baseline { index, message })?;
    }
    for text in &options.requirements {
        parse_requirement(scenario, text)
            .map_err(|err| RequirementError::Given(Refusal::option(caller, "require", err)))?;
    }
    Ok(())
}

/// The settings of a check's re-run of `scenario` against `recorded`: the baseline's
/// samples and percentile limit, the scenario's sampling, `seed` or the baseline's.
pub fn check_settings(scenario: &Scenario, recorded: &Baseline, seed: Option<u64>) -> RunSettings {
    RunSettings {
        samples: recorded.samples,
        seed: seed.unwrap_or(recorded.seed),
        exact_percentile_limit: recorded.exact_percentile_limit,
        sampling: scenario.sampling,
    }
}

/// Whether a run of `settings` (a merge of shards) can be checked against `recorded`: the
/// same samples and exact-percentile limit; the error says how to run the shards.
pub fn baseline_matches(recorded: &Baseline, settings: &RunSettings) -> Result<(), String> {
    if (recorded.samples, recorded.exact_percentile_limit)
        != (settings.samples, settings.exact_percentile_limit)
    {
        return Err(format!(
            "a baseline of {} samples (exact percentiles up to {} values), the shards ran {} ({}): run the shards with --samples {} --exact-percentile-limit {}",
            recorded.samples,
            recorded.exact_percentile_limit,
            settings.samples,
            settings.exact_percentile_limit,
            recorded.samples,
            recorded.exact_percentile_limit
        ));
    }
    Ok(())
}

/// Whether `recorded` was recorded from the text of `scenario` (the same SHA-256; a
/// baseline older than the digest has none and passes). A design change is a changed
/// text: `changed` (`--scenario-changed`) accepts it, and the check then says where the
/// text changed. The error says both digests and what to do.
pub fn baseline_text_matches(
    recorded: &Baseline,
    scenario: &Scenario,
    changed: bool,
    caller: Caller,
) -> Result<(), String> {
    match &recorded.scenario_sha256 {
        Some(digest) if !changed && *digest != scenario.digest => Err(format!(
            "scenario_sha256: recorded from another text of scenario {:?} (sha256 {}…, this file's {}…): to check the changed design against it (the report says where the text changed) pass {}, or write a new baseline",
            scenario.name,
            &digest[..digest.len().min(12)],
            &scenario.digest[..12],
            caller.option("scenario_changed")
        )),
        _ => Ok(()),
    }
}
