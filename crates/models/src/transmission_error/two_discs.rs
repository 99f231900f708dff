//! The physical reading of the transmission error (docs/models.md §12, "physical
//! reading"): two cycloid discs with eccentrics 180° apart on m cranks, each disc located
//! by its own eccentrics (four-bar closure), first contact over both discs or the
//! load-shared mean, crank and input-shaft tilts through 001 Eq. 5–8 at the planes of the
//! contacts, interference as an indicator, and no output pin-hole term (an output runout
//! translates the output, it does not turn it).
//!
//! Frames and signs. Output (carrier) angle Θ, counter-clockwise positive; TE positive
//! when the output is ahead. The eccentric of disc 1 points at χ = −z_p·Θ in the carrier
//! (ψ = Θ + χ = −z_c·Θ in the housing), that of disc 2 at χ + π; each disc's eccentric
//! frame has x along its eccentric and y its counter-clockwise normal, and a carrier
//! vector v has the components σ_d·R(z_p·Θ)·v in it (σ_1 = +1, σ_2 = −1). Crank k sits at
//! β_k = 2π(k − 1)/m on the crank circle a_w, with radial u_k and tangential t_k.
//!
//! Per disc d (all lengths mm, angles rad):
//! - eccentric centre error of crank k at disc d's plane, eccentric frame:
//!   E_kd = q_kd + a·λ_k·ŷ + σ_d·R(z_p·Θ)·B_kd, with q_kd the eccentric's own error (crank
//!   frame: magnitude, phase), λ_k the crank's rotation error from the involute stage
//!   (its lag g_k/(r2·cos α), counter-clockwise because the crank turns clockwise
//!   against the carrier), and B_kd = R(β_k)·(b_r + z_d·τ_t, b_t − z_d·τ_r) the crank axis
//!   at the disc plane z_d = ±s/2 (bore position b, axis tilt τ about u_k and t_k; 001
//!   Eq. 5–8: θ = ω × p).
//! - disc translation T_d = mean_k E_kd + σ_d·R(z_p·Θ)·r_d (r_d the runout of the disc's
//!   profile about its crank holes, disc frame = carrier frame).
//! - disc rotation against the carrier (four-bar closure of a rigid disc on m crank pins
//!   of equal bearing stiffness: the least-squares fit of the pins, exact across the line
//!   of the pins for m = 2): ρ_d = Σ_k t_k·E_kd/(m·a_w), with t_k in the same frame;
//!   for two cranks with eccentric errors e_1 = −e_2 across that line, ρ = e_⊥/a_w =
//!   (e_1 − e_2)_⊥/(2·a_w). `crank_closure` "averaged" sets ρ_d = 0 (002's reading).
//! - crank offset C_d = −T_d,y/(a·z_c) − ρ_d: the translation across the eccentric is an
//!   eccentric phase change T_d,y/a, which the pins turn into a disc rotation
//!   −T_d,y/(a·z_c) (cycloid relation Θ_disc = −ψ/z_c); the carrier is the disc less ρ_d.
//! - the disc's turn past its mesh: with the input locked, the output turned
//!   counter-clockwise by δΘ turns carrier and disc by δΘ and the cranks, rolling on the
//!   fixed sun, by (1 + z_s/z_pl)·δΘ, and so the eccentric; the mesh would turn the disc by
//!   −(1 + z_s/z_pl)·δΘ/z_c, so the disc is δΘ·(z_p + z_s/z_pl)/z_c = δΘ/κ counter-clockwise
//!   past its mesh, which closes the gaps of the pins with l_i > 0 (sin φ > 0). A
//!   counter-clockwise output (the window's upper end) is therefore limited by the l > 0
//!   pins, a lagging output (its lower end: forward drive, the single-flank test) by the
//!   l < 0 pins: the drive flank is the l < 0 one. The pins hold disc d between a
//!   drive-flank lag K_d = min over l_i < 0 of g_i/|l_i| and a coast-flank lead
//!   L_d = min over l_i > 0 of g_i/l_i (g_i the clearances of docs/models.md §12 with
//!   d_r = T_d,x and disc d's own profile and tooth errors; the modification in the
//!   standard form of the drive flank, measured from the disc turned into drive-flank
//!   contact). An exact profile agrees (tests/data/exact_profile_windows.csv, tested in
//!   tests/transmission_error.rs): a translation across the eccentric towards the l > 0
//!   pins and a larger pin on the l > 0 side both lower the upper end.
//! - the output follows the disc through the cranks that ride on it: a disc rotation ε
//!   with the crank held against the carrier turns the output by ε·z_c/z_p (the whole
//!   carrier, cranks and disc turn about the output axis, where the pin normals have the
//!   lever a·z_p), and by ε·z_c/D with the carrier feedback (D = z_p + z_s/z_pl); κ =
//!   z_c/D scales every disc-side term (002 takes κ = 1).
//!
//! Output window of disc d: [κ·(C_d − K_d), κ·(C_d + L_d)]. First contact (light load,
//! the single-flank test): TE = max_d κ·(C_d − K_d); load-shared (both discs loaded, equal
//! stiffness): TE = mean_d κ·(C_d − K_d). The windows of the two discs must overlap at every
//! point: where they do not, the profile interferes (a negative play), the sample has no
//! rigid transmission error and the indicator `profile_interference` is 1. Its preload is
//! then judged by the one rule of every model (`crate::preload`, docs/models.md §14.8) at
//! the point where the discs fit least: both discs' pins from the exact geometry, each at
//! its crank offset C_d, balanced at zero torque (overlap, largest pin force, no-load
//! torque, `preloaded`, `over_preloaded`).
//!
//! The curve is tabulated at N points (a drive table of the l < 0 slots and a coast table
//! of the l > 0 slots per fractional pin pitch of disc 1, disc 2's slots found at the phase
//! half a revolution of the eccentric on); peak-to-peak is refined at its extremes by the
//! exact geometry (a parabola on the winning contact near the maximum, the crossing of the
//! two contacts near the minimum, which is a kink): the sampled extremes are off by up to
//! L·h/2 (L the largest slope, h = 2π/N), the refined ones only move towards the true ones
//! (tests/transmission_error.rs).
//!
//! The reading's data is [`Physical`] (built once by [`build`]: its options, the preload
//! rule, both flanks' slot tables, disc 2's phases and tooth columns, the per-point
//! angles), its per-thread work state [`TwoDiscScratch`]; its methods read what every
//! reading shares from [`Common`]. The loaded reading (module `loaded`) builds on its row
//! terms and crank offsets; this module names nothing of it.

use std::f64::consts::PI;

use super::common::{
    quads, smallest, smallest_lane, smallest_ratio, Common, PinTable, Point, MAX_CRANKS,
};
use crate::cycloid::{CycloidStage, PinFactors};
use crate::preload::{slip_arm, zero_torque, DiscPins, PreloadRule, LEVER_FLOOR};
use crate::spectrum::OrderDft;
use crate::{ConditionEffect, InputSpec, OutputCondition, OutputKind, OutputSpec};

/// How the two discs share the output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum DiscContact {
    /// Light load: the disc that touches first carries the output.
    FirstContact,
    /// Both discs loaded with equal stiffness: the mean of their contact angles.
    LoadShared,
}

/// How a disc on m crank pins takes up their differences.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum CrankClosure {
    /// The rigid disc turns to fit its pins (four-bar closure, least squares for m > 2).
    FourBar,
    /// The bearings take the differences up; the disc only translates by their mean
    /// (002's reading).
    Averaged,
}

/// Fixed inputs of the physical reading, in order.
pub(super) const FIXED: [(&str, &str, &str); 8] = [
    (
        "sun_runout_x_mm",
        "mm",
        "sun (input shaft) centre at the sun plane, sun frame, x",
    ),
    (
        "sun_runout_y_mm",
        "mm",
        "sun (input shaft) centre at the sun plane, sun frame, y",
    ),
    (
        "sun_tilt_x_rad",
        "rad",
        "input shaft tilt about x, sun frame (001 Eq. 7: moves the sun plane by −Δα·L_s along y)",
    ),
    (
        "sun_tilt_y_rad",
        "rad",
        "input shaft tilt about y, sun frame (001 Eq. 7: moves the sun plane by +Δβ·L_s along x)",
    ),
    (
        "equidistant_modification_mm",
        "mm",
        "Δr_rp, equidistant modification of both discs (003; positive: clearance)",
    ),
    (
        "shift_modification_mm",
        "mm",
        "Δr_p, shift modification of both discs (003; negative: clearance)",
    ),
    (
        "pin_circle_radius_error_mm",
        "mm",
        "δr_p, pin circle radius minus design",
    ),
    (
        "pin_radius_error_mm",
        "mm",
        "δr_rp, pin radius minus design",
    ),
];

/// Inputs per disc d, in order (name stems; the disc number follows).
pub(super) const PER_DISC: [(&str, &str); 3] = [
    (
        "profile_normal_error_mm",
        "profile error of disc d normal to the profile, every tooth (002 δ31; positive: clearance)",
    ),
    (
        "disc_runout_x_mm",
        "runout of disc d's profile about its crank holes, disc frame, x (along the eccentric at Θ = 0)",
    ),
    (
        "disc_runout_y_mm",
        "runout of disc d's profile about its crank holes, disc frame, y",
    ),
];

/// Inputs per crank k, in order (name stems; the crank number follows, then the disc).
pub(super) const PER_CRANK: [(&str, &str, &str); 7] = [
    (
        "planet_runout_x_mm",
        "mm",
        "planet runout, planet frame, along the eccentric of disc 1",
    ),
    (
        "planet_runout_y_mm",
        "mm",
        "planet runout, planet frame, across the eccentric of disc 1",
    ),
    (
        "center_distance_error_mm",
        "mm",
        "sun–planet centre distance error, carrier frame (002 δ11)",
    ),
    (
        "crank_axis_radial_error_mm",
        "mm",
        "crank axis position midway between the discs, carrier frame, radial",
    ),
    (
        "crank_axis_tangential_error_mm",
        "mm",
        "crank axis position midway between the discs, carrier frame, tangential",
    ),
    (
        "crank_axis_tilt_radial_rad",
        "rad",
        "crank axis tilt about the radial direction, carrier frame (001 Eq. 7 at the disc planes)",
    ),
    (
        "crank_axis_tilt_tangential_rad",
        "rad",
        "crank axis tilt about the tangential direction, carrier frame (001 Eq. 7 at the disc planes)",
    ),
];

/// Inputs per eccentric (crank k, disc d), in order.
pub(super) const PER_ECCENTRIC: [(&str, &str); 2] = [
    (
        "crank_eccentricity_error_mm",
        "eccentric of crank k under disc d: magnitude error, crank frame (002 δ21)",
    ),
    (
        "crank_phase_error_mm",
        "eccentric of crank k under disc d: position error across the eccentric (counter-clockwise), crank frame",
    ),
];

/// Inputs per crank: the crank's own and its two eccentrics'.
pub(super) const CRANK_STRIDE: usize = PER_CRANK.len() + 2 * PER_ECCENTRIC.len();

/// The physical reading's data: its options, the cycloid stage, both flanks' slot tables
/// (built once, disc 2 reading disc 1's at its own phase), the per-point angles, the
/// direct DFT of its five output orders, and where its inputs lie in a row.
#[derive(Debug, Clone)]
pub(super) struct Physical {
    contact: DiscContact,
    closure: CrankClosure,
    /// a_w, mm.
    crank_radius: f64,
    /// s/2, mm: the disc planes at z = +s/2 (disc 1) and −s/2 (disc 2).
    half_spacing: f64,
    /// L_s, mm: from the input shaft's reference to the sun plane.
    sun_offset: f64,
    /// κ = z_c/D.
    kappa: f64,
    /// The one preload rule (docs/models.md §14.5): it judges where the discs do not fit.
    preload_rule: PreloadRule,
    stage: CycloidStage,
    /// Slots with a negative lever (the drive flank: the window's lower end, the TE),
    /// factors over |l|; entry e of a block is slot `drive_first_slot` + e.
    drive: PinTable,
    /// ⌊z_p/2⌋: the first slot that can have a negative lever.
    drive_first_slot: usize,
    /// Slots with a positive lever (the coast flank: the window's upper end), entry e is
    /// slot e.
    coast: PinTable,
    /// Per disc-1 phase p: disc 2's block.
    phase_2: Vec<u32>,
    /// Tooth space of each entry of disc 2's drive and coast blocks, per disc-1 phase p
    /// (p·width + e), relative to the same tooth shift k_j as disc 1.
    tooth_2_drive: Vec<u32>,
    tooth_2_coast: Vec<u32>,
    /// Per curve point (in `curve_points` order): disc 2's whole pin pitches, mod z_p.
    pin_shift_2: Vec<u32>,
    /// Per group: the pin shifts of its first point on each disc, when it has LANES points
    /// whose shifts advance by `lane_stride` (mod z_p) from one to the next.
    lane_shifts: Vec<Option<[u32; 2]>>,
    /// Δ = z_c·z_p·(N/g)/N mod z_p, the pin-shift stride within a group.
    lane_stride: usize,
    /// A(φ), B(φ), C(φ) of [`Physical::coast_floor`] at φ = π·(k + ½)/G,
    /// k < G = FLOOR_GRID, and their largest slopes |dA/dφ|, |dB/dφ|, |dC/dφ| (taken on a
    /// grid 64 times finer, by differences, and doubled).
    floor_grid: Vec<[f64; 3]>,
    floor_slopes: [f64; 3],
    /// Whether every group's points share z_p·Θ and (i − 1)·Θ (an integral sun order
    /// that the group spacing N/g turns by whole revolutions): C_d is then one value per
    /// group.
    uniform_groups: bool,
    /// Per point index j: (sin, cos) of z_p·Θ and of (i − 1)·Θ.
    angles: Vec<[f64; 4]>,
    /// The same as four columns.
    columns: [Vec<f64>; 4],
    /// (sin β_k, cos β_k).
    crank_angles: Vec<(f64, f64)>,
    /// The direct DFT of the output orders 1, z_c, z_p, 2·z_c, 2·z_p.
    orders: OrderDft<5>,
    /// Input offsets: per disc, cranks, pins, teeth.
    disc_base: usize,
    crank_base: usize,
    pin_base: usize,
    tooth_base: usize,
}

