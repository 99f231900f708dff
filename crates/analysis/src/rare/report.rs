//! The report of `rvtol rare`: JSON (`rvtol_version`, `scenario`, `scenario_sha256`,
//! `seed`, `output`, `unit`, `event`, `dims`, `precision`, `max_evaluations`,
//! `level_samples`, `sides` (per side of the event: FORM's `beta`, `probability` Φ(−β),
//! `converged`, `iterations`, `stopped`; the importance sampling's `centre` (`FORM` or
//! `conditional mean`), `centre_distance`, `no_centre`, `evaluations`, `importance` per
//! source, `centre_inputs` per random input) and `estimates` per method (`method`, then `probability`, `ppm`,
//! `interval`, `relative_half_width`, `evaluations`, `reached`, `events`, `runs`,
//! `plain_monte_carlo`: the evaluations plain Monte Carlo needs for the same relative
//! half width, `warning`, `tail` (subset simulation's levels as [value, probability]);
//! or `refused` with why)) and the same as readable text.

use serde::Serialize;

use super::{event_text, value_at_score, Estimate, Method, Rare, RareSettings, Side, Z_95};
use rvtol_engine::figures::OrderedNumbers;
use rvtol_engine::format::{format_ppm, format_sig, group_thousands, text_table};
use rvtol_engine::scenario::{Scenario, ScenarioError};

/// One side of the event, searched.
#[derive(Debug, Clone, Serialize)]
pub struct SideReport {
    /// The side's event.
    pub event: String,
    /// FORM's β = |u*|, when it converged.
    pub beta: Option<f64>,
    /// FORM's Φ(−β), when it converged.
    pub probability: Option<f64>,
    /// Whether FORM converged.
    pub converged: bool,
    /// FORM's iterations.
    pub iterations: usize,
    /// Why FORM stopped short or found no point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// How the importance sampling's centre was found (`FORM`, `conditional mean`), or
    /// null when there is none.
    pub centre: Option<&'static str>,
    /// The same as the text says it.
    #[serde(skip)]
    pub centre_phrase: Option<&'static str>,
    /// The centre's distance from the nominal point in the normal space.
    pub centre_distance: Option<f64>,
    /// Why there is no centre.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_centre: Option<String>,
    /// Model evaluations of the search.
    pub evaluations: u64,
    /// The sources' importance factors at the centre, largest first.
    pub importance: OrderedNumbers,
    /// The random inputs at the centre.
    pub centre_inputs: OrderedNumbers,
}

/// One estimator's figure.
#[derive(Debug, Clone, Serialize)]
pub struct EstimateReport {
    /// `importance` or `subset`.
    pub method: &'static str,
    /// The probability.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub probability: Option<f64>,
    /// The same in ppm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ppm: Option<f64>,
    /// Its 95 % interval (none from a single subset-simulation run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interval: Option<[f64; 2]>,
    /// The interval's half width over the estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_half_width: Option<f64>,
    /// Model evaluations (FORM's included for importance sampling).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub evaluations: Option<u64>,
    /// Whether the asked precision was reached.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reached: Option<bool>,
    /// Event points (importance sampling).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub events: Option<u64>,
    /// Independent runs (subset simulation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs: Option<u64>,
    /// Evaluations plain Monte Carlo needs for the same relative half width:
    /// z²·(1 − p)/(h²·p).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plain_monte_carlo: Option<f64>,
    /// What the reader should know.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// Why the method gives no figure.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
    /// Subset simulation's levels on the way: per level the output's value and the
    /// probability of passing it (means over the runs; the tail's quantiles at 10⁻¹,
    /// 10⁻², …).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tail: Vec<[f64; 2]>,
}

/// The report.
#[derive(Debug, Clone, Serialize)]
pub struct RareReport {
    /// rvtol's version.
    pub rvtol_version: &'static str,
    /// The scenario's name.
    pub scenario: String,
    /// Its text's digest.
    pub scenario_sha256: String,
    /// The seed.
    pub seed: u64,
    /// The output.
    pub output: String,
    /// Its unit.
    pub unit: String,
    /// The event.
    pub event: String,
    /// Dimensions of the normal space.
    pub dims: usize,
    /// The asked relative half width.
    pub precision: f64,
    /// The evaluation budget per method.
    pub max_evaluations: u64,
    /// Points per level of subset simulation.
    pub level_samples: usize,
    /// Per side of the event, its search.
    pub sides: Vec<SideReport>,
    /// Per method.
    pub estimates: Vec<EstimateReport>,
    /// Whether the event lies below its values (a `below` threshold, a lower spec limit),
    /// so that the tail's levels read downwards.
    #[serde(skip)]
    pub downwards: bool,
}

