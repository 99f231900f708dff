//! The scenario format's ways of writing the inputs: variable arrays bound by `*` patterns
//! (the same draws as separate variables, one error source), and measured values
//! resampled by an `empirical` distribution, inline or from a CSV column (its moments, its
//! support, its unit, its reproducibility and its shards), and parts written in µm and
//! arcsec, with every refusal naming its JSON path.

use crate::common;

use std::path::{Path, PathBuf};

use common::run_rvtol;
use rvtol_engine::report::RunReport;
use rvtol_engine::{run, sample_table, RunSettings, Scenario, DEFAULT_EXACT_PERCENTILE_LIMIT};
use rvtol_tests::{scenario_path, SIGMA_BOUND};
use serde_json::{json, Value};

fn settings(samples: u64, seed: u64) -> RunSettings {
    RunSettings {
        samples,
        seed,
        exact_percentile_limit: DEFAULT_EXACT_PERCENTILE_LIMIT,
        sampling: Default::default(),
    }
}

/// A linear stack y = Σ a_k·e_k over `n` inputs e_1 … e_n, each a tolerance band ± 0.01.
fn stack(n: usize, as_array: bool) -> Value {
    let coefficients: serde_json::Map<String, Value> = (1..=n)
        .map(|k| (format!("e_{k}"), json!(k as f64 * 0.5 - 1.0)))
        .collect();
    let band = json!({ "tolerance_band": { "lower": -0.01, "upper": 0.01, "cp": 1.0 } });
    let (variables, inputs) = if as_array {
        (
            json!([{ "name": "e", "unit": "mm", "count": n, "distribution": band }]),
            json!({ "e_*": "e" }),
        )
    } else {
        let variables: Vec<Value> = (1..=n)
            .map(|k| json!({ "name": format!("e_{k}"), "unit": "mm", "distribution": band }))
            .collect();
        let inputs: serde_json::Map<String, Value> = (1..=n)
            .map(|k| (format!("e_{k}"), json!(format!("e_{k}"))))
            .collect();
        (Value::from(variables), Value::from(inputs))
    };
    json!({
        "name": "array-stack",
        "variables": variables,
        "models": [{
            "model": "linear_stack",
            "params": { "coefficients": coefficients, "unit": "mm" },
            "inputs": inputs
        }]
    })
}

/// A run's JSON report without the digest of its scenario text and the sources of its
/// inputs (an array's members share its name, separate variables have their own): the
/// figures two texts that draw the same samples share.
fn figures(scenario: &Scenario, result: rvtol_engine::RunResult) -> String {
    let mut report = RunReport::new(scenario, result);
    report.scenario_sha256.clear();
    for input in &mut report.inputs {
        input.source.clear();
    }
    report.to_json()
}

fn scenario(document: &Value) -> Scenario {
    Scenario::from_json(&document.to_string(), "test").unwrap()
}

fn error(document: &Value) -> String {
    match Scenario::from_json(&document.to_string(), "test") {
        Ok(_) => panic!("accepted: {document}"),
        Err(err) => err.to_string(),
    }
}

