//! The 95 % intervals of the moment-method Cp and Cpk in `rvtol run`'s report cover the
//! true index at their nominal rate, for a normal output and for one with light tails.
//!
//! Outputs with known indices, each a linear stack of one variable, spec −3 ≤ x ≤ 4:
//! x ~ N(0, 1): Cp = 7/6, Cpk = min(4/3, 1) = 1 (lower side); u ~ U(−√3, √3) (σ = 1,
//! excess kurtosis −1.2, where the normal-theory variance of s, σ²/(2n), would be 2.5
//! times too large and the interval needlessly wide): the same Cp and Cpk. 1,000 runs of
//! 2,000 samples (seeds 1–1000). The intervals are asymptotic (delta method), so their
//! coverage is about 95 %: the count of covering runs is then about Binomial(1000, 0.95),
//! which lies within 950 ± 3.5·√(1000·0.95·0.05) = 950 ± 24.1 with probability above
//! 0.999; outside means the interval under- or overcovers. (Over 3,000 runs the four
//! rates were 94.4–95.0 %.)

use rvtol_engine::report::RunReport;
use rvtol_engine::{run, RunSettings, Scenario};

const RUNS: u64 = 1_000;
const SAMPLES: u64 = 2_000;

fn scenario() -> Scenario {
    let text = r#"{
      "name": "capability-intervals",
      "variables": [
        { "name": "x", "unit": "1", "distribution": { "normal": { "mean": 0.0, "sd": 1.0 } } },
        { "name": "u", "unit": "1", "distribution": { "uniform": { "lower": -1.7320508075688772, "upper": 1.7320508075688772 } } }
      ],
      "models": [
        { "model": "linear_stack", "params": { "output": "normal", "unit": "1", "coefficients": { "x": 1.0 } }, "inputs": { "x": "x" } },
        { "model": "linear_stack", "params": { "output": "light_tailed", "unit": "1", "coefficients": { "u": 1.0 } }, "inputs": { "u": "u" } }
      ],
      "spec_limits": {
        "normal": { "lower": -3.0, "upper": 4.0 },
        "light_tailed": { "lower": -3.0, "upper": 4.0 }
      }
    }"#;
    Scenario::from_json(text, "capability-intervals").unwrap()
}

#[test]
fn cp_and_cpk_intervals_cover_at_their_nominal_rate() {
    let scenario = scenario();
    let (cp, cpk) = (7.0 / 6.0, 1.0);
    // Per output: runs whose Cp and Cpk intervals cover, and the mean Cpk half-width.
    let mut covered = [[0u64; 2]; 2];
    let mut half_width = [0.0f64; 2];
    for seed in 1..=RUNS {
        let settings = RunSettings {
            samples: SAMPLES,
            seed,
            exact_percentile_limit: 1_000_000,
            sampling: Default::default(),
        };
        let report = RunReport::new(&scenario, run(&scenario, settings, &|_| {}).unwrap());
        for (o, output) in report.outputs.iter().enumerate() {
            let c = output.capability.as_ref().unwrap();
            let [a, b] = c.cp_ci95.unwrap();
            let [d, e] = c.cpk_ci95.unwrap();
            covered[o][0] += u64::from(a <= cp && cp <= b);
            covered[o][1] += u64::from(d <= cpk && cpk <= e);
            half_width[o] += (e - d) / 2.0 / RUNS as f64;
        }
    }
    for (o, name) in ["normal", "light-tailed"].iter().enumerate() {
        for (k, index) in ["Cp", "Cpk"].iter().enumerate() {
            let count = covered[o][k];
            assert!(
                (926..=974).contains(&count),
                "{name} output, {index}: {count} of {RUNS} intervals cover the true value"
            );
        }
    }
    // Bissell's (1990) half-width for the normal output: 1.96·√(1/(9n) + Cpk²/(2n)).
    let n = SAMPLES as f64;
    let bissell = 1.959963984540054 * (1.0 / (9.0 * n) + cpk * cpk / (2.0 * n)).sqrt();
    assert!(
        (half_width[0] / bissell - 1.0).abs() < 0.05,
        "normal output: mean Cpk half-width {} against Bissell's {bissell}",
        half_width[0]
    );
    // The light tails narrow it: Var(s) = σ²(κ + 2)/(4n) with κ = −1.2.
    let light = 1.959963984540054 * (1.0 / (9.0 * n) + cpk * cpk * 0.8 / (4.0 * n)).sqrt();
    assert!(
        (half_width[1] / light - 1.0).abs() < 0.05,
        "light-tailed output: mean Cpk half-width {} against {light}",
        half_width[1]
    );
}
