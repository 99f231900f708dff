//! Evaluating a scenario's models on a block of sampled inputs held column by column:
//! each model input is a slice, either a sampled column or a constant column filled once,
//! or an output of a model above it (the models are evaluated in their order, each block
//! once), the model is called once per block ([`ErrorModel::evaluate_columns`], so no dynamic
//! dispatch per sample), and each output lands as a contiguous column for the statistics.
//! Shared by the Monte Carlo run (column-major blocks straight from the sampler) and the
//! sensitivity analyses (row-major rows, transposed here); owns its scratch buffers, so
//! the hot loop does not allocate (for models of up to [`STACK_INPUTS`] inputs; beyond,
//! one small buffer of slices per block). Rows whose outputs are not finite are counted
//! per output and checked against the allowed share as a run's samples are
//! ([`check_non_finite_rows`]).
//!
//! [`ErrorModel::evaluate_columns`]: rvtol_models::ErrorModel::evaluate_columns

use rvtol_models::ConditionEffect;

use crate::chunk::CHUNK_SIZE;
use crate::scenario::{Binding, Scenario, ScenarioError};

/// The drawn inputs and the models' outputs of every sample of a run, one row per sample
/// in sample order: the values [`run`] draws and evaluates for the same seed, whatever
/// the thread count.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleTable {
    /// Rows (samples).
    pub rows: usize,
    /// Input-space columns per row ([`Scenario::columns`] order).
    pub n_inputs: usize,
    /// Outputs per row ([`Scenario::outputs`] order).
    pub n_outputs: usize,
    /// Row-major inputs, `rows × n_inputs`.
    pub inputs: Vec<f64>,
    /// Row-major outputs, `rows × n_outputs`.
    pub outputs: Vec<f64>,
}

impl SampleTable {
    /// Row `r`'s inputs.
    pub fn input_row(&self, r: usize) -> &[f64] {
        &self.inputs[r * self.n_inputs..(r + 1) * self.n_inputs]
    }

    /// Row `r`'s outputs.
    pub fn output_row(&self, r: usize) -> &[f64] {
        &self.outputs[r * self.n_outputs..(r + 1) * self.n_outputs]
    }
}

/// Most values (rows × (inputs + outputs)) a [`SampleTable`] holds: 160 MB of numbers.
pub const MAX_SAMPLE_TABLE_VALUES: u64 = 20_000_000;

/// Whether a [`SampleTable`] of `rows` rows of `scenario` (its inputs and outputs) stays
/// within [`MAX_SAMPLE_TABLE_VALUES`]; the error says how many rows fit.
pub fn check_table_rows(scenario: &Scenario, rows: u64) -> Result<(), String> {
    let columns = (scenario.input_space.n_columns() + scenario.outputs.len()).max(1) as u64;
    let most = MAX_SAMPLE_TABLE_VALUES / columns;
    if rows > most {
        return Err(format!(
            "at most {most} rows of this scenario ({columns} columns, {MAX_SAMPLE_TABLE_VALUES} values), asked {rows}"
        ));
    }
    Ok(())
}

/// Model inputs whose slices are gathered on the stack (larger models use one heap
/// buffer per block).
pub const STACK_INPUTS: usize = 256;

/// Scratch buffers and bindings to evaluate up to [`CHUNK_SIZE`] rows at a time.
pub struct ChunkEvaluator<'a> {
    scenario: &'a Scenario,
    /// Per model, one [`CHUNK_SIZE`]-long column per constant input, in input order.
    constant_columns: Vec<Vec<f64>>,
    /// Column-major copy of row-major input for [`ChunkEvaluator::evaluate`] (grown on
    /// first use: the run's hot loop never needs it).
    transposed: Vec<f64>,
    /// Column-major outputs of one model for one block.
    model_outputs: Vec<f64>,
    /// One column per scenario output; the first `m` values are those of the last block.
    pub output_columns: Vec<Vec<f64>>,
}

impl<'a> ChunkEvaluator<'a> {
    /// Buffers for `scenario`.
    pub fn new(scenario: &'a Scenario) -> Self {
        let constant_columns = scenario
            .models
            .iter()
            .map(|bound| {
                bound
                    .bindings
                    .iter()
                    .filter_map(|binding| match binding {
                        Binding::Constant(value) => Some([*value; 1].repeat(CHUNK_SIZE)),
                        Binding::Column(_) | Binding::Output(_) => None,
                    })
                    .flatten()
                    .collect()
            })
            .collect();
        let max_outputs = scenario
            .models
            .iter()
            .map(|bound| bound.model.outputs().len())
            .max()
            .unwrap_or(0);
        ChunkEvaluator {
            scenario,
            constant_columns,
            transposed: Vec::new(),
            model_outputs: vec![0.0; CHUNK_SIZE * max_outputs],
            output_columns: vec![vec![0.0; CHUNK_SIZE]; scenario.outputs.len()],
        }
    }

