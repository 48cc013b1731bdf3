//! The per-size proposal engine of the paper (Osinsky 2023, §3): the weights
//! `u^k_i = a_k(i) N_i`, `v^k_j = b_k(j) N_j` of every size in one segment tree
//! ([`WideTree`](super::WideTree) or [`BinaryTree`](super::BinaryTree)), so a count
//! change walks a single path. A proposal picks k ∝ `U_k V_k`, then i and j by descending
//! the tree; the bound at the pair is exact per size (`low = bound`).

use super::proposal::{Candidate, Low, Outcome, ProposalEngine, rank_mismatch};
use super::trees::{ProposalTree, Weights};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::{open_unit, unit_f64};
use crate::scheme::population::{
    Population, rate_overflow, try_reserve, try_resize, within_budget,
};
use alloc::borrow::Cow;
use alloc::vec::Vec;
use rand_core::Rng;

/// The per-size tree engine (see the module docs).
pub struct TreeEngine<const R: usize, T> {
    /// `counts[i - 1] = N_i`, length M.
    counts: Vec<u64>,
    /// `fab[i - 1] = [[a_0(i), ..], [b_0(i), ..]]`: the weights of one particle of size i
    /// (packed so that an update reads one cache line).
    fab: Vec<Weights<R>>,
    /// Proposal tree over the weights `u^k_i = a_k(i) N_i`, `v^k_i = b_k(i) N_i`.
    tree: T,
    /// Current maximum size M (a power of two; the tree's leaf count).
    m: usize,
}

impl<const R: usize, T> core::fmt::Debug for TreeEngine<R, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("TreeEngine")
            .field("rank", &R)
            .field("max_size", &self.m)
            .finish_non_exhaustive()
    }
}

/// `w · c` component-wise.
#[inline]
fn scale<const R: usize>(w: &Weights<R>, c: f64) -> Weights<R> {
    let mut out = [[0.0; R]; 2];
    for p in 0..2 {
        for k in 0..R {
            out[p][k] = w[p][k] * c;
        }
    }
    out
}

/// A restored tree against the one its counts and kernel build: it may differ by the
/// rounding of its incremental updates (relative to the largest finite weight; a
/// weight emptied by differences may sit a rounding below 0), never by more — a
/// corrupted weight (NaN, infinite, off) is refused. Sums that overflow to infinity in
/// the fresh tree too are the state the scheme holds (it refuses to advance until new
/// counts or a new kernel rebuild it), so a clone or a restart of that state restores
/// (fuzzing finding 9).
pub(super) fn check_restored<const R: usize, T: ProposalTree<R>>(got: &T, fresh: &T) -> Result<()> {
    let (got, want) = (got.values(), fresh.values());
    let scale = want
        .iter()
        .filter(|w| w.is_finite())
        .fold(0.0f64, |a, &b| a.max(b));
    if got.len() != want.len()
        || got.iter().zip(&want).any(|(&g, &w)| {
            !(g == w || (g.is_finite() && (g - w).abs() <= 1e-6 * w + 1e-9 * scale))
        })
    {
        return Err(Error::Checkpoint {
            what: "tree weights do not match the counts and the kernel",
        });
    }
    Ok(())
}

/// `S_A = Σ_k U_k V_k` from a tree's totals.
#[inline]
pub(super) fn tree_rate<const R: usize>(root: &Weights<R>) -> f64 {
    let mut sa = 0.0;
    for k in 0..R {
        sa += root[0][k] * root[1][k];
    }
    sa
}

/// [`tree_rate`], an error when it is not finite (weights past `f64::MAX`: no waiting
/// time can be drawn).
pub(super) fn checked_rate<const R: usize>(root: &Weights<R>) -> Result<f64> {
    let sa = tree_rate(root);
    if sa.is_finite() {
        Ok(sa)
    } else {
        Err(rate_overflow(sa))
    }
}

/// The leaves of one proposal: component k ∝ `U_k V_k`, then side u's leaf ∝ its
/// `u^k` weight and side v's ∝ its `v^k` weight (three random words).
#[inline(always)]
pub(super) fn descend_leaves<const R: usize, T: ProposalTree<R>, G: Rng + ?Sized>(
    tree: &T,
    rng: &mut G,
) -> (usize, usize) {
    let root = tree.totals();
    let mut weights = [0.0; R];
    let mut sa = 0.0;
    for k in 0..R {
        weights[k] = root[0][k] * root[1][k];
        sa += weights[k];
    }
    let mut r = sa * open_unit(rng);
    let mut k = R - 1;
    for (kk, &w) in weights.iter().enumerate() {
        r -= w;
        if r <= 0.0 && w > 0.0 {
            k = kk;
            break;
        }
    }
    let tu = root[0][k] * unit_f64(rng.next_u64());
    let tv = root[1][k] * unit_f64(rng.next_u64());
    tree.descend_pair(k, tu, tv)
}

