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
//!
//! The reading's data is [`Loaded`] (the torque, the solver, the nominal and the pins'
//! table [`PinPhases`]), its per-thread work state [`LoadedScratch`]; its methods take what
//! every reading shares ([`Common`]) and the physical reading it builds on ([`Physical`]:
//! the row's terms, the crank offsets, κ, the output orders, where the pin and tooth inputs
//! lie), whose tables judge interference and preload in the same row.

use std::f64::consts::PI;

use super::common::{gcd, Common};
use super::two_discs::{lane_squares, lane_stats, Physical, RowTerms, TE_OUTPUTS};
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
        face_width: rule.contact().face_width(),
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
        stage: *stage,
    })
}

/// The loaded reading's data: the torque, the solver, the nominal the curve is measured from
/// and the pins' table. Its code reads the physical reading's geometry ([`Physical`]: the
/// row's terms, the crank offsets, κ, the output orders) and never its tables.
#[derive(Debug, Clone)]
pub(super) struct Loaded {
    /// T, the output torque, N·m.
    torque: f64,
    /// M* = −λ·T, the pins' total moment, N·mm.
    target: f64,
    /// The contact law and the crank side's compliance.
    solver: TwoDiscs,
    /// ⟨κ·x⟩ of the perfect reducer at T, rad at the output.
    nominal: f64,
    /// The pins' factors at every place the curve's points put them.
    table: PinPhases,
    /// The stage the table is built for (a table at another point count: `at_points`).
    stage: CycloidStage,
}

/// The pins' place at every fractional pin pitch the curve's points and the two discs put
/// them at: pin slot s of phase p sits at φ = 2π(s + p/P)/z_p from its disc's eccentric.
/// Point j puts disc d's slots q = 2·z_c·z_p·j + d·z_p·N half-steps of 1/(2N) pitch on, so
/// the phases met are the multiples of G = gcd(2·z_c·z_p, z_p·N, 2N) and P = 2N/G.
///
/// Every factor of a pin (`CycloidStage::pin_factors_at`, with the modification of
/// `two_discs::modification`) is a combination of a = sin φ/S, b = cos φ/S and c = 1/S
/// (S = √(1 + K1² − 2K1·cos φ)):
///
/// ```text
/// lever l = e·z_c·a            modification  1 + a  (Δr_rp),  −c + K1·b − √(1 − K1²)·a  (Δr_p)
/// radial  c − K1·b             eccentric     K1·c − b          tangential  K1·a
/// ```
///
/// so the table holds a, b and c (entry p·z_p + s; a = 0 where the lever is below the
/// floor), and the tooth space of a slot as round(t) and round(t + ½),
/// t = z_c·λ/2π − p/P (λ the slot's polar angle about the disc centre from the eccentric):
/// the geometry of `exact_gap_at` without its square roots and arc tangents at every
/// point, in 32 bytes a slot, so that the table stays in a core's cache.
#[derive(Debug, Clone, Default)]
pub(super) struct PinPhases {
    /// N, the curve's points per revolution.
    points: usize,
    /// G, the half-steps of 1/(2N) pitch from one phase to the next.
    step: usize,
    /// K1 and √(1 − K1²).
    k1: f64,
    k1_root: f64,
    /// [a, b, c] of entry p·z_p + s.
    factors: Vec<[f64; 3]>,
    /// [round(t), round(t + ½)] of entry p·z_p + s.
    tooth: Vec<[i32; 2]>,
}

