//! The crank side of one disc in series: what each element adds to the output angle for
//! one load state (docs/models.md §13).
//!
//! ```text
//! each crank carries, per disc, τ = T_c/(m·a_w) in the symmetric mode and |F|/m in the
//! antisymmetric mode (shaft.rs); every nonlinear row is taken at its secant stiffness at
//! the rms load √(τ² + (|F|/m)²); the disc turns against the carrier by ρ = T_c·c_S/(m·a_w²)
//! and shifts across its eccentric by F_x·c_A/m, a turn of F_x·c_A/(m·e·z_c) at the pins.
//! support bearings (roller rows, each in the plate's seat c_seat = c_oval/(E·B)) add, at
//! the plane x1,
//!   c_sup = share_A·(1 − x1/L)/k_A + share_B·(x1/L)/k_B
//! carrier: support B moves tangentially by the carrier's twist (carrier.rs), which moves
//! the eccentric planes by x1/L and x2/L of it; the two discs carrying equal shares, the
//! output sees their mean:
//!   c_car = m·S_B·a_w²·((x1 + x2)/(2L))/K_c   (symmetric mode only)
//! ```

use super::{CrankShaft, RollerRow};

/// The crank side of one disc: m cranks on the crank circle, each with a needle row, a
/// shaft on two support rows, the carrier, and the involute stage; what the chain adds to
/// the pins' rotation (docs/models.md §13).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrankSide {
    /// m, cranks.
    pub cranks: f64,
    /// a_w, crank circle radius, mm.
    pub crank_circle_radius: f64,
    /// e·z_c, the lever of the disc's translation on the pins (its pitch radius), mm.
    pub pitch_radius: f64,
    /// The needle row of one eccentric.
    pub needle: RollerRow,
    /// c_bore, the disc around the needle row's bore, mm/N (0: a rigid disc).
    pub bore_compliance: f64,
    /// The crank shaft.
    pub shaft: CrankShaft,
    /// One support bearing row (both supports alike).
    pub support: RollerRow,
    /// The carrier plate around one support bearing's outer ring, mm/N (0: rigid plates).
    pub support_housing_compliance: f64,
    /// K_c, N·mm/rad.
    pub carrier_stiffness: f64,
    /// C_inv, rad per N·mm at the output.
    pub involute_compliance: f64,
}

/// The output angle of each element of the crank side for one load state, rad at the
/// output (already multiplied by the reflection factor the caller gives).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ChainTerms {
    /// Needle rows.
    pub needle: f64,
    /// The discs around the needle rows' bores.
    pub disc_bore: f64,
    /// Crank shaft bending and shear.
    pub shaft: f64,
    /// Support bearings.
    pub support: f64,
    /// Carrier wind-up.
    pub carrier: f64,
    /// Involute stage and crank torsion.
    pub involute: f64,
}

impl ChainTerms {
    /// The sum of the terms.
    pub fn total(&self) -> f64 {
        self.needle + self.disc_bore + self.shaft + self.support + self.carrier + self.involute
    }
}

