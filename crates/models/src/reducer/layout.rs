//! The inputs and outputs of `rv_lost_motion`, their names, units and places in a row:
//! the reducer-wide deviations, then per disc, per crank (with its two eccentrics), per pin.
//! Names shared with `transmission_error`'s physical reading mean the same quantity in the
//! same frame.

use crate::preload;
use crate::{ConditionEffect, InputSpec, OutputCondition, OutputKind, OutputSpec};

/// Reducer-wide inputs, in order.
const FIXED: [(&str, &str, &str); 12] = [
    ("common_normal_upper_deviation_mm", "mm", "E_ws, upper deviation of the sun–planet common normal length (000 Eq. 5)"),
    ("common_normal_lower_deviation_mm", "mm", "E_wi, lower deviation of the common normal length (000 Eq. 5)"),
    ("equidistant_modification_error_mm", "mm", "δΔr_rp, error of the equidistant modification, both discs (positive: clearance)"),
    ("shift_modification_error_mm", "mm", "δΔr_p, error of the shift modification, both discs (positive: less clearance)"),
    ("pin_circle_radius_error_mm", "mm", "δr_p, pin circle radius minus design, every pin"),
    ("pin_radius_error_mm", "mm", "δr_rp, pin radius minus design, every pin (a batch's mean)"),
    ("pin_hole_clearance_mm", "mm", "δJ, diametral clearance of a pin in its housing groove: every pin may retreat by δJ/2"),
    ("crank_bearing_clearance_mm", "mm", "u, radial internal clearance of the needle rows between eccentrics and discs (ISO 5753-1: total radial travel), every crank"),
    ("input_shaft_du_mm", "mm", "input shaft deviation Δu (001) at its reference point"),
    ("input_shaft_dv_mm", "mm", "input shaft deviation Δv (001)"),
    ("input_shaft_dalpha_rad", "rad", "input shaft tilt Δα about x (001)"),
    ("input_shaft_dbeta_rad", "rad", "input shaft tilt Δβ about y (001)"),
];

/// Inputs per disc d (name stems; the disc number 1 or 2 follows).
const PER_DISC: [(&str, &str, &str); 5] = [
    ("profile_normal_error_mm", "mm", "profile error of disc d normal to the profile, every tooth (positive: clearance)"),
    ("disc_runout_mm", "mm", "F_r, radial runout of disc d's toothing about its crank bores (span: twice the toothing's eccentricity)"),
    ("disc_runout_phase_rad", "rad", "phase of disc d's runout in the disc frame (uniform over a turn when only the magnitude is toleranced)"),
    ("cumulative_pitch_deviation_mm", "mm", "F_p, total cumulative pitch deviation of disc d on the measuring circle (span of a once-per-revolution deviation)"),
    ("cumulative_pitch_phase_rad", "rad", "phase of disc d's cumulative pitch deviation in the disc frame"),
];

/// Inputs per crank k: its axis in the carrier (position and tilt, at the deviation
/// reference midway between the two discs' planes; 001 Eq. 5–8 carries a tilt to each
/// disc's plane), its needle rows' clearance, then its eccentric under each disc d.
const PER_CRANK: [(&str, &str, &str); 5] = [
    (
        "crank_axis_radial_error_mm",
        "mm",
        "crank k's axis (its bores in the carrier), radial, carrier frame",
    ),
    (
        "crank_axis_tangential_error_mm",
        "mm",
        "crank k's axis, tangential, carrier frame",
    ),
    (
        "crank_axis_tilt_radial_rad",
        "rad",
        "crank k's axis tilt about the radial direction, carrier frame (001 Eq. 7: moves the axis tangentially by −τ_r·z at the disc plane z = ±s/2)",
    ),
    (
        "crank_axis_tilt_tangential_rad",
        "rad",
        "crank k's axis tilt about the tangential direction, carrier frame (001 Eq. 7: moves the axis radially by +τ_t·z at the disc plane z = ±s/2)",
    ),
    (
        "crank_bearing_clearance_deviation_mm",
        "mm",
        "crank k's needle rows' radial internal clearance less the reducer's u (crank_bearing_clearance_mm)",
    ),
];
const PER_ECCENTRIC: [(&str, &str); 2] = [
    ("crank_eccentricity_error_mm", "eccentric of crank k under disc d: magnitude error"),
    ("crank_phase_error_mm", "eccentric of crank k under disc d: position error across the eccentric (counter-clockwise)"),
];

/// Inputs per pin i (name stems; the pin number follows).
const PER_PIN: [(&str, &str); 3] = [
    (
        "pin_radial_error_mm",
        "radial position error of pin i (outward), housing frame",
    ),
    (
        "pin_tangential_error_mm",
        "tangential position error of pin i (counter-clockwise), housing frame",
    ),
    (
        "pin_radius_deviation_mm",
        "radius of pin i less the batch's mean radius (pin_radius_error_mm)",
    ),
];

