//! What `rvtol allocate` may change: the scenario's `allocation` section (per error
//! source: the tolerance's bounds and its manufacturing cost model; the levers), compiled
//! with the rest of the scenario so `validate` reports its problems with the others'. What
//! the allocation must reach (`--target`) is rvtol-analysis' `target` module.
//!
//! The tolerance of a source is one number in the source's own terms, so that bounds and
//! cost tables read as a drawing does (scenarios/README.md, docs/models.md §9):
//! - a `tolerance_band` variable: its half-width (the ± limit);
//! - a `uniform` or `triangular` variable: its half-width;
//! - a `normal` or `truncated_normal` variable: 3σ;
//! - a part given by `tolerance_band`: Δτ (001 Eq. 9);
//! - a part given by covariance or standard deviations: the factor on its standard
//!   deviations (1 today).
//!
//! Scaling a tolerance by s scales the source's spread by s about its centre and keeps
//! its shape (Cp, relative mean shift, truncation in σ units, correlations).

use rvtol_deviation::Shown;
use std::collections::BTreeMap;

use serde::Deserialize;

use crate::scenario::ScenarioError;

/// How a source's tolerance is expressed and therefore how it is scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToleranceKind {
    /// `parts[i]` with `tolerance_band`: the tolerance is Δτ.
    PartToleranceBand,
    /// `parts[i]` with `covariance`: the tolerance is a factor on the standard deviations.
    PartCovariance,
    /// `parts[i]` with `sd` (and `correlation`): a factor on the standard deviations.
    PartSd,
    /// `variables[i]` with `tolerance_band`: the half-width of the band.
    VariableToleranceBand,
    /// `variables[i]` with `normal`: 3σ.
    VariableNormal,
    /// `variables[i]` with `uniform`: the half-width.
    VariableUniform,
    /// `variables[i]` with `triangular`: the half-width.
    VariableTriangular,
    /// `variables[i]` with `truncated_normal`: 3σ.
    VariableTruncatedNormal,
    /// `variables[i]` with `folded_normal`: the half-width of the band of the signed
    /// quantity.
    VariableFoldedNormal,
    /// `variables[i]` with `rayleigh`: the upper tolerance (99.865 % quantile at Cp = 1).
    VariableRayleigh,
    /// `variables[i]` with `lognormal`: a factor on the spread of the log.
    VariableLognormal,
    /// `variables[i]` with `empirical`: a factor on the spread of the values about their
    /// mean (and on the bandwidth).
    VariableEmpirical,
}

impl ToleranceKind {
    /// What the tolerance number means, for reports.
    pub fn meaning(self) -> &'static str {
        match self {
            ToleranceKind::PartToleranceBand => "tolerance band Δτ",
            ToleranceKind::PartCovariance | ToleranceKind::PartSd => "factor on the sd",
            ToleranceKind::VariableToleranceBand | ToleranceKind::VariableFoldedNormal => {
                "± band half-width"
            }
            ToleranceKind::VariableRayleigh => "upper tolerance",
            ToleranceKind::VariableLognormal => "factor on the log sd",
            ToleranceKind::VariableEmpirical => "factor on the spread about the mean",
            ToleranceKind::VariableUniform | ToleranceKind::VariableTriangular => "± half-width",
            ToleranceKind::VariableNormal | ToleranceKind::VariableTruncatedNormal => "3σ",
        }
    }
}

/// A part or variable of the scenario, described by its tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct ToleranceSource {
    /// The part or variable name.
    pub name: String,
    /// JSON path of its definition (`parts[0]`, `variables[3]`).
    pub path: String,
    /// How its tolerance is expressed.
    pub kind: ToleranceKind,
    /// Its tolerance in the scenario as written.
    pub current: f64,
    /// Unit of the tolerance ("" for a factor).
    pub unit: String,
}

