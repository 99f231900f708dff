//! Reports of a run and of a nominal evaluation: the JSON documents (a stable contract for
//! users' scripts) and the readable text tables. The engine renders; the CLI writes.
//!
//! JSON of `run`: `rvtol_version`, `scenario`, `seed`, `samples`, `chunk_size`,
//! `percentile_method`, `constraint` (when a part has the 001 Eq. 11 constraint) and
//! `outputs`, an array with per output `name`, `unit`, `kind`, `n`, `non_finite`, `mean`,
//! `sd`, `skewness`, `excess_kurtosis`, `min`, `max`, `percentiles` (keyed by the percent
//! as a string), `histogram`; indicator outputs add `events`, `fraction`, `fraction_ci95`;
//! outputs with spec limits add `spec`, `cp` (null when one-sided) with `cp_ci95`, `cpk`
//! with `cpk_ci95`, `cp_percentile`, `cpk_percentile`, `ppm_out`, `ppm_out_ci95`. No timing
//! and no thread count: the document is byte-identical for the same seed and samples.

use rayon::prelude::*;
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use crate::chunk::CHUNK_SIZE;
use crate::evaluate::SampleTable;
use crate::run::{
    replicated_sd, Distribution, OutputAccumulator, PercentileMethod, ReplicateFigures, RunResult,
};
use crate::scenario::{OutputInfo, Scenario};
use crate::stats::quantile_sketch::bucket_representative;
use crate::stats::{
    binomial_rank_interval, capability_from_moments, capability_percentile_method,
    cpk_on_upper_side, cpk_standard_error, out_of_spec_interval, percentiles_type7_with_intervals,
    replicate_standard_error, student_t_quantile, Histogram, Moments, QuantileSketch, SpecLimits,
    StandardisedSketch,
};
use rvtol_deviation::Shown;

use crate::format::{format_ppm, format_sig, group_thousands};
use rvtol_models::{ConditionEffect, OutputKind};

pub use crate::stats::PERCENTS;
/// Bins of the report histograms.
pub const HISTOGRAM_BINS: usize = 40;
/// Confidence of the intervals on ppm and fractions.
pub const CONFIDENCE: f64 = 0.95;

/// Numbers keyed by name, serialised as a JSON object in the given order.
#[derive(Debug, Clone, PartialEq)]
pub struct OrderedNumbers(pub Vec<(String, f64)>);

impl Serialize for OrderedNumbers {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (key, value) in &self.0 {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

impl OrderedNumbers {
    /// The value under `key`.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
    }
}

/// Intervals keyed by name, serialised as a JSON object of [lower, upper] pairs in the
/// given order; an end is null where the sample cannot bound it.
#[derive(Debug, Clone, PartialEq)]
pub struct OrderedIntervals(pub Vec<(String, [Option<f64>; 2])>);

impl Serialize for OrderedIntervals {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (key, value) in &self.0 {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

impl OrderedIntervals {
    /// The interval under `key`.
    pub fn get(&self, key: &str) -> Option<[Option<f64>; 2]> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
    }
}

/// How percentiles were computed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PercentileMethodReport {
    /// `exact` or `sketch`.
    pub kind: &'static str,
    /// The estimator, in words.
    pub estimator: &'static str,
    /// Relative error bound of a sketch.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_error: Option<f64>,
}

/// Acceptance of the 001 Eq. 11 constraint.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstraintReport {
    /// JSON paths of the constrained parts.
    pub parts: Vec<String>,
    /// Independent groups of inequalities, each drawn by its own rejection loop.
    pub independent_groups: usize,
    /// Candidate draws over all groups.
    pub candidate_draws: u64,
    /// Probability that an unconstrained draw satisfies the whole constraint (product of
    /// the groups' acceptance rates; for a replicated run, from the build's pilot).
    pub acceptance_rate: f64,
    /// How a replicated run drew the constrained parts (absent: by rejection, counted in
    /// `candidate_draws`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drawn_by: Option<&'static str>,
}

/// How a Latin hypercube or RQMC run drew its rows (absent from a Monte Carlo report).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SamplingReport {
    /// `lhs` or `rqmc`.
    pub method: &'static str,
    /// Independent randomizations R.
    pub replicates: u64,
    /// Points n of each (samples = R·n).
    pub points_per_replicate: u64,
    /// How the intervals are computed (`replicate_ci95` of a run, the indices' intervals
    /// of a sensitivity analysis).
    pub interval_method: &'static str,
}

/// The 95 % intervals of a replicated run's figures from the spread of their replicate
/// values: the figure of all rows ± t(0.975, R − 1)·s/√R, s the standard deviation of
/// the R replicates' values of it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplicateIntervals {
    /// Of the mean.
    pub mean: [f64; 2],
    /// Of the standard deviation.
    pub sd: [f64; 2],
    /// Of each percentile.
    pub percentiles: OrderedIntervals,
    /// Of ppm out of spec (lower end at least 0), when the output has spec limits and some
    /// but not all rows are out of spec.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ppm_out_of_spec: Option<[f64; 2]>,
}

/// What `interval_method` says.
const REPLICATE_INTERVAL_METHOD: &str = "figure of all rows +- t(0.975, R-1)*s/sqrt(R), s the standard deviation of the figure over the R independent replicates";

/// Histogram in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HistogramReport {
    /// Left edge of the first bin.
    pub lower_edge: f64,
    /// Bin width.
    pub bin_width: f64,
    /// Counts per bin.
    pub counts: Vec<u64>,
}

