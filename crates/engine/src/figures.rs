//! Every figure of every output of a run, computed once: moments, percentiles with their
//! error bounds and distribution-free 95 % intervals, the histogram, an indicator's
//! fraction, capability (Cp and Cpk with their intervals, the percentile method, ppm out
//! of spec with its Clopper–Pearson interval) and, for a replicated run, the intervals from
//! its replicates ([`output_figures`]). The run report ([`crate::report`]) renders them;
//! rvtol-analysis' gate turns them into bands and its allocation compares them with a
//! target, both reading order statistics at other ranks through [`OrderStatistics`] and
//! intervals at the one 95 % quantile, [`Z95`].

use rayon::prelude::*;
use rvtol_models::{ConditionEffect, OutputKind};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use crate::format::{format_sig, group_thousands};
use crate::run::{replicated_sd, KeptValues, OutputAccumulator, ReplicateFigures, RunResult};
use crate::scenario::{OutputInfo, Scenario};
use crate::stats::conformity::{interpolate_beyond, Placement};
use crate::stats::exact::type7_position;
use crate::stats::quantile_sketch::bucket_representative;
use crate::stats::{
    binomial_rank_interval, capability_from_moments, capability_percentile_method,
    cpk_on_upper_side, cpk_standard_error, out_of_spec_interval, percentiles_type7,
    percentiles_with_intervals_beyond, replicate_standard_error, student_t_quantile, Histogram,
    Moments, QuantileSketch, SpecLimits, StandardisedSketch,
};

pub use crate::stats::PERCENTS;
/// Bins of the report histograms.
pub const HISTOGRAM_BINS: usize = 40;
/// Confidence of the intervals on percentiles, ppm and fractions.
pub const CONFIDENCE: f64 = 0.95;
/// z of the two-sided 95 % normal interval, Φ⁻¹(0.975): the one such constant of the
/// figures, the gate's requirements and the allocation.
pub const Z95: f64 = 1.959963984540054;

/// `value ± Z95·se`: the symmetric 95 % interval of an estimate with standard error `se`.
pub fn symmetric95(value: f64, se: f64) -> [f64; 2] {
    [value - Z95 * se, value + Z95 * se]
}

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

/// An output's histogram.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HistogramFigures {
    /// Left edge of the first bin.
    pub lower_edge: f64,
    /// Bin width.
    pub bin_width: f64,
    /// Counts per bin.
    pub counts: Vec<u64>,
    /// Of them, the samples an indicator flags non-conforming, per bin (their values
    /// stand, but the assemblies do not conform): when the output has such samples.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flagged: Option<Vec<u64>>,
}

/// Capability figures of an output with spec limits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CapabilityFigures {
    /// The limits.
    pub spec: SpecFigures,
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
pub struct ConditionFigures {
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

/// An output's spec limits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpecFigures {
    /// Lower limit or null.
    pub lower: Option<f64>,
    /// Upper limit or null.
    pub upper: Option<f64>,
}

/// Every figure of one output of a run, as the run report gives it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputFigures {
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
    pub condition: Option<ConditionFigures>,
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
    /// Percentiles keyed by percent, as a conformity judgement reads them
    /// ([`crate::stats::conformity`]): a sample that does not conform although its value
    /// does not show it (flagged, excluded, not finite) lies beyond the limits in the tail
    /// the percentile reads; null where the percentile reads such a sample (beyond the
    /// limits). Without such samples, the type-7 percentiles of the values.
    pub percentiles: OrderedNumbers,
    /// Where samples lie beyond the limits: the plain percentiles of the finite values,
    /// flagged ones included (the values' distribution, not a conformity figure).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_percentiles: Option<OrderedNumbers>,
    /// Bound on each percentile's error from the percentile method, in the output's unit:
    /// 0 for exact order statistics; for the sketch, α·|percentile − centre|.
    pub percentile_error_bounds: OrderedNumbers,
    /// Distribution-free 95 % confidence interval of each percentile: the order
    /// statistics [X_(l), X_(u)] of the exact binomial ranks among all the samples (Hahn &
    /// Meeker 1991 §5.2; `binomial_rank_interval`), from the sketch moved out by its error
    /// bound; an end is null where too few samples lie beyond the percentile to bound it,
    /// or where it reads a sample beyond the limits (as `percentiles`).
    pub percentile_ci95: OrderedIntervals,
    /// Histogram over [min, max].
    pub histogram: HistogramFigures,
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
    pub capability: Option<CapabilityFigures>,
    /// A replicated run's 95 % intervals from its replicates (the iid intervals above
    /// assume independent rows, which a Latin hypercube or RQMC replicate does not have).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replicate_ci95: Option<ReplicateIntervals>,
}

