//! The catalogue's figures of one assembly from the loaded contact solution
//! (docs/models.md §14.9, `loaded_figures` = 1): both discs' pins elastic pin by pin on the
//! gaps of the windows (`windows.rs`, every deviation where it acts), coupled through the
//! crank side, at the output angle of the widest window, with the torque applied at the
//! output and the input locked, in both directions of motion.
//!
//! ```text
//! state (τ, w): output torque τ (N·m, > 0 turns the output forward), output moving
//!   forward (w = +1) or backward (w = −1)
//!   pins' arms   a_i = l_i + v·λ·μ_p·h_i, v = −w (the disc frame's x runs against the
//!                output's: τ > 0 loads the l < 0 flank), zero where the sign would flip
//!   bearings     τ_e = sign(τ)·max(0, |τ| − w·sign(τ)·T_fb(|τ|)), T_fb the needle rows'
//!                friction torque at the output (torsion_curve's, on the frictionless loads)
//!   solve        M_1 + M_2 = M* = −λ·τ_e  (crate::loaded, the needle slack s_d taken up
//!                toward each disc's moment, c the crank side's compliance of one disc
//!                against the other at the state's load level)
//!   angle        φ(τ, w) = −[λ·(x − c·M̄) + ζ·(chain(|M̄|, ζ·F̄_x, F̄_y) + housing)]
//!                M̄ = M*/2, ζ = sign(M̄) (+1 at zero), F̄ the discs' mean pin resultant
//!                (F_x = Σ F_i·l_i/(e·z_c) across the eccentric, F_y = −Σ F_i·f_x,i along
//!                it), chain = CrankSide::terms (every element of the torsion curve's
//!                chain, §13), housing = 2·λ·Σ_d U_h(F_d − F_d,0)/|M*| (housing.rs, F_0 the
//!                zero-torque forces of the same branch)
//! figures (inv = max(0, Δφ12'), the involute stage's backlash in series)
//!   lost motion      = [φ(+3 %, +) + φ(+3 %, −)]/2 − [φ(−3 %, −) + φ(−3 %, +)]/2 + inv
//!   hysteresis loss  = φ(0, −) − φ(0, +) + inv     (`Torsion::at_zero`: at zero torque
//!                      where the pair presses itself, approached from either side where a
//!                      disc presses only its own pins, the window W where nothing presses)
//!   rigidity         = (T_r − T_r/2)/(φ(T_r, +) − φ(T_r/2, +))
//!   angle at rated   = [φ(T_r, +) − φ(−T_r, −) + inv]/2   (half the loop's span)
//!   pin force        = the largest pin force at ±T_r
//! ```
//!
//! λ(x − c·M̄) takes the pins' turn and the part of the crank side in which the discs
//! differ (the solver's c·(M_d − M̄)); the chain adds the crank side of the mean load, as
//! the torsion curve's one profile does, so that two alike discs give the torsion curve's
//! angle (tested). The housing's influence matrix is the torsion curve's, at the pins'
//! nearest whole places (the grid puts them at fractions 1/q of a pitch).

use super::geometry::{Grid, Reducer};
use crate::cycloid_pin_contact::MAX_PINS;
use crate::loaded::{LoadedDisc, Solution, TwoDiscs, Unconverged};
use crate::preload::PinContact;
use crate::stiffness::{build, CrankSide, Housing};
use crate::{ModelError, ModelParams, ARCMIN_PER_RAD};

/// The catalogue's lost motion is read at ±3 % of rated torque.
pub(super) const LOST_MOTION_SHARE: f64 = 0.03;

/// The torque at which a branch is taken as arriving at zero, a share of rated: its
/// elastic angle is some 10⁻¹¹ arcmin.
const ZERO_SHARE: f64 = 1e-12;

/// The load levels whose crank-side compliance the solver takes: 3 % (and zero torque),
/// 50 % and 100 % of rated.
const LEVELS: [f64; 3] = [LOST_MOTION_SHARE, 0.5, 1.0];

/// The needle rows' Coulomb friction (torsion_curve's, docs/models.md §13).
#[derive(Debug, Clone, Copy)]
struct BearingFriction {
    /// μ_b.
    coefficient: f64,
    /// d_j, mm.
    journal_diameter: f64,
    /// z1/z2: a crank's turn against its disc per radian of the output.
    crank_turn: f64,
}

/// The loaded figures' model: the crank side, the housing, the friction and a solver per
/// load level.
#[derive(Debug, Clone)]
pub(super) struct Torsion {
    side: CrankSide,
    housing: Option<Housing>,
    /// T_r, N·m.
    rated: f64,
    lambda: f64,
    /// λ·μ_p.
    pin_friction: f64,
    bearing: BearingFriction,
    solvers: [TwoDiscs; 3],
    /// e·z_c, mm.
    pitch_radius: f64,
    /// q, points per pin pitch of the grid.
    per_pin: usize,
    pins: usize,
}

