//! Tests of the one preload rule: its pieces against their definitions, and the same class
//! for the same reducer with the same deviations in every model that judges preload
//! (issue test (e)).

use super::*;
use crate::{ErrorModel, GeometricHysteresis, ModelParams, ParamValue};

/// The RV-20E's stage (000 Table 8; K1 derived) with 2 mm pins, 8 mm faces, μ 0.02 and
/// 167 N·m rated (the shipped scenarios' values).
fn rule(extra: &[(&str, f64)]) -> PreloadRule {
    let mut params = ModelParams::new()
        .with_number("pin_count", 40.0)
        .with_number("cycloid_teeth", 39.0)
        .with_number("pin_circle_radius_mm", 52.0)
        .with_number("eccentricity_mm", 0.9)
        .with_number("pin_friction_coefficient", 0.02)
        .with_number("rated_torque_nm", 167.0);
    for &(key, value) in extra {
        params = params.with_number(key, value);
    }
    let stage = CycloidStage::from_params(&params, MAX_PINS).unwrap();
    let ratio = 1.0 + 42.0 / 12.0 * 40.0;
    let lambda = 39.0 / 40.0 * (1.0 - 1.0 / ratio);
    PreloadRule::from_params(&params, &stage, 2.0, 8.0, (ratio, lambda)).unwrap()
}

/// One disc's design pins (Table 9's equidistant amount, the shift `shift`) as the
/// balance of a pair reads them.
fn design_disc(rule: &PreloadRule, shift: f64) -> (Vec<f64>, DiscPins) {
    let c = &rule.columns;
    let gaps: Vec<f64> = (0..c.index.len())
        .map(|j| -0.010 * c.equidistant[j] + shift * c.shift[j])
        .collect();
    let mut disc = DiscPins::new(0.0, 0.0);
    for (j, g) in gaps.iter().enumerate() {
        disc.push(*g, c.pins.lever[j], c.pins.arm[j]);
    }
    (gaps, disc)
}

#[test]
fn alike_discs_balance_as_the_pair_does() {
    // balance::alike is zero_torque of two equal discs with no offset and no slack (a
    // Newton step on one disc's loaded set against the pair's balance of both discs).
    let rule = rule(&[]);
    for shift in [-0.012, -0.010, -0.006] {
        let (gaps, disc) = design_disc(&rule, shift);
        let c = &rule.columns;
        let one = balance::alike(rule.contact(), &gaps, &c.pins).unwrap();
        let pair = zero_torque(rule.contact(), &mut [disc.clone(), disc]);
        assert!(one.pin_force > 0.0, "{shift}: preloaded");
        for (a, b) in [
            (one.overlap_um, pair.overlap_um),
            (one.pin_force, pair.pin_force),
            (one.no_load_torque, pair.no_load_torque),
        ] {
            assert!((a - b).abs() <= 1e-9 * b, "{a} vs {b}");
        }
    }
}

#[test]
fn the_design_profile_is_preloaded_as_validation_md_says() {
    // The RV-20E's design profile (Table 9's modification, no error): its flanks overlap
    // by 1.34 µm and the largest pin force at zero torque is about 152 N (validation.md);
    // a 10 µm larger pin circle frees it.
    let rule = rule(&[]);
    let (overlapping, load) = rule.of_profile((-0.010, -0.012), [0.0; 3]);
    assert!(overlapping);
    assert!((load.overlap_um - 1.34).abs() < 0.01, "{}", load.overlap_um);
    assert!((load.pin_force - 152.0).abs() < 2.0, "{}", load.pin_force);
    // The same profile given pin by pin (z_p clearances, the pins at φ = 0 and π too).
    let stage = rule.stage;
    let clearances: Vec<f64> = (0..40)
        .map(|i| {
            let (sin, cos) = (2.0 * PI * i as f64 / 40.0).sin_cos();
            let p = stage.pin_factors_at(sin, cos);
            -0.010 * p.equidistant - 0.012 * p.shift
        })
        .collect();
    assert_eq!(rule.of_clearances(&clearances), load);
    assert_eq!(
        rule.of_profile((-0.010, -0.012), [0.010, 0.0, 0.0]),
        (false, Preload::NONE)
    );
}

