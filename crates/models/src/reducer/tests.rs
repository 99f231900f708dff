//! Tests of `rv_lost_motion` against hand calculations and against the transmission-error
//! model's geometry (docs/models.md §14).

use super::geometry::needle_lever_at;
use super::*;
use crate::TransmissionError;
use std::f64::consts::PI;

fn params(set: &[(&str, f64)]) -> ModelParams {
    let mut params = RvLostMotion::rv20e_params();
    for &(key, value) in set {
        params = params.with_number(key, value);
    }
    params
}

fn model(set: &[(&str, f64)]) -> RvLostMotion {
    RvLostMotion::from_params(&params(set)).expect("valid parameters")
}

fn row(model: &RvLostMotion, set: &[(&str, f64)]) -> Vec<f64> {
    let mut x = vec![0.0; model.inputs().len()];
    for &(name, value) in set {
        let i = model
            .input_index(name)
            .unwrap_or_else(|| panic!("no input {name}"));
        x[i] = value;
    }
    x
}

/// A fixed stream of uniform numbers on [−1, 1) (xorshift64; tests only).
fn uniform() -> impl FnMut() -> f64 {
    let mut state = 0x9e3779b97f4a7c15_u64;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

fn outputs(model: &RvLostMotion, x: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; model.outputs().len()];
    model.evaluate(x, &mut out);
    out
}

/// A design with 10 µm of equidistant clearance and no shift: free at every angle.
const CLEAR: [(&str, f64); 2] = [
    ("equidistant_modification_mm", 0.010),
    ("shift_modification_mm", 0.0),
];

/// e·z_c of the RV-20E, mm.
const PITCH_LEVER: f64 = 0.9 * 39.0;

#[test]
fn the_design_play_approaches_the_closed_form_as_pins_pass_the_pitch_point() {
    // 003's standard form (validation.md 003): a pin at each pitch point gives the play
    // λ·2(Δr_rp − √(1 − K1²)·Δr_p)/(e·z_c); pins off the pitch point only widen it, by a
    // term quadratic in their distance from it, so the narrowest window over the grid
    // tends to the closed form from above as q grows.
    for design in [
        CLEAR,
        [
            ("equidistant_modification_mm", -0.010),
            ("shift_modification_mm", -0.0206),
        ],
    ] {
        let k1: f64 = 0.9 * 40.0 / 52.0;
        let closed = 2.0 * (design[0].1 - (1.0 - k1 * k1).sqrt() * design[1].1) / PITCH_LEVER;
        let mut previous = f64::INFINITY;
        for q in [1.0, 4.0, 16.0, 64.0] {
            let m = model(&[design[0], design[1], ("positions_per_pin", q)]);
            let x = row(&m, &[]);
            let narrowest = m
                .window_widths(&x)
                .into_iter()
                .fold(f64::INFINITY, f64::min)
                / m.lambda();
            assert!(
                narrowest >= closed - 1e-15,
                "q {q}: {narrowest} below {closed}"
            );
            assert!(narrowest <= previous + 1e-15, "q {q}: not converging");
            previous = narrowest;
        }
        assert!(
            (previous / closed - 1.0).abs() < 1e-3,
            "q = 64: {previous} against {closed}"
        );
    }
}

#[test]
fn identical_discs_give_the_one_disc_window_and_an_offset_disc_narrows_it() {
    // (a) Without deviations both discs see the same pins (z_p even: φ + π is a pin's
    // angle too), so the common window is either disc's. Disc 2's eccentrics moved across
    // by t on both cranks translate it across (T_y = t) and turn its window by
    // −λ·t/(e·z_c): the common window narrows by exactly that.
    let m = model(&CLEAR);
    let zero = row(&m, &[]);
    let t = 0.002;
    let moved = row(
        &m,
        &[
            ("crank_phase_error_mm_1_2", t),
            ("crank_phase_error_mm_2_2", t),
        ],
    );
    for k in [0, 3, 57, 101] {
        let [one, two] = m.disc_windows(&zero, k);
        assert!((one.0 - two.0).abs() < 1e-15 && (one.1 - two.1).abs() < 1e-15);
        let width = m.window_widths(&zero)[k];
        assert!((width - (one.1 - one.0)).abs() < 1e-15);
        let narrowed = m.window_widths(&moved)[k];
        let expected = m.lambda() * t / PITCH_LEVER;
        assert!(
            (width - narrowed - expected).abs() < 1e-12 * expected,
            "k {k}: narrowed by {} against λ·t/(e·z_c) = {expected}",
            width - narrowed
        );
    }
}

#[test]
fn a_runout_across_the_eccentric_turns_the_window_and_along_it_takes_play() {
    // (b) A runout r of disc 1's toothing: across its eccentric it turns disc 1's window by
    // −λ·r/(e·z_c) without changing its width (every pin normal passes through the pitch
    // point: a translation across is a turn of r/(e·z_c) for every pin); along it the gaps
    // change by r·(K1 − cos φ)/S, zero at the pitch point, of either sign on either side of
    // it, so the disc's play falls whichever way it moves.
    let m = model(&[CLEAR[0], CLEAR[1], ("positions_per_pin", 1.0)]);
    let k = 0; // z_pΘ = 0: the disc frame is the eccentric frame.
    let zero = row(&m, &[]);
    let [(lo, hi), _] = m.disc_windows(&zero, k);
    let r = 0.005;
    let across = row(
        &m,
        &[
            ("disc_runout_mm_1", 2.0 * r),
            ("disc_runout_phase_rad_1", 0.5 * PI),
        ],
    );
    let [(lo_a, hi_a), _] = m.disc_windows(&across, k);
    let turn = m.lambda() * r / PITCH_LEVER;
    assert!(((hi_a - lo_a) - (hi - lo)).abs() < 1e-15 * (hi - lo).abs().max(1e-9) + 1e-18);
    assert!((lo_a - (lo - turn)).abs() < 1e-12 * turn);
    for phase in [0.0, PI] {
        let along = row(
            &m,
            &[
                ("disc_runout_mm_1", 2.0 * r),
                ("disc_runout_phase_rad_1", phase),
            ],
        );
        let [(lo_b, hi_b), _] = m.disc_windows(&along, k);
        assert!(
            hi_b - lo_b < hi - lo - 1e-3 * (hi - lo),
            "phase {phase}: play {} not below {}",
            hi_b - lo_b,
            hi - lo
        );
    }
}