#[test]
fn an_array_draws_what_its_members_as_variables_draw() {
    // The array's members are columns in the place of the separate variables, drawn from
    // the same stream positions: the run reports are the same bytes. Its variance is the
    // closed form Σ a_k²·σ², σ = 0.02/6 (tolerance band at Cp 1).
    let n = 12;
    let array = scenario(&stack(n, true));
    let separate = scenario(&stack(n, false));
    let names: Vec<&str> = array.columns.iter().map(|c| c.name.as_str()).collect();
    let expected: Vec<String> = (1..=n).map(|k| format!("e_{k}")).collect();
    assert_eq!(names, expected);
    assert_eq!(array.sources.len(), 1);
    assert_eq!(array.sources[0].name, "e");
    assert_eq!(array.sources[0].columns, (0..n).collect::<Vec<_>>());
    assert_eq!(separate.sources.len(), n);
    let a = run(&array, settings(40_000, 3), &|_| {}).unwrap();
    let b = run(&separate, settings(40_000, 3), &|_| {}).unwrap();
    assert_eq!(figures(&array, a), figures(&separate, b));
    let sigma = 0.02 / 6.0;
    let variance: f64 = (1..=n)
        .map(|k| (k as f64 * 0.5 - 1.0).powi(2) * sigma * sigma)
        .sum();
    let (cov_columns, _, cov) = array.input_space.gaussian_specification();
    assert_eq!(cov_columns.len(), n);
    let coefficients: Vec<f64> = (1..=n).map(|k| k as f64 * 0.5 - 1.0).collect();
    let mut from_space = 0.0;
    for i in 0..n {
        for j in 0..n {
            from_space += coefficients[i] * cov[(i, j)] * coefficients[j];
        }
    }
    assert!((from_space - variance).abs() <= 1e-15 * variance);
}

#[test]
fn the_shipped_transmission_scenarios_use_arrays() {
    // 40 pins × (radial, tangential) and 39 tooth spaces per disc as four arrays: the
    // file lists 28 variables for 182 quantities, each array one source.
    let text = rvtol_tests::shipped_text(scenario_path("rv40e-transmission.json"));
    let document: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(document["variables"].as_array().unwrap().len(), 28);
    let te = Scenario::from_json(&text, "te").unwrap();
    assert_eq!(te.columns.len(), 3 * 6 + 182);
    for (name, count) in [
        ("pin_radial", 40),
        ("pin_tangential", 40),
        ("tooth_profile_1", 39),
        ("tooth_profile_2", 39),
    ] {
        let source = te.sources.iter().find(|s| s.name == name).unwrap();
        assert_eq!(source.columns.len(), count, "{name}");
        let last = format!("{name}_{count}");
        assert!(te.columns.iter().any(|c| c.name == last), "{last}");
    }
}

#[test]
fn a_pattern_may_bind_one_number_or_one_variable_to_every_input_it_matches() {
    let mut document = stack(3, true);
    document["models"][0]["inputs"] = json!({ "e_*": 0.25 });
    let constant = scenario(&document);
    let result = run(&constant, settings(100, 1), &|_| {}).unwrap();
    // y = 0.25·Σ a_k = 0.25·(−0.5 + 0 + 0.5) = 0, with no spread.
    assert_eq!(result.outputs[0].moments.mean, 0.0);
    document["variables"] = json!([{ "name": "common", "unit": "mm", "distribution": { "normal": { "mean": 1.0, "sd": 0.0 } } }]);
    document["models"][0]["inputs"] = json!({ "e_*": "common" });
    let shared = scenario(&document);
    assert_eq!(shared.columns.len(), 1);
}

/// A change to a scenario document.
type Mutation = Box<dyn Fn(&mut Value)>;

