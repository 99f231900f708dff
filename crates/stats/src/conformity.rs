//! Percentiles as a conformity judgement reads them: one meaning of a flagged sample for
//! every figure that judges conformity (the run report's percentiles, the gate's bands and
//! requirements, an allocation's target, the page, Python).
//!
//! A sample that does not conform for a reason its value does not show (flagged
//! non-conforming by its indicator, excluded, not finite) lies beyond the spec limits:
//! among the N samples drawn, the n conforming values keep their order and the N − n
//! others sit above them for an output with an upper limit only, below them for a lower
//! limit only, and with two limits or none in the tail the percentile reads (above for a
//! percentile at or above the median, below under it) ([`Placement`]). So "P99.865 ≤ U"
//! holds exactly when at most 0.135 % of the assemblies are above U or non-conforming,
//! and "P0.135 ≥ L" exactly when at most 0.135 % are below L or non-conforming. A percentile that reads such a sample is beyond
//! the limits: +∞ or −∞ here, `null` in JSON, "beyond" in text. With no such sample the
//! figures are the plain type-7 percentiles of the values, bit for bit.

use crate::capability::SpecLimits;

/// Where the samples beyond the limits sit among the conforming values: above them for an
/// output with an upper spec limit only, below them for a lower limit only, and for two
/// limits or none in the tail each percentile reads (above for a percentile at or above
/// the median, below under it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// Above every value.
    Above,
    /// Below every value.
    Below,
    /// In the tail of the percentile read.
    Tail,
}

impl Placement {
    /// The placement for an output with spec limits `limits`.
    pub fn of(limits: Option<SpecLimits>) -> Placement {
        match limits.map(|l| (l.lower.is_some(), l.upper.is_some())) {
            Some((false, true)) => Placement::Above,
            Some((true, false)) => Placement::Below,
            _ => Placement::Tail,
        }
    }

    /// Whether the samples beyond sit above the values when `percent` is read.
    pub fn above(self, percent: f64) -> bool {
        match self {
            Placement::Above => true,
            Placement::Below => false,
            Placement::Tail => percent >= 50.0,
        }
    }

    /// What a sample beyond the limits stands for when `percent` is read: +∞ or −∞.
    pub fn beyond_value(self, percent: f64) -> f64 {
        if self.above(percent) {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        }
    }

    /// The rank among the `n` conforming values of 0-based rank `rank` among all
    /// `n + beyond` samples when `percent` is read; `None` where a sample beyond sits.
    pub fn value_rank(self, rank: usize, n: usize, beyond: usize, percent: f64) -> Option<usize> {
        if self.above(percent) {
            (rank < n).then_some(rank)
        } else {
            rank.checked_sub(beyond)
        }
    }
}

/// Type-7 interpolation between neighbouring order statistics either of which may be a
/// sample beyond the limits (±∞): the result is beyond whenever it reads one.
pub fn interpolate_beyond(lower: f64, upper: f64, weight: f64) -> f64 {
    if weight == 0.0 || lower == upper || lower.is_infinite() {
        lower
    } else if upper.is_infinite() {
        upper
    } else {
        lower + weight * (upper - lower)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beyond_samples_sit_beyond_the_limits_the_output_has() {
        let tail = Placement::Tail;
        // 3 values, 2 beyond: above them for the upper tail, below for the lower one.
        assert_eq!(
            (0..5)
                .map(|r| tail.value_rank(r, 3, 2, 99.0))
                .collect::<Vec<_>>(),
            [Some(0), Some(1), Some(2), None, None]
        );
        assert_eq!(
            (0..5)
                .map(|r| tail.value_rank(r, 3, 2, 1.0))
                .collect::<Vec<_>>(),
            [None, None, Some(0), Some(1), Some(2)]
        );
        assert_eq!(tail.beyond_value(50.0), f64::INFINITY);
        assert_eq!(tail.beyond_value(49.9), f64::NEG_INFINITY);
        // An upper limit only: above the values whatever the percentile; a lower: below.
        let upper = Placement::of(Some(SpecLimits {
            lower: None,
            upper: Some(1.0),
        }));
        assert_eq!(upper, Placement::Above);
        assert_eq!(upper.value_rank(0, 3, 2, 1.0), Some(0));
        let lower = Placement::of(Some(SpecLimits {
            lower: Some(0.0),
            upper: None,
        }));
        assert_eq!(lower.beyond_value(99.0), f64::NEG_INFINITY);
        assert_eq!(Placement::of(None), Placement::Tail);
    }

    #[test]
    fn interpolation_reading_a_beyond_sample_is_beyond() {
        assert_eq!(interpolate_beyond(1.0, f64::INFINITY, 0.25), f64::INFINITY);
        assert_eq!(
            interpolate_beyond(f64::NEG_INFINITY, 1.0, 0.25),
            f64::NEG_INFINITY
        );
        assert_eq!(interpolate_beyond(1.0, f64::INFINITY, 0.0), 1.0);
        assert_eq!(interpolate_beyond(1.0, 3.0, 0.25), 1.5);
    }
}
