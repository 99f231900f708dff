//! `cycloid_pin_contact`: load sharing between a modified cycloid disc and its pins, the
//! pin forces, contact stresses and crank bearing forces (document 003, RV-80E), with the
//! corrections of validation.md.
//!
//! Geometry (docs/models.md §10). Pin i (i = 1..z_p) sits at the angle
//! φ_i = 2π(i − 1)/z_p about the pin-circle centre, measured from the eccentricity
//! direction. With K1 = e·z_p/r_p and S_i = √(1 + K1² − 2K1·cos φ_i), the common normal of
//! pin i passes through the pitch point, its unit vector (from the pin into the disc) is
//! n_i = (−sin φ_i, K1 − cos φ_i)/S_i (x perpendicular to the eccentricity, y along it),
//! and its lever arm about the disc centre is l_i = e·z_c·sin φ_i/S_i (validation.md 003).
//!
//! Clearance along the normal (validation.md 003, standard form; 003's a + b·cos ψ never
//! reaches zero): Δ_i = Δr_rp·(1 − sin φ_i/S_i) − Δr_p·(1 − K1·cos φ_i −
//! √(1 − K1²)·sin φ_i)/S_i, plus the first-order effect of the manufacturing errors, each a
//! displacement projected on n_i: pin circle radius error δr_p (every pin outward):
//! +δr_p·(1 − K1·cos φ_i)/S_i; pin radius error δr_rp: −δr_rp; crank eccentricity error δe
//! (disc centre along y): +δe·(K1 − cos φ_i)/S_i; per-pin radial error δr_i:
//! +δr_i·(1 − K1·cos φ_i)/S_i; per-pin tangential error δt_i (direction of increasing φ):
//! +δt_i·K1·sin φ_i/S_i. A uniform rotation of the disc is absorbed by the load solve.
//! The same signed formula holds on the reverse flank (l_i < 0): a disc turned by β
//! compresses pin i by l_i·β − Δ_i whichever flank it is on, so a profile whose flanks
//! overlap (Δ_i < 0 on both sides of the first contact) is preloaded and both flanks carry
//! load at zero torque.
//!
//! Disc torque (torque balance; docs/models.md §10): the housing takes T·(1 − 1/i) of the
//! output torque T (the input takes T/i, i = 1 + (z2/z1)·z_p), and since every pin normal
//! passes through the pitch point, e·z_p from the pin-circle centre and e·z_c from the disc
//! centre, the pins' moment about the disc centre is z_c/z_p of theirs about the axis. A
//! disc carrying the share s of the load therefore carries T_c = s·λ·|T| with
//!   λ = (z_c/z_p)·(1 − 1/i)                        (0.96694 for the RV-80E-121)
//! and, by virtual work, its rotation reaches the output multiplied by the same λ. 003
//! (and 004) take T_c = s·T, 3.4 % high; `disc_torque_balance` = 0 keeps that reading.
//!
//! Load sharing (Li Lixing's method, as 003 describes it: F_max and δ_max iterated): under
//! the disc torque T_c the disc turns by β; pin i deforms by d_i = l_i·β − Δ_i and carries
//! F_i = K·max(d_i, 0), with K = F_max/δ(F_max) the secant stiffness of the most loaded
//! contact. β solves the torque balance Σ F_i·l_i = T_c (monotone in β), F_max = max F_i,
//! and K is updated until F_max settles; each update solves, on the current loaded set,
//! the most loaded pin's F = A + B·K(F) with K(F) = F/δ(F) (Newton on one variable), so
//! two or three passes settle it where the plain F → K → F iteration took ten. Without modification every F_i is proportional to
//! l_i and F_max = T_c·max l_i/Σ l_i², whose continuous limit is 4·T_c/(K1·z_c·r_p). At
//! zero torque a preloaded profile settles where Σ F_i·l_i = 0, which fixes β whatever K,
//! and the most loaded pin's deformation fixes K (δ(F_max) = d_max).
//!
//! Friction (used by `torsion_curve`; docs/models.md §13): a Coulomb coefficient μ at the
//! pin contacts adds to the torque balance the moment of the friction forces μ·F_i about
//! the disc centre, whose arm is the distance of the contact's tangent from the disc
//! centre, h_i = |(r_p·(K1·cos φ_i − 1) − e·(K1 − cos φ_i))/S_i + r_rp|; while the disc
//! turns forward (loading) the balance is Σ F_i·(l_i + λ·μ·h_i) = T_c, backward
//! Σ F_i·(l_i − λ·μ·h_i) = T_c (λ: the contact slips by h_i per radian of the disc's turn
//! against the housing, which is λ times its turn against the pins). A pin whose friction
//! arm would reverse its moment (|l_i| < λ·μ·h_i, within a few degrees of φ = 0 or π,
//! where no profile loads a pin) gets a zero moment arm.
//!
//! Contact approach δ(F): two steel line contacts in series (disc–pin and pin–housing),
//! each by Palmgren's formula δ = 3.84·10⁻⁵·F^0.9/L^0.8 (mm, N), the standard fit to the
//! Hertz–Lundberg line-contact approach of bearing steel. 003's two-cylinder formula is
//! not used for the approach: it diverges where the profile's curvature radius does, at
//! the inflection point next to which the most loaded pins sit.
//!
//! Contact stress (Hertz line contact, Johnson 1985 §4.2): σ_i = √(F_i·E*/(π·L·R*_i)),
//! 1/E* = 2(1 − ν²)/E, R*_i = r_rp·(1 + r_rp/ρ0_i) from the signed curvature radius of the
//! theoretical profile ρ0 = r_p·S³/(K1·(z_p + 1)·cos φ − (1 + z_p·K1²)) (validation.md;
//! positive on the concave root side). 003's σ = √(F·E_d/(π·ρ·l_e)) omits the factor
//! 1/(2(1 − ν²)) of E*.
//!
//! Crank bearings: each of m cranks on the crank circle a_w carries T_c/(m·a_w)
//! tangentially (003's F_n1 = T/(m·e) is dimensionally a lever of e; its printed value
//! equals three cranks on a 42 mm circle) plus 1/m of the pin-force resultant (F_x, F_y),
//! whose direction turns with the crank relative to the tangent; the largest bearing
//! force over a crank turn is T_c/(m·a_w) + |(F_x, F_y)|/m (003's "simplified" F_n(θ)
//! drops the cross term and is not used).
//!
//! Preload (docs/models.md §14.8): at zero torque the same clearances are balanced by the
//! one rule of every model (`crate::preload`), both discs alike: the overlap, the largest
//! pin force and the no-load torque, `preloaded` and `over_preloaded` (the largest pin force
//! above the rated one of the modification as ground brought to zero play). A contact model
//! another model embeds (`of_disc`) has no rule and no such outputs.
//!
//! Left out: the friction forces' own resultant (below μ·|F| and across the load), the
//! disc's and pins' bending, per-flank differences beyond the clearances (a negative torque
//! loads the mirrored flank with the same clearances: |T|).

use rvtol_deviation::Shown;
use std::f64::consts::PI;

use crate::cycloid::{CycloidStage, PinFactors};
use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
};

/// Largest pin count the model accepts (per-sample arrays live on the stack).
pub const MAX_PINS: usize = 128;
/// The parameters of one disc and its pins: what a model that embeds this one hands over
/// under the same keys (see [`CycloidPinContact::of_disc`]).
const DISC_KEYS: [&str; 12] = [
    "pin_count",
    "cycloid_teeth",
    "pin_circle_radius_mm",
    "pin_radius_mm",
    "eccentricity_mm",
    "disc_face_width_mm",
    "disc_load_share",
    "youngs_modulus_mpa",
    "poisson_ratio",
    "sun_teeth",
    "planet_teeth",
    "disc_torque_balance",
];
use crate::preload::{self, PreloadRule, CONTACTS_PER_PIN, LEVER_FLOOR, PALMGREN};

