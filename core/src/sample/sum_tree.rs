//! A flat-array sum (segment) tree for weighted sampling.
//!
//! Leaves hold non-negative weights `w_0, ..., w_{n−1}`; every internal node holds the sum
//! of its two children, so the root is the total. Sampling descends from the root with a
//! uniform `u ∈ [0, total)`; an update rewrites one leaf and recomputes the sums on its
//! path, both in O(log n). The layout is the classic implicit heap: node 1 is the root,
//! node `i` has children `2i` and `2i + 1`, leaves sit at `capacity + index`.
//!
//! **No drift.** An update *recomputes* each ancestor as the sum of its two children
//! instead of adding a difference, so every node is always exactly the floating-point sum
//! of its children: the tree after a million updates is bit-identical to a tree built
//! afresh from the same leaves. For integer weights ([`u64`]) everything is exact, and
//! an update that would overflow the total is refused.
//!
//! Modelled on `rand_distr`'s `WeightedTreeIndex`; used by the event-driven schemes
//! (Eibeck & Wagner 2000; Osinsky 2023).
//!
//! # Example
//! ```
//! use coagula_core::tree::SumTree;
//! let mut t = SumTree::from_weights(&[1u64, 0, 3]).unwrap();
//! assert_eq!(t.total(), 4);
//! assert_eq!(t.sample(0).unwrap(), 0);
//! assert_eq!(t.sample(1).unwrap(), 2); // index 1 has weight 0: never drawn
//! t.update(1, 5).unwrap();
//! assert_eq!(t.sample(1).unwrap(), 1);
//! let mut rng = rand_pcg::Pcg64::new(1, 1);
//! let i = t.sample_rng(&mut rng).unwrap();
//! assert!(i < 3);
//! ```

use crate::error::{Error, Result};
use alloc::vec;
use alloc::vec::Vec;
use core::fmt::Debug;
use rand_core::Rng;

/// A weight type of [`SumTree`]: `u64` (exact) or `f64`.
pub trait Weight: Copy + PartialOrd + Debug + Default {
    /// The zero weight.
    const ZERO: Self;
    /// Checks that a weight is admissible (finite and non-negative for floats).
    fn validate(self) -> Result<Self>;
    /// Sum of two weights; `None` on overflow.
    fn add(self, other: Self) -> Option<Self>;
    /// `self − other`, assuming `other ≤ self`.
    fn sub(self, other: Self) -> Self;
    /// A uniform draw from `[0, bound)`, `bound > 0`.
    fn uniform_below<R: Rng + ?Sized>(rng: &mut R, bound: Self) -> Self;
}

impl Weight for u64 {
    const ZERO: Self = 0;
    fn validate(self) -> Result<Self> {
        Ok(self)
    }
    fn add(self, other: Self) -> Option<Self> {
        self.checked_add(other)
    }
    fn sub(self, other: Self) -> Self {
        self - other
    }
    /// Lemire's multiply-and-reject method: exactly uniform.
    fn uniform_below<R: Rng + ?Sized>(rng: &mut R, bound: Self) -> Self {
        crate::random::below(rng, bound)
    }
}

impl Weight for f64 {
    const ZERO: Self = 0.0;
    fn validate(self) -> Result<Self> {
        if self.is_finite() && self >= 0.0 {
            Ok(self)
        } else {
            Err(Error::InvalidRate {
                name: "tree weight",
                value: self,
            })
        }
    }
    fn add(self, other: Self) -> Option<Self> {
        let s = self + other;
        s.is_finite().then_some(s)
    }
    fn sub(self, other: Self) -> Self {
        self - other
    }
    fn uniform_below<R: Rng + ?Sized>(rng: &mut R, bound: Self) -> Self {
        bound * unit_f64(rng.next_u64())
    }
}

pub use crate::random::unit_f64;

/// A sum tree over weights of type `W` (`u64` or `f64`). See the module docs.
#[derive(Clone)]
pub struct SumTree<W: Weight> {
    /// `nodes[1]` is the root; leaves at `cap..cap + len`; `nodes[0]` unused.
    nodes: Vec<W>,
    cap: usize,
    len: usize,
}

impl<W: Weight> Debug for SumTree<W> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SumTree")
            .field("len", &self.len)
            .field("total", &self.total())
            .finish_non_exhaustive()
    }
}

impl<W: Weight> Default for SumTree<W> {
    fn default() -> Self {
        Self::new()
    }
}

impl<W: Weight> SumTree<W> {
    /// An empty tree.
    pub fn new() -> Self {
        Self::with_capacity(1)
    }

    /// An empty tree with room for `n` leaves before it must grow.
    pub fn with_capacity(n: usize) -> Self {
        let cap = n.max(1).next_power_of_two();
        SumTree {
            nodes: vec![W::ZERO; 2 * cap],
            cap,
            len: 0,
        }
    }

