//! Fixed-width histograms, from raw values or from a [`QuantileSketch`], and
//! a compact ASCII rendering.
//!
//! Bins are equal-width intervals [lower_edge + i·w, lower_edge + (i+1)·w),
//! the last one closed on the right (the convention of `numpy.histogram`).
//! Values outside [min, max] are clamped into the first or last bin, so the
//! counts always add up to the number of (non-NaN) values. Built from a
//! sketch, each bucket's count goes to the bin containing its representative
//! value 2·lo·hi / (lo + hi) (Masson, Rim & Lee 2019, DDSketch), so bin
//! counts are exact up to the sketch's relative accuracy in the values.

use crate::quantile_sketch::{bucket_representative, QuantileSketch};

/// Largest number of lines produced by [`Histogram::render_text`].
const MAX_RENDERED_LINES: usize = 12;

/// Equal-width histogram.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Left edge of the first bin.
    pub lower_edge: f64,
    /// Width of every bin (0 for the degenerate single-bin histogram).
    pub bin_width: f64,
    /// Count per bin.
    pub counts: Vec<u64>,
}

impl Histogram {
    /// Empty histogram over [min, max] with `bins` bins.
    ///
    /// `bins == 0` is treated as 1; bounds given in decreasing order are
    /// swapped. When min == max (or a bound is not finite) the histogram is
    /// a single bin of width 0 at `lower_edge` = min (0 if min is not
    /// finite) that receives every value.
    fn empty(min: f64, max: f64, bins: usize) -> Histogram {
        let (low, high) = if min <= max { (min, max) } else { (max, min) };
        if !(low.is_finite() && high.is_finite()) || low == high {
            return Histogram {
                lower_edge: if low.is_finite() { low } else { 0.0 },
                bin_width: 0.0,
                counts: vec![0],
            };
        }
        let bins = bins.max(1);
        Histogram {
            lower_edge: low,
            bin_width: (high - low) / bins as f64,
            counts: vec![0; bins],
        }
    }

    /// Bin index of `value`, clamped into the range (`None` for NaN).
    fn bin_of(&self, value: f64) -> Option<usize> {
        if value.is_nan() {
            return None;
        }
        let last = self.counts.len() - 1;
        if self.bin_width == 0.0 {
            return Some(0);
        }
        let position = ((value - self.lower_edge) / self.bin_width).floor();
        Some(if position <= 0.0 {
            0
        } else {
            (position as usize).min(last)
        })
    }

    /// Histogram of `values` over [min, max] with `bins` equal bins, the last
    /// closed on the right. Values outside the range are counted in the
    /// first/last bin; NaN is ignored. When min == max (or a bound is not
    /// finite) the result is one bin of width 0 holding every value;
    /// `bins == 0` is treated as 1; reversed bounds are swapped.
    pub fn from_values(values: &[f64], min: f64, max: f64, bins: usize) -> Histogram {
        let mut histogram = Histogram::empty(min, max, bins);
        histogram.add_values(values);
        histogram
    }

    /// Adds `values` with the rules of [`Histogram::from_values`].
    pub fn add_values(&mut self, values: &[f64]) {
        for &value in values {
            if let Some(bin) = self.bin_of(value) {
                self.counts[bin] += 1;
            }
        }
    }

    /// Adds the counts of a histogram over the same bins.
    pub fn add_counts(&mut self, other: &Histogram) {
        for (count, more) in self.counts.iter_mut().zip(&other.counts) {
            *count += more;
        }
    }

    /// Histogram of a sketch: each bucket's count goes to the bin containing
    /// its representative value (clamped into [min, max]); same bin rules as
    /// [`Histogram::from_values`]. The zero bucket is placed at 0.0.
    pub fn from_sketch(sketch: &QuantileSketch, min: f64, max: f64, bins: usize) -> Histogram {
        let mut histogram = Histogram::empty(min, max, bins);
        for (lo, hi, count) in sketch.buckets() {
            if let Some(bin) = histogram.bin_of(bucket_representative(lo, hi)) {
                histogram.counts[bin] += count;
            }
        }
        histogram
    }

    /// Bin edges: `counts.len() + 1` values `lower_edge + i·bin_width`.
    pub fn edges(&self) -> Vec<f64> {
        (0..=self.counts.len())
            .map(|i| self.lower_edge + i as f64 * self.bin_width)
            .collect()
    }

    /// Total count.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// Compact ASCII bar chart: one line per group of adjacent bins (bins
    /// are merged so that there are at most 12 lines), each
    /// `"  <from> .. <to> | <bar padded to width> <count>"` with the edges
    /// right-aligned to a common width and the count right-aligned. Bars are
    /// `#` scaled so the largest group spans `width` characters (any
    /// non-zero count gets at least one `#`). Empty for an empty histogram.
    pub fn render_text(&self, width: usize) -> Vec<String> {
        if self.counts.is_empty() {
            return Vec::new();
        }
        let group_size = self.counts.len().div_ceil(MAX_RENDERED_LINES);
        let groups: Vec<(f64, f64, u64)> = self
            .counts
            .chunks(group_size)
            .enumerate()
            .map(|(group, counts)| {
                let first_bin = group * group_size;
                let from = self.lower_edge + first_bin as f64 * self.bin_width;
                let to = self.lower_edge + (first_bin + counts.len()) as f64 * self.bin_width;
                (from, to, counts.iter().sum())
            })
            .collect();

        let step = self.bin_width * group_size as f64;
        let largest_magnitude = groups
            .iter()
            .map(|&(from, to, _)| from.abs().max(to.abs()))
            .fold(0.0, f64::max);
        let format_edge = edge_formatter(step, largest_magnitude);
        let labels: Vec<(String, String)> = groups
            .iter()
            .map(|&(from, to, _)| (format_edge(from), format_edge(to)))
            .collect();
        let label_width = labels
            .iter()
            .map(|(from, to)| from.len().max(to.len()))
            .max()
            .unwrap_or(0);
        let largest_count = groups.iter().map(|g| g.2).max().unwrap_or(0);
        let count_width = largest_count.to_string().len();

        groups
            .iter()
            .zip(&labels)
            .map(|(&(_, _, count), (from, to))| {
                let bar_length = if largest_count == 0 || count == 0 {
                    0
                } else {
                    let scaled = (count as f64 / largest_count as f64 * width as f64).round();
                    (scaled as usize).clamp(1, width.max(1))
                };
                let bar = "#".repeat(bar_length);
                format!(
                    "  {from:>label_width$} .. {to:>label_width$} | {bar:<width$} {count:>count_width$}"
                )
            })
            .collect()
    }
}

