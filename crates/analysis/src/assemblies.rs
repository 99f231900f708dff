//! Assemblies chosen for their output value, and the curves of the models at them: beside
//! the nominal assembly's curves, a page draws those of the assemblies whose output lies
//! nearest the run's P50 and P99.865 (a transmission-error trace of the median assembly
//! and of one in the tail, where the spec bites).
//!
//! The assemblies are the first [`ASSEMBLY_ROWS`] rows drawn with the run's seed by Monte
//! Carlo (the run's own first rows when it ran Monte Carlo; a Latin hypercube or RQMC run
//! draws others): of those whose output has a value (not excluded by its indicator, finite)
//! the one nearest each target value, the first on a tie. Choosing among 4,096 rows puts
//! about 5.5 rows above the P99.865 value, so the one chosen lies near it, not exactly on
//! it; the page says which row it is and its value. A curve the model gives no finite
//! value for at the chosen assembly (the rigid first-contact reading of a transmission
//! error where the profiles interfere at rest) is named, not drawn.

use rvtol_engine::chunk::Sampling;
use rvtol_engine::run::{model_inputs_of_row, sample_table};
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_engine::{RunSettings, DEFAULT_EXACT_PERCENTILE_LIMIT};
use rvtol_models::{ConditionEffect, Curve, OutputKind};

/// Rows searched for the chosen assemblies.
pub const ASSEMBLY_ROWS: u64 = 4096;

/// One model's curves at an assembly chosen for the value of one of its outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct ChosenAssembly {
    /// The model's name.
    pub model: &'static str,
    /// The output the assembly was chosen by.
    pub output: String,
    /// What it was chosen for (`P50`).
    pub label: String,
    /// The target value (the run's percentile).
    pub target: f64,
    /// The row (0-based) among the rows drawn.
    pub sample: u64,
    /// Rows drawn.
    pub rows: u64,
    /// The output's value there.
    pub value: f64,
    /// The model's curves there that have a value at every point.
    pub curves: Vec<Curve>,
    /// The titles of those it gives no finite value for there (a rigid first-contact
    /// curve of an assembly whose profiles interfere at rest).
    pub left_out: Vec<String>,
}

/// The output a model's chosen assemblies are chosen by: its first continuous output with
/// spec limits, else its first continuous output.
pub fn curve_output(scenario: &Scenario, model: usize) -> Option<usize> {
    let bound = &scenario.models[model];
    let own = bound.first_output..bound.first_output + bound.model.outputs().len();
    let continuous: Vec<usize> = own
        .filter(|&o| scenario.outputs[o].kind == OutputKind::Continuous)
        .collect();
    (continuous.iter())
        .find(|&&o| scenario.outputs[o].spec.is_some())
        .or(continuous.first())
        .copied()
}

/// For each model that draws curves, the assemblies nearest `targets(output)` (label, value)
/// of its [`curve_output`], among the first [`ASSEMBLY_ROWS`] (at most `samples`) rows drawn
/// with `seed`, each with the model's curves there. Uses the current rayon pool.
pub fn chosen_assemblies(
    scenario: &Scenario,
    seed: u64,
    samples: u64,
    targets: &dyn Fn(&str) -> Vec<(String, f64)>,
) -> Result<Vec<ChosenAssembly>, ScenarioError> {
    // (model, its output, the targets to choose by); a model that draws no curves has
    // none at the chosen rows either and is left out there.
    type Drawing = (usize, usize, Vec<(String, f64)>);
    let drawing: Vec<Drawing> = (0..scenario.models.len())
        .filter_map(|m| {
            let o = curve_output(scenario, m)?;
            let wanted = targets(&scenario.outputs[o].name);
            (!wanted.is_empty()).then_some((m, o, wanted))
        })
        .collect();
    if drawing.is_empty() {
        return Ok(Vec::new());
    }
    let rows = samples.clamp(1, ASSEMBLY_ROWS);
    let table = sample_table(
        scenario,
        RunSettings {
            samples: rows,
            seed,
            exact_percentile_limit: DEFAULT_EXACT_PERCENTILE_LIMIT,
            sampling: Sampling::MONTE_CARLO,
        },
    )?;
    let mut chosen = Vec::new();
    for (m, o, wanted) in drawing {
        for (label, target) in wanted {
            let Some(r) = nearest_row(scenario, &table, o, target) else {
                continue;
            };
            let (row, outputs) = (table.input_row(r), table.output_row(r));
            let inputs = model_inputs_of_row(scenario, row, outputs);
            let (curves, left_out) = (scenario.models[m].model.curves(&inputs[m]).into_iter())
                .partition::<Vec<Curve>, _>(|curve| curve.first_non_finite().is_none());
            if curves.is_empty() && left_out.is_empty() {
                continue;
            }
            chosen.push(ChosenAssembly {
                model: scenario.models[m].model.name(),
                output: scenario.outputs[o].name.clone(),
                label,
                target,
                sample: r as u64,
                rows,
                value: outputs[o],
                curves,
                left_out: left_out.into_iter().map(|curve| curve.title).collect(),
            });
        }
    }
    Ok(chosen)
}

/// The row of `table` whose output `o` lies nearest `target`, among those with a value
/// (finite, not excluded by the output's indicator); the first on a tie.
fn nearest_row(
    scenario: &Scenario,
    table: &rvtol_engine::SampleTable,
    o: usize,
    target: f64,
) -> Option<usize> {
    let excluded = |outputs: &[f64]| match scenario.outputs[o].condition {
        Some((k, ConditionEffect::Excluded)) => outputs[k].is_finite() && outputs[k] != 0.0,
        _ => false,
    };
    (0..table.rows)
        .filter(|&r| {
            let outputs = table.output_row(r);
            outputs[o].is_finite() && !excluded(outputs)
        })
        .min_by(|&a, &b| {
            let distance = |r: usize| (table.output_row(r)[o] - target).abs();
            distance(a).total_cmp(&distance(b)).then(a.cmp(&b))
        })
}
