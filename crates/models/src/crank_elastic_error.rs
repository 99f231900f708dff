//! `crank_elastic_error`: the forces between the cranks and a cycloid disc over a crank
//! turn, and the elastic lag of the output from the deflection of the crank bearings
//! (document 004, RV40E), with the four-bar closure of cranks whose eccentrics differ
//! (docs/models.md §11).
//!
//! Frame (004's o_p–xy): y along the eccentricity of the disc analysed (disc 3), x
//! perpendicular to it, the frame of `cycloid_pin_contact`. θ is 004's angle of the disc
//! relative to that frame; one crank turn sweeps θ over [0, 2π). The m cranks (2 or 3) sit
//! on the crank circle a = a_w + δa (004's a0 and its error δa); crank k's hole is at
//! r_k = a·R(2π(k − 1)/m)·(−sin θ, −cos θ) from the disc centre, so that for two cranks
//! crank 4 and crank 4' are 004's. Tangential components of a crank force are taken along
//! ẑ × r̂_k, radial ones towards the disc centre (004's F_r). Lengths in mm, forces in N,
//! torques in N·mm inside (N·m at the inputs), stiffnesses in N/mm, angles rad inside.
//!
//! Disc torque and pin resultant: the load sharing of `cycloid_pin_contact` with the same
//! geometry gives (F_x, F_y) and the disc torque T_c = s·λ·|T| (torque balance,
//! λ = (z_c/z_p)·(1 − 1/i); `disc_torque_balance` = 0: s·|T| and λ = 1, as 004 prints it),
//! for the row (T, Δr_rp, Δr_p, 0, 0, δē, 0) with δē the mean radial misfit of the
//! eccentrics of disc 3 (below). The contact model keeps the design lever arms; with the
//! actual eccentricity e = e0 + δē, F_x = T_c/(e·z_c) still holds exactly, so (F_x, F_y)
//! is scaled by e0/e.
//!
//! Disc on its cranks (the general form of 004's three disc equations and closure): crank
//! k holds the disc's bore through a bearing of stiffness k_k (isotropic), and its
//! eccentric centre is off its design place by the misfit q_k. A rigid disc takes the pose
//! (t, ρ), translation and rotation against the carrier, and crank k pushes it with
//!   G_k = k_k·(q_k − t − ρ·ẑ × r_k);
//! equilibrium with the pins, Σ G_k = (F_x, F_y) and Σ r_k × G_k = T_c, is linear in
//! (t_x, t_y, ρ):
//!   [ S0   0   −Sy ] [t_x]   [Σ k·q_x − F_x      ]
//!   [ 0    S0   Sx ] [t_y] = [Σ k·q_y − F_y      ]     S0 = Σ k_k, (Sx, Sy) = Σ k_k·r_k,
//!   [ −Sy  Sx   S2 ] [ ρ ]   [Σ k·(r × q) − T_c   ]     S2 = Σ k_k·|r_k|²
//! With two equal bearings and no misfit it gives 004's closed form (validation.md 004):
//!   F_t43 = ½(F_x·r_c'/a + F_x·cos θ − F_y·sin θ), F_t4'3 = ½(F_x·r_c'/a − F_x·cos θ +
//!   F_y·sin θ), F_r43 = F_r4'3 = ½(F_x·sin θ + F_y·cos θ), r_c' = e·z_c,
//! i.e. 004's closure F_r43 = F_r4'3 is the equal-stiffness case of this compatibility.
//!
//! Four-bar closure: with misfits alone the pose is kinematic. For two cranks
//!   ρ = r_1 × (q_1 − q_2)/(2a²) = (q_1 − q_2)⊥/(2a),
//! the component of q_1 − q_2 across the line of the crank axes (004's four-bar: the
//! cranks are the eccentrics, the coupler the disc, the fixed link the carrier); the
//! component along it cannot be taken up by a rigid disc and loads both bearings as a
//! preload pair. Three cranks over-determine the disc: the pose is the bearings' weighted
//! fit and every misfit not fitted is preload. A crank's misfit at a disc is its 6-DOF
//! deviation (du, dv, dw, dα, dβ, dγ; 001) moved to that disc's eccentric centre by
//! φ = ε + ω × p (001 Eq. 5–8), p = (0, ±e0, z) in the crank's frame (y along disc 3's
//! eccentric, z along the crank axis from the deviation's reference point; the eccentric
//! of disc 3' points the other way), plus the eccentricity error δe_k along each
//! eccentric. Crank-borne misfits turn with the eccentrics, so in each disc's eccentric
//! frame they are constant while the crank holes go round: the four-bar turn is a
//! sinusoid over the crank turn. A misfit the crank carries alike to both eccentrics
//! (δe_k, dγ_k, and tilts about the middle) points opposite ways at the two discs, which
//! turn opposite ways: the output sees the mean of the two discs, and the difference is
//! held by the pins as preload or eaten by free play (not modelled here). dw moves no
//! contact in the plane and is not an input.
//!
//! Output angle: a disc's turn ρ and its translation t_x across its eccentric (which the
//! pins see as a turn of t_x/(e·z_c), since every pin normal passes through the pitch
//! point, e·z_c from the disc centre) reach the output, with the input held, as
//!   Δβ = −λ·(ρ + t_x/(e·z_c))        (positive: the output lags under load)
//! `disc_translation` = 0 keeps 004's reading, the crank-hole line's turn alone, with
//! 004's arctan: Δβ = λ·arctan(−ρ), which for two equal bearings k is 004's
//! arctan(T_c/(2k·a²)) (0.3316° for 004's k = 10⁶ N/m at 30 N·m with two discs).
//!
//! Bearing stiffness: a ringless needle row of Z needles of length l on the eccentric
//! (`needle_roller_count`, `needle_roller_length_mm`), at its secant stiffness at the
//! load's rms over a crank turn √((T_c/(m·a))² + (|F|/m)²) (Palmgren line contact and
//! Stribeck's 4.08, crates/models/src/stiffness/contact.rs), times (1 + x_k) for crank k; or, when
//! `crank_bearing_stiffness_n_per_mm` is given, that constant k (004's k1 = k3).
//!
//! 004's crank equations (axial positions from the planet gear: output bearing 5 at l1,
//! disc 3 at l1 + l2, disc 3' at l1 + l2 + l3, bearing 5' at l1 + … + l4) with F_t12 =
//! −F_x·e/R2, F_r12 = F_t12·tan α' and the disc equations make 004's 8 × 8 system in
//! (F_t43, F_t4'3, F_r43, F_r4'3, F_t54, F_t5'4, F_r54, F_r5'4) for two cranks:
//! [`CrankElasticError::equilibrium_system`] and [`CrankElasticError::solve_equilibrium`]
//! (nalgebra LU); the tests check the closed form against them. They are not used per
//! sample; l1..l4 also place the two eccentric planes for the tilts.
//!
//! Outputs, over N = `angle_steps` angles θ_j = 2πj/N: the mean elastic lag (arcmin; the
//! lag with the loads and no misfit), the max − min of the output angle (elastic lag plus
//! the mean of the two discs' four-bar turns), the torsional stiffness |T|/mean lag of the
//! crank side (N·m/arcmin), the largest tangential and radial crank force on disc 3 over
//! the turn (preload included), and the max − min of disc 3's own four-bar turn. A
//! negative output torque loads the other flank and is treated by symmetry (|T|). A row
//! with a non-finite input, k_k ≤ 0, e ≤ 0 or a ≤ 0 gives NaN outputs; at T = 0 a needle
//! row has no finite secant stiffness, and the stiffness and the forces are NaN.
//!
//! Left out: the crank shaft, its support bearings and the carrier (`torsion_curve` chains
//! them), bearing clearance (`geometric_hysteresis`'s Δu), the disc-against-disc preload of
//! opposite four-bar turns, per-crank carrier bore errors (the transmission error model's).

use rvtol_deviation::Shown;
use std::f64::consts::PI;

use nalgebra::{SMatrix, SVector};
use rvtol_deviation::point_displacement;

use crate::cycloid_pin_contact::CycloidPinContact;
use crate::stiffness::RollerRow;
use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
    ARCMIN_PER_RAD,
};

