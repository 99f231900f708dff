//! rvtol-report: one self-contained HTML page (inline SVG, no script, nothing loaded from
//! a network) from rvtol's JSON reports — `run`, `sensitivity`, `allocate`, `stack`, `sweep` — and the
//! models' nominal curves, for a design review and as a reproducible record.
//!
//! The page reads the JSON reports, the stable contract of the engine, and nothing else
//! of the engine: `rvtol run|sensitivity|allocate|stack --html` renders the report it has just
//! made, `rvtol report` renders saved ones, and both give the same page for the same
//! reports. Nothing here computes a statistic; the page draws and tabulates what the
//! reports say. The same reports give the same bytes (no clock, no randomness).
//!
//! Layout: [`chart`] draws (plotters, SVG backend), [`html`] builds the markup, this file
//! reads the reports into sections (`inputs.rs` the run's inputs, `stack.rs` the stack
//! report's).

pub mod chart;
pub mod html;
mod inputs;
mod rare;
mod stack;
mod sweep;

use rvtol_models::{Curve, CurveStyle};
use serde_json::Value;

use chart::{BarRow, Cumulative, Limits, Marker};
use html::{escape, figure, number, table};
use rvtol_analysis::target::TargetFigure;
use rvtol_engine::format::group_thousands as thousands;
use rvtol_engine::stats::{conformity::Placement, SpecLimits};

/// What the page is a record of.
#[derive(Debug, Clone, Default)]
pub struct Record {
    /// Scenario name.
    pub scenario: String,
    /// Its description, when the scenario file is at hand.
    pub description: Option<String>,
    /// The scenario file as the user named it.
    pub source: Option<String>,
    /// The command that made the page.
    pub command: Option<String>,
    /// Version of the rvtol that renders the page.
    pub version: String,
}

/// The reports a page shows; any of them may be absent.
pub struct Report<'a> {
    /// What the page records.
    pub record: Record,
    /// The JSON report of `rvtol run`.
    pub run: Option<&'a Value>,
    /// The JSON report of `rvtol sensitivity`.
    pub sensitivity: Option<&'a Value>,
    /// The JSON report of `rvtol allocate`.
    pub allocation: Option<&'a Value>,
    /// The JSON report of `rvtol stack`.
    pub stack: Option<&'a Value>,
    /// The JSON report of `rvtol sweep`.
    pub sweep: Option<&'a Value>,
    /// The JSON report of `rvtol rare`.
    pub rare: Option<&'a Value>,
    /// Model name and its curves with every deviation at its mean.
    pub curves: &'a [(String, Vec<Curve>)],
    /// Why a model's curves are not drawn (a point that is not finite at the nominal
    /// design), one sentence per model: the page says so where the curves would be.
    pub curves_left_out: &'a [String],
    /// The curves of assemblies chosen for an output's value, drawn after their model's
    /// nominal curves.
    pub assemblies: &'a [AssemblyCurves],
}

/// A model's curves at one assembly chosen for its output's value (the median one, one in
/// the tail).
#[derive(Debug, Clone, PartialEq)]
pub struct AssemblyCurves {
    /// The model's name, as in [`Report::curves`].
    pub model: String,
    /// Which assembly, in a few words (`the P50 assembly of lost_motion_arcmin`).
    pub heading: String,
    /// How it was chosen, in a sentence: the percentile's value, the rows searched, the
    /// row and its value.
    pub note: String,
    /// Its curves.
    pub curves: Vec<Curve>,
    /// The titles of the curves the model gives no finite value for at this assembly.
    pub left_out: Vec<String>,
}

/// Why a page could not be made, in one line.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportError(pub String);

impl std::fmt::Display for ReportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ReportError {}

impl From<chart::ChartError> for ReportError {
    fn from(err: chart::ChartError) -> Self {
        ReportError(format!("cannot draw a chart: {}", err.0))
    }
}

/// Which command wrote a JSON report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `rvtol run`.
    Run,
    /// `rvtol sensitivity`.
    Sensitivity,
    /// `rvtol allocate`.
    Allocation,
    /// `rvtol stack`.
    Stack,
    /// `rvtol sweep`.
    Sweep,
    /// `rvtol rare`.
    Rare,
}

impl Kind {
    /// The command's name.
    pub fn command(self) -> &'static str {
        match self {
            Kind::Run => "run",
            Kind::Sensitivity => "sensitivity",
            Kind::Allocation => "allocate",
            Kind::Stack => "stack",
            Kind::Sweep => "sweep",
            Kind::Rare => "rare",
        }
    }
}

/// The kind of a JSON report, from the fields only that command writes.
pub fn kind_of(report: &Value) -> Option<Kind> {
    let has = |key: &str| report.get(key).is_some();
    if !has("rvtol_version") || !has("scenario") {
        return None;
    }
    if has("percentile_method") && has("outputs") {
        Some(Kind::Run)
    } else if has("base_samples") && has("outputs") {
        Some(Kind::Sensitivity)
    } else if has("target") && has("sources") {
        Some(Kind::Allocation)
    } else if has("corners") && has("outputs") {
        Some(Kind::Stack)
    } else if has("axes") && has("points") {
        Some(Kind::Sweep)
    } else if has("estimates") && has("sides") {
        Some(Kind::Rare)
    } else {
        None
    }
}

fn f(value: &Value, key: &str) -> Option<f64> {
    value.get(key).and_then(Value::as_f64)
}

fn s<'v>(value: &'v Value, key: &str) -> Option<&'v str> {
    value.get(key).and_then(Value::as_str)
}

fn pair(value: Option<&Value>) -> (Option<f64>, Option<f64>) {
    match value.and_then(Value::as_array) {
        Some(a) if a.len() == 2 => (a[0].as_f64(), a[1].as_f64()),
        _ => (None, None),
    }
}

/// A two-number interval with both ends.
fn closed(value: Option<&Value>) -> Option<(f64, f64)> {
    match pair(value) {
        (Some(a), Some(b)) => Some((a, b)),
        _ => None,
    }
}

