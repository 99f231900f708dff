//! Distributions of scalar error parameters (a pin radius error, a bearing clearance, …).
//!
//! - `Normal { mean, sd }`.
//! - `ToleranceBand { lower, upper, cp, mean_shift }`: a normal process centred in the band
//!   [L, U] and shifted by `mean_shift`, with process capability Cp:
//!   μ = (L + U)/2 + shift, σ = (U − L)/(6·Cp) (the ISO 22514 definition of Cp solved for σ).
//! - `Uniform { lower, upper }`.
//! - `Triangular { lower, mode, upper }`, drawn by its inverse CDF.
//! - `TruncatedNormal { mean, sd, lower, upper }`: N(μ, σ²) restricted to [L, U], drawn by
//!   the inverse CDF, u ~ U(Φ(a), Φ(b)), x = μ + σ·Φ⁻¹(u) with a = (L − μ)/σ, b = (U − μ)/σ;
//!   evaluated on the side of the mean where the tail probabilities keep their precision.
//!
//! - `FoldedNormal { mean, sd }`: |X| for X ~ N(μ, σ²), the magnitude of a signed
//!   deviation (a clearance, a position error's size). Mean σ·√(2/π)·e^(−μ²/2σ²) +
//!   μ·(1 − 2Φ(−μ/σ)), variance μ² + σ² − mean² (Leone, Nelson & Nottingham 1961). Drawn
//!   as |μ + σ·z|.
//! - `Rayleigh { sigma }`: the length of a 2-D eccentricity whose two components are
//!   independent N(0, σ²) (a radial runout, the amplitude of a once-per-revolution pitch
//!   error). Mean σ·√(π/2), variance (4 − π)/2·σ²; drawn as σ·√(z1² + z2²), the
//!   eccentricity itself.
//! - `Lognormal { mu, sigma }`: exp(μ + σ·Z). Mean e^(μ + σ²/2), variance
//!   (e^(σ²) − 1)·e^(2μ + σ²); drawn as exp(μ + σ·z).
//! - `Empirical(law)`: measured values resampled, optionally smoothed with the variance
//!   kept ([`EmpiricalLaw`]): one uniform by the inverse of the empirical CDF, plus one
//!   ziggurat normal when smoothed.
//!
//! The magnitude laws take their standard normals z from the project's ziggurat, the
//! normal source of every path (in bulk, column by column, in the run's sampler).
//!
//! The scenario gives the three non-negative laws from a tolerance the way it gives a
//! normal from a band ([`RAYLEIGH_QUANTILE`], [`FOLDED_QUANTILE`]): the stated upper limit
//! is the 99.865 % quantile at Cp = 1, as a band limit is for a normal.
//!
//! Normal and tolerance-band parameters join the scenario's multivariate normal (they can
//! be correlated with part components); the others are drawn independently: the uniform,
//! triangular and truncated normal laws from one uniform of the stream by their inverse
//! CDF, the magnitude laws from ziggurat normals.

use crate::empirical::EmpiricalLaw;
use crate::shown::Shown;
use rand::{Rng, RngExt};
use statrs::function::erf::{erfc, erfc_inv};

use crate::error::DeviationError;
use crate::inverse_normal::standard_normal_inverse;
use crate::unit::unit_scale;

/// The distribution of one scalar error parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum ScalarDistribution {
    /// Normal with mean and standard deviation.
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (≥ 0).
        sd: f64,
    },
    /// A normal process in a tolerance band with capability Cp and a mean shift.
    ToleranceBand {
        /// Lower limit L.
        lower: f64,
        /// Upper limit U (≥ L).
        upper: f64,
        /// Process capability Cp (> 0); σ = (U − L)/(6·Cp).
        cp: f64,
        /// Shift of the mean from the band centre, same unit as the limits.
        mean_shift: f64,
    },
    /// Uniform on [lower, upper].
    Uniform {
        /// Lower end.
        lower: f64,
        /// Upper end (≥ lower).
        upper: f64,
    },
    /// Triangular on [lower, upper] with the given mode.
    Triangular {
        /// Lower end.
        lower: f64,
        /// Mode, in [lower, upper].
        mode: f64,
        /// Upper end.
        upper: f64,
    },
    /// Normal N(mean, sd²) truncated to [lower, upper].
    TruncatedNormal {
        /// Mean of the untruncated normal.
        mean: f64,
        /// Standard deviation of the untruncated normal (> 0).
        sd: f64,
        /// Lower truncation point.
        lower: f64,
        /// Upper truncation point (> lower).
        upper: f64,
    },
    /// |X| with X ~ N(mean, sd²).
    FoldedNormal {
        /// Mean of the underlying normal.
        mean: f64,
        /// Standard deviation of the underlying normal (≥ 0).
        sd: f64,
    },
    /// The length of a 2-D vector of two independent N(0, σ²) components.
    Rayleigh {
        /// σ of each component (≥ 0).
        sigma: f64,
    },
    /// exp(μ + σ·Z), Z standard normal.
    Lognormal {
        /// μ, the log of the median.
        mu: f64,
        /// σ of the log (≥ 0).
        sigma: f64,
    },
    /// Measured values, resampled (checked when built: [`EmpiricalLaw::new`]).
    Empirical(EmpiricalLaw),
}

