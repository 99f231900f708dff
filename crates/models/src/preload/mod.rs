//! The one preload rule (docs/models.md §14.5): every model of a whole reducer
//! (`rv_lost_motion`, `geometric_hysteresis` in both readings, `torsion_curve`,
//! `cycloid_pin_contact`, `transmission_error`'s physical reading) judges an overlap of the
//! cycloid stage by the same physics, the same contact law and the same limit, so the same
//! reducer with the same deviations gets the same class in every model.
//!
//! ```text
//! contact law     δ(F) = 2·3.84·10⁻⁵·F^0.9/L^0.8 per pin (two Palmgren line contacts, as
//!                 cycloid_pin_contact and the torsion curve)
//! preload         the zero-torque balance of both discs' pins (balance.rs): the largest
//!                 approach d_max (µm), the largest pin force F_max = δ⁻¹(d_max), the
//!                 no-load torque at the input T_0 = μ·Σ K·d_i·h_i/i (both discs)
//! limits          F_max ≤ F_r (default); d_max ≤ d_lim and T_0 ≤ T_lim when a scenario sets
//!                 them. F_r is the largest pin force at rated torque of the design's profile
//!                 brought to zero play (every clearance changed by one amount until the
//!                 window closes), one disc carrying λ·T_r/2, the largest over q = 4
//!                 positions of the pins per pin pitch
//! class           free: the flanks do not overlap and no gear stage is jammed
//!                 over-preloaded: a limit exceeded, or a jammed involute or crank-bearing
//!                 stage (a negative clearance there has no allowance)
//!                 preloaded within the limit otherwise: a design state, it conforms
//! lumped models   a model that knows the stage as 000's Eq. 16 judges it on its profile:
//!                 the clearances at the pins' places φ_i = 2π·i/z_p of its modification,
//!                 pin circle, pin radius and eccentricity (the contact model's standard
//!                 form), the rest of Eq. 16 (δJ, ΔF_r, δt, ΔF_p) as an equivalent
//!                 equidistant amount, as the torsion curve's one profile; both discs alike
//! ```
//! A model whose modification is one of its inputs (design and error together) takes F_r
//! of the modification as ground; the rated force is kept per thread for the last
//! modification seen (a pure function of it: the same bits whatever the thread).

mod balance;
mod rows;

use std::cell::RefCell;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

use rvtol_deviation::Shown;

use crate::cycloid::CycloidStage;
use crate::{ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec};
pub(crate) use balance::{zero_torque, AlikePins, DiscPins, MAX_PINS};
pub(crate) use rows::Profiles;

/// Palmgren's line-contact constant (mm, N): δ = 3.84·10⁻⁵·F^0.9/L^0.8, two contacts in
/// series per pin (disc–pin, pin–housing).
pub(crate) const PALMGREN: f64 = 3.84e-5;
pub(crate) const CONTACTS_PER_PIN: f64 = 2.0;

/// Points per pin pitch at which the rated force is taken (rv_lost_motion's default q).
const RATED_POSITIONS: usize = 4;

/// The parameters of the rule, the same keys in every model that judges preload.
pub(crate) const PARAMS: [ParamSpec; 4] = [
    ParamSpec { name: "rated_torque_nm", unit: "N·m", description: "T_r, rated output torque (sets the default preload limit)", default: None },
    ParamSpec { name: "preload_limit_pin_force_n", unit: "N", description: "largest pin force at zero torque allowed (default: the largest pin force at rated torque of the design's profile brought to zero play)", default: None },
    ParamSpec { name: "preload_limit_overlap_um", unit: "µm", description: "largest approach of a pin contact at zero torque allowed (default: no limit on it)", default: None },
    ParamSpec { name: "preload_limit_no_load_torque_nm", unit: "N·m", description: "largest no-load torque at the input allowed (default: no limit on it)", default: None },
];

/// The pins' radius and the disc's face width, for a model that has no pin contacts of its
/// own (`geometric_hysteresis`, `transmission_error`).
pub(crate) const PIN_RADIUS: ParamSpec = ParamSpec {
    name: "pin_radius_mm",
    unit: "mm",
    description: "r_rp, pin radius (the preload rule's pin contacts)",
    default: None,
};
pub(crate) const FACE_WIDTH: ParamSpec = ParamSpec {
    name: "disc_face_width_mm",
    unit: "mm",
    description: "L, the disc's face width (the preload rule's contact length)",
    default: None,
};

/// The pin friction's key (a model with a friction of its own declares it once).
pub(crate) const FRICTION: ParamSpec = ParamSpec {
    name: "pin_friction_coefficient",
    unit: "1",
    description: "μ at the pin contacts (the no-load torque of a preload)",
    default: Some(0.0),
};

