//! The zero-torque balance of two discs whose flanks overlap (docs/models.md §14.5): where
//! the two discs' windows fail to overlap, the flanks are squeezed at zero torque. At the
//! output angle of the largest overlap, the discs settle where their pins' moments balance:
//! ```text
//! disc d turned by y_d against its pins: pin i deforms by d_i = l_i·y_d − g_i (> 0: loaded)
//! moment (per unit contact stiffness)  T_d(y) = Σ_i max(0, l_i·y − g_i)·l_i   (increasing)
//! with the output at u = Θ/λ:          x_d = u − C_d, and the needle rows' slack s_d lets
//!                                      the disc take any y in [x_d − s_d, x_d + s_d] free
//! balance at zero output torque        Σ_d τ_d(u) = 0,  τ_d = T_d(y_d) at the y_d of least |T_d|
//! contact law (two Palmgren line contacts per pin, as cycloid_pin_contact):
//!                                      δ(F) = 2·3.84·10⁻⁵·F^0.9/L^0.8
//! largest pin force                    F_max = δ⁻¹(max_i d_i),  K = F_max/max_i d_i (secant)
//! no-load torque at the input          T_0 = μ·Σ_i K·d_i·h_i / i
//! ```
//! The balance is taken with the secant stiffness of the most loaded pin for every pin (as
//! the contact model's zero-torque solution), so it fixes the y_d whatever K. h_i is the
//! arm of the contact's tangent about the disc centre: a pin slips by h_i per radian of the
//! disc's turn against the housing, which turns once per output turn while the input turns
//! i times. Left out of T_0: the friction of the crank bearings, support and main bearings
//! and seals under the preload's forces.
//!
//! The root u lies in [min_d(C_d − s_d + min(L_d, −K_d)), max_d(C_d + s_d + max(L_d, −K_d))]
//! (below min(L_d, −K_d) no drive pin of disc d carries, above the max no coast pin; −K_d
//! alone bounds it only while the disc's own flanks leave play), found by safeguarded
//! Newton steps on the piecewise linear sum (docs/models.md §14.5).

use super::{PinContact, Preload};

/// Most pins of a disc (the stage's own limit).
pub(crate) const MAX_PINS: usize = 200;

/// One disc's pins at one output angle: gap (the pitch's turn folded in), lever and slip
/// arm, held on the stack (the model allocates nothing per sample).
#[derive(Debug, Clone)]
pub(crate) struct DiscPins {
    gaps: [f64; MAX_PINS],
    levers: [f64; MAX_PINS],
    arms: [f64; MAX_PINS],
    len: usize,
    /// C_d and the slack s_d, rad (disc angles).
    pub offset: f64,
    pub slack: f64,
    /// The instruction sets the moment sums may use (the processor's report).
    arch: pulp::Arch,
}

impl DiscPins {
    /// No pins yet.
    pub fn new(offset: f64, slack: f64) -> DiscPins {
        DiscPins {
            gaps: [0.0; MAX_PINS],
            levers: [0.0; MAX_PINS],
            arms: [0.0; MAX_PINS],
            len: 0,
            offset,
            slack,
            arch: pulp::Arch::new(),
        }
    }

    /// Adds a pin.
    pub fn push(&mut self, gap: f64, lever: f64, arm: f64) {
        self.gaps[self.len] = gap;
        self.levers[self.len] = lever;
        self.arms[self.len] = arm;
        self.len += 1;
    }

    fn gaps(&self) -> &[f64] {
        &self.gaps[..self.len]
    }

    fn levers(&self) -> &[f64] {
        &self.levers[..self.len]
    }

    /// Empties the disc for another output angle (keeping its storage).
    pub fn reset(&mut self, offset: f64, slack: f64) {
        self.len = 0;
        self.offset = offset;
        self.slack = slack;
    }

    /// Keeps, in their order, the pins that can be loaded (l·y − g > 0) at some output
    /// angle u in [u_lo, u_hi]: the disc then turns within y in [u_lo − C − s,
    /// u_hi − C + s], and l·y − g is monotone in y in floating point too, so a pin left
    /// out is one whose term [`DiscPins::moment`] and the balance's sums would skip at
    /// every y they reach: the sums keep every term they had.
    fn retain_loadable(&mut self, u_lo: f64, u_hi: f64) {
        let (y_lo, y_hi) = (
            (u_lo - self.offset) - self.slack,
            (u_hi - self.offset) + self.slack,
        );
        // Without a branch on which pins stay (it changes from row to row): every pin is
        // written at the next free place, which moves on only past a pin kept.
        let mut kept = 0;
        for i in 0..self.len {
            let (g, l, h) = (self.gaps[i], self.levers[i], self.arms[i]);
            let y = if l > 0.0 { y_hi } else { y_lo };
            let reach = if l == 0.0 { -g } else { l * y - g };
            self.gaps[kept] = g;
            self.levers[kept] = l;
            self.arms[kept] = h;
            // NaN bounds keep every pin (the balance then has no root either way).
            kept += usize::from(reach > 0.0 || reach.is_nan());
        }
        self.len = kept;
    }

