//! A crank's support bearing: one tapered roller row set against the crank's other support
//! with an axial preload (a shim), under a radial load (docs/models.md §13, "Supports with
//! their preload").
//!
//! ```text
//! roller at azimuth ψ from the load, both contacts in series by Palmgren's law (contact.rs):
//!   normal approach δ_ψ = δ_a·sin α + δ_r·cos α·cos ψ,   Q_ψ = K_n·max(δ_ψ, 0)^(10/9),
//!   K_n = (l^0.8/(2·3.84·10⁻⁵))^(10/9)
//! the row as a continuous ring of Z rollers (Harris & Kotzalas 2007, Ch. 7: the load-zone
//! integrals of Sjövall):
//!   F_r = Z·(1/2π)∫ Q_ψ·cos α·cos ψ dψ,    F_a = Z·(1/2π)∫ Q_ψ·sin α dψ
//! the shim fixes the axial approach at its preloaded value δ_a0 (the crank's two supports
//! set against each other; in the symmetric mode both see the same radial load, so the
//! crank does not move axially): F_a0 = Z·K_n·δ_n0^(10/9)·sin α with δ_n0 = δ_a0·sin α.
//! With x = δ_r·cos α/δ_n0 (x ≤ 1: every roller loaded),
//!   F_r = (F_a0/tan α)·J(x),   J(x) = (1/π)∫₀^ψ_l (1 + x·cos ψ)^(10/9)·cos ψ dψ,
//!   ψ_l = π (x ≤ 1) or arccos(−1/x),   δ_r = x·δ_n0/cos α
//! J(x) = 5x/9 + O(x³) for small x; J(x) → g0·x^(10/9), g0 = (1/π)∫₀^(π/2) cos^(19/9)ψ dψ
//! = 0.244799 = 1/4.0850 for large x (no preload: Stribeck's 4.08, the discrete rows' fit,
//! is kept for F_a0 = 0); J(1) = 0.545495.
//! ```
//!
//! J is tabulated once (ln J against ln x, 1 024 nodes, cubic Hermite with the exact
//! slopes; within 1e-9 of the quadrature for x beyond a factor 2 from 1, 3e-5 next to
//! x = 1, where J'' is singular) and inverted per load: a binary search and two or three
//! Newton steps.

use super::contact::{RollerRow, PALMGREN_LINE};
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Exponent of the roller load in its approach, Q ∝ δ^(10/9) (Palmgren).
const LOAD_EXPONENT: f64 = 10.0 / 9.0;

/// A support row with its axial preload.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaperedRow {
    /// The rollers: count, effective length, contact angle (> 0 when preloaded).
    pub row: RollerRow,
    /// F_a0, the axial preload of the row, N (0: set to zero clearance, no preload).
    pub preload: f64,
}

impl TaperedRow {
    /// δ_n0, each roller's normal approach under the preload alone, mm (module comment).
    pub fn preload_approach(&self) -> f64 {
        let row = &self.row;
        let stiffness = (row.length.powf(0.8) / (2.0 * PALMGREN_LINE)).powf(LOAD_EXPONENT);
        (self.preload / (row.rollers * stiffness * row.contact_angle.sin())).powf(0.9)
    }

    /// Radial deflection δ_r under the radial load `load` (N, ≥ 0), mm: the preloaded
    /// load zone's (module comment), or the unpreloaded row's Stribeck closed form.
    pub fn radial_deflection(&self, load: f64) -> f64 {
        if self.preload <= 0.0 {
            return self.row.radial_deflection(load);
        }
        let alpha = self.row.contact_angle;
        let x = load_zone().inverse(load * alpha.tan() / self.preload);
        x * self.preload_approach() / alpha.cos()
    }

    /// The least preload that keeps every roller of `row` loaded under the radial load
    /// `load`: x = 1 there, F_a0 = F·tan α/J(1), N (module comment).
    pub fn full_zone_preload(row: &RollerRow, load: f64) -> f64 {
        load * row.contact_angle.tan() / load_zone_integral(1.0, false)
    }

