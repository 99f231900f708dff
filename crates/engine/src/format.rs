//! Numbers as the reports print them, in one place so that the text tables, the JUnit
//! report, the HTML page and the messages read alike: five significant digits
//! ([`format_sig`]), a change as a signed percentage ([`format_change`]), ppm
//! ([`format_ppm`]), counts with thousands separators ([`group_thousands`]), and text
//! escaped for XML and HTML ([`escape_markup`]). (Numbers in error messages as a person
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
