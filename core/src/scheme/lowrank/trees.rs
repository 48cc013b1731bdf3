//! The proposal trees of low-rank Monte Carlo: one structure holds, for every size, all
//! 2R weights `u^k_i = a_k(i) N_i` and `v^k_i = b_k(i) N_i`, and samples a size by
//! descending one of them.
//!
//! Two layouts, measured against each other by `coagula bench lowrank --tree`:
//! * [`BinaryTree`] — a binary segment tree whose nodes hold all 2R partial sums; an
//!   update recomputes each ancestor from its two children (no drift, ever).
//! * [`WideTree`] — an 8-ary tree whose nodes hold, per component, the sums of their 8
//!   children in one 64-byte cache line. A descent reads one line per level, forms the
//!   running sums in a depth-3 tree of additions and picks the child by 8 independent
//!   comparisons (log₈ M dependent loads instead of log₂ M); an update adds the change
//!   to one entry per component and level. (Storing running sums instead makes the
//!   descent cheaper but an update 8 times dearer; a collision makes 3 updates of 2R
//!   rows against 2 descents of one row, and that layout measured slower.) Updates
//!   add differences, so rounding can accumulate:
//!   the tree is rebuilt from the exact integer counts every `REBUILD` updates, which
//!   bounds the relative drift of any partial sum by about `REBUILD · 2⁻⁵³ ≈ 2e-10`. A
//!   size whose count is zero can then carry a ghost weight of that order; the scheme
//!   rejects a proposal that lands on it, which is exact thinning.

use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use alloc::vec::Vec;

/// Per-size weights: `[0][k] = u^k_i`, `[1][k] = v^k_i`.
pub type Weights<const R: usize> = [[f64; R]; 2];

/// A proposal tree over `m` sizes (m a power of two ≥ 8).
pub trait ProposalTree<const R: usize>: Sized {
    /// Builds the tree over `m` leaves with `leaf(i)` the weights of index i; a failed
    /// allocation is [`Error::Capacity`].
    fn build(m: usize, leaf: impl Fn(usize) -> Weights<R>) -> Result<Self>;
    /// Recomputes every node from `leaf` in place (same leaf count; no allocation).
    fn refill(&mut self, leaf: impl Fn(usize) -> Weights<R>);
    /// Bytes of a tree over `m` leaves (`None` on overflow).
    fn bytes(m: usize) -> Option<usize>;
    /// Totals of every component.
    fn totals(&self) -> Weights<R>;
    /// Leaf index found by descending component `k` of part `p` with `target ∈ [0, total)`.
    fn descend(&self, p: usize, k: usize, target: f64) -> usize;
    /// Two descents at once: component `k` of u with `tu` and of v with `tv`. Layouts
    /// may interleave them so that the two chains of dependent loads overlap.
    #[inline]
    fn descend_pair(&self, k: usize, tu: f64, tv: f64) -> (usize, usize) {
        (self.descend(0, k, tu), self.descend(1, k, tv))
    }
    /// Whether [`add`](Self::add) needs the leaf's new exact value (layouts that
    /// recompute from children); others only add the difference, and the caller skips
    /// computing the leaf.
    const NEEDS_LEAF: bool;
    /// Adds `delta` to the weights of leaf `i`, whose new exact value is `leaf` (only
    /// meaningful when [`NEEDS_LEAF`](Self::NEEDS_LEAF)).
    fn add(&mut self, i: usize, delta: &Weights<R>, leaf: &Weights<R>);

    /// Doubles every weight (exact in floating point).
    fn double(&mut self);
    /// True when the tree has drifted enough to want a rebuild.
    fn wants_rebuild(&self) -> bool {
        false
    }
    /// Every stored weight, in a fixed order (for comparing a restored tree with one
    /// rebuilt from the counts).
    fn values(&self) -> Vec<f64>;
    /// Writes the exact contents (for a bit-identical restore).
    fn save(&self, w: &mut Writer);
    /// Reads contents written by [`save`](Self::save) for a tree over `m` leaves.
    fn load(m: usize, r: &mut Reader) -> Result<Self>;
}

fn bad_tree() -> Error {
    Error::Checkpoint {
        what: "tree contents do not match the sizes",
    }
}

/// Binary segment tree with recomputed ancestors.
#[derive(Clone, Debug)]
pub struct BinaryTree<const R: usize> {
    nodes: Vec<Weights<R>>,
    m: usize,
}

#[inline]
fn add<const R: usize>(a: &Weights<R>, b: &Weights<R>) -> Weights<R> {
    let mut out = [[0.0; R]; 2];
    for p in 0..2 {
        for k in 0..R {
            out[p][k] = a[p][k] + b[p][k];
        }
    }
    out
}