/// Capability figures of an output with spec limits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CapabilityReport {
    /// The limits.
    pub spec: SpecReport,
    /// Cp = (U − L)/(6σ); null when one-sided or not given (`capability_note`).
    pub cp: Option<f64>,
    /// 95 % interval of Cp: Cp·(1 ± z·SE(s)/s), SE(s) = s·√((κ + 2)/(4n)) (delta method).
    pub cp_ci95: Option<[f64; 2]>,
    /// Cpk = min(U − μ, μ − L)/(3σ) over the limits set; null when not given.
    pub cpk: Option<f64>,
    /// 95 % interval of Cpk: Cpk ± z·SE, SE by the delta method with the output's skewness
    /// and kurtosis ([`crate::stats::cpk_standard_error`]; Bissell 1990 for a normal).
    pub cpk_ci95: Option<[f64; 2]>,
    /// Percentile-method Cp = (U − L)/(P99.865 − P0.135) (ISO 22514-2); null when
    /// one-sided or not given.
    pub cp_percentile: Option<f64>,
    /// Percentile-method Cpk; null when not given.
    pub cpk_percentile: Option<f64>,
    /// Why the indices are not given, when they are not: samples that do not conform
    /// although the values do not show it (not finite, excluded, flagged), or values
    /// without spread.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub capability_note: Option<String>,
    /// Samples out of spec per million samples drawn: outside the limits, not finite,
    /// excluded or flagged non-conforming.
    pub ppm_out: f64,
    /// Clopper–Pearson 95 % interval on `ppm_out`.
    pub ppm_out_ci95: [f64; 2],
}

/// The samples an output's qualifying indicator excluded or flagged.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionReport {
    /// The indicator output.
    pub indicator: String,
    /// `excluded` (no value: kept out of the statistics) or `non-conforming` (the value is
    /// in the statistics, the sample does not conform).
    pub effect: &'static str,
    /// Samples with the indicator set.
    pub samples: u64,
    /// Their share of the samples drawn.
    pub fraction: f64,
    /// Whether a flagged sample within the limits conforms (`spec_limits` setting).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub flagged_conform: bool,
}

/// Spec limits in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpecReport {
    /// Lower limit or null.
    pub lower: Option<f64>,
    /// Upper limit or null.
    pub upper: Option<f64>,
}

/// Statistics of one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputReport {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// `continuous` or `indicator`.
    pub kind: &'static str,
    /// Finite samples (those in the statistics below).
    pub n: u64,
    /// Samples whose value was not finite although nothing excluded them: lost data, kept
    /// out of the statistics and counted out of spec.
    pub non_finite: u64,
    /// `non_finite` as a share of the samples drawn.
    pub non_finite_fraction: f64,
    /// The first sample (index in the run) whose value was not finite.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_non_finite_sample: Option<u64>,
    /// The samples the output's qualifying indicator excluded or flagged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub condition: Option<ConditionReport>,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1).
    pub sd: f64,
    /// Skewness g1.
    pub skewness: f64,
    /// Excess kurtosis g2.
    pub excess_kurtosis: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Percentiles keyed by percent.
    pub percentiles: OrderedNumbers,
    /// Bound on each percentile's error from the percentile method, in the output's unit:
    /// 0 for exact order statistics; for the sketch, α·|percentile − centre|.
    pub percentile_error_bounds: OrderedNumbers,
    /// Distribution-free 95 % confidence interval of each percentile: the order
    /// statistics [X_(l), X_(u)] of the exact binomial ranks (Hahn & Meeker 1991 §5.2;
    /// `binomial_rank_interval`), from the sketch moved out by its error bound; an end is
    /// null where too few values lie beyond the percentile to bound it.
    pub percentile_ci95: OrderedIntervals,
    /// Histogram over [min, max].
    pub histogram: HistogramReport,
    /// Events (samples with value ≠ 0) of an indicator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<u64>,
    /// events / n of an indicator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fraction: Option<f64>,
    /// Clopper–Pearson 95 % interval on `fraction`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fraction_ci95: Option<[f64; 2]>,
    /// Capability, when spec limits are set.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub capability: Option<CapabilityReport>,
    /// A replicated run's 95 % intervals from its replicates (the iid intervals above
    /// assume independent rows, which a Latin hypercube or RQMC replicate does not have).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replicate_ci95: Option<ReplicateIntervals>,
}

/// The report of `rvtol run`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// Seed.
    pub seed: u64,
    /// Samples drawn.
    pub samples: u64,
    /// Samples per chunk (reproducibility contract).
    pub chunk_size: usize,
    /// How percentiles were computed.
    pub percentile_method: PercentileMethodReport,
    /// Constraint acceptance, when a part is constrained.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraint: Option<ConstraintReport>,
    /// How the rows were drawn, for a Latin hypercube or RQMC run (absent: Monte Carlo).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampling: Option<SamplingReport>,
    /// One entry per output.
    pub outputs: Vec<OutputReport>,
}