/// The 99.865 % quantile of the standard Rayleigh law, √(−2·ln 0.00135) = 3.6353: a
/// Rayleigh quantity with upper tolerance U at Cp has σ = U/(3.6353·Cp).
pub const RAYLEIGH_QUANTILE: f64 = 3.635_285_597_179_897;
/// The 99.865 % quantile of |Z| for a standard normal Z, Φ⁻¹(1 − 0.00135/2) = 3.2051.
pub const FOLDED_QUANTILE: f64 = 3.205_133_180_184_792;

/// The probability below a magnitude's upper tolerance limit, 99.865 % (a normal's +3σ
/// point, as rounded where the scenario turns a tolerance into a law:
/// [`RAYLEIGH_QUANTILE`], [`FOLDED_QUANTILE`]).
pub const TOLERANCE_P: f64 = 0.998_65;

/// The p quantile of |X| for X ~ N(μ, σ²): the t with P(|X| > t) =
/// Q((t − μ)/σ) + Q((t + μ)/σ) = 1 − p (Q the upper tail, which keeps its relative
/// precision where p is near 1), by bisection on [0, |μ| + 10σ] to the last bit (the
/// tail falls as t grows); σ·Φ⁻¹((1 + p)/2) when μ = 0. (statrs' erfc, behind Q, is
/// good to about 1e-12 absolute there, so t to about 1e-10 relative off centre.)
fn folded_normal_quantile(mean: f64, sd: f64, p: f64) -> f64 {
    if sd == 0.0 || mean == 0.0 {
        // Centred: P(|X| ≤ t) = 2Φ(t/σ) − 1, inverted in closed form.
        return sd * standard_normal_inverse(0.5 * (1.0 + p)) + mean.abs();
    }
    let tail = |t: f64| {
        standard_normal_upper_tail((t - mean) / sd) + standard_normal_upper_tail((t + mean) / sd)
    };
    let (mut low, mut high) = (0.0, mean.abs() + 10.0 * sd);
    for _ in 0..200 {
        let middle = 0.5 * (low + high);
        if middle <= low || middle >= high {
            break;
        }
        if tail(middle) > 1.0 - p {
            low = middle;
        } else {
            high = middle;
        }
    }
    high
}

/// The t with P(|X| > t) = q for X ~ N(μ, σ²), σ > 0 and μ ≠ 0 (the copula's inverse, a
/// tail given as q to keep its precision): Q((t − μ)/σ) + Q((t + μ)/σ) = q, by Newton
/// steps kept inside a bisection bracket on [0, |μ| + 40σ] (the tail falls as t grows,
/// with slope −(φ((t − μ)/σ) + φ((t + μ)/σ))/σ); about five steps to round-off.
fn folded_normal_beyond(mean: f64, sd: f64, q: f64) -> f64 {
    let tail = |t: f64| {
        standard_normal_upper_tail((t - mean) / sd) + standard_normal_upper_tail((t + mean) / sd)
    };
    let (mut low, mut high) = (0.0, mean.abs() + 40.0 * sd);
    let mut t = mean.abs();
    for _ in 0..200 {
        let excess = tail(t) - q;
        if excess > 0.0 {
            low = t;
        } else {
            high = t;
        }
        let slope = (standard_normal_density((t - mean) / sd)
            + standard_normal_density((t + mean) / sd))
            / sd;
        let newton = t + excess / slope;
        let next = if newton > low && newton < high {
            newton
        } else {
            0.5 * (low + high)
        };
        if next == t || high - low <= f64::EPSILON * high {
            break;
        }
        t = next;
    }
    t
}

pub(crate) fn standard_normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

fn standard_normal_upper_tail(x: f64) -> f64 {
    0.5 * erfc(x / std::f64::consts::SQRT_2)
}

