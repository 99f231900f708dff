//! The page's sweep section, from the JSON report of `rvtol sweep`: per output, its mean,
//! P50 and P99.865 over the grid (with the spec limits), its out-of-spec ppm when it has
//! limits, and the table of every point's figures with their 95 % intervals.

use rvtol_models::{Curve, CurveStyle, Series};
use serde_json::Value;

use super::html::{escape, figure, number, table};
use super::{anchor, array, f, s, ReportError};
use rvtol_engine::format::{format_ppm, group_thousands as thousands};

/// The section.
pub(crate) fn sweep_section(report: &Value) -> Result<String, ReportError> {
    let axes = array(report, "axes", "sweep report")?;
    let points = array(report, "points", "sweep report")?;
    let names = array(report, "outputs", "sweep report")?;
    let paths: Vec<&str> = axes.iter().map(|a| s(a, "path").unwrap_or("?")).collect();
    let mut out = String::from("<section id=\"sweep\">\n<h2>Sweep of design values</h2>\n");
    out.push_str(&format!(
        "<p class=\"note\">{} points, each a whole run of {} samples with seed {} (the same \
         rows at every point: the points differ by the design alone). Swept: {}. Percentiles \
         as conformity reads them (a flagged sample lies beyond the limits; none where one \
         reaches them).</p>\n",
        points.len(),
        thousands(report.get("samples").and_then(Value::as_u64).unwrap_or(0)),
        report.get("seed").and_then(Value::as_u64).unwrap_or(0),
        axes.iter()
            .map(|a| {
                let current = f(a, "current").map_or(String::new(), |c| {
                    format!(" ({} in the scenario)", number(Some(c)))
                });
                format!(
                    "<code>{}</code>{current}",
                    escape(s(a, "path").unwrap_or("?"))
                )
            })
            .collect::<Vec<_>>()
            .join(" × ")
    ));
    for (k, name) in names.iter().enumerate() {
        let name = name.as_str().unwrap_or("output");
        let of = |p: &Value| p["outputs"].get(k).cloned().unwrap_or(Value::Null);
        let unit = points
            .first()
            .map(of)
            .and_then(|o| s(&o, "unit").map(String::from))
            .unwrap_or_default();
        out.push_str(&format!(
            "<h3 id=\"{}\">{} ({})</h3>\n<div class=\"pair\">\n",
            anchor("sweep", name),
            escape(name),
            escape(&unit)
        ));
        let figures = |label: &str, value: &dyn Fn(&Value) -> Option<f64>| {
            lines(points, &paths, label, &|p| value(&of(p)))
        };
        // One axis: the mean, P50 and P99.865 where the run reads them; two: the mean, one
        // line per value of the second axis.
        let mut series = figures("mean", &|o| f(o, "mean"));
        if paths.len() == 1 {
            series.extend(figures("P50", &|o| f(&o["percentiles"], "50")));
            series.extend(figures("P99.865", &|o| f(&o["percentiles"], "99.865")));
        }
        let spec = points.first().map(of).map(|o| o["spec"].clone());
        let x = axis_range(points);
        for (key, label) in [("lower", "LSL"), ("upper", "USL")] {
            if let (Some(limit), Some((x0, x1))) = (spec.as_ref().and_then(|s| f(s, key)), x) {
                series.push(Series {
                    label: format!("{label} {}", number(Some(limit))),
                    points: vec![(x0, limit), (x1, limit)],
                });
            }
        }
        let what = if paths.len() == 1 {
            "Mean, P50 and P99.865 (where the run reads them: a percentile the flagged samples reach lies beyond the limits and is not drawn)"
        } else {
            "The mean, one line per value of the second design value"
        };
        let y_label = format!("{name} ({unit})");
        let chart = curve(
            &format!("{name} over {}", short(paths[0])),
            paths[0],
            &y_label,
            series,
        );
        out.push_str(&figure(
            &super::chart::curve(&chart)?,
            &format!("{what}: each point a run."),
        ));
        if spec.as_ref().is_some_and(|s| s.is_object()) {
            let ppm = figures("out of spec", &|o| f(o, "ppm_out"));
            let title = format!("{name}: out of spec over {}", short(paths[0]));
            out.push_str(&figure(
                &super::chart::curve(&curve(&title, paths[0], "out of spec (ppm)", ppm))?,
                "Out of spec per million assemblies (outside the limits, not finite, or flagged \
                 non-conforming), one line per value of the second design value when there is one.",
            ));
        }
        out.push_str("</div>\n");
        out.push_str(&point_table(points, &paths, k));
    }
    out.push_str("</section>\n");
    Ok(out)
}

