//! Tests of the transmission-error model on its shipped scenarios: document 002's literal
//! reading reproduces the one-disc model's figures bit for bit; the physical reading's
//! order amplitudes against the exact curve at 2^16 points with their aliasing bound;
//! peak-to-peak convergence with the point count; interference counted, not hidden; a
//! disc's window against the exact profile windows of tests/data/exact_profile_windows.csv.

use rvtol_engine::report::RunReport;
use rvtol_engine::{run, RunSettings};
use rvtol_models::{ErrorModel, ModelParams, ParamValue, RealFft, TransmissionError};
use rvtol_tests::scenario_path;

fn report(file: &str, samples: u64) -> serde_json::Value {
    let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
    let settings = RunSettings {
        samples,
        seed: scenario.seed,
        exact_percentile_limit: 8_000_000,
        sampling: Default::default(),
    };
    let result = run(&scenario, settings, &|_| {}).unwrap();
    serde_json::from_str(&RunReport::new(&scenario, result).to_json()).unwrap()
}

fn output<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|o| o["name"] == name)
        .unwrap_or_else(|| panic!("{name}"))
}

#[test]
fn document_002_reading_reproduces_the_one_disc_model() {
    // The figures of the one-disc model that the physical reading replaced, from its
    // binary (rvtol run scenarios/rv40e-transmission.json --samples 20000, seed 40, before
    // the two-disc change; the scenario is now rv40e-transmission-002.json with reading
    // "document_002"): mean, sd, median and maximum of every output, and 378,800 ppm of
    // peak-to-peak above 60″. Bit for bit (the literal reading runs the same arithmetic),
    // up to the last bit that reading a float from JSON may round: 2 ulp.
    let report = report("rv40e-transmission-002.json", 20_000);
    let expected: [(&str, [f64; 4]); 6] = [
        (
            "te_peak_to_peak_arcsec",
            [
                56.355286509208675,
                17.26982585937894,
                54.517736084426375,
                139.88057927162288,
            ],
        ),
        (
            "te_rms_arcsec",
            [
                13.08388193232722,
                5.304192083090712,
                12.267023268543952,
                43.01043171262814,
            ],
        ),
        (
            "te_mean_arcsec",
            [
                4.4033013220814885,
                7.615745047986673,
                4.463065565865793,
                34.69458376949902,
            ],
        ),
        (
            "te_order_1_arcsec",
            [
                15.95364863620937,
                8.416764474652052,
                14.901010671944459,
                60.44084579901898,
            ],
        ),
        (
            "te_order_39_arcsec",
            [
                1.491501403548338,
                0.8020855569708949,
                1.389131231338039,
                5.995110690999357,
            ],
        ),
        (
            "te_order_40_arcsec",
            [
                6.345232166639418,
                3.2964443532631664,
                5.9668720012797305,
                23.308711426695105,
            ],
        ),
    ];
    let same = |a: f64, b: f64| (a - b).abs() <= 2.0 * f64::EPSILON * b.abs();
    for (name, [mean, sd, median, max]) in expected {
        let o = output(&report, name);
        for (key, value, expected) in [
            ("mean", o["mean"].as_f64().unwrap(), mean),
            ("sd", o["sd"].as_f64().unwrap(), sd),
            ("median", o["percentiles"]["50"].as_f64().unwrap(), median),
            ("max", o["max"].as_f64().unwrap(), max),
        ] {
            assert!(same(value, expected), "{name} {key}: {value} vs {expected}");
        }
    }
    let pp = output(&report, "te_peak_to_peak_arcsec");
    assert_eq!(pp["ppm_out"].as_f64().unwrap(), 378_800.0);
}

#[test]
fn physical_scenario_runs_with_every_sample_counted() {
    // The shipped scenario reads the transmission error under load on the reducer's own
    // tight profile: every sample has one, also those whose discs do not fit between the
    // pins (crank pairing preloads them), which profile_interference counts as a fraction
    // and the preload rule judges; none is left out of the statistics.
    let report = report("rv40e-transmission.json", 2_000);
    let interference = output(&report, "profile_interference");
    assert!(interference["events"].as_u64().unwrap() > 0);
    let preloaded = output(&report, "preloaded")["events"].as_u64().unwrap();
    assert_eq!(preloaded, interference["events"].as_u64().unwrap());
    for o in report["outputs"].as_array().unwrap() {
        if o["kind"] == "continuous" {
            assert_eq!(o["non_finite"].as_u64().unwrap(), 0, "{}", o["name"]);
        }
    }
}