/// The fixed inputs, in order.
const FIXED_INPUTS: [(&str, &str, &str); 7] = [
    (
        "output_torque_nm",
        "N·m",
        "torque at the output; the disc carries disc_load_share of it",
    ),
    (
        "equidistant_modification_mm",
        "mm",
        "Δr_rp, equidistant modification (positive: clearance)",
    ),
    (
        "shift_modification_mm",
        "mm",
        "Δr_p, shift modification (negative: clearance)",
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
    (
        "eccentricity_error_mm",
        "mm",
        "δe, crank eccentricity minus design",
    ),
    ("face_width_error_mm", "mm", "disc face width minus design"),
];

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "pin_count",
        unit: "",
        description: "z_p, pins",
        default: None,
    },
    ParamSpec {
        name: "cycloid_teeth",
        unit: "",
        description: "z_c = z_p − 1",
        default: None,
    },
    ParamSpec {
        name: "pin_circle_radius_mm",
        unit: "mm",
        description: "r_p, design",
        default: None,
    },
    ParamSpec {
        name: "pin_radius_mm",
        unit: "mm",
        description: "r_rp, design",
        default: None,
    },
    ParamSpec {
        name: "eccentricity_mm",
        unit: "mm",
        description: "e, design",
        default: None,
    },
    ParamSpec {
        name: "disc_face_width_mm",
        unit: "mm",
        description: "L, contact length of one disc (003 leaves it out)",
        default: None,
    },
    ParamSpec {
        name: "disc_load_share",
        unit: "",
        description: "share of the output torque carried by one disc",
        default: Some(0.5),
    },
    ParamSpec {
        name: "crank_count",
        unit: "",
        description: "m, cranks",
        default: None,
    },
    ParamSpec {
        name: "crank_circle_radius_mm",
        unit: "mm",
        description: "a_w, distance of the crank axes from the reducer axis",
        default: None,
    },
    ParamSpec {
        name: "youngs_modulus_mpa",
        unit: "MPa",
        description: "E of disc and pins",
        default: Some(206_000.0),
    },
    ParamSpec {
        name: "poisson_ratio",
        unit: "",
        description: "ν of disc and pins",
        default: Some(0.3),
    },
    ParamSpec {
        name: "sun_teeth",
        unit: "",
        description: "z1, sun teeth, for the ratio i = 1 + (z2/z1)·z_p of the torque balance and the no-load torque of a preload (003: 12)",
        default: None,
    },
    ParamSpec {
        name: "planet_teeth",
        unit: "",
        description: "z2, planet teeth (003: 36)",
        default: None,
    },
    ParamSpec {
        name: "disc_torque_balance",
        unit: "",
        description: "1: a disc carries share·(z_c/z_p)·(1 − 1/i)·|T| (torque balance); 0: share·|T| as 003 and 004 print it",
        default: Some(1.0),
    },
    preload::FRICTION,
    preload::PARAMS[0],
    preload::PARAMS[1],
    preload::PARAMS[2],
    preload::PARAMS[3],
    ParamSpec {
        name: "pin_position_errors",
        unit: "",
        description:
            "1: add inputs pin_radial_error_mm_i and pin_tangential_error_mm_i per pin; 0: none",
        default: Some(0.0),
    },
];

/// Registry entry.
pub const ENTRY: ModelEntry = ModelEntry {
    name: "cycloid_pin_contact",
    summary: "cycloid–pin load sharing with profile modification (document 003): pin forces, engaged pins, Hertz contact stress, crank bearing forces",
    params: PARAMS,
    build: |params| Ok(Box::new(CycloidPinContact::from_params(params)?)),
    example_params: || {
        ModelParams::new()
            .with_number("pin_count", 40.0)
            .with_number("cycloid_teeth", 39.0)
            .with_number("pin_circle_radius_mm", 76.5)
            .with_number("pin_radius_mm", 3.0)
            .with_number("eccentricity_mm", 1.5)
            .with_number("disc_face_width_mm", 12.0)
            .with_number("sun_teeth", 12.0)
            .with_number("planet_teeth", 36.0)
            .with_number("crank_count", 3.0)
            .with_number("crank_circle_radius_mm", 42.0)
            .with_number("rated_torque_nm", 784.0)
    },
    example_inputs: &[("output_torque_nm", 800.0)],
};

/// The contact model with its design geometry.
#[derive(Debug, Clone)]
pub struct CycloidPinContact {
    pin_radius: f64,
    face_width: f64,
    load_share: f64,
    /// λ = (z_c/z_p)·(1 − 1/i) with the torque balance, 1 without.
    torque_factor: f64,
    cranks: f64,
    crank_circle_radius: f64,
    /// E* of the line contact, MPa.
    contact_modulus: f64,
    per_pin_errors: bool,
    /// The checked stage geometry (pins, teeth, r_p, e).
    stage: CycloidStage,
    /// Per pin, everything that depends on the design geometry only.
    geometry: Vec<PinGeometry>,
    /// Per pin, its lever l_i (the column the load solve reads as one slice).
    levers: Vec<f64>,
    /// Per pin, the friction arm h_i (module comment), mm.
    slip_arms: Vec<f64>,
    /// The preload rule (not for a contact model another model embeds).
    rule: Option<PreloadRule>,
    inputs: Vec<InputSpec>,
    outputs: Vec<OutputSpec>,
}

/// Pin forces and what follows from them, for one set of inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSolution {
    /// F_i per pin, N (pin i at φ = 2π(i − 1)/z_p).
    pub forces: Vec<f64>,
    /// Lever arms l_i, mm.
    pub levers: Vec<f64>,
    /// Clearances Δ_i, mm.
    pub clearances: Vec<f64>,
    /// Contact stress per pin, MPa (0 where unloaded).
    pub stresses: Vec<f64>,
    /// Disc rotation β under load, rad.
    pub rotation: f64,
    /// Resultant of the forces the disc exerts on the pins (003's sign), N.
    pub resultant: (f64, f64),
    /// Largest crank bearing force over a crank turn, N.
    pub max_crank_bearing_force: f64,
    /// Iterations of the F_max–stiffness loop.
    pub iterations: usize,
}

