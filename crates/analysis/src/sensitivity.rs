//! Variance-based sensitivity of every continuous output to the scenario's error sources:
//! Sobol' first-order and total indices with confidence intervals (bootstrap, or from the
//! replicates of a Latin hypercube or scrambled Sobol' design). The same estimators rank
//! the failures ([`Analysed`]): for every output with spec limits, the indicator of a
//! sample that does not conform (1, else 0: the run's out-of-spec rule sample by sample,
//! [`rvtol_engine::run::sample_out_of_spec`]), and every indicator output (a preload, an
//! interference). The Sobol' indices of a 0/1 quantity Y with P(Y = 1) = p apportion its
//! variance p(1 − p): S_g = Var E[Y | X_g]/(p(1 − p)) is how much knowing group g alone
//! tells whether an assembly fails, and S_Tg the share that involves g at all; the model
//! evaluations are the same, no run is added.
//!
//! Estimators, from two independent sample matrices A and B of N rows and, per group g,
//! the matrices A_B^(g) (A with g's columns taken from B) and B_A^(g) (the converse):
//!
//! ```text
//! V    = variance of the 2N values f(A), f(B)
//! S_g  = ½·[ (1/N)·Σ f(B)·(f(A_B^(g)) − f(A)) + (1/N)·Σ f(A)·(f(B_A^(g)) − f(B)) ] / V
//!                                                              (Saltelli et al. 2010, Table 2 b)
//! ST_g = ½·[ (1/2N)·Σ (f(A) − f(A_B^(g)))² + (1/2N)·Σ (f(B) − f(B_A^(g)))² ] / V
//!                                                  (Jansen 1999; Saltelli et al. 2010, Table 2 f)
//! ```
//!
//! Each bracket is the published estimator on one of the two symmetric designs; their mean
//! uses both and has a smaller variance. Every value is first centred on the mean of f(A)
//! and f(B). N·(2G + 2) model evaluations. Sobol' indices need independent inputs, so the groups are
//! the error sources (a part's six correlated components form one group) merged wherever
//! the scenario correlates two of them. Intervals: percentile bootstrap over the N rows
//! (Archer, Saltelli & Sobol' 1997), resample b drawn from its own stream, while the
//! N·(2G + 2) values per output fit the row-bootstrap limit; beyond it, a bootstrap over
//! blocks of consecutive rows whose sums alone are kept (bounded memory at any N; see
//! [`IntervalMethod`]). The row bootstrap never reads rows at random: each row's 2G + 2
//! estimator terms are stored contiguously, and a resample is the multinomial count of
//! every row, drawn block by block (conditional binomials split the N picks among blocks
//! of rows that stay in cache, uniform picks place them within a block) and summed in one
//! sequential pass per block for all resamples ([`row_resamples`]).
//!
//! **Replicated designs** (`"sampling": "lhs" | "rqmc"`, [`IntervalMethod::Replicates`]):
//! A and B are the two halves of one randomized point in 2D dimensions (D the uniforms a
//! row takes, [`InputSpace::quasi_dimensions`]): row i of A is point i's dimensions
//! 0 … D − 1 and row i of B its dimensions D … 2D − 1, turned into rows by the inverse
//! CDFs of the run's quasi path (the design of Saltelli et al. 2010: A and B the left and
//! right halves of one quasi-random sample of dimension 2k). Each point of a scrambled
//! Sobol' or Latin hypercube design is uniform on (0, 1)^2D, so row i of A and row i of B
//! are independent and the estimators above keep their expectations; the design's balance
//! makes their error shrink faster than N^−1/2 for smooth models. The rows of one design
//! are not independent, so no bootstrap over them: the N base samples are R independent
//! randomizations of N/R points, the index is the estimator over all N rows, and its
//! interval is ± t(R − 1)·s/√R, s the standard deviation of the R replicates' own
//! estimates (the randomized-QMC interval: Owen, *Monte Carlo theory, methods and
//! examples*, ch. 17). Values are centred on the mean of f over [`CHUNK_SIZE`] Monte Carlo
//! rows of a stream of their own (so that the replicates stay independent of one another).
//!
//! [`InputSpace::quasi_dimensions`]: rvtol_deviation::InputSpace::quasi_dimensions
//!
//! Reproducibility: chunk k of A and B draws from `ChaCha8Rng::seed_from_u64(seed)` with
//! streams 2k and 2k + 1 (Monte Carlo), or is points of its replicate (replicates laid out
//! one after another in chunks, as a run's: [`Sampling::chunk_rows`]); chunks are collected
//! in order and every sum runs sequentially, so the result does not depend on the thread
//! count. The analysis is the merge of partials of chunk ranges ([`sobol_chunks`],
//! [`merge_sobol`]): a shard computes the model values of its chunks, the merge the
//! indices and the bootstrap, so the result does not depend on the shard count either.

use std::ops::Range;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Binomial, Distribution};
use rayon::prelude::*;

use rvtol_deviation::{PointSet, SamplerScratch};

use rvtol_engine::chunk::{Sampling, CHUNK_SIZE};
use rvtol_engine::evaluate::ChunkEvaluator;
use rvtol_engine::scenario::{InputGroup, Scenario, ScenarioError};
use rvtol_engine::stats::{replicate_standard_error, student_t_quantile};
use rvtol_engine::{FoldError, MergeError};

/// First bootstrap stream (far above the 2k, 2k + 1 streams of the sample matrices).
const BOOTSTRAP_STREAM_BASE: u64 = 1 << 62;
/// Stream of the Monte Carlo rows that centre a replicated design's values (apart from
/// the matrices' and the bootstrap's streams).
const CENTRE_STREAM: u64 = 1 << 61;

/// Default most model values (N·(2G + 2) per continuous output) kept for the row
/// bootstrap (800 MB); beyond it the intervals come from the block bootstrap.
pub const DEFAULT_ROW_BOOTSTRAP_LIMIT: u64 = 100_000_000;
/// Most blocks of the block bootstrap: the block length is the smallest power of two of at
/// least 64 rows that keeps their number at or below this (and at most a chunk).
const MAX_BOOTSTRAP_BLOCKS: u64 = 65_536;

/// What to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensitivitySettings {
    /// Base samples N (rows of A and of B).
    pub base_samples: u64,
    /// Seed.
    pub seed: u64,
    /// Bootstrap resamples for the intervals.
    pub bootstrap: usize,
    /// Confidence of the intervals (0.95).
    pub confidence: f64,
    /// Most model values kept for the row bootstrap; beyond, the block bootstrap
    /// ([`IntervalMethod`]).
    pub row_bootstrap_limit: u64,
    /// How the rows of A and B are drawn: Monte Carlo (bootstrap intervals) or R
    /// replicates of a Latin hypercube or scrambled Sobol' design (intervals from the
    /// replicates, module docs).
    pub sampling: Sampling,
}

