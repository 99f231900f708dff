//! The bodies around the rows: the bore of a plate that houses a roller row, under the
//! row's load (docs/models.md §13).
//!
//! ```text
//! a bore of radius a in a plate of thickness t, the row's load spread as p(ψ) = p0·cos ψ
//! over its loaded half (net force P = π·a·t·p0/2); plane stress, the displacement of the
//! bore at the load line, ψ = 0:
//!   Fourier harmonics of p: p0/π (n = 0), p0/2 (n = 1), 2p0·(−1)^(k+1)/(π(4k² − 1)) (n = 2k)
//!   n = 0 (Lamé, hole under pressure):          u = p_n·a·(1 + ν)/E
//!   n ≥ 2 (Michell, hole in an infinite plate):  u = p_n·a·(2n + 1 − ν)/(E·(n² − 1))
//!   summed (G the Catalan constant, 0.915966):
//!     u_oval = c_oval·P/(E·t),  c_oval = (2/π²)·((1 + ν) + 2(G − ½) + 2(1 − ν)(½ − π/8))
//!     (0.46246 for ν = 0.3)
//!   n = 1, the net force carried to a rim R from the bore's centre: Kelvin's plane-stress
//!   point force, bore against rim along the load
//!     u_net = (1 + ν)(3 − ν)/(4π)·ln(R/a)·P/(E·t)
//! the disc around a needle row's bore (the row has no outer ring: the disc is its
//! housing), a = d_j/2 + D, R = r_p − a_w, t the disc's thickness:
//!   c_bore = (c_oval + (1 + ν)(3 − ν)/(4π)·ln(R/a))/(E·t)       (mm/N, linear, both modes)
//! a support bearing's seat: the outer ring in a carrier plate as thick as the bearing is
//! wide (B); Palmgren's formula holds for rings in a rigid housing, so the plate's bore
//! adds its ovalisation, c_seat = c_oval/(E·B), in series with the row; and the plate
//! carries the seat's net force to the pillars, s = 2·a_w·sin(π/(2m)) from the seat's
//! centre (the nearest pillar root; a_s = D_s/2 the seat's bore):
//!   c_path = (1 + ν)(3 − ν)/(4π)·ln(s/a_s)/(E·B)
//!
//! the disc web between its bores and pins, weakened by the pillars' holes (radius r_h):
//! Kelvin's plane-stress point force P along x at the origin, at (r, θ) (Timoshenko &
//! Goodier 1970 §42, from u_x = k[−(3 − ν) ln r + (1 + ν)cos²θ], u_y = k(1 + ν)cos θ sin θ,
//! k = P(1 + ν)/(4π·E·t)):
//!   σ_xx = −P·cos θ/(4π·r·t)·((1 − ν) + 2(1 + ν)cos²θ)
//!   σ_yy =  P·cos θ/(4π·r·t)·(2(1 + ν)cos²θ − (1 + 3ν))
//!   τ_xy = −P·sin θ/(4π·r·t)·((1 − ν) + 2(1 + ν)cos²θ)
//! a traction-free round hole of radius r_h in a plate under the stresses (σ1, σ2) raises
//! its complementary energy by (Kirsch's field; Betti: ΔU = −½∮T⁰·(u⁰ + u_c), u_c the
//! hole's field under −T⁰)
//!   ΔU = (π·r_h²·t/E)·((σ1 + σ2)²/2 + (σ1 − σ2)²)
//! (uniaxial: E_eff = E(1 − 3f), f the holes' area fraction), so, the hole small beside its
//! distance to the bores (r_h/s ≈ ¼ here), the bores' Kelvin fields at each pillar hole's
//! centre give the disc's added compliance per unit force at a bore, by Castigliano:
//!   symmetric (a tangential unit force at each of the m bores)   c_web,S = 2·ΣΔU/m
//!   antisymmetric (the same unit force at every bore, its direction turning with the
//!   crank against the disc: the mean over the direction)           c_web,A = 2·⟨ΣΔU⟩/m
//! ```

use std::f64::consts::PI;

/// Catalan's constant G = Σ (−1)^k/(2k + 1)², to f64 precision.
const CATALAN: f64 = 0.915_965_594_177_219;

