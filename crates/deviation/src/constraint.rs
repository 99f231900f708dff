//! The assembly constraint of document 001 Eq. 11 on a shaft's deviation.
//!
//! ```text
//! Δu + Δβ·L1/2 ≤ Δτ   and   Δv + Δα·L1/2 ≤ Δτ                              (001 Eq. 11)
//! ```
//!
//! The translation at the shaft's end plus the tilt's lever over half the length must stay
//! inside the tolerance band. rvtol imposes it by rejection: the part's normal block is
//! redrawn until both inequalities hold, which samples the normal distribution of Eq. 2
//! conditioned on Eq. 11. The acceptance rate is counted and reported; a constraint whose
//! acceptance is below 1 % is an error (the conditioned distribution would then be far
//! from the specified one and the run needlessly slow).

/// The Eq. 11 constraint of one part, with the band Δτ (mm) and length L1 (mm) it uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TiltConstraint {
    /// Tolerance band Δτ = τ1 − τ2, mm.
    pub delta_tau_mm: f64,
    /// Feature length L1, mm.
    pub length_mm: f64,
}

impl TiltConstraint {
    /// Whether a deviation (Δu, Δv, Δw, Δα, Δβ, Δγ) satisfies 001 Eq. 11.
    #[inline]
    pub fn holds(&self, deviation: &[f64]) -> bool {
        let half_length = 0.5 * self.length_mm;
        deviation[0] + deviation[4] * half_length <= self.delta_tau_mm
            && deviation[1] + deviation[3] * half_length <= self.delta_tau_mm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_of_tolerance_band_lies_on_the_boundary() {
        // With the Eq. 10 means, Δu + Δβ·L1/2 = Δτ/2 + (Δτ/L1)·L1/2 = Δτ: on the boundary.
        let c = TiltConstraint {
            delta_tau_mm: 0.004,
            length_mm: 120.0,
        };
        assert!(c.holds(&[0.002, 0.002, 0.0, 0.004 / 120.0, 0.004 / 120.0, 0.0]));
        assert!(!c.holds(&[0.0041, 0.0, 0.0, 0.0, 0.0, 0.0]));
        assert!(!c.holds(&[0.0, 0.0, 0.0, 0.0001, 0.0, 0.0]));
    }
}
