//! `rv_lost_motion` against an independent computation on the exact geometry
//! (tests/data/exact_profile_windows.csv, written by scripts/exact-profile-windows.py
//! without reading rvtol's code: the ground cycloid profile of the RV-20E, pins placed,
//! clearances along the exact normals, each window by root finding to 1e-15 rad).

use crate::common;
use rvtol_models::{ErrorModel, RvLostMotion};
use std::f64::consts::PI;

const ARCMIN: f64 = 10800.0 / PI;

/// One row of the reference.
struct Reference {
    case: String,
    equidistant: f64,
    shift: f64,
    grid: usize,
    along: f64,
    across: f64,
    pin: Option<usize>,
    radial: f64,
    tangential: f64,
    radius: f64,
    play: f64,
    centre: f64,
}

fn reference() -> Vec<Reference> {
    let text = std::fs::read_to_string(
        common::workspace_dir().join("tests/data/exact_profile_windows.csv"),
    )
    .expect("reference table");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (case, dr_rp, dr_p, along, across, pin, radial, tangential, radius, play, centre) = (
        at("case"),
        at("dr_rp_mm"),
        at("dr_p_mm"),
        at("t_along_mm"),
        at("t_across_mm"),
        at("pin_moved"),
        at("pin_radial_mm"),
        at("pin_tangential_mm"),
        at("pin_radius_mm"),
        at("play_arcmin"),
        at("centre_arcmin"),
    );
    lines
        .filter_map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            let name = f[case];
            let grid = name.split_once("/grid")?.1.parse().ok()?;
            if name.starts_with("E") {
                return None;
            }
            let number = |i: usize| f[i].parse::<f64>().unwrap_or(0.0);
            Some(Reference {
                case: name.split('/').next().unwrap_or("").to_string(),
                equidistant: number(dr_rp),
                shift: number(dr_p),
                grid,
                along: number(along),
                across: number(across),
                pin: f[pin].parse().ok(),
                radial: number(radial),
                tangential: number(tangential),
                radius: number(radius),
                play: number(play),
                centre: number(centre),
            })
        })
        .collect()
}

