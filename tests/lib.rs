//! Shared helpers of rvtol's integration tests, and the precision policy of its
//! statistical tests.
//!
//! Precision policy: a statistical test compares a Monte Carlo estimate with its exact
//! value and accepts a difference of at most [`SIGMA_BOUND`] standard errors of the
//! estimator, the standard error derived from the exact distribution (not from the
//! sample). For a normal statistic a 5σ bound has a false-alarm probability of 5.7e-7 per
//! comparison; all tests use fixed seeds, so a pass is reproducible and a failure means a
//! change in the sampler or the model, which a reviewer must explain. Distribution tests
//! use the Kolmogorov–Smirnov statistic against its 0.1 % critical value.

use std::path::PathBuf;

/// Standard errors allowed between an estimate and its exact value.
pub const SIGMA_BOUND: f64 = 5.0;

/// Asymptotic 0.1 % critical value of √n·D for the one-sample Kolmogorov–Smirnov test
/// (the Kolmogorov distribution's 0.999 quantile).
pub const KS_CRITICAL_0_001: f64 = 1.949;

/// Path of a file in scenarios/.
pub fn scenario_path(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(file)
}

/// One-sample Kolmogorov–Smirnov statistic √n·D of `values` against `cdf`.
pub fn ks_statistic(values: &mut [f64], cdf: impl Fn(f64) -> f64) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len() as f64;
    let d = values
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let f = cdf(x);
            (f - i as f64 / n).max((i + 1) as f64 / n - f)
        })
        .fold(0.0, f64::max);
    n.sqrt() * d
}

/// Closed form of scenarios/linear-stack-correlated.json: mean c + aᵀμ and sd √(aᵀΣa)
/// over the normal columns (validation.md, "Checks that need no document").
pub fn linear_closed_form(scenario: &rvtol_engine::Scenario) -> (f64, f64) {
    let coefficients = [
        ("bore_depth", 1.0),
        ("bearing_width", -1.0),
        ("spacer_width", -1.0),
        ("carrier.dw", -1.0),
        ("carrier.dbeta", -40.0),
    ];
    let (columns, mean, cov) = scenario.input_space.gaussian_specification();
    let a: Vec<f64> = columns
        .iter()
        .map(|&c| {
            let name = &scenario.columns[c].name;
            coefficients
                .iter()
                .find(|(n, _)| n == name)
                .map_or(0.0, |(_, v)| *v)
        })
        .collect();
    let m: f64 = a.iter().zip(mean.iter()).map(|(a, m)| a * m).sum();
    let mut variance = 0.0;
    for i in 0..a.len() {
        for j in 0..a.len() {
            variance += a[i] * cov[(i, j)] * a[j];
        }
    }
    (m, variance.sqrt())
}

/// The JSON report of a run of `scenario` on a pool of `threads` threads.
pub fn run_with_threads(
    scenario: &rvtol_engine::Scenario,
    settings: rvtol_engine::RunSettings,
    threads: usize,
) -> String {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let result = pool
        .install(|| rvtol_engine::run(scenario, settings, &|_| {}))
        .unwrap();
    rvtol_engine::report::RunReport::new(scenario, result).to_json()
}

/// Run settings of `samples` Monte Carlo rows from `seed`, exact percentiles up to the
/// default limit.
pub fn run_settings(samples: u64, seed: u64) -> rvtol_engine::RunSettings {
    rvtol_engine::RunSettings {
        samples,
        seed,
        exact_percentile_limit: rvtol_engine::DEFAULT_EXACT_PERCENTILE_LIMIT,
        sampling: rvtol_engine::Sampling::default(),
    }
}

/// Asserts every Shapley effect within `tolerance` of its expected share (in order).
pub fn assert_effects_near(
    effects: &[rvtol_analysis::shapley::ShapleyEffect],
    expected: impl IntoIterator<Item = f64>,
    tolerance: f64,
) {
    for (effect, expected) in effects.iter().zip(expected) {
        assert!(
            (effect.effect - expected).abs() < tolerance,
            "{}: {} vs {expected}",
            effect.input,
            effect.effect
        );
    }
}

/// The one line a scenario document is refused with (panics when it is accepted).
pub fn refusal(document: &serde_json::Value) -> String {
    match rvtol_engine::Scenario::from_json(&document.to_string(), "test") {
        Ok(_) => panic!("accepted"),
        Err(err) => err.to_string(),
    }
}

/// Asserts that a run's report has the same bits for 1, 2 and 4 threads and for 1 and 3
/// shards merged (the reproducibility contract).
pub fn assert_same_bits_for_threads_and_shards(
    scenario: &rvtol_engine::Scenario,
    settings: rvtol_engine::RunSettings,
) {
    use rvtol_engine::{merge, run_chunks, shard_range};
    let one = run_with_threads(scenario, settings, 1);
    assert_eq!(one, run_with_threads(scenario, settings, 2), "2 threads");
    assert_eq!(one, run_with_threads(scenario, settings, 4), "4 threads");
    for shards in [1u64, 3] {
        let partials = (0..shards)
            .map(|k| {
                let chunks = shard_range(settings.chunk_count(), k, shards);
                run_chunks(scenario, settings, chunks, &|_| {}).unwrap()
            })
            .collect();
        let merged = merge(scenario, settings, partials).unwrap();
        assert_eq!(
            one,
            rvtol_engine::report::RunReport::new(scenario, merged).to_json(),
            "{shards} shards"
        );
    }
}

/// A shipped scenario's text as rvtol loads it from its file: the reducer file and the data
/// files it names written in (so the text stands alone, wherever it is written or parsed).
pub fn shipped_text(path: impl AsRef<std::path::Path>) -> String {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).expect("shipped scenario");
    let limit = rvtol_analysis::request::input_file::ReadLimit::library();
    let folder = rvtol_analysis::request::scenario::scenario_folder(path);
    rvtol_analysis::request::data::inline_data_files(&text, &folder, &limit)
        .expect("shipped scenario's files")
        .into_owned()
}
