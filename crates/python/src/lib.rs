//! rvtol from Python: the module `rvtol`, built with maturin (crates/python/pyproject.toml).
//!
//! A thin layer over rvtol-engine and rvtol-analysis: every function makes the request the
//! command of the same name makes (rvtol-analysis' `request`: the same defaults, limits and
//! checks, the memory it needs against `max_memory` or what the machine has) and computes
//! what it computes (the same calls, the same JSON report, so the same bits for the same
//! seed), and hands the report over as a Python dict (the JSON parsed by Python's `json`),
//! arrays as numpy arrays. The work runs with the interpreter's lock released, on a rayon
//! pool of `threads` threads (default: all cores). Errors are `ValueError` with the command
//! line's one-line message, options spelt as this module's keywords (a scenario value by
//! its JSON path).

mod function;

use numpy::{PyArray2, PyReadonlyArray2, ToPyArray};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use rvtol_analysis::allocation::allocate as run_allocation;
use rvtol_analysis::allocation::report::AllocationReport;
use rvtol_analysis::rare::report::rare_report;
use rvtol_analysis::rare::Method;
use rvtol_analysis::request::allocation::AllocationRequest;
use rvtol_analysis::request::input_file::ReadLimit;
use rvtol_analysis::request::rare::RareRequest;
use rvtol_analysis::request::run::{check_samples_out, sampling_method, RunRequest};
use rvtol_analysis::request::scenario::{ScenarioSource, SourceError};
use rvtol_analysis::request::sensitivity::{
    SensitivityRequest, ShapleyRequest, DEFAULT_OUTER, DEFAULT_PERMUTATIONS, DEFAULT_SAMPLES,
};
use rvtol_analysis::request::stack::StackRequest;
use rvtol_analysis::request::{machine, memory, Caller};
use rvtol_analysis::sensitivity::sobol_indices;
use rvtol_analysis::sensitivity_report::SensitivityReport;
use rvtol_analysis::shapley::shapley_effects;
use rvtol_analysis::stack::report::stack_report;
use rvtol_engine::chunk::SamplingMethod;
use rvtol_engine::{RunReport, DEFAULT_EXACT_PERCENTILE_LIMIT};

/// The Python module's spelling of options in the library's messages.
const CALLER: Caller = Caller::Python;

/// A validated scenario: `Scenario(path)` reads a scenario file, `Scenario(dict)` takes
/// the scenario as a dict (as the JSON file would hold it); `functions={name: f}` gives
/// the Python functions its `python` models name (module `function`).
#[pyclass(module = "rvtol", frozen)]
struct Scenario {
    inner: rvtol_engine::Scenario,
    /// The scenario's JSON text (the allocation reads it), its `python` models naming
    /// their functions by key.
    text: String,
    /// The keys of its functions in the table of module `function`.
    functions: Vec<String>,
}

impl Drop for Scenario {
    fn drop(&mut self) {
        function::unregister(&self.functions);
    }
}

impl Scenario {
    /// The first problem a call of one of its Python functions had, as a `ValueError`.
    fn raise_function_error(&self) -> PyResult<()> {
        match function::take_error(&self.functions) {
            Some(message) => Err(value_error(message)),
            None => Ok(()),
        }
    }
}

