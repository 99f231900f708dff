//! CSV tables of numbers with a header: the rows `rvtol evaluate` runs, the measurements
//! `rvtol fit` reads and the data columns of an `empirical` distribution. A heading
//! `name [unit]` gives a column's name and unit; every problem is one line naming the
//! file, the line and the column.

use std::borrow::Cow;
use std::path::Path;

use super::input_file::{read_text, ReadLimit};

/// A CSV file of numbers with a header: its columns as (name, unit) from `name [unit]`,
/// and its rows with their line numbers.
pub struct CsvTable<'a> {
    /// The file, for messages.
    pub path: &'a Path,
    /// (name, unit) per column, in file order.
    pub columns: Vec<(String, Option<String>)>,
    /// The records with their line numbers.
    pub rows: Vec<(u64, csv::StringRecord)>,
}

impl<'a> CsvTable<'a> {
    /// Reads a CSV file of numbers with a header (no column twice), of at most
    /// `limit.bytes` ([`super::input_file`]); the error is one line.
    pub fn read(path: &'a Path, limit: &ReadLimit) -> Result<CsvTable<'a>, String> {
        let text = read_text(path, limit)?;
        CsvTable::parse(path, &text)
    }

    /// [`CsvTable::read`] on a text already read; `path` names it in messages.
    pub fn parse(path: &'a Path, text: &str) -> Result<CsvTable<'a>, String> {
        // Line ends of Windows exports: the reader would count the lines of a CRLF file
        // one short. (A copy only of a text that has them.)
        let text = if text.contains('\r') {
            Cow::Owned(text.replace("\r\n", "\n"))
        } else {
            Cow::Borrowed(text)
        };
        let at = |line: u64| format!("{}: line {line}", path.display());
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let columns: Vec<(String, Option<String>)> = reader
            .headers()
            .map_err(|err| format!("{}: {err}", at(1)))?
            .iter()
            .map(|heading| match heading.rsplit_once(" [") {
                Some((name, unit)) if unit.ends_with(']') => (
                    name.to_string(),
                    Some(rvtol_engine::scenario::units::canonical(
                        unit.trim_end_matches(']'),
                    )),
                ),
                _ => (heading.to_string(), None),
            })
            .collect();
        if columns.len() == 1 && columns[0].0.contains(';') {
            return Err(format!(
                "{}: the columns are separated by ';': rvtol reads comma-separated values (',' between columns, '.' in decimals)",
                at(1)
            ));
        }
        if let Some((i, _)) = columns
            .iter()
            .enumerate()
            .find(|(i, (n, _))| columns[..*i].iter().any(|(m, _)| m == n))
        {
            return Err(format!(
                "{}: column '{}' appears twice",
                at(1),
                columns[i].0
            ));
        }
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|err| {
                let line = err.position().map_or(0, |p| p.line());
                format!("{}: {err}", at(line))
            })?;
            rows.push((record.position().map_or(0, |p| p.line()), record));
        }
        Ok(CsvTable {
            path,
            columns,
            rows,
        })
    }

    /// "FILE: line N", for messages.
    pub fn at(&self, line: u64) -> String {
        format!("{}: line {line}", self.path.display())
    }

    /// Cell `i` of `record` (on `line`) as a finite number, or one line saying why not.
    pub fn number(&self, line: u64, record: &csv::StringRecord, i: usize) -> Result<f64, String> {
        let cell = record.get(i).unwrap_or("");
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!(
                "{}, column '{}': not a finite number: '{cell}'",
                self.at(line),
                self.columns[i].0
            )),
        }
    }

    /// The column names, in file order.
    pub fn names(&self) -> Vec<&str> {
        self.columns.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// The numbers of the column `name`, empty cells left out (a column of a table whose
    /// columns have different lengths); `None` when there is no such column.
    pub fn column(&self, name: &str) -> Option<Result<Vec<f64>, String>> {
        let i = self.columns.iter().position(|(n, _)| n == name)?;
        let values = self
            .rows
            .iter()
            .filter(|(_, record)| !record.get(i).unwrap_or("").is_empty())
            .map(|(line, record)| self.number(*line, record, i))
            .collect();
        Some(values)
    }
}
