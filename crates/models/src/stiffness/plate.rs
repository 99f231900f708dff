//! The end plate's bending around a pillar's root: the plate, beyond the root's local
//! deformation (the half-space of carrier.rs), bends as a plate under the pillar's end
//! moment (docs/models.md §13, "The end plate").
//!
//! ```text
//! a Kirchhoff plate of thickness t, D = E·t³/(12(1 − ν²)), around a rigid hub of radius c
//! (the pillar's end, its rocking-equivalent radius (4I/π)^¼), clamped at the radius b
//! where the plate meets its nearest support-bearing seat (the outer ring pressed in, the
//! crank through it): b = 2·a_w·sin(π/(2m)) − D_s/2, the distance from the pillar's axis
//! to the seat's bore (D_s the bearing's outer diameter).
//! The hub tilted by θ: w = f(r)·cos φ, f = A·r³ + B·r + C/r + D_c·r·ln r (the n = 1
//! biharmonic), f(c) = θ·c, f'(c) = θ, f(b) = f'(b) = 0, solved in closed form:
//!   C = b²c²θ/(2[(b² − c²) − (b² + c²)·ln(b/c)]),  D_c = 2C(b² + c²)/(b²c²),  A = −C/(b²c²)
//! Only the r·ln r term carries a net moment (Timoshenko & Woinowsky-Krieger 1959 §19: the
//! concentrated moment w = −M·x·(2 ln r + 1)/(8πD)), M = −4πD·D_c, so the hub's stiffness
//!   K_p = M/θ = 4πD·(b² + c²)/((b² + c²)·ln(b/c) − (b² − c²))
//! ```
//!
//! The plate is as thick as its spans are long (t/b about ½), where Kirchhoff's theory
//! omits the transverse shear; that part of the deformation near the root is the
//! half-space root's, so the two are taken in series.

use std::f64::consts::PI;

/// K_p, the rotational stiffness of a rigid hub of radius `hub` in a plate of thickness
/// `thickness` clamped at `clamp` (> hub), N·mm/rad (module comment).
pub fn hub_tilt_stiffness(hub: f64, clamp: f64, thickness: f64, youngs: f64, poisson: f64) -> f64 {
    let rigidity = youngs * thickness.powi(3) / (12.0 * (1.0 - poisson * poisson));
    let (b2, c2) = (clamp * clamp, hub * hub);
    4.0 * PI * rigidity * (b2 + c2) / ((b2 + c2) * (clamp / hub).ln() - (b2 - c2))
}

/// The coefficients (A, B, C, D_c) of f for a unit tilt (module comment).
pub fn hub_deflection_coefficients(hub: f64, clamp: f64) -> (f64, f64, f64, f64) {
    let (b2, c2) = (clamp * clamp, hub * hub);
    let c = b2 * c2 / (2.0 * ((b2 - c2) - (b2 + c2) * (clamp / hub).ln()));
    let d = 2.0 * c * (b2 + c2) / (b2 * c2);
    let a = -c / (b2 * c2);
    // f(b) = 0: A·b² + B + C/b² + D_c·ln b = 0.
    let b = -(a * b2 + c / b2 + d * clamp.ln());
    (a, b, c, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closed_form_meets_its_edges_and_its_moment_is_the_plates() {
        // An independent check of the module comment's solution: f meets the four edge
        // conditions, and the moment the plate carries across any circle r,
        // M(r) = π·r·(M_r + M_rφ − r·Q_r) with Timoshenko's M_r = −D(f'' + ν(f'/r − f/r²)),
        // M_rφ = −(1 − ν)D(f'/r − f/r²), Q_r = −D·d/dr(f'' + f'/r − f/r²), is the same on
        // every circle (equilibrium) and equals K_p (the r³, r and 1/r terms carry none).
        let (c, b, t, e, nu): (f64, f64, f64, f64, f64) = (6.278, 21.39, 11.75, 206_000.0, 0.3);
        let rigidity = e * t.powi(3) / (12.0 * (1.0 - nu * nu));
        let (a3, b1, c1, d1) = hub_deflection_coefficients(c, b);
        let f = |r: f64| a3 * r.powi(3) + b1 * r + c1 / r + d1 * r * r.ln();
        let f1 = |r: f64| 3.0 * a3 * r * r + b1 - c1 / (r * r) + d1 * (r.ln() + 1.0);
        let f2 = |r: f64| 6.0 * a3 * r + 2.0 * c1 / r.powi(3) + d1 / r;
        let f3 = |r: f64| 6.0 * a3 - 6.0 * c1 / r.powi(4) - d1 / (r * r);
        assert!((f(c) - c).abs() < 1e-12 && (f1(c) - 1.0).abs() < 1e-12);
        assert!(f(b).abs() < 1e-12 && f1(b).abs() < 1e-12);
        let stiffness = hub_tilt_stiffness(c, b, t, e, nu);
        for r in [c, 0.5 * (b + c), b] {
            let twist = f1(r) / r - f(r) / (r * r);
            let laplacian_slope = f3(r) + f2(r) / r - 2.0 * twist / r;
            let moment_r = -rigidity * (f2(r) + nu * twist);
            let moment_twist = -(1.0 - nu) * rigidity * twist;
            let shear = -rigidity * laplacian_slope;
            let moment = PI * r * (moment_r + moment_twist - r * shear);
            assert!(
                (moment / stiffness - 1.0).abs() < 1e-9,
                "{r}: {moment} vs {stiffness}"
            );
        }
    }

    #[test]
    fn rv20e_end_plate_by_hand() {
        // RV-20E: hub c = R_r of an 11 × 11 pillar = (4·1220.0833/π)^¼ = 6.27805 mm; seat
        // 30202 (D 35 mm) on the crank circle 27.5 mm, a pillar between two cranks:
        // b = 2·27.5·sin 45° − 17.5 = 21.39087 mm; t = 11.75 mm: D = 206 000·11.75³/10.92
        // = 3.06026e7 N·mm; b/c = 3.40725, ln = 1.22590; b² + c² = 496.9834, b² − c² =
        // 418.1555; K_p = 4π·3.06026e7·496.9834/(496.9834·1.22590 − 418.1555) =
        // 1.91122e11/191.0987 = 1.00012e9 N·mm/rad: 13.4 times the half-space root's
        // rocking stiffness 7.46860e7 (carrier.rs).
        let b = 2.0 * 27.5 * (PI / 4.0).sin() - 17.5;
        assert!((b - 21.39087).abs() < 1e-5);
        let c = (4.0 * 1220.0833333_f64 / PI).powf(0.25);
        let k = hub_tilt_stiffness(c, b, 11.75, 206_000.0, 0.3);
        assert!((k / 1.00012e9 - 1.0).abs() < 1e-4, "{k}");
    }
}
