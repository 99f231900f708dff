//! The `expression` model through the engine: written as formulas, the built-in
//! `linear_stack`, `ishigami` and `sobol_g` give the same samples for the same seed; a
//! run's report has the same bits for any thread and shard count; the pin-in-hole gap's
//! out-of-spec share matches its closed form; malformed formulas are refused with one line
//! naming the JSON path and the character.

use rvtol_engine::{sample_table, Scenario};
use rvtol_tests::{
    assert_same_bits_for_threads_and_shards, refusal, run_settings, run_with_threads,
    scenario_path, SIGMA_BOUND,
};
use serde_json::{json, Value};
use statrs::distribution::{ContinuousCDF, Normal};

fn shipped(file: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(scenario_path(file)).unwrap()).unwrap()
}

fn scenario(document: &Value) -> Scenario {
    Scenario::from_json(&document.to_string(), "test").unwrap_or_else(|err| panic!("{err}"))
}

/// An expression model with one output `y` (unit `unit`) of `formula`, its inputs those
/// of `model` bound as `model` binds them, each read in `input_units[name]` (or `unit`).
fn as_expression(model: &Value, formula: &str, unit: &str, input_units: &Value) -> Value {
    let bindings = model["inputs"].as_object().unwrap();
    let inputs: serde_json::Map<String, Value> = bindings
        .keys()
        .map(|name| {
            let unit = input_units
                .get(name)
                .and_then(Value::as_str)
                .unwrap_or(unit);
            (name.clone(), json!(unit))
        })
        .collect();
    json!({
        "model": "expression",
        "params": {
            "inputs": inputs,
            "outputs": { "y": { "formula": formula, "unit": unit } }
        },
        "inputs": bindings
    })
}

/// Output 0 of every sample of the shipped scenario and of the same scenario with its
/// model replaced by `formula`.
fn both(file: &str, formula: &str, unit: &str, input_units: Value) -> (Vec<f64>, Vec<f64>) {
    let original = shipped(file);
    let mut written = original.clone();
    written["models"][0] = as_expression(&original["models"][0], formula, unit, &input_units);
    let spec = written["spec_limits"].as_object().cloned();
    if let Some(spec) = spec {
        // The output is `y` here.
        let limits = spec.values().next().cloned().unwrap();
        written["spec_limits"] = json!({ "y": limits });
    }
    let seed = original["seed"].as_u64().unwrap();
    let table = |document: &Value| {
        let scenario = scenario(document);
        let table = sample_table(&scenario, run_settings(100_000, seed)).unwrap();
        (0..table.rows)
            .map(|r| table.outputs[r * table.n_outputs])
            .collect::<Vec<f64>>()
    };
    (table(&original), table(&written))
}

#[test]
fn built_in_models_written_as_formulas_give_the_same_samples() {
    // The formulas associate as the built-in models compute (c + a1·x1 + …, left to
    // right; Π over the G-function's factors from the left), so the linear stack and the
    // G-function agree bit for bit and Ishigami to 1e-15 of each value (its x⁴ is
    // `powi` in both, its sines the same calls).
    let (stack, written) = both(
        "linear-stack-correlated.json",
        "0 + 1*bore + -1*bearing + -1*spacer + -1*carrier_axial + -40*carrier_tilt",
        "mm",
        json!({ "carrier_tilt": "rad" }),
    );
    assert_eq!(stack.len(), 100_000);
    for (r, (a, b)) in stack.iter().zip(&written).enumerate() {
        assert_eq!(a.to_bits(), b.to_bits(), "linear stack, sample {r}");
    }
    let (ishigami, written) = both(
        "ishigami.json",
        "sin(x1) + 7*sin(x2)*sin(x2) + 0.1*x3^4*sin(x1)",
        "1",
        json!({ "x1": "rad", "x2": "rad", "x3": "rad" }),
    );
    for (r, (a, b)) in ishigami.iter().zip(&written).enumerate() {
        assert!(
            (a - b).abs() <= 1e-15 * a.abs(),
            "Ishigami, sample {r}: {a} against {b}"
        );
    }
    let factor = |i: usize, a: f64| format!("((abs(4*x{i} - 2) + {a}) / (1 + {a}))");
    let coefficients = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0];
    let product: Vec<String> = (coefficients.iter().enumerate())
        .map(|(i, &a)| factor(i + 1, a))
        .collect();
    let (g, written) = both("sobol-g.json", &product.join(" * "), "1", json!({}));
    for (r, (a, b)) in g.iter().zip(&written).enumerate() {
        assert_eq!(a.to_bits(), b.to_bits(), "G-function, sample {r}");
    }
}

