//! The transmission error under load (docs/models.md §12.9; `disc_contact` "loaded", the
//! default of the physical reading): at every point Θ_j of the curve the output angle of
//! the loaded contact solution (`crate::loaded`) at the output torque T with the input
//! locked, both discs elastic pin by pin on their signed gaps and coupled through the
//! crank side, less the output angle of the perfect reducer (no deviation, no modification)
//! at the same torque, averaged over the revolution:
//!
//! ```text
//! gaps g_i, levers l_i, crank offsets C_d     the physical reading's geometry (§12.3–12.4),
//!                                            pin by pin at Θ_j (two_discs.rs: exact_gap_at)
//! solve  M_1 + M_2 = −λ·T,  x = C_d + y_d + c·M_d(y_d)          (crate::loaded)
//! TE(Θ_j) = κ·x_j − ⟨κ·x⟩_perfect                               (κ = λ = z_c/D)
//! ```
//!
//! T > 0 loads the drive flank (l < 0): the single-flank test's brake torque. c is the
//! crank side's compliance of one disc against the other (`CrankSide::disc_compliance`,
//! linearised at each disc carrying half of λ·T). The angle is measured in the frame of the
//! rigid reading (from the disc turned into drive-flank contact), so that as T → 0+ the
//! curve tends to the rigid first contact (`crate::loaded`'s limit: the disc that touches
//! first takes the whole load while its elastic angle is below the other's gap), less the
//! perfect reducer's angle, which tends to 0. An assembly whose discs do not fit (crank
//! pairing, a full disc) has a loaded solution all the same: both flanks carry, its
//! transmission error is finite, and the preload rule judges it (`over_preloaded` marks
//! it non-conforming). The curve is sampled (no refinement of its extremes: it has no
//! kinks at the first contact, only where a pin comes into contact); its orders are the
//! direct DFT of the rigid reading, the same five.

use std::f64::consts::PI;

use super::two_discs::{lane_squares, lane_stats, RowTerms, TE_OUTPUTS};
use super::TransmissionError;
use crate::cycloid::CycloidStage;
use crate::loaded::{LoadedDisc, Solution, TwoDiscs, Unconverged};
use crate::preload::{PreloadRule, LEVER_FLOOR};
use crate::stiffness::build;
use crate::{ModelError, ModelParams};
use rvtol_deviation::Shown;

/// The default torque of the loaded reading, a fraction of the rated torque: 3 %, the load
/// at which a catalogue reads lost motion (validation.md), a light load as a single-flank
/// transmission-error test applies.
pub(super) const DEFAULT_LOAD_FRACTION: f64 = 0.03;

/// The loaded reading from its parameters: the torque (`load_torque_nm`, default 3 % of
/// `rated_torque_nm`), the preload rule's contact law, and the crank side built from its
/// keys (`crate::stiffness::build`) with `cranks` cranks on the crank circle a_w, whose
/// compliance of one disc against the other is taken at each disc carrying half of λ·T.
pub(super) fn build(
    params: &ModelParams,
    stage: &CycloidStage,
    rule: &PreloadRule,
    (cranks, crank_radius): (usize, f64),
    (ratio, lambda): (f64, f64),
) -> Result<Loaded, ModelError> {
    let rated = params.positive("rated_torque_nm", None)?;
    let torque = params.number("load_torque_nm", Some(DEFAULT_LOAD_FRACTION * rated))?;
    if !(torque > 0.0 && torque <= 10.0 * rated) {
        return Err(ModelError::new(
            "load_torque_nm",
            format!(
                "must be above 0 and at most 10 times rated_torque_nm ({} N·m), got {}",
                Shown(rated),
                Shown(torque)
            ),
        ));
    }
    let reducer = build::Reducer {
        cranks,
        crank_circle_radius: crank_radius,
        pins: stage.pins,
        teeth: stage.teeth,
        pin_circle_radius: stage.pin_circle_radius,
        eccentricity: stage.eccentricity,
        curtate: stage.k1(),
        face_width: rule.contact().face_width,
        ratio,
        reference_disc_torque: 0.5 * lambda * DEFAULT_LOAD_FRACTION * rated * 1000.0,
        elastic_bodies: params.flag("body_compliance", true)?,
    };
    let side = build::crank_side(params, &reducer)?.side;
    let disc_torque = 0.5 * lambda * torque * 1000.0;
    Ok(Loaded {
        torque,
        target: -2.0 * disc_torque,
        solver: TwoDiscs {
            contact: *rule.contact(),
            compliance: side.disc_compliance(disc_torque),
        },
        nominal: 0.0,
    })
}

/// The loaded reading's data.
#[derive(Debug, Clone)]
pub(super) struct Loaded {
    /// T, the output torque, N·m.
    pub torque: f64,
    /// M* = −λ·T, the pins' total moment, N·mm.
    pub target: f64,
    /// The contact law and the crank side's compliance.
    pub solver: TwoDiscs,
    /// ⟨κ·x⟩ of the perfect reducer at T, rad at the output.
    pub nominal: f64,
}

/// Per-thread work state of the loaded curve: both discs' gaps and levers at one point.
#[derive(Debug, Default)]
pub(super) struct LoadedScratch {
    gaps: [Vec<f64>; 2],
    levers: [Vec<f64>; 2],
}

impl TransmissionError {
    /// The loaded reading's data (the physical reading with `disc_contact` "loaded").
    fn loaded(&self) -> &Loaded {
        self.loaded
            .as_deref()
            .expect("called on the loaded reading")
    }

