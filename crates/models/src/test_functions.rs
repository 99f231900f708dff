//! Sensitivity-analysis test functions with closed-form Sobol indices, so that users (and
//! the tests) can check the sensitivity estimators on problems with known answers.
//!
//! `ishigami` (Ishigami & Homma 1990), inputs x1, x2, x3 ~ U(−π, π):
//!
//! ```text
//! y = sin x1 + a·sin² x2 + b·x3⁴·sin x1
//! V = a²/8 + b·π⁴/5 + b²·π⁸/18 + 1/2,  V1 = (1 + b·π⁴/5)²/2,  V2 = a²/8,  V3 = 0,
//! V13 = b²·π⁸·(1/18 − 1/50)
//! ```
//! For a = 7, b = 0.1: S = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437)
//! (validation.md).
//!
//! `sobol_g` (Sobol' G-function, Saltelli & Sobol' 1995), inputs x_i ~ U(0, 1), i = 1..k,
//! coefficients a_i ≥ 0:
//!
//! ```text
//! y = Π (|4·x_i − 2| + a_i) / (1 + a_i)
//! V_i = 1/(3·(1 + a_i)²),  V = Π (1 + V_i) − 1,  S_i = V_i/V,  ST_i = V_i·Π_{j≠i}(1 + V_j)/V
//! ```

use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
    ParamValue,
};
use rvtol_deviation::Shown;

/// The Ishigami function.
#[derive(Debug, Clone)]
pub struct Ishigami {
    a: f64,
    b: f64,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

const ISHIGAMI_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "a",
        unit: "1",
        description: "coefficient of sin² x2",
        default: Some(7.0),
    },
    ParamSpec {
        name: "b",
        unit: "1",
        description: "coefficient of x3⁴·sin x1",
        default: Some(0.1),
    },
];

/// Registry entry of `ishigami`.
pub const ISHIGAMI_ENTRY: ModelEntry = ModelEntry {
    name: "ishigami",
    summary:
        "Ishigami test function y = sin x1 + a sin² x2 + b x3⁴ sin x1 (closed-form Sobol indices)",
    params: ISHIGAMI_PARAMS,
    build: |params| Ok(Box::new(Ishigami::from_params(params)?)),
    example_params: ModelParams::new,
    example_inputs: &[],
};

impl Ishigami {
    /// Builds it from `a` and `b` (defaults 7 and 0.1).
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let a = params.number("a", Some(7.0))?;
        let b = params.number("b", Some(0.1))?;
        params.reject_unknown(&["a", "b"])?;
        Ok(Ishigami {
            a,
            b,
            inputs: ["x1", "x2", "x3"]
                .iter()
                .map(|name| InputSpec {
                    name: name.to_string(),
                    unit: "rad".into(),
                    description: "uniform on (−π, π)",
                })
                .collect(),
            outputs: vec![OutputSpec {
                name: "y".into(),
                unit: "1".into(),
                description: "Ishigami function",
                kind: OutputKind::Continuous,
                condition: None,
            }],
        })
    }

    /// Closed-form first-order and total Sobol indices (S1, S2, S3), (ST1, ST2, ST3).
    pub fn sobol_indices(&self) -> ([f64; 3], [f64; 3]) {
        let pi4 = std::f64::consts::PI.powi(4);
        let pi8 = pi4 * pi4;
        let (a, b) = (self.a, self.b);
        let v1 = 0.5 * (1.0 + b * pi4 / 5.0).powi(2);
        let v2 = a * a / 8.0;
        let v13 = b * b * pi8 * (1.0 / 18.0 - 1.0 / 50.0);
        let v = v1 + v2 + v13;
        ([v1 / v, v2 / v, 0.0], [(v1 + v13) / v, v2 / v, v13 / v])
    }
}

impl ErrorModel for Ishigami {
    fn name(&self) -> &'static str {
        ISHIGAMI_ENTRY.name
    }
    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    #[inline]
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        let s1 = x[0].sin();
        let s2 = x[1].sin();
        out[0] = s1 + self.a * s2 * s2 + self.b * x[2].powi(4) * s1;
    }
}

