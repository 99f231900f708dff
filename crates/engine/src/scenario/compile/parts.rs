//! The `parts` section: each part's 6-DOF deviation (mean with a covariance, standard
//! deviations with a correlation, or a tolerance band, 001 Eq. 9–12), in its `units`
//! converted to the models' mm and rad, added to the input space as six named columns
//! `part.du` … `part.dgamma`, and one error source.

use rvtol_deviation::{unit_scale, PartSpec, SixDof};

use super::super::file::PartFile;
use super::super::{ColumnInfo, ColumnLaw, InputGroup};
use super::{check_name, Compiler};
use crate::error::ScenarioError;

/// Compiles every part.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    for (i, part) in &file.parts {
        let path = format!("parts[{i}]");
        let spec =
            check_name(&format!("{path}.name"), &part.name).and_then(|()| part_spec(&path, part));
        let spec = match spec {
            Ok(spec) => spec,
            Err(err) => {
                compiler.report(Err(err));
                compiler.broken.insert(part.name.clone());
                for component in SixDof::NAMES {
                    compiler.broken.insert(format!("{}.{component}", part.name));
                }
                continue;
            }
        };
        let first = compiler.builder.add_part(&path, &spec);
        compiler.sources.push(InputGroup {
            name: part.name.clone(),
            columns: (first..first + 6).collect(),
        });
        for (k, component) in SixDof::NAMES.iter().enumerate() {
            let sd = spec.covariance[k][k].sqrt();
            let info = ColumnInfo {
                name: format!("{}.{component}", part.name),
                unit: Some(SixDof::UNITS[k].to_string()),
                tolerance: [spec.mean[k] - 3.0 * sd, spec.mean[k] + 3.0 * sd],
                law: ColumnLaw {
                    name: "normal",
                    parameters: vec![("mean", spec.mean[k]), ("sd", sd)],
                    mean: spec.mean[k],
                    sd,
                },
            };
            let named = compiler.add_column(&format!("{path}.name"), info, first + k);
            compiler.report(named);
        }
    }
}

fn fixed_array<const N: usize>(path: &str, values: &[f64]) -> Result<[f64; N], ScenarioError> {
    values.try_into().map_err(|_| {
        ScenarioError::new(path, format!("expected {N} numbers, got {}", values.len()))
    })
}

fn fixed_matrix(path: &str, rows: &[Vec<f64>]) -> Result<[[f64; 6]; 6], ScenarioError> {
    if rows.len() != 6 {
        return Err(ScenarioError::new(
            path,
            format!(
                "expected 6 rows of 6 numbers (row-major), got {} rows",
                rows.len()
            ),
        ));
    }
    let mut matrix = [[0.0; 6]; 6];
    for (i, row) in rows.iter().enumerate() {
        matrix[i] = fixed_array::<6>(&format!("{path}[{i}]"), row)?;
    }
    Ok(matrix)
}

/// The factors from a part's `units` to the models' mm and rad, per component, and the
/// phrase its error messages add; (all 1, "") without `units`.
fn part_units(path: &str, part: &PartFile) -> Result<([f64; 6], String), ScenarioError> {
    let Some(units) = &part.units else {
        return Ok(([1.0; 6], String::new()));
    };
    if part.tolerance_band.is_some() {
        return Err(ScenarioError::new(
            format!("{path}.units"),
            "a tolerance_band part is given in mm (delta_tau_mm, length_mm); units apply to mean, sd and covariance",
        ));
    }
    let factor =
        |key: &str, unit: &Option<String>, model_unit: &str, kind: &str| match unit.as_deref() {
            None => Ok(1.0),
            Some(u) if u == model_unit => Ok(1.0),
            Some(u) => super::super::units::conversion(u, model_unit).ok_or_else(|| {
                ScenarioError::new(
                    format!("{path}.units.{key}"),
                    format!(
                        "{u:?} is not a unit of {kind} rvtol knows ({})",
                        super::super::units::known()
                    ),
                )
            }),
        };
    let t = factor("translation", &units.translation, "mm", "length")?;
    let r = factor("rotation", &units.rotation, "rad", "angle")?;
    let phrase = format!(
        " (converted from {} and {} to mm and rad)",
        units.translation.as_deref().unwrap_or("mm"),
        units.rotation.as_deref().unwrap_or("rad")
    );
    Ok(([t, t, t, r, r, r], phrase))
}

fn part_spec(path: &str, part: &PartFile) -> Result<PartSpec, ScenarioError> {
    let (factors, phrase) = part_units(path, part)?;
    part_spec_in_model_units(path, part, &factors).map_err(|err| ScenarioError {
        message: format!("{}{phrase}", err.message),
        ..err
    })
}

/// The part's spec with `mean`, `sd` and `covariance` multiplied by the unit factors (a
/// covariance entry by f_i·f_j).
fn part_spec_in_model_units(
    path: &str,
    part: &PartFile,
    factors: &[f64; 6],
) -> Result<PartSpec, ScenarioError> {
    let forms = [
        part.covariance.is_some(),
        part.sd.is_some() || part.correlation.is_some(),
        part.tolerance_band.is_some(),
    ];
    if forms.iter().filter(|f| **f).count() != 1 {
        return Err(ScenarioError::new(
            path,
            "give exactly one of: mean + covariance, mean + sd + correlation, tolerance_band",
        ));
    }
    if let Some(band) = &part.tolerance_band {
        if part.mean.is_some() {
            return Err(ScenarioError::new(
                format!("{path}.mean"),
                "a tolerance_band part derives its mean (001 Eq. 10); remove mean",
            ));
        }
        return Ok(PartSpec::from_tolerance_band(
            &format!("{path}.tolerance_band"),
            band.delta_tau_mm,
            band.length_mm,
            band.constraint_eq11,
        )?);
    }
    let mean_path = format!("{path}.mean");
    let mut mean = match &part.mean {
        Some(m) => fixed_array::<6>(&mean_path, m)?,
        None => [0.0; 6],
    };
    for (x, &f) in mean.iter_mut().zip(factors) {
        *x = unit_scale(*x, f);
    }
    if let Some(covariance) = &part.covariance {
        let mut covariance = fixed_matrix(&format!("{path}.covariance"), covariance)?;
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = unit_scale(unit_scale(*x, factors[i]), factors[j]);
            }
        }
        return Ok(PartSpec::from_covariance(path, mean, covariance)?);
    }
    let sd = part.sd.as_deref().ok_or_else(|| {
        ScenarioError::new(format!("{path}.sd"), "sd is required with correlation")
    })?;
    let mut sd = fixed_array::<6>(&format!("{path}.sd"), sd)?;
    for (x, &f) in sd.iter_mut().zip(factors) {
        *x = unit_scale(*x, f);
    }
    let correlation = match &part.correlation {
        Some(c) => fixed_matrix(&format!("{path}.correlation"), c)?,
        None => std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 })),
    };
    Ok(PartSpec::from_correlation(path, mean, sd, correlation)?)
}
