//! The reducer as one definition (teeth, pin circle, pins, eccentricity, the design
//! modification as generating amounts, cranks, disc face width, friction, rated torque),
//! its derived quantities (ratio i, λ, K1), and the fixed grid on which
//! `rv_lost_motion` looks at the two discs over one output revolution: M = q·z_p output
//! angles, the pin angles φ they produce, each with its factors (docs/models.md §14).
//!
//! Frames (those of `transmission_error`'s physical reading, docs/models.md §12.1): output
//! angle Θ; the eccentric of disc 1 points at χ = −z_p·Θ in the carrier (disc frame =
//! carrier frame: the disc translates against the carrier), that of disc 2 at χ + π; pin i
//! (0-based) sits at φ = 2π·i/z_p + z_c·Θ (+ π on disc 2) from its disc's eccentric.
//!
//! The grid. With Θ_k = 2π·k/M and M = q·z_p, φ = 2π·(q·i + z_c·k)/M + d·π takes only the
//! 2M values π·j/M, so every factor is tabulated once per j (the `Columns`), and z_p·Θ_k =
//! 2π·k/q takes q values.

use std::f64::consts::PI;

use crate::cycloid::CycloidStage;
use crate::preload::{slip_arm, LEVER_FLOOR};
use crate::{ModelError, ModelParams};
use rvtol_deviation::Shown;

/// Most cranks of a reducer.
pub(crate) const MAX_CRANKS: usize = 3;

/// The reducer, checked once.
#[derive(Debug, Clone)]
pub(crate) struct Reducer {
    pub stage: CycloidStage,
    /// r_rp, mm.
    pub pin_radius: f64,
    /// Design modification, generating amounts (mm): equidistant Δr_rp, shift Δr_p.
    pub equidistant: f64,
    pub shift: f64,
    /// i = 1 + (z2/z1)·z_p (000 Eq. 4).
    pub ratio: f64,
    /// λ = (z_c/z_p)·(1 − 1/i): a disc's turn against the pins at the output.
    pub lambda: f64,
    /// a0, the sun–planet centre distance = the crank circle radius a_w (the planets ride
    /// on the cranks), mm.
    pub center_distance: f64,
    /// r1, mm; α, rad; the sun mesh's axial place on the input shaft, mm.
    pub sun_pitch_radius: f64,
    pub pressure_angle: f64,
    pub sun_position: f64,
    /// m, 2 or 3.
    pub cranks: usize,
    /// L, mm.
    pub face_width: f64,
    /// r_m, the circle on which a cumulative pitch deviation is measured, mm.
    pub pitch_radius: f64,
    /// s/2, half the axial distance between the two eccentrics' (discs') mid-planes, mm:
    /// disc 1's plane at z = +s/2 from a crank's deviation reference, disc 2's at −s/2.
    pub half_spacing: f64,
}

impl Reducer {
    /// Reads the reducer's parameters (keys as in the module's `PARAMS`).
    pub fn from_params(params: &ModelParams) -> Result<Self, ModelError> {
        let sun_teeth = params.count("sun_teeth", None)? as f64;
        let planet_teeth = params.count("planet_teeth", None)? as f64;
        let stage = CycloidStage::from_params(params, crate::preload::MAX_PINS)?;
        let pin_radius = params.positive("pin_radius_mm", None)?;
        stage.check_pin_radius("pin_radius_mm", pin_radius)?;
        let equidistant = params.number("equidistant_modification_mm", None)?;
        let shift = params.number("shift_modification_mm", None)?;
        for (key, value) in [
            ("equidistant_modification_mm", equidistant),
            ("shift_modification_mm", shift),
        ] {
            if value.abs() >= 0.5 * pin_radius {
                return Err(ModelError::new(
                    key,
                    format!(
                        "a modification of {} mm is not a small correction of pins of radius {} mm",
                        Shown(value),
                        Shown(pin_radius)
                    ),
                ));
            }
        }
        let pressure_angle_deg = params.number("pressure_angle_deg", Some(20.0))?;
        if !(pressure_angle_deg > 0.0 && pressure_angle_deg < 90.0) {
            return Err(ModelError::new(
                "pressure_angle_deg",
                format!("must lie in (0, 90), got {}", Shown(pressure_angle_deg)),
            ));
        }
        let cranks = params.count("crank_count", Some(2.0))? as usize;
        if !(2..=MAX_CRANKS).contains(&cranks) {
            return Err(ModelError::new(
                "crank_count",
                format!("must be 2 or 3, got {cranks}"),
            ));
        }
        let pin_circle = stage.pin_circle_radius;
        let pitch_radius =
            params.positive("pitch_measuring_radius_mm", Some(pin_circle - pin_radius))?;
        let ratio = 1.0 + planet_teeth * stage.pins as f64 / sun_teeth;
        Ok(Reducer {
            lambda: stage.teeth as f64 / stage.pins as f64 * (1.0 - 1.0 / ratio),
            stage,
            pin_radius,
            equidistant,
            shift,
            ratio,
            center_distance: params.positive("center_distance_mm", None)?,
            sun_pitch_radius: params.positive("sun_pitch_radius_mm", None)?,
            pressure_angle: pressure_angle_deg.to_radians(),
            sun_position: params.number("sun_gear_axial_position_mm", Some(0.0))?,
            cranks,
            face_width: params.positive("disc_face_width_mm", None)?,
            pitch_radius,
            half_spacing: 0.5 * params.positive("crank_eccentric_spacing_mm", None)?,
        })
    }

