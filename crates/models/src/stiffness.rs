//! The elastic elements between an RV reducer's output flange and its pins, other than the
//! pin contacts themselves (those are `cycloid_pin_contact`'s load sharing): the needle row
//! on each crank eccentric and the disc body around its bore, the crank shaft between its
//! support bearings, the support bearings, the carrier's wind-up (pillars and their roots
//! in the plates) and the involute first stage. `torsion_curve` chains them
//! in series with the pins (docs/models.md §13); `crank_elastic_error` uses the needle row.
//!
//! Units: lengths mm, forces N, torques N·mm, stiffnesses N/mm (translation) and N·mm/rad
//! (rotation), angles rad. Steel: E and ν are parameters of the models.
//!
//! ```text
//! line contact (Palmgren 1959; Harris 2001 §6.4): approach of one roller–raceway contact
//!   δ(Q) = 3.84·10⁻⁵·Q^0.9 / l^0.8                                      (mm, N, mm)
//! roller row under a radial load F (Stribeck–Palmgren, zero clearance, half the row
//! loaded; NSK "Bearing internal load distribution", Eq. 5):
//!   Q_max = 4.08·F/(Z·cos α),   δ_r(F) = 2·δ(Q_max)/cos α    (two contacts per roller)
//!   secant stiffness k(F) = F/δ_r(F)
//!
//! disc bore (the needle row has no outer ring: the disc is its housing). Palmgren's
//! formula is the approach of rollers and raceways; the disc around the bore deforms as
//! well, under the row's load spread as p(ψ) = p0·cos ψ over the loaded half of a bore of
//! radius a = d_j/2 + D in a plate of thickness t (net force P = π·a·t·p0/2). Plane stress,
//! the displacement of the bore at the load line, ψ = 0:
//!   Fourier harmonics of p: p0/π (n = 0), p0/2 (n = 1), 2p0·(−1)^(k+1)/(π(4k² − 1)) (n = 2k)
//!   n = 0 (Lamé, hole under pressure):          u = p_n·a·(1 + ν)/E
//!   n ≥ 2 (Michell, hole in an infinite plate):  u = p_n·a·(2n + 1 − ν)/(E·(n² − 1))
//!   summed (G the Catalan constant, 0.915966):
//!     u_oval = c_oval·P/(E·t),  c_oval = (2/π²)·((1 + ν) + 2(G − ½) + 2(1 − ν)(½ − π/8))
//!     (0.46246 for ν = 0.3)
//!   n = 1, the net force carried to the pins at the rim, R = r_p − a_w from the bore's
//!   centre: Kelvin's plane-stress point force, bore against rim along the load
//!     u_net = (1 + ν)(3 − ν)/(4π)·ln(R/a)·P/(E·t)
//!   c_bore = (c_oval + (1 + ν)(3 − ν)/(4π)·ln(R/a))/(E·t)       (mm/N, linear, both modes)
//! support bearings' seats: each outer ring sits in a carrier plate as thick as the bearing
//! is wide (B); Palmgren's formula holds for rings in a rigid housing, so the plate's bore
//! adds its ovalisation, c_seat = c_oval/(E·B), in series with each support's row (the
//! net force's path through the plate to the pillars is left out: a deep ring, a few per
//! cent of the pillars' compliance).
//!
//! crank shaft: a uniform solid beam of diameter d on two simple supports (the support
//! bearings, span L), eccentric planes at x1 = (L − s)/2 and x2 = (L + s)/2; deflection at
//! x per unit load at a (b = L − a), x ≤ a, Euler–Bernoulli plus Timoshenko shear
//! (Roark, Table 8.1 case 1e; Timoshenko & Gere 1972 §2.9):
//!   w(x; a) = b·x·(L² − b² − x²)/(6·E·I·L) + b·x/(κ·G·A·L)      (mirror for x > a)
//!   I = π·d⁴/64, A = π·d²/4, G = E/(2(1 + ν)), κ = 6(1 + ν)/(7 + 6ν) (solid circle)
//! the two discs load each crank in two modes (docs/models.md §13):
//!   symmetric (the disc torque: the same force at x1 and x2)
//!     c_S = w(x1; x1) + w(x1; x2),  support shares S_A = (2L − x1 − x2)/L, S_B = (x1 + x2)/L
//!   antisymmetric (the pin resultant and eccentric misfits: opposite forces, the two
//!   discs' eccentrics being 180° apart)
//!     c_A = w(x1; x1) − w(x1; x2),  support shares A_A = (x2 − x1)/L, A_B = −A_A
//!   support bearings (roller rows) add, at the plane x1,
//!     c_sup = share_A·(1 − x1/L)/k_A + share_B·(x1/L)/k_B
//!
//! carrier: the support B sits in the carrier plate that n_p pillars (width b tangential,
//! depth h radial, length L_p, on the radius r_p) join to the output flange, which carries
//! support A; each pillar is clamped in both plates (a fixed–guided beam) and twists:
//!   K_c = n_p·r_p²/(L_p³/(12·E·h·b³/12) + L_p/(κ_r·G·b·h)) + n_p·G·J_p/L_p
//!   κ_r = 5/6 (rectangle), J_p = β·max(b,h)·min(b,h)³, β from Roark Table 10.7 case 4;
//! the plates are not rigid where a pillar enters them: each root is the pillar's section
//! as a rigid footing on an elastic half-space (sliding Bycroft 1956, rocking Borowicka
//! 1943, twisting Reissner & Sagoci 1944; Gazetas 1991 Table 1, equivalent radii of
//! Richart, Hall & Woods 1970):
//!   K_h = 8·G·R_h/(2 − ν),       R_h = √(b·h/π)
//!   K_r = 8·G·R_r³/(3(1 − ν)),   R_r = (4·I/π)^¼, I = h·b³/12 (rocking in the tangential plane)
//!   K_t = 16·G·R_t³/3,           R_t = (2·I_p/π)^¼, I_p = b·h·(b² + h²)/12
//! with both roots alike the pillar still bends about its middle (moment F·L_p/2 at each
//! root), so a pillar on its roots has the lateral and twist compliances
//!   c_lat = L_p³/(12·E·I) + L_p/(κ_r·G·b·h) + 2/K_h + L_p²/(2·K_r),   c_tw = L_p/(G·J_p) + 2/K_t
//!   K_c = n_p·(r_p²/c_lat + 1/c_tw)
//! (a plate of finite thickness, and a bolted end plate, are softer than the half-space:
//! the roots are a lower bound of that compliance);
//! support B moves tangentially by the carrier twist, which moves the eccentric planes by
//! x1/L and x2/L of it; the two discs carrying equal shares, the output sees their mean:
//!     c_car = m·S_B·a_w²·((x1 + x2)/(2L))/K_c   (symmetric mode only)
//!
//! involute stage (input locked): the sun–planet mesh (ISO 6336-1 mesh stiffness c_γ per mm
//! of face width b) and the crank's torsion between its planet and its eccentrics turn the
//! crank by δφ = M_c·(1/(c_γ·b·r_b2²) + L_t/(G·J)); the crank torque is
//! M_c = T·(z2/z1)/(i·m) and δφ reaches the output as δφ·z2/(z1·i), so
//!   C_inv = (z2/(z1·i))²·(1/(c_γ·b·r_b2²) + L_t/(G·J))/m                (rad per N·mm)
//! ```
//!
//! Sign convention: every compliance and deflection is a positive magnitude along the
//! load; the models give them their signs.
//!
//! Left out, and why (docs/models.md §13 gives their sizes): radial clearance of the rows
//! (their free play is `geometric_hysteresis`'s Δu; at 2 µm it changes the 50–100 % slope
//! of an RV-20E needle row by under 1 %, checked in the tests), preload of the support
//! bearings (it stiffens them: the unpreloaded secant is the softer bound), edge loading of
//! a row whose journal tilts with the shaft's bending, the bending of the disc's lobes, the
//! plates' bores around the support bearings and their in-plane paths to the pillars, the
//! housing and the main bearings (they carry no torque about the axis), the planet gear's
//! force on the crank shaft (about 3 % of the eccentric loads).

