//! The `correlations` section: a correlation between two named columns (a variable, an
//! array's member, a part's component) enters the joint normal, which is then built and
//! checked as a whole (positive semi-definite per correlated group) — the input space the
//! models' bindings refer to. A correlation is given as `rho`, the correlation of the
//! normal scores (of the values, between two normals), or as `spearman`, the rank
//! correlation, turned into the former by ρ = 2·sin(π·ρ_S/6) (the Gaussian copula,
//! rvtol-deviation's `copula.rs`).

use rvtol_deviation::normal_score_from_spearman;

use super::super::file::CorrelationFile;
use super::Compiler;
use crate::error::ScenarioError;

/// The normal-score correlation of an entry: its `rho`, or its `spearman` converted; one of
/// them, in [−1, 1].
fn normal_score_correlation(
    path: &str,
    correlation: &CorrelationFile,
) -> Result<f64, ScenarioError> {
    match (correlation.rho, correlation.spearman) {
        (Some(rho), None) => Ok(rho),
        (None, Some(spearman)) => {
            let at = format!("{path}.spearman");
            if spearman.is_nan() || spearman.abs() > 1.0 {
                return Err(ScenarioError::new(
                    at,
                    format!(
                        "a rank correlation must lie in [-1, 1], got {}",
                        rvtol_deviation::Shown(spearman)
                    ),
                ));
            }
            Ok(normal_score_from_spearman(spearman))
        }
        (Some(_), Some(_)) => Err(ScenarioError::new(
            path,
            "give either rho (the correlation of the normal scores) or spearman (the rank correlation), not both",
        )),
        (None, None) => Err(ScenarioError::new(
            path,
            "give rho (the correlation; of the normal scores for a non-normal quantity) or spearman (the rank correlation)",
        )),
    }
}

/// Compiles every correlation and builds the input space.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    for (i, correlation) in &file.correlations {
        let path = format!("correlations[{i}]");
        let mut ends = [0usize; 2];
        let mut resolved = true;
        for (k, name) in correlation.between.iter().enumerate() {
            match compiler.column_by_name.get(name) {
                Some(&column) => ends[k] = column,
                None => {
                    resolved = false;
                    let problem = if let Some((_, members)) = compiler.arrays.get(name) {
                        Some(ScenarioError::new(
                            format!("{path}.between[{k}]"),
                            format!(
                                "{name:?} is an array of {} members: correlate a member ({name}_1 …)",
                                members.len()
                            ),
                        ))
                    } else if !compiler.broken.contains(name) {
                        Some(ScenarioError::new(
                            format!("{path}.between[{k}]"),
                            format!("no variable or part component named {name:?}"),
                        ))
                    } else {
                        None
                    };
                    compiler.problems.extend(problem);
                }
            }
        }
        let rho = match normal_score_correlation(&path, correlation) {
            Ok(rho) => Some(rho),
            Err(err) => {
                compiler.problems.push(err);
                None
            }
        };
        if let (true, Some(rho)) = (resolved, rho) {
            let correlated = (compiler.builder)
                .correlate(&path, ends[0], ends[1], rho)
                .map_err(ScenarioError::from);
            compiler.report(correlated);
        }
    }
    let builder = std::mem::take(&mut compiler.builder);
    match builder.build("correlations") {
        Ok(space) => compiler.input_space = Some(space),
        Err(err) => compiler.report(Err(err.into())),
    }
}