/// The RV40E model of the physical scenario at N points per revolution, with pin and
/// tooth-space errors, in the rigid first contact (the reading these tests check: its
/// tabulated curve, refined extremes and orders against the exact geometry).
/// The shipped RV40E in the rigid first contact, its discs 12 mm apart: the geometry these
/// tests' busy rows and figures were measured on (the reducer's own spacing is 11 mm; at
/// 11 mm the row of `peak_to_peak_converges_with_the_point_count` has two maxima within
/// 0.23″ of each other, and the refinement at 4096 points, which follows the sampled
/// maximum's branch, finds the lower one: 27.99″ against at least 28.22″).
fn rv40e(points: usize) -> TransmissionError {
    let params = crate::common::model_params("rv40e-transmission.json")
        .with_number("points_per_revolution", points as f64)
        .with_number("crank_eccentric_spacing_mm", 12.0)
        .with("disc_contact", ParamValue::Text("first_contact".into()));
    TransmissionError::from_params(&params).unwrap()
}

/// A row with 003's modification and every error a few µm (tilts a few µm over 12 mm),
/// from a fixed xorshift stream.
fn busy_row(model: &TransmissionError, seed: u64) -> Vec<f64> {
    let mut state = seed;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    model
        .inputs()
        .iter()
        .map(|input| match input.name.as_str() {
            "equidistant_modification_mm" => 0.01,
            "shift_modification_mm" => -0.008,
            _ if input.unit == "rad" => 0.004 / 12.0 * next(),
            _ => 0.004 * next(),
        })
        .collect()
}

fn evaluate(model: &TransmissionError, row: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; model.outputs().len()];
    model.evaluate(row, &mut out);
    out
}

/// Points of the reference curve: the contact's harmonics decay like 1/k² past the mesh
/// order 1560, so that at 2^16 points every harmonic that matters is resolved.
const REFERENCE: usize = 1 << 16;

#[test]
fn order_amplitudes_against_the_exact_curve_with_their_aliasing_bound() {
    // The outputs' order amplitudes are the DFT of the N = 4096-point curve; the DFT of N
    // samples at order k is the sum of the true coefficients at k and at m·N ± k (m ≥ 1).
    // The exact curve at 2^16 points resolves those up to 32768: the difference between
    // the 4096-point amplitude and the 2^16-point one is bounded by the 2^16 spectrum's
    // amplitudes at 4096·m ± k, m = 1..7 (plus rounding, 1e-9″). The bound is below
    // 0.005″ or 0.5 % of the amplitude, whichever is larger: stated in docs/models.md §12.
    let model = rv40e(4096);
    let names: Vec<String> = model.outputs().iter().map(|o| o.name.clone()).collect();
    let fft = RealFft::new(REFERENCE);
    let mut work = vec![(0.0, 0.0); REFERENCE / 2];
    for seed in [1, 2, 3] {
        let row = busy_row(&model, seed);
        let out = evaluate(&model, &row);
        assert_eq!(out[8], 0.0, "seed {seed}: no interference");
        let exact = model.exact_curve(&row, REFERENCE).unwrap();
        fft.transform(&exact, &mut work);
        for (index, order) in [(3, 1), (4, 39), (5, 40), (6, 78), (7, 80)] {
            let reference = fft.amplitude(&work, order);
            let aliases: f64 = (1..8)
                .map(|m| {
                    fft.amplitude(&work, 4096 * m - order) + fft.amplitude(&work, 4096 * m + order)
                })
                .sum();
            let difference = (out[index] - reference).abs();
            assert!(
                difference <= aliases + 1e-9,
                "seed {seed} {}: {} vs {reference}, bound {aliases}",
                names[index],
                out[index]
            );
            assert!(
                aliases <= 5e-3 * reference.max(1.0),
                "seed {seed} order {order}: aliases {aliases} of {reference}"
            );
        }
    }
}

