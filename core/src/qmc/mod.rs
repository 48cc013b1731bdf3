//! Quasi-Monte Carlo: digital (t,s)-sequences in base 2 and their randomisations.
//!
//! * [`Niederreiter2`]: Niederreiter's base-2 sequence, built from the irreducible
//!   polynomials over GF(2) as in P. Bratley, B. L. Fox & H. Niederreiter,
//!   "Implementation and tests of low-discrepancy sequences", ACM TOMS 2(3) (1992)
//!   195–213 (algorithm 738), bit-identical to GSL's `gsl_qrng_niederreiter_2`.
//! * [`Sobol`]: Sobol' sequence with the direction numbers of S. Joe & F. Y. Kuo,
//!   "Constructing Sobol sequences with better two-dimensional projections",
//!   SIAM J. Sci. Comput. 30 (2008) 2635–2654 (`new-joe-kuo-6.21201`).
//! * [`Scrambled`]: random digital shift, J. Matoušek's random linear scrambling
//!   ("On the L2-discrepancy for anchored boxes", J. Complexity 14 (1998) 527–556)
//!   and A. B. Owen's nested uniform scrambling ("Randomly permuted (t,m,s)-nets and
//!   (t,s)-sequences", 1995) in the hash-based form of B. Burley, "Practical
//!   Hash-based Owen Scrambling", JCGT 9(4) (2020).
//! * [`net`]: t-values from the generating matrices (rank conditions) and by counting
//!   points in elementary intervals.
//!
//! # Indexing and order
//!
//! A digital sequence is given by one generating matrix `C_j` per coordinate `j` over
//! GF(2). **Point `p`** (natural order) has coordinate `j` equal to `C_j · digits(p)`:
//! the XOR of the columns `C_j[r]` over the set bits `r` of `p`. Each column is stored
//! as one [`Word`] whose most significant bit is the first binary digit.
//!
//! * [`DigitalSequence::point`] / [`DigitalSequence::point_bits`]: random access to
//!   point `p` in natural order.
//! * [`DigitalSequence::block`]: the `N = 2^m` points `nN, …, nN + N − 1` in natural
//!   order (row `i` of the output is point `nN + i`). It is filled by a Gray-code walk
//!   (one XOR per coordinate and point) that writes each point to its natural row; it
//!   does not allocate. Because the zero point is kept, every such aligned block is a
//!   digital shift of the first one, hence a (t,m,s)-net with the t of the sequence.
//! * [`GrayIter`]: sequential generation in **Gray-code order**, as GSL and scipy
//!   produce it: its `k`-th output is point [`gray_code`]`(k) = k ^ (k >> 1)`. It
//!   visits aligned blocks as sets too — the outputs `k ∈ [nN, nN+N)` are the points
//!   of the natural block `gray_code(n)` — but in a different order.
//!
//! # Precision: 32 or 64 bits
//!
//! Every sequence is generic over the word, `u32` or `u64` (the default). A `u32`
//! sequence has 32 digits per coordinate and at most 2^32 points; as `f64` its
//! coordinates are multiples of 2^-32. A `u64` sequence has 64 digits and 2^64 points,
//! and converts to `f64` by its top 53 digits. Index `2^BITS` and beyond is an
//! [`crate::error::Error::IndexOutOfRange`], never a wrap.
//!
//! For the stochastic particle scheme (N = 2^20 particles, ~1600 steps, one block of
//! 2^20 points per step): the index reaches 1600·2^20 ≈ 1.7·10^9 < 2^31, so 32-bit
//! indices suffice (up to 4096 steps of 2^20). `k = floor(N u1)`, `l = floor(N u2)`
//! need only m = 20 digits. But the test `u3 < pc` with `pc = dt·K̃` as small as
//! 10^-6…10^-9 needs `u3` resolved well below `pc`: with 32 digits `u3` lives on the
//! grid 2^-32 ≈ 2.3·10^-10, so `P(u3 < pc)` is off by up to 2^-32, a relative error
//! of 0.02 % at `pc = 10^-6` but 23 % at 10^-9 (and any `pc < 2^-32` is accepted
//! with probability 2^-32). Use `u64` words for the scheme (53 digits reach the
//! `f64`); `u32` suffices only when every probability compared is ≫ 2^-32.
//!
//! # Example
//!
//! ```
//! use coagula_core::qmc::{DigitalSequence, Niederreiter2, Randomization, Scrambled, Sobol};
//! use rand_core::SeedableRng;
//!
//! let sobol = Sobol::<u64>::new(3)?;
//! let mut x = [0.0; 3];
//! sobol.point(1, &mut x)?;
//! assert_eq!(x, [0.5, 0.5, 0.5]);
//!
//! // One time step of the scheme: block n of N = 2^10 points, row-major.
//! let nied = Niederreiter2::<u64>::new(3)?;
//! let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
//! let owen = Scrambled::new(nied, Randomization::Owen, &mut rng);
//! let mut block = vec![0.0; 1024 * 3];
//! owen.block(5, 10, &mut block)?;
//! assert!(block.iter().all(|&u| (0.0..1.0).contains(&u)));
//! # Ok::<(), coagula_core::error::Error>(())
//! ```