/// What a row contributes, reduced once per row.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RowTerms {
    pub d_rp: f64,
    pub d_p: f64,
    pub err_rp: f64,
    pub err_rrp: f64,
    pub profile: [f64; 2],
    /// Per crank, λ_k = l0 + l1·cos z_pΘ + l2·sin z_pΘ + l3·cos (i−1)Θ + l4·sin (i−1)Θ, rad.
    pub lam: [[f64; 5]; MAX_CRANKS],
    /// Per disc, the mean eccentric error (along, across), eccentric frame.
    pub q_mean: [(f64, f64); 2],
    /// Per disc, mean crank axis at the disc plane plus the disc runout, carrier frame.
    pub v: [(f64, f64); 2],
    /// Per disc, Σ_k t_k·R(−z_pΘ)·q_kd = p1·cos z_pΘ + p2·sin z_pΘ.
    pub p1: [f64; 2],
    pub p2: [f64; 2],
    /// Per disc, Σ_k t_k·B_kd (carrier frame).
    pub rho_const: [f64; 2],
    /// Largest |radial| and |tangential| pin error.
    pub pin_bound: (f64, f64),
}

/// A contact branch: the pin in contact on each disc that counts (first contact: one
/// disc; load-shared: both).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Branch {
    One { disc: usize, pin: usize },
    Both { pins: [usize; 2] },
}

/// The exact geometry at one angle.
#[derive(Debug, Clone, Copy)]
pub(super) struct Exact {
    /// TE, rad.
    pub te: f64,
    /// Whether the two discs' windows overlap (no interference).
    pub clear: bool,
    pub branch: Branch,
    /// −κ·mean λ/z_c: the involute stage's common part, rad.
    pub involute: f64,
    /// Per disc κ·C_d, rad.
    pub crank: [f64; 2],
    /// Per disc its window [κ·(C_d − K_d), κ·(C_d + L_d)], rad (the upper end +∞ where
    /// the coast flank was not asked for).
    pub windows: [(f64, f64); 2],
}

impl Physical {
    /// Reduces a row of the physical reading to its per-row terms.
    pub(super) fn row_terms(&self, common: &Common, inputs: &[f64]) -> RowTerms {
        let m = common.cranks;
        let (sin_a, cos_a) = common.pressure;
        let inverse_base = 1.0 / common.base_radius;
        let (sun_x, sun_y) = (
            inputs[0] + self.sun_offset * inputs[3],
            inputs[1] - self.sun_offset * inputs[2],
        );
        let mut terms = RowTerms {
            d_rp: inputs[4],
            d_p: inputs[5],
            err_rp: inputs[6],
            err_rrp: inputs[7],
            ..RowTerms::default()
        };
        for d in 0..2 {
            let disc = &inputs[self.disc_base + 3 * d..self.disc_base + 3 * (d + 1)];
            terms.profile[d] = disc[0];
            terms.v[d] = (disc[1], disc[2]);
        }
        let mean = 1.0 / m as f64;
        for k in 0..m {
            let row = &inputs[self.crank_base + CRANK_STRIDE * k..][..CRANK_STRIDE];
            let (sb, cb) = self.crank_angles[k];
            // Involute stage: action line n_k = sin α·u_k + cos α·t_k; lag g_k/(r2·cos α).
            let n = (sin_a * cb - cos_a * sb, sin_a * sb + cos_a * cb);
            let (px, py) = (row[0], row[1]);
            terms.lam[k] = [
                row[2] * sin_a * inverse_base,
                (n.0 * px + n.1 * py) * inverse_base,
                (n.0 * py - n.1 * px) * inverse_base,
                -(n.0 * sun_x + n.1 * sun_y) * inverse_base,
                -(n.1 * sun_x - n.0 * sun_y) * inverse_base,
            ];
            let (b_r, b_t, tau_r, tau_t) = (row[3], row[4], row[5], row[6]);
            for d in 0..2 {
                let z = if d == 0 {
                    self.half_spacing
                } else {
                    -self.half_spacing
                };
                let (r, t) = (b_r + z * tau_t, b_t - z * tau_r);
                // Carrier frame: R(β_k)·(r, t).
                let b = (r * cb - t * sb, r * sb + t * cb);
                terms.v[d].0 += b.0 * mean;
                terms.v[d].1 += b.1 * mean;
                terms.rho_const[d] += t;
                let (qx, qy) = (row[7 + 2 * d], row[8 + 2 * d]);
                terms.q_mean[d].0 += qx * mean;
                terms.q_mean[d].1 += qy * mean;
                // t_k·R(−θ)·q = (−sin β, cos β)·(qx c + qy s, −qx s + qy c).
                terms.p1[d] += -sb * qx + cb * qy;
                terms.p2[d] += -sb * qy - cb * qx;
            }
        }
        // (v started from the disc runouts, weight 1, before the crank means were added.)
        if common.per_pin {
            let pins = &inputs[self.pin_base..self.pin_base + 2 * common.pins];
            let (radial, tangential) = pins.split_at(common.pins);
            terms.pin_bound = (
                radial.iter().fold(0.0, |a, v| f64::max(a, v.abs())),
                tangential.iter().fold(0.0, |a, v| f64::max(a, v.abs())),
            );
        }
        terms
    }

    /// C_d for both discs and the involute stage's common part at one angle, from
    /// (sin, cos) of z_p·Θ and of (i − 1)·Θ.
    #[inline(always)]
    pub(super) fn crank_offsets(
        &self,
        common: &Common,
        terms: &RowTerms,
        angles: [f64; 4],
    ) -> ([f64; 2], f64) {
        let [s, c, ss, cs] = angles;
        let m = common.cranks as f64;
        let (mut lam_sum, mut four) = (0.0, 0.0);
        for (l, &(sb, cb)) in terms.lam[..common.cranks].iter().zip(&self.crank_angles) {
            let lam = l[0] + l[1] * c + l[2] * s + l[3] * cs + l[4] * ss;
            lam_sum += lam;
            four += lam * (cb * c - sb * s);
        }
        let a = common.eccentricity;
        let lam_mean = lam_sum / m;
        let inverse_azc = 1.0 / (a * common.cycloid_teeth as f64);
        let inverse_aw = 1.0 / (m * self.crank_radius);
        let mut offsets = [0.0; 2];
        for (d, offset) in offsets.iter_mut().enumerate() {
            let sigma = if d == 0 { 1.0 } else { -1.0 };
            let across =
                terms.q_mean[d].1 + a * lam_mean + sigma * (terms.v[d].0 * s + terms.v[d].1 * c);
            let rho = match self.closure {
                CrankClosure::FourBar => {
                    (sigma * (terms.p1[d] * c + terms.p2[d] * s + a * four) + terms.rho_const[d])
                        * inverse_aw
                }
                CrankClosure::Averaged => 0.0,
            };
            *offset = -across * inverse_azc - rho;
        }
        (
            offsets,
            -self.kappa * lam_mean / common.cycloid_teeth as f64,
        )
    }

    /// The coefficients of C_d over the products [1, x, y, u, w, x², xy, y², xu, yu, xw, yw]
    /// of x = cos z_pΘ, y = sin z_pΘ, u = cos (i−1)Θ, w = sin (i−1)Θ: the expansion of
    /// [`Self::crank_offsets`] (λ_k is linear in x, y, u, w; the four-bar term multiplies
    /// it by cos(β_k + z_pΘ) = cos β_k·x − sin β_k·y).
    pub(super) fn offset_coefficients(&self, common: &Common, terms: &RowTerms) -> [[f64; 12]; 2] {
        let m = common.cranks as f64;
        let a = common.eccentricity;
        let inverse_azc = 1.0 / (a * common.cycloid_teeth as f64);
        let inverse_aw = 1.0 / (m * self.crank_radius);
        // Means of the λ coefficients, and Σ_k l_i·cos β_k, Σ_k l_i·sin β_k.
        let (mut mean, mut lc, mut ls) = ([0.0; 5], [0.0; 5], [0.0; 5]);
        for (l, &(sb, cb)) in terms.lam[..common.cranks].iter().zip(&self.crank_angles) {
            for i in 0..5 {
                mean[i] += l[i] / m;
                lc[i] += l[i] * cb;
                ls[i] += l[i] * sb;
            }
        }
        let mut coefficients = [[0.0; 12]; 2];
        for (d, c) in coefficients.iter_mut().enumerate() {
            let sigma = if d == 0 { 1.0 } else { -1.0 };
            let (vx, vy) = terms.v[d];
            let across = [
                terms.q_mean[d].1 + a * mean[0],
                a * mean[1] + sigma * vy,
                a * mean[2] + sigma * vx,
                a * mean[3],
                a * mean[4],
            ];
            for i in 0..5 {
                c[i] = -across[i] * inverse_azc;
            }
            if self.closure == CrankClosure::FourBar {
                let rho = [
                    terms.rho_const[d],
                    sigma * (terms.p1[d] + a * lc[0]),
                    sigma * (terms.p2[d] - a * ls[0]),
                    0.0,
                    0.0,
                    sigma * a * lc[1],
                    sigma * a * (lc[2] - ls[1]),
                    -sigma * a * ls[2],
                    sigma * a * lc[3],
                    -sigma * a * ls[3],
                    sigma * a * lc[4],
                    -sigma * a * ls[4],
                ];
                for i in 0..12 {
                    c[i] -= rho[i] * inverse_aw;
                }
            }
        }
        coefficients
    }

    /// A floor under each disc's coast-flank ratio over the whole revolution, rad. The
    /// coast clearance is c0 + errors over |l|, plus the half play δ* = (Δr_rp −
    /// Δr_p·√(1 − K1²))/(a·z_c), with c0 = Δr_rp − Δr_p·A(φ); every error enters through
    /// one of A = (1 − K1·cos φ)/S (pin circle, radial pin), B = |K1 − cos φ|/S (the disc's
    /// displacement along its eccentric), C = K1·|sin φ|/S (tangential pin) or 1 (profile,
    /// pin radius, tooth space). With P = |δr_p| + max|δr_i|, T = max|δt_i|, D = |δ_n,d| +
    /// |δr_rp| + max|δ_n,d,j| and |d_r| at most |mean q_x| + |v_d|, the numerator is at least
    /// N(φ) = Δr_rp − D + (−Δr_p − P)·A − |d_r|·B − T·C, whose minimum over φ is taken on
    /// a grid of A, B, C less their largest slopes times half the grid spacing. A
    /// non-negative minimum N gives a ratio of at least δ* + N/(a·z_c) (|l| ≤ a·z_c); else
    /// −∞, and the coast flank is scanned where the windows need it.
    pub(super) fn coast_floor(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
    ) -> [f64; 2] {
        let k1 = self.stage.k1();
        let azc = common.eccentricity * common.cycloid_teeth as f64;
        let half_play = (terms.d_rp - terms.d_p * (1.0 - k1 * k1).sqrt()) / azc;
        let (bound_r, bound_t) = terms.pin_bound;
        let alpha = -terms.d_p - terms.err_rp.abs() - bound_r;
        let mut floors = [f64::NEG_INFINITY; 2];
        for (d, floor) in floors.iter_mut().enumerate() {
            let teeth = if common.per_tooth {
                let start = self.tooth_base + d * common.cycloid_teeth;
                inputs[start..start + common.cycloid_teeth]
                    .iter()
                    .fold(0.0, |a, v| f64::max(a, v.abs()))
            } else {
                0.0
            };
            let along = terms.q_mean[d].0.abs() + terms.v[d].0.hypot(terms.v[d].1);
            let constant = terms.d_rp - terms.profile[d].abs() - terms.err_rrp.abs() - teeth;
            let mut least = f64::INFINITY;
            for &[a, b, c] in &self.floor_grid {
                let v = alpha * a - along * b - bound_t * c;
                least = if v < least { v } else { least };
            }
            let [slope_a, slope_b, slope_c] = self.floor_slopes;
            let margin = (alpha.abs() * slope_a + along * slope_b + bound_t * slope_c)
                * (0.5 * PI / self.floor_grid.len() as f64);
            let numerator = constant + least - margin;
            if numerator >= 0.0 {
                *floor = half_play + numerator / azc;
            }
        }
        floors
    }

    /// T_d,x, the disc displacement along its eccentric, from (sin, cos) of z_p·Θ.
    #[inline(always)]
    pub(super) fn along(terms: &RowTerms, d: usize, s: f64, c: f64) -> f64 {
        let sigma = if d == 0 { 1.0 } else { -1.0 };
        terms.q_mean[d].0 + sigma * (terms.v[d].0 * c - terms.v[d].1 * s)
    }

