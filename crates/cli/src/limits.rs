//! The parsers of the numbers and names on the command line: counts (`1e6` allowed),
//! seeds, shares, memory sizes, sampling methods, shards. (What a command may ask of this machine,
//! its threads and its memory budget, is rvtol-analysis' `request::machine`, shared with
//! the Python module.)

/// A whole number of at least 1, written as digits (`1000000`, `1_000_000`) or in exponent
/// form when that is a whole number (`1e6`, `2.5e6`).
pub fn parse_count(text: &str) -> Result<u64, String> {
    let cleaned = text.trim().replace('_', "");
    let value = match cleaned.parse::<u64>() {
        Ok(value) => value,
        Err(_) => {
            let x: f64 = cleaned
                .parse()
                .map_err(|_| "must be a whole number of at least 1".to_string())?;
            // `u64::MAX as f64` is 2⁶⁴, one more than the largest count: a value that
            // reaches it would saturate to u64::MAX rather than be refused.
            if !(x.is_finite() && x.fract() == 0.0 && x >= 1.0 && x < u64::MAX as f64) {
                return Err(if x.is_finite() && x >= u64::MAX as f64 {
                    format!(
                        "must be at most {}",
                        rvtol_engine::format::group_thousands(u64::MAX)
                    )
                } else {
                    "must be a whole number of at least 1".to_string()
                });
            }
            x as u64
        }
    };
    if value == 0 {
        return Err("must be at least 1".to_string());
    }
    Ok(value)
}

/// A seed of the random streams: a whole number from 0 to 2⁶⁴ − 1 (`_` may group digits).
pub fn parse_seed(text: &str) -> Result<u64, String> {
    text.trim().replace('_', "").parse::<u64>().map_err(|_| {
        format!(
            "must be a whole number from 0 to {}",
            rvtol_engine::format::group_thousands(u64::MAX)
        )
    })
}

/// A share between 0 and 1 (`0.001`).
pub fn parse_share(text: &str) -> Result<f64, String> {
    let x: f64 = text
        .trim()
        .parse()
        .map_err(|_| "must be a number between 0 and 1".to_string())?;
    if (0.0..=1.0).contains(&x) {
        Ok(x)
    } else {
        Err("must be a number between 0 and 1".to_string())
    }
}

/// A memory size in bytes: a number with an optional unit k, M, G or T (powers of 1024,
/// with or without a trailing B or iB: `512M`, `4GiB`, `2.5G`).
pub fn parse_size(text: &str) -> Result<f64, String> {
    let trimmed = text.trim();
    let upper = trimmed.to_ascii_uppercase();
    let unit_start = upper
        .find(|c: char| c.is_ascii_alphabetic())
        .unwrap_or(upper.len());
    let (number, unit) = upper.split_at(unit_start);
    let factor = match unit.trim_end_matches("IB").trim_end_matches('B') {
        "" => 1.0,
        "K" => 1024.0,
        "M" => 1024.0_f64.powi(2),
        "G" => 1024.0_f64.powi(3),
        "T" => 1024.0_f64.powi(4),
        _ => return Err("must be a size such as 512M, 4G or 1073741824".to_string()),
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| "must be a size such as 512M, 4G or 1073741824".to_string())?;
    if !(value.is_finite() && value > 0.0) {
        return Err("must be a positive size such as 512M or 4G".to_string());
    }
    // The budget is compared with byte counts that are u64: a size beyond them (2⁶⁴ bytes,
    // 16 EiB) is no budget any machine has, and would not read back as what was written.
    let bytes = value * factor;
    if bytes >= u64::MAX as f64 {
        return Err("must be less than 16 EiB (18,446,744,073,709,551,616 bytes)".to_string());
    }
    Ok(bytes)
}

/// `--sampling`: a method name.
pub fn parse_sampling(text: &str) -> Result<rvtol_deviation::SamplingMethod, String> {
    use rvtol_deviation::SamplingMethod;
    SamplingMethod::parse(text).ok_or_else(|| {
        format!(
            "unknown method {text:?}, expected one of {}",
            SamplingMethod::NAMES.join(", ")
        )
    })
}

/// `--shard`: `K/N` (0 <= K < N), as rvtol-analysis' shard format reads it.
pub fn parse_shard(text: &str) -> Result<(u64, u64), String> {
    rvtol_analysis::shard::parse_shard(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_read_as_written() {
        assert_eq!(parse_count("1000000"), Ok(1_000_000));
        assert_eq!(parse_count("1_000_000"), Ok(1_000_000));
        assert_eq!(parse_count("1e6"), Ok(1_000_000));
        assert_eq!(parse_count("2.5e6"), Ok(2_500_000));
        assert_eq!(parse_count("1e9"), Ok(1_000_000_000));
        for bad in ["0", "-1", "1.5", "x", "nan", "inf", "-1e6", ""] {
            assert!(parse_count(bad).is_err(), "{bad}");
        }
        assert_eq!(
            parse_count("1e30"),
            Err("must be at most 18,446,744,073,709,551,615".to_string())
        );
        // One above u64::MAX reads as the f64 2⁶⁴, which `as u64` would saturate.
        for beyond in [
            "18446744073709551616",
            "18446744073709551617",
            "1.8446744073709552e19",
        ] {
            assert_eq!(
                parse_count(beyond),
                Err("must be at most 18,446,744,073,709,551,615".to_string()),
                "{beyond}"
            );
        }
        assert_eq!(parse_count("18446744073709551615"), Ok(u64::MAX));
    }

    #[test]
    fn seeds_are_any_u64() {
        assert_eq!(parse_seed("0"), Ok(0));
        assert_eq!(parse_seed("1_000"), Ok(1000));
        assert_eq!(parse_seed("18446744073709551615"), Ok(u64::MAX));
        for bad in ["-1", "1.5", "1e3", "x", "", "18446744073709551616"] {
            assert_eq!(
                parse_seed(bad),
                Err("must be a whole number from 0 to 18,446,744,073,709,551,615".to_string()),
                "{bad}"
            );
        }
    }

    #[test]
    fn shares_and_sizes() {
        assert_eq!(parse_share("0.01"), Ok(0.01));
        assert!(parse_share("1.5").is_err());
        assert!(parse_share("-0.1").is_err());
        assert_eq!(parse_size("512M"), Ok(512.0 * 1024.0 * 1024.0));
        assert_eq!(parse_size("4GiB"), Ok(4.0 * 1024.0_f64.powi(3)));
        assert_eq!(parse_size("1000"), Ok(1000.0));
        assert!(parse_size("4X").is_err());
        assert!(parse_size("-1G").is_err());
        for beyond in ["18446744073709551616", "16777216T", "17179869184G"] {
            assert_eq!(
                parse_size(beyond),
                Err("must be less than 16 EiB (18,446,744,073,709,551,616 bytes)".to_string()),
                "{beyond}"
            );
        }
    }
}