    /// A tree over `weights`. Errors on a negative or non-finite weight, or an overflow.
    pub fn from_weights(weights: &[W]) -> Result<Self> {
        let mut t = Self::with_capacity(weights.len());
        for (i, &w) in weights.iter().enumerate() {
            t.nodes[t.cap + i] = w.validate()?;
        }
        t.len = weights.len();
        t.rebuild()?;
        Ok(t)
    }

    /// Recomputes every internal node from the leaves (O(capacity)).
    fn rebuild(&mut self) -> Result<()> {
        for i in (1..self.cap).rev() {
            self.nodes[i] = self.nodes[2 * i]
                .add(self.nodes[2 * i + 1])
                .ok_or(Error::Overflow { name: "tree total" })?;
        }
        Ok(())
    }

    /// Number of leaves.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no leaves.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Leaves that fit before the next doubling.
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// The sum of all weights.
    pub fn total(&self) -> W {
        self.nodes[1]
    }

    /// The weight of leaf `i`, or `None` past the end.
    pub fn get(&self, i: usize) -> Option<W> {
        (i < self.len).then(|| self.nodes[self.cap + i])
    }

    /// The weights of all leaves, in order.
    pub fn weights(&self) -> &[W] {
        &self.nodes[self.cap..self.cap + self.len]
    }

    /// Sets the weight of leaf `i`. On error (index out of range, invalid weight, total
    /// overflow) the tree is unchanged.
    pub fn update(&mut self, i: usize, w: W) -> Result<()> {
        if i >= self.len {
            return Err(Error::IndexOutOfRange {
                name: "leaf",
                index: i as u64,
                limit: self.len as u64,
            });
        }
        let w = w.validate()?;
        let old = self.nodes[self.cap + i];
        // every partial sum is bounded by the new total, so checking it suffices
        if self.total().sub(old).add(w).is_none() {
            return Err(Error::Overflow { name: "tree total" });
        }
        self.set_leaf_unchecked(i, w);
        Ok(())
    }

    /// Writes leaf `i` and recomputes its ancestors. The caller guarantees `i < len`,
    /// `w` valid and no overflow.
    #[inline]
    fn set_leaf_unchecked(&mut self, i: usize, w: W) {
        let mut node = self.cap + i;
        self.nodes[node] = w;
        // the running sum stays in a register: each level loads only the sibling,
        // never the node just stored (no store-to-load chain); the sums are the
        // same bits as `left + right` (addition commutes exactly)
        let mut sum = w;
        while node > 1 {
            let sibling = self.nodes[node ^ 1];
            let (l, r) = if node & 1 == 0 {
                (sum, sibling)
            } else {
                (sibling, sum)
            };
            sum = l.add(r).unwrap_or(l);
            node >>= 1;
            self.nodes[node] = sum;
        }
    }

    /// Appends a leaf, doubling the capacity when full (the only allocation).
    pub fn push(&mut self, w: W) -> Result<()> {
        let w = w.validate()?;
        if self.total().add(w).is_none() {
            return Err(Error::Overflow { name: "tree total" });
        }
        if self.len == self.cap {
            self.grow(2 * self.cap);
        }
        self.len += 1;
        self.set_leaf_unchecked(self.len - 1, w);
        Ok(())
    }

    /// Removes and returns the last leaf.
    pub fn pop(&mut self) -> Option<W> {
        if self.len == 0 {
            return None;
        }
        let w = self.nodes[self.cap + self.len - 1];
        self.set_leaf_unchecked(self.len - 1, W::ZERO);
        self.len -= 1;
        Some(w)
    }

    /// Extends to `n` leaves (new leaves have weight zero), growing by doubling.
    pub fn resize_zero(&mut self, n: usize) {
        if n > self.cap {
            self.grow(n.next_power_of_two());
        }
        if n < self.len {
            for i in n..self.len {
                self.set_leaf_unchecked(i, W::ZERO);
            }
        }
        self.len = n;
    }

    fn grow(&mut self, new_cap: usize) {
        let mut nodes = vec![W::ZERO; 2 * new_cap];
        nodes[new_cap..new_cap + self.len]
            .copy_from_slice(&self.nodes[self.cap..self.cap + self.len]);
        self.nodes = nodes;
        self.cap = new_cap;
        // sums of the old tree were valid, so no overflow is possible
        let _ = self.rebuild();
    }