/// Disc 1's window (play, centre) in disc arcmin for the reference row, on a grid of 8
/// points per pin pitch: the reference's φ0 = j·2π/320 is z_c·Θ_k for k = 7j mod 8
/// (39·7 ≡ 1 mod 8), where pin i' of the model is the reference's pin i' + ⌊39k/8⌋.
fn window(row: &Reference, zero: bool) -> (f64, f64) {
    thread_local! {
        static MODELS: std::cell::RefCell<Vec<((f64, f64), RvLostMotion)>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    let key = (row.equidistant, row.shift);
    let model = MODELS.with(|models| {
        let mut models = models.borrow_mut();
        if let Some((_, model)) = models.iter().find(|(k, _)| *k == key) {
            return model.clone();
        }
        let model = build(row);
        models.push((key, model.clone()));
        model
    });
    window_of(&model, row, zero)
}

/// The reference's RV-20E (document 000's Table 8, pins of 2 mm: the model's example) with
/// the row's modification, q = 8.
fn build(row: &Reference) -> RvLostMotion {
    let params = RvLostMotion::rv20e_params()
        .with_number("equidistant_modification_mm", row.equidistant)
        .with_number("shift_modification_mm", row.shift)
        .with_number("positions_per_pin", 8.0);
    RvLostMotion::from_params(&params).expect("valid")
}

/// [`window`] on `model`.
fn window_of(model: &RvLostMotion, row: &Reference, zero: bool) -> (f64, f64) {
    let k = (7 * row.grid) % 8;
    let mut x = vec![0.0; model.inputs().len()];
    let mut set = |name: String, value: f64| {
        x[model.input_index(&name).expect("input")] = value;
    };
    if !zero {
        // The toothing's translation, given in the eccentric frame at Θ_k: the runout's
        // phase in the disc frame is its angle less z_p·Θ_k = 2π·k/8.
        let size = row.along.hypot(row.across);
        if size > 0.0 {
            set("disc_runout_mm_1".into(), 2.0 * size);
            set(
                "disc_runout_phase_rad_1".into(),
                row.across.atan2(row.along) - 2.0 * PI * k as f64 / 8.0,
            );
        }
        if let Some(pin) = row.pin {
            let ours = (pin + 40 - (39 * k) / 8 % 40) % 40 + 1;
            set(format!("pin_radial_error_mm_{ours}"), row.radial);
            set(format!("pin_tangential_error_mm_{ours}"), row.tangential);
            set(format!("pin_radius_deviation_mm_{ours}"), row.radius);
        }
    }
    let [(lo, hi), _] = model.disc_windows(&x, k);
    let lambda = model.lambda();
    (
        (hi - lo) / lambda * ARCMIN,
        0.5 * (hi + lo) / lambda * ARCMIN,
    )
}

/// The model is first order in every clearance term (003's standard form for the
/// modification, projections on the pin normals for the deviations): the exact windows
/// differ by second-order terms of the modification (up to 20.6 µm) and the deviations (up
/// to 5 µm), which move the play by up to 0.0113 arcmin over these rows (1.2 % of a
/// 0.96 arcmin play) and the centre by up to 0.0023 arcmin. The accuracy claimed in
/// docs/models.md §14 and checked here: 0.015 arcmin on the play and its changes, 0.003
/// arcmin on the centre's changes, while the changes themselves reach 0.49 arcmin.
const PLAY_ACCURACY: f64 = 0.015;
const CENTRE_ACCURACY: f64 = 0.003;

#[test]
fn windows_follow_the_exact_profile() {
    let rows = reference();
    assert!(rows.len() > 200, "{} rows", rows.len());
    let mut largest_change: f64 = 0.0;
    for row in &rows {
        let base = rows
            .iter()
            .find(|r| {
                r.case == "A"
                    && r.grid == row.grid
                    && r.equidistant == row.equidistant
                    && r.shift == row.shift
            })
            .expect("its unperturbed row");
        let (play0, centre0) = window(row, true);
        let (play, centre) = window(row, false);
        let (d_play, d_centre) = (play - play0, centre - centre0);
        let (e_play, e_centre) = (row.play - base.play, row.centre - base.centre);
        let label = format!(
            "{} ({}, {}) grid {} t ({}, {}) pin {:?} ({}, {}, {})",
            row.case,
            row.equidistant,
            row.shift,
            row.grid,
            row.along,
            row.across,
            row.pin,
            row.radial,
            row.tangential,
            row.radius
        );
        assert!(
            (play - row.play).abs() <= PLAY_ACCURACY,
            "{label}: play {play} against {}",
            row.play
        );
        assert!(
            (d_play - e_play).abs() <= PLAY_ACCURACY,
            "{label}: play change {d_play} against {e_play}"
        );
        assert!(
            (d_centre - e_centre).abs() <= CENTRE_ACCURACY,
            "{label}: centre change {d_centre} against {e_centre}"
        );
        largest_change = largest_change.max(e_play.abs()).max(e_centre.abs());
    }
    // The comparison has teeth: the reference's changes are far larger than the accuracy.
    assert!(largest_change > 0.45, "{largest_change}");
}

#[test]
fn a_runout_turns_the_window_across_and_takes_play_along_as_the_exact_profile_does() {
    // The figures of the issue this model answers, on the tight profile (Δr_rp −0.010,
    // Δr_p −0.0206 mm) at every reference phase: 5 µm across turns the window by
    // t/(e·z_c) = 0.4897 arcmin and leaves the play (|change| < 0.002 arcmin); 5 µm along
    // takes between 0.1 and 0.2 arcmin of play away in either direction.
    let rows = reference();
    let tight: Vec<&Reference> = rows
        .iter()
        .filter(|r| r.case == "B" && r.shift == -0.0206)
        .collect();
    assert_eq!(tight.len(), 8 * 9);
    for row in tight {
        let (play0, centre0) = window(row, true);
        let (play, centre) = window(row, false);
        if row.across.abs() == 0.005 {
            assert!((play - play0).abs() < 0.002, "{} {}", play, play0);
            let turn = -row.across / (0.9 * 39.0) * ARCMIN;
            assert!(
                ((centre - centre0) - turn).abs() < 1e-9,
                "{centre} {centre0} {turn}"
            );
        }
        if row.along.abs() == 0.005 {
            assert!(
                (0.1..0.2).contains(&(play0 - play)),
                "{row_along}: {}",
                play0 - play,
                row_along = row.along
            );
        }
    }
}
