//! Niederreiter's sequence in base 2.
//!
//! Construction of P. Bratley, B. L. Fox & H. Niederreiter, "Implementation and tests
//! of low-discrepancy sequences", ACM Trans. Model. Comput. Simul. 2(3) (1992)
//! 195–213 (ACM TOMS algorithm 738, `INLO2`/`CALCC2`/`CALCV2`), following GSL's
//! `qrng/niederreiter-2.c` choice of the free constants (K_q = e·q and all arbitrary
//! elements 1), so that the top 31 digits are bit-identical to
//! `gsl_qrng_niederreiter_2` (GSL stops at 12 dimensions and 31 digits; this one
//! goes on with the same construction).
//!
//! Coordinate `i` uses the `i`-th irreducible polynomial over GF(2) in the order of
//! TOMS 738 and GSL (by degree, then by value): x, x+1, x²+x+1, x³+x+1, x³+x²+1,
//! x⁴+x+1, … The sequence is a (t,s)-sequence with t = Σ (deg p_i − 1).

use alloc::vec;
use alloc::vec::Vec;

use super::{DigitalSequence, Word};
use crate::error::{Error, Result};

/// Niederreiter's base-2 (t,s)-sequence, generic over the digit word (`u32`: 32 digits
/// and 2^32 points; `u64`: 64 digits and 2^64 points).
///
/// Coordinates 1 and 2 coincide with Sobol' coordinates 1 and 2 (van der Corput and
/// the Pascal matrix); coordinate 3 (polynomial x²+x+1) differs, and the first three
/// coordinates form a (1,3)-sequence.
///
/// # Example
///
/// ```
/// use coagula_core::qmc::{DigitalSequence, Niederreiter2};
///
/// let nied = Niederreiter2::<u64>::new(3)?;
/// assert_eq!(nied.polynomial(2), 0b111); // x^2 + x + 1
/// let mut x = [0.0; 3];
/// nied.point(1, &mut x)?;
/// assert_eq!(x, [0.5, 0.5, 0.75]);
/// assert!(Niederreiter2::<u64>::new(Niederreiter2::<u64>::MAX_DIM + 1).is_err());
/// # Ok::<(), coagula_core::error::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Niederreiter2<W: Word = u64> {
    dim: usize,
    /// `dim * W::BITS` columns, coordinate after coordinate.
    cols: Vec<W>,
    /// Irreducible polynomial of each coordinate (bit k = coefficient of x^k).
    polys: Vec<u64>,
}

/// Remainder of `a` modulo `b` over GF(2) (`b != 0`).
fn poly_rem(mut a: u64, b: u64) -> u64 {
    let db = 63 - b.leading_zeros();
    while a != 0 && 63 - a.leading_zeros() >= db {
        a ^= b << (63 - a.leading_zeros() - db);
    }
    a
}

fn is_irreducible(p: u64) -> bool {
    let deg = 63 - p.leading_zeros();
    // Any factor has degree <= deg / 2; try every polynomial of degree 1..=deg/2.
    let limit = 1u64 << (deg / 2 + 1);
    (2..limit).all(|q| poly_rem(p, q) != 0)
}

/// The first `n` irreducible polynomials over GF(2), by degree then value.
fn irreducible_polynomials(n: usize) -> Vec<u64> {
    (2u64..).filter(|&p| is_irreducible(p)).take(n).collect()
}

/// Carry-less product over GF(2).
fn clmul(a: u128, b: u64) -> u128 {
    let mut r = 0u128;
    let mut b = b;
    while b != 0 {
        r ^= a << b.trailing_zeros();
        b &= b - 1;
    }
    r
}

/// Length of the scratch sequence `v` of BFN section 2.3 (indices used: up to
/// `BITS - 1 + deg - 1`, and the polynomial degree `m <= BITS + deg - 1`).
const VLEN: usize = 2 * 64 + 64;

/// Fills `out` (`W::BITS` columns) with the generating matrix for polynomial `px`,
/// exactly as GSL's `calculate_cj`/`calculate_v`.
fn generating_matrix<W: Word>(px: u64, out: &mut [W]) {
    let nbits = W::BITS as usize;
    let e = (63 - px.leading_zeros()) as usize;
    let mut pb: u128 = 1; // px^(J-1), then px^J
    let mut pb_deg = 0usize;
    let mut v = [0u8; VLEN];
    let mut u = 0usize;
    for c in out.iter_mut() {
        *c = W::ZERO;
    }
    for j in 0..nbits {
        if u == 0 {
            // calculate_v: B <- B * PX; K_J = deg(old B); v = 0…0 1 1…1 then the
            // linear recurrence with characteristic polynomial B.
            let bigm = pb_deg;
            pb = clmul(pb, px);
            pb_deg += e;
            let m = pb_deg;
            v[..bigm].fill(0);
            v[bigm] = 1;
            if m > bigm + 1 {
                v[bigm + 1..m].fill(1);
            }
            for r in 0..VLEN - m {
                let mut term = 0u8;
                for k in 0..m {
                    term ^= ((pb >> k) as u8 & 1) & v[r + k];
                }
                v[r + m] = term;
            }
        }
        // Digit j of column r is v[r + u] (GSL: ci[r][j] = v[r+u], packed MSB-first).
        let digit = W::ONE << (W::BITS - 1 - j as u32);
        for (r, c) in out.iter_mut().enumerate() {
            if v[r + u] == 1 {
                *c = *c | digit;
            }
        }
        u += 1;
        if u == e {
            u = 0;
        }
    }
}

