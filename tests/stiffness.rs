//! The torsional compliance chain and the load models' disc torque on the shipped
//! scenarios: every element of the crank side against a hand calculation, the torque
//! balance in the contact, elastic and torsion models alike, the four-bar closure of
//! unequal cranks, what the disc's shift along its eccentric would change, and the
//! nominal figures of the three torsion scenarios (docs/models.md §10, §11, §13).

use rvtol_models::{
    assembly_preload, disc_web_compliance, hub_tilt_stiffness, net_force_compliance, BoltedJoint,
    Carrier, CrankElasticError, CrankShaft, CycloidPinContact, EndCompliance, ErrorModel,
    InvoluteStage, ModelParams, RollerRow, TaperedRow, TorsionCurve, TorsionTerms, ARCMIN_PER_RAD,
};
use rvtol_tests::scenario_path;
use std::f64::consts::PI;
use std::path::PathBuf;

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
    scenario.models[0].inputs_of_row(&row, &[])
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
    // Supports (30202 size: 13 rollers of 8.225 mm at 13°, 11.75 mm wide), preloaded by the
    // rule (stiffness/build.rs): at 3 % of rated, T_c = 2425.053 N·mm, τ = 44.0919 N,
    // |F|/m = 34.5449 N, A_A = 9/30.75 = 0.292683, reaction √(44.0919² + (34.5449·
    // 0.292683)²) = 45.2363 N, F_a0 = 45.2363·tan 13°/J(1) = 45.2363·0.230868/0.545495 =
    // 19.1452 N. At rated both supports carry √((1469.73·1)² + (1151.50·0.292683)²) =
    // 1507.88 N: J(x) = 1507.88·tan 13°/19.1452 = 18.1832 at x = 47.0225, δ_n0 =
    // (19.1452/(13·2.428147e5·sin 13°))^0.9 = 7.72108e-5 mm, δ_r = x·δ_n0/cos 13° =
    // 3.72615e-3 mm, 2.47112e-6 mm/N (unpreloaded: 2.53446e-6); plus the plate's seat
    // 0.462461/(206 000·11.75) = 1.91060e-7: 2.66218e-6 mm/N; weights 1 − x1/L = 0.646341
    // and 0.353659; symmetric 2.66218e-6, antisymmetric 0.292683·(0.646341 − 0.353659)·
    // 2.66218e-6 = 2.28050e-7; term 1.44982e-4 rad = 0.498410 arcmin.
    assert!(
        (side.support.preload / 19.1452 - 1.0).abs() < 1e-5,
        "{}",
        side.support.preload
    );
    assert!((side.support.radial_deflection(1507.8756) / 3.72615e-3 - 1.0).abs() < 1e-5);
    assert!((side.support_housing_compliance / 1.91060e-7 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.support) - 0.498410).abs() < 1e-5,
        "{}",
        arcmin(terms.support)
    );
    // The plates' paths from each seat (bore 35/2 mm) to the nearest pillar, s = 2·27.5·
    // sin 45° = 38.8909 mm: 0.279317·ln(38.8909/17.5)/(206 000·11.75) = 0.279317·0.798559/
    // 2 420 500 = 9.21508e-8 mm/N, weighted as the seats: 51.7390·9.21508e-8 + 31.7592·
    // 0.0856633·9.21508e-8 = 5.01850e-6 rad = 0.0172523 arcmin.
    assert!((side.seat_path_compliance / 9.21508e-8 - 1.0).abs() < 1e-5);
    assert!(
        (arcmin(terms.seat_path) - 0.0172523).abs() < 1e-6,
        "{}",
        arcmin(terms.seat_path)
    );
    // The disc web around the pillars' holes (stiffness/bodies.rs: c_web,S = 3.846930e-8,
    // c_web,A = 2.565422e-8 mm/N): 51.7390·3.846930e-8 + 31.7592·2.565422e-8 =
    // 2.80512e-6 rad = 0.00964330 arcmin.
    assert!((side.web_compliance.0 / 3.846930e-8 - 1.0).abs() < 1e-6);
    assert!((side.web_compliance.1 / 2.565422e-8 - 1.0).abs() < 1e-6);
    assert!(
        (arcmin(terms.disc_web) - 0.00964330).abs() < 1e-7,
        "{}",
        arcmin(terms.disc_web)
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
    // The end plate at the pillars' B ends. Its bolted joint (stiffness/joint.rs, M5 12.9 at
    // VDI 2230's 12 378.5 N on 97.2417 mm²): sliding 2.21801e-8 mm/N, rocking 1.51146e-9 and
    // twisting 9.17672e-10 rad/(N·mm) added to the root's: the guided beam with unequal
    // ends gives the lateral 8.09012e-6 mm/N (7.93352e-6 without), the twist 1.36346e-7,
    // K_c = 2.01625e8 N·mm/rad, and 3.68158e-6·(2.05415e8/2.01625e8 − 1)·51.7390 =
    // 3.58038e-6 rad = 0.0123084 arcmin. Its bending around the root (stiffness/plate.rs,
    // K_p = 1.00012e9 N·mm/rad added to the rocking): lateral 8.17692e-6, K_c = 1.99640e8,
    // 1.92906e-6 rad more = 0.00663163 arcmin.
    assert!(
        (1.0 / (1.0 / side.carrier_stiffness + side.end_plate_joint_compliance) / 2.01625e8 - 1.0)
            .abs()
            < 1e-5
    );
    assert!(
        (arcmin(terms.end_plate_joint) - 0.0123084).abs() < 1e-6,
        "{}",
        arcmin(terms.end_plate_joint)
    );
    assert!(
        (arcmin(terms.end_plate_bending) - 0.00663163).abs() < 1e-6,
        "{}",
        arcmin(terms.end_plate_bending)
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
    // (Within rounding: powi folded at compile time may round differently.)
    let roots = carrier.torsional_stiffness_on_elastic_roots(206_000.0, 0.3);
    assert!((side.carrier_stiffness / roots - 1.0).abs() < 1e-14);
    // The end plate: its bolted joint (M5 by the rule, VDI 2230's preload, Ito's C and m, the
    // cone through an 11.75 mm plate) and its bending around a hub of the root's radius,
    // clamped 38.8909 − 17.5 mm out.
    let joint = BoltedJoint {
        width: 11.0,
        depth: 11.0,
        hole: 5.5,
        cone: 8.5 + 2.0 * 11.75 * 0.348,
        preload: assembly_preload(5.0, 0.8, 0.12),
        coefficient: 0.046,
        exponent: 0.48,
    }
    .compliance(0.3);
    let bolted = carrier.torsional_stiffness_with_end_plate(206_000.0, 0.3, &joint);
    let joint_part = 1.0 / bolted - 1.0 / roots;
    assert!((side.end_plate_joint_compliance / joint_part - 1.0).abs() < 1e-9);
    let seat_to_pillar = (2.0 * 27.5 * 27.5 * (1.0 - (PI / 2.0).cos())).sqrt();
    let hub = (4.0 * 1220.0833333_f64 / PI).powf(0.25);
    let plate = hub_tilt_stiffness(hub, seat_to_pillar - 17.5, 11.75, 206_000.0, 0.3);
    let bent = EndCompliance {
        rocking: joint.rocking + 1.0 / plate,
        ..joint
    };
    let whole = carrier.torsional_stiffness_with_end_plate(206_000.0, 0.3, &bent);
    let bending_part = 1.0 / whole - 1.0 / bolted;
    assert!((side.end_plate_bending_compliance / bending_part - 1.0).abs() < 1e-9);
    let path = net_force_compliance(17.5, seat_to_pillar, 11.75, 206_000.0, 0.3);
    assert!((side.seat_path_compliance / path - 1.0).abs() < 1e-14);
    let hole = 0.5 * 11f64.hypot(11.0) + 0.9;
    let web = disc_web_compliance(2, 27.5, 27.5, hole, 8.0, 206_000.0, 0.3);
    assert!((side.web_compliance.0 / web.0 - 1.0).abs() < 1e-14);
    assert!((side.web_compliance.1 / web.1 - 1.0).abs() < 1e-14);
    // With body_compliance 0 the discs, the plates and the housing are rigid (rigidity
    // 75.01 N·m/arcmin on this scenario before the supports were preloaded, 74.99 with the
    // rule's light preload: its continuous load zone, 4.085 for Stribeck's 4.08 at
    // heavy load, docs/models.md §13).

    let rigid = TorsionCurve::from_params(
        &params_of("rv20e-torsion.json").with_number("body_compliance", 0.0),
    )
    .unwrap();
    let rigid_side = *rigid.crank_side();
    assert_eq!(rigid_side.bore_compliance, 0.0);
    assert_eq!(rigid_side.support_housing_compliance, 0.0);
    assert_eq!(rigid_side.web_compliance, (0.0, 0.0));
    assert_eq!(rigid_side.seat_path_compliance, 0.0);
    assert_eq!(rigid_side.end_plate_joint_compliance, 0.0);
    assert_eq!(rigid_side.end_plate_bending_compliance, 0.0);
    assert_eq!(
        rigid_side.carrier_stiffness,
        carrier.torsional_stiffness(206_000.0, 0.3)
    );
    let x = nominal_inputs("rv20e-torsion.json");
    let mut out = vec![0.0; rigid.outputs().len()];
    rigid.evaluate(&x, &mut out);
    assert!((out[2] / 74.9900 - 1.0).abs() < 2e-5, "{}", out[2]);
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

/// The names of the chain's terms, in the order of [`Figures::shares`] and the tables of
/// docs/models.md §13 and the README.
pub const TERMS: [&str; 12] = [
    "pins",
    "needle rows",
    "disc around the bores",
    "disc web (pillar holes)",
    "crank shaft",
    "support bearings and seats",
    "seats' paths to the pillars",
    "carrier (pillars on their roots)",
    "end plate's bolted joints",
    "end plate's bending",
    "housing around the pins",
    "involute stage",
];

/// A torsion scenario's figures at the design point (every error zero).
#[derive(Debug, Clone)]
pub struct Figures {
    /// Rigidity (N·m/arcmin), lost motion, hysteresis loss and angle at rated (arcmin).
    pub rigidity: f64,
    pub lost_motion: f64,
    pub hysteresis_loss: f64,
    pub angle_at_rated: f64,
    /// Each term's share of the frictionless 50–100 % slope, %, in [`TERMS`]' order.
    pub shares: [f64; 12],
    /// Each term's angle at rated torque, frictionless, arcmin.
    pub at_rated: [f64; 12],
}

fn term_values(terms: &TorsionTerms) -> [f64; 12] {
    let c = &terms.chain;
    [
        terms.pins,
        c.needle,
        c.disc_bore,
        c.disc_web,
        c.shaft,
        c.support,
        c.seat_path,
        c.carrier,
        c.end_plate_joint,
        c.end_plate_bending,
        c.housing,
        c.involute,
    ]
}

/// The figures of a shipped torsion scenario, or of its parameters changed by `edit`.
pub fn figures_with(file: &str, edit: &dyn Fn(ModelParams) -> ModelParams) -> Figures {
    let model = TorsionCurve::from_params(&edit(params_of(file))).unwrap();
    let x = nominal_inputs(file);
    let mut out = vec![0.0; model.outputs().len()];
    model.evaluate(&x, &mut out);
    let rated = model.rated_torque();
    let full = term_values(&model.breakdown(&x, rated).unwrap());
    let half = term_values(&model.breakdown(&x, 0.5 * rated).unwrap());
    let slope: f64 = full.iter().sum::<f64>() - half.iter().sum::<f64>();
    let mut shares = [0.0; 12];
    for (share, (f, h)) in shares.iter_mut().zip(full.iter().zip(half)) {
        *share = (f - h) / slope * 100.0;
    }
    Figures {
        rigidity: out[2],
        lost_motion: out[0],
        hysteresis_loss: out[1],
        angle_at_rated: out[4],
        shares,
        at_rated: full,
    }
}

/// The figures of a shipped torsion scenario.
pub fn figures(file: &str) -> Figures {
    figures_with(file, &|p| p)
}

#[test]
fn torsion_scenarios_nominal_figures() {
    // The nominal figures docs/models.md §13 and the README quote, pinned so that a change
    // of the model or of a scenario's dimensions is deliberate: rigidity (N·m/arcmin), lost
    // motion, hysteresis loss and angle at rated (arcmin). They follow from the dimensions
    // of the scenarios (rules of §13), not from the catalogue; §13 compares them with it.
    let all: Vec<(&str, Figures)> = [
        "rv20e-torsion.json",
        "rv40e-torsion.json",
        "rv80e-torsion.json",
    ]
    .iter()
    .map(|file| (*file, figures(file)))
    .collect();
    for (file, f) in &all {
        eprintln!(
            "{file}: rigidity {:.6}, lost motion {:.6}, hysteresis loss {:.6}, angle at rated {:.6}",
            f.rigidity, f.lost_motion, f.hysteresis_loss, f.angle_at_rated
        );
        for (name, (share, angle)) in TERMS.iter().zip(f.shares.iter().zip(f.at_rated)) {
            eprintln!("    {name}: {share:.2} % ({angle:.5} arcmin at rated)");
        }
    }
    for ((file, f), (rigidity, lost_motion, hysteresis_loss, angle)) in all.iter().zip([
        // The RV-20E's nominal is preloaded: its housing term is read against the zero-torque
        // forces of its own branch (was 61.2397, 0.453912, 0.280178, 2.92717 against the
        // frictionless ones), and its crank side from rest at zero torque too (the hysteresis
        // loss was 0.280178 while the crank side was read at T > 0 only).
        (61.2420, 0.453468, 0.294806, 2.92798),
        (141.008, 0.889675, 0.630372, 3.43030),
        (336.371, 0.713035, 0.495170, 2.74828),
    ]) {
        let close = |value: f64, pinned: f64| (value / pinned - 1.0).abs() < 2e-5;
        assert!(
            close(f.rigidity, rigidity),
            "{file}: rigidity {}",
            f.rigidity
        );
        assert!(
            close(f.lost_motion, lost_motion),
            "{file}: lost motion {}",
            f.lost_motion
        );
        assert!(
            close(f.hysteresis_loss, hysteresis_loss),
            "{file}: hysteresis loss {}",
            f.hysteresis_loss
        );
        assert!(
            close(f.angle_at_rated, angle),
            "{file}: angle {}",
            f.angle_at_rated
        );
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
        "support_bearing_outer_diameter_mm",
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
    // A longer span or longer pillars soften, as does a softer joint surface (Ito's C,
    // default 0.046).
    for key in [
        "crank_support_span_mm",
        "carrier_pillar_length_mm",
        "joint_deflection_coefficient",
    ] {
        let value = base.number(key, Some(0.046)).unwrap();
        let changed = rigidity(&base.clone().with_number(key, value * 1.1));
        eprintln!("{key}: {:+.2} %", (changed / reference - 1.0) * 100.0);
        assert!(changed < reference, "{key}");
    }
}

/// The three torsion scenarios with their catalogue figures (validation.md, "Real
/// reducers": the Nabtesco RV-E catalogue as validation.md quotes it; the RV-42N's for the
/// RV-40E's class): name, file, rigidity (N·m/arcmin).
pub const CATALOGUE: [(&str, &str, f64); 3] = [
    ("RV-20E", "rv20e-torsion.json", 49.0),
    ("RV-40E", "rv40e-torsion.json", 108.0),
    ("RV-80E", "rv80e-torsion.json", 196.0),
];

/// The aim of issue 29: rigidity within ±30 % of the catalogue.
const WITHIN: f64 = 0.30;

/// The factor in [0.75, 2] on the estimated dimensions `keys` of `file` (all scaled alike)
/// that brings the rigidity to `target`, by bisection (the rigidity is monotone in each);
/// `None` when no factor in that range reaches it or the model refuses the dimensions.
fn factor_for(file: &str, keys: &[&str], target: f64) -> Option<f64> {
    let rigidity = |factor: f64| -> Option<f64> {
        let mut p = params_of(file);
        for key in keys {
            let v = p.number(key, None).unwrap();
            p = p.with_number(key, v * factor);
        }
        let model = TorsionCurve::from_params(&p).ok()?;
        let x = nominal_inputs(file);
        let mut out = vec![0.0; model.outputs().len()];
        model.evaluate(&x, &mut out);
        Some(out[2])
    };
    let (mut lo, mut hi) = (0.75, 2.0);
    let rises = rigidity(1.1)? > rigidity(1.0)?;
    let above = |f: f64| rigidity(f).map(|r| (r > target) == rises);
    if above(lo)? || !above(hi)? {
        return None;
    }
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if above(mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The estimated dimensions whose change docs/models.md §13 gives for a size outside the
/// aim: (label, keys scaled together).
const LEVERS: [(&str, &[&str]); 4] = [
    ("eccentric journal d_j", &["crank_journal_diameter_mm"]),
    (
        "pillar section b × h",
        &["carrier_pillar_width_mm", "carrier_pillar_depth_mm"],
    ),
    ("pillar length L_p", &["carrier_pillar_length_mm"]),
    ("support span L", &["crank_support_span_mm"]),
];

#[test]
fn rigidity_against_the_catalogue() {
    // Issue 29's aim, rigidity within ±30 % of the catalogue: the RV-20E (1.250) holds it,
    // the RV-40E (1.306 against 108; 1.248 against the RV-42N's 113) misses it by 0.6 %, the
    // RV-80E with its three cranks (Yang 2021; scenarios/reducers/rv80e.json) by far
    // (1.716). What would bring each to 1.30 times its catalogue figure, one estimated
    // dimension at a time (docs/models.md §13): RV-40E, the journal 0.75 % thinner, or the
    // pillars' section 0.65 % smaller, or the pillars 1.1 % longer, or the support span
    // 1.0 % longer; RV-80E, no plausible single dimension (the pillars 1.65 times as long,
    // or the support span 1.51 times; the journal and the pillars' section not within
    // 0.75–2 times). The RV-80E's crank count decides: with two cranks (document 003's text)
    // it is 1.220.
    let ratios: Vec<f64> = CATALOGUE
        .iter()
        .map(|(_, file, catalogue)| figures(file).rigidity / catalogue)
        .collect();
    eprintln!("ratios {ratios:?}");
    assert!((ratios[0] - 1.2498).abs() < 1e-3, "{ratios:?}");
    assert!((ratios[1] - 1.3056).abs() < 1e-3, "{ratios:?}");
    assert!((ratios[2] - 1.7162).abs() < 1e-3, "{ratios:?}");
    assert!(ratios[0] < 1.0 + WITHIN);
    assert!(ratios[1] > 1.0 + WITHIN && ratios[1] * 108.0 / 113.0 < 1.0 + WITHIN);
    assert!(ratios[2] > 1.0 + WITHIN);
    let two = figures_with("rv80e-torsion.json", &|p| p.with_number("crank_count", 2.0));
    assert!(
        (two.rigidity / 196.0 - 1.2201).abs() < 1e-3,
        "{}",
        two.rigidity
    );
    for ((name, file, catalogue), pinned) in CATALOGUE[1..].iter().zip([
        [Some(0.9925), Some(0.9935), Some(1.0108), Some(1.0102)],
        [None, None, Some(1.6493), Some(1.5103)],
    ]) {
        let target = (1.0 + WITHIN) * catalogue;
        let factors: Vec<Option<f64>> = LEVERS
            .iter()
            .map(|(_, keys)| factor_for(file, keys, target))
            .collect();
        eprintln!("{name} to {target} N·m/arcmin: {factors:?}");
        for (factor, pinned) in factors.iter().zip(pinned) {
            match (factor, pinned) {
                (Some(f), Some(p)) => assert!((f - p).abs() < 2e-4, "{name}: {factors:?}"),
                (None, None) => {}
                _ => panic!("{name}: {factors:?}"),
            }
        }
    }
}

#[test]
fn support_preload_moves_the_angle_more_than_the_rigidity() {
    // The supports' preload (docs/models.md §13): the rule's light preload (every roller
    // loaded at 3 % of rated: 19.1 / 35.9 / 39.1 N) against none and against a setting
    // that keeps every roller loaded at rated (638 / 1197 / 1302 N): the rigidity (the
    // 50–100 % slope, where the rows' load zones are partial either way) moves by under
    // 0.1 % with the light preload and 8 % with the heavy one; the angle at rated by 0.4 %
    // and 8 %.
    for (name, file, _) in CATALOGUE {
        let model = torsion(file);
        let side = *model.crank_side();
        let rated = 0.5 * model.torque_factor() * model.rated_torque() * 1000.0;
        let heavy = TaperedRow::full_zone_preload(&side.support.row, side.support_load(rated));
        let base = figures(file);
        let none = figures_with(file, &|p| p.with_number("support_preload_n", 0.0));
        let rigid = figures_with(file, &|p| p.with_number("support_preload_n", heavy));
        eprintln!(
            "{name}: preload {:.1} N (heavy {heavy:.0} N): rigidity {:.2} / {:.2} / {:.2}, angle {:.3} / {:.3} / {:.3}, lost motion {:.3} / {:.3} / {:.3}",
            side.support.preload,
            base.rigidity,
            none.rigidity,
            rigid.rigidity,
            base.angle_at_rated,
            none.angle_at_rated,
            rigid.angle_at_rated,
            base.lost_motion,
            none.lost_motion,
            rigid.lost_motion
        );
        assert!((base.rigidity / none.rigidity - 1.0).abs() < 1e-3);
        assert!(rigid.rigidity / base.rigidity > 1.07 && rigid.rigidity / base.rigidity < 1.09);
        assert!(base.angle_at_rated < none.angle_at_rated);
        assert!(rigid.angle_at_rated / base.angle_at_rated < 0.93);
    }
}

/// The markdown of the torsion tables docs/models.md §13 and the README show: the figures
/// against the catalogue, each term's angle at rated and share of the slope, and the
/// shipped scenarios' runs.
pub fn torsion_tables() -> [String; 3] {
    let all: Vec<Figures> = CATALOGUE.iter().map(|(_, f, _)| figures(f)).collect();
    let mut figures_table = String::from(
        "| | RV-20E | RV-40E | RV-80E | catalogue (validation.md: Nabtesco RV-E) |\n|---|---|---|---|---|\n",
    );
    let row = |label: &str, values: Vec<String>, catalogue: &str| {
        format!("| {label} | {} | {catalogue} |\n", values.join(" | "))
    };
    figures_table += &row(
        "torsional rigidity (N·m/arcmin)",
        all.iter().map(|f| format!("{:.1}", f.rigidity)).collect(),
        "about 49 / 108 (RV-42N: 113) / 196",
    );
    figures_table += &row(
        "model / catalogue",
        all.iter()
            .zip(CATALOGUE)
            .map(|(f, (_, _, c))| format!("{:.2}", f.rigidity / c))
            .collect(),
        "aim 0.70–1.30 (RV-40E against the RV-42N: 1.27)",
    );
    figures_table += &row(
        "angle at rated torque (arcmin)",
        all.iter()
            .map(|f| format!("{:.2}", f.angle_at_rated))
            .collect(),
        "not stated",
    );
    figures_table += &row(
        "lost motion at ±3 % rated (arcmin)",
        all.iter()
            .map(|f| format!("{:.2}", f.lost_motion))
            .collect(),
        "≤ 1",
    );
    figures_table += &row(
        "hysteresis loss (arcmin)",
        all.iter()
            .map(|f| format!("{:.2}", f.hysteresis_loss))
            .collect(),
        "RV-42N: < 1",
    );
    figures_table += &row(
        "rigidity with rigid discs, plates, housing (`body_compliance` 0)",
        CATALOGUE
            .iter()
            .map(|(_, file, _)| {
                let rigid = figures_with(file, &|p| p.with_number("body_compliance", 0.0));
                format!("{:.1}", rigid.rigidity)
            })
            .collect(),
        "—",
    );
    let mut terms_table = String::from("| term | RV-20E | RV-40E | RV-80E |\n|---|---|---|---|\n");
    for (k, name) in TERMS.iter().enumerate() {
        let cells: Vec<String> = all
            .iter()
            .map(|f| format!("{:.3}, {:.1} %", f.at_rated[k], f.shares[k]))
            .collect();
        terms_table += &format!("| {name} | {} |\n", cells.join(" | "));
    }
    [figures_table, terms_table, runs_table()]
}

/// The shipped torsion scenarios run as shipped (100 000 samples, their seeds, two
/// threads: the result does not depend on the count): the docs' table of their outputs.
fn runs_table() -> String {
    let reports: Vec<serde_json::Value> = CATALOGUE
        .iter()
        .map(|(_, file, _)| {
            let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
            let settings = rvtol_engine::RunSettings {
                samples: scenario.samples,
                seed: scenario.seed,
                exact_percentile_limit: rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT,
                sampling: Default::default(),
            };
            serde_json::from_str(&rvtol_tests::run_with_threads(&scenario, settings, 2)).unwrap()
        })
        .collect();
    let output = |report: &serde_json::Value, name: &str| -> serde_json::Value {
        report["outputs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["name"] == name)
            .unwrap()
            .clone()
    };
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let mut table = format!(
        "| | RV-20E (seed {}) | RV-40E ({}) | RV-80E ({}) |\n|---|---|---|---|\n",
        reports[0]["seed"], reports[1]["seed"], reports[2]["seed"]
    );
    let mut line = |label: &str, cell: &dyn Fn(&serde_json::Value) -> String| {
        let cells: Vec<String> = reports.iter().map(cell).collect();
        table += &format!("| {label} | {} |\n", cells.join(" | "));
    };
    // The values' P99.865 (flagged ones included): among all the assemblies it is beyond
    // the limit, the over-preloaded ones lying beyond it (docs/models.md, "Conformity").
    line(
        "lost motion mean, sd, P99.865 of the values (arcmin)",
        &|r| {
            let o = output(r, "lost_motion_arcmin");
            assert!(o["percentiles"]["99.865"].is_null());
            format!(
                "{:.3}, {:.3}, {:.2}",
                number(&o["mean"]),
                number(&o["sd"]),
                number(&o["value_percentiles"]["99.865"])
            )
        },
    );
    line("out of spec (above 1 arcmin, or over-preloaded)", &|r| {
        format!(
            "{:.1} %",
            number(&output(r, "lost_motion_arcmin")["ppm_out"]) / 1e4
        )
    });
    line("hysteresis loss mean (arcmin)", &|r| {
        format!(
            "{:.3}",
            number(&output(r, "hysteresis_loss_arcmin")["mean"])
        )
    });
    line(
        "rigidity mean, sd (P0.135 … P99.865) (N·m/arcmin)",
        &|r| {
            let o = output(r, "torsional_rigidity_nm_per_arcmin");
            format!(
                "{:.1}, {:.1} ({:.1} … {:.1})",
                number(&o["mean"]),
                number(&o["sd"]),
                number(&o["percentiles"]["0.135"]),
                number(&o["percentiles"]["99.865"])
            )
        },
    );
    line("angle at rated mean (arcmin)", &|r| {
        format!("{:.2}", number(&output(r, "angle_at_rated_arcmin")["mean"]))
    });
    line("preloaded", &|r| {
        format!("{:.1} %", 100.0 * number(&output(r, "preloaded")["mean"]))
    });
    line("preload pin force P99.865 (N)", &|r| {
        format!(
            "{:.0}",
            number(&output(r, "preload_pin_force_n")["percentiles"]["99.865"])
        )
    });
    table
}

/// The content between `<!-- torsion-table: NAME -->` and the next
/// `<!-- /torsion-table -->` in `text`, for each NAME: its byte range.
fn torsion_blocks(text: &str, name: &str) -> Vec<std::ops::Range<usize>> {
    let open = format!("<!-- torsion-table: {name} -->\n");
    let mut found = Vec::new();
    let mut search = 0;
    while let Some(at) = text[search..].find(&open) {
        let start = search + at + open.len();
        let end = start
            + text[start..]
                .find("<!-- /torsion-table -->")
                .expect("a torsion table is closed by <!-- /torsion-table -->");
        found.push(start..end);
        search = end;
    }
    found
}

#[test]
fn torsion_tables_are_the_models_figures() {
    // The torsion curve's figures against the catalogue, its terms' shares and the shipped
    // scenarios' runs, in README.md and docs/models.md §13, as this module computes
    // them from the three shipped torsion scenarios. RVTOL_README_BLESS=1 rewrites them.
    let [figures, terms, runs] = torsion_tables();
    let bless = std::env::var_os("RVTOL_README_BLESS").is_some();
    let mut stale = Vec::new();
    for file in ["README.md", "docs/models.md"] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let mut updated = text.clone();
        let mut blocks: Vec<(std::ops::Range<usize>, &str)> = Vec::new();
        for (name, table) in [("figures", &figures), ("terms", &terms), ("runs", &runs)] {
            blocks.extend(
                torsion_blocks(&text, name)
                    .into_iter()
                    .map(|r| (r, table.as_str())),
            );
        }
        assert!(
            blocks.len() >= 2,
            "{file} shows the torsion figures and terms tables"
        );
        blocks.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
        for (range, table) in blocks {
            if text[range.clone()] != *table {
                stale.push(file);
                updated.replace_range(range, table);
            }
        }
        if bless && updated != text {
            std::fs::write(&path, updated).unwrap();
        }
    }
    assert!(
        bless || stale.is_empty(),
        "the torsion tables of {stale:?} differ from the model's figures; after a deliberate \
         change rerun with RVTOL_README_BLESS=1 and update the prose"
    );
}