/// The figures of every output of a run's result, in scenario order (each output's on its
/// own, in parallel: the selection over every kept value is the dearest step). The kept
/// values are reordered in place, never changed.
pub fn output_figures(scenario: &Scenario, result: &mut RunResult) -> Vec<OutputFigures> {
    let samples = result.samples;
    let replicates = &result.replicates;
    // t(0.975, R − 1) of the replicate intervals (R ≥ 2 whenever there are any).
    let replicate_t =
        (replicates.len() >= 2).then(|| student_t_quantile((replicates.len() - 1) as f64, 0.975));
    scenario
        .outputs
        .par_iter()
        .zip(result.outputs.par_iter_mut())
        .enumerate()
        .map(|(output, (info, acc))| {
            let context = OutputContext {
                scenario,
                output,
                info,
                samples,
                replicates,
                replicate_t,
            };
            context.figures(acc)
        })
        .collect()
}

/// What the figures of one output read besides its accumulator.
struct OutputContext<'a> {
    scenario: &'a Scenario,
    /// The output's index.
    output: usize,
    info: &'a OutputInfo,
    /// Samples drawn.
    samples: u64,
    /// Each replicate's figures (none for Monte Carlo).
    replicates: &'a [Vec<ReplicateFigures>],
    /// t(0.975, R − 1) of a replicated run.
    replicate_t: Option<f64>,
}

/// Figures keyed by the percents of [`PERCENTS`].
fn keyed<T>(values: impl IntoIterator<Item = T>) -> Vec<(String, T)> {
    PERCENTS
        .iter()
        .zip(values)
        .map(|((key, _), value)| (key.to_string(), value))
        .collect()
}