/// The scenario text with each `python` model's `params.function` replaced by the key
/// of its function, registered now (the keys returned); a name no model uses, or a model
/// whose name is not among `functions`, is an error.
fn with_functions(
    text: &str,
    functions: Option<&Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<String>)> {
    let Some(functions) = functions else {
        return Ok((text.to_string(), Vec::new()));
    };
    let mut document: serde_json::Value = serde_json::from_str(text).map_err(value_error)?;
    let mut given: Vec<(String, Py<PyAny>)> = Vec::new();
    for (name, function) in functions.iter() {
        let name: String = name
            .extract()
            .map_err(|_| PyTypeError::new_err("functions: the keys are names (str)"))?;
        if !function.is_callable() {
            return Err(PyTypeError::new_err(format!(
                "functions[{name:?}]: not callable"
            )));
        }
        given.push((name, function.unbind()));
    }
    let mut keys: Vec<(String, String)> = Vec::new();
    let models = document.get_mut("models").and_then(|m| m.as_array_mut());
    for (i, model) in models.into_iter().flatten().enumerate() {
        if model.get("model").and_then(|m| m.as_str()) != Some(function::ENTRY.name) {
            continue;
        }
        let Some(slot) = model.pointer_mut("/params/function") else {
            continue; // the model says what is missing
        };
        let name = slot.as_str().unwrap_or_default().to_string();
        let Some((_, f)) = given.iter().find(|(n, _)| *n == name) else {
            return Err(value_error(format!(
                "models[{i}].params.function: {name:?} is not among the functions given ({})",
                given
                    .iter()
                    .map(|(n, _)| format!("{n:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        };
        let key = function::register(&name, f.clone_ref(functions.py()));
        *slot = serde_json::Value::String(key.clone());
        keys.push((name, key));
    }
    if let Some((unused, _)) = given
        .iter()
        .find(|(n, _)| !keys.iter().any(|(k, _)| k == n))
    {
        let keys: Vec<String> = keys.into_iter().map(|(_, k)| k).collect();
        function::unregister(&keys);
        return Err(value_error(format!(
            "functions[{unused:?}]: no `python` model of the scenario names it (params.function)"
        )));
    }
    let keys = keys.into_iter().map(|(_, k)| k).collect();
    Ok((document.to_string(), keys))
}

fn value_error(message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(message.to_string())
}

/// The scenario's JSON text and its fallback name, from a path or a dict, with the
/// numbers of the data files it refers to written in (paths relative to the file's
/// folder, or to the working directory for a dict), as the command line reads it.
fn scenario_text(source: &Bound<'_, PyAny>) -> PyResult<(String, String)> {
    let source = if let Ok(path) = source.extract::<std::path::PathBuf>() {
        ScenarioSource::File(path)
    } else if source.is_instance_of::<PyDict>() {
        let json = source.py().import("json")?;
        let text: String = json.call_method1("dumps", (source,))?.extract()?;
        ScenarioSource::Text {
            text,
            folder: std::path::PathBuf::from("."),
        }
    } else {
        return Err(PyTypeError::new_err(
            "a scenario is a path (str or os.PathLike) or a dict",
        ));
    };
    let text = source
        .read(&ReadLimit::library())
        .map_err(|err| match err {
            SourceError::Read(message) => value_error(message),
            SourceError::Scenario(err) => value_error(err),
        })?;
    Ok((text.text, text.fallback_name))
}

/// A rayon pool of `threads` threads (all cores when None) for `command`, once what it
/// needs in memory at that thread count fits the budget (`max_memory` or what the machine
/// has).
fn pool(
    command: &str,
    threads: Option<usize>,
    max_memory: Option<f64>,
    need: impl FnOnce(usize) -> memory::MemoryNeed,
) -> PyResult<rayon::ThreadPool> {
    machine::pool_for(command, threads.map(|n| n as u64), max_memory, CALLER, need)
        .map_err(value_error)
}

/// A JSON document as a Python object.
fn parsed<'py>(py: Python<'py>, json: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (json,))
}

#[pymethods]
impl Scenario {
    #[new]
    #[pyo3(signature = (source, *, functions = None))]
    fn new(source: &Bound<'_, PyAny>, functions: Option<&Bound<'_, PyDict>>) -> PyResult<Scenario> {
        let (text, name) = scenario_text(source)?;
        let (text, keys) = with_functions(&text, functions)?;
        match rvtol_engine::Scenario::from_json(&text, &name) {
            Ok(inner) => Ok(Scenario {
                inner,
                text,
                functions: keys,
            }),
            Err(err) => {
                function::unregister(&keys);
                Err(value_error(err))
            }
        }
    }

    /// The scenario's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The input columns, in the order `evaluate` and the samples use: a variable, or a
    /// part's `part.du` … `part.dgamma`.
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.inner.columns.iter().map(|c| c.name.clone()).collect()
    }

    /// The outputs, in order.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.inner.outputs.iter().map(|o| o.name.clone()).collect()
    }

    /// Every output on given input rows (a 2-D float array, one column per input in the
    /// order of `inputs`): a 2-D array with one column per output. Rows that would need
    /// more memory than `max_memory` bytes (default: what the machine has) are refused
    /// before any is evaluated.
    #[pyo3(signature = (inputs, threads = None, max_memory = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        inputs: &Bound<'py, PyAny>,
        threads: Option<usize>,
        max_memory: Option<f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        evaluate_rows(
            py,
            &self.inner,
            &self.functions,
            inputs,
            threads,
            max_memory,
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "rvtol.Scenario({:?}: {} inputs, {} outputs)",
            self.inner.name,
            self.inner.columns.len(),
            self.inner.outputs.len()
        )
    }
}

/// Evaluates `scenario` on given rows (any 2-D array-like of numbers: converted to
/// float64); `functions` are the keys of its Python functions.
fn evaluate_rows<'py>(
    py: Python<'py>,
    scenario: &rvtol_engine::Scenario,
    functions: &[String],
    inputs: &Bound<'py, PyAny>,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let converted = py
        .import("numpy")?
        .call_method1("asarray", (inputs, "float64"))
        .map_err(|err| value_error(format!("inputs: not a 2-D array of numbers: {err}")))?;
    let converted: PyReadonlyArray2<'py, f64> = converted.extract().map_err(|_| {
        value_error("inputs: a 2-D array (one row per sample, one column per input)")
    })?;
    let array = converted.as_array();
    let (rows, columns) = array.dim();
    let n_inputs = scenario.input_space.n_columns();
    if columns != n_inputs {
        return Err(value_error(format!(
            "inputs: {columns} columns, the scenario has {n_inputs} inputs ({})",
            scenario
                .columns
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    rvtol_engine::evaluate::check_table_rows(scenario, rows as u64)
        .map_err(|message| value_error(format!("inputs: {message}")))?;
    let pool = pool("evaluate", threads, max_memory, |threads| {
        memory::rows_evaluation(scenario, rows as u64, threads)
    })?;
    let values: Vec<f64> = array.iter().copied().collect();
    let table =
        py.detach(|| pool.install(|| rvtol_engine::evaluate::evaluate_rows(scenario, values)));
    if let Some(message) = function::take_error(functions) {
        return Err(value_error(message));
    }
    let outputs = numpy::ndarray::Array2::from_shape_vec((rows, table.n_outputs), table.outputs)
        .map_err(value_error)?;
    Ok(outputs.to_pyarray(py))
}

/// Evaluates the model `model` with the parameters `params` (a dict; the others at the
/// example design's values, as `rvtol init` writes them) on given input rows: a 2-D float
/// array with one column per model input in the order `rvtol models` lists them. Returns a
/// 2-D array with one column per model output. Rows run in parallel on `threads` threads;
/// rows that would need more memory than `max_memory` bytes (default: what the machine
/// has) are refused before any is evaluated.
#[pyfunction]
#[pyo3(signature = (model, params, inputs, threads = None, max_memory = None))]
fn evaluate<'py>(
    py: Python<'py>,
    model: &str,
    params: Option<&Bound<'py, PyDict>>,
    inputs: &Bound<'py, PyAny>,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let given: serde_json::Map<String, serde_json::Value> = match params {
        Some(params) => {
            let json = py.import("json")?;
            let text: String = json.call_method1("dumps", (params,))?.extract()?;
            serde_json::from_str(&text).map_err(value_error)?
        }
        None => serde_json::Map::new(),
    };
    // The skeleton of the model with these parameters: its inputs are the model's.
    let skeleton =
        rvtol_engine::scenario::skeleton::skeleton_with(model, &given).map_err(value_error)?;
    let scenario = rvtol_engine::Scenario::from_json(&skeleton, model).map_err(value_error)?;
    evaluate_rows(py, &scenario, &[], inputs, threads, max_memory)
}

/// Runs the Monte Carlo simulation (as `rvtol run`): returns the JSON report as a dict,
/// and with `samples_out=True` also a dict of the samples: `inputs` and `outputs` (2-D
/// arrays, one row per sample), `input_names`, `output_names`. `samples`, `seed`,
/// `sampling` ("mc", "lhs" or "rqmc") and `replicates` default to the scenario's. A run
/// whose share of non-finite values exceeds `max_non_finite` raises after nothing is
/// returned; one that needs more memory than `max_memory` bytes (default: what the machine
/// has) raises before it starts.
#[pyfunction]
#[pyo3(signature = (scenario, samples = None, seed = None, *, sampling = None, replicates = None,
    samples_out = false, exact_percentile_limit = DEFAULT_EXACT_PERCENTILE_LIMIT,
    max_non_finite = 0.0, threads = None, max_memory = None))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    samples: Option<u64>,
    seed: Option<u64>,
    sampling: Option<&str>,
    replicates: Option<u64>,
    samples_out: bool,
    exact_percentile_limit: u64,
    max_non_finite: f64,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = &scenario.inner;
    let request = RunRequest {
        samples,
        seed,
        exact_percentile_limit,
        sampling: method(sampling)?,
        replicates,
    };
    let settings = request.settings(s, CALLER).map_err(value_error)?;
    if samples_out {
        check_samples_out(s, settings.samples, CALLER).map_err(value_error)?;
    }
    let pool = pool("run", threads, max_memory, |threads| {
        memory::run(s, &settings, threads)
    })?;
    let result = py.detach(|| {
        pool.install(|| -> Result<_, rvtol_engine::ScenarioError> {
            let result = rvtol_engine::run(s, settings, &|_| {})?;
            rvtol_engine::run::check_non_finite(s, &result, max_non_finite)?;
            let json = RunReport::new(s, result).to_json();
            let table = if samples_out {
                Some(rvtol_engine::sample_table(s, settings)?)
            } else {
                None
            };
            Ok((json, table))
        })
    });
    scenario.raise_function_error()?;
    let (json, table) = result.map_err(value_error)?;
    let report = parsed(py, &json)?;
    let Some(table) = table else {
        return Ok(report);
    };
    let array = |values: Vec<f64>, width: usize| {
        numpy::ndarray::Array2::from_shape_vec((table.rows, width), values)
            .map(|a| a.to_pyarray(py))
            .map_err(value_error)
    };
    let out = PyDict::new(py);
    out.set_item("inputs", array(table.inputs, table.n_inputs)?)?;
    out.set_item("outputs", array(table.outputs, table.n_outputs)?)?;
    out.set_item(
        "input_names",
        PyList::new(py, s.columns.iter().map(|c| c.name.clone()))?,
    )?;
    out.set_item(
        "output_names",
        PyList::new(py, s.outputs.iter().map(|o| o.name.clone()))?,
    )?;
    Ok((report, out).into_pyobject(py)?.into_any())
}