/// The capability figures of one output from its statistics. `samples` is every sample
/// drawn, `out` those that do not conform, `hidden` those among them that the values do
/// not show (with the reason), which leaves the indices undefined.
fn capability(
    limits: SpecLimits,
    m: &Moments,
    percentiles: &OrderedNumbers,
    samples: u64,
    out: u64,
    hidden: Option<String>,
) -> CapabilityReport {
    let (ppm, lower, upper) = out_of_spec_interval(out, samples, CONFIDENCE).to_ppm();
    let mut report = CapabilityReport {
        spec: SpecReport {
            lower: limits.lower,
            upper: limits.upper,
        },
        cp: None,
        cp_ci95: None,
        cpk: None,
        cpk_ci95: None,
        cp_percentile: None,
        cpk_percentile: None,
        capability_note: None,
        ppm_out: ppm,
        ppm_out_ci95: [lower, upper],
    };
    if let Some(reason) = hidden {
        report.capability_note = Some(format!(
            "indices not given: {reason}; the indices of the remaining values would overstate the capability, ppm_out counts these samples"
        ));
        return report;
    }
    if m.n < 2 || m.sd().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        report.capability_note =
            Some("indices not given: the values do not spread (sd 0)".to_string());
        return report;
    }
    let moment = capability_from_moments(m.mean, m.sd(), limits);
    let pct = capability_percentile_method(
        percentiles.get("0.135").unwrap_or(f64::NAN),
        percentiles.get("50").unwrap_or(f64::NAN),
        percentiles.get("99.865").unwrap_or(f64::NAN),
        limits,
    );
    report.cp = moment.cp;
    report.cpk = moment.cpk;
    // z of the two-sided 95 % normal interval.
    const Z95: f64 = 1.959963984540054;
    let symmetric = |value: f64, se: f64| [value - Z95 * se, value + Z95 * se];
    report.cp_ci95 = moment
        .cp
        .map(|cp| symmetric(cp, cp * m.sd_standard_error() / m.sd()));
    report.cpk_ci95 = moment.cpk.map(|cpk| {
        let upper_side = cpk_on_upper_side(m.mean, limits);
        symmetric(
            cpk,
            cpk_standard_error(cpk, upper_side, m.n, m.skewness(), m.excess_kurtosis()),
        )
    });
    report.cp_percentile = pct.cp;
    report.cpk_percentile = pct.cpk;
    if report.cpk_percentile.is_none() {
        report.capability_note = Some(
            "percentile-method indices not given: the percentiles do not spread on the side of a limit".to_string(),
        );
    }
    report
}

/// The samples of an output that do not conform although its values do not show it, as
/// words for the capability note (none: the values tell the whole story).
fn hidden_nonconforming(
    acc: &OutputAccumulator,
    info: &OutputInfo,
    samples: u64,
) -> Option<String> {
    let share = |count: u64| {
        format!(
            "{} samples ({} %)",
            group_thousands(count),
            format_sig(100.0 * count as f64 / samples as f64)
        )
    };
    let mut parts = Vec::new();
    if acc.non_finite > 0 {
        parts.push(format!("{} are not finite", share(acc.non_finite)));
    }
    if acc.excluded > 0 {
        parts.push(format!("{} are excluded", share(acc.excluded)));
    }
    if acc.flagged_within_spec > 0 && !info.flagged_conform {
        parts.push(format!(
            "{} are flagged non-conforming within the limits",
            share(acc.flagged_within_spec)
        ));
    }
    (!parts.is_empty()).then(|| parts.join(", "))
}

