//! `rvtol fit`: a normal model of measured parts (one row per part, one column per
//! deviation component), ready to paste into a scenario, with the evidence on whether a
//! normal is the right model.
//!
//! - Mean and covariance. The correlations are shrunk by Ledoit & Wolf's (2004, "A
//!   well-conditioned estimator for large-dimensional covariance matrices", J. Multivariate
//!   Anal. 88) estimator applied to the standardised data, target the identity: R* = δ·I +
//!   (1 − δ)·R with δ = min(1, b̄²/d²), d² = ‖R − I‖²_F, b̄² = (1/n²)·Σ_k ‖y_k y_kᵀ − R‖²_F
//!   = (1/n²)·(Σ_k (y_kᵀy_k)² − n‖R‖²_F). Standardising first keeps the estimator
//!   independent of the units (a part's mm and rad differ by orders of magnitude), leaves
//!   every variance at its sample value (n − 1 divisor) and pulls only the correlations
//!   towards 0, by more when the sample is small; for n ≤ p the sample matrix is singular
//!   and the shrunk one is not. Σ = D·R*·D, D the sample standard deviations.
//! - Positive semi-definite repair: eigenvalues below 0 (rounding; a constant column) are
//!   set to 0 and the largest change of an entry reported.
//! - Normality. Per component Anderson–Darling's A² with μ and σ estimated, A*² = A²(1 +
//!   0.75/n + 2.25/n²), p-value from D'Agostino & Stephens (1986, "Goodness-of-Fit
//!   Techniques", Table 4.9), for n ≥ 8. Jointly Mardia's (1970, Biometrika 57) skewness
//!   b₁,p (n·b₁,p/6 ~ χ² with p(p + 1)(p + 2)/6 degrees of freedom) and kurtosis b₂,p
//!   ((b₂,p − p(p + 2))/√(8p(p + 2)/n) ~ N(0, 1), two-sided), when the sample covariance is
//!   non-singular and at most [`MARDIA_MAX_PARTS`] parts are given.
//!   Why not statrs' `stats_tests::anderson_darling` (statrs is a dependency): it tests
//!   against a distribution the caller passes, with the same A*² and the same D'Agostino &
//!   Stephens branches, but takes ln(1 − F(x)) directly, which becomes ln 0 = −∞ for a
//!   part beyond about 8σ (here ln Φ(−z), exact in that tail); sorts with
//!   `partial_cmp().unwrap()` (a panic on NaN, here `total_cmp`); has no n ≥ 8 floor and no
//!   cut where the last branch's quadratic turns upward (A* ≥ 153, here p = 0). Switching
//!   would change the printed statistics in the last bits and lose those guards; the 25
//!   lines stay.
//! - What is printed validates ([`check_fragment`]): the fragment, pasted into a scenario,
//!   loads as `rvtol validate` loads it, or the fit is refused with one line naming the
//!   column (its heading) the problem comes from: a heading that is no variable name, a
//!   unit rvtol does not know, values too large for a variance or for a scenario's range.

use nalgebra::{DMatrix, SymmetricEigen};

use rvtol_engine::scenario::{units, Scenario};
use serde_json::{json, Value};
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

/// A test statistic and its p-value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Test {
    /// The statistic (A*², n·b₁/6, or the kurtosis z).
    pub statistic: f64,
    /// Its p-value.
    pub p_value: f64,
}

/// The fitted normal model and its diagnostics.
#[derive(Debug, Clone)]
pub struct Fit {
    /// Measured parts (rows).
    pub n: usize,
    /// Component names, in column order.
    pub names: Vec<String>,
    /// Sample means.
    pub mean: Vec<f64>,
    /// The shrunk, repaired covariance (p × p, row-major).
    pub covariance: Vec<f64>,
    /// Ledoit–Wolf's δ on the correlations (0: the sample correlations, 1: none).
    pub shrinkage: f64,
    /// The largest change of an entry by the positive semi-definite repair, when any.
    pub repair: Option<f64>,
    /// Anderson–Darling per component (None below 8 parts or for a constant column).
    pub anderson_darling: Vec<Option<Test>>,
    /// Mardia's multivariate skewness and kurtosis (None when the sample covariance is
    /// singular, p = 1, or more than [`MARDIA_MAX_PARTS`] parts are given).
    pub mardia: Option<(Test, Test)>,
}

