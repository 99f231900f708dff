//! The scenario file format: the serde types of every section and their parsing with the
//! JSON path of every problem.
//!
//! The text is parsed in two steps. First into a JSON value, refusing duplicate keys
//! (serde_json would keep the last silently) and reporting a syntax error with its line and
//! column. Then each section, and each element of an array section, is deserialised from
//! that value on its own, so that every schema problem (an unknown key, a wrong type, a
//! distribution object with two or no distributions, three names in `between`) is reported
//! with its JSON path, and a problem in one element does not hide those of the others.
//! Finally every number is checked against the range rvtol accepts ([`MAX_DEVIATION`],
//! [`MAX_COVARIANCE`], [`MAX_PARAMETER`]): larger values have no physical meaning in a
//! tolerance study and would overflow the statistics.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use serde::de::{self, DeserializeOwned, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::Value;

use super::allocation::AllocationFile;
use super::ScenarioError;
use rvtol_deviation::Shown;

/// Largest magnitude of a deviation's parameter (a mean, sd, bound or band limit; mm or
/// rad), of a correlation's partner values and of a spec limit.
pub const MAX_DEVIATION: f64 = 1e6;
/// Largest magnitude of a covariance entry (mm², mm·rad, rad²).
pub const MAX_COVARIANCE: f64 = 1e12;
/// Largest magnitude of a model parameter or constant input (the models check their own
/// physical ranges within it).
pub const MAX_PARAMETER: f64 = 1e12;

/// The scenario file, its sections parsed one by one ([`parse`]); array sections keep each
/// element's index in the file, for the JSON paths of later problems.
#[derive(Debug, Default)]
pub(super) struct ScenarioFile {
    pub(super) name: Option<String>,
    pub(super) description: Option<String>,
    pub(super) samples: Option<u64>,
    pub(super) seed: Option<u64>,
    pub(super) sampling: Option<String>,
    pub(super) replicates: Option<u64>,
    pub(super) parts: Vec<(usize, PartFile)>,
    pub(super) variables: Vec<(usize, VariableFile)>,
    pub(super) correlations: Vec<(usize, CorrelationFile)>,
    pub(super) models: Vec<(usize, ModelFile)>,
    pub(super) spec_limits: BTreeMap<String, SpecFile>,
    pub(super) sensitivity_groups: Vec<(usize, GroupFile)>,
    pub(super) allocation: Option<AllocationFile>,
    pub(super) reducer: Option<ReducerFile>,
    /// Names of parts and variables whose element did not parse (a part's names include
    /// its components `name.du` …): what refers to them is not reported again.
    pub(super) broken_names: BTreeSet<String>,
}

