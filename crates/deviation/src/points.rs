//! The uniform points behind a run's rows under the three sampling methods: plain Monte
//! Carlo (the ChaCha8 streams of the input space, not here), Latin hypercube and
//! randomized quasi-Monte Carlo (scrambled Sobol' points).
//!
//! A [`PointSet`] holds `replicates` independent randomizations of `points` points each in
//! `dims` dimensions; point i of replicate r in dimension d is a pure function of (seed, r,
//! i, d), so any row range can be filled by any thread or shard with the same bits.
//!
//! - **Latin hypercube** (McKay, Beckman & Conover 1979): u = (π_{r,d}(i) + v)/n with
//!   π_{r,d} a random permutation of {0 … n−1} and v uniform on (0, 1): each dimension's n
//!   points fill its n strata once. The permutation is Kensler's hashed permutation
//!   (Kensler 2013, *Correlated Multi-Jittered Sampling*, Pixar TM 13-01, `permute`): a
//!   bijection of the next power of two built from steps that are each invertible on its
//!   low bits, restricted to {0 … n−1} by cycle walking, so it can be evaluated for one
//!   index without materialising the permutation.
//! - **Randomized QMC**: the Sobol' sequence (Sobol' 1967) with the direction numbers of
//!   Joe & Kuo (2008, *Constructing Sobol sequences with better two-dimensional
//!   projections*, file new-joe-kuo-6.21201, from the `sobol` crate), point i computed
//!   directly as the XOR of the direction numbers of i's set bits (consecutive points by one
//!   XOR of a prefix table), then nested uniform scrambling (Owen 1995) by the hash of
//!   Laine & Karras as made practical by Burley (2020, *Practical Hash-based Owen
//!   Scrambling*, JCGT 9(4)) with Vegdahl's constants (2021): on the bit-reversed value,
//!   an addition of the seed, multiplications by odd numbers and x ^= x·(even number),
//!   each of which changes a bit only from the bits below it, so that in the original
//!   order every digit is permuted depending on the digits above it only. The 32 digits
//!   the direction numbers give are followed by 21 uniform digits from a hash of (seed, i,
//!   d): two distinct points differ within their first 32 digits, so independent deeper
//!   digits are exactly what Owen's scrambling gives them. Every point is uniform on
//!   (0, 1)^d, each 2^m-point block of a dimension keeps one point per interval of width
//!   2^−m.
//!
//! sobol_burley was considered and not used: it caps a sequence at 2^16 points and 256
//! dimensions and returns f32 (24 bits: the P99.865 of a run needs the tail below
//! 2^−24, and runs go to 1e7 rows). Here a replicate holds up to 2^32 points and
//! 21 200 dimensions.

use std::sync::OnceLock;

use sobol::params::JoeKuoD6;
use sobol::Sobol;

/// How the rows of a run are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SamplingMethod {
    /// Independent draws from the ChaCha8 streams (the default).
    MonteCarlo,
    /// Latin hypercube: every dimension stratified into n equal-probability strata.
    LatinHypercube,
    /// Randomized quasi-Monte Carlo: Owen-scrambled Sobol' points.
    Rqmc,
}

impl SamplingMethod {
    /// The names a scenario and the command line use, in the order of the variants.
    pub const NAMES: [&'static str; 3] = ["mc", "lhs", "rqmc"];

    /// The method's name in scenarios, reports and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SamplingMethod::MonteCarlo => "mc",
            SamplingMethod::LatinHypercube => "lhs",
            SamplingMethod::Rqmc => "rqmc",
        }
    }

    /// The method of a name.
    pub fn parse(name: &str) -> Option<SamplingMethod> {
        match name {
            "mc" => Some(SamplingMethod::MonteCarlo),
            "lhs" => Some(SamplingMethod::LatinHypercube),
            "rqmc" => Some(SamplingMethod::Rqmc),
            _ => None,
        }
    }

    /// The most points one replicate may hold: 2^32 for Sobol' (32-bit direction numbers),
    /// 2^32 − 1 for the Latin hypercube (a 32-bit permutation); unbounded for Monte Carlo.
    pub fn max_points(self) -> u64 {
        match self {
            SamplingMethod::MonteCarlo => u64::MAX,
            SamplingMethod::LatinHypercube => u32::MAX as u64,
            SamplingMethod::Rqmc => 1 << 32,
        }
    }
}

