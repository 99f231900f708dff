//! The expression model against the built-in models it can be written as, its semantics
//! row by row and block by block, and its messages.

use super::*;
use crate::{Ishigami, LinearStack, SobolG};

fn text(s: &str) -> ParamValue {
    ParamValue::Text(s.into())
}

/// An expression model of `inputs` (all in `unit`) with one output per formula.
fn model(inputs: &[&str], unit: &str, outputs: &[(&str, &str)]) -> Result<Expression, ModelError> {
    Expression::from_params(&params(inputs, unit, &[], outputs))
}

fn params(
    inputs: &[&str],
    unit: &str,
    lets: &[(&str, &str)],
    outputs: &[(&str, &str)],
) -> ModelParams {
    let object = |entries: Vec<(String, ParamValue)>| ParamValue::Object(entries);
    let mut params = ModelParams::new()
        .with(
            "inputs",
            object(inputs.iter().map(|i| (i.to_string(), text(unit))).collect()),
        )
        .with(
            "outputs",
            object(
                outputs
                    .iter()
                    .map(|(name, formula)| {
                        (
                            name.to_string(),
                            object(vec![
                                ("formula".into(), text(formula)),
                                ("unit".into(), text("1")),
                            ]),
                        )
                    })
                    .collect(),
            ),
        );
    if !lets.is_empty() {
        params = params.with(
            "let",
            object(lets.iter().map(|(n, f)| (n.to_string(), text(f))).collect()),
        );
    }
    params
}

/// A deterministic spread of rows over (−4, 4) (a Weyl sequence per input).
fn rows(n: usize, k: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|r| {
            (0..k)
                .map(|i| {
                    let u = ((r as f64 + 0.5) * (0.618_033_988_749_895 + 0.1 * i as f64)).fract();
                    8.0 * u - 4.0
                })
                .collect()
        })
        .collect()
}

/// The model's outputs for `rows`, by the column form in blocks of `block` rows.
fn columns(model: &dyn ErrorModel, rows: &[Vec<f64>], block: usize) -> Vec<Vec<f64>> {
    let n_out = model.outputs().len();
    let mut out = vec![Vec::new(); n_out];
    for chunk in rows.chunks(block) {
        let m = chunk.len();
        let cols: Vec<Vec<f64>> = (0..model.inputs().len())
            .map(|i| chunk.iter().map(|r| r[i]).collect())
            .collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let mut y = vec![f64::NAN; m * n_out];
        model.evaluate_columns(&refs, &mut y);
        for j in 0..n_out {
            out[j].extend_from_slice(&y[j * m..(j + 1) * m]);
        }
    }
    out
}

fn assert_close(expected: f64, got: f64, what: &str) {
    let scale = expected.abs().max(f64::MIN_POSITIVE);
    assert!(
        (expected - got).abs() <= 1e-15 * scale,
        "{what}: {expected} against {got}"
    );
}

#[test]
fn agrees_with_the_linear_stack_bit_for_bit() {
    // c + Σ a_i·x_i summed left to right, as LinearStack does.
    let stack = LinearStack::from_params(
        &ModelParams::new()
            .with(
                "coefficients",
                ParamValue::Named(vec![
                    ("a".into(), 1.5),
                    ("b".into(), -2.25),
                    ("c".into(), 0.1),
                ]),
            )
            .with_number("constant", 0.3),
    )
    .unwrap();
    let expression = model(
        &["a", "b", "c"],
        "mm",
        &[("y", "0.3 + 1.5*a + -2.25*b + 0.1*c")],
    )
    .unwrap();
    let data = rows(1000, 3);
    let ours = columns(&expression, &data, 64);
    for (r, row) in data.iter().enumerate() {
        let mut y = [0.0];
        stack.evaluate(row, &mut y);
        assert_eq!(y[0].to_bits(), ours[0][r].to_bits(), "row {r}");
    }
}

#[test]
fn agrees_with_ishigami_and_sobol_g() {
    let ishigami = Ishigami::from_params(&ModelParams::new()).unwrap();
    let written = model(
        &["x1", "x2", "x3"],
        "rad",
        &[("y", "sin(x1) + 7*sin(x2)*sin(x2) + 0.1*x3^4*sin(x1)")],
    )
    .unwrap();
    let data = rows(2000, 3);
    let ours = columns(&written, &data, 64);
    for (r, row) in data.iter().enumerate() {
        let mut y = [0.0];
        ishigami.evaluate(row, &mut y);
        assert_close(y[0], ours[0][r], "ishigami");
    }
    let g = SobolG::from_params(&ModelParams::new().with(
        "coefficients",
        ParamValue::Named(vec![
            ("x1".into(), 0.0),
            ("x2".into(), 1.0),
            ("x3".into(), 9.0),
        ]),
    ))
    .unwrap();
    let written = model(
        &["x1", "x2", "x3"],
        "1",
        &[("y", "(abs(4*x1 - 2) + 0)/(1 + 0) * ((abs(4*x2 - 2) + 1)/(1 + 1)) * ((abs(4*x3 - 2) + 9)/(1 + 9))")],
    )
    .unwrap();
    let data: Vec<Vec<f64>> = rows(2000, 3)
        .into_iter()
        .map(|r| r.iter().map(|x| (x + 4.0) / 8.0).collect())
        .collect();
    let ours = columns(&written, &data, 64);
    for (r, row) in data.iter().enumerate() {
        let mut y = [0.0];
        g.evaluate(row, &mut y);
        assert_close(y[0], ours[0][r], "sobol_g");
    }
}

