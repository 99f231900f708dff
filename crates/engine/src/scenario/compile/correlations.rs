//! The `correlations` section: a correlation between two named columns (a variable, an
//! array's member, a part's component) enters the joint normal, which is then built and
//! checked as a whole (positive semi-definite per correlated group) — the input space the
//! models' bindings refer to.

use super::Compiler;
use crate::error::ScenarioError;

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
        if resolved {
            let correlated = (compiler.builder)
                .correlate(&path, ends[0], ends[1], correlation.rho)
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