pub mod net;
mod niederreiter;
mod niederreiter_table;
pub mod points;
mod scramble;
mod sobol;
mod sobol_table;
mod word;

use alloc::vec;
use alloc::vec::Vec;

use crate::error::{Error, Result};

pub use niederreiter::Niederreiter2;
pub use scramble::{Randomization, Scrambled};
pub use sobol::Sobol;
pub use word::Word;

/// The Gray code `k ^ (k >> 1)`: the natural index of the `k`-th output of a
/// [`GrayIter`] (and of GSL's and scipy's generators).
#[inline]
pub const fn gray_code(k: u64) -> u64 {
    k ^ (k >> 1)
}

/// The inverse of [`gray_code`]: the Gray-code position at which point `p` is output.
#[inline]
pub const fn gray_code_inverse(p: u64) -> u64 {
    let mut k = p;
    let mut s = 1;
    while s < 64 {
        k ^= k >> s;
        s <<= 1;
    }
    k
}

/// Checks that point `index` exists for words of type `W` (index < 2^BITS).
#[inline]
pub(crate) fn check_index<W: Word>(name: &'static str, index: u64) -> Result<()> {
    if W::BITS < 64 && index >> W::BITS != 0 {
        Err(Error::IndexOutOfRange {
            name,
            index,
            limit: 1u64 << W::BITS,
        })
    } else {
        Ok(())
    }
}

#[inline]
fn check_len(name: &'static str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(Error::BufferLength {
            name,
            expected,
            got,
        })
    }
}

/// `C · digits(index)`: XOR of the columns selected by the set bits of `index`.
/// `index` must be below 2^BITS (checked by the callers).
#[inline]
pub(crate) fn apply<W: Word>(cols: &[W], index: u64) -> W {
    let mut x = W::ZERO;
    let mut i = index;
    while i != 0 {
        if let Some(&c) = cols.get(i.trailing_zeros() as usize) {
            x ^= c;
        }
        i &= i - 1;
    }
    x
}

/// A digital sequence in base 2: one generating matrix per coordinate, plus an
/// optional digit-wise output map (identity except for scrambled sequences).
///
/// Implemented by [`Niederreiter2`], [`Sobol`] and [`Scrambled`]. All provided
/// methods validate their arguments and return errors rather than panic; none of
/// them allocates except [`gray_iter`](Self::gray_iter).
///
/// # Example
///
/// ```
/// use coagula_core::qmc::{DigitalSequence, Sobol};
///
/// let s = Sobol::<u32>::new(2)?;
/// let mut bits = [0u32; 2];
/// s.point_bits(3, &mut bits)?;
/// assert_eq!(bits, [0xc000_0000, 0x4000_0000]); // (0.75, 0.25)
/// assert!(s.point_bits(1 << 32, &mut bits).is_err()); // past 2^32 points
/// # Ok::<(), coagula_core::error::Error>(())
/// ```
pub trait DigitalSequence {
    /// The digit word, `u32` or `u64`.
    type Word: Word;