/// How the intervals are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntervalMethod {
    /// Every model value is kept and the bootstrap resamples rows (the estimator's own
    /// sampling unit); values centred on the mean of f(A), f(B).
    Rows,
    /// Only the estimator's sums over blocks of consecutive rows are kept (memory grows
    /// with the number of blocks, not of rows) and the bootstrap resamples blocks: the rows
    /// are independent, so block sums are independent and identically distributed (the
    /// last block may be shorter) and their resampled totals give the percentile interval
    /// of the ratio estimators. Values centred on the mean of f(A), f(B) over chunk 0.
    Blocks {
        /// Rows per block.
        rows: u64,
    },
    /// A replicated Latin hypercube or scrambled Sobol' design: per chunk only the
    /// estimator's sums are kept, and the interval is Student's from the spread of the
    /// replicates' estimates (module docs). Values centred on the mean of f over
    /// [`CHUNK_SIZE`] Monte Carlo rows of their own stream.
    Replicates,
}

impl SensitivitySettings {
    /// How an analysis of `scenario` with these settings computes its intervals.
    pub fn interval_method(&self, scenario: &Scenario) -> IntervalMethod {
        if self.sampling.is_replicated() {
            return IntervalMethod::Replicates;
        }
        let variants = 2 * independent_groups(scenario).len() as u64 + 2;
        let values = self
            .base_samples
            .saturating_mul(variants)
            .saturating_mul(analysed_quantities(scenario).len() as u64);
        if values <= self.row_bootstrap_limit {
            IntervalMethod::Rows
        } else {
            let wanted = self.base_samples.div_ceil(MAX_BOOTSTRAP_BLOCKS);
            IntervalMethod::Blocks {
                rows: wanted.next_power_of_two().clamp(64, CHUNK_SIZE as u64),
            }
        }
    }

    /// Number of chunks of A and B ([`Sampling::chunk_count`]).
    pub fn chunk_count(&self) -> u64 {
        self.sampling.chunk_count(self.base_samples)
    }

    /// Base samples in the chunks before `chunk` (for progress).
    pub fn samples_before_chunk(&self, chunk: u64) -> u64 {
        self.sampling.rows_before_chunk(self.base_samples, chunk)
    }
}

/// An estimate with its confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Point estimate from all N rows.
    pub value: f64,
    /// Percentile bootstrap interval, or Student's from the replicates.
    pub interval: [f64; 2],
}

/// The indices of one group for one output.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupIndices {
    /// The group's name.
    pub group: String,
    /// First-order index S.
    pub first_order: Estimate,
    /// Total index ST.
    pub total: Estimate,
}

/// The indices of one output, groups sorted by decreasing total index.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSensitivity {
    /// Output name (for a conformity indicator, the output's name and ` out of spec`).
    pub name: String,
    /// Output unit (`1` for a 0/1 quantity).
    pub unit: String,
    /// What is apportioned.
    pub quantity: Analysed,
    /// Mean of the quantity over the 2N rows of A and B (for a 0/1 quantity, the share of
    /// rows where it is 1).
    pub mean: f64,
    /// Variance V of the output.
    pub variance: f64,
    /// Rows left out because a value was not finite.
    pub non_finite_rows: u64,
    /// One entry per group.
    pub indices: Vec<GroupIndices>,
}

/// A quantity whose variance a sensitivity analysis apportions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Analysed {
    /// A continuous output's value (the scenario's output index).
    Value(usize),
    /// 1 where a sample of the continuous output does not conform to its spec limits, 0
    /// where it does ([`rvtol_engine::run::sample_out_of_spec`]).
    OutOfSpec(usize),
    /// An indicator output's 0/1 value.
    Indicator(usize),
}

impl Analysed {
    /// The scenario output it is computed from.
    pub fn output(self) -> usize {
        match self {
            Analysed::Value(o) | Analysed::OutOfSpec(o) | Analysed::Indicator(o) => o,
        }
    }

    /// Its name in reports: the output's, with ` out of spec` for a conformity indicator.
    pub fn name(self, scenario: &Scenario) -> String {
        let name = &scenario.outputs[self.output()].name;
        match self {
            Analysed::OutOfSpec(_) => format!("{name} out of spec"),
            _ => name.clone(),
        }
    }

    /// Its unit: the output's for a value, `1` for a 0/1 quantity.
    pub fn unit(self, scenario: &Scenario) -> String {
        match self {
            Analysed::Value(o) => scenario.outputs[o].unit.clone(),
            _ => "1".to_string(),
        }
    }

    /// `value`, `out_of_spec` or `indicator`.
    pub fn kind(self) -> &'static str {
        match self {
            Analysed::Value(_) => "value",
            Analysed::OutOfSpec(_) => "out_of_spec",
            Analysed::Indicator(_) => "indicator",
        }
    }

    /// Its values over `m` rows from the evaluated outputs `columns` (`columns[o][row]`).
    fn column(self, scenario: &Scenario, columns: &[Vec<f64>], m: usize) -> Vec<f64> {
        match self {
            Analysed::Value(o) | Analysed::Indicator(o) => columns[o][..m].to_vec(),
            Analysed::OutOfSpec(o) => {
                let flags = scenario.outputs[o].condition.map(|(k, _)| &columns[k][..m]);
                (0..m)
                    .map(|r| {
                        let flag = flags.map_or(0.0, |f| f[r]);
                        let out =
                            rvtol_engine::run::sample_out_of_spec(scenario, o, columns[o][r], flag);
                        f64::from(u8::from(out))
                    })
                    .collect()
            }
        }
    }
}

/// What a sensitivity analysis of `scenario` apportions, in report order: every continuous
/// output's value, then the conformity indicator of each one with spec limits, then every
/// indicator output.
pub fn analysed_quantities(scenario: &Scenario) -> Vec<Analysed> {
    let continuous = scenario.continuous_outputs();
    let values = continuous.iter().map(|&o| Analysed::Value(o));
    let out_of_spec = (continuous.iter())
        .filter(|&&o| scenario.outputs[o].spec.is_some())
        .map(|&o| Analysed::OutOfSpec(o));
    let indicators = (0..scenario.outputs.len())
        .filter(|&o| scenario.outputs[o].kind == rvtol_models::OutputKind::Indicator)
        .map(Analysed::Indicator);
    values.chain(out_of_spec).chain(indicators).collect()
}