    /// Secant radial compliance δ_r(F)/F at the load F > 0; at F = 0 the tangent at zero
    /// load (the preloaded row is linear there; an unpreloaded row's is infinite), mm/N.
    pub fn secant_compliance(&self, load: f64) -> f64 {
        if load > 0.0 || self.preload <= 0.0 {
            return self.radial_deflection(load) / load;
        }
        // dδ_r/dF at 0: δ_r = x·δ_n0/cos α with x = (9/5)·F·tan α/F_a0 (J ≈ 5x/9).
        let alpha = self.row.contact_angle;
        1.8 * alpha.tan() / self.preload * self.preload_approach() / alpha.cos()
    }
}

/// The load-zone function J of the module comment and its inverse.
#[derive(Debug)]
pub(crate) struct LoadZone {
    /// ln x of the nodes (uniform).
    log_x: Vec<f64>,
    /// ln J at the nodes.
    log_j: Vec<f64>,
    /// d ln J/d ln x at the nodes.
    slope: Vec<f64>,
    /// g0 and g1 of J ≈ x^(10/9)·(g0 + g1/x) beyond the last node.
    asymptote: (f64, f64),
}

/// The nodes: ln x_k = (k − FIRST_NODE)·STEP, k < NODES (x from 1.0e-3 to 8.6e4), one of
/// them at x = 1, where J'' is singular (J'' ∝ |1 − x|^(−7/18): the last roller unloads).
const STEP: f64 = 1.0 / 56.0;
const FIRST_NODE: usize = 387;
const NODES: usize = 1024;
const LOG_X_RANGE: (f64, f64) = (
    -(FIRST_NODE as f64) * STEP,
    (NODES - 1 - FIRST_NODE) as f64 * STEP,
);

/// The table, built on first use.
pub(crate) fn load_zone() -> &'static LoadZone {
    static TABLE: OnceLock<LoadZone> = OnceLock::new();
    TABLE.get_or_init(LoadZone::new)
}

impl LoadZone {
    fn new() -> Self {
        let last = LOG_X_RANGE.1;
        let log_x: Vec<f64> = (0..NODES)
            .map(|k| (k as f64 - FIRST_NODE as f64) * STEP)
            .collect();
        let (mut log_j, mut slope) = (Vec::with_capacity(NODES), Vec::with_capacity(NODES));
        for &s in &log_x {
            let x = s.exp();
            let (j, dj) = (load_zone_integral(x, false), load_zone_integral(x, true));
            log_j.push(j.ln());
            slope.push(x * dj / j);
        }
        let g0 = cosine_power_integral();
        let x_last = last.exp();
        let g1 = (log_j[NODES - 1].exp() / x_last.powf(LOAD_EXPONENT) - g0) * x_last;
        LoadZone {
            log_x,
            log_j,
            slope,
            asymptote: (g0, g1),
        }
    }

    /// J(x) from the table (module comment).
    #[cfg(test)]
    pub(crate) fn value(&self, x: f64) -> f64 {
        let s = x.ln();
        if s <= self.log_x[0] {
            return 5.0 / 9.0 * x;
        }
        if s >= self.log_x[NODES - 1] {
            let (g0, g1) = self.asymptote;
            return x.powf(LOAD_EXPONENT) * (g0 + g1 / x);
        }
        let k = self.node_below(s);
        self.hermite(k, s).0.exp()
    }

