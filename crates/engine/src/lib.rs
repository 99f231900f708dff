//! rvtol-engine: from a scenario file to statistics.
//!
//! Data flows one way: [`scenario`] loads and validates the JSON into a [`Scenario`]
//! (input space + bound models + outputs); [`run`] draws chunks in parallel under the
//! reproducibility contract and folds model outputs into [`stats`] accumulators;
//! [`report`] turns the result into JSON and text. Nothing downstream reaches back into
//! the scenario or the sampler, and the engine never prints. The analyses that use a run
//! (sensitivity, the gate, the allocation, the fit, shards) are rvtol-analysis, above.

pub mod chunk;
pub mod error;
pub mod evaluate;
pub mod figures;
pub mod format;
pub mod report;
pub mod run;
pub mod scenario;
pub mod stats;

pub use chunk::{shard_range, Sampling};
pub use evaluate::SampleTable;
pub use report::{NominalReport, RunReport};
pub use run::{
    merge, nominal, nominal_curves, run, run_chunks, sample_table, RunPartial, RunResult,
    RunSettings, DEFAULT_EXACT_PERCENTILE_LIMIT,
};
pub use scenario::{Scenario, ScenarioError};