#[test]
fn peak_to_peak_converges_with_the_point_count() {
    // The curve is continuous with slopes bounded by L (measured on the exact curve at
    // 2^16 points as max |ΔTE|/h): sampled at spacing h its extremes lie within L·h/2 of
    // the true ones, so the true p-p exceeds the sampled one by at most L·h: O(1/N), and
    // the exact curve at 2^16 points bounds it from above. The refinement of the extremes
    // on the exact geometry moves them only towards the true ones (its maximum is the
    // value of one contact branch, a lower bound of TE; its minimum a value of TE), so
    // every refined p-p is a lower bound of the true one, at least the sampled one. With
    // the best of them as the truth's floor: the sampled p-p at every N lies within L·h_N
    // of it, and the refined p-p at N = 4096 comes closer to it than the sampled p-p at
    // N = 65536 (the refinement is worth more than 16 times the points).
    let reference_model = rv40e(4096);
    let row = busy_row(&reference_model, 7);
    let exact = reference_model.exact_curve(&row, REFERENCE).unwrap();
    let h = 2.0 * std::f64::consts::PI / REFERENCE as f64;
    let slope = (0..REFERENCE)
        .map(|j| (exact[(j + 1) % REFERENCE] - exact[j]).abs() / h)
        .fold(0.0, f64::max);
    let (lo, hi) = exact
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let ceiling = hi - lo + slope * h;
    let mut figures = Vec::new();
    for points in [4096, 8192, 16384, 32768, 65536] {
        let model = rv40e(points);
        let refined = evaluate(&model, &row)[0];
        let curve = model.curve(&row);
        let sampled = curve.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - curve.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(
            sampled <= refined + 1e-12 && refined <= ceiling,
            "{points}: sampled {sampled}, refined {refined}, true ≤ {ceiling}"
        );
        figures.push((points, sampled, refined));
    }
    let floor = figures
        .iter()
        .map(|f| f.2)
        .fold(f64::NEG_INFINITY, f64::max);
    for &(points, sampled, _) in &figures {
        let spacing = 2.0 * std::f64::consts::PI / points as f64;
        assert!(
            floor - sampled <= slope * spacing,
            "{points}: sampled {sampled} more than L·h = {} below {floor}",
            slope * spacing
        );
    }
    let (refined_at_4096, sampled_at_65536) = (figures[0].2, figures[4].1);
    assert!(
        floor - refined_at_4096 < floor - sampled_at_65536,
        "refined at 4096 {refined_at_4096}, sampled at 65536 {sampled_at_65536}, floor {floor}"
    );
}

#[test]
fn an_interfering_sample_is_counted_not_reported_as_a_huge_lag() {
    // Disc 1 20 µm too full: 002's literal reading gives a lead of thousands of
    // arcseconds over the short-lever pins; the physical reading flags the sample (see
    // the unit test in crates/models for the play 2δ* = 126.9″ it exceeds).
    let model = rv40e(4096);
    let mut row = busy_row(&model, 11);
    let index = model
        .inputs()
        .iter()
        .position(|i| i.name == "profile_normal_error_mm_1")
        .unwrap();
    row[index] = -0.020;
    let out = evaluate(&model, &row);
    assert_eq!(out[8], 1.0);
    assert!(out[..8].iter().all(|v| v.is_nan()));
}

/// One row of tests/data/exact_profile_windows.csv, the fields this test reads.
struct WindowRow {
    case: String,
    dr_rp: f64,
    dr_p: f64,
    phi0: f64,
    t_along: f64,
    t_across: f64,
    /// The pin changed (0-based, housing angle 2π·i/40 + φ0), if any.
    pin: Option<usize>,
    pin_radial: f64,
    pin_tangential: f64,
    pin_radius: f64,
    beta: (f64, f64),
    d_beta: (f64, f64),
}