    /// T_d(y), mm² (per unit stiffness: N·mm per N/mm).
    fn moment(&self, y: f64) -> f64 {
        let mut sum = 0.0;
        for (g, l) in self.gaps().iter().zip(self.levers()) {
            let d = l * y - g;
            sum += carried(d, d * l);
        }
        sum
    }

    /// The disc's turn y in [x − s, x + s] where |T_d| is least, and T_d there.
    fn settle(&self, x: f64) -> (f64, f64) {
        let (lo, hi) = (x - self.slack, x + self.slack);
        let (t_lo, t_hi) = (self.moment(lo), self.moment(hi));
        if t_lo >= 0.0 {
            (lo, t_lo)
        } else if t_hi <= 0.0 {
            (hi, t_hi)
        } else {
            let y = newton_root(|y| self.moment_and_slope(y), lo, hi);
            (y, 0.0)
        }
    }

    /// T_d at the settled turn of [`DiscPins::settle`] without the turn itself (0 where
    /// the disc finds its balance within its slack), its slope in the disc's place x
    /// (T_d' = Σ l² over the loaded pins at the end of the slack that pushes, 0 within it)
    /// and its terms' size.
    fn settled_moment(&self, x: f64) -> (f64, f64, f64) {
        let low = self.moment_and_slope(x - self.slack);
        if low.0 >= 0.0 {
            return low;
        }
        let high = self.moment_and_slope(x + self.slack);
        if high.0 <= 0.0 {
            high
        } else {
            (0.0, 0.0, 0.0)
        }
    }

    /// T_d(y) (as [`DiscPins::moment`]), its slope Σ l² and its terms' size Σ d·|l| over
    /// the loaded pins.
    ///
    /// Summed in four lanes (pin i in lane i mod 4, the lanes added in a fixed order), with
    /// a mask instead of a branch (which pins carry changes from row to row): the same
    /// bits on every machine, and loops the compiler turns into packed instructions, built
    /// for the widest instruction set the processor has (`pulp`, as the windows' folds).
    fn moment_and_slope(&self, y: f64) -> (f64, f64, f64) {
        /// The sums as an operation `pulp` compiles once per instruction set.
        struct Sums<'a>(&'a DiscPins, f64);
        impl pulp::WithSimd for Sums<'_> {
            type Output = (f64, f64, f64);
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) -> Self::Output {
                self.0.moment_and_slope_in_lanes(self.1)
            }
        }
        self.arch.dispatch(Sums(self, y))
    }

    /// [`DiscPins::moment_and_slope`]'s sums, inlined into each instruction set's build.
    #[inline(always)]
    fn moment_and_slope_in_lanes(&self, y: f64) -> (f64, f64, f64) {
        sums_in_lanes(self.gaps(), self.levers(), y)
    }

    /// (L_d, K_d): the smallest g/l over the drive flank (its lag) and the smallest g/|l|
    /// over the coast flank (its lead), rad, in one pass, each pin's g/l selected by its
    /// flank rather than branched on (−g/l is −(g/l) exactly: a quotient's rounding does
    /// not depend on its sign).
    fn flanks(&self) -> (f64, f64) {
        let (mut lag, mut lead) = (f64::INFINITY, f64::INFINITY);
        for (g, l) in self.gaps().iter().zip(self.levers()) {
            let ratio = g / l;
            lag = lag.min(if *l > 0.0 { ratio } else { f64::INFINITY });
            lead = lead.min(if *l < 0.0 { -ratio } else { f64::INFINITY });
        }
        (lag, lead)
    }
}

/// `term` where the pin's approach d is positive (it carries), else +0.0 (its bits masked
/// to zero): added to a sum, the sum of the pins that carry, as a branch on d would give
/// (a sum that starts at +0.0 is unchanged by +0.0), without a branch on which pins carry,
/// which changes from row to row and which a processor mispredicts.
#[inline(always)]
fn carried(d: f64, term: f64) -> f64 {
    let mask = if d > 0.0 { u64::MAX } else { 0 };
    f64::from_bits(term.to_bits() & mask)
}