/// Most dimensions a scrambled Sobol' point set can have (Joe & Kuo's table).
pub const MAX_SOBOL_DIMENSIONS: usize = 21_201;
/// Dimensions of the smaller table, loaded when it suffices.
const STANDARD_SOBOL_DIMENSIONS: usize = 1_000;

/// 2^−53: the spacing of the uniforms (53 random bits).
const UNIT: f64 = 1.0 / (1u64 << 53) as f64;
/// The largest double below 1: no uniform reaches 1 (nor 0), so Φ⁻¹(u) stays finite.
const BELOW_ONE: f64 = 1.0 - UNIT;

/// Points a scrambled Sobol' column is filled by at a time: their coordinates in one
/// sequential pass, their scrambling in a second, independent one.
const FILL_PIECE: usize = 64;

/// The splitmix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer.
#[inline]
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// A uniform in (0, 1) from 53 bits of a hash.
#[inline]
fn unit_interval(bits: u64) -> f64 {
    (((bits >> 11) as f64) + 0.5) * UNIT
}

/// Kensler's hashed permutation of {0 … l−1} (module docs): index i ↦ π_p(i).
#[inline]
fn permute(mut i: u32, l: u32, p: u32) -> u32 {
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    ((i as u64 + p as u64) % l as u64) as u32
}

/// The Laine–Karras hash on the bit-reversed value (module docs): a nested uniform
/// scramble of the 32 digits of `x` for the seed `seed`.
#[inline]
fn owen_scramble(x: u32, seed: u32) -> u32 {
    let mut v = x.reverse_bits();
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v.reverse_bits()
}

/// The prefix XORs P[c] = v_0 ^ … ^ v_c of the 32 direction numbers of every dimension
/// (v_k as the 32-bit integer v_k·2^32), for up to `dims` dimensions.
fn sobol_prefixes(dims: usize) -> Vec<[u32; 32]> {
    static STANDARD: OnceLock<Vec<[u32; 32]>> = OnceLock::new();
    static EXTENDED: OnceLock<Vec<[u32; 32]>> = OnceLock::new();
    let build = |n: usize, params: JoeKuoD6| -> Vec<[u32; 32]> {
        Sobol::<u32>::init_direction_vals::<u32>(n, 32, &params)
            .into_iter()
            .map(|v| {
                let mut prefix = [0u32; 32];
                let mut acc = 0;
                for (p, &d) in prefix.iter_mut().zip(&v) {
                    acc ^= d;
                    *p = acc;
                }
                prefix
            })
            .collect()
    };
    let table = if dims <= STANDARD_SOBOL_DIMENSIONS {
        STANDARD.get_or_init(|| build(STANDARD_SOBOL_DIMENSIONS, JoeKuoD6::standard()))
    } else {
        EXTENDED.get_or_init(|| build(MAX_SOBOL_DIMENSIONS, JoeKuoD6::extended()))
    };
    table[..dims].to_vec()
}

/// The 32-bit Sobol' coordinate of point `i` from a dimension's prefix table:
/// XOR of v_k over the set bits k of i, with v_k = P[k] ^ P[k−1].
#[inline]
fn sobol_coordinate(prefix: &[u32; 32], i: u32) -> u32 {
    let mut x = 0;
    let mut bits = i;
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        x ^= prefix[k] ^ if k > 0 { prefix[k - 1] } else { 0 };
        bits &= bits - 1;
    }
    x
}

/// The randomized points of a Latin hypercube or scrambled Sobol' design (module docs).
#[derive(Debug, Clone)]
pub struct PointSet {
    method: SamplingMethod,
    dims: usize,
    points: u64,
    seed: u64,
    /// Scrambled Sobol' only: each dimension's prefix table.
    prefixes: Vec<[u32; 32]>,
}