/// c_oval: the displacement of a bore at its load line under a row's load spread as
/// cos ψ over the loaded half, per P/(E·t), without the net force's n = 1 harmonic
/// (module comment): (2/π²)·((1 + ν) + 2(G − ½) + 2(1 − ν)(½ − π/8)).
pub(crate) fn bore_ovalisation_factor(poisson: f64) -> f64 {
    2.0 / (PI * PI)
        * ((1.0 + poisson) + 2.0 * (CATALAN - 0.5) + 2.0 * (1.0 - poisson) * (0.5 - PI / 8.0))
}

/// (1 + ν)(3 − ν)/(4π)·ln(R/a)/(E·t): Kelvin's net force carried from a bore of radius
/// `bore_radius` to a rim or root `distance` from its centre in a plate of `thickness`,
/// mm/N (module comment); zero when the distance is no larger than the bore.
pub fn net_force_compliance(
    bore_radius: f64,
    distance: f64,
    thickness: f64,
    youngs: f64,
    poisson: f64,
) -> f64 {
    (1.0 + poisson) * (3.0 - poisson) / (4.0 * PI) * (distance / bore_radius).ln().max(0.0)
        / (youngs * thickness)
}

/// Kelvin's plane-stress stresses (σ_xx, σ_yy, τ_xy) at (x, y) from a point force
/// (f_x, f_y) at the origin of a plate of `thickness`, MPa (module comment).
pub fn kelvin_stress(force: (f64, f64), at: (f64, f64), thickness: f64, poisson: f64) -> [f64; 3] {
    let magnitude = force.0.hypot(force.1);
    if magnitude == 0.0 {
        return [0.0; 3];
    }
    // In the force's frame: x' along the force.
    let (c, s) = (force.0 / magnitude, force.1 / magnitude);
    let (x, y) = (c * at.0 + s * at.1, -s * at.0 + c * at.1);
    let r = x.hypot(y);
    let (cos, sin) = (x / r, y / r);
    let scale = magnitude / (4.0 * PI * r * thickness);
    let lobe = (1.0 - poisson) + 2.0 * (1.0 + poisson) * cos * cos;
    let xx = -scale * cos * lobe;
    let yy = scale * cos * (2.0 * (1.0 + poisson) * cos * cos - (1.0 + 3.0 * poisson));
    let xy = -scale * sin * lobe;
    // Back to the plate's frame: σ = R·σ'·Rᵀ.
    [
        c * c * xx - 2.0 * c * s * xy + s * s * yy,
        s * s * xx + 2.0 * c * s * xy + c * c * yy,
        c * s * (xx - yy) + (c * c - s * s) * xy,
    ]
}

/// ΔU of a traction-free hole of radius `radius` in a plate of `thickness` under the
/// stresses `stress` (σ_xx, σ_yy, τ_xy), N·mm (module comment).
pub fn hole_energy(stress: [f64; 3], radius: f64, thickness: f64, youngs: f64) -> f64 {
    let [xx, yy, xy] = stress;
    let deviator = (xx - yy) * (xx - yy) + 4.0 * xy * xy;
    PI * radius * radius * thickness / youngs * (0.5 * (xx + yy) * (xx + yy) + deviator)
}

