//! The limit state of a rare event: the scenario's map from the standard normal space
//! onto its law ([`rvtol_deviation::InputSpace::sample_columns_from_normals`]: one score
//! per dimension, the constraints of 001 Eq. 11 met by exact conditional inversion, so the
//! normal space has no forbidden region and no rejection weight) followed by the models,
//! read as a score s(z) whose positive values are the event.
//!
//! - `above t`: s = y − t; `below t`: s = t − y;
//! - out of spec: s = max(y − U, L − y) over the limits the spec sets, and s = +∞ for a
//!   sample the output's indicator flags non-conforming (unless the spec lets flagged
//!   samples conform) or excludes: the conformity every figure of rvtol uses;
//! - a value the model cannot compute (non-finite, not excluded by an indicator) is +∞,
//!   the event (as a run counts it out of spec), and is counted
//!   ([`LimitState::non_finite`]) for the `--max-non-finite` check; an excluded sample
//!   has no value: in the event out of spec, −∞ (never) above or below a threshold.
//!
//! Rows are evaluated in tasks of [`TASK_ROWS`] over the current rayon pool and gathered
//! in row order: the scores of a batch do not depend on the thread count. Each thread of
//! the pool keeps one set of buffers (a model evaluator with its constant columns) for
//! the limit state's life: building them per task cost more than a fast model's rows.

use std::sync::Mutex;

use rayon::prelude::*;
use rvtol_deviation::SamplerScratch;
use rvtol_engine::evaluate::ChunkEvaluator;
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_models::ConditionEffect;

/// Rows per parallel task: few, so that a batch of a costly model (milliseconds a row)
/// spreads over the threads.
const TASK_ROWS: usize = 32;

/// Which values of the output are the event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// The value above a threshold.
    Above(f64),
    /// The value below a threshold.
    Below(f64),
    /// The sample does not conform to the output's spec limits.
    OutOfSpec,
}

/// One output's event over the standard normal space of a scenario.
pub struct LimitState<'a> {
    scenario: &'a Scenario,
    /// Told the rows of each batch as it is done.
    progress: &'a (dyn Fn(u64) + Sync),
    output: usize,
    event: Event,
    dims: usize,
    /// Model evaluations (rows) so far.
    pub evaluations: u64,
    /// Of them, those whose value is not finite.
    pub non_finite: u64,
    /// One worker per thread of the pool it was made in (a thread takes the one of its
    /// index; the lock is never contended within that pool).
    workers: Vec<Mutex<Worker<'a>>>,
}

impl<'a> LimitState<'a> {
    /// The limit state of `event` on output `output`; an error when the scenario's law
    /// cannot be reached from normal scores (three coupled Eq. 11 inequalities), has no
    /// random input, or the event is out of spec and the output has no spec limits.
    /// `progress` is told the rows of each batch as it is done.
    pub fn new(
        scenario: &'a Scenario,
        output: usize,
        event: Event,
        progress: &'a (dyn Fn(u64) + Sync),
    ) -> Result<LimitState<'a>, ScenarioError> {
        let dims = scenario.input_space.quasi_dimensions()?;
        if dims == 0 {
            return Err(ScenarioError::new(
                "variables",
                "the scenario has no random input: its outputs have no tail",
            ));
        }
        if event == Event::OutOfSpec && scenario.outputs[output].spec.is_none() {
            return Err(ScenarioError::new(
                "spec_limits",
                format!(
                    "{} has no spec limits to be out of; give a threshold (--above or --below)",
                    scenario.outputs[output].name
                ),
            ));
        }
        Ok(LimitState {
            scenario,
            progress,
            output,
            event,
            dims,
            evaluations: 0,
            non_finite: 0,
            workers: (0..rayon::current_num_threads())
                .map(|_| Mutex::new(Worker::new(scenario)))
                .collect(),
        })
    }

    /// Dimensions of the normal space.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// The scores of row-major points `z` ([`LimitState::dims`] per point), in point order.
    pub fn scores(&mut self, z: &[f64]) -> Vec<f64> {
        self.evaluate(z).into_iter().map(|(_, s)| s).collect()
    }

    /// The output's value and the score of row-major points `z`, in point order; the value
    /// is NaN where the model gives none (not finite, or the sample excluded).
    pub fn evaluate(&mut self, z: &[f64]) -> Vec<(f64, f64)> {
        let dims = self.dims.max(1);
        self.evaluations += (z.len() / dims) as u64;
        let (output, event, workers) = (self.output, self.event, &self.workers);
        let blocks: Vec<Vec<(f64, f64)>> = z
            .par_chunks(TASK_ROWS * dims)
            .map(|block| {
                let index = rayon::current_thread_index().unwrap_or(0) % workers.len();
                let mut worker = workers[index].lock().unwrap_or_else(|e| e.into_inner());
                worker.evaluate(block, dims, output, event)
            })
            .collect();
        (self.progress)((z.len() / dims) as u64);
        let mut pairs = blocks.concat();
        for (_, s) in pairs.iter_mut().filter(|(_, s)| s.is_nan()) {
            self.non_finite += 1;
            *s = f64::INFINITY;
        }
        pairs
    }

    /// The input row (the scenario's columns) of one point.
    pub fn row(&self, z: &[f64]) -> Vec<f64> {
        let space = &self.scenario.input_space;
        let mut columns = vec![0.0; space.n_columns()];
        let mut scores = z.to_vec();
        (space.sample_columns_from_normals(
            &mut scores,
            &mut columns,
            &mut SamplerScratch::default(),
        ))
        .expect("the dimensions were checked when the limit state was made");
        columns
    }
}

