//! The crank shaft between its two support bearings, loaded at its two eccentrics
//! (docs/models.md §13).
//!
//! ```text
//! a uniform solid beam of diameter d on two simple supports (the support bearings, span L),
//! eccentric planes at x1 = (L − s)/2 and x2 = (L + s)/2; deflection at x per unit load at
//! a (b = L − a), x ≤ a, Euler–Bernoulli plus Timoshenko shear (Roark, Table 8.1 case 1e;
//! Timoshenko & Gere 1972 §2.9):
//!   w(x; a) = b·x·(L² − b² − x²)/(6·E·I·L) + b·x/(κ·G·A·L)      (mirror for x > a)
//!   I = π·d⁴/64, A = π·d²/4, G = E/(2(1 + ν)), κ = 6(1 + ν)/(7 + 6ν) (solid circle)
//! the two discs load each crank in two modes:
//!   symmetric (the disc torque: the same force at x1 and x2)
//!     c_S = w(x1; x1) + w(x1; x2),  support shares S_A = (2L − x1 − x2)/L, S_B = (x1 + x2)/L
//!   antisymmetric (the pin resultant and eccentric misfits: opposite forces, the two
//!   discs' eccentrics being 180° apart)
//!     c_A = w(x1; x1) − w(x1; x2),  support shares A_A = (x2 − x1)/L, A_B = −A_A
//! ```

use std::f64::consts::PI;

/// A crank shaft on its two support bearings with the eccentrics of the two discs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrankShaft {
    /// L, span between the support bearings' load centres, mm.
    pub span: f64,
    /// x1, plane of the first disc's eccentric from support A, mm.
    pub first: f64,
    /// x2, plane of the second disc's eccentric from support A, mm.
    pub second: f64,
    /// E·I, N·mm².
    pub bending_rigidity: f64,
    /// κ·G·A, N.
    pub shear_rigidity: f64,
    /// G·J, N·mm²/rad.
    pub torsional_rigidity: f64,
}

/// The compliances of a crank shaft at its first eccentric plane in the two load modes
/// (module comment), per newton at each eccentric, mm/N, and the shares of the load that
/// each support carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShaftModes {
    /// c_S, the same force on both eccentrics.
    pub symmetric: f64,
    /// c_A, opposite forces on the two eccentrics.
    pub antisymmetric: f64,
    /// (S_A, S_B): support reactions per newton on each eccentric, symmetric mode.
    pub symmetric_reactions: (f64, f64),
    /// (A_A, A_B): support reactions per newton, antisymmetric mode (+1 at x1, −1 at x2).
    pub antisymmetric_reactions: (f64, f64),
}

impl CrankShaft {
    /// A solid round shaft of `diameter`, supports `span` apart, eccentric planes `spacing`
    /// apart and centred between the supports; E (MPa) and ν.
    pub fn new(diameter: f64, span: f64, spacing: f64, youngs: f64, poisson: f64) -> Self {
        let shear_modulus = youngs / (2.0 * (1.0 + poisson));
        let kappa = 6.0 * (1.0 + poisson) / (7.0 + 6.0 * poisson);
        let area = PI * diameter * diameter / 4.0;
        let inertia = PI * diameter.powi(4) / 64.0;
        CrankShaft {
            span,
            first: 0.5 * (span - spacing),
            second: 0.5 * (span + spacing),
            bending_rigidity: youngs * inertia,
            shear_rigidity: kappa * shear_modulus * area,
            torsional_rigidity: shear_modulus * 2.0 * inertia,
        }
    }

    /// Deflection at `at` (mm from support A) per newton at `load_at`, rigid supports,
    /// mm/N (module comment).
    pub fn influence(&self, at: f64, load_at: f64) -> f64 {
        let length = self.span;
        // Mirror so that the point lies left of the load: w(x; a) = w(L − x; L − a).
        let (x, a) = if at <= load_at {
            (at, load_at)
        } else {
            (length - at, length - load_at)
        };
        let b = length - a;
        b * x * (length * length - b * b - x * x) / (6.0 * self.bending_rigidity * length)
            + b * x / (self.shear_rigidity * length)
    }

