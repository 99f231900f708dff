//! `rvtol evaluate`'s rows: the scenario's input columns found by their headings in a
//! table of rows (as `run --samples-out` writes it: the index and the outputs may be
//! there too, nothing else), each converted from its heading's unit into the input's, as
//! one row-major block ([`input_rows`]), read within what the memory allows
//! ([`rows_limit`]).

use rvtol_deviation::human_bytes;
use rvtol_engine::evaluate::check_table_rows;
use rvtol_engine::scenario::units;
use rvtol_engine::Scenario;

use super::input_file::ReadLimit;
use super::machine::memory_budget;
use super::memory;
use super::samples::SAMPLE_INDEX;
use super::table::CsvTable;
use super::{Caller, Refusal};

/// The rows of `table` (the file `shown` as messages name it) as the scenario's input
/// columns, row-major.
pub fn input_rows(table: &CsvTable, shown: &str, scenario: &Scenario) -> Result<Vec<f64>, Refusal> {
    let names = table.names();
    let known_other =
        |name: &str| name == SAMPLE_INDEX || scenario.outputs.iter().any(|o| o.name == name);
    // Where each input column is in the file.
    let mut position = Vec::with_capacity(scenario.columns.len());
    let mut missing = Vec::new();
    for column in &scenario.columns {
        match names.iter().position(|n| *n == column.name) {
            Some(i) => position.push(i),
            None => missing.push(column.name.clone()),
        }
    }
    if !missing.is_empty() {
        return Err(Refusal::Input(format!(
            "{}: no column for the input{} {} (the header names every input column of the scenario, as `rvtol run --samples-out` writes it)",
            table.at(1),
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        )));
    }
    if let Some(unknown) = names
        .iter()
        .find(|n| !known_other(n) && !scenario.columns.iter().any(|c| c.name == **n))
    {
        return Err(Refusal::Input(format!(
            "{}: column '{unknown}' is neither an input nor an output of the scenario",
            table.at(1)
        )));
    }
    let n_inputs = scenario.columns.len();
    check_table_rows(scenario, table.rows.len() as u64)
        .map_err(|message| Refusal::Input(format!("{shown}: {message}; split the file")))?;
    // A heading's unit is the column's: converted into the scenario's unit of that input
    // (µm into mm), refused when it cannot be (another kind, or a unit rvtol does not know).
    let mut factor = Vec::with_capacity(position.len());
    for (column, &i) in scenario.columns.iter().zip(&position) {
        factor.push(match (&table.columns[i].1, &column.unit) {
            (Some(given), Some(wanted)) if given != wanted => {
                units::conversion(given, wanted).ok_or_else(|| {
                    Refusal::Input(format!(
                        "{}: column '{} [{given}]' is in {given}, but the input is in {wanted} and {given} does not convert to it (units rvtol knows: {})",
                        table.at(1),
                        column.name,
                        units::known()
                    ))
                })?
            }
            _ => 1.0,
        });
    }
    let mut values = Vec::with_capacity(table.rows.len() * n_inputs);
    for (line, record) in &table.rows {
        for (&i, &f) in position.iter().zip(&factor) {
            let value = table.number(*line, record, i).map_err(Refusal::Input)?;
            values.push(if f == 1.0 { value } else { value * f });
        }
    }
    if values.is_empty() {
        return Err(Refusal::Input(format!("{shown}: no rows")));
    }
    Ok(values)
}

/// The bound of the rows `evaluate` reads: what the memory budget (`max_memory` or what the
/// machine has, within the process's limits, with `threads` workers) allows for rows read,
/// evaluated and written out ([`memory::table_evaluation_factor`] bytes per byte of the
/// file). A file is checked against it before it is read (`memory::table_evaluation`); a
/// pipe or standard input is cut at it.
pub fn rows_limit(
    scenario: &Scenario,
    max_memory: Option<f64>,
    threads: usize,
    caller: Caller,
) -> ReadLimit {
    let (budget, budget_source) = memory_budget(max_memory, threads, caller);
    ReadLimit {
        bytes: ((budget - memory::BASE_BYTES).max(0.0) / memory::table_evaluation_factor(scenario))
            as u64,
        source: format!(
            "what the {} of memory available ({budget_source}) allows for rows read, evaluated and written out; split the rows into smaller files",
            human_bytes(budget)
        ),
    }
}
