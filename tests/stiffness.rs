//! The torsional compliance chain and the load models' disc torque on the shipped
//! scenarios: every element of the crank side against a hand calculation, the torque
//! balance in the contact, elastic and torsion models alike, the four-bar closure of
//! unequal cranks, what the disc's shift along its eccentric would change, and the
//! nominal figures of the three torsion scenarios (docs/models.md §10, §11, §13).

use rvtol_models::{
    Carrier, CrankElasticError, CrankShaft, CycloidPinContact, ErrorModel, InvoluteStage,
    ModelParams, RollerRow, TorsionCurve, ARCMIN_PER_RAD,
};
use rvtol_tests::scenario_path;

/// The numeric parameters of the first model of a shipped scenario.
fn params_of(file: &str) -> ModelParams {
    crate::common::model_params(file)
}

/// The first model's inputs at the scenario's nominal (every deviation at its mean).
/// The model's inputs at the design point: every input at its mean, except the magnitudes
/// (pin-hole clearance, runout, cumulative pitch error), whose design value is 0 while the
/// mean of their laws (folded normal, Rayleigh) is not.
fn nominal_inputs(file: &str) -> Vec<f64> {
    let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
    let mut row = scenario.input_space.mean_row();
    for (column, info) in scenario.columns.iter().enumerate() {
        if [
            "pin_hole_clearance",
            "cycloid_radial_runout",
            "cycloid_cumulative_pitch_error",
        ]
        .contains(&info.name.as_str())
        {
            row[column] = 0.0;
        }
    }
    scenario.models[0].inputs_of_row(&row)
}

fn torsion(file: &str) -> TorsionCurve {
    TorsionCurve::from_params(&params_of(file)).unwrap()
}