    /// Fills `curve` (N values, rad at the output) with the loaded transmission error of a
    /// row, warm starting each point from the previous one; the first point that has no
    /// solution ends it with its cause.
    pub(super) fn loaded_curve(
        &self,
        inputs: &[f64],
        terms: &RowTerms,
        scratch: &mut LoadedScratch,
        curve: &mut [f64],
    ) -> Result<(), Unconverged> {
        let loaded = self.loaded();
        let kappa = self.physical().kappa;
        let mut warm = Solution::COLD;
        let n = curve.len() as f64;
        for (j, value) in curve.iter_mut().enumerate() {
            let theta = 2.0 * PI * j as f64 / n;
            let offsets = self.loaded_pins(inputs, terms, theta, scratch);
            let discs = [0, 1].map(|d| LoadedDisc {
                gaps: &scratch.gaps[d],
                levers: &scratch.levers[d],
                offset: offsets[d],
            });
            warm = loaded.solver.solve(&discs, loaded.target, &warm)?;
            *value = kappa * warm.carrier - loaded.nominal;
        }
        Ok(())
    }

    /// Both discs' pins at Θ from the exact geometry (gaps and levers into `scratch`, the
    /// pins whose lever holds a turn), and their crank offsets C_d.
    fn loaded_pins(
        &self,
        inputs: &[f64],
        terms: &RowTerms,
        theta: f64,
        scratch: &mut LoadedScratch,
    ) -> [f64; 2] {
        let angles = self.angles_at(theta);
        let (offsets, _) = self.crank_offsets(terms, angles);
        let (pitch_sin, pitch_cos) = (2.0 * PI / self.pins as f64).sin_cos();
        for d in 0..2 {
            let d_r = Self::along(terms, d, angles[0], angles[1]);
            let start = (self.cycloid_teeth as f64 * theta + d as f64 * PI).rem_euclid(2.0 * PI);
            let (gaps, levers) = (&mut scratch.gaps[d], &mut scratch.levers[d]);
            gaps.clear();
            levers.clear();
            let mut previous = (0.0, 1.0);
            for pin in 0..self.pins {
                // Exact sin_cos every 8 pins, the rotation between (as `exact_flanks`).
                let (sin, cos) = if pin % 8 == 0 {
                    (start + 2.0 * PI * pin as f64 / self.pins as f64).sin_cos()
                } else {
                    let (sin, cos) = previous;
                    (
                        sin * pitch_cos + cos * pitch_sin,
                        cos * pitch_cos - sin * pitch_sin,
                    )
                };
                previous = (sin, cos);
                let (gap, lever) = self.exact_gap_at(inputs, terms, d, pin, theta, d_r, (sin, cos));
                if lever.abs() > LEVER_FLOOR * self.eccentricity {
                    gaps.push(gap);
                    levers.push(lever);
                }
            }
        }
        offsets
    }

    /// The loaded reading's outputs [p-p, rms, mean, orders 1, z_c, z_p, 2z_c, 2z_p]
    /// (arcsec) of a row; NaN where a point has no solution.
    pub(super) fn evaluate_loaded(
        &self,
        inputs: &[f64],
        terms: &RowTerms,
        scratch: &mut LoadedScratch,
        curve: &mut Vec<f64>,
        outputs: &mut [f64],
    ) {
        curve.resize(self.points, 0.0);
        if self.loaded_curve(inputs, terms, scratch, curve).is_err() {
            outputs[..TE_OUTPUTS].fill(f64::NAN);
            return;
        }
        let n = self.points as f64;
        let quads = curve.as_chunks::<4>().0;
        let lanes = lane_stats(quads);
        let lo = lanes.lo.into_iter().fold(f64::INFINITY, f64::min);
        let hi = lanes.hi.into_iter().fold(f64::NEG_INFINITY, f64::max);
        let mean = ((lanes.sum[0] + lanes.sum[1]) + (lanes.sum[2] + lanes.sum[3])) / n;
        let squares = lane_squares(quads, mean);
        let var = ((squares[0] + squares[1]) + (squares[2] + squares[3])) / n;
        let orders = self.physical().orders.amplitudes(curve);
        let to_arcsec = crate::ARCSEC_PER_RAD;
        outputs[0] = (hi - lo) * to_arcsec;
        outputs[1] = var.sqrt() * to_arcsec;
        outputs[2] = mean * to_arcsec;
        for (out, order) in outputs[3..TE_OUTPUTS].iter_mut().zip(orders) {
            *out = order * to_arcsec;
        }
    }

    /// T, the loaded reading's output torque, N·m (None outside the loaded reading).
    pub fn load_torque(&self) -> Option<f64> {
        self.loaded.as_ref().map(|l| l.torque)
    }

    /// The loaded transmission error of a row at the N points, arcsec (None outside the
    /// loaded reading, or where a point has no solution).
    pub fn loaded_curve_arcsec(&self, inputs: &[f64]) -> Option<Vec<f64>> {
        self.loaded.as_ref()?;
        let terms = self.row_terms(inputs);
        let mut curve = vec![0.0; self.points];
        let mut scratch = LoadedScratch::default();
        self.loaded_curve(inputs, &terms, &mut scratch, &mut curve)
            .ok()?;
        Some(
            curve
                .into_iter()
                .map(|v| v * crate::ARCSEC_PER_RAD)
                .collect(),
        )
    }

    /// ⟨κ·x⟩ of the perfect reducer (every input 0: no deviation, no modification), rad:
    /// the nominal the loaded curve is measured from (set once, when the model is built).
    pub(super) fn perfect_loaded_angle(&self) -> Result<f64, Unconverged> {
        let zero = vec![0.0; self.inputs.len()];
        let terms = self.row_terms(&zero);
        let mut curve = vec![0.0; self.points];
        let mut scratch = LoadedScratch::default();
        self.loaded_curve(&zero, &terms, &mut scratch, &mut curve)?;
        Ok(curve.iter().sum::<f64>() / self.points as f64)
    }
}

#[cfg(test)]
mod tests;