impl OutputContext<'_> {
    /// The figures of the output whose accumulator is `acc`.
    fn figures(&self, acc: &mut OutputAccumulator) -> OutputFigures {
        let (info, samples) = (self.info, self.samples);
        let found = percentile_figures(acc, samples, Placement::of(info.spec));
        let m = &acc.moments;
        let (min, max) = if m.n > 0 {
            (m.min, m.max)
        } else {
            (f64::NAN, f64::NAN)
        };
        let percentiles = OrderedNumbers(keyed(
            found.values.into_iter().map(|v| v.unwrap_or(f64::NAN)),
        ));
        let indicator = info.kind == OutputKind::Indicator;
        let interval = out_of_spec_interval(acc.nonzero, m.n, CONFIDENCE);
        let defined = |x: f64| if m.n > 0 { x } else { f64::NAN };
        // A replicated run's sd is unbiased under its design (`ReplicateFigures`).
        let sd = replicated_sd(self.replicates, self.output).unwrap_or_else(|| m.sd());
        let replicate_ci95 = (self.replicate_t)
            .filter(|_| !indicator)
            .map(|t| self.replicate_intervals(acc, sd, &percentiles, t));
        OutputFigures {
            name: info.name.clone(),
            unit: info.unit.clone(),
            kind: if indicator { "indicator" } else { "continuous" },
            n: m.n,
            non_finite: acc.non_finite,
            non_finite_fraction: acc.non_finite as f64 / samples as f64,
            first_non_finite_sample: acc.first_non_finite,
            condition: self.condition(acc),
            mean: defined(m.mean),
            sd: defined(sd),
            skewness: defined(m.skewness()),
            excess_kurtosis: defined(m.excess_kurtosis()),
            min,
            max,
            capability: info.spec.map(|limits| {
                capability_figures(
                    limits,
                    m,
                    &percentiles,
                    samples,
                    acc.out_of_spec(info.flagged_conform),
                    hidden_nonconforming(acc, info, samples),
                )
            }),
            percentiles,
            value_percentiles: found.of_values.map(|values| {
                OrderedNumbers(keyed(values.into_iter().map(|v| v.unwrap_or(f64::NAN))))
            }),
            percentile_error_bounds: OrderedNumbers(keyed(found.bounds)),
            percentile_ci95: OrderedIntervals(keyed(found.intervals)),
            histogram: HistogramFigures {
                lower_edge: found.histogram.lower_edge,
                bin_width: found.histogram.bin_width,
                counts: found.histogram.counts,
                flagged: found.flagged_counts,
            },
            events: indicator.then_some(acc.nonzero),
            fraction: indicator.then_some(interval.fraction),
            fraction_ci95: indicator.then_some([interval.lower, interval.upper]),
            replicate_ci95,
        }
    }

    /// The samples the output's qualifying indicator excluded or flagged.
    fn condition(&self, acc: &OutputAccumulator) -> Option<ConditionFigures> {
        self.info.condition.map(|(k, effect)| {
            let (effect, count) = match effect {
                ConditionEffect::Excluded => ("excluded", acc.excluded),
                ConditionEffect::NonConforming => ("non-conforming", acc.flagged),
            };
            ConditionFigures {
                indicator: self.scenario.outputs[k].name.clone(),
                effect,
                samples: count,
                fraction: count as f64 / self.samples as f64,
                flagged_conform: self.info.flagged_conform,
            }
        })
    }

    /// A replicated run's intervals of the output's figures from its replicates: each
    /// figure's replicate estimate ± (t·s/√R + its bias bound), stretched to hold the
    /// figure of all rows; none where a replicate has no value.
    fn replicate_intervals(
        &self,
        acc: &OutputAccumulator,
        sd: f64,
        percentiles: &OrderedNumbers,
        t: f64,
    ) -> ReplicateIntervals {
        let (o, replicates, samples, info) =
            (self.output, self.replicates, self.samples, self.info);
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
            mean: of(acc.moments.mean, |r| r.mean),
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
            // Not when no row or every row is out of spec: the replicates then agree
            // exactly and their spread says nothing (the Clopper–Pearson interval of the
            // capability still does).
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
    }
}

/// One output's percentiles (per [`PERCENTS`]), their error bounds and 95 % intervals,
/// its histogram, and where samples lie beyond the limits, the plain percentiles of its
/// values.
struct PercentileFigures {
    values: Vec<Option<f64>>,
    bounds: Vec<f64>,
    intervals: Vec<[Option<f64>; 2]>,
    histogram: Histogram,
    /// The histogram's counts of flagged samples alone, when there are any.
    flagged_counts: Option<Vec<u64>>,
    of_values: Option<Vec<Option<f64>>>,
}

/// The percentiles as a conformity judgement reads them ([`crate::stats::conformity`]:
/// the samples of `samples` whose value is not among the conforming ones lie beyond the
/// limits), their bounds and intervals, and the histogram of every finite value (flagged
/// ones included): exact order statistics of the kept values (one selection pass,
/// reordering them), read from the sketch, or those of an indicator's zeros and ones.
fn percentile_figures(
    acc: &mut OutputAccumulator,
    samples: u64,
    placement: Placement,
) -> PercentileFigures {
    let m = &acc.moments;
    let (min, max) = if m.n > 0 {
        (m.min, m.max)
    } else {
        (f64::NAN, f64::NAN)
    };
    let beyond = acc.beyond(samples);
    let percents: Vec<f64> = PERCENTS.iter().map(|p| p.1).collect();
    match (&mut acc.kept, &mut acc.flagged_kept) {
        (KeptValues::Values(values), flagged) => {
            let flagged: &[f64] = match flagged {
                KeptValues::Values(flagged) => flagged,
                _ => &[],
            };
            let mut histogram = Histogram::from_values(values, min, max, HISTOGRAM_BINS);
            let flagged_counts = (!flagged.is_empty())
                .then(|| Histogram::from_values(flagged, min, max, HISTOGRAM_BINS).counts);
            histogram.add_values(flagged);
            // The plain percentiles of the values, before the selection reorders them.
            let of_values = (beyond > 0).then(|| {
                let mut all = [&values[..], flagged].concat();
                percentiles_type7(&mut all, &percents)
            });
            let found = percentiles_with_intervals_beyond(
                values,
                &percents,
                CONFIDENCE,
                beyond as usize,
                placement,
            );
            PercentileFigures {
                intervals: found
                    .iter()
                    .map(|f| f.map_or([None, None], |f| [f.lower, f.upper]))
                    .collect(),
                values: found.iter().map(|f| f.map(|f| f.value)).collect(),
                bounds: vec![0.0; PERCENTS.len()],
                histogram,
                flagged_counts,
                of_values,
            }
        }
        (
            KeptValues::Sketch {
                sketch,
                center,
                scale,
            },
            flagged,
        ) => {
            let flagged = match flagged {
                KeptValues::Sketch { sketch, .. } => Some(&*sketch),
                _ => None,
            };
            let read = StandardisedSketch {
                sketch,
                center: *center,
                scale: *scale,
                min,
                max,
            };
            sketch_percentile_figures(read, flagged, beyond, placement)
        }
        (KeptValues::Dropped, _) => {
            unreachable!("a run for a report keeps every output's distribution")
        }
        (KeptValues::Indicator, _) => indicator_percentile_figures(acc.nonzero, m.n),
    }
}