impl CrankSide {
    /// The terms for one disc that carries the disc torque T_c (N·mm, ≥ 0) with the pin
    /// resultant (F_x, F_y) (N; F_x across the eccentric), at the output torque T (N·mm,
    /// ≥ 0); the needle rows' stiffness is multiplied by `needle_factor` (> 0); the disc's
    /// rotation and translation reach the output multiplied by `reflection` (λ).
    ///
    /// Each crank carries τ = T_c/(m·a_w) across its radius in the symmetric mode and
    /// |F|/m in the antisymmetric mode, whose direction turns with the crank against τ's;
    /// every nonlinear row is taken at its secant stiffness at the load's rms over a crank
    /// turn, √(τ² + (|F|/m)²) (the cross term averages out). The disc turns against the
    /// carrier by ρ = T_c·c_S/(m·a_w²) and shifts across its eccentric by F_x·c_A/m, which
    /// the pins see as a turn of F_x·c_A/(m·e·z_c) (docs/models.md §13).
    pub fn terms(
        &self,
        disc_torque: f64,
        force: (f64, f64),
        needle_factor: f64,
        output_torque: f64,
        reflection: f64,
    ) -> ChainTerms {
        if disc_torque <= 0.0 {
            return ChainTerms::default();
        }
        let (m, a) = (self.cranks, self.crank_circle_radius);
        let tangential = disc_torque / (m * a);
        let shared = force.0.hypot(force.1) / m;
        // Output angle per unit compliance in each mode.
        let symmetric = reflection * disc_torque / (m * a * a);
        let antisymmetric = reflection * force.0.abs() / (m * self.pitch_radius);
        let needle_load = tangential.hypot(shared);
        let needle = self.needle.secant_compliance(needle_load) / needle_factor;
        let modes = self.shaft.modes();
        let (weight_a, weight_b) = self.shaft.support_weights();
        let (s_a, s_b) = modes.symmetric_reactions;
        let (anti_a, anti_b) = modes.antisymmetric_reactions;
        let load_a = (tangential * s_a).hypot(shared * anti_a);
        let load_b = (tangential * s_b).hypot(shared * anti_b);
        let (compliance_a, compliance_b) = (
            self.support.secant_compliance(load_a) + self.support_housing_compliance,
            self.support.secant_compliance(load_b) + self.support_housing_compliance,
        );
        let support_symmetric = s_a * weight_a * compliance_a + s_b * weight_b * compliance_b;
        let support_antisymmetric =
            anti_a * weight_a * compliance_a + anti_b * weight_b * compliance_b;
        // Support B's tangential shift reaches the planes x1 and x2 by x1/L and x2/L; the
        // two discs share the load equally, so the output sees the mean.
        let mean_plane = 0.5 * (self.shaft.first + self.shaft.second) / self.shaft.span;
        let carrier = m * s_b * a * a * mean_plane / self.carrier_stiffness;
        ChainTerms {
            needle: (symmetric + antisymmetric) * needle,
            disc_bore: (symmetric + antisymmetric) * self.bore_compliance,
            shaft: symmetric * modes.symmetric + antisymmetric * modes.antisymmetric,
            support: symmetric * support_symmetric + antisymmetric * support_antisymmetric,
            carrier: symmetric * carrier,
            involute: self.involute_compliance * output_torque,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn terms_vanish_without_torque_and_scale_with_reflection() {
        let side = CrankSide {
            cranks: 2.0,
            crank_circle_radius: 27.5,
            pitch_radius: 35.1,
            needle: RollerRow {
                rollers: 15.0,
                length: 6.0,
                contact_angle: 0.0,
            },
            bore_compliance: 4.0e-7,
            shaft: CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3),
            support: RollerRow {
                rollers: 14.0,
                length: 7.0,
                contact_angle: 15f64.to_radians(),
            },
            support_housing_compliance: 2.0e-7,
            carrier_stiffness: 3e8,
            involute_compliance: 1e-11,
        };
        assert_eq!(
            side.terms(0.0, (0.0, 0.0), 1.0, 0.0, 1.0),
            ChainTerms::default()
        );
        let one = side.terms(80_000.0, (2300.0, -120.0), 1.0, 167_000.0, 1.0);
        let half = side.terms(80_000.0, (2300.0, -120.0), 1.0, 167_000.0, 0.5);
        assert!((half.shaft / one.shaft - 0.5).abs() < 1e-15);
        assert!((half.needle / one.needle - 0.5).abs() < 1e-15);
        assert!((half.disc_bore / one.disc_bore - 0.5).abs() < 1e-15);
        assert_eq!(half.involute, one.involute);
        // A stiffer needle row halves its term only.
        let stiff = side.terms(80_000.0, (2300.0, -120.0), 2.0, 167_000.0, 1.0);
        assert!((stiff.needle / one.needle - 0.5).abs() < 1e-15);
        assert_eq!(stiff.shaft, one.shaft);
        assert_eq!(stiff.disc_bore, one.disc_bore);
        // The disc bore is linear and carries both modes like the row: (sym + anti)·c_bore.
        let symmetric = 80_000.0 / (2.0 * 27.5 * 27.5);
        let antisymmetric = 2300.0 / (2.0 * 35.1);
        assert!((one.disc_bore / ((symmetric + antisymmetric) * 4.0e-7) - 1.0).abs() < 1e-14);
    }
}
