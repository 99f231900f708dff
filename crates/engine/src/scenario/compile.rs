//! Validation of a parsed scenario file into a [`Scenario`]: every value checked once, every
//! problem collected with its JSON path ([`compile`]).

use std::collections::{BTreeMap, BTreeSet};

use rvtol_deviation::{
    index_list, unit_scale, EmpiricalLaw, InputSpaceBuilder, PartSpec, SamplingMethod,
    ScalarDistribution, Shown, SixDof, RAYLEIGH_QUANTILE,
};
use rvtol_models::{ConditionEffect, ErrorModel, ModelEntry, ModelParams, OutputKind, ParamValue};
use serde_json::Value;

use super::allocation::{compile_allocation, compile_levers, ToleranceKind, ToleranceSource};
use super::file::{
    DistributionFile, ModelFile, PartFile, ReducerFile, ScenarioFile, SpecFile, VariableFile,
    MAX_ARRAY_MEMBERS,
};
use super::{
    Binding, BoundModel, ColumnInfo, InputGroup, OutputInfo, Scenario, ScenarioError,
    DEFAULT_SAMPLES, DEFAULT_SEED,
};
use crate::chunk::Sampling;
use crate::stats::SpecLimits;

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

/// The file index of the variable named `name`, or of the array whose member it is
/// (`name_K`).
fn variable_index(file: &ScenarioFile, name: &str) -> Option<usize> {
    file.variables.iter().find_map(|(i, variable)| {
        let member = variable.count.is_some()
            && name
                .strip_prefix(variable.name.as_str())
                .and_then(|rest| rest.strip_prefix('_'))
                .is_some_and(|k| k.parse::<u64>().is_ok());
        (variable.name == name || member).then_some(*i)
    })
}