/// The analysis and its report (uses the current rayon pool; `progress` is told the
/// model evaluations as they are done).
pub fn rare_report(
    scenario: &Scenario,
    settings: &RareSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<RareReport, ScenarioError> {
    let rare = super::rare(scenario, settings, progress)?;
    Ok(RareReport::new(scenario, settings, &rare))
}

impl RareReport {
    /// The report of `rare`.
    pub fn new(scenario: &Scenario, settings: &RareSettings, rare: &Rare) -> RareReport {
        let info = &scenario.outputs[settings.output];
        let sides = (rare.sides.iter())
            .map(|side| side_report(scenario, side))
            .collect();
        RareReport {
            rvtol_version: env!("CARGO_PKG_VERSION"),
            scenario: scenario.name.clone(),
            scenario_sha256: scenario.digest.clone(),
            seed: settings.seed,
            output: info.name.clone(),
            unit: info.unit.clone(),
            event: event_text(settings.event),
            dims: rare.dims,
            precision: settings.budget.precision,
            max_evaluations: settings.budget.max_evaluations,
            level_samples: settings.level_samples,
            sides,
            downwards: value_at_score(settings.event, scenario, settings.output, 1.0)
                .zip(value_at_score(
                    settings.event,
                    scenario,
                    settings.output,
                    0.0,
                ))
                .is_some_and(|(one, zero)| one < zero),
            estimates: (rare.results.iter())
                .map(|r| {
                    let mut report = estimate_report(r.method, &r.estimate);
                    if let Ok(e) = &r.estimate {
                        report.tail = (e.tail.iter())
                            .filter_map(|&(b, p)| {
                                value_at_score(settings.event, scenario, settings.output, b)
                                    .map(|v| [v, p])
                            })
                            .collect();
                    }
                    report
                })
                .collect(),
        }
    }

    /// The JSON text (pretty, newline-terminated).
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("a rare-event report serialises");
        text.push('\n');
        text
    }

    /// The readable report.
    pub fn to_text(&self) -> String {
        let mut text = format!(
            "rare event: {} {} ({}), scenario {}, seed {}, {} normal dimensions\n",
            self.output, self.event, self.unit, self.scenario, self.seed, self.dims
        );
        for side in &self.sides {
            text.push('\n');
            text.push_str(&side_text(side));
        }
        text.push('\n');
        let rows: Vec<Vec<String>> = self.estimates.iter().map(estimate_row).collect();
        text.push_str(&text_table(
            &[
                "method",
                "ppm",
                "95 % interval (ppm)",
                "±",
                "evaluations",
                "plain Monte Carlo",
            ],
            &rows,
        ));
        for e in &self.estimates {
            if let Some(why) = &e.refused {
                text.push_str(&format!("{}: no figure: {why}\n", e.method));
            }
            if let Some(warning) = &e.warning {
                text.push_str(&format!("{}: {warning}\n", e.method));
            }
            if !e.tail.is_empty() {
                let rows: Vec<Vec<String>> = (e.tail.iter())
                    .map(|[v, p]| vec![format!("  {}", format_sig(*v)), format_sig(*p)])
                    .collect();
                text.push_str(&format!(
                    "\n{}'s levels, the tail on the way (means over its runs):\n",
                    e.method
                ));
                let side = if self.downwards { "  below" } else { "  above" };
                text.push_str(&text_table(&[side, "probability"], &rows));
            }
            if e.reached == Some(false) {
                text.push_str(&format!(
                    "{}: the budget ran out before ±{} % (--max-evaluations)\n",
                    e.method,
                    format_sig(100.0 * self.precision)
                ));
            }
        }
        text
    }
}

