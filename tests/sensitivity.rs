//! Tests of the Sobol' sensitivity indices against closed forms (validation.md, "Checks
//! that need no document"): the Ishigami function (a = 7, b = 0.1) and the Sobol'
//! G-function, with 2^16 base samples; grouping of correlated sources; reproducibility.
//!
//! A 95 % interval misses the true value 5 % of the time, so "every interval of one run
//! covers its closed form" fails for a correct estimator in about a quarter of the seeds
//! (six intervals). The tests therefore check the coverage over many seeds against its
//! binomial distribution (precision policy, tests/lib.rs), and every interval's width.

use rvtol_analysis::sensitivity::{
    independent_groups, sobol_indices, IntervalMethod, SensitivitySettings,
    DEFAULT_ROW_BOOTSTRAP_LIMIT,
};
use rvtol_analysis::sensitivity_report::SensitivityReport;
use rvtol_deviation::SamplingMethod;
use rvtol_engine::{Sampling, Scenario};
use rvtol_models::{Ishigami, ModelParams, ParamValue, SobolG};
use rvtol_tests::{scenario_path, SIGMA_BOUND};

const BASE_SAMPLES: u64 = 1 << 16;

fn settings(seed: u64) -> SensitivitySettings {
    SensitivitySettings {
        base_samples: BASE_SAMPLES,
        seed,
        bootstrap: 300,
        confidence: 0.95,
        row_bootstrap_limit: DEFAULT_ROW_BOOTSTRAP_LIMIT,
        sampling: Sampling::MONTE_CARLO,
    }
}

/// Runs `seeds` analyses of a one-output scenario; returns (intervals covering the closed
/// form, intervals in all, widest interval).
fn coverage(file: &str, seeds: u64, closed_form: impl Fn(&str) -> (f64, f64)) -> (u64, u64, f64) {
    coverage_with(file, seeds, closed_form, settings)
}

/// [`coverage`] with the settings of each seed given.
fn coverage_with(
    file: &str,
    seeds: u64,
    closed_form: impl Fn(&str) -> (f64, f64),
    settings: impl Fn(u64) -> SensitivitySettings,
) -> (u64, u64, f64) {
    let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
    let (mut covered, mut total, mut widest) = (0u64, 0u64, 0.0f64);
    for seed in 1..=seeds {
        let outputs = sobol_indices(&scenario, settings(seed), &|_| {}).unwrap();
        for index in &outputs[0].indices {
            let (s, st) = closed_form(&index.group);
            for (value, interval) in [(s, index.first_order.interval), (st, index.total.interval)] {
                total += 1;
                covered += u64::from(interval[0] <= value && value <= interval[1]);
                widest = widest.max(interval[1] - interval[0]);
            }
        }
    }
    (covered, total, widest)
}

fn assert_coverage(covered: u64, total: u64) {
    // Binomial(total, 0.95): bound 5 standard deviations below the mean.
    let n = total as f64;
    let floor = 0.95 * n - SIGMA_BOUND * (n * 0.95 * 0.05).sqrt();
    assert!(
        covered as f64 >= floor,
        "{covered} of {total} intervals cover (floor {floor:.1})"
    );
}

#[test]
fn ishigami_intervals_cover_the_closed_form_and_are_narrow() {
    let (covered, total, widest) = coverage("ishigami.json", 20, ishigami_closed_form());
    assert_coverage(covered, total);
    assert!(widest < 0.02, "widest interval {widest}");
}

