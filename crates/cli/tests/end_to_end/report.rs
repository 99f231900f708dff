//! The HTML report (`--html`, `rvtol report`): for every shipped scenario the page is one
//! self-contained, well-formed document with a histogram and a cumulative plot per
//! continuous output, its spec limits and percentile markers drawn, the model curves of
//! the models that draw them, no NaN or infinity anywhere, nothing loaded from elsewhere
//! (no script, no external reference), and the same bytes for the same reports; the
//! sensitivity and allocation sections from their JSON; a report of another scenario is
//! one line of bad input.

use crate::common;

use common::{run_rvtol, scenario, workspace_dir};
use rvtol_engine::format::group_thousands as thousands;
use serde_json::Value;

fn temp_dir(label: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rvtol-report-{label}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn ok(output: &std::process::Output) {
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Checks that hold for every page: well-formed frame, balanced figures and SVGs, no
/// non-finite number, nothing external.
fn check_page(page: &str, what: &str) {
    assert!(page.starts_with("<!DOCTYPE html>"), "{what}: no doctype");
    assert!(page.trim_end().ends_with("</html>"), "{what}: not closed");
    let count = |needle: &str| page.matches(needle).count();
    assert_eq!(count("<figure>"), count("</figure>"), "{what}: figures");
    assert_eq!(count("<svg "), count("</svg>"), "{what}: SVGs");
    assert_eq!(
        count("<figure>"),
        count("<svg "),
        "{what}: one drawing per figure"
    );
    for bad in [
        "NaN", "inf<", ">inf", "\"inf", "-inf", "Infinity", "<script", "<link", "<img", "src=",
        "@import", "url(",
    ] {
        assert!(!page.contains(bad), "{what}: the page contains {bad:?}");
    }
    // A value cell stays on one line (numbers, `white-space: nowrap`): a sentence there
    // widens its table past the page and pushes the values off screen and paper (a
    // capability note once did).
    for cell in page.split("<td class=\"num\">").skip(1) {
        let text = &cell[..cell.find("</td>").unwrap_or(cell.len())];
        assert!(
            text.chars().count() <= 60,
            "{what}: a value cell of {} characters: {text}",
            text.chars().count()
        );
    }
    // The only address is the SVG namespace.
    for (i, _) in page.match_indices("http") {
        assert!(
            page[i..].starts_with("http://www.w3.org/2000/svg"),
            "{what}: an external address at {}",
            &page[i..(i + 60).min(page.len())]
        );
    }
}

#[test]
fn run_html_of_every_shipped_scenario_has_its_plots() {
    let dir = temp_dir("run");
    let mut files: Vec<_> = std::fs::read_dir(workspace_dir().join("scenarios"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    assert!(files.len() >= 10);
    for path in files {
        let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
        let html = dir.join(format!("{stem}.html"));
        let json = dir.join(format!("{stem}.json"));
        let samples = if stem.contains("transmission") {
            "64"
        } else {
            "2000"
        };
        let output = run_rvtol(&[
            "run",
            path.to_str().unwrap(),
            "--samples",
            samples,
            "--json",
            json.to_str().unwrap(),
            "--html",
            html.to_str().unwrap(),
            "--quiet",
        ]);
        ok(&output);
        let page = std::fs::read_to_string(&html).unwrap();
        check_page(&page, &stem);
        let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert!(page.contains(&format!(
            "rvtol report: {}",
            report["scenario"].as_str().unwrap()
        )));
        assert!(
            page.contains(&format!("seed {}", report["seed"])),
            "{stem}: seed"
        );
        // The inputs on the record: a row per random input of the run's JSON.
        let inputs = report["inputs"].as_array().unwrap();
        assert!(!inputs.is_empty(), "{stem}: inputs");
        assert!(page.contains("<section id=\"inputs\">"), "{stem}: inputs");
        for input in inputs {
            let column = input["column"].as_str().unwrap();
            assert!(
                page.contains(&format!("<tr><td>{column}")),
                "{stem}: {column}"
            );
        }
        let mut continuous = 0;
        for output in report["outputs"].as_array().unwrap() {
            let name = output["name"].as_str().unwrap();
            if output["kind"] == "indicator" {
                assert!(
                    page.contains(&format!("<td>{name}</td>")),
                    "{stem}: indicator {name}"
                );
                continue;
            }
            if output["n"].as_u64().unwrap() == 0 {
                continue;
            }
            continuous += 1;
            for chart in ["histogram", "cumulative distribution"] {
                assert!(
                    page.contains(&format!("{name}: {chart}")),
                    "{stem}: {name} {chart}"
                );
            }
            for marker in ["P0.135", "P50", "P99.865"] {
                assert!(
                    page.contains(&format!(">\n{marker}\n<")),
                    "{stem}: {name} {marker}"
                );
            }
            // Samples flagged non-conforming are drawn apart, their count in the caption.
            if let Some(flagged) = output["histogram"]["flagged"].as_array() {
                let count: u64 = flagged.iter().filter_map(Value::as_u64).sum();
                let counts: u64 = output["histogram"]["counts"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter_map(Value::as_u64)
                    .sum();
                assert!(count > 0 && count <= counts, "{stem}: {name} flagged");
                assert!(page.contains("flagged non-conforming"), "{stem}: legend");
                assert!(
                    page.contains(&format!("Orange: the {} samples", thousands(count))),
                    "{stem}: {name} caption"
                );
            }
            if let Some(spec) = output.get("spec") {
                for (key, label) in [("lower", "LSL"), ("upper", "USL")] {
                    if spec[key].is_number() {
                        assert!(page.contains(label), "{stem}: {name} {label}");
                    }
                }
                assert!(page.contains("Cpk (moments, 95 % CI)"));
            }
        }
        let figures = page.matches("<figure>").count();
        let curves = match stem.as_str() {
            "rv40e-transmission" => 3,
            "rv40e-transmission-002" => 2,
            // The whole loop and its ±3 % window.
            s if s.contains("torsion") => 2,
            _ => 0,
        };
        // Each model's curves at the nominal assembly and at the P50 and the P99.865
        // assemblies of its output, but for those the model gives no finite value for
        // there (named in a note).
        let mut assembly_figures = 0;
        for which in ["P50", "P99.865"].into_iter().filter(|_| curves > 0) {
            let at = page
                .find(&format!(": the {which} assembly of "))
                .unwrap_or_else(|| panic!("{stem}: the {which} assembly"));
            let block = &page[at..];
            let block = &block[..block[1..].find("<h3>").unwrap_or(block.len() - 1) + 1];
            let left_out = block
                .split("Not drawn, the model giving them no finite value for this assembly: ")
                .nth(1)
                .map_or(0, |note| {
                    note[..note.find("</p>").unwrap()].split("; ").count()
                });
            assert_eq!(
                block.matches("<figure>").count() + left_out,
                curves,
                "{stem}: {which}"
            );
            assembly_figures += curves - left_out;
        }
        assert_eq!(
            figures,
            2 * continuous + curves + assembly_figures,
            "{stem}: figures"
        );
        if curves > 0 {
            assert!(page.contains("id=\"curves\""), "{stem}: curves");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn report_composes_run_sensitivity_and_allocation_into_one_page() {
    let dir = temp_dir("compose");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let file = scenario("allocation-linear.json");
    ok(&run_rvtol(&[
        "run",
        &file,
        "--samples",
        "20000",
        "--json",
        &path("run.json"),
        "--quiet",
    ]));
    ok(&run_rvtol(&[
        "sensitivity",
        &file,
        "--samples",
        "2048",
        "--bootstrap",
        "50",
        "--json",
        &path("sens.json"),
        "--quiet",
    ]));
    let allocation = run_rvtol(&[
        "allocate",
        &file,
        "--output",
        "gap_mm",
        "--target",
        "sd <= 0.02",
        "--samples",
        "20000",
        "--json",
        &path("alloc.json"),
        "--quiet",
    ]);
    assert!(matches!(allocation.status.code(), Some(0 | 1)));
    let reports = [path("run.json"), path("sens.json"), path("alloc.json")];
    let mut pages = Vec::new();
    // The same command twice (the page records the command line).
    for out in ["a.html", "a.html"] {
        let mut args = vec!["report".to_string()];
        args.extend(reports.iter().cloned());
        args.extend(["--scenario".into(), file.clone(), "-o".into(), path(out)]);
        let output = run_rvtol(&args);
        ok(&output);
        pages.push(std::fs::read_to_string(path(out)).unwrap());
    }
    assert!(pages[0] == pages[1], "the same reports give the same bytes");
    let page = &pages[0];
    check_page(page, "composed");
    // A linear stack: its linearised contributions are drawn (R² = 1).
    assert!(page.contains("gap_mm: linearised contributions"));
    for id in ["record", "run", "sensitivity", "allocation"] {
        assert!(
            page.contains(&format!("<section id=\"{id}\">")),
            "section {id}"
        );
    }
    // Tornado rows and the allocation's before/after plot.
    for input in ["x1", "x2", "x3", "x4"] {
        assert!(page.contains(&format!(">\n{input}\n<")), "bar of {input}");
    }
    assert!(page.contains("gap_mm: Sobol&apos; indices"));
    assert!(page.contains("gap_mm: before and after"));
    assert!(page.contains("Proposed change of each tolerance"));
    // The description comes from the scenario file.
    assert!(page.contains("Chase &amp; Greenwood 1988"));

    // A report of another scenario: one line, exit 2, nothing written.
    ok(&run_rvtol(&[
        "run",
        &scenario("ishigami.json"),
        "--samples",
        "1000",
        "--json",
        &path("other.json"),
        "--quiet",
    ]));
    let target = path("mixed.html");
    let output = run_rvtol(&[
        "report",
        &path("run.json"),
        &path("other.json"),
        "-o",
        &target,
    ]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("one page shows one scenario"), "{stderr}");
    assert!(!std::path::Path::new(&target).exists());
    // Every report records the SHA-256 of the text it ran, and the page shows it.
    let digest_of = |file: &str| -> String {
        let json: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        json["scenario_sha256"].as_str().unwrap().to_string()
    };
    let digest = digest_of(&path("run.json"));
    assert!(digest.len() == 64 && digest.chars().all(|c| c.is_ascii_hexdigit()));
    assert_eq!(digest, digest_of(&path("sens.json")));
    assert_eq!(digest, digest_of(&path("alloc.json")));
    assert!(page.contains(&format!("<code>{digest}</code>")));
    // The same scenario name with another text (edited after the run): its report is
    // refused beside the first's, and so is the edited file as the page's scenario.
    let mut edited: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    edited["description"] = Value::from("edited after the run");
    std::fs::write(path("edited.json"), edited.to_string()).unwrap();
    ok(&run_rvtol(&[
        "run",
        &path("edited.json"),
        "--samples",
        "1000",
        "--json",
        &path("edited-run.json"),
        "--quiet",
    ]));
    assert_ne!(digest, digest_of(&path("edited-run.json")));
    let refused = |args: &[&str], says: &str| {
        let output = run_rvtol(args);
        assert_eq!(output.status.code(), Some(2));
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
        assert!(!std::path::Path::new(&target).exists());
    };
    refused(
        &[
            "report",
            &path("sens.json"),
            &path("edited-run.json"),
            "-o",
            &target,
        ],
        "another text of it",
    );
    refused(
        &[
            "report",
            &path("run.json"),
            "--scenario",
            &path("edited.json"),
            "-o",
            &target,
        ],
        "not the scenario text the reports were computed from",
    );
    // Two run reports, and a file that is no report.
    let output = run_rvtol(&[
        "report",
        &path("run.json"),
        &path("run.json"),
        "-o",
        &target,
    ]);
    assert_eq!(output.status.code(), Some(2));
    std::fs::write(path("no.json"), "{\"a\": 1}").unwrap();
    let output = run_rvtol(&["report", &path("no.json"), "-o", &target]);
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("not a JSON report"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_linearisation_that_does_not_fit_is_not_drawn() {
    // The pin in a hole: the radial offset √(x² + y²) has no slope at the nominal, and the
    // linear fit explains R² ≈ 0.69 of the gap's variation (README), below the 0.9 the
    // stack flags: the page says so instead of drawing shares that give the position
    // errors 0 %.
    let dir = temp_dir("linearity");
    let html = dir.join("pin.html");
    ok(&run_rvtol(&[
        "sensitivity",
        &scenario("pin-in-hole.json"),
        "--samples",
        "4096",
        "--bootstrap",
        "50",
        "--html",
        html.to_str().unwrap(),
        "--quiet",
    ]));
    let page = std::fs::read_to_string(&html).unwrap();
    check_page(&page, "pin-in-hole sensitivity");
    assert!(!page.contains("linearised contributions</text>"));
    assert!(page.contains("Linearised contributions not drawn"));
    assert!(page.contains("(below 0.9)"));
    std::fs::remove_dir_all(&dir).ok();
}

#[cfg(unix)]
#[test]
fn a_page_path_that_is_not_utf8_is_recorded_lossily_not_a_panic() {
    use std::os::unix::ffi::OsStrExt;
    let dir = temp_dir("utf8");
    let mut name = b"page-".to_vec();
    name.extend_from_slice(&[0xff, b'.', b'h', b't', b'm', b'l']);
    let path = dir.join(std::ffi::OsStr::from_bytes(&name));
    let output = common::run_rvtol(&[
        std::ffi::OsStr::new("run"),
        std::ffi::OsStr::new(&scenario("ishigami.json")),
        std::ffi::OsStr::new("--samples"),
        std::ffi::OsStr::new("100"),
        std::ffi::OsStr::new("--html"),
        path.as_os_str(),
        std::ffi::OsStr::new("--quiet"),
    ]);
    ok(&output);
    let page = std::fs::read_to_string(&path).unwrap();
    assert!(
        page.contains("page-\u{fffd}.html"),
        "the command line, lossily"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_run_records_its_inputs_and_the_page_tabulates_them_with_their_contributions() {
    // The correlated linear stack: its law as the scenario file states it, in the run's
    // JSON and on the page, with each source's total Sobol' index and each input's RSS
    // share beside it when the sensitivity and stack reports are composed with the run.
    let dir = temp_dir("inputs");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let file = scenario("linear-stack-correlated.json");
    for (command, json, extra) in [
        ("run", "run.json", &["--samples", "20000"][..]),
        (
            "sensitivity",
            "sens.json",
            &["--samples", "1024", "--bootstrap", "20"],
        ),
        ("stack", "stack.json", &["--samples", "2000"]),
    ] {
        let mut args = vec![command, file.as_str(), "--json"];
        let out = path(json);
        args.push(&out);
        args.extend_from_slice(extra);
        args.push("--quiet");
        ok(&run_rvtol(&args));
    }
    let read = |name: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(path(name)).unwrap()).unwrap()
    };
    let run = read("run.json");
    let inputs = run["inputs"].as_array().unwrap();
    let by_column = |column: &str| -> &Value {
        (inputs.iter())
            .find(|i| i["column"] == column)
            .unwrap_or_else(|| panic!("{column} not among the inputs: {inputs:#?}"))
    };
    // carrier.dgamma has sd 0: not random, not listed; five carrier components and three
    // variables are.
    assert_eq!(inputs.len(), 8, "{inputs:#?}");
    assert!(inputs.iter().all(|i| i["column"] != "carrier.dgamma"));
    // The file's "tolerance_band": L 24.98, U 25.02, Cp 1.33: σ = (U − L)/(6·Cp).
    let bore = by_column("bore_depth");
    assert_eq!(bore["source"], "bore_depth");
    assert_eq!(bore["distribution"], "tolerance band");
    assert_eq!(bore["parameters"]["cp"], 1.33);
    assert_eq!(bore["unit"], "mm");
    assert!((bore["mean"].as_f64().unwrap() - 25.0).abs() < 1e-12);
    let sd = 0.04 / (6.0 * 1.33);
    assert!((bore["sd"].as_f64().unwrap() - sd).abs() < 1e-15);
    assert_eq!(bore["tolerance"], serde_json::json!([24.98, 25.02]));
    assert_eq!(bore["correlated_with"], serde_json::json!(["carrier.dw"]));
    // The mean shift moves the mean: 9.95 + 0.002.
    let spacer = by_column("spacer_width");
    assert!((spacer["mean"].as_f64().unwrap() - 9.952).abs() < 1e-12);
    assert_eq!(
        spacer["correlated_with"],
        serde_json::json!(["bearing_width"])
    );
    // A part component: a normal of the part's joint law, ±3 sd its tolerance.
    let du = by_column("carrier.du");
    assert_eq!(du["source"], "carrier");
    assert_eq!(du["distribution"], "normal");
    assert_eq!(du["sd"], 0.003);
    let tolerance = du["tolerance"].as_array().unwrap();
    assert!((tolerance[0].as_f64().unwrap() + 3.0 * 0.003).abs() < 1e-15);
    assert!((tolerance[1].as_f64().unwrap() - 3.0 * 0.003).abs() < 1e-15);
    assert_eq!(du["correlated_with"], serde_json::json!(["carrier.dbeta"]));
    assert!(du.get("constrained").is_none());
    // The page: a row per input, the contributions read from the composed reports.
    let html = path("page.html");
    ok(&run_rvtol(&[
        "report",
        &path("run.json"),
        &path("sens.json"),
        &path("stack.json"),
        "-o",
        &html,
    ]));
    let page = std::fs::read_to_string(&html).unwrap();
    check_page(&page, "inputs");
    let section = &page[page
        .find("<section id=\"inputs\">")
        .expect("an inputs section")..];
    let section = &section[..section.find("</section>").unwrap()];
    for input in inputs {
        let column = input["column"].as_str().unwrap();
        assert!(section.contains(&format!("<td>{column}")), "{column}");
    }
    assert!(section.contains("S_T · axial_gap_mm"));
    assert!(section.contains("RSS % · axial_gap_mm"));
    let row_of = |column: &str| -> &str {
        let start = section.find(&format!("<tr><td>{column}")).unwrap();
        &section[start..start + section[start..].find("</tr>").unwrap()]
    };
    let number = |v: &Value| rvtol_engine::format::format_sig(v.as_f64().unwrap());
    // bore_depth is correlated with the carrier: one Sobol' group holds both.
    let sensitivity = read("sens.json");
    let group = (sensitivity["outputs"][0]["indices"]
        .as_array()
        .unwrap()
        .iter())
    .find(|g| {
        let name = g["input"].as_str().unwrap();
        name.split('+').any(|n| n == "bore_depth")
    })
    .unwrap();
    assert!(
        group["input"].as_str().unwrap().contains("carrier"),
        "{group:#}"
    );
    let bore_row = row_of("bore_depth");
    assert!(
        bore_row.contains(&format!(
            "<td class=\"num\">{}</td>",
            number(&group["total"])
        )),
        "{bore_row}"
    );
    let stack = read("stack.json");
    let share = (stack["outputs"][0]["contributors"]
        .as_array()
        .unwrap()
        .iter())
    .find(|c| c["column"] == "bore_depth")
    .unwrap();
    assert!(
        bore_row.contains(&format!(
            "<td class=\"num\">{}</td>",
            number(&share["rss_percent"])
        )),
        "{bore_row}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_rare_event_writes_its_page_and_composes_with_the_stack() {
    let dir = temp_dir("rare");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let file = scenario("motor-assembly-stack.json");
    ok(&run_rvtol(&[
        "rare",
        &file,
        "--output",
        "gap_mm",
        "--above",
        "0.38",
        "--json",
        &path("rare.json"),
        "--html",
        &path("rare.html"),
        "--quiet",
    ]));
    let page = std::fs::read_to_string(path("rare.html")).unwrap();
    check_page(&page, "rare");
    assert!(page.contains("<section id=\"rare\">"));
    assert!(page.contains("importance sampling") && page.contains("subset simulation"));
    assert!(page.contains("What drives above 0.38000"));
    // The largest importance factor is the case's (the README's stack: e_case 66 %).
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(path("rare.json")).unwrap()).unwrap();
    let first = report["sides"][0]["importance"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap();
    assert_eq!(first, "e_case");
    assert!(page.contains("The tail on the way to the event"));
    ok(&run_rvtol(&[
        "stack",
        &file,
        "--json",
        &path("stack.json"),
        "--quiet",
    ]));
    ok(&run_rvtol(&[
        "report",
        &path("stack.json"),
        &path("rare.json"),
        "--scenario",
        &file,
        "-o",
        &path("both.html"),
    ]));
    let both = std::fs::read_to_string(path("both.html")).unwrap();
    check_page(&both, "stack and rare");
    assert!(both.contains("<section id=\"rare\">") && both.contains("<section id=\"stack\">"));
}

#[test]
fn a_sweep_writes_its_page_and_composes_with_the_run() {
    let dir = temp_dir("sweep");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let file = scenario("rv20e-hysteresis.json");
    let set = "--set=reducer.params.shift_modification_mm=-0.016:-0.010:3";
    ok(&run_rvtol(&[
        "sweep",
        &file,
        set,
        "--output",
        "hysteresis_arcmin",
        "--samples",
        "5000",
        "--json",
        &path("sweep.json"),
        "--html",
        &path("sweep.html"),
        "--quiet",
    ]));
    let page = std::fs::read_to_string(path("sweep.html")).unwrap();
    check_page(&page, "sweep");
    assert!(page.contains("<section id=\"sweep\">"));
    assert!(page.contains("hysteresis_arcmin over shift_modification_mm"));
    assert!(page.contains("hysteresis_arcmin: out of spec over shift_modification_mm"));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(path("sweep.json")).unwrap()).unwrap();
    let values: Vec<f64> = (report["axes"][0]["values"].as_array().unwrap().iter())
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(values, [-0.016, -0.013, -0.010]);
    assert_eq!(report["axes"][0]["current"], -0.012);
    // Composed with a run of the same text.
    ok(&run_rvtol(&[
        "run",
        &file,
        "--samples",
        "5000",
        "--json",
        &path("run.json"),
        "--quiet",
    ]));
    ok(&run_rvtol(&[
        "report",
        &path("run.json"),
        &path("sweep.json"),
        "-o",
        &path("both.html"),
    ]));
    let both = std::fs::read_to_string(path("both.html")).unwrap();
    check_page(&both, "run and sweep");
    assert!(both.contains("<section id=\"sweep\">") && both.contains("<section id=\"run\">"));
    // Mistakes: one line each, exit 2, nothing written.
    for (args, says) in [
        (
            vec!["--set=reducer.params.shift_modification_mm=a,b"],
            "\"a\" is not a finite number",
        ),
        (
            vec!["--set=reducer.params.shift_modification_mm=0:1:1"],
            "at least 2",
        ),
        (
            vec!["--set=models[0].inputs.pin_radius_error_mm=0"],
            "not a design value",
        ),
        (vec!["--set=shift=0"], "is not a design value path"),
        (
            vec![
                "--set=reducer.params.shift_modification_mm=0",
                "--output",
                "preloaded",
            ],
            "--output: \"preloaded\" is an indicator; a sweep reads continuous outputs",
        ),
    ] {
        let target = path("refused.json");
        let mut all = vec!["sweep", file.as_str(), "--json", target.as_str()];
        all.extend(args);
        let out = run_rvtol(&all);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{all:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{all:?}: {stderr}");
        assert!(!std::path::Path::new(&target).exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}
