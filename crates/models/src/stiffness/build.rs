//! The crank side built from a model's parameters, with the estimation rules of
//! docs/models.md §13 for the dimensions a scenario leaves out (`torsion_curve`'s keys).
//!
//! ```text
//! rules (the same for every size):
//!   needle diameter D = d_j/5;  support width B = l_s/0.7
//!   support bearing outer diameter D_s = d_j + 4·D_w, D_w = π·d_j/(1.2·Z_s − 2π) (the
//!     roller-count rule Z_s = π·d_m/(1.2·D_w), D_w = (D_s − d)/4, inverted with d = d_j)
//!   support preload F_a0: the least that keeps every roller of a support loaded under its
//!     reaction at 3 % of rated torque (the closed-form pin resultant): J(1) = 0.545495,
//!     F_a0 = F_r(3 %)·tan α/J(1) (tapered.rs)
//!   end plate bolt: the largest of M4–M10 no thicker than half the pillar's smaller side,
//!     12.9, VDI 2230's assembly preload (joint.rs); Ito's C = 0.046, m = 0.48
//!   the end plate as thick as a support bearing is wide (B); its pillars' holes through
//!     the discs of radius √(b² + h²)/2 + e (the pillar's half-diagonal and the disc's orbit)
//!   seat to pillar s = √(a_w² + r_c² − 2·a_w·r_c·cos(π/m)) (r_c the pillars' radius, a
//!     pillar midway between two cranks); the end plate clamped around a pillar at
//!     b = s − D_s/2 (plate.rs)
//! ```

use super::{
    assembly_preload, bolt_for_pillar, hub_tilt_stiffness, BoltedJoint, Carrier, CrankShaft,
    CrankSide, EndCompliance, Housing, InvoluteStage, RollerRow, TaperedRow,
};
use crate::{ModelError, ModelParams, ParamSpec};
use rvtol_deviation::{Rounded, Shown};
use std::f64::consts::PI;

