//! The bolted joint between a carrier pillar and the end plate: one bolt on the pillar's
//! axis clamps the pillar's end face to the plate, and the joint's rough, ground faces
//! add their own compliance to the pillar's root in the plate (docs/models.md §13, "The
//! end plate").
//!
//! ```text
//! bolt preload (VDI 2230 Part 1, 2015, §5.5.1: assembly preload at 90 % of the yield
//! point, torque-controlled, property class 12.9, R_p0.2 = 1 100 MPa (ISO 898-1), thread
//! friction μ_G = 0.12; ISO 724 thread: d2 = d − 0.649519·P, d3 = d − 1.226869·P):
//!   F_M = A_S·0.9·R_p0.2/√(1 + 3·(1.5·(d2/d_S)·(P/(π·d2) + 1.155·μ_G))²),
//!   d_S = (d2 + d3)/2, A_S = π·d_S²/4
//! (checked against VDI 2230's tabulated M8×1, 12.9, μ 0.12: 34.7 kN)
//! contact: the pillar's end face b × h less the bolt's clearance hole d_h (ISO 273,
//! medium), A_j = b·h − π·d_h²/4; VDI 2230's deformation cone from the head (ISO 4762
//! head diameter d_k) through the plate of thickness t (tan φ = 0.348, its least value
//! for a tapped joint) spreads to d_k + 2·t·0.348 at the joint, wider than the face at
//! the three sizes, so the whole face is pressed (a narrower cone would press
//! π·(d_k + 2·t·0.348)²/4 of it): p = F_M/A_j
//! joint surface (Ito 2008, Table 6-5, after Ito & Tsutsumi: ground S45C faces, average of
//! eight specimens, δ in µm with p in MPa): δ = C·p^m, C = 0.046, m = 0.48, so the normal
//! stiffness per area is k_n = dp/dδ = p^(1 − m)/(C·m)   (N/(mm²·µm))
//! tangential (Campañá, Persson & Müser 2011, as Mindlin 1949 for one contact):
//!   k_t = k_n·2(1 − ν)/(2 − ν)
//! the pillar's end, per pillar:
//!   rocking in the tangential plane 1/(k_n·I_j), I_j = h·b³/12 − π·d_h⁴/64
//!   sliding 1/(k_t·A_j),  twisting 1/(k_t·J_j), J_j = b·h·(b² + h²)/12 − π·d_h⁴/32
//! ```
//!
//! The pressure at these sizes (100–130 MPa) lies beyond Ito's specimens (up to about
//! 28 MPa); the power law is extrapolated, and C, m scatter by about 2 between specimens:
//! both are parameters. Embedding loosens the preload by a few per cent; the joint's
//! compliances scale as F_M^(m − 1).

use std::f64::consts::PI;

/// Metric coarse threads the end plate's bolt is chosen from: (d, pitch P (ISO 261),
/// clearance hole d_h (ISO 273, medium), socket head diameter d_k (ISO 4762)), mm.
pub const BOLTS: [(f64, f64, f64, f64); 5] = [
    (4.0, 0.7, 4.5, 7.0),
    (5.0, 0.8, 5.5, 8.5),
    (6.0, 1.0, 6.6, 10.0),
    (8.0, 1.25, 9.0, 13.0),
    (10.0, 1.5, 11.0, 16.0),
];

/// R_p0.2 of property class 12.9, MPa (ISO 898-1).
pub const YIELD_12_9: f64 = 1100.0;
/// μ_G, thread friction of VDI 2230's tables for lightly oiled black-oxide bolts.
pub const THREAD_FRICTION: f64 = 0.12;
/// VDI 2230's utilisation of the yield point at assembly, ν.
pub const YIELD_UTILISATION: f64 = 0.9;
/// The least tan φ of VDI 2230's deformation cone for a tapped-thread joint.
pub const CONE_TAN_MIN: f64 = 0.348;
/// Ito's Table 6-5, ground S45C joints, average: δ = C·p^m (µm, MPa).
pub const ITO_COEFFICIENT: f64 = 0.046;
/// Ito's Table 6-5 exponent m.
pub const ITO_EXPONENT: f64 = 0.48;

