//! The clearance windows of the two discs, pin by pin, at the grid's output angles
//! (docs/models.md §14.2–14.4).
//!
//! Per disc d at output angle Θ (lengths mm, angles rad):
//! ```text
//! gap of pin i   g_i = Δr_rp·f_e + Δr_p·f_s                      design modification (003)
//!                    + δΔr_rp·f_e + δΔr_p·f_s + δ_n,d               modification errors
//!                    + (δr_p + δr_i)·f_r + δt_i·f_t − δr_rp − δρ_i   pin circle, pin i, radii
//!                    + δJ/2 + T_d,x·f_x − l_i·ε_d(ϑ_i)              groove, disc shift, pitch
//! disc shift     T_d = mean_k q_kd + σ_d·R(z_p·Θ)·(mean_k B_kd + r_d)  (eccentric frame)
//! four-bar turn  ρ_d = Σ_k t_k·(q_kd + R(…)·B_kd)/(m·a_w)
//! crank offset   C_d = −T_d,y/(e·z_c) − ρ_d
//! pitch          ε_d(ϑ) = (F_p,d/2)·cos(ϑ − ϕ_p,d)/r_m,  ϑ_i = polar_i − z_p·Θ + d·π
//! window         [λ·(C_d − K_d − h_d·u/2), λ·(C_d + L_d + h_d·u/2)]
//!                L_d = min_{l_i>0} g_i/l_i,  K_d = min_{l_i<0} g_i/|l_i|
//!                (the output turned counter-clockwise by δθ with the input locked turns
//!                the disc counter-clockwise past its mesh by δθ/λ, which closes the gaps
//!                of the pins with l_i > 0: they bound the upper end; docs/models.md §14.2)
//! output window  the intersection over d; its width W(Θ) (negative: the flanks overlap)
//! ```
//! with f_e … f_t the pin factors of `cycloid.rs`, q_kd the eccentric error (along,
//! across), B_kd = R(β_k)·(b_r + z_d·τ_t, b_t − z_d·τ_r) crank k's axis in the carrier at
//! disc d's plane z_d = ±s/2 (bore position b, tilt τ; 001 Eq. 7), r_d disc d's runout
//! vector (half the radial runout F_r,d at its phase), u the needle rows' radial internal
//! clearance (the bore centre moves within u/2; crank k's within (u + δu_k)/2) and h_d the
//! needle lever of `geometry.rs` (`needle_slack` when the cranks' clearances differ).
//!
//! Every pin of both discs counts at every point (a pin far from the pitch point sets the
//! window when its own error is large enough). Two paths compute the same windows:
//! [`disc_window`], every gap in full (the reference, and the public `disc_windows`), and
//! [`RowTable`], the model's: a row reduced once to its crank angles' runs, each run folded
//! over all its z_p rotations at once (folds.rs), so that a point's window costs one
//! subtraction, one product and one comparison per pin in packed lanes (equal to 1e-15,
//! tested).

use super::folds::{fold_flank, Flank, Turned};
use super::geometry::{needle_slack, Grid, Reducer, MAX_CRANKS};
use super::layout::{Layout, ECCENTRICS};
use crate::chains::{in_chains, total, CHAINS};

/// What a row contributes, reduced once per row.
#[derive(Debug, Clone, Default)]
pub(crate) struct RowTerms {
    /// δΔr_rp, δΔr_p, δr_p.
    pub equidistant_error: f64,
    pub shift_error: f64,
    pub pin_circle_error: f64,
    /// Per disc: the gap every pin of the disc shares (−δr_rp + δJ/2 + δ_n,d), mm.
    pub common: [f64; 2],
    /// Per disc: the mean eccentric error (along, across), eccentric frame.
    pub eccentric: [(f64, f64); 2],
    /// Per disc: mean crank axis plus runout, carrier frame.
    pub carried: [(f64, f64); 2],
    /// Per disc: Σ_k t_k·R(−z_pΘ)·q_kd = p1·cos z_pΘ + p2·sin z_pΘ, and Σ_k t_k·B_kd.
    pub p1: [f64; 2],
    pub p2: [f64; 2],
    pub rho_const: [f64; 2],
    /// Per disc: (F_p/2)/r_m·(cos ϕ_p, sin ϕ_p), rad.
    pub pitch: [(f64, f64); 2],
    /// u/2, the bore centres' free radius, mm (0 for an interference fit, u < 0).
    pub needle_radius: f64,
    /// Per crank: (u + δu_k)/2, its bore centre's free radius, mm (≥ 0); `needle_even`
    /// when every crank has u/2.
    pub needle_radii: [f64; MAX_CRANKS],
    pub needle_even: bool,
}

/// One disc's window at one output angle, disc angles (rad) before the factor λ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DiscWindow {
    /// C_d.
    pub offset: f64,
    /// L_d and K_d.
    pub lag: f64,
    pub lead: f64,
    /// h_d·u/2.
    pub slack: f64,
}

impl DiscWindow {
    /// Lower and upper end at the output, rad: the l < 0 pins bound the lower end, the
    /// l > 0 pins the upper (rigid: negative width where the disc's own flanks overlap).
    pub fn ends(&self, lambda: f64) -> (f64, f64) {
        (
            lambda * (self.offset - self.lead - self.slack),
            lambda * (self.offset + self.lag + self.slack),
        )
    }

