//! Exact sample percentiles, Hyndman & Fan (1996) definition 7 ("Sample
//! quantiles in statistical packages", The American Statistician 50(4),
//! 361–365), the default of R's `quantile()` and of `numpy.percentile`:
//! for n values and p in [0, 1], h = (n − 1)·p and the result interpolates
//! linearly between the order statistics of 0-based ranks floor(h) and
//! floor(h) + 1.
//!
//! Order statistics are found with `select_nth_unstable_by(f64::total_cmp)`
//! (expected linear time), never with a full sort. The slice is reordered;
//! no function here assumes anything about its order on entry, except the
//! `_of_sorted` ones and [`order_statistic_interval`], which take a sorted slice.

use crate::binomial::binomial_rank_interval;
use crate::conformity::{interpolate_beyond, Placement};

/// 0-based position h = (n − 1)·p of percent `percent` (clamped into
/// [0, 100]) among `count` values; `None` for NaN.
pub fn type7_position(count: usize, percent: f64) -> Option<(usize, f64)> {
    if count == 0 || percent.is_nan() {
        return None;
    }
    let fraction_of_range = percent.clamp(0.0, 100.0) / 100.0;
    let position = (count - 1) as f64 * fraction_of_range;
    let lower_rank = (position.floor() as usize).min(count - 1);
    let weight = if lower_rank + 1 < count {
        position - lower_rank as f64
    } else {
        0.0
    };
    Some((lower_rank, weight))
}

/// Linear interpolation between neighbouring order statistics.
fn interpolate(lower: f64, upper: f64, weight: f64) -> f64 {
    if weight == 0.0 || lower == upper {
        lower
    } else {
        lower + weight * (upper - lower)
    }
}

/// Smallest element by `f64::total_cmp`; `None` when empty.
fn total_min(values: &[f64]) -> Option<f64> {
    values.iter().copied().min_by(|a, b| a.total_cmp(b))
}

/// Type 7 percentile of `sorted_or_unsorted` at `percent` (0–100, clamped;
/// e.g. 99.865), reordering the slice in place by selection (not a full
/// sort). `None` for an empty slice or NaN `percent`.
///
/// Values are ordered by `f64::total_cmp` (NaN is not expected; a positive
/// NaN would sort above +inf, a negative one below −inf).
pub fn percentile_type7(sorted_or_unsorted: &mut [f64], percent: f64) -> Option<f64> {
    let (lower_rank, weight) = type7_position(sorted_or_unsorted.len(), percent)?;
    let (_, &mut lower, above) =
        sorted_or_unsorted.select_nth_unstable_by(lower_rank, f64::total_cmp);
    if weight == 0.0 {
        return Some(lower);
    }
    // Everything above the selected element is ≥ it, so the next order
    // statistic is the minimum of that part.
    let upper = total_min(above).unwrap_or(lower);
    Some(interpolate(lower, upper, weight))
}

/// Type 7 percentiles of `values` at each of `percents` (same rules as
/// [`percentile_type7`], same results bit for bit), in the order of
/// `percents`. The slice is reordered in place.
///
/// The needed order statistics are selected in increasing rank order, each
/// within the part of the slice above the previous one, so the cost is
/// O(n·k) at worst for k percentiles and close to O(n·log k) in practice.
pub fn percentiles_type7(values: &mut [f64], percents: &[f64]) -> Vec<Option<f64>> {
    let count = values.len();
    let splits: Vec<Option<(usize, f64)>> = percents
        .iter()
        .map(|&percent| type7_position(count, percent))
        .collect();
    values_at_splits(values, &splits)
}

/// The value at each (lower rank, weight) of `splits`, interpolated linearly towards the
/// next rank, from one selection pass; `None` where the split is `None`.
fn values_at_splits(values: &mut [f64], splits: &[Option<(usize, f64)>]) -> Vec<Option<f64>> {
    let ranks: Vec<usize> = splits
        .iter()
        .flatten()
        .flat_map(|&(rank, weight)| std::iter::once(rank).chain((weight > 0.0).then_some(rank + 1)))
        .collect();
    let order_statistics = select_ranks(values, ranks);
    let lookup = |rank: usize| order_statistic(&order_statistics, rank);
    splits
        .iter()
        .map(|split| {
            split.map(|(rank, weight)| {
                let lower = lookup(rank);
                if weight == 0.0 {
                    lower
                } else {
                    interpolate(lower, lookup(rank + 1), weight)
                }
            })
        })
        .collect()
}