#[test]
fn array_mistakes_are_refused_with_their_json_path() {
    let mut cases: Vec<(Mutation, &str)> = vec![
        (
            Box::new(|d| d["variables"][0]["count"] = json!(0)),
            "variables[0].count: an array has 1 to 100000 members, got 0",
        ),
        (
            Box::new(|d| d["variables"][0]["count"] = json!(100_001)),
            "variables[0].count: an array has 1 to 100000 members, got 100001",
        ),
        (
            Box::new(|d| d["variables"][0]["count"] = json!(4)),
            "models[0].inputs.e_*: binds 3 inputs (indices 1-3) but \"e\" has 4 members: the array must match the inputs one to one",
        ),
        (
            Box::new(|d| d["variables"][0]["count"] = json!(2)),
            "models[0].inputs.e_*: binds \"e_3\" to member 3 of \"e\", which has 2 members",
        ),
        (
            Box::new(|d| d["models"][0]["inputs"]["e_2"] = json!("e_2")),
            "models[0].inputs.e_*: binds \"e_2\", which models[0].inputs.e_2 binds already",
        ),
        (
            Box::new(|d| d["models"][0]["inputs"] = json!({ "e_1": "e", "e_2": "e_2", "e_3": "e_3" })),
            "models[0].inputs.e_1: \"e\" is an array of 3 members: bind it with a pattern (\"e_1_*\": \"e\") or name one member (e_1 …)",
        ),
        (
            Box::new(|d| d["models"][0]["inputs"]["f_*"] = json!("e")),
            "models[0].inputs.f_*: matches no input of linear_stack; its inputs are: e_{1..3}",
        ),
        (
            Box::new(|d| d["models"][0]["inputs"] = json!({})),
            "models[0].inputs: 3 model inputs are not bound: e_{1..3} (mm); give each a number or a variable name",
        ),
        (
            Box::new(|d| d["models"][0]["inputs"] = json!({ "e_*_*": "e" })),
            "models[0].inputs.e_*_*: a pattern has one '*', which stands for the index (1, 2, …)",
        ),
        (
            Box::new(|d| {
                d["variables"]
                    .as_array_mut()
                    .unwrap()
                    .push(json!({ "name": "e_2", "distribution": { "normal": { "mean": 0, "sd": 1 } } }))
            }),
            "variables[1].name: name \"e_2\" is used twice",
        ),
        (
            Box::new(|d| {
                d["variables"]
                    .as_array_mut()
                    .unwrap()
                    .push(json!({ "name": "e", "distribution": { "normal": { "mean": 0, "sd": 1 } } }))
            }),
            "variables[0].name: name \"e\" is used twice (by this array and by a variable or part component)",
        ),
        (
            Box::new(|d| d["variables"][0]["count"] = json!(2.5)),
            "variables[0].count: invalid type: floating point `2.5`, expected a whole number of at least 0",
        ),
    ];
    cases.push((
        Box::new(|d| d["correlations"] = json!([{ "between": ["e", "e_1"], "rho": 0.5 }])),
        "correlations[0].between[0]: \"e\" is an array of 3 members: correlate a member (e_1 …)",
    ));
    // A typo in a pattern: its own line first, naming the inputs it left unbound, then one
    // line for all of them.
    cases.push((
        Box::new(|d| d["models"][0]["inputs"] = json!({ "f_*": "e" })),
        "models[0].inputs.f_*: matches no input of linear_stack; the inputs left unbound are: e_{1..3}",
    ));
    for (mutate, expected) in cases {
        let mut document = stack(3, true);
        mutate(&mut document);
        let message = error(&document);
        assert!(
            message.contains(expected),
            "{message}\nexpected: {expected}"
        );
    }
}

/// Twelve measured values, exact in binary (so the CSV and the JSON give the same bits):
/// a skewed set, mean 8.25/12 = 0.6875, variance (1/n) 23.9375/12 − 0.6875² = 1.52214.
const MEASURED: [f64; 12] = [
    -1.0, -0.5, -0.25, 0.0, 0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.5, 3.5,
];

/// A stack y = 2·x + w over an empirical x and a normal w.
fn empirical_stack(empirical: Value, unit: &str) -> Value {
    json!({
        "name": "empirical-stack",
        "variables": [
            { "name": "x", "unit": unit, "distribution": { "empirical": empirical } },
            { "name": "w", "unit": "mm", "distribution": { "normal": { "mean": 0.0, "sd": 0.125 } } }
        ],
        "models": [{
            "model": "linear_stack",
            "params": { "coefficients": { "x": 2.0, "w": 1.0 }, "unit": "mm" },
            "inputs": { "x": "x", "w": "w" }
        }]
    })
}

fn moments(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, variance)
}