/// The scenario's sensitivity groups (its `sensitivity_groups`, then each remaining
/// source) made independent: groups that the scenario correlates are merged (names joined
/// with `+`); groups with no random column are left out.
pub fn independent_groups(scenario: &Scenario) -> Vec<InputGroup> {
    let space = &scenario.input_space;
    let units = &scenario.sensitivity_groups;
    let mut unit_of_column = vec![None; space.n_columns()];
    for (u, unit) in units.iter().enumerate() {
        for &c in &unit.columns {
            unit_of_column[c] = Some(u);
        }
    }
    let mut parent: Vec<usize> = (0..units.len()).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for group in space.correlated_groups() {
        for (i, &ci) in group.iter().enumerate() {
            for &cj in &group[i + 1..] {
                if !space.dependent(ci, cj) {
                    continue;
                }
                if let (Some(a), Some(b)) = (unit_of_column[ci], unit_of_column[cj]) {
                    let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                    if ra != rb {
                        parent[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
        }
    }
    let random_column = |column: usize| space.is_random(column);
    let mut groups: Vec<InputGroup> = Vec::new();
    let mut group_of_root = vec![usize::MAX; units.len()];
    for (s, source) in units.iter().enumerate() {
        if !source.columns.iter().any(|&c| random_column(c)) {
            continue;
        }
        let r = root(&mut parent, s);
        if group_of_root[r] == usize::MAX {
            group_of_root[r] = groups.len();
            groups.push(InputGroup {
                name: source.name.clone(),
                columns: Vec::new(),
            });
        } else {
            let name = &mut groups[group_of_root[r]].name;
            name.push('+');
            name.push_str(&source.name);
        }
        groups[group_of_root[r]].columns.extend(&source.columns);
    }
    groups
}

/// Model values of one chunk: `values[quantity][variant][row]` over the analysed quantities,
/// variant 0 = A, 1 = B, 2 + g = A_B^(g), 2 + G + g = B_A^(g).
pub type ChunkValues = Vec<Vec<Vec<f64>>>;

/// Per analysed quantity: the estimator's sums over each block of a chunk, and the chunk's
/// rows left out because a value was not finite.
pub type ChunkBlocks = Vec<(Vec<BlockSums>, u64)>;

/// The model values of chunk `chunk`; its 2G + 2 matrices side by side when `side_by_side`
/// (fewer chunks in flight than threads), else one after the other on the calling thread.
fn evaluate_chunk(
    scenario: &Scenario,
    plan: &SobolPlan,
    settings: SensitivitySettings,
    chunk: u64,
    side_by_side: bool,
) -> Result<ChunkValues, ScenarioError> {
    let (groups, analysed) = (&plan.groups, &plan.analysed);
    let (replicate, first_row, _, m) = settings.sampling.chunk_rows(settings.base_samples, chunk);
    let space = &scenario.input_space;
    let n_columns = space.n_columns();
    let mut counts = space.new_constraint_counts();
    let mut scratch = SamplerScratch::default();
    // Column-major matrices (`a[c·m + r]` is column c of row r), as the models take them.
    let mut a = vec![0.0; m * n_columns];
    let mut b = vec![0.0; m * n_columns];
    match &plan.points {
        None => {
            for (matrix, stream) in [(&mut a, 2 * chunk), (&mut b, 2 * chunk + 1)] {
                let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
                rng.set_stream(stream);
                space.sample_columns_with(&mut rng, matrix, &mut counts, &mut scratch)?;
            }
        }
        Some(points) => {
            let dims = points.dims() / 2;
            for (matrix, first_dim) in [(&mut a, 0), (&mut b, dims)] {
                space.sample_columns_from_point_dims(
                    points,
                    first_dim,
                    replicate,
                    first_row,
                    matrix,
                    &mut scratch,
                )?;
            }
        }
    }
    // The 2G + 2 matrices (A, B, A with group g's columns from B, B with them from A), side
    // by side where the chunks alone leave threads idle (a run of fewer base samples than a
    // chunk is one chunk; a matrix's values do not depend on the thread that evaluates it).
    // Otherwise in one job, so that a thread holds one chunk's matrices at a time, as the
    // memory estimate counts them (`request::memory::sensitivity`).
    let n_groups = groups.len();
    let variants = 2 * n_groups + 2;
    let per_variant: Vec<Vec<Vec<f64>>> = (0..variants)
        .into_par_iter()
        .with_min_len(if side_by_side { 1 } else { variants })
        .map_init(
            || (ChunkEvaluator::new(scenario), Vec::new()),
            |(evaluator, mixed), variant| {
                let matrix: &[f64] = match variant {
                    0 => &a,
                    1 => &b,
                    _ => {
                        let g = (variant - 2) % n_groups;
                        let (base, donor) = if variant - 2 < n_groups {
                            (&a, &b)
                        } else {
                            (&b, &a)
                        };
                        mixed.clear();
                        mixed.extend_from_slice(base);
                        for &c in &groups[g].columns {
                            mixed[c * m..(c + 1) * m].copy_from_slice(&donor[c * m..(c + 1) * m]);
                        }
                        mixed
                    }
                };
                evaluator.evaluate_columns_at(matrix, m, 0);
                (analysed.iter())
                    .map(|a| a.column(scenario, &evaluator.output_columns, m))
                    .collect()
            },
        )
        .collect();
    let mut values: ChunkValues = vec![Vec::with_capacity(variants); analysed.len()];
    for variant in per_variant {
        for (slot, column) in variant.into_iter().enumerate() {
            values[slot].push(column);
        }
    }
    Ok(values)
}

/// The mean of the finite values (0 when none is): the centre of block sums.
fn finite_mean<'a>(values: impl Iterator<Item = &'a f64>) -> f64 {
    let finite: Vec<f64> = values.copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        0.0
    } else {
        rvtol_engine::stats::Moments::from_slice(&finite).mean
    }
}

/// The centres of a replicated design ([`IntervalMethod::Replicates`]): the mean of f over
/// [`CHUNK_SIZE`] Monte Carlo rows drawn from [`CENTRE_STREAM`], independent of every
/// replicate.
fn replicate_centres(
    scenario: &Scenario,
    plan: &SobolPlan,
    seed: u64,
) -> Result<Vec<f64>, ScenarioError> {
    let space = &scenario.input_space;
    let mut rows = vec![0.0; CHUNK_SIZE * space.n_columns()];
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(CENTRE_STREAM);
    space.sample_columns_with(
        &mut rng,
        &mut rows,
        &mut space.new_constraint_counts(),
        &mut SamplerScratch::default(),
    )?;
    let mut evaluator = ChunkEvaluator::new(scenario);
    evaluator.evaluate_columns_at(&rows, CHUNK_SIZE, 0);
    Ok(plan
        .analysed
        .iter()
        .map(|a| {
            finite_mean(
                a.column(scenario, &evaluator.output_columns, CHUNK_SIZE)
                    .iter(),
            )
        })
        .collect())
}

/// The estimator's 2G + 2 terms of row `r` of `f[variant][row]`, values less `centre`:
/// f_A + f_B, f_A² + f_B², then per group f_B·(f_AB − f_A) + f_A·(f_BA − f_B) (first
/// order) and (f_A − f_AB)² + (f_B − f_BA)² (total). Their sums over rows are
/// [`BlockSums`].
fn row_terms(f: &[Vec<f64>], r: usize, centre: f64, out: &mut [f64]) {
    let n_groups = (f.len() - 2) / 2;
    let (fa, fb) = (f[0][r] - centre, f[1][r] - centre);
    out[0] = fa + fb;
    out[1] = fa * fa + fb * fb;
    for g in 0..n_groups {
        let fab = f[2 + g][r] - centre;
        let fba = f[2 + n_groups + g][r] - centre;
        out[2 + g] = fb * (fab - fa) + fa * (fba - fb);
        out[2 + n_groups + g] = (fa - fab) * (fa - fab) + (fb - fba) * (fb - fba);
    }
}

/// The estimator's sums over a set of rows, for one output: enough to give the indices
/// ([`BlockSums::indices`]) and to be added block by block.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockSums {
    /// Rows summed.
    pub rows: u64,
    /// Σ f(A) + f(B).
    pub sum: f64,
    /// Σ f(A)² + f(B)².
    pub sum_squares: f64,
    /// Σ f(B)·(f(A_B) − f(A)) + f(A)·(f(B_A) − f(B)) per group.
    pub first: Vec<f64>,
    /// Σ (f(A) − f(A_B))² + (f(B) − f(B_A))² per group.
    pub total: Vec<f64>,
}

impl BlockSums {
    fn new(n_groups: usize) -> BlockSums {
        BlockSums {
            rows: 0,
            sum: 0.0,
            sum_squares: 0.0,
            first: vec![0.0; n_groups],
            total: vec![0.0; n_groups],
        }
    }

    fn add(&mut self, other: &BlockSums) {
        self.rows += other.rows;
        self.sum += other.sum;
        self.sum_squares += other.sum_squares;
        for (a, b) in self.first.iter_mut().zip(&other.first) {
            *a += b;
        }
        for (a, b) in self.total.iter_mut().zip(&other.total) {
            *a += b;
        }
    }

    /// Adds one row's terms ([`row_terms`]).
    fn add_terms(&mut self, terms: &[f64]) {
        let n_groups = self.first.len();
        self.rows += 1;
        self.sum += terms[0];
        self.sum_squares += terms[1];
        for (s, t) in self.first.iter_mut().zip(&terms[2..2 + n_groups]) {
            *s += t;
        }
        for (s, t) in self.total.iter_mut().zip(&terms[2 + n_groups..]) {
            *s += t;
        }
    }

    /// Adds row `r` of `f[variant][row]` (values centred on `centre`) when all its values
    /// are finite; returns whether it did. `terms` is scratch of 2G + 2.
    fn add_row(&mut self, f: &[Vec<f64>], r: usize, centre: f64, terms: &mut [f64]) -> bool {
        if !f.iter().all(|v| v[r].is_finite()) {
            return false;
        }
        row_terms(f, r, centre, terms);
        self.add_terms(terms);
        true
    }

    /// The first-order and total indices ([`BlockSums::indices`] without the variance).
    fn first_and_total(&self) -> (Vec<f64>, Vec<f64>) {
        let (_, first, total) = self.indices();
        (first, total)
    }

    /// The mean of the values these sums were taken of, centred on `centre`.
    fn mean(&self, centre: f64) -> f64 {
        centre + self.sum / (2.0 * self.rows as f64)
    }

    /// (variance V of the 2·rows values f_A, f_B, first-order indices, total indices):
    /// V = (Σ(f_A² + f_B²)/2n − mean²)·2n/(2n − 1), S_g = first_g/(2n)/V, ST_g =
    /// total_g/(4n)/V (module docs).
    fn indices(&self) -> (f64, Vec<f64>, Vec<f64>) {
        let nf = self.rows as f64;
        let mean = self.sum / (2.0 * nf);
        let variance =
            (self.sum_squares / (2.0 * nf) - mean * mean) * (2.0 * nf) / (2.0 * nf - 1.0);
        (
            variance,
            self.first
                .iter()
                .map(|s| s / (2.0 * nf) / variance)
                .collect(),
            self.total
                .iter()
                .map(|s| s / (4.0 * nf) / variance)
                .collect(),
        )
    }
}

/// The model values a range of chunks contributes to the indices.
#[derive(Debug, Clone, PartialEq)]
pub enum SobolChunks {
    /// Every value of each chunk (the row bootstrap).
    Rows(Vec<ChunkValues>),
    /// The block sums of each chunk, the values centred on `centres` (per continuous
    /// output): the block bootstrap (centred on the mean of f(A), f(B) over chunk 0), or a
    /// replicated design (one block per chunk, [`IntervalMethod::Replicates`]).
    Blocks {
        /// Centre per continuous output.
        centres: Vec<f64>,
        /// Per chunk, per continuous output, the sums of its blocks.
        chunks: Vec<ChunkBlocks>,
    },
}

/// What a range of chunks of A and B contributes to the Sobol' indices: the part of the
/// analysis a shard computes ([`sobol_chunks`]) and [`merge_sobol`] finishes.
#[derive(Debug, Clone, PartialEq)]
pub struct SobolPartial {
    /// The chunks covered.
    pub chunks: Range<u64>,
    /// Their values or block sums.
    pub values: SobolChunks,
}

/// The checked settings of one analysis.
struct SobolPlan {
    groups: Vec<InputGroup>,
    analysed: Vec<Analysed>,
    method: IntervalMethod,
    /// A replicated design's points: 2D dimensions, A the first D, B the last D.
    points: Option<PointSet>,
}

fn sobol_plan(
    scenario: &Scenario,
    settings: SensitivitySettings,
) -> Result<SobolPlan, ScenarioError> {
    if settings.base_samples < 2 {
        return Err(ScenarioError::new(
            "samples",
            "sensitivity needs at least 2 base samples",
        ));
    }
    if settings.bootstrap < 2 {
        return Err(ScenarioError::new(
            "bootstrap",
            "needs at least 2 resamples",
        ));
    }
    let groups = independent_groups(scenario);
    if groups.is_empty() {
        return Err(ScenarioError::new(
            "parts/variables",
            "the scenario has no random input",
        ));
    }
    let sampling = settings.sampling;
    sampling.check(settings.base_samples, "base samples", &scenario.input_space)?;
    let points = if sampling.is_replicated() {
        let dims = scenario.input_space.quasi_dimensions()?;
        let points = PointSet::new(
            sampling.method,
            2 * dims,
            sampling.replicate_points(settings.base_samples),
            settings.seed,
        )
        .map_err(|message| ScenarioError::new("sampling", message))?;
        Some(points)
    } else {
        None
    };
    Ok(SobolPlan {
        groups,
        analysed: analysed_quantities(scenario),
        method: settings.interval_method(scenario),
        points,
    })
}

/// Evaluates chunks `chunks` of A, B and the mixed matrices (a shard of the analysis):
/// the values [`sobol_indices`] computes for them, whatever the thread count. `progress`
/// receives base samples done.
pub fn sobol_chunks(
    scenario: &Scenario,
    settings: SensitivitySettings,
    chunks: Range<u64>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<SobolPartial, ScenarioError> {
    let plan = sobol_plan(scenario, settings)?;
    let n_chunks = settings.chunk_count();
    if chunks.start > chunks.end || chunks.end > n_chunks {
        return Err(ScenarioError::new(
            "(sensitivity)",
            format!(
                "chunks {}..{} are not within the analysis' {n_chunks} chunks",
                chunks.start, chunks.end
            ),
        ));
    }
    let chunk_samples =
        |chunk: u64| settings.sampling.chunk_rows(settings.base_samples, chunk).3 as u64;
    let side_by_side = chunks.end - chunks.start < rayon::current_num_threads() as u64;
    let evaluate = |chunk: u64| {
        let values = evaluate_chunk(scenario, &plan, settings, chunk, side_by_side);
        progress(chunk_samples(chunk));
        values
    };
    let (centres, block_rows) = match plan.method {
        IntervalMethod::Rows => {
            let values = (chunks.start..chunks.end)
                .into_par_iter()
                .map(evaluate)
                .collect::<Result<_, _>>()?;
            return Ok(SobolPartial {
                chunks,
                values: SobolChunks::Rows(values),
            });
        }
        // Centres from chunk 0, which every run draws identically.
        IntervalMethod::Blocks { rows } => (
            evaluate_chunk(scenario, &plan, settings, 0, true)?
                .iter()
                .map(|f| finite_mean(f[0].iter().chain(&f[1])))
                .collect::<Vec<f64>>(),
            rows as usize,
        ),
        IntervalMethod::Replicates => (
            replicate_centres(scenario, &plan, settings.seed)?,
            CHUNK_SIZE,
        ),
    };
    let n_groups = plan.groups.len();
    let blocks = (chunks.start..chunks.end)
        .into_par_iter()
        .map(|chunk| {
            let values = evaluate(chunk)?;
            Ok(values
                .iter()
                .zip(&centres)
                .map(|(f, &centre)| {
                    let m = f[0].len();
                    let mut dropped = 0;
                    let mut terms = vec![0.0; 2 * n_groups + 2];
                    let blocks = (0..m)
                        .step_by(block_rows)
                        .map(|first| {
                            let mut sums = BlockSums::new(n_groups);
                            for r in first..(first + block_rows).min(m) {
                                dropped += u64::from(!sums.add_row(f, r, centre, &mut terms));
                            }
                            sums
                        })
                        .collect();
                    (blocks, dropped)
                })
                .collect())
        })
        .collect::<Result<_, ScenarioError>>()?;
    let values = SobolChunks::Blocks {
        centres,
        chunks: blocks,
    };
    Ok(SobolPartial { chunks, values })
}

/// The indices from partials that cover the analysis' chunks exactly once (in any order):
/// bit for bit those of [`sobol_indices`], which merges its own single partial here.
pub fn merge_sobol(
    scenario: &Scenario,
    settings: SensitivitySettings,
    mut partials: Vec<SobolPartial>,
) -> Result<Vec<OutputSensitivity>, FoldError> {
    let plan = sobol_plan(scenario, settings)?;
    let broken = |message: String| Err(MergeError::new(message).into());
    partials.sort_by_key(|p| (p.chunks.start, p.chunks.end));
    let n_chunks = settings.chunk_count();
    let mut next = 0;
    for partial in &partials {
        if partial.chunks.start != next {
            return broken(format!(
                "chunks {}..{} {}",
                next.min(partial.chunks.start),
                next.max(partial.chunks.start),
                if partial.chunks.start < next {
                    "are in two partials"
                } else {
                    "are missing"
                }
            ));
        }
        next = partial.chunks.end;
    }
    if next != n_chunks {
        return broken(format!("chunks {next}..{n_chunks} are missing"));
    }
    let n_outputs = plan.analysed.len();
    let n_variants = 2 * plan.groups.len() + 2;
    match plan.method {
        IntervalMethod::Rows => {
            let mut chunks = Vec::with_capacity(n_chunks as usize);
            for partial in partials {
                let width = partial.chunks.end - partial.chunks.start;
                let rows_of =
                    |chunk: u64| settings.sampling.chunk_rows(settings.base_samples, chunk).3;
                match partial.values {
                    SobolChunks::Rows(values)
                        if values.len() as u64 == width
                            && values.iter().zip(partial.chunks.clone()).all(|(c, chunk)| {
                                c.len() == n_outputs
                                    && c.iter().all(|o| {
                                        o.len() == n_variants
                                            && o.iter().all(|v| v.len() == rows_of(chunk))
                                    })
                            }) =>
                    {
                        chunks.extend(values)
                    }
                    _ => return broken("a partial's values do not fit the analysis".into()),
                }
            }
            Ok(indices_from_rows(scenario, &plan, settings, &chunks)?)
        }
        IntervalMethod::Blocks { .. } | IntervalMethod::Replicates => {
            let mut centres_seen: Option<Vec<f64>> = None;
            let mut chunks = Vec::with_capacity(n_chunks as usize);
            for partial in partials {
                let width = partial.chunks.end - partial.chunks.start;
                match partial.values {
                    SobolChunks::Blocks {
                        centres,
                        chunks: blocks,
                    } if blocks.len() as u64 == width
                        && centres.len() == n_outputs
                        && blocks.iter().all(|c| c.len() == n_outputs) =>
                    {
                        let same = |a: &[f64], b: &[f64]| {
                            a.iter()
                                .map(|x| x.to_bits())
                                .eq(b.iter().map(|x| x.to_bits()))
                        };
                        match &centres_seen {
                            Some(seen) if !same(seen, &centres) => {
                                return broken("the partials' block centres differ".into())
                            }
                            Some(_) => {}
                            None => centres_seen = Some(centres),
                        }
                        chunks.extend(blocks);
                    }
                    _ => return broken("a partial's block sums do not fit the analysis".into()),
                }
            }
            let centres = centres_seen.unwrap_or_default();
            Ok(if plan.method == IntervalMethod::Replicates {
                indices_from_replicates(scenario, &plan, settings, &chunks, &centres)?
            } else {
                indices_from_blocks(scenario, &plan, settings, &chunks, &centres)?
            })
        }
    }
}

/// A replicated design ([`IntervalMethod::Replicates`]): the indices from the totals of
/// every chunk's sums, their intervals from the spread of each replicate's own indices.
fn indices_from_replicates(
    scenario: &Scenario,
    plan: &SobolPlan,
    settings: SensitivitySettings,
    chunks: &[ChunkBlocks],
    centres: &[f64],
) -> Result<Vec<OutputSensitivity>, ScenarioError> {
    let (groups, analysed) = (&plan.groups, &plan.analysed);
    let n_groups = groups.len();
    let sampling = settings.sampling;
    let t = student_t_quantile(
        (sampling.replicates - 1) as f64,
        0.5 + settings.confidence / 2.0,
    );
    let mut results = Vec::with_capacity(analysed.len());
    for (slot, &quantity) in analysed.iter().enumerate() {
        let mut replicates = vec![BlockSums::new(n_groups); sampling.replicates as usize];
        let mut non_finite_rows = 0;
        for (chunk, blocks) in (0..).zip(chunks) {
            let (replicate, _, _, rows) = sampling.chunk_rows(settings.base_samples, chunk);
            match &blocks[slot] {
                (sums, dropped)
                    if sums.len() == 1
                        && sums[0].first.len() == n_groups
                        && sums[0].total.len() == n_groups
                        && sums[0].rows + dropped == rows as u64 =>
                {
                    replicates[replicate as usize].add(&sums[0]);
                    non_finite_rows += dropped;
                }
                _ => {
                    return Err(ScenarioError::new(
                        "(merge)",
                        "a partial's sums do not fit the analysis' replicates",
                    ))
                }
            }
        }
        if replicates.iter().any(|r| r.rows < 2) {
            return Err(ScenarioError::new(
                format!("(output {})", quantity.name(scenario)),
                "a replicate has fewer than 2 finite rows: the sensitivity is undefined",
            ));
        }
        let mut all = BlockSums::new(n_groups);
        replicates.iter().for_each(|r| all.add(r));
        let (variance, first, total) = all.indices();
        let estimates = replicates.iter().map(BlockSums::first_and_total).collect();
        results.push(output_sensitivity(
            scenario,
            (quantity, all.mean(centres[slot])),
            groups,
            settings,
            variance,
            non_finite_rows,
            (first, total),
            Spread::Replicates { estimates, t },
        ));
    }
    Ok(results)
}

/// The block bootstrap ([`IntervalMethod::Blocks`]): the indices from the totals of every
/// chunk's block sums and the intervals from resampled blocks.
fn indices_from_blocks(
    scenario: &Scenario,
    plan: &SobolPlan,
    settings: SensitivitySettings,
    chunks: &[ChunkBlocks],
    centres: &[f64],
) -> Result<Vec<OutputSensitivity>, ScenarioError> {
    let (groups, analysed) = (&plan.groups, &plan.analysed);
    let n_groups = groups.len();
    let mut results = Vec::with_capacity(analysed.len());
    for (slot, &quantity) in analysed.iter().enumerate() {
        let blocks: Vec<&BlockSums> = chunks
            .iter()
            .flat_map(|chunk| chunk[slot].0.iter())
            .filter(|b| b.rows > 0)
            .collect();
        let non_finite_rows: u64 = chunks.iter().map(|chunk| chunk[slot].1).sum();
        let mut all = BlockSums::new(n_groups);
        for block in &blocks {
            if block.first.len() != n_groups || block.total.len() != n_groups {
                return Err(ScenarioError::new(
                    "(merge)",
                    "a partial's block sums do not fit the analysis",
                ));
            }
            all.add(block);
        }
        if all.rows < 2 || blocks.len() < 2 {
            return Err(ScenarioError::new(
                format!("(output {})", quantity.name(scenario)),
                "fewer than 2 finite rows: the sensitivity is undefined",
            ));
        }
        let (variance, first, total) = all.indices();
        let resamples: Vec<(Vec<f64>, Vec<f64>)> = (0..settings.bootstrap)
            .into_par_iter()
            .map(|b| {
                let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
                rng.set_stream(BOOTSTRAP_STREAM_BASE + b as u64);
                let mut sums = BlockSums::new(n_groups);
                for _ in 0..blocks.len() {
                    sums.add(blocks[rng.random_range(0..blocks.len())]);
                }
                sums.first_and_total()
            })
            .collect();
        results.push(output_sensitivity(
            scenario,
            (quantity, all.mean(centres[slot])),
            groups,
            settings,
            variance,
            non_finite_rows,
            (first, total),
            Spread::Bootstrap(resamples),
        ));
    }
    Ok(results)
}

/// What an interval comes from: per resample or replicate, (first-order, total) indices
/// of every group.
enum Spread {
    /// Bootstrap resamples: the percentile interval.
    Bootstrap(Vec<(Vec<f64>, Vec<f64>)>),
    /// Independent replicates: the estimate ± t·s/√R, t the Student quantile of the
    /// confidence (R − 1 degrees of freedom).
    Replicates {
        /// Per replicate, its (first-order, total) indices.
        estimates: Vec<(Vec<f64>, Vec<f64>)>,
        /// The t quantile.
        t: f64,
    },
}

impl Spread {
    /// The interval of `value`, group g's first-order (`total` false) or total index.
    fn interval(&self, value: f64, g: usize, total: bool, confidence: f64) -> [f64; 2] {
        let pick =
            |(first, totals): &(Vec<f64>, Vec<f64>)| if total { totals[g] } else { first[g] };
        match self {
            Spread::Bootstrap(resamples) => {
                percentile_interval(resamples.iter().map(pick).collect(), confidence)
            }
            Spread::Replicates { estimates, t } => {
                let values: Vec<f64> = estimates.iter().map(pick).collect();
                let h = t * replicate_standard_error(&values);
                [value - h, value + h]
            }
        }
    }
}

/// The indices of `quantity` (with its mean) and their intervals, groups sorted by
/// decreasing total index.
#[allow(clippy::too_many_arguments)]
fn output_sensitivity(
    scenario: &Scenario,
    (quantity, mean): (Analysed, f64),
    groups: &[InputGroup],
    settings: SensitivitySettings,
    variance: f64,
    non_finite_rows: u64,
    (first, total): (Vec<f64>, Vec<f64>),
    spread: Spread,
) -> OutputSensitivity {
    let mut group_indices: Vec<GroupIndices> = groups
        .iter()
        .enumerate()
        .map(|(g, group)| GroupIndices {
            group: group.name.clone(),
            first_order: Estimate {
                value: first[g],
                interval: spread.interval(first[g], g, false, settings.confidence),
            },
            total: Estimate {
                value: total[g],
                interval: spread.interval(total[g], g, true, settings.confidence),
            },
        })
        .collect();
    group_indices.sort_by(|a, b| b.total.value.total_cmp(&a.total.value));
    OutputSensitivity {
        name: quantity.name(scenario),
        unit: quantity.unit(scenario),
        quantity,
        mean,
        variance,
        non_finite_rows,
        indices: group_indices,
    }
}

fn percentile_interval(mut values: Vec<f64>, confidence: f64) -> [f64; 2] {
    let tail = 50.0 * (1.0 - confidence);
    let ends = rvtol_engine::stats::percentiles_type7(&mut values, &[tail, 100.0 - tail]);
    [ends[0].unwrap_or(f64::NAN), ends[1].unwrap_or(f64::NAN)]
}

/// Computes the indices. `progress` receives base samples done.
pub fn sobol_indices(
    scenario: &Scenario,
    settings: SensitivitySettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<OutputSensitivity>, ScenarioError> {
    let partial = sobol_chunks(scenario, settings, 0..settings.chunk_count(), progress)?;
    merge_sobol(scenario, settings, vec![partial]).map_err(FoldError::of_own_partial)
}

/// Rows of a cache block of the row bootstrap: the estimator terms of a block (2G + 2
/// numbers per row) stay in cache while every resample sums its picks among them.
const BOOTSTRAP_BLOCK_ROWS: usize = 2048;

/// Word offset, in a resample's stream, of the picks within block j: (j + 1)·2^40 (the
/// block totals take the words from 0; a block draws far fewer than 2^40 words).
const BLOCK_WORD_STRIDE: u128 = 1 << 40;

/// The row bootstrap's resamples of one output: per resample, the estimator sums
/// ([`BlockSums`]) over `m` rows drawn with replacement from the finite rows, whose terms
/// `terms` holds row-major (`k` = 2G + 2 per row: f_A + f_B, f_A² + f_B², the first-order
/// terms, the total terms; values centred).
///
/// A resample is the multinomial count of each row among m uniform picks, drawn without
/// reading rows at random: resample b's stream (`BOOTSTRAP_STREAM_BASE + b`) first splits
/// the m picks among the blocks of [`BOOTSTRAP_BLOCK_ROWS`] rows by conditional binomials
/// (block j gets Bin(picks left, rows of j / rows left)), then places block j's picks
/// uniformly among its rows from the word offset (j + 1)·[`BLOCK_WORD_STRIDE`]. That is the
/// multinomial law of the classic bootstrap, exactly. Blocks are taken in order, each held
/// in cache while every resample adds count × terms over its rows (in parallel over the
/// resamples); each resample's sum runs in block order, so the result does not depend on
/// the thread count.
fn row_resamples(
    terms: &[f64],
    k: usize,
    n_groups: usize,
    seed: u64,
    bootstrap: usize,
) -> Vec<BlockSums> {
    let m = terms.len() / k;
    let blocks = m.div_ceil(BOOTSTRAP_BLOCK_ROWS);
    let stream = |b: usize, block: Option<usize>| {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(BOOTSTRAP_STREAM_BASE + b as u64);
        if let Some(j) = block {
            rng.set_word_pos((j as u128 + 1) * BLOCK_WORD_STRIDE);
        }
        rng
    };
    // Per resample: its totals stream, the picks not yet placed, and its sums.
    let mut states: Vec<(ChaCha8Rng, u64, Vec<f64>)> = (0..bootstrap)
        .map(|b| (stream(b, None), m as u64, vec![0.0; k]))
        .collect();
    let mut rows_left = m as u64;
    for j in 0..blocks {
        let start = j * BOOTSTRAP_BLOCK_ROWS;
        let rows = BOOTSTRAP_BLOCK_ROWS.min(m - start);
        let block = &terms[start * k..(start + rows) * k];
        let last = j + 1 == blocks;
        let share = rows as f64 / rows_left as f64;
        states.par_iter_mut().enumerate().for_each_init(
            || vec![0u32; BOOTSTRAP_BLOCK_ROWS],
            |counts, (b, (totals, picks_left, sums))| {
                let picks = if last || *picks_left == 0 {
                    *picks_left
                } else {
                    Binomial::new(*picks_left, share)
                        .expect("0 < share ≤ 1")
                        .sample(totals)
                };
                *picks_left -= picks;
                if picks == 0 {
                    return;
                }
                let counts = &mut counts[..rows];
                counts.fill(0);
                let mut rng = stream(b, Some(j));
                for _ in 0..picks {
                    counts[rng.random_range(0..rows)] += 1;
                }
                for (&c, row) in counts.iter().zip(block.chunks_exact(k)) {
                    if c != 0 {
                        let c = c as f64;
                        for (s, t) in sums.iter_mut().zip(row) {
                            *s += c * t;
                        }
                    }
                }
            },
        );
        rows_left -= rows as u64;
    }
    states
        .into_iter()
        .map(|(_, _, sums)| BlockSums {
            rows: m as u64,
            sum: sums[0],
            sum_squares: sums[1],
            first: sums[2..2 + n_groups].to_vec(),
            total: sums[2 + n_groups..].to_vec(),
        })
        .collect()
}

/// The row bootstrap ([`IntervalMethod::Rows`]) over every chunk's values, in chunk order.
fn indices_from_rows(
    scenario: &Scenario,
    plan: &SobolPlan,
    settings: SensitivitySettings,
    chunks: &[ChunkValues],
) -> Result<Vec<OutputSensitivity>, ScenarioError> {
    let (groups, analysed) = (&plan.groups, &plan.analysed);
    let n_variants = 2 * groups.len() + 2;
    let mut results = Vec::with_capacity(analysed.len());
    for (slot, &quantity) in analysed.iter().enumerate() {
        // Concatenate the chunks in order: f[variant][row].
        let mut f: Vec<Vec<f64>> =
            vec![Vec::with_capacity(settings.base_samples as usize); n_variants];
        for chunk in chunks {
            for (variant, values) in chunk[slot].iter().enumerate() {
                f[variant].extend_from_slice(values);
            }
        }
        let n = f[0].len();
        let finite_rows: Vec<usize> = (0..n)
            .filter(|&r| f.iter().all(|v| v[r].is_finite()))
            .collect();
        let non_finite_rows = (n - finite_rows.len()) as u64;
        if finite_rows.len() < 2 {
            return Err(ScenarioError::new(
                format!("(output {})", quantity.name(scenario)),
                "fewer than 2 finite rows: the sensitivity is undefined",
            ));
        }
        // Centre every value on the mean of f(A) and f(B): the indices are then computed
        // from deviations, which keeps the variance free of cancellation for outputs whose
        // spread is small against their value, and lowers the estimators' variance.
        let centre = finite_rows.iter().map(|&r| f[0][r] + f[1][r]).sum::<f64>()
            / (2.0 * finite_rows.len() as f64);
        let variance = {
            let values: Vec<f64> = finite_rows
                .iter()
                .flat_map(|&r| [f[0][r] - centre, f[1][r] - centre])
                .collect();
            rvtol_engine::stats::Moments::from_slice(&values).variance()
        };
        // The estimator's terms of every finite row, row-major: their sums in row order
        // give the indices, and a resample reads them block by block (row_resamples).
        let n_groups = groups.len();
        let k = 2 * n_groups + 2;
        let mut terms = vec![0.0; finite_rows.len() * k];
        let mut all = BlockSums::new(n_groups);
        for (&r, row) in finite_rows.iter().zip(terms.chunks_exact_mut(k)) {
            row_terms(&f, r, centre, row);
            all.add_terms(row);
        }
        drop(f);
        let (_, first, total) = all.indices();
        let resamples: Vec<(Vec<f64>, Vec<f64>)> =
            row_resamples(&terms, k, n_groups, settings.seed, settings.bootstrap)
                .into_iter()
                .map(|sums| sums.first_and_total())
                .collect();
        results.push(output_sensitivity(
            scenario,
            (quantity, centre),
            groups,
            settings,
            variance,
            non_finite_rows,
            (first, total),
            Spread::Bootstrap(resamples),
        ));
    }
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows whose terms reveal a resample's counts: [1, in block 0, in block 1, in block 2,
    /// is row 0, is the last row] (n_groups = 2).
    fn counting_terms(m: usize) -> Vec<f64> {
        let mut terms = vec![0.0; m * 6];
        for (r, row) in terms.chunks_exact_mut(6).enumerate() {
            row[0] = 1.0;
            row[1 + (r / BOOTSTRAP_BLOCK_ROWS).min(2)] = 1.0;
            row[4] = (r == 0) as u8 as f64;
            row[5] = (r == m - 1) as u8 as f64;
        }
        terms
    }

    #[test]
    fn a_resample_is_the_multinomial_count_of_m_picks() {
        // m = 5000 rows in blocks of 2048, 2048, 904; 4000 resamples. Each resample places
        // exactly m picks; a block's count is Bin(m, p_j) (mean m·p_j, variance
        // m·p_j·(1 − p_j)), two blocks' counts correlate as −√(p_i·p_j/((1 − p_i)(1 − p_j)))
        // (multinomial), and a row's count has mean 1 and variance 1 − 1/m. Means within 5
        // standard errors; a block count's variance within 5·√(2/B) relative (its sampling
        // error at B resamples, near-normal counts), a row count's within 5·√((κ − 1)/B)
        // (κ its binomial kurtosis); the correlation within 5/√B.
        let m = 5000;
        let b = 4000;
        let sums = row_resamples(&counting_terms(m), 6, 2, 42, b);
        assert!(sums.iter().all(|s| s.sum == m as f64 && s.rows == m as u64));
        let bf = b as f64;
        let stats = |x: &dyn Fn(&BlockSums) -> f64| {
            let v: Vec<f64> = sums.iter().map(x).collect();
            let mean = v.iter().sum::<f64>() / bf;
            let var = v.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (bf - 1.0);
            (v, mean, var)
        };
        let p = [2048.0 / 5000.0, 2048.0 / 5000.0, 904.0 / 5000.0];
        let blocks: Vec<(Vec<f64>, f64, f64)> = (0..3)
            .map(|j| {
                stats(&move |s: &BlockSums| match j {
                    0 => s.sum_squares,
                    1 => s.first[0],
                    _ => s.first[1],
                })
            })
            .collect();
        for (j, (_, mean, var)) in blocks.iter().enumerate() {
            let expected_var = m as f64 * p[j] * (1.0 - p[j]);
            assert!(
                (mean - m as f64 * p[j]).abs() < 5.0 * (expected_var / bf).sqrt(),
                "block {j}: mean {mean}"
            );
            assert!(
                (var / expected_var - 1.0).abs() < 5.0 * (2.0 / bf).sqrt(),
                "block {j}: variance {var} against {expected_var}"
            );
        }
        let (v0, m0, s0) = (&blocks[0].0, blocks[0].1, blocks[0].2);
        let (v1, m1, s1) = (&blocks[1].0, blocks[1].1, blocks[1].2);
        let cov = v0
            .iter()
            .zip(v1)
            .map(|(x, y)| (x - m0) * (y - m1))
            .sum::<f64>()
            / (bf - 1.0);
        let rho = cov / (s0 * s1).sqrt();
        let expected = -(p[0] * p[1] / ((1.0 - p[0]) * (1.0 - p[1]))).sqrt();
        assert!(
            (rho - expected).abs() < 5.0 / bf.sqrt(),
            "{rho} against {expected}"
        );
        for (name, x) in [
            (
                "row 0",
                &(|s: &BlockSums| s.total[0]) as &dyn Fn(&BlockSums) -> f64,
            ),
            ("last row", &|s: &BlockSums| s.total[1]),
        ] {
            let (_, mean, var) = stats(x);
            let expected_var = 1.0 - 1.0 / m as f64;
            assert!(
                (mean - 1.0).abs() < 5.0 * (expected_var / bf).sqrt(),
                "{name}: {mean}"
            );
            // A row's count is Bin(m, 1/m), kurtosis 3 + (1 − 6p(1 − p))/(mp(1 − p)) ≈ 4:
            // the sample variance's relative standard error is √((κ − 1)/B).
            let p = 1.0 / m as f64;
            let kurtosis = 3.0 + (1.0 - 6.0 * p * (1.0 - p)) / (m as f64 * p * (1.0 - p));
            assert!(
                (var / expected_var - 1.0).abs() < 5.0 * ((kurtosis - 1.0) / bf).sqrt(),
                "{name}: variance {var}"
            );
        }
    }

    #[test]
    fn resamples_do_not_depend_on_the_thread_count() {
        let terms: Vec<f64> = (0..9000 * 6).map(|i| ((i * 7919) % 1000) as f64).collect();
        let with = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| row_resamples(&terms, 6, 2, 3, 64))
        };
        assert_eq!(with(1), with(2));
        assert_eq!(with(1), with(3));
    }
}