#[test]
fn a_pitch_deviation_averaged_over_its_phase_leaves_the_play() {
    // (c) A once-per-revolution pitch deviation turns each tooth by ε(ϑ) = (F_p/2)/r_m·
    // cos(ϑ − ϕ): the drive and coast pins sit at different ϑ, so the disc's play changes
    // by ε(ϑ_coast) − ε(ϑ_drive), first order in F_p and zero in the mean over ϕ. With
    // 0.1 µm no pin's part in the window changes, so each play is linear in F_p.
    let m = model(&[CLEAR[0], CLEAR[1], ("positions_per_pin", 1.0)]);
    let zero = row(&m, &[]);
    let k = 5;
    let [(lo, hi), _] = m.disc_windows(&zero, k);
    let n = 64;
    let (mut sum, mut largest) = (0.0, 0.0_f64);
    for j in 0..n {
        let phase = 2.0 * PI * j as f64 / n as f64;
        let x = row(
            &m,
            &[
                ("cumulative_pitch_deviation_mm_1", 1e-4),
                ("cumulative_pitch_phase_rad_1", phase),
            ],
        );
        let [(lo_p, hi_p), _] = m.disc_windows(&x, k);
        let change = (hi_p - lo_p) - (hi - lo);
        sum += change;
        largest = largest.max(change.abs());
    }
    // The play does move with the phase (the test can fail) …
    let epsilon = m.lambda() * 0.5e-4 / (52.0 - 2.0);
    assert!(largest > 0.1 * epsilon, "largest change {largest}");
    // … and its mean over the phase is zero to rounding.
    assert!(
        (sum / n as f64).abs() < 1e-9 * largest,
        "mean change {}",
        sum / n as f64
    );
}

#[test]
fn the_needle_lever_matches_its_hand_calculation() {
    // (d) Two cranks on the line β = 0, π (ĵ = (0, 1) their tangent): maximising
    // t·ŷ/(e·z_c) + u/a_w over |t ± u·ĵ| ≤ 1 gives, with t = p·ĵ + q·b̂ (|p| + |u| ≤
    // √(1 − q²)), h = √(A² + B²), A = max(|ŷ·ĵ|/(e·z_c), 1/a_w), B = |ŷ·b̂|/(e·z_c).
    let cranks = [(0.0, 1.0), (PI.sin(), PI.cos())];
    let (a_w, ezc) = (27.5, PITCH_LEVER);
    for angle in [0.0, 0.3, 0.5 * PI, 1.0, 2.5, PI] {
        let y: (f64, f64) = angle.sin_cos();
        let (along_b, along_j) = (y.1, y.0);
        let a = (along_j.abs() / ezc).max(1.0 / a_w);
        let b = along_b.abs() / ezc;
        let expected = a.hypot(b);
        let h = needle_lever_at(y, &cranks, a_w, ezc);
        assert!(
            (h - expected).abs() < 1e-9 * expected,
            "angle {angle}: {h} against {expected}"
        );
    }
    // A radial internal clearance u (the bore centres move within u/2) widens the common
    // window at each angle by λ·u·h (both discs: ŷ_2 = −ŷ_1, the same h).
    let m = model(&CLEAR);
    let zero = row(&m, &[]);
    let u = 0.002;
    let loose = row(&m, &[("crank_bearing_clearance_mm", u)]);
    let (w0, w1) = (m.window_widths(&zero), m.window_widths(&loose));
    for k in [0, 1, 2, 3, 17] {
        let turn = 2.0 * PI * k as f64 / m.points() as f64;
        let across = -40.0 * turn + 0.5 * PI;
        let h = needle_lever_at(across.sin_cos(), &cranks, a_w, ezc);
        let expected = m.lambda() * u * h;
        assert!(
            ((w1[k] - w0[k]) - expected).abs() < 1e-12 * expected,
            "k {k}"
        );
    }
    // Between 1/a_w (a turn only) and √(1/a_w² + 1/(e·z_c)²) (with a translation along
    // the crank line): 000 Eq. 20's Δu/a0 is the lower end without λ.
    let widening: Vec<f64> = w0
        .iter()
        .zip(&w1)
        .map(|(a, b)| (b - a) / (m.lambda() * u))
        .collect();
    let (low, high) = widening
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(
        (low - 1.0 / a_w).abs() < 1e-3 / a_w
            && (high - (1.0 / a_w).hypot(1.0 / ezc)).abs() < 1e-3 / a_w
    );
}