/// [`percentile_figures`] from the sketch of the conforming values (`read`), the sketch of
/// the flagged ones and the count of samples beyond the limits.
fn sketch_percentile_figures(
    read: StandardisedSketch,
    flagged: Option<&QuantileSketch>,
    beyond: u64,
    placement: Placement,
) -> PercentileFigures {
    let (sketch, center, scale) = (read.sketch, read.center, read.scale);
    let alpha = sketch.relative_accuracy();
    let n = sketch.count() as usize;
    let count = n + beyond as usize;
    // Rank ⌊q·(N − 1)⌋ among all N samples (the sketch's quantile when none is beyond).
    let standardised: Vec<Result<f64, f64>> = PERCENTS
        .iter()
        .map(|&(_, percent)| {
            let last = count.saturating_sub(1);
            let q = (percent / 100.0).clamp(0.0, 1.0);
            let rank = ((q * last as f64).floor() as usize).min(last);
            match placement.value_rank(rank, n, beyond as usize, percent) {
                Some(k) if n > 0 => sketch.order_statistic(k as u64).ok_or(f64::NAN),
                _ if count == 0 => Err(f64::NAN),
                _ => Err(placement.beyond_value(percent)),
            }
        })
        .collect();
    let mut histogram = histogram_of_standardised_sketch(sketch, center, scale, read.min, read.max);
    let mut flagged_counts = None;
    if let Some(flagged) = flagged {
        let more = histogram_of_standardised_sketch(flagged, center, scale, read.min, read.max);
        histogram.add_counts(&more);
        flagged_counts = more.counts.iter().any(|&c| c > 0).then_some(more.counts);
    }
    let of_values = (beyond > 0).then(|| {
        let mut all = sketch.clone();
        if let Some(flagged) = flagged {
            all.merge(flagged)
                .expect("the two sketches of one output share their accuracy");
        }
        PERCENTS
            .iter()
            .map(|p| {
                all.quantile(p.1 / 100.0)
                    .map(|z| (center + scale * z).clamp(read.min, read.max))
            })
            .collect()
    });
    PercentileFigures {
        // Back to output units; the true order statistic lies in [min, max].
        values: standardised
            .iter()
            .map(|z| match *z {
                Ok(z) => Some((center + scale * z).clamp(read.min, read.max)),
                Err(beyond) => Some(beyond).filter(|v| !v.is_nan()),
            })
            .collect(),
        bounds: standardised
            .iter()
            .map(|z| match *z {
                Ok(z) => alpha * (scale * z).abs(),
                Err(beyond) if beyond.is_infinite() => 0.0,
                Err(_) => f64::NAN,
            })
            .collect(),
        intervals: PERCENTS
            .iter()
            .map(|&(_, percent)| {
                let (l, u) = binomial_rank_interval(count, percent / 100.0, CONFIDENCE);
                let at = |rank: usize, outward: f64| {
                    placement
                        .value_rank(rank, n, beyond as usize, percent)
                        .map_or(placement.beyond_value(percent), |k| {
                            read.order_statistic(k as u64, outward)
                        })
                };
                [l.map(|r| at(r, -1.0)), u.map(|r| at(r, 1.0))]
            })
            .collect(),
        histogram,
        flagged_counts,
        of_values,
    }
}

