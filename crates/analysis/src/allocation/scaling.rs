//! A scenario with some tolerances scaled: edits the scenario's JSON so that the scaled
//! scenario is an ordinary scenario file (it can be written out, validated and run).
//!
//! Scaling source k by s_k (its tolerance t_k → s_k·t_k) scales its spread about its
//! centre and keeps its shape:
//! - tolerance band [l, u] with Cp and mean shift δ: centre c = (l + u)/2 stays,
//!   half-width and δ scale by s (σ = (u − l)/(6·Cp) scales by s, the shift keeps its
//!   fraction of the band);
//! - uniform [l, u]: about its centre; triangular (l, m, u): about its mode;
//! - normal (μ, σ): σ → s·σ; truncated normal: σ and both bounds' distances from μ;
//! - folded normal: its signed band as a tolerance band; Rayleigh: its upper tolerance
//!   (σ scales by s); lognormal: the spread of the log, upper → median·(upper/median)^s;
//! - a part's tolerance band Δτ → s·Δτ (001 Eq. 9–12 scale every σ and the Eq. 11
//!   bound by s, so the acceptance rate is unchanged); a part's standard deviations → s·σ,
//!   its covariance → s²·Σ.
//!
//! Correlations between sources are coefficients, so a covariance between sources j and
//! k scales by s_j·s_k.

use serde_json::Value;

use rvtol_engine::scenario::allocation::{AllocatableSource, ToleranceKind};
use rvtol_engine::scenario::ScenarioError;

/// Returns `document` with each source's tolerance scaled by the matching factor, and the
/// `allocation` section removed when `keep_allocation` is false.
pub fn scaled_document(
    document: &Value,
    sources: &[AllocatableSource],
    factors: &[f64],
    keep_allocation: bool,
) -> Result<Value, ScenarioError> {
    assert_eq!(sources.len(), factors.len(), "one factor per source");
    let mut scaled = document.clone();
    if !keep_allocation {
        if let Some(map) = scaled.as_object_mut() {
            map.remove("allocation");
        }
    }
    for (source, &s) in sources.iter().zip(factors) {
        let (collection, index) = locate(&source.source.path)?;
        let node = scaled
            .get_mut(collection)
            .and_then(|c| c.get_mut(index))
            .ok_or_else(|| missing(&source.source.path))?;
        scale_node(node, source.source.kind, s).ok_or_else(|| missing(&source.source.path))?;
    }
    Ok(scaled)
}

fn missing(path: &str) -> ScenarioError {
    ScenarioError::new(path, "changed since it was validated")
}

/// `parts[3]` → ("parts", 3).
fn locate(path: &str) -> Result<(&str, usize), ScenarioError> {
    let (collection, rest) = path.split_once('[').ok_or_else(|| missing(path))?;
    let index = rest
        .strip_suffix(']')
        .and_then(|i| i.parse().ok())
        .ok_or_else(|| missing(path))?;
    Ok((collection, index))
}

fn number(node: &Value, key: &str) -> Option<f64> {
    node.get(key)?.as_f64()
}

fn set(node: &mut Value, key: &str, value: f64) -> Option<()> {
    *node.get_mut(key)? = serde_json::Number::from_f64(value)
        .map(Value::Number)
        .unwrap_or(Value::Null);
    Some(())
}

/// Scales the `[l, u]` of `node` about `centre`.
fn scale_about(node: &mut Value, centre: f64, s: f64) -> Option<()> {
    let (l, u) = (number(node, "lower")?, number(node, "upper")?);
    set(node, "lower", centre - s * (centre - l))?;
    set(node, "upper", centre + s * (u - centre))
}

