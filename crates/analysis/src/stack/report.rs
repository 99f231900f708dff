//! The report of `rvtol stack`: JSON (`rvtol_version`, `scenario`, `seed`, `method`,
//! `corners`, `all_corners`, `evaluations`, `linearity_rows`, `poor_linearity_below`,
//! `monte_carlo_samples`, and `outputs`, each with `name`, `unit`, `nominal`,
//! `worst_case` (`low` and `high`: `value`, `flagged`, `inside`, `inputs`), `arithmetic`,
//! `rss`, `r_squared`, `note`, `spec`, `monte_carlo` (`mean`, `p0_135`, `p99_865`,
//! `ppm_out`) and `contributors` (`source`, `column`, `unit`, `lower`, `upper`,
//! `sensitivity`, `worst_case_percent`, `rss_percent`, `swing`, by decreasing RSS share,
//! then swing)) and the
//! same as readable tables.

use serde::Serialize;

use super::{OutputStack, Stack, StackSettings, LINEARITY_ROWS, POOR_LINEARITY};
use rvtol_engine::figures::{output_figures, OrderedNumbers, OutputFigures, SpecFigures};
use rvtol_engine::format::{
    format_figure, format_ppm, format_rounded, format_sig, format_tolerance, group_thousands,
};
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_engine::RunSettings;

/// The methods, in words.
const METHOD: &str = "tolerance box: each input between its tolerance limits (stated limits; a normal's mean +- 3 sd; 0 to the 99.865 % point of a magnitude), cut by the parts' Eq. 11 constraints; nominal at the box centre; sensitivities by central differences there; arithmetic = sum |g|T; RSS = sqrt(sum g T rho g T), each tolerance read as +-3 sd; worst case of the model over every corner (at most 4,096) or the gradient's corners, then a coordinate search over the corners and inner levels of the leading 24 inputs; R2 of the linearisation over rows of the scenario's law";

/// One end of the worst case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EndReport {
    /// The output's value.
    pub value: f64,
    /// Whether the output's indicator flags the assembly there (non-conforming whatever
    /// the value).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub flagged: bool,
    /// Whether the search found it inside the box rather than at a corner.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub inside: bool,
    /// The random inputs there, keyed by column.
    pub inputs: OrderedNumbers,
}

/// The worst case of one output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorstCaseReport {
    /// The lowest value found (null when no point tried had a value).
    pub low: Option<EndReport>,
    /// The highest value found.
    pub high: Option<EndReport>,
    /// How: `every corner` (exact for an output monotone in each input) or `gradient
    /// corners`, each followed by the coordinate search.
    pub search: &'static str,
}

/// One random column's part.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContributorReport {
    /// Its source (part or variable).
    pub source: String,
    /// The column.
    pub column: String,
    /// Its unit, when known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// Lower tolerance limit.
    pub lower: f64,
    /// Upper tolerance limit.
    pub upper: f64,
    /// ∂output/∂input at the box centre.
    pub sensitivity: f64,
    /// Share of the arithmetic stack, percent.
    pub worst_case_percent: f64,
    /// Share of the RSS variance, percent.
    pub rss_percent: f64,
    /// The output's largest change with this input alone at a limit of its tolerance.
    pub swing: f64,
}

/// The Monte Carlo run's figures beside the stack.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonteCarloReport {
    /// Mean.
    pub mean: f64,
    /// P0.135 as a conformity judgement reads it (null: beyond the limits).
    pub p0_135: Option<f64>,
    /// P99.865 (null: beyond the limits).
    pub p99_865: Option<f64>,
    /// Out of spec per million, when the output has limits.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ppm_out: Option<f64>,
}

/// One output's stack.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutputStackReport {
    /// Output name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Value at the box centre.
    pub nominal: f64,
    /// Whether the output's indicator flags the centre.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub nominal_flagged: bool,
    /// The model's worst case over the box.
    pub worst_case: WorstCaseReport,
    /// Nominal ∓ Σ|g|·T.
    pub arithmetic: [f64; 2],
    /// Nominal ∓ RSS.
    pub rss: [f64; 2],
    /// R² of the linearisation (null when the rows' values do not vary).
    pub r_squared: Option<f64>,
    /// What to read with care.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The output's spec limits, when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spec: Option<SpecFigures>,
    /// The Monte Carlo run's figures, when run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<MonteCarloReport>,
    /// Per random input, by decreasing |RSS share|.
    pub contributors: Vec<ContributorReport>,
}