#[test]
fn plain_resampling_draws_only_the_measured_values_at_their_moments() {
    let scenario = scenario(&empirical_stack(json!({ "values": MEASURED }), "mm"));
    let n = 100_000;
    let table = sample_table(&scenario, settings(n, 11)).unwrap();
    let x: Vec<f64> = (0..table.rows)
        .map(|r| table.inputs[r * table.n_inputs])
        .collect();
    assert!(x.iter().all(|v| MEASURED.contains(v)));
    // The law's moments are the values' (divisor n); the draws' mean is within SIGMA_BOUND
    // standard errors of it, and each value's count within SIGMA_BOUND binomial sd of n/12
    // (n/6 for the 0, measured twice).
    let (m, s2) = moments(&MEASURED);
    assert_eq!(m, 0.6875);
    assert!((s2 - (23.9375 / 12.0 - 0.6875 * 0.6875)).abs() < 1e-15);
    let (mean, _) = moments(&x);
    assert!(
        (mean - m).abs() < SIGMA_BOUND * (s2 / n as f64).sqrt(),
        "{mean}"
    );
    for value in [-1.0, 0.0, 3.5] {
        let p = MEASURED.iter().filter(|v| **v == value).count() as f64 / 12.0;
        let count = x.iter().filter(|v| **v == value).count() as f64;
        let sd = (n as f64 * p * (1.0 - p)).sqrt();
        assert!(
            (count - n as f64 * p).abs() < SIGMA_BOUND * sd,
            "{value}: {count}"
        );
    }
    // The nominal takes the law's mean.
    assert_eq!(scenario.input_space.mean_row()[0], m);
}

#[test]
fn the_smoothed_bootstrap_keeps_the_values_moments_and_leaves_their_support() {
    // Silverman's bandwidth h for the twelve values, with the shrink c = √(1 + h²/s²): the
    // draws' mean and variance are the values' m and s², within SIGMA_BOUND standard errors:
    // √(s²/n) for the mean, s²·√((κ − 1)/n) for the variance, κ the law's kurtosis,
    // (μ4 + 6h²s² + 3h⁴)/(c⁴s⁴) with μ4 the values' fourth central moment (the draw is
    // m + (D + hZ)/c, D the value's deviation, Z an independent standard normal).
    let scenario = scenario(&empirical_stack(
        json!({ "values": MEASURED, "bandwidth": "silverman" }),
        "mm",
    ));
    let n = 100_000;
    let table = sample_table(&scenario, settings(n, 12)).unwrap();
    let x: Vec<f64> = (0..table.rows)
        .map(|r| table.inputs[r * table.n_inputs])
        .collect();
    let (m, s2) = moments(&MEASURED);
    let (mean, variance) = moments(&x);
    assert!(
        (mean - m).abs() < SIGMA_BOUND * (s2 / n as f64).sqrt(),
        "{mean}"
    );
    let h = rvtol_deviation::EmpiricalLaw::silverman_bandwidth(&MEASURED);
    let mu4 = MEASURED.iter().map(|v| (v - m).powi(4)).sum::<f64>() / MEASURED.len() as f64;
    let c2 = 1.0 + h * h / s2;
    let kurtosis = (mu4 + 6.0 * h * h * s2 + 3.0 * h.powi(4)) / (c2 * c2 * s2 * s2);
    assert!(
        (variance - s2).abs() < SIGMA_BOUND * s2 * ((kurtosis - 1.0) / n as f64).sqrt(),
        "{variance} (kurtosis {kurtosis})"
    );
    assert!(x.iter().filter(|v| !MEASURED.contains(v)).count() > n as usize / 2);
    assert!(x.iter().any(|v| *v > 3.5) && x.iter().any(|v| *v < -1.0));
}

#[test]
fn an_empirical_run_is_the_same_bytes_on_1_2_and_4_threads() {
    let scenario = scenario(&empirical_stack(
        json!({ "values": MEASURED, "bandwidth": 0.25 }),
        "mm",
    ));
    let reports: Vec<String> = [1, 2, 4]
        .iter()
        .map(|&threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let result = pool
                .install(|| run(&scenario, settings(50_000, 2), &|_| {}))
                .unwrap();
            RunReport::new(&scenario, result).to_json()
        })
        .collect();
    assert_eq!(reports[0], reports[1]);
    assert_eq!(reports[0], reports[2]);
}

