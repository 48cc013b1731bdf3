//! Randomisation of digital sequences for randomised QMC (RQMC).
//!
//! * Random digital shift: XOR of every coordinate with a uniform random word.
//! * Random linear scrambling of J. Matoušek, "On the L2-discrepancy for anchored
//!   boxes", J. Complexity 14 (1998) 527–556 (also in his *Geometric Discrepancy*,
//!   1999): digits `y = L x + e` with `L` a uniform random nonsingular lower-triangular
//!   binary matrix (unit diagonal) and `e` a random digital shift, per coordinate.
//!   Folded into the generating matrices (`C_j <- L_j C_j`), so generation costs the
//!   same as without scrambling.
//! * Nested uniform scrambling of A. B. Owen, "Randomly permuted (t,m,s)-nets and
//!   (t,s)-sequences", in *Monte Carlo and Quasi-Monte Carlo Methods in Scientific
//!   Computing*, LNS 106 (1995) 299–317, in the hash-based form of B. Burley,
//!   "Practical Hash-based Owen Scrambling", JCGT 9(4) (2020): a Laine–Karras
//!   permutation of the bit-reversed word with one random seed per coordinate.
//!
//! All three keep the (t,m,s)-net property of every aligned block of 2^m points (the
//! tests check it by counting).

use alloc::vec::Vec;

use rand_core::Rng;

use super::{DigitalSequence, Word};

/// Kind of randomisation applied by [`Scrambled`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Randomization {
    /// No randomisation: the deterministic sequence (no random numbers are drawn).
    None,
    /// Random digital shift (XOR with a random word per coordinate).
    DigitalShift,
    /// Matoušek's random linear scrambling plus a random digital shift.
    Matousek,
    /// Owen's nested uniform scrambling (hash-based, Burley 2020).
    Owen,
}

/// A randomised digital sequence.
///
/// The random parameters are drawn once, in [`new`](Self::new), from the caller's
/// RNG; the result is again a [`DigitalSequence`] with random access, blocks and the
/// Gray-code iterator. Point `p` of the scrambled sequence is the scramble of point
/// `p` of the original.
///
/// # Example
///
/// ```
/// use coagula_core::qmc::{DigitalSequence, Randomization, Scrambled, Sobol};
/// use rand_core::SeedableRng;
///
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(42);
/// let lms = Scrambled::new(Sobol::<u64>::new(2)?, Randomization::Matousek, &mut rng);
/// let mut block = [0.0; 2 * 16];
/// lms.block(0, 4, &mut block)?;
/// // Still a (0,4,2)-net: one point in each of the 16 columns of width 1/16.
/// let mut seen = [false; 16];
/// for p in block.chunks_exact(2) {
///     seen[(p[0] * 16.0) as usize] = true;
/// }
/// assert!(seen.iter().all(|&s| s));
/// # Ok::<(), coagula_core::error::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scrambled<S: DigitalSequence> {
    seq: S,
    kind: Randomization,
    /// Generating matrices in use (`L_j C_j` for Matoušek, a copy otherwise).
    cols: Vec<S::Word>,
    /// Per coordinate: the digital shift, or the Owen seed.
    param: Vec<S::Word>,
}

/// `L · x` for the lower-triangular matrix whose row `i` (digit `i`, most significant
/// first) is `rows[i]` (a word mask over the digits).
fn lower_times<W: Word>(rows: &[u64], x: W) -> W {
    let b = W::BITS;
    let x = x.to_u64();
    let mut y = 0u64;
    for (i, &row) in rows.iter().enumerate() {
        y |= u64::from((row & x).count_ones() & 1) << (b - 1 - i as u32);
    }
    W::from_u64(y)
}

impl<S: DigitalSequence> Scrambled<S> {
    /// Randomises `seq` with `kind`, drawing the random parameters from `rng`.
    pub fn new<R: Rng + ?Sized>(seq: S, kind: Randomization, rng: &mut R) -> Self {
        let dim = seq.dim();
        let b = S::Word::BITS;
        let mut s = Scrambled {
            seq,
            kind,
            cols: Vec::with_capacity(dim * b as usize),
            param: Vec::with_capacity(dim),
        };
        s.rerandomize(rng);
        s
    }

