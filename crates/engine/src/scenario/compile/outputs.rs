//! The outputs: each bound model's outputs join the scenario's with their qualifying
//! indicators (an output an earlier model produced too is a problem), and the
//! `spec_limits` section gives a continuous output its lower and upper limits (and whether
//! a sample its indicator flags may still conform within them, `flagged_conform`). An
//! output no model produces is reported once every model built.

use rvtol_deviation::Shown;
use rvtol_models::{ConditionEffect, ErrorModel, ModelEntry, OutputKind};

use super::super::file::SpecFile;
use super::super::OutputInfo;
use super::Compiler;
use crate::error::ScenarioError;
use crate::stats::SpecLimits;

impl Compiler<'_> {
    /// Adds the model's outputs (a name an earlier model produced too makes the model
    /// unbound) with their qualifying indicators; returns the index of the first.
    pub(super) fn add_outputs(
        &mut self,
        path: &str,
        entry: &ModelEntry,
        model: &dyn ErrorModel,
        bound: &mut bool,
    ) -> usize {
        let first_output = self.outputs.len();
        for output in model.outputs() {
            if self.outputs.iter().any(|o| o.name == output.name) {
                self.report(Err(ScenarioError::new(
                    format!("{path}.model"),
                    format!(
                        "output {:?} is produced by an earlier model too",
                        output.name
                    ),
                )));
                *bound = false;
            }
            self.outputs.push(OutputInfo {
                name: output.name.clone(),
                unit: output.unit.clone(),
                kind: output.kind,
                description: output.description.to_string(),
                spec: None,
                condition: None,
                flagged_conform: false,
            });
        }
        for (j, output) in model.outputs().iter().enumerate() {
            if let Some(condition) = output.condition {
                let indicator = model
                    .outputs()
                    .iter()
                    .position(|o| o.name == condition.indicator && o.kind == OutputKind::Indicator)
                    .unwrap_or_else(|| {
                        panic!(
                            "model {} qualifies {} by {}, which is not one of its indicator outputs",
                            entry.name, output.name, condition.indicator
                        )
                    });
                self.outputs[first_output + j].condition =
                    Some((first_output + indicator, condition.effect));
            }
        }
        first_output
    }
}

/// Sets the spec limits of every output the section names.
pub(super) fn compile(compiler: &mut Compiler) {
    let file = compiler.file;
    for (name, spec) in &file.spec_limits {
        let path = format!("spec_limits.{name}");
        let all_built = compiler.models_built == file.models.len();
        let Some(output) = compiler.outputs.iter_mut().find(|o| &o.name == name) else {
            if all_built {
                compiler.report(Err(ScenarioError::new(
                    &path,
                    format!("no output named {name:?}"),
                )));
            }
            continue;
        };
        let limits = spec_limits(&path, name, spec, output);
        compiler.report(limits);
    }
}

/// The spec limits of one output.
fn spec_limits(
    path: &str,
    name: &str,
    spec: &SpecFile,
    output: &mut OutputInfo,
) -> Result<(), ScenarioError> {
    if output.kind != OutputKind::Continuous {
        return Err(ScenarioError::new(
            path,
            "spec limits apply to continuous outputs only",
        ));
    }
    if spec.lower.is_none() && spec.upper.is_none() {
        return Err(ScenarioError::new(path, "give lower, upper or both"));
    }
    if let (Some(l), Some(u)) = (spec.lower, spec.upper) {
        if l >= u {
            return Err(ScenarioError::new(
                format!("{path}.upper"),
                format!("upper {} must exceed lower {}", Shown(u), Shown(l)),
            ));
        }
    }
    if spec.flagged_conform
        && !matches!(output.condition, Some((_, ConditionEffect::NonConforming)))
    {
        return Err(ScenarioError::new(
            format!("{path}.flagged_conform"),
            format!("{name:?} has no indicator that flags non-conforming samples"),
        ));
    }
    output.spec = Some(SpecLimits {
        lower: spec.lower,
        upper: spec.upper,
    });
    output.flagged_conform = spec.flagged_conform;
    Ok(())
}