impl<const R: usize> ProposalTree<R> for BinaryTree<R> {
    const NEEDS_LEAF: bool = true;

    fn build(m: usize, leaf: impl Fn(usize) -> Weights<R>) -> Result<Self> {
        let mut nodes = Vec::new();
        crate::scheme::population::try_resize(&mut nodes, 2 * m, [[0.0; R]; 2])?;
        let mut t = BinaryTree { nodes, m };
        t.refill(leaf);
        Ok(t)
    }

    fn refill(&mut self, leaf: impl Fn(usize) -> Weights<R>) {
        let m = self.m;
        for i in 0..m {
            self.nodes[m + i] = leaf(i);
        }
        for n in (1..m).rev() {
            self.nodes[n] = add(&self.nodes[2 * n], &self.nodes[2 * n + 1]);
        }
    }

    fn bytes(m: usize) -> Option<usize> {
        m.checked_mul(2 * core::mem::size_of::<Weights<R>>())
    }

    #[inline]
    fn totals(&self) -> Weights<R> {
        self.nodes[1]
    }

    #[inline(never)]
    fn descend(&self, p: usize, k: usize, mut target: f64) -> usize {
        let mut node = 1;
        while node < self.m {
            let left = self.nodes[2 * node][p][k];
            let right = self.nodes[2 * node + 1][p][k];
            // branch-free; never step into a zero-weight subtree
            let go_right = (target >= left) & (right > 0.0);
            target -= if go_right { left } else { 0.0 };
            node = 2 * node + usize::from(go_right);
        }
        node - self.m
    }

    /// The two descents interleaved level by level, so that their chains of dependent
    /// loads overlap (the same leaves as two calls of [`descend`](Self::descend)).
    #[inline]
    fn descend_pair(&self, k: usize, mut tu: f64, mut tv: f64) -> (usize, usize) {
        let (mut nu, mut nv) = (1, 1);
        while nu < self.m {
            let (lu, ru) = (self.nodes[2 * nu][0][k], self.nodes[2 * nu + 1][0][k]);
            let (lv, rv) = (self.nodes[2 * nv][1][k], self.nodes[2 * nv + 1][1][k]);
            let gu = (tu >= lu) & (ru > 0.0);
            let gv = (tv >= lv) & (rv > 0.0);
            tu -= if gu { lu } else { 0.0 };
            tv -= if gv { lv } else { 0.0 };
            nu = 2 * nu + usize::from(gu);
            nv = 2 * nv + usize::from(gv);
        }
        (nu - self.m, nv - self.m)
    }

    #[inline]
    fn add(&mut self, i: usize, _delta: &Weights<R>, leaf: &Weights<R>) {
        let mut node = self.m + i;
        self.nodes[node] = *leaf;
        while node > 1 {
            node >>= 1;
            self.nodes[node] = add(&self.nodes[2 * node], &self.nodes[2 * node + 1]);
        }
    }

    fn double(&mut self) {
        for n in &mut self.nodes {
            for part in n.iter_mut() {
                for v in part.iter_mut() {
                    *v *= 2.0;
                }
            }
        }
    }

    fn values(&self) -> Vec<f64> {
        self.nodes
            .iter()
            .flat_map(|n| n.iter().flat_map(|p| p.iter().copied()))
            .collect()
    }

    fn save(&self, w: &mut Writer) {
        w.f64s(&self.values());
    }

    fn load(m: usize, r: &mut Reader) -> Result<Self> {
        let flat = r.f64s()?;
        if flat.len() != 2 * m * 2 * R {
            return Err(bad_tree());
        }
        let mut t = Self::build(m, |_| [[0.0; R]; 2])?;
        for (i, node) in t.nodes.iter_mut().enumerate() {
            for p in 0..2 {
                for k in 0..R {
                    node[p][k] = flat[(i * 2 + p) * R + k];
                }
            }
        }
        Ok(t)
    }
}

const B: usize = 8;
/// Updates between rebuilds of a [`WideTree`].
pub const REBUILD: u64 = 1 << 22;

/// One row: the sums of a node's 8 children for one component (one cache line).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Row([f64; B]);

/// 8-ary tree of child sums, one cache line per node and component.
#[derive(Clone, Debug)]
pub struct WideTree<const R: usize> {
    /// Nodes level by level, bottom (each covering 8 leaves) first; node `q` of level `l`
    /// is `rows[start[l] + q]`, and its rows are `[p][k]`.
    rows: Vec<[[Row; R]; 2]>,
    start: Vec<usize>,
    total: Weights<R>,
    updates: u64,
}

