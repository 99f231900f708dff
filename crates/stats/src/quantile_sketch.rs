//! Relative-accuracy, mergeable quantile sketch in the style of DDSketch
//! (Masson, Rim & Lee, "DDSketch: A Fast and Fully-Mergeable Quantile Sketch
//! with Relative-Error Guarantees", PVLDB 12(12), 2019), with the
//! "linearly interpolated" logarithmic index mapping of section 4.2 of that
//! paper at a power-of-two resolution, so that the index is read straight from
//! the bits of the `f64`.
//!
//! # Index mapping
//!
//! Write |x| = 2^e·(1 + t) with t in [0, 1) (the IEEE 754 exponent and
//! mantissa). Each binade [2^e, 2^(e+1)) is cut into 2^m buckets of equal
//! width in t, and the bucket index is the top 12 + m bits of |x|'s
//! representation: `index = bits(|x|) >> (52 − m)`. The bucket bounds are then
//! exact doubles, lo = from_bits(index << (52 − m)) and hi the next bound, and a
//! bucket spans a ratio hi / lo = 1 + 2^−m / (1 + t) ≤ 1 + 2^−m. The resolution m
//! is the smallest with 1 + 2^−m ≤ gamma = (1 + alpha) / (1 − alpha). The
//! representative value 2·lo·hi / (lo + hi) is then within a relative error
//! (hi − lo) / (hi + lo) ≤ (gamma − 1) / (gamma + 1) = alpha of every value in
//! the bucket, in particular of the true order statistic. (For alpha = 1e-3,
//! m = 9: 512 buckets per binade, a worst-case relative error of 9.8e-4.)
//!
//! # Layout
//!
//! Positive values and negative values (by |x|) go to two dense stores of
//! `u64` counts with an index offset that grows in either direction as
//! needed. Values with |x| < 1e-30 (including ±0) go to a zero count and are
//! reported as 0.0. Values with |x| > 1e30 (including ±inf) are clamped to
//! |x| = 1e30, i.e. counted in the top bucket. NaN is ignored (not counted).
//!
//! Counts are integers, so merging is exact and order-independent: merging
//! sketches in any order gives the same bucket counts.
//!
//! # Why not the `sketches-ddsketch` crate
//!
//! That crate (a port of DataDog's Go DDSketch) has the same guarantee and merge, but
//! keys a value by `ln(v) / ln(gamma)`: a libm logarithm per value, whose last bit the
//! platform's libm decides, so a value near a bucket bound may land in another bucket on
//! another machine, and the reports must be bit-identical everywhere. It also collapses
//! its lowest buckets beyond `max_num_bins` (2048 by default), which loses the lower
//! tail's accuracy that a lower spec limit needs, sends |v| below `min_value` (1e-9 by
//! default) to zero, and exposes neither its buckets (the histogram drawn from a sketch
//! needs their bounds, [`bucket_representative`]) nor a byte format (a shard file carries
//! the sketch). The index read from the bits here needs no logarithm and no collapse.

use std::fmt;

/// Values with a magnitude below this go to the zero count.
pub const ZERO_THRESHOLD: f64 = 1e-30;
/// Values with a magnitude above this are clamped to it (top bucket).
pub const CLAMP_MAGNITUDE: f64 = 1e30;
/// Smallest accepted relative accuracy; smaller requests are raised to it
/// (bounds the memory: 2^16 buckets per binade, about 1.3·10^7 per sign over
/// 1e-30..1e30).
pub const MIN_RELATIVE_ACCURACY: f64 = 1e-5;
/// Largest accepted relative accuracy; larger requests are lowered to it.
pub const MAX_RELATIVE_ACCURACY: f64 = 0.49;
/// Relative accuracy used when the requested one is NaN.
pub const DEFAULT_RELATIVE_ACCURACY: f64 = 0.01;

/// Number of buckets allocated the first time a store receives a value.
const INITIAL_STORE_LENGTH: i64 = 128;

const SIGN_BIT: u64 = 1 << 63;
/// Values inserted per pass of [`QuantileSketch::insert_slice`].
const INSERT_PIECE: usize = 256;