impl CycloidPinContact {
    /// Builds the model from its parameters.
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        Self::build(params, true)
    }

    /// Builds the model, with the preload rule and its outputs when `judged`.
    fn build(params: &ModelParams, judged: bool) -> Result<Self, ModelError> {
        let stage = CycloidStage::from_params(params, MAX_PINS)?;
        let pins = stage.pins;
        let pin_radius = params.positive("pin_radius_mm", None)?;
        stage.check_pin_radius("pin_radius_mm", pin_radius)?;
        let face_width = params.positive("disc_face_width_mm", None)?;
        let load_share = params.positive("disc_load_share", Some(0.5))?;
        if load_share > 1.0 {
            return Err(ModelError::new(
                "disc_load_share",
                format!("must be at most 1, got {}", Shown(load_share)),
            ));
        }
        let cranks = params.count("crank_count", None)? as f64;
        let crank_circle_radius = params.positive("crank_circle_radius_mm", None)?;
        let torque_factor = if params.flag("disc_torque_balance", true)? {
            let sun = params.count("sun_teeth", None)? as f64;
            let planet = params.count("planet_teeth", None)? as f64;
            torque_balance_factor(&stage, planet / sun)
        } else {
            // Read (so that they are not unknown) but not used.
            for key in ["sun_teeth", "planet_teeth"] {
                params.number(key, Some(0.0))?;
            }
            1.0
        };
        let youngs = params.positive("youngs_modulus_mpa", Some(206_000.0))?;
        let poisson = params.number("poisson_ratio", Some(0.3))?;
        if !(0.0..0.5).contains(&poisson) {
            return Err(ModelError::new(
                "poisson_ratio",
                format!("must lie in [0, 0.5), got {}", Shown(poisson)),
            ));
        }
        let per_pin = params.flag("pin_position_errors", false)?;
        let rule = if judged {
            let sun = params.count("sun_teeth", None)? as f64;
            let planet = params.count("planet_teeth", None)? as f64;
            let ratio = 1.0 + planet / sun * pins as f64;
            Some(PreloadRule::from_params(
                params,
                &stage,
                pin_radius,
                face_width,
                (ratio, torque_factor),
            )?)
        } else {
            None
        };
        params.reject_unknown(&PARAMS.iter().map(|p| p.name).collect::<Vec<_>>())?;
        let mut inputs: Vec<InputSpec> = FIXED_INPUTS
            .iter()
            .map(|(name, unit, description)| InputSpec {
                name: name.to_string(),
                unit: unit.to_string(),
                description,
            })
            .collect();
        if per_pin {
            for i in 1..=pins {
                inputs.push(InputSpec {
                    name: format!("pin_radial_error_mm_{i}"),
                    unit: "mm".into(),
                    description: "radial position error of pin i (outward)",
                });
            }
            for i in 1..=pins {
                inputs.push(InputSpec {
                    name: format!("pin_tangential_error_mm_{i}"),
                    unit: "mm".into(),
                    description: "tangential position error of pin i (towards increasing φ)",
                });
            }
        }
        let output = |name: &str, unit: &str, description: &'static str| OutputSpec {
            name: name.into(),
            unit: unit.into(),
            description,
            kind: OutputKind::Continuous,
            condition: None,
        };
        let mut model = CycloidPinContact {
            pin_radius,
            face_width,
            load_share,
            torque_factor,
            cranks,
            crank_circle_radius,
            contact_modulus: youngs / (2.0 * (1.0 - poisson * poisson)),
            per_pin_errors: per_pin,
            stage,
            geometry: Vec::new(),
            levers: Vec::new(),
            slip_arms: Vec::new(),
            rule,
            inputs,
            outputs: vec![
                output("max_pin_force_n", "N", "largest pin force F_max"),
                output("engaged_pins", "pins", "pins carrying load"),
                output("max_contact_stress_mpa", "MPa", "largest Hertz contact stress"),
                output("max_crank_bearing_force_n", "N", "largest crank bearing force over a crank turn"),
                output("pin_force_x_n", "N", "resultant of the forces on the pins, perpendicular to the eccentricity (003's F_x)"),
                output("pin_force_y_n", "N", "resultant of the forces on the pins, along the eccentricity (003's F_y)"),
            ],
        };
        if model.rule.is_some() {
            model.outputs.extend(preload::outputs());
        }
        model.geometry = (0..pins).map(|i| model.pin_geometry(i)).collect();
        model.levers = model.geometry.iter().map(|pin| pin.factors.lever).collect();
        model.slip_arms = (0..pins)
            .map(|i| model.slip_arm(2.0 * PI * i as f64 / pins as f64))
            .collect();
        Ok(model)
    }

    /// The design quantities of pin i (at φ = 2π·i/z_p, 0-based), see the module comment.
    fn pin_geometry(&self, i: usize) -> PinGeometry {
        let phi = 2.0 * PI * i as f64 / self.stage.pins as f64;
        let factors = self.stage.pin_factors(phi);
        PinGeometry {
            factors,
            // R*/r_rp = 1 + r_rp/ρ0.
            curvature_factor: 1.0 + self.pin_radius * self.inverse_curvature_radius(phi.cos()),
            // The disc pushes the pin along −n_i = (sin φ, −(K1 − cos φ))/S: its x part is
            // l/(e·z_c), its y part −(eccentric factor).
            push: (
                factors.lever / (self.stage.eccentricity * self.stage.teeth as f64),
                -factors.eccentric,
            ),
        }
    }

    /// The contact model of one disc, for a model that embeds it (the crank elastic error,
    /// the torsion curve): the disc and pin parameters ([`DISC_KEYS`]) are taken from the
    /// embedding model's own, so that this model checks them and names them in its errors;
    /// `cranks` cranks sit on `crank_circle_radius`.
    pub(crate) fn of_disc(
        params: &ModelParams,
        cranks: usize,
        crank_circle_radius: f64,
    ) -> Result<Self, ModelError> {
        Self::build(
            &params
                .subset(&DISC_KEYS)
                .with_number("crank_count", cranks as f64)
                .with_number("crank_circle_radius_mm", crank_circle_radius),
            false,
        )
    }

    /// The checked cycloid–pin stage geometry (z_p, z_c, r_p, e).
    pub(crate) fn stage(&self) -> &CycloidStage {
        &self.stage
    }

    /// Design disc face width (contact length), mm.
    pub(crate) fn face_width(&self) -> f64 {
        self.face_width
    }

    /// λ = (z_c/z_p)·(1 − 1/i) with the torque balance (`disc_torque_balance` = 1), 1
    /// without: the disc torque is share·λ·|T| and the disc's rotation reaches the output
    /// multiplied by λ (module comment).
    pub fn torque_factor(&self) -> f64 {
        self.torque_factor
    }

    /// T_c, the torque of one disc for the output torque `output_torque_nm`, N·mm.
    pub fn disc_torque(&self, output_torque_nm: f64) -> f64 {
        self.load_share * self.torque_factor * output_torque_nm.abs() * 1000.0
    }

    /// K1 = e·z_p/r_p of the design.
    pub fn k1(&self) -> f64 {
        self.stage.k1()
    }

    /// Signed curvature radius ρ0 of the theoretical profile at pin angle φ (validation.md
    /// 003; positive on the concave root side), mm.
    pub fn profile_curvature_radius(&self, phi: f64) -> f64 {
        1.0 / self.inverse_curvature_radius(phi.cos())
    }

    /// The friction arm h at pin angle φ: the distance of the contact's tangent from the
    /// disc centre, |(r_p·(K1·cos φ − 1) − e·(K1 − cos φ))/S + r_rp|, mm (module comment).
    pub fn slip_arm(&self, phi: f64) -> f64 {
        let (k1, rp, e) = (
            self.k1(),
            self.stage.pin_circle_radius,
            self.stage.eccentricity,
        );
        let cos = phi.cos();
        let s = (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
        ((rp * (k1 * cos - 1.0) - e * (k1 - cos)) / s + self.pin_radius).abs()
    }

    /// 1/ρ0 at cos φ: finite everywhere, zero at the inflection point.
    fn inverse_curvature_radius(&self, cos: f64) -> f64 {
        let k1 = self.k1();
        let zp = self.stage.pins as f64;
        let s = (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
        (k1 * (zp + 1.0) * cos - (1.0 + zp * k1 * k1)) / (self.stage.pin_circle_radius * s.powi(3))
    }

    /// Resultant (F_x, F_y) of the forces the disc exerts on the pins (003's sign: along
    /// −n_i), from the pin forces in pin order, N.
    pub fn pin_force_resultant(&self, forces: &[f64]) -> (f64, f64) {
        let (mut fx, mut fy) = (0.0, 0.0);
        for (pin, &f) in self.geometry.iter().zip(forces) {
            fx += f * pin.push.0;
            fy += f * pin.push.1;
        }
        (fx, fy)
    }

    /// Resultant (F_x, F_y) of the pin forces for one row of inputs (in the order of
    /// `inputs()`), without allocating: the per-sample entry point for models that build on
    /// this one (`crank_elastic_error`). Same value as [`Self::solve`]'s `resultant`.
    pub(crate) fn resultant(&self, inputs: &[f64]) -> (f64, f64) {
        self.solve_pins(inputs).resultant
    }

    /// The clearances Δ_i of every pin for one row of inputs (pin order; the first z_p
    /// entries are used), mm, for a model that solves several load cases on one profile.
    pub(crate) fn profile(&self, inputs: &[f64]) -> [f64; MAX_PINS] {
        self.clearances(inputs)
    }

    /// The rotations at which the two flanks first touch, rad: forward β_f = min over
    /// l_i > 0 of Δ_i/l_i and reverse β_r = max over l_i < 0 of Δ_i/l_i. β_f − β_r is the
    /// stage's free play when positive and its overlap (preload) when negative. NaN when a
    /// clearance is not finite.
    pub(crate) fn flank_contacts(&self, clearances: &[f64]) -> (f64, f64) {
        let (mut forward, mut reverse) = (f64::INFINITY, f64::NEG_INFINITY);
        // A pin on the line of centres (φ = 0 or π) holds no turn of the disc: its lever is
        // sin φ's rounding (2.5e-15 mm at φ = π), and Δ_i/l_i would make an overlap there a
        // flank contact at ±5e10 rad. The preload rule leaves it out by the same floor.
        let floor = LEVER_FLOOR * self.stage.eccentricity;
        for (&lever, &clearance) in self.levers.iter().zip(clearances) {
            if !clearance.is_finite() {
                return (f64::NAN, f64::NAN);
            }
            if lever > floor {
                forward = forward.min(clearance / lever);
            } else if lever < -floor {
                reverse = reverse.max(clearance / lever);
            }
        }
        (forward, reverse)
    }

    /// Contact approach δ(F) of one pin (two Palmgren line contacts in series), mm.
    pub fn approach(&self, force: f64, face_width: f64) -> f64 {
        CONTACTS_PER_PIN * PALMGREN * force.powf(0.9) / face_width.powf(0.8)
    }

    /// Solves the load sharing for one row of inputs (in the order of `inputs()`).
    pub fn solve(&self, inputs: &[f64]) -> ContactSolution {
        let n = self.stage.pins;
        let solved = self.solve_pins(inputs);
        ContactSolution {
            forces: solved.forces[..n].to_vec(),
            levers: self.levers.clone(),
            clearances: solved.clearances[..n].to_vec(),
            stresses: (0..n)
                .map(|i| self.stress(i, solved.forces[i], solved.face_width))
                .collect(),
            rotation: solved.rotation,
            resultant: solved.resultant,
            max_crank_bearing_force: solved.max_crank_bearing_force,
            iterations: solved.iterations,
        }
    }

    /// Hertz line-contact stress of pin i under force F.
    fn stress(&self, i: usize, force: f64, face_width: f64) -> f64 {
        if force <= 0.0 {
            return 0.0;
        }
        let radius = self.pin_radius * self.geometry[i].curvature_factor;
        (force * self.contact_modulus / (PI * face_width * radius)).sqrt()
    }

    /// The clearance Δ_i of every pin along its normal for one row of inputs (pin order,
    /// on the stack).
    fn clearances(&self, inputs: &[f64]) -> [f64; MAX_PINS] {
        let n = self.stage.pins;
        let (d_rp, d_p) = (inputs[1], inputs[2]);
        let (err_rp, err_rrp, err_e) = (inputs[3], inputs[4], inputs[5]);
        let mut clearances = [0.0; MAX_PINS];
        for (i, pin) in self.geometry.iter().enumerate() {
            let f = &pin.factors;
            let mut clearance = d_rp * f.equidistant + d_p * f.shift + err_rp * f.radial - err_rrp
                + err_e * f.eccentric;
            if self.per_pin_errors {
                clearance += inputs[7 + i] * f.radial + inputs[7 + n + i] * f.tangential;
            }
            clearances[i] = clearance;
        }
        clearances
    }

    /// Clearances, load sharing and resultants for one row of inputs; the per-pin arrays
    /// live on the stack.
    fn solve_pins(&self, inputs: &[f64]) -> Solved {
        let torque = self.disc_torque(inputs[0]);
        let face_width = self.face_width + inputs[6];
        let clearances = self.clearances(inputs);
        let sharing = self.share_load(&clearances, face_width, torque, 0.0);
        let tangential = torque / (self.cranks * self.crank_circle_radius);
        let resultant = sharing.resultant;
        Solved {
            forces: sharing.forces,
            clearances,
            face_width,
            rotation: sharing.rotation,
            resultant,
            max_crank_bearing_force: tangential + resultant.0.hypot(resultant.1) / self.cranks,
            iterations: sharing.iterations,
        }
    }

    /// The load sharing of one disc on the clearances `clearances` (pin order) with the
    /// face width `face_width` (mm) under the disc torque `disc_torque` (N·mm, ≥ 0), with
    /// the friction `friction` = ±λ·μ (+ while the disc turns forward, − backward, 0
    /// frictionless; module comment). At zero torque a preloaded profile gives its preload
    /// forces and a profile with free play none (its rotation then lies in the free play).
    pub(crate) fn share_load(
        &self,
        clearances: &[f64],
        face_width: f64,
        disc_torque: f64,
        friction: f64,
    ) -> Sharing {
        let n = self.stage.pins;
        let levers = &self.levers[..n];
        let clearances = &clearances[..n];
        // Moment arms of the torque balance: l_i + friction·h_i, zero where friction would
        // reverse the pin's moment.
        let mut moment_arms = [0.0; MAX_PINS];
        for ((arm, &lever), &slip) in moment_arms.iter_mut().zip(levers).zip(&self.slip_arms) {
            let with_friction = lever + friction * slip;
            *arm = if with_friction * lever > 0.0 {
                with_friction
            } else {
                0.0
            };
        }
        let moment_arms = &moment_arms[..n];
        let mut forces = [0.0; MAX_PINS];
        let mut rotation = 0.0;
        let mut iterations = 0;
        if !disc_torque.is_finite() || clearances.iter().any(|d| !d.is_finite()) {
            rotation = f64::NAN;
        } else if disc_torque > 0.0 {
            let mut f_max =
                4.0 * disc_torque / (n as f64 * self.stage.eccentricity * self.stage.teeth as f64);
            // δ(F) = c·F^0.9, so the secant stiffness is K(F) = F^0.1/c.
            let c = CONTACTS_PER_PIN * PALMGREN / face_width.powf(0.8);
            for _ in 0..100 {
                iterations += 1;
                let stiffness = f_max / self.approach(f_max, face_width);
                rotation = solve_rotation(levers, moment_arms, clearances, disc_torque / stiffness);
                let (mut largest, mut top) = (0.0_f64, 0);
                let (mut slope, mut offset) = (0.0, 0.0);
                for i in 0..n {
                    let deformation = levers[i] * rotation - clearances[i];
                    let f = stiffness * deformation.max(0.0);
                    forces[i] = f;
                    if f > largest {
                        (largest, top) = (f, i);
                    }
                    if deformation > 0.0 {
                        slope += levers[i] * moment_arms[i];
                        offset += clearances[i] * moment_arms[i];
                    }
                }
                let settled = (largest - f_max).abs() <= 1e-12 * largest;
                f_max = largest;
                if settled {
                    break;
                }
                // On the current loaded set β = (T_c/K + Σ Δ_i·m_i)/Σ l_i·m_i, so the most
                // loaded pin carries F = K·(l_j·β − Δ_j) = A + B·K with K = F^0.1/c: solve
                // that for F (Newton) instead of iterating F → K → F, which contracts only
                // by about 0.1 per step; the next pass checks the loaded set.
                if slope > 0.0 {
                    let a = levers[top] * disc_torque / slope;
                    let b = levers[top] * offset / slope - clearances[top];
                    let mut f = largest;
                    for _ in 0..30 {
                        let power = f.powf(0.1);
                        let residual = f - a - b * power / c;
                        let derivative = 1.0 - 0.1 * b * power / (c * f);
                        let next = f - residual / derivative;
                        if !(next > 0.0 && next.is_finite()) {
                            break;
                        }
                        let done = (next - f).abs() <= 1e-14 * next;
                        f = next;
                        if done {
                            break;
                        }
                    }
                    if f > 0.0 && f.is_finite() {
                        f_max = f;
                    }
                }
            }
        } else {
            // Zero torque: Σ max(l_i·β − Δ_i, 0)·m_i = 0 fixes β whatever K; a preloaded
            // profile then has a largest deformation d_max > 0, and δ(F_max) = d_max gives
            // F_max = (d_max·L^0.8/(2·3.84e-5))^(1/0.9) and K = F_max/d_max.
            rotation = solve_rotation(levers, moment_arms, clearances, 0.0);
            let largest_deformation = levers
                .iter()
                .zip(clearances)
                .map(|(l, d)| l * rotation - d)
                .fold(0.0, f64::max);
            if largest_deformation > 0.0 {
                let f_max = (largest_deformation * face_width.powf(0.8)
                    / (CONTACTS_PER_PIN * PALMGREN))
                    .powf(1.0 / 0.9);
                let stiffness = f_max / largest_deformation;
                for i in 0..n {
                    forces[i] = stiffness * (levers[i] * rotation - clearances[i]).max(0.0);
                }
            }
        }
        let resultant = self.pin_force_resultant(&forces[..n]);
        Sharing {
            forces,
            rotation,
            resultant,
            iterations,
        }
    }
}

/// The torque-balance factor λ = (z_c/z_p)·(1 − 1/i), i = 1 + (z2/z1)·z_p (module comment).
pub(crate) fn torque_balance_factor(stage: &CycloidStage, planet_per_sun: f64) -> f64 {
    let pins = stage.pins as f64;
    let ratio = 1.0 + planet_per_sun * pins;
    stage.teeth as f64 / pins * (1.0 - 1.0 / ratio)
}

/// The design quantities of one pin: lever arm l_i and the factors that project each
/// clearance term and error on the normal n_i (module comment), and its contact geometry.
#[derive(Debug, Clone, Copy)]
struct PinGeometry {
    factors: PinFactors,
    /// R*/r_rp = 1 + r_rp/ρ0.
    curvature_factor: f64,
    /// Unit vector along which the disc pushes the pin (−n_i), in 003's axes.
    push: (f64, f64),
}

/// One solve: per-pin arrays (pin order, on the stack: no allocation per sample) and what
/// follows from them.
struct Solved {
    forces: [f64; MAX_PINS],
    clearances: [f64; MAX_PINS],
    /// Disc face width of this row, mm.
    face_width: f64,
    rotation: f64,
    resultant: (f64, f64),
    max_crank_bearing_force: f64,
    iterations: usize,
}

/// The load sharing of one disc for one load case (on the stack).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sharing {
    /// F_i, pin order, N.
    pub forces: [f64; MAX_PINS],
    /// β, rad (NaN for a non-finite case).
    pub rotation: f64,
    /// (F_x, F_y), 003's sign, N.
    pub resultant: (f64, f64),
    /// Iterations of the F_max–stiffness loop (0 at zero torque).
    pub iterations: usize,
}

