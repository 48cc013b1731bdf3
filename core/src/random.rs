//! Random variates from a caller's generator: the one place every scheme draws from.
//!
//! Uniforms (`unit_f64`, `open_unit`), exactly uniform bounded integers (Lemire's
//! multiply-and-reject, `below`), exponentials (`exp1` by the logarithm, `Ziggurat` by
//! Marsaglia & Tsang's ziggurat), geometric counts, normals (Marsaglia's polar method),
//! gamma (Marsaglia & Tsang 2000), beta and small binomials. All take `&mut R` with
//! `R: Rng + ?Sized`, and all floating point goes through `libm`, so a seed gives the
//! same bits on every platform.
//!
//! The **seed policy** lives here too: [`generator`]`(seed, stream)` is the stream
//! every front end (Rust, the C ABI, the CLI) derives from a seed, so the same seed and
//! stream give the same run everywhere; [`substream`] derives the independent streams a
//! scheme's set-up needs (e.g. the key of a randomised sequence) from the same pair.
//!
//! # Example
//! ```
//! use coagula_core::random::generator;
//! use rand_core::Rng;
//! let (mut a, mut b) = (generator(42, 54), generator(42, 54));
//! assert_eq!(a.next_u64(), b.next_u64());
//! assert_ne!(generator(42, 54).next_u64(), generator(42, 55).next_u64());
//! ```

use rand_core::{Infallible, Rng, TryRng};

/// xoshiro256++ (Blackman & Vigna 2019): 256 bits of state, period `2^256 − 1`, four
/// xor/shift/rotate steps and one add per draw. It is the seed policy's generator: on the
/// bucketed layout's largest Brownian row (10^7 monomers to t = 10^5) a run takes 6.6 s
/// with it against 7.0 s with PCG-XSL-RR-128/64 (MCG) and 7.5 s with the 128-bit LCG
/// with a stream increment (O'Neill's `pcg64`), the generator's latency being on the
/// proposal loop's critical path. Its whole state is four words
/// ([`Xoshiro256PlusPlus::parts`]), which is what a checkpoint stores.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Xoshiro256PlusPlus {
    s: [u64; 4],
}

/// The generator of the seed policy (see [`generator`]).
pub type Generator = Xoshiro256PlusPlus;

/// SplitMix64's output function (Steele, Lea & Flood 2014): a bijection of `u64` that
/// mixes every input bit into every output bit.
#[inline]
const fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

impl Xoshiro256PlusPlus {
    /// The generator with state `s` as it is (the reference's `s[0..4]`); `None` for the
    /// all-zero state, which the generator never leaves.
    pub fn from_parts(s: [u64; 4]) -> Option<Self> {
        (s != [0; 4]).then_some(Xoshiro256PlusPlus { s })
    }

    /// The generator with state `s`, which the caller knows is not all zero (the state
    /// of another generator).
    #[inline(always)]
    pub(crate) fn from_parts_unchecked(s: [u64; 4]) -> Self {
        Xoshiro256PlusPlus { s }
    }

    /// The state words (`s[0..4]` of the reference implementation).
    pub fn parts(&self) -> [u64; 4] {
        self.s
    }

    /// The generator of `(seed, stream)`: both are mixed (SplitMix64 rounds) into the
    /// 256-bit state, so distinct pairs start at unrelated points of the period.
    pub fn new(seed: u64, stream: u64) -> Self {
        let a = mix64(seed.wrapping_add(GOLDEN));
        let b = mix64(stream.wrapping_add(GOLDEN.wrapping_mul(2)) ^ a);
        let mut s = [0u64; 4];
        for (i, w) in s.iter_mut().enumerate() {
            let i = i as u64;
            *w = mix64(a.wrapping_add(GOLDEN.wrapping_mul(i + 3)))
                ^ mix64(b.wrapping_add(GOLDEN.wrapping_mul(i + 7)));
        }
        if s == [0; 4] {
            s[0] = GOLDEN;
        }
        Xoshiro256PlusPlus { s }
    }
}

