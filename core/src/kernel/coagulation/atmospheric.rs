//! The "atmospheric" kernel of integer sizes,
//! `K(i, j) = (i + j)(i^{1/3} + j^{1/3})^{2/3} / ((i j)^{5/9} |i^{2/3} − j^{2/3}|)`,
//! `K(i, i) = 4`, as Dyachenko, Matveev & Valiakhmetov (arXiv 2501.10206, 2025) run it.
//! Its earliest code is a 1-D aerosol column model of Lake Baikal (2023, credited to
//! N. V. Brilliantov), where it replaced a differential-sedimentation kernel; the
//! nearest theory is Zagidullin, Smirnov, Matveev & Brilliantov (arXiv 2112.14584,
//! aggregation at sedimentation with diffusion). See `docs/design/block-majorants.md`.
//!
//! It peaks next to the diagonal (`K(i, i + 1) ≈ 3 · 2^{2/3} i^{4/9}`) and is
//! homogeneous of degree −5/9 off it, so no low-rank bound is tight: the rank-2 bound
//! `A + Aᵀ = 0.2556 (x^{−5/9} + y^{−5/9}) + 4.7625 (x y)^{2/9}` holds on integer pairs
//! (the tests scan them), but the acceptance under it falls as the sizes grow. Block
//! majorants ([`sup_block`]) fit it.
//!
//! On real sizes the kernel is unbounded near the diagonal: it is a kernel of integer
//! sizes only, and its bounds hold for integer sizes from 1.

/// `A(x, y) = A0 x^{−5/9} + (A1 / 2) (x y)^{2/9}`: the coefficients of the rank-2 bound.
pub const A0: f64 = 0.2556;
/// See [`A0`].
pub const A1: f64 = 4.7625;
/// `c` of the product majorant `h(x) = c (x^{2/9} + x^{−5/9})`, `c² ≥ A1` (valid for
/// sizes from 1, where `x^{2/9} ≥ 1` covers the `A0` terms).
pub const MAJORANT_C: f64 = 2.182_316;

/// `K(x, y)` with coefficient 1 from `cx = x^{1/3}`, `cy = y^{1/3}`. The difference
/// `x^{2/3} − y^{2/3}` is written as `(x − y)(cx + cy)/(cx² + cx cy + cy²)`, exact in
/// the difference of the sizes (no cancellation next to the diagonal).
#[inline]
pub(crate) fn rate(x: f64, y: f64, cx: f64, cy: f64) -> f64 {
    if x == y {
        return 4.0;
    }
    let s = cx + cy;
    let p = cx * cy;
    let q = s / p;
    (x + y) * super::cbrt(q * q) * (cx * cx + cy * cy + p) / (p * (x - y).abs() * s)
}

/// `K` with coefficient 1 at integer sizes.
fn at(i: f64, j: f64) -> f64 {
    rate(i, j, super::cbrt_of(i), super::cbrt_of(j))
}

/// The ends of a block rounded inwards to integers from 1, `None` when it holds no
/// integer pair.
fn integer_ends(x0: f64, x1: f64, y0: f64, y1: f64) -> Option<(f64, f64, f64, f64)> {
    let (x0, x1, y0, y1) = (
        libm::ceil(x0.max(1.0)),
        libm::floor(x1),
        libm::ceil(y0.max(1.0)),
        libm::floor(y1),
    );
    (x0 <= x1 && y0 <= y1).then_some((x0, x1, y0, y1))
}

