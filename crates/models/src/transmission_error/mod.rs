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
//! - `"document_002"` (module `literal`): 002 read literally: one disc, the cranks
//!   averaged, 002's δ41 at r6, disc-side errors 1:1. It reproduces the one-disc model
//!   figure for figure (tests/transmission_error.rs).
//!
//! This module is the model's shell: [`TransmissionError`] holds what every reading
//! shares ([`Common`], module `common`) and the reading the parameters ask for
//! ([`ReadingModel`]), each reading's data its own type with its own code; the model's
//! methods and [`ErrorModel`] dispatch on the reading. The per-thread work state
//! ([`Search`]) holds one part per reading.

use rvtol_deviation::Shown;
use std::cell::RefCell;

use crate::cycloid::CycloidStage;
use crate::preload;
use crate::spectrum::RealFft;
use crate::stiffness::build;
use crate::{
    concat_params, Curve, ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputSpec,
    ParamSpec, ARCSEC_PER_RAD,
};

mod common;
mod literal;
mod loaded;
mod setup;
#[cfg(test)]
mod test_support;
mod two_discs;

use common::{gcd, Common, MAX_CRANKS};
use literal::{Literal, LiteralScratch, StageErrors};
use loaded::{Loaded, LoadedScratch};
use setup::Reading;
use two_discs::{Physical, TwoDiscScratch, UnderLoad};

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

/// The transmission-error model: what every reading shares, and the reading.
#[derive(Debug, Clone)]
pub struct TransmissionError {
    /// The geometry, the curve's points, the FFT, the inputs and outputs.
    common: Common,
    /// The reading the parameters ask for, with its data.
    reading: ReadingModel,
}

/// The reading of the model (docs/models.md §12), each with its own data.
#[derive(Debug, Clone)]
enum ReadingModel {
    /// Document 002's literal reading (`reading` "document_002").
    Literal(Literal),
    /// The physical reading with a rigid contact (`disc_contact` "first_contact" or
    /// "load_shared").
    Rigid(Box<Physical>),
    /// The physical reading under load (`disc_contact` "loaded", the default): the loaded
    /// solution, and the rigid reading whose tables flag interference and whose preload
    /// rule judges it.
    Loaded(Box<Physical>, Box<Loaded>),
}