#[test]
fn rows_and_blocks_give_the_same_bits() {
    let expression = Expression::from_params(&params(
        &["x", "y", "z"],
        "mm",
        &[("r", "hypot(x, y)"), ("t", "atan2(y, x)")],
        &[
            ("a", "r > 1 ? sqrt(r) * cos(t) : -exp(z) / (1 + r^2)"),
            ("b", "max(x, y, z) - min(abs(x), ln(1 + r), floor(z)) + ceil(y)^3"),
            ("c", "if(a < 0 || !(z >= 1), log10(1 + abs(a)), tan(a) * asin(z / 4) + acos(y / 4) - atan(x))"),
            ("d", "a + b * c - 2^x + x**0.5"),
        ],
    ))
    .unwrap();
    let data = rows(1000, 3);
    let whole = columns(&expression, &data, 1000);
    for block in [1, 7, 64] {
        let parts = columns(&expression, &data, block);
        for (j, (w, p)) in whole.iter().zip(&parts).enumerate() {
            for (r, (x, y)) in w.iter().zip(p).enumerate() {
                assert_eq!(
                    x.to_bits(),
                    y.to_bits(),
                    "output {j}, row {r}, blocks of {block}"
                );
            }
        }
    }
    for (r, row) in data.iter().enumerate() {
        let mut y = [0.0; 4];
        expression.evaluate(row, &mut y);
        for j in 0..4 {
            assert_eq!(
                y[j].to_bits(),
                whole[j][r].to_bits(),
                "row form, output {j}, row {r}"
            );
        }
    }
}

#[test]
fn semantics_of_conditions_and_nan() {
    let expression = model(
        &["x", "y"],
        "1",
        &[
            ("lt", "x < y"),
            ("pick", "x ? 10 : 20"),
            ("lo", "min(x, y)"),
            ("not", "!x"),
            ("both", "x && y"),
        ],
    )
    .unwrap();
    let run = |x: f64, y: f64| {
        let mut out = [0.0; 5];
        expression.evaluate(&[x, y], &mut out);
        out
    };
    assert_eq!(run(1.0, 2.0), [1.0, 10.0, 1.0, 0.0, 1.0]);
    assert_eq!(run(0.0, 2.0), [1.0, 20.0, 0.0, 1.0, 0.0]);
    // A NaN operand propagates through comparisons, selections, min and logic; so does
    // an infinite one (a division by zero), which a comparison would otherwise turn into
    // a plain 1.
    assert!(run(f64::NAN, 2.0).iter().all(|v| v.is_nan()));
    assert!(run(f64::INFINITY, 2.0).iter().all(|v| v.is_nan()));
    let with_infinite_y = run(2.0, f64::NEG_INFINITY);
    for j in [0, 2, 4] {
        assert!(with_infinite_y[j].is_nan(), "output {j}");
    }
}

#[test]
fn an_indicator_that_is_not_0_or_1_is_a_failed_sample() {
    let object = |entries: Vec<(&str, ParamValue)>| {
        ParamValue::Object(
            entries
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
        )
    };
    let p = ModelParams::new()
        .with("inputs", object(vec![("x", text("1"))]))
        .with(
            "outputs",
            object(vec![(
                "event",
                object(vec![
                    ("formula", text("x")),
                    ("unit", text("1")),
                    ("kind", text("indicator")),
                ]),
            )]),
        );
    let expression = Expression::from_params(&p).unwrap();
    assert_eq!(expression.outputs()[0].kind, OutputKind::Indicator);
    let ys = columns(
        &expression,
        &[vec![0.0], vec![1.0], vec![0.5], vec![-1.0]],
        64,
    );
    assert_eq!(ys[0][..2], [0.0, 1.0]);
    assert!(ys[0][2].is_nan() && ys[0][3].is_nan());
}

#[test]
fn parameters_lets_and_outputs_read_by_later_formulas() {
    let p = params(
        &["x"],
        "mm",
        &[("twice", "2 * x")],
        &[("y", "twice + k"), ("z", "y * pi")],
    )
    .with_number("k", 0.5);
    let expression = Expression::from_params(&p).unwrap();
    let mut out = [0.0; 2];
    expression.evaluate(&[3.0], &mut out);
    assert_eq!(out, [6.5, 6.5 * std::f64::consts::PI]);
}

