//! The line-contact laws a needle row could be given, side by side: why the chain keeps
//! Palmgren's (docs/models.md §13, "The needle rows' law").
//!
//! ```text
//! Palmgren (1959; Harris 2001 §6.4), measured on rollers between raceways, one contact:
//!   δ_P(Q) = 3.84·10⁻⁵·Q^0.9/l^0.8                       (mm, N, mm); a roller: 2·δ_P
//! ISO/TS 16281 (2008), the standard's roller between its two raceways (all slices):
//!   Q = 35 948·l^(8/9)·δ^(10/9)  ⇔  δ_ISO = (Q/(35 948·l^(8/9)))^0.9
//! Lundberg (1939), finite-length line contact on elastic half-spaces: the pressure is
//! Hertz's semi-ellipse across (half-width b) and uniform along l; the surface of each
//! body at the middle of the contact approaches the body's far field by
//!   w = 2Q(1 − ν²)/(π·E·l)·(ln(l/(2b)) + 1.8864),     1.8864 = ½ + 2·ln 2
//!   (Boussinesq: w = (1 − ν²)/(π·E)·∫ p(x)·2·asinh(l/(2|x|)) dx, p = p0·√(1 − x²/b²),
//!   with asinh(l/(2|x|)) = ln(l/|x|) + O(x²/l²) and ∫₀¹ √(1 − t²)·ln t dt = −(π/8)(1 + 2 ln 2))
//!   b = √(4·Q·R/(π·l·E*)), 1/E* = 2(1 − ν²)/E (two steel bodies), 1/R = 1/R1 ± 1/R2
//!   a contact of two bodies approaches by 2w; a needle between journal (convex) and bore
//!   (concave) by 2w_inner + 2w_outer
//! ```
//!
//! Read as the approach of one body, w alone, Lundberg's expression is 1.67 times stiffer
//! than Palmgren on an RV-20E needle; as the approach of the two bodies it was derived
//! for, 1.20 times softer; ISO/TS 16281 is 3.4 % softer than Palmgren (tests).

use std::f64::consts::PI;

/// ISO/TS 16281's line-contact constant of a roller between two steel raceways, N per
/// mm^(10/9)·mm^(8/9): Q = 35 948·l^(8/9)·δ^(10/9).
pub const ISO_16281_ROLLER: f64 = 35_948.0;

/// Lundberg's constant, ½ + 2·ln 2 = 1.886 294 (printed 1.8864): module comment.
pub const LUNDBERG_CONSTANT: f64 = 0.5 + 2.0 * std::f64::consts::LN_2;

/// Hertz's half-width b of a line contact of two steel bodies, mm, under the force `force`
/// (N) over `length` (mm) with the reduced radius `radius` (mm): b = √(4·Q·R/(π·l·E*)),
/// 1/E* = 2(1 − ν²)/E (Johnson 1985, Eq. 4.43).
pub fn hertz_half_width(force: f64, length: f64, radius: f64, youngs: f64, poisson: f64) -> f64 {
    let contact_modulus = youngs / (2.0 * (1.0 - poisson * poisson));
    (4.0 * force * radius / (PI * length * contact_modulus)).sqrt()
}

/// Lundberg's approach w of one body's surface at the middle of the contact, mm (module
/// comment).
pub fn lundberg_body_approach(
    force: f64,
    length: f64,
    half_width: f64,
    youngs: f64,
    poisson: f64,
) -> f64 {
    2.0 * force * (1.0 - poisson * poisson) / (PI * youngs * length)
        * ((length / (2.0 * half_width)).ln() + LUNDBERG_CONSTANT)
}

/// The approach of a needle of diameter `diameter` between a journal of diameter
/// `journal` and the bore it runs in (journal + 2·diameter), mm, by Lundberg's law with
/// both bodies of each contact counted (`both_bodies`) or, as the expression is sometimes
/// read, one (module comment).
pub fn lundberg_needle_approach(
    force: f64,
    length: f64,
    diameter: f64,
    journal: f64,
    youngs: f64,
    poisson: f64,
    both_bodies: bool,
) -> f64 {
    let needle = 0.5 * diameter;
    let (inner, outer) = (0.5 * journal, 0.5 * journal + diameter);
    let bodies = if both_bodies { 2.0 } else { 1.0 };
    [
        needle * inner / (needle + inner),
        needle * outer / (outer - needle),
    ]
    .iter()
    .map(|&radius| {
        let b = hertz_half_width(force, length, radius, youngs, poisson);
        bodies * lundberg_body_approach(force, length, b, youngs, poisson)
    })
    .sum()
}