/// The pin in a hole: gap = (D − d)/2 − √(x² + y²), D and d normal, the pin's position
/// errors x, y independent N(0, σ²) (written in µm, read in mm).
fn pin_in_hole(samples: u64) -> Value {
    json!({
        "name": "pin-in-hole",
        "samples": samples,
        "seed": 11,
        "variables": [
            { "name": "hole", "unit": "mm", "distribution": { "normal": { "mean": 10.012, "sd": 0.003 } } },
            { "name": "pin", "unit": "mm", "distribution": { "normal": { "mean": 9.992, "sd": 0.002 } } },
            { "name": "x", "unit": "µm", "distribution": { "normal": { "mean": 0.0, "sd": 4.0 } } },
            { "name": "y", "unit": "µm", "distribution": { "normal": { "mean": 0.0, "sd": 4.0 } } }
        ],
        "models": [{
            "model": "expression",
            "params": {
                "inputs": { "hole_d": "mm", "pin_d": "mm", "x": "mm", "y": "mm" },
                "let": { "offset": "hypot(x, y)" },
                "outputs": { "gap_mm": { "formula": "(hole_d - pin_d) / 2 - offset", "unit": "mm" } }
            },
            "inputs": { "hole_d": "hole", "pin_d": "pin", "x": "x", "y": "y" }
        }],
        "spec_limits": { "gap_mm": { "lower": 0.0 } }
    })
}

#[test]
fn pin_in_hole_failure_rate_matches_its_closed_form() {
    // R = √(x² + y²) is Rayleigh(σ), C = (D − d)/2 ~ N(m, s²) independent:
    // P(gap < 0) = P(R > C) = Φ(−m/s) + σ/√(σ² + s²)·exp(−m²/(2(σ² + s²)))·Φ(mσ/(s√(σ² + s²)))
    // (condition on C; P(R > c) = exp(−c²/2σ²) for c > 0; complete the square).
    let (m, s, sigma) = (0.010, (0.003f64.hypot(0.002)) / 2.0, 0.004);
    let phi = |z: f64| Normal::standard().cdf(z);
    let v = sigma * sigma + s * s;
    let p = phi(-m / s)
        + sigma / v.sqrt() * (-m * m / (2.0 * v)).exp() * phi(m * sigma / (s * v.sqrt()));
    let n = 2_000_000u64;
    let scenario = scenario(&pin_in_hole(n));
    let table = sample_table(&scenario, run_settings(n, 11)).unwrap();
    let failed = (0..table.rows).filter(|&r| table.outputs[r] < 0.0).count() as f64;
    let estimate = failed / n as f64;
    let se = (p * (1.0 - p) / n as f64).sqrt();
    assert!(
        (estimate - p).abs() <= SIGMA_BOUND * se,
        "P(gap < 0) = {estimate} against {p} (se {se})"
    );
    // The µm inputs were converted: the mean gap is m − σ√(π/2), not m − 1000·σ√(π/2).
    let mean = table.outputs.iter().sum::<f64>() / n as f64;
    let exact_mean = m - sigma * (std::f64::consts::PI / 2.0).sqrt();
    assert!(
        (mean - exact_mean).abs() < 1e-5,
        "mean gap {mean} against {exact_mean}"
    );
}