#[test]
fn rv20e_crank_side_against_the_hand_calculation() {
    // The RV-20E of scenarios/rv20e-torsion.json at rated torque, 167 N·m, with the pin
    // resultant F = (T_c/(e·z_c), 0) (F_y set to 0 for the hand calculation). Steel:
    // E = 206 000 MPa, ν = 0.3, G = 79 230.8 MPa, κ = 6(1 + ν)/(7 + 6ν) = 0.886364.
    //
    // Loads: λ = (39/40)(1 − 1/141) = 0.968085, T_c = 0.5·λ·167 000 = 80 835.11 N·mm,
    // e·z_c = 0.9·39 = 35.1 mm, F_x = 2302.99 N; per crank (m = 2, a_w = 27.5 mm)
    // τ = T_c/(m·a_w) = 1469.73 N, |F|/m = 1151.50 N, rms G = 1867.10 N.
    // Output angle per unit compliance: symmetric λ·T_c/(m·a_w²) = 51.7390 N,
    // antisymmetric λ·F_x/(m·e·z_c) = 31.7592 N.
    let lambda: f64 = 39.0 / 40.0 * (1.0 - 1.0 / 141.0);
    let t_c = 0.5 * lambda * 167_000.0;
    assert!((t_c - 80_835.106).abs() < 1e-3);
    let force_x = t_c / 35.1;
    let side = *torsion("rv20e-torsion.json").crank_side();
    let terms = side.terms(t_c, (force_x, 0.0), 1.0, 167_000.0, lambda);
    let arcmin = |rad: f64| rad * ARCMIN_PER_RAD;
    // Needle row (15 needles of 6 mm): Q_max = 4.08·1867.10/15 = 507.850 N,
    // δ = 2·3.84e-5·507.850^0.9/6^0.8 = 4.98887e-3 mm, compliance 2.67199e-6 mm/N
    // (374 252 N/mm), term (51.7390 + 31.7592)·2.67199e-6 = 2.23107e-4 rad = 0.76698 arcmin.
    let q_max: f64 = 4.08 * 1867.0966 / 15.0;
    let needle_deflection = 2.0 * 3.84e-5 * q_max.powf(0.9) / 6f64.powf(0.8);
    assert!((needle_deflection - 4.98887e-3).abs() < 1e-8);
    assert!(
        (arcmin(terms.needle) - 0.76698).abs() < 1e-5,
        "{}",
        arcmin(terms.needle)
    );
    // Shaft (d = 15 mm, span 30.75 mm, eccentrics at x1 = 10.875 and x2 = 19.875 mm):
    // EI = 206 000·π·15⁴/64 = 5.11920e8 N·mm², κGA = 0.886364·79 230.8·176.715 = 1.24102e7 N;
    // w(x1; x1) = 1.55563e-6, w(x1; x2) = 1.19773e-6 mm/N (Roark Table 8.1 case 1e + shear),
    // c_S = 2.75336e-6, c_A = 3.57902e-7; term 51.7390·c_S + 31.7592·c_A = 1.53823e-4 rad
    // = 0.52880 arcmin.
    let shaft = side.shaft;
    assert!((shaft.bending_rigidity / 5.11920e8 - 1.0).abs() < 1e-5);
    assert!((shaft.shear_rigidity / 1.24102e7 - 1.0).abs() < 1e-5);
    let modes = shaft.modes();
    assert!((modes.symmetric / 2.75336e-6 - 1.0).abs() < 1e-5);
    assert!((modes.antisymmetric / 3.57902e-7 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.shaft) - 0.52880).abs() < 1e-5,
        "{}",
        arcmin(terms.shaft)
    );
    // Disc bore (the needle row's housing: bore 15/2 + 3 = 10.5 mm, rim 52 − 27.5 = 24.5 mm
    // from it, disc 8 mm thick): c_bore = (0.462461 + 0.279317·ln(24.5/10.5))/(206 000·8)
    // = 4.24227e-7 mm/N (stiffness.rs: Michell's ovalisation and Kelvin's net force); term
    // (51.7390 + 31.7592)·4.24227e-7 = 3.54221e-5 rad = 0.121772 arcmin.
    assert!((side.bore_compliance / 4.24227e-7 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.disc_bore) - 0.121772).abs() < 1e-6,
        "{}",
        arcmin(terms.disc_bore)
    );
    // Supports (30202 size: 13 rollers of 8.225 mm at 13°, 11.75 mm wide): shares
    // S_A = S_B = 1, A_A = 9/30.75 = 0.292683; rms loads √((1469.73·1)² + (1151.50·0.292683)²)
    // = 1507.88 N at both; row compliance 2.53446e-6 mm/N plus the plate's seat
    // 0.462461/(206 000·11.75) = 1.91060e-7, 2.72552e-6 mm/N; weights 1 − x1/L = 0.646341 and
    // 0.353659; symmetric 2.72552e-6, antisymmetric 0.292683·(0.646341 − 0.353659)·2.72552e-6
    // = 2.33477e-7; term 1.48430e-4 rad = 0.510268 arcmin (the row alone: 0.47450).
    let support_deflection = {
        let cos = 13f64.to_radians().cos();
        2.0 * 3.84e-5 * (4.08 * 1507.8756 / (13.0 * cos)).powf(0.9) / 8.225f64.powf(0.8) / cos
    };
    assert!((support_deflection / 1507.8756 / 2.53446e-6 - 1.0).abs() < 1e-5);
    assert!((side.support_housing_compliance / 1.91060e-7 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.support) - 0.510268).abs() < 1e-5,
        "{}",
        arcmin(terms.support)
    );
    // Carrier (two 11 × 11 mm pillars, 19 mm, on 27.5 mm), each pillar on its two roots
    // (stiffness.rs: the section a rigid footing on a half-space): lateral 19³/(12EI) +
    // 19/((5/6)G·121) + 2/K_h + 19²/(2K_r) = 4.65241e-6 + 8.6433e-7 + 2.41678e-6 =
    // 7.93352e-6 mm/N; twist β = 1/3 − 0.21·(1 − 1/12) = 0.140833, 19/(G·0.140833·11⁴) +
    // 2/K_t = 1.35429e-7 rad/(N·mm); K_c = 2·(27.5²/7.93352e-6 + 1/1.35429e-7) = 2.05415e8
    // N·mm/rad (rigid plates: 3.42297e8); the far support's shift reaches the eccentric
    // planes by (x1 + x2)/(2L) = 0.5 on average, so m·S_B·a_w²·0.5/K_c = 3.68158e-6 mm/N;
    // term 51.7390·3.68158e-6 = 1.90481e-4 rad = 0.654826 arcmin (rigid plates: 0.39297).
    assert!((side.carrier_stiffness / 2.05415e8 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.carrier) - 0.654826).abs() < 1e-5,
        "{}",
        arcmin(terms.carrier)
    );
    // Involute stage (z1 12, z2 42, i 141, r_b2 = 27.5·42/54·cos 20° = 20.0990 mm, b = 8 mm,
    // c_γ = 20 N/(mm·µm), crank torsion over 10.875 + 15.375 mm with GJ = G·π·15⁴/32):
    // C_inv = (42/(12·141))²·(1/(20 000·8·20.0990²) + 26.25/GJ)/2 = 2.53036e-11 rad/(N·mm);
    // term at 167 000 N·mm 4.22570e-6 rad = 0.014527 arcmin.
    assert!((side.involute_compliance / 2.53036e-11 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.involute) - 0.014527).abs() < 1e-6,
        "{}",
        arcmin(terms.involute)
    );
}