/// Smallest m ≥ 0 with 1 + 2^−m ≤ gamma: buckets per binade are 2^m.
fn subbucket_bits(gamma: f64) -> u32 {
    (0..=52)
        .find(|&m| 1.0 + 0.5f64.powi(m as i32) <= gamma)
        .unwrap_or(52)
}

/// Representative value of a bucket [lo, hi] (both of the same sign, or both
/// zero): the harmonic mean 2·lo·hi / (lo + hi), whose relative error is at
/// most alpha for every value of the bucket. Returns 0 for the zero bucket.
pub fn bucket_representative(lo: f64, hi: f64) -> f64 {
    let sum = lo + hi;
    if sum == 0.0 {
        0.0
    } else {
        2.0 * lo * hi / sum
    }
}

/// Error returned by [`QuantileSketch::merge`] when the two sketches were
/// built with different relative accuracies (their buckets do not line up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SketchMismatch {
    /// Relative accuracy of the sketch merged into.
    pub this_relative_accuracy: f64,
    /// Relative accuracy of the sketch that could not be merged.
    pub other_relative_accuracy: f64,
}

impl fmt::Display for SketchMismatch {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            formatter,
            "cannot merge quantile sketches with different relative accuracies ({} and {})",
            self.this_relative_accuracy, self.other_relative_accuracy
        )
    }
}

impl std::error::Error for SketchMismatch {}

/// Dense counts for a contiguous range of bucket indices.
#[derive(Clone, Debug, Default)]
struct Store {
    /// `counts[i]` is the count of bucket index `offset + i`.
    counts: Vec<u64>,
    offset: i64,
}

impl Store {
    /// Counts one value in each bucket of `indices` (all inside
    /// [lowest_index, highest_index]).
    fn add_all(&mut self, indices: &[i64], lowest_index: i64, highest_index: i64) {
        let mut done = 0;
        while done < indices.len() {
            // Count with the store's range in registers until an index falls outside it
            // (one predictable branch per value), then grow and go on.
            let offset = self.offset;
            let counts = &mut self.counts[..];
            for &index in &indices[done..] {
                let position = index.wrapping_sub(offset) as u64;
                if position >= counts.len() as u64 {
                    break;
                }
                counts[position as usize] += 1;
                done += 1;
            }
            if let Some(&index) = indices.get(done) {
                self.grow_to_include(index, index, lowest_index, highest_index);
            }
        }
    }

    /// Makes the dense range cover [from, to] (both inside
    /// [lowest_index, highest_index]), with amortised slack.
    #[cold]
    fn grow_to_include(&mut self, from: i64, to: i64, lowest_index: i64, highest_index: i64) {
        let length = self.counts.len() as i64;
        let (new_low, new_high) = if length == 0 {
            let half = INITIAL_STORE_LENGTH / 2;
            (from.min(to - half), to.max(from + half))
        } else {
            let current_high = self.offset + length - 1;
            let slack = length.max(INITIAL_STORE_LENGTH);
            let new_low = if from < self.offset {
                from.min(self.offset - slack)
            } else {
                self.offset
            };
            let new_high = if to > current_high {
                to.max(current_high + slack)
            } else {
                current_high
            };
            (new_low, new_high)
        };
        let new_low = new_low.max(lowest_index).min(from);
        let new_high = new_high.min(highest_index).max(to);
        let mut counts = vec![0u64; (new_high - new_low + 1) as usize];
        if length > 0 {
            let shift = (self.offset - new_low) as usize;
            counts[shift..shift + length as usize].copy_from_slice(&self.counts);
        }
        self.counts = counts;
        self.offset = new_low;
    }

    /// Non-zero buckets as (index, count), increasing index.
    fn non_zero(&self) -> impl DoubleEndedIterator<Item = (i64, u64)> + '_ {
        let offset = self.offset;
        self.counts
            .iter()
            .enumerate()
            .filter(|(_, &count)| count > 0)
            .map(move |(position, &count)| (offset + position as i64, count))
    }

    fn merge(&mut self, other: &Store, lowest_index: i64, highest_index: i64) {
        let mut non_zero = other.non_zero();
        let Some((first, _)) = non_zero.next() else {
            return;
        };
        let last = non_zero.next_back().map_or(first, |(index, _)| index);
        let length = self.counts.len() as i64;
        if length == 0 || first < self.offset || last >= self.offset + length {
            self.grow_to_include(first, last, lowest_index, highest_index);
        }
        for (index, count) in other.non_zero() {
            self.counts[(index - self.offset) as usize] += count;
        }
    }
}

