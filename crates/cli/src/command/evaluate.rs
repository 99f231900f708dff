//! `rvtol evaluate`: the scenario's models on given input rows (a CSV with a column per
//! input), the rows with their outputs as CSV or Parquet.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use rvtol_analysis::request::evaluate::{input_rows, rows_limit};
use rvtol_analysis::request::memory;

use super::{
    check_memory, load, outputs_ok, problem_of_file, read_csv, sample_table_bytes, scenario_inputs,
    target, thread_pool, threads, Execution, CALLER,
};
use crate::output::{is_stdout, note, print, write_bytes, Format};
use crate::BadInput;

/// The arguments of `rvtol evaluate`.
#[derive(Debug, Args)]
pub struct EvaluateArgs {
    /// Scenario file (JSON; "-" reads standard input).
    pub scenario: PathBuf,
    /// Input rows: CSV with a header naming every input column (`rvtol run
    /// --samples-out` writes one; a `[unit]` after a name, a `sample` column and
    /// output columns are allowed).
    #[arg(long, value_name = "CSV")]
    pub inputs: PathBuf,
    /// Write the rows with their outputs to PATH instead of standard output (PATH ends
    /// in .csv or .parquet, which chooses the format).
    #[arg(short = 'o', long = "output", value_name = "PATH")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub execution: Execution,
}

/// `rvtol evaluate`: the models on the rows of a CSV.
pub fn evaluate(args: EvaluateArgs) -> Result<()> {
    let (scenario_path, inputs_path) = (args.scenario.as_path(), args.inputs.as_path());
    let (output, execution) = (args.output.as_deref(), &args.execution);
    if is_stdout(scenario_path) && is_stdout(inputs_path) {
        return Err(BadInput(
            "--inputs: standard input ('-') already gives the scenario: name the rows' file".into(),
        )
        .into());
    }
    let mut inputs = scenario_inputs(scenario_path);
    inputs.push(("the input rows", inputs_path.to_path_buf()));
    outputs_ok(&[target("-o", output, Format::Table)], &inputs)?;
    let scenario = load(scenario_path)?;
    // What evaluating the rows takes, from the file's size before it is read; a pipe or
    // standard input is cut where the rows would exceed the memory.
    let threads = threads(execution)?;
    if let Some(metadata) = std::fs::metadata(inputs_path)
        .ok()
        .filter(|_| !is_stdout(inputs_path))
    {
        if metadata.is_file() {
            let need = memory::table_evaluation(
                &scenario,
                metadata.len(),
                &inputs_path.display().to_string(),
            );
            check_memory(need, execution, "evaluate", threads)?;
        }
    }
    let rows_limit = rows_limit(&scenario, execution.max_memory, threads, CALLER);
    let table = read_csv(inputs_path, &rows_limit, "--inputs")?;
    let values = input_rows(&table, &inputs_path.display().to_string(), &scenario)
        .map_err(|refusal| BadInput(refusal.to_string()))?;
    let pool = thread_pool(threads)?;
    let rows = pool.install(|| rvtol_engine::evaluate::evaluate_rows(&scenario, values));
    // Rows the models could not evaluate are lost data, as a run's samples: counted and
    // reported, and beyond --max-non-finite a failure that writes no table.
    let row = |r: usize| table.at(table.rows[r].0);
    rvtol_engine::evaluate::check_non_finite_rows(&scenario, &rows, execution.max_non_finite, &row)
        .map_err(|err| problem_of_file(scenario_path, err))?;
    let lost = rvtol_engine::evaluate::non_finite_rows(&scenario, &rows);
    for (o, line) in rvtol_engine::evaluate::non_finite_lines(&scenario, &rows, &lost, &row) {
        note(&format!(
            "warning: {}: {line}, within the allowed {} % (--max-non-finite): written as NaN",
            scenario.model_of_output(o),
            rvtol_deviation::Shown(100.0 * execution.max_non_finite)
        ));
    }
    match output {
        Some(path) => write_bytes(path, &sample_table_bytes(path, &scenario, &rows)?),
        None => print(&rvtol_analysis::request::samples::sample_csv(
            &scenario, &rows,
        )),
    }
}