#[test]
fn the_windows_are_those_of_the_transmission_error_geometry() {
    // One geometry: on the deviations both models take (pin positions, pin circle and pin
    // radius, modification, disc profile and runout, crank axes and their tilts at the two
    // disc planes, eccentrics), each disc's
    // window at each output angle equals the transmission-error model's physical reading,
    // pin by pin.
    let m = model(&[
        CLEAR[0],
        CLEAR[1],
        ("positions_per_pin", 2.0),
        ("crank_eccentric_spacing_mm", 10.0),
    ]);
    let te = TransmissionError::from_params(
        &ModelParams::new()
            .with_number("crank_circle_radius_mm", 27.5)
            .with_number("crank_eccentric_spacing_mm", 10.0)
            .with_number("sun_teeth", 12.0)
            .with_number("planet_teeth", 42.0)
            .with_number("module_mm", 1.0)
            .with_number("pin_count", 40.0)
            .with_number("cycloid_teeth", 39.0)
            .with_number("pin_circle_radius_mm", 52.0)
            .with_number("eccentricity_mm", 0.9)
            .with_number("pin_radius_mm", 2.0)
            .with_number("disc_face_width_mm", 8.0)
            .with_number("rated_torque_nm", 167.0)
            .with_number("pin_position_errors", 1.0)
            .with(
                "disc_contact",
                crate::ParamValue::Text("first_contact".into()),
            ),
    )
    .expect("valid");
    let mut next = uniform();
    let mut shared: Vec<(String, f64)> = vec![
        ("equidistant_modification_error_mm".into(), 0.001 * next()),
        ("shift_modification_error_mm".into(), 0.002 * next()),
        ("pin_circle_radius_error_mm".into(), 0.005 * next()),
        ("pin_radius_error_mm".into(), 0.002 * next()),
    ];
    for d in 1..=2 {
        shared.push((format!("profile_normal_error_mm_{d}"), 0.002 * next()));
        for k in 1..=2 {
            shared.push((
                format!("crank_eccentricity_error_mm_{k}_{d}"),
                0.003 * next(),
            ));
            shared.push((format!("crank_phase_error_mm_{k}_{d}"), 0.003 * next()));
        }
    }
    for k in 1..=2 {
        shared.push((format!("crank_axis_radial_error_mm_{k}"), 0.004 * next()));
        shared.push((
            format!("crank_axis_tangential_error_mm_{k}"),
            0.004 * next(),
        ));
        shared.push((format!("crank_axis_tilt_radial_rad_{k}"), 4e-4 * next()));
        shared.push((format!("crank_axis_tilt_tangential_rad_{k}"), 4e-4 * next()));
    }
    for i in 1..=40 {
        shared.push((format!("pin_radial_error_mm_{i}"), 0.003 * next()));
        shared.push((format!("pin_tangential_error_mm_{i}"), 0.003 * next()));
    }
    let runout = [
        (0.004 * next(), 0.004 * next()),
        (0.004 * next(), 0.004 * next()),
    ];
    let mut ours: Vec<(String, f64)> = shared.clone();
    for (d, (rx, ry)) in runout.iter().enumerate() {
        ours.push((format!("disc_runout_mm_{}", d + 1), 2.0 * rx.hypot(*ry)));
        ours.push((format!("disc_runout_phase_rad_{}", d + 1), ry.atan2(*rx)));
    }
    let x = {
        let set: Vec<(&str, f64)> = ours.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        row(&m, &set)
    };
    let mut y = vec![0.0; te.inputs().len()];
    let mut put = |name: &str, value: f64| {
        let i = te
            .input_index(name)
            .unwrap_or_else(|| panic!("TE has no {name}"));
        y[i] += value;
    };
    put("equidistant_modification_mm", 0.010);
    for (name, value) in &shared {
        let name = name
            .replace(
                "equidistant_modification_error_mm",
                "equidistant_modification_mm",
            )
            .replace("shift_modification_error_mm", "shift_modification_mm");
        put(&name, *value);
    }
    for (d, (rx, ry)) in runout.iter().enumerate() {
        put(&format!("disc_runout_x_mm_{}", d + 1), *rx);
        put(&format!("disc_runout_y_mm_{}", d + 1), *ry);
    }
    // Both bound the upper end of disc d's window by the pins with l > 0, κ·(C_d + L_d),
    // and the lower by those with l < 0, κ·(C_d − K_d); the transmission error measures
    // the angle from the disc turned into contact on the l < 0 flank, 003's reference
    // turned by 2δ*, δ* = (Δr_rp − √(1 − K1²)·Δr_p)/(e·z_c) (its modification inputs
    // carry the errors): its ends are ours plus 2κ·δ*, at every pin, every angle.
    let (d_rp, d_p) = (
        y[te.input_index("equidistant_modification_mm")
            .expect("input")],
        y[te.input_index("shift_modification_mm").expect("input")],
    );
    let k1: f64 = 0.9 * 40.0 / 52.0;
    let offset = 2.0 * m.lambda() * (d_rp - (1.0 - k1 * k1).sqrt() * d_p) / PITCH_LEVER;
    for k in 0..m.points() {
        let theta = 2.0 * PI * k as f64 / m.points() as f64;
        let theirs = te.disc_windows(&y, theta).expect("physical reading");
        let ours = m.disc_windows(&x, k);
        for d in 0..2 {
            for (a, b) in [(ours[d].0, theirs[d].0), (ours[d].1, theirs[d].1)] {
                assert!(
                    (a + offset - b).abs() < 1e-15,
                    "k {k} disc {d}: {a} + {offset} against {b}"
                );
            }
        }
    }
}

#[test]
fn the_rv20e_design_is_preloaded_within_the_limit() {
    // 000 Table 9's modification (Δr_rp −0.010, Δr_p −0.012 mm) on Table 8's RV-20E
    // overlaps each flank by −(Δr_rp − √(1 − K1²)·Δr_p) = 1.3407 µm at a pin
    // on the pitch point (K1 = 0.9·40/52 derived); validation.md ("What a small preload
    // does": exact Palmgren pin contacts, 8 mm face) gives about 152 N of largest pin force
    // at zero torque, below the largest pin force at rated torque: preloaded within the
    // limit, which conforms.
    let m = model(&[("positions_per_pin", 16.0)]);
    let out = outputs(&m, &row(&m, &[]));
    let k1: f64 = 0.9 * 40.0 / 52.0;
    let closed = 1000.0 * (0.010 - (1.0 - k1 * k1).sqrt() * 0.012);
    // (Pins off the pitch point overlap less: the grid's largest overlap tends to the
    // closed form from below.)
    assert!(
        out[4] <= closed * (1.0 + 1e-12) && out[4] > closed * (1.0 - 2e-3),
        "overlap {} µm against {closed}",
        out[4]
    );
    assert!((out[5] / 152.0 - 1.0).abs() < 0.03, "pin force {}", out[5]);
    assert!(out[5] < m.rated_pin_force());
    assert_eq!((out[7], out[8]), (1.0, 0.0));
    assert_eq!(out[0], 0.0);
    assert!(out[6] > 0.0);
    // A deeper overlap is over the limit: 5 µm more shift per flank.
    let deeper = model(&[
        ("positions_per_pin", 16.0),
        ("shift_modification_mm", -0.0055),
    ]);
    let out = outputs(&deeper, &row(&deeper, &[]));
    assert!(out[5] > deeper.rated_pin_force(), "{} N", out[5]);
    assert_eq!((out[7], out[8]), (1.0, 1.0));
}