/// Sorts report entries by the number under `key`, largest first (missing or non-finite
/// last).
fn sort_descending(entries: &mut [&Value], key: &str) {
    let of = |v: &Value| {
        f(v, key)
            .filter(|t| t.is_finite())
            .unwrap_or(f64::NEG_INFINITY)
    };
    entries.sort_by(|a, b| of(b).total_cmp(&of(a)));
}

fn array<'v>(value: &'v Value, key: &str, what: &str) -> Result<&'v Vec<Value>, ReportError> {
    value.get(key).and_then(Value::as_array).ok_or_else(|| {
        ReportError(format!(
            "{what}: no `{key}` list: not a report of this rvtol"
        ))
    })
}

/// An HTML id from a name.
fn anchor(prefix: &str, name: &str) -> String {
    let clean: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect();
    format!("{prefix}-{clean}")
}

/// Renders the page.
pub fn render(report: &Report) -> Result<String, ReportError> {
    let record = &report.record;
    let mut body = String::new();
    let mut nav: Vec<(String, String)> = vec![("record".into(), "Record".into())];
    let mut sections = String::new();
    if let Some(inputs) =
        (report.run).and_then(|run| inputs::inputs_section(run, report.sensitivity, report.stack))
    {
        sections.push_str(&inputs);
        nav.push(("inputs".into(), "Inputs".into()));
    }
    if let Some(run) = report.run {
        sections.push_str(&run_section(run)?);
        nav.push(("run".into(), "Output distributions".into()));
    }
    if let Some(sensitivity) = report.sensitivity {
        sections.push_str(&sensitivity_section(sensitivity)?);
        nav.push(("sensitivity".into(), "Sensitivity".into()));
    }
    if let Some(allocation) = report.allocation {
        sections.push_str(&allocation_section(allocation)?);
        nav.push(("allocation".into(), "Allocation".into()));
    }
    if let Some(stack) = report.stack {
        sections.push_str(&stack::stack_section(stack)?);
        nav.push(("stack".into(), "Worst case and RSS".into()));
    }
    if let Some(sweep) = report.sweep {
        sections.push_str(&sweep::sweep_section(sweep)?);
        nav.push(("sweep".into(), "Sweep".into()));
    }
    if let Some(rare) = report.rare {
        sections.push_str(&rare::rare_section(rare)?);
        nav.push(("rare".into(), "Rare event".into()));
    }
    if !report.curves.is_empty() || !report.curves_left_out.is_empty() {
        sections.push_str(&curves_section(
            report.curves,
            report.curves_left_out,
            report.assemblies,
        )?);
        nav.push(("curves".into(), "Model curves".into()));
    }
    body.push_str(&format!(
        "<header>\n<h1>rvtol report: {}</h1>\n",
        escape(&record.scenario)
    ));
    if let Some(description) = &record.description {
        body.push_str(&format!("<p class=\"lead\">{}</p>\n", escape(description)));
    }
    body.push_str("<nav>");
    for (id, label) in &nav {
        body.push_str(&format!("<a href=\"#{id}\">{}</a>", escape(label)));
    }
    body.push_str("</nav>\n</header>\n");
    body.push_str(&record_section(report));
    body.push_str(&sections);
    body.push_str(&format!(
        "<footer>Written by rvtol {}. Every figure on this page is read from the JSON reports named under Record; \
         the same reports give the same page. The page holds no script and loads nothing.</footer>\n",
        escape(&record.version)
    ));
    Ok(html::page(
        &format!("rvtol report: {}", record.scenario),
        &body,
    ))
}

/// Scenario, command, versions, seeds and sample counts: what reproduces the page.
fn record_section(report: &Report) -> String {
    let record = &report.record;
    let mut rows: Vec<Vec<String>> = vec![vec!["scenario".into(), escape(&record.scenario)]];
    // The digest of the scenario text every report was computed from (`rvtol report`
    // composes reports of one text only).
    let digest = [
        report.run,
        report.sensitivity,
        report.allocation,
        report.stack,
        report.sweep,
        report.rare,
    ]
    .into_iter()
    .flatten()
    .find_map(|json| s(json, "scenario_sha256"));
    if let Some(digest) = digest {
        rows.push(vec![
            "scenario SHA-256".into(),
            format!(
                "<code>{}</code> (of the scenario text, data files written in)",
                escape(digest)
            ),
        ]);
    }
    if let Some(source) = &record.source {
        rows.push(vec![
            "scenario file".into(),
            format!("<code>{}</code>", escape(source)),
        ]);
    }
    if let Some(command) = &record.command {
        rows.push(vec![
            "command".into(),
            format!("<code>{}</code>", escape(command)),
        ]);
    }
    let mut reproduce = |kind: &str, json: &Value, samples_key: &str| {
        let mut parts = vec![format!(
            "rvtol {}",
            escape(s(json, "rvtol_version").unwrap_or("?"))
        )];
        if let Some(seed) = json.get("seed").and_then(Value::as_u64) {
            parts.push(format!("seed {seed}"));
        }
        if let Some(verify) = json.get("verification_seed").and_then(Value::as_u64) {
            parts.push(format!("verification seed {verify}"));
        }
        match (
            json.get("rare"),
            json.get(samples_key).and_then(Value::as_u64),
        ) {
            // An allocation by importance sampling: its count is a sample's points.
            (Some(_), Some(n)) => parts.push(format!(
                "importance sampling (--rare), {} points per estimate",
                thousands(n)
            )),
            (None, Some(n)) => parts.push(format!("{} samples", thousands(n))),
            (_, None) => {}
        }
        if let Some(sampling) = json.get("sampling") {
            parts.push(format!(
                "{} sampling, {} (intervals from the replicates)",
                escape(s(sampling, "method").unwrap_or("?")),
                replicates_of(sampling)
            ));
        }
        if let Some(method) = json.get("percentile_method") {
            parts.push(format!(
                "{} percentiles ({})",
                escape(s(method, "kind").unwrap_or("?")),
                escape(s(method, "estimator").unwrap_or(""))
            ));
        }
        if let Some(b) = json.get("bootstrap").and_then(Value::as_u64) {
            parts.push(format!("{b} bootstrap resamples"));
        }
        if let Some(e) = json.get("evaluations").and_then(Value::as_u64) {
            parts.push(format!("{} evaluations", thousands(e)));
        }
        rows.push(vec![kind.into(), parts.join(", ")]);
    };
    if let Some(run) = report.run {
        reproduce("run report", run, "samples");
    }
    if let Some(sensitivity) = report.sensitivity {
        reproduce("sensitivity report", sensitivity, "base_samples");
    }
    if let Some(allocation) = report.allocation {
        reproduce("allocation report", allocation, "samples");
    }
    if let Some(stack) = report.stack {
        reproduce("stack report", stack, "monte_carlo_samples");
    }
    if let Some(sweep) = report.sweep {
        reproduce("sweep report", sweep, "samples");
    }
    if let Some(rare) = report.rare {
        reproduce("rare-event report", rare, "samples");
    }
    rows.push(vec![
        "page written by".into(),
        format!("rvtol {}", escape(&record.version)),
    ]);
    let mut out = String::from("<section id=\"record\">\n<h2>Record</h2>\n");
    out.push_str(&table(&["", ""], &rows, &[]).replacen("<table>", "<table class=\"meta\">", 1));
    out.push_str("</section>\n");
    out
}

