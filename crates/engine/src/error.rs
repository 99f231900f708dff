//! The errors of what a user gives rvtol that it cannot use, each one line: a
//! [`ScenarioError`] names the JSON path of a scenario's value (or of a run setting) and
//! says what is wrong; a [`MergeError`] says why partial results (a sharded run's or
//! analysis') do not fold into one result, where no value of the scenario is wrong; a
//! [`FoldError`] is either, for the merges that also build the scenario's plan. A
//! baseline's problems are rvtol-analysis' `gate::BaselineError`.

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

/// Partial results that do not fold into one result: chunks missing or given twice,
/// partials of different runs. Shown as `(merge): what is wrong`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("(merge): {message}")]
pub struct MergeError {
    /// What is wrong, in one line.
    pub message: String,
}

impl MergeError {
    /// A new merge error.
    pub fn new(message: impl Into<String>) -> Self {
        MergeError {
            message: message.into(),
        }
    }
}

/// Why partials do not give an analysis' result: the scenario refuses the analysis (as
/// the unsharded command would), or the partials do not fold ([`MergeError`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FoldError {
    /// The scenario's problem.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The partials' problem.
    #[error(transparent)]
    Merge(#[from] MergeError),
}

impl FoldError {
    /// The error of a merge of one partial of the whole analysis, its own (what the
    /// unsharded command does): only the scenario can refuse it, the partial always folds.
    pub fn of_own_partial(self) -> ScenarioError {
        match self {
            FoldError::Scenario(err) => err,
            FoldError::Merge(err) => panic!("one partial of the whole analysis folds: {err}"),
        }
    }
}
