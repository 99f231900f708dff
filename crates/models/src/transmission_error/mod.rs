//! `transmission_error`: the kinematic transmission error of an RV reducer over one output
//! revolution by the action-line increment principle (document 002, RV40E), with the
//! corrections of validation.md; its peak-to-peak, rms and order amplitudes (by FFT in
//! document 002's reading, by a direct DFT of the five output orders in the physical one).
//!
//! Two readings (parameter `reading`, docs/models.md §12):
//! - `"physical"` (default, module `two_discs`): two discs with eccentrics 180° apart on
//!   m cranks, four-bar closure of each disc on its crank pins, crank and input-shaft
//!   tilts at their planes (001 Eq. 5–8), disc-side errors reaching the output times
//!   κ = z_c/D because the cranks ride on the output, no output pin-hole term (a runout of
//!   the output translates it, it does not turn it). The discs' contact (`disc_contact`):
//!   under load (default, module `loaded`: every pin of both discs elastic on its own gap,
//!   the crank side between them, so a preloaded assembly has a transmission error and
//!   the preload rule judges it), or rigid, first contact over both discs or their
//!   load-shared mean, where interference is an indicator that excludes the sample.
//!   `setup` builds what the parameters ask for once.
//! - `"document_002"`: 002 read literally, the model below: one disc, the cranks
//!   averaged, 002's δ41 at r6, disc-side errors 1:1. It reproduces the one-disc model
//!   figure for figure (tests/transmission_error.rs).
//!
//! Document 002's literal reading:
//!
//! Kinematics (validation.md 002; docs/models.md §12). Pins fixed in the housing, output
//! (carrier) angle Θ. The crank's eccentric direction turns at ψ = −z_c·Θ in the housing,
//! i.e. at −z_p·Θ relative to the carrier; the disc turns with the output (Θ); the sun
//! turns at i·Θ with i = 1 + (z_pl/z_s)·z_p (121 for the RV40E; 002's
//! (1 + z_r/z_s)·z_p = 160 is wrong), i.e. at (i − 1)·Θ relative to the carrier.
//!
//! Frames of the error sources, and of the action lines they are projected on:
//! - sun runout s: sun frame; sun–planet action lines: carrier frame.
//! - planet runout p_k: planet k = crank k frame; centre-distance error c_k: carrier frame,
//!   along the line of centres.
//! - crank eccentric error q_k (along the eccentric: magnitude; perpendicular: phase):
//!   crank frame; crank-axis position error b_k (radial, tangential on the crank circle):
//!   carrier frame.
//! - pins (radial, tangential position errors; pin circle and pin radius errors): housing.
//! - cycloid profile errors (all teeth; per tooth space): disc frame.
//! - output runout o (eccentricity of the output pin-hole circle): output frame, projected
//!   on an action line fixed in the housing (the only reading under which 002's δ41 gives
//!   its once-per-revolution sinusoid; turning with the output, a radial error projects to
//!   exactly zero).
//!
//! Stages (002's four sub-mechanisms), each reduced to the output angle ΔΘ:
//! 1. Involute stage (002 Δθ1): the mesh gap of planet k along its action line
//!    n_k = sin α·u_k + cos α·t_k is g_k = n_k·(c_k·u_k + R(−z_p·Θ)·p_k − R((i−1)·Θ)·s);
//!    the planet (crank) lags by g_k/(r2·cos α); the mean over the cranks reaches the
//!    output divided by D = z_p + z_s/z_pl = i·z_s/z_pl (121/3 for the RV40E: the
//!    planet-carrier feedback of 002; D = z_p without it).
//! 2. Crank stage (002 Δθ2): the disc centre moves by d = mean_k(q_k) +
//!    R(z_p·Θ)·mean_k(R(β_k)·b_k) in the eccentric frame; its component d_t
//!    perpendicular to the eccentric advances the disc's revolution by d_t/a, the output by
//!    d_t/(a·z_c) (002: Δθ2/i_cycloidal).
//! 3. Cycloid–pin stage (002 Δθ3, with validation.md's correction: δ_n/(r·cos α3), where
//!    r·cos α3 is the lever l of the action line about the disc centre): pin i at
//!    φ_i = γ_i − ψ from the eccentric has lever l_i = a·z_c·sin φ_i/S_i (document 003)
//!    and clearance along its normal g_i = the standard modification clearance (003) +
//!    d_r·(K1 − cos φ_i)/S_i + pin errors projected as in 003 + the profile error of the
//!    tooth space at pin i. Under a light driving load the disc turns until the first pin
//!    touches: the output lags by min over pins with l_i > 0 of g_i/l_i (002's flank, with
//!    its crank stage's sign; the physical reading's drive flank is l_i < 0, docs/models.md
//!    §12.4).
//! 4. Output mechanism (002 Δθ4): ΔΘ4 = n14·R(Θ)·o/r6.
//!
//! TE(Θ) = ΔΘ1 + ΔΘ2 + ΔΘ3 + ΔΘ4, positive when the output is ahead. The curve is
//! sampled at N points per output revolution (N a power of two above twice the cycloid
//! mesh order z_c·z_p and the first-stage mesh order z_s·(i − 1)); outputs are its
//! peak-to-peak, its rms about the mean, its mean and the FFT semi-amplitudes of orders
//! 1, z_c and z_p.

use rvtol_deviation::Shown;
use std::cell::RefCell;
use std::f64::consts::PI;

use crate::cycloid::CycloidStage;
use crate::preload::{self, PreloadRule};
use crate::spectrum::RealFft;
use crate::stiffness::build;
use crate::{
    concat_params, Curve, CurveStyle, ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams,
    OutputKind, OutputSpec, ParamSpec, Series, ARCSEC_PER_RAD,
};

mod common;
mod loaded;
mod setup;
#[cfg(test)]
mod test_support;
mod two_discs;

use common::{gcd, smallest, smallest_ratio, Group, PinTable, Point, MAX_CRANKS};
use setup::Reading;

use loaded::{Loaded, LoadedScratch};
use two_discs::{Physical, TwoDiscScratch};