/// The crank side's parameters (the keys [`crank_side`] reads beside the reducer's own), in
/// the order the models that build it list them.
pub(crate) const PARAMS: [ParamSpec; 28] = [
    ParamSpec {
        name: "youngs_modulus_mpa",
        unit: "MPa",
        description: "E of every steel part",
        default: Some(206_000.0),
    },
    ParamSpec {
        name: "poisson_ratio",
        unit: "1",
        description: "ν of every steel part",
        default: Some(0.3),
    },
    ParamSpec {
        name: "crank_journal_diameter_mm",
        unit: "mm",
        description: "d_j, eccentric journal (needle inner raceway), also the crank's bending and torsion diameter",
        default: None,
    },
    ParamSpec {
        name: "needle_roller_count",
        unit: "1",
        description: "Z, needles between one eccentric and the disc bore",
        default: None,
    },
    ParamSpec {
        name: "needle_roller_diameter_mm",
        unit: "mm",
        description: "D, needle diameter: the disc's bore is d_j/2 + D; default d_j/5 (the estimation rule of docs/models.md §13)",
        default: None,
    },
    ParamSpec {
        name: "needle_roller_length_mm",
        unit: "mm",
        description: "l, effective needle length",
        default: None,
    },
    ParamSpec {
        name: "crank_support_span_mm",
        unit: "mm",
        description: "L, between the load centres of a crank's two support bearings",
        default: None,
    },
    ParamSpec {
        name: "crank_eccentric_spacing_mm",
        unit: "mm",
        description: "s, between the two eccentrics' (the discs') mid-planes, centred in the span (< L); a crank's tilt acts on a disc at ±s/2",
        default: None,
    },
    ParamSpec {
        name: "support_roller_count",
        unit: "1",
        description: "Z_s, rollers of one support bearing",
        default: None,
    },
    ParamSpec {
        name: "support_roller_length_mm",
        unit: "mm",
        description: "l_s, effective roller length of a support bearing",
        default: None,
    },
    ParamSpec {
        name: "support_contact_angle_deg",
        unit: "deg",
        description: "α_s, contact angle of a support bearing (tapered rollers), in [0, 45)",
        default: None,
    },
    ParamSpec {
        name: "support_bearing_width_mm",
        unit: "mm",
        description: "B, width of a support bearing, the thickness of the carrier plate around it; default support_roller_length_mm/0.7 (the estimation rule of docs/models.md §13)",
        default: None,
    },
    ParamSpec {
        name: "support_bearing_outer_diameter_mm",
        unit: "mm",
        description: "D_s, outer diameter of a support bearing, the end plate's seat bore; default d_j + 4π·d_j/(1.2·Z_s − 2π) (the roller-count rule of docs/models.md §13 inverted)",
        default: None,
    },
    ParamSpec {
        name: "support_preload_n",
        unit: "N",
        description: "F_a0, axial preload of each support bearing (the crank's shim), ≥ 0; default the least that keeps every roller loaded under a support's reaction at 3 % of rated torque (docs/models.md §13)",
        default: None,
    },
    ParamSpec {
        name: "carrier_pillar_count",
        unit: "1",
        description: "n_p, pillars joining the carrier's plates; default crank_count",
        default: None,
    },
    ParamSpec {
        name: "carrier_pillar_radius_mm",
        unit: "mm",
        description: "r_p, radius of the pillars' centres; default crank_circle_radius_mm",
        default: None,
    },
    ParamSpec {
        name: "carrier_pillar_width_mm",
        unit: "mm",
        description: "b, pillar section across the radius",
        default: None,
    },
    ParamSpec {
        name: "carrier_pillar_depth_mm",
        unit: "mm",
        description: "h, pillar section along the radius",
        default: None,
    },
    ParamSpec {
        name: "carrier_pillar_length_mm",
        unit: "mm",
        description: "L_p, free pillar length between the plates",
        default: None,
    },
    ParamSpec {
        name: "end_plate_bolt_diameter_mm",
        unit: "mm",
        description: "d, the 12.9 bolt clamping each pillar to the end plate: 4, 5, 6, 8 or 10; default the largest no thicker than half the pillar's smaller side",
        default: None,
    },
    ParamSpec {
        name: "end_plate_bolt_preload_n",
        unit: "N",
        description: "F_M, that bolt's preload; default VDI 2230's assembly preload (12.9, μ_G 0.12, 90 % of the yield point)",
        default: None,
    },
    ParamSpec {
        name: "joint_deflection_coefficient",
        unit: "µm/MPa^m",
        description: "C of the joint surface's δ = C·p^m (Ito, Modular Design for Machine Tools, Table 6-5: ground steel 0.046)",
        default: Some(0.046),
    },
    ParamSpec {
        name: "joint_deflection_exponent",
        unit: "1",
        description: "m of the joint surface's δ = C·p^m, in (0, 1) (Ito, Table 6-5: ground steel 0.48)",
        default: Some(0.48),
    },
    ParamSpec {
        name: "disc_pillar_hole_radius_mm",
        unit: "mm",
        description: "r_h, the holes the pillars pass through in each disc; default the pillar's half-diagonal plus e",
        default: None,
    },
    ParamSpec {
        name: "planet_face_width_mm",
        unit: "mm",
        description: "b, face width of the sun–planet mesh",
        default: None,
    },
    ParamSpec {
        name: "mesh_stiffness_n_per_mm_um",
        unit: "N/(mm·µm)",
        description: "c_γ, mesh stiffness per mm of face width (ISO 6336-1: about 20 for steel spur gears)",
        default: Some(20.0),
    },
    ParamSpec {
        name: "planet_gear_overhang_mm",
        unit: "mm",
        description: "l1, planet gear to the nearer support bearing along the crank",
        default: None,
    },
    ParamSpec {
        name: "body_compliance",
        unit: "1",
        description: "1: the discs (around their bores and pillars' holes), the carrier's plates (seats, paths to the pillars, the pillars' roots, the end plate's joints and bending) and the housing around the pins are elastic (docs/models.md §13); 0: rigid bodies",
        default: Some(1.0),
    },
];

/// What the crank side needs of the reducer around it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reducer {
    /// m, cranks.
    pub cranks: usize,
    /// a_w, mm.
    pub crank_circle_radius: f64,
    /// z_p, pins.
    pub pins: usize,
    /// z_c, disc teeth.
    pub teeth: usize,
    /// r_p, mm.
    pub pin_circle_radius: f64,
    /// e, mm.
    pub eccentricity: f64,
    /// K1 = e·z_p/r_p.
    pub curtate: f64,
    /// The disc's face width, mm.
    pub face_width: f64,
    /// i, the reducer's ratio.
    pub ratio: f64,
    /// T_c at 3 % of rated torque, N·mm (the preload rule's load).
    pub reference_disc_torque: f64,
    /// The discs, plates and housing elastic (`body_compliance`).
    pub elastic_bodies: bool,
}

/// The crank side and what the torsion model keeps beside it.
#[derive(Debug, Clone)]
pub(crate) struct Built {
    /// The chain.
    pub side: CrankSide,
    /// The housing's influence matrix (`None` with rigid bodies).
    pub housing: Option<Housing>,
    /// d_j, mm.
    pub journal_diameter: f64,
    /// z1/z2.
    pub crank_turn: f64,
}

