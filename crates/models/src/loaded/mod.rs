//! The loaded contact solution at one output position (docs/models.md §12.9): both cycloid
//! discs elastic pin by pin on their own signed gaps, coupled through the crank side, the
//! output torque split between them by equilibrium. The transmission error under load
//! (`transmission_error`, `disc_contact` "loaded") solves it at every point of its curve;
//! the torsion curve's two-disc lost motion can take it over as it is.
//!
//! ```text
//! disc d turned by y_d from its rigid place (rad, disc frame; its crank offset C_d apart):
//!   pin i approaches by    d_i = l_i·y_d − g_i        (g_i < 0: an overlap; l_i < 0 drive flank)
//!   its force              F_i = K_d·max(0, d_i),  K_d = F(d_max)/d_max, F = δ⁻¹
//!   the pins' moment       M_d(y_d) = Σ_i F_i·l_i                   (N·mm, rises with y_d)
//! crank side: the disc turns against the carrier by c·M_d (plus a part common to both
//!   discs, fixed by their sum: CrankSide::disc_compliance), so the carrier stands at
//!   x = C_d + y_d + c·M_d(y_d)                  (the same x for both discs)
//! equilibrium at the output torque T (input locked; λ the torque balance of §10):
//!   M_1 + M_2 = M* = −λ·T                        (T > 0 loads the drive flank: the output lags)
//! ```
//!
//! The contact law is the one of every model that loads the pins (`crate::preload`'s
//! `PinContact`: two Palmgren line contacts in series per pin, δ(F) = 2·3.84·10⁻⁵·F^0.9/L^0.8,
//! with Li Lixing's common secant stiffness of the most loaded pin, as
//! `cycloid_pin_contact`'s load sharing and the zero-torque balance of `crate::preload`):
//! one disc without crank compliance reproduces that load sharing (tested).
//!
//! Unknown per point: the carrier angle x; for each x each disc settles where
//! h_d(y) = y + c·M_d(y) − (x − C_d) vanishes (h_d rises with slope ≥ 1, so from any y0
//! the root lies between y0 and y0 − h_d(y0): a bracket without search), and
//! Φ(x) = M_1 + M_2 − M* rises with x (dΦ/dx = Σ_d M_d'/(1 + c·M_d')). Both are solved by a
//! safeguarded Newton iteration (Newton's step inside a bracket, bisection where it would
//! leave it; Numerical Recipes' rtsafe): the functions are monotone and piecewise smooth
//! (they kink where a pin comes into contact or the most loaded pin changes). The outer
//! bracket is found by stepping out from the warm start (the previous point's solution,
//! or the rigid first contact) with doubling steps. Every loop is capped; a point that does
//! not converge is an [`Unconverged`] with its cause, never a hang.
//!
//! From a warm start (the previous point of a curve) a fast path comes first: Newton's
//! iteration on both turns at once (R_1 = M_1 + M_2 − M*, R_2 = x_1 − x_2), which settles in
//! a few steps where the loaded pins stay; where it does not within [`FAST_STEPS`], the
//! safeguarded iteration above takes over. Both stop at the same tolerances.

use crate::preload::{PinContact, SecantLaw};

#[cfg(test)]
mod tests;

/// Most iterations of one safeguarded Newton solve.
const MAX_ITERATIONS: u32 = 100;
/// Most doublings of the outer bracket's step.
const MAX_DOUBLINGS: u32 = 80;
/// The carrier angle is settled to this width of its bracket, rad (2·10⁻⁸ arcsec).
const ANGLE_TOLERANCE: f64 = 1e-13;
/// A disc's turn is settled to this width, rad (finer than the carrier's, so that the
/// outer function is smooth at its resolution).
const TURN_TOLERANCE: f64 = 1e-16;
/// Steps of the fast path (both discs' turns by Newton's iteration) before the
/// safeguarded iteration takes over.
const FAST_STEPS: u32 = 8;
/// The torque balance is met to this fraction of the output's moment.
const MOMENT_TOLERANCE: f64 = 1e-12;
/// First step of the outer bracket's search where the warm start gives none, rad.
const FIRST_STEP: f64 = 1e-7;

/// One disc's pins at one output position.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LoadedDisc<'a> {
    /// g_i, the signed gaps along the pins' normals at the disc's rigid place, mm.
    pub gaps: &'a [f64],
    /// l_i, the levers about the disc centre, mm (l < 0: the drive flank).
    pub levers: &'a [f64],
    /// C_d, the disc's crank offset, rad (disc frame).
    pub offset: f64,
}