    /// The clearance ratio g/|l| of pin `pin` (0-based) on disc d at Θ, with its lever's
    /// sign, from the geometry (no tables): the reference the tables must reproduce. `d_r`
    /// is the disc's displacement along its eccentric at Θ ([`Self::along`]).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn exact_ratio(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        d: usize,
        pin: usize,
        theta: f64,
        d_r: f64,
    ) -> (f64, f64) {
        let zp = common.pins as f64;
        let phi = 2.0 * PI * pin as f64 / zp + common.cycloid_teeth as f64 * theta + d as f64 * PI;
        let (sin, cos) = phi.rem_euclid(2.0 * PI).sin_cos();
        self.exact_ratio_at(common, inputs, terms, d, pin, theta, d_r, (sin, cos))
    }

    /// [`Self::exact_ratio`] with (sin φ, cos φ) of the pin given.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn exact_ratio_at(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        d: usize,
        pin: usize,
        theta: f64,
        d_r: f64,
        angle: (f64, f64),
    ) -> (f64, f64) {
        let (g, lever) = self.exact_gap_at(common, inputs, terms, d, pin, theta, d_r, angle);
        (g / lever.abs(), lever)
    }

    /// The gap g (mm, along the pin's normal; negative: an overlap) and the lever l (mm) of
    /// pin `pin` on disc d at Θ, (sin φ, cos φ) of the pin given: the clearance the windows'
    /// ratios g/|l| are made of.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn exact_gap_at(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        d: usize,
        pin: usize,
        theta: f64,
        d_r: f64,
        (sin, cos): (f64, f64),
    ) -> (f64, f64) {
        let factors = self.stage.pin_factors_at(sin, cos);
        let (equidistant, shift) = modification(&factors);
        let (pin_r, pin_t) = if common.per_pin {
            (
                inputs[self.pin_base + pin],
                inputs[self.pin_base + common.pins + pin],
            )
        } else {
            (0.0, 0.0)
        };
        let tooth = if common.per_tooth {
            let zc = common.cycloid_teeth as f64;
            let r_p = self.stage.pin_circle_radius;
            let polar = (r_p * sin).atan2(r_p * cos - common.eccentricity);
            let space = ((zc * (polar - common.pins as f64 * theta) / (2.0 * PI)).round() as i64)
                .rem_euclid(zc as i64);
            inputs[self.tooth_base + d * common.cycloid_teeth + space as usize]
        } else {
            0.0
        };
        let g = terms.d_rp * equidistant
            + terms.d_p * shift
            + d_r * factors.eccentric
            + (terms.err_rp + pin_r) * factors.radial
            + pin_t * factors.tangential
            + terms.profile[d]
            - terms.err_rrp
            + tooth;
        (g, factors.lever)
    }

    /// The whole physical geometry at Θ, pin by pin: the reference of the tabulated curve
    /// and the refinement of its extremes.
    pub(super) fn exact(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        theta: f64,
    ) -> Exact {
        self.exact_flanks(common, inputs, terms, theta, true)
    }

    /// [`Self::exact`], the coast flank (l > 0) only when `coast` (else its windows' upper
    /// ends are +∞ and `clear` is true).
    pub(super) fn exact_flanks(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        theta: f64,
        coast: bool,
    ) -> Exact {
        let angles = common.angles_at(theta);
        let (offsets, involute) = self.crank_offsets(common, terms, angles);
        let mut windows = [(0.0, 0.0); 2];
        let mut winners = [0; 2];
        // Pin φ by rotation: pin 1 at z_c·Θ (+π on disc 2), then one pitch at a time.
        let (pitch_sin, pitch_cos) = (2.0 * PI / common.pins as f64).sin_cos();
        for d in 0..2 {
            let d_r = Self::along(terms, d, angles[0], angles[1]);
            let start = (common.cycloid_teeth as f64 * theta + d as f64 * PI).rem_euclid(2.0 * PI);
            // K_d over the drive flank (l < 0, with the pin that holds it), L_d over the
            // coast flank (l > 0).
            let (mut lag, mut lead, mut winner) = (f64::INFINITY, f64::INFINITY, 0);
            let mut previous = (0.0, 1.0);
            for pin in 0..common.pins {
                // Exact sin_cos every 8 pins keeps the rotation's rounding at the 1e-15 level.
                let (sin, cos) = if pin % 8 == 0 {
                    (start + 2.0 * PI * pin as f64 / common.pins as f64).sin_cos()
                } else {
                    let (sin, cos) = previous;
                    (
                        sin * pitch_cos + cos * pitch_sin,
                        cos * pitch_cos - sin * pitch_sin,
                    )
                };
                previous = (sin, cos);
                if !coast && sin >= 0.0 {
                    continue;
                }
                let (ratio, lever) =
                    self.exact_ratio_at(common, inputs, terms, d, pin, theta, d_r, (sin, cos));
                if lever < -1e-12 * common.eccentricity {
                    if ratio < lag {
                        (lag, winner) = (ratio, pin);
                    }
                } else if lever > 1e-12 * common.eccentricity {
                    lead = lead.min(ratio);
                }
            }
            windows[d] = (
                self.kappa * (offsets[d] - lag),
                self.kappa * (offsets[d] + lead),
            );
            winners[d] = winner;
        }
        let (te, branch) = match self.contact {
            DiscContact::FirstContact => {
                let disc = if windows[1].0 > windows[0].0 { 1 } else { 0 };
                (
                    windows[disc].0,
                    Branch::One {
                        disc,
                        pin: winners[disc],
                    },
                )
            }
            DiscContact::LoadShared => (
                0.5 * (windows[0].0 + windows[1].0),
                Branch::Both { pins: winners },
            ),
        };
        let drive = windows[0].0.max(windows[1].0);
        let coast = windows[0].1.min(windows[1].1);
        Exact {
            te,
            clear: coast >= drive,
            branch,
            involute,
            crank: [self.kappa * offsets[0], self.kappa * offsets[1]],
            windows,
        }
    }

    /// The value of one contact branch at Θ (a lower bound of TE there), or None where
    /// one of its pins has no driving lever (l < 0).
    pub(super) fn branch_value(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        branch: Branch,
        theta: f64,
    ) -> Option<f64> {
        let angles = common.angles_at(theta);
        let (offsets, _) = self.crank_offsets(common, terms, angles);
        let one = |d: usize, pin: usize| {
            let d_r = Self::along(terms, d, angles[0], angles[1]);
            let (ratio, lever) = self.exact_ratio(common, inputs, terms, d, pin, theta, d_r);
            (lever < 0.0).then(|| self.kappa * (offsets[d] - ratio))
        };
        match branch {
            Branch::One { disc, pin } => one(disc, pin),
            Branch::Both { pins } => Some(0.5 * (one(0, pins[0])? + one(1, pins[1])?)),
        }
    }

    /// Fills `curve` (N values, rad) from the tables; returns false when the profile
    /// interferes at some point (the curve is then still filled, from the drive flanks,
    /// l < 0).
    /// With `stages`, also the parts [involute, cranks, contact] per point.
    pub(super) fn physical_curve(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        scratch: &mut TwoDiscScratch,
        curve: &mut [f64],
        stages: Option<&mut [[f64; 3]]>,
    ) -> bool {
        let n = common.points;
        let table = &self.drive;
        let coast_table = &self.coast;
        // Entry e of a drive block is slot s0 + e: its pin at shift k is (s0 + e − k) mod z_p.
        let s0 = self.drive_first_slot;
        let width = table.width;
        let pins = common.pins;
        // The smooth part, point by point in index order, from its expansion in products of
        // the sinusoids of z_p·Θ and (i − 1)·Θ (the loop vectorises).
        let coefficients = self.offset_coefficients(common, terms);
        let smooth = |d: usize, angles: [f64; 4]| smooth_offset(&coefficients[d], angles);
        for (d, offsets) in scratch.offsets.iter_mut().enumerate() {
            offsets.resize(n, 0.0);
            if !self.uniform_groups {
                let [sin, cos, sun_sin, sun_cos] = &self.columns;
                let angles = sin.iter().zip(cos).zip(sun_sin.iter().zip(sun_cos));
                for (offset, ((&y, &x), (&w, &u))) in offsets.iter_mut().zip(angles) {
                    *offset = smooth(d, [y, x, w, u]);
                }
            }
        }
        self.lay_out_row_errors(common, inputs, scratch);
        self.lay_out_lane_errors(common, scratch);
        let kappa = self.kappa;
        let first_contact = self.contact == DiscContact::FirstContact;
        // The coast flank matters only where the two discs' windows might not overlap:
        // first a floor for the whole row, then, where it is too low, one per group
        // (the group's coast sums less the largest pin terms), then the exact minimum.
        let row_floor = self.coast_floor(common, inputs, terms);
        let row_floor_holds = row_floor.iter().all(|f| f.is_finite());
        let (bound_r, bound_t) = terms.pin_bound;
        let TwoDiscScratch {
            offsets,
            pin_radial,
            pin_tangential,
            lane_radial,
            lane_tangential,
            tooth,
            drive,
            coast,
            ..
        } = scratch;
        let mut clear = true;
        scratch.narrowest = (f64::INFINITY, 0);
        for (group_index, group) in common.groups.iter().enumerate() {
            let points = &common.curve_points[group.start as usize..group.end as usize];
            let p = group.phase as usize;
            let blocks = [p, self.phase_2[p] as usize];
            let (s, c) = points[0].crank;
            let tooth_shift = points[0].tooth_shift as usize;
            let along = [Self::along(terms, 0, s, c), Self::along(terms, 1, s, c)];
            if self.uniform_groups {
                let angles = self.angles[points[0].index as usize];
                for (d, offsets) in offsets.iter_mut().enumerate() {
                    let value = smooth(d, angles);
                    for point in points {
                        offsets[point.index as usize] = value;
                    }
                }
            }
            let heads = GroupHeads {
                blocks,
                phase: p,
                tooth_shift,
                along,
            };
            self.fill_group_heads(common, terms, &heads, tooth, drive, true);
            let fill_coast = |coast: &mut [Vec<f64>; 2]| {
                self.fill_group_heads(common, terms, &heads, tooth, coast, false)
            };
            let mut coast_filled = false;
            let floor = if row_floor_holds {
                row_floor
            } else {
                fill_coast(coast);
                coast_filled = true;
                [0, 1].map(|d| {
                    let block = blocks[d] * width..(blocks[d] + 1) * width;
                    let columns = [
                        &coast_table.radial[block.clone()],
                        &coast_table.tangential[block],
                    ];
                    smallest_less_pins(&coast[d], columns[0], columns[1], bound_r, bound_t)
                })
            };
            let best = [smallest(&drive[0]), smallest(&drive[1])];
            let block = |d: usize| blocks[d] * width..(blocks[d] + 1) * width;
            let radial = [&table.radial[block(0)], &table.radial[block(1)]];
            let tangential = [&table.tangential[block(0)], &table.tangential[block(1)]];
            // The slots that can hold a disc's minimum at any of the group's points: those
            // whose sum less the largest pin terms is below the smallest sum plus them (in
            // whole quadruples).
            let narrow = common.per_pin && self.lane_shifts[group_index].is_none();
            let candidates = [0, 1].map(|d| match narrow {
                true => candidate_slots(&drive[d], radial[d], tangential[d], bound_r, bound_t),
                false => [0, width],
            });
            // A group of LANES points whose pins advance by a fixed stride: its minima for
            // all its points at once, the points as vector lanes.
            let lanes = match self.lane_shifts[group_index] {
                Some(first) if common.per_pin => Some([0, 1].map(|d| {
                    // (s0 − k) mod z_p: k < z_p, s0 < z_p.
                    let start = (pins - first[d] as usize + s0) % pins;
                    let lane_errors = (&lane_radial[start..], &lane_tangential[start..]);
                    lane_lags(
                        &drive[d],
                        radial[d],
                        candidates[d],
                        lane_errors.0,
                        lane_errors.1,
                    )
                })),
                _ => None,
            };
            // The lane group's points in one pass when the floor clears them all.
            if let Some(lags) = &lanes {
                if let Some(values) =
                    lane_values(lags, points, offsets, floor, kappa, first_contact)
                {
                    for (point, value) in points.iter().zip(values) {
                        curve[point.index as usize] = value;
                    }
                    continue;
                }
            }
            for (point_index, point) in points.iter().enumerate() {
                let j = point.index as usize;
                let offset = [offsets[0][j], offsets[1][j]];
                let shifts = [
                    point.pin_shift as usize,
                    self.pin_shift_2[group.start as usize + point_index] as usize,
                ];
                // low_d = κ·(C_d − K_d); first contact needs only their maximum, one scan
                // over both discs' slots of ratio − C_d. The first pin row of disc d's
                // drive entries, and of its coast entries (slot e: pin (e − k) mod z_p).
                let drive_start = shifts.map(|k| (pins - k + s0) % pins);
                let coast_start = shifts.map(|k| pins - k);
                let (low, drive_end) = if let Some(lags) = &lanes {
                    let low = [0, 1].map(|d| kappa * (offset[d] - lags[d][point_index]));
                    (low, if low[1] > low[0] { low[1] } else { low[0] })
                } else if !common.per_pin {
                    let low = [kappa * (offset[0] - best[0]), kappa * (offset[1] - best[1])];
                    (low, if low[1] > low[0] { low[1] } else { low[0] })
                } else if first_contact {
                    let pins = [&pin_radial[..], &pin_tangential[..]];
                    let columns = [radial, tangential];
                    let least = pair_least(drive, columns, candidates, drive_start, pins, offset);
                    ([0.0; 2], -kappa * least)
                } else {
                    let lag = [0, 1].map(|d| {
                        let start = drive_start[d];
                        smallest_ratio(
                            &drive[d],
                            radial[d],
                            tangential[d],
                            &pin_radial[start..start + width],
                            &pin_tangential[start..start + width],
                        )
                    });
                    let low = [kappa * (offset[0] - lag[0]), kappa * (offset[1] - lag[1])];
                    (low, if low[1] > low[0] { low[1] } else { low[0] })
                };
                let high = (kappa * (offset[0] + floor[0])).min(kappa * (offset[1] + floor[1]));
                if !overlap(high, drive_end) {
                    // The floor does not clear the point: the exact coast minimum.
                    if !coast_filled {
                        fill_coast(coast);
                        coast_filled = true;
                    }
                    let pin_errors = [&pin_radial[..], &pin_tangential[..]];
                    let high =
                        self.coast_high(common, coast, blocks, coast_start, pin_errors, offset);
                    if !overlap(high, drive_end) {
                        clear = false;
                        if high - drive_end < scratch.narrowest.0 {
                            scratch.narrowest = (high - drive_end, j);
                        }
                    }
                }
                curve[j] = if first_contact {
                    drive_end
                } else {
                    0.5 * (low[0] + low[1])
                };
            }
        }
        if let Some(stages) = stages {
            self.fill_stages(common, terms, offsets, curve, stages);
        }
        clear
    }

    /// The parts [involute, cranks, contact] of the curve at every point, from the discs'
    /// crank offsets C_d.
    fn fill_stages(
        &self,
        common: &Common,
        terms: &RowTerms,
        offsets: &[Vec<f64>; 2],
        curve: &[f64],
        stages: &mut [[f64; 3]],
    ) {
        for (j, stage) in stages.iter_mut().enumerate() {
            let involute = self.crank_offsets(common, terms, self.angles[j]).1;
            let crank = 0.5 * self.kappa * (offsets[0][j] + offsets[1][j]) - involute;
            *stage = [involute, crank, curve[j] - involute - crank];
        }
    }
}

impl Physical {
    /// A row's pin and tooth-space errors laid out for [`Self::physical_curve`]: repeated
    /// so that both flanks' tables read them in slot order (zeros where the model has no
    /// such inputs), and the discs' head columns sized to the table's width.
    fn lay_out_row_errors(&self, common: &Common, inputs: &[f64], scratch: &mut TwoDiscScratch) {
        let (pins, teeth, width) = (common.pins, common.cycloid_teeth, self.drive.width);
        let repeat = |target: &mut Vec<f64>, values: &[f64], len: usize| {
            target.clear();
            if values.is_empty() {
                target.resize(len, 0.0);
            } else {
                target.extend(values.iter().cycle().take(len));
            }
        };
        let n_pins = if common.per_pin { pins } else { 0 };
        let pin_inputs = &inputs[self.pin_base..self.pin_base + 2 * n_pins];
        let (pin_radial, pin_tangential) = pin_inputs.split_at(n_pins);
        repeat(&mut scratch.pin_radial, pin_radial, pins + width);
        repeat(&mut scratch.pin_tangential, pin_tangential, pins + width);
        let n_teeth = if common.per_tooth { teeth } else { 0 };
        for d in 0..2 {
            let errors =
                &inputs[self.tooth_base + d * n_teeth..self.tooth_base + (d + 1) * n_teeth];
            repeat(&mut scratch.tooth[d], errors, 2 * teeth);
        }
        for heads in [&mut scratch.drive, &mut scratch.coast] {
            for head in heads.iter_mut() {
                head.resize(width, 0.0);
            }
        }
    }