#[test]
fn the_class_follows_the_limits() {
    // Free without overlap; within up to the rated force (365 N for the RV-20E design,
    // rv_lost_motion's figure); over beyond it, beyond a set overlap or torque limit, or
    // with a jammed gear stage.
    let rule = rule(&[]);
    let rated = rule.rated_pin_force(-0.010, -0.012);
    assert!((rated - 365.0).abs() < 5.0, "{rated}");
    let design = (-0.010, -0.012);
    let at = |force: f64| Preload {
        overlap_um: 1.0,
        pin_force: force,
        no_load_torque: 0.01,
    };
    assert_eq!(
        rule.classify(&Preload::NONE, (false, false), design),
        PreloadClass::Free
    );
    assert_eq!(
        rule.classify(&at(0.99 * rated), (true, false), design),
        PreloadClass::Within
    );
    assert_eq!(
        rule.classify(&at(1.01 * rated), (true, false), design),
        PreloadClass::Over
    );
    assert_eq!(
        rule.classify(&Preload::NONE, (false, true), design),
        PreloadClass::Over
    );
    let strict = super::tests::rule(&[("preload_limit_overlap_um", 0.5)]);
    assert_eq!(
        strict.classify(&at(100.0), (true, false), design),
        PreloadClass::Over
    );
    let torque = super::tests::rule(&[("preload_limit_no_load_torque_nm", 0.005)]);
    assert_eq!(
        torque.classify(&at(100.0), (true, false), design),
        PreloadClass::Over
    );
    let forced = super::tests::rule(&[("preload_limit_pin_force_n", 50.0)]);
    assert_eq!(forced.rated_pin_force(-0.010, -0.012), 50.0);
    // The memory of the last rated force is a memory only: the same value either way.
    assert_eq!(rule.design_rated_force(-0.010, -0.012), rated);
    assert_eq!(
        rule.rated_pin_force(0.0, -0.02),
        rule.design_rated_force(0.0, -0.02)
    );
}

/// The deviations every model of a whole reducer takes: the pin circle δr_p, the pins'
/// radius δr_rp (every pin alike) and the modification's errors δΔr_rp, δΔr_p.
#[derive(Debug, Clone, Copy)]
struct Shared {
    pin_circle: f64,
    pin_radius: f64,
    equidistant: f64,
    shift: f64,
}

/// (preloaded, over_preloaded, pin force) from a model's outputs by name.
fn class_of(model: &dyn ErrorModel, x: &[f64]) -> (f64, f64, f64) {
    let mut out = vec![0.0; model.outputs().len()];
    model.evaluate(x, &mut out);
    let at = |name: &str| {
        let i = model.outputs().iter().position(|o| o.name == name).unwrap();
        out[i]
    };
    (
        at("preloaded"),
        at("over_preloaded"),
        at("preload_pin_force_n"),
    )
}

/// A row of `model` with the named inputs set, the others 0.
fn row_of(model: &dyn ErrorModel, set: &[(&str, f64)]) -> Vec<f64> {
    let mut x = vec![0.0; model.inputs().len()];
    for &(name, value) in set {
        let i = model.inputs().iter().position(|s| s.name == name);
        x[i.unwrap_or_else(|| panic!("{} has no input {name}", model.name()))] = value;
    }
    x
}