impl PinPhases {
    /// The table of the stage for N points per revolution.
    fn new(stage: &CycloidStage, points: usize) -> PinPhases {
        let (zp, zc) = (stage.pins, stage.teeth);
        let step = gcd(gcd(2 * zc * zp, zp * points), 2 * points);
        let phases = 2 * points / step;
        let (r_p, e, k1) = (stage.pin_circle_radius, stage.eccentricity, stage.k1());
        let mut table = PinPhases {
            points,
            step,
            k1,
            k1_root: (1.0 - k1 * k1).sqrt(),
            ..PinPhases::default()
        };
        for p in 0..phases {
            let fraction = p as f64 / phases as f64;
            for slot in 0..zp {
                let phi = 2.0 * PI * (slot as f64 + fraction) / zp as f64;
                let (sin, cos) = phi.sin_cos();
                let c = 1.0 / (1.0 + k1 * k1 - 2.0 * k1 * cos).sqrt();
                let a = sin * c;
                let holds = (e * zc as f64 * a).abs() > LEVER_FLOOR * e;
                table
                    .factors
                    .push([if holds { a } else { 0.0 }, cos * c, c]);
                let polar = (r_p * sin).atan2(r_p * cos - e);
                let t = zc as f64 * polar / (2.0 * PI) - fraction;
                table
                    .tooth
                    .push([t.round() as i32, (t + 0.5).round() as i32]);
            }
        }
        table
    }
}

/// Which of a disc's pins [`Loaded::pins`] keeps.
#[derive(Debug, Clone, Copy)]
enum Keep {
    /// Every pin whose lever holds a turn.
    All,
    /// The pins that come into contact within [`NEAR_TURN`] of the disc's turn (rad).
    Near(f64),
}

/// Per-thread work state of the loaded curve: the row's pin and tooth-space errors laid out
/// so that a point reads them in a row, both discs' kept pins at one point (gaps and
/// levers), and every pin's where the near ones do not settle a point.
#[derive(Debug, Default)]
pub(super) struct LoadedScratch {
    /// R = the pin circle's radius error + the pin's radial error, as [R, K1·R], pin by
    /// pin, twice over (slot s + offset).
    pin_radial: Vec<[f64; 2]>,
    /// K1 × the pin's tangential error, twice over.
    pin_tangential: Vec<f64>,
    /// Each disc's tooth-space errors, three times over (round(t) + shift + z_c).
    teeth: [Vec<f64>; 2],
    /// The kept pins of each disc: gaps and levers in their first `kept` entries.
    gaps: [Vec<f64>; 2],
    levers: [Vec<f64>; 2],
    kept: [usize; 2],
}

/// The pins within this turn of contact at the previous point's solution (rad, disc
/// frame; 2″, some twenty times a point's step on a busy curve) are the solver's first
/// set; where the solution's turns stay within it of the previous point's, every pin in
/// contact is among them (l·y − g > 0 and |y − y₀| ≤ NEAR_TURN give
/// l·y₀ + |l|·NEAR_TURN − g > 0), else every pin is checked.
const NEAR_TURN: f64 = 1e-5;

impl LoadedScratch {
    /// Lays out the row's pin and tooth-space errors (zeros where the model has none).
    /// `k1` is K1 of the loaded reading's table.
    fn prepare(
        &mut self,
        common: &Common,
        physical: &Physical,
        k1: f64,
        inputs: &[f64],
        terms: &RowTerms,
    ) {
        let (zp, zc) = (common.pins, common.cycloid_teeth);
        let (pin_base, tooth_base) = (physical.pin_base(), physical.tooth_base());
        self.pin_radial.clear();
        self.pin_tangential.clear();
        for _ in 0..2 {
            for pin in 0..zp {
                let (r, t) = if common.per_pin {
                    (inputs[pin_base + pin], inputs[pin_base + zp + pin])
                } else {
                    (0.0, 0.0)
                };
                let radial = terms.err_rp + r;
                self.pin_radial.push([radial, k1 * radial]);
                self.pin_tangential.push(k1 * t);
            }
        }
        for (d, teeth) in self.teeth.iter_mut().enumerate() {
            teeth.clear();
            for _ in 0..3 {
                for space in 0..zc {
                    teeth.push(if common.per_tooth {
                        inputs[tooth_base + d * zc + space]
                    } else {
                        0.0
                    });
                }
            }
        }
        for d in 0..2 {
            self.gaps[d].resize(zp, 0.0);
            self.levers[d].resize(zp, 0.0);
        }
    }