/// Where each input sits in a row.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    pub common_normal: (usize, usize),
    pub equidistant_error: usize,
    pub shift_error: usize,
    pub pin_circle_error: usize,
    pub pin_radius_error: usize,
    pub pin_hole_clearance: usize,
    pub needle_clearance: usize,
    pub shaft: usize,
    discs: usize,
    cranks: usize,
    /// The first per-pin input: radial errors, then tangential, then radii.
    pub pins: usize,
}

/// Where a crank's eccentrics start among its inputs.
pub(crate) const ECCENTRICS: usize = PER_CRANK.len();
/// Inputs per crank (its axis, its needle rows, its two eccentrics).
const CRANK_STRIDE: usize = PER_CRANK.len() + 2 * PER_ECCENTRIC.len();

impl Layout {
    pub fn new(cranks: usize) -> Layout {
        let discs = FIXED.len();
        let crank_base = discs + 2 * PER_DISC.len();
        let pin_base = crank_base + cranks * CRANK_STRIDE;
        Layout {
            common_normal: (0, 1),
            equidistant_error: 2,
            shift_error: 3,
            pin_circle_error: 4,
            pin_radius_error: 5,
            pin_hole_clearance: 6,
            needle_clearance: 7,
            shaft: 8,
            discs,
            cranks: crank_base,
            pins: pin_base,
        }
    }

    /// The first input of disc d (0-based): profile, runout, its phase, pitch, its phase.
    pub fn disc(&self, d: usize) -> usize {
        self.discs + PER_DISC.len() * d
    }

    /// The first input of crank k (0-based): axis radial, tangential, tilt about the
    /// radial and the tangential direction, needle clearance deviation, then per disc d the
    /// eccentric's magnitude and phase errors at + ECCENTRICS + 2d and + ECCENTRICS + 1 + 2d.
    pub fn crank(&self, k: usize) -> usize {
        self.cranks + CRANK_STRIDE * k
    }
}

/// The model's inputs for m cranks and z_p pins.
pub(crate) fn inputs(cranks: usize, pins: usize) -> Vec<InputSpec> {
    let input = |name: String, unit: &str, description: &'static str| InputSpec {
        name,
        unit: unit.into(),
        description,
    };
    let mut specs: Vec<InputSpec> = FIXED
        .iter()
        .map(|&(name, unit, description)| input(name.into(), unit, description))
        .collect();
    for d in 1..=2 {
        for &(name, unit, description) in &PER_DISC {
            specs.push(input(format!("{name}_{d}"), unit, description));
        }
    }
    for k in 1..=cranks {
        for &(name, unit, description) in &PER_CRANK {
            specs.push(input(format!("{name}_{k}"), unit, description));
        }
        for d in 1..=2 {
            for &(name, description) in &PER_ECCENTRIC {
                specs.push(input(format!("{name}_{k}_{d}"), "mm", description));
            }
        }
    }
    for &(name, description) in &PER_PIN {
        for i in 1..=pins {
            specs.push(input(format!("{name}_{i}"), "mm", description));
        }
    }
    specs
}

/// The outputs, in order.
pub(crate) fn outputs(loaded: bool) -> Vec<OutputSpec> {
    let condition = Some(OutputCondition {
        indicator: preload::OVER_PRELOADED,
        effect: ConditionEffect::NonConforming,
    });
    let output = |name: &str, unit: &str, description: &'static str, kind, condition| OutputSpec {
        name: name.into(),
        unit: unit.into(),
        description,
        kind,
        condition,
    };
    use OutputKind::Continuous;
    let mut outputs = vec![
        output("lost_motion_arcmin", "arcmin", "free play at the output with the input locked, at the worst of the M output angles: the two discs' common window plus the involute stage's backlash", Continuous, condition),
        output("lost_motion_mean_arcmin", "arcmin", "the same, averaged over the M output angles of one revolution", Continuous, condition),
        output("lost_motion_least_arcmin", "arcmin", "the same, at the best of the M output angles", Continuous, condition),
        output("involute_stage_arcmin", "arcmin", "involute stage backlash at the output, signed (000 Eq. 5, 12)", Continuous, None),
    ];
    outputs.extend(preload::outputs());
    if loaded {
        outputs.extend([
            output("lost_motion_loaded_arcmin", "arcmin", "the catalogue's lost motion: the torsion curve's midline at +3 % less −3 % of rated torque, from the loaded contact solution at the widest window's output angle (docs/models.md §14.9)", Continuous, condition),
            output("hysteresis_loss_arcmin", "arcmin", "the torsion curve's width at zero torque, at the same angle", Continuous, None),
            output("torsional_rigidity_nm_per_arcmin", "N·m/arcmin", "(T_r − T_r/2)/(φ(T_r) − φ(T_r/2)) on the loading branch, at the same angle", Continuous, None),
            output("angle_at_rated_arcmin", "arcmin", "half the torsion curve's span between −T_r and +T_r, at the same angle", Continuous, None),
            output("pin_force_at_rated_n", "N", "the largest pin force at ±T_r, at the same angle", Continuous, None),
        ]);
    }
    outputs
}