    /// The window at rest, rad at the output: the rigid one where the disc has play; where
    /// its own flanks overlap, its slack about its own balance y0, the root of
    /// Σ max(0, l·y − g)·l over its pins `pins` (g − l·ε, l), found here by plain
    /// bisection (the row table's fast path finds it by bracketed Newton steps on every
    /// rotation of a run at once, `OwnBalances`: this is its independent check).
    pub fn at_rest(&self, lambda: f64, pins: &[(f64, f64)]) -> (f64, f64) {
        if self.lag + self.lead >= 0.0 {
            return self.ends(lambda);
        }
        let moment = |y: f64| -> f64 { pins.iter().map(|(g, l)| (l * y - g).max(0.0) * l).sum() };
        let (mut lo, mut hi) = (self.lag, -self.lead);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if moment(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let rest = 0.5 * (lo + hi);
        (
            lambda * (self.offset + rest - self.slack),
            lambda * (self.offset + rest + self.slack),
        )
    }
}

/// Reduces a row (finite inputs) to its terms.
pub(crate) fn row_terms(reducer: &Reducer, grid: &Grid, layout: &Layout, x: &[f64]) -> RowTerms {
    let m = reducer.cranks;
    let mut terms = RowTerms {
        equidistant_error: x[layout.equidistant_error],
        shift_error: x[layout.shift_error],
        pin_circle_error: x[layout.pin_circle_error],
        needle_radius: 0.5 * x[layout.needle_clearance].max(0.0),
        needle_even: true,
        ..RowTerms::default()
    };
    let mean = 1.0 / m as f64;
    for d in 0..2 {
        let disc = layout.disc(d);
        let (runout, runout_phase) = (0.5 * x[disc + 1], x[disc + 2]);
        let (pitch, pitch_phase) = (0.5 * x[disc + 3] / reducer.pitch_radius, x[disc + 4]);
        terms.common[d] =
            -x[layout.pin_radius_error] + 0.5 * x[layout.pin_hole_clearance] + x[disc];
        let (sr, cr) = runout_phase.sin_cos();
        terms.carried[d] = (runout * cr, runout * sr);
        let (sp, cp) = pitch_phase.sin_cos();
        terms.pitch[d] = (pitch * cp, pitch * sp);
    }
    for (k, &(sb, cb)) in grid.crank_angles.iter().enumerate() {
        let crank = layout.crank(k);
        // Its inputs in layout.rs's PER_CRANK order: axis, tilt, needle clearance deviation.
        let [b_r, b_t, tau_r, tau_t, deviation] = [0, 1, 2, 3, 4].map(|i| x[crank + i]);
        terms.needle_radii[k] = 0.5 * (x[layout.needle_clearance] + deviation).max(0.0);
        terms.needle_even &= deviation == 0.0;
        for d in 0..2 {
            // The axis at disc d's plane z_d = ±s/2 (001 Eq. 7: θ × p).
            let z = if d == 0 {
                reducer.half_spacing
            } else {
                -reducer.half_spacing
            };
            let (r, t) = (b_r + z * tau_t, b_t - z * tau_r);
            let bore = (r * cb - t * sb, r * sb + t * cb);
            terms.carried[d].0 += bore.0 * mean;
            terms.carried[d].1 += bore.1 * mean;
            terms.rho_const[d] += t;
            let (qx, qy) = (
                x[crank + ECCENTRICS + 2 * d],
                x[crank + ECCENTRICS + 1 + 2 * d],
            );
            terms.eccentric[d].0 += qx * mean;
            terms.eccentric[d].1 += qy * mean;
            terms.p1[d] += -sb * qx + cb * qy;
            terms.p2[d] += -sb * qy - cb * qx;
        }
    }
    terms
}

/// The needle rows' slack h_d·u/2 of disc d at crank angle kq (disc angle, rad): the
/// grid's lever times u/2 when every crank has the same clearance, else the slack of the
/// cranks' own radii (geometry.rs `needle_slack`).
pub(crate) fn needle_slack_of(
    reducer: &Reducer,
    grid: &Grid,
    terms: &RowTerms,
    kq: usize,
    d: usize,
) -> f64 {
    if terms.needle_even {
        grid.needle_lever[2 * kq + d] * terms.needle_radius
    } else {
        needle_slack(
            grid.across[2 * kq + d],
            &grid.crank_angles,
            &terms.needle_radii[..reducer.cranks],
            reducer.center_distance,
            reducer.pitch_lever(),
        )
    }
}

/// C_d and T_d,x of disc d at a point whose z_p·Θ has (sin, cos) `turn`.
pub(crate) fn offset_and_shift(
    reducer: &Reducer,
    terms: &RowTerms,
    d: usize,
    (s, c): (f64, f64),
) -> (f64, f64) {
    let sigma = if d == 0 { 1.0 } else { -1.0 };
    let (vx, vy) = terms.carried[d];
    let along = terms.eccentric[d].0 + sigma * (vx * c - vy * s);
    let across = terms.eccentric[d].1 + sigma * (vx * s + vy * c);
    let rho = (sigma * (terms.p1[d] * c + terms.p2[d] * s) + terms.rho_const[d])
        / (reducer.cranks as f64 * reducer.center_distance);
    (-across / reducer.pitch_lever() - rho, along)
}

/// The window of disc d at grid point k: every pin, read from the grid's columns (one
/// contiguous run of z_p entries, in two pieces where the pins wrap round), in a loop
/// without branches that the compiler vectorises. For each pin, t = g_i/l_i − ε_i (signed
/// l): L_d = min t over l_i > 0, K_d = −max t over l_i < 0.
pub(crate) fn disc_window(
    reducer: &Reducer,
    grid: &Grid,
    layout: &Layout,
    terms: &RowTerms,
    x: &[f64],
    k: usize,
    d: usize,
) -> DiscWindow {
    let kq = k % grid.per_pin;
    let turn = grid.turn[kq];
    let (offset, shift) = offset_and_shift(reducer, terms, d, turn);
    let pitch = turned_pitch(terms, d, turn);
    let pins = reducer.stage.pins;
    let (base, start) = grid.placement(k, d);
    let coefficients = Coefficients {
        equidistant: terms.equidistant_error,
        shift: terms.shift_error,
        pin_circle: terms.pin_circle_error,
        common: terms.common[d],
        along: shift,
        pitch,
    };
    let pin_columns = (
        &x[layout.pins..layout.pins + pins],
        &x[layout.pins + pins..layout.pins + 2 * pins],
        &x[layout.pins + 2 * pins..layout.pins + 3 * pins],
    );
    // Pins [0, z_p − start) sit at m = start.., pins [z_p − start, z_p) at m = 0...
    let split = pins - start;
    let (lag_a, coast_a) = scan(
        &grid.columns,
        base + start..base + pins,
        (
            &pin_columns.0[..split],
            &pin_columns.1[..split],
            &pin_columns.2[..split],
        ),
        &coefficients,
    );
    let (lag_b, coast_b) = scan(
        &grid.columns,
        base..base + start,
        (
            &pin_columns.0[split..],
            &pin_columns.1[split..],
            &pin_columns.2[split..],
        ),
        &coefficients,
    );
    DiscWindow {
        offset,
        lag: lag_a.min(lag_b),
        lead: -coast_a.max(coast_b),
        slack: needle_slack_of(reducer, grid, terms, kq, d),
    }
}

/// Every pin of disc d at grid point k computed in full, in pin order: (g − l·ε, l), the
/// gap with the pitch's turn folded in and the lever, the pins at φ = 0 or π (no lever)
/// left out; for [`DiscWindow::at_rest`].
pub(crate) fn direct_pins(
    reducer: &Reducer,
    grid: &Grid,
    layout: &Layout,
    terms: &RowTerms,
    x: &[f64],
    (k, d): (usize, usize),
) -> Vec<(f64, f64)> {
    let turn = grid.turn[k % grid.per_pin];
    let (_, along) = offset_and_shift(reducer, terms, d, turn);
    let (pa, pb) = turned_pitch(terms, d, turn);
    let pins = reducer.stage.pins;
    let (base, start) = grid.placement(k, d);
    let columns = &grid.columns;
    let pin = |block: usize, i: usize| x[layout.pins + block * pins + i];
    (0..pins)
        .filter_map(|i| {
            let j = base + (start + i) % pins;
            let lever = columns.lever[j];
            let gap = columns.design_gap[j]
                + terms.equidistant_error * columns.equidistant[j]
                + terms.shift_error * columns.shift[j]
                + (terms.pin_circle_error + pin(0, i)) * columns.radial[j]
                + pin(1, i) * columns.tangential[j]
                + along * columns.eccentric[j]
                + (terms.common[d] - pin(2, i));
            let pitch = pa * columns.polar_cos[j] + pb * columns.polar_sin[j];
            (columns.inverse_lever[j] != 0.0).then_some((gap - lever * pitch, lever))
        })
        .collect()
}

/// What a point and disc add to every pin's gap.
struct Coefficients {
    equidistant: f64,
    shift: f64,
    pin_circle: f64,
    common: f64,
    along: f64,
    pitch: (f64, f64),
}

/// min t over the drive pins and max t over the coast pins of one run of columns, kept in
/// four lanes so that the loop compiles to packed instructions. Exactly the minimum and
/// maximum: the order of the comparisons does not change them.
#[inline(always)]
fn scan(
    columns: &super::geometry::Columns,
    run: std::ops::Range<usize>,
    (radial, tangential, radius): (&[f64], &[f64], &[f64]),
    k: &Coefficients,
) -> (f64, f64) {
    let n = run.len();
    let c = columns.run(run);
    let (g0, fe, fs) = (c.design_gap, c.equidistant, c.shift);
    let (fr, ft, fx) = (c.radial, c.tangential, c.eccentric);
    let (inverse, cp, sp) = (c.inverse_lever, c.polar_cos, c.polar_sin);
    let (radial, tangential, radius) = (&radial[..n], &tangential[..n], &radius[..n]);
    // Every slice is n long: the checks below let the compiler drop the indexing checks.
    assert!(
        [g0, fe, fs, fr, ft, fx, inverse, cp, sp, radial, tangential, radius]
            .iter()
            .all(|column| column.len() == n)
    );
    // g_i/l_i − ε_i (a macro: the compiler left a closure out of line).
    macro_rules! ratio {
        ($i:expr) => {{
            let i = $i;
            let gap = g0[i]
                + k.equidistant * fe[i]
                + k.shift * fs[i]
                + (k.pin_circle + radial[i]) * fr[i]
                + tangential[i] * ft[i]
                + k.along * fx[i]
                + (k.common - radius[i]);
            gap * inverse[i] - (k.pitch.0 * cp[i] + k.pitch.1 * sp[i])
        }};
    }
    let (mut low, mut high) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4]);
    let whole = n / 4 * 4;
    for start in (0..whole).step_by(4) {
        for lane in 0..4 {
            let i = start + lane;
            let r = ratio!(i);
            let d = if inverse[i] > 0.0 { r } else { f64::INFINITY };
            let c = if inverse[i] < 0.0 {
                r
            } else {
                f64::NEG_INFINITY
            };
            low[lane] = if d < low[lane] { d } else { low[lane] };
            high[lane] = if c > high[lane] { c } else { high[lane] };
        }
    }
    for i in whole..n {
        let r = ratio!(i);
        if inverse[i] > 0.0 && r < low[0] {
            low[0] = r;
        }
        if inverse[i] < 0.0 && r > high[0] {
            high[0] = r;
        }
    }
    let lag = low
        .iter()
        .fold(f64::INFINITY, |a, &v| if v < a { v } else { a });
    let lead = high
        .iter()
        .fold(f64::NEG_INFINITY, |a, &v| if v > a { v } else { a });
    (lag, lead)
}

