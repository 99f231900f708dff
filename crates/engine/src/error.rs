//! The error of everything a user gives rvtol that it cannot use: a [`ScenarioError`]
//! names the JSON path of the value (or the option, or the file) and says what is wrong
//! in one line. Scenario files, run settings, baselines and shard files all report
//! through it, so a front-end prints any of them alike.

/// A scenario that cannot be read or used, with the JSON path of the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {message}")]
pub struct ScenarioError {
    /// JSON path of the offending value (`(file)` for the file as a whole).
    pub path: String,
    /// What is wrong, in one line.
    pub message: String,
}

impl ScenarioError {
    /// A new error at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        ScenarioError {
            path: path.into(),
            message: message.into(),
        }
    }
}

impl From<rvtol_deviation::DeviationError> for ScenarioError {
    fn from(err: rvtol_deviation::DeviationError) -> Self {
        ScenarioError::new(err.path(), err.message())
    }
}
