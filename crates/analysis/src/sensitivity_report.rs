//! The report of `rvtol sensitivity`: JSON (`rvtol_version`, `scenario`, `seed`,
//! `base_samples`, `evaluations`, `bootstrap` and `bootstrap_unit` (Monte Carlo) or
//! `sampling` (a replicated design), `confidence`, `method`, and `outputs`, each
//! with `name`, `unit`, `kind` (`value`; `out_of_spec` for an output's conformity
//! indicator, `indicator` for an indicator output, both 0/1 with their `share` of rows at
//! 1), `variance`, `non_finite_rows` and `indices`: per input group `input`,
//! `first_order`, `first_order_ci`, `total`, `total_ci`, sorted by decreasing total index)
//! and a readable ranking table per output.

use serde::Serialize;

use crate::sensitivity::{Analysed, IntervalMethod, OutputSensitivity, SensitivitySettings};
use rvtol_engine::format::{format_sig, group_thousands};
use rvtol_engine::report::SamplingReport;
use rvtol_engine::scenario::Scenario;

/// The estimators, in words.
const ESTIMATORS: &str = "Sobol' indices of independent input groups: first order by Saltelli et al. (2010), total by Jansen (1999), each averaged over the A_B and B_A designs";

/// The intervals of a replicated design, in words.
const REPLICATE_INTERVAL_METHOD: &str = "index of all N rows +- t(0.975, R-1)*s/sqrt(R), s the standard deviation of the index over the R independent replicates";

/// A share as a percentage with five significant digits (`2.1530 %`).
fn percent(share: f64) -> String {
    format!("{} %", format_sig(100.0 * share))
}

/// Most rows of the linearised screening that completes a sensitivity report.
pub const SCREENING_ROWS: u64 = 65_536;

/// One input group's indices.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IndexReport {
    /// Input group (part, variable, or correlated sources joined with `+`).
    pub input: String,
    /// First-order Sobol' index.
    pub first_order: f64,
    /// Its interval (bootstrap, or from the replicates).
    pub first_order_ci: [f64; 2],
    /// Total Sobol' index.
    pub total: f64,
    /// Its interval (bootstrap, or from the replicates).
    pub total_ci: [f64; 2],
}

/// One source's Shapley effect.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShapleyReport {
    /// The source (part or variable).
    pub input: String,
    /// Its share of the output variance.
    pub effect: f64,
    /// 95 % interval.
    pub ci: [f64; 2],
}

/// One source's screening figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScreeningSourceReport {
    /// The source.
    pub input: String,
    /// Share of the linearised variance, in percent.
    pub contribution_percent: f64,
    /// Sum of its squared standardized regression coefficients.
    pub src_squared: f64,
    /// Derivatives at the nominal point, keyed by column.
    pub derivatives_at_nominal: rvtol_engine::figures::OrderedNumbers,
}

/// Screening figures of one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScreeningReport {
    /// gᵀΣg at the nominal point.
    pub linearised_variance: f64,
    /// R² of the linear regression on the random columns.
    pub r_squared: f64,
    /// Per source, by decreasing |contribution|.
    pub sources: Vec<ScreeningSourceReport>,
}

/// One output's ranking.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputSensitivityReport {
    /// Output name (an output's conformity indicator: its name and ` out of spec`).
    pub name: String,
    /// Unit.
    pub unit: String,
    /// `value`, `out_of_spec` or `indicator` ([`crate::sensitivity::Analysed::kind`]).
    pub kind: &'static str,
    /// For a 0/1 quantity, the share of the 2N rows of A and B at 1 (out of spec, or
    /// flagged); its variance is share·(1 − share)·2N/(2N − 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub share: Option<f64>,
    /// Output variance.
    pub variance: f64,
    /// Rows left out for non-finite values.
    pub non_finite_rows: u64,
    /// Indices, most important first (none when the output does not vary).
    pub indices: Vec<IndexReport>,
    /// Why there are no indices, when there are none: an output that does not vary has no
    /// variance to apportion.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Screening: contribution %, SRC² and derivatives at the nominal point, per source.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub screening: Option<ScreeningReport>,
    /// Shapley effects per source, most important first, when computed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shapley: Option<Vec<ShapleyReport>>,
}