    /// Evaluates every model on the first `m` rows of row-major `rows` (`n_columns` per
    /// row) and fills `output_columns[o][..m]`. `m` ≤ [`CHUNK_SIZE`].
    pub fn evaluate(&mut self, rows: &[f64], m: usize) {
        let n_columns = self.scenario.input_space.n_columns();
        let mut transposed = std::mem::take(&mut self.transposed);
        if transposed.len() < m * n_columns {
            transposed.resize(m * n_columns, 0.0);
        }
        if n_columns > 0 {
            for (c, column) in transposed[..m * n_columns]
                .chunks_exact_mut(m.max(1))
                .enumerate()
            {
                for (x, row) in column.iter_mut().zip(rows.chunks_exact(n_columns)) {
                    *x = row[c];
                }
            }
        }
        self.evaluate_columns_at(&transposed[..m * n_columns], m, 0);
        self.transposed = transposed;
    }

    /// Evaluates every model on a column-major block of `m` rows (`columns[c·m + r]` is
    /// input-space column c of row r) and fills `output_columns[o][first..first + m]`: a
    /// chunk evaluated block by block (`first + m` ≤ [`CHUNK_SIZE`]).
    pub fn evaluate_columns_at(&mut self, columns: &[f64], m: usize, first: usize) {
        for (bound, constants) in self.scenario.models.iter().zip(&self.constant_columns) {
            let n_in = bound.bindings.len();
            let n_out = bound.model.outputs().len();
            let mut stack: [&[f64]; STACK_INPUTS] = [&[]; STACK_INPUTS];
            let mut heap: Vec<&[f64]> = Vec::new();
            let inputs: &mut [&[f64]] = if n_in <= STACK_INPUTS {
                &mut stack[..n_in]
            } else {
                heap.resize(n_in, &[]);
                &mut heap
            };
            let mut constant = constants.chunks_exact(CHUNK_SIZE);
            for (input, binding) in inputs.iter_mut().zip(&bound.bindings) {
                *input = match binding {
                    Binding::Column(c) => &columns[c * m..(c + 1) * m],
                    // Written by a model above, for these rows.
                    Binding::Output(o) => &self.output_columns[*o][first..first + m],
                    Binding::Constant(_) => &constant.next().expect("one column per constant")[..m],
                };
            }
            let outputs = &mut self.model_outputs[..m * n_out];
            bound.model.evaluate_columns(inputs, outputs);
            for (j, values) in outputs.chunks_exact(m.max(1)).enumerate() {
                self.output_columns[bound.first_output + j][first..first + m]
                    .copy_from_slice(values);
            }
        }
    }
}

/// Evaluates every model on given input rows (row-major, `scenario.input_space.n_columns()`
/// values per row: a designed experiment, measured assemblies, another sampler's design),
/// in blocks of [`CHUNK_SIZE`] rows in parallel (the current rayon pool); each row's
/// outputs depend on that row alone.
pub fn evaluate_rows(scenario: &Scenario, inputs: Vec<f64>) -> SampleTable {
    use rayon::prelude::*;
    let n_inputs = scenario.input_space.n_columns();
    let n_outputs = scenario.outputs.len();
    let rows = inputs.len().checked_div(n_inputs).unwrap_or(0);
    let blocks: Vec<Vec<f64>> = inputs
        .par_chunks(CHUNK_SIZE * n_inputs.max(1))
        .map_init(
            || ChunkEvaluator::new(scenario),
            |evaluator, block| {
                let m = block.len() / n_inputs.max(1);
                evaluator.evaluate(block, m);
                let mut outputs = Vec::with_capacity(m * n_outputs);
                for r in 0..m {
                    outputs.extend(evaluator.output_columns.iter().map(|column| column[r]));
                }
                outputs
            },
        )
        .collect();
    SampleTable {
        rows,
        n_inputs,
        n_outputs,
        inputs,
        outputs: blocks.concat(),
    }
}

