//! The charts of the report, drawn with `plotters` into SVG strings: a histogram against
//! spec limits with percentile markers, a normal probability plot, grouped horizontal bars
//! with interval whiskers (tornado and Pareto charts), and the models' curves (a dense
//! trace as its envelope, a spectrum as stems on a logarithmic order
//! axis). Text is SVG `<text>`, laid out by the browser; no font files are read.
//!
//! Every function checks its ranges before drawing, so a chart never carries a NaN or an
//! infinite coordinate: non-finite points are left out, and a degenerate range is widened.

use std::ops::Range;

use plotters::chart::MeshStyle;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rvtol_models::{Curve, CurveStyle};
use statrs::distribution::{ContinuousCDF, Normal};

/// Chart size in pixels (the page scales it to its column).
pub const WIDTH: u32 = 620;
const HEIGHT: u32 = 360;
const FONT: &str = "sans-serif";

/// Series colours: blue, red, green, purple, orange, cyan.
pub const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 78, 121),
    RGBColor(192, 80, 77),
    RGBColor(79, 138, 60),
    RGBColor(128, 100, 162),
    RGBColor(217, 130, 43),
    RGBColor(75, 172, 198),
];
const LIMIT: RGBColor = RGBColor(200, 30, 30);
const MARKER: RGBColor = RGBColor(40, 40, 40);
const GRID: RGBColor = RGBColor(225, 225, 225);

/// A drawing failure (plotters' error as text).
#[derive(Debug)]
pub struct ChartError(pub String);

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for ChartError {
    fn from(err: DrawingAreaErrorKind<E>) -> Self {
        ChartError(err.to_string())
    }
}

type Drawn = Result<String, ChartError>;

/// Spec limits of an output.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    /// Lower spec limit.
    pub lower: Option<f64>,
    /// Upper spec limit.
    pub upper: Option<f64>,
}

impl Limits {
    fn each(&self) -> impl Iterator<Item = (&'static str, f64)> {
        [("LSL", self.lower), ("USL", self.upper)]
            .into_iter()
            .filter_map(|(name, v)| v.filter(|v| v.is_finite()).map(|v| (name, v)))
    }
}

/// A percentile marker: its probability (%), value and 95 % interval (an open end is
/// `None`: beyond the sample's extreme).
#[derive(Debug, Clone)]
pub struct Marker {
    /// Probability, %.
    pub percent: f64,
    /// The percentile.
    pub value: f64,
    /// Its 95 % interval (an open end: beyond the sample's extreme).
    pub interval: (Option<f64>, Option<f64>),
}

impl Marker {
    fn label(&self) -> String {
        format!("P{}", trim(self.percent))
    }
}

/// A probability level as written: 0.0032, 0.135, 50, 99.9968.
fn trim_percent(v: f64) -> String {
    if !(0.01..=99.99).contains(&v) {
        format!("{v:.4}")
    } else {
        trim(v)
    }
}

fn trim(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// A short tick label: up to 4 significant digits, no trailing zeros.
pub fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-4..6).contains(&magnitude) {
        return format!("{v:.2e}");
    }
    let decimals = (3 - magnitude).clamp(0, 8) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Tick labels for an axis over [lo, hi] with about `labels` labels: [`tick`]'s four
/// significant digits, or as many decimals as the step between labels needs where those
/// would print one label for all (an output that spans 0.026330 to 0.026334 read
/// "0.02633" at every tick).
pub fn axis_ticks(lo: f64, hi: f64, labels: usize) -> impl Fn(&f64) -> String {
    let step = (hi - lo).abs() / labels.max(1) as f64;
    let magnitude = lo.abs().max(hi.abs()).log10().floor() as i32;
    let fine = step > 0.0 && step.is_finite() && step < 10f64.powi(magnitude - 3);
    let decimals = if fine {
        (1 - step.log10().floor() as i32).clamp(0, 12) as usize
    } else {
        0
    };
    move |v: &f64| {
        if fine {
            let s = format!("{v:.decimals$}");
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            tick(*v)
        }
    }
}

/// [lo, hi] widened to a non-empty finite range with a margin of `pad` of its width.
fn padded(lo: f64, hi: f64, pad: f64) -> (f64, f64) {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() && hi >= lo {
        (lo, hi)
    } else {
        (0.0, 1.0)
    };
    let width = hi - lo;
    if width > 1e-12 * lo.abs().max(hi.abs()) && width > 0.0 {
        (lo - pad * width, hi + pad * width)
    } else {
        let half = (lo.abs() * 0.05).max(1e-9);
        (lo - half, hi + half)
    }
}

fn text(size: u32) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font())
}

fn anchored(size: u32, h: HPos, v: VPos) -> TextStyle<'static> {
    text(size).pos(Pos::new(h, v))
}