impl Fit {
    /// Covariance entry (i, j).
    pub fn cov(&self, i: usize, j: usize) -> f64 {
        self.covariance[i * self.names.len() + j]
    }

    /// Standard deviation of component i.
    pub fn sd(&self, i: usize) -> f64 {
        self.cov(i, i).max(0.0).sqrt()
    }
}

/// Most columns one fit takes. The fragment holds a correlation for every pair of columns
/// and the repair an eigen-decomposition of the p × p covariance, both growing with p²
/// (p³ for the time): 3,000 columns took 41 s, 6.2 GB and wrote 480 MB; 500 write about
/// 14 MB. More columns than that are no longer a fragment a person pastes.
pub const MAX_FIT_COLUMNS: usize = 500;

/// Fits `rows` (n rows of `names.len()` finite values), at most [`MAX_FIT_COLUMNS`].
pub fn fit(names: &[String], rows: &[Vec<f64>]) -> Result<Fit, String> {
    let p = names.len();
    let n = rows.len();
    if p == 0 {
        return Err("no columns".into());
    }
    if p > MAX_FIT_COLUMNS {
        return Err(format!(
            "{} columns to fit, more than the {MAX_FIT_COLUMNS} rvtol fit takes (the fragment holds a correlation for every pair of columns, {} pairs here): fit the columns that vary together a group at a time (one part with --part, or a file per group)",
            rvtol_engine::format::group_thousands(p as u64),
            rvtol_engine::format::group_thousands((p * (p - 1) / 2) as u64)
        ));
    }
    if n < 2 {
        return Err(format!(
            "{n} row: a covariance needs at least 2 measured parts"
        ));
    }
    let nf = n as f64;
    // A constant column's mean is its value and its spread exactly 0 (the sum's rounding
    // would give a mean in the last digits beside it and a spread of 10⁻¹⁸).
    let constant: Vec<bool> = (0..p)
        .map(|j| rows.iter().all(|r| r[j] == rows[0][j]))
        .collect();
    let mean: Vec<f64> = (0..p)
        .map(|j| {
            if constant[j] {
                rows[0][j]
            } else {
                rows.iter().map(|r| r[j]).sum::<f64>() / nf
            }
        })
        .collect();
    // Sample standard deviations (n − 1) and the standardised data (1/n scaling, so that
    // R = YᵀY/n has a unit diagonal).
    let centred = DMatrix::from_fn(n, p, |k, j| rows[k][j] - mean[j]);
    let ss: Vec<f64> = (0..p).map(|j| centred.column(j).norm_squared()).collect();
    let sd: Vec<f64> = ss.iter().map(|s| (s / (nf - 1.0)).sqrt()).collect();
    let scale: Vec<f64> = ss.iter().map(|s| (s / nf).sqrt()).collect();
    let y = DMatrix::from_fn(n, p, |k, j| {
        if scale[j] > 0.0 {
            centred[(k, j)] / scale[j]
        } else {
            0.0
        }
    });
    let mut r = y.transpose() * &y / nf;
    for j in 0..p {
        // A constant column keeps a unit diagonal (its variance is 0 in Σ anyway).
        r[(j, j)] = 1.0;
    }
    let identity = DMatrix::<f64>::identity(p, p);
    let d2 = (&r - &identity).norm_squared();
    let row_norms: f64 = y.row_iter().map(|row| row.norm_squared().powi(2)).sum();
    let b2_bar = ((row_norms - nf * r.norm_squared()) / (nf * nf)).max(0.0);
    let shrinkage = if d2 > 0.0 {
        (b2_bar / d2).min(1.0)
    } else {
        0.0
    };
    let shrunk = &identity * shrinkage + &r * (1.0 - shrinkage);
    let mut sigma = DMatrix::from_fn(p, p, |i, j| sd[i] * sd[j] * shrunk[(i, j)]);
    // Positive semi-definite repair.
    let eigen = SymmetricEigen::new(sigma.clone());
    let mut repair = None;
    if eigen.eigenvalues.iter().any(|&l| l < 0.0) {
        let clipped = eigen.eigenvalues.map(|l| l.max(0.0));
        let repaired =
            &eigen.eigenvectors * DMatrix::from_diagonal(&clipped) * eigen.eigenvectors.transpose();
        let repaired = (&repaired + repaired.transpose()) * 0.5;
        let change = (&repaired - &sigma).amax();
        repair = Some(change);
        sigma = repaired;
    }
    let anderson_darling = (0..p)
        .map(|j| anderson_darling(&rows.iter().map(|r| r[j]).collect::<Vec<_>>()))
        .collect();
    // Mardia on the columns that vary (a constant one makes the covariance singular).
    let varying: Vec<usize> = (0..p).filter(|&j| ss[j] > 0.0).collect();
    let mardia = mardia(&centred.select_columns(varying.iter()));
    Ok(Fit {
        n,
        names: names.to_vec(),
        mean,
        covariance: sigma.transpose().iter().copied().collect(),
        shrinkage,
        repair,
        anderson_darling,
        mardia,
    })
}

