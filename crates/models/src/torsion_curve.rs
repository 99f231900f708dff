//! `torsion_curve`: the hysteresis (torsion) curve of an RV reducer, output angle against
//! output torque with the input locked, from −rated to +rated and back, and the catalogue
//! figures read from it: lost motion, hysteresis loss, torsional rigidity. It combines the
//! geometric clearance of document 000 with the elastic deformation of documents 003 (pin
//! contact) and 004 (crank bearings); docs/models.md §13.
//!
//! Units: torque in N·m, angles in arcmin at the output (rad inside), lengths in mm.
//! Sign convention: a positive torque turns the output in the positive sense and the output
//! angle θ(T) has the sign of T (the output yields in the direction of the torque).
//!
//! ```text
//! clearance (000, the whole of geometric_hysteresis built from the same parameters):
//!   c = Δφ_Σ = max(0, Δφ12') + max(0, Δφ34) + max(0, Δφ56')              (000 Eq. 21)
//!
//! elastic lag under an output torque T ≥ 0, two series compliances:
//!   E(T) = [β(T) − β_fc] + arctan(T_disc/(2·k·a²)),   T_disc = share·T          (rad)
//!   β(T)  disc rotation of the load sharing of 003 (secant Palmgren stiffness of the most
//!         loaded pin, Σ F_i·l_i = T_disc; cycloid_pin_contact), rad
//!   β_fc  rotation at which the driving flank first touches, min over l_i > 0 of Δ_i/l_i
//!   arctan(T_disc/(2·k·a²))  004's four-bar lag with equal stiffness k on both cranks,
//!         a = crank circle radius (half the distance of the two crank axes)
//!
//! frictionless reading of the curve:
//!   θ(T) = sign(T)·(c/2 + E(|T|)) on both branches; at T = 0 the output crosses the
//!   clearance c at zero torque (a vertical segment of height c).
//!   hysteresis loss    = width of the loop at T = 0                   = c
//!   lost motion        = midline θ(+3 % rated) − midline θ(−3 % rated) = c + 2·E(0.03·T_r)
//!   torsional rigidity = (T_r − T_r/2)/(E(T_r) − E(T_r/2))   (catalogue: 50 % to 100 %)
//!   angle at rated     = c/2 + E(T_r)
//! ```
//!
//! Readings (docs/models.md §13):
//! - The free play is 000's c only. β of the contact model is measured from the reference
//!   of its clearance form (the disc turned to first contact in the continuous limit) and
//!   moves with the manufacturing errors it is fed (a pin radius error δr_rp alone shifts
//!   the first contact by δr_rp/l): that rigid take-up is free play that 000 already counts
//!   (its modification and δ-terms), so E is measured from the first contact β_fc. E(0) = 0,
//!   E is continuous at 0+ and increasing; the progressive take-up of the other pins'
//!   modification clearances as more pins engage stays in E (the soft start of the curve).
//! - The load sharing takes its own modification inputs (`contact_*`): 000's design
//!   modification (Δr_rp = −0.010, Δr_p = −0.012 mm) enters c through 000's printed Eq. 16,
//!   and in 003's clearance form the same numbers overlap the reverse flank by 2.7 µm (a
//!   preloaded stage, 000's Eq. 13–15 reading gives −0.33 arcmin; docs/models.md §2.3),
//!   so they cannot describe the load sharing. The manufacturing errors δr_p, δr_rp and δe
//!   are shared: 000's inputs feed both.
//! - Friction (a friction torque in the pins, bearings and seals) would separate the
//!   loading and unloading branches and widen the loop away from T = 0; it is not modelled.
//! - A row with a non-finite input, a non-finite clearance or k·(1 + x_k) ≤ 0 gives NaN
//!   outputs (the engine counts them).

use crate::crank_elastic_error::CrankElasticError;
use crate::cycloid_pin_contact::CycloidPinContact;
use crate::geometric_hysteresis::{self, GeometricHysteresis};
use crate::{
    Curve, CurveStyle, ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind,
    OutputSpec, ParamSpec, Series, ARCMIN_PER_RAD,
};

