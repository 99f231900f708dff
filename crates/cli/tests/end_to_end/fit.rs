//! `rvtol fit`: the fitted covariance recovers a known 6×6 covariance within the sampling
//! error at several n, stays positive semi-definite when n < 6 (where the sample matrix is
//! singular and the shrinkage must carry it), and the fragment loads as a scenario part;
//! the normality diagnostics pass normal data at their stated false-alarm rate and flag
//! uniform data. `rvtol fit --part` takes a part's columns out of a wider file and carries
//! the units of its headings into the part, which then equals the part fitted in mm and rad.
//!
//! Sampling error of a covariance entry (normal data): Var(s_ij) = (σ_ii·σ_jj + σ_ij²)/(n −
//! 1). The fit shrinks the correlations by Ledoit–Wolf's δ towards 0, a bias of δ·|σ_ij|
//! on an off-diagonal entry; the variances are not shrunk. An entry is accepted within
//! 4.5 standard errors plus that bias (36 entries: a false failure below 36·7·10⁻⁶ per n).

use crate::common;

use common::run_rvtol;
use nalgebra::DMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rvtol_analysis::fit::{anderson_darling, fit, fragment};
use rvtol_engine::Scenario;

fn truth() -> DMatrix<f64> {
    // sd in mm and rad, as a part has them; correlations up to 0.6.
    let sd = [0.004, 0.003, 0.002, 5e-5, 4e-5, 1e-5];
    let mut r = DMatrix::<f64>::identity(6, 6);
    for (i, j, rho) in [
        (0, 1, 0.6),
        (0, 4, 0.4),
        (1, 3, -0.5),
        (2, 5, 0.3),
        (3, 4, 0.2),
    ] {
        r[(i, j)] = rho;
        r[(j, i)] = rho;
    }
    DMatrix::from_fn(6, 6, |i, j| sd[i] * sd[j] * r[(i, j)])
}

/// n rows of N(mean, Σ) from standard normals by Box–Muller.
fn draw(sigma: &DMatrix<f64>, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let l = sigma.clone().cholesky().expect("positive definite").l();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut normal = move || {
        let u: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
        let v: f64 = rng.random();
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    };
    let mean = [0.01, -0.002, 0.0, 1e-4, 0.0, -2e-5];
    (0..n)
        .map(|_| {
            let z = nalgebra::DVector::from_fn(6, |_, _| normal());
            let x = &l * z;
            (0..6).map(|i| mean[i] + x[i]).collect()
        })
        .collect()
}

fn names() -> Vec<String> {
    ["du", "dv", "dw", "dalpha", "dbeta", "dgamma"]
        .map(String::from)
        .to_vec()
}

#[test]
fn recovers_a_known_covariance_within_its_sampling_error() {
    let sigma = truth();
    let mut shrinkage = Vec::new();
    for (n, seed) in [(30, 1), (200, 2), (2000, 3)] {
        let fitted = fit(&names(), &draw(&sigma, n, seed)).unwrap();
        let nf = n as f64;
        for i in 0..6 {
            for j in 0..6 {
                let se =
                    ((sigma[(i, i)] * sigma[(j, j)] + sigma[(i, j)].powi(2)) / (nf - 1.0)).sqrt();
                let bias = if i == j {
                    0.0
                } else {
                    fitted.shrinkage * sigma[(i, j)].abs()
                };
                let error = (fitted.cov(i, j) - sigma[(i, j)]).abs();
                assert!(
                    error <= 4.5 * se + bias,
                    "n = {n}, entry ({i}, {j}): {} against {} (se {se}, δ {})",
                    fitted.cov(i, j),
                    sigma[(i, j)],
                    fitted.shrinkage
                );
            }
        }
        assert!(fitted.repair.is_none(), "n = {n}: no repair needed");
        shrinkage.push(fitted.shrinkage);
    }
    // Less shrinkage as the sample grows.
    assert!(
        shrinkage[0] > shrinkage[1] && shrinkage[1] > shrinkage[2],
        "{shrinkage:?}"
    );
}