use std::f64::consts::PI;

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
        let net = (1.0 + poisson) * (3.0 - poisson) / (4.0 * PI)
            * (rim_distance / bore_radius).ln().max(0.0);
        (bore_ovalisation_factor(poisson) + net) / (youngs * thickness)
    }
}

/// Catalan's constant G = Σ (−1)^k/(2k + 1)², to f64 precision.
const CATALAN: f64 = 0.915_965_594_177_219;

/// c_oval: the displacement of a bore at its load line under a row's load spread as
/// cos ψ over the loaded half, per P/(E·t), without the net force's n = 1 harmonic
/// (module comment): (2/π²)·((1 + ν) + 2(G − ½) + 2(1 − ν)(½ − π/8)).
fn bore_ovalisation_factor(poisson: f64) -> f64 {
    2.0 / (PI * PI)
        * ((1.0 + poisson) + 2.0 * (CATALAN - 0.5) + 2.0 * (1.0 - poisson) * (0.5 - PI / 8.0))
}

/// A crank shaft on its two support bearings with the eccentrics of the two discs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrankShaft {
    /// L, span between the support bearings' load centres, mm.
    pub span: f64,
    /// x1, plane of the first disc's eccentric from support A, mm.
    pub first: f64,
    /// x2, plane of the second disc's eccentric from support A, mm.
    pub second: f64,
    /// E·I, N·mm².
    pub bending_rigidity: f64,
    /// κ·G·A, N.
    pub shear_rigidity: f64,
    /// G·J, N·mm²/rad.
    pub torsional_rigidity: f64,
}

