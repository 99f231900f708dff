//! The cycloid–pin stage geometry shared by the models that have one (contact, elastic
//! error, transmission error): pin count z_p, tooth count z_c = z_p − 1, pin circle radius
//! r_p and eccentricity e, checked once with errors naming the parameter key.

use crate::{ModelError, ModelParams};

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
                    stage.k1()
                ),
            ));
        }
        Ok(stage)
    }

    /// K1 = e·z_p/r_p.
    pub fn k1(&self) -> f64 {
        self.eccentricity * self.pins as f64 / self.pin_circle_radius
    }
}