    /// Draws new random parameters from `rng`, in place: the same draws as
    /// [`new`](Self::new) with this sequence and kind, and no allocation (the tables
    /// keep their size), so an RQMC scheme can re-randomise every block without
    /// touching the heap.
    pub fn rerandomize<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        let dim = self.seq.dim();
        let b = S::Word::BITS;
        self.cols.clear();
        self.param.clear();
        let mut rows = [0u64; 64];
        for j in 0..dim {
            let c = self.seq.matrix(j);
            match self.kind {
                Randomization::Matousek => {
                    for (i, row) in rows.iter_mut().take(b as usize).enumerate() {
                        let i = i as u32;
                        let diag = 1u64 << (b - 1 - i);
                        // Digits more significant than digit i: word bits above `diag`.
                        let above = if i == 0 {
                            0
                        } else {
                            (u64::MAX << (64 - i)) >> (64 - b)
                        };
                        *row = diag | (rng.next_u64() & above);
                    }
                    self.cols
                        .extend(c.iter().map(|&x| lower_times(&rows[..b as usize], x)));
                }
                _ => self.cols.extend_from_slice(c),
            }
            self.param.push(match self.kind {
                Randomization::None => S::Word::ZERO,
                _ => S::Word::from_u64(rng.next_u64()),
            });
        }
    }

    /// The unscrambled sequence.
    pub fn inner(&self) -> &S {
        &self.seq
    }

    /// The randomisation in use.
    pub fn kind(&self) -> Randomization {
        self.kind
    }
}

impl<S: DigitalSequence> DigitalSequence for Scrambled<S> {
    type Word = S::Word;

    #[inline]
    fn dim(&self) -> usize {
        self.seq.dim()
    }

    #[inline]
    fn matrix(&self, coord: usize) -> &[S::Word] {
        let b = S::Word::BITS as usize;
        &self.cols[coord * b..(coord + 1) * b]
    }

    #[inline]
    fn finish(&self, coord: usize, x: S::Word) -> S::Word {
        let p = self.param.get(coord).copied().unwrap_or(S::Word::ZERO);
        match self.kind {
            Randomization::None => x,
            Randomization::DigitalShift | Randomization::Matousek => x ^ p,
            Randomization::Owen => x.nested_scramble(p),
        }
    }
}

