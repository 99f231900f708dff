//! Tests of the CI gate (`rvtol baseline` / `rvtol check`): an unchanged scenario passes
//! exactly with the baseline's seed; with other seeds its false-alarm rate over 50 seeds
//! stays at the nominal 1 %; widening the tolerance of the largest contributor (the pin
//! circle radius error, first in `rvtol sensitivity`) by 20 % fails and names the change;
//! exit codes and JUnit XML through the binary.

mod common;

use common::{run_rvtol, workspace_dir};
use rvtol_engine::gate::{baseline, check, Baseline, FAMILY_FALSE_ALARM};
use rvtol_engine::{RunSettings, Scenario};

const SAMPLES: u64 = 100_000;

fn rv20e_text() -> String {
    std::fs::read_to_string(workspace_dir().join("scenarios/rv20e-hysteresis.json")).unwrap()
}

fn widened_text() -> String {
    // pin_circle_radius_error: ±0.010 mm → ±0.012 mm (+20 %).
    let text = rv20e_text();
    let widened = text.replacen(
        "\"lower\": -0.010, \"upper\": 0.010",
        "\"lower\": -0.012, \"upper\": 0.012",
        1,
    );
    assert_ne!(text, widened);
    widened
}

/// A gate run of SAMPLES samples with `seed`, exact percentiles.
fn settings(seed: u64) -> RunSettings {
    RunSettings {
        samples: SAMPLES,
        seed,
        exact_percentile_limit: rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT,
    }
}

fn scenario(text: &str) -> Scenario {
    Scenario::from_json(text, "rv20e-hysteresis").unwrap()
}

#[test]
fn unchanged_scenario_with_the_same_seed_reproduces_every_figure() {
    let text = rv20e_text();
    let s = scenario(&text);
    let recorded = baseline(&s, &text, settings(11), 0.0, &|_| {}).unwrap();
    let report = check(&s, &text, &recorded, 11, 0.0, &|_| {}).unwrap();
    assert!(report.passed);
    assert!(report.scenario_changes.is_empty());
    for c in &report.comparisons {
        assert_eq!(c.value, Some(c.baseline), "{} {}", c.output, c.figure);
    }
}

#[test]
fn false_alarm_rate_over_50_seeds_is_at_most_nominal() {
    // Family-wise level α = FAMILY_FALSE_ALARM (Bonferroni over the gated figures). The
    // bands hold for a baseline and a check that are both random, so each trial is an
    // independent pair (baseline seed 2k + 1, check seed 2k + 2); checks against one fixed
    // baseline are not independent trials (an unlucky baseline fails many of them). Over 50
    // pairs the number of failures is at most Binomial(50, α) if the bands are right: for
    // α = 1 %, P(≥ 4) = 0.0016, so more than 3 failures means the bands are too narrow.
    let text = rv20e_text();
    let s = scenario(&text);
    let failures = (0..50u64)
        .filter(|&k| {
            let recorded = baseline(&s, &text, settings(2 * k + 1), 0.0, &|_| {}).unwrap();
            !check(&s, &text, &recorded, 2 * k + 2, 0.0, &|_| {})
                .unwrap()
                .passed
        })
        .count();
    assert!(
        failures <= 3,
        "{failures} false alarms in 50 independent pairs at α = {FAMILY_FALSE_ALARM}"
    );
}

#[test]
fn widening_the_largest_contributor_by_20_percent_fails_and_names_the_change() {
    let text = rv20e_text();
    let recorded = baseline(&scenario(&text), &text, settings(1), 0.0, &|_| {}).unwrap();
    let widened = widened_text();
    for seed in [1, 2, 3] {
        let report = check(&scenario(&widened), &widened, &recorded, seed, 0.0, &|_| {}).unwrap();
        assert!(!report.passed, "seed {seed}");
        assert_eq!(
            report.scenario_changes,
            [
                "variables[0].distribution.tolerance_band.lower",
                "variables[0].distribution.tolerance_band.upper"
            ]
        );
        assert!(report
            .moved_lines()
            .iter()
            .any(|line| line.starts_with("moved: hysteresis_arcmin sd:")));
    }
}

#[test]
fn cli_exit_codes_and_junit() {
    let dir = std::env::temp_dir().join(format!("rvtol-gate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = dir.join("baseline.json");
    let junit = dir.join("junit.xml");
    let wide = dir.join("wide.json");
    std::fs::write(&wide, widened_text()).unwrap();
    let scenario_file = workspace_dir().join("scenarios/rv20e-hysteresis.json");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let out = run_rvtol(&[
        "baseline",
        &s(&scenario_file),
        "-o",
        &s(&base),
        "--samples",
        "50000",
        "--quiet",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    Baseline::from_json(&std::fs::read_to_string(&base).unwrap()).unwrap();

    let out = run_rvtol(&[
        "check",
        &s(&scenario_file),
        "--baseline",
        &s(&base),
        "--junit",
        &s(&junit),
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites"));
    assert!(xml.contains("failures=\"0\""));
    let figures = rvtol_engine::gate::gated_figure_count(&scenario(&rv20e_text()));
    assert_eq!(xml.matches("<testcase ").count(), figures);

    let out = run_rvtol(&[
        "check",
        &s(&wide),
        "--baseline",
        &s(&base),
        "--junit",
        &s(&junit),
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout
        .lines()
        .any(|l| l.starts_with("moved: hysteresis_arcmin")));
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.contains("<failure message=\"moved: "));
    assert_eq!(xml.matches("<testcase ").count(), figures);
    assert!(xml.trim_end().ends_with("</testsuite>\n</testsuites>"));

    // A broken baseline file is bad input: exit 2 with one line naming the path.
    std::fs::write(&base, "{\"rvtol_version\": \"0.1.0\"}").unwrap();
    let out = run_rvtol(&["check", &s(&scenario_file), "--baseline", &s(&base)]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("missing field"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}