    /// e·z_c, mm: the lever of the pitch point about the disc centre.
    pub fn pitch_lever(&self) -> f64 {
        self.stage.eccentricity * self.stage.teeth as f64
    }
}

/// A pin angle φ of the grid with its factors (docs/models.md §10, §14).
#[derive(Debug, Clone, Copy)]
struct Slot {
    /// l = e·z_c·sin φ/S, mm (signed: > 0 on the drive flank).
    pub lever: f64,
    /// Factors of the equidistant and shift amounts (003's standard form), of an outward
    /// pin displacement, of the disc's displacement along its eccentric, of a tangential
    /// pin displacement.
    pub equidistant: f64,
    pub shift: f64,
    pub radial: f64,
    pub eccentric: f64,
    pub tangential: f64,
    /// cos and sin of the pin's polar angle about the disc centre, from the eccentric.
    pub polar: (f64, f64),
    /// h, the arm of the contact's tangent about the disc centre (the pin's slip per radian
    /// of the disc's turn against the housing), mm.
    pub slip_arm: f64,
    /// The design modification's clearance g0, mm.
    pub design_gap: f64,
}

/// The output angles of the grid with what each needs.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    /// q, points per pin pitch (per turn of the cranks against the carrier); M = q·z_p.
    pub per_pin: usize,
    pub points: usize,
    /// z_p and z_c.
    pins: usize,
    teeth: usize,
    /// Per crank angle kq < q (z_p·Θ_k depends on k mod q only): (sin, cos) of z_p·Θ.
    pub turn: Vec<(f64, f64)>,
    /// Per crank angle kq and disc d (index 2·kq + d): the needle rows' lever, the largest
    /// shift of the window (disc angle, rad) per mm of the bore centres' free radius
    /// (docs/models.md §14.3).
    pub needle_lever: Vec<f64>,
    /// Per crank angle kq and disc d (index 2·kq + d): (sin, cos) of the direction across
    /// the disc's eccentric in the carrier.
    pub across: Vec<(f64, f64)>,
    /// (sin, cos) of each crank's place β_k on the crank circle.
    pub crank_angles: Vec<(f64, f64)>,
    /// The 2M slots as columns.
    pub columns: Columns,
    /// Per grid point k: where each disc's window sits among a row table's window ends,
    /// (2·kq + d)·z_p + start (`placement`), so that a point reads its ends without a
    /// division.
    pub ends_at: Vec<[u32; 2]>,
    /// Per window index (`ends_at`'s): the index of the same disc's window at the grid's
    /// previous point (k − 1, cyclic), where a search may start (windows.rs).
    pub previous: Vec<u32>,
    /// The instruction sets the row tables' folds may use (folds.rs).
    pub arch: pulp::Arch,
}

