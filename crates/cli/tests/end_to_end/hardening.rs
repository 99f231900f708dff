//! One test per class of defect the hardening campaign found, end to end through the
//! binary: non-finite model values counted and failing, report files on devices, FIFOs and
//! symbolic links, a closed or full standard output, requests refused for memory, the
//! thread bound, the accepted-but-wrong inputs, the exit codes of `check`, extreme values,
//! and the wording of messages.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::{run_rvtol, rvtol_binary, workspace_dir, TempScenario};
use serde_json::Value;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The one stderr line of a failed command, after checking the exit code and that nothing
/// panicked.
fn one_line(output: &Output, code: i32) -> String {
    let stderr = text(&output.stderr);
    assert_eq!(
        output.status.code(),
        Some(code),
        "exit code; stderr:\n{stderr}\nstdout:\n{}",
        text(&output.stdout)
    );
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    let line = stderr.strip_suffix('\n').unwrap_or(&stderr);
    assert!(!line.contains('\n'), "more than one line: {stderr}");
    assert!(line.starts_with("error: "), "{stderr}");
    line.to_string()
}

fn shipped(file: &str) -> Value {
    let path = workspace_dir().join("scenarios").join(file);
    serde_json::from_str(&rvtol_tests::shipped_text(path)).expect("parse")
}

fn with(file: &str, change: impl FnOnce(&mut Value)) -> String {
    let mut scenario = shipped(file);
    change(&mut scenario);
    serde_json::to_string_pretty(&scenario).expect("serialise")
}

/// A fresh directory in the temporary directory.
fn scratch(label: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rvtol-hardening-{label}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch directory");
    dir
}

fn path_arg(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

// ---------------------------------------------------------------------------------------
// Non-finite model values.

/// The RV-20E torsion scenario with the crank bearing stiffness error bound to a constant
/// of −1 (a zero stiffness): every sample's lost motion is NaN.
fn torsion_with_zero_stiffness() -> String {
    with("rv20e-torsion.json", |s| {
        s["models"][0]["inputs"]["crank_bearing_stiffness_error"] = Value::from(-1.0);
    })
}

#[test]
fn non_finite_outputs_are_counted_and_fail_the_run_naming_the_model() {
    let scenario = TempScenario::new("hardening-nan", &torsion_with_zero_stiffness());
    let path = path_arg(scenario.path());
    let out = run_rvtol(&["run", path, "--samples", "2000", "--json", "-", "--quiet"]);
    let line = one_line(&out, 2);
    assert!(
        line.contains("models[0] (torsion_curve): lost_motion_arcmin is not finite for 2,000 of 2,000 samples (100.00 %, first at sample 0)"),
        "{line}"
    );
    // The report is still written: it says how many, which share, and counts them out of
    // spec (every sample: 1e6 ppm), with no index and the reason.
    let report: Value = serde_json::from_slice(&out.stdout).expect("report");
    let lost = &report["outputs"][0];
    assert_eq!(lost["name"], "lost_motion_arcmin");
    assert_eq!(lost["n"], 0);
    assert_eq!(lost["non_finite"], 2000);
    assert_eq!(lost["non_finite_fraction"], 1.0);
    assert_eq!(lost["first_non_finite_sample"], 0);
    assert!(lost["mean"].is_null(), "no mean of no values");
    assert_eq!(lost["ppm_out"], 1e6);
    assert!(lost["cpk"].is_null());
    assert!(lost["capability_note"]
        .as_str()
        .is_some_and(|n| n.contains("2,000 samples (100.00 %) are not finite")));
    // Nominal and curve refuse it, naming the model and the output.
    let nominal = one_line(&run_rvtol(&["nominal", path]), 2);
    assert!(
        nominal
            .contains("models[0] (torsion_curve): lost_motion_arcmin is NaN at the nominal point"),
        "{nominal}"
    );
    let dir = scratch("nan-curve");
    let curve = one_line(&run_rvtol(&["curve", path, "--out-dir", path_arg(&dir)]), 2);
    assert!(
        curve.contains("models[0] (torsion_curve): curve torsion_curve"),
        "{curve}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_share_of_non_finite_samples_is_reported_and_may_be_allowed() {
    // The stiffness error drawn from N(0, 0.5): k·(1 + x) ≤ 0, a NaN sample, with
    // probability Φ(−2) = 0.02275.
    let contents = with("rv20e-torsion.json", |s| {
        let variables = s["variables"].as_array_mut().expect("variables");
        let v = variables
            .iter_mut()
            .find(|v| v["name"] == "crank_bearing_stiffness_error")
            .expect("the stiffness error variable");
        v["distribution"] = serde_json::json!({ "normal": { "mean": 0.0, "sd": 0.5 } });
    });
    let scenario = TempScenario::new("hardening-nan-share", &contents);
    let path = path_arg(scenario.path());
    let samples = 20_000.0;
    let refused = run_rvtol(&["run", path, "--samples", "20000", "--quiet"]);
    assert!(one_line(&refused, 2).contains("more than the allowed 0 %"));
    let allowed = run_rvtol(&[
        "run",
        path,
        "--samples",
        "20000",
        "--max-non-finite",
        "0.05",
        "--json",
        "-",
        "--quiet",
    ]);
    assert_eq!(allowed.status.code(), Some(0), "{}", text(&allowed.stderr));
    let report: Value = serde_json::from_slice(&allowed.stdout).expect("report");
    let lost = &report["outputs"][0];
    let share = lost["non_finite_fraction"].as_f64().expect("share");
    // Binomial: p = Φ(−2) = 0.0227501, sd √(p(1 − p)/n); bound 5 sd.
    let p = 0.022_750_131_948_179;
    assert!(
        (share - p).abs() <= 5.0 * (p * (1.0 - p) / samples).sqrt(),
        "{share}"
    );
    // Every lost sample is out of spec: ppm at least the lost share.
    assert!(lost["ppm_out"].as_f64().expect("ppm") >= share * 1e6);
    assert!(lost["cpk"].is_null() && lost["capability_note"].is_string());
}

// ---------------------------------------------------------------------------------------
// Report files: devices, FIFOs, symbolic links, permissions.

/// A character device equal to /dev/null, made in `dir` (root can; otherwise a symbolic
/// link to /dev/null stands in, which the writer must follow to the device).
fn null_device(dir: &Path) -> PathBuf {
    let node = dir.join("null-device");
    let made = Command::new("mknod")
        .arg(&node)
        .args(["c", "1", "3"])
        .status()
        .is_ok_and(|s| s.success());
    if !made {
        std::os::unix::fs::symlink("/dev/null", &node).expect("symlink to /dev/null");
    }
    node
}

#[cfg(unix)]
#[test]
fn a_report_written_to_a_device_leaves_the_device() {
    use std::os::unix::fs::FileTypeExt;
    let dir = scratch("device");
    let device = null_device(&dir);
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    for args in [
        vec![
            "run",
            path_arg(&scenario),
            "--samples",
            "1000",
            "--quiet",
            "--json",
        ],
        vec![
            "baseline",
            path_arg(&scenario),
            "--samples",
            "1000",
            "--quiet",
            "-o",
        ],
    ] {
        let mut args = args;
        args.push(path_arg(&device));
        let out = run_rvtol(&args);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let kind = std::fs::metadata(&device).expect("device").file_type();
        assert!(kind.is_char_device(), "{args:?} replaced the device");
    }
    assert!(std::fs::metadata("/dev/null")
        .expect("/dev/null")
        .file_type()
        .is_char_device());
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(unix)]
#[test]
fn a_report_written_to_a_fifo_goes_through_it() {
    let dir = scratch("fifo");
    let fifo = dir.join("report.fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo")
        .success());
    let reader_path = fifo.clone();
    let reader =
        std::thread::spawn(move || std::fs::read_to_string(reader_path).expect("read fifo"));
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "1000",
        "--quiet",
        "--json",
        path_arg(&fifo),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let received = reader.join().expect("reader");
    let report: Value = serde_json::from_str(&received).expect("the report came through");
    assert_eq!(report["samples"], 1000);
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata(&fifo)
        .expect("fifo")
        .file_type()
        .is_fifo());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unwritable_destination_is_refused_before_the_run() {
    // Nothing is computed or printed: the table would come before the samples file.
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let scenario = path_arg(&scenario);
    let dir = scratch("destinations");
    let missing = "its folder /nonexistent-rvtol-dir";
    for (args, message) in [
        (
            vec![
                "run",
                scenario,
                "--samples-out",
                "/nonexistent-rvtol-dir/x.csv",
            ],
            missing,
        ),
        (
            vec!["run", scenario, "--json", "/nonexistent-rvtol-dir/x.json"],
            missing,
        ),
        (
            vec!["run", scenario, "--html", path_arg(&dir)],
            "it is a directory",
        ),
        (
            vec![
                "run",
                scenario,
                "--shard",
                "0/2",
                "--partial",
                "/nonexistent-rvtol-dir/p",
            ],
            missing,
        ),
        (
            vec!["baseline", scenario, "-o", "/nonexistent-rvtol-dir/b.json"],
            missing,
        ),
    ] {
        let out = run_rvtol(&args);
        let line = one_line(&out, 2);
        assert!(line.contains(message), "{args:?}: {line}");
        assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(target_os = "linux")]
#[test]
fn dev_stdout_on_a_pipe_takes_the_report_and_the_samples() {
    // The test harness reads standard output through a pipe: /dev/stdout links to
    // /proc/self/fd/1, whose link text `pipe:[…]` is no path; the writers go through it.
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "3",
        "--quiet",
        "--json",
        "/dev/stdout",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let json_end = stdout.find("\n}").expect("the JSON report") + 2;
    let report: Value = serde_json::from_str(&stdout[..json_end]).expect("JSON");
    assert_eq!(report["samples"], 3);
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "3",
        "--quiet",
        "--samples-out",
        "/dev/stdout",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(text(&out.stdout).lines().any(|l| l.starts_with("sample,")));
}

#[cfg(unix)]
#[test]
fn a_symlink_keeps_pointing_at_its_target_which_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = scratch("symlink");
    let target = dir.join("report.json");
    std::fs::write(&target, "old").expect("write");
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o600)).expect("chmod");
    let link = dir.join("link.json");
    std::os::unix::fs::symlink("report.json", &link).expect("symlink");
    // A temporary left by a run that was killed (process 0 never lives).
    let stale = dir.join(".report.json.rvtol-tmp-0");
    std::fs::write(&stale, "half a report").expect("write");
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "1000",
        "--quiet",
        "--json",
        path_arg(&link),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(std::fs::symlink_metadata(&link)
        .expect("link")
        .file_type()
        .is_symlink());
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(&target).expect("target")).expect("json");
    assert_eq!(report["samples"], 1000);
    let mode = std::fs::metadata(&target)
        .expect("target")
        .permissions()
        .mode();
    assert_eq!(mode & 0o777, 0o600, "permissions kept");
    assert!(!stale.exists(), "the killed run's temporary is cleaned up");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------
