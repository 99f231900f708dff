//! Tests of the worst-case and RSS stack (`rvtol stack`, rvtol_analysis::stack) against
//! closed forms: the motor-assembly demo stack of MITCalc's tolerance-chain calculator
//! (worst case 0.1 ± 0.383 mm, RSS 0.1 ± 0.17825 mm), the RSS of a correlated linear stack,
//! the extremes of the Ishigami and Sobol' G functions over their boxes (one inside the
//! box, found by the search), the Eq. 11 constraint kept by every extreme, and the same
//! result on one thread and on two.

use rvtol_analysis::stack::{stack, Stack, StackSettings};
use rvtol_engine::Scenario;
use rvtol_tests::{scenario_path, shipped_text};

fn load(file: &str) -> Scenario {
    Scenario::from_json(&shipped_text(scenario_path(file)), file).unwrap()
}

fn stack_of(scenario: &Scenario) -> Stack {
    let settings = StackSettings {
        seed: scenario.seed,
        outputs: scenario.continuous_outputs(),
        max_non_finite: 0.0,
    };
    stack(scenario, &settings).unwrap()
}

fn ends(stack: &Stack, output: usize) -> [f64; 2] {
    stack.outputs[output]
        .worst_case
        .each_ref()
        .map(|end| end.as_ref().unwrap().value)
}

#[test]
fn the_motor_assembly_stack_is_the_published_one() {
    // scenarios/motor-assembly-stack.json: gap = a − b − c + d − e + f − g with half
    // tolerances 0.036, 0.03, 0.06, 0.026, 0.145, 0.026, 0.06 around a nominal gap of
    // 0.1 mm. MITCalc's demo (and the dimstack package's example of it): WC ± 0.383,
    // RSS ± 0.17825 = √(Σ T²) = √0.031773.
    let scenario = load("motor-assembly-stack.json");
    let s = stack_of(&scenario);
    assert!(s.all_corners);
    assert_eq!(s.corners, 128.0);
    let out = &s.outputs[0];
    // The nominal and the worst case are model values (to the rounding of sums of
    // numbers near 200 mm); the arithmetic and RSS stacks rest on central differences,
    // whose step (1e-4·T, 3e-6 to 1.5e-5 mm) turns that rounding (ulp 2.8e-14 mm) into
    // about 1e-9 relative.
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    let near = |a: f64, b: f64| (a - b).abs() < 1e-8 * b.abs();
    assert!(close(out.nominal, 0.1), "{}", out.nominal);
    let [low, high] = ends(&s, 0);
    assert!(
        close(low, 0.1 - 0.383) && close(high, 0.1 + 0.383),
        "{low} {high}"
    );
    assert!(near(out.arithmetic, 0.383), "{}", out.arithmetic);
    let halves: [f64; 7] = [0.036, 0.03, 0.06, 0.026, 0.145, 0.026, 0.06];
    let rss = halves.iter().map(|t| t * t).sum::<f64>().sqrt();
    assert!(near(out.rss, rss), "{} {rss}", out.rss);
    assert_eq!(format!("{:.5}", out.rss), "0.17825");
    // Each contributor's RSS share is T²/ΣT² and its arithmetic share T/ΣT; the case (e)
    // leads with 0.145²/0.031773 = 66.2 %.
    let total: f64 = halves.iter().map(|t| t * t).sum();
    for (c, t) in out.contributors.iter().zip(halves) {
        assert!((c.rss_share - t * t / total).abs() < 1e-8, "{c:?}");
        assert!((c.worst_case_share - t / 0.383).abs() < 1e-8, "{c:?}");
        assert!((c.sensitivity.abs() - 1.0).abs() < 1e-8, "{c:?}");
        assert!((c.swing - t).abs() < 1e-12, "{c:?}");
    }
    // A linear output: its linearisation is exact over the scenario's law.
    assert!((out.r_squared.unwrap() - 1.0).abs() < 1e-9);
    assert!(out
        .worst_case
        .iter()
        .flatten()
        .all(|e| !e.inside && !e.flagged));
}

#[test]
fn a_correlated_stack_has_the_closed_form_rss() {
    // scenarios/linear-stack-correlated.json: y = bore − bearing − spacer − dw − 40·dβ.
    // Tolerances (half widths): bore band 24.98–25.02 → 0.02 (its Cp 1.33 does not matter,
    // the stated limits do); bearing N(15, 0.004) → 3σ = 0.012; spacer band 9.94–9.96 →
    // 0.01; carrier.dw sd 0.002 → 0.006; carrier.dβ sd 1e-4 → 3e-4 (×40 = 0.012).
    // Correlations: bearing–spacer 0.5, dw–bore −0.2 (carrier du–dβ 0.3, du unused).
    let scenario = load("linear-stack-correlated.json");
    let s = stack_of(&scenario);
    let out = &s.outputs[0];
    let (bore, bearing, spacer, dw, tilt): (f64, f64, f64, f64, f64) =
        (0.02, -0.012, -0.01, -0.006, -0.012);
    let variance = bore * bore
        + bearing * bearing
        + spacer * spacer
        + dw * dw
        + tilt * tilt
        + 2.0 * 0.5 * bearing * spacer
        + 2.0 * -0.2 * dw * bore;
    assert!(
        (out.rss - variance.sqrt()).abs() < 1e-9,
        "{} {}",
        out.rss,
        variance.sqrt()
    );
    let arithmetic = 0.02 + 0.012 + 0.01 + 0.006 + 0.012;
    assert!(
        (out.arithmetic - arithmetic).abs() < 1e-9,
        "{}",
        out.arithmetic
    );
    // Euler's shares sum to 1 with correlated inputs.
    let shares: f64 = out.contributors.iter().map(|c| c.rss_share).sum();
    assert!((shares - 1.0).abs() < 1e-12, "{shares}");
}

