//! A value in another unit: the one conversion the scalar laws and the measured values
//! share when a scenario gives them in µm, degrees or arcminutes (the models take mm and
//! rad).

/// x·f for a change of unit by the factor f, computed as x / (1/f) when 1/f is a whole
/// number (µm to mm divides by 1000): a decimal written in the file (−0.72 µm) then lands
/// on the double nearest its converted decimal (−0.00072 mm), not one a rounding away.
#[inline]
pub fn unit_scale(x: f64, f: f64) -> f64 {
    let inverse = 1.0 / f;
    if inverse.fract() == 0.0 && inverse.abs() < 9.0e15 {
        x / inverse
    } else {
        x * f
    }
}
