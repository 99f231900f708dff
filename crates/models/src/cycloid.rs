//! The cycloid–pin stage geometry shared by the models that have one (contact, elastic
//! error, transmission error): pin count z_p, tooth count z_c = z_p − 1, pin circle radius
//! r_p and eccentricity e, checked once with errors naming the parameter key, and the
//! factors of a pin's contact normal (documents 003 and validation.md 003), in the one
//! place both the contact and the transmission-error model take them from.

use crate::{ModelError, ModelParams};
use rvtol_deviation::{Rounded, Shown};

/// A checked cycloid–pin stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CycloidStage {
    /// z_p.
    pub pins: usize,
    /// z_c = z_p − 1.
    pub teeth: usize,
    /// r_p, mm.
    pub pin_circle_radius: f64,
    /// e, mm.
    pub eccentricity: f64,
}

impl CycloidStage {
    /// Reads `pin_count`, `cycloid_teeth`, `pin_circle_radius_mm` and `eccentricity_mm`:
    /// 3 ≤ z_p ≤ `max_pins`, z_c = z_p − 1 (a ratio of z_c needs one tooth fewer than
    /// pins; 003's table swaps the counts), radii positive, K1 = e·z_p/r_p < 1 (a curtate
    /// cycloid).
    pub fn from_params(params: &ModelParams, max_pins: usize) -> Result<Self, ModelError> {
        let pins = params.count("pin_count", None)? as usize;
        if !(3..=max_pins).contains(&pins) {
            return Err(ModelError::new(
                "pin_count",
                format!("must be between 3 and {max_pins}, got {pins}"),
            ));
        }
        let teeth = params.count("cycloid_teeth", None)? as usize;
        if teeth + 1 != pins {
            return Err(ModelError::new(
                "cycloid_teeth",
                format!(
                    "must be pin_count − 1 = {}, got {teeth} (one tooth fewer than pins; 40 pins and 39 teeth give the ratio 121)",
                    pins - 1
                ),
            ));
        }
        let pin_circle_radius = params.positive("pin_circle_radius_mm", None)?;
        let eccentricity = params.positive("eccentricity_mm", None)?;
        let stage = CycloidStage {
            pins,
            teeth,
            pin_circle_radius,
            eccentricity,
        };
        if stage.k1() >= 1.0 {
            return Err(ModelError::new(
                "eccentricity_mm",
                format!(
                    "K1 = e·z_p/r_p = {} must be below 1 (a curtate cycloid)",
                    Rounded(stage.k1())
                ),
            ));
        }
        Ok(stage)
    }

    /// Checks that pins of radius `pin_radius` (the parameter `key`) fit the stage: adjacent
    /// pins must not overlap, r_rp < r_p·sin(π/z_p), and the disc profile, the inner
    /// equidistant of the theoretical cycloid at distance r_rp, must not be undercut:
    /// r_rp below the smallest curvature radius of the theoretical profile where it is
    /// convex (the inverse curvature κ = (K1·(z_p + 1)·cos φ − (1 + z_p·K1²))/(r_p·S³) of
    /// document 003 negative; the equidistant loops where 1 + r_rp·κ ≤ 0).
    pub fn check_pin_radius(&self, key: &str, pin_radius: f64) -> Result<(), ModelError> {
        let zp = self.pins as f64;
        let gap_limit = self.pin_circle_radius * (std::f64::consts::PI / zp).sin();
        if pin_radius >= gap_limit {
            return Err(ModelError::new(
                key,
                format!(
                    "pins of radius {} overlap their neighbours on a {} mm pin circle with {} pins: the radius must be below r_p·sin(π/z_p) = {}",
                    Shown(pin_radius),
                    Shown(self.pin_circle_radius),
                    self.pins,
                    Rounded(gap_limit)
                ),
            ));
        }
        let k1 = self.k1();
        // κ depends on cos φ only: scan c = cos φ over [−1, 1].
        let most_convex = (0..=10_000)
            .map(|i| -1.0 + 2.0 * i as f64 / 10_000.0)
            .map(|c| {
                let s = (1.0 + k1 * k1 - 2.0 * k1 * c).sqrt();
                (k1 * (zp + 1.0) * c - (1.0 + zp * k1 * k1)) / (self.pin_circle_radius * s.powi(3))
            })
            .fold(f64::INFINITY, f64::min);
        if most_convex < 0.0 && 1.0 + pin_radius * most_convex <= 0.0 {
            return Err(ModelError::new(
                key,
                format!(
                    "pins of radius {} undercut the disc profile: the theoretical cycloid's smallest convex curvature radius is {} mm (K1 = {}), and the pin radius must stay below it",
                    Shown(pin_radius),
                    Shown(-1.0 / most_convex),
                    Shown(k1)
                ),
            ));
        }
        Ok(())
    }

    /// K1 = e·z_p/r_p.
    pub fn k1(&self) -> f64 {
        self.eccentricity * self.pins as f64 / self.pin_circle_radius
    }

    /// The factors of the pin at φ from the eccentric (docs/models.md §10): with
    /// S = √(1 + K1² − 2K1·cos φ), its lever l = e·z_c·sin φ/S about the disc centre and
    /// the projections on its contact normal of each clearance term and displacement.
    pub fn pin_factors(&self, phi: f64) -> PinFactors {
        let (sin, cos) = phi.sin_cos();
        self.pin_factors_at(sin, cos)
    }

    /// [`Self::pin_factors`] from sin φ and cos φ.
    pub fn pin_factors_at(&self, sin: f64, cos: f64) -> PinFactors {
        let k1 = self.k1();
        let s = (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
        PinFactors {
            lever: self.eccentricity * self.teeth as f64 * sin / s,
            equidistant: 1.0 - sin / s,
            shift: -(1.0 - k1 * cos - (1.0 - k1 * k1).sqrt() * sin) / s,
            radial: (1.0 - k1 * cos) / s,
            eccentric: (k1 - cos) / s,
            tangential: k1 * sin / s,
        }
    }
}

/// The lever and normal projections of one pin, see [`CycloidStage::pin_factors`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PinFactors {
    /// l = e·z_c·sin φ/S, mm.
    pub lever: f64,
    /// Factor of the equidistant modification Δr_rp: 1 − sin φ/S (003 standard form).
    pub equidistant: f64,
    /// Factor of the shift modification Δr_p: −(1 − K1·cos φ − √(1 − K1²)·sin φ)/S.
    pub shift: f64,
    /// Factor of a radial (outward) pin displacement: (1 − K1·cos φ)/S.
    pub radial: f64,
    /// Factor of a disc-centre displacement along the eccentric: (K1 − cos φ)/S.
    pub eccentric: f64,
    /// Factor of a tangential pin displacement (towards increasing φ): K1·sin φ/S.
    pub tangential: f64,
}