/// Inputs of 000 (`geometric_hysteresis`), in its order, come first.
const HYSTERESIS_INPUTS: usize = 18;
/// Positions of the shared manufacturing errors among 000's inputs.
const PIN_CIRCLE_RADIUS_ERROR: usize = 4;
const PIN_RADIUS_ERROR: usize = 5;
const ECCENTRICITY_ERROR: usize = 12;

/// The inputs after 000's, in order.
const OWN_INPUTS: [(&str, &str, &str); 3] = [
    (
        "contact_equidistant_modification_mm",
        "mm",
        "Δr_rp of the load sharing (003's clearance form, positive: clearance); shapes E only",
    ),
    (
        "contact_shift_modification_mm",
        "mm",
        "Δr_p of the load sharing (003's clearance form, negative: clearance); shapes E only",
    ),
    (
        "crank_bearing_stiffness_error",
        "1",
        "x_k, relative error of the crank bearing stiffness, both cranks: k·(1 + x_k)",
    ),
];

/// The outputs, in order.
const OUTPUTS: [(&str, &str, &str); 5] = [
    (
        "lost_motion_arcmin",
        "arcmin",
        "midline angle at +3 % minus −3 % rated torque: c + 2·E(0.03·T_r)",
    ),
    (
        "hysteresis_loss_arcmin",
        "arcmin",
        "width of the loop at zero torque; frictionless: the clearance c",
    ),
    (
        "torsional_rigidity_nm_per_arcmin",
        "N·m/arcmin",
        "(T_r − T_r/2)/(E(T_r) − E(T_r/2)), slope between 50 % and 100 % rated",
    ),
    (
        "clearance_arcmin",
        "arcmin",
        "c, geometric lost motion of 000 (geometric_hysteresis's hysteresis_arcmin)",
    ),
    (
        "angle_at_rated_arcmin",
        "arcmin",
        "output angle at rated torque: c/2 + E(T_r)",
    ),
];

const PARAMS: &[ParamSpec] = &[
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
        description: "K1 of 000's Eq. 16, 17 only; default e·Zp/rp (000 Table 8 prints 0.72); the load sharing uses e·Zp/rp",
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
        description: "a0, sun–planet centre distance, the lever of 000 Eq. 18, 20 (000 Table 8: 27.5)",
        default: None,
    },
    ParamSpec {
        name: "sun_pitch_radius_mm",
        unit: "mm",
        description: "r1, sun pitch radius (000 Table 8: 13.5)",
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
        description: "contact length of one cycloid disc (not in 000; RV-20E assumed 8)",
        default: None,
    },
    ParamSpec {
        name: "disc_load_share",
        unit: "1",
        description: "share of the output torque carried by one disc (two discs: 0.5)",
        default: Some(0.5),
    },
    ParamSpec {
        name: "crank_circle_radius_mm",
        unit: "mm",
        description: "a, crank axes from the reducer axis = half their distance (two cranks); default center_distance_mm, 000's own lever of the crank bearing",
        default: None,
    },
    ParamSpec {
        name: "crank_bearing_stiffness_n_per_mm",
        unit: "N/mm",
        description: "k, radial stiffness between one crank eccentric and one disc (004; not in 000, RV-20E assumed 2e5)",
        default: None,
    },
    ParamSpec {
        name: "rated_torque_nm",
        unit: "N·m",
        description: "T_r, rated output torque (RV-20E catalogue: 167)",
        default: None,
    },
];

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "torsion_curve",
    summary: "hysteresis (torsion) curve, input locked: 000 clearance + 003 pin-contact and 004 crank-bearing compliance; lost motion at ±3 % rated, hysteresis loss, torsional rigidity 50-100 % rated (frictionless)",
    params: PARAMS,
    build: |params| Ok(Box::new(TorsionCurve::from_params(params)?)),
    example_params: TorsionCurve::rv20e_params,
};

/// Points per branch of the drawn curve, −rated..=+rated (the 0 point is drawn twice).
const CURVE_STEPS: usize = 100;