/// Per-thread work state, one part per reading (no allocation per sample).
#[derive(Debug, Default)]
struct Search {
    /// The curve of the row (arcsec in the literal reading, rad in the physical ones).
    curve: Vec<f64>,
    /// The literal reading's work state.
    literal: LiteralScratch,
    /// The physical reading's.
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
            (Some(rule), Some((crank_radius, _, _))) if under_load => Some(loaded::build(
                params,
                &stage,
                rule,
                (cranks, crank_radius),
                (ratio, lambda),
                points,
            )?),
            _ => None,
        };
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let (inputs, outputs) = if literal {
            literal::specs(cranks, pins, cycloid_teeth, per_pin, per_tooth)
        } else {
            two_discs::specs(
                cranks,
                pins,
                cycloid_teeth,
                (per_pin, per_tooth),
                under_load,
            )
        };

        // The readings' phase tables: the fractional pin pitch of the eccentric at point j
        // takes N/gcd(z_c·z_p, N) values. A slot s has a positive lever while
        // 0 < s + f < z_p/2, a negative one while z_p/2 < s + f < z_p.
        let g = gcd(cycloid_mesh, points);
        let width = pins.div_ceil(2).next_multiple_of(4);
        let (curve_points, groups) = setup::curve_points(&stage, points, g, ratio);
        let alpha = alpha.to_radians();
        let divisor = if feedback {
            pins as f64 + sun_teeth / planet_teeth
        } else {
            pins as f64
        };
        let common = Common {
            sun_teeth,
            planet_teeth,
            pins,
            cycloid_teeth,
            eccentricity,
            cranks,
            points,
            base_radius: module * planet_teeth / 2.0 * alpha.cos(),
            pressure: alpha.sin_cos(),
            divisor,
            per_pin,
            per_tooth,
            curve_points,
            groups,
            fft: RealFft::new(points),
            inputs,
            outputs,
        };
        let reading = match (physical_geometry, preload_rule) {
            (Some((crank_radius, spacing, sun_offset)), Some(rule)) => {
                let physical = Box::new(two_discs::build(
                    &stage,
                    width,
                    g,
                    &common,
                    Physical::settings(
                        contact,
                        closure,
                        crank_radius,
                        spacing,
                        sun_offset,
                        cycloid_teeth as f64 / divisor,
                    ),
                    rule,
                ));
                match loaded {
                    Some(loaded) => ReadingModel::Loaded(physical, Box::new(loaded)),
                    None => ReadingModel::Rigid(physical),
                }
            }
            // 002's literal reading: no physical geometry, no preload rule.
            _ => ReadingModel::Literal(Literal::new(&stage, points, g, width, output_radius)),
        };
        TransmissionError { common, reading }.with_loaded_nominal()
    }

    /// Sets the loaded reading's nominal, the perfect reducer's mean angle at its torque.
    fn with_loaded_nominal(mut self) -> Result<Self, ModelError> {
        if let ReadingModel::Loaded(physical, loaded) = &mut self.reading {
            loaded
                .set_nominal(&self.common, physical)
                .map_err(|cause| {
                    ModelError::new(
                        "load_torque_nm",
                        format!("the perfect reducer has no loaded solution: {cause}"),
                    )
                })?;
        }
        Ok(self)
    }

    /// The physical reading's data (rigid or under load); None for document 002's literal
    /// reading.
    fn physical(&self) -> Option<&Physical> {
        match &self.reading {
            ReadingModel::Literal(_) => None,
            ReadingModel::Rigid(physical) | ReadingModel::Loaded(physical, _) => Some(physical),
        }
    }

    /// Overall ratio i = 1 + (z_pl/z_s)·z_p (validation.md 002: 121 for the RV40E).
    pub fn ratio(&self) -> f64 {
        self.common.ratio()
    }

    /// Divisor from a crank rotation error to the output: z_p + z_s/z_pl with the carrier
    /// feedback (121/3 for the RV40E), z_p without.
    pub fn crank_divisor(&self) -> f64 {
        self.common.divisor
    }

    /// Points of the curve per output revolution.
    pub fn points(&self) -> usize {
        self.common.points
    }

    /// Index of a named input.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.common.inputs.iter().position(|i| i.name == name)
    }

    /// Calls `sink(j, stages)` for every point j of the curve (stage errors in rad): 002's
    /// literal reading (the physical reading's stage parts are in its curves).
    ///
    /// # Panics
    ///
    /// On a model of the physical reading.
    pub fn trace(&self, inputs: &[f64], sink: impl FnMut(usize, StageErrors)) {
        let ReadingModel::Literal(literal) = &self.reading else {
            panic!("trace is document 002's literal reading's (the physical reading's stage parts are in its curves)");
        };
        SEARCH.with_borrow_mut(|search| {
            literal.trace_with(&self.common, inputs, &mut search.literal, sink)
        })
    }

    /// TE(Θ_j) in arcsec at Θ_j = 2πj/N, from the tables (the physical reading's curve
    /// also where its discs interfere).
    pub fn curve(&self, inputs: &[f64]) -> Vec<f64> {
        let common = &self.common;
        let mut curve = vec![0.0; common.points];
        match &self.reading {
            ReadingModel::Literal(literal) => SEARCH.with_borrow_mut(|search| {
                literal.fill_curve(common, inputs, &mut search.literal, &mut curve)
            }),
            ReadingModel::Rigid(physical) | ReadingModel::Loaded(physical, _) => {
                let terms = physical.row_terms(common, inputs);
                SEARCH.with_borrow_mut(|search| {
                    physical.physical_curve(
                        common,
                        inputs,
                        &terms,
                        &mut search.two,
                        &mut curve,
                        None,
                    )
                });
                curve.iter_mut().for_each(|v| *v *= ARCSEC_PER_RAD);
            }
        }
        curve
    }

    /// The physical reading's TE at Θ_j = 2πj/n in arcsec, from the geometry pin by pin
    /// (no tables, any n; NaN where the discs interfere): the reference of the tabulated
    /// curve and of its order amplitudes. None for the document_002 reading.
    pub fn exact_curve(&self, inputs: &[f64], n: usize) -> Option<Vec<f64>> {
        let physical = self.physical()?;
        Some(
            physical
                .exact_curve_stages(&self.common, inputs, n)
                .into_iter()
                .map(|(te, _)| te * ARCSEC_PER_RAD)
                .collect(),
        )
    }

    /// Both discs' windows [lower, upper] at the output angle Θ (rad), from the whole
    /// geometry pin by pin: [κ·(C_d − K_d), κ·(C_d + L_d)], the lower end set by the pins
    /// with l < 0 (forward drive), the upper by those with l > 0, the angle measured from
    /// the disc turned into contact on the l < 0 flank (`rv_lost_motion` measures it from
    /// 003's reference, 2κ·δ* lower). None for 002's literal one-disc reading.
    pub fn disc_windows(&self, inputs: &[f64], theta: f64) -> Option<[(f64, f64); 2]> {
        let physical = self.physical()?;
        let terms = physical.row_terms(&self.common, inputs);
        Some(physical.exact(&self.common, inputs, &terms, theta).windows)
    }

    /// Whether the model follows the physical reading (two discs).
    pub fn is_physical(&self) -> bool {
        self.physical().is_some()
    }

    /// T, the loaded reading's output torque, N·m (None outside the loaded reading).
    pub fn load_torque(&self) -> Option<f64> {
        match &self.reading {
            ReadingModel::Loaded(_, loaded) => Some(loaded.torque()),
            _ => None,
        }
    }

    /// The loaded transmission error of a row at the N points, arcsec (None outside the
    /// loaded reading, or where a point has no solution).
    pub fn loaded_curve_arcsec(&self, inputs: &[f64]) -> Option<Vec<f64>> {
        match &self.reading {
            ReadingModel::Loaded(physical, loaded) => {
                loaded.curve_arcsec(&self.common, physical, inputs)
            }
            _ => None,
        }
    }

    /// Semi-amplitudes of orders 0..N/2 of a curve (order 0: the mean), arcsec.
    pub fn spectrum(&self, curve: &[f64]) -> Vec<f64> {
        self.common.spectrum(curve)
    }
}