impl RunReport {
    /// Builds the report of a finished run (computes percentiles and histograms).
    pub fn new(scenario: &Scenario, mut result: RunResult) -> RunReport {
        let percentile_method = match result.percentile_method {
            PercentileMethod::Exact => PercentileMethodReport {
                kind: "exact",
                estimator: "order statistics, Hyndman-Fan type 7 (linear interpolation, as R and numpy default)",
                relative_error: None,
            },
            PercentileMethod::Sketch { relative_accuracy } => PercentileMethodReport {
                kind: "sketch",
                estimator: "relative-accuracy quantile sketch of (x - m)/s, m and s the mean and sd of the first chunk: each percentile lies within relative_error*|percentile - m| (percentile_error_bounds) of the order statistic of rank floor(q*(n-1))",
                relative_error: Some(relative_accuracy),
            },
        };
        let constraint = scenario
            .input_space
            .has_constraints()
            .then(|| ConstraintReport {
                parts: scenario.input_space.constraint_paths().to_vec(),
                independent_groups: result.constraint_counts.groups.len(),
                candidate_draws: result.constraint_counts.attempts(),
                acceptance_rate: if result.sampling.is_replicated() {
                    scenario.input_space.pilot_acceptance_rate()
                } else {
                    result.constraint_counts.acceptance_rate()
                },
                drawn_by: result
                    .sampling
                    .is_replicated()
                    .then_some("exact conditional inversion"),
            });
        let replicates = std::mem::take(&mut result.replicates);
        // t(0.975, R − 1) of the replicate intervals (R ≥ 2 whenever there are any).
        let replicate_t = (replicates.len() >= 2)
            .then(|| student_t_quantile((replicates.len() - 1) as f64, 0.975));
        // Each output's percentiles and histogram on its own (in parallel: the selection
        // over every kept value is the report's dearest step), collected in order.
        let outputs = scenario
            .outputs
            .par_iter()
            .zip(result.outputs.par_iter_mut())
            .enumerate()
            .map(|(o, (info, acc))| {
                let m = &acc.moments;
                let (min, max) = if m.n > 0 {
                    (m.min, m.max)
                } else {
                    (f64::NAN, f64::NAN)
                };
                let exact_bounds = || vec![0.0; PERCENTS.len()];
                let n_values = m.n as usize;
                let rank_intervals = || {
                    PERCENTS
                        .iter()
                        .map(|p| binomial_rank_interval(n_values, p.1 / 100.0, CONFIDENCE))
                };
                let (percentiles, bounds, intervals, histogram) = match &mut acc.distribution {
                    Distribution::Values(values) => {
                        let percents: Vec<f64> = PERCENTS.iter().map(|p| p.1).collect();
                        let histogram = Histogram::from_values(values, min, max, HISTOGRAM_BINS);
                        let found = percentiles_type7_with_intervals(values, &percents, CONFIDENCE);
                        let intervals: Vec<[Option<f64>; 2]> = found
                            .iter()
                            .map(|f| f.map_or([None, None], |f| [f.lower, f.upper]))
                            .collect();
                        let found: Vec<Option<f64>> =
                            found.iter().map(|f| f.map(|f| f.value)).collect();
                        (found, exact_bounds(), intervals, histogram)
                    }
                    Distribution::Sketch {
                        sketch,
                        center,
                        scale,
                    } => {
                        let alpha = sketch.relative_accuracy();
                        let standardised: Vec<Option<f64>> = PERCENTS
                            .iter()
                            .map(|p| sketch.quantile(p.1 / 100.0))
                            .collect();
                        // Back to output units; the true order statistic lies in [min, max].
                        let values = standardised
                            .iter()
                            .map(|z| z.map(|z| (*center + *scale * z).clamp(min, max)))
                            .collect();
                        let bounds = standardised
                            .iter()
                            .map(|z| z.map_or(f64::NAN, |z| alpha * (*scale * z).abs()))
                            .collect();
                        let histogram =
                            histogram_of_standardised_sketch(sketch, *center, *scale, min, max);
                        let read = StandardisedSketch {
                            sketch,
                            center: *center,
                            scale: *scale,
                            min,
                            max,
                        };
                        let intervals = rank_intervals()
                            .map(|(l, u)| {
                                [
                                    l.map(|r| read.order_statistic(r as u64, -1.0)),
                                    u.map(|r| read.order_statistic(r as u64, 1.0)),
                                ]
                            })
                            .collect();
                        (values, bounds, intervals, histogram)
                    }
                    Distribution::Dropped => {
                        unreachable!("a run for a report keeps every output's distribution")
                    }
                    Distribution::Indicator => {
                        let zeros = m.n - acc.nonzero;
                        let value = |rank: usize| if (rank as u64) < zeros { 0.0 } else { 1.0 };
                        (
                            PERCENTS
                                .iter()
                                .map(|p| binary_percentile(zeros, m.n, p.1))
                                .collect(),
                            exact_bounds(),
                            rank_intervals()
                                .map(|(l, u)| [l.map(value), u.map(value)])
                                .collect(),
                            Histogram {
                                lower_edge: 0.0,
                                bin_width: 0.5,
                                counts: vec![zeros, acc.nonzero],
                            },
                        )
                    }
                };
                let percentiles = OrderedNumbers(
                    PERCENTS
                        .iter()
                        .zip(percentiles)
                        .map(|((key, _), v)| (key.to_string(), v.unwrap_or(f64::NAN)))
                        .collect(),
                );
                let percentile_error_bounds = OrderedNumbers(
                    PERCENTS
                        .iter()
                        .zip(bounds)
                        .map(|((key, _), b)| (key.to_string(), b))
                        .collect(),
                );
                let percentile_ci95 = OrderedIntervals(
                    PERCENTS
                        .iter()
                        .zip(intervals)
                        .map(|((key, _), i)| (key.to_string(), i))
                        .collect(),
                );
                let indicator = info.kind == OutputKind::Indicator;
                let events = indicator.then_some(acc.nonzero);
                let interval = out_of_spec_interval(acc.nonzero, m.n, CONFIDENCE);
                let samples = result.samples;
                let defined = |x: f64| if m.n > 0 { x } else { f64::NAN };
                // A replicated run's sd is unbiased under its design (`ReplicateFigures`).
                let sd = replicated_sd(&replicates, o).unwrap_or_else(|| m.sd());
                let replicate_ci95 = replicate_t.filter(|_| !indicator).map(|t| {
                    // A figure's replicate estimate ± (t·s/√R + its bias bound), stretched to
                    // hold the figure of all rows; none where a replicate has no value.
                    let around = |pooled: Option<f64>, values: Vec<f64>, bias: f64| {
                        let centre = values.iter().sum::<f64>() / values.len() as f64;
                        let h = t * replicate_standard_error(&values) + bias;
                        match pooled {
                            Some(p) if h.is_finite() && centre.is_finite() && p.is_finite() => {
                                [Some((centre - h).min(p)), Some((centre + h).max(p))]
                            }
                            _ => [None, None],
                        }
                    };
                    let of = |pooled: f64, figure: fn(&ReplicateFigures) -> f64| {
                        let values = replicates.iter().map(|r| figure(&r[o])).collect();
                        let [l, u] = around(Some(pooled), values, 0.0);
                        [l.unwrap_or(f64::NAN), u.unwrap_or(f64::NAN)]
                    };
                    ReplicateIntervals {
                        mean: of(m.mean, |r| r.mean),
                        sd: of(sd, |r| r.sd),
                        percentiles: OrderedIntervals(
                            PERCENTS
                                .iter()
                                .enumerate()
                                .map(|(k, (key, _))| {
                                    let read = |figures: &ReplicateFigures| {
                                        (figures.percentiles[k])
                                            .zip(figures.percentile_bias_bounds[k])
                                            .unwrap_or((f64::NAN, f64::NAN))
                                    };
                                    let (values, bounds): (Vec<f64>, Vec<f64>) =
                                        replicates.iter().map(|r| read(&r[o])).unzip();
                                    let bias = bounds.iter().sum::<f64>() / bounds.len() as f64;
                                    (key.to_string(), around(percentiles.get(key), values, bias))
                                })
                                .collect(),
                        ),
                        // Not when no row or every row is out of spec: the replicates then
                        // agree exactly and their spread says nothing (the Clopper–Pearson
                        // interval of the capability still does).
                        ppm_out_of_spec: info.spec.and_then(|_| {
                            let out = acc.out_of_spec(info.flagged_conform);
                            (out > 0 && out < samples).then(|| {
                                let [l, u] = of(1e6 * out as f64 / samples as f64, |r| {
                                    1e6 * r.out_of_spec_fraction
                                });
                                [l.max(0.0), u]
                            })
                        }),
                    }
                });
                OutputReport {
                    name: info.name.clone(),
                    unit: info.unit.clone(),
                    kind: if indicator { "indicator" } else { "continuous" },
                    n: m.n,
                    non_finite: acc.non_finite,
                    non_finite_fraction: acc.non_finite as f64 / samples as f64,
                    first_non_finite_sample: acc.first_non_finite,
                    condition: info.condition.map(|(k, effect)| {
                        let (effect, count) = match effect {
                            ConditionEffect::Excluded => ("excluded", acc.excluded),
                            ConditionEffect::NonConforming => ("non-conforming", acc.flagged),
                        };
                        ConditionReport {
                            indicator: scenario.outputs[k].name.clone(),
                            effect,
                            samples: count,
                            fraction: count as f64 / samples as f64,
                            flagged_conform: info.flagged_conform,
                        }
                    }),
                    mean: defined(m.mean),
                    sd: defined(sd),
                    skewness: defined(m.skewness()),
                    excess_kurtosis: defined(m.excess_kurtosis()),
                    min,
                    max,
                    capability: info.spec.map(|limits| {
                        capability(
                            limits,
                            m,
                            &percentiles,
                            samples,
                            acc.out_of_spec(info.flagged_conform),
                            hidden_nonconforming(acc, info, samples),
                        )
                    }),
                    percentiles,
                    percentile_error_bounds,
                    percentile_ci95,
                    histogram: HistogramReport {
                        lower_edge: histogram.lower_edge,
                        bin_width: histogram.bin_width,
                        counts: histogram.counts,
                    },
                    events,
                    fraction: indicator.then_some(interval.fraction),
                    fraction_ci95: indicator.then_some([interval.lower, interval.upper]),
                    replicate_ci95,
                }
            })
            .collect();
        RunReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            seed: result.seed,
            samples: result.samples,
            chunk_size: CHUNK_SIZE,
            percentile_method,
            constraint,
            sampling: result.sampling.is_replicated().then(|| SamplingReport {
                method: result.sampling.method.name(),
                replicates: result.sampling.replicates,
                points_per_replicate: result.samples / result.sampling.replicates,
                interval_method: REPLICATE_INTERVAL_METHOD,
            }),
            outputs,
        }
    }

    /// The JSON document (pretty-printed, trailing newline).
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("report serialises");
        text.push('\n');
        text
    }

    /// The readable summary: a table of the outputs, capability lines and a text histogram
    /// per continuous output.
    pub fn to_text(&self) -> String {
        let mut lines = Vec::new();
        let method = match self.percentile_method.relative_error {
            Some(alpha) => {
                format!("percentiles from a sketch (error ≤ {alpha:e} × distance from the centre)")
            }
            None => "exact percentiles (type 7)".to_string(),
        };
        lines.push(format!(
            "rvtol {} | scenario {} | {} samples | seed {} | {method}",
            self.rvtol_version,
            self.scenario,
            group_thousands(self.samples),
            self.seed
        ));
        if let Some(sampling) = &self.sampling {
            lines.push(format!(
                "sampling {}: {} independent replicates of {} points; intervals from the replicates' spread (Student t, {} degrees of freedom)",
                match sampling.method {
                    "lhs" => "Latin hypercube",
                    _ => "randomized QMC (scrambled Sobol')",
                },
                sampling.replicates,
                group_thousands(sampling.points_per_replicate),
                sampling.replicates - 1
            ));
        }
        if let Some(c) = &self.constraint {
            lines.push(match c.drawn_by {
                Some(method) => format!(
                    "constraint 001 Eq. 11 on {}: drawn by {method} (it holds for {:.2} % of unconstrained draws)",
                    c.parts.join(", "),
                    100.0 * c.acceptance_rate,
                ),
                None => format!(
                    "constraint 001 Eq. 11 on {}: acceptance {:.2} % ({} candidate draws in {} independent groups)",
                    c.parts.join(", "),
                    100.0 * c.acceptance_rate,
                    group_thousands(c.candidate_draws),
                    c.independent_groups
                ),
            });
        }
        lines.push(String::new());
        let name_width = name_column_width(self.outputs.iter().map(|o| o.name.as_str()));
        lines.push(format!(
            "{:<name_width$}  {:<8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
            "output", "unit", "mean", "sd", "P0.135", "P50", "P99.865", "min", "max"
        ));
        for o in &self.outputs {
            if o.kind == "indicator" {
                let ci = o.fraction_ci95.unwrap_or([f64::NAN; 2]);
                lines.push(format!(
                    "{:<name_width$}  {:<8} {:>10}  of samples (95 % CI {} .. {} %)",
                    o.name,
                    "%",
                    format!("{:.4}", 100.0 * o.fraction.unwrap_or(f64::NAN)),
                    format_sig(100.0 * ci[0]),
                    format_sig(100.0 * ci[1]),
                ));
                continue;
            }
            lines.push(format!(
                "{:<name_width$}  {:<8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}",
                o.name,
                o.unit,
                format_sig(o.mean),
                format_sig(o.sd),
                format_sig(o.percentiles.get("0.135").unwrap_or(f64::NAN)),
                format_sig(o.percentiles.get("50").unwrap_or(f64::NAN)),
                format_sig(o.percentiles.get("99.865").unwrap_or(f64::NAN)),
                format_sig(o.min),
                format_sig(o.max),
            ));
        }
        let continuous: Vec<&OutputReport> = self
            .outputs
            .iter()
            .filter(|o| o.kind != "indicator" && o.n > 0)
            .collect();
        if let (false, Some(sampling)) = (continuous.is_empty(), &self.sampling) {
            lines.push(String::new());
            lines.push(format!(
                "95 % intervals from the {} replicates",
                sampling.replicates
            ));
            lines.push(format!(
                "{:<name_width$}  {:>23} {:>23} {:>23} {:>23}",
                "output", "mean", "sd", "P50", "P99.865"
            ));
            let pair = |[l, u]: [Option<f64>; 2]| match (l, u) {
                (Some(l), Some(u)) => format!("{} .. {}", format_sig(l), format_sig(u)),
                _ => "n/a".to_string(),
            };
            for o in &continuous {
                let Some(r) = &o.replicate_ci95 else { continue };
                let [ml, mu] = r.mean;
                let [sl, su] = r.sd;
                lines.push(format!(
                    "{:<name_width$}  {:>23} {:>23} {:>23} {:>23}",
                    o.name,
                    pair([
                        Some(ml).filter(|x| x.is_finite()),
                        Some(mu).filter(|x| x.is_finite())
                    ]),
                    pair([
                        Some(sl).filter(|x| x.is_finite()),
                        Some(su).filter(|x| x.is_finite())
                    ]),
                    pair(r.percentiles.get("50").unwrap_or([None, None])),
                    pair(r.percentiles.get("99.865").unwrap_or([None, None])),
                ));
            }
        } else if !continuous.is_empty() {
            let sketch = if self.percentile_method.relative_error.is_some() {
                ", from the sketch moved out by its error bound"
            } else {
                ""
            };
            lines.push(String::new());
            lines.push(format!(
                "95 % confidence intervals of the percentiles (distribution-free, order statistics{sketch})"
            ));
            lines.push(format!(
                "{:<name_width$}  {:>23} {:>23} {:>23}",
                "output", "P0.135", "P50", "P99.865"
            ));
            let end = |x: Option<f64>, open: &str| x.map_or(open.to_string(), format_sig);
            for o in continuous {
                let interval = |key: &str| {
                    let [l, u] = o.percentile_ci95.get(key).unwrap_or([None, None]);
                    format!("{} .. {}", end(l, "below min"), end(u, "above max"))
                };
                lines.push(format!(
                    "{:<name_width$}  {:>23} {:>23} {:>23}",
                    o.name,
                    interval("0.135"),
                    interval("50"),
                    interval("99.865")
                ));
            }
        }
        let with_spec: Vec<&OutputReport> = self
            .outputs
            .iter()
            .filter(|o| o.capability.is_some())
            .collect();
        if !with_spec.is_empty() {
            lines.push(String::new());
            lines.push("capability against spec limits".to_string());
            for o in with_spec {
                let c = o.capability.as_ref().expect("filtered");
                let spec = match (c.spec.lower.map(Shown), c.spec.upper.map(Shown)) {
                    (Some(l), Some(u)) => format!("{l} ≤ x ≤ {u}"),
                    (Some(l), None) => format!("x ≥ {l}"),
                    (None, Some(u)) => format!("x ≤ {u}"),
                    (None, None) => String::new(),
                };
                let index = |x: Option<f64>| x.map(format_sig).unwrap_or_else(|| "n/a".into());
                let with_ci = |x: Option<f64>, ci: Option<[f64; 2]>| match (x, ci) {
                    (Some(x), Some([lo, hi])) => format!(
                        "{} (95 % CI {} .. {})",
                        format_sig(x),
                        format_sig(lo),
                        format_sig(hi)
                    ),
                    (x, _) => index(x),
                };
                lines.push(format!(
                    "  {} ({spec} {}): Cp {}  Cpk {}  | percentile method Cp {}  Cpk {}  | out of spec {} ppm (95 % CI {} .. {})",
                    o.name,
                    o.unit,
                    with_ci(c.cp, c.cp_ci95),
                    with_ci(c.cpk, c.cpk_ci95),
                    index(c.cp_percentile),
                    index(c.cpk_percentile),
                    format_ppm(c.ppm_out),
                    format_ppm(c.ppm_out_ci95[0]),
                    format_ppm(c.ppm_out_ci95[1]),
                ));
                if let Some([l, u]) = o.replicate_ci95.as_ref().and_then(|r| r.ppm_out_of_spec) {
                    lines.push(format!(
                        "    out of spec from the replicates: 95 % interval {} .. {} ppm",
                        format_sig(l),
                        format_sig(u)
                    ));
                }
                if let Some(note) = &c.capability_note {
                    lines.push(format!("    {note}"));
                }
            }
        }
        for o in &self.outputs {
            if o.non_finite > 0 {
                lines.push(format!(
                    "lost data: {} of {} samples ({} %) of {} are not finite (first at sample {}): kept out of its statistics, counted out of spec",
                    group_thousands(o.non_finite),
                    group_thousands(self.samples),
                    format_sig(100.0 * o.non_finite_fraction),
                    o.name,
                    o.first_non_finite_sample.unwrap_or(0),
                ));
            }
            if let Some(c) = o.condition.as_ref().filter(|c| c.samples > 0) {
                let what = match (c.effect, c.flagged_conform) {
                    ("excluded", _) => {
                        "excluded (no value): kept out of its statistics, counted out of spec"
                    }
                    (_, false) => "flagged non-conforming: in its statistics, counted out of spec",
                    (_, true) => {
                        "flagged: in its statistics, conforming within the limits (flagged_conform)"
                    }
                };
                lines.push(format!(
                    "{}: {} samples ({} %) with {} set are {what}",
                    o.name,
                    group_thousands(c.samples),
                    format_sig(100.0 * c.fraction),
                    c.indicator,
                ));
            }
        }
        for o in self.outputs.iter().filter(|o| o.kind == "continuous") {
            lines.push(String::new());
            lines.push(format!("{} ({})", o.name, o.unit));
            if o.n == 0 {
                lines.push("  (no finite values)".to_string());
                continue;
            }
            let histogram = Histogram {
                lower_edge: o.histogram.lower_edge,
                bin_width: o.histogram.bin_width,
                counts: o.histogram.counts.clone(),
            };
            lines.extend(histogram.render_text(40));
        }
        let mut text = lines.join("\n");
        text.push('\n');
        text
    }
}