/// The inputs before the per-crank blocks, in order.
const COMMON_INPUTS: [(&str, &str, &str); 4] = [
    (
        "output_torque_nm",
        "N·m",
        "torque at the output; one disc carries disc_load_share of it (times λ)",
    ),
    (
        "equidistant_modification_mm",
        "mm",
        "Δr_rp, equidistant modification (positive: clearance), fed to the contact model",
    ),
    (
        "shift_modification_mm",
        "mm",
        "Δr_p, shift modification (negative: clearance), fed to the contact model",
    ),
    (
        "crank_spacing_error_mm",
        "mm",
        "δa, 004's error of the crank circle radius (carrier and disc alike)",
    ),
];

/// Inputs of each crank k, in order (names get the suffix `_k`).
const CRANK_INPUTS: [(&str, &str, &str); 7] = [
    (
        "eccentricity_error_mm",
        "mm",
        "δe_k, eccentricity minus design of crank k's eccentrics (along each)",
    ),
    (
        "crank_du_mm",
        "mm",
        "crank k's 6-DOF deviation du (001), across disc 3's eccentric",
    ),
    (
        "crank_dv_mm",
        "mm",
        "crank k's dv (001), along disc 3's eccentric",
    ),
    (
        "crank_dalpha_rad",
        "rad",
        "crank k's tilt dα about x (001), acts at each disc's plane",
    ),
    (
        "crank_dbeta_rad",
        "rad",
        "crank k's tilt dβ about y (001), acts at each disc's plane",
    ),
    (
        "crank_dgamma_rad",
        "rad",
        "crank k's turn dγ about its axis (001): a phase error e·dγ of its eccentrics",
    ),
    (
        "crank_bearing_stiffness_error",
        "1",
        "x_k, relative error of crank k's bearing stiffness: k·(1 + x_k)",
    ),
];

/// The outputs, in order.
const OUTPUTS: [(&str, &str, &str); 6] = [
    (
        "elastic_error_arcmin",
        "arcmin",
        "mean over a crank turn of the elastic lag Δβ of the output (positive: lags)",
    ),
    (
        "elastic_error_ripple_arcmin",
        "arcmin",
        "max − min over a crank turn of the output angle (elastic lag and the discs' mean four-bar turn)",
    ),
    (
        "torsional_stiffness_nm_per_arcmin",
        "N·m/arcmin",
        "|output torque| / elastic_error_arcmin (crank bearings only)",
    ),
    (
        "max_crank_tangential_force_n",
        "N",
        "largest tangential force of a crank on disc 3 over a crank turn (F_t43, F_t4'3, …)",
    ),
    (
        "crank_radial_force_n",
        "N",
        "largest |radial force| of a crank on disc 3 over a crank turn",
    ),
    (
        "four_bar_error_arcmin",
        "arcmin",
        "max − min over a crank turn of disc 3's four-bar turn from the cranks' misfits, at the output",
    ),
];

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "pin_count",
        unit: "1",
        description: "z_p, pins (004: 40)",
        default: None,
    },
    ParamSpec {
        name: "cycloid_teeth",
        unit: "1",
        description: "z_c = z_p − 1 (004: 39)",
        default: None,
    },
    ParamSpec {
        name: "pin_circle_radius_mm",
        unit: "mm",
        description: "r_p (not in 004; 002 Table 1 gives 64 for the RV40E)",
        default: None,
    },
    ParamSpec {
        name: "pin_radius_mm",
        unit: "mm",
        description: "r_rp (not in 004)",
        default: None,
    },
    ParamSpec {
        name: "eccentricity_mm",
        unit: "mm",
        description: "e, design (004: 1.3)",
        default: None,
    },
    ParamSpec {
        name: "disc_face_width_mm",
        unit: "mm",
        description: "contact length of one disc (not in 004)",
        default: None,
    },
    ParamSpec {
        name: "disc_load_share",
        unit: "1",
        description: "share of the output torque carried by one disc",
        default: Some(0.5),
    },
    ParamSpec {
        name: "disc_torque_balance",
        unit: "1",
        description: "1: disc torque share·λ·|T| and output angle λ·(disc turn), λ = (z_c/z_p)(1 − 1/i); 0: share·|T| and one to one (004 as printed)",
        default: Some(1.0),
    },
    ParamSpec {
        name: "youngs_modulus_mpa",
        unit: "MPa",
        description: "E of disc and pins",
        default: Some(206_000.0),
    },
    ParamSpec {
        name: "poisson_ratio",
        unit: "1",
        description: "ν of disc and pins",
        default: Some(0.3),
    },
    ParamSpec {
        name: "crank_count",
        unit: "1",
        description: "m, cranks on the crank circle, 2 or 3 (004: 2)",
        default: Some(2.0),
    },
    ParamSpec {
        name: "crank_circle_radius_mm",
        unit: "mm",
        description: "a_w, crank axes from the reducer axis (004's a0 = 36, half the distance of its two crank axes)",
        default: None,
    },
    ParamSpec {
        name: "planet_pitch_radius_mm",
        unit: "mm",
        description: "R2, planet pitch radius (004: 26), for the 8 × 8 check",
        default: None,
    },
    ParamSpec {
        name: "pressure_angle_deg",
        unit: "deg",
        description: "α', pressure angle of the spur stage (004: 20)",
        default: Some(20.0),
    },
    ParamSpec {
        name: "sun_teeth",
        unit: "1",
        description: "z1, sun teeth (004: 10)",
        default: None,
    },
    ParamSpec {
        name: "planet_teeth",
        unit: "1",
        description: "z2, planet teeth (004: 26)",
        default: None,
    },
    ParamSpec {
        name: "needle_roller_count",
        unit: "1",
        description: "Z, needles between one crank eccentric and the disc bore (read unless crank_bearing_stiffness_n_per_mm is given)",
        default: None,
    },
    ParamSpec {
        name: "needle_roller_length_mm",
        unit: "mm",
        description: "l, effective needle length (read unless crank_bearing_stiffness_n_per_mm is given)",
        default: None,
    },
    ParamSpec {
        name: "crank_bearing_stiffness_n_per_mm",
        unit: "N/mm",
        description: "k, a constant stiffness between one crank eccentric and the disc instead of the needle row (004's reading; 004: 10⁶ N/m)",
        default: None,
    },
    ParamSpec {
        name: "disc_translation",
        unit: "1",
        description: "1: the disc's shift on its bearings turns the output through the pins (t_x/(e·z_c)); 0: the crank-hole line's turn alone, with 004's arctan",
        default: Some(1.0),
    },
    ParamSpec {
        name: "crank_l1_mm",
        unit: "mm",
        description: "004's l1: planet gear to output bearing 5 along the crank",
        default: None,
    },
    ParamSpec {
        name: "crank_l2_mm",
        unit: "mm",
        description: "004's l2: bearing 5 to disc 3",
        default: None,
    },
    ParamSpec {
        name: "crank_l3_mm",
        unit: "mm",
        description: "004's l3: disc 3 to disc 3'",
        default: None,
    },
    ParamSpec {
        name: "crank_l4_mm",
        unit: "mm",
        description: "004's l4: disc 3' to bearing 5'",
        default: None,
    },
    ParamSpec {
        name: "crank_reference_position_mm",
        unit: "mm",
        description: "where along the crank (from the planet gear) its 6-DOF deviation refers to; default midway between the discs, l1 + l2 + l3/2",
        default: None,
    },
    ParamSpec {
        name: "angle_steps",
        unit: "1",
        description: "N, angles θ sampled over one crank turn (4..=3600)",
        default: Some(72.0),
    },
];

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "crank_elastic_error",
    summary: "crank forces over a turn and elastic lag of the output from the crank bearings, with the four-bar closure of unequal cranks (document 004; 2 or 3 cranks; needle-row stiffness), pin resultant from cycloid_pin_contact",
    params: PARAMS,
    build: |params| Ok(Box::new(CrankElasticError::from_params(params)?)),
    example_params: CrankElasticError::rv40e_params,
    example_inputs: &[("output_torque_nm", 412.0)],
};