/// One disc's pins at the figures' output angle.
#[derive(Debug, Clone)]
pub(super) struct Pins {
    pub gaps: Vec<f64>,
    pub levers: Vec<f64>,
    /// h_i, the friction arms, mm.
    pub slip: Vec<f64>,
    /// f_x,i, the factor of a displacement along the eccentric (the pin force's along
    /// component is −F_i·f_x,i).
    pub along: Vec<f64>,
    /// The pin's nearest whole place from the eccentric (the housing's index).
    pub place: Vec<usize>,
    /// C_d and s_d, rad (disc frame).
    pub offset: f64,
    pub slack: f64,
    /// The moment arms for the disc frame's motion v = −1 and v = +1.
    arms: [Vec<f64>; 2],
}

impl Pins {
    /// No pins yet.
    pub const fn new() -> Pins {
        Pins {
            gaps: Vec::new(),
            levers: Vec::new(),
            slip: Vec::new(),
            along: Vec::new(),
            place: Vec::new(),
            offset: 0.0,
            slack: 0.0,
            arms: [Vec::new(), Vec::new()],
        }
    }

    /// Empties the disc for another row (keeping its storage).
    pub fn reset(&mut self, offset: f64, slack: f64) {
        for v in [
            &mut self.gaps,
            &mut self.levers,
            &mut self.slip,
            &mut self.along,
        ] {
            v.clear();
        }
        self.place.clear();
        (self.offset, self.slack) = (offset, slack);
    }
}

/// The figures of one assembly (module comment): arcmin, N·m/arcmin and N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Figures {
    pub lost_motion: f64,
    pub hysteresis_loss: f64,
    pub rigidity: f64,
    pub angle_at_rated: f64,
    pub pin_force: f64,
}

impl Figures {
    /// No solution: every figure NaN (the engine counts the row).
    pub const NONE: Figures = Figures {
        lost_motion: f64::NAN,
        hysteresis_loss: f64::NAN,
        rigidity: f64::NAN,
        angle_at_rated: f64::NAN,
        pin_force: f64::NAN,
    };
}

/// Whether a disc's own flanks overlap (its pins carry at rest whatever its slack):
/// the drive flank's first touch beyond the coast flank's.
fn overlaps_itself(disc: &Pins) -> bool {
    let (mut drive, mut coast) = (f64::NEG_INFINITY, f64::INFINITY);
    for (g, l) in disc.gaps.iter().zip(&disc.levers) {
        let touch = g / l;
        if *l < 0.0 {
            drive = drive.max(touch);
        } else {
            coast = coast.min(touch);
        }
    }
    drive > coast
}

/// Both discs' pin forces by place, N.
type DiscForces = [[f64; MAX_PINS]; 2];

/// The pins' loads of one solution ([`Torsion::pin_loads`]).
struct PinLoads {
    forces: DiscForces,
    resultant: (f64, f64),
    largest: f64,
}

/// One solved state: the output angle (rad, the output's sense), each disc's pin forces
/// by place, the largest pin force, and the solution (a warm start for the next state).
struct State {
    angle: f64,
    forces: [[f64; MAX_PINS]; 2],
    largest: f64,
    solution: Solution,
}

impl Torsion {
    /// The figures' model from the crank side's keys (`crate::stiffness::build`), the
    /// needle rows' friction and the rated torque.
    pub fn from_params(
        params: &ModelParams,
        reducer: &Reducer,
        contact: &PinContact,
        grid: &Grid,
    ) -> Result<Torsion, ModelError> {
        let rated = params.positive("rated_torque_nm", None)?;
        let stage = &reducer.stage;
        let built = build::crank_side(
            params,
            &build::Reducer {
                cranks: reducer.cranks,
                crank_circle_radius: reducer.center_distance,
                pins: stage.pins,
                teeth: stage.teeth,
                pin_circle_radius: stage.pin_circle_radius,
                eccentricity: stage.eccentricity,
                curtate: stage.k1(),
                face_width: reducer.face_width,
                ratio: reducer.ratio,
                reference_disc_torque: 0.5 * reducer.lambda * LOST_MOTION_SHARE * rated * 1000.0,
                elastic_bodies: params.flag("body_compliance", true)?,
            },
        )?;
        let side = built.side;
        let solvers = LEVELS.map(|share| {
            let disc_torque = 0.5 * reducer.lambda * share * rated * 1000.0;
            TwoDiscs::new(contact, side.disc_compliance(disc_torque))
        });
        Ok(Torsion {
            side,
            housing: built.housing,
            rated,
            lambda: reducer.lambda,
            pin_friction: reducer.lambda
                * params.friction_coefficient("pin_friction_coefficient")?,
            bearing: BearingFriction {
                coefficient: params.friction_coefficient("crank_bearing_friction_coefficient")?,
                journal_diameter: built.journal_diameter,
                crank_turn: built.crank_turn,
            },
            solvers,
            pitch_radius: reducer.pitch_lever(),
            per_pin: grid.per_pin,
            pins: stage.pins,
        })
    }