/// Histogram over [min, max] of a sketch of (x − center)/scale: each bucket's count goes to
/// the bin of its representative value mapped back to output units.
fn histogram_of_standardised_sketch(
    sketch: &QuantileSketch,
    center: f64,
    scale: f64,
    min: f64,
    max: f64,
) -> Histogram {
    let width = (max - min) / HISTOGRAM_BINS as f64;
    if !(width > 0.0 && width.is_finite()) {
        return Histogram {
            lower_edge: if min.is_finite() { min } else { 0.0 },
            bin_width: 0.0,
            counts: vec![sketch.count()],
        };
    }
    let mut counts = vec![0u64; HISTOGRAM_BINS];
    for (lo, hi, count) in sketch.buckets() {
        let value = center + scale * bucket_representative(lo, hi);
        let bin = ((value - min) / width)
            .floor()
            .clamp(0.0, (HISTOGRAM_BINS - 1) as f64);
        counts[bin as usize] += count;
    }
    Histogram {
        lower_edge: min,
        bin_width: width,
        counts,
    }
}

/// Type-7 percentile of a sample of `zeros` zeros followed by ones, `n` values in all.
fn binary_percentile(zeros: u64, n: u64, percent: f64) -> Option<f64> {
    if n == 0 {
        return None;
    }
    let h = (n - 1) as f64 * percent / 100.0;
    let low = h.floor() as u64;
    let value = |rank: u64| if rank < zeros { 0.0 } else { 1.0 };
    let (a, b) = (value(low), value((low + 1).min(n - 1)));
    Some(a + (h - low as f64) * (b - a))
}

