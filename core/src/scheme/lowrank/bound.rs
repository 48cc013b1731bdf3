//! The bound: the kernel's low-rank factors `a_k(x), b_k(x)` (`K ≤ A + Aᵀ`,
//! `A(x, y) = Σ_k a_k(x) b_k(y)`, see [`crate::kernel`]), validated, and their
//! coarsening to log-linear size buckets with integer quantisation (the bucketed
//! layout's bound `Â ≥ A`).
//!
//! Buckets: every size below 64 is its own bucket; above, each octave `[2^g, 2^{g+1})`
//! is cut into 32 buckets of equal width, so a bucket spans at most 1/32 of its lower
//! end and 2^32 sizes need 897 buckets. A bucket's bound takes its largest factor per
//! row; its smallest factor feeds the squeeze.

use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use alloc::vec::Vec;

/// The low-rank factors `(a(x), b(x))` of size x; a negative or non-finite one is an
/// error.
pub(crate) fn factors_at<K: CoagulationKernel + ?Sized, const R: usize>(
    kernel: &K,
    x: f64,
) -> Result<([f64; R], [f64; R])> {
    let (mut a, mut b) = ([0.0; R], [0.0; R]);
    kernel.factors(x, &mut a, &mut b);
    for &v in a.iter().chain(&b) {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "low-rank factor",
                value: v,
            });
        }
    }
    Ok((a, b))
}

/// Extends a per-size factor table `fab` (`fab[i − 1] = [a(i), b(i)]`) to sizes
/// `..= m`, validating every new row before the table changes (nothing to do when it
/// already covers `m`).
pub(crate) fn extend_rows<K: CoagulationKernel + ?Sized, const R: usize>(
    kernel: &K,
    fab: &mut alloc::vec::Vec<[[f64; R]; 2]>,
    m: usize,
) -> Result<()> {
    use crate::scheme::population::try_reserve;
    let start = fab.len();
    if m <= start {
        return Ok(());
    }
    let mut new = alloc::vec::Vec::new();
    try_reserve(&mut new, m - start)?;
    for i in start + 1..=m {
        let (a, b) = factors_at::<K, R>(kernel, i as f64)?;
        new.push([a, b]);
    }
    try_reserve(fab, new.len())?;
    fab.extend(new);
    Ok(())
}

/// Re-reads every row of a factor table from `kernel` (the rule validated them).
pub(crate) fn reread_rows<K: CoagulationKernel + ?Sized, const R: usize>(
    kernel: &K,
    fab: &mut [[[f64; R]; 2]],
) {
    for (i, f) in fab.iter_mut().enumerate() {
        let (mut a, mut b) = ([0.0; R], [0.0; R]);
        kernel.factors((i + 1) as f64, &mut a, &mut b);
        *f = [a, b];
    }
}

/// log2 of the buckets per octave.
pub(crate) const SUB_BITS: u32 = 5;
/// Buckets per octave.
pub(crate) const SUB: u64 = 1 << SUB_BITS;
/// Sizes below this are their own bucket.
pub(crate) const SINGLE: u64 = 2 * SUB;

/// The bucket of size `x ≥ 1`.
#[inline]
pub(crate) fn bucket_of(x: u64) -> usize {
    if x < SINGLE {
        x as usize
    } else {
        let g = 63 - x.leading_zeros();
        let sh = g - SUB_BITS;
        (sh as u64 * SUB + (x >> sh)) as usize
    }
}

/// The sizes `lo..=hi` of bucket `b ≥ 1`.
#[inline]
pub(crate) fn bucket_range(b: usize) -> (u64, u64) {
    let b = b as u64;
    if b < SINGLE {
        (b, b)
    } else {
        let sh = b / SUB - 1;
        let m = b - sh * SUB;
        (m << sh, ((m + 1) << sh) - 1)
    }
}

/// log2 of the width of bucket b.
#[inline]
pub(crate) fn width_bits(b: usize) -> u32 {
    if (b as u64) < SINGLE {
        0
    } else {
        (b as u64 / SUB - 1) as u32
    }
}

/// Length of a size-indexed count array for maximum size m: it covers the whole
/// bucket of m.
pub(crate) fn count_len(m: u64) -> usize {
    bucket_range(bucket_of(m)).1 as usize + 1
}

/// The exact factor extremes `[max, min]` per row `[a_0 .. a_{R−1}, b_0 .. b_{R−1}]`
/// over bucket b: every size is evaluated, or only the bucket's two ends when the
/// kernel declares [`CoagulationKernel::monotone_factors`]. Bucket 0 holds no size and
/// has zero extremes.
pub(crate) fn bucket_extremes<K: CoagulationKernel + ?Sized, const R: usize, const W: usize>(
    kernel: &K,
    b: usize,
) -> Result<[[f64; W]; 2]> {
    let mut ext = [[0.0; W], [f64::INFINITY; W]];
    if b == 0 {
        ext[1] = [0.0; W];
        return Ok(ext);
    }
    let (lo, hi) = bucket_range(b);
    // monotone factors: the two ends bound the bucket (see `monotone_factors`)
    let ends = [lo, hi];
    let all = lo..=hi;
    let sizes: &mut dyn Iterator<Item = u64> = if kernel.monotone_factors() {
        // (a singleton's two ends are one size)
        &mut ends.into_iter().take(if lo == hi { 1 } else { 2 })
    } else {
        &mut all.into_iter()
    };
    for x in sizes {
        let (a, bb) = factors_at::<K, R>(kernel, x as f64)?;
        for (r, &v) in a.iter().chain(&bb).enumerate() {
            ext[0][r] = ext[0][r].max(v);
            ext[1][r] = ext[1][r].min(v);
        }
    }
    Ok(ext)
}