/// Where an output's samples beyond the limits sit among its values (by its spec limits).
fn placement_of(output: &Value) -> Placement {
    let spec = output.get("spec");
    Placement::of(Some(SpecLimits {
        lower: spec.and_then(|s| f(s, "lower")),
        upper: spec.and_then(|s| f(s, "upper")),
    }))
}

/// The table of an output's percentiles with their intervals: "beyond the limits" for a
/// percentile that reads a sample beyond them, an interval's open end "beyond" on the side
/// where such samples sit.
fn percentile_table(output: &Value, markers: &[Marker]) -> String {
    let placement = placement_of(output);
    let has_beyond = output.get("value_percentiles").is_some();
    let rows: Vec<Vec<String>> = markers
        .iter()
        .map(|m| {
            let above = placement.above(m.percent);
            let end = |x: Option<f64>, open: &str, side: bool| match x {
                Some(x) => number(Some(x)),
                None if has_beyond && side => "beyond".into(),
                None => open.into(),
            };
            let (value, interval) = if m.value.is_infinite() {
                ("beyond the limits".into(), String::new())
            } else {
                (
                    number(Some(m.value)),
                    format!(
                        "{} .. {}",
                        end(m.interval.0, "below min", !above),
                        end(m.interval.1, "above max", above)
                    ),
                )
            };
            vec![format!("P{}", m.percent), value, interval]
        })
        .collect();
    table(&["percentile", "value", "95 % CI"], &rows, &[1, 2])
}

/// The report's percentiles, in its order, keyed by the percent as text, with their
/// intervals: a replicated run's from its replicates, else the order-statistic ones.
fn markers(output: &Value) -> Vec<Marker> {
    let replicated = output
        .get("replicate_ci95")
        .and_then(|r| r.get("percentiles"));
    let (Some(values), intervals) = (
        output.get("percentiles").and_then(Value::as_object),
        replicated.or_else(|| output.get("percentile_ci95")),
    ) else {
        return Vec::new();
    };
    // With samples beyond the limits (the report then gives the values' own percentiles
    // too), a null percentile reads them: ±∞ where the output's limits place them.
    let beyond = output.get("value_percentiles").is_some();
    let placement = placement_of(output);
    values
        .iter()
        .filter_map(|(key, value)| {
            let percent: f64 = key.parse().ok()?;
            let beyond_value = placement.beyond_value(percent);
            Some(Marker {
                percent,
                value: value.as_f64().or(beyond.then_some(beyond_value))?,
                interval: pair(intervals.and_then(|i| i.get(key))),
            })
        })
        .collect()
}

fn run_section(run: &Value) -> Result<String, ReportError> {
    let outputs = array(run, "outputs", "run report")?;
    let mut out = String::from("<section id=\"run\">\n<h2>Output distributions</h2>\n");
    let percentile_intervals = match run.get("sampling") {
        Some(sampling) => {
            format!(
            "Rows from {} ({} independent replicates); percentile intervals are 95 % intervals \
             from the replicates' spread (Student t). The out-of-spec fraction's interval is \
             Clopper–Pearson's for independent rows (the text report adds the replicates').",
            match s(sampling, "method") {
                Some("lhs") => "a Latin hypercube",
                _ => "scrambled Sobol' points",
            },
            sampling.get("replicates").and_then(Value::as_u64).unwrap_or(0)
        )
        }
        None => "Percentile intervals are distribution-free 95 % confidence intervals from order \
                 statistics (exact binomial ranks); an open end means the interval reaches \
                 beyond the sample's extreme. The out-of-spec fraction's interval is \
                 Clopper–Pearson's exact one."
            .to_string(),
    };
    out.push_str(&format!(
        "<p class=\"note\">{} samples, seed {}. {percentile_intervals}</p>\n",
        thousands(run.get("samples").and_then(Value::as_u64).unwrap_or(0)),
        run.get("seed").and_then(Value::as_u64).unwrap_or(0)
    ));
    let mut indicators = Vec::new();
    for output in outputs {
        let name = s(output, "name").unwrap_or("output");
        let unit = s(output, "unit").unwrap_or("");
        if s(output, "kind") == Some("indicator") {
            let (lo, hi) = pair(output.get("fraction_ci95"));
            indicators.push(vec![
                escape(name),
                thousands(output.get("events").and_then(Value::as_u64).unwrap_or(0)),
                thousands(output.get("n").and_then(Value::as_u64).unwrap_or(0)),
                format!("{} %", number(f(output, "fraction").map(|v| v * 100.0))),
                format!(
                    "{} .. {} %",
                    number(lo.map(|v| v * 100.0)),
                    number(hi.map(|v| v * 100.0))
                ),
            ]);
            continue;
        }
        out.push_str(&output_block(output, name, unit)?);
    }
    if !indicators.is_empty() {
        out.push_str("<h3>Indicators</h3>\n<p class=\"note\">Outputs that flag a sample (interference, preload): how many samples were flagged.</p>\n");
        out.push_str(&table(
            &["indicator", "flagged", "of samples", "fraction", "95 % CI"],
            &indicators,
            &[1, 2, 3, 4],
        ));
    }
    out.push_str("</section>\n");
    Ok(out)
}