/// The report of `rvtol nominal`: every output at the mean of every deviation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NominalReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// One entry per output.
    pub outputs: Vec<NominalOutput>,
}

/// One output at the nominal point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NominalOutput {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Value; null when the output's indicator excludes the nominal sample.
    pub value: Option<f64>,
    /// The indicator that excludes the nominal sample, when one does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excluded_by: Option<String>,
}

impl NominalReport {
    /// Builds the report from the nominal values ([`crate::run::nominal`]).
    pub fn new(scenario: &Scenario, values: &[Option<f64>]) -> NominalReport {
        NominalReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            outputs: scenario
                .outputs
                .iter()
                .zip(values)
                .map(|(o, &value)| NominalOutput {
                    name: o.name.clone(),
                    unit: o.unit.clone(),
                    value,
                    excluded_by: match (value, o.condition) {
                        (None, Some((k, _))) => Some(scenario.outputs[k].name.clone()),
                        _ => None,
                    },
                })
                .collect(),
        }
    }

    /// The JSON document.
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("report serialises");
        text.push('\n');
        text
    }

    /// A two-column table.
    pub fn to_text(&self) -> String {
        let width = name_column_width(self.outputs.iter().map(|o| o.name.as_str()));
        let mut text = format!(
            "scenario {} at nominal (every deviation at its mean)\n\n",
            self.scenario
        );
        for o in &self.outputs {
            let value = match (o.value, &o.excluded_by) {
                (Some(v), _) => format!("{v:.6}"),
                (None, Some(indicator)) => format!("excluded ({indicator})"),
                (None, None) => "-".to_string(),
            };
            text.push_str(&format!("{:<width$}  {:>12}  {}\n", o.name, value, o.unit));
        }
        text
    }
}

