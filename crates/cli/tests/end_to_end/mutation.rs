//! The mutation suite: structure-aware mutations of every shipped scenario, each run by the
//! real binary under a time bound. Every case must end in one of two ways:
//!
//! - exit 0 with a JSON report whose figures are all finite numbers (an index may be null
//!   only with the note saying why), or
//! - exit 2 with exactly one line on stderr, `error: FILE: PATH: message`, naming where
//!   the problem is (a JSON path, or `JSON syntax` with the line and column);
//!
//! never a panic, an abort, a hang or another exit code.
//!
//! Mutations: every numeric leaf set to NaN, +inf and −inf (written as the tokens a JSON
//! writer might produce), ±1e308, ±1e6 (the edge of the range rvtol accepts for a
//! deviation), a thousand times its value, 0 and its negative, a string, null, and
//! removed; every
//! object given an unknown key; every array emptied and extended by a copy of its last
//! element. Arrays of many like elements (the transmission scenario's per-pin variables)
//! are mutated in their first [`ELEMENTS_MUTATED`] elements only: the others have the same
//! structure. Each case runs `rvtol run FILE --samples 64 --json - --quiet` and, when that
//! succeeds, `rvtol nominal FILE --json -`.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use common::{rvtol_binary, workspace_dir};
use serde_json::Value;

/// Elements of an array that are mutated (the rest share their structure).
const ELEMENTS_MUTATED: usize = 3;
/// Longest a case may take before it counts as a hang.
const TIME_BOUND: Duration = Duration::from_secs(60);

/// One step of a JSON path.
#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn path_text(path: &[Step]) -> String {
    let mut text = String::new();
    for step in path {
        match step {
            Step::Key(key) if text.is_empty() => text.push_str(key),
            Step::Key(key) => {
                text.push('.');
                text.push_str(key);
            }
            Step::Index(i) => text.push_str(&format!("[{i}]")),
        }
    }
    text
}

fn at_mut<'a>(value: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(value, |v, step| match step {
        Step::Key(key) => v.get_mut(key).expect("path exists"),
        Step::Index(i) => v.get_mut(*i).expect("path exists"),
    })
}

/// A mutated scenario: what was done where, and the file's text.
struct Case {
    what: String,
    text: String,
}

/// Every mutation of `root`.
fn mutations(root: &Value) -> Vec<Case> {
    let mut cases = Vec::new();
    let mut stack: Vec<Vec<Step>> = vec![Vec::new()];
    while let Some(path) = stack.pop() {
        let mut probe = root.clone();
        let node = at_mut(&mut probe, &path).clone();
        let place = path_text(&path);
        let mut edit = |what: &str, change: &dyn Fn(&mut Value)| {
            let mut mutated = root.clone();
            change(at_mut(&mut mutated, &path));
            cases.push(Case {
                what: format!("{place}: {what}"),
                text: serde_json::to_string_pretty(&mutated).expect("serialisable"),
            });
        };
        match &node {
            Value::Number(n) => {
                let x = n.as_f64().unwrap_or(0.0);
                for (what, value) in [
                    ("1e308", Value::from(1e308)),
                    ("-1e308", Value::from(-1e308)),
                    // The edge of the accepted range, and a value a thousand times off.
                    ("1e6", Value::from(1e6)),
                    ("-1e6", Value::from(-1e6)),
                    ("×1000", Value::from(x * 1000.0)),
                    ("0", Value::from(0)),
                    ("negative", Value::from(-x.abs() - 1.0)),
                    ("a string", Value::from("x")),
                    ("null", Value::Null),
                ] {
                    edit(what, &|v: &mut Value| *v = value.clone());
                }
                // Tokens that are not JSON numbers, as a careless writer emits them.
                for token in ["NaN", "Infinity", "-Infinity"] {
                    let marker = "\"__rvtol_mutation__\"";
                    let mut mutated = root.clone();
                    *at_mut(&mut mutated, &path) = Value::from("__rvtol_mutation__");
                    let text = serde_json::to_string_pretty(&mutated)
                        .expect("serialisable")
                        .replace(marker, token);
                    cases.push(Case {
                        what: format!("{place}: {token}"),
                        text,
                    });
                }
            }
            Value::Object(entries) => {
                edit("an unknown key", &|v: &mut Value| {
                    v.as_object_mut()
                        .expect("object")
                        .insert("unknown_mutation_key".into(), Value::from(1));
                });
                for key in entries.keys() {
                    let mut child = path.clone();
                    child.push(Step::Key(key.clone()));
                    stack.push(child);
                }
            }
            Value::Array(items) => {
                edit("emptied", &|v: &mut Value| {
                    *v = Value::Array(Vec::new());
                });
                if let Some(last) = items.last() {
                    let last = last.clone();
                    edit("extended", &|v: &mut Value| {
                        v.as_array_mut().expect("array").push(last.clone());
                    });
                }
                for i in 0..items.len().min(ELEMENTS_MUTATED) {
                    let mut child = path.clone();
                    child.push(Step::Index(i));
                    stack.push(child);
                }
            }
            _ => {}
        }
        // Removing the node from its parent.
        if let Some((last, parent)) = path.split_last() {
            let mut mutated = root.clone();
            match (at_mut(&mut mutated, parent), last) {
                (Value::Object(map), Step::Key(key)) => {
                    map.remove(key);
                }
                (Value::Array(items), Step::Index(i)) => {
                    items.remove(*i);
                }
                _ => {}
            }
            cases.push(Case {
                what: format!("{place}: removed"),
                text: serde_json::to_string_pretty(&mutated).expect("serialisable"),
            });
        }
    }
    cases
}