/// A row's gaps without the pins' own terms, per crank angle and disc: everything in a
/// window but the pins depends on the output angle only through z_p·Θ_k, which takes q
/// values, and the point's slots are one residue's z_p columns; so the row is reduced to
/// 2q runs of z_p values (t_m = g_m − l_m·ε_m, the pin terms left out) with their offsets
/// and slacks. The z_p points of one run differ only in the rotation `start` by which the
/// pins meet its entries (pin i meets entry (start + i) mod z_p, and start takes every
/// value once as k runs over the points of one crank angle, z_c and z_p being coprime), so
/// [`RowTable::fill`] folds each run entry by entry over every rotation at once (folds.rs)
/// into the window ends that [`RowTable::ends`] then looks up.
#[derive(Debug, Clone, Default)]
pub(crate) struct RowTable {
    /// Per (kq, d) at 2·kq + d: z_p values t_m.
    pub runs: Vec<f64>,
    /// Per (kq, d): the first column entry of its residue (r·z_p), C_d, the slack s_d.
    pub heads: Vec<(usize, f64, f64)>,
    /// Whether any pin has a radial or tangential error (else only its radius acts).
    pub placed_pins: bool,
    /// The pins' radii, radial and tangential errors reversed and doubled (z_p − 1 − u
    /// mod z_p at u < 2·z_p): entry m's pins over the rotations 0..z_p are
    /// `[z_p − 1 − m .. 2·z_p − 1 − m]`.
    turned: [Vec<f64>; 3],
    /// Per (kq, d) and rotation at (2·kq + d)·z_p + start: the window's ends (lower,
    /// upper) at the output, rad.
    pub window_ends: Vec<(f64, f64)>,
    /// The same, rigid: [C − K − s, C + L + s] also where the disc's own flanks overlap
    /// (L + K < 0), so that the width measures every overlap, the disc's own and the
    /// pair's (where the preload is judged).
    pub rigid_ends: Vec<(f64, f64)>,
    /// Whether some disc's own flanks overlap at some point of the row.
    pub own_overlap: bool,
    /// Room for a disc's own balance.
    own: OwnScratch,
    /// Per rotation: the drive flank's least and the coast flank's largest ratio.
    lag: Vec<f64>,
    coast: Vec<f64>,
}