/// The histogram and the cumulative plot of an output, side by side.
fn distribution_figures(
    output: &Value,
    name: &str,
    label: &str,
    limits: Limits,
    all_markers: &[Marker],
) -> Result<String, ReportError> {
    let mut out = String::new();
    let three: Vec<Marker> = all_markers
        .iter()
        .filter(|m| [0.135, 50.0, 99.865].contains(&m.percent))
        .cloned()
        .collect();
    let histogram = output.get("histogram");
    let counts: Vec<u64> = histogram
        .and_then(|h| h.get("counts"))
        .and_then(Value::as_array)
        .map(|c| c.iter().filter_map(Value::as_u64).collect())
        .unwrap_or_default();
    let flagged: Option<Vec<u64>> = histogram
        .and_then(|h| h.get("flagged"))
        .and_then(Value::as_array)
        .map(|c| c.iter().filter_map(Value::as_u64).collect())
        .filter(|c: &Vec<u64>| c.len() == counts.len());
    let lower_edge = histogram.and_then(|h| f(h, "lower_edge"));
    let bin_width = histogram.and_then(|h| f(h, "bin_width"));
    let total: u64 = counts.iter().sum();
    let flagged_total: u64 = flagged.iter().flatten().sum();
    // On the chart, where flagged samples hide among the values: the out-of-spec share.
    let corner = (flagged_total > 0).then(|| {
        format!(
            "out of spec {} % (flagged {} %)",
            number(f(output, "ppm_out").map(|ppm| ppm / 1e4)),
            number(Some(100.0 * flagged_total as f64 / total as f64))
        )
    });
    out.push_str("<div class=\"pair\">\n");
    match (lower_edge, bin_width) {
        (Some(lower_edge), Some(bin_width)) if total > 0 => {
            let svg = chart::histogram(
                &format!("{name}: histogram"),
                label,
                lower_edge,
                bin_width,
                &counts,
                flagged.as_deref(),
                corner.as_deref(),
                limits,
                &three,
            )?;
            let flagged_note = if flagged_total > 0 {
                format!(
                    " Orange: the {} samples ({} %) an indicator flags non-conforming, drawn at \
                     their values but out of spec; the percentiles and the ppm place them beyond \
                     the limits.",
                    thousands(flagged_total),
                    number(Some(100.0 * flagged_total as f64 / total as f64))
                )
            } else {
                String::new()
            };
            out.push_str(&figure(
                &svg,
                &format!(
                    "Histogram of the {} samples with a value, {} bins. Dashed: P0.135, P50, P99.865, \
                     their 95 % intervals shaded. Red: spec limits.{flagged_note}",
                    thousands(total),
                    counts.len()
                ),
            ));
            // The cumulative fraction at the bin edges of `counts` less `without` per bin.
            let cumulative_of = |without: &dyn Fn(usize) -> u64| {
                let mut sum = 0u64;
                (counts.iter().enumerate())
                    .map(|(k, c)| {
                        sum += c - without(k);
                        (
                            lower_edge + bin_width * (k + 1) as f64,
                            sum as f64 / total as f64,
                        )
                    })
                    .collect::<Vec<_>>()
            };
            let mut curves = vec![Cumulative {
                label: if flagged_total > 0 {
                    "every value (flagged included), cumulative at the bin edges".into()
                } else {
                    "histogram, cumulative at the bin edges".into()
                },
                points: cumulative_of(&|_| 0),
            }];
            if let Some(flagged) = flagged.as_ref().filter(|_| flagged_total > 0) {
                curves.push(Cumulative {
                    label: "conforming by their flags: the flagged ones lie beyond".into(),
                    points: cumulative_of(&|k| flagged[k]),
                });
            }
            let svg = chart::probability_plot(
                &format!("{name}: cumulative distribution"),
                label,
                &curves,
                all_markers,
                limits,
                None,
            )?;
            out.push_str(&figure(
                &svg,
                &format!(
                    "Cumulative distribution on a normal probability scale (a normal distribution \
                     is a straight line; the tails are spread out): the histogram's cumulative \
                     fraction at its bin edges, and the seven reported percentiles with their 95 % \
                     intervals.{}",
                    if flagged_total > 0 {
                        " The second curve leaves the flagged samples out (it ends below 1 by \
                         their share): the reported percentiles read that one, the flagged \
                         samples placed beyond the limits."
                    } else {
                        ""
                    }
                ),
            ));
        }
        _ => out.push_str("<p class=\"note\">No sample has a value: nothing to draw.</p>\n"),
    }
    out.push_str("</div>\n");
    Ok(out)
}

