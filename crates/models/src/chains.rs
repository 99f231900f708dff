//! Four chains of additions: the order in which the kernels that sum over pins in packed
//! instructions (the row table's own balances, the preload rule's rows) add their terms.
//! Term j goes to chain j mod 4 in order and the chains are added as (c0 + c1) + (c2 + c3):
//! four independent chains instead of one four times as long, and the same bits on every
//! instruction set (`balance::sums_in_lanes` keeps the same order in its row form).

/// Chains of additions.
pub(crate) const CHAINS: usize = 4;

/// Runs `$add!(c, j)` for every term j in 0..`$n` in order, c = j mod [`CHAINS`] its chain.
/// A macro, not a function taking a closure: a closure would be compiled without the
/// instruction set's features, out of line.
macro_rules! in_chains {
    ($n:expr, $add:ident) => {{
        let n: usize = $n;
        let whole = n / $crate::chains::CHAINS * $crate::chains::CHAINS;
        for j in (0..whole).step_by($crate::chains::CHAINS) {
            $add!(0, j);
            $add!(1, j + 1);
            $add!(2, j + 2);
            $add!(3, j + 3);
        }
        for j in whole..n {
            $add!(j - whole, j);
        }
    }};
}
pub(crate) use in_chains;

/// The chains' sums added in their fixed order, (c0 + c1) + (c2 + c3), in every lane.
#[inline(always)]
pub(crate) fn total<S: pulp::Simd>(simd: S, chains: [S::f64s; CHAINS]) -> S::f64s {
    let [c0, c1, c2, c3] = chains;
    simd.add_f64s(simd.add_f64s(c0, c1), simd.add_f64s(c2, c3))
}
