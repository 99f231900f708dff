//! Numbers as the reports print them, in one place so that the text tables, the JUnit
//! report, the HTML page and the messages read alike: five significant digits
//! ([`format_sig`]; [`format_rounded`] for a derivative's noisy last digits,
//! [`format_tolerance`] for a tolerance as centre ± half width), a change as a signed percentage ([`format_change`]), ppm
//! ([`format_ppm`]), counts with thousands separators ([`group_thousands`]), aligned text
//! tables ([`text_table`]), and text escaped for XML and HTML ([`escape_markup`]). (Numbers in error messages as a person
//! writes them are rvtol-deviation's `Shown`.)

/// A number with 5 significant digits, switching to exponent form when very large or
/// small.
pub fn format_sig(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "-".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    if x == 0.0 {
        return "0".into();
    }
    let magnitude = x.abs().log10().floor() as i32;
    if !(-4..6).contains(&magnitude) {
        return format!("{x:.4e}");
    }
    let decimals = (4 - magnitude).max(0) as usize;
    format!("{x:.decimals$}")
}

/// [`format_sig`] of x rounded to 7 significant digits first: a derivative by central
/// differences carries rounding noise in its last digits (0.999999999 for 1), which a
/// table of five digits should not show as 1.00000 beside 1.0000.
pub fn format_rounded(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format_sig(x);
    }
    let scale = 10f64.powi(6 - x.abs().log10().floor() as i32);
    format_sig((x * scale).round() / scale)
}

/// A tolerance interval [lower, upper] as its centre ± its half width, both to three
/// significant digits of the half width (`200.000 ± 0.145`); exponent form for a half
/// width below 0.001 or from 100,000 (`2.5000e-5 ± 2.50e-5`).
pub fn format_tolerance(lower: f64, upper: f64) -> String {
    let (centre, half) = (0.5 * (lower + upper), 0.5 * (upper - lower));
    if half == 0.0 || !half.is_finite() {
        return format_sig(centre);
    }
    let magnitude = half.abs().log10().floor() as i32;
    if !(-3..5).contains(&magnitude) {
        return format!("{} ± {half:.2e}", format_sig(centre));
    }
    let decimals = (2 - magnitude).max(0) as usize;
    format!("{centre:.decimals$} ± {half:.decimals$}")
}

/// A figure judged against spec limits as text: [`format_sig`], with a percentile that
/// reads samples beyond the limits (±∞, [`crate::stats::conformity`]) as `beyond`.
pub fn format_figure(x: f64) -> String {
    if x.is_infinite() {
        "beyond".into()
    } else {
        format_sig(x)
    }
}

/// The change a ratio `factor` (new / old) makes, as a signed percentage (`+100.0 %`,
/// `-12.5 %`; `+1.0000e8 %` beyond a million percent); a factor too large for its
/// percentage to be a number reads as the factor (`×1.0000e308`), and one that is no
/// number as `n/a`: a table never shows `inf %`.
pub fn format_change(factor: f64) -> String {
    let percent = (factor - 1.0) * 100.0;
    if !factor.is_finite() {
        "n/a".into()
    } else if !percent.is_finite() {
        format!("×{}", format_sig(factor))
    } else if percent.abs() < 1e6 {
        format!("{percent:+.1} %")
    } else {
        format!(
            "{}{} %",
            if percent > 0.0 { "+" } else { "" },
            format_sig(percent)
        )
    }
}

/// A ppm figure for the text report: [`format_sig`], except that a whole million (every
/// sample out of spec) stays a plain number beside its neighbours (`1000000`, not
/// `1.0000e6`).
pub fn format_ppm(x: f64) -> String {
    if x.is_finite() && x.abs() >= 1e5 {
        format!("{x:.0}")
    } else {
        format_sig(x)
    }
}

/// Text with `&`, `<`, `>`, `"` and `'` escaped for XML and HTML (the JUnit report of
/// `check`, the HTML page).
pub fn escape_markup(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// 10000000 → "10,000,000".
pub fn group_thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A text table: the heading and the rows in columns two spaces apart, the first column
/// left-aligned and the others right-aligned (numbers), each line newline-terminated.
pub fn text_table(heading: &[&str], rows: &[Vec<String>]) -> String {
    let mut widths: Vec<usize> = heading.iter().map(|h| h.chars().count()).collect();
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    let line = |cells: Vec<&str>| {
        let mut text = String::new();
        for (i, (cell, &w)) in cells.iter().zip(&widths).enumerate() {
            let pad = " ".repeat(w - cell.chars().count());
            match i {
                0 => text.push_str(&format!("{cell}{pad}")),
                _ => text.push_str(&format!("  {pad}{cell}")),
            }
        }
        text.trim_end().to_string() + "\n"
    };
    let mut text = line(heading.to_vec());
    for row in rows {
        text.push_str(&line(row.iter().map(String::as_str).collect()));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_text_table_aligns_names_left_and_numbers_right() {
        let rows = vec![
            vec!["subset".to_string(), "1.25".to_string()],
            vec!["importance".to_string(), "10.5".to_string()],
        ];
        assert_eq!(
            text_table(&["method", "ppm"], &rows),
            "method       ppm\nsubset      1.25\nimportance  10.5\n"
        );
    }

    #[test]
    fn a_derivative_loses_its_rounding_noise_and_a_tolerance_reads_as_centre_and_half() {
        assert_eq!(format_rounded(-0.999_999_999_6), "-1.0000");
        assert_eq!(format_rounded(1_801.234_567), "1801.2");
        assert_eq!(format_rounded(0.0), "0");
        assert_eq!(format_tolerance(199.855, 200.145), "200.000 ± 0.145");
        assert_eq!(format_tolerance(1.75, 1.81), "1.7800 ± 0.0300");
        assert_eq!(format_tolerance(0.0, 5e-5), "2.5000e-5 ± 2.50e-5");
        assert_eq!(format_tolerance(3.0, 3.0), "3.0000");
    }
}
