//! Data files a scenario refers to: the CSV column of an `empirical` distribution
//! (`{"empirical": {"csv": "pins.csv", "column": "radius_error"}}`) and a reducer defined in
//! a file of its own (`"reducer": {"file": "reducers/rv20e.json"}`, shared by the scenarios
//! of one reducer), read when the scenario is loaded from its file, with the path relative
//! to the scenario's folder.
//!
//! A column headed `name [unit]` gives the variable its unit when the variable names none;
//! a variable in another unit is an error (write it in the column's unit: it is converted
//! at load time like any variable).
//!
//! The numbers are written into the scenario text (`values`, with `source` naming the file
//! and column in place of `csv` and `column`; the reducer file's object in place of the
//! reference, with `file` kept to say where it came from), and that text is the scenario
//! from then on: a shard
//! carries it, `rvtol merge` and `rvtol allocate`'s scaled copies parse it, and none of
//! them reads the CSV again or sees a CSV that changed in between. A text without a CSV
//! reference is returned as it is, byte for byte.

use std::borrow::Cow;
use std::path::Path;

use serde_json::Value;

use rvtol_engine::scenario::{parse_value, units, ScenarioError};

use super::input_file::ReadLimit;
use super::table::CsvTable;

/// The scenario text with every CSV reference of an `empirical` distribution replaced by
/// the column's numbers; `base` is the folder relative paths start from. An unreadable
/// file, a missing column or a cell that is not a number is an error at the reference's
/// JSON path. Empty cells are skipped (columns of different lengths). Each file has at
/// most `limit.bytes` ([`super::input_file`]).
pub fn inline_data_files<'a>(
    text: &'a str,
    base: &Path,
    limit: &ReadLimit,
) -> Result<Cow<'a, str>, ScenarioError> {
    if !text.contains("\"csv\"") && !text.contains("\"file\"") {
        return Ok(Cow::Borrowed(text));
    }
    // A text that does not parse is left to the scenario parser, which says where.
    let Ok(mut document) = parse_value(text) else {
        return Ok(Cow::Borrowed(text));
    };
    let mut changed = inline_reducer_file(&mut document, base, limit)?;
    if let Some(Value::Array(variables)) = document.get_mut("variables") {
        for (i, variable) in variables.iter_mut().enumerate() {
            let at = format!("variables[{i}].distribution.empirical");
            let Some((file, column)) = csv_reference(&at, variable)? else {
                continue;
            };
            let path = base.join(&file);
            let table = CsvTable::read(&path, limit)
                .map_err(|message| ScenarioError::new(format!("{at}.csv"), message))?;
            let values = match table.column(&column) {
                None => {
                    return Err(ScenarioError::new(
                        format!("{at}.column"),
                        format!(
                            "{} has no column {column:?} (its columns: {})",
                            path.display(),
                            table.names().join(", ")
                        ),
                    ))
                }
                Some(values) => {
                    values.map_err(|message| ScenarioError::new(format!("{at}.csv"), message))?
                }
            };
            // The column's unit (`name [unit]`) is the variable's: adopted when the
            // variable names none, else it must be the same unit.
            let column_unit = table
                .columns
                .iter()
                .find(|(name, _)| *name == column)
                .and_then(|(_, unit)| unit.clone());
            if let Some(column_unit) = column_unit {
                let same = |a: &str, b: &str| a == b || units::conversion(a, b) == Some(1.0);
                match variable.get("unit").and_then(Value::as_str) {
                    None => variable["unit"] = Value::from(column_unit),
                    Some(unit) if same(unit, &column_unit) => {}
                    Some(unit) => {
                        return Err(ScenarioError::new(
                            format!("variables[{i}].unit"),
                            format!(
                                "{unit} differs from the unit of the column {column:?} of {}, {column_unit}: write the variable's unit as {column_unit} (it is converted at load time)",
                                path.display()
                            ),
                        ))
                    }
                }
            }
            if values.is_empty() {
                return Err(ScenarioError::new(
                    format!("{at}.column"),
                    format!(
                        "the column {column:?} of {} holds no numbers",
                        path.display()
                    ),
                ));
            }
            let count = values.len();
            let empirical = &mut variable["distribution"]["empirical"];
            if let Some(object) = empirical.as_object_mut() {
                object.remove("csv");
                object.remove("column");
                object.insert(
                    "source".into(),
                    Value::from(format!("{file}, column {column}: {count} values")),
                );
                object.insert("values".into(), Value::from(values));
            }
            changed = true;
        }
    }
    if !changed {
        return Ok(Cow::Borrowed(text));
    }
    let mut inlined = serde_json::to_string_pretty(&document).expect("a JSON value serialises");
    inlined.push('\n');
    Ok(Cow::Owned(inlined))
}

