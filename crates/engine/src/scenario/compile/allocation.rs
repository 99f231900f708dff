//! The `allocation` section: the sources `rvtol allocate` may change (each with its
//! tolerance's bounds and cost models, checked against the source's current tolerance,
//! [`ToleranceSource`]) and the levers (discrete choices of a design value with their
//! costs). Compiled with the rest of the scenario, so `validate` reports its problems
//! with the others'; the section's types are [`super::super::allocation`]'s.

use rvtol_deviation::Shown;

use super::super::allocation::{
    AllocatableSource, AllocationFile, CostModel, Lever, ToleranceKind, ToleranceSource,
    MAX_LEVER_COMBINATIONS,
};
use super::super::file::{DistributionFile, PartFile, ScenarioFile, VariableFile};
use super::design::design_value;
use super::Compiler;
use crate::error::ScenarioError;

/// Compiles the levers and the sources of the section, when the scenario has one.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    let Some(section) = &file.allocation else {
        return;
    };
    match compile_levers(section, file) {
        Ok(levers) => compiler.allocation_levers = levers,
        Err(err) => compiler.report(Err(err)),
    }
    // A source that could not be built is reported already; its allocation is not checked
    // again.
    if section.names_any(&compiler.broken) {
        return;
    }
    let tolerances: Vec<ToleranceSource> = (file.parts.iter())
        .map(|(i, part)| part_tolerance(&format!("parts[{i}]"), part))
        .chain(
            file.variables
                .iter()
                .map(|(i, variable)| variable_tolerance(&format!("variables[{i}]"), variable)),
        )
        .collect();
    match compile_allocation(section, &tolerances) {
        Ok(allocation) => compiler.allocation = allocation,
        Err(err) => compiler.report(Err(err)),
    }
}

/// A part's tolerance as `rvtol allocate` reads it (see [`super::super::allocation`]).
fn part_tolerance(path: &str, part: &PartFile) -> ToleranceSource {
    let (kind, current, unit) = match &part.tolerance_band {
        Some(band) => (ToleranceKind::PartToleranceBand, band.delta_tau_mm, "mm"),
        None if part.covariance.is_some() => (ToleranceKind::PartCovariance, 1.0, ""),
        None => (ToleranceKind::PartSd, 1.0, ""),
    };
    ToleranceSource {
        name: part.name.clone(),
        path: path.to_string(),
        kind,
        current,
        unit: unit.to_string(),
    }
}

/// A variable's tolerance as `rvtol allocate` reads it (see [`super::super::allocation`]).
fn variable_tolerance(path: &str, variable: &VariableFile) -> ToleranceSource {
    let (kind, current) = match variable.distribution {
        DistributionFile::Normal { sd, .. } => (ToleranceKind::VariableNormal, 3.0 * sd),
        DistributionFile::ToleranceBand { lower, upper, .. } => {
            (ToleranceKind::VariableToleranceBand, 0.5 * (upper - lower))
        }
        DistributionFile::Uniform { lower, upper } => {
            (ToleranceKind::VariableUniform, 0.5 * (upper - lower))
        }
        DistributionFile::Triangular { lower, upper, .. } => {
            (ToleranceKind::VariableTriangular, 0.5 * (upper - lower))
        }
        DistributionFile::TruncatedNormal { sd, .. } => {
            (ToleranceKind::VariableTruncatedNormal, 3.0 * sd)
        }
        DistributionFile::FoldedNormal { lower, upper, .. } => {
            (ToleranceKind::VariableFoldedNormal, 0.5 * (upper - lower))
        }
        DistributionFile::Rayleigh { upper, .. } => (ToleranceKind::VariableRayleigh, upper),
        DistributionFile::Lognormal { .. } => (ToleranceKind::VariableLognormal, 1.0),
        DistributionFile::Empirical { .. } => (ToleranceKind::VariableEmpirical, 1.0),
    };
    // A factor has no unit.
    let unit = match kind {
        ToleranceKind::VariableLognormal | ToleranceKind::VariableEmpirical => String::new(),
        _ => variable.unit.clone().unwrap_or_default(),
    };
    ToleranceSource {
        name: variable.name.clone(),
        path: path.to_string(),
        kind,
        current,
        unit,
    }
}

