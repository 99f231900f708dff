//! Tests of the CI gate (`rvtol baseline` / `rvtol check`): an unchanged scenario passes
//! exactly with the baseline's seed; with other seeds its false-alarm rate over 50 seeds
//! stays at the nominal 1 %; widening the tolerance of the largest contributor (the pin
//! circle radius error, first in `rvtol sensitivity`) by 20 % fails and names the change;
//! one-sided checks and absolute requirements: the same false-alarm bound over 50
//! independent pairs, and detection in each direction; exit codes and JUnit XML through
//! the binary.

use crate::common;

use common::{run_rvtol, workspace_dir};
use rvtol_analysis::gate::{
    baseline, check, check_with, parse_requirement, Baseline, CheckOptions, Worse,
    FAMILY_FALSE_ALARM,
};
use rvtol_engine::{RunSettings, Scenario};

const SAMPLES: u64 = 100_000;

fn rv20e_text() -> String {
    rvtol_tests::shipped_text(workspace_dir().join("scenarios/rv20e-hysteresis.json"))
}

fn widened_text() -> String {
    // pin_circle_radius_error: ±0.010 mm → ±0.012 mm (+20 %).
    pin_circle_band(&rv20e_text(), 0.012)
}

/// `text` with the pin circle radius error's band ±`limit` mm.
fn pin_circle_band(text: &str, limit: f64) -> String {
    let mut document: serde_json::Value = serde_json::from_str(text).unwrap();
    let variable = document["variables"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|v| v["name"] == "pin_circle_radius_error")
        .unwrap();
    let band = &mut variable["distribution"]["tolerance_band"];
    band["lower"] = (-limit).into();
    band["upper"] = limit.into();
    let changed = serde_json::to_string_pretty(&document).unwrap();
    assert_ne!(text, changed);
    changed
}