/// Cases that ended with exit 0 (a finite report) and with exit 2 (one located line).
static ACCEPTED: AtomicUsize = AtomicUsize::new(0);
static REFUSED: AtomicUsize = AtomicUsize::new(0);

/// What went wrong with a case, if anything: its run, and for a scenario that runs, its
/// nominal evaluation.
fn judge(file: &Path, case: &Case) -> Option<String> {
    std::fs::write(file, &case.text).expect("write the case");
    let ran = judge_command(
        file,
        case,
        &["run", "--samples", "64", "--json", "-", "--quiet"],
    );
    if ran.is_some() || ACCEPTED_LAST.with(|a| !a.get()) {
        return ran;
    }
    judge_command(file, case, &["nominal", "--json", "-"])
}

thread_local! {
    /// Whether the last command judged on this thread exited 0.
    static ACCEPTED_LAST: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs one command on the case's file and judges how it ended.
fn judge_command(file: &Path, case: &Case, args: &[&str]) -> Option<String> {
    ACCEPTED_LAST.with(|a| a.set(false));
    let mut child = Command::new(rvtol_binary())
        .args(args)
        .arg(file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rvtol");
    let started = Instant::now();
    // Read both pipes on their own threads so a large report cannot block the child.
    let mut stdout = child.stdout.take().expect("piped");
    let mut stderr = child.stderr.take().expect("piped");
    let out = std::thread::spawn(move || {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut text).ok();
        text
    });
    let err = std::thread::spawn(move || {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut text).ok();
        text
    });
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if started.elapsed() > TIME_BOUND {
            let _ = child.kill();
            let _ = child.wait();
            return Some(format!(
                "{} ({}): no answer within {TIME_BOUND:?}",
                case.what, args[0]
            ));
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let (stdout, stderr) = (out.join().expect("reader"), err.join().expect("reader"));
    let fail = |why: &str| {
        Some(format!(
            "{} ({}): {why}\n  status {:?}\n  stderr {}",
            case.what,
            args[0],
            status.code(),
            stderr.trim_end()
        ))
    };
    if stderr.contains("panicked") {
        return fail("panic");
    }
    match status.code() {
        Some(0) => {
            let report: Value = match serde_json::from_str(&stdout) {
                Ok(report) => report,
                Err(_) => return fail("exit 0 without a JSON report"),
            };
            if args[0] == "run" {
                ACCEPTED.fetch_add(1, Ordering::Relaxed);
            }
            ACCEPTED_LAST.with(|a| a.set(true));
            non_finite_figure(&report)
                .and_then(|where_| fail(&format!("non-finite figure {where_}")))
        }
        Some(2) => {
            let line = stderr.strip_suffix('\n').unwrap_or(&stderr);
            let prefix = format!("error: {}: ", file.display());
            if line.contains('\n') {
                return fail("more than one line on stderr");
            }
            let Some(rest) = line.strip_prefix(&prefix) else {
                return fail("not `error: FILE: …`");
            };
            // PATH: message, the path without spaces (or `JSON syntax`).
            let located = rest.starts_with("JSON syntax: ")
                || rest
                    .split_once(": ")
                    .is_some_and(|(path, message)| !path.is_empty() && !message.is_empty());
            if located {
                if args[0] == "run" {
                    REFUSED.fetch_add(1, Ordering::Relaxed);
                }
                None
            } else {
                fail("no JSON path")
            }
        }
        _ => fail("exit code neither 0 nor 2"),
    }
}

/// The first figure of a run or nominal report that is not a finite number where one must
/// be.
fn non_finite_figure(report: &Value) -> Option<String> {
    let outputs = report["outputs"].as_array()?;
    for output in outputs {
        let name = output["name"].as_str().unwrap_or("?");
        if let Some(value) = output.get("value") {
            // A nominal value: a finite number, or null where an indicator excludes it.
            if !(value.as_f64().is_some_and(f64::is_finite)
                || value.is_null() && output.get("excluded_by").is_some())
            {
                return Some(format!("{name} = {value}"));
            }
            continue;
        }
        let mut figures: Vec<(&str, &Value)> = [
            "mean",
            "sd",
            "skewness",
            "excess_kurtosis",
            "min",
            "max",
            "ppm_out",
        ]
        .iter()
        .filter(|k| output.get(**k).is_some())
        .map(|k| (*k, &output[*k]))
        .collect();
        // A percentile is null where it reads a sample beyond the limits (flagged, excluded,
        // not finite: docs/models.md, "Conformity"); the report then gives the values' own
        // percentiles, which must be numbers.
        match (
            output["percentiles"].as_object(),
            output.get("value_percentiles"),
        ) {
            (Some(_), Some(values)) => {
                let values = values.as_object()?;
                figures.extend(values.iter().map(|(k, v)| (k.as_str(), v)));
            }
            (Some(percentiles), None) => {
                figures.extend(percentiles.iter().map(|(k, v)| (k.as_str(), v)));
            }
            _ => {}
        }
        for (key, value) in figures {
            if !value.as_f64().is_some_and(f64::is_finite) {
                return Some(format!("{name}.{key} = {value}"));
            }
        }
        let noted = output.get("capability_note").is_some();
        let one_sided = output["spec"]["lower"].is_null() != output["spec"]["upper"].is_null();
        for key in ["cp", "cpk", "cp_percentile", "cpk_percentile"] {
            match output.get(key) {
                None => {}
                Some(Value::Null) if noted => {}
                Some(Value::Null) if one_sided && (key == "cp" || key == "cp_percentile") => {}
                Some(Value::Null) => return Some(format!("{name}.{key} is null without a note")),
                Some(v) if !v.as_f64().is_some_and(f64::is_finite) => {
                    return Some(format!("{name}.{key} = {v}"))
                }
                Some(_) => {}
            }
        }
    }
    None
}

fn shipped_scenarios() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(workspace_dir().join("scenarios"))
        .expect("scenarios/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_mutation_of_every_shipped_scenario_ends_cleanly() {
    let cases: Vec<(String, Case)> = shipped_scenarios()
        .iter()
        .flat_map(|file| {
            let text = rvtol_tests::shipped_text(file);
            let root: Value = serde_json::from_str(&text).expect("shipped scenario parses");
            let stem = file
                .file_stem()
                .expect("stem")
                .to_string_lossy()
                .into_owned();
            mutations(&root)
                .into_iter()
                .map(move |case| (stem.clone(), case))
        })
        .collect();
    assert!(cases.len() > 1000, "only {} cases", cases.len());
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism().map_or(2, |n| n.get());
    let failures: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let (cases, next) = (&cases, &next);
                scope.spawn(move || {
                    let file = std::env::temp_dir()
                        .join(format!("rvtol-mutation-{}-{w}.json", std::process::id()));
                    let mut failures = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some((stem, case)) = cases.get(i) else {
                            break;
                        };
                        if let Some(failure) = judge(&file, case) {
                            failures.push(format!("{stem} {failure}"));
                        }
                    }
                    let _ = std::fs::remove_file(&file);
                    failures
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("worker"))
            .collect()
    });
    eprintln!(
        "{} cases: {} ran with finite figures, {} refused with a located line, {} failed",
        cases.len(),
        ACCEPTED.load(Ordering::Relaxed),
        REFUSED.load(Ordering::Relaxed),
        failures.len()
    );
    // Both ends must be exercised: a suite whose cases all fail to parse tests nothing.
    assert!(ACCEPTED.load(Ordering::Relaxed) > 100 && REFUSED.load(Ordering::Relaxed) > 100);
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