    /// The pin errors in lane order (after [`Self::lay_out_row_errors`]):
    /// lane_radial[q][m] = δr of pin (q − m·Δ) mod z_p, Δ the stride of the pin shift
    /// between a lane group's consecutive points. A tangential pin error's ratio is
    /// −δt·K1/(a·z_c) in every drive slot (see `lane_lags`).
    fn lay_out_lane_errors(&self, common: &Common, scratch: &mut TwoDiscScratch) {
        let pins = common.pins;
        let lane_rows = pins + self.drive.width;
        let tangential_ratio =
            -self.stage.k1() / (common.eccentricity * common.cycloid_teeth as f64);
        for (target, source, scale) in [
            (&mut scratch.lane_radial, &scratch.pin_radial, 1.0),
            (
                &mut scratch.lane_tangential,
                &scratch.pin_tangential,
                tangential_ratio,
            ),
        ] {
            target.clear();
            target.resize(lane_rows, [0.0; LANES]);
            if common.per_pin {
                // Column m is the pin list turned by m·Δ: walk it with a wrapping index.
                let step = pins - self.lane_stride;
                let mut first = 0;
                for m in 0..LANES {
                    let mut index = first;
                    for row in target.iter_mut() {
                        row[m] = source[index] * scale;
                        index += 1;
                        if index == pins {
                            index = 0;
                        }
                    }
                    first = (first + step) % pins;
                }
            }
        }
    }
}

/// A group's place in the tables, for [`Physical::fill_group_heads`]: each disc's
/// block, the phase (disc 2's tooth columns), the tooth shift k_j mod z_c and each disc's
/// displacement along its eccentric.
struct GroupHeads {
    blocks: [usize; 2],
    phase: usize,
    tooth_shift: usize,
    along: [f64; 2],
}

impl Physical {
    /// Fills both discs' head columns of a group on the drive flank (`drive_flank`) or the
    /// coast flank: the part of each slot's ratio common to the group's points
    /// (`fill_heads`; on the drive flank one pass for the pair where disc 2 sees disc 1's
    /// slots, even pin counts).
    fn fill_group_heads(
        &self,
        common: &Common,
        terms: &RowTerms,
        group: &GroupHeads,
        tooth: &[Vec<f64>; 2],
        heads: &mut [Vec<f64>; 2],
        drive_flank: bool,
    ) {
        let (table, width) = if drive_flank {
            (&self.drive, self.drive.width)
        } else {
            (&self.coast, self.drive.width)
        };
        let (blocks, p) = (group.blocks, group.phase);
        let teeth_of = |d: usize| -> &[u32] {
            let block = blocks[d] * width..(blocks[d] + 1) * width;
            match (d, drive_flank) {
                (0, _) => &table.tooth[block],
                (_, true) => &self.tooth_2_drive[p * width..(p + 1) * width],
                (_, false) => &self.tooth_2_coast[p * width..(p + 1) * width],
            }
        };
        let errors = |d: usize| &tooth[d][common.cycloid_teeth - group.tooth_shift..];
        if drive_flank && blocks[0] == blocks[1] {
            // Even pin counts: disc 2 sees disc 1's slots; one pass over the block.
            let [first, second] = heads;
            fill_heads_pair(
                table,
                blocks[0] * width..(blocks[0] + 1) * width,
                [teeth_of(0), teeth_of(1)],
                [errors(0), errors(1)],
                terms,
                group.along,
                [first, second],
            );
            return;
        }
        for (d, head) in heads.iter_mut().enumerate() {
            fill_heads(
                table,
                blocks[d] * width..(blocks[d] + 1) * width,
                teeth_of(d),
                errors(d),
                terms,
                terms.profile[d] - terms.err_rrp,
                group.along[d],
                head,
            );
        }
    }

    /// The upper end of the output's window at a point from the exact coast minimum of
    /// both discs (their coast heads filled): min_d κ·(C_d + lead_d), `coast_start` the
    /// first pin row of each disc's coast entries, `pin_errors` the repeated radial and
    /// tangential pin errors, `offset` the discs' C_d.
    fn coast_high(
        &self,
        common: &Common,
        coast: &[Vec<f64>; 2],
        blocks: [usize; 2],
        coast_start: [usize; 2],
        [pin_radial, pin_tangential]: [&[f64]; 2],
        offset: [f64; 2],
    ) -> f64 {
        let width = self.drive.width;
        let mut high = f64::INFINITY;
        for d in 0..2 {
            let lead = if common.per_pin {
                let block = blocks[d] * width..(blocks[d] + 1) * width;
                let start = coast_start[d];
                smallest_ratio(
                    &coast[d],
                    &self.coast.radial[block.clone()],
                    &self.coast.tangential[block],
                    &pin_radial[start..start + width],
                    &pin_tangential[start..start + width],
                )
            } else {
                smallest(&coast[d])
            };
            high = high.min(self.kappa * (offset[d] + lead));
        }
        high
    }
}

/// The first contact over both discs' candidate slots at one point (min over d and e of
/// ratio − C_d, [`smallest_ratio_pair`]): `columns` the discs' radial and tangential table
/// columns, `candidates` each disc's slot range, `starts` each disc's first pin row in the
/// repeated pin errors `pins` (radial, tangential), `offset` the discs' C_d.
fn pair_least(
    drive: &[Vec<f64>; 2],
    [radial, tangential]: [[&[f64]; 2]; 2],
    candidates: [[usize; 2]; 2],
    [first, second]: [usize; 2],
    [pin_radial, pin_tangential]: [&[f64]; 2],
    offset: [f64; 2],
) -> f64 {
    let ([a0, a1], [b0, b1]) = (candidates[0], candidates[1]);
    smallest_ratio_pair(
        [&drive[0][a0..a1], &drive[1][b0..b1]],
        [&radial[0][a0..a1], &radial[1][b0..b1]],
        [&tangential[0][a0..a1], &tangential[1][b0..b1]],
        [
            &pin_radial[first + a0..first + a1],
            &pin_radial[second + b0..second + b1],
        ],
        [
            &pin_tangential[first + a0..first + a1],
            &pin_tangential[second + b0..second + b1],
        ],
        offset,
    )
}

/// A lane group's curve values from its drive lags `lags` (both discs, the points as
/// lanes) when the row's or the group's coast floor clears every one of its points; None
/// when it does not clear them all (the points are then taken one by one).
fn lane_values(
    lags: &[[f64; LANES]; 2],
    points: &[Point],
    offsets: &[Vec<f64>; 2],
    floor: [f64; 2],
    kappa: f64,
    first_contact: bool,
) -> Option<[f64; LANES]> {
    let mut values = [0.0; LANES];
    let mut cleared = true;
    let mut offset = [[0.0; LANES]; 2];
    for (m, point) in points.iter().enumerate() {
        let j = point.index as usize;
        offset[0][m] = offsets[0][j];
        offset[1][m] = offsets[1][j];
    }
    for m in 0..LANES {
        let low = [
            kappa * (offset[0][m] - lags[0][m]),
            kappa * (offset[1][m] - lags[1][m]),
        ];
        let drive_end = if low[1] > low[0] { low[1] } else { low[0] };
        let high_0 = kappa * (offset[0][m] + floor[0]);
        let high_1 = kappa * (offset[1][m] + floor[1]);
        let high = if high_1 < high_0 { high_1 } else { high_0 };
        cleared &= high >= drive_end;
        values[m] = if first_contact {
            drive_end
        } else {
            0.5 * (low[0] + low[1])
        };
    }
    cleared.then_some(values)
}

/// A disc's smooth crank offset at the angles [sin z_pΘ, cos z_pΘ, sin (i−1)Θ, cos (i−1)Θ]
/// from its expansion `a` in their products ([`Physical::offset_coefficients`]).
#[inline(always)]
fn smooth_offset(a: &[f64; 12], [y, x, w, u]: [f64; 4]) -> f64 {
    a[0] + a[1] * x
        + a[2] * y
        + a[3] * u
        + a[4] * w
        + a[5] * (x * x)
        + a[6] * (x * y)
        + a[7] * (y * y)
        + a[8] * (x * u)
        + a[9] * (y * u)
        + a[10] * (x * w)
        + a[11] * (y * w)
}

/// min over both discs d and their slots e of head_de + δr·radial_de + δt·tangential_de −
/// C_d: −max_d (C_d − K_d), one reduction for the two discs.
#[inline(always)]
fn smallest_ratio_pair(
    head: [&[f64]; 2],
    radial: [&[f64]; 2],
    tangential: [&[f64]; 2],
    pin_radial: [&[f64]; 2],
    pin_tangential: [&[f64]; 2],
    offset: [f64; 2],
) -> f64 {
    let mut lanes = [f64::INFINITY; 4];
    for d in 0..2 {
        let count = head[d].len() / 4;
        let (h, a, b) = (
            quads(head[d], count),
            quads(radial[d], count),
            quads(tangential[d], count),
        );
        let (pa, pb) = (quads(pin_radial[d], count), quads(pin_tangential[d], count));
        for c in 0..count {
            for lane in 0..4 {
                let v =
                    h[c][lane] + pa[c][lane] * a[c][lane] + pb[c][lane] * b[c][lane] - offset[d];
                lanes[lane] = if v < lanes[lane] { v } else { lanes[lane] };
            }
        }
    }
    smallest_lane(lanes)
}

/// Whether a window's upper end `high` reaches its lower end `low` (false for NaN).
#[inline(always)]
fn overlap(high: f64, low: f64) -> bool {
    high >= low
}

/// Points of a lane group.
pub(super) const LANES: usize = 8;

/// The smallest ratio of each of a lane group's points over the slots [range), with the
/// pin errors in lane order from the group's first pin row.
#[inline(always)]
///
/// A tangential pin displacement δt projects on the contact normal as K1·sin φ/S and the
/// lever is a·z_c·sin φ/S, negative in a drive slot: its ratio −δt·K1/(a·z_c) is the same
/// in every drive slot, so the lanes carry it ready-made (`pin_tangential` holds
/// −δt·K1/(a·z_c)).
fn lane_lags(
    head: &[f64],
    radial: &[f64],
    range: [usize; 2],
    pin_radial: &[[f64; LANES]],
    pin_tangential: &[[f64; LANES]],
) -> [f64; LANES] {
    let mut lags = [f64::INFINITY; LANES];
    // Sliced to the range first, so that the loop carries no bounds checks.
    let [first, last] = range;
    let columns = head[first..last]
        .iter()
        .zip(&radial[first..last])
        .zip(&pin_radial[first..last])
        .zip(&pin_tangential[first..last]);
    for (((&h, &a), pr), pt) in columns {
        for m in 0..LANES {
            let v = h + pr[m] * a + pt[m];
            lags[m] = if v < lags[m] { v } else { lags[m] };
        }
    }
    lags
}

/// The range [first, last) of slots, in whole quadruples, outside which no slot can hold
/// the minimum of head_e + δr·radial_e + δt·tangential_e for |δr| ≤ R, |δt| ≤ T: a slot
/// whose head_e − R·|radial_e| − T·|tangential_e| exceeds min_f(head_f + R·|radial_f| +
/// T·|tangential_f|) never does.
#[inline(always)]
fn candidate_slots(head: &[f64], radial: &[f64], tangential: &[f64], r: f64, t: f64) -> [usize; 2] {
    let width = head.len();
    let mut upper = f64::INFINITY;
    for e in 0..width {
        let v = head[e] + r * radial[e].abs() + t * tangential[e].abs();
        upper = if v < upper { v } else { upper };
    }
    let reach = |e: usize| head[e] - r * radial[e].abs() - t * tangential[e].abs() <= upper;
    match (0..width).position(reach) {
        Some(first) => {
            let last = (0..width).rposition(reach).unwrap_or(first);
            [first / 4 * 4, (last / 4 + 1) * 4]
        }
        // Only when a sum is NaN: scan everything, so that the NaN reaches the curve.
        None => [0, width],
    }
}

/// min over e of head_e − R·|radial_e| − T·|tangential_e|: the smallest value a slot's
/// ratio can take over any pin errors with |δr| ≤ R and |δt| ≤ T.
#[inline(always)]
fn smallest_less_pins(head: &[f64], radial: &[f64], tangential: &[f64], r: f64, t: f64) -> f64 {
    let mut lanes = [f64::INFINITY; 4];
    let (head, radial, tangential) = (
        head.as_chunks::<4>().0,
        radial.as_chunks::<4>().0,
        tangential.as_chunks::<4>().0,
    );
    for ((h, a), b) in head.iter().zip(radial).zip(tangential) {
        for lane in 0..4 {
            let v = h[lane] - r * a[lane].abs() - t * b[lane].abs();
            lanes[lane] = if v < lanes[lane] { v } else { lanes[lane] };
        }
    }
    smallest_lane(lanes)
}

/// head_e = Δr_rp·eq_e + Δr_p·sh_e + δr_p·rad_e + constant/l_e + d_r·ecc_e + δ_n,j(e)/l_e +
/// blocked_e, over one block of a slot table.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn fill_heads(
    table: &PinTable,
    block: std::ops::Range<usize>,
    tooth_of: &[u32],
    space: &[f64],
    terms: &RowTerms,
    constant: f64,
    d_r: f64,
    head: &mut [f64],
) {
    let width = table.width;
    let blocked = &table.blocked[block.clone()][..width];
    let inverse_lever = &table.inverse_lever[block.clone()][..width];
    let equidistant = &table.equidistant[block.clone()][..width];
    let shift = &table.shift[block.clone()][..width];
    let eccentric = &table.eccentric[block.clone()][..width];
    let radial = &table.radial[block][..width];
    let head = &mut head[..width];
    for (value, &t) in head.iter_mut().zip(&tooth_of[..width]) {
        *value = space[t as usize];
    }
    for e in 0..width {
        head[e] = terms.d_rp * equidistant[e]
            + terms.d_p * shift[e]
            + terms.err_rp * radial[e]
            + constant * inverse_lever[e]
            + d_r * eccentric[e]
            + head[e] * inverse_lever[e]
            + blocked[e];
    }
}

/// [`fill_heads`] for both discs over one block (disc 2 in disc 1's slots): the table's
/// columns are read once.
#[inline(always)]
fn fill_heads_pair(
    table: &PinTable,
    block: std::ops::Range<usize>,
    tooth_of: [&[u32]; 2],
    space: [&[f64]; 2],
    terms: &RowTerms,
    along: [f64; 2],
    [first, second]: [&mut Vec<f64>; 2],
) {
    let width = table.width;
    let blocked = &table.blocked[block.clone()][..width];
    let inverse_lever = &table.inverse_lever[block.clone()][..width];
    let equidistant = &table.equidistant[block.clone()][..width];
    let shift = &table.shift[block.clone()][..width];
    let eccentric = &table.eccentric[block.clone()][..width];
    let radial = &table.radial[block][..width];
    let (first, second) = (&mut first[..width], &mut second[..width]);
    for e in 0..width {
        first[e] = space[0][tooth_of[0][e] as usize];
        second[e] = space[1][tooth_of[1][e] as usize];
    }
    let constant = [
        terms.profile[0] - terms.err_rrp,
        terms.profile[1] - terms.err_rrp,
    ];
    for e in 0..width {
        let common = terms.d_rp * equidistant[e]
            + terms.d_p * shift[e]
            + terms.err_rp * radial[e]
            + blocked[e];
        first[e] = common + (constant[0] + first[e]) * inverse_lever[e] + along[0] * eccentric[e];
        second[e] = common + (constant[1] + second[e]) * inverse_lever[e] + along[1] * eccentric[e];
    }
}