impl TryRng for Xoshiro256PlusPlus {
    type Error = Infallible;

    #[inline]
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok((self.try_next_u64()? >> 32) as u32)
    }

    #[inline]
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        let s = &mut self.s;
        let r = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        Ok(r)
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let w = self.try_next_u64()?.to_le_bytes();
            chunk.copy_from_slice(&w[..chunk.len()]);
        }
        Ok(())
    }
}

/// The seed policy: the generator of `(seed, stream)`. Every front end (Rust, the C
/// ABI, the CLI) derives its random stream from a seed this way, so a seed means the
/// same run everywhere.
pub fn generator(seed: u64, stream: u64) -> Generator {
    Xoshiro256PlusPlus::new(seed, stream)
}

/// What a derived stream is for (each purpose is independent of the main stream and of
/// the others).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Purpose {
    /// The random parameters of a randomised (scrambled, shifted) sequence.
    Scrambling,
    /// Replica `r` of an ensemble (replica 0 is the main stream itself).
    Replica(u64),
    /// Random parameters of an initial state (e.g. the shift of a lattice of quantiles).
    Initial,
    /// The velocities of a gas's initial particles (Maxwellian draws).
    Velocities,
}

/// An independent generator derived from `(seed, stream)` for `purpose`: the scrambling
/// of a sequence draws from its own stream, so the sim's main stream is the same with
/// and without it; replica r gets the stream `stream + r` of a seed mixed with r.
pub fn substream(seed: u64, stream: u64, purpose: Purpose) -> Generator {
    match purpose {
        Purpose::Scrambling => generator(seed ^ 0x5c4a_3b1e_0000_0001, stream),
        Purpose::Initial => generator(seed ^ 0x1a17_0c3d_0000_0002, stream),
        Purpose::Velocities => generator(seed, stream ^ 0x5645_4c4f_4349_5459),
        Purpose::Replica(0) => generator(seed, stream),
        Purpose::Replica(r) => generator(mix64(seed ^ r.wrapping_mul(GOLDEN)), stream ^ mix64(r)),
    }
}