/// T(y) = Σ max(0, l·y − g)·l over the pins (gaps g, levers l), its slope Σ l² and its
/// terms' size Σ d·|l| over the loaded pins: pin i in lane i mod 4, the lanes added in a
/// fixed order, a mask instead of a branch (which pins carry changes from row to row). The
/// same bits on every machine; inlined into a `pulp` build, loops the compiler turns into
/// packed instructions, and four chains of additions instead of one.
#[inline(always)]
fn sums_in_lanes(gaps: &[f64], levers: &[f64], y: f64) -> (f64, f64, f64) {
    const LANES: usize = 4;
    let (mut sum, mut slope, mut size) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    let mut add = |lane: usize, g: f64, l: f64| {
        let d = l * y - g;
        sum[lane] += carried(d, d * l);
        slope[lane] += carried(d, l * l);
        size[lane] += carried(d, d * l.abs());
    };
    let whole = gaps.len() / LANES * LANES;
    for (g, l) in gaps[..whole]
        .chunks_exact(LANES)
        .zip(levers[..whole].chunks_exact(LANES))
    {
        for lane in 0..LANES {
            add(lane, g[lane], l[lane]);
        }
    }
    for (i, (g, l)) in gaps[whole..].iter().zip(&levers[whole..]).enumerate() {
        add(i, *g, *l);
    }
    let total = |v: [f64; LANES]| (v[0] + v[1]) + (v[2] + v[3]);
    (total(sum), total(slope), total(size))
}

/// The zero-torque balance of the two discs. It drops from `discs` the pins that no
/// output angle of the balance's bracket loads (they do not act on it).
pub(crate) fn zero_torque(contact: &PinContact, discs: &mut [DiscPins; 2]) -> Preload {
    let ((lo, hi), start) = bracket(discs);
    let margin = 1e-9 * (hi - lo).abs().max(1e-12);
    let (u_lo, u_hi) = (lo - margin, hi + margin);
    // The balance reads only pins that can take load somewhere in the bracket.
    for disc in discs.iter_mut() {
        disc.retain_loadable(u_lo, u_hi);
    }
    let u = if lo.is_finite() && hi.is_finite() {
        balance_root(discs, (u_lo, u_hi), start)
    } else {
        f64::NAN
    };
    preload_at(contact, discs, u)
}

/// The output angles [lo, hi] that hold the balance's root, and where Newton starts: the
/// middle of the conflict between the discs' windows (the highest lower end and the lowest
/// upper end). Σ_d τ_d(u) rises with u; beyond the ends every disc pushes one way: below
/// y = min(L_d, −K_d) no drive pin of disc d is loaded (T_d ≤ 0), above max(L_d, −K_d) no
/// coast pin (T_d ≥ 0). (−K_d alone bounds it below only while the disc's own flanks do
/// not overlap, L_d ≥ −K_d; where they do, T_d(−K_d) > 0 already.)
fn bracket(discs: &[DiscPins; 2]) -> ((f64, f64), f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut lower, mut upper) = (f64::NEG_INFINITY, f64::INFINITY);
    for p in discs {
        let (lag, lead) = p.flanks();
        lo = lo.min(p.offset - p.slack + lag.min(-lead));
        hi = hi.max(p.offset + p.slack + lag.max(-lead));
        lower = lower.max(p.offset - p.slack - lead);
        upper = upper.min(p.offset + p.slack + lag);
    }
    ((lo, hi), 0.5 * (lower + upper))
}

/// The preload of the two discs with the output at u: each disc settled within its slack,
/// the largest approach, its force and the drag of every loaded pin.
fn preload_at(contact: &PinContact, discs: &[DiscPins; 2], u: f64) -> Preload {
    let turns = [
        discs[0].settle(u - discs[0].offset).0,
        discs[1].settle(u - discs[1].offset).0,
    ];
    let largest = discs
        .iter()
        .zip(turns)
        .flat_map(|(p, y)| p.gaps().iter().zip(p.levers()).map(move |(g, l)| l * y - g))
        .fold(0.0_f64, f64::max);
    if largest <= 0.0 {
        return Preload::NONE;
    }
    let pin_force = contact.force_at(largest);
    let stiffness = pin_force / largest;
    let mut drag = 0.0;
    for (p, y) in discs.iter().zip(turns) {
        for ((g, l), h) in p.gaps().iter().zip(p.levers()).zip(&p.arms[..p.len]) {
            let d = l * y - g;
            drag += carried(d, stiffness * d * h);
        }
    }
    Preload {
        overlap_um: 1000.0 * largest,
        pin_force,
        no_load_torque: contact.friction * drag / contact.ratio / 1000.0,
    }
}

