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

pub mod binomial;
pub mod capability;
pub mod conformity;
pub mod exact;
pub mod histogram;
pub mod moments;
pub mod quantile_sketch;

pub use binomial::binomial_rank_interval;
pub use capability::{
    capability_from_moments, capability_percentile_method, cpk_on_upper_side, cpk_standard_error,
    out_of_spec_interval, MomentCapability, ProportionEstimate, SpecLimits,
};
pub use exact::{
    order_statistic_interval, percentile_type7, percentile_type7_of_sorted, percentiles_type7,
    percentiles_type7_with_intervals, percentiles_with_intervals_beyond, values_at_ranks,
    PercentileWithInterval,
};
/// Percentiles every report gives: the ±1, 2, 3 σ points of a normal law and the median.
pub const PERCENTS: [(&str, f64); 7] = [
    ("0.135", 0.135),
    ("2.275", 2.275),
    ("15.866", 15.866),
    ("50", 50.0),
    ("84.134", 84.134),
    ("97.725", 97.725),
    ("99.865", 99.865),
];

pub use histogram::Histogram;
pub use moments::{
    proportion_standard_error, replicate_standard_error, student_t_quantile, Moments,
};
pub use quantile_sketch::{QuantileSketch, SketchMismatch, SketchParts, StandardisedSketch};