/// Anderson–Darling A*² and its p-value for a normal with estimated μ and σ (module docs).
pub fn anderson_darling(values: &[f64]) -> Option<Test> {
    let n = values.len();
    if n < 8 || values.iter().all(|&v| v == values[0]) {
        return None;
    }
    let nf = n as f64;
    let mean = values.iter().sum::<f64>() / nf;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (nf - 1.0)).sqrt();
    if sd.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mut z: Vec<f64> = values.iter().map(|v| (v - mean) / sd).collect();
    z.sort_by(f64::total_cmp);
    let normal = Normal::standard();
    // ln Φ(z) and ln(1 − Φ(z)) = ln Φ(−z), each from the side that keeps its precision.
    let ln_cdf = |x: f64| normal.cdf(x).max(f64::MIN_POSITIVE).ln();
    let sum: f64 = (0..n)
        .map(|i| (2 * i + 1) as f64 * (ln_cdf(z[i]) + ln_cdf(-z[n - 1 - i])))
        .sum();
    let a2 = -nf - sum / nf;
    let a = a2 * (1.0 + 0.75 / nf + 2.25 / (nf * nf));
    // The last branch's quadratic has its minimum at A* = 5.709/(2·0.0186) = 153.5 (p about
    // e^−437) and rises beyond it, where the fit no longer holds: p is 0 there.
    let p = if a >= 153.0 {
        0.0
    } else if a >= 0.6 {
        (1.2937 - 5.709 * a + 0.0186 * a * a).exp()
    } else if a >= 0.34 {
        (0.9177 - 4.279 * a - 1.38 * a * a).exp()
    } else if a >= 0.2 {
        1.0 - (-8.318 + 42.796 * a - 59.938 * a * a).exp()
    } else {
        1.0 - (-13.436 + 101.14 * a - 223.73 * a * a).exp()
    };
    Some(Test {
        statistic: a,
        p_value: p.clamp(0.0, 1.0),
    })
}

/// Mardia's skewness and kurtosis tests of the centred rows (module docs).
/// Most parts Mardia's skewness is computed for: it sums over all n² pairs of parts
/// (O(n²·p) time, O(n·p) memory; 20,000 parts take about a second).
pub const MARDIA_MAX_PARTS: usize = 20_000;

fn mardia(centred: &DMatrix<f64>) -> Option<(Test, Test)> {
    let (n, p) = centred.shape();
    if p < 2 || n <= p || n > MARDIA_MAX_PARTS {
        return None;
    }
    let nf = n as f64;
    let s = centred.transpose() * centred / nf;
    let cholesky = s.cholesky()?;
    // Rows whitened: g_ij = w_iᵀ w_j with w = L⁻¹ d.
    let w = cholesky.l().solve_lower_triangular(&centred.transpose())?;
    // Σ_ij g_ij³ over the pairs, never holding the n × n matrix.
    let mut b1 = 0.0;
    let mut b2 = 0.0;
    for i in 0..n {
        let wi = w.column(i);
        let gii = wi.dot(&wi);
        b1 += gii.powi(3);
        b2 += gii * gii;
        for j in i + 1..n {
            b1 += 2.0 * wi.dot(&w.column(j)).powi(3);
        }
    }
    let b1 = b1 / (nf * nf);
    let b2 = b2 / nf;
    let pf = p as f64;
    let dof = pf * (pf + 1.0) * (pf + 2.0) / 6.0;
    let skew = nf * b1 / 6.0;
    let skew_p = 1.0 - ChiSquared::new(dof).ok()?.cdf(skew);
    let kurt = (b2 - pf * (pf + 2.0)) / (8.0 * pf * (pf + 2.0) / nf).sqrt();
    let kurt_p = 2.0 * Normal::standard().cdf(-kurt.abs());
    Some((
        Test {
            statistic: skew,
            p_value: skew_p,
        },
        Test {
            statistic: kurt,
            p_value: kurt_p,
        },
    ))
}