/// The pin contact law and what turns its forces into a drag at the input.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PinContact {
    /// L, the contact length, mm (private: L^0.8 is kept with it).
    face_width: f64,
    /// μ at the pins.
    pub friction: f64,
    /// i, the reducer's ratio (the input turns i times per output turn).
    pub ratio: f64,
    /// L^0.8, taken once (a preloaded row asks for a force per row).
    face_power: f64,
}

impl PinContact {
    /// The contact law of pins on a face width L (mm) with friction μ, in a reducer of
    /// ratio i.
    pub fn new(face_width: f64, friction: f64, ratio: f64) -> PinContact {
        PinContact {
            face_width,
            friction,
            ratio,
            face_power: face_width.powf(0.8),
        }
    }

    /// L, the contact length, mm.
    pub fn face_width(&self) -> f64 {
        self.face_width
    }

    /// The pin contact's approach δ(F) = 2·3.84·10⁻⁵·F^0.9/L^0.8, mm.
    pub fn approach(&self, force: f64) -> f64 {
        CONTACTS_PER_PIN * PALMGREN * force.powf(0.9) / self.face_power
    }

    /// The force F with δ(F) = `approach`, N.
    pub fn force_at(&self, approach: f64) -> f64 {
        (approach * self.face_power / (CONTACTS_PER_PIN * PALMGREN)).powf(1.0 / 0.9)
    }

    /// The secant law of a pin: K(δ) = F(δ)/δ = C·δ^(1/9) (F ∝ δ^(1/0.9)), Li Lixing's
    /// common stiffness of the most loaded pin, as the load sharing and the zero-torque
    /// balance take it; the coefficient C = (L^0.8/(2·3.84·10⁻⁵))^(1/0.9), N/mm^(10/9).
    pub fn secant_law(&self) -> SecantLaw {
        SecantLaw {
            coefficient: self.force_at(1.0),
        }
    }
}

/// K(δ) = C·δ^(1/9) and its derivative ([`PinContact::secant_law`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SecantLaw {
    /// C, N/mm^(10/9): the force at an approach of 1 mm.
    pub coefficient: f64,
}

impl SecantLaw {
    /// K at the approach δ > 0 (N/mm) and dK/dδ = K/(9·δ); δ^(1/9) by [`ninth_root`] (a
    /// loaded solve asks for it some ten times a point).
    #[inline]
    pub fn stiffness(&self, approach: f64) -> (f64, f64) {
        let stiffness = self.coefficient * ninth_root(approach);
        (stiffness, stiffness / (9.0 * approach))
    }
}

/// Sub-intervals of [1, 2) the mantissa's root is taken in (the top six mantissa bits).
pub(crate) const ROOT_CELLS: usize = 64;

/// binom(1/9, k) for k = 1..7.
const BINOMIAL_NINTH: [f64; 7] = [
    1.0 / 9.0,
    -4.0 / 81.0,
    68.0 / 2187.0,
    -442.0 / 19683.0,
    3094.0 / 177147.0,
    -68068.0 / 4782969.0,
    515372.0 / 43046721.0,
];

/// The cells' midpoints m_i = 1 + (i + ½)/64, their inverses and ninth roots, and 2^(r/9)
/// for r = 0..8.
struct RootTable {
    middle: [f64; ROOT_CELLS],
    inverse: [f64; ROOT_CELLS],
    root: [f64; ROOT_CELLS],
    ninths: [f64; 9],
}

fn root_table() -> &'static RootTable {
    static TABLE: std::sync::OnceLock<RootTable> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut table = RootTable {
            middle: [0.0; ROOT_CELLS],
            inverse: [0.0; ROOT_CELLS],
            root: [0.0; ROOT_CELLS],
            ninths: [0.0; 9],
        };
        for i in 0..ROOT_CELLS {
            let m = 1.0 + (i as f64 + 0.5) / ROOT_CELLS as f64;
            table.middle[i] = m;
            table.inverse[i] = 1.0 / m;
            table.root[i] = m.cbrt().cbrt();
        }
        for (r, ninth) in table.ninths.iter_mut().enumerate() {
            *ninth = (r as f64).exp2().cbrt().cbrt();
        }
        table
    })
}

