//! Quality checks for digital nets and sequences in base 2: the t-value.
//!
//! A set of 2^m points in `[0,1)^s` is a (t,m,s)-net if every elementary interval
//! `Π_j [a_j 2^-d_j, (a_j+1) 2^-d_j)` with `Σ d_j = m − t` contains exactly 2^t points
//! (H. Niederreiter, *Random Number Generation and Quasi-Monte Carlo Methods*, SIAM
//! 1992, ch. 4). For a digital net with generating matrices `C_j` this holds iff, for
//! every such `(d_j)`, the first `d_j` rows of each `C_j` restricted to the first `m`
//! columns are linearly independent over GF(2) (the rank conditions).
//!
//! * [`t_value_net`] / [`t_value_sequence`]: t from the rank conditions on the
//!   generating matrices of a [`DigitalSequence`] (valid for the unscrambled,
//!   digitally shifted and Matoušek-scrambled sequences, whose output map is a digital
//!   shift). Since every aligned block of 2^m points of a digital sequence is a
//!   digital shift of the first one, the t of [`t_value_net`] holds for every block.
//! * [`t_value_by_counting`]: t of an explicit point set (digit words) by counting the
//!   points in every elementary interval; works for any randomisation, including
//!   Owen's nested scrambling.

use alloc::vec;
use alloc::vec::Vec;

use super::{DigitalSequence, Word};
use crate::error::{Error, Result};

/// Row `i` of the upper-left part of a generating matrix: bit `r` is digit `i`
/// (0-based, most significant first) of column `r`, for `r < m`.
fn rows<W: Word>(cols: &[W], m: u32) -> [u64; 64] {
    let b = W::BITS;
    let mut rows = [0u64; 64];
    for (r, c) in cols.iter().take(m as usize).enumerate() {
        let c = c.to_u64();
        for (i, row) in rows.iter_mut().take(b as usize).enumerate() {
            *row |= ((c >> (b - 1 - i as u32)) & 1) << r;
        }
    }
    rows
}

/// An XOR basis of GF(2)^64 vectors, indexed by leading bit.
#[derive(Clone, Copy)]
struct Basis([u64; 64]);

impl Basis {
    /// Adds `x`; returns `false` if it is a combination of the basis.
    fn insert(&mut self, mut x: u64) -> bool {
        while x != 0 {
            let h = 63 - x.leading_zeros() as usize;
            if self.0[h] == 0 {
                self.0[h] = x;
                return true;
            }
            x ^= self.0[h];
        }
        false
    }
}

/// Whether, for every composition `(d_j)` of `remaining` over `rows[level..]`, the
/// first `d_j` rows of each matrix together with `basis` are independent.
fn independent(rows: &[[u64; 64]], level: usize, remaining: usize, basis: &Basis) -> bool {
    let Some(cur) = rows.get(level) else {
        return remaining == 0;
    };
    let mut b = *basis;
    if level + 1 == rows.len() {
        return cur.iter().take(remaining).all(|&r| b.insert(r));
    }
    for d in 0..=remaining {
        if d > 0 && !b.insert(cur[d - 1]) {
            return false;
        }
        if !independent(rows, level + 1, remaining - d, &b) {
            return false;
        }
    }
    true
}

fn check_coords<S: DigitalSequence + ?Sized>(seq: &S, coords: &[usize]) -> Result<()> {
    for &c in coords {
        if c >= seq.dim() {
            return Err(Error::Dimension {
                requested: c + 1,
                max: seq.dim(),
            });
        }
    }
    Ok(())
}

fn check_m<W: Word>(m: u32) -> Result<()> {
    if m > W::BITS {
        return Err(Error::IndexOutOfRange {
            name: "m",
            index: u64::from(m),
            limit: u64::from(W::BITS) + 1,
        });
    }
    Ok(())
}

/// The t-value of the digital (t,m,s)-net formed by the coordinates `coords`
/// (0-based) of the first 2^m points of `seq` — and of every aligned block of 2^m
/// points — from the rank conditions on the generating matrices. `m <= Word::BITS`.
pub fn t_value_net<S: DigitalSequence + ?Sized>(seq: &S, coords: &[usize], m: u32) -> Result<u32> {
    check_coords(seq, coords)?;
    check_m::<S::Word>(m)?;
    let rs: Vec<[u64; 64]> = coords.iter().map(|&c| rows(seq.matrix(c), m)).collect();
    let empty = Basis([0; 64]);
    let mut k = 0;
    while k < m as usize && independent(&rs, 0, k + 1, &empty) {
        k += 1;
    }
    Ok(m - k as u32)
}