#[test]
fn fewer_parts_than_components_still_give_a_usable_part() {
    let sigma = truth();
    for n in [2, 4, 5] {
        let fitted = fit(&names(), &draw(&sigma, n, 10 + n as u64)).unwrap();
        let matrix = DMatrix::from_fn(6, 6, |i, j| fitted.cov(i, j));
        let smallest = matrix.symmetric_eigenvalues().min();
        assert!(
            smallest >= -1e-12 * matrix.trace(),
            "n = {n}: smallest eigenvalue {smallest}"
        );
        // Two parts give y_k·y_kᵀ = R for both rows, so Ledoit–Wolf's estimate of the
        // sample matrix's variance, and δ, is 0: the matrix is the rank-1 sample one
        // (positive semi-definite, as checked). From three parts on, δ > 0.
        if n >= 3 {
            assert!(fitted.shrinkage > 0.0, "n = {n}: the shrinkage carries it");
        }
        // The fragment is a valid part of a scenario that runs.
        let part = fragment(
            &fitted,
            Some("carrier"),
            &[None, None, None, None, None, None],
            "test.csv",
        );
        let scenario = serde_json::json!({
            "name": "fit",
            "parts": part["parts"],
            "models": [{
                "model": "linear_stack",
                "params": { "output": "y", "unit": "mm", "coefficients": { "a": 1.0, "b": 30.0 }, "input_units": { "b": "rad" } },
                "inputs": { "a": "carrier.du", "b": "carrier.dalpha" }
            }]
        });
        let scenario = Scenario::from_json(&scenario.to_string(), "fit")
            .unwrap_or_else(|err| panic!("n = {n}: {err}"));
        let settings = rvtol_engine::RunSettings {
            samples: 1000,
            seed: 1,
            exact_percentile_limit: 1_000_000,
            sampling: Default::default(),
        };
        rvtol_engine::run(&scenario, settings, &|_| {}).unwrap();
    }
    // One part is not enough for a covariance.
    assert!(fit(&names(), &draw(&sigma, 1, 9)).is_err());
}

