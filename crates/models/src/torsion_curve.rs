//! `torsion_curve`: the hysteresis (torsion) curve of an RV reducer, output angle against
//! output torque with the input locked, from −rated to +rated and back, and the catalogue
//! figures read from it: lost motion, hysteresis loss, torsional rigidity. It combines the
//! free play of document 000, the pin-contact load sharing of document 003 on the same
//! profile, the compliance chain (needle rows and the disc around their bores and pillar
//! holes, crank shafts, preloaded support bearings in their seats and the plates' paths to
//! the pillars, carrier pillars on their roots, the end plate's bolted joints and bending,
//! the housing around the pins, involute stage; crates/models/src/stiffness/) and Coulomb
//! friction at the pins and crank bearings; docs/models.md §13.
//!
//! Units: torque in N·m (N·mm inside), angles in arcmin at the output (rad inside),
//! lengths in mm. Sign convention: a positive torque turns the output in the positive
//! sense and the output angle θ(T) has the sign of T; the loading branch runs from −T_r
//! to +T_r, the unloading branch back.
//!
//! ```text
//! one profile (docs/models.md §13): the load sharing's clearances (003's standard form)
//! are built from 000's inputs: Δr_rp + δΔr_rp + δ_eq, Δr_p + δΔr_p, δr_p, δr_rp, δe, where
//! δ_eq = c_other·e·z_c/2 is the equidistant amount whose backlash 2δ/(e·z_c) equals
//! 000's Eq. 16 terms that have no place on a pin (δJ, ΔF_r, δt, ΔF_p), taken from
//! geometric_hysteresis on a row that holds only them.
//!
//! free play (rad at the output, λ = (z_c/z_p)(1 − 1/i)):
//!   cycloid stage  c_cyc = λ·(β_f − β_r),  β_f = min_{l_i>0} Δ_i/l_i,  β_r = max_{l_i<0} Δ_i/l_i
//!                  (= λ·2(Δr_rp − √(1 − K1²)·Δr_p)/(e·z_c) for a pure modification: 000
//!                  Eq. 13–15, the same as 003's form; negative: the flanks overlap)
//!   c = max(0, Δφ12') + max(0, Δφ56') + max(0, c_cyc)            (000 Eq. 5/12, 20, 21)
//!   `clearance_reading` = 0: c_cyc = 000's printed Eq. 16 (geometric_hysteresis)
//!
//! elastic angle E(T; s) at T ≥ 0 while the output moves forward (s = +1, loading) or
//! backward (s = −1, unloading):
//!   T_fb  = μ_b·2m·G·(d_j/2)·(z1/z2)  crank-bearing friction torque at the output
//!           (2m needle rows; G = √((T_c/(m·a_w))² + (F_x/m)²); each row turns by z1/z2 per
//!           radian of the output)
//!   T_c   = s_d·λ·(T − s·T_fb)                 (s_d the disc's share of the load)
//!   β     load sharing of 003 with Σ F_i·(l_i + s·λ·μ_p·h_i) = T_c (cycloid_pin_contact)
//!   E     = λ·(β − β_ref) + the crank side's terms (CrankSide: needle rows, disc bore and
//!           web, shaft, supports, seats' paths, carrier, end plate's joints and bending,
//!           involute; F_x with its sign) at (T_c, F) less those at rest, (0, F_0) the
//!           frictionless zero-torque resultant of a preload (none with free play)
//!           + housing λ·2·U_h(F − F_0)/T_c (stiffness/housing.rs, F_0 the zero-torque
//!           forces under the same s·λ·μ_p); `body_compliance` = 0: rigid discs, plates
//!           and housing
//!   β_ref = β_f when the stage has free play, else β_0, the zero-torque equilibrium of the
//!           preloaded flanks (Σ F_i·l_i = 0)
//!
//! the curve:  θ(T) = c/2 + E(T; s) for T > 0, θ(−T) = −(c/2 + E(T; −s)), and at T = 0 the
//!             free play c is crossed (the loop's vertical segment)
//!   lost motion        = midline θ(+3 % T_r) − midline θ(−3 % T_r)
//!                      = c + E(0.03·T_r; +1) + E(0.03·T_r; −1)
//!   hysteresis loss    = width of the loop at T = 0 = c + 2·E(0; −1)
//!   torsional rigidity = (T_r − T_r/2)/(E(T_r; +1) − E(T_r/2; +1))   (loading branch)
//!   angle at rated     = c/2 + E(T_r; +1)
//! ```
//!
//! Readings (docs/models.md §13):
//! - One profile. 000's printed Eq. 16 gives its own design modification (Δr_rp = −0.010,
//!   Δr_p = −0.012 mm) +0.27 arcmin of free play, while the same numbers in 000's Eq. 13–15
//!   and in 003's clearance form overlap the flanks by 0.26 arcmin at the disc (0.33 with
//!   Table 8's printed K1 = 0.72): the printed first line puts √(1 − K1²) on the
//!   equidistant term too. The default takes the free play from the
//!   clearances the load sharing uses, so that both see one profile; `clearance_reading` = 0
//!   keeps 000's printed term for the free play (and then the two disagree).
//! - Preload. A cycloid stage whose flanks overlap has no free play: both flanks carry
//!   load at zero torque (their preload), the reverse flank unloads as the torque rises,
//!   and the curve starts stiffer; with friction its loop has a width at zero torque. The
//!   preload is judged by the one rule of every model (`crate::preload`, docs/models.md
//!   §14.8) on the same profile: its overlap, largest pin force and no-load torque at zero
//!   torque, `preloaded`, and `over_preloaded` (the largest pin force above the design's at
//!   rated torque, or a jammed gear stage), which flags `lost_motion_arcmin` and
//!   `clearance_arcmin` non-conforming. 000's involute and crank-bearing terms, when
//!   negative (an interference fit), add no free play and are not stiffened.
//! - Friction: Coulomb at the pins (μ_p, h_i the arm of the contact's tangent about the
//!   disc centre) and at the needle rows (μ_b, rolling-bearing coefficient on the journal
//!   radius); the support and main bearings and the seals are left out. Friction
//!   vanishes with the load on a stage with free play, so its loop closes at zero torque
//!   unless the stage is preloaded.
//! - Both flanks alike: the negative branch mirrors the positive one (|T|).
//! - 6-DOF parts: 000's input shaft (du, dv, dα, dβ at the sun mesh through 001 Eq. 5–8)
//!   acts on the involute free play only; dw and dγ move no mesh. The cranks sit at their
//!   design places (their deviations are `crank_elastic_error`'s), so the chain is the same
//!   for every crank and crank angle.
//! - A row with a non-finite input, or k·(1 + x_k) ≤ 0, gives NaN outputs (the engine counts
//!   them).
//!
//! Left out (docs/models.md §13 says why and how much): the bending of the disc's lobes, the
//! main bearings (no torque about the axis; their tilt under the two discs' couple stays
//! under 1 % of E), the rows' edge loading under the shaft's slope, the disc's shift along
//! its eccentric in the load sharing (under 1 % of E), the planet gear's force on the crank
//! shaft, the friction of the support and main bearings and of the seals, the input shaft's
//! torsion.

use crate::cycloid_pin_contact::CycloidPinContact;
use crate::geometric_hysteresis::{self, GeometricHysteresis};
use crate::preload::{self, Preload, PreloadRule};
use crate::stiffness::{build, ChainTerms, CrankSide, Housing};
use crate::{
    concat_params, ConditionEffect, Curve, CurveStyle, ErrorModel, InputSpec, ModelEntry,
    ModelError, ModelParams, OutputCondition, OutputKind, OutputSpec, ParamSpec, Series,
    ARCMIN_PER_RAD,
};

/// Inputs of 000 (`geometric_hysteresis`), in its order, come first: its eighteen, without
/// the fitter's measuring error (the torsion curve takes the pins as drawn, one class, where
/// that input has no effect; the embedded model gets 0 for it).
const HYSTERESIS_INPUTS: usize = 18;
/// Positions of 000's inputs that shape the profile.
const EQUIDISTANT: usize = 2;
const SHIFT: usize = 3;
const PIN_CIRCLE_RADIUS_ERROR: usize = 4;
const PIN_RADIUS_ERROR: usize = 5;
/// δJ, ΔF_r, δt, ΔF_p: 000's Eq. 16 terms without a place on a pin.
const OTHER_TERMS: [usize; 4] = [6, 7, 8, 9];
const EQUIDISTANT_ERROR: usize = 10;
const SHIFT_ERROR: usize = 11;
const ECCENTRICITY_ERROR: usize = 12;

/// The inputs after 000's, in order.
const OWN_INPUTS: [(&str, &str, &str); 1] = [(
    "crank_bearing_stiffness_error",
    "1",
    "x_k, relative error of the needle rows' stiffness, every crank: k·(1 + x_k)",
)];