#[test]
fn crank_side_parts_build_from_their_dimensions() {
    // The public pieces the models assemble, from the same dimensions: the same numbers.
    let side = *torsion("rv20e-torsion.json").crank_side();
    assert_eq!(
        side.bore_compliance,
        RollerRow::ringless_housing_compliance(10.5, 24.5, 8.0, 206_000.0, 0.3)
    );
    assert_eq!(
        side.support_housing_compliance,
        RollerRow::housing_ovalisation_compliance(11.75, 206_000.0, 0.3)
    );
    let shaft = CrankShaft::new(15.0, 30.75, 9.0, 206_000.0, 0.3);
    assert_eq!(side.shaft, shaft);
    assert_eq!(
        side.needle,
        RollerRow {
            rollers: 15.0,
            length: 6.0,
            contact_angle: 0.0
        }
    );
    let carrier = Carrier {
        pillars: 2.0,
        radius: 27.5,
        width: 11.0,
        depth: 11.0,
        length: 19.0,
    };
    assert_eq!(
        side.carrier_stiffness,
        carrier.torsional_stiffness_on_elastic_roots(206_000.0, 0.3)
    );
    // With body_compliance 0 the disc and the plates are rigid: the chain before they were
    // added (rigidity 75.0 N·m/arcmin on this scenario, docs/models.md §13).
    let rigid = TorsionCurve::from_params(
        &params_of("rv20e-torsion.json").with_number("body_compliance", 0.0),
    )
    .unwrap();
    let rigid_side = *rigid.crank_side();
    assert_eq!(rigid_side.bore_compliance, 0.0);
    assert_eq!(rigid_side.support_housing_compliance, 0.0);
    assert_eq!(
        rigid_side.carrier_stiffness,
        carrier.torsional_stiffness(206_000.0, 0.3)
    );
    let x = nominal_inputs("rv20e-torsion.json");
    let mut out = vec![0.0; rigid.outputs().len()];
    rigid.evaluate(&x, &mut out);
    assert!((out[2] / 75.0063 - 1.0).abs() < 2e-5, "{}", out[2]);
    let involute = InvoluteStage {
        sun_teeth: 12.0,
        planet_teeth: 42.0,
        cranks: 2.0,
        planet_base_radius: 27.5 * 42.0 / 54.0 * 20f64.to_radians().cos(),
        face_width: 8.0,
        mesh_stiffness: 20_000.0,
        torsion_length: 10.875 + 0.5 * 30.75,
    };
    assert_eq!(
        side.involute_compliance,
        involute.output_compliance(141.0, shaft.torsional_rigidity)
    );
}

