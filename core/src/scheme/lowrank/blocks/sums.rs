//! A 4-ary sum tree over the blocks' intensities (a wider node than binary shortens the
//! chain of dependent loads on a descent; `docs/design/block-majorants.md`). The levels
//! lie in one vector, leaves first, each padded with zeros to a multiple of four, so a
//! descent reads four children without a bound check and picks one without a branch. A
//! node is the sum of its four children, recomputed from them on every change, so sums
//! never drift and a rebuild from the leaves gives the same bits as the updates that
//! led to them.

use crate::error::Result;
use crate::memory::try_reserve;
use alloc::vec::Vec;

#[derive(Clone, Debug)]
pub(crate) struct QuadSums {
    /// Every level, leaves first; the last level is the root alone (padded).
    nodes: Vec<f64>,
    /// Where each level starts in `nodes`.
    starts: Vec<usize>,
    /// The number of leaves (before padding).
    len: usize,
}

/// The sum of four children in one fixed order.
#[inline]
fn sum4(v: &[f64]) -> f64 {
    (v[0] + v[1]) + (v[2] + v[3])
}

impl QuadSums {
    /// Bytes for `n` leaves (at most a third more above them, and the padding).
    pub fn bytes(n: usize) -> Option<usize> {
        n.checked_add(3)?
            .checked_mul(8)?
            .checked_mul(4)?
            .checked_div(3)?
            .checked_add(64 * 32)
    }

    /// The tree over `leaves`.
    pub fn new(leaves: &[f64]) -> Result<QuadSums> {
        let len = leaves.len();
        let mut sizes = Vec::new();
        let mut n = len.max(1);
        loop {
            let padded = n.div_ceil(4) * 4;
            sizes.push(padded);
            if n == 1 {
                break;
            }
            n = padded / 4;
        }
        let mut nodes = Vec::new();
        try_reserve(&mut nodes, sizes.iter().sum())?;
        let mut starts = Vec::new();
        try_reserve(&mut starts, sizes.len())?;
        nodes.extend_from_slice(leaves);
        nodes.resize(sizes[0], 0.0);
        starts.push(0);
        for l in 1..sizes.len() {
            let below = starts[l - 1];
            starts.push(nodes.len());
            for p in 0..sizes[l - 1] / 4 {
                let s = sum4(&nodes[below + 4 * p..below + 4 * p + 4]);
                nodes.push(s);
            }
            let end = starts[l] + sizes[l];
            nodes.resize(end, 0.0);
        }
        Ok(QuadSums { nodes, starts, len })
    }

    /// The total.
    #[inline]
    pub fn total(&self) -> f64 {
        self.nodes[self.starts[self.starts.len() - 1]]
    }

    /// Leaf `i` (0 for a padding leaf).
    #[inline]
    pub fn leaf(&self, i: usize) -> f64 {
        self.nodes[i]
    }

    pub fn leaves(&self) -> &[f64] {
        &self.nodes[..self.len]
    }

    /// Sets leaf `i < len` and the sums above it.
    #[inline]
    pub fn set(&mut self, i: usize, v: f64) {
        self.nodes[i] = v;
        let mut i = i;
        for l in 1..self.starts.len() {
            let p = i / 4;
            let below = self.starts[l - 1] + 4 * p;
            let s = sum4(&self.nodes[below..below + 4]);
            self.nodes[self.starts[l] + p] = s;
            i = p;
        }
    }

    /// Multiplies every node by `f` (a power of two: exact).
    pub fn scale(&mut self, f: f64) {
        for v in &mut self.nodes {
            *v *= f;
        }
    }

    /// The leaf where `u ∈ [0, total)` falls: at each node the child whose prefix sums
    /// enclose u. Rounding past a node's end lands on its last child, which may be a
    /// zero leaf or padding: a padding node (of any level) ends the descent at `len`,
    /// a ghost the caller rejects, and a zero leaf is rejected by its thinning.
    #[inline]
    pub fn find(&self, mut u: f64) -> usize {
        let mut i = 0usize;
        for l in (0..self.starts.len() - 1).rev() {
            let at = self.starts[l] + 4 * i;
            let v = &self.nodes[at..at + 4];
            let c0 = v[0];
            let c1 = c0 + v[1];
            let c2 = c1 + v[2];
            let k = usize::from(u >= c0) + usize::from(u >= c1) + usize::from(u >= c2);
            u -= [0.0, c0, c1, c2][k];
            i = 4 * i + k;
            // the real nodes of level l: the leaves, or a quarter of the level below
            let real = if l == 0 {
                self.len
            } else {
                (self.starts[l] - self.starts[l - 1]) / 4
            };
            if i >= real {
                return self.len;
            }
        }
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rounding at the top of the range never leaves the tree: with the mass at the two
    /// ends of a tree whose last internal node is padded, `u` just below the total could
    /// walk into a padding node and on past the vector (an independent review found it
    /// with 298 leaves); now it ends at a real leaf or at the ghost index `len`.
    #[test]
    fn rounding_past_the_end_stays_in_the_tree() {
        for n in [5usize, 17, 70, 298, 1000, 4097] {
            for (a, b) in [(0.990_71, 1.009_29), (1.0, 1.0), (1e-300, 3.0), (0.5, 0.0)] {
                let mut leaves = alloc::vec![0.0; n];
                leaves[0] = a;
                leaves[n - 1] = b;
                let t = QuadSums::new(&leaves).unwrap();
                for u in [
                    t.total(),
                    t.total() * (1.0 - f64::EPSILON / 2.0),
                    f64::from_bits(t.total().to_bits() - 1),
                    0.0,
                ] {
                    let i = t.find(u);
                    assert!(i <= n, "{n} {a} {b} {u}: {i}");
                    if i < n && u < t.total() {
                        assert!(leaves[i] > 0.0 || i == n - 1, "{n}: {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn sums_and_descents() {
        for n in [1usize, 2, 5, 16, 17, 70] {
            let leaves: Vec<f64> = (0..n).map(|i| (i % 3) as f64).collect();
            let mut t = QuadSums::new(&leaves).unwrap();
            let total: f64 = leaves.iter().sum();
            assert_eq!(t.total(), total);
            // every leaf found at the start of its range and inside it
            let mut acc = 0.0;
            for (i, &w) in leaves.iter().enumerate() {
                if w > 0.0 {
                    assert_eq!(t.find(acc), i);
                    assert_eq!(t.find(acc + w * 0.5), i);
                }
                acc += w;
            }
            t.set(n - 1, 10.0);
            let mut again = leaves.clone();
            again[n - 1] = 10.0;
            let fresh = QuadSums::new(&again).unwrap();
            assert_eq!(t.total().to_bits(), fresh.total().to_bits());
            assert_eq!(t.leaves(), fresh.leaves());
            t.scale(4.0);
            assert_eq!(t.total(), 4.0 * fresh.total());
        }
    }
}
