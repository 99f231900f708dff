//! What the transmission error's readings share: [`Common`], the model's geometry from its
//! parameters (teeth, eccentricity, cranks, the involute stage, the divisor to the output),
//! the curve's points and their groups (the points that see the same pin slots), the FFT
//! and the inputs and outputs; the pin-slot table form both readings tabulate their
//! clearances in (document 002's one table, the physical reading's one per flank), and the
//! vectorised minimum scans over its columns. It names no other module of the model.

use crate::spectrum::RealFft;
use crate::{InputSpec, OutputSpec};

/// Largest crank count.
pub(super) const MAX_CRANKS: usize = 6;

/// What every reading of the model shares: the design geometry read from the parameters,
/// the curve's points in their groups, the FFT of N points, and the inputs and outputs of
/// the reading asked for.
#[derive(Debug, Clone)]
pub(super) struct Common {
    /// z_s.
    pub(super) sun_teeth: f64,
    /// z_pl.
    pub(super) planet_teeth: f64,
    /// z_p.
    pub(super) pins: usize,
    /// z_c.
    pub(super) cycloid_teeth: usize,
    /// a, mm.
    pub(super) eccentricity: f64,
    /// m.
    pub(super) cranks: usize,
    /// N, points of the curve per output revolution.
    pub(super) points: usize,
    /// r2·cos α, mm.
    pub(super) base_radius: f64,
    /// sin α, cos α.
    pub(super) pressure: (f64, f64),
    /// Divisor from the crank rotation to the output.
    pub(super) divisor: f64,
    /// Whether the inputs hold per-pin position errors.
    pub(super) per_pin: bool,
    /// Whether the inputs hold per-tooth-space profile errors.
    pub(super) per_tooth: bool,
    /// The curve points, grouped (see [`Group`]).
    pub(super) curve_points: Vec<Point>,
    pub(super) groups: Vec<Group>,
    pub(super) fft: RealFft,
    pub(super) inputs: Vec<InputSpec>,
    pub(super) outputs: Vec<OutputSpec>,
}

impl Common {
    /// Overall ratio i = 1 + (z_pl/z_s)·z_p (validation.md 002: 121 for the RV40E).
    pub(super) fn ratio(&self) -> f64 {
        1.0 + self.planet_teeth / self.sun_teeth * self.pins as f64
    }

    /// Semi-amplitudes of orders 0..N/2 of a curve (order 0: the mean), arcsec.
    pub(super) fn spectrum(&self, curve: &[f64]) -> Vec<f64> {
        let mut work = vec![(0.0, 0.0); self.points / 2];
        self.fft.transform(curve, &mut work);
        let mut amplitudes: Vec<f64> = (0..=self.points / 2)
            .map(|k| self.fft.amplitude(&work, k))
            .collect();
        amplitudes[0] = self.fft.bin(&work, 0).0 / self.points as f64;
        amplitudes
    }

    /// [sin, cos] of z_p·Θ and of (i − 1)·Θ: the crank's and the sun's angles at Θ.
    pub(super) fn angles_at(&self, theta: f64) -> [f64; 4] {
        let (s, c) = (self.pins as f64 * theta).sin_cos();
        let (ss, cs) = ((self.ratio() - 1.0) * theta).sin_cos();
        [s, c, ss, cs]
    }
}

/// The pin slots of every phase of the curve, as columns (structure of arrays) in blocks of
/// `width` entries per phase: entry e of phase p is pin slot s = e, at φ = 2π(s + p·g/N)/z_p
/// from the eccentric; pin i is in slot (i − 1 + k_j) mod z_p at point j. Slots whose lever
/// is not positive, and slots past the last pin (3 pins in 4 slots), are padding
/// (`blocked` = +∞, every factor 0). Each clearance factor is
/// stored divided by the lever l, so that a row's clearance ratio g/l is a sum of products.
/// (The physical reading builds its own tables of this form, one per flank, in
/// `two_discs`: there the drive flank is the pins with l < 0, their factors over |l|.)
#[derive(Debug, Clone, Default)]
pub(super) struct PinTable {
    /// Entries per phase: the ⌈z_p/2⌉ slots that can have a positive lever, rounded up to
    /// a multiple of 4 (the chunk of the vectorised scans).
    pub(super) width: usize,
    /// 0 for a pin with a positive lever, +∞ for padding.
    pub(super) blocked: Vec<f64>,
    /// 1/l, 1/mm.
    pub(super) inverse_lever: Vec<f64>,
    /// (1 − sin φ/S)/l: factor of Δr_rp.
    pub(super) equidistant: Vec<f64>,
    /// −(1 − K1·cos φ − √(1 − K1²)·sin φ)/(S·l): factor of Δr_p.
    pub(super) shift: Vec<f64>,
    /// (K1 − cos φ)/(S·l): factor of a disc displacement along the eccentric.
    pub(super) eccentric: Vec<f64>,
    /// (1 − K1·cos φ)/(S·l): factor of a radial pin displacement.
    pub(super) radial: Vec<f64>,
    /// K1·sin φ/(S·l): factor of a tangential pin displacement.
    pub(super) tangential: Vec<f64>,
    /// Tooth space in contact when the eccentric has turned no whole pin pitch (k_j = 0):
    /// round(z_c·λ/2π − phase fraction) mod z_c, λ the pin's polar angle about the disc
    /// centre from the eccentric; at point j it is this minus k_j (mod z_c).
    pub(super) tooth: Vec<u32>,
}