#[test]
fn every_load_model_carries_the_balanced_disc_torque() {
    // The torque balance (docs/models.md §10): the housing takes T·(1 − 1/i), the pins'
    // moment about the disc centre is z_c/z_p of theirs about the axis, so one disc carries
    // share·λ·T, λ = (z_c/z_p)(1 − 1/i), 3.4 % below the share·T of 003 and 004.
    // Contact (RV-80E, i 121): F_x·e·z_c = 0.55·λ·800 N·m.
    let contact = CycloidPinContact::from_params(&params_of("rv80e-contact.json")).unwrap();
    let lambda_80: f64 = 39.0 / 40.0 * (1.0 - 1.0 / 121.0);
    assert!((contact.torque_factor() - lambda_80).abs() < 1e-15);
    let mut out = vec![0.0; contact.outputs().len()];
    let inputs = nominal_inputs("rv80e-contact.json");
    contact.evaluate(&inputs, &mut out);
    let t_c = 0.55 * lambda_80 * 800_000.0;
    assert!(
        (out[4] * 1.5 * 39.0 / t_c - 1.0).abs() < 1e-12,
        "{}",
        out[4]
    );
    // Elastic (RV-40E, i 121, e·z_c = 1.25·39 = 48.75 mm): with a constant k = 3e5 N/mm on
    // both cranks the lag is
    // λ·T_c·(1/(2k·a_w²) + 1/(2k·(e·z_c)²)), T_c = 0.5·λ·412 N·m.
    let elastic = CrankElasticError::from_params(
        &params_of("rv40e-elastic.json").with_number("crank_bearing_stiffness_n_per_mm", 3e5),
    )
    .unwrap();
    let lambda_40: f64 = 39.0 / 40.0 * (1.0 - 1.0 / 121.0);
    assert!((elastic.torque_factor() - lambda_40).abs() < 1e-15);
    let inputs = nominal_inputs("rv40e-elastic.json");
    let mut out = vec![0.0; elastic.outputs().len()];
    elastic.evaluate(&inputs, &mut out);
    let t_c = 0.5 * lambda_40 * 412_000.0;
    let hand = lambda_40 * t_c * (1.0 / (6e5 * 36.0 * 36.0) + 1.0 / (6e5 * 48.75 * 48.75));
    assert!(
        (out[0] / (hand * ARCMIN_PER_RAD) - 1.0).abs() < 1e-12,
        "{}",
        out[0]
    );
    // Torsion (RV-20E, i 141): its embedded contact model has the same λ (the unit test
    // unmodified_pins_give_the_closed_form checks its pins against F_max = T_c·max l_i/Σ l_i²
    // with T_c = 0.5·λ·T).
    let model = torsion("rv20e-torsion.json");
    let lambda_20 = 39.0 / 40.0 * (1.0 - 1.0 / 141.0);
    assert!((model.torque_factor() - lambda_20).abs() < 1e-15);
}

#[test]
fn unequal_eccentrics_turn_each_disc_by_the_four_bar_closure() {
    // scenarios/rv40e-elastic.json's model, no load, eccentricities +δ and −δ on the two
    // cranks (equal and opposite): each disc turns by (q1 − q2)⊥/(2·a_w) = δ·sin θ/a_w over
    // the crank turn, max − min 2δ/a_w, reaching the output times λ; the two discs turn
    // opposite ways, so the output does not.
    let model = CrankElasticError::from_params(&params_of("rv40e-elastic.json")).unwrap();
    let mut inputs = nominal_inputs("rv40e-elastic.json");
    inputs[0] = 0.0;
    let delta = 0.005;
    let names: Vec<String> = model.inputs().iter().map(|i| i.name.clone()).collect();
    let at = |name: &str| names.iter().position(|n| n == name).unwrap();
    inputs[at("eccentricity_error_mm_1")] = delta;
    inputs[at("eccentricity_error_mm_2")] = -delta;
    let mut out = vec![0.0; model.outputs().len()];
    model.evaluate(&inputs, &mut out);
    let lambda = model.torque_factor();
    let expected = 2.0 * lambda * delta / 36.0 * ARCMIN_PER_RAD;
    assert!(
        (out[5] / expected - 1.0).abs() < 1e-12,
        "{} vs {expected}",
        out[5]
    );
    assert!(out[1] < 1e-12, "{}", out[1]);
    for state in model.turn(&inputs) {
        let closure = -lambda * (-2.0 * delta * state.theta.sin()) / (2.0 * 36.0);
        assert!((state.four_bar[0] - closure).abs() < 1e-15);
        assert!((state.four_bar[1] + closure).abs() < 1e-15);
    }
}

