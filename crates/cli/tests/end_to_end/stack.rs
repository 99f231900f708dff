//! `rvtol stack`: its JSON holds the figures the tables print (worst case, arithmetic,
//! RSS, the Monte Carlo run's percentiles beside), the same bytes for any thread count, and
//! a bad request is one line with exit 2 that writes nothing.

use crate::common::{json_of, run_rvtol, scenario};

#[test]
fn the_json_report_holds_the_stack_beside_the_monte_carlo_run() {
    let path = scenario("motor-assembly-stack.json");
    let args = [
        "stack",
        path.as_str(),
        "--samples",
        "100000",
        "--json",
        "-",
        "--threads",
        "1",
    ];
    let report = json_of(&args);
    let output = &report["outputs"][0];
    assert_eq!(output["name"], "gap_mm");
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let worst = [
        &output["worst_case"]["low"]["value"],
        &output["worst_case"]["high"]["value"],
    ];
    assert!((number(worst[0]) + 0.283).abs() < 1e-12 && (number(worst[1]) - 0.483).abs() < 1e-12);
    assert_eq!(output["worst_case"]["search"], "every corner");
    assert!((number(&output["rss"][1]) - 0.27825).abs() < 5e-6);
    // Beside it the run: P99.865 of N(0.1, (0.17825/3)²) is 0.27825; its standard error
    // at 100,000 samples is about σ·√(p(1−p))/(φ(3)·√n) = 0.0594·0.0367/(0.00443·316)
    // ≈ 0.0016.
    let p99 = number(&output["monte_carlo"]["p99_865"]);
    assert!((p99 - 0.27825).abs() < 5.0 * 0.0016, "{p99}");
    assert_eq!(report["monte_carlo_samples"], 100000);
    assert_eq!(output["contributors"][0]["column"], "e_case");
    // The same bytes on two threads.
    let mut two = args;
    two[7] = "2";
    assert_eq!(report, json_of(&two));
}

#[test]
fn an_unknown_output_is_one_line_naming_the_option() {
    let path = scenario("motor-assembly-stack.json");
    let out = run_rvtol(&["stack", path.as_str(), "--output", "gap"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--output: no output \"gap\"; the scenario's continuous outputs: gap_mm"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn the_page_shows_the_stack_and_report_reads_its_json() {
    let dir = tempfile_dir("stack-page");
    let (json, html, again) = (dir.join("s.json"), dir.join("s.html"), dir.join("r.html"));
    let path = scenario("motor-assembly-stack.json");
    let out = run_rvtol(&[
        "stack",
        path.as_str(),
        "--samples",
        "20000",
        "--json",
        json.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = std::fs::read_to_string(&html).unwrap();
    for text in [
        "<h2>Worst case and RSS beside Monte Carlo</h2>",
        "worst case (every corner)",
        "0.48300",
        "200.000 ± 0.145 mm",
        "stack report</td><td>rvtol",
    ] {
        assert!(page.contains(text), "{text}");
    }
    let out = run_rvtol(&[
        "report",
        json.to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("(stack)"));
    let from_json = std::fs::read_to_string(&again).unwrap();
    assert!(from_json.contains("<h2>Worst case and RSS beside Monte Carlo</h2>"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A fresh folder under the system's temporary one.
fn tempfile_dir(label: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rvtol-{label}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