#[test]
fn a_free_design_has_lost_motion_and_no_preload() {
    let m = model(&CLEAR);
    let out = outputs(&m, &row(&m, &[]));
    assert!(out[0] > 0.0 && out[1] > 0.0 && out[1] <= out[0]);
    assert_eq!(&out[4..], &[0.0; 5]);
}

#[test]
fn a_non_finite_input_gives_nan_outputs() {
    let m = model(&[]);
    let x = row(&m, &[("pin_radial_error_mm_7", f64::NAN)]);
    assert!(outputs(&m, &x).iter().all(|v| v.is_nan()));
}

#[test]
fn bad_parameters_name_their_key() {
    for (key, value, needle) in [
        ("crank_count", 4.0, "must be 2 or 3"),
        ("positions_per_pin", 65.0, "at most 64"),
        ("preload_limit_pin_force_n", -1.0, "must not be negative"),
        ("equidistant_modification_mm", 1.5, "not a small correction"),
        ("pin_friction_coefficient", 1.5, "[0, 1)"),
    ] {
        let error = RvLostMotion::from_params(&params(&[(key, value)])).unwrap_err();
        assert_eq!(error.key, key);
        assert!(error.to_string().contains(needle), "{error}");
    }
}

/// Rows with every deviation drawn uniform within ±1.5 µm (phases over a turn), a free
/// profile (Δr_p −0.0206 mm) and the design's involute backlash.
fn random_rows(m: &RvLostMotion, n: usize) -> Vec<Vec<f64>> {
    let mut next = uniform();
    let len = m.inputs().len();
    (0..n)
        .map(|_| {
            let mut x: Vec<f64> = (0..len).map(|_| 0.0015 * next()).collect();
            for (name, value) in [
                ("common_normal_upper_deviation_mm", 0.0035),
                ("common_normal_lower_deviation_mm", -0.0309),
                ("crank_bearing_clearance_mm", 0.002),
            ] {
                x[m.input_index(name).expect("input")] = value;
            }
            for d in 1..=2 {
                for phase in ["disc_runout_phase_rad", "cumulative_pitch_phase_rad"] {
                    x[m.input_index(&format!("{phase}_{d}")).expect("input")] = PI * (1.0 + next());
                }
            }
            x
        })
        .collect()
}

#[test]
fn the_worst_grows_and_the_mean_settles_with_the_points_per_crank_turn() {
    // §14.4: the grids of q = 4, 8, 16 are nested, so the worst of M angles can only grow
    // with q and the least only fall; the mean over the revolution is a periodic mean that
    // q = 4 already settles: on these rows (every pin and disc deviation within ±1.5 µm,
    // lost motion about 0.9 arcmin) by under 0.005 arcmin on average, where the worst
    // still grows by several times that.
    let free = [
        ("equidistant_modification_mm", -0.010),
        ("shift_modification_mm", -0.0206),
    ];
    let models: Vec<RvLostMotion> = [4.0, 8.0, 16.0]
        .iter()
        .map(|&q| model(&[free[0], free[1], ("positions_per_pin", q)]))
        .collect();
    let (mut growth, mut mean_change) = (0.0, 0.0);
    for x in random_rows(&models[0], 100) {
        let out: Vec<Vec<f64>> = models.iter().map(|m| outputs(m, &x)).collect();
        assert!(out[0][0] <= out[1][0] && out[1][0] <= out[2][0], "{out:?}");
        assert!(
            out[2][2] <= out[1][2] && out[1][2] <= out[0][2],
            "least: {out:?}"
        );
        growth += out[2][0] - out[0][0];
        mean_change += (out[2][1] - out[0][1]).abs() / 100.0;
    }
    assert!(mean_change < 0.005, "{mean_change}");
    assert!(growth / 100.0 > 3.0 * mean_change, "{growth} {mean_change}");
}

#[test]
fn the_outputs_read_the_windows() {
    // lost motion = the widest, mean and least common window (clipped at 0) plus the
    // involute backlash, 000 Eq. 5: −(E_ws + E_wi)/(2·r1·i·cos α)·10800/π = 0.02633 arcmin
    // (validation.md 000) without shaft deviations.
    let m = model(&[
        ("equidistant_modification_mm", -0.010),
        ("shift_modification_mm", -0.0206),
    ]);
    for x in random_rows(&m, 20) {
        let out = outputs(&m, &x);
        let widths: Vec<f64> = m.window_widths(&x);
        let involute = out[3];
        let widest = widths.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let mean = widths.iter().map(|w| w.max(0.0)).sum::<f64>() / widths.len() as f64;
        let least = widths.iter().cloned().fold(f64::INFINITY, f64::min);
        assert_eq!(out[0], widest.max(0.0) * ARCMIN_PER_RAD + involute.max(0.0));
        assert!((out[1] - (mean * ARCMIN_PER_RAD + involute.max(0.0))).abs() < 1e-12);
        assert_eq!(out[2], least.max(0.0) * ARCMIN_PER_RAD + involute.max(0.0));
    }
    let nominal = outputs(
        &m,
        &row(
            &m,
            &[
                ("common_normal_upper_deviation_mm", 0.0035),
                ("common_normal_lower_deviation_mm", -0.0309),
            ],
        ),
    );
    assert!((nominal[3] - 0.02633).abs() < 5e-6, "{}", nominal[3]);
}