/// Width of a table's name column: the longest name, at least 6.
fn name_column_width<'a>(names: impl Iterator<Item = &'a str>) -> usize {
    names.map(str::len).max().unwrap_or(0).max(6)
}

/// The sample table as CSV: a `sample` index column, then one column per input-space
/// column and one per output, headed `name [unit]` (an indicator `name [0/1]`, its flag); numbers in Rust's shortest form that
/// reads back to the same value (non-finite values as `NaN`, `inf`, `-inf`, which pandas
/// and polars read). The same table gives the same bytes.
pub fn sample_csv(scenario: &Scenario, table: &SampleTable) -> String {
    let quote = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut out = sample_headings(scenario)
        .iter()
        .map(|h| quote(h))
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    use std::fmt::Write;
    for r in 0..table.rows {
        let _ = write!(out, "{r}");
        let inputs = &table.inputs[r * table.n_inputs..(r + 1) * table.n_inputs];
        let outputs = &table.outputs[r * table.n_outputs..(r + 1) * table.n_outputs];
        for v in inputs.iter().chain(outputs) {
            let _ = write!(out, ",{v}");
        }
        out.push('\n');
    }
    out
}

/// The column headings of a sample table, as both file formats name them: `sample`, then
/// `name [unit]` for every input column and every output (an indicator's unit is `0/1`: its
/// value is the flag, whatever unit its share is shown in).
pub fn sample_headings(scenario: &Scenario) -> Vec<String> {
    let heading = |name: &str, unit: Option<&str>| match unit {
        Some(unit) if !unit.is_empty() => format!("{name} [{unit}]"),
        _ => name.to_string(),
    };
    let mut headings = vec!["sample".to_string()];
    headings.extend(
        scenario
            .columns
            .iter()
            .map(|c| heading(&c.name, c.unit.as_deref())),
    );
    headings.extend(scenario.outputs.iter().map(|o| {
        let unit = if o.kind == OutputKind::Indicator {
            "0/1"
        } else {
            &o.unit
        };
        heading(&o.name, Some(unit))
    }));
    headings
}