/// The report of a stack analysis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StackReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (data files written in), hex.
    pub scenario_sha256: String,
    /// Seed of the linearity rows.
    pub seed: u64,
    /// The methods, in words.
    pub method: &'static str,
    /// Corners of the tolerance box.
    pub corners: f64,
    /// Whether every corner was evaluated.
    pub all_corners: bool,
    /// Model evaluations of the stack (the Monte Carlo run's apart).
    pub evaluations: u64,
    /// Rows of the linearity check.
    pub linearity_rows: usize,
    /// R² below which the linear figures are flagged.
    pub poor_linearity_below: f64,
    /// Samples of the Monte Carlo run beside, when run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monte_carlo_samples: Option<u64>,
    /// Per output.
    pub outputs: Vec<OutputStackReport>,
}

/// The stack of `settings.outputs` and, with `run_settings`, the Monte Carlo run beside it
/// (`progress` gets the run's samples as its chunks finish): the report of `rvtol stack`
/// (uses the current rayon pool).
pub fn stack_report(
    scenario: &Scenario,
    settings: &StackSettings,
    run_settings: Option<RunSettings>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<StackReport, ScenarioError> {
    let stack = super::stack(scenario, settings)?;
    let figures = match run_settings {
        Some(run) => {
            let mut result = rvtol_engine::run(scenario, run, progress)?;
            rvtol_engine::run::check_non_finite(scenario, &result, settings.max_non_finite)?;
            Some((output_figures(scenario, &mut result), run.samples))
        }
        None => None,
    };
    let beside = figures.as_ref().map(|(f, n)| (f.as_slice(), *n));
    Ok(StackReport::new(scenario, settings, &stack, beside))
}

impl StackReport {
    /// The report of `stack`, with the Monte Carlo run's figures (and its samples) when
    /// given.
    pub fn new(
        scenario: &Scenario,
        settings: &StackSettings,
        stack: &Stack,
        monte_carlo: Option<(&[OutputFigures], u64)>,
    ) -> StackReport {
        let outputs = (stack.outputs.iter())
            .map(|output| {
                let figures = monte_carlo.map(|(figures, _)| &figures[output.output]);
                output_report(scenario, stack.all_corners, output, figures)
            })
            .collect();
        StackReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            scenario_sha256: scenario.digest.clone(),
            seed: settings.seed,
            method: METHOD,
            corners: stack.corners,
            all_corners: stack.all_corners,
            evaluations: stack.evaluations,
            linearity_rows: LINEARITY_ROWS,
            poor_linearity_below: POOR_LINEARITY,
            monte_carlo_samples: monte_carlo.map(|(_, samples)| samples),
            outputs,
        }
    }

    /// The JSON text (pretty, newline-terminated).
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("a stack report serialises");
        text.push('\n');
        text
    }
}

fn output_report(
    scenario: &Scenario,
    all_corners: bool,
    output: &OutputStack,
    figures: Option<&OutputFigures>,
) -> OutputStackReport {
    let info = &scenario.outputs[output.output];
    let y0 = output.nominal;
    let end = |e: &super::Extreme| EndReport {
        value: e.value,
        flagged: e.flagged,
        inside: e.inside,
        inputs: OrderedNumbers(
            (output.contributors.iter())
                .map(|c| (scenario.columns[c.column].name.clone(), e.row[c.column]))
                .collect(),
        ),
    };
    let [low, high] = &output.worst_case;
    let mut contributors: Vec<ContributorReport> = (output.contributors.iter())
        .map(|c| contributor_report(scenario, c))
        .collect();
    contributors.sort_by(|a, b| {
        (b.rss_percent.abs().total_cmp(&a.rss_percent.abs())).then(b.swing.total_cmp(&a.swing))
    });
    OutputStackReport {
        name: info.name.clone(),
        unit: info.unit.clone(),
        nominal: y0,
        nominal_flagged: output.nominal_flagged,
        worst_case: WorstCaseReport {
            low: low.as_ref().map(end),
            high: high.as_ref().map(end),
            search: if all_corners {
                "every corner"
            } else {
                "gradient corners"
            },
        },
        arithmetic: [y0 - output.arithmetic, y0 + output.arithmetic],
        rss: [y0 - output.rss, y0 + output.rss],
        r_squared: output.r_squared,
        note: note(output),
        spec: info.spec.map(|s| SpecFigures {
            lower: s.lower,
            upper: s.upper,
        }),
        monte_carlo: figures.map(monte_carlo_report),
        contributors,
    }
}