/// The mesh of a chart in the page's style (light grid at the major ticks only, 12 px
/// labels, 13 px axis descriptions), for the caller to add its labels and draw.
fn mesh<'a, 'b, DB, X, Y>(
    chart: &'b mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
) -> MeshStyle<'a, 'b, X, Y, DB>
where
    DB: DrawingBackend,
    X: Ranged + ValueFormatter<<X as Ranged>::ValueType>,
    Y: Ranged + ValueFormatter<<Y as Ranged>::ValueType>,
{
    let mut style = chart.configure_mesh();
    style
        .light_line_style(TRANSPARENT)
        .bold_line_style(GRID)
        .label_style(text(12))
        .axis_desc_style(text(13));
    style
}

/// The legend of a chart in the page's style, at `position`, labels of `size` px.
fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    size: u32,
) -> Result<(), ChartError>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.9))
        .border_style(GRID)
        .label_font(text(size))
        .draw()?;
    Ok(())
}

/// A new SVG drawing of `height` pixels into `out`, white.
fn canvas(out: &mut String, height: u32) -> Result<DrawingArea<SVGBackend<'_>, Shift>, ChartError> {
    let root = SVGBackend::with_string(out, (WIDTH, height)).into_drawing_area();
    root.fill(&WHITE)?;
    Ok(root)
}

/// Histogram of a run's output (bins from the report) against its spec limits, with the
/// P0.135, P50 and P99.865 markers and their 95 % intervals as shaded bands.
#[allow(clippy::too_many_arguments)]
pub fn histogram(
    title: &str,
    x_label: &str,
    lower_edge: f64,
    bin_width: f64,
    counts: &[u64],
    flagged: Option<&[u64]>,
    corner: Option<&str>,
    limits: Limits,
    markers: &[Marker],
) -> Drawn {
    let upper_edge = lower_edge + bin_width * counts.len() as f64;
    let data = (lower_edge, upper_edge);
    // A limit joins the axis when it lies within one data width of the data; a farther
    // one is named in the corner instead.
    let reach = (upper_edge - lower_edge).max(bin_width);
    let near = |v: f64| v >= data.0 - reach && v <= data.1 + reach;
    let mut lo = data.0;
    let mut hi = data.1;
    for (_, v) in limits.each().filter(|(_, v)| near(*v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let (x0, x1) = padded(lo, hi, 0.04);
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.18;
    let mut out = String::new();
    {
        let root = canvas(&mut out, HEIGHT)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, text(15))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(62)
            .build_cartesian_2d(x0..x1, 0.0..top)?;
        mesh(&mut chart)
            .disable_x_mesh()
            .x_desc(x_label)
            .y_desc("samples per bin")
            .x_labels(8)
            .y_labels(6)
            .x_label_formatter(&axis_ticks(x0, x1, 8))
            .y_label_formatter(&|v| tick(*v))
            .draw()?;
        // Interval bands first, under the bars; a percentile beyond the limits (its value
        // infinite, its interval unknown) has no band: shading its open interval would
        // cover the whole axis.
        for marker in markers.iter().filter(|m| m.value.is_finite()) {
            let (a, b) = (
                marker.interval.0.unwrap_or(data.0).max(x0),
                marker.interval.1.unwrap_or(data.1).min(x1),
            );
            if a.is_finite() && b.is_finite() && b > a {
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(a, 0.0), (b, top)],
                    MARKER.mix(0.10).filled(),
                )))?;
            }
        }
        // The flagged samples of a bin (their values stand, the assemblies do not conform)
        // stacked on its other samples, in their own colour.
        let flagged_of = |i: usize| flagged.and_then(|f| f.get(i)).copied().unwrap_or(0);
        let bars = COLOURS[0];
        chart
            .draw_series(
                counts
                    .iter()
                    .enumerate()
                    .filter(|&(i, &c)| c > flagged_of(i))
                    .map(|(i, &c)| {
                        let left = lower_edge + bin_width * i as f64;
                        Rectangle::new(
                            [(left, 0.0), (left + bin_width, (c - flagged_of(i)) as f64)],
                            bars.mix(0.75).filled(),
                        )
                    }),
            )?
            .label(if flagged.is_some() {
                "conforming by their flags"
            } else {
                "samples"
            })
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 14, y + 5)], bars.mix(0.75).filled())
            });
        if flagged.is_some() {
            let orange = COLOURS[4];
            chart
                .draw_series(
                    counts
                        .iter()
                        .enumerate()
                        .filter(|&(i, _)| flagged_of(i) > 0)
                        .map(|(i, &c)| {
                            let left = lower_edge + bin_width * i as f64;
                            Rectangle::new(
                                [
                                    (left, (c - flagged_of(i)) as f64),
                                    (left + bin_width, c as f64),
                                ],
                                orange.mix(0.85).filled(),
                            )
                        }),
                )?
                .label("flagged non-conforming")
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 14, y + 5)], orange.mix(0.85).filled())
                });
        }
        for (k, marker) in markers.iter().enumerate() {
            if !marker.value.is_finite() {
                continue;
            }
            let series = chart.draw_series(DashedLineSeries::new(
                [(marker.value, 0.0), (marker.value, top * 0.88)],
                5,
                3,
                MARKER.stroke_width(1),
            ))?;
            if k == 0 {
                series.label("percentile, 95 % CI shaded").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 14, y)], MARKER.stroke_width(1))
                });
            }
            // Alternate heights, so that neighbouring labels do not overlap.
            let height = if k % 2 == 0 { 0.985 } else { 0.94 };
            chart.draw_series(std::iter::once(Text::new(
                marker.label(),
                (marker.value, top * height),
                anchored(11, HPos::Center, VPos::Top),
            )))?;
        }
        let mut far = Vec::new();
        let mut first_limit = true;
        for (name, v) in limits.each() {
            if !near(v) {
                far.push(format!("{name} {} (off the axis)", tick(v)));
                continue;
            }
            let series =
                chart.draw_series(LineSeries::new([(v, 0.0), (v, top)], LIMIT.stroke_width(2)))?;
            if first_limit {
                series.label("spec limit").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 14, y)], LIMIT.stroke_width(2))
                });
                first_limit = false;
            }
            chart.draw_series(std::iter::once(Text::new(
                format!("{name} {}", tick(v)),
                (v, top * 0.80),
                anchored(12, HPos::Center, VPos::Bottom).color(&LIMIT),
            )))?;
        }
        // No legend: the labels on the lines and the caption say what they are, and a
        // legend box would cover a tail.
        if let Some(corner) = corner {
            let (xs, ys) = chart.plotting_area().get_pixel_range();
            root.draw(&Text::new(
                corner.to_string(),
                (xs.end - 6, ys.start + 4),
                anchored(12, HPos::Right, VPos::Top).color(&COLOURS[4].mix(1.0)),
            ))?;
        }
        if !far.is_empty() {
            let (xs, ys) = chart.plotting_area().get_pixel_range();
            root.draw(&Text::new(
                far.join(", "),
                (xs.start + 6, ys.end - 8),
                anchored(12, HPos::Left, VPos::Bottom).color(&LIMIT),
            ))?;
        }
        root.present()?;
    }
    Ok(out)
}