/// The 2M slots as columns grouped by residue: the slots of one grid point and disc are
/// j = r + 2q·m (m = 0..z_p) for one r = j mod 2q, so column entry r·z_p + m holds slot j,
/// and a point's pins read one contiguous run of z_p entries (rotated by a whole number of
/// pins). `inverse_lever` is 1/l, signed, and 0 where the lever is below the floor.
#[derive(Debug, Clone, Default)]
pub(crate) struct Columns {
    pub design_gap: Vec<f64>,
    pub equidistant: Vec<f64>,
    pub shift: Vec<f64>,
    pub radial: Vec<f64>,
    pub tangential: Vec<f64>,
    pub eccentric: Vec<f64>,
    pub lever: Vec<f64>,
    pub inverse_lever: Vec<f64>,
    pub polar_cos: Vec<f64>,
    pub polar_sin: Vec<f64>,
    pub slip_arm: Vec<f64>,
    /// Per residue r: the entries m with a positive lever (the drive flank, φ in (0, π))
    /// and those with a negative one, each one range (φ grows with m from below 2π/z_p).
    pub drive: Vec<std::ops::Range<usize>>,
    pub coast: Vec<std::ops::Range<usize>>,
}

/// The entries `range` of every column, each a slice of the range's length (a loop over
/// them indexes without checks, which the compiler then vectorises).
pub(crate) struct ColumnRun<'a> {
    pub design_gap: &'a [f64],
    pub equidistant: &'a [f64],
    pub shift: &'a [f64],
    pub radial: &'a [f64],
    pub tangential: &'a [f64],
    pub eccentric: &'a [f64],
    pub lever: &'a [f64],
    pub inverse_lever: &'a [f64],
    pub polar_cos: &'a [f64],
    pub polar_sin: &'a [f64],
}

impl Columns {
    /// The entries `range` of every column.
    pub fn run(&self, range: std::ops::Range<usize>) -> ColumnRun<'_> {
        ColumnRun {
            design_gap: &self.design_gap[range.clone()],
            equidistant: &self.equidistant[range.clone()],
            shift: &self.shift[range.clone()],
            radial: &self.radial[range.clone()],
            tangential: &self.tangential[range.clone()],
            eccentric: &self.eccentric[range.clone()],
            lever: &self.lever[range.clone()],
            inverse_lever: &self.inverse_lever[range.clone()],
            polar_cos: &self.polar_cos[range.clone()],
            polar_sin: &self.polar_sin[range],
        }
    }

    fn new(slots: &[Slot], per_pin: usize, pins: usize, floor: f64) -> Columns {
        let mut columns = Columns::default();
        for r in 0..2 * per_pin {
            let run = |positive: bool| {
                let inside = |m: usize| {
                    let lever = slots[r + 2 * per_pin * m].lever;
                    if positive {
                        lever > floor
                    } else {
                        lever < -floor
                    }
                };
                let first = (0..pins).find(|&m| inside(m)).unwrap_or(pins);
                let end = (first..pins).find(|&m| !inside(m)).unwrap_or(pins);
                debug_assert!((end..pins).all(|m| !inside(m)));
                first..end
            };
            columns.drive.push(run(true));
            columns.coast.push(run(false));
            for m in 0..pins {
                let s = &slots[r + 2 * per_pin * m];
                columns.design_gap.push(s.design_gap);
                columns.equidistant.push(s.equidistant);
                columns.shift.push(s.shift);
                columns.radial.push(s.radial);
                columns.tangential.push(s.tangential);
                columns.eccentric.push(s.eccentric);
                columns.lever.push(s.lever);
                columns.inverse_lever.push(if s.lever.abs() > floor {
                    1.0 / s.lever
                } else {
                    0.0
                });
                columns.polar_cos.push(s.polar.0);
                columns.polar_sin.push(s.polar.1);
                columns.slip_arm.push(s.slip_arm);
            }
        }
        columns
    }
}