#[test]
fn the_no_load_torque_is_the_pin_friction_of_the_preload() {
    // T_0 = μ·Σ F_i·h_i/i: linear in μ at a fixed preload, zero without friction, and the
    // preload's forces do not depend on μ.
    let outs: Vec<Vec<f64>> = [0.0, 0.02, 0.04]
        .iter()
        .map(|&mu| {
            let m = model(&[("pin_friction_coefficient", mu)]);
            outputs(&m, &row(&m, &[]))
        })
        .collect();
    assert_eq!(outs[0][6], 0.0);
    assert!(outs[1][6] > 0.0);
    assert!((outs[2][6] / outs[1][6] - 2.0).abs() < 1e-12);
    assert_eq!(outs[0][5], outs[2][5]);
}

#[test]
fn the_row_table_gives_the_pin_by_pin_windows() {
    // The fast path (a row reduced to its crank angles' runs, windows.rs RowTable) against
    // every pin's gap computed in full at every point, with and without pins out of place.
    let m = model(&[
        ("equidistant_modification_mm", -0.010),
        ("shift_modification_mm", -0.0206),
    ]);
    let rows = random_rows(&m, 10);
    let unplaced: Vec<Vec<f64>> = rows
        .iter()
        .map(|x| {
            let mut x = x.clone();
            for i in 1..=40 {
                for name in ["pin_radial_error_mm", "pin_tangential_error_mm"] {
                    x[m.input_index(&format!("{name}_{i}")).expect("input")] = 0.0;
                }
            }
            x
        })
        .collect();
    // And Table 9's design, whose discs overlap their own flanks by 1.34 µm, with the
    // needle rows' clearance: a disc rests at its own balance, its slack about it.
    let design = model(&[]);
    let design_rows = random_rows(&design, 10);
    let mut own = 0;
    for (m, x) in rows
        .iter()
        .chain(&unplaced)
        .map(|x| (&m, x))
        .chain(design_rows.iter().map(|x| (&design, x)))
    {
        let widths = m.window_widths(x);
        for (k, width) in widths.iter().enumerate() {
            let [one, two] = m.disc_windows_at_rest(x, k);
            let direct = one.1.min(two.1) - one.0.max(two.0);
            // Bisection to the last bit against Newton's step to 1e-16 rad.
            assert!(
                (width - direct).abs() < 1e-15,
                "k {k}: {width} against {direct}"
            );
            let rigid = m.disc_windows(x, k);
            own += usize::from(rigid.iter().zip([one, two]).any(|(r, a)| r != &a));
        }
    }
    assert!(own > 100, "{own} points with a disc overlapping itself");
}

#[test]
fn a_crank_tilt_acts_at_the_two_disc_planes_as_opposite_bore_errors() {
    // 001 Eq. 7 (displacement θ × p of a point p on the axis): a tilt τ_t of crank 1 about
    // its tangential direction moves its axis radially by +τ_t·s/2 at disc 1's plane
    // (z = +s/2) and by −τ_t·s/2 at disc 2's; a tilt τ_r about the radial direction moves
    // it tangentially by −τ_r·z. Each disc's window equals the one a bore error of that
    // size gives (s = 9 mm, the RV-20E's eccentric spacing).
    let m = model(&CLEAR);
    let (tau, half) = (2e-4, 4.5);
    for (tilt, bore, sign) in [
        (
            "crank_axis_tilt_tangential_rad_1",
            "crank_axis_radial_error_mm_1",
            1.0,
        ),
        (
            "crank_axis_tilt_radial_rad_1",
            "crank_axis_tangential_error_mm_1",
            -1.0,
        ),
    ] {
        let tilted = row(&m, &[(tilt, tau)]);
        let at_one = row(&m, &[(bore, sign * tau * half)]);
        let at_two = row(&m, &[(bore, -sign * tau * half)]);
        for k in [0, 1, 2, 3, 41, 117] {
            let windows = m.disc_windows(&tilted, k);
            let (one, two) = (m.disc_windows(&at_one, k)[0], m.disc_windows(&at_two, k)[1]);
            for (a, b) in [(windows[0], one), (windows[1], two)] {
                assert!(
                    (a.0 - b.0).abs() < 1e-15 && (a.1 - b.1).abs() < 1e-15,
                    "{tilt} k {k}"
                );
            }
        }
        // And the tilt moves the discs' windows: it is not lost on the way.
        assert_ne!(m.window_widths(&tilted), m.window_widths(&row(&m, &[])));
    }
}

#[test]
fn the_needle_slack_of_unequal_clearances_matches_its_hand_calculation() {
    use super::geometry::needle_slack;
    let (a_w, ezc) = (27.5, PITCH_LEVER);
    let two = [(0.0, 1.0), (PI.sin(), PI.cos())];
    let three: Vec<(f64, f64)> = (0..3)
        .map(|k| (2.0 * PI * k as f64 / 3.0).sin_cos())
        .collect();
    // Equal radii ρ: ρ times the unit lever, for two and three cranks.
    for angle in [0.0, 0.3, 0.5 * PI, 1.0, 2.5, PI, 4.0] {
        let y: (f64, f64) = angle.sin_cos();
        for cranks in [&two[..], &three[..]] {
            let unit = needle_lever_at(y, cranks, a_w, ezc);
            let radii = vec![0.0013; cranks.len()];
            let slack = needle_slack(y, cranks, &radii, a_w, ezc);
            assert!(
                (slack - 0.0013 * unit).abs() < 1e-12 * unit,
                "{angle}: {slack}"
            );
        }
    }
    // Two cranks, the across direction along the cranks' tangent ĵ (y_x = 0): the bores
    // take their circles' ends along ĵ, p_1 = ρ_1·ĵ and p_2 = −ρ_2·ĵ (since 1/(e·z_c) <
    // 1/a_w), so h = ρ_1·(1/P + 1/a_w)/2 + ρ_2·(1/a_w − 1/P)/2 (P = e·z_c).
    let (r1, r2) = (0.0015, 0.0005);
    let expected = r1 * (1.0 / ezc + 1.0 / a_w) / 2.0 + r2 * (1.0 / a_w - 1.0 / ezc) / 2.0;
    let slack = needle_slack((1.0, 0.0), &two, &[r1, r2], a_w, ezc);
    assert!(
        (slack - expected).abs() < 1e-12 * expected,
        "{slack} against {expected}"
    );
    // The two-crank form against the general search (three cranks' code path on two).
    for angle in [0.2_f64, 1.1, 2.0, 3.3, 5.0] {
        let y: (f64, f64) = angle.sin_cos();
        let closed = needle_slack(y, &two, &[r1, r2], a_w, ezc);
        let searched = super::geometry::any_crank_slack(y, &two, &[r1, r2], a_w, ezc);
        assert!(
            (closed - searched).abs() < 1e-12 * closed,
            "{angle}: {closed} {searched}"
        );
    }
    // A held bore (ρ = 0) leaves the other's slack, finite.
    let held = needle_slack(0.6_f64.sin_cos(), &three, &[0.0, 0.001, 0.002], a_w, ezc);
    assert!(held.is_finite() && held > 0.0, "{held}");
}