/// The load on one disc that enters 004's equilibrium equations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscLoad {
    /// F_x, pin resultant perpendicular to the eccentricity, N.
    pub force_x: f64,
    /// F_y, pin resultant along the eccentricity, N.
    pub force_y: f64,
    /// e, actual eccentricity, mm (r_c' = e·z_c, F_t12 = −F_x·e/R2).
    pub eccentricity: f64,
    /// a = a_w + δa, mm.
    pub crank_circle_radius: f64,
    /// T_c, N·mm.
    pub disc_torque: f64,
}

/// Forces of cranks 4 and 4' on disc 3 at one θ (004's closed form), N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscForces {
    /// F_t43.
    pub f_t43: f64,
    /// F_t4'3.
    pub f_t4p3: f64,
    /// F_r43 = F_r4'3.
    pub f_r: f64,
}

/// The 8 unknowns of 004's system at one θ, N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrankForces {
    /// F_t43, crank 4 on disc 3, tangential.
    pub f_t43: f64,
    /// F_t4'3, crank 4' on disc 3, tangential.
    pub f_t4p3: f64,
    /// F_r43, crank 4 on disc 3, radial.
    pub f_r43: f64,
    /// F_r4'3, crank 4' on disc 3, radial.
    pub f_r4p3: f64,
    /// F_t54, output bearing 5 on crank 4, tangential.
    pub f_t54: f64,
    /// F_t5'4, output bearing 5' on crank 4, tangential.
    pub f_t5p4: f64,
    /// F_r54, output bearing 5 on crank 4, radial.
    pub f_r54: f64,
    /// F_r5'4, output bearing 5' on crank 4, radial.
    pub f_r5p4: f64,
}

/// The stiffness between a crank eccentric and the disc.
#[derive(Debug, Clone, Copy, PartialEq)]
enum CrankBearing {
    /// A constant k, N/mm (004's reading).
    Constant(f64),
    /// A needle row at its secant stiffness.
    Needles(RollerRow),
}

/// A disc's pose on its cranks: translation (t_x, t_y) against the design and rotation ρ
/// against the carrier.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// t_x, across the eccentric, mm.
    pub shift_x: f64,
    /// t_y, along the eccentric, mm.
    pub shift_y: f64,
    /// ρ, rad.
    pub rotation: f64,
}

/// The output angle and its parts at one angle θ of a crank turn (rad at the output).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleState {
    /// θ, rad.
    pub theta: f64,
    /// The elastic lag, mean of the two discs (loads, no misfit).
    pub elastic: f64,
    /// The four-bar turn of disc 3 and disc 3' (misfits, no load), each as it would turn
    /// the output.
    pub four_bar: [f64; 2],
    /// The output angle: elastic lag plus the mean of the discs' four-bar turns.
    pub output: f64,
    /// Largest tangential force of a crank on disc 3, N.
    pub max_tangential: f64,
    /// Largest |radial force| of a crank on disc 3, N.
    pub max_radial: f64,
}

/// The crank elastic error model with its checked geometry.
#[derive(Debug, Clone)]
pub struct CrankElasticError {
    /// The pin-force model of the same disc (m cranks on the crank circle).
    contact: CycloidPinContact,
    cranks: usize,
    crank_circle_radius: f64,
    planet_pitch_radius: f64,
    /// tan α'.
    tan_pressure_angle: f64,
    ratio: f64,
    bearing: CrankBearing,
    disc_translation: bool,
    /// 004's l1..l4, mm.
    crank_lengths: [f64; 4],
    /// Axial positions of the eccentric planes of disc 3 and disc 3' from the cranks'
    /// deviation reference point, mm.
    planes: [f64; 2],
    /// (sin θ_j, cos θ_j) for θ_j = 2πj/N.
    angles: Vec<(f64, f64)>,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

impl CrankElasticError {
    /// The RV40E of document 004 (z_p 40, z_c 39, e 1.3 mm, a0 36 mm, two cranks, R2 26 mm,
    /// α' 20°, z1 10, z2 26), with what 004 leaves out: r_p 64 mm (002 Table 1's RV40E),
    /// pin radius 2.5 mm, face width 10 mm, l1..l4 = 13.625, 13.625, 11, 13.625 mm, and the needle row
    /// of the RV-40E estimate of docs/models.md §13 (15 needles of 8 mm).
    pub fn rv40e_params() -> ModelParams {
        ModelParams::new()
            .with_number("pin_count", 40.0)
            .with_number("cycloid_teeth", 39.0)
            .with_number("pin_circle_radius_mm", 64.0)
            .with_number("pin_radius_mm", 2.5)
            .with_number("eccentricity_mm", 1.3)
            .with_number("disc_face_width_mm", 10.0)
            .with_number("crank_circle_radius_mm", 36.0)
            .with_number("planet_pitch_radius_mm", 26.0)
            .with_number("sun_teeth", 10.0)
            .with_number("planet_teeth", 26.0)
            .with_number("needle_roller_count", 15.0)
            .with_number("needle_roller_length_mm", 8.0)
            .with_number("crank_l1_mm", 13.625)
            .with_number("crank_l2_mm", 13.625)
            .with_number("crank_l3_mm", 11.0)
            .with_number("crank_l4_mm", 13.625)
    }

    /// Builds the model, checking every parameter once.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let crank_circle_radius = params.positive("crank_circle_radius_mm", None)?;
        let cranks = params.count("crank_count", Some(2.0))? as usize;
        if !(2..=3).contains(&cranks) {
            return Err(ModelError::new(
                "crank_count",
                format!("must be 2 or 3, got {cranks}"),
            ));
        }
        // The disc and pin parameters go to the contact model, which checks them under
        // their own keys; its cranks sit on the crank circle.
        let contact = CycloidPinContact::of_disc(params, cranks, crank_circle_radius)?;
        let planet_pitch_radius = params.positive("planet_pitch_radius_mm", None)?;
        let pressure_angle = params.number("pressure_angle_deg", Some(20.0))?;
        if !(pressure_angle > 0.0 && pressure_angle < 90.0) {
            return Err(ModelError::new(
                "pressure_angle_deg",
                format!("must lie in (0, 90), got {}", Shown(pressure_angle)),
            ));
        }
        let sun_teeth = params.count("sun_teeth", None)? as f64;
        let planet_teeth = params.count("planet_teeth", None)? as f64;
        // A constant stiffness when given (004's reading), else the needle row.
        let bearing = if params
            .number("crank_bearing_stiffness_n_per_mm", Some(f64::NAN))?
            .is_nan()
        {
            CrankBearing::Needles(RollerRow {
                rollers: params.count("needle_roller_count", None)? as f64,
                length: params.positive("needle_roller_length_mm", None)?,
                contact_angle: 0.0,
            })
        } else {
            CrankBearing::Constant(params.positive("crank_bearing_stiffness_n_per_mm", None)?)
        };
        let disc_translation = params.flag("disc_translation", true)?;
        let crank_lengths = [
            params.positive("crank_l1_mm", None)?,
            params.positive("crank_l2_mm", None)?,
            params.positive("crank_l3_mm", None)?,
            params.positive("crank_l4_mm", None)?,
        ];
        let [l1, l2, l3, _] = crank_lengths;
        let reference = params.number("crank_reference_position_mm", Some(l1 + l2 + 0.5 * l3))?;
        let angle_steps = params.count("angle_steps", Some(72.0))? as usize;
        if !(4..=3600).contains(&angle_steps) {
            return Err(ModelError::new(
                "angle_steps",
                format!("must be between 4 and 3600, got {angle_steps}"),
            ));
        }
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let pins = contact.stage().pins;
        let mut inputs: Vec<InputSpec> = COMMON_INPUTS
            .iter()
            .map(|&(name, unit, description)| InputSpec {
                name: name.into(),
                unit: unit.into(),
                description,
            })
            .collect();
        for k in 1..=cranks {
            for &(name, unit, description) in &CRANK_INPUTS {
                inputs.push(InputSpec {
                    name: format!("{name}_{k}"),
                    unit: unit.into(),
                    description,
                });
            }
        }
        Ok(CrankElasticError {
            contact,
            cranks,
            crank_circle_radius,
            planet_pitch_radius,
            tan_pressure_angle: pressure_angle.to_radians().tan(),
            ratio: 1.0 + planet_teeth / sun_teeth * pins as f64,
            bearing,
            disc_translation,
            crank_lengths,
            planes: [l1 + l2 - reference, l1 + l2 + l3 - reference],
            angles: (0..angle_steps)
                .map(|j| (2.0 * PI * j as f64 / angle_steps as f64).sin_cos())
                .collect(),
            inputs,
            outputs: OUTPUTS
                .iter()
                .map(|&(name, unit, description)| OutputSpec {
                    name: name.into(),
                    unit: unit.into(),
                    description,
                    kind: OutputKind::Continuous,
                    condition: None,
                })
                .collect(),
        })
    }