/// Each model's (preloaded, over, force) for the shared deviations on the RV-20E.
fn classes(d: Shared) -> Vec<(&'static str, (f64, f64, f64))> {
    let common = [
        ("common_normal_upper_deviation_mm", 0.0035),
        ("common_normal_lower_deviation_mm", -0.0309),
    ];
    let lost = crate::RvLostMotion::from_params(&crate::RvLostMotion::rv20e_params()).unwrap();
    let mut set: Vec<(String, f64)> = common.iter().map(|&(k, v)| (k.to_string(), v)).collect();
    set.push(("pin_circle_radius_error_mm".into(), d.pin_circle));
    set.push(("equidistant_modification_error_mm".into(), d.equidistant));
    set.push(("shift_modification_error_mm".into(), d.shift));
    set.push(("pin_radius_error_mm".into(), d.pin_radius));
    let named: Vec<(&str, f64)> = set.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    let lost_row = row_of(&lost, &named);

    // 000's inputs, the physical reading with K1 derived (e·z_p/r_p).
    let mut params = GeometricHysteresis::rv20e_params();
    params.insert(
        "curtate_ratio".into(),
        ParamValue::Number(0.9 * 40.0 / 52.0),
    );
    let hysteresis = GeometricHysteresis::from_params(&params).unwrap();
    let lumped = [
        ("equidistant_modification_mm", -0.010),
        ("shift_modification_mm", -0.012),
        ("pin_circle_radius_error_mm", d.pin_circle),
        ("pin_radius_error_mm", d.pin_radius),
        ("equidistant_modification_error_mm", d.equidistant),
        ("shift_modification_error_mm", d.shift),
        ("crank_bearing_clearance_mm", 0.002),
        common[0],
        common[1],
    ];
    let hysteresis_row = row_of(&hysteresis, &lumped);
    let torsion = crate::TorsionCurve::from_params(&crate::TorsionCurve::rv20e_params()).unwrap();
    let torsion_row = row_of(&torsion, &lumped);

    let contact_params = ModelParams::new()
        .with_number("pin_count", 40.0)
        .with_number("cycloid_teeth", 39.0)
        .with_number("pin_circle_radius_mm", 52.0)
        .with_number("pin_radius_mm", 2.0)
        .with_number("eccentricity_mm", 0.9)
        .with_number("disc_face_width_mm", 8.0)
        .with_number("sun_teeth", 12.0)
        .with_number("planet_teeth", 42.0)
        .with_number("crank_count", 2.0)
        .with_number("crank_circle_radius_mm", 27.5)
        .with_number("pin_friction_coefficient", 0.02)
        .with_number("rated_torque_nm", 167.0);
    let contact = crate::CycloidPinContact::from_params(&contact_params).unwrap();
    let contact_row = row_of(
        &contact,
        &[
            ("output_torque_nm", 10.0),
            ("equidistant_modification_mm", -0.010 + d.equidistant),
            ("shift_modification_mm", -0.012 + d.shift),
            ("pin_circle_radius_error_mm", d.pin_circle),
            ("pin_radius_error_mm", d.pin_radius),
        ],
    );
    let te_params = ModelParams::new()
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
        .with_number("pin_friction_coefficient", 0.02)
        .with_number("rated_torque_nm", 167.0)
        // The preload is judged alike in every contact reading; the rigid one needs no
        // crank side.
        .with(
            "disc_contact",
            crate::ParamValue::Text("first_contact".into()),
        );
    let te = crate::TransmissionError::from_params(&te_params).unwrap();
    let te_row = row_of(
        &te,
        &[
            ("equidistant_modification_mm", -0.010 + d.equidistant),
            ("shift_modification_mm", -0.012 + d.shift),
            ("pin_circle_radius_error_mm", d.pin_circle),
            ("pin_radius_error_mm", d.pin_radius),
        ],
    );
    vec![
        ("rv_lost_motion", class_of(&lost, &lost_row)),
        ("transmission_error", class_of(&te, &te_row)),
        (
            "geometric_hysteresis",
            class_of(&hysteresis, &hysteresis_row),
        ),
        ("torsion_curve", class_of(&torsion, &torsion_row)),
        ("cycloid_pin_contact", class_of(&contact, &contact_row)),
    ]
}

