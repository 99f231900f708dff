//! The `python` model: outputs computed by a Python function the caller hands to
//! `Scenario(…, functions={"name": f})`.
//!
//! A scenario names it like any model:
//!
//! ```json
//! { "model": "python",
//!   "params": { "function": "gap",
//!               "inputs":  { "hole_d": "mm", "pin_d": "mm", "x": "mm", "y": "mm" },
//!               "outputs": { "gap_mm": { "unit": "mm" } } },
//!   "inputs": { "hole_d": "hole", "pin_d": "pin", "x": "hole_x", "y": "hole_y" } }
//! ```
//!
//! The function is called once per block of rows the engine evaluates (64 rows of a run)
//! with a dict of one float64 numpy array per input, and returns a dict of one array-like
//! per output (or, for one output, the array-like itself); lists, float32 and integer
//! arrays are converted to float64. Its values for a row depend on that row alone when it
//! computes element by element (numpy's arithmetic does), so a run gives the same bits for
//! any thread count; the calls take the interpreter's lock in turn. An exception, or an
//! answer of the wrong shape, makes that block's outputs NaN and is kept; the function
//! that asked for the work raises it as a `ValueError` naming the function.
//!
//! The engine finds a model by name in a registry of `'static` entries, so the functions
//! live in this module's table under a key unique to the `Scenario` that holds them
//! (`gap#3`), written into the scenario's text in place of the caller's name; the entry
//! leaves the table when the `Scenario` is dropped.

use std::collections::HashMap;
use std::sync::{Arc, LazyLock, Mutex};

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyMapping};
use rvtol_models::declared::declared_output;
use rvtol_models::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputSpec, ParamSpec, ParamValue,
};

/// A function a `Scenario` holds, and the first problem a call of it had.
struct Registered {
    /// The caller's name of it.
    label: String,
    function: Py<PyAny>,
    error: Mutex<Option<String>>,
}

/// The functions of every live `Scenario`, by their unique key.
static FUNCTIONS: LazyLock<Mutex<HashMap<String, Arc<Registered>>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));

/// The next key's serial number.
static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn table() -> std::sync::MutexGuard<'static, HashMap<String, Arc<Registered>>> {
    FUNCTIONS.lock().unwrap_or_else(|e| e.into_inner())
}

/// Registers `function` (the caller's `label`) and returns its unique key.
pub fn register(label: &str, function: Py<PyAny>) -> String {
    let key = format!(
        "{label}#{}",
        SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    );
    table().insert(
        key.clone(),
        Arc::new(Registered {
            label: label.to_string(),
            function,
            error: Mutex::new(None),
        }),
    );
    key
}

/// Takes the functions of `keys` out of the table (their `Scenario` is gone).
pub fn unregister(keys: &[String]) {
    let mut table = table();
    for key in keys {
        table.remove(key);
    }
}

/// The first problem a call of one of the functions `keys` had since the last time
/// asked (cleared), as the message a `ValueError` carries.
pub fn take_error(keys: &[String]) -> Option<String> {
    let table = table();
    keys.iter().find_map(|key| {
        let registered = table.get(key)?;
        let mut error = registered.error.lock().unwrap_or_else(|e| e.into_inner());
        error.take()
    })
}

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "function",
        unit: "",
        description: "the name of a function given to Scenario(…, functions={name: f})",
        default: None,
    },
    ParamSpec {
        name: "inputs",
        unit: "",
        description: "object: each input's name → the unit the function reads it in",
        default: None,
    },
    ParamSpec {
        name: "outputs",
        unit: "",
        description: "object: each output's name → {\"unit\", optional \"kind\": \"indicator\"}",
        default: None,
    },
];

/// Registry entry (registered when the module loads).
pub static ENTRY: ModelEntry = ModelEntry {
    name: "python",
    summary: "outputs computed by a Python function given to rvtol.Scenario(…, functions={name: f}) (the Python package only)",
    params: PARAMS,
    build: |params| Ok(Box::new(PythonModel::from_params(params)?)),
    example_params: ModelParams::new,
    example_inputs: &[],
};

