//! The `sensitivity_groups` section: the units of the Sobol' analysis, each a named set
//! of error sources (parts and variables) analysed as one; every source in no group is a
//! unit of its own.

use std::collections::BTreeSet;

use super::super::file::ScenarioFile;
use super::super::InputGroup;
use super::{check_name, Compiler};
use crate::error::ScenarioError;

/// Compiles the groups.
pub(super) fn compile(compiler: &mut Compiler) {
    let mut problems = Vec::new();
    let mut report = |result: Result<(), ScenarioError>| {
        if let Err(err) = result {
            problems.push(err);
        }
    };
    compiler.sensitivity_groups = sensitivity_groups(
        compiler.file,
        &compiler.sources,
        &compiler.broken,
        &mut report,
    );
    compiler.problems.extend(problems);
}

/// The units of the Sobol' analysis: the scenario's groups, then every source in none.
fn sensitivity_groups(
    file: &ScenarioFile,
    sources: &[InputGroup],
    broken: &BTreeSet<String>,
    report: &mut impl FnMut(Result<(), ScenarioError>),
) -> Vec<InputGroup> {
    let mut groups: Vec<InputGroup> = Vec::new();
    let mut grouped: Vec<&str> = Vec::new();
    for (i, group) in &file.sensitivity_groups {
        let path = format!("sensitivity_groups[{i}]");
        if let Err(err) = check_name(&format!("{path}.name"), &group.name) {
            report(Err(err));
            continue;
        }
        if group.members.is_empty() {
            report(Err(ScenarioError::new(
                format!("{path}.members"),
                "needs at least one member",
            )));
            continue;
        }
        if sources.iter().any(|s| s.name == group.name) && !group.members.contains(&group.name) {
            report(Err(ScenarioError::new(
                format!("{path}.name"),
                format!("{:?} is already the name of a part or variable", group.name),
            )));
            continue;
        }
        let mut columns = Vec::new();
        for (k, member) in group.members.iter().enumerate() {
            let member_path = format!("{path}.members[{k}]");
            let Some(source) = sources.iter().find(|s| &s.name == member) else {
                if !broken.contains(member) {
                    report(Err(ScenarioError::new(
                        &member_path,
                        format!("no part or variable named {member:?}"),
                    )));
                }
                continue;
            };
            if grouped.contains(&member.as_str()) {
                report(Err(ScenarioError::new(
                    member_path,
                    format!("{member:?} is already in a group"),
                )));
                continue;
            }
            grouped.push(member);
            columns.extend(&source.columns);
        }
        groups.push(InputGroup {
            name: group.name.clone(),
            columns,
        });
    }
    groups.extend(
        sources
            .iter()
            .filter(|s| !grouped.contains(&s.name.as_str()))
            .cloned(),
    );
    groups
}
