//! Order spectrum of a curve sampled over one revolution: a radix-2 real FFT, and a direct
//! DFT of a few orders.
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
//!
//! [`OrderDft`] sums the DFT directly at a few fixed orders, when those are all a model
//! reports: with the curve folded to a quarter revolution it costs K·N/2 multiplications
//! and additions for K orders, against the FFT's O(N·log N) complex operations for all of
//! them (for N = 4096 and five orders, an eighth of the FFT's time).
//!
//! Why not `realfft` (over `rustfft`), which computes the same real-to-complex transform
//! with the same packing: its planner picks the algorithm at run time from the CPU's
//! features (AVX and FMA, SSE4.1, Neon), and those algorithms add in other orders, so
//! the spectrum's last bits, and the transmission error's outputs through them, would
//! depend on the machine the run is on; a run must give the same bits everywhere. The
//! split-column form and the direct DFT of a few orders are not offered by it either.

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

/// cos and sin of 2πm/n, reduced exactly in integers to an angle in [0, π/4] before
/// `sin_cos`: every twiddle is that of its first-octant counterpart up to exact sign and
/// swap, the quarter turns are exactly 0 and ±1, the octants ±√½. `n` a multiple of 8.
fn twiddle(m: usize, n: usize) -> (f64, f64) {
    let m = m % n;
    // m/n = (q + r/n)/4 turns: quadrant q, remainder r < n in units of a quarter turn / n.
    let (q, r) = (4 * m / n, 4 * m % n);
    let (c, s) = if 2 * r == n {
        // The octant itself: both √½, rounded once.
        (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        )
    } else if 2 * r < n {
        let (s, c) = (0.5 * PI * r as f64 / n as f64).sin_cos();
        (c, s)
    } else {
        // cos(π/2 − a) = sin a, sin(π/2 − a) = cos a.
        let (s, c) = (0.5 * PI * (n - r) as f64 / n as f64).sin_cos();
        (s, c)
    };
    match q {
        0 => (c, s),
        1 => (-s, c),
        2 => (-c, -s),
        _ => (s, -c),
    }
}

/// Points summed side by side in [`OrderDft`]'s lanes.
const DFT_LANES: usize = 4;

/// Blocks of [`OrderDft`] summed apart before they join the running sums.
const DFT_GROUP: usize = 16;

/// The lanes' sum, in a fixed tree.
#[inline(always)]
fn lane_sum(v: [f64; DFT_LANES]) -> f64 {
    (v[0] + v[1]) + (v[2] + v[3])
}

/// Per order, the lanes of the sums of the folded curve times cos and times sin.
type LaneSums<const K: usize> = [[[f64; DFT_LANES]; 2]; K];

/// The DFT X_k = Σ_j x_j·e^{−2πijk/N} of an N-point real curve at K fixed orders, summed
/// directly (K·N/2 multiplications and additions).
///
/// The curve is folded twice, so that only the quarter 0 ≤ j < N/4 is summed. With
/// c_j = cos(2πkj/N), s_j = sin(2πkj/N), H = N/2: c_{N−j} = c_j and s_{N−j} = −s_j, and
/// c_{H−j} = (−1)^k·c_j and s_{H−j} = −(−1)^k·s_j. Hence
///
/// Re X_k = Σ_{j<N/4} E_j·c_j + (x_{N/4} + x_{3N/4})·cos(πk/2),
/// −Im X_k = Σ_{j<N/4} O_j·s_j + (x_{N/4} − x_{3N/4})·sin(πk/2),
///
/// where, with a_j = x_j + x_{N−j}, b_j = x_{H−j} + x_{H+j}, c'_j = x_j − x_{N−j},
/// d_j = x_{H−j} − x_{H+j} (and a_0 = x_0, b_0 = x_H, c'_0 = d_0 = 0), E_j = a_j ± b_j and
/// O_j = c'_j ∓ d_j, upper signs for even k. The twiddles are exact table values: the
/// angle index k·j mod N is reduced in integers, then to the first octant (see
/// [`twiddle`]); they are laid out per block of [`DFT_LANES`] points and order, so that one
/// pass reads them in order. The sums run in [`DFT_LANES`] fixed lanes, added in a fixed
/// tree: the bits depend on neither the instruction set nor the threads.
#[derive(Debug, Clone)]
pub struct OrderDft<const K: usize> {
    n: usize,
    /// Whether each order is odd (E = a − b, O = c' + d).
    odd: [bool; K],
    /// Per block of DFT_LANES points j < N/4: per order, the lanes' c_j and s_j.
    twiddles: Vec<LaneSums<K>>,
    /// Per order, cos(πk/2) and sin(πk/2): exactly 0 or ±1.
    quarter: [(f64, f64); K],
}

