//! The vector expression of a part's deviation at a point (document 001 Eq. 5–8).
//!
//! ```text
//! φ = ε + θ                                                                  (Eq. 5)
//! ε = Δu·i + Δv·j + Δw·k                                                     (Eq. 6)
//! θ = Δα·r_Δα + Δβ·r_Δβ + Δγ·r_Δγ,   r = L·sin ω                             (Eq. 7, 8)
//! ```
//!
//! For small rotations the displacement of a point p (mm, in the part's frame, measured
//! from the point the deviation refers to) caused by the rotations ω = (Δα, Δβ, Δγ) is
//! θ = ω × p; its magnitude for one rotation is Δ·|p|·sin ω, ω being the angle between the
//! rotation axis and p: the action radius r = L·sin ω of Eq. 8. Units: mm and rad in,
//! mm out.

/// Displacement φ = ε + ω × p (mm) of the point `point_mm` of a part whose deviation is
/// (Δu, Δv, Δw, Δα, Δβ, Δγ).
#[inline]
pub fn point_displacement(deviation: &[f64; 6], point_mm: [f64; 3]) -> [f64; 3] {
    let [du, dv, dw, da, db, dg] = *deviation;
    let [x, y, z] = point_mm;
    [
        du + (db * z - dg * y),
        dv + (dg * x - da * z),
        dw + (da * y - db * x),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn zero_deviation_gives_zero_displacement() {
        assert_eq!(point_displacement(&[0.0; 6], [1.0, 2.0, 3.0]), [0.0; 3]);
    }

    #[test]
    fn tilt_about_x_moves_a_point_on_the_axis_by_its_lever() {
        // A point 100 mm along z, tilted by Δα = 1e-4 rad about x, moves by −0.01 mm in y
        // (action radius r = L·sin 90° = 100 mm, Eq. 8).
        let d = point_displacement(&[0.0, 0.0, 0.0, 1e-4, 0.0, 0.0], [0.0, 0.0, 100.0]);
        assert!((d[1] + 0.01).abs() < 1e-15);
        assert_eq!(d[0], 0.0);
        assert_eq!(d[2], 0.0);
    }

    proptest! {
        #[test]
        fn magnitude_of_one_rotation_is_action_radius(angle in -1e-3f64..1e-3, px in -50.0f64..50.0, py in -50.0f64..50.0, pz in -50.0f64..50.0) {
            // |θ| for a rotation about z alone is |Δγ|·L·sin ω = |Δγ|·sqrt(x² + y²).
            let d = point_displacement(&[0.0, 0.0, 0.0, 0.0, 0.0, angle], [px, py, pz]);
            let magnitude = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let expected = angle.abs() * (px * px + py * py).sqrt();
            prop_assert!((magnitude - expected).abs() <= 1e-12 * (1.0 + expected));
        }
    }
}
