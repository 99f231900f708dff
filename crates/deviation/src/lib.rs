//! rvtol-deviation: what can deviate in an RV reducer and how it is drawn.
//!
//! The deviation model of source document 001 (Zheng Yang, "Deviation modeling of RV
//! retarder parts based on probability statistics and vector"):
//!
//! - a part's deviation is the six-component vector (Δu, Δv, Δw, Δα, Δβ, Δγ): three
//!   translations in mm and three small rotations in rad, always in that order
//!   ([`SixDof`], 001 Eq. 1);
//! - the components are jointly normal with a mean vector and a full covariance
//!   (001 Eq. 2–4), given directly, as standard deviations plus a correlation matrix, or
//!   derived from a tolerance band (001 Eq. 9, 10, 12; [`PartSpec::from_tolerance_band`]),
//!   optionally restricted by the constraint of 001 Eq. 11 ([`TiltConstraint`]);
//! - scalar error parameters follow a [`ScalarDistribution`], measured values an
//!   [`EmpiricalLaw`] (resampled, optionally smoothed);
//! - all normal components of a scenario form one multivariate normal, drawn by
//!   [`InputSpace`] from a pivoted Cholesky factor ([`pivoted_cholesky`]) so that positive
//!   semi-definite covariances work and zero-variance components are exactly their mean;
//!   a correlated scalar of another law joins it through its normal score (the Gaussian
//!   copula, `copula.rs`);
//! - the vector expression φ = ε + θ (001 Eq. 5–8) turns a part's deviation into the
//!   displacement of a point on it ([`point_displacement`]).
//!
//! No I/O, no serde, no threads: the engine owns those.

mod cholesky;
mod conditional;
mod constraint;
mod copula;
mod displacement;
mod empirical;
mod error;
mod input_space;
mod inverse_normal;
mod normal;
mod part;
mod points;
mod scalar;
mod shown;
mod unit;

pub use cholesky::{
    factorise_covariance, pivoted_cholesky, smallest_eigenvalue, CholeskyFactor,
    EIGENVALUE_MESSAGE_LIMIT,
};
pub use conditional::ConditionalSampler;
pub use constraint::{LinearInequality, TiltConstraint};
pub use copula::{normal_score_from_spearman, sample_spearman, spearman_from_normal_score};
pub use displacement::point_displacement;
pub use empirical::{EmpiricalLaw, MIN_EMPIRICAL_VALUES};
pub use error::{DeviationError, MatrixKind};
pub use input_space::{ConstraintCounts, InputSpace, InputSpaceBuilder, SamplerScratch};
pub use inverse_normal::standard_normal_inverse;
pub use normal::{Ziggurat, ZigguratScratch};
pub use part::{check_covariance, PartSpec, SixDof};
pub use points::{PointSet, SamplingMethod, MAX_SOBOL_DIMENSIONS};
pub use scalar::{standard_normal_mass, ScalarDistribution, FOLDED_QUANTILE, RAYLEIGH_QUANTILE};
pub use shown::{human_bytes, index_list, Rounded, Shown};
pub use unit::unit_scale;