/// Maps 64 random bits to a double in `[0, 1)` (top 53 bits).
#[inline]
pub fn unit_f64(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform double in `(0, 1]` (never 0, so `ln` is finite).
#[inline]
pub(crate) fn open_unit<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    ((rng.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// An exponential variate with mean 1.
#[inline]
pub(crate) fn exp1<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    -libm::log(open_unit(rng))
}

/// Rejection loops give up after this many tries in a row and return a fallback
/// value: a real generator fails one of them that often with probability below
/// 2^-1000, so only a degenerate stream (a host callback returning constant bits)
/// gets there — and it cannot hang a call. (The C ABI detects such a stream itself
/// and reports it.)
pub(crate) const MAX_TRIES: u32 = 1000;

/// A uniform integer in `[0, n)`, exactly (Lemire's multiply-and-reject), `n ≥ 1`.
#[inline]
pub(crate) fn below<Rn: Rng + ?Sized>(rng: &mut Rn, n: u64) -> u64 {
    let mut m = u128::from(rng.next_u64()) * u128::from(n);
    if (m as u64) < n {
        let threshold = n.wrapping_neg() % n;
        let mut tries = 0;
        while (m as u64) < threshold && tries < MAX_TRIES {
            m = u128::from(rng.next_u64()) * u128::from(n);
            tries += 1;
        }
    }
    (m >> 64) as u64
}

/// A uniform integer in `[0, n)` for a 128-bit `n` (a total mass of many particles):
/// [`below`] when `n` fits 64 bits, else masked rejection; `None` for `n = 0`.
pub(crate) fn below_wide<Rn: Rng + ?Sized>(rng: &mut Rn, n: u128) -> Option<u128> {
    if n == 0 {
        return None;
    }
    if let Ok(m) = u64::try_from(n) {
        return Some(u128::from(below(rng, m)));
    }
    let mask = u128::MAX >> (n - 1).leading_zeros();
    let mut r = 0;
    for _ in 0..MAX_TRIES {
        r = (u128::from(rng.next_u64()) << 64 | u128::from(rng.next_u64())) & mask;
        if r < n {
            return Some(r);
        }
    }
    // (a degenerate stream only: the mask takes more than half the range each try)
    Some(r % n)
}

/// Failures before the first success of Bernoulli(p) trials (`u64::MAX` for p = 0).
pub(crate) fn geometric<Rn: Rng + ?Sized>(p: f64, rng: &mut Rn) -> u64 {
    if p <= 0.0 {
        return u64::MAX;
    }
    if p >= 1.0 {
        return 0;
    }
    let g = libm::log(open_unit(rng)) / libm::log1p(-p);
    if g < 1.8e19 { g as u64 } else { u64::MAX }
}

/// A standard normal variate (Marsaglia's polar method).
pub(crate) fn normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    for _ in 0..MAX_TRIES {
        let u = 2.0 * open_unit(rng) - 1.0;
        let v = 2.0 * open_unit(rng) - 1.0;
        let s = u * u + v * v;
        if s < 1.0 && s > 0.0 {
            return u * libm::sqrt(-2.0 * libm::log(s) / s);
        }
    }
    0.0
}

/// A gamma variate of shape `a ≥ 1` and unit scale (Marsaglia & Tsang 2000).
pub(crate) fn gamma<R: Rng + ?Sized>(a: f64, rng: &mut R) -> f64 {
    debug_assert!(a >= 1.0);
    let d = a - 1.0 / 3.0;
    let c = 1.0 / libm::sqrt(9.0 * d);
    for _ in 0..MAX_TRIES {
        let x = normal(rng);
        let v = 1.0 + c * x;
        if v <= 0.0 {
            continue;
        }
        let v = v * v * v;
        let u = open_unit(rng);
        let x2 = x * x;
        if u < 1.0 - 0.0331 * x2 * x2 || libm::log(u) < 0.5 * x2 + d * (1.0 - v + libm::log(v)) {
            return d * v;
        }
    }
    d
}

/// A beta variate of shapes `a, b ≥ 1`.
pub(crate) fn beta<R: Rng + ?Sized>(a: f64, b: f64, rng: &mut R) -> f64 {
    let x = gamma(a, rng);
    let y = gamma(b, rng);
    x / (x + y)
}

/// A binomial `(n, p)` variate by counting `n` uniforms: O(n), for rare paths only.
pub(crate) fn binomial_by_count<R: Rng + ?Sized>(n: u64, p: f64, rng: &mut R) -> u64 {
    (0..n).filter(|_| open_unit(rng) <= p).count() as u64
}

/// Exponential variates by the ziggurat method (Marsaglia & Tsang 2000), 256 layers:
/// one 64-bit draw, one multiply and one comparison in ~99% of calls, exact in
/// distribution (the rare wedge and tail cases fall back to `exp`/`ln`). The tables are
/// constants ([`ziggurat_table`]), computed with `libm` and checked bit for bit against
/// that computation by a test, so they are identical on every platform and building a
/// scheme costs no 500 `exp`/`ln` calls (which dominated small systems).
#[derive(Clone, Copy)]
pub(crate) struct Ziggurat;

impl core::fmt::Debug for Ziggurat {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Ziggurat")
    }
}

/// Rightmost layer boundary and layer area of the 256-layer exponential ziggurat.
const ZIG_EXP_R: f64 = 7.697_117_470_131_05;
#[cfg(test)]
const ZIG_EXP_V: f64 = 0.003_949_659_822_581_557;

mod ziggurat_table;

impl Ziggurat {
    pub(crate) fn new() -> Self {
        Ziggurat
    }

