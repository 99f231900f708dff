//! One meaning of a non-conforming sample through the binary (issue: `run` printed a
//! P99.865 within the limit that `check --require` called met while `allocate` called it
//! beyond the limits): on the RV-20E selective-fitting scenario, where 5.7 % of the
//! assemblies are over-preloaded (flagged non-conforming, mostly within the 1 arcmin
//! limit), `run` (text, JSON and page), `check` and `allocate` all place those samples
//! beyond the limit, so P99.865 is beyond it everywhere. The library test
//! tests/conformity.rs checks the figures against a reference from the sampled rows; the
//! Python package's test (crates/python/tests) the same case from Python.

use crate::common::{run_rvtol, scenario};

const SAMPLES: &str = "20000";

fn stdout(args: &[&str]) -> (i32, String) {
    let out = run_rvtol(args);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
    )
}

#[test]
fn run_check_and_allocate_give_one_answer_on_selective_fitting() {
    let path = scenario("rv20e-selective-fitting.json");
    let dir = tempfile_dir("conformity");
    // run: JSON null (beyond), the values' own percentile beside it, the page and the
    // text say "beyond".
    let (code, json) = stdout(&["run", &path, "--samples", SAMPLES, "--json", "-", "--quiet"]);
    assert_eq!(code, 0);
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    let output = report["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|o| o["name"] == "hysteresis_arcmin")
        .unwrap();
    assert!(
        output["percentiles"]["99.865"].is_null(),
        "{}",
        output["percentiles"]
    );
    assert!(output["percentiles"]["50"].is_f64());
    assert!(output["value_percentiles"]["99.865"].is_f64());
    let (_, text) = stdout(&["run", &path, "--samples", SAMPLES, "--quiet"]);
    let row = text
        .lines()
        .find(|l| l.starts_with("hysteresis_arcmin "))
        .unwrap();
    assert!(row.contains(" beyond "), "{row}");
    let page = dir.join("page.html");
    let page_arg = page.display().to_string();
    let (code, _) = stdout(&[
        "run",
        &path,
        "--samples",
        SAMPLES,
        "--html",
        &page_arg,
        "--quiet",
    ]);
    assert_eq!(code, 0);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("<td>P99.865</td><td class=\"num\">beyond the limits</td>"));
    // check: the requirement is violated, not met.
    let baseline = dir.join("baseline.json").display().to_string();
    let (code, _) = stdout(&[
        "baseline",
        &path,
        "--samples",
        SAMPLES,
        "--output",
        &baseline,
        "--quiet",
    ]);
    assert_eq!(code, 0);
    let (code, text) = stdout(&[
        "check",
        &path,
        "--baseline",
        &baseline,
        "--require",
        "hysteresis_arcmin p99.865 <= 1.0",
        "--quiet",
    ]);
    assert_eq!(code, 1, "{text}");
    assert!(
        text.contains(
            "violated: hysteresis_arcmin p99.865 <= 1.0 (hysteresis_arcmin p99.865: beyond"
        ),
        "{text}"
    );
    // allocate: today's figure is beyond the limits too.
    let (code, text) = stdout(&[
        "allocate",
        &path,
        "--output",
        "hysteresis_arcmin",
        "--target",
        "p99.865 <= 1.0",
        "--samples",
        SAMPLES,
        "--quiet",
    ]);
    assert_eq!(code, 0, "{text}");
    let today = text.lines().find(|l| l.starts_with("today")).unwrap();
    assert!(today.contains("p99.865 = beyond the limits"), "{today}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A fresh folder in the temporary directory for this test.
fn tempfile_dir(label: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rvtol-{label}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
