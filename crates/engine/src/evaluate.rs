//! Evaluating a scenario's models on a block of sampled input rows: gather each model's
//! inputs from the row columns (constants pre-filled once), call the model once per block
//! (`evaluate_batch`, so no dynamic dispatch per sample), and lay each output out as a
//! contiguous column for the statistics. Shared by the Monte Carlo run and the
//! sensitivity analysis; owns its scratch buffers, so the hot loop does not allocate.

use crate::run::CHUNK_SIZE;
use crate::scenario::Scenario;

/// Scratch buffers and bindings to evaluate up to [`CHUNK_SIZE`] rows at a time.
pub struct ChunkEvaluator<'a> {
    scenario: &'a Scenario,
    gathers: Vec<Vec<(usize, usize)>>,
    model_inputs: Vec<Vec<f64>>,
    model_outputs: Vec<Vec<f64>>,
    /// One column per scenario output; the first `m` values are those of the last block.
    pub output_columns: Vec<Vec<f64>>,
}

impl<'a> ChunkEvaluator<'a> {
    /// Buffers for `scenario`.
    pub fn new(scenario: &'a Scenario) -> Self {
        ChunkEvaluator {
            scenario,
            gathers: scenario
                .models
                .iter()
                .map(|m| m.column_bindings())
                .collect(),
            model_inputs: scenario
                .models
                .iter()
                .map(|m| m.constant_template().repeat(CHUNK_SIZE))
                .collect(),
            model_outputs: scenario
                .models
                .iter()
                .map(|m| vec![0.0; CHUNK_SIZE * m.model.outputs().len()])
                .collect(),
            output_columns: vec![vec![0.0; CHUNK_SIZE]; scenario.outputs.len()],
        }
    }

    /// Evaluates every model on the first `m` rows (row-major, `n_columns` per row) and
    /// fills `output_columns[o][..m]`. `m` ≤ [`CHUNK_SIZE`].
    pub fn evaluate(&mut self, rows: &[f64], m: usize) {
        self.evaluate_at(rows, m, 0);
    }

    /// Like [`ChunkEvaluator::evaluate`], but fills `output_columns[o][first..first + m]`:
    /// a chunk evaluated block by block (`first + m` ≤ [`CHUNK_SIZE`]).
    pub fn evaluate_at(&mut self, rows: &[f64], m: usize, first: usize) {
        let n_columns = self.scenario.input_space.n_columns().max(1);
        for (model_index, bound) in self.scenario.models.iter().enumerate() {
            let n_in = bound.model.inputs().len();
            let n_out = bound.model.outputs().len();
            let inputs = &mut self.model_inputs[model_index][..m * n_in];
            if n_in > 0 {
                // One bound input at a time: a tight strided copy per input.
                for &(input, column) in &self.gathers[model_index] {
                    for (dst, row) in inputs
                        .chunks_exact_mut(n_in)
                        .zip(rows.chunks_exact(n_columns))
                    {
                        dst[input] = row[column];
                    }
                }
            }
            let outputs = &mut self.model_outputs[model_index][..m * n_out];
            bound.model.evaluate_batch(inputs, outputs);
            for j in 0..n_out {
                let column = &mut self.output_columns[bound.first_output + j];
                for (r, value) in column[first..first + m].iter_mut().enumerate() {
                    *value = outputs[r * n_out + j];
                }
            }
        }
    }
}