    /// Disc d's kept pins.
    fn disc(&self, d: usize, offset: f64) -> LoadedDisc<'_> {
        LoadedDisc {
            gaps: &self.gaps[d][..self.kept[d]],
            levers: &self.levers[d][..self.kept[d]],
            arms: &self.levers[d][..self.kept[d]],
            offset,
            slack: 0.0,
        }
    }
}

impl Loaded {
    /// T, the output torque, N·m.
    pub(super) fn torque(&self) -> f64 {
        self.torque
    }

    /// Sets the nominal to ⟨κ·x⟩ of the perfect reducer (every input 0: no deviation, no
    /// modification), rad: the nominal the loaded curve is measured from (set once, when
    /// the model is built; the curve it is taken from is measured from 0).
    pub(super) fn set_nominal(
        &mut self,
        common: &Common,
        physical: &Physical,
    ) -> Result<(), Unconverged> {
        let zero = vec![0.0; common.inputs.len()];
        let terms = physical.row_terms(common, &zero);
        let mut curve = vec![0.0; common.points];
        let mut scratch = LoadedScratch::default();
        self.curve(common, physical, &zero, &terms, &mut scratch, &mut curve)?;
        self.nominal = curve.iter().sum::<f64>() / common.points as f64;
        Ok(())
    }

    /// Fills `curve` (N values, rad at the output) with the loaded transmission error of a
    /// row, warm starting each point from the previous one; the first point that has no
    /// solution ends it with its cause.
    pub(super) fn curve(
        &self,
        common: &Common,
        physical: &Physical,
        inputs: &[f64],
        terms: &RowTerms,
        scratch: &mut LoadedScratch,
        curve: &mut [f64],
    ) -> Result<(), Unconverged> {
        let kappa = physical.kappa();
        scratch.prepare(common, physical, self.table.k1, inputs, terms);
        let mut warm = Solution::COLD;
        for (j, value) in curve.iter_mut().enumerate() {
            warm = self.point(common, physical, j, terms, scratch, &warm)?;
            *value = kappa * warm.carrier - self.nominal;
        }
        Ok(())
    }

    /// The solution at point j from the previous point's `warm`: on the pins near contact
    /// first (a few of the z_p), then on every pin where the turns moved beyond
    /// [`NEAR_TURN`] and a pin outside them is in contact, or there is no previous
    /// solution.
    fn point(
        &self,
        common: &Common,
        physical: &Physical,
        j: usize,
        terms: &RowTerms,
        scratch: &mut LoadedScratch,
        warm: &Solution,
    ) -> Result<Solution, Unconverged> {
        let solver = &self.solver;
        let target = self.target;
        if warm.carrier.is_finite() {
            let keep = warm.turns.map(Keep::Near);
            let offsets = self.pins(common, physical, terms, j, keep, scratch);
            let near = [0, 1].map(|d| scratch.disc(d, offsets[d]));
            if let Ok(solution) = solver.solve(&near, target, warm) {
                let within = (0..2).all(|d| (solution.turns[d] - warm.turns[d]).abs() <= NEAR_TURN);
                let touching =
                    |s: &LoadedScratch| [0, 1].map(|d| s.disc(d, 0.0).touching(solution.turns[d]));
                if within {
                    return Ok(solution);
                }
                let near_touching = touching(scratch);
                self.pins(common, physical, terms, j, [Keep::All; 2], scratch);
                if touching(scratch) == near_touching {
                    return Ok(solution);
                }
                let all = [0, 1].map(|d| scratch.disc(d, offsets[d]));
                return solver.solve(&all, target, warm);
            }
        }
        let offsets = self.pins(common, physical, terms, j, [Keep::All; 2], scratch);
        let all = [0, 1].map(|d| scratch.disc(d, offsets[d]));
        solver.solve(&all, target, warm)
    }

