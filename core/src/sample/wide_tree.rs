//! An 8-ary sum tree of `f64` weights, one cache line per node.
//!
//! The binary [`SumTree`](super::sum_tree::SumTree) walks one level per bit of the
//! index, and below its top levels every level is another cache line: 13 lines for
//! 8192 leaves. Here a node holds the sums of its eight children in one 64-byte
//! aligned line, so a draw or an update touches one line per three bits (5 for 8192
//! leaves). Direct simulation over size counts draws two leaves and moves three per
//! event on a tree of a few thousand sizes, where this halves the tree's share of
//! the time (see `docs/results/eventflow-samplers.md`).
//!
//! As in the binary tree, every sum is *recomputed* from its children, never
//! adjusted by a difference: no drift, and a tree after any sequence of updates is
//! bit-identical to one built from the same leaves. A leaf of weight zero is never
//! drawn.

use crate::error::{Error, Result};
use alloc::vec::Vec;
use rand_core::Rng;

/// Eight weights in one cache line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Line([f64; 8]);

/// The sum of a line, pairwise (the one order every sum uses: three dependent adds
/// where a left-to-right sum has seven).
#[inline]
fn line_sum(l: &Line) -> f64 {
    let w = &l.0;
    ((w[0] + w[1]) + (w[2] + w[3])) + ((w[4] + w[5]) + (w[6] + w[7]))
}

/// An 8-ary sum tree over `len` weights (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct WideTree {
    /// `levels[0]` is the leaves' lines, `levels[d][j].0[c]` the sum of line
    /// `8j + c` of `levels[d − 1]`; the last level has one line.
    levels: Vec<Vec<Line>>,
    len: usize,
}

impl WideTree {
    /// A tree over `weights` (each finite and `≥ 0`, with a finite total).
    pub(crate) fn from_weights(weights: &[f64]) -> Result<Self> {
        let mut leaves = Vec::new();
        leaves
            .try_reserve_exact(weights.len().div_ceil(8).max(1))
            .map_err(|_| Error::Overflow {
                name: "sum tree allocation",
            })?;
        leaves.resize(weights.len().div_ceil(8).max(1), Line::default());
        for (i, &w) in weights.iter().enumerate() {
            if !(w >= 0.0 && w.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "tree weight",
                    value: w,
                });
            }
            leaves[i / 8].0[i % 8] = w;
        }
        let mut t = WideTree {
            levels: alloc::vec![leaves],
            len: weights.len(),
        };
        while t.levels.last().map_or(0, Vec::len) > 1 {
            let below = t.levels.last().map_or(&[][..], |v| &v[..]);
            let mut up = alloc::vec![Line::default(); below.len().div_ceil(8)];
            for (j, l) in below.iter().enumerate() {
                up[j / 8].0[j % 8] = line_sum(l);
            }
            t.levels.push(up);
        }
        if !t.total().is_finite() {
            return Err(Error::Overflow { name: "tree total" });
        }
        Ok(t)
    }

    /// The sum of all weights.
    #[inline]
    pub(crate) fn total(&self) -> f64 {
        self.levels.last().map_or(0.0, |top| line_sum(&top[0]))
    }

    /// Extends to `n ≥ len` leaves, the new ones of weight zero (rebuilds the tree:
    /// O(n), the same bits as a fresh build).
    pub(crate) fn resize_zero(&mut self, n: usize) -> Result<()> {
        let mut w = Vec::new();
        w.try_reserve_exact(n.max(self.len))
            .map_err(|_| Error::Overflow {
                name: "sum tree allocation",
            })?;
        w.extend(self.levels[0].iter().flat_map(|l| l.0).take(self.len));
        w.resize(n.max(self.len), 0.0);
        *self = WideTree::from_weights(&w)?;
        Ok(())
    }

    /// Sets the weights of several leaves (later entries win where an index repeats);
    /// on error (an index out of range, an invalid weight, a total that could
    /// overflow) the tree is unchanged.
    pub(crate) fn update_many<const K: usize>(&mut self, leaves: [(usize, f64); K]) -> Result<()> {
        let mut bound = self.total();
        for &(i, w) in &leaves {
            if i >= self.len {
                return Err(Error::IndexOutOfRange {
                    name: "leaf",
                    index: i as u64,
                    limit: self.len as u64,
                });
            }
            if !(w >= 0.0 && w.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "tree weight",
                    value: w,
                });
            }
            bound += w;
        }
        if !bound.is_finite() {
            return Err(Error::Overflow { name: "tree total" });
        }
        let mut idx = [0usize; K];
        for (x, &(i, w)) in idx.iter_mut().zip(&leaves) {
            self.levels[0][i / 8].0[i % 8] = w;
            *x = i / 8;
        }
        for d in 1..self.levels.len() {
            let (lo, hi) = self.levels.split_at_mut(d);
            let (below, up) = (&lo[d - 1], &mut hi[0]);
            for p in 0..K {
                let x = idx[p];
                // paths that met below share the rest of the way: sum a line once
                if !idx[..p].contains(&x) {
                    up[x / 8].0[x % 8] = line_sum(&below[x]);
                }
            }
            for x in &mut idx {
                *x /= 8;
            }
        }
        Ok(())
    }

    /// Two independent draws with probability `w_i / total` (two uniforms, the first
    /// for the first leaf); the descents are interleaved.
    pub(crate) fn sample_pair_rng<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<(usize, usize)> {
        let total = self.total();
        if total.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return Err(Error::Empty);
        }
        let mut u = [
            total * super::sum_tree::unit_f64(rng.next_u64()),
            total * super::sum_tree::unit_f64(rng.next_u64()),
        ];
        let mut j = [0usize; 2];
        for level in self.levels.iter().rev() {
            for (j, u) in j.iter_mut().zip(&mut u) {
                let c = pick(&level[*j], u);
                *j = 8 * *j + c;
            }
        }
        Ok((j[0], j[1]))
    }
}