/// The `reducer` section: the reducer's parameters, given once for every model of the
/// scenario (each model takes the keys it knows), with a source for each.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ReducerFile {
    /// Documentation for the reader of the file; not used by the run.
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) name: Option<String>,
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) description: Option<String>,
    #[serde(default)]
    pub(super) params: serde_json::Map<String, serde_json::Value>,
    /// Parameter key → where its value comes from (a document, a reference, or an
    /// estimate and its rule).
    #[serde(default)]
    pub(super) sources: serde_json::Map<String, serde_json::Value>,
    /// The reducer file the section was read from (written in when the scenario is loaded,
    /// `data.rs`): a shared definition holds the keys of every model of its reducer.
    #[serde(default)]
    pub(super) file: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GroupFile {
    pub(super) name: String,
    pub(super) members: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PartFile {
    pub(super) name: String,
    /// Documentation for the reader of the file; not used by the run.
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) description: Option<String>,
    #[serde(default)]
    pub(super) mean: Option<Vec<f64>>,
    #[serde(default)]
    pub(super) covariance: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    pub(super) sd: Option<Vec<f64>>,
    #[serde(default)]
    pub(super) correlation: Option<Vec<Vec<f64>>>,
    #[serde(default)]
    pub(super) tolerance_band: Option<ToleranceBandFile>,
    /// The units `mean`, `sd` and `covariance` are written in (default mm and rad).
    #[serde(default)]
    pub(super) units: Option<PartUnitsFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PartUnitsFile {
    /// Unit of du, dv, dw: a length (`mm`, `µm`, `um`, `m`).
    #[serde(default, deserialize_with = "unit_name")]
    pub(super) translation: Option<String>,
    /// Unit of dalpha, dbeta, dgamma: an angle (`rad`, `mrad`, `µrad`, `urad`, `deg`,
    /// `arcmin`, `arcsec`).
    #[serde(default, deserialize_with = "unit_name")]
    pub(super) rotation: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ToleranceBandFile {
    pub(super) delta_tau_mm: f64,
    pub(super) length_mm: f64,
    #[serde(default)]
    pub(super) constraint_eq11: bool,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct VariableFile {
    pub(super) name: String,
    #[serde(default, deserialize_with = "unit_name")]
    pub(super) unit: Option<String>,
    /// Documentation for the reader of the file; not used by the run.
    #[serde(default)]
    #[allow(dead_code)]
    pub(super) description: Option<String>,
    /// An array of this many independent members with the one distribution (`name_1` …
    /// `name_N`, one error source), e.g. a position error of every pin.
    #[serde(default)]
    pub(super) count: Option<u64>,
    pub(super) distribution: DistributionFile,
}

/// A unit as written, with the Greek letter mu read as the micro sign
/// ([`super::units::canonical`]).
fn unit_name<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<String>, D::Error> {
    let unit: Option<String> = Deserialize::deserialize(deserializer)?;
    Ok(unit.map(|unit| super::units::canonical(&unit)))
}

/// Largest number of members of a variable array (`variables[i].count`).
pub const MAX_ARRAY_MEMBERS: u64 = 100_000;

pub(super) fn default_cp() -> f64 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum DistributionFile {
    Normal {
        mean: f64,
        sd: f64,
    },
    ToleranceBand {
        lower: f64,
        upper: f64,
        #[serde(default = "default_cp")]
        cp: f64,
        #[serde(default)]
        mean_shift: f64,
    },
    Uniform {
        lower: f64,
        upper: f64,
    },
    Triangular {
        lower: f64,
        mode: f64,
        upper: f64,
    },
    TruncatedNormal {
        mean: f64,
        sd: f64,
        lower: f64,
        upper: f64,
    },
    /// The magnitude |X| of a tolerance-band quantity X.
    FoldedNormal {
        lower: f64,
        upper: f64,
        #[serde(default = "default_cp")]
        cp: f64,
        #[serde(default)]
        mean_shift: f64,
    },
    /// A radial magnitude whose 99.865 % quantile is `upper` at Cp = 1.
    Rayleigh {
        upper: f64,
        #[serde(default = "default_cp")]
        cp: f64,
    },
    /// A lognormal quantity with its median and the 99.865 % quantile `upper` at Cp = 1.
    Lognormal {
        median: f64,
        upper: f64,
        #[serde(default = "default_cp")]
        cp: f64,
    },
    /// Measured values resampled: given inline (`values`) or read from a CSV column
    /// (`csv`, `column`) when the scenario is loaded from its file ([`super::data`]).
    Empirical {
        #[serde(default)]
        values: Option<Vec<f64>>,
        #[serde(default)]
        csv: Option<String>,
        /// Where the values came from; read by [`super::data`] from the JSON value.
        #[serde(default)]
        #[allow(dead_code)]
        column: Option<String>,
        /// Documentation: where `values` came from (written by [`super::data`]).
        #[serde(default)]
        #[allow(dead_code)]
        source: Option<String>,
        /// A kernel bandwidth (in the variable's unit) or `"silverman"`; none: plain
        /// resampling.
        #[serde(default)]
        bandwidth: Option<Value>,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CorrelationFile {
    pub(super) between: [String; 2],
    /// The correlation of the two quantities' normal scores (for two normals, their
    /// correlation).
    #[serde(default)]
    pub(super) rho: Option<f64>,
    /// Spearman's rank correlation, in place of `rho`.
    #[serde(default)]
    pub(super) spearman: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ModelFile {
    pub(super) model: String,
    #[serde(default)]
    pub(super) params: serde_json::Map<String, serde_json::Value>,
    #[serde(default)]
    pub(super) inputs: serde_json::Map<String, serde_json::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SpecFile {
    #[serde(default)]
    pub(super) lower: Option<f64>,
    #[serde(default)]
    pub(super) upper: Option<f64>,
    #[serde(default)]
    pub(super) flagged_conform: bool,
}

/// A JSON value that refuses duplicate keys (serde_json's own `Value` keeps the last).
struct Checked(Value);

impl<'de> Deserialize<'de> for Checked {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(CheckedVisitor).map(Checked)
    }
}

struct CheckedVisitor;

impl<'de> Visitor<'de> for CheckedVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        Checked::deserialize(d).map(|c| c.0)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut values = Vec::new();
        while let Some(Checked(value)) = seq.next_element()? {
            values.push(value);
        }
        Ok(Value::Array(values))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut object = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(de::Error::custom(format!(
                    "key {key:?} appears twice; give each key once"
                )));
            }
            let Checked(value) = map.next_value()?;
            object.insert(key, value);
        }
        Ok(Value::Object(object))
    }
}

/// "(root)" for the empty path serde_path_to_error gives the document itself.
fn shown_path(path: String) -> String {
    if path == "." || path.is_empty() {
        "(root)".to_string()
    } else {
        path
    }
}

/// Parses the text into a JSON value: a syntax error (with its line and column) or a
/// duplicate key (with its path) is the one problem.
pub fn parse_value(text: &str) -> Result<Value, ScenarioError> {
    let mut deserializer = serde_json::Deserializer::from_str(text);
    let value =
        serde_path_to_error::deserialize::<_, Checked>(&mut deserializer).map_err(|err| {
            let path = shown_path(err.path().to_string());
            let inner = err.into_inner();
            if inner.is_syntax() || inner.is_eof() {
                ScenarioError::new("JSON syntax", inner.to_string())
            } else {
                ScenarioError::new(path, inner.to_string())
            }
        })?;
    deserializer
        .end()
        .map_err(|err| ScenarioError::new("JSON syntax", err.to_string()))?;
    Ok(value.0)
}

/// Deserialises `value` (found at `path`) as a `T`, with the JSON path of any problem.
pub(super) fn from_value<T: DeserializeOwned>(
    path: &str,
    value: &Value,
) -> Result<T, ScenarioError> {
    serde_path_to_error::deserialize::<_, T>(value).map_err(|err| {
        let inner_path = err.path().to_string();
        let full = match (path.is_empty(), inner_path.as_str()) {
            (true, _) => shown_path(inner_path.clone()),
            (false, "." | "") => path.to_string(),
            (false, rest) if rest.starts_with('[') => format!("{path}{rest}"),
            (false, rest) => format!("{path}.{rest}"),
        };
        ScenarioError::new(full, tidy_serde_message(&err.into_inner().to_string()))
    })
}

/// serde's messages, in the words of a scenario file: a number as a person writes it, and
/// the enum wording of a distribution object.
fn tidy_serde_message(message: &str) -> String {
    let message = message.replace(
        "invalid value: map, expected map with a single key",
        "give exactly one distribution, e.g. {\"normal\": {\"mean\": 0, \"sd\": 0.001}}",
    );
    let message = message.replace(
        "expected fewer elements in array",
        "expected fewer elements",
    );
    // Rust's type names mean nothing to the reader of a scenario.
    let message = message
        .replace("expected f64", "expected a number")
        .replace("expected u64", "expected a whole number of at least 0")
        .replace("expected usize", "expected a whole number of at least 0")
        .replace("expected i64", "expected a whole number")
        .replace("expected a boolean", "expected true or false");
    // serde writes floats in full ("floating point `1000000…`"): shorten them.
    let mut out = String::with_capacity(message.len());
    let mut rest = message.as_str();
    while let Some(start) = rest.find("floating point `") {
        let (before, after) = rest.split_at(start + "floating point `".len());
        out.push_str(before);
        match after.find('`') {
            Some(end) => {
                let number = &after[..end];
                match number.parse::<f64>() {
                    Ok(x) => out.push_str(&Shown(x).to_string()),
                    Err(_) => out.push_str(number),
                }
                rest = &after[end..];
            }
            None => {
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// The keys a scenario file may have at its top level.
const TOP_LEVEL_KEYS: [&str; 14] = [
    "name",
    "description",
    "samples",
    "seed",
    "sampling",
    "replicates",
    "parts",
    "variables",
    "correlations",
    "models",
    "spec_limits",
    "sensitivity_groups",
    "allocation",
    "reducer",
];

/// Parses every section of the scenario file: the file with the elements that parsed, and
/// every problem found (each with its JSON path).
pub(super) fn parse(text: &str) -> Result<(ScenarioFile, Vec<ScenarioError>), ScenarioError> {
    let root = parse_value(text)?;
    let Value::Object(object) = &root else {
        return Err(ScenarioError::new(
            "(root)",
            "a scenario is a JSON object with models, parts, variables, …",
        ));
    };
    let mut problems = Vec::new();
    let mut file = ScenarioFile::default();
    for key in object.keys() {
        if !TOP_LEVEL_KEYS.contains(&key.as_str()) {
            problems.push(ScenarioError::new(
                key.clone(),
                format!(
                    "unknown field `{key}`, expected one of {}",
                    TOP_LEVEL_KEYS
                        .iter()
                        .map(|k| format!("`{k}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
    }
    check_magnitudes(&root, &mut problems);
    let take = |key: &str| -> Option<&Value> { object.get(key).filter(|v| !v.is_null()) };
    macro_rules! scalar {
        ($key:literal, $field:ident) => {
            if let Some(value) = take($key) {
                match from_value(&$key, value) {
                    Ok(v) => file.$field = Some(v),
                    Err(err) => problems.push(err),
                }
            }
        };
    }
    scalar!("name", name);
    scalar!("description", description);
    scalar!("samples", samples);
    scalar!("seed", seed);
    scalar!("sampling", sampling);
    scalar!("replicates", replicates);
    scalar!("allocation", allocation);
    scalar!("reducer", reducer);
    if let Some(value) = take("spec_limits") {
        match value {
            Value::Object(entries) => {
                for (name, spec) in entries {
                    match from_value(&format!("spec_limits.{name}"), spec) {
                        Ok(spec) => {
                            file.spec_limits.insert(name.clone(), spec);
                        }
                        Err(err) => problems.push(err),
                    }
                }
            }
            _ => problems.push(ScenarioError::new(
                "spec_limits",
                "must be an object: output name → {\"lower\": …, \"upper\": …}",
            )),
        }
    }
    file.parts = elements(object.get("parts"), "parts", &mut problems);
    file.variables = elements(object.get("variables"), "variables", &mut problems);
    file.broken_names = broken_names(object, &file);
    file.correlations = elements(object.get("correlations"), "correlations", &mut problems);
    file.models = elements(object.get("models"), "models", &mut problems);
    file.sensitivity_groups = elements(
        object.get("sensitivity_groups"),
        "sensitivity_groups",
        &mut problems,
    );
    if !object.contains_key("models") {
        problems.push(ScenarioError::new(
            "models",
            "missing: a scenario needs at least one model",
        ));
    }
    Ok((file, problems))
}

/// The names of the parts and variables whose element did not parse (see
/// [`ScenarioFile::broken_names`]).
fn broken_names(object: &serde_json::Map<String, Value>, file: &ScenarioFile) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let items = |key: &str| match object.get(key) {
        Some(Value::Array(items)) => items.clone(),
        _ => Vec::new(),
    };
    // The parsed elements' indices, as sets: a scenario may hold 100,000 variables.
    let parsed = |indices: Vec<usize>| indices.into_iter().collect::<BTreeSet<usize>>();
    let parts = parsed(file.parts.iter().map(|(j, _)| *j).collect());
    let variables = parsed(file.variables.iter().map(|(j, _)| *j).collect());
    for (i, item) in items("parts").iter().enumerate() {
        if !parts.contains(&i) {
            if let Some(name) = item.get("name").and_then(Value::as_str) {
                names.insert(name.to_string());
                for component in rvtol_deviation::SixDof::NAMES {
                    names.insert(format!("{name}.{component}"));
                }
            }
        }
    }
    for (i, item) in items("variables").iter().enumerate() {
        if !variables.contains(&i) {
            if let Some(name) = item.get("name").and_then(Value::as_str) {
                names.insert(name.to_string());
            }
        }
    }
    names
}

/// The elements of an array section, each parsed on its own: (its index, the element)
/// for those that parsed; a problem for each that did not.
fn elements<T: DeserializeOwned>(
    value: Option<&Value>,
    key: &str,
    problems: &mut Vec<ScenarioError>,
) -> Vec<(usize, T)> {
    match value {
        None | Some(Value::Null) => Vec::new(),
        Some(Value::Array(items)) => items
            .iter()
            .enumerate()
            .filter_map(|(i, item)| match from_value(&format!("{key}[{i}]"), item) {
                Ok(parsed) => Some((i, parsed)),
                Err(err) => {
                    problems.push(err);
                    None
                }
            })
            .collect(),
        Some(_) => {
            problems.push(ScenarioError::new(key, "must be an array"));
            Vec::new()
        }
    }
}

/// Checks every number of the file against the accepted ranges (module docs).
fn check_magnitudes(root: &Value, problems: &mut Vec<ScenarioError>) {
    fn walk(path: &str, value: &Value, limit: f64, problems: &mut Vec<ScenarioError>) {
        match value {
            Value::Number(n) => {
                let x = n.as_f64().unwrap_or(f64::INFINITY);
                if x.abs() > limit {
                    problems.push(ScenarioError::new(
                        path,
                        format!(
                            "{} is outside ±{}, the range rvtol accepts here: larger values have no physical meaning in a tolerance study and would overflow the statistics",
                            Shown(x),
                            Shown(limit)
                        ),
                    ));
                }
            }
            Value::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    walk(&format!("{path}[{i}]"), item, limit, problems);
                }
            }
            Value::Object(entries) => {
                for (key, item) in entries {
                    let child = format!("{path}.{key}");
                    let limit = if key == "covariance" {
                        MAX_COVARIANCE
                    } else {
                        limit
                    };
                    walk(&child, item, limit, problems);
                }
            }
            _ => {}
        }
    }
    let Value::Object(object) = root else {
        return;
    };
    for (key, value) in object {
        let limit = match key.as_str() {
            "parts" | "variables" | "correlations" | "spec_limits" => MAX_DEVIATION,
            "models" | "allocation" | "reducer" => MAX_PARAMETER,
            _ => continue,
        };
        walk(key, value, limit, problems);
    }
}
