//! Roller contacts: Palmgren's line-contact approach, the Stribeck–Palmgren load
//! distribution of a roller row, and the row's secant stiffness (docs/models.md §13).
//!
//! ```text
//! line contact (Palmgren 1959; Harris 2001 §6.4): approach of one roller–raceway contact
//!   δ(Q) = 3.84·10⁻⁵·Q^0.9 / l^0.8                                      (mm, N, mm)
//! roller row under a radial load F (Stribeck–Palmgren, zero clearance, half the row
//! loaded; NSK "Bearing internal load distribution", Eq. 5):
//!   Q_max = 4.08·F/(Z·cos α),   δ_r(F) = 2·δ(Q_max)/cos α    (two contacts per roller)
//!   secant stiffness k(F) = F/δ_r(F)
//! ```

use super::bodies::{bore_ovalisation_factor, net_force_compliance};

/// Palmgren's line-contact coefficient: δ = 3.84·10⁻⁵·Q^0.9/l^0.8, mm with Q in N and l in
/// mm (Palmgren 1959; Harris 2001 §6.4), steel on steel.
pub const PALMGREN_LINE: f64 = 3.84e-5;

/// Stribeck–Palmgren factor of a line-contact row with zero clearance: the most loaded
/// roller carries Q_max = 4.08·F/(Z·cos α) (NSK, "Bearing internal load distribution",
/// Eq. 5; Harris 2001 §7.2).
pub const STRIBECK_LINE: f64 = 4.08;

/// Approach of one line contact under the normal force `force` (N) over the length
/// `length` (mm), mm (Palmgren).
#[inline]
pub fn line_contact_approach(force: f64, length: f64) -> f64 {
    PALMGREN_LINE * force.powf(0.9) / length.powf(0.8)
}

/// A row of rollers (a crank eccentric's needle row, which runs on the journal and in the
/// disc bore without rings, or one row of a tapered support bearing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RollerRow {
    /// Z, rollers in the row.
    pub rollers: f64,
    /// l, effective roller length, mm.
    pub length: f64,
    /// α, contact angle, rad (0 for a needle or cylindrical row).
    pub contact_angle: f64,
}

impl RollerRow {
    /// Radial deflection δ_r under the radial load `load` (N), mm: 2·δ(Q_max)/cos α with
    /// Q_max = 4.08·F/(Z·cos α) (module comment).
    pub fn radial_deflection(&self, load: f64) -> f64 {
        let cos = self.contact_angle.cos();
        let roller_load = STRIBECK_LINE * load / (self.rollers * cos);
        2.0 * line_contact_approach(roller_load, self.length) / cos
    }

    /// Secant radial compliance δ_r(F)/F at the load F > 0 (mm/N).
    pub fn secant_compliance(&self, load: f64) -> f64 {
        self.radial_deflection(load) / load
    }

    /// c_seat = c_oval/(E·B), the ovalisation of a plate's bore of thickness B (the carrier
    /// plate around a support bearing's outer ring) under the row's load, mm/N (module
    /// comment; the net force's path through the plate is not in it).
    pub fn housing_ovalisation_compliance(thickness: f64, youngs: f64, poisson: f64) -> f64 {
        bore_ovalisation_factor(poisson) / (youngs * thickness)
    }

    /// c_bore, the compliance of the plate that is a ringless row's housing (the cycloid
    /// disc around its crank bore), mm/N: the bore of radius `bore_radius` in a plate of
    /// `thickness`, its net force carried to a rim `rim_distance` from the bore's centre;
    /// E (MPa) and ν (module comment: Michell's harmonics n = 0 and n ≥ 2 at the load line
    /// and Kelvin's point force for n = 1). Linear: the same at every load.
    pub fn ringless_housing_compliance(
        bore_radius: f64,
        rim_distance: f64,
        thickness: f64,
        youngs: f64,
        poisson: f64,
    ) -> f64 {
        bore_ovalisation_factor(poisson) / (youngs * thickness)
            + net_force_compliance(bore_radius, rim_distance, thickness, youngs, poisson)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;
    #[test]
    fn roller_row_is_palmgren_at_the_stribeck_load() {
        // 15 needles of 6 mm, 1870 N: Q_max = 4.08·1870/15 = 508.64 N; one contact
        // 3.84e-5·508.64^0.9/6^0.8 = 2.4979e-3 mm; two contacts 4.9958e-3 mm.
        let row = RollerRow {
            rollers: 15.0,
            length: 6.0,
            contact_angle: 0.0,
        };
        let q: f64 = 4.08 * 1870.0 / 15.0;
        assert!((q - 508.64).abs() < 1e-9);
        let hand = 2.0 * 3.84e-5 * q.powf(0.9) / 6.0_f64.powf(0.8);
        assert!((hand - 4.9958e-3).abs() < 1e-7, "{hand}");
        assert_eq!(row.radial_deflection(1870.0), hand);
        // A contact angle α divides the roller load and the radial deflection by cos α.
        let tapered = RollerRow {
            contact_angle: 15f64.to_radians(),
            ..row
        };
        let cos = 15f64.to_radians().cos();
        let expected =
            2.0 * 3.84e-5 * (4.08 * 1870.0 / (15.0 * cos)).powf(0.9) / 6.0_f64.powf(0.8) / cos;
        assert!((tapered.radial_deflection(1870.0) / expected - 1.0).abs() < 1e-14);
    }

    #[test]
    fn stribeck_factor_is_the_discrete_roller_sum_at_zero_clearance() {
        // F = Σ Q_j·cos ψ_j with Q_j ∝ (δ_r·cos ψ_j)^(1/0.9) over the rollers facing the load
        // (zero clearance): for 15 rollers Q_max/(F/Z) lies within 1 % of 4.08.
        let z = 15;
        let sum: f64 = (0..z)
            .map(|j| (2.0 * PI * j as f64 / z as f64).cos())
            .filter(|c| *c > 0.0)
            .map(|c| c.powf(1.0 / 0.9) * c)
            .sum();
        let factor = z as f64 / sum;
        assert!((factor / 4.08 - 1.0).abs() < 0.01, "{factor}");
    }

    #[test]
    fn radial_clearance_hardly_changes_the_slope_of_a_needle_row() {
        // The module comment's claim: 15 needles of 6 mm (an RV-20E row at 50 and 100 %
        // rated), a diametral clearance of 2 µm (000 Table 9's Δu) changes the secant
        // slope between 935 N and 1870 N by under 1 %. Discrete roller sum
        // F = Σ K·(δ_r·cos ψ_j − c/2)^(1/0.9)·cos ψ_j solved for δ_r by bisection.
        let (z, length) = (15, 6.0);
        let deflection = |load: f64, clearance: f64| -> f64 {
            let per_roller = 2.0 * PALMGREN_LINE / f64::powf(length, 0.8);
            let force = |radial: f64| -> f64 {
                (0..z)
                    .map(|j| (2.0 * PI * j as f64 / z as f64).cos())
                    .map(|c| {
                        let d = radial * c - 0.5 * clearance;
                        if d > 0.0 {
                            (d / per_roller).powf(1.0 / 0.9) * c
                        } else {
                            0.0
                        }
                    })
                    .sum()
            };
            let (mut lo, mut hi) = (0.0, 1e-6);
            while force(hi) < load {
                hi *= 2.0;
            }
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if force(mid) < load {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        let slope =
            |clearance: f64| 935.0 / (deflection(1870.0, clearance) - deflection(935.0, clearance));
        let change = slope(0.002) / slope(0.0) - 1.0;
        assert!(change.abs() < 0.01, "{change}");
    }
}