impl<W: Word> Niederreiter2<W> {
    /// Largest supported dimension (polynomials up to degree 8).
    pub const MAX_DIM: usize = 64;

    /// The first `dim` coordinates (`1 <= dim <= MAX_DIM`).
    pub fn new(dim: usize) -> Result<Self> {
        if dim == 0 || dim > Self::MAX_DIM {
            return Err(Error::Dimension {
                requested: dim,
                max: Self::MAX_DIM,
            });
        }
        let polys = irreducible_polynomials(dim);
        let b = W::BITS as usize;
        let mut cols = vec![W::ZERO; dim * b];
        for (p, chunk) in polys.iter().zip(cols.chunks_exact_mut(b)) {
            generating_matrix(*p, chunk);
        }
        Ok(Niederreiter2 { dim, cols, polys })
    }

    /// Irreducible polynomial of coordinate `coord` (0-based), bit k = coefficient of
    /// x^k. Panics if `coord >= dim()`.
    pub fn polynomial(&self, coord: usize) -> u64 {
        self.polys[coord]
    }

    /// The t-value Σ (deg p_i − 1) of the first `dim` coordinates, from the theory.
    pub fn t_theory(&self) -> u32 {
        self.polys.iter().map(|p| 62 - p.leading_zeros()).sum()
    }
}

impl Niederreiter2<u64> {
    /// The sequence in dimension 3 from a precomputed table (what
    /// [`PointSource::niederreiter`](crate::qmc::points::PointSource::niederreiter) uses): equal to
    /// `new(3)`, without its ~2 ms of polynomial arithmetic.
    pub fn dim3() -> Self {
        Niederreiter2 {
            dim: 3,
            cols: super::niederreiter_table::COLS.to_vec(),
            polys: super::niederreiter_table::POLYS.to_vec(),
        }
    }
}

impl<W: Word> DigitalSequence for Niederreiter2<W> {
    type Word = W;

    #[inline]
    fn dim(&self) -> usize {
        self.dim
    }