/// The components of a part, in a part's column order.
pub const PART_COMPONENTS: [&str; 6] = ["du", "dv", "dw", "dalpha", "dbeta", "dgamma"];

fn p_text(test: Option<Test>) -> String {
    match test {
        Some(t) => format!("{:.3}", t.p_value),
        None => "n/a".into(),
    }
}

/// The diagnostics in one sentence, for the fragment's description.
pub fn summary(fit: &Fit, source: &str) -> String {
    let ad: Vec<String> = fit
        .names
        .iter()
        .zip(&fit.anderson_darling)
        .map(|(name, t)| format!("{name} {}", p_text(*t)))
        .collect();
    let mut text = format!(
        "fitted by rvtol fit from {source}: {} measured parts; Ledoit–Wolf shrinkage of the correlations δ = {:.3}",
        fit.n, fit.shrinkage
    );
    if let Some(change) = fit.repair {
        text.push_str(&format!(
            "; positive semi-definite repair changed an entry by at most {change:.3e}"
        ));
    }
    text.push_str(&format!(
        "; normality, Anderson–Darling p: {}",
        ad.join(", ")
    ));
    match fit.mardia {
        Some((skew, kurt)) => text.push_str(&format!(
            "; Mardia skewness p {:.3}, kurtosis p {:.3}",
            skew.p_value, kurt.p_value
        )),
        None => text
            .push_str("; Mardia n/a (too few parts, more than 20,000, or a singular covariance)"),
    }
    text.push_str(" (p < 0.05: a normal is doubtful for that component)");
    text
}

/// The scenario fragment: one part (`part` named, the six components in order; with
/// `units` when its columns are headed in other units than mm and rad) or one normal
/// variable per column with their correlations.
pub fn fragment(fit: &Fit, part: Option<&str>, units: &[Option<String>], source: &str) -> Value {
    let p = fit.names.len();
    if let Some(name) = part {
        let description = summary(fit, source);
        let covariance: Vec<Vec<f64>> = (0..p)
            .map(|i| (0..p).map(|j| fit.cov(i, j)).collect())
            .collect();
        let mut part = json!({
            "name": name,
            "description": description,
            "mean": fit.mean,
            "covariance": covariance,
        });
        // Columns headed in other units than mm and rad: the part says so (`units`).
        let (translation, rotation) = (units.first(), units.get(3));
        let mut given = serde_json::Map::new();
        if let Some(Some(unit)) = translation.filter(|u| u.as_deref() != Some("mm")) {
            given.insert("translation".into(), json!(unit));
        }
        if let Some(Some(unit)) = rotation.filter(|u| u.as_deref() != Some("rad")) {
            given.insert("rotation".into(), json!(unit));
        }
        if !given.is_empty() {
            part["units"] = Value::Object(given);
        }
        return json!({ "parts": [part] });
    }
    let joint = match fit.mardia {
        Some((skew, kurt)) => format!(
            "jointly: Ledoit–Wolf shrinkage of the correlations δ = {:.3}, Mardia skewness p {:.3}, kurtosis p {:.3}",
            fit.shrinkage, skew.p_value, kurt.p_value
        ),
        None => format!(
            "jointly: Ledoit–Wolf shrinkage of the correlations δ = {:.3}",
            fit.shrinkage
        ),
    };
    let variables: Vec<Value> = (0..p)
        .map(|i| {
            let mut v = json!({
                "name": fit.names[i],
                "distribution": { "normal": { "mean": fit.mean[i], "sd": fit.sd(i) } },
            });
            if let Some(unit) = &units[i] {
                v["unit"] = json!(unit);
            }
            v["description"] = json!(format!(
                "fitted by rvtol fit from {source}, {} measured parts; Anderson–Darling p {}; {}",
                fit.n,
                p_text(fit.anderson_darling[i]),
                joint
            ));
            v
        })
        .collect();
    let mut correlations = Vec::new();
    for i in 0..p {
        for j in i + 1..p {
            let (si, sj) = (fit.sd(i), fit.sd(j));
            if si > 0.0 && sj > 0.0 {
                let rho = (fit.cov(i, j) / (si * sj)).clamp(-1.0, 1.0);
                if rho != 0.0 {
                    correlations
                        .push(json!({ "between": [fit.names[i], fit.names[j]], "rho": rho }));
                }
            }
        }
    }
    json!({ "variables": variables, "correlations": correlations })
}