impl PointSet {
    /// The design of `method` (Latin hypercube or RQMC) over `dims` dimensions with
    /// `points` points per replicate, randomized from `seed`. Fails, with the reason, when
    /// `points` or `dims` exceed the method's limits or `method` is Monte Carlo.
    pub fn new(
        method: SamplingMethod,
        dims: usize,
        points: u64,
        seed: u64,
    ) -> Result<PointSet, String> {
        if method == SamplingMethod::MonteCarlo {
            return Err("Monte Carlo rows come from the random streams, not a point set".into());
        }
        if points == 0 || points > method.max_points() {
            return Err(format!(
                "{} takes 1 to {} points per replicate, got {points}",
                method.name(),
                method.max_points()
            ));
        }
        if method == SamplingMethod::Rqmc && dims > MAX_SOBOL_DIMENSIONS {
            return Err(format!(
                "scrambled Sobol' points have at most {MAX_SOBOL_DIMENSIONS} dimensions, the inputs need {dims}"
            ));
        }
        let prefixes = if method == SamplingMethod::Rqmc {
            sobol_prefixes(dims)
        } else {
            Vec::new()
        };
        Ok(PointSet {
            method,
            dims,
            points,
            seed,
            prefixes,
        })
    }

    /// Dimensions per point.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// Points per replicate.
    pub fn points(&self) -> u64 {
        self.points
    }

    /// The method.
    pub fn method(&self) -> SamplingMethod {
        self.method
    }

    /// The randomization key of dimension `dim` of replicate `replicate`.
    #[inline]
    fn key(&self, replicate: u64, dim: usize) -> u64 {
        mix(mix(mix(self.seed) ^ replicate) ^ dim as u64)
    }

    /// Fills `out` (column-major: `out[d·count + k]` is dimension d of point first + k)
    /// with points `first .. first + count` of replicate `replicate`, each coordinate in
    /// (0, 1). Panics when the range leaves the replicate (a caller's bug).
    pub fn fill(&self, replicate: u64, first: u64, count: usize, out: &mut [f64]) {
        self.fill_dims(replicate, first, count, 0..self.dims, out);
    }