/// The sampling method a name asks for (`None`: the scenario's).
fn method(sampling: Option<&str>) -> PyResult<Option<SamplingMethod>> {
    sampling
        .map(|name| sampling_method(name, CALLER).map_err(value_error))
        .transpose()
}

/// Sobol' first-order and total indices with their intervals, the linearised screening
/// and, with `shapley=True`, Shapley effects (as `rvtol sensitivity`): the JSON report as
/// a dict. `sampling` ("mc", "lhs" or "rqmc") and `replicates` default to the scenario's;
/// Monte Carlo intervals come from `bootstrap` resamples (default 500), those of an lhs or
/// rqmc design from its replicates. The limits are the command line's (at least 2 base
/// samples, 2 to 1,000,000 resamples, at most 10⁹ Shapley draws, the memory it needs
/// within `max_memory` bytes or what the machine has).
#[pyfunction]
#[pyo3(signature = (scenario, samples = DEFAULT_SAMPLES, seed = None, *, sampling = None,
    replicates = None, bootstrap = None,
    row_bootstrap_limit = rvtol_analysis::sensitivity::DEFAULT_ROW_BOOTSTRAP_LIMIT,
    shapley = false, permutations = DEFAULT_PERMUTATIONS, outer = DEFAULT_OUTER,
    threads = None, max_memory = None))]