    #[inline]
    fn matrix(&self, coord: usize) -> &[W] {
        let b = W::BITS as usize;
        &self.cols[coord * b..(coord + 1) * b]
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_dimension_3_table_is_the_computation() {
        assert_eq!(
            super::Niederreiter2::<u64>::dim3(),
            super::Niederreiter2::<u64>::new(3).unwrap()
        );
    }

    use super::*;
    use crate::qmc::{Sobol, gray_code, net};

    const GSL: &str = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/nied2_gsl.txt"
    ));

    fn parse_rows(text: &str) -> Vec<Vec<u64>> {
        text.lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| {
                l.split_whitespace()
                    .map(|h| u64::from_str_radix(h, 16).unwrap())
                    .collect()
            })
            .collect()
    }

    #[test]
    fn polynomial_order_as_gsl() {
        let p = irreducible_polynomials(12);
        assert_eq!(p, [2, 3, 7, 11, 13, 19, 25, 31, 37, 41, 47, 55]);
        // Counts of irreducible polynomials of degree 1..=8 (Gauss' formula).
        let all = irreducible_polynomials(71);
        let mut count = [0usize; 9];
        for q in all {
            count[(63 - q.leading_zeros()) as usize] += 1;
        }
        assert_eq!(count, [0, 2, 1, 2, 3, 6, 9, 18, 30]);
    }

    /// GSL's k-th output is natural point gray(k); GSL keeps 31 digits.
    #[test]
    fn matches_gsl_bit_for_bit() {
        let rows = parse_rows(GSL);
        assert_eq!(rows.len(), 4096);
        let n32 = Niederreiter2::<u32>::new(12).unwrap();
        let n64 = Niederreiter2::<u64>::new(12).unwrap();
        let mut p32 = [0u32; 12];
        let mut p64 = [0u64; 12];
        let mut q32 = [0u32; 12];
        let mut it = n32.gray_iter();
        let mut matched = 0;
        for (k, row) in rows.iter().enumerate() {
            assert_eq!(row.len(), 12);
            n32.point_bits(gray_code(k as u64), &mut p32).unwrap();
            n64.point_bits(gray_code(k as u64), &mut p64).unwrap();
            it.next_bits_into(&mut q32).unwrap();
            for j in 0..12 {
                assert_eq!(u64::from(p32[j] >> 1), row[j], "point {k} coord {j}");
                assert_eq!(p64[j] >> 33, row[j], "point {k} coord {j} (64-bit)");
                assert_eq!(q32[j], p32[j]);
                matched += 1;
            }
        }
        assert_eq!(matched, 4096 * 12);
    }

    #[test]
    fn low_dims_equal_sobol_third_differs() {
        let n = Niederreiter2::<u64>::new(3).unwrap();
        let s = Sobol::<u64>::new(3).unwrap();
        assert_eq!(n.matrix(0), s.matrix(0));
        assert_eq!(n.matrix(1), s.matrix(1));
        assert_ne!(n.matrix(2), s.matrix(2));
        let (mut a, mut b) = ([0u64; 3], [0u64; 3]);
        let mut differ = false;
        for p in 0..4096 {
            n.point_bits(p, &mut a).unwrap();
            s.point_bits(p, &mut b).unwrap();
            assert_eq!(a[..2], b[..2]);
            differ |= a[2] != b[2];
        }
        assert!(differ);
        let n32 = Niederreiter2::<u32>::new(2).unwrap();
        let s32 = Sobol::<u32>::new(2).unwrap();
        assert_eq!(n32.matrix(1), s32.matrix(1));
    }

    /// Degree of the polynomial of `coord`, minus one: the theoretical t of the
    /// coordinate alone.
    fn t_bound(n: &Niederreiter2<u64>, coord: usize) -> u32 {
        62 - n.polynomial(coord).leading_zeros()
    }

    /// Each of the first 20 coordinates alone is a (t,1)-sequence with t <= deg - 1:
    /// for every m, the first m - t rows of the upper-left m×m block are independent
    /// (unlike Sobol', the matrices are not triangular, so t = 0 is not automatic,
    /// and the full BITS×BITS truncation can lose up to deg - 1 in rank).
    #[test]
    fn single_coordinates_up_to_20() {
        let n = Niederreiter2::<u64>::new(20).unwrap();
        let n32 = Niederreiter2::<u32>::new(20).unwrap();
        for j in 0..20 {
            assert!(net::t_value_net(&n, &[j], 64).unwrap() <= t_bound(&n, j));
            assert!(net::t_value_net(&n32, &[j], 32).unwrap() <= t_bound(&n, j));
            let t = net::t_value_sequence(&n, &[j], 64);
            assert!(t <= t_bound(&n, j), "coord {j}: t = {t}");
            assert_eq!(t, net::t_value_sequence(&n32, &[j], 32), "coord {j}");
        }
        assert_eq!(net::t_value_sequence(&n, &[0], 64), 0);
        assert_eq!(net::t_value_sequence(&n, &[1], 64), 0);
    }

    #[test]
    fn t_values_from_rank_conditions() {
        let n = Niederreiter2::<u64>::new(20).unwrap();
        // Dims 1-2: a (0,2)-sequence; every aligned block of 2^m points is a
        // (0,m,2)-net for all m up to 64.
        assert_eq!(net::t_value_sequence(&n, &[0, 1], 64), 0);
        // Dims 1-3: a (1,3)-sequence (t = 0 + 0 + 1).
        assert_eq!(net::t_value_sequence(&n, &[0, 1, 2], 32), 1);
        assert_eq!(n.t_theory(), 1 + 2 + 2 + 3 + 3 + 3 + 4 * 6 + 5 * 6);
        // Pairs among the first 20 coordinates: t of a pair <= sum of (deg - 1).
        for a in 0..20 {
            for b in a + 1..20 {
                let t = net::t_value_sequence(&n, &[a, b], 24);
                let bound = t_bound(&n, a) + t_bound(&n, b);
                assert!(t <= bound, "pair {a},{b}: t = {t} > {bound}");
            }
        }
    }

    #[test]
    fn first_dims_t_value_by_counting() {
        let n = Niederreiter2::<u64>::new(3).unwrap();
        let mut buf = vec![0u64; 3 << 12];
        for m in 1u32..=12 {
            for blk in [0u64, 1, 7, 12345] {
                let len = 3usize << m;
                n.block_bits(blk, m, &mut buf[..len]).unwrap();
                let pts = &buf[..len];
                assert_eq!(net::t_value_by_counting(pts, 3, &[0, 1], m).unwrap(), 0);
                assert!(net::t_value_by_counting(pts, 3, &[0, 1, 2], m).unwrap() <= 1);
            }
        }
    }
}
