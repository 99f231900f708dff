//! Importance sampling around the design points: points drawn from the defensive mixture
//! q(z) = π₀·φ(z) + Σₖ πₖ·φ(z − u*ₖ) (Hesterberg, "Weighted average importance sampling
//! and defensive mixture distributions", Technometrics 37 (1995) 185–194), π₀ =
//! [`DEFENSIVE`], the rest shared by the design points (one per side of the event), each
//! event point weighted by
//!
//!   w(z) = φ(z)/q(z) = 1 / (π₀ + Σₖ πₖ·exp(u*ₖ·z − |u*ₖ|²/2)) ≤ 1/π₀,
//!
//! and P̂ = (1/n)·Σ w·1[s(z) > 0], an unbiased estimate whatever the design points are
//! (they only set its variance); its standard error from the sample variance of w·1, the
//! interval P̂ ± z₀.₉₇₅·SE. Batches of [`BATCH`] points, batch b from the ChaCha8 stream
//! `STREAM + b` of the seed and evaluated in one parallel pass, until the interval's half
//! width is at most the asked share of P̂ (with at least [`MIN_EVENTS`] event points) or
//! the evaluation budget is spent: the same figures for a seed at any thread count.
//!
//! The estimate assumes the event lies around its design points (one region per side). A
//! region far from them is reached only by the defensive component, rarely and with a
//! large weight; the largest single weight's share of the sum is reported, and above
//! [`DOMINANT_SHARE`] the estimate carries a warning.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use super::limit::LimitState;
use super::{Budget, Estimate, Z_95};

/// The standard normal component's share of the mixture.
pub const DEFENSIVE: f64 = 0.1;
/// Points per batch.
pub const BATCH: usize = 1024;
/// Event points needed before the interval may stop the sampling.
const MIN_EVENTS: u64 = 30;
/// The share of the sum one weight may carry before the estimate is flagged.
const DOMINANT_SHARE: f64 = 0.1;
/// The streams of the batches: 2⁶¹ + 2⁶⁰ + b (the run's are k, the screening's 2⁶⁰ + k,
/// the stack's linearity rows 2⁶¹ + k).
const STREAM: u64 = (1 << 61) + (1 << 60);

/// Running sums of the weighted indicator w·1[s > 0].
#[derive(Default)]
pub(crate) struct Sums {
    n: u64,
    events: u64,
    /// Σ w over the event points.
    pub sum: f64,
    sum_squares: f64,
    largest: f64,
}

impl Sums {
    /// Adds a point: its weight when it is in the event, None when not.
    pub fn push(&mut self, event_weight: Option<f64>) {
        self.n += 1;
        if let Some(w) = event_weight {
            self.events += 1;
            self.sum += w;
            self.sum_squares += w * w;
            self.largest = self.largest.max(w);
        }
    }

    /// The estimate P̂ = Σ w·1/n.
    pub fn mean(&self) -> f64 {
        self.sum / self.n as f64
    }

    /// The standard error of the mean, from the sample variance of w·1.
    pub fn standard_error(&self) -> f64 {
        let n = self.n as f64;
        let variance = (self.sum_squares / n - self.mean().powi(2)).max(0.0) * n / (n - 1.0);
        (variance / n).sqrt()
    }
}

/// The defensive mixture around a set of centres: how its points are drawn and weighted.
#[derive(Debug, Clone, PartialEq)]
pub struct Mixture {
    centres: Vec<Vec<f64>>,
    /// |u*ₖ|²/2 per centre.
    shifts: Vec<f64>,
    /// πₖ, the share of each centre.
    share: f64,
    dims: usize,
}

impl Mixture {
    /// The mixture around `centres` (at least one) in `dims` dimensions.
    pub fn new(centres: &[Vec<f64>], dims: usize) -> Mixture {
        Mixture {
            shifts: centres.iter().map(|c| 0.5 * dot(c, c)).collect(),
            share: (1.0 - DEFENSIVE) / centres.len() as f64,
            centres: centres.to_vec(),
            dims,
        }
    }

    /// Batch `batch` of the seed's points ([`BATCH`] of them, row-major, in `points`):
    /// the ChaCha8 stream `STREAM + batch` of `seed`, the same whoever draws it.
    pub fn draw(&self, seed: u64, batch: u64, points: &mut [f64]) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(STREAM + batch);
        for point in points.chunks_exact_mut(self.dims.max(1)) {
            let pick: f64 = rng.random();
            let centre = ((pick - DEFENSIVE) / self.share).floor();
            let centre = (pick >= DEFENSIVE)
                .then(|| &self.centres[(centre as usize).min(self.centres.len() - 1)]);
            for (d, z) in point.iter_mut().enumerate() {
                let xi: f64 = rng.sample(StandardNormal);
                *z = xi + centre.map_or(0.0, |c| c[d]);
            }
        }
    }

    /// The weight φ(z)/q(z) of a point.
    pub fn weight(&self, point: &[f64]) -> f64 {
        let mixture: f64 = (self.centres.iter().zip(&self.shifts))
            .map(|(c, h)| self.share * (dot(c, point) - h).exp())
            .sum();
        1.0 / (DEFENSIVE + mixture)
    }
}

/// The importance-sampling estimate of `limit`'s event around `centres`.
pub fn estimate(
    limit: &mut LimitState,
    centres: &[Vec<f64>],
    seed: u64,
    budget: &Budget,
) -> Estimate {
    let dims = limit.dims();
    let mixture = Mixture::new(centres, dims);
    let start = limit.evaluations;
    let mut sums = Sums::default();
    let mut batch = 0u64;
    let mut points = vec![0.0; BATCH * dims];
    loop {
        mixture.draw(seed, batch, &mut points);
        let scores = limit.scores(&points);
        for (point, s) in points.chunks_exact(dims.max(1)).zip(scores) {
            sums.push((s > 0.0).then(|| mixture.weight(point)));
        }
        batch += 1;
        let half = Z_95 * sums.standard_error();
        let reached = sums.events >= MIN_EVENTS && half <= budget.precision * sums.mean();
        if reached || limit.evaluations - start + BATCH as u64 > budget.max_evaluations {
            return finish(&sums, reached, limit.evaluations - start);
        }
    }
}

fn finish(sums: &Sums, reached: bool, evaluations: u64) -> Estimate {
    let p = sums.mean();
    let half = Z_95 * sums.standard_error();
    let dominant = sums.sum > 0.0 && sums.largest / sums.sum > DOMINANT_SHARE;
    Estimate {
        probability: p,
        interval: [(p - half).max(0.0), p + half],
        evaluations,
        reached,
        events: sums.events,
        runs: 0,
        tail: Vec::new(),
        warning: dominant.then(|| {
            format!(
                "one point carries {:.0} % of the estimate: the event may reach beyond its design points; compare subset simulation",
                100.0 * sums.largest / sums.sum
            )
        }),
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}