    /// Both discs' pins at point j of N from the table (gaps and levers of the pins `keep`
    /// keeps into `scratch`, prepared for the row), and their crank offsets C_d: the
    /// geometry of `exact_gap_at`, pin by pin.
    fn pins(
        &self,
        common: &Common,
        physical: &Physical,
        terms: &RowTerms,
        j: usize,
        keep: [Keep; 2],
        scratch: &mut LoadedScratch,
    ) -> [f64; 2] {
        let table = &self.table;
        let (n, zp, zc) = (table.points, common.pins, common.cycloid_teeth);
        let (k1, root) = (table.k1, table.k1_root);
        let lever_scale = common.eccentricity * zc as f64;
        let theta = 2.0 * PI * j as f64 / n as f64;
        let angles = common.angles_at(theta);
        let (offsets, _) = physical.crank_offsets(common, terms, angles);
        for (d, keep) in keep.into_iter().enumerate() {
            // Disc d's pins in half-pitch units of 1/(2N): q = 2·z_c·z_p·j + d·z_p·N.
            let q = 2 * zc * zp * j + d * zp * n;
            let (whole, rest) = (q / (2 * n), q % (2 * n));
            let base = rest / table.step * zp;
            let d_r = Physical::along(terms, d, angles[0], angles[1]);
            // gap = (Δr_rp + profile − Δr_rp-error + tooth) + a·(Δr_rp − √(1 − K1²)·Δr_p
            // + K1·T) + b·(K1·Δr_p − d_r − K1·R) + c·(−Δr_p + K1·d_r + R) (PinPhases).
            let constant = terms.d_rp + terms.profile[d] - terms.err_rrp;
            let along_a = terms.d_rp - root * terms.d_p;
            let along_b = k1 * terms.d_p - d_r;
            let along_c = -terms.d_p + k1 * d_r;
            // Slot s holds pin (s − k) mod z_p: entry s + (z_p − k mod z_p) of the doubled
            // pin columns; its tooth space round(t + d·z_p/2) − k (mod z_c) is entry
            // round(·) + ((d·z_p/2 − k) mod z_c) + z_c of the tripled one (for an odd z_p,
            // disc 2's half pitch rounds with t + ½).
            let pin_offset = (zp - whole % zp) % zp;
            let shift = ((d * (zp / 2)) as i64 - (whole % zc) as i64).rem_euclid(zc as i64);
            let tooth_offset = shift + zc as i64;
            let rounding = usize::from(d == 1 && zp % 2 == 1);
            let slots = base..base + zp;
            let factors = &table.factors[slots.clone()];
            let tooth_of = &table.tooth[slots];
            let radial = &scratch.pin_radial[pin_offset..pin_offset + zp];
            let tangential = &scratch.pin_tangential[pin_offset..pin_offset + zp];
            let teeth = &scratch.teeth[d];
            let (gaps, levers) = (&mut scratch.gaps[d], &mut scratch.levers[d]);
            let mut kept = 0;
            for s in 0..zp {
                let [a, b, c] = factors[s];
                let [r, k1_r] = radial[s];
                let tooth = teeth[(i64::from(tooth_of[s][rounding]) + tooth_offset) as usize];
                let gap = constant
                    + tooth
                    + a * (along_a + tangential[s])
                    + b * (along_b - k1_r)
                    + c * (along_c + r);
                let lever = lever_scale * a;
                let holds = match keep {
                    Keep::All => lever != 0.0,
                    Keep::Near(turn) => {
                        lever != 0.0 && lever * turn + lever.abs() * NEAR_TURN - gap > 0.0
                    }
                };
                gaps[kept] = gap;
                levers[kept] = lever;
                kept += usize::from(holds);
            }
            scratch.kept[d] = kept;
        }
        offsets
    }