fn output_block(output: &Value, name: &str, unit: &str) -> Result<String, ReportError> {
    let label = if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({unit})")
    };
    let mut out = format!(
        "<h3 id=\"{}\">{}</h3>\n",
        anchor("out", name),
        escape(&label)
    );
    let spec = output.get("spec");
    let limits = Limits {
        lower: spec.and_then(|s| f(s, "lower")),
        upper: spec.and_then(|s| f(s, "upper")),
    };
    let all_markers = markers(output);
    out.push_str(&distribution_figures(
        output,
        name,
        &label,
        limits,
        &all_markers,
    )?);
    // Figures.
    let count = |key: &str| output.get(key).and_then(Value::as_u64).unwrap_or(0);
    let mut rows = vec![
        vec!["samples with a value".into(), thousands(count("n"))],
        vec!["non-finite".into(), thousands(count("non_finite"))],
    ];
    if let Some(condition) = output.get("condition") {
        let effect = s(condition, "effect").unwrap_or("");
        let reading = match effect {
            "excluded" => "excluded from the figures",
            "non-conforming" => "counted out of spec",
            other => other,
        };
        rows.push(vec![
            format!(
                "flagged by {}",
                escape(s(condition, "indicator").unwrap_or("?"))
            ),
            format!(
                "{} ({} %), {}",
                thousands(
                    condition
                        .get("samples")
                        .and_then(Value::as_u64)
                        .unwrap_or(0)
                ),
                number(f(condition, "fraction").map(|v| v * 100.0)),
                escape(reading)
            ),
        ]);
    }
    for (label, key) in [
        ("mean", "mean"),
        ("standard deviation", "sd"),
        ("skewness", "skewness"),
        ("excess kurtosis", "excess_kurtosis"),
        ("min", "min"),
        ("max", "max"),
    ] {
        rows.push(vec![label.into(), number(f(output, key))]);
    }
    let mut tables = table(&["figure", "value"], &rows, &[1]);
    tables.push_str(&percentile_table(output, &all_markers));
    if limits.lower.is_some() || limits.upper.is_some() {
        let spec_text = match (limits.lower, limits.upper) {
            (Some(l), Some(u)) => format!("{} ≤ x ≤ {}", number(Some(l)), number(Some(u))),
            (Some(l), None) => format!("x ≥ {}", number(Some(l))),
            (None, Some(u)) => format!("x ≤ {}", number(Some(u))),
            _ => String::new(),
        };
        let with_ci = |value: Option<f64>, key: &str| {
            let (lo, hi) = pair(output.get(key));
            match (value, lo, hi) {
                (Some(v), Some(lo), Some(hi)) => {
                    format!(
                        "{} ({} .. {})",
                        number(Some(v)),
                        number(Some(lo)),
                        number(Some(hi))
                    )
                }
                (v, _, _) => number(v),
            }
        };
        let (ppm_lo, ppm_hi) = pair(output.get("ppm_out_ci95"));
        let capability = vec![
            vec!["spec".into(), escape(&spec_text)],
            vec![
                "Cp (moments, 95 % CI)".into(),
                with_ci(f(output, "cp"), "cp_ci95"),
            ],
            vec![
                "Cpk (moments, 95 % CI)".into(),
                with_ci(f(output, "cpk"), "cpk_ci95"),
            ],
            vec![
                "Cp (percentiles)".into(),
                number(f(output, "cp_percentile")),
            ],
            vec![
                "Cpk (percentiles)".into(),
                number(f(output, "cpk_percentile")),
            ],
            vec![
                "out of spec, ppm (95 % CI)".into(),
                format!(
                    "{} ({} .. {})",
                    number(f(output, "ppm_out")),
                    number(ppm_lo),
                    number(ppm_hi)
                ),
            ],
        ];
        tables.push_str(&table(&["capability", "value"], &capability, &[1]));
        // Below the table, as a paragraph that wraps: in the value column (numbers, kept
        // on one line) a sentence widened the table past the page and pushed the values
        // off it.
        if let Some(note) = s(output, "capability_note") {
            tables.push_str(&format!("<p class=\"note\">{}</p>\n", escape(note)));
        }
    }
    out.push_str(&format!(
        "<div class=\"pair\">\n<div>{tables}</div>\n</div>\n"
    ));
    Ok(out)
}

/// "R replicates of n points" from a report's `sampling`.
fn replicates_of(sampling: &Value) -> String {
    let count = |key: &str| sampling.get(key).and_then(Value::as_u64).unwrap_or(0);
    format!(
        "{} replicates of {} points",
        count("replicates"),
        thousands(count("points_per_replicate"))
    )
}