/// x^(1/9) for x > 0, within a few ulps of `x.cbrt().cbrt()` (tested) at a third of its
/// cost, from IEEE arithmetic alone (the same bits on every machine): x = 2^E·m with
/// m in [1, 2); E = 9q + r gives 2^q·2^(r/9); m's cell i (its top six bits) gives
/// m_i^(1/9)·(1 + u)^(1/9), u = m/m_i − 1 with |u| ≤ 1/129, by the binomial series to u⁷,
/// whose remainder is below |binom(1/9, 8)|·u⁸/(1 − |u|) < 2·10⁻¹⁹ of the root. Zero,
/// subnormal and non-finite x take the two cube roots.
pub(crate) fn ninth_root(x: f64) -> f64 {
    let bits = x.to_bits();
    let biased = (bits >> 52) as i64; // the sign bit is 0 for x > 0
    if !(1..0x7ff).contains(&biased) {
        return x.cbrt().cbrt();
    }
    let table = root_table();
    let m = f64::from_bits((bits & ((1 << 52) - 1)) | (1023 << 52));
    let cell = ((bits >> 46) & (ROOT_CELLS as u64 - 1)) as usize;
    let u = (m - table.middle[cell]) * table.inverse[cell];
    let [c1, c2, c3, c4, c5, c6, c7] = BINOMIAL_NINTH;
    let series = 1.0 + u * (c1 + u * (c2 + u * (c3 + u * (c4 + u * (c5 + u * (c6 + u * c7))))));
    let exponent = biased - 1023;
    let (q, r) = (exponent.div_euclid(9), exponent.rem_euclid(9) as usize);
    let power = f64::from_bits(((q + 1023) as u64) << 52);
    power * table.ninths[r] * table.root[cell] * series
}

/// The preload of an assembly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Preload {
    /// The largest approach of a pin contact at zero torque (the overlap a flank takes up),
    /// µm.
    pub overlap_um: f64,
    /// The largest pin force at zero torque, N.
    pub pin_force: f64,
    /// The no-load torque at the input, N·m.
    pub no_load_torque: f64,
}

impl Preload {
    /// No preload.
    pub const NONE: Preload = Preload {
        overlap_um: 0.0,
        pin_force: 0.0,
        no_load_torque: 0.0,
    };
}

/// The class of an assembly's preload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PreloadClass {
    /// No overlap, no jammed stage.
    Free,
    /// An overlap within the limits: conforms.
    Within,
    /// A limit exceeded or a jammed gear stage: does not conform.
    Over,
}

impl PreloadClass {
    /// The `preloaded` indicator.
    pub fn preloaded(self) -> f64 {
        f64::from(u8::from(self != PreloadClass::Free))
    }

    /// The `over_preloaded` indicator.
    pub fn over(self) -> f64 {
        f64::from(u8::from(self == PreloadClass::Over))
    }
}

/// The limits of the class; the pin force's default is the design's rated force.
#[derive(Debug, Clone, Copy)]
struct Limits {
    pin_force: Option<f64>,
    overlap_um: f64,
    no_load_torque: f64,
}

/// The rule for one reducer.
#[derive(Debug, Clone)]
pub(crate) struct PreloadRule {
    contact: PinContact,
    stage: CycloidStage,
    /// r_rp, mm.
    pin_radius: f64,
    /// One disc's share of the rated torque at the pins, λ·T_r/2, N·mm.
    disc_torque: f64,
    limits: Limits,
    /// The pins with a lever at φ_i = 2π·i/z_p, as columns.
    columns: PinColumns,
    /// The pins' places (fractions of a pitch) at which the rated force is taken.
    positions: Vec<f64>,
    /// Tells this rule's rated forces from another's in the per-thread memory.
    id: u64,
}

/// The factors of the pins with a lever at φ_i = 2π·i/z_p (`index` i), as columns.
#[derive(Debug, Clone, Default)]
struct PinColumns {
    index: Vec<usize>,
    equidistant: Vec<f64>,
    shift: Vec<f64>,
    radial: Vec<f64>,
    eccentric: Vec<f64>,
    pins: AlikePins,
}

impl PinColumns {
    fn new(stage: &CycloidStage, pin_radius: f64) -> PinColumns {
        let zp = stage.pins;
        let mut c = PinColumns::default();
        for i in 0..zp {
            let (sin, cos) = (2.0 * PI * i as f64 / zp as f64).sin_cos();
            let p = stage.pin_factors_at(sin, cos);
            if p.lever.abs() > LEVER_FLOOR * stage.eccentricity {
                c.index.push(i);
                c.equidistant.push(p.equidistant);
                c.shift.push(p.shift);
                c.radial.push(p.radial);
                c.eccentric.push(p.eccentric);
                c.pins.push(p.lever, slip_arm(stage, pin_radius, cos));
            }
        }
        c
    }
}

