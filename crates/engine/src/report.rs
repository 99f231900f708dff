//! Reports of a run and of a nominal evaluation: the JSON documents (a stable contract for
//! users' scripts) and the readable text tables. They render the figures
//! [`crate::figures`] computes; the engine renders, the CLI writes.
//!
//! JSON of `run`: `rvtol_version`, `scenario`, `seed`, `samples`, `chunk_size`,
//! `percentile_method`, `constraint` (when a part has the 001 Eq. 11 constraint),
//! `inputs` (per random column `source`, `column`, `unit`, `distribution`, `parameters`,
//! `mean`, `sd`, `tolerance`, `correlated_with`, `constrained`) and `outputs`, an array with per output `name`, `unit`, `kind`, `n`, `non_finite`, `mean`,
//! `sd`, `skewness`, `excess_kurtosis`, `min`, `max`, `percentiles` (keyed by the percent
//! as a string), `histogram`; indicator outputs add `events`, `fraction`, `fraction_ci95`;
//! outputs with spec limits add `spec`, `cp` (null when one-sided) with `cp_ci95`, `cpk`
//! with `cpk_ci95`, `cp_percentile`, `cpk_percentile`, `ppm_out`, `ppm_out_ci95`. No timing
//! and no thread count: the document is byte-identical for the same seed and samples.

use serde::Serialize;

use crate::chunk::CHUNK_SIZE;
use crate::figures::{output_figures, OrderedNumbers, OutputFigures};
use crate::format::{format_figure, format_ppm, format_sig, group_thousands};
use crate::run::{PercentileMethod, RunResult};
use crate::scenario::Scenario;
use crate::stats::Histogram;
use rvtol_deviation::Shown;
use rvtol_models::ConditionEffect;

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

/// What `interval_method` says.
const REPLICATE_INTERVAL_METHOD: &str = "figure of all rows +- t(0.975, R-1)*s/sqrt(R), s the standard deviation of the figure over the R independent replicates";

/// One random input (a column of the input space) as the scenario states it: the record
/// of what the run drew.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputReport {
    /// Its error source (the part or variable).
    pub source: String,
    /// The column (`variable` or `part.component`).
    pub column: String,
    /// Its unit, when known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// The law's name (`normal`, `tolerance band`, `uniform`, ...).
    pub distribution: &'static str,
    /// Its parameters as stated.
    pub parameters: OrderedNumbers,
    /// The law's mean.
    pub mean: f64,
    /// The law's standard deviation.
    pub sd: f64,
    /// Tolerance limits [lower, upper]: the stated limits, or mean ± 3 sd of a normal, or
    /// the 99.865 % point of a magnitude (what `rvtol stack` reads).
    pub tolerance: [f64; 2],
    /// The columns the scenario correlates with it (of their values or normal scores).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub correlated_with: Vec<String>,
    /// Whether the 001 Eq. 11 constraint restricts it (its law is then the stated one
    /// conditioned on the constraint).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub constrained: bool,
}

/// The random inputs of a scenario, source by source ([`InputReport`]); columns that do not
/// vary are left out.
pub fn input_reports(scenario: &Scenario) -> Vec<InputReport> {
    let space = &scenario.input_space;
    let constrained: Vec<usize> = (space.inequalities().iter())
        .flat_map(|inequality| inequality.columns)
        .collect();
    let mut inputs = Vec::new();
    for source in &scenario.sources {
        for &column in source.columns.iter().filter(|&&c| space.is_random(c)) {
            let info = &scenario.columns[column];
            let law = &info.law;
            inputs.push(InputReport {
                source: source.name.clone(),
                column: info.name.clone(),
                unit: info.unit.clone(),
                distribution: law.name,
                parameters: OrderedNumbers(
                    (law.parameters.iter())
                        .map(|&(key, value)| (key.to_string(), value))
                        .collect(),
                ),
                mean: law.mean,
                sd: law.sd,
                tolerance: info.tolerance,
                correlated_with: (0..scenario.columns.len())
                    .filter(|&other| space.dependent(column, other))
                    .map(|other| scenario.columns[other].name.clone())
                    .collect(),
                constrained: constrained.contains(&column),
            });
        }
    }
    inputs
}

/// The report of `rvtol run`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (data files written in), hex.
    pub scenario_sha256: String,
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
    /// The random inputs as the scenario states them ([`InputReport`]).
    pub inputs: Vec<InputReport>,
    /// One entry per output.
    pub outputs: Vec<OutputFigures>,
}