fn scale_node(node: &mut Value, kind: ToleranceKind, s: f64) -> Option<()> {
    match kind {
        ToleranceKind::PartToleranceBand => {
            let band = node.get_mut("tolerance_band")?;
            let delta_tau = number(band, "delta_tau_mm")?;
            set(band, "delta_tau_mm", s * delta_tau)
        }
        ToleranceKind::PartCovariance => {
            for row in node.get_mut("covariance")?.as_array_mut()? {
                for entry in row.as_array_mut()? {
                    let v = entry.as_f64()?;
                    *entry = Value::from(s * s * v);
                }
            }
            Some(())
        }
        ToleranceKind::PartSd => {
            for entry in node.get_mut("sd")?.as_array_mut()? {
                let v = entry.as_f64()?;
                *entry = Value::from(s * v);
            }
            Some(())
        }
        ToleranceKind::VariableToleranceBand => {
            let band = node.get_mut("distribution")?.get_mut("tolerance_band")?;
            let centre = 0.5 * (number(band, "lower")? + number(band, "upper")?);
            scale_about(band, centre, s)?;
            if let Some(shift) = number(band, "mean_shift") {
                set(band, "mean_shift", s * shift)?;
            }
            Some(())
        }
        ToleranceKind::VariableNormal => {
            let normal = node.get_mut("distribution")?.get_mut("normal")?;
            let sd = number(normal, "sd")?;
            set(normal, "sd", s * sd)
        }
        ToleranceKind::VariableUniform => {
            let uniform = node.get_mut("distribution")?.get_mut("uniform")?;
            let centre = 0.5 * (number(uniform, "lower")? + number(uniform, "upper")?);
            scale_about(uniform, centre, s)
        }
        ToleranceKind::VariableTriangular => {
            let triangular = node.get_mut("distribution")?.get_mut("triangular")?;
            let mode = number(triangular, "mode")?;
            scale_about(triangular, mode, s)
        }
        ToleranceKind::VariableTruncatedNormal => {
            let truncated = node.get_mut("distribution")?.get_mut("truncated_normal")?;
            let (mean, sd) = (number(truncated, "mean")?, number(truncated, "sd")?);
            set(truncated, "sd", s * sd)?;
            scale_about(truncated, mean, s)
        }
        ToleranceKind::VariableFoldedNormal => {
            let band = node.get_mut("distribution")?.get_mut("folded_normal")?;
            let centre = 0.5 * (number(band, "lower")? + number(band, "upper")?);
            scale_about(band, centre, s)?;
            if let Some(shift) = number(band, "mean_shift") {
                set(band, "mean_shift", s * shift)?;
            }
            Some(())
        }
        ToleranceKind::VariableRayleigh => {
            let rayleigh = node.get_mut("distribution")?.get_mut("rayleigh")?;
            let upper = number(rayleigh, "upper")?;
            set(rayleigh, "upper", s * upper)
        }
        ToleranceKind::VariableLognormal => {
            // σ of the log → s·σ about the median: upper → median·(upper/median)^s.
            let lognormal = node.get_mut("distribution")?.get_mut("lognormal")?;
            let (median, upper) = (number(lognormal, "median")?, number(lognormal, "upper")?);
            set(lognormal, "upper", median * (upper / median).powf(s))
        }
        ToleranceKind::VariableEmpirical => {
            // Every value moves to m + s·(x − m) about the values' mean m, so the
            // spread (and a given bandwidth) scales by s and the mean stays.
            let empirical = node.get_mut("distribution")?.get_mut("empirical")?;
            let values = empirical.get_mut("values")?.as_array_mut()?;
            let numbers: Vec<f64> = values.iter().map(Value::as_f64).collect::<Option<_>>()?;
            let mean = numbers.iter().sum::<f64>() / numbers.len().max(1) as f64;
            for (entry, x) in values.iter_mut().zip(numbers) {
                *entry = serde_json::Number::from_f64(mean + s * (x - mean))
                    .map(Value::Number)
                    .unwrap_or(Value::Null);
            }
            if let Some(h) = number(empirical, "bandwidth") {
                set(empirical, "bandwidth", s * h)?;
            }
            Some(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rvtol_engine::scenario::allocation::{CostModel, ToleranceSource};

    fn source(path: &str, kind: ToleranceKind) -> AllocatableSource {
        AllocatableSource {
            source: ToleranceSource {
                name: "x".into(),
                path: path.into(),
                kind,
                current: 1.0,
                unit: String::new(),
            },
            min: 0.1,
            max: 10.0,
            cost: CostModel::Reciprocal { a: 0.0, b: 1.0 },
            cost_models: vec![CostModel::Reciprocal { a: 0.0, b: 1.0 }],
        }
    }

    #[test]
    fn each_kind_scales_about_its_centre() {
        let document: Value = serde_json::from_str(
            r#"{
              "parts": [
                { "name": "a", "tolerance_band": { "delta_tau_mm": 0.004, "length_mm": 50 } },
                { "name": "b", "sd": [1, 2, 3, 4, 5, 6] },
                { "name": "c", "covariance": [[4, 1], [1, 9]] }
              ],
              "variables": [
                { "name": "d", "distribution": { "tolerance_band": { "lower": 9, "upper": 11, "cp": 1.33, "mean_shift": 0.2 } } },
                { "name": "e", "distribution": { "normal": { "mean": 5, "sd": 0.5 } } },
                { "name": "f", "distribution": { "uniform": { "lower": 1, "upper": 3 } } },
                { "name": "g", "distribution": { "triangular": { "lower": 0, "mode": 1, "upper": 4 } } },
                { "name": "h", "distribution": { "truncated_normal": { "mean": 0, "sd": 1, "lower": -2, "upper": 3 } } },
                { "name": "i", "distribution": { "empirical": { "values": [1, 2, 6], "bandwidth": 0.5 } } }
              ],
              "allocation": {}
            }"#,
        )
        .unwrap();
        let sources = [
            source("parts[0]", ToleranceKind::PartToleranceBand),
            source("parts[1]", ToleranceKind::PartSd),
            source("parts[2]", ToleranceKind::PartCovariance),
            source("variables[0]", ToleranceKind::VariableToleranceBand),
            source("variables[1]", ToleranceKind::VariableNormal),
            source("variables[2]", ToleranceKind::VariableUniform),
            source("variables[3]", ToleranceKind::VariableTriangular),
            source("variables[4]", ToleranceKind::VariableTruncatedNormal),
            source("variables[5]", ToleranceKind::VariableEmpirical),
        ];
        let scaled = scaled_document(&document, &sources, &[0.5; 9], false).unwrap();
        assert!(scaled.get("allocation").is_none());
        let parts = &scaled["parts"];
        assert_eq!(parts[0]["tolerance_band"]["delta_tau_mm"], 0.002);
        assert_eq!(parts[0]["tolerance_band"]["length_mm"], 50);
        assert_eq!(
            parts[1]["sd"],
            serde_json::json!([0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
        );
        assert_eq!(
            parts[2]["covariance"],
            serde_json::json!([[1.0, 0.25], [0.25, 2.25]])
        );
        let v = &scaled["variables"];
        let band = &v[0]["distribution"]["tolerance_band"];
        assert_eq!(
            (band["lower"].as_f64(), band["upper"].as_f64()),
            (Some(9.5), Some(10.5))
        );
        assert_eq!(
            (band["cp"].as_f64(), band["mean_shift"].as_f64()),
            (Some(1.33), Some(0.1))
        );
        assert_eq!(v[1]["distribution"]["normal"]["sd"], 0.25);
        assert_eq!(v[1]["distribution"]["normal"]["mean"], 5);
        let uniform = &v[2]["distribution"]["uniform"];
        assert_eq!(
            (uniform["lower"].as_f64(), uniform["upper"].as_f64()),
            (Some(1.5), Some(2.5))
        );
        let tri = &v[3]["distribution"]["triangular"];
        assert_eq!(
            (tri["lower"].as_f64(), tri["upper"].as_f64()),
            (Some(0.5), Some(2.5))
        );
        let tn = &v[4]["distribution"]["truncated_normal"];
        assert_eq!(
            (
                tn["sd"].as_f64(),
                tn["lower"].as_f64(),
                tn["upper"].as_f64()
            ),
            (Some(0.5), Some(-1.0), Some(1.5))
        );
        // About the values' mean 3: 1, 2, 6 → 2, 2.5, 4.5; the bandwidth halves too.
        let empirical = &v[5]["distribution"]["empirical"];
        assert_eq!(empirical["values"], serde_json::json!([2.0, 2.5, 4.5]));
        assert_eq!(empirical["bandwidth"], 0.25);
        let kept = scaled_document(&document, &sources[..1], &[2.0], true).unwrap();
        assert!(kept.get("allocation").is_some());
        assert_eq!(kept["parts"][0]["tolerance_band"]["delta_tau_mm"], 0.008);
    }
}
