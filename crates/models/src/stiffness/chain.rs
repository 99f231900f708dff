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

use super::{CrankShaft, RollerRow, TaperedRow};

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
    /// (c_web,S, c_web,A), the disc web around the pillars' holes, mm/N (bodies.rs).
    pub web_compliance: (f64, f64),
    /// The crank shaft.
    pub shaft: CrankShaft,
    /// One support bearing row with its preload (both supports alike).
    pub support: TaperedRow,
    /// The carrier plate around one support bearing's outer ring, mm/N (0: rigid plates).
    pub support_housing_compliance: f64,
    /// c_path, the plate carrying a seat's net force to the pillars, mm/N (bodies.rs).
    pub seat_path_compliance: f64,
    /// K_c, the pillars on their half-space roots, N·mm/rad.
    pub carrier_stiffness: f64,
    /// What the end plate's bolted joints add to 1/K_c, rad per N·mm (joint.rs).
    pub end_plate_joint_compliance: f64,
    /// What the end plate's bending adds to 1/K_c beyond the joints, rad per N·mm
    /// (plate.rs).
    pub end_plate_bending_compliance: f64,
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
    /// The disc web weakened by the pillars' holes.
    pub disc_web: f64,
    /// Crank shaft bending and shear.
    pub shaft: f64,
    /// Support bearings and their seats' ovalisation.
    pub support: f64,
    /// The plates' paths from the seats to the pillars.
    pub seat_path: f64,
    /// Carrier wind-up: the pillars on their roots.
    pub carrier: f64,
    /// The end plate's bolted joints.
    pub end_plate_joint: f64,
    /// The end plate's bending around the pillars' roots.
    pub end_plate_bending: f64,
    /// The housing around the pin grooves (filled in by the caller, who has the pin
    /// forces: housing.rs).
    pub housing: f64,
    /// Involute stage and crank torsion.
    pub involute: f64,
}

impl ChainTerms {
    /// The sum of the terms.
    pub fn total(&self) -> f64 {
        self.needle
            + self.disc_bore
            + self.disc_web
            + self.shaft
            + self.support
            + self.seat_path
            + self.carrier
            + self.end_plate_joint
            + self.end_plate_bending
            + self.housing
            + self.involute
    }

    /// Every term multiplied by `factor` (rad to arcmin).
    pub fn scaled(&self, factor: f64) -> ChainTerms {
        self.combined(self, |a, _| a * factor)
    }

    /// Each term less `other`'s: what a change of load state adds, term by term.
    pub fn minus(&self, other: &ChainTerms) -> ChainTerms {
        self.combined(other, |a, b| a - b)
    }

    /// `f` of each term and `other`'s same term.
    fn combined(&self, other: &ChainTerms, f: impl Fn(f64, f64) -> f64) -> ChainTerms {
        ChainTerms {
            needle: f(self.needle, other.needle),
            disc_bore: f(self.disc_bore, other.disc_bore),
            disc_web: f(self.disc_web, other.disc_web),
            shaft: f(self.shaft, other.shaft),
            support: f(self.support, other.support),
            seat_path: f(self.seat_path, other.seat_path),
            carrier: f(self.carrier, other.carrier),
            end_plate_joint: f(self.end_plate_joint, other.end_plate_joint),
            end_plate_bending: f(self.end_plate_bending, other.end_plate_bending),
            housing: f(self.housing, other.housing),
            involute: f(self.involute, other.involute),
        }
    }
}

