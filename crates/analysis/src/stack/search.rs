//! The worst case of one output over the tolerance box: the extremes over every corner
//! when there are few enough, then a coordinate search from the best corner found.
//!
//! - **Corners** ([`corner_extremes`]): when the box has at most [`MOST_VERTICES`]
//!   corners, every one is evaluated; the largest and smallest values are the exact worst
//!   case of an output monotone in each input (whatever the direction), a linear one among
//!   them. Otherwise the corner the gradient at the centre points to (per coordinate, the
//!   vertex with the largest g·x for the maximum, the smallest for the minimum): exact for
//!   a linear output and for one monotone in each input with the gradient's signs.
//! - **Coordinate search** ([`improve`]): from that corner, each of the leading
//!   coordinates (by |g|·T, at most [`MOST_SEARCHED`]) tries each of its levels (the
//!   corners, and points inside: the quarter points and the centre of an interval, the
//!   inner points of a constrained pair); the best improving move is taken, until no move
//!   improves (at most [`MOST_ROUNDS`] rounds). Pattern search on a grid: what it finds is
//!   a value the box reaches, so the true worst case is at least as far out; an
//!   improvement on the corners is reported (an extreme inside the box: the output is not
//!   monotone there).
//!
//! Candidates whose value is not finite (a sample the model excludes) are never taken.
//! Every step is deterministic and the candidates are evaluated in a fixed order, so the
//! result does not depend on the thread count.

use rayon::prelude::*;
use rvtol_engine::evaluate::ChunkEvaluator;
use rvtol_engine::scenario::Scenario;

use super::tolerance_box::ToleranceBox;

/// Most corners evaluated one by one.
pub const MOST_VERTICES: u64 = 4096;
/// Most coordinates the search moves.
pub const MOST_SEARCHED: usize = 24;
/// Most rounds of the search.
pub const MOST_ROUNDS: usize = 50;

/// The best row found in one direction, with its value.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// The input row.
    pub row: Vec<f64>,
    /// The output's value there.
    pub value: f64,
}

/// Model values of many rows, counted.
pub(super) struct Evaluator<'a> {
    pub scenario: &'a Scenario,
    pub evaluations: u64,
}

/// Rows per parallel task: few, so that the search's rounds of a few hundred rows of a
/// costly model (the loaded transmission error, milliseconds a row) spread over the
/// threads.
const TASK_ROWS: usize = 16;

impl Evaluator<'_> {
    /// Every output of every row (row-major rows in, row-major outputs out), in blocks of
    /// [`TASK_ROWS`] over the current rayon pool, in row order.
    pub fn outputs(&mut self, rows: Vec<f64>) -> Vec<f64> {
        let n_columns = self.scenario.input_space.n_columns().max(1);
        self.evaluations += (rows.len() / n_columns) as u64;
        let scenario = self.scenario;
        let blocks: Vec<Vec<f64>> = rows
            .par_chunks(TASK_ROWS * n_columns)
            .map_init(
                || ChunkEvaluator::new(scenario),
                |evaluator, block| {
                    let m = block.len() / n_columns;
                    evaluator.evaluate(block, m);
                    (0..m)
                        .flat_map(|r| evaluator.output_columns.iter().map(move |c| c[r]))
                        .collect()
                },
            )
            .collect();
        blocks.concat()
    }
}