fn check_name(path: &str, name: &str) -> Result<(), ScenarioError> {
    let ok = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if ok {
        Ok(())
    } else {
        Err(ScenarioError::new(
            path,
            format!("name {name:?} must be non-empty and use only letters, digits, '_' and '-'"),
        ))
    }
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
            Some(u) => super::units::conversion(u, model_unit).ok_or_else(|| {
                ScenarioError::new(
                    format!("{path}.units.{key}"),
                    format!(
                        "{u:?} is not a unit of {kind} rvtol knows ({})",
                        super::units::known()
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

/// A part's tolerance as `rvtol allocate` reads it (see [`super::allocation`]).
fn part_tolerance(path: &str, part: &PartFile) -> ToleranceSource {
    let (kind, current, unit) = match &part.tolerance_band {
        Some(band) => (ToleranceKind::PartToleranceBand, band.delta_tau_mm, "mm"),
        None if part.covariance.is_some() => (ToleranceKind::PartCovariance, 1.0, ""),
        None => (ToleranceKind::PartSd, 1.0, ""),
    };
    ToleranceSource {
        name: part.name.clone(),
        path: path.to_string(),
        kind,
        current,
        unit: unit.to_string(),
    }
}

/// A variable's tolerance as `rvtol allocate` reads it (see [`super::allocation`]).
fn variable_tolerance(path: &str, variable: &VariableFile) -> ToleranceSource {
    let (kind, current) = match variable.distribution {
        DistributionFile::Normal { sd, .. } => (ToleranceKind::VariableNormal, 3.0 * sd),
        DistributionFile::ToleranceBand { lower, upper, .. } => {
            (ToleranceKind::VariableToleranceBand, 0.5 * (upper - lower))
        }
        DistributionFile::Uniform { lower, upper } => {
            (ToleranceKind::VariableUniform, 0.5 * (upper - lower))
        }
        DistributionFile::Triangular { lower, upper, .. } => {
            (ToleranceKind::VariableTriangular, 0.5 * (upper - lower))
        }
        DistributionFile::TruncatedNormal { sd, .. } => {
            (ToleranceKind::VariableTruncatedNormal, 3.0 * sd)
        }
        DistributionFile::FoldedNormal { lower, upper, .. } => {
            (ToleranceKind::VariableFoldedNormal, 0.5 * (upper - lower))
        }
        DistributionFile::Rayleigh { upper, .. } => (ToleranceKind::VariableRayleigh, upper),
        DistributionFile::Lognormal { .. } => (ToleranceKind::VariableLognormal, 1.0),
        DistributionFile::Empirical { .. } => (ToleranceKind::VariableEmpirical, 1.0),
    };
    // A factor has no unit.
    let unit = match kind {
        ToleranceKind::VariableLognormal | ToleranceKind::VariableEmpirical => String::new(),
        _ => variable.unit.clone().unwrap_or_default(),
    };
    ToleranceSource {
        name: variable.name.clone(),
        path: path.to_string(),
        kind,
        current,
        unit,
    }
}

/// The distribution a variable's file entry describes, and the key of its object; a
/// tolerance-style parameter that cannot give a distribution (Cp ≤ 0, a median ≤ 0) is an
/// error at `path` (the variable's `distribution`).
fn distribution(
    path: &str,
    d: &DistributionFile,
) -> Result<(ScalarDistribution, &'static str), ScenarioError> {
    let positive_cp = |kind: &str, cp: f64| {
        if cp > 0.0 {
            Ok(cp)
        } else {
            Err(ScenarioError::new(
                format!("{path}.{kind}.cp"),
                format!("process capability must be positive, got {}", Shown(cp)),
            ))
        }
    };
    Ok(match *d {
        DistributionFile::Empirical {
            ref values,
            ref csv,
            ref bandwidth,
            ..
        } => {
            let at = format!("{path}.empirical");
            if values.is_some() && csv.is_some() {
                return Err(ScenarioError::new(
                    &at,
                    "give the numbers in `values` or a CSV file in `csv` and `column`, not both (`source` may name where the values came from)",
                ));
            }
            let Some(values) = values else {
                return Err(match csv {
                    Some(_) => ScenarioError::new(
                        format!("{at}.csv"),
                        "a data file is read when the scenario is loaded from its file (its path is relative to the scenario's folder); a scenario given as text or a dict needs the numbers in `values`",
                    ),
                    None => ScenarioError::new(
                        &at,
                        "give the measured numbers in `values`, or a CSV file and its column in `csv` and `column`",
                    ),
                });
            };
            let bandwidth = match bandwidth {
                None => 0.0,
                Some(Value::String(rule)) if rule == "silverman" => {
                    EmpiricalLaw::silverman_bandwidth(values)
                }
                Some(Value::Number(h)) => h.as_f64().unwrap_or(f64::NAN),
                Some(other) => {
                    return Err(ScenarioError::new(
                        format!("{at}.bandwidth"),
                        format!("expected a number ≥ 0 (in the variable's unit) or \"silverman\", got {other}"),
                    ))
                }
            };
            (
                ScalarDistribution::Empirical(EmpiricalLaw::new(&at, values, bandwidth)?),
                "empirical",
            )
        }
        DistributionFile::Normal { mean, sd } => {
            (ScalarDistribution::Normal { mean, sd }, "normal")
        }
        DistributionFile::ToleranceBand {
            lower,
            upper,
            cp,
            mean_shift,
        } => (
            ScalarDistribution::ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            },
            "tolerance_band",
        ),
        DistributionFile::Uniform { lower, upper } => {
            (ScalarDistribution::Uniform { lower, upper }, "uniform")
        }
        DistributionFile::Triangular { lower, mode, upper } => (
            ScalarDistribution::Triangular { lower, mode, upper },
            "triangular",
        ),
        DistributionFile::TruncatedNormal {
            mean,
            sd,
            lower,
            upper,
        } => (
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            },
            "truncated_normal",
        ),
        DistributionFile::FoldedNormal {
            lower,
            upper,
            cp,
            mean_shift,
        } => {
            let cp = positive_cp("folded_normal", cp)?;
            if upper < lower {
                return Err(ScenarioError::new(
                    format!("{path}.folded_normal.upper"),
                    format!(
                        "upper limit {} is below lower limit {}",
                        Shown(upper),
                        Shown(lower)
                    ),
                ));
            }
            (
                ScalarDistribution::FoldedNormal {
                    mean: 0.5 * (lower + upper) + mean_shift,
                    sd: (upper - lower) / (6.0 * cp),
                },
                "folded_normal",
            )
        }
        DistributionFile::Rayleigh { upper, cp } => {
            let cp = positive_cp("rayleigh", cp)?;
            if upper < 0.0 {
                return Err(ScenarioError::new(
                    format!("{path}.rayleigh.upper"),
                    format!(
                        "a magnitude's upper tolerance must not be negative, got {}",
                        Shown(upper)
                    ),
                ));
            }
            (
                ScalarDistribution::Rayleigh {
                    sigma: upper / (RAYLEIGH_QUANTILE * cp),
                },
                "rayleigh",
            )
        }
        DistributionFile::Lognormal { median, upper, cp } => {
            let cp = positive_cp("lognormal", cp)?;
            if median <= 0.0 {
                return Err(ScenarioError::new(
                    format!("{path}.lognormal.median"),
                    format!("must be positive, got {}", Shown(median)),
                ));
            }
            if upper < median {
                return Err(ScenarioError::new(
                    format!("{path}.lognormal.upper"),
                    format!(
                        "the upper tolerance {} is below the median {}",
                        Shown(upper),
                        Shown(median)
                    ),
                ));
            }
            (
                ScalarDistribution::Lognormal {
                    mu: median.ln(),
                    sigma: (upper / median).ln() / (3.0 * cp),
                },
                "lognormal",
            )
        }
    })
}

pub(super) fn model_params(
    path: &str,
    map: &serde_json::Map<String, serde_json::Value>,
) -> Result<ModelParams, ScenarioError> {
    let mut params = ModelParams::new();
    for (key, value) in map {
        let value = match value {
            serde_json::Value::Number(n) => ParamValue::Number(n.as_f64().unwrap_or(f64::NAN)),
            serde_json::Value::String(s) => ParamValue::Text(s.clone()),
            serde_json::Value::Object(entries) => {
                let mut named = Vec::with_capacity(entries.len());
                for (name, v) in entries {
                    let number = v.as_f64().ok_or_else(|| {
                        ScenarioError::new(
                            format!("{path}.{key}.{name}"),
                            format!("expected a number, got {v}"),
                        )
                    })?;
                    named.push((name.clone(), number));
                }
                ParamValue::Named(named)
            }
            other => {
                return Err(ScenarioError::new(
                    format!("{path}.{key}"),
                    format!("expected a number, a string or an object of numbers, got {other}"),
                ))
            }
        };
        params.insert(key.clone(), value);
    }
    Ok(params)
}

/// A `*` pattern of a model's `inputs` (`"pin_radial_error_mm_*"`) split at its star; `None`
/// for a plain input name.
fn pattern(key: &str) -> Option<(&str, &str)> {
    key.split_once('*')
}

/// A positive index written without leading zeros (`7`, `40`; not `07`, `0`, `x`): what a
/// pattern's star and a family's trailing `_N` stand for.
pub(super) fn positive_index(digits: &str) -> Option<u64> {
    let ok = !digits.is_empty()
        && !digits.starts_with('0')
        && digits.bytes().all(|b| b.is_ascii_digit());
    ok.then(|| digits.parse().ok()).flatten()
}

/// A name's stem and trailing index (`pin_radial_error_mm_7` → (`pin_radial_error_mm`, 7)).
pub(super) fn trailing_index(name: &str) -> Option<(&str, u64)> {
    let (stem, digits) = name.rsplit_once('_')?;
    Some((stem, positive_index(digits)?))
}

/// The index an input name gives a pattern's star: the digits between its prefix and
/// suffix ([`positive_index`]).
fn pattern_index(prefix: &str, suffix: &str, input: &str) -> Option<u64> {
    positive_index(input.strip_prefix(prefix)?.strip_suffix(suffix)?)
}

/// How a model input is bound in the file: the bound value, the binding's JSON path, and
/// the star's index when a `*` pattern binds it.
struct InputBinding<'a> {
    value: &'a serde_json::Value,
    path: String,
    /// The `*` pattern that binds the input and the index its star stands for.
    pattern: Option<(&'a str, u64)>,
}

/// The binding of a model input: by its own key, or by the one `*` pattern that matches
/// it. An input bound twice (its own key and a pattern, or two patterns) is an error
/// naming both.
fn input_binding<'a>(
    path: &str,
    inputs: &'a serde_json::Map<String, serde_json::Value>,
    input: &str,
) -> Result<Option<InputBinding<'a>>, ScenarioError> {
    let mut found = inputs.get(input).map(|value| InputBinding {
        value,
        path: format!("{path}.inputs.{input}"),
        pattern: None,
    });
    for (key, value) in inputs {
        let Some((prefix, suffix)) = pattern(key) else {
            continue;
        };
        let Some(index) = pattern_index(prefix, suffix, input) else {
            continue;
        };
        let key_path = format!("{path}.inputs.{key}");
        if let Some(earlier) = &found {
            return Err(ScenarioError::new(
                key_path,
                format!("binds {input:?}, which {} binds already", earlier.path),
            ));
        }
        found = Some(InputBinding {
            value,
            path: key_path,
            pattern: Some((key.as_str(), index)),
        });
    }
    Ok(found)
}

/// A model of the file built from its parameters, or the problem (with its JSON path) that
/// kept it from building. Built once: the units of its inputs serve the variables' unit
/// conversion, before the model's bindings are checked.
type BuiltModel = Result<(&'static ModelEntry, Box<dyn ErrorModel>), ScenarioError>;

fn build_model(path: &str, model_file: &ModelFile, reducer: Option<&ReducerFile>) -> BuiltModel {
    let Some(entry) = rvtol_models::find(&model_file.model) else {
        let known: Vec<&str> = rvtol_models::all().iter().map(|e| e.name).collect();
        return Err(ScenarioError::new(
            format!("{path}.model"),
            format!(
                "unknown model {:?}; known models: {}",
                model_file.model,
                known.join(", ")
            ),
        ));
    };
    let mut params = model_params(&format!("{path}.params"), &model_file.params)?;
    // The reducer's parameters this model knows, unless it gives them itself (an error:
    // a reducer is defined once).
    let mut shared = BTreeSet::new();
    if let Some(reducer) = reducer {
        let given = model_params("reducer.params", &reducer.params)?;
        for (key, value) in given.entries() {
            if !entry.params.iter().any(|spec| spec.name == key) {
                continue;
            }
            if model_file.params.contains_key(key) {
                return Err(ScenarioError::new(
                    format!("{path}.params.{key}"),
                    "also given in reducer.params: a reducer is defined once, leave it out here",
                ));
            }
            params.insert(key.to_string(), value.clone());
            shared.insert(key.to_string());
        }
    }
    let model = (entry.build)(&params).map_err(|err| {
        let section = if shared.contains(&err.key) {
            "reducer".to_string()
        } else {
            path.to_string()
        };
        ScenarioError::new(format!("{section}.params.{}", err.key), err.reason)
    })?;
    Ok((entry, model))
}

/// The `reducer` section's own checks: each of its parameters is taken by some model of
/// the scenario, and each source names one of its parameters and is a text.
fn check_reducer(file: &ScenarioFile) -> Vec<ScenarioError> {
    let Some(reducer) = &file.reducer else {
        return Vec::new();
    };
    let entries: Vec<&ModelEntry> = file
        .models
        .iter()
        .filter_map(|(_, model)| rvtol_models::find(&model.model))
        .collect();
    let mut problems = Vec::new();
    for key in reducer.params.keys() {
        if !entries
            .iter()
            .any(|e| e.params.iter().any(|spec| spec.name == key))
        {
            let names: Vec<&str> = entries.iter().map(|e| e.name).collect();
            problems.push(ScenarioError::new(
                format!("reducer.params.{key}"),
                format!(
                    "no model of this scenario takes it (models: {}; `rvtol models` lists their parameters)",
                    names.join(", ")
                ),
            ));
        }
    }
    for (key, source) in &reducer.sources {
        if !reducer.params.contains_key(key) {
            problems.push(ScenarioError::new(
                format!("reducer.sources.{key}"),
                "not a key of reducer.params: a source says where a parameter's value comes from",
            ));
        } else if !source.is_string() {
            problems.push(ScenarioError::new(
                format!("reducer.sources.{key}"),
                format!("must be a text (a document, a reference, or an estimate and its rule), got {source}"),
            ));
        }
    }
    problems
}

/// Per variable name, the units of the model inputs it is bound to, each with the binding's
/// JSON path. Models that do not build are left out here: the binding pass reports them.
fn bound_input_units(
    file: &ScenarioFile,
    built: &[BuiltModel],
) -> BTreeMap<String, Vec<(String, String)>> {
    let mut units: BTreeMap<String, Vec<(String, String)>> = BTreeMap::new();
    for ((i, model_file), built) in file.models.iter().zip(built) {
        let Ok((_, model)) = built else {
            continue;
        };
        for input in model.inputs() {
            let binding = input_binding(&format!("models[{i}]"), &model_file.inputs, &input.name);
            if let Ok(Some(InputBinding {
                value: serde_json::Value::String(name),
                path,
                ..
            })) = binding
            {
                units
                    .entry(name.clone())
                    .or_default()
                    .push((input.unit.clone(), path));
            }
        }
    }
    units
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
    let Some(factor) = super::units::conversion(unit, target) else {
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

/// Names with runs of consecutive trailing indices collapsed (`pin_radial_error_mm_1` …
/// `_40` as `pin_radial_error_mm_{1..40}`), joined with commas: a model's inputs in one
/// readable line.
fn indexed_summary(names: &[&str]) -> String {
    let split = trailing_index;
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < names.len() {
        let mut j = i;
        if let Some((stem, first)) = split(names[i]) {
            while j + 1 < names.len()
                && split(names[j + 1]) == Some((stem, first + (j + 1 - i) as u64))
            {
                j += 1;
            }
            if j - i >= 2 {
                parts.push(format!("{stem}_{{{first}..{}}}", first + (j - i) as u64));
                i = j + 1;
                continue;
            }
        }
        parts.push(names[i].to_string());
        i += 1;
    }
    parts.join(", ")
}

/// Validates the parsed file and builds the scenario, adding every problem to `problems`;
/// `None` when something the scenario needs could not be built. Elements that failed to
/// parse or to compile are left out, and what refers to them (a correlation with a broken
/// variable, a binding to a broken part) is not reported again.
pub(super) fn compile(
    file: ScenarioFile,
    fallback_name: &str,
    problems: &mut Vec<ScenarioError>,
) -> Option<Scenario> {
    let models_failed_to_parse = problems.iter().any(|p| p.path.starts_with("models"));
    let mut report = |result: Result<(), ScenarioError>| {
        if let Err(err) = result {
            problems.push(err);
        }
    };
    if file.samples == Some(0) {
        report(Err(ScenarioError::new("samples", "must be at least 1")));
    }
    let sampling = sampling_of(&file);
    if let Err(err) = &sampling {
        report(Err(err.clone()));
    }
    let sampling = sampling.unwrap_or_default();
    let mut builder = InputSpaceBuilder::new();
    let mut columns: Vec<ColumnInfo> = Vec::new();
    let mut sources: Vec<InputGroup> = Vec::new();
    let mut column_by_name: BTreeMap<String, usize> = BTreeMap::new();
    // Names of parts and variables that could not be built: references to them are not
    // reported again.
    let mut broken: BTreeSet<String> = file.broken_names.clone();
    let mut add_name = |path: &str,
                        name: String,
                        column: usize,
                        unit: Option<String>,
                        columns: &mut Vec<ColumnInfo>| {
        // The column exists whatever its name: its info stays aligned with the index.
        columns.push(ColumnInfo {
            name: name.clone(),
            unit,
        });
        if column_by_name.contains_key(&name) {
            return Err(ScenarioError::new(
                path,
                format!("name {name:?} is used twice"),
            ));
        }
        column_by_name.insert(name, column);
        Ok(())
    };

    for (i, part) in &file.parts {
        let path = format!("parts[{i}]");
        let spec =
            check_name(&format!("{path}.name"), &part.name).and_then(|()| part_spec(&path, part));
        let spec = match spec {
            Ok(spec) => spec,
            Err(err) => {
                report(Err(err));
                broken.insert(part.name.clone());
                for component in SixDof::NAMES {
                    broken.insert(format!("{}.{component}", part.name));
                }
                continue;
            }
        };
        let first = builder.add_part(&path, &spec);
        sources.push(InputGroup {
            name: part.name.clone(),
            columns: (first..first + 6).collect(),
        });
        for (k, component) in SixDof::NAMES.iter().enumerate() {
            report(add_name(
                &format!("{path}.name"),
                format!("{}.{component}", part.name),
                first + k,
                Some(SixDof::UNITS[k].to_string()),
                &mut columns,
            ));
        }
    }
    let built_models: Vec<BuiltModel> = file
        .models
        .iter()
        .map(|(i, model_file)| {
            build_model(&format!("models[{i}]"), model_file, file.reducer.as_ref())
        })
        .collect();
    for problem in check_reducer(&file) {
        report(Err(problem));
    }
    let bound_units = bound_input_units(&file, &built_models);
    // The variable arrays (`count`): name → member columns, for the `*` bindings.
    let mut arrays: BTreeMap<String, (String, Vec<usize>)> = BTreeMap::new();
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
                    .filter_map(|name| bound_units.get(name))
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
                report(Err(err));
                broken.insert(variable.name.clone());
                broken.extend(members.into_iter().flatten().flatten());
                continue;
            }
        };
        let names = match members {
            Ok(Some(members)) => members,
            _ => vec![variable.name.clone()],
        };
        let mut group = Vec::with_capacity(names.len());
        for name in names {
            let column = builder.add_scalar(&path, dist.clone());
            group.push(column);
            report(add_name(
                &format!("{path}.name"),
                name,
                column,
                unit.clone(),
                &mut columns,
            ));
        }
        if variable.count.is_some() {
            arrays.insert(variable.name.clone(), (path.clone(), group.clone()));
        }
        sources.push(InputGroup {
            name: variable.name.clone(),
            columns: group,
        });
    }
    // An array's name is not a column, but it names its source: no column may take it.
    for (name, (path, _)) in &arrays {
        if column_by_name.contains_key(name) {
            report(Err(ScenarioError::new(
                format!("{path}.name"),
                format!("name {name:?} is used twice (by this array and by a variable or part component)"),
            )));
        }
    }
    for (i, correlation) in &file.correlations {
        let path = format!("correlations[{i}]");
        let mut ends = [0usize; 2];
        let mut resolved = true;
        for (k, name) in correlation.between.iter().enumerate() {
            match column_by_name.get(name) {
                Some(&column) => ends[k] = column,
                None => {
                    resolved = false;
                    if let Some((_, members)) = arrays.get(name) {
                        report(Err(ScenarioError::new(
                            format!("{path}.between[{k}]"),
                            format!(
                                "{name:?} is an array of {} members: correlate a member ({name}_1 …)",
                                members.len()
                            ),
                        )));
                    } else if !broken.contains(name) {
                        report(Err(ScenarioError::new(
                            format!("{path}.between[{k}]"),
                            format!("no variable or part component named {name:?}"),
                        )));
                    }
                }
            }
        }
        if resolved {
            report(
                builder
                    .correlate(&path, ends[0], ends[1], correlation.rho)
                    .map_err(ScenarioError::from),
            );
        }
    }
    let input_space = match builder.build("correlations") {
        Ok(space) => Some(space),
        Err(err) => {
            report(Err(err.into()));
            None
        }
    };

    if file.models.is_empty() && !models_failed_to_parse {
        report(Err(ScenarioError::new(
            "models",
            "needs at least one model",
        )));
    }
    let mut models = Vec::new();
    let mut outputs: Vec<OutputInfo> = Vec::new();
    // Models whose outputs are known (built, bound or not): every output name is known
    // when all are.
    let mut models_built = 0;
    for ((i, model_file), built) in file.models.iter().zip(built_models) {
        let path = format!("models[{i}]");
        let (entry, model) = match built {
            Ok(built) => built,
            Err(err) => {
                report(Err(err));
                continue;
            }
        };
        models_built += 1;
        let mut bindings = Vec::with_capacity(model.inputs().len());
        let mut bound = true;
        // Per `*` pattern, the indices of the inputs it binds.
        let mut pattern_indices: BTreeMap<&str, Vec<u64>> = BTreeMap::new();
        // Patterns that bind an input bound already (reported once, not checked further).
        let mut conflicted: BTreeSet<String> = BTreeSet::new();
        // Inputs bound by nothing, and the binding paths reported already (a pattern's
        // mistake is the same for every input it matches: one line).
        let mut unbound: Vec<&str> = Vec::new();
        let mut reported: BTreeSet<String> = BTreeSet::new();
        for key in model_file.inputs.keys() {
            if key.matches('*').count() > 1 {
                report(Err(ScenarioError::new(
                    format!("{path}.inputs.{key}"),
                    "a pattern has one '*', which stands for the index (1, 2, …)",
                )));
                bound = false;
            }
        }
        for input in model.inputs() {
            let binding = match input_binding(&path, &model_file.inputs, &input.name) {
                Err(err) => {
                    conflicted.insert(err.path.clone());
                    Err(err)
                }
                Ok(None) => {
                    // Reported once for all of them, below.
                    unbound.push(input.name.as_str());
                    Ok(Binding::Constant(0.0))
                }
                Ok(Some(InputBinding {
                    value,
                    path: binding_path,
                    pattern,
                })) => {
                    if let Some((key, index)) = pattern {
                        pattern_indices.entry(key).or_default().push(index);
                    }
                    let index = pattern.map(|(_, index)| index);
                    match value {
                        serde_json::Value::Number(n) => {
                            let v = n.as_f64().unwrap_or(f64::NAN);
                            if !v.is_finite() {
                                Err(ScenarioError::new(&binding_path, "must be a finite number"))
                            } else {
                                model
                                    .check_constant(bindings.len(), v)
                                    .map(|()| Binding::Constant(v))
                                    .map_err(|reason| ScenarioError::new(&binding_path, reason))
                            }
                        }
                        serde_json::Value::String(name) => {
                            // A pattern bound to an array takes the member of its index; an
                            // array's name alone names no single column. `None`: a broken
                            // variable, reported already.
                            let column = match (arrays.get(name), index) {
                                (Some((_, members)), Some(k)) => {
                                    members.get(k as usize - 1).copied().map(Some).ok_or_else(|| {
                                        ScenarioError::new(
                                            &binding_path,
                                            format!(
                                                "binds {:?} to member {k} of {name:?}, which has {} members",
                                                input.name,
                                                members.len()
                                            ),
                                        )
                                    })
                                }
                                (Some((_, members)), None) => Err(ScenarioError::new(
                                    &binding_path,
                                    format!(
                                        "{name:?} is an array of {} members: bind it with a pattern (\"{}_*\": {name:?}) or name one member ({name}_1 …)",
                                        members.len(),
                                        input.name
                                    ),
                                )),
                                (None, _) => match column_by_name.get(name) {
                                    Some(&column) => Ok(Some(column)),
                                    None if broken.contains(name) => Ok(None),
                                    None => Err(ScenarioError::new(
                                        &binding_path,
                                        format!("no variable or part component named {name:?}"),
                                    )),
                                },
                            };
                            match column {
                                Ok(Some(column)) => match &columns[column].unit {
                                    // A unit rvtol does not know is the variable's mistake:
                                    // said at its `unit`.
                                    Some(unit)
                                        if input.unit != "any"
                                            && unit != &input.unit
                                            && !super::units::is_known(unit)
                                            && variable_index(&file, name).is_some() =>
                                    {
                                        Err(ScenarioError::new(
                                            format!(
                                                "variables[{}].unit",
                                                variable_index(&file, name).unwrap_or_default()
                                            ),
                                            format!(
                                                "{unit:?} is not a unit rvtol knows ({}); {binding_path} wants {}",
                                                super::units::known(),
                                                input.unit
                                            ),
                                        ))
                                    }
                                    Some(unit) if input.unit != "any" && unit != &input.unit => {
                                        Err(ScenarioError::new(
                                            &binding_path,
                                            format!(
                                                "{name:?} is in {unit}{} but the input wants {}",
                                                if super::units::is_known(unit) {
                                                    String::new()
                                                } else {
                                                    format!(
                                                        ", which is not a unit rvtol knows ({})",
                                                        super::units::known()
                                                    )
                                                },
                                                input.unit
                                            ),
                                        ))
                                    }
                                    _ => Ok(Binding::Column(column)),
                                },
                                Ok(None) => {
                                    bound = false;
                                    Ok(Binding::Constant(0.0))
                                }
                                Err(err) => Err(err),
                            }
                        }
                        other => Err(ScenarioError::new(
                            &binding_path,
                            format!("expected a number or a variable name, got {other}"),
                        )),
                    }
                }
            };
            match binding {
                Ok(binding) => bindings.push(binding),
                Err(err) => {
                    if reported.insert(err.path.clone()) {
                        report(Err(err));
                    }
                    bound = false;
                    bindings.push(Binding::Constant(0.0));
                }
            }
        }
        let known = || {
            let names: Vec<&str> = model.inputs().iter().map(|i| i.name.as_str()).collect();
            indexed_summary(&names)
        };
        for (key, value) in &model_file.inputs {
            let key_path = format!("{path}.inputs.{key}");
            if pattern(key).is_none() {
                if !model.inputs().iter().any(|input| &input.name == key) {
                    report(Err(ScenarioError::new(
                        key_path,
                        format!(
                            "{} has no input {key:?}; its inputs are: {}",
                            entry.name,
                            known()
                        ),
                    )));
                    bound = false;
                }
                continue;
            }
            if key.matches('*').count() > 1 {
                continue;
            }
            let indices = pattern_indices
                .get(key.as_str())
                .cloned()
                .unwrap_or_default();
            if indices.is_empty() {
                report(Err(ScenarioError::new(
                    key_path,
                    if unbound.is_empty() {
                        format!(
                            "matches no input of {}; its inputs are: {}",
                            entry.name,
                            known()
                        )
                    } else {
                        format!(
                            "matches no input of {}; the inputs left unbound are: {}",
                            entry.name,
                            indexed_summary(&unbound)
                        )
                    },
                )));
                bound = false;
                continue;
            }
            // A pattern that binds an input bound already is reported once, above.
            if conflicted.contains(&key_path) {
                continue;
            }
            // A pattern bound to an array binds every member, once.
            if let Some((_, members)) = value.as_str().and_then(|name| arrays.get(name)) {
                let mut seen = indices.clone();
                seen.sort_unstable();
                let all = seen.len() == members.len()
                    && seen.iter().enumerate().all(|(k, &i)| i == k as u64 + 1);
                if !all && seen.iter().all(|&i| i as usize <= members.len()) {
                    let name = value.as_str().unwrap_or_default();
                    report(Err(ScenarioError::new(
                        key_path,
                        format!(
                            "binds {} inputs (indices {}) but {name:?} has {} members: the array must match the inputs one to one",
                            seen.len(),
                            index_list(&seen),
                            members.len()
                        ),
                    )));
                    bound = false;
                }
            }
        }
        if !unbound.is_empty() {
            bound = false;
            let units: BTreeSet<&str> = model
                .inputs()
                .iter()
                .filter(|i| unbound.contains(&i.name.as_str()))
                .map(|i| i.unit.as_str())
                .collect();
            let units: Vec<&str> = units.into_iter().collect();
            report(Err(ScenarioError::new(
                format!("{path}.inputs"),
                if unbound.len() == 1 {
                    format!(
                        "model input {:?} ({}) is not bound: give a number or a variable name",
                        unbound[0],
                        units.join(", ")
                    )
                } else {
                    format!(
                        "{} model inputs are not bound: {} ({}); give each a number or a variable name (a key with one `*` binds a family)",
                        unbound.len(),
                        indexed_summary(&unbound),
                        units.join(", ")
                    )
                },
            )));
        }
        let first_output = outputs.len();
        for output in model.outputs() {
            if outputs.iter().any(|o| o.name == output.name) {
                report(Err(ScenarioError::new(
                    format!("{path}.model"),
                    format!(
                        "output {:?} is produced by an earlier model too",
                        output.name
                    ),
                )));
                bound = false;
            }
            outputs.push(OutputInfo {
                name: output.name.clone(),
                unit: output.unit.clone(),
                kind: output.kind,
                description: output.description.to_string(),
                spec: None,
                condition: None,
                flagged_conform: false,
            });
        }
        for (j, output) in model.outputs().iter().enumerate() {
            if let Some(condition) = output.condition {
                let indicator = model
                    .outputs()
                    .iter()
                    .position(|o| o.name == condition.indicator && o.kind == OutputKind::Indicator)
                    .unwrap_or_else(|| {
                        panic!(
                            "model {} qualifies {} by {}, which is not one of its indicator outputs",
                            entry.name, output.name, condition.indicator
                        )
                    });
                outputs[first_output + j].condition =
                    Some((first_output + indicator, condition.effect));
            }
        }
        if bound {
            models.push(BoundModel {
                model,
                bindings,
                first_output,
            });
        }
    }

    for (name, spec) in &file.spec_limits {
        let path = format!("spec_limits.{name}");
        let Some(output) = outputs.iter_mut().find(|o| &o.name == name) else {
            if models_built == file.models.len() {
                report(Err(ScenarioError::new(
                    &path,
                    format!("no output named {name:?}"),
                )));
            }
            continue;
        };
        report(spec_limits(&path, name, spec, output));
    }

    let sensitivity_groups = sensitivity_groups(&file, &sources, &broken, &mut report);

    let allocation_levers = match &file.allocation {
        Some(section) => compile_levers(section, file.models.len()).unwrap_or_else(|err| {
            report(Err(err));
            Vec::new()
        }),
        None => Vec::new(),
    };
    let allocation = match &file.allocation {
        // A source that could not be built is reported already; its allocation is not
        // checked again.
        Some(section) if section.names_any(&broken) => Vec::new(),
        Some(section) => {
            let tolerances: Vec<ToleranceSource> =
                file.parts
                    .iter()
                    .map(|(i, part)| part_tolerance(&format!("parts[{i}]"), part))
                    .chain(file.variables.iter().map(|(i, variable)| {
                        variable_tolerance(&format!("variables[{i}]"), variable)
                    }))
                    .collect();
            match compile_allocation(section, &tolerances) {
                Ok(allocation) => allocation,
                Err(err) => {
                    report(Err(err));
                    Vec::new()
                }
            }
        }
        None => Vec::new(),
    };

    Some(Scenario {
        name: file.name.unwrap_or_else(|| fallback_name.to_string()),
        description: file.description.unwrap_or_default(),
        samples: file.samples.unwrap_or(DEFAULT_SAMPLES),
        seed: file.seed.unwrap_or(DEFAULT_SEED),
        sampling,
        input_space: input_space?,
        columns,
        sources,
        sensitivity_groups,
        models,
        outputs,
        allocation,
        allocation_levers,
    })
}

/// The scenario's `sampling` and `replicates` (a method name and, for `lhs` and `rqmc`,
/// the replicates, [`Sampling::DEFAULT_REPLICATES`] when not given).
fn sampling_of(file: &ScenarioFile) -> Result<Sampling, ScenarioError> {
    let method = match file.sampling.as_deref() {
        None => SamplingMethod::MonteCarlo,
        Some(name) => SamplingMethod::parse(name).ok_or_else(|| {
            ScenarioError::new(
                "sampling",
                format!(
                    "unknown method {name:?}, expected one of {}",
                    SamplingMethod::NAMES.map(|n| format!("{n:?}")).join(", ")
                ),
            )
        })?,
    };
    let mut sampling = Sampling::of(method);
    if let Some(replicates) = file.replicates {
        if method == SamplingMethod::MonteCarlo {
            return Err(ScenarioError::new(
                "replicates",
                "Monte Carlo rows are independent and have no replicates: give replicates with \"sampling\": \"lhs\" or \"rqmc\"",
            ));
        }
        sampling.replicates = replicates;
    }
    Ok(sampling)
}

/// The spec limits of one output.
fn spec_limits(
    path: &str,
    name: &str,
    spec: &SpecFile,
    output: &mut OutputInfo,
) -> Result<(), ScenarioError> {
    if output.kind != OutputKind::Continuous {
        return Err(ScenarioError::new(
            path,
            "spec limits apply to continuous outputs only",
        ));
    }
    if spec.lower.is_none() && spec.upper.is_none() {
        return Err(ScenarioError::new(path, "give lower, upper or both"));
    }
    if let (Some(l), Some(u)) = (spec.lower, spec.upper) {
        if l >= u {
            return Err(ScenarioError::new(
                format!("{path}.upper"),
                format!("upper {} must exceed lower {}", Shown(u), Shown(l)),
            ));
        }
    }
    if spec.flagged_conform
        && !matches!(output.condition, Some((_, ConditionEffect::NonConforming)))
    {
        return Err(ScenarioError::new(
            format!("{path}.flagged_conform"),
            format!("{name:?} has no indicator that flags non-conforming samples"),
        ));
    }
    output.spec = Some(SpecLimits {
        lower: spec.lower,
        upper: spec.upper,
    });
    output.flagged_conform = spec.flagged_conform;
    Ok(())
}

/// The units of the Sobol' analysis: the scenario's groups, then every source in none.
fn sensitivity_groups(
    file: &ScenarioFile,
    sources: &[InputGroup],
    broken: &BTreeSet<String>,
    report: &mut impl FnMut(Result<(), ScenarioError>),
) -> Vec<InputGroup> {
    let mut groups: Vec<InputGroup> = Vec::new();
    let mut grouped: Vec<&str> = Vec::new();
    for (i, group) in &file.sensitivity_groups {
        let path = format!("sensitivity_groups[{i}]");
        if let Err(err) = check_name(&format!("{path}.name"), &group.name) {
            report(Err(err));
            continue;
        }
        if group.members.is_empty() {
            report(Err(ScenarioError::new(
                format!("{path}.members"),
                "needs at least one member",
            )));
            continue;
        }
        if sources.iter().any(|s| s.name == group.name) && !group.members.contains(&group.name) {
            report(Err(ScenarioError::new(
                format!("{path}.name"),
                format!("{:?} is already the name of a part or variable", group.name),
            )));
            continue;
        }
        let mut columns = Vec::new();
        for (k, member) in group.members.iter().enumerate() {
            let member_path = format!("{path}.members[{k}]");
            let Some(source) = sources.iter().find(|s| &s.name == member) else {
                if !broken.contains(member) {
                    report(Err(ScenarioError::new(
                        &member_path,
                        format!("no part or variable named {member:?}"),
                    )));
                }
                continue;
            };
            if grouped.contains(&member.as_str()) {
                report(Err(ScenarioError::new(
                    member_path,
                    format!("{member:?} is already in a group"),
                )));
                continue;
            }
            grouped.push(member);
            columns.extend(&source.columns);
        }
        groups.push(InputGroup {
            name: group.name.clone(),
            columns,
        });
    }
    groups.extend(
        sources
            .iter()
            .filter(|s| !grouped.contains(&s.name.as_str()))
            .cloned(),
    );
    groups
}