#[allow(clippy::too_many_arguments)]
fn sensitivity<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    samples: u64,
    seed: Option<u64>,
    sampling: Option<&str>,
    replicates: Option<u64>,
    bootstrap: Option<u64>,
    row_bootstrap_limit: u64,
    shapley: bool,
    permutations: u64,
    outer: u64,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = &scenario.inner;
    let request = SensitivityRequest {
        samples,
        seed,
        sampling: method(sampling)?,
        replicates,
        bootstrap,
        row_bootstrap_limit,
        shapley: shapley.then_some(ShapleyRequest {
            permutations,
            outer,
        }),
    };
    let settings = request.settings(s, CALLER).map_err(value_error)?;
    let shapley = request.shapley_settings(settings.seed);
    let pool = pool("sensitivity", threads, max_memory, |threads| {
        memory::sensitivity(s, &settings, threads)
    })?;
    let json = py.detach(|| {
        pool.install(|| -> Result<String, rvtol_engine::ScenarioError> {
            let outputs = sobol_indices(s, settings, &|_| {})?;
            let effects = match shapley {
                Some(shapley) => Some(shapley_effects(s, shapley)?),
                None => None,
            };
            Ok(SensitivityReport::complete(s, settings, outputs, effects)?.to_json())
        })
    });
    scenario.raise_function_error()?;
    let json = json.map_err(value_error)?;
    parsed(py, &json)
}