#[cfg(test)]
impl TransmissionError {
    /// The shared part and the physical reading's data, for the readings' tests.
    fn physical_parts(&self) -> (&Common, &Physical) {
        let physical = self.physical().expect("a model of the physical reading");
        (&self.common, physical)
    }

    /// The shared part, the physical reading's data and the loaded reading's, for its tests.
    fn loaded_parts(&self) -> (&Common, &Physical, &Loaded) {
        match &self.reading {
            ReadingModel::Loaded(physical, loaded) => (&self.common, physical, loaded),
            _ => panic!("a model of the loaded reading"),
        }
    }
}

impl ErrorModel for TransmissionError {
    fn name(&self) -> &'static str {
        "transmission_error"
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.common.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.common.outputs
    }

    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]) {
        let common = &self.common;
        SEARCH.with_borrow_mut(|search| {
            let Search {
                curve,
                literal: literal_scratch,
                two,
                loaded: loaded_scratch,
            } = search;
            match &self.reading {
                ReadingModel::Literal(literal) => {
                    literal.evaluate_with(common, inputs, curve, literal_scratch, outputs)
                }
                ReadingModel::Rigid(physical) => {
                    physical.evaluate_physical(common, inputs, curve, two, outputs, false);
                }
                ReadingModel::Loaded(physical, loaded) => {
                    let under_load = true;
                    if let Some(terms) =
                        physical.evaluate_physical(common, inputs, curve, two, outputs, under_load)
                    {
                        loaded.evaluate(
                            common,
                            physical,
                            inputs,
                            &terms,
                            loaded_scratch,
                            curve,
                            outputs,
                        );
                    }
                }
            }
        })
    }

    fn curves(&self, inputs: &[f64]) -> Vec<Curve> {
        let common = &self.common;
        match &self.reading {
            ReadingModel::Literal(literal) => {
                SEARCH.with_borrow_mut(|search| literal.curves(common, inputs, &mut search.literal))
            }
            ReadingModel::Rigid(physical) => physical.curves(common, inputs, None),
            ReadingModel::Loaded(physical, loaded) => {
                // The detail and the spectrum under load too, from the loaded solution at
                // their own 2^16 points (the rigid first contact of a preloaded or
                // interfering assembly has none).
                let fine = loaded
                    .at_points(two_discs::SPECTRUM_POINTS)
                    .curve_arcsec(common, physical, inputs);
                let under_load =
                    loaded
                        .curve_arcsec(common, physical, inputs)
                        .map(|curve| UnderLoad {
                            torque: loaded.torque(),
                            curve,
                            fine,
                        });
                physical.curves(common, inputs, under_load)
            }
        }
    }
}