    /// The overall ratio 1 + (z2/z1)·z_p (105 for the RV40E of 004).
    pub fn ratio(&self) -> f64 {
        self.ratio
    }

    /// λ of the embedded contact model (1 without the torque balance).
    pub fn torque_factor(&self) -> f64 {
        self.contact.torque_factor()
    }

    /// The misfits q_k of crank k's eccentric centre at disc 3 and at disc 3', each in
    /// that disc's eccentric frame (module comment), mm.
    fn misfits(&self, inputs: &[f64], crank: usize) -> [(f64, f64); 2] {
        let block = &inputs[COMMON_INPUTS.len() + CRANK_INPUTS.len() * crank..];
        let eccentricity_error = block[0];
        let deviation = [block[1], block[2], 0.0, block[3], block[4], block[5]];
        let e0 = self.contact.stage().eccentricity;
        let at_first = point_displacement(&deviation, [0.0, e0, self.planes[0]]);
        let at_second = point_displacement(&deviation, [0.0, -e0, self.planes[1]]);
        [
            (at_first[0], at_first[1] + eccentricity_error),
            (-at_second[0], -at_second[1] + eccentricity_error),
        ]
    }

    /// The disc load for one row of inputs (in the order of `inputs()`): the pin resultant
    /// of the contact model for (T, Δr_rp, Δr_p, δē), δē the mean radial misfit of disc 3's
    /// eccentrics, scaled by e0/e so that F_x·e·z_c = T_c with the actual e = e0 + δē
    /// (module comment). No allocation.
    pub fn disc_load(&self, inputs: &[f64]) -> DiscLoad {
        let mean_error = (0..self.cranks)
            .map(|k| self.misfits(inputs, k)[0].1)
            .sum::<f64>()
            / self.cranks as f64;
        let contact_row = [inputs[0], inputs[1], inputs[2], 0.0, 0.0, mean_error, 0.0];
        let (force_x, force_y) = self.contact.resultant(&contact_row);
        let eccentricity = self.contact.stage().eccentricity + mean_error;
        let scale = self.contact.stage().eccentricity / eccentricity;
        DiscLoad {
            force_x: force_x * scale,
            force_y: force_y * scale,
            eccentricity,
            crank_circle_radius: self.crank_circle_radius + inputs[3],
            disc_torque: self.contact.disc_torque(inputs[0]),
        }
    }

    /// The base stiffness of one crank bearing for a disc load (N/mm): the constant k, or
    /// the needle row's secant at the rms load √((T_c/(m·a))² + (|F|/m)²) (infinite at zero
    /// load).
    fn base_stiffness(&self, load: &DiscLoad) -> f64 {
        match self.bearing {
            CrankBearing::Constant(k) => k,
            CrankBearing::Needles(row) => {
                let m = self.cranks as f64;
                let rms = (load.disc_torque / (m * load.crank_circle_radius))
                    .hypot(load.force_x.hypot(load.force_y) / m);
                1.0 / row.secant_compliance(rms)
            }
        }
    }

    /// Position of crank k's hole from the disc centre at θ for disc 3 (mm); disc 3' sees
    /// the negative.
    fn crank_position(&self, a: f64, crank: usize, sin: f64, cos: f64) -> (f64, f64) {
        let (s, c) = (2.0 * PI * crank as f64 / self.cranks as f64).sin_cos();
        let (x, y) = (-a * sin, -a * cos);
        (c * x - s * y, s * x + c * y)
    }

    /// The pose of a disc with its crank holes at `positions`, bearing stiffnesses
    /// `stiffness`, misfits `misfits`, pin resultant `force` and disc torque `torque`
    /// (module comment's 3 × 3 system, solved by Cramer's rule; symmetric and positive
    /// definite for two or more cranks on a circle).
    pub fn pose(
        positions: &[(f64, f64)],
        stiffness: &[f64],
        misfits: &[(f64, f64)],
        force: (f64, f64),
        torque: f64,
    ) -> Pose {
        let (mut s0, mut sx, mut sy, mut s2) = (0.0, 0.0, 0.0, 0.0);
        let (mut bx, mut by, mut bm) = (-force.0, -force.1, -torque);
        for ((&(rx, ry), &k), &(qx, qy)) in positions.iter().zip(stiffness).zip(misfits) {
            s0 += k;
            sx += k * rx;
            sy += k * ry;
            s2 += k * (rx * rx + ry * ry);
            bx += k * qx;
            by += k * qy;
            bm += k * (rx * qy - ry * qx);
        }
        // [[s0, 0, −sy], [0, s0, sx], [−sy, sx, s2]]
        let det = s0 * (s0 * s2 - sx * sx) - sy * sy * s0;
        let shift_x = ((s0 * s2 - sx * sx) * bx - sx * sy * by + s0 * sy * bm) / det;
        let shift_y = (-sx * sy * bx + (s0 * s2 - sy * sy) * by - s0 * sx * bm) / det;
        let rotation = (s0 * sy * bx - s0 * sx * by + s0 * s0 * bm) / det;
        Pose {
            shift_x,
            shift_y,
            rotation,
        }
    }

    /// The output angle a disc's pose gives, rad (module comment): −λ·(ρ + t_x/(e·z_c)),
    /// or 004's λ·arctan(−ρ) without the translation.
    fn pose_angle(&self, pose: &Pose, load: &DiscLoad) -> f64 {
        let lambda = self.contact.torque_factor();
        if self.disc_translation {
            let pitch = load.eccentricity * self.contact.stage().teeth as f64;
            -lambda * (pose.rotation + pose.shift_x / pitch)
        } else {
            lambda * (-pose.rotation).atan()
        }
    }

