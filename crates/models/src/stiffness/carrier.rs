//! The carrier's wind-up: its pillars between the output flange and the end plate, each
//! on elastic roots in the plates (docs/models.md §13).
//!
//! ```text
//! n_p pillars (width b tangential, depth h radial, length L_p, on the radius r_p), each
//! clamped in both plates (a fixed–guided beam) and twisting:
//!   K_c = n_p·r_p²/(L_p³/(12·E·h·b³/12) + L_p/(κ_r·G·b·h)) + n_p·G·J_p/L_p
//!   κ_r = 5/6 (rectangle), J_p = β·max(b,h)·min(b,h)³, β from Roark Table 10.7 case 4;
//! each root is the pillar's section as a rigid footing on an elastic half-space (sliding
//! Bycroft 1956, rocking Borowicka 1943, twisting Reissner & Sagoci 1944; Gazetas 1991
//! Table 1, equivalent radii of Richart, Hall & Woods 1970):
//!   K_h = 8·G·R_h/(2 − ν),       R_h = √(b·h/π)
//!   K_r = 8·G·R_r³/(3(1 − ν)),   R_r = (4·I/π)^¼, I = h·b³/12 (rocking in the tangential plane)
//!   K_t = 16·G·R_t³/3,           R_t = (2·I_p/π)^¼, I_p = b·h·(b² + h²)/12
//! with both roots alike the pillar still bends about its middle (moment F·L_p/2 at each
//! root), so a pillar on its roots has the lateral and twist compliances
//!   c_lat = L_p³/(12·E·I) + L_p/(κ_r·G·b·h) + 2/K_h + L_p²/(2·K_r),   c_tw = L_p/(G·J_p) + 2/K_t
//!   K_c = n_p·(r_p²/c_lat + 1/c_tw)
//! the end plate is bolted to the pillars' ends (joint.rs) and bends around them
//! (plate.rs): its root adds, per pillar, a sliding s_B, a rocking r_B and a twisting t_B
//! compliance to the half-space's, so the pillar's ends differ (A: the output flange, the
//! pillar grown out of it; B: the end plate). A fixed–guided beam with end rotational
//! compliances c_A, c_B (Castigliano, the end moment M_A the redundant; a = L_p/(E·I)):
//!   M_A = F·L_p·(a/2 + c_B)/(a + c_A + c_B)
//!   δ/F = L_p³/(3·E·I) + c_B·L_p² − L_p²·(a/2 + c_B)²/(a + c_A + c_B)
//! (= L_p³/(12·E·I) + c·L_p²/2 for c_A = c_B = c), so
//!   c_lat = δ/F + L_p/(κ_r·G·b·h) + 2/K_h + s_B,   c_A = 1/K_r,   c_B = 1/K_r + r_B
//!   c_tw = L_p/(G·J_p) + 2/K_t + t_B
//! ```

use super::joint::EndCompliance;
use std::f64::consts::PI;

/// The carrier's pillars between its output flange and its second plate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Carrier {
    /// n_p, pillars.
    pub pillars: f64,
    /// r_p, radius of the pillars' centres, mm.
    pub radius: f64,
    /// b, pillar width in the tangential direction, mm.
    pub width: f64,
    /// h, pillar depth in the radial direction, mm.
    pub depth: f64,
    /// L_p, free pillar length between the plates, mm.
    pub length: f64,
}

impl Carrier {
    /// K_c, torsional stiffness between the two plates, N·mm/rad (module comment).
    pub fn torsional_stiffness(&self, youngs: f64, poisson: f64) -> f64 {
        let shear_modulus = youngs / (2.0 * (1.0 + poisson));
        let (b, h, length) = (self.width, self.depth, self.length);
        let inertia = h * b.powi(3) / 12.0;
        let lateral = 1.0
            / (length.powi(3) / (12.0 * youngs * inertia)
                + length / (5.0 / 6.0 * shear_modulus * b * h));
        let (long, short) = (b.max(h), b.min(h));
        let twist = rectangle_torsion_factor(long / short) * long * short.powi(3);
        self.pillars * (self.radius * self.radius * lateral + shear_modulus * twist / length)
    }

    /// The compliances of one pillar root (module comment): (1/K_h sliding, mm/N; 1/K_r
    /// rocking in the tangential plane and 1/K_t twisting, rad per N·mm), its section a
    /// rigid footing on an elastic half-space of E (MPa) and ν.
    pub fn root_compliances(&self, youngs: f64, poisson: f64) -> (f64, f64, f64) {
        let shear_modulus = youngs / (2.0 * (1.0 + poisson));
        let (b, h) = (self.width, self.depth);
        let sliding_radius = (b * h / PI).sqrt();
        let rocking_radius = (4.0 * h * b.powi(3) / 12.0 / PI).powf(0.25);
        let twisting_radius = (2.0 * b * h * (b * b + h * h) / 12.0 / PI).powf(0.25);
        (
            (2.0 - poisson) / (8.0 * shear_modulus * sliding_radius),
            3.0 * (1.0 - poisson) / (8.0 * shear_modulus * rocking_radius.powi(3)),
            3.0 / (16.0 * shear_modulus * twisting_radius.powi(3)),
        )
    }