    /// The tables as `libm` computes them: layer boundaries `x` and `f = exp(−x)`.
    #[cfg(test)]
    fn compute() -> ([f64; 257], [f64; 257]) {
        let (mut x, mut f) = ([0.0; 257], [0.0; 257]);
        let fr = libm::exp(-ZIG_EXP_R);
        x[0] = ZIG_EXP_V / fr;
        x[1] = ZIG_EXP_R;
        for i in 2..256 {
            x[i] = -libm::log(ZIG_EXP_V / x[i - 1] + libm::exp(-x[i - 1]));
        }
        x[256] = 0.0;
        for i in 0..257 {
            f[i] = libm::exp(-x[i]);
        }
        (x, f)
    }

    /// An exponential variate with mean 1.
    #[inline(always)]
    pub(crate) fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let (xs, fs) = (&ziggurat_table::X, &ziggurat_table::F);
        for _ in 0..MAX_TRIES {
            let bits = rng.next_u64();
            let i = (bits & 0xff) as usize;
            let u = (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
            let x = u * xs[i];
            if x < xs[i + 1] {
                return x;
            }
            if i == 0 {
                // tail beyond R: memoryless, R + Exp(1)
                return ZIG_EXP_R + exp1(rng);
            }
            let y = fs[i + 1] + (fs[i] - fs[i + 1]) * crate::tree::unit_f64(rng.next_u64());
            if y < libm::exp(-x) {
                return x;
            }
        }
        1.0
    }
}

/// Standard normal variates by the ziggurat method (Marsaglia & Tsang 2000, 256
/// layers, the sign from a bit of the same draw as the layer and the abscissa): one
/// 64-bit draw, one multiply and one comparison in ~98.8% of calls, exact in
/// distribution (wedges against `exp`, the tail beyond R by Marsaglia's exponential
/// method). Tables are constants ([`normal_table`]) that a test checks bit for bit
/// against their `libm` computation. The Langevin schemes take one or two per step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NormalZiggurat;

/// Rightmost layer boundary and layer area of the 256-layer normal ziggurat (for the
/// density `exp(−x²/2)` without its normalisation).
const ZIG_NORM_R: f64 = 3.654_152_885_361_009;
#[cfg(test)]
const ZIG_NORM_V: f64 = 0.004_928_673_233_992_336;

mod normal_table;

impl NormalZiggurat {
    /// The tables as `libm` computes them: layer boundaries `x` and `f = exp(−x²/2)`.
    #[cfg(test)]
    fn compute() -> ([f64; 257], [f64; 257]) {
        let dens = |x: f64| libm::exp(-0.5 * x * x);
        let (mut x, mut f) = ([0.0; 257], [0.0; 257]);
        x[0] = ZIG_NORM_V / dens(ZIG_NORM_R);
        x[1] = ZIG_NORM_R;
        for i in 2..256 {
            x[i] = libm::sqrt(-2.0 * libm::log(ZIG_NORM_V / x[i - 1] + dens(x[i - 1])));
        }
        x[256] = 0.0;
        for i in 0..257 {
            f[i] = dens(x[i]);
        }
        (x, f)
    }