/// The output angle u in [lo, hi] where Σ_d τ_d(u) = 0 (τ_d = `settled_moment` at
/// u − C_d), by Newton's step as [`newton_root`] takes it: the sum rises with u and is
/// piecewise linear (its pieces end where a pin starts or stops carrying, or a disc
/// reaches an end of its slack). Every fourfold narrowing of the bracket drops the pins no
/// u left in it can load (`retain_loadable`: the sums keep every term they had).
fn balance_root(discs: &mut [DiscPins; 2], (mut lo, mut hi): (f64, f64), start: f64) -> f64 {
    let mut filtered = hi - lo;
    let mut u = if start > lo && start < hi {
        start
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..200 {
        let (mut value, mut slope, mut size) = (0.0, 0.0, 0.0);
        for p in discs.iter() {
            let (t, k, z) = p.settled_moment(u - p.offset);
            value += t;
            slope += k;
            size += z;
        }
        match newton_step((value, slope, size), u, (&mut lo, &mut hi)) {
            Step::Root(root) => return root,
            Step::Next(next) => u = next,
        }
        if hi - lo < 0.25 * filtered {
            discs.iter_mut().for_each(|p| p.retain_loadable(lo, hi));
            filtered = hi - lo;
        }
    }
    u
}

/// What a Newton step found.
enum Step {
    Root(f64),
    Next(f64),
}

/// One safeguarded Newton step from u with f(u) = value (slope, terms' size): the bracket
/// narrowed to the side where the root lies, the step kept within it (else bisection).
fn newton_step(
    (value, slope, size): (f64, f64, f64),
    u: f64,
    (lo, hi): (&mut f64, &mut f64),
) -> Step {
    if value == 0.0 || value.abs() <= 1e-14 * size {
        return Step::Root(u);
    }
    if value < 0.0 {
        *lo = u;
    } else {
        *hi = u;
    }
    let newton = u - value / slope;
    let next = if newton > *lo && newton < *hi {
        newton
    } else {
        0.5 * (*lo + *hi)
    };
    // Rounding's stagnation: a step within a few ulps of u itself (not of the bracket,
    // which a pin at the end of a flank, its lever near 0, can make 10⁸ times wider).
    if (next - u).abs() <= 1e-15 * u.abs().max(next.abs()) {
        Step::Root(next)
    } else {
        Step::Next(next)
    }
}

/// A root in [lo, hi] of an increasing, piecewise linear f given with its slope and its
/// terms' size, f(lo) ≤ 0 ≤ f(hi): Newton's step lands on the root once it stands on the
/// root's piece; it is kept within the bracket that every evaluation narrows (bisection
/// where it would leave it). Converged when f is below its rounding (10⁻¹⁴ of the size of
/// its terms) or the step below 10⁻¹⁵ of u: a few evaluations where the regula
/// falsi of [`root`] takes about fifteen on these sums (the two agree: tested).
fn newton_root(f: impl Fn(f64) -> (f64, f64, f64), mut lo: f64, mut hi: f64) -> f64 {
    let mut u = 0.5 * (lo + hi);
    for _ in 0..200 {
        match newton_step(f(u), u, (&mut lo, &mut hi)) {
            Step::Root(root) => return root,
            Step::Next(next) => u = next,
        }
    }
    u
}

/// The zero-torque balance of two discs alike (no offset between them, no slack), whose
/// pins have the gaps `gaps`, levers `levers` and slip arms `arms`: each disc settles where
/// its own moment vanishes, T(y) = Σ max(0, l_i·y − g_i)·l_i = 0 in [L, −K] (L the drive
/// flank's lag, K the coast flank's lead, L + K < 0 where the flanks overlap); the same
/// preload as [`zero_torque`] of the pair. T is increasing and piecewise linear: Newton's
/// step lands on the root once it has the loaded set, kept within the bracket (bisection
/// where it would leave it). None when the flanks do not overlap.
pub(crate) fn alike(contact: &PinContact, gaps: &[f64], pins: &AlikePins) -> Option<Preload> {
    /// The balance as an operation `pulp` compiles once per instruction set.
    struct Balance<'a>(&'a PinContact, &'a [f64], &'a AlikePins);
    impl pulp::WithSimd for Balance<'_> {
        type Output = Option<Preload>;
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, _simd: S) -> Self::Output {
            alike_in_lanes(self.0, self.1, self.2)
        }
    }
    pins.arch.dispatch(Balance(contact, gaps, pins))
}

/// [`alike`], inlined into each instruction set's build: the moments summed by
/// [`sums_in_lanes`].
#[inline(always)]
fn alike_in_lanes(contact: &PinContact, gaps: &[f64], pins: &AlikePins) -> Option<Preload> {
    let (lag, lead) = pins.flanks(gaps);
    // NaN gaps give a NaN play: no overlap to balance.
    if (lag + lead).is_nan() || lag + lead >= 0.0 {
        return None;
    }
    let (levers, arms) = (&pins.lever[..], &pins.arm[..]);
    let (mut lo, mut hi) = (lag, -lead);
    let mut y = 0.5 * (lo + hi);
    for _ in 0..ALIKE_STEPS {
        // Branch-free over the pins (the loaded set changes from row to row).
        let (moment, slope, size) = sums_in_lanes(gaps, levers, y);
        // The two flanks' moments cancel to rounding: y is the root.
        if moment.abs() <= 1e-13 * size {
            break;
        }
        if moment < 0.0 {
            lo = y;
        } else {
            hi = y;
        }
        let newton = y - moment / slope;
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let settled = (next - y).abs() <= 1e-15 * (hi - lo).abs().max(y.abs());
        y = next;
        if settled {
            break;
        }
    }
    let largest = largest_approach(gaps, levers, y);
    let drag = drag_in_lanes(gaps, levers, arms, y);
    Some(preload_of(contact, largest, drag))
}