/// The child of a row that holds `target`, and the target within it. The running sums
/// are formed in a tree of additions (depth 3, not 7) and compared independently; when
/// rounding leaves `target ≥` the row's total, the last child with weight is taken.
#[inline(always)]
fn pick(row: &[f64; B], target: &mut f64) -> usize {
    let r = row;
    let s01 = r[0] + r[1];
    let s23 = r[2] + r[3];
    let s45 = r[4] + r[5];
    let s67 = r[6] + r[7];
    let s03 = s01 + s23;
    let s47 = s45 + s67;
    let prefix = [
        r[0],
        s01,
        s01 + r[2],
        s03,
        s03 + r[4],
        s03 + s45,
        s03 + s45 + r[6],
        s03 + s47,
    ];
    let mut c = 0;
    for &p in &prefix {
        c += usize::from(p <= *target);
    }
    if c >= B {
        c = B - 1;
        while c > 0 && r[c] <= 0.0 {
            c -= 1;
        }
    }
    if c > 0 {
        *target -= prefix[c - 1];
    }
    c
}

impl<const R: usize> WideTree<R> {
    #[inline]
    fn levels(&self) -> usize {
        self.start.len()
    }
}

/// Level starts of an 8-ary tree over `m` leaves (sizes m/8, m/64, ... down to 1; the
/// root may have fewer than 8 children) and the node count.
fn wide_levels(m: usize) -> (Vec<usize>, usize) {
    debug_assert!(m.is_power_of_two() && m >= B);
    let mut start = Vec::new();
    let mut count = 0;
    let mut n = m;
    loop {
        let nodes = n.div_ceil(B);
        start.push(count);
        count += nodes;
        if nodes == 1 {
            break;
        }
        n = nodes;
    }
    (start, count)
}

impl<const R: usize> ProposalTree<R> for WideTree<R> {
    const NEEDS_LEAF: bool = false;

    fn build(m: usize, leaf: impl Fn(usize) -> Weights<R>) -> Result<Self> {
        let (start, count) = wide_levels(m);
        let mut rows = Vec::new();
        crate::scheme::population::try_resize(&mut rows, count, [[Row([0.0; B]); R]; 2])?;
        let mut t = WideTree {
            rows,
            start,
            total: [[0.0; R]; 2],
            updates: 0,
        };
        t.refill(leaf);
        Ok(t)
    }

    fn refill(&mut self, leaf: impl Fn(usize) -> Weights<R>) {
        let m = self.start.get(1).copied().unwrap_or(1) * B;
        let (start, rows) = (&self.start, &mut self.rows);
        for q in 0..m / B {
            for c in 0..B {
                let w = leaf(q * B + c);
                for p in 0..2 {
                    for k in 0..R {
                        rows[q][p][k].0[c] = w[p][k];
                    }
                }
            }
        }
        let mut below = m / B;
        for l in 1..start.len() {
            let nodes = below.div_ceil(B);
            for q in 0..nodes {
                for c in 0..B {
                    for p in 0..2 {
                        for k in 0..R {
                            rows[start[l] + q][p][k].0[c] = if c < below - q * B {
                                let child = start[l - 1] + q * B + c;
                                rows[child][p][k].0.iter().sum()
                            } else {
                                0.0
                            };
                        }
                    }
                }
            }
            below = nodes;
        }
        let root = &rows[rows.len() - 1];
        for p in 0..2 {
            for k in 0..R {
                self.total[p][k] = root[p][k].0.iter().sum();
            }
        }
        self.updates = 0;
    }

    fn bytes(m: usize) -> Option<usize> {
        wide_levels(m)
            .1
            .checked_mul(core::mem::size_of::<[[Row; R]; 2]>())
    }

    #[inline]
    fn totals(&self) -> Weights<R> {
        self.total
    }

    #[inline]
    fn descend(&self, p: usize, k: usize, mut target: f64) -> usize {
        let mut q = 0; // node index within its level
        for l in (0..self.levels()).rev() {
            let c = pick(&self.rows[self.start[l] + q][p][k].0, &mut target);
            q = q * B + c;
        }
        q
    }

    #[inline]
    fn descend_pair(&self, k: usize, mut tu: f64, mut tv: f64) -> (usize, usize) {
        let (mut qu, mut qv) = (0, 0);
        for l in (0..self.levels()).rev() {
            let s = self.start[l];
            let cu = pick(&self.rows[s + qu][0][k].0, &mut tu);
            let cv = pick(&self.rows[s + qv][1][k].0, &mut tv);
            qu = qu * B + cu;
            qv = qv * B + cv;
        }
        (qu, qv)
    }

    #[inline]
    fn add(&mut self, i: usize, d: &Weights<R>, _leaf: &Weights<R>) {
        let mut idx = i;
        for l in 0..self.levels() {
            let (q, c) = (idx / B, idx % B);
            let node = &mut self.rows[self.start[l] + q];
            for p in 0..2 {
                for k in 0..R {
                    node[p][k].0[c] += d[p][k];
                }
            }
            idx = q;
        }
        for p in 0..2 {
            for k in 0..R {
                self.total[p][k] += d[p][k];
            }
        }
        self.updates += 1;
    }