fn standard_normal_density(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Φ(b) − Φ(a) of the standard normal law, from the upper tails when a > 0 to keep
/// precision far out.
pub fn standard_normal_mass(a: f64, b: f64) -> f64 {
    if a > 0.0 {
        standard_normal_upper_tail(a) - standard_normal_upper_tail(b)
    } else {
        standard_normal_cdf(b) - standard_normal_cdf(a)
    }
}

/// Φ⁻¹(p) for p in (0, 1).
fn standard_normal_quantile(p: f64) -> f64 {
    -std::f64::consts::SQRT_2 * erfc_inv(2.0 * p)
}

impl ScalarDistribution {
    /// The law of f·X for a positive factor f (a change of unit, µm to mm: f = 1e-3):
    /// every location and spread scales by f, a capability stays, a lognormal's μ moves by
    /// ln f.
    pub fn scaled(&self, f: f64) -> ScalarDistribution {
        use ScalarDistribution::*;
        match *self {
            Normal { mean, sd } => Normal {
                mean: unit_scale(mean, f),
                sd: unit_scale(sd, f),
            },
            ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            } => ToleranceBand {
                lower: unit_scale(lower, f),
                upper: unit_scale(upper, f),
                cp,
                mean_shift: unit_scale(mean_shift, f),
            },
            Uniform { lower, upper } => Uniform {
                lower: unit_scale(lower, f),
                upper: unit_scale(upper, f),
            },
            Triangular { lower, mode, upper } => Triangular {
                lower: unit_scale(lower, f),
                mode: unit_scale(mode, f),
                upper: unit_scale(upper, f),
            },
            TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            } => TruncatedNormal {
                mean: unit_scale(mean, f),
                sd: unit_scale(sd, f),
                lower: unit_scale(lower, f),
                upper: unit_scale(upper, f),
            },
            FoldedNormal { mean, sd } => FoldedNormal {
                mean: unit_scale(mean, f),
                sd: unit_scale(sd, f),
            },
            Rayleigh { sigma } => Rayleigh {
                sigma: unit_scale(sigma, f),
            },
            Lognormal { mu, sigma } => Lognormal {
                mu: mu + f.ln(),
                sigma,
            },
            Empirical(ref law) => Empirical(law.scaled(f)),
        }
    }

    /// Checks the parameters; `path` is the JSON path of the distribution object.
    pub fn validate(&self, path: &str) -> Result<(), DeviationError> {
        let field = |name: &str| format!("{path}.{name}");
        match *self {
            ScalarDistribution::Normal { mean, sd } => {
                DeviationError::finite(&field("mean"), mean)?;
                DeviationError::non_negative(&field("sd"), sd)?;
            }
            ScalarDistribution::ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            } => {
                DeviationError::finite(&field("lower"), lower)?;
                DeviationError::finite(&field("upper"), upper)?;
                DeviationError::finite(&field("mean_shift"), mean_shift)?;
                DeviationError::finite(&field("cp"), cp)?;
                if upper < lower {
                    return Err(DeviationError::invalid(
                        field("upper"),
                        format!(
                            "upper limit {} is below lower limit {}",
                            Shown(upper),
                            Shown(lower)
                        ),
                    ));
                }
                if cp <= 0.0 {
                    return Err(DeviationError::invalid(
                        field("cp"),
                        format!("process capability must be positive, got {}", Shown(cp)),
                    ));
                }
            }
            ScalarDistribution::Uniform { lower, upper } => {
                DeviationError::finite(&field("lower"), lower)?;
                DeviationError::finite(&field("upper"), upper)?;
                if upper < lower {
                    return Err(DeviationError::invalid(
                        field("upper"),
                        format!(
                            "upper end {} is below lower end {}",
                            Shown(upper),
                            Shown(lower)
                        ),
                    ));
                }
            }
            ScalarDistribution::Triangular { lower, mode, upper } => {
                DeviationError::finite(&field("lower"), lower)?;
                DeviationError::finite(&field("mode"), mode)?;
                DeviationError::finite(&field("upper"), upper)?;
                if !(lower <= mode && mode <= upper) {
                    return Err(DeviationError::invalid(
                        field("mode"),
                        format!(
                            "need lower ≤ mode ≤ upper, got {}, {}, {}",
                            Shown(lower),
                            Shown(mode),
                            Shown(upper)
                        ),
                    ));
                }
            }
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            } => {
                DeviationError::finite(&field("mean"), mean)?;
                DeviationError::non_negative(&field("sd"), sd)?;
                DeviationError::finite(&field("lower"), lower)?;
                DeviationError::finite(&field("upper"), upper)?;
                if sd == 0.0 {
                    return Err(DeviationError::invalid(
                        field("sd"),
                        "a truncated normal needs a positive standard deviation",
                    ));
                }
                if upper <= lower {
                    return Err(DeviationError::invalid(
                        field("upper"),
                        format!(
                            "upper bound {} must exceed lower bound {}",
                            Shown(upper),
                            Shown(lower)
                        ),
                    ));
                }
                let (a, b) = ((lower - mean) / sd, (upper - mean) / sd);
                let mass = standard_normal_mass(a, b);
                if mass < 1e-300 || !mass.is_finite() {
                    return Err(DeviationError::invalid(
                        path,
                        format!(
                            "the interval [{}, {}] holds no probability of N({}, {}²)",
                            Shown(lower),
                            Shown(upper),
                            Shown(mean),
                            Shown(sd)
                        ),
                    ));
                }
            }
            ScalarDistribution::FoldedNormal { mean, sd } => {
                DeviationError::finite(&field("mean"), mean)?;
                DeviationError::non_negative(&field("sd"), sd)?;
            }
            ScalarDistribution::Rayleigh { sigma } => {
                DeviationError::non_negative(&field("sigma"), sigma)?;
            }
            // Checked when it was built.
            ScalarDistribution::Empirical(_) => {}
            ScalarDistribution::Lognormal { mu, sigma } => {
                DeviationError::finite(&field("mu"), mu)?;
                DeviationError::non_negative(&field("sigma"), sigma)?;
                // e^(2μ + σ²)·e^(σ²) must stay finite for the moments.
                if 2.0 * mu + 2.0 * sigma * sigma > 700.0 {
                    return Err(DeviationError::invalid(
                        field("sigma"),
                        "the spread of the log is too large for finite moments",
                    ));
                }
            }
        }
        Ok(())
    }

    /// The law's name and its parameters as the scenario states them, for a record of the
    /// inputs (an empirical law: the number of values and the kernel bandwidth).
    pub fn law(&self) -> (&'static str, Vec<(&'static str, f64)>) {
        use ScalarDistribution::*;
        match *self {
            Normal { mean, sd } => ("normal", vec![("mean", mean), ("sd", sd)]),
            ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            } => (
                "tolerance band",
                vec![
                    ("lower", lower),
                    ("upper", upper),
                    ("cp", cp),
                    ("mean_shift", mean_shift),
                ],
            ),
            Uniform { lower, upper } => ("uniform", vec![("lower", lower), ("upper", upper)]),
            Triangular { lower, mode, upper } => (
                "triangular",
                vec![("lower", lower), ("mode", mode), ("upper", upper)],
            ),
            TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            } => (
                "truncated normal",
                vec![
                    ("mean", mean),
                    ("sd", sd),
                    ("lower", lower),
                    ("upper", upper),
                ],
            ),
            FoldedNormal { mean, sd } => ("folded normal", vec![("mean", mean), ("sd", sd)]),
            Rayleigh { sigma } => ("rayleigh", vec![("sigma", sigma)]),
            Lognormal { mu, sigma } => ("lognormal", vec![("mu", mu), ("sigma", sigma)]),
            Empirical(ref law) => (
                "empirical",
                vec![
                    ("values", law.values().len() as f64),
                    ("bandwidth", law.bandwidth()),
                ],
            ),
        }
    }

    /// Mean and standard deviation when the distribution is normal (it then joins the
    /// joint multivariate normal); `None` otherwise.
    pub fn as_normal(&self) -> Option<(f64, f64)> {
        match *self {
            ScalarDistribution::Normal { mean, sd } => Some((mean, sd)),
            ScalarDistribution::ToleranceBand {
                lower,
                upper,
                cp,
                mean_shift,
            } => Some((
                0.5 * (lower + upper) + mean_shift,
                (upper - lower) / (6.0 * cp),
            )),
            _ => None,
        }
    }

    /// The tolerance limits [lower, upper] of the distribution: the box a worst case and
    /// an RSS stack read. The stated limits where the law has them (a tolerance band's L
    /// and U, whatever its Cp and mean shift; the ends of a uniform, triangular or
    /// truncated normal law); μ ± 3σ of a normal; 0 to the 99.865 % point of a magnitude
    /// (Rayleigh, folded normal: how a scenario turns a tolerance "≤ U" into these laws,
    /// [`RAYLEIGH_QUANTILE`], [`FOLDED_QUANTILE`]); the 0.135 % and 99.865 % points of a
    /// lognormal, exp(μ ∓ 3σ); the measured range of an empirical law.
    pub fn tolerance_limits(&self) -> [f64; 2] {
        use ScalarDistribution::*;
        match *self {
            ToleranceBand { lower, upper, .. }
            | Uniform { lower, upper }
            | Triangular { lower, upper, .. }
            | TruncatedNormal { lower, upper, .. } => [lower, upper],
            FoldedNormal { mean, sd } => [0.0, folded_normal_quantile(mean, sd, TOLERANCE_P)],
            Rayleigh { sigma } => [0.0, RAYLEIGH_QUANTILE * sigma],
            Lognormal { mu, sigma } => [(mu - 3.0 * sigma).exp(), (mu + 3.0 * sigma).exp()],
            Empirical(ref law) => {
                let values = law.values();
                let fold =
                    |f: fn(f64, f64) -> f64, start: f64| values.iter().copied().fold(start, f);
                [
                    fold(f64::min, f64::INFINITY),
                    fold(f64::max, f64::NEG_INFINITY),
                ]
            }
            ref normal => {
                let (mean, sd) = normal.as_normal().unwrap_or((f64::NAN, f64::NAN));
                [mean - 3.0 * sd, mean + 3.0 * sd]
            }
        }
    }

    /// The variance of the distribution.
    pub fn variance(&self) -> f64 {
        match *self {
            ScalarDistribution::Uniform { lower, upper } => (upper - lower).powi(2) / 12.0,
            ScalarDistribution::Triangular { lower, mode, upper } => {
                (lower * lower + mode * mode + upper * upper
                    - lower * mode
                    - lower * upper
                    - mode * upper)
                    / 18.0
            }
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            } => {
                // Var = σ²·[1 + (aφ(a) − bφ(b))/Z − ((φ(a) − φ(b))/Z)²].
                let (a, b) = ((lower - mean) / sd, (upper - mean) / sd);
                let mass = standard_normal_mass(a, b);
                let (pa, pb) = (standard_normal_density(a), standard_normal_density(b));
                let shift = (pa - pb) / mass;
                sd * sd * (1.0 + (a * pa - b * pb) / mass - shift * shift)
            }
            ScalarDistribution::FoldedNormal { mean, sd } => {
                let m = self.mean();
                (mean * mean + sd * sd - m * m).max(0.0)
            }
            ScalarDistribution::Rayleigh { sigma } => {
                (4.0 - std::f64::consts::PI) / 2.0 * sigma * sigma
            }
            ScalarDistribution::Lognormal { mu, sigma } => {
                let s2 = sigma * sigma;
                s2.exp_m1() * (2.0 * mu + s2).exp()
            }
            ScalarDistribution::Empirical(ref law) => law.variance(),
            ref other => other.as_normal().map(|(_, sd)| sd * sd).unwrap_or(f64::NAN),
        }
    }

    /// The mean of the distribution (the "nominal" value).
    pub fn mean(&self) -> f64 {
        match *self {
            ScalarDistribution::Uniform { lower, upper } => 0.5 * (lower + upper),
            ScalarDistribution::Triangular { lower, mode, upper } => (lower + mode + upper) / 3.0,
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            } => {
                // E[X] = μ + σ·(φ(a) − φ(b)) / (Φ(b) − Φ(a)).
                let (a, b) = ((lower - mean) / sd, (upper - mean) / sd);
                let mass = standard_normal_mass(a, b);
                mean + sd * (standard_normal_density(a) - standard_normal_density(b)) / mass
            }
            ScalarDistribution::FoldedNormal { mean, sd } => {
                if sd == 0.0 {
                    return mean.abs();
                }
                sd * (2.0 / std::f64::consts::PI).sqrt() * (-0.5 * (mean / sd).powi(2)).exp()
                    + mean * (1.0 - 2.0 * standard_normal_cdf(-mean / sd))
            }
            ScalarDistribution::Rayleigh { sigma } => sigma * (0.5 * std::f64::consts::PI).sqrt(),
            ScalarDistribution::Lognormal { mu, sigma } => (mu + 0.5 * sigma * sigma).exp(),
            ScalarDistribution::Empirical(ref law) => law.mean(),
            ref other => other.as_normal().map(|(m, _)| m).unwrap_or(f64::NAN),
        }
    }

    /// Standard normals one draw of a magnitude law takes (1 for the folded normal and the
    /// lognormal, 2 for the Rayleigh law); 0 for the other kinds, which are drawn by their
    /// inverse CDF (or by the joint normal).
    pub fn normals_per_draw(&self) -> usize {
        match self {
            ScalarDistribution::FoldedNormal { .. } | ScalarDistribution::Lognormal { .. } => 1,
            ScalarDistribution::Rayleigh { .. } => 2,
            _ => 0,
        }
    }

    /// A magnitude law's value from its standard normals ([`Self::normals_per_draw`] of
    /// them): |μ + σ·z|, σ·√(z1² + z2²) (the length of the 2-D eccentricity (σz1, σz2)),
    /// exp(μ + σ·z). NaN for the other kinds.
    #[inline]
    pub fn from_normals(&self, z: &[f64]) -> f64 {
        match *self {
            ScalarDistribution::FoldedNormal { mean, sd } => (mean + sd * z[0]).abs(),
            ScalarDistribution::Rayleigh { sigma } => sigma * (z[0] * z[0] + z[1] * z[1]).sqrt(),
            ScalarDistribution::Lognormal { mu, sigma } => (mu + sigma * z[0]).exp(),
            _ => f64::NAN,
        }
    }

    /// The value at the uniform u in (0, 1), for the quasi-random and stratified rows:
    /// the inverse CDF of the uniform, triangular, truncated normal and Rayleigh laws
    /// (σ·√(−2·ln(1 − u))); |μ + σ·Φ⁻¹(u)| and exp(μ + σ·Φ⁻¹(u)) for the folded normal and
    /// the lognormal; the empirical inverse CDF, and when smoothed the kernel's normal from
    /// the position of u inside its value's share, v = u·n − ⌊u·n⌋ (uniform on (0, 1) and
    /// independent of the chosen value), z = Φ⁻¹(v). One uniform per value for every law.
    pub fn from_uniform(&self, u: f64) -> f64 {
        match *self {
            ScalarDistribution::Uniform { lower, upper } => lower + (upper - lower) * u,
            ScalarDistribution::Triangular { lower, mode, upper } => {
                let width = upper - lower;
                if width == 0.0 {
                    return lower;
                }
                let split = (mode - lower) / width;
                if u < split {
                    lower + (u * width * (mode - lower)).sqrt()
                } else {
                    upper - ((1.0 - u) * width * (upper - mode)).sqrt()
                }
            }
            ScalarDistribution::TruncatedNormal {
                mean,
                sd,
                lower,
                upper,
            } => {
                let (a, b) = ((lower - mean) / sd, (upper - mean) / sd);
                let z = if a > 0.0 {
                    // Upper tail: work with Q(x) = 1 − Φ(x) to keep precision.
                    let (qa, qb) = (standard_normal_upper_tail(a), standard_normal_upper_tail(b));
                    -standard_normal_quantile(qa - u * (qa - qb))
                } else {
                    let (pa, pb) = (standard_normal_cdf(a), standard_normal_cdf(b));
                    standard_normal_quantile(pa + u * (pb - pa))
                };
                (mean + sd * z).clamp(lower, upper)
            }
            ScalarDistribution::FoldedNormal { .. } | ScalarDistribution::Lognormal { .. } => {
                self.from_normals(&[standard_normal_inverse(u)])
            }
            ScalarDistribution::Rayleigh { sigma } => sigma * (-2.0 * (-u).ln_1p()).sqrt(),
            ScalarDistribution::Empirical(ref law) => {
                if law.bandwidth() == 0.0 {
                    return law.quantile_of(u);
                }
                let position = u * law.values().len() as f64;
                let v = (position - position.floor()).clamp(f64::EPSILON, 1.0 - f64::EPSILON);
                law.value(u, standard_normal_inverse(v))
            }
            ref normal => {
                let (mean, sd) = normal.as_normal().unwrap_or((0.0, 0.0));
                mean + sd * standard_normal_inverse(u)
            }
        }
    }

    /// The value whose normal score is z: F⁻¹(Φ(z)), the marginal transform of the
    /// Gaussian copula (`docs/models.md` §3). Monotone in z, so a rank correlation of the
    /// normal scores is the rank correlation of the values. The tail that matters is taken
    /// as such: Q(z) = 1 − Φ(z) from erfc where a law's upper quantile needs it (Rayleigh
    /// σ·√(−2·ln Q(z)), the folded normal, the triangular law's upper side), so z = 8
    /// still gives a finite value beyond the bulk. The lognormal is exp(μ + σz) exactly;
    /// the folded normal solves P(|X| > x) = Q(z) (closed form when centred:
    /// x = σ·√2·erfc⁻¹(Q(z))); the other laws take their [`Self::from_uniform`] at Φ(z)
    /// (an empirical law at most the last value below 1, so that a smoothed one keeps its
    /// kernel draw inside the share of its largest value).
    pub fn from_normal_score(&self, z: f64) -> f64 {
        let below = standard_normal_cdf(z);
        let above = standard_normal_upper_tail(z);
        match *self {
            ScalarDistribution::Lognormal { mu, sigma } => (mu + sigma * z).exp(),
            ScalarDistribution::Rayleigh { sigma } => {
                // ln(1 − Φ(z)): from Q(z) in the upper half, ln_1p(−Φ(z)) in the lower.
                let log_above = if z > 0.0 {
                    above.ln()
                } else {
                    (-below).ln_1p()
                };
                sigma * (-2.0 * log_above).sqrt()
            }
            ScalarDistribution::FoldedNormal { mean, sd } => {
                if sd == 0.0 || mean == 0.0 {
                    sd * std::f64::consts::SQRT_2 * erfc_inv(above) + mean.abs()
                } else {
                    folded_normal_beyond(mean, sd, above)
                }
            }
            ScalarDistribution::Triangular { lower, mode, upper } => {
                let width = upper - lower;
                if width == 0.0 {
                    return lower;
                }
                if below < (mode - lower) / width {
                    lower + (below * width * (mode - lower)).sqrt()
                } else {
                    upper - (above * width * (upper - mode)).sqrt()
                }
            }
            ScalarDistribution::Empirical(_) => {
                self.from_uniform(below.min(1.0 - f64::EPSILON / 2.0))
            }
            ref normal @ (ScalarDistribution::Normal { .. }
            | ScalarDistribution::ToleranceBand { .. }) => {
                let (mean, sd) = normal.as_normal().unwrap_or((0.0, 0.0));
                mean + sd * z
            }
            _ => self.from_uniform(below),
        }
    }

    /// Draws one value. Normal kinds are normally drawn by the joint sampler; this method
    /// draws them too, for completeness. The magnitude laws take their normals from the
    /// ziggurat, one at a time ([`Self::from_normals`]).
    #[inline]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            ScalarDistribution::Uniform { .. }
            | ScalarDistribution::Triangular { .. }
            | ScalarDistribution::TruncatedNormal { .. } => self.from_uniform(rng.random::<f64>()),
            ScalarDistribution::Empirical(ref law) => law.sample(rng),
            ScalarDistribution::FoldedNormal { .. }
            | ScalarDistribution::Rayleigh { .. }
            | ScalarDistribution::Lognormal { .. } => {
                let normal = crate::normal::Ziggurat::get();
                let z = [normal.sample(rng), normal.sample(rng)];
                self.from_normals(&z[..self.normals_per_draw()])
            }
            ref normal => {
                let (mean, sd) = normal.as_normal().unwrap_or((0.0, 0.0));
                mean + sd * crate::normal::Ziggurat::get().sample(rng)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaling_a_law_scales_its_mean_and_spread() {
        // f·X has mean f·E[X] and variance f²·Var[X], for every law (a change of unit).
        let f = 1e-3;
        for law in [
            ScalarDistribution::Normal { mean: 5.0, sd: 2.0 },
            ScalarDistribution::ToleranceBand {
                lower: -4.0,
                upper: 6.0,
                cp: 1.33,
                mean_shift: 0.5,
            },
            ScalarDistribution::Uniform {
                lower: -3.0,
                upper: 7.0,
            },
            ScalarDistribution::Triangular {
                lower: -1.0,
                mode: 0.5,
                upper: 4.0,
            },
            ScalarDistribution::TruncatedNormal {
                mean: 1.0,
                sd: 2.0,
                lower: -1.0,
                upper: 4.0,
            },
            ScalarDistribution::FoldedNormal { mean: 1.0, sd: 3.0 },
            ScalarDistribution::Rayleigh { sigma: 4.0 },
            ScalarDistribution::Lognormal {
                mu: 1.5,
                sigma: 0.2,
            },
        ] {
            let scaled = law.scaled(f);
            assert!(
                (scaled.mean() - f * law.mean()).abs() <= 1e-14 * (f * law.mean()).abs().max(f),
                "{law:?}"
            );
            assert!(
                (scaled.variance() - f * f * law.variance()).abs()
                    <= 1e-13 * f * f * law.variance(),
                "{law:?}"
            );
        }
    }
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn tolerance_band_sigma_from_cp() {
        // σ = (U − L)/(6·Cp): band ±0.01 mm with Cp 1.33 → σ = 0.02/7.98.
        let d = ScalarDistribution::ToleranceBand {
            lower: -0.01,
            upper: 0.01,
            cp: 1.33,
            mean_shift: 0.001,
        };
        let (mean, sd) = d.as_normal().unwrap();
        assert_eq!(mean, 0.001);
        assert!((sd - 0.02 / 7.98).abs() < 1e-18);
    }

    fn sample_mean_and_variance(d: &ScalarDistribution, n: usize) -> (f64, f64) {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let xs: Vec<f64> = (0..n).map(|_| d.sample(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        (mean, var)
    }

    #[test]
    fn non_normal_means_and_variances() {
        // Closed forms: uniform var (b−a)²/12; triangular var (a²+b²+c²−ab−ac−bc)/18;
        // standard normal truncated to [0, ∞) approximated by [0, 40]: mean √(2/π),
        // var 1 − 2/π. Bound: 5 standard errors of the mean, √(var/n).
        let n = 200_000;
        let cases = [
            (
                ScalarDistribution::Uniform {
                    lower: 1.0,
                    upper: 3.0,
                },
                2.0,
                4.0 / 12.0,
            ),
            (
                ScalarDistribution::Triangular {
                    lower: 0.0,
                    mode: 1.0,
                    upper: 4.0,
                },
                5.0 / 3.0,
                (0.0 + 16.0 + 1.0 - 0.0 - 0.0 - 4.0) / 18.0,
            ),
            (
                ScalarDistribution::TruncatedNormal {
                    mean: 0.0,
                    sd: 1.0,
                    lower: 0.0,
                    upper: 40.0,
                },
                (2.0 / std::f64::consts::PI).sqrt(),
                1.0 - 2.0 / std::f64::consts::PI,
            ),
        ];
        for (d, mean, var) in cases.into_iter().chain(magnitude_laws()) {
            d.validate("d").unwrap();
            assert!((d.mean() - mean).abs() < 1e-12, "{d:?} closed-form mean");
            assert!(
                (d.variance() - var).abs() < 1e-12,
                "{d:?} closed-form variance"
            );
            let (m, v) = sample_mean_and_variance(&d, n);
            let se = (var / n as f64).sqrt();
            assert!((m - mean).abs() < 5.0 * se, "{d:?}: mean {m} vs {mean}");
            // Var of the sample variance ≈ (μ4 − σ⁴)/n ≤ 2σ⁴/n·(1 + kurtosis/2); 10 % is
            // over 20 standard errors for these light-tailed laws at n = 2e5.
            assert!((v - var).abs() < 0.02 * var, "{d:?}: var {v} vs {var}");
        }
    }

    /// The non-negative laws with their closed-form means and variances: a folded standard
    /// normal (√(2/π), 1 − 2/π), a folded N(1, 0.5²) (mean 0.5·√(2/π)·e^(−2) +
    /// (1 − 2Φ(−2)), variance 1.25 − mean²), Rayleigh σ = 2 (2·√(π/2), (4 − π)/2·4) and
    /// lognormal (0, 0.5) (e^(1/8), (e^(1/4) − 1)·e^(1/4)).
    fn magnitude_laws() -> Vec<(ScalarDistribution, f64, f64)> {
        let pi = std::f64::consts::PI;
        let shifted_mean =
            0.5 * (2.0 / pi).sqrt() * (-2.0f64).exp() + (1.0 - 2.0 * standard_normal_cdf(-2.0));
        vec![
            (
                ScalarDistribution::FoldedNormal { mean: 0.0, sd: 1.0 },
                (2.0 / pi).sqrt(),
                1.0 - 2.0 / pi,
            ),
            (
                ScalarDistribution::FoldedNormal { mean: 1.0, sd: 0.5 },
                shifted_mean,
                1.25 - shifted_mean * shifted_mean,
            ),
            (
                ScalarDistribution::Rayleigh { sigma: 2.0 },
                2.0 * (0.5 * pi).sqrt(),
                (4.0 - pi) / 2.0 * 4.0,
            ),
            (
                ScalarDistribution::Lognormal {
                    mu: 0.0,
                    sigma: 0.5,
                },
                0.125f64.exp(),
                (0.25f64.exp() - 1.0) * 0.25f64.exp(),
            ),
        ]
    }

    #[test]
    fn tolerance_quantiles_are_the_99_865_percent_points() {
        // P(R ≤ 3.6353·σ) = 1 − exp(−3.6353²/2) = 0.99865; P(|Z| ≤ 3.2051) = 0.99865.
        assert!((1.0 - (-0.5 * RAYLEIGH_QUANTILE.powi(2)).exp() - 0.99865).abs() < 1e-12);
        let folded = 1.0 - 2.0 * standard_normal_upper_tail(FOLDED_QUANTILE);
        assert!((folded - 0.99865).abs() < 1e-12, "{folded}");
    }

    #[test]
    fn tolerance_limits_are_the_stated_limits_or_the_99_865_percent_points() {
        use ScalarDistribution::*;
        let band = ToleranceBand {
            lower: 1.75,
            upper: 1.81,
            cp: 1.33,
            mean_shift: 0.01,
        };
        assert_eq!(band.tolerance_limits(), [1.75, 1.81]);
        let normal = Normal { mean: 2.0, sd: 0.5 };
        assert_eq!(normal.tolerance_limits(), [0.5, 3.5]);
        let rayleigh = Rayleigh { sigma: 2.0 };
        assert_eq!(rayleigh.tolerance_limits(), [0.0, 2.0 * RAYLEIGH_QUANTILE]);
        // A centred folded normal's limit is FOLDED_QUANTILE·σ (σ·Φ⁻¹((1 + p)/2), Wichura's
        // inverse to the last bits).
        let [low, high] = FoldedNormal { mean: 0.0, sd: 3.0 }.tolerance_limits();
        assert_eq!(low, 0.0);
        assert!(
            (high / (3.0 * FOLDED_QUANTILE) - 1.0).abs() < 1e-14,
            "{high}"
        );
        // Off centre: P(|X| ≤ t) = 0.99865 at the limit, from both tails.
        let (mean, sd) = (1.0, 0.8);
        let [_, t] = FoldedNormal { mean, sd }.tolerance_limits();
        // (To 1e-12 in probability, the precision of statrs' erfc that the existing
        // quantile test above holds FOLDED_QUANTILE to.)
        let q = standard_normal_upper_tail((t - mean) / sd)
            + standard_normal_upper_tail((t + mean) / sd);
        assert!((q - (1.0 - TOLERANCE_P)).abs() < 1e-12, "{q}");
        let [a, b] = Lognormal {
            mu: 0.5,
            sigma: 0.1,
        }
        .tolerance_limits();
        assert_eq!([a, b], [(0.2f64).exp(), (0.8f64).exp()]);
        let law = crate::EmpiricalLaw::new("v", &[3.0, 1.0, 2.0, 5.0, 4.0], 0.0).unwrap();
        assert_eq!(Empirical(law).tolerance_limits(), [1.0, 5.0]);
    }

    #[test]
    fn magnitudes_are_never_negative() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for (d, _, _) in magnitude_laws() {
            assert!((0..100_000).all(|_| {
                let x = d.sample(&mut rng);
                x.is_finite() && x >= 0.0
            }));
        }
    }

    #[test]
    fn truncated_normal_in_far_tail_stays_in_bounds() {
        let d = ScalarDistribution::TruncatedNormal {
            mean: 0.0,
            sd: 1.0,
            lower: 8.0,
            upper: 9.0,
        };
        d.validate("d").unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..1000 {
            let x = d.sample(&mut rng);
            assert!((8.0..=9.0).contains(&x));
        }
    }

    #[test]
    fn invalid_parameters_name_their_path() {
        let d = ScalarDistribution::Normal {
            mean: 0.0,
            sd: f64::NAN,
        };
        assert_eq!(
            d.validate("variables[3].distribution.normal")
                .unwrap_err()
                .to_string(),
            "variables[3].distribution.normal.sd: must be a finite number, got NaN"
        );
        let d = ScalarDistribution::ToleranceBand {
            lower: 1.0,
            upper: 0.0,
            cp: 1.0,
            mean_shift: 0.0,
        };
        assert!(d
            .validate("v")
            .unwrap_err()
            .to_string()
            .starts_with("v.upper: upper limit 0 is below"));
    }
}