/// Most Newton steps of [`alike`]'s balance.
pub(super) const ALIKE_STEPS: usize = 100;

/// The preload of two discs alike whose balance stands at the largest approach `largest`
/// (mm) with the loaded pins' Σ d_i·h_i `drag` (mm², one disc); none where no pin is
/// loaded.
#[inline]
pub(super) fn preload_of(contact: &PinContact, largest: f64, drag: f64) -> Preload {
    if largest.is_nan() || largest <= 0.0 {
        return Preload::NONE;
    }
    let pin_force = contact.force_at(largest);
    let stiffness = pin_force / largest;
    let drag = stiffness * drag;
    Preload {
        overlap_um: 1000.0 * largest,
        pin_force,
        no_load_torque: contact.friction * 2.0 * drag / contact.ratio / 1000.0,
    }
}

/// max(0, max_i (l_i·y − g_i)), in four lanes (a maximum does not depend on the order it is
/// taken in: the bits of one pass).
#[inline(always)]
fn largest_approach(gaps: &[f64], levers: &[f64], y: f64) -> f64 {
    const LANES: usize = 4;
    let mut largest = [0.0_f64; LANES];
    let whole = gaps.len() / LANES * LANES;
    for (g, l) in gaps[..whole]
        .chunks_exact(LANES)
        .zip(levers[..whole].chunks_exact(LANES))
    {
        for lane in 0..LANES {
            largest[lane] = largest[lane].max(l[lane] * y - g[lane]);
        }
    }
    for (i, (g, l)) in gaps[whole..].iter().zip(&levers[whole..]).enumerate() {
        largest[i] = largest[i].max(l * y - g);
    }
    largest[0].max(largest[1]).max(largest[2].max(largest[3]))
}

/// Σ d_i·h_i over the loaded pins (d_i = l_i·y − g_i > 0), in four lanes added in a fixed
/// order (as [`sums_in_lanes`]).
#[inline(always)]
fn drag_in_lanes(gaps: &[f64], levers: &[f64], arms: &[f64], y: f64) -> f64 {
    const LANES: usize = 4;
    let mut drag = [0.0; LANES];
    let mut add = |lane: usize, g: f64, l: f64, h: f64| {
        let d = l * y - g;
        drag[lane] += carried(d, d * h);
    };
    let whole = gaps.len() / LANES * LANES;
    for ((g, l), h) in gaps[..whole]
        .chunks_exact(LANES)
        .zip(levers[..whole].chunks_exact(LANES))
        .zip(arms[..whole].chunks_exact(LANES))
    {
        for lane in 0..LANES {
            add(lane, g[lane], l[lane], h[lane]);
        }
    }
    for (i, ((g, l), h)) in gaps[whole..]
        .iter()
        .zip(&levers[whole..])
        .zip(&arms[whole..])
        .enumerate()
    {
        add(i, *g, *l, *h);
    }
    (drag[0] + drag[1]) + (drag[2] + drag[3])
}

/// The pins of a disc whose preload [`alike`] balances: levers l, their inverses 1/l and
/// slip arms h (mm), the drive flank's (l > 0) first.
#[derive(Debug, Clone)]
pub(crate) struct AlikePins {
    pub lever: Vec<f64>,
    pub inverse: Vec<f64>,
    pub arm: Vec<f64>,
    /// The instruction sets the balance may use (the processor's report).
    pub(super) arch: pulp::Arch,
}

impl Default for AlikePins {
    fn default() -> AlikePins {
        AlikePins {
            lever: Vec::new(),
            inverse: Vec::new(),
            arm: Vec::new(),
            arch: pulp::Arch::new(),
        }
    }
}

impl AlikePins {
    /// Adds a pin (lever non-zero).
    pub fn push(&mut self, lever: f64, arm: f64) {
        self.lever.push(lever);
        self.inverse.push(1.0 / lever);
        self.arm.push(arm);
    }

