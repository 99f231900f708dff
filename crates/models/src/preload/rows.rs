//! The preload rule of many rows at once ([`PreloadRule::of_profiles`]): one row per
//! vector lane, the pins in a loop, so a row's profile, flanks, balance, largest approach
//! and drag are packed instructions without a sum across lanes (the row form,
//! [`PreloadRule::of_profile`], sums each row's pins in four lanes and adds them across).
//!
//! Each lane does the row form's arithmetic on its row: the same operations in the same
//! order (no product fused), the moments' four chains as `balance::sums_in_lanes` keeps
//! them (pin j in chain j mod 4, added as (c0 + c1) + (c2 + c3)), the same safeguarded
//! Newton steps stopped by the same tests, a lane frozen where its row stopped. So the
//! bits are the row form's, at every instruction set (tested). A row whose profile is not
//! finite somewhere is left to the row form (its minima pass over NaN as `f64::min` does,
//! which packed minima do not).

use pulp::Simd;

use super::{balance, Preload, PreloadRule, MAX_PINS};
use crate::chains::{in_chains, total, CHAINS};

/// The profiles of a block of rows, one column per parameter (every column as long as the
/// block): the modification (Δr_rp, Δr_p) and the pin circle, pin radius and eccentricity
/// errors (δr_p, δr_rp, δe), mm, as [`PreloadRule::of_profile`] takes them.
pub(crate) struct Profiles<'a> {
    pub equidistant: &'a [f64],
    pub shift: &'a [f64],
    pub pin_circle: &'a [f64],
    pub pin_radius: &'a [f64],
    pub eccentric: &'a [f64],
}

/// Lanes of the widest instruction set (AVX-512: eight doubles).
const MOST_LANES: usize = 8;

impl PreloadRule {
    /// [`PreloadRule::of_profile`] of every row of `profiles`, into `out` (as long as the
    /// block): the same bits.
    pub fn of_profiles(&self, profiles: &Profiles, out: &mut [(bool, Preload)]) {
        let n = out.len();
        for column in [
            profiles.equidistant,
            profiles.shift,
            profiles.pin_circle,
            profiles.pin_radius,
            profiles.eccentric,
        ] {
            assert_eq!(column.len(), n, "one profile per row");
        }
        self.columns.pins.arch.dispatch(Rows {
            rule: self,
            profiles,
            out,
        });
    }
}

/// The rule on a block of rows, as an operation `pulp` compiles once per instruction set.
struct Rows<'a> {
    rule: &'a PreloadRule,
    profiles: &'a Profiles<'a>,
    out: &'a mut [(bool, Preload)],
}

impl pulp::WithSimd for Rows<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let lanes = S::F64_LANES;
        assert!(lanes <= MOST_LANES);
        let mut gaps = [simd.splat_f64s(0.0); MAX_PINS];
        let n = self.out.len();
        for first in (0..n).step_by(lanes) {
            let rows = first..(first + lanes).min(n);
            let group = Group::new(simd, self.rule, self.profiles, rows.clone(), &mut gaps);
            let result = group.balance();
            let mut values = [[0.0; MOST_LANES]; 4];
            for (value, v) in values.iter_mut().zip(result) {
                S::as_mut_simd_f64s(&mut value[..lanes]).0[0] = v;
            }
            let [finite, overlapping, largest, drag] = values;
            for (lane, r) in rows.enumerate() {
                self.out[r] = if finite[lane] == 0.0 {
                    let p = self.profiles;
                    self.rule.of_profile(
                        (p.equidistant[r], p.shift[r]),
                        [p.pin_circle[r], p.pin_radius[r], p.eccentric[r]],
                    )
                } else if overlapping[lane] == 0.0 {
                    (false, Preload::NONE)
                } else {
                    (
                        true,
                        balance::preload_of(&self.rule.contact, largest[lane], drag[lane]),
                    )
                };
            }
        }
    }
}

/// Up to a vector's lanes of rows, their gaps filled.
struct Group<'a, S: Simd> {
    simd: S,
    rule: &'a PreloadRule,
    gaps: &'a [S::f64s],
    /// 1 in the lanes whose every gap is finite, else 0.
    finite: S::f64s,
}