#[test]
fn empirical_values_in_micrometres_are_converted_to_the_models_millimetres() {
    // linear_stack takes any unit, so the conversion is seen through an RV-20E input in mm:
    // the pin radius error written as measured values in µm.
    let mut document: Value = serde_json::from_str(&rvtol_tests::shipped_text(scenario_path(
        "rv20e-hysteresis.json",
    )))
    .unwrap();
    let variable = variable_mut(&mut document, "pin_radius_error");
    variable["unit"] = "µm".into();
    variable["distribution"] = json!({ "empirical": { "values": MEASURED } });
    let scenario = scenario(&document);
    let column = scenario
        .columns
        .iter()
        .position(|c| c.name == "pin_radius_error")
        .unwrap();
    assert_eq!(scenario.columns[column].unit.as_deref(), Some("mm"));
    let (m, _) = moments(&MEASURED);
    assert!((scenario.input_space.mean_row()[column] - m * 1e-3).abs() < 1e-18);
    // A unit rvtol does not know is named as such, at the variable's `unit`.
    let variable = variable_mut(&mut document, "pin_radius_error");
    variable["unit"] = "micron".into();
    let message = error(&document);
    assert!(
        message.contains(
            "variables[1].unit: \"micron\" is not a unit rvtol knows (lengths mm, µm, um, m;"
        ),
        "{message}"
    );
}

/// A folder in the temporary directory, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(label: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("rvtol-{label}-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("data")).unwrap();
        TempDir(dir)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

/// The measured values as a CSV with a part number, the column `x [mm]` and a shorter
/// column (empty cells).
fn measured_csv() -> String {
    let mut text = String::from("part,x [mm],note\n");
    for (i, v) in MEASURED.iter().enumerate() {
        text.push_str(&format!("{},{v},{}\n", i + 1, if i < 3 { "7" } else { "" }));
    }
    text
}

fn load(path: &Path) -> Result<Scenario, String> {
    rvtol_analysis::request::scenario::load(path).map_err(|err| err.to_string())
}

#[test]
fn a_csv_column_is_read_relative_to_the_scenario_and_written_into_its_text() {
    let dir = TempDir::new("empirical-csv");
    dir.write("data/measured.csv", &measured_csv());
    let reference = empirical_stack(json!({ "csv": "data/measured.csv", "column": "x" }), "mm");
    let path = dir.write("stack.json", &reference.to_string());
    let (from_file, text) = rvtol_analysis::request::scenario::read(&path).unwrap();
    let inline = scenario(&empirical_stack(json!({ "values": MEASURED }), "mm"));
    let a = run(&from_file, settings(20_000, 5), &|_| {}).unwrap();
    let b = run(&inline, settings(20_000, 5), &|_| {}).unwrap();
    assert_eq!(figures(&from_file, a), figures(&inline, b));
    // The text carries the numbers with their source in place of the reference, and
    // parses without the CSV.
    let document: Value = serde_json::from_str(&text).unwrap();
    let empirical = &document["variables"][0]["distribution"]["empirical"];
    assert_eq!(empirical["values"], json!(MEASURED));
    assert_eq!(
        empirical["source"],
        "data/measured.csv, column x: 12 values"
    );
    assert!(empirical.get("csv").is_none() && empirical.get("column").is_none());
    assert!(Scenario::from_json(&text, "copy").is_ok());
    // Windows line ends count the lines as a reader of the file does.
    dir.write("data/crlf.csv", "x [mm]\r\n1\r\n2\r\nthree\r\n");
    let mut crlf = reference.clone();
    crlf["variables"][0]["distribution"]["empirical"]["csv"] = "data/crlf.csv".into();
    let path = dir.write("crlf.json", &crlf.to_string());
    let message = load(&path).err().unwrap();
    assert!(
        message.contains("line 4, column 'x': not a finite number: 'three'"),
        "{message}"
    );
    // A column headed with a unit gives it to a variable without one.
    let mut no_unit = reference.clone();
    no_unit["variables"][0]
        .as_object_mut()
        .unwrap()
        .remove("unit");
    let path = dir.write("no-unit.json", &no_unit.to_string());
    assert_eq!(load(&path).unwrap().columns[0].unit.as_deref(), Some("mm"));
    // A text without a CSV reference is returned as it is.
    let plain = rvtol_tests::shipped_text(scenario_path("rv20e-hysteresis.json"));
    let (_, text) =
        rvtol_analysis::request::scenario::read(&scenario_path("rv20e-hysteresis.json")).unwrap();
    assert_eq!(text, plain);
}