/// The compliances of a crank shaft at its first eccentric plane in the two load modes
/// (module comment), per newton at each eccentric, mm/N, and the shares of the load that
/// each support carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShaftModes {
    /// c_S, the same force on both eccentrics.
    pub symmetric: f64,
    /// c_A, opposite forces on the two eccentrics.
    pub antisymmetric: f64,
    /// (S_A, S_B): support reactions per newton on each eccentric, symmetric mode.
    pub symmetric_reactions: (f64, f64),
    /// (A_A, A_B): support reactions per newton, antisymmetric mode (+1 at x1, −1 at x2).
    pub antisymmetric_reactions: (f64, f64),
}

impl CrankShaft {
    /// A solid round shaft of `diameter`, supports `span` apart, eccentric planes `spacing`
    /// apart and centred between the supports; E (MPa) and ν.
    pub fn new(diameter: f64, span: f64, spacing: f64, youngs: f64, poisson: f64) -> Self {
        let shear_modulus = youngs / (2.0 * (1.0 + poisson));
        let kappa = 6.0 * (1.0 + poisson) / (7.0 + 6.0 * poisson);
        let area = PI * diameter * diameter / 4.0;
        let inertia = PI * diameter.powi(4) / 64.0;
        CrankShaft {
            span,
            first: 0.5 * (span - spacing),
            second: 0.5 * (span + spacing),
            bending_rigidity: youngs * inertia,
            shear_rigidity: kappa * shear_modulus * area,
            torsional_rigidity: shear_modulus * 2.0 * inertia,
        }
    }

    /// Deflection at `at` (mm from support A) per newton at `load_at`, rigid supports,
    /// mm/N (module comment).
    pub fn influence(&self, at: f64, load_at: f64) -> f64 {
        let length = self.span;
        // Mirror so that the point lies left of the load: w(x; a) = w(L − x; L − a).
        let (x, a) = if at <= load_at {
            (at, load_at)
        } else {
            (length - at, length - load_at)
        };
        let b = length - a;
        b * x * (length * length - b * b - x * x) / (6.0 * self.bending_rigidity * length)
            + b * x / (self.shear_rigidity * length)
    }

    /// The two load modes at the first eccentric plane.
    pub fn modes(&self) -> ShaftModes {
        let (x1, x2, length) = (self.first, self.second, self.span);
        let direct = self.influence(x1, x1);
        let cross = self.influence(x1, x2);
        let anti_a = (x2 - x1) / length;
        ShaftModes {
            symmetric: direct + cross,
            antisymmetric: direct - cross,
            symmetric_reactions: ((2.0 * length - x1 - x2) / length, (x1 + x2) / length),
            antisymmetric_reactions: (anti_a, -anti_a),
        }
    }

    /// Weights (1 − x1/L, x1/L) with which the deflections of supports A and B move the
    /// first eccentric plane.
    pub fn support_weights(&self) -> (f64, f64) {
        (1.0 - self.first / self.span, self.first / self.span)
    }
}

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
        let shear_modulus = youngs / (2.0 * (1.0 + poisson));
        let (b, h, length) = (self.width, self.depth, self.length);
        let (sliding, rocking, twisting) = self.root_compliances(youngs, poisson);
        let lateral = length.powi(3) / (12.0 * youngs * h * b.powi(3) / 12.0)
            + length / (5.0 / 6.0 * shear_modulus * b * h)
            + 2.0 * sliding
            + 0.5 * length * length * rocking;
        let (long, short) = (b.max(h), b.min(h));
        let twist = rectangle_torsion_factor(long / short) * long * short.powi(3);
        let twist_compliance = length / (shear_modulus * twist) + 2.0 * twisting;
        self.pillars * (self.radius * self.radius / lateral + 1.0 / twist_compliance)
    }
}