impl RowTable {
    /// Fills the table of a row: its runs, then every window end.
    pub fn fill(
        &mut self,
        reducer: &Reducer,
        grid: &Grid,
        layout: &Layout,
        terms: &RowTerms,
        x: &[f64],
    ) {
        let (q, pins) = (grid.per_pin, reducer.stage.pins);
        let columns = &grid.columns;
        self.runs.resize(2 * q * pins, 0.0);
        self.heads.clear();
        let positions = &x[layout.pins..layout.pins + 2 * pins];
        self.placed_pins = positions.iter().any(|v| *v != 0.0);
        for kq in 0..q {
            let turn = grid.turn[kq];
            for d in 0..2 {
                let (offset, along) = offset_and_shift(reducer, terms, d, turn);
                let pitch = turned_pitch(terms, d, turn);
                let (base, _) = grid.placement(kq, d);
                let run = &mut self.runs[(2 * kq + d) * pins..(2 * kq + d + 1) * pins];
                let c = columns.run(base..base + pins);
                let (g0, fe, fs) = (c.design_gap, c.equidistant, c.shift);
                let (fr, fx, lever) = (c.radial, c.eccentric, c.lever);
                let (cp, sp) = (c.polar_cos, c.polar_sin);
                for (m, t) in run.iter_mut().enumerate() {
                    let gap = g0[m]
                        + terms.equidistant_error * fe[m]
                        + terms.shift_error * fs[m]
                        + terms.pin_circle_error * fr[m]
                        + along * fx[m]
                        + terms.common[d];
                    let epsilon = pitch.0 * cp[m] + pitch.1 * sp[m];
                    *t = gap - lever[m] * epsilon;
                }
                let slack = needle_slack_of(reducer, grid, terms, kq, d);
                self.heads.push((base, offset, slack));
            }
        }
        self.turn_pins(layout, x, pins);
        self.window_ends.clear();
        self.rigid_ends.clear();
        self.own_overlap = false;
        for run in 0..2 * q {
            self.ends_of_run(reducer, grid, run);
        }
    }

    /// The pins' columns reversed and doubled (`turned`).
    fn turn_pins(&mut self, layout: &Layout, x: &[f64], pins: usize) {
        let columns = if self.placed_pins { 3 } else { 1 };
        for (c, turned) in self.turned.iter_mut().take(columns).enumerate() {
            // c = 0 the radii (the third block of pin inputs), 1 radial, 2 tangential.
            let block = [2, 0, 1][c];
            let pin = &x[layout.pins + block * pins..layout.pins + (block + 1) * pins];
            // Entry u < z_p holds pin z_p − 1 − u, and so does entry z_p + u.
            turned.clear();
            turned.extend(pin.iter().rev());
            turned.extend(pin.iter().rev());
        }
    }