/// Units a fitted variable may carry: those a scenario converts (lengths, angles) and `1`
/// (a ratio), the units the models' inputs take.
fn unit_known(unit: &str) -> bool {
    unit == "1" || units::is_known(unit)
}

/// Checks that `fragment` (of [`fragment`], for `fit` and `part`) is what a scenario takes:
/// every fitted figure finite, every variable name and unit valid, and the fragment, pasted
/// into a scenario beside a model that reads none of it, loading as `rvtol validate` loads
/// a scenario. The error is one line naming the column by its heading (`headings`, in the
/// fit's column order, as the file writes them: `name [unit]`).
pub fn check_fragment(
    fit: &Fit,
    fragment: &Value,
    part: Option<&str>,
    headings: &[String],
) -> Result<(), String> {
    let p = fit.names.len();
    let column = |i: usize| match headings.get(i) {
        Some(h) if !h.is_empty() => format!("column '{h}'"),
        _ => format!("column {} (no heading)", i + 1),
    };
    for i in 0..p {
        if !(fit.mean[i].is_finite() && fit.cov(i, i).is_finite()) {
            return Err(format!(
                "{}: its values are too large for a mean and a variance (they overflow): give them in a smaller unit",
                column(i)
            ));
        }
    }
    for i in 0..p {
        for j in i + 1..p {
            if !fit.cov(i, j).is_finite() {
                return Err(format!(
                    "{} and {}: their covariance is not a finite number: give the values in a smaller unit",
                    column(i),
                    column(j)
                ));
            }
        }
    }
    if part.is_none() {
        for (i, variable) in fragment["variables"]
            .as_array()
            .into_iter()
            .flatten()
            .enumerate()
        {
            let name = variable["name"].as_str().unwrap_or("");
            if name.is_empty() {
                return Err(format!(
                    "{}: a variable needs a name: head the column with one",
                    column(i)
                ));
            }
            if !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                let hint = match name.split_once('.') {
                    Some((part, component)) if PART_COMPONENTS.contains(&component) => {
                        format!(" (a part's component: fit the part with --part {part})")
                    }
                    _ => String::new(),
                };
                return Err(format!(
                    "{}: {name:?} is not a variable name: use only letters, digits, '_' and '-'{hint}",
                    column(i)
                ));
            }
            if let Some(unit) = variable["unit"].as_str() {
                if !unit_known(unit) {
                    return Err(format!(
                        "{}: {unit:?} is not a unit rvtol knows ({}; 1 for a ratio): head the column with one of them, or none",
                        column(i),
                        units::known()
                    ));
                }
            }
        }
    }
    // The fragment in a scenario whose one model binds a constant: it must load.
    let mut scenario = fragment.clone();
    scenario["name"] = json!("rvtol-fit-check");
    scenario["models"] = json!([{
        "model": "linear_stack",
        "params": { "output": "rvtol-fit-check", "coefficients": { "x": 0.0 } },
        "inputs": { "x": 0.0 }
    }]);
    let Err(err) = Scenario::from_json(&scenario.to_string(), "rvtol-fit-check") else {
        return Ok(());
    };
    // The problem's JSON path names the column it comes from.
    let indexed = |prefix: &str| -> Option<(usize, String)> {
        let rest = err.path.strip_prefix(prefix)?;
        let (index, rest) = rest.split_once(']')?;
        Some((
            index.parse().ok()?,
            rest.trim_start_matches('.').to_string(),
        ))
    };
    let located = if let Some((i, what)) = indexed("variables[") {
        format!("{}: fitted {what}", column(i))
    } else if let Some((k, _)) = indexed("correlations[") {
        let pair = &fragment["correlations"][k]["between"];
        let position = |end: usize| {
            let name = pair[end].as_str().unwrap_or("");
            fit.names.iter().position(|n| n == name).unwrap_or(p)
        };
        format!(
            "{} and {}: fitted correlation",
            column(position(0)),
            column(position(1))
        )
    } else if let Some(rest) = err.path.strip_prefix("parts[0].") {
        let index = |key: &str| {
            rest.strip_prefix(key)
                .and_then(|r| r.strip_prefix('['))
                .and_then(|r| r.split(']').next())
                .and_then(|i| i.parse::<usize>().ok())
        };
        match (index("mean"), index("covariance")) {
            (Some(i), _) | (_, Some(i)) if i < p => format!("{}: fitted {rest}", column(i)),
            _ if rest == "units.translation" => format!("{}: unit", column(0)),
            _ if rest == "units.rotation" => format!("{}: unit", column(3)),
            _ => format!("part {}: fitted {rest}", part.unwrap_or("")),
        }
    } else {
        format!("the fitted fragment: {}", err.path)
    };
    Err(format!("{located}: {}", err.message))
}

