//! Dependence between quantities of any law (the Gaussian copula) through the engine: a
//! scenario's `spearman` correlation between a Rayleigh runout and a normal pitch error is
//! the rank correlation of the drawn values; reports keep their bits for any thread and
//! shard count; Sobol' grouping merges copula-correlated sources; Shapley effects of a
//! correlated uniform × normal pair match their closed form; a malformed entry is refused
//! with its path.

use rvtol_deviation::sample_spearman;
use rvtol_engine::{sample_table, Scenario};
use rvtol_tests::{
    assert_effects_near, assert_same_bits_for_threads_and_shards, refusal, run_settings,
};
use serde_json::{json, Value};

fn scenario(document: &Value) -> Scenario {
    Scenario::from_json(&document.to_string(), "test").unwrap_or_else(|err| panic!("{err}"))
}

/// A runout (Rayleigh, ≤ 11 µm at Cp 1: σ = 11/3.6353 µm) and a pitch error (normal, mm)
/// of one grinding set-up, correlated by `correlation`, and a model passing both through
/// (in µm).
fn grinding(samples: u64, correlation: Value) -> Value {
    json!({
        "name": "grinding",
        "samples": samples,
        "seed": 5,
        "variables": [
            { "name": "runout", "unit": "µm", "distribution": { "rayleigh": { "upper": 11.0 } } },
            { "name": "pitch", "unit": "mm", "distribution": { "normal": { "mean": 0.0, "sd": 0.004 } } }
        ],
        "correlations": [correlation],
        "models": [{
            "model": "expression",
            "params": {
                "inputs": { "r": "µm", "p": "µm" },
                "outputs": {
                    "runout_um": { "formula": "r", "unit": "µm" },
                    "pitch_um": { "formula": "p", "unit": "µm" }
                }
            },
            "inputs": { "r": "runout", "p": "pitch" }
        }]
    })
}

#[test]
fn a_spearman_correlation_is_the_rank_correlation_of_the_values() {
    // n = 200 000: atanh(r_S) has standard error √(1.06/(n − 3)) under a Gaussian copula
    // (Fieller, Hartley & Pearson 1957); bound 4 standard errors.
    let n = 200_000u64;
    let target = 0.6;
    let document = grinding(
        n,
        json!({ "between": ["runout", "pitch"], "spearman": target }),
    );
    let table = sample_table(&scenario(&document), run_settings(n, 5)).unwrap();
    let (runout, pitch): (Vec<f64>, Vec<f64>) = table
        .outputs
        .chunks_exact(table.n_outputs)
        .map(|row| (row[0], row[1]))
        .unzip();
    assert!(
        runout.iter().all(|&r| r >= 0.0),
        "a runout is never negative"
    );
    let r = sample_spearman(&runout, &pitch);
    let se = (1.06 / (n as f64 - 3.0)).sqrt();
    assert!(
        (r.atanh() - f64::atanh(target)).abs() < 4.0 * se,
        "Spearman {r} against {target}"
    );
    // The runout keeps its Rayleigh law: mean σ√(π/2), sd σ√((4 − π)/2) (5 SE).
    let sigma = 11.0 / rvtol_deviation::RAYLEIGH_QUANTILE;
    let mean = runout.iter().sum::<f64>() / n as f64;
    let sd = ((4.0 - std::f64::consts::PI) / 2.0).sqrt() * sigma;
    let exact = sigma * (std::f64::consts::PI / 2.0).sqrt();
    assert!(
        (mean - exact).abs() < 5.0 * sd / (n as f64).sqrt(),
        "{mean}"
    );
}

#[test]
fn copula_reports_have_the_same_bits_for_any_thread_and_shard_count() {
    let n = 300_000u64;
    let document = grinding(
        n,
        json!({ "between": ["pitch", "runout"], "spearman": -0.4 }),
    );
    let scenario = scenario(&document);
    let settings = run_settings(n, 5);
    assert_same_bits_for_threads_and_shards(&scenario, settings);
}

#[test]
fn sobol_grouping_merges_sources_correlated_through_the_copula() {
    let document = grinding(1000, json!({ "between": ["runout", "pitch"], "rho": 0.3 }));
    let groups = rvtol_analysis::sensitivity::independent_groups(&scenario(&document));
    let names: Vec<&str> = groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["runout+pitch"]);
}

#[test]
fn shapley_effects_of_a_correlated_uniform_match_the_closed_form() {
    // y = u with u = Φ(z₁) uniform on (0, 1) and x = z₂ normal, corr(z₁, z₂) = ρ. With
    // c(S) = Var E[y | x_S]: c({u}) = Var y = 1/12 and c({x}) = Var Φ(ρ·x/√(2 − ρ²))
    // = asin(ρ²/2)/(2π) (E[Φ(W)²] = 1/4 + asin(r)/(2π) for W ~ N(0, s²),
    // r = s²/(1 + s²) = ρ²/2). Shapley: Sh_x = c({x})/2, so x's share of Var y is
    // 3·asin(ρ²/2)/π = 0.3111 at ρ = 0.8, and u's the rest. Within 0.01, as the linear
    // Gaussian case (tests/sensitivity.rs).
    use rvtol_analysis::shapley::{shapley_effects, ShapleySettings};
    let rho: f64 = 0.8;
    let document = json!({
        "name": "shapley-copula",
        "seed": 3,
        "variables": [
            { "name": "u", "distribution": { "uniform": { "lower": 0.0, "upper": 1.0 } } },
            { "name": "x", "distribution": { "normal": { "mean": 0.0, "sd": 1.0 } } }
        ],
        "correlations": [{ "between": ["u", "x"], "rho": rho }],
        "models": [{
            "model": "linear_stack",
            "params": { "output": "y", "unit": "1", "coefficients": { "a": 1.0, "b": 0.0 } },
            "inputs": { "a": "u", "b": "x" }
        }]
    });
    let settings = ShapleySettings {
        permutations: 600,
        outer: 1000,
        inner: 3,
        seed: 9,
    };
    let effects = &shapley_effects(&scenario(&document), settings).unwrap()[0].1;
    let share_x = 3.0 * (rho * rho / 2.0).asin() / std::f64::consts::PI;
    assert_effects_near(effects, [1.0 - share_x, share_x], 0.01);
}

#[test]
fn a_malformed_correlation_is_refused_with_its_path() {
    let both = grinding(
        10,
        json!({ "between": ["runout", "pitch"], "rho": 0.2, "spearman": 0.2 }),
    );
    assert!(refusal(&both).starts_with("correlations[0]: give either rho"));
    let neither = grinding(10, json!({ "between": ["runout", "pitch"] }));
    assert!(refusal(&neither).starts_with("correlations[0]: give rho"));
    let beyond = grinding(
        10,
        json!({ "between": ["runout", "pitch"], "spearman": 1.2 }),
    );
    assert!(refusal(&beyond)
        .starts_with("correlations[0].spearman: a rank correlation must lie in [-1, 1], got 1.2"));
    // Three rank correlations of −0.9: their normal scores' matrix is indefinite.
    let mut indefinite = grinding(
        10,
        json!({ "between": ["runout", "pitch"], "spearman": -0.9 }),
    );
    indefinite["variables"].as_array_mut().unwrap().push(
        json!({ "name": "third", "distribution": { "uniform": { "lower": 0.0, "upper": 1.0 } } }),
    );
    for pair in [["runout", "third"], ["pitch", "third"]] {
        indefinite["correlations"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "between": pair, "spearman": -0.9 }));
    }
    let message = refusal(&indefinite);
    assert!(
        message.starts_with("correlations (joint correlation of"),
        "{message}"
    );
}
