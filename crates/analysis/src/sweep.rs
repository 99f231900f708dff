//! `rvtol sweep`: one or two design values over a grid, a whole run at each point.
//!
//! Each point of the grid is the scenario with its design values set
//! ([`rvtol_engine::scenario::design`]), loaded and checked as any scenario, and run with
//! the sweep's seed and samples: its figures are those of `rvtol run` on that text, bit for
//! bit (the same rows, the same model), so two points differ by the design alone (common
//! random numbers). The report keeps each point's figures of the chosen outputs as the run
//! report has them (`OutputFigures`, with their intervals).
//!
//! JSON: `rvtol_version`, `scenario`, `scenario_sha256`, `seed`, `samples`, `axes` (per
//! axis `path`, `current`, `values`), `outputs` (the names) and `points` (per point
//! `values`, one per axis, and `outputs`, the run report's figures of each chosen output).

use serde::Serialize;
use serde_json::Value;

use rvtol_engine::figures::{output_figures, OutputFigures};
use rvtol_engine::format::{format_figure, format_ppm, format_sig};
use rvtol_engine::scenario::design::DesignValue;
use rvtol_engine::scenario::{Scenario, ScenarioError};
use rvtol_engine::RunSettings;

/// Most points of a sweep (each is a whole run).
pub const MAX_POINTS: usize = 400;

/// One axis of the grid: a design value and the values it takes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Axis {
    /// The design value's path.
    pub path: String,
    /// Its value in the scenario as written, when it gives one.
    pub current: Option<f64>,
    /// The values it takes, in order.
    pub values: Vec<f64>,
    /// The design value, checked against the scenario.
    #[serde(skip)]
    pub value: DesignValue,
}

/// One point of the grid and its run's figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Point {
    /// One value per axis.
    pub values: Vec<f64>,
    /// The run report's figures of each chosen output.
    pub outputs: Vec<OutputFigures>,
}

/// The report of `rvtol sweep`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepReport {
    /// Version of rvtol that produced it.
    pub rvtol_version: &'static str,
    /// Scenario name.
    pub scenario: String,
    /// SHA-256 of the scenario text as loaded (before any value is set).
    pub scenario_sha256: String,
    /// Seed of every point's run.
    pub seed: u64,
    /// Samples of every point's run.
    pub samples: u64,
    /// The axes, the first varying slowest.
    pub axes: Vec<Axis>,
    /// The outputs reported.
    pub outputs: Vec<String>,
    /// The points, the first axis varying slowest.
    pub points: Vec<Point>,
}

/// The grid of `axes` (the design values with their values, the first varying slowest)
/// checked against `scenario_text`: at most [`MAX_POINTS`] points.
pub fn axes(scenario_text: &str, grid: &[(String, Vec<f64>)]) -> Result<Vec<Axis>, String> {
    let mut points = 1usize;
    let mut axes = Vec::with_capacity(grid.len());
    for (path, values) in grid {
        let value = DesignValue::parse(scenario_text, path)?;
        if values.is_empty() {
            return Err(format!("{path}: give at least one value"));
        }
        if axes.iter().any(|a: &Axis| a.path == *path) {
            return Err(format!("{path} is set twice"));
        }
        points = points.saturating_mul(values.len());
        axes.push(Axis {
            path: path.clone(),
            current: value.current,
            values: values.clone(),
            value,
        });
    }
    if points > MAX_POINTS {
        return Err(format!(
            "the grid has {points} points, each a whole run; at most {MAX_POINTS}"
        ));
    }
    Ok(axes)
}

