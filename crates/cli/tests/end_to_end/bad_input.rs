//! End-to-end tests of bad input: every broken scenario, bad argument and usage error
//! must make `rvtol` exit with code 2 and, for scenarios and arguments, print exactly one
//! line `error: …` on stderr that names the JSON path of the problem, with nothing on
//! stdout and no panic. Each scenario case is checked with both `rvtol validate` and
//! `rvtol run --samples 1000 --quiet`, which must fail the same way.

use crate::common;

use std::process::Output;

use common::{run_rvtol, TempScenario};
use serde_json::{json, Value};

/// A small valid scenario: two normal variables x1, x2 stacked as y = x1 − 2·x2.
fn base() -> Value {
    json!({
        "name": "bad-input-base",
        "samples": 1000,
        "seed": 7,
        "variables": [
            { "name": "x1", "unit": "mm", "distribution": { "normal": { "mean": 0.0, "sd": 0.1 } } },
            { "name": "x2", "unit": "mm", "distribution": { "normal": { "mean": 1.0, "sd": 0.2 } } }
        ],
        "models": [
            {
                "model": "linear_stack",
                "params": { "coefficients": { "a": 1.0, "b": -2.0 } },
                "inputs": { "a": "x1", "b": "x2" }
            }
        ]
    })
}

/// The base scenario after `change`.
fn scenario_with(change: impl FnOnce(&mut Value)) -> String {
    let mut scenario = base();
    change(&mut scenario);
    serde_json::to_string_pretty(&scenario).expect("serialisable")
}

/// A part with six zero means and `covariance`.
fn part_with_covariance(covariance: Value) -> Value {
    json!({ "name": "shaft", "mean": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], "covariance": covariance })
}