/// Rows per row group of a sample table's Parquet file.
const PARQUET_ROW_GROUP: usize = 1 << 20;

/// A sample table as a Parquet file: the columns and headings of [`sample_csv`], `sample`
/// as INT64 and every other column as DOUBLE (the exact values), plain encoding, no
/// compression, row groups of 2^20 rows; no timestamp, so the same table gives the same
/// bytes. pandas (with pyarrow), polars and DuckDB read it as it is.
pub fn sample_parquet(scenario: &Scenario, table: &SampleTable) -> Result<Vec<u8>, String> {
    use parquet::basic::{Compression, Repetition, Type as PhysicalType};
    use parquet::data_type::{DoubleType, Int64Type};
    use parquet::file::properties::{EnabledStatistics, WriterProperties};
    use parquet::file::writer::SerializedFileWriter;
    use parquet::schema::types::Type;
    use std::sync::Arc;

    let error = |err: parquet::errors::ParquetError| format!("Parquet: {err}");
    let headings = sample_headings(scenario);
    let fields = headings
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let physical = if i == 0 {
                PhysicalType::INT64
            } else {
                PhysicalType::DOUBLE
            };
            Type::primitive_type_builder(name, physical)
                .with_repetition(Repetition::REQUIRED)
                .build()
                .map(Arc::new)
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(error)?;
    let schema = Type::group_type_builder("rvtol_samples")
        .with_fields(fields)
        .build()
        .map_err(error)?;
    let properties = WriterProperties::builder()
        .set_created_by(format!("rvtol {}", env!("CARGO_PKG_VERSION")))
        .set_compression(Compression::UNCOMPRESSED)
        .set_dictionary_enabled(false)
        .set_statistics_enabled(EnabledStatistics::Chunk)
        .build();
    let mut writer = SerializedFileWriter::new(Vec::new(), Arc::new(schema), Arc::new(properties))
        .map_err(error)?;
    let mut start = 0;
    while start < table.rows || (table.rows == 0 && start == 0) {
        let end = (start + PARQUET_ROW_GROUP).min(table.rows);
        let mut group = writer.next_row_group().map_err(error)?;
        let mut column = 0;
        while let Some(mut writer) = group.next_column().map_err(error)? {
            if column == 0 {
                let index: Vec<i64> = (start as i64..end as i64).collect();
                writer
                    .typed::<Int64Type>()
                    .write_batch(&index, None, None)
                    .map_err(error)?;
            } else {
                let (values, width, j) = if column <= table.n_inputs {
                    (&table.inputs, table.n_inputs, column - 1)
                } else {
                    (&table.outputs, table.n_outputs, column - 1 - table.n_inputs)
                };
                let data: Vec<f64> = (start..end).map(|r| values[r * width + j]).collect();
                writer
                    .typed::<DoubleType>()
                    .write_batch(&data, None, None)
                    .map_err(error)?;
            }
            writer.close().map_err(error)?;
            column += 1;
        }
        group.close().map_err(error)?;
        if table.rows == 0 {
            break;
        }
        start = end;
    }
    writer.into_inner().map_err(error)
}