#[test]
fn the_search_finds_the_extremes_of_the_ishigami_function_inside_its_box() {
    // f = sin x1 + 7 sin² x2 + 0.1 x3⁴ sin x1 on [−π, π]³: the largest value
    // 1 + 7 + 0.1π⁴ at x1 = π/2, x2 = ±π/2, x3 = ±π, the smallest −1 − 0.1π⁴ at
    // x1 = −π/2, sin x2 = 0, x3 = ±π. Points inside the box (x1 = ±π/2), on the search's
    // quarter-point levels; every corner gives f = 0 (sin ±π = 0 up to rounding).
    let scenario = load("ishigami.json");
    let s = stack_of(&scenario);
    let pi4 = std::f64::consts::PI.powi(4);
    let [low, high] = ends(&s, 0);
    assert!((high - (8.0 + 0.1 * pi4)).abs() < 1e-9, "{high}");
    assert!((low - (-1.0 - 0.1 * pi4)).abs() < 1e-9, "{low}");
    assert!(s.outputs[0].worst_case.iter().flatten().all(|e| e.inside));
    // The linearisation at the centre (gradient (1, 0, 0)) explains little of it.
    assert!(s.outputs[0].r_squared.unwrap() < 0.9);
}

#[test]
fn the_sobol_g_function_is_largest_at_a_corner_and_smallest_at_the_centre() {
    // G = Π (|4x − 2| + a)/(1 + a) on [0, 1]⁶ with a = (0, 1, 4.5, 9, 99, 99): each factor
    // is largest at x = 0 or 1 (2 + a)/(1 + a) and smallest at x = ½, a/(1 + a) (0 for
    // a = 0).
    let scenario = load("sobol-g.json");
    let s = stack_of(&scenario);
    let a = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0];
    let largest: f64 = a.iter().map(|a| (2.0 + a) / (1.0 + a)).product();
    let [low, high] = ends(&s, 0);
    assert!((high - largest).abs() < 1e-12 * largest, "{high} {largest}");
    assert_eq!(low, 0.0);
}

#[test]
fn every_extreme_keeps_the_eq_11_constraint() {
    // rv20e-lost-motion's input shaft is a tolerance_band part: its box is cut by 001
    // Eq. 11, and no extreme may leave it.
    let scenario = load("rv20e-lost-motion.json");
    assert!(!scenario.input_space.inequalities().is_empty());
    let settings = StackSettings {
        seed: 1,
        outputs: vec![scenario.output_index("lost_motion_arcmin").unwrap()],
        max_non_finite: 0.0,
    };
    let s = stack(&scenario, &settings).unwrap();
    for end in s.outputs[0].worst_case.iter().flatten() {
        for q in scenario.input_space.inequalities() {
            let lhs = q.coefficients[0] * end.row[q.columns[0]]
                + q.coefficients[1] * end.row[q.columns[1]];
            assert!(lhs <= q.bound * (1.0 + 1e-12), "{lhs} > {}", q.bound);
        }
    }
    // At the centre of its box the nominal RV-20E has no free play in the cycloid stage
    // (its lost motion there, 0.0263 arcmin, is the involute stage's alone): on the edge
    // of preload, where the lost motion is flat in the pins, so the linearisation explains
    // nothing, and the lowest end is a preloaded (flagged) assembly.
    let out = &s.outputs[0];
    assert!(!out.nominal_flagged);
    assert!(out.r_squared.unwrap() < 0.9);
    assert!(out.worst_case[0].as_ref().unwrap().flagged);
}

#[test]
fn an_outputs_stack_does_not_depend_on_the_others_asked() {
    let scenario = load("rv20e-lost-motion.json");
    let lost_motion = scenario.output_index("lost_motion_arcmin").unwrap();
    let alone = StackSettings {
        seed: 3,
        outputs: vec![lost_motion],
        max_non_finite: 0.0,
    };
    let every = StackSettings {
        outputs: scenario.continuous_outputs(),
        ..alone.clone()
    };
    let of_every = stack(&scenario, &every).unwrap();
    let position = every
        .outputs
        .iter()
        .position(|&o| o == lost_motion)
        .unwrap();
    assert_eq!(
        stack(&scenario, &alone).unwrap().outputs[0],
        of_every.outputs[position]
    );
}

#[test]
fn the_stack_is_the_same_on_one_thread_and_on_two() {
    let scenario = load("rv20e-lost-motion.json");
    let settings = StackSettings {
        seed: 3,
        outputs: scenario.continuous_outputs(),
        max_non_finite: 0.0,
    };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| stack(&scenario, &settings).unwrap())
    };
    assert_eq!(on(1), on(2));
}