#[test]
fn empirical_mistakes_are_refused_with_their_json_path() {
    let dir = TempDir::new("empirical-errors");
    dir.write("data/measured.csv", &measured_csv());
    dir.write("data/bad.csv", "x [mm]\n1\ntwo\n");
    let at = "variables[0].distribution.empirical";
    let cases: Vec<(Value, &str, String)> = vec![
        (
            json!({ "csv": "data/missing.csv", "column": "x" }),
            "mm",
            format!("{at}.csv: "),
        ),
        (
            json!({ "csv": "data/measured.csv", "column": "y" }),
            "mm",
            format!("{at}.column: "),
        ),
        (
            json!({ "csv": "data/bad.csv", "column": "x" }),
            "mm",
            format!("{at}.csv: "),
        ),
        (
            json!({ "csv": "data/measured.csv" }),
            "mm",
            format!("{at}.column: name the CSV column that holds the measured values"),
        ),
        (
            json!({ "csv": "data/measured.csv", "column": "x" }),
            "µm",
            "variables[0].unit: µm differs from the unit of the column \"x\"".to_string(),
        ),
        (
            json!({ "values": [1.5] }),
            "mm",
            format!("{at}.values: needs at least 2 values to resample, got 1"),
        ),
        (
            json!({ "values": [1.5, 2.0], "bandwidth": -0.5 }),
            "mm",
            format!("{at}.bandwidth: must not be negative"),
        ),
        (
            json!({ "values": [1.5, 2.0], "bandwidth": "scott" }),
            "mm",
            format!(
                "{at}.bandwidth: expected a number ≥ 0 (in the variable's unit) or \"silverman\""
            ),
        ),
        (
            json!({}),
            "mm",
            format!("{at}: give the measured numbers in `values`, or a CSV file and its column"),
        ),
        (
            json!({ "values": [1.0, 2.0], "csv": "data/measured.csv", "column": "x" }),
            "mm",
            format!(
                "{at}: give the numbers in `values` or a CSV file in `csv` and `column`, not both"
            ),
        ),
        (
            json!({ "csv": "data/empty.csv", "column": "x" }),
            "mm",
            format!("{at}.column: the column \"x\" of "),
        ),
        (
            json!({ "csv": "data/measured.csv", "column": "x", "bandwidth": 0.1 }),
            "micron",
            "variables[0].unit: micron differs from the unit of the column \"x\"".to_string(),
        ),
        (
            json!({ "csv": "data/semicolons.csv", "column": "x" }),
            "mm",
            "line 1: the columns are separated by ';': rvtol reads comma-separated values"
                .to_string(),
        ),
    ];
    dir.write("data/empty.csv", "x [mm],y\n,1\n,2\n");
    dir.write("data/semicolons.csv", "x;y\n1;2\n");
    for (k, (empirical, unit, expected)) in cases.into_iter().enumerate() {
        let path = dir.write(
            &format!("case-{k}.json"),
            &empirical_stack(empirical, unit).to_string(),
        );
        let message = load(&path).err().expect("refused");
        assert!(
            message.contains(&expected),
            "{message}\nexpected: {expected}"
        );
        // The command line says the same in one line, exit 2.
        let out = run_rvtol(&["validate", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2));
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(&expected), "{stderr}");
    }
    // Without the scenario's file (a text or a Python dict) a CSV reference cannot be read.
    let text = empirical_stack(json!({ "csv": "data/measured.csv", "column": "x" }), "mm");
    let message = error(&text);
    assert!(
        message.contains(&format!(
            "{at}.csv: a data file is read when the scenario is loaded from its file"
        )),
        "{message}"
    );
}