/// The order statistics of the 0-based `ranks` (any order, duplicates allowed; each
/// below `values.len()`), as (rank, value) in increasing rank. Divide and conquer: the
/// middle rank is selected first, then the ranks below it within the part below and
/// those above within the part above, so k ranks cost O(n·log k) rather than O(n·k). The
/// slice is reordered in place; the values are the order statistics whatever the order of
/// selection.
fn select_ranks(values: &mut [f64], mut ranks: Vec<usize>) -> Vec<(usize, f64)> {
    fn select(values: &mut [f64], ranks: &[usize], offset: usize, out: &mut Vec<(usize, f64)>) {
        if ranks.is_empty() {
            return;
        }
        let middle = ranks.len() / 2;
        let rank = ranks[middle] - offset;
        let (below, &mut value, above) = values.select_nth_unstable_by(rank, f64::total_cmp);
        out.push((offset + rank, value));
        select(below, &ranks[..middle], offset, out);
        select(above, &ranks[middle + 1..], offset + rank + 1, out);
    }
    ranks.sort_unstable();
    ranks.dedup();
    let mut order_statistics = Vec::with_capacity(ranks.len());
    select(values, &ranks, 0, &mut order_statistics);
    order_statistics.sort_unstable_by_key(|&(rank, _)| rank);
    order_statistics
}

/// The value of `rank` among the (rank, value) pairs [`select_ranks`] gives; NaN for a
/// rank that was not selected.
fn order_statistic(order_statistics: &[(usize, f64)], rank: usize) -> f64 {
    order_statistics
        .binary_search_by_key(&rank, |&(r, _)| r)
        .map_or(f64::NAN, |index| order_statistics[index].1)
}

/// The values at fractional 0-based ranks `positions` of `values` (linear interpolation
/// between the neighbouring order statistics), from one selection pass; `None` for a
/// position outside [0, n − 1] or NaN, where the sample has no value to read. The slice is
/// reordered in place. Type 7 is position (n − 1)·p; a replicated design's figures also
/// read Hazen's n·p − ½ and Weibull's (n + 1)·p − 1 (run.rs).
pub fn values_at_ranks(values: &mut [f64], positions: &[f64]) -> Vec<Option<f64>> {
    let last = values.len() as f64 - 1.0;
    let split = |position: f64| {
        (0.0..=last).contains(&position).then(|| {
            let lower_rank = position.floor();
            (lower_rank as usize, position - lower_rank)
        })
    };
    let splits: Vec<Option<(usize, f64)>> = positions.iter().map(|&p| split(p)).collect();
    values_at_splits(values, &splits)
}

/// A type 7 percentile with its distribution-free confidence interval
/// ([`binomial_rank_interval`]); an end is `None` where the sample cannot bound it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PercentileWithInterval {
    /// The type 7 percentile.
    pub value: f64,
    /// X_(l), the interval's lower end.
    pub lower: Option<f64>,
    /// X_(u), the interval's upper end.
    pub upper: Option<f64>,
}

/// Type 7 percentiles of `values` at each of `percents` (bit for bit those of
/// [`percentiles_type7`]) with their distribution-free intervals at `confidence`, from one
/// selection pass over every rank needed. The slice is reordered in place.
pub fn percentiles_type7_with_intervals(
    values: &mut [f64],
    percents: &[f64],
    confidence: f64,
) -> Vec<Option<PercentileWithInterval>> {
    percentiles_with_intervals_beyond(values, percents, confidence, 0, Placement::Tail)
}