/// Inputs per crank, in order.
const CRANK_INPUTS: [(&str, &str); 7] = [
    (
        "planet_runout_x_mm",
        "planet runout, planet frame, along the crank's eccentric",
    ),
    (
        "planet_runout_y_mm",
        "planet runout, planet frame, perpendicular to the eccentric",
    ),
    (
        "center_distance_error_mm",
        "sun–planet centre distance error, carrier frame (002 δ11)",
    ),
    (
        "crank_eccentricity_error_mm",
        "eccentric magnitude error, crank frame (002 δ21)",
    ),
    (
        "crank_phase_error_mm",
        "eccentric position error perpendicular to the eccentric, crank frame",
    ),
    (
        "crank_axis_radial_error_mm",
        "crank bore position error, carrier frame, radial",
    ),
    (
        "crank_axis_tangential_error_mm",
        "crank bore position error, carrier frame, tangential",
    ),
];
/// The fixed inputs, in order.
const FIXED_INPUTS: [(&str, &str); 9] = [
    ("sun_runout_x_mm", "sun (input shaft) runout, sun frame"),
    ("sun_runout_y_mm", "sun (input shaft) runout, sun frame"),
    (
        "equidistant_modification_mm",
        "Δr_rp, equidistant modification (003; positive: clearance)",
    ),
    (
        "shift_modification_mm",
        "Δr_p, shift modification (003; negative: clearance)",
    ),
    (
        "profile_normal_error_mm",
        "cycloid profile error normal to the profile, every tooth (002 δ31; positive: clearance)",
    ),
    (
        "pin_circle_radius_error_mm",
        "δr_p, pin circle radius minus design",
    ),
    ("pin_radius_error_mm", "δr_rp, pin radius minus design"),
    (
        "output_runout_x_mm",
        "eccentricity of the output pin-hole circle, output frame (002 δ41)",
    ),
    (
        "output_runout_y_mm",
        "eccentricity of the output pin-hole circle, output frame",
    ),
];

/// The model's own keys (`PARAMS` adds the preload rule's and the crank side's).
const OWN_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "sun_teeth",
        unit: "",
        description: "z_s",
        default: None,
    },
    ParamSpec {
        name: "planet_teeth",
        unit: "",
        description: "z_pl, teeth of each planet (spur gear on a crank)",
        default: None,
    },
    ParamSpec {
        name: "module_mm",
        unit: "mm",
        description: "module of the involute stage (planet pitch radius r2 = m·z_pl/2)",
        default: None,
    },
    ParamSpec {
        name: "pressure_angle_deg",
        unit: "deg",
        description: "α of the involute stage",
        default: Some(20.0),
    },
    ParamSpec {
        name: "pin_count",
        unit: "",
        description: "z_p, pins",
        default: None,
    },
    ParamSpec {
        name: "cycloid_teeth",
        unit: "",
        description: "z_c = z_p − 1",
        default: None,
    },
    ParamSpec {
        name: "pin_circle_radius_mm",
        unit: "mm",
        description: "r_p",
        default: None,
    },
    ParamSpec {
        name: "eccentricity_mm",
        unit: "mm",
        description: "a, crank eccentricity",
        default: None,
    },
    ParamSpec {
        name: "output_pin_circle_radius_mm",
        unit: "mm",
        description: "r6, radius of the output pin holes (document_002 reading only: 002's δ41 term; the physical reading has no such term)",
        default: None,
    },
    ParamSpec {
        name: "crank_count",
        unit: "",
        description: "cranks (= planets), evenly spaced",
        default: Some(2.0),
    },
    ParamSpec {
        name: "points_per_revolution",
        unit: "",
        description: "N, samples of the curve over one output revolution (power of two)",
        default: Some(4096.0),
    },
    ParamSpec {
        name: "carrier_feedback",
        unit: "",
        description:
            "1: the planet-carrier feedback of 002 (divisor z_p + z_s/z_pl); 0: divisor z_p",
        default: Some(1.0),
    },
    ParamSpec {
        name: "pin_position_errors",
        unit: "",
        description: "1: add inputs pin_radial_error_mm_i and pin_tangential_error_mm_i per pin",
        default: Some(0.0),
    },
    ParamSpec {
        name: "tooth_profile_errors",
        unit: "",
        description: "1: add an input per tooth space of each disc (tooth_profile_error_mm_d_j; document_002: tooth_profile_error_mm_j of its one disc)",
        default: Some(0.0),
    },
    ParamSpec {
        name: "reading",
        unit: "text",
        description: "\"physical\" (default): two discs 180° apart, four-bar crank closure, no output pin-hole term, interference flagged (docs/models.md §12); \"document_002\": 002's literal reading (one disc, mean of the cranks, output pin-hole runout at r6, disc-side errors 1:1 at the output)",
        default: None,
    },
    ParamSpec {
        name: "disc_contact",
        unit: "text",
        description: "physical reading: \"loaded\" (default; the loaded contact solution at load_torque_nm: both discs' pins elastic on their signed gaps, coupled through the crank side, docs/models.md §12.9), \"first_contact\" (rigid, light load: the disc that touches first carries the output) or \"load_shared\" (rigid, both discs loaded: the mean of their contact angles)",
        default: None,
    },
    ParamSpec {
        name: "load_torque_nm",
        unit: "N·m",
        description: "T, the output torque of the loaded reading, input locked, on the drive flank (default 3 % of rated_torque_nm: the light load at which a catalogue reads lost motion and a single-flank test runs)",
        default: None,
    },
    ParamSpec {
        name: "crank_closure",
        unit: "text",
        description: "physical reading: \"four_bar\" (default; a rigid disc turns to fit its crank pins) or \"averaged\" (the crank bearings take up the pins' differences; 002's reading)",
        default: None,
    },
    ParamSpec {
        name: "crank_circle_radius_mm",
        unit: "mm",
        description: "a_w, radius of the crank circle (physical reading; 36 mm for the RV40E, document 004's a0)",
        default: None,
    },
    ParamSpec {
        name: "sun_plane_offset_mm",
        unit: "mm",
        description: "L_s, axial distance from the input shaft's deviation reference to the sun's mid-plane (physical reading; input shaft tilts act there)",
        default: Some(0.0),
    },
];

/// The preload rule's contact keys, which it shares with the load sharing.
const SHARED_PARAMS: &[ParamSpec] = &[preload::PIN_RADIUS, preload::FACE_WIDTH, preload::FRICTION];

const PARAMS: [ParamSpec;
    OWN_PARAMS.len() + SHARED_PARAMS.len() + preload::PARAMS.len() + build::PARAMS.len()] =
    concat_params(&[OWN_PARAMS, SHARED_PARAMS, &preload::PARAMS, &build::PARAMS]);

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "transmission_error",
    summary: "transmission error over one output revolution by the action-line increment principle (document 002), two discs on four-bar cranks, under load by default (every pin of both discs elastic on its own gap, the crank side between them; or rigid first contact, load shared, or 002's literal one-disc reading): peak-to-peak, rms, order amplitudes, interference, preload",
    params: &PARAMS,
    build: |params| Ok(Box::new(TransmissionError::from_params(params)?)),
    example_params: rv40e_params,
    example_inputs: &[],
};