/// z = Φ⁻¹(p) of the standard normal.
fn probit(p: f64) -> f64 {
    Normal::standard().inverse_cdf(p)
}

/// Horizontal probability grid (normal scale) with labels in percent, drawn on the
/// plotting area of `chart` and labelled on `root`.
fn probability_grid<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    x: (f64, f64),
    z: (f64, f64),
) -> Result<(), ChartError>
where
    DB::ErrorType: 'static,
{
    // The ±kσ levels of a normal distribution, k = 0..4: one label per unit of z.
    let levels = [
        0.003167, 0.135, 2.275, 15.866, 50.0, 84.134, 97.725, 99.865, 99.996833,
    ];
    for percent in levels {
        let level = probit(percent / 100.0);
        if level < z.0 || level > z.1 {
            continue;
        }
        chart.draw_series(LineSeries::new([(x.0, level), (x.1, level)], GRID))?;
        let (px, py) = chart.backend_coord(&(x.0, level));
        root.draw(&Text::new(
            format!("{} %", trim_percent(percent)),
            (px - 6, py),
            anchored(11, HPos::Right, VPos::Center),
        ))?;
    }
    Ok(())
}

/// A target on a probability plot: the value a percentile must not pass, drawn as a
/// vertical line, and the percentile's level (%) as a horizontal one.
pub struct Target {
    /// The limit on the value.
    pub value: f64,
    /// The targeted percentile, %, when the target is one.
    pub percent: Option<f64>,
    /// Legend text.
    pub label: String,
}

/// One line of a probability plot: points (x, cumulative fraction).
pub struct Cumulative {
    /// Legend text.
    pub label: String,
    /// (x, cumulative fraction in (0, 1)); other fractions are not drawn.
    pub points: Vec<(f64, f64)>,
}