#[test]
fn anderson_darling_passes_normals_and_flags_uniforms_at_their_rates() {
    // 400 samples each. Normal, n = 50: rejections at p < 0.05 are Binomial(400, 0.05)
    // (the p-values of D'Agostino & Stephens are accurate to about ±0.005 there): mean 20,
    // sd 4.4; at most 35 (3.4 sd). Uniform, n = 100: the test's power against the uniform
    // is above 0.85 at this size (369 of 400 with these seeds); with a power of 0.85 the
    // count is Binomial(400, 0.85), mean 340, sd 7.1: at least 316 (3.4 sd below).
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let mut normal_rejections = 0;
    let mut uniform_rejections = 0;
    for _ in 0..400 {
        let normal: Vec<f64> = (0..50)
            .map(|_| {
                let u: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
                let v: f64 = rng.random();
                (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
            })
            .collect();
        if anderson_darling(&normal).unwrap().p_value < 0.05 {
            normal_rejections += 1;
        }
        let uniform: Vec<f64> = (0..100).map(|_| rng.random::<f64>()).collect();
        if anderson_darling(&uniform).unwrap().p_value < 0.05 {
            uniform_rejections += 1;
        }
    }
    assert!(
        normal_rejections <= 35,
        "{normal_rejections} of 400 normal samples rejected"
    );
    assert!(
        uniform_rejections >= 316,
        "{uniform_rejections} of 400 uniform samples flagged"
    );
}

#[test]
fn anderson_darling_flags_a_large_uniform_sample() {
    // At n = 60,000 A* is in the thousands, beyond the range of D'Agostino & Stephens'
    // p-value polynomial (which rises again past A* = 153.5): p must stay at 0.
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let uniform: Vec<f64> = (0..60_000).map(|_| rng.random::<f64>()).collect();
    let test = anderson_darling(&uniform).unwrap();
    assert!(test.statistic > 153.0 && test.p_value == 0.0, "{test:?}");
}

#[test]
fn mardia_flags_a_uniform_cloud_and_passes_a_normal_one() {
    let sigma = truth();
    // Normal data: each p-value is uniform, so each test fails this bound with
    // probability 0.001.
    let fitted = fit(&names(), &draw(&sigma, 500, 5)).unwrap();
    let (skew, kurt) = fitted.mardia.unwrap();
    assert!(
        skew.p_value > 0.001 && kurt.p_value > 0.001,
        "{skew:?} {kurt:?}"
    );
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let uniform: Vec<Vec<f64>> = (0..500)
        .map(|_| (0..6).map(|_| rng.random::<f64>()).collect())
        .collect();
    let fitted = fit(&names(), &uniform).unwrap();
    let (_, kurt) = fitted.mardia.unwrap();
    // Six independent uniforms (excess kurtosis −1.2 each): E b₂,p = p² + 0.8p = 40.8
    // against p(p + 2) = 48 for a normal, sd √(8·48/500) = 0.88: z ≈ −8.2.
    assert!(kurt.statistic < -5.0 && kurt.p_value < 1e-6, "{kurt:?}");
}

#[test]
fn a_part_is_fitted_from_a_wider_file_in_its_headings_units() {
    // 300 parts drawn in mm and rad, written twice: in mm/rad, and in µm/arcsec with a
    // serial-number column and another part's column around them. The two fragments give
    // the same joint normal once loaded (to rounding).
    let rows = draw(&truth(), 300, 77);
    let dir = std::env::temp_dir().join(format!("rvtol-fit-units-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let arcsec = 648_000.0 / std::f64::consts::PI;
    let mut plain = String::from("du,dv,dw,dalpha,dbeta,dgamma\n");
    let mut wide = String::from(
        "serial,carrier.du [µm],carrier.dv [µm],carrier.dw [µm],other.du [mm],carrier.dalpha [arcsec],carrier.dbeta [arcsec],carrier.dgamma [arcsec]\n",
    );
    for (k, row) in rows.iter().enumerate() {
        let text: Vec<String> = row.iter().map(|x| x.to_string()).collect();
        plain.push_str(&format!("{}\n", text.join(",")));
        wide.push_str(&format!(
            "{},{},{},{},0.5,{},{},{}\n",
            1000 + k,
            row[0] * 1e3,
            row[1] * 1e3,
            row[2] * 1e3,
            row[3] * arcsec,
            row[4] * arcsec,
            row[5] * arcsec
        ));
    }
    let fitted = |name: &str, text: &str| -> serde_json::Value {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = run_rvtol(&["fit", path.to_str().unwrap(), "--part", "carrier"]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        if name == "wide.csv" {
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                stderr.contains("other columns left out: serial, other.du"),
                "{stderr}"
            );
        }
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let a = fitted("plain.csv", &plain);
    let b = fitted("wide.csv", &wide);
    assert!(a["parts"][0].get("units").is_none());
    assert_eq!(
        b["parts"][0]["units"],
        serde_json::json!({ "translation": "µm", "rotation": "arcsec" })
    );
    let load = |part: &serde_json::Value| {
        let scenario = serde_json::json!({
            "parts": part["parts"],
            "models": [{
                "model": "linear_stack",
                "params": { "coefficients": { "a": 1.0 } },
                "inputs": { "a": "carrier.du" }
            }]
        });
        Scenario::from_json(&scenario.to_string(), "fit").unwrap()
    };
    let (_, mean_a, cov_a) = load(&a).input_space.gaussian_specification();
    let (_, mean_b, cov_b) = load(&b).input_space.gaussian_specification();
    for i in 0..mean_a.len() {
        assert!((mean_a[i] - mean_b[i]).abs() <= 1e-12 * cov_a[(i, i)].sqrt().max(1e-300));
        for j in 0..mean_a.len() {
            let scale = (cov_a[(i, i)] * cov_a[(j, j)]).sqrt().max(1e-300);
            assert!(
                (cov_a[(i, j)] - cov_b[(i, j)]).abs() <= 1e-12 * scale,
                "{i} {j}"
            );
        }
    }
    // A misspelt part names the parts the file has.
    let out = run_rvtol(&[
        "fit",
        dir.join("wide.csv").to_str().unwrap(),
        "--part",
        "carier",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains(
            "no columns carier.du … carier.dgamma (the file has the parts carrier, other)"
        ),
        "{stderr}"
    );
    // Translations in two units are refused.
    let mixed = wide.replacen("carrier.dv [µm]", "carrier.dv [mm]", 1);
    let path = dir.join("mixed.csv");
    std::fs::write(&path, mixed).unwrap();
    let out = run_rvtol(&["fit", path.to_str().unwrap(), "--part", "carrier"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("the translation columns of the part are in different units (µm, mm, µm)"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_constant_column_has_its_value_as_mean_and_no_spread_and_no_normality_test() {
    // 0.0035 summed ten times and divided by ten is 0.0035000000000000027 in floating
    // point, and the deviations from that give an sd of 10⁻¹⁸ and a normality test on
    // rounding noise; a measured constant is its value with sd 0.
    let rows: Vec<Vec<f64>> = (0..10)
        .map(|k| vec![0.0035, k as f64 + 0.5 * (k % 3) as f64])
        .collect();
    let fitted = fit(&["a".to_string(), "b".to_string()], &rows).expect("fit");
    assert_eq!(fitted.mean[0], 0.0035);
    assert_eq!(fitted.covariance[0], 0.0, "variance of the constant column");
    assert_eq!(fitted.covariance[1], 0.0, "its covariance with the other");
    assert!(fitted.anderson_darling[0].is_none());
    assert!(fitted.anderson_darling[1].is_some());
    assert!(anderson_darling(&[0.0035; 12]).is_none());
}

#[test]
fn the_sample_index_of_a_samples_file_is_not_fitted() {
    let dir = std::env::temp_dir().join(format!("rvtol-fit-index-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let samples = dir.join("s.csv");
    // A scenario of variables only: a part's columns (`carrier.du`) are fitted with --part.
    let scenario = common::workspace_dir().join("scenarios/allocation-linear.json");
    let out = run_rvtol(&[
        "run",
        scenario.to_str().unwrap(),
        "--samples",
        "40",
        "--quiet",
        "--samples-out",
        samples.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run_rvtol(&["fit", samples.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fragment: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let names: Vec<&str> = fragment["variables"]
        .as_array()
        .expect("variables")
        .iter()
        .map(|v| v["name"].as_str().expect("name"))
        .collect();
    assert!(!names.contains(&"sample"), "{names:?}");
    assert!(names.contains(&"x1"), "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The one stderr line of a refused `fit` (exit 2, nothing on stdout, no panic).
fn refused(out: &std::process::Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let line = stderr.strip_suffix('\n').unwrap_or(&stderr);
    assert!(
        !line.contains('\n') && line.starts_with("error: "),
        "one line: {stderr}"
    );
    line.to_string()
}

#[test]
fn what_fit_prints_validates_or_it_refuses_naming_the_column() {
    let dir = std::env::temp_dir().join(format!("rvtol-fit-valid-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("m.csv");
    let fit_of = |text: &str, part: Option<&str>| {
        std::fs::write(&file, text).expect("write");
        let mut args = vec!["fit", file.to_str().unwrap()];
        args.extend(part.iter().flat_map(|p| ["--part", *p]));
        run_rvtol(&args)
    };
    let six = "du,dv,dw,dalpha,dbeta,dgamma";
    for (text, part, needle) in [
        (
            "a,b\n1e200,1\n2,2\n3,1\n",
            None,
            "column 'a': its values are too large for a mean and a variance",
        ),
        (
            "a,b\n1e7,1\n2e7,2\n3e7,1\n",
            None,
            "column 'a': fitted distribution.normal.mean: 2e7 is outside ±1e6",
        ),
        (
            ",b\n1,2\n2,1\n3,3\n",
            None,
            "column 1 (no heading): a variable needs a name",
        ),
        (
            "a,b c\n1,2\n2,1\n3,3\n",
            None,
            "column 'b c': \"b c\" is not a variable name",
        ),
        (
            "a,d.e\n1,2\n2,1\n3,3\n",
            None,
            "column 'd.e': \"d.e\" is not a variable name",
        ),
        (
            "a,carrier.du [mm]\n1,2\n2,1\n3,3\n",
            None,
            "(a part's component: fit the part with --part carrier)",
        ),
        (
            "a [furlong],b\n1,2\n2,1\n3,3\n",
            None,
            "column 'a [furlong]': \"furlong\" is not a unit rvtol knows",
        ),
        (
            "du [furlong],dv [furlong],dw [furlong],dalpha,dbeta,dgamma\n1,0,0,0,0,0\n2,1,0,0,0,0\n0,0,1,1,0,0\n",
            Some("c"),
            "column 'du [furlong]': unit: \"furlong\" is not a unit of length rvtol knows",
        ),
        (
            &format!("{six}\n1e7,0,0,0,0,0\n2e7,1,0,0,0,0\n0,0,1,1,0,0\n"),
            Some("c"),
            "column 'du': fitted mean[0]: 1e7 is outside ±1e6",
        ),
    ] {
        let line = refused(&fit_of(text, part));
        assert!(line.contains(needle), "{text:?}: {line}");
    }
    // A refused fit prints no diagnostics before its error (the columns left out of a
    // part), and none after.
    let line = refused(&fit_of(
        "serial,carrier.du,carrier.dv,carrier.dw,carrier.dalpha,carrier.dbeta,carrier.dgamma\n1,0,0,0,0,0,x\n2,1,0,0,0,0,0\n",
        Some("carrier"),
    ));
    assert!(line.contains("not a finite number: 'x'"), "{line}");
    // What it prints, pasted into a scenario, validates: variables in µm and a ratio.
    let out = fit_of(
        "gap [µm],ratio [1],plain\n1,0.5,3\n2,0.25,1\n4,0.75,2\n3,0.5,5\n",
        None,
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut scenario: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    scenario["models"] = serde_json::json!([{
        "model": "linear_stack",
        "params": { "coefficients": { "a": 1.0 } },
        "inputs": { "a": "plain" }
    }]);
    let pasted = dir.join("pasted.json");
    std::fs::write(&pasted, scenario.to_string()).expect("write");
    let out = run_rvtol(&["validate", pasted.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}
