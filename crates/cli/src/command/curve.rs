//! `rvtol curve`: the nominal curves of the scenario's models (transmission-error trace
//! and order spectrum, torsion curve), a CSV and an SVG plot each.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_engine::nominal_curves;

use super::{load, problem_of_file};
use crate::output::{is_stdout, StagedOutputs};
use crate::BadInput;

/// The arguments of `rvtol curve`.
#[derive(Debug, Args)]
pub struct CurveArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// Directory for the files (created when missing).
    #[arg(long, value_name = "DIR", default_value = ".")]
    pub out_dir: PathBuf,
}

/// `rvtol curve`: the curves' files, and a line for each on standard output.
pub fn curve(args: CurveArgs) -> Result<()> {
    let (scenario_path, out_dir) = (args.scenario.as_path(), args.out_dir.as_path());
    if is_stdout(out_dir) {
        return Err(BadInput(
            "--out-dir: a curve is two files (CSV and SVG): name a folder, not '-'".into(),
        )
        .into());
    }
    if std::fs::metadata(out_dir).is_ok_and(|m| !m.is_dir()) {
        return Err(BadInput(format!(
            "--out-dir: {} is a file: name a folder (it is created if missing)",
            out_dir.display()
        ))
        .into());
    }
    let scenario = load(scenario_path)?;
    let drawn = nominal_curves(&scenario).map_err(|err| problem_of_file(scenario_path, err))?;
    if drawn.is_empty() {
        return Err(BadInput(format!(
            "{}: none of its models draws a curve (transmission_error and torsion_curve do)",
            scenario_path.display()
        ))
        .into());
    }
    std::fs::create_dir_all(out_dir).map_err(|err| {
        BadInput(format!(
            "--out-dir: cannot create {}: {err}",
            out_dir.display()
        ))
    })?;
    let mut lines = String::new();
    let mut staged = StagedOutputs::new();
    for (model, curves) in drawn {
        for curve in curves {
            let stem = out_dir.join(&curve.name);
            let (csv, svg) = (stem.with_extension("csv"), stem.with_extension("svg"));
            let drawn = rvtol_report::curve_svg(&curve)
                .map_err(|err| BadInput(format!("{}: {err}", svg.display())))?;
            staged.add(&csv, &rvtol_report::curve_csv(&curve))?;
            staged.add(&svg, &drawn)?;
            lines.push_str(&format!(
                "{model}: {} -> {}, {}\n",
                curve.title,
                csv.display(),
                svg.display()
            ));
        }
    }
    staged.add_stdout(&lines);
    staged.commit()
}
