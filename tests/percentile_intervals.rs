//! The percentiles' 95 % confidence intervals of `rvtol run` cover the true percentile at
//! least at their nominal rate, on the exact and on the sketch path, and are not wider
//! than the order statistics' sampling law says.
//!
//! Outputs with known quantiles: x ~ N(0, 1) (x_p = Φ⁻¹(p)) and y = exp(0.5·Z) with Z
//! standard normal (a skewed law, y_p = exp(0.5·Φ⁻¹(p))), each a linear stack of one
//! variable. 400 runs of 2,000 samples per path (seeds 1–400). The binomial-rank
//! interval covers with probability at least 95 % for a continuous law (by construction,
//! Hahn & Meeker 1991 §5.2), so the count of covering runs is at least Binomial(400, 0.95):
//! it falls below 380 − 3.5·√(400·0.95·0.05) = 364.7 with probability below 3·10⁻⁴ per
//! percentile. Fewer means the intervals undercover.

use rvtol_engine::figures::PERCENTS;
use rvtol_engine::report::RunReport;
use rvtol_engine::{run, RunSettings, Scenario};
use statrs::distribution::{ContinuousCDF, Normal};

const RUNS: u64 = 400;
const SAMPLES: u64 = 2_000;

fn scenario() -> Scenario {
    let text = r#"{
      "name": "percentile-intervals",
      "variables": [
        { "name": "x", "unit": "1", "distribution": { "normal": { "mean": 0.0, "sd": 1.0 } } },
        { "name": "y", "unit": "1", "distribution": { "lognormal": { "median": 1.0, "upper": 4.4816890703380645, "cp": 1.0 } } }
      ],
      "models": [
        { "model": "linear_stack", "params": { "output": "normal", "unit": "1", "coefficients": { "x": 1.0 } }, "inputs": { "x": "x" } },
        { "model": "linear_stack", "params": { "output": "skewed", "unit": "1", "coefficients": { "y": 1.0 } }, "inputs": { "y": "y" } }
      ]
    }"#;
    // upper = e^1.5 = median·exp(3σ) with σ = 0.5 at Cp 1 (scenarios/README.md).
    Scenario::from_json(text, "percentile-intervals").unwrap()
}

fn true_quantile(output: usize, percent: f64) -> f64 {
    let z = Normal::new(0.0, 1.0).unwrap().inverse_cdf(percent / 100.0);
    if output == 0 {
        z
    } else {
        (0.5 * z).exp()
    }
}

/// Per output and percent: runs whose interval covers the true quantile, and the mean
/// width of the median's interval (NaN when an end is open).
fn coverage(exact_percentile_limit: u64) -> (Vec<Vec<u64>>, [f64; 2]) {
    let scenario = scenario();
    let mut covered = vec![vec![0u64; PERCENTS.len()]; 2];
    let mut median_width = [0.0; 2];
    for seed in 1..=RUNS {
        let settings = RunSettings {
            samples: SAMPLES,
            seed,
            exact_percentile_limit,
            sampling: Default::default(),
        };
        let report = RunReport::new(&scenario, run(&scenario, settings, &|_| {}).unwrap());
        for (o, output) in report.outputs.iter().enumerate() {
            for (k, (key, percent)) in PERCENTS.iter().enumerate() {
                let [lower, upper] = output.percentile_ci95.get(key).unwrap();
                let truth = true_quantile(o, *percent);
                if lower.is_none_or(|l| l <= truth) && upper.is_none_or(|u| truth <= u) {
                    covered[o][k] += 1;
                }
                if *key == "50" {
                    median_width[o] += (upper.unwrap() - lower.unwrap()) / RUNS as f64;
                }
            }
        }
    }
    (covered, median_width)
}

fn check(exact_percentile_limit: u64, path: &str) {
    let (covered, median_width) = coverage(exact_percentile_limit);
    for (o, counts) in covered.iter().enumerate() {
        for ((key, _), &count) in PERCENTS.iter().zip(counts) {
            assert!(
                count >= 365,
                "{path}, output {o}, P{key}: {count} of {RUNS} intervals cover the true value"
            );
        }
    }
    // The median's interval spans about 2·1.96·√(p(1 − p)/n)/f(x_p): f = φ(0) for the
    // normal, φ(0)/(0.5·1) for y = exp(0.5·Z) at its median 1. Mean width within 10 %.
    let phi0 = 1.0 / (2.0 * std::f64::consts::PI).sqrt();
    let half = 1.96 * (0.25 / SAMPLES as f64).sqrt();
    for (o, density) in [phi0, phi0 / 0.5].into_iter().enumerate() {
        let expected = 2.0 * half / density;
        assert!(
            (median_width[o] / expected - 1.0).abs() < 0.1,
            "{path}, output {o}: mean width {} against {expected}",
            median_width[o]
        );
    }
}

#[test]
fn exact_percentile_intervals_cover_at_the_nominal_rate() {
    check(u64::MAX, "exact");
}

#[test]
fn sketch_percentile_intervals_cover_at_the_nominal_rate() {
    check(1, "sketch");
}

/// The intervals' ranks at n = 10³ … 10¹² for every reported percentile equal those of an
/// independent 40-digit computation (`scripts/binomial-reference.py`, which writes
/// `tests/data/binomial_ranks.csv` with the margin by which its decisive tail sums clear
/// 2.5 %: every margin is above 2·10⁻⁷, far beyond the 10⁻¹³ accuracy of rvtol's sums, so
/// the ranks must agree exactly). The library CDF they replaced was off by thousands of
/// ranks at n = 4·10⁷ (its continued fraction stopped before converging).
#[test]
fn interval_ranks_equal_a_high_precision_reference_up_to_a_trillion_values() {
    use rvtol_engine::stats::binomial_rank_interval;
    let table = include_str!("data/binomial_ranks.csv");
    let rank = |cell: &str| (!cell.is_empty()).then(|| cell.parse::<usize>().unwrap());
    let mut rows = 0;
    for line in table.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let n: usize = cells[0].parse().unwrap();
        let percent: f64 = cells[1].parse().unwrap();
        let margin: f64 = cells[4].parse().unwrap();
        assert!(margin > 1e-9, "{line}: too close to its level to decide");
        let expected = (rank(cells[2]), rank(cells[3]));
        assert_eq!(
            binomial_rank_interval(n, percent / 100.0, 0.95),
            expected,
            "n {n}, P{percent}"
        );
        rows += 1;
    }
    assert_eq!(rows, 13 * PERCENTS.len());
}

/// End to end at the size where the median's interval was found wrong: 40 samples of
/// 4·10⁷ uniform values (true median ½), each with its P50 interval from the exact path.
/// The interval covers with probability at least 95 %, so the covering count is at least
/// Binomial(40, 0.95); below 38 − 3.5·√(40·0.95·0.05) = 33.2 with probability under
/// 2·10⁻³ (the broken ranks covered 26 of 40).
#[test]
fn median_interval_covers_at_forty_million_values() {
    use rand::{RngExt, SeedableRng};
    use rayon::prelude::*;
    use rvtol_engine::stats::percentiles_type7_with_intervals;
    let n = 40_000_000;
    let covered = (0..40u64)
        .into_par_iter()
        .filter(|&seed| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let mut values: Vec<f64> = (0..n).map(|_| rng.random::<f64>()).collect();
            let found = percentiles_type7_with_intervals(&mut values, &[50.0], 0.95)[0].unwrap();
            found.lower.unwrap() <= 0.5 && 0.5 < found.upper.unwrap()
        })
        .count();
    assert!(
        covered >= 34,
        "{covered} of 40 P50 intervals hold the true median"
    );
}
