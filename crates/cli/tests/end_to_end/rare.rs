//! `rvtol rare`: its JSON holds the figures the text prints, the same bytes for any thread
//! count, a file it writes is the JSON, and a bad request is one line with exit 2 that
//! writes nothing.

use crate::common::{json_of, run_rvtol, scenario, stdout_of};

#[test]
fn the_json_report_holds_both_estimates_and_the_same_bytes_on_two_threads() {
    // The motor-assembly stack's gap is normal, N(0.1, (0.17825/3)²) (its RSS stack): the
    // gap above 0.1 + 4.753424·0.0594167 mm has probability Q(4.753424) = 1e-6.
    let path = scenario("motor-assembly-stack.json");
    let threshold = format!("{}", 0.1 + 4.753_424_3 * 0.17825 / 3.0);
    let args = [
        "rare",
        path.as_str(),
        "--output",
        "gap_mm",
        "--above",
        threshold.as_str(),
        "--json",
        "-",
        "--threads",
        "1",
    ];
    let report = json_of(&args);
    assert_eq!(report["output"], "gap_mm");
    assert_eq!(report["sides"][0]["centre"], "FORM");
    let beta = report["sides"][0]["beta"].as_f64().unwrap();
    assert!((beta - 4.753_424_3).abs() < 1e-4, "{beta}");
    for (k, method) in ["importance", "subset"].iter().enumerate() {
        let estimate = &report["estimates"][k];
        assert_eq!(estimate["method"], *method);
        let [low, high] = [0, 1].map(|i| estimate["interval"][i].as_f64().unwrap());
        assert!(low <= 1e-6 && 1e-6 <= high, "{method}: [{low}, {high}]");
        assert_eq!(estimate["reached"], true);
    }
    let mut two = args;
    two[9] = "2";
    assert_eq!(report, json_of(&two));
}

#[test]
fn a_bad_request_is_one_line_with_exit_2() {
    let path = scenario("motor-assembly-stack.json");
    for (args, says) in [
        (vec!["--output", "gap"], "--output: no output \"gap\""),
        (vec!["--above", "1", "--below", "0"], "cannot be used with"),
        (vec!["--precision", "2"], "--precision: 2 is not a share"),
        (
            vec!["--level-samples", "10"],
            "--level-samples: 10 is outside",
        ),
        (vec!["--above", "inf"], "--above: not a finite number"),
    ] {
        let mut all = vec!["rare", path.as_str()];
        all.extend(args.iter().copied());
        let out = run_rvtol(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn a_lower_limit_reads_its_tail_downwards() {
    // The pin-in-hole gap's spec is a lower limit (0): subset simulation's levels are
    // values below which the gap falls, decreasing towards the limit.
    let path = scenario("pin-in-hole.json");
    let out = stdout_of(&[
        "rare",
        path.as_str(),
        "--output",
        "gap_mm",
        "--method",
        "subset",
        "-q",
    ]);
    let text = String::from_utf8_lossy(&out);
    let heading = text
        .lines()
        .position(|l| l.starts_with("  below"))
        .expect(&text);
    let levels: Vec<f64> = (text.lines().skip(heading + 1))
        .map_while(|l| l.split_whitespace().next().and_then(|v| v.parse().ok()))
        .collect();
    assert!(levels.len() >= 3, "{text}");
    assert!(
        levels.windows(2).all(|w| w[1] < w[0]) && levels[levels.len() - 1] > 0.0,
        "{levels:?}"
    );
}

#[test]
fn one_subset_run_states_no_interval_and_a_method_asked_twice_runs_once() {
    // A budget below one run's evaluations: one run, no interval (not [0, inf]).
    let path = scenario("pin-in-hole.json");
    let args = [
        "rare",
        path.as_str(),
        "--output",
        "gap_mm",
        "--method",
        "subset",
        "--method",
        "subset",
        "--max-evaluations",
        "1000",
        "--json",
        "-",
    ];
    let report = json_of(&args);
    let estimates = report["estimates"].as_array().unwrap();
    assert_eq!(estimates.len(), 1);
    assert_eq!(estimates[0]["runs"], 1);
    assert!(estimates[0].get("interval").is_none(), "{report}");
    assert_eq!(estimates[0]["reached"], false);
}