/// A design value's path without its section (`shift_modification_mm`).
fn short(path: &str) -> &str {
    path.rsplit('.').next().unwrap_or(path)
}

/// A line chart.
fn curve(title: &str, x_label: &str, y_label: &str, series: Vec<Series>) -> Curve {
    Curve {
        name: "sweep".into(),
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        style: CurveStyle::Lines,
        series,
    }
}

/// The first axis's least and greatest value.
fn axis_range(points: &[Value]) -> Option<(f64, f64)> {
    let xs: Vec<f64> = points
        .iter()
        .filter_map(|p| p["values"][0].as_f64())
        .collect();
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// One series of `label` over the first axis (one per value of the second axis, when
/// there is one); a point without the figure is left out.
fn lines(
    points: &[Value],
    paths: &[&str],
    label: &str,
    value: &dyn Fn(&Value) -> Option<f64>,
) -> Vec<Series> {
    let second = |p: &Value| p["values"].get(1).and_then(Value::as_f64);
    let mut groups: Vec<Option<f64>> = Vec::new();
    for p in points {
        if !groups.contains(&second(p)) {
            groups.push(second(p));
        }
    }
    groups
        .into_iter()
        .map(|group| Series {
            label: match group {
                Some(v) => format!("{label} at {} = {}", short(paths[1]), number(Some(v))),
                None => label.to_string(),
            },
            points: points
                .iter()
                .filter(|p| second(p) == group)
                .filter_map(|p| Some((p["values"][0].as_f64()?, value(p)?)))
                .collect(),
        })
        .filter(|s| !s.points.is_empty())
        .collect()
}

/// Output `k`'s figures at every point.
fn point_table(points: &[Value], paths: &[&str], k: usize) -> String {
    let mut header: Vec<String> = paths.iter().map(|p| short(p).to_string()).collect();
    header.extend(
        [
            "mean",
            "sd",
            "P50",
            "95 % CI",
            "P99.865",
            "95 % CI",
            "out of spec ppm",
            "95 % CI",
        ]
        .map(String::from),
    );
    let interval = |pair: Option<&Value>| {
        let end = |i: usize| pair.and_then(|p| p.get(i)).and_then(Value::as_f64);
        format!("{} .. {}", number(end(0)), number(end(1)))
    };
    let rows: Vec<Vec<String>> = points
        .iter()
        .map(|p| {
            let o = &p["outputs"][k];
            let percentile = |key: &str| match f(&o["percentiles"], key) {
                Some(v) => (number(Some(v)), interval(o["percentile_ci95"].get(key))),
                None => ("beyond".to_string(), String::new()),
            };
            let (p50, p50_ci) = percentile("50");
            let (tail, tail_ci) = percentile("99.865");
            let ppm = f(o, "ppm_out").map_or("n/a".to_string(), format_ppm);
            let ppm_ci = o.get("ppm_out_ci95").map_or(String::new(), |c| {
                let end = |i: usize| {
                    c.get(i)
                        .and_then(Value::as_f64)
                        .map_or("n/a".into(), format_ppm)
                };
                format!("{} .. {}", end(0), end(1))
            });
            let mut row: Vec<String> = (0..paths.len())
                .map(|a| number(p["values"][a].as_f64()))
                .collect();
            row.extend([
                number(f(o, "mean")),
                number(f(o, "sd")),
                p50,
                p50_ci,
                tail,
                tail_ci,
                ppm,
                ppm_ci,
            ]);
            row
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let numeric: Vec<usize> = (0..header.len()).collect();
    table(&header, &rows, &numeric)
}