/// The outputs, in order.
const OUTPUTS: [(&str, &str, &str, OutputKind); 5] = [
    (
        "lost_motion_arcmin",
        "arcmin",
        "midline angle at +3 % minus −3 % rated torque: c + E(3 %; +) + E(3 %; −)",
        OutputKind::Continuous,
    ),
    (
        "hysteresis_loss_arcmin",
        "arcmin",
        "width of the loop at zero torque: c + 2·E(0; −)",
        OutputKind::Continuous,
    ),
    (
        "torsional_rigidity_nm_per_arcmin",
        "N·m/arcmin",
        "(T_r − T_r/2)/(E(T_r) − E(T_r/2)) on the loading branch, 50 % to 100 % rated",
        OutputKind::Continuous,
    ),
    (
        "clearance_arcmin",
        "arcmin",
        "c, free play: 000's involute and crank-bearing terms and the cycloid stage's play",
        OutputKind::Continuous,
    ),
    (
        "angle_at_rated_arcmin",
        "arcmin",
        "output angle at rated torque on the loading branch: c/2 + E(T_r; +)",
        OutputKind::Continuous,
    ),
];

/// The model's own keys, in three runs between the crank side's (`PARAMS`).
const OWN_PARAMS: [&[ParamSpec]; 3] = [
    &[
        ParamSpec {
            name: "sun_teeth",
            unit: "1",
            description: "Z1, sun gear teeth (000 Table 8: 12)",
            default: None,
        },
        ParamSpec {
            name: "planet_teeth",
            unit: "1",
            description: "Z2, planet gear teeth (000 Table 8: 42)",
            default: None,
        },
        ParamSpec {
            name: "cycloid_teeth",
            unit: "1",
            description: "Zc, cycloid teeth = pin_count − 1 (000 Table 8: 39)",
            default: None,
        },
        ParamSpec {
            name: "pin_count",
            unit: "1",
            description: "Zp, pins, 3..=128 (000 Table 8: 40)",
            default: None,
        },
        ParamSpec {
            name: "pin_circle_radius_mm",
            unit: "mm",
            description: "rp, pin centre circle radius (000 Table 8: 52)",
            default: None,
        },
        ParamSpec {
            name: "eccentricity_mm",
            unit: "mm",
            description: "e, cycloid eccentricity (000 Table 8: 0.9)",
            default: None,
        },
        ParamSpec {
            name: "curtate_ratio",
            unit: "1",
            description: "K1 of 000's Eq. 16, 17 only; default e·Zp/rp (000 Table 8 prints 0.72); the profile uses e·Zp/rp",
            default: None,
        },
        ParamSpec {
            name: "pressure_angle_deg",
            unit: "deg",
            description: "α of the involute stage (000 Table 8: 20)",
            default: Some(20.0),
        },
        ParamSpec {
            name: "center_distance_mm",
            unit: "mm",
            description: "a0, the lever of 000 Eq. 18, 20 (000 Table 8: 27.5)",
            default: None,
        },
        ParamSpec {
            name: "sun_pitch_radius_mm",
            unit: "mm",
            description: "r1, sun pitch radius of 000 Eq. 5 (000 Table 8: 13.5)",
            default: None,
        },
        ParamSpec {
            name: "sun_gear_axial_position_mm",
            unit: "mm",
            description: "z of the sun mesh from the input shaft's deviation reference point (000)",
            default: Some(0.0),
        },
        ParamSpec {
            name: "pin_radius_mm",
            unit: "mm",
            description: "r_rp, pin radius (000 Table 8: 2)",
            default: None,
        },
        ParamSpec {
            name: "disc_face_width_mm",
            unit: "mm",
            description: "contact length of one cycloid disc",
            default: None,
        },
        ParamSpec {
            name: "disc_load_share",
            unit: "1",
            description: "share of the output torque carried by one disc (two discs: 0.5)",
            default: Some(0.5),
        },
        ParamSpec {
            name: "disc_torque_balance",
            unit: "1",
            description: "1: disc torque share·λ·T and output angle λ·(disc frame), λ = (z_c/z_p)(1 − 1/i); 0: share·T and one to one (as 000, 003, 004 print it)",
            default: Some(1.0),
        },
    ],
    &[
        ParamSpec {
            name: "crank_count",
            unit: "1",
            description: "m, cranks, 2 or 3",
            default: Some(2.0),
        },
        ParamSpec {
            name: "crank_circle_radius_mm",
            unit: "mm",
            description: "a_w, crank axes from the reducer axis; default center_distance_mm",
            default: None,
        },
    ],
    &[
        ParamSpec {
            name: "pin_friction_coefficient",
            unit: "1",
            description: "μ_p, Coulomb friction at the pin contacts, in [0, 0.5)",
            default: None,
        },
        ParamSpec {
            name: "crank_bearing_friction_coefficient",
            unit: "1",
            description: "μ_b, friction coefficient of a needle row on its journal radius, in [0, 0.5)",
            default: None,
        },
        ParamSpec {
            name: "clearance_reading",
            unit: "1",
            description: "1: the cycloid stage's free play from the load sharing's own profile; 0: 000's printed Eq. 16",
            default: Some(1.0),
        },
        ParamSpec {
            name: "rated_torque_nm",
            unit: "N·m",
            description: "T_r, rated output torque (RV-20E catalogue: 167)",
            default: None,
        },
    ],
];

/// The crank side's keys (`stiffness::build`), split where the model's own crank keys go.
const CRANK_SIDE: (&[ParamSpec], &[ParamSpec]) = build::PARAMS.as_slice().split_at(2);

/// The preload rule's limits (its first key, the pin radius, is this model's own).
const PRELOAD_LIMITS: &[ParamSpec] = preload::PARAMS.as_slice().split_at(1).1;

const PARAMS: [ParamSpec;
    OWN_PARAMS[0].len()
        + OWN_PARAMS[1].len()
        + OWN_PARAMS[2].len()
        + build::PARAMS.len()
        + PRELOAD_LIMITS.len()] = concat_params(&[
    OWN_PARAMS[0],
    CRANK_SIDE.0,
    OWN_PARAMS[1],
    CRANK_SIDE.1,
    OWN_PARAMS[2],
    PRELOAD_LIMITS,
]);

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "torsion_curve",
    summary: "hysteresis (torsion) curve, input locked: 000 free play, 003 load sharing on the same profile, needle rows, discs, crank shafts, preloaded supports, carrier with its bolted end plate, housing and involute stage in series, Coulomb friction; lost motion at ±3 % rated, hysteresis loss, torsional rigidity 50-100 % rated",
    params: &PARAMS,
    build: |params| Ok(Box::new(TorsionCurve::from_params(params)?)),
    example_params: TorsionCurve::rv20e_params,
    example_inputs: &[
        ("common_normal_upper_deviation_mm", 0.0035),
        ("common_normal_lower_deviation_mm", -0.0309),
        ("equidistant_modification_mm", -0.010),
        ("shift_modification_mm", -0.012),
    ],
};

/// Points per branch of the drawn curve, −rated..=+rated (the 0 point is drawn twice).
const CURVE_STEPS: usize = 100;

/// One branch of the drawn loop: (torque N·m, angle arcmin) points.
type Branch = Vec<(f64, f64)>;

/// The torque of the catalogue's lost motion, a share of the rated torque (±3 %).
const LOST_MOTION_TORQUE_SHARE: f64 = 0.03;

