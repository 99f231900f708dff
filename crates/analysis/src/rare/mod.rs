//! Rare events: the probability of an output's event (above or below a threshold, or out
//! of spec with the conformity every figure uses) down to 1 ppm and below, with a stated
//! interval, at far fewer model evaluations than plain Monte Carlo.
//!
//! The event is searched and sampled in the standard normal space of the scenario
//! ([`limit`]): FORM finds its most probable point on each side ([`form`]); where FORM
//! does not converge (an output with kinks and flats) the side's centre is the mean of
//! the normal law conditioned on the event, from one subset-simulation run
//! ([`subset::conditional_mean`]); importance sampling around those centres estimates the
//! probability ([`importance`]), and subset simulation estimates it with no assumption
//! about where the event lies ([`subset`]).
//! Both intervals are 95 %; each method stops when its half width is at most the asked
//! share of its estimate, or at the evaluation budget (then it says the precision was not
//! reached). Every figure is the same for a seed at any thread count.
//!
//! The importance factors (the squared direction cosines of a side's centre, α² = (uᵢ/|u|)²,
//! summed over the dimensions that move one error source; at FORM's design point α is
//! the limit state's normal) say which sources drive the event: each source's share of
//! the squared distance from the nominal point to the event.

pub mod form;
pub mod importance;
pub mod limit;
pub mod report;
pub mod subset;

use rvtol_engine::scenario::{Scenario, ScenarioError};

pub use limit::Event;

/// z₀.₉₇₅ of the standard normal law.
pub const Z_95: f64 = 1.959_963_984_540_054;

/// Which estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Importance sampling around FORM's design points.
    Importance,
    /// Subset simulation.
    Subset,
}

impl Method {
    /// The name reports and options use.
    pub fn name(self) -> &'static str {
        match self {
            Method::Importance => "importance",
            Method::Subset => "subset",
        }
    }

    /// The estimator as a sentence names it.
    pub fn phrase(self) -> &'static str {
        match self {
            Method::Importance => "importance sampling",
            Method::Subset => "subset simulation",
        }
    }
}

/// When an estimator stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// The 95 % interval's half width, as a share of the estimate, to stop at.
    pub precision: f64,
    /// Model evaluations an estimator may make.
    pub max_evaluations: u64,
}

/// What a rare-event analysis is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct RareSettings {
    /// Seed of every draw.
    pub seed: u64,
    /// The output (index among the scenario's outputs).
    pub output: usize,
    /// Its event.
    pub event: Event,
    /// The estimators, in order.
    pub methods: Vec<Method>,
    /// Their stopping rule.
    pub budget: Budget,
    /// Points per level of subset simulation.
    pub level_samples: usize,
    /// The share of evaluations the output may be non-finite in (`--max-non-finite`).
    pub max_non_finite: f64,
}

/// One estimator's figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The probability.
    pub probability: f64,
    /// Its 95 % interval.
    pub interval: [f64; 2],
    /// Model evaluations made.
    pub evaluations: u64,
    /// Whether the interval reached the asked precision.
    pub reached: bool,
    /// Points in the event (importance sampling).
    pub events: u64,
    /// Independent runs (subset simulation).
    pub runs: u64,
    /// The tail on the way to the event (subset simulation): per intermediate level, its
    /// score threshold and the probability of scoring above it, means over the runs.
    pub tail: Vec<(f64, f64)>,
    /// What the reader should know about this figure.
    pub warning: Option<String>,
}

/// One estimator's outcome: its figure, or why it gives none.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodResult {
    /// The estimator.
    pub method: Method,
    /// Its figure, or why there is none.
    pub estimate: Result<Estimate, String>,
}

/// How a side's centre was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Found {
    /// FORM's design point.
    Form,
    /// The mean of the law conditioned on the event.
    ConditionalMean,
}

impl Found {
    /// The name reports use.
    pub fn name(self) -> &'static str {
        match self {
            Found::Form => "FORM",
            Found::ConditionalMean => "conditional mean",
        }
    }

    /// What the centre is, as the text report says it.
    pub fn phrase(self) -> &'static str {
        match self {
            Found::Form => "the design point",
            Found::ConditionalMean => "the conditional mean",
        }
    }
}

/// One side of the event, searched.
#[derive(Debug, Clone, PartialEq)]
pub struct Side {
    /// The side's event (a threshold; out of spec has a side per limit).
    pub event: Event,
    /// FORM's design point, or why there is none.
    pub design: Result<form::DesignPoint, String>,
    /// The centre importance sampling uses, how it was found; or why there is none.
    pub centre: Result<(Vec<f64>, Found), String>,
    /// The sources' importance factors at the centre, largest first (none without one).
    pub importance: Vec<Importance>,
    /// Model evaluations of the search (FORM and, where it ran, the conditional mean's).
    pub evaluations: u64,
    /// Of them, those whose value is not finite.
    pub non_finite: u64,
    /// The input row at the centre.
    pub row: Vec<f64>,
}