    /// The leaf `i` with `Σ_{j<i} w_j ≤ u < Σ_{j≤i} w_j`, for `0 ≤ u < total`. A leaf of
    /// weight zero is never returned; a `u ≥ total` (from rounding) yields the last leaf
    /// of positive weight. Errors when the total is zero.
    pub fn sample(&self, mut u: W) -> Result<usize> {
        if self.total() <= W::ZERO {
            return Err(Error::Empty);
        }
        let mut node = 1;
        while node < self.cap {
            let left = self.nodes[2 * node];
            let right = self.nodes[2 * node + 1];
            // branch-free step (a random descent mispredicts half its branches)
            let go_right = !(u < left || right <= W::ZERO);
            u = if go_right { u.sub(left) } else { u };
            node = 2 * node + go_right as usize;
        }
        Ok(node - self.cap)
    }

    /// Draws a leaf with probability `w_i / total` using the caller's RNG.
    pub fn sample_rng<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<usize> {
        let total = self.total();
        if total <= W::ZERO {
            return Err(Error::Empty);
        }
        self.sample(W::uniform_below(rng, total))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::{prop, prop_assert_eq, proptest};
    use rand_pcg::Pcg64;

    fn linear_scan(w: &[u64], u: u64) -> usize {
        let mut acc = 0;
        for (i, &x) in w.iter().enumerate() {
            acc += x;
            if u < acc {
                return i;
            }
        }
        unreachable!("u beyond total")
    }

    proptest! {
        #[test]
        fn sampling_matches_linear_scan(
            weights in prop::collection::vec(0u64..1000, 1..200),
            updates in prop::collection::vec((0usize..200, 0u64..1000), 0..50),
            probes in prop::collection::vec(0u64..u64::MAX, 1..50),
        ) {
            let mut w = weights.clone();
            let mut t = SumTree::from_weights(&weights).unwrap();
            for (i, x) in updates {
                let i = i % w.len();
                w[i] = x;
                t.update(i, x).unwrap();
            }
            let total: u64 = w.iter().sum();
            prop_assert_eq!(t.total(), total);
            prop_assert_eq!(t.weights(), &w[..]);
            if total > 0 {
                for p in probes {
                    let u = p % total;
                    prop_assert_eq!(t.sample(u).unwrap(), linear_scan(&w, u));
                }
            } else {
                prop_assert_eq!(t.sample(0), Err(Error::Empty));
            }
        }

        #[test]
        fn float_tree_matches_integer_tree(
            weights in prop::collection::vec(0u32..1000, 1..100),
            probes in prop::collection::vec(0u64..u64::MAX, 1..50),
        ) {
            // integer-valued doubles add exactly, so both trees must agree everywhere
            let wi: Vec<u64> = weights.iter().map(|&x| u64::from(x)).collect();
            let wf: Vec<f64> = weights.iter().map(|&x| f64::from(x)).collect();
            let ti = SumTree::from_weights(&wi).unwrap();
            let tf = SumTree::from_weights(&wf).unwrap();
            prop_assert_eq!(ti.total() as f64, tf.total());
            if ti.total() > 0 {
                for p in probes {
                    let u = p % ti.total();
                    prop_assert_eq!(ti.sample(u).unwrap(), tf.sample(u as f64).unwrap());
                }
            }
        }

        #[test]
        fn push_pop_resize_keep_sums(
            weights in prop::collection::vec(0u64..1000, 0..70),
            n in 0usize..100,
        ) {
            let mut t = SumTree::new();
            for &w in &weights {
                t.push(w).unwrap();
            }
            prop_assert_eq!(t.total(), weights.iter().sum::<u64>());
            t.resize_zero(n);
            let kept: u64 = weights.iter().take(n).sum();
            prop_assert_eq!(t.total(), kept);
            prop_assert_eq!(t.len(), n);
            let mut rest = kept;
            while let Some(w) = t.pop() {
                rest -= w;
                prop_assert_eq!(t.total(), rest);
            }
        }
    }

    #[test]
    fn zero_weight_leaves_are_never_sampled_even_at_rounding_edges() {
        let t = SumTree::from_weights(&[0.1, 0.2, 0.0, 0.0]).unwrap();
        assert_eq!(t.sample(t.total()).unwrap(), 1);
        assert_eq!(t.sample(f64::MAX).unwrap(), 1);
        assert_eq!(t.sample(0.0).unwrap(), 0);
        let t = SumTree::from_weights(&[0.0, 0.0, 0.0, 0.3]).unwrap();
        assert_eq!(t.sample(0.0).unwrap(), 3);
    }

    #[test]
    fn invalid_input_is_refused_and_leaves_the_tree_unchanged() {
        assert!(SumTree::from_weights(&[1.0, f64::NAN]).is_err());
        assert!(SumTree::from_weights(&[-1.0]).is_err());
        let mut t = SumTree::from_weights(&[1.0, 2.0]).unwrap();
        assert!(t.update(0, -3.0).is_err());
        assert!(t.update(0, f64::INFINITY).is_err());
        assert!(t.update(2, 1.0).is_err());
        assert_eq!(t.weights(), &[1.0, 2.0]);
        let mut t = SumTree::from_weights(&[u64::MAX - 1, 0]).unwrap();
        assert_eq!(t.update(1, 2), Err(Error::Overflow { name: "tree total" }));
        assert_eq!(t.weights(), &[u64::MAX - 1, 0]);
        assert!(t.push(5).is_err());
        assert_eq!(t.len(), 2);
        assert!(SumTree::from_weights(&[u64::MAX, 1]).is_err());
        let empty: SumTree<f64> = SumTree::new();
        let mut rng = Pcg64::new(7, 7);
        assert_eq!(empty.sample_rng(&mut rng), Err(Error::Empty));
    }

    /// 1e7 random updates of a float tree: the total must stay bit-identical to a tree
    /// rebuilt from the same leaves, and within rounding of an exact (integer) sum.
    #[test]
    fn ten_million_updates_do_not_drift() {
        let n = 1000;
        let mut rng = Pcg64::new(0xC0A6, 0x5EED);
        let mut t = SumTree::from_weights(&vec![0.0f64; n]).unwrap();
        // weights are multiples of 2^-20 below 2^20, so an exact integer mirror exists
        let mut exact: Vec<u64> = vec![0; n];
        for _ in 0..10_000_000 {
            let i = (rng.next_u64() % n as u64) as usize;
            let q = rng.next_u64() >> 24; // < 2^40
            exact[i] = q;
            t.update(i, q as f64 * libm::ldexp(1.0, -20)).unwrap();
        }
        let rebuilt = SumTree::from_weights(t.weights()).unwrap();
        assert_eq!(t.total().to_bits(), rebuilt.total().to_bits());
        let exact_total: u64 = exact.iter().sum();
        let exact_total = exact_total as f64 * libm::ldexp(1.0, -20);
        let rel = (t.total() - exact_total).abs() / exact_total;
        assert!(rel < 1e-13, "relative drift {rel:e}");
    }

    /// Chi-square test of sampling frequencies against the weights. The threshold is
    /// the 1 − 1e-6 quantile of χ²(df) (Wilson–Hilferty), so a correct sampler fails
    /// with probability 1e-6 for a given seed, and a wrong one (e.g. off by one leaf or
    /// a factor 2 in a weight) fails with certainty at this sample size.
    #[test]
    fn sampling_frequencies_pass_chi_square() {
        let mut rng = Pcg64::new(42, 54);
        let weights: Vec<f64> = (0..37)
            .map(|i| {
                if i % 5 == 3 {
                    0.0
                } else {
                    1.0 + (i * 7 % 11) as f64
                }
            })
            .collect();
        let t = SumTree::from_weights(&weights).unwrap();
        let ti =
            SumTree::from_weights(&weights.iter().map(|&w| w as u64).collect::<Vec<_>>()).unwrap();
        let draws = 2_000_000usize;
        for integer in [false, true] {
            let mut counts = vec![0usize; weights.len()];
            for _ in 0..draws {
                let i = if integer {
                    ti.sample_rng(&mut rng)
                } else {
                    t.sample_rng(&mut rng)
                }
                .unwrap();
                counts[i] += 1;
            }
            let (chi2, df) = chi_square(&counts, &weights);
            let z = 4.753; // standard normal 1 − 1e-6 quantile
            let a = 2.0 / (9.0 * df as f64);
            let crit = df as f64 * libm::pow(1.0 - a + z * libm::sqrt(a), 3.0);
            assert!(chi2 < crit, "chi2 = {chi2} with {df} df exceeds {crit}");
            for (c, w) in counts.iter().zip(&weights) {
                if *w == 0.0 {
                    assert_eq!(*c, 0);
                }
            }
        }
    }

    fn chi_square(counts: &[usize], weights: &[f64]) -> (f64, usize) {
        let n: usize = counts.iter().sum();
        let total: f64 = weights.iter().sum();
        let mut chi2 = 0.0;
        let mut df = 0;
        for (&c, &w) in counts.iter().zip(weights) {
            if w > 0.0 {
                let e = n as f64 * w / total;
                chi2 += (c as f64 - e) * (c as f64 - e) / e;
                df += 1;
            }
        }
        (chi2, df - 1)
    }

    #[test]
    fn integer_uniform_is_unbiased_at_small_bounds() {
        let mut rng = Pcg64::new(3, 9);
        let mut counts = [0usize; 3];
        for _ in 0..300_000 {
            counts[u64::uniform_below(&mut rng, 3) as usize] += 1;
        }
        let (chi2, _) = chi_square(&counts, &[1.0, 1.0, 1.0]);
        assert!(chi2 < 27.6, "chi2 {chi2}"); // χ²(2) at 1 − 1e-6
    }
}