/// Per-thread work state of the physical reading.
#[derive(Debug, Default)]
pub(super) struct TwoDiscScratch {
    /// Pin errors in lane order (see `physical_curve`).
    pub lane_radial: Vec<[f64; LANES]>,
    pub lane_tangential: Vec<[f64; LANES]>,
    /// Per disc, C_d at every point, rad.
    pub offsets: [Vec<f64>; 2],
    pub pin_radial: Vec<f64>,
    pub pin_tangential: Vec<f64>,
    pub tooth: [Vec<f64>; 2],
    pub drive: [Vec<f64>; 2],
    pub coast: [Vec<f64>; 2],
    /// Where the discs fit least: (upper − lower end of the common window, rad at the
    /// output; the point j), among the points where they do not fit.
    pub narrowest: (f64, usize),
}

/// The options of the physical reading, before its tables are built.
pub(super) struct Settings {
    contact: DiscContact,
    closure: CrankClosure,
    crank_radius: f64,
    half_spacing: f64,
    sun_offset: f64,
    kappa: f64,
}

impl Physical {
    pub(super) fn settings(
        contact: DiscContact,
        closure: CrankClosure,
        crank_radius: f64,
        spacing: f64,
        sun_offset: f64,
        kappa: f64,
    ) -> Settings {
        Settings {
            contact,
            closure,
            crank_radius,
            half_spacing: spacing / 2.0,
            sun_offset,
            kappa,
        }
    }

    /// κ = z_c/D: what a disc-side angle is at the output.
    pub(super) fn kappa(&self) -> f64 {
        self.kappa
    }

    /// Where a row's per-pin inputs start (radial errors, then tangential).
    pub(super) fn pin_base(&self) -> usize {
        self.pin_base
    }

    /// Where a row's per-tooth-space inputs start (disc 1's, then disc 2's).
    pub(super) fn tooth_base(&self) -> usize {
        self.tooth_base
    }

    /// The semi-amplitudes of the output orders 1, z_c, z_p, 2·z_c and 2·z_p of a curve of
    /// N points (the direct DFT).
    pub(super) fn order_amplitudes(&self, curve: &[f64]) -> [f64; 5] {
        self.orders.amplitudes(curve)
    }
}

/// The factors of Δr_rp and Δr_p in the clearance of a pin at φ, either flank, measured
/// from the disc turned into drive-flank contact (the drive flank being the pins with
/// l < 0, which a forward drive loads: module comment). The centred modified disc has the
/// mirror-symmetric clearance c0 = Δr_rp − Δr_p·(1 − K1·cos φ)/S on both flanks; turned by
/// the half play δ* = (Δr_rp − Δr_p·√(1 − K1²))/(e·z_c) clockwise until the drive pin at
/// cos φ = K1 touches, each pin's clearance is c0 + l·δ*: 003's standard form mirrored,
/// Δr_rp·(1 + sin φ/S) − Δr_p·(1 − K1·cos φ + √(1 − K1²)·sin φ)/S, which vanishes at that
/// pin. The coast flank (l > 0) then has c0 + l·δ*, and over both flanks the play is 2δ*,
/// 000's (2Δr_rp − 2Δr_p·√(1 − K1²))/(e·z_c). From the pin's factors (003's standard form
/// 1 − sin φ/S and −(1 − K1·cos φ − √(1 − K1²)·sin φ)/S, the radial (1 − K1·cos φ)/S):
/// 2 − equidistant and −2·radial − shift, no root or division of its own.
#[inline(always)]
pub(super) fn modification(factors: &PinFactors) -> (f64, f64) {
    (
        2.0 - factors.equidistant,
        -2.0 * factors.radial - factors.shift,
    )
}

/// A flank's slot table (see [`PinTable`]): entry e of phase p is slot s = first + e at
/// φ = 2π(s + f)/z_p (f = `fraction_of(p)`), kept where the lever's sign is the flank's
/// (negative on the drive flank, positive on the coast flank) and the slot a pin's; the
/// factors over |l|, the modification from [`modification`].
fn flank_table(
    stage: &CycloidStage,
    phases: usize,
    width: usize,
    fraction_of: impl Fn(usize) -> f64,
    first: usize,
    drive: bool,
) -> PinTable {
    let pins = stage.pins;
    let mut table = PinTable {
        width,
        ..PinTable::default()
    };
    for p in 0..phases {
        let fraction = fraction_of(p);
        for e in 0..width {
            let slot = first + e;
            let phi = 2.0 * PI * (slot as f64 + fraction) / pins as f64;
            let sin = phi.sin();
            let side = if drive { -sin } else { sin };
            if slot >= pins || side <= 1e-12 {
                table.push_padding();
                continue;
            }
            let factors = stage.pin_factors(phi);
            let inverse_lever = 1.0 / factors.lever.abs();
            let (equidistant, shift) = modification(&factors);
            table.blocked.push(0.0);
            table.inverse_lever.push(inverse_lever);
            table.equidistant.push(equidistant * inverse_lever);
            table.shift.push(shift * inverse_lever);
            table.eccentric.push(factors.eccentric * inverse_lever);
            table.radial.push(factors.radial * inverse_lever);
            table.tangential.push(factors.tangential * inverse_lever);
            table.tooth.push(tooth_space(stage, phi, fraction));
        }
    }
    table
}

/// Points of the grid of [`Physical::floor_grid`] over (0, π).
const FLOOR_GRID: usize = 128;

/// [A, B, C] = [(1 − K1·cos φ)/S, |K1 − cos φ|/S, K1·|sin φ|/S] (the coast floor's factors;
/// even in φ, so (0, π) covers both flanks).
fn floor_factors(stage: &CycloidStage, phi: f64) -> [f64; 3] {
    let k1 = stage.k1();
    let (sin, cos) = phi.sin_cos();
    let s = (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
    [
        (1.0 - k1 * cos) / s,
        (k1 - cos).abs() / s,
        k1 * sin.abs() / s,
    ]
}

/// round(z_c·λ/2π − f) mod z_c: the tooth space of the slot at φ from its disc's eccentric,
/// λ the slot's polar angle about the disc centre, f the fractional pin pitch of disc 1.
fn tooth_space(stage: &CycloidStage, phi: f64, fraction: f64) -> u32 {
    let (sin, cos) = phi.sin_cos();
    let r_p = stage.pin_circle_radius;
    let polar = (r_p * sin).atan2(r_p * cos - stage.eccentricity);
    ((stage.teeth as f64 * polar / (2.0 * PI) - fraction).round() as i64)
        .rem_euclid(stage.teeth as i64) as u32
}

/// Builds the physical reading on the shared geometry `common`: the drive and coast tables,
/// disc 2's phases and tooth columns, and the per-point angles, with the options `settings`
/// and the preload rule `preload_rule`. `width`: the entries per phase of every table (the
/// ⌈z_p/2⌉ slots that can have a lever of one sign, rounded up to a multiple of 4);
/// `common_divisor`: g = gcd(z_c·z_p, N), the fractional pin pitch steps by g/N.
pub(super) fn build(
    stage: &CycloidStage,
    width: usize,
    common_divisor: usize,
    common: &Common,
    settings: Settings,
    preload_rule: PreloadRule,
) -> Physical {
    let (pins, teeth) = (stage.pins, stage.teeth);
    let (curve_points, groups) = (&common.curve_points, &common.groups);
    let n = common.points;
    let g = common_divisor;
    let phases = n / g;
    let fraction_of = |p: usize| p as f64 * g as f64 / n as f64;
    // Disc 2 sees the pins half a revolution of the eccentric on: z_p·N/2 in units of 1/N
    // pin pitch, which N/2 being a multiple of g keeps on the phase grid.
    let half_turn = pins * n / 2;
    let phase_2: Vec<u32> = (0..phases)
        .map(|p| (((p * g + half_turn) % n) / g) as u32)
        .collect();
    // Drive slots (sin φ < 0): s + f > z_p/2, so s ≥ ⌊z_p/2⌋, at most ⌈z_p/2⌉ of them;
    // coast slots (sin φ > 0): s + f < z_p/2, from s = 0.
    let drive_first_slot = pins / 2;
    let drive = flank_table(stage, phases, width, fraction_of, drive_first_slot, true);
    let coast = flank_table(stage, phases, width, fraction_of, 0, false);
    // Disc 2's tooth spaces, per disc-1 phase, relative to disc 1's tooth shift.
    let mut tooth_2_drive = Vec::with_capacity(phases * width);
    let mut tooth_2_coast = Vec::with_capacity(phases * width);
    for (p, &block_2) in phase_2.iter().enumerate() {
        let block_2 = block_2 as usize;
        let fraction = fraction_of(p);
        let fraction_2 = fraction_of(block_2);
        for e in 0..width {
            let drive_phi = 2.0 * PI * ((drive_first_slot + e) as f64 + fraction_2) / pins as f64;
            tooth_2_drive.push(if drive.blocked[block_2 * width + e] == 0.0 {
                tooth_space(stage, drive_phi, fraction)
            } else {
                0
            });
            let coast_phi = 2.0 * PI * (e as f64 + fraction_2) / pins as f64;
            tooth_2_coast.push(if coast.blocked[block_2 * width + e] == 0.0 {
                tooth_space(stage, coast_phi, fraction)
            } else {
                0
            });
        }
    }
    let pin_shift_2: Vec<u32> = curve_points
        .iter()
        .map(|point| {
            let turns = teeth * pins * point.index as usize + half_turn;
            ((turns / n) % pins) as u32
        })
        .collect();
    let lane_stride = (teeth * pins / g) % pins;
    let lane_shifts = groups
        .iter()
        .map(|group| {
            let (start, end) = (group.start as usize, group.end as usize);
            if end - start != LANES {
                return None;
            }
            let first = [curve_points[start].pin_shift, pin_shift_2[start]];
            let regular = (0..LANES).all(|m| {
                let expected = |k: u32| ((k as usize + m * lane_stride) % pins) as u32;
                curve_points[start + m].pin_shift == expected(first[0])
                    && pin_shift_2[start + m] == expected(first[1])
            });
            regular.then_some(first)
        })
        .collect();
    let angles: Vec<[f64; 4]> = (0..n)
        .map(|j| {
            let theta = 2.0 * PI * j as f64 / n as f64;
            let (s, c) = (2.0 * PI * ((pins * j) % n) as f64 / n as f64).sin_cos();
            // An integral sun order (120 for the RV40E) reduced exactly, as z_p·j is.
            let sun = common.ratio() - 1.0;
            let (ss, cs) = if sun.fract() == 0.0 {
                (2.0 * PI * ((sun as usize * j) % n) as f64 / n as f64).sin_cos()
            } else {
                (sun * theta).sin_cos()
            };
            [s, c, ss, cs]
        })
        .collect();
    let crank_angles = (0..common.cranks)
        .map(|k| (2.0 * PI * k as f64 / common.cranks as f64).sin_cos())
        .collect();
    let disc_base = FIXED.len();
    let crank_base = disc_base + 2 * PER_DISC.len();
    let pin_base = crank_base + CRANK_STRIDE * common.cranks;
    let tooth_base = pin_base + if common.per_pin { 2 * pins } else { 0 };
    Physical {
        contact: settings.contact,
        closure: settings.closure,
        crank_radius: settings.crank_radius,
        half_spacing: settings.half_spacing,
        sun_offset: settings.sun_offset,
        kappa: settings.kappa,
        preload_rule,
        stage: *stage,
        drive,
        drive_first_slot,
        coast,
        phase_2,
        tooth_2_drive,
        tooth_2_coast,
        pin_shift_2,
        lane_shifts,
        lane_stride,
        floor_grid: (0..FLOOR_GRID)
            .map(|k| floor_factors(stage, PI * (k as f64 + 0.5) / FLOOR_GRID as f64))
            .collect(),
        floor_slopes: {
            let fine = 64 * FLOOR_GRID;
            let step = PI / fine as f64;
            let mut slopes = [0.0f64; 3];
            for k in 0..fine {
                let (a, b) = (
                    floor_factors(stage, k as f64 * step),
                    floor_factors(stage, (k + 1) as f64 * step),
                );
                for i in 0..3 {
                    slopes[i] = slopes[i].max(2.0 * (b[i] - a[i]).abs() / step);
                }
            }
            slopes
        },
        uniform_groups: groups.iter().all(|group| {
            let first = angles[curve_points[group.start as usize].index as usize];
            curve_points[group.start as usize..group.end as usize]
                .iter()
                .all(|point| angles[point.index as usize] == first)
        }),
        columns: [0, 1, 2, 3].map(|i| angles.iter().map(|a| a[i]).collect()),
        angles,
        crank_angles,
        orders: OrderDft::new(n, [1, teeth, pins, 2 * teeth, 2 * pins]),
        disc_base,
        crank_base,
        pin_base,
        tooth_base,
    }
}

/// The inputs and outputs of the physical reading.
pub(super) fn specs(
    cranks: usize,
    pins: usize,
    teeth: usize,
    (per_pin, per_tooth): (bool, bool),
    loaded: bool,
) -> (Vec<InputSpec>, Vec<OutputSpec>) {
    let input = |name: String, unit: &str, description: &'static str| InputSpec {
        name,
        unit: unit.into(),
        description,
    };
    let mut inputs: Vec<InputSpec> = FIXED
        .iter()
        .map(|(name, unit, description)| input(name.to_string(), unit, description))
        .collect();
    for d in 1..=2 {
        for (name, description) in PER_DISC {
            inputs.push(input(format!("{name}_{d}"), "mm", description));
        }
    }
    for k in 1..=cranks {
        for (name, unit, description) in PER_CRANK {
            inputs.push(input(format!("{name}_{k}"), unit, description));
        }
        for d in 1..=2 {
            for (name, description) in PER_ECCENTRIC {
                inputs.push(input(format!("{name}_{k}_{d}"), "mm", description));
            }
        }
    }
    if per_pin {
        for i in 1..=pins {
            inputs.push(input(
                format!("pin_radial_error_mm_{i}"),
                "mm",
                "radial position error of pin i (outward), housing frame, both disc planes",
            ));
        }
        for i in 1..=pins {
            inputs.push(input(
                format!("pin_tangential_error_mm_{i}"),
                "mm",
                "tangential position error of pin i, housing frame, both disc planes",
            ));
        }
    }
    if per_tooth {
        for d in 1..=2 {
            for j in 1..=teeth {
                inputs.push(input(
                    format!("tooth_profile_error_mm_{d}_{j}"),
                    "mm",
                    "normal profile error of tooth space j of disc d, both flanks, disc frame (positive: clearance); space 1 on disc d's eccentric at Θ = 0",
                ));
            }
        }
    }
    // The rigid readings have no transmission error where the discs do not fit; the loaded
    // reading has one, which an over-preload makes non-conforming (docs/models.md §14.8).
    let condition = Some(if loaded {
        OutputCondition {
            indicator: crate::preload::OVER_PRELOADED,
            effect: ConditionEffect::NonConforming,
        }
    } else {
        OutputCondition {
            indicator: INTERFERENCE,
            effect: ConditionEffect::Excluded,
        }
    });
    let output = |name: String, description: &'static str| OutputSpec {
        name,
        unit: "arcsec".into(),
        description,
        kind: OutputKind::Continuous,
        condition,
    };
    let outputs = vec![
        output("te_peak_to_peak_arcsec".into(), "peak-to-peak transmission error over one output revolution (extremes refined on the exact geometry)"),
        output("te_rms_arcsec".into(), "rms of the transmission error about its mean"),
        output("te_mean_arcsec".into(), "mean of the transmission error (a constant angular offset; negative: the output lags)"),
        output("te_order_1_arcsec".into(), "semi-amplitude of order 1 (once per output revolution)"),
        output(format!("te_order_{teeth}_arcsec"), "semi-amplitude of order z_c (pin-borne errors that differ between the two discs)"),
        output(format!("te_order_{pins}_arcsec"), "semi-amplitude of order z_p (crank- and disc-borne errors)"),
        output(format!("te_order_{}_arcsec", 2 * teeth), "semi-amplitude of order 2·z_c (pin-borne errors seen by both discs)"),
        output(format!("te_order_{}_arcsec", 2 * pins), "semi-amplitude of order 2·z_p (crank-borne errors the two discs see in opposition)"),
        OutputSpec {
            name: INTERFERENCE.into(),
            unit: "fraction".into(),
            description: "1 when the two discs' angular windows between the pins fail to overlap somewhere on the revolution (a profile that interferes: no rigid transmission error)",
            kind: OutputKind::Indicator,
            condition: None,
        },
    ];
    let mut outputs = outputs;
    outputs.extend(crate::preload::outputs());
    (inputs, outputs)
}