#[test]
fn block_bootstrap_intervals_cover_the_closed_form_too() {
    // With the row-bootstrap limit below N·(2G + 2) the intervals come from resampled blocks
    // of rows (2^16 base samples: 64-row blocks, 1024 of them); their coverage must hold at
    // the same nominal rate, and their width stay that of the row bootstrap (< 0.02).
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("ishigami.json")).unwrap();
    let blocks = SensitivitySettings {
        row_bootstrap_limit: 1,
        ..settings(1)
    };
    assert_eq!(
        blocks.interval_method(&scenario),
        IntervalMethod::Blocks { rows: 64 }
    );
    let (covered, total, widest) =
        coverage_with("ishigami.json", 20, ishigami_closed_form(), |seed| {
            SensitivitySettings {
                row_bootstrap_limit: 1,
                ..settings(seed)
            }
        });
    assert_coverage(covered, total);
    assert!(widest < 0.02, "widest interval {widest}");
}

#[test]
fn g_function_intervals_cover_the_closed_form_and_are_narrow() {
    let (covered, total, widest) = coverage("sobol-g.json", 10, g_closed_form());
    assert_coverage(covered, total);
    assert!(widest < 0.02, "widest interval {widest}");
}

/// A group's closed-form (first-order, total) indices.
type ClosedForm<'a> = dyn Fn(&str) -> (f64, f64) + 'a;

/// The closed-form indices of scenarios/ishigami.json's inputs x1, x2, x3 (a = 7, b = 0.1).
fn ishigami_closed_form() -> impl Fn(&str) -> (f64, f64) {
    let (s, st) = Ishigami::from_params(&ModelParams::new())
        .unwrap()
        .sobol_indices();
    move |name: &str| {
        let i = ["x1", "x2", "x3"].iter().position(|n| *n == name).unwrap();
        (s[i], st[i])
    }
}

/// The closed-form indices of scenarios/sobol-g.json's inputs x1 … x6 (a = 0, 1, 4.5, 9,
/// 99, 99).
fn g_closed_form() -> impl Fn(&str) -> (f64, f64) {
    let coefficients = [0.0, 1.0, 4.5, 9.0, 99.0, 99.0];
    let params = ModelParams::new().with(
        "coefficients",
        ParamValue::Named(
            coefficients
                .iter()
                .enumerate()
                .map(|(i, a)| (format!("x{}", i + 1), *a))
                .collect(),
        ),
    );
    let (s, st) = SobolG::from_params(&params).unwrap().sobol_indices();
    move |name: &str| {
        let i: usize = name[1..].parse::<usize>().unwrap() - 1;
        (s[i], st[i])
    }
}

/// Settings of a replicated design: `replicates` of `points` each.
fn replicated(
    method: SamplingMethod,
    replicates: u64,
    points: u64,
    seed: u64,
) -> SensitivitySettings {
    SensitivitySettings {
        base_samples: replicates * points,
        sampling: Sampling { method, replicates },
        ..settings(seed)
    }
}

/// Per index (group, first-order or total) of a one-output scenario, the estimates over
/// `seeds` analyses and their interval widths.
fn estimates_over_seeds(
    file: &str,
    seeds: u64,
    settings: impl Fn(u64) -> SensitivitySettings,
) -> std::collections::BTreeMap<(String, bool), Vec<(f64, f64)>> {
    let scenario = rvtol_analysis::request::scenario::load(&scenario_path(file)).unwrap();
    let mut all = std::collections::BTreeMap::new();
    for seed in 1..=seeds {
        let outputs = sobol_indices(&scenario, settings(seed), &|_| {}).unwrap();
        for index in &outputs[0].indices {
            for (total, estimate) in [(false, index.first_order), (true, index.total)] {
                all.entry((index.group.clone(), total))
                    .or_insert_with(Vec::new)
                    .push((estimate.value, estimate.interval[1] - estimate.interval[0]));
            }
        }
    }
    all
}