/// The `allocation.levers` of the scenario `scenario`, each a design value
/// ([`crate::scenario::design`]).
fn compile_levers(
    file: &AllocationFile,
    scenario: &ScenarioFile,
) -> Result<Vec<Lever>, ScenarioError> {
    let mut levers = Vec::new();
    let mut combinations = 1usize;
    for (name, lever) in &file.levers {
        let path = format!("allocation.levers.{name}");
        let target = design_value(scenario, &lever.param)
            .map_err(|message| ScenarioError::new(format!("{path}.param"), message))?;
        if lever.values.is_empty() {
            return Err(ScenarioError::new(
                format!("{path}.values"),
                "give at least one candidate value",
            ));
        }
        if lever.cost.len() != lever.values.len() {
            return Err(ScenarioError::new(
                format!("{path}.cost"),
                format!(
                    "give one cost per value: {} values, {} costs",
                    lever.values.len(),
                    lever.cost.len()
                ),
            ));
        }
        for (i, &c) in lever.cost.iter().enumerate() {
            if !(c.is_finite() && c >= 0.0) {
                return Err(ScenarioError::new(
                    format!("{path}.cost[{i}]"),
                    format!("must be a finite number ≥ 0, got {}", Shown(c)),
                ));
            }
        }
        combinations = combinations.saturating_mul(lever.values.len());
        if combinations > MAX_LEVER_COMBINATIONS {
            return Err(ScenarioError::new(
                format!("{path}.values"),
                format!(
                    "the levers give more than {MAX_LEVER_COMBINATIONS} combinations, each a whole allocation; offer fewer values"
                ),
            ));
        }
        levers.push(Lever {
            name: name.clone(),
            target,
            values: lever.values.clone(),
            costs: lever.cost.clone(),
        });
    }
    Ok(levers)
}

/// Validates the `allocation` section against the scenario's parts and variables.
fn compile_allocation(
    file: &AllocationFile,
    sources: &[ToleranceSource],
) -> Result<Vec<AllocatableSource>, ScenarioError> {
    if file.sources.is_empty() {
        return Err(ScenarioError::new(
            "allocation.sources",
            "name at least one part or variable whose tolerance may change",
        ));
    }
    if let Some(unknown) = file
        .sources
        .keys()
        .find(|name| !sources.iter().any(|s| &s.name == *name))
    {
        return Err(ScenarioError::new(
            format!("allocation.sources.{unknown}"),
            format!("no part or variable named {unknown:?}"),
        ));
    }
    let mut allocatable = Vec::with_capacity(file.sources.len());
    // In scenario order (parts, then variables), the order of every report.
    for source in sources {
        let Some(entry) = file.sources.get(&source.name) else {
            continue;
        };
        let path = format!("allocation.sources.{}", source.name);
        if !(source.current.is_finite() && source.current > 0.0) {
            return Err(ScenarioError::new(
                &path,
                format!(
                    "{} has no spread to scale (its {} is {})",
                    source.name,
                    source.kind.meaning(),
                    source.current
                ),
            ));
        }
        let models = entry.cost.models();
        if models.is_empty() {
            return Err(ScenarioError::new(
                format!("{path}.cost"),
                "give a reciprocal, exponential or table cost model",
            ));
        }
        for model in &models {
            model.validate(&format!("{path}.cost"))?;
        }
        let range = models.iter().find_map(CostModel::range);
        let min = entry.min.or(range.map(|r| r.0)).ok_or_else(|| {
            ScenarioError::new(
                format!("{path}.min"),
                "required (the smallest tolerance the process can hold)",
            )
        })?;
        let max = entry.max.or(range.map(|r| r.1)).ok_or_else(|| {
            ScenarioError::new(
                format!("{path}.max"),
                "required (the largest tolerance the design may take)",
            )
        })?;
        if !(min.is_finite() && min > 0.0) {
            return Err(ScenarioError::new(
                format!("{path}.min"),
                format!("must be a finite number > 0, got {}", Shown(min)),
            ));
        }
        if !(max.is_finite() && max >= min) {
            return Err(ScenarioError::new(
                format!("{path}.max"),
                format!(
                    "must be a finite number ≥ min ({}), got {}",
                    Shown(min),
                    Shown(max)
                ),
            ));
        }
        if let Some((lo, hi)) = range {
            if lo > min || hi < max {
                return Err(ScenarioError::new(
                    format!("{path}.cost.table"),
                    format!(
                        "covers tolerances {lo} .. {hi} but the bounds are {min} .. {max}: \
                         the table must cover the bounds"
                    ),
                ));
            }
        }
        allocatable.push(AllocatableSource {
            source: source.clone(),
            min,
            max,
            cost: models[0].clone(),
            cost_models: models,
        });
    }
    Ok(allocatable)
}