/// Normal probability plot: the cumulative distributions as lines on a probit scale (a
/// normal output is a straight line; the tails, where the spec limits bite, are spread
/// out), the percentile markers with their 95 % intervals as horizontal whiskers, the
/// spec limits and an optional target line.
pub fn probability_plot(
    title: &str,
    x_label: &str,
    lines: &[Cumulative],
    markers: &[Marker],
    limits: Limits,
    target: Option<Target>,
) -> Drawn {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1 > 0.0 && p.1 < 1.0;
    let mut x_lo = f64::INFINITY;
    let mut x_hi = f64::NEG_INFINITY;
    let mut z_lo: f64 = -3.2;
    let mut z_hi: f64 = 3.2;
    for line in lines {
        for p in line.points.iter().filter(|p| finite(p)) {
            x_lo = x_lo.min(p.0);
            x_hi = x_hi.max(p.0);
            let z = probit(p.1).clamp(-5.0, 5.0);
            z_lo = z_lo.min(z);
            z_hi = z_hi.max(z);
        }
    }
    for m in markers.iter().filter(|m| m.value.is_finite()) {
        x_lo = x_lo.min(m.value);
        x_hi = x_hi.max(m.value);
    }
    let data_width = (x_hi - x_lo).max(0.0);
    let (data_lo, data_hi) = (x_lo, x_hi);
    let near = |v: f64| v >= data_lo - data_width && v <= data_hi + data_width;
    for (_, v) in limits.each().filter(|(_, v)| near(*v)) {
        x_lo = x_lo.min(v);
        x_hi = x_hi.max(v);
    }
    if let Some(Target { value: v, .. }) = &target {
        if v.is_finite() && near(*v) {
            x_lo = x_lo.min(*v);
            x_hi = x_hi.max(*v);
        }
    }
    let (x0, x1) = padded(x_lo, x_hi, 0.04);
    let (z0, z1) = (z_lo - 0.25, z_hi + 0.25);
    let mut out = String::new();
    {
        let root = canvas(&mut out, HEIGHT)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, text(15))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, z0..z1)?;
        mesh(&mut chart)
            .disable_y_mesh()
            .y_labels(0)
            .x_labels(8)
            .x_desc(x_label)
            .y_desc("cumulative probability (normal scale)")
            .x_label_formatter(&axis_ticks(x0, x1, 8))
            .draw()?;
        probability_grid(&root, &mut chart, (x0, x1), (z0, z1))?;
        for (i, line) in lines.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let points: Vec<(f64, f64)> = line
                .points
                .iter()
                .filter(|p| finite(p))
                .map(|&(x, p)| (x, probit(p)))
                .filter(|&(_, z)| z >= z0 && z <= z1)
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
                .label(line.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 14, y)], colour.stroke_width(2))
                });
            if points.len() <= 60 {
                chart.draw_series(points.iter().map(|&p| Circle::new(p, 2, colour.filled())))?;
            }
        }
        let mut labelled = false;
        for m in markers.iter().filter(|m| m.value.is_finite()) {
            let z = probit(m.percent / 100.0);
            if z < z0 || z > z1 {
                continue;
            }
            let (a, b) = (
                m.interval.0.unwrap_or(x0).max(x0),
                m.interval.1.unwrap_or(x1).min(x1),
            );
            if a.is_finite() && b.is_finite() && b >= a {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(a, z), (b, z)],
                    MARKER.stroke_width(2),
                )))?;
                for end in [a, b] {
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(end, z - 0.08), (end, z + 0.08)],
                        MARKER.stroke_width(2),
                    )))?;
                }
            }
            let series = chart.draw_series(std::iter::once(Circle::new(
                (m.value, z),
                4,
                MARKER.filled(),
            )))?;
            if !labelled {
                series
                    .label("percentile with its 95 % CI")
                    .legend(|(x, y)| Circle::new((x + 7, y), 4, MARKER.filled()));
                labelled = true;
            }
        }
        let mut first_limit = true;
        for (name, v) in limits.each().filter(|(_, v)| *v >= x0 && *v <= x1) {
            let series =
                chart.draw_series(LineSeries::new([(v, z0), (v, z1)], LIMIT.stroke_width(2)))?;
            if first_limit {
                series.label("spec limit").legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 14, y)], LIMIT.stroke_width(2))
                });
                first_limit = false;
            }
            chart.draw_series(std::iter::once(Text::new(
                format!("{name} {}", tick(v)),
                (v, z1),
                anchored(12, HPos::Center, VPos::Top).color(&LIMIT),
            )))?;
        }
        if let Some(target) = target.filter(|t| t.value >= x0 && t.value <= x1) {
            let v = target.value;
            chart
                .draw_series(DashedLineSeries::new(
                    [(v, z0), (v, z1)],
                    6,
                    4,
                    MARKER.stroke_width(2),
                ))?
                .label(target.label)
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 14, y)], MARKER.stroke_width(2))
                });
            // The targeted percentile's level, up to the limit.
            let level = target.percent.map(|p| probit(p / 100.0));
            if let Some(z) = level.filter(|z| *z > z0 && *z < z1) {
                chart.draw_series(DashedLineSeries::new(
                    [(x0, z), (v, z)],
                    6,
                    4,
                    MARKER.stroke_width(1),
                ))?;
            }
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight, 12)?;
        root.present()?;
    }
    Ok(out)
}