/// The extremes of each output of `outputs` over the box's corners (all of them, or the
/// two of each gradient of `gradients`); per output `[lowest, highest]` (`None` where no
/// corner has a finite value), and whether every corner was evaluated.
pub(super) fn corner_extremes(
    evaluator: &mut Evaluator,
    tolerance_box: &ToleranceBox,
    gradients: &[Vec<f64>],
    outputs: &[usize],
) -> (Vec<[Option<Found>; 2]>, bool) {
    let n_out = evaluator.scenario.outputs.len();
    let rows: Vec<Vec<f64>> = if tolerance_box.vertex_count() <= MOST_VERTICES {
        (0..tolerance_box.vertex_count())
            .map(|i| {
                let mut row = tolerance_box.centre.clone();
                tolerance_box.vertex(i, &mut row);
                row
            })
            .collect()
    } else {
        (gradients.iter())
            .flat_map(|g| [-1.0, 1.0].map(|s| gradient_corner(tolerance_box, g, s)))
            .collect()
    };
    let values = evaluator.outputs(rows.concat());
    let extremes = outputs
        .iter()
        .map(|&o| {
            let value_of = |r: usize| values[r * n_out + o];
            [-1.0, 1.0].map(|s| {
                (0..rows.len())
                    .filter(|&r| value_of(r).is_finite())
                    .fold(None, |best: Option<usize>, r| match best {
                        Some(b) if s * value_of(r) <= s * value_of(b) => Some(b),
                        _ => Some(r),
                    })
                    .map(|r| Found {
                        row: rows[r].clone(),
                        value: value_of(r),
                    })
            })
        })
        .collect();
    (extremes, tolerance_box.vertex_count() <= MOST_VERTICES)
}

/// The corner the gradient points to: the maximum's for `sign` +1, the minimum's for −1.
fn gradient_corner(tolerance_box: &ToleranceBox, gradient: &[f64], sign: f64) -> Vec<f64> {
    let signed: Vec<f64> = gradient.iter().map(|g| sign * g).collect();
    let mut row = tolerance_box.centre.clone();
    for k in &tolerance_box.coordinates {
        k.set(&mut row, k.best_vertex(&signed));
    }
    row
}

/// The box's centre with one coordinate at a time moved to each of its corners, every
/// output evaluated once at each: the swings of every output and the corner each
/// coordinate alone pushes furthest come from these rows.
pub(super) struct OneAtATime {
    /// Per row, its coordinate and the index of the corner it takes.
    moves: Vec<(usize, usize)>,
    /// Row-major outputs of the rows.
    values: Vec<f64>,
    /// Outputs per row.
    n_out: usize,
}

impl OneAtATime {
    /// Evaluates the rows.
    pub fn of(evaluator: &mut Evaluator, tolerance_box: &ToleranceBox) -> OneAtATime {
        let mut rows = Vec::new();
        let mut moves = Vec::new();
        for (k, coordinate) in tolerance_box.coordinates.iter().enumerate() {
            for (j, vertex) in coordinate.vertices.iter().enumerate() {
                let mut row = tolerance_box.centre.clone();
                coordinate.set(&mut row, vertex);
                rows.extend(row);
                moves.push((k, j));
            }
        }
        OneAtATime {
            moves,
            values: evaluator.outputs(rows),
            n_out: evaluator.scenario.outputs.len(),
        }
    }

    /// Per coordinate, the output's largest change |f − f(m)| with that coordinate alone
    /// at a corner: its swing, an influence that needs no derivative (a centre where the
    /// output is flat, as the nominal RV-20E's lost motion in its pins, has a zero gradient
    /// but not a zero swing).
    pub fn swings(&self, nominal: &[f64], output: usize, coordinates: usize) -> Vec<f64> {
        let mut swing = vec![0.0f64; coordinates];
        for (r, &(k, _)) in self.moves.iter().enumerate() {
            let change = (self.values[r * self.n_out + output] - nominal[output]).abs();
            if change.is_finite() {
                swing[k] = swing[k].max(change);
            }
        }
        swing
    }

    /// The corner where each coordinate sits at the vertex that alone moves `output`
    /// furthest in direction `sign` (the first among equals, a vertex without a finite
    /// value last).
    pub fn corner(&self, tolerance_box: &ToleranceBox, output: usize, sign: f64) -> Vec<f64> {
        let score = |r: usize| match self.values[r * self.n_out + output] {
            v if v.is_finite() => sign * v,
            _ => f64::NEG_INFINITY,
        };
        let mut best: Vec<Option<usize>> = vec![None; tolerance_box.coordinates.len()];
        for (r, &(k, _)) in self.moves.iter().enumerate() {
            if best[k].is_none_or(|b| score(r) > score(b)) {
                best[k] = Some(r);
            }
        }
        let mut row = tolerance_box.centre.clone();
        for (k, r) in best.iter().enumerate() {
            if let Some(r) = r {
                let coordinate = &tolerance_box.coordinates[k];
                coordinate.set(&mut row, &coordinate.vertices[self.moves[*r].1]);
            }
        }
        row
    }
}

