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
//!
//! Load sharing (Li Lixing's method, as 003 describes it: F_max and δ_max iterated): under
//! the disc torque T_c the disc turns by β; pin i deforms by d_i = l_i·β − Δ_i and carries
//! F_i = K·max(d_i, 0), with K = F_max/δ(F_max) the secant stiffness of the most loaded
//! contact. β solves the torque balance Σ F_i·l_i = T_c (monotone in β), F_max = max F_i,
//! and K is updated until F_max settles. Without modification every F_i is proportional to
//! l_i and F_max = T_c·max l_i/Σ l_i², whose continuous limit is 4·T_c/(K1·z_c·r_p).
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

use rvtol_deviation::Shown;
use std::f64::consts::PI;

use crate::cycloid::{CycloidStage, PinFactors};
use crate::{
    ErrorModel, InputSpec, ModelEntry, ModelError, ModelParams, OutputKind, OutputSpec, ParamSpec,
};

/// Largest pin count the model accepts (per-sample arrays live on the stack).
pub const MAX_PINS: usize = 128;
/// The parameters of one disc and its pins: what a model that embeds this one hands over
/// under the same keys (see [`CycloidPinContact::of_two_crank_disc`]).
const DISC_KEYS: [&str; 9] = [
    "pin_count",
    "cycloid_teeth",
    "pin_circle_radius_mm",
    "pin_radius_mm",
    "eccentricity_mm",
    "disc_face_width_mm",
    "disc_load_share",
    "youngs_modulus_mpa",
    "poisson_ratio",
];
/// Palmgren's line-contact coefficient, mm·N^−0.9·mm^0.8.
const PALMGREN: f64 = 3.84e-5;
/// Line contacts in series per pin: disc–pin and pin–housing.
const CONTACTS_PER_PIN: f64 = 2.0;

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
            .with_number("crank_count", 3.0)
            .with_number("crank_circle_radius_mm", 42.0)
    },
};

/// The contact model with its design geometry.
#[derive(Debug, Clone)]
pub struct CycloidPinContact {
    pin_radius: f64,
    face_width: f64,
    load_share: f64,
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
        let youngs = params.positive("youngs_modulus_mpa", Some(206_000.0))?;
        let poisson = params.number("poisson_ratio", Some(0.3))?;
        if !(0.0..0.5).contains(&poisson) {
            return Err(ModelError::new(
                "poisson_ratio",
                format!("must lie in [0, 0.5), got {}", Shown(poisson)),
            ));
        }
        let per_pin = params.flag("pin_position_errors", false)?;
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
            cranks,
            crank_circle_radius,
            contact_modulus: youngs / (2.0 * (1.0 - poisson * poisson)),
            per_pin_errors: per_pin,
            stage,
            geometry: Vec::new(),
            levers: Vec::new(),
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
        model.geometry = (0..pins).map(|i| model.pin_geometry(i)).collect();
        model.levers = model.geometry.iter().map(|pin| pin.factors.lever).collect();
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

    /// The contact model of one disc of a two-crank reducer, for a model that embeds it
    /// (the crank elastic error, the torsion curve): the disc and pin parameters
    /// ([`DISC_KEYS`]) are taken from the embedding model's own, so that this model checks
    /// them and names them in its errors; the cranks sit on `crank_circle_radius`.
    pub(crate) fn of_two_crank_disc(
        params: &ModelParams,
        crank_circle_radius: f64,
    ) -> Result<Self, ModelError> {
        Self::from_params(
            &params
                .subset(&DISC_KEYS)
                .with_number("crank_count", 2.0)
                .with_number("crank_circle_radius_mm", crank_circle_radius),
        )
    }

    /// The checked cycloid–pin stage geometry (z_p, z_c, r_p, e).
    pub(crate) fn stage(&self) -> &CycloidStage {
        &self.stage
    }

