//! The page's inputs section, from the `inputs` of the run's JSON report: each random
//! input's law as the scenario states it (distribution, parameters, mean, sd, tolerance,
//! unit), and where a sensitivity or stack report is composed beside it, what each input
//! contributes (its source's total Sobol' index, its share of the RSS stack).

use serde_json::Value;

use super::html::{escape, number, table};
use super::{f, s};

/// Outputs of each analysis whose contributions get a column (the others are in its
/// section).
const CONTRIBUTION_COLUMNS: usize = 1;

/// What an input contributes, read by its source and column.
type ContributionOf<'a> = Box<dyn Fn(&str, &str) -> Option<f64> + 'a>;

/// One column of contributions: its header and the value for an input (`source`,
/// `column`).
struct Contribution<'a> {
    header: String,
    value: ContributionOf<'a>,
}

/// The section, when the run report lists its inputs.
pub(crate) fn inputs_section(
    run: &Value,
    sensitivity: Option<&Value>,
    stack: Option<&Value>,
) -> Option<String> {
    let inputs = run.get("inputs")?.as_array()?;
    if inputs.is_empty() {
        return None;
    }
    let mut contributions = sensitivity.map(sobol_columns).unwrap_or_default();
    contributions.extend(stack.map(stack_columns).unwrap_or_default());
    let mut header = vec![
        "input",
        "distribution",
        "mean",
        "sd",
        "lower",
        "upper",
        "unit",
    ];
    let headers: Vec<String> = contributions.iter().map(|c| c.header.clone()).collect();
    header.extend(headers.iter().map(String::as_str));
    let numeric: Vec<usize> = [2, 3, 4, 5].into_iter().chain(7..header.len()).collect();
    let rows: Vec<Vec<String>> = inputs
        .iter()
        .map(|input| input_row(input, &contributions))
        .collect();
    let mut out = String::from("<section id=\"inputs\">\n<h2>Inputs</h2>\n");
    out.push_str(
        "<p class=\"note\">Each random input as the scenario states it (after unit conversion): \
         its law and parameters, the law's mean and standard deviation, and its tolerance \
         limits, lower and upper (the stated limits; mean ± 3 sd of a normal; 0 to the 99.865 % point of a \
         magnitude). A part's components are normals of its joint law; those marked \
         &quot;Eq. 11&quot; are drawn under document 001's constraint, which moves their mean \
         and narrows their spread.",
    );
    if !contributions.is_empty() {
        out.push_str(
            " S_T: the total Sobol' index of the input's source (its group) on the \
             sensitivity report's first output; RSS %: the input's share of the RSS \
             stack's variance on the stack report's first output, where its linearisation \
             describes it (R² high enough, see the stack section). The other outputs' \
             figures are in their sections.",
        );
    }
    out.push_str("</p>\n");
    out.push_str(&table(&header, &rows, &numeric));
    out.push_str("</section>\n");
    Some(out)
}

/// One input's row.
fn input_row(input: &Value, contributions: &[Contribution]) -> Vec<String> {
    let column = s(input, "column").unwrap_or("?");
    let source = s(input, "source").unwrap_or(column);
    let mut name = escape(column);
    if let Some(with) = input.get("correlated_with").and_then(Value::as_array) {
        let names: Vec<&str> = with.iter().filter_map(Value::as_str).collect();
        if !names.is_empty() {
            name.push_str(&format!(
                "<br><small>correlated with {}</small>",
                escape(&names.join(", "))
            ));
        }
    }
    if input.get("constrained").and_then(Value::as_bool) == Some(true) {
        name.push_str(" <small>(Eq. 11)</small>");
    }
    let limit = |i: usize| {
        let limits = input.get("tolerance").and_then(Value::as_array);
        number(limits.and_then(|l| l.get(i)).and_then(Value::as_f64))
    };
    let mut row = vec![
        name,
        law(input),
        number(f(input, "mean")),
        number(f(input, "sd")),
        limit(0),
        limit(1),
        escape(s(input, "unit").unwrap_or("")),
    ];
    row.extend(
        contributions
            .iter()
            .map(|c| (c.value)(source, column).map_or(String::new(), |v| number(Some(v)))),
    );
    row
}

/// "tolerance band" over "lower -0.01, upper 0.01, cp 1, mean_shift 0", escaped.
fn law(input: &Value) -> String {
    let name = s(input, "distribution").unwrap_or("?");
    let parameters: Vec<String> = input
        .get("parameters")
        .and_then(Value::as_object)
        .map(|map| {
            map.iter()
                .map(|(key, value)| format!("{key} {}", number(value.as_f64())))
                .collect()
        })
        .unwrap_or_default();
    format!(
        "{}<br><small>{}</small>",
        escape(name),
        escape(&parameters.join(", "))
    )
}

/// The total index of each source on the sensitivity report's first outputs: a source's
/// own, or that of the group holding it (`a+b`).
fn sobol_columns(report: &Value) -> Vec<Contribution<'_>> {
    let outputs = report.get("outputs").and_then(Value::as_array);
    outputs
        .into_iter()
        .flatten()
        .take(CONTRIBUTION_COLUMNS)
        .map(|output| {
            let name = s(output, "name").unwrap_or("output");
            let header = match s(output, "kind") {
                Some("out_of_spec") => format!("S_T · {name} out of spec"),
                _ => format!("S_T · {name}"),
            };
            let indices = output.get("indices").and_then(Value::as_array);
            Contribution {
                header,
                value: Box::new(move |source, _| {
                    indices?
                        .iter()
                        .find(|v| {
                            s(v, "input").is_some_and(|group| group.split('+').any(|g| g == source))
                        })
                        .and_then(|v| f(v, "total"))
                }),
            }
        })
        .collect()
}

/// Each input's share of the RSS variance on the stack report's first outputs, where the
/// linearisation describes the output (R² at least the report's `poor_linearity_below`;
/// the stack section says why the others are not read).
fn stack_columns(report: &Value) -> Vec<Contribution<'_>> {
    let outputs = report.get("outputs").and_then(Value::as_array);
    let poor = f(report, "poor_linearity_below").unwrap_or(1.0);
    outputs
        .into_iter()
        .flatten()
        .take(CONTRIBUTION_COLUMNS)
        .filter(move |output| f(output, "r_squared").is_some_and(|r2| r2 >= poor))
        .map(|output| {
            let contributors = output.get("contributors").and_then(Value::as_array);
            Contribution {
                header: format!("RSS % · {}", s(output, "name").unwrap_or("output")),
                value: Box::new(move |_, column| {
                    contributors?
                        .iter()
                        .find(|c| s(c, "column") == Some(column))
                        .and_then(|c| f(c, "rss_percent"))
                }),
            }
        })
        .collect()
}