impl<'a, S: Simd> Group<'a, S> {
    /// The gaps of the rows `rows` (the lanes past them take zero profiles, whose flanks do
    /// not overlap) at every pin with a lever: Δr_rp·f_e + Δr_p·f_s + δr_p·f_r − δr_rp +
    /// δe·f_x, added in the row form's order.
    #[inline(always)]
    fn new(
        simd: S,
        rule: &'a PreloadRule,
        p: &Profiles,
        rows: std::ops::Range<usize>,
        gaps: &'a mut [S::f64s; MAX_PINS],
    ) -> Self {
        // Whole vectors of a zero-padded copy (pulp's partial loads are functions of their
        // own, outside the dispatched builds).
        let mut lanes = [[0.0; MOST_LANES]; 5];
        let columns = [
            p.equidistant,
            p.shift,
            p.pin_circle,
            p.pin_radius,
            p.eccentric,
        ];
        for (lane, column) in lanes.iter_mut().zip(columns) {
            lane[..rows.len()].copy_from_slice(&column[rows.clone()]);
        }
        let [equidistant, shift, pin_circle, pin_radius, eccentric] =
            lanes.map(|lane| S::as_simd_f64s(&lane[..S::F64_LANES]).0[0]);
        let c = &rule.columns;
        let infinity = simd.splat_f64s(f64::INFINITY);
        let mut finite = simd.splat_f64s(1.0);
        let pins = c.index.len();
        for (j, gap) in gaps[..pins].iter_mut().enumerate() {
            let factor = |column: &[f64]| simd.splat_f64s(column[j]);
            let sum = simd.add_f64s(
                simd.mul_f64s(equidistant, factor(&c.equidistant)),
                simd.mul_f64s(shift, factor(&c.shift)),
            );
            let sum = simd.add_f64s(sum, simd.mul_f64s(pin_circle, factor(&c.radial)));
            let sum = simd.sub_f64s(sum, pin_radius);
            *gap = simd.add_f64s(sum, simd.mul_f64s(eccentric, factor(&c.eccentric)));
            // |g| < ∞ is false for ±∞ and NaN.
            let bounded = simd.less_than_f64s(simd.abs_f64s(*gap), infinity);
            finite = simd.select_f64s(bounded, finite, simd.splat_f64s(0.0));
        }
        Group {
            simd,
            rule,
            gaps: &gaps[..pins],
            finite,
        }
    }

    /// [`balance::alike`] in every lane: (finite, overlapping, largest approach, drag),
    /// the flags 1 or 0.
    #[inline(always)]
    fn balance(&self) -> [S::f64s; 4] {
        let simd = self.simd;
        let (zero, one, half) = (
            simd.splat_f64s(0.0),
            simd.splat_f64s(1.0),
            simd.splat_f64s(0.5),
        );
        let (lag, lead) = self.flanks();
        // NaN gaps are the row form's (finite = 0); here the flanks are finite or +∞.
        let overlapping = simd.less_than_f64s(simd.add_f64s(lag, lead), zero);
        let (mut lo, mut hi) = (lag, simd.neg_f64s(lead));
        let mut y = simd.mul_f64s(half, simd.add_f64s(lo, hi));
        let mut open = overlapping;
        let (root_tolerance, step_tolerance) = (simd.splat_f64s(1e-13), simd.splat_f64s(1e-15));
        for _ in 0..balance::ALIKE_STEPS {
            if simd.first_true_m64s(open) == S::F64_LANES {
                break;
            }
            let (moment, slope, size) = self.sums(y);
            // The two flanks' moments cancel to rounding: y is the root.
            let root = simd.less_than_or_equal_f64s(
                simd.abs_f64s(moment),
                simd.mul_f64s(root_tolerance, size),
            );
            open = simd.and_m64s(open, not(simd, root));
            let below = simd.less_than_f64s(moment, zero);
            lo = simd.select_f64s(simd.and_m64s(open, below), y, lo);
            hi = simd.select_f64s(simd.and_m64s(open, not(simd, below)), y, hi);
            let newton = simd.sub_f64s(y, simd.div_f64s(moment, slope));
            let inside = simd.and_m64s(
                simd.greater_than_f64s(newton, lo),
                simd.less_than_f64s(newton, hi),
            );
            let middle = simd.mul_f64s(half, simd.add_f64s(lo, hi));
            let next = simd.select_f64s(inside, newton, middle);
            let scale = simd.max_f64s(simd.abs_f64s(simd.sub_f64s(hi, lo)), simd.abs_f64s(y));
            let settled = simd.less_than_or_equal_f64s(
                simd.abs_f64s(simd.sub_f64s(next, y)),
                simd.mul_f64s(step_tolerance, scale),
            );
            y = simd.select_f64s(open, next, y);
            open = simd.and_m64s(open, not(simd, settled));
        }
        let (largest, drag) = self.largest_and_drag(y);
        [
            self.finite,
            simd.select_f64s(overlapping, one, zero),
            largest,
            drag,
        ]
    }