/// Per lane of a curve's quadruples (the points j ≡ lane mod 4, in index order): the
/// smallest and the largest value, the quadruple at which each first occurs, and the sum.
pub(super) struct LaneStats {
    pub lo: [f64; 4],
    pub hi: [f64; 4],
    lo_at: [usize; 4],
    hi_at: [usize; 4],
    pub sum: [f64; 4],
}

/// [`LaneStats`] of a curve in one pass. Not inlined: inlined, LLVM vectorised the minima
/// and maxima but summed the lanes one by one (a chain of dependent scalar additions).
#[inline(never)]
pub(super) fn lane_stats(quads: &[[f64; 4]]) -> LaneStats {
    let (mut lo, mut hi, mut sum) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4], [0.0; 4]);
    let (mut lo_at, mut hi_at) = ([0; 4], [0; 4]);
    for (q, quad) in quads.iter().enumerate() {
        for lane in 0..4 {
            let v = quad[lane];
            let (below, above) = (v < lo[lane], v > hi[lane]);
            lo[lane] = if below { v } else { lo[lane] };
            lo_at[lane] = if below { q } else { lo_at[lane] };
            hi[lane] = if above { v } else { hi[lane] };
            hi_at[lane] = if above { q } else { hi_at[lane] };
            sum[lane] += v;
        }
    }
    LaneStats {
        lo,
        hi,
        lo_at,
        hi_at,
        sum,
    }
}

/// Per lane, Σ (v − mean)², in index order. Not inlined, for the same reason as
/// [`lane_stats`].
#[inline(never)]
pub(super) fn lane_squares(quads: &[[f64; 4]], mean: f64) -> [f64; 4] {
    let mut squares = [0.0; 4];
    for quad in quads {
        for lane in 0..4 {
            squares[lane] += (quad[lane] - mean) * (quad[lane] - mean);
        }
    }
    squares
}

/// The transmission error's own outputs, before the interference indicator and the preload
/// rule's five.
pub(super) const TE_OUTPUTS: usize = 8;

/// Name of the interference indicator.
pub(super) const INTERFERENCE: &str = "profile_interference";

impl Physical {
    /// [`crate::ErrorModel::evaluate`] of the physical reading's rigid pass: the rigid
    /// curve, the interference indicator and the preload rule's outputs, and the rigid
    /// readings' transmission error. `under_load` (the loaded reading): it returns the
    /// row's terms for the loaded solution to finish the row instead (the parent module
    /// dispatches, so that this reading does not depend on the loaded one).
    pub(super) fn evaluate_physical(
        &self,
        common: &Common,
        inputs: &[f64],
        curve: &mut Vec<f64>,
        scratch: &mut TwoDiscScratch,
        outputs: &mut [f64],
        under_load: bool,
    ) -> Option<RowTerms> {
        if inputs.iter().any(|v| !v.is_finite()) {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
            return None;
        }
        let terms = self.row_terms(common, inputs);
        curve.resize(common.points, 0.0);
        outputs[TE_OUTPUTS + 1..].fill(0.0);
        if !self.physical_curve(common, inputs, &terms, scratch, curve, None) {
            outputs[..TE_OUTPUTS].iter_mut().for_each(|o| *o = f64::NAN);
            outputs[TE_OUTPUTS] = 1.0;
            let theta = 2.0 * PI * scratch.narrowest.1 as f64 / common.points as f64;
            let judged = self.judge_preload(common, inputs, &terms, theta);
            outputs[TE_OUTPUTS + 1..].copy_from_slice(&judged);
            return under_load.then_some(terms);
        }
        if under_load {
            outputs[TE_OUTPUTS] = 0.0;
            return Some(terms);
        }
        let n = common.points;
        let quads = curve.as_chunks::<4>().0;
        let lanes = lane_stats(quads);
        let (lo, hi) = (
            lanes.lo.into_iter().fold(f64::INFINITY, f64::min),
            lanes.hi.into_iter().fold(f64::NEG_INFINITY, f64::max),
        );
        let sum = (lanes.sum[0] + lanes.sum[1]) + (lanes.sum[2] + lanes.sum[3]);
        let mean = sum / n as f64;
        let squares = lane_squares(quads, mean);
        let var = ((squares[0] + squares[1]) + (squares[2] + squares[3])) / n as f64;
        // The first point at which each extreme occurs: the lanes' first occurrences (a
        // search of the curve where an extreme is not finite).
        let first = |value: f64, lane_values: [f64; 4], at: [usize; 4]| {
            if value.is_finite() {
                (0..4)
                    .filter(|&lane| lane_values[lane] == value)
                    .map(|lane| 4 * at[lane] + lane)
                    .min()
            } else {
                curve.iter().position(|v| *v == value)
            }
        };
        let (lo, hi) = match (
            first(lo, lanes.lo, lanes.lo_at),
            first(hi, lanes.hi, lanes.hi_at),
        ) {
            (Some(j_lo), Some(j_hi)) => {
                self.refine_extremes(common, inputs, &terms, curve, (lo, j_lo), (hi, j_hi))
            }
            _ => (lo, hi),
        };
        // Five orders: summed directly, not by an FFT of all N/2.
        let orders = self.orders.amplitudes(curve);
        let to_arcsec = crate::ARCSEC_PER_RAD;
        outputs[0] = (hi - lo) * to_arcsec;
        outputs[1] = var.sqrt() * to_arcsec;
        outputs[2] = mean * to_arcsec;
        for (out, order) in outputs[3..8].iter_mut().zip(orders) {
            *out = order * to_arcsec;
        }
        outputs[TE_OUTPUTS] = 0.0;
        if !outputs[..TE_OUTPUTS].iter().all(|v| v.is_finite()) {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
        }
        None
    }

    /// The preload rule's five outputs at the output angle Θ where the discs fit least
    /// (docs/models.md §14.5): both discs' pins from the exact geometry, each disc at its
    /// crank offset C_d, balanced at zero torque.
    fn judge_preload(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        theta: f64,
    ) -> [f64; 5] {
        let rule = &self.preload_rule;
        let angles = common.angles_at(theta);
        let (offsets, _) = self.crank_offsets(common, terms, angles);
        let mut discs = [0, 1].map(|d| {
            let d_r = Self::along(terms, d, angles[0], angles[1]);
            let mut disc = DiscPins::new(offsets[d], 0.0);
            for pin in 0..common.pins {
                let phi = 2.0 * PI * pin as f64 / common.pins as f64
                    + common.cycloid_teeth as f64 * theta
                    + d as f64 * PI;
                let (sin, cos) = phi.rem_euclid(2.0 * PI).sin_cos();
                let (ratio, lever) =
                    self.exact_ratio_at(common, inputs, terms, d, pin, theta, d_r, (sin, cos));
                if lever.abs() > LEVER_FLOOR * common.eccentricity {
                    disc.push(
                        ratio * lever.abs(),
                        lever,
                        slip_arm(&self.stage, rule.pin_radius(), cos),
                    );
                }
            }
            disc
        });
        let load = zero_torque(rule.contact(), &mut discs);
        let class = rule.classify(&load, (true, false), (inputs[4], inputs[5]));
        [
            load.overlap_um,
            load.pin_force,
            load.no_load_torque,
            class.preloaded(),
            class.over(),
        ]
    }

    /// The curve's extremes refined on the exact geometry, rad. Near the maximum (a smooth
    /// maximum of one contact branch, since TE is the upper envelope of its branches) the
    /// winning branch's parabola through three points gives its vertex, and a second
    /// parabola through the vertex and points h/8 either side a better one, whose branch
    /// values are lower bounds of TE there; near the minimum (a kink where two branches cross) the
    /// crossing of the two branches' chords gives the angle at which TE is evaluated
    /// exactly. Both can only widen the sampled range towards the true one. `j_lo`, `j_hi`:
    /// the first points at which the sampled extremes `lo`, `hi` occur.
    pub(super) fn refine_extremes(
        &self,
        common: &Common,
        inputs: &[f64],
        terms: &RowTerms,
        curve: &[f64],
        (lo, j_lo): (f64, usize),
        (hi, j_hi): (f64, usize),
    ) -> (f64, f64) {
        let n = common.points;
        let h = 2.0 * PI / n as f64;
        let at = |j: usize| 2.0 * PI * j as f64 / n as f64;
        let mut best_hi = hi;
        let top = self.exact_flanks(common, inputs, terms, at(j_hi), false);
        // Two parabola steps: through the point and its neighbours, then through the first
        // vertex and points h/8 either side of it (a branch whose curvature changes fast
        // is far from a parabola over ±h).
        let (mut centre_at, mut spacing) = (at(j_hi), h);
        let mut centre = self.branch_value(common, inputs, terms, top.branch, centre_at);
        for _ in 0..2 {
            let values = [-spacing, spacing]
                .map(|dt| self.branch_value(common, inputs, terms, top.branch, centre_at + dt));
            let ([Some(before), Some(after)], Some(middle)) = (values, centre) else {
                break;
            };
            let curvature = before - 2.0 * middle + after;
            if curvature >= 0.0 {
                break;
            }
            let t = (0.5 * (before - after) / curvature).clamp(-1.0, 1.0);
            centre_at += t * spacing;
            centre = self.branch_value(common, inputs, terms, top.branch, centre_at);
            match centre {
                Some(v) => best_hi = best_hi.max(v),
                None => break,
            }
            spacing /= 8.0;
        }
        // The kink at the minimum lies towards the lower neighbour.
        let mut best_lo = lo;
        let (previous, next) = (curve[(j_lo + n - 1) % n], curve[(j_lo + 1) % n]);
        let side = if previous < next { -1.0 } else { 1.0 };
        let bottom = self.exact_flanks(common, inputs, terms, at(j_lo), false);
        let theta = at(j_lo) + side * h;
        let near = self.exact_flanks(common, inputs, terms, theta, false);
        if near.branch != bottom.branch {
            // Chords of the two branches from Θ_lo (t = 0) to its neighbour (t = 1).
            if let (Some(a_lo), Some(b_near)) = (
                self.branch_value(common, inputs, terms, near.branch, at(j_lo)),
                self.branch_value(common, inputs, terms, bottom.branch, theta),
            ) {
                let (a_near, b_lo) = (near.te, bottom.te);
                let denominator = (a_near - a_lo) - (b_near - b_lo);
                let t = (b_lo - a_lo) / denominator;
                if t > 0.0 && t < 1.0 {
                    let crossing =
                        self.exact_flanks(common, inputs, terms, at(j_lo) + side * t * h, false);
                    best_lo = best_lo.min(crossing.te);
                }
            }
        }
        (best_lo, best_hi)
    }

    /// The curve of one row from the exact geometry at `n` points (rad; NaN where the
    /// discs interfere), with the stage parts [involute, crank, contact].
    pub(super) fn exact_curve_stages(
        &self,
        common: &Common,
        inputs: &[f64],
        n: usize,
    ) -> Vec<(f64, [f64; 3])> {
        let terms = self.row_terms(common, inputs);
        (0..n)
            .map(|j| {
                let exact = self.exact(common, inputs, &terms, 2.0 * PI * j as f64 / n as f64);
                let te = if exact.clear { exact.te } else { f64::NAN };
                let crank = 0.5 * (exact.crank[0] + exact.crank[1]) - exact.involute;
                (te, [exact.involute, crank, te - exact.involute - crank])
            })
            .collect()
    }
}

/// Points of the exact curve the spectrum of `rvtol curve` is taken from: 2^16, so that the
/// contact's harmonics up to order 32768 are resolved before the orders up to N/2 are
/// listed (at N points the harmonics of the mesh order z_c·z_p alias).
pub(super) const SPECTRUM_POINTS: usize = 1 << 16;

/// The detail curve spans 1/DETAIL_FRACTION of a revolution (4.5°: some 20 cycles of the
/// RV40E's cycloid–pin mesh, order z_c·z_p = 1560; 819 points).
const DETAIL_FRACTION: usize = 80;

/// The loaded reading's curves of a row, for [`Physical::curves`].
pub(super) struct UnderLoad {
    /// T, N·m.
    pub torque: f64,
    /// The loaded transmission error at the curve's N points, arcsec.
    pub curve: Vec<f64>,
    /// The same at [`SPECTRUM_POINTS`], arcsec (None where a point has no solution).
    pub fine: Option<Vec<f64>>,
}