impl RunReport {
    /// The report of a finished run: its figures ([`output_figures`]) with the run's
    /// settings.
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
        let outputs = output_figures(scenario, &mut result);
        RunReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            scenario_sha256: scenario.digest.clone(),
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
            inputs: input_reports(scenario),
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
        self.header_lines(&mut lines);
        lines.push(String::new());
        let name_width = name_column_width(self.outputs.iter().map(|o| o.name.as_str()));
        self.table_lines(&mut lines, name_width);
        self.interval_lines(&mut lines, name_width);
        self.capability_lines(&mut lines);
        self.accounting_lines(&mut lines);
        self.histogram_lines(&mut lines);
        let mut text = lines.join("\n");
        text.push('\n');
        text
    }

    /// The first lines: the run, its sampling and its constraint.
    fn header_lines(&self, lines: &mut Vec<String>) {
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
    }

    /// The table of every output's mean, sd, percentiles and range.
    fn table_lines(&self, lines: &mut Vec<String>, name_width: usize) {
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
                format_figure(o.percentiles.get("0.135").unwrap_or(f64::NAN)),
                format_figure(o.percentiles.get("50").unwrap_or(f64::NAN)),
                format_figure(o.percentiles.get("99.865").unwrap_or(f64::NAN)),
                format_sig(o.min),
                format_sig(o.max),
            ));
        }
    }

    /// The intervals of the continuous outputs' figures: a replicated run's from its
    /// replicates, else the percentiles' distribution-free ones.
    fn interval_lines(&self, lines: &mut Vec<String>, name_width: usize) {
        let continuous: Vec<&OutputFigures> = self
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
                let percentile_pair = |key: &str| {
                    if o.percentiles.get(key).is_some_and(f64::is_infinite) {
                        "beyond".to_string()
                    } else {
                        pair(r.percentiles.get(key).unwrap_or([None, None]))
                    }
                };
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
                    percentile_pair("50"),
                    percentile_pair("99.865"),
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
            for o in continuous {
                // An end that reads a sample beyond the limits is "beyond"; an open one
                // reaches past the sample's extreme.
                let end = |x: Option<f64>, open: &str| x.map_or(open.to_string(), format_figure);
                let interval = |key: &str| {
                    if o.percentiles.get(key).is_some_and(f64::is_infinite) {
                        return "beyond".to_string();
                    }
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
    }

    /// The capability of every output with spec limits.
    fn capability_lines(&self, lines: &mut Vec<String>) {
        let with_spec: Vec<&OutputFigures> = self
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
    }

    /// The samples lost (not finite) and those an indicator excluded or flagged.
    fn accounting_lines(&self, lines: &mut Vec<String>) {
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
            if let Some(values) = &o.value_percentiles {
                let at = |key: &str| format_sig(values.get(key).unwrap_or(f64::NAN));
                lines.push(format!(
                    "{}: its percentiles place the samples that do not conform although their values do not show it (flagged, excluded, not finite) beyond the spec limits (\"beyond\" where a percentile reaches them); of the values alone, flagged ones included: P0.135 {}, P50 {}, P99.865 {}",
                    o.name,
                    at("0.135"),
                    at("50"),
                    at("99.865"),
                ));
            }
        }
    }

    /// A text histogram per continuous output.
    fn histogram_lines(&self, lines: &mut Vec<String>) {
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
    }
}

/// The report of `rvtol nominal`: every output at the mean of every deviation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NominalReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (data files written in), hex.
    pub scenario_sha256: String,
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
    /// The indicator that flags the nominal sample non-conforming (an over-preloaded
    /// design's lost motion: a value, but an assembly out of spec), when one does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flagged_by: Option<String>,
}

impl NominalReport {
    /// Builds the report from the nominal values ([`crate::run::nominal`]).
    pub fn new(scenario: &Scenario, values: &[Option<f64>]) -> NominalReport {
        NominalReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            scenario_sha256: scenario.digest.clone(),
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
                    flagged_by: match o.condition {
                        Some((k, ConditionEffect::NonConforming))
                            if values[k].is_some_and(|v| v != 0.0) =>
                        {
                            Some(scenario.outputs[k].name.clone())
                        }
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
            let flag = match &o.flagged_by {
                Some(indicator) => format!("  flagged by {indicator}: does not conform"),
                None => String::new(),
            };
            text.push_str(&format!(
                "{:<width$}  {:>12}  {}{flag}\n",
                o.name, value, o.unit
            ));
        }
        text
    }
}

/// Width of a table's name column: the longest name, at least 6.
fn name_column_width<'a>(names: impl Iterator<Item = &'a str>) -> usize {
    names.map(str::len).max().unwrap_or(0).max(6)
}