/// The rows of one output whose value is not finite although its indicator does not
/// exclude them: lost data, as a run counts it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NonFiniteRows {
    /// How many.
    pub count: usize,
    /// The first (row index), if any.
    pub first: Option<usize>,
}

/// Per output of `scenario`, the rows of `table` whose value is not finite (a row its
/// output's [`ConditionEffect::Excluded`] indicator flags has no value and is not counted).
pub fn non_finite_rows(scenario: &Scenario, table: &SampleTable) -> Vec<NonFiniteRows> {
    let n = table.n_outputs;
    (0..n)
        .map(|o| {
            let mut lost = NonFiniteRows::default();
            for r in 0..table.rows {
                let row = &table.outputs[r * n..(r + 1) * n];
                let excluded = match scenario.outputs[o].condition {
                    Some((k, ConditionEffect::Excluded)) => row[k].is_finite() && row[k] != 0.0,
                    _ => false,
                };
                if !excluded && !row[o].is_finite() {
                    lost.count += 1;
                    lost.first.get_or_insert(r);
                }
            }
            lost
        })
        .collect()
}

/// One line per output that lost rows, for standard error: `OUTPUT is not finite for K of
/// N rows (S %, first in ROW)`, `row` naming a row index as the caller's file has it.
pub fn non_finite_lines(
    scenario: &Scenario,
    table: &SampleTable,
    lost: &[NonFiniteRows],
    row: &dyn Fn(usize) -> String,
) -> Vec<(usize, String)> {
    lost.iter()
        .enumerate()
        .filter(|(_, l)| l.count > 0)
        .map(|(o, l)| {
            (
                o,
                format!(
                    "{} is not finite for {} of {} rows ({} %, first in {})",
                    scenario.outputs[o].name,
                    crate::format::group_thousands(l.count as u64),
                    crate::format::group_thousands(table.rows as u64),
                    crate::format::format_sig(100.0 * l.count as f64 / table.rows as f64),
                    row(l.first.unwrap_or(0))
                ),
            )
        })
        .collect()
}

/// As a run's `run::check_non_finite`, for given rows: the first output that lost
/// more than `max_share` of the rows to non-finite values is an error naming its model's
/// JSON path, the count, the share and the first such row (`row` names it).
pub fn check_non_finite_rows(
    scenario: &Scenario,
    table: &SampleTable,
    max_share: f64,
    row: &dyn Fn(usize) -> String,
) -> Result<(), ScenarioError> {
    let lost = non_finite_rows(scenario, table);
    for (o, line) in non_finite_lines(scenario, table, &lost, row) {
        let share = lost[o].count as f64 / table.rows as f64;
        if share > max_share {
            return Err(ScenarioError::new(
                scenario.model_of_output(o),
                format!(
                    "{line}, more than the allowed {} %: the model cannot evaluate these inputs; correct the rows, or accept a share with --max-non-finite",
                    rvtol_deviation::Shown(100.0 * max_share)
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stack y = x with x given: one row NaN-free, one whose value overflows to inf.
    fn stack() -> Scenario {
        Scenario::from_json(
            r#"{
                "variables": [ { "name": "x", "distribution": { "normal": { "mean": 0, "sd": 1 } } } ],
                "models": [ { "model": "linear_stack",
                              "params": { "output": "y", "coefficients": { "x": 1e12 } },
                              "inputs": { "x": "x" } } ]
            }"#,
            "stack",
        )
        .expect("a valid scenario")
    }

    #[test]
    fn lost_rows_are_counted_and_fail_beyond_the_allowed_share() {
        let scenario = stack();
        let table = evaluate_rows(&scenario, vec![1.0, 1e300, 2.0, 1e300]);
        let lost = non_finite_rows(&scenario, &table);
        assert_eq!(
            lost,
            [NonFiniteRows {
                count: 2,
                first: Some(1)
            }]
        );
        let row = |r: usize| format!("row {r}");
        let err = check_non_finite_rows(&scenario, &table, 0.0, &row).unwrap_err();
        assert_eq!(err.path, "models[0] (linear_stack)");
        assert!(
            err.message
                .starts_with("y is not finite for 2 of 4 rows (50.000 %, first in row 1), more than the allowed 0 %"),
            "{}",
            err.message
        );
        assert!(check_non_finite_rows(&scenario, &table, 0.5, &row).is_ok());
        assert!(check_non_finite_rows(&scenario, &table, 0.49, &row).is_err());
    }
}