#[test]
fn the_discs_shift_along_its_eccentric_hardly_moves_the_pins() {
    // docs/models.md §13 leaves out the disc's shift along its eccentric on its crank
    // bearings, t_y = −F_y·c_A/m, from the pins' load sharing. Check the claim on the RV-20E
    // (preloaded) and RV-40E nominals at rated torque: feeding t_y back as an eccentricity
    // change moves the pins' rotation by under 1 % of the whole elastic angle.
    for file in [
        "rv20e-torsion.json",
        "rv40e-torsion.json",
        "rv80e-torsion.json",
    ] {
        let params = params_of(file);
        let model = torsion(file);
        let side = *model.crank_side();
        let x = nominal_inputs(file);
        let rated = params.number("rated_torque_nm", None).unwrap();
        let cranks = params.number("crank_count", None).unwrap();
        let radius = params.number("crank_circle_radius_mm", None).unwrap();
        // The torsion model's contact keys only (the rest are not the contact model's).
        let keys = [
            "pin_count",
            "cycloid_teeth",
            "pin_circle_radius_mm",
            "pin_radius_mm",
            "eccentricity_mm",
            "disc_face_width_mm",
            "disc_load_share",
            "sun_teeth",
            "planet_teeth",
            "pin_friction_coefficient",
            "rated_torque_nm",
        ];
        let mut contact_params = ModelParams::new()
            .with_number("crank_count", cranks)
            .with_number("crank_circle_radius_mm", radius);
        for key in keys {
            if let Ok(v) = params.number(key, None) {
                contact_params = contact_params.with_number(key, v);
            }
        }
        let contact = CycloidPinContact::from_params(&contact_params).unwrap();
        // The profile row of the nominal: 000's modification, no other error.
        let row = [rated, x[2], x[3], 0.0, 0.0, 0.0, 0.0];
        let solution = contact.solve(&row);
        let t_c = contact.disc_torque(rated);
        let (fx, fy) = solution.resultant;
        let g = (t_c / (cranks * radius)).hypot(fx.hypot(fy) / cranks);
        let compliance = side.needle.secant_compliance(g) + side.shaft.modes().antisymmetric;
        let shift = -fy * compliance / cranks;
        let shifted = contact.solve(&[rated, x[2], x[3], 0.0, 0.0, shift, 0.0]);
        let lambda = contact.torque_factor();
        let change = lambda * (shifted.rotation - solution.rotation) * ARCMIN_PER_RAD;
        let whole = model.breakdown(&x, rated).unwrap().total();
        assert!(
            change.abs() < 0.01 * whole,
            "{file}: {change} arcmin of {whole}"
        );
    }
}