fn exact_profile_windows() -> Vec<WindowRow> {
    let path = crate::common::workspace_dir().join("tests/data/exact_profile_windows.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let number = |fields: &[&str], name: &str| -> f64 { fields[column(name)].parse().unwrap() };
    lines
        .map(|line| line.split(',').collect::<Vec<_>>())
        // E2 rows are closed forms without a pin phase.
        .filter(|fields| !fields[column("phi0_rad")].is_empty())
        .map(|fields| WindowRow {
            case: fields[column("case")].to_string(),
            dr_rp: number(&fields, "dr_rp_mm"),
            dr_p: number(&fields, "dr_p_mm"),
            phi0: number(&fields, "phi0_rad"),
            t_along: number(&fields, "t_along_mm"),
            t_across: number(&fields, "t_across_mm"),
            pin: fields[column("pin_moved")].parse().ok(),
            pin_radial: number(&fields, "pin_radial_mm"),
            pin_tangential: number(&fields, "pin_tangential_mm"),
            pin_radius: number(&fields, "pin_radius_mm"),
            beta: (
                number(&fields, "beta_lo_rad"),
                number(&fields, "beta_hi_rad"),
            ),
            d_beta: (
                number(&fields, "d_beta_lo_rad"),
                number(&fields, "d_beta_hi_rad"),
            ),
        })
        .collect()
}

#[test]
fn disc_windows_move_as_the_exact_profile_windows_do() {
    // tests/data/exact_profile_windows.csv: one RV-20E disc's rotational window [β_lo, β_hi]
    // among its 40 pins from the exact profile (z_p 40, z_c 39, r_p 52 mm, e 0.9 mm; β > 0
    // counter-clockwise, closing the gaps of the pins with sin φ > 0, which set β_hi), and
    // the same in the first-order model (rows E1:…). Disc 1 of the physical reading on that
    // geometry (module and crank circle any consistent values: they do not reach a window)
    // has the window [κ·(C − K), κ·(C + L)]: u = window/κ is the disc's turn past its mesh,
    // β, the lower end set by the pins with l < 0, the upper by those with l > 0 (docs/
    // models.md §12.4). Its origin is the disc turned into drive-flank contact, δ* =
    // (Δr_rp − Δr_p·√(1 − K1²))/(e·z_c) clockwise of the reference's centred disc.
    //
    // Frames: the model puts pin i (0-based) at φ = 2π·i/z_p + z_c·Θ from disc 1's
    // eccentric, the reference at 2π·i/z_p + φ0: Θ = φ0/z_c. The reference's toothing
    // translation (t_along, t_across) in the eccentric frame is the disc runout r_1 =
    // R(−z_p·Θ)·(t_along, t_across) (disc frame, which the model turns by z_p·Θ into the
    // eccentric frame); its pin moves are the pin's radial and tangential errors; its pin
    // radius δ on pin i is the radial error −δ·S_i/(1 − K1·cos φ_i), which changes that
    // pin's clearance by −δ as the larger pin does (the model has no per-pin radius).
    //
    // 1. Against the first-order rows (E1): u − δ* equals [β_lo, β_hi] to rounding
    //    (1e-12 rad), every modification, phase, translation and pin move.
    // 2. Against the exact rows: the changes of u's ends equal the reference's d_beta_lo,
    //    d_beta_hi to first order: within 0.005 arcmin + 10 % of the change (the changes
    //    are 5 µm at most, up to 0.49 arcmin; the reference's own first-order rows differ
    //    from its exact ones by at most 0.0039 arcmin, where an outward pin move hands the
    //    limit to the neighbouring pin on the tight profile, and by 10 % of the change for
    //    a translation along the eccentric). With the lower end set by the l > 0 pins, as
    //    before this test, a 5 µm larger pin on that side would move the lower end up by
    //    0.49 arcmin where the reference moves the upper end down by as much.
    let (zp, zc, r_p, e) = (40.0, 39.0, 52.0, 0.9);
    let params = ModelParams::new()
        .with_number("crank_circle_radius_mm", 27.5)
        .with_number("crank_eccentric_spacing_mm", 12.0)
        .with_number("sun_teeth", 9.0)
        .with_number("planet_teeth", 27.0)
        .with_number("module_mm", 1.0)
        .with_number("pin_count", zp)
        .with_number("cycloid_teeth", zc)
        .with_number("pin_circle_radius_mm", r_p)
        .with_number("eccentricity_mm", e)
        .with_number("pin_radius_mm", 2.0)
        .with_number("disc_face_width_mm", 8.0)
        .with_number("rated_torque_nm", 167.0)
        .with_number("pin_position_errors", 1.0)
        // The rigid windows are what the exact profile's are compared with.
        .with("disc_contact", ParamValue::Text("first_contact".into()));
    let model = TransmissionError::from_params(&params).unwrap();
    let kappa = zc / (zp + 9.0 / 27.0);
    let k1 = e * zp / r_p;
    let arcmin = std::f64::consts::PI / 10800.0;
    let index = |name: &str| model.input_index(name).unwrap_or_else(|| panic!("{name}"));
    // u = window/κ of disc 1 for one row, with or without its change.
    let window = |row: &WindowRow, changed: bool| -> (f64, f64) {
        let theta = row.phi0 / zc;
        let mut inputs = vec![0.0; model.inputs().len()];
        inputs[index("equidistant_modification_mm")] = row.dr_rp;
        inputs[index("shift_modification_mm")] = row.dr_p;
        if changed {
            let (s, c) = (zp * theta).sin_cos();
            inputs[index("disc_runout_x_mm_1")] = row.t_along * c + row.t_across * s;
            inputs[index("disc_runout_y_mm_1")] = -row.t_along * s + row.t_across * c;
            if let Some(i) = row.pin {
                let phi = 2.0 * std::f64::consts::PI * i as f64 / zp + row.phi0;
                let s_i = (1.0 + k1 * k1 - 2.0 * k1 * phi.cos()).sqrt();
                let radius_as_radial = -row.pin_radius * s_i / (1.0 - k1 * phi.cos());
                inputs[index(&format!("pin_radial_error_mm_{}", i + 1))] =
                    row.pin_radial + radius_as_radial;
                inputs[index(&format!("pin_tangential_error_mm_{}", i + 1))] = row.pin_tangential;
            }
        }
        let [(lo, hi), _] = model.disc_windows(&inputs, theta).unwrap();
        (lo / kappa, hi / kappa)
    };
    let rows = exact_profile_windows();
    let (mut first_order, mut exact) = (0, 0);
    for row in &rows {
        let changed = window(row, true);
        if row.case.starts_with("E1:") {
            let half_play = (row.dr_rp - row.dr_p * (1.0 - k1 * k1).sqrt()) / (e * zc);
            let (lo, hi) = (changed.0 - half_play, changed.1 - half_play);
            assert!(
                (lo - row.beta.0).abs() < 1e-12 && (hi - row.beta.1).abs() < 1e-12,
                "{} (t {}, {}): [{lo:e}, {hi:e}] against [{:e}, {:e}]",
                row.case,
                row.t_along,
                row.t_across,
                row.beta.0,
                row.beta.1
            );
            first_order += 1;
        } else {
            let base = window(row, false);
            let moved = (changed.0 - base.0, changed.1 - base.1);
            for (end, ours, theirs) in
                [("lo", moved.0, row.d_beta.0), ("hi", moved.1, row.d_beta.1)]
            {
                let tolerance = 0.005 * arcmin + 0.1 * theirs.abs();
                assert!(
                    (ours - theirs).abs() <= tolerance,
                    "{} (t {}, {}; pin {:?}: {}, {}, {}): β_{end} moves by {:.5} arcmin, the \
                     exact profile's by {:.5}",
                    row.case,
                    row.t_along,
                    row.t_across,
                    row.pin,
                    row.pin_radial,
                    row.pin_tangential,
                    row.pin_radius,
                    ours / arcmin,
                    theirs / arcmin
                );
            }
            exact += 1;
        }
    }
    assert_eq!((first_order, exact), (330, 330));
}

#[test]
fn assemblies_get_their_detail_and_spectrum_under_load() {
    // The shipped TE scenario reads under load: most drawn assemblies are preloaded or
    // interfere, and have no rigid first contact, so their detail and spectrum (at 2^16
    // points) come from the loaded solution too. Every curve of twelve drawn rows is
    // finite, and the detail's loaded total at every 16th point (2^16 against the curve's
    // 4096) is the curve's own at that point (two solutions of the same point, each
    // settled to 1e-13 rad: 1e-6 arcsec).
    use rand::SeedableRng;
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("rv40e-transmission.json")).unwrap();
    let n = scenario.input_space.n_columns();
    let rows = 12;
    let mut drawn = vec![0.0; rows * n];
    let mut counts = scenario.input_space.new_constraint_counts();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    scenario
        .input_space
        .sample_rows(&mut rng, &mut drawn, &mut counts)
        .unwrap();
    let model = &scenario.models[0];
    let mut interfering = 0;
    for row in drawn.chunks_exact(n) {
        let x = model.inputs_of_row(row, &[]);
        let curves = model.model.curves(&x);
        for curve in &curves {
            assert_eq!(curve.first_non_finite(), None, "{}", curve.name);
        }
        let (whole, detail) = (&curves[0], &curves[1]);
        assert!(detail.series[0].label.starts_with("total under load"));
        assert!(curves[2].series[0].label.starts_with("under load"));
        let (coarse, fine) = (&whole.series[0].points, &detail.series[0].points);
        for (j, point) in coarse
            .iter()
            .enumerate()
            .take_while(|(j, _)| 16 * j < fine.len())
        {
            let fine_point = fine[16 * j];
            assert!((point.0 - fine_point.0).abs() < 1e-9);
            assert!(
                (point.1 - fine_point.1).abs() < 1e-6,
                "point {j}: {} against {}",
                point.1,
                fine_point.1
            );
        }
        // The rows whose rigid first contact interferes: their rigid detail and spectrum
        // were NaN, and not drawn.
        let outputs = model.model.outputs();
        let flag = outputs
            .iter()
            .position(|o| o.name == "profile_interference")
            .unwrap();
        let mut out = vec![0.0; outputs.len()];
        model.model.evaluate(&x, &mut out);
        interfering += usize::from(out[flag] == 1.0);
    }
    assert!(
        interfering > 0,
        "no drawn row interferes: the test shows nothing"
    );
}
