//! `rvtol fit`'s columns: which columns of a table of measurements are fitted, in what
//! order, with their units, and the rows of numbers ([`fit_columns`]). A part's six columns
//! (`NAME.du` … `NAME.dgamma`, or bare `du` … in a file of one part) are taken in component
//! order, its translations in one unit and its rotations in one; without a part every
//! column is a variable. The index column of a sample table is left out.

use std::collections::BTreeSet;

use super::samples::SAMPLE_INDEX;
use super::table::CsvTable;
use super::{Caller, Refusal};
use crate::fit::PART_COMPONENTS;

/// The columns a fit takes, their rows and what was left out.
#[derive(Debug, Clone, PartialEq)]
pub struct FitColumns {
    /// Index of each fitted column in the table, in fitting order.
    pub order: Vec<usize>,
    /// Their names.
    pub names: Vec<String>,
    /// Their units, as headed.
    pub units: Vec<Option<String>>,
    /// Their headings as written (`name [unit]`).
    pub headings: Vec<String>,
    /// The rows, the fitted columns' numbers in order.
    pub rows: Vec<Vec<f64>>,
    /// What a person should know: columns left out.
    pub notes: Vec<String>,
}

/// The columns of `table` (the file `shown` as the notes name it) a fit of `part` (or of every
/// column as variables) takes.
pub fn fit_columns(
    table: &CsvTable,
    shown: &str,
    part: Option<&str>,
    caller: Caller,
) -> Result<FitColumns, Refusal> {
    let mut notes = Vec::new();
    let names = table.names();
    // A part's columns in its component order.
    let order: Vec<usize> = match part {
        Some(name) => {
            if name.is_empty()
                || !name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                return Err(Refusal::option(
                    caller,
                    "part",
                    format!("'{name}' is not a part name (letters, digits, _ and -)"),
                ));
            }
            let prefix = format!("{name}.");
            let component = |n: &str| n.strip_prefix(&prefix).unwrap_or(n).to_string();
            // A file with columns `NAME.du` … (several parts, a sample file, an export
            // with serial numbers) gives the part those six; a file of bare `du` … must
            // hold nothing else.
            let qualified = names.iter().any(|n| n.starts_with(&prefix));
            let ignored: Vec<&str> = names
                .iter()
                .filter(|n| (qualified && !n.starts_with(&prefix)) || **n == SAMPLE_INDEX)
                .copied()
                .collect();
            if !ignored.is_empty() {
                let left_out = if ignored.len() > 6 {
                    format!("{}, … ({} in all)", ignored[..5].join(", "), ignored.len())
                } else {
                    ignored.join(", ")
                };
                notes.push(format!(
                    "{shown}: fitting {name}.du … {name}.dgamma; other columns left out: {left_out}"
                ));
            }
            // Columns of other parts but none of this one: most likely a misspelt name.
            let parts: BTreeSet<&str> = names
                .iter()
                .filter_map(|n| n.split_once('.'))
                .filter(|(_, c)| PART_COMPONENTS.contains(c))
                .map(|(p, _)| p)
                .collect();
            if !qualified && !parts.is_empty() {
                return Err(Refusal::Input(format!(
                    "{}: no columns {name}.du … {name}.dgamma (the file has the parts {})",
                    table.at(1),
                    parts.into_iter().collect::<Vec<_>>().join(", ")
                )));
            }
            if let Some(other) = names
                .iter()
                .find(|n| !ignored.contains(n) && !PART_COMPONENTS.contains(&component(n).as_str()))
            {
                return Err(Refusal::Input(format!(
                    "{}: column '{other}' is not a component of part {name} ({})",
                    table.at(1),
                    PART_COMPONENTS.join(", ")
                )));
            }
            let mut order = Vec::new();
            for c in PART_COMPONENTS {
                match names.iter().position(|n| component(n) == c) {
                    Some(i) => order.push(i),
                    None => {
                        return Err(Refusal::Input(format!(
                            "{}: no column for {name}.{c} (a part needs all six components)",
                            table.at(1)
                        )))
                    }
                }
            }
            order
        }
        None => (0..names.len())
            .filter(|&i| names[i] != SAMPLE_INDEX)
            .collect(),
    };
    let mut rows = Vec::with_capacity(table.rows.len());
    for (line, record) in &table.rows {
        rows.push(
            order
                .iter()
                .map(|&i| table.number(*line, record, i).map_err(Refusal::Input))
                .collect::<Result<Vec<f64>, Refusal>>()?,
        );
    }
    let names: Vec<String> = order.iter().map(|&i| table.columns[i].0.clone()).collect();
    let units: Vec<Option<String>> = order.iter().map(|&i| table.columns[i].1.clone()).collect();
    if part.is_some() {
        // A part's translations share one unit, its rotations one.
        for (kind, range) in [("translation", 0..3), ("rotation", 3..6)] {
            let first = &units[range.start];
            if units[range.clone()].iter().any(|u| u != first) {
                return Err(Refusal::Input(format!(
                    "{}: the {kind} columns of the part are in different units ({}); give them one",
                    table.at(1),
                    units[range]
                        .iter()
                        .map(|u| u.as_deref().unwrap_or("none"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
    }
    let headings: Vec<String> = order
        .iter()
        .map(|&i| match &table.columns[i] {
            (name, Some(unit)) => format!("{name} [{unit}]"),
            (name, None) => name.clone(),
        })
        .collect();
    Ok(FitColumns {
        order,
        names,
        units,
        headings,
        rows,
        notes,
    })
}