    /// The housing's index of the pin at column entry m of residue r (slot r + 2q·m, at
    /// (m + r/(2q)) pitches from the eccentric): the nearest whole place.
    pub fn place(&self, residue: usize, m: usize) -> usize {
        (m + usize::from(residue >= self.per_pin)) % self.pins
    }

    /// The figures of the two discs' pins `pins` (filled by the model at the output angle
    /// of the widest window `window`, rad at the output, with the involute stage's free
    /// play `involute`, rad): [`Figures::NONE`] where a state has no solution.
    pub fn figures(&self, pins: &mut [Pins; 2], window: f64, involute: f64) -> Figures {
        for disc in pins.iter_mut() {
            for (v, arms) in [-1.0, 1.0].into_iter().zip(disc.arms.iter_mut()) {
                arms.clear();
                arms.extend(disc.levers.iter().zip(&disc.slip).map(|(&l, &h)| {
                    let arm = l + v * self.pin_friction * h;
                    if arm * l > 0.0 {
                        arm
                    } else {
                        0.0
                    }
                }));
            }
        }
        self.solve_figures(pins, window, involute)
            .unwrap_or(Figures::NONE)
    }

    fn solve_figures(
        &self,
        pins: &[Pins; 2],
        window: f64,
        involute: f64,
    ) -> Result<Figures, Unconverged> {
        let rated = self.rated;
        let small = LOST_MOTION_SHARE * rated;
        let cold = Solution::COLD;
        let (hysteresis, rest) = self.at_zero(pins, window)?;
        let rest_of = |w: f64| if w > 0.0 { &rest[0] } else { &rest[1] };
        let at = |(torque, w): (f64, f64), level, warm: &Solution| {
            self.state(pins, (torque, w), level, Some(rest_of(w)), warm)
        };
        let plus = at((small, 1.0), 0, &cold)?;
        let plus_back = at((small, -1.0), 0, &plus.solution)?;
        let minus = at((-small, -1.0), 0, &cold)?;
        let minus_back = at((-small, 1.0), 0, &minus.solution)?;
        let half = at((0.5 * rated, 1.0), 1, &plus.solution)?;
        let full = at((rated, 1.0), 2, &half.solution)?;
        let full_minus = at((-rated, -1.0), 2, &minus.solution)?;
        let lost_motion = 0.5 * (plus.angle + plus_back.angle)
            - 0.5 * (minus.angle + minus_back.angle)
            + involute;
        Ok(Figures {
            lost_motion: lost_motion * ARCMIN_PER_RAD,
            hysteresis_loss: (hysteresis + involute) * ARCMIN_PER_RAD,
            rigidity: 0.5 * rated / ((full.angle - half.angle) * ARCMIN_PER_RAD),
            angle_at_rated: 0.5 * (full.angle - full_minus.angle + involute) * ARCMIN_PER_RAD,
            pin_force: full.largest.max(full_minus.largest),
        })
    }

    /// The loop's width at zero torque (rad) and each branch's rest forces, [w = +1,
    /// w = −1], for the housing (module comment). Where the pair presses itself (no free
    /// window) one state at zero torque per branch (the curve is continuous there); where
    /// the window is free and a disc presses its own pins, the two branches approached at
    /// [`ZERO_SHARE`] of rated torque; where nothing presses at rest, the window itself
    /// (the friction vanishes with the load) and no rest forces.
    fn at_zero(
        &self,
        pins: &[Pins; 2],
        window: f64,
    ) -> Result<(f64, [DiscForces; 2]), Unconverged> {
        let pressed = window <= 0.0;
        if !pressed && !pins.iter().any(overlaps_itself) {
            return Ok((window, [[[0.0; MAX_PINS]; 2]; 2]));
        }
        let up = self.state(pins, (0.0, 1.0), 0, None, &Solution::COLD)?;
        let down = self.state(pins, (0.0, -1.0), 0, None, &up.solution)?;
        let width = if pressed {
            down.angle - up.angle
        } else {
            // The housing's angle vanishes with the torque, as in the zero-torque states
            // (its Castigliano form, a change of energy over the torque, has no limit
            // where the forces move at no torque).
            let near = ZERO_SHARE * self.rated;
            let above = self.state(pins, (near, -1.0), 0, None, &down.solution)?;
            let below = self.state(pins, (-near, 1.0), 0, None, &up.solution)?;
            above.angle - below.angle
        };
        Ok((width, [up.forces, down.forces]))
    }

