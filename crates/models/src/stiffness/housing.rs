//! The housing around the pin grooves: the pins press the housing's bore outward where the
//! load sharing puts them, and the bore deforms as a whole (docs/models.md §13, "The
//! housing").
//!
//! ```text
//! the housing beside one disc: an infinite plate of the disc's thickness t with a hole of
//! radius r_p (the pin circle); pin i at φ_i presses it with F_i along −n_i
//! (cycloid_pin_contact.rs), radially outward α_i·F_i and along e_φ β_i·F_i,
//!   α_i = (1 − K1·cos φ_i)/S_i,   β_i = K1·sin φ_i/S_i
//! a point force on the hole spreads over its harmonics (1/(2π·a·t) at n = 0,
//! cos n(φ − φ_i)/(π·a·t) at n ≥ 1); the hole's response to each (a = r_p):
//!   n = 0: pressure (Lamé) u_r = P_r(1 + ν)/(2π·E·t); torque u_φ = P_φ(1 + ν)/(2π·E·t)
//!   n ≥ 2 (Michell: Airy φ = (A·r⁻ⁿ + B·r²⁻ⁿ)cos nφ, σ_rr(a) = S cos nφ, τ_rφ(a) = T sin nφ,
//!   displacements decaying at infinity): with A' = A·a⁻ⁿ⁻², B' = B·a⁻ⁿ,
//!     B' = (T − S)/(2(n − 1)),   A' = −(2T + n(T − S))/(2n(n + 1))
//!     u_r = U cos nφ, E·U/a = n(1 + ν)A' + ((n + 2) + ν(n − 2))B'
//!     u_φ = V sin nφ, E·V/a = n(1 + ν)A' + (n(1 + ν) − 4)B'
//!   (for T = 0: U = −S·a(2n + 1 − ν)/(E(n² − 1)), the bore formula of bodies.rs); a
//!   radial force is S = −P_r/(π·a·t) in this family about φ_i, a tangential one T =
//!   P_φ/(π·a·t) in the family turned by a quarter wave (u_r = U sin, u_φ = −V cos)
//!   n = 1, the net force, is not the housing's: the two discs' resultants are opposite and
//!   meet in the housing a face width apart (and the main bearings carry what is left)
//! the harmonics stop at n = z_p/2: shorter waves are the field around each groove, which
//! the pin's own contact (Palmgren, cycloid_pin_contact.rs) already holds.
//! The housing's energy U_h = ½·Σ_i Σ_j F_i·F_j·g_ij (g_ij the displacement at pin i along
//! its force per unit force at pin j, symmetric by Maxwell–Betti) turns the disc, to first
//! order in the housing's compliance (Castigliano, the pins' forces held):
//!   δβ = 2·(U_h(F) − U_h(F_0))/T_c        (F_0 the forces at zero torque: a preload's)
//! ```

use std::f64::consts::PI;

/// One harmonic n with the responses (U, V) to a unit radial and a unit shear traction.
type Harmonic = (f64, (f64, f64), (f64, f64));

/// The housing's influence matrix g_ij for the pins of one disc.
#[derive(Debug, Clone, PartialEq)]
pub struct Housing {
    pins: usize,
    /// g_ij, row-major, mm/N.
    influence: Vec<f64>,
}

/// The housing's displacements (u_r, u_φ) at r = a, per unit radial (S) and shear (T)
/// traction amplitude of harmonic n ≥ 2, times E/a: (U, V) (module comment).
pub fn michell_response(n: f64, normal: f64, shear: f64, poisson: f64) -> (f64, f64) {
    let b = (shear - normal) / (2.0 * (n - 1.0));
    let a = -(2.0 * shear + n * (shear - normal)) / (2.0 * n * (n + 1.0));
    (
        n * (1.0 + poisson) * a + ((n + 2.0) + poisson * (n - 2.0)) * b,
        n * (1.0 + poisson) * a + (n * (1.0 + poisson) - 4.0) * b,
    )
}