    /// x with J(x) = j (j ≥ 0).
    pub(crate) fn inverse(&self, j: f64) -> f64 {
        if j <= 0.0 {
            return 0.0;
        }
        let y = j.ln();
        if y <= self.log_j[0] {
            return 1.8 * j;
        }
        if y >= self.log_j[NODES - 1] {
            return self.inverse_asymptote(j);
        }
        // The interval holding y (ln J rises with ln x), then Newton on the cubic.
        let (mut lo, mut hi) = (0, NODES - 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.log_j[mid] <= y {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (a, b) = (self.log_x[lo], self.log_x[hi]);
        let mut s = a + (b - a) * (y - self.log_j[lo]) / (self.log_j[hi] - self.log_j[lo]);
        for _ in 0..8 {
            let (value, derivative) = self.hermite(lo, s);
            let next = (s - (value - y) / derivative).clamp(a, b);
            let done = (next - s).abs() <= 1e-15 * (1.0 + s.abs());
            s = next;
            if done {
                break;
            }
        }
        s.exp()
    }

    /// Newton on x^(10/9)·(g0 + g1/x) = j from the leading term.
    fn inverse_asymptote(&self, j: f64) -> f64 {
        let (g0, g1) = self.asymptote;
        let mut x = (j / g0).powf(0.9);
        for _ in 0..20 {
            let f = x.powf(LOAD_EXPONENT) * (g0 + g1 / x) - j;
            let df = x.powf(1.0 / 9.0) * (LOAD_EXPONENT * g0 + g1 / (9.0 * x));
            let next = x - f / df;
            let done = (next - x).abs() <= 1e-15 * x;
            x = next;
            if done {
                break;
            }
        }
        x
    }

    /// The node at or below ln x = s (inside the table).
    #[cfg(test)]
    fn node_below(&self, s: f64) -> usize {
        let k = ((s - LOG_X_RANGE.0) / STEP).floor() as usize;
        k.min(NODES - 2)
    }

    /// The cubic Hermite interpolant of ln J on [s_k, s_(k+1)] at s: (value, d/ds).
    fn hermite(&self, k: usize, s: f64) -> (f64, f64) {
        let h = self.log_x[k + 1] - self.log_x[k];
        let t = (s - self.log_x[k]) / h;
        let (y0, y1) = (self.log_j[k], self.log_j[k + 1]);
        let (m0, m1) = (self.slope[k] * h, self.slope[k + 1] * h);
        let (t2, t3) = (t * t, t * t * t);
        let value = (2.0 * t3 - 3.0 * t2 + 1.0) * y0
            + (t3 - 2.0 * t2 + t) * m0
            + (-2.0 * t3 + 3.0 * t2) * y1
            + (t3 - t2) * m1;
        let derivative = ((6.0 * t2 - 6.0 * t) * y0
            + (3.0 * t2 - 4.0 * t + 1.0) * m0
            + (-6.0 * t2 + 6.0 * t) * y1
            + (3.0 * t2 - 2.0 * t) * m1)
            / h;
        (value, derivative)
    }
}

/// J(x), or dJ/dx = (1/π)∫ (10/9)·(1 + x·cos ψ)^(1/9)·cos²ψ dψ with `derivative`, over
/// the loaded arc (module comment).
pub(crate) fn load_zone_integral(x: f64, derivative: bool) -> f64 {
    let end = if x <= 1.0 { PI } else { (-1.0 / x).acos() };
    let integrand = |psi: f64| {
        let c = psi.cos();
        let v = (1.0 + x * c).max(0.0);
        if derivative {
            LOAD_EXPONENT * v.powf(1.0 / 9.0) * c * c
        } else {
            v.powf(LOAD_EXPONENT) * c
        }
    };
    arc_integral(&integrand, end) / PI
}

/// g0 = (1/π)∫₀^(π/2) cos^(19/9)ψ dψ.
fn cosine_power_integral() -> f64 {
    arc_integral(&|psi: f64| psi.cos().max(0.0).powf(19.0 / 9.0), 0.5 * PI) / PI
}

/// ∫₀^end f(ψ) dψ for an f that vanishes at `end` like a power of (end − ψ): with
/// ψ = end·(1 − (1 − u)⁴) the integrand becomes smooth there, then 32 panels of eight-point
/// Gauss–Legendre in u.
fn arc_integral(f: &dyn Fn(f64) -> f64, end: f64) -> f64 {
    const NODES: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const WEIGHTS: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    const PANELS: usize = 32;
    let h = 1.0 / PANELS as f64;
    let mut sum = 0.0;
    for panel in 0..PANELS {
        let centre = (panel as f64 + 0.5) * h;
        for (node, weight) in NODES.iter().zip(WEIGHTS) {
            for u in [centre - 0.5 * h * node, centre + 0.5 * h * node] {
                let rest = 1.0 - u;
                let psi = end * (1.0 - rest.powi(4));
                sum += weight * 0.5 * h * f(psi) * 4.0 * end * rest.powi(3);
            }
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Γ(z) for z > 0.5 (Lanczos, g = 7, nine coefficients: 15 digits).
    fn gamma(z: f64) -> f64 {
        const G: [f64; 9] = [
            0.999_999_999_999_809_9,
            676.520_368_121_885_1,
            -1_259.139_216_722_402_8,
            771.323_428_777_653_1,
            -176.615_029_162_140_6,
            12.507_343_278_686_905,
            -0.138_571_095_265_720_12,
            9.984_369_578_019_572e-6,
            1.505_632_735_149_311_6e-7,
        ];
        let z = z - 1.0;
        let t = z + 7.5;
        let sum: f64 = G[0] + (1..9).map(|i| G[i] / (z + i as f64)).sum::<f64>();
        (2.0 * PI).sqrt() * t.powf(z + 0.5) * (-t).exp() * sum
    }

    /// Wallis' integral ∫₀^(π/2) cos^p u du = (√π/2)·Γ((p + 1)/2)/Γ(p/2 + 1).
    fn wallis(p: f64) -> f64 {
        0.5 * PI.sqrt() * gamma(0.5 * (p + 1.0)) / gamma(0.5 * p + 1.0)
    }

    #[test]
    fn load_zone_function_against_wallis_integrals() {
        // Hand calculation (module comment): for large x, J/x^(10/9) → g0 =
        // (1/π)·W(19/9) = 0.244799 (1/g0 = 4.0850, Stribeck's continuous factor); at x = 1,
        // with 1 + cos ψ = 2cos²(ψ/2), J(1) = (2^(19/9)/π)·(2·W(38/9) − W(20/9)) = 0.545495;
        // for small x, J = 5x/9.
        assert!((gamma(5.0) - 24.0).abs() < 1e-12 && (gamma(0.5) - PI.sqrt()).abs() < 1e-14);
        let g0 = wallis(19.0 / 9.0) / PI;
        let j1 = 2f64.powf(19.0 / 9.0) / PI * (2.0 * wallis(38.0 / 9.0) - wallis(20.0 / 9.0));
        assert!((g0 - 0.244_799).abs() < 1e-6 && (j1 - 0.545_495).abs() < 1e-6);
        let table = load_zone();
        assert!(
            (table.asymptote.0 / g0 - 1.0).abs() < 1e-10,
            "{:?}",
            table.asymptote
        );
        assert!((load_zone_integral(1.0, false) / j1 - 1.0).abs() < 1e-11);
        assert!((table.value(1.0) / j1 - 1.0).abs() < 1e-11);
        assert!((table.value(1e-4) / (5e-4 / 9.0) - 1.0).abs() < 1e-8);
        assert!((table.value(1e7) / (g0 * 1e7f64.powf(10.0 / 9.0)) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_table_inverts_the_integral() {
        // Between the nodes and beyond them: J(inverse(J(x))) = J(x) and the interpolant
        // stays within 1e-9 of the quadrature, 5e-5 for x within a factor 2 of 1 (J'' is
        // singular at x = 1: there the cubic's error falls as h^1.6 only).
        let table = load_zone();
        for x in [
            2e-4_f64, 0.013, 0.37, 0.8, 0.99, 0.999, 1.0, 1.001, 1.01, 1.3, 2.815, 47.3, 812.0,
            3e4, 4e5,
        ] {
            let tolerance = if x.ln().abs() < 0.7 { 5e-5 } else { 1e-9 };
            let exact = load_zone_integral(x, false);
            assert!((table.value(x) / exact - 1.0).abs() < tolerance, "{x}");
            assert!((table.inverse(exact) / x - 1.0).abs() < tolerance, "{x}");
        }
        assert_eq!(table.inverse(0.0), 0.0);
    }

    #[test]
    fn preloaded_rv20e_support_by_hand() {
        // The RV-20E support (30202 size: 13 rollers of 8.225 mm at 13°) with 300 N of
        // preload under its rated reaction 1507.88 N (tests/stiffness.rs). K_n =
        // (8.225^0.8/7.68e-5)^(10/9) = 2.428147e5 N/mm^(10/9); δ_n0 = (300/(13·K_n·sin 13°))^0.9
        // = 9.18826e-4 mm; J(x) = 1507.88·tan 13°/300 = 1.160402 at x = 2.81538; δ_r =
        // x·δ_n0/cos 13° = 2.65489e-3 mm (unpreloaded: 3.82165e-3 mm). At zero load the
        // row is linear: 1.8·tan 13°/300·δ_n0/cos 13° = 1.306245e-6 mm/N.
        let row = TaperedRow {
            row: RollerRow {
                rollers: 13.0,
                length: 8.225,
                contact_angle: 13f64.to_radians(),
            },
            preload: 300.0,
        };
        assert!((row.preload_approach() / 9.18826e-4 - 1.0).abs() < 1e-5);
        let x = load_zone().inverse(1507.8756 * 13f64.to_radians().tan() / 300.0);
        assert!((x / 2.81538 - 1.0).abs() < 1e-5, "{x}");
        assert!((row.radial_deflection(1507.8756) / 2.65489e-3 - 1.0).abs() < 1e-5);
        assert!((row.secant_compliance(0.0) / 1.306245e-6 - 1.0).abs() < 1e-5);
        let free = TaperedRow {
            preload: 0.0,
            ..row
        };
        assert_eq!(
            free.radial_deflection(1507.8756),
            row.row.radial_deflection(1507.8756)
        );
        assert!((free.radial_deflection(1507.8756) / 3.82165e-3 - 1.0).abs() < 1e-5);
    }

    #[test]
    fn the_continuous_ring_is_the_limit_of_the_discrete_rollers() {
        // 3 600 rollers of a thirteen-roller row's total stiffness (K per roller ×13/3600),
        // the axial approach held at the preload's: the discrete sum
        // F_r = Σ K·max(δ_n0 + δ_r·cos α·cos ψ_j, 0)^(10/9)·cos α·cos ψ_j, solved for δ_r by
        // bisection, agrees with the table to 1e-6 at light and heavy loads.
        let row = TaperedRow {
            row: RollerRow {
                rollers: 13.0,
                length: 8.225,
                contact_angle: 13f64.to_radians(),
            },
            preload: 300.0,
        };
        let (cos, n0) = (row.row.contact_angle.cos(), row.preload_approach());
        let per_roller =
            (8.225f64.powf(0.8) / (2.0 * PALMGREN_LINE)).powf(LOAD_EXPONENT) * 13.0 / 3600.0;
        let force = |radial: f64| -> f64 {
            (0..3600)
                .map(|j| (2.0 * PI * j as f64 / 3600.0).cos())
                .map(|c| {
                    per_roller * (n0 + radial * cos * c).max(0.0).powf(LOAD_EXPONENT) * cos * c
                })
                .sum()
        };
        for load in [20.0, 400.0, 1507.8756, 9000.0] {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if force(mid) < load {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let discrete = 0.5 * (lo + hi);
            let continuous = row.radial_deflection(load);
            assert!(
                (continuous / discrete - 1.0).abs() < 1e-6,
                "{load}: {continuous} vs {discrete}"
            );
        }
    }
}
