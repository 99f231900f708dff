//! The report of `rvtol allocate`: JSON (a stable contract, documented in README.md) and
//! a text table per source with the current and proposed tolerance, cost and share of
//! variance, then the target figure before, after and in the verification run.

use serde::Serialize;

use super::{Allocation, Evaluation, MARGIN_Z};
use rvtol_engine::format::{format_change, format_sig};

/// One source's row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SourceReport {
    /// Part or variable name.
    pub source: String,
    /// What the tolerance number means (e.g. "± band half-width", "3σ").
    pub tolerance: &'static str,
    /// Unit of the tolerance ("" for a factor on the standard deviations).
    pub unit: String,
    /// Tolerance in the scenario.
    pub current: f64,
    /// The optimum before rounding.
    pub optimum: f64,
    /// Proposed tolerance: the optimum rounded to three significant digits (down where
    /// the source matters), the value verified.
    pub proposed: f64,
    /// proposed / current.
    pub factor: f64,
    /// Bounds [min, max] from the scenario.
    pub bounds: [f64; 2],
    /// Cost model, in words.
    pub cost_model: String,
    /// Cost at the current tolerance (null outside a cost table's range).
    pub current_cost: Option<f64>,
    /// Cost at the proposed tolerance.
    pub proposed_cost: f64,
    /// Share of the output variance at the proposal (Euler allocation of the Monte Carlo
    /// variance; a_k²σ_k²/σ² for a linear stack).
    pub variance_share: f64,
}

/// A figure with its Monte Carlo uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigureReport {
    /// The target figure.
    pub value: f64,
    /// Its 95 % interval.
    pub ci: [f64; 2],
    /// Its standard error.
    pub standard_error: f64,
    /// Output mean.
    pub mean: f64,
    /// Output standard deviation.
    pub sd: f64,
    /// Seed of the run.
    pub seed: u64,
    /// Finite samples.
    pub n: u64,
    /// The output's distribution in outline (for a plot of before and after).
    pub quantiles: QuantileOutline,
}

/// Type-7 percentiles `value` at the levels `p` (%); a flagged sample beyond every limit
/// makes an end ±∞, written as null.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantileOutline {
    /// Levels, %.
    pub p: Vec<f64>,
    /// Percentiles of the output.
    pub value: Vec<f64>,
}

impl FigureReport {
    fn new(e: &Evaluation, seed: u64) -> FigureReport {
        FigureReport {
            value: e.figure,
            ci: [e.interval.0, e.interval.1],
            standard_error: e.standard_error,
            mean: e.mean,
            sd: e.sd,
            seed,
            n: e.n,
            quantiles: QuantileOutline {
                p: e.quantiles.iter().map(|q| q.0).collect(),
                value: e.quantiles.iter().map(|q| q.1).collect(),
            },
        }
    }
}

/// The common-scaling comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CommonScaleReport {
    /// One factor on every allocatable tolerance.
    pub factor: f64,
    /// Its total cost.
    pub cost: f64,
}

/// The JSON report of `rvtol allocate`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AllocationReport {
    /// Version of rvtol.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (data files written in), hex.
    pub scenario_sha256: String,
    /// The output's spec limits, when the scenario sets them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spec: Option<rvtol_engine::figures::SpecFigures>,
    /// The constrained output.
    pub output: String,
    /// Its unit.
    pub unit: String,
    /// The target, normalised (`p99.865 <= 1`).
    pub target: String,
    /// "met" (the independent run's figure and its whole 95 % interval satisfy the target),
    /// "not verified" (they do not: the figure misses, or its interval straddles it) or
    /// "infeasible" (no tolerances within the bounds meet it).
    pub status: &'static str,
    /// Samples of every evaluation.
    pub samples: u64,
    /// Seed of the optimisation (common random numbers).
    pub seed: u64,
    /// Seed of the verification run.
    pub verification_seed: u64,
    /// Standard errors kept between the optimised figure and the target.
    pub margin_standard_errors: f64,
    /// One row per allocatable source, scenario order.
    pub sources: Vec<SourceReport>,
    /// Total cost today (null when a source's current cost is undefined).
    pub current_cost: Option<f64>,
    /// Total cost of the proposal.
    pub proposed_cost: f64,
    /// Total cost of the optimum before rounding.
    pub optimum_cost: f64,
    /// Every tolerance scaled by one factor instead (null when none meets the target).
    pub common_scale: Option<CommonScaleReport>,
    /// The figure at today's tolerances (optimisation seed).
    pub current: FigureReport,
    /// The figure at the proposal (optimisation seed).
    pub proposed: FigureReport,
    /// The figure of the independent verification run at the proposal.
    pub verification: FigureReport,
    /// Sequential Lagrange iterations.
    pub iterations: usize,
    /// Evaluations of the target figure made (Monte Carlo runs, or importance-sampling
    /// estimates with `--rare`).
    pub evaluations: usize,
    /// The lever values of the answer (absent without levers).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub levers: Vec<LeverReport>,
    /// Every combination of lever values tried (absent without levers).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub lever_options: Vec<LeverOptionReport>,
    /// How importance sampling estimated the constraint (present with `--rare`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rare: Option<RareReport>,
}