#[cfg(test)]
mod fragment_tests {
    use super::*;

    fn checked(names: &[&str], units: &[Option<&str>], rows: &[Vec<f64>]) -> Result<(), String> {
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        let units: Vec<Option<String>> = units.iter().map(|u| u.map(String::from)).collect();
        let headings: Vec<String> = names
            .iter()
            .zip(&units)
            .map(|(n, u)| match u {
                Some(u) => format!("{n} [{u}]"),
                None => n.clone(),
            })
            .collect();
        let fitted = fit(&names, rows).expect("a fit");
        check_fragment(
            &fitted,
            &fragment(&fitted, None, &units, "m.csv"),
            None,
            &headings,
        )
    }

    #[test]
    fn a_fragment_a_scenario_would_refuse_is_refused_naming_the_column() {
        let rows = vec![vec![1.0, 2.0], vec![2.0, 1.0], vec![3.0, 3.0]];
        assert!(checked(&["a", "b"], &[Some("µm"), Some("1")], &rows).is_ok());
        let err = checked(&["a", "b c"], &[None, None], &rows).unwrap_err();
        assert!(
            err.starts_with("column 'b c': \"b c\" is not a variable name"),
            "{err}"
        );
        let err = checked(&["a", "b"], &[Some("furlong"), None], &rows).unwrap_err();
        assert!(
            err.starts_with("column 'a [furlong]': \"furlong\" is not a unit"),
            "{err}"
        );
        let huge = vec![vec![1e200, 1.0], vec![2.0, 2.0], vec![3.0, 1.0]];
        let err = checked(&["a", "b"], &[None, None], &huge).unwrap_err();
        assert!(
            err.starts_with("column 'a': its values are too large"),
            "{err}"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn more_columns_than_a_fragment_holds_are_refused_before_any_work() {
        let columns = MAX_FIT_COLUMNS + 1;
        let names: Vec<String> = (0..columns).map(|j| format!("c{j}")).collect();
        let rows: Vec<Vec<f64>> = (0..3)
            .map(|k| (0..columns).map(|j| (k * columns + j) as f64).collect())
            .collect();
        let started = std::time::Instant::now();
        let err = fit(&names, &rows).unwrap_err();
        assert_eq!(
            err,
            "501 columns to fit, more than the 500 rvtol fit takes (the fragment holds a correlation for every pair of columns, 125,250 pairs here): fit the columns that vary together a group at a time (one part with --part, or a file per group)"
        );
        assert!(started.elapsed().as_secs_f64() < 1.0);
        assert!(fit(
            &names[..MAX_FIT_COLUMNS],
            &[
                rows[0][..MAX_FIT_COLUMNS].to_vec(),
                rows[1][..MAX_FIT_COLUMNS].to_vec()
            ]
        )
        .is_ok());
    }
}