fn contributor_report(scenario: &Scenario, c: &super::Contributor) -> ContributorReport {
    let column = &scenario.columns[c.column];
    let source = (scenario.sources.iter())
        .find(|s| s.columns.contains(&c.column))
        .map_or_else(|| column.name.clone(), |s| s.name.clone());
    ContributorReport {
        source,
        column: column.name.clone(),
        unit: column.unit.clone(),
        lower: column.tolerance[0],
        upper: column.tolerance[1],
        sensitivity: c.sensitivity,
        worst_case_percent: 100.0 * c.worst_case_share,
        rss_percent: 100.0 * c.rss_share,
        swing: c.swing,
    }
}

fn monte_carlo_report(figures: &OutputFigures) -> MonteCarloReport {
    let finite = |x: Option<f64>| x.filter(|v| v.is_finite());
    MonteCarloReport {
        mean: figures.mean,
        p0_135: finite(figures.percentiles.get("0.135")),
        p99_865: finite(figures.percentiles.get("99.865")),
        ppm_out: figures.capability.as_ref().map(|c| c.ppm_out),
    }
}

/// What to read with care: a poor linearisation, a flagged centre or end, an extreme
/// inside the box.
fn note(output: &OutputStack) -> Option<String> {
    let mut notes = Vec::new();
    match output.r_squared {
        Some(r2) if r2 < POOR_LINEARITY => notes.push(format!(
            "the linearisation explains R² = {} of the output's variation (below {POOR_LINEARITY}): the arithmetic and RSS figures and the shares do not describe this output; read the worst case and the Monte Carlo figures",
            format_sig(r2)
        )),
        None => notes.push("the output does not vary over the scenario's law: no R²".into()),
        _ => {}
    }
    if output.nominal_flagged {
        notes.push("the centre of the box is flagged (non-conforming whatever its value)".into());
    }
    let flagged = output
        .worst_case
        .each_ref()
        .map(|e| e.as_ref().is_some_and(|e| e.flagged));
    let ends = match flagged {
        [true, true] => Some("both ends of the worst case are"),
        [true, false] => Some("the lowest end of the worst case is"),
        [false, true] => Some("the highest end of the worst case is"),
        [false, false] => None,
    };
    if let Some(ends) = ends {
        notes.push(format!(
            "{ends} flagged (an assembly that does not conform whatever its value)"
        ));
    }
    if output.worst_case.iter().flatten().any(|e| e.inside) {
        notes.push("an extreme lies inside the box, not at a corner: the output is not monotone in every input there".into());
    }
    (!notes.is_empty()).then(|| notes.join("; "))
}

impl StackReport {
    /// The readable tables.
    pub fn to_text(&self) -> String {
        let mut lines = vec![format!(
            "rvtol {} | scenario {} | stack: {} corners ({}), {} model evaluations, {} rows of the scenario's law for R² (seed {}){}",
            self.rvtol_version,
            self.scenario,
            match self.corners < 1e15 {
                true => group_thousands(self.corners as u64),
                false => format!("{:.3e}", self.corners),
            },
            if self.all_corners { "every one evaluated" } else { "the gradient's evaluated, then searched" },
            group_thousands(self.evaluations),
            group_thousands(self.linearity_rows as u64),
            self.seed,
            match self.monte_carlo_samples {
                Some(n) => format!(" | Monte Carlo: {} samples", group_thousands(n)),
                None => String::new(),
            }
        )];
        for output in &self.outputs {
            lines.push(String::new());
            lines.extend(output_text(output));
        }
        let mut text = lines.join("\n");
        text.push('\n');
        text
    }
}