impl Grid {
    /// The grid of `reducer` with q = `per_pin` points per pin pitch.
    pub fn new(reducer: &Reducer, per_pin: usize) -> Grid {
        let stage = &reducer.stage;
        let zp = stage.pins;
        let points = per_pin * zp;
        let slots: Vec<Slot> = (0..2 * points)
            .map(|j| slot(reducer, PI * j as f64 / points as f64))
            .collect();
        let crank_angles: Vec<(f64, f64)> = (0..reducer.cranks)
            .map(|k| (2.0 * PI * k as f64 / reducer.cranks as f64).sin_cos())
            .collect();
        let (mut needle_lever, mut across_all) = (Vec::new(), Vec::new());
        for kq in 0..per_pin {
            for d in 0..2 {
                // Disc d's eccentric at χ = −z_p·Θ (+π), its across direction χ + π/2.
                let across = -2.0 * PI * kq as f64 / per_pin as f64 + d as f64 * PI + 0.5 * PI;
                across_all.push(across.sin_cos());
                needle_lever.push(needle_lever_at(
                    across.sin_cos(),
                    &crank_angles,
                    reducer.center_distance,
                    reducer.pitch_lever(),
                ));
            }
        }
        let mut grid = Grid {
            per_pin,
            points,
            pins: zp,
            teeth: stage.teeth,
            turn: (0..per_pin)
                .map(|kq| (2.0 * PI * kq as f64 / per_pin as f64).sin_cos())
                .collect(),
            needle_lever,
            across: across_all,
            crank_angles,
            columns: Columns::new(&slots, per_pin, zp, LEVER_FLOOR * stage.eccentricity),
            ends_at: Vec::new(),
            previous: Vec::new(),
            arch: pulp::Arch::new(),
        };
        grid.ends_at = (0..points)
            .map(|k| {
                [0, 1].map(|d| {
                    let (_, start) = grid.placement(k, d);
                    // At most 2·64·200 entries: the index fits u32.
                    ((2 * (k % per_pin) + d) * zp + start) as u32
                })
            })
            .collect();
        grid.previous = vec![0; 2 * points];
        for k in 0..points {
            let before = grid.ends_at[(k + points - 1) % points];
            for (d, &at) in grid.ends_at[k].iter().enumerate() {
                grid.previous[at as usize] = before[d];
            }
        }
        grid
    }

    /// Where disc d's pins sit at grid point k: the first column entry of their residue
    /// (r·z_p) and the rotation `start`: pin i meets entry (start + i) mod z_p. Pin i is at
    /// slot j = 2q·i + c with c = 2·z_c·k + d·M (mod 2M), so r = c mod 2q, start = c div 2q.
    #[inline]
    pub fn placement(&self, k: usize, d: usize) -> (usize, usize) {
        let q = self.per_pin;
        let c = (2 * self.teeth * k + d * self.points) % (2 * self.points);
        ((c % (2 * q)) * self.pins, c / (2 * q))
    }
}

/// The slot at φ.
fn slot(reducer: &Reducer, phi: f64) -> Slot {
    let stage = &reducer.stage;
    let (sin, cos) = phi.sin_cos();
    let f = stage.pin_factors_at(sin, cos);
    let (r_p, e) = (stage.pin_circle_radius, stage.eccentricity);
    let polar = (r_p * sin).atan2(r_p * cos - e).sin_cos();
    Slot {
        lever: f.lever,
        equidistant: f.equidistant,
        shift: f.shift,
        radial: f.radial,
        eccentric: f.eccentric,
        tangential: f.tangential,
        polar: (polar.1, polar.0),
        slip_arm: slip_arm(stage, reducer.pin_radius, cos),
        design_gap: reducer.equidistant * f.equidistant + reducer.shift * f.shift,
    }
}

/// The needle rows' lever for one disc whose across-the-eccentric direction is `across`
/// (sin, cos) in the carrier: with every bore centre free to move within a circle of radius
/// 1 about its eccentric's centre, the largest t·ŷ/(e·z_c) + ρ over the disc's translations
/// t and turns ρ against the carrier that keep every bore within its circle (bore k at a_w
/// on the crank circle moves by t + ρ·a_w·ĵ_k, ĵ_k its tangent). A translation across the
/// eccentric turns the window like a turn of t/(e·z_c) (every pin normal passes through the
/// pitch point, e·z_c from the disc centre), a turn against the carrier like itself.
/// Concave in u = ρ·a_w: golden-section search, with the largest ŷ·t over the intersection
/// of the circles (centres −u·ĵ_k) from its candidate points.
pub(crate) fn needle_lever_at(
    across: (f64, f64),
    cranks: &[(f64, f64)],
    crank_radius: f64,
    pitch_lever: f64,
) -> f64 {
    let y = (across.1, across.0);
    let value = |u: f64| {
        let centres: Vec<(f64, f64)> = cranks.iter().map(|&(sb, cb)| (u * sb, -u * cb)).collect();
        largest_along(y, &centres) / pitch_lever + u / crank_radius
    };
    golden_max(value, (-1.0, 1.0), 200)
}

