//! Order spectrum of a curve sampled over one revolution: a radix-2 real FFT.
//!
//! A curve x_0..x_{N−1} sampled at N equally spaced angles of one revolution (N a power
//! of two) has the discrete Fourier transform X_k = Σ_j x_j·e^{−2πijk/N}; the order-k
//! component is the sinusoid of k cycles per revolution with semi-amplitude
//! A_k = 2|X_k|/N (1 ≤ k < N/2), the convention of gear transmission-error spectra.
//!
//! The real transform packs the even and odd samples into one complex sequence of N/2
//! points (z_m = x_2m + i·x_2m+1), transforms it with an iterative radix-2
//! decimation-in-time FFT and separates the halves:
//! X_k = ½(Z_k + Z̄_{M−k}) − ½i·e^{−2πik/N}·(Z_k − Z̄_{M−k}), M = N/2. Twiddles and the
//! bit-reversal permutation are computed once per plan; a transform allocates nothing.
//!
//! [`RealFft::transform_split`] is the same transform on separate real and imaginary
//! columns (structure of arrays), whose butterflies vectorise: the same operations in the
//! same order, so the same bits (tested).

use std::f64::consts::PI;

/// A complex number as (re, im).
pub type Complex = (f64, f64);

/// A reusable real-FFT plan for one length.
#[derive(Debug, Clone)]
pub struct RealFft {
    n: usize,
    /// The twiddles of the half-length complex transform stage by stage: the stage that
    /// combines blocks of `half` points uses e^{−2πij/(2·half)}, j < half, stored at
    /// `half − 1 ..= 2·half − 2` (M − 1 in all), so that each stage reads them in order.
    twiddles: Vec<Complex>,
    /// e^{−2πik/N}, k ≤ M, for the separation step.
    unpack: Vec<Complex>,
    /// Bit-reversed index of every m < M.
    bit_reversed: Vec<u32>,
}

impl RealFft {
    /// A plan for curves of `n` samples; `n` must be a power of two, at least 4.
    pub fn new(n: usize) -> RealFft {
        assert!(n >= 4 && n.is_power_of_two(), "FFT length {n}");
        let m = n / 2;
        let bits = m.trailing_zeros();
        let angle = |k: usize, of: usize| -2.0 * PI * k as f64 / of as f64;
        RealFft {
            n,
            twiddles: (0..bits)
                .flat_map(|stage| {
                    let half = 1usize << stage;
                    (0..half).map(move |j| {
                        let (s, c) = angle(j, 2 * half).sin_cos();
                        (c, s)
                    })
                })
                .collect(),
            unpack: (0..=m)
                .map(|k| {
                    let (s, c) = angle(k, n).sin_cos();
                    (c, s)
                })
                .collect(),
            bit_reversed: (0..m as u32)
                .map(|i| {
                    if bits == 0 {
                        0
                    } else {
                        i.reverse_bits() >> (32 - bits)
                    }
                })
                .collect(),
        }
    }

    /// Curve length N.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false: a plan has at least 4 points.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Transforms `x` (N samples) into the half-length work buffer `work` (N/2 complex):
    /// afterwards [`Self::bin`] gives any X_k.
    pub fn transform(&self, x: &[f64], work: &mut [Complex]) {
        let m = self.n / 2;
        assert_eq!(x.len(), self.n);
        assert_eq!(work.len(), m);
        for (i, &r) in self.bit_reversed.iter().enumerate() {
            work[r as usize] = (x[2 * i], x[2 * i + 1]);
        }
        let mut half = 1;
        while half < m {
            let twiddles = &self.twiddles[half - 1..2 * half - 1];
            for block in work.chunks_exact_mut(2 * half) {
                let (lower, upper) = block.split_at_mut(half);
                for ((a, b), w) in lower.iter_mut().zip(upper.iter_mut()).zip(twiddles) {
                    let t = (b.0 * w.0 - b.1 * w.1, b.0 * w.1 + b.1 * w.0);
                    (*a, *b) = ((a.0 + t.0, a.1 + t.1), (a.0 - t.0, a.1 - t.1));
                }
            }
            half *= 2;
        }
    }

    /// [`Self::transform`] into separate real and imaginary columns of N/2 values each;
    /// [`Self::split_amplitude`] then gives A_k.
    pub fn transform_split(&self, x: &[f64], re: &mut [f64], im: &mut [f64]) {
        let m = self.n / 2;
        assert_eq!(x.len(), self.n);
        assert!(re.len() == m && im.len() == m);
        for (i, &r) in self.bit_reversed.iter().enumerate() {
            re[r as usize] = x[2 * i];
            im[r as usize] = x[2 * i + 1];
        }
        let mut half = 1;
        while half < m {
            let twiddles = &self.twiddles[half - 1..2 * half - 1];
            for (block_re, block_im) in re
                .chunks_exact_mut(2 * half)
                .zip(im.chunks_exact_mut(2 * half))
            {
                let (lower_re, upper_re) = block_re.split_at_mut(half);
                let (lower_im, upper_im) = block_im.split_at_mut(half);
                for j in 0..half {
                    let (wr, wi) = twiddles[j];
                    let (br, bi) = (upper_re[j], upper_im[j]);
                    let (tr, ti) = (br * wr - bi * wi, br * wi + bi * wr);
                    let (ar, ai) = (lower_re[j], lower_im[j]);
                    lower_re[j] = ar + tr;
                    lower_im[j] = ai + ti;
                    upper_re[j] = ar - tr;
                    upper_im[j] = ai - ti;
                }
            }
            half *= 2;
        }
    }