/// The rule of docs/models.md §13: the largest bolt of [`BOLTS`] whose diameter is at most
/// half the pillar's smaller side; `None` when even the smallest is too large.
pub fn bolt_for_pillar(width: f64, depth: f64) -> Option<(f64, f64, f64, f64)> {
    BOLTS
        .iter()
        .rev()
        .find(|bolt| bolt.0 <= 0.5 * width.min(depth))
        .copied()
}

/// VDI 2230's assembly preload F_M of a 12.9 bolt of diameter `d` and pitch `pitch` at
/// the thread friction `friction`, N (module comment).
pub fn assembly_preload(d: f64, pitch: f64, friction: f64) -> f64 {
    let d2 = d - 0.649_519 * pitch;
    let d3 = d - 1.226_869 * pitch;
    let ds = 0.5 * (d2 + d3);
    let area = PI * ds * ds / 4.0;
    let torsion = 1.5 * d2 / ds * (pitch / (PI * d2) + 1.155 * friction);
    area * YIELD_UTILISATION * YIELD_12_9 / (1.0 + 3.0 * torsion * torsion).sqrt()
}

/// The joint between one pillar's end face and the end plate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoltedJoint {
    /// b, the face's width across the radius, mm.
    pub width: f64,
    /// h, the face's depth along the radius, mm.
    pub depth: f64,
    /// d_h, the bolt's clearance hole, mm.
    pub hole: f64,
    /// VDI 2230's deformation cone's diameter at the joint, d_k + 2·t·tan φ, mm.
    pub cone: f64,
    /// F_M, the bolt's preload, N.
    pub preload: f64,
    /// C of δ = C·p^m, µm/MPa^m.
    pub coefficient: f64,
    /// m of δ = C·p^m.
    pub exponent: f64,
}

/// The joint's compliances at the pillar's end: (sliding mm/N, rocking and twisting rad
/// per N·mm).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EndCompliance {
    /// Tangential sliding of the end, mm/N.
    pub sliding: f64,
    /// Rocking in the tangential plane, rad per N·mm.
    pub rocking: f64,
    /// Twisting about the pillar's axis, rad per N·mm.
    pub twisting: f64,
}

impl BoltedJoint {
    /// A_j, the pressed area: the face within the cone, less the hole, mm².
    pub fn area(&self) -> f64 {
        let face = (self.width * self.depth).min(PI * self.cone * self.cone / 4.0);
        face - PI * self.hole * self.hole / 4.0
    }

    /// p = F_M/A_j, MPa.
    pub fn pressure(&self) -> f64 {
        self.preload / self.area()
    }

    /// k_n = p^(1 − m)/(C·m), N/mm³ (Ito's N/(mm²·µm) × 1 000).
    pub fn normal_stiffness(&self) -> f64 {
        1000.0 * self.pressure().powf(1.0 - self.exponent) / (self.coefficient * self.exponent)
    }