#[test]
fn torsion_scenarios_nominal_figures() {
    // The nominal figures docs/models.md §13 and the README quote, pinned so that a change
    // of the model or of a scenario's dimensions is deliberate: rigidity (N·m/arcmin), lost
    // motion, hysteresis loss and angle at rated (arcmin), and the terms' shares of the
    // frictionless 50–100 % slope. They follow from the dimensions of the scenarios (rules of
    // §13), not from the catalogue; §13 compares them with it.
    for (file, rigidity, lost_motion, hysteresis_loss, angle) in [
        ("rv20e-torsion.json", 63.1326, 0.468945, 0.280178, 2.86020),
        ("rv40e-torsion.json", 147.742, 0.896250, 0.630372, 3.29165),
        ("rv80e-torsion.json", 355.310, 0.714969, 0.495170, 2.61637),
    ] {
        let model = torsion(file);
        let x = nominal_inputs(file);
        let mut out = vec![0.0; model.outputs().len()];
        model.evaluate(&x, &mut out);
        eprintln!(
            "{file}: rigidity {:.6}, lost motion {:.6}, hysteresis loss {:.6}, angle at rated {:.6}",
            out[2], out[0], out[1], out[4]
        );
        let rated = model.rated_torque();
        let (full, half) = (
            model.breakdown(&x, rated).unwrap(),
            model.breakdown(&x, 0.5 * rated).unwrap(),
        );
        let slope = full.total() - half.total();
        let share = |a: f64, b: f64| (a - b) / slope * 100.0;
        eprintln!(
            "{file}: pins {:.1} %, needle {:.1} %, disc bore {:.1} %, shaft {:.1} %, support {:.1} %, carrier {:.1} %, involute {:.2} %; at rated {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.5} arcmin",
            share(full.pins, half.pins),
            share(full.chain.needle, half.chain.needle),
            share(full.chain.disc_bore, half.chain.disc_bore),
            share(full.chain.shaft, half.chain.shaft),
            share(full.chain.support, half.chain.support),
            share(full.chain.carrier, half.chain.carrier),
            share(full.chain.involute, half.chain.involute),
            full.pins,
            full.chain.needle,
            full.chain.disc_bore,
            full.chain.shaft,
            full.chain.support,
            full.chain.carrier,
            full.chain.involute,
        );
        let close = |value: f64, pinned: f64| (value / pinned - 1.0).abs() < 2e-5;
        assert!(close(out[2], rigidity), "{file}: rigidity {}", out[2]);
        assert!(close(out[0], lost_motion), "{file}: lost motion {}", out[0]);
        assert!(
            close(out[1], hysteresis_loss),
            "{file}: hysteresis loss {}",
            out[1]
        );
        assert!(close(out[4], angle), "{file}: angle {}", out[4]);
    }
}

#[test]
fn rigidity_rises_with_every_stiffening_dimension() {
    // Each estimated dimension made 10 % larger (or, for the contact angle, the roller
    // count), the rest kept: a stiffer part can only raise the rigidity. The relative
    // changes (printed) are docs/models.md §13's sensitivity table.
    let base = params_of("rv20e-torsion.json");
    let x = nominal_inputs("rv20e-torsion.json");
    let rigidity = |params: &ModelParams| {
        let model = TorsionCurve::from_params(params).unwrap();
        let mut out = vec![0.0; model.outputs().len()];
        model.evaluate(&x, &mut out);
        out[2]
    };
    let reference = rigidity(&base);
    for key in [
        "disc_face_width_mm",
        "crank_journal_diameter_mm",
        "needle_roller_count",
        "needle_roller_length_mm",
        "needle_roller_diameter_mm",
        "support_roller_count",
        "support_roller_length_mm",
        "support_bearing_width_mm",
        "carrier_pillar_width_mm",
        "carrier_pillar_depth_mm",
        "planet_face_width_mm",
    ] {
        let value = base.number(key, None).unwrap();
        let scaled = if key.ends_with("count") {
            (value * 1.1).round()
        } else {
            value * 1.1
        };
        let changed = rigidity(&base.clone().with_number(key, scaled));
        eprintln!("{key}: {:+.2} %", (changed / reference - 1.0) * 100.0);
        assert!(changed > reference, "{key}: {changed} vs {reference}");
    }
    // A longer span or longer pillars soften.
    for key in ["crank_support_span_mm", "carrier_pillar_length_mm"] {
        let value = base.number(key, None).unwrap();
        let changed = rigidity(&base.clone().with_number(key, value * 1.1));
        eprintln!("{key}: {:+.2} %", (changed / reference - 1.0) * 100.0);
        assert!(changed < reference, "{key}");
    }
}
