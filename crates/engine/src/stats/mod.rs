//! Statistics of Monte Carlo samples: mergeable central moments, a
//! relative-accuracy quantile sketch, exact percentiles, histograms and
//! process-capability indices.
//!
//! Everything here is deterministic: [`Moments`] merged in a fixed (chunk)
//! order and [`QuantileSketch`] merged in any order give bit-identical results
//! whatever the number of threads that produced the chunks.
//!
//! Formula sources are cited in each submodule: Pébay 2008 (moment merging),
//! Masson, Rim & Lee 2019 (DDSketch), Hyndman & Fan 1996 (type 7 sample
//! quantiles), Clopper & Pearson 1934 (exact binomial interval) and
//! ISO 22514-2 (percentile method for capability indices).

pub mod capability;
pub mod exact;
pub mod histogram;
pub mod moments;
pub mod quantile_sketch;

pub use capability::{
    capability_from_moments, capability_percentile_method, cpk_on_upper_side, cpk_standard_error,
    out_of_spec_interval, MomentCapability, ProportionEstimate, SpecLimits,
};
pub use exact::{
    binomial_rank_interval, order_statistic_interval, percentile_type7, percentile_type7_of_sorted,
    percentiles_type7, percentiles_type7_with_intervals, PercentileWithInterval,
};
pub use histogram::Histogram;
pub use moments::{proportion_standard_error, Moments};
pub use quantile_sketch::{QuantileSketch, SketchMismatch, SketchParts, StandardisedSketch};