#[test]
fn replicated_designs_are_unbiased_and_their_intervals_cover_the_closed_form() {
    // Ishigami and the G-function, 16 replicates of 2^10 points: the seeds' average of
    // every index within SIGMA_BOUND standard errors (the seeds' spread / √seeds: the
    // estimators' variance under LHS and RQMC has no closed form) of the closed form, and
    // the coverage of the t intervals binomial at 95 % (assert_coverage).
    let (ishigami, g) = (ishigami_closed_form(), g_closed_form());
    let cases: [(&str, &ClosedForm<'_>); 2] = [("ishigami.json", &ishigami), ("sobol-g.json", &g)];
    for method in [SamplingMethod::Rqmc, SamplingMethod::LatinHypercube] {
        for (file, closed_form) in cases {
            let seeds = 30;
            let (covered, total, _) = coverage_with(file, seeds, closed_form, |seed| {
                replicated(method, 16, 1 << 10, seed)
            });
            assert_coverage(covered, total);
            for ((group, is_total), values) in
                estimates_over_seeds(file, seeds, |seed| replicated(method, 16, 1 << 10, seed))
            {
                let (first, total) = closed_form(&group);
                let exact = if is_total { total } else { first };
                let n = values.len() as f64;
                let mean = values.iter().map(|v| v.0).sum::<f64>() / n;
                let spread =
                    (values.iter().map(|v| (v.0 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
                assert!(
                    (mean - exact).abs() <= SIGMA_BOUND * spread / n.sqrt() + 1e-12,
                    "{method:?} {file} {group} (total: {is_total}): mean {mean} vs {exact}, spread {spread}"
                );
            }
        }
    }
}

#[test]
fn rqmc_intervals_shrink_faster_than_monte_carlo() {
    // Ishigami is smooth: the scrambled Sobol' design's interval width falls faster than
    // N^−1/2 (observed N^−0.90 from 2^8 to 2^12 points per replicate), and at 2^12 points
    // it is narrower than the Monte Carlo bootstrap's at the same N (observed 4.0 times).
    // The mean width over every index and 5 seeds. Each seed's mean width varies by about
    // 17 % under rqmc (its t interval rests on 16 replicates), so the 5 seeds' mean by
    // about 8 %: the bounds, slope −0.75 and half the Monte Carlo width, sit several of
    // those spreads from the observed values, and a design that lost its balance (slope
    // −0.5, width ratio 1) fails both.
    let mean_width = |settings: &dyn Fn(u64) -> SensitivitySettings| {
        let all = estimates_over_seeds("ishigami.json", 5, settings);
        let widths: Vec<f64> = all.values().flatten().map(|v| v.1).collect();
        widths.iter().sum::<f64>() / widths.len() as f64
    };
    let small = mean_width(&|seed| replicated(SamplingMethod::Rqmc, 16, 1 << 8, seed));
    let large = mean_width(&|seed| replicated(SamplingMethod::Rqmc, 16, 1 << 12, seed));
    let slope = (large / small).ln() / 16f64.ln();
    assert!(slope < -0.75, "width {small} → {large}: slope {slope}");
    let monte_carlo = mean_width(&|seed| SensitivitySettings {
        base_samples: 16 << 12,
        ..settings(seed)
    });
    assert!(
        large * 2.0 < monte_carlo,
        "rqmc width {large} against Monte Carlo's {monte_carlo}"
    );
}

#[test]
fn replicated_designs_are_refused_where_they_do_not_fit() {
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("ishigami.json")).unwrap();
    let refused = |settings: SensitivitySettings| {
        sobol_indices(&scenario, settings, &|_| {})
            .unwrap_err()
            .to_string()
    };
    let message = refused(SensitivitySettings {
        base_samples: 1000,
        ..replicated(SamplingMethod::Rqmc, 16, 1, 1)
    });
    assert!(
        message.contains("samples: 1000 base samples do not split into 16 replicates")
            && message.contains("such as 1024"),
        "{message}"
    );
    let message = refused(replicated(SamplingMethod::Rqmc, 1, 1024, 1));
    assert!(
        message.contains("replicates: must lie in 2..=1024"),
        "{message}"
    );
    let message = refused(SensitivitySettings {
        sampling: Sampling {
            method: SamplingMethod::MonteCarlo,
            replicates: 4,
        },
        ..settings(1)
    });
    assert!(
        message.contains("Monte Carlo rows are independent"),
        "{message}"
    );
}

#[test]
fn correlated_sources_form_one_group_and_a_part_is_one_group() {
    // linear-stack-correlated.json correlates bearing_width with spacer_width and the
    // carrier's dw with bore_depth: two groups remain (a part's six components stay together).
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("linear-stack-correlated.json"))
            .unwrap();
    let names: Vec<String> = independent_groups(&scenario)
        .into_iter()
        .map(|g| g.name)
        .collect();
    assert_eq!(names, ["carrier+bore_depth", "bearing_width+spacer_width"]);
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("rv20e-hysteresis.json")).unwrap();
    let groups = independent_groups(&scenario);
    assert_eq!(groups.len(), 10);
    assert_eq!(groups[0].name, "input_shaft");
    assert_eq!(groups[0].columns.len(), 6);
}

#[test]
fn report_is_byte_identical_for_1_and_2_threads() {
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("rv20e-hysteresis.json")).unwrap();
    for sampling in [
        Sampling::MONTE_CARLO,
        Sampling {
            method: SamplingMethod::Rqmc,
            replicates: 4,
        },
    ] {
        let settings = SensitivitySettings {
            base_samples: 10_000,
            seed: 4,
            bootstrap: 50,
            confidence: 0.95,
            row_bootstrap_limit: DEFAULT_ROW_BOOTSTRAP_LIMIT,
            sampling,
        };
        let json = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let outputs = pool
                .install(|| sobol_indices(&scenario, settings, &|_| {}))
                .unwrap();
            SensitivityReport::new(&scenario, settings, outputs).to_json()
        };
        assert_eq!(json(1), json(2), "{sampling:?}");
    }
}