/// The supports' weights and loads for one load state (module comment).
struct SupportState {
    /// Symmetric and antisymmetric weights of a compliance c_A at support A, c_B at B:
    /// (S_A·w_A, S_B·w_B) and (A_A·w_A, A_B·w_B).
    symmetric: (f64, f64),
    antisymmetric: (f64, f64),
    /// The rms radial loads of supports A and B, N.
    loads: (f64, f64),
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
    /// the pins see as a turn of F_x·c_A/(m·e·z_c), with F_x's sign (docs/models.md §13).
    /// A preload's resultant loads the crank side at T_c = 0: the terms of a load state
    /// are measured from its zero-torque state by [`ChainTerms::minus`] (the caller's).
    pub fn terms(
        &self,
        disc_torque: f64,
        force: (f64, f64),
        needle_factor: f64,
        output_torque: f64,
        reflection: f64,
    ) -> ChainTerms {
        if !(disc_torque > 0.0 || force.0 != 0.0 || force.1 != 0.0) {
            return ChainTerms::default();
        }
        let (m, a) = (self.cranks, self.crank_circle_radius);
        let tangential = disc_torque / (m * a);
        let shared = force.0.hypot(force.1) / m;
        // Output angle per unit compliance in each mode.
        let symmetric = reflection * disc_torque / (m * a * a);
        let antisymmetric = reflection * force.0 / (m * self.pitch_radius);
        let needle = self.needle.secant_compliance(tangential.hypot(shared)) / needle_factor;
        let modes = self.shaft.modes();
        let supports = self.support_state(tangential, shared);
        let row =
            |load: f64| self.support.secant_compliance(load) + self.support_housing_compliance;
        let (row_a, row_b) = (row(supports.loads.0), row(supports.loads.1));
        let weigh = |(wa, wb): (f64, f64), ca: f64, cb: f64| wa * ca + wb * cb;
        let path = self.seat_path_compliance;
        // Support B's tangential shift reaches the planes x1 and x2 by x1/L and x2/L; the
        // two discs share the load equally, so the output sees the mean.
        let mean_plane = 0.5 * (self.shaft.first + self.shaft.second) / self.shaft.span;
        let carrier = symmetric * m * modes.symmetric_reactions.1 * a * a * mean_plane;
        ChainTerms {
            needle: (symmetric + antisymmetric) * needle,
            disc_bore: (symmetric + antisymmetric) * self.bore_compliance,
            disc_web: symmetric * self.web_compliance.0 + antisymmetric * self.web_compliance.1,
            shaft: symmetric * modes.symmetric + antisymmetric * modes.antisymmetric,
            support: symmetric * weigh(supports.symmetric, row_a, row_b)
                + antisymmetric * weigh(supports.antisymmetric, row_a, row_b),
            seat_path: symmetric * weigh(supports.symmetric, path, path)
                + antisymmetric * weigh(supports.antisymmetric, path, path),
            carrier: carrier / self.carrier_stiffness,
            end_plate_joint: carrier * self.end_plate_joint_compliance,
            end_plate_bending: carrier * self.end_plate_bending_compliance,
            housing: 0.0,
            involute: self.involute_compliance * output_torque,
        }
    }