/// Chooses a number format for edges: fixed-point with enough decimals to
/// resolve `step` (two significant digits of it), or scientific notation for
/// very large or very small magnitudes.
fn edge_formatter(step: f64, largest_magnitude: f64) -> impl Fn(f64) -> String {
    let scientific =
        largest_magnitude >= 1e7 || (largest_magnitude > 0.0 && largest_magnitude < 1e-4);
    let decimals = if step > 0.0 && step.is_finite() {
        (2.0 - step.log10().floor()).clamp(0.0, 12.0) as usize
    } else {
        4
    };
    move |value: f64| {
        if scientific {
            format!("{value:.4e}")
        } else {
            format!("{value:.decimals$}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_values_matches_numpy_convention() {
        // numpy.histogram([0, 1, 2, 3, 4, 5], bins=5, range=(0, 5)) gives
        // counts [1, 1, 1, 1, 2]: the last bin [4, 5] is closed on the right.
        let values = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let histogram = Histogram::from_values(&values, 0.0, 5.0, 5);
        assert_eq!(histogram.counts, vec![1, 1, 1, 1, 2]);
        assert_eq!(histogram.edges(), vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(histogram.bin_width, 1.0);
    }

    #[test]
    fn out_of_range_nan_and_degenerate() {
        let histogram = Histogram::from_values(&[-10.0, 0.5, f64::NAN, 10.0], 0.0, 1.0, 2);
        assert_eq!(histogram.counts, vec![1, 2]);
        let single = Histogram::from_values(&[2.0, 2.0, 3.0], 2.0, 2.0, 10);
        assert_eq!(single.counts, vec![3]);
        assert_eq!(single.bin_width, 0.0);
        assert_eq!(single.edges(), vec![2.0, 2.0]);
        let zero_bins = Histogram::from_values(&[1.0], 0.0, 2.0, 0);
        assert_eq!(zero_bins.counts, vec![1]);
        let reversed = Histogram::from_values(&[0.25, 0.75], 1.0, 0.0, 2);
        assert_eq!(reversed.counts, vec![1, 1]);
        let infinite = Histogram::from_values(&[1.0], f64::NEG_INFINITY, 1.0, 4);
        assert_eq!(infinite.counts, vec![1]);
        assert_eq!(infinite.lower_edge, 0.0);
    }

    #[test]
    fn from_sketch_agrees_with_values() {
        // Values in bin centres, far from the edges (relative accuracy 0.1 %
        // moves them by at most 0.01), so both histograms agree exactly.
        let values: Vec<f64> = (0..1000).map(|i| -4.5 + (i % 10) as f64).collect();
        let mut sketch = QuantileSketch::new(0.001);
        sketch.insert_slice(&values);
        sketch.insert(0.0);
        let mut with_zero = values.clone();
        with_zero.push(0.0);
        let from_sketch = Histogram::from_sketch(&sketch, -5.0, 5.0, 10);
        let from_values = Histogram::from_values(&with_zero, -5.0, 5.0, 10);
        assert_eq!(from_sketch, from_values);
        assert_eq!(from_sketch.total(), 1001);
        assert_eq!(from_sketch.counts[5], 101);
    }

    #[test]
    fn render_text_layout() {
        let histogram = Histogram {
            lower_edge: 0.5,
            bin_width: 0.25,
            counts: vec![10, 40, 0, 20],
        };
        let lines = histogram.render_text(8);
        assert_eq!(
            lines,
            vec![
                "  0.500 .. 0.750 | ##       10",
                "  0.750 .. 1.000 | ######## 40",
                "  1.000 .. 1.250 |           0",
                "  1.250 .. 1.500 | ####     20",
            ]
        );
        assert!(lines.iter().all(|line| line.is_ascii()));
    }

    #[test]
    fn render_text_merges_to_at_most_twelve_lines() {
        let counts: Vec<u64> = (0..100).collect();
        let histogram = Histogram {
            lower_edge: 0.0,
            bin_width: 1.0,
            counts,
        };
        let lines = histogram.render_text(20);
        assert!(lines.len() <= 12);
        assert_eq!(lines.len(), 12); // ceil(100 / 9) = 12 groups of 9 bins
        let total: u64 = lines
            .iter()
            .map(|line| {
                line.split_whitespace()
                    .last()
                    .unwrap()
                    .parse::<u64>()
                    .unwrap()
            })
            .sum();
        assert_eq!(total, 4950);
        let widths: Vec<usize> = lines.iter().map(String::len).collect();
        assert!(widths.windows(2).all(|pair| pair[0] == pair[1]));
        let degenerate = Histogram::from_values(&[1.0, 1.0], 1.0, 1.0, 5);
        assert_eq!(degenerate.render_text(4).len(), 1);
        assert!(Histogram {
            lower_edge: 0.0,
            bin_width: 1.0,
            counts: vec![]
        }
        .render_text(10)
        .is_empty());
    }
}
