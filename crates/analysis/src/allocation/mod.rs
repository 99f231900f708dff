//! Tolerance allocation (`rvtol allocate`): the cheapest set of tolerances, within the
//! scenario's bounds, whose Monte Carlo output distribution meets a target such as
//! `p99.865 <= 1.0`, `cpk >= 1.33` or `ppm_out <= 100`.
//!
//! Method (docs/models.md §9): the decision variables are the factors s_k on each
//! allocatable source's tolerance, the constraint is h(s) = excess of the target figure +
//! z·SE ≤ 0 (a margin of [`MARGIN_Z`] = 3 + 1.96 Monte Carlo standard errors, so that an
//! independent run's 95 % interval lies within the target too: that run's figure differs
//! from the optimised one by about N(0, 2·SE²), so it misses by more than the 1.96·SE its
//! interval needs with probability Φ(−3/√2) = 1.7 %), and the objective is Σ c_k(s_k·t_k).
//! 1. Every evaluation of h is a Monte Carlo run of the scaled scenario with one seed:
//!    common random numbers make h a deterministic, piecewise-smooth function of s.
//! 2. Sequential Lagrange allocation: h is linearised in the variances u_k = s_k² by
//!    forward differences (the classical linear-stack model, in which the output variance
//!    is Σ a_k²·σ_k², has exactly this form), and the linearised problem
//!    min Σ c_k subject to Σ w_k·s_k² ≤ budget is solved by the Lagrange condition
//!    c_k'(s_k) + 2λ·w_k·s_k = 0 per source and bisection on λ, within a trust region;
//!    repeated from the new point until the factors settle.
//! 3. The result is refined against the Monte Carlo result: one common factor on the
//!    sources that matter is bisected until h = 0. The cheapest feasible point seen wins.
//! 4. Proposed tolerances are rounded to three significant digits (tighter where that
//!    matters) and verified by an independent run with a different seed, whose figure and
//!    95 % interval are reported: `met` only when the whole interval satisfies the target,
//!    else `not verified`. The common-scaling answer (every tolerance scaled by
//!    one factor) is reported beside it for comparison.

pub mod rare;
pub mod report;
pub mod scaling;

use rvtol_models::OutputKind;
use serde_json::Value;

use rvtol_engine::figures::{percentile_of_sorted_with_interval, symmetric95, CONFIDENCE, Z95};
use rvtol_engine::run::{run_for_output, KeptValues, RunSettings};
use rvtol_engine::scenario::allocation::{self as spec, AllocatableSource, CostKind};
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_engine::stats::conformity::Placement;
use rvtol_engine::stats::{
    capability_from_moments, cpk_on_upper_side, cpk_standard_error, out_of_spec_interval,
    proportion_standard_error, Moments, SpecLimits,
};

use crate::rare::Method;
use crate::target::{Target, TargetFigure};
use rare::{RareOptions, RareSample};

/// Standard errors kept between the optimised figure and the target.
pub const MARGIN_Z: f64 = 3.0 + Z95;

/// Samples of importance sampling built at most, `--rare` (the first around the current
/// tolerances, each next around the point the previous one led to).
pub const MAX_STAGES: usize = 4;

/// Sequential Lagrange iterations at most.
pub const MAX_ITERATIONS: usize = 30;
/// Relative step of the forward differences, on the tolerance factor.
const DIFFERENCE_STEP: f64 = 0.05;
/// Largest change of a factor in the first iteration (trust region, ratio).
const TRUST_RATIO: f64 = 2.0;
/// The iterations stop when no factor moves by more than this (relative).
const SETTLED: f64 = 1e-3;
/// Significant digits of the proposed tolerances.
const SIGNIFICANT_DIGITS: i32 = 3;

/// How to allocate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllocationSettings {
    /// Samples of every Monte Carlo evaluation (and of the verification run).
    pub samples: u64,
    /// Seed of the optimisation runs (common random numbers).
    pub seed: u64,
    /// Seed of the independent verification run (must differ from `seed`).
    pub verification_seed: u64,
    /// The cost model to use where a source gives several (`--cost`).
    pub cost: Option<CostKind>,
    /// A ppm target estimated by importance sampling (`--rare`) instead of Monte Carlo
    /// runs of `samples`.
    pub rare: Option<RareOptions>,
}

/// The default sample count for a target: enough for about 100 samples beyond a tail
/// percentile or out of spec, at least 200,000 and at most 4,000,000.
pub fn default_samples(target: &Target) -> u64 {
    let samples = tail_fraction(target).map_or(0.0, |tail| 100.0 / tail);
    (samples.ceil() as u64).clamp(200_000, 4_000_000)
}

/// The fraction of samples in the tail a percentile or ppm target constrains; None for
/// the moment-based targets.
fn tail_fraction(target: &Target) -> Option<f64> {
    match target.figure {
        TargetFigure::Percentile(p) => Some(p.min(100.0 - p) / 100.0),
        TargetFigure::PpmOut => Some(target.value / 1e6),
        _ => None,
    }
}

/// One Monte Carlo evaluation of the target figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// The target figure (for ppm_out in the optimisation: from the interpolated
    /// empirical distribution, continuous in the tolerances; in the verification: the
    /// count).
    pub figure: f64,
    /// Its Monte Carlo standard error.
    pub standard_error: f64,
    /// 95 % interval of the figure.
    pub interval: (f64, f64),
    /// Finite samples.
    pub n: u64,
    /// Mean of the output.
    pub mean: f64,
    /// Standard deviation of the output.
    pub sd: f64,
    /// The output's distribution in outline: (p in %, type-7 percentile) at
    /// [`QUANTILE_LEVELS`] as a conformity judgement reads them (±∞ where a level reads a
    /// sample beyond the limits: flagged, excluded or not finite).
    pub quantiles: Vec<(f64, f64)>,
}

/// The percentile levels (%) of [`Evaluation::quantiles`]: the ±kσ levels of a normal and
/// enough between them to draw the distribution on a probability scale.
pub const QUANTILE_LEVELS: [f64; 29] = [
    0.135, 0.25, 0.5, 1.0, 2.275, 5.0, 10.0, 15.866, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0,
    55.0, 60.0, 65.0, 70.0, 75.0, 80.0, 84.134, 90.0, 95.0, 97.725, 99.0, 99.5, 99.75, 99.865,
];

/// The outline of the conforming values `sorted` with `beyond` samples beyond the limits,
/// as a conformity judgement reads it (±∞ where a level reads one of those).
fn outline(sorted: &[f64], beyond: (usize, Placement)) -> Vec<(f64, f64)> {
    QUANTILE_LEVELS
        .iter()
        .filter_map(|&p| {
            let (value, _, _) = percentile_of_sorted_with_interval(sorted, beyond, p, 0.0)?;
            Some((p, value))
        })
        .collect()
}