    /// Number of coordinates.
    fn dim(&self) -> usize;

    /// Generating matrix of coordinate `coord` (0-based, `< dim()`), as `Word::BITS`
    /// columns: column `r` is the image of bit `r` of the index, its most significant
    /// bit the first digit. Panics if `coord >= dim()`.
    fn matrix(&self, coord: usize) -> &[Self::Word];

    /// Digit-wise map applied after the linear part (digital shift, nested scramble).
    /// The identity for unscrambled sequences.
    #[inline]
    fn finish(&self, coord: usize, x: Self::Word) -> Self::Word {
        let _ = coord;
        x
    }

    /// Point `index` (natural order) as digit words; `out.len()` must be `dim()`.
    fn point_bits(&self, index: u64, out: &mut [Self::Word]) -> Result<()> {
        check_index::<Self::Word>("index", index)?;
        check_len("out", self.dim(), out.len())?;
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.finish(j, apply(self.matrix(j), index));
        }
        Ok(())
    }

    /// Point `index` (natural order) in `[0, 1)^dim`; `out.len()` must be `dim()`.
    fn point(&self, index: u64, out: &mut [f64]) -> Result<()> {
        check_index::<Self::Word>("index", index)?;
        check_len("out", self.dim(), out.len())?;
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.finish(j, apply(self.matrix(j), index)).to_unit();
        }
        Ok(())
    }

    /// Block `n` of `N = 2^m` points as digit words: row `i` (`out[i*dim..(i+1)*dim]`)
    /// is point `n·N + i`. `out.len()` must be `N·dim()`. Does not allocate.
    fn block_bits(&self, n: u64, m: u32, out: &mut [Self::Word]) -> Result<()> {
        fill_block(self, n, m, out, |w| w)
    }

    /// Block `n` of `N = 2^m` points in `[0, 1)^dim`: row `i`
    /// (`out[i*dim..(i+1)*dim]`) is point `n·N + i`. `out.len()` must be `N·dim()`.
    /// Does not allocate.
    fn block(&self, n: u64, m: u32, out: &mut [f64]) -> Result<()> {
        fill_block(self, n, m, out, Word::to_unit)
    }

    /// A Gray-code cursor at position 0 (allocates one word per coordinate).
    fn gray_iter(&self) -> GrayIter<'_, Self>
    where
        Self: Sized,
    {
        GrayIter::new(self)
    }
}