impl PartialEq for Store {
    /// Equal when the non-zero bucket counts are equal (the dense layout may
    /// differ with the insertion order).
    fn eq(&self, other: &Store) -> bool {
        self.non_zero().eq(other.non_zero())
    }
}

/// A [`QuantileSketch`]'s counts as plain numbers: what a shard's partial result stores.
#[derive(Clone, Debug, PartialEq)]
pub struct SketchParts {
    /// Relative accuracy alpha.
    pub relative_accuracy: f64,
    /// Values counted as zero.
    pub zero_count: u64,
    /// Non-empty buckets of positive values as (index, count), increasing index.
    pub positive: Vec<(i64, u64)>,
    /// Non-empty buckets of negative values (by magnitude) as (index, count), increasing
    /// index.
    pub negative: Vec<(i64, u64)>,
}

/// Mergeable quantile sketch with relative accuracy `alpha` (see the module
/// documentation for the index mapping and the guarantees).
///
/// Two sketches compare equal when they have the same relative accuracy and
/// the same bucket counts (regardless of how the dense stores were grown).
#[derive(Clone, Debug, PartialEq)]
pub struct QuantileSketch {
    relative_accuracy: f64,
    /// 52 − m: the index is the magnitude's bits shifted right by this.
    shift: u32,
    lowest_index: i64,
    highest_index: i64,
    positive: Store,
    negative: Store,
    zero_count: u64,
    count: u64,
}

impl QuantileSketch {
    /// Creates an empty sketch with relative accuracy `relative_accuracy`
    /// (alpha, e.g. 0.01 for 1 %). Values outside
    /// [`MIN_RELATIVE_ACCURACY`, `MAX_RELATIVE_ACCURACY`] are clamped into
    /// that range and NaN gives [`DEFAULT_RELATIVE_ACCURACY`]; read the value
    /// actually used back with [`QuantileSketch::relative_accuracy`].
    pub fn new(relative_accuracy: f64) -> QuantileSketch {
        let alpha = if relative_accuracy.is_nan() {
            DEFAULT_RELATIVE_ACCURACY
        } else {
            relative_accuracy.clamp(MIN_RELATIVE_ACCURACY, MAX_RELATIVE_ACCURACY)
        };
        let gamma = (1.0 + alpha) / (1.0 - alpha);
        let shift = 52 - subbucket_bits(gamma);
        QuantileSketch {
            relative_accuracy: alpha,
            shift,
            lowest_index: (ZERO_THRESHOLD.to_bits() >> shift) as i64,
            highest_index: (CLAMP_MAGNITUDE.to_bits() >> shift) as i64,
            positive: Store::default(),
            negative: Store::default(),
            zero_count: 0,
            count: 0,
        }
    }

    /// The relative accuracy alpha actually used.
    pub fn relative_accuracy(&self) -> f64 {
        self.relative_accuracy
    }

    /// The bucket ratio bound gamma = (1 + alpha) / (1 - alpha).
    pub fn gamma(&self) -> f64 {
        (1.0 + self.relative_accuracy) / (1.0 - self.relative_accuracy)
    }

    /// Bucket index of a magnitude in [ZERO_THRESHOLD, CLAMP_MAGNITUDE] (the mapping
    /// `insert_slice` applies inline).
    #[cfg(test)]
    fn index_of(&self, magnitude: f64) -> i64 {
        (magnitude.to_bits() >> self.shift) as i64
    }

    /// Lower and upper magnitude bounds of bucket `index` (exact).
    fn bucket_bounds(&self, index: i64) -> (f64, f64) {
        (
            f64::from_bits((index as u64) << self.shift),
            f64::from_bits(((index + 1) as u64) << self.shift),
        )
    }

    /// Adds one value. |x| < 1e-30 (and ±0) counts as zero, |x| > 1e30
    /// (and ±inf) is clamped to 1e30, NaN is ignored.
    #[inline]
    pub fn insert(&mut self, x: f64) {
        self.insert_slice(std::slice::from_ref(&x));
    }

