//! Model parameters as handed over by the engine (no serde here), with typed accessors that
//! record which keys were read, so unknown keys are reported, and error messages that the
//! engine prefixes with the JSON path of the `params` object.

use rvtol_deviation::Shown;
use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};

use thiserror::Error;

/// A parameter value: a number, or an object of named numbers (for example the
/// coefficients of `linear_stack`).
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// A number.
    Number(f64),
    /// Named numbers, in the scenario's order.
    Named(Vec<(String, f64)>),
    /// A text (a name or a unit).
    Text(String),
    /// An object whose values are not all numbers (the formulas and units of an
    /// `expression` model), in the scenario's order.
    Object(Vec<(String, ParamValue)>),
}

impl ParamValue {
    /// What kind of value it is, for messages (`a number`, `a string`, `an object`).
    pub fn kind(&self) -> &'static str {
        match self {
            ParamValue::Number(_) => "a number",
            ParamValue::Text(_) => "a string",
            ParamValue::Named(_) | ParamValue::Object(_) => "an object",
        }
    }
}

/// An invalid model parameter: `key` is relative to the model's `params` object. A model
/// that checks several independent parts (the formulas of an `expression`) names the
/// first problem and carries the others in `further`, so `rvtol validate` lists them all.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{key}: {reason}")]
pub struct ModelError {
    /// Key path inside `params` (`z_c`, `coefficients.x1`).
    pub key: String,
    /// What is wrong.
    pub reason: String,
    /// Further problems found in the same build, in order.
    pub further: Vec<ModelError>,
}

impl ModelError {
    /// A new error for `key`.
    pub fn new(key: impl Into<String>, reason: impl Into<String>) -> Self {
        ModelError {
            key: key.into(),
            reason: reason.into(),
            further: Vec::new(),
        }
    }

    /// The first of `problems` carrying the rest; `None` when there are none.
    pub fn of_all(problems: Vec<ModelError>) -> Option<ModelError> {
        let mut problems = problems.into_iter();
        let mut first = problems.next()?;
        first.further.extend(problems);
        Some(first)
    }

    /// This problem and the further ones, in order.
    pub fn all(&self) -> impl Iterator<Item = &ModelError> {
        std::iter::once(self).chain(&self.further)
    }
}

/// The parameters of one model in a scenario.
#[derive(Debug, Clone, Default)]
pub struct ModelParams {
    values: BTreeMap<String, ParamValue>,
    read: RefCell<BTreeSet<String>>,
}

/// Parameters renamed since they were introduced: (old key, new key, why).
const RENAMED: &[(&str, &str, &str)] = &[(
    "disc_spacing_mm",
    "crank_eccentric_spacing_mm",
    "the discs' mid-planes are their eccentrics': one dimension of the reducer, the crank side's too",
)];

impl ModelParams {
    /// Empty parameters.
    pub fn new() -> Self {
        Self::default()
    }

    /// Every parameter set, by key (for writing them out; reading through this does not
    /// count as use).
    pub fn entries(&self) -> impl Iterator<Item = (&str, &ParamValue)> {
        self.values.iter().map(|(k, v)| (k.as_str(), v))
    }

    /// Adds a value (builder style).
    pub fn with(mut self, key: &str, value: ParamValue) -> Self {
        self.values.insert(key.to_string(), value);
        self
    }

    /// Adds a number (builder style).
    pub fn with_number(self, key: &str, value: f64) -> Self {
        self.with(key, ParamValue::Number(value))
    }

    /// Inserts a value.
    pub fn insert(&mut self, key: String, value: ParamValue) {
        self.values.insert(key, value);
    }

    /// A finite number, or the default when absent and a default exists.
    pub fn number(&self, key: &str, default: Option<f64>) -> Result<f64, ModelError> {
        self.read.borrow_mut().insert(key.to_string());
        match self.values.get(key) {
            Some(ParamValue::Number(v)) if v.is_finite() => Ok(*v),
            Some(ParamValue::Number(v)) => Err(ModelError::new(
                key,
                format!("must be a finite number, got {}", Shown(*v)),
            )),
            Some(ParamValue::Named(_) | ParamValue::Object(_)) => {
                Err(ModelError::new(key, "must be a number, got an object"))
            }
            Some(ParamValue::Text(_)) => {
                Err(ModelError::new(key, "must be a number, got a string"))
            }
            None => default.ok_or_else(|| ModelError::new(key, "required parameter is missing")),
        }
    }

    /// A number that must be strictly positive.
    pub fn positive(&self, key: &str, default: Option<f64>) -> Result<f64, ModelError> {
        let value = self.number(key, default)?;
        if value > 0.0 {
            Ok(value)
        } else {
            Err(ModelError::new(
                key,
                format!("must be positive, got {}", Shown(value)),
            ))
        }
    }

