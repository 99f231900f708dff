//! The ppm constraint of `rvtol allocate --rare`: the out-of-spec probability of a scaled
//! scenario estimated by importance sampling ([`crate::rare`]) with common random numbers.
//!
//! The tolerances scale the map from the standard normal space onto the deviations, never
//! the normal space itself: points z drawn once from the defensive mixture q around the
//! event's centres, each with its weight w(z) = φ(z)/q(z), estimate the probability of
//! every scaled scenario s without bias,
//!
//!   P̂(s) = (1/N)·Σ w(zᵢ)·1[g_s(zᵢ) > 0],
//!
//! whatever the centres are (they set the variance only). The same points for every s make
//! P̂ a deterministic function of the tolerances, as the common seed does for a Monte Carlo
//! figure. In the optimisation the indicator of the point nearest above the threshold is
//! interpolated linearly in the score between its neighbours below and above (the weighted
//! analogue of the interpolated empirical distribution the Monte Carlo figure uses), so
//! that P̂ moves continuously with the tolerances; the verification counts.
//!
//! The centres are FORM's design points (or the conditional means) of the scenario at the
//! factors where the sample is built; the sample's size N is what importance sampling
//! needs there to reach the asked precision. As the optimisation tightens the tolerances
//! the event moves away from those centres and the estimate loses precision; the
//! allocation then builds a new sample around the point it found ([`RareSample::fits`]).

use rayon::prelude::*;
use rvtol_engine::figures::{symmetric95, Z95};
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_engine::stats::conformity::Placement;
use rvtol_engine::stats::SpecLimits;

use super::{Evaluation, QUANTILE_LEVELS};
use crate::rare::importance::{self, Mixture, Sums, BATCH};
use crate::rare::limit::LimitState;
use crate::rare::{self as tail, subset, Budget, Estimate, Event, Method, RareSettings};

/// How `allocate --rare` estimates its constraint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RareOptions {
    /// The 95 % interval's half width, as a share of the estimate, a sample is built for.
    pub precision: f64,
    /// Points a sample may have at most.
    pub max_evaluations: u64,
    /// Points per level of the subset simulation that finds a centre where FORM does not
    /// converge.
    pub level_samples: usize,
}

/// Batches drawn and evaluated together.
const GROUP: u64 = 16;

/// A sample's estimate fits a point when its relative standard error there is within this
/// factor (either way) of the one it has where it was built.
const FITS: f64 = 1.25;

/// Points of the normal space drawn once around the event's centres, with their weights.
#[derive(Debug, Clone, PartialEq)]
pub struct RareSample {
    mixture: Mixture,
    seed: u64,
    batches: u64,
    /// The tolerance factors whose scenario the centres were found on.
    pub at: Vec<f64>,
    /// Model evaluations spent building it (the centres' search and the sizing run).
    pub evaluations: u64,
    /// The importance-sampling estimate where it was built.
    pub estimate: Estimate,
}

impl RareSample {
    /// A sample for `scenario` (the tolerances at factors `at`): the centres of its event
    /// out of spec on `output`, and as many batches of points as importance sampling needs
    /// there to reach the asked precision (within the budget). A side whose event holds at
    /// the nominal point has the origin as its centre (plain Monte Carlo there).
    pub fn build(
        scenario: &Scenario,
        output: usize,
        seed: u64,
        options: RareOptions,
        at: Vec<f64>,
    ) -> Result<RareSample, ScenarioError> {
        let quiet = |_: u64| {};
        let budget = Budget {
            precision: options.precision,
            max_evaluations: options.max_evaluations,
        };
        let settings = RareSettings {
            seed,
            output,
            event: Event::OutOfSpec,
            methods: vec![Method::Importance],
            budget,
            level_samples: options.level_samples,
            // A sample the model cannot evaluate is out of spec, as in a run.
            max_non_finite: 1.0,
        };
        let mut evaluations = 0;
        let mut centres = Vec::new();
        for side in tail::search_sides(scenario, &settings, &quiet)? {
            evaluations += side.evaluations;
            let mut limit = LimitState::new(scenario, output, side.event, &quiet)?;
            let origin = vec![0.0; limit.dims()];
            match side.centre {
                Ok((u, _)) => centres.push(u),
                _ if limit.scores(&origin)[0] > 0.0 => centres.push(origin),
                Err(why) => {
                    return Err(ScenarioError::new(
                        "--rare",
                        format!(
                            "no centre to sample around on {} of {}: {why}",
                            tail::event_text(side.event),
                            scenario.outputs[output].name
                        ),
                    ))
                }
            }
            evaluations += limit.evaluations;
        }
        let mut limit = LimitState::new(scenario, output, Event::OutOfSpec, &quiet)?;
        let estimate = importance::estimate(&mut limit, &centres, seed, &budget);
        Ok(RareSample {
            mixture: Mixture::new(&centres, limit.dims()),
            seed,
            batches: estimate.evaluations / BATCH as u64,
            at,
            evaluations: evaluations + estimate.evaluations,
            estimate,
        })
    }