    /// The joint's sliding, rocking and twisting compliances (module comment).
    pub fn compliance(&self, poisson: f64) -> EndCompliance {
        let (b, h, d) = (self.width, self.depth, self.hole);
        let normal = self.normal_stiffness();
        let tangential = normal * 2.0 * (1.0 - poisson) / (2.0 - poisson);
        let rocking_inertia = h * b.powi(3) / 12.0 - PI * d.powi(4) / 64.0;
        let polar = b * h * (b * b + h * h) / 12.0 - PI * d.powi(4) / 32.0;
        EndCompliance {
            sliding: 1.0 / (tangential * self.area()),
            rocking: 1.0 / (normal * rocking_inertia),
            twisting: 1.0 / (tangential * polar),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vdi_2230_preload_reproduces_its_table() {
        // VDI 2230 (2001 edition's table, fine thread M8×1, 12.9, μ_G 0.12, 90 % of the
        // yield point): 34.7 kN. d2 = 7.350481, d3 = 6.773131, d_S = 7.061806, A_S =
        // 39.1671 mm²; 1.5·(d2/d_S)·(1/(π·d2) + 0.1386) = 0.284011; F_M = 39.1671·990/
        // √(1 + 3·0.284011²) = 34 794 N, within 0.3 % of the table (its A_S is rounded).
        let fine = assembly_preload(8.0, 1.0, THREAD_FRICTION);
        assert!((fine / 34_793.5 - 1.0).abs() < 1e-5, "{fine}");
        assert!((fine / 34_700.0 - 1.0).abs() < 3e-3);
        // The coarse sizes the rule picks: M5 (P 0.8) 12 378.5 N, M6 (P 1) 17 500.2 N, M8
        // (P 1.25) 32 015.7 N, by the same formula.
        for (d, p, hand) in [
            (5.0, 0.8, 12_378.5),
            (6.0, 1.0, 17_500.2),
            (8.0, 1.25, 32_015.7),
        ] {
            let f = assembly_preload(d, p, THREAD_FRICTION);
            assert!((f / hand - 1.0).abs() < 1e-5, "M{d}: {f}");
        }
    }

    #[test]
    fn the_bolt_rule_and_the_cone() {
        // Half the pillar's side: 11 mm → M5, 14 → M6, 17 → M8 (RV-20E, -40E, -80E);
        // VDI 2230's cone through a plate as thick as the support bearing is wide (11.75,
        // 15.25, 16.25 mm) reaches 8.5 + 2·11.75·0.348 = 16.68 > 11, 20.61 > 14, 24.31 > 17.
        let cases = [(11.0, 11.75, 5.0), (14.0, 15.25, 6.0), (17.0, 16.25, 8.0)];
        for (side, plate, d) in cases {
            let bolt = bolt_for_pillar(side, side).unwrap();
            assert_eq!(bolt.0, d);
            assert!(bolt.3 + 2.0 * plate * CONE_TAN_MIN > side);
        }
        assert!(bolt_for_pillar(7.0, 12.0).is_none());
    }

    #[test]
    fn rv20e_joint_by_hand() {
        // 11 × 11 mm face, M5 hole 5.5 mm: A_j = 121 − 23.758294 = 97.241706 mm²; F_M =
        // 12 378.5 N gives p = 127.296 MPa; k_n = 127.296^0.52/(0.046·0.48) = 562.995
        // N/(mm²·µm); k_t = 562.995·1.4/1.7 = 463.643. Rocking: I_j = 11⁴/12 −
        // π·5.5⁴/64 = 1220.0833 − 44.9180 = 1175.1653 mm⁴, 1/(562 995·1175.1653) =
        // 1.51146e-9 rad/(N·mm) (the half-space root's 1.33894e-8: 11 %); sliding
        // 1/(463 643·97.2417) = 2.21801e-8 mm/N; twisting J_j = 2·1220.0833 − 89.8360 =
        // 2350.3306 mm⁴, 1/(463 643·2350.3306) = 9.17672e-10.
        let joint = BoltedJoint {
            width: 11.0,
            depth: 11.0,
            hole: 5.5,
            cone: 8.5 + 2.0 * 11.75 * CONE_TAN_MIN,
            preload: assembly_preload(5.0, 0.8, THREAD_FRICTION),
            coefficient: ITO_COEFFICIENT,
            exponent: ITO_EXPONENT,
        };
        assert!((joint.area() - 97.241706).abs() < 1e-6);
        assert!((joint.pressure() / 127.296 - 1.0).abs() < 1e-5);
        assert!((joint.normal_stiffness() / 562_995.0 - 1.0).abs() < 1e-5);
        let c = joint.compliance(0.3);
        assert!((c.rocking / 1.51146e-9 - 1.0).abs() < 1e-5, "{c:?}");
        assert!((c.sliding / 2.21801e-8 - 1.0).abs() < 1e-5, "{c:?}");
        assert!((c.twisting / 9.17672e-10 - 1.0).abs() < 1e-5, "{c:?}");
        // Ito's stiffness per area at 10/50/100 MPa: 150/350/500 N/(mm²·µm) (validation.md).
        for (p, k) in [(10.0, 150.0), (50.0, 350.0), (100.0, 500.0)] {
            let at = BoltedJoint {
                preload: p * joint.area(),
                ..joint
            };
            assert!(
                (at.normal_stiffness() / 1000.0 / k - 1.0).abs() < 0.06,
                "{p}"
            );
        }
    }
}