impl LoadedDisc<'_> {
    /// M(y) and dM/dy (module comment): N·mm and N·mm/rad. Zero where no pin is loaded.
    pub fn moment(&self, law: &SecantLaw, y: f64) -> (f64, f64) {
        let (mut sum, mut slope) = (0.0, 0.0);
        let (mut largest, mut lever_of_largest) = (0.0_f64, 0.0);
        for (g, l) in self.gaps.iter().zip(self.levers) {
            let d = l * y - g;
            if d > 0.0 {
                sum += d * l;
                slope += l * l;
                if d > largest {
                    (largest, lever_of_largest) = (d, *l);
                }
            }
        }
        if largest <= 0.0 {
            return (0.0, 0.0);
        }
        // M = K(d_max)·Σ d_i·l_i, dM/dy = K·Σ l_i² + K'(d_max)·l_max·Σ d_i·l_i.
        let (stiffness, derivative) = law.stiffness(largest);
        (
            stiffness * sum,
            stiffness * slope + derivative * lever_of_largest * sum,
        )
    }

    /// How many pins are in contact at the turn y (l·y − g > 0).
    pub fn touching(&self, y: f64) -> usize {
        self.gaps
            .iter()
            .zip(self.levers)
            .filter(|(g, l)| *l * y - *g > 0.0)
            .count()
    }

    /// The turn at which the first pin of the flank that `sign` loads touches (sign < 0:
    /// the drive flank, the largest g/l over l < 0; sign > 0: the smallest over l > 0).
    fn first_touch(&self, sign: f64) -> f64 {
        let mut touch = sign * f64::INFINITY;
        for (g, l) in self.gaps.iter().zip(self.levers) {
            if l * sign > 0.0 {
                let ratio = g / l;
                touch = if sign < 0.0 {
                    touch.max(ratio)
                } else {
                    touch.min(ratio)
                };
            }
        }
        touch
    }
}

/// Why a point has no loaded solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Unconverged {
    /// No sign change of the torque balance within the bracket search (a non-finite gap,
    /// or a disc with no pin on the loaded flank).
    NoBracket,
    /// The safeguarded Newton iteration did not settle within its cap.
    Iterations,
    /// A disc would turn more than [`MAX_TURN`] from its rigid place: gaps that large are
    /// beyond the contact the solution rests on (each pin's approach l·y, linear in the
    /// turn), and an absurd input must not cost the bracket search's every doubling.
    BeyondSmallTurns,
}

/// The largest turn of a disc from its rigid place the solution takes, rad (34′, some
/// hundred times a real RV's play).
pub(crate) const MAX_TURN: f64 = 0.01;

impl std::fmt::Display for Unconverged {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unconverged::NoBracket => write!(
                f,
                "the torque balance has no sign change within {MAX_DOUBLINGS} doublings of the bracket (a non-finite gap, or no pin on the loaded flank)"
            ),
            Unconverged::Iterations => write!(
                f,
                "the safeguarded Newton iteration did not settle in {MAX_ITERATIONS} steps"
            ),
            Unconverged::BeyondSmallTurns => write!(
                f,
                "a disc would turn more than {MAX_TURN} rad from its rigid place (gaps beyond the linearised contact)"
            ),
        }
    }
}

/// The solution at one output position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Solution {
    /// x, the carrier's angle in disc-frame radians (the output angle is λ·x).
    pub carrier: f64,
    /// y_d, each disc's turn from its rigid place, rad.
    pub turns: [f64; 2],
    /// M_d, each disc's pin moment, N·mm.
    pub moments: [f64; 2],
    /// Evaluations of the torque balance (the fast path: of both discs' moments).
    pub iterations: u32,
}

impl Solution {
    /// No previous solution: the solver starts from the rigid first contact.
    pub const COLD: Solution = Solution {
        carrier: f64::NAN,
        turns: [f64::NAN; 2],
        moments: [0.0; 2],
        iterations: 0,
    };
}

/// The two discs' loaded contact (module comment).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TwoDiscs {
    /// The pins' secant law (of the contact law `PinContact`).
    pub law: SecantLaw,
    /// c, a disc's turn against the other through the crank side per N·mm of its own pin
    /// moment, rad/(N·mm) (0: rigid cranks).
    pub compliance: f64,
}

impl TwoDiscs {
    /// The solver for the pins' contact law `contact` and the crank side's compliance c.
    pub fn new(contact: &PinContact, compliance: f64) -> TwoDiscs {
        TwoDiscs {
            law: contact.secant_law(),
            compliance,
        }
    }