/// The quantisation step of a row whose largest factor is `fmax`, so that every factor
/// is at most `qmax` steps: a power of two (integer-valued factors then quantise
/// exactly, and a pair of singleton buckets has bound = squeeze), at least the smallest
/// normal double (factors near it would make the power of two underflow to 0).
pub(crate) fn quantum(fmax: f64, qmax: u64) -> f64 {
    if fmax > 0.0 {
        let mut sc = libm::exp2(libm::ceil(libm::log2(fmax / qmax as f64))).max(f64::MIN_POSITIVE);
        while fmax / sc > qmax as f64 {
            sc *= 2.0;
        }
        sc
    } else {
        1.0
    }
}

/// `f` rounded up to whole quanta `scale`: the integer weight `q` with `q · scale ≥ f`.
pub(crate) fn quantise_up(f: f64, scale: f64) -> u64 {
    let mut q = libm::ceil(f / scale) as u64;
    while (q as f64) * scale < f {
        q += 1;
    }
    q
}

/// Largest number of initial particles of the bucket engines (counts are stored as
/// `u32`).
pub const MAX_PARTICLES: u64 = u32::MAX as u64;

/// Calls `f(size, count)` for the sizes in a list of offsets from `lo`, in increasing
/// order (`scratch` holds a sorted copy).
pub(super) fn each_in_list(
    lo: u64,
    list: &[u32],
    scratch: &mut Vec<u32>,
    f: &mut dyn FnMut(u64, u64),
) {
    scratch.clear();
    scratch.extend_from_slice(list);
    scratch.sort_unstable();
    let mut i = 0;
    while i < scratch.len() {
        let j = i + scratch[i..]
            .iter()
            .take_while(|&&o| o == scratch[i])
            .count();
        f(lo + u64::from(scratch[i]), (j - i) as u64);
        i = j;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Coagulation;

    /// A kernel's factors without its monotonicity claim: every size is evaluated.
    struct Exhaustive(Coagulation);

    impl CoagulationKernel for Exhaustive {
        fn rate(&self, x: f64, y: f64) -> f64 {
            self.0.rate(x, y)
        }
        fn rank(&self) -> usize {
            self.0.rank()
        }
        fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
            self.0.factors(x, a, b);
        }
        fn min_size(&self) -> f64 {
            self.0.min_size()
        }
    }

    /// Bucket b's extremes (as bits) from the two ends and from every size.
    fn both<const R: usize, const W: usize>(
        k: &Coagulation,
        slow: &Exhaustive,
        b: usize,
    ) -> (alloc::vec::Vec<u64>, alloc::vec::Vec<u64>) {
        let bits = |e: [[f64; W]; 2]| e.iter().flatten().map(|x| x.to_bits()).collect();
        (
            bits(bucket_extremes::<_, R, W>(k, b).unwrap()),
            bits(bucket_extremes::<_, R, W>(slow, b).unwrap()),
        )
    }

    /// The built-in kernels' bucket bounds from the two ends of each bucket equal those
    /// from every size, bit for bit, for every bucket up to sizes 2^20 (a factor that
    /// is not monotone, or a rounding that is not, would show here).
    #[test]
    fn monotone_factors_bound_buckets_as_every_size_does() {
        let kernels = [
            Coagulation::constant(2.5).unwrap(),
            Coagulation::additive(),
            Coagulation::multiplicative(),
            Coagulation::product(0.8).unwrap(),
            Coagulation::homogeneous(1.5).unwrap(),
            Coagulation::free_molecular(),
            Coagulation::brownian(),
            Coagulation::free_molecular().with_coefficient(3.0).unwrap(),
        ];
        for k in kernels {
            assert!(k.monotone_factors());
            let slow = Exhaustive(k);
            assert!(!slow.monotone_factors());
            for b in 0..=bucket_of(1 << 20) {
                let (fast, every) = match k.rank() {
                    1 => both::<1, 2>(&k, &slow, b),
                    2 => both::<2, 4>(&k, &slow, b),
                    _ => both::<3, 6>(&k, &slow, b),
                };
                assert_eq!(fast, every, "{} bucket {b}", k.name());
            }
        }
    }

    #[test]
    fn quantisation_bounds_from_above() {
        for f in [1.0, 3.0, 0.1, 1e-300, 7.5e10] {
            let s = quantum(f, 1 << 40);
            let q = quantise_up(f, s);
            assert!(q as f64 * s >= f && q <= 1 << 40, "{f}");
        }
        assert_eq!(
            quantise_up(3.0, quantum(3.0, 1 << 20)) as f64 * quantum(3.0, 1 << 20),
            3.0
        );
    }
}