/// The torsion curve model with its sub-models built from one parameter set.
#[derive(Debug, Clone)]
pub struct TorsionCurve {
    hysteresis: GeometricHysteresis,
    /// Load sharing of one disc, m cranks on the crank circle, no per-pin errors.
    contact: CycloidPinContact,
    /// The one preload rule (docs/models.md §14.5).
    rule: PreloadRule,
    side: CrankSide,
    /// The housing around the pin grooves (`None`: rigid bodies).
    housing: Option<Housing>,
    rated_torque: f64,
    pin_friction: f64,
    bearing_friction: f64,
    journal_diameter: f64,
    /// z1/z2: turn of a crank against its disc per radian of the output, input locked.
    crank_turn: f64,
    consistent_clearance: bool,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

/// The profile of one row and what follows from it (stack only).
#[derive(Debug, Clone, Copy)]
struct RowState {
    /// Clearances Δ_i, pin order.
    clearances: [f64; crate::cycloid_pin_contact::MAX_PINS],
    /// β_ref, rad.
    reference: f64,
    /// c, free play at the output, rad.
    free_play: f64,
    /// The cycloid stage overlaps.
    preloaded: bool,
    /// The involute or crank-bearing stage has a negative clearance.
    jammed: bool,
    /// Needle stiffness factor 1 + x_k.
    needle_factor: f64,
    /// F_0, the pin forces at zero torque (a preload's; zero with free play), N: without
    /// friction, and on the branch that moves forward and backward (`ZeroForces`).
    preload_forces: ZeroForces,
    /// The crank side's terms at rest: loaded by the frictionless zero-torque resultant
    /// of a preload (none with free play), the state every load state is measured from,
    /// as the pins' turn is from β_ref. rad at the output.
    rest: ChainTerms,
}

/// The pin forces at zero torque of a preloaded stage, frictionless and with the friction
/// of either direction of motion (N, pin order). The housing's angle is read from the
/// change of the pin forces that the torque makes (λ·2·U_h(F − F_0)/T_c, Clapeyron), so
/// F_0 is the zero-torque state of the same branch: with friction the zero-torque forces
/// differ from the frictionless ones, and against those F − F_0 would stay finite as the
/// torque vanishes and the term grow as 1/T_c (the loading branch of a preloaded RV-20E
/// rose by 0.06 arcmin at 0.02 N·m and fell back by 0.3 N·m).
#[derive(Debug, Clone, Copy)]
struct ZeroForces([[f64; crate::cycloid_pin_contact::MAX_PINS]; 3]);

impl ZeroForces {
    /// None carry: a stage with free play.
    const NONE: ZeroForces = ZeroForces([[0.0; crate::cycloid_pin_contact::MAX_PINS]; 3]);

    /// F_0 under the pin friction `friction` (0, +λ·μ_p forward, −λ·μ_p backward).
    fn under(&self, friction: f64) -> &[f64; crate::cycloid_pin_contact::MAX_PINS] {
        match friction.partial_cmp(&0.0) {
            Some(std::cmp::Ordering::Greater) => &self.0[1],
            Some(std::cmp::Ordering::Less) => &self.0[2],
            _ => &self.0[0],
        }
    }
}

/// The elastic angle of one load case split into its elements, arcmin at the output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorsionTerms {
    /// Pin contacts: λ·(β − β_ref).
    pub pins: f64,
    /// The crank side, element by element.
    pub chain: ChainTerms,
}

impl TorsionTerms {
    /// E, the sum.
    pub fn total(&self) -> f64 {
        self.pins + self.chain.total()
    }
}

impl TorsionCurve {
    /// The RV-20E: 000 Table 8 (K1 as printed, 0.72, for 000's terms; pin radius 2 mm;
    /// a0 = 27.5 mm, also the crank circle), two cranks, rated torque 167 N·m (catalogue),
    /// and the estimated dimensions of docs/models.md §13: disc face width 8 mm, eccentric
    /// journal 15 mm with 15 needles of 3 × 6 mm, support span 30.75 mm with the eccentrics
    /// 9 mm apart, 30202-size supports (13 rollers of 8.2 mm at 13°, 11.75 mm wide, 35 mm
    /// outside, ISO 355), two 11 × 11 × 19 mm pillars, planet face width 8 mm with an 11 mm
    /// overhang; friction 0.02 at the pins
    /// (000 Table 7's dynamic coefficient) and 0.002 in the needle rows (SKF).
    pub fn rv20e_params() -> ModelParams {
        GeometricHysteresis::rv20e_params()
            .with_number("pin_radius_mm", 2.0)
            .with_number("disc_face_width_mm", 8.0)
            .with_number("crank_circle_radius_mm", 27.5)
            .with_number("crank_journal_diameter_mm", 15.0)
            .with_number("needle_roller_count", 15.0)
            .with_number("needle_roller_diameter_mm", 3.0)
            .with_number("needle_roller_length_mm", 6.0)
            .with_number("crank_support_span_mm", 30.75)
            .with_number("crank_eccentric_spacing_mm", 9.0)
            .with_number("support_roller_count", 13.0)
            .with_number("support_roller_length_mm", 8.225)
            .with_number("support_contact_angle_deg", 13.0)
            .with_number("support_bearing_width_mm", 11.75)
            .with_number("support_bearing_outer_diameter_mm", 35.0)
            .with_number("carrier_pillar_width_mm", 11.0)
            .with_number("carrier_pillar_depth_mm", 11.0)
            .with_number("carrier_pillar_length_mm", 19.0)
            .with_number("planet_face_width_mm", 8.0)
            .with_number("planet_gear_overhang_mm", 10.875)
            .with_number("pin_friction_coefficient", 0.02)
            .with_number("crank_bearing_friction_coefficient", 0.002)
            .with_number("rated_torque_nm", 167.0)
    }

