//! A part's six-degree-of-freedom deviation and its distribution (source document 001).
//!
//! The deviation vector is E = (Δu, Δv, Δw, Δα, Δβ, Δγ) (001 Eq. 1): translations along
//! x, y, z in mm and small rotations about x, y, z in rad. Its distribution is the
//! multivariate normal N(u, B) of 001 Eq. 2–4, with mean u and covariance B.
//!
//! A tolerance band Δτ = τ1 − τ2 on a feature of length L1 (001 §4.1) gives, by Eq. 9, 10
//! and 12:
//!
//! ```text
//! max Δu = max Δv = Δτ,   max Δα = max Δβ = 2Δτ/L1,   Δw = Δγ = 0            (Eq. 9)
//! u = (Δτ/2, Δτ/2, 0, Δτ/L1, Δτ/L1, 0)                                      (Eq. 10)
//! σ = (Δτ/6, Δτ/6, 0, Δτ/(3·L1), Δτ/(3·L1), 0)                              (Eq. 12)
//! ```
//!
//! Document 001 omits its Eq. 13 (the covariance); rvtol derives it from Eq. 12 as the
//! diagonal matrix diag(σ²): the document gives no correlation between the components.
//! It is singular (two zero variances), which the pivoted Cholesky sampler accepts.

use crate::shown::Shown;
use nalgebra::DMatrix;

use crate::cholesky::smallest_eigenvalue;
use crate::constraint::TiltConstraint;
use crate::error::{DeviationError, MatrixKind};

/// Names of the six components, in order, as used in scenario bindings
/// (`"input_shaft.du"`), with their units.
pub struct SixDof;

impl SixDof {
    /// Component names in order: du, dv, dw (mm), dalpha, dbeta, dgamma (rad).
    pub const NAMES: [&'static str; 6] = ["du", "dv", "dw", "dalpha", "dbeta", "dgamma"];
    /// Units of the components, in order.
    pub const UNITS: [&'static str; 6] = ["mm", "mm", "mm", "rad", "rad", "rad"];

    /// Index of a component by name.
    pub fn index(name: &str) -> Option<usize> {
        Self::NAMES.iter().position(|&n| n == name)
    }
}

/// The distribution of one part's 6-DOF deviation: mean and full covariance, plus the
/// optional constraint of 001 Eq. 11.
#[derive(Debug, Clone, PartialEq)]
pub struct PartSpec {
    /// Mean vector u (001 Eq. 3, 10).
    pub mean: [f64; 6],
    /// Covariance B (001 Eq. 4), row-major.
    pub covariance: [[f64; 6]; 6],
    /// The rejection constraint of 001 Eq. 11, when enabled.
    pub constraint: Option<TiltConstraint>,
}

impl PartSpec {
    /// A part from its mean and full covariance, checked for finiteness, symmetry and
    /// positive semi-definiteness. `path` is the part's JSON path.
    pub fn from_covariance(
        path: &str,
        mean: [f64; 6],
        covariance: [[f64; 6]; 6],
    ) -> Result<Self, DeviationError> {
        for (i, &m) in mean.iter().enumerate() {
            DeviationError::finite(&format!("{path}.mean[{i}]"), m)?;
        }
        let matrix = DMatrix::from_fn(6, 6, |i, j| covariance[i][j]);
        check_covariance(&format!("{path}.covariance"), &matrix)?;
        Ok(PartSpec {
            mean,
            covariance,
            constraint: None,
        })
    }

    /// A part from its mean, standard deviations and correlation matrix: B = D·R·D.
    pub fn from_correlation(
        path: &str,
        mean: [f64; 6],
        sd: [f64; 6],
        correlation: [[f64; 6]; 6],
    ) -> Result<Self, DeviationError> {
        for (i, &s) in sd.iter().enumerate() {
            DeviationError::non_negative(&format!("{path}.sd[{i}]"), s)?;
        }
        let corr_path = format!("{path}.correlation");
        for (i, row) in correlation.iter().enumerate() {
            for (j, &r) in row.iter().enumerate() {
                let entry = format!("{corr_path}[{i}][{j}]");
                DeviationError::finite(&entry, r)?;
                if i == j && r != 1.0 {
                    return Err(DeviationError::invalid(
                        entry,
                        format!(
                            "diagonal of a correlation matrix must be 1, got {}",
                            Shown(r)
                        ),
                    ));
                }
                if r.abs() > 1.0 {
                    return Err(DeviationError::invalid(
                        entry,
                        format!("correlation must lie in [-1, 1], got {}", Shown(r)),
                    ));
                }
            }
        }
        let matrix = DMatrix::from_fn(6, 6, |i, j| correlation[i][j]);
        check_matrix(&corr_path, &matrix, MatrixKind::Correlation)?;
        let mut covariance = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                covariance[i][j] = sd[i] * correlation[i][j] * sd[j];
            }
        }
        Self::from_covariance(path, mean, covariance)
    }

