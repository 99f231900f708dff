//! The page's stack section, from the JSON report of `rvtol stack`: per output the
//! nominal, the worst case, the arithmetic and RSS stacks and the Monte Carlo percentiles
//! side by side with the spec limits, what to read with care, the contributors' shares as
//! bars and the contributor table.

use serde_json::Value;

use super::chart::{self, BarRow};
use super::html::{escape, figure, number, table};
use super::{anchor, array, f, s, ReportError};
use rvtol_engine::format::{format_rounded, format_tolerance, group_thousands as thousands};

/// Most contributors drawn and tabulated (every one is in the JSON report).
const SHOWN: usize = 20;

/// The section.
pub(crate) fn stack_section(report: &Value) -> Result<String, ReportError> {
    let outputs = array(report, "outputs", "stack report")?;
    let mut out =
        String::from("<section id=\"stack\">\n<h2>Worst case and RSS beside Monte Carlo</h2>\n");
    out.push_str(&format!(
        "<p class=\"note\">{}. {} corners ({}), {} model evaluations, R² over {} rows of the scenario's law (below {} the linear figures do not describe the output).</p>\n",
        escape(s(report, "method").unwrap_or("")),
        corners(f(report, "corners")),
        match report.get("all_corners").and_then(Value::as_bool) {
            Some(true) => "every one evaluated",
            _ => "the gradients' evaluated, then searched",
        },
        thousands(report.get("evaluations").and_then(Value::as_u64).unwrap_or(0)),
        thousands(report.get("linearity_rows").and_then(Value::as_u64).unwrap_or(0)),
        number(f(report, "poor_linearity_below")),
    ));
    for output in outputs {
        out.push_str(&output_block(output)?);
    }
    out.push_str("</section>\n");
    Ok(out)
}

/// A corner count: grouped digits, or exponent form when it is beyond 10¹⁵.
fn corners(count: Option<f64>) -> String {
    match count {
        Some(n) if n < 1e15 => thousands(n as u64),
        other => number(other),
    }
}

fn output_block(output: &Value) -> Result<String, ReportError> {
    let name = s(output, "name").unwrap_or("output");
    let unit = s(output, "unit").unwrap_or("");
    let mut out = format!(
        "<h3 id=\"{}\">{} ({})</h3>\n",
        anchor("stack", name),
        escape(name),
        escape(unit)
    );
    out.push_str(&figures_table(output));
    if let Some(note) = s(output, "note") {
        out.push_str(&format!("<p class=\"note\">{}.</p>\n", escape(note)));
    }
    let contributors: Vec<&Value> = output
        .get("contributors")
        .and_then(Value::as_array)
        .map(|a| a.iter().take(SHOWN).collect())
        .unwrap_or_default();
    if !contributors.is_empty() {
        out.push_str(&shares_chart(name, output, &contributors)?);
        out.push_str(&contributor_table(output, &contributors));
    }
    Ok(out)
}