impl<S: DigitalSequence> Scrambled<S> {
    /// A fingerprint of the randomisation (kind, matrices and per-coordinate
    /// parameters): equal fingerprints mean identical point sets.
    pub fn fingerprint(&self) -> u64 {
        let kind = match self.kind {
            Randomization::None => 0,
            Randomization::DigitalShift => 1,
            Randomization::Matousek => 2,
            Randomization::Owen => 3,
        };
        crate::checkpoint::fingerprint(
            core::iter::once(kind)
                .chain(self.cols.iter().map(|w| w.to_u64()))
                .chain(self.param.iter().map(|w| w.to_u64())),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qmc::{Niederreiter2, Sobol, net};
    use alloc::vec;
    use rand_core::SeedableRng;
    use rand_pcg::Pcg64;

    const KINDS: [Randomization; 4] = [
        Randomization::None,
        Randomization::DigitalShift,
        Randomization::Matousek,
        Randomization::Owen,
    ];

    /// Count-based t-values of scrambled blocks equal those of the unscrambled ones.
    fn keeps_nets<S: DigitalSequence + Clone>(seq: &S, rng: &mut Pcg64, ms: &[u32]) {
        let d = seq.dim();
        let mmax = *ms.iter().max().unwrap();
        let mut buf = vec![S::Word::ZERO; d << mmax];
        for kind in KINDS {
            for _rep in 0..2 {
                let sc = Scrambled::new(seq.clone(), kind, rng);
                for &m in ms {
                    let len = d << m;
                    for blk in [0u64, 1, 77] {
                        sc.block_bits(blk, m, &mut buf[..len]).unwrap();
                        let pts = &buf[..len];
                        assert_eq!(
                            net::t_value_by_counting(pts, d, &[0, 1], m).unwrap(),
                            0,
                            "{kind:?} m={m} block {blk}"
                        );
                        assert!(net::t_value_by_counting(pts, d, &[0, 1, 2], m).unwrap() <= 1);
                    }
                }
                if kind != Randomization::Owen {
                    // Linear scrambles: the rank conditions still hold.
                    assert_eq!(net::t_value_sequence(&sc, &[0, 1], S::Word::BITS), 0);
                    assert_eq!(net::t_value_sequence(&sc, &[0, 1, 2], 24), 1);
                }
            }
        }
    }

    #[test]
    fn scrambles_keep_net_property() {
        let mut rng = Pcg64::seed_from_u64(2024);
        let ms = [1, 3, 6, 10, 12];
        keeps_nets(&Sobol::<u64>::new(3).unwrap(), &mut rng, &ms);
        keeps_nets(&Sobol::<u32>::new(3).unwrap(), &mut rng, &ms);
        keeps_nets(&Niederreiter2::<u64>::new(3).unwrap(), &mut rng, &ms);
        keeps_nets(&Niederreiter2::<u32>::new(3).unwrap(), &mut rng, &ms);
    }

    #[test]
    fn scrambles_change_points_and_none_does_not() {
        let mut rng = Pcg64::seed_from_u64(5);
        let s = Sobol::<u64>::new(4).unwrap();
        let (mut a, mut b) = ([0u64; 4], [0u64; 4]);
        for kind in KINDS {
            let sc = Scrambled::new(s.clone(), kind, &mut rng);
            let mut differ = 0;
            for p in 0..64 {
                s.point_bits(p, &mut a).unwrap();
                sc.point_bits(p, &mut b).unwrap();
                differ += usize::from(a != b);
            }
            if kind == Randomization::None {
                assert_eq!(differ, 0);
            } else {
                assert!(differ >= 63, "{kind:?}");
            }
        }
    }

    /// RQMC sanity: the mean over replicates of a smooth integrand is unbiased and the
    /// scrambled estimates are far more accurate than plain Monte Carlo would be.
    #[test]
    fn rqmc_estimates_are_accurate() {
        let mut rng = Pcg64::seed_from_u64(77);
        let f = |x: &[f64]| {
            x.iter()
                .map(|&u| 1.5 * (1.0 - (2.0 * u - 1.0).powi(2)))
                .product::<f64>()
        };
        let m = 10;
        let d = 3;
        let mut buf = vec![0.0; d << m];
        for kind in [
            Randomization::DigitalShift,
            Randomization::Matousek,
            Randomization::Owen,
        ] {
            for seq_kind in 0..2 {
                let mut sum = 0.0;
                let mut max_err: f64 = 0.0;
                let reps = 16;
                for _ in 0..reps {
                    let est = if seq_kind == 0 {
                        let sc = Scrambled::new(Sobol::<u64>::new(d).unwrap(), kind, &mut rng);
                        sc.block(0, m, &mut buf).unwrap();
                        buf.chunks_exact(d).map(f).sum::<f64>() / (1u64 << m) as f64
                    } else {
                        let sc =
                            Scrambled::new(Niederreiter2::<u32>::new(d).unwrap(), kind, &mut rng);
                        sc.block(2, m, &mut buf).unwrap();
                        buf.chunks_exact(d).map(f).sum::<f64>() / (1u64 << m) as f64
                    };
                    sum += est;
                    max_err = max_err.max((est - 1.0).abs());
                }
                // Plain MC with 1024 points: standard error ~ 0.03.
                assert!(max_err < 0.01, "{kind:?} {seq_kind}: {max_err}");
                assert!((sum / 16.0 - 1.0).abs() < 0.003, "{kind:?} {seq_kind}");
            }
        }
    }

    #[test]
    fn gray_iter_of_scrambled_matches_random_access() {
        let mut rng = Pcg64::seed_from_u64(9);
        for kind in KINDS {
            let sc = Scrambled::new(Niederreiter2::<u64>::new(5).unwrap(), kind, &mut rng);
            let mut it = sc.gray_iter();
            it.seek(1000).unwrap();
            let (mut a, mut b) = ([0.0; 5], [0.0; 5]);
            for k in 1000..1100u64 {
                it.next_into(&mut a).unwrap();
                sc.point(crate::qmc::gray_code(k), &mut b).unwrap();
                assert_eq!(a, b);
            }
        }
    }
}
