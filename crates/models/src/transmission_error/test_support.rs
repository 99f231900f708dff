//! What the transmission-error model's three test modules share: the literal reading's
//! (`literal.rs`), the physical reading's (`two_discs.rs`) and the reading under load's
//! (`loaded/tests.rs`).

use super::TransmissionError;
use crate::{ErrorModel, ModelParams, ParamValue};

/// The model of `params` (which must build).
pub(super) fn with(params: ModelParams) -> TransmissionError {
    TransmissionError::from_params(&params).unwrap()
}

/// `params` with the text parameter `key` set to `value`.
pub(super) fn text(params: ModelParams, key: &str, value: &str) -> ModelParams {
    params.with(key, ParamValue::Text(value.into()))
}

/// A zero row with the named inputs set.
pub(super) fn row(model: &TransmissionError, set: &[(&str, f64)]) -> Vec<f64> {
    let mut row = vec![0.0; model.inputs().len()];
    for (name, value) in set {
        row[model.input_index(name).unwrap_or_else(|| panic!("{name}"))] = *value;
    }
    row
}

/// The model's outputs on `row`.
pub(super) fn outputs(model: &TransmissionError, row: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; model.outputs().len()];
    model.evaluate(row, &mut out);
    out
}

/// 003's modification: a play 2δ* = 2(Δr_rp − Δr_p·√(1 − K1²))/(a·z_c) = 126.9″ per disc
/// (see `modification` in two_discs.rs).
pub(super) const MODIFIED: [(&str, f64); 2] = [
    ("equidistant_modification_mm", 0.01),
    ("shift_modification_mm", -0.008),
];

/// Values in [−½, ½) from a xorshift stream of `seed`.
pub(super) fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}