/// One category of a horizontal bar chart: its name and one value per series, each with
/// an optional 95 % interval.
pub struct BarRow {
    /// Category name, left of its bars.
    pub name: String,
    /// Per series: the bar's value and its interval.
    pub values: Vec<(f64, Option<(f64, f64)>)>,
}

/// Grouped horizontal bars, one row per category from the top, one bar per series with its
/// interval as a whisker (a tornado chart when the rows are sorted by size).
pub fn horizontal_bars(title: &str, x_label: &str, series: &[&str], rows: &[BarRow]) -> Drawn {
    let finite = |v: f64| v.is_finite();
    let mut lo: f64 = 0.0;
    let mut hi: f64 = 0.0;
    for row in rows {
        for &(v, ci) in &row.values {
            for x in [Some(v), ci.map(|c| c.0), ci.map(|c| c.1)]
                .into_iter()
                .flatten()
            {
                if finite(x) {
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
        }
    }
    let (x0, x1) = padded(lo, hi, 0.03);
    let name_width = rows
        .iter()
        .map(|r| r.name.chars().count())
        .max()
        .unwrap_or(4) as u32
        * 7
        + 16;
    // Below the rows, a free band for the legend (one row's height per series, when there
    // are several), so that it never covers a bar.
    let legend_rows = if series.len() > 1 {
        series.len() as f64 * 0.9
    } else {
        0.0
    };
    let height = (110 + (26.0 * (rows.len().max(1) as f64 + legend_rows)) as u32).max(180);
    let n = rows.len().max(1) as f64;
    let mut out = String::new();
    {
        let root = canvas(&mut out, height)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, text(15))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(name_width.min(WIDTH / 2))
            .build_cartesian_2d(x0..x1, -legend_rows..n)?;
        mesh(&mut chart)
            .disable_y_mesh()
            .y_labels(0)
            .x_labels(8)
            .x_desc(x_label)
            .x_label_formatter(&|v| tick(*v))
            .draw()?;
        let k = series.len().max(1) as f64;
        let thickness = 0.8 / k;
        for (s, label) in series.iter().enumerate() {
            let colour = COLOURS[s % COLOURS.len()];
            let bars = rows.iter().enumerate().filter_map(|(i, row)| {
                let (v, _) = *row.values.get(s)?;
                finite(v).then(|| {
                    let top = n - i as f64 - 0.1 - thickness * s as f64;
                    Rectangle::new([(0.0, top - thickness), (v, top)], colour.mix(0.8).filled())
                })
            });
            chart
                .draw_series(bars)?
                .label(label.to_string())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.mix(0.8).filled())
                });
            for (i, row) in rows.iter().enumerate() {
                let Some(&(_, Some((a, b)))) = row.values.get(s) else {
                    continue;
                };
                if !(finite(a) && finite(b)) {
                    continue;
                }
                let middle = n - i as f64 - 0.1 - thickness * (s as f64 + 0.5);
                let tick_half = thickness * 0.3;
                for path in [
                    vec![(a, middle), (b, middle)],
                    vec![(a, middle - tick_half), (a, middle + tick_half)],
                    vec![(b, middle - tick_half), (b, middle + tick_half)],
                ] {
                    chart.draw_series(std::iter::once(PathElement::new(
                        path,
                        MARKER.stroke_width(1),
                    )))?;
                }
            }
        }
        chart.draw_series(LineSeries::new(
            [(0.0, 0.0), (0.0, n)],
            MARKER.stroke_width(1),
        ))?;
        for (i, row) in rows.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(x0, n - i as f64 - 0.5));
            root.draw(&Text::new(
                row.name.clone(),
                (px - 8, py),
                anchored(12, HPos::Right, VPos::Center),
            ))?;
        }
        if series.len() > 1 {
            legend(&mut chart, SeriesLabelPosition::LowerRight, 12)?;
        }
        root.present()?;
    }
    Ok(out)
}

/// Points of a series that can be drawn (finite; x > 0 on a logarithmic axis).
fn drawable(points: &[(f64, f64)], log_x: bool) -> Vec<(f64, f64)> {
    points
        .iter()
        .copied()
        .filter(|&(x, y)| x.is_finite() && y.is_finite() && (!log_x || x > 0.0))
        .collect()
}

/// Points per series above which a line is drawn as its envelope (the band between the
/// least and greatest value in each of [`ENVELOPE_BINS`] slices of x), which a dense,
/// fast-varying trace needs: drawn point to point it fills a band with moiré.
pub const DENSE: usize = 1200;
const ENVELOPE_BINS: usize = 360;