    /// The window ends of one run (crank angle and disc) at its z_p rotations.
    fn ends_of_run(&mut self, reducer: &Reducer, grid: &Grid, run_index: usize) {
        let pins = reducer.stage.pins;
        let (base, offset, slack) = self.heads[run_index];
        let run = &self.runs[run_index * pins..(run_index + 1) * pins];
        let residue = base / pins;
        let columns = &grid.columns;
        let inverse = &columns.inverse_lever[base..base + pins];
        self.lag.clear();
        self.lag.resize(pins, f64::INFINITY);
        self.coast.clear();
        self.coast.resize(pins, f64::NEG_INFINITY);
        let turned = Turned {
            radius: &self.turned[0],
            placed: self
                .placed_pins
                .then(|| (&self.turned[1][..], &self.turned[2][..])),
        };
        let flank = |(entries, largest): (std::ops::Range<usize>, bool)| Flank {
            entries,
            run,
            inverse,
            radial: &columns.radial[base..base + pins],
            tangential: &columns.tangential[base..base + pins],
            largest,
        };
        let both = [
            flank((columns.drive[residue].clone(), false)),
            flank((columns.coast[residue].clone(), true)),
        ];
        fold_flank(grid.arch, &mut self.lag, &both[0], &turned);
        fold_flank(grid.arch, &mut self.coast, &both[1], &turned);
        let lambda = reducer.lambda;
        let own = &mut self.own;
        own.levers.clear();
        own.levers.extend(
            columns.lever[base..base + pins]
                .iter()
                .zip(inverse)
                .map(|(l, v)| if *v != 0.0 { *l } else { 0.0 }),
        );
        // Each search starts from the same disc's rest at the previous grid point where
        // this row has it (the runs of the crank angle before: it moves little from
        // point to point); the root does not depend on the start, only its steps do.
        let first = run_index * pins;
        own.guesses.clear();
        own.guesses
            .extend(grid.previous[first..first + pins].iter().map(|&at| {
                let at = at as usize;
                if at < first {
                    own.all_rests[at]
                } else {
                    f64::NAN
                }
            }));
        grid.arch.dispatch(OwnBalances {
            own,
            run,
            factors: (
                &columns.radial[base..base + pins],
                &columns.tangential[base..base + pins],
            ),
            turned: &turned,
            brackets: (&self.lag, &self.coast),
        });
        self.own.all_rests.resize(first + pins, f64::NAN);
        self.own.all_rests[first..first + pins].copy_from_slice(&self.own.rests);
        for (s, (&lag, &coast)) in self.lag.iter().zip(&self.coast).enumerate() {
            // A disc whose own flanks overlap (coast > lag) fits nowhere rigidly: its
            // pins hold it at its own balance y0 and its slack alone is free (§14.2).
            let ends = |(lower, upper): (f64, f64)| {
                (
                    lambda * (offset + lower - slack),
                    lambda * (offset + upper + slack),
                )
            };
            let rigid = ends((coast, lag));
            self.rigid_ends.push(rigid);
            self.window_ends.push(if coast > lag {
                self.own_overlap = true;
                let rest = self.own.rests[s];
                ends((rest, rest))
            } else {
                rigid
            });
        }
    }

    /// The window ends of disc d at grid point k, output angles (rad).
    #[inline(always)]
    pub fn ends(&self, grid: &Grid, k: usize, d: usize) -> (f64, f64) {
        self.window_ends[grid.ends_at[k][d] as usize]
    }

    /// The rigid window ends of disc d at grid point k (`rigid_ends`), rad.
    #[inline(always)]
    pub fn rigid(&self, grid: &Grid, k: usize, d: usize) -> (f64, f64) {
        self.rigid_ends[grid.ends_at[k][d] as usize]
    }
}

/// ε's (cos, sin) coefficients on the polar angle: (F_p/2)/r_m·(cos, sin) of ϕ_p + z_p·Θ − d·π.
pub(crate) fn turned_pitch(terms: &RowTerms, d: usize, (s, c): (f64, f64)) -> (f64, f64) {
    let sigma = if d == 0 { 1.0 } else { -1.0 };
    let (a, b) = terms.pitch[d];
    // cos(ϑ − ϕ) with ϑ = polar − z_pΘ + dπ: = cos(polar − (ϕ + z_pΘ − dπ)).
    let (pc, ps) = (a * c - b * s, a * s + b * c);
    (sigma * pc, sigma * ps)
}

/// The rests of one run's rotations whose discs overlap their own flanks: the search of
/// [`OwnSearch`] for every rotation at once, a rotation to a lane, as the operation `pulp`
/// compiles once per instruction set. Each lane's sums run in a fixed order
/// (`OwnScratch::sums`) and every operation is one IEEE operation per lane (no product
/// fused): the same bits at every width.
struct OwnBalances<'a> {
    own: &'a mut OwnScratch,
    /// t_m of the run.
    run: &'a [f64],
    /// f_r,m and f_t,m of the run.
    factors: (&'a [f64], &'a [f64]),
    /// The pins' columns reversed and doubled.
    turned: &'a Turned<'a>,
    /// lag[s] and coast[s] of the run.
    brackets: (&'a [f64], &'a [f64]),
}

impl pulp::WithSimd for OwnBalances<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(mut self, simd: S) {
        let pins = self.run.len();
        let lanes = pins.div_ceil(OWN_LANES) * OWN_LANES;
        self.own.start(self.brackets, lanes);
        // Every vector of lanes searches at first.
        self.own.open.clear();
        self.own.open.resize(lanes / S::F64_LANES, true);
        self.fill_gaps(lanes);
        let own = self.own;
        for _ in 0..OWN_BALANCE_STEPS {
            own.sums(simd, lanes);
            if own.step(simd) {
                break;
            }
        }
        own.rests.clear();
        own.rests.extend_from_slice(&own.search.y[..pins]);
    }
}

