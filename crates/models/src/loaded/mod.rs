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
    /// a_i, each pin's arm in the torque balance, mm: l_i, or with the pins' Coulomb
    /// friction l_i + f·h_i (`cycloid_pin_contact`'s arms; zero where the friction would
    /// reverse the pin's moment). The approach is l_i·y − g_i either way.
    pub arms: &'a [f64],
    /// C_d, the disc's crank offset, rad (disc frame).
    pub offset: f64,
    /// s_d, the needle rows' slack, rad (disc frame; 0: none): the disc turns against the
    /// carrier by up to ±s_d without a moment (docs/models.md §14.3), so that
    /// x = C_d + y_d + c·M_d + s_d·sign(M_d), and anywhere within ±s_d while M_d = 0.
    pub slack: f64,
}

impl LoadedDisc<'_> {
    /// M(y) and dM/dy (module comment): N·mm and N·mm/rad. Zero where no pin is loaded.
    pub fn moment(&self, law: &SecantLaw, y: f64) -> (f64, f64) {
        let (mut sum, mut slope) = (0.0, 0.0);
        let (mut largest, mut lever_of_largest) = (0.0_f64, 0.0);
        for ((g, l), a) in self.gaps.iter().zip(self.levers).zip(self.arms) {
            let d = l * y - g;
            if d > 0.0 {
                sum += d * a;
                slope += l * a;
                if d > largest {
                    (largest, lever_of_largest) = (d, *l);
                }
            }
        }
        if largest <= 0.0 {
            return (0.0, 0.0);
        }
        // M = K(d_max)·Σ d_i·a_i, dM/dy = K·Σ l_i·a_i + K'(d_max)·l_max·Σ d_i·a_i.
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
        for ((g, l), a) in self.gaps.iter().zip(self.levers).zip(self.arms) {
            if l * sign > 0.0 && *a != 0.0 {
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

    /// The turns at which the pins' moment vanishes, [y_lo, y_hi]: between the two flanks'
    /// first touches where the disc has play, the one root of M where its own flanks
    /// overlap (M rises through it; a bracketed safeguarded Newton iteration).
    fn zero_set(&self, law: &SecantLaw) -> Result<(f64, f64), Unconverged> {
        let (lo, hi) = (self.first_touch(-1.0), self.first_touch(1.0));
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(Unconverged::NoBracket);
        }
        if lo <= hi {
            return Ok((lo, hi));
        }
        // M(hi) < 0 < M(lo): the drive flank carries at hi, the coast flank at lo.
        let mut f = |y: f64| Ok(self.moment(law, y));
        let root = bracketed_root(&mut f, (hi, lo), TURN_TOLERANCE)?;
        Ok((root, root))
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
        let zeros = if discs.iter().any(|d| d.slack > 0.0) {
            [self.zero_set(&discs[0])?, self.zero_set(&discs[1])?]
        } else {
            [(f64::NAN, f64::NAN); 2]
        };
        let start = if warm.carrier.is_finite() {
            warm.carrier
        } else {
            // The rigid first contact on the loaded flank: the disc that touches first
            // (its slack taken up toward the load).
            let touch = discs.map(|d| d.offset + d.first_touch(sign) + sign * d.slack);
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
                    self.settle(&discs[d], x - discs[d].offset, turns[d], zeros[d])?;
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

    /// A start at rest: each disc at the middle of the turns where its pins' moment
    /// vanishes (its own balance where its flanks overlap), the carrier at their mean
    /// place. A warm start for [`Self::solve`] that does not rest on the rigid first
    /// contact, which a pin of small lever overlapping its disc puts far away.
    pub fn at_rest(&self, discs: &[LoadedDisc; 2]) -> Result<Solution, Unconverged> {
        let mut turns = [0.0; 2];
        for (turn, disc) in turns.iter_mut().zip(discs) {
            let (lo, hi) = disc.zero_set(&self.law)?;
            *turn = 0.5 * (lo + hi);
        }
        Ok(Solution {
            carrier: 0.5 * (discs[0].offset + turns[0] + discs[1].offset + turns[1]),
            turns,
            moments: [0.0; 2],
            iterations: 0,
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
            // The slack, taken up toward each disc's moment: smooth where neither vanishes.
            let taken = |disc: &LoadedDisc, m: f64| match disc.slack > 0.0 {
                true if m == 0.0 => None,
                true => Some(disc.slack.copysign(m)),
                false => Some(0.0),
            };
            let (s1, s2) = (taken(&discs[0], m1)?, taken(&discs[1], m2)?);
            let r1 = m1 + m2 - target;
            let x1 = discs[0].offset + turns[0] + c * m1 + s1;
            let x2 = discs[1].offset + turns[1] + c * m2 + s2;
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

    /// The zero set of disc d's moment (`LoadedDisc::zero_set`) under this solver's law.
    fn zero_set(&self, disc: &LoadedDisc) -> Result<(f64, f64), Unconverged> {
        disc.zero_set(&self.law)
    }

    /// Disc d's turn y with y + c·M(y) + s·sign(M(y)) = `reach` (= x − C_d), from the
    /// guess `guess`: (y, M(y), M'(y)). With slack, `zero` is the zero set of M: a reach
    /// within s of it leaves the disc without moment, on its nearest point; beyond, the
    /// slack is taken up and the smooth relation solved for reach ∓ s.
    fn settle(
        &self,
        disc: &LoadedDisc,
        reach: f64,
        guess: f64,
        (zero_lo, zero_hi): (f64, f64),
    ) -> Result<(f64, f64, f64), Unconverged> {
        let s = disc.slack;
        if s > 0.0 {
            if reach > zero_hi + s {
                return self.settle_taken(disc, reach - s, guess.max(zero_hi));
            }
            if reach < zero_lo - s {
                return self.settle_taken(disc, reach + s, guess.min(zero_lo));
            }
            return Ok((reach.clamp(zero_lo, zero_hi), 0.0, 0.0));
        }
        self.settle_taken(disc, reach, guess)
    }

    /// Disc d's turn y with y + c·M(y) = `reach`, from the guess `guess`: (y, M(y), M'(y)).
    fn settle_taken(
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
    let bracket = if direction > 0.0 {
        (near, far)
    } else {
        (far, near)
    };
    bracketed_root(f, bracket, ANGLE_TOLERANCE)
}

/// The root of the rising function `f` (value, slope) within `(lo, hi)`, where f(lo) ≤ 0
/// ≤ f(hi): Newton's step inside the bracket, bisection where it would leave it, until the
/// bracket or the step is below `tolerance`.
fn bracketed_root(
    f: &mut impl FnMut(f64) -> Result<(f64, f64), Unconverged>,
    (mut lo, mut hi): (f64, f64),
    tolerance: f64,
) -> Result<f64, Unconverged> {
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
        if hi - lo <= tolerance {
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
        let settled = (next - x).abs() <= tolerance;
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