/// (x, min, max) per slice of [x0, x1].
fn envelope(points: &[(f64, f64)], x0: f64, x1: f64) -> Vec<(f64, f64, f64)> {
    let mut bins = vec![(f64::INFINITY, f64::NEG_INFINITY); ENVELOPE_BINS];
    let width = (x1 - x0) / ENVELOPE_BINS as f64;
    for &(x, y) in points {
        let k = (((x - x0) / width) as usize).min(ENVELOPE_BINS - 1);
        bins[k].0 = bins[k].0.min(y);
        bins[k].1 = bins[k].1.max(y);
    }
    bins.into_iter()
        .enumerate()
        .filter(|(_, (lo, hi))| lo <= hi)
        .map(|(k, (lo, hi))| (x0 + width * (k as f64 + 0.5), lo, hi))
        .collect()
}

/// A model curve: lines (an envelope band when dense, see [`DENSE`]) or stems on a
/// logarithmic x axis (a spectrum, its largest peaks labelled).
pub fn curve(curve: &Curve) -> Drawn {
    let log_x = curve.style == CurveStyle::LogStems;
    let series: Vec<Vec<(f64, f64)>> = curve
        .series
        .iter()
        .map(|s| drawable(&s.points, log_x))
        .collect();
    let all = series.iter().flatten();
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in all {
        x_lo = x_lo.min(x);
        x_hi = x_hi.max(x);
        y_lo = y_lo.min(y);
        y_hi = y_hi.max(y);
    }
    if log_x {
        y_lo = y_lo.min(0.0);
    }
    let (y0, y1) = padded(y_lo, y_hi, 0.06);
    let y0 = if log_x { 0.0f64.max(y0).min(y_lo) } else { y0 };
    // Room above the data for the legend, one line per series (one series has none: the
    // page's caption names it), and for the labels of a spectrum's peaks.
    let with_legend = curve.series.len() > 1;
    let room = if with_legend {
        0.07 * curve.series.len() as f64
    } else {
        0.0
    } + if log_x { 0.08 } else { 0.0 };
    let y1 = y1 + (y1 - y0) * room;
    // A tick within rounding of zero reads 0, not 5.55e-17.
    let zero = (y1 - y0) * 1e-9;
    let y_tick = move |v: &f64| tick(if v.abs() < zero { 0.0 } else { *v });
    let title = curve.title.clone();
    let mut out = String::new();
    let mut sub_pixel = SubPixelLines::default();
    {
        let root = canvas(&mut out, HEIGHT)?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(title, text(15))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(66);
        let colour_of = |i: usize| COLOURS[i % COLOURS.len()];
        if log_x {
            let (x0, x1) = if x_lo.is_finite() && x_hi > x_lo {
                (x_lo * 0.8, x_hi * 1.25)
            } else {
                (0.8, 10.0)
            };
            let mut chart = builder.build_cartesian_2d((x0..x1).log_scale(), y0..y1)?;
            mesh(&mut chart)
                .x_desc(curve.x_label.as_str())
                .y_desc(curve.y_label.as_str())
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&y_tick)
                .draw()?;
            for (i, points) in series.iter().enumerate() {
                let colour = colour_of(i);
                chart
                    .draw_series(points.iter().map(|&(x, y)| {
                        PathElement::new(vec![(x, 0.0f64.max(y0)), (x, y)], colour.stroke_width(1))
                    }))?
                    .label(curve.series[i].label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 14, y)], colour.stroke_width(2))
                    });
                // The largest peaks labelled with their order: those above 5 % of the
                // largest, at most 6, none within 8 % of a labelled order.
                let mut peaks = points.clone();
                peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
                let largest = peaks.first().map_or(0.0, |p| p.1);
                let mut labelled: Vec<f64> = Vec::new();
                for &(x, y) in &peaks {
                    if labelled.len() == 6 || y <= 0.05 * largest || y <= 0.0 {
                        break;
                    }
                    if labelled.iter().any(|&l| (x / l).ln().abs() < 0.08) {
                        continue;
                    }
                    labelled.push(x);
                    chart.draw_series(std::iter::once(Text::new(
                        tick(x),
                        (x, y),
                        anchored(11, HPos::Center, VPos::Bottom).color(&colour),
                    )))?;
                }
            }
            if with_legend {
                legend(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
            }
        } else {
            let (x0, x1) = if x_lo.is_finite() && x_hi > x_lo {
                (x_lo, x_hi)
            } else {
                padded(x_lo, x_hi, 0.05)
            };
            let mut chart = builder.build_cartesian_2d(x0..x1, y0..y1)?;
            mesh(&mut chart)
                .x_desc(curve.x_label.as_str())
                .y_desc(curve.y_label.as_str())
                .x_labels(10)
                .x_label_formatter(&axis_ticks(x0, x1, 10))
                .y_label_formatter(&y_tick)
                .draw()?;
            if y0 < 0.0 && y1 > 0.0 {
                chart.draw_series(LineSeries::new(
                    [(x0, 0.0), (x1, 0.0)],
                    RGBColor(150, 150, 150),
                ))?;
            }
            for (i, points) in series.iter().enumerate() {
                let colour = colour_of(i);
                let width = if i == 0 { 2 } else { 1 };
                if points.len() > DENSE {
                    let band = envelope(points, x0, x1);
                    let outline: Vec<(f64, f64)> = band
                        .iter()
                        .map(|&(x, _, hi)| (x, hi))
                        .chain(band.iter().rev().map(|&(x, lo, _)| (x, lo)))
                        .collect();
                    chart
                        .draw_series(std::iter::once(Polygon::new(
                            outline,
                            colour.mix(0.35).filled(),
                        )))?
                        .label(format!("{} (band)", curve.series[i].label))
                        .legend(move |(x, y)| {
                            Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.mix(0.35).filled())
                        });
                    for edge in [1usize, 2] {
                        chart.draw_series(LineSeries::new(
                            band.iter()
                                .map(|&(x, lo, hi)| (x, if edge == 1 { lo } else { hi })),
                            colour.stroke_width(1),
                        ))?;
                    }
                } else {
                    // Drawn in a marker colour and given its sub-pixel points afterwards
                    // (`SubPixelLines`): the SVG backend rounds every point to a whole
                    // pixel, which makes a shallow line a staircase.
                    chart
                        .draw_series(LineSeries::new(
                            points.iter().copied(),
                            sub_pixel.marker(i).stroke_width(width),
                        ))?
                        .label(curve.series[i].label.clone())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 14, y)], colour.stroke_width(2))
                        });
                    let pixels = chart.plotting_area().get_pixel_range();
                    sub_pixel.add(i, colour, points, pixels, (x0..x1, y0..y1));
                }
            }
            if with_legend {
                legend(&mut chart, SeriesLabelPosition::UpperRight, 11)?;
            }
        }
        root.present()?;
    }
    Ok(sub_pixel.apply(out))
}