/// The keys a reducer file may hold (those of the scenario's `reducer` section but `file`).
const REDUCER_KEYS: [&str; 4] = ["name", "description", "params", "sources"];

/// Replaces a `reducer` section that names a file (`{"file": …}` and nothing else) by the
/// file's object with `file` kept; whether it did.
fn inline_reducer_file(
    document: &mut Value,
    base: &Path,
    limit: &ReadLimit,
) -> Result<bool, ScenarioError> {
    let Some(file) = reducer_reference(document)? else {
        return Ok(false);
    };
    let path = base.join(&file);
    let at = "reducer.file";
    let text = super::input_file::read_text(&path, limit)
        .map_err(|message| ScenarioError::new(at, message))?;
    let reducer = parse_value(&text).map_err(|err| {
        ScenarioError::new(
            at,
            format!("{} at {}: {}", path.display(), err.path, err.message),
        )
    })?;
    let Value::Object(mut reducer) = reducer else {
        return Err(ScenarioError::new(
            at,
            format!(
                "{} must hold a JSON object (name, description, params, sources)",
                path.display()
            ),
        ));
    };
    if let Some(key) = reducer.keys().find(|k| !REDUCER_KEYS.contains(&k.as_str())) {
        return Err(ScenarioError::new(
            at,
            format!(
                "{} has the key {key:?}; a reducer file holds {}",
                path.display(),
                REDUCER_KEYS.join(", ")
            ),
        ));
    }
    reducer.insert("file".into(), Value::from(file));
    document["reducer"] = Value::Object(reducer);
    Ok(true)
}

/// The file a `reducer` section names, when it names one; a section with `file` and
/// anything else is an error (a reducer is defined in one place).
fn reducer_reference(document: &Value) -> Result<Option<String>, ScenarioError> {
    let Some(Value::Object(section)) = document.get("reducer") else {
        return Ok(None);
    };
    let Some(file) = section.get("file") else {
        return Ok(None);
    };
    let Value::String(file) = file else {
        return Err(ScenarioError::new(
            "reducer.file",
            format!("expected the path of a reducer file, got {file}"),
        ));
    };
    // A section read in already (the file's object with `file` kept) is not read again.
    if section.contains_key("params") {
        return Ok(None);
    }
    if let Some(other) = section.keys().find(|k| *k != "file") {
        return Err(ScenarioError::new(
            format!("reducer.{other}"),
            "a reducer given by its file has nothing else here: the file defines it once",
        ));
    }
    Ok(Some(file.clone()))
}

/// The (file, column) of a variable's `empirical` distribution that names a CSV file and
/// has no `values` yet; `None` for every other variable.
/// The data files the scenario text refers to, relative paths joined to `base` (for the
/// checks that keep a command's outputs off its inputs); a text that does not parse, or a
/// malformed reference, names none (loading the scenario says what is wrong).
pub fn data_files(text: &str, base: &Path) -> Vec<std::path::PathBuf> {
    if !text.contains("\"csv\"") && !text.contains("\"file\"") {
        return Vec::new();
    }
    let Ok(document) = parse_value(text) else {
        return Vec::new();
    };
    let mut files: Vec<std::path::PathBuf> = reducer_reference(&document)
        .ok()
        .flatten()
        .map(|file| base.join(file))
        .into_iter()
        .collect();
    if let Some(Value::Array(variables)) = document.get("variables") {
        files.extend(
            variables
                .iter()
                .filter_map(|variable| csv_reference("", variable).ok().flatten())
                .map(|(file, _)| base.join(file)),
        );
    }
    files
}

fn csv_reference(at: &str, variable: &Value) -> Result<Option<(String, String)>, ScenarioError> {
    let Some(empirical) = variable
        .get("distribution")
        .and_then(|d| d.get("empirical"))
        .and_then(Value::as_object)
    else {
        return Ok(None);
    };
    if empirical.contains_key("values") {
        return Ok(None);
    }
    let Some(csv) = empirical.get("csv") else {
        return Ok(None);
    };
    let Value::String(file) = csv else {
        return Err(ScenarioError::new(
            format!("{at}.csv"),
            format!("expected the path of a CSV file, got {csv}"),
        ));
    };
    let Some(Value::String(column)) = empirical.get("column") else {
        return Err(ScenarioError::new(
            format!("{at}.column"),
            "name the CSV column that holds the measured values",
        ));
    };
    Ok(Some((file.clone(), column.clone())))
}
