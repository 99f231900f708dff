//! Worst case, RSS and the contributor table of each continuous output, over the
//! scenario's tolerance box ([`tolerance_box`]), to stand beside the Monte Carlo run:
//!
//! - the **nominal** value y₀ = f(m) at the box's centre m (every input at the middle of
//!   its tolerance interval [m − T, m + T]);
//! - the **sensitivities** g = ∂f/∂x at m by central differences, h = 10⁻⁴·T per column;
//! - the **arithmetic stack** y₀ ± Σ|g_c|·T_c (the linear worst case);
//! - the **RSS stack** y₀ ± √(Σ_cd g_c·T_c·ρ_cd·g_d·T_d): each tolerance read as ±3σ, ρ
//!   the scenario's correlation (0 between independent inputs), the classic
//!   root-sum-square;
//! - the **worst case** of the model itself over the box ([`search`]): every corner when
//!   there are at most 4,096, else the gradient's corners, then a coordinate search
//!   that may find an extreme inside the box;
//! - the **contributor table**: per random column its tolerance, sensitivity, share of
//!   the arithmetic stack |g_c|·T_c/Σ|g|·T and of the RSS variance
//!   g_c·T_c·(ρ·g·T)_c/RSS² (Euler's allocation: the shares sum to 100 %, a correlated
//!   input's can be negative), and its swing: the output's largest change when that input
//!   alone goes to a limit of its tolerance (no derivative: it sees an input the centre is
//!   flat in);
//! - the **linearity check**: R² = 1 − Σ(f − f_lin)²/Σ(f − f̄)² of the linearisation
//!   f_lin(x) = y₀ + g·(x − m) over [`LINEARITY_ROWS`] rows drawn from the scenario's own
//!   law (streams 2⁶¹ + k of the seed); below [`POOR_LINEARITY`] the RSS and arithmetic
//!   figures are flagged as unreliable.
//!
//! Deterministic for a seed, whatever the thread count (fixed rows in a fixed order).

pub mod report;
mod search;
mod tolerance_box;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rvtol_engine::chunk::CHUNK_SIZE;
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_models::ConditionEffect;

use search::{corner_extremes, improve, swing_corners, Evaluator, Found, OneAtATime};
pub use search::{MOST_ROUNDS, MOST_SEARCHED, MOST_VERTICES};
use tolerance_box::ToleranceBox;

/// Rows of the linearity check.
pub const LINEARITY_ROWS: usize = CHUNK_SIZE;
/// R² of the linearisation below which the linear figures are flagged.
pub const POOR_LINEARITY: f64 = 0.9;
/// The linearity rows' streams: 2⁶¹ + k (the screening's are 2⁶⁰ + k, the run's k).
const LINEARITY_STREAM_BASE: u64 = 1 << 61;
/// Central-difference step as a fraction of a column's half tolerance.
const STEP: f64 = 1e-4;

/// What the stack analysis is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct StackSettings {
    /// Seed of the linearity rows.
    pub seed: u64,
    /// The continuous outputs to analyse (indices among the scenario's outputs).
    pub outputs: Vec<usize>,
    /// The share of rows (of the linearity rows, and of the Monte Carlo run beside) an
    /// output may be non-finite in without an error (`--max-non-finite`, as a run's).
    pub max_non_finite: f64,
}

/// One random column's part in one output's stack.
#[derive(Debug, Clone, PartialEq)]
pub struct Contributor {
    /// The column (index among the scenario's columns).
    pub column: usize,
    /// ∂f/∂x at the centre.
    pub sensitivity: f64,
    /// |g|·T over the arithmetic stack.
    pub worst_case_share: f64,
    /// Its share of the RSS variance (Euler).
    pub rss_share: f64,
    /// The output's largest change when this input alone (with its Eq. 11 partner) goes
    /// to a corner of its tolerance, the others at the centre.
    pub swing: f64,
}

/// One end of the worst case.
#[derive(Debug, Clone, PartialEq)]
pub struct Extreme {
    /// The output's value.
    pub value: f64,
    /// The input row where it is reached.
    pub row: Vec<f64>,
    /// Whether the output's indicator flags the sample there (a preloaded stage's lost
    /// motion: non-conforming whatever the value).
    pub flagged: bool,
    /// Whether the coordinate search went beyond the corners (an extreme inside the box).
    pub inside: bool,
}