    /// Semi-amplitude A_k (1 ≤ k < N/2) from the columns of [`Self::transform_split`].
    pub fn split_amplitude(&self, re: &[f64], im: &[f64], k: usize) -> f64 {
        let m = self.n / 2;
        let z = (re[k % m], im[k % m]);
        let other = (m - k % m) % m;
        let zc = (re[other], -im[other]);
        let even = (0.5 * (z.0 + zc.0), 0.5 * (z.1 + zc.1));
        let diff = (0.5 * (z.0 - zc.0), 0.5 * (z.1 - zc.1));
        let odd = (diff.1, -diff.0);
        let w = self.unpack[k];
        let (x_re, x_im) = (
            even.0 + w.0 * odd.0 - w.1 * odd.1,
            even.1 + w.0 * odd.1 + w.1 * odd.0,
        );
        2.0 * x_re.hypot(x_im) / self.n as f64
    }

    /// X_k (0 ≤ k ≤ N/2) from a work buffer filled by [`Self::transform`].
    pub fn bin(&self, work: &[Complex], k: usize) -> Complex {
        let m = self.n / 2;
        let z = work[k % m];
        let zc = work[(m - k % m) % m];
        let zc = (zc.0, -zc.1);
        let even = (0.5 * (z.0 + zc.0), 0.5 * (z.1 + zc.1));
        let diff = (0.5 * (z.0 - zc.0), 0.5 * (z.1 - zc.1));
        // odd = −i·diff, then times the twiddle.
        let odd = (diff.1, -diff.0);
        let w = self.unpack[k];
        (
            even.0 + w.0 * odd.0 - w.1 * odd.1,
            even.1 + w.0 * odd.1 + w.1 * odd.0,
        )
    }

    /// Semi-amplitude A_k = 2|X_k|/N of order k (1 ≤ k < N/2).
    pub fn amplitude(&self, work: &[Complex], k: usize) -> f64 {
        let (re, im) = self.bin(work, k);
        2.0 * re.hypot(im) / self.n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct O(N²) DFT, the definition the FFT must reproduce.
    fn dft(x: &[f64], k: usize) -> Complex {
        let n = x.len();
        x.iter().enumerate().fold((0.0, 0.0), |acc, (j, &v)| {
            let (s, c) = (-2.0 * PI * (j * k) as f64 / n as f64).sin_cos();
            (acc.0 + v * c, acc.1 + v * s)
        })
    }

    #[test]
    fn matches_the_direct_transform() {
        for n in [4, 8, 64, 512] {
            let x: Vec<f64> = (0..n)
                .map(|j| ((j * 7919) % 113) as f64 / 17.0 - 3.0)
                .collect();
            let fft = RealFft::new(n);
            let mut work = vec![(0.0, 0.0); n / 2];
            fft.transform(&x, &mut work);
            for k in 0..=n / 2 {
                let (a, b) = (fft.bin(&work, k), dft(&x, k));
                assert!(
                    (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                    "n {n} k {k}: {a:?} vs {b:?}"
                );
            }
        }
    }

    #[test]
    fn split_columns_give_the_same_amplitudes() {
        // The structure-of-arrays transform performs the same butterflies in the same
        // order: its amplitudes have the interleaved one's bits.
        for n in [4, 64, 4096] {
            let x: Vec<f64> = (0..n)
                .map(|j| ((j * 7919) % 113) as f64 / 17.0 - 3.0)
                .collect();
            let fft = RealFft::new(n);
            let mut work = vec![(0.0, 0.0); n / 2];
            fft.transform(&x, &mut work);
            let (mut re, mut im) = (vec![0.0; n / 2], vec![0.0; n / 2]);
            fft.transform_split(&x, &mut re, &mut im);
            for k in 1..n / 2 {
                let (a, b) = (fft.amplitude(&work, k), fft.split_amplitude(&re, &im, k));
                assert_eq!(a.to_bits(), b.to_bits(), "n {n} k {k}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn a_sinusoid_has_its_semi_amplitude_at_its_order() {
        let n = 4096;
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let t = 2.0 * PI * j as f64 / n as f64;
                2.5 * (39.0 * t + 0.3).sin() + 0.7 * (t - 1.0).cos() + 4.0
            })
            .collect();
        let fft = RealFft::new(n);
        let mut work = vec![(0.0, 0.0); n / 2];
        fft.transform(&x, &mut work);
        assert!((fft.amplitude(&work, 39) - 2.5).abs() < 1e-12);
        assert!((fft.amplitude(&work, 1) - 0.7).abs() < 1e-12);
        assert!(fft.amplitude(&work, 40) < 1e-12);
        assert!((fft.bin(&work, 0).0 / n as f64 - 4.0).abs() < 1e-12);
    }
}
