//! Errors of the deviation model. Each names the JSON path of the offending value, as
//! handed in by the caller, so that a user can find it in the scenario file.

use crate::shown::{Rounded, Shown};
use thiserror::Error;

/// A deviation specification that cannot be sampled.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DeviationError {
    /// A value that must be finite is NaN or infinite.
    #[error("{path}: must be a finite number, got {}", Shown(*value))]
    NotFinite {
        /// JSON path of the value.
        path: String,
        /// The value found.
        value: f64,
    },
    /// A standard deviation, variance or width that must not be negative is.
    #[error("{path}: must not be negative, got {}", Shown(*value))]
    Negative {
        /// JSON path of the value.
        path: String,
        /// The value found.
        value: f64,
    },
    /// A matrix that must be symmetric is not.
    #[error(
        "{path}: matrix is not symmetric: [{row}][{col}] = {} but [{col}][{row}] = {}", Shown(*upper), Shown(*lower)
    )]
    Asymmetric {
        /// JSON path of the matrix.
        path: String,
        /// Row of the first mismatching entry.
        row: usize,
        /// Column of the first mismatching entry.
        col: usize,
        /// Entry (row, col).
        upper: f64,
        /// Entry (col, row).
        lower: f64,
    },
    /// A covariance or correlation matrix has a negative eigenvalue.
    #[error("{path}: {matrix} is not positive semi-definite{}", match smallest_eigenvalue {
        Some(value) => format!(" (smallest eigenvalue {})", Rounded(*value)),
        None => String::new(),
    })]
    Indefinite {
        /// JSON path of the matrix.
        path: String,
        /// What the user wrote: a covariance or correlations.
        matrix: MatrixKind,
        /// Its smallest eigenvalue (of the correlation matrix for correlations), when the
        /// matrix is small enough to compute it.
        smallest_eigenvalue: Option<f64>,
    },
    /// Any other invalid value, with the reason.
    #[error("{path}: {reason}")]
    Invalid {
        /// JSON path of the value.
        path: String,
        /// What is wrong.
        reason: String,
    },
}

/// The kind of matrix a definiteness message names: the one the scenario gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatrixKind {
    /// A covariance matrix.
    Covariance,
    /// A correlation matrix, or correlations between columns.
    Correlation,
}

impl std::fmt::Display for MatrixKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            MatrixKind::Covariance => "covariance",
            MatrixKind::Correlation => "correlation",
        })
    }
}

impl DeviationError {
    /// The JSON path of the offending value.
    pub fn path(&self) -> &str {
        match self {
            DeviationError::NotFinite { path, .. }
            | DeviationError::Negative { path, .. }
            | DeviationError::Asymmetric { path, .. }
            | DeviationError::Indefinite { path, .. }
            | DeviationError::Invalid { path, .. } => path,
        }
    }

    /// What is wrong, without the path.
    pub fn message(&self) -> String {
        let text = self.to_string();
        let prefix_length = self.path().len() + ": ".len();
        text.get(prefix_length..).unwrap_or(&text).to_string()
    }

    pub(crate) fn invalid(path: impl Into<String>, reason: impl Into<String>) -> Self {
        DeviationError::Invalid {
            path: path.into(),
            reason: reason.into(),
        }
    }

    /// Checks that `value` is finite.
    pub(crate) fn finite(path: &str, value: f64) -> Result<f64, Self> {
        if value.is_finite() {
            Ok(value)
        } else {
            Err(DeviationError::NotFinite {
                path: path.to_string(),
                value,
            })
        }
    }

    /// Checks that `value` is finite and not negative.
    pub(crate) fn non_negative(path: &str, value: f64) -> Result<f64, Self> {
        let value = Self::finite(path, value)?;
        if value < 0.0 {
            Err(DeviationError::Negative {
                path: path.to_string(),
                value,
            })
        } else {
            Ok(value)
        }
    }
}
