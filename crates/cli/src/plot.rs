//! Rendering of model curves (`rvtol curve`): a CSV table and a self-contained SVG plot
//! with axes, ticks, grid, legend and title. Pure string building; the caller writes the
//! files atomically.

use rvtol_models::{Curve, CurveStyle};

const WIDTH: f64 = 960.0;
const HEIGHT: f64 = 540.0;
const LEFT: f64 = 86.0;
const RIGHT: f64 = 24.0;
const TOP: f64 = 70.0;
const BOTTOM: f64 = 64.0;
const COLOURS: [&str; 6] = [
    "#1f4e79", "#c0504d", "#4f8a3c", "#8064a2", "#d9822b", "#4bacc6",
];

/// The curve as CSV: one x column and one y column per series when the series share their
/// x values, else an x and a y column per series (shorter series padded with empty cells).
pub fn to_csv(curve: &Curve) -> String {
    let quote = |s: &str| {
        if s.contains([',', '"']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let shared = curve.series.windows(2).all(|w| {
        w[0].points.len() == w[1].points.len()
            && w[0]
                .points
                .iter()
                .zip(&w[1].points)
                .all(|(a, b)| a.0 == b.0)
    });
    let mut out = String::new();
    if shared {
        out.push_str(&quote(&curve.x_label));
        for s in &curve.series {
            out.push(',');
            out.push_str(&quote(&format!("{} – {}", s.label, curve.y_label)));
        }
        out.push('\n');
        let rows = curve.series.first().map_or(0, |s| s.points.len());
        for i in 0..rows {
            out.push_str(&format!("{}", curve.series[0].points[i].0));
            for s in &curve.series {
                out.push_str(&format!(",{}", s.points[i].1));
            }
            out.push('\n');
        }
    } else {
        let header: Vec<String> = curve
            .series
            .iter()
            .flat_map(|s| {
                [
                    quote(&format!("{} – {}", s.label, curve.x_label)),
                    quote(&format!("{} – {}", s.label, curve.y_label)),
                ]
            })
            .collect();
        out.push_str(&header.join(","));
        out.push('\n');
        let rows = curve
            .series
            .iter()
            .map(|s| s.points.len())
            .max()
            .unwrap_or(0);
        for i in 0..rows {
            let cells: Vec<String> = curve
                .series
                .iter()
                .flat_map(|s| match s.points.get(i) {
                    Some((x, y)) => [x.to_string(), y.to_string()],
                    None => [String::new(), String::new()],
                })
                .collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
    }
    out
}

/// Tick positions at 1, 2 or 5 times a power of ten covering [lo, hi].
fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    let raw = span / target as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|s| span / s <= target as f64 + 0.5)
        .unwrap_or(10.0 * power);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

fn label(value: f64) -> String {
    if value == 0.0 {
        return "0".into();
    }
    let magnitude = value.abs();
    if !(1e-3..1e5).contains(&magnitude) {
        return format!("{value:.1e}");
    }
    let text = format!("{value:.4}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    text.to_string()
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The curve as a standalone SVG document.
pub fn to_svg(curve: &Curve) -> String {
    let log_x = curve.style == CurveStyle::LogStems;
    // A point is drawn when both coordinates are finite and, on a log axis, x > 0.
    let plottable = |&&(x, y): &&(f64, f64)| x.is_finite() && y.is_finite() && (!log_x || x > 0.0);
    let points = curve
        .series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(plottable);
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in points {
        let x = if log_x { x.log10() } else { x };
        x_lo = x_lo.min(x);
        x_hi = x_hi.max(x);
        y_lo = y_lo.min(y);
        y_hi = y_hi.max(y);
    }
    if !x_lo.is_finite() {
        (x_lo, x_hi, y_lo, y_hi) = (0.0, 1.0, 0.0, 1.0);
    }
    if log_x {
        x_lo = x_lo.floor();
        x_hi = x_hi.ceil().max(x_lo + 1.0);
        y_lo = y_lo.min(0.0);
    }
    if y_hi - y_lo < 1e-12 * y_hi.abs().max(1.0) {
        let pad = 0.5 * y_hi.abs().max(1e-9);
        y_lo -= pad;
        y_hi += pad;
    } else {
        let pad = 0.05 * (y_hi - y_lo);
        y_hi += pad;
        if !(log_x && y_lo == 0.0) {
            y_lo -= pad;
        }
    }
    if x_hi - x_lo <= 0.0 {
        x_hi = x_lo + 1.0;
    }
    let plot_w = WIDTH - LEFT - RIGHT;
    let plot_h = HEIGHT - TOP - BOTTOM;
    let sx = |x: f64| {
        let x = if log_x { x.log10() } else { x };
        LEFT + (x - x_lo) / (x_hi - x_lo) * plot_w
    };
    let sy = |y: f64| TOP + (y_hi - y) / (y_hi - y_lo) * plot_h;

    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{HEIGHT}\" viewBox=\"0 0 {WIDTH} {HEIGHT}\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"13\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    svg.push_str(&format!(
        "<text x=\"{}\" y=\"28\" text-anchor=\"middle\" font-size=\"17\" font-weight=\"bold\">{}</text>\n",
        WIDTH / 2.0,
        escape(&curve.title)
    ));
    // Grid and ticks.
    let x_ticks: Vec<(f64, String)> = if log_x {
        (x_lo as i64..=x_hi as i64)
            .map(|p| (10f64.powi(p as i32), label(10f64.powi(p as i32))))
            .collect()
    } else {
        nice_ticks(x_lo, x_hi, 8)
            .into_iter()
            .map(|t| (t, label(t)))
            .collect()
    };
    for (x, text) in &x_ticks {
        let px = sx(*x);
        svg.push_str(&format!(
            "<line x1=\"{px:.1}\" y1=\"{TOP}\" x2=\"{px:.1}\" y2=\"{:.1}\" stroke=\"#e3e3e3\"/>\n<text x=\"{px:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{text}</text>\n",
            TOP + plot_h,
            TOP + plot_h + 18.0
        ));
    }
    for t in nice_ticks(y_lo, y_hi, 6) {
        let py = sy(t);
        svg.push_str(&format!(
            "<line x1=\"{LEFT}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"{}\"/>\n<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>\n",
            LEFT + plot_w,
            if t == 0.0 { "#9a9a9a" } else { "#e3e3e3" },
            LEFT - 8.0,
            py + 4.0,
            label(t)
        ));
    }
    svg.push_str(&format!(
        "<rect x=\"{LEFT}\" y=\"{TOP}\" width=\"{plot_w}\" height=\"{plot_h}\" fill=\"none\" stroke=\"#333\"/>\n"
    ));
    svg.push_str(&format!(
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>\n",
        LEFT + plot_w / 2.0,
        HEIGHT - 18.0,
        escape(&curve.x_label)
    ));
    svg.push_str(&format!(
        "<text x=\"20\" y=\"{:.1}\" text-anchor=\"middle\" transform=\"rotate(-90 20 {:.1})\">{}</text>\n",
        TOP + plot_h / 2.0,
        TOP + plot_h / 2.0,
        escape(&curve.y_label)
    ));
    // Data.
    for (i, series) in curve.series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let finite = series.points.iter().filter(plottable);
        match curve.style {
            CurveStyle::Lines => {
                let path: Vec<String> = finite
                    .map(|&(x, y)| format!("{:.2},{:.2}", sx(x), sy(y)))
                    .collect();
                svg.push_str(&format!(
                    "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"{}\" points=\"{}\"/>\n",
                    if i == 0 { 1.8 } else { 1.0 },
                    path.join(" ")
                ));
            }
            CurveStyle::LogStems => {
                let base = sy(0.0_f64.max(y_lo));
                for &(x, y) in finite {
                    svg.push_str(&format!(
                        "<line x1=\"{0:.2}\" y1=\"{base:.2}\" x2=\"{0:.2}\" y2=\"{1:.2}\" stroke=\"{colour}\"/>\n",
                        sx(x),
                        sy(y)
                    ));
                }
            }
        }
    }
    // Legend: one row between the title and the plot, clear of the data.
    if curve.series.len() > 1 {
        let mut x = LEFT;
        for (i, series) in curve.series.iter().enumerate() {
            let y = TOP - 14.0;
            svg.push_str(&format!(
                "<line x1=\"{x:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"{}\" stroke-width=\"2.5\"/>\n<text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n",
                x + 22.0,
                COLOURS[i % COLOURS.len()],
                x + 28.0,
                y + 4.0,
                escape(&series.label)
            ));
            x += 48.0 + 7.0 * series.label.chars().count() as f64;
        }
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;
    use rvtol_models::Series;

    fn curve(style: CurveStyle, series: Vec<Series>) -> Curve {
        Curve {
            name: "c".into(),
            title: "T <1>".into(),
            x_label: "x (deg)".into(),
            y_label: "y, arcsec".into(),
            style,
            series,
        }
    }

    #[test]
    fn csv_shares_the_x_column_when_it_can() {
        let a = Series {
            label: "a".into(),
            points: vec![(0.0, 1.0), (1.0, 2.0)],
        };
        let b = Series {
            label: "b".into(),
            points: vec![(0.0, 3.0), (1.0, 4.0)],
        };
        let csv = to_csv(&curve(CurveStyle::Lines, vec![a.clone(), b]));
        assert_eq!(
            csv,
            "x (deg),\"a – y, arcsec\",\"b – y, arcsec\"\n0,1,3\n1,2,4\n"
        );
        let c = Series {
            label: "c".into(),
            points: vec![(5.0, 6.0)],
        };
        let csv = to_csv(&curve(CurveStyle::Lines, vec![a, c]));
        assert_eq!(csv.lines().nth(2).unwrap(), "1,2,,");
    }

    #[test]
    fn svg_is_well_formed_and_escapes_text() {
        let s = Series {
            label: "s".into(),
            points: (1..100).map(|k| (k as f64, 1.0 / k as f64)).collect(),
        };
        for style in [CurveStyle::Lines, CurveStyle::LogStems] {
            let svg = to_svg(&curve(style, vec![s.clone()]));
            assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
            assert!(svg.contains("T &lt;1&gt;"));
            assert!(!svg.contains("NaN") && !svg.contains("inf"));
        }
    }

    #[test]
    fn ticks_are_round_numbers_inside_the_range() {
        assert_eq!(
            nice_ticks(0.0, 360.0, 8),
            vec![0.0, 50.0, 100.0, 150.0, 200.0, 250.0, 300.0, 350.0]
        );
        let ticks = nice_ticks(-0.37, 0.81, 6);
        assert!(ticks.iter().all(|t| (-0.37..=0.81).contains(t)));
        assert!(ticks.len() >= 4);
    }
}
