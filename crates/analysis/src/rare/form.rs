//! FORM: the most probable point of the event in the standard normal space, by the
//! improved Hasofer–Lind–Rackwitz–Fiessler iteration (Zhang & Der Kiureghian, "Finite
//! element reliability methods for inelastic structures", 1997; the merit function of
//! Zhang & Der Kiureghian 1995).
//!
//! With g(u) = −s(u) (the event is g ≤ 0) and its gradient ∇g by central differences
//! (step [`STEP`] in each normal score, 2·dims + 1 rows evaluated as one batch), the
//! HL-RF direction is d = ((∇g·u − g)/|∇g|²)·∇g − u; the step λ ∈ {1, ½, …, 2⁻⁷} is the
//! first (largest) with Armijo's decrease of the merit m(u) = ½|u|² + c·|g(u)|,
//! c = 2|u|/|∇g| + 10 (> |u|/|∇g|, which makes d a descent direction of m), all eight
//! candidates evaluated as one batch. Converged when |g| ≤ [`TOLERANCE`]·|g(0)| and
//! |u − (α·u)α| ≤ [`TOLERANCE`]·max(1, |u|), α = −∇g/|∇g|. Then β = |u*|, the
//! first-order probability Φ(−β), and α = u*/β at convergence (the importance factors
//! are α², summing to 1).
//!
//! FORM's probability is exact for a linear event in the normal space and an
//! approximation otherwise; rvtol reports it as the importance sampling's starting point
//! and the event's importance factors, never as the estimate.

use super::limit::LimitState;

/// Central-difference step in the normal space.
const STEP: f64 = 1e-3;
/// Relative tolerance of the convergence tests.
const TOLERANCE: f64 = 1e-3;
/// Iterations before FORM gives up.
const MAX_ITERATIONS: usize = 60;
/// Step halvings tried per iteration.
const LINE_STEPS: usize = 8;
/// Armijo's sufficient-decrease factor.
const ARMIJO: f64 = 1e-4;

/// The most probable point found.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignPoint {
    /// The point u* in the normal space.
    pub u: Vec<f64>,
    /// β = |u*|.
    pub beta: f64,
    /// Whether both convergence tests held.
    pub converged: bool,
    /// Iterations made.
    pub iterations: usize,
    /// Why FORM stopped short, when it did.
    pub stopped: Option<String>,
}

/// g and ∇g at a point.
struct Linearised {
    g: f64,
    gradient: Vec<f64>,
}

/// The design point of `limit`'s event from the nominal point, or why there is none:
/// the origin (every input at its nominal law's centre) already in the event (not a rare
/// event) or the model not finite there.
pub fn design_point(limit: &mut LimitState) -> Result<DesignPoint, String> {
    let dims = limit.dims();
    let origin = vec![0.0; dims];
    let g0 = -limit.scores(&origin)[0];
    if !g0.is_finite() {
        return Err("the event holds at the nominal point or the model is not finite there".into());
    }
    if g0 <= 0.0 {
        return Err("the event holds at the nominal point: it is not rare".into());
    }
    Ok(iterate(limit, origin, g0))
}

/// The iteration from `u` (g(0) = `g0` sets the tolerance on g).
fn iterate(limit: &mut LimitState, mut u: Vec<f64>, g0: f64) -> DesignPoint {
    let mut here = linearise(limit, &u);
    let mut stopped = None;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < MAX_ITERATIONS {
        let norm = length(&here.gradient);
        if !(norm.is_finite() && norm > 0.0) || here.gradient.iter().any(|x| !x.is_finite()) {
            stopped = Some("the model's gradient is zero or not finite on the way".to_string());
            break;
        }
        let alpha: Vec<f64> = here.gradient.iter().map(|x| -x / norm).collect();
        if iterations > 0 && close(&u, &alpha, here.g, g0) {
            converged = true;
            break;
        }
        iterations += 1;
        match step(limit, &u, &here, norm) {
            Some(next) => u = next,
            None => {
                stopped = Some("no step decreases the merit function".to_string());
                break;
            }
        }
        here = linearise(limit, &u);
        if !here.g.is_finite() {
            stopped = Some("the model is not finite on the way".to_string());
            break;
        }
    }
    if !converged && stopped.is_none() {
        stopped = Some(format!("not converged in {MAX_ITERATIONS} iterations"));
    }
    DesignPoint {
        beta: length(&u),
        u,
        converged,
        iterations,
        stopped,
    }
}

/// Whether u is on the limit state (relative to g(0)) and parallel to α.
fn close(u: &[f64], alpha: &[f64], g: f64, g0: f64) -> bool {
    let along: f64 = u.iter().zip(alpha).map(|(u, a)| u * a).sum();
    let across = length(
        &(u.iter().zip(alpha))
            .map(|(u, a)| u - along * a)
            .collect::<Vec<_>>(),
    );
    g.abs() <= TOLERANCE * g0.abs() && across <= TOLERANCE * length(u).max(1.0)
}

/// The next point of the iteration from `u` (g and ∇g there, |∇g| = `norm`), or `None`
/// when no step length decreases the merit.
fn step(limit: &mut LimitState, u: &[f64], here: &Linearised, norm: f64) -> Option<Vec<f64>> {
    let dims = u.len();
    let grad = &here.gradient;
    let scale = (dot(grad, u) - here.g) / (norm * norm);
    let d: Vec<f64> = grad.iter().zip(u).map(|(g, u)| scale * g - u).collect();
    let c = 2.0 * length(u) / norm + 10.0;
    let merit = |v: &[f64], g: f64| 0.5 * dot(v, v) + c * g.abs();
    // ∇m·d = u·d + c·sign(g)·∇g·d.
    let slope = dot(u, &d) + c * here.g.signum() * dot(grad, &d);
    let lambdas: Vec<f64> = (0..LINE_STEPS).map(|k| 0.5f64.powi(k as i32)).collect();
    let mut points = Vec::with_capacity(LINE_STEPS * dims);
    for &lambda in &lambdas {
        points.extend(u.iter().zip(&d).map(|(u, d)| u + lambda * d));
    }
    let g: Vec<f64> = limit.scores(&points).into_iter().map(|s| -s).collect();
    let start = merit(u, here.g);
    (0..LINE_STEPS)
        .find(|&k| {
            let v = &points[k * dims..(k + 1) * dims];
            g[k].is_finite() && merit(v, g[k]) <= start + ARMIJO * lambdas[k] * slope.min(0.0)
        })
        .map(|k| points[k * dims..(k + 1) * dims].to_vec())
}

/// g and its central-difference gradient at `u`, as one batch.
fn linearise(limit: &mut LimitState, u: &[f64]) -> Linearised {
    let dims = u.len();
    let mut points = u.to_vec();
    for d in 0..dims {
        for sign in [1.0, -1.0] {
            let start = points.len();
            points.extend_from_slice(u);
            points[start + d] += sign * STEP;
        }
    }
    let g: Vec<f64> = limit.scores(&points).into_iter().map(|s| -s).collect();
    Linearised {
        g: g[0],
        gradient: (0..dims)
            .map(|d| (g[1 + 2 * d] - g[2 + 2 * d]) / (2.0 * STEP))
            .collect(),
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

fn length(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