#[test]
fn a_crank_s_own_needle_clearance_widens_the_window_between_its_neighbours() {
    // u + δu on both cranks is the even clearance u + δu; δu on one crank only widens the
    // window at every angle no less than nothing and no more than δu on both.
    let m = model(&CLEAR);
    let (u, du) = (0.002, 0.001);
    let base = row(&m, &[("crank_bearing_clearance_mm", u)]);
    let even = row(&m, &[("crank_bearing_clearance_mm", u + du)]);
    let both = row(
        &m,
        &[
            ("crank_bearing_clearance_mm", u),
            ("crank_bearing_clearance_deviation_mm_1", du),
            ("crank_bearing_clearance_deviation_mm_2", du),
        ],
    );
    let one = row(
        &m,
        &[
            ("crank_bearing_clearance_mm", u),
            ("crank_bearing_clearance_deviation_mm_1", du),
        ],
    );
    let widths = |x: &[f64]| m.window_widths(x);
    let (w0, we, wb, w1) = (widths(&base), widths(&even), widths(&both), widths(&one));
    for k in 0..m.points() {
        assert!(
            (we[k] - wb[k]).abs() < 1e-12 * we[k].abs().max(1e-6),
            "k {k}"
        );
        assert!(w1[k] >= w0[k] - 1e-15 && w1[k] <= wb[k] + 1e-15, "k {k}");
    }
    assert!(w1.iter().zip(&w0).any(|(a, b)| a > b));
}

/// The RV-20E with the torsion curve's crank side (`TorsionCurve::rv20e_params`, the same
/// estimates as scenarios/reducers/rv20e.json) and the loaded figures on.
/// A row of the loaded figures' tests: every input a small deviation (±4 µm, phases as
/// small), 000's common normal deviations and a crank bearing clearance in its band
/// (2–3 µm), drawn from `next`.
fn loaded_row(m: &RvLostMotion, next: &mut impl FnMut() -> f64) -> Vec<f64> {
    let mut x: Vec<f64> = (0..m.inputs().len()).map(|_| 0.004 * next()).collect();
    for (name, value) in [
        ("common_normal_upper_deviation_mm", 0.0035),
        ("common_normal_lower_deviation_mm", -0.0309),
        ("crank_bearing_clearance_mm", 0.002 + 0.001 * next()),
    ] {
        x[m.input_index(name).expect("input")] = value;
    }
    x
}

fn loaded_model(set: &[(&str, f64)]) -> RvLostMotion {
    let mut p = params(&[
        ("loaded_figures", 1.0),
        ("crank_journal_diameter_mm", 15.0),
        ("needle_roller_count", 15.0),
        ("needle_roller_diameter_mm", 3.0),
        ("needle_roller_length_mm", 6.0),
        ("crank_support_span_mm", 30.75),
        ("support_roller_count", 13.0),
        ("support_roller_length_mm", 8.225),
        ("support_contact_angle_deg", 13.0),
        ("support_bearing_width_mm", 11.75),
        ("support_bearing_outer_diameter_mm", 35.0),
        ("carrier_pillar_width_mm", 11.0),
        ("carrier_pillar_depth_mm", 11.0),
        ("carrier_pillar_length_mm", 19.0),
        ("planet_face_width_mm", 8.0),
        ("planet_gear_overhang_mm", 10.875),
        ("crank_bearing_friction_coefficient", 0.002),
    ]);
    for &(key, value) in set {
        p = p.with_number(key, value);
    }
    RvLostMotion::from_params(&p).expect("valid parameters")
}

/// The loaded figures of a row: [lost motion, hysteresis loss, rigidity, angle at rated,
/// pin force at rated].
fn figures(model: &RvLostMotion, x: &[f64]) -> [f64; 5] {
    let out = outputs(model, x);
    [out[9], out[10], out[11], out[12], out[13]]
}

/// The torsion curve's [lost motion, hysteresis loss, rigidity, angle at rated] for the
/// RV-20E with the modification (Δr_rp, Δr_p) and no deviation, the friction coefficients
/// (μ_p, μ_b).
fn torsion_curve_figures(modification: (f64, f64), friction: (f64, f64)) -> [f64; 4] {
    let params = crate::TorsionCurve::rv20e_params()
        .with_number("curtate_ratio", 0.9 * 40.0 / 52.0)
        .with_number("pin_friction_coefficient", friction.0)
        .with_number("crank_bearing_friction_coefficient", friction.1);
    let curve = crate::TorsionCurve::from_params(&params).unwrap();
    let mut x = vec![0.0; curve.inputs().len()];
    let index = |name: &str| curve.inputs().iter().position(|i| i.name == name).unwrap();
    x[index("equidistant_modification_mm")] = modification.0;
    x[index("shift_modification_mm")] = modification.1;
    let mut out = vec![0.0; curve.outputs().len()];
    curve.evaluate(&x, &mut out);
    let at = |name: &str| out[curve.outputs().iter().position(|o| o.name == name).unwrap()];
    [
        at("lost_motion_arcmin"),
        at("hysteresis_loss_arcmin"),
        at("torsional_rigidity_nm_per_arcmin"),
        at("angle_at_rated_arcmin"),
    ]
}