impl OwnBalances<'_> {
    /// Every rotation's gaps (`OwnScratch::gaps`) of the entries that may carry: the pin
    /// that meets entry m at rotation s is (m − s) mod z_p, entry z_p − 1 − m + s of the
    /// turned columns, so each entry's rotations are one contiguous run of them. An entry
    /// whose pin carries in no lane anywhere in its bracket (l·y − g ≤ 0 at the end of
    /// the bracket where l·y is largest: rounding keeps l·y monotone in y) adds nothing
    /// to any sum and is left out; the searches never leave their brackets.
    #[inline(always)]
    fn fill_gaps(&mut self, lanes: usize) {
        let pins = self.run.len();
        let own = &mut *self.own;
        own.gaps.resize(pins * lanes, 0.0);
        own.kept.clear();
        let (fr, ft) = self.factors;
        let (lows, highs) = (&own.search.lo[..lanes], &own.search.hi[..lanes]);
        for (m, &lever) in own.levers[..pins].iter().enumerate() {
            let at = pins - 1 - m..2 * pins - 1 - m;
            let (t, radius) = (self.run[m], &self.turned.radius[at.clone()]);
            let j = own.kept.len();
            let (row, past) = own.gaps[j * lanes..(j + 1) * lanes].split_at_mut(pins);
            past.fill(0.0);
            match self.turned.placed {
                Some((radial, tangential)) => {
                    let (radial, tangential) = (&radial[at.clone()], &tangential[at]);
                    for (s, gap) in row.iter_mut().enumerate() {
                        *gap = t + radial[s] * fr[m] + tangential[s] * ft[m] - radius[s];
                    }
                }
                None => {
                    for (gap, r) in row.iter_mut().zip(radius) {
                        *gap = t - r;
                    }
                }
            }
            let ends = if lever > 0.0 { highs } else { lows };
            let carries = row
                .iter()
                .zip(ends)
                .fold(false, |any, (g, y)| any | (lever * y - g > 0.0));
            if carries {
                own.kept.push((lever, lever * lever));
            }
        }
    }
}

/// The search for the turn y0 at which a disc whose own flanks overlap rests, one lane
/// per rotation: where its pins' moment M(y) = Σ max(0, l·y − g)·l vanishes
/// (docs/models.md §14.2; the common secant stiffness of the pins drops out), between the
/// drive flank's least ratio `lag` and the coast flank's largest `coast`, where M changes
/// sign. M is piecewise linear in y: on the piece of the pins A that carry at y,
/// M(y) = y·S_A − P_A with P_A = Σ_A g·l, S_A = Σ_A l², whose root is P_A/S_A. Each step
/// takes the sums at y and moves to that root (Newton's step; a bisection of the bracket
/// where it would leave it); where y is the root of the pins that carry at y (P_A/S_A = y,
/// bit for bit), it is M's root. So the root depends on the pins alone, not on the path to
/// it (the start, the bracket's steps), but where rounding alone decides whether a pin
/// carries at the root: there the bracket closes within the tolerance. A rotation whose
/// disc does not overlap itself stands at NaN, where no pin carries: settled at once.
#[derive(Debug, Clone, Default)]
struct OwnSearch {
    /// Per lane: the turn (rad), the bracket, whether settled (1) or not (0).
    y: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    done: Vec<f64>,
}

/// A row table's room for the discs' own balances ([`OwnBalances`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct OwnScratch {
    /// The gaps of every rotation of the entries that may carry, entry j's at j·lanes + s
    /// (the lanes past z_p at 0); the run's levers (0 where a pin has none) and those of
    /// the entries kept, with their squares.
    gaps: Vec<f64>,
    levers: Vec<f64>,
    kept: Vec<(f64, f64)>,
    search: OwnSearch,
    /// The sums at the current turns, per lane; per vector of lanes, whether any lane in
    /// it is still searching.
    sums: (Vec<f64>, Vec<f64>),
    open: Vec<bool>,
    /// Per rotation of the run: y0 where the disc overlaps its own flanks, else NaN; where
    /// its search starts (NaN: the bracket's middle).
    rests: Vec<f64>,
    guesses: Vec<f64>,
    /// The rests of the row's runs so far, at their window index.
    all_rests: Vec<f64>,
}

impl OwnScratch {
    /// Every lane at its start (`guesses`, else its bracket's middle; NaN and settled, with
    /// a NaN bracket, where the disc does not overlap itself, and past the rotations).
    fn start(&mut self, (lags, coasts): (&[f64], &[f64]), lanes: usize) {
        let search = &mut self.search;
        let columns = [
            &mut search.y,
            &mut search.lo,
            &mut search.hi,
            &mut search.done,
            &mut self.sums.0,
            &mut self.sums.1,
        ];
        for column in columns {
            column.resize(lanes, 0.0);
        }
        let rotations = lags.len();
        for (rotation, (&lag, &coast)) in lags.iter().zip(coasts).enumerate() {
            let overlaps = coast > lag;
            let guess = self.guesses[rotation];
            search.y[rotation] = if !overlaps {
                f64::NAN
            } else if guess > lag && guess < coast {
                guess
            } else {
                0.5 * (lag + coast)
            };
            let (lo, hi) = if overlaps {
                (lag, coast)
            } else {
                (f64::NAN, f64::NAN)
            };
            search.lo[rotation] = lo;
            search.hi[rotation] = hi;
            search.done[rotation] = if overlaps { 0.0 } else { 1.0 };
        }
        for column in [&mut search.y, &mut search.lo, &mut search.hi] {
            column[rotations..].fill(f64::NAN);
        }
        search.done[rotations..].fill(1.0);
    }