/// E and ν of every steel part.
#[derive(Debug, Clone, Copy)]
struct Steel {
    youngs: f64,
    poisson: f64,
}

/// Builds the crank side from `params` (module comment); the errors name the key.
pub(crate) fn crank_side(params: &ModelParams, reducer: &Reducer) -> Result<Built, ModelError> {
    let steel = Steel {
        youngs: params.positive("youngs_modulus_mpa", Some(206_000.0))?,
        poisson: params.number("poisson_ratio", Some(0.3))?,
    };
    let journal_diameter = params.positive("crank_journal_diameter_mm", None)?;
    let needle = RollerRow {
        rollers: params.count("needle_roller_count", None)? as f64,
        length: params.positive("needle_roller_length_mm", None)?,
        contact_angle: 0.0,
    };
    let needle_diameter =
        params.positive("needle_roller_diameter_mm", Some(0.2 * journal_diameter))?;
    let shaft = shaft(params, journal_diameter, steel)?;
    let row = support_row(params)?;
    let support_width = params.positive("support_bearing_width_mm", Some(row.length / 0.7))?;
    let carrier = Carrier {
        pillars: params.count("carrier_pillar_count", Some(reducer.cranks as f64))? as f64,
        radius: params.positive(
            "carrier_pillar_radius_mm",
            Some(reducer.crank_circle_radius),
        )?,
        width: params.positive("carrier_pillar_width_mm", None)?,
        depth: params.positive("carrier_pillar_depth_mm", None)?,
        length: params.positive("carrier_pillar_length_mm", None)?,
    };
    let (involute, crank_turn) = involute(params, reducer, shaft.span)?;
    let seat_diameter = params.positive(
        "support_bearing_outer_diameter_mm",
        Some(
            journal_diameter
                + 4.0 * PI * journal_diameter / (1.2 * row.rollers - 2.0 * PI).max(1e-9),
        ),
    )?;
    let support = TaperedRow { row, preload: 0.0 };
    let preload = support_preload(params, reducer, support, shaft)?;
    let joint = end_plate_joint(params, &carrier, support_width)?;
    let hole = params.positive(
        "disc_pillar_hole_radius_mm",
        Some(0.5 * carrier.width.hypot(carrier.depth) + reducer.eccentricity),
    )?;
    let mut side = CrankSide {
        cranks: reducer.cranks as f64,
        crank_circle_radius: reducer.crank_circle_radius,
        pitch_radius: reducer.eccentricity * reducer.teeth as f64,
        needle,
        bore_compliance: 0.0,
        web_compliance: (0.0, 0.0),
        shaft,
        support: TaperedRow { row, preload },
        support_housing_compliance: 0.0,
        seat_path_compliance: 0.0,
        carrier_stiffness: carrier.torsional_stiffness(steel.youngs, steel.poisson),
        end_plate_joint_compliance: 0.0,
        end_plate_bending_compliance: 0.0,
        involute_compliance: involute.output_compliance(reducer.ratio, shaft.torsional_rigidity),
    };
    let bodies = Bodies {
        bore_radius: 0.5 * journal_diameter + needle_diameter,
        seat_diameter,
        support_width,
        hole,
        carrier,
        joint,
        steel,
    };
    bodies.check(reducer)?;
    let housing = if reducer.elastic_bodies {
        bodies.add_to(&mut side, reducer);
        Some(Housing::new(
            reducer.pins,
            reducer.pin_circle_radius,
            reducer.curtate,
            reducer.face_width,
            steel.youngs,
            steel.poisson,
        ))
    } else {
        None
    };
    Ok(Built {
        side,
        housing,
        journal_diameter,
        crank_turn,
    })
}

/// The crank shaft from its span, eccentric spacing and journal.
fn shaft(params: &ModelParams, journal: f64, steel: Steel) -> Result<CrankShaft, ModelError> {
    let span = params.positive("crank_support_span_mm", None)?;
    let spacing = params.positive("crank_eccentric_spacing_mm", None)?;
    if spacing >= span {
        return Err(ModelError::new(
            "crank_eccentric_spacing_mm",
            format!(
                "must be below crank_support_span_mm ({}), got {}",
                Shown(span),
                Shown(spacing)
            ),
        ));
    }
    Ok(CrankShaft::new(
        journal,
        span,
        spacing,
        steel.youngs,
        steel.poisson,
    ))
}

