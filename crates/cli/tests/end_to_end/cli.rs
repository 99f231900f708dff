//! End-to-end tests of the `rvtol` binary on the shipped scenarios: the two README
//! commands' work, byte-identical JSON reports across thread counts, the report contract
//! (keys users' scripts rely on), `nominal`, `models`, and atomic report writing.

use crate::common;

use common::{run_rvtol, scenario};

fn temp_path(label: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("rvtol-cli-{label}-{}.json", std::process::id()))
}

#[test]
fn run_json_is_byte_identical_with_1_2_and_4_threads() {
    let mut reports = Vec::new();
    for threads in ["1", "2", "4"] {
        let path = temp_path(&format!("threads-{threads}"));
        let output = run_rvtol(&[
            "run",
            &scenario("rv20e-hysteresis.json"),
            "--samples",
            "300000",
            "--seed",
            "17",
            "--threads",
            threads,
            "--json",
            path.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        reports.push(std::fs::read(&path).unwrap());
        std::fs::remove_file(&path).unwrap();
    }
    assert_eq!(reports[0], reports[1]);
    assert_eq!(reports[0], reports[2]);
}

#[test]
fn run_report_has_the_documented_keys() {
    let output = run_rvtol(&[
        "run",
        &scenario("rv20e-hysteresis.json"),
        "--samples",
        "50000",
        "--json",
        "-",
        "--quiet",
    ]);
    assert_eq!(output.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    for key in ["rvtol_version", "seed", "samples", "outputs"] {
        assert!(report.get(key).is_some(), "missing {key}");
    }
    assert_eq!(report["samples"], 50000);
    assert_eq!(report["seed"], 20221013);
    let outputs = report["outputs"].as_array().unwrap();
    let hysteresis = outputs
        .iter()
        .find(|o| o["name"] == "hysteresis_arcmin")
        .unwrap();
    for key in [
        "name",
        "unit",
        "n",
        "mean",
        "sd",
        "min",
        "max",
        "percentiles",
        "histogram",
        "spec",
        "cp",
        "cpk",
        "ppm_out",
    ] {
        assert!(hysteresis.get(key).is_some(), "missing {key}");
    }
    // 36 % of the assemblies are over-preloaded: beyond the upper limit, so the upper
    // percentiles are null ("beyond"); the values' own are given beside.
    for percent in ["0.135", "2.275", "50", "97.725", "99.865"] {
        let beyond = ["97.725", "99.865"].contains(&percent);
        let value = &hysteresis["percentiles"][percent];
        assert!(
            if beyond {
                value.is_null()
            } else {
                value.is_f64()
            },
            "percentile {percent}"
        );
        assert!(
            hysteresis["value_percentiles"][percent].is_f64(),
            "{percent}"
        );
    }
    assert_eq!(hysteresis["unit"], "arcmin");
    assert_eq!(hysteresis["spec"]["upper"], 1.0);
    assert!(hysteresis["cp"].is_null(), "one-sided spec has no Cp");
    let preloaded = outputs.iter().find(|o| o["name"] == "preloaded").unwrap();
    assert_eq!(preloaded["kind"], "indicator");
    assert!(preloaded["fraction"].is_f64());
}

#[test]
fn nominal_marks_a_design_that_does_not_conform() {
    // rv20e-hysteresis with its profile-shift error's band moved to +3..+9 µm: the nominal
    // design is over-preloaded (802 N against the 365 N rated pin force), so its lost
    // motion is a value of an assembly out of spec, and nominal must say so.
    let mut scenario: serde_json::Value = serde_json::from_str(&rvtol_tests::shipped_text(
        scenario("rv20e-hysteresis.json"),
    ))
    .unwrap();
    let variables = scenario["variables"].as_array_mut().unwrap();
    let shift = (variables.iter_mut())
        .find(|v| v["name"] == "shift_modification_error")
        .unwrap();
    shift["distribution"]["tolerance_band"]["lower"] = 0.003.into();
    shift["distribution"]["tolerance_band"]["upper"] = 0.009.into();
    let over = common::TempScenario::new("cli-over-preloaded", &scenario.to_string());
    let output = run_rvtol(&["nominal", over.path().to_str().unwrap(), "--json", "-"]);
    assert_eq!(output.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let lost_motion = &report["outputs"][0];
    assert_eq!(lost_motion["name"], "hysteresis_arcmin");
    assert_eq!(lost_motion["flagged_by"], "over_preloaded");
    let text = run_rvtol(&["nominal", over.path().to_str().unwrap()]);
    let line = String::from_utf8_lossy(&text.stdout)
        .lines()
        .find(|l| l.starts_with("hysteresis_arcmin"))
        .unwrap()
        .to_string();
    assert!(
        line.ends_with("flagged by over_preloaded: does not conform"),
        "{line}"
    );
    // The shipped design is preloaded within the limit: a design state, no mark.
    let shipped = nominal_report("rv20e-hysteresis.json");
    assert!(shipped["outputs"][0].get("flagged_by").is_none());
}

#[test]
fn nominal_json_gives_the_published_hysteresis_at_the_design_point() {
    // 000 §5.2: 0.5467 arcmin, within 1 % (validation.md), for the design values with every
    // manufacturing error zero. The scenario's nominal is the mean of every input, which for
    // the magnitudes (runout, pitch error, clearance: Rayleigh and folded laws) is not zero,
    // so the design point binds them to 0.
    let mut scenario: serde_json::Value = serde_json::from_str(&rvtol_tests::shipped_text(
        scenario("rv20e-hysteresis.json"),
    ))
    .unwrap();
    // Document 000's reading of its Eq. 16 (the physical default puts the design's flanks
    // in overlap, docs/models.md §2).
    // With its printed K1 = 0.72 (the reducer derives 0.692).
    scenario["models"][0]["params"]["reading"] = "document_000".into();
    scenario["models"][0]["params"]["curtate_ratio"] = 0.72.into();
    let inputs = scenario["models"][0]["inputs"].as_object_mut().unwrap();
    for (name, binding) in inputs.iter_mut() {
        let variable = binding.as_str().is_some_and(|b| !b.starts_with("reducer."));
        if variable && name != "crank_bearing_clearance_mm" {
            *binding = 0.0.into();
        }
    }
    let design = common::TempScenario::new("cli-design-point", &scenario.to_string());
    let output = run_rvtol(&["nominal", design.path().to_str().unwrap(), "--json", "-"]);
    assert_eq!(output.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let value = nominal_value(&report, "hysteresis_arcmin");
    assert!((value - 0.5467).abs() < 0.01 * 0.5467, "{value}");
}

#[test]
fn models_lists_inputs_outputs_and_units() {
    let output = run_rvtol(&["models"]);
    assert_eq!(output.status.code(), Some(0));
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("geometric_hysteresis"));
    assert!(text.contains("linear_stack"));
    assert!(text.contains("cycloid_cumulative_pitch_error_mm"));
    assert!(text.contains("hysteresis_arcmin"));
}

/// Temporary files left in `dir` by writes to `file_name` (`.NAME.tmp-PID`).
fn leftover_temporaries(dir: &std::path::Path, file_name: &str) -> usize {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.starts_with(&format!(".{file_name}.tmp-"))
        })
        .count()
}

#[test]
fn reports_are_written_through_a_temporary_file() {
    // A successful run replaces the target and leaves no temporary file; a run that fails
    // (here on bad input) neither creates, truncates nor litters.
    let path = temp_path("atomic");
    let file_name = path.file_name().unwrap().to_string_lossy().into_owned();
    let dir = path.parent().unwrap().to_path_buf();
    std::fs::write(&path, "previous report\n").unwrap();
    let arguments = |samples: &str| {
        vec![
            "run".to_string(),
            scenario("rv20e-hysteresis.json"),
            "--samples".into(),
            samples.into(),
            "--json".into(),
            path.to_str().unwrap().into(),
            "--quiet".into(),
        ]
    };
    let output = run_rvtol(&arguments("0"));
    assert_eq!(output.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "previous report\n");
    assert_eq!(leftover_temporaries(&dir, &file_name), 0);

    let output = run_rvtol(&arguments("5000"));
    assert_eq!(output.status.code(), Some(0));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(report["samples"], 5000);
    assert_eq!(leftover_temporaries(&dir, &file_name), 0);
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn rv80e_contact_nominal_and_run() {
    // Nominal: the disc's torque balance gives F_x = T_c/(e·z_c) with T_c = 0.55·λ·800 N·m,
    // λ = (39/40)(1 − 1/121) (docs/models.md §10), exactly, and the 003 modification
    // engages 8–11 pins (validation.md 003).
    let report = nominal_report("rv80e-contact.json");
    let value = |name: &str| nominal_value(&report, name);
    let t_c = 0.55 * (39.0 / 40.0) * (1.0 - 1.0 / 121.0) * 800_000.0;
    assert!((value("pin_force_x_n") - t_c / 58.5).abs() < 1e-9 * 7272.0);
    assert!((8.0..=11.0).contains(&value("engaged_pins")));
    assert!(
        value("max_pin_force_n") > 752.14,
        "modification concentrates the load"
    );

    // 1e5 samples: every sample solved (no non-finite value), the F_x identity holds in
    // every sample, and the spread comes from the errors.
    let output = run_rvtol(&[
        "run",
        &scenario("rv80e-contact.json"),
        "--samples",
        "100000",
        "--json",
        "-",
        "--quiet",
    ]);
    assert_eq!(output.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    for o in report["outputs"].as_array().unwrap() {
        assert_eq!(o["non_finite"], 0, "{}", o["name"]);
        assert_eq!(o["n"], 100_000);
        let name = o["name"].as_str().unwrap();
        let (min, max) = (o["min"].as_f64().unwrap(), o["max"].as_f64().unwrap());
        match name {
            "pin_force_x_n" => assert!((max - min) < 1e-9 * max),
            "engaged_pins" => assert!(min >= 1.0 && max <= 40.0),
            "pin_force_y_n" => assert!(o["sd"].as_f64().unwrap() > 0.0),
            // The preload rule's outputs: 0 for a free assembly, most of them here.
            "preload_overlap_um"
            | "preload_pin_force_n"
            | "no_load_torque_nm"
            | "preloaded"
            | "over_preloaded" => assert!(min == 0.0 && max >= 0.0, "{name}"),
            _ => assert!(min > 0.0 && o["sd"].as_f64().unwrap() > 0.0, "{name}"),
        }
    }
}

/// The `value` of a named output of a `nominal --json -` report.
fn nominal_value(report: &serde_json::Value, name: &str) -> f64 {
    report["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|o| o["name"] == name)
        .unwrap_or_else(|| panic!("{name}"))["value"]
        .as_f64()
        .unwrap()
}

fn nominal_report(file: &str) -> serde_json::Value {
    let output = run_rvtol(&["nominal", &scenario(file), "--json", "-"]);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

/// A short run's JSON with `threads` workers.
fn run_json(file: &str, samples: &str, threads: &str) -> Vec<u8> {
    let output = run_rvtol(&[
        "run",
        &scenario(file),
        "--samples",
        samples,
        "--threads",
        threads,
        "--json",
        "-",
        "--quiet",
    ]);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    output.stdout
}

#[test]
fn new_physical_models_run_reproducibly_with_every_sample_finite() {
    // The transmission-error model keeps per-thread work buffers: the reproducibility
    // contract (same seed, same bytes, whatever the thread count) must still hold. 9000
    // samples are three chunks of at most 4096, so two threads really share the run.
    let samples = "9000";
    for file in [
        "rv40e-transmission.json",
        "rv40e-elastic.json",
        "rv20e-torsion.json",
        "rv40e-torsion.json",
        "rv80e-torsion.json",
    ] {
        let one = run_json(file, samples, "1");
        assert_eq!(one, run_json(file, samples, "2"), "{file}");
        let report: serde_json::Value = serde_json::from_slice(&one).unwrap();
        for o in report["outputs"].as_array().unwrap() {
            assert_eq!(o["non_finite"], 0, "{file} {}", o["name"]);
        }
    }
}

#[test]
fn rv40e_elastic_nominal_has_no_ripple_and_its_stiffness_is_torque_over_lag() {
    // docs/models.md §11: two equal cranks without misfit turn the disc by the same angle
    // all round the crank turn (no ripple, no four-bar turn), and the crank-side stiffness
    // is |T|/lag; the lag's closed form is checked in crates/models and tests/stiffness.rs.
    let report = nominal_report("rv40e-elastic.json");
    let lag = nominal_value(&report, "elastic_error_arcmin");
    assert!(lag > 0.0);
    assert!(nominal_value(&report, "elastic_error_ripple_arcmin").abs() < 1e-12);
    assert!(nominal_value(&report, "four_bar_error_arcmin").abs() < 1e-12);
    let stiffness = nominal_value(&report, "torsional_stiffness_nm_per_arcmin");
    assert!((stiffness - 412.0 / lag).abs() < 1e-9 * stiffness);
}

#[test]
fn rv20e_torsion_nominal_free_play_is_000s_involute_and_crank_terms() {
    // docs/models.md §13 (one profile): 000's design modification overlaps the cycloid
    // stage's flanks, so its nominal free play is 000's involute and crank-bearing terms,
    // which the RV-20E hysteresis scenario reports at its nominal; the loop is wider by the
    // preload's friction, and the lost motion exceeds the free play.
    let torsion = nominal_report("rv20e-torsion.json");
    let hysteresis = nominal_report("rv20e-hysteresis.json");
    let c = nominal_value(&hysteresis, "involute_stage_arcmin")
        + nominal_value(&hysteresis, "crank_bearing_arcmin");
    assert!((nominal_value(&torsion, "clearance_arcmin") - c).abs() < 1e-12);
    assert_eq!(nominal_value(&torsion, "preloaded"), 1.0);
    assert!(nominal_value(&torsion, "hysteresis_loss_arcmin") > c);
    assert!(nominal_value(&torsion, "lost_motion_arcmin") > c);
}

#[test]
fn curve_writes_csv_and_svg_for_the_transmission_error_and_torsion_models() {
    let dir = temp_path("curves");
    for file in ["rv40e-transmission.json", "rv20e-torsion.json"] {
        let output = run_rvtol(&["curve", &scenario(file), "--out-dir", dir.to_str().unwrap()]);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
    for stem in [
        "transmission_error",
        "transmission_error_detail",
        "transmission_error_spectrum",
        "torsion_curve",
        "torsion_curve_3_percent",
    ] {
        let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{stem}"
        );
        let csv = std::fs::read_to_string(dir.join(format!("{stem}.csv"))).unwrap();
        let rows = csv.lines().count() - 1;
        match stem {
            // 4096 points per revolution; orders 1..2048.
            "transmission_error" => assert_eq!(rows, 4096),
            "transmission_error_spectrum" => assert_eq!(rows, 2048),
            // The first 1/80 of the revolution at 65536 points per revolution, both ends.
            "transmission_error_detail" => assert_eq!(rows, 820),
            _ => assert!(rows > 100),
        }
    }
    // A scenario without curve-drawing models is bad input.
    let output = run_rvtol(&[
        "curve",
        &scenario("ishigami.json"),
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(output.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn init_writes_a_valid_runnable_skeleton_for_every_model() {
    // Every model of the registry: the skeleton validates, runs (finite figures only:
    // --max-non-finite is 0 by default) and binds every input of the model to a variable.
    let dir = std::env::temp_dir().join(format!("rvtol-init-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for entry in rvtol_models::all() {
        let path = dir.join(format!("{}.json", entry.name));
        let out = run_rvtol(&["init", entry.name, "-o", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", entry.name);
        let text = std::fs::read_to_string(&path).unwrap();
        let scenario: serde_json::Value = serde_json::from_str(&text).unwrap();
        let model = (entry.build)(&(entry.example_params)()).unwrap();
        let bound = scenario["models"][0]["inputs"].as_object().unwrap();
        // A family of indexed inputs is bound by one `*` key: count what each key covers.
        let covered: usize = bound
            .keys()
            .map(|key| match key.split_once('*') {
                Some((stem, tail)) => model
                    .inputs()
                    .iter()
                    .filter(|i| {
                        i.name.strip_prefix(stem).is_some_and(|rest| {
                            rest.strip_suffix(tail).is_some_and(|index| {
                                !index.is_empty() && index.bytes().all(|b| b.is_ascii_digit())
                            })
                        })
                    })
                    .count(),
                None => 1,
            })
            .sum();
        assert_eq!(covered, model.inputs().len(), "{}", entry.name);
        for (name, value) in entry.example_inputs {
            assert!(model.inputs().iter().any(|i| i.name == *name), "{name}");
            let variable = scenario["variables"]
                .as_array()
                .unwrap()
                .iter()
                .find(|v| v["name"] == *name)
                .unwrap();
            assert_eq!(variable["distribution"]["normal"]["mean"], *value);
        }
        let out = run_rvtol(&["validate", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(0), "{}", entry.name);
        let report = dir.join(format!("{}.report.json", entry.name));
        let out = run_rvtol(&[
            "run",
            path.to_str().unwrap(),
            "--samples",
            "100",
            "--quiet",
            "--json",
            report.to_str().unwrap(),
        ]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}: {}",
            entry.name,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // A design's parameters in place of the example's: the transmission error with an
    // input per pin and per tooth space, whose families the skeleton writes as arrays.
    let path = dir.join("te-pins.json");
    let out = run_rvtol(&[
        "init",
        "transmission_error",
        "--param",
        "pin_position_errors=1",
        "--param",
        "tooth_profile_errors=1",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let scenario: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let inputs = scenario["models"][0]["inputs"].as_object().unwrap();
    assert_eq!(inputs["pin_radial_error_mm_*"], "pin_radial_error_mm");
    assert_eq!(
        inputs["tooth_profile_error_mm_2_*"],
        "tooth_profile_error_mm_2"
    );
    let counts: Vec<u64> = scenario["variables"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v["count"].as_u64())
        .collect();
    assert_eq!(counts, [40, 40, 39, 39]);
    let out = run_rvtol(&["validate", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("(194 input columns"));
    for (bad, message) in [
        (
            "pin_position_errors",
            "--param pin_position_errors: expected KEY=VALUE",
        ),
        ("no_such=1", "--param no_such: unknown parameter"),
    ] {
        let out = run_rvtol(&["init", "transmission_error", "--param", bad]);
        assert_eq!(out.status.code(), Some(2));
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
    }
    let out = run_rvtol(&["init", "no_such_model"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("geometric_hysteresis"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn samples_out_writes_the_runs_own_rows_with_the_same_bytes_for_any_thread_count() {
    // The CSV's outputs are the values the run's statistics are made of: the exact
    // type-7 median of a column equals the report's P50 bit for bit, and the mean agrees
    // to rounding; the file is byte-identical for 1, 2 and 4 threads.
    let dir = std::env::temp_dir().join(format!("rvtol-samples-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut files = Vec::new();
    for threads in ["1", "2", "4"] {
        let csv = dir.join(format!("samples-{threads}.csv"));
        let json = dir.join(format!("report-{threads}.json"));
        let output = run_rvtol(&[
            "run",
            &scenario("rv20e-hysteresis.json"),
            "--samples",
            "10000",
            "--threads",
            threads,
            "--samples-out",
            csv.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        files.push((std::fs::read(&csv).unwrap(), json));
    }
    assert!(
        files[0].0 == files[1].0 && files[0].0 == files[2].0,
        "same seed, same bytes"
    );
    let text = String::from_utf8(files[0].0.clone()).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[0], "sample");
    assert!(header.contains(&"preloaded [0/1]"));
    let column = header
        .iter()
        .position(|h| *h == "hysteresis_arcmin [arcmin]")
        .unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 10_000);
    assert!(rows
        .iter()
        .enumerate()
        .all(|(i, r)| r[0] == i.to_string() && r.len() == header.len()));
    let mut values: Vec<f64> = rows.iter().map(|r| r[column].parse().unwrap()).collect();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files[0].1).unwrap()).unwrap();
    let output = &report["outputs"][0];
    assert_eq!(output["name"], "hysteresis_arcmin");
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let reported_mean = output["mean"].as_f64().unwrap();
    assert!((mean - reported_mean).abs() <= 1e-12 * reported_mean.abs());
    // Type 7 at p = 0.5 over 10,000 values: the mean of the 5,000th and 5,001st, of the
    // values alone, and with the over-preloaded samples placed above every value (they lie
    // beyond the upper limit: docs/models.md, "Conformity").
    let median = |values: &mut Vec<f64>| {
        values.sort_by(f64::total_cmp);
        values[4999] + 0.5 * (values[5000] - values[4999])
    };
    assert_eq!(
        median(&mut values),
        output["value_percentiles"]["50"].as_f64().unwrap()
    );
    let flag = header
        .iter()
        .position(|h| *h == "over_preloaded [0/1]")
        .unwrap();
    let mut placed: Vec<f64> = rows
        .iter()
        .map(|r| {
            if r[flag] == "1" {
                f64::MAX
            } else {
                r[column].parse().unwrap()
            }
        })
        .collect();
    assert_eq!(
        median(&mut placed),
        output["percentiles"]["50"].as_f64().unwrap()
    );

    // Beyond the table's limit: one line, exit 2, before any work, nothing written.
    let target = dir.join("too-big.csv");
    let output = run_rvtol(&[
        "run",
        &scenario("rv40e-transmission.json"),
        "--samples",
        "1e7",
        "--samples-out",
        target.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("--samples-out: at most"), "{stderr}");
    assert!(!target.exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn samples_out_parquet_holds_the_csv_values_with_the_same_bytes_for_any_thread_count() {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::RowAccessor;
    let dir = std::env::temp_dir().join(format!("rvtol-parquet-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |threads: &str, file: &str| {
        let path = dir.join(file);
        let output = run_rvtol(&[
            "run",
            &scenario("rv20e-hysteresis.json"),
            "--samples",
            "5000",
            "--threads",
            threads,
            "--samples-out",
            path.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        std::fs::read(path).unwrap()
    };
    let one = write("1", "one.parquet");
    assert!(one == write("2", "two.parquet") && one == write("4", "four.parquet"));
    let csv = String::from_utf8(write("1", "rows.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let reader =
        SerializedFileReader::new(std::fs::File::open(dir.join("one.parquet")).unwrap()).unwrap();
    let schema = reader.metadata().file_metadata().schema_descr();
    let names: Vec<&str> = schema.columns().iter().map(|c| c.name()).collect();
    assert_eq!(names, header, "the CSV's headings");
    let mut n = 0;
    for (r, row) in reader.get_row_iter(None).unwrap().enumerate() {
        let row = row.unwrap();
        assert_eq!(row.get_long(0).unwrap(), r as i64);
        for (j, expected) in rows[r].iter().enumerate().skip(1) {
            assert_eq!(
                row.get_double(j).unwrap().to_bits(),
                expected.to_bits(),
                "row {r} column {j}"
            );
        }
        n += 1;
    }
    assert_eq!(n, 5000);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn evaluate_on_the_rows_of_samples_out_gives_the_same_file_back() {
    // `evaluate` recomputes the outputs from the written inputs: numbers written in their
    // shortest exact form read back to the same bits, and a row's outputs depend on that
    // row alone, so the file comes back byte for byte.
    let dir = std::env::temp_dir().join(format!("rvtol-evaluate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (file, samples) in [
        ("rv20e-selective-fitting.json", "3000"),
        ("rv80e-contact.json", "500"),
    ] {
        let written = dir.join("samples.csv");
        let again = dir.join("evaluated.csv");
        let output = run_rvtol(&[
            "run",
            &scenario(file),
            "--samples",
            samples,
            "--samples-out",
            written.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(output.status.code(), Some(0), "{file}");
        let output = run_rvtol(&[
            "evaluate",
            &scenario(file),
            "--inputs",
            written.to_str().unwrap(),
            "-o",
            again.to_str().unwrap(),
        ]);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{file}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        assert!(
            std::fs::read(&written).unwrap() == std::fs::read(&again).unwrap(),
            "{file}: evaluate gave other bytes"
        );
    }
    // Bad rows: one line naming the file, the line and the column; exit 2.
    let header =
        "pin_circle_radius_error,pin_radius_error,pin_hole_clearance,cycloid_radial_runout,\
cycloid_cumulative_pitch_error,equidistant_modification_error,shift_modification_error,\
eccentricity_error,crank_bearing_clearance,input_shaft.du,input_shaft.dv,input_shaft.dw,\
input_shaft.dalpha,input_shaft.dbeta,input_shaft.dgamma";
    let zeros = vec!["0"; 15].join(",");
    let mut bad_cell = vec!["0"; 15];
    bad_cell[3] = "1e-3mm";
    for (contents, expected) in [
        (format!("{header}\n{zeros}\n"), None),
        (
            format!("{header}\n{zeros}\n{}\n", bad_cell.join(",")),
            Some("line 3, column 'cycloid_radial_runout': not a finite number: '1e-3mm'"),
        ),
        (
            format!("{header},extra\n{zeros},1\n"),
            Some("column 'extra' is neither an input nor an output"),
        ),
        (
            "pin_radius_error\n0\n".to_string(),
            Some("no column for the inputs"),
        ),
        (format!("{header}\n"), Some("no rows")),
        (
            format!(
                "{}\n{zeros}\n",
                header.replacen("pin_radius_error,", "pin_radius_error [rad],", 1)
            ),
            Some("column 'pin_radius_error [rad]' is in rad, but the input is in mm and rad does not convert to it"),
        ),
    ] {
        let path = dir.join("rows.csv");
        std::fs::write(&path, contents).unwrap();
        let output = run_rvtol(&[
            "evaluate",
            &scenario("rv20e-hysteresis.json"),
            "--inputs",
            path.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        match expected {
            None => {
                assert_eq!(output.status.code(), Some(0), "{stderr}");
                let stdout = String::from_utf8_lossy(&output.stdout);
                assert_eq!(stdout.lines().count(), 2);
                assert!(stdout.lines().nth(1).unwrap().starts_with("0,"));
            }
            Some(message) => {
                assert_eq!(output.status.code(), Some(2), "{stderr}");
                assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
                assert!(stderr.contains(message), "{stderr}");
            }
        }
    }
    // A heading's unit is converted into the input's: 2 µm of pin radius error is the
    // row of 0.002 mm, value for value.
    let in_mm = format!("{header}\n0,0.002,{}\n", vec!["0"; 13].join(","));
    let in_um = format!(
        "{}\n0,2,{}\n",
        header.replacen("pin_radius_error,", "pin_radius_error [µm],", 1),
        vec!["0"; 13].join(",")
    );
    let mut outputs = Vec::new();
    for (name, contents) in [("mm.csv", in_mm), ("um.csv", in_um)] {
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        let output = run_rvtol(&[
            "evaluate",
            &scenario("rv20e-hysteresis.json"),
            "--inputs",
            path.to_str().unwrap(),
        ]);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        outputs.push(output.stdout);
    }
    assert_eq!(outputs[0], outputs[1]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn fit_writes_a_part_that_a_scenario_takes_and_refuses_bad_columns() {
    let dir = std::env::temp_dir().join(format!("rvtol-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("measured.csv");
    // 12 measured parts, components in another order and with the part's prefix and units.
    let mut text = String::from("carrier.dv [mm],carrier.du [mm],carrier.dw [mm],carrier.dgamma [rad],carrier.dbeta [rad],carrier.dalpha [rad]\n");
    let mut x = 0.37_f64;
    for _ in 0..12 {
        let mut cells = Vec::new();
        for scale in [0.003, 0.004, 0.002, 1e-5, 4e-5, 5e-5] {
            x = (x * 9301.0 + 0.49297).fract();
            cells.push(format!("{}", (x - 0.5) * scale));
        }
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    std::fs::write(&csv, text).unwrap();
    let fragment = dir.join("part.json");
    let output = run_rvtol(&[
        "fit",
        csv.to_str().unwrap(),
        "--part",
        "carrier",
        "-o",
        fragment.to_str().unwrap(),
    ]);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(String::from_utf8_lossy(&output.stderr).contains("12 measured parts"));
    let part: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fragment).unwrap()).unwrap();
    let covariance = &part["parts"][0]["covariance"];
    assert_eq!(covariance.as_array().unwrap().len(), 6);
    // du is the second column of the file but the first component of the part.
    let var_du = covariance[0][0].as_f64().unwrap();
    assert!(var_du > 0.0 && var_du < 0.004f64.powi(2));
    let scenario = serde_json::json!({
        "name": "fitted",
        "parts": part["parts"],
        "models": [{
            "model": "linear_stack",
            "params": { "output": "y", "unit": "mm", "coefficients": { "a": 1.0 } },
            "inputs": { "a": "carrier.du" }
        }]
    });
    let path = dir.join("fitted.json");
    std::fs::write(&path, scenario.to_string()).unwrap();
    let output = run_rvtol(&["validate", path.to_str().unwrap()]);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    // A column that is no component of the part: one line, exit 2.
    std::fs::write(&csv, "du,dv,dw,dalpha,dbeta,dgamma,width\n0,0,0,0,0,0,1\n").unwrap();
    let output = run_rvtol(&["fit", csv.to_str().unwrap(), "--part", "carrier"]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("column 'width' is not a component of part carrier"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