/// The report of a sensitivity analysis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensitivityReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (data files written in), hex.
    pub scenario_sha256: String,
    /// Seed.
    pub seed: u64,
    /// Base samples N.
    pub base_samples: u64,
    /// Model evaluations, N·(2G + 2).
    pub evaluations: u64,
    /// Bootstrap resamples (Monte Carlo only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bootstrap: Option<usize>,
    /// Confidence of the intervals.
    pub confidence: f64,
    /// Estimators and intervals, in words.
    pub method: String,
    /// How a Monte Carlo analysis' intervals were resampled: `rows`, or `blocks` of
    /// `bootstrap_block_rows` consecutive rows (bounded memory beyond the row-bootstrap
    /// limit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bootstrap_unit: Option<&'static str>,
    /// Rows per resampled block, for `blocks`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bootstrap_block_rows: Option<u64>,
    /// How a Latin hypercube or RQMC design drew A and B and gives the intervals (absent
    /// for Monte Carlo).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampling: Option<SamplingReport>,
    /// One entry per continuous output.
    pub outputs: Vec<OutputSensitivityReport>,
}

impl SensitivityReport {
    /// Builds the report.
    pub fn new(
        scenario: &Scenario,
        settings: SensitivitySettings,
        outputs: Vec<OutputSensitivity>,
    ) -> Self {
        let groups = outputs.first().map_or(0, |o| o.indices.len()) as u64;
        let (bootstrap_unit, bootstrap_block_rows) = match settings.interval_method(scenario) {
            IntervalMethod::Rows => (Some("rows"), None),
            IntervalMethod::Blocks { rows } => (Some("blocks"), Some(rows)),
            IntervalMethod::Replicates => (None, None),
        };
        let sampling = settings.sampling;
        let replicated = sampling.is_replicated();
        SensitivityReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            scenario_sha256: scenario.digest.clone(),
            seed: settings.seed,
            base_samples: settings.base_samples,
            evaluations: settings.base_samples * (2 * groups + 2),
            bootstrap: (!replicated).then_some(settings.bootstrap),
            confidence: settings.confidence,
            method: if replicated {
                format!("{ESTIMATORS}; A and B the two halves of each point of {} replicates of a {}; intervals from the replicates", sampling.replicates, match sampling.method {
                    rvtol_deviation::SamplingMethod::Rqmc => "scrambled Sobol' design",
                    _ => "Latin hypercube",
                })
            } else {
                format!("{ESTIMATORS}; percentile bootstrap intervals over the base samples")
            },
            bootstrap_unit,
            bootstrap_block_rows,
            sampling: replicated.then(|| SamplingReport {
                method: sampling.method.name(),
                replicates: sampling.replicates,
                points_per_replicate: sampling.replicate_points(settings.base_samples),
                interval_method: REPLICATE_INTERVAL_METHOD,
            }),
            outputs: outputs
                .into_iter()
                .map(|o| OutputSensitivityReport {
                    name: o.name,
                    unit: o.unit,
                    kind: o.quantity.kind(),
                    share: (!matches!(o.quantity, Analysed::Value(_))).then_some(o.mean),
                    variance: o.variance,
                    non_finite_rows: o.non_finite_rows,
                    note: (o.variance.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater))
                        .then(|| match o.quantity {
                            Analysed::Value(_) => "the output does not vary: no variance to apportion",
                            Analysed::OutOfSpec(_) if o.mean == 0.0 => "no row of A and B is out of spec: nothing to rank (more base samples reach a smaller share)",
                            Analysed::OutOfSpec(_) => "every row of A and B is out of spec: nothing to rank",
                            Analysed::Indicator(_) => "the indicator takes one value in every row of A and B: nothing to rank",
                        }.to_string()),
                    indices: o
                        .indices
                        .into_iter()
                        .filter(|_| o.variance > 0.0)
                        .map(|g| IndexReport {
                            input: g.group,
                            first_order: g.first_order.value,
                            first_order_ci: g.first_order.interval,
                            total: g.total.value,
                            total_ci: g.total.interval,
                        })
                        .collect(),
                    screening: None,
                    shapley: None,
                })
                .collect(),
        }
    }

    /// The whole report of `rvtol sensitivity` from the Sobol' indices and, when asked,
    /// the Shapley effects: the linearised screening (at most 65,536 rows, seeded with the
    /// analysis' seed) is computed here. The command line, its merge of shards and the
    /// Python package all build their report with this, so they agree bit for bit.
    pub fn complete(
        scenario: &Scenario,
        settings: SensitivitySettings,
        outputs: Vec<OutputSensitivity>,
        shapley: Option<Vec<(String, Vec<crate::shapley::ShapleyEffect>)>>,
    ) -> Result<SensitivityReport, rvtol_engine::ScenarioError> {
        let screening = crate::screening::screening(
            scenario,
            &crate::shapley::players(scenario),
            settings.base_samples.min(SCREENING_ROWS),
            settings.seed,
        )?;
        let report = SensitivityReport::new(scenario, settings, outputs).with_screening(screening);
        Ok(match shapley {
            Some(effects) => report.with_shapley(effects),
            None => report,
        })
    }

    /// Adds the screening figures.
    pub fn with_screening(mut self, screening: Vec<crate::screening::OutputScreening>) -> Self {
        for output_screening in screening {
            let mut sources: Vec<ScreeningSourceReport> = output_screening
                .sources
                .into_iter()
                .map(|s| ScreeningSourceReport {
                    input: s.input,
                    contribution_percent: 100.0 * s.contribution,
                    src_squared: s.src_squared,
                    derivatives_at_nominal: rvtol_engine::figures::OrderedNumbers(s.derivatives),
                })
                .collect();
            sources.sort_by(|a, b| {
                b.contribution_percent
                    .abs()
                    .total_cmp(&a.contribution_percent.abs())
            });
            if let Some(output) = self
                .outputs
                .iter_mut()
                .find(|o| o.name == output_screening.name)
            {
                output.screening = Some(ScreeningReport {
                    linearised_variance: output_screening.linearised_variance,
                    r_squared: output_screening.r_squared,
                    sources,
                });
            }
        }
        self
    }

    /// Adds Shapley effects (`(output name, effects)` as from
    /// [`crate::shapley::shapley_effects`]).
    pub fn with_shapley(
        mut self,
        effects: Vec<(String, Vec<crate::shapley::ShapleyEffect>)>,
    ) -> Self {
        for (name, mut list) in effects {
            list.sort_by(|a, b| b.effect.total_cmp(&a.effect));
            if let Some(output) = self.outputs.iter_mut().find(|o| o.name == name) {
                output.shapley = Some(
                    list.into_iter()
                        .map(|e| ShapleyReport {
                            input: e.input,
                            effect: e.effect,
                            ci: e.interval,
                        })
                        .collect(),
                );
            }
        }
        self
    }

    /// The JSON document.
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("report serialises");
        text.push('\n');
        text
    }

    /// One ranking table per output.
    pub fn to_text(&self) -> String {
        let intervals = match (&self.sampling, self.bootstrap) {
            (Some(sampling), _) => format!(
                "sampling {}: {} replicates of {} points, intervals from their spread (Student t, {} degrees of freedom)",
                sampling.method,
                sampling.replicates,
                group_thousands(sampling.points_per_replicate),
                sampling.replicates - 1
            ),
            (None, bootstrap) => format!(
                "{} bootstrap resamples{}",
                bootstrap.unwrap_or(0),
                match self.bootstrap_block_rows {
                    Some(rows) => format!(" of blocks of {rows} rows"),
                    None => String::new(),
                }
            ),
        };
        let mut lines = vec![format!(
            "rvtol {} | scenario {} | sensitivity: {} base samples ({} model evaluations) | seed {} | {intervals}, {:.0} % intervals",
            self.rvtol_version,
            self.scenario,
            group_thousands(self.base_samples),
            group_thousands(self.evaluations),
            self.seed,
            100.0 * self.confidence
        )];
        let interval = |ci: [f64; 2]| format!("[{}, {}]", format_sig(ci[0]), format_sig(ci[1]));
        for output in &self.outputs {
            lines.push(String::new());
            let squared_unit = if output.unit == "1" {
                String::new()
            } else {
                format!(" {}²", output.unit)
            };
            lines.push(match output.share {
                Some(share) => format!(
                    "{}: {}{} of the rows of A and B, variance {}",
                    output.name,
                    if output.kind == "indicator" {
                        "set in "
                    } else {
                        ""
                    },
                    percent(share),
                    format_sig(output.variance),
                ),
                None => format!(
                    "{} ({}), variance {}{squared_unit}",
                    output.name,
                    output.unit,
                    format_sig(output.variance),
                ),
            });
            if let Some(note) = &output.note {
                lines.push(format!("  {note}"));
                continue;
            }
            let width = output
                .indices
                .iter()
                .map(|i| i.input.len())
                .max()
                .unwrap_or(5)
                .max(5);
            // Columns as wide as their widest entry, so that every row lines up.
            let cells: Vec<[String; 4]> = output
                .indices
                .iter()
                .map(|index| {
                    [
                        format_sig(index.first_order),
                        interval(index.first_order_ci),
                        format_sig(index.total),
                        interval(index.total_ci),
                    ]
                })
                .collect();
            let column = |k: usize, heading: &str| {
                cells
                    .iter()
                    .map(|c| c[k].chars().count())
                    .chain([heading.len()])
                    .max()
                    .unwrap_or(0)
            };
            let (w0, w1, w2) = (
                column(0, "first"),
                column(1, "interval"),
                column(2, "total"),
            );
            let row = |input: &str, c: [&str; 4]| {
                format!(
                    "  {input:<width$}  {:>w0$} {:<w1$}  {:>w2$} {}",
                    c[0], c[1], c[2], c[3]
                )
            };
            lines.push(row("input", ["first", "interval", "total", "interval"]));
            for (index, c) in output.indices.iter().zip(&cells) {
                lines.push(row(&index.input, [&c[0], &c[1], &c[2], &c[3]]));
            }
            if let Some(screening) = &output.screening {
                lines.push(format!(
                    "  screening (linearised variance {}, regression R² {:.4}):",
                    format_sig(screening.linearised_variance),
                    screening.r_squared
                ));
                lines.push(format!(
                    "  {:<width$}  {:>13} {:>9}",
                    "input", "contribution", "SRC²"
                ));
                for source in &screening.sources {
                    lines.push(format!(
                        "  {:<width$}  {:>12}% {:>9}",
                        source.input,
                        format!("{:.2}", source.contribution_percent),
                        format_sig(source.src_squared)
                    ));
                }
            }
            if let Some(shapley) = &output.shapley {
                lines.push(format!(
                    "  {:<width$}  {:>9} {}",
                    "input", "Shapley", "interval"
                ));
                for effect in shapley {
                    lines.push(format!(
                        "  {:<width$}  {:>9} {}",
                        effect.input,
                        format_sig(effect.effect),
                        interval(effect.ci)
                    ));
                }
            }
            if output.non_finite_rows > 0 {
                lines.push(format!(
                    "  warning: {} rows with non-finite values were left out",
                    output.non_finite_rows
                ));
            }
        }
        let mut text = lines.join("\n");
        text.push('\n');
        text
    }
}