impl Housing {
    /// The housing beside a disc of `thickness` around the pin circle `pin_circle_radius`
    /// with `pins` pins and K1 = `curtate` (module comment).
    pub fn new(
        pins: usize,
        pin_circle_radius: f64,
        curtate: f64,
        thickness: f64,
        youngs: f64,
        poisson: f64,
    ) -> Self {
        let a = pin_circle_radius;
        let directions: Vec<(f64, f64)> = (0..pins)
            .map(|i| {
                let phi = 2.0 * PI * i as f64 / pins as f64;
                let s = (1.0 + curtate * curtate - 2.0 * curtate * phi.cos()).sqrt();
                ((1.0 - curtate * phi.cos()) / s, curtate * phi.sin() / s)
            })
            .collect();
        // Per unit force: the displacements (u_r, u_φ) at angular distance d from a radial
        // and from a tangential unit force.
        let lame = (1.0 + poisson) / (2.0 * PI * youngs * thickness);
        let scale = a / youngs / (PI * a * thickness);
        let harmonics: Vec<Harmonic> = (2..=pins / 2)
            .map(|n| {
                let n = n as f64;
                (
                    n,
                    michell_response(n, -1.0, 0.0, poisson),
                    michell_response(n, 0.0, 1.0, poisson),
                )
            })
            .collect();
        let mut influence = vec![0.0; pins * pins];
        for (i, &(ai, bi)) in directions.iter().enumerate() {
            for (j, &(aj, bj)) in directions.iter().enumerate() {
                let d = 2.0 * PI * (i as f64 - j as f64) / pins as f64;
                // At pin i from a unit radial (r) and tangential (t) force at pin j.
                let (mut rr, mut tr, mut rt, mut tt) = (lame, 0.0, 0.0, lame);
                for &(n, (u_s, v_s), (u_t, v_t)) in &harmonics {
                    let (cos, sin) = ((n * d).cos(), (n * d).sin());
                    rr += scale * u_s * cos;
                    tr += scale * v_s * sin;
                    rt += scale * u_t * sin;
                    tt -= scale * v_t * cos;
                }
                influence[i * pins + j] = ai * (rr * aj + rt * bj) + bi * (tr * aj + tt * bj);
            }
        }
        Housing { pins, influence }
    }

    /// g_ij, mm/N.
    pub fn influence(&self, i: usize, j: usize) -> f64 {
        self.influence[i * self.pins + j]
    }