/// Runs every point of the grid `axes` over `scenario` (of text `scenario_text`), the
/// outputs `outputs` (indices into the scenario's, names that every point keeps), with
/// `settings`; `progress` gets each point's samples as its chunks finish. Uses the current
/// rayon pool.
pub fn sweep(
    scenario: &Scenario,
    scenario_text: &str,
    axes: Vec<Axis>,
    outputs: &[usize],
    settings: RunSettings,
    max_non_finite: f64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<SweepReport, ScenarioError> {
    let document: Value = serde_json::from_str(scenario_text)
        .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?;
    let names: Vec<String> = (outputs.iter())
        .map(|&o| scenario.outputs[o].name.clone())
        .collect();
    let mut points = Vec::new();
    for values in grid(&axes) {
        let mut variant = document.clone();
        let at = (axes.iter().zip(&values))
            .map(|(axis, v)| format!("{} = {}", axis.path, format_sig(*v)))
            .collect::<Vec<_>>()
            .join(", ");
        for (axis, &value) in axes.iter().zip(&values) {
            axis.value.set(&mut variant, value)?;
        }
        let point = Scenario::from_json(&variant.to_string(), &scenario.name)
            .map_err(|err| ScenarioError::new(err.path, format!("{} (at {at})", err.message)))?;
        let mut result = rvtol_engine::run(&point, settings, progress)?;
        rvtol_engine::run::check_non_finite(&point, &result, max_non_finite)
            .map_err(|err| ScenarioError::new(err.path, format!("{} (at {at})", err.message)))?;
        let figures = output_figures(&point, &mut result);
        let chosen = (names.iter())
            .map(|name| {
                (figures.iter().find(|f| f.name == *name).cloned()).ok_or_else(|| {
                    ScenarioError::new("--output", format!("no output {name:?} at {at}"))
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        points.push(Point {
            values,
            outputs: chosen,
        });
    }
    Ok(SweepReport {
        rvtol_version: env!("CARGO_PKG_VERSION"),
        scenario: scenario.name.clone(),
        scenario_sha256: scenario.digest.clone(),
        seed: settings.seed,
        samples: settings.samples,
        axes,
        outputs: names,
        points,
    })
}

/// Every combination of the axes' values, the first axis varying slowest.
fn grid(axes: &[Axis]) -> Vec<Vec<f64>> {
    let mut points = vec![Vec::new()];
    for axis in axes {
        points = (points.into_iter())
            .flat_map(|prefix| {
                axis.values.iter().map(move |&v| {
                    let mut next = prefix.clone();
                    next.push(v);
                    next
                })
            })
            .collect();
    }
    points
}

impl SweepReport {
    /// The JSON document (pretty-printed, trailing newline).
    pub fn to_json(&self) -> String {
        let mut text = serde_json::to_string_pretty(self).expect("report serialises");
        text.push('\n');
        text
    }

    /// The readable report: per output, a table of the points with the mean, the sd, P50
    /// and P99.865 (as conformity reads them: "beyond" where flagged samples reach them)
    /// with their 95 % intervals, and the out-of-spec ppm with its interval.
    pub fn to_text(&self) -> String {
        let mut lines = vec![format!(
            "rvtol {} | scenario {} | sweep of {} | {} points | {} samples each | seed {}",
            self.rvtol_version,
            self.scenario,
            (self.axes.iter().map(|a| a.path.as_str()))
                .collect::<Vec<_>>()
                .join(" x "),
            self.points.len(),
            rvtol_engine::format::group_thousands(self.samples),
            self.seed
        )];
        for axis in &self.axes {
            if let Some(current) = axis.current {
                lines.push(format!(
                    "{}: {} in the scenario",
                    axis.path,
                    format_sig(current)
                ));
            }
        }
        for (k, name) in self.outputs.iter().enumerate() {
            lines.push(String::new());
            lines.push(self.table(k, name));
        }
        let mut text = lines.join("\n");
        text.push('\n');
        text
    }

    /// Output `k`'s table.
    fn table(&self, k: usize, name: &str) -> String {
        let unit = self
            .points
            .first()
            .map_or("", |p| p.outputs[k].unit.as_str());
        let mut header: Vec<String> = (self.axes.iter())
            .map(|a| a.path.rsplit('.').next().unwrap_or(&a.path).to_string())
            .collect();
        header.extend(
            [
                "mean",
                "sd",
                "P50 (95 % CI)",
                "P99.865 (95 % CI)",
                "out of spec ppm (95 % CI)",
            ]
            .map(String::from),
        );
        let mut rows = vec![header];
        for point in &self.points {
            let o = &point.outputs[k];
            let percentile = |key: &str| {
                let value = o.percentiles.get(key);
                let ci = o.percentile_ci95.get(key).unwrap_or([None, None]);
                let end = |v: Option<f64>| v.map_or("..".to_string(), format_figure);
                match value {
                    Some(v) if v.is_finite() => {
                        format!("{} ({} .. {})", format_figure(v), end(ci[0]), end(ci[1]))
                    }
                    _ => "beyond".to_string(),
                }
            };
            let ppm = match &o.capability {
                Some(c) => format!(
                    "{} ({} .. {})",
                    format_ppm(c.ppm_out),
                    format_ppm(c.ppm_out_ci95[0]),
                    format_ppm(c.ppm_out_ci95[1])
                ),
                None => "n/a".into(),
            };
            let mut row: Vec<String> = point.values.iter().map(|v| format_sig(*v)).collect();
            row.extend([
                format_figure(o.mean),
                format_figure(o.sd),
                percentile("50"),
                percentile("99.865"),
                ppm,
            ]);
            rows.push(row);
        }
        let widths: Vec<usize> = (0..rows[0].len())
            .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
            .collect();
        let mut out = format!("{name} ({unit})");
        for row in rows {
            let cells: Vec<String> = (row.iter().zip(&widths))
                .map(|(cell, &w)| format!("{cell:>w$}"))
                .collect();
            out.push('\n');
            out.push_str(cells.join("  ").trim_end());
        }
        out
    }
}