    /// A Coulomb friction coefficient, in [0, 0.5) (required).
    pub fn friction_coefficient(&self, key: &str) -> Result<f64, ModelError> {
        let value = self.number(key, None)?;
        if (0.0..0.5).contains(&value) {
            Ok(value)
        } else {
            Err(ModelError::new(
                key,
                format!("must lie in [0, 0.5), got {}", Shown(value)),
            ))
        }
    }

    /// A switch given as 0 or 1 (the default when absent).
    pub fn flag(&self, key: &str, default: bool) -> Result<bool, ModelError> {
        let value = self.number(key, Some(if default { 1.0 } else { 0.0 }))?;
        if value != 0.0 && value != 1.0 {
            return Err(ModelError::new(
                key,
                format!("must be 0 or 1, got {}", Shown(value)),
            ));
        }
        Ok(value == 1.0)
    }

    /// A number that must be a positive whole number (a tooth or pin count).
    pub fn count(&self, key: &str, default: Option<f64>) -> Result<u32, ModelError> {
        let value = self.number(key, default)?;
        if value >= 1.0 && value.fract() == 0.0 && value <= u32::MAX as f64 {
            Ok(value as u32)
        } else {
            Err(ModelError::new(
                key,
                format!("must be a positive whole number, got {}", Shown(value)),
            ))
        }
    }

    /// An object of named numbers.
    pub fn named(&self, key: &str) -> Result<&[(String, f64)], ModelError> {
        self.read.borrow_mut().insert(key.to_string());
        match self.values.get(key) {
            Some(ParamValue::Named(entries)) => Ok(entries),
            Some(ParamValue::Object(entries)) => {
                let (name, value) = entries
                    .iter()
                    .find(|(_, value)| !matches!(value, ParamValue::Number(_)))
                    .expect("an object of numbers only is read as Named");
                Err(ModelError::new(
                    format!("{key}.{name}"),
                    format!("expected a number, got {}", value.kind()),
                ))
            }
            Some(_) => Err(ModelError::new(key, "must be an object of named numbers")),
            None => Err(ModelError::new(key, "required parameter is missing")),
        }
    }

    /// An object's entries in the scenario's order (`None` when absent): an object of
    /// numbers only is given as entries of numbers.
    pub fn object(&self, key: &str) -> Result<Option<Vec<(String, ParamValue)>>, ModelError> {
        self.read.borrow_mut().insert(key.to_string());
        match self.values.get(key) {
            Some(ParamValue::Object(entries)) => Ok(Some(entries.clone())),
            Some(ParamValue::Named(entries)) => Ok(Some(
                entries
                    .iter()
                    .map(|(name, x)| (name.clone(), ParamValue::Number(*x)))
                    .collect(),
            )),
            Some(other) => Err(ModelError::new(
                key,
                format!("must be an object, got {}", other.kind()),
            )),
            None => Ok(None),
        }
    }

    /// A text, or the default when absent.
    pub fn text(&self, key: &str, default: &str) -> Result<String, ModelError> {
        self.read.borrow_mut().insert(key.to_string());
        match self.values.get(key) {
            Some(ParamValue::Text(text)) => Ok(text.clone()),
            Some(_) => Err(ModelError::new(key, "must be a string")),
            None => Ok(default.to_string()),
        }
    }

    /// The values under `keys` that are present, for a sub-model: absent keys stay absent,
    /// so the sub-model applies its own default or names the missing key, and checks the
    /// values under the same keys. Whether the keys are allowed here is up to this model's
    /// own [`Self::reject_unknown`] list.
    pub fn subset(&self, keys: &[&str]) -> ModelParams {
        let mut to = ModelParams::new();
        for &key in keys {
            if let Some(value) = self.values.get(key) {
                to.insert(key.to_string(), value.clone());
            }
        }
        to
    }

    /// Fails on the first key that no accessor read (call after building); a key renamed
    /// since ([`RENAMED`]) is told its new name.
    pub fn reject_unknown(&self, known: &[&str]) -> Result<(), ModelError> {
        let read = self.read.borrow();
        let Some(key) = self
            .values
            .keys()
            .find(|k| !read.contains(k.as_str()) && !known.contains(&k.as_str()))
        else {
            return Ok(());
        };
        let message = match RENAMED
            .iter()
            .find(|(old, new, _)| old == key && known.contains(new))
        {
            Some((_, new, why)) => format!("renamed {new} ({why})"),
            None => format!("unknown parameter; expected one of: {}", known.join(", ")),
        };
        Err(ModelError::new(key.clone(), message))
    }
}