#[test]
fn every_model_gives_the_same_preload_class_for_the_same_deviations() {
    // Issue test (e). The deviations every model takes, on a grid through free, preloaded
    // within the limit and over-preloaded RV-20E assemblies (81 rows), in all five models
    // that judge preload. rv_lost_motion judges at the narrowest of its 160 output angles,
    // transmission_error at the narrowest of its 4,096, the others on the profile at the
    // pins' places φ_i = 2π·i/z_p, one of those angles: the same pins where the window is
    // narrowest, so their pin forces agree to rounding and grid (measured: within 0.02 %). The class must agree wherever rv_lost_motion's pin force is more than 1 %
    // from the limit and above 1 N.
    let limit = crate::RvLostMotion::from_params(&crate::RvLostMotion::rv20e_params())
        .unwrap()
        .rated_pin_force();
    let (mut compared, mut kinds) = (0, [0; 3]);
    for pin_radius in [
        -0.004, -0.003, -0.002, -0.001, 0.0, 0.001, 0.002, 0.003, 0.004,
    ] {
        for pin_circle in [-0.004, 0.0, 0.004] {
            for (equidistant, shift) in [(0.0, 0.0), (0.001, -0.003), (-0.001, 0.003)] {
                let d = Shared {
                    pin_circle,
                    pin_radius,
                    equidistant,
                    shift,
                };
                let all = classes(d);
                let (_, (preloaded, over, force)) = all[0];
                let near_limit = (force / limit - 1.0).abs() < 0.01;
                let near_free = preloaded == 1.0 && force < 1.0;
                for (name, (p, o, f)) in &all[1..] {
                    // These take the modification as one input, design and error together:
                    // their limit is that of the modification as ground.
                    let as_ground = ["cycloid_pin_contact", "transmission_error"];
                    if as_ground.contains(name) && (equidistant, shift) != (0.0, 0.0) {
                        continue;
                    }
                    if preloaded == 1.0 && !near_limit && !near_free {
                        assert!(
                            (f / force - 1.0).abs() < 0.001,
                            "{d:?}: {name} {f} N vs {force} N"
                        );
                    }
                    if near_limit || near_free {
                        continue;
                    }
                    assert_eq!(
                        (*p, *o),
                        (preloaded, over),
                        "{d:?}: {name} {f} N vs {force} N"
                    );
                }
                if !(near_limit || near_free) {
                    compared += 1;
                    kinds[(preloaded + over) as usize] += 1;
                }
            }
        }
    }
    // The grid reaches every class.
    assert!(kinds.iter().all(|&k| k > 0), "{kinds:?} of {compared}");
}

#[test]
fn the_rows_in_lanes_are_the_row_form_bit_for_bit() {
    // of_profiles (one row per vector lane) against of_profile row by row, at every
    // instruction set this processor has: overlapping and free profiles around the RV-20E's
    // design (Table 9's modification ± 10 µm, pin circle ± 10 µm, pins and eccentricity
    // ± 5 µm), a zero row, and rows whose gaps are not finite (left to the row form).
    use crate::reducer::test_streams::{every_width, stream};
    let rule = rule(&[]);
    let mut next = stream(34);
    let mut rows: Vec<[f64; 5]> = (0..203)
        .map(|_| {
            [
                -0.010 + 0.010 * next(),
                -0.012 + 0.010 * next(),
                0.010 * next(),
                0.005 * next(),
                0.005 * next(),
            ]
        })
        .collect();
    rows[5] = [0.0; 5];
    rows[17][2] = f64::NAN;
    rows[40][4] = f64::INFINITY;
    rows[41][0] = 1e308;
    let expected: Vec<(bool, Preload)> = rows
        .iter()
        .map(|r| rule.of_profile((r[0], r[1]), [r[2], r[3], r[4]]))
        .collect();
    let overlapping = expected.iter().filter(|e| e.0).count();
    let loaded = expected.iter().filter(|e| e.1.pin_force > 0.0).count();
    assert!(overlapping > 40 && overlapping < 180, "{overlapping}");
    assert!(loaded > 40, "{loaded}");
    let bits = |(o, p): &(bool, Preload)| {
        (
            *o,
            [p.overlap_um, p.pin_force, p.no_load_torque].map(f64::to_bits),
        )
    };
    let column = |k: usize| rows.iter().map(|r| r[k]).collect::<Vec<f64>>();
    let columns: Vec<Vec<f64>> = (0..5).map(column).collect();
    for (name, width) in every_width() {
        // Blocks of every length the lanes split unevenly, and the whole at once.
        for block in [1, 3, 8, 64, 203] {
            let mut out = vec![(false, Preload::NONE); rows.len()];
            for first in (0..rows.len()).step_by(block) {
                let r = first..(first + block).min(rows.len());
                let profiles = Profiles {
                    equidistant: &columns[0][r.clone()],
                    shift: &columns[1][r.clone()],
                    pin_circle: &columns[2][r.clone()],
                    pin_radius: &columns[3][r.clone()],
                    eccentric: &columns[4][r.clone()],
                };
                rows::of_profiles_in(width, &rule, &profiles, &mut out[r]);
            }
            for (i, (got, want)) in out.iter().zip(&expected).enumerate() {
                assert_eq!(bits(got), bits(want), "{name}, blocks of {block}, row {i}");
            }
        }
    }
}