/// How `allocate --rare` estimated its ppm constraint.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RareReport {
    /// The 95 % interval's half width, as a share of the estimate, each sample was built
    /// for.
    pub precision: f64,
    /// The points a sample could have.
    pub max_evaluations: u64,
    /// Samples built around the event's centres (the first at today's tolerances).
    pub stages: usize,
    /// Points of the last sample (every estimate of the last stage).
    pub points: u64,
    /// The tolerance factors, per source, whose centres the last sample was drawn around.
    pub centred_at: Vec<f64>,
    /// Model evaluations of the whole allocation (every lever combination's).
    pub model_evaluations: u64,
    /// The verification's estimator: `importance` (around the proposal's own centres,
    /// with the verification seed), or `subset` where importance sampling did not reach
    /// its precision within the budget or one point carried much of its estimate.
    pub verified_by: &'static str,
    /// The same as the text says it.
    #[serde(skip)]
    pub verified_by_phrase: &'static str,
}

/// A lever's value in the answer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeverReport {
    /// The lever's name.
    pub lever: String,
    /// The model parameter it sets.
    pub param: String,
    /// Its value.
    pub value: f64,
    /// Its cost (added to the tolerances' cost).
    pub cost: f64,
}

/// One combination of lever values and the allocation found for it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeverOptionReport {
    /// Each lever's value, in the order of `levers`.
    pub values: Vec<f64>,
    /// Cost of the lever values.
    pub lever_cost: f64,
    /// Cost of the tolerances proposed for them.
    pub tolerance_cost: f64,
    /// Their sum.
    pub total_cost: f64,
    /// `met`, `not verified` or `infeasible`.
    pub status: &'static str,
    /// The verification run's figure.
    pub verification: f64,
}

/// A target figure as text: a number, or why there is none. A percentile is ±∞ when it
/// reads samples that do not conform although their values do not show it (flagged,
/// excluded, not finite), which lie beyond the limits in its tail; a capability index has
/// no value when such samples exist.
fn figure_text(value: f64) -> String {
    if value.is_finite() {
        format_sig(value)
    } else if value.is_infinite() {
        "beyond the limits (non-conforming samples in the tail)".to_string()
    } else {
        "n/a (flagged or non-finite samples)".to_string()
    }
}

