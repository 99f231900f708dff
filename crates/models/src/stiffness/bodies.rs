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
//! adds its ovalisation, c_seat = c_oval/(E·B), in series with the row.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stiffness::RollerRow;
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