    /// τ_e, the torque the elastic chain carries at the output torque τ (N·m) moving in
    /// the direction w: the needle rows' friction takes T_fb of it while |τ| grows and
    /// gives it back while |τ| falls (torsion_curve's, on the frictionless row loads).
    fn effective_torque(&self, torque: f64, w: f64) -> f64 {
        let magnitude = torque.abs();
        let disc_torque = 0.5 * self.lambda * magnitude * 1000.0;
        let (m, a) = (self.side.cranks, self.side.crank_circle_radius);
        let row = (disc_torque / (m * a)).hypot(disc_torque / (self.pitch_radius * m));
        let b = &self.bearing;
        let friction =
            b.coefficient * 2.0 * m * row * 0.5 * b.journal_diameter * b.crank_turn / 1000.0;
        let growing = w * torque.signum();
        (magnitude - growing * friction).max(0.0).copysign(torque)
    }

    /// The state (τ, w) solved with the crank side of load level `level`, the housing read
    /// against the rest forces `rest` (module comment; none: no housing term, as at zero
    /// torque).
    fn state(
        &self,
        pins: &[Pins; 2],
        (torque, w): (f64, f64),
        level: usize,
        rest: Option<&[[f64; MAX_PINS]; 2]>,
        warm: &Solution,
    ) -> Result<State, Unconverged> {
        let v = usize::from(w < 0.0);
        let effective = if torque == 0.0 {
            0.0
        } else {
            self.effective_torque(torque, w)
        };
        let target = -self.lambda * effective * 1000.0;
        let solver = &self.solvers[level];
        let discs = [0, 1].map(|d| LoadedDisc {
            gaps: &pins[d].gaps,
            levers: &pins[d].levers,
            arms: &pins[d].arms[v],
            offset: pins[d].offset,
            slack: pins[d].slack,
        });
        let start;
        let warm = if warm.carrier.is_finite() {
            warm
        } else {
            start = solver.at_rest(&discs)?;
            &start
        };
        let solution = solver.solve(&discs, target, warm)?;
        let loads = self.pin_loads(pins, &solution, solver);
        let mean = 0.5 * target;
        let zeta = if mean < 0.0 { -1.0 } else { 1.0 };
        let (across, along) = loads.resultant;
        let chain = self
            .side
            .terms(
                mean.abs(),
                (zeta * across, along),
                1.0,
                effective.abs() * 1000.0,
                self.lambda,
            )
            .total();
        let housing = match (&self.housing, rest) {
            (Some(housing), Some(rest)) if mean != 0.0 => {
                self.housing_angle(housing, &loads.forces, rest, target.abs())
            }
            _ => 0.0,
        };
        let disc_frame = self.lambda * (solution.carrier - solver.compliance * mean);
        Ok(State {
            angle: -(disc_frame + zeta * (chain + housing)),
            forces: loads.forces,
            largest: loads.largest,
            solution,
        })
    }

    /// Each disc's pin forces (by place) in the solution, their mean resultant (F̄_x
    /// across the eccentric, F̄_y along it) and the largest force.
    fn pin_loads(&self, pins: &[Pins; 2], solution: &Solution, solver: &TwoDiscs) -> PinLoads {
        let mut loads = PinLoads {
            forces: [[0.0; MAX_PINS]; 2],
            resultant: (0.0, 0.0),
            largest: 0.0,
        };
        for (d, disc) in pins.iter().enumerate() {
            let y = solution.turns[d];
            let approach = |i: usize| disc.levers[i] * y - disc.gaps[i];
            let deepest = (0..disc.gaps.len()).map(approach).fold(0.0, f64::max);
            if deepest <= 0.0 {
                continue;
            }
            let stiffness = solver.law.stiffness(deepest).0;
            for i in 0..disc.gaps.len() {
                let f = stiffness * approach(i).max(0.0);
                loads.forces[d][disc.place[i]] = f;
                loads.resultant.0 += 0.5 * f * disc.levers[i] / self.pitch_radius;
                loads.resultant.1 -= 0.5 * f * disc.along[i];
                loads.largest = loads.largest.max(f);
            }
        }
        loads
    }

    /// The housing's turn of the discs, 2λ·Σ_d U_h(F_d − F_d,0)/|M*| (housing.rs), rad.
    fn housing_angle(
        &self,
        housing: &Housing,
        forces: &[[f64; MAX_PINS]; 2],
        rest: &[[f64; MAX_PINS]; 2],
        moment: f64,
    ) -> f64 {
        let mut energy = 0.0;
        for (f, f0) in forces.iter().zip(rest) {
            let mut change = [0.0; MAX_PINS];
            for ((c, a), b) in change.iter_mut().zip(f).zip(f0).take(self.pins) {
                *c = a - b;
            }
            energy += housing.energy(&change);
        }
        self.lambda * 2.0 * energy / moment
    }
}