// Standard output closed or full.

#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    let scenario = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    let dir = scratch("pipe");
    let baseline = dir.join("b.json");
    for args in [
        vec!["validate", path_arg(&scenario)],
        vec!["models"],
        vec!["run", path_arg(&scenario), "--samples", "2000", "--quiet"],
        vec![
            "baseline",
            path_arg(&scenario),
            "--samples",
            "2000",
            "--quiet",
            "-o",
            path_arg(&baseline),
        ],
    ] {
        let mut child = Command::new(rvtol_binary())
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start");
        drop(child.stdout.take()); // the reader goes away at once, as `| head -0` does
        let out = child.wait_with_output().expect("wait");
        assert_eq!(
            out.status.code(),
            Some(0),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert!(out.stderr.is_empty(), "{args:?}: {}", text(&out.stderr));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_output_is_one_line() {
    let scenario = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    for args in [
        vec!["validate", path_arg(&scenario)],
        vec!["run", path_arg(&scenario), "--samples", "2000", "--quiet"],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full");
        let out = Command::new(rvtol_binary())
            .args(&args)
            .stdout(full)
            .output()
            .expect("run");
        let line = one_line(&out, 2);
        assert!(
            line.starts_with("error: cannot write to standard output: No space left on device"),
            "{line}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Memory and threads.

#[test]
fn requests_that_cannot_fit_are_refused_before_they_start() {
    let scenario = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    let path = path_arg(&scenario);
    let run = one_line(
        &run_rvtol(&[
            "run",
            path,
            "--samples",
            "1e9",
            "--exact-percentile-limit",
            "1e10",
            "--max-memory",
            "1G",
        ]),
        2,
    );
    // 8 bytes per kept value: 1e9 samples of each continuous output, the figure named.
    let continuous = rvtol_analysis::request::scenario::load(&scenario)
        .expect("load")
        .continuous_outputs()
        .len();
    assert!(
        run.starts_with(&format!(
            "error: run: needs about {:.1} GB of memory ({},000,000,000 kept values for exact percentiles of {continuous} outputs, and 64.0 MB for the program and its tables), more than the 1.1 GB available (--max-memory): lower --exact-percentile-limit",
            8.0 * continuous as f64 + 0.064 + 8.0 * continuous as f64 * 4.194304e-3,
            continuous
        )),
        "{run}"
    );
    let sensitivity = one_line(
        &run_rvtol(&[
            "sensitivity",
            path,
            "--samples",
            "1e8",
            "--row-bootstrap-limit",
            "1e12",
            "--max-memory",
            "1G",
        ]),
        2,
    );
    assert!(
        sensitivity.contains("model values for the row bootstrap"),
        "{sensitivity}"
    );
    assert!(
        sensitivity.contains("lower --row-bootstrap-limit"),
        "{sensitivity}"
    );
    let allocate = one_line(
        &run_rvtol(&[
            "allocate",
            path,
            "--output",
            "hysteresis_arcmin",
            "--target",
            "p99.865 <= 1.5",
            "--samples",
            "1e10",
            "--max-memory",
            "1G",
        ]),
        2,
    );
    assert!(
        allocate.contains("kept values of the targeted output"),
        "{allocate}"
    );
    // Blocks of rows beyond memory on one thread: fewer samples help, more threads do not.
    let blocks = one_line(
        &run_rvtol(&[
            "sensitivity",
            path,
            "--samples",
            "1e12",
            "--threads",
            "1",
            "--max-memory",
            "1G",
        ]),
        2,
    );
    assert!(
        blocks.contains("blocks of rows for the intervals"),
        "{blocks}"
    );
    assert!(blocks.ends_with(": ask for fewer --samples"), "{blocks}");
    // Below the fixed allowance nothing fits: the way out is a larger budget.
    let tiny = one_line(
        &run_rvtol(&[
            "run",
            path,
            "--samples",
            "10",
            "--threads",
            "1",
            "--max-memory",
            "60M",
        ]),
        2,
    );
    assert!(
        tiny.contains("and 64.0 MB for the program and its tables")
            && tiny.contains(": allow at least"),
        "{tiny}"
    );
    // A baseline file that claims more than fits is refused by check, not aborted.
    let dir = scratch("memory");
    let baseline = dir.join("b.json");
    let written = run_rvtol(&[
        "baseline",
        path,
        "--samples",
        "2000",
        "--quiet",
        "-o",
        path_arg(&baseline),
    ]);
    assert_eq!(written.status.code(), Some(0), "{}", text(&written.stderr));
    let mut recorded: Value =
        serde_json::from_str(&std::fs::read_to_string(&baseline).expect("read")).expect("json");
    recorded["samples"] = Value::from(1_000_000_000_000u64);
    recorded["exact_percentile_limit"] = Value::from(u64::MAX);
    std::fs::write(&baseline, recorded.to_string()).expect("write");
    let check = one_line(
        &run_rvtol(&[
            "check",
            path,
            "--baseline",
            path_arg(&baseline),
            "--max-memory",
            "1G",
        ]),
        2,
    );
    assert!(check.starts_with("error: check: needs about"), "{check}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_baseline_of_a_billion_samples_takes_bounded_memory() {
    // Beyond the exact-percentile limit the gate's percentiles come from the sketch: the
    // memory estimate stays below 100 MB for any sample count (the run is not made).
    let scenario = rvtol_analysis::request::scenario::load(
        &workspace_dir().join("scenarios/rv20e-hysteresis.json"),
    )
    .expect("load");
    let settings = rvtol_engine::RunSettings {
        samples: 1_000_000_000,
        seed: 1,
        exact_percentile_limit: rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT,
        sampling: Default::default(),
    };
    let need = rvtol_analysis::request::memory::run(&scenario, &settings, 2);
    assert!(need.bytes < 100e6, "{need:?}");
}

#[test]
fn threads_beyond_four_per_core_are_refused() {
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let line = one_line(
        &run_rvtol(&["run", path_arg(&scenario), "--threads", "10000", "--quiet"]),
        2,
    );
    assert!(
        line.starts_with("error: --threads: 10000 is more than "),
        "{line}"
    );
}

#[test]
fn huge_scenarios_validate_fast_or_are_refused() {
    // 100,000 unused variables: the covariance is kept per correlated group, not dense.
    let mut many = shipped("linear-stack-correlated.json");
    let variables = many["variables"].as_array_mut().expect("variables");
    for i in 0..100_000 {
        variables.push(serde_json::json!({
            "name": format!("unused{i}"),
            "distribution": { "normal": { "mean": 0.0, "sd": 1.0 } }
        }));
    }
    let scenario = TempScenario::new("hardening-many", &many.to_string());
    let started = std::time::Instant::now();
    let out = run_rvtol(&["validate", path_arg(scenario.path())]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(started.elapsed().as_secs() < 30, "{:?}", started.elapsed());
    // A 20,000-column correlated chain is refused with the figure and the way out.
    let mut chain = shipped("linear-stack-correlated.json");
    let variables = chain["variables"].as_array_mut().expect("variables");
    for i in 0..20_000 {
        variables.push(serde_json::json!({
            "name": format!("c{i}"),
            "distribution": { "normal": { "mean": 0.0, "sd": 1.0 } }
        }));
    }
    let correlations = chain["correlations"].as_array_mut().expect("correlations");
    for i in 0..19_999 {
        correlations.push(
            serde_json::json!({ "between": [format!("c{i}"), format!("c{}", i + 1)], "rho": 0.4 }),
        );
    }
    let scenario = TempScenario::new("hardening-chain", &chain.to_string());
    let line = one_line(&run_rvtol(&["validate", path_arg(scenario.path())]), 2);
    assert!(
        line.contains("correlations: 20000 normal columns are correlated into one group"),
        "{line}"
    );
    assert!(line.contains("6.4 GB"), "{line}");
}

// ---------------------------------------------------------------------------------------
// Accepted but wrong, now refused.

fn assert_refused(label: &str, contents: &str, needles: &[&str]) {
    let scenario = TempScenario::new(label, contents);
    let line = one_line(&run_rvtol(&["validate", path_arg(scenario.path())]), 2);
    for needle in needles {
        assert!(
            line.contains(needle),
            "{label}: missing {needle:?} in {line}"
        );
    }
}

#[test]
fn a_pair_correlated_twice_is_refused() {
    let contents = with("linear-stack-correlated.json", |s| {
        let correlations = s["correlations"].as_array_mut().expect("correlations");
        let mut again = correlations[0].clone();
        again["rho"] = Value::from(-0.1);
        correlations.push(again);
    });
    assert_refused(
        "hardening-twice",
        &contents,
        &["correlations[2]: correlates the same pair as correlations[0]"],
    );
}

#[test]
fn impossible_geometry_is_refused() {
    assert_refused(
        "hardening-eccentricity",
        &with("rv20e-hysteresis.json", |s| {
            s["reducer"]["params"]["eccentricity_mm"] = Value::from(60.0);
        }),
        &["reducer.params.eccentricity_mm", "e·z_p/r_p = 46.15"],
    );
    assert_refused(
        "hardening-pin-radius",
        &with("rv80e-contact.json", |s| {
            s["reducer"]["params"]["pin_radius_mm"] = Value::from(1000.0);
        }),
        &["reducer.params.pin_radius_mm", "overlap their neighbours"],
    );
    // Pins that fit between their neighbours but are larger than the profile's smallest
    // convex curvature radius (7.52 mm for the RV-80E: r_p·(1 + K1)³/(K1·(z_p + 1) + 1 +
    // z_p·K1²) at φ = π).
    assert_refused(
        "hardening-undercut",
        &with("rv80e-contact.json", |s| {
            s["reducer"]["params"]["pin_radius_mm"] = Value::from(5.5);
            s["reducer"]["params"]["eccentricity_mm"] = Value::from(1.85);
        }),
        &["reducer.params.pin_radius_mm", "undercut the disc profile"],
    );
}

#[test]
fn extreme_values_are_refused_with_the_range() {
    assert_refused(
        "hardening-1e308",
        &with("rv20e-hysteresis.json", |s| {
            s["variables"][0]["distribution"]["tolerance_band"]["upper"] = Value::from(1e308);
        }),
        &["variables[0].distribution.tolerance_band.upper: 1e308 is outside ±1e6"],
    );
}

// ---------------------------------------------------------------------------------------
// Exit codes of check.

#[test]
fn check_against_the_wrong_baseline_is_bad_input() {
    let dir = scratch("check");
    let baseline = dir.join("b.json");
    let hysteresis = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    let written = run_rvtol(&[
        "baseline",
        path_arg(&hysteresis),
        "--samples",
        "2000",
        "--quiet",
        "-o",
        path_arg(&baseline),
    ]);
    assert_eq!(written.status.code(), Some(0));
    let other = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let line = one_line(
        &run_rvtol(&[
            "check",
            path_arg(&other),
            "--baseline",
            path_arg(&baseline),
            "--quiet",
        ]),
        2,
    );
    assert!(
        line.contains("scenario: the baseline records scenario \"rv20e-hysteresis\", not \"linear-stack-correlated\""),
        "{line}"
    );
    let recorded: Value =
        serde_json::from_str(&std::fs::read_to_string(&baseline).expect("read")).expect("json");
    for (label, change, needle) in [
        (
            "output",
            ("output", "no_such_output"),
            "figures[0].output: the scenario has no output",
        ),
        (
            "figure",
            ("figure", "p42"),
            "figures[0].figure: \"p42\" is not a figure",
        ),
    ] {
        let mut broken = recorded.clone();
        broken["figures"][0][change.0] = Value::from(change.1);
        let file = dir.join(format!("{label}.json"));
        std::fs::write(&file, broken.to_string()).expect("write");
        let line = one_line(
            &run_rvtol(&[
                "check",
                path_arg(&hysteresis),
                "--baseline",
                path_arg(&file),
                "--quiet",
            ]),
            2,
        );
        assert!(line.contains(needle), "{line}");
    }
    let mut empty = recorded.clone();
    empty["figures"] = Value::Array(Vec::new());
    let file = dir.join("empty.json");
    std::fs::write(&file, empty.to_string()).expect("write");
    let line = one_line(
        &run_rvtol(&[
            "check",
            path_arg(&hysteresis),
            "--baseline",
            path_arg(&file),
            "--quiet",
        ]),
        2,
    );
    assert!(line.contains("figures: is empty"), "{line}");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------
// Messages.

#[test]
fn validate_reports_every_problem_one_line_each() {
    let contents = with("rv20e-hysteresis.json", |s| {
        s["variables"][0]["distribution"]["tolerance_band"]["cp"] = Value::from(-1.0);
        s["variables"][1]["distribution"]["tolerance_band"]["extra"] = Value::from(1.0);
        s["correlations"] = serde_json::json!([{ "between": ["a", "b", "c"], "rho": 0.5 }]);
        // A spec on no output: its models are built, so every output name is known even
        // though a variable they bind is broken.
        s["spec_limits"]["nope"] = serde_json::json!({ "upper": 1 });
    });
    let stderr = validate_problems("hardening-many-problems", &contents, 4);
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        stderr.contains("spec_limits.nope: no output named \"nope\""),
        "{stderr}"
    );
    assert!(lines.iter().all(|l| l.starts_with("error: ")), "{stderr}");
    assert!(stderr.contains("variables[0].distribution.tolerance_band.cp: process capability must be positive, got -1"), "{stderr}");
    assert!(
        stderr.contains("variables[1].distribution.tolerance_band.extra: unknown field `extra`"),
        "{stderr}"
    );
    assert!(
        stderr.contains("correlations[0].between: invalid length 3, expected fewer elements"),
        "{stderr}"
    );
    // A unit rvtol does not know is the variable's mistake, said at its `unit`.
    let contents = with("rv20e-hysteresis.json", |s| {
        s["variables"][1]["unit"] = Value::from("micron");
    });
    assert_refused(
        "hardening-unknown-unit",
        &contents,
        &["variables[1].unit: \"micron\" is not a unit rvtol knows (lengths mm, µm"],
    );
    // Rust's type names stay out of the messages.
    let contents = with("rv20e-hysteresis.json", |s| {
        s["variables"][0]["distribution"]["tolerance_band"]["cp"] = Value::from("1");
    });
    assert_refused(
        "hardening-string-number",
        &contents,
        &["variables[0].distribution.tolerance_band.cp: invalid type: string \"1\", expected a number"],
    );
}

#[test]
fn validate_names_every_mistaken_formula_and_run_the_first() {
    // An expression model with three mistaken formulas (one of them read by another,
    // which stays silent): validate lists the three, one line each; run refuses with the
    // first, on one line.
    let contents = with("pin-in-hole.json", |s| {
        let params = &mut s["models"][0]["params"];
        params["let"]["offset"] = Value::from("hypot(x, yy)");
        params["outputs"]["gap_mm"]["formula"] = Value::from("half_clearance - ofset");
        params["outputs"]["float_mm"]["formula"] = Value::from("half_clearance + sqr(offset)");
    });
    let stderr = validate_problems("hardening-formulas", &contents, 3);
    let lines: Vec<&str> = stderr.lines().collect();
    for (line, needle) in lines.iter().zip([
        "models[0].params.let.offset: character 10: unknown name \"yy\"",
        "models[0].params.outputs.gap_mm.formula: character 18: unknown name \"ofset\"",
        "models[0].params.outputs.float_mm.formula: character 18: unknown function \"sqr\"",
    ]) {
        assert!(line.contains(needle), "{needle:?} in {stderr}");
    }
    let scenario = TempScenario::new("hardening-formulas-run", &contents);
    let line = one_line(
        &run_rvtol(&["run", path_arg(scenario.path()), "--samples", "100"]),
        2,
    );
    assert!(line.contains("let.offset: character 10"), "{line}");
}

/// `rvtol validate` of `contents`: exit 2 and `count` lines on standard error, the last
/// one counting them; the lines.
fn validate_problems(label: &str, contents: &str, count: usize) -> String {
    let scenario = TempScenario::new(label, contents);
    let out = run_rvtol(&["validate", path_arg(scenario.path())]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), count, "{stderr}");
    assert!(
        lines[count - 1].ends_with(&format!("({count} problems)")),
        "{stderr}"
    );
    stderr
}

#[test]
fn schema_errors_carry_their_json_path() {
    for (label, distribution, needle) in [
        (
            "two-distributions",
            serde_json::json!({ "normal": { "mean": 0, "sd": 1 }, "uniform": { "lower": 0, "upper": 1 } }),
            "variables[0].distribution: give exactly one distribution",
        ),
        (
            "empty-distribution",
            serde_json::json!({}),
            "variables[0].distribution: give exactly one distribution",
        ),
        (
            "extra-key",
            serde_json::json!({ "normal": { "mean": 0, "sd": 1, "skew": 2 } }),
            "variables[0].distribution.normal.skew: unknown field `skew`",
        ),
    ] {
        let contents = with("rv20e-hysteresis.json", |s| {
            s["variables"][0]["distribution"] = distribution;
        });
        assert_refused(&format!("hardening-{label}"), &contents, &[needle]);
    }
    // A duplicate key is not silently the last one.
    let text =
        std::fs::read_to_string(workspace_dir().join("scenarios/linear-stack-correlated.json"))
            .expect("read")
            .replacen("\"seed\":", "\"seed\": 3, \"seed\":", 1);
    assert_refused(
        "hardening-duplicate-key",
        &text,
        &["key \"seed\" appears twice"],
    );
}

#[test]
fn usage_errors_are_one_line_naming_the_option() {
    let line = one_line(&run_rvtol(&["run", "x.json", "--samples", "-1"]), 2);
    assert_eq!(
        line,
        "error: invalid value '-1' for '--samples <SAMPLES>': must be a whole number of at least 1 (see 'rvtol run --help')"
    );
    // A seed is any u64, said without Rust's parser's words; the limit in groups.
    let line = one_line(&run_rvtol(&["sensitivity", "x.json", "--seed", "-1"]), 2);
    assert_eq!(
        line,
        "error: invalid value '-1' for '--seed <SEED>': must be a whole number from 0 to 18,446,744,073,709,551,615 (see 'rvtol sensitivity --help')"
    );
    let line = one_line(&run_rvtol(&["run", "x.json", "--samples", "1e30"]), 2);
    assert!(
        line.contains("must be at most 18,446,744,073,709,551,615"),
        "{line}"
    );
    // merge's usage errors point at its own help.
    let line = one_line(&run_rvtol(&["merge"]), 2);
    assert!(line.ends_with("(see 'rvtol merge --help')"), "{line}");
    let line = one_line(&run_rvtol(&["run"]), 2);
    assert!(line.contains("<SCENARIO>"), "{line}");
    let line = one_line(&run_rvtol(&["frobnicate"]), 2);
    assert!(
        line.contains("unrecognized subcommand 'frobnicate'"),
        "{line}"
    );
    // Counts may be written in exponent form.
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "2e3",
        "--quiet",
        "--json",
        "-",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: Value = serde_json::from_slice(&out.stdout).expect("json");
    assert_eq!(report["samples"], 2000);
}

// ---------------------------------------------------------------------------------------
// Outputs that would destroy an input or each other, standard output and input as `-`.

/// Runs rvtol with `input` on its standard input.
fn run_with_stdin(args: &[&str], input: &str) -> Output {
    use std::io::Write;
    let mut child = Command::new(rvtol_binary())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rvtol");
    // A command that refuses before reading (both inputs '-') may exit before the text is
    // written: its closed pipe is no failure of the test.
    match child
        .stdin
        .take()
        .expect("stdin")
        .write_all(input.as_bytes())
    {
        Err(err) if err.kind() != std::io::ErrorKind::BrokenPipe => panic!("write stdin: {err}"),
        _ => {}
    }
    child.wait_with_output().expect("rvtol output")
}

#[cfg(unix)]
#[test]
fn an_output_on_an_input_or_on_another_output_is_refused_and_nothing_is_touched() {
    let dir = scratch("inputs");
    let scenario = dir.join("my.json");
    std::fs::copy(
        workspace_dir().join("scenarios/linear-stack-correlated.json"),
        &scenario,
    )
    .expect("copy");
    let original = std::fs::read(&scenario).expect("read");
    let link = dir.join("link.json");
    std::os::unix::fs::symlink("my.json", &link).expect("symlink");
    let same = dir.join("same.txt");
    let s = path_arg(&scenario);
    let destroy = "is the scenario file, which this command reads: writing there would destroy it";
    for (args, message) in [
        (vec!["run", s, "--json", s], destroy),
        (vec!["run", s, "--json", path_arg(&link)], destroy),
        (vec!["sensitivity", s, "--json", s], destroy),
        (vec!["baseline", s, "-o", s], destroy),
        (vec!["nominal", s, "--json", s], destroy),
        (
            vec![
                "allocate",
                s,
                "--output",
                "gap_mm",
                "--target",
                "p99.865 <= 1",
                "--write-scenario",
                s,
            ],
            destroy,
        ),
        (vec!["check", s, "--baseline", s, "--json", s], destroy),
        (
            vec![
                "check",
                s,
                "--baseline",
                "b.json",
                "--json",
                path_arg(&same),
                "--junit",
                path_arg(&same),
            ],
            "is also the file of --junit: give each output its own file",
        ),
        (
            vec!["run", s, "--json", "-", "--html", "-"],
            "--html: standard output ('-') already takes --json",
        ),
        (
            vec!["run", s, "--shard", "0/2", "--partial", "-"],
            "--partial: '-' (standard output) cannot take a binary file",
        ),
        (
            vec!["run", s, "--samples-out", "x.xlsx"],
            "--samples-out: x.xlsx: name it .csv or .parquet (the extension chooses the format)",
        ),
        (
            vec!["run", s, "--html", "x.pdf"],
            "--html: x.pdf: name it .html or .htm",
        ),
        (
            vec!["run", s, "--json", "x.parquet"],
            "--json: x.parquet: .parquet names another format (JSON is written there)",
        ),
        (
            vec!["check", s, "--baseline", "b.json", "--junit", "j.json"],
            "--junit: j.json: .json names another format (JUnit XML is written there)",
        ),
        (vec!["curve", s, "--out-dir", s], "is a file: name a folder"),
    ] {
        let out = run_rvtol(&args);
        let line = one_line(&out, 2);
        assert!(line.contains(message), "{args:?}: {line}");
        assert!(out.stdout.is_empty(), "{args:?}: {}", text(&out.stdout));
        assert_eq!(
            std::fs::read(&scenario).expect("read"),
            original,
            "{args:?}"
        );
        assert!(!same.exists(), "{args:?}");
    }
    // The data file an empirical distribution reads is an input too.
    let data = dir.join("pins.csv");
    std::fs::write(&data, "radius\n0.001\n0.002\n0.003\n").expect("write");
    let with_data = dir.join("data.json");
    std::fs::write(
        &with_data,
        with("linear-stack-correlated.json", |d| {
            d["variables"][0]["distribution"] =
                serde_json::json!({ "empirical": { "csv": "pins.csv", "column": "radius" } });
        }),
    )
    .expect("write");
    let line = one_line(
        &run_rvtol(&[
            "run",
            path_arg(&with_data),
            "--samples-out",
            path_arg(&data),
        ]),
        2,
    );
    assert!(line.contains("is a data file of the scenario"), "{line}");
    assert_eq!(
        std::fs::read_to_string(&data).expect("read"),
        "radius\n0.001\n0.002\n0.003\n"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn dash_is_standard_output_for_every_writer_and_standard_input_for_the_scenario() {
    let dir = scratch("dash");
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let s = path_arg(&scenario);
    let run = |args: &[&str]| {
        let out = Command::new(rvtol_binary())
            .args(args)
            .current_dir(&dir)
            .output()
            .expect("run");
        assert_eq!(
            out.status.code(),
            Some(0),
            "{args:?}: {}",
            text(&out.stderr)
        );
        text(&out.stdout)
    };
    let page = run(&["run", s, "--samples", "50", "--quiet", "--html", "-"]);
    assert!(
        page.starts_with("<!DOCTYPE html>"),
        "{}",
        &page[..page.len().min(80)]
    );
    let rows = run(&["run", s, "--samples", "3", "--quiet", "--samples-out", "-"]);
    assert!(rows.starts_with("sample,"), "{rows}");
    assert_eq!(rows.lines().count(), 4, "{rows}");
    let skeleton = run(&["init", "linear_stack", "-o", "-"]);
    assert!(skeleton.trim_start().starts_with('{'), "{skeleton}");
    let baseline = run(&["baseline", s, "--samples", "100", "--quiet", "-o", "-"]);
    let baseline: Value = serde_json::from_str(&baseline).expect("the baseline alone");
    assert_eq!(baseline["samples"], 100);
    assert!(
        !dir.join("-").exists(),
        "a file named '-' was created instead of writing to standard output"
    );
    // A scenario on standard input: the same report as from its file.
    let from_file = run_rvtol(&["run", s, "--samples", "1000", "--json", "-"]);
    let text_in = std::fs::read_to_string(&scenario).expect("read");
    let from_stdin = run_with_stdin(&["run", "-", "--samples", "1000", "--json", "-"], &text_in);
    assert_eq!(
        from_stdin.status.code(),
        Some(0),
        "{}",
        text(&from_stdin.stderr)
    );
    assert_eq!(from_stdin.stdout, from_file.stdout);
    let valid = run_with_stdin(&["validate", "-"], &text_in);
    assert_eq!(
        text(&valid.stdout),
        "standard input: valid (9 input columns, 1 model, 1 output)\n"
    );
    let broken = run_with_stdin(&["validate", "-"], "{");
    assert!(one_line(&broken, 2).starts_with("error: standard input: JSON syntax"));
    let twice = run_with_stdin(&["evaluate", "-", "--inputs", "-"], &text_in);
    assert!(
        one_line(&twice, 2).contains("--inputs: standard input ('-') already gives the scenario")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(target_os = "linux")]
#[test]
fn a_folder_that_takes_no_new_file_is_refused_before_the_run() {
    // /sys takes no new file, for root too (a chmod'ed folder would not stop root).
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    for option in ["--json", "--html", "--samples-out"] {
        let name = if option == "--html" {
            "/sys/x.html"
        } else {
            "/sys/x.csv"
        };
        let out = run_rvtol(&["run", path_arg(&scenario), option, name]);
        let line = one_line(&out, 2);
        assert!(
            line.starts_with(&format!(
                "error: {option}: cannot write {name}: its folder /sys takes no new file"
            )),
            "{line}"
        );
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn a_file_that_is_no_baseline_and_a_bad_init_parameter_are_named_as_such() {
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let s = path_arg(&scenario);
    let line = one_line(&run_rvtol(&["check", s, "--baseline", s]), 2);
    assert!(
        line.ends_with("not a baseline but a scenario (no `figures`): `rvtol baseline SCENARIO -o FILE` writes one"),
        "{line}"
    );
    let line = one_line(
        &run_rvtol(&["init", "geometric_hysteresis", "--param", "pin_count=abc"]),
        2,
    );
    assert_eq!(
        line,
        "error: --param pin_count: must be a number, got a string"
    );
}

// ---------------------------------------------------------------------------------------
// The memory a job really has: the process's limits, and inputs read within a bound.

/// Runs rvtol under `ulimit -v KIB` (the address-space limit of the process), with `env`.
fn run_under_address_limit(kib: u64, args: &[&str], env: &[(&str, &str)]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("ulimit -v \"$0\" && exec \"$@\"")
        .arg(kib.to_string())
        .arg(rvtol_binary())
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("start sh")
}

#[test]
fn an_address_space_limit_bounds_the_memory_budget() {
    let allocation = common::scenario("allocation-linear.json");
    let hysteresis = common::scenario("rv20e-hysteresis.json");
    // The requests of the report: each aborted (exit 134) on a failed allocation under
    // `ulimit -v 6291456` (6 GiB) while the machine had more available.
    let allocate = one_line(
        &run_under_address_limit(
            6_291_456,
            &[
                "allocate",
                &allocation,
                "--output",
                "gap_mm",
                "--target",
                "sd <= 0.02",
                "--samples",
                "1e9",
                "--quiet",
            ],
            &[],
        ),
        2,
    );
    assert!(
        allocate.starts_with("error: allocate: needs about 16.1 GB of memory")
            && allocate.contains(
                "available (the address-space limit of this process, ulimit -v 6.4 GB, less "
            )
            && allocate.ends_with("): ask for fewer --samples"),
        "{allocate}"
    );
    let run = one_line(
        &run_under_address_limit(
            6_291_456,
            &[
                "run",
                &hysteresis,
                "--samples",
                "2e8",
                "--exact-percentile-limit",
                "1e13",
            ],
            &[],
        ),
        2,
    );
    assert!(
        run.contains("available (the address-space limit of this process, ulimit -v 6.4 GB")
            && run.ends_with(": lower --exact-percentile-limit (the percentiles then come from the bounded-memory sketch) or ask for fewer --samples"),
        "{run}"
    );
    // --max-memory cannot raise the limit.
    let raised = one_line(
        &run_under_address_limit(
            2_097_152,
            &[
                "run",
                &hysteresis,
                "--samples",
                "1e8",
                "--exact-percentile-limit",
                "1e13",
                "--max-memory",
                "100G",
            ],
            &[],
        ),
        2,
    );
    assert!(
        raised.contains("worker thread") && raised.contains(", which --max-memory cannot raise)"),
        "{raised}"
    );
    // What fits under the limit runs.
    let fits = run_under_address_limit(
        2_097_152,
        &["run", &hysteresis, "--samples", "1e5", "--quiet"],
        &[],
    );
    assert_eq!(fits.status.code(), Some(0), "{}", text(&fits.stderr));
}

/// A memory cgroup with a limit, where this machine lets the test make one (cgroup v2
/// under /sys/fs/cgroup with the memory controller given to its children, or cgroup v1's
/// memory controller); removed when dropped.
struct MemoryCgroup {
    dir: PathBuf,
}

impl MemoryCgroup {
    fn new(label: &str, bytes: u64) -> Result<MemoryCgroup, String> {
        let name = format!("rvtol-hardening-{label}-{}", std::process::id());
        let unified = Path::new("/sys/fs/cgroup");
        let mut candidates = Vec::new();
        if std::fs::read_to_string(unified.join("cgroup.subtree_control"))
            .is_ok_and(|controllers| controllers.split_whitespace().any(|c| c == "memory"))
        {
            candidates.push((unified.join(&name), "memory.max"));
        }
        let v1 = Path::new("/sys/fs/cgroup/memory");
        if v1.join("memory.limit_in_bytes").is_file() {
            candidates.push((v1.join(&name), "memory.limit_in_bytes"));
        }
        let mut failures = Vec::new();
        for (dir, limit_file) in candidates {
            let made = std::fs::create_dir(&dir)
                .and_then(|()| std::fs::write(dir.join(limit_file), bytes.to_string()));
            match made {
                Ok(()) => return Ok(MemoryCgroup { dir }),
                Err(err) => {
                    let _ = std::fs::remove_dir(&dir);
                    failures.push(format!("{}: {err}", dir.display()));
                }
            }
        }
        Err(if failures.is_empty() {
            "no cgroup v2 with a memory controller for children, nor cgroup v1's memory controller"
                .to_string()
        } else {
            failures.join("; ")
        })
    }

    /// Runs rvtol with `args` in this cgroup.
    fn run(&self, args: &[&str]) -> Output {
        Command::new("sh")
            .arg("-c")
            .arg("echo $$ > \"$0\" && exec \"$@\"")
            .arg(self.dir.join("cgroup.procs"))
            .arg(rvtol_binary())
            .args(args)
            .output()
            .expect("start sh")
    }
}

impl Drop for MemoryCgroup {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir(&self.dir);
    }
}

#[test]
fn a_cgroup_memory_limit_bounds_the_memory_budget() {
    // The parsing of the cgroup files is unit-tested in the CLI (limits.rs); here the
    // binary in a real cgroup, where the machine lets the test make one.
    let cgroup = match MemoryCgroup::new("budget", 512 << 20) {
        Ok(cgroup) => cgroup,
        Err(why) => {
            println!("note: cgroup part skipped: cannot make a memory cgroup here ({why})");
            return;
        }
    };
    let hysteresis = common::scenario("rv20e-hysteresis.json");
    // 1e8 kept values of each output: far beyond 512 MiB (the OOM killer's, without the check).
    let line = one_line(
        &cgroup.run(&[
            "run",
            &hysteresis,
            "--samples",
            "1e8",
            "--exact-percentile-limit",
            "1e13",
        ]),
        2,
    );
    assert!(
        line.contains("available (the memory limit of this process's cgroup, /sys/fs/cgroup/")
            && line.contains(" 536.9 MB less ")
            && line.ends_with(": lower --exact-percentile-limit (the percentiles then come from the bounded-memory sketch) or ask for fewer --samples"),
        "{line}"
    );
    let fits = cgroup.run(&["run", &hysteresis, "--samples", "1e5", "--quiet"]);
    assert_eq!(fits.status.code(), Some(0), "{}", text(&fits.stderr));
}

/// The one line of a character device given where a file is read whole.
fn assert_device_refused(output: &Output, device: &Path) {
    let line = one_line(output, 2);
    assert_eq!(
        line,
        format!(
            "error: {}: cannot read: a character device, not a regular file (rvtol reads its inputs whole from regular files, or from a pipe)",
            device.display()
        )
    );
}

#[cfg(unix)]
#[test]
fn a_device_given_as_a_file_to_read_whole_is_refused() {
    let dir = scratch("device");
    // A copy of /dev/zero (mknod, as root), else /dev/zero itself: it never ends, and read
    // whole it took all memory. The commands run under an address-space limit so that
    // a build without the check aborts instead of filling the machine.
    let copy = dir.join("zero");
    let device = match Command::new("mknod")
        .arg(&copy)
        .args(["c", "1", "5"])
        .status()
    {
        Ok(status) if status.success() => copy,
        _ => PathBuf::from("/dev/zero"),
    };
    let d = path_arg(&device);
    let limited = |args: &[&str]| run_under_address_limit(4_194_304, args, &[]);
    let stack = common::scenario("linear-stack-correlated.json");
    assert_device_refused(&limited(&["run", d, "--quiet"]), &device);
    assert_device_refused(&limited(&["validate", d]), &device);
    assert_device_refused(&limited(&["evaluate", &stack, "--inputs", d]), &device);
    assert_device_refused(&limited(&["fit", d]), &device);
    assert_device_refused(&limited(&["merge", d]), &device);
    assert_device_refused(&limited(&["check", &stack, "--baseline", d]), &device);
    let page = dir.join("page.html");
    assert_device_refused(&limited(&["report", d, "-o", path_arg(&page)]), &device);
    // The data column of an empirical distribution, at its JSON path.
    let scenario = TempScenario::new(
        "hardening-device-column",
        &with("linear-stack-correlated.json", |s| {
            let variables = s["variables"].as_array_mut().expect("variables");
            variables[0]["distribution"] =
                serde_json::json!({"empirical": {"csv": d, "column": "x"}});
        }),
    );
    let line = one_line(&limited(&["validate", path_arg(scenario.path())]), 2);
    assert!(
        line.contains("variables[0].distribution.empirical.csv")
            && line.contains(&format!(
                "{d}: cannot read: a character device, not a regular file"
            )),
        "{line}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn rows_to_evaluate_are_checked_against_the_memory_before_they_are_read() {
    let dir = scratch("rows");
    let stack = common::scenario("linear-stack-correlated.json");
    let rows = dir.join("rows.csv");
    let written = run_rvtol(&[
        "run",
        &stack,
        "--samples",
        "50000",
        "--samples-out",
        path_arg(&rows),
        "--quiet",
    ]);
    assert_eq!(written.status.code(), Some(0), "{}", text(&written.stderr));
    let size = std::fs::metadata(&rows).expect("rows").len() as f64;
    // 10 MB of rows in 64 MiB: the rows, their records, the values, the evaluated table and
    // its CSV take about five times the file (the report's 1,000,000 rows reached 1.5 GB).
    let line = one_line(
        &run_rvtol(&[
            "evaluate",
            &stack,
            "--inputs",
            path_arg(&rows),
            "--max-memory",
            "64M",
            "-o",
            path_arg(&dir.join("out.csv")),
        ]),
        2,
    );
    assert!(
        line.starts_with("error: evaluate: needs about ")
            && line.contains(&format!(
                "(the {:.1} MB of rows of {} read, evaluated and written out, and 64.0 MB for the program and its tables), more than the 67.1 MB available (--max-memory): split the rows into smaller files",
                size / 1e6,
                rows.display()
            )),
        "{line}"
    );
    assert!(!dir.join("out.csv").exists());
    // Through standard input, whose size is unknown: cut where the rows exceed it.
    let piped = run_with_stdin(
        &["evaluate", &stack, "--inputs", "-", "--max-memory", "64M"],
        &std::fs::read_to_string(&rows).expect("rows"),
    );
    let line = one_line(&piped, 2);
    assert!(
        line.starts_with("error: standard input: more than ")
            && line.ends_with("(what the 67.1 MB of memory available (--max-memory) allows for rows read, evaluated and written out; split the rows into smaller files)"),
        "{line}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fit_refuses_more_columns_than_a_fragment_can_hold_before_any_work() {
    let dir = scratch("wide");
    // The report's file: 3,000 columns of 5 rows took 41 s and 6.2 GB and wrote 480 MB.
    let columns = 3000;
    let mut csv = (0..columns)
        .map(|j| format!("c{j}"))
        .collect::<Vec<_>>()
        .join(",");
    csv.push('\n');
    for k in 0..5 {
        let row: Vec<String> = (0..columns)
            .map(|j| format!("{}", ((k * 7919 + j * 104_729) % 1000) as f64 / 1000.0))
            .collect();
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    let wide = dir.join("wide.csv");
    std::fs::write(&wide, csv).expect("write");
    let started = std::time::Instant::now();
    let out = run_rvtol(&["fit", path_arg(&wide)]);
    let line = one_line(&out, 2);
    assert_eq!(
        line,
        format!(
            "error: {}: 3,000 columns to fit, more than the 500 rvtol fit takes (the fragment holds a correlation for every pair of columns, 4,498,500 pairs here): fit the columns that vary together a group at a time (one part with --part, or a file per group)",
            wide.display()
        )
    );
    assert!(out.stdout.is_empty());
    assert!(started.elapsed().as_secs_f64() < 10.0);
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------
// A long run says how long.

#[test]
fn a_long_run_says_how_long_it_will_take_even_quiet_and_outside_a_terminal() {
    let stack = common::scenario("linear-stack-correlated.json");
    // The threshold (a minute) set low, so that a short run counts as long.
    let long = |args: &[&str]| {
        Command::new(rvtol_binary())
            .args(args)
            .env("RVTOL_ESTIMATE_THRESHOLD_SECONDS", "0.000001")
            .output()
            .expect("start rvtol")
    };
    for (command, args) in [
        ("run", vec!["run", &stack, "--samples", "100000", "--quiet"]),
        (
            "sensitivity",
            vec!["sensitivity", &stack, "--samples", "40000", "--quiet"],
        ),
    ] {
        let out = long(&args);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        let stderr = text(&out.stderr);
        let lines: Vec<&str> = stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{stderr}");
        let samples = args[3].parse::<u64>().expect("samples");
        assert!(
            lines[0].starts_with(&format!(
                "{command}: {} samples will take about ",
                if samples == 100_000 {
                    "100,000"
                } else {
                    "40,000"
                }
            )) && lines[0].contains(" s at the pace of the first ")
                && lines[0].ends_with("; fewer --samples take less"),
            "{stderr}"
        );
    }
    // A run of less than the threshold says nothing.
    let short = run_rvtol(&["run", &stack, "--samples", "100000", "--quiet"]);
    assert_eq!(short.status.code(), Some(0));
    assert!(short.stderr.is_empty(), "{}", text(&short.stderr));
    // --help says so.
    let help = text(&run_rvtol(&["run", "--help"]).stdout);
    assert!(
        help.contains(
            "A run whose samples will take more than a minute says so in one line on stderr"
        ),
        "{help}"
    );
}

// ---------------------------------------------------------------------------------------
// Shard files: the shard count bounded, impossible statistics refused by file name.

/// Rewrites a shard file with `change` applied to its decoded header and statistics, its
/// checksum recomputed as rvtol computes it (a file that passes the checksum).
fn rewritten_shard(
    from: &Path,
    to: &Path,
    change: impl FnOnce(&mut rvtol_analysis::shard::ShardHeader, &mut rvtol_engine::run::RunPartial),
) {
    use rvtol_analysis::shard::{decode, encode, ShardContent};
    let mut file = decode(&std::fs::read(from).expect("read shard")).expect("decode shard");
    let ShardContent::Run(partial) = &mut file.content else {
        panic!("a run's shard");
    };
    change(&mut file.header, partial);
    std::fs::write(to, encode(&file.header, &file.content)).expect("write shard");
}

/// Writes shard `k` of `n` of the RV-20E hysteresis run of 20,000 samples (5 chunks).
fn hysteresis_shard(k: u64, n: u64, to: &Path) {
    let scenario = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    let shard = format!("{k}/{n}");
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "20000",
        "--quiet",
        "--shard",
        &shard,
        "--partial",
        path_arg(to),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
}

#[test]
fn a_shard_count_beyond_the_bound_is_refused_and_merge_holds_nothing_per_declared_shard() {
    let dir = scratch("shard-count");
    let scenario = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    let part = dir.join("z.part");
    for shard in ["0/18446744073709551615", "0/100000000", "0/100001"] {
        let line = one_line(
            &run_rvtol(&[
                "run",
                path_arg(&scenario),
                "--samples",
                "20000",
                "--quiet",
                "--shard",
                shard,
                "--partial",
                path_arg(&part),
            ]),
            2,
        );
        assert!(
            line.contains("'--shard <K/N>'") && line.contains("N must be at most 100,000 shards"),
            "{line}"
        );
        assert!(!part.exists());
    }
    // A file that declares such a count anyway (its checksum recomputed) is refused by
    // name, by merge and by merge --missing alike, without reserving memory per shard.
    let real = dir.join("real.part");
    hysteresis_shard(0, 2, &real);
    for shards in [u64::MAX, 100_000_000] {
        rewritten_shard(&real, &part, |header, _| header.shards = shards);
        for args in [vec!["merge", "--missing"], vec!["merge"]] {
            let mut args = args;
            args.push(path_arg(&part));
            let line = one_line(&run_rvtol(&args), 2);
            assert!(
                line.starts_with(&format!("error: {}: damaged: ", path_arg(&part)))
                    && line.contains("more than the 100,000 a run may have"),
                "{args:?}: {line}"
            );
        }
    }
    // The largest count: the missing shards are listed as ranges.
    let last = dir.join("last.part");
    hysteresis_shard(5, 100_000, &last);
    let out = run_rvtol(&["merge", "--missing", path_arg(&last)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert_eq!(text(&out.stdout), "0-4,6-99999\n");
    let line = one_line(&run_rvtol(&["merge", path_arg(&last)]), 2);
    assert!(
        line.starts_with("error: shards 0-4,6-99999 of 100000 have no file"),
        "{line}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn impossible_statistics_in_a_re_checksummed_shard_file_are_refused_naming_it() {
    use rvtol_engine::run::KeptValues;
    let dir = scratch("shard-statistics");
    let (first, second) = (dir.join("0.part"), dir.join("1.part"));
    hysteresis_shard(0, 2, &first);
    hysteresis_shard(1, 2, &second);
    let bad = dir.join("bad.part");
    type Change = Box<dyn FnOnce(&mut rvtol_engine::run::RunPartial)>;
    let cases: Vec<(&str, Change, &str)> = vec![
        (
            "a NaN chunk mean",
            Box::new(|p| p.chunk_moments[0].1[0].mean = f64::NAN),
            "output 0: its mean is NaN",
        ),
        (
            "n = 2^63",
            Box::new(|p| p.chunk_moments[0].1[0].n = 1 << 63),
            "n = 9,223,372,036,854,775,808 values in a chunk of 4096 rows",
        ),
        (
            "min above max",
            Box::new(|p| {
                let m = &mut p.chunk_moments[0].1[0];
                std::mem::swap(&mut m.min, &mut m.max);
            }),
            "above max",
        ),
        (
            "a NaN value",
            Box::new(|p| {
                let KeptValues::Values(values) = &mut p.replicates[0].1[0].kept else {
                    panic!("exact percentiles keep the values");
                };
                values[7] = f64::NAN;
            }),
            "value 7 is NaN",
        ),
        (
            "more samples counted than rows",
            Box::new(|p| p.replicates[0].1[0].excluded += 1),
            "excluded samples in",
        ),
        (
            "a duplicated chunk index",
            Box::new(|p| p.chunk_moments[1].0 = p.chunk_moments[0].0),
            "appears twice",
        ),
    ];
    for (label, change, needle) in cases {
        rewritten_shard(&second, &bad, |_, partial| change(partial));
        for args in [
            vec!["merge", path_arg(&first), path_arg(&bad)],
            vec!["merge", "--missing", path_arg(&first), path_arg(&bad)],
        ] {
            let line = one_line(&run_rvtol(&args), 2);
            assert!(
                line.starts_with(&format!("error: {}: damaged: ", path_arg(&bad)))
                    && line.contains(needle),
                "{label}: {line}"
            );
        }
    }
    // The untouched pair merges.
    let out = run_rvtol(&["merge", path_arg(&first), path_arg(&second), "--json", "-"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn numbers_beyond_their_range_and_negative_ones_name_their_option() {
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let s = path_arg(&scenario);
    // One above u64::MAX reads as 2⁶⁴, which used to saturate: a run without end, or a
    // budget of any size.
    let line = one_line(
        &run_rvtol(&["run", s, "--samples", "18446744073709551616", "--quiet"]),
        2,
    );
    assert_eq!(
        line,
        "error: invalid value '18446744073709551616' for '--samples <SAMPLES>': must be at most 18,446,744,073,709,551,615 (see 'rvtol run --help')"
    );
    let line = one_line(
        &run_rvtol(&["run", s, "--max-memory", "18446744073709551616", "--quiet"]),
        2,
    );
    assert_eq!(
        line,
        "error: invalid value '18446744073709551616' for '--max-memory <SIZE>': must be less than 16 EiB (18,446,744,073,709,551,616 bytes) (see 'rvtol run --help')"
    );
    // A negative value is the option's value, not another argument.
    let line = one_line(&run_rvtol(&["run", s, "--max-memory", "-1"]), 2);
    assert_eq!(
        line,
        "error: invalid value '-1' for '--max-memory <SIZE>': must be a positive size such as 512M or 4G (see 'rvtol run --help')"
    );
    let line = one_line(
        &run_rvtol(&["run", s, "--shard", "-1/3", "--partial", "x.part"]),
        2,
    );
    assert!(
        line.starts_with("error: invalid value '-1/3' for '--shard <K/N>': ")
            && line.contains("0 <= K < N"),
        "{line}"
    );
    let line = one_line(
        &run_rvtol(&["sensitivity", s, "--shard", "-1/3", "--partial", "x.part"]),
        2,
    );
    assert!(
        line.starts_with("error: invalid value '-1/3' for '--shard <K/N>': "),
        "{line}"
    );
}

// ---------------------------------------------------------------------------------------
// Messages, round 2.

#[test]
fn rvtol_alone_prints_a_short_usage() {
    let out = run_rvtol::<&str>(&[]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.lines().count() <= 4, "{stderr}");
    assert!(stderr.contains("rvtol --help"), "{stderr}");
    assert!(
        stderr.contains("run, merge, nominal, sensitivity, baseline, check"),
        "{stderr}"
    );
}

#[test]
fn init_parameter_messages_show_numbers_as_written_or_rounded() {
    let line = one_line(
        &run_rvtol(&["init", "geometric_hysteresis", "--param", "pin_count=1e300"]),
        2,
    );
    assert_eq!(
        line,
        "error: --param pin_count: must be a positive whole number, got 1e300"
    );
    let line = one_line(
        &run_rvtol(&[
            "init",
            "geometric_hysteresis",
            "--param",
            "pin_count=1e-300",
        ]),
        2,
    );
    assert!(line.ends_with("got 1e-300"), "{line}");
    // Numbers rvtol derives have four significant digits.
    let line = one_line(
        &run_rvtol(&[
            "init",
            "cycloid_pin_contact",
            "--param",
            "eccentricity_mm=1e300",
        ]),
        2,
    );
    assert_eq!(
        line,
        "error: --param eccentricity_mm: K1 = e·z_p/r_p = 5.229e299 must be below 1 (a curtate cycloid)"
    );
    let line = one_line(
        &run_rvtol(&[
            "init",
            "cycloid_pin_contact",
            "--param",
            "pin_radius_mm=1e300",
        ]),
        2,
    );
    assert!(line.ends_with("r_p·sin(π/z_p) = 6.002"), "{line}");
    for (model, param) in [
        ("torsion_curve", "needle_roller_diameter_mm=-1e300"),
        ("geometric_hysteresis", "eccentricity_mm=1e300"),
        ("crank_elastic_error", "disc_torque_balance=1e300"),
    ] {
        let line = one_line(&run_rvtol(&["init", model, "--param", param]), 2);
        assert!(line.len() < 250, "{line}");
        assert!(
            !line.contains("0000000000"),
            "{model} {param}: a number in full: {line}"
        );
    }
}

#[test]
fn standard_input_is_read_once_and_a_baseline_may_come_from_it() {
    let dir = scratch("stdin-once");
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let s = path_arg(&scenario);
    let baseline = dir.join("b.json");
    let out = run_rvtol(&[
        "baseline",
        s,
        "--samples",
        "1000",
        "--quiet",
        "-o",
        path_arg(&baseline),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let recorded = std::fs::read_to_string(&baseline).expect("read");
    // The baseline on standard input: the same check as from its file.
    let from_file = run_rvtol(&["check", s, "--baseline", path_arg(&baseline), "-q"]);
    let from_stdin = run_with_stdin(&["check", s, "--baseline", "-", "-q"], &recorded);
    assert_eq!(
        from_stdin.status.code(),
        Some(0),
        "{}",
        text(&from_stdin.stderr)
    );
    assert_eq!(from_stdin.stdout, from_file.stdout);
    // Both the scenario and the baseline cannot be.
    let text_in = std::fs::read_to_string(&scenario).expect("read");
    let line = one_line(
        &run_with_stdin(&["check", "-", "--baseline", "-"], &text_in),
        2,
    );
    assert!(
        line.contains("--baseline: standard input ('-') already gives the scenario"),
        "{line}"
    );
    // Nor two reports.
    let report = dir.join("r.json");
    let out = run_rvtol(&[
        "run",
        s,
        "--samples",
        "1000",
        "--quiet",
        "--json",
        path_arg(&report),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let json = std::fs::read_to_string(&report).expect("read");
    let page = dir.join("page.html");
    let line = one_line(
        &run_with_stdin(&["report", "-", "-", "-o", path_arg(&page)], &json),
        2,
    );
    assert!(
        line.contains("standard input ('-') can be read once"),
        "{line}"
    );
    assert!(!page.exists());
    let out = run_with_stdin(&["report", "-", "-o", path_arg(&page)], &json);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_parquet_file_as_csv_input_is_named_as_such() {
    let dir = scratch("parquet-inputs");
    let scenario = workspace_dir().join("scenarios/linear-stack-correlated.json");
    let s = path_arg(&scenario);
    let rows = dir.join("rows.parquet");
    let out = run_rvtol(&[
        "run",
        s,
        "--samples",
        "10",
        "--quiet",
        "--samples-out",
        path_arg(&rows),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let line = one_line(&run_rvtol(&["evaluate", s, "--inputs", path_arg(&rows)]), 2);
    assert!(
        line.starts_with(&format!(
            "error: --inputs: {} is a Parquet file; rows are read from CSV only",
            path_arg(&rows)
        )),
        "{line}"
    );
    let binary = dir.join("rows.csv");
    std::fs::write(&binary, [0xffu8, 0xfe, 0x00, 0x41]).expect("write");
    let line = one_line(
        &run_rvtol(&["evaluate", s, "--inputs", path_arg(&binary)]),
        2,
    );
    assert!(
        line.contains("--inputs: ") && line.contains("is not a CSV file"),
        "{line}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_change_too_large_for_a_percentage_is_never_inf() {
    let dir = scratch("huge-factor");
    let scenario = workspace_dir().join("scenarios/allocation-linear.json");
    let report = dir.join("allocation.json");
    let out = run_rvtol(&[
        "allocate",
        path_arg(&scenario),
        "--output",
        "gap_mm",
        "--target",
        "p99.865 <= 1",
        "--samples",
        "20000",
        "--quiet",
        "--json",
        path_arg(&report),
    ]);
    assert!(
        out.status.code().is_some_and(|c| c <= 1),
        "{}",
        text(&out.stderr)
    );
    let mut allocation: Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("read")).expect("json");
    allocation["sources"][0]["factor"] = Value::from(1e308);
    std::fs::write(&report, allocation.to_string()).expect("write");
    let page = dir.join("page.html");
    let out = run_rvtol(&["report", path_arg(&report), "-o", path_arg(&page)]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let html = std::fs::read_to_string(&page).expect("read");
    assert!(!html.contains("inf %"), "an inf percentage on the page");
    assert!(html.contains("×1.0000e308"), "the factor itself");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_indefinite_correlation_is_called_a_correlation_with_a_rounded_eigenvalue() {
    // Three correlations that cannot hold together: eigenvalue 1 − 1.8 = −0.8.
    let contents = with("linear-stack-correlated.json", |s| {
        s["correlations"] = serde_json::json!([
            { "between": ["bearing_width", "spacer_width"], "rho": 0.9 },
            { "between": ["bearing_width", "bore_depth"], "rho": 0.9 },
            { "between": ["spacer_width", "bore_depth"], "rho": -0.9 }
        ]);
    });
    assert_refused(
        "hardening-correlations-indefinite",
        &contents,
        &["correlations (joint correlation of variables[0], variables[1], variables[2]): correlation is not positive semi-definite (smallest eigenvalue -0.8)"],
    );
    // A part's correlation matrix, likewise (with its own ±0.3 of the tilts).
    let contents = with("linear-stack-correlated.json", |s| {
        let correlation = &mut s["parts"][0]["correlation"];
        for (i, j, rho) in [(0, 1, 0.9), (0, 2, 0.9), (1, 2, -0.9)] {
            correlation[i][j] = Value::from(rho);
            correlation[j][i] = Value::from(rho);
        }
    });
    assert_refused(
        "hardening-part-correlation-indefinite",
        &contents,
        &["parts[0].correlation: correlation is not positive semi-definite (smallest eigenvalue -0.8329)"],
    );
}

#[test]
fn the_greek_mu_is_read_as_the_micro_sign_in_units() {
    // The carrier in µm and µrad, the bore depth in µm, written with either letter.
    let micro = |mu: char| {
        with("linear-stack-correlated.json", |s| {
            let part = &mut s["parts"][0];
            part["units"] = serde_json::json!({
                "translation": format!("{mu}m"),
                "rotation": format!("{mu}rad"),
            });
            part["mean"] = serde_json::json!([0.0, 0.0, 2.0, 0.0, 0.0, 0.0]);
            part["sd"] = serde_json::json!([3.0, 3.0, 2.0, 100.0, 100.0, 0.0]);
        })
    };
    let mut reports = Vec::new();
    for (label, mu) in [("micro-sign", '\u{b5}'), ("greek-mu", '\u{3bc}')] {
        let file = TempScenario::new(&format!("hardening-{label}"), &micro(mu));
        let out = run_rvtol(&[
            "run",
            path_arg(file.path()),
            "--samples",
            "2000",
            "--quiet",
            "--json",
            "-",
        ]);
        assert_eq!(out.status.code(), Some(0), "{label}: {}", text(&out.stderr));
        // The two texts differ (µ, μ), so do their digests; every figure is the same.
        let mut report: Value = serde_json::from_slice(&out.stdout).expect("a JSON report");
        report["scenario_sha256"] = Value::Null;
        reports.push(report);
    }
    assert_eq!(reports[0], reports[1], "µ and μ give one run");
    // A variable in μm bound to an input in mm is converted as one in µm.
    let hysteresis = |unit: &str| {
        with("rv20e-hysteresis.json", |s| {
            let variables = s["variables"].as_array_mut().expect("variables");
            let v = variables
                .iter_mut()
                .find(|v| v["name"] == "pin_circle_radius_error")
                .expect("the pin circle radius error");
            v["unit"] = Value::from(unit);
            v["distribution"] = serde_json::json!({
                "tolerance_band": { "lower": -10.0, "upper": 10.0, "cp": 1.0 }
            });
        })
    };
    let mut means = Vec::new();
    for unit in ["\u{b5}m", "\u{3bc}m"] {
        let file = TempScenario::new("hardening-mu-variable", &hysteresis(unit));
        let out = run_rvtol(&[
            "run",
            path_arg(file.path()),
            "--samples",
            "2000",
            "--quiet",
            "--json",
            "-",
        ]);
        assert_eq!(out.status.code(), Some(0), "{unit}: {}", text(&out.stderr));
        let report: Value = serde_json::from_slice(&out.stdout).expect("report");
        means.push(report["outputs"][0]["mean"].clone());
    }
    assert_eq!(means[0], means[1]);
}

// ---------------------------------------------------------------------------------------
// A failing command replaces none of its outputs.

/// The files of `dir` whose names mark a report's temporary (`.NAME.rvtol-tmp-PID`).
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("read the folder")
        .flatten()
        .map(|entry| entry.file_name().to_string_lossy().into_owned())
        .filter(|name| name.contains(".rvtol-tmp-"))
        .collect()
}

#[test]
fn a_failing_run_merge_or_sensitivity_replaces_none_of_its_outputs() {
    let dir = scratch("staged");
    let scenario = dir.join("nan.json");
    std::fs::write(&scenario, torsion_with_zero_stiffness()).expect("write");
    let s = path_arg(&scenario);
    let (json, html, csv) = (dir.join("r.json"), dir.join("r.html"), dir.join("r.csv"));
    let old = |path: &Path| std::fs::write(path, "old\n").expect("write");
    let untouched = |args: &[&str]| {
        for path in [&json, &html, &csv] {
            assert_eq!(
                std::fs::read_to_string(path).expect("read"),
                "old\n",
                "{args:?}: {} was replaced by a failing command",
                path.display()
            );
        }
        assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
    };
    for path in [&json, &html, &csv] {
        old(path);
    }
    let (j, h, c) = (path_arg(&json), path_arg(&html), path_arg(&csv));
    // Every sample is lost, more than the allowed 0 %: the run fails, its table still says
    // what was lost, and no file is replaced.
    let args = [
        "run",
        s,
        "--samples",
        "300",
        "--quiet",
        "--json",
        j,
        "--html",
        h,
        "--samples-out",
        c,
    ];
    let out = run_rvtol(&args);
    assert!(one_line(&out, 2).contains("is not finite for 300 of 300 samples"));
    assert!(text(&out.stdout).contains("lost data: 300 of 300 samples"));
    untouched(&args);
    // The merge of its shards fails alike.
    let shards: Vec<PathBuf> = (0..2).map(|k| dir.join(format!("p{k}.bin"))).collect();
    for (k, shard) in shards.iter().enumerate() {
        let out = run_rvtol(&[
            "run",
            s,
            "--samples",
            "300",
            "--quiet",
            "--shard",
            &format!("{k}/2"),
            "--partial",
            path_arg(shard),
        ]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    }
    let args = [
        "merge",
        path_arg(&shards[0]),
        path_arg(&shards[1]),
        "--quiet",
        "--json",
        j,
        "--html",
        h,
    ];
    let out = run_rvtol(&args);
    assert!(one_line(&out, 2).contains("is not finite for 300 of 300 samples"));
    untouched(&args);
    // A sensitivity analysis that loses 2 % of its rows (the stiffness error drawn from
    // N(0, 0.5)), more than the allowed 0 %.
    std::fs::write(
        &scenario,
        with("rv20e-torsion.json", |s| {
            let variables = s["variables"].as_array_mut().expect("variables");
            let v = variables
                .iter_mut()
                .find(|v| v["name"] == "crank_bearing_stiffness_error")
                .expect("the stiffness error variable");
            v["distribution"] = serde_json::json!({ "normal": { "mean": 0.0, "sd": 0.5 } });
        }),
    )
    .expect("write");
    let args = [
        "sensitivity",
        s,
        "--samples",
        "256",
        "--bootstrap",
        "10",
        "--quiet",
        "--json",
        j,
        "--html",
        h,
    ];
    let out = run_rvtol(&args);
    assert!(one_line(&out, 2).contains("rows with non-finite model values"));
    untouched(&args);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_page_leaves_out_a_nominal_curve_the_model_cannot_draw_and_says_why() {
    // The stiffness error's mean at −1: the nominal design has no stiffness, its torsion
    // curve is NaN, and about half of the samples are lost, within the allowed 90 %.
    let dir = scratch("nan-page");
    let scenario = dir.join("half.json");
    std::fs::write(
        &scenario,
        with("rv20e-torsion.json", |s| {
            let variables = s["variables"].as_array_mut().expect("variables");
            let v = variables
                .iter_mut()
                .find(|v| v["name"] == "crank_bearing_stiffness_error")
                .expect("the stiffness error variable");
            v["distribution"]["normal"]["mean"] = Value::from(-1.0);
        }),
    )
    .expect("write");
    let (json, html) = (dir.join("r.json"), dir.join("r.html"));
    let out = run_rvtol(&[
        "run",
        path_arg(&scenario),
        "--samples",
        "1000",
        "--quiet",
        "--max-non-finite",
        "0.9",
        "--json",
        path_arg(&json),
        "--html",
        path_arg(&html),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let page = std::fs::read_to_string(&html).expect("the page");
    assert!(
        page.contains("Not drawn: models[0] (torsion_curve): curve torsion_curve")
            && page.contains("at the nominal point"),
        "the page says which curve is left out and why"
    );
    let note_start = page.find("Not drawn:").expect("the note");
    let note_end = note_start + page[note_start..].find("</p>").expect("the note's end");
    let outside = format!("{}{}", &page[..note_start], &page[note_end..]);
    assert!(
        !outside.contains("NaN"),
        "no NaN drawn or tabulated on the page"
    );
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the report")).expect("JSON");
    assert!(report["outputs"][0]["non_finite"].as_u64().unwrap_or(0) > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn evaluate_counts_the_rows_it_cannot_evaluate_and_fails_beyond_the_allowed_share() {
    let dir = scratch("evaluate-nan");
    let scenario = workspace_dir().join("scenarios/rv20e-torsion.json");
    let s = path_arg(&scenario);
    let rows = dir.join("rows.csv");
    let out = run_rvtol(&[
        "run",
        s,
        "--samples",
        "2",
        "--quiet",
        "--samples-out",
        path_arg(&rows),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    // The crank bearing stiffness error of the first row at −1: no stiffness, NaN outputs.
    let written = std::fs::read_to_string(&rows).expect("rows");
    let mut lines: Vec<String> = written.lines().map(String::from).collect();
    let column = lines[0]
        .split(',')
        .position(|h| h.starts_with("crank_bearing_stiffness_error"))
        .expect("the stiffness error column");
    let mut cells: Vec<String> = lines[1].split(',').map(String::from).collect();
    cells[column] = "-1".into();
    lines[1] = cells.join(",");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, lines.join("\n") + "\n").expect("write");
    let table = dir.join("out.csv");
    std::fs::write(&table, "old\n").expect("write");
    for allowed in [None, Some("0")] {
        let mut args = vec![
            "evaluate",
            s,
            "--inputs",
            path_arg(&bad),
            "-o",
            path_arg(&table),
        ];
        args.extend(allowed.iter().flat_map(|a| ["--max-non-finite", *a]));
        let line = one_line(&run_rvtol(&args), 2);
        assert!(
            line.contains("models[0] (torsion_curve): lost_motion_arcmin is not finite for 1 of 2 rows (50.000 %, first in ")
                && line.contains("bad.csv: line 2), more than the allowed 0 %"),
            "{args:?}: {line}"
        );
        assert_eq!(std::fs::read_to_string(&table).expect("read"), "old\n");
    }
    // To standard output: nothing printed.
    let out = run_rvtol(&["evaluate", s, "--inputs", path_arg(&bad)]);
    one_line(&out, 2);
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    // Allowed: written, and reported on standard error.
    let out = run_rvtol(&[
        "evaluate",
        s,
        "--inputs",
        path_arg(&bad),
        "-o",
        path_arg(&table),
        "--max-non-finite",
        "0.5",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains(
            "warning: models[0] (torsion_curve): lost_motion_arcmin is not finite for 1 of 2 rows"
        ),
        "{stderr}"
    );
    let written = std::fs::read_to_string(&table).expect("read");
    assert_eq!(written.lines().count(), 3, "{written}");
    let _ = std::fs::remove_dir_all(&dir);
}