/// Nominal, worst case, arithmetic, RSS, Monte Carlo and spec limits, low and high.
fn figures_table(output: &Value) -> String {
    let end = |key: &str| {
        let end = output.get("worst_case").and_then(|w| w.get(key));
        let value = end.and_then(|e| f(e, "value"));
        let flagged = end.and_then(|e| e.get("flagged")).and_then(Value::as_bool) == Some(true);
        format!(
            "{}{}",
            number(value),
            if flagged { " (flagged)" } else { "" }
        )
    };
    let ends = |key: &str| {
        let pair = output.get(key).and_then(Value::as_array);
        let at = |i: usize| pair.and_then(|p| p.get(i)).and_then(Value::as_f64);
        [number(at(0)), number(at(1))]
    };
    let search = output
        .get("worst_case")
        .and_then(|w| s(w, "search"))
        .unwrap_or("?");
    let [a0, a1] = ends("arithmetic");
    let [r0, r1] = ends("rss");
    let mut rows = vec![
        vec![
            "nominal (box centre)".into(),
            number(f(output, "nominal")),
            String::new(),
        ],
        vec![
            format!("worst case ({})", escape(search)),
            end("low"),
            end("high"),
        ],
        vec!["arithmetic (linear)".into(), a0, a1],
        vec!["RSS (linear, tolerance = ±3 sd)".into(), r0, r1],
    ];
    if let Some(mc) = output.get("monte_carlo") {
        let read = |key: &str| match f(mc, key) {
            Some(v) => number(Some(v)),
            None => "beyond the limits".into(),
        };
        rows.push(vec![
            "Monte Carlo P0.135, P99.865".into(),
            read("p0_135"),
            read("p99_865"),
        ]);
        if let Some(ppm) = f(mc, "ppm_out") {
            rows.push(vec![
                "Monte Carlo out of spec (ppm)".into(),
                number(Some(ppm)),
                String::new(),
            ]);
        }
    }
    if let Some(spec) = output.get("spec") {
        let limit = |key: &str| f(spec, key).map_or("none".to_string(), |v| number(Some(v)));
        rows.push(vec!["spec limits".into(), limit("lower"), limit("upper")]);
    }
    rows.push(vec![
        "linearisation R²".into(),
        number(f(output, "r_squared")),
        String::new(),
    ]);
    table(&["", "low", "high"], &rows, &[1, 2])
}

/// Each contributor's share of the arithmetic stack and of the RSS variance, as bars.
fn shares_chart(
    name: &str,
    output: &Value,
    contributors: &[&Value],
) -> Result<String, ReportError> {
    let rows: Vec<BarRow> = contributors
        .iter()
        .map(|c| BarRow {
            name: s(c, "column").unwrap_or("?").to_string(),
            values: vec![
                (f(c, "worst_case_percent").unwrap_or(f64::NAN), None),
                (f(c, "rss_percent").unwrap_or(f64::NAN), None),
            ],
        })
        .collect();
    let svg = chart::horizontal_bars(
        &format!("{name}: contributors"),
        "share (%)",
        &["arithmetic", "RSS"],
        &rows,
    )?;
    let r2 = number(f(output, "r_squared"));
    Ok(figure(
        &svg,
        &format!(
            "Each input's share of the arithmetic stack, |g|·T / Σ|g|·T, and of the RSS \
             variance, g·T·(ρ·g·T) / RSS² (Euler's allocation: the shares sum to 100 %, a \
             correlated input's can be negative); g the sensitivity at the box centre, T the \
             half tolerance. Linearisation R² {r2}: where it is far below 1 the shares do not \
             describe the output, and the swing column of the table (the output's largest \
             change with that input alone at a limit) is the guide."
        ),
    ))
}

fn contributor_table(output: &Value, contributors: &[&Value]) -> String {
    let rows: Vec<Vec<String>> = contributors
        .iter()
        .map(|c| {
            let unit = s(c, "unit").map_or(String::new(), |u| format!(" {}", escape(u)));
            let tolerance = match (f(c, "lower"), f(c, "upper")) {
                (Some(low), Some(high)) => escape(&format_tolerance(low, high)),
                _ => "n/a".into(),
            };
            vec![
                escape(s(c, "column").unwrap_or("?")),
                format!("{tolerance}{unit}"),
                f(c, "sensitivity").map_or("n/a".into(), format_rounded),
                number(f(c, "worst_case_percent")),
                number(f(c, "rss_percent")),
                f(c, "swing").map_or("n/a".into(), format_rounded),
            ]
        })
        .collect();
    let mut out = table(
        &[
            "input",
            "tolerance",
            "sensitivity",
            "arithmetic %",
            "RSS %",
            "swing",
        ],
        &rows,
        &[2, 3, 4, 5],
    );
    let all = output
        .get("contributors")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    if all > contributors.len() {
        out.push_str(&format!(
            "<p class=\"note\">The first {} of {all} inputs by RSS share; every one is in the JSON report.</p>\n",
            contributors.len()
        ));
    }
    out
}