#[test]
fn two_alike_discs_under_load_give_the_torsion_curve() {
    // No deviation: both discs alike, so the pair's loaded solution is the torsion curve's
    // one-disc load sharing at half the torque each (crate::loaded), with the same crank
    // side, housing and friction. One point per pin pitch puts the pins at whole places,
    // where the torsion curve has them. Three profiles: none (zero play), 10 µm of
    // equidistant clearance (free: 0.93 arcmin) and Table 9's design (preloaded, 1.34 µm
    // per flank), with and without friction. The two solvers settle the angle to 1e-13 rad
    // (the carrier) and F_max to 1e-12 of itself (the load sharing): 1e-8 of the smallest
    // figure, the lost motion's elastic part at ±3 %, bounds both.
    for modification in [(0.0, 0.0), (0.010, 0.0), (-0.010, -0.012)] {
        for friction in [(0.02, 0.002), (0.0, 0.0)] {
            let m = loaded_model(&[
                ("positions_per_pin", 1.0),
                ("equidistant_modification_mm", modification.0),
                ("shift_modification_mm", modification.1),
                ("pin_friction_coefficient", friction.0),
                ("crank_bearing_friction_coefficient", friction.1),
            ]);
            let ours = figures(&m, &row(&m, &[]));
            let theirs = torsion_curve_figures(modification, friction);
            for (name, (a, b)) in [
                "lost motion",
                "hysteresis loss",
                "rigidity",
                "angle at rated",
            ]
            .iter()
            .zip(ours.iter().zip(theirs))
            {
                assert!(
                    (a - b).abs() <= 1e-8 * b.abs().max(0.01),
                    "{name} {modification:?} {friction:?}: {a} against the torsion curve's {b}"
                );
            }
        }
    }
}

#[test]
fn without_friction_the_loaded_lost_motion_is_the_free_play_and_the_elastic_angles() {
    // The catalogue's lost motion of a stage with play, frictionless: the free play (the
    // window, crossed at zero torque) plus the elastic angle from first contact to 3 % of
    // rated torque on each side (torsion_curve's E(3 %; ±), the same chain).
    let frictionless = [
        ("pin_friction_coefficient", 0.0),
        ("crank_bearing_friction_coefficient", 0.0),
    ];
    let m = loaded_model(&[&CLEAR[..], &frictionless[..], &[("positions_per_pin", 1.0)]].concat());
    let x = row(&m, &[]);
    let out = outputs(&m, &x);
    let params = crate::TorsionCurve::rv20e_params()
        .with_number("curtate_ratio", 0.9 * 40.0 / 52.0)
        .with_number("pin_friction_coefficient", 0.0)
        .with_number("crank_bearing_friction_coefficient", 0.0);
    let curve = crate::TorsionCurve::from_params(&params).unwrap();
    let mut y = vec![0.0; curve.inputs().len()];
    y[2] = 0.010; // equidistant_modification_mm (000's order)
    let elastic = |loading| curve.elastic_angle(&y, 0.03 * 167.0, loading).unwrap();
    let expected = out[0] + elastic(true) + elastic(false);
    assert!(out[0] > 0.9, "free play {}", out[0]);
    assert!(
        (out[9] - expected).abs() < 1e-9,
        "{} against {} + {} + {}",
        out[9],
        out[0],
        elastic(true),
        elastic(false)
    );
}

#[test]
fn the_needle_slack_under_load_is_free_play() {
    // The needle rows' clearance u lets each disc turn by ±s without moment (§14.3): the
    // discs take it up toward the load, so the curve moves out by λ·s on each side and the
    // lost motion at ±3 % grows by 2λ·s, the window's own growth, with play or preloaded
    // (both discs carry the load's sign at ±3 %). One point per pin pitch: every point has
    // the same crank angle, so the same s.
    let u = [("crank_bearing_clearance_mm", 0.004)];
    // So does the loop's width at zero torque: with play it is the window; the design's
    // discs, which overlap their own flanks, rest pressed by their pins at zero torque and
    // their loop (the pins' friction) opens by the slack's 2λ·s.
    let growth = |set: &[(&str, f64)]| {
        let m = loaded_model(&[set, &[("positions_per_pin", 1.0)]].concat());
        let (tight, loose) = (outputs(&m, &row(&m, &[])), outputs(&m, &row(&m, &u)));
        (
            loose[9] - tight[9],
            loose[0] - tight[0],
            loose[10] - tight[10],
        )
    };
    let (free_loaded, free_window, free_loop) = growth(&CLEAR);
    let (preloaded_loaded, preloaded_window, preloaded_loop) = growth(&[]);
    assert!(
        (free_loop - free_window).abs() < 1e-9,
        "{free_loop} against {free_window}"
    );
    assert!(
        (preloaded_loop - free_window).abs() < 1e-9,
        "{preloaded_loop} against {free_window}"
    );
    // The design's discs are held by their own pins: the whole slack is free play at rest
    // (the window of each disc is its slack about its own balance, §14.2), as with play.
    assert!(
        (preloaded_window - free_window).abs() < 1e-12,
        "{preloaded_window} against {free_window}"
    );
    // 2λ·s with s = (u/2)·h, h between 1/a_w and √(1/a_w² + 1/(e·z_c)²) (§14.3).
    let lambda = 39.0 / 40.0 * (1.0 - 1.0 / 141.0);
    let bound = |h: f64| 2.0 * lambda * 0.002 * h * crate::ARCMIN_PER_RAD;
    assert!(free_window > bound(1.0 / 27.5) * (1.0 - 1e-9));
    assert!(free_window < bound((1.0 / 27.5_f64).hypot(1.0 / PITCH_LEVER)));
    assert!(
        (free_loaded - free_window).abs() < 1e-9,
        "{free_loaded} against {free_window}"
    );
    assert!(
        (preloaded_loaded - free_window).abs() < 1e-9,
        "{preloaded_loaded} against {free_window}"
    );
}