/// `sup K(i, j)` (coefficient 1) over the integer pairs of the block
/// `x0 ≤ i ≤ x1`, `y0 ≤ j ≤ y1` (ends rounded inwards; 0 for an empty block).
///
/// Off the diagonal K is quasi-convex along each axis (falling, then rising towards the
/// diagonal; the tests scan it), so a block on one side of the diagonal has its
/// supremum at a corner. Along the diagonal `K(i, i + 1)` rises with i (the tests scan
/// it), and `K(i, i) = 4`: a block that meets the diagonal has its supremum at a
/// corner, at the adjacent pair of its largest shared sizes, or 4. O(1).
pub fn sup_block(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let Some((x0, x1, y0, y1)) = integer_ends(x0, x1, y0, y1) else {
        return 0.0;
    };
    if x1 < y0 || y1 < x0 {
        return [at(x0, y0), at(x0, y1), at(x1, y0), at(x1, y1)]
            .into_iter()
            .fold(0.0, f64::max);
    }
    // each side of the diagonal (rows i below columns j, then above) on its own; on
    // the side i < j, rows i in [a0, a1'] with a1' = min(a1, b1 − 1), columns from
    // max(i + 1, b0) to b1. A row's supremum is at one of those two ends (quasi-convex
    // in j). K(i, b1) is quasi-convex in i: ends a0, a1'. K(i, b0) for i < b0 likewise:
    // ends a0, min(a1', b0 − 1). K(i, i + 1) for i ≥ b0 rises: end a1'.
    let side = |(a0, a1): (f64, f64), (b0, b1): (f64, f64)| {
        let a1 = a1.min(b1 - 1.0);
        if a0 > a1 {
            return 0.0_f64;
        }
        let mut v = at(a0, b1).max(at(a1, b1));
        if a0 < b0 {
            v = v.max(at(a0, b0)).max(at(a1.min(b0 - 1.0), b0));
        }
        if a1 >= a0.max(b0) {
            v = v.max(at(a1, a1 + 1.0));
        }
        v
    };
    // K(i, i) = 4 on the shared sizes
    side((x0, x1), (y0, y1))
        .max(side((y0, y1), (x0, x1)))
        .max(4.0)
}

/// `min K(x, 1)` over real `0 < x < 1` (at x ≈ 0.184310, 6.0519269263…), rounded down:
/// by homogeneity `min_x K(x, y) = COLUMN_MIN · y^{−5/9}` along a column.
pub const COLUMN_MIN: f64 = 6.0519;
/// Where `K(x, 1)` has its minimum: in `(COLUMN_ARGMIN.0, COLUMN_ARGMIN.1)` (falling
/// below, rising above; the tests scan it).
pub const COLUMN_ARGMIN: (f64, f64) = (0.1842, 0.1845);