/// The RV40E of document 002 Table 1, with the crank circle of document 004 (a0 = 36 mm)
/// and the crank side of scenarios/reducers/rv40e.json (its eccentrics, and so the discs'
/// mid-planes, 11 mm apart: one 10 mm face width + 1 mm, the rule of docs/models.md §13).
fn rv40e_params() -> ModelParams {
    ModelParams::new()
        .with_number("crank_circle_radius_mm", 36.0)
        .with_number("pin_radius_mm", 3.0)
        .with_number("disc_face_width_mm", 10.0)
        .with_number("pin_friction_coefficient", 0.02)
        .with_number("rated_torque_nm", 412.0)
        .with_number("sun_teeth", 9.0)
        .with_number("planet_teeth", 27.0)
        .with_number("module_mm", 2.0)
        .with_number("pin_count", 40.0)
        .with_number("cycloid_teeth", 39.0)
        .with_number("pin_circle_radius_mm", 64.0)
        .with_number("eccentricity_mm", 1.25)
        .with_number("output_pin_circle_radius_mm", 27.0)
        .with_number("crank_journal_diameter_mm", 20.0)
        .with_number("needle_roller_count", 15.0)
        .with_number("needle_roller_diameter_mm", 4.0)
        .with_number("needle_roller_length_mm", 8.0)
        .with_number("crank_support_span_mm", 38.25)
        .with_number("crank_eccentric_spacing_mm", 11.0)
        .with_number("support_roller_count", 13.0)
        .with_number("support_roller_length_mm", 10.675)
        .with_number("support_contact_angle_deg", 13.0)
        .with_number("support_bearing_width_mm", 15.25)
        .with_number("support_bearing_outer_diameter_mm", 47.0)
        .with_number("carrier_pillar_width_mm", 14.0)
        .with_number("carrier_pillar_depth_mm", 14.0)
        .with_number("carrier_pillar_length_mm", 23.0)
        .with_number("planet_face_width_mm", 10.0)
        .with_number("planet_gear_overhang_mm", 13.625)
}

/// The stage contributions at one point, rad.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageErrors {
    /// ΔΘ1, involute stage with the carrier feedback.
    pub involute: f64,
    /// ΔΘ2, crank (parallel-linkage input) stage.
    pub crank: f64,
    /// ΔΘ3, cycloid–pin stage.
    pub cycloid: f64,
    /// ΔΘ4, output mechanism.
    pub output: f64,
}

impl StageErrors {
    /// The total, rad.
    pub fn total(&self) -> f64 {
        self.involute + self.crank + self.cycloid + self.output
    }
}

/// The transmission-error model with its design geometry and precomputed tables.
#[derive(Debug, Clone)]
pub struct TransmissionError {
    sun_teeth: f64,
    planet_teeth: f64,
    pins: usize,
    cycloid_teeth: usize,
    eccentricity: f64,
    output_radius: f64,
    cranks: usize,
    points: usize,
    /// r2·cos α, mm.
    base_radius: f64,
    /// sin α, cos α.
    pressure: (f64, f64),
    /// Divisor from the crank rotation to the output.
    divisor: f64,
    per_pin: bool,
    per_tooth: bool,
    table: PinTable,
    /// The curve points, grouped (see [`Group`]).
    curve_points: Vec<Point>,
    groups: Vec<Group>,
    fft: RealFft,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
    /// The physical reading's data; None for document 002's literal reading.
    physical: Option<Box<Physical>>,
    /// The one preload rule (docs/models.md §14.5), with the physical reading.
    preload_rule: Option<PreloadRule>,
    /// The loaded reading's data (`disc_contact` "loaded").
    loaded: Option<Box<Loaded>>,
}

/// Per-thread work state of the first-contact search, refilled for every row: the per-pin
/// and per-tooth errors laid out twice in a row, so that the errors seen by consecutive
/// slots are one contiguous slice whatever the shift (zeros when the model has no such
/// inputs), and one group's ratios without the pin errors.
#[derive(Debug, Default)]
struct Search {
    pin_radial: Vec<f64>,
    pin_tangential: Vec<f64>,
    tooth: Vec<f64>,
    /// Per entry of the current group's block, the part of its ratio common to all the
    /// group's points (everything but the pin errors).
    head: Vec<f64>,
    /// The curve of the row, arcsec.
    curve: Vec<f64>,
    /// The FFT's real and imaginary columns (document 002's reading).
    fft_re: Vec<f64>,
    fft_im: Vec<f64>,
    /// The physical reading's work state.
    two: TwoDiscScratch,
    /// The loaded reading's.
    loaded: LoadedScratch,
}

// Per-thread work state (no allocation per sample).
thread_local! {
    static SEARCH: RefCell<Search> = RefCell::new(Search::default());
}

impl TransmissionError {
    /// Builds the model from its parameters.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let sun_teeth = params.count("sun_teeth", None)? as f64;
        let planet_teeth = params.count("planet_teeth", None)? as f64;
        let module = params.positive("module_mm", None)?;
        let alpha = params.positive("pressure_angle_deg", Some(20.0))?;
        if alpha >= 45.0 {
            return Err(ModelError::new(
                "pressure_angle_deg",
                format!("must be below 45, got {}", Shown(alpha)),
            ));
        }
        let stage = CycloidStage::from_params(params, 256)?;
        let (pins, cycloid_teeth) = (stage.pins, stage.teeth);
        let eccentricity = stage.eccentricity;
        let cranks = params.count("crank_count", Some(2.0))? as usize;
        if cranks > MAX_CRANKS {
            return Err(ModelError::new(
                "crank_count",
                format!("must be at most {MAX_CRANKS}, got {cranks}"),
            ));
        }
        let ratio = 1.0 + planet_teeth / sun_teeth * pins as f64;
        let points = params.count("points_per_revolution", Some(4096.0))? as usize;
        let cycloid_mesh = cycloid_teeth * pins;
        let first_mesh = ((ratio - 1.0) * sun_teeth).round() as usize;
        let needed = 2 * cycloid_mesh.max(first_mesh);
        if !points.is_power_of_two() || points <= needed || points > 1 << 16 {
            return Err(ModelError::new(
                "points_per_revolution",
                format!(
                    "must be a power of two above {needed} (twice the highest mesh order, {} ) and at most 65536, got {points}",
                    cycloid_mesh.max(first_mesh)
                ),
            ));
        }
        let feedback = params.flag("carrier_feedback", true)?;
        let per_pin = params.flag("pin_position_errors", false)?;
        let per_tooth = params.flag("tooth_profile_errors", false)?;
        let Reading {
            literal,
            contact,
            under_load,
            closure,
        } = Reading::from_params(params)?;
        // r6 belongs to 002's output pin-hole term, which only its literal reading has.
        let output_radius = if literal {
            params.positive("output_pin_circle_radius_mm", None)?
        } else {
            0.0
        };
        let physical_geometry = if literal {
            None
        } else {
            Some(setup::physical_geometry(params, &stage)?)
        };
        // λ, the torque balance of the discs against the output (docs/models.md §10).
        let lambda = cycloid_teeth as f64 / pins as f64 * (1.0 - 1.0 / ratio);
        let preload_rule = setup::preload_rule(params, &stage, literal, (ratio, lambda))?;
        let loaded = match (&preload_rule, physical_geometry) {
            (Some(rule), Some((crank_radius, _, _))) if under_load => {
                Some(Box::new(loaded::build(
                    params,
                    &stage,
                    rule,
                    (cranks, crank_radius),
                    (ratio, lambda),
                    points,
                )?))
            }
            _ => None,
        };
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let (inputs, outputs) = if literal {
            literal_specs(cranks, pins, cycloid_teeth, per_pin, per_tooth)
        } else {
            two_discs::specs(
                cranks,
                pins,
                cycloid_teeth,
                (per_pin, per_tooth),
                under_load,
            )
        };

