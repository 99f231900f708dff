//! rvtol-engine, the run core: from a scenario's text to each output's figures.
//!
//! Data flows one way, and the modules are layered the same way (no module imports one
//! that imports it back): on the ground floor [`error`], [`format`] (numbers as every report
//! prints them), [`chunk`] (the chunk-and-stream contract) and [`stats`] (the crate
//! rvtol-stats, re-exported: the statistics every figure is made of); then [`scenario`],
//! which validates the JSON into a [`Scenario`] (input space + bound models + outputs),
//! section by section; [`evaluate`], the models on a block of rows; [`run`], which draws
//! chunks in parallel under the reproducibility contract and folds model outputs into
//! accumulators; [`figures`], every output's figures with their intervals, computed once;
//! [`report`], which renders them as JSON and text. Nothing downstream reaches back into
//! the scenario or the sampler; the engine reads no file and never prints. The analyses
//! that use a run (sensitivity, the gate, the allocation, the fit, shards) and the
//! requests the front-ends make are rvtol-analysis, above.

pub mod chunk;
pub mod error;
pub mod evaluate;
pub mod figures;
pub mod format;
pub mod report;
pub mod run;
pub mod scenario;

/// The statistics every figure is made of (the crate rvtol-stats).
pub use rvtol_stats as stats;

pub use chunk::{shard_range, Sampling};
pub use error::{FoldError, MergeError};
pub use evaluate::SampleTable;
pub use report::{NominalReport, RunReport};
pub use run::{
    merge, nominal, nominal_curves, run, run_chunks, sample_table, RunPartial, RunResult,
    RunSettings, DEFAULT_EXACT_PERCENTILE_LIMIT,
};
pub use scenario::{Scenario, ScenarioError};