/// Numbers the rules (the memory of rated forces is keyed by it).
static RULES: AtomicU64 = AtomicU64::new(0);

thread_local! {
    /// The last rated force computed on this thread: (rule, Δr_rp bits, Δr_p bits, F_r).
    static RATED: RefCell<(u64, u64, u64, f64)> = const { RefCell::new((u64::MAX, 0, 0, 0.0)) };
}

impl PreloadRule {
    /// Reads the rule's parameters ([`PARAMS`], [`FRICTION`]) for the stage `stage` with
    /// pins of radius `pin_radius`, face width `face_width`, ratio i and λ.
    pub fn from_params(
        params: &ModelParams,
        stage: &CycloidStage,
        pin_radius: f64,
        face_width: f64,
        (ratio, lambda): (f64, f64),
    ) -> Result<Self, ModelError> {
        let friction = params.number(FRICTION.name, FRICTION.default)?;
        if !(0.0..1.0).contains(&friction) {
            return Err(ModelError::new(
                FRICTION.name,
                format!("must lie in [0, 1), got {}", Shown(friction)),
            ));
        }
        let rated_torque = params.positive("rated_torque_nm", None)?;
        let limit = |key: &str| -> Result<Option<f64>, ModelError> {
            let value = params.number(key, Some(f64::INFINITY))?;
            if value < 0.0 {
                return Err(ModelError::new(
                    key,
                    format!("must not be negative, got {}", Shown(value)),
                ));
            }
            Ok(value.is_finite().then_some(value))
        };
        let limits = Limits {
            pin_force: limit("preload_limit_pin_force_n")?,
            overlap_um: limit("preload_limit_overlap_um")?.unwrap_or(f64::INFINITY),
            no_load_torque: limit("preload_limit_no_load_torque_nm")?.unwrap_or(f64::INFINITY),
        };
        let teeth = stage.teeth;
        // The grid's positions: pin i at 2π·(i + f)/z_p with f = (z_c·k mod q)/q.
        let mut positions: Vec<f64> = (0..RATED_POSITIONS)
            .map(|k| ((teeth * k) % RATED_POSITIONS) as f64 / RATED_POSITIONS as f64)
            .collect();
        positions.sort_by(f64::total_cmp);
        positions.dedup();
        let columns = PinColumns::new(stage, pin_radius);
        Ok(PreloadRule {
            contact: PinContact::new(face_width, friction, ratio),
            stage: *stage,
            pin_radius,
            disc_torque: 0.5 * lambda * rated_torque * 1000.0,
            limits,
            columns,
            positions,
            id: RULES.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// The contact law.
    pub fn contact(&self) -> &PinContact {
        &self.contact
    }

    /// r_rp, mm.
    pub fn pin_radius(&self) -> f64 {
        self.pin_radius
    }

    /// F_r of the modification (Δr_rp, Δr_p), N (module comment).
    pub fn rated_pin_force(&self, equidistant: f64, shift: f64) -> f64 {
        if let Some(limit) = self.limits.pin_force {
            return limit;
        }
        let key = (self.id, equidistant.to_bits(), shift.to_bits());
        let cached = RATED.with(|m| {
            let m = m.borrow();
            ((m.0, m.1, m.2) == key).then_some(m.3)
        });
        if let Some(force) = cached {
            return force;
        }
        let force = self.design_rated_force(equidistant, shift);
        RATED.with(|m| *m.borrow_mut() = (key.0, key.1, key.2, force));
        force
    }

    /// F_r computed (no memory).
    pub fn design_rated_force(&self, equidistant: f64, shift: f64) -> f64 {
        let stage = &self.stage;
        let zp = stage.pins;
        let lever = stage.eccentricity * stage.teeth as f64;
        self.positions
            .iter()
            .map(|&f| {
                let mut pins = DiscPins::new(0.0, 0.0);
                for i in 0..zp {
                    let phi = 2.0 * PI * (i as f64 + f) / zp as f64;
                    let (sin, cos) = phi.sin_cos();
                    let p = stage.pin_factors_at(sin, cos);
                    if p.lever.abs() > LEVER_FLOOR * stage.eccentricity {
                        let gap = equidistant * p.equidistant + shift * p.shift;
                        pins.push(gap, p.lever, 0.0);
                    }
                }
                balance::closed_pin_force(&self.contact, self.disc_torque, (zp, lever), pins)
            })
            .fold(0.0, f64::max)
    }

    /// The class of a preload of a stage whose flanks overlap (`overlapping`) or not, with a
    /// gear stage of negative clearance (`jammed`) or not, the rated force taken for the
    /// modification (Δr_rp, Δr_p) when the default limit applies.
    pub fn classify(
        &self,
        preload: &Preload,
        (overlapping, jammed): (bool, bool),
        modification: (f64, f64),
    ) -> PreloadClass {
        if jammed {
            return PreloadClass::Over;
        }
        if !overlapping {
            return PreloadClass::Free;
        }
        let over = preload.overlap_um > self.limits.overlap_um
            || preload.no_load_torque > self.limits.no_load_torque
            || preload.pin_force > self.rated_pin_force(modification.0, modification.1);
        if over {
            PreloadClass::Over
        } else {
            PreloadClass::Within
        }
    }

    /// The preload of one disc's clearances Δ_i at the pins' places φ_i = 2π·i/z_p (the
    /// contact model's profile), both discs alike.
    pub fn of_clearances(&self, clearances: &[f64]) -> Preload {
        let mut gaps = [0.0; MAX_PINS];
        for (gap, &i) in gaps.iter_mut().zip(&self.columns.index) {
            *gap = clearances[i];
        }
        self.alike(&gaps).unwrap_or(Preload::NONE)
    }

    /// Whether the flanks of the profile of the modification (Δr_rp, Δr_p) with the pin
    /// circle, pin radius and eccentricity errors (δr_p, δr_rp, δe) overlap, and its
    /// preload (module comment): the contact model's clearances at φ_i = 2π·i/z_p.
    pub fn of_profile(
        &self,
        (equidistant, shift): (f64, f64),
        errors: [f64; 3],
    ) -> (bool, Preload) {
        let [pin_circle, pin_radius, eccentric] = errors;
        let c = &self.columns;
        let mut gaps = [0.0; MAX_PINS];
        for (j, gap) in gaps[..c.index.len()].iter_mut().enumerate() {
            *gap = equidistant * c.equidistant[j] + shift * c.shift[j] + pin_circle * c.radial[j]
                - pin_radius
                + eccentric * c.eccentric[j];
        }
        match self.alike(&gaps) {
            Some(load) => (true, load),
            None => (false, Preload::NONE),
        }
    }

    /// The balance of both discs alike on the gaps of the pins with a lever (None: the
    /// flanks do not overlap).
    fn alike(&self, gaps: &[f64; MAX_PINS]) -> Option<Preload> {
        let n = self.columns.index.len();
        balance::alike(&self.contact, &gaps[..n], &self.columns.pins)
    }
}

/// Levers below this fraction of e (pins within about 1e-12 rad of φ = 0 or π) hold no turn
/// of the disc.
pub(crate) const LEVER_FLOOR: f64 = 1e-12;

/// h, the arm of the contact's tangent about the disc centre (the pin's slip per radian of
/// the disc's turn against the housing), mm (docs/models.md §13).
pub(crate) fn slip_arm(stage: &CycloidStage, pin_radius: f64, cos: f64) -> f64 {
    let k1 = stage.k1();
    let s = (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
    let (r_p, e) = (stage.pin_circle_radius, stage.eccentricity);
    ((r_p * (k1 * cos - 1.0) - e * (k1 - cos)) / s + pin_radius).abs()
}

/// Names of the rule's indicators.
pub(crate) const PRELOADED: &str = "preloaded";
pub(crate) const OVER_PRELOADED: &str = "over_preloaded";

/// The rule's outputs, in order: overlap, pin force, no-load torque, preloaded, over.
pub(crate) fn outputs() -> [OutputSpec; 5] {
    let output = |name: &str, unit: &str, description: &'static str, kind| OutputSpec {
        name: name.into(),
        unit: unit.into(),
        description,
        kind,
        condition: None,
    };
    use OutputKind::{Continuous, Indicator};
    [
        output("preload_overlap_um", "µm", "largest approach of a pin contact at zero torque (where the windows are narrowest): the overlap a flank takes up (0 when free)", Continuous),
        output("preload_pin_force_n", "N", "largest pin force at zero torque (where the windows are narrowest; 0 when free)", Continuous),
        output("no_load_torque_nm", "N·m", "drag torque at the input from the pin friction under the preload, both discs (0 when free)", Continuous),
        output(PRELOADED, "fraction", "1 when the flanks overlap or a gear stage interferes: the free play is gone (a preload within the limits conforms)", Indicator),
        output(OVER_PRELOADED, "fraction", "1 when the preload exceeds a limit (pin force, overlap or no-load torque; by default the design's largest pin force at rated torque) or a gear stage interferes: the assembly does not conform", Indicator),
    ]
}

#[cfg(test)]
mod tests;