        // Phase table: the fractional pin pitch of the eccentric at point j takes
        // N/gcd(z_c·z_p, N) values. A slot s has a positive lever while 0 < s + f < z_p/2.
        let g = gcd(cycloid_mesh, points);
        let width = pins.div_ceil(2).next_multiple_of(4);
        // Filled for 002's reading only: the physical reading builds its own, one per flank.
        let table = if literal {
            setup::literal_table(&stage, points, g, width)
        } else {
            PinTable {
                width,
                ..PinTable::default()
            }
        };
        let (curve_points, groups) = setup::curve_points(&stage, points, g, ratio);
        let alpha = alpha.to_radians();
        let divisor = if feedback {
            pins as f64 + sun_teeth / planet_teeth
        } else {
            pins as f64
        };
        let physical = physical_geometry.map(|(crank_radius, spacing, sun_offset)| {
            Box::new(two_discs::build(
                &stage,
                width,
                &curve_points,
                &groups,
                two_discs::Layout {
                    points,
                    common_divisor: g,
                    cranks,
                    per_pin,
                    ratio,
                },
                Physical::settings(
                    contact,
                    closure,
                    crank_radius,
                    spacing,
                    sun_offset,
                    cycloid_teeth as f64 / divisor,
                ),
            ))
        });
        TransmissionError {
            sun_teeth,
            planet_teeth,
            pins,
            cycloid_teeth,
            eccentricity,
            output_radius,
            cranks,
            points,
            base_radius: module * planet_teeth / 2.0 * alpha.cos(),
            pressure: alpha.sin_cos(),
            divisor,
            per_pin,
            per_tooth,
            table,
            curve_points,
            groups,
            fft: RealFft::new(points),
            inputs,
            outputs,
            physical,
            preload_rule,
            loaded,
        }
        .with_loaded_nominal()
    }

    /// Sets the loaded reading's nominal, the perfect reducer's mean angle at its torque.
    fn with_loaded_nominal(mut self) -> Result<Self, ModelError> {
        if self.loaded.is_some() {
            let nominal = self.perfect_loaded_angle().map_err(|cause| {
                ModelError::new(
                    "load_torque_nm",
                    format!("the perfect reducer has no loaded solution: {cause}"),
                )
            })?;
            if let Some(loaded) = self.loaded.as_mut() {
                loaded.nominal = nominal;
            }
        }
        Ok(self)
    }

    /// Overall ratio i = 1 + (z_pl/z_s)·z_p (validation.md 002: 121 for the RV40E).
    pub fn ratio(&self) -> f64 {
        1.0 + self.planet_teeth / self.sun_teeth * self.pins as f64
    }

    /// Divisor from a crank rotation error to the output: z_p + z_s/z_pl with the carrier
    /// feedback (121/3 for the RV40E), z_p without.
    pub fn crank_divisor(&self) -> f64 {
        self.divisor
    }

    /// Points of the curve per output revolution.
    pub fn points(&self) -> usize {
        self.points
    }

    /// Index of a named input.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|i| i.name == name)
    }

    /// Calls `sink(j, stages)` for every point j of the curve (stage errors in rad): 002's
    /// literal reading (the physical reading's stage parts are in its curves).
    pub fn trace(&self, inputs: &[f64], sink: impl FnMut(usize, StageErrors)) {
        SEARCH.with_borrow_mut(|search| self.trace_with(inputs, search, sink))
    }

    /// [`Self::trace`] with an explicit work state.
    #[inline(always)]
    fn trace_with(
        &self,
        inputs: &[f64],
        search: &mut Search,
        mut sink: impl FnMut(usize, StageErrors),
    ) {
        let n_fixed = FIXED_INPUTS.len();
        let (sun_x, sun_y) = (inputs[0], inputs[1]);
        let (d_rp, d_p, profile) = (inputs[2], inputs[3], inputs[4]);
        let (err_rp, err_rrp) = (inputs[5], inputs[6]);
        let (out_x, out_y) = (inputs[7], inputs[8]);
        let m = self.cranks as f64;
        let (sin_a, cos_a) = self.pressure;
        // Per crank k at β_k = 2π(k − 1)/m on the carrier: its action line n_k, and the
        // mean eccentric error and crank-bore error (the latter in the carrier frame).
        // The planet runouts p_k turn at −z_p·Θ in the carrier and the sun runout s at
        // (i − 1)·Θ: n_k·R(−z_p·Θ)·p_k = cos(z_p·Θ)·(n_k·p_k) + sin(z_p·Θ)·(n_k × p_k) and
        // n·R((i − 1)·Θ)·s = cos((i − 1)·Θ)·(n·s) + sin((i − 1)·Θ)·(n × s), n = Σ n_k.
        let mut involute_constant = 0.0;
        let (mut planet_cos, mut planet_sin) = (0.0, 0.0);
        let (mut q_r, mut q_t, mut b_x, mut b_y) = (0.0, 0.0, 0.0, 0.0);
        let mut normal_sum = (0.0, 0.0);
        for k in 0..self.cranks {
            let row = &inputs[n_fixed + 7 * k..n_fixed + 7 * (k + 1)];
            let (sb, cb) = (2.0 * PI * k as f64 / m).sin_cos();
            // u_k = (cb, sb), t_k = (−sb, cb); n_k = sin α·u_k + cos α·t_k.
            let n = (sin_a * cb - cos_a * sb, sin_a * sb + cos_a * cb);
            normal_sum = (normal_sum.0 + n.0, normal_sum.1 + n.1);
            let (px, py) = (row[0], row[1]);
            planet_cos += n.0 * px + n.1 * py;
            planet_sin += n.0 * py - n.1 * px;
            involute_constant += row[2] * sin_a; // n_k·(c_k·u_k)
            q_r += row[3];
            q_t += row[4];
            b_x += row[5] * cb - row[6] * sb;
            b_y += row[5] * sb + row[6] * cb;
        }
        let (q_r, q_t, b_x, b_y) = (q_r / m, q_t / m, b_x / m, b_y / m);
        let sun_cos = normal_sum.0 * sun_x + normal_sum.1 * sun_y;
        let sun_sin = normal_sum.1 * sun_x - normal_sum.0 * sun_y;
        // Per-point divisions become products: 1/(a·z_c) for the crank stage and the
        // output runout over r6, both once per row.
        let inverse_lever_base = 1.0 / (self.eccentricity * self.cycloid_teeth as f64);
        let (out_x, out_y) = (out_x / self.output_radius, out_y / self.output_radius);
        let involute_scale = -1.0 / (m * self.base_radius * self.divisor);
        let constant = profile - err_rrp;
        // Per-pin and per-tooth inputs follow the cranks' (empty when the model has none).
        let n_pins = if self.per_pin { self.pins } else { 0 };
        let n_teeth = if self.per_tooth {
            self.cycloid_teeth
        } else {
            0
        };
        let (pin_inputs, tooth_errors) = inputs[n_fixed + 7 * self.cranks..].split_at(2 * n_pins);
        let (pin_radial, pin_tangential) = pin_inputs.split_at(n_pins);
        let tooth_errors = &tooth_errors[..n_teeth];
        let table = &self.table;
        let width = table.width;
        // Each error list repeated from its start (zeros when the model has none), long
        // enough for the window read at any shift: pin + width values for the pins (the
        // width exceeds the pin count for 3 pins), twice the teeth for the tooth spaces.
        let repeat = |target: &mut Vec<f64>, values: &[f64], len: usize| {
            target.clear();
            if values.is_empty() {
                target.resize(len, 0.0);
            } else {
                target.extend(values.iter().cycle().take(len));
            }
        };
        if self.per_pin {
            repeat(&mut search.pin_radial, pin_radial, self.pins + width);
            repeat(
                &mut search.pin_tangential,
                pin_tangential,
                self.pins + width,
            );
        }
        repeat(&mut search.tooth, tooth_errors, 2 * self.cycloid_teeth);
        let Search {
            pin_radial,
            pin_tangential,
            tooth,
            head,
            ..
        } = search;
        head.resize(width, 0.0);
        let (pins, teeth) = (self.pins as u32, self.cycloid_teeth as u32);
        for group in &self.groups {
            let points = &self.curve_points[group.start as usize..group.end as usize];
            let block = group.phase as usize * width..(group.phase as usize + 1) * width;
            let blocked = &table.blocked[block.clone()];
            let inverse_lever = &table.inverse_lever[block.clone()];
            let equidistant = &table.equidistant[block.clone()];
            let shift = &table.shift[block.clone()];
            let eccentric = &table.eccentric[block.clone()];
            let radial = &table.radial[block.clone()];
            let tangential = &table.tangential[block.clone()];
            let tooth_of = &table.tooth[block];
            // The disc displacement along the eccentric and the tooth spaces of the group.
            let (sx, cx) = points[0].crank;
            let d_r = q_r + b_x * cx - b_y * sx;
            let space = &tooth[(teeth - points[0].tooth_shift) as usize..];
            for (value, &t) in head.iter_mut().zip(tooth_of) {
                *value = space[t as usize];
            }
            let head = &mut head[..width];
            let (blocked, inverse_lever, equidistant, shift, eccentric) = (
                &blocked[..width],
                &inverse_lever[..width],
                &equidistant[..width],
                &shift[..width],
                &eccentric[..width],
            );
            let (radial, tangential) = (&radial[..width], &tangential[..width]);
            for e in 0..width {
                head[e] = d_rp * equidistant[e]
                    + d_p * shift[e]
                    + err_rp * radial[e]
                    + constant * inverse_lever[e]
                    + d_r * eccentric[e]
                    + head[e] * inverse_lever[e]
                    + blocked[e];
            }
            // Without pin errors the first contact is the smallest head at every point.
            let best = smallest(head);
            for point in points {
                let j = point.index as usize;
                // 1. Involute stage.
                let (sx, cx) = point.crank; // planet frame at −z_p·Θ in the carrier
                let (ss, cs) = point.sun; // sun frame at (i − 1)·Θ in the carrier
                let gap = involute_constant + planet_cos * cx + planet_sin * sx
                    - (sun_cos * cs + sun_sin * ss);
                let involute = gap * involute_scale;
                // 2. Crank stage: disc displacement across the eccentric.
                let d_t = q_t + b_x * sx + b_y * cx;
                let crank = d_t * inverse_lever_base;
                // 3. Cycloid–pin stage: the smallest clearance ratio over the slots.
                let lag = if self.per_pin {
                    let pin = (pins - point.pin_shift) as usize;
                    smallest_ratio(
                        head,
                        radial,
                        tangential,
                        &pin_radial[pin..pin + width],
                        &pin_tangential[pin..pin + width],
                    )
                } else {
                    best
                };
                // 4. Output mechanism: n14 fixed in the housing, o turning with the output.
                let (so, co) = point.output;
                let output = out_x * so + out_y * co;
                sink(
                    j,
                    StageErrors {
                        involute,
                        crank,
                        cycloid: -lag,
                        output,
                    },
                );
            }
        }
    }

    /// [`ErrorModel::evaluate`] with an explicit work state: the curve, its peak-to-peak,
    /// rms and mean, and the amplitudes of orders 1, z_c and z_p.
    fn evaluate_with(&self, inputs: &[f64], search: &mut Search, outputs: &mut [f64]) {
        // The scans pass over a NaN ratio, so a non-finite input must not reach them.
        if inputs.iter().any(|v| !v.is_finite()) {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
            return;
        }
        let mut curve = std::mem::take(&mut search.curve);
        curve.resize(self.points, 0.0);
        self.fill_curve(inputs, search, &mut curve);
        // Four lanes (N is a multiple of 4), so that the passes vectorise.
        let n = curve.len() as f64;
        let quads = curve.as_chunks::<4>().0;
        let (mut lo, mut hi, mut sum) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4], [0.0; 4]);
        for quad in quads {
            for lane in 0..4 {
                let v = quad[lane];
                lo[lane] = if v < lo[lane] { v } else { lo[lane] };
                hi[lane] = if v > hi[lane] { v } else { hi[lane] };
                sum[lane] += v;
            }
        }
        let (lo, hi) = (
            lo.into_iter().fold(f64::INFINITY, f64::min),
            hi.into_iter().fold(f64::NEG_INFINITY, f64::max),
        );
        let sum = (sum[0] + sum[1]) + (sum[2] + sum[3]);
        let mean = sum / n;
        let mut squares = [0.0; 4];
        for quad in quads {
            for lane in 0..4 {
                squares[lane] += (quad[lane] - mean) * (quad[lane] - mean);
            }
        }
        let var = ((squares[0] + squares[1]) + (squares[2] + squares[3])) / n;
        // The split transform has the interleaved one's bits and vectorises.
        let (re, im) = (&mut search.fft_re, &mut search.fft_im);
        re.resize(self.points / 2, 0.0);
        im.resize(self.points / 2, 0.0);
        self.fft.transform_split(&curve, re, im);
        let [first, cycloid, pins] =
            [1, self.cycloid_teeth, self.pins].map(|k| self.fft.split_amplitude(re, im, k));
        outputs[..6].copy_from_slice(&[hi - lo, var.sqrt(), mean, first, cycloid, pins]);
        if !(hi - lo).is_finite() || !sum.is_finite() {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
        }
        search.curve = curve;
    }

    /// Fills `curve` (N values) with TE(Θ_j) in arcsec.
    #[inline(always)]
    fn fill_curve(&self, inputs: &[f64], search: &mut Search, curve: &mut [f64]) {
        self.trace_with(inputs, search, |j, stages| {
            curve[j] = stages.total() * ARCSEC_PER_RAD
        });
    }

    /// TE(Θ_j) in arcsec at Θ_j = 2πj/N, from the tables (the physical reading's curve
    /// also where its discs interfere).
    pub fn curve(&self, inputs: &[f64]) -> Vec<f64> {
        let mut curve = vec![0.0; self.points];
        if self.physical.is_some() {
            let terms = self.row_terms(inputs);
            SEARCH.with_borrow_mut(|search| {
                self.physical_curve(inputs, &terms, &mut search.two, &mut curve, None)
            });
            curve.iter_mut().for_each(|v| *v *= ARCSEC_PER_RAD);
        } else {
            SEARCH.with_borrow_mut(|search| self.fill_curve(inputs, search, &mut curve));
        }
        curve
    }

    /// The physical reading's TE at Θ_j = 2πj/n in arcsec, from the geometry pin by pin
    /// (no tables, any n; NaN where the discs interfere): the reference of the tabulated
    /// curve and of its order amplitudes. None for the document_002 reading.
    pub fn exact_curve(&self, inputs: &[f64], n: usize) -> Option<Vec<f64>> {
        self.physical.as_ref()?;
        Some(
            self.exact_curve_stages(inputs, n)
                .into_iter()
                .map(|(te, _)| te * ARCSEC_PER_RAD)
                .collect(),
        )
    }

    /// Whether the model follows the physical reading (two discs).
    pub fn is_physical(&self) -> bool {
        self.physical.is_some()
    }

    /// Semi-amplitudes of orders 0..N/2 of a curve (order 0: the mean), arcsec.
    pub fn spectrum(&self, curve: &[f64]) -> Vec<f64> {
        let mut work = vec![(0.0, 0.0); self.points / 2];
        self.fft.transform(curve, &mut work);
        let mut amplitudes: Vec<f64> = (0..=self.points / 2)
            .map(|k| self.fft.amplitude(&work, k))
            .collect();
        amplitudes[0] = self.fft.bin(&work, 0).0 / self.points as f64;
        amplitudes
    }
}