    /// Adds every value of `xs` (same rules as [`QuantileSketch::insert`]).
    pub fn insert_slice(&mut self, xs: &[f64]) {
        self.insert_mapped(xs, |x| x);
    }

    /// Adds (x − center)·inverse_scale for every x of `xs`, without a buffer of the
    /// standardised values (same rules as [`QuantileSketch::insert`] on the result).
    pub fn insert_standardised(&mut self, xs: &[f64], center: f64, inverse_scale: f64) {
        self.insert_mapped(xs, |x| (x - center) * inverse_scale);
    }

    #[inline(always)]
    fn insert_mapped(&mut self, xs: &[f64], map: impl Fn(f64) -> f64) {
        // Two passes per piece: compact the bucket indices by sign without a
        // data-dependent branch (centred data has a random sign), then count them with
        // each store's range in registers.
        let zero_bits = ZERO_THRESHOLD.to_bits();
        let clamp_bits = CLAMP_MAGNITUDE.to_bits();
        let mut positive = [0i64; INSERT_PIECE];
        let mut negative = [0i64; INSERT_PIECE];
        for piece in xs.chunks(INSERT_PIECE) {
            let (mut n_positive, mut n_negative) = (0usize, 0usize);
            for &x in piece {
                let bits = map(x).to_bits();
                let magnitude = bits & !SIGN_BIT;
                if !(zero_bits..=clamp_bits).contains(&magnitude) {
                    // Rare: zero, tiny, huge, infinite or NaN.
                    self.insert_outside_range(f64::from_bits(bits));
                    continue;
                }
                let index = (magnitude >> self.shift) as i64;
                let is_negative = bits >> 63 != 0;
                // Both writes stay in bounds: each count is at most the values seen so far.
                positive[n_positive & (INSERT_PIECE - 1)] = index;
                negative[n_negative & (INSERT_PIECE - 1)] = index;
                n_positive += usize::from(!is_negative);
                n_negative += usize::from(is_negative);
            }
            let (lowest, highest) = (self.lowest_index, self.highest_index);
            self.positive
                .add_all(&positive[..n_positive], lowest, highest);
            self.negative
                .add_all(&negative[..n_negative], lowest, highest);
            self.count += (n_positive + n_negative) as u64;
        }
    }

    /// A value whose magnitude lies outside [ZERO_THRESHOLD, CLAMP_MAGNITUDE]: the zero
    /// count, the top bucket (clamped), or nothing (NaN).
    #[cold]
    fn insert_outside_range(&mut self, x: f64) {
        let magnitude = x.abs();
        if magnitude < ZERO_THRESHOLD {
            self.zero_count += 1;
            self.count += 1;
        } else if magnitude > CLAMP_MAGNITUDE {
            // The top bucket, that of CLAMP_MAGNITUDE.
            let index = self.highest_index;
            let store = if x.is_sign_negative() {
                &mut self.negative
            } else {
                &mut self.positive
            };
            store.add_all(&[index], self.lowest_index, self.highest_index);
            self.count += 1;
        }
    }

    /// Adds the counts of `other` into `self`. Exact and order-independent.
    ///
    /// Fails, leaving `self` unchanged, when the relative accuracies differ.
    pub fn merge(&mut self, other: &QuantileSketch) -> Result<(), SketchMismatch> {
        if self.relative_accuracy.to_bits() != other.relative_accuracy.to_bits() {
            return Err(SketchMismatch {
                this_relative_accuracy: self.relative_accuracy,
                other_relative_accuracy: other.relative_accuracy,
            });
        }
        self.positive
            .merge(&other.positive, self.lowest_index, self.highest_index);
        self.negative
            .merge(&other.negative, self.lowest_index, self.highest_index);
        self.zero_count += other.zero_count;
        self.count += other.count;
        Ok(())
    }

    /// Number of values counted (NaN excluded).
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Number of values counted as zero (|x| < 1e-30).
    pub fn zero_count(&self) -> u64 {
        self.zero_count
    }