impl PinTable {
    /// An entry that no pin fills or that has no lever on this flank: blocked (+∞), every
    /// factor 0.
    pub(super) fn push_padding(&mut self) {
        self.blocked.push(f64::INFINITY);
        for column in [
            &mut self.inverse_lever,
            &mut self.equidistant,
            &mut self.shift,
            &mut self.eccentric,
            &mut self.radial,
            &mut self.tangential,
        ] {
            column.push(0.0);
        }
        self.tooth.push(0);
    }
}

/// Per curve point: the angles and indices of point j.
#[derive(Debug, Clone, Copy)]
pub(super) struct Point {
    /// (sin, cos) of Θ.
    pub(super) output: (f64, f64),
    /// (sin, cos) of z_p·Θ (crank against carrier), from z_p·j reduced modulo N, so that
    /// the points of a group have the same bits.
    pub(super) crank: (f64, f64),
    /// (sin, cos) of (i − 1)·Θ (sun against carrier).
    pub(super) sun: (f64, f64),
    /// Whole pin pitches the eccentric has turned, k_j, modulo z_p.
    pub(super) pin_shift: u32,
    /// k_j modulo z_c.
    pub(super) tooth_shift: u32,
    /// Its index j on the curve.
    pub(super) index: u32,
}

/// Points of the curve that see the same pin slots (the same fractional pin pitch), the
/// same disc displacement along the eccentric (the same z_p·Θ modulo 2π) and the same tooth
/// spaces in those slots (the same k_j modulo z_c): they differ only in which pin sits in
/// each slot. For the RV40E (N = 4096, z_c·z_p = 1560) the 4096 points form 512 groups of 8.
#[derive(Debug, Clone, Copy)]
pub(super) struct Group {
    /// Block of the pin table.
    pub(super) phase: u32,
    /// Range of its points in `curve_points`.
    pub(super) start: u32,
    pub(super) end: u32,
}

pub(super) fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The first `chunks` quadruples of a column.
#[inline(always)]
pub(super) fn quads(column: &[f64], chunks: usize) -> &[[f64; 4]] {
    &column.as_chunks::<4>().0[..chunks]
}

/// min over k of head + pin_radial·radial + pin_tangential·tangential, over columns of
/// equal length, a multiple of 4. Four independent minima in fixed-size chunks let the loop
/// vectorise; `<` selects compile to plain min instructions.
#[inline(always)]
pub(super) fn smallest_ratio(
    head: &[f64],
    radial: &[f64],
    tangential: &[f64],
    pin_radial: &[f64],
    pin_tangential: &[f64],
) -> f64 {
    let count = head.len() / 4;
    let (head, radial, tangential) = (
        quads(head, count),
        quads(radial, count),
        quads(tangential, count),
    );
    let (pin_radial, pin_tangential) = (quads(pin_radial, count), quads(pin_tangential, count));
    let mut lanes = [f64::INFINITY; 4];
    for c in 0..count {
        for lane in 0..4 {
            let v = head[c][lane]
                + pin_radial[c][lane] * radial[c][lane]
                + pin_tangential[c][lane] * tangential[c][lane];
            lanes[lane] = if v < lanes[lane] { v } else { lanes[lane] };
        }
    }
    smallest_lane(lanes)
}

/// The smallest value of a column whose length is a multiple of 4, in four lanes (the
/// pin-free form of [`smallest_ratio`]).
#[inline(always)]
pub(super) fn smallest(column: &[f64]) -> f64 {
    let mut lanes = [f64::INFINITY; 4];
    for quad in column.as_chunks::<4>().0 {
        for lane in 0..4 {
            lanes[lane] = if quad[lane] < lanes[lane] {
                quad[lane]
            } else {
                lanes[lane]
            };
        }
    }
    smallest_lane(lanes)
}

/// The smallest of four lanes, by `<` selects (plain min instructions; a NaN lane is
/// passed over, as in the lanes themselves).
#[inline(always)]
pub(super) fn smallest_lane(lanes: [f64; 4]) -> f64 {
    let select = |a: f64, b: f64| if b < a { b } else { a };
    select(select(lanes[0], lanes[1]), select(lanes[2], lanes[3]))
}