/// Block `n` of `N = 2^m` points of a digital sequence with 64-bit words, no
/// randomisation (`finish` the identity on coordinate 0) and 3 coordinates, visited by the first coordinate's top `m`
/// digits `k = ⌊N u_0⌋` instead of by index: `visit(k, x1, x2)` gets the digit words of
/// coordinates 1 and 2 of the point whose first coordinate has those digits, with `k`
/// in Gray-code order (`k = j ^ (j >> 1)`, `j = 0, 1, …`: every aligned run of `2^b`
/// consecutive calls stays in one aligned run of `2^b` values of `k`, so arrays indexed
/// by `k` are walked nearly in order).
///
/// The words are those of [`DigitalSequence::block_bits`] bit for bit (the same points,
/// each updated by XOR of columns): only the order of the visits differs. In the block
/// the top `m` digits of the first coordinate are `A p ⊕ c` for point `p` (`A` the top
/// `m × m` corner of the first generating matrix, `c` from the block number), so the
/// point of digits `k` is `p = A⁻¹ (k ⊕ c)`, and a step of `k` in one bit moves `p` by
/// one column of `A⁻¹`. Returns `Ok(false)` without visiting anything when `A` is
/// singular (no first coordinate that is a (0, m, 1)-net) or `m > 53`; the first error
/// of `visit` stops the walk and is returned.
pub(crate) fn walk_by_first<S>(
    seq: &S,
    n: u64,
    m: u32,
    mut visit: impl FnMut(usize, u64, u64) -> Result<()>,
) -> Result<bool>
where
    S: DigitalSequence<Word = u64> + ?Sized,
{
    // (a sequence of more coordinates is not a mass-flow block: the block path refuses it)
    if seq.dim() != 3 || m == 0 || m > 53 {
        return Ok(false);
    }
    let big_n = check_block::<u64>(n, m, 3, 3usize << m)?;
    let base = n << m;
    let (c0, c1, c2) = (seq.matrix(0), seq.matrix(1), seq.matrix(2));
    let top = |w: u64| (w >> (64 - m)) as usize;
    // pairs (image k, preimage p), reduced until image r is bit r alone
    let mut pairs: [(usize, usize); 64] = [(0, 0); 64];
    for (r, pair) in pairs.iter_mut().enumerate().take(m as usize) {
        *pair = (c0.get(r).map_or(0, |&w| top(w)), 1 << r);
    }
    for b in 0..m as usize {
        let Some(pivot) = (b..m as usize).find(|&i| pairs[i].0 >> b & 1 == 1) else {
            return Ok(false);
        };
        pairs.swap(b, pivot);
        let (img, pre) = pairs[b];
        for (i, pair) in pairs.iter_mut().enumerate().take(m as usize) {
            if i != b && pair.0 >> b & 1 == 1 {
                pair.0 ^= img;
                pair.1 ^= pre;
            }
        }
    }
    // the point of k = 0, and the moves of coordinates 1, 2 per bit of k
    let c = top(apply(c0, base));
    let p0 = (0..m as usize)
        .filter(|&b| c >> b & 1 == 1)
        .fold(0, |p, b| p ^ pairs[b].1);
    let mut x1 = apply(c1, base | p0 as u64);
    let mut x2 = apply(c2, base | p0 as u64);
    let mut d1 = [0u64; 64];
    let mut d2 = [0u64; 64];
    for b in 0..m as usize {
        d1[b] = apply(c1, pairs[b].1 as u64);
        d2[b] = apply(c2, pairs[b].1 as u64);
    }
    for j in 0..big_n {
        visit(j ^ (j >> 1), seq.finish(1, x1), seq.finish(2, x2))?;
        let r = (j + 1).trailing_zeros() as usize;
        if r < m as usize {
            x1 ^= d1[r];
            x2 ^= d2[r];
        }
    }
    Ok(true)
}

/// Validates block `n` of `2^m` points and returns `N = 2^m`.
fn check_block<W: Word>(n: u64, m: u32, dim: usize, len: usize) -> Result<usize> {
    if m > W::BITS || m >= usize::BITS {
        return Err(Error::IndexOutOfRange {
            name: "m",
            index: u64::from(m),
            limit: u64::from(W::BITS.min(usize::BITS - 1) + 1),
        });
    }
    let free = W::BITS - m; // number of index bits left for n
    if free < 64 && n >> free != 0 {
        return Err(Error::IndexOutOfRange {
            name: "block n",
            index: n,
            limit: 1u64 << free,
        });
    }
    let big_n = 1usize << m;
    let expected = big_n.checked_mul(dim).ok_or(Error::Overflow {
        name: "block length",
    })?;
    check_len("out", expected, len)?;
    Ok(big_n)
}