#[test]
fn an_over_preloaded_assembly_has_finite_loaded_figures() {
    // Pins 6 µm oversize: every flank overlaps by about 7 µm, far over the pin-force limit.
    // The loaded solution still stands: both flanks carry at zero torque, the reverse flank
    // unloads as the torque rises, so the lost motion at ±3 % is less than the design's and
    // the largest pin force at rated more.
    let m = loaded_model(&[]);
    let design = outputs(&m, &row(&m, &[]));
    let over = outputs(&m, &row(&m, &[("pin_radius_error_mm", 0.006)]));
    assert_eq!(over[8], 1.0, "over-preloaded");
    assert!(
        over[9..14].iter().all(|v| v.is_finite()),
        "{:?}",
        &over[9..14]
    );
    assert!(over[9] < design[9], "{} against {}", over[9], design[9]);
    assert!(over[13] > design[13], "{} against {}", over[13], design[13]);
    assert!(
        over[10] > design[10],
        "hysteresis loss {} against {}",
        over[10],
        design[10]
    );
}

#[test]
fn the_loaded_figures_are_asked_for() {
    // Off by default: the nine outputs of the free play and the preload, no crank side.
    assert_eq!(model(&[]).outputs().len(), 9);
    let m = loaded_model(&[]);
    let names: Vec<&str> = m.outputs()[9..].iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "lost_motion_loaded_arcmin",
            "hysteresis_loss_arcmin",
            "torsional_rigidity_nm_per_arcmin",
            "angle_at_rated_arcmin",
            "pin_force_at_rated_n"
        ]
    );
    // On, the crank side's keys are needed: the missing one is named.
    let error = RvLostMotion::from_params(&params(&[("loaded_figures", 1.0)])).unwrap_err();
    assert!(
        error.to_string().contains("crank_journal_diameter_mm"),
        "{error}"
    );
}

#[test]
fn a_disc_held_by_its_own_pins_is_preloaded_whatever_its_slack() {
    // Table 9's design overlaps each disc's own flanks by 1.34 µm: its pins press it at
    // rest whether or not the needle rows' clearance leaves the pair free to turn. With
    // 4 µm of clearance (slack 0.48 arcmin, above the 0.25 arcmin of the overlap) the
    // preload is the same as without (each disc rests at its own balance: the same
    // overlap, pin forces and drag), and the free play is the slack's.
    let m = model(&[("positions_per_pin", 16.0)]);
    let tight = outputs(&m, &row(&m, &[]));
    let loose = outputs(&m, &row(&m, &[("crank_bearing_clearance_mm", 0.004)]));
    assert_eq!(
        (loose[7], loose[8]),
        (1.0, 0.0),
        "preloaded within the limit"
    );
    for i in 4..7 {
        assert!(
            (loose[i] - tight[i]).abs() <= 1e-9 * tight[i],
            "output {i}: {} against {}",
            loose[i],
            tight[i]
        );
    }
    assert!(loose[0] > 0.4, "free play {}", loose[0]);
}
#[test]
fn random_assemblies_get_bounded_loaded_figures() {
    // Deviations of ±4 µm on every input (pins, discs, eccentrics, cranks), 1–3 µm of needle
    // clearance: discs pressed by their own pins, pins of small lever overlapping, pairs
    // free or pressing each other. Every figure is finite; the catalogue's lost motion
    // holds the free play at its angle (the window crossed at zero torque, the elastic
    // angles and the friction's loop added); the loop is at least the involute stage's
    // play; the rigidity stays within half of the nominal 60 N·m/arcmin (the crank side is
    // the same; the pins carry on one flank at 50–100 % of rated, fewer of them where the
    // gaps spread: 39–68 N·m/arcmin over these rows).
    let m = loaded_model(&[]);
    let mut next = uniform();
    for _ in 0..2000 {
        let mut x = loaded_row(&m, &mut next);
        for d in 1..=2 {
            for phase in ["disc_runout_phase_rad", "cumulative_pitch_phase_rad"] {
                x[m.input_index(&format!("{phase}_{d}")).expect("input")] = PI * (1.0 + next());
            }
        }
        let out = outputs(&m, &x);
        assert!(out[9..14].iter().all(|v| v.is_finite()), "{out:?}");
        assert!(
            out[9] >= out[0] - 1e-9,
            "lost motion {} below the free play {}",
            out[9],
            out[0]
        );
        assert!(out[10] >= out[3] - 1e-9, "{out:?}");
        assert!(out[11] > 30.0 && out[11] < 90.0, "rigidity {}", out[11]);
    }
}

#[test]
fn the_loaded_figures_do_not_hang_on_rounding() {
    // Rows as above; each again with one disc's profile error moved by 1e-15 mm,
    // which moves the windows' ends by their rounding only. A window that is one disc's
    // slack about its own balance is equally wide at every point of its crank angle where
    // it lies within the other disc's, but for rounding; the loaded figures are read at
    // the first of the widest (to 1e-12 rad), so the nudge moves them by rounding too
    // (the strict widest, chosen by rounding, moved them by up to some percent on such
    // rows). Asserted to 1e-6 relative (the loaded solves settle to some 1e-9); some rows
    // have such ties (counted).
    let m = loaded_model(&[]);
    let mut next = uniform();
    let nudged = m.input_index("profile_normal_error_mm_1").expect("input");
    let mut ties = 0;
    for _ in 0..300 {
        let mut x = loaded_row(&m, &mut next);
        let out = outputs(&m, &x);
        x[nudged] += 1e-15;
        let again = outputs(&m, &x);
        for (a, b) in out[9..14].iter().zip(&again[9..14]) {
            assert!((a - b).abs() <= 1e-6 * a.abs(), "{out:?}\n{again:?}");
        }
        let widths = m.window_widths(&x);
        let widest = widths.iter().fold(f64::NEG_INFINITY, |a, w| a.max(*w));
        ties += usize::from(widths.iter().filter(|w| **w >= widest - 1e-12).count() > 1);
    }
    assert!(ties > 10, "{ties} rows with ties"); // 20 of the 300
}