/// The Sobol' G-function.
#[derive(Debug, Clone)]
pub struct SobolG {
    coefficients: Vec<f64>,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

const SOBOL_G_PARAMS: &[ParamSpec] = &[ParamSpec {
    name: "coefficients",
    unit: "1",
    description: "object mapping each input name to its a_i ≥ 0 (small a_i: important input)",
    default: None,
}];

/// Registry entry of `sobol_g`.
pub const SOBOL_G_ENTRY: ModelEntry = ModelEntry {
    name: "sobol_g",
    summary: "Sobol' G-function y = Π (|4x_i − 2| + a_i)/(1 + a_i), x_i ~ U(0, 1) (closed-form Sobol indices)",
    params: SOBOL_G_PARAMS,
    build: |params| Ok(Box::new(SobolG::from_params(params)?)),
    example_params: || {
        ModelParams::new().with(
            "coefficients",
            ParamValue::Named(vec![("x1".into(), 0.0), ("x2".into(), 1.0), ("x3".into(), 9.0)]),
        )
    },
    example_inputs: &[],
};

impl SobolG {
    /// Builds it from its coefficients.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let named = params.named("coefficients")?;
        if named.is_empty() {
            return Err(ModelError::new("coefficients", "needs at least one input"));
        }
        let mut coefficients = Vec::new();
        let mut inputs = Vec::new();
        for (name, a) in named {
            if !(a.is_finite() && *a >= 0.0) {
                return Err(ModelError::new(
                    format!("coefficients.{name}"),
                    format!("must be a finite number ≥ 0, got {}", Shown(*a)),
                ));
            }
            coefficients.push(*a);
            inputs.push(InputSpec {
                name: name.clone(),
                unit: "1".into(),
                description: "uniform on (0, 1)",
            });
        }
        params.reject_unknown(&["coefficients"])?;
        Ok(SobolG {
            coefficients,
            inputs,
            outputs: vec![OutputSpec {
                name: "y".into(),
                unit: "1".into(),
                description: "Sobol' G-function",
                kind: OutputKind::Continuous,
                condition: None,
            }],
        })
    }

    /// Closed-form first-order and total Sobol indices, one per input.
    pub fn sobol_indices(&self) -> (Vec<f64>, Vec<f64>) {
        let partial: Vec<f64> = self
            .coefficients
            .iter()
            .map(|a| 1.0 / (3.0 * (1.0 + a) * (1.0 + a)))
            .collect();
        let product: f64 = partial.iter().map(|v| 1.0 + v).product();
        let v = product - 1.0;
        let first = partial.iter().map(|vi| vi / v).collect();
        let total = partial
            .iter()
            .map(|vi| vi * product / (1.0 + vi) / v)
            .collect();
        (first, total)
    }
}

impl ErrorModel for SobolG {
    fn name(&self) -> &'static str {
        SOBOL_G_ENTRY.name
    }
    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    #[inline]
    fn evaluate(&self, x: &[f64], out: &mut [f64]) {
        let mut y = 1.0;
        for (xi, a) in x.iter().zip(&self.coefficients) {
            y *= ((4.0 * xi - 2.0).abs() + a) / (1.0 + a);
        }
        out[0] = y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ishigami_indices_match_validation() {
        // validation.md: a = 7, b = 0.1 → S1 = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437).
        let model = Ishigami::from_params(&ModelParams::new()).unwrap();
        let (s, st) = model.sobol_indices();
        let expected_s = [0.3139, 0.4424, 0.0];
        let expected_st = [0.5576, 0.4424, 0.2437];
        for i in 0..3 {
            assert!((s[i] - expected_s[i]).abs() < 5e-5, "S{i} = {}", s[i]);
            assert!((st[i] - expected_st[i]).abs() < 5e-5, "ST{i} = {}", st[i]);
        }
    }

    #[test]
    fn ishigami_value() {
        // y(π/2, π/2, 1) = 1 + 7 + 0.1 = 8.1.
        let model = Ishigami::from_params(&ModelParams::new()).unwrap();
        let mut out = [0.0];
        let h = std::f64::consts::FRAC_PI_2;
        model.evaluate(&[h, h, 1.0], &mut out);
        assert!((out[0] - 8.1).abs() < 1e-12);
    }

    #[test]
    fn g_function_indices_sum_to_one_without_interactions() {
        // One input: S = ST = 1. Several: Σ S_i < 1 ≤ Σ ST_i.
        let params = SOBOL_G_ENTRY.example_params;
        let model = SobolG::from_params(&params()).unwrap();
        let (s, st) = model.sobol_indices();
        let sum_s: f64 = s.iter().sum();
        let sum_st: f64 = st.iter().sum();
        assert!(sum_s < 1.0 && sum_st > 1.0);
        // a = 0: V_1 = 1/3; a = 1: 1/12; a = 9: 1/300. V = (4/3)(13/12)(301/300) − 1.
        let v = (4.0 / 3.0) * (13.0 / 12.0) * (301.0 / 300.0) - 1.0;
        assert!((s[0] - (1.0 / 3.0) / v).abs() < 1e-12);
    }
}