fn fill_block<S, T>(
    seq: &S,
    n: u64,
    m: u32,
    out: &mut [T],
    conv: impl Fn(S::Word) -> T,
) -> Result<()>
where
    S: DigitalSequence + ?Sized,
{
    let dim = seq.dim();
    let big_n = check_block::<S::Word>(n, m, dim, out.len())?;
    // `m < 64` here (m < usize::BITS), and `n << m` fits since n < 2^(BITS - m).
    let base = n << m;
    if dim <= 4 {
        // Few coordinates: one Gray-code walk per coordinate (the k-th visited point
        // is base + gray(k), stored at its natural row gray(k)).
        for j in 0..dim {
            let cols = seq.matrix(j);
            let mut x = apply(cols, base);
            for k in 0..big_n {
                let row = k ^ (k >> 1);
                if let Some(o) = out.get_mut(row * dim + j) {
                    *o = conv(seq.finish(j, x));
                }
                let next = k + 1;
                if next < big_n
                    && let Some(&c) = cols.get(next.trailing_zeros() as usize)
                {
                    x ^= c;
                }
            }
        }
        return Ok(());
    }
    // Many coordinates: groups of up to TILE coordinates walked together, with their
    // state on the stack (no allocation), so that each visited row is written
    // contiguously.
    const TILE: usize = 32;
    let mut state = [<S::Word as Word>::ZERO; TILE];
    let mut mats: [&[S::Word]; TILE] = [&[]; TILE];
    let mut g0 = 0;
    while g0 < dim {
        let gw = TILE.min(dim - g0);
        for (i, (s, c)) in state.iter_mut().zip(mats.iter_mut()).take(gw).enumerate() {
            *c = seq.matrix(g0 + i);
            *s = apply(c, base);
        }
        for k in 0..big_n {
            let row = k ^ (k >> 1);
            let at = row * dim + g0;
            if let Some(o) = out.get_mut(at..at + gw) {
                for (i, (o, &s)) in o.iter_mut().zip(&state).enumerate() {
                    *o = conv(seq.finish(g0 + i, s));
                }
            }
            let next = k + 1;
            if next < big_n {
                let r = next.trailing_zeros() as usize;
                for (s, c) in state.iter_mut().zip(&mats).take(gw) {
                    if let Some(&x) = c.get(r) {
                        *s ^= x;
                    }
                }
            }
        }
        g0 += gw;
    }
    Ok(())
}

/// Sequential generation in Gray-code order: the `k`-th output is point
/// [`gray_code`]`(k)`, so consecutive outputs differ by one XOR per coordinate.
/// This is the order of GSL's `gsl_qrng_niederreiter_2`/`gsl_qrng_sobol` and of
/// scipy's `Sobol`. Allocation happens only in the constructor.
///
/// # Example
///
/// ```
/// use coagula_core::qmc::{gray_code, DigitalSequence, Sobol};
///
/// let s = Sobol::<u64>::new(2)?;
/// let mut it = s.gray_iter();
/// it.seek(5)?;
/// let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
/// it.next_into(&mut a)?;
/// s.point(gray_code(5), &mut b)?; // point 7
/// assert_eq!(a, b);
/// assert_eq!(it.position(), 6);
/// # Ok::<(), coagula_core::error::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct GrayIter<'a, S: DigitalSequence> {
    seq: &'a S,
    pos: u64,
    /// `true` once the last representable point has been output.
    done: bool,
    /// Linear part `C_j · gray(pos)` of each coordinate.
    state: Vec<S::Word>,
}

impl<'a, S: DigitalSequence> GrayIter<'a, S> {
    /// A cursor at position 0 (the zero point, before any scrambling).
    pub fn new(seq: &'a S) -> Self {
        GrayIter {
            seq,
            pos: 0,
            done: false,
            state: vec![<S::Word as Word>::ZERO; seq.dim()],
        }
    }