    /// A part from a tolerance band Δτ on a feature of length L1 (001 Eq. 9, 10, 12), with
    /// the Eq. 11 constraint when `constrained` is set.
    pub fn from_tolerance_band(
        path: &str,
        delta_tau_mm: f64,
        length_mm: f64,
        constrained: bool,
    ) -> Result<Self, DeviationError> {
        let delta_tau =
            DeviationError::non_negative(&format!("{path}.delta_tau_mm"), delta_tau_mm)?;
        let length = DeviationError::finite(&format!("{path}.length_mm"), length_mm)?;
        if length <= 0.0 {
            return Err(DeviationError::invalid(
                format!("{path}.length_mm"),
                format!("must be positive, got {}", Shown(length)),
            ));
        }
        // Eq. 10: u = max/2 with the maxima of Eq. 9.
        let mean = [
            delta_tau / 2.0,
            delta_tau / 2.0,
            0.0,
            delta_tau / length,
            delta_tau / length,
            0.0,
        ];
        // Eq. 12.
        let sd = [
            delta_tau / 6.0,
            delta_tau / 6.0,
            0.0,
            delta_tau / (3.0 * length),
            delta_tau / (3.0 * length),
            0.0,
        ];
        let mut covariance = [[0.0; 6]; 6];
        for (i, &s) in sd.iter().enumerate() {
            covariance[i][i] = s * s;
        }
        Ok(PartSpec {
            mean,
            covariance,
            constraint: constrained.then_some(TiltConstraint {
                delta_tau_mm: delta_tau,
                length_mm: length,
            }),
        })
    }

    /// Standard deviations (square roots of the covariance diagonal).
    pub fn sd(&self) -> [f64; 6] {
        std::array::from_fn(|i| self.covariance[i][i].sqrt())
    }
}

/// Checks that a covariance matrix is finite, symmetric and positive semi-definite.
///
/// Symmetry is checked to a relative 1e-12 of the larger of the two entries' magnitude and
/// the matrix's largest diagonal; definiteness allows a smallest eigenvalue down to
/// −1e-12 · (largest diagonal), i.e. rounding only.
pub fn check_covariance(path: &str, matrix: &DMatrix<f64>) -> Result<(), DeviationError> {
    check_matrix(path, matrix, MatrixKind::Covariance)
}

/// [`check_covariance`] of a matrix the scenario gives as `kind`, which its message names.
fn check_matrix(path: &str, matrix: &DMatrix<f64>, kind: MatrixKind) -> Result<(), DeviationError> {
    let n = matrix.nrows();
    for i in 0..n {
        for j in 0..n {
            DeviationError::finite(&format!("{path}[{i}][{j}]"), matrix[(i, j)])?;
        }
        if matrix[(i, i)] < 0.0 {
            return Err(DeviationError::Negative {
                path: format!("{path}[{i}][{i}]"),
                value: matrix[(i, i)],
            });
        }
    }
    let scale = (0..n).map(|i| matrix[(i, i)]).fold(0.0_f64, f64::max);
    for i in 0..n {
        for j in (i + 1)..n {
            let (upper, lower) = (matrix[(i, j)], matrix[(j, i)]);
            let tolerance = 1e-12 * upper.abs().max(lower.abs()).max(scale);
            if (upper - lower).abs() > tolerance {
                return Err(DeviationError::Asymmetric {
                    path: path.to_string(),
                    row: i,
                    col: j,
                    upper,
                    lower,
                });
            }
        }
    }
    let smallest = smallest_eigenvalue(matrix);
    if smallest < -1e-12 * scale.max(f64::MIN_POSITIVE) {
        return Err(DeviationError::Indefinite {
            path: path.to_string(),
            matrix: kind,
            smallest_eigenvalue: Some(smallest),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tolerance_band_matches_document_001() {
        // validation.md, 001: Δτ and L1 give u = (Δτ/2, Δτ/2, 0, Δτ/L1, Δτ/L1, 0) and
        // σ = (Δτ/6, Δτ/6, 0, Δτ/(3L1), Δτ/(3L1), 0).
        let (dt, l1) = (0.012, 120.0);
        let part = PartSpec::from_tolerance_band("parts[0]", dt, l1, false).unwrap();
        assert_eq!(part.mean, [0.006, 0.006, 0.0, 0.0001, 0.0001, 0.0]);
        let sd = part.sd();
        let expected = [0.002, 0.002, 0.0, dt / 360.0, dt / 360.0, 0.0];
        for i in 0..6 {
            assert!((sd[i] - expected[i]).abs() <= 1e-15 * expected[i].max(1e-300));
        }
    }

    #[test]
    fn asymmetric_covariance_names_entry() {
        let mut cov = [[0.0; 6]; 6];
        for (i, row) in cov.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        cov[0][1] = 0.5;
        let err = PartSpec::from_covariance("parts[2]", [0.0; 6], cov).unwrap_err();
        assert_eq!(
            err.to_string(),
            "parts[2].covariance: matrix is not symmetric: [0][1] = 0.5 but [1][0] = 0"
        );
    }

    #[test]
    fn indefinite_covariance_reports_smallest_eigenvalue() {
        let mut cov = [[0.0; 6]; 6];
        for (i, row) in cov.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        // [[1, 2], [2, 1]] has eigenvalues 3 and −1.
        cov[0][1] = 2.0;
        cov[1][0] = 2.0;
        let err = PartSpec::from_covariance("parts[0]", [0.0; 6], cov).unwrap_err();
        match err {
            DeviationError::Indefinite {
                path,
                smallest_eigenvalue,
                matrix,
            } => {
                assert_eq!(matrix, MatrixKind::Covariance);
                assert_eq!(path, "parts[0].covariance");
                assert!((smallest_eigenvalue.unwrap() + 1.0).abs() < 1e-12);
            }
            other => panic!("expected Indefinite, got {other}"),
        }
    }

    #[test]
    fn negative_sd_is_rejected() {
        let mut corr = [[0.0; 6]; 6];
        for (i, row) in corr.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        let err =
            PartSpec::from_correlation("parts[1]", [0.0; 6], [1.0, -1.0, 0.0, 0.0, 0.0, 0.0], corr)
                .unwrap_err();
        assert_eq!(
            err.to_string(),
            "parts[1].sd[1]: must not be negative, got -1"
        );
    }
}