fn output_text(output: &OutputStackReport) -> Vec<String> {
    let mut lines = vec![format!("{} ({})", output.name, output.unit)];
    let value = |e: &Option<EndReport>| match e {
        Some(e) => format!(
            "{}{}",
            format_sig(e.value),
            if e.flagged { " (flagged)" } else { "" }
        ),
        None => "-".into(),
    };
    let mut figures: Vec<[String; 3]> = vec![
        [
            "nominal (box centre)".into(),
            format_sig(output.nominal),
            if output.nominal_flagged {
                "(flagged)"
            } else {
                ""
            }
            .into(),
        ],
        [
            format!("worst case ({})", output.worst_case.search),
            value(&output.worst_case.low),
            value(&output.worst_case.high),
        ],
        pair("arithmetic (linear)", output.arithmetic),
        pair("RSS (linear, T = 3 sd)", output.rss),
    ];
    if let Some(mc) = &output.monte_carlo {
        let ends = |x: Option<f64>, beyond: f64| format_figure(x.unwrap_or(beyond));
        figures.push([
            "Monte Carlo P0.135, P99.865".into(),
            ends(mc.p0_135, f64::NEG_INFINITY),
            ends(mc.p99_865, f64::INFINITY),
        ]);
    }
    if let Some(spec) = &output.spec {
        let limit = |x: Option<f64>| x.map_or("-".into(), format_sig);
        figures.push(["spec limits".into(), limit(spec.lower), limit(spec.upper)]);
    }
    lines.extend(table(
        &[["".into(), "low".into(), "high".into()]],
        &figures,
        &[false, true, true],
    ));
    let mut summary = match output.r_squared {
        Some(r2) => format!("  linearisation R² {}", format_sig(r2)),
        None => "  linearisation R² -".into(),
    };
    if let Some(ppm) = output.monte_carlo.as_ref().and_then(|mc| mc.ppm_out) {
        summary.push_str(&format!(
            " | Monte Carlo out of spec {} ppm",
            format_ppm(ppm)
        ));
    }
    lines.push(summary);
    if let Some(note) = &output.note {
        lines.push(format!("  note: {note}"));
    }
    lines.extend(contributor_table(&output.contributors));
    lines
}

fn pair(label: &str, [low, high]: [f64; 2]) -> [String; 3] {
    [label.into(), format_sig(low), format_sig(high)]
}

/// Most contributor rows the text shows (all are in the JSON).
const SHOWN_CONTRIBUTORS: usize = 15;

fn contributor_table(contributors: &[ContributorReport]) -> Vec<String> {
    let rows: Vec<[String; 6]> = (contributors.iter().take(SHOWN_CONTRIBUTORS))
        .map(|c| {
            [
                c.column.clone(),
                format_tolerance(c.lower, c.upper),
                format_rounded(c.sensitivity),
                format!("{:.2}", c.worst_case_percent),
                format!("{:.2}", c.rss_percent),
                format_rounded(c.swing),
            ]
        })
        .collect();
    let heading = [
        "contributor".into(),
        "tolerance".into(),
        "sensitivity".into(),
        "arith. %".into(),
        "RSS %".into(),
        "swing".into(),
    ];
    let mut lines = vec![String::new()];
    lines.extend(table(
        &[heading],
        &rows,
        &[false, false, true, true, true, true],
    ));
    if contributors.len() > SHOWN_CONTRIBUTORS {
        lines.push(format!(
            "  … {} more (every one in --json)",
            contributors.len() - SHOWN_CONTRIBUTORS
        ));
    }
    lines
}

/// Rows as aligned text, each column as wide as its widest cell, indented by two.
fn table<const N: usize>(
    headings: &[[String; N]],
    rows: &[[String; N]],
    right: &[bool; N],
) -> Vec<String> {
    let all: Vec<&[String; N]> = headings.iter().chain(rows).collect();
    let widths: [usize; N] =
        std::array::from_fn(|k| all.iter().map(|r| r[k].chars().count()).max().unwrap_or(0));
    all.iter()
        .map(|r| {
            let cells: Vec<String> = (0..N)
                .map(|k| match right[k] {
                    true => format!("{:>w$}", r[k], w = widths[k]),
                    false => format!("{:<w$}", r[k], w = widths[k]),
                })
                .collect();
            format!("  {}", cells.join("  ")).trim_end().to_string()
        })
        .collect()
}