/// [`percentiles_type7_with_intervals`] as a conformity judgement reads them
/// ([`crate::conformity`]): `values` are the conforming ones, `beyond` samples lie beyond
/// the limits where `placement` puts them, and the ranks are among all
/// `values.len() + beyond` samples. A percentile or an interval end that reads a beyond
/// sample is ±∞. With `beyond` 0, bit for bit
/// [`percentiles_type7_with_intervals`].
pub fn percentiles_with_intervals_beyond(
    values: &mut [f64],
    percents: &[f64],
    confidence: f64,
    beyond: usize,
    placement: Placement,
) -> Vec<Option<PercentileWithInterval>> {
    let n = values.len();
    let count = n + beyond;
    let positions: Vec<Option<(usize, f64)>> = percents
        .iter()
        .map(|&percent| type7_position(count, percent))
        .collect();
    let intervals: Vec<(Option<usize>, Option<usize>)> = percents
        .iter()
        .map(|&percent| binomial_rank_interval(count, percent / 100.0, confidence))
        .collect();
    let mut ranks: Vec<usize> = Vec::new();
    for ((position, &(l, u)), &percent) in positions.iter().zip(&intervals).zip(percents) {
        let mut need = |rank: usize| ranks.extend(placement.value_rank(rank, n, beyond, percent));
        if let Some((lower_rank, weight)) = *position {
            need(lower_rank);
            if weight > 0.0 {
                need(lower_rank + 1);
            }
            l.into_iter().chain(u).for_each(need);
        }
    }
    let order_statistics = select_ranks(values, ranks);
    positions
        .iter()
        .zip(&intervals)
        .zip(percents)
        .map(|((position, &(l, u)), &percent)| {
            let lookup = |rank: usize| {
                placement
                    .value_rank(rank, n, beyond, percent)
                    .map_or(placement.beyond_value(percent), |k| {
                        order_statistic(&order_statistics, k)
                    })
            };
            position.map(|(lower_rank, weight)| {
                let lower = lookup(lower_rank);
                PercentileWithInterval {
                    value: if weight == 0.0 {
                        lower
                    } else {
                        interpolate_beyond(lower, lookup(lower_rank + 1), weight)
                    },
                    lower: l.map(lookup),
                    upper: u.map(lookup),
                }
            })
        })
        .collect()
}

/// Type 7 percentile of an already sorted slice (ascending by `f64::total_cmp`): the
/// same value as [`percentile_type7`], read off without selection. `None` for an empty
/// slice or NaN `percent`.
pub fn percentile_type7_of_sorted(sorted: &[f64], percent: f64) -> Option<f64> {
    let (lower_rank, weight) = type7_position(sorted.len(), percent)?;
    let upper = sorted
        .get(lower_rank + 1)
        .copied()
        .unwrap_or(sorted[lower_rank]);
    Some(interpolate(sorted[lower_rank], upper, weight))
}