fn sensitivity_section(report: &Value) -> Result<String, ReportError> {
    let outputs = array(report, "outputs", "sensitivity report")?;
    let mut out = String::from("<section id=\"sensitivity\">\n<h2>Sensitivity</h2>\n");
    let sampling = report.get("sampling");
    let intervals_from = match sampling {
        Some(sampling) => format!("the spread of {} (Student t)", replicates_of(sampling)),
        None => format!(
            "{} bootstrap resamples over the {}",
            report.get("bootstrap").and_then(Value::as_u64).unwrap_or(0),
            escape(s(report, "bootstrap_unit").unwrap_or("rows"))
        ),
    };
    if let Some(method) = s(report, "method") {
        out.push_str(&format!(
            "<p class=\"note\">{}. {} base samples, {} model evaluations; intervals at {} % from {intervals_from}.</p>\n",
            escape(method),
            thousands(report.get("base_samples").and_then(Value::as_u64).unwrap_or(0)),
            thousands(report.get("evaluations").and_then(Value::as_u64).unwrap_or(0)),
            f(report, "confidence").map_or("n/a".to_string(), |c| format!("{:.0}", c * 100.0)),
        ));
    }
    let whiskers = if sampling.is_some() {
        "Whiskers: intervals from the replicates."
    } else {
        "Whiskers: bootstrap intervals."
    };
    for output in outputs {
        let name = s(output, "name").unwrap_or("output");
        out.push_str(&format!(
            "<h3 id=\"{}\">{}</h3>\n",
            anchor("sens", name),
            escape(name)
        ));
        if let Some(share) = f(output, "share") {
            let what = match s(output, "kind") {
                Some("out_of_spec") => {
                    "out of spec (the run's rule: outside the limits, not \
                     finite, or flagged non-conforming)"
                }
                _ => "set",
            };
            out.push_str(&format!(
                "<p class=\"note\">A 0/1 quantity, {what} in {} % of the rows of A and B: its \
                 Sobol' indices say which sources decide whether an assembly fails.</p>\n",
                number(Some(100.0 * share))
            ));
        }
        if let Some(note) = s(output, "note") {
            out.push_str(&format!("<p class=\"note\">{}.</p>\n", escape(note)));
        }
        let mut indices: Vec<&Value> = output
            .get("indices")
            .and_then(Value::as_array)
            .map(|a| a.iter().collect())
            .unwrap_or_default();
        sort_descending(&mut indices, "total");
        out.push_str("<div class=\"pair\">\n");
        if !indices.is_empty() {
            let rows: Vec<BarRow> = indices
                .iter()
                .map(|v| {
                    let ci = |key: &str| closed(v.get(key));
                    BarRow {
                        name: s(v, "input").unwrap_or("?").to_string(),
                        values: vec![
                            (
                                f(v, "first_order").unwrap_or(f64::NAN),
                                ci("first_order_ci"),
                            ),
                            (f(v, "total").unwrap_or(f64::NAN), ci("total_ci")),
                        ],
                    }
                })
                .collect();
            let svg = chart::horizontal_bars(
                &format!("{name}: Sobol' indices"),
                "share of the output variance",
                &["first order S_i", "total S_Ti"],
                &rows,
            )?;
            out.push_str(&figure(
                &svg,
                &format!(
                    "Sources sorted by total index. First order: the share of the variance the \
                     source explains alone; total: with all its interactions. {whiskers}"
                ),
            ));
        }
        if let Some(effects) = output.get("shapley").and_then(Value::as_array) {
            let mut effects: Vec<&Value> = effects.iter().collect();
            sort_descending(&mut effects, "effect");
            let rows: Vec<BarRow> = effects
                .iter()
                .map(|v| BarRow {
                    name: s(v, "input").unwrap_or("?").to_string(),
                    values: vec![(f(v, "effect").unwrap_or(f64::NAN), closed(v.get("ci")))],
                })
                .collect();
            let svg = chart::horizontal_bars(
                &format!("{name}: Shapley effects"),
                "share of the output variance",
                &["Shapley effect"],
                &rows,
            )?;
            out.push_str(&figure(
                &svg,
                "Shapley effects: each source's fair share of the variance, interactions and \
                 correlations split among the sources involved; they sum to 1 and stay \
                 meaningful when sources are correlated. Whiskers: 95 % intervals.",
            ));
        }
        let screening = output.get("screening");
        let sources: Vec<&Value> = screening
            .and_then(|s| s.get("sources"))
            .and_then(Value::as_array)
            .map(|a| a.iter().collect())
            .unwrap_or_default();
        let r_squared = screening.and_then(|s| f(s, "r_squared"));
        let poor = rvtol_analysis::stack::POOR_LINEARITY;
        let linear_enough = r_squared.is_some_and(|r2| r2 >= poor);
        if !sources.is_empty() && !linear_enough {
            // A chart of contributions the linearisation does not support would be read
            // as a ranking: say why it is not drawn instead.
            out.push_str(&format!(
                "<p class=\"note\">Linearised contributions not drawn: the linear fit to the \
                 samples explains R² = {} of the output's variation (below {poor}), so the \
                 first-order Taylor shares at the nominal do not describe this output; the \
                 Sobol' indices are the ranking. The shares are in the JSON report.</p>\n",
                number(r_squared)
            ));
        }
        if !sources.is_empty() && linear_enough {
            let rows: Vec<BarRow> = sources
                .iter()
                .map(|v| BarRow {
                    name: s(v, "input").unwrap_or("?").to_string(),
                    values: vec![(f(v, "contribution_percent").unwrap_or(f64::NAN), None)],
                })
                .collect();
            let svg = chart::horizontal_bars(
                &format!("{name}: linearised contributions"),
                "share of the linearised variance (%)",
                &["contribution"],
                &rows,
            )?;
            out.push_str(&figure(
                &svg,
                &format!(
                    "First-order Taylor expansion at the nominal: each source's (∂y/∂x)²·Var(x) as a \
                     share of their sum. R² of the linear fit to the samples: {} (drawn from \
                     {poor} up; below, the model is not linear over the tolerances, and the \
                     Sobol' indices are the ranking to trust).",
                    number(r_squared)
                ),
            ));
        }
        out.push_str("</div>\n");
        let rows: Vec<Vec<String>> = indices
            .iter()
            .map(|v| {
                let (a, b) = pair(v.get("first_order_ci"));
                let (c, d) = pair(v.get("total_ci"));
                vec![
                    escape(s(v, "input").unwrap_or("?")),
                    number(f(v, "first_order")),
                    format!("{} .. {}", number(a), number(b)),
                    number(f(v, "total")),
                    format!("{} .. {}", number(c), number(d)),
                ]
            })
            .collect();
        if !rows.is_empty() {
            out.push_str(&table(
                &["source", "first order", "95 % CI", "total", "95 % CI"],
                &rows,
                &[1, 2, 3, 4],
            ));
        }
    }
    out.push_str("</section>\n");
    Ok(out)
}