/// A model whose outputs a Python function computes.
struct PythonModel {
    registered: Arc<Registered>,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

/// The entries of the object `key` of `params` (required).
fn object(params: &ModelParams, key: &str) -> Result<Vec<(String, ParamValue)>, ModelError> {
    params
        .object(key)?
        .ok_or_else(|| ModelError::new(key, "required"))
}

/// The text of `value` at `path`, non-empty.
fn text(path: &str, value: Option<&ParamValue>) -> Result<String, ModelError> {
    match value {
        Some(ParamValue::Text(text)) if !text.trim().is_empty() => Ok(text.clone()),
        Some(other) => Err(ModelError::new(
            path,
            format!("expected a non-empty string, got {}", other.kind()),
        )),
        None => Err(ModelError::new(path, "required")),
    }
}

impl PythonModel {
    fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let key = params.text("function", "")?;
        let registered = table().get(&key).cloned().ok_or_else(|| {
            ModelError::new(
                "function",
                format!(
                    "{:?} is not a function given to this Scenario (Scenario(…, functions={{name: f}}))",
                    key.split('#').next().unwrap_or_default()
                ),
            )
        })?;
        let mut inputs = Vec::new();
        for (name, unit) in object(params, "inputs")? {
            let unit = text(&format!("inputs.{name}"), Some(&unit))?;
            inputs.push(InputSpec {
                name,
                unit,
                description: "an input of the Python function",
            });
        }
        let mut outputs = Vec::new();
        for (name, spec) in object(params, "outputs")? {
            let path = format!("outputs.{name}");
            let (output, _) =
                declared_output(&name, &path, &spec, &[], "an output of the Python function")?;
            outputs.push(output);
        }
        if outputs.is_empty() {
            return Err(ModelError::new("outputs", "needs at least one output"));
        }
        params.reject_unknown(&["function", "inputs", "outputs"])?;
        Ok(PythonModel {
            registered,
            inputs,
            outputs,
        })
    }

    /// Calls the function on `n` rows and writes its outputs column by column.
    fn call(
        &self,
        py: Python<'_>,
        inputs: &[&[f64]],
        n: usize,
        outputs: &mut [f64],
    ) -> Result<(), String> {
        let label = &self.registered.label;
        let python = |err: PyErr| format!("function {label:?}: {err}");
        let dict = PyDict::new(py);
        for (spec, column) in self.inputs.iter().zip(inputs) {
            dict.set_item(&spec.name, PyArray1::from_slice(py, &column[..n]))
                .map_err(python)?;
        }
        let result = self
            .registered
            .function
            .bind(py)
            .call1((dict,))
            .map_err(|err| format!("function {label:?} raised {err}"))?;
        let numpy = py.import("numpy").map_err(python)?;
        let mapping = result.cast::<PyMapping>().ok();
        for (j, spec) in self.outputs.iter().enumerate() {
            let value = match (&mapping, self.outputs.len()) {
                (Some(mapping), _) => mapping.get_item(&spec.name).map_err(|_| {
                    format!(
                        "function {label:?} returned no {:?}: return a dict with one array per output",
                        spec.name
                    )
                })?,
                (None, 1) => result.clone(),
                (None, _) => {
                    return Err(format!(
                        "function {label:?} returned {}: with several outputs, return a dict with one array per output",
                        result.get_type().name().map_or_else(|_| "a value".into(), |n| n.to_string())
                    ))
                }
            };
            let array = numpy
                .call_method1("asarray", (value, "float64"))
                .and_then(|a| a.call_method1("reshape", (-1,)))
                .map_err(|err| {
                    format!(
                        "function {label:?}: output {:?} is not numbers: {err}",
                        spec.name
                    )
                })?;
            let array = array
                .cast_into::<PyArray1<f64>>()
                .map_err(|err| err.to_string())?;
            let values: PyReadonlyArray1<f64> = array.readonly();
            let values = values.as_slice().map_err(|err| err.to_string())?;
            if values.len() != n {
                return Err(format!(
                    "function {label:?} returned {} values of {:?} for {n} rows: one per row",
                    values.len(),
                    spec.name
                ));
            }
            outputs[j * n..(j + 1) * n].copy_from_slice(values);
        }
        Ok(())
    }
}

impl ErrorModel for PythonModel {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]) {
        let columns: Vec<&[f64]> = inputs.iter().map(std::slice::from_ref).collect();
        self.evaluate_columns(&columns, outputs);
    }

    fn evaluate_columns(&self, inputs: &[&[f64]], outputs: &mut [f64]) {
        let n = outputs.len() / self.outputs.len().max(1);
        let result = Python::attach(|py| self.call(py, inputs, n, outputs));
        if let Err(message) = result {
            outputs.fill(f64::NAN);
            let mut error = (self.registered.error.lock()).unwrap_or_else(|e| e.into_inner());
            error.get_or_insert(message);
        }
    }
}
