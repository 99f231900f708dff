//! `expression`: a model written in the scenario, its outputs formulas over its inputs and
//! parameters, for an assembly none of the built-in models describes (a pin in a hole with
//! a position tolerance: `gap = (D − d)/2 − hypot(x, y)`).
//!
//! ```json
//! { "model": "expression",
//!   "params": {
//!     "inputs":  { "hole_d": "mm", "pin_d": "mm", "x": "mm", "y": "mm" },
//!     "let":     { "offset": "hypot(x, y)" },
//!     "outputs": { "gap_mm": { "formula": "(hole_d - pin_d)/2 - offset", "unit": "mm" } },
//!     "units":   { "k": "1" },
//!     "k": 1.0 },
//!   "inputs": { "hole_d": "hole", "pin_d": "pin", "x": "x_pos", "y": "y_pos" } }
//! ```
//!
//! `params.inputs` declares each input and the unit the formulas read it in (a variable
//! bound to it is converted to that unit when it loads, like any model's input);
//! `params.let` names intermediate quantities; `params.outputs` gives each output its
//! formula, its unit, optionally a `description` and `"kind": "indicator"` for a 0/1
//! event; every other number in `params` is a parameter the formulas read by name (an
//! `allocation` lever can change it), its unit optionally in `params.units`. A formula
//! reads the inputs, the parameters, `pi` and every `let` and output defined above it.
//! The grammar and functions are [`parse`]'s and [`compile`]'s; the arithmetic
//! [`program`]'s.
//!
//! Why a parser written here and a column program rather than a crate: the crates
//! evaluate one row at a time, from a tree with a context map of names (`evalexpr`,
//! `meval`), a compiled slab with a name callback (`fasteval`) or a flat expression
//! (`exmex`); `meval` (2019) and `fasteval` (2020) are no longer released, three of the four
//! lack `atan2` and `hypot`, and none gives the character of a mistake in a form this error
//! contract can use. Measured on the ten-input function of the `expression_per_sample`
//! benchmark (one thread, 4096 rows, best of 20 passes, a throwaway program against
//! evalexpr 12.0.3, exmex 0.20.5, fasteval 0.2.4, meval 0.2.0, `atan(a/b)` and
//! `sqrt(a^2 + b^2)` where a crate has no `atan2` or `hypot`): evalexpr 2.3 µs a sample,
//! meval 2.0 µs, fasteval 379 ns, exmex 202 ns; this column program 73 ns (criterion), the
//! same function as a built-in model 70 ns. The program evaluates a block of rows per
//! instruction, which is what makes a formula as fast as a built-in model, and its
//! messages say where the mistake is.

mod compile;
mod parse;
mod program;

use std::collections::{HashMap, HashSet};

use crate::declared::{declared_output, unit_text};
use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
    ParamValue,
};
use compile::{CompileError, Compiler, CONSTANTS, FUNCTIONS};
use program::{Inputs, Program};

/// Most inputs, `let`s, outputs and parameters an expression model may declare together.
const MOST_NAMES: usize = 10_000;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "inputs",
        unit: "",
        description: "object: each input's name → the unit the formulas read it in",
        default: None,
    },
    ParamSpec {
        name: "let",
        unit: "",
        description: "object: named intermediate quantities → their formulas (optional)",
        default: None,
    },
    ParamSpec {
        name: "outputs",
        unit: "",
        description: "object: each output's name → {\"formula\", \"unit\", optional \"description\" and \"kind\": \"indicator\"}",
        default: None,
    },
    ParamSpec {
        name: "units",
        unit: "",
        description: "object: a parameter's name → its unit (optional; every other number in params is a parameter)",
        default: None,
    },
];

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "expression",
    summary: "outputs written as formulas over named inputs and parameters (+ − * / ^, sin … atan2, sqrt, hypot, exp, ln, log10, abs, min, max, floor, ceil, if, comparisons, c ? a : b, pi)",
    params: PARAMS,
    build: |params| Ok(Box::new(Expression::from_params(params)?)),
    example_params: example,
    example_inputs: &[("hole_d", 10.0), ("pin_d", 9.9)],
};