/// The stack of one output.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputStack {
    /// The output (index among the scenario's outputs).
    pub output: usize,
    /// Its value at the centre of the box.
    pub nominal: f64,
    /// Whether its indicator flags the centre.
    pub nominal_flagged: bool,
    /// Σ|g|·T.
    pub arithmetic: f64,
    /// √(Σ g·T·ρ·g·T).
    pub rss: f64,
    /// [lowest, highest] found over the box; `None` where no point tried has a value.
    pub worst_case: [Option<Extreme>; 2],
    /// R² of the linearisation over the scenario's law; `None` when the rows' values do
    /// not vary or none is finite.
    pub r_squared: Option<f64>,
    /// Per random column, in column order.
    pub contributors: Vec<Contributor>,
}

/// The stacks of the asked outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct Stack {
    /// Corners of the box (a float: 2²⁰⁰ of them are a number too).
    pub corners: f64,
    /// Whether every corner was evaluated.
    pub all_corners: bool,
    /// Model evaluations (rows), the linearity rows included.
    pub evaluations: u64,
    /// Per asked output, in the asked order.
    pub outputs: Vec<OutputStack>,
}

/// The worst case, RSS and contributors of `settings.outputs` over the scenario's
/// tolerance box (uses the current rayon pool for the model evaluations).
pub fn stack(scenario: &Scenario, settings: &StackSettings) -> Result<Stack, ScenarioError> {
    let tolerance_box = ToleranceBox::of(scenario)?;
    let mut evaluator = Evaluator {
        scenario,
        evaluations: 0,
    };
    // The gradients of every continuous output (the same rows): each one's corners are
    // starts for every asked output, so an output's figures do not depend on which others
    // are asked.
    let continuous = scenario.continuous_outputs();
    let (nominal, every_gradient) =
        centre_and_gradients(&mut evaluator, &tolerance_box, &continuous);
    let gradients: Vec<Vec<f64>> = (settings.outputs.iter())
        .map(|o| {
            every_gradient[continuous.iter().position(|c| c == o).expect("continuous")].clone()
        })
        .collect();
    let (corners, all_corners) = corner_extremes(
        &mut evaluator,
        &tolerance_box,
        &every_gradient,
        &settings.outputs,
    );
    let one = OneAtATime::of(&mut evaluator, &tolerance_box);
    let swing: Vec<Vec<f64>> = (settings.outputs.iter())
        .map(|&o| one.swings(&nominal, o, tolerance_box.coordinates.len()))
        .collect();
    let swung = swing_corners(&mut evaluator, &tolerance_box, &one, &settings.outputs);
    let found: Vec<[Option<(Found, bool)>; 2]> = (settings.outputs.iter().enumerate())
        .zip(corners.into_iter().zip(swung))
        .map(|((i, &o), ([low, high], [swung_low, swung_high]))| {
            let influence = (gradients[i].as_slice(), swing[i].as_slice());
            [(low, swung_low, -1.0), (high, swung_high, 1.0)].map(|(end, swung, sign)| {
                let centre = (nominal[o].is_finite()).then(|| Found {
                    row: tolerance_box.centre.clone(),
                    value: nominal[o],
                });
                let starts = [end, swung, centre];
                let best = (starts.into_iter().flatten())
                    .map(|start| improve(&mut evaluator, &tolerance_box, influence, o, sign, start))
                    .reduce(|a, b| {
                        if sign * b.value > sign * a.value {
                            b
                        } else {
                            a
                        }
                    });
                best.map(|best| {
                    let inside = !tolerance_box.is_corner(&best.row);
                    (best, inside)
                })
            })
        })
        .collect();
    let r_squared = linearity(
        &mut evaluator,
        &tolerance_box,
        settings,
        &nominal,
        &gradients,
    )?;
    let flags = flags_at(&mut evaluator, &tolerance_box, settings, &found);
    let outputs = (settings.outputs.iter().enumerate())
        .zip(found)
        .map(|((i, &o), ends)| {
            let mut column_swing = vec![0.0; tolerance_box.centre.len()];
            for (k, coordinate) in tolerance_box.coordinates.iter().enumerate() {
                coordinate
                    .columns
                    .iter()
                    .for_each(|&c| column_swing[c] = swing[i][k]);
            }
            let (arithmetic, rss, contributors) =
                contributions(scenario, &tolerance_box, &gradients[i], &column_swing);
            let [centre_flag, low_flag, high_flag] = flags[i];
            OutputStack {
                output: o,
                nominal: nominal[o],
                nominal_flagged: centre_flag,
                arithmetic,
                rss,
                worst_case: [(ends[0].clone(), low_flag), (ends[1].clone(), high_flag)].map(
                    |(end, flagged)| {
                        end.map(|(best, inside)| Extreme {
                            value: best.value,
                            row: best.row,
                            flagged,
                            inside,
                        })
                    },
                ),
                r_squared: r_squared[i],
                contributors,
            }
        })
        .collect();
    Ok(Stack {
        corners: tolerance_box.corners(),
        all_corners,
        evaluations: evaluator.evaluations,
        outputs,
    })
}

