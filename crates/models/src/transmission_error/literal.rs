//! Document 002's literal reading of the transmission error (`reading` "document_002"):
//! one disc, the cranks averaged, 002's δ41 at r6, disc-side errors 1:1 at the output. It
//! reproduces the one-disc model figure for figure (tests/transmission_error.rs). Its data
//! is [`Literal`] (the output pin-hole radius and the one disc's pin table), its per-thread
//! work state [`LiteralScratch`]; what it shares with the physical reading (the geometry,
//! the curve's points, the FFT) it reads from [`Common`].
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

use std::f64::consts::PI;

use super::common::{smallest, smallest_ratio, Common, PinTable};
use crate::cycloid::CycloidStage;
use crate::{Curve, CurveStyle, InputSpec, OutputKind, OutputSpec, Series, ARCSEC_PER_RAD};

/// Inputs per crank, in order.
pub(super) const CRANK_INPUTS: [(&str, &str); 7] = [
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
pub(super) const FIXED_INPUTS: [(&str, &str); 9] = [
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

/// Document 002's literal reading: the radius of its output pin holes and its one disc's
/// pin table.
#[derive(Debug, Clone)]
pub(super) struct Literal {
    /// r6, mm: the output pin-hole circle 002's δ41 acts at.
    output_radius: f64,
    /// The disc's slots with a positive lever, per phase of the curve.
    table: PinTable,
}

/// Per-thread work state of the literal reading's first-contact search, refilled for every
/// row: the per-pin and per-tooth errors laid out twice in a row, so that the errors seen by
/// consecutive slots are one contiguous slice whatever the shift (zeros when the model has
/// no such inputs), one group's ratios without the pin errors, and the FFT's columns.
#[derive(Debug, Default)]
pub(super) struct LiteralScratch {
    pin_radial: Vec<f64>,
    pin_tangential: Vec<f64>,
    tooth: Vec<f64>,
    /// Per entry of the current group's block, the part of its ratio common to all the
    /// group's points (everything but the pin errors).
    head: Vec<f64>,
    /// The FFT's real and imaginary columns.
    fft_re: Vec<f64>,
    fft_im: Vec<f64>,
}

impl Literal {
    /// The reading for N = `points` points, g = gcd(z_c·z_p, N), `width` slots per phase,
    /// r6 = `output_radius`.
    pub(super) fn new(
        stage: &CycloidStage,
        points: usize,
        g: usize,
        width: usize,
        output_radius: f64,
    ) -> Literal {
        Literal {
            output_radius,
            table: table(stage, points, g, width),
        }
    }

    /// Calls `sink(j, stages)` for every point j of the curve (stage errors in rad), with an
    /// explicit work state.
    #[inline(always)]
    pub(super) fn trace_with(
        &self,
        common: &Common,
        inputs: &[f64],
        scratch: &mut LiteralScratch,
        mut sink: impl FnMut(usize, StageErrors),
    ) {
        let n_fixed = FIXED_INPUTS.len();
        let (sun_x, sun_y) = (inputs[0], inputs[1]);
        let (d_rp, d_p, profile) = (inputs[2], inputs[3], inputs[4]);
        let (err_rp, err_rrp) = (inputs[5], inputs[6]);
        let (out_x, out_y) = (inputs[7], inputs[8]);
        let m = common.cranks as f64;
        let (sin_a, cos_a) = common.pressure;
        // Per crank k at β_k = 2π(k − 1)/m on the carrier: its action line n_k, and the
        // mean eccentric error and crank-bore error (the latter in the carrier frame).
        // The planet runouts p_k turn at −z_p·Θ in the carrier and the sun runout s at
        // (i − 1)·Θ: n_k·R(−z_p·Θ)·p_k = cos(z_p·Θ)·(n_k·p_k) + sin(z_p·Θ)·(n_k × p_k) and
        // n·R((i − 1)·Θ)·s = cos((i − 1)·Θ)·(n·s) + sin((i − 1)·Θ)·(n × s), n = Σ n_k.
        let mut involute_constant = 0.0;
        let (mut planet_cos, mut planet_sin) = (0.0, 0.0);
        let (mut q_r, mut q_t, mut b_x, mut b_y) = (0.0, 0.0, 0.0, 0.0);
        let mut normal_sum = (0.0, 0.0);
        for k in 0..common.cranks {
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
        let inverse_lever_base = 1.0 / (common.eccentricity * common.cycloid_teeth as f64);
        let (out_x, out_y) = (out_x / self.output_radius, out_y / self.output_radius);
        let involute_scale = -1.0 / (m * common.base_radius * common.divisor);
        let constant = profile - err_rrp;
        // Per-pin and per-tooth inputs follow the cranks' (empty when the model has none).
        let n_pins = if common.per_pin { common.pins } else { 0 };
        let n_teeth = if common.per_tooth {
            common.cycloid_teeth
        } else {
            0
        };
        let (pin_inputs, tooth_errors) = inputs[n_fixed + 7 * common.cranks..].split_at(2 * n_pins);
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
        if common.per_pin {
            repeat(&mut scratch.pin_radial, pin_radial, common.pins + width);
            repeat(
                &mut scratch.pin_tangential,
                pin_tangential,
                common.pins + width,
            );
        }
        repeat(&mut scratch.tooth, tooth_errors, 2 * common.cycloid_teeth);
        let LiteralScratch {
            pin_radial,
            pin_tangential,
            tooth,
            head,
            ..
        } = scratch;
        head.resize(width, 0.0);
        let (pins, teeth) = (common.pins as u32, common.cycloid_teeth as u32);
        for group in &common.groups {
            let points = &common.curve_points[group.start as usize..group.end as usize];
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
                let lag = if common.per_pin {
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

    /// [`crate::ErrorModel::evaluate`] with an explicit work state (`curve` the row's): the
    /// curve, its peak-to-peak, rms and mean, and the amplitudes of orders 1, z_c and z_p.
    pub(super) fn evaluate_with(
        &self,
        common: &Common,
        inputs: &[f64],
        curve: &mut Vec<f64>,
        scratch: &mut LiteralScratch,
        outputs: &mut [f64],
    ) {
        // The scans pass over a NaN ratio, so a non-finite input must not reach them.
        if inputs.iter().any(|v| !v.is_finite()) {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
            return;
        }
        curve.resize(common.points, 0.0);
        self.fill_curve(common, inputs, scratch, curve);
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
        let (re, im) = (&mut scratch.fft_re, &mut scratch.fft_im);
        re.resize(common.points / 2, 0.0);
        im.resize(common.points / 2, 0.0);
        common.fft.transform_split(curve, re, im);
        let [first, cycloid, pins] =
            [1, common.cycloid_teeth, common.pins].map(|k| common.fft.split_amplitude(re, im, k));
        outputs[..6].copy_from_slice(&[hi - lo, var.sqrt(), mean, first, cycloid, pins]);
        if !(hi - lo).is_finite() || !sum.is_finite() {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
        }
    }

    /// Fills `curve` (N values) with TE(Θ_j) in arcsec.
    #[inline(always)]
    pub(super) fn fill_curve(
        &self,
        common: &Common,
        inputs: &[f64],
        scratch: &mut LiteralScratch,
        curve: &mut [f64],
    ) {
        self.trace_with(common, inputs, scratch, |j, stages| {
            curve[j] = stages.total() * ARCSEC_PER_RAD
        });
    }

    /// The literal reading's curves: the curve with its four stages, and its FFT order
    /// spectrum.
    pub(super) fn curves(
        &self,
        common: &Common,
        inputs: &[f64],
        scratch: &mut LiteralScratch,
    ) -> Vec<Curve> {
        let n = common.points;
        let mut stages = vec![StageErrors::default(); n];
        self.trace_with(common, inputs, scratch, |j, s| stages[j] = s);
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
        let spectrum = common.spectrum(&total);
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

/// The literal reading's pin table ([`PinTable`]) for N = `points` points, g = gcd(z_c·z_p, N):
/// N/g phases of `width` slots each.
fn table(stage: &CycloidStage, points: usize, g: usize, width: usize) -> PinTable {
    let (pins, cycloid_teeth) = (stage.pins, stage.teeth);
    let (pin_circle_radius, eccentricity) = (stage.pin_circle_radius, stage.eccentricity);
    let mut table = PinTable {
        width,
        ..PinTable::default()
    };
    let zc = cycloid_teeth as i64;
    for p in 0..points / g {
        let fraction = p as f64 * g as f64 / points as f64;
        for s in 0..width {
            let phi = 2.0 * PI * (s as f64 + fraction) / pins as f64;
            let (sin, cos) = phi.sin_cos();
            // Padding: no positive lever, or past the last pin (3 pins, 4 slots).
            if s >= pins || sin <= 1e-12 {
                table.push_padding();
                continue;
            }
            let factors = stage.pin_factors(phi);
            let inverse_lever = 1.0 / factors.lever;
            let polar = (pin_circle_radius * sin).atan2(pin_circle_radius * cos - eccentricity);
            let tooth = ((cycloid_teeth as f64 * polar / (2.0 * PI) - fraction).round() as i64)
                .rem_euclid(zc);
            table.blocked.push(0.0);
            table.inverse_lever.push(inverse_lever);
            table.equidistant.push(factors.equidistant * inverse_lever);
            table.shift.push(factors.shift * inverse_lever);
            table.eccentric.push(factors.eccentric * inverse_lever);
            table.radial.push(factors.radial * inverse_lever);
            table.tangential.push(factors.tangential * inverse_lever);
            table.tooth.push(tooth as u32);
        }
    }
    table
}

/// The inputs and outputs of document 002's literal reading (one disc).
pub(super) fn specs(
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

#[cfg(test)]
mod tests {
    use super::super::test_support::{outputs, row, with, MODIFIED};
    use super::super::TransmissionError;
    use super::*;
    use crate::{ErrorModel, ModelParams, ParamValue};

    /// The tests of this module check document 002's literal reading; the physical
    /// reading's are in `two_discs`, the loaded reading's in `loaded/tests.rs`.
    fn rv40e_params() -> ModelParams {
        super::super::rv40e_params().with("reading", ParamValue::Text("document_002".into()))
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