impl<const R: usize, T: ProposalTree<R>> TreeEngine<R, T> {
    /// Bytes of the per-size arrays and the tree for maximum size `m`.
    fn bytes_for(m: usize) -> Option<usize> {
        let per_size = core::mem::size_of::<u64>() + core::mem::size_of::<Weights<R>>();
        m.checked_mul(per_size)?.checked_add(T::bytes(m)?)
    }

    /// Computes the factor tables for sizes `fab.len() + 1 ..= m`, validating them
    /// (nothing to do when the tables already cover `m`).
    fn extend_factors<K: CoagulationKernel>(&mut self, kernel: &K, m: usize) -> Result<()> {
        super::bound::extend_rows(kernel, &mut self.fab, m)
    }

    /// The weights of size index `idx` (zero past the count array).
    #[inline]
    fn leaf_value(&self, idx: usize) -> Weights<R> {
        scale(
            &self.fab[idx],
            self.counts.get(idx).copied().unwrap_or(0) as f64,
        )
    }

    /// Recomputes the tree from the exact counts, in place.
    fn rebuild(&mut self) {
        let (fab, counts) = (&self.fab, &self.counts);
        self.tree.refill(|idx| scale(&fab[idx], counts[idx] as f64));
    }

    /// Changes `N` at index `idx` by `delta` and updates the tree.
    #[inline]
    fn change(&mut self, idx: usize, delta: i64) {
        // in u64 (a count may pass 2^63): a removal takes particles the proposal drew
        // from this size, an addition stays below the total, so this never fails; the
        // check stays in release builds (the count is what exactness rests on)
        self.counts[idx] = self.counts[idx]
            .checked_add_signed(delta)
            .expect("a size's count stays within [0, total particles]");
        let leaf = if T::NEEDS_LEAF {
            self.leaf_value(idx)
        } else {
            [[0.0; R]; 2]
        };
        self.tree
            .add(idx, &scale(&self.fab[idx], delta as f64), &leaf);
    }

    /// Grows the size table to `new_m`: budget, factors, counts and the new tree are
    /// all prepared before anything the scheme uses changes.
    fn grow<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        new_m: usize,
        budget: usize,
    ) -> Result<()> {
        // the old tree lives on while the new one is built
        let bytes = Self::bytes_for(new_m).and_then(|b| b.checked_add(T::bytes(self.m)?));
        within_budget(bytes, budget)?;
        self.extend_factors(kernel, new_m)?;
        let more = new_m - self.counts.len();
        try_reserve(&mut self.counts, more)?;
        let tree = T::build(new_m, |idx| self.leaf_value(idx))?;
        self.counts.resize(new_m, 0);
        self.m = new_m;
        self.tree = tree;
        Ok(())
    }
}

impl<const R: usize, T: ProposalTree<R>> ProposalEngine<R> for TreeEngine<R, T> {
    /// The two sizes' indices.
    type Loc = (usize, usize);
    const TAG: u64 = crate::scheme::tag::LOWRANK;
    const LOW: Low = Low::Bound;

    fn build<K: CoagulationKernel>(kernel: &K, counts: &[u64], pop: &Population) -> Result<Self> {
        if kernel.rank() != R || R == 0 {
            return Err(rank_mismatch());
        }
        let m = counts.len().next_power_of_two().max(64);
        within_budget(Self::bytes_for(m), pop.memory_budget)?;
        let mut s = TreeEngine {
            counts: Vec::new(),
            fab: Vec::new(),
            tree: T::build(8, |_| [[0.0; R]; 2])?,
            m,
        };
        try_resize(&mut s.counts, m, 0)?;
        s.counts[..counts.len()].copy_from_slice(counts);
        s.extend_factors(kernel, m)?;
        s.tree = T::build(m, |idx| s.leaf_value(idx))?;
        Ok(s)
    }

    #[inline]
    fn rate_now(&self) -> Option<f64> {
        Some(tree_rate(&self.tree.totals()))
    }

    fn refresh<G: Rng + ?Sized>(&mut self, _pop: &Population, _rng: &mut G) -> Result<f64> {
        checked_rate(&self.tree.totals())
    }

    #[inline]
    fn propose<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Option<Candidate<(usize, usize)>> {
        let (i, j) = descend_leaves(&self.tree, rng);
        if self.counts[i] == 0 || self.counts[j] == 0 {
            // a ghost weight left by rounding (see `trees`): thinning rejects it
            return None;
        }
        if i == j && (self.counts[i] as f64) * open_unit(rng) <= 1.0 {
            // the particle with itself, probability 1/N_i: `u ≤ 1/N_i` for u in (0, 1]
            // (with `<`, u = 1 accepted a lone particle's pair with itself)
            return None;
        }
        Some(Candidate {
            x: (i + 1) as u64,
            y: (j + 1) as u64,
            at: (i, j),
        })
    }

    #[inline]
    fn bounds(&self, &(i, j): &(usize, usize)) -> (f64, f64) {
        let mut bound = 0.0;
        for kk in 0..R {
            bound +=
                self.fab[i][0][kk] * self.fab[j][1][kk] + self.fab[j][0][kk] * self.fab[i][1][kk];
        }
        (bound, bound)
    }

