//! Test inputs shared by the kernels' tests (the row table's folds.rs and windows.rs, the
//! preload rule's rows.rs): a small deterministic stream, the pins' columns reversed and
//! doubled as the row table's kernels read them, and every instruction set a kernel is
//! built for.

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

/// An instruction set a kernel is built for, or the run-time dispatch the model uses.
#[derive(Clone, Copy)]
pub(crate) enum Width {
    Scalar,
    #[cfg(target_arch = "x86_64")]
    Avx2(pulp::x86::V3),
    #[cfg(target_arch = "x86_64")]
    Avx512(pulp::x86::V4),
    Dispatched,
}

impl Width {
    /// Applies `op` in this width.
    pub fn apply<Op: pulp::WithSimd>(self, op: Op) -> Op::Output {
        use pulp::Simd;
        match self {
            Width::Scalar => Simd::vectorize(pulp::Scalar::new(), op),
            #[cfg(target_arch = "x86_64")]
            Width::Avx2(simd) => Simd::vectorize(simd, op),
            #[cfg(target_arch = "x86_64")]
            Width::Avx512(simd) => Simd::vectorize(simd, op),
            Width::Dispatched => pulp::Arch::new().dispatch(op),
        }
    }
}

/// Every instruction set pulp builds the kernels for that this processor has (scalar,
/// AVX2, AVX-512), and the dispatch, each named: the kernels' tests compare the results of
/// every width bit for bit.
pub(crate) fn every_width() -> Vec<(&'static str, Width)> {
    let mut widths = vec![("scalar", Width::Scalar)];
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(simd) = pulp::x86::V3::try_new() {
            widths.push(("AVX2", Width::Avx2(simd)));
        }
        if let Some(simd) = pulp::x86::V4::try_new() {
            widths.push(("AVX-512", Width::Avx512(simd)));
        }
    }
    widths.push(("dispatched", Width::Dispatched));
    widths
}
