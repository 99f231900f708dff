//! README.md's worked examples are executed and compared: the documentation cannot drift
//! from what the binary prints.
//!
//! Each example block in README.md is preceded by an HTML comment (invisible in the
//! rendered page) that says how it was produced:
//!
//! ```text
//! <!-- readme-example
//! rvtol baseline scenarios/rv20e-hysteresis.json -o {tmp}/base.json
//! edit scenarios/rv20e-hysteresis.json /variables/0/distribution/tolerance_band/lower -0.012 > {tmp}/wide.json
//! rvtol check {tmp}/wide.json --baseline {tmp}/base.json
//! status 1
//! lines "moved: hysteresis_arcmin mean" 2, ..., "rvtol check" 1
//! -->
//! ```
//!
//! - `rvtol ARGS` runs the binary (arguments split on blanks, double quotes group, single
//!   quotes group and keep what they hold, double quotes included, for a JSON value);
//!   `{tmp}` is a temporary directory of the example, and its path followed by `/` is left
//!   out of the output (a file written there shows as its name);
//! - `edit SOURCE POINTER VALUE > DEST` copies a scenario with the JSON value at the
//!   pointer replaced (several `edit`s may chain through the same file);
//! - `status N` is the exit code the last command must return (default 0), every earlier
//!   command must succeed;
//! - `stderr` shows the last command's standard error instead of its standard output (a
//!   message a mistake gets);
//! - `lines` selects the lines of the last command's standard output shown in the block,
//!   comma-separated: ranges `a-b` and single lines (1-based), `"TEXT" N` for N lines from
//!   the first line that starts with TEXT (no comma in it; leading blanks ignored), and
//!   `...` for an elision line.
//!
//! The fenced block that follows the comment must equal the selected lines. To regenerate
//! the blocks after a deliberate change, run this test with `RVTOL_README_BLESS=1`, and
//! update the prose that quotes the figures (the diff shows which moved).

use crate::common;

use common::{rvtol_binary, workspace_dir};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One example: its commands and the position of its block in README.md.
struct Example {
    /// The line of the comment (1-based), for messages.
    line: usize,
    directives: Vec<String>,
    /// Byte range of the fenced block's content (between the fences).
    block: std::ops::Range<usize>,
}

fn examples(readme: &str) -> Vec<Example> {
    let mut found = Vec::new();
    let mut search = 0;
    while let Some(start) = readme[search..].find("<!-- readme-example") {
        let start = search + start;
        let end = start
            + readme[start..]
                .find("-->")
                .expect("a readme-example comment is closed by -->");
        let directives = readme[start..end]
            .lines()
            .skip(1)
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .map(str::to_string)
            .collect();
        let fence = end
            + readme[end..]
                .find("```")
                .expect("a block follows the comment");
        let content = fence + readme[fence..].find('\n').expect("fence line ends") + 1;
        let close = content
            + readme[content..]
                .find("```")
                .expect("the example's block is closed");
        found.push(Example {
            line: readme[..start].lines().count() + 1,
            directives,
            block: content..close,
        });
        search = close + 3;
    }
    found
}

/// Splits a command line on blanks; double quotes group (and are removed).
fn split_arguments(line: &str) -> Vec<String> {
    let mut arguments = Vec::new();
    let mut current = String::new();
    let mut quoted = false;
    let mut literal = false;
    let mut started = false;
    for c in line.chars() {
        match c {
            '\'' if !quoted => {
                literal = !literal;
                started = true;
            }
            c if literal => current.push(c),
            '"' => {
                quoted = !quoted;
                started = true;
            }
            c if c.is_whitespace() && !quoted => {
                if started {
                    arguments.push(std::mem::take(&mut current));
                    started = false;
                }
            }
            c => {
                current.push(c);
                started = true;
            }
        }
    }
    if started {
        arguments.push(current);
    }
    arguments
}

fn select(output: &str, selection: &str, example: usize) -> String {
    let lines: Vec<&str> = output.lines().collect();
    let mut shown = String::new();
    for item in selection.split(',').map(str::trim) {
        if item == "..." {
            shown.push_str("...\n");
            continue;
        }
        let (a, b) = if let Some(quoted) = item.strip_prefix('"') {
            // "TEXT" N: N lines from the first line that starts with TEXT.
            let (text, count) = quoted
                .split_once('"')
                .unwrap_or_else(|| panic!("README.md:{example}: unclosed quote in {item}"));
            let count: usize = count.trim().parse().expect("a line count after the anchor");
            let first = lines
                .iter()
                .position(|l| l.trim_start().starts_with(text))
                .unwrap_or_else(|| panic!("README.md:{example}: no line starts with {text:?}"));
            (first + 1, first + count)
        } else {
            let (a, b) = item.split_once('-').unwrap_or((item, item));
            (
                a.parse().expect("line numbers"),
                b.parse().expect("line numbers"),
            )
        };
        assert!(
            a >= 1 && b <= lines.len() && a <= b,
            "README.md:{example}: lines {item} of an output of {} lines",
            lines.len()
        );
        for line in &lines[a - 1..b] {
            shown.push_str(line.trim_end());
            shown.push('\n');
        }
    }
    shown
}