fn side_report(scenario: &Scenario, side: &Side) -> SideReport {
    let space = &scenario.input_space;
    let design = side.design.as_ref().ok().filter(|d| d.converged);
    let centre = side.centre.as_ref().ok();
    SideReport {
        event: event_text(side.event),
        beta: design.map(|d| d.beta),
        probability: design.map(|d| normal_upper_tail(d.beta)),
        converged: design.is_some(),
        iterations: side.design.as_ref().map_or(0, |d| d.iterations),
        stopped: match &side.design {
            Ok(d) => d.stopped.clone(),
            Err(why) => Some(why.clone()),
        },
        centre: centre.map(|(_, by)| by.name()),
        centre_phrase: centre.map(|(_, by)| by.phrase()),
        centre_distance: centre.map(|(u, _)| u.iter().map(|x| x * x).sum::<f64>().sqrt()),
        no_centre: side.centre.as_ref().err().cloned(),
        evaluations: side.evaluations,
        importance: OrderedNumbers(
            (side.importance.iter())
                .map(|f| (f.source.clone(), f.factor))
                .collect(),
        ),
        centre_inputs: OrderedNumbers(
            (0..space.n_columns())
                .filter(|&c| space.is_random(c) && !side.row.is_empty())
                .map(|c| (scenario.columns[c].name.clone(), side.row[c]))
                .collect(),
        ),
    }
}

fn estimate_report(method: Method, estimate: &Result<Estimate, String>) -> EstimateReport {
    let mut report = EstimateReport {
        method: method.name(),
        probability: None,
        ppm: None,
        interval: None,
        relative_half_width: None,
        evaluations: None,
        reached: None,
        events: None,
        runs: None,
        plain_monte_carlo: None,
        warning: None,
        refused: None,
        tail: Vec::new(),
    };
    match estimate {
        Ok(e) => {
            let p = e.probability;
            let h = 0.5 * (e.interval[1] - e.interval[0]) / p;
            report.probability = Some(p);
            report.ppm = Some(1e6 * p);
            // One subset run has no interval (its half width is ∞): none is written.
            report.interval = e
                .interval
                .iter()
                .all(|x| x.is_finite())
                .then_some(e.interval);
            report.relative_half_width = (h.is_finite()).then_some(h);
            report.evaluations = Some(e.evaluations);
            report.reached = Some(e.reached);
            report.events = (method == Method::Importance).then_some(e.events);
            report.runs = (method == Method::Subset).then_some(e.runs);
            report.plain_monte_carlo = (p > 0.0 && h.is_finite() && h > 0.0)
                .then(|| Z_95 * Z_95 * (1.0 - p) / (h * h * p));
            report.warning = e.warning.clone();
        }
        Err(why) => report.refused = Some(why.clone()),
    }
    report
}

fn side_text(side: &SideReport) -> String {
    let mut text = match (side.beta, side.probability) {
        (Some(beta), Some(p)) => format!(
            "{}: FORM β = {}, Φ(−β) = {} ppm ({} iterations)",
            side.event,
            format_sig(beta),
            format_ppm(1e6 * p),
            side.iterations,
        ),
        _ => format!(
            "{}: FORM did not converge ({})",
            side.event,
            side.stopped.as_deref().unwrap_or("no design point")
        ),
    };
    match (side.centre_phrase, side.centre_distance) {
        (Some(phrase), Some(distance)) => text.push_str(&format!(
            "; centre: {phrase}, {} sd from the nominal point; {} evaluations\n",
            format_sig(distance),
            group_thousands(side.evaluations)
        )),
        _ => text.push_str(&format!(
            "; no centre: {}\n",
            side.no_centre.as_deref().unwrap_or("")
        )),
    }
    let rows: Vec<Vec<String>> = (side.importance.0.iter())
        .filter(|(_, f)| *f >= 0.005)
        .map(|(s, f)| vec![format!("  {s}"), format!("{} %", format_sig(100.0 * f))])
        .collect();
    if !rows.is_empty() {
        text.push_str(&text_table(&["  source", "importance (α²)"], &rows));
    }
    text
}

fn estimate_row(e: &EstimateReport) -> Vec<String> {
    let dash = || "-".to_string();
    vec![
        e.method.to_string(),
        e.ppm.map_or_else(dash, format_ppm),
        e.interval.map_or_else(dash, |[a, b]| {
            format!("[{}, {}]", format_ppm(1e6 * a), format_ppm(1e6 * b))
        }),
        e.relative_half_width
            .map_or_else(dash, |h| format!("{} %", format_sig(100.0 * h))),
        e.evaluations.map_or_else(dash, group_thousands),
        e.plain_monte_carlo.map_or_else(dash, |n| match n < 1e15 {
            true => group_thousands(n.round() as u64),
            false => format_sig(n),
        }),
    ]
}

/// Q(x) = 1 − Φ(x).
fn normal_upper_tail(x: f64) -> f64 {
    0.5 * statrs::function::erf::erfc(x / std::f64::consts::SQRT_2)
}