/// The needle rows' slack of one disc (disc angle, rad) when crank k's bore centre is free
/// within its own radius ρ_k ≥ 0 (mm) of its eccentric's centre: the largest
/// t·ŷ/(e·z_c) + ρ over the disc's translations t and turns ρ against the carrier that keep
/// every bore within its circle ([`needle_lever_at`] is this with every ρ_k = 1; with equal
/// radii ρ the slack is ρ times that lever, docs/models.md §14.3).
pub(crate) fn needle_slack(
    across: (f64, f64),
    cranks: &[(f64, f64)],
    radii: &[f64],
    crank_radius: f64,
    pitch_lever: f64,
) -> f64 {
    if cranks.len() == 2 {
        two_crank_slack(across, (radii[0], radii[1]), crank_radius, pitch_lever)
    } else {
        any_crank_slack(across, cranks, radii, crank_radius, pitch_lever)
    }
}

/// Two cranks at β = 0 and π (ĵ_1 = −ĵ_2 = ŷ_carrier): with p_k = t + u·ĵ_k the bores'
/// displacements, p_1 − p_2 = 2u·ĵ_1 makes both share their component X across ĵ, and
/// t·ŷ/P + u/a_w = y_x·X/P + c_1·p_1,y + c_2·p_2,y with c_{1,2} = y_y/(2P) ± 1/(2a_w)
/// (P = e·z_c, y the across direction). At a given X each p_k,y takes its circle's end
/// ±√(ρ_k² − X²) of the sign of c_k, so the slack is the maximum over |X| ≤ min ρ_k of
/// f(X) = y_x·X/P + |c_1|·√(ρ_1² − X²) + |c_2|·√(ρ_2² − X²), concave: its derivative
/// falls from +∞ to −∞ and is bisected to its zero (64 steps, 2⁻⁶⁴ of the radius).
fn two_crank_slack(
    across: (f64, f64),
    (r1, r2): (f64, f64),
    crank_radius: f64,
    pitch_lever: f64,
) -> f64 {
    let (y_x, y_y) = (across.1, across.0);
    let (r1, r2) = (r1.max(0.0), r2.max(0.0));
    let c1 = (0.5 * y_y / pitch_lever + 0.5 / crank_radius).abs();
    let c2 = (0.5 * y_y / pitch_lever - 0.5 / crank_radius).abs();
    let f = |x: f64| {
        y_x * x / pitch_lever
            + c1 * (r1 * r1 - x * x).max(0.0).sqrt()
            + c2 * (r2 * r2 - x * x).max(0.0).sqrt()
    };
    let reach = r1.min(r2);
    if reach == 0.0 {
        return f(0.0);
    }
    let slope = |x: f64| {
        y_x / pitch_lever - c1 * x / (r1 * r1 - x * x).sqrt() - c2 * x / (r2 * r2 - x * x).sqrt()
    };
    let (mut lo, mut hi) = (-reach, reach);
    for _ in 0..64 {
        let mid = 0.5 * (lo + hi);
        if slope(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    f(0.5 * (lo + hi))
}

/// Any crank count: golden-section search over u = ρ·a_w of the largest t·ŷ over the
/// circles' intersection (concave in u; −∞ where the circles do not meet, an interval
/// about u = 0, which is always feasible). 90 steps: 0.618⁹⁰ of the interval, below
/// 1e-18 of a radius.
pub(crate) fn any_crank_slack(
    across: (f64, f64),
    cranks: &[(f64, f64)],
    radii: &[f64],
    crank_radius: f64,
    pitch_lever: f64,
) -> f64 {
    let y = (across.1, across.0);
    let m = cranks.len().min(MAX_CRANKS);
    let value = |u: f64| {
        // On the stack: the search evaluates this 90 times per slack, per sample.
        let mut circles = [((0.0, 0.0), 0.0); MAX_CRANKS];
        for (circle, (&(sb, cb), &r)) in circles.iter_mut().zip(cranks.iter().zip(radii)) {
            *circle = ((u * sb, -u * cb), r.max(0.0));
        }
        largest_along_circles(y, &circles[..m]) / pitch_lever + u / crank_radius
    };
    // |u|·|ĵ_j − ĵ_k| ≤ ρ_j + ρ_k for any two cranks, and |ĵ_j − ĵ_k| ≥ √3 for m ≤ 3.
    let reach = 2.0 * radii.iter().fold(0.0_f64, |a, &r| a.max(r)) / 3.0_f64.sqrt();
    golden_max(value, (-reach, reach), 90).max(value(0.0))
}

/// The largest value of a concave `value` over (lo, hi) by golden-section search in
/// `steps` steps; where `value` is −∞ (infeasible) outside an interval that holds 0, a step
/// whose two points are both infeasible moves towards 0.
fn golden_max(value: impl Fn(f64) -> f64, (mut lo, mut hi): (f64, f64), steps: u32) -> f64 {
    let golden = 0.5 * (5.0_f64.sqrt() - 1.0);
    let (mut a, mut b) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
    let (mut fa, mut fb) = (value(a), value(b));
    for _ in 0..steps {
        if fa == f64::NEG_INFINITY && fb == f64::NEG_INFINITY {
            // The feasible interval holds 0 and neither point.
            if b <= 0.0 {
                lo = b;
            } else if a >= 0.0 {
                hi = a;
            } else {
                (lo, hi) = (a, b);
            }
            (a, b) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
            (fa, fb) = (value(a), value(b));
        } else if fa < fb {
            lo = a;
            (a, fa) = (b, fb);
            b = lo + golden * (hi - lo);
            fb = value(b);
        } else {
            hi = b;
            (b, fb) = (a, fa);
            a = hi - golden * (hi - lo);
            fa = value(a);
        }
    }
    fa.max(fb)
}

/// The largest y·t over the intersection of circles (centre, radius) (−∞ when empty):
/// a circle's own extreme point inside every other circle, or a point where two cross.
fn largest_along_circles(y: (f64, f64), circles: &[((f64, f64), f64)]) -> f64 {
    let scale = circles.iter().fold(0.0_f64, |a, c| a.max(c.1));
    let inside = |p: (f64, f64)| {
        circles.iter().all(|&(c, r)| {
            let (dx, dy) = (p.0 - c.0, p.1 - c.1);
            dx * dx + dy * dy <= (r + 1e-12 * scale) * (r + 1e-12 * scale)
        })
    };
    let mut best = f64::NEG_INFINITY;
    let mut consider = |p: (f64, f64)| {
        if inside(p) {
            best = best.max(y.0 * p.0 + y.1 * p.1);
        }
    };
    for (i, &(a, ra)) in circles.iter().enumerate() {
        consider((a.0 + ra * y.0, a.1 + ra * y.1));
        for &(b, rb) in &circles[i + 1..] {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let gap = dx.hypot(dy);
            if gap > ra + rb || gap < (ra - rb).abs() || gap == 0.0 {
                continue;
            }
            // The chord: at `along` from a towards b, half-length `half`.
            let along = (ra * ra - rb * rb + gap * gap) / (2.0 * gap);
            let half = (ra * ra - along * along).max(0.0).sqrt();
            let mid = (a.0 + along * dx / gap, a.1 + along * dy / gap);
            let normal = (-dy / gap, dx / gap);
            consider((mid.0 + half * normal.0, mid.1 + half * normal.1));
            consider((mid.0 - half * normal.0, mid.1 - half * normal.1));
        }
    }
    best
}

/// The largest y·t over the intersection of unit circles about `centres` (−∞ when empty):
/// the optimum is a circle's own extreme point inside every other circle, or a point where
/// two circles cross.
fn largest_along(y: (f64, f64), centres: &[(f64, f64)]) -> f64 {
    let inside = |p: (f64, f64)| {
        centres
            .iter()
            .all(|c| (p.0 - c.0).hypot(p.1 - c.1) <= 1.0 + 1e-12)
    };
    let mut best = f64::NEG_INFINITY;
    let mut consider = |p: (f64, f64)| {
        if inside(p) {
            best = best.max(y.0 * p.0 + y.1 * p.1);
        }
    };
    for (i, a) in centres.iter().enumerate() {
        consider((a.0 + y.0, a.1 + y.1));
        for b in &centres[i + 1..] {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let gap = dx.hypot(dy);
            if gap > 2.0 || gap == 0.0 {
                continue;
            }
            let half = (1.0 - 0.25 * gap * gap).max(0.0).sqrt();
            let mid = (a.0 + 0.5 * dx, a.1 + 0.5 * dy);
            let normal = (-dy / gap, dx / gap);
            consider((mid.0 + half * normal.0, mid.1 + half * normal.1));
            consider((mid.0 - half * normal.0, mid.1 - half * normal.1));
        }
    }
    best
}
