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

use super::two_discs::{lane_squares, lane_stats, modification, RowTerms, TE_OUTPUTS};
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
    points: usize,
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
        solver: TwoDiscs::new(rule.contact(), side.disc_compliance(disc_torque)),
        nominal: 0.0,
        table: PinPhases::new(stage, points),
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
    /// The pins' factors at every place the curve's points put them.
    pub table: PinPhases,
}

/// The pins' factors at every fractional pin pitch the curve's points and the two discs
/// put them at: pin slot s of phase p sits at φ = 2π(s + p/P)/z_p from its disc's
/// eccentric, P = 2N/g phases (g = gcd(z_c·z_p, N); the factor 2 for disc 2, half a
/// revolution of the eccentric on, which is half a pitch for an odd pin count). Entry
/// p·z_p + s; the tooth space of a slot as round(t) and round(t + ½), t = z_c·λ/2π − p/P
/// (λ the slot's polar angle about the disc centre from the eccentric): the geometry of
/// `exact_gap_at` without its square roots and arc tangents at every point.
#[derive(Debug, Clone, Default)]
pub(super) struct PinPhases {
    /// P.
    phases: usize,
    /// Entry p·z_p + s, one slot's factors together (a point reads its slots in a row).
    slots: Vec<SlotFactors>,
}

/// One slot's factors (two_discs.rs: `exact_gap_at`) and tooth space.
#[derive(Debug, Clone, Copy)]
struct SlotFactors {
    lever: f64,
    equidistant: f64,
    shift: f64,
    eccentric: f64,
    radial: f64,
    tangential: f64,
    /// round(t), round(t + ½).
    tooth: [i32; 2],
}

impl PinPhases {
    /// The table of the stage for N points per revolution.
    fn new(stage: &CycloidStage, points: usize) -> PinPhases {
        let (zp, zc) = (stage.pins, stage.teeth);
        let phases = 2 * points / gcd(zc * zp, points);
        let mut table = PinPhases {
            phases,
            ..PinPhases::default()
        };
        let (r_p, e) = (stage.pin_circle_radius, stage.eccentricity);
        for p in 0..phases {
            let fraction = p as f64 / phases as f64;
            for slot in 0..zp {
                let phi = 2.0 * PI * (slot as f64 + fraction) / zp as f64;
                let (sin, cos) = phi.sin_cos();
                let factors = stage.pin_factors_at(sin, cos);
                let (equidistant, shift) = modification(&factors);
                let polar = (r_p * sin).atan2(r_p * cos - e);
                let t = zc as f64 * polar / (2.0 * PI) - fraction;
                table.slots.push(SlotFactors {
                    lever: factors.lever,
                    equidistant,
                    shift,
                    eccentric: factors.eccentric,
                    radial: factors.radial,
                    tangential: factors.tangential,
                    tooth: [t.round() as i32, (t + 0.5).round() as i32],
                });
            }
        }
        table
    }
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// Per-thread work state of the loaded curve: both discs' gaps and levers at one point,
/// and the pins near contact the solver is given first.
#[derive(Debug, Default)]
pub(super) struct LoadedScratch {
    gaps: [Vec<f64>; 2],
    levers: [Vec<f64>; 2],
    near_gaps: [Vec<f64>; 2],
    near_levers: [Vec<f64>; 2],
}

/// The pins within this turn of contact at the previous point's solution (rad, disc
/// frame; 2″, some twenty times a point's step on a busy curve) are the solver's first
/// set; the solution is then checked against every pin.
const NEAR_TURN: f64 = 1e-5;

impl LoadedScratch {
    /// Keeps in the near set the pins of each disc that come into contact within
    /// [`NEAR_TURN`] of the turns `turns`.
    fn select_near(&mut self, turns: [f64; 2]) {
        for (d, turn) in turns.into_iter().enumerate() {
            let (gaps, levers) = (&mut self.near_gaps[d], &mut self.near_levers[d]);
            gaps.clear();
            levers.clear();
            for (g, l) in self.gaps[d].iter().zip(&self.levers[d]) {
                if l * turn + l.abs() * NEAR_TURN - g > 0.0 {
                    gaps.push(*g);
                    levers.push(*l);
                }
            }
        }
    }

    /// Whether every pin in contact at the turns `turns` is in the near set.
    fn near_holds(&self, turns: [f64; 2]) -> bool {
        (0..2).all(|d| {
            let count = |gaps: &[f64], levers: &[f64]| {
                gaps.iter()
                    .zip(levers)
                    .filter(|(g, l)| *l * turns[d] - *g > 0.0)
                    .count()
            };
            count(&self.gaps[d], &self.levers[d]) == count(&self.near_gaps[d], &self.near_levers[d])
        })
    }
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
        for (j, value) in curve.iter_mut().enumerate() {
            let offsets = self.loaded_pins(inputs, terms, j, scratch);
            // The pins near contact first (a few of the z_p), then every pin where the
            // solution touches one outside them or there is no previous solution.
            let mut solved = None;
            if warm.carrier.is_finite() {
                scratch.select_near(warm.turns);
                let near = [0, 1].map(|d| LoadedDisc {
                    gaps: &scratch.near_gaps[d],
                    levers: &scratch.near_levers[d],
                    offset: offsets[d],
                });
                if let Ok(solution) = loaded.solver.solve(&near, loaded.target, &warm) {
                    if scratch.near_holds(solution.turns) {
                        solved = Some(solution);
                    }
                }
            }
            warm = match solved {
                Some(solution) => solution,
                None => {
                    let all = [0, 1].map(|d| LoadedDisc {
                        gaps: &scratch.gaps[d],
                        levers: &scratch.levers[d],
                        offset: offsets[d],
                    });
                    loaded.solver.solve(&all, loaded.target, &warm)?
                }
            };
            *value = kappa * warm.carrier - loaded.nominal;
        }
        Ok(())
    }