/// β with Σ max(l_i·β − Δ_i, 0)·m_i = `target` (≥ 0), m_i the moment arms (same sign as
/// l_i or zero). The left side g(β) is continuous, piecewise linear and non-decreasing
/// (slope Σ over loaded pins of l_i·m_i ≥ 0), so a bracket is found by doubling and the
/// root by Newton steps on the current loaded set, kept in the bracket by bisection. At
/// target 0 with free play, g vanishes on the whole play and a point of it is returned.
fn solve_rotation(levers: &[f64], moment_arms: &[f64], clearances: &[f64], target: f64) -> f64 {
    // A non-finite row has no root; the bracket search below would never end.
    if !target.is_finite() || clearances.iter().any(|d| !d.is_finite()) {
        return f64::NAN;
    }
    let g = |beta: f64| -> (f64, f64) {
        let (mut value, mut slope) = (0.0, 0.0);
        for ((&l, &m), &d) in levers.iter().zip(moment_arms).zip(clearances) {
            let deformation = l * beta - d;
            if deformation > 0.0 {
                value += deformation * m;
                slope += l * m;
            }
        }
        (value, slope)
    };
    let (mut lo, mut hi) = (-1e-6, 1e-6);
    while g(hi).0 < target {
        hi *= 2.0;
    }
    while g(lo).0 > target {
        lo *= 2.0;
    }
    let mut beta = hi;
    for _ in 0..200 {
        let (value, slope) = g(beta);
        let residual = value - target;
        if residual.abs() <= 1e-14 * target {
            break;
        }
        if residual > 0.0 {
            hi = beta;
        } else {
            lo = beta;
        }
        let newton = if slope > 0.0 {
            beta - residual / slope
        } else {
            f64::NAN
        };
        beta = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if hi - lo <= 1e-15 * hi.abs().max(lo.abs()) {
            break;
        }
    }
    beta
}