    /// (P, S) = (Σ g·l, Σ l²) over the pins that carry at each lane's y (l·y − g > 0): the
    /// kept entries' j-th in chain j mod 4 in their order, the chains added as
    /// (c0 + c1) + (c2 + c3) (four chains of additions, not one four times as long).
    #[inline(always)]
    fn sums<S: pulp::Simd>(&mut self, simd: S, lanes: usize) {
        let zero = simd.splat_f64s(0.0);
        let (p, s) = (&mut self.sums.0, &mut self.sums.1);
        let (p, s) = (S::as_mut_simd_f64s(p).0, S::as_mut_simd_f64s(s).0);
        let y = S::as_simd_f64s(&self.search.y).0;
        let vectors = p.len();
        let kept = &self.kept[..];
        let n = kept.len();
        let gaps = S::as_simd_f64s(&self.gaps[..n * lanes]).0;
        assert_eq!(gaps.len(), n * vectors);
        for (v, ((p, s), &y)) in p.iter_mut().zip(s.iter_mut()).zip(y).enumerate() {
            if !self.open[v] {
                // Every lane settled: its sums are not read again.
                continue;
            }
            let (mut cp, mut cs) = ([zero; CHAINS], [zero; CHAINS]);
            // Entry j's terms into chain c (a macro: a closure would be compiled without
            // the instruction set's features, out of line).
            macro_rules! add {
                ($c:expr, $j:expr) => {{
                    let (c, j) = ($c, $j);
                    let (g, (l, ll)) = (gaps[j * vectors + v], kept[j]);
                    let (l, ll) = (simd.splat_f64s(l), simd.splat_f64s(ll));
                    // l·y − g > 0 exactly where l·y > g (a difference of two doubles is
                    // 0 only where they are equal).
                    let carries = simd.greater_than_f64s(simd.mul_f64s(l, y), g);
                    let gl = simd.select_f64s(carries, simd.mul_f64s(g, l), zero);
                    let ll = simd.select_f64s(carries, ll, zero);
                    cp[c] = simd.add_f64s(cp[c], gl);
                    cs[c] = simd.add_f64s(cs[c], ll);
                }};
            }
            in_chains!(n, add);
            *p = total(simd, cp);
            *s = total(simd, cs);
        }
    }

    /// One step of every lane not yet settled (`OwnSearch`); whether all are.
    #[inline(always)]
    fn step<S: pulp::Simd>(&mut self, simd: S) -> bool {
        let search = &mut self.search;
        let (zero, one, half) = (
            simd.splat_f64s(0.0),
            simd.splat_f64s(1.0),
            simd.splat_f64s(0.5),
        );
        let tolerance = simd.splat_f64s(OWN_BALANCE_TOLERANCE);
        let (ys, los, his, dones) = (
            S::as_mut_simd_f64s(&mut search.y).0,
            S::as_mut_simd_f64s(&mut search.lo).0,
            S::as_mut_simd_f64s(&mut search.hi).0,
            S::as_mut_simd_f64s(&mut search.done).0,
        );
        let (p_now, s_now) = (
            S::as_simd_f64s(&self.sums.0).0,
            S::as_simd_f64s(&self.sums.1).0,
        );
        let mut open = false;
        for v in 0..ys.len() {
            let (y, p, s) = (ys[v], p_now[v], s_now[v]);
            // y is the root of the pins that carry at y (P/S = y: a fixed point, reached by
            // the Newton step before), or no pin carries (M = 0): settled where it stands.
            let root = simd.div_f64s(p, s);
            let settled = simd.or_m64s(
                simd.or_m64s(simd.equal_f64s(root, y), simd.equal_f64s(s, zero)),
                simd.equal_f64s(dones[v], one),
            );
            let above =
                simd.greater_than_or_equal_f64s(simd.sub_f64s(simd.mul_f64s(y, s), p), zero);
            let lo = simd.select_f64s(above, los[v], y);
            let hi = simd.select_f64s(above, y, his[v]);
            let inside = simd.and_m64s(
                simd.greater_than_f64s(root, lo),
                simd.less_than_f64s(root, hi),
            );
            let middle = simd.mul_f64s(half, simd.add_f64s(lo, hi));
            let next = simd.select_f64s(inside, root, middle);
            let narrow = simd.less_than_or_equal_f64s(simd.sub_f64s(hi, lo), tolerance);
            ys[v] = simd.select_f64s(settled, y, next);
            los[v] = simd.select_f64s(settled, los[v], lo);
            his[v] = simd.select_f64s(settled, his[v], hi);
            dones[v] = simd.select_f64s(simd.or_m64s(settled, narrow), one, zero);
            self.open[v] = simd.reduce_sum_f64s(simd.sub_f64s(one, dones[v])) > 0.0;
            open |= self.open[v];
        }
        !open
    }
}

/// Lanes are padded to a multiple of this.
const OWN_LANES: usize = 8;

/// Most steps of a disc's own balance (each one Newton's or a bisection's).
const OWN_BALANCE_STEPS: usize = 100;

/// A disc's own balance is settled to this width of its bracket, rad (3·10⁻¹³ arcmin).
const OWN_BALANCE_TOLERANCE: f64 = 1e-16;

#[cfg(test)]
mod tests {
    use super::super::test_streams::{doubled, every_width, stream};
    use super::*;