/// A manufacturing cost model: cost as a function of the tolerance t (in the source's
/// tolerance unit). Every model is non-increasing in t: a looser tolerance never costs
/// more.
#[derive(Debug, Clone, PartialEq)]
pub enum CostModel {
    /// c = a + b / t (Chase & Greenwood 1988, reciprocal cost–tolerance model).
    Reciprocal {
        /// Fixed cost a.
        a: f64,
        /// Coefficient b ≥ 0.
        b: f64,
    },
    /// c = a + b·exp(−rate·t) (Speckhart 1972, exponential cost–tolerance model).
    Exponential {
        /// Fixed cost a.
        a: f64,
        /// Coefficient b ≥ 0.
        b: f64,
        /// Rate > 0, per tolerance unit.
        rate: f64,
    },
    /// Measured points [t, cost], t strictly increasing, cost non-increasing; linear
    /// interpolation between them, no extrapolation.
    Table(Vec<[f64; 2]>),
}

/// The kinds of cost model, as `--cost` names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CostKind {
    /// [`CostModel::Reciprocal`].
    Reciprocal,
    /// [`CostModel::Exponential`].
    Exponential,
    /// [`CostModel::Table`].
    Table,
}

impl CostKind {
    /// Parses `reciprocal`, `exponential` or `table`.
    pub fn parse(text: &str) -> Option<CostKind> {
        match text {
            "reciprocal" => Some(CostKind::Reciprocal),
            "exponential" => Some(CostKind::Exponential),
            "table" => Some(CostKind::Table),
            _ => None,
        }
    }