/// The child `c` of a line with `Σ_{i<c} w_i ≤ u < Σ_{i≤c} w_i`, `u` reduced by the
/// weights before it; zero weights are skipped, and a `u` at or past the line's sum
/// (rounding) gives the last positive child.
#[inline]
fn pick(l: &Line, u: &mut f64) -> usize {
    let mut last = 0;
    for (c, &w) in l.0.iter().enumerate() {
        if w > 0.0 {
            if *u < w {
                return c;
            }
            *u -= w;
            last = c;
        }
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_pcg::Pcg64Mcg;
    use rand_pcg::rand_core::SeedableRng;

    fn weights(n: usize, seed: u64) -> Vec<f64> {
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let u = crate::random::unit_f64(rng.next_u64());
                // a third of the leaves empty, the rest spread over six decades
                if i % 3 == 1 {
                    0.0
                } else {
                    libm::pow(10.0, 6.0 * u - 3.0)
                }
            })
            .collect()
    }

    #[test]
    fn totals_and_updates_match_a_fresh_build() {
        for n in [1usize, 7, 8, 9, 64, 65, 513, 5000] {
            let w = weights(n, n as u64);
            let mut t = WideTree::from_weights(&w).unwrap();
            let exact: f64 = w.iter().sum();
            approx::assert_relative_eq!(t.total(), exact, max_relative = 1e-12);
            let mut w2 = w.clone();
            let mut rng = Pcg64Mcg::seed_from_u64(3);
            for step in 0..2000 {
                let i = crate::random::below(&mut rng, n as u64) as usize;
                let j = crate::random::below(&mut rng, n as u64) as usize;
                let x = if step % 5 == 0 {
                    0.0
                } else {
                    step as f64 * 0.37
                };
                w2[i] = x;
                w2[j] = x + 1.0;
                t.update_many([(i, x), (j, x + 1.0)]).unwrap();
            }
            let fresh = WideTree::from_weights(&w2).unwrap();
            assert_eq!(t.total().to_bits(), fresh.total().to_bits(), "n = {n}");
            for (a, b) in t.levels.iter().zip(&fresh.levels) {
                for (x, y) in a.iter().zip(b) {
                    for (p, q) in x.0.iter().zip(&y.0) {
                        assert_eq!(p.to_bits(), q.to_bits());
                    }
                }
            }
        }
    }

    #[test]
    fn draws_follow_the_weights_and_skip_empty_leaves() {
        // the same frequencies as the binary tree's (itself chi-square tested), and
        // never an empty leaf: a chi-square of the draws against the weights
        let n = 300;
        let w = weights(n, 11);
        let t = WideTree::from_weights(&w).unwrap();
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        let draws = 400_000;
        let mut hits = alloc::vec![0u64; n];
        for _ in 0..draws / 2 {
            let (a, b) = t.sample_pair_rng(&mut rng).unwrap();
            hits[a] += 1;
            hits[b] += 1;
        }
        let total: f64 = w.iter().sum();
        let (mut chi2, mut cells) = (0.0, 0);
        for (h, &wi) in hits.iter().zip(&w) {
            if wi == 0.0 {
                assert_eq!(*h, 0, "an empty leaf was drawn");
                continue;
            }
            let e = draws as f64 * wi / total;
            if e >= 5.0 {
                chi2 += (*h as f64 - e) * (*h as f64 - e) / e;
                cells += 1;
            }
        }
        // chi-square with `cells − 1` degrees of freedom: mean d, sd √(2d); 6 sd is
        // a false alarm below 1e-6, and a weight off by a factor of 2 in one leaf of
        // expectation ≥ 5 adds ≥ 2.5 per such leaf, across many leaves far more
        let d = (cells - 1) as f64;
        assert!(
            chi2 < d + 6.0 * libm::sqrt(2.0 * d),
            "chi2 {chi2} with {d} dof"
        );
    }

    #[test]
    fn rounding_at_the_top_gives_the_last_positive_leaf() {
        let t = WideTree::from_weights(&[0.0, 2.0, 0.0, 1.0, 0.0]).unwrap();
        let mut u = 3.0; // = the total: past every leaf
        let c = pick(&t.levels[0][0], &mut u);
        assert_eq!(c, 3);
    }

    #[test]
    fn bad_weights_and_indices_are_refused_and_change_nothing() {
        let mut t = WideTree::from_weights(&[1.0, 2.0, 3.0]).unwrap();
        assert!(t.update_many([(3, 1.0)]).is_err());
        assert!(t.update_many([(0, 5.0), (1, f64::NAN)]).is_err());
        assert!(t.update_many([(0, f64::MAX), (1, f64::MAX)]).is_err());
        assert_eq!(t.total(), 6.0);
        assert!(WideTree::from_weights(&[-1.0]).is_err());
        assert!(
            WideTree::from_weights(&[0.0, 0.0])
                .unwrap()
                .sample_pair_rng(&mut Pcg64Mcg::seed_from_u64(1))
                .is_err()
        );
    }
}