fn allocation_section(report: &Value) -> Result<String, ReportError> {
    let sources = array(report, "sources", "allocation report")?;
    let output = s(report, "output").unwrap_or("output");
    let unit = s(report, "unit").unwrap_or("");
    let target = s(report, "target").unwrap_or("?");
    let status = s(report, "status").unwrap_or("?");
    let mut out = String::from("<section id=\"allocation\">\n<h2>Allocation</h2>\n");
    let class = if status == "met" {
        "status-met"
    } else {
        "status-bad"
    };
    out.push_str(&format!(
        "<p>Output <b>{}</b>, target <code>{}</code>: <span class=\"{class}\">{}</span>. \
         Total cost {} today, {} proposed.</p>\n",
        escape(output),
        escape(target),
        escape(status),
        number(f(report, "current_cost")),
        number(f(report, "proposed_cost")),
    ));
    let rare = report.get("rare");
    if let Some(rare) = rare {
        out.push_str(&format!(
            "<p>The targeted ppm is estimated by importance sampling (<code>--rare</code>): \
             weighted points drawn once around the out-of-spec event's centres and re-used for \
             every set of tolerances tried, {} sample(s) built ({} points in the last), \
             the verification by {}; {} model evaluations in all.</p>\n",
            thousands(rare.get("stages").and_then(Value::as_u64).unwrap_or(0)),
            thousands(rare.get("points").and_then(Value::as_u64).unwrap_or(0)),
            match s(rare, "verified_by") {
                Some("subset") => "subset simulation",
                _ => "importance sampling around the proposal's own centres",
            },
            thousands(
                rare.get("model_evaluations")
                    .and_then(Value::as_u64)
                    .unwrap_or(0)
            ),
        ));
    }
    // Tolerance changes.
    let rows: Vec<BarRow> = sources
        .iter()
        .map(|v| BarRow {
            name: s(v, "source").unwrap_or("?").to_string(),
            values: vec![(
                // A change too large to draw (a factor of 1e308) is left out, as a missing one.
                f(v, "factor")
                    .map(|factor| (factor - 1.0) * 100.0)
                    .filter(|change| change.is_finite())
                    .unwrap_or(f64::NAN),
                None,
            )],
        })
        .collect();
    out.push_str("<div class=\"pair\">\n");
    let svg = chart::horizontal_bars(
        "Proposed change of each tolerance",
        "proposed / current − 1 (%): right loosens, left tightens",
        &["tolerance change"],
        &rows,
    )?;
    out.push_str(&figure(
        &svg,
        "Each source's proposed tolerance against today's.",
    ));
    out.push_str(&before_and_after(report, output, unit, target)?);
    out.push_str("</div>\n");
    let mut rows = Vec::new();
    for v in sources {
        let (lo, hi) = pair(v.get("bounds"));
        rows.push(vec![
            escape(s(v, "source").unwrap_or("?")),
            escape(s(v, "tolerance").unwrap_or("")),
            escape(s(v, "unit").unwrap_or("")),
            number(f(v, "current")),
            number(f(v, "proposed")),
            rvtol_engine::format::format_change(f(v, "factor").unwrap_or(f64::NAN)),
            format!("{} .. {}", number(lo), number(hi)),
            number(f(v, "current_cost")),
            number(f(v, "proposed_cost")),
            format!("{} %", number(f(v, "variance_share").map(|x| x * 100.0))),
        ]);
    }
    out.push_str(&table(
        &[
            "source",
            "tolerance",
            "unit",
            "current",
            "proposed",
            "change",
            "bounds",
            "cost now",
            "cost new",
            "variance share",
        ],
        &rows,
        &[3, 4, 5, 6, 7, 8, 9],
    ));
    let mut runs = Vec::new();
    for (key, label) in [
        ("current", "today"),
        ("proposed", "proposed (optimisation run)"),
        ("verification", "proposed (verification run)"),
    ] {
        if let Some(run) = report.get(key) {
            let (lo, hi) = pair(run.get("ci"));
            runs.push(vec![
                label.into(),
                number(f(run, "value")),
                format!("{} .. {}", number(lo), number(hi)),
                number(f(run, "mean")),
                number(f(run, "sd")),
                run.get("seed")
                    .and_then(Value::as_u64)
                    .map_or("".into(), |s| s.to_string()),
                thousands(run.get("n").and_then(Value::as_u64).unwrap_or(0)),
            ]);
        }
    }
    out.push_str(&table(
        &[
            "run",
            "targeted figure",
            "95 % CI",
            "mean",
            "sd",
            "seed",
            if rare.is_some() { "points" } else { "samples" },
        ],
        &runs,
        &[1, 2, 3, 4, 5, 6],
    ));
    if let Some(options) = report.get("lever_options").and_then(Value::as_array) {
        out.push_str(&lever_options_table(report, options));
    }
    out.push_str("</section>\n");
    Ok(out)
}

/// The targeted output's distribution today and with the proposed tolerances, with the
/// target where it is a value of the output (empty without the runs' outlines).
fn before_and_after(
    report: &Value,
    output: &str,
    unit: &str,
    target: &str,
) -> Result<String, ReportError> {
    // Before and after.
    let distribution = |key: &str| -> Option<Cumulative> {
        let run = report.get(key)?;
        let q = run.get("quantiles")?;
        let p = q.get("p")?.as_array()?;
        let v = q.get("value")?.as_array()?;
        let label = match key {
            "current" => "today".to_string(),
            "verification" => format!(
                "proposed, verification run (seed {})",
                run.get("seed").and_then(Value::as_u64).unwrap_or(0)
            ),
            _ => "proposed, optimisation run".to_string(),
        };
        Some(Cumulative {
            label,
            points: p
                .iter()
                .zip(v)
                .filter_map(|(p, v)| Some((v.as_f64()?, p.as_f64()? / 100.0)))
                .collect(),
        })
    };
    let lines: Vec<Cumulative> = ["current", "verification"]
        .iter()
        .filter_map(|k| distribution(k))
        .collect();
    // A target on a value of the output (a percentile, the mean) is a line on the plot;
    // one on a spread or an index is not.
    let target_line = match rvtol_analysis::target::Target::parse(target) {
        Ok(parsed) => match parsed.figure {
            TargetFigure::Percentile(p) => Some((parsed.value, Some(p))),
            TargetFigure::Mean => Some((parsed.value, None)),
            _ => None,
        },
        Err(_) => None,
    };
    if lines.is_empty() {
        return Ok(String::new());
    }
    let label = if unit.is_empty() {
        output.to_string()
    } else {
        format!("{output} ({unit})")
    };
    let spec = report.get("spec");
    let limits = Limits {
        lower: spec.and_then(|s| f(s, "lower")),
        upper: spec.and_then(|s| f(s, "upper")),
    };
    // Where a run's quantiles stop: the samples beyond the limits (flagged, excluded, not
    // finite) have no value on this axis, so its curve ends below 100 %.
    let ends: Vec<String> = (lines.iter())
        .filter_map(|line| {
            let last = line.points.last()?.1;
            (last < 0.99).then(|| format!("{} at {} %", line.label, number(Some(100.0 * last))))
        })
        .collect();
    let ends = if ends.is_empty() {
        String::new()
    } else {
        format!(
            " A curve ends where its samples beyond the limits begin (flagged non-conforming, \
             excluded or not finite: no value to draw): {}.",
            ends.join("; ")
        )
    };
    let drawn = match (
        target_line.is_some(),
        limits.lower.or(limits.upper).is_some(),
    ) {
        (true, true) => "; the target and the spec limits drawn",
        (true, false) => "; the target drawn",
        (false, true) => "; the spec limits drawn",
        (false, false) => "",
    };
    let svg = chart::probability_plot(
        &format!("{output}: before and after"),
        &label,
        &lines,
        &[],
        limits,
        target_line.map(|(value, percent)| chart::Target {
            value,
            percent,
            label: format!("target {target}"),
        }),
    )?;
    Ok(figure(
        &svg,
        &format!(
            "The targeted output's cumulative distribution today and with the proposed \
             tolerances (the independent verification run), on a normal probability \
             scale{drawn}.{ends}"
        ),
    ))
}