    /// K_c with each pillar on its two elastic roots, N·mm/rad (module comment).
    pub fn torsional_stiffness_on_elastic_roots(&self, youngs: f64, poisson: f64) -> f64 {
        self.torsional_stiffness_with_end_plate(youngs, poisson, &EndCompliance::default())
    }

    /// K_c with each pillar on its two elastic roots and the end plate's extra compliances
    /// `end` at its B end (joint and plate), N·mm/rad (module comment).
    pub fn torsional_stiffness_with_end_plate(
        &self,
        youngs: f64,
        poisson: f64,
        end: &EndCompliance,
    ) -> f64 {
        let shear_modulus = youngs / (2.0 * (1.0 + poisson));
        let (b, h, length) = (self.width, self.depth, self.length);
        let (sliding, rocking, twisting) = self.root_compliances(youngs, poisson);
        let bending = youngs * h * b.powi(3) / 12.0;
        let lateral = guided_beam_compliance(length, bending, rocking, rocking + end.rocking)
            + length / (5.0 / 6.0 * shear_modulus * b * h)
            + 2.0 * sliding
            + end.sliding;
        let (long, short) = (b.max(h), b.min(h));
        let twist = rectangle_torsion_factor(long / short) * long * short.powi(3);
        let twist_compliance = length / (shear_modulus * twist) + 2.0 * twisting + end.twisting;
        self.pillars * (self.radius * self.radius / lateral + 1.0 / twist_compliance)
    }
}

/// δ/F of a fixed–guided beam of length `length` and bending rigidity E·I `bending` whose
/// ends rotate against the compliances `end_a` and `end_b` (rad per N·mm), mm/N (module
/// comment).
pub fn guided_beam_compliance(length: f64, bending: f64, end_a: f64, end_b: f64) -> f64 {
    let a = length / bending;
    let l2 = length * length;
    length * l2 / (3.0 * bending) + end_b * l2
        - l2 * (0.5 * a + end_b).powi(2) / (a + end_a + end_b)
}

