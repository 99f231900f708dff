//! The involute first stage seen from the output with the input locked
//! (docs/models.md §13).
//!
//! ```text
//! the sun–planet mesh (ISO 6336-1 mesh stiffness c_γ per mm of face width b) and the
//! crank's torsion between its planet and its eccentrics turn the crank by
//! δφ = M_c·(1/(c_γ·b·r_b2²) + L_t/(G·J)); the crank torque is M_c = T·(z2/z1)/(i·m) and
//! δφ reaches the output as δφ·z2/(z1·i), so
//!   C_inv = (z2/(z1·i))²·(1/(c_γ·b·r_b2²) + L_t/(G·J))/m                (rad per N·mm)
//! ```

/// The involute first stage seen from the output with the input locked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvoluteStage {
    /// z1, sun teeth.
    pub sun_teeth: f64,
    /// z2, planet teeth.
    pub planet_teeth: f64,
    /// m, cranks (planets).
    pub cranks: f64,
    /// r_b2, planet base radius, mm.
    pub planet_base_radius: f64,
    /// b, face width of the sun–planet mesh, mm.
    pub face_width: f64,
    /// c_γ, mesh stiffness per mm of face width, N/mm per mm (ISO 6336-1: N/(mm·µm) × 1000).
    pub mesh_stiffness: f64,
    /// L_t, crank length between the planet gear and the middle of its eccentrics, mm.
    pub torsion_length: f64,
}

impl InvoluteStage {
    /// C_inv, output angle per output torque, rad per N·mm, for the overall ratio `ratio`
    /// and the crank's torsional rigidity G·J (module comment).
    pub fn output_compliance(&self, ratio: f64, crank_torsional_rigidity: f64) -> f64 {
        let reflection = self.planet_teeth / (self.sun_teeth * ratio);
        let crank = 1.0 / (self.mesh_stiffness * self.face_width * self.planet_base_radius.powi(2))
            + self.torsion_length / crank_torsional_rigidity;
        reflection * reflection * crank / self.cranks
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn involute_stage_reflects_by_the_square_of_the_crank_ratio() {
        // RV-20E-141 (z1 12, z2 42, two cranks, i 141): reflection 42/(12·141) = 0.024823.
        let stage = InvoluteStage {
            sun_teeth: 12.0,
            planet_teeth: 42.0,
            cranks: 2.0,
            planet_base_radius: 20.0,
            face_width: 8.0,
            mesh_stiffness: 20_000.0,
            torsion_length: 20.0,
        };
        let gj = 1e9;
        let reflection: f64 = 42.0 / (12.0 * 141.0);
        let hand = reflection.powi(2) * (1.0 / (20_000.0 * 8.0 * 400.0) + 20.0 / gj) / 2.0;
        assert!((stage.output_compliance(141.0, gj) / hand - 1.0).abs() < 1e-14);
    }
}