    /// Share of the output torque carried by one disc.
    pub(crate) fn load_share(&self) -> f64 {
        self.load_share
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

    /// Disc rotation β under load (rad, [`Self::solve`]'s `rotation`) for one row of
    /// inputs, without allocating: a per-sample entry point of `torsion_curve`.
    pub(crate) fn rotation(&self, inputs: &[f64]) -> f64 {
        self.solve_pins(inputs).rotation
    }

    /// The rotation at which the driving flank first touches, min over pins with l_i > 0 of
    /// Δ_i/l_i (rad; NaN when a clearance is not finite), for one row of inputs (its torque
    /// is not used): the clearances only, no load solve.
    pub(crate) fn first_contact(&self, inputs: &[f64]) -> f64 {
        let clearances = self.clearances(inputs);
        let mut first_contact = f64::INFINITY;
        for (&lever, &clearance) in self.levers.iter().zip(&clearances) {
            if !clearance.is_finite() {
                return f64::NAN;
            }
            if lever > 0.0 {
                first_contact = first_contact.min(clearance / lever);
            }
        }
        first_contact
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
        let n = self.stage.pins;
        let torque = self.load_share * inputs[0].abs() * 1000.0; // N·mm; either flank alike
        let face_width = self.face_width + inputs[6];
        let clearances = self.clearances(inputs);
        let (levers, active_clearances) = (&self.levers[..], &clearances[..n]);
        let mut forces = [0.0; MAX_PINS];
        let mut f_max =
            4.0 * torque / (n as f64 * self.stage.eccentricity * self.stage.teeth as f64);
        let mut rotation = 0.0;
        let mut iterations = 0;
        if torque > 0.0 {
            for _ in 0..100 {
                iterations += 1;
                let stiffness = f_max / self.approach(f_max, face_width);
                rotation = solve_rotation(levers, active_clearances, torque / stiffness);
                let mut largest: f64 = 0.0;
                for i in 0..n {
                    let f = stiffness * (levers[i] * rotation - active_clearances[i]).max(0.0);
                    forces[i] = f;
                    largest = largest.max(f);
                }
                let settled = (largest - f_max).abs() <= 1e-12 * largest;
                f_max = largest;
                if settled {
                    break;
                }
            }
        }
        let resultant = self.pin_force_resultant(&forces[..n]);
        let tangential = torque / (self.cranks * self.crank_circle_radius);
        Solved {
            forces,
            clearances,
            face_width,
            rotation,
            resultant,
            max_crank_bearing_force: tangential + resultant.0.hypot(resultant.1) / self.cranks,
            iterations,
        }
    }
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

/// β with Σ max(l_i·β − Δ_i, 0)·l_i = `target` (> 0). The left side g(β) is continuous,
/// piecewise linear and non-decreasing (slope Σ over loaded pins of l_i²), so a bracket
/// is found by doubling and the root by Newton steps on the current loaded set, kept in
/// the bracket by bisection.
fn solve_rotation(levers: &[f64], clearances: &[f64], target: f64) -> f64 {
    // A non-finite row has no root; the bracket search below would never end.
    if !target.is_finite() || clearances.iter().any(|d| !d.is_finite()) {
        return f64::NAN;
    }
    let g = |beta: f64| -> (f64, f64) {
        let (mut value, mut slope) = (0.0, 0.0);
        for (&l, &d) in levers.iter().zip(clearances) {
            let deformation = l * beta - d;
            if deformation > 0.0 {
                value += deformation * l;
                slope += l * l;
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RV-80E of document 003 (validation.md: 40 pins, 39 teeth, e 1.5 mm, r_p 76.5 mm,
    /// pin diameter 6 mm), with the parameters 003 leaves out: face width 12 mm, three
    /// cranks on a 42 mm circle (the reading of 003's printed F_n1).
    fn rv80e(share: f64) -> CycloidPinContact {
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
        let mut out = [0.0; 6];
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
        let mut out = [0.0; 6];
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
        let mut out = [0.0; 6];
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
}