/// β of a solid rectangle's torsion constant J = β·a·b³ (a ≥ b), Roark & Young Table 10.7
/// case 4: β = 1/3 − 0.21·(b/a)·(1 − (b/a)⁴/12).
fn rectangle_torsion_factor(aspect: f64) -> f64 {
    let ratio = 1.0 / aspect;
    1.0 / 3.0 - 0.21 * ratio * (1.0 - ratio.powi(4) / 12.0)
}

/// The involute first stage seen from the output with the input locked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvoluteStage {
    /// z1, sun teeth.
    pub sun_teeth: f64,
    /// z2, planet teeth.
    pub planet_teeth: f64,
    /// m, cranks (planets).
    pub cranks: f64,
    /// r_b2, planet base radius, mm.
    pub planet_base_radius: f64,
    /// b, face width of the sun–planet mesh, mm.
    pub face_width: f64,
    /// c_γ, mesh stiffness per mm of face width, N/mm per mm (ISO 6336-1: N/(mm·µm) × 1000).
    pub mesh_stiffness: f64,
    /// L_t, crank length between the planet gear and the middle of its eccentrics, mm.
    pub torsion_length: f64,
}

impl InvoluteStage {
    /// C_inv, output angle per output torque, rad per N·mm, for the overall ratio `ratio`
    /// and the crank's torsional rigidity G·J (module comment).
    pub fn output_compliance(&self, ratio: f64, crank_torsional_rigidity: f64) -> f64 {
        let reflection = self.planet_teeth / (self.sun_teeth * ratio);
        let crank = 1.0 / (self.mesh_stiffness * self.face_width * self.planet_base_radius.powi(2))
            + self.torsion_length / crank_torsional_rigidity;
        reflection * reflection * crank / self.cranks
    }
}

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
    /// The crank shaft.
    pub shaft: CrankShaft,
    /// One support bearing row (both supports alike).
    pub support: RollerRow,
    /// The carrier plate around one support bearing's outer ring, mm/N (0: rigid plates).
    pub support_housing_compliance: f64,
    /// K_c, N·mm/rad.
    pub carrier_stiffness: f64,
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
    /// Crank shaft bending and shear.
    pub shaft: f64,
    /// Support bearings.
    pub support: f64,
    /// Carrier wind-up.
    pub carrier: f64,
    /// Involute stage and crank torsion.
    pub involute: f64,
}