impl ErrorModel for CycloidPinContact {
    fn name(&self) -> &'static str {
        "cycloid_pin_contact"
    }

    fn inputs(&self) -> &[InputSpec] {
        &self.inputs
    }

    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }

    fn check_constant(&self, input: usize, value: f64) -> Result<(), String> {
        match input {
            0 if value == 0.0 => Err("a torque of 0 N·m engages no pin".into()),
            6 if self.face_width + value <= 0.0 => Err(format!(
                "leaves a disc face width of {} mm; it must stay positive",
                self.face_width + value
            )),
            _ => Ok(()),
        }
    }

    fn evaluate(&self, inputs: &[f64], outputs: &mut [f64]) {
        let solved = self.solve_pins(inputs);
        if inputs.iter().any(|v| !v.is_finite())
            || !solved.rotation.is_finite()
            || !solved.resultant.0.is_finite()
        {
            outputs.iter_mut().for_each(|o| *o = f64::NAN);
            return;
        }
        let forces = &solved.forces[..self.stage.pins];
        let (mut f_max, mut engaged, mut sigma_max) = (0.0_f64, 0.0, 0.0_f64);
        let threshold = 1e-9 * forces.iter().cloned().fold(0.0, f64::max);
        for (i, &f) in forces.iter().enumerate() {
            if f > threshold {
                engaged += 1.0;
                f_max = f_max.max(f);
                sigma_max = sigma_max.max(self.stress(i, f, solved.face_width));
            }
        }
        outputs[0] = f_max;
        outputs[1] = engaged;
        outputs[2] = sigma_max;
        outputs[3] = solved.max_crank_bearing_force;
        outputs[4] = solved.resultant.0;
        outputs[5] = solved.resultant.1;
        if let Some(rule) = &self.rule {
            let clearances = &solved.clearances[..self.stage.pins];
            let (forward, reverse) = self.flank_contacts(clearances);
            let overlapping = forward < reverse;
            let load = if overlapping {
                rule.of_clearances(clearances)
            } else {
                preload::Preload::NONE
            };
            let class = rule.classify(&load, (overlapping, false), (inputs[1], inputs[2]));
            outputs[6] = load.overlap_um;
            outputs[7] = load.pin_force;
            outputs[8] = load.no_load_torque;
            outputs[9] = class.preloaded();
            outputs[10] = class.over();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RV-80E of document 003 (validation.md: 40 pins, 39 teeth, e 1.5 mm, r_p 76.5 mm,
    /// pin diameter 6 mm), with the parameters 003 leaves out: face width 12 mm, three
    /// cranks on a 42 mm circle (the reading of 003's printed F_n1), and 003's disc torque
    /// T_c = share·T (`disc_torque_balance` 0), against which 003's numbers are checked.
    fn rv80e(share: f64) -> CycloidPinContact {
        let params = (ENTRY.example_params)()
            .with_number("disc_load_share", share)
            .with_number("disc_torque_balance", 0.0);
        CycloidPinContact::from_params(&params).unwrap()
    }

    /// The same RV-80E with the torque balance (the default).
    fn rv80e_balanced(share: f64) -> CycloidPinContact {
        let params = (ENTRY.example_params)().with_number("disc_load_share", share);
        CycloidPinContact::from_params(&params).unwrap()
    }

    /// Inputs: torque, Δr_rp, Δr_p, then every error 0.
    fn row(torque: f64, equidistant: f64, shift: f64) -> Vec<f64> {
        vec![torque, equidistant, shift, 0.0, 0.0, 0.0, 0.0]
    }

    #[test]
    fn a_non_finite_row_gives_nan_outputs() {
        let model = rv80e(0.5);
        let mut out = [0.0; 11];
        for bad in [f64::NAN, f64::INFINITY] {
            model.evaluate(&row(800.0, bad, -0.008), &mut out);
            assert!(out.iter().all(|v| v.is_nan()), "{out:?}");
            model.evaluate(&row(bad, 0.004, -0.008), &mut out);
            assert!(out.iter().all(|v| v.is_nan()), "{out:?}");
        }
    }

    #[test]
    fn unmodified_profile_gives_the_closed_form() {
        let model = rv80e(0.5);
        let solution = model.solve(&row(800.0, 0.0, 0.0));
        let t_c = 400_000.0;
        // Discrete form: F_max = T_c·max l_i/Σ l_i² (forces proportional to l_i).
        let l_max = solution.levers.iter().cloned().fold(0.0, f64::max);
        let sum_l2: f64 = solution
            .levers
            .iter()
            .filter(|l| **l > 0.0)
            .map(|l| l * l)
            .sum();
        let f_max = solution.forces.iter().cloned().fold(0.0, f64::max);
        assert!((f_max - t_c * l_max / sum_l2).abs() < 1e-9 * f_max);
        // Continuous limit 4·T_c/(K1·z_c·r_p) = 683.76 N (validation.md 003): the discrete
        // pins reach max sin φ/S = 0.99912 of the continuous maximum 1, and Σ sin²φ/S² over
        // the loaded half equals z_p/4 up to terms of order K1^z_p = 6e-5, so the two
        // agree to 0.09 %: the ratio is 0.99912 within 1e-4.
        let closed = 4.0 * t_c / (model.k1() * 39.0 * 76.5);
        assert!((closed - 683.76).abs() < 0.005);
        assert!(
            (f_max / closed - 0.99912).abs() < 1e-4,
            "{f_max} vs {closed}"
        );
        // 19 loaded pins: the ones with 0 < φ < π.
        let mut out = [0.0; 11];
        model.evaluate(&row(800.0, 0.0, 0.0), &mut out);
        assert_eq!(out[1], 19.0);
        assert_eq!(out[0], f_max);
        // At the 0.55 share: 752.14 N in the continuous limit.
        let at_055 = rv80e(0.55).solve(&row(800.0, 0.0, 0.0));
        let f = at_055.forces.iter().cloned().fold(0.0, f64::max);
        assert!((f / 0.99912 - 752.14).abs() < 0.05, "{f}");
    }

    #[test]
    fn torque_balance_and_engaged_pins_with_modification() {
        // 003: shift a = 0.008 mm, equidistant b = 0.004 mm; as a clearance-giving
        // modification Δr_rp = +0.004, Δr_p = −0.008 (validation.md: 8–11 pins engage).
        let model = rv80e(0.55);
        let inputs = row(800.0, 0.004, -0.008);
        let solution = model.solve(&inputs);
        let moment: f64 = solution
            .forces
            .iter()
            .zip(&solution.levers)
            .map(|(f, l)| f * l)
            .sum();
        assert!((moment - 440_000.0).abs() < 1e-9 * 440_000.0, "{moment}");
        let mut out = [0.0; 11];
        model.evaluate(&inputs, &mut out);
        assert!((8.0..=11.0).contains(&out[1]), "engaged {}", out[1]);
        // Modification concentrates the load: F_max above the unmodified 752 N.
        assert!(out[0] > 760.0);
        // The clearance is zero at cos φ = K1 and positive elsewhere.
        assert!(solution.clearances.iter().all(|c| *c >= -1e-15));
        // Deformation compatibility: every loaded pin has F_i = K·(l_i·β − Δ_i) with one K.
        let ratios: Vec<f64> = solution
            .forces
            .iter()
            .zip(solution.levers.iter().zip(&solution.clearances))
            .filter(|(f, _)| **f > 0.0)
            .map(|(f, (l, c))| f / (l * solution.rotation - c))
            .collect();
        for r in &ratios {
            assert!((r / ratios[0] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_documents_force_table_gives_its_resultant() {
        // 003's table (pins 2..20) carries Σ F_i·l_i = 437.33 N·m and F_x = 7475.81 N,
        // F_y = −2248.29 N (validation.md 003).
        let table = [
            702.07, 785.98, 785.02, 780.65, 747.56, 710.30, 670.07, 627.28, 582.17, 534.88, 485.55,
            434.32, 381.34, 326.80, 270.90, 213.93, 156.17, 97.97, 39.68,
        ];
        let model = rv80e(0.55);
        let mut forces = vec![0.0; 40];
        forces[1..20].copy_from_slice(&table);
        let (fx, fy) = model.pin_force_resultant(&forces);
        assert!((fx - 7475.81).abs() < 0.01, "{fx}");
        assert!((fy + 2248.29).abs() < 0.01, "{fy}");
        let levers = model.solve(&row(0.0, 0.0, 0.0)).levers;
        let moment: f64 = forces.iter().zip(&levers).map(|(f, l)| f * l).sum();
        assert!((moment / 1000.0 - 437.33).abs() < 0.005, "{moment}");
    }

    /// Position of pin 0 (at angle 0 in the housing) in the disc frame when the crank has
    /// turned by θ: the disc centre is at e·(sin θ, cos θ) and the disc has turned by
    /// θ/z_c; the curve it traces is the theoretical profile.
    fn profile_point(model: &CycloidPinContact, theta: f64) -> (f64, f64) {
        let (ox, oy) = (
            model.stage.eccentricity * theta.sin(),
            model.stage.eccentricity * theta.cos(),
        );
        let (dx, dy) = (-ox, model.stage.pin_circle_radius - oy);
        let (s, c) = (-theta / model.stage.teeth as f64).sin_cos();
        (c * dx - s * dy, s * dx + c * dy)
    }

    #[test]
    fn curvature_formula_matches_the_numerical_curvature() {
        let model = rv80e(0.5);
        let h = 1e-4;
        for phi in [0.05, 0.3, 0.6, 0.66, 1.0, 2.0, 3.0] {
            // Pin angle φ relative to the eccentricity: θ = −φ for the pin at angle 0.
            let theta = -phi;
            let (x0, y0) = profile_point(&model, theta - h);
            let (x1, y1) = profile_point(&model, theta);
            let (x2, y2) = profile_point(&model, theta + h);
            let (dx, dy) = ((x2 - x0) / (2.0 * h), (y2 - y0) / (2.0 * h));
            let (ddx, ddy) = (
                (x2 - 2.0 * x1 + x0) / (h * h),
                (y2 - 2.0 * y1 + y0) / (h * h),
            );
            let numerical = (dx * dx + dy * dy).powf(1.5) / (dx * ddy - dy * ddx);
            let formula = model.profile_curvature_radius(phi);
            // Central differences: relative error O(h²·(z_p)²) ≈ 2e-5.
            assert!(
                (numerical / formula - 1.0).abs() < 1e-4,
                "φ {phi}: numerical {numerical}, formula {formula}"
            );
        }
    }

    #[test]
    fn errors_enter_as_projected_displacements() {
        let model = rv80e(0.55);
        let modified = row(800.0, 0.004, -0.008);
        // Pins larger by exactly the equidistant modification undo it up to a rigid
        // rotation of the disc: the unmodified forces come back.
        let mut undone = modified.clone();
        undone[4] = 0.004;
        undone[2] = 0.0;
        let a = model.solve(&undone);
        let b = model.solve(&row(800.0, 0.0, 0.0));
        for (fa, fb) in a.forces.iter().zip(&b.forces) {
            assert!((fa - fb).abs() < 1e-6 * b.forces.iter().cloned().fold(0.0, f64::max));
        }
        // Opening the clearance of the most loaded pin moves its load to the others.
        let per_pin = CycloidPinContact::from_params(
            &(ENTRY.example_params)()
                .with_number("disc_load_share", 0.55)
                .with_number("pin_position_errors", 1.0),
        )
        .unwrap();
        assert_eq!(per_pin.inputs().len(), 7 + 80);
        let mut inputs = modified.clone();
        inputs.resize(87, 0.0);
        let base = per_pin.solve(&inputs);
        let top = (0..40)
            .max_by(|&i, &j| base.forces[i].total_cmp(&base.forces[j]))
            .unwrap();
        inputs[7 + top] = 0.002;
        let moved = per_pin.solve(&inputs);
        assert!(moved.forces[top] < base.forces[top]);
        let max_moved = moved.forces.iter().cloned().fold(0.0, f64::max);
        assert!(max_moved > base.forces[top] * 0.9);
    }

    #[test]
    fn crank_bearing_force_is_the_largest_over_a_turn() {
        // Per crank: F_n1 = T_c/(m·a_w) along the crank-circle tangent plus (F_x, F_y)/m
        // turned by the crank angle θ; the maximum of the magnitude over θ is
        // F_n1 + |F|/m.
        let model = rv80e(0.55);
        let solution = model.solve(&row(800.0, 0.004, -0.008));
        let f_n1 = 440_000.0 / (3.0 * 42.0);
        let (fx, fy) = (solution.resultant.0 / 3.0, solution.resultant.1 / 3.0);
        let largest = (0..3600)
            .map(|k| {
                let (s, c) = (k as f64 * PI / 1800.0).sin_cos();
                (f_n1 + c * fx - s * fy).hypot(s * fx + c * fy)
            })
            .fold(0.0, f64::max);
        assert!((largest / solution.max_crank_bearing_force - 1.0).abs() < 1e-6);
    }

    #[test]
    fn disc_torque_follows_the_torque_balance() {
        // RV-80E-121 (003: sun 12, planet 36, 40 pins): i = 1 + 3·40 = 121, λ = (39/40)·
        // (1 − 1/121) = 0.96694215; at 800 N·m and share 0.5, T_c = 386 776.86 N·mm.
        let model = rv80e_balanced(0.5);
        let lambda: f64 = 39.0 / 40.0 * (1.0 - 1.0 / 121.0);
        assert!((lambda - 0.966_942_15).abs() < 1e-8);
        assert_eq!(model.torque_factor(), lambda);
        let t_c = model.disc_torque(800.0);
        assert!((t_c - 386_776.86).abs() < 0.01, "{t_c}");
        let solution = model.solve(&row(800.0, 0.004, -0.008));
        let moment: f64 = solution
            .forces
            .iter()
            .zip(&solution.levers)
            .map(|(f, l)| f * l)
            .sum();
        assert!((moment / t_c - 1.0).abs() < 1e-12);
        // The torque balance of the whole reducer: the pin normals all pass through the
        // pitch point, so the pins' moment about the reducer axis (the housing's reaction)
        // is z_p/z_c of theirs about the disc centre, and two discs give the housing
        // exactly T·(1 − 1/i), the output torque less the input's share T/i. Moments about
        // the axis computed from the pin positions r_p·(sin φ, cos φ) and the normals.
        let (k1, rp) = (model.k1(), 76.5);
        let about_axis: f64 = solution
            .forces
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let phi = 2.0 * PI * i as f64 / 40.0;
                let s = (1.0 + k1 * k1 - 2.0 * k1 * phi.cos()).sqrt();
                let (nx, ny) = (-phi.sin() / s, (k1 - phi.cos()) / s);
                let (px, py) = (rp * phi.sin(), rp * phi.cos());
                // Moment about the axis of the pin's force on the disc, F·n, which the
                // housing reacts.
                (px * ny - py * nx) * f
            })
            .sum();
        assert!((about_axis / (moment * 40.0 / 39.0) - 1.0).abs() < 1e-12);
        assert!((2.0 * about_axis / (800_000.0 * (1.0 - 1.0 / 121.0)) - 1.0).abs() < 1e-12);
        // 003's reading puts 3.42 % more on the disc: 1/λ − 1.
        let printed = rv80e(0.5).disc_torque(800.0);
        assert!((printed / t_c - 1.0 / lambda).abs() < 1e-15);
        assert!((1.0 / lambda - 1.0 - 0.0342).abs() < 5e-5);
    }

    #[test]
    fn the_tooth_counts_are_required_by_the_torque_balance_and_the_preload_rule() {
        // The ratio i sets the torque balance's λ and the no-load torque of a preload (its
        // pin friction reaches the input divided by i): both readings need the teeth.
        let without = (ENTRY.example_params)();
        let mut params = ModelParams::new();
        for spec in PARAMS.iter().filter(|p| p.name != "sun_teeth") {
            if let Ok(v) = without.number(spec.name, None) {
                params = params.with_number(spec.name, v);
            }
        }
        let err = CycloidPinContact::from_params(&params).unwrap_err();
        assert_eq!(err.key, "sun_teeth");
        let printed = params.clone().with_number("disc_torque_balance", 0.0);
        let err = CycloidPinContact::from_params(&printed).unwrap_err();
        assert_eq!(err.key, "sun_teeth");
        let with_teeth = printed.with_number("sun_teeth", 12.0);
        assert_eq!(
            CycloidPinContact::from_params(&with_teeth)
                .unwrap()
                .torque_factor(),
            1.0
        );
    }

    #[test]
    fn friction_arm_is_the_distance_of_the_contact_tangent() {
        // h = |(P − O_c)·n| with the contact point P = pin + r_rp·n, the disc centre O_c
        // = (0, e) and the pin at r_p·(sin φ, cos φ) (module comment), computed from the
        // coordinates.
        let model = rv80e(0.5);
        let (k1, rp, e, rrp) = (model.k1(), 76.5, 1.5, 3.0);
        for phi in [0.2, 0.7, 1.1, 2.5, 4.0] {
            let s = (1.0_f64 + k1 * k1 - 2.0 * k1 * f64::cos(phi)).sqrt();
            let (nx, ny) = (-f64::sin(phi) / s, (k1 - f64::cos(phi)) / s);
            let (px, py) = (rp * f64::sin(phi) + rrp * nx, rp * f64::cos(phi) + rrp * ny);
            let hand = (px * nx + (py - e) * ny).abs();
            assert!((model.slip_arm(phi) / hand - 1.0).abs() < 1e-12, "{phi}");
        }
    }

    #[test]
    fn friction_changes_the_torque_balance_by_its_moment() {
        // Loading: Σ F_i·(l_i + λ·μ·h_i) = T_c; the pins then carry less normal moment and
        // the disc turns less than without friction; unloading the other way round.
        let model = rv80e_balanced(0.5);
        let clearances = model.profile(&row(0.0, 0.004, -0.008));
        let t_c = model.disc_torque(800.0);
        let lambda = model.torque_factor();
        let mu = 0.02;
        let free = model.share_load(&clearances, 12.0, t_c, 0.0);
        let loading = model.share_load(&clearances, 12.0, t_c, lambda * mu);
        let unloading = model.share_load(&clearances, 12.0, t_c, -lambda * mu);
        let balance = |sharing: &Sharing, friction: f64| -> f64 {
            (0..40)
                .map(|i| {
                    let phi = 2.0 * PI * i as f64 / 40.0;
                    sharing.forces[i] * (model.levers[i] + friction * model.slip_arm(phi))
                })
                .sum()
        };
        assert!((balance(&loading, lambda * mu) / t_c - 1.0).abs() < 1e-12);
        assert!((balance(&unloading, -lambda * mu) / t_c - 1.0).abs() < 1e-12);
        assert!(loading.rotation < free.rotation && free.rotation < unloading.rotation);
        // The friction moment over the normal moment is about μ·λ·h/l, h ≈ l for the
        // loaded pins near cos φ = K1: between 0.5·μ and 2·μ here.
        let normal: f64 = (0..40).map(|i| loading.forces[i] * model.levers[i]).sum();
        let ratio = (t_c - normal) / normal;
        assert!(ratio > 0.5 * mu && ratio < 2.0 * mu, "{ratio}");
    }

    #[test]
    fn an_overlapping_profile_is_preloaded_on_both_flanks() {
        // 000's Table 9 design modification Δr_rp = −0.010, Δr_p = −0.012 mm on the RV-80E:
        // backlash 2(Δr_rp − √(1 − K1²)·Δr_p)/(e·z_c) < 0 (000 Eq. 13–15 = 003's standard
        // form): the flanks overlap, the forward first contact lies beyond the reverse one.
        let model = rv80e_balanced(0.5);
        let clearances = model.profile(&row(0.0, -0.010, -0.012));
        let (forward, reverse) = model.flank_contacts(&clearances);
        assert!(forward < reverse, "{forward} {reverse}");
        let k1 = model.k1();
        let continuous = 2.0 * (-0.010 + (1.0 - k1 * k1).sqrt() * 0.012) / (1.5 * 39.0);
        // Discrete pins touch later than the continuous profile: the play they see is at
        // least the continuous one, within the pin spacing's second order (1e-6 rad here).
        assert!((forward - reverse) >= continuous - 1e-12);
        assert!(
            (forward - reverse) - continuous < 1e-6,
            "{} {continuous}",
            forward - reverse
        );
        // Zero torque: both flanks loaded, moments balanced, β between the two contacts.
        let zero = model.share_load(&clearances, 12.0, 0.0, 0.0);
        let moment: f64 = (0..40).map(|i| zero.forces[i] * model.levers[i]).sum();
        let forward_load: f64 = (0..40)
            .filter(|&i| model.levers[i] > 0.0)
            .map(|i| zero.forces[i] * model.levers[i])
            .sum();
        assert!(forward_load > 0.0 && moment.abs() < 1e-9 * forward_load);
        assert!(zero.rotation > forward && zero.rotation < reverse);
        // The largest pin's deformation is δ(F_max): K is its secant.
        let f_max = zero.forces.iter().cloned().fold(0.0, f64::max);
        let d_max = (0..40)
            .map(|i| model.levers[i] * zero.rotation - clearances[i])
            .fold(0.0, f64::max);
        assert!((model.approach(f_max, 12.0) / d_max - 1.0).abs() < 1e-12);
        // A profile with free play carries nothing at zero torque.
        let play = model.profile(&row(0.0, 0.004, -0.008));
        let none = model.share_load(&play, 12.0, 0.0, 0.0);
        assert!(none.forces.iter().all(|f| *f == 0.0));
    }

    #[test]
    fn an_overlap_on_the_line_of_centres_holds_no_turn() {
        // Pin 20 of 40 sits at φ = π: its lever e·z_c·sin φ/S is sin π's rounding, and an
        // overlap there (Δ < 0) must not become a flank contact at Δ/l ≈ ∓5e10 rad. The
        // flanks' play is the one of the same profile without that overlap, as the preload
        // rule (which leaves levers under LEVER_FLOOR·e out) has it.
        let model = rv80e_balanced(0.5);
        assert!(model.levers[20].abs() <= LEVER_FLOOR * 1.5 && model.levers[20] != 0.0);
        let play = model.profile(&row(0.0, 0.004, -0.008));
        let (forward, reverse) = model.flank_contacts(&play);
        assert!(forward > reverse && forward.is_finite() && reverse.is_finite());
        let mut overlapped = play;
        overlapped[20] = -0.001;
        assert_eq!(model.flank_contacts(&overlapped), (forward, reverse));
    }

    #[test]
    fn load_sharing_settles_in_a_few_passes_at_its_fixed_point() {
        // The secant K must be the most loaded pin's own: δ(F_max) equals its deformation
        // l_j·β − Δ_j to 1e-12, reached in at most 4 passes (module comment: the plain
        // F → K → F iteration contracts by about 0.1 per pass and took 9–10 here).
        let model = rv80e_balanced(0.5);
        for (torque, equidistant, shift) in [
            (800.0, 0.004, -0.008),
            (24.0, 0.004, -0.008),
            (800.0, -0.010, -0.0198),
            (800.0, -0.010, -0.012),
        ] {
            let solution = model.solve(&row(torque, equidistant, shift));
            assert!(solution.iterations <= 4, "{} passes", solution.iterations);
            let (top, f_max) = solution
                .forces
                .iter()
                .cloned()
                .enumerate()
                .fold((0, 0.0), |m, (i, f)| if f > m.1 { (i, f) } else { m });
            let deformation = solution.levers[top] * solution.rotation - solution.clearances[top];
            assert!(
                (model.approach(f_max, 12.0) / deformation - 1.0).abs() < 1e-12,
                "{torque} {equidistant} {shift}"
            );
        }
    }
}