    /// Both discs' pins at point j of N from the table (gaps and levers into `scratch`, the
    /// pins whose lever holds a turn), and their crank offsets C_d: the geometry of
    /// `exact_gap_at`, pin by pin.
    fn loaded_pins(
        &self,
        inputs: &[f64],
        terms: &RowTerms,
        j: usize,
        scratch: &mut LoadedScratch,
    ) -> [f64; 2] {
        let table = &self.loaded().table;
        let ph = self.physical();
        let (n, zp, zc) = (self.points, self.pins, self.cycloid_teeth);
        let theta = 2.0 * PI * j as f64 / n as f64;
        let angles = self.angles_at(theta);
        let (offsets, _) = self.crank_offsets(terms, angles);
        let floor = LEVER_FLOOR * self.eccentricity;
        for d in 0..2 {
            // Disc d's pins in half-pitch units of 1/(2N): q = 2·z_c·z_p·j + d·z_p·N.
            let q = 2 * zc * zp * j + d * zp * n;
            let (whole, rest) = (q / (2 * n), q % (2 * n));
            let phase = rest * table.phases / (2 * n);
            let d_r = Self::along(terms, d, angles[0], angles[1]);
            let constant = terms.profile[d] - terms.err_rrp;
            let (gaps, levers) = (&mut scratch.gaps[d], &mut scratch.levers[d]);
            gaps.clear();
            levers.clear();
            let base = phase * zp;
            // Slot s holds pin (s − k) mod z_p; tooth spaces shifted by k (mod z_c), and by
            // half a revolution of the eccentric on disc 2. Indices step without divisions.
            let mut pin = (zp - whole % zp) % zp;
            let tooth_shift = (d * (zp / 2)) as i64 - (whole % zc) as i64;
            for factors in &table.slots[base..base + zp] {
                let lever = factors.lever;
                let this_pin = pin;
                pin = if pin + 1 == zp { 0 } else { pin + 1 };
                if lever.abs() <= floor {
                    continue;
                }
                let pin = this_pin;
                let (pin_r, pin_t) = if self.per_pin {
                    (inputs[ph.pin_base + pin], inputs[ph.pin_base + zp + pin])
                } else {
                    (0.0, 0.0)
                };
                let tooth = if self.per_tooth {
                    // round(t + d·z_p/2) − k: for an odd z_p, disc 2's half pitch rounds
                    // with t + ½.
                    let [round, half] = factors.tooth;
                    let rounded = if d == 1 && zp % 2 == 1 { half } else { round };
                    let mut space = i64::from(rounded) + tooth_shift;
                    while space < 0 {
                        space += zc as i64;
                    }
                    while space >= zc as i64 {
                        space -= zc as i64;
                    }
                    inputs[ph.tooth_base + d * zc + space as usize]
                } else {
                    0.0
                };
                gaps.push(
                    terms.d_rp * factors.equidistant
                        + terms.d_p * factors.shift
                        + d_r * factors.eccentric
                        + (terms.err_rp + pin_r) * factors.radial
                        + pin_t * factors.tangential
                        + constant
                        + tooth,
                );
                levers.push(lever);
            }
        }
        offsets
    }

    /// [`Self::loaded_pins`] from the geometry pin by pin (`exact_gap_at`): the reference
    /// of the table.
    #[cfg(test)]
    fn exact_loaded_pins(
        &self,
        inputs: &[f64],
        terms: &RowTerms,
        theta: f64,
        scratch: &mut LoadedScratch,
    ) -> [f64; 2] {
        let angles = self.angles_at(theta);
        let (offsets, _) = self.crank_offsets(terms, angles);
        for d in 0..2 {
            let d_r = Self::along(terms, d, angles[0], angles[1]);
            let start = self.cycloid_teeth as f64 * theta + d as f64 * PI;
            let (gaps, levers) = (&mut scratch.gaps[d], &mut scratch.levers[d]);
            gaps.clear();
            levers.clear();
            for pin in 0..self.pins {
                let phi = (start + 2.0 * PI * pin as f64 / self.pins as f64).rem_euclid(2.0 * PI);
                let (gap, lever) =
                    self.exact_gap_at(inputs, terms, d, pin, theta, d_r, phi.sin_cos());
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
