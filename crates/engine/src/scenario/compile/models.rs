//! The models' input bindings, the pass after the input space is built: each model that
//! built ([`super::reducer`]) has every input bound ([`super::bindings`]), every key of its
//! `inputs` names an input or matches some by its pattern (an array's pattern its members
//! one to one), and its outputs join the scenario's ([`super::outputs`]). A model with any
//! problem is reported and left out of the scenario.

use std::collections::{BTreeMap, BTreeSet};

use rvtol_deviation::index_list;
use rvtol_models::{ErrorModel, InputSpec, ModelEntry};

use super::super::file::ModelFile;
use super::super::{Binding, BoundModel};
use super::bindings::{indexed_summary, input_binding, pattern, InputBinding};
use super::Compiler;
use crate::error::ScenarioError;

/// A model of the file built from its parameters, or the problems (each with its JSON
/// path) that kept it from building. Built once: the units of its inputs serve the
/// variables' unit conversion, before the model's bindings are checked.
pub(super) type BuiltModel = Result<(&'static ModelEntry, Box<dyn ErrorModel>), Vec<ScenarioError>>;

/// Binds every model that built; reports those that did not.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    if file.models.is_empty() && !compiler.models_failed_to_parse {
        compiler.report(Err(ScenarioError::new(
            "models",
            "needs at least one model",
        )));
    }
    let built = std::mem::take(&mut compiler.built_models);
    for (i, built) in built.iter().enumerate() {
        if let Ok((_, model)) = built {
            for output in model.outputs() {
                compiler
                    .outputs_below
                    .entry(output.name.clone())
                    .or_insert(i);
            }
        }
    }
    for ((i, model_file), built) in file.models.iter().zip(built) {
        let path = format!("models[{i}]");
        compiler.models_bound = *i;
        let (entry, model) = match built {
            Ok(built) => built,
            Err(problems) => {
                for problem in problems {
                    compiler.report(Err(problem));
                }
                continue;
            }
        };
        compiler.models_built += 1;
        compiler.bind_model(&path, model_file, entry, model);
    }
}

/// The binding pass of one model.
struct ModelBinding<'m> {
    /// One binding per input so far.
    bindings: Vec<Binding>,
    /// Whether the model is bound so far (no problem found).
    bound: bool,
    /// Per `*` pattern, the indices of the inputs it binds.
    pattern_indices: BTreeMap<&'m str, Vec<u64>>,
    /// Patterns that bind an input bound already (reported once, not checked further).
    conflicted: BTreeSet<String>,
    /// Inputs bound by nothing.
    unbound: Vec<&'m str>,
    /// The binding paths reported already (a pattern's mistake is the same for every
    /// input it matches: one line).
    reported: BTreeSet<String>,
}