    /// Builds the model: 000 and 003 from the same parameter set (their own checks name the
    /// keys), then the crank side and its own parameters.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        // 000 with its stage terms in the disc frame as printed: the torsion curve builds the
        // cycloid stage's free play from the pins itself and takes λ to the output there.
        let hysteresis_keys: Vec<&str> = geometric_hysteresis::ENTRY
            .params
            .iter()
            .map(|p| p.name)
            .filter(|name| *name != "reading")
            .collect();
        let mut hysteresis_params = params.subset(&hysteresis_keys);
        hysteresis_params.insert(
            "reading".to_string(),
            crate::ParamValue::Text("document_000".to_string()),
        );
        let hysteresis = GeometricHysteresis::from_params(&hysteresis_params)?;
        // Selective fitting changes the pins the load sharing sees; the torsion curve
        // models the pins as drawn.
        if params.count("pin_classes", Some(1.0))? != 1 {
            return Err(ModelError::new(
                "pin_classes",
                "selective fitting is modelled by geometric_hysteresis only; the torsion curve takes the pins as drawn (1 class)",
            ));
        }
        // 000 has checked center_distance_mm (present and positive).
        let center_distance = params.positive("center_distance_mm", None)?;
        let crank_circle_radius =
            params.positive("crank_circle_radius_mm", Some(center_distance))?;
        let cranks = params.count("crank_count", Some(2.0))? as usize;
        if !(2..=3).contains(&cranks) {
            return Err(ModelError::new(
                "crank_count",
                format!("must be 2 or 3, got {cranks}"),
            ));
        }
        let contact = CycloidPinContact::of_disc(params, cranks, crank_circle_radius)?;
        let consistent_clearance = params.flag("clearance_reading", true)?;
        let elastic_bodies = params.flag("body_compliance", true)?;
        let rated_torque = params.positive("rated_torque_nm", None)?;
        let stage = *contact.stage();
        let reducer = build::Reducer {
            cranks,
            crank_circle_radius,
            pins: stage.pins,
            teeth: stage.teeth,
            pin_circle_radius: stage.pin_circle_radius,
            eccentricity: stage.eccentricity,
            curtate: contact.k1(),
            face_width: contact.face_width(),
            ratio: hysteresis.ratio(),
            reference_disc_torque: contact.disc_torque(0.03 * rated_torque),
            elastic_bodies,
        };
        let built = build::crank_side(params, &reducer)?;
        let pin_friction = params.friction_coefficient("pin_friction_coefficient")?;
        let bearing_friction = params.friction_coefficient("crank_bearing_friction_coefficient")?;
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let inputs = hysteresis.inputs()[..HYSTERESIS_INPUTS]
            .iter()
            .cloned()
            .chain(
                OWN_INPUTS
                    .iter()
                    .map(|&(name, unit, description)| InputSpec {
                        name: name.into(),
                        unit: unit.into(),
                        description,
                    }),
            )
            .collect();
        let rule = PreloadRule::from_params(
            params,
            contact.stage(),
            params.positive("pin_radius_mm", None)?,
            contact.face_width(),
            (hysteresis.ratio(), contact.torque_factor()),
        )?;
        let lost_motion = Some(OutputCondition {
            indicator: preload::OVER_PRELOADED,
            effect: ConditionEffect::NonConforming,
        });
        let mut outputs: Vec<OutputSpec> = OUTPUTS
            .iter()
            .map(|&(name, unit, description, kind)| OutputSpec {
                name: name.into(),
                unit: unit.into(),
                description,
                kind,
                condition: match name {
                    "lost_motion_arcmin" | "clearance_arcmin" => lost_motion,
                    _ => None,
                },
            })
            .collect();
        outputs.extend(preload::outputs());
        Ok(TorsionCurve {
            hysteresis,
            contact,
            rule,
            side: built.side,
            housing: built.housing,
            rated_torque,
            pin_friction,
            bearing_friction,
            journal_diameter: built.journal_diameter,
            crank_turn: built.crank_turn,
            consistent_clearance,
            inputs,
            outputs,
        })
    }

    /// Rated torque T_r, N·m.
    pub fn rated_torque(&self) -> f64 {
        self.rated_torque
    }

    /// λ of the embedded contact model.
    pub fn torque_factor(&self) -> f64 {
        self.contact.torque_factor()
    }

    /// The crank side the model chains after the pins.
    pub fn crank_side(&self) -> &CrankSide {
        &self.side
    }

    /// 000's stage outputs for a row: [hysteresis, involute, cycloid, crank, overlap]
    /// (`geometric_hysteresis`'s order).
    fn hysteresis_outputs(&self, x: &[f64]) -> [f64; 5] {
        let mut row = [0.0; geometric_hysteresis::INPUT_COUNT];
        row[..HYSTERESIS_INPUTS].copy_from_slice(&x[..HYSTERESIS_INPUTS]);
        self.hysteresis.stage_outputs(&row)
    }

    /// The contact row of the one profile (module comment): (T, Δr_rp', Δr_p', δr_p,
    /// δr_rp, δe, 0) with 000's modification errors added and δ_eq for δJ, ΔF_r, δt, ΔF_p.
    fn profile_row(&self, x: &[f64]) -> [f64; 7] {
        let mut others = [0.0; geometric_hysteresis::INPUT_COUNT];
        for i in OTHER_TERMS {
            others[i] = x[i];
        }
        let out = self.hysteresis.stage_outputs(&others);
        // 000's cycloid term of these inputs alone (Kn·δe vanishes without modification),
        // arcmin at the disc, as an equidistant amount: backlash 2δ/(e·z_c).
        let equivalent = 0.5 * out[2] / ARCMIN_PER_RAD * self.side.pitch_radius;
        [
            0.0,
            x[EQUIDISTANT] + x[EQUIDISTANT_ERROR] + equivalent,
            x[SHIFT] + x[SHIFT_ERROR],
            x[PIN_CIRCLE_RADIUS_ERROR],
            x[PIN_RADIUS_ERROR],
            x[ECCENTRICITY_ERROR],
            0.0,
        ]
    }

    /// The profile, free play and preload of one row; `None` when it cannot be evaluated.
    fn row_state(&self, x: &[f64]) -> Option<RowState> {
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let needle_factor = 1.0 + x[HYSTERESIS_INPUTS];
        if needle_factor <= 0.0 {
            return None;
        }
        let clearances = self.contact.profile(&self.profile_row(x));
        let (forward, reverse) = self.contact.flank_contacts(&clearances);
        let play = forward - reverse;
        if !play.is_finite() {
            return None;
        }
        let lambda = self.contact.torque_factor();
        let stages = self.hysteresis_outputs(x);
        let cycloid = if self.consistent_clearance {
            lambda * play
        } else {
            stages[2] / ARCMIN_PER_RAD
        };
        let free_play =
            (stages[1].max(0.0) + stages[3].max(0.0)) / ARCMIN_PER_RAD + cycloid.max(0.0);
        let width = self.contact.face_width();
        let (reference, preload_forces, rest) = if play >= 0.0 {
            (forward, ZeroForces::NONE, ChainTerms::default())
        } else {
            let friction = self.contact.torque_factor() * self.pin_friction;
            let zero = |f: f64| self.contact.share_load(&clearances, width, 0.0, f);
            let frictionless = zero(0.0);
            // Only the housing reads F_0; without friction every branch's is the same.
            let branch = |f: f64| match self.housing.is_some() && f != 0.0 {
                true => zero(f).forces,
                false => frictionless.forces,
            };
            let forces = ZeroForces([frictionless.forces, branch(friction), branch(-friction)]);
            let rest = self
                .side
                .terms(0.0, frictionless.resultant, needle_factor, 0.0, lambda);
            (frictionless.rotation, forces, rest)
        };
        let preloaded = if self.consistent_clearance {
            play < 0.0
        } else {
            stages[2] < 0.0
        };
        Some(RowState {
            clearances,
            reference,
            free_play,
            preloaded,
            jammed: stages[1] < 0.0 || stages[3] < 0.0,
            needle_factor,
            preload_forces,
            rest,
        })
    }

    /// E(T; s) split into its elements, arcmin, for T ≥ 0 (N·m) and the direction of motion
    /// `forward` (s = +1) or not (s = −1); `friction` off gives the frictionless curve.
    fn terms(&self, state: &RowState, torque: f64, forward: bool, friction: bool) -> TorsionTerms {
        let s = if forward { 1.0 } else { -1.0 };
        let lambda = self.contact.torque_factor();
        let (m, a) = (self.side.cranks, self.side.crank_circle_radius);
        let output = torque * 1000.0;
        let frictionless = self.contact.disc_torque(torque);
        let (pin_friction, bearing_torque) = if friction {
            // Crank-bearing friction torque at the output (module comment), with the rms
            // row load of the frictionless case and F_x = T_c/(e·z_c).
            let row_load =
                (frictionless / (m * a)).hypot(frictionless / (self.side.pitch_radius * m));
            let torque = self.bearing_friction
                * 2.0
                * m
                * row_load
                * 0.5
                * self.journal_diameter
                * self.crank_turn;
            (s * lambda * self.pin_friction, torque)
        } else {
            (0.0, 0.0)
        };
        // The elastic chain carries what the needle rows' friction leaves of the torque.
        let effective = (output - s * bearing_torque).max(0.0);
        let disc_torque = self.contact.disc_torque(effective / 1000.0);
        let sharing = self.contact.share_load(
            &state.clearances,
            self.contact.face_width(),
            disc_torque,
            pin_friction,
        );
        let pins = if disc_torque > 0.0 || state.preloaded {
            lambda * (sharing.rotation - state.reference)
        } else {
            0.0
        };
        // Measured from rest: a preload's resultant loads the crank side at zero torque
        // already (with friction, the branch's own resultant differs from it there).
        let mut chain = self
            .side
            .terms(
                disc_torque,
                sharing.resultant,
                state.needle_factor,
                effective,
                lambda,
            )
            .minus(&state.rest);
        // The housing turns the disc by 2·U_h(F − F_0)/T_c (housing.rs).
        if let (Some(housing), true) = (&self.housing, disc_torque > 0.0) {
            let mut change = [0.0; crate::cycloid_pin_contact::MAX_PINS];
            for ((d, f), f0) in change
                .iter_mut()
                .zip(&sharing.forces)
                .zip(state.preload_forces.under(pin_friction))
            {
                *d = f - f0;
            }
            chain.housing = lambda * 2.0 * housing.energy(&change) / disc_torque;
        }
        TorsionTerms {
            pins: pins * ARCMIN_PER_RAD,
            chain: chain.scaled(ARCMIN_PER_RAD),
        }
    }

    /// E(T; s), arcmin.
    fn elastic(&self, state: &RowState, torque: f64, forward: bool) -> f64 {
        self.terms(state, torque, forward, true).total()
    }

    /// The frictionless elastic angle at `torque_nm` (≥ 0) split into its elements, arcmin,
    /// for one row of inputs; `None` when the row cannot be evaluated.
    pub fn breakdown(&self, x: &[f64], torque_nm: f64) -> Option<TorsionTerms> {
        let state = self.row_state(x)?;
        Some(self.terms(&state, torque_nm.abs(), true, false))
    }

    /// The elastic angle E(T; s) with friction, arcmin, for one row (s: `loading`).
    pub fn elastic_angle(&self, x: &[f64], torque_nm: f64, loading: bool) -> Option<f64> {
        let state = self.row_state(x)?;
        Some(self.elastic(&state, torque_nm.abs(), loading))
    }

    /// c, the free play of one row, arcmin.
    pub fn free_play(&self, x: &[f64]) -> Option<f64> {
        Some(self.row_state(x)?.free_play * ARCMIN_PER_RAD)
    }
}