/// Distribution-free interval [X_(l), X_(u)] for the `percent` percentile from the sorted
/// sample `sorted` (normal approximation to the binomial count of values below the
/// percentile): ranks ⌊n·p − z·√(n·p·(1 − p))⌋ and ⌈n·p + z·√(n·p·(1 − p))⌉, clamped to
/// the sample. `None` for an empty sample.
pub fn order_statistic_interval(sorted: &[f64], percent: f64, z: f64) -> Option<(f64, f64)> {
    let last = sorted.len().checked_sub(1)?;
    let (nf, p) = (sorted.len() as f64, (percent / 100.0).clamp(0.0, 1.0));
    let centre = nf * p;
    let reach = z * (nf * p * (1.0 - p)).sqrt();
    let lower_rank = ((centre - reach).floor().max(0.0) as usize).min(last);
    let upper_rank = ((centre + reach).ceil() as usize).min(last);
    Some((sorted[lower_rank], sorted[upper_rank]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SpecLimits;

    #[test]
    fn percentiles_with_intervals_match_the_plain_ones_and_the_sorted_ranks() {
        let values: Vec<f64> = (0..1001)
            .map(|i| ((i * 389) % 1001) as f64 * 0.25)
            .collect();
        let percents = [0.135, 2.275, 50.0, 97.725, 99.865];
        let plain = percentiles_type7(&mut values.clone(), &percents);
        let with = percentiles_type7_with_intervals(&mut values.clone(), &percents, 0.95);
        let mut sorted = values.clone();
        sorted.sort_unstable_by(f64::total_cmp);
        for ((p, a), b) in percents.iter().zip(&plain).zip(&with) {
            let b = b.unwrap();
            assert_eq!(a.unwrap().to_bits(), b.value.to_bits(), "{p}");
            let (l, u) = binomial_rank_interval(values.len(), p / 100.0, 0.95);
            assert_eq!(b.lower, l.map(|r| sorted[r]), "{p}");
            assert_eq!(b.upper, u.map(|r| sorted[r]), "{p}");
        }
    }

    #[test]
    fn conformity_percentiles_are_type7_of_the_samples_with_the_beyond_ones_placed() {
        // Reference: the samples beyond the limits materialised as ±1e300 where the
        // placement puts them, type 7 of the whole list; a result that reads one of them
        // is beyond (±∞), any other is the reference bit for bit, and so are the interval
        // ends (binomial ranks among all the samples).
        let values: Vec<f64> = (0..397)
            .map(|i| ((i * 151) % 397) as f64 * 0.01 - 1.0)
            .collect();
        let percents = [0.135, 2.275, 15.866, 50.0, 84.134, 97.725, 99.865];
        let limits = |lower: Option<f64>, upper: Option<f64>| SpecLimits { lower, upper };
        for placement in [
            Placement::Tail,
            Placement::of(Some(limits(None, Some(1.0)))),
            Placement::of(Some(limits(Some(0.0), None))),
        ] {
            for beyond in [0usize, 1, 3, 10, 60, 397] {
                let found = percentiles_with_intervals_beyond(
                    &mut values.clone(),
                    &percents,
                    0.95,
                    beyond,
                    placement,
                );
                for (&p, found) in percents.iter().zip(&found) {
                    let sentinel = placement.beyond_value(p).signum() * 1e300;
                    let mut all = values.clone();
                    all.extend(std::iter::repeat_n(sentinel, beyond));
                    all.sort_unstable_by(f64::total_cmp);
                    let reference = percentile_type7_of_sorted(&all, p).unwrap();
                    let found = found.unwrap();
                    if reference.abs() > 1e290 {
                        assert_eq!(found.value, placement.beyond_value(p), "{p} {beyond}");
                    } else {
                        assert_eq!(found.value.to_bits(), reference.to_bits(), "{p} {beyond}");
                    }
                    let (l, u) = binomial_rank_interval(all.len(), p / 100.0, 0.95);
                    let end = |rank: Option<usize>| {
                        rank.map(|r| {
                            if all[r].abs() > 1e290 {
                                placement.beyond_value(p)
                            } else {
                                all[r]
                            }
                        })
                    };
                    assert_eq!(found.lower, end(l), "{p} {beyond}");
                    assert_eq!(found.upper, end(u), "{p} {beyond}");
                }
            }
        }
    }

    #[test]
    fn values_at_ranks_read_type7_positions_bit_for_bit_and_nothing_outside() {
        let values: Vec<f64> = (0..257).map(|i| ((i * 97) % 257) as f64 * 0.3).collect();
        let percents = [0.0, 0.135, 15.866, 50.0, 99.865, 100.0];
        let positions: Vec<f64> = percents.iter().map(|p| 256.0 * (p / 100.0)).collect();
        let by_rank = values_at_ranks(&mut values.clone(), &positions);
        let by_type7 = percentiles_type7(&mut values.clone(), &percents);
        for ((p, a), b) in percents.iter().zip(&by_rank).zip(&by_type7) {
            assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "{p}");
        }
        // Hazen's rank of P0.135 among 257 values is 257·0.00135 − ½ < 0: no value.
        let outside = values_at_ranks(&mut values.clone(), &[-0.153, 256.5, f64::NAN]);
        assert_eq!(outside, vec![None, None, None]);
    }

    #[test]
    fn sorted_percentiles_equal_the_selected_ones() {
        let values: Vec<f64> = (0..101)
            .map(|i| ((i * 37) % 101) as f64 * 0.5 - 3.0)
            .collect();
        let mut sorted = values.clone();
        sorted.sort_unstable_by(f64::total_cmp);
        for percent in [0.0, 0.135, 2.5, 50.0, 97.725, 99.865, 100.0] {
            let selected = percentile_type7(&mut values.clone(), percent);
            assert_eq!(
                percentile_type7_of_sorted(&sorted, percent),
                selected,
                "{percent}"
            );
        }
        assert_eq!(percentile_type7_of_sorted(&[], 50.0), None);
    }

    fn one_to_ten() -> Vec<f64> {
        // Shuffled on purpose: the functions must not rely on order.
        vec![7.0, 3.0, 10.0, 1.0, 9.0, 2.0, 8.0, 5.0, 4.0, 6.0]
    }

    #[test]
    fn numpy_known_values() {
        // numpy.percentile(np.arange(1, 11), p) (linear = type 7):
        // 25 → 3.25, 50 → 5.5, 99.865 → 9.98785, 0.135 → 1.01215,
        // 0 → 1, 100 → 10, 90 → 9.1. (h = 9·p/100, e.g. 9·0.99865 = 8.98785
        // → 9 + 0.98785·(10 − 9).)
        let cases = [
            (25.0, 3.25),
            (50.0, 5.5),
            (99.865, 9.98785),
            (0.135, 1.01215),
            (0.0, 1.0),
            (100.0, 10.0),
            (90.0, 9.1),
        ];
        let mut values = one_to_ten();
        for (percent, expected) in cases {
            let got = percentile_type7(&mut values, percent).unwrap();
            assert!((got - expected).abs() < 1e-12, "p {percent}: {got}");
        }
        let percents: Vec<f64> = cases.iter().map(|&(p, _)| p).collect();
        let mut values = one_to_ten();
        let all = percentiles_type7(&mut values, &percents);
        for ((percent, expected), got) in cases.iter().zip(&all) {
            let got = got.unwrap();
            assert!((got - expected).abs() < 1e-12, "p {percent}: {got}");
        }
    }

    #[test]
    fn odd_count_and_duplicates() {
        // numpy.percentile([5, 1, 3, 3, 9], [10, 50, 75]) = [1.8, 3.0, 5.0]:
        // sorted 1 3 3 5 9, h = 4·p: 0.4 → 1 + 0.4·2, 2 → 3, 3 → 5.
        let mut values = vec![5.0, 1.0, 3.0, 3.0, 9.0];
        let got = percentiles_type7(&mut values, &[10.0, 50.0, 75.0]);
        assert!((got[0].unwrap() - 1.8).abs() < 1e-12);
        assert_eq!(got[1], Some(3.0));
        assert_eq!(got[2], Some(5.0));
    }

    #[test]
    fn empty_single_nan_and_clamping() {
        assert_eq!(percentile_type7(&mut [], 50.0), None);
        assert_eq!(percentile_type7(&mut [4.0], 50.0), Some(4.0));
        assert_eq!(percentile_type7(&mut [4.0, 6.0], f64::NAN), None);
        assert_eq!(percentile_type7(&mut [4.0, 6.0], -5.0), Some(4.0));
        assert_eq!(percentile_type7(&mut [4.0, 6.0], 500.0), Some(6.0));
        assert_eq!(percentiles_type7(&mut [], &[1.0, 50.0]), vec![None, None]);
        assert_eq!(
            percentiles_type7(&mut [1.0, 2.0], &[f64::NAN, 50.0]),
            vec![None, Some(1.5)]
        );
    }

    #[test]
    fn batch_matches_single_calls_bit_for_bit() {
        // LCG data (Knuth MMIX constants) with many ties.
        let mut state = 12345u64;
        let data: Vec<f64> = (0..5001)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((state >> 40) % 1000) as f64 / 7.0 - 50.0
            })
            .collect();
        let percents = [
            99.865, 0.135, 50.0, 0.0, 100.0, 25.0, 75.0, 50.0, 1.0, 99.0, 33.3,
        ];
        let mut batch_values = data.clone();
        let batch = percentiles_type7(&mut batch_values, &percents);
        let mut sorted = data.clone();
        sorted.sort_by(f64::total_cmp);
        for (&percent, got) in percents.iter().zip(&batch) {
            let mut single_values = data.clone();
            let single = percentile_type7(&mut single_values, percent).unwrap();
            assert_eq!(got.unwrap().to_bits(), single.to_bits());
            // Against a full sort (reference implementation of type 7).
            let h = 5000.0 * (percent / 100.0);
            let lower = sorted[h.floor() as usize];
            let upper = sorted[(h.floor() as usize + 1).min(5000)];
            let reference = lower + (h - h.floor()) * (upper - lower);
            assert!((single - reference).abs() < 1e-9);
        }
    }
}
