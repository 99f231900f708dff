//! Numbers and sizes as a person writes them, for messages: `1e308` rather than the 309
//! digits of `{}` on an `f64`, `3.2 GB` rather than a byte count, `0,2-5,9` rather than
//! every index.

use std::fmt;

/// An `f64` shown as a person writes it: the shortest form that reads back to the same
/// value, in exponent form (`1e308`, `2.5e-7`) when it is large or small.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown(pub f64);

impl fmt::Display for Shown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x.is_nan() {
            f.write_str("NaN")
        } else if x.is_infinite() {
            f.write_str(if x > 0.0 { "inf" } else { "-inf" })
        } else if x != 0.0 && !(1e-4..1e6).contains(&x.abs()) {
            write!(f, "{x:e}")
        } else {
            write!(f, "{x}")
        }
    }
}

/// A number rvtol computed, shown in a message to four significant digits in the form of
/// [`Shown`] (`5.021`, `7.692e299`, `-0.4562`): a value the user wrote is shown as written
/// ([`Shown`]); one derived from it carries no more digits than a person reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rounded(pub f64);

impl fmt::Display for Rounded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() || x == 0.0 {
            return Shown(x).fmt(f);
        }
        // Four significant digits in exponent form read back as the rounded value.
        let rounded: f64 = format!("{x:.3e}").parse().unwrap_or(x);
        Shown(rounded).fmt(f)
    }
}

/// A byte count with a decimal unit: `512 B`, `3.2 GB`.
pub fn human_bytes(bytes: f64) -> String {
    const UNITS: [&str; 7] = ["B", "kB", "MB", "GB", "TB", "PB", "EB"];
    let mut value = bytes.max(0.0);
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{value:.0} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// Increasing indices as a person (and Slurm's `--array`) writes them: runs of three or
/// more joined as `a-b` (`0,2-5,9`). Shard lists and the indices a pattern binds.
pub fn index_list(indices: &[u64]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        if j >= i + 2 {
            parts.push(format!("{}-{}", indices[i], indices[j]));
        } else {
            parts.extend(indices[i..=j].iter().map(u64::to_string));
        }
        i = j + 1;
    }
    parts.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_lists_join_runs_of_three() {
        assert_eq!(index_list(&[0, 2, 3, 4, 5, 9]), "0,2-5,9");
        assert_eq!(index_list(&[1, 2, 7]), "1,2,7");
        assert_eq!(index_list(&[]), "");
    }

    #[test]
    fn numbers_read_as_written() {
        assert_eq!(Shown(1e308).to_string(), "1e308");
        assert_eq!(Shown(-1e308).to_string(), "-1e308");
        assert_eq!(Shown(2.5e-7).to_string(), "2.5e-7");
        assert_eq!(Shown(0.0125).to_string(), "0.0125");
        assert_eq!(Shown(76.5).to_string(), "76.5");
        assert_eq!(Shown(0.0).to_string(), "0");
        assert_eq!(Shown(123456.0).to_string(), "123456");
        assert_eq!(Shown(1234567.0).to_string(), "1.234567e6");
        assert_eq!(Shown(f64::NAN).to_string(), "NaN");
        assert_eq!(Shown(f64::NEG_INFINITY).to_string(), "-inf");
    }

    #[test]
    fn computed_numbers_have_four_significant_digits() {
        assert_eq!(Rounded(5.021382126582076).to_string(), "5.021");
        assert_eq!(Rounded(7.692307692307693e299).to_string(), "7.692e299");
        assert_eq!(Rounded(-0.4562305898749055).to_string(), "-0.4562");
        assert_eq!(Rounded(-1.2877736398384065e-5).to_string(), "-1.288e-5");
        assert_eq!(Rounded(10.5).to_string(), "10.5");
        assert_eq!(Rounded(123456.7).to_string(), "123500");
        assert_eq!(Rounded(0.0).to_string(), "0");
        assert_eq!(Rounded(f64::INFINITY).to_string(), "inf");
    }

    #[test]
    fn sizes_read_as_written() {
        assert_eq!(human_bytes(512.0), "512 B");
        assert_eq!(human_bytes(3.2e9), "3.2 GB");
        assert_eq!(human_bytes(8e10), "80.0 GB");
    }
}