impl Physical {
    /// The curves of the physical reading: the tabulated curve with its stage parts, and
    /// the detail and the order spectrum (orders 1..N/2) of the exact curve at
    /// [`SPECTRUM_POINTS`]; with `under_load`, the loaded reading's curve first, and its
    /// detail and spectrum from its own curve at [`SPECTRUM_POINTS`] (where that has a
    /// solution at every point) in place of the rigid first contact's, which a preloaded or
    /// interfering assembly does not have.
    pub(super) fn curves(
        &self,
        common: &Common,
        inputs: &[f64],
        under_load: Option<UnderLoad>,
    ) -> Vec<crate::Curve> {
        use crate::{Curve, CurveStyle, Series, ARCSEC_PER_RAD};
        let n = common.points;
        let terms = self.row_terms(common, inputs);
        let mut curve = vec![0.0; n];
        let mut stages = vec![[0.0; 3]; n];
        let mut scratch = TwoDiscScratch::default();
        self.physical_curve(
            common,
            inputs,
            &terms,
            &mut scratch,
            &mut curve,
            Some(&mut stages),
        );
        let degrees = |j: usize| 360.0 * j as f64 / n as f64;
        let series = |label: &str, value: &dyn Fn(usize) -> f64| Series {
            label: label.into(),
            points: (0..n)
                .map(|j| (degrees(j), value(j) * ARCSEC_PER_RAD))
                .collect(),
        };
        // The loaded reading's curve first (its torque in the label), the rigid first
        // contact and its stages after it.
        let torque_label = |torque: f64| format!("{} N·m", rvtol_deviation::Shown(torque));
        let (loaded_series, total_label) = match &under_load {
            Some(load) => (
                Some(Series {
                    label: format!("total under load ({})", torque_label(load.torque)),
                    points: (0..n).map(|j| (degrees(j), load.curve[j])).collect(),
                }),
                "rigid first contact",
            ),
            None => (None, "total"),
        };
        let exact_stages = self.exact_curve_stages(common, inputs, SPECTRUM_POINTS);
        // The loaded curve at the detail's and the spectrum's points where there is one.
        let fine = under_load.and_then(|load| Some((load.torque, load.fine?)));
        let rigid: Vec<f64>;
        let exact: &[f64] = match &fine {
            Some((_, fine)) => fine,
            None => {
                rigid = exact_stages
                    .iter()
                    .map(|(te, _)| te * ARCSEC_PER_RAD)
                    .collect();
                &rigid
            }
        };
        // The first 1/DETAIL_FRACTION of the revolution on the exact geometry, fine enough
        // to resolve the cycloid–pin mesh (order z_c·z_p, 1560 for the RV40E), which the
        // tabulated curve's N points alias.
        let detail_points = SPECTRUM_POINTS / DETAIL_FRACTION;
        let detail_degrees = |j: usize| 360.0 * j as f64 / SPECTRUM_POINTS as f64;
        // Series of the total (part 0) or of stage part − 1.
        let detail = |label: &str, part: usize| Series {
            label: label.into(),
            points: exact_stages[..=detail_points]
                .iter()
                .enumerate()
                .map(|(j, (total, stages))| {
                    let value = if part == 0 { *total } else { stages[part - 1] };
                    (detail_degrees(j), value * ARCSEC_PER_RAD)
                })
                .collect(),
        };
        // Under load: the loaded total, and the involute and crank parts, which the load
        // leaves as they are (the rigid first contact's total and contact part are not
        // drawn: a preloaded or interfering assembly has none).
        let detail_series = match &fine {
            Some((torque, fine)) => vec![
                Series {
                    label: format!("total under load ({})", torque_label(*torque)),
                    points: (0..=detail_points)
                        .map(|j| (detail_degrees(j), fine[j]))
                        .collect(),
                },
                detail("involute stage", 1),
                detail("cranks", 2),
            ],
            None => vec![
                detail("total", 0),
                detail("involute stage", 1),
                detail("cranks", 2),
                detail("cycloid–pin contact", 3),
            ],
        };
        let spectrum_label = match &fine {
            Some((torque, _)) => format!(
                "under load ({}), {SPECTRUM_POINTS} points",
                torque_label(*torque)
            ),
            None => format!("exact curve, {SPECTRUM_POINTS} points"),
        };
        let fft = crate::RealFft::new(SPECTRUM_POINTS);
        let mut work = vec![(0.0, 0.0); SPECTRUM_POINTS / 2];
        fft.transform(exact, &mut work);
        vec![
            Curve {
                name: "transmission_error".into(),
                title: "Transmission error over one output revolution (two discs)".into(),
                x_label: "output angle (deg)".into(),
                y_label: "transmission error (arcsec)".into(),
                style: CurveStyle::Lines,
                series: loaded_series
                    .into_iter()
                    .chain([
                    series(total_label, &|j| curve[j]),
                    series("involute stage (common to the cranks)", &|j| stages[j][0]),
                    series(
                        "cranks (translation and four-bar, mean of the discs)",
                        &|j| stages[j][1],
                    ),
                    series(
                        "cycloid–pin contact (first contact over both discs)",
                        &|j| stages[j][2],
                    ),
                ])
                .collect(),
            },
            Curve {
                name: "transmission_error_detail".into(),
                title: format!(
                    "Transmission error, the first {}° of the revolution ({SPECTRUM_POINTS} points per revolution)",
                    360.0 / DETAIL_FRACTION as f64
                ),
                x_label: "output angle (deg)".into(),
                y_label: "transmission error (arcsec)".into(),
                style: CurveStyle::Lines,
                series: detail_series,
            },
            Curve {
                name: "transmission_error_spectrum".into(),
                title: "Order spectrum of the transmission error".into(),
                x_label: "order (cycles per output revolution)".into(),
                y_label: "semi-amplitude (arcsec)".into(),
                style: CurveStyle::LogStems,
                series: vec![Series {
                    label: spectrum_label,
                    points: (1..=n / 2)
                        .map(|k| (k as f64, fft.amplitude(&work, k)))
                        .collect(),
                }],
            },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{outputs, row, text, with, xorshift, MODIFIED};
    use super::super::TransmissionError;
    use super::*;
    use crate::{ErrorModel, ModelParams, ParamValue, ARCSEC_PER_RAD};

    /// The RV40E in the rigid first contact (the readings these tests check; the loaded
    /// reading's are in loaded/tests.rs).
    fn params() -> ModelParams {
        text(
            super::super::rv40e_params(),
            "disc_contact",
            "first_contact",
        )
    }

    /// 5 µm, the error size of 002 Table 2.
    const DELTA: f64 = 0.005;

    /// κ = z_c/D with D = z_p + z_s/z_pl = 121/3 (carrier feedback).
    const KAPPA: f64 = 39.0 / (121.0 / 3.0);

    /// A row with every input set: modification with play, and every error a few µm (tilts
    /// a few µm over the disc spacing).
    fn busy_row(model: &TransmissionError, seed: u64) -> Vec<f64> {
        let mut next = xorshift(seed);
        let mut row: Vec<f64> = model
            .inputs()
            .iter()
            .map(|input| {
                let scale = if input.unit == "rad" {
                    0.004 / 12.0
                } else {
                    0.004
                };
                scale * next()
            })
            .collect();
        for (name, value) in MODIFIED {
            row[model.input_index(name).unwrap()] = value;
        }
        row
    }

    #[test]
    fn tabulated_curve_equals_the_exact_geometry() {
        // The tables (disc 1's slots, the coast slots, disc 2 half a revolution of the
        // eccentric on, per-group sums) against the geometry recomputed pin by pin at every
        // point, with every input set: for the RV40E's 40 pins, for an odd pin count (disc
        // 2's slots then sit half a pitch off disc 1's) and for 3 pins in 4 slots, each
        // with 2 and 3 cranks and both contact readings.
        for (zp, cranks, contact) in [
            (40, 2, "first_contact"),
            (40, 3, "load_shared"),
            (41, 2, "first_contact"),
            (41, 3, "load_shared"),
            (3, 2, "first_contact"),
        ] {
            let model = with(text(
                params()
                    .with_number("pin_count", zp as f64)
                    .with_number("cycloid_teeth", (zp - 1) as f64)
                    .with_number("crank_count", cranks as f64)
                    .with_number("sun_plane_offset_mm", 40.0)
                    .with_number("pin_position_errors", 1.0)
                    .with_number("tooth_profile_errors", 1.0),
                "disc_contact",
                contact,
            ));
            let row = busy_row(&model, 0x2545_f491_4f6c_dd1d ^ zp as u64);
            let tabulated = model.curve(&row);
            let exact = model.exact_curve(&row, model.points()).unwrap();
            for (j, (a, b)) in tabulated.iter().zip(&exact).enumerate() {
                assert!(
                    (a - b).abs() < 1e-9 * b.abs().max(1.0),
                    "{zp} pins, {cranks} cranks, {contact}, point {j}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn interference_flag_equals_the_exact_windows() {
        // The coast flank's tables (a floor per row, one per group, then the exact minimum
        // over the slots) against the geometry pin by pin: the indicator is 1 exactly when
        // at some point of the curve the exact windows of the two discs fail to overlap.
        // Both eccentrics under disc 1 displaced by r across themselves turn its window
        // against disc 2's by κ·r/(a·z_c): the play 2δ* = 126.9″ at r = 30 µm, less what
        // the other inputs (every one set, a few µm) take, so the rows cross from clear to
        // interfering between 10 and 40 µm (40, 41 and 3 pins).
        for zp in [40, 41, 3] {
            let model = with(
                params()
                    .with_number("pin_count", zp as f64)
                    .with_number("cycloid_teeth", (zp - 1) as f64)
                    .with_number("pin_position_errors", 1.0)
                    .with_number("tooth_profile_errors", 1.0),
            );
            let phases = [1, 2].map(|k| {
                model
                    .input_index(&format!("crank_phase_error_mm_{k}_1"))
                    .unwrap()
            });
            let (mut clear, mut interfering) = (0, 0);
            for (k, r) in [0.0, 0.010, 0.020, 0.026, 0.028, 0.030, 0.032, 0.034, 0.040]
                .iter()
                .enumerate()
            {
                let mut row = busy_row(&model, 0x51f1_5eed ^ ((k as u64) << 4) ^ zp as u64);
                for index in phases {
                    row[index] = *r;
                }
                let flagged = outputs(&model, &row)[8] == 1.0;
                let (common, ph) = model.physical_parts();
                let terms = ph.row_terms(common, &row);
                let n = model.points();
                let exact = (0..n).any(|j| {
                    !ph.exact(common, &row, &terms, 2.0 * PI * j as f64 / n as f64)
                        .clear
                });
                assert_eq!(flagged, exact, "{zp} pins, runout {r}");
                if flagged {
                    interfering += 1;
                } else {
                    clear += 1;
                }
            }
            assert!(
                clear > 0 && interfering > 0,
                "{zp} pins: {clear} clear, {interfering} not"
            );
        }
    }

    #[test]
    fn order_outputs_are_the_fft_amplitudes_of_the_curve() {
        // The outputs' orders come from the direct DFT of the five orders: the same
        // amplitudes as the FFT of the curve, to the last bits (odd and even pin counts,
        // an odd one making z_p odd and z_c even).
        for zp in [40, 41, 13] {
            let model = with(
                params()
                    .with_number("pin_count", zp as f64)
                    .with_number("cycloid_teeth", (zp - 1) as f64)
                    .with_number("pin_position_errors", 1.0)
                    .with_number("tooth_profile_errors", 1.0),
            );
            for seed in 0..4 {
                let row = busy_row(&model, 0x9e37_79b9 ^ (seed << 8) ^ zp as u64);
                let out = outputs(&model, &row);
                assert_eq!(out[8], 0.0, "{zp} pins, seed {seed}");
                let spectrum = model.spectrum(&model.curve(&row));
                let largest = out[3..8].iter().fold(0.0f64, |a, &b| a.max(b));
                for (value, k) in out[3..8].iter().zip([1, zp - 1, zp, 2 * zp - 2, 2 * zp]) {
                    assert!(
                        (value - spectrum[k]).abs() <= 1e-14 * largest,
                        "{zp} pins, seed {seed}, order {k}: {value} vs {}",
                        spectrum[k]
                    );
                }
            }
        }
    }

    #[test]
    fn perfect_reducer_has_no_error() {
        let model = with(params());
        let out = outputs(&model, &row(&model, &[]));
        assert_eq!(out, vec![0.0; 14]);
    }

    #[test]
    fn four_bar_closure_turns_the_disc_by_the_eccentric_difference_over_2_aw() {
        // Crank 1's eccentric under disc 1 is 5 µm long, crank 2's 5 µm short: the disc's
        // pins are q1 − q2 = 2δ apart along the eccentric, whose component across the line
        // of the cranks, 2δ·sin(z_p·Θ), turns the rigid disc by (q1 − q2)⊥/(2·a_w) =
        // δ·sin(z_p·Θ)/a_w against the carrier (semi-amplitude 28.648″ at a_w = 36 mm);
        // the carrier follows at −ρ, so C_1 = −ρ. Disc 2's eccentrics are exact (C_2 = 0),
        // and with the cranks averaged (002) nothing turns.
        let model = with(params());
        let row = row(
            &model,
            &[
                ("crank_eccentricity_error_mm_1_1", DELTA),
                ("crank_eccentricity_error_mm_2_1", -DELTA),
            ],
        );
        let (common, ph) = model.physical_parts();
        let terms = ph.row_terms(common, &row);
        assert!((DELTA / 36.0 * ARCSEC_PER_RAD - 28.648).abs() < 5e-4);
        for j in 0..model.points() {
            let angles = ph.angles[j];
            let (offsets, _) = ph.crank_offsets(common, &terms, angles);
            let rho = -DELTA * angles[0] / 36.0;
            assert!((offsets[0] + rho).abs() < 1e-15, "{j}: {offsets:?} {rho}");
            assert_eq!(offsets[1], 0.0);
        }
        let averaged = with(text(params(), "crank_closure", "averaged"));
        let (common, ph) = averaged.physical_parts();
        let terms = ph.row_terms(common, &row);
        for &angles in &ph.angles {
            assert_eq!(ph.crank_offsets(common, &terms, angles).0, [0.0, 0.0]);
        }
    }

    #[test]
    fn paired_cranks_turn_the_two_discs_in_opposition() {
        // Crank 1's two eccentrics 5 µm long, crank 2's 5 µm short (a crank pair that is
        // not matched): the discs' eccentrics point opposite ways, so disc 2 turns by −ρ
        // where disc 1 turns by ρ = −δ·sin(z_p·Θ)/a_w. Load-shared, the output takes the
        // mean: nothing changes. First contact, it follows the disc ahead: κ·|ρ| added to
        // the modified curve, a full-wave rectified sine of semi-amplitude κ·δ/a_w =
        // 27.701″ with mean (2/π)·κ·δ/a_w and order-2z_p amplitude (4/3π)·κ·δ/a_w, and
        // nothing at order z_p. The discs' windows, 126.9″ wide, stay 2·28.6″ apart at
        // most: they overlap.
        let pairs = [
            ("crank_eccentricity_error_mm_1_1", DELTA),
            ("crank_eccentricity_error_mm_1_2", DELTA),
            ("crank_eccentricity_error_mm_2_1", -DELTA),
            ("crank_eccentricity_error_mm_2_2", -DELTA),
        ];
        let amplitude = KAPPA * DELTA / 36.0 * ARCSEC_PER_RAD;
        assert!((amplitude - 27.701).abs() < 5e-4, "{amplitude}");
        for contact in ["first_contact", "load_shared"] {
            let model = with(text(params(), "disc_contact", contact));
            let reference = model.curve(&row(&model, &MODIFIED));
            let mut set = MODIFIED.to_vec();
            set.extend(pairs);
            let paired = row(&model, &set);
            let curve = model.curve(&paired);
            for (j, (v, r)) in curve.iter().zip(&reference).enumerate() {
                let rectified = amplitude * model.physical_parts().1.angles[j][0].abs();
                let expected = if contact == "load_shared" {
                    0.0
                } else {
                    rectified
                };
                assert!((v - r - expected).abs() < 1e-9, "{contact} {j}: {v} {r}");
            }
            let out = outputs(&model, &paired);
            assert_eq!(out[8], 0.0, "no interference");
        }
        // The rectified sine's own spectrum, from its closed form (modification off, so
        // the reference curve is the flat mesh with a uniform offset removed by the FFT).
        let model = with(params());
        let base = model.curve(&row(&model, &MODIFIED));
        let mut set = MODIFIED.to_vec();
        set.extend(pairs);
        let curve = model.curve(&row(&model, &set));
        let difference: Vec<f64> = curve.iter().zip(&base).map(|(a, b)| a - b).collect();
        let spectrum = model.spectrum(&difference);
        // |sin x| = 2/π − (4/π)·Σ_n cos(2nx)/(4n² − 1), x = z_pΘ: order 80·n. On 4096
        // points the term n aliases onto order 80 when 80·(n ∓ 1) is a multiple of 4096
        // (n = 256·m ± 1) and onto the mean when 80·n is (n = 256·m): those terms bound
        // the difference. Order 40 takes no alias (80·n ∓ 40 is never a multiple of 4096).
        let term = |n: f64| 4.0 / (PI * (4.0 * n * n - 1.0)) * amplitude;
        // Terms m < M summed, the tail m ≥ M bounded by 2A/(π·256²·(M − 1)) (the terms
        // are below 2A/(π·(256·m)²)·(1 + 1e-5) there).
        let last = 10_000;
        let aliases = |offset: f64| -> f64 {
            let head: f64 = (1..last)
                .map(|m| 256.0 * m as f64)
                .map(|n| term(n - offset) + term(n + offset))
                .sum();
            let tail = 2.0 * amplitude / (PI * 65536.0 * (last - 1) as f64) * (1.0 + 1e-5);
            (head + tail) * if offset == 0.0 { 0.5 } else { 1.0 }
        };
        assert!(spectrum[40] < 1e-9, "{}", spectrum[40]);
        let order_80 = (spectrum[80] - term(1.0)).abs();
        assert!(
            order_80 < aliases(1.0) + 1e-9,
            "{order_80} {}",
            aliases(1.0)
        );
        let mean = (spectrum[0] - 2.0 / PI * amplitude).abs();
        assert!(mean < aliases(0.0) + 1e-9, "{mean} {}", aliases(0.0));
    }

    #[test]
    fn crank_phase_error_on_every_eccentric_lags_by_delta_over_a_d() {
        // Every eccentric 5 µm across (counter-clockwise, against the eccentric's
        // clockwise turn in the carrier): a pure translation T_y = δ, the disc turns by
        // −δ/(a·z_c) and the output by κ times that, −δ/(a·D) = −20.455″ (002's Δθ2 over
        // the cycloid ratio is δ/(a·z_c) = 21.155″: it forgets that the cranks ride on the
        // output). The same as the crank rotation λ = δ/a that the involute stage gives,
        // which reaches the output divided by D.
        let model = with(params());
        let set: Vec<(&str, f64)> = [
            "crank_phase_error_mm_1_1",
            "crank_phase_error_mm_1_2",
            "crank_phase_error_mm_2_1",
            "crank_phase_error_mm_2_2",
        ]
        .iter()
        .map(|name| (*name, DELTA))
        .collect();
        let lag = DELTA / (1.25 * 121.0 / 3.0) * ARCSEC_PER_RAD;
        assert!((lag - 20.456).abs() < 5e-4, "{lag}");
        let curve = model.curve(&row(&model, &set));
        assert!(curve.iter().all(|v| (v + lag).abs() < 1e-9), "{}", curve[0]);
    }

    #[test]
    fn involute_stage_is_the_crank_rotation_over_d() {
        // Centre distance +5 µm on both planets: each crank lags by δ·tan α/r2 (the mesh gap
        // δ·sin α over the base radius r2·cos α), which reaches the output as −δ·tan α/
        // (r2·D) = −0.345″ (validation.md: 0.348″ with the divisor 40, ×120/121 with the
        // feedback), as in 002's reading. Equal on both cranks, it turns no disc.
        let model = with(params());
        let set = [
            ("center_distance_error_mm_1", DELTA),
            ("center_distance_error_mm_2", DELTA),
        ];
        let lag = DELTA * 20f64.to_radians().tan() / (27.0 * 121.0 / 3.0) * ARCSEC_PER_RAD;
        let curve = model.curve(&row(&model, &set));
        assert!(
            curve.iter().all(|v| (v + lag).abs() < 1e-12),
            "{}",
            curve[0]
        );
    }

    #[test]
    fn pin_errors_cancel_at_odd_multiples_of_39_with_symmetric_discs() {
        // Pin-borne errors with identical discs: disc 2 sees disc 1's pins half a
        // revolution of the eccentric later, Θ + π/z_c, so the first-contact envelope
        // max(TE_1(Θ), TE_1(Θ + π/z_c)) has the period 2π/(2·z_c): nothing at order 39 (on
        // the 4096-point grid the samples of order 78·n cannot alias onto an odd multiple
        // of 39 either, 4096·m ± 39 being odd), its content at 78. The load-shared mean
        // cancels the same way. One disc's profile error breaks the symmetry and order 39
        // returns; with disc 2 retracted by 20 µm of profile (85″ of extra play, more than
        // the pin errors' ratios move) the curve is disc 1's alone: κ times 002's one-disc
        // curve mirrored. Disc 1's drive pins are those with l < 0, 002's those with l > 0
        // (002's reading keeps its own flank), so the two meet under the reflection
        // φ → −φ: pin i (0-based) at Θ is 002's pin (z_p − i) mod z_p at −Θ, with its
        // radial error and its tangential error reversed (the modification, the radial
        // factor and |l| are even in φ, the tangential factor odd).
        let mut next = xorshift(99);
        let errors: Vec<(f64, f64)> = (0..40).map(|_| (0.003 * next(), 0.003 * next())).collect();
        let named = |mirrored: bool| -> Vec<(String, f64)> {
            (0..40)
                .flat_map(|i| {
                    let (radial, tangential) = if mirrored {
                        let (r, t) = errors[(40 - i) % 40];
                        (r, -t)
                    } else {
                        errors[i]
                    };
                    [
                        (format!("pin_radial_error_mm_{}", i + 1), radial),
                        (format!("pin_tangential_error_mm_{}", i + 1), tangential),
                    ]
                })
                .collect()
        };
        let (pins, mirrored) = (named(false), named(true));
        let pins: Vec<(&str, f64)> = pins.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        let mut set = MODIFIED.to_vec();
        set.extend(&pins);
        for contact in ["first_contact", "load_shared"] {
            let model = with(text(
                params().with_number("pin_position_errors", 1.0),
                "disc_contact",
                contact,
            ));
            let out = outputs(&model, &row(&model, &set));
            let (order_39, order_78) = (out[4], out[6]);
            assert!(order_78 > 0.05, "{contact}: {order_78}");
            assert!(
                order_39 < 1e-12 * order_78.max(1.0),
                "{contact}: {order_39}"
            );
            let mut asymmetric = set.clone();
            asymmetric.push(("profile_normal_error_mm_1", 0.001));
            let out = outputs(&model, &row(&model, &asymmetric));
            assert!(out[4] > 1e-3, "{contact}: {}", out[4]);
        }
        let model = with(params().with_number("pin_position_errors", 1.0));
        let literal = with(
            params()
                .with_number("pin_position_errors", 1.0)
                .with("reading", ParamValue::Text("document_002".into())),
        );
        let mut retracted = set.clone();
        retracted.push(("profile_normal_error_mm_2", 0.02));
        let curve = model.curve(&row(&model, &retracted));
        let mut reflected = MODIFIED.to_vec();
        reflected.extend(mirrored.iter().map(|(n, v)| (n.as_str(), *v)));
        let one_disc = literal.curve(&row(&literal, &reflected));
        let n = curve.len();
        for (j, a) in curve.iter().enumerate() {
            let b = KAPPA * one_disc[(n - j) % n];
            assert!((a - b).abs() < 1e-9, "{j}: {a} vs {b}");
        }
    }

    #[test]
    fn crank_pattern_offset_moves_both_discs_in_opposition() {
        // The output flange's crank bores offset together from the main-bearing axis by b
        // (the physical reading of a flange runout: 002's δ41 has no pin holes to act on
        // in an RV reducer): both discs translate by b in the carrier, which their opposite
        // eccentrics see in opposition. Across the eccentric: C_d = ∓b·sin(z_pΘ)/(a·z_c)
        // (b = (δ, 0) in the carrier, disc 1's eccentric at −z_pΘ); along it: ±b·cos(z_pΘ).
        // Nothing turns a disc (equal bores), and no input of the physical reading is named
        // after the output pin holes.
        let model = with(params());
        assert!(model.input_index("output_runout_x_mm").is_none());
        let (common, ph) = model.physical_parts();
        let terms = ph.row_terms(
            common,
            &row(
                &model,
                &[
                    ("crank_axis_radial_error_mm_1", DELTA),
                    ("crank_axis_radial_error_mm_2", -DELTA),
                ],
            ),
        );
        for &angles in &ph.angles {
            let (offsets, _) = ph.crank_offsets(common, &terms, angles);
            let across = -DELTA * angles[0] / (1.25 * 39.0);
            assert!((offsets[0] - across).abs() < 1e-18, "{offsets:?} {across}");
            assert!((offsets[1] + across).abs() < 1e-18, "{offsets:?} {across}");
            let along = DELTA * angles[1];
            assert!((Physical::along(&terms, 0, angles[0], angles[1]) - along).abs() < 1e-18);
            assert!((Physical::along(&terms, 1, angles[0], angles[1]) + along).abs() < 1e-18);
        }
    }

    #[test]
    fn crank_tilt_displaces_the_two_disc_planes_oppositely() {
        // 001 Eq. 5–8: a tilt τ_t of crank 1 about its tangential direction moves its axis
        // radially by +τ_t·s/2 at disc 1 and −τ_t·s/2 at disc 2, exactly as radial bore
        // errors of +τ_t·s/2 and −τ_t·s/2 would at each plane; the mean over the two cranks
        // halves it. A tilt about the radial direction moves the axis tangentially by
        // −τ_r·z. The sun's tilt acts at L_s: Δβ·L_s along x, −Δα·L_s along y.
        // The example's discs sit on its eccentrics, s = 11 mm apart (s/2 = 5.5 mm).
        let model = with(params().with_number("sun_plane_offset_mm", 40.0));
        let tau = 1e-4;
        let (common, ph) = model.physical_parts();
        let terms = ph.row_terms(
            common,
            &row(&model, &[("crank_axis_tilt_tangential_rad_1", tau)]),
        );
        assert!((terms.v[0].0 - tau * 5.5 / 2.0).abs() < 1e-18);
        assert!((terms.v[1].0 + tau * 5.5 / 2.0).abs() < 1e-18);
        let terms = ph.row_terms(
            common,
            &row(&model, &[("crank_axis_tilt_radial_rad_1", tau)]),
        );
        assert!((terms.rho_const[0] + tau * 5.5).abs() < 1e-18);
        assert!((terms.rho_const[1] - tau * 5.5).abs() < 1e-18);
        let tilted = model.curve(&row(
            &model,
            &[("sun_tilt_y_rad", 1e-4), ("sun_tilt_x_rad", -5e-5)],
        ));
        let shifted = model.curve(&row(
            &model,
            &[
                ("sun_runout_x_mm", 1e-4 * 40.0),
                ("sun_runout_y_mm", 5e-5 * 40.0),
            ],
        ));
        for (a, b) in tilted.iter().zip(&shifted) {
            assert!((a - b).abs() < 1e-12);
        }
    }

    #[test]
    fn an_interfering_profile_is_flagged_and_has_no_transmission_error() {
        // A disc 20 µm too full (profile error −0.020 mm on disc 1): its play 2δ* = 126.9″
        // shrinks by 2·0.020/(a·z_c)-ish, 169″ at the longest lever: negative; and at the
        // pins by the eccentric the clearance Δr_rp − Δr_p = 18 µm turns negative on both
        // flanks, where 002's reading reports a lead of thousands of arcseconds (a
        // negative clearance over a lever near zero). Here the indicator is 1 and every
        // continuous output NaN; 5 µm too full (42″ less play) still fits.
        let model = with(params());
        let mut set = MODIFIED.to_vec();
        set.push(("profile_normal_error_mm_1", -0.020));
        let out = outputs(&model, &row(&model, &set));
        assert_eq!(out[8], 1.0);
        assert!(out[..8].iter().all(|v| v.is_nan()), "{out:?}");
        // The preload rule judges it (docs/models.md §14.5): preloaded, with a finite pin
        // force at zero torque; 20 µm of one disc's profile is far over the limit.
        assert_eq!((out[12], out[13]), (1.0, 1.0), "{out:?}");
        assert!(out[9] > 0.0 && out[10] > 0.0 && out[11] >= 0.0, "{out:?}");
        let mut set = MODIFIED.to_vec();
        set.push(("profile_normal_error_mm_1", -0.005));
        let out = outputs(&model, &row(&model, &set));
        assert_eq!(out[8], 0.0);
        assert!(out[..8].iter().all(|v| v.is_finite()), "{out:?}");
        assert_eq!(out[9..], [0.0; 5]);
        for spec in &model.outputs()[..8] {
            let expected = Some(crate::OutputCondition {
                indicator: INTERFERENCE,
                effect: crate::ConditionEffect::Excluded,
            });
            assert_eq!(spec.condition, expected, "{}", spec.name);
        }
        assert!(model.outputs()[8..]
            .iter()
            .all(|spec| spec.condition.is_none()));
    }
}
