//! `linear_stack`: a linear tolerance stack y = c + Σ a_i·x_i over named inputs.
//!
//! Users run their own one-dimensional stacks with it, and it checks the whole engine
//! against a closed form: with jointly normal inputs of mean μ and covariance Σ,
//! E[y] = c + aᵀμ and sd(y) = √(aᵀΣa) exactly (validation.md, "Checks that need no
//! document").
//!
//! Parameters: `coefficients` (object: input name → a_i, in the unit of y per unit of the
//! input), `constant` (c, default 0), `output` (name of y, default `stack`), `unit` (unit
//! of y, default `mm`), `input_units` (object: input name → the unit a_i reads it in;
//! default the stack's unit).
//!
//! Every input has a unit, so the engine converts a variable written in another unit of
//! the same kind (a width in µm into a stack in mm) and refuses one of another kind (an
//! angle bound to a length): a stack never adds µm to mm as they stand. An input read in
//! another kind of unit than the stack's (a tilt in rad times a lever in mm/rad) says so
//! in `input_units`.

use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
    ParamValue,
};
use rvtol_deviation::Shown;

/// y = c + Σ a_i·x_i.
#[derive(Debug, Clone)]
pub struct LinearStack {
    coefficients: Vec<f64>,
    constant: f64,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "coefficients",
        unit: "output unit per input unit",
        description: "object mapping each input name to its coefficient a_i",
        default: None,
    },
    ParamSpec {
        name: "constant",
        unit: "output unit",
        description: "constant term c",
        default: Some(0.0),
    },
    ParamSpec {
        name: "input_units",
        unit: "",
        description: "object mapping an input name to the unit its coefficient reads it in (default: the stack's unit)",
        default: None,
    },
];

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "linear_stack",
    summary: "linear tolerance stack y = c + Σ a_i·x_i (closed form: mean c + aᵀμ, sd √(aᵀΣa)); params also take `output` (name, default \"stack\") and `unit` (default \"mm\", also the inputs' unless `input_units` says otherwise)",
    params: PARAMS,
    build: |params| Ok(Box::new(LinearStack::from_params(params)?)),
    example_params: || {
        ModelParams::new().with(
            "coefficients",
            ParamValue::Named(vec![("x1".into(), 1.0), ("x2".into(), -2.0)]),
        )
    },
    example_inputs: &[],
};

impl LinearStack {
    /// Builds the stack from its parameters.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let named = params.named("coefficients")?;
        if named.is_empty() {
            return Err(ModelError::new("coefficients", "needs at least one input"));
        }
        let unit = params.text("unit", "mm")?;
        let input_units = params.object("input_units")?.unwrap_or_default();
        for (name, value) in &input_units {
            let key = format!("input_units.{name}");
            if !named.iter().any(|(input, _)| input == name) {
                return Err(ModelError::new(key, format!("{name:?} has no coefficient")));
            }
            match value {
                ParamValue::Text(unit) if !unit.trim().is_empty() => {}
                other => {
                    return Err(ModelError::new(
                        key,
                        format!("expected a unit (a non-empty string), got {}", other.kind()),
                    ))
                }
            }
        }
        let mut inputs = Vec::with_capacity(named.len());
        let mut coefficients = Vec::with_capacity(named.len());
        for (name, a) in named {
            if !a.is_finite() {
                return Err(ModelError::new(
                    format!("coefficients.{name}"),
                    format!("must be a finite number, got {}", Shown(*a)),
                ));
            }
            let input_unit = input_units
                .iter()
                .find_map(|(input, value)| match value {
                    ParamValue::Text(unit) if input == name => Some(unit.clone()),
                    _ => None,
                })
                .unwrap_or_else(|| unit.clone());
            inputs.push(InputSpec {
                name: name.clone(),
                unit: input_unit,
                description: "stack input",
            });
            coefficients.push(*a);
        }
        let constant = params.number("constant", Some(0.0))?;
        let output = params.text("output", "stack")?;
        if output.is_empty() {
            return Err(ModelError::new("output", "must not be empty"));
        }
        params.reject_unknown(&["coefficients", "constant", "output", "unit", "input_units"])?;
        Ok(LinearStack {
            coefficients,
            constant,
            inputs,
            outputs: vec![OutputSpec {
                name: output,
                unit,
                description: "c + Σ a_i·x_i",
                kind: OutputKind::Continuous,
                condition: None,
            }],
        })
    }
}

impl ErrorModel for LinearStack {
    fn name(&self) -> &'static str {
        "linear_stack"
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    #[inline]
    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]) {
        let mut y = self.constant;
        for (a, x) in self.coefficients.iter().zip(inputs) {
            y += a * x;
        }
        outputs[0] = y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluates_the_sum() {
        let params = ModelParams::new()
            .with(
                "coefficients",
                ParamValue::Named(vec![("a".into(), 2.0), ("b".into(), -0.5)]),
            )
            .with_number("constant", 1.0);
        let model = LinearStack::from_params(&params).unwrap();
        let mut out = [0.0];
        model.evaluate(&[3.0, 4.0], &mut out);
        assert_eq!(out[0], 1.0 + 6.0 - 2.0);
    }

    #[test]
    fn unknown_parameter_is_named() {
        let params = ModelParams::new()
            .with("coefficients", ParamValue::Named(vec![("a".into(), 1.0)]))
            .with_number("gain", 1.0);
        let err = LinearStack::from_params(&params).unwrap_err();
        assert_eq!(err.key, "gain");
    }
}
