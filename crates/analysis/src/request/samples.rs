//! The rows of a run or of `evaluate` as a file ([`SampleTable`]: every input and output of
//! every sample): CSV, or Parquet when the file's name ends in `.parquet`; the same table
//! gives the same bytes.

use std::path::Path;

use rvtol_engine::evaluate::SampleTable;
use rvtol_engine::Scenario;
use rvtol_models::OutputKind;

/// The row index column of `run --samples-out` and `evaluate`: not a measurement, `fit`
/// and `evaluate` leave it out.
pub const SAMPLE_INDEX: &str = "sample";

/// The table as the file `path` takes it: Parquet when its name ends in `.parquet`, else
/// CSV; the error (Parquet's) is one line.
pub fn sample_table_bytes(
    path: &Path,
    scenario: &Scenario,
    table: &SampleTable,
) -> Result<Vec<u8>, String> {
    let parquet = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("parquet"));
    if parquet {
        sample_parquet(scenario, table)
    } else {
        Ok(sample_csv(scenario, table).into_bytes())
    }
}

/// The sample table as CSV: a `sample` index column, then one column per input-space
/// column and one per output, headed `name [unit]` (an indicator `name [0/1]`, its flag); numbers in Rust's shortest form that
/// reads back to the same value (non-finite values as `NaN`, `inf`, `-inf`, which pandas
/// and polars read). The same table gives the same bytes.
pub fn sample_csv(scenario: &Scenario, table: &SampleTable) -> String {
    let quote = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut out = sample_headings(scenario)
        .iter()
        .map(|h| quote(h))
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    use std::fmt::Write;
    for r in 0..table.rows {
        let _ = write!(out, "{r}");
        let inputs = &table.inputs[r * table.n_inputs..(r + 1) * table.n_inputs];
        let outputs = &table.outputs[r * table.n_outputs..(r + 1) * table.n_outputs];
        for v in inputs.iter().chain(outputs) {
            let _ = write!(out, ",{v}");
        }
        out.push('\n');
    }
    out
}

/// The column headings of a sample table, as both file formats name them: `sample`, then
/// `name [unit]` for every input column and every output (an indicator's unit is `0/1`: its
/// value is the flag, whatever unit its share is shown in).
pub fn sample_headings(scenario: &Scenario) -> Vec<String> {
    let heading = |name: &str, unit: Option<&str>| match unit {
        Some(unit) if !unit.is_empty() => format!("{name} [{unit}]"),
        _ => name.to_string(),
    };
    let mut headings = vec!["sample".to_string()];
    headings.extend(
        scenario
            .columns
            .iter()
            .map(|c| heading(&c.name, c.unit.as_deref())),
    );
    headings.extend(scenario.outputs.iter().map(|o| {
        let unit = if o.kind == OutputKind::Indicator {
            "0/1"
        } else {
            &o.unit
        };
        heading(&o.name, Some(unit))
    }));
    headings
}

/// Rows per row group of a sample table's Parquet file.
const PARQUET_ROW_GROUP: usize = 1 << 20;

/// A sample table as a Parquet file: the columns and headings of [`sample_csv`], `sample`
/// as INT64 and every other column as DOUBLE (the exact values), plain encoding, no
/// compression, row groups of 2^20 rows; no timestamp, so the same table gives the same
/// bytes. pandas (with pyarrow), polars and DuckDB read it as it is.
pub fn sample_parquet(scenario: &Scenario, table: &SampleTable) -> Result<Vec<u8>, String> {
    use parquet::basic::{Compression, Repetition, Type as PhysicalType};
    use parquet::data_type::{DoubleType, Int64Type};
    use parquet::file::properties::{EnabledStatistics, WriterProperties};
    use parquet::file::writer::SerializedFileWriter;
    use parquet::schema::types::Type;
    use std::sync::Arc;

    let error = |err: parquet::errors::ParquetError| format!("Parquet: {err}");
    let headings = sample_headings(scenario);
    let fields = headings
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let physical = if i == 0 {
                PhysicalType::INT64
            } else {
                PhysicalType::DOUBLE
            };
            Type::primitive_type_builder(name, physical)
                .with_repetition(Repetition::REQUIRED)
                .build()
                .map(Arc::new)
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(error)?;
    let schema = Type::group_type_builder("rvtol_samples")
        .with_fields(fields)
        .build()
        .map_err(error)?;
    let properties = WriterProperties::builder()
        .set_created_by(format!("rvtol {}", env!("CARGO_PKG_VERSION")))
        .set_compression(Compression::UNCOMPRESSED)
        .set_dictionary_enabled(false)
        .set_statistics_enabled(EnabledStatistics::Chunk)
        .build();
    let mut writer = SerializedFileWriter::new(Vec::new(), Arc::new(schema), Arc::new(properties))
        .map_err(error)?;
    let mut start = 0;
    while start < table.rows || (table.rows == 0 && start == 0) {
        let end = (start + PARQUET_ROW_GROUP).min(table.rows);
        let mut group = writer.next_row_group().map_err(error)?;
        let mut column = 0;
        while let Some(mut writer) = group.next_column().map_err(error)? {
            if column == 0 {
                let index: Vec<i64> = (start as i64..end as i64).collect();
                writer
                    .typed::<Int64Type>()
                    .write_batch(&index, None, None)
                    .map_err(error)?;
            } else {
                let (values, width, j) = if column <= table.n_inputs {
                    (&table.inputs, table.n_inputs, column - 1)
                } else {
                    (&table.outputs, table.n_outputs, column - 1 - table.n_inputs)
                };
                let data: Vec<f64> = (start..end).map(|r| values[r * width + j]).collect();
                writer
                    .typed::<DoubleType>()
                    .write_batch(&data, None, None)
                    .map_err(error)?;
            }
            writer.close().map_err(error)?;
            column += 1;
        }
        group.close().map_err(error)?;
        if table.rows == 0 {
            break;
        }
        start = end;
    }
    writer.into_inner().map_err(error)
}
