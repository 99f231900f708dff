//! The folds of a row table's runs over every rotation (windows.rs `RowTable`): for each
//! run entry m (t_m, 1/l_m) of a flank, the extreme over the rotations s of
//! ```text
//! r(m, s) = (t_m + δr_i·f_r,m + δt_i·f_t,m − ρ_i)·(1/l_m),   i = (m − s) mod z_p
//! lag[s]   = min over the drive entries,   coast[s] = max over the coast entries
//! ```
//! the loop that carries most of `rv_lost_motion`'s cost. It runs over the rotations, a
//! contiguous slice of the pins' columns reversed and doubled, and is compiled three times:
//! for the baseline x86-64 (two lanes), and for AVX2 and AVX-512 (four and eight), chosen
//! once by the processor's own report ([`Kernel::detect`]); a binary built for the
//! baseline runs everywhere and uses the wider instructions where they exist. Every width
//! gives the same bits: a difference, a product and a comparison are exact IEEE operations
//! whatever the lane count, no product is fused, and a minimum or maximum does not depend
//! on the order of its comparisons (tested: `folds_agree_to_the_bit_in_every_width`).

use std::ops::Range;

/// One flank of one run: its entries, the run's t and 1/l, the pins' factors f_r, f_t
/// (indexed by entry), and whether its extreme is the largest (coast) or the least.
pub(crate) struct Flank<'a> {
    pub entries: Range<usize>,
    pub run: &'a [f64],
    pub inverse: &'a [f64],
    pub radial: &'a [f64],
    pub tangential: &'a [f64],
    pub largest: bool,
}

/// The pins' columns reversed and doubled (entry m's pins over the rotations 0..z_p are
/// `[z_p − 1 − m .. 2·z_p − 1 − m]`): the radii ρ, and the radial and tangential errors
/// when any pin is out of place.
pub(crate) struct Turned<'a> {
    pub radius: &'a [f64],
    pub placed: Option<(&'a [f64], &'a [f64])>,
}

/// Folds every entry of `flank` into `extreme` (one value per rotation), with the widest
/// instructions `arch` (the processor's report, `pulp::Arch::new()`) allows.
pub(crate) fn fold_flank(arch: pulp::Arch, extreme: &mut [f64], flank: &Flank, turned: &Turned) {
    arch.dispatch(Fold {
        extreme,
        flank,
        turned,
    })
}

/// [`fold_all`] as the operation `pulp` compiles once per instruction set and calls
/// within a function that enables it (so that the plain loops below vectorise for it).
struct Fold<'a, 'b> {
    extreme: &'a mut [f64],
    flank: &'a Flank<'b>,
    turned: &'a Turned<'b>,
}

impl pulp::WithSimd for Fold<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        fold_all(self.extreme, self.flank, self.turned)
    }
}

/// Every entry of the flank (inlined into each kernel, which compiles it for its width):
/// rotations in blocks of [`WIDE`], then of [`LANES`], held in registers while every
/// entry passes, then the rotations left over one by one. A block's comparisons form one
/// chain per register, so that the wide block (two AVX-512 registers, four AVX2 ones)
/// keeps the processor busy while each comparison waits for the one before it.
#[inline(always)]
fn fold_all(extreme: &mut [f64], flank: &Flank, turned: &Turned) {
    let pins = extreme.len();
    let wide = pins / WIDE * WIDE;
    for block in (0..wide).step_by(WIDE) {
        fold_block::<WIDE>(extreme, block, flank, turned);
    }
    let whole = wide + (pins - wide) / LANES * LANES;
    for block in (wide..whole).step_by(LANES) {
        fold_block::<LANES>(extreme, block, flank, turned);
    }
    for (s, e) in extreme.iter_mut().enumerate().skip(whole) {
        for m in flank.entries.clone() {
            let at = pins - 1 - m + s;
            *e = extreme_of_flank(flank.largest, *e, ratio(flank, turned, m, at));
        }
    }
}

/// One block of N rotations from `block` (the flank's kind chosen once for the block).
#[inline(always)]
fn fold_block<const N: usize>(extreme: &mut [f64], block: usize, flank: &Flank, turned: &Turned) {
    let lanes: &mut [f64; N] = (&mut extreme[block..block + N])
        .try_into()
        .expect("a block of N");
    match (turned.placed, flank.largest) {
        (None, true) => block_of::<N, true, false>(lanes, block, flank, turned),
        (None, false) => block_of::<N, false, false>(lanes, block, flank, turned),
        (Some(_), true) => block_of::<N, true, true>(lanes, block, flank, turned),
        (Some(_), false) => block_of::<N, false, true>(lanes, block, flank, turned),
    }
}

/// The lanes of one block of rotations starting at `block`, every entry folded in.
#[inline(always)]
fn block_of<const N: usize, const LARGEST: bool, const PLACED: bool>(
    lanes: &mut [f64; N],
    block: usize,
    flank: &Flank,
    turned: &Turned,
) {
    let pins = flank.run.len();
    let mut acc = *lanes;
    for m in flank.entries.clone() {
        let at = pins - 1 - m + block;
        let (t, v) = (flank.run[m], flank.inverse[m]);
        let rho: &[f64; N] = turned.radius[at..at + N].try_into().expect("lanes");
        if PLACED {
            let (radial, tangential) = turned.placed.expect("placed pins");
            let radial: &[f64; N] = radial[at..at + N].try_into().expect("lanes");
            let tangential: &[f64; N] = tangential[at..at + N].try_into().expect("lanes");
            let (fr, ft) = (flank.radial[m], flank.tangential[m]);
            for lane in 0..N {
                let r = (t + radial[lane] * fr + tangential[lane] * ft - rho[lane]) * v;
                acc[lane] = extreme_of::<LARGEST>(acc[lane], r);
            }
        } else {
            for lane in 0..N {
                acc[lane] = extreme_of::<LARGEST>(acc[lane], (t - rho[lane]) * v);
            }
        }
    }
    *lanes = acc;
}