    /// Sweeps one crank turn for one row of inputs, calling `visit` at each θ_j; `None`
    /// when the row cannot be evaluated (non-finite value, k_k ≤ 0, e ≤ 0, a ≤ 0). No
    /// allocation.
    fn sweep(&self, inputs: &[f64], mut visit: impl FnMut(AngleState)) -> Option<DiscLoad> {
        if !inputs.iter().all(|x| x.is_finite()) {
            return None;
        }
        let load = self.disc_load(inputs);
        let loaded = load.disc_torque > 0.0;
        // Without load only the misfits act, and the kinematic pose depends on the
        // stiffness ratios 1 + x_k alone.
        let base = if loaded {
            self.base_stiffness(&load)
        } else {
            1.0
        };
        let m = self.cranks;
        let mut stiffness = [0.0; 3];
        let mut misfits = [[(0.0, 0.0); 3]; 2];
        for k in 0..m {
            let error = inputs[COMMON_INPUTS.len() + CRANK_INPUTS.len() * k + 6];
            stiffness[k] = base * (1.0 + error);
            let [first, second] = self.misfits(inputs, k);
            misfits[0][k] = first;
            misfits[1][k] = second;
        }
        let a = load.crank_circle_radius;
        let valid = load.eccentricity > 0.0
            && a > 0.0
            && load.force_x.is_finite()
            && stiffness[..m].iter().all(|k| *k > 0.0);
        if !valid {
            return None;
        }
        let stiffness = &stiffness[..m];
        let no_misfit = [(0.0, 0.0); 3];
        for &(sin, cos) in &self.angles {
            let mut positions = [(0.0, 0.0); 3];
            for (k, position) in positions.iter_mut().enumerate().take(m) {
                *position = self.crank_position(a, k, sin, cos);
            }
            let mirrored = positions.map(|(x, y)| (-x, -y));
            let mut elastic = 0.0;
            let mut four_bar = [0.0; 2];
            let (mut max_tangential, mut max_radial) = (f64::NEG_INFINITY, 0.0_f64);
            for (disc, holes) in [&positions, &mirrored].into_iter().enumerate() {
                let holes = &holes[..m];
                let kinematic = Self::pose(holes, stiffness, &misfits[disc][..m], (0.0, 0.0), 0.0);
                four_bar[disc] = self.pose_angle(&kinematic, &load);
                let loads = if loaded {
                    Self::pose(
                        holes,
                        stiffness,
                        &no_misfit[..m],
                        (load.force_x, load.force_y),
                        load.disc_torque,
                    )
                } else {
                    Pose::default()
                };
                elastic += 0.5 * self.pose_angle(&loads, &load);
                if disc == 0 {
                    // Crank forces on disc 3 from the whole pose (loads and misfits).
                    let total = Pose {
                        shift_x: kinematic.shift_x + loads.shift_x,
                        shift_y: kinematic.shift_y + loads.shift_y,
                        rotation: kinematic.rotation + loads.rotation,
                    };
                    for k in 0..m {
                        let (rx, ry) = holes[k];
                        let (qx, qy) = misfits[0][k];
                        let gx = stiffness[k] * (qx - total.shift_x + total.rotation * ry);
                        let gy = stiffness[k] * (qy - total.shift_y - total.rotation * rx);
                        let (ux, uy) = (rx / a, ry / a);
                        max_tangential = max_tangential.max(-gx * uy + gy * ux);
                        max_radial = max_radial.max((gx * ux + gy * uy).abs());
                    }
                }
            }
            let theta = sin.atan2(cos);
            visit(AngleState {
                theta: if theta < 0.0 { theta + 2.0 * PI } else { theta },
                elastic,
                four_bar,
                output: elastic + 0.5 * (four_bar[0] + four_bar[1]),
                max_tangential,
                max_radial,
            });
        }
        Some(load)
    }

    /// The states over one crank turn for one row of inputs (empty when the row cannot be
    /// evaluated); for tests and inspection, allocates.
    pub fn turn(&self, inputs: &[f64]) -> Vec<AngleState> {
        let mut states = Vec::with_capacity(self.angles.len());
        let _ = self.sweep(inputs, |state| states.push(state));
        states
    }

    /// 004's disc equations with the closure F_r43 = F_r4'3, in closed form at θ (two
    /// cranks).
    pub fn disc_forces(&self, load: &DiscLoad, theta: f64) -> DiscForces {
        let (sin, cos) = theta.sin_cos();
        let sum = load.force_x * load.eccentricity * self.contact.stage().teeth as f64
            / load.crank_circle_radius;
        let difference = load.force_x * cos - load.force_y * sin;
        DiscForces {
            f_t43: 0.5 * (sum + difference),
            f_t4p3: 0.5 * (sum - difference),
            f_r: 0.5 * (load.force_x * sin + load.force_y * cos),
        }
    }

    /// 004's 8 equations at θ as A·x = b, x = (F_t43, F_t4'3, F_r43, F_r4'3, F_t54, F_t5'4,
    /// F_r54, F_r5'4): rows 1–3 the disc equations, 4–7 the crank-4 equations with
    /// F_t12 = −F_x·e/R2 and F_r12 = F_t12·tan α', 8 the closure F_r43 − F_r4'3 = 0 (two
    /// cranks).
    pub fn equilibrium_system(
        &self,
        load: &DiscLoad,
        theta: f64,
    ) -> (SMatrix<f64, 8, 8>, SVector<f64, 8>) {
        let (s, c) = theta.sin_cos();
        let [l1, l2, l3, l4] = self.crank_lengths;
        let (at_disc, at_disc_p, at_end) = (l1 + l2, l1 + l2 + l3, l1 + l2 + l3 + l4);
        let a = load.crank_circle_radius;
        let f_t12 = -load.force_x * load.eccentricity / self.planet_pitch_radius;
        let f_r12 = f_t12 * self.tan_pressure_angle;
        #[rustfmt::skip]
        let matrix = SMatrix::<f64, 8, 8>::from_row_slice(&[
            -c, c, -s, -s, 0.0, 0.0, 0.0, 0.0,
            s, -s, -c, -c, 0.0, 0.0, 0.0, 0.0,
            a, a, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            -c, -c, -s, s, 1.0, 1.0, 0.0, 0.0,
            s, s, -c, c, 0.0, 0.0, -1.0, -1.0,
            -c * at_disc, -c * at_disc_p, -s * at_disc, s * at_disc_p, l1, at_end, 0.0, 0.0,
            -s * at_disc, -s * at_disc_p, c * at_disc, -c * at_disc_p, 0.0, 0.0, l1, at_end,
            0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0,
        ]);
        let rhs = SVector::<f64, 8>::from_column_slice(&[
            -load.force_x,
            -load.force_y,
            load.force_x * load.eccentricity * self.contact.stage().teeth as f64,
            -(f_t12 * c + f_r12 * s),
            f_t12 * s - f_r12 * c,
            0.0,
            0.0,
            0.0,
        ]);
        (matrix, rhs)
    }

    /// Solves [`Self::equilibrium_system`] by LU; `None` if it is singular (it is not for
    /// checked parameters: the disc block has determinant 4a, the crank block
    /// (l2 + l3 + l4)²).
    pub fn solve_equilibrium(&self, load: &DiscLoad, theta: f64) -> Option<CrankForces> {
        let (matrix, rhs) = self.equilibrium_system(load, theta);
        let x = matrix.lu().solve(&rhs)?;
        Some(CrankForces {
            f_t43: x[0],
            f_t4p3: x[1],
            f_r43: x[2],
            f_r4p3: x[3],
            f_t54: x[4],
            f_t5p4: x[5],
            f_r54: x[6],
            f_r5p4: x[7],
        })
    }
}