#[test]
fn shards_of_a_scenario_with_a_csv_merge_without_it() {
    // The shard files carry the scenario text with the numbers written in: the merge
    // gives the single run's report byte for byte after the CSV is gone.
    let dir = TempDir::new("empirical-shards");
    let csv = dir.write("data/measured.csv", &measured_csv());
    let path = dir.write(
        "stack.json",
        &empirical_stack(
            json!({ "csv": "data/measured.csv", "column": "x", "bandwidth": "silverman" }),
            "mm",
        )
        .to_string(),
    );
    let single = dir.0.join("single.json");
    let args = |extra: &[&str]| -> Vec<String> {
        let mut args: Vec<String> = [
            "run",
            path.to_str().unwrap(),
            "--samples",
            "30000",
            "--quiet",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let out = run_rvtol(&args(&["--json", single.to_str().unwrap()]));
    assert_eq!(out.status.code(), Some(0));
    let mut partials = Vec::new();
    for k in 0..3 {
        let partial = dir.0.join(format!("part-{k}.rvtol"));
        let shard = format!("{k}/3");
        let out = run_rvtol(&args(&[
            "--shard",
            &shard,
            "--partial",
            partial.to_str().unwrap(),
        ]));
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        partials.push(partial.to_str().unwrap().to_string());
    }
    std::fs::remove_file(csv).unwrap();
    let merged = dir.0.join("merged.json");
    let mut merge = vec!["merge".to_string()];
    merge.extend(partials);
    merge.extend(["--json".to_string(), merged.to_str().unwrap().to_string()]);
    let out = run_rvtol(&merge);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(&single).unwrap(),
        std::fs::read(&merged).unwrap()
    );
}

/// The linear stack's carrier part rewritten with translations in µm and rotations in
/// arcsec, as `sd` + correlation or as a covariance.
fn carrier_in_micrometres_and_arcsec(as_covariance: bool) -> Value {
    let mut document: Value = serde_json::from_str(
        &std::fs::read_to_string(scenario_path("linear-stack-correlated.json")).unwrap(),
    )
    .unwrap();
    let part = &mut document["parts"][0];
    let arcsec_per_rad = 648_000.0 / std::f64::consts::PI;
    let factors = [
        1e3,
        1e3,
        1e3,
        arcsec_per_rad,
        arcsec_per_rad,
        arcsec_per_rad,
    ];
    let scale = |values: &Value| -> Vec<f64> {
        values
            .as_array()
            .unwrap()
            .iter()
            .zip(factors)
            .map(|(v, f)| v.as_f64().unwrap() * f)
            .collect()
    };
    let mean = scale(&part["mean"]);
    let sd = scale(&part["sd"]);
    part["mean"] = json!(mean);
    part["units"] = json!({ "translation": "µm", "rotation": "arcsec" });
    if as_covariance {
        let correlation = part["correlation"].clone();
        let covariance: Vec<Vec<f64>> = (0..6)
            .map(|i| {
                (0..6)
                    .map(|j| correlation[i][j].as_f64().unwrap() * sd[i] * sd[j])
                    .collect()
            })
            .collect();
        let object = part.as_object_mut().unwrap();
        object.remove("sd");
        object.remove("correlation");
        object.insert("covariance".into(), json!(covariance));
    } else {
        part["sd"] = json!(sd);
    }
    document
}

#[test]
fn a_part_in_micrometres_and_arcsec_is_the_part_in_millimetres_and_radians() {
    // The joint normal's mean and covariance over every column agree with the shipped
    // file's to rounding (relative 1e-12), for both ways of giving the part.
    let shipped =
        rvtol_analysis::request::scenario::load(&scenario_path("linear-stack-correlated.json"))
            .unwrap();
    let (columns, mean, cov) = shipped.input_space.gaussian_specification();
    for as_covariance in [false, true] {
        let converted = scenario(&carrier_in_micrometres_and_arcsec(as_covariance));
        let (c, m, v) = converted.input_space.gaussian_specification();
        assert_eq!(c, columns);
        for i in 0..columns.len() {
            assert!((m[i] - mean[i]).abs() <= 1e-12 * mean[i].abs().max(1e-300));
            for j in 0..columns.len() {
                let scale = (cov[(i, i)] * cov[(j, j)]).sqrt().max(1e-300);
                assert!((v[(i, j)] - cov[(i, j)]).abs() <= 1e-12 * scale, "{i} {j}");
            }
        }
        let units: Vec<_> = converted.columns[..6]
            .iter()
            .map(|c| c.unit.clone().unwrap())
            .collect();
        assert_eq!(units, ["mm", "mm", "mm", "rad", "rad", "rad"]);
    }
}

#[test]
fn part_unit_mistakes_are_refused_with_their_json_path() {
    let mut document = carrier_in_micrometres_and_arcsec(false);
    document["parts"][0]["units"]["rotation"] = "µm".into();
    assert!(error(&document)
        .contains("parts[0].units.rotation: \"µm\" is not a unit of angle rvtol knows"));
    let mut document = carrier_in_micrometres_and_arcsec(false);
    document["parts"][0]["units"]["length"] = "µm".into();
    assert!(error(&document).contains("parts[0].units.length: unknown field `length`"));
    // A value's error says which units it was written in.
    let mut document = carrier_in_micrometres_and_arcsec(false);
    document["parts"][0]["sd"][0] = json!(-3.0);
    let message = error(&document);
    assert!(
        message.contains("parts[0].sd")
            && message.contains("(converted from µm and arcsec to mm and rad)"),
        "{message}"
    );
    let mut document = carrier_in_micrometres_and_arcsec(false);
    let part = document["parts"][0].as_object_mut().unwrap();
    for key in ["mean", "sd", "correlation"] {
        part.remove(key);
    }
    part.insert(
        "tolerance_band".into(),
        json!({ "delta_tau_mm": 0.004, "length_mm": 50 }),
    );
    assert!(error(&document).contains("parts[0].units: a tolerance_band part is given in mm"));
}

/// The variable named `name` of a scenario document.
fn variable_mut<'a>(document: &'a mut Value, name: &str) -> &'a mut Value {
    document["variables"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|v| v["name"] == name)
        .unwrap()
}

