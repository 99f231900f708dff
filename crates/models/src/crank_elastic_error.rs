//! `crank_elastic_error`: the forces between the two cranks and a cycloid disc over a crank
//! turn, and the elastic lag of the output from the deflection of the crank bearings
//! (document 004, RV40E), with the readings of validation.md 004 (docs/models.md §11).
//!
//! Frame (004's o_p–xy): y along the crank eccentricity, x perpendicular to it, the frame of
//! `cycloid_pin_contact`. θ is 004's angle of the disc relative to that frame (the line
//! of the two crank holes against x); 004 replaces θ by θ − γ for a crank angle γ, so one
//! crank turn sweeps θ over [0, 2π). Tangential and radial components of a crank force are
//! taken at its crank hole (perpendicular to and along the hole's radius a). Lengths in mm,
//! forces in N, torques in N·mm inside (N·m at the inputs), stiffnesses in N/mm.
//!
//! Pin resultant (F_x, F_y): the resultant of the pin forces on one disc, from the load
//! sharing of `cycloid_pin_contact` built with the same geometry (2 cranks on the circle
//! a0), for the row (T, Δr_rp, Δr_p, 0, 0, δē, 0), δē = (δe_1 + δe_2)/2. Its torque balance
//! gives F_x·e·z_c = T_disc = share·|T| exactly. The contact model keeps the design lever
//! arms; with the actual eccentricity e = e0 + δē the identity F_x = T_disc/(e·z_c) is still
//! exact (l_i = e·z_c·sin φ_i/S_i and the x part of the push direction is sin φ_i/S_i), so
//! (F_x, F_y) is scaled by e0/e (first order for F_y, as the contact model itself).
//!
//! Disc 3 (004's three disc equations; a = a0 + δa, 004's extension by δa):
//!   −F_t43·cos θ − F_r43·sin θ + F_t4'3·cos θ − F_r4'3·sin θ = −F_x
//!    F_t43·sin θ − F_r43·cos θ − F_t4'3·sin θ − F_r4'3·cos θ = −F_y
//!   (F_t43 + F_t4'3)·a = F_x·r_c',   r_c' = e·z_c.
//! With 004's closure F_r43 = F_r4'3 (the disc is stiff between its crank holes: equal
//! radial deformation) they solve in closed form (validation.md 004):
//!   F_t43  = ½(F_x·r_c'/a + F_x·cos θ − F_y·sin θ)
//!   F_t4'3 = ½(F_x·r_c'/a − F_x·cos θ + F_y·sin θ)
//!   F_r43  = F_r4'3 = ½(F_x·sin θ + F_y·cos θ)
//! so F_t43 + F_t4'3 = T_disc/a whatever e. Disc 3' carries the mirrored forces
//! (F_t43 = F_t4'3', F_t4'3 = F_t43', …).
//!
//! Crank 4 (004's four crank equations; axial positions from the planet gear: output
//! bearing 5 at l1, disc 3 at l1 + l2, disc 3' at l1 + l2 + l3, bearing 5' at l1 + … + l4):
//!   F_t12·cos θ + F_r12·sin θ + F_t54 − F_r43·sin θ − F_t43·cos θ + F_r4'3·sin θ
//!     − F_t4'3·cos θ + F_t5'4 = 0
//!   −F_t12·sin θ + F_r12·cos θ − F_r54 − F_r43·cos θ + F_t43·sin θ + F_r4'3·cos θ
//!     + F_t4'3·sin θ − F_r5'4 = 0
//!   F_t54·l1 + (−F_r43·sin θ − F_t43·cos θ)·(l1 + l2) + (F_r4'3·sin θ − F_t4'3·cos θ)
//!     ·(l1 + l2 + l3) + F_t5'4·(l1 + … + l4) = 0
//!   F_r54·l1 + (F_r43·cos θ − F_t43·sin θ)·(l1 + l2) + (−F_r4'3·cos θ − F_t4'3·sin θ)
//!     ·(l1 + l2 + l3) + F_r5'4·(l1 + … + l4) = 0
//! with the crank's torque balance −F_x·e = F_t12·R2 (004's simplification, which the
//! first disc equation makes exact) and F_r12 = F_t12·tan α'. Disc, crank and closure
//! equations are 8 linear equations in (F_t43, F_t4'3, F_r43, F_r4'3, F_t54, F_t5'4, F_r54,
//! F_r5'4): [`CrankElasticError::equilibrium_system`] and
//! [`CrankElasticError::solve_equilibrium`] (nalgebra LU) build and solve them; the tests
//! check the closed form against them. They are not used per sample.
//!
//! Elastic lag (004's four-bar linkage: cranks l1, l3 = the eccentricities, coupler = the
//! disc's crank-hole distance, fixed link l4 = 2a on the carrier; 004 reuses the symbols
//! l1..l4 for the axial positions above):
//!   Δβ = arctan((Δl1·sin β1 + Δl3·sin β3)/(l4 + Δl1·cos β1 + Δl3·cos β3)),
//!   Δl1 = F_t43/k1, Δl3 = F_t4'3/k3, k_i = k·(1 + x_i).
//! Reading (validation.md 004): the tangential deflections are perpendicular to the fixed
//! link (β1 = β3 = 90°, parallel cranks), so
//!   Δβ(θ) = arctan((F_t43/k1 + F_t4'3/k3)/(2a)),
//! evaluated at θ_j = 2πj/N, j = 0..N−1 (N = `angle_steps`). With k1 = k3 = k it is
//! arctan(T_disc/(2k·a²)) for every θ and e: 0.3316° for 004's k = 10⁶ N/m at 30 N·m with
//! two discs (T_disc = 15 N·m). The numerator is formed as
//! ½(F_t43 + F_t4'3)(1/k1 + 1/k3) + ½(F_t43 − F_t4'3)(1/k1 − 1/k3), so equal stiffnesses give
//! exactly no ripple.
//!
//! Sign: Δβ > 0 is a lag of the output behind the input under load (004's table prints a
//! lag as negative). A negative output torque loads the other flank and is treated by
//! symmetry (|T|), as in `cycloid_pin_contact`; every output is then a magnitude.
//!
//! Outputs: mean of Δβ over the turn (arcmin), its max − min, the torsional stiffness
//! |T|/mean Δβ (N·m/arcmin; at T = 0 its small-load limit 4a²/(share·(1/k1 + 1/k3))), the
//! largest of F_t43, F_t4'3 over the turn and the largest |F_r43|. A row with a
//! non-finite input, k_i ≤ 0, e ≤ 0 or a ≤ 0 gives NaN outputs (the engine counts them).