/// One support bearing's rollers.
fn support_row(params: &ModelParams) -> Result<RollerRow, ModelError> {
    let contact_angle = params.number("support_contact_angle_deg", None)?;
    if !(0.0..45.0).contains(&contact_angle) {
        return Err(ModelError::new(
            "support_contact_angle_deg",
            format!("must lie in [0, 45), got {}", Shown(contact_angle)),
        ));
    }
    Ok(RollerRow {
        rollers: params.count("support_roller_count", None)? as f64,
        length: params.positive("support_roller_length_mm", None)?,
        contact_angle: contact_angle.to_radians(),
    })
}

/// The involute stage and the crank's turn per output radian, z1/z2.
fn involute(
    params: &ModelParams,
    reducer: &Reducer,
    span: f64,
) -> Result<(InvoluteStage, f64), ModelError> {
    let sun = params.count("sun_teeth", None)? as f64;
    let planet = params.count("planet_teeth", None)? as f64;
    let pressure_angle = params.number("pressure_angle_deg", Some(20.0))?;
    let stage = InvoluteStage {
        sun_teeth: sun,
        planet_teeth: planet,
        cranks: reducer.cranks as f64,
        planet_base_radius: reducer.crank_circle_radius * planet / (sun + planet)
            * pressure_angle.to_radians().cos(),
        face_width: params.positive("planet_face_width_mm", None)?,
        mesh_stiffness: 1000.0 * params.positive("mesh_stiffness_n_per_mm_um", Some(20.0))?,
        torsion_length: params.positive("planet_gear_overhang_mm", None)? + 0.5 * span,
    };
    Ok((stage, sun / planet))
}

/// F_a0, the supports' axial preload: given, or the rule's (module comment).
fn support_preload(
    params: &ModelParams,
    reducer: &Reducer,
    support: TaperedRow,
    shaft: CrankShaft,
) -> Result<f64, ModelError> {
    let alpha = support.row.contact_angle;
    let rule = if alpha > 0.0 {
        let reaction = super::chain::closed_form_support_load(
            &shaft,
            reducer.cranks as f64,
            reducer.crank_circle_radius,
            reducer.eccentricity * reducer.teeth as f64,
            reducer.reference_disc_torque,
        );
        TaperedRow::full_zone_preload(&support.row, reaction)
    } else {
        0.0
    };
    let preload = params.number("support_preload_n", Some(rule))?;
    if !(preload >= 0.0 && preload.is_finite()) || (preload > 0.0 && alpha == 0.0) {
        return Err(ModelError::new(
            "support_preload_n",
            format!(
                "must be ≥ 0, and 0 for supports without a contact angle (support_contact_angle_deg {}), got {}",
                Shown(alpha.to_degrees()),
                Shown(preload)
            ),
        ));
    }
    Ok(preload)
}

/// The end plate's bolted joint on each pillar (module comment; joint.rs).
fn end_plate_joint(
    params: &ModelParams,
    carrier: &Carrier,
    plate_thickness: f64,
) -> Result<BoltedJoint, ModelError> {
    let rule = bolt_for_pillar(carrier.width, carrier.depth);
    let diameter = params.number("end_plate_bolt_diameter_mm", rule.map(|b| b.0))?;
    let Some(bolt) = super::joint::BOLTS.iter().find(|b| b.0 == diameter) else {
        return Err(ModelError::new(
            "end_plate_bolt_diameter_mm",
            format!(
                "must be one of 4, 5, 6, 8, 10 (ISO coarse threads with their holes and heads), got {}",
                Shown(diameter)
            ),
        ));
    };
    let joint = BoltedJoint {
        width: carrier.width,
        depth: carrier.depth,
        hole: bolt.2,
        cone: bolt.3 + 2.0 * plate_thickness * super::joint::CONE_TAN_MIN,
        preload: params.positive(
            "end_plate_bolt_preload_n",
            Some(assembly_preload(
                bolt.0,
                bolt.1,
                super::joint::THREAD_FRICTION,
            )),
        )?,
        coefficient: params.positive(
            "joint_deflection_coefficient",
            Some(super::joint::ITO_COEFFICIENT),
        )?,
        exponent: params.positive(
            "joint_deflection_exponent",
            Some(super::joint::ITO_EXPONENT),
        )?,
    };
    if joint.exponent >= 1.0 || joint.area() <= 0.0 {
        let (key, what) = if joint.exponent >= 1.0 {
            ("joint_deflection_exponent", "must lie in (0, 1)")
        } else {
            (
                "end_plate_bolt_diameter_mm",
                "its clearance hole must leave the pillar's face some area",
            )
        };
        return Err(ModelError::new(key, what.to_string()));
    }
    Ok(joint)
}