/// The torsion curve model with its three sub-models built from one parameter set.
#[derive(Debug, Clone)]
pub struct TorsionCurve {
    hysteresis: GeometricHysteresis,
    /// Load sharing of one disc, 2 cranks on the crank circle, no per-pin errors.
    contact: CycloidPinContact,
    rated_torque: f64,
    crank_circle_radius: f64,
    crank_stiffness: f64,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

impl TorsionCurve {
    /// The RV-20E: 000 Table 8 (K1 as printed, 0.72, for 000's terms; pin radius 2 mm),
    /// and what 000 does not give: disc face width 8 mm (assumed), two discs (share 0.5),
    /// crank circle radius = a0 = 27.5 mm (000's lever of the crank bearing, Eq. 18), crank
    /// bearing stiffness 2e5 N/mm (assumed), rated torque 167 N·m (RV-20E catalogue).
    pub fn rv20e_params() -> ModelParams {
        GeometricHysteresis::rv20e_params()
            .with_number("pin_radius_mm", 2.0)
            .with_number("disc_face_width_mm", 8.0)
            .with_number("disc_load_share", 0.5)
            .with_number("crank_circle_radius_mm", 27.5)
            .with_number("crank_bearing_stiffness_n_per_mm", 2.0e5)
            .with_number("rated_torque_nm", 167.0)
    }