use rvtol_deviation::Shown;
use std::f64::consts::PI;

use nalgebra::{SMatrix, SVector};

use crate::cycloid_pin_contact::CycloidPinContact;
use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
    ARCMIN_PER_RAD,
};

/// The inputs, in order.
const INPUTS: [(&str, &str, &str); 8] = [
    (
        "output_torque_nm",
        "N·m",
        "torque at the output; one disc carries disc_load_share of it",
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
        "eccentricity_error_mm_1",
        "mm",
        "δe of crank 4, eccentricity minus design",
    ),
    (
        "eccentricity_error_mm_2",
        "mm",
        "δe of crank 4', eccentricity minus design",
    ),
    (
        "crank_spacing_error_mm",
        "mm",
        "δa, 004's error of a0 (half the distance between the crank axes)",
    ),
    (
        "crank_bearing_stiffness_error_1",
        "1",
        "x_1, relative error of crank 4's bearing stiffness: k1 = k·(1 + x_1)",
    ),
    (
        "crank_bearing_stiffness_error_2",
        "1",
        "x_2, relative error of the bearing stiffness of crank 4': k3 = k·(1 + x_2)",
    ),
];

/// The outputs, in order.
const OUTPUTS: [(&str, &str, &str); 5] = [
    (
        "elastic_error_arcmin",
        "arcmin",
        "mean over a crank turn of the elastic lag Δβ of the output (positive: lags)",
    ),
    (
        "elastic_error_ripple_arcmin",
        "arcmin",
        "max − min of Δβ over a crank turn",
    ),
    (
        "torsional_stiffness_nm_per_arcmin",
        "N·m/arcmin",
        "|output torque| / elastic_error_arcmin (crank bearings only)",
    ),
    (
        "max_crank_tangential_force_n",
        "N",
        "largest of F_t43, F_t4'3 over a crank turn",
    ),
    (
        "crank_radial_force_n",
        "N",
        "largest |F_r43| = |F_r4'3| over a crank turn",
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
        name: "crank_center_distance_half_mm",
        unit: "mm",
        description: "a0, half the distance between the two crank axes (004: 36)",
        default: None,
    },
    ParamSpec {
        name: "planet_pitch_radius_mm",
        unit: "mm",
        description: "R2, planet pitch radius (004: 26)",
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
        name: "crank_bearing_stiffness_n_per_mm",
        unit: "N/mm",
        description: "k, nominal stiffness of the bearing between one crank eccentric and the disc (004: 10⁶ N/m)",
        default: None,
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
        name: "angle_steps",
        unit: "1",
        description: "N, angles θ sampled over one crank turn (4..=3600)",
        default: Some(72.0),
    },
];

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "crank_elastic_error",
    summary: "crank forces over a turn and elastic lag of the output from crank bearing stiffness (document 004, four-bar reading), pin resultant from cycloid_pin_contact",
    params: PARAMS,
    build: |params| Ok(Box::new(CrankElasticError::from_params(params)?)),
    example_params: CrankElasticError::rv40e_params,
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
    /// a = a0 + δa, mm.
    pub crank_half_distance: f64,
    /// T_disc = share·|T|, N·mm.
    pub disc_torque: f64,
}