/// Every output at the centre, and per output of `outputs` the gradient over the columns
/// (0 for a column that does not vary).
fn centre_and_gradients(
    evaluator: &mut Evaluator,
    tolerance_box: &ToleranceBox,
    outputs: &[usize],
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n_columns = tolerance_box.centre.len();
    let varying: Vec<usize> = (0..n_columns)
        .filter(|&c| tolerance_box.half_width[c] > 0.0)
        .collect();
    let mut rows = tolerance_box.centre.clone();
    for &c in &varying {
        for sign in [1.0, -1.0] {
            let mut row = tolerance_box.centre.clone();
            row[c] += sign * STEP * tolerance_box.half_width[c];
            rows.extend(row);
        }
    }
    let values = evaluator.outputs(rows);
    let n_out = evaluator.scenario.outputs.len();
    let nominal = values[..n_out].to_vec();
    let gradients = (outputs.iter())
        .map(|&o| {
            let mut g = vec![0.0; n_columns];
            for (k, &c) in varying.iter().enumerate() {
                let (plus, minus) = (
                    values[(1 + 2 * k) * n_out + o],
                    values[(2 + 2 * k) * n_out + o],
                );
                g[c] = (plus - minus) / (2.0 * STEP * tolerance_box.half_width[c]);
            }
            g
        })
        .collect();
    (nominal, gradients)
}

/// The arithmetic and RSS half widths and the contributors of one output (`swing` per
/// column: its coordinate's).
fn contributions(
    scenario: &Scenario,
    tolerance_box: &ToleranceBox,
    gradient: &[f64],
    swing: &[f64],
) -> (f64, f64, Vec<Contributor>) {
    let space = &scenario.input_space;
    let columns: Vec<usize> = (0..gradient.len())
        .filter(|&c| tolerance_box.half_width[c] > 0.0)
        .collect();
    let a: Vec<f64> = (columns.iter())
        .map(|&c| gradient[c] * tolerance_box.half_width[c])
        .collect();
    let correlation = |c: usize, d: usize| {
        if c == d {
            return 1.0;
        }
        let covariance = space.covariance(c, d);
        match covariance {
            0.0 => 0.0,
            _ => covariance / (space.covariance(c, c) * space.covariance(d, d)).sqrt(),
        }
    };
    let rho_a: Vec<f64> = (columns.iter())
        .map(|&c| {
            (columns.iter().zip(&a))
                .map(|(&d, ad)| correlation(c, d) * ad)
                .sum()
        })
        .collect();
    let arithmetic: f64 = a.iter().map(|x| x.abs()).sum();
    let variance: f64 = a.iter().zip(&rho_a).map(|(x, y)| x * y).sum();
    let share = |x: f64, total: f64| if total > 0.0 { x / total } else { 0.0 };
    let contributors = (columns.iter().enumerate())
        .map(|(k, &c)| Contributor {
            column: c,
            sensitivity: gradient[c],
            worst_case_share: share(a[k].abs(), arithmetic),
            rss_share: share(a[k] * rho_a[k], variance),
            swing: swing[c],
        })
        .collect();
    (arithmetic, variance.max(0.0).sqrt(), contributors)
}