impl ErrorModel for TorsionCurve {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        let Some(state) = self.row_state(x) else {
            out.fill(f64::NAN);
            return;
        };
        let c = state.free_play * ARCMIN_PER_RAD;
        let rated = self.rated_torque;
        let three = LOST_MOTION_TORQUE_SHARE * rated;
        let lost_motion =
            c + self.elastic(&state, three, true) + self.elastic(&state, three, false);
        let at_zero = if state.preloaded {
            self.elastic(&state, 0.0, false)
        } else {
            0.0
        };
        let at_rated = self.elastic(&state, rated, true);
        let at_half = self.elastic(&state, 0.5 * rated, true);
        let load = if state.preloaded {
            self.rule
                .of_clearances(&state.clearances[..self.contact.stage().pins])
        } else {
            Preload::NONE
        };
        let class = self.rule.classify(
            &load,
            (state.preloaded, state.jammed),
            (x[EQUIDISTANT], x[SHIFT]),
        );
        let values = [
            lost_motion,
            c + 2.0 * at_zero,
            (rated - 0.5 * rated) / (at_rated - at_half),
            c,
            0.5 * c + at_rated,
            load.overlap_um,
            load.pin_force,
            load.no_load_torque,
            class.preloaded(),
            class.over(),
        ];
        if values.iter().all(|v| v.is_finite()) {
            out.copy_from_slice(&values);
        } else {
            out.fill(f64::NAN);
        }
    }

    fn curves(&self, x: &[f64]) -> Vec<Curve> {
        let state = self.row_state(x);
        let rated = self.rated_torque;
        let curve = |name: &str, title: &str, (reach, ends): (f64, &str), steps: usize| {
            let (loading, unloading) = self.hysteresis_loop(state.as_ref(), reach, steps);
            Curve {
                name: name.into(),
                title: title.into(),
                x_label: "output torque (N·m)".into(),
                y_label: "output angle (arcmin)".into(),
                style: CurveStyle::Lines,
                series: vec![
                    Series {
                        label: format!("loading (−{ends} → +{ends})"),
                        points: loading,
                    },
                    Series {
                        label: format!("unloading (+{ends} → −{ends})"),
                        points: unloading,
                    },
                ],
            }
        };
        vec![
            curve(
                "torsion_curve",
                "Hysteresis (torsion) curve, input locked",
                (rated, "rated"),
                CURVE_STEPS,
            ),
            // Where the catalogue reads lost motion (from the loop's ends at ±3 % of rated)
            // and the hysteresis loss: drawn at its own scale.
            curve(
                "torsion_curve_3_percent",
                "Within ±3 % of rated torque: lost motion and hysteresis loss",
                (LOST_MOTION_TORQUE_SHARE * rated, "3 % of rated"),
                CURVE_STEPS,
            ),
        ]
    }
}