    /// (L, K): the smallest g/l over l > 0 and the smallest −g/l over l < 0, rad. Four
    /// lanes of minima, each pin's ratio selected by its flank rather than branched on: a
    /// minimum does not depend on the order it is taken in (NaN ratios are passed over
    /// either way), so the lanes give the bits of one pass, in packed instructions when
    /// inlined into a `pulp` build.
    #[inline(always)]
    pub fn flanks(&self, gaps: &[f64]) -> (f64, f64) {
        const LANES: usize = 4;
        let (mut lag, mut lead) = ([f64::INFINITY; LANES], [f64::INFINITY; LANES]);
        let mut take = |lane: usize, g: f64, r: f64| {
            let ratio = g * r;
            lag[lane] = lag[lane].min(if r > 0.0 { ratio } else { f64::INFINITY });
            lead[lane] = lead[lane].min(if r > 0.0 { f64::INFINITY } else { -ratio });
        };
        let inverse = &self.inverse[..gaps.len()];
        let whole = gaps.len() / LANES * LANES;
        for (g, r) in gaps[..whole]
            .chunks_exact(LANES)
            .zip(inverse[..whole].chunks_exact(LANES))
        {
            for lane in 0..LANES {
                take(lane, g[lane], r[lane]);
            }
        }
        for (i, (g, r)) in gaps[whole..].iter().zip(&inverse[whole..]).enumerate() {
            take(i, *g, *r);
        }
        let least = |v: [f64; LANES]| v[0].min(v[1]).min(v[2].min(v[3]));
        (least(lag), least(lead))
    }
}

/// The largest pin force of one disc carrying `disc_torque` (N·mm) on the pins `pins` (of a
/// stage of `pin_count` pins whose pitch point has the lever `pitch_lever`) brought to zero play (every gap changed by one amount until the window closes: neither
/// play nor preload), N. The secant stiffness K = F_max/δ(F_max) is iterated to its fixed
/// point, as the contact model does (Li Lixing's method).
pub(crate) fn closed_pin_force(
    contact: &PinContact,
    disc_torque: f64,
    (pin_count, pitch_lever): (usize, f64),
    mut pins: DiscPins,
) -> f64 {
    // The play with every gap changed by c rises with c: close it.
    let play = |c: f64| {
        let mut moved = pins.clone();
        moved.gaps[..moved.len].iter_mut().for_each(|g| *g += c);
        let (lag, lead) = moved.flanks();
        lag + lead
    };
    let scale = pins.gaps().iter().fold(1e-6_f64, |a, g| a.max(g.abs()));
    let closing = root(play, -4.0 * scale, 4.0 * scale);
    let len = pins.len;
    pins.gaps[..len].iter_mut().for_each(|g| *g += closing);
    let (lag, lead) = pins.flanks();
    let lo = lag.min(-lead);
    let mut force = 4.0 * disc_torque / (pin_count as f64 * pitch_lever);
    for _ in 0..200 {
        let stiffness = force / contact.approach(force);
        let target = disc_torque / stiffness;
        let hi = lo.abs() + 1.0;
        let y = root(|y| target - pins.moment(y), lo - 1.0, hi);
        let deformation = pins
            .gaps()
            .iter()
            .zip(pins.levers())
            .map(|(g, l)| l * y - g)
            .fold(0.0_f64, f64::max);
        let next = stiffness * deformation;
        let settled = (next - force).abs() <= 1e-12 * next;
        force = next;
        if settled {
            break;
        }
    }
    force
}

