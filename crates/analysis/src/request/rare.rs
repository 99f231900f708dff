//! A rare-event analysis as a caller asks for it (`rvtol rare`): the output by name (the
//! scenario's only continuous output when none is named), its event (a threshold above or
//! below, else its spec limits), the estimators, the precision to stop at, the budget of
//! model evaluations and the points per level of subset simulation.

use rvtol_engine::Scenario;

use super::stack::continuous_outputs;
use super::{Caller, Refusal};
use crate::rare::{Budget, Event, Method, RareSettings};

/// The default relative half width of the 95 % interval: ±10 %.
pub const DEFAULT_PRECISION: f64 = 0.1;
/// The default evaluation budget per estimator.
pub const DEFAULT_MAX_EVALUATIONS: u64 = 10_000_000;
/// The default points per level of subset simulation.
pub const DEFAULT_LEVEL_SAMPLES: usize = 2000;
/// The fewest points per level (p₀N = 10 chains).
pub const LEAST_LEVEL_SAMPLES: usize = 100;

/// What a caller asks of a rare-event analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct RareRequest {
    /// The output, by name.
    pub output: Option<String>,
    /// The event's threshold: the value above it.
    pub above: Option<f64>,
    /// The event's threshold: the value below it.
    pub below: Option<f64>,
    /// The estimators (both when empty; one asked twice runs once).
    pub methods: Vec<Method>,
    /// The relative half width to stop at.
    pub precision: Option<f64>,
    /// The evaluation budget per estimator.
    pub max_evaluations: Option<u64>,
    /// Points per level of subset simulation.
    pub level_samples: Option<u64>,
    /// The seed.
    pub seed: Option<u64>,
    /// The share of evaluations the output may be non-finite in (`--max-non-finite`).
    pub max_non_finite: f64,
}

impl RareRequest {
    /// The settings, checked against `scenario`.
    pub fn settings(&self, scenario: &Scenario, caller: Caller) -> Result<RareSettings, Refusal> {
        let output = self.output(scenario, caller)?;
        let event = match (self.above, self.below) {
            (Some(_), Some(_)) => {
                return Err(Refusal::option(
                    caller,
                    "below",
                    "give one threshold: --above or --below",
                ))
            }
            (Some(t), None) => Event::Above(finite(t, "above", caller)?),
            (None, Some(t)) => Event::Below(finite(t, "below", caller)?),
            (None, None) if scenario.outputs[output].spec.is_some() => Event::OutOfSpec,
            (None, None) => {
                return Err(Refusal::option(
                    caller,
                    "above",
                    format!(
                        "{} has no spec limits: give the event's threshold (--above or --below)",
                        scenario.outputs[output].name
                    ),
                ))
            }
        };
        let precision = precision(self.precision, caller)?;
        let level_samples = self.level_samples.unwrap_or(DEFAULT_LEVEL_SAMPLES as u64);
        if level_samples < LEAST_LEVEL_SAMPLES as u64 || level_samples > 10_000_000 {
            return Err(Refusal::option(
                caller,
                "level_samples",
                format!("{level_samples} is outside 100 to 10,000,000"),
            ));
        }
        let mut methods: Vec<Method> = Vec::new();
        for &m in &self.methods {
            if !methods.contains(&m) {
                methods.push(m);
            }
        }
        if methods.is_empty() {
            methods = vec![Method::Importance, Method::Subset];
        }
        Ok(RareSettings {
            seed: self.seed.unwrap_or(scenario.seed),
            output,
            event,
            methods,
            budget: Budget {
                precision,
                max_evaluations: self.max_evaluations.unwrap_or(DEFAULT_MAX_EVALUATIONS),
            },
            level_samples: level_samples as usize,
            max_non_finite: self.max_non_finite,
        })
    }

    /// The asked output, or the scenario's only continuous one.
    fn output(&self, scenario: &Scenario, caller: Caller) -> Result<usize, Refusal> {
        let names: Vec<String> = self.output.iter().cloned().collect();
        let outputs = continuous_outputs(scenario, &names, "a rare event", caller)?;
        match outputs.as_slice() {
            [one] => Ok(*one),
            _ => Err(Refusal::option(
                caller,
                "output",
                format!(
                    "name the output whose event to estimate: {}",
                    (outputs.iter())
                        .map(|&o| scenario.outputs[o].name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )),
        }
    }
}

/// The asked relative half width (the default ±10 %), refused outside (0, 1).
pub(crate) fn precision(asked: Option<f64>, caller: Caller) -> Result<f64, Refusal> {
    let precision = asked.unwrap_or(DEFAULT_PRECISION);
    if !(precision > 0.0 && precision < 1.0) {
        return Err(Refusal::option(
            caller,
            "precision",
            format!("{precision} is not a share between 0 and 1 (0.1: ±10 %)"),
        ));
    }
    Ok(precision)
}

fn finite(t: f64, option: &str, caller: Caller) -> Result<f64, Refusal> {
    match t.is_finite() {
        true => Ok(t),
        false => Err(Refusal::option(caller, option, "not a finite number")),
    }
}