/// Per output of `outputs`, [lowest, highest] of the corners [`OneAtATime::corner`]
/// gives (evaluated in one batch): a start for the search beside the gradients' corners,
/// which a flat centre leaves uninformed; `None` where the corner has no finite value.
pub(super) fn swing_corners(
    evaluator: &mut Evaluator,
    tolerance_box: &ToleranceBox,
    one: &OneAtATime,
    outputs: &[usize],
) -> Vec<[Option<Found>; 2]> {
    let rows: Vec<Vec<f64>> = (outputs.iter())
        .flat_map(|&o| [-1.0, 1.0].map(|sign| one.corner(tolerance_box, o, sign)))
        .collect();
    let values = evaluator.outputs(rows.concat());
    let n_out = evaluator.scenario.outputs.len();
    (outputs.iter().enumerate())
        .map(|(i, &o)| {
            [0, 1].map(|d| {
                let r = 2 * i + d;
                let value = values[r * n_out + o];
                value.is_finite().then(|| Found {
                    row: rows[r].clone(),
                    value,
                })
            })
        })
        .collect()
}

/// The coordinate search from `start` for output `output` in direction `sign` (+1 the
/// maximum, −1 the minimum) over the leading coordinates by swing and |g|·T.
pub(super) fn improve(
    evaluator: &mut Evaluator,
    tolerance_box: &ToleranceBox,
    (gradient, swing): (&[f64], &[f64]),
    output: usize,
    sign: f64,
    start: Found,
) -> Found {
    let searched = leading_coordinates(tolerance_box, gradient, swing);
    let n_out = evaluator.scenario.outputs.len();
    let mut best = start;
    for _ in 0..MOST_ROUNDS {
        let mut candidates: Vec<Vec<f64>> = Vec::new();
        for &k in &searched {
            let coordinate = &tolerance_box.coordinates[k];
            for level in &coordinate.levels {
                if !coordinate.holds(&best.row, level) {
                    let mut row = best.row.clone();
                    coordinate.set(&mut row, level);
                    candidates.push(row);
                }
            }
        }
        let values = evaluator.outputs(candidates.concat());
        let margin = 1e-12 * best.value.abs().max(f64::MIN_POSITIVE);
        let mut chosen = None;
        let mut target = sign * best.value + margin;
        for (r, _) in candidates.iter().enumerate() {
            let value = values[r * n_out + output];
            if value.is_finite() && sign * value > target {
                (chosen, target) = (Some(r), sign * value);
            }
        }
        let Some(r) = chosen else { break };
        best = Found {
            value: values[r * n_out + output],
            row: candidates.swap_remove(r),
        };
    }
    best
}

/// The coordinates the search moves: the first [`MOST_SEARCHED`] by decreasing
/// influence, the larger of the swing and Σ|g_c|·T_c over their columns (scenario order
/// among equals). A coordinate with neither stays in while there is room: no change from
/// the centre does not make it idle elsewhere in the box.
fn leading_coordinates(
    tolerance_box: &ToleranceBox,
    gradient: &[f64],
    swing: &[f64],
) -> Vec<usize> {
    let weight = |k: usize| -> f64 {
        let linear: f64 = (tolerance_box.coordinates[k].columns.iter())
            .map(|&c| (gradient[c] * tolerance_box.half_width[c]).abs())
            .sum();
        linear.max(swing[k])
    };
    let mut order: Vec<usize> = (0..tolerance_box.coordinates.len()).collect();
    order.sort_by(|&a, &b| weight(b).total_cmp(&weight(a)).then(a.cmp(&b)));
    order.truncate(MOST_SEARCHED);
    order
}