    /// The compliance of one disc against the other through the crank side, rad of the
    /// disc per N·mm of its own pin moment, linearised at the load state of the disc torque
    /// T_c (N·mm, > 0) with the closed-form pin resultant F_x = T_c/(e·z_c) (every pin
    /// normal passes through the pitch point, e·z_c from the disc centre).
    ///
    /// Two discs whose pin moments M_1, M_2 differ load the crank side in two patterns
    /// (docs/models.md §12.9): their torques, τ_d = M_d/(m·a_w) across each crank, and
    /// their pin resultants, M_d/(e·z_c·m) along each disc's across direction, which are
    /// opposite in the carrier (eccentrics 180° apart). A disc's own elements (its needle
    /// rows, the disc around its bores and its web) see only its own load; the crank shaft
    /// and the supports see both planes, w(x1; x1) for a load at the own plane and
    /// w(x1; x2) for one at the other. Split into M_1 + M_2 (fixed by the output torque:
    /// a common turn of both discs, the carrier's wind-up with it) and M_d − M_other, the
    /// part that differs turns disc d by c·M_d plus a constant, with
    ///
    /// ```text
    /// c = c_rot/(m·a_w²) + c_trans/(m·(e·z_c)²)
    /// c_rot   = row + bore + web_S + (w11 − w12) + supports and paths, antisymmetric weights
    /// c_trans = row + bore + web_A + (w11 + w12) + supports and paths, symmetric weights
    /// ```
    ///
    /// (the torques are the same at both planes when the discs are alike, the resultants
    /// opposite: the shaft's modes swap against [`Self::terms`]'s). Rows at their secant
    /// stiffness at the rms load of the state, as in [`Self::terms`]; the carrier's
    /// wind-up and the involute stage carry only the sum and do not appear.
    pub fn disc_compliance(&self, disc_torque: f64) -> f64 {
        let (m, a) = (self.cranks, self.crank_circle_radius);
        let tangential = disc_torque / (m * a);
        let shared = disc_torque / (self.pitch_radius * m);
        let own = self.needle.secant_compliance(tangential.hypot(shared)) + self.bore_compliance;
        let modes = self.shaft.modes();
        let supports = self.support_state(tangential, shared);
        let row =
            |load: f64| self.support.secant_compliance(load) + self.support_housing_compliance;
        let rows = (row(supports.loads.0), row(supports.loads.1));
        let path = self.seat_path_compliance;
        let weigh = |(wa, wb): (f64, f64)| wa * (rows.0 + path) + wb * (rows.1 + path);
        let rotation =
            own + self.web_compliance.0 + modes.antisymmetric + weigh(supports.antisymmetric);
        let translation = own + self.web_compliance.1 + modes.symmetric + weigh(supports.symmetric);
        rotation / (m * a * a) + translation / (m * self.pitch_radius * self.pitch_radius)
    }

    /// The supports' weights (shares times the lever of each support on the first
    /// eccentric plane) and rms loads for the crank loads τ and |F|/m.
    fn support_state(&self, tangential: f64, shared: f64) -> SupportState {
        support_state(&self.shaft, tangential, shared)
    }

    /// The larger rms radial load of the two supports for the disc torque T_c with the
    /// closed-form pin resultant F_x = T_c/(e·z_c) (the unmodified profile), N.
    pub fn support_load(&self, disc_torque: f64) -> f64 {
        closed_form_support_load(
            &self.shaft,
            self.cranks,
            self.crank_circle_radius,
            self.pitch_radius,
            disc_torque,
        )
    }
}

/// The supports' weights and rms loads of a shaft for the crank loads τ and |F|/m.
fn support_state(shaft: &CrankShaft, tangential: f64, shared: f64) -> SupportState {
    let modes = shaft.modes();
    let (weight_a, weight_b) = shaft.support_weights();
    let (s_a, s_b) = modes.symmetric_reactions;
    let (anti_a, anti_b) = modes.antisymmetric_reactions;
    SupportState {
        symmetric: (s_a * weight_a, s_b * weight_b),
        antisymmetric: (anti_a * weight_a, anti_b * weight_b),
        loads: (
            (tangential * s_a).hypot(shared * anti_a),
            (tangential * s_b).hypot(shared * anti_b),
        ),
    }
}