    /// The relative standard error of the estimate where the sample was built (1 when it
    /// saw no event there).
    pub fn relative_error(&self) -> f64 {
        let p = self.estimate.probability;
        match p > 0.0 {
            true => (self.estimate.interval[1] - p) / Z95 / p,
            false => 1.0,
        }
    }

    /// Whether importance sampling where the sample was built can be trusted: it reached
    /// its precision, with no single point carrying much of it.
    pub fn trusted(&self) -> bool {
        self.estimate.reached && self.estimate.warning.is_none()
    }

    /// Points in the sample.
    pub fn points(&self) -> u64 {
        self.batches * BATCH as u64
    }

    /// Whether the sample estimates `evaluation`'s figure about as precisely as where it
    /// was built: its relative standard error within a factor [`FITS`] of that one. The
    /// margin of the optimisation uses the built one: a point estimated less precisely
    /// would get too small a margin, one estimated more precisely too large a margin.
    pub fn fits(&self, evaluation: &Evaluation) -> bool {
        let (relative, built) = (
            evaluation.standard_error / evaluation.figure,
            self.relative_error(),
        );
        evaluation.figure > 0.0 && relative <= FITS * built && relative >= built / FITS
    }

    /// The out-of-spec ppm of `scenario` (the tolerances scaled) on the sample's points:
    /// counted when `counted`, else with the threshold's neighbour interpolated; its
    /// standard error and 95 % interval; and the output's mean, sd and outline from the
    /// weighted points (self-normalised). `limits` are the output's spec limits. Also
    /// returns the model evaluations made.
    pub fn evaluate(
        &self,
        scenario: &Scenario,
        output: usize,
        limits: Option<SpecLimits>,
        counted: bool,
    ) -> Result<(Evaluation, u64), ScenarioError> {
        let quiet = |_: u64| {};
        let mut limit = LimitState::new(scenario, output, Event::OutOfSpec, &quiet)?;
        let dims = limit.dims().max(1);
        let mut weighted = Vec::with_capacity(self.points() as usize);
        // Batches in groups, each batch drawn and weighted in a task of its own (its
        // points are those of its stream, whichever thread draws them).
        let mut first = 0;
        while first < self.batches {
            let last = (first + GROUP).min(self.batches);
            let drawn: Vec<(Vec<f64>, Vec<f64>)> = (first..last)
                .into_par_iter()
                .map(|batch| {
                    let mut points = vec![0.0; BATCH * dims];
                    self.mixture.draw(self.seed, batch, &mut points);
                    let weights = points.chunks_exact(dims).map(|p| self.mixture.weight(p));
                    let weights = weights.collect();
                    (points, weights)
                })
                .collect();
            let points: Vec<f64> = drawn.iter().flat_map(|d| d.0.iter().copied()).collect();
            let pairs = limit.evaluate(&points);
            let weights = drawn.iter().flat_map(|d| d.1.iter().copied());
            for ((value, score), weight) in pairs.into_iter().zip(weights) {
                weighted.push(Weighted {
                    value,
                    score,
                    weight,
                });
            }
            first = last;
        }
        let evaluation =
            evaluation(&weighted, counted, Placement::of(limits)).ok_or_else(|| {
                ScenarioError::new(
                    "--output",
                    "fewer than 2 finite values: nothing to allocate against",
                )
            })?;
        Ok((evaluation, limit.evaluations))
    }
}