/// r(m, s) of entry m with the pins' columns read at `at` (= z_p − 1 − m + s).
#[inline(always)]
fn ratio(flank: &Flank, turned: &Turned, m: usize, at: usize) -> f64 {
    gap_at(flank, turned, m, at) * flank.inverse[m]
}

/// g(m, s), the gap of entry m's pin with the pins' columns read at `at` (= z_p − 1 − m
/// + s): t_m + δr_i·f_r,m + δt_i·f_t,m − ρ_i.
#[inline(always)]
fn gap_at(flank: &Flank, turned: &Turned, m: usize, at: usize) -> f64 {
    let t = flank.run[m];
    match turned.placed {
        Some((radial, tangential)) => {
            t + radial[at] * flank.radial[m] + tangential[at] * flank.tangential[m]
                - turned.radius[at]
        }
        None => t - turned.radius[at],
    }
}

/// [`extreme_of`] with the flank's choice at run time.
#[inline(always)]
fn extreme_of_flank(largest: bool, e: f64, r: f64) -> f64 {
    if largest {
        extreme_of::<true>(e, r)
    } else {
        extreme_of::<false>(e, r)
    }
}

/// The extreme of `e` and `r`: the larger with `LARGEST`, else the smaller (`e` on a tie).
#[inline(always)]
fn extreme_of<const LARGEST: bool>(e: f64, r: f64) -> f64 {
    if LARGEST {
        if r > e {
            r
        } else {
            e
        }
    } else if r < e {
        r
    } else {
        e
    }
}

/// Rotations per block: one AVX-512 register, two AVX2 or four SSE2 ones.
const LANES: usize = 8;

/// Rotations per wide block: two AVX-512 registers, four AVX2 ones (the widths tried on
/// the RV-20E: 16 the fastest; 24, 32 and 40 spill registers and are slower).
const WIDE: usize = 16;

#[cfg(test)]
mod tests {
    use super::super::test_streams::{doubled, every_width, stream};
    use super::*;

    #[test]
    fn folds_agree_to_the_bit_in_every_width() {
        // Every kernel this processor runs against the baseline, on runs of 40 and 37
        // entries (a remainder for every lane count), both flanks, with and without pins
        // out of place; ties included (a repeated radius).
        let mut next = stream(7);
        for pins in [40, 37, 8] {
            let column = |next: &mut dyn FnMut() -> f64, scale: f64| -> Vec<f64> {
                (0..pins).map(|_| scale * next()).collect()
            };
            let run = column(&mut next, 3e-3);
            let inverse: Vec<f64> = (0..pins)
                .map(|m| {
                    if m < pins / 2 {
                        50.0 + m as f64
                    } else {
                        -60.0 - m as f64
                    }
                })
                .collect();
            let (fr, ft) = (column(&mut next, 1.0), column(&mut next, 1.0));
            let mut radius = column(&mut next, 4e-3);
            radius[3] = radius[5];
            let (radius, radial, tangential) = (
                doubled(&radius),
                doubled(&column(&mut next, 5e-3)),
                doubled(&column(&mut next, 5e-3)),
            );
            for placed in [None, Some((&radial[..], &tangential[..]))] {
                let turned = Turned {
                    radius: &radius,
                    placed,
                };
                for (entries, largest) in [(0..pins / 2, false), (pins / 2..pins, true)] {
                    let flank = Flank {
                        entries,
                        run: &run,
                        inverse: &inverse,
                        radial: &fr,
                        tangential: &ft,
                        largest,
                    };
                    let start = if largest {
                        f64::NEG_INFINITY
                    } else {
                        f64::INFINITY
                    };
                    let mut reference = vec![start; pins];
                    fold_all(&mut reference, &flank, &turned);
                    // The reference itself against the plain definition.
                    for (s, r) in reference.iter().enumerate() {
                        let direct = flank
                            .entries
                            .clone()
                            .map(|m| {
                                let at = pins - 1 - m + s;
                                match placed {
                                    Some((a, b)) => {
                                        (run[m] + a[at] * fr[m] + b[at] * ft[m] - radius[at])
                                            * inverse[m]
                                    }
                                    None => (run[m] - radius[at]) * inverse[m],
                                }
                            })
                            .fold(start, |a, v| if largest { a.max(v) } else { a.min(v) });
                        assert_eq!(r.to_bits(), direct.to_bits(), "rotation {s}");
                    }
                    // The baseline, AVX2 and AVX-512 builds of the fold where the
                    // processor runs them, the dispatch, and the model's entry point.
                    let mut widths: Vec<(&str, Vec<f64>)> = Vec::new();
                    for (name, width) in every_width() {
                        let mut folded = vec![start; pins];
                        width.apply(Fold {
                            extreme: &mut folded,
                            flank: &flank,
                            turned: &turned,
                        });
                        widths.push((name, folded));
                    }
                    let mut folded = vec![start; pins];
                    fold_flank(pulp::Arch::new(), &mut folded, &flank, &turned);
                    widths.push(("fold_flank", folded));
                    for (name, folded) in widths {
                        let same = folded
                            .iter()
                            .zip(&reference)
                            .all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "{name}, {pins} pins, placed {}", placed.is_some());
                    }
                }
            }
        }
    }
}