    /// One run's rests by every kernel this processor runs, with the searches started at
    /// `guesses`: (name, rests).
    fn rests_in_every_width(
        (run, levers, inverse): (&[f64], &[f64], &[f64]),
        factors: (&[f64], &[f64]),
        turned: &Turned,
        brackets: (&[f64], &[f64]),
        guesses: &[f64],
    ) -> Vec<(&'static str, Vec<f64>)> {
        let mut widths = Vec::new();
        for (name, width) in every_width() {
            let mut own = OwnScratch::default();
            own.levers.extend(
                levers
                    .iter()
                    .zip(inverse)
                    .map(|(l, v)| if *v != 0.0 { *l } else { 0.0 }),
            );
            own.guesses.extend_from_slice(guesses);
            width.apply(OwnBalances {
                own: &mut own,
                run,
                factors,
                turned,
                brackets,
            });
            widths.push((name, own.rests));
        }
        widths
    }

    #[test]
    fn own_balances_agree_to_the_bit_in_every_width_and_from_any_start() {
        // Runs of 40, 37 and 8 entries (padded lanes, remainders of the chains), pins in
        // and out of place, gaps of either sign so that most rotations overlap their own
        // flanks. Each rest against plain bisection of Σ max(0, l·y − g)·l on the gaps
        // computed in full; every width, and every start (the bracket's middle, the
        // neighbouring rotation's rest, a point near either end), to the bit.
        let mut next = stream(11);
        let (mut overlapping, mut free) = (0, 0);
        for pins in [40, 37, 8] {
            let column = |next: &mut dyn FnMut() -> f64, scale: f64| -> Vec<f64> {
                (0..pins).map(|_| scale * next()).collect()
            };
            // The 37-entry runs with more clearance: some rotations do not overlap.
            let clearance = if pins == 37 { 5e-3 } else { 0.0 };
            let run: Vec<f64> = column(&mut next, 2e-3)
                .iter()
                .map(|t| t + clearance)
                .collect();
            let levers: Vec<f64> = (0..pins)
                .map(|m| match m % 7 {
                    0 => 0.0,
                    _ if m < pins / 2 => 10.0 + m as f64,
                    _ => -12.0 - m as f64,
                })
                .collect();
            let inverse: Vec<f64> = levers
                .iter()
                .map(|l| if *l != 0.0 { 1.0 / l } else { 0.0 })
                .collect();
            let (fr, ft) = (column(&mut next, 1.0), column(&mut next, 1.0));
            let (radius, radial, tangential) = (
                doubled(&column(&mut next, 4e-3)),
                doubled(&column(&mut next, 3e-3)),
                doubled(&column(&mut next, 3e-3)),
            );
            for placed in [None, Some((&radial[..], &tangential[..]))] {
                let turned = Turned {
                    radius: &radius,
                    placed,
                };
                // Rotation s's gaps in full, and its bracket as the folds find it.
                let gaps = |s: usize| -> Vec<f64> {
                    (0..pins)
                        .map(|m| {
                            let at = pins - 1 - m + s;
                            match placed {
                                Some((a, b)) => run[m] + a[at] * fr[m] + b[at] * ft[m] - radius[at],
                                None => run[m] - radius[at],
                            }
                        })
                        .collect()
                };
                let (mut lags, mut coasts) =
                    (vec![f64::INFINITY; pins], vec![f64::NEG_INFINITY; pins]);
                for s in 0..pins {
                    for (g, v) in gaps(s).iter().zip(&inverse) {
                        if *v > 0.0 {
                            lags[s] = lags[s].min(g * v);
                        } else if *v < 0.0 {
                            coasts[s] = coasts[s].max(g * v);
                        }
                    }
                }
                let data = (&run[..], &levers[..], &inverse[..]);
                let brackets = (&lags[..], &coasts[..]);
                let middle = rests_in_every_width(
                    data,
                    (&fr, &ft),
                    &turned,
                    brackets,
                    &vec![f64::NAN; pins],
                );
                let reference = &middle[0].1;
                for s in 0..pins {
                    if coasts[s] <= lags[s] {
                        assert!(reference[s].is_nan(), "rotation {s} has no rest");
                        free += 1;
                        continue;
                    }
                    overlapping += 1;
                    // The independent check: `DiscWindow::at_rest`'s plain bisection on
                    // the pins with a lever, at no offset and no slack.
                    let pins_of: Vec<(f64, f64)> = gaps(s)
                        .into_iter()
                        .zip(&levers)
                        .filter(|(_, l)| **l != 0.0)
                        .map(|(g, l)| (g, *l))
                        .collect();
                    let window = DiscWindow {
                        offset: 0.0,
                        lag: lags[s],
                        lead: -coasts[s],
                        slack: 0.0,
                    };
                    let (bisected, _) = window.at_rest(1.0, &pins_of);
                    let scale = lags[s].abs().max(coasts[s].abs());
                    assert!(
                        (reference[s] - bisected).abs() <= 1e-13 * scale,
                        "{pins} pins, rotation {s}: {} against {bisected}",
                        reference[s]
                    );
                }
                let near = |f: f64| -> Vec<f64> {
                    (0..pins)
                        .map(|s| lags[s] + f * (coasts[s] - lags[s]))
                        .collect()
                };
                let neighbour: Vec<f64> = (0..pins).map(|s| reference[(s + 1) % pins]).collect();
                for guesses in [neighbour, near(1e-3), near(0.999)] {
                    let started =
                        rests_in_every_width(data, (&fr, &ft), &turned, brackets, &guesses);
                    for (name, rests) in middle.iter().chain(&started) {
                        let same = rests
                            .iter()
                            .zip(reference)
                            .all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "{name}, {pins} pins, placed {}", placed.is_some());
                    }
                }
            }
        }
        // The test reaches both: rotations that search and rotations that do not.
        assert!(
            overlapping > 100 && free > 10,
            "{overlapping} overlap, {free} do not"
        );
    }
}