#[test]
fn every_formula_is_checked_and_a_broken_one_stands_in_for_its_readers() {
    // Four formulas with a mistake each (a syntax error among them), and one that reads
    // a broken one (`v` reads `r`, as `z` does): four problems, in the formulas' order,
    // none of them a consequence of another.
    let p = params(
        &["x", "y"],
        "mm",
        &[("r", "hypot(x, yy)")],
        &[
            ("z", "r + ofset"),
            ("w", "sqr(x)"),
            ("v", "r * 2"),
            ("u", "x +* 2"),
        ],
    );
    let err = Expression::from_params(&p).unwrap_err();
    let found: Vec<(&str, &str)> = err
        .all()
        .map(|e| (e.key.as_str(), e.reason.as_str()))
        .collect();
    assert_eq!(
        found,
        [
            (
                "let.r",
                "character 10: unknown name \"yy\" (did you mean y?)"
            ),
            ("outputs.z.formula", "character 5: unknown name \"ofset\""),
            (
                "outputs.w.formula",
                "character 1: unknown function \"sqr\" (did you mean sqrt?)"
            ),
            (
                "outputs.u.formula",
                "character 4: expected a number, a name or '(', got '*'"
            ),
        ]
    );
    // One mistake is one problem.
    let one = params(&["x"], "mm", &[], &[("y", "sin(xx)")]);
    assert!(Expression::from_params(&one)
        .unwrap_err()
        .further
        .is_empty());
}

#[test]
fn mistakes_are_named_by_path_and_character() {
    let cases: Vec<(ModelParams, &str, &str)> = vec![
        (
            params(&["x"], "mm", &[], &[("y", "x +* 2")]),
            "outputs.y.formula",
            "character 4: expected a number",
        ),
        (
            params(&["x"], "mm", &[], &[("y", "hypot(x)")]),
            "outputs.y.formula",
            "character 1: hypot takes 2 arguments, got 1",
        ),
        (
            params(&["x"], "mm", &[], &[("y", "sin(xx)")]),
            "outputs.y.formula",
            "character 5: unknown name \"xx\" (did you mean x?)",
        ),
        (
            params(&["x"], "mm", &[], &[("y", "z + x"), ("z", "x")]),
            "outputs.y.formula",
            "defined below, at outputs.z",
        ),
        (
            params(&["x"], "mm", &[("r", "x")], &[("y", "x")]),
            "let.r",
            "no formula reads it",
        ),
        (
            params(&["x"], "mm", &[], &[("y", "x")]).with_number("gain", 2.0),
            "gain",
            "no formula reads",
        ),
        (
            params(&["x", "sin"], "mm", &[], &[("y", "x")]),
            "inputs.sin",
            "function or constant",
        ),
        (
            params(&["x"], "mm", &[("x", "1")], &[("y", "x")]),
            "let.x",
            "declared already, at inputs.x",
        ),
        (
            params(&["2x"], "mm", &[], &[("y", "1")]),
            "inputs.2x",
            "not a name",
        ),
        (
            params(&["x"], "", &[], &[("y", "x")]),
            "inputs.x",
            "unit is empty",
        ),
        (
            params(&["x"], "mm", &[], &[]),
            "outputs",
            "at least one output",
        ),
        (
            params(&["x"], "mm", &[], &[("y", "")]),
            "outputs.y.formula",
            "character 1: the formula is empty",
        ),
    ];
    for (p, key, says) in cases {
        let err = Expression::from_params(&p).unwrap_err();
        assert_eq!(err.key, key, "{err}");
        assert!(err.reason.contains(says), "{key}: {}", err.reason);
    }
    let no_unit = ModelParams::new()
        .with("inputs", ParamValue::Object(vec![("x".into(), text("mm"))]))
        .with(
            "outputs",
            ParamValue::Object(vec![(
                "y".into(),
                ParamValue::Object(vec![("formula".into(), text("x"))]),
            )]),
        );
    assert!(Expression::from_params(&no_unit)
        .unwrap_err()
        .reason
        .contains("needs a \"unit\""));
}

#[test]
fn the_example_builds_and_computes_the_gap() {
    let expression = Expression::from_params(&example()).unwrap();
    let mut out = [0.0];
    expression.evaluate(&[10.0, 9.9, 0.03, 0.04], &mut out);
    assert_eq!(out[0], (10.0 - 9.9) / 2.0 - 0.03f64.hypot(0.04));
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Any text at all: a tree or a positioned mistake, never a panic.
        #[test]
        fn any_text_parses_or_is_refused(text in "\\PC{0,200}") {
            if let Err(err) = parse::parse(&text) {
                prop_assert!(err.at >= 1 && err.at <= text.chars().count() + 1);
            }
        }

        /// Text made of the formulas' own alphabet (names, numbers, operators, brackets):
        /// the model builds or names the character of its mistake, and a model that builds
        /// evaluates a row without a panic.
        #[test]
        fn formula_alphabet_builds_or_is_refused(
            text in "([xyk]|sin|hypot|min|if|pi|[0-9.eE]|[-+*/^(),?:<>=!&| ]){0,60}"
        ) {
            let p = params(&["x", "y"], "mm", &[], &[("z", &text)]);
            match Expression::from_params(&p) {
                Ok(model) => {
                    let mut out = [0.0];
                    model.evaluate(&[0.25, -1.5], &mut out);
                }
                Err(err) => {
                    prop_assert_eq!(err.key.as_str(), "outputs.z.formula");
                    prop_assert!(err.reason.starts_with("character "), "{}", err.reason);
                }
            }
        }
    }
}