    /// U_h = ½·Σ F_i·F_j·g_ij of the pin forces `forces` (pin order), N·mm; only the
    /// loaded pins' pairs (about half the pins carry load).
    pub fn energy(&self, forces: &[f64]) -> f64 {
        let mut loaded = [0usize; crate::cycloid_pin_contact::MAX_PINS];
        let mut count = 0;
        for (i, &f) in forces.iter().enumerate().take(self.pins) {
            if f != 0.0 {
                loaded[count] = i;
                count += 1;
            }
        }
        let loaded = &loaded[..count];
        let mut sum = 0.0;
        for &i in loaded {
            let row = &self.influence[i * self.pins..(i + 1) * self.pins];
            let inner: f64 = loaded.iter().map(|&j| row[j] * forces[j]).sum();
            sum += forces[i] * inner;
        }
        0.5 * sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn michells_shear_response_by_finite_differences() {
        // The module comment's Airy family with a shear traction on the hole: A, B from
        // σ_rr(a) = S, τ_rφ(a) = T (stresses as in bodies.rs' test), u_r(a) = −∫_a^∞ ε_rr dr
        // by Simpson on r = a·e^s, u_φ from ε_φφ = u_r/r + (1/r)∂u_φ/∂φ at r = a; against
        // michell_response for S = 0 and for T = 0.
        let (a, e, nu) = (10.0_f64, 1.0_f64, 0.3_f64);
        for n in [2.0_f64, 3.0, 5.0] {
            for (s_amp, t_amp) in [(1.0, 0.0), (0.0, 1.0), (-0.4, 0.7)] {
                let coef = |r: f64, aa: f64, bb: f64| {
                    let f = aa * r.powf(-n) + bb * r.powf(2.0 - n);
                    let d1 = -n * aa * r.powf(-n - 1.0) + (2.0 - n) * bb * r.powf(1.0 - n);
                    let d2 = n * (n + 1.0) * aa * r.powf(-n - 2.0)
                        + (2.0 - n) * (1.0 - n) * bb * r.powf(-n);
                    (d1 / r - n * n * f / (r * r), d2, n * (d1 / r - f / (r * r)))
                };
                let (s1, _, t1) = coef(a, 1.0, 0.0);
                let (s2, _, t2) = coef(a, 0.0, 1.0);
                let det = s1 * t2 - s2 * t1;
                let aa = (s_amp * t2 - s2 * t_amp) / det;
                let bb = (s1 * t_amp - t1 * s_amp) / det;
                let (end, steps) = (30.0, 60_000);
                let h = end / steps as f64;
                let g = |x: f64| {
                    let r = a * x.exp();
                    let (srr, stt, _) = coef(r, aa, bb);
                    (srr - nu * stt) / e * r
                };
                let mut integral = g(0.0) + g(end);
                for i in 1..steps {
                    integral += g(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
                }
                let u_r = -integral * h / 3.0;
                let (srr, stt, _) = coef(a, aa, bb);
                let u_phi = (a * (stt - nu * srr) / e - u_r) / n;
                let (big_u, big_v) = michell_response(n, s_amp, t_amp, nu);
                assert!(
                    (u_r - big_u * a / e).abs() < 1e-7,
                    "n {n}: {u_r} vs {big_u}"
                );
                assert!(
                    (u_phi - big_v * a / e).abs() < 1e-7,
                    "n {n}: {u_phi} vs {big_v}"
                );
            }
        }
        // Normal load alone is the bore formula: U = −S(2n + 1 − ν)/(n² − 1).
        let (u, _) = michell_response(3.0, 1.0, 0.0, 0.3);
        assert!((u + (7.0 - 0.3) / 8.0).abs() < 1e-15);
    }

    #[test]
    fn uniform_and_single_harmonic_loads_by_hand() {
        // K1 = 0 makes every pin push radially (α = 1, β = 0). Equal forces F on all 40 pins
        // load only n = 0 (the others cancel up to n = z_p/2): a pressure 40F/(2π·a·t),
        // u_r = 40F(1 + ν)/(2π·E·t), U = ½·40F·u_r = 800·F²·1.3/(2π·E·t) = 1.004376e-4·F²
        // for E = 206 000, t = 8. Forces F·cos 2φ_i load only n = 2: the hole's traction
        // σ_rr = −(40F/(2π·a·t))·cos 2φ, u_r(φ) = (40F/(2π·a·t))·a(5 − ν)/(3E)·cos 2φ, and
        // U = ½·Σ F cos²(2φ_i)·40F(4.7)/(6π·E·t) = ½·20·F²·40·4.7/(6π·206 000·8) =
        // 6.052008e-5·F².
        let (e, t) = (206_000.0, 8.0);
        let housing = Housing::new(40, 52.0, 0.0, t, e, 0.3);
        let uniform = housing.energy(&[1.0; 40]);
        assert!((uniform / (800.0 * 1.3 / (2.0 * PI * e * t)) - 1.0).abs() < 1e-12);
        assert!((uniform / 1.004376e-4 - 1.0).abs() < 1e-6, "{uniform}");
        let wave: Vec<f64> = (0..40)
            .map(|i| (2.0 * 2.0 * PI * i as f64 / 40.0).cos())
            .collect();
        let second = housing.energy(&wave);
        let hand = 0.5 * 20.0 * 40.0 * 4.7 / (6.0 * PI * e * t);
        assert!((second / hand - 1.0).abs() < 1e-12, "{second} vs {hand}");
        assert!((second / 6.052008e-5 - 1.0).abs() < 1e-6, "{second}");
    }

    #[test]
    fn the_influence_is_symmetric_and_its_energy_positive() {
        // Maxwell–Betti: g_ij = g_ji (which checks the families' signs); the energy of any
        // set of pin forces is positive (the n = 0 and n ≥ 2 parts of a hole in an infinite
        // plate are); and the n = 0 part by hand: three pins (no harmonic up to z_p/2 = 1),
        // K1 = 0.7, a unit force on pin 0 (φ = 0: S = 0.3, α = 1, β = 0) stores
        // ½·(1 + ν)/(2π·E·t) = ½·1.3/(2π·206 000·8) = 6.27735e-8 N·mm.
        let housing = Housing::new(40, 52.0, 0.692, 8.0, 206_000.0, 0.3);
        for i in 0..40 {
            for j in 0..40 {
                let (a, b) = (housing.influence(i, j), housing.influence(j, i));
                assert!((a - b).abs() <= 1e-12 * a.abs().max(b.abs()), "{i} {j}");
            }
        }
        let forces: Vec<f64> = (0..40).map(|i| (0.37 * i as f64).sin().max(0.0)).collect();
        assert!(housing.energy(&forces) > 0.0);
        let bare = Housing::new(3, 52.0, 0.7, 8.0, 206_000.0, 0.3);
        let one = bare.energy(&[1.0, 0.0, 0.0]);
        assert!((one / 6.27735e-8 - 1.0).abs() < 1e-5, "{one}");
    }
}