/// Forces of cranks 4 and 4' on disc 3 at one θ (the closed form), N.
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

/// The crank elastic error model with its checked geometry.
#[derive(Debug, Clone)]
pub struct CrankElasticError {
    /// The pin-force model of the same disc (2 cranks on the circle a0).
    contact: CycloidPinContact,
    crank_half_distance: f64,
    planet_pitch_radius: f64,
    /// tan α'.
    tan_pressure_angle: f64,
    ratio: f64,
    stiffness: f64,
    /// 004's l1..l4, mm.
    crank_lengths: [f64; 4],
    /// (sin θ_j, cos θ_j) for θ_j = 2πj/N.
    angles: Vec<(f64, f64)>,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

impl CrankElasticError {
    /// The RV40E of document 004 (z_p 40, z_c 39, e 1.3 mm, a0 36 mm, R2 26 mm, α' 20°,
    /// z1 10, z2 26, k = 10⁶ N/m), with what 004 leaves out: r_p 64 mm (002 Table 1's
    /// RV40E), pin radius 2.5 mm, face width 10 mm, l1..l4 = 15, 12, 11, 12 mm (assumed).
    pub fn rv40e_params() -> ModelParams {
        ModelParams::new()
            .with_number("pin_count", 40.0)
            .with_number("cycloid_teeth", 39.0)
            .with_number("pin_circle_radius_mm", 64.0)
            .with_number("pin_radius_mm", 2.5)
            .with_number("eccentricity_mm", 1.3)
            .with_number("disc_face_width_mm", 10.0)
            .with_number("crank_center_distance_half_mm", 36.0)
            .with_number("planet_pitch_radius_mm", 26.0)
            .with_number("sun_teeth", 10.0)
            .with_number("planet_teeth", 26.0)
            .with_number("crank_bearing_stiffness_n_per_mm", 1000.0)
            .with_number("crank_l1_mm", 15.0)
            .with_number("crank_l2_mm", 12.0)
            .with_number("crank_l3_mm", 11.0)
            .with_number("crank_l4_mm", 12.0)
    }