    /// The solution at one position for the total pin moment `target` = M* (N·mm), warm
    /// started from `warm` (the previous point's, or [`Solution::COLD`]).
    pub fn solve(
        &self,
        discs: &[LoadedDisc; 2],
        target: f64,
        warm: &Solution,
    ) -> Result<Solution, Unconverged> {
        let finite = |disc: &LoadedDisc| {
            disc.offset.is_finite() && disc.gaps.iter().chain(disc.levers).all(|v| v.is_finite())
        };
        if !(target.is_finite() && discs.iter().all(finite)) {
            return Err(Unconverged::NoBracket);
        }
        if warm.carrier.is_finite() {
            if let Some(solution) = self.newton_pair(discs, target, warm) {
                return within_small_turns(solution);
            }
        }
        let sign = if target < 0.0 { -1.0 } else { 1.0 };
        let start = if warm.carrier.is_finite() {
            warm.carrier
        } else {
            // The rigid first contact on the loaded flank: the disc that touches first.
            let touch = discs.map(|d| d.offset + d.first_touch(sign));
            let first = if sign < 0.0 {
                touch[0].max(touch[1])
            } else {
                touch[0].min(touch[1])
            };
            if !first.is_finite() {
                return Err(Unconverged::NoBracket);
            }
            if discs.iter().any(|d| (first - d.offset).abs() > MAX_TURN) {
                return Err(Unconverged::BeyondSmallTurns);
            }
            first
        };
        let mut turns = warm.turns;
        for (turn, disc) in turns.iter_mut().zip(discs) {
            if !turn.is_finite() {
                *turn = start - disc.offset;
            }
        }
        let mut evaluations = 0;
        let mut moments = [0.0; 2];
        let mut balance = |x: f64| -> Result<(f64, f64), Unconverged> {
            evaluations += 1;
            let (mut total, mut slope) = (-target, 0.0);
            for d in 0..2 {
                let (y, moment, stiffness) =
                    self.settle(&discs[d], x - discs[d].offset, turns[d])?;
                turns[d] = y;
                moments[d] = moment;
                total += moment;
                slope += stiffness / (1.0 + self.compliance * stiffness);
            }
            Ok((total, slope))
        };
        let carrier = outer_root(&mut balance, start)?;
        // The last evaluation may have been at another bracket end: settle at the root.
        balance(carrier)?;
        within_small_turns(Solution {
            carrier,
            turns,
            moments,
            iterations: evaluations,
        })
    }

    /// The fast path from a warm start: Newton's iteration on both discs' turns at once,
    /// R_1 = M_1(y_1) + M_2(y_2) − M* and R_2 = (C_1 + y_1 + c·M_1) − (C_2 + y_2 + c·M_2),
    /// a few steps where the loaded pins stay the same from one point to the next. None
    /// (and the safeguarded iteration takes over) when it has not settled within
    /// [`FAST_STEPS`] steps, or meets a singular or non-finite step.
    fn newton_pair(
        &self,
        discs: &[LoadedDisc; 2],
        target: f64,
        warm: &Solution,
    ) -> Option<Solution> {
        let c = self.compliance;
        let mut turns = warm.turns;
        for step in 0..FAST_STEPS {
            let [(m1, a1), (m2, a2)] = [0, 1].map(|d| discs[d].moment(&self.law, turns[d]));
            let r1 = m1 + m2 - target;
            let x1 = discs[0].offset + turns[0] + c * m1;
            let x2 = discs[1].offset + turns[1] + c * m2;
            let r2 = x1 - x2;
            if r1.abs() <= MOMENT_TOLERANCE * target.abs().max(1.0) && r2.abs() <= ANGLE_TOLERANCE {
                return Some(Solution {
                    carrier: 0.5 * (x1 + x2),
                    turns,
                    moments: [m1, m2],
                    iterations: step + 1,
                });
            }
            // J = [[a1, a2], [1 + c·a1, −(1 + c·a2)]]; J·Δ = −R.
            let (b1, b2) = (1.0 + c * a1, 1.0 + c * a2);
            let det = -a1 * b2 - a2 * b1;
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let d1 = (r1 * b2 + a2 * r2) / det;
            let d2 = (r1 * b1 - a1 * r2) / det;
            if !(d1.is_finite() && d2.is_finite()) {
                return None;
            }
            turns = [turns[0] + d1, turns[1] + d2];
        }
        None
    }