/// β of a solid rectangle's torsion constant J = β·a·b³ (a ≥ b), Roark & Young Table 10.7
/// case 4: β = 1/3 − 0.21·(b/a)·(1 − (b/a)⁴/12).
fn rectangle_torsion_factor(aspect: f64) -> f64 {
    let ratio = 1.0 / aspect;
    1.0 / 3.0 - 0.21 * ratio * (1.0 - ratio.powi(4) / 12.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unequal_ends_of_a_guided_beam() {
        // Equal ends give the symmetric L³/(12EI) + c·L²/2; rigid ends L³/(12EI); a free
        // end B (c_B → ∞) the cantilever L³/(3EI) + c_A·L²; and Castigliano by hand for
        // L = 19, EI = 2.51337e8 (11 × 11 steel), c_A = 1.33894e-8, c_B = 1.5e-8:
        // a = 7.55957e-8, M_A/(F·L) = (3.77978e-8 + 1.5e-8)/(7.55957e-8 + 2.83894e-8) =
        // 0.507744, δ/F = 9.09668e-6 + 5.415e-6 − 361·(5.27978e-8)²/1.039851e-7 =
        // 4.83406e-6 mm/N.
        let (l, ei): (f64, f64) = (19.0, 206_000.0 * 1220.0833333);
        let c = 1.33894e-8;
        let symmetric = l.powi(3) / (12.0 * ei) + c * l * l / 2.0;
        assert!((guided_beam_compliance(l, ei, c, c) / symmetric - 1.0).abs() < 1e-12);
        assert!(
            (guided_beam_compliance(l, ei, 0.0, 0.0) / (l.powi(3) / (12.0 * ei)) - 1.0).abs()
                < 1e-12
        );
        let cantilever = l.powi(3) / (3.0 * ei) + c * l * l;
        assert!((guided_beam_compliance(l, ei, c, 1.0) / cantilever - 1.0).abs() < 1e-6);
        let hand = guided_beam_compliance(l, ei, c, 1.5e-8);
        assert!((hand / 4.83406e-6 - 1.0).abs() < 1e-5, "{hand}");
        // The end plate's extra compliance at B softens the carrier, the flange end kept.
        let carrier = Carrier {
            pillars: 2.0,
            radius: 27.5,
            width: 11.0,
            depth: 11.0,
            length: 19.0,
        };
        let plain = carrier.torsional_stiffness_on_elastic_roots(206_000.0, 0.3);
        let end = EndCompliance {
            sliding: 2.2e-8,
            rocking: 1.5e-9,
            twisting: 9.2e-10,
        };
        assert!(carrier.torsional_stiffness_with_end_plate(206_000.0, 0.3, &end) < plain);
    }
    #[test]
    fn carrier_pillars_as_fixed_guided_beams() {
        // Two 11 × 11 mm pillars, 18 mm long, on 27.5 mm: lateral stiffness per pillar
        // 1/(L³/(12EI) + L/(κGA)) with I = 11⁴/12 = 1220.08 mm⁴.
        let carrier = Carrier {
            pillars: 2.0,
            radius: 27.5,
            width: 11.0,
            depth: 11.0,
            length: 18.0,
        };
        let (e, g) = (206_000.0, 206_000.0 / 2.6);
        let lateral =
            1.0 / (18f64.powi(3) / (12.0 * e * 1220.0833) + 18.0 / (5.0 / 6.0 * g * 121.0));
        // Square section: β = 1/3 − 0.21·(1 − 1/12) = 0.140833 (Roark: 0.141).
        let twist = 0.140833 * 11f64.powi(4);
        let hand = 2.0 * (27.5 * 27.5 * lateral + g * twist / 18.0);
        let k = carrier.torsional_stiffness(e, 0.3);
        assert!((k / hand - 1.0).abs() < 1e-5, "{k} vs {hand}");
    }

    #[test]
    fn pillar_roots_as_rigid_footings_on_a_half_space() {
        // 11 × 11 mm pillar (RV-20E), E = 206 000 MPa, ν = 0.3, G = 79 230.77 MPa.
        // Sliding: R_h = √(121/π) = 6.20609 mm, K_h = 8·G·6.20609/1.7 = 2.31394e6 N/mm.
        // Rocking: I = 11⁴/12 = 1220.083 mm⁴, R_r = (4I/π)^¼ = 6.27805 mm,
        // K_r = 8·G·6.27805³/(3·0.7) = 7.46860e7 N·mm/rad.
        // Twisting: I_p = 2·I, R_t = (2·I_p/π)^¼ = R_r for a square, K_t = 16·G·R_t³/3
        // = 1.04560e8 N·mm/rad.
        let carrier = Carrier {
            pillars: 2.0,
            radius: 27.5,
            width: 11.0,
            depth: 11.0,
            length: 19.0,
        };
        let (e, nu) = (206_000.0_f64, 0.3_f64);
        let g = e / 2.6;
        let r_h = (121.0 / PI).sqrt();
        let r_r = (4.0 * 1220.0833333 / PI).powf(0.25);
        let r_t = (2.0 * 2440.1666667 / PI).powf(0.25);
        assert!((r_h - 6.20609).abs() < 1e-5 && (r_r - 6.27805).abs() < 1e-5);
        let (sliding, rocking, twisting) = carrier.root_compliances(e, nu);
        assert!((sliding * 8.0 * g * r_h / 1.7 - 1.0).abs() < 1e-9);
        assert!((1.0 / sliding / 2.31394e6 - 1.0).abs() < 1e-5);
        assert!((1.0 / rocking / 7.46860e7 - 1.0).abs() < 1e-5);
        assert!((1.0 / twisting / 1.04560e8 - 1.0).abs() < 1e-5);
        assert!((rocking * 8.0 * g * r_r.powi(3) / 2.1 - 1.0).abs() < 1e-9);
        assert!((twisting * 16.0 * g * r_t.powi(3) / 3.0 - 1.0).abs() < 1e-9);
        // The half-space root is stiffer than O'Donnell's (1960) plane-stress root of the
        // same section, a slab of the pillar's width: 1/K_r = 3.67/(E·a³) here against
        // 16.67/π = 5.31 per E·b·h².
        let odonnell = 16.67 / (PI * e * 11f64.powi(3));
        assert!(
            rocking < odonnell && rocking > 0.6 * odonnell,
            "{rocking} {odonnell}"
        );
        // K_c on the roots: lateral 1/K_lat = 19³/(12EI) + 19/((5/6)G·121) + 2/K_h
        // + 19²/2·(1/K_r) = 4.65241e-6 + 8.6433e-7 + 2.41678e-6 = 7.93352e-6 mm/N, twist
        // 19/(G·J) + 2/K_t; the roots add 70.5 % to the pillar's lateral compliance.
        let lateral_rigid =
            19f64.powi(3) / (12.0 * e * 1220.0833333) + 19.0 / (5.0 / 6.0 * g * 121.0);
        let lateral = lateral_rigid + 2.0 * sliding + 0.5 * 361.0 * rocking;
        assert!(
            (lateral / 7.93352e-6 - 1.0).abs() < 1e-5
                && (lateral / lateral_rigid - 1.70525).abs() < 1e-4,
            "{}",
            lateral / lateral_rigid
        );
        let twist = 0.140833 * 11f64.powi(4);
        let hand = 2.0 * (27.5 * 27.5 / lateral + 1.0 / (19.0 / (g * twist) + 2.0 * twisting));
        let k = carrier.torsional_stiffness_on_elastic_roots(e, nu);
        assert!((k / hand - 1.0).abs() < 1e-5, "{k} vs {hand}");
        assert!(k < carrier.torsional_stiffness(e, nu));
    }
}