    /// Builds the model, checking every parameter once.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let crank_half_distance = params.positive("crank_center_distance_half_mm", None)?;
        // The disc and pin parameters go to the contact model, which checks them under
        // their own keys; its two cranks sit on the circle a0.
        let contact = CycloidPinContact::of_two_crank_disc(params, crank_half_distance)?;
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
        let stiffness = params.positive("crank_bearing_stiffness_n_per_mm", None)?;
        let crank_lengths = [
            params.positive("crank_l1_mm", None)?,
            params.positive("crank_l2_mm", None)?,
            params.positive("crank_l3_mm", None)?,
            params.positive("crank_l4_mm", None)?,
        ];
        let angle_steps = params.count("angle_steps", Some(72.0))? as usize;
        if !(4..=3600).contains(&angle_steps) {
            return Err(ModelError::new(
                "angle_steps",
                format!("must be between 4 and 3600, got {angle_steps}"),
            ));
        }
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let pins = contact.stage().pins;
        Ok(CrankElasticError {
            contact,
            crank_half_distance,
            planet_pitch_radius,
            tan_pressure_angle: pressure_angle.to_radians().tan(),
            ratio: 1.0 + planet_teeth / sun_teeth * pins as f64,
            stiffness,
            crank_lengths,
            angles: (0..angle_steps)
                .map(|j| (2.0 * PI * j as f64 / angle_steps as f64).sin_cos())
                .collect(),
            inputs: INPUTS
                .iter()
                .map(|&(name, unit, description)| InputSpec {
                    name: name.into(),
                    unit: unit.into(),
                    description,
                })
                .collect(),
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

    /// The disc load for one row of inputs (in the order of `inputs()`): the pin resultant
    /// of the contact model for (T, Δr_rp, Δr_p, δē), scaled by e0/e so that
    /// F_x·e·z_c = T_disc with the actual e = e0 + δē (module comment). No allocation.
    pub fn disc_load(&self, inputs: &[f64]) -> DiscLoad {
        let mean_error = 0.5 * (inputs[3] + inputs[4]);
        let contact_row = [inputs[0], inputs[1], inputs[2], 0.0, 0.0, mean_error, 0.0];
        let (force_x, force_y) = self.contact.resultant(&contact_row);
        let eccentricity = self.contact.stage().eccentricity + mean_error;
        let scale = self.contact.stage().eccentricity / eccentricity;
        DiscLoad {
            force_x: force_x * scale,
            force_y: force_y * scale,
            eccentricity,
            crank_half_distance: self.crank_half_distance + inputs[5],
            disc_torque: self.contact.load_share() * inputs[0].abs() * 1000.0,
        }
    }

    /// 004's disc equations with the closure F_r43 = F_r4'3, in closed form at θ.
    pub fn disc_forces(&self, load: &DiscLoad, theta: f64) -> DiscForces {
        let (sin, cos) = theta.sin_cos();
        self.disc_forces_at(load, sin, cos)
    }

    fn disc_forces_at(&self, load: &DiscLoad, sin: f64, cos: f64) -> DiscForces {
        let sum = self.tangential_sum(load);
        let difference = load.force_x * cos - load.force_y * sin;
        DiscForces {
            f_t43: 0.5 * (sum + difference),
            f_t4p3: 0.5 * (sum - difference),
            f_r: 0.5 * (load.force_x * sin + load.force_y * cos),
        }
    }

    /// F_t43 + F_t4'3 = F_x·r_c'/a (004's third disc equation).
    fn tangential_sum(&self, load: &DiscLoad) -> f64 {
        load.force_x * load.eccentricity * self.contact.stage().teeth as f64
            / load.crank_half_distance
    }

    /// 004's 8 equations at θ as A·x = b, x = (F_t43, F_t4'3, F_r43, F_r4'3, F_t54, F_t5'4,
    /// F_r54, F_r5'4): rows 1–3 the disc equations, 4–7 the crank-4 equations with
    /// F_t12 = −F_x·e/R2 and F_r12 = F_t12·tan α', 8 the closure F_r43 − F_r4'3 = 0.
    pub fn equilibrium_system(
        &self,
        load: &DiscLoad,
        theta: f64,
    ) -> (SMatrix<f64, 8, 8>, SVector<f64, 8>) {
        let (s, c) = theta.sin_cos();
        let [l1, l2, l3, l4] = self.crank_lengths;
        let (at_disc, at_disc_p, at_end) = (l1 + l2, l1 + l2 + l3, l1 + l2 + l3 + l4);
        let a = load.crank_half_distance;
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

    /// 004's four-bar lag with parallel cranks (docs/models.md §11): the disc's crank-hole
    /// line turns by arctan((Δl1 + Δl3)/(2a)) against the carrier when its two crank holes
    /// deflect tangentially by Δl1 + Δl3 in all (mm), a the crank circle radius (mm); rad.
    pub(crate) fn four_bar_lag(deflection: f64, a: f64) -> f64 {
        (deflection / (2.0 * a)).atan()
    }

    /// Outputs for one disc load and the two crank stiffnesses (N/mm, > 0).
    fn over_turn(&self, load: &DiscLoad, k1: f64, k3: f64) -> [f64; 5] {
        let a = load.crank_half_distance;
        let sum = self.tangential_sum(load);
        let (compliance_sum, compliance_difference) = (1.0 / k1 + 1.0 / k3, 1.0 / k1 - 1.0 / k3);
        let (mut lag_sum, mut lag_min, mut lag_max) = (0.0, f64::INFINITY, f64::NEG_INFINITY);
        let (mut tangential_max, mut radial_max) = (f64::NEG_INFINITY, 0.0_f64);
        for &(sin, cos) in &self.angles {
            let forces = self.disc_forces_at(load, sin, cos);
            let deflection = 0.5 * sum * compliance_sum
                + 0.5 * (forces.f_t43 - forces.f_t4p3) * compliance_difference;
            let lag = Self::four_bar_lag(deflection, a);
            lag_sum += lag;
            lag_min = lag_min.min(lag);
            lag_max = lag_max.max(lag);
            tangential_max = tangential_max.max(forces.f_t43.max(forces.f_t4p3));
            radial_max = radial_max.max(forces.f_r.abs());
        }
        let lag_mean = lag_sum / self.angles.len() as f64 * ARCMIN_PER_RAD;
        let torque_nm = load.disc_torque / (1000.0 * self.contact.load_share());
        let stiffness = if torque_nm > 0.0 {
            torque_nm / lag_mean
        } else {
            4.0 * a * a / (self.contact.load_share() * compliance_sum) / (1000.0 * ARCMIN_PER_RAD)
        };
        [
            lag_mean,
            (lag_max - lag_min) * ARCMIN_PER_RAD,
            stiffness,
            tangential_max,
            radial_max,
        ]
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
        let k1 = self.stiffness * (1.0 + inputs[6]);
        let k3 = self.stiffness * (1.0 + inputs[7]);
        let eccentricity = self.contact.stage().eccentricity + 0.5 * (inputs[3] + inputs[4]);
        let a = self.crank_half_distance + inputs[5];
        let valid = inputs.iter().all(|x| x.is_finite())
            && k1 > 0.0
            && k3 > 0.0
            && eccentricity > 0.0
            && a > 0.0;
        if !valid {
            outputs.fill(f64::NAN);
            return;
        }
        let load = self.disc_load(inputs);
        outputs.copy_from_slice(&self.over_turn(&load, k1, k3));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 004's RV40E with k = 10⁶ N/m = 1000 N/mm (004's value) and the assumed r_p 64 mm
    /// (002 Table 1), pin radius 2.5 mm, face width 10 mm, l1..l4 15, 12, 11, 12 mm.
    fn rv40e() -> CrankElasticError {
        CrankElasticError::from_params(&CrankElasticError::rv40e_params()).unwrap()
    }

    fn with(key: &str, value: f64) -> Result<CrankElasticError, ModelError> {
        CrankElasticError::from_params(&CrankElasticError::rv40e_params().with_number(key, value))
    }

    /// Inputs: torque, Δr_rp, Δr_p, δe_1, δe_2, δa, x_1, x_2.
    fn row(torque: f64, equidistant: f64, shift: f64) -> [f64; 8] {
        [torque, equidistant, shift, 0.0, 0.0, 0.0, 0.0, 0.0]
    }

    fn eval(model: &CrankElasticError, inputs: &[f64; 8]) -> [f64; 5] {
        let mut out = [0.0; 5];
        model.evaluate(inputs, &mut out);
        out
    }

    /// 004's "about 0.33°" (validation.md 004): arctan(T_disc/(2k·a0²)) with T_disc =
    /// 15 000 N·mm, k = 1000 N/mm, a0 = 36 mm, in degrees.
    fn the_033_degrees() -> f64 {
        (15_000.0_f64 / (2.0 * 1000.0 * 36.0 * 36.0))
            .atan()
            .to_degrees()
    }

    #[test]
    fn ratio_is_105() {
        // 004: i = 105 = 1 + (26/10)·40 (validation.md 004).
        assert_eq!(rv40e().ratio(), 105.0);
    }

    #[test]
    fn pin_resultant_carries_the_disc_torque() {
        // Torque balance of the contact model: F_x·e·z_c = T_disc = 0.5·T (module
        // comment), with modification and with eccentricity errors (actual e).
        let model = rv40e();
        for (torque, errors) in [
            (30.0, (0.0, 0.0)),
            (412.0, (0.003, -0.001)),
            (200.0, (-0.004, -0.002)),
        ] {
            let mut inputs = row(torque, 0.01, -0.008);
            (inputs[3], inputs[4]) = errors;
            let load = model.disc_load(&inputs);
            let t_disc = 0.5 * torque * 1000.0;
            assert_eq!(load.disc_torque, t_disc);
            assert!((load.eccentricity - (1.3 + 0.5 * (errors.0 + errors.1))).abs() < 1e-15);
            let moment = load.force_x * load.eccentricity * 39.0;
            assert!(
                (moment / t_disc - 1.0).abs() < 1e-12,
                "{moment} vs {t_disc}"
            );
            // The modification concentrates the load: F_y is not zero.
            assert!(load.force_y.abs() > 1e-3 * load.force_x);
        }
        // Without errors the resultant is the contact model's own (its outputs 4, 5).
        let inputs = row(412.0, 0.01, -0.008);
        let load = model.disc_load(&inputs);
        let mut contact_out = [0.0; 6];
        model
            .contact
            .evaluate(&[412.0, 0.01, -0.008, 0.0, 0.0, 0.0, 0.0], &mut contact_out);
        assert_eq!(
            (load.force_x, load.force_y),
            (contact_out[4], contact_out[5])
        );
    }

    #[test]
    fn closed_form_agrees_with_the_8x8_solve() {
        // validation.md 004: the closed form must agree with a full 8×8 solve.
        let model = rv40e();
        for torque in [30.0, 150.0, 412.0] {
            for (da, de) in [(0.0, 0.0), (0.005, -0.003)] {
                let mut inputs = row(torque, 0.01, -0.008);
                (inputs[3], inputs[4], inputs[5]) = (de, de, da);
                let load = model.disc_load(&inputs);
                for k in 0..24 {
                    let theta = k as f64 * PI / 12.0 + 0.1;
                    let closed = model.disc_forces(&load, theta);
                    let solved = model.solve_equilibrium(&load, theta).unwrap();
                    let scale = load.force_x.hypot(load.force_y);
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
                    // 004's unsimplified crank moment equation holds with the solution:
                    // (−F_r43 sin θ − F_t43 cos θ)e − (F_r4'3 sin θ − F_t4'3 cos θ)e
                    //   − F_t12·R2 = 0, F_t12 = −F_x·e/R2.
                    let (s, c) = theta.sin_cos();
                    let e = load.eccentricity;
                    let moment = (-solved.f_r43 * s - solved.f_t43 * c) * e
                        - (solved.f_r4p3 * s - solved.f_t4p3 * c) * e
                        + load.force_x * e;
                    assert!(moment.abs() < 1e-9 * load.force_x * e, "{moment}");
                }
            }
        }
    }

    #[test]
    fn tangential_sum_is_independent_of_eccentricity() {
        // validation.md 004: F_t43 + F_t4'3 = T_disc/a0 whatever e (1.2, 1.3, 1.4 mm;
        // K1 = e·40/64 stays below 1), at any θ, with modification.
        for e in [1.2, 1.3, 1.4] {
            let model = with("eccentricity_mm", e).unwrap();
            let load = model.disc_load(&row(30.0, 0.01, -0.008));
            for theta in [0.0, 0.7, 2.0, 4.5] {
                let forces = model.disc_forces(&load, theta);
                let sum = forces.f_t43 + forces.f_t4p3;
                assert!(
                    (sum / (15_000.0 / 36.0) - 1.0).abs() < 1e-12,
                    "e {e}: {sum}"
                );
            }
        }
    }

    #[test]
    fn lag_of_033_degrees_independent_of_eccentricity() {
        // validation.md 004: k = 10⁶ N/m, 30 N·m, two discs: arctan(15000/(2·1000·36²))
        // = 0.3316° (printed to 4 digits), no ripple, whatever e.
        assert!((the_033_degrees() - 0.3316).abs() < 5e-5);
        for e in [1.2, 1.3, 1.4] {
            let model = with("eccentricity_mm", e).unwrap();
            for inputs in [
                row(30.0, 0.0, 0.0),
                row(30.0, 0.01, -0.008),
                [30.0, 0.01, -0.008, 0.05, -0.02, 0.0, 0.0, 0.0],
            ] {
                let out = eval(&model, &inputs);
                let degrees = out[0] / 60.0;
                assert!(
                    (degrees / the_033_degrees() - 1.0).abs() < 1e-12,
                    "e {e}: {degrees}°"
                );
                assert!(out[1] == 0.0, "ripple {}", out[1]);
            }
        }
        // 004's table magnitude (0.035–0.039°) is not reproduced (validation.md 004).
    }

    #[test]
    fn unequal_stiffness_gives_ripple_between_the_equal_cases() {
        // k1 = 1.2k, k3 = 0.8k: Δβ(θ) varies with F_t43 − F_t4'3 ∝ F_x cos θ − F_y sin θ;
        // its mean lies between the lags with 1.2k and with 0.8k on both cranks.
        let model = rv40e();
        let mut unequal = row(412.0, 0.01, -0.008);
        (unequal[6], unequal[7]) = (0.2, -0.2);
        let mut stiff = unequal;
        stiff[7] = 0.2;
        let mut soft = unequal;
        soft[6] = -0.2;
        let (out, out_stiff, out_soft) = (
            eval(&model, &unequal),
            eval(&model, &stiff),
            eval(&model, &soft),
        );
        assert!(out[1] > 0.0);
        assert!(out_stiff[0] < out[0] && out[0] < out_soft[0], "{out:?}");
        assert_eq!(out_stiff[1], 0.0);
        // Small-angle form of the mean: T_disc·(1/k1 + 1/k3)/(4a²) (the cos/sin terms
        // average out over the equally spaced θ); the arctan bends it by ~x²/3 = 2.3e-3 here
        // (x = 0.083 rad).
        let small = 206_000.0 * (1.0 / 1200.0 + 1.0 / 800.0) / (4.0 * 36.0 * 36.0);
        let bent = (out[0] / ARCMIN_PER_RAD / small - 1.0).abs();
        assert!(bent < 3e-3, "{bent}");
    }

    #[test]
    fn lag_is_linear_in_torque_for_equal_stiffness() {
        // With k1 = k3 the lag is arctan(T_disc/(2k·a²)): tan Δβ ∝ T exactly, and the
        // torsional stiffness |T|/Δβ is constant up to the arctan's x²/3 (2.3e-8 at 412 N·m).
        let model = with("crank_bearing_stiffness_n_per_mm", 3.0e5).unwrap();
        let reference = eval(&model, &row(30.0, 0.01, -0.008));
        let expected_stiffness = 2.0 * 3.0e5 * 36.0 * 36.0 / 0.5 / (1000.0 * ARCMIN_PER_RAD);
        for torque in [30.0, 100.0, 412.0, -412.0] {
            let out = eval(&model, &row(torque, 0.01, -0.008));
            let tan_ratio = (out[0] / ARCMIN_PER_RAD).tan() / (reference[0] / ARCMIN_PER_RAD).tan();
            assert!((tan_ratio - torque.abs() / 30.0).abs() < 1e-12 * tan_ratio);
            assert!(
                (out[2] / expected_stiffness - 1.0).abs() < 5e-8,
                "{}",
                out[2]
            );
        }
        // No load: no lag, and the stiffness is the small-load limit.
        let unloaded = eval(&model, &row(0.0, 0.01, -0.008));
        assert_eq!(&unloaded[..2], &[0.0, 0.0]);
        assert!((unloaded[2] / expected_stiffness - 1.0).abs() < 1e-12);
        assert_eq!(&unloaded[3..], &[0.0, 0.0]);
    }

    #[test]
    fn crank_forces_over_a_turn() {
        // max over θ of max(F_t43, F_t4'3) = ½(T_disc/a + |F|) and max |F_r| = ½|F|,
        // |F| = |(F_x, F_y)|, up to the 5° grid: cos(2.5°) = 0.99905.
        let model = rv40e();
        let inputs = row(412.0, 0.01, -0.008);
        let load = model.disc_load(&inputs);
        let magnitude = load.force_x.hypot(load.force_y);
        let out = eval(&model, &inputs);
        let tangential = 0.5 * (206_000.0 / 36.0 + magnitude);
        assert!(
            out[3] <= tangential * (1.0 + 1e-12) && out[3] >= tangential - 0.5 * magnitude * 1e-3
        );
        assert!(out[4] <= 0.5 * magnitude * (1.0 + 1e-12) && out[4] >= 0.5 * magnitude * 0.999);
    }

    #[test]
    fn the_sign_of_f_y_does_not_change_the_outputs() {
        // 004 does not fix the sense of F_y against the contact model's; flipping it is
        // θ → −θ, and the outputs over the symmetric θ grid do not change.
        let model = rv40e();
        let load = model.disc_load(&row(412.0, 0.01, -0.008));
        let flipped = DiscLoad {
            force_y: -load.force_y,
            ..load
        };
        let (a, b) = (
            model.over_turn(&load, 1200.0, 800.0),
            model.over_turn(&flipped, 1200.0, 800.0),
        );
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * x.abs(), "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn bad_rows_give_nan() {
        let model = rv40e();
        let mut inputs = row(412.0, 0.01, -0.008);
        inputs[6] = -1.0; // k1 = 0
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
        let mut inputs = row(412.0, 0.01, -0.008);
        inputs[7] = -1.5;
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
        let mut inputs = row(412.0, 0.01, -0.008);
        inputs[2] = f64::NAN;
        assert!(eval(&model, &inputs).iter().all(|x| x.is_nan()));
        let mut inputs = row(412.0, 0.01, -0.008);
        inputs[0] = f64::INFINITY;
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
            ("disc_face_width_mm", 0.0, "disc_face_width_mm"),
            (
                "crank_center_distance_half_mm",
                -36.0,
                "crank_center_distance_half_mm",
            ),
            ("crank_l3_mm", 0.0, "crank_l3_mm"),
            ("pressure_angle_deg", 90.0, "pressure_angle_deg"),
            ("angle_steps", 2.0, "angle_steps"),
            ("disc_load_share", 1.5, "disc_load_share"),
            ("crank_count", 3.0, "crank_count"),
        ];
        for (key, value, named) in cases {
            let err = with(key, value).unwrap_err();
            assert_eq!(err.key, named, "{key} = {value}: {err}");
        }
        let err = with("eccentricity_mm", 1.6).unwrap_err();
        assert!(err.to_string().contains("must be below 1"), "{err}");
        let err = with("cycloid_teeth", 40.0).unwrap_err();
        assert!(err.to_string().contains("pin_count − 1 = 39"), "{err}");
        let err = with("crank_count", 3.0).unwrap_err();
        assert!(err.to_string().contains("unknown parameter"), "{err}");
        // Nothing given: the first required key read (the crank circle, needed to build the
        // contact model) is named.
        let err = CrankElasticError::from_params(&ModelParams::new()).unwrap_err();
        assert_eq!(err.key, "crank_center_distance_half_mm");
        let err = CrankElasticError::from_params(
            &ModelParams::new().with_number("crank_center_distance_half_mm", 36.0),
        )
        .unwrap_err();
        assert_eq!(err.key, "pin_count");
    }

    #[test]
    fn registry_example_builds() {
        let model = (ENTRY.build)(&(ENTRY.example_params)()).unwrap();
        assert_eq!(model.inputs().len(), 8);
        assert_eq!(model.outputs().len(), 5);
        assert_eq!(
            crate::find("crank_elastic_error").unwrap().name,
            "crank_elastic_error"
        );
    }
}