    fn double(&mut self) {
        for n in &mut self.rows {
            for part in n.iter_mut() {
                for row in part.iter_mut() {
                    for v in row.0.iter_mut() {
                        *v *= 2.0;
                    }
                }
            }
        }
        for part in self.total.iter_mut() {
            for v in part.iter_mut() {
                *v *= 2.0;
            }
        }
    }

    fn wants_rebuild(&self) -> bool {
        self.updates >= REBUILD
    }

    fn values(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .rows
            .iter()
            .flat_map(|n| {
                n.iter()
                    .flat_map(|p| p.iter().flat_map(|row| row.0.iter().copied()))
            })
            .collect();
        v.extend(self.total.iter().flat_map(|p| p.iter().copied()));
        v
    }

    fn save(&self, w: &mut Writer) {
        let v = self.values();
        let (flat, tot) = v.split_at(v.len() - 2 * R);
        w.f64s(flat);
        w.f64s(tot);
        w.u64(self.updates);
    }

    fn load(m: usize, r: &mut Reader) -> Result<Self> {
        let flat = r.f64s()?;
        let tot = r.f64s()?;
        let updates = r.u64()?;
        let mut t = Self::build(m, |_| [[0.0; R]; 2])?;
        if flat.len() != t.rows.len() * 2 * R * B || tot.len() != 2 * R {
            return Err(bad_tree());
        }
        let mut it = flat.into_iter();
        for node in t.rows.iter_mut() {
            for part in node.iter_mut() {
                for row in part.iter_mut() {
                    for v in row.0.iter_mut() {
                        *v = it.next().unwrap_or(0.0);
                    }
                }
            }
        }
        for p in 0..2 {
            for k in 0..R {
                t.total[p][k] = tot[p * R + k];
            }
        }
        // a saved tree is rebuilt at REBUILD updates: more is not a state a run leaves
        if updates > REBUILD {
            return Err(bad_tree());
        }
        t.updates = updates;
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::Rng;

    fn check_same<T: ProposalTree<2>>(m: usize) {
        let mut rng = rand_pcg::Pcg64Mcg::new(5);
        let mut w: Vec<Weights<2>> = (0..m)
            .map(|i| {
                if i % 3 == 1 {
                    [[0.0; 2]; 2]
                } else {
                    [[(i % 7) as f64, 1.0], [2.0, (i % 5) as f64]]
                }
            })
            .collect();
        let mut t = T::build(m, |i| w[i]).unwrap();
        for _ in 0..2000 {
            let i = (rng.next_u64() % m as u64) as usize;
            let new = [
                [(rng.next_u64() % 9) as f64, (rng.next_u64() % 3) as f64],
                [1.0, (rng.next_u64() % 2) as f64],
            ];
            let mut d = [[0.0; 2]; 2];
            for p in 0..2 {
                for k in 0..2 {
                    d[p][k] = new[p][k] - w[i][p][k];
                }
            }
            t.add(i, &d, &new);
            w[i] = new;
        }
        // integer-valued weights add exactly: compare with a linear scan
        for p in 0..2 {
            for k in 0..2 {
                let total: f64 = w.iter().map(|x| x[p][k]).sum();
                assert_eq!(t.totals()[p][k], total);
                if total == 0.0 {
                    continue;
                }
                for u in 0..total as u64 {
                    let target = u as f64 + 0.5;
                    let mut acc = 0.0;
                    let expect = w
                        .iter()
                        .position(|x| {
                            acc += x[p][k];
                            target < acc
                        })
                        .unwrap();
                    assert_eq!(t.descend(p, k, target), expect, "m={m} p={p} k={k} u={u}");
                }
                // a target at or beyond the total lands on the last positive leaf
                let last = w.iter().rposition(|x| x[p][k] > 0.0).unwrap();
                assert_eq!(t.descend(p, k, total), last);
            }
        }
        // the paired descent finds what two single descents find
        let tot = t.totals();
        for k in 0..2 {
            for _ in 0..500 {
                let tu = crate::random::unit_f64(rng.next_u64()) * tot[0][k];
                let tv = crate::random::unit_f64(rng.next_u64()) * tot[1][k];
                let single = (t.descend(0, k, tu), t.descend(1, k, tv));
                assert_eq!(t.descend_pair(k, tu, tv), single, "m={m} k={k}");
            }
        }
    }

    #[test]
    fn both_layouts_match_a_linear_scan() {
        for m in [64, 128, 1024, 4096] {
            check_same::<BinaryTree<2>>(m);
            check_same::<WideTree<2>>(m);
        }
    }
}