impl<const K: usize> OrderDft<K> {
    /// A plan for the `orders` (each below N/2) of curves of `n` samples; `n` must be a
    /// power of two, at least 16.
    pub fn new(n: usize, orders: [usize; K]) -> OrderDft<K> {
        assert!(n >= 16 && n.is_power_of_two(), "DFT length {n}");
        assert!(
            orders.iter().all(|&k| k < n / 2),
            "orders {orders:?} of {n}"
        );
        let table: Vec<(f64, f64)> = (0..n).map(|m| twiddle(m, n)).collect();
        let twiddles = (0..n / 4 / DFT_LANES)
            .map(|block| {
                orders.map(|k| {
                    let mut lanes = [[0.0; DFT_LANES]; 2];
                    for lane in 0..DFT_LANES {
                        // k < N/2 and j < N/4: k·j < N²/8, reduced exactly.
                        let (c, s) = table[(k * (block * DFT_LANES + lane)) % n];
                        lanes[0][lane] = c;
                        lanes[1][lane] = s;
                    }
                    lanes
                })
            })
            .collect();
        OrderDft {
            n,
            odd: orders.map(|k| k % 2 == 1),
            twiddles,
            quarter: orders.map(|k| table[(k * (n / 4)) % n]),
        }
    }

    /// X_k of each order, as (re, im), from the curve `x` (N samples).
    pub fn bins(&self, x: &[f64]) -> [Complex; K] {
        let n = self.n;
        assert_eq!(x.len(), n);
        let sums = self.lane_sums(x);
        let quarter = n / 4;
        let (a, c) = (x[quarter] + x[3 * quarter], x[quarter] - x[3 * quarter]);
        std::array::from_fn(|k| {
            let (cos, sin) = self.quarter[k];
            (
                lane_sum(sums[k][0]) + a * cos,
                -(lane_sum(sums[k][1]) + c * sin),
            )
        })
    }

    /// Semi-amplitude A_k = 2|X_k|/N of each order.
    pub fn amplitudes(&self, x: &[f64]) -> [f64; K] {
        self.bins(x)
            .map(|(re, im)| 2.0 * re.hypot(im) / self.n as f64)
    }

    /// The lanes of Σ_{j<N/4} E_j·c_j and Σ_{j<N/4} O_j·s_j per order. Not inlined into
    /// [`Self::bins`]: there LLVM's SLP vectoriser grouped the lanes of different orders
    /// (towards the final sums) and shuffled them at every block, 2.5 times slower than
    /// this loop, in which each order's lanes form one vector.
    #[inline(never)]
    fn lane_sums(&self, x: &[f64]) -> LaneSums<K> {
        let n = self.n;
        let (half, quarter) = (n / 2, n / 4);
        let mut sums = [[[0.0; DFT_LANES]; 2]; K];
        // The first block: j = 0 has no mirror about 0 and its mirror about N/4 is x_H.
        let mut first = [[0.0; DFT_LANES]; 4];
        (first[0][0], first[1][0]) = (x[0] + x[half], x[0] - x[half]);
        for lane in 1..DFT_LANES {
            let (a, b) = (x[lane] + x[n - lane], x[half - lane] + x[half + lane]);
            let (c, d) = (x[lane] - x[n - lane], x[half - lane] - x[half + lane]);
            first[0][lane] = a + b;
            first[1][lane] = a - b;
            first[2][lane] = c + d;
            first[3][lane] = c - d;
        }
        self.add_block(&mut sums, &first, &self.twiddles[0]);
        // Block i ≥ 1, j = i·L + lane: x_j and x_{H+j} forwards, x_{N−j} and x_{H−j} from
        // the blocks that end at N − i·L and H − i·L, read backwards. In groups of
        // DFT_GROUP blocks summed apart, so that the rounding grows like that of pairwise
        // sums (as accurate as the FFT against a 40-digit DFT; a single running sum per
        // lane was 2–4 times less).
        let ahead = x[..quarter].as_chunks::<DFT_LANES>().0;
        let ahead_half = x[half..half + quarter].as_chunks::<DFT_LANES>().0;
        let behind = x[n + 1 - quarter..n + 1 - DFT_LANES]
            .as_chunks::<DFT_LANES>()
            .0;
        let behind_half = x[half + 1 - quarter..half + 1 - DFT_LANES]
            .as_chunks::<DFT_LANES>()
            .0;
        let count = ahead.len();
        for start in (1..count).step_by(DFT_GROUP) {
            let end = (start + DFT_GROUP).min(count);
            let blocks = ahead[start..end]
                .iter()
                .zip(behind[count - end..count - start].iter().rev())
                .zip(behind_half[count - end..count - start].iter().rev())
                .zip(&ahead_half[start..end])
                .zip(&self.twiddles[start..end]);
            let mut group = [[[0.0; DFT_LANES]; 2]; K];
            for ((((front, back), front_half), back_half), twiddles) in blocks {
                let mut folded = [[0.0; DFT_LANES]; 4];
                for lane in 0..DFT_LANES {
                    let mirror = DFT_LANES - 1 - lane;
                    let (a, b) = (
                        front[lane] + back[mirror],
                        front_half[mirror] + back_half[lane],
                    );
                    let (c, d) = (
                        front[lane] - back[mirror],
                        front_half[mirror] - back_half[lane],
                    );
                    folded[0][lane] = a + b;
                    folded[1][lane] = a - b;
                    folded[2][lane] = c + d;
                    folded[3][lane] = c - d;
                }
                self.add_block(&mut group, &folded, twiddles);
            }
            for (sum, group) in sums.as_flattened_mut().iter_mut().zip(group.as_flattened()) {
                for lane in 0..DFT_LANES {
                    sum[lane] += group[lane];
                }
            }
        }
        sums
    }

