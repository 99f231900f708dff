//! Tests of design values (rvtol_engine::scenario::design) and the sweep over them
//! (rvtol_analysis::sweep): the three kinds of path, the refusals with their reasons, a
//! lever on the reducer's profile modification, and each point of a sweep equal, bit for
//! bit, to a run of the scenario with that value written in.

use rvtol_analysis::sweep::{axes, sweep};
use rvtol_engine::figures::output_figures;
use rvtol_engine::scenario::design::DesignValue;
use rvtol_engine::Scenario;
use rvtol_tests::{run_settings, scenario_path, shipped_text};
use serde_json::Value;

fn rv20e() -> String {
    shipped_text(scenario_path("rv20e-hysteresis.json"))
}

#[test]
fn design_values_are_named_by_the_reducer_a_model_parameter_or_a_constant_input() {
    let text = rv20e();
    // The reducer's shift modification (Table 9, -0.012 mm), and the model input bound
    // to it.
    let reducer = DesignValue::parse(&text, "reducer.params.shift_modification_mm").unwrap();
    assert_eq!(reducer.current, Some(-0.012));
    let input = DesignValue::parse(&text, "models[0].inputs.shift_modification_mm").unwrap();
    assert_eq!(input.current, Some(-0.012));
    // A number bound as an input (E_ws, Table 9).
    let constant =
        DesignValue::parse(&text, "models[0].inputs.common_normal_upper_deviation_mm").unwrap();
    assert_eq!(constant.current, Some(0.0035));
    // What is not a design value, each with why.
    for (path, says) in [
        (
            "models[0].inputs.pin_radius_error_mm",
            "bound to the random quantity \"pin_radius_error\"",
        ),
        (
            "models[0].params.pin_count",
            "the reducer gives \"pin_count\" to every model",
        ),
        (
            "reducer.params.no_such_key",
            "the scenario's reducer has no parameter \"no_such_key\"",
        ),
        ("models[3].params.x", "the scenario has no models[3]"),
        (
            "models[0].inputs.no_such_input",
            "models[0] binds no input \"no_such_input\"",
        ),
        ("shift_modification_mm", "is not a design value path"),
    ] {
        let err = DesignValue::parse(&text, path).unwrap_err();
        assert!(err.contains(says), "{path}: {err}");
    }
}

#[test]
fn setting_the_reducer_value_moves_every_reader_of_it() {
    // The reducer's value reaches the model through its bound input: setting it there or
    // on the input gives the same nominal lost motion, and not the scenario's.
    let text = rv20e();
    let nominal_with = |path: &str| {
        let mut document: Value = serde_json::from_str(&text).unwrap();
        DesignValue::parse(&text, path)
            .unwrap()
            .set(&mut document, -0.016)
            .unwrap();
        let scenario = Scenario::from_json(&document.to_string(), "x").unwrap();
        rvtol_engine::nominal(&scenario).unwrap()[0].unwrap()
    };
    let before =
        rvtol_engine::nominal(&Scenario::from_json(&text, "x").unwrap()).unwrap()[0].unwrap();
    let by_reducer = nominal_with("reducer.params.shift_modification_mm");
    let by_input = nominal_with("models[0].inputs.shift_modification_mm");
    assert_eq!(by_reducer, by_input);
    assert!(by_reducer != before, "{by_reducer} {before}");
}

#[test]
fn an_allocation_lever_may_set_the_profile_modification() {
    let mut document: Value =
        serde_json::from_str(&shipped_text(scenario_path("rv20e-selective-fitting.json"))).unwrap();
    document["allocation"]["levers"] = serde_json::json!({
        "shift": {
            "param": "reducer.params.shift_modification_mm",
            "values": [-0.012, -0.014],
            "cost": [0.0, 0.1]
        }
    });
    let scenario = Scenario::from_json(&document.to_string(), "x").unwrap();
    assert_eq!(
        scenario.allocation_levers[0].target.path,
        "reducer.params.shift_modification_mm"
    );
    document["allocation"]["levers"]["shift"]["param"] =
        "models[0].inputs.pin_radius_error_mm".into();
    let err = Scenario::from_json(&document.to_string(), "x")
        .err()
        .unwrap();
    assert_eq!(err.path, "allocation.levers.shift.param");
    assert!(
        err.message.contains("not a design value"),
        "{}",
        err.message
    );
}

#[test]
fn each_point_of_a_sweep_is_the_run_of_its_text_bit_for_bit() {
    let text = rv20e();
    let scenario = Scenario::from_json(&text, "rv20e-hysteresis").unwrap();
    let grid = vec![
        (
            "reducer.params.shift_modification_mm".to_string(),
            vec![-0.014, -0.010],
        ),
        (
            "models[0].inputs.common_normal_upper_deviation_mm".to_string(),
            vec![0.0035, 0.0],
        ),
    ];
    let axes = axes(&text, &grid).unwrap();
    let outputs = scenario.continuous_outputs();
    let settings = run_settings(20_000, 5);
    let report = sweep(&scenario, &text, axes, &outputs, settings, 0.0, &|_| {}).unwrap();
    assert_eq!(report.points.len(), 4);
    for point in &report.points {
        let mut document: Value = serde_json::from_str(&text).unwrap();
        for ((path, _), &value) in grid.iter().zip(&point.values) {
            DesignValue::parse(&text, path)
                .unwrap()
                .set(&mut document, value)
                .unwrap();
        }
        let alone = Scenario::from_json(&document.to_string(), "rv20e-hysteresis").unwrap();
        let mut result = rvtol_engine::run(&alone, settings, &|_| {}).unwrap();
        let figures = output_figures(&alone, &mut result);
        let chosen: Vec<_> = outputs.iter().map(|&o| figures[o].clone()).collect();
        assert_eq!(point.outputs, chosen, "{:?}", point.values);
    }
    // The design moves the lost motion: the first and the last points differ.
    assert_ne!(
        report.points[0].outputs[0].mean,
        report.points[3].outputs[0].mean
    );
    // A grid too large, and a value path given twice, are refused before any run.
    let wide = vec![(
        "reducer.params.shift_modification_mm".to_string(),
        vec![0.0; 401],
    )];
    assert!(rvtol_analysis::sweep::axes(&text, &wide)
        .unwrap_err()
        .contains("at most 400"));
    let twice = vec![grid[0].clone(), grid[0].clone()];
    assert!(rvtol_analysis::sweep::axes(&text, &twice)
        .unwrap_err()
        .contains("set twice"));
}