/// One task's buffers.
struct Worker<'a> {
    scenario: &'a Scenario,
    evaluator: ChunkEvaluator<'a>,
    scratch: SamplerScratch,
    transposed: Vec<f64>,
    columns: Vec<f64>,
}

impl<'a> Worker<'a> {
    fn new(scenario: &'a Scenario) -> Worker<'a> {
        Worker {
            scenario,
            evaluator: ChunkEvaluator::new(scenario),
            scratch: SamplerScratch::default(),
            transposed: Vec::new(),
            columns: Vec::new(),
        }
    }

    /// The values and scores of a block of row-major points.
    fn evaluate(
        &mut self,
        block: &[f64],
        dims: usize,
        output: usize,
        event: Event,
    ) -> Vec<(f64, f64)> {
        let space = &self.scenario.input_space;
        let m = block.len() / dims;
        self.transposed.resize(dims * m, 0.0);
        for (r, point) in block.chunks_exact(dims).enumerate() {
            for (d, &value) in point.iter().enumerate() {
                self.transposed[d * m + r] = value;
            }
        }
        self.columns.resize(space.n_columns() * m, 0.0);
        (space.sample_columns_from_normals(
            &mut self.transposed[..dims * m],
            &mut self.columns,
            &mut self.scratch,
        ))
        .expect("the dimensions were checked when the limit state was made");
        self.evaluator.evaluate_columns_at(&self.columns, m, 0);
        (0..m)
            .map(|r| self.value_and_score(r, output, event))
            .collect()
    }

    /// The value (NaN when excluded or not finite) and the score of row `r` of the last
    /// block (the score NaN where the value is not finite and no indicator excludes the
    /// sample).
    fn value_and_score(&self, r: usize, output: usize, event: Event) -> (f64, f64) {
        let info = &self.scenario.outputs[output];
        let column = |k: usize| self.evaluator.output_columns[k][r];
        let y = column(output);
        let (excluded, flagged) = match info.condition {
            Some((k, ConditionEffect::Excluded)) => (column(k) != 0.0, false),
            Some((k, ConditionEffect::NonConforming)) => {
                (false, !info.flagged_conform && column(k) != 0.0)
            }
            None => (false, false),
        };
        let value = if excluded || !y.is_finite() {
            f64::NAN
        } else {
            y
        };
        let score = match event {
            _ if excluded => match event {
                Event::OutOfSpec => f64::INFINITY,
                _ => f64::NEG_INFINITY,
            },
            _ if !y.is_finite() => f64::NAN,
            Event::Above(t) => y - t,
            Event::Below(t) => t - y,
            Event::OutOfSpec if flagged => f64::INFINITY,
            Event::OutOfSpec => {
                let limits = info.spec.expect("checked in LimitState::new");
                let above = limits.upper.map_or(f64::NEG_INFINITY, |u| y - u);
                let below = limits.lower.map_or(f64::NEG_INFINITY, |l| l - y);
                above.max(below)
            }
        };
        (value, score)
    }
}