/// The source groups' importance factors at one side's design point.
#[derive(Debug, Clone, PartialEq)]
pub struct Importance {
    /// The source (names joined by `+` where one normal dimension moves several).
    pub source: String,
    /// Σα² of its dimensions.
    pub factor: f64,
}

/// The analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct Rare {
    /// Dimensions of the normal space.
    pub dims: usize,
    /// Each side of the event, searched (when importance sampling is asked).
    pub sides: Vec<Side>,
    /// Per asked method.
    pub results: Vec<MethodResult>,
}

/// The rare-event analysis of `settings` on `scenario` (uses the current rayon pool;
/// `progress` is told the model evaluations as they are done).
pub fn rare(
    scenario: &Scenario,
    settings: &RareSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Rare, ScenarioError> {
    let mut limit = limit::LimitState::new(scenario, settings.output, settings.event, progress)?;
    let dims = limit.dims();
    let sides: Vec<Side> = match settings.methods.contains(&Method::Importance) {
        true => search_sides(scenario, settings, progress)?,
        false => Vec::new(),
    };
    let mut results: Vec<MethodResult> = (settings.methods.iter())
        .map(|&method| MethodResult {
            method,
            estimate: match method {
                Method::Importance => importance_estimate(&mut limit, &sides, settings),
                Method::Subset => subset::estimate(
                    &mut limit,
                    settings.level_samples,
                    settings.seed,
                    &settings.budget,
                ),
            },
        })
        .collect();
    flag_disagreement(&mut results);
    check_non_finite(scenario, settings, &limit, &sides)?;
    Ok(Rare {
        dims,
        sides,
        results,
    })
}

/// An error when the output was not finite in more evaluations than `--max-non-finite`
/// allows (they were read as the event).
fn check_non_finite(
    scenario: &Scenario,
    settings: &RareSettings,
    limit: &limit::LimitState,
    sides: &[Side],
) -> Result<(), ScenarioError> {
    let evaluations = limit.evaluations + sides.iter().map(|s| s.evaluations).sum::<u64>();
    let non_finite = limit.non_finite + sides.iter().map(|s| s.non_finite).sum::<u64>();
    if non_finite as f64 <= settings.max_non_finite * evaluations as f64 {
        return Ok(());
    }
    Err(ScenarioError::new(
        scenario.model_of_output(settings.output),
        format!(
            "{} is not finite in {non_finite} of the {evaluations} evaluations of the rare-event search (more than the {} % allowed, --max-non-finite): the model cannot evaluate part of the tail",
            scenario.outputs[settings.output].name,
            rvtol_deviation::Shown(100.0 * settings.max_non_finite)
        ),
    ))
}

/// Warns on the importance sampling's figure when its interval and subset simulation's
/// do not overlap: the centres may miss part of the event, and subset simulation, which
/// assumes nothing about where the event lies, is the one to trust.
fn flag_disagreement(results: &mut [MethodResult]) {
    let interval = |m: Method, results: &[MethodResult]| {
        (results.iter())
            .find(|r| r.method == m)
            .and_then(|r| r.estimate.as_ref().ok().map(|e| e.interval))
    };
    let (Some(a), Some(b)) = (
        interval(Method::Importance, results),
        interval(Method::Subset, results),
    ) else {
        return;
    };
    if a[1] < b[0] || b[1] < a[0] {
        let importance = (results.iter_mut())
            .find(|r| r.method == Method::Importance)
            .and_then(|r| r.estimate.as_mut().ok())
            .expect("found above");
        let note = "its interval and subset simulation's do not overlap: the centres may miss part of the event; subset simulation assumes nothing about where the event lies".to_string();
        importance.warning = Some(match importance.warning.take() {
            Some(before) => format!("{before}; {note}"),
            None => note,
        });
    }
}

/// Each side of the event searched for its centre (FORM's design point, else the
/// conditional mean): one per threshold, one per spec limit out of spec.
pub fn search_sides(
    scenario: &Scenario,
    settings: &RareSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Side>, ScenarioError> {
    (side_events(scenario, settings).into_iter())
        .map(|event| search(scenario, settings, event, progress))
        .collect()
}

/// One side searched: FORM, and the conditional mean where FORM does not converge.
fn search(
    scenario: &Scenario,
    settings: &RareSettings,
    event: Event,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Side, ScenarioError> {
    let mut side = limit::LimitState::new(scenario, settings.output, event, progress)?;
    let design = form::design_point(&mut side);
    let centre = match &design {
        Ok(d) if d.converged => Ok((d.u.clone(), Found::Form)),
        Err(why) if why.contains("not rare") => Err(why.clone()),
        _ => subset::conditional_mean(&mut side, settings.level_samples, settings.seed)
            .map(|u| (u, Found::ConditionalMean)),
    };
    let row = centre
        .as_ref()
        .map_or_else(|_| Vec::new(), |(u, _)| side.row(u));
    let importance = centre
        .as_ref()
        .map_or_else(|_| Vec::new(), |(u, _)| importance_factors(scenario, u));
    Ok(Side {
        event,
        design,
        centre,
        importance,
        evaluations: side.evaluations,
        non_finite: side.non_finite,
        row,
    })
}

/// The one-sided events FORM searches: the threshold's, or one per spec limit.
fn side_events(scenario: &Scenario, settings: &RareSettings) -> Vec<Event> {
    match settings.event {
        Event::OutOfSpec => {
            let limits = scenario.outputs[settings.output].spec;
            let (lower, upper) = limits.map_or((None, None), |l| (l.lower, l.upper));
            (upper.map(Event::Above).into_iter())
                .chain(lower.map(Event::Below))
                .collect()
        }
        threshold => vec![threshold],
    }
}

/// Importance sampling around the sides' centres; refused when a side has none.
fn importance_estimate(
    limit: &mut limit::LimitState,
    sides: &[Side],
    settings: &RareSettings,
) -> Result<Estimate, String> {
    let mut centres = Vec::new();
    for side in sides {
        match &side.centre {
            Ok((u, _)) => centres.push(u.clone()),
            Err(why) => {
                return Err(format!(
                    "no centre to sample around on {}: {why}; subset simulation does not need one",
                    event_text(side.event)
                ))
            }
        }
    }
    if centres.is_empty() {
        return Err("the event has no side to search".to_string());
    }
    let mut estimate = importance::estimate(limit, &centres, settings.seed, &settings.budget);
    let form_evaluations: u64 = sides.iter().map(|s| s.evaluations).sum();
    estimate.evaluations += form_evaluations;
    Ok(estimate)
}

/// Σα² per source of the scenario, α = u/|u| the direction of a side's centre (a
/// dimension that moves several sources' columns counts for their names joined by `+`),
/// largest first.
fn importance_factors(scenario: &Scenario, u: &[f64]) -> Vec<Importance> {
    let norm = u.iter().map(|x| x * x).sum::<f64>().sqrt();
    let alpha: Vec<f64> = u
        .iter()
        .map(|x| if norm > 0.0 { x / norm } else { 0.0 })
        .collect();
    let moved = scenario.input_space.quasi_dimension_columns();
    let mut factors: Vec<Importance> = Vec::new();
    for (columns, a) in moved.iter().zip(&alpha) {
        let names: Vec<&str> = (scenario.sources.iter())
            .filter(|s| s.columns.iter().any(|c| columns.contains(c)))
            .map(|s| s.name.as_str())
            .collect();
        let source = names.join("+");
        match factors.iter_mut().find(|f| f.source == source) {
            Some(f) => f.factor += a * a,
            None => factors.push(Importance {
                source,
                factor: a * a,
            }),
        }
    }
    factors.sort_by(|a, b| b.factor.total_cmp(&a.factor));
    factors
}

/// The output's value at a score of `event`: the threshold plus (above) or less (below)
/// the score; out of spec, the same on the side of a one-sided spec; `None` for a
/// two-sided spec, whose score is the distance beyond the nearer limit.
pub fn value_at_score(event: Event, scenario: &Scenario, output: usize, score: f64) -> Option<f64> {
    match event {
        Event::Above(t) => Some(t + score),
        Event::Below(t) => Some(t - score),
        Event::OutOfSpec => match scenario.outputs[output].spec.map(|l| (l.lower, l.upper)) {
            Some((None, Some(u))) => Some(u + score),
            Some((Some(l), None)) => Some(l - score),
            _ => None,
        },
    }
}

/// An event as reports write it.
pub fn event_text(event: Event) -> String {
    match event {
        Event::Above(t) => format!("above {}", rvtol_engine::format::format_sig(t)),
        Event::Below(t) => format!("below {}", rvtol_engine::format::format_sig(t)),
        Event::OutOfSpec => "out of spec".to_string(),
    }
}