/// The bodies' dimensions (module comment).
struct Bodies {
    bore_radius: f64,
    seat_diameter: f64,
    support_width: f64,
    hole: f64,
    carrier: Carrier,
    joint: BoltedJoint,
    steel: Steel,
}

impl Bodies {
    /// s, from a seat's centre to the nearest pillar's.
    fn seat_to_pillar(&self, reducer: &Reducer) -> f64 {
        let (a, r) = (reducer.crank_circle_radius, self.carrier.radius);
        (a * a + r * r - 2.0 * a * r * (PI / reducer.cranks as f64).cos()).sqrt()
    }

    /// The dimensions the bodies need must fit in the reducer; the errors name the key.
    fn check(&self, reducer: &Reducer) -> Result<(), ModelError> {
        let rim = reducer.pin_circle_radius - reducer.crank_circle_radius;
        if self.bore_radius >= rim {
            return Err(ModelError::new(
                "needle_roller_diameter_mm",
                format!(
                    "the disc's bore (crank_journal_diameter_mm/2 + needle_roller_diameter_mm = {} mm) must lie inside the pin circle, {} mm beyond the crank circle",
                    Rounded(self.bore_radius),
                    Rounded(rim)
                ),
            ));
        }
        if !reducer.elastic_bodies {
            return Ok(());
        }
        if self.carrier.pillars != reducer.cranks as f64 {
            return Err(ModelError::new(
                "carrier_pillar_count",
                "must equal crank_count with body_compliance 1 (a pillar midway between two cranks: the seats' paths and the discs' holes)".to_string(),
            ));
        }
        let between = self.seat_to_pillar(reducer);
        if self.hole + self.bore_radius >= between {
            return Err(ModelError::new(
                "disc_pillar_hole_radius_mm",
                format!(
                    "a pillar's hole must clear the crank bores: {} + {} mm against {} mm between their centres",
                    Rounded(self.hole),
                    Rounded(self.bore_radius),
                    Rounded(between)
                ),
            ));
        }
        let clamp = between - 0.5 * self.seat_diameter;
        if clamp <= self.hub_radius() {
            return Err(ModelError::new(
                "support_bearing_outer_diameter_mm",
                format!(
                    "the seat's bore must leave the end plate around a pillar: {} mm from the pillar's axis to the seat, inside its root ({} mm)",
                    Rounded(clamp),
                    Rounded(self.hub_radius())
                ),
            ));
        }
        Ok(())
    }

    /// c, the pillar's rocking-equivalent radius (carrier.rs).
    fn hub_radius(&self) -> f64 {
        let (b, h) = (self.carrier.width, self.carrier.depth);
        (4.0 * h * b.powi(3) / 12.0 / PI).powf(0.25)
    }

    /// The body terms of the crank side (module comment).
    fn add_to(&self, side: &mut CrankSide, reducer: &Reducer) {
        let Steel { youngs, poisson } = self.steel;
        let rim = reducer.pin_circle_radius - reducer.crank_circle_radius;
        let s = self.seat_to_pillar(reducer);
        side.bore_compliance = RollerRow::ringless_housing_compliance(
            self.bore_radius,
            rim,
            reducer.face_width,
            youngs,
            poisson,
        );
        side.web_compliance = super::bodies::disc_web_compliance(
            reducer.cranks,
            reducer.crank_circle_radius,
            self.carrier.radius,
            self.hole,
            reducer.face_width,
            youngs,
            poisson,
        );
        side.support_housing_compliance =
            RollerRow::housing_ovalisation_compliance(self.support_width, youngs, poisson);
        side.seat_path_compliance = super::bodies::net_force_compliance(
            0.5 * self.seat_diameter,
            s,
            self.support_width,
            youngs,
            poisson,
        );
        let roots = self
            .carrier
            .torsional_stiffness_on_elastic_roots(youngs, poisson);
        let joint = self.joint.compliance(poisson);
        let bolted = self
            .carrier
            .torsional_stiffness_with_end_plate(youngs, poisson, &joint);
        let plate = hub_tilt_stiffness(
            self.hub_radius(),
            s - 0.5 * self.seat_diameter,
            self.support_width,
            youngs,
            poisson,
        );
        let bent = EndCompliance {
            rocking: joint.rocking + 1.0 / plate,
            ..joint
        };
        let whole = self
            .carrier
            .torsional_stiffness_with_end_plate(youngs, poisson, &bent);
        side.carrier_stiffness = roots;
        side.end_plate_joint_compliance = 1.0 / bolted - 1.0 / roots;
        side.end_plate_bending_compliance = 1.0 / whole - 1.0 / bolted;
    }
}