/// The disc web's added compliances (c_web,S, c_web,A) per unit force at each of `cranks`
/// bores on the radius `crank_radius`, with a pillar hole of radius `hole` on the radius
/// `pillar_radius` midway between neighbouring bores, in a disc of `thickness`, mm/N
/// (module comment).
pub fn disc_web_compliance(
    cranks: usize,
    crank_radius: f64,
    pillar_radius: f64,
    hole: f64,
    thickness: f64,
    youngs: f64,
    poisson: f64,
) -> (f64, f64) {
    let m = cranks as f64;
    let angle = |k: usize, offset: f64| 2.0 * PI * k as f64 / m + offset;
    let energy = |force_at: &dyn Fn(usize) -> (f64, f64)| -> f64 {
        (0..cranks)
            .map(|j| {
                let theta = angle(j, PI / m);
                let centre = (pillar_radius * theta.cos(), pillar_radius * theta.sin());
                let mut stress = [0.0; 3];
                for k in 0..cranks {
                    let phi = angle(k, 0.0);
                    let bore = (crank_radius * phi.cos(), crank_radius * phi.sin());
                    let at = (centre.0 - bore.0, centre.1 - bore.1);
                    let part = kelvin_stress(force_at(k), at, thickness, poisson);
                    for (total, add) in stress.iter_mut().zip(part) {
                        *total += add;
                    }
                }
                hole_energy(stress, hole, thickness, youngs)
            })
            .sum()
    };
    let symmetric = energy(&|k| {
        let phi = angle(k, 0.0);
        (-phi.sin(), phi.cos())
    });
    let along_x = energy(&|_| (1.0, 0.0));
    let along_y = energy(&|_| (0.0, 1.0));
    (2.0 * symmetric / m, (along_x + along_y) / m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stiffness::RollerRow;

    #[test]
    fn kelvins_stresses_balance_the_force_and_follow_from_its_displacements() {
        // Equilibrium: the tractions on a circle of radius 3 around a force (2, −1) N in a
        // 1 mm plate sum to minus the force; Hooke: the stresses are E/(1 − ν²)-weighted
        // derivatives of the module comment's displacement field (central differences).
        let (nu, e, force) = (0.3, 206_000.0, (2.0, -1.0));
        let steps = 20_000;
        let (mut fx, mut fy) = (0.0, 0.0);
        for k in 0..steps {
            let t = 2.0 * PI * (k as f64 + 0.5) / steps as f64;
            let (c, s) = (t.cos(), t.sin());
            let [xx, yy, xy] = kelvin_stress(force, (3.0 * c, 3.0 * s), 1.0, nu);
            let ds = 3.0 * 2.0 * PI / steps as f64;
            fx += (xx * c + xy * s) * ds;
            fy += (xy * c + yy * s) * ds;
        }
        assert!(
            (fx + 2.0).abs() < 1e-9 && (fy - 1.0).abs() < 1e-9,
            "{fx} {fy}"
        );
        // Displacement of a unit force along x: u_x = k(−(3 − ν) ln r + (1 + ν)x²/r²),
        // u_y = k(1 + ν)xy/r², k = (1 + ν)/(4πE).
        let k = (1.0 + nu) / (4.0 * PI * e);
        let u = |x: f64, y: f64| {
            let r2 = x * x + y * y;
            (
                k * (-(3.0 - nu) * 0.5 * r2.ln() + (1.0 + nu) * x * x / r2),
                k * (1.0 + nu) * x * y / r2,
            )
        };
        let (x, y, h) = (1.3, -0.7, 1e-5);
        let exx = (u(x + h, y).0 - u(x - h, y).0) / (2.0 * h);
        let eyy = (u(x, y + h).1 - u(x, y - h).1) / (2.0 * h);
        let gxy = (u(x, y + h).0 - u(x, y - h).0 + u(x + h, y).1 - u(x - h, y).1) / (2.0 * h);
        let hooke = [
            e / (1.0 - nu * nu) * (exx + nu * eyy),
            e / (1.0 - nu * nu) * (eyy + nu * exx),
            e / (2.0 * (1.0 + nu)) * gxy,
        ];
        let closed = kelvin_stress((1.0, 0.0), (x, y), 1.0, nu);
        for (a, b) in hooke.iter().zip(closed) {
            assert!((a / b - 1.0).abs() < 1e-6, "{hooke:?} vs {closed:?}");
        }
    }

    #[test]
    fn a_holes_energy_is_kirschs() {
        // Uniaxial σ: ΔU = 1.5·π·r²·t·σ²/E, the dilute E(1 − 3f); equibiaxial: 2·π·r²·t·σ²/E
        // (Betti with Lamé's hole: u⁰ = σa(1 − ν)/E, u_c = σa(1 + ν)/E, ΔU =
        // ½·σ·2πa·t·(u⁰ + u_c)); pure shear τ: 4·π·r²·t·τ²/E.
        let (r, t, e) = (2.0, 3.0, 200_000.0);
        let unit = PI * r * r * t / e;
        assert!((hole_energy([10.0, 0.0, 0.0], r, t, e) / (150.0 * unit) - 1.0).abs() < 1e-14);
        assert!((hole_energy([10.0, 10.0, 0.0], r, t, e) / (200.0 * unit) - 1.0).abs() < 1e-14);
        let betti = 0.5 * 10.0 * 2.0 * PI * r * t * (10.0 * r * (0.7 + 1.3) / e);
        assert!((hole_energy([10.0, 10.0, 0.0], r, t, e) / betti - 1.0).abs() < 1e-14);
        assert!((hole_energy([0.0, 0.0, 10.0], r, t, e) / (400.0 * unit) - 1.0).abs() < 1e-14);
        assert!((hole_energy([10.0, -10.0, 0.0], r, t, e) / (400.0 * unit) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn rv20e_disc_web_by_hand() {
        // Two bores on 27.5 mm, pillar holes at ±90° of radius 11·√2/2 + 0.9 = 8.678175 mm
        // (the pillar's half-diagonal and the disc's orbit e), a disc 8 mm thick.
        // Symmetric mode: unit tangential forces (0, 1) at (27.5, 0) and (0, −1) at
        // (−27.5, 0); the hole at (0, 27.5) sits r = 38.890873 mm from each, 45° off each
        // force's line. In the force's frame scale = 1/(4π·38.890873·8) = 2.557786e-4 MPa,
        // cos θ = ±0.707107: σ'_xx = ∓2.557786e-4·0.707107·(0.7 + 2.6·0.5) = ∓3.617158e-4,
        // σ'_yy = ±2.557786e-4·0.707107·(1.3 − 1.9) = ∓1.085147e-4, τ' = −3.617158e-4;
        // rotated into the plate (the force along y) the two bores give (∓1.085147e-4,
        // ∓3.617158e-4, 3.617158e-4): their sum is pure shear τ = 7.234316e-4 MPa. Kirsch:
        // ΔU = π·8.678175²·8/206 000·4τ² = 1.923465e-8 N·mm per hole, both holes alike,
        // so c_web,S = 2·(2·ΔU)/m = 3.846930e-8 mm/N, 9.1 % of the bore's 4.24227e-7;
        // antisymmetric (x: 3.846930e-8, y: 1.283913e-8, mean over the direction)
        // c_web,A = 2.565422e-8 mm/N.
        let hole = 11.0 * 2f64.sqrt() / 2.0 + 0.9;
        let (s, a) = disc_web_compliance(2, 27.5, 27.5, hole, 8.0, 206_000.0, 0.3);
        let one = kelvin_stress((0.0, 1.0), (-27.5, 27.5), 8.0, 0.3);
        let other = kelvin_stress((0.0, -1.0), (27.5, 27.5), 8.0, 0.3);
        assert!((one[0] + 1.085147e-4).abs() < 1e-10 && (one[1] + 3.617158e-4).abs() < 1e-10);
        assert!((one[2] - 3.617158e-4).abs() < 1e-10 && (other[2] - one[2]).abs() < 1e-15);
        assert!((one[0] + other[0]).abs() < 1e-15 && (one[1] + other[1]).abs() < 1e-15);
        let tau: f64 = 7.234316e-4;
        let per_hole = PI * hole * hole * 8.0 / 206_000.0 * 4.0 * tau * tau;
        assert!((s / (2.0 * per_hole) - 1.0).abs() < 1e-6, "{s}");
        assert!((s / 3.846930e-8 - 1.0).abs() < 1e-6, "{s}");
        assert!((a / 2.565422e-8 - 1.0).abs() < 1e-6, "{a}");
    }

    #[test]
    fn bore_ovalisation_is_the_sum_of_michells_harmonics() {
        // The module comment's closed form against the harmonic sum it comes from:
        // (2/π)·[(1 + ν)/π + Σ_k 2(−1)^(k+1)/(π(4k² − 1))·(4k + 1 − ν)/(4k² − 1)],
        // the n = 2k term p_n·(2n + 1 − ν)/(n² − 1) with p_n/p0 = 2(−1)^(k+1)/(π(4k² − 1)),
        // p0·a/E = 2P/(π·E·t). 200 000 terms: the tail is below 1e-15.
        for nu in [0.0, 0.25, 0.3, 0.45] {
            let series: f64 = (1..200_000)
                .map(|k| {
                    let k = k as f64;
                    let q = 4.0 * k * k - 1.0;
                    2.0 * if k as i64 % 2 == 1 { 1.0 } else { -1.0 } / (PI * q)
                        * (4.0 * k + 1.0 - nu)
                        / q
                })
                .sum();
            let sum = 2.0 / PI * ((1.0 + nu) / PI + series);
            assert!((bore_ovalisation_factor(nu) - sum).abs() < 1e-12, "{nu}");
        }
        // ν = 0.3: (2/π²)·(1.3 + 2·0.415966 + 1.4·0.107301) = 0.202642·2.282151 = 0.462461.
        assert!((bore_ovalisation_factor(0.3) - 0.462461).abs() < 1e-6);
    }

    #[test]
    fn michells_harmonic_displacement_by_finite_differences() {
        // The n ≥ 2 displacement u_r(a) = p·a·(2n + 1 − ν)/(E·(n² − 1)) the factor rests on:
        // Michell's φ = f(r)·cos nθ, f = A·r^−n + B·r^(2−n), decaying at infinity, with
        // σ_rr = f'/r − n²f/r², σ_θθ = f'', τ_rθ = n·(f'/r − f/r²) (times sin nθ); A and B
        // solved from σ_rr(a) = −p, τ_rθ(a) = 0, and u_r(a) = −∫_a^∞ ε_rr dr (plane stress,
        // ε_rr = (σ_rr − ν·σ_θθ)/E) by Simpson's rule on r = a·e^s.
        let (a, p, e, nu) = (10.0_f64, 1.0_f64, 1.0_f64, 0.3_f64);
        for n in [2.0_f64, 3.0, 4.0, 7.0] {
            let coef = |r: f64, aa: f64, bb: f64| {
                let phi = aa * r.powf(-n) + bb * r.powf(2.0 - n);
                let d1 = -n * aa * r.powf(-n - 1.0) + (2.0 - n) * bb * r.powf(1.0 - n);
                let d2 =
                    n * (n + 1.0) * aa * r.powf(-n - 2.0) + (2.0 - n) * (1.0 - n) * bb * r.powf(-n);
                let srr = d1 / r - n * n * phi / (r * r);
                let stt = d2;
                let trt = n * (d1 / r - phi / (r * r));
                (srr, stt, trt)
            };
            // Linear in (A, B): solve σ_rr(a) = −p, τ_rθ(a) = 0.
            let (s1, _, t1) = coef(a, 1.0, 0.0);
            let (s2, _, t2) = coef(a, 0.0, 1.0);
            let det = s1 * t2 - s2 * t1;
            let aa = (-p * t2) / det;
            let bb = (p * t1) / det;
            // ∫_a^∞ ε_rr dr on r = a·e^s (Simpson in s up to s = 30: the tail beyond,
            // about e^−30 of the integral for n = 2, is far below the tolerance).
            let (end, steps) = (30.0, 60_000);
            let h = end / steps as f64;
            let f = |s: f64| {
                let r = a * s.exp();
                let (srr, stt, _) = coef(r, aa, bb);
                (srr - nu * stt) / e * r
            };
            let mut integral = f(0.0) + f(end);
            for i in 1..steps {
                integral += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            integral *= h / 3.0;
            let u = -integral;
            let closed = p * a * (2.0 * n + 1.0 - nu) / (e * (n * n - 1.0));
            assert!((u / closed - 1.0).abs() < 1e-6, "n = {n}: {u} vs {closed}");
        }
    }

    #[test]
    fn ringless_housing_of_an_rv20e_disc() {
        // RV-20E: bore a = 15/2 + 3 = 10.5 mm, rim R = 52 − 27.5 = 24.5 mm, t = 8 mm:
        // ln(24.5/10.5) = 0.84729786, (1.3·2.7)/(4π) = 0.27931693, so
        // c_bore = (0.46246078 + 0.27931693·0.84729786)/(206 000·8) = 0.69912537/1 648 000
        // = 4.242266e-7 mm/N (0.79 µm at the row's 1867 N, beside its 4.99 µm).
        let c = RollerRow::ringless_housing_compliance(10.5, 24.5, 8.0, 206_000.0, 0.3);
        let hand = (0.46246078 + 0.27931693 * 0.84729786) / 1_648_000.0;
        assert!((c / hand - 1.0).abs() < 1e-7, "{c} vs {hand}");
        assert!((c / 4.242266e-7 - 1.0).abs() < 1e-6);
        // A rim no farther than the bore leaves the ovalisation alone.
        let near = RollerRow::ringless_housing_compliance(10.5, 10.0, 8.0, 206_000.0, 0.3);
        assert!((near * 1_648_000.0 - 0.46246078).abs() < 1e-8);
    }
}