    /// True when no value has been counted.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Estimate of the order statistic of 0-based rank `floor(q·(n − 1))`
    /// (the lower neighbour of the Hyndman & Fan type 7 position, no
    /// interpolation), with relative error at most alpha against that exact
    /// order statistic (values clamped at 1e30 or zeroed below 1e-30
    /// excepted). `q` is clamped into [0, 1]. `None` when the sketch is empty
    /// or `q` is NaN.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        if self.count == 0 || q.is_nan() {
            return None;
        }
        let q = q.clamp(0.0, 1.0);
        self.order_statistic(((q * (self.count - 1) as f64).floor() as u64).min(self.count - 1))
    }

    /// Estimate of the order statistic of 0-based rank `rank` (clamped to the count), with
    /// relative error at most alpha against the exact one (as [`Self::quantile`]). `None`
    /// when the sketch is empty.
    pub fn order_statistic(&self, rank: u64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let rank = rank.min(self.count - 1);
        let mut seen = 0u64;
        for (index, count) in self.negative.non_zero().rev() {
            seen += count;
            if seen > rank {
                let (lo, hi) = self.bucket_bounds(index);
                return Some(-bucket_representative(lo, hi));
            }
        }
        seen += self.zero_count;
        if seen > rank {
            return Some(0.0);
        }
        for (index, count) in self.positive.non_zero() {
            seen += count;
            if seen > rank {
                let (lo, hi) = self.bucket_bounds(index);
                return Some(bucket_representative(lo, hi));
            }
        }
        // Unreachable when the counts are consistent; return the largest
        // bucket rather than panic.
        self.buckets()
            .last()
            .map(|(lo, hi, _)| bucket_representative(lo, hi))
    }

    /// The sketch's counts as plain numbers, for storing it ([`SketchParts`]).
    pub fn to_parts(&self) -> SketchParts {
        SketchParts {
            relative_accuracy: self.relative_accuracy,
            zero_count: self.zero_count,
            positive: self.positive.non_zero().collect(),
            negative: self.negative.non_zero().collect(),
        }
    }

    /// The sketch whose counts `parts` holds ([`QuantileSketch::to_parts`]): equal to the
    /// sketch they were taken from. Fails on a relative accuracy outside the accepted
    /// range, indices not increasing or outside the mapping's range, or zero counts.
    pub fn from_parts(parts: &SketchParts) -> Result<QuantileSketch, String> {
        let alpha = parts.relative_accuracy;
        if !(MIN_RELATIVE_ACCURACY..=MAX_RELATIVE_ACCURACY).contains(&alpha) {
            return Err(format!("relative accuracy {alpha} out of range"));
        }
        let mut sketch = QuantileSketch::new(alpha);
        if sketch.relative_accuracy.to_bits() != alpha.to_bits() {
            return Err(format!("relative accuracy {alpha} out of range"));
        }
        let (lowest, highest) = (sketch.lowest_index, sketch.highest_index);
        let mut count = parts.zero_count;
        for (buckets, store) in [
            (&parts.positive, &mut sketch.positive),
            (&parts.negative, &mut sketch.negative),
        ] {
            let (Some(&(first, _)), Some(&(last, _))) = (buckets.first(), buckets.last()) else {
                continue;
            };
            let increasing = buckets.windows(2).all(|pair| pair[0].0 < pair[1].0);
            if !increasing || first < lowest || last > highest {
                return Err("bucket indices not increasing within the mapping's range".into());
            }
            if buckets.iter().any(|&(_, n)| n == 0) {
                return Err("a stored bucket is empty".into());
            }
            store.grow_to_include(first, last, lowest, highest);
            for &(index, n) in buckets {
                store.counts[(index - store.offset) as usize] = n;
                count = count
                    .checked_add(n)
                    .ok_or_else(|| "bucket counts overflow".to_string())?;
            }
        }
        sketch.zero_count = parts.zero_count;
        sketch.count = count;
        Ok(sketch)
    }

    /// Non-empty buckets as `(lo, hi, count)` in increasing value order:
    /// negative buckets first (lo and hi negative, lo < hi), then the zero
    /// bucket as `(0.0, 0.0, count)` if non-empty, then positive buckets.
    /// Use [`bucket_representative`] for the value a bucket stands for.
    pub fn buckets(&self) -> impl Iterator<Item = (f64, f64, u64)> + '_ {
        let negative = self.negative.non_zero().rev().map(move |(index, count)| {
            let (lo, hi) = self.bucket_bounds(index);
            (-hi, -lo, count)
        });
        let zero = (self.zero_count > 0).then_some((0.0, 0.0, self.zero_count));
        let positive = self.positive.non_zero().map(move |(index, count)| {
            let (lo, hi) = self.bucket_bounds(index);
            (lo, hi, count)
        });
        negative.chain(zero).chain(positive)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_rebuild_the_same_sketch() {
        let mut rng = XorShift(0x5eed);
        let mut sketch = QuantileSketch::new(1e-3);
        for _ in 0..10_000 {
            sketch.insert(rng.wide_value());
        }
        sketch.insert(0.0);
        sketch.insert(f64::INFINITY);
        let parts = sketch.to_parts();
        let rebuilt = QuantileSketch::from_parts(&parts).unwrap();
        assert_eq!(rebuilt, sketch);
        assert_eq!(rebuilt.count(), sketch.count());
        for q in [0.0, 0.00135, 0.5, 0.99865, 1.0] {
            assert_eq!(rebuilt.quantile(q), sketch.quantile(q));
        }
        // Damaged parts are refused, not trusted.
        let mut unordered = parts.clone();
        unordered.positive.reverse();
        assert!(QuantileSketch::from_parts(&unordered).is_err());
        let mut outside = parts.clone();
        outside.negative.push((i64::MAX, 1));
        assert!(QuantileSketch::from_parts(&outside).is_err());
        let mut empty_bucket = parts.clone();
        empty_bucket.positive[0].1 = 0;
        assert!(QuantileSketch::from_parts(&empty_bucket).is_err());
        let mut accuracy = parts;
        accuracy.relative_accuracy = 0.7;
        assert!(QuantileSketch::from_parts(&accuracy).is_err());
    }

    /// xorshift64* (Vigna 2016), for test data only.
    struct XorShift(u64);

    impl XorShift {
        fn next_u64(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }

        fn uniform(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
        }

        /// Random sign, magnitude log-uniform in 1e-6..1e6.
        fn wide_value(&mut self) -> f64 {
            let magnitude = 10f64.powf(-6.0 + 12.0 * self.uniform());
            if self.next_u64() & 1 == 1 {
                -magnitude
            } else {
                magnitude
            }
        }
    }

    fn wide_data(count: usize, seed: u64) -> Vec<f64> {
        let mut generator = XorShift(seed);
        (0..count).map(|_| generator.wide_value()).collect()
    }

    /// Exact order statistic of rank floor(q·(n−1)) (definition in the
    /// `quantile` docs).
    fn exact_lower_order_statistic(sorted: &[f64], q: f64) -> f64 {
        sorted[(q * (sorted.len() - 1) as f64).floor() as usize]
    }

    #[test]
    fn relative_error_within_alpha_against_exact_order_statistics() {
        for alpha in [0.001, 0.01, 0.05] {
            let mut data = wide_data(20_000, 0x9e37_79b9_7f4a_7c15);
            data.extend([0.0, -0.0, 0.0]);
            let mut sketch = QuantileSketch::new(alpha);
            sketch.insert_slice(&data);
            data.sort_by(f64::total_cmp);
            for step in 0..=1000 {
                let q = step as f64 / 1000.0;
                let exact = exact_lower_order_statistic(&data, q);
                let estimate = sketch.quantile(q).unwrap();
                if exact == 0.0 {
                    assert_eq!(estimate, 0.0);
                } else {
                    let error = (estimate - exact).abs() / exact.abs();
                    // The bound is alpha (module docs); allow rounding.
                    assert!(
                        error <= alpha * (1.0 + 1e-9),
                        "alpha {alpha} q {q}: exact {exact} estimate {estimate} error {error}"
                    );
                }
            }
        }
    }

    #[test]
    fn bucket_ratio_at_most_gamma() {
        for alpha in [0.0001, 0.01, 0.2] {
            let mut sketch = QuantileSketch::new(alpha);
            sketch.insert_slice(&wide_data(5_000, 12345));
            let gamma = sketch.gamma();
            let mut checked = 0;
            for (lo, hi, _) in sketch.buckets() {
                if lo == 0.0 && hi == 0.0 {
                    continue;
                }
                let ratio = hi.abs().max(lo.abs()) / hi.abs().min(lo.abs());
                assert!(ratio > 1.0);
                assert!(
                    ratio <= gamma * (1.0 + 1e-12),
                    "ratio {ratio} gamma {gamma}"
                );
                checked += 1;
            }
            assert!(checked > 100);
            // Every bucket index in a sweep across binades around 1.0, including t = 0
            // and the last bucket of a binade.
            let one = sketch.index_of(1.0);
            for index in one - 2000..one + 2000 {
                let (lo, hi) = sketch.bucket_bounds(index);
                assert!(hi / lo <= gamma * (1.0 + 1e-12));
            }
        }
    }

    #[test]
    fn values_land_inside_their_bucket() {
        let sketch = QuantileSketch::new(0.01);
        for value in wide_data(10_000, 77) {
            let magnitude = value.abs();
            let (lo, hi) = sketch.bucket_bounds(sketch.index_of(magnitude));
            assert!(lo * (1.0 - 1e-12) <= magnitude && magnitude <= hi * (1.0 + 1e-12));
        }
    }

    #[test]
    fn merge_equals_sketch_of_union() {
        let first = wide_data(7_000, 1);
        let second: Vec<f64> = wide_data(9_000, 2).iter().map(|x| x * 1e3).collect();
        let mut sketch_first = QuantileSketch::new(0.01);
        sketch_first.insert_slice(&first);
        let mut sketch_second = QuantileSketch::new(0.01);
        sketch_second.insert_slice(&second);
        sketch_second.insert(0.0);

        let mut union = QuantileSketch::new(0.01);
        union.insert_slice(&first);
        union.insert_slice(&second);
        union.insert(0.0);

        let mut merged_forward = sketch_first.clone();
        merged_forward.merge(&sketch_second).unwrap();
        let mut merged_backward = sketch_second.clone();
        merged_backward.merge(&sketch_first).unwrap();
        let mut merged_from_empty = QuantileSketch::new(0.01);
        merged_from_empty.merge(&merged_forward).unwrap();

        let union_buckets: Vec<_> = union.buckets().collect();
        assert_eq!(merged_forward.buckets().collect::<Vec<_>>(), union_buckets);
        assert_eq!(merged_backward.buckets().collect::<Vec<_>>(), union_buckets);
        assert_eq!(merged_forward, union);
        assert_eq!(merged_backward, union);
        assert_eq!(merged_from_empty, union);
        assert_eq!(merged_forward.count(), 16_001);
    }

    #[test]
    fn merge_rejects_different_accuracy() {
        let mut a = QuantileSketch::new(0.01);
        a.insert(1.0);
        let mut b = QuantileSketch::new(0.02);
        b.insert(2.0);
        let error = a.merge(&b).unwrap_err();
        assert_eq!(error.this_relative_accuracy, 0.01);
        assert_eq!(error.other_relative_accuracy, 0.02);
        assert_eq!(a.count(), 1);
    }

    #[test]
    fn counts_with_zeros_negatives_and_special_values() {
        let mut sketch = QuantileSketch::new(0.01);
        assert!(sketch.is_empty());
        assert_eq!(sketch.quantile(0.5), None);
        sketch.insert_slice(&[0.0, -0.0, 1e-40, -3.0, -2.0, 5.0, f64::NAN]);
        assert_eq!(sketch.count(), 6);
        assert_eq!(sketch.zero_count(), 3);
        // Sorted: -3, -2, 0, 0, 0, 5; rank floor(q·5).
        let check = |q: f64, exact: f64| {
            let estimate = sketch.quantile(q).unwrap();
            assert!((estimate - exact).abs() <= 0.01 * exact.abs() * (1.0 + 1e-9));
        };
        check(0.0, -3.0);
        check(0.2, -2.0);
        check(0.5, 0.0);
        check(1.0, 5.0);
        check(-4.0, -3.0);
        check(7.0, 5.0);
        assert_eq!(sketch.quantile(f64::NAN), None);
        let total: u64 = sketch.buckets().map(|(_, _, count)| count).sum();
        assert_eq!(total, 6);
        let values: Vec<f64> = sketch
            .buckets()
            .map(|(lo, hi, _)| bucket_representative(lo, hi))
            .collect();
        assert!(values.windows(2).all(|pair| pair[0] < pair[1]));

        // Infinities clamp to the 1e30 bucket.
        sketch.insert(f64::INFINITY);
        sketch.insert(f64::NEG_INFINITY);
        sketch.insert(1e300);
        assert_eq!(sketch.count(), 9);
        let top = sketch.quantile(1.0).unwrap();
        assert!((top - 1e30).abs() <= 0.01 * 1e30);
        let bottom = sketch.quantile(0.0).unwrap();
        assert!((bottom + 1e30).abs() <= 0.01 * 1e30);
    }

    #[test]
    fn out_of_range_accuracy_is_clamped() {
        assert_eq!(QuantileSketch::new(0.0).relative_accuracy(), 1e-5);
        assert_eq!(QuantileSketch::new(0.9).relative_accuracy(), 0.49);
        assert_eq!(QuantileSketch::new(f64::NAN).relative_accuracy(), 0.01);
        let mut sketch = QuantileSketch::new(-1.0);
        sketch.insert_slice(&[1.0, 2.0, 3.0]);
        let median = sketch.quantile(0.5).unwrap();
        assert!((median - 2.0).abs() <= 2.0 * 1e-5 * (1.0 + 1e-9));
    }

    #[test]
    fn resolution_is_the_coarsest_that_meets_alpha() {
        // alpha = 1e-3: gamma − 1 = 2.002e-3, so 2^−9 = 1.95e-3 qualifies and 2^−8 does
        // not: 512 buckets per binade.
        let sketch = QuantileSketch::new(0.001);
        assert_eq!(sketch.shift, 52 - 9);
        let (lo, hi) = sketch.bucket_bounds(sketch.index_of(1.0));
        assert_eq!((lo, hi), (1.0, 1.0 + 1.0 / 512.0));
        assert_eq!(QuantileSketch::new(0.49).shift, 52);
        assert_eq!(QuantileSketch::new(1e-5).shift, 52 - 16);
    }

    #[test]
    fn insert_slice_equals_single_inserts_across_pieces() {
        let data = wide_data(3 * INSERT_PIECE + 7, 5);
        let mut bulk = QuantileSketch::new(0.001);
        bulk.insert_slice(&data);
        let mut single = QuantileSketch::new(0.001);
        for &x in &data {
            single.insert(x);
        }
        assert_eq!(bulk, single);
        assert_eq!(bulk.count(), data.len() as u64);
        // The standardising entry counts the mapped values exactly as a slice of them.
        let (center, inverse_scale) = (0.25, 1.0 / 3.0);
        let mapped: Vec<f64> = data.iter().map(|x| (x - center) * inverse_scale).collect();
        let mut standardised = QuantileSketch::new(0.001);
        standardised.insert_standardised(&data, center, inverse_scale);
        let mut of_mapped = QuantileSketch::new(0.001);
        of_mapped.insert_slice(&mapped);
        assert_eq!(standardised, of_mapped);
    }
}

/// A sketch of standardised values (x − centre)/scale, as a run keeps for an output beyond
/// the exact-percentile limit, read back in the output's units.
#[derive(Debug, Clone, Copy)]
pub struct StandardisedSketch<'a> {
    /// The sketch of the standardised values.
    pub sketch: &'a QuantileSketch,
    /// The centre subtracted.
    pub center: f64,
    /// The scale divided by.
    pub scale: f64,
    /// The smallest value seen (every order statistic lies within [min, max]).
    pub min: f64,
    /// The largest value seen.
    pub max: f64,
}

impl StandardisedSketch<'_> {
    /// The order statistic of 0-based `rank` in output units, moved by `outward` (−1
    /// down, +1 up, 0 not) times the sketch's error bound α·|x − centre|, so that with
    /// outward ≠ 0 it lies beyond the exact order statistic on that side; within
    /// [min, max]. NaN for an empty sketch.
    pub fn order_statistic(&self, rank: u64, outward: f64) -> f64 {
        let Some(z) = self.sketch.order_statistic(rank) else {
            return f64::NAN;
        };
        let x = self.scale * z;
        (self.center + x + outward * self.sketch.relative_accuracy() * x.abs())
            .clamp(self.min, self.max)
    }
}