impl Evaluation {
    /// Whether this run shows the target met: the figure and its whole 95 % interval
    /// satisfy it (an interval that straddles the target, or an undefined figure, does
    /// not).
    pub fn verifies(&self, target: &Target) -> bool {
        [self.figure, self.interval.0, self.interval.1]
            .iter()
            .all(|&f| target.excess(f) <= 0.0)
    }
}

/// One source's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceAllocation {
    /// The source and its bounds and cost.
    pub source: AllocatableSource,
    /// The optimum before rounding.
    pub optimum: f64,
    /// Proposed tolerance: the optimum rounded to three significant digits.
    pub proposed: f64,
    /// Cost at the current tolerance (None outside a cost table).
    pub current_cost: Option<f64>,
    /// Cost at the proposed tolerance.
    pub proposed_cost: f64,
    /// Share of the output variance at the proposal (Euler allocation:
    /// s_k²·∂Var/∂(s_k²) / Var, which is the classical a_k²σ_k²/σ² for a linear stack).
    pub variance_share: f64,
}

/// Every tolerance scaled by one factor: the comparison users know.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommonScale {
    /// The factor.
    pub factor: f64,
    /// Total cost.
    pub cost: f64,
}

/// The answer of `rvtol allocate`.
#[derive(Debug, Clone, PartialEq)]
pub struct Allocation {
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (data files written in), hex.
    pub scenario_sha256: String,
    /// The output's spec limits, when the scenario sets them.
    pub spec: Option<SpecLimits>,
    /// The constrained output.
    pub output: String,
    /// Its unit.
    pub unit: String,
    /// The target.
    pub target: Target,
    /// Settings used.
    pub settings: AllocationSettings,
    /// Per allocatable source, in scenario order.
    pub sources: Vec<SourceAllocation>,
    /// The figure at the current tolerances (optimisation seed).
    pub current: Evaluation,
    /// The figure at the proposal (optimisation seed).
    pub proposed: Evaluation,
    /// The independent verification run at the proposal.
    pub verification: Evaluation,
    /// Whether a feasible allocation was found within the bounds.
    pub feasible: bool,
    /// Whether the verification run meets the target.
    pub verified: bool,
    /// Total cost at the current tolerances (None when a source's is undefined).
    pub current_cost: Option<f64>,
    /// Total cost of the proposal.
    pub proposed_cost: f64,
    /// Total cost of the optimum before rounding.
    pub optimum_cost: f64,
    /// The common-scaling comparison (None when no common factor meets the target).
    pub common_scale: Option<CommonScale>,
    /// Sequential Lagrange iterations run.
    pub iterations: usize,
    /// Monte Carlo evaluations run (including the verification).
    pub evaluations: usize,
    /// The lever values of the answer (empty without levers).
    pub levers: Vec<LeverChoice>,
    /// Every lever combination tried (empty without levers).
    pub lever_options: Vec<LeverOption>,
    /// How importance sampling estimated the constraint (`--rare`).
    pub rare: Option<RareUse>,
}

/// How `allocate --rare` estimated its constraint.
#[derive(Debug, Clone, PartialEq)]
pub struct RareUse {
    /// The options asked.
    pub options: RareOptions,
    /// Samples built (stages).
    pub stages: usize,
    /// Points of the last sample: every evaluation of the optimisation's last stage.
    pub points: u64,
    /// The tolerance factors the last sample's centres were found at, per source.
    pub centred_at: Vec<f64>,
    /// Model evaluations of the whole allocation (searches, samples, verification).
    pub model_evaluations: u64,
    /// The verification's estimator: importance sampling around the proposal's own
    /// centres, or subset simulation where that did not reach its precision or one point
    /// carried much of it.
    pub verified_by: Method,
}

/// The optimisation problem, with everything an evaluation needs.
struct Problem<'a> {
    document: Value,
    name: &'a str,
    digest: &'a str,
    sources: Vec<AllocatableSource>,
    output: usize,
    output_name: &'a str,
    target: Target,
    limits: Option<SpecLimits>,
    /// Whether flagged samples within the limits conform (the output's spec setting).
    flagged_conform: bool,
    samples: u64,
    /// Factor bounds per source: [min/t, max/t].
    bounds: Vec<(f64, f64)>,
    progress: &'a (dyn Fn(usize) + Sync),
    evaluations: std::cell::Cell<usize>,
    /// `--rare`: how the constraint is estimated, and the current sample.
    rare: Option<RareOptions>,
    sample: std::cell::RefCell<Option<RareSample>>,
    /// `--rare`: model evaluations (rows) so far.
    model_evaluations: std::cell::Cell<u64>,
    /// `--rare`: the estimator of the last verification.
    verified_by: std::cell::Cell<Option<Method>>,
}

/// What one search of the sequential Lagrange allocation found.
struct Search {
    /// The cheapest feasible point seen.
    best: Option<Point>,
    /// The sources the constraint depends on, at the last iterate.
    matters: Vec<bool>,
    /// The common-scaling comparison.
    common: Option<CommonScale>,
    /// Iterations run.
    iterations: usize,
}

/// A point of the search: factors, their evaluation, the constraint value and the cost.
#[derive(Debug, Clone)]
struct Point {
    factors: Vec<f64>,
    evaluation: Evaluation,
    constraint: f64,
    cost: f64,
}

/// A lever's value in an allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct LeverChoice {
    /// The lever's name.
    pub name: String,
    /// The model parameter it sets, as a path (`models[0].params.pin_classes`).
    pub param: String,
    /// The value.
    pub value: f64,
    /// Its cost.
    pub cost: f64,
}

/// One combination of lever values tried, with the allocation found for it.
#[derive(Debug, Clone, PartialEq)]
pub struct LeverOption {
    /// The value of each lever, in the order of [`Allocation::levers`].
    pub values: Vec<f64>,
    /// Cost of the lever values.
    pub lever_cost: f64,
    /// Cost of the proposed tolerances.
    pub tolerance_cost: f64,
    /// `met`, `not verified` or `infeasible`.
    pub status: &'static str,
    /// The verification run's figure.
    pub verification: f64,
}