/// A lower bound of K (coefficient 1) over the integer pairs of the block
/// `x0 ≤ i ≤ x1`, `y0 ≤ j ≤ y1` (ends rounded inwards; 0 for an empty block), the
/// squeeze of block majorants. For `i < j`, `K(i, j) = i^{−5/9} φ(j / i)` with φ falling
/// on `(1, ∞)` (from ∞ to 1; the tests scan it), so a row's minimum over its columns is
/// at the last column `y1`; along that column K is quasi-convex in i, so its minimum
/// over the rows is at an end, or, when the rows reach the column's minimiser
/// ([`COLUMN_ARGMIN`]` · y1`), the column's minimum [`COLUMN_MIN`]` · y1^{−5/9}`.
/// `K(i, i) = 4` on shared sizes. Lowered by 1e-9 against rounding in the evaluations.
/// O(1).
pub fn inf_block(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let Some((x0, x1, y0, y1)) = integer_ends(x0, x1, y0, y1) else {
        return 0.0;
    };
    // rows i in [a0, a1'] below columns j ≤ b1, a1' = min(a1, b1 − 1)
    let side = |(a0, a1): (f64, f64), b1: f64| {
        let a1 = a1.min(b1 - 1.0);
        if a0 > a1 {
            return f64::INFINITY;
        }
        let ends = at(a0, b1).min(at(a1, b1));
        if a0 < COLUMN_ARGMIN.1 * b1 && a1 > COLUMN_ARGMIN.0 * b1 {
            ends.min(COLUMN_MIN * libm::pow(b1, -5.0 / 9.0))
        } else {
            ends
        }
    };
    let mut v = side((x0, x1), y1).min(side((y0, y1), x1));
    if x0 <= y1 && y0 <= x1 {
        v = v.min(4.0);
    }
    if v.is_finite() { v * (1.0 - 1e-9) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::{Coagulation, CoagulationKernel};
    use libm::{cbrt, pow};

    /// The formula as written, with `pow` (no rewriting of the difference).
    fn direct(i: f64, j: f64) -> f64 {
        if i == j {
            return 4.0;
        }
        (i + j) * pow(cbrt(i) + cbrt(j), 2.0 / 3.0)
            / (pow(i * j, 5.0 / 9.0) * (pow(i, 2.0 / 3.0) - pow(j, 2.0 / 3.0)).abs())
    }

    #[test]
    fn rate_is_the_formula() {
        let k = Coagulation::atmospheric();
        for (i, j) in [
            (1.0, 2.0),
            (2.0, 1.0),
            (3.0, 3.0),
            (7.0, 1000.0),
            (999.0, 1000.0),
        ] {
            let (a, b) = (k.rate(i, j), direct(i, j));
            assert!((a - b).abs() <= 1e-12 * b, "({i}, {j}): {a} vs {b}");
        }
        // far from the table, next to the diagonal: the direct form loses digits to
        // cancellation (about 1e-8 here), ours does not
        let (a, b) = (k.rate(1e7, 1e7 + 1.0), direct(1e7, 1e7 + 1.0));
        assert!((a - b).abs() <= 1e-6 * b, "{a} vs {b}");
        // the asymptote K(i, i + 1) → 3 · 2^{2/3} i^{4/9}
        let i = 1e12;
        let r = k.rate(i, i + 1.0) / (3.0 * pow(2.0, 2.0 / 3.0) * pow(i, 4.0 / 9.0));
        assert!((r - 1.0).abs() < 1e-5, "{r}");
        assert_eq!(k.rate(5.0, 5.0), 4.0);
        let b = Coagulation::atmospheric().with_coefficient(2.0).unwrap();
        assert_eq!(b.rate(5.0, 5.0), 8.0);
        assert!(Coagulation::atmospheric().with_min_size(0.5).is_err());
    }

    /// The rank-2 bound on integer pairs: every pair up to 1200 and the pairs next to
    /// the diagonal (where the ratio K / (A + Aᵀ) is largest) up to 2^40.
    #[test]
    fn low_rank_bound_and_majorant_hold_on_integer_pairs() {
        let k = Coagulation::atmospheric();
        let check = |i: f64, j: f64| {
            let r = k.rate(i, j);
            let a = k.low_rank_bound(i, j).unwrap();
            assert!(r <= a, "({i}, {j}): K {r} > A + Aᵀ {a}");
            let h = k.majorant(i).unwrap() * k.majorant(j).unwrap();
            assert!(r <= h, "({i}, {j}): K {r} > h h {h}");
        };
        for i in 1..=1200u32 {
            for j in i..=1200 {
                check(f64::from(i), f64::from(j));
            }
        }
        let mut i = 1200.0;
        while i < 1.1e12 {
            for d in 1..=4 {
                check(i, i + f64::from(d));
            }
            i = libm::floor(i * 1.37);
        }
        assert!(k.low_rank_is_loose() && !k.low_rank_is_exact());
    }

    /// `sup_block` against a scan of every integer pair of blocks on and off the
    /// diagonal: an upper bound, and attained (so K is quasi-convex as assumed).
    #[test]
    fn sup_block_is_the_maximum_over_the_block() {
        let k = Coagulation::atmospheric();
        let mut blocks = alloc::vec::Vec::new();
        for &(x0, w, y0, v) in &[
            (1u32, 8u32, 1u32, 8u32),
            (1, 1, 1, 1),
            (5, 1, 6, 1),
            (1, 8, 9, 8),
            (9, 8, 1, 8),
            (17, 16, 40, 3),
            (100, 60, 130, 90),
            (130, 90, 100, 60),
            (1000, 1, 1, 2000),
            (700, 300, 800, 40),
            (64, 64, 256, 256),
            (3, 500, 200, 7),
        ] {
            blocks.push((x0, x0 + w - 1, y0, y0 + v - 1));
        }
        // a sweep of offsets along the diagonal
        for s in [1u32, 2, 3, 8, 33] {
            for off in 0..12 {
                for x0 in [1u32, 2, 7, 50, 301] {
                    blocks.push((x0, x0 + s - 1, x0 + off, x0 + off + s - 1));
                }
            }
        }
        for (x0, x1, y0, y1) in blocks {
            let mut max = 0.0_f64;
            for i in x0..=x1 {
                for j in y0..=y1 {
                    max = max.max(k.rate(f64::from(i), f64::from(j)));
                }
            }
            let (a, b, c, d) = (f64::from(x0), f64::from(x1), f64::from(y0), f64::from(y1));
            let sup = k.sup_block(a, b, c, d).unwrap();
            assert!(
                sup >= max && sup <= max * (1.0 + 1e-12),
                "[{x0},{x1}]x[{y0},{y1}]: sup {sup}, scan {max}"
            );
            if x0 == y0 && x1 == y1 {
                assert_eq!(k.sup_rate(a, b), Some(sup));
            }
        }
        assert_eq!(sup_block(3.0, 2.0, 1.0, 5.0), 0.0);
    }

    /// `inf_block` against a scan of every integer pair of blocks on, next to and away
    /// from the diagonal: a lower bound, and the least value itself up to the real
    /// minimum along a column ([`COLUMN_MIN`]) and the 1e-9 margin. Then φ(c) = K(1, c)
    /// falls on (1, 10^6] (what the bound assumes), and `COLUMN_MIN` is below the
    /// column's minimum and within 1e-4 of it.
    #[test]
    fn inf_block_is_below_the_minimum_over_the_block() {
        let k = Coagulation::atmospheric();
        let mut blocks = alloc::vec::Vec::new();
        for s in [1u32, 2, 4, 8, 16, 64] {
            for gap in [0u32, 1, 2, 3, 5, 17, 200] {
                for x0 in [1u32, 2, 5, 50, 301, 1000] {
                    blocks.push((x0, x0 + s - 1, x0 + gap * s, x0 + gap * s + s - 1));
                    blocks.push((x0 + gap * s, x0 + gap * s + s - 1, x0, x0 + s - 1));
                }
            }
        }
        blocks.extend([(1u32, 3u32, 1000u32, 3000u32), (1, 1, 1, 1), (7, 7, 9, 9)]);
        let mut tight = 0;
        for (x0, x1, y0, y1) in blocks {
            let mut min = f64::INFINITY;
            for i in x0..=x1 {
                for j in y0..=y1 {
                    min = min.min(k.rate(f64::from(i), f64::from(j)));
                }
            }
            let (a, b, c, d) = (f64::from(x0), f64::from(x1), f64::from(y0), f64::from(y1));
            let inf = k.inf_block(a, b, c, d);
            assert!(
                inf <= min && inf > 0.0,
                "[{x0},{x1}]x[{y0},{y1}]: inf {inf}, scan {min}"
            );
            // the least value at the ends, or the column's real minimum (rows reaching
            // the minimiser: their integer minimum is within 5 % of it here)
            if inf >= min * (1.0 - 2e-9) {
                tight += 1;
            } else {
                assert!(inf >= 0.95 * min, "[{x0},{x1}]x[{y0},{y1}]: {inf} vs {min}");
            }
        }
        assert!(tight > 400, "{tight}");
        assert_eq!(inf_block(3.0, 2.0, 1.0, 5.0), 0.0);
        let phi = |c: f64| rate(1.0, c, 1.0, cbrt(c));
        let mut last = f64::INFINITY;
        let mut c = 1.0 + 1e-6;
        while c < 1e6 {
            assert!(phi(c) < last, "{c}");
            last = phi(c);
            c *= 1.01;
        }
        let psi = |r: f64| rate(r, 1.0, cbrt(r), 1.0);
        let mut least = f64::INFINITY;
        for n in 1..100_000 {
            least = least.min(psi(f64::from(n) * 1e-5));
        }
        assert!(
            COLUMN_MIN < least && least < COLUMN_MIN * (1.0 + 1e-4),
            "{least}"
        );
        // falling up to the minimiser's bracket, rising after it
        let (lo, hi) = COLUMN_ARGMIN;
        for n in 1..10_000 {
            let r = f64::from(n) * lo / 1e4;
            assert!(psi(r) > psi(r + lo / 1e4), "{r}");
            let r = hi + f64::from(n) * (1.0 - hi) / 1e4;
            assert!(psi(r - (1.0 - hi) / 1e4) < psi(r), "{r}");
        }
    }
}
