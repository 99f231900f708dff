//! `rvtol fit`: a normal model (mean, shrunk covariance) of measured parts with normality
//! diagnostics, printed as the scenario fragment to paste.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::fit::{check_fragment, fit as fit_normal, fragment};
use rvtol_analysis::request::fit::{fit_columns, FitColumns};

use super::{outputs_ok, read_csv, target, whole_file_limit, CALLER};
use crate::output::{note, print, write_report, Format};
use crate::BadInput;

/// The arguments of `rvtol fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Measurements: CSV with a header naming each column (`name` or `name [unit]`;
    /// a `sample` column, the row index of a samples file, is left out); "-" reads
    /// standard input.
    pub measurements: PathBuf,
    /// Fit one 6-DOF part of this name: the columns are its du, dv, dw, dalpha,
    /// dbeta, dgamma (or NAME.du …), in any order.
    #[arg(long, value_name = "NAME")]
    pub part: Option<String>,
    /// Write the fragment to PATH instead of standard output.
    #[arg(short = 'o', long = "output", value_name = "PATH")]
    pub output: Option<PathBuf>,
}

/// `rvtol fit`: a normal model of measured parts, as a scenario fragment.
pub fn fit(args: FitArgs) -> Result<()> {
    let (path, part, output) = (
        args.measurements.as_path(),
        args.part.as_deref(),
        args.output.as_deref(),
    );
    outputs_ok(
        &[target("-o", output, Format::Json)],
        &[("the measurements", path.to_path_buf())],
    )?;
    let table = read_csv(path, whole_file_limit(), "MEASUREMENTS")?;
    // Diagnostics go to standard error once the fragment is written: a refused fit says
    // only why.
    let FitColumns {
        names,
        units,
        headings,
        rows,
        notes,
        ..
    } = fit_columns(&table, &path.display().to_string(), part, CALLER)
        .map_err(|refusal| BadInput(refusal.to_string()))?;
    let fitted =
        fit_normal(&names, &rows).map_err(|err| BadInput(format!("{}: {err}", path.display())))?;
    let source = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let value = fragment(&fitted, part, &units, &source);
    // What is printed must validate when pasted into a scenario.
    check_fragment(&fitted, &value, part, &headings)
        .map_err(|message| BadInput(format!("{}: {message}", path.display())))?;
    let text = serde_json::to_string_pretty(&value).expect("a fragment serialises") + "\n";
    match output {
        Some(out) => write_report(out, &text)?,
        None => print(&text)?,
    }
    // The diagnostics where a person reads them; the fragment stays clean for a pipe.
    for line in notes {
        note(&line);
    }
    note(&rvtol_analysis::fit::summary(&fitted, &source));
    let doubtful: Vec<&str> = fitted
        .names
        .iter()
        .zip(&fitted.anderson_darling)
        .filter(|(_, t)| t.is_some_and(|t| t.p_value < 0.05))
        .map(|(n, _)| n.as_str())
        .collect();
    if !doubtful.is_empty() {
        note(&format!(
            "warning: a normal is doubtful for {} (Anderson–Darling p < 0.05): consider another distribution, or resampling the measurements (`empirical`, scenarios/README.md)",
            doubtful.join(", ")
        ));
    }
    Ok(())
}