    /// The loaded reading's outputs [p-p, rms, mean, orders 1, z_c, z_p, 2z_c, 2z_p]
    /// (arcsec) of a row; NaN where a point has no solution.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn evaluate(
        &self,
        common: &Common,
        physical: &Physical,
        inputs: &[f64],
        terms: &RowTerms,
        scratch: &mut LoadedScratch,
        curve: &mut Vec<f64>,
        outputs: &mut [f64],
    ) {
        curve.resize(common.points, 0.0);
        if self
            .curve(common, physical, inputs, terms, scratch, curve)
            .is_err()
        {
            outputs[..TE_OUTPUTS].fill(f64::NAN);
            return;
        }
        let n = common.points as f64;
        let quads = curve.as_chunks::<4>().0;
        let lanes = lane_stats(quads);
        let lo = lanes.lo.into_iter().fold(f64::INFINITY, f64::min);
        let hi = lanes.hi.into_iter().fold(f64::NEG_INFINITY, f64::max);
        let mean = ((lanes.sum[0] + lanes.sum[1]) + (lanes.sum[2] + lanes.sum[3])) / n;
        let squares = lane_squares(quads, mean);
        let var = ((squares[0] + squares[1]) + (squares[2] + squares[3])) / n;
        let orders = physical.order_amplitudes(curve);
        let to_arcsec = crate::ARCSEC_PER_RAD;
        outputs[0] = (hi - lo) * to_arcsec;
        outputs[1] = var.sqrt() * to_arcsec;
        outputs[2] = mean * to_arcsec;
        for (out, order) in outputs[3..TE_OUTPUTS].iter_mut().zip(orders) {
            *out = order * to_arcsec;
        }
    }

    /// The same reading at `points` points per revolution: its own table of the pins'
    /// places, the same torque, solver and nominal (for `rvtol curve`'s detail and spectrum,
    /// which need more points than the curve's N).
    pub(super) fn at_points(&self, points: usize) -> Loaded {
        Loaded {
            table: PinPhases::new(&self.stage, points),
            ..self.clone()
        }
    }

    /// The loaded transmission error of a row at the table's points, arcsec (None where a
    /// point has no solution).
    pub(super) fn curve_arcsec(
        &self,
        common: &Common,
        physical: &Physical,
        inputs: &[f64],
    ) -> Option<Vec<f64>> {
        let terms = physical.row_terms(common, inputs);
        let mut curve = vec![0.0; self.table.points];
        let mut scratch = LoadedScratch::default();
        self.curve(common, physical, inputs, &terms, &mut scratch, &mut curve)
            .ok()?;
        Some(
            curve
                .into_iter()
                .map(|v| v * crate::ARCSEC_PER_RAD)
                .collect(),
        )
    }
}

/// [`Loaded::pins`] from the geometry pin by pin (`exact_gap_at`): the reference of the
/// table.
#[cfg(test)]
fn exact_pins(
    common: &Common,
    physical: &Physical,
    inputs: &[f64],
    terms: &RowTerms,
    theta: f64,
    scratch: &mut LoadedScratch,
) -> [f64; 2] {
    let angles = common.angles_at(theta);
    let (offsets, _) = physical.crank_offsets(common, terms, angles);
    for d in 0..2 {
        let d_r = Physical::along(terms, d, angles[0], angles[1]);
        let start = common.cycloid_teeth as f64 * theta + d as f64 * PI;
        let (gaps, levers) = (&mut scratch.gaps[d], &mut scratch.levers[d]);
        gaps.clear();
        levers.clear();
        for pin in 0..common.pins {
            let phi = (start + 2.0 * PI * pin as f64 / common.pins as f64).rem_euclid(2.0 * PI);
            let (gap, lever) =
                physical.exact_gap_at(common, inputs, terms, d, pin, theta, d_r, phi.sin_cos());
            if lever.abs() > LEVER_FLOOR * common.eccentricity {
                gaps.push(gap);
                levers.push(lever);
            }
        }
        scratch.kept[d] = gaps.len();
    }
    offsets
}

#[cfg(test)]
mod tests;