/// [`percentile_figures`] of an indicator: `events` ones among `n` values.
fn indicator_percentile_figures(events: u64, n: u64) -> PercentileFigures {
    let zeros = n - events;
    let value = |rank: usize| if (rank as u64) < zeros { 0.0 } else { 1.0 };
    PercentileFigures {
        values: PERCENTS
            .iter()
            .map(|p| binary_percentile(zeros, n, p.1))
            .collect(),
        bounds: vec![0.0; PERCENTS.len()],
        intervals: PERCENTS
            .iter()
            .map(|p| binomial_rank_interval(n as usize, p.1 / 100.0, CONFIDENCE))
            .map(|(l, u)| [l.map(value), u.map(value)])
            .collect(),
        histogram: Histogram {
            lower_edge: 0.0,
            bin_width: 0.5,
            counts: vec![zeros, events],
        },
        flagged_counts: None,
        of_values: None,
    }
}

/// The capability figures of one output from its statistics. `samples` is every sample
/// drawn, `out` those that do not conform, `hidden` those among them that the values do
/// not show (with the reason), which leaves the indices undefined.
fn capability_figures(
    limits: SpecLimits,
    m: &Moments,
    percentiles: &OrderedNumbers,
    samples: u64,
    out: u64,
    hidden: Option<String>,
) -> CapabilityFigures {
    let (ppm, lower, upper) = out_of_spec_interval(out, samples, CONFIDENCE).to_ppm();
    let mut report = CapabilityFigures {
        spec: SpecFigures {
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
    report.cp_ci95 = moment
        .cp
        .map(|cp| symmetric95(cp, cp * m.sd_standard_error() / m.sd()));
    report.cpk_ci95 = moment.cpk.map(|cpk| {
        let upper_side = cpk_on_upper_side(m.mean, limits);
        symmetric95(
            cpk,
            cpk_standard_error(cpk, upper_side, m.n, m.skewness(), m.excess_kurtosis()),
        )
    });
    report.cp_percentile = pct.cp;
    report.cpk_percentile = pct.cpk;
    let beyond = ["0.135", "50", "99.865"]
        .iter()
        .any(|key| percentiles.get(key).is_some_and(f64::is_infinite));
    if beyond {
        report.cp_percentile = None;
        report.cpk_percentile = None;
        report.capability_note = Some(
            "percentile-method indices not given: a percentile lies beyond the limits (flagged samples in its tail)".to_string(),
        );
    } else if report.cpk_percentile.is_none() {
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

/// An output's conforming values ready to be read at any rank, with the samples beyond
/// the limits as a conformity judgement places them ([`crate::stats::conformity`]):
/// sorted exact values, or the quantile sketch of a run beyond the exact-percentile limit
/// with its frame. The gate's bands and requirements and the allocation's percentile
/// targets read their percentiles and intervals here.
pub enum OrderStatistics {
    /// The conforming values, sorted by `f64::total_cmp`, and the samples beyond.
    Exact {
        /// The values.
        sorted: Vec<f64>,
        /// Samples beyond the limits.
        beyond: u64,
        /// Where they sit.
        placement: Placement,
    },
    /// The sketch of the standardised conforming values.
    Sketch {
        /// The sketch.
        sketch: QuantileSketch,
        /// Centre subtracted before insertion.
        center: f64,
        /// Scale divided out before insertion.
        scale: f64,
        /// Samples beyond the limits.
        beyond: u64,
        /// Where they sit.
        placement: Placement,
        /// Smallest value.
        min: f64,
        /// Largest value.
        max: f64,
    },
}

impl OrderStatistics {
    /// The order statistics of an output's conforming values (`kept`, within [`min`,
    /// `max`]) among `samples` samples, the others beyond the limits `limits`; `None` for
    /// an indicator or a dropped output, which keep none.
    pub fn new(
        kept: KeptValues,
        samples: u64,
        limits: Option<SpecLimits>,
        (min, max): (f64, f64),
    ) -> Option<OrderStatistics> {
        let beyond = samples.saturating_sub(kept.count());
        let placement = Placement::of(limits);
        match kept {
            KeptValues::Values(mut values) => {
                values.sort_unstable_by(f64::total_cmp);
                Some(OrderStatistics::Exact {
                    sorted: values,
                    beyond,
                    placement,
                })
            }
            KeptValues::Sketch {
                sketch,
                center,
                scale,
            } => Some(OrderStatistics::Sketch {
                sketch,
                center,
                scale,
                beyond,
                placement,
                min,
                max,
            }),
            KeptValues::Indicator | KeptValues::Dropped => None,
        }
    }

    /// The type-7 percentile at `percent` and its distribution-free interval [X_(l), X_(u)]
    /// at z, of normal-approximation ranks N·p ∓ z·√(N·p·(1 − p)) among all N samples
    /// (`value`, `low`, `high`); ±∞ where they read a sample beyond the limits; from a
    /// sketch, each end moved out by its error bound α·|x − centre|. NaN for no samples.
    pub fn percentile_with_interval(&self, percent: f64, z: f64) -> (f64, f64, f64) {
        match self {
            OrderStatistics::Exact {
                sorted,
                beyond,
                placement,
            } => percentile_of_sorted_with_interval(
                sorted,
                (*beyond as usize, *placement),
                percent,
                z,
            )
            .unwrap_or((f64::NAN, f64::NAN, f64::NAN)),
            OrderStatistics::Sketch {
                sketch,
                center,
                scale,
                beyond,
                placement,
                min,
                max,
            } => {
                let sketch = StandardisedSketch {
                    sketch,
                    center: *center,
                    scale: *scale,
                    min: *min,
                    max: *max,
                };
                let n = sketch.sketch.count() as usize;
                let count = n as u64 + beyond;
                if count == 0 {
                    return (f64::NAN, f64::NAN, f64::NAN);
                }
                let last = (count - 1) as f64;
                let at_rank = |rank: f64, outward: f64| {
                    placement
                        .value_rank(rank as usize, n, *beyond as usize, percent)
                        .map_or(placement.beyond_value(percent), |k| {
                            sketch.order_statistic(k as u64, outward)
                        })
                };
                let (nf, p) = (count as f64, (percent / 100.0).clamp(0.0, 1.0));
                let value = at_rank((p * last).floor(), 0.0);
                let reach = z * (nf * p * (1.0 - p)).sqrt();
                let low = at_rank((nf * p - reach).floor().clamp(0.0, last), -1.0);
                let high = at_rank((nf * p + reach).ceil().clamp(0.0, last), 1.0);
                (value, low.min(value), high.max(value))
            }
        }
    }
}

/// [`OrderStatistics::percentile_with_interval`] of sorted conforming values with `beyond`
/// samples beyond the limits where `placement` puts them; `None` when there are no
/// samples. With `beyond` 0, the type-7 percentile of `sorted` and
/// [`crate::stats::order_statistic_interval`]'s interval, bit for bit.
pub fn percentile_of_sorted_with_interval(
    sorted: &[f64],
    (beyond, placement): (usize, Placement),
    percent: f64,
    z: f64,
) -> Option<(f64, f64, f64)> {
    let n = sorted.len();
    let count = n + beyond;
    let at = |rank: usize| {
        placement
            .value_rank(rank, n, beyond, percent)
            .map_or(placement.beyond_value(percent), |k| sorted[k])
    };
    let (lower_rank, weight) = type7_position(count, percent)?;
    let upper = if lower_rank + 1 < count {
        at(lower_rank + 1)
    } else {
        at(lower_rank)
    };
    let value = interpolate_beyond(at(lower_rank), upper, weight);
    let last = count - 1;
    let (nf, p) = (count as f64, (percent / 100.0).clamp(0.0, 1.0));
    let centre = nf * p;
    let reach = z * (nf * p * (1.0 - p)).sqrt();
    let low = ((centre - reach).floor().max(0.0) as usize).min(last);
    let high = ((centre + reach).ceil() as usize).min(last);
    Some((value, at(low), at(high)))
}