/// The table of the levers' combinations with their costs and verdicts.
fn lever_options_table(report: &Value, options: &[Value]) -> String {
    let levers: Vec<String> = report
        .get("levers")
        .and_then(Value::as_array)
        .map(|l| l.iter().filter_map(|v| s(v, "lever").map(escape)).collect())
        .unwrap_or_default();
    let rows: Vec<Vec<String>> = options
        .iter()
        .map(|o| {
            let values: Vec<String> = o
                .get("values")
                .and_then(Value::as_array)
                .map(|v| v.iter().map(|x| number(x.as_f64())).collect())
                .unwrap_or_default();
            vec![
                values.join(", "),
                number(f(o, "lever_cost")),
                number(f(o, "tolerance_cost")),
                number(f(o, "total_cost")),
                escape(s(o, "status").unwrap_or("")),
                number(f(o, "verification")),
            ]
        })
        .collect();
    let lever_header = if levers.is_empty() {
        "lever".to_string()
    } else {
        levers.join(", ")
    };
    table(
        &[
            &lever_header,
            "lever cost",
            "tolerance cost",
            "total",
            "status",
            "verification",
        ],
        &rows,
        &[1, 2, 3, 5],
    )
}

fn curves_section(
    curves: &[(String, Vec<Curve>)],
    left_out: &[String],
    assemblies: &[AssemblyCurves],
) -> Result<String, ReportError> {
    let mut out = String::from(
        "<section id=\"curves\">\n<h2>Model curves</h2>\n<p class=\"note\">Every deviation at its mean \
         (the nominal assembly of the scenario); below, where the run's report is at hand, the \
         same curves of drawn assemblies whose output lies nearest the run's percentiles.</p>\n",
    );
    for why in left_out {
        out.push_str(&format!(
            "<p class=\"note\">Not drawn: {}.</p>\n",
            escape(why)
        ));
    }
    for (model, list) in curves {
        out.push_str(&format!(
            "<h3>{}: the nominal assembly</h3>\n",
            escape(model)
        ));
        out.push_str(&curve_figures(list)?);
        for assembly in assemblies.iter().filter(|a| &a.model == model) {
            out.push_str(&format!(
                "<h3>{}: {}</h3>\n<p class=\"note\">{}</p>\n",
                escape(model),
                escape(&assembly.heading),
                escape(&assembly.note)
            ));
            if !assembly.left_out.is_empty() {
                out.push_str(&format!(
                    "<p class=\"note\">Not drawn, the model giving them no finite value for this \
                     assembly: {}.</p>\n",
                    escape(&assembly.left_out.join("; "))
                ));
            }
            out.push_str(&curve_figures(&assembly.curves)?);
        }
    }
    out.push_str("</section>\n");
    Ok(out)
}

/// A model's curves as figures, two abreast.
fn curve_figures(list: &[Curve]) -> Result<String, ReportError> {
    let mut out = String::from("<div class=\"pair\">\n");
    for curve in list {
        let svg = chart::curve(curve)?;
        let dense = curve.style == CurveStyle::Lines
            && curve.series.iter().any(|s| s.points.len() > chart::DENSE);
        let mut caption = match curve.series.as_slice() {
            [one] => {
                let mut label = one.label.clone();
                if let Some(first) = label.get(..1) {
                    label.replace_range(..1, &first.to_uppercase());
                }
                format!("{label}.")
            }
            _ => String::new(),
        };
        if dense {
            caption.push_str(
                " The whole curve. A trace too dense to draw point by point is drawn as its \
                 band: the least and greatest value in each 1/360 of the axis.",
            );
        }
        out.push_str(&figure(&svg, caption.trim_start()));
    }
    out.push_str("</div>\n");
    Ok(out)
}

/// The curve as CSV: one x column and one y column per series when the series share their
/// x values, else an x and a y column per series (shorter series padded with empty cells).
pub fn curve_csv(curve: &Curve) -> String {
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
                    Some(&(x, y)) => [format!("{x}"), format!("{y}")],
                    None => [String::new(), String::new()],
                })
                .collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
    }
    out
}

/// The curve as a standalone SVG chart (`rvtol curve`).
pub fn curve_svg(curve: &Curve) -> Result<String, ReportError> {
    Ok(chart::curve(curve)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_before_and_after_plot_draws_the_spec_and_says_where_a_curve_ends() {
        // Today's quantiles stop at 90 %: the rest of the samples lie beyond the limit
        // (null values, as the allocation report writes them); the verification run's
        // curve is whole.
        let p = [0.135, 2.275, 50.0, 84.134, 90.0, 97.725, 99.865];
        let report = serde_json::json!({
            "spec": { "lower": null, "upper": 1.0 },
            "current": { "quantiles": { "p": p, "value": [0.1, 0.2, 0.5, 0.8, 0.95, null, null] } },
            "verification": {
                "seed": 7,
                "quantiles": { "p": p, "value": [0.1, 0.15, 0.3, 0.5, 0.6, 0.8, 0.9] }
            }
        });
        let html = before_and_after(&report, "y", "mm", "p99.865 <= 1").unwrap();
        assert!(html.contains("USL 1"), "the spec limit is drawn");
        assert!(html.contains("target p99.865 &lt;= 1") || html.contains("target p99.865 <= 1"));
        assert!(html.contains("today at 90"), "{html}");
        assert!(
            !html.contains("(seed 7) at"),
            "a whole curve has no end note"
        );
    }
}