/// Runs the allocation. `scenario_text` is the scenario file the `scenario` was compiled
/// from; `progress` is told the number of Monte Carlo evaluations done so far.
///
/// With levers (`allocation.levers`: a model parameter such as the number of pin classes
/// of selective fitting, with candidate values and their costs), every combination of
/// lever values is a scenario of its own whose tolerances are allocated as described in
/// the module documentation; the answer is the combination whose tolerances and lever
/// values together cost least among those verified to meet the target (else among those
/// feasible, else the one closest to the target). Every combination is reported.
pub fn allocate(
    scenario: &Scenario,
    scenario_text: &str,
    output: &str,
    target: Target,
    settings: AllocationSettings,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Allocation, ScenarioError> {
    let levers = &scenario.allocation_levers;
    if levers.is_empty() {
        return allocate_tolerances(scenario, scenario_text, output, target, settings, progress);
    }
    let document: Value = serde_json::from_str(scenario_text)
        .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?;
    let done = std::cell::Cell::new(0usize);
    let mut tried: Vec<(Vec<usize>, Allocation)> = Vec::new();
    for combination in lever_combinations(levers) {
        let mut variant = document.clone();
        set_lever_values(&mut variant, levers, &combination)?;
        let text = variant.to_string();
        let lever_scenario = Scenario::from_json(&text, &scenario.name).map_err(|err| {
            ScenarioError::new(
                err.path,
                format!("{} (with {})", err.message, describe(levers, &combination)),
            )
        })?;
        let before = done.get();
        let allocation =
            allocate_tolerances(&lever_scenario, &text, output, target, settings, &|n| {
                progress(before + n)
            })?;
        done.set(before + allocation.evaluations);
        tried.push((combination, allocation));
    }
    let lever_cost = |combination: &[usize]| -> f64 {
        levers
            .iter()
            .zip(combination)
            .map(|(lever, &i)| lever.costs[i])
            .sum()
    };
    let rank = |status: &str| match status {
        "met" => 0,
        "not verified" => 1,
        _ => 2,
    };
    let options: Vec<LeverOption> = tried
        .iter()
        .map(|(combination, allocation)| LeverOption {
            values: levers
                .iter()
                .zip(combination)
                .map(|(lever, &i)| lever.values[i])
                .collect(),
            lever_cost: lever_cost(combination),
            tolerance_cost: allocation.proposed_cost,
            status: allocation.status(),
            verification: allocation.verification.figure,
        })
        .collect();
    let best = (0..tried.len())
        .min_by(|&a, &b| {
            let key = |i: usize| {
                let (combination, allocation) = &tried[i];
                let status = rank(allocation.status());
                let merit = if status < 2 {
                    allocation.proposed_cost + lever_cost(combination)
                } else {
                    target.excess(allocation.verification.figure)
                };
                (status, merit)
            };
            let (ka, kb) = (key(a), key(b));
            ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
        })
        .expect("at least one lever combination");
    let model_evaluations: u64 = (tried.iter())
        .filter_map(|(_, a)| a.rare.as_ref().map(|r| r.model_evaluations))
        .sum();
    let (combination, mut allocation) = tried.swap_remove(best);
    if let Some(rare) = allocation.rare.as_mut() {
        rare.model_evaluations = model_evaluations;
    }
    allocation.levers = levers
        .iter()
        .zip(&combination)
        .map(|(lever, &i)| LeverChoice {
            name: lever.name.clone(),
            param: lever.target.path.clone(),
            value: lever.values[i],
            cost: lever.costs[i],
        })
        .collect();
    allocation.lever_options = options;
    allocation.evaluations = done.get();
    // The record is of the scenario text the user gave, not of the chosen variant's.
    allocation.scenario_sha256 = scenario.digest.clone();
    Ok(allocation)
}

/// Every combination of lever values, as indices into each lever's values, the first
/// lever varying slowest.
fn lever_combinations(levers: &[spec::Lever]) -> Vec<Vec<usize>> {
    let mut combinations = vec![Vec::new()];
    for lever in levers {
        combinations = combinations
            .into_iter()
            .flat_map(|prefix| {
                (0..lever.values.len()).map(move |i| {
                    let mut next = prefix.clone();
                    next.push(i);
                    next
                })
            })
            .collect();
    }
    combinations
}

fn describe(levers: &[spec::Lever], combination: &[usize]) -> String {
    levers
        .iter()
        .zip(combination)
        .map(|(lever, &i)| {
            format!(
                "{} = {}",
                lever.name,
                rvtol_deviation::Shown(lever.values[i])
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Sets each lever's model parameter in a scenario document to the value `combination`
/// picks.
fn set_lever_values(
    document: &mut Value,
    levers: &[spec::Lever],
    combination: &[usize],
) -> Result<(), ScenarioError> {
    for (lever, &i) in levers.iter().zip(combination) {
        (lever.target.set(document, lever.values[i])).map_err(|err| {
            ScenarioError::new(format!("allocation.levers.{}", lever.name), err.message)
        })?;
    }
    Ok(())
}

/// The allocation of the tolerances alone (the scenario's levers as written).
fn allocate_tolerances(
    scenario: &Scenario,
    scenario_text: &str,
    output: &str,
    target: Target,
    settings: AllocationSettings,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Allocation, ScenarioError> {
    if scenario.allocation.is_empty() {
        return Err(ScenarioError::new(
            "allocation",
            "missing: rvtol allocate needs an allocation section naming the sources that may \
             change, with their bounds and costs (scenarios/README.md)",
        ));
    }
    let output_index = scenario.output_index(output).ok_or_else(|| {
        let names: Vec<&str> = scenario
            .continuous_outputs()
            .into_iter()
            .map(|o| scenario.outputs[o].name.as_str())
            .collect();
        ScenarioError::new(
            "--output",
            format!("no output named {output:?}; outputs: {}", names.join(", ")),
        )
    })?;
    let info = &scenario.outputs[output_index];
    if info.kind != OutputKind::Continuous {
        return Err(ScenarioError::new(
            "--output",
            format!("{output} is an indicator (an event count); allocate a continuous output"),
        ));
    }
    let limits = info.spec;
    let needs = match target.figure {
        TargetFigure::Cp => Some("both a lower and an upper limit"),
        TargetFigure::Cpk | TargetFigure::PpmOut => Some("a lower or an upper limit"),
        _ => None,
    };
    if let Some(needs) = needs {
        let ok = match (target.figure, limits) {
            (TargetFigure::Cp, Some(l)) => l.lower.is_some() && l.upper.is_some(),
            (_, Some(_)) => true,
            (_, None) => false,
        };
        if !ok {
            return Err(ScenarioError::new(
                format!("spec_limits.{output}"),
                format!("the target {} needs {needs}", target.expression()),
            ));
        }
    }
    if settings.rare.is_some() && target.figure != TargetFigure::PpmOut {
        return Err(ScenarioError::new(
            "--rare",
            format!(
                "importance sampling estimates ppm_out targets; {} is a Monte Carlo figure",
                target.expression()
            ),
        ));
    }
    if settings.samples < 100 {
        return Err(ScenarioError::new(
            "--samples",
            "allocation needs at least 100 samples per evaluation",
        ));
    }
    let tail = tail_fraction(&target).filter(|_| settings.rare.is_none());
    if let Some(tail) = tail.map(|f| settings.samples as f64 * f) {
        if tail < 10.0 {
            let needed = (settings.samples as f64 * 10.0 / tail).ceil();
            return Err(ScenarioError::new(
                "--samples",
                format!(
                    "{} samples leave {tail:.1} samples in the tail {} constrains; use at \
                     least {needed} (the default gives about 100)",
                    settings.samples,
                    target.expression()
                ),
            ));
        }
    }
    if settings.seed == settings.verification_seed {
        return Err(ScenarioError::new(
            "--verify-seed",
            "must differ from the optimisation seed",
        ));
    }
    let sources = scenario
        .allocation
        .iter()
        .map(|source| source.with_cost(settings.cost))
        .collect::<Result<Vec<_>, _>>()?;
    let document: Value = serde_json::from_str(scenario_text)
        .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?;
    let problem = Problem {
        document,
        name: &scenario.name,
        digest: &scenario.digest,
        sources,
        output: output_index,
        output_name: output,
        target,
        limits,
        flagged_conform: info.flagged_conform,
        samples: settings.samples,
        bounds: scenario
            .allocation
            .iter()
            .map(|a| (a.min / a.source.current, a.max / a.source.current))
            .collect(),
        progress,
        evaluations: std::cell::Cell::new(0),
        rare: settings.rare,
        sample: std::cell::RefCell::new(None),
        model_evaluations: std::cell::Cell::new(0),
        verified_by: std::cell::Cell::new(None),
    };
    problem.solve(settings, &info.unit)
}

impl Problem<'_> {
    fn solve(&self, settings: AllocationSettings, unit: &str) -> Result<Allocation, ScenarioError> {
        let k = self.sources.len();
        let seed = settings.seed;
        let today = vec![1.0; k];
        if self.rare.is_some() {
            self.recentre(&today, seed)?;
        }
        let current = self.point(&today, seed, false)?;
        let (search, stages) = self.search_in_stages(&current, seed)?;
        let Search {
            best,
            matters,
            common,
            iterations,
        } = search;
        let feasible = best.is_some();
        // Infeasible: report the tightest point (every source at its lower bound).
        let chosen = match best {
            Some(point) => point,
            None => self.point(&self.tightest(), seed, false)?,
        };
        // Rounded as described; if that breaks the constraint (a source rounded to
        // nearest that mattered after all), every source rounded down; else unrounded.
        let mut rounded = self.round(&chosen.factors, &matters);
        let mut proposed = self.point(&rounded, seed, false)?;
        if feasible && proposed.constraint > 0.0 {
            rounded = self.round(&chosen.factors, &vec![true; k]);
            proposed = self.point(&rounded, seed, false)?;
            if proposed.constraint > 0.0 {
                rounded = chosen.factors.clone();
                proposed = chosen.clone();
            }
        }
        let (_, variance_gradient) = self.constraint_gradient(&proposed, seed)?;
        let variance = proposed.evaluation.sd.powi(2);
        let verification = self.point(&rounded, settings.verification_seed, true)?;
        let verified = verification.evaluation.verifies(&self.target);

        let sources = self
            .sources
            .iter()
            .enumerate()
            .map(|(j, source)| SourceAllocation {
                source: source.clone(),
                optimum: chosen.factors[j] * source.source.current,
                proposed: rounded[j] * source.source.current,
                current_cost: source.cost.cost(source.source.current),
                proposed_cost: self.source_cost(j, rounded[j]),
                variance_share: if variance > 0.0 {
                    rounded[j].powi(2) * variance_gradient[j] / variance
                } else {
                    0.0
                },
            })
            .collect::<Vec<_>>();
        let current_cost = sources.iter().map(|s| s.current_cost).sum::<Option<f64>>();
        Ok(Allocation {
            scenario: self.name.to_string(),
            scenario_sha256: self.digest.to_string(),
            spec: self.limits,
            output: self.output_name.to_string(),
            unit: unit.to_string(),
            target: self.target,
            settings,
            proposed_cost: proposed.cost,
            optimum_cost: chosen.cost,
            sources,
            current: current.evaluation,
            proposed: proposed.evaluation,
            verification: verification.evaluation,
            feasible,
            verified,
            current_cost,
            common_scale: common,
            iterations,
            evaluations: self.evaluations.get(),
            levers: Vec::new(),
            lever_options: Vec::new(),
            rare: self.rare.map(|options| {
                let sample = self.sample.borrow();
                let sample = sample.as_ref().expect("built before the first point");
                RareUse {
                    options,
                    stages,
                    points: sample.points(),
                    centred_at: sample.at.clone(),
                    model_evaluations: self.model_evaluations.get(),
                    verified_by: self.verified_by.get().expect("verified above"),
                }
            }),
        })
    }

    /// The search from `current`; with `--rare`, repeated from the point found, on a new
    /// sample around it, while the last sample does not estimate that point about as
    /// precisely as where it was built (at most [`MAX_STAGES`] samples). Also returns the
    /// samples built (1 without `--rare`); the iterations are summed over the stages.
    fn search_in_stages(
        &self,
        current: &Point,
        seed: u64,
    ) -> Result<(Search, usize), ScenarioError> {
        let mut search = self.search(current, seed)?;
        let mut stages = 1;
        while self.rare.is_some() && stages < MAX_STAGES {
            let found = match &search.best {
                Some(point) => point.clone(),
                None => self.point(&self.tightest(), seed, false)?,
            };
            if self.sample_fits(&found) {
                break;
            }
            self.recentre(&found.factors, seed)?;
            stages += 1;
            let start = self.point(&found.factors, seed, false)?;
            let iterations = search.iterations;
            search = self.search(&start, seed)?;
            search.iterations += iterations;
        }
        Ok((search, stages))
    }

    /// The sequential Lagrange allocation from `x`, refined against the estimated
    /// figure, and the common-scaling comparison.
    fn search(&self, x: &Point, seed: u64) -> Result<Search, ScenarioError> {
        let k = self.sources.len();
        let start = self.clamp(&x.factors);
        let mut x = if start == x.factors {
            x.clone()
        } else {
            self.point(&start, seed, false)?
        };
        let mut best: Option<Point> = None;
        let keep = |candidate: &Point, best: &mut Option<Point>| {
            if candidate.constraint <= 0.0 && best.as_ref().is_none_or(|b| candidate.cost < b.cost)
            {
                *best = Some(candidate.clone());
            }
        };
        keep(&x, &mut best);

        let mut iterations = 0;
        let mut weights = self.constraint_gradient(&x, seed)?.0;
        // Trust region (log radius). A step is accepted when it reduces the infeasibility
        // max(h − tol, 0), or keeps it at 0 and lowers the cost; else the region shrinks.
        // tol, half a standard error of the figure, lets iterates sit on the constraint up
        // to Monte Carlo noise; the final refinement makes the answer feasible exactly.
        let mut radius = TRUST_RATIO.ln();
        while iterations < MAX_ITERATIONS && radius >= SETTLED {
            iterations += 1;
            let load: f64 = (0..k).map(|j| weights[j] * x.factors[j].powi(2)).sum();
            let budget = load - x.constraint;
            let boxes: Vec<(f64, f64)> = (0..k)
                .map(|j| {
                    let (lo, hi) = self.bounds[j];
                    let s = x.factors[j];
                    ((s * (-radius).exp()).max(lo), (s * radius.exp()).min(hi))
                })
                .collect();
            let next = self.lagrange(&weights, budget, &boxes);
            let step = next
                .iter()
                .zip(&x.factors)
                .map(|(a, b)| (a / b).ln().abs())
                .fold(0.0, f64::max);
            if step < SETTLED {
                break;
            }
            let candidate = self.point(&next, seed, false)?;
            keep(&candidate, &mut best);
            let tolerance = 0.5 * x.evaluation.standard_error;
            let infeasibility = |p: &Point| (p.constraint - tolerance).max(0.0);
            let better = infeasibility(&candidate) < infeasibility(&x)
                || (infeasibility(&candidate) == 0.0
                    && infeasibility(&x) == 0.0
                    && candidate.cost < x.cost);
            if better {
                x = candidate;
                weights = self.constraint_gradient(&x, seed)?.0;
            } else {
                radius *= 0.5;
            }
        }

        // Refine against the Monte Carlo result: one factor on the sources that matter.
        let matters: Vec<bool> = weights.iter().map(|&w| w > 0.0).collect();
        if let Some((refined, _)) = self.level(&x.factors, &matters, seed)? {
            keep(&refined, &mut best);
        }
        let common = self
            .level(&vec![1.0; k], &vec![true; k], seed)?
            .map(|(p, factor)| {
                keep(&p, &mut best);
                CommonScale {
                    factor,
                    cost: p.cost,
                }
            });

        Ok(Search {
            best,
            matters,
            common,
            iterations,
        })
    }

    /// Every source at its lower bound.
    fn tightest(&self) -> Vec<f64> {
        self.bounds.iter().map(|b| b.0).collect()
    }

    fn clamp(&self, factors: &[f64]) -> Vec<f64> {
        factors
            .iter()
            .zip(&self.bounds)
            .map(|(s, (lo, hi))| s.clamp(*lo, *hi))
            .collect()
    }

    fn source_cost(&self, j: usize, factor: f64) -> f64 {
        let source = &self.sources[j];
        source
            .cost
            .cost(factor * source.source.current)
            .unwrap_or(f64::INFINITY)
    }

    fn total_cost(&self, factors: &[f64]) -> f64 {
        (0..factors.len())
            .map(|j| self.source_cost(j, factors[j]))
            .sum()
    }

    /// The scenario with the tolerances scaled by `factors`.
    fn scenario(&self, factors: &[f64]) -> Result<Scenario, ScenarioError> {
        let document = scaling::scaled_document(&self.document, &self.sources, factors, false)?;
        Scenario::from_json(&document.to_string(), self.name)
            .map_err(|err| ScenarioError::new(err.path, format!("{} (scaled)", err.message)))
    }

    /// Evaluates the target figure at `factors`.
    fn point(
        &self,
        factors: &[f64],
        seed: u64,
        verification: bool,
    ) -> Result<Point, ScenarioError> {
        let scenario = self.scenario(factors)?;
        let evaluation = match self.rare {
            Some(options) => self.importance(&scenario, options, seed, verification)?,
            None => self.monte_carlo(&scenario, seed, verification)?,
        };
        self.evaluations.set(self.evaluations.get() + 1);
        (self.progress)(self.evaluations.get());
        let constraint = self.target.excess(evaluation.figure)
            + MARGIN_Z * self.margin_error(&evaluation, verification);
        Ok(Point {
            factors: factors.to_vec(),
            // A figure without a finite margin (e.g. Cpk of a constant output) cannot be
            // shown to meet the target.
            constraint: if constraint.is_nan() {
                f64::INFINITY
            } else {
                constraint
            },
            cost: self.total_cost(factors),
            evaluation,
        })
    }

    /// The target figure of one Monte Carlo run of `scenario`.
    fn monte_carlo(
        &self,
        scenario: &Scenario,
        seed: u64,
        verification: bool,
    ) -> Result<Evaluation, ScenarioError> {
        let mut result = run_for_output(
            scenario,
            RunSettings {
                samples: self.samples,
                seed,
                exact_percentile_limit: u64::MAX,
                sampling: scenario.sampling,
            },
            self.output,
            &|_| {},
        )?;
        let accumulator = result.outputs.swap_remove(self.output);
        let out = accumulator.out_of_spec(self.flagged_conform);
        // The kept values are the conforming ones; the others lie beyond the limits.
        let hidden_out = accumulator.beyond(self.samples);
        let KeptValues::Values(mut values) = accumulator.kept else {
            unreachable!("allocation runs keep every value");
        };
        values.sort_unstable_by(f64::total_cmp);
        let evaluation = evaluate_figure(
            self.target.figure,
            &values,
            &accumulator.moments,
            self.limits,
            OutOfSpec {
                samples: self.samples,
                hidden: hidden_out,
                counted: verification.then_some(out),
            },
        );
        evaluation.ok_or_else(|| {
            ScenarioError::new(
                "--output",
                "fewer than 2 finite values: nothing to allocate against",
            )
        })
    }

    /// The out-of-spec ppm of `scenario` by importance sampling: on the current sample's
    /// points in the optimisation; on a sample of its own, built with the verification
    /// seed around the scenario's own centres, in the verification.
    fn importance(
        &self,
        scenario: &Scenario,
        options: RareOptions,
        seed: u64,
        verification: bool,
    ) -> Result<Evaluation, ScenarioError> {
        let fresh;
        let sample = self.sample.borrow();
        let sample = match verification {
            true => {
                fresh = RareSample::build(scenario, self.output, seed, options, Vec::new())?;
                self.count(fresh.evaluations);
                &fresh
            }
            false => sample.as_ref().expect("built before the first point"),
        };
        let (mut evaluation, evaluations) =
            sample.evaluate(scenario, self.output, self.limits, verification)?;
        self.count(evaluations);
        if verification {
            self.verified_by.set(Some(Method::Importance));
            if !sample.trusted() {
                let evaluations =
                    rare::by_subset(scenario, self.output, seed, options, &mut evaluation)?;
                self.count(evaluations);
                self.verified_by.set(Some(Method::Subset));
            }
        }
        Ok(evaluation)
    }

    /// The standard error the constraint's margin uses: the figure's own; with `--rare`
    /// in the optimisation, the figure times the relative standard error of its sample
    /// where the sample was built. An importance-sampling standard error is a sample
    /// quantity that jumps as points cross the threshold; the relative one of the sample's
    /// centre moves with the figure smoothly, and holds near the centre (the allocation
    /// builds a new sample when the point it finds is estimated less precisely,
    /// [`RareSample::fits`]).
    fn margin_error(&self, evaluation: &Evaluation, verification: bool) -> f64 {
        let sample = self.sample.borrow();
        match sample.as_ref().filter(|_| !verification) {
            Some(sample) => evaluation.figure * sample.relative_error(),
            None => evaluation.standard_error,
        }
    }

    /// Counts model evaluations.
    fn count(&self, evaluations: u64) {
        self.model_evaluations
            .set(self.model_evaluations.get() + evaluations);
    }

    /// `--rare`: a new sample of importance sampling around the event's centres at the
    /// tolerance factors `at`.
    fn recentre(&self, at: &[f64], seed: u64) -> Result<(), ScenarioError> {
        let options = self.rare.expect("only with --rare");
        let scenario = self.scenario(at)?;
        let sample = RareSample::build(&scenario, self.output, seed, options, at.to_vec())?;
        self.count(sample.evaluations);
        *self.sample.borrow_mut() = Some(sample);
        Ok(())
    }

    /// Whether the current sample estimates `point`'s figure as precisely as it was built
    /// to (else the allocation builds a new one around it).
    fn sample_fits(&self, point: &Point) -> bool {
        let sample = self.sample.borrow();
        let sample = sample.as_ref().expect("built before the first point");
        sample.at == point.factors || sample.fits(&point.evaluation)
    }

    /// Forward differences of the constraint and of the output variance with respect to
    /// each u_k = s_k².
    fn constraint_gradient(
        &self,
        x: &Point,
        seed: u64,
    ) -> Result<(Vec<f64>, Vec<f64>), ScenarioError> {
        let k = x.factors.len();
        let mut constraint = vec![0.0; k];
        let mut variance = vec![0.0; k];
        for j in 0..k {
            let (lo, hi) = self.bounds[j];
            let s = x.factors[j];
            if hi <= lo {
                continue; // a fixed source: no direction to move
            }
            // Central differences where both steps fit (the sd is concave in u, so a
            // one-sided difference would bias the weights), else one step to the farther
            // side, never beyond the bounds.
            let (up, down) = (s * (1.0 + DIFFERENCE_STEP), s * (1.0 - DIFFERENCE_STEP));
            let steps: Vec<f64> = if up <= hi && down >= lo {
                vec![up, down]
            } else if up <= hi {
                vec![up]
            } else if down >= lo {
                vec![down]
            } else if hi - s >= s - lo {
                vec![hi]
            } else {
                vec![lo]
            };
            let mut evaluated = Vec::with_capacity(2);
            for &stepped in &steps {
                let mut factors = x.factors.clone();
                factors[j] = stepped;
                evaluated.push((stepped, self.point(&factors, seed, false)?));
            }
            let ((u1, p1), (u0, p0)) = match evaluated.as_slice() {
                [(a, pa), (b, pb)] => ((a * a, pa), (b * b, pb)),
                [(a, pa)] => ((a * a, pa), (s * s, x)),
                _ => unreachable!("one or two steps"),
            };
            constraint[j] = (p1.constraint - p0.constraint) / (u1 - u0);
            variance[j] = (p1.evaluation.sd.powi(2) - p0.evaluation.sd.powi(2)) / (u1 - u0);
        }
        Ok((constraint, variance))
    }

    /// Minimises Σ c_k(s_k) subject to Σ w_k·s_k² ≤ budget, s_k in its box: per source the
    /// Lagrange condition, and bisection on the multiplier λ. When even the tightest
    /// point of the boxes misses the budget, returns that point.
    fn lagrange(&self, weights: &[f64], budget: f64, boxes: &[(f64, f64)]) -> Vec<f64> {
        let solve = |lambda: f64| -> Vec<f64> {
            (0..weights.len())
                .map(|j| {
                    if weights[j] <= 0.0 {
                        // Loosening cannot hurt the target: the cheapest point of the box.
                        self.source_argmin(j, 0.0, boxes[j])
                    } else if lambda.is_infinite() {
                        boxes[j].0
                    } else {
                        self.source_argmin(j, lambda * weights[j], boxes[j])
                    }
                })
                .collect()
        };
        let load = |s: &[f64]| -> f64 { s.iter().zip(weights).map(|(s, w)| w * s * s).sum() };
        let free = solve(0.0);
        if load(&free) <= budget {
            return free;
        }
        let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
        while load(&solve(hi)) > budget {
            lo = hi;
            hi *= 16.0;
            if hi > 1e300 {
                return solve(f64::INFINITY);
            }
        }
        if lo == 0.0 {
            lo = hi / 16.0;
            while lo > 1e-300 && load(&solve(lo)) <= budget {
                hi = lo;
                lo /= 16.0;
            }
        }
        for _ in 0..100 {
            let mid = (lo * hi).sqrt();
            if load(&solve(mid)) > budget {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi / lo < 1.0 + 1e-12 {
                break;
            }
        }
        solve(hi)
    }

    /// argmin over s in `bounds` of c_k(s·t_k) + penalty·s² (a grid, then golden section
    /// around the best grid point; no convexity needed).
    fn source_argmin(&self, j: usize, penalty: f64, (lo, hi): (f64, f64)) -> f64 {
        if hi <= lo {
            return lo;
        }
        let phi = |s: f64| self.source_cost(j, s) + penalty * s * s;
        const GRID: usize = 128;
        let ratio = (hi / lo).ln();
        let at = |i: usize| lo * (ratio * i as f64 / GRID as f64).exp();
        let mut best = 0;
        let mut best_value = phi(lo);
        for i in 1..=GRID {
            let v = phi(at(i));
            if v < best_value {
                best = i;
                best_value = v;
            }
        }
        let (mut a, mut b) = (at(best.saturating_sub(1)), at((best + 1).min(GRID)));
        let golden = 0.5 * (5f64.sqrt() - 1.0);
        let mut c = b - golden * (b - a);
        let mut d = a + golden * (b - a);
        for _ in 0..80 {
            if phi(c) < phi(d) {
                b = d;
            } else {
                a = c;
            }
            c = b - golden * (b - a);
            d = a + golden * (b - a);
            if b - a <= 1e-12 * b {
                break;
            }
        }
        let s = 0.5 * (a + b);
        if phi(s) <= best_value {
            s
        } else {
            at(best)
        }
    }

    /// Scales the sources where `scaled` is true by one factor γ (clamped to their
    /// bounds), and bisects γ on the Monte Carlo constraint to the loosest feasible point.
    /// None when even the tightest γ misses the target.
    fn level(
        &self,
        base: &[f64],
        scaled: &[bool],
        seed: u64,
    ) -> Result<Option<(Point, f64)>, ScenarioError> {
        if !scaled.iter().any(|&b| b) {
            let p = self.point(base, seed, false)?;
            return Ok((p.constraint <= 0.0).then_some((p, 1.0)));
        }
        let at = |gamma: f64| -> Vec<f64> {
            base.iter()
                .zip(scaled)
                .zip(&self.bounds)
                .map(|((s, on), (lo, hi))| if *on { (s * gamma).clamp(*lo, *hi) } else { *s })
                .collect()
        };
        let range = |pick: fn(&(f64, f64)) -> f64, fold: fn(f64, f64) -> f64, init: f64| {
            base.iter()
                .zip(scaled)
                .zip(&self.bounds)
                .filter(|((_, on), _)| **on)
                .map(|((s, _), b)| pick(b) / s)
                .fold(init, fold)
        };
        let gamma_lo = range(|b| b.0, f64::min, f64::INFINITY);
        let gamma_hi = range(|b| b.1, f64::max, 0.0);
        let loosest = self.point(&at(gamma_hi), seed, false)?;
        if loosest.constraint <= 0.0 {
            return Ok(Some((loosest, gamma_hi)));
        }
        let tightest = self.point(&at(gamma_lo), seed, false)?;
        if tightest.constraint > 0.0 {
            return Ok(None);
        }
        let (mut lo, mut hi) = (gamma_lo, gamma_hi);
        let mut feasible = (tightest, gamma_lo);
        while hi / lo > 1.0 + 1e-4 {
            let mid = (lo * hi).sqrt();
            let p = self.point(&at(mid), seed, false)?;
            if p.constraint <= 0.0 {
                lo = mid;
                feasible = (p, mid);
            } else {
                hi = mid;
            }
        }
        Ok(Some(feasible))
    }

    /// Rounds each proposed tolerance to [`SIGNIFICANT_DIGITS`] digits: down where the
    /// source matters (so the rounding never loosens the design), to nearest elsewhere;
    /// then back into the bounds.
    fn round(&self, factors: &[f64], matters: &[bool]) -> Vec<f64> {
        factors
            .iter()
            .enumerate()
            .map(|(j, &s)| {
                let source = &self.sources[j];
                let t = s * source.source.current;
                // t = m·10^e with 100 ≤ m < 1000 (three digits); scaling by 10^e rather
                // than its inverse stays finite for any normal t.
                let unit = 10f64.powi(t.log10().floor() as i32 - (SIGNIFICANT_DIGITS - 1));
                let mantissa = t / unit;
                let rounded = if matters[j] {
                    // A hair of slack so that exact decimals are not pushed one step down.
                    (mantissa * (1.0 + 1e-12)).floor()
                } else {
                    mantissa.round()
                } * unit;
                let rounded = if rounded.is_finite() && rounded > 0.0 {
                    rounded
                } else {
                    t
                };
                (rounded.clamp(source.min, source.max) / source.source.current)
                    .clamp(self.bounds[j].0, self.bounds[j].1)
            })
            .collect()
    }
}

/// The scenario file with the proposed tolerances written in (its `allocation` section
/// kept), pretty-printed: a scenario users can run, check and commit.
pub fn proposal_document(
    scenario_text: &str,
    allocation: &Allocation,
) -> Result<String, ScenarioError> {
    let mut document: Value = serde_json::from_str(scenario_text)
        .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?;
    for lever in &allocation.levers {
        let target =
            rvtol_engine::scenario::design::DesignValue::parse(scenario_text, &lever.param)
                .map_err(|message| ScenarioError::new(&lever.param, message))?;
        target.set(&mut document, lever.value)?;
    }
    let sources: Vec<AllocatableSource> = allocation
        .sources
        .iter()
        .map(|s| s.source.clone())
        .collect();
    let factors: Vec<f64> = allocation
        .sources
        .iter()
        .map(|s| s.proposed / s.source.source.current)
        .collect();
    let mut scaled = scaling::scaled_document(&document, &sources, &factors, true)?;
    mark_provenance(&mut scaled, allocation);
    let mut text = serde_json::to_string_pretty(&scaled)
        .map_err(|err| ScenarioError::new("(proposal)", err.to_string()))?;
    text.push('\n');
    Ok(text)
}

/// Names a proposal for what it is: `NAME-allocated`, so that its reports are not taken
/// for the original's (`rvtol report` composes one scenario's reports), and a
/// description that opens with where it came from (the rvtol version, the scenario, the
/// output and target, the seeds, the outcome) before the original's.
fn mark_provenance(document: &mut Value, allocation: &Allocation) {
    let Some(fields) = document.as_object_mut() else {
        return;
    };
    let original = fields
        .get("description")
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_string();
    let outcome = match (allocation.feasible, allocation.verified) {
        (false, _) => "infeasible",
        (true, false) => "not verified",
        (true, true) => "met",
    };
    let estimator = match &allocation.rare {
        Some(rare) => format!(
            "importance sampling, --rare --precision {}",
            rare.options.precision
        ),
        None => format!("{} samples", allocation.settings.samples),
    };
    let provenance = format!(
        "Tolerances proposed by rvtol {} allocate from scenario {:?} (text sha256 {}): {} {} (seed {}, verification seed {}, {estimator}): {outcome}.",
        env!("CARGO_PKG_VERSION"),
        allocation.scenario,
        allocation.scenario_sha256,
        allocation.output,
        allocation.target.expression(),
        allocation.settings.seed,
        allocation.settings.verification_seed,
    );
    let description = match original.is_empty() {
        true => provenance,
        false => format!("{provenance} {original}"),
    };
    fields.insert(
        "name".into(),
        Value::from(format!("{}-allocated", allocation.scenario)),
    );
    fields.insert("description".into(), Value::from(description));
}

/// The target figure of a sorted sample, its standard error and 95 % interval.
/// `counted_out`: the number of samples out of spec, for a verification run's ppm (the
/// optimisation uses the continuous interpolated version instead).
/// What a run says about the samples out of spec, for [`evaluate_figure`].
#[derive(Debug, Clone, Copy)]
struct OutOfSpec {
    /// Samples drawn.
    samples: u64,
    /// Samples that do not conform although their values do not show it (not finite,
    /// excluded, flagged non-conforming): beyond the limits, not among the sorted values.
    hidden: u64,
    /// The counted samples out of spec, for the verification; the optimisation uses the
    /// interpolated count instead.
    counted: Option<u64>,
}

fn evaluate_figure(
    figure: TargetFigure,
    sorted: &[f64],
    moments: &Moments,
    limits: Option<SpecLimits>,
    out_of_spec: OutOfSpec,
) -> Option<Evaluation> {
    let (mean, sd) = (moments.mean, moments.sd());
    let (excess_kurtosis, skewness) = (moments.excess_kurtosis(), moments.skewness());
    let n = sorted.len();
    // Where the samples beyond the limits sit among the values (rvtol_engine::stats::conformity).
    let beyond = (out_of_spec.hidden as usize, Placement::of(limits));
    // A percentile reads the samples beyond the limits too (all of them, at worst).
    let among = match figure {
        TargetFigure::Percentile(_) => n as u64 + out_of_spec.hidden,
        _ => n as u64,
    };
    if among < 2 {
        return None;
    }
    let nf = n as f64;
    let sd_relative_se = if sd > 0.0 {
        moments.sd_standard_error() / sd
    } else {
        0.0
    };
    let symmetric = |value: f64, se: f64| {
        let [low, high] = symmetric95(value, se);
        (value, se, (low, high))
    };
    let (value, se, interval) = match figure {
        TargetFigure::Percentile(p) => {
            let (value, low, high) = percentile_of_sorted_with_interval(sorted, beyond, p, Z95)?;
            // Beyond the limits: no spread to speak of (the constraint is +∞ anyway).
            let se = if value.is_infinite() {
                0.0
            } else {
                (high - low) / (2.0 * Z95)
            };
            (value, se, (low, high))
        }
        TargetFigure::Mean => symmetric(mean, moments.mean_standard_error()),
        TargetFigure::Sd => symmetric(sd, moments.sd_standard_error()),
        // The indices are undefined when samples are out of spec in a way the values do not
        // show (as in the run report): no Cp or Cpk target can be met then.
        TargetFigure::Cp | TargetFigure::Cpk if out_of_spec.hidden > 0 => {
            return Some(Evaluation {
                figure: f64::NAN,
                standard_error: f64::NAN,
                interval: (f64::NAN, f64::NAN),
                n: moments.n,
                mean,
                sd,
                quantiles: outline(sorted, beyond),
            });
        }
        TargetFigure::Cp => {
            let cp = capability_from_moments(mean, sd, limits?).cp?;
            symmetric(cp, cp * sd_relative_se)
        }
        TargetFigure::Cpk => {
            let limits = limits?;
            let cpk = capability_from_moments(mean, sd, limits).cpk?;
            let upper_side = cpk_on_upper_side(mean, limits);
            symmetric(
                cpk,
                cpk_standard_error(cpk, upper_side, n as u64, skewness, excess_kurtosis),
            )
        }
        TargetFigure::PpmOut => {
            let limits = limits?;
            // Among every sample drawn: the finite values out of the limits, plus the
            // samples that do not conform although their values do not show it.
            let samples = out_of_spec.samples;
            let fraction = match out_of_spec.counted {
                Some(out) => out as f64 / samples as f64,
                None => {
                    let below = limits.lower.map_or(0.0, |l| interpolated_cdf(sorted, l));
                    let above = limits
                        .upper
                        .map_or(0.0, |u| 1.0 - interpolated_cdf(sorted, u));
                    ((below + above) * nf + out_of_spec.hidden as f64) / samples as f64
                }
            };
            let se = 1e6 * proportion_standard_error(fraction, samples);
            let interval = match out_of_spec.counted {
                Some(out) => {
                    let e = out_of_spec_interval(out, samples, CONFIDENCE);
                    (e.lower * 1e6, e.upper * 1e6)
                }
                None => {
                    let [low, high] = symmetric95(fraction * 1e6, se);
                    (low.max(0.0), high)
                }
            };
            (fraction * 1e6, se, interval)
        }
    };
    Some(Evaluation {
        figure: value,
        standard_error: se,
        interval,
        n: moments.n,
        mean,
        sd,
        quantiles: outline(sorted, beyond),
    })
}

/// The empirical distribution function interpolated between order statistics (the
/// inverse of the type-7 percentile): continuous in the sample values, so the fraction
/// out of spec moves smoothly as the tolerances do.
fn interpolated_cdf(sorted: &[f64], x: f64) -> f64 {
    let n = sorted.len();
    if x < sorted[0] {
        return 0.0;
    }
    if x >= sorted[n - 1] {
        return 1.0;
    }
    let j = sorted.partition_point(|&v| v <= x) - 1;
    let width = sorted[j + 1] - sorted[j];
    let fraction = if width > 0.0 {
        (x - sorted[j]) / width
    } else {
        0.0
    };
    (j as f64 + fraction) / (n - 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use rvtol_engine::stats::percentile_type7_of_sorted;

    #[test]
    fn met_needs_the_whole_interval_on_the_right_side() {
        // Issue example: P99.865 1.4791 .. 1.5088 against ≤ 1.5 is not verified, although
        // its figure meets it; an interval within the target is; an undefined figure is not.
        let at = |figure: f64, interval: (f64, f64)| Evaluation {
            figure,
            standard_error: 0.0,
            interval,
            n: 1000,
            mean: 0.0,
            sd: 0.0,
            quantiles: Vec::new(),
        };
        let at_most = Target::parse("p99.865 <= 1.5").unwrap();
        assert!(!at(1.49, (1.4791, 1.5088)).verifies(&at_most));
        assert!(at(1.49, (1.4791, 1.4999)).verifies(&at_most));
        assert!(!at(1.51, (1.49, 1.52)).verifies(&at_most));
        assert!(!at(f64::NAN, (f64::NAN, f64::NAN)).verifies(&at_most));
        let at_least = Target::parse("cpk >= 1.33").unwrap();
        assert!(!at(1.35, (1.32, 1.38)).verifies(&at_least));
        assert!(at(1.40, (1.34, 1.46)).verifies(&at_least));
        // The margin: an optimum at −z·SE fails verification by noise with probability
        // Φ(−(z − 1.96)/√2) = Φ(−3/√2) ≈ 1.7 %.
        assert!((MARGIN_Z - Z95 - 3.0).abs() < 1e-15);
    }

    #[test]
    fn interpolated_cdf_inverts_type7() {
        let sorted: Vec<f64> = (0..101).map(|i| (i as f64).powf(1.5)).collect();
        for p in [3.0, 17.5, 50.0, 99.2] {
            let x = percentile_type7_of_sorted(&sorted, p).unwrap();
            assert!((interpolated_cdf(&sorted, x) - p / 100.0).abs() < 1e-12);
        }
        assert_eq!(interpolated_cdf(&sorted, -1.0), 0.0);
        assert_eq!(interpolated_cdf(&sorted, 1e9), 1.0);
    }

    #[test]
    fn default_samples_reach_the_tail() {
        let t = Target::parse("p99.865 <= 1").unwrap();
        assert_eq!(default_samples(&t), 200_000);
        let t = Target::parse("ppm_out <= 10").unwrap();
        assert_eq!(default_samples(&t), 4_000_000);
        let t = Target::parse("ppm_out <= 200").unwrap();
        assert_eq!(default_samples(&t), 500_000);
    }
}