/// The inputs and outputs of document 002's literal reading (one disc).
fn literal_specs(
    cranks: usize,
    pins: usize,
    cycloid_teeth: usize,
    per_pin: bool,
    per_tooth: bool,
) -> (Vec<InputSpec>, Vec<OutputSpec>) {
    let mut inputs: Vec<InputSpec> = FIXED_INPUTS
        .iter()
        .map(|(name, description)| InputSpec {
            name: name.to_string(),
            unit: "mm".into(),
            description,
        })
        .collect();
    for k in 1..=cranks {
        for (name, description) in CRANK_INPUTS {
            inputs.push(InputSpec {
                name: format!("{name}_{k}"),
                unit: "mm".into(),
                description,
            });
        }
    }
    if per_pin {
        for i in 1..=pins {
            inputs.push(InputSpec {
                name: format!("pin_radial_error_mm_{i}"),
                unit: "mm".into(),
                description: "radial position error of pin i (outward), housing frame",
            });
        }
        for i in 1..=pins {
            inputs.push(InputSpec {
                name: format!("pin_tangential_error_mm_{i}"),
                unit: "mm".into(),
                description: "tangential position error of pin i, housing frame",
            });
        }
    }
    if per_tooth {
        for j in 1..=cycloid_teeth {
            inputs.push(InputSpec { name: format!("tooth_profile_error_mm_{j}"), unit: "mm".into(), description: "normal profile error of tooth space j of the disc, disc frame (positive: clearance)" });
        }
    }
    let output = |name: String, description: &'static str| OutputSpec {
        name,
        unit: "arcsec".into(),
        description,
        kind: OutputKind::Continuous,
        condition: None,
    };
    let outputs = vec![
        output(
            "te_peak_to_peak_arcsec".into(),
            "peak-to-peak transmission error over one output revolution",
        ),
        output(
            "te_rms_arcsec".into(),
            "rms of the transmission error about its mean",
        ),
        output(
            "te_mean_arcsec".into(),
            "mean of the transmission error (a constant angular offset; negative: the output lags)",
        ),
        output(
            "te_order_1_arcsec".into(),
            "FFT semi-amplitude of order 1 (once per output revolution)",
        ),
        output(
            format!("te_order_{cycloid_teeth}_arcsec"),
            "FFT semi-amplitude of order z_c (pin-borne errors)",
        ),
        output(
            format!("te_order_{pins}_arcsec"),
            "FFT semi-amplitude of order z_p (crank- and disc-borne errors)",
        ),
    ];
    (inputs, outputs)
}

