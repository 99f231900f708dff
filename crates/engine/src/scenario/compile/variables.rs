//! The `variables` section: each scalar error parameter's law ([`super::distributions`]),
//! written in its `unit` and converted at load time to the unit of the model inputs it
//! feeds; a variable with `count` is an array of members `name_1` … `name_N`, each a
//! column of its own, one error source together.

use std::collections::BTreeSet;

use super::super::file::{VariableFile, MAX_ARRAY_MEMBERS};
use super::super::{ColumnInfo, ColumnLaw, InputGroup};
use super::distributions::distribution;
use super::{check_name, Compiler};
use crate::error::ScenarioError;

/// Compiles every variable, then checks that no column takes an array's name.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    for (i, variable) in &file.variables {
        let path = format!("variables[{i}]");
        // Checked in the unit the file gives, which the messages name.
        let in_unit = |err: ScenarioError| match &variable.unit {
            Some(unit)
                if !unit.is_empty()
                    && !err.path.ends_with(".cp")
                    && !err.path.ends_with(".empirical") =>
            {
                ScenarioError {
                    message: format!("{} (values in {unit})", err.message),
                    ..err
                }
            }
            _ => err,
        };
        let members = array_members(&path, variable);
        let checked = check_name(&format!("{path}.name"), &variable.name)
            .and_then(|()| members.as_ref().map(|_| ()).map_err(Clone::clone))
            .and_then(|()| {
                distribution(&format!("{path}.distribution"), &variable.distribution)
                    .map_err(in_unit)
            })
            .and_then(|(dist, kind)| {
                dist.validate(&format!("{path}.distribution.{kind}"))
                    .map(|()| dist)
                    .map_err(|err| in_unit(ScenarioError::from(err)))
            })
            .and_then(|dist| {
                // The inputs bound to the variable: by its name, or by a member's.
                let names =
                    std::iter::once(&variable.name).chain(members.iter().flatten().flatten());
                let bound: Vec<(String, String)> = names
                    .filter_map(|name| compiler.bound_units.get(name))
                    .flatten()
                    .cloned()
                    .collect();
                let conversion = match &variable.unit {
                    Some(unit) => variable_conversion(&path, unit, &bound)?,
                    None => None,
                };
                Ok(match conversion {
                    Some((factor, unit)) => (dist.scaled(factor), Some(unit)),
                    None => (dist, variable.unit.clone()),
                })
            });
        let (dist, unit) = match checked {
            Ok(dist) => dist,
            Err(err) => {
                compiler.report(Err(err));
                compiler.broken.insert(variable.name.clone());
                compiler
                    .broken
                    .extend(members.into_iter().flatten().flatten());
                continue;
            }
        };
        let names = match members {
            Ok(Some(members)) => members,
            _ => vec![variable.name.clone()],
        };
        let mut group = Vec::with_capacity(names.len());
        for name in names {
            let column = compiler.builder.add_scalar(&path, dist.clone());
            group.push(column);
            let info = ColumnInfo {
                name,
                unit: unit.clone(),
                tolerance: dist.tolerance_limits(),
                law: column_law(&dist),
            };
            let named = compiler.add_column(&format!("{path}.name"), info, column);
            compiler.report(named);
        }
        if variable.count.is_some() {
            compiler
                .arrays
                .insert(variable.name.clone(), (path.clone(), group.clone()));
        }
        compiler.sources.push(InputGroup {
            name: variable.name.clone(),
            columns: group,
        });
    }
    // An array's name is not a column, but it names its source: no column may take it.
    let taken: Vec<ScenarioError> = (compiler.arrays.iter())
        .filter(|(name, _)| compiler.column_by_name.contains_key(*name))
        .map(|(name, (path, _))| {
            ScenarioError::new(
                format!("{path}.name"),
                format!("name {name:?} is used twice (by this array and by a variable or part component)"),
            )
        })
        .collect();
    compiler.problems.extend(taken);
}

/// The factor and unit a variable written in `unit` is converted to at load time
/// ([`super::units`]): when every input it is bound to wants one unit of the same kind,
/// other than its own. An error when it feeds both such an input and one of any unit.
fn variable_conversion(
    path: &str,
    unit: &str,
    bound: &[(String, String)],
) -> Result<Option<(f64, String)>, ScenarioError> {
    let targets: BTreeSet<&str> = bound
        .iter()
        .map(|(u, _)| u.as_str())
        .filter(|u| *u != "any")
        .collect();
    let [target] = targets.into_iter().collect::<Vec<_>>()[..] else {
        return Ok(None);
    };
    let Some(factor) = super::super::units::conversion(unit, target) else {
        return Ok(None);
    };
    if let Some((_, any_path)) = bound.iter().find(|(u, _)| u == "any") {
        return Err(ScenarioError::new(
            format!("{path}.unit"),
            format!(
                "a variable in {unit} would be converted to {target} for the inputs that want {target} but not for {any_path}, which takes any unit: write it in {target}"
            ),
        ));
    }
    Ok(Some((factor, target.to_string())))
}

/// The member names of a variable array (`name_1` … `name_N` for `count` N), `None` for a
/// plain variable.
fn array_members(
    path: &str,
    variable: &VariableFile,
) -> Result<Option<Vec<String>>, ScenarioError> {
    match variable.count {
        None => Ok(None),
        Some(n) if (1..=MAX_ARRAY_MEMBERS).contains(&n) => Ok(Some(
            (1..=n).map(|k| format!("{}_{k}", variable.name)).collect(),
        )),
        Some(n) => Err(ScenarioError::new(
            format!("{path}.count"),
            format!("an array has 1 to {MAX_ARRAY_MEMBERS} members, got {n}"),
        )),
    }
}

/// The record of a variable's law.
fn column_law(dist: &rvtol_deviation::ScalarDistribution) -> ColumnLaw {
    let (name, parameters) = dist.law();
    ColumnLaw {
        name,
        parameters,
        mean: dist.mean(),
        sd: dist.variance().sqrt(),
    }
}