    fn prepare<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        outcome: &Outcome,
        pop: &Population,
    ) -> Result<()> {
        let Outcome::Merge { size } = *outcome else {
            return Ok(());
        };
        if size > self.m as u64 {
            self.grow(kernel, 2 * self.m, pop.memory_budget)?;
        }
        Ok(())
    }

    #[inline]
    fn apply(&mut self, c: &Candidate<(usize, usize)>, outcome: &Outcome) {
        let Outcome::Merge { size } = *outcome else {
            return;
        };
        let (i, j) = c.at;
        if i == j {
            self.change(i, -2);
        } else {
            self.change(i, -1);
            self.change(j, -1);
        }
        self.change(size as usize - 1, 1);
    }

    const EDITS: bool = true;

    /// A size by its particle number (`by_mass`: number times size) in one pass over
    /// the counts (the tree holds the kernel's weights, not counts): O(M) a draw, and
    /// the edit O(log M), against a state replacement's O(M) rebuild.
    fn draw_particle<G: Rng + ?Sized>(
        &self,
        by_mass: bool,
        n: u64,
        rng: &mut G,
    ) -> Option<(u64, (usize, u64))> {
        let counts = self.counts.iter().copied().enumerate();
        let idx = super::edit::pick(counts, n, by_mass, |i| i as u64 + 1, rng)?;
        Some(((idx + 1) as u64, (idx, 0)))
    }

    fn remove_particle(&mut self, (idx, _): (usize, u64), _x: u64) {
        self.change(idx, -1);
    }

    fn add_particle<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        x: u64,
        pop: &Population,
    ) -> Result<()> {
        while x > self.m as u64 {
            self.grow(kernel, 2 * self.m, pop.memory_budget)?;
        }
        self.change(x as usize - 1, 1);
        Ok(())
    }

    const REWEIGHS: bool = true;

    #[inline]
    fn count(&self, size: u64) -> u64 {
        usize::try_from(size - 1)
            .ok()
            .and_then(|i| self.counts.get(i))
            .copied()
            .unwrap_or(0)
    }

    fn reweigh<K: CoagulationKernel>(&mut self, kernel: &K, size: u64) {
        let idx = (size - 1) as usize;
        if idx >= self.m {
            return;
        }
        let (mut a, mut b) = ([0.0; R], [0.0; R]);
        kernel.factors(size as f64, &mut a, &mut b);
        let new = [a, b];
        let n = self.counts[idx] as f64;
        let mut delta = [[0.0; R]; 2];
        for p in 0..2 {
            for k in 0..R {
                delta[p][k] = (new[p][k] - self.fab[idx][p][k]) * n;
            }
        }
        self.fab[idx] = new;
        if self.counts[idx] > 0 {
            let leaf = if T::NEEDS_LEAF {
                self.leaf_value(idx)
            } else {
                [[0.0; R]; 2]
            };
            self.tree.add(idx, &delta, &leaf);
        }
    }

    fn refactor<K: CoagulationKernel>(&mut self, kernel: &K) {
        super::bound::reread_rows(kernel, &mut self.fab);
        self.rebuild();
    }

    fn double(&mut self, _pop: &Population) {
        for c in &mut self.counts {
            *c *= 2;
        }
        // doubling every leaf doubles every partial sum exactly
        self.tree.double();
    }

    #[inline]
    fn settle(&mut self, _pop: &Population) {
        if self.tree.wants_rebuild() {
            self.rebuild();
        }
    }

    fn counts(&self) -> Cow<'_, [u64]> {
        Cow::Borrowed(&self.counts)
    }

    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        for (i, &c) in self.counts.iter().enumerate() {
            if c > 0 {
                f(i as u64 + 1, c);
            }
        }
    }

    fn max_size(&self) -> u64 {
        self.m as u64
    }

    fn save(&self, w: &mut Writer) {
        w.u64s(&self.counts);
        self.tree.save(w);
    }

    fn load<K: CoagulationKernel>(
        kernel: &K,
        m: u64,
        pop: &Population,
        r: &mut Reader,
    ) -> Result<Self> {
        let m = usize::try_from(m).map_err(|_| Error::Checkpoint {
            what: "invalid maximum size",
        })?;
        let counts = r.u64s()?;
        if counts.len() != m
            || counts.iter().try_fold(0u64, |a, &c| a.checked_add(c)) != Some(pop.n)
        {
            return Err(Error::Checkpoint {
                what: "counts do not add up",
            });
        }
        within_budget(Self::bytes_for(m), pop.memory_budget)?;
        let tree = T::load(m, r)?;
        // the tree as the counts and the kernel make it
        let fresh = Self::build(kernel, &counts, pop)?;
        check_restored(&tree, &fresh.tree)?;
        let mut s = TreeEngine {
            counts,
            fab: Vec::new(),
            tree,
            m,
        };
        s.extend_factors(kernel, m)?;
        Ok(s)
    }
}