/// The worst case over the tolerance box, the arithmetic and RSS stacks, the contributor
/// table and the linearisation's R², beside a Monte Carlo run's P0.135, P99.865 and ppm
/// out of spec (as `rvtol stack`): the JSON report as a dict. `outputs` (a list of names)
/// defaults to every continuous output, `samples` and `seed` to the scenario's;
/// `monte_carlo=False` leaves the run out; an output that is not finite in more than
/// `max_non_finite` of the rows (default 0) raises, as `run` does.
#[pyfunction]
#[pyo3(signature = (scenario, outputs = None, *, samples = None, seed = None,
    monte_carlo = true, max_non_finite = 0.0, threads = None, max_memory = None))]
#[allow(clippy::too_many_arguments)]
fn stack<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    outputs: Option<Vec<String>>,
    samples: Option<u64>,
    seed: Option<u64>,
    monte_carlo: bool,
    max_non_finite: f64,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = &scenario.inner;
    let request = StackRequest {
        outputs: outputs.unwrap_or_default(),
        seed,
        monte_carlo,
        samples,
        max_non_finite,
    };
    let (settings, run_settings) = request.settings(s, CALLER).map_err(value_error)?;
    let pool = pool("stack", threads, max_memory, |threads| {
        memory::stack(s, run_settings.as_ref(), threads)
    })?;
    let json = py.detach(|| {
        pool.install(|| {
            stack_report(s, &settings, run_settings, &|_| {}).map(|report| report.to_json())
        })
    });
    scenario.raise_function_error()?;
    let json = json.map_err(value_error)?;
    parsed(py, &json)
}

/// The probability of an output's rare event (as `rvtol rare`): out of its spec limits
/// (flagged assemblies counted) unless `above` or `below` gives a threshold, by
/// importance sampling and subset simulation (`methods`, a list of `"importance"`,
/// `"subset"`; default both), each until its 95 % interval is within `precision` (0.1:
/// ±10 %) or `max_evaluations` are spent: the JSON report as a dict. `output` defaults to
/// the scenario's only continuous output.
#[pyfunction]
#[pyo3(signature = (scenario, output = None, *, above = None, below = None, methods = None,
    precision = None, max_evaluations = None, level_samples = None, seed = None,
    max_non_finite = 0.0, threads = None, max_memory = None))]
#[allow(clippy::too_many_arguments)]
fn rare<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    output: Option<String>,
    above: Option<f64>,
    below: Option<f64>,
    methods: Option<Vec<String>>,
    precision: Option<f64>,
    max_evaluations: Option<u64>,
    level_samples: Option<u64>,
    seed: Option<u64>,
    max_non_finite: f64,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = &scenario.inner;
    let methods = (methods.unwrap_or_default().iter())
        .map(|m| match m.as_str() {
            "importance" => Ok(Method::Importance),
            "subset" => Ok(Method::Subset),
            other => Err(PyValueError::new_err(format!(
                "methods: unknown method {other:?}: importance or subset"
            ))),
        })
        .collect::<PyResult<Vec<Method>>>()?;
    let request = RareRequest {
        output,
        above,
        below,
        methods,
        precision,
        max_evaluations,
        level_samples,
        seed,
        max_non_finite,
    };
    let settings = request.settings(s, CALLER).map_err(value_error)?;
    let pool = pool("rare", threads, max_memory, |threads| {
        memory::rare(s, settings.level_samples, threads)
    })?;
    let json = py.detach(|| {
        pool.install(|| rare_report(s, &settings, &|_| {}).map(|report| report.to_json()))
    });
    scenario.raise_function_error()?;
    let json = json.map_err(value_error)?;
    parsed(py, &json)
}