    /// (L, K) of every lane: the smallest g/l over the drive flank and the smallest −g/l
    /// over the coast flank, rad (as `AlikePins::flanks`: g times 1/l; a minimum does not
    /// depend on the order it is taken in).
    #[inline(always)]
    fn flanks(&self) -> (S::f64s, S::f64s) {
        let simd = self.simd;
        let infinity = simd.splat_f64s(f64::INFINITY);
        let (mut lag, mut lead) = (infinity, infinity);
        for (&g, &r) in self.gaps.iter().zip(&self.rule.columns.pins.inverse) {
            let ratio = simd.mul_f64s(g, simd.splat_f64s(r));
            if r > 0.0 {
                lag = simd.min_f64s(lag, ratio);
            } else {
                lead = simd.min_f64s(lead, simd.neg_f64s(ratio));
            }
        }
        (lag, lead)
    }

    /// T(y) = Σ max(0, l·y − g)·l, its slope Σ l² and its terms' size Σ d·|l| over the
    /// loaded pins of every lane, in `balance::sums_in_lanes`'s four chains.
    #[inline(always)]
    fn sums(&self, y: S::f64s) -> (S::f64s, S::f64s, S::f64s) {
        let simd = self.simd;
        let zero = simd.splat_f64s(0.0);
        let (mut sum, mut slope, mut size) = ([zero; CHAINS], [zero; CHAINS], [zero; CHAINS]);
        let levers = &self.rule.columns.pins.lever;
        // Pin j's terms into chain c (a macro: a closure would be compiled without the
        // instruction set's features, out of line).
        macro_rules! add {
            ($c:expr, $j:expr) => {{
                let (c, j) = ($c, $j);
                let l = levers[j];
                let d = simd.sub_f64s(simd.mul_f64s(simd.splat_f64s(l), y), self.gaps[j]);
                let carries = simd.greater_than_f64s(d, zero);
                let term = simd.mul_f64s(d, simd.splat_f64s(l));
                sum[c] = simd.add_f64s(sum[c], simd.select_f64s(carries, term, zero));
                let square = simd.splat_f64s(l * l);
                slope[c] = simd.add_f64s(slope[c], simd.select_f64s(carries, square, zero));
                let term = simd.mul_f64s(d, simd.splat_f64s(l.abs()));
                size[c] = simd.add_f64s(size[c], simd.select_f64s(carries, term, zero));
            }};
        }
        in_chains!(self.gaps.len(), add);
        (total(simd, sum), total(simd, slope), total(simd, size))
    }

    /// max(0, max_j (l_j·y − g_j)) and Σ d_j·h_j over the loaded pins (four chains, as
    /// `balance::drag_in_lanes`) of every lane.
    #[inline(always)]
    fn largest_and_drag(&self, y: S::f64s) -> (S::f64s, S::f64s) {
        let simd = self.simd;
        let zero = simd.splat_f64s(0.0);
        let pins = &self.rule.columns.pins;
        let mut largest = zero;
        let mut drag = [zero; CHAINS];
        macro_rules! add {
            ($c:expr, $j:expr) => {{
                let (c, j) = ($c, $j);
                let l = simd.splat_f64s(pins.lever[j]);
                let d = simd.sub_f64s(simd.mul_f64s(l, y), self.gaps[j]);
                largest = simd.max_f64s(largest, d);
                let term = simd.mul_f64s(d, simd.splat_f64s(pins.arm[j]));
                let carries = simd.greater_than_f64s(d, zero);
                drag[c] = simd.add_f64s(drag[c], simd.select_f64s(carries, term, zero));
            }};
        }
        in_chains!(self.gaps.len(), add);
        (largest, total(simd, drag))
    }
}

/// The lanes where `mask` is false.
#[inline(always)]
fn not<S: Simd>(simd: S, mask: S::m64s) -> S::m64s {
    let zero = simd.splat_f64s(0.0);
    simd.xor_m64s(mask, simd.equal_f64s(zero, zero))
}

/// [`PreloadRule::of_profiles`] built for the instruction set `width` (the tests compare
/// every width's bits).
#[cfg(test)]
pub(super) fn of_profiles_in(
    width: crate::reducer::test_streams::Width,
    rule: &PreloadRule,
    profiles: &Profiles,
    out: &mut [(bool, Preload)],
) {
    width.apply(Rows {
        rule,
        profiles,
        out,
    });
}