    /// Adds one block: per order, E·c and O·s, lane by lane; `folded` is
    /// [a + b, a − b, c' + d, c' − d].
    #[inline(always)]
    fn add_block(
        &self,
        sums: &mut LaneSums<K>,
        folded: &[[f64; DFT_LANES]; 4],
        twiddles: &LaneSums<K>,
    ) {
        for k in 0..K {
            let (e, o) = if self.odd[k] {
                (&folded[1], &folded[2])
            } else {
                (&folded[0], &folded[3])
            };
            let [cos, sin] = &twiddles[k];
            for lane in 0..DFT_LANES {
                sums[k][0][lane] += e[lane] * cos[lane];
            }
            for lane in 0..DFT_LANES {
                sums[k][1][lane] += o[lane] * sin[lane];
            }
        }
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
    fn twiddles_are_the_first_octant_ones_with_exact_quarter_turns() {
        for n in [16, 64, 4096] {
            for m in 0..2 * n {
                let (c, s) = twiddle(m, n);
                let (s0, c0) = (2.0 * PI * (m % n) as f64 / n as f64).sin_cos();
                assert!((c - c0).abs() < 1e-15 && (s - s0).abs() < 1e-15, "{m}/{n}");
                // Mirror images are exact: the same first-octant value up to sign and swap.
                assert_eq!(twiddle(n - m % n, n), (c, -s), "{m}/{n}");
                assert_eq!(twiddle(m + n / 4, n), (-s, c), "{m}/{n}");
            }
            assert_eq!(twiddle(0, n), (1.0, 0.0));
            assert_eq!(twiddle(n / 4, n), (0.0, 1.0));
            assert_eq!(twiddle(n / 2, n), (-1.0, 0.0));
            assert_eq!(twiddle(3 * n / 4, n), (0.0, -1.0));
        }
    }

    #[test]
    fn order_dft_matches_the_direct_transform_and_the_fft() {
        for n in [16, 64, 512, 4096] {
            let x: Vec<f64> = (0..n)
                .map(|j| ((j * 7919) % 113) as f64 / 17.0 - 3.0)
                .collect();
            let orders = [1, 3, 4, n / 4 - 1, n / 2 - 1];
            let dft_plan = OrderDft::new(n, orders);
            let fft = RealFft::new(n);
            let mut work = vec![(0.0, 0.0); n / 2];
            fft.transform(&x, &mut work);
            let bins = dft_plan.bins(&x);
            let amplitudes = dft_plan.amplitudes(&x);
            for (i, &k) in orders.iter().enumerate() {
                let (a, b) = (bins[i], dft(&x, k));
                assert!(
                    (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                    "n {n} k {k}: {a:?} vs {b:?}"
                );
                let (a, b) = (amplitudes[i], fft.amplitude(&work, k));
                assert!(
                    (a - b).abs() <= 1e-13 * b.abs().max(1.0),
                    "n {n} k {k}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn order_dft_of_sinusoids() {
        let n = 4096;
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let t = 2.0 * PI * j as f64 / n as f64;
                2.5 * (39.0 * t + 0.3).sin() + 0.7 * (t - 1.0).cos() + 4.0 + 0.2 * (80.0 * t).cos()
            })
            .collect();
        let plan = OrderDft::new(n, [1, 39, 40, 78, 80]);
        let a = plan.amplitudes(&x);
        for (value, expected) in a.into_iter().zip([0.7, 2.5, 0.0, 0.0, 0.2]) {
            assert!((value - expected).abs() < 1e-12, "{a:?}");
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