impl AllocationReport {
    /// Builds the report.
    pub fn new(a: &Allocation) -> AllocationReport {
        AllocationReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: a.scenario.clone(),
            scenario_sha256: a.scenario_sha256.clone(),
            spec: a.spec.map(|limits| rvtol_engine::figures::SpecFigures {
                lower: limits.lower,
                upper: limits.upper,
            }),
            output: a.output.clone(),
            unit: a.unit.clone(),
            target: a.target.expression(),
            status: a.status(),
            samples: a.rare.as_ref().map_or(a.settings.samples, |r| r.points),
            seed: a.settings.seed,
            verification_seed: a.settings.verification_seed,
            margin_standard_errors: MARGIN_Z,
            sources: a
                .sources
                .iter()
                .map(|s| SourceReport {
                    source: s.source.source.name.clone(),
                    tolerance: s.source.source.kind.meaning(),
                    unit: s.source.source.unit.clone(),
                    current: s.source.source.current,
                    optimum: s.optimum,
                    proposed: s.proposed,
                    factor: s.proposed / s.source.source.current,
                    bounds: [s.source.min, s.source.max],
                    cost_model: s.source.cost.describe(),
                    current_cost: s.current_cost,
                    proposed_cost: s.proposed_cost,
                    variance_share: s.variance_share,
                })
                .collect(),
            current_cost: a.current_cost,
            proposed_cost: a.proposed_cost,
            optimum_cost: a.optimum_cost,
            common_scale: a.common_scale.map(|c| CommonScaleReport {
                factor: c.factor,
                cost: c.cost,
            }),
            current: FigureReport::new(&a.current, a.settings.seed),
            proposed: FigureReport::new(&a.proposed, a.settings.seed),
            verification: FigureReport::new(&a.verification, a.settings.verification_seed),
            iterations: a.iterations,
            evaluations: a.evaluations,
            levers: a
                .levers
                .iter()
                .map(|l| LeverReport {
                    lever: l.name.clone(),
                    param: l.param.clone(),
                    value: l.value,
                    cost: l.cost,
                })
                .collect(),
            lever_options: a
                .lever_options
                .iter()
                .map(|o| LeverOptionReport {
                    values: o.values.clone(),
                    lever_cost: o.lever_cost,
                    tolerance_cost: o.tolerance_cost,
                    total_cost: o.lever_cost + o.tolerance_cost,
                    status: o.status,
                    verification: o.verification,
                })
                .collect(),
            rare: a.rare.as_ref().map(|r| RareReport {
                precision: r.options.precision,
                max_evaluations: r.options.max_evaluations,
                stages: r.stages,
                points: r.points,
                centred_at: r.centred_at.clone(),
                model_evaluations: r.model_evaluations,
                verified_by: r.verified_by.name(),
                verified_by_phrase: r.verified_by.phrase(),
            }),
        }
    }

    /// Pretty JSON with a final newline.
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("report serialises");
        text.push('\n');
        text
    }

    /// The human-readable table.
    pub fn to_text(&self) -> String {
        let mut out = String::new();
        let unit = |u: &str| {
            if u.is_empty() {
                "×sd".to_string()
            } else {
                u.to_string()
            }
        };
        let estimator = match &self.rare {
            Some(r) => format!(
                "importance sampling, {} points per estimate",
                rvtol_engine::format::group_thousands(r.points)
            ),
            None => format!(
                "{} samples per run",
                rvtol_engine::format::group_thousands(self.samples)
            ),
        };
        out.push_str(&format!(
            "rvtol {} | allocate {} | output {} | target {} | {estimator}, seed {}\n\n",
            self.rvtol_version, self.scenario, self.output, self.target, self.seed
        ));
        let header = [
            "source",
            "tolerance",
            "unit",
            "current",
            "proposed",
            "change",
            "bounds",
            "cost now",
            "cost new",
            "var share",
        ];
        let mut rows: Vec<[String; 10]> = vec![header.map(str::to_string)];
        for s in &self.sources {
            rows.push([
                s.source.clone(),
                s.tolerance.to_string(),
                unit(&s.unit),
                format_sig(s.current),
                format_sig(s.proposed),
                format_change(s.factor),
                format!("{} .. {}", format_sig(s.bounds[0]), format_sig(s.bounds[1])),
                s.current_cost.map_or("n/a".into(), format_sig),
                format_sig(s.proposed_cost),
                // + 0.0 turns a negative zero into "0.0".
                format!("{:.1} %", (s.variance_share * 1000.0).round() / 10.0 + 0.0),
            ]);
        }
        let widths: Vec<usize> = (0..10)
            .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
            .collect();
        for row in &rows {
            let mut line = String::new();
            for (c, cell) in row.iter().enumerate() {
                let pad = widths[c] - cell.chars().count();
                if c < 3 {
                    line.push_str(cell);
                    line.push_str(&" ".repeat(pad));
                } else {
                    line.push_str(&" ".repeat(pad));
                    line.push_str(cell);
                }
                line.push_str("  ");
            }
            out.push_str(line.trim_end());
            out.push('\n');
        }
        let rest: f64 = 1.0 - self.sources.iter().map(|s| s.variance_share).sum::<f64>();
        out.push_str(&format!(
            "rest of the variance (fixed sources, interactions, curvature): {:.1} %\n\n",
            rest * 100.0
        ));
        out.push_str(&format!(
            "total cost: {} today, {} proposed",
            self.current_cost.map_or("n/a".into(), format_sig),
            format_sig(self.proposed_cost)
        ));
        if let Some(now) = self.current_cost {
            out.push_str(&format!(" ({})", format_change(self.proposed_cost / now)));
        }
        out.push('\n');
        if !self.levers.is_empty() {
            let names: Vec<&str> = self.levers.iter().map(|l| l.lever.as_str()).collect();
            let lever_cost: f64 = self.levers.iter().map(|l| l.cost).sum();
            out.push_str(&format!(
                "levers: {} (cost {}); total with the tolerances {}\n",
                self.levers
                    .iter()
                    .map(|l| format!("{} = {}", l.lever, format_sig(l.value)))
                    .collect::<Vec<_>>()
                    .join(", "),
                format_sig(lever_cost),
                format_sig(lever_cost + self.proposed_cost)
            ));
            out.push_str(&format!(
                "  {:<24} {:>11} {:>15} {:>11}  {:<13} {}\n",
                names.join(", "),
                "lever cost",
                "tolerance cost",
                "total",
                "status",
                "verification"
            ));
            for option in &self.lever_options {
                let values: Vec<String> = option.values.iter().map(|v| format_sig(*v)).collect();
                out.push_str(&format!(
                    "  {:<24} {:>11} {:>15} {:>11}  {:<13} {}\n",
                    values.join(", "),
                    format_sig(option.lever_cost),
                    format_sig(option.tolerance_cost),
                    format_sig(option.total_cost),
                    option.status,
                    figure_text(option.verification)
                ));
            }
        }
        match &self.common_scale {
            // Both unrounded: the proposal's rounding (down where a source matters) can
            // cost a little more than either.
            Some(c) => out.push_str(&format!(
                "every tolerance × {} instead (within its bounds): cost {} unrounded, against the optimum's {} unrounded\n",
                format_sig(c.factor),
                format_sig(c.cost),
                format_sig(self.optimum_cost)
            )),
            None => out.push_str("no common factor on the tolerances meets the target\n"),
        }
        let figure = |label: &str, f: &FigureReport| {
            let interval = if f.value.is_finite() {
                format!(
                    " (95 % CI {} .. {})",
                    figure_text(f.ci[0]),
                    figure_text(f.ci[1])
                )
            } else {
                String::new()
            };
            format!(
                "{label:<26} {} = {}{interval}, mean {}, sd {}, seed {}\n",
                self.target.split_whitespace().next().unwrap_or(""),
                figure_text(f.value),
                format_sig(f.mean),
                format_sig(f.sd),
                f.seed
            )
        };
        out.push('\n');
        out.push_str(&figure(
            if self.levers.is_empty() {
                "today:"
            } else {
                "today, with the levers:"
            },
            &self.current,
        ));
        out.push_str(&figure("proposed (optimisation):", &self.proposed));
        out.push_str(&figure("proposed (verification):", &self.verification));
        out.push_str(&self.verdict());
        out
    }

    /// The closing paragraph: the status and what it rests on, or what to do.
    fn verdict(&self) -> String {
        let (runs, more) = match &self.rare {
            Some(r) => (
                format!(
                    "{} importance-sampling estimates on {} sample(s), verified by {}; {} model \
                     evaluations",
                    self.evaluations,
                    r.stages,
                    r.verified_by_phrase,
                    rvtol_engine::format::group_thousands(r.model_evaluations)
                ),
                "a smaller --precision (or, where the verification's estimate stopped at its \
                 budget, a larger --max-evaluations)",
            ),
            None => (
                format!("{} Monte Carlo runs", self.evaluations),
                "more --samples",
            ),
        };
        format!(
            "\n{}: {}\n",
            self.status,
            match self.status {
                "met" => format!(
                    "the independent run meets {} with its whole 95 % interval (optimised with a \
                     margin of {:.2} standard errors; {} iterations, {runs})",
                    self.target, self.margin_standard_errors, self.iterations
                ),
                "infeasible" => format!(
                    "no tolerances within the bounds meet {}; shown: every source at its lower \
                     bound. Widen the bounds or tighten sources outside the allocation section.",
                    self.target
                ),
                _ => format!(
                    "the independent run gives {} (95 % interval {} .. {}), which does not show {} \
                     with confidence; {}",
                    format_sig(self.verification.value),
                    format_sig(self.verification.ci[0]),
                    format_sig(self.verification.ci[1]),
                    self.target,
                    match self.rare.is_some() && self.proposed.ci[1] < self.verification.ci[0] {
                        true => "the optimisation's importance-sampling estimate lies below the \
                                 verification's interval: its sample misses part of the event, so \
                                 its tolerances are too loose. Allocate with Monte Carlo runs (no \
                                 --rare) or to a tighter target"
                            .to_string(),
                        false => format!("rerun with {more}"),
                    }
                ),
            }
        )
    }
}

impl Allocation {
    /// "met", "not verified" or "infeasible".
    pub fn status(&self) -> &'static str {
        if !self.feasible {
            "infeasible"
        } else if self.verified {
            "met"
        } else {
            "not verified"
        }
    }
}