fn edit(arguments: &[String], tmp: &Path, root: &Path, example: usize) {
    assert!(
        arguments.len() == 5 && arguments[3] == ">",
        "README.md:{example}: edit SOURCE POINTER VALUE > DEST"
    );
    let resolve = |p: &str| -> PathBuf { root.join(p.replace("{tmp}", &tmp.to_string_lossy())) };
    // The copy stands alone: the reducer file it names is written in, as rvtol reads it.
    let text = rvtol_tests::shipped_text(resolve(&arguments[0]));
    let mut scenario: serde_json::Value = serde_json::from_str(&text).expect("source is JSON");
    let value: serde_json::Value = serde_json::from_str(&arguments[2]).expect("value is JSON");
    *scenario
        .pointer_mut(&arguments[1])
        .unwrap_or_else(|| panic!("README.md:{example}: no {} in the scenario", arguments[1])) =
        value;
    std::fs::write(
        resolve(&arguments[4]),
        serde_json::to_string_pretty(&scenario).unwrap(),
    )
    .expect("edit destination");
}

/// Runs an example's directives from the workspace root; returns the block it shows.
fn produce(example: &Example, root: &Path) -> String {
    let tmp = std::env::temp_dir().join(format!(
        "rvtol-readme-{}-{}",
        std::process::id(),
        example.line
    ));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut status = 0;
    let mut selection = None;
    let mut from_stderr = false;
    let mut commands = Vec::new();
    for directive in &example.directives {
        let words = split_arguments(&directive.replace("{tmp}", &tmp.to_string_lossy()));
        match words.first().map(String::as_str) {
            Some("rvtol") | Some("edit") => commands.push(words),
            Some("status") => status = words[1].parse().expect("status N"),
            Some("lines") => selection = Some(directive["lines".len()..].trim().to_string()),
            Some("stderr") => from_stderr = true,
            _ => panic!("README.md:{}: unknown directive {directive}", example.line),
        }
    }
    let last = commands
        .iter()
        .rposition(|c| c[0] == "rvtol")
        .expect("an example runs rvtol");
    let mut shown = String::new();
    for (i, words) in commands.iter().enumerate() {
        if words[0] == "edit" {
            edit(&words[1..], &tmp, root, example.line);
            continue;
        }
        let output = Command::new(rvtol_binary())
            .args(&words[1..])
            .current_dir(root)
            .output()
            .expect("cannot start rvtol");
        let expected = if i == last { status } else { 0 };
        assert_eq!(
            output.status.code(),
            Some(expected),
            "README.md:{}: `{}` exited with {:?}: {}",
            example.line,
            words.join(" "),
            output.status.code(),
            String::from_utf8_lossy(&output.stderr)
        );
        if i == last {
            let stream = if from_stderr {
                output.stderr
            } else {
                output.stdout
            };
            let stdout = String::from_utf8(stream)
                .expect("UTF-8 output")
                .replace(&format!("{}/", tmp.display()), "");
            shown = match &selection {
                Some(selection) => select(&stdout, selection, example.line),
                None => stdout
                    .lines()
                    .map(|l| format!("{}\n", l.trim_end()))
                    .collect(),
            };
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
    shown
}

#[test]
fn readme_examples_print_what_the_readme_shows() {
    let root = workspace_dir();
    let path = root.join("README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let found = examples(&readme);
    assert!(
        found.len() >= 6,
        "README.md has {} checked examples; the run, selective fitting, sensitivity, \
         transmission sensitivity, gate and allocation examples are all checked",
        found.len()
    );
    let bless = std::env::var_os("RVTOL_README_BLESS").is_some();
    let mut updated = readme.clone();
    let mut stale = Vec::new();
    // From the last block to the first, so that earlier byte ranges stay valid.
    for example in found.iter().rev() {
        let shown = produce(example, &root);
        if readme[example.block.clone()] != shown {
            stale.push(example.line);
            if bless {
                updated.replace_range(example.block.clone(), &shown);
            } else {
                let want: Vec<&str> = shown.lines().collect();
                let have: Vec<&str> = readme[example.block.clone()].lines().collect();
                let first = want
                    .iter()
                    .zip(&have)
                    .position(|(a, b)| a != b)
                    .unwrap_or(want.len().min(have.len()));
                eprintln!(
                    "README.md:{}: block differs from the output, first at its line {}:\n  \
                     README: {}\n  output: {}",
                    example.line,
                    first + 1,
                    have.get(first).unwrap_or(&"(end)"),
                    want.get(first).unwrap_or(&"(end)")
                );
            }
        }
    }
    if bless {
        if updated != readme {
            std::fs::write(&path, updated).unwrap();
        }
        return;
    }
    assert!(
        stale.is_empty(),
        "README.md examples at lines {stale:?} differ from what rvtol prints; after a \
         deliberate change rerun with RVTOL_README_BLESS=1 and update the prose"
    );
}

#[test]
fn argument_splitting_groups_quotes() {
    assert_eq!(
        split_arguments(r#"edit a.json /x '{"k": "v w"}' > b"#),
        ["edit", "a.json", "/x", r#"{"k": "v w"}"#, ">", "b"]
    );
    assert_eq!(
        split_arguments(r#"allocate s.json --target "p99.865 <= 1.0"  -o x"#),
        [
            "allocate",
            "s.json",
            "--target",
            "p99.865 <= 1.0",
            "-o",
            "x"
        ]
    );
}