/// The pin in a hole of the module's documentation: what `rvtol init expression` writes.
fn example() -> ModelParams {
    let text = |s: &str| ParamValue::Text(s.into());
    ModelParams::new()
        .with(
            "inputs",
            ParamValue::Object(vec![
                ("hole_d".into(), text("mm")),
                ("pin_d".into(), text("mm")),
                ("x".into(), text("mm")),
                ("y".into(), text("mm")),
            ]),
        )
        .with(
            "let",
            ParamValue::Object(vec![("offset".into(), text("hypot(x, y)"))]),
        )
        .with(
            "outputs",
            ParamValue::Object(vec![(
                "gap_mm".into(),
                ParamValue::Object(vec![
                    ("formula".into(), text("(hole_d - pin_d) / 2 - offset")),
                    ("unit".into(), text("mm")),
                    (
                        "description".into(),
                        text("radial gap on the tight side of a pin placed off the hole's axis"),
                    ),
                ]),
            )]),
        )
}

/// A model whose outputs are formulas.
#[derive(Debug, Clone)]
pub struct Expression {
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
    program: Program,
}

/// One formula to compile: its name, where it is written and its text.
struct Formula {
    name: String,
    path: String,
    text: String,
    output: bool,
}

impl Expression {
    /// Builds the model from its parameters: every formula parsed and compiled, every
    /// mistake named by its key path and character.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let declared = params
            .object("inputs")?
            .ok_or_else(|| ModelError::new("inputs", "required: each input's name → its unit"))?;
        let lets = params.object("let")?.unwrap_or_default();
        let outputs = params.object("outputs")?.ok_or_else(|| {
            ModelError::new(
                "outputs",
                "required: each output's name → {\"formula\": …, \"unit\": …}",
            )
        })?;
        let units = params.object("units")?.unwrap_or_default();
        if declared.len() + lets.len() + outputs.len() > MOST_NAMES {
            return Err(ModelError::new(
                "inputs",
                format!("at most {MOST_NAMES} names in all"),
            ));
        }
        if outputs.is_empty() {
            return Err(ModelError::new("outputs", "needs at least one output"));
        }
        let mut names = Names::default();
        let mut inputs = Vec::with_capacity(declared.len());
        for (name, unit) in &declared {
            names.declare(name, &format!("inputs.{name}"))?;
            inputs.push(InputSpec {
                name: name.clone(),
                unit: unit_text(&format!("inputs.{name}"), unit)?,
                description: "an input of the formulas",
            });
        }
        let parameters = parameters(params, &units, &mut names)?;
        let mut formulas = Vec::with_capacity(lets.len() + outputs.len());
        for (name, value) in &lets {
            let path = format!("let.{name}");
            names.declare(name, &path)?;
            let ParamValue::Text(text) = value else {
                return Err(ModelError::new(
                    path,
                    format!("expected a formula (a string), got {}", value.kind()),
                ));
            };
            formulas.push(Formula {
                name: name.clone(),
                path,
                text: text.clone(),
                output: false,
            });
        }
        let mut specs = Vec::with_capacity(outputs.len());
        for (name, value) in &outputs {
            let path = format!("outputs.{name}");
            names.declare(name, &path)?;
            let (formula, spec) = output(name, &path, value)?;
            formulas.push(formula);
            specs.push(spec);
        }
        let below: HashMap<String, String> = (formulas.iter())
            .map(|f| (f.name.clone(), f.path.clone()))
            .collect();
        let input_names: Vec<String> = inputs.iter().map(|i| i.name.clone()).collect();
        let mut compiler = Compiler::new(&input_names, &parameters, below);
        // Every formula is checked, each mistake named: a formula that fails stands as a
        // NaN for those that read it, so they report their own mistakes only.
        let mut problems = Vec::new();
        for formula in &formulas {
            let at_path = |err: CompileError| {
                ModelError::new(
                    formula_path(formula),
                    format!("character {}: {}", err.at, err.message),
                )
            };
            let defined = parse::parse(&formula.text)
                .map_err(|err| {
                    at_path(CompileError {
                        at: err.at,
                        message: err.message,
                    })
                })
                .and_then(|tree| {
                    (compiler.define(&formula.name, &tree, formula.output)).map_err(at_path)
                });
            if let Err(problem) = defined {
                problems.push(problem);
                let stand_in = parse::parse("0/0").expect("a NaN parses");
                compiler
                    .define(&formula.name, &stand_in, formula.output)
                    .expect("a NaN compiles");
            }
        }
        if let Some(first) = ModelError::of_all(problems) {
            return Err(first);
        }
        for (name, _) in &parameters {
            if !compiler.was_read(name) {
                return Err(ModelError::new(
                    name.clone(),
                    "a parameter no formula reads (a misspelt key?)",
                ));
            }
        }
        for formula in formulas.iter().filter(|f| !f.output) {
            if !compiler.was_read(&formula.name) {
                return Err(ModelError::new(formula.path.clone(), "no formula reads it"));
            }
        }
        Ok(Expression {
            inputs,
            outputs: specs,
            program: compiler.finish(),
        })
    }
}