/// A root of f on [lo, hi] where f(lo) ≥ 0 ≥ f(hi) (or the reverse) by the Illinois
/// variant of regula falsi, to 1e-15 of the bracket: f here is monotone and piecewise
/// linear, where it converges in a few steps.
pub(crate) fn root(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    let (mut f_lo, mut f_hi) = (f(lo), f(hi));
    if f_lo == 0.0 {
        return lo;
    }
    if f_hi == 0.0 {
        return hi;
    }
    if f_lo.signum() == f_hi.signum() || !(f_lo.is_finite() && f_hi.is_finite()) {
        return f64::NAN;
    }
    let tolerance = 1e-15 * (hi - lo).abs().max(lo.abs().max(hi.abs()));
    let mut side = 0;
    for _ in 0..200 {
        let mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let mid = if mid > lo.min(hi) && mid < lo.max(hi) {
            mid
        } else {
            0.5 * (lo + hi)
        };
        let f_mid = f(mid);
        if f_mid == 0.0 || (hi - lo).abs() <= tolerance {
            return mid;
        }
        if f_mid.signum() == f_hi.signum() {
            (hi, f_hi) = (mid, f_mid);
            if side == -1 {
                f_lo *= 0.5;
            }
            side = -1;
        } else {
            (lo, f_lo) = (mid, f_mid);
            if side == 1 {
                f_hi *= 0.5;
            }
            side = 1;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An RV-20E-like disc: 40 pins on a flank lever l_i = e·z_c·sin φ_i/S (drive for
    /// φ in (0, π)), gaps `gap(φ)` in mm.
    fn disc(offset: f64, slack: f64, mut gap: impl FnMut(f64) -> f64) -> DiscPins {
        let mut pins = DiscPins::new(offset, slack);
        for i in 0..40 {
            let phi = 2.0 * std::f64::consts::PI * (i as f64 + 0.3) / 40.0;
            let lever = 0.9 * 39.0 * phi.sin() / (1.0 + 0.48 * phi.cos()).sqrt();
            if lever.abs() > 1e-3 {
                pins.push(gap(phi), lever, 2.0 * phi.cos().abs() + 1.0);
            }
        }
        pins
    }

    fn contact() -> PinContact {
        PinContact::new(8.0, 0.02, 141.0)
    }

    /// The same balance by the regula falsi of [`root`] on the same sum.
    fn by_regula_falsi(discs: &[DiscPins; 2], lo: f64, hi: f64) -> f64 {
        let total = |u: f64| discs.iter().map(|p| p.settled_moment(u - p.offset).0).sum();
        root(total, lo, hi)
    }

    #[test]
    fn discs_overlapping_themselves_beyond_their_slack_are_balanced() {
        // Two equal discs, no offset, whose own flanks overlap (every gap −3 µm plus a
        // profile): each settles at its own root y* in [L, −K], where the pair does too,
        // whatever the slack. With the slack small against the overlap, T(−K − 2s) > 0:
        // the bracket [min(C − s − K), max(C + s + L)] read before did not hold the root,
        // and the balance came out as no preload at all.
        let gap = |phi: f64| -0.003 + 0.004 * (1.0 - phi.cos()).powi(2);
        let one = disc(0.0, 0.0, gap);
        let (lag, lead) = one.flanks();
        assert!(lag + lead < 0.0, "the flanks overlap: L {lag}, K {lead}");
        let reference = zero_torque(&contact(), &mut [one.clone(), one.clone()]);
        assert!(reference.pin_force > 0.0);
        for slack in [1e-6, 1e-5, 3e-5] {
            let d = disc(0.0, slack, gap);
            assert!(
                d.moment(-lead - 2.0 * slack) > 0.0,
                "the old bracket misses"
            );
            let pair = zero_torque(&contact(), &mut [d.clone(), d]);
            for (a, b) in [
                (pair.overlap_um, reference.overlap_um),
                (pair.pin_force, reference.pin_force),
                (pair.no_load_torque, reference.no_load_torque),
            ] {
                assert!(
                    (a / b - 1.0).abs() < 1e-12,
                    "slack {slack}: {a} against {b}"
                );
            }
        }
    }

    #[test]
    fn a_pin_at_the_end_of_a_flank_does_not_stop_the_balance_early() {
        // A pin whose lever is almost 0 (at a flank's end) and whose gap is slightly
        // negative has g/l of −10¹⁰ rad: the bracket grows 10¹⁴ times wider than the
        // discs' conflict, and a step criterion relative to it stopped Newton on its first
        // small step. From starts across the conflict, the root must leave the sum at its
        // rounding.
        let gap = |phi: f64| -0.003 + 0.004 * (1.0 - phi.cos()).powi(2);
        let mut discs = [
            disc(2e-5, 1e-5, gap),
            disc(-3e-5, 2e-5, |phi| gap(phi) + 0.001),
        ];
        discs[0].push(-1e-5, 1e-15, 0.0);
        let ((lo, hi), _) = bracket(&discs);
        assert!(lo < -1e9, "the bracket is wide: {lo}");
        let total = |u: f64| {
            discs.iter().fold((0.0, 0.0), |(v, z), p| {
                let (t, _, size) = p.settled_moment(u - p.offset);
                (v + t, z + size)
            })
        };
        for start in [-4e-4, -1e-4, -2e-5, 0.0, 3e-5, 1e-4, 4e-4] {
            let u = balance_root(&mut discs.clone(), (lo, hi), start);
            let (value, size) = total(u);
            let reference = total(start).1.max(total(0.0).1);
            assert!(
                value.abs() <= 1e-12 * reference,
                "start {start}: F({u}) = {value} of terms {size}"
            );
        }
    }

    #[test]
    fn newton_and_regula_falsi_find_the_same_balance() {
        // Random pairs: offsets, slacks, gaps (a modification profile, a pin-by-pin
        // scatter, an overlap of either sign): the preload at Newton's root of the
        // balance against the preload at the regula falsi's on the same bracket, to 1e-9
        // (the roots differ on flat stretches, where both discs balance within their
        // slack and every u there gives the same turns: 906 of the 2,000 pairs; 1,868
        // are preloaded).
        let mut state = 12345u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut preloaded, mut bisected) = (0, 0);
        for _ in 0..2000 {
            let shift = -0.006 * next() + 0.002;
            let scatter: Vec<f64> = (0..40).map(|_| 0.004 * (next() - 0.5)).collect();
            let make = |offset: f64, slack: f64| {
                let mut i = 0;
                disc(offset, slack, |phi| {
                    i += 1;
                    shift + 0.004 * (1.0 - phi.cos()).powi(2) + scatter[(i - 1) % 40]
                })
            };
            let discs = [
                make(2e-4 * (next() - 0.5), 5e-5 * next()),
                make(2e-4 * (next() - 0.5), 5e-5 * next()),
            ];
            let ((lo, hi), _) = bracket(&discs);
            let falsi = by_regula_falsi(&discs, lo, hi);
            let newton = balance_root(&mut discs.clone(), (lo, hi), 0.5 * (lo + hi));
            let (a, b) = (
                preload_at(&contact(), &discs, newton),
                preload_at(&contact(), &discs, falsi),
            );
            for (x, y) in [
                (a.overlap_um, b.overlap_um),
                (a.pin_force, b.pin_force),
                (a.no_load_torque, b.no_load_torque),
            ] {
                let close = (x - y).abs() <= 1e-9 * y.abs().max(1e-12);
                assert!(
                    close,
                    "{x} against {y}: Newton u {newton}, regula falsi {falsi}"
                );
            }
            preloaded += usize::from(b.pin_force > 0.0);
            bisected += usize::from((newton - falsi).abs() > 1e-12 * (hi - lo));
        }
        // Both kinds occur.
        assert!(
            preloaded > 500 && bisected > 10,
            "{preloaded} preloaded, {bisected} flat"
        );
    }

    /// `alike` as one serial pass per sum (the form before the lanes): the reference.
    fn alike_serial(contact: &PinContact, gaps: &[f64], pins: &AlikePins) -> Option<Preload> {
        let (mut lag, mut lead) = (f64::INFINITY, f64::INFINITY);
        for (g, r) in gaps.iter().zip(&pins.inverse) {
            if *r > 0.0 {
                lag = lag.min(g * r);
            } else {
                lead = lead.min(-(g * r));
            }
        }
        if (lag + lead).is_nan() || lag + lead >= 0.0 {
            return None;
        }
        let moment = |y: f64| -> f64 {
            gaps.iter()
                .zip(&pins.lever)
                .map(|(g, l)| (l * y - g).max(0.0) * l)
                .sum()
        };
        let y = root(moment, lag, -lead);
        let largest = gaps
            .iter()
            .zip(&pins.lever)
            .fold(0.0_f64, |m, (g, l)| m.max(l * y - g));
        let force = contact.force_at(largest);
        let drag: f64 = (gaps.iter().zip(&pins.lever).zip(&pins.arm))
            .map(|((g, l), h)| (l * y - g).max(0.0) * h)
            .sum();
        Some(Preload {
            overlap_um: 1000.0 * largest,
            pin_force: force,
            no_load_torque: contact.friction * 2.0 * (force / largest) * drag
                / contact.ratio
                / 1000.0,
        })
    }

    #[test]
    fn the_alike_balance_in_lanes_is_the_serial_one() {
        // 40 pins of which 38 carry a lever (0 to 39 of them kept: every remainder of the
        // lanes), gaps of a modification with errors that overlap the flanks or not.
        let mut pins = AlikePins::default();
        for i in 1..40 {
            let phi = 2.0 * std::f64::consts::PI * i as f64 / 40.0;
            if i != 20 {
                let lever = 0.9 * 39.0 * phi.sin() / (1.0 + 0.48 * phi.cos()).sqrt();
                pins.push(lever, 2.0 * phi.cos().abs() + 1.0);
            }
        }
        let law = contact();
        let (mut overlapping, mut free) = (0, 0);
        for case in 0..400 {
            let k = case as f64;
            let gap = |j: usize| {
                let phi = 2.0 * std::f64::consts::PI * j as f64 / 40.0;
                -0.004
                    + 0.003 * (1.0 - phi.sin())
                    + 1e-3 * (0.37 * k).sin() * phi.cos()
                    + 2e-4 * ((k + 3.0) * j as f64).sin()
            };
            let n = case % 39;
            let gaps: Vec<f64> = (0..n).map(gap).collect();
            let mut some = pins.clone();
            for v in [&mut some.lever, &mut some.inverse, &mut some.arm] {
                v.truncate(n);
            }
            // The balance is the serial one's root to rounding (the sums' order differs;
            // measured: 4.4e-15 relative at most over these cases).
            let (lag, lead) = some.flanks(&gaps);
            let serial = alike_serial(&law, &gaps, &some);
            match (alike(&law, &gaps, &some), serial) {
                (None, None) => free += 1,
                (Some(a), Some(b)) => {
                    overlapping += 1;
                    assert!(lag + lead < 0.0);
                    for (x, y) in [
                        (a.overlap_um, b.overlap_um),
                        (a.pin_force, b.pin_force),
                        (a.no_load_torque, b.no_load_torque),
                    ] {
                        assert!(
                            (x - y).abs() <= 1e-13 * y.abs(),
                            "case {case}: {x} against {y}"
                        );
                    }
                }
                (a, b) => panic!("case {case}: {a:?} against {b:?}"),
            }
        }
        assert!(overlapping > 100 && free > 50, "{overlapping} {free}");
    }
}