    /// A standard normal variate.
    #[inline(always)]
    pub(crate) fn sample<R: Rng + ?Sized>(rng: &mut R) -> f64 {
        let (xs, fs) = (&normal_table::X, &normal_table::F);
        for _ in 0..MAX_TRIES {
            let bits = rng.next_u64();
            let i = (bits & 0xff) as usize;
            // bit 8 is the sign; bits 11.. the abscissa (disjoint from the layer bits)
            let sign = f64::from_bits(((bits >> 8) & 1) << 63 | 1.0f64.to_bits());
            let u = (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
            let x = u * xs[i];
            if x < xs[i + 1] {
                return sign * x;
            }
            if i == 0 {
                // tail beyond R (Marsaglia 1964): R + a with a ~ Exp(R), kept with
                // probability exp(−a²/2)
                for _ in 0..MAX_TRIES {
                    let a = -libm::log(open_unit(rng)) / ZIG_NORM_R;
                    let b = -libm::log(open_unit(rng));
                    if 2.0 * b > a * a {
                        return sign * (ZIG_NORM_R + a);
                    }
                }
                return sign * ZIG_NORM_R;
            }
            let y = fs[i + 1] + (fs[i] - fs[i + 1]) * crate::tree::unit_f64(rng.next_u64());
            if y < libm::exp(-0.5 * x * x) {
                return sign * x;
            }
        }
        0.0
    }
}

/// Sample mean and variance (for the variate tests here and in `scheme::clock`).
#[cfg(test)]
pub(crate) fn mean_var(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let v = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use rand_core::SeedableRng;

    /// Published vectors of the reference implementation: from `s = {1, 2, 3, 4}` the
    /// first output is `rotl(1 + 4, 23) + 1 = 41943041`; from `s = {0, 0, 0, 1}` the
    /// first ten (as tabulated by independent ports of Vigna's C code).
    #[test]
    fn xoshiro256pp_matches_the_reference() {
        let mut x = Xoshiro256PlusPlus::from_parts([1, 2, 3, 4]).unwrap();
        assert_eq!(x.next_u64(), 41_943_041);
        let mut x = Xoshiro256PlusPlus::from_parts([0, 0, 0, 1]).unwrap();
        let got: Vec<u64> = (0..10).map(|_| x.next_u64()).collect();
        assert_eq!(
            got,
            [
                0x0000_0000_0080_0000,
                0x0000_0000_0080_0011,
                0x0002_2000_0080_0011,
                0x0002_2000_4400_0020,
                0x0002_2000_4480_08a1,
                0x0110_2100_8022_08a0,
                0x0114_0022_8420_0880,
                0x0402_8966_44a6_4095,
                0x8a14_a0a2_44ac_c891,
                0x8c88_ba46_80b2_0495,
            ]
        );
        assert_eq!(Xoshiro256PlusPlus::from_parts(x.parts()), Some(x.clone()));
        assert_eq!(Xoshiro256PlusPlus::from_parts([0; 4]), None);
    }

    /// Distinct (seed, stream) pairs give distinct, uncorrelated-looking streams: no two
    /// of 64 neighbouring pairs share a first output, and one output bit is balanced.
    #[test]
    fn seeds_and_streams_give_distinct_streams() {
        let mut firsts = Vec::new();
        let mut ones = 0u32;
        for seed in 0..8u64 {
            for stream in 0..8u64 {
                let mut g = generator(seed, stream);
                let v = g.next_u64();
                firsts.push(v);
                ones += (v >> 63) as u32;
            }
        }
        let mut sorted = firsts.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), 64);
        // binomial(64, 1/2), sd 4: 6 sd either way is far beyond chance
        assert!((8..=56).contains(&ones), "{ones}");
        assert_ne!(generator(1, 2).next_u64(), generator(2, 1).next_u64());
    }

    /// The constant tables are what `libm` computes, bit for bit (on a mismatch the
    /// message is the table to paste into `ziggurat_table.rs`).
    #[test]
    fn ziggurat_tables_are_the_libm_computation() {
        let computed = Ziggurat::compute();
        check_tables(
            "ziggurat",
            computed,
            (&ziggurat_table::X, &ziggurat_table::F),
        );
    }

    /// Panics unless `computed` equals the constant `tables` bit for bit, with the
    /// tables to paste in the message.
    fn check_tables(
        name: &str,
        (x, f): ([f64; 257], [f64; 257]),
        tables: (&[f64; 257], &[f64; 257]),
    ) {
        let same = |a: &[f64; 257], b: &[f64; 257]| {
            a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits())
        };
        if !same(&x, tables.0) || !same(&f, tables.1) {
            let mut out = alloc::string::String::new();
            for (name, t) in [("X", &x), ("F", &f)] {
                out.push_str(&alloc::format!(
                    "pub(super) static {name}: [f64; 257] = [\n"
                ));
                for v in t.iter() {
                    out.push_str(&alloc::format!(
                        "    f64::from_bits(0x{:016x}),\n",
                        v.to_bits()
                    ));
                }
                out.push_str("];\n");
            }
            panic!("{name} tables differ from libm's:\n{out}");
        }
    }

    /// The ziggurat's moments and tail probabilities match Exp(1) within 5 standard
    /// errors over 4e6 draws.
    #[test]
    fn ziggurat_is_exponential() {
        let z = Ziggurat::new();
        let mut rng = rand_pcg::Pcg64Mcg::new(77);
        let n = 4_000_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        let thresholds = [0.01, 0.5, 1.0, 3.0, 7.0, 7.7, 9.0];
        let mut above = [0usize; 7];
        for _ in 0..n {
            let x = z.sample(&mut rng);
            assert!(x >= 0.0 && x.is_finite());
            s1 += x;
            s2 += x * x;
            for (c, &t) in above.iter_mut().zip(&thresholds) {
                if x > t {
                    *c += 1;
                }
            }
        }
        let nf = n as f64;
        let mean = s1 / nf;
        assert!((mean - 1.0).abs() < 5.0 / libm::sqrt(nf), "mean {mean}");
        let m2 = s2 / nf; // E x² = 2, Var x² = 20
        assert!(
            (m2 - 2.0).abs() < 5.0 * libm::sqrt(20.0 / nf),
            "second moment {m2}"
        );
        for (c, &t) in above.iter().zip(&thresholds) {
            let p = libm::exp(-t);
            let se = libm::sqrt(p * (1.0 - p) / nf);
            let got = *c as f64 / nf;
            assert!(
                (got - p).abs() < 5.0 * se + 1e-9,
                "P(X > {t}) = {got}, expected {p}"
            );
        }
    }

    /// The normal ziggurat's tables are what `libm` computes, bit for bit (on a mismatch
    /// the message is the table to paste into `normal_table.rs`).
    #[test]
    fn normal_tables_are_the_libm_computation() {
        let (x, f) = NormalZiggurat::compute();
        assert!(x[255] > 0.0 && x[255] < x[254], "last layer {}", x[255]);
        check_tables(
            "normal ziggurat",
            (x, f),
            (&normal_table::X, &normal_table::F),
        );
    }

    /// The normal ziggurat's first four moments and its tail probabilities (both signs,
    /// through the layers, the wedges and the tail beyond R = 3.654) match N(0, 1)
    /// within 5 standard errors over 4e6 draws.
    #[test]
    fn normal_ziggurat_is_standard_normal() {
        let mut rng = rand_pcg::Pcg64Mcg::new(78);
        let n = 4_000_000;
        let mut s = [0.0f64; 4];
        let thresholds = [-4.0, -3.7, -2.0, -0.3, 0.0, 0.01, 1.0, 3.0, 3.6, 3.7, 4.5];
        let mut above = [0usize; 11];
        for _ in 0..n {
            let x = NormalZiggurat::sample(&mut rng);
            assert!(x.is_finite());
            let mut p = 1.0;
            for m in s.iter_mut() {
                p *= x;
                *m += p;
            }
            for (c, &t) in above.iter_mut().zip(&thresholds) {
                if x > t {
                    *c += 1;
                }
            }
        }
        let nf = n as f64;
        // moments 0, 1, 0, 3 with variances 1, 2, 15, 96
        for (k, (exp, var)) in [(0.0, 1.0), (1.0, 2.0), (0.0, 15.0), (3.0, 96.0)]
            .iter()
            .enumerate()
        {
            let m = s[k] / nf;
            assert!(
                (m - exp).abs() < 5.0 * libm::sqrt(var / nf),
                "moment {} = {m}",
                k + 1
            );
        }
        for (c, &t) in above.iter().zip(&thresholds) {
            let p = 0.5 * libm::erfc(t / core::f64::consts::SQRT_2);
            let se = libm::sqrt(p * (1.0 - p) / nf);
            let got = *c as f64 / nf;
            assert!(
                (got - p).abs() < 5.0 * se + 1e-9,
                "P(X > {t}) = {got}, expected {p}"
            );
        }
    }

    /// Gamma and beta variates have their mean and variance within 5 standard errors
    /// (the variance's standard error from the fourth central moment).
    #[test]
    fn gamma_and_beta_moments() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let n = 200_000;
        for a in [1.0, 2.0, 7.0, 300.0, 1e6] {
            let xs: Vec<f64> = (0..n).map(|_| gamma(a, &mut rng)).collect();
            let (m, v) = mean_var(&xs);
            // Var = a; fourth central moment 3a² + 6a
            let se_m = libm::sqrt(a / n as f64);
            let se_v = libm::sqrt((3.0 * a * a + 6.0 * a - a * a) / n as f64);
            assert!((m - a).abs() < 5.0 * se_m, "gamma({a}) mean {m}");
            assert!((v - a).abs() < 5.0 * se_v, "gamma({a}) variance {v}");
        }
        for (a, b) in [(1.0, 1.0), (1.0, 999.0), (40.0, 3.0), (5e4, 5e4)] {
            let xs: Vec<f64> = (0..n).map(|_| beta(a, b, &mut rng)).collect();
            let (m, v) = mean_var(&xs);
            let want_m = a / (a + b);
            let want_v = a * b / ((a + b) * (a + b) * (a + b + 1.0));
            assert!(
                (m - want_m).abs() < 5.0 * libm::sqrt(want_v / n as f64),
                "beta({a},{b}) mean {m}"
            );
            // the sample variance's standard error is Var · sqrt((κ − 1)/n), κ the
            // beta distribution's kurtosis (≈ 9 for beta(1, 999)); 5.5 SE
            let excess = 6.0 * ((a - b) * (a - b) * (a + b + 1.0) - a * b * (a + b + 2.0))
                / (a * b * (a + b + 2.0) * (a + b + 3.0));
            let se_v = want_v * libm::sqrt((2.0 + excess) / n as f64);
            assert!(
                (v - want_v).abs() < 5.5 * se_v,
                "beta({a},{b}) variance {v} vs {want_v}"
            );
        }
    }

    /// `below_wide`: `below`'s draws where n fits 64 bits; past them uniform (a
    /// chi-square over 4 quarters of n = 3 · 2^64 + 1, where a modulo draw of 128 bits
    /// would be 3e-20 off: the check is of the range and the quarters' counts), and
    /// `None` for 0.
    #[test]
    fn wide_draws_are_below_n_and_uniform() {
        let mut a = Xoshiro256PlusPlus::new(3, 0);
        let mut b = a.clone();
        for n in [1u64, 7, u64::MAX] {
            assert_eq!(
                below_wide(&mut a, u128::from(n)),
                Some(u128::from(below(&mut b, n)))
            );
        }
        assert_eq!(below_wide(&mut a, 0), None);
        let n = 3 * (1u128 << 64) + 1;
        let mut quarters = [0u32; 4];
        let draws = 40_000;
        for _ in 0..draws {
            let r = below_wide(&mut a, n).unwrap();
            assert!(r < n);
            quarters[(r * 4 / n) as usize] += 1;
        }
        let e = f64::from(draws) / 4.0;
        let chi2: f64 = quarters
            .iter()
            .map(|&c| (f64::from(c) - e).powi(2) / e)
            .sum();
        // 3 degrees of freedom: P(chi2 > 27.9) = 4e-6 (fixed seed: deterministic)
        assert!(chi2 < 27.9, "{quarters:?}: {chi2}");
    }
}
