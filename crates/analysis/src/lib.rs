//! rvtol-analysis: what rvtol computes from runs of a scenario, above the run core
//! (rvtol-engine), which never uses it.
//!
//! - [`sensitivity`]: Sobol' indices by group with their intervals ([`sensitivity_report`]
//!   the report), [`shapley`] effects for correlated inputs, [`screening`] by derivatives
//!   at the nominal point;
//! - [`gate`]: the CI gate, a baseline's figures with their noise bands and the check of a
//!   re-run against them; [`target`] the requirement grammar it shares with the
//!   allocation and the page;
//! - [`allocation`]: the cheapest tolerances that meet a target;
//! - [`rare`]: the probability of a rare event (1 ppm and below) by importance sampling
//!   around FORM's design points and by subset simulation;
//! - [`assemblies`]: assemblies chosen for an output's value (the median, the tail), with
//!   the model curves at them, for a page;
//! - [`sweep`]: one or two design values over a grid, a whole run at each point;
//! - [`fit`]: a normal model of measured parts, as a scenario fragment;
//! - [`shard`]: a shard's file and the assembly of a set of them for the merge;
//! - [`request`]: the requests the command line and the Python module make (scenario
//!   sources, settings with their defaults and limits, memory), one API for both.

pub mod allocation;
pub mod assemblies;
pub mod fit;
pub mod gate;
pub mod rare;
pub mod request;
pub mod screening;
pub mod sensitivity;
pub mod sensitivity_report;
pub mod shapley;
pub mod shard;
pub mod stack;
pub mod sweep;
pub mod target;