#[test]
fn reports_have_the_same_bits_for_any_thread_and_shard_count() {
    let scenario = scenario(&pin_in_hole(300_000));
    let settings = run_settings(300_000, 11);
    assert_same_bits_for_threads_and_shards(&scenario, settings);
}

#[test]
fn malformed_formulas_are_refused_with_path_and_character() {
    let path = "models[0].params.outputs.gap_mm.formula";
    let cases: Vec<(String, String)> = vec![
        (
            "((hole_d - pin_d) / 2 - offset".into(),
            "character 31: the '(' at character 1 is not closed".into(),
        ),
        (
            "(hole_d - pin_d)) / 2".into(),
            "character 17: this ')' closes no '('".into(),
        ),
        (
            "(hole_d - pin_d) / 2 - hypt(x, y)".into(),
            "character 24: unknown function \"hypt\" (did you mean hypot?)".into(),
        ),
        (
            "(hole_d - pin_d) / 2 - hypot(x)".into(),
            "character 24: hypot takes 2 arguments, got 1".into(),
        ),
        ("".into(), "character 1: the formula is empty".into()),
        (
            format!("{}offset{}", "(".repeat(10_000), ")".repeat(10_000)),
            "character 10001: the formula has 20006 characters".into(),
        ),
        (
            format!("{}offset{}", "(".repeat(500), ")".repeat(500)),
            "character 102: the formula nests deeper than 100 levels".into(),
        ),
        (
            format!("offset{}", " + offset".repeat(120_000)),
            "character 10001: the formula has 1080006 characters".into(),
        ),
        (
            "offset + größe".into(),
            "character 12: 'ö' (U+00F6) cannot be in a name".into(),
        ),
        (
            "offset + δ".into(),
            "character 10: 'δ' (U+03B4) cannot be in a name".into(),
        ),
        (
            "offset = 0".into(),
            "character 8: '=' alone is no operator".into(),
        ),
    ];
    for (formula, says) in cases {
        let mut document = pin_in_hole(1000);
        document["models"][0]["params"]["outputs"]["gap_mm"]["formula"] = json!(formula);
        let err = refusal(&document);
        assert!(!err.contains('\n'), "one line: {err}");
        assert!(err.starts_with(path), "{err}");
        assert!(err.contains(&says), "{says:?} in {err}");
    }
}

#[test]
fn a_unit_that_does_not_convert_is_refused_at_the_binding() {
    let mut document = pin_in_hole(1000);
    document["variables"][2]["unit"] = json!("rad");
    let err = refusal(&document);
    assert_eq!(
        err,
        "models[0].inputs.x: \"x\" is in rad but the input wants mm (params.inputs.x)"
    );
    let mut document = pin_in_hole(1000);
    document["models"][0]["params"]["inputs"]["x"] = json!("microns");
    assert!(refusal(&document).starts_with(
        "models[0].inputs.x: \"x\" is in µm, but the input's unit \"microns\" is not one rvtol converts (lengths mm, µm"
    ));
}

/// The pin in a hole as a chain: one model computes the radial offset, a second reads it.
fn chained(samples: u64) -> Value {
    let mut document = pin_in_hole(samples);
    document["models"] = json!([
        {
            "model": "expression",
            "params": {
                "inputs": { "x": "mm", "y": "mm" },
                "outputs": { "offset_mm": { "formula": "hypot(x, y)", "unit": "mm" } }
            },
            "inputs": { "x": "x", "y": "y" }
        },
        {
            "model": "expression",
            "params": {
                "inputs": { "hole_d": "mm", "pin_d": "mm", "offset": "mm" },
                "outputs": { "gap_mm": { "formula": "(hole_d - pin_d) / 2 - offset", "unit": "mm" } }
            },
            "inputs": { "hole_d": "hole", "pin_d": "pin", "offset": "offset_mm" }
        }
    ]);
    document
}