/// The t-value of `seq` restricted to `coords` as a (t,s)-sequence, checked for all
/// `m = 1..=m_max` (`m_max <= Word::BITS`): the largest t of the nets of 2^m points.
/// Panics if a coordinate is out of range or `m_max > Word::BITS` (test helper).
pub fn t_value_sequence<S: DigitalSequence + ?Sized>(seq: &S, coords: &[usize], m_max: u32) -> u32 {
    check_coords(seq, coords).expect("coordinate out of range");
    check_m::<S::Word>(m_max).expect("m_max too large");
    // k_max(m) (largest k with all compositions independent) does not decrease with
    // m, so each m starts from the previous k.
    let empty = Basis([0; 64]);
    let mut k = 0usize;
    let mut t = 0;
    for m in 1..=m_max {
        let rs: Vec<[u64; 64]> = coords.iter().map(|&c| rows(seq.matrix(c), m)).collect();
        while k < m as usize && independent(&rs, 0, k + 1, &empty) {
            k += 1;
        }
        t = t.max(m - k as u32);
    }
    t
}

/// Whether the points form a (t,m,s)-net in the coordinates `coords`, by counting.
///
/// `points` holds 2^m points of `dim` digit words each, row-major (as written by
/// [`DigitalSequence::block_bits`]).
pub fn is_net_by_counting<W: Word>(
    points: &[W],
    dim: usize,
    coords: &[usize],
    m: u32,
    t: u32,
) -> Result<bool> {
    check_points(points, dim, coords, m)?;
    if t >= m {
        return Ok(true);
    }
    let k = m - t;
    let mut counts = vec![0u32; 1usize << k];
    let mut d = vec![0u32; coords.len()];
    Ok(compositions(&mut d, 0, k, &mut |d| {
        counts.fill(0);
        for p in points.chunks_exact(dim) {
            let mut cell = 0usize;
            for (&c, &dj) in coords.iter().zip(d.iter()) {
                if dj > 0 {
                    let top = p[c].to_u64() >> (W::BITS - dj);
                    cell = (cell << dj) | top as usize;
                }
            }
            counts[cell] += 1;
        }
        counts.iter().all(|&n| n == 1 << t)
    }))
}

/// Calls `f` on every composition of `left` into `d[level..]`; stops at the first
/// `false`.
fn compositions(
    d: &mut [u32],
    level: usize,
    left: u32,
    f: &mut impl FnMut(&[u32]) -> bool,
) -> bool {
    if level + 1 >= d.len() {
        if let Some(last) = d.get_mut(level) {
            *last = left;
        }
        return f(d);
    }
    for x in 0..=left {
        d[level] = x;
        if !compositions(d, level + 1, left - x, f) {
            return false;
        }
    }
    true
}

fn check_points<W: Word>(points: &[W], dim: usize, coords: &[usize], m: u32) -> Result<()> {
    check_m::<W>(m)?;
    if m >= usize::BITS - 1 {
        return Err(Error::Overflow { name: "2^m" });
    }
    for &c in coords {
        if c >= dim {
            return Err(Error::Dimension {
                requested: c + 1,
                max: dim,
            });
        }
    }
    let expected = dim
        .checked_mul(1usize << m)
        .ok_or(Error::Overflow { name: "points" })?;
    if points.len() != expected {
        return Err(Error::BufferLength {
            name: "points",
            expected,
            got: points.len(),
        });
    }
    Ok(())
}

/// The smallest t for which the 2^m points (row-major digit words, `dim` per point)
/// form a (t,m,s)-net in the coordinates `coords`, by counting points in elementary
/// intervals.
pub fn t_value_by_counting<W: Word>(
    points: &[W],
    dim: usize,
    coords: &[usize],
    m: u32,
) -> Result<u32> {
    check_points(points, dim, coords, m)?;
    for t in 0..m {
        if is_net_by_counting(points, dim, coords, m, t)? {
            return Ok(t);
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qmc::{Niederreiter2, Sobol};

    #[test]
    fn counting_agrees_with_rank() {
        let n = Niederreiter2::<u32>::new(6).unwrap();
        let s = Sobol::<u32>::new(6).unwrap();
        let m = 9;
        let mut buf = vec![0u32; 6 << m];
        for coords in [
            &[0usize, 1][..],
            &[0, 1, 2],
            &[2, 4],
            &[1, 3, 5],
            &[0, 1, 2, 3, 4, 5],
        ] {
            for blk in [0u64, 3] {
                n.block_bits(blk, m, &mut buf).unwrap();
                assert_eq!(
                    t_value_by_counting(&buf, 6, coords, m).unwrap(),
                    t_value_net(&n, coords, m).unwrap(),
                    "Niederreiter {coords:?}"
                );
                s.block_bits(blk, m, &mut buf).unwrap();
                assert_eq!(
                    t_value_by_counting(&buf, 6, coords, m).unwrap(),
                    t_value_net(&s, coords, m).unwrap(),
                    "Sobol {coords:?}"
                );
            }
        }
    }

    #[test]
    fn bad_arguments() {
        let s = Sobol::<u32>::new(2).unwrap();
        assert!(t_value_net(&s, &[2], 4).is_err());
        assert!(t_value_net(&s, &[0], 33).is_err());
        assert!(t_value_by_counting(&[0u32; 8], 2, &[0, 1], 3).is_err());
        assert!(t_value_by_counting(&[0u32; 16], 2, &[0, 2], 3).is_err());
        // Non-net: all points equal.
        assert_eq!(t_value_by_counting(&[0u32; 16], 2, &[0, 1], 3).unwrap(), 3);
    }
}