impl ErrorModel for TransmissionError {
    fn name(&self) -> &'static str {
        "transmission_error"
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]) {
        SEARCH.with_borrow_mut(|search| {
            if self.physical.is_some() {
                let Search {
                    curve, two, loaded, ..
                } = search;
                if let Some(terms) = self.evaluate_physical(inputs, curve, two, outputs) {
                    self.evaluate_loaded(inputs, &terms, loaded, curve, outputs);
                }
            } else {
                self.evaluate_with(inputs, search, outputs)
            }
        })
    }

    fn curves(&self, inputs: &[f64]) -> Vec<Curve> {
        if self.physical.is_some() {
            return self.physical_curves(inputs);
        }
        let n = self.points;
        let mut stages = vec![StageErrors::default(); n];
        self.trace(inputs, |j, s| stages[j] = s);
        let degrees = |j: usize| 360.0 * j as f64 / n as f64;
        let series = |label: &str, pick: fn(&StageErrors) -> f64| Series {
            label: label.into(),
            points: stages
                .iter()
                .enumerate()
                .map(|(j, s)| (degrees(j), pick(s) * ARCSEC_PER_RAD))
                .collect(),
        };
        let total: Vec<f64> = stages.iter().map(|s| s.total() * ARCSEC_PER_RAD).collect();
        let spectrum = self.spectrum(&total);
        vec![
            Curve {
                name: "transmission_error".into(),
                title: "Transmission error over one output revolution".into(),
                x_label: "output angle (deg)".into(),
                y_label: "transmission error (arcsec)".into(),
                style: CurveStyle::Lines,
                series: vec![
                    series("total", |s| s.total()),
                    series("involute stage", |s| s.involute),
                    series("crank stage", |s| s.crank),
                    series("cycloid–pin stage", |s| s.cycloid),
                    series("output mechanism", |s| s.output),
                ],
            },
            Curve {
                name: "transmission_error_spectrum".into(),
                title: "Order spectrum of the transmission error".into(),
                x_label: "order (cycles per output revolution)".into(),
                y_label: "semi-amplitude (arcsec)".into(),
                style: CurveStyle::LogStems,
                series: vec![Series {
                    label: "FFT".into(),
                    points: spectrum
                        .iter()
                        .enumerate()
                        .skip(1)
                        .map(|(k, &a)| (k as f64, a))
                        .collect(),
                }],
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::{outputs, row, with, MODIFIED};
    use super::*;
    use crate::ParamValue;

    /// The tests of this module check document 002's literal reading; the physical
    /// reading's are in `two_discs`.
    fn rv40e_params() -> ModelParams {
        super::rv40e_params().with("reading", ParamValue::Text("document_002".into()))
    }

    fn rv40e() -> TransmissionError {
        TransmissionError::from_params(&rv40e_params()).unwrap()
    }

    /// 5 µm, the error size of 002 Table 2.
    const DELTA: f64 = 0.005;

    #[test]
    fn ratio_and_feedback_divisor() {
        let model = rv40e();
        // validation.md 002: 121 = 1 + (27/9)·40; the feedback divisor 121/3.
        assert_eq!(model.ratio(), 121.0);
        assert!((model.crank_divisor() - 121.0 / 3.0).abs() < 1e-12);
        let plain = with(rv40e_params().with_number("carrier_feedback", 0.0));
        assert_eq!(plain.crank_divisor(), 40.0);
    }

    #[test]
    fn perfect_reducer_has_no_error() {
        let model = rv40e();
        let curve = model.curve(&row(&model, &[]));
        assert!(curve.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn a_non_finite_input_gives_nan_outputs() {
        // One tooth space's error NaN: the scans would pass over its ratios and report a
        // finite, wrong curve; the outputs must be NaN so the engine counts the sample.
        let model = with(rv40e_params().with_number("tooth_profile_errors", 1.0));
        let mut row = row(&model, &[("equidistant_modification_mm", 0.01)]);
        let mut outputs = vec![0.0; 6];
        model.evaluate(&row, &mut outputs);
        assert!(outputs.iter().all(|v| v.is_finite()));
        let tooth = model.input_index("tooth_profile_error_mm_7").unwrap();
        row[tooth] = f64::NAN;
        model.evaluate(&row, &mut outputs);
        assert!(outputs.iter().all(|v| v.is_nan()), "{outputs:?}");
    }

    #[test]
    fn output_pin_circle_lever_is_delta_over_r6_at_order_1() {
        // validation.md 002: δ/r6 = 38.197″ for 5 µm (semi-amplitude, order 1).
        let model = rv40e();
        let lever = DELTA / 27.0 * ARCSEC_PER_RAD;
        assert!((lever - 38.197).abs() < 5e-4);
        let out = outputs(&model, &row(&model, &[("output_runout_x_mm", DELTA)]));
        assert!((out[3] - lever).abs() < 1e-9, "{}", out[3]);
        assert!((out[0] - 2.0 * lever).abs() < 1e-9);
        assert!(out[4] < 1e-9 && out[5] < 1e-9);
        assert!((out[1] - lever / 2f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn profile_normal_error_lever_is_delta_over_a_zc() {
        // validation.md 002: δ/(a·z_c) = 21.155″ for 5 µm. The disc turns until the pin
        // with the largest lever touches; max l_i ≤ a·z_c, reached to within the pin
        // spacing, so |TE| lies in [21.155, 21.155/0.995] and its mean lag is 21.155 to
        // within 0.3 %.
        let model = rv40e();
        let lever = DELTA / (1.25 * 39.0) * ARCSEC_PER_RAD;
        assert!((lever - 21.155).abs() < 5e-4);
        let curve = model.curve(&row(&model, &[("profile_normal_error_mm", DELTA)]));
        for v in &curve {
            assert!(*v <= -lever * (1.0 - 1e-12) && *v >= -lever / 0.995, "{v}");
        }
        let mean = curve.iter().sum::<f64>() / curve.len() as f64;
        assert!((mean / -lever - 1.0).abs() < 3e-3, "{mean}");
    }

    #[test]
    fn crank_phase_error_lever_is_delta_over_a_zc() {
        // validation.md 002: the crank-stage lever δ/(a·z_c) = 21.155″ (002's Δθ2 divided
        // by the cycloid ratio), halved when one of the two cranks is in error (10.6″).
        let model = rv40e();
        let lever = DELTA / (1.25 * 39.0) * ARCSEC_PER_RAD;
        let both = model.curve(&row(
            &model,
            &[
                ("crank_phase_error_mm_1", DELTA),
                ("crank_phase_error_mm_2", DELTA),
            ],
        ));
        assert!(both.iter().all(|v| (v - lever).abs() < 1e-9));
        let one = model.curve(&row(&model, &[("crank_phase_error_mm_1", DELTA)]));
        assert!(one.iter().all(|v| (v - lever / 2.0).abs() < 1e-9));
        assert!((lever / 2.0 - 10.578).abs() < 1e-3);
    }

    #[test]
    fn involute_centre_distance_lever_with_and_without_feedback() {
        // validation.md 002: δ·tan α/(r2·z_p) = 0.348″ for 5 µm (r2 = 27 mm, module 2);
        // the carrier feedback divides by 121/3 instead of 40.
        let set = [
            ("center_distance_error_mm_1", DELTA),
            ("center_distance_error_mm_2", DELTA),
        ];
        let plain = with(rv40e_params().with_number("carrier_feedback", 0.0));
        let lever = DELTA * 20f64.to_radians().tan() / (27.0 * 40.0) * ARCSEC_PER_RAD;
        assert!((lever - 0.348).abs() < 5e-4, "{lever}");
        let without = plain.curve(&row(&plain, &set));
        assert!(without.iter().all(|v| (v + lever).abs() < 1e-12));
        let model = rv40e();
        let with_feedback = model.curve(&row(&model, &set));
        assert!(with_feedback
            .iter()
            .all(|v| (v + lever * 120.0 / 121.0).abs() < 1e-12));
    }

    /// Largest semi-amplitude at an order that is not a multiple of `order`, below 400.
    /// The first contact switches pins abruptly, so the curve's harmonics fall off slowly
    /// and the high ones alias (the mesh order's second harmonic 3120 at 976, order
    /// 39·100 at 196): a few tenths of a percent of the fundamental, hence the 1 % bound.
    fn largest_off_harmonic(spectrum: &[f64], order: usize) -> f64 {
        (1..400)
            .filter(|k| k % order != 0)
            .map(|k| spectrum[k])
            .fold(0.0, f64::max)
    }

    #[test]
    fn pin_errors_appear_at_order_39_disc_errors_at_40() {
        // validation.md 002: pin-borne errors at z_c = 39 per revolution (the eccentric
        // passes a housing-fixed pin 39 times), disc- and crank-borne at z_p = 40.
        let params = rv40e_params()
            .with_number("pin_position_errors", 1.0)
            .with_number("tooth_profile_errors", 1.0);
        let model = with(params);
        let mut set = MODIFIED.to_vec();
        set.push(("pin_radial_error_mm_1", -0.004));
        let spectrum = model.spectrum(&model.curve(&row(&model, &set)));
        assert!(spectrum[39] > 0.05, "{}", spectrum[39]);
        assert!(largest_off_harmonic(&spectrum, 39) < 1e-2 * spectrum[39]);
        let mut set = MODIFIED.to_vec();
        set.push(("tooth_profile_error_mm_7", -0.004));
        let spectrum = model.spectrum(&model.curve(&row(&model, &set)));
        assert!(spectrum[40] > 0.05, "{}", spectrum[40]);
        assert!(largest_off_harmonic(&spectrum, 40) < 1e-2 * spectrum[40]);
        // A crank-bore error of one crank turns against the eccentric: order 40.
        let mut set = MODIFIED.to_vec();
        set.push(("crank_axis_radial_error_mm_1", DELTA));
        let spectrum = model.spectrum(&model.curve(&row(&model, &set)));
        let peak = (1..spectrum.len())
            .max_by(|a, b| spectrum[*a].total_cmp(&spectrum[*b]))
            .unwrap();
        assert_eq!(peak, 40);
    }

    #[test]
    fn table_2_ordering_of_four_5_micron_errors() {
        // 002 Table 2, used for its ordering only (validation.md): output mechanism >
        // cycloid profile > crank eccentricity (one of two cranks) > involute stage, by the
        // largest change of the curve over a revolution, with 003-style modification.
        let model = rv40e();
        let base = model.curve(&row(&model, &MODIFIED));
        let effect = |name: &str| {
            let mut set = MODIFIED.to_vec();
            set.push((name, DELTA));
            let curve = model.curve(&row(&model, &set));
            curve
                .iter()
                .zip(&base)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        let output = effect("output_runout_x_mm");
        let profile = effect("profile_normal_error_mm");
        let crank = effect("crank_axis_radial_error_mm_1");
        let involute = effect("center_distance_error_mm_1");
        assert!(
            output > profile && profile > crank && crank > involute,
            "{output} {profile} {crank} {involute}"
        );
    }

    #[test]
    fn table_driven_first_contact_equals_direct_geometry() {
        // RV-40E's 40 pins, and the smallest reducer accepted (3 pins), whose slot table
        // (rounded up to 4 slots) is wider than its pin count.
        first_contact_equals_direct_geometry(40);
        first_contact_equals_direct_geometry(3);
    }

    /// The cycloid–pin stage recomputed from scratch at every point: pin angles from Θ,
    /// the 003 factors, the tooth space from the pin's polar angle about the disc centre,
    /// and the minimum of g/l over the pins with a positive lever.
    fn first_contact_equals_direct_geometry(zp: usize) {
        let zc = zp - 1;
        let model = with(
            rv40e_params()
                .with_number("pin_count", zp as f64)
                .with_number("cycloid_teeth", zc as f64)
                .with_number("pin_position_errors", 1.0)
                .with_number("tooth_profile_errors", 1.0),
        );
        let (rp, e) = (64.0, 1.25);
        let k1 = e * zp as f64 / rp;
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let n = model.inputs().len();
        let mut row = vec![0.0; n];
        let pin_base = FIXED_INPUTS.len() + 2 * CRANK_INPUTS.len();
        for v in &mut row[pin_base..] {
            *v = 0.006 * next();
        }
        let (d_rp, d_p, profile, err_rp, err_rrp, q_r) =
            (0.011, -0.007, 0.001, 0.002, -0.001, 0.002);
        row[2..7].copy_from_slice(&[d_rp, d_p, profile, err_rp, err_rrp]);
        row[FIXED_INPUTS.len() + 3] = q_r; // both cranks' eccentric magnitude
        row[FIXED_INPUTS.len() + 7 + 3] = q_r;
        // Crank bores (carrier frame): crank 1 at β = 0 radial 3 µm, crank 2 at β = π radial
        // 1 µm and tangential 2 µm: the mean bore error is b = (1, −1) µm, and the disc moves
        // along the eccentric by d_r = q_r + b_x·cos(z_p·Θ) − b_y·sin(z_p·Θ).
        row[FIXED_INPUTS.len() + 5] = 0.003;
        row[FIXED_INPUTS.len() + 7 + 5] = 0.001;
        row[FIXED_INPUTS.len() + 7 + 6] = 0.002;
        let (b_x, b_y) = (0.001, -0.001);
        let mut traced = vec![0.0; 4096];
        model.trace(&row, |j, s| traced[j] = s.cycloid);
        for (j, &traced) in traced.iter().enumerate() {
            let theta = 2.0 * PI * j as f64 / 4096.0;
            let d_r = q_r + b_x * (zp as f64 * theta).cos() - b_y * (zp as f64 * theta).sin();
            let mut lag = f64::INFINITY;
            for i in 0..zp {
                let phi =
                    (2.0 * PI * i as f64 / zp as f64 + zc as f64 * theta).rem_euclid(2.0 * PI);
                let (sin, cos) = phi.sin_cos();
                if sin <= 1e-9 {
                    continue;
                }
                let root = (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
                let lever = e * zc as f64 * sin / root;
                let polar = (rp * sin).atan2(rp * cos - e);
                let space = ((zc as f64 * (polar - zp as f64 * theta) / (2.0 * PI)).round() as i64)
                    .rem_euclid(zc as i64) as usize;
                let g = d_rp * (1.0 - sin / root)
                    - d_p * (1.0 - k1 * cos - (1.0 - k1 * k1).sqrt() * sin) / root
                    + d_r * (k1 - cos) / root
                    + (err_rp + row[pin_base + i]) * (1.0 - k1 * cos) / root
                    + row[pin_base + zp + i] * k1 * sin / root
                    + profile
                    - err_rrp
                    + row[pin_base + 2 * zp + space];
                lag = lag.min(g / lever);
            }
            assert!(
                (traced + lag).abs() < 1e-9 * lag.abs().max(1e-6),
                "{zp} pins, point {j}: {} vs {}",
                traced,
                -lag
            );
        }
    }

    #[test]
    fn bad_parameters_name_their_key() {
        let fails = |params: ModelParams, key: &str| {
            let error = TransmissionError::from_params(&params).unwrap_err();
            assert_eq!(error.key, key, "{error:?}");
        };
        fails(
            rv40e_params().with_number("cycloid_teeth", 40.0),
            "cycloid_teeth",
        );
        fails(
            rv40e_params().with_number("eccentricity_mm", 1.7),
            "eccentricity_mm",
        );
        fails(
            rv40e_params().with_number("points_per_revolution", 2048.0),
            "points_per_revolution",
        );
        fails(
            rv40e_params().with_number("points_per_revolution", 5000.0),
            "points_per_revolution",
        );
        fails(
            rv40e_params().with_number("output_pin_circle_radius_mm", 0.0),
            "output_pin_circle_radius_mm",
        );
        fails(
            rv40e_params().with_number("carrier_feedback", 2.0),
            "carrier_feedback",
        );
    }
}