/// Per asked output, R² of its linearisation over rows of the scenario's law.
fn linearity(
    evaluator: &mut Evaluator,
    tolerance_box: &ToleranceBox,
    settings: &StackSettings,
    nominal: &[f64],
    gradients: &[Vec<f64>],
) -> Result<Vec<Option<f64>>, ScenarioError> {
    let space = &evaluator.scenario.input_space;
    let n_columns = space.n_columns();
    let mut rows = vec![0.0; LINEARITY_ROWS * n_columns];
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    rng.set_stream(LINEARITY_STREAM_BASE);
    space.sample_rows(&mut rng, &mut rows, &mut space.new_constraint_counts())?;
    let values = evaluator.outputs(rows.clone());
    let scenario = evaluator.scenario;
    let n_out = scenario.outputs.len();
    for &o in &settings.outputs {
        // An excluded sample (its qualifying indicator set) has no value by design.
        let excluded = |r: usize| match scenario.outputs[o].condition {
            Some((k, ConditionEffect::Excluded)) => {
                let flag = values[r * n_out + k];
                flag.is_finite() && flag != 0.0
            }
            _ => false,
        };
        let failed = (0..LINEARITY_ROWS)
            .filter(|&r| !values[r * n_out + o].is_finite() && !excluded(r))
            .count();
        if failed as f64 > settings.max_non_finite * LINEARITY_ROWS as f64 {
            return Err(ScenarioError::new(
                scenario.model_of_output(o),
                format!(
                    "{} is not finite in {failed} of the {LINEARITY_ROWS} rows of the scenario's law the stack draws for R² (more than the {} % allowed, --max-non-finite): the model cannot evaluate part of the scenario",
                    scenario.outputs[o].name,
                    rvtol_deviation::Shown(100.0 * settings.max_non_finite)
                ),
            ));
        }
    }
    Ok((settings.outputs.iter().zip(gradients))
        .map(|(&o, g)| {
            let pairs: Vec<(f64, f64)> = (rows.chunks_exact(n_columns).enumerate())
                .map(|(r, row)| {
                    let linear: f64 = (row.iter().zip(&tolerance_box.centre).zip(g))
                        .map(|((x, m), g)| g * (x - m))
                        .sum();
                    (values[r * n_out + o], nominal[o] + linear)
                })
                .filter(|(f, _)| f.is_finite())
                .collect();
            let n = pairs.len() as f64;
            let mean = pairs.iter().map(|(f, _)| f).sum::<f64>() / n;
            let total: f64 = pairs.iter().map(|(f, _)| (f - mean).powi(2)).sum();
            let residual: f64 = pairs.iter().map(|(f, l)| (f - l).powi(2)).sum();
            (total > 0.0 && residual.is_finite()).then(|| 1.0 - residual / total)
        })
        .collect())
}

/// Per asked output, whether its indicator flags [the centre, the lowest end, the
/// highest end].
fn flags_at(
    evaluator: &mut Evaluator,
    tolerance_box: &ToleranceBox,
    settings: &StackSettings,
    found: &[[Option<(Found, bool)>; 2]],
) -> Vec<[bool; 3]> {
    let mut rows = tolerance_box.centre.clone();
    for ends in found {
        for end in ends {
            let row = end.as_ref().map_or(&tolerance_box.centre, |(f, _)| &f.row);
            rows.extend(row);
        }
    }
    let values = evaluator.outputs(rows);
    let scenario = evaluator.scenario;
    let n_out = scenario.outputs.len();
    (settings.outputs.iter().enumerate())
        .map(|(i, &o)| {
            let flag = |r: usize| match scenario.outputs[o].condition {
                Some((indicator, ConditionEffect::NonConforming)) => {
                    values[r * n_out + indicator] != 0.0
                }
                _ => false,
            };
            [flag(0), flag(1 + 2 * i), flag(2 + 2 * i)]
        })
        .collect()
}