/// The out-of-spec ppm of `scenario` by subset simulation (the verification's estimate
/// where importance sampling cannot be trusted: it assumes nothing about where the event
/// lies): its figure, standard error and 95 % interval written into `evaluation`, whose
/// mean, sd and outline stay those of the weighted points; and the model evaluations.
pub fn by_subset(
    scenario: &Scenario,
    output: usize,
    seed: u64,
    options: RareOptions,
    evaluation: &mut Evaluation,
) -> Result<u64, ScenarioError> {
    let quiet = |_: u64| {};
    let mut limit = LimitState::new(scenario, output, Event::OutOfSpec, &quiet)?;
    let budget = Budget {
        precision: options.precision,
        max_evaluations: options.max_evaluations,
    };
    let estimate = subset::estimate(&mut limit, options.level_samples, seed, &budget)
        .map_err(|why| ScenarioError::new("--rare", format!("the verification: {why}")))?;
    let [low, high] = estimate.interval;
    evaluation.figure = 1e6 * estimate.probability;
    evaluation.standard_error = 1e6 * (high - low) / (2.0 * Z95);
    evaluation.interval = (1e6 * low, 1e6 * high);
    Ok(limit.evaluations)
}

/// One point's output value (NaN when it has none), score and weight.
#[derive(Debug, Clone, Copy)]
struct Weighted {
    value: f64,
    score: f64,
    weight: f64,
}

/// The figures of a weighted sample (None with fewer than two finite values).
fn evaluation(points: &[Weighted], counted: bool, placement: Placement) -> Option<Evaluation> {
    let mut sums = Sums::default();
    for p in points {
        sums.push((p.score > 0.0).then_some(p.weight));
    }
    let standard_error = sums.standard_error();
    let probability = match counted {
        true => sums.mean(),
        false => (sums.sum - interpolated_share(points)) / points.len() as f64,
    };
    let [low, high] = symmetric95(1e6 * probability, 1e6 * standard_error);
    let Body {
        mean,
        sd,
        quantiles,
    } = body(points, placement)?;
    Some(Evaluation {
        figure: 1e6 * probability,
        standard_error: 1e6 * standard_error,
        interval: (low.max(0.0), high),
        n: points.len() as u64,
        mean,
        sd,
        quantiles,
    })
}

/// The part of the weight of the point nearest above the threshold (score 0) that the
/// linear interpolation between it and the nearest point below takes off the count:
/// w·(0 − s₋)/(s₊ − s₋). Zero when either neighbour is missing or infinite.
fn interpolated_share(points: &[Weighted]) -> f64 {
    let below = (points.iter())
        .filter(|p| p.score <= 0.0)
        .map(|p| p.score)
        .fold(f64::NEG_INFINITY, f64::max);
    let above = (points.iter())
        .filter(|p| p.score > 0.0)
        .min_by(|a, b| a.score.total_cmp(&b.score));
    match above {
        Some(p) if below.is_finite() && p.score.is_finite() => {
            p.weight * (0.0 - below) / (p.score - below)
        }
        _ => 0.0,
    }
}