#[test]
fn a_reducer_section_is_its_parameters_given_to_each_model() {
    // scenarios/rv20e-lost-motion.json names its reducer file (scenarios/reducers/rv20e.json,
    // written into the text when loaded); the same parameters written into the model's
    // `params` give the same run, bit for bit.
    let text = rvtol_tests::shipped_text(scenario_path("rv20e-lost-motion.json"));
    let shared: Value = serde_json::from_str(&text).unwrap();
    let mut inline = shared.clone();
    let reducer = inline
        .as_object_mut()
        .unwrap()
        .remove("reducer")
        .expect("the scenario has a reducer section");
    // The shared file holds every model's keys: the model takes those it knows.
    let entry = rvtol_models::find("rv_lost_motion").unwrap();
    for (key, value) in reducer["params"].as_object().unwrap() {
        if entry.params.iter().any(|spec| spec.name == key) {
            inline["models"][0]["params"][key] = value.clone();
        }
    }
    let results: Vec<Vec<u64>> = [shared, inline]
        .iter()
        .map(|document| {
            let result = run(&scenario(document), settings(256, 3), &|_| {}).unwrap();
            result
                .outputs
                .iter()
                .flat_map(|o| [o.moments.mean.to_bits(), o.moments.m2.to_bits()])
                .collect()
        })
        .collect();
    assert_eq!(results[0], results[1]);
}