    /// The name as written.
    pub fn name(self) -> &'static str {
        match self {
            CostKind::Reciprocal => "reciprocal",
            CostKind::Exponential => "exponential",
            CostKind::Table => "table",
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ReciprocalFile {
    #[serde(default)]
    a: f64,
    b: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExponentialFile {
    #[serde(default)]
    a: f64,
    b: f64,
    rate: f64,
}

/// A source's `cost`: one or more models; `--cost` picks one when there are several.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CostFile {
    #[serde(default)]
    reciprocal: Option<ReciprocalFile>,
    #[serde(default)]
    exponential: Option<ExponentialFile>,
    #[serde(default)]
    table: Option<Vec<[f64; 2]>>,
}

impl CostFile {
    pub(crate) fn models(&self) -> Vec<CostModel> {
        let mut models = Vec::new();
        if let Some(r) = &self.reciprocal {
            models.push(CostModel::Reciprocal { a: r.a, b: r.b });
        }
        if let Some(e) = &self.exponential {
            models.push(CostModel::Exponential {
                a: e.a,
                b: e.b,
                rate: e.rate,
            });
        }
        if let Some(t) = &self.table {
            models.push(CostModel::Table(t.clone()));
        }
        models
    }
}

impl CostModel {
    /// The cost at tolerance `t`; None outside a table's range.
    pub fn cost(&self, t: f64) -> Option<f64> {
        match self {
            CostModel::Reciprocal { a, b } => Some(a + b / t),
            CostModel::Exponential { a, b, rate } => Some(a + b * (-rate * t).exp()),
            CostModel::Table(points) => {
                let first = points.first()?;
                let last = points.last()?;
                // A relative slack so that bounds equal to the table's ends survive rounding.
                let slack = 1e-12 * last[0].abs().max(first[0].abs());
                if t < first[0] - slack || t > last[0] + slack {
                    return None;
                }
                let t = t.clamp(first[0], last[0]);
                let k = points
                    .partition_point(|p| p[0] <= t)
                    .clamp(1, points.len() - 1);
                let (p0, p1) = (points[k - 1], points[k]);
                let w = (t - p0[0]) / (p1[0] - p0[0]);
                Some(p0[1] + w * (p1[1] - p0[1]))
            }
        }
    }

    /// The tolerance range on which the model is defined, if limited.
    pub fn range(&self) -> Option<(f64, f64)> {
        match self {
            CostModel::Table(points) => Some((points.first()?[0], points.last()?[0])),
            _ => None,
        }
    }

    pub(crate) fn validate(&self, path: &str) -> Result<(), ScenarioError> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(ScenarioError::new(
                    format!("{path}.{name}"),
                    "must be a finite number",
                ))
            }
        };
        // b scales the part of the cost that a looser tolerance saves.
        let saving = |name: &str, b: f64| {
            finite(name, b)?;
            if b < 0.0 {
                return Err(ScenarioError::new(
                    format!("{path}.{name}"),
                    format!(
                        "must be ≥ 0 (a looser tolerance cannot cost more), got {}",
                        Shown(b)
                    ),
                ));
            }
            Ok(())
        };
        match self {
            CostModel::Reciprocal { a, b } => {
                finite("reciprocal.a", *a)?;
                saving("reciprocal.b", *b)?;
            }
            CostModel::Exponential { a, b, rate } => {
                finite("exponential.a", *a)?;
                saving("exponential.b", *b)?;
                finite("exponential.rate", *rate)?;
                if *rate <= 0.0 {
                    return Err(ScenarioError::new(
                        format!("{path}.exponential.rate"),
                        format!("must be > 0, got {}", Shown(*rate)),
                    ));
                }
            }
            CostModel::Table(points) => {
                if points.len() < 2 {
                    return Err(ScenarioError::new(
                        format!("{path}.table"),
                        "needs at least two [tolerance, cost] points",
                    ));
                }
                for (k, p) in points.iter().enumerate() {
                    let here = format!("{path}.table[{k}]");
                    if !p[0].is_finite() || !p[1].is_finite() {
                        return Err(ScenarioError::new(here, "must be two finite numbers"));
                    }
                    if p[0] <= 0.0 {
                        return Err(ScenarioError::new(
                            here,
                            format!("tolerance must be > 0, got {}", Shown(p[0])),
                        ));
                    }
                    if k > 0 {
                        let q = points[k - 1];
                        if p[0] <= q[0] {
                            return Err(ScenarioError::new(
                                here,
                                format!(
                                    "tolerances must increase strictly: {} follows {}",
                                    p[0], q[0]
                                ),
                            ));
                        }
                        if p[1] > q[1] {
                            return Err(ScenarioError::new(
                                here,
                                format!(
                                    "cost {} at tolerance {} exceeds cost {} at the tighter {}: \
                                     a looser tolerance cannot cost more",
                                    p[1], p[0], q[1], q[0]
                                ),
                            ));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Its kind.
    pub fn kind(&self) -> CostKind {
        match self {
            CostModel::Reciprocal { .. } => CostKind::Reciprocal,
            CostModel::Exponential { .. } => CostKind::Exponential,
            CostModel::Table(_) => CostKind::Table,
        }
    }

    /// A one-line description, for reports.
    pub fn describe(&self) -> String {
        match self {
            CostModel::Reciprocal { a, b } => format!("{a} + {b}/t"),
            CostModel::Exponential { a, b, rate } => format!("{a} + {b}·exp(-{rate}·t)"),
            CostModel::Table(points) => format!("table of {} points", points.len()),
        }
    }
}

/// The scenario's `allocation` section as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AllocationFile {
    /// Documentation for the reader of the file; not used.
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    pub(crate) sources: BTreeMap<String, AllocationSourceFile>,
    #[serde(default)]
    pub(crate) levers: BTreeMap<String, LeverFile>,
}

/// A discrete design choice as written: a design value's path (`param`) and its candidate
/// values with their costs.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LeverFile {
    /// Documentation for the reader of the file; not used.
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    pub(crate) param: String,
    pub(crate) values: Vec<f64>,
    pub(crate) cost: Vec<f64>,
}

/// A discrete design choice `rvtol allocate` makes besides the tolerances: a design value
/// (the number of pin classes of selective fitting, the profile modification) set to one
/// of its candidate values, each with a cost added to the tolerances' cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Lever {
    /// The lever's name (its key in `allocation.levers`).
    pub name: String,
    /// The design value it sets ([`super::design`]).
    pub target: super::design::DesignValue,
    /// Candidate values.
    pub values: Vec<f64>,
    /// Cost of each value.
    pub costs: Vec<f64>,
}

/// Most candidate combinations of all levers together (each is a whole allocation).
pub const MAX_LEVER_COMBINATIONS: usize = 64;

impl AllocationFile {
    /// Whether the section names any of `names` as a source.
    pub(crate) fn names_any(&self, names: &std::collections::BTreeSet<String>) -> bool {
        self.sources.keys().any(|name| names.contains(name))
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct AllocationSourceFile {
    #[serde(default)]
    pub(crate) min: Option<f64>,
    #[serde(default)]
    pub(crate) max: Option<f64>,
    pub(crate) cost: CostFile,
}

/// A source whose tolerance `rvtol allocate` may change.
#[derive(Debug, Clone, PartialEq)]
pub struct AllocatableSource {
    /// The source and its current tolerance.
    pub source: ToleranceSource,
    /// Smallest tolerance allowed.
    pub min: f64,
    /// Largest tolerance allowed.
    pub max: f64,
    /// Cost as a function of the tolerance: the scenario's model, or the one `--cost`
    /// picks (see [`AllocatableSource::with_cost`]).
    pub cost: CostModel,
    /// Every cost model the scenario gives for the source.
    pub cost_models: Vec<CostModel>,
}

impl AllocatableSource {
    /// The source with the cost model of kind `kind` (when `Some`), or its only one.
    pub fn with_cost(&self, kind: Option<CostKind>) -> Result<AllocatableSource, ScenarioError> {
        let path = format!("allocation.sources.{}.cost", self.source.name);
        let model = match kind {
            Some(kind) => self
                .cost_models
                .iter()
                .find(|m| m.kind() == kind)
                .ok_or_else(|| {
                    ScenarioError::new(&path, format!("has no {} model (--cost)", kind.name()))
                })?,
            None if self.cost_models.len() == 1 => &self.cost_models[0],
            None => {
                let kinds: Vec<&str> = self.cost_models.iter().map(|m| m.kind().name()).collect();
                return Err(ScenarioError::new(
                    &path,
                    format!(
                        "gives {} cost models ({}); choose one with --cost",
                        kinds.len(),
                        kinds.join(", ")
                    ),
                ));
            }
        };
        Ok(AllocatableSource {
            cost: model.clone(),
            ..self.clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_cost_interpolates_and_stays_in_range() {
        let table = CostModel::Table(vec![[0.01, 10.0], [0.02, 6.0], [0.04, 5.0]]);
        assert_eq!(table.cost(0.01), Some(10.0));
        assert_eq!(table.cost(0.015), Some(8.0));
        assert_eq!(table.cost(0.03), Some(5.5));
        assert_eq!(table.cost(0.04), Some(5.0));
        assert_eq!(table.cost(0.005), None);
        assert_eq!(table.cost(0.05), None);
        let reciprocal = CostModel::Reciprocal { a: 1.0, b: 0.02 };
        assert_eq!(reciprocal.cost(0.01), Some(3.0));
        let exponential = CostModel::Exponential {
            a: 0.0,
            b: 2.0,
            rate: 100.0,
        };
        assert!((exponential.cost(0.01).unwrap() - 2.0 * (-1.0f64).exp()).abs() < 1e-15);
    }

    #[test]
    fn bad_costs_name_their_path() {
        let err = CostModel::Table(vec![[0.01, 5.0], [0.02, 6.0]])
            .validate("allocation.sources.x.cost")
            .unwrap_err();
        assert_eq!(err.path, "allocation.sources.x.cost.table[1]");
        let err = CostModel::Reciprocal { a: 0.0, b: -1.0 }
            .validate("c")
            .unwrap_err();
        assert_eq!(err.path, "c.reciprocal.b");
    }
}
