//! Units a scenario's variables may be written in, converted at load time.
//!
//! The models take lengths in mm and angles in rad. A variable may be written in another
//! unit of the same kind (`µm` or `um`, `m`; `mrad`, `µrad` or `urad`, `deg`, `arcmin`,
//! `arcsec`): when every model input it is bound to wants one unit of that kind, its
//! distribution is converted to that unit at load time (f·X: `ScalarDistribution::scaled`)
//! and its column carries the model's unit from then on (in the report, the sample files
//! and the analyses). A variable bound only to inputs that take any unit (`linear_stack`)
//! keeps its own unit: there the numbers mean what the user wrote. Error messages about a
//! variable's distribution name the unit its values are in.

use std::f64::consts::PI;

/// Known units: (name, kind, value of one unit in the kind's model unit).
const UNITS: &[(&str, &str, f64)] = &[
    ("mm", "length", 1.0),
    ("µm", "length", 1e-3),
    ("um", "length", 1e-3),
    ("m", "length", 1e3),
    ("rad", "angle", 1.0),
    ("mrad", "angle", 1e-3),
    ("µrad", "angle", 1e-6),
    ("urad", "angle", 1e-6),
    ("deg", "angle", PI / 180.0),
    ("arcmin", "angle", PI / 10_800.0),
    ("arcsec", "angle", PI / 648_000.0),
];

/// The Greek small letter mu (U+03BC), which keyboards and editors give as often as the
/// micro sign (U+00B5) that the unit names here use.
const GREEK_MU: char = '\u{3bc}';
/// The micro sign (U+00B5).
const MICRO_SIGN: char = '\u{b5}';

/// A unit as rvtol names it: `μm` and `μrad` written with the Greek letter mu are the same
/// units as `µm` and `µrad` with the micro sign, and are read as those.
pub fn canonical(unit: &str) -> String {
    unit.replace(GREEK_MU, &MICRO_SIGN.to_string())
}

/// The known units, for messages: `lengths mm, µm, um, m; angles rad, …`.
pub fn known() -> String {
    ["length", "angle"]
        .iter()
        .map(|kind| {
            let names: Vec<&str> = UNITS
                .iter()
                .filter(|(_, k, _)| k == kind)
                .map(|(name, _, _)| *name)
                .collect();
            format!("{kind}s {}", names.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Whether `unit` is one of the units rvtol converts.
pub fn is_known(unit: &str) -> bool {
    UNITS.iter().any(|(name, _, _)| *name == unit)
}

/// The factor f that turns a value in `from` into one in `to` (x_to = f·x_from), when both
/// are known units of one kind and differ; `None` otherwise.
pub fn conversion(from: &str, to: &str) -> Option<f64> {
    if from == to {
        return None;
    }
    let find = |unit: &str| UNITS.iter().find(|(name, _, _)| *name == unit);
    match (find(from), find(to)) {
        (Some((_, kind_from, a)), Some((_, kind_to, b))) if kind_from == kind_to => Some(a / b),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_between_units_of_one_kind() {
        assert_eq!(conversion("µm", "mm"), Some(1e-3));
        assert_eq!(conversion("um", "mm"), Some(1e-3));
        assert_eq!(conversion("mm", "µm"), Some(1e3));
        assert_eq!(conversion("arcsec", "rad"), Some(PI / 648_000.0));
        assert_eq!(conversion("arcmin", "rad"), Some(PI / 10_800.0));
        assert_eq!(conversion("deg", "rad"), Some(PI / 180.0));
        // 60 arcsec are one arcmin.
        assert!((conversion("arcsec", "arcmin").unwrap() * 60.0 - 1.0).abs() < 1e-15);
        assert_eq!(conversion("mm", "mm"), None);
        assert_eq!(conversion("µm", "rad"), None);
        // The Greek letter mu is read as the micro sign.
        assert_eq!(canonical("\u{3bc}m"), "\u{b5}m");
        assert_eq!(canonical("\u{3bc}rad"), "µrad");
        assert_eq!(canonical("µm"), "µm");
        assert_eq!(canonical("mm"), "mm");
        assert_eq!(conversion("N", "mm"), None);
        assert_eq!(
            known(),
            "lengths mm, µm, um, m; angles rad, mrad, µrad, urad, deg, arcmin, arcsec"
        );
    }
}