    /// The sequence being walked.
    pub fn sequence(&self) -> &'a S {
        self.seq
    }

    /// Gray-code position of the next output.
    pub fn position(&self) -> u64 {
        self.pos
    }

    /// Natural index of the next output, `gray_code(position())`.
    pub fn next_index(&self) -> u64 {
        gray_code(self.pos)
    }

    /// Moves to Gray-code position `pos` (the next output is point `gray_code(pos)`).
    pub fn seek(&mut self, pos: u64) -> Result<()> {
        check_index::<S::Word>("position", pos)?;
        let g = gray_code(pos);
        for (j, s) in self.state.iter_mut().enumerate() {
            *s = apply(self.seq.matrix(j), g);
        }
        self.pos = pos;
        self.done = false;
        Ok(())
    }

    fn advance(&mut self) {
        let next = self.pos.wrapping_add(1);
        if next == 0 || (S::Word::BITS < 64 && next >> S::Word::BITS != 0) {
            self.done = true;
            return;
        }
        let r = next.trailing_zeros() as usize;
        for (j, s) in self.state.iter_mut().enumerate() {
            if let Some(&c) = self.seq.matrix(j).get(r) {
                *s ^= c;
            }
        }
        self.pos = next;
    }

    fn check(&self, len: usize) -> Result<()> {
        if self.done {
            // The last representable point has been output.
            return Err(Error::IndexOutOfRange {
                name: "position",
                index: self.pos.saturating_add(1),
                limit: if S::Word::BITS < 64 {
                    1u64 << S::Word::BITS
                } else {
                    u64::MAX
                },
            });
        }
        check_len("out", self.state.len(), len)
    }

    /// Writes the next point as digit words and advances.
    pub fn next_bits_into(&mut self, out: &mut [S::Word]) -> Result<()> {
        self.check(out.len())?;
        for (j, (o, &s)) in out.iter_mut().zip(&self.state).enumerate() {
            *o = self.seq.finish(j, s);
        }
        self.advance();
        Ok(())
    }

    /// Writes the next point in `[0, 1)^dim` and advances.
    pub fn next_into(&mut self, out: &mut [f64]) -> Result<()> {
        self.check(out.len())?;
        for (j, (o, &s)) in out.iter_mut().zip(&self.state).enumerate() {
            *o = self.seq.finish(j, s).to_unit();
        }
        self.advance();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dims_and_orders<S: DigitalSequence>(s: &S) {
        let d = s.dim();
        let m = 7;
        let nn = 1usize << m;
        let mut blk = vec![S::Word::default(); nn * d];
        let mut p = vec![S::Word::default(); d];
        let mut q = vec![S::Word::default(); d];
        let mut it = s.gray_iter();
        for n in [0u64, 1, 5, 1000] {
            s.block_bits(n, m, &mut blk).unwrap();
            it.seek(n << m).unwrap();
            let mut seen = vec![false; nn];
            for i in 0..nn {
                let idx = (n << m) + i as u64;
                s.point_bits(idx, &mut p).unwrap();
                assert_eq!(
                    &blk[i * d..(i + 1) * d],
                    &p[..],
                    "block row = natural point"
                );
                // Gray iterator: k-th output is point gray(k).
                it.next_bits_into(&mut q).unwrap();
                let g = gray_code(idx);
                s.point_bits(g, &mut p).unwrap();
                assert_eq!(p, q);
                assert_eq!(g >> m, gray_code(n), "Gray block n = natural block gray(n)");
                seen[(g as usize) & (nn - 1)] = true;
            }
            assert!(seen.iter().all(|&b| b));
        }
        // f64 versions agree with the bits.
        let mut f = vec![0.0; nn * d];
        s.block(3, m, &mut f).unwrap();
        s.block_bits(3, m, &mut blk).unwrap();
        for (a, b) in f.iter().zip(&blk) {
            assert_eq!(*a, b.to_unit());
        }
    }

    #[test]
    fn block_iter_and_random_access_agree() {
        dims_and_orders(&Sobol::<u64>::new(5).unwrap());
        dims_and_orders(&Sobol::<u64>::new(70).unwrap()); // several tiles in `block`
        dims_and_orders(&Sobol::<u32>::new(3).unwrap()); // per-coordinate `block` path
        dims_and_orders(&Sobol::<u32>::new(5).unwrap());
        dims_and_orders(&Niederreiter2::<u64>::new(7).unwrap());
        dims_and_orders(&Niederreiter2::<u32>::new(7).unwrap());
    }

    /// The walk by first digits visits exactly the block's points (same words), each
    /// at the `k` its first coordinate gives.
    #[test]
    fn walk_by_first_visits_the_block() {
        fn check<S: DigitalSequence<Word = u64>>(seq: &S) {
            for (n, m) in [(0u64, 1u32), (0, 5), (3, 4), (7, 10), (1, 12)] {
                let big_n = 1usize << m;
                let mut block = vec![0u64; 3 * big_n];
                seq.block_bits(n, m, &mut block).unwrap();
                let mut want: Vec<Option<(u64, u64)>> = vec![None; big_n];
                for p in 0..big_n {
                    let k = (block[3 * p] >> (64 - m)) as usize;
                    assert!(want[k].is_none(), "first digits repeat");
                    want[k] = Some((block[3 * p + 1], block[3 * p + 2]));
                }
                let mut seen = 0;
                let mut last = None;
                let walked = walk_by_first(seq, n, m, |k, x1, x2| {
                    assert_eq!(want[k], Some((x1, x2)), "n {n} m {m} k {k}");
                    want[k] = None;
                    seen += 1;
                    last = Some(k);
                    Ok(())
                })
                .unwrap();
                assert!(walked);
                assert_eq!(seen, big_n);
                // Gray order: the last visit is k = N/2
                assert_eq!(last, Some(big_n / 2));
            }
        }
        check(&Niederreiter2::<u64>::dim3());
        check(&Sobol::<u64>::new(3).unwrap());
        // both have van der Corput's first coordinate (A a permutation): rotate the
        // coordinates so that A is Niederreiter's second one, a full triangular matrix
        // whose inversion needs the elimination's row additions
        struct Rotated(Niederreiter2<u64>);
        impl DigitalSequence for Rotated {
            type Word = u64;
            fn dim(&self) -> usize {
                3
            }
            fn matrix(&self, coord: usize) -> &[u64] {
                self.0.matrix((coord + 1) % 3)
            }
        }
        let rotated = Rotated(Niederreiter2::<u64>::dim3());
        let a = rotated.matrix(0);
        assert!(
            (1..8).any(|r| a[r].count_ones() > 1),
            "not a permutation: the test covers the row additions"
        );
        check(&rotated);
    }

    #[test]
    fn gray_inverse() {
        for k in [0u64, 1, 2, 3, 1000, u64::MAX, 1 << 63, 0xdead_beef] {
            assert_eq!(gray_code_inverse(gray_code(k)), k);
            assert_eq!(gray_code(gray_code_inverse(k)), k);
        }
    }

    #[test]
    fn errors_not_wraps() {
        let s = Sobol::<u32>::new(2).unwrap();
        let mut p = [0u32; 2];
        let mut f = [0.0; 2];
        assert!(s.point_bits((1 << 32) - 1, &mut p).is_ok());
        assert_eq!(
            s.point(1 << 32, &mut f),
            Err(Error::IndexOutOfRange {
                name: "index",
                index: 1 << 32,
                limit: 1 << 32
            })
        );
        assert!(matches!(
            s.point(0, &mut [0.0; 3]),
            Err(Error::BufferLength { .. })
        ));
        // Block: n < 2^(32 - m).
        let mut b = vec![0u32; 2 * 4];
        assert!(s.block_bits((1 << 30) - 1, 2, &mut b).is_ok());
        assert!(matches!(
            s.block_bits(1 << 30, 2, &mut b),
            Err(Error::IndexOutOfRange {
                name: "block n",
                ..
            })
        ));
        assert!(matches!(
            s.block_bits(0, 33, &mut b),
            Err(Error::IndexOutOfRange { name: "m", .. })
        ));
        assert!(matches!(
            s.block_bits(0, 3, &mut b),
            Err(Error::BufferLength { .. })
        ));
        // Gray iterator stops after point 2^32 - 1.
        let mut it = s.gray_iter();
        it.seek((1 << 32) - 1).unwrap();
        assert!(it.next_bits_into(&mut p).is_ok());
        assert!(it.next_bits_into(&mut p).is_err());
        assert!(it.seek(1 << 32).is_err());
        // u64: every index exists.
        let s = Sobol::<u64>::new(2).unwrap();
        let mut p = [0u64; 2];
        assert!(s.point_bits(u64::MAX, &mut p).is_ok());
        let mut it = s.gray_iter();
        it.seek(u64::MAX).unwrap();
        assert!(it.next_bits_into(&mut p).is_ok());
        assert!(it.next_bits_into(&mut p).is_err());
        let mut b = [0u64; 2];
        assert!(s.block_bits(u64::MAX, 0, &mut b).is_ok());
        assert!(s.block_bits(1 << 63, 1, &mut [0u64; 4]).is_err());
    }
}