    /// [`PointSet::fill`] for the dimensions `dims` only: `out[j·count + k]` is dimension
    /// `dims.start + j` of point first + k (the A and B matrices of a sensitivity design
    /// are two windows of one point). Panics when the range leaves the replicate or the
    /// point (a caller's bug).
    pub fn fill_dims(
        &self,
        replicate: u64,
        first: u64,
        count: usize,
        dims: std::ops::Range<usize>,
        out: &mut [f64],
    ) {
        assert!(first + count as u64 <= self.points && dims.end <= self.dims);
        assert!(out.len() >= dims.len() * count);
        for (j, d) in dims.enumerate() {
            let key = self.key(replicate, d);
            let column = &mut out[j * count..(j + 1) * count];
            match self.method {
                SamplingMethod::LatinHypercube => {
                    let (n, p) = (self.points as u32, (key >> 32) as u32);
                    let scale = 1.0 / self.points as f64;
                    for (k, u) in column.iter_mut().enumerate() {
                        let i = first + k as u64;
                        let stratum = permute(i as u32, n, p) as f64;
                        let jitter =
                            unit_interval(mix(key ^ i.wrapping_mul(0xa24b_aed4_963e_e407)));
                        *u = ((stratum + jitter) * scale).min(BELOW_ONE);
                    }
                }
                SamplingMethod::Rqmc => {
                    let prefix = &self.prefixes[d];
                    let seed = (key >> 32) as u32;
                    let mut x = sobol_coordinate(prefix, first as u32);
                    let mut coordinates = [0u32; FILL_PIECE];
                    for (p, piece) in column.chunks_mut(FILL_PIECE).enumerate() {
                        let start = first + (p * FILL_PIECE) as u64;
                        // The Sobol' coordinates, each one XOR from the last (point i + 1
                        // flips bits 0 … c of point i, c = trailing ones of i) ...
                        for (i, slot) in (start..).zip(&mut coordinates[..piece.len()]) {
                            *slot = x;
                            x ^= prefix[(i as u32).trailing_ones().min(31) as usize];
                        }
                        // ... then scrambled and completed each on its own (a loop the
                        // compiler vectorises).
                        let coordinates = &coordinates[..piece.len()];
                        for k in 0..piece.len() {
                            let i = start + k as u64;
                            let digits = owen_scramble(coordinates[k], seed) as u64;
                            let deeper = mix(key ^ i.wrapping_mul(0x9fb2_1c65_1e98_df25)) >> 43;
                            piece[k] =
                                (((digits << 21 | deeper) as f64 + 0.5) * UNIT).min(BELOW_ONE);
                        }
                    }
                }
                SamplingMethod::MonteCarlo => unreachable!("checked in new"),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kensler_permutation_is_a_permutation_for_any_length() {
        for l in [1u32, 2, 3, 7, 64, 100, 1000, 4097] {
            for p in [0u32, 1, 0xdead_beef, 0x1234_5678] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, l, p) as usize;
                    assert!(!seen[j], "l {l} p {p}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn sobol_points_are_the_published_sequence() {
        // Natural-order Sobol' points (Joe & Kuo 2008): dimension 1 is van der Corput
        // (0, 1/2, 1/4, 3/4, …); dimension 2 (s = 1, m1 = 1) has v1 = 1/2, v2 = 3/4, v3 =
        // 5/8, so its points 0 … 3 are 0, 1/2, 3/4, 1/4.
        let p = sobol_prefixes(2);
        let x = |d: usize, i: u32| sobol_coordinate(&p[d], i) as f64 / 2f64.powi(32);
        assert_eq!([x(0, 0), x(0, 1), x(0, 2), x(0, 3)], [0.0, 0.5, 0.25, 0.75]);
        assert_eq!([x(1, 0), x(1, 1), x(1, 2), x(1, 3)], [0.0, 0.5, 0.75, 0.25]);
        assert_eq!(x(1, 4), 0.625);
    }

    #[test]
    fn every_dyadic_block_is_stratified_in_every_dimension() {
        // The defining property the scramble keeps: points k·2^m … (k+1)·2^m − 1 of a
        // dimension have one point in each interval [j/2^m, (j+1)/2^m). The Latin
        // hypercube's n points have one in each [j/n, (j+1)/n).
        let dims = 40;
        for (method, n) in [
            (SamplingMethod::Rqmc, 1024u64),
            (SamplingMethod::LatinHypercube, 1000),
        ] {
            let set = PointSet::new(method, dims, n, 17).unwrap();
            for replicate in 0..3 {
                // Filled in two uneven pieces: the pieces join into the same points.
                let mut whole = vec![0.0; dims * n as usize];
                set.fill(replicate, 0, n as usize, &mut whole);
                let (a, b) = (333usize, n as usize - 333);
                let (mut first, mut second) = (vec![0.0; dims * a], vec![0.0; dims * b]);
                set.fill(replicate, 0, a, &mut first);
                set.fill(replicate, a as u64, b, &mut second);
                for d in 0..dims {
                    let column = &whole[d * n as usize..(d + 1) * n as usize];
                    assert_eq!(&column[..a], &first[d * a..(d + 1) * a]);
                    assert_eq!(&column[a..], &second[d * b..(d + 1) * b]);
                    let mut seen = vec![false; n as usize];
                    for &u in column {
                        assert!(u > 0.0 && u < 1.0);
                        let j = (u * n as f64) as usize;
                        assert!(!seen[j], "{method:?} replicate {replicate} dim {d}");
                        seen[j] = true;
                    }
                }
            }
        }
    }

    #[test]
    fn replicates_and_seeds_randomize_independently() {
        // Coordinate (i, d) over many replicates is uniform: its mean over 4000 replicates
        // is 1/2 within 5 standard errors (√(1/12/4000) = 0.0046).
        for method in [SamplingMethod::Rqmc, SamplingMethod::LatinHypercube] {
            let set = PointSet::new(method, 3, 16, 5).unwrap();
            let mut sums = vec![0.0; 3 * 16];
            let mut out = vec![0.0; 3 * 16];
            for r in 0..4000 {
                set.fill(r, 0, 16, &mut out);
                for (s, u) in sums.iter_mut().zip(&out) {
                    *s += u;
                }
            }
            for s in sums {
                assert!((s / 4000.0 - 0.5).abs() < 5.0 * (1.0 / 12.0 / 4000.0f64).sqrt());
            }
            let other = PointSet::new(method, 3, 16, 6).unwrap();
            let (mut a, mut b) = (vec![0.0; 48], vec![0.0; 48]);
            set.fill(0, 0, 16, &mut a);
            other.fill(0, 0, 16, &mut b);
            assert_ne!(a, b);
        }
    }

    #[test]
    fn limits_are_refused_with_the_reason() {
        assert!(PointSet::new(SamplingMethod::Rqmc, 21_202, 8, 1)
            .unwrap_err()
            .contains("21201"));
        assert!(PointSet::new(SamplingMethod::LatinHypercube, 2, 0, 1)
            .unwrap_err()
            .contains("1 to"));
        assert!(PointSet::new(SamplingMethod::Rqmc, 1_001, 8, 1).is_ok());
    }
}
