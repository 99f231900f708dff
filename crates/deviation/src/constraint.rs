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

/// One linear inequality over two columns of a sample row: c0·x[i0] + c1·x[i1] ≤ bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearInequality {
    /// The two columns.
    pub columns: [usize; 2],
    /// Their coefficients.
    pub coefficients: [f64; 2],
    /// Right-hand side.
    pub bound: f64,
}

impl LinearInequality {
    /// Whether the row satisfies it.
    #[inline]
    pub fn holds(&self, row: &[f64]) -> bool {
        self.coefficients[0] * row[self.columns[0]] + self.coefficients[1] * row[self.columns[1]]
            <= self.bound
    }
}

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

    /// The two inequalities of Eq. 11 for a part whose Δu sits in column `first_column`:
    /// Δu + Δβ·L1/2 ≤ Δτ (columns 0 and 4) and Δv + Δα·L1/2 ≤ Δτ (columns 1 and 3). They
    /// involve disjoint components, so when those are independent each can be drawn by
    /// its own rejection loop.
    pub fn inequalities(&self, first_column: usize) -> [LinearInequality; 2] {
        let half_length = 0.5 * self.length_mm;
        [
            LinearInequality {
                columns: [first_column, first_column + 4],
                coefficients: [1.0, half_length],
                bound: self.delta_tau_mm,
            },
            LinearInequality {
                columns: [first_column + 1, first_column + 3],
                coefficients: [1.0, half_length],
                bound: self.delta_tau_mm,
            },
        ]
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