/// ISO/TS 16281's approach of a roller between its raceways, mm.
pub fn iso_16281_roller_approach(force: f64, length: f64) -> f64 {
    (force / (ISO_16281_ROLLER * length.powf(8.0 / 9.0))).powf(0.9)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stiffness::line_contact_approach;

    #[test]
    fn lundbergs_constant_is_the_boussinesq_integral_of_the_hertz_strip() {
        // The module comment's derivation checked numerically: the surface displacement at
        // the middle of a semi-elliptic strip, b = 0.0345 mm, l = 6 mm (an RV-20E needle on
        // its journal), by the midpoint rule in x = b·sin t (200 000 points), against the
        // closed form with ½ + 2 ln 2; the O((b/l)²) remainder is below 1e-6.
        let (q, l, b, e, nu): (f64, f64, f64, f64, f64) = (507.85, 6.0, 0.0345, 206_000.0, 0.3);
        let p0 = 2.0 * q / (PI * b * l);
        let steps = 200_000;
        let h = PI / steps as f64;
        let integral: f64 = (0..steps)
            .map(|k| {
                let t = -0.5 * PI + (k as f64 + 0.5) * h;
                let x = b * t.sin();
                p0 * t.cos() * 2.0 * (l / (2.0 * x.abs())).asinh() * b * t.cos() * h
            })
            .sum();
        let numeric = (1.0 - nu * nu) / (PI * e) * integral;
        let closed = lundberg_body_approach(q, l, b, e, nu);
        assert!(
            (numeric / closed - 1.0).abs() < 1e-6,
            "{numeric} vs {closed}"
        );
        assert!((LUNDBERG_CONSTANT - 1.886_294).abs() < 1e-6);
    }

    #[test]
    fn palmgren_lies_between_the_two_readings_of_lundberg_on_an_rv20e_needle() {
        // One needle of the RV-20E row (journal 15 mm, needles 3 × 6 mm) at the most loaded
        // roller's force at rated torque, Q = 4.08·1867.10/15 = 507.85 N (tests/stiffness.rs).
        // Hertz half-widths: inner R = 1.5·7.5/9 = 1.25 mm, b = 0.034499 mm; outer (bore
        // radius 10.5 mm) R = 1.5·10.5/9 = 1.75 mm, b = 0.040820 mm. Lundberg per body:
        // 2Q(1 − ν²)/(πEl) = 2.38052e-4 mm times (ln(l/2b) + 1.886294): inner 6.35125 →
        // 1.51193e-3 mm, outer 6.18298 → 1.47188e-3 mm. Needle: both bodies 5.96762e-3 mm,
        // one body 2.98381e-3 mm; Palmgren (two contacts) 2·3.84e-5·507.85^0.9/6^0.8 =
        // 4.98887e-3 mm; ISO/TS 16281 (507.85/(35948·6^(8/9)))^0.9 = 5.15862e-3 mm.
        let (q, l, d, journal, e, nu) = (507.85, 6.0, 3.0, 15.0, 206_000.0, 0.3);
        let b_inner = hertz_half_width(q, l, 1.25, e, nu);
        let b_outer = hertz_half_width(q, l, 1.75, e, nu);
        assert!((b_inner - 0.034499).abs() < 1e-6 && (b_outer - 0.040820).abs() < 1e-6);
        let both = lundberg_needle_approach(q, l, d, journal, e, nu, true);
        let one = lundberg_needle_approach(q, l, d, journal, e, nu, false);
        let palmgren = 2.0 * line_contact_approach(q, l);
        let iso = iso_16281_roller_approach(q, l);
        assert!((both / 5.96762e-3 - 1.0).abs() < 2e-5, "{both}");
        assert!((one / 2.98381e-3 - 1.0).abs() < 2e-5, "{one}");
        assert!((palmgren / 4.98887e-3 - 1.0).abs() < 1e-5, "{palmgren}");
        assert!((iso / 5.15862e-3 - 1.0).abs() < 1e-5, "{iso}");
        // The ratios docs/models.md quotes: one body 1.67 times stiffer than Palmgren, both
        // bodies 1.20 times softer, ISO 3.4 % softer.
        assert!((palmgren / one - 1.672).abs() < 1e-3);
        assert!((both / palmgren - 1.196).abs() < 1e-3);
        assert!((iso / palmgren - 1.034).abs() < 1e-3);
        // On the row: its radial deflection is its most loaded needle's approach (Stribeck,
        // contact.rs), so the row's slope between 50 and 100 % rated, the part of the
        // rigidity it sets, is (Q/2)/(δ(Q) − δ(Q/2)) in each law, per needle: Palmgren
        // 1.0967e5 N/mm, Lundberg both bodies 0.821 of it, one body 1.643 (the logarithm
        // makes Lundberg's law nearer linear than Q^0.9).
        let slope = |law: &dyn Fn(f64) -> f64| 0.5 * q / (law(q) - law(0.5 * q));
        let palmgren_slope = slope(&|f| 2.0 * line_contact_approach(f, l));
        let both_slope = slope(&|f| lundberg_needle_approach(f, l, d, journal, e, nu, true));
        let one_slope = slope(&|f| lundberg_needle_approach(f, l, d, journal, e, nu, false));
        assert!(
            (palmgren_slope / 1.0967e5 - 1.0).abs() < 1e-4,
            "{palmgren_slope}"
        );
        assert!(
            (both_slope / palmgren_slope - 0.821).abs() < 1e-3,
            "{both_slope}"
        );
        assert!(
            (one_slope / palmgren_slope - 1.643).abs() < 1e-3,
            "{one_slope}"
        );
    }
}
