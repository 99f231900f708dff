//! The page's rare-event section, from the JSON report of `rvtol rare`: the event, each
//! estimator's probability with its 95 % interval, its model evaluations and those plain
//! Monte Carlo would need for the same precision (or why it gives no figure), each side's
//! centre with the sources' importance factors as bars, and subset simulation's levels as
//! the tail's quantiles.

use serde_json::Value;

use super::chart::{self, BarRow};
use super::html::{escape, figure, number, table};
use super::{array, f, s, ReportError};
use rvtol_engine::format::{format_ppm, group_thousands as thousands};

/// The section.
pub(crate) fn rare_section(report: &Value) -> Result<String, ReportError> {
    let sides = array(report, "sides", "rare-event report")?;
    let estimates = array(report, "estimates", "rare-event report")?;
    let output = s(report, "output").unwrap_or("output");
    let unit = s(report, "unit").unwrap_or("");
    let mut out = String::from("<section id=\"rare\">\n<h2>Rare event</h2>\n");
    out.push_str(&format!(
        "<p>The probability that <b>{}</b> is {} ({}), seed {}, in the {} dimensions of the \
         scenario's standard normal space; each estimator stops when its 95 % interval is \
         within ±{} % of its estimate or at {} model evaluations.</p>\n",
        escape(output),
        escape(s(report, "event").unwrap_or("?")),
        escape(unit),
        report.get("seed").and_then(Value::as_u64).unwrap_or(0),
        report.get("dims").and_then(Value::as_u64).unwrap_or(0),
        percent(f(report, "precision").unwrap_or(f64::NAN)),
        thousands(
            report
                .get("max_evaluations")
                .and_then(Value::as_u64)
                .unwrap_or(0)
        ),
    ));
    out.push_str(&estimates_table(estimates));
    for side in sides {
        out.push_str(&side_figure(side)?);
    }
    for estimate in estimates {
        out.push_str(&tail_table(estimate, unit));
    }
    out.push_str("</section>\n");
    Ok(out)
}

/// One row per estimator: its ppm, interval, evaluations, plain Monte Carlo's and a note.
fn estimates_table(estimates: &[Value]) -> String {
    let rows: Vec<Vec<String>> = estimates
        .iter()
        .map(|e| {
            let method = match s(e, "method") {
                Some("importance") => "importance sampling",
                Some("subset") => "subset simulation",
                other => other.unwrap_or("?"),
            };
            if let Some(why) = s(e, "refused") {
                return vec![
                    method.into(),
                    "no figure".into(),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    escape(why),
                ];
            }
            let interval = match e.get("interval").and_then(Value::as_array) {
                Some(i) if i.len() == 2 => format!(
                    "{} .. {}",
                    format_ppm(i[0].as_f64().unwrap_or(f64::NAN) * 1e6),
                    format_ppm(i[1].as_f64().unwrap_or(f64::NAN) * 1e6)
                ),
                _ => "none (one run)".into(),
            };
            let evaluations = e.get("evaluations").and_then(Value::as_u64);
            let plain = f(e, "plain_monte_carlo");
            let fewer = match (evaluations, plain) {
                (Some(n), Some(p)) if n > 0 => format!("{} ×", thousands((p / n as f64) as u64)),
                _ => String::new(),
            };
            let mut note = String::new();
            if e.get("reached").and_then(Value::as_bool) == Some(false) {
                note.push_str("precision not reached within the budget. ");
            }
            if let Some(warning) = s(e, "warning") {
                note.push_str(&escape(warning));
            }
            vec![
                method.into(),
                f(e, "ppm").map_or("n/a".into(), format_ppm),
                interval,
                evaluations.map_or(String::new(), thousands),
                plain.map_or(String::new(), |p| thousands(p as u64)),
                fewer,
                note,
            ]
        })
        .collect();
    table(
        &[
            "estimator",
            "ppm",
            "95 % interval, ppm",
            "model evaluations",
            "plain Monte Carlo for the same precision",
            "fewer",
            "note",
        ],
        &rows,
        &[1, 2, 3, 4, 5],
    )
}

/// A side's centre and the sources' importance factors at it, as bars.
fn side_figure(side: &Value) -> Result<String, ReportError> {
    let event = s(side, "event").unwrap_or("?");
    let mut out = format!("<h3>{}</h3>\n", escape(event));
    let form = match (
        f(side, "beta"),
        side.get("converged").and_then(Value::as_bool),
    ) {
        (Some(beta), Some(true)) => format!(
            "FORM converged: β = {}, Φ(−β) = {} ppm.",
            number(Some(beta)),
            format_ppm(f(side, "probability").unwrap_or(f64::NAN) * 1e6)
        ),
        _ => format!(
            "FORM did not converge ({}).",
            escape(s(side, "stopped").unwrap_or("no design point"))
        ),
    };
    let centre = match (s(side, "centre"), f(side, "centre_distance")) {
        (Some(kind), Some(distance)) => format!(
            " Importance sampling's centre: {}, {} standard deviations from the nominal point.",
            escape(kind),
            number(Some(distance))
        ),
        _ => format!(
            " No centre: {}.",
            escape(s(side, "no_centre").unwrap_or("none found"))
        ),
    };
    out.push_str(&format!(
        "<p class=\"note\">{form}{centre} {} model evaluations.</p>\n",
        thousands(side.get("evaluations").and_then(Value::as_u64).unwrap_or(0))
    ));
    let Some(factors) = side.get("importance").and_then(Value::as_object) else {
        return Ok(out);
    };
    if factors.is_empty() {
        return Ok(out);
    }
    let rows: Vec<BarRow> = factors
        .iter()
        .map(|(name, value)| BarRow {
            name: name.clone(),
            values: vec![(100.0 * value.as_f64().unwrap_or(f64::NAN), None)],
        })
        .collect();
    let svg = chart::horizontal_bars(
        &format!("What drives {event}"),
        "importance factor α² at the centre (%)",
        &["α²"],
        &rows,
    )?;
    out.push_str(&figure(
        &svg,
        "Each source's share of the squared distance from the nominal point to the event's \
         centre (the squared direction cosines, summed over the dimensions that move the \
         source).",
    ));
    Ok(out)
}

/// Subset simulation's levels: the output's value at each level and the probability of
/// passing it (empty for another estimator).
fn tail_table(estimate: &Value, unit: &str) -> String {
    let Some(levels) = estimate.get("tail").and_then(Value::as_array) else {
        return String::new();
    };
    let rows: Vec<Vec<String>> = levels
        .iter()
        .filter_map(Value::as_array)
        .map(|level| {
            let at = |i: usize| level.get(i).and_then(Value::as_f64);
            vec![number(at(0)), format_ppm(at(1).unwrap_or(f64::NAN) * 1e6)]
        })
        .collect();
    if rows.is_empty() {
        return String::new();
    }
    format!(
        "<h3>The tail on the way to the event</h3>\n<p class=\"note\">Subset simulation's \
         levels, means over its runs: the value the output passes with each probability.</p>\n{}",
        table(
            &[&format!("value ({})", escape(unit)), "ppm beyond"],
            &rows,
            &[0, 1]
        )
    )
}

/// A share as a percentage with no trailing zeros (0.1 → "10").
fn percent(share: f64) -> String {
    let text = format!("{:.3}", 100.0 * share);
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}