    /// The two load modes at the first eccentric plane.
    pub fn modes(&self) -> ShaftModes {
        let (x1, x2, length) = (self.first, self.second, self.span);
        let direct = self.influence(x1, x1);
        let cross = self.influence(x1, x2);
        let anti_a = (x2 - x1) / length;
        ShaftModes {
            symmetric: direct + cross,
            antisymmetric: direct - cross,
            symmetric_reactions: ((2.0 * length - x1 - x2) / length, (x1 + x2) / length),
            antisymmetric_reactions: (anti_a, -anti_a),
        }
    }

    /// Weights (1 − x1/L, x1/L) with which the deflections of supports A and B move the
    /// first eccentric plane.
    pub fn support_weights(&self) -> (f64, f64) {
        (1.0 - self.first / self.span, self.first / self.span)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn shaft_influence_is_the_textbook_beam() {
        // Load at mid-span: w(L/2) = P·L³/(48EI) + P·L/(4κGA) (bending plus shear).
        let shaft = CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3);
        let (ei, kga) = (shaft.bending_rigidity, shaft.shear_rigidity);
        let mid = shaft.influence(14.0, 14.0);
        let hand = 28f64.powi(3) / (48.0 * ei) + 28.0 / (4.0 * kga);
        assert!((mid / hand - 1.0).abs() < 1e-14);
        // Maxwell–Betti reciprocity: w(x; a) = w(a; x).
        for (x, a) in [(3.0, 20.0), (9.5, 18.5), (25.0, 1.0)] {
            let (w1, w2) = (shaft.influence(x, a), shaft.influence(a, x));
            assert!((w1 / w2 - 1.0).abs() < 1e-12, "{x} {a}");
        }
        // EI and κGA of a 15 mm solid shaft: I = π·15⁴/64 = 2485.05 mm⁴,
        // κ = 6·1.3/8.8 = 0.886364, G = 79 230.8 MPa, A = 176.715 mm².
        assert!((ei / (206_000.0 * 2485.049) - 1.0).abs() < 1e-6);
        assert!((kga / (0.886364 * 79_230.77 * 176.7146) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn shaft_modes_split_the_load() {
        // Hand calculation, span 28, spacing 9 (x1 = 9.5, x2 = 18.5): S_A = S_B = 1 (each
        // support takes one eccentric's force in the symmetric mode), A_A = 9/28.
        let shaft = CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3);
        let modes = shaft.modes();
        assert_eq!(modes.symmetric_reactions, (1.0, 1.0));
        assert!((modes.antisymmetric_reactions.0 - 9.0 / 28.0).abs() < 1e-15);
        assert_eq!(
            modes.antisymmetric_reactions.1,
            -modes.antisymmetric_reactions.0
        );
        // Symmetric: the superposed two-load deflection; antisymmetric is smaller.
        let direct = shaft.influence(9.5, 9.5);
        let cross = shaft.influence(9.5, 18.5);
        assert_eq!(modes.symmetric, direct + cross);
        assert!(modes.antisymmetric < modes.symmetric && modes.antisymmetric > 0.0);
        // Two equal loads P at a = x1 and L − a, bending alone: the deflection under a load
        // is P·a²·(3L − 4a)/(6EI) (the symmetric two-load case of Roark Table 8.1).
        let bending_only = CrankShaft {
            shear_rigidity: f64::INFINITY,
            ..shaft
        };
        let a: f64 = 9.5;
        let hand = a * a * (3.0 * 28.0 - 4.0 * a) / (6.0 * shaft.bending_rigidity);
        assert!((bending_only.modes().symmetric / hand - 1.0).abs() < 1e-12);
    }
}