/// The cheapest tolerances within the scenario's `allocation` bounds that meet `target` on
/// `output` (as `rvtol allocate`), verified by an independent run: the JSON report as a
/// dict (its `status` says met, not verified or infeasible). `rare=True` estimates a ppm
/// target by importance sampling (`--rare`, with `precision` and `max_evaluations`).
#[pyfunction]
#[pyo3(signature = (scenario, output, target, *, cost = None, samples = None, seed = None,
    verify_seed = None, rare = false, precision = None, max_evaluations = None,
    threads = None, max_memory = None))]
#[allow(clippy::too_many_arguments)]
fn allocate<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    output: &str,
    target: &str,
    cost: Option<&str>,
    samples: Option<u64>,
    seed: Option<u64>,
    verify_seed: Option<u64>,
    rare: bool,
    precision: Option<f64>,
    max_evaluations: Option<u64>,
    threads: Option<usize>,
    max_memory: Option<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let s = &scenario.inner;
    let request = AllocationRequest {
        target,
        cost,
        samples,
        seed,
        verify_seed,
        rare,
        precision,
        max_evaluations,
    };
    let (target, settings) = request.settings(s, CALLER).map_err(value_error)?;
    let pool = pool("allocate", threads, max_memory, |threads| {
        memory::allocation(s, &settings, threads)
    })?;
    let text = &scenario.text;
    let json = py.detach(|| {
        pool.install(|| {
            run_allocation(s, text, output, target, settings, &|_| {})
                .map(|allocation| AllocationReport::new(&allocation).to_json())
        })
    });
    scenario.raise_function_error()?;
    let json = json.map_err(value_error)?;
    parsed(py, &json)
}

/// The models: a list of dicts with `name`, `summary`, `params` (the parameters' names),
/// `inputs` and `outputs` (each a list of (name, unit)).
#[pyfunction]
fn models(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for entry in rvtol_models::all() {
        let model = (entry.build)(&(entry.example_params)()).map_err(value_error)?;
        let item = PyDict::new(py);
        item.set_item("name", entry.name)?;
        item.set_item("summary", entry.summary)?;
        let params: Vec<&str> = entry.params.iter().map(|p| p.name).collect();
        item.set_item("params", PyList::new(py, params)?)?;
        let pairs = |ports: Vec<(String, String)>| PyList::new(py, ports);
        item.set_item(
            "inputs",
            pairs(
                model
                    .inputs()
                    .iter()
                    .map(|i| (i.name.clone(), i.unit.clone()))
                    .collect(),
            )?,
        )?;
        item.set_item(
            "outputs",
            pairs(
                model
                    .outputs()
                    .iter()
                    .map(|o| (o.name.clone(), o.unit.clone()))
                    .collect(),
            )?,
        )?;
        list.append(item)?;
    }
    Ok(list)
}

/// rvtol: Monte Carlo tolerance and deviation statistics for RV reducers.
#[pymodule]
fn rvtol(module: &Bound<'_, PyModule>) -> PyResult<()> {
    rvtol_models::register(&function::ENTRY);
    module.add_class::<Scenario>()?;
    module.add_function(wrap_pyfunction!(run, module)?)?;
    module.add_function(wrap_pyfunction!(evaluate, module)?)?;
    module.add_function(wrap_pyfunction!(sensitivity, module)?)?;
    module.add_function(wrap_pyfunction!(stack, module)?)?;
    module.add_function(wrap_pyfunction!(rare, module)?)?;
    module.add_function(wrap_pyfunction!(allocate, module)?)?;
    module.add_function(wrap_pyfunction!(models, module)?)?;
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