impl ErrorModel for CrankElasticError {
    fn name(&self) -> &'static str {
        "crank_elastic_error"
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    fn check_constant(&self, input: usize, value: f64) -> Result<(), String> {
        // The torque is the contact model's first input as well.
        match input {
            0 => self.contact.check_constant(0, value),
            _ => Ok(()),
        }
    }

    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]) {
        let (mut elastic_sum, mut output_min, mut output_max) =
            (0.0, f64::INFINITY, f64::NEG_INFINITY);
        let (mut four_bar_min, mut four_bar_max) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut tangential, mut radial) = (f64::NEG_INFINITY, 0.0_f64);
        let swept = self.sweep(inputs, |state| {
            elastic_sum += state.elastic;
            output_min = output_min.min(state.output);
            output_max = output_max.max(state.output);
            four_bar_min = four_bar_min.min(state.four_bar[0]);
            four_bar_max = four_bar_max.max(state.four_bar[0]);
            tangential = tangential.max(state.max_tangential);
            radial = radial.max(state.max_radial);
        });
        if swept.is_none() {
            outputs.fill(f64::NAN);
            return;
        }
        let elastic = elastic_sum / self.angles.len() as f64 * ARCMIN_PER_RAD;
        // |T|/lag is undefined at zero torque, and so are the bearing forces (a needle row
        // has no finite secant stiffness without load; the misfits' preload is then left
        // undetermined for a constant stiffness too, to keep one rule).
        let torque = inputs[0].abs();
        let (stiffness, tangential, radial) = if torque > 0.0 {
            (torque / elastic, tangential, radial)
        } else {
            (f64::NAN, f64::NAN, f64::NAN)
        };
        outputs.copy_from_slice(&[
            elastic,
            (output_max - output_min) * ARCMIN_PER_RAD,
            stiffness,
            tangential,
            radial,
            (four_bar_max - four_bar_min) * ARCMIN_PER_RAD,
        ]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 004's RV40E with the needle row of docs/models.md §13 (15 needles of 8 mm) and the
    /// torque balance (the defaults).
    fn rv40e() -> CrankElasticError {
        CrankElasticError::from_params(&CrankElasticError::rv40e_params()).unwrap()
    }

    /// 004's RV40E as printed: k = 10⁶ N/m = 1000 N/mm on both cranks, T_c = share·T,
    /// the crank-hole line's turn alone.
    fn rv40e_as_printed() -> CrankElasticError {
        CrankElasticError::from_params(
            &CrankElasticError::rv40e_params()
                .with_number("crank_bearing_stiffness_n_per_mm", 1000.0)
                .with_number("disc_torque_balance", 0.0)
                .with_number("disc_translation", 0.0),
        )
        .unwrap()
    }

    fn with(key: &str, value: f64) -> Result<CrankElasticError, ModelError> {
        CrankElasticError::from_params(&CrankElasticError::rv40e_params().with_number(key, value))
    }

    /// Inputs for m cranks: torque, Δr_rp, Δr_p, δa, then per crank δe, du, dv, dα, dβ,
    /// dγ, x, all zero.
    fn row(cranks: usize, torque: f64, equidistant: f64, shift: f64) -> Vec<f64> {
        let mut x = vec![0.0; 4 + 7 * cranks];
        (x[0], x[1], x[2]) = (torque, equidistant, shift);
        x
    }

    /// Index of crank k's input j (0: δe, 1: du, 2: dv, 3: dα, 4: dβ, 5: dγ, 6: x).
    fn at(crank: usize, j: usize) -> usize {
        4 + 7 * crank + j
    }

    fn eval(model: &CrankElasticError, inputs: &[f64]) -> [f64; 6] {
        let mut out = [0.0; 6];
        model.evaluate(inputs, &mut out);
        out
    }

    #[test]
    fn ratio_is_105() {
        // 004: i = 105 = 1 + (26/10)·40 (validation.md 004).
        assert_eq!(rv40e().ratio(), 105.0);
    }

    #[test]
    fn pin_resultant_carries_the_disc_torque() {
        // F_x·e·z_c = T_c = 0.5·λ·T, λ = (39/40)(1 − 1/105) = 0.965714 (torque balance),
        // with modification and eccentricity errors (the actual e).
        let model = rv40e();
        let lambda: f64 = 39.0 / 40.0 * (1.0 - 1.0 / 105.0);
        assert!((model.torque_factor() - lambda).abs() < 1e-15);
        for (torque, errors) in [
            (30.0, (0.0, 0.0)),
            (412.0, (0.003, -0.001)),
            (200.0, (-0.004, -0.002)),
        ] {
            let mut inputs = row(2, torque, 0.01, -0.008);
            (inputs[at(0, 0)], inputs[at(1, 0)]) = errors;
            let load = model.disc_load(&inputs);
            let t_c = 0.5 * lambda * torque * 1000.0;
            assert!((load.disc_torque / t_c - 1.0).abs() < 1e-15);
            assert!((load.eccentricity - (1.3 + 0.5 * (errors.0 + errors.1))).abs() < 1e-15);
            let moment = load.force_x * load.eccentricity * 39.0;
            assert!((moment / t_c - 1.0).abs() < 1e-12, "{moment} vs {t_c}");
            assert!(load.force_y.abs() > 1e-3 * load.force_x);
        }
    }

    #[test]
    fn equal_bearings_give_004s_closed_form_and_it_the_8x8_solve() {
        // validation.md 004: the closed form must agree with a full 8×8 solve; the general
        // pose with two equal bearings and no misfit gives the closed form's forces.
        let model = rv40e();
        for torque in [30.0, 150.0, 412.0] {
            for da in [0.0, 0.005] {
                let mut inputs = row(2, torque, 0.01, -0.008);
                inputs[3] = da;
                let load = model.disc_load(&inputs);
                let scale = load.force_x.hypot(load.force_y);
                for k in 0..24 {
                    let theta = k as f64 * PI / 12.0 + 0.1;
                    let closed = model.disc_forces(&load, theta);
                    let solved = model.solve_equilibrium(&load, theta).unwrap();
                    for (a, b) in [
                        (closed.f_t43, solved.f_t43),
                        (closed.f_t4p3, solved.f_t4p3),
                        (closed.f_r, solved.f_r43),
                        (closed.f_r, solved.f_r4p3),
                    ] {
                        assert!((a - b).abs() < 1e-9 * scale, "θ {theta}: {a} vs {b}");
                    }
                    let (matrix, rhs) = model.equilibrium_system(&load, theta);
                    let x = SVector::<f64, 8>::from_column_slice(&[
                        solved.f_t43,
                        solved.f_t4p3,
                        solved.f_r43,
                        solved.f_r4p3,
                        solved.f_t54,
                        solved.f_t5p4,
                        solved.f_r54,
                        solved.f_r5p4,
                    ]);
                    let residual = (matrix * x - rhs).amax();
                    let size = matrix.amax() * x.amax() + rhs.amax();
                    assert!(residual < 1e-9 * size, "residual {residual} of {size}");
                    // The pose: crank 4 at a·(−sin θ, −cos θ), crank 4' opposite, k equal.
                    let (s, c) = theta.sin_cos();
                    let a = load.crank_circle_radius;
                    let holes = [(-a * s, -a * c), (a * s, a * c)];
                    let k = 3e5;
                    let pose = CrankElasticError::pose(
                        &holes,
                        &[k, k],
                        &[(0.0, 0.0), (0.0, 0.0)],
                        (load.force_x, load.force_y),
                        load.disc_torque,
                    );
                    // 004's F_r of both cranks points the same way (along crank 4's
                    // radius, inwards): compare magnitudes.
                    for (i, (tangential, radial)) in
                        [(closed.f_t43, closed.f_r), (closed.f_t4p3, closed.f_r)]
                            .into_iter()
                            .enumerate()
                    {
                        let (rx, ry) = holes[i];
                        let gx = k * (-pose.shift_x + pose.rotation * ry);
                        let gy = k * (-pose.shift_y - pose.rotation * rx);
                        let (ux, uy) = (rx / a, ry / a);
                        assert!((-gx * uy + gy * ux - tangential).abs() < 1e-9 * scale);
                        assert!(((gx * ux + gy * uy).abs() - radial.abs()).abs() < 1e-9 * scale);
                    }
                }
            }
        }
    }

    #[test]
    fn lag_of_033_degrees_as_printed() {
        // validation.md 004: k = 10⁶ N/m, 30 N·m, two discs: arctan(15000/(2·1000·36²))
        // = 0.3316°, no ripple, whatever e, with the literal reading (T_c = share·T, the
        // crank-hole line's turn alone).
        let printed: f64 = (15_000.0_f64 / (2.0 * 1000.0 * 36.0 * 36.0))
            .atan()
            .to_degrees();
        assert!((printed - 0.3316).abs() < 5e-5);
        for e in [1.2, 1.3, 1.4] {
            let model = CrankElasticError::from_params(
                &CrankElasticError::rv40e_params()
                    .with_number("eccentricity_mm", e)
                    .with_number("crank_bearing_stiffness_n_per_mm", 1000.0)
                    .with_number("disc_torque_balance", 0.0)
                    .with_number("disc_translation", 0.0),
            )
            .unwrap();
            let out = eval(&model, &row(2, 30.0, 0.01, -0.008));
            assert!(
                (out[0] / 60.0 / printed - 1.0).abs() < 1e-12,
                "e {e}: {}",
                out[0]
            );
            assert!(out[1] < 1e-12 * out[0], "ripple {}", out[1]);
        }
        assert_eq!(rv40e_as_printed().torque_factor(), 1.0);
    }

    #[test]
    fn physical_lag_adds_the_disc_shift_and_the_torque_balance() {
        // Equal constant k, no misfit: ρ = −T_c/(2k·a²), t_x = −F_x/(2k), so the output lag
        // is λ·T_c·(1/(2k·a²) + 1/(2k·(e·z_c)²)) with T_c = 0.5·λ·T and F_x = T_c/(e·z_c):
        // at 412 N·m, k = 3e5 N/mm, a = 36, e·z_c = 50.7 mm, λ = 0.965714.
        let model = with("crank_bearing_stiffness_n_per_mm", 3e5).unwrap();
        let lambda: f64 = 39.0 / 40.0 * (1.0 - 1.0 / 105.0);
        let t_c = 0.5 * lambda * 412_000.0;
        let k = 3e5;
        let hand = lambda * t_c * (1.0 / (2.0 * k * 36.0 * 36.0) + 1.0 / (2.0 * k * 50.7 * 50.7));
        let out = eval(&model, &row(2, 412.0, 0.01, -0.008));
        assert!(
            (out[0] / (hand * ARCMIN_PER_RAD) - 1.0).abs() < 1e-12,
            "{}",
            out[0]
        );
        assert!(out[1] < 1e-9 * out[0]);
        assert!((out[2] - 412.0 / out[0]).abs() < 1e-9 * out[2]);
        // Without the shift, the crank-hole line alone: λ·arctan(T_c/(2k·a²)).
        let rotation_only = CrankElasticError::from_params(
            &CrankElasticError::rv40e_params()
                .with_number("crank_bearing_stiffness_n_per_mm", 3e5)
                .with_number("disc_translation", 0.0),
        )
        .unwrap();
        let alone = lambda * (t_c / (2.0 * k * 36.0 * 36.0)).atan() * ARCMIN_PER_RAD;
        let out = eval(&rotation_only, &row(2, 412.0, 0.01, -0.008));
        assert!((out[0] / alone - 1.0).abs() < 1e-12);
    }

    #[test]
    fn needle_row_stiffness_is_palmgren_at_the_rms_load() {
        // 15 needles of 8 mm: k = G/δ(G), δ(G) = 2·3.84e-5·(4.08·G/15)^0.9/8^0.8 at the rms
        // crank load G = √((T_c/(2a))² + (|F|/2)²); the lag is then the constant-k lag with
        // that k.
        let model = rv40e();
        let inputs = row(2, 412.0, 0.01, -0.008);
        let load = model.disc_load(&inputs);
        let g = (load.disc_torque / 72.0).hypot(0.5 * load.force_x.hypot(load.force_y));
        let deflection = 2.0 * 3.84e-5 * (4.08 * g / 15.0).powf(0.9) / 8f64.powf(0.8);
        let k = g / deflection;
        let constant = with("crank_bearing_stiffness_n_per_mm", k).unwrap();
        let (a, b) = (eval(&model, &inputs), eval(&constant, &inputs));
        assert!((a[0] / b[0] - 1.0).abs() < 1e-12, "{} vs {}", a[0], b[0]);
        // A realistic row is far stiffer than 004's 10⁶ N/m.
        assert!(k > 1e5, "{k}");
    }

    #[test]
    fn equal_and_opposite_eccentrics_turn_the_disc_by_the_four_bar_closure() {
        // Crank 1's eccentric longer by δ, crank 2's shorter by δ (no other misfit):
        // q1 − q2 = (0, 2δ) in disc 3's eccentric frame. Its component across the crank
        // line (crank 4's hole at a·(−sin θ, −cos θ), so the line's normal ẑ × r̂ is
        // (cos θ, −sin θ)) is −2δ·sin θ, and disc 3 turns by ρ = (q1 − q2)⊥/(2a) =
        // −δ·sin θ/a; at the output −λ·ρ = λ·δ·sin θ/a, with max − min 2·λ·δ/a over the
        // turn. The second eccentric of each crank points the other way: disc 3' turns
        // opposite, and the output (their mean) does not turn.
        let model = with("crank_bearing_stiffness_n_per_mm", 3e5).unwrap();
        let delta = 0.004;
        let mut inputs = row(2, 412.0, 0.01, -0.008);
        (inputs[at(0, 0)], inputs[at(1, 0)]) = (delta, -delta);
        let lambda = model.torque_factor();
        let states = model.turn(&inputs);
        assert_eq!(states.len(), 72);
        for state in &states {
            let (s, c) = state.theta.sin_cos();
            let across = 2.0 * delta * -s + 0.0 * c; // (0, 2δ)·(cos θ, −sin θ)
            let rho = across / (2.0 * 36.0);
            assert!(
                (state.four_bar[0] + lambda * rho).abs() < 1e-15,
                "θ {}: {} vs {}",
                state.theta,
                state.four_bar[0],
                -lambda * rho
            );
            assert!((state.four_bar[0] + state.four_bar[1]).abs() < 1e-18);
        }
        let out = eval(&model, &inputs);
        let peak_to_peak = 2.0 * lambda * delta / 36.0 * ARCMIN_PER_RAD;
        assert!((out[5] / peak_to_peak - 1.0).abs() < 1e-12, "{}", out[5]);
        // The output's ripple: equal bearings and no output four-bar turn: none.
        assert!(out[1] < 1e-9, "{}", out[1]);
        // The misfit along the crank line (2δ·cos θ) preloads the two bearings against
        // each other: the largest radial force grows.
        let unmisfitted = eval(&model, &row(2, 412.0, 0.01, -0.008));
        assert!(out[4] > unmisfitted[4]);
    }

    #[test]
    fn a_crank_shifted_as_a_whole_turns_the_output() {
        // Crank 1 shifted by du across disc 3's eccentric (a 6-DOF translation: the same
        // vector at both eccentrics). Disc 3: q1 = (du, 0), ρ = r_1 × q1/(2a²) =
        // du·cos θ/(2a), t = q1/2; disc 3' (frame turned by π, holes at −r_k): q1' =
        // (−du, 0), the same ρ and the opposite shift. The output, their mean, turns by
        // −λ·du·cos θ/(2a): max − min λ·du/a, which is also disc 3's four-bar p-p (its shift
        // is constant over the turn).
        let model = with("crank_bearing_stiffness_n_per_mm", 3e5).unwrap();
        let du = 0.003;
        let mut inputs = row(2, 412.0, 0.01, -0.008);
        inputs[at(0, 1)] = du;
        let lambda = model.torque_factor();
        for state in model.turn(&inputs) {
            let mean = 0.5 * (state.four_bar[0] + state.four_bar[1]);
            let expected = -lambda * du * state.theta.cos() / 72.0;
            assert!((mean - expected).abs() < 1e-15, "θ {}", state.theta);
        }
        let out = eval(&model, &inputs);
        let peak_to_peak = lambda * du / 36.0 * ARCMIN_PER_RAD;
        assert!((out[1] / peak_to_peak - 1.0).abs() < 1e-9, "{}", out[1]);
        assert!((out[5] / peak_to_peak - 1.0).abs() < 1e-9, "{}", out[5]);
    }

    #[test]
    fn tilts_act_at_the_disc_planes() {
        // A tilt dβ about y moves each eccentric centre by dβ·z along x (001 Eq. 5–8), at the
        // planes z = ∓l3/2 = ∓5.5 mm (reference midway): −5.5·dβ at disc 3, +5.5·dβ at disc
        // 3', i.e. −5.5·dβ in each disc's own frame. So disc 3 turns as under a shift
        // du = −5.5·dβ, and disc 3' the opposite way to that shift's.
        let model = with("crank_bearing_stiffness_n_per_mm", 3e5).unwrap();
        let mut tilted = row(2, 412.0, 0.01, -0.008);
        tilted[at(0, 4)] = 2e-4;
        let mut shifted = row(2, 412.0, 0.01, -0.008);
        shifted[at(0, 1)] = 2e-4 * (-5.5);
        let (a, b) = (model.turn(&tilted), model.turn(&shifted));
        for (x, y) in a.iter().zip(&b) {
            assert!((x.four_bar[0] - y.four_bar[0]).abs() < 1e-15);
            assert!((x.four_bar[1] + y.four_bar[1]).abs() < 1e-15);
        }
    }

    #[test]
    fn three_cranks_share_the_torque_and_fit_their_misfits() {
        // Three equal cranks, no misfit: each carries T_c/(3a) tangentially plus F/3, so the
        // lag is λ·T_c·(1/(3k·a²) + 1/(3k·(e·z_c)²)), and there is no ripple.
        let params = CrankElasticError::rv40e_params()
            .with_number("crank_count", 3.0)
            .with_number("crank_bearing_stiffness_n_per_mm", 3e5);
        let model = CrankElasticError::from_params(&params).unwrap();
        assert_eq!(model.inputs().len(), 4 + 21);
        let inputs = row(3, 412.0, 0.01, -0.008);
        let load = model.disc_load(&inputs);
        let lambda = model.torque_factor();
        let t_c = load.disc_torque;
        let hand =
            lambda * t_c * (1.0 / (3.0 * 3e5 * 36.0 * 36.0) + 1.0 / (3.0 * 3e5 * 50.7 * 50.7));
        let out = eval(&model, &inputs);
        assert!((out[0] / (hand * ARCMIN_PER_RAD) - 1.0).abs() < 1e-12);
        assert!(out[1] < 1e-9 * out[0]);
        // A misfit on one crank only: the fitted pose turns the disc by the weighted share
        // r_1 × q_1/(3a²), and the rest preloads.
        let mut misfit = row(3, 412.0, 0.01, -0.008);
        misfit[at(0, 0)] = 0.003;
        let states = model.turn(&misfit);
        let amplitude = states
            .iter()
            .map(|s| s.four_bar[0].abs())
            .fold(0.0, f64::max);
        let expected = lambda * 0.003 / (3.0 * 36.0);
        // Disc shift: mean misfit q1/3 along y, no turn of the output from it; the
        // rotation's amplitude over the sampled angles reaches λ·δ/(3a) within cos(2.5°).
        assert!(amplitude <= expected * (1.0 + 1e-12) && amplitude > expected * 0.999);
    }

    #[test]
    fn unequal_stiffness_gives_ripple_between_the_equal_cases() {
        // k1 = 1.2k, k3 = 0.8k: the lag varies over the turn; its mean lies between the
        // lags with 1.2k and with 0.8k on both cranks.
        let model = with("crank_bearing_stiffness_n_per_mm", 3e5).unwrap();
        let mut unequal = row(2, 412.0, 0.01, -0.008);
        (unequal[at(0, 6)], unequal[at(1, 6)]) = (0.2, -0.2);
        let mut stiff = unequal.clone();
        stiff[at(1, 6)] = 0.2;
        let mut soft = unequal.clone();
        soft[at(0, 6)] = -0.2;
        let (out, out_stiff, out_soft) = (
            eval(&model, &unequal),
            eval(&model, &stiff),
            eval(&model, &soft),
        );
        assert!(out[1] > 0.0);
        assert!(out_stiff[0] < out[0] && out[0] < out_soft[0], "{out:?}");
        assert!(out_stiff[1] < 1e-9 * out_stiff[0]);
    }

    #[test]
    fn lag_is_linear_in_torque_for_a_constant_stiffness() {
        // With a constant k the pose is linear in the loads, and the lag takes of the pin
        // resultant only F_x = T_c/(e·z_c) (the torque balance), so |T|/lag is the same at
        // 100, 200 and 412 N·m (and on the other flank) up to rounding.
        let model = with("crank_bearing_stiffness_n_per_mm", 3e5).unwrap();
        let reference = eval(&model, &row(2, 412.0, 0.01, -0.008))[2];
        for torque in [100.0, 200.0, -412.0] {
            let out = eval(&model, &row(2, torque, 0.01, -0.008));
            assert!(
                (out[2] / reference - 1.0).abs() < 1e-12,
                "{torque}: {}",
                out[2]
            );
        }
        // No load: no lag, the kinematic ripple alone; stiffness and forces undefined.
        let unloaded = eval(&model, &row(2, 0.0, 0.01, -0.008));
        assert_eq!(&unloaded[..2], &[0.0, 0.0]);
        assert!(unloaded[2].is_nan() && unloaded[3].is_nan() && unloaded[4].is_nan());
        assert_eq!(unloaded[5], 0.0);
    }

    #[test]
    fn crank_forces_over_a_turn() {
        // max over θ of the tangential force = ½(T_c/a + |F|) and max |F_r| = ½|F|, up to
        // the 5° grid: cos(2.5°) = 0.99905 (two equal cranks, no misfit).
        let model = rv40e();
        let inputs = row(2, 412.0, 0.01, -0.008);
        let load = model.disc_load(&inputs);
        let magnitude = load.force_x.hypot(load.force_y);
        let out = eval(&model, &inputs);
        let tangential = 0.5 * (load.disc_torque / 36.0 + magnitude);
        assert!(
            out[3] <= tangential * (1.0 + 1e-12) && out[3] >= tangential - 0.5 * magnitude * 1e-3
        );
        assert!(out[4] <= 0.5 * magnitude * (1.0 + 1e-12) && out[4] >= 0.5 * magnitude * 0.999);
    }

    #[test]
    fn bad_rows_give_nan() {
        let model = rv40e();
        let mut inputs = row(2, 412.0, 0.01, -0.008);
        inputs[at(0, 6)] = -1.0; // k1 = 0
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
        let mut inputs = row(2, 412.0, 0.01, -0.008);
        inputs[2] = f64::NAN;
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
        let mut inputs = row(2, 412.0, 0.01, -0.008);
        inputs[0] = f64::INFINITY;
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
        let mut inputs = row(2, 412.0, 0.01, -0.008);
        inputs[3] = -40.0; // a ≤ 0
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases = [
            ("pin_count", 41.0, "cycloid_teeth"),
            ("cycloid_teeth", 40.0, "cycloid_teeth"),
            ("eccentricity_mm", 1.6, "eccentricity_mm"), // K1 = 1.6·40/64 = 1
            ("pin_circle_radius_mm", 50.0, "eccentricity_mm"), // K1 = 1.04
            (
                "crank_bearing_stiffness_n_per_mm",
                0.0,
                "crank_bearing_stiffness_n_per_mm",
            ),
            (
                "crank_bearing_stiffness_n_per_mm",
                -5.0,
                "crank_bearing_stiffness_n_per_mm",
            ),
            ("needle_roller_count", 0.5, "needle_roller_count"),
            ("needle_roller_length_mm", 0.0, "needle_roller_length_mm"),
            ("disc_face_width_mm", 0.0, "disc_face_width_mm"),
            ("crank_circle_radius_mm", -36.0, "crank_circle_radius_mm"),
            ("crank_l3_mm", 0.0, "crank_l3_mm"),
            ("pressure_angle_deg", 90.0, "pressure_angle_deg"),
            ("angle_steps", 2.0, "angle_steps"),
            ("disc_load_share", 1.5, "disc_load_share"),
            ("crank_count", 4.0, "crank_count"),
            ("disc_translation", 2.0, "disc_translation"),
            (
                "crank_center_distance_half_mm",
                36.0,
                "crank_center_distance_half_mm",
            ),
        ];
        for (key, value, named) in cases {
            let err = with(key, value).unwrap_err();
            assert_eq!(err.key, named, "{key} = {value}: {err}");
        }
        let err = with("eccentricity_mm", 1.6).unwrap_err();
        assert!(err.to_string().contains("must be below 1"), "{err}");
        let err = with("cycloid_teeth", 40.0).unwrap_err();
        assert!(err.to_string().contains("pin_count − 1 = 39"), "{err}");
        let err = with("crank_center_distance_half_mm", 36.0).unwrap_err();
        assert!(err.to_string().contains("unknown parameter"), "{err}");
        let err = with("crank_bearing_stiffness_n_per_mm", -5.0).unwrap_err();
        assert!(err.to_string().contains("must be positive"), "{err}");
        // Nothing given: the first required key read is named.
        let err = CrankElasticError::from_params(&ModelParams::new()).unwrap_err();
        assert_eq!(err.key, "crank_circle_radius_mm");
        let err = CrankElasticError::from_params(
            &ModelParams::new().with_number("crank_circle_radius_mm", 36.0),
        )
        .unwrap_err();
        assert_eq!(err.key, "pin_count");
    }

    #[test]
    fn registry_example_builds() {
        let model = (ENTRY.build)(&(ENTRY.example_params)()).unwrap();
        assert_eq!(model.inputs().len(), 18);
        assert_eq!(model.outputs().len(), 6);
        let names: Vec<&str> = model.inputs().iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names[4], "eccentricity_error_mm_1");
        assert_eq!(names[17], "crank_bearing_stiffness_error_2");
        assert_eq!(
            crate::find("crank_elastic_error").unwrap().name,
            "crank_elastic_error"
        );
    }
}