/// The self-normalised weighted mean and sd of the finite values, and their outline: the
/// weighted inverse distribution function at [`QUANTILE_LEVELS`], the points beyond the
/// limits that their values do not show (flagged, excluded, not finite: score +∞) placed
/// as a conformity judgement places them (±∞ where a level reads one).
fn body(points: &[Weighted], placement: Placement) -> Option<Body> {
    let hidden = |p: &Weighted| p.score == f64::INFINITY || p.value.is_nan();
    let mut kept: Vec<(f64, f64)> = (points.iter())
        .filter(|p| !hidden(p))
        .map(|p| (p.value, p.weight))
        .collect();
    if kept.len() < 2 {
        return None;
    }
    let finite = points.iter().filter(|p| p.value.is_finite());
    let total: f64 = finite.clone().map(|p| p.weight).sum();
    let mean = finite.clone().map(|p| p.weight * p.value).sum::<f64>() / total;
    let variance = finite
        .map(|p| p.weight * (p.value - mean).powi(2))
        .sum::<f64>()
        / total;
    kept.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let hidden_weight: f64 = points.iter().filter(|p| hidden(p)).map(|p| p.weight).sum();
    let all = kept.iter().map(|k| k.1).sum::<f64>() + hidden_weight;
    let quantiles = QUANTILE_LEVELS
        .iter()
        .map(|&p| {
            let level = p / 100.0 * all;
            let above = placement.above(p);
            // The hidden weight first (below every value) or last (above).
            let mut cumulative = if above { 0.0 } else { hidden_weight };
            if cumulative >= level && hidden_weight > 0.0 {
                return (p, placement.beyond_value(p));
            }
            for &(value, weight) in &kept {
                cumulative += weight;
                if cumulative >= level {
                    return (p, value);
                }
            }
            (p, placement.beyond_value(p))
        })
        .collect();
    Some(Body {
        mean,
        sd: variance.sqrt(),
        quantiles,
    })
}

/// The output's distribution as the weighted points give it.
struct Body {
    mean: f64,
    sd: f64,
    /// (level %, value) at [`QUANTILE_LEVELS`].
    quantiles: Vec<(f64, f64)>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(value: f64, score: f64, weight: f64) -> Weighted {
        Weighted {
            value,
            score,
            weight,
        }
    }

    #[test]
    fn interpolation_is_continuous_as_a_point_crosses_the_threshold() {
        // Scores −1 and s (s > 0 crossing to 0): the interpolated count → the count
        // without the crossing point as s → 0+, and the full count far above.
        let at = |s: f64| {
            let points = [point(0.0, -1.0, 1.0), point(1.0, s, 2.0)];
            let sum: f64 = points
                .iter()
                .filter(|p| p.score > 0.0)
                .map(|p| p.weight)
                .sum();
            sum - interpolated_share(&points)
        };
        assert!(at(1e-12) < 1e-11, "{}", at(1e-12));
        // s = 1: half the way from −1 to 1 lies below 0: half the weight counts.
        assert!((at(1.0) - 1.0).abs() < 1e-15);
        assert!((at(1e12) - 2.0).abs() < 1e-11);
    }

    #[test]
    fn weighted_figures_of_equal_weights_are_the_plain_ones() {
        // Four points of weight 1, one in the event: P = 1/4, SE = sqrt(p(1−p)/(n−1)·…)
        // from the sample variance of the indicator: var = (1/4 − 1/16)·4/3 = 1/4.
        let points = [
            point(1.0, -3.0, 1.0),
            point(2.0, -2.0, 1.0),
            point(3.0, -1.0, 1.0),
            point(4.0, 0.5, 1.0),
        ];
        let e = evaluation(&points, true, Placement::Above).unwrap();
        assert!((e.figure - 250_000.0).abs() < 1e-9);
        assert!((e.standard_error - 1e6 * (0.25f64 / 4.0).sqrt()).abs() < 1e-6);
        assert!((e.mean - 2.5).abs() < 1e-15);
        assert!((e.sd - 1.25f64.sqrt()).abs() < 1e-15);
        // The inverse distribution function: P50 is the second value, P99.865 the last.
        let at = |p: f64| e.quantiles.iter().find(|q| q.0 == p).unwrap().1;
        assert_eq!(at(50.0), 2.0);
        assert_eq!(at(99.865), 4.0);
    }

    #[test]
    fn flagged_points_sit_beyond_the_limit_in_the_outline() {
        // A flagged point (score +∞) of weight 1 among three: P99.865 reads it (+∞
        // above an upper limit), P25 does not.
        let points = [
            point(1.0, -3.0, 1.0),
            point(2.0, -2.0, 1.0),
            point(3.0, f64::INFINITY, 1.0),
        ];
        let e = evaluation(&points, true, Placement::Above).unwrap();
        let at = |p: f64| e.quantiles.iter().find(|q| q.0 == p).unwrap().1;
        assert_eq!(at(99.865), f64::INFINITY);
        assert_eq!(at(25.0), 1.0);
        assert!((e.figure - 1e6 / 3.0).abs() < 1e-6);
    }
}
