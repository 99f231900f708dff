//! Test inputs shared by the row table's kernel tests (folds.rs, windows.rs): a small
//! deterministic stream and the pins' columns reversed and doubled as the kernels read them.

/// A small deterministic stream in [−1, 1) (a linear congruential generator).
pub(crate) fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// A pin column reversed and doubled (`folds::Turned`): entry u holds pin
/// z_p − 1 − (u mod z_p).
pub(crate) fn doubled(v: &[f64]) -> Vec<f64> {
    let pins = v.len();
    (0..2 * pins)
        .map(|u| v[(2 * pins - 1 - u) % pins])
        .collect()
}