/// Closed-form Shapley effects of y = aᵀx, x ~ N(μ, Σ) (Owen & Prieur 2017): with
/// c(J) = a_Jᵀ(Σ_JJ − Σ_{J,K}Σ_KK⁻¹Σ_{K,J})a_J, K the complement of J,
/// Sh_j = Σ_{S ⊆ −j} |S|!(d − |S| − 1)!/d! · (c(S ∪ {j}) − c(S)) / aᵀΣa.
fn linear_gaussian_shapley(a: &[f64], cov: &nalgebra::DMatrix<f64>) -> Vec<f64> {
    let d = a.len();
    let cost = |set: u32| -> f64 {
        let j: Vec<usize> = (0..d).filter(|i| set & (1 << i) != 0).collect();
        let k: Vec<usize> = (0..d).filter(|i| set & (1 << i) == 0).collect();
        if j.is_empty() {
            return 0.0;
        }
        let sub = |r: &[usize], c: &[usize]| {
            nalgebra::DMatrix::from_fn(r.len(), c.len(), |x, y| cov[(r[x], c[y])])
        };
        let mut conditional = sub(&j, &j);
        if !k.is_empty() {
            let inverse = sub(&k, &k).try_inverse().unwrap();
            conditional -= sub(&j, &k) * inverse * sub(&k, &j);
        }
        let aj = nalgebra::DVector::from_iterator(j.len(), j.iter().map(|&i| a[i]));
        (aj.transpose() * conditional * aj)[(0, 0)]
    };
    let factorial = |n: usize| (1..=n).product::<usize>() as f64;
    let total = cost((1 << d) - 1);
    (0..d)
        .map(|j| {
            (0u32..(1 << d))
                .filter(|s| s & (1 << j) == 0)
                .map(|s| {
                    let size = s.count_ones() as usize;
                    factorial(size) * factorial(d - size - 1) / factorial(d)
                        * (cost(s | (1 << j)) - cost(s))
                })
                .sum::<f64>()
                / total
        })
        .collect()
}