    /// Builds the model: 000 and 003 from the same parameter set (their own checks name the
    /// keys), then its own parameters.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let hysteresis_keys: Vec<&str> = geometric_hysteresis::ENTRY
            .params
            .iter()
            .map(|p| p.name)
            .collect();
        let hysteresis = GeometricHysteresis::from_params(&params.subset(&hysteresis_keys))?;
        // 000 has checked center_distance_mm (present and positive).
        let center_distance = params.positive("center_distance_mm", None)?;
        let crank_circle_radius =
            params.positive("crank_circle_radius_mm", Some(center_distance))?;
        let contact = CycloidPinContact::of_two_crank_disc(params, crank_circle_radius)?;
        let crank_stiffness = params.positive("crank_bearing_stiffness_n_per_mm", None)?;
        let rated_torque = params.positive("rated_torque_nm", None)?;
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let inputs = hysteresis
            .inputs()
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
        Ok(TorsionCurve {
            hysteresis,
            contact,
            rated_torque,
            crank_circle_radius,
            crank_stiffness,
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

    /// Rated torque T_r, N·m.
    pub fn rated_torque(&self) -> f64 {
        self.rated_torque
    }

    /// Everything E needs from one input row: the contact row (torque first, then Δr_rp,
    /// Δr_p, δr_p, δr_rp, δe, face width error 0), the first-contact rotation β_fc (rad) and
    /// the crank bearing stiffness k·(1 + x_k) (N/mm); `None` when the row cannot be
    /// evaluated (non-finite value, k ≤ 0).
    fn elastic_state(&self, x: &[f64]) -> Option<ElasticState> {
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let own = &x[HYSTERESIS_INPUTS..];
        let stiffness = self.crank_stiffness * (1.0 + own[2]);
        if !(stiffness > 0.0 && stiffness.is_finite()) {
            return None;
        }
        let row = [
            0.0,
            own[0],
            own[1],
            x[PIN_CIRCLE_RADIUS_ERROR],
            x[PIN_RADIUS_ERROR],
            x[ECCENTRICITY_ERROR],
            0.0,
        ];
        let first_contact = self.contact.first_contact(&row);
        first_contact.is_finite().then_some(ElasticState {
            row,
            first_contact,
            stiffness,
        })
    }

    /// E(T) for T ≥ 0, arcmin: contact rotation from first contact + four-bar crank lag.
    fn elastic_lag(&self, state: &ElasticState, torque: f64) -> f64 {
        if torque <= 0.0 {
            return 0.0;
        }
        let mut row = state.row;
        row[0] = torque;
        let contact = self.contact.rotation(&row) - state.first_contact;
        let a = self.crank_circle_radius;
        // Equal stiffness on both cranks: the tangential forces sum to T_disc/a (004), so
        // the two holes deflect by T_disc/(a·k) in all.
        let disc_torque = self.contact.load_share() * torque * 1000.0; // N·mm
        let crank = CrankElasticError::four_bar_lag(disc_torque / (a * state.stiffness), a);
        (contact + crank) * ARCMIN_PER_RAD
    }

    /// The clearance c (arcmin) of 000 for one row.
    fn clearance(&self, x: &[f64]) -> f64 {
        let mut out = [0.0; geometric_hysteresis::OUTPUT_COUNT];
        self.hysteresis.evaluate(&x[..HYSTERESIS_INPUTS], &mut out);
        out[geometric_hysteresis::HYSTERESIS]
    }

    /// c and E(|T|) at the torques of the drawn curve, T_j = T_r·(j − 50)/50, j = 0..=100;
    /// `None` when the row cannot be evaluated.
    fn curve_values(&self, x: &[f64]) -> Option<(f64, Vec<f64>)> {
        let state = self.elastic_state(x)?;
        let c = self.clearance(x);
        let half = CURVE_STEPS / 2;
        // E at |T| = T_r·k/50, k = 0..=50.
        let lags: Vec<f64> = (0..=half)
            .map(|k| self.elastic_lag(&state, self.rated_torque * k as f64 / half as f64))
            .collect();
        (c.is_finite() && lags.iter().all(|e| e.is_finite())).then_some((c, lags))
    }
}

/// Per-row state of the elastic part (stack only).
#[derive(Debug, Clone, Copy)]
struct ElasticState {
    row: [f64; 7],
    first_contact: f64,
    stiffness: f64,
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
        let Some(state) = self.elastic_state(x) else {
            out.fill(f64::NAN);
            return;
        };
        let c = self.clearance(x);
        let rated = self.rated_torque;
        let at_3_percent = self.elastic_lag(&state, 0.03 * rated);
        let at_half = self.elastic_lag(&state, 0.5 * rated);
        let at_rated = self.elastic_lag(&state, rated);
        let values = [
            c + 2.0 * at_3_percent,
            c,
            (rated - 0.5 * rated) / (at_rated - at_half),
            c,
            0.5 * c + at_rated,
        ];
        if values.iter().all(|v| v.is_finite()) {
            out.copy_from_slice(&values);
        } else {
            out.fill(f64::NAN);
        }
    }

    fn curves(&self, x: &[f64]) -> Vec<Curve> {
        let half = CURVE_STEPS / 2;
        let rated = self.rated_torque;
        let (c, lags) = self
            .curve_values(x)
            .unwrap_or((f64::NAN, vec![f64::NAN; half + 1]));
        // θ(T_j) = sign(T)·(c/2 + E(|T|)), T_j = T_r·(j − 50)/50 (exact 0 and symmetry).
        let point = |j: usize| -> (f64, f64) {
            let torque = rated * (j as f64 - half as f64) / half as f64;
            let angle = if j > half {
                0.5 * c + lags[j - half]
            } else {
                -(0.5 * c + lags[half - j])
            };
            (torque, angle)
        };
        let mut loading = Vec::with_capacity(CURVE_STEPS + 2);
        for j in 0..=CURVE_STEPS {
            if j == half {
                // The clearance is crossed at zero torque, from −c/2 to +c/2.
                loading.push((0.0, -0.5 * c));
                loading.push((0.0, 0.5 * c));
            } else {
                loading.push(point(j));
            }
        }
        let mut unloading = Vec::with_capacity(CURVE_STEPS + 2);
        for j in (0..=CURVE_STEPS).rev() {
            if j == half {
                unloading.push((0.0, 0.5 * c));
                unloading.push((0.0, -0.5 * c));
            } else {
                unloading.push(point(j));
            }
        }
        vec![Curve {
            name: "torsion_curve".into(),
            title: "Hysteresis (torsion) curve, input locked (frictionless)".into(),
            x_label: "output torque (N·m)".into(),
            y_label: "output angle (arcmin)".into(),
            style: CurveStyle::Lines,
            series: vec![
                Series {
                    label: "loading (−rated → +rated)".into(),
                    points: loading,
                },
                Series {
                    label: "unloading (+rated → −rated)".into(),
                    points: unloading,
                },
            ],
        }]
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    fn rv20e() -> TorsionCurve {
        TorsionCurve::from_params(&TorsionCurve::rv20e_params()).unwrap()
    }

    fn with(key: &str, value: f64) -> Result<TorsionCurve, ModelError> {
        TorsionCurve::from_params(&TorsionCurve::rv20e_params().with_number(key, value))
    }

    /// 000 Table 9 design values (E_ws, E_wi, Δr_rp, Δr_p, Δu), every δ-term and the input
    /// shaft at zero (the nominal of geometric_hysteresis's tests), and the load-sharing
    /// modification of the shipped scenario (Δr_rp = 0.010, Δr_p = −0.008 mm, assumed).
    fn nominal() -> [f64; 21] {
        let mut x = [0.0; 21];
        x[0] = 0.0035;
        x[1] = -0.0309;
        x[2] = -0.010;
        x[3] = -0.012;
        x[13] = 0.002;
        x[18] = 0.010;
        x[19] = -0.008;
        x
    }

    fn eval(model: &TorsionCurve, x: &[f64]) -> [f64; 5] {
        let mut out = [0.0; 5];
        model.evaluate(x, &mut out);
        out
    }

    /// E(T) of the model for row x, arcmin.
    fn lag(model: &TorsionCurve, x: &[f64], torque: f64) -> f64 {
        model.elastic_lag(&model.elastic_state(x).unwrap(), torque)
    }

    /// 004's four-bar lag with equal stiffness, arctan(T_disc/(2k·a²)), in arcmin, for the
    /// RV-20E parameters (share 0.5, k = 2e5 N/mm, a = 27.5 mm).
    fn crank_lag(torque: f64) -> f64 {
        (0.5 * torque * 1000.0 / (2.0 * 2.0e5 * 27.5 * 27.5)).atan() * ARCMIN_PER_RAD
    }

    /// A row with the Table 9 manufacturing errors at a fraction of their limits (signs
    /// mixed) and an input shaft deviation.
    fn perturbed() -> [f64; 21] {
        let mut x = nominal();
        let deltas = [
            0.003, -0.001, 0.002, 0.004, 0.0, -0.005, 0.0004, -0.001, 0.002,
        ];
        x[4..13].copy_from_slice(&deltas);
        x[14] = 0.001;
        x[15] = -0.0005;
        x[16] = 1e-5;
        x[20] = 0.1;
        x
    }

    #[test]
    fn clearance_is_the_geometric_hysteresis_of_the_same_row() {
        let model = rv20e();
        let reference =
            GeometricHysteresis::from_params(&GeometricHysteresis::rv20e_params()).unwrap();
        for x in [nominal(), perturbed()] {
            let mut expected = [0.0; geometric_hysteresis::OUTPUT_COUNT];
            reference.evaluate(&x[..18], &mut expected);
            let out = eval(&model, &x);
            assert_eq!(out[3], expected[0]);
        }
        // 000 §5.2: Δφ_Σ = 0.5467 arcmin, ±1 % (validation.md); rvtol's reading 0.54823
        // (docs/models.md §2.2).
        let c = eval(&model, &nominal())[3];
        assert!((c - 0.5467).abs() < 0.01 * 0.5467, "{c}");
        assert!((c - 0.54823).abs() < 0.00005, "{c}");
    }

    #[test]
    fn elastic_lag_is_zero_at_zero_torque_and_increasing() {
        let model = rv20e();
        for x in [nominal(), perturbed()] {
            assert_eq!(lag(&model, &x, 0.0), 0.0);
            // Continuous at 0+: the take-up to first contact is not in E (module comment).
            // At 1e-6·T_r the crank part is 9.5e-7 arcmin (∝ T) and the contact part, ∝ F^0.9
            // on the first pin, 6.2e-6 arcmin on the nominal row; the first contact itself
            // moves by 0.39 arcmin for δr_rp = 0.004 mm (0.004/l), so E(0+) < 1e-4 arcmin
            // says it is not in E.
            let tiny = lag(&model, &x, 167e-6);
            assert!(tiny > 0.0 && tiny < 1e-4, "{tiny}");
            let mut previous = 0.0;
            for k in 1..=100 {
                let e = lag(&model, &x, 167.0 * k as f64 / 100.0);
                assert!(e > previous, "E not increasing at {k} %: {e} ≤ {previous}");
                previous = e;
            }
        }
    }

    #[test]
    fn outputs_follow_the_frictionless_reading() {
        let model = rv20e();
        for x in [nominal(), perturbed()] {
            let out = eval(&model, &x);
            let c = out[3];
            let (e3, e50, e100) = (
                lag(&model, &x, 0.03 * 167.0),
                lag(&model, &x, 0.5 * 167.0),
                lag(&model, &x, 167.0),
            );
            assert_eq!(out[0], c + 2.0 * e3);
            assert_eq!(out[1], c);
            assert_eq!(out[2], 83.5 / (e100 - e50));
            assert_eq!(out[4], 0.5 * c + e100);
            assert!(out.iter().all(|v| v.is_finite() && *v > 0.0));
        }
    }

    #[test]
    fn unmodified_contact_part_is_the_closed_form() {
        // Unmodified profile, no errors: every loaded pin has F_i = K·l_i·β, so
        // F_max = T_c·max l_i/Σ l_i² and β = δ(F_max)/max l_i with Palmgren's
        // δ(F) = 2·3.84e-5·F^0.9/L^0.8 (003's load sharing, docs/models.md §10), and
        // l_i = e·z_c·sin φ_i/S_i (validation.md 003) with K1 = e·z_p/r_p from Table 8.
        let model = rv20e();
        let mut x = nominal();
        (x[18], x[19]) = (0.0, 0.0);
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
        for torque in [5.01, 83.5, 167.0] {
            let t_c = 0.5 * torque * 1000.0;
            let f_max: f64 = t_c * l_max / sum_l2;
            let beta = 2.0 * 3.84e-5 * f_max.powf(0.9) / width.powf(0.8) / l_max;
            let contact = lag(&model, &x, torque) - crank_lag(torque);
            assert!(
                (contact / (beta * ARCMIN_PER_RAD) - 1.0).abs() < 1e-9,
                "{torque} N·m: {contact} vs {}",
                beta * ARCMIN_PER_RAD
            );
        }
    }

    #[test]
    fn contact_part_is_the_disc_rotation_from_first_contact() {
        // With the modification and errors: the contact part of E is 003's β from its
        // full solve minus min over loaded-side pins of Δ_i/l_i, and the solve carries the
        // disc torque (torque balance Σ F_i·l_i = T_disc).
        let model = rv20e();
        let x = perturbed();
        let row = [167.0, x[18], x[19], x[4], x[5], x[12], 0.0];
        let solution = model.contact.solve(&row);
        let moment: f64 = solution
            .forces
            .iter()
            .zip(&solution.levers)
            .map(|(f, l)| f * l)
            .sum();
        assert!((moment / 83_500.0 - 1.0).abs() < 1e-9, "{moment}");
        let first_contact = solution
            .levers
            .iter()
            .zip(&solution.clearances)
            .filter(|(l, _)| **l > 0.0)
            .map(|(l, c)| c / l)
            .fold(f64::INFINITY, f64::min);
        // k·(1 + 0.1) in the perturbed row.
        let crank = (83_500.0_f64 / (2.0 * 2.2e5 * 27.5 * 27.5)).atan();
        let expected = (solution.rotation - first_contact + crank) * ARCMIN_PER_RAD;
        assert!((lag(&model, &x, 167.0) - expected).abs() < 1e-12 * expected);
        // The errors move the first contact (δr_rp alone by δr_rp/l): it is not free play
        // counted twice.
        assert!(first_contact.abs() > 1e-6, "{first_contact}");
    }

    #[test]
    fn reference_crank_lag_is_the_four_bar_lag_of_004() {
        // The tests above check E's crank part against `crank_lag`, arctan(T_disc/(2k·a0²)).
        // That reference must be what 004's model gives on the same RV-20E geometry with
        // equal stiffness: the crank_elastic_error model's mean lag equals it.
        let params = ModelParams::new()
            .with_number("pin_count", 40.0)
            .with_number("cycloid_teeth", 39.0)
            .with_number("pin_circle_radius_mm", 52.0)
            .with_number("pin_radius_mm", 2.0)
            .with_number("eccentricity_mm", 0.9)
            .with_number("disc_face_width_mm", 8.0)
            .with_number("crank_center_distance_half_mm", 27.5)
            .with_number("planet_pitch_radius_mm", 31.5)
            .with_number("sun_teeth", 12.0)
            .with_number("planet_teeth", 42.0)
            .with_number("crank_bearing_stiffness_n_per_mm", 2.0e5)
            .with_number("crank_l1_mm", 10.0)
            .with_number("crank_l2_mm", 10.0)
            .with_number("crank_l3_mm", 10.0)
            .with_number("crank_l4_mm", 10.0);
        let crank_model = CrankElasticError::from_params(&params).unwrap();
        for torque in [5.01, 83.5, 167.0] {
            let mut out = [0.0; 5];
            crank_model.evaluate(&[torque, 0.01, -0.008, 0.0, 0.0, 0.0, 0.0, 0.0], &mut out);
            assert!((out[0] / crank_lag(torque) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn rigidity_is_the_slope_of_the_curve_between_50_and_100_percent() {
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
    fn curve_is_odd_symmetric_and_crosses_the_clearance_at_zero_torque() {
        let model = rv20e();
        let x = perturbed();
        let c = eval(&model, &x)[3];
        let curves = model.curves(&x);
        assert_eq!(curves.len(), 1);
        let curve = &curves[0];
        assert_eq!(curve.name, "torsion_curve");
        assert_eq!(curve.style, CurveStyle::Lines);
        let (loading, unloading) = (&curve.series[0].points, &curve.series[1].points);
        assert_eq!(loading.len(), 102);
        assert_eq!(unloading.len(), 102);
        assert_eq!(loading[0], (-167.0, loading[0].1));
        assert_eq!(loading[101].0, 167.0);
        assert_eq!(unloading[0].0, 167.0);
        // Odd symmetry: θ(−T) = −θ(T), and the unloading branch is the loading branch
        // traversed backwards (frictionless).
        for (i, &(t, theta)) in loading.iter().enumerate() {
            let (mt, mtheta) = loading[101 - i];
            assert_eq!((t, theta), (-mt, -mtheta));
            assert_eq!(unloading[101 - i], (t, theta));
        }
        // Monotone in T on each side, and the vertical crossing at T = 0 of height c.
        for w in loading.windows(2) {
            assert!(w[1].0 >= w[0].0 && w[1].1 > w[0].1, "{w:?}");
        }
        assert_eq!(loading[50], (0.0, -0.5 * c));
        assert_eq!(loading[51], (0.0, 0.5 * c));
        assert_eq!(unloading[50], (0.0, 0.5 * c));
        assert_eq!(unloading[51], (0.0, -0.5 * c));
        let width = loading[51].1 - loading[50].1;
        assert!((width - c).abs() < 1e-15);
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases = [
            ("rated_torque_nm", 0.0, "rated_torque_nm"),
            ("rated_torque_nm", -167.0, "rated_torque_nm"),
            (
                "crank_bearing_stiffness_n_per_mm",
                0.0,
                "crank_bearing_stiffness_n_per_mm",
            ),
            ("disc_face_width_mm", 0.0, "disc_face_width_mm"),
            ("pin_radius_mm", -2.0, "pin_radius_mm"),
            ("crank_circle_radius_mm", 0.0, "crank_circle_radius_mm"),
            ("disc_load_share", 1.5, "disc_load_share"),
            // 000 accepts 38 < 40; 003 needs z_c = z_p − 1.
            ("cycloid_teeth", 38.0, "cycloid_teeth"),
            // 000: pins must exceed the teeth.
            ("pin_count", 39.0, "pin_count"),
            ("curtate_ratio", 1.2, "curtate_ratio"),
            // 000 takes K1 as printed; 003 checks e·z_p/r_p = 1.4·40/52 = 1.08 < 1.
            ("eccentricity_mm", 1.4, "eccentricity_mm"),
            ("sun_pitch_radius_mm", 0.0, "sun_pitch_radius_mm"),
            ("crank_count", 3.0, "crank_count"),
        ];
        for (key, value, named) in cases {
            let err = with(key, value).unwrap_err();
            assert_eq!(err.key, named, "{key} = {value}: {err}");
        }
        assert!(with("crank_count", 3.0)
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
            "crank_bearing_stiffness_n_per_mm",
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
        // crank_circle_radius_mm defaults to center_distance_mm.
        let mut params = ModelParams::new();
        for spec in PARAMS.iter().filter(|p| p.name != "crank_circle_radius_mm") {
            if let Ok(v) = TorsionCurve::rv20e_params().number(spec.name, None) {
                params = params.with_number(spec.name, v);
            }
        }
        let defaulted = TorsionCurve::from_params(&params).unwrap();
        assert_eq!(defaulted.crank_circle_radius, 27.5);
    }

    #[test]
    fn rows_that_cannot_be_evaluated_give_nan() {
        let model = rv20e();
        let mut cases = Vec::new();
        for (index, value) in [
            (0, f64::NAN),
            (5, f64::INFINITY),
            (18, f64::NAN),
            (19, f64::NEG_INFINITY),
            (20, -1.0), // k = 0
            (20, -3.0),
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
        x[18] = 1e300;
        let out = eval(&model, &x);
        assert!(out.iter().all(|v| v.is_finite()) || out.iter().all(|v| v.is_nan()));
    }

    proptest::proptest! {
        #[test]
        fn rows_within_the_tolerances_give_ordered_finite_outputs(
            deltas in proptest::array::uniform9(-1.0f64..1.0),
            equidistant in 0.008f64..0.012,
            shift in -0.010f64..-0.006,
            stiffness_error in -0.15f64..0.15,
        ) {
            // Table 9 limits (000) for the δ-terms, the scenario's bands for the rest.
            let limits = [0.010, 0.004, 0.005, 0.015, 0.0, 0.019, 0.001, 0.003, 0.005];
            let mut x = nominal();
            for (i, (d, l)) in deltas.iter().zip(limits).enumerate() {
                x[4 + i] = d * l;
            }
            (x[18], x[19], x[20]) = (equidistant, shift, stiffness_error);
            let model = rv20e();
            let out = eval(&model, &x);
            proptest::prop_assert!(out.iter().all(|v| v.is_finite()), "{:?}", out);
            let c = out[3];
            proptest::prop_assert!(c >= 0.0);
            proptest::prop_assert!(out[0] > c && out[4] > 0.5 * c && out[2] > 0.0);
            // E(3 %) < E(50 %) < E(100 %): the midline at 3 % lies below the rated angle.
            proptest::prop_assert!(out[0] - c < 2.0 * (out[4] - 0.5 * c));
        }
    }

    #[test]
    fn registry_example_builds() {
        let entry = crate::find("torsion_curve").unwrap();
        let model = (entry.build)(&(entry.example_params)()).unwrap();
        assert_eq!(model.inputs().len(), 21);
        assert_eq!(model.outputs().len(), 5);
        assert_eq!(model.inputs()[0].name, "common_normal_upper_deviation_mm");
        assert_eq!(
            model.inputs()[18].name,
            "contact_equidistant_modification_mm"
        );
        let names: Vec<&str> = model.inputs().iter().map(|i| i.name.as_str()).collect();
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len());
    }
}