impl Compiler<'_> {
    /// Binds the inputs of `model` (built from `model_file`, at `path`) and adds its
    /// outputs; the model joins the scenario when nothing was wrong.
    fn bind_model(
        &mut self,
        path: &str,
        model_file: &ModelFile,
        entry: &'static ModelEntry,
        model: Box<dyn ErrorModel>,
    ) {
        let mut state = ModelBinding {
            bindings: Vec::with_capacity(model.inputs().len()),
            bound: true,
            pattern_indices: BTreeMap::new(),
            conflicted: BTreeSet::new(),
            unbound: Vec::new(),
            reported: BTreeSet::new(),
        };
        for key in model_file.inputs.keys() {
            if key.matches('*').count() > 1 {
                self.report(Err(ScenarioError::new(
                    format!("{path}.inputs.{key}"),
                    "a pattern has one '*', which stands for the index (1, 2, …)",
                )));
                state.bound = false;
            }
        }
        for input in model.inputs() {
            self.bind_input(path, model_file, &*model, input, &mut state);
        }
        self.check_input_keys(path, model_file, entry, &*model, &mut state);
        self.report_unbound(path, &*model, &mut state);
        let first_output = self.add_outputs(path, entry, &*model, &mut state.bound);
        let ModelBinding {
            bindings, bound, ..
        } = state;
        if bound {
            self.models.push(BoundModel {
                model,
                bindings,
                first_output,
            });
        }
    }

    /// Binds one input of `model`: by its key or a pattern, to a number or a column.
    fn bind_input<'m>(
        &mut self,
        path: &str,
        model_file: &'m ModelFile,
        model: &dyn ErrorModel,
        input: &'m InputSpec,
        state: &mut ModelBinding<'m>,
    ) {
        let binding = match input_binding(path, &model_file.inputs, &input.name) {
            Err(err) => {
                state.conflicted.insert(err.path.clone());
                Err(err)
            }
            Ok(None) => {
                // Reported once for all of them, below.
                state.unbound.push(input.name.as_str());
                Ok(Some(Binding::Constant(0.0)))
            }
            Ok(Some(InputBinding {
                value,
                path: binding_path,
                pattern,
            })) => {
                if let Some((key, index)) = pattern {
                    state.pattern_indices.entry(key).or_default().push(index);
                }
                let index = pattern.map(|(_, index)| index);
                let position = state.bindings.len();
                self.bound_value(model, position, input, value, &binding_path, index)
            }
        };
        match binding {
            Ok(Some(binding)) => state.bindings.push(binding),
            // A reference to an element that could not be built, reported already.
            Ok(None) => {
                state.bound = false;
                state.bindings.push(Binding::Constant(0.0));
            }
            Err(err) => {
                if state.reported.insert(err.path.clone()) {
                    self.report(Err(err));
                }
                state.bound = false;
                state.bindings.push(Binding::Constant(0.0));
            }
        }
    }

    /// Every key of the model's `inputs` names one of its inputs, or is a pattern that
    /// matches some (an array's pattern binds its members one to one).
    fn check_input_keys(
        &mut self,
        path: &str,
        model_file: &ModelFile,
        entry: &ModelEntry,
        model: &dyn ErrorModel,
        state: &mut ModelBinding,
    ) {
        let known = || {
            let names: Vec<&str> = model.inputs().iter().map(|i| i.name.as_str()).collect();
            indexed_summary(&names)
        };
        for (key, value) in &model_file.inputs {
            let key_path = format!("{path}.inputs.{key}");
            if pattern(key).is_none() {
                if !model.inputs().iter().any(|input| &input.name == key) {
                    self.report(Err(ScenarioError::new(
                        key_path,
                        format!(
                            "{} has no input {key:?}; its inputs are: {}",
                            entry.name,
                            known()
                        ),
                    )));
                    state.bound = false;
                }
                continue;
            }
            if key.matches('*').count() > 1 {
                continue;
            }
            let indices = (state.pattern_indices)
                .get(key.as_str())
                .cloned()
                .unwrap_or_default();
            if indices.is_empty() {
                self.report(Err(ScenarioError::new(
                    key_path,
                    if state.unbound.is_empty() {
                        format!(
                            "matches no input of {}; its inputs are: {}",
                            entry.name,
                            known()
                        )
                    } else {
                        format!(
                            "matches no input of {}; the inputs left unbound are: {}",
                            entry.name,
                            indexed_summary(&state.unbound)
                        )
                    },
                )));
                state.bound = false;
                continue;
            }
            // A pattern that binds an input bound already is reported once, above.
            if state.conflicted.contains(&key_path) {
                continue;
            }
            // A pattern bound to an array binds every member, once.
            let mismatch = value
                .as_str()
                .and_then(|name| self.arrays.get(name))
                .and_then(|(_, members)| {
                    let mut seen = indices.clone();
                    seen.sort_unstable();
                    let all = seen.len() == members.len()
                        && seen.iter().enumerate().all(|(k, &i)| i == k as u64 + 1);
                    (!all && seen.iter().all(|&i| i as usize <= members.len())).then(|| {
                        let name = value.as_str().unwrap_or_default();
                        ScenarioError::new(
                            key_path,
                            format!(
                                "binds {} inputs (indices {}) but {name:?} has {} members: the array must match the inputs one to one",
                                seen.len(),
                                index_list(&seen),
                                members.len()
                            ),
                        )
                    })
                });
            if let Some(problem) = mismatch {
                self.report(Err(problem));
                state.bound = false;
            }
        }
    }

    /// The inputs bound by nothing, in one problem.
    fn report_unbound(&mut self, path: &str, model: &dyn ErrorModel, state: &mut ModelBinding) {
        let unbound = &state.unbound;
        if unbound.is_empty() {
            return;
        }
        state.bound = false;
        let units: BTreeSet<&str> = model
            .inputs()
            .iter()
            .filter(|i| unbound.contains(&i.name.as_str()))
            .map(|i| i.unit.as_str())
            .collect();
        let units: Vec<&str> = units.into_iter().collect();
        self.report(Err(ScenarioError::new(
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
                    indexed_summary(unbound),
                    units.join(", ")
                )
            },
        )));
    }
}