    /// Disc d's turn y with y + c·M(y) = `reach` (= x − C_d), from the guess `guess`:
    /// (y, M(y), M'(y)).
    fn settle(
        &self,
        disc: &LoadedDisc,
        reach: f64,
        guess: f64,
    ) -> Result<(f64, f64, f64), Unconverged> {
        let c = self.compliance;
        let h = |y: f64| {
            let (m, dm) = disc.moment(&self.law, y);
            (y + c * m - reach, 1.0 + c * dm, m, dm)
        };
        let (h0, _, m0, dm0) = h(guess);
        if h0 == 0.0 {
            return Ok((guess, m0, dm0));
        }
        // h rises with slope ≥ 1: the root lies between y0 and y0 − h(y0).
        let (mut lo, mut hi) = if h0 < 0.0 {
            (guess, guess - h0)
        } else {
            (guess - h0, guess)
        };
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(Unconverged::NoBracket);
        }
        let mut y = guess;
        let (mut value, mut slope) = (h0, 1.0 + c * dm0);
        for _ in 0..MAX_ITERATIONS {
            let newton = y - value / slope;
            y = if newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let (v, s, m, dm) = h(y);
            if v == 0.0 || hi - lo <= TURN_TOLERANCE.max(1e-15 * y.abs()) {
                return Ok((y, m, dm));
            }
            if v < 0.0 {
                lo = y;
            } else {
                hi = y;
            }
            if (v.abs() <= TURN_TOLERANCE) && (newton - y).abs() <= TURN_TOLERANCE {
                return Ok((y, m, dm));
            }
            (value, slope) = (v, s);
        }
        Err(Unconverged::Iterations)
    }
}

/// The solution where both discs' turns are within [`MAX_TURN`].
fn within_small_turns(solution: Solution) -> Result<Solution, Unconverged> {
    if solution.turns.iter().all(|t| t.abs() <= MAX_TURN) {
        Ok(solution)
    } else {
        Err(Unconverged::BeyondSmallTurns)
    }
}

/// The root of the rising function `f` (value, slope) from `start`: a bracket stepped out
/// with doubling steps, then a safeguarded Newton iteration in it (module comment).
fn outer_root(
    f: &mut impl FnMut(f64) -> Result<(f64, f64), Unconverged>,
    start: f64,
) -> Result<f64, Unconverged> {
    let (f0, slope0) = f(start)?;
    if f0 == 0.0 {
        return Ok(start);
    }
    let direction = if f0 < 0.0 { 1.0 } else { -1.0 };
    // Newton's step, widened by half, is the first try; then doubling.
    let mut step = if slope0 > 0.0 {
        1.5 * (f0 / slope0).abs()
    } else {
        FIRST_STEP
    };
    let mut near = start;
    let mut far = start;
    let mut far_value = f0;
    for _ in 0..MAX_DOUBLINGS {
        far = start + direction * step;
        far_value = f(far)?.0;
        if !far_value.is_finite() {
            return Err(Unconverged::NoBracket);
        }
        if far_value.signum() != f0.signum() || far_value == 0.0 {
            break;
        }
        near = far;
        step *= 2.0;
    }
    if far_value.signum() == f0.signum() && far_value != 0.0 {
        return Err(Unconverged::NoBracket);
    }
    if far_value == 0.0 {
        return Ok(far);
    }
    let (mut lo, mut hi) = if direction > 0.0 {
        (near, far)
    } else {
        (far, near)
    };
    // Start from the bracket end nearer the root by the chord.
    let mut x = 0.5 * (lo + hi);
    let (mut value, mut slope) = f(x)?;
    for _ in 0..MAX_ITERATIONS {
        if value == 0.0 {
            return Ok(x);
        }
        if value < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        if hi - lo <= ANGLE_TOLERANCE {
            return Ok(0.5 * (lo + hi));
        }
        let newton = if slope > 0.0 {
            x - value / slope
        } else {
            f64::NAN
        };
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let settled = (next - x).abs() <= ANGLE_TOLERANCE;
        x = next;
        (value, slope) = f(x)?;
        if settled {
            return Ok(x);
        }
    }
    Err(Unconverged::Iterations)
}

/// One disc without crank compliance carrying the pin moment `target` (N·mm): its turn y
/// with M(y) = target, by the same safeguarded Newton iteration (the per-pin solution the
/// load sharing of `cycloid_pin_contact` must equal; tested against it).
#[cfg(test)]
pub(crate) fn one_disc(
    contact: &PinContact,
    disc: &LoadedDisc,
    target: f64,
) -> Result<f64, Unconverged> {
    if !(target.is_finite() && disc.gaps.iter().chain(disc.levers).all(|v| v.is_finite())) {
        return Err(Unconverged::NoBracket);
    }
    let sign = if target < 0.0 { -1.0 } else { 1.0 };
    let start = disc.first_touch(sign);
    if !start.is_finite() {
        return Err(Unconverged::NoBracket);
    }
    let law = contact.secant_law();
    let mut f = |y: f64| -> Result<(f64, f64), Unconverged> {
        let (m, dm) = disc.moment(&law, y);
        Ok((m - target, dm))
    };
    outer_root(&mut f, start)
}