#[test]
fn a_chain_of_models_equals_the_same_computation_as_one_formula() {
    let n = 50_000;
    let one = sample_table(&scenario(&pin_in_hole(n)), run_settings(n, 11)).unwrap();
    let chain_scenario = scenario(&chained(n));
    let names: Vec<&str> = chain_scenario
        .outputs
        .iter()
        .map(|o| o.name.as_str())
        .collect();
    assert_eq!(names, ["offset_mm", "gap_mm"]);
    let chain = sample_table(&chain_scenario, run_settings(n, 11)).unwrap();
    assert_eq!(one.inputs, chain.inputs);
    for r in 0..n as usize {
        let (x, y) = (one.inputs[r * 4 + 2], one.inputs[r * 4 + 3]);
        assert_eq!(
            chain.outputs[r * 2].to_bits(),
            x.hypot(y).to_bits(),
            "offset, row {r}"
        );
        assert_eq!(
            one.outputs[r].to_bits(),
            chain.outputs[r * 2 + 1].to_bits(),
            "gap, row {r}"
        );
    }
    // The nominal design reads the chain too.
    let nominal = rvtol_engine::nominal(&chain_scenario).unwrap();
    assert_eq!(nominal, [Some(0.0), Some((10.012 - 9.992) / 2.0)]);
    // The same bits for any thread count.
    let settings = run_settings(100_000, 5);
    let report = run_with_threads(&chain_scenario, settings, 1);
    assert_eq!(report, run_with_threads(&chain_scenario, settings, 2));
}

#[test]
fn a_chain_that_is_out_of_order_or_of_another_unit_is_refused() {
    let mut document = chained(1000);
    let models = document["models"].as_array_mut().unwrap();
    models.swap(0, 1);
    assert_eq!(
        refusal(&document),
        "models[0].inputs.offset: \"offset_mm\" is an output of models[1], below this model: a model reads the outputs of the models above it (order the models so; a chain has no cycle)"
    );
    let mut document = chained(1000);
    document["models"][0]["params"]["inputs"]["y"] = json!("mm");
    document["models"][0]["inputs"]["x"] = json!("offset_mm");
    assert!(refusal(&document).starts_with(
        "models[0].inputs.x: \"offset_mm\" is an output of this model: a model cannot read its own output"
    ));
    let mut document = chained(1000);
    document["models"][1]["params"]["inputs"]["offset"] = json!("µm");
    assert_eq!(
        refusal(&document),
        "models[1].inputs.offset: output \"offset_mm\" is in mm but the input wants µm: a chained output is not converted (declare the output in µm or the input in mm)"
    );
}

#[test]
fn a_stack_of_an_output_that_is_not_finite_is_refused_as_a_run_is() {
    // √x of a normal x is NaN in half the rows: the stack refuses it as `run` does,
    // instead of reporting R² and shares of the finite half.
    let mut document = pin_in_hole(1000);
    document["models"][0]["params"]["outputs"]["gap_mm"]["formula"] =
        json!("sqrt(x) + 0*offset + 0*hole_d + 0*pin_d");
    let scenario = scenario(&document);
    let settings = rvtol_analysis::stack::StackSettings {
        seed: 1,
        outputs: vec![0],
        max_non_finite: 0.0,
    };
    let Err(err) = rvtol_analysis::stack::stack(&scenario, &settings) else {
        panic!("a stack of NaN accepted");
    };
    assert!(
        err.to_string()
            .starts_with("models[0] (expression): gap_mm is not finite in ")
            && err
                .to_string()
                .contains("of the 4096 rows of the scenario's law the stack draws for R²"),
        "{err}"
    );
    // Allowed, the finite rows carry the figures.
    let allowed = rvtol_analysis::stack::StackSettings {
        max_non_finite: 0.6,
        ..settings
    };
    assert!(rvtol_analysis::stack::stack(&scenario, &allowed).is_ok());
}