impl Expression {
    /// An indicator output's value other than 0 or 1 (a formula that is no event, such
    /// as a difference) becomes NaN: the run counts it as a failed sample rather than as
    /// an event that happened.
    fn check_indicators(&self, n: usize, outputs: &mut [f64]) {
        for (j, spec) in self.outputs.iter().enumerate() {
            if spec.kind == OutputKind::Indicator {
                for v in &mut outputs[j * n..(j + 1) * n] {
                    if *v != 0.0 && *v != 1.0 {
                        *v = f64::NAN;
                    }
                }
            }
        }
    }
}

/// Where a formula's text is: `let.NAME` or `outputs.NAME.formula`.
fn formula_path(formula: &Formula) -> String {
    if formula.output {
        format!("{}.formula", formula.path)
    } else {
        formula.path.clone()
    }
}

/// The model's parameters: every number of `params` outside the four sections, each
/// with its unit from `units` (which may name parameters only).
fn parameters(
    params: &ModelParams,
    units: &[(String, ParamValue)],
    names: &mut Names,
) -> Result<Vec<(String, f64)>, ModelError> {
    let mut parameters = Vec::new();
    let sections: Vec<&str> = PARAMS.iter().map(|p| p.name).collect();
    for (key, value) in params.entries() {
        if sections.contains(&key) {
            continue;
        }
        if !matches!(value, ParamValue::Number(_)) {
            return Err(ModelError::new(
                key,
                format!(
                    "unknown section (expected one of: {}); a parameter is a number, got {}",
                    sections.join(", "),
                    value.kind()
                ),
            ));
        }
        names.declare(key, key)?;
        parameters.push((key.to_string(), params.number(key, None)?));
    }
    for (name, unit) in units {
        let path = format!("units.{name}");
        unit_text(&path, unit)?;
        if !parameters.iter().any(|(p, _)| p == name) {
            return Err(ModelError::new(
                path,
                format!("{name:?} is not a parameter (a number in params)"),
            ));
        }
    }
    Ok(parameters)
}

/// An output's formula and spec from its object ([`crate::declared::declared_output`] with
/// its `formula`).
fn output(name: &str, path: &str, value: &ParamValue) -> Result<(Formula, OutputSpec), ModelError> {
    let (spec, fields) = declared_output(
        name,
        path,
        value,
        &["formula"],
        "a formula of the expression model",
    )?;
    let formula = match fields.iter().find(|(k, _)| k == "formula").map(|(_, v)| v) {
        Some(ParamValue::Text(text)) => text.clone(),
        Some(other) => {
            return Err(ModelError::new(
                format!("{path}.formula"),
                format!("expected a string, got {}", other.kind()),
            ))
        }
        None => return Err(ModelError::new(path, "needs a \"formula\"")),
    };
    Ok((
        Formula {
            name: name.to_string(),
            path: path.to_string(),
            text: formula,
            output: true,
        },
        spec,
    ))
}

/// The names declared so far: each a valid, unreserved name, declared once.
#[derive(Default)]
struct Names {
    seen: HashMap<String, String>,
}

impl Names {
    fn declare(&mut self, name: &str, path: &str) -> Result<(), ModelError> {
        let mut chars = name.chars();
        let valid = chars
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid {
            return Err(ModelError::new(
                path,
                format!("{name:?} is not a name: ASCII letters, digits and '_', not starting with a digit"),
            ));
        }
        let reserved: HashSet<&str> = (FUNCTIONS.iter().map(|(f, _)| *f))
            .chain(CONSTANTS.iter().map(|(c, _)| *c))
            .collect();
        if reserved.contains(name) {
            return Err(ModelError::new(
                path,
                format!("{name:?} is a function or constant of the formulas; choose another name"),
            ));
        }
        if let Some(earlier) = self.seen.insert(name.to_string(), path.to_string()) {
            return Err(ModelError::new(
                path,
                format!("{name:?} is declared already, at {earlier}"),
            ));
        }
        Ok(())
    }
}

impl ErrorModel for Expression {
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
        self.program.run(1, Inputs::Row(inputs), outputs);
        self.check_indicators(1, outputs);
    }

    fn evaluate_columns(&self, inputs: &[&[f64]], outputs: &mut [f64]) {
        if self.outputs.is_empty() {
            return;
        }
        let n = outputs.len() / self.outputs.len();
        self.program.run(n, Inputs::Columns(inputs), outputs);
        self.check_indicators(n, outputs);
    }
}

#[cfg(test)]
mod tests;