impl ChainTerms {
    /// The sum of the terms.
    pub fn total(&self) -> f64 {
        self.needle + self.disc_bore + self.shaft + self.support + self.carrier + self.involute
    }
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
    /// the pins see as a turn of F_x·c_A/(m·e·z_c) (docs/models.md §13).
    pub fn terms(
        &self,
        disc_torque: f64,
        force: (f64, f64),
        needle_factor: f64,
        output_torque: f64,
        reflection: f64,
    ) -> ChainTerms {
        if disc_torque <= 0.0 {
            return ChainTerms::default();
        }
        let (m, a) = (self.cranks, self.crank_circle_radius);
        let tangential = disc_torque / (m * a);
        let shared = force.0.hypot(force.1) / m;
        // Output angle per unit compliance in each mode.
        let symmetric = reflection * disc_torque / (m * a * a);
        let antisymmetric = reflection * force.0.abs() / (m * self.pitch_radius);
        let needle_load = tangential.hypot(shared);
        let needle = self.needle.secant_compliance(needle_load) / needle_factor;
        let modes = self.shaft.modes();
        let (weight_a, weight_b) = self.shaft.support_weights();
        let (s_a, s_b) = modes.symmetric_reactions;
        let (anti_a, anti_b) = modes.antisymmetric_reactions;
        let load_a = (tangential * s_a).hypot(shared * anti_a);
        let load_b = (tangential * s_b).hypot(shared * anti_b);
        let (compliance_a, compliance_b) = (
            self.support.secant_compliance(load_a) + self.support_housing_compliance,
            self.support.secant_compliance(load_b) + self.support_housing_compliance,
        );
        let support_symmetric = s_a * weight_a * compliance_a + s_b * weight_b * compliance_b;
        let support_antisymmetric =
            anti_a * weight_a * compliance_a + anti_b * weight_b * compliance_b;
        // Support B's tangential shift reaches the planes x1 and x2 by x1/L and x2/L; the
        // two discs share the load equally, so the output sees the mean.
        let mean_plane = 0.5 * (self.shaft.first + self.shaft.second) / self.shaft.span;
        let carrier = m * s_b * a * a * mean_plane / self.carrier_stiffness;
        ChainTerms {
            needle: (symmetric + antisymmetric) * needle,
            disc_bore: (symmetric + antisymmetric) * self.bore_compliance,
            shaft: symmetric * modes.symmetric + antisymmetric * modes.antisymmetric,
            support: symmetric * support_symmetric + antisymmetric * support_antisymmetric,
            carrier: symmetric * carrier,
            involute: self.involute_compliance * output_torque,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn shaft_influence_is_the_textbook_beam() {
        // Load at mid-span: w(L/2) = P·L³/(48EI) + P·L/(4κGA) (bending plus shear).
        let shaft = CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3);
        let (ei, kga) = (shaft.bending_rigidity, shaft.shear_rigidity);
        let mid = shaft.influence(14.0, 14.0);
        let hand = 28f64.powi(3) / (48.0 * ei) + 28.0 / (4.0 * kga);
        assert!((mid / hand - 1.0).abs() < 1e-14);
        // Maxwell–Betti reciprocity: w(x; a) = w(a; x).
        for (x, a) in [(3.0, 20.0), (9.5, 18.5), (25.0, 1.0)] {
            let (w1, w2) = (shaft.influence(x, a), shaft.influence(a, x));
            assert!((w1 / w2 - 1.0).abs() < 1e-12, "{x} {a}");
        }
        // EI and κGA of a 15 mm solid shaft: I = π·15⁴/64 = 2485.05 mm⁴,
        // κ = 6·1.3/8.8 = 0.886364, G = 79 230.8 MPa, A = 176.715 mm².
        assert!((ei / (206_000.0 * 2485.049) - 1.0).abs() < 1e-6);
        assert!((kga / (0.886364 * 79_230.77 * 176.7146) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn shaft_modes_split_the_load() {
        // Hand calculation, span 28, spacing 9 (x1 = 9.5, x2 = 18.5): S_A = S_B = 1 (each
        // support takes one eccentric's force in the symmetric mode), A_A = 9/28.
        let shaft = CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3);
        let modes = shaft.modes();
        assert_eq!(modes.symmetric_reactions, (1.0, 1.0));
        assert!((modes.antisymmetric_reactions.0 - 9.0 / 28.0).abs() < 1e-15);
        assert_eq!(
            modes.antisymmetric_reactions.1,
            -modes.antisymmetric_reactions.0
        );
        // Symmetric: the superposed two-load deflection; antisymmetric is smaller.
        let direct = shaft.influence(9.5, 9.5);
        let cross = shaft.influence(9.5, 18.5);
        assert_eq!(modes.symmetric, direct + cross);
        assert!(modes.antisymmetric < modes.symmetric && modes.antisymmetric > 0.0);
        // Two equal loads P at a = x1 and L − a, bending alone: the deflection under a load
        // is P·a²·(3L − 4a)/(6EI) (the symmetric two-load case of Roark Table 8.1).
        let bending_only = CrankShaft {
            shear_rigidity: f64::INFINITY,
            ..shaft
        };
        let a: f64 = 9.5;
        let hand = a * a * (3.0 * 28.0 - 4.0 * a) / (6.0 * shaft.bending_rigidity);
        assert!((bending_only.modes().symmetric / hand - 1.0).abs() < 1e-12);
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
    fn involute_stage_reflects_by_the_square_of_the_crank_ratio() {
        // RV-20E-141 (z1 12, z2 42, two cranks, i 141): reflection 42/(12·141) = 0.024823.
        let stage = InvoluteStage {
            sun_teeth: 12.0,
            planet_teeth: 42.0,
            cranks: 2.0,
            planet_base_radius: 20.0,
            face_width: 8.0,
            mesh_stiffness: 20_000.0,
            torsion_length: 20.0,
        };
        let gj = 1e9;
        let reflection: f64 = 42.0 / (12.0 * 141.0);
        let hand = reflection.powi(2) * (1.0 / (20_000.0 * 8.0 * 400.0) + 20.0 / gj) / 2.0;
        assert!((stage.output_compliance(141.0, gj) / hand - 1.0).abs() < 1e-14);
    }

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
            shaft: CrankShaft::new(15.0, 28.0, 9.0, 206_000.0, 0.3),
            support: RollerRow {
                rollers: 14.0,
                length: 7.0,
                contact_angle: 15f64.to_radians(),
            },
            support_housing_compliance: 2.0e-7,
            carrier_stiffness: 3e8,
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