impl TorsionCurve {
    /// The loop of the torsion curve between −reach and +reach N·m in `steps` steps: the
    /// loading branch (−reach → +reach) and the unloading one, each crossing the free play
    /// at zero torque. Moving forward (loading): θ = c/2 + E(T; +) for T > 0,
    /// −(c/2 + E(|T|; −)) for T < 0; backward the other way round.
    fn hysteresis_loop(
        &self,
        state: Option<&RowState>,
        reach: f64,
        steps: usize,
    ) -> (Branch, Branch) {
        let half = steps / 2;
        let torque = |j: usize| reach * (j as f64 - half as f64) / half as f64;
        let c = state.map_or(f64::NAN, |s| s.free_play * ARCMIN_PER_RAD);
        // E at |T| = reach·k/half, k = 0..=half, moving forward and backward.
        let lags = |forward: bool| -> Vec<f64> {
            (0..=half)
                .map(|k| match state {
                    Some(s) => self.elastic(s, reach * k as f64 / half as f64, forward),
                    None => f64::NAN,
                })
                .collect()
        };
        let (ahead, back) = (lags(true), lags(false));
        let point = |j: usize, forward: bool| -> (f64, f64) {
            let (same, other) = if forward {
                (&ahead, &back)
            } else {
                (&back, &ahead)
            };
            let angle = if j > half {
                0.5 * c + same[j - half]
            } else {
                -(0.5 * c + other[half - j])
            };
            (torque(j), angle)
        };
        let mut loading = Vec::with_capacity(steps + 2);
        for j in 0..=steps {
            if j == half {
                // The free play is crossed at zero torque.
                loading.push((0.0, -(0.5 * c + back[0])));
                loading.push((0.0, 0.5 * c + ahead[0]));
            } else {
                loading.push(point(j, true));
            }
        }
        let mut unloading = Vec::with_capacity(steps + 2);
        for j in (0..=steps).rev() {
            if j == half {
                unloading.push((0.0, 0.5 * c + back[0]));
                unloading.push((0.0, -(0.5 * c + ahead[0])));
            } else {
                unloading.push(point(j, false));
            }
        }
        (loading, unloading)
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    /// 000's row of a torsion row: its first 18 inputs and no measuring error.
    fn hysteresis_row(x: &[f64]) -> [f64; geometric_hysteresis::INPUT_COUNT] {
        let mut row = [0.0; geometric_hysteresis::INPUT_COUNT];
        row[..HYSTERESIS_INPUTS].copy_from_slice(&x[..HYSTERESIS_INPUTS]);
        row
    }

    fn rv20e() -> TorsionCurve {
        TorsionCurve::from_params(&TorsionCurve::rv20e_params()).unwrap()
    }

    fn with(key: &str, value: f64) -> Result<TorsionCurve, ModelError> {
        TorsionCurve::from_params(&TorsionCurve::rv20e_params().with_number(key, value))
    }

    /// 000 Table 9 design values (E_ws, E_wi, Δr_rp, Δr_p, Δu), every δ-term and the input
    /// shaft at zero, x_k = 0.
    fn nominal() -> [f64; 19] {
        let mut x = [0.0; 19];
        x[0] = 0.0035;
        x[1] = -0.0309;
        x[2] = -0.010;
        x[3] = -0.012;
        x[13] = 0.002;
        x
    }

    /// The nominal with a modification that leaves free play (003's sign convention:
    /// Δr_rp = 0.010, Δr_p = −0.008 mm, 3.09 arcmin of backlash in the disc frame).
    fn with_play() -> [f64; 19] {
        let mut x = nominal();
        (x[2], x[3]) = (0.010, -0.008);
        x
    }

    /// A row with Table 9 manufacturing errors at a fraction of their limits (signs mixed),
    /// an input shaft deviation and a stiffness error.
    fn perturbed() -> [f64; 19] {
        let mut x = with_play();
        let deltas = [
            0.003, -0.001, 0.002, 0.004, 0.0, -0.005, 0.0004, -0.001, 0.002,
        ];
        x[4..13].copy_from_slice(&deltas);
        x[14] = 0.001;
        x[15] = -0.0005;
        x[16] = 1e-5;
        x[18] = 0.1;
        x
    }

    fn eval(model: &TorsionCurve, x: &[f64]) -> [f64; 10] {
        let mut out = [0.0; 10];
        model.evaluate(x, &mut out);
        out
    }

    fn lag(model: &TorsionCurve, x: &[f64], torque: f64, loading: bool) -> f64 {
        model.elastic_angle(x, torque, loading).unwrap()
    }

    #[test]
    fn free_play_of_the_profile_is_000s_eq_13_to_15() {
        // One profile: the cycloid stage's play is λ·(β_f − β_r) from the load sharing's
        // clearances. For a pure modification it is 000's Eq. 13–15 (= 003's form),
        // λ·2(Δr_rp − √(1 − K1²)·Δr_p)/(e·z_c), K1 = e·z_p/r_p = 0.692 (the discrete pins
        // see at most 1 % more, the pin spacing's second order): for 0.010/−0.008 mm,
        // 3.09·λ arcmin; with 000's −0.010/−0.012 mm, −0.28·λ (the flanks overlap).
        let model = rv20e();
        let lambda = model.torque_factor();
        assert!((lambda - 39.0 / 40.0 * (1.0 - 1.0 / 141.0)).abs() < 1e-15);
        let k1: f64 = 0.9 * 40.0 / 52.0;
        let s = (1.0 - k1 * k1).sqrt();
        let continuous =
            |equidistant: f64, shift: f64| lambda * 2.0 * (equidistant - s * shift) / 35.1;
        // Stage terms of 000 for the same row: involute and crank bearing.
        let reference =
            GeometricHysteresis::from_params(&GeometricHysteresis::rv20e_params()).unwrap();
        let mut stages = [0.0; geometric_hysteresis::OUTPUT_COUNT];
        reference.evaluate(&hysteresis_row(&with_play()), &mut stages);
        let others = (stages[1] + stages[3]) / ARCMIN_PER_RAD;
        let play = model.free_play(&with_play()).unwrap() / ARCMIN_PER_RAD - others;
        let expected = continuous(0.010, -0.008);
        assert!((expected * ARCMIN_PER_RAD - 3.09 * lambda).abs() < 0.005);
        assert!(
            play >= expected - 1e-12 && play < expected * 1.01,
            "{play} {expected}"
        );
        // The overlap: no cycloid play, preloaded, and 000's Table 9 nominal keeps only the
        // involute and crank-bearing terms (0.02633 + 0.25002 arcmin, 000 §5.2).
        let out = eval(&model, &nominal());
        assert!(continuous(-0.010, -0.012) < 0.0);
        assert_eq!(out[8], 1.0);
        assert!((out[3] - (0.02633 + 0.25002)).abs() < 1e-4, "{}", out[3]);
        assert!(out[6] > 0.0);
    }

    #[test]
    fn printed_reading_keeps_000s_clearance() {
        // clearance_reading 0: c is geometric_hysteresis's hysteresis_arcmin for the same
        // row, bit for bit, 0.54823 arcmin at the nominal (000 §5.2: 0.5467 ± 1 %).
        let model = with("clearance_reading", 0.0).unwrap();
        let reference = GeometricHysteresis::from_params(
            &GeometricHysteresis::rv20e_params()
                .with("reading", crate::ParamValue::Text("document_000".into())),
        )
        .unwrap();
        for x in [nominal(), perturbed()] {
            let mut expected = [0.0; geometric_hysteresis::OUTPUT_COUNT];
            reference.evaluate(&hysteresis_row(&x), &mut expected);
            assert_eq!(eval(&model, &x)[3], expected[0]);
        }
        let c = eval(&model, &nominal())[3];
        assert!((c - 0.5467).abs() < 0.01 * 0.5467, "{c}");
        // 000's printed term is positive here, so the stage counts as not preloaded, but
        // the load sharing sees the one profile and its overlap (its zero-torque preload).
        assert_eq!(eval(&model, &nominal())[5], 0.0);
    }

    #[test]
    fn elastic_angle_is_zero_at_zero_torque_with_play_and_increasing() {
        let model = rv20e();
        for x in [with_play(), perturbed()] {
            assert_eq!(lag(&model, &x, 0.0, true), 0.0);
            assert_eq!(lag(&model, &x, 0.0, false), 0.0);
            // Continuous at 0+: the take-up to first contact is free play, not elastic.
            let tiny = lag(&model, &x, 167e-6, true);
            assert!(tiny > 0.0 && tiny < 1e-3, "{tiny}");
            let mut previous = 0.0;
            for k in 1..=100 {
                let e = lag(&model, &x, 167.0 * k as f64 / 100.0, true);
                assert!(e > previous, "E not increasing at {k} %: {e} ≤ {previous}");
                previous = e;
            }
        }
    }

    #[test]
    fn a_preloaded_branch_is_continuous_at_zero_torque() {
        // The nominal RV-20E is preloaded; with pin friction each branch's zero-torque
        // pins carry a resultant across the eccentric that loads the crank side. Its
        // terms are measured from rest at every torque, zero included, so E(0⁺; s) is
        // E(0; s) (the crank side read at T > 0 only once jumped by 0.0073 arcmin a side
        // here, and the hysteresis loss left that part out).
        let model = rv20e();
        let x = nominal();
        assert_eq!(eval(&model, &x)[8], 1.0, "the nominal is preloaded");
        for forward in [true, false] {
            let at_zero = lag(&model, &x, 0.0, forward);
            let above = lag(&model, &x, 1e-9, forward);
            assert!(
                (above - at_zero).abs() < 1e-9,
                "{forward}: {at_zero} → {above}"
            );
        }
        // Friction holds each branch back at zero torque: the unloading one above.
        assert!(lag(&model, &x, 0.0, false) > 0.0 && lag(&model, &x, 0.0, true) < 0.0);
        // Frictionless, the rest state is the zero-torque state: no chain term there.
        let rest = model.breakdown(&x, 0.0).unwrap();
        assert!(rest.chain.total().abs() < 1e-12, "{rest:?}");
    }

    #[test]
    fn outputs_follow_the_catalogue_definitions() {
        let model = rv20e();
        for x in [nominal(), with_play(), perturbed()] {
            let out = eval(&model, &x);
            let c = out[3];
            let preloaded = out[8] == 1.0;
            let (l3, u3) = (lag(&model, &x, 5.01, true), lag(&model, &x, 5.01, false));
            let (e50, e100) = (lag(&model, &x, 83.5, true), lag(&model, &x, 167.0, true));
            let zero = if preloaded {
                lag(&model, &x, 0.0, false)
            } else {
                0.0
            };
            assert_eq!(out[0], c + l3 + u3);
            assert_eq!(out[1], c + 2.0 * zero);
            assert_eq!(out[2], 83.5 / (e100 - e50));
            assert_eq!(out[4], 0.5 * c + e100);
            assert!(out[..5].iter().all(|v| v.is_finite() && *v > 0.0));
            // Friction lowers the loading branch and raises the unloading one.
            assert!(l3 < u3);
        }
    }

    #[test]
    fn unmodified_pins_give_the_closed_form() {
        // Unmodified profile, no errors, no friction: every loaded pin has F_i = K·l_i·β, so
        // F_max = T_c·max l_i/Σ l_i² and β = δ(F_max)/max l_i with Palmgren's
        // δ(F) = 2·3.84e-5·F^0.9/L^0.8 (003's load sharing, docs/models.md §10), l_i =
        // e·z_c·sin φ_i/S_i (validation.md 003), K1 = e·z_p/r_p; T_c = 0.5·λ·T and the pins'
        // angle at the output is λ·β.
        let model = rv20e();
        let mut x = nominal();
        (x[2], x[3]) = (0.0, 0.0);
        let (e, zc, zp, rp, width): (f64, f64, f64, f64, f64) = (0.9, 39.0, 40.0, 52.0, 8.0);
        let k1: f64 = e * zp / rp;
        let levers: Vec<f64> = (0..40)
            .map(|i| {
                let phi = 2.0 * PI * i as f64 / zp;
                e * zc * phi.sin() / (1.0 + k1 * k1 - 2.0 * k1 * phi.cos()).sqrt()
            })
            .collect();
        let sum_l2: f64 = levers.iter().filter(|l| **l > 0.0).map(|l| l * l).sum();
        let l_max = levers.iter().cloned().fold(0.0, f64::max);
        let lambda = model.torque_factor();
        for torque in [5.01, 83.5, 167.0] {
            let t_c = 0.5 * lambda * torque * 1000.0;
            let f_max: f64 = t_c * l_max / sum_l2;
            let beta = 2.0 * 3.84e-5 * f_max.powf(0.9) / width.powf(0.8) / l_max;
            let pins = model.breakdown(&x, torque).unwrap().pins;
            assert!(
                (pins / (lambda * beta * ARCMIN_PER_RAD) - 1.0).abs() < 1e-9,
                "{torque} N·m: {pins} vs {}",
                lambda * beta * ARCMIN_PER_RAD
            );
        }
    }

    #[test]
    fn chain_terms_are_the_crank_sides_for_the_pin_resultant() {
        // The crank-side part of E is CrankSide::terms for the disc torque 0.5·λ·T and the
        // pin resultant of the same solve (frictionless breakdown).
        let model = rv20e();
        let x = perturbed();
        let lambda = model.torque_factor();
        let t_c = 0.5 * lambda * 167_000.0;
        let state = model.row_state(&x).unwrap();
        let sharing = model.contact.share_load(&state.clearances, 8.0, t_c, 0.0);
        let chain = model
            .crank_side()
            .terms(t_c, sharing.resultant, 1.1, 167_000.0, lambda);
        let breakdown = model.breakdown(&x, 167.0).unwrap();
        let housing = breakdown.chain.housing;
        assert!(
            ((breakdown.chain.total() - housing) / (chain.total() * ARCMIN_PER_RAD) - 1.0).abs()
                < 1e-12
        );
        // The housing's term is the caller's: λ·2·U_h(F − F_0)/T_c (stiffness/housing.rs).
        let change: Vec<f64> = (0..40)
            .map(|i| sharing.forces[i] - state.preload_forces.under(0.0)[i])
            .collect();
        let energy = model.housing.as_ref().unwrap().energy(&change);
        let hand = lambda * 2.0 * energy / t_c * ARCMIN_PER_RAD;
        assert!(
            housing > 0.0 && (housing / hand - 1.0).abs() < 1e-12,
            "{housing} vs {hand}"
        );
        // And the torque balance: Σ F_i·l_i = T_c.
        let moment: f64 = sharing
            .forces
            .iter()
            .zip(0..40)
            .map(|(f, i)| {
                let phi = 2.0 * PI * i as f64 / 40.0;
                let k1: f64 = 0.9 * 40.0 / 52.0;
                f * 0.9 * 39.0 * phi.sin() / (1.0 + k1 * k1 - 2.0 * k1 * phi.cos()).sqrt()
            })
            .sum();
        assert!((moment / t_c - 1.0).abs() < 1e-12);
    }

    #[test]
    fn pin_friction_shifts_the_loop_by_its_moment() {
        // At the same disc turn (same normal forces F_i), loading and unloading need the
        // disc torques Σ F_i·(l_i ± λ·μ·h_i): the loop's width in torque at that turn is
        // 2·λ·μ·Σ F_i·h_i. Check: the frictionless forces at T_c give, with friction, the
        // loading torque T_c + λμΣF_i·h_i, and solving the loading case at that torque
        // returns the same turn.
        let model = rv20e();
        let x = with_play();
        let state = model.row_state(&x).unwrap();
        let lambda = model.torque_factor();
        let mu = 0.02;
        let t_c = 0.5 * lambda * 100_000.0;
        let free = model.contact.share_load(&state.clearances, 8.0, t_c, 0.0);
        let friction_moment: f64 = (0..40)
            .map(|i| {
                free.forces[i] * lambda * mu * model.contact.slip_arm(2.0 * PI * i as f64 / 40.0)
            })
            .sum();
        let loading =
            model
                .contact
                .share_load(&state.clearances, 8.0, t_c + friction_moment, lambda * mu);
        assert!((loading.rotation / free.rotation - 1.0).abs() < 1e-10);
        let unloading =
            model
                .contact
                .share_load(&state.clearances, 8.0, t_c - friction_moment, -lambda * mu);
        assert!((unloading.rotation / free.rotation - 1.0).abs() < 1e-10);
        // About μ of the torque: h_i ≈ l_i on the loaded pins (between 0.5μ and 2μ).
        let ratio = friction_moment / t_c;
        assert!(
            ratio > 0.5 * lambda * mu && ratio < 2.0 * lambda * mu,
            "{ratio}"
        );
    }

    #[test]
    fn bearing_friction_reduces_the_disc_torque_by_its_reflected_torque() {
        // Only needle-row friction: the loading branch at T is the frictionless one at
        // T − T_fb, T_fb = μ_b·2m·G·(d_j/2)·(z1/z2), G = √((T_c/(m·a))² + (T_c/(m·e·z_c))²)
        // with T_c = 0.5·λ·T (module comment).
        let params = TorsionCurve::rv20e_params()
            .with_number("pin_friction_coefficient", 0.0)
            .with_number("crank_bearing_friction_coefficient", 0.002);
        let model = TorsionCurve::from_params(&params).unwrap();
        let frictionless = TorsionCurve::from_params(
            &params.with_number("crank_bearing_friction_coefficient", 0.0),
        )
        .unwrap();
        let x = with_play();
        let lambda = model.torque_factor();
        let t_c = 0.5 * lambda * 167_000.0;
        let g = (t_c / (2.0 * 27.5)).hypot(t_c / (2.0 * 35.1));
        let t_fb = 0.002 * 4.0 * g * 7.5 * (12.0 / 42.0) / 1000.0; // N·m
        assert!(t_fb > 0.0 && t_fb < 1e-3 * 167.0, "{t_fb}");
        let loading = lag(&model, &x, 167.0, true);
        let shifted = lag(&frictionless, &x, 167.0 - t_fb, true);
        assert!((loading / shifted - 1.0).abs() < 1e-12);
        let unloading = lag(&model, &x, 167.0, false);
        assert!((unloading / lag(&frictionless, &x, 167.0 + t_fb, false) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_preloaded_stage_has_no_free_play_and_starts_stiffer() {
        // 000's design modification overlaps the flanks: both carry load at zero torque, the
        // curve has no cycloid free play, and its first 3 % is stiffer than the same
        // geometry with a clearance-giving profile (one flank, taking up its modification).
        let model = rv20e();
        let preloaded = nominal();
        let out = eval(&model, &preloaded);
        assert_eq!(out[8], 1.0);
        // 1.34 µm per flank and about 152 N at zero torque (validation.md), within the
        // design's 365 N at rated torque: preloaded within the limit.
        assert!((out[5] - 1.34).abs() < 0.01, "{}", out[5]);
        assert!((out[6] - 152.0).abs() < 2.0, "{}", out[6]);
        assert_eq!(out[9], 0.0);
        let frictionless = with("pin_friction_coefficient", 0.0).unwrap();
        // Frictionless: E(0) = 0 on both branches, hysteresis loss = c.
        assert_eq!(lag(&frictionless, &preloaded, 0.0, true), 0.0);
        assert_eq!(eval(&frictionless, &preloaded)[1], out[3]);
        // With friction the preload's friction opens the loop at zero torque.
        let opening = lag(&model, &preloaded, 0.0, false);
        assert!(opening > 0.0 && (out[1] - out[3] - 2.0 * opening).abs() < 1e-15);
        // Stiffer start: E(3 %) below the clearance profile's.
        let e3_preloaded = lag(&frictionless, &preloaded, 5.01, true);
        let e3_play = lag(&frictionless, &with_play(), 5.01, true);
        assert!(e3_preloaded < e3_play, "{e3_preloaded} vs {e3_play}");
        // The reverse flank unloads: at rated torque the preloaded stage carries the load
        // on the forward flank only, like the clearance profile.
        assert!(out[6] > 0.0);
    }

    #[test]
    fn rigidity_is_the_slope_of_the_loading_branch_between_50_and_100_percent() {
        let model = rv20e();
        for x in [nominal(), perturbed()] {
            let out = eval(&model, &x);
            let curve = &model.curves(&x)[0];
            let loading = &curve.series[0].points;
            // Loading: j = 0..=100 with the 0 point doubled; T_r/2 is j = 75 (index 76),
            // T_r is j = 100 (index 101).
            let (half, rated) = (loading[76], loading[101]);
            assert_eq!((half.0, rated.0), (83.5, 167.0));
            let slope = (rated.0 - half.0) / (rated.1 - half.1);
            assert!(
                (slope / out[2] - 1.0).abs() < 1e-12,
                "{slope} vs {}",
                out[2]
            );
            assert!((rated.1 - out[4]).abs() < 1e-12);
        }
    }

    #[test]
    fn curve_is_a_loop_symmetric_about_the_origin() {
        let model = rv20e();
        for x in [nominal(), with_play()] {
            let out = eval(&model, &x);
            let c = out[3];
            let curves = model.curves(&x);
            assert_eq!(curves.len(), 2);
            let names: Vec<&str> = curves.iter().map(|c| c.name.as_str()).collect();
            assert_eq!(names, ["torsion_curve", "torsion_curve_3_percent"]);
            let rated = model.rated_torque;
            for (curve, reach) in curves.iter().zip([rated, 0.03 * rated]) {
                assert_eq!(curve.style, CurveStyle::Lines);
                let (loading, unloading) = (&curve.series[0].points, &curve.series[1].points);
                assert_eq!((loading.len(), unloading.len()), (102, 102));
                assert_eq!((loading[0].0, loading[101].0), (-reach, reach));
                // Point symmetry: the unloading branch is the loading branch turned by 180°.
                for i in 0..102 {
                    let (t, theta) = loading[i];
                    assert_eq!((-t, -theta), unloading[i], "{i}");
                }
                // Monotone in T, the whole loop and its ±3 % window alike (the housing's
                // term of a preloaded stage read against the zero-torque forces of its own
                // branch: `ZeroForces`), the unloading branch above the loading one for
                // T > 0.
                for w in loading.windows(2) {
                    assert!(w[1].0 >= w[0].0 && w[1].1 >= w[0].1, "{w:?}");
                }
                for j in 52..102 {
                    assert!(unloading[101 - j].1 > loading[j].1, "{j}");
                }
                // The width at zero torque is the hysteresis loss, at either scale.
                let width = unloading[50].1 - loading[50].1;
                assert!((width - out[1]).abs() < 1e-12, "{width} vs {}", out[1]);
                assert!((loading[51].1 - loading[50].1 - c).abs() < 1e-12);
            }
            // The window's loading branch spans the lost motion: from −(c/2 + E(3 %; −))
            // to c/2 + E(3 %; +).
            let window = &curves[1].series[0].points;
            let span = window[101].1 - window[0].1;
            assert!((span - out[0]).abs() < 1e-12, "{span} vs {}", out[0]);
        }
    }

    #[test]
    fn two_and_three_cranks() {
        // Three cranks share the crank side: its terms shrink (not exactly by 2/3, the
        // rows being nonlinear and the carrier having three pillars).
        let two = rv20e();
        let three = with("crank_count", 3.0).unwrap();
        let x = with_play();
        let (a, b) = (
            two.breakdown(&x, 167.0).unwrap(),
            three.breakdown(&x, 167.0).unwrap(),
        );
        assert_eq!(a.pins, b.pins);
        assert!(b.chain.needle < a.chain.needle && b.chain.shaft < a.chain.shaft);
        assert!(with("crank_count", 4.0).is_err());
    }

    #[test]
    fn body_compliance_softens_the_chain_by_its_own_terms() {
        // body_compliance 0 (rigid disc and plates) against the default: the pins, the
        // needle rows, the shaft and the involute stage are the same; the disc bore is new,
        // the supports gain their seats and the carrier its pillar roots (stiffness/);
        // the default needle diameter and support width are the estimation rules' d_j/5 and
        // l_s/0.7 (3 mm and 11.75 mm on the RV-20E: the same model).
        let soft = rv20e();
        let rigid = with("body_compliance", 0.0).unwrap();
        let x = nominal();
        let (a, b) = (
            soft.breakdown(&x, 167.0).unwrap(),
            rigid.breakdown(&x, 167.0).unwrap(),
        );
        assert_eq!(a.pins, b.pins);
        assert_eq!(a.chain.needle, b.chain.needle);
        assert_eq!(a.chain.shaft, b.chain.shaft);
        assert_eq!(a.chain.involute, b.chain.involute);
        assert_eq!(b.chain.disc_bore, 0.0);
        assert!(a.chain.disc_bore > 0.0);
        assert!(a.chain.support > b.chain.support && a.chain.carrier > b.chain.carrier);
        let mut out = [0.0; 10];
        let mut out_rigid = [0.0; 10];
        soft.evaluate(&x, &mut out);
        rigid.evaluate(&x, &mut out_rigid);
        assert!(out[2] < out_rigid[2] && out[4] > out_rigid[4]);
        let keys: Vec<&str> = geometric_hysteresis::ENTRY
            .params
            .iter()
            .chain(&PARAMS)
            .map(|p| p.name)
            .filter(|name| {
                !["needle_roller_diameter_mm", "support_bearing_width_mm"].contains(name)
            })
            .collect();
        let defaults = TorsionCurve::rv20e_params().subset(&keys);
        let by_rule = TorsionCurve::from_params(&defaults).unwrap();
        assert_eq!(by_rule.crank_side(), soft.crank_side());
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases = [
            ("rated_torque_nm", 0.0, "rated_torque_nm"),
            ("rated_torque_nm", -167.0, "rated_torque_nm"),
            ("disc_face_width_mm", 0.0, "disc_face_width_mm"),
            ("pin_radius_mm", -2.0, "pin_radius_mm"),
            ("crank_circle_radius_mm", 0.0, "crank_circle_radius_mm"),
            ("disc_load_share", 1.5, "disc_load_share"),
            ("cycloid_teeth", 38.0, "cycloid_teeth"),
            ("pin_count", 39.0, "pin_count"),
            ("curtate_ratio", 1.2, "curtate_ratio"),
            ("eccentricity_mm", 1.4, "eccentricity_mm"),
            ("sun_pitch_radius_mm", 0.0, "sun_pitch_radius_mm"),
            ("crank_count", 1.0, "crank_count"),
            ("needle_roller_count", 0.0, "needle_roller_count"),
            (
                "crank_eccentric_spacing_mm",
                40.0,
                "crank_eccentric_spacing_mm",
            ),
            (
                "support_contact_angle_deg",
                45.0,
                "support_contact_angle_deg",
            ),
            ("carrier_pillar_width_mm", 0.0, "carrier_pillar_width_mm"),
            ("pin_friction_coefficient", -0.1, "pin_friction_coefficient"),
            (
                "crank_bearing_friction_coefficient",
                0.5,
                "crank_bearing_friction_coefficient",
            ),
            ("clearance_reading", 2.0, "clearance_reading"),
            ("body_compliance", 0.5, "body_compliance"),
            (
                "needle_roller_diameter_mm",
                0.0,
                "needle_roller_diameter_mm",
            ),
            // The bore, 7.5 + 17.5 = 25 mm, reaches past the pin circle 24.5 mm away.
            (
                "needle_roller_diameter_mm",
                17.5,
                "needle_roller_diameter_mm",
            ),
            ("support_bearing_width_mm", -1.0, "support_bearing_width_mm"),
            ("support_preload_n", -5.0, "support_preload_n"),
            // The seat's bore (70/2 mm) reaches past a pillar's root (38.9 − 35 < 6.3 mm).
            (
                "support_bearing_outer_diameter_mm",
                70.0,
                "support_bearing_outer_diameter_mm",
            ),
            (
                "end_plate_bolt_diameter_mm",
                7.0,
                "end_plate_bolt_diameter_mm",
            ),
            ("end_plate_bolt_preload_n", 0.0, "end_plate_bolt_preload_n"),
            (
                "joint_deflection_coefficient",
                0.0,
                "joint_deflection_coefficient",
            ),
            (
                "joint_deflection_exponent",
                1.2,
                "joint_deflection_exponent",
            ),
            (
                "disc_pillar_hole_radius_mm",
                -1.0,
                "disc_pillar_hole_radius_mm",
            ),
            // 30 + 10.5 mm reaches past the 38.9 mm between a bore and a hole.
            (
                "disc_pillar_hole_radius_mm",
                30.0,
                "disc_pillar_hole_radius_mm",
            ),
            // Three pillars for two cranks: the body terms put a pillar between two cranks.
            ("carrier_pillar_count", 3.0, "carrier_pillar_count"),
            (
                "crank_bearing_stiffness_n_per_mm",
                2e5,
                "crank_bearing_stiffness_n_per_mm",
            ),
        ];
        for (key, value, named) in cases {
            let err = with(key, value).unwrap_err();
            assert_eq!(err.key, named, "{key} = {value}: {err}");
        }
        assert!(with("crank_bearing_stiffness_n_per_mm", 2e5)
            .unwrap_err()
            .to_string()
            .contains("unknown parameter"));
        assert!(with("cycloid_teeth", 38.0)
            .unwrap_err()
            .to_string()
            .contains("pin_count − 1"));
        for key in [
            "pin_radius_mm",
            "disc_face_width_mm",
            "needle_roller_count",
            "crank_support_span_mm",
            "pin_friction_coefficient",
            "rated_torque_nm",
            "center_distance_mm",
        ] {
            let mut params = ModelParams::new();
            for spec in PARAMS.iter().filter(|p| p.name != key) {
                if let Ok(v) = TorsionCurve::rv20e_params().number(spec.name, None) {
                    params = params.with_number(spec.name, v);
                }
            }
            let err = TorsionCurve::from_params(&params).unwrap_err();
            assert_eq!(err.key, key, "{err}");
            assert!(err.to_string().contains("missing"), "{err}");
        }
        let text = TorsionCurve::rv20e_params()
            .with("rated_torque_nm", crate::ParamValue::Text("rated".into()));
        assert_eq!(
            TorsionCurve::from_params(&text).unwrap_err().key,
            "rated_torque_nm"
        );
    }

    #[test]
    fn rows_that_cannot_be_evaluated_give_nan() {
        let model = rv20e();
        let mut cases = Vec::new();
        for (index, value) in [
            (0, f64::NAN),
            (5, f64::INFINITY),
            (2, f64::NAN),
            (12, f64::NEG_INFINITY),
            (18, -1.0), // k = 0
            (18, -3.0),
        ] {
            let mut x = nominal();
            x[index] = value;
            cases.push(x);
        }
        for x in &cases {
            assert!(eval(&model, x).iter().all(|v| v.is_nan()), "{x:?}");
            let curve = &model.curves(x)[0];
            assert!(curve.series[0].points.iter().all(|p| p.1.is_nan()));
        }
        // Absurd but finite clearances: no hang, no panic.
        let mut x = nominal();
        x[2] = 1e300;
        let out = eval(&model, &x);
        assert!(out.iter().all(|v| v.is_finite()) || out.iter().all(|v| v.is_nan()));
    }

    proptest::proptest! {
        #[test]
        fn rows_within_the_tolerances_give_ordered_finite_outputs(
            deltas in proptest::array::uniform9(-1.0f64..1.0),
            stiffness_error in -0.15f64..0.15,
        ) {
            // Table 9 limits (000) for the δ-terms, 000's design modification.
            let limits = [0.010, 0.004, 0.005, 0.015, 0.0, 0.019, 0.001, 0.003, 0.005];
            let mut x = nominal();
            for (i, (d, l)) in deltas.iter().zip(limits).enumerate() {
                x[4 + i] = d * l;
            }
            x[18] = stiffness_error;
            let model = rv20e();
            let out = eval(&model, &x);
            proptest::prop_assert!(out.iter().all(|v| v.is_finite()), "{:?}", out);
            let c = out[3];
            proptest::prop_assert!(c >= 0.0);
            proptest::prop_assert!(out[0] > c && out[4] > 0.5 * c && out[2] > 0.0);
            proptest::prop_assert!(out[1] >= c);
            proptest::prop_assert!(out[8] == 0.0 || out[8] == 1.0);
            proptest::prop_assert!(out[9] == 0.0 || out[9] == 1.0);
            proptest::prop_assert!(out[9] <= out[8]);
            proptest::prop_assert!((out[6] > 0.0) == (out[8] == 1.0));
            proptest::prop_assert!((out[5] > 0.0) == (out[6] > 0.0));
        }
    }

    #[test]
    fn registry_example_builds() {
        let entry = crate::find("torsion_curve").unwrap();
        let model = (entry.build)(&(entry.example_params)()).unwrap();
        assert_eq!(model.inputs().len(), 19);
        assert_eq!(model.outputs().len(), 10);
        assert_eq!(model.inputs()[0].name, "common_normal_upper_deviation_mm");
        assert_eq!(model.inputs()[18].name, "crank_bearing_stiffness_error");
        assert_eq!(model.outputs()[8].kind, OutputKind::Indicator);
        assert_eq!(model.outputs()[9].name, "over_preloaded");
    }
}