/// A gate run of SAMPLES samples with `seed`, exact percentiles.
fn settings(seed: u64) -> RunSettings {
    RunSettings {
        samples: SAMPLES,
        seed,
        exact_percentile_limit: rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT,
        sampling: Default::default(),
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
    let figures = rvtol_analysis::gate::gated_figure_count(&scenario(&rv20e_text()));
    assert_eq!(xml.matches("<testcase ").count(), figures);

    // The widened text is another text than the baseline's: refused, one line, no JUnit
    // written over the last one; with --scenario-changed it is checked.
    let before = std::fs::read(&junit).unwrap();
    let out = run_rvtol(&[
        "check",
        &s(&wide),
        "--baseline",
        &s(&base),
        "--junit",
        &s(&junit),
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("scenario_sha256: recorded from another text")
            && stderr.contains("--scenario-changed"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&junit).unwrap(), before);
    let out = run_rvtol(&[
        "check",
        &s(&wide),
        "--baseline",
        &s(&base),
        "--junit",
        &s(&junit),
        "--scenario-changed",
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

fn options(one_sided: bool, requirements: &[&str]) -> CheckOptions {
    CheckOptions {
        one_sided,
        requirements: requirements.iter().map(|r| r.to_string()).collect(),
    }
}

#[test]
fn one_sided_checks_and_requirements_keep_the_false_alarm_bound() {
    // As above, 50 independent baseline/check pairs of the unchanged RV-20E, now one-sided
    // and with requirements at the true values (the worst case for a requirement that is
    // met): P50 of the lost motion among all the samples 0.6345 (its P99.865 is beyond the
    // limit: 36 % of the assemblies are over-preloaded) and its mean 0.3938 (10⁶ samples,
    // the README's run; their own Monte Carlo errors, about 0.0014 and 0.0003, are well
    // below the 10⁵-sample intervals of about ±0.009 and ±0.003). A requirement fails only when its whole
    // interval misses it, at the family's z: at most 3 failures in 50, P(≥ 4) = 0.0016 for
    // a family level of 1 %.
    let text = rv20e_text();
    let s = scenario(&text);
    let checked = options(true, &["hysteresis_arcmin p50 <= 0.6345", "mean <= 0.3938"]);
    let failures = (0..50u64)
        .filter(|&k| {
            let recorded = baseline(&s, &text, settings(2 * k + 1), 0.0, &|_| {}).unwrap();
            let report =
                check_with(&s, &text, &recorded, 2 * k + 2, 0.0, &checked, &|_| {}).unwrap();
            assert_eq!(report.requirements.len(), 2);
            !report.passed
        })
        .count();
    assert!(
        failures <= 3,
        "{failures} false alarms in 50 independent pairs at α = {FAMILY_FALSE_ALARM}"
    );
}

#[test]
fn requirements_detect_a_violation_and_pass_a_margin() {
    // RV-20E lost motion, 40.8 % out of spec (36.4 % over-preloaded, the rest above
    // 1 arcmin): the values' P99.865 is 1.77 arcmin, but the over-preloaded assemblies lie
    // beyond the limit (docs/models.md, "Conformity"), so P99.865 is beyond it and
    // "≤ 2.0" is violated; P50 among all the samples is 0.635 arcmin (95 % interval
    // 0.626 .. 0.643 at 100,000 samples, seed 1), well above 0.6 and below 0.7.
    let text = rv20e_text();
    let s = scenario(&text);
    let recorded = baseline(&s, &text, settings(1), 0.0, &|_| {}).unwrap();
    for seed in [2, 3, 4] {
        let report = check_with(
            &s,
            &text,
            &recorded,
            seed,
            0.0,
            &options(
                false,
                &[
                    "p50 <= 0.6",
                    "p50 <= 0.7",
                    "p99.865 <= 2.0",
                    "ppm_out <= 300000",
                ],
            ),
            &|_| {},
        )
        .unwrap();
        let status: Vec<&str> = report.requirements.iter().map(|r| r.status).collect();
        assert_eq!(
            status,
            ["violated", "met", "violated", "violated"],
            "seed {seed}"
        );
        assert_eq!(report.requirements[2].value, Some(f64::INFINITY));
        assert!(!report.passed);
        assert!(report.comparisons.iter().all(|c| c.passed));
        // cpk is undefined when over-preloaded samples are counted out of spec within the
        // limits: a requirement on it cannot be shown met and fails.
        let report = check_with(
            &s,
            &text,
            &recorded,
            seed,
            0.0,
            &options(false, &["cpk >= 0.1"]),
            &|_| {},
        )
        .unwrap();
        assert_eq!(report.requirements[0].value, None);
        assert!(!report.passed);
    }
}

/// A linear stack with an upper spec only: gap = x1 + x2, x1 ±0.03 (Cp 1), x2 σ = 0.01,
/// gap ≤ 0.08; `half_width` sets x1's band.
fn upper_spec_text(half_width: f64) -> String {
    format!(
        r#"{{
      "name": "one-sided",
      "variables": [
        {{ "name": "x1", "unit": "mm", "distribution": {{ "tolerance_band": {{ "lower": -{half_width}, "upper": {half_width}, "cp": 1.0 }} }} }},
        {{ "name": "x2", "unit": "mm", "distribution": {{ "normal": {{ "mean": 0.0, "sd": 0.01 }} }} }}
      ],
      "models": [
        {{ "model": "linear_stack", "params": {{ "output": "gap", "unit": "mm", "coefficients": {{ "x1": 1.0, "x2": 1.0 }} }}, "inputs": {{ "x1": "x1", "x2": "x2" }} }}
      ],
      "spec_limits": {{ "gap": {{ "upper": 0.08 }} }}
    }}"#
    )
}

#[test]
fn one_sided_checks_pass_an_improvement_and_fail_a_deterioration() {
    // Tightening x1 from ±0.03 to ±0.02 narrows the gap (sd 0.0141 → 0.0120): a two-sided
    // check fails it, a one-sided one passes it (the sd and the upper percentiles fall,
    // the lower tail rises, which an upper spec does not mind). Widening to ±0.04 fails
    // both ways. The baseline's scenario name is the same, as for an edited scenario.
    let reference = upper_spec_text(0.03);
    let s = Scenario::from_json(&reference, "one-sided").unwrap();
    let recorded = baseline(&s, &reference, settings(1), 0.0, &|_| {}).unwrap();
    let verdict = |half_width: f64, one_sided: bool| {
        let text = upper_spec_text(half_width);
        let changed = Scenario::from_json(&text, "one-sided").unwrap();
        check_with(
            &changed,
            &text,
            &recorded,
            2,
            0.0,
            &options(one_sided, &[]),
            &|_| {},
        )
        .unwrap()
    };
    let tightened = verdict(0.02, true);
    assert!(tightened.passed, "{}", tightened.to_text());
    let directions: Vec<Option<Worse>> = tightened.comparisons.iter().map(|c| c.worse).collect();
    assert_eq!(
        directions,
        [
            Some(Worse::Higher),
            Some(Worse::Higher),
            Some(Worse::Neither),
            Some(Worse::Neither),
            Some(Worse::Higher),
            Some(Worse::Higher),
            Some(Worse::Higher),
            Some(Worse::Higher),
        ]
    );
    assert!(!verdict(0.02, false).passed);
    let widened = verdict(0.04, true);
    assert!(!widened.passed);
    assert!(widened
        .moved_lines()
        .iter()
        .any(|l| l.starts_with("moved: gap p99.865:")));
    assert!(!verdict(0.04, false).passed);
}

/// The RV-20E scenario drawn by scrambled Sobol' points (16 replicates).
fn rqmc_text(text: &str) -> String {
    text.replacen('{', "{\n  \"sampling\": \"rqmc\",", 1)
}

#[test]
fn replicated_gates_keep_the_false_alarm_bound_with_narrower_bands() {
    // Under RQMC the bands come from the replicates' spread (Student t, 15 degrees of
    // freedom): the same false-alarm bound over 50 independent pairs as above, bands of
    // the mean and sd at least 3 times narrower than Monte Carlo's at the same samples
    // (measured: about 7 times), and a 1 % wider pin circle tolerance (lost motion mean
    // +0.6 %, which Monte Carlo's bands of ±0.6 % at these samples let pass) caught for
    // every seed tried.
    let text = rqmc_text(&rv20e_text());
    let s = scenario(&text);
    let rqmc = |seed| RunSettings {
        sampling: s.sampling,
        ..settings(seed)
    };
    let failures = (0..50u64)
        .filter(|&k| {
            let recorded = baseline(&s, &text, rqmc(2 * k + 1), 0.0, &|_| {}).unwrap();
            !check(&s, &text, &recorded, 2 * k + 2, 0.0, &|_| {})
                .unwrap()
                .passed
        })
        .count();
    assert!(failures <= 3, "{failures} false alarms in 50 pairs");
    let recorded = baseline(&s, &text, rqmc(1), 0.0, &|_| {}).unwrap();
    let mc_text = rv20e_text();
    let mc = baseline(&scenario(&mc_text), &mc_text, settings(1), 0.0, &|_| {}).unwrap();
    for figure in ["mean", "sd"] {
        let width = |b: &Baseline| {
            let f = b
                .figures
                .iter()
                .find(|f| f.output == "hysteresis_arcmin" && f.figure == figure)
                .unwrap();
            f.upper - f.lower
        };
        assert!(
            3.0 * width(&recorded) < width(&mc),
            "{figure}: {} against Monte Carlo's {}",
            width(&recorded),
            width(&mc)
        );
    }
    let wider = rqmc_text(&pin_circle_band(&rv20e_text(), 0.0101));
    for seed in [2, 3, 4] {
        let report = check(&scenario(&wider), &wider, &recorded, seed, 0.0, &|_| {}).unwrap();
        assert!(!report.passed, "seed {seed}");
    }
}

#[test]
fn a_requirement_that_does_not_parse_says_why_once() {
    // The target's message quotes what it read; the requirement's text is not repeated
    // before it, and a named output is kept in front.
    let s = scenario(&rv20e_text());
    let err = parse_requirement(&s, "p99.865 <= abc").unwrap_err();
    assert!(
        err.starts_with("\"p99.865 <= abc\": \"abc\" is not a number"),
        "{err}"
    );
    let err = parse_requirement(&s, "hysteresis_arcmin p99.865 <= abc").unwrap_err();
    assert!(
        err.starts_with("hysteresis_arcmin: \"p99.865 <= abc\": \"abc\" is not a number"),
        "{err}"
    );
}