/// The 6×6 identity as JSON rows.
fn identity6() -> Vec<Vec<f64>> {
    (0..6)
        .map(|i| (0..6).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Asserts exit code 2, empty stdout, no panic and exactly one stderr line starting with
/// `error: ` that contains every `needle`; returns that line.
fn assert_one_line_error(what: &str, output: &Output, needles: &[&str]) -> String {
    let stdout = text(&output.stdout);
    let stderr = text(&output.stderr);
    let context = format!(
        "{what}\n--- status {:?}\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        output.status.code()
    );
    assert_eq!(output.status.code(), Some(2), "exit code: {context}");
    assert!(!stderr.contains("panicked"), "panic: {context}");
    assert!(stdout.is_empty(), "stdout not empty: {context}");
    let line = stderr.strip_suffix('\n').unwrap_or(&stderr);
    assert!(!line.contains('\n'), "more than one line: {context}");
    assert!(
        line.starts_with("error: "),
        "no `error: ` prefix: {context}"
    );
    for needle in needles {
        assert!(line.contains(needle), "missing {needle:?}: {context}");
    }
    line.to_string()
}

/// Writes `contents` as a scenario, runs `validate` and `run`, and asserts both fail with
/// the same single line naming `json_path` (as `: <path>: `, when given) and `words`.
fn assert_bad_scenario(label: &str, contents: &str, json_path: Option<&str>, words: &[&str]) {
    let file = TempScenario::new(&format!("bad-input-{label}"), contents);
    let path_needle = json_path.map(|p| format!(": {p}: "));
    let mut needles: Vec<&str> = words.to_vec();
    if let Some(p) = &path_needle {
        needles.push(p);
    }
    let validate = run_rvtol(&["validate".as_ref(), file.path().as_os_str()]);
    let validate_line = assert_one_line_error(&format!("{label}: validate"), &validate, &needles);
    let run = run_rvtol(&[
        "run".as_ref(),
        file.path().as_os_str(),
        "--samples".as_ref(),
        "1000".as_ref(),
        "--quiet".as_ref(),
    ]);
    let run_line = assert_one_line_error(&format!("{label}: run"), &run, &needles);
    assert_eq!(validate_line, run_line, "{label}: validate and run differ");
}

#[test]
fn valid_base_scenario_validates_and_runs() {
    let file = TempScenario::new("bad-input-valid", &scenario_with(|_| {}));
    let validate = run_rvtol(&["validate".as_ref(), file.path().as_os_str()]);
    assert_eq!(
        validate.status.code(),
        Some(0),
        "{}",
        text(&validate.stderr)
    );
    assert!(text(&validate.stdout).contains("valid"));
    assert!(validate.stderr.is_empty(), "{}", text(&validate.stderr));
    let run = run_rvtol(&[
        "run".as_ref(),
        file.path().as_os_str(),
        "--samples".as_ref(),
        "1000".as_ref(),
        "--quiet".as_ref(),
    ]);
    assert_eq!(run.status.code(), Some(0), "{}", text(&run.stderr));
    assert!(!run.stdout.is_empty());
}

#[test]
fn malformed_json_missing_comma() {
    let contents = scenario_with(|_| {}).replacen("\"seed\": 7,", "\"seed\": 7", 1);
    assert!(contents.contains("\"seed\": 7\n"));
    assert_bad_scenario("missing-comma", &contents, None, &[" at line ", " column "]);
}

#[test]
fn malformed_json_truncated() {
    let full = scenario_with(|_| {});
    assert_bad_scenario(
        "truncated",
        &full[..full.len() / 2],
        None,
        &[" at line ", " column "],
    );
}

#[test]
fn unknown_key_at_top_level() {
    let contents = scenario_with(|s| s["sampels"] = json!(10));
    assert_bad_scenario(
        "unknown-top-key",
        &contents,
        Some("sampels"),
        &["unknown field"],
    );
}

#[test]
fn unknown_key_inside_a_variable() {
    let contents = scenario_with(|s| s["variables"][1]["colour"] = json!("red"));
    assert_bad_scenario(
        "unknown-variable-key",
        &contents,
        Some("variables[1].colour"),
        &["unknown field"],
    );
}

#[test]
fn sd_given_as_a_string() {
    let contents =
        scenario_with(|s| s["variables"][0]["distribution"]["normal"]["sd"] = json!("0.1"));
    assert_bad_scenario(
        "sd-string",
        &contents,
        Some("variables[0].distribution.normal.sd"),
        &["invalid type", "string"],
    );
}

#[test]
fn negative_samples_in_file() {
    let contents = scenario_with(|s| s["samples"] = json!(-5));
    assert_bad_scenario("samples-negative", &contents, Some("samples"), &["-5"]);
}

#[test]
fn negative_sd() {
    let contents =
        scenario_with(|s| s["variables"][1]["distribution"]["normal"]["sd"] = json!(-0.2));
    assert_bad_scenario(
        "sd-negative",
        &contents,
        Some("variables[1].distribution.normal.sd"),
        &["must not be negative"],
    );
}

#[test]
fn nan_sd_as_string() {
    let contents =
        scenario_with(|s| s["variables"][0]["distribution"]["normal"]["sd"] = json!("NaN"));
    assert_bad_scenario(
        "sd-nan",
        &contents,
        Some("variables[0].distribution.normal.sd"),
        &["invalid type", "NaN"],
    );
}

#[test]
fn tolerance_band_with_zero_cp() {
    let contents = scenario_with(|s| {
        s["variables"][1]["distribution"] =
            json!({ "tolerance_band": { "lower": -0.1, "upper": 0.1, "cp": 0.0 } })
    });
    assert_bad_scenario(
        "cp-zero",
        &contents,
        Some("variables[1].distribution.tolerance_band.cp"),
        &["process capability must be positive"],
    );
}

#[test]
fn asymmetric_part_covariance() {
    let mut covariance = identity6();
    covariance[0][1] = 0.5;
    let contents = scenario_with(|s| s["parts"] = json!([part_with_covariance(json!(covariance))]));
    assert_bad_scenario(
        "cov-asymmetric",
        &contents,
        Some("parts[0].covariance"),
        &["not symmetric"],
    );
}

#[test]
fn indefinite_part_covariance() {
    let mut covariance = identity6();
    covariance[0][1] = 2.0;
    covariance[1][0] = 2.0;
    let contents = scenario_with(|s| s["parts"] = json!([part_with_covariance(json!(covariance))]));
    assert_bad_scenario(
        "cov-indefinite",
        &contents,
        Some("parts[0].covariance"),
        &["positive semi-definite", "smallest eigenvalue -1"],
    );
}

#[test]
fn model_input_not_bound() {
    let contents = scenario_with(|s| {
        s["models"][0]["inputs"]
            .as_object_mut()
            .expect("inputs object")
            .remove("b");
    });
    assert_bad_scenario(
        "input-unbound",
        &contents,
        Some("models[0].inputs"),
        &["\"b\"", "not bound"],
    );
}

#[test]
fn unknown_model_name() {
    let contents = scenario_with(|s| s["models"][0]["model"] = json!("frobnicator"));
    assert_bad_scenario(
        "unknown-model",
        &contents,
        Some("models[0].model"),
        &["unknown model", "frobnicator"],
    );
}

#[test]
fn zero_samples_in_file() {
    let contents = scenario_with(|s| s["samples"] = json!(0));
    assert_bad_scenario("samples-zero", &contents, Some("samples"), &["at least 1"]);
}

#[test]
fn zero_samples_on_command_line() {
    let file = TempScenario::new("bad-input-samples-arg-zero", &scenario_with(|_| {}));
    let output = run_rvtol(&[
        "run".as_ref(),
        file.path().as_os_str(),
        "--samples".as_ref(),
        "0".as_ref(),
        "--quiet".as_ref(),
    ]);
    assert_one_line_error("run --samples 0", &output, &["--samples", "at least 1"]);
}

#[test]
fn correlation_with_unknown_variable() {
    let contents =
        scenario_with(|s| s["correlations"] = json!([{ "between": ["x1", "x9"], "rho": 0.5 }]));
    assert_bad_scenario(
        "corr-unknown",
        &contents,
        Some("correlations[0].between[1]"),
        &["\"x9\""],
    );
}

#[test]
fn correlation_above_one() {
    let contents =
        scenario_with(|s| s["correlations"] = json!([{ "between": ["x1", "x2"], "rho": 1.5 }]));
    assert_bad_scenario(
        "corr-rho",
        &contents,
        Some("correlations[0].rho"),
        &["[-1, 1]", "1.5"],
    );
}

#[test]
fn spec_limits_for_unknown_output() {
    let contents = scenario_with(|s| s["spec_limits"] = json!({ "nonesuch": { "upper": 1.0 } }));
    assert_bad_scenario(
        "spec-unknown",
        &contents,
        Some("spec_limits.nonesuch"),
        &["no output named"],
    );
}

#[test]
fn model_input_bound_to_unknown_variable() {
    let contents = scenario_with(|s| s["models"][0]["inputs"]["b"] = json!("x9"));
    assert_bad_scenario(
        "input-unknown-variable",
        &contents,
        Some("models[0].inputs.b"),
        &["\"x9\""],
    );
}

#[test]
fn part_covariance_with_five_rows() {
    let mut covariance = identity6();
    covariance.pop();
    let contents = scenario_with(|s| s["parts"] = json!([part_with_covariance(json!(covariance))]));
    assert_bad_scenario(
        "cov-five-rows",
        &contents,
        Some("parts[0].covariance"),
        &["6 rows", "got 5 rows"],
    );
}

#[test]
fn usage_run_without_file() {
    let output = run_rvtol(&["run"]);
    assert_eq!(output.status.code(), Some(2), "{}", text(&output.stderr));
    assert!(!text(&output.stderr).contains("panicked"));
}

#[test]
fn usage_unknown_command() {
    let output = run_rvtol(&["frobnicate"]);
    assert_eq!(output.status.code(), Some(2), "{}", text(&output.stderr));
    assert!(!text(&output.stderr).contains("panicked"));
}

#[test]
fn missing_scenario_file() {
    let missing = std::env::temp_dir().join(format!(
        "rvtol-bad-input-missing-{}.json",
        std::process::id()
    ));
    let _ = std::fs::remove_file(&missing);
    let name = missing.display().to_string();
    let validate = run_rvtol(&["validate".as_ref(), missing.as_os_str()]);
    let validate_line =
        assert_one_line_error("validate missing file", &validate, &[&name, "cannot read"]);
    let run = run_rvtol(&[
        "run".as_ref(),
        missing.as_os_str(),
        "--samples".as_ref(),
        "1000".as_ref(),
        "--quiet".as_ref(),
    ]);
    let run_line = assert_one_line_error("run missing file", &run, &[&name, "cannot read"]);
    assert_eq!(validate_line, run_line);
}

// ---------------------------------------------------------------------------------------
// rvtol allocate: the allocation section (checked by validate and run too) and the
// allocate arguments.

/// The base scenario with an allocation section on x1 and x2 and spec limits on y.
fn allocatable() -> Value {
    let mut s = base();
    s["allocation"] = json!({
        "sources": {
            "x1": { "min": 0.05, "max": 0.6, "cost": { "reciprocal": { "b": 1.0 } } },
            "x2": { "cost": { "table": [[0.1, 5.0], [0.6, 2.0], [1.2, 1.0]] } }
        }
    });
    s
}

fn allocatable_with(change: impl FnOnce(&mut Value)) -> String {
    let mut scenario = allocatable();
    change(&mut scenario);
    serde_json::to_string_pretty(&scenario).expect("serialisable")
}

/// Runs `rvtol allocate` on `contents` with `args` (after the defaults `--output stack
/// --target "sd <= 0.3"`, which later arguments override) and asserts the one-line error.
fn assert_bad_allocate(label: &str, contents: &str, args: &[&str], needles: &[&str]) {
    let file = TempScenario::new(&format!("bad-allocate-{label}"), contents);
    let mut all = vec![
        "allocate",
        file.path().to_str().unwrap(),
        "--samples",
        "1000",
        "--quiet",
    ];
    let has = |flag: &str| args.contains(&flag);
    if !has("--output") {
        all.extend(["--output", "stack"]);
    }
    if !has("--target") {
        all.extend(["--target", "sd <= 0.3"]);
    }
    all.extend_from_slice(args);
    let output = run_rvtol(&all);
    assert_one_line_error(&format!("{label}: allocate"), &output, needles);
}

#[test]
fn allocation_section_is_valid_and_allocates() {
    let file = TempScenario::new("allocate-valid", &allocatable_with(|_| {}));
    let output = run_rvtol(&[
        "allocate",
        file.path().to_str().unwrap(),
        "--output",
        "stack",
        "--target",
        "sd <= 0.3",
        "--samples",
        "2000",
        "--quiet",
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", text(&output.stderr));
}

#[test]
fn allocation_source_unknown() {
    let contents = allocatable_with(|s| {
        s["allocation"]["sources"]["x9"] = s["allocation"]["sources"]["x1"].clone()
    });
    assert_bad_scenario(
        "allocation-unknown",
        &contents,
        Some("allocation.sources.x9"),
        &["no part or variable named \"x9\""],
    );
}

#[test]
fn allocation_bounds_reversed() {
    let contents = allocatable_with(|s| s["allocation"]["sources"]["x1"]["max"] = json!(0.01));
    assert_bad_scenario(
        "allocation-bounds",
        &contents,
        Some("allocation.sources.x1.max"),
        &["≥ min (0.05)"],
    );
}

#[test]
fn allocation_bound_missing_without_table() {
    let contents = allocatable_with(|s| {
        s["allocation"]["sources"]["x1"]
            .as_object_mut()
            .unwrap()
            .remove("min");
    });
    assert_bad_scenario(
        "allocation-no-min",
        &contents,
        Some("allocation.sources.x1.min"),
        &["required"],
    );
}

#[test]
fn allocation_cost_table_rising() {
    let contents = allocatable_with(|s| {
        s["allocation"]["sources"]["x2"]["cost"]["table"][2] = json!([1.2, 9.0])
    });
    assert_bad_scenario(
        "allocation-table",
        &contents,
        Some("allocation.sources.x2.cost.table[2]"),
        &["cannot cost more"],
    );
}

#[test]
fn allocation_cost_table_short_of_the_bounds() {
    let contents = allocatable_with(|s| s["allocation"]["sources"]["x2"]["max"] = json!(2.0));
    assert_bad_scenario(
        "allocation-table-range",
        &contents,
        Some("allocation.sources.x2.cost.table"),
        &["must cover the bounds"],
    );
}

#[test]
fn allocate_without_allocation_section() {
    assert_bad_allocate(
        "no-section",
        &scenario_with(|_| {}),
        &[],
        &[": allocation: missing"],
    );
}

#[test]
fn allocate_bad_target() {
    let contents = allocatable_with(|_| {});
    assert_bad_allocate(
        "target",
        &contents,
        &["--target", "p99.865 < 1"],
        &["--target: "],
    );
    assert_bad_allocate(
        "target-cpk",
        &contents,
        &["--target", "cpk <= 2"],
        &["--target: ", "cpk >= VALUE"],
    );
}

#[test]
fn allocate_unknown_output() {
    assert_bad_allocate(
        "output",
        &allocatable_with(|_| {}),
        &["--output", "z"],
        &[": --output: no output named \"z\"; outputs: stack"],
    );
}

#[test]
fn allocate_capability_target_without_spec_limits() {
    assert_bad_allocate(
        "cpk-no-spec",
        &allocatable_with(|_| {}),
        &["--target", "cpk >= 1.33"],
        &[": spec_limits.stack: ", "needs a lower or an upper limit"],
    );
}

#[test]
fn allocate_cost_model_choice() {
    let both = allocatable_with(|s| {
        s["allocation"]["sources"]["x1"]["cost"]["exponential"] = json!({ "b": 2.0, "rate": 5.0 })
    });
    assert_bad_allocate(
        "cost-ambiguous",
        &both,
        &[],
        &[": allocation.sources.x1.cost: ", "choose one with --cost"],
    );
    assert_bad_allocate(
        "cost-missing",
        &both,
        &["--cost", "exponential"],
        &[": allocation.sources.x2.cost: has no exponential model"],
    );
    assert_bad_allocate(
        "cost-unknown",
        &both,
        &["--cost", "linear"],
        &["--cost: unknown cost model"],
    );
}

#[test]
fn allocate_with_too_few_samples_for_the_tail() {
    // assert_bad_allocate runs with --samples 1000: too few for a 99.865 % tail.
    assert_bad_allocate(
        "samples",
        &allocatable_with(|_| {}),
        &["--target", "p99.865 <= 1"],
        &[
            ": --samples: 1000 samples leave 1.4 samples",
            "use at least",
        ],
    );
}

// ---- Physical models of issue 4: bad parameters and a torque that engages no pin ----

/// A shipped scenario after `change`.
fn shipped_with(file: &str, change: impl FnOnce(&mut Value)) -> String {
    let path = common::workspace_dir().join("scenarios").join(file);
    let mut scenario: Value =
        serde_json::from_str(&rvtol_tests::shipped_text(path)).expect("shipped scenario is JSON");
    change(&mut scenario);
    serde_json::to_string_pretty(&scenario).expect("serialisable")
}

#[test]
fn contact_with_fewer_pins_than_teeth_plus_one() {
    let contents = shipped_with("rv80e-contact.json", |s| {
        s["reducer"]["params"]["cycloid_teeth"] = json!(40)
    });
    assert_bad_scenario(
        "contact-pins",
        &contents,
        Some("reducer.params.cycloid_teeth"),
        &["pin_count − 1"],
    );
}

#[test]
fn transmission_error_with_k1_at_or_above_one() {
    let contents = shipped_with("rv40e-transmission.json", |s| {
        s["reducer"]["params"]["eccentricity_mm"] = json!(1.6)
    });
    assert_bad_scenario(
        "te-k1",
        &contents,
        Some("reducer.params.eccentricity_mm"),
        &["K1", "below 1"],
    );
}

#[test]
fn transmission_error_with_too_few_points() {
    let contents = shipped_with("rv40e-transmission.json", |s| {
        s["models"][0]["params"]["points_per_revolution"] = json!(2048)
    });
    assert_bad_scenario(
        "te-points",
        &contents,
        Some("models[0].params.points_per_revolution"),
        &["power of two above 3120"],
    );
}

#[test]
fn transmission_error_with_the_old_disc_spacing_key() {
    // The discs' spacing is the reducer's crank_eccentric_spacing_mm: the old key is told
    // its new name.
    let contents = shipped_with("rv40e-transmission.json", |s| {
        s["models"][0]["params"]["disc_spacing_mm"] = json!(12.0)
    });
    assert_bad_scenario(
        "te-disc-spacing",
        &contents,
        Some("models[0].params.disc_spacing_mm"),
        &["renamed crank_eccentric_spacing_mm"],
    );
}

#[test]
fn contact_with_zero_face_width() {
    let contents = shipped_with("rv80e-contact.json", |s| {
        s["reducer"]["params"]["disc_face_width_mm"] = json!(0.0)
    });
    assert_bad_scenario(
        "contact-face-width",
        &contents,
        Some("reducer.params.disc_face_width_mm"),
        &["must be positive"],
    );
}

#[test]
fn elastic_with_negative_stiffness() {
    let contents = shipped_with("rv40e-elastic.json", |s| {
        s["models"][0]["params"]["crank_bearing_stiffness_n_per_mm"] = json!(-3e5)
    });
    assert_bad_scenario(
        "elastic-stiffness",
        &contents,
        Some("models[0].params.crank_bearing_stiffness_n_per_mm"),
        &["must be positive"],
    );
}

#[test]
fn torsion_with_zero_rated_torque() {
    let contents = shipped_with("rv20e-torsion.json", |s| {
        s["reducer"]["params"]["rated_torque_nm"] = json!(0.0)
    });
    assert_bad_scenario(
        "torsion-rated",
        &contents,
        Some("reducer.params.rated_torque_nm"),
        &["must be positive"],
    );
}

#[test]
fn contact_with_a_torque_that_engages_no_pin() {
    let contents = shipped_with("rv80e-contact.json", |s| {
        s["models"][0]["inputs"]["output_torque_nm"] = json!(0.0)
    });
    assert_bad_scenario(
        "contact-torque",
        &contents,
        Some("models[0].inputs.output_torque_nm"),
        &["engages no pin"],
    );
}

#[test]
fn elastic_with_a_torque_that_engages_no_pin() {
    let contents = shipped_with("rv40e-elastic.json", |s| {
        s["models"][0]["inputs"]["output_torque_nm"] = json!(0)
    });
    assert_bad_scenario(
        "elastic-torque",
        &contents,
        Some("models[0].inputs.output_torque_nm"),
        &["engages no pin"],
    );
}

/// `rvtol init` checks its parameters as `validate` checks a scenario's: every parameter of
/// every model at an absurd value (1e308, outside every range a scenario accepts) or given
/// as a non-number is refused with one line naming `--param`, and nothing is written.
#[test]
fn init_refuses_every_parameter_validate_would_refuse() {
    let dir = std::env::temp_dir().join(format!("rvtol-bad-init-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let skeleton = dir.join("skeleton.json");
    let out = skeleton.to_str().expect("utf-8 path");
    let mut cases = 0;
    for entry in rvtol_models::all() {
        for spec in entry.params {
            for value in ["1e308", "-1e308", "abc"] {
                let param = format!("{}={value}", spec.name);
                let what = format!("init {} --param {param}", entry.name);
                let output = run_rvtol(&["init", entry.name, "--param", &param, "-o", out]);
                assert_one_line_error(&what, &output, &["error: --param "]);
                assert!(!skeleton.exists(), "{what}: a skeleton was written");
                cases += 1;
            }
        }
    }
    assert!(cases > 100, "{cases} cases");
    // The one named in the issue: a parameter the physical reading does not read is still
    // the model's number.
    let output = run_rvtol(&[
        "init",
        "transmission_error",
        "--param",
        "output_pin_circle_radius_mm=abc",
    ]);
    assert_one_line_error(
        "output_pin_circle_radius_mm=abc",
        &output,
        &["error: --param output_pin_circle_radius_mm: must be a number, got a string"],
    );
    let output = run_rvtol(&[
        "init",
        "geometric_hysteresis",
        "--param",
        "center_distance_mm=1e308",
    ]);
    assert_one_line_error(
        "center_distance_mm=1e308",
        &output,
        &["error: --param center_distance_mm: 1e308 is outside ±"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The shipped geometric RV-20E with `change` applied to its JSON.
fn rv20e_lost_motion_with(change: impl FnOnce(&mut Value)) -> String {
    let text = rvtol_tests::shipped_text(common::scenario("rv20e-lost-motion.json"));
    let mut scenario: Value = serde_json::from_str(&text).unwrap();
    change(&mut scenario);
    serde_json::to_string_pretty(&scenario).expect("serialisable")
}

#[test]
fn a_reducer_parameter_given_twice_or_taken_by_no_model_is_refused() {
    // A reducer is defined once: the `reducer` section's keys go to every model that knows
    // them, a model that gives one of them itself is refused, and so is a reducer key no
    // model takes, a source of no parameter, and a bad value, each at its own path.
    let twice = rv20e_lost_motion_with(|s| {
        s["models"][0]["params"]["pin_count"] = json!(40);
    });
    assert_bad_scenario(
        "reducer key given twice",
        &twice,
        Some("models[0].params.pin_count"),
        &["also given in reducer.params", "defined once"],
    );
    // A shared reducer file holds the keys of every model of its reducer; a key no model
    // of rvtol takes is still refused.
    let unused = rv20e_lost_motion_with(|s| {
        s["reducer"]["params"]["needle_row_count"] = json!(15);
    });
    assert_bad_scenario(
        "reducer key no model takes",
        &unused,
        Some("reducer.params.needle_row_count"),
        &["no model of rvtol takes it", "reducers/rv20e.json"],
    );
    // A section of the scenario's own holds what its models take: the torsion curve's
    // crank circle radius (rv_lost_motion's crank circle is the centre distance) is
    // refused there.
    let inline = rv20e_lost_motion_with(|s| {
        let reducer = s["reducer"].as_object_mut().unwrap();
        reducer.remove("file");
        let params = reducer["params"].as_object_mut().unwrap();
        let entry = rvtol_models::find("rv_lost_motion").unwrap();
        params.retain(|key, _| entry.params.iter().any(|spec| spec.name == key));
        params.insert("crank_circle_radius_mm".into(), json!(27.5));
        reducer["sources"]
            .as_object_mut()
            .unwrap()
            .retain(|key, _| entry.params.iter().any(|spec| spec.name == key));
    });
    assert_bad_scenario(
        "inline reducer key no model of the scenario takes",
        &inline,
        Some("reducer.params.crank_circle_radius_mm"),
        &["no model of this scenario takes it", "rv_lost_motion"],
    );
    let source = rv20e_lost_motion_with(|s| {
        s["reducer"]["sources"]["pin_length_mm"] = json!("a drawing");
    });
    assert_bad_scenario(
        "source of no parameter",
        &source,
        Some("reducer.sources.pin_length_mm"),
        &["not a key of reducer.params"],
    );
    let value = rv20e_lost_motion_with(|s| {
        s["reducer"]["params"]["crank_count"] = json!(4);
    });
    assert_bad_scenario(
        "bad reducer value",
        &value,
        Some("reducer.params.crank_count"),
        &["must be 2 or 3"],
    );
}