/// The model curves' lines at sub-pixel precision. The SVG backend writes whole-pixel
/// points, so a line of small slope is drawn as a staircase one pixel high; each such
/// line is drawn in a marker colour of its own (never a series colour) and its
/// `<polyline>` then gets the points at a tenth of a pixel and its true colour. The
/// points are mapped as the chart maps them (its plotting area's pixel range, the y axis
/// reversed), without the rounding.
#[derive(Default)]
struct SubPixelLines {
    /// (marker colour, true colour, points) per line.
    lines: Vec<(String, String, String)>,
}

impl SubPixelLines {
    /// The marker colour of line `i`.
    fn marker(&self, i: usize) -> RGBColor {
        RGBColor(1, 2, 3 + (i % 250) as u8)
    }

    /// Line `i` of `colour` through `points` on a plotting area of the pixels `(px, py)`
    /// showing the values `(x, y)`.
    fn add(
        &mut self,
        i: usize,
        colour: RGBColor,
        points: &[(f64, f64)],
        (px, py): (Range<i32>, Range<i32>),
        (x, y): (Range<f64>, Range<f64>),
    ) {
        // The chart's own pixel ends: x from left to right − 1, y from bottom − 1 up to top.
        let (left, right) = (px.start as f64, (px.end - 1) as f64);
        let (bottom, top) = ((py.end - 1) as f64, py.start as f64);
        let at = |v: f64, r: &Range<f64>, a: f64, b: f64| {
            a + (b - a) * (v - r.start) / (r.end - r.start)
        };
        let mut text = String::new();
        for &(u, v) in points {
            let (sx, sy) = (at(u, &x, left, right), at(v, &y, bottom, top));
            if sx.is_finite() && sy.is_finite() {
                text.push_str(&format!("{sx:.1},{sy:.1} "));
            }
        }
        let hex = |c: RGBColor| format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2);
        self.lines.push((hex(self.marker(i)), hex(colour), text));
    }

    /// The drawing `svg` with each marked line's points and colour put right.
    fn apply(&self, mut svg: String) -> String {
        for (marker, colour, points) in &self.lines {
            let Some(at) = svg.find(&format!("stroke=\"{marker}\"")) else {
                continue;
            };
            let start = svg[..at].rfind('<').unwrap_or(at);
            let end = at + svg[at..].find("/>").unwrap_or(svg.len() - at);
            let element = svg[start..end]
                .replace(marker.as_str(), colour)
                .split(" points=\"")
                .next()
                .unwrap_or_default()
                .to_string();
            svg.replace_range(start..end, &format!("{element} points=\"{points}\""));
        }
        svg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(1.5), "1.5");
        assert_eq!(tick(250.0), "250");
        assert_eq!(tick(0.000123456), "0.0001235");
        assert_eq!(tick(1234567.0), "1.23e6");
        // An axis narrower than the fourth digit gets the digits that tell its ticks apart.
        let narrow = axis_ticks(0.026330, 0.026334, 8);
        assert_eq!(narrow(&0.026330), "0.02633");
        assert_eq!(narrow(&0.0263305), "0.0263305");
        assert_eq!(axis_ticks(0.0, 2.0, 8)(&0.25), "0.25");
    }

    #[test]
    fn degenerate_ranges_are_widened() {
        let (a, b) = padded(1.0, 1.0, 0.05);
        assert!(a < 1.0 && b > 1.0);
        let (a, b) = padded(f64::NAN, 2.0, 0.05);
        assert!(a.is_finite() && b > a);
    }

    #[test]
    fn a_histogram_draws_its_limits_and_markers_and_no_non_finite_number() {
        let svg = histogram(
            "t",
            "x (mm)",
            0.0,
            0.1,
            &[1, 5, 9, 5, 1],
            Some(&[0, 0, 2, 5, 1]),
            Some("out of spec 12 %"),
            Limits {
                lower: Some(0.05),
                upper: Some(f64::NAN),
            },
            &[Marker {
                percent: 50.0,
                value: 0.25,
                interval: (Some(0.2), None),
            }],
        )
        .unwrap();
        assert!(svg.contains("LSL 0.05") && svg.contains("P50"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        // The flagged counts stack on the other samples in their own colour (COLOURS[4]:
        // one bar per bin that holds any, 3, and the corner note in it).
        assert_eq!(svg.matches("fill=\"#D9822B\"").count(), 3 + 1, "{svg}");
        assert!(svg.contains("out of spec 12 %"));
    }

    #[test]
    fn a_percentile_beyond_the_limits_shades_nothing() {
        // P99.865 read beyond the limits (flagged samples in the tail): value +inf, no
        // interval. The page once shaded its open interval over the whole axis.
        let draw = |markers: &[Marker]| {
            let limits = Limits {
                lower: None,
                upper: Some(0.3),
            };
            histogram(
                "t",
                "x",
                0.0,
                0.1,
                &[1, 5, 9, 5, 1],
                None,
                None,
                limits,
                markers,
            )
            .unwrap()
        };
        let median = Marker {
            percent: 50.0,
            value: 0.25,
            interval: (Some(0.2), Some(0.3)),
        };
        let beyond = Marker {
            percent: 99.865,
            value: f64::INFINITY,
            interval: (None, None),
        };
        assert_eq!(draw(&[median.clone(), beyond]), draw(&[median]));
    }

    #[test]
    fn a_shallow_line_is_drawn_at_sub_pixel_points_in_its_own_colour() {
        // 0.2 arcmin over 10 N·m on a 360 px chart: whole-pixel points made it a staircase.
        let points: Vec<(f64, f64)> = (0..=50)
            .map(|k| (-5.0 + 0.2 * k as f64, -0.1 + 0.004 * k as f64))
            .collect();
        let mut shifted = points.clone();
        shifted.iter_mut().for_each(|p| p.1 += 0.05);
        let drawn = curve(&Curve {
            name: "line".into(),
            title: "a line".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            style: CurveStyle::Lines,
            series: vec![
                rvtol_models::Series {
                    label: "one".into(),
                    points,
                },
                rvtol_models::Series {
                    label: "two".into(),
                    points: shifted,
                },
            ],
        })
        .unwrap();
        assert!(!drawn.contains("#010203") && !drawn.contains("#010204"));
        for colour in ["#1F4E79", "#C0504D"] {
            let at = drawn.find(&format!("stroke=\"{colour}\"")).unwrap();
            let points = &drawn[at..];
            let points = &points[points.find("points=\"").unwrap() + 8..];
            let points: Vec<(f64, f64)> = points[..points.find('"').unwrap()]
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            assert_eq!(points.len(), 51, "{colour}");
            assert!(points.iter().any(|p| p.1.fract() != 0.0), "{colour}");
            // On one straight line, to the tenth of a pixel they are written with.
            let (a, b) = (points[0], points[50]);
            for p in &points {
                let on = a.1 + (b.1 - a.1) * (p.0 - a.0) / (b.0 - a.0);
                assert!(
                    (p.1 - on).abs() <= 0.1,
                    "{colour}: {p:?} off the line by {}",
                    p.1 - on
                );
            }
            // The line ends at the plotting area's ends (x from its first to last pixel).
            assert!(a.0 < b.0 && b.1 < a.1, "{colour}: rises to the right");
        }
    }
}