/// The larger rms radial load of a shaft's two supports, `cranks` cranks on
/// `crank_radius`, for the disc torque T_c with the closed-form pin resultant
/// F_x = T_c/(e·z_c), `pitch_radius` = e·z_c, N.
pub(crate) fn closed_form_support_load(
    shaft: &CrankShaft,
    cranks: f64,
    crank_radius: f64,
    pitch_radius: f64,
    disc_torque: f64,
) -> f64 {
    let state = support_state(
        shaft,
        disc_torque / (cranks * crank_radius),
        disc_torque / (pitch_radius * cranks),
    );
    state.loads.0.max(state.loads.1)
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
            web_compliance: (3.0e-8, 2.0e-8),
            shaft: CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3),
            support: TaperedRow {
                row: RollerRow {
                    rollers: 14.0,
                    length: 7.0,
                    contact_angle: 15f64.to_radians(),
                },
                preload: 0.0,
            },
            support_housing_compliance: 2.0e-7,
            seat_path_compliance: 1.0e-7,
            carrier_stiffness: 3e8,
            end_plate_joint_compliance: 1e-10,
            end_plate_bending_compliance: 5e-11,
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
        // The body terms are linear: the web by mode, the seats' paths weighted like the
        // supports' seats, the end plate's increments in proportion to the carrier's.
        let web = symmetric * 3.0e-8 + antisymmetric * 2.0e-8;
        assert!((one.disc_web / web - 1.0).abs() < 1e-14);
        assert!((one.end_plate_joint / one.carrier - 3e8 * 1e-10).abs() < 1e-12);
        assert!((one.end_plate_bending / one.carrier - 3e8 * 5e-11).abs() < 1e-12);
        // The seats' paths are weighted as the seats' ovalisation: their ratio is 1e-7/2e-7
        // once the rows are taken out (rows of zero compliance: a huge row stiffness).
        let stiff_rows = CrankSide {
            support: TaperedRow {
                row: RollerRow {
                    length: 1e12,
                    ..side.support.row
                },
                preload: 0.0,
            },
            ..side
        };
        let bodies = stiff_rows.terms(80_000.0, (2300.0, -120.0), 1.0, 167_000.0, 1.0);
        assert!((bodies.seat_path / bodies.support - 0.5).abs() < 1e-6);
        assert_eq!(one.housing, 0.0);
        // A preloaded support is stiffer, the rest unchanged.
        let preloaded = CrankSide {
            support: TaperedRow {
                preload: 300.0,
                ..side.support
            },
            ..side
        };
        let with = preloaded.terms(80_000.0, (2300.0, -120.0), 1.0, 167_000.0, 1.0);
        assert!(with.support < one.support && with.shaft == one.shaft);
        // The support load of the closed-form resultant: τ = T_c/(m·a_w) = 1454.55 N,
        // |F|/m = T_c/(e·z_c·m) = 1139.60 N, A_A = 9/28: √(1454.55² + (1139.60·9/28)²) =
        // 1499.96 N at both supports.
        assert!((side.support_load(80_000.0) / 1499.96 - 1.0).abs() < 1e-5);
        disc_compliance_swaps_the_shaft_and_support_modes(&side);
    }

    /// [`CrankSide::disc_compliance`] against [`CrankSide::terms`] of the same state (the
    /// closed-form resultant F_x = T_c/(e·z_c)): the same elements, with the shaft's and
    /// the supports' symmetric and antisymmetric parts swapped between the torque (1/a_w²)
    /// and the resultant (1/(e·z_c)²), and without the carrier and the end plate (the sum
    /// of the two discs' moments is fixed).
    fn disc_compliance_swaps_the_shaft_and_support_modes(side: &CrankSide) {
        let t_c = 80_000.0;
        let (m, a, p) = (side.cranks, side.crank_circle_radius, side.pitch_radius);
        let terms = side.terms(t_c, (t_c / p, 0.0), 1.0, 0.0, 1.0);
        let kept = terms.total() - terms.carrier - terms.end_plate_joint - terms.end_plate_bending;
        let modes = side.shaft.modes();
        let supports = side.support_state(t_c / (m * a), t_c / (p * m));
        let row = |load: f64| {
            side.support.secant_compliance(load)
                + side.support_housing_compliance
                + side.seat_path_compliance
        };
        let (row_a, row_b) = (row(supports.loads.0), row(supports.loads.1));
        let weigh = |(wa, wb): (f64, f64)| wa * row_a + wb * row_b;
        let swing = (modes.antisymmetric - modes.symmetric)
            + (weigh(supports.antisymmetric) - weigh(supports.symmetric));
        let hand = kept / t_c + swing * (1.0 / (m * a * a) - 1.0 / (m * p * p));
        let model = side.disc_compliance(t_c);
        assert!((model / hand - 1.0).abs() < 1e-12, "{model} vs {hand}");
    }
}