#[test]
fn shapley_effects_of_a_linear_gaussian_model_match_the_closed_form() {
    use rvtol_analysis::shapley::{shapley_effects, ShapleySettings};
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("shapley-linear-gaussian.json"))
            .unwrap();
    let (_, _, cov) = scenario.input_space.gaussian_specification();
    let exact = linear_gaussian_shapley(&[1.0, 1.0, 0.5], &cov);
    assert!((exact.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    let settings = ShapleySettings {
        permutations: 600,
        outer: 1000,
        inner: 3,
        seed: 9,
    };
    let effects = &shapley_effects(&scenario, settings).unwrap()[0].1;
    // Issue acceptance: within 0.01 of the closed form.
    rvtol_tests::assert_effects_near(effects, exact.iter().copied(), 0.01);
}

#[test]
fn screening_of_a_linear_stack_is_exact() {
    // For y = c + aᵀx the central difference is the coefficient (to rounding), gᵀΣg is the
    // closed-form variance 8.957994e-5 mm² (tests/engine.rs), the Euler shares sum to 1 and
    // the regression fits exactly (R² = 1).
    use rvtol_analysis::screening::screening;
    use rvtol_analysis::shapley::players;
    let scenario =
        rvtol_analysis::request::scenario::load(&scenario_path("linear-stack-correlated.json"))
            .unwrap();
    let result = screening(&scenario, &players(&scenario), 20_000, 3).unwrap();
    let output = &result[0];
    assert!((output.linearised_variance - 8.957994e-5).abs() < 1e-11);
    assert!((output.r_squared - 1.0).abs() < 1e-9);
    let shares: f64 = output.sources.iter().map(|s| s.contribution).sum();
    assert!((shares - 1.0).abs() < 1e-12);
    let expected = [
        ("bore_depth", 1.0),
        ("bearing_width", -1.0),
        ("spacer_width", -1.0),
        ("carrier.dw", -1.0),
        ("carrier.dbeta", -40.0),
        ("carrier.du", 0.0),
    ];
    for (column, coefficient) in expected {
        let derivative = output
            .sources
            .iter()
            .flat_map(|s| &s.derivatives)
            .find(|(c, _)| c == column)
            .unwrap()
            .1;
        assert!(
            (derivative - coefficient).abs() < 1e-6,
            "{column}: {derivative}"
        );
    }
}

#[test]
fn user_defined_groups_replace_their_members() {
    let text = rvtol_tests::shipped_text(scenario_path("rv20e-hysteresis.json"));
    let grouped = text.replacen(
        "\"spec_limits\"",
        "\"sensitivity_groups\": [{ \"name\": \"cycloid_gear\", \"members\": [\"cycloid_radial_runout\", \"cycloid_cumulative_pitch_error\"] }],\n  \"spec_limits\"",
        1,
    );
    let scenario = Scenario::from_json(&grouped, "grouped").unwrap();
    let groups = independent_groups(&scenario);
    assert_eq!(groups.len(), 9);
    assert_eq!(groups[0].name, "cycloid_gear");
    assert_eq!(groups[0].columns.len(), 2);
    assert!(!groups.iter().any(|g| g.name == "cycloid_radial_runout"));

    let unknown = grouped.replace(
        "\"cycloid_radial_runout\", \"cycloid",
        "\"cycloid_runout\", \"cycloid",
    );
    let err = Scenario::from_json(&unknown, "bad").err().unwrap();
    assert_eq!(
        err.to_string(),
        "sensitivity_groups[0].members[0]: no part or variable named \"cycloid_runout\""
    );
    let twice = grouped.replace(
        "\"members\": [\"cycloid_radial_runout\", \"cycloid_cumulative_pitch_error\"]",
        "\"members\": [\"cycloid_radial_runout\", \"cycloid_radial_runout\"]",
    );
    let err = Scenario::from_json(&twice, "bad").err().unwrap();
    assert_eq!(
        err.to_string(),
        "sensitivity_groups[0].members[1]: \"cycloid_radial_runout\" is already in a group"
    );
}

/// Φ₂(h, h; r), the bivariate standard normal CDF on the diagonal: Φ(h)² plus
/// ∫₀^r exp(−h²/(1 + ρ))/(2π√(1 − ρ²)) dρ (∂Φ₂/∂ρ is the bivariate density, Plackett
/// 1954), by Simpson's rule on 2000 intervals (the integrand is smooth for r < 1).
fn bivariate_diagonal(h: f64, r: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let density = |rho: f64| {
        (-h * h / (1.0 + rho)).exp() / (2.0 * std::f64::consts::PI * (1.0 - rho * rho).sqrt())
    };
    let n = 2000;
    let step = r / n as f64;
    let simpson: f64 = (0..=n)
        .map(|i| {
            let weight = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            weight * density(i as f64 * step)
        })
        .sum::<f64>()
        * step
        / 3.0;
    Normal::standard().cdf(h).powi(2) + simpson
}

#[test]
fn failure_indicator_indices_cover_their_closed_form() {
    // y = x1 + x2, x1 ~ N(0, 1), x2 ~ N(0, 0.5²) independent, spec y ≤ t = 1: the
    // indicator I = 1{y > t} has p = Q(t/σ), σ² = 1.25. E[I | x1] = Φ((x1 − t)/σ2), so
    // Var E[I | x1] = Φ₂(h, h; σ1²/σ²) − p² with h = −t/σ (E[Φ(az + b)²] for z standard
    // normal is Φ₂ on the diagonal at b/√(1 + a²), correlation a²/(1 + a²)); likewise for
    // x2. S_i = that over p(1 − p); with two independent inputs S_T1 = 1 − S_2. Coverage
    // of the 95 % intervals over 10 seeds (binomial floor, as above), and the reported
    // share p within 5 standard errors of the run's rows.
    use statrs::distribution::{ContinuousCDF, Normal};
    let (s1, s2, t) = (1.0f64, 0.5f64, 1.0f64);
    let sigma = s1.hypot(s2);
    let h = -t / sigma;
    let p = Normal::standard().cdf(h);
    let first =
        |si: f64| (bivariate_diagonal(h, si * si / (sigma * sigma)) - p * p) / (p * (1.0 - p));
    let exact = [(first(s1), 1.0 - first(s2)), (first(s2), 1.0 - first(s1))];
    let document = serde_json::json!({
        "name": "threshold",
        "variables": [
            { "name": "x1", "distribution": { "normal": { "mean": 0.0, "sd": s1 } } },
            { "name": "x2", "distribution": { "normal": { "mean": 0.0, "sd": s2 } } }
        ],
        "models": [{
            "model": "linear_stack",
            "params": { "output": "y", "unit": "1", "coefficients": { "a": 1.0, "b": 1.0 } },
            "inputs": { "a": "x1", "b": "x2" }
        }],
        "spec_limits": { "y": { "upper": t } }
    });
    let scenario = Scenario::from_json(&document.to_string(), "threshold").unwrap();
    let (mut covered, mut total) = (0, 0);
    for seed in 1..=10 {
        let outputs = sobol_indices(&scenario, settings(seed), &|_| {}).unwrap();
        let failure = outputs.iter().find(|o| o.name == "y out of spec").unwrap();
        let n = 2.0 * BASE_SAMPLES as f64;
        assert!(
            (failure.mean - p).abs() < SIGMA_BOUND * (p * (1.0 - p) / n).sqrt(),
            "share {} against {p}",
            failure.mean
        );
        for index in &failure.indices {
            let (s, st) = exact[if index.group == "x1" { 0 } else { 1 }];
            for (value, interval) in [(s, index.first_order.interval), (st, index.total.interval)] {
                total += 1;
                covered += u64::from(interval[0] <= value && value <= interval[1]);
            }
        }
    }
    assert_coverage(covered, total);
}
