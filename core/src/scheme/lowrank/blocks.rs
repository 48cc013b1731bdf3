//! Block majorants: the proposal engine for kernels that no low-rank bound fits
//! (issue 45; `docs/design/block-majorants.md`). The idea is the block-majorant Monte
//! Carlo of Dyachenko, Matveev & Valiakhmetov (2025) on the mosaic partition of their
//! deterministic solver (arXiv 2501.10206), the thinning of Eibeck & Wagner (2000).
//!
//! **State.** Counts `N_i` of integer sizes `i = 1..M` (M a power of two) in a binary
//! sum tree: the node of an aligned strip of sizes holds their particle number.
//!
//! **Blocks.** The upper triangle of the size-pair matrix is cut into blocks
//! (`partition`): small next to the diagonal, growing away from it, each block a row
//! strip and a column strip of the tree. A block's bound is the kernel's supremum over
//! it (`CoagulationKernel::sup_block`), and its intensity `I_b = sup_b R_b C_b` (rows
//! and columns the strips' particle numbers, read from the count tree),
//! `sup_b R_b (R_b − 1)/2` on the diagonal (its pairs of distinct particles).
//!
//! **Proposals.** A block b is chosen in proportion to a majorant `Î_b ≥ I_b` from a
//! 4-ary sum tree (`sums`) and kept with probability `I_b / Î_b`; a row size and a
//! column size are drawn by count, descending the count tree from the strips' nodes
//! (on the diagonal an ordered pair of distinct particles of the strip, uniform: the
//! second drawn among the other `R_b − 1`, so no proposal pairs a particle with
//! itself). Proposals arrive at rate `Σ_b Î_b / V`, so each unordered pair of
//! distinct particles in block b is proposed at rate `sup_b / V`; the rule accepts with
//! `K / sup_b`, giving rate `K / V` (Osinsky 2023 §2's law). A uniform below the block's
//! lower bound (`CoagulationKernel::inf_block`, [`Low::Infimum`]) accepts without
//! evaluating K: the decision K would give on the same draw, so only the cost changes.
//!
//! **The lazy majorant.** After an event, a block meeting the merged size (whose count
//! rose) has its `Î_b` raised to `I_b (1 + m)` when `I_b > Î_b` (m = [`BAND`]); counts
//! that fall leave `Î_b ≥ I_b`. A block that the thinning by `I_b / Î_b` rejects while
//! `I_b (1 + m)² < Î_b` is tightened to `I_b (1 + m)`, and the proposals after it come
//! at the new total rate. The thinning keeps the law exact (`Î` changes only at
//! proposals, from the state: a predictable majorant).
//!
//! **Allowances.** Each side of a block holds an allowance, the two within `Î_b`
//! (`sup_b · pairs ≤ Î_b`), and each strip of the count tree a cap, the least allowance
//! of its blocks; a count that passes its cap has its strip's blocks looked at (raised
//! if `I_b > Î_b`, the headroom split afresh). So `I_b ≤ Î_b` holds between looks, the
//! raises happen exactly when checking every block after every event would make them,
//! and a strip of many particles is looked at once in many events (the whole run of
//! the canonical case: 11 % less time than checking every block).
//!
//! Memory: `24 M` bytes for the count tree and its caps, and about 72 bytes a block.
//! Growth of M (a merged size beyond it) and particle doubling rebuild or rescale the
//! structures.

mod partition;
mod sums;
#[cfg(test)]
mod tests;

use super::proposal::{Candidate, Low, Outcome, ProposalEngine};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::memory::{try_reserve, within_budget};
use crate::random::{below, open_unit, unit_f64};
use crate::scheme::population::{Population, rate_overflow};
use alloc::borrow::Cow;
use alloc::vec::Vec;
use partition::{Block, Partition};
use rand_core::Rng;
use sums::QuadSums;

/// Diagonal blocks are `2^MIN_LEVEL` sizes wide (wider in a log-linear partition, at
/// most 1/32 of their sizes: `partition`).
pub const MIN_LEVEL: u32 = 2;
/// A block is kept whole once its gap to the diagonal is at least this many sides.
pub const SEPARATION: u64 = 1;
/// Blocks per size of the partition of M sizes with the constants above, at most (1.32
/// at M = 2^8, 1.25 from 2^17; the partition's tests check it for M = 2^6 … 2^21).
/// What the memory estimate assumes.
pub const BLOCKS_PER_SIZE: f64 = 1.33;
/// The lazy majorant's band m (see the module docs).
pub const BAND: f64 = 0.05;

/// The block-majorant proposal engine (see the module docs).
#[derive(Clone, Debug)]
pub struct BlockEngine {
    /// `M`, a power of two.
    m: u64,
    /// The count tree: node 1 the root, node `(M >> ℓ) + s` strip s of level ℓ, leaf
    /// `M + i − 1` the count of size i.
    tree: Vec<u64>,
    part: Partition,
    /// `sup K` over each block, and a lower bound of K over it (`inf_block`; 0 when
    /// unknown): the squeeze. Side by side, as a proposal reads both.
    sup: Vec<[f64; 2]>,
    /// `Î_b`.
    hats: QuadSums,
    /// Per count-tree node, the least allowance of the blocks in its strip's list (at
    /// most `u32::MAX`): a count that rises past it has its list looked at.
    caps: Vec<u32>,
    /// The tree's total changed since the last refresh.
    changed: bool,
}

/// `I_b` from the block's sup (finite) and its strips' particle numbers (the pair count
/// first: an empty strip gives 0, never `∞ · 0`).
#[inline]
fn intensity(b: &Block, sup: f64, rows: u64, cols: u64) -> f64 {
    intensity_of_pairs(b.diagonal(), sup, rows, cols)
}

/// [`intensity`] of a block given as diagonal or not (what a member list knows).
#[inline]
fn intensity_of_pairs(diagonal: bool, sup: f64, rows: u64, cols: u64) -> f64 {
    sup * pairs(diagonal, rows, cols)
}

/// The lazy majorant for intensity `i`.
#[inline]
fn hat_for(i: f64) -> f64 {
    i * (1.0 + BAND)
}

/// The unordered pairs of distinct particles of a block given as diagonal or not.
#[inline]
fn pairs(diagonal: bool, rows: u64, cols: u64) -> f64 {
    if diagonal {
        0.5 * rows as f64 * rows.saturating_sub(1) as f64
    } else {
        rows as f64 * cols as f64
    }
}

/// The allowances `(a, b) ≥ (r, c)` of a block's two sides (the same on the diagonal),
/// such that `sup · pairs(a, b) ≤ hat`: the headroom of `Î` split between the sides in
/// proportion to their counts. Needs `sup · pairs(r, c) ≤ hat`.
fn allot(diagonal: bool, sup: f64, hat: f64, r: u64, c: u64) -> (u64, u64) {
    if !(sup > 0.0 && hat < f64::INFINITY) {
        // (a block of bound 0 never has an intensity; an infinite Î is never passed)
        return (u64::MAX, u64::MAX);
    }
    let p = hat / sup;
    // (float-to-integer casts saturate)
    let (mut a, mut b) = if diagonal {
        let n = (0.5 * (1.0 + libm::sqrt(1.0 + 8.0 * p))) as u64;
        (n, n)
    } else if r == 0 && c == 0 {
        (0, 0)
    } else if r == 0 {
        ((p / c as f64) as u64, c)
    } else if c == 0 {
        (r, (p / r as f64) as u64)
    } else {
        let t = libm::sqrt(p / (r as f64 * c as f64));
        ((r as f64 * t) as u64, (c as f64 * t) as u64)
    };
    (a, b) = (a.max(r), b.max(c));
    // against rounding: back towards (r, c), where the bound holds
    while sup * pairs(diagonal, a, b) > hat && (a > r || b > c) {
        a = r + (a - r) / 2;
        b = c + (b - c) / 2;
    }
    if diagonal { (a, a) } else { (a, b) }
}

/// An allowance as a cap (saturated).
#[inline]
fn cap_of(allow: u64) -> u32 {
    allow.min(u64::from(u32::MAX)) as u32
}

impl BlockEngine {
    /// Bytes of the engine over M sizes with `b` blocks.
    fn bytes_for(m: u64, b: usize) -> Option<usize> {
        let levels = m.trailing_zeros();
        usize::try_from(m)
            .ok()?
            .checked_mul(24)?
            .checked_add(Partition::bytes(levels, MIN_LEVEL, b)?)?
            .checked_add(b.checked_mul(16)?)?
            .checked_add(QuadSums::bytes(b)?)
    }

    /// Bytes of the engine over `m` sizes (a power of two) with a log-linear
    /// partition; `None` past the largest M (2^31) or the address space.
    pub(super) fn log_linear_bytes(m: u64) -> Option<usize> {
        let levels = m.trailing_zeros();
        if !m.is_power_of_two() || levels > 31 {
            return None;
        }
        Self::bytes_for(m, Partition::count(levels, MIN_LEVEL, SEPARATION, true))
    }

    #[inline]
    fn node(&self, level: u8, strip: u32) -> usize {
        ((self.m >> level) + u64::from(strip)) as usize
    }

    /// The count-tree nodes of the block's row and column strips.
    #[inline]
    fn nodes(&self, b: &Block) -> (usize, usize) {
        (self.node(b.row_level, b.row), self.node(b.col_level, b.col))
    }

    /// The block's intensity now.
    #[inline]
    fn intensity_of(&self, id: usize) -> f64 {
        let b = &self.part.blocks[id];
        let (rn, cn) = self.nodes(b);
        let (rows, cols) = (self.tree[rn], self.tree[cn]);
        intensity(b, self.sup[id][0], rows, cols)
    }

    /// The engine over `counts` (`counts[i − 1] = N_i`, at most `m` of them) for M = `m`.
    fn with_size<K: CoagulationKernel>(
        kernel: &K,
        counts: &[u64],
        m: u64,
        budget: usize,
    ) -> Result<Self> {
        let levels = m.trailing_zeros();
        if levels > 31 {
            // (before counting the blocks: the partition names strips below 2^32)
            return Err(Error::Capacity {
                name: "maximum particle size",
                capacity: 1 << 31,
            });
        }
        let ll = kernel.log_linear_blocks();
        let nb = Partition::count(levels, MIN_LEVEL, SEPARATION, ll);
        within_budget(Self::bytes_for(m, nb), budget)?;
        let part = Partition::new(levels, MIN_LEVEL, SEPARATION, ll)?;
        let mu = m as usize;
        let mut tree = Vec::new();
        try_reserve(&mut tree, 2 * mu)?;
        tree.resize(2 * mu, 0u64);
        tree[mu..mu + counts.len()].copy_from_slice(counts);
        for n in (1..mu).rev() {
            tree[n] = tree[2 * n].saturating_add(tree[2 * n + 1]);
        }
        let mut sup = Vec::new();
        try_reserve(&mut sup, nb)?;
        for b in &part.blocks {
            // (sizes are indices + 1)
            let ((r0, r1), (c0, c1)) = b.ranges();
            let v = kernel
                .sup_block((r0 + 1) as f64, r1 as f64, (c0 + 1) as f64, c1 as f64)
                .ok_or(Error::Unsupported {
                    what: "block majorants need the kernel's supremum over a block of sizes (sup_block)",
                })?;
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidRate {
                    name: "kernel supremum over a block (sup_block)",
                    value: v,
                });
            }
            // (a lower bound that is not a number, or not below the sup, squeezes
            // nothing: at the sup itself the rule would accept without its uniform,
            // and the draws would differ from a run without the squeeze)
            let w = kernel.inf_block((r0 + 1) as f64, r1 as f64, (c0 + 1) as f64, c1 as f64);
            sup.push([v, if w >= 0.0 && w < v { w } else { 0.0 }]);
        }
        let mut caps = Vec::new();
        try_reserve(&mut caps, 2 * mu)?;
        caps.resize(2 * mu, u32::MAX);
        let mut s = BlockEngine {
            m,
            tree,
            part,
            sup,
            hats: QuadSums::new(&[])?,
            caps,
            changed: true,
        };
        let mut leaves = Vec::new();
        try_reserve(&mut leaves, nb)?;
        leaves.extend((0..nb).map(|id| hat_for(s.intensity_of(id))));
        s.hats = QuadSums::new(&leaves)?;
        s.allot_all();
        Ok(s)
    }

    /// Sets the allowance of the entry at `k` (in the list of `node`), saturated,
    /// lowering the node's cap to it (a cap left below the least allowance only costs a
    /// look).
    #[inline]
    fn give(&mut self, k: usize, node: usize, allow: u64) {
        let a = cap_of(allow);
        self.part.members[k].allow = a;
        self.caps[node] = self.caps[node].min(a);
    }

    /// Splits the headroom of the block of entry `k` (in the list of `node`) between its
    /// sides afresh.
    fn allot_at(&mut self, node: usize, k: usize) {
        let mb = self.part.members[k];
        let (id, other) = (mb.id as usize, mb.other as usize);
        let diagonal = other == node;
        let (r, c) = (self.tree[node], self.tree[other]);
        let (x, y) = allot(diagonal, self.sup[id][0], self.hats.leaf(id), r, c);
        self.give(k, node, x);
        if !diagonal {
            self.give(mb.twin as usize, other, y);
        }
    }

    /// Splits block `id`'s headroom between its sides afresh.
    fn allot(&mut self, id: usize) {
        let (rn, _) = self.nodes(&self.part.blocks[id]);
        if let Some(k) = self.part.find(rn as u32, id) {
            self.allot_at(rn, k);
        }
    }

    /// Every block's allowances and every cap afresh (after a build, a doubling, a
    /// restore).
    fn allot_all(&mut self) {
        self.caps.fill(u32::MAX);
        for node in 1..self.caps.len() {
            for k in self.part.list(node as u32) {
                // (each block once, from its first entry)
                if k <= self.part.members[k].twin as usize {
                    self.allot_at(node, k);
                }
            }
        }
    }

    /// After the count of `node` rose past its cap: the blocks of its list whose
    /// allowance it passed have `Î` raised to `I (1 + m)` if `I > Î`, and their
    /// headroom split afresh; the cap becomes the least allowance.
    fn look(&mut self, node: usize) {
        let mine = self.tree[node];
        let mut cap = u32::MAX;
        for k in self.part.list(node as u32) {
            let mb = self.part.members[k];
            if mine <= u64::from(mb.allow) {
                cap = cap.min(mb.allow);
                continue;
            }
            let (id, other) = (mb.id as usize, mb.other as usize);
            let diagonal = other == node;
            let theirs = self.tree[other];
            let sup = self.sup[id][0];
            let i = intensity_of_pairs(diagonal, sup, mine, theirs);
            let mut hat = self.hats.leaf(id);
            if i > hat {
                hat = hat_for(i);
                self.hats.set(id, hat);
                self.changed = true;
            }
            let (x, y) = allot(diagonal, sup, hat, mine, theirs);
            let x = cap_of(x);
            self.part.members[k].allow = x;
            cap = cap.min(x);
            if !diagonal {
                self.give(mb.twin as usize, other, y);
            }
        }
        self.caps[node] = cap;
    }

    /// Adds `d` (±1, or −2) to the count of size index `p` along its path.
    #[inline]
    fn change(&mut self, p: u64, d: i64) {
        let mut n = (self.m + p) as usize;
        while n >= 1 {
            self.tree[n] = self.tree[n].wrapping_add_signed(d);
            n /= 2;
        }
    }

    /// Adds 1 to the count of size index `p` along its path; a strip whose count passes
    /// its cap has its blocks looked at ([`Self::look`]): `Î` of a block whose intensity
    /// passed it is raised to `I (1 + m)`. A count that falls leaves `Î ≥ I`; a block
    /// whose `Î` has become loose is tightened when it is next drawn.
    ///
    /// Each side of a block holds an allowance, the pair of them within `Î`; a strip's
    /// count stays at or below the least allowance of its blocks, so `I ≤ Î` holds
    /// without reading `Î`, and a look comes only when a count passes its cap — seldom
    /// for strips of many particles. `Î` is raised exactly when `I > Î`, as by checking
    /// every block meeting `p` after every event.
    #[inline]
    fn rise(&mut self, p: u64) {
        let mut n = (self.m + p) as usize;
        while n >= 1 {
            self.tree[n] += 1;
            // (the strips a look reads are disjoint from this one's, so not on the path)
            if self.tree[n] > u64::from(self.caps[n]) {
                self.look(n);
            }
            n /= 2;
        }
    }

    /// The size indices of the `u1`-th particle below node `n1` and the `u2`-th below
    /// `n2` (each below its node's count), the two descents walked in lockstep so that
    /// the loads of one overlap those of the other, each step without a branch on the
    /// count.
    #[inline]
    fn descend2(
        &self,
        (mut n1, mut u1): (usize, u64),
        (mut n2, mut u2): (usize, u64),
    ) -> (u64, u64) {
        let m = self.m as usize;
        while n1 < m || n2 < m {
            if n1 < m {
                let left = self.tree[2 * n1];
                let right = usize::from(u1 >= left);
                u1 -= left * right as u64;
                n1 = 2 * n1 + right;
            }
            if n2 < m {
                let left = self.tree[2 * n2];
                let right = usize::from(u2 >= left);
                u2 -= left * right as u64;
                n2 = 2 * n2 + right;
            }
        }
        ((n1 - m) as u64, (n2 - m) as u64)
    }
}

impl<const R: usize> ProposalEngine<R> for BlockEngine {
    /// The block.
    type Loc = usize;
    const TAG: u64 = crate::scheme::tag::BLOCKS;
    const LOW: Low = Low::Infimum;

    fn build<K: CoagulationKernel>(kernel: &K, counts: &[u64], pop: &Population) -> Result<Self> {
        let m = (counts.len() as u64).next_power_of_two().max(64);
        Self::with_size(kernel, counts, m, pop.memory_budget)
    }

    fn refresh<G: Rng + ?Sized>(&mut self, _pop: &Population, _rng: &mut G) -> Result<f64> {
        let total = self.hats.total();
        if !total.is_finite() {
            return Err(rate_overflow(total));
        }
        self.changed = false;
        Ok(total)
    }

    #[inline]
    fn needs_refresh(&self) -> bool {
        self.changed
    }

    const REFRESH_AFTER_REJECT: bool = true;

    #[inline]
    fn propose<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Option<Candidate<usize>> {
        let id = self.hats.find(unit_f64(rng.next_u64()) * self.hats.total());
        // (padding, reached only by rounding: a ghost the thinning rejects)
        let b = *self.part.blocks.get(id)?;
        let hat = self.hats.leaf(id);
        let (rn, cn) = self.nodes(&b);
        let (rows, cols) = (self.tree[rn], self.tree[cn]);
        let i = intensity(&b, self.sup[id][0], rows, cols);
        // the lazy majorant's thinning (an empty block, or a rounding ghost, too); a
        // rejected block whose majorant is loose is tightened, and the proposals after
        // this one come at the new rate (the event loop refreshes after a rejection
        // too, `REFRESH_AFTER_REJECT`; a rejection changes nothing else, so no error
        // can follow the change)
        if !(i > 0.0 && open_unit(rng) * hat <= i) {
            if hat_for(hat_for(i)) < hat {
                self.hats.set(id, hat_for(i));
                self.allot(id);
                self.changed = true;
            }
            return None;
        }
        let (x, y) = if b.diagonal() {
            // an ordered pair of distinct particles of the strip, uniform
            let p = below(rng, rows);
            let mut q = below(rng, rows - 1);
            if q >= p {
                q += 1;
            }
            self.descend2((rn, p), (rn, q))
        } else {
            // (disjoint strips)
            let (p, q) = (below(rng, rows), below(rng, cols));
            self.descend2((rn, p), (cn, q))
        };
        Some(Candidate {
            x: x + 1,
            y: y + 1,
            at: id,
        })
    }

    #[inline]
    fn bounds(&self, &id: &usize) -> (f64, f64) {
        (self.sup[id][0], self.sup[id][1])
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
        if size > self.m {
            let m = size.checked_next_power_of_two().ok_or(Error::Capacity {
                name: "maximum particle size",
                capacity: usize::MAX,
            })?;
            // (the old engine stays alive beside the new one while it is built)
            let old = Self::bytes_for(self.m, self.part.blocks.len()).unwrap_or(usize::MAX);
            let counts = &self.tree[self.m as usize..];
            *self = Self::with_size(kernel, counts, m, pop.memory_budget.saturating_sub(old))?;
        }
        Ok(())
    }

    #[inline]
    fn apply(&mut self, c: &Candidate<usize>, outcome: &Outcome) {
        let Outcome::Merge { size } = *outcome else {
            return;
        };
        let (x, y, z) = (c.x - 1, c.y - 1, size - 1);
        if x == y {
            self.change(x, -2);
        } else {
            self.change(x, -1);
            self.change(y, -1);
        }
        self.rise(z);
    }

    fn double(&mut self, _pop: &Population) {
        for c in &mut self.tree {
            *c *= 2;
        }
        // every off-diagonal intensity and majorant times 4, exactly; a diagonal
        // block's pairs of distinct particles more than that (2R (2R − 1) = 4 R (R − 1)
        // + 2R), so its majorant is raised where the scaled one falls short
        self.hats.scale(4.0);
        for id in 0..self.part.blocks.len() {
            if self.part.blocks[id].diagonal() {
                let i = self.intensity_of(id);
                if i > self.hats.leaf(id) {
                    self.hats.set(id, hat_for(i));
                }
            }
        }
        self.allot_all();
        self.changed = true;
    }

    #[inline]
    fn settle(&mut self, _pop: &Population) {}

    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        for (i, &c) in self.tree[self.m as usize..].iter().enumerate() {
            if c > 0 {
                f(i as u64 + 1, c);
            }
        }
    }

    fn counts(&self) -> Cow<'_, [u64]> {
        Cow::Borrowed(&self.tree[self.m as usize..])
    }

    fn max_size(&self) -> u64 {
        self.m
    }

    fn rate_now(&self) -> Option<f64> {
        (!self.changed).then(|| self.hats.total())
    }

    fn save(&self, w: &mut Writer) {
        w.u64(u64::from(self.changed));
        w.u64s(&self.tree[self.m as usize..]);
        w.u64(self.hats.leaves().len() as u64);
        for &h in self.hats.leaves() {
            w.f64(h);
        }
    }

    fn load<K: CoagulationKernel>(
        kernel: &K,
        m: u64,
        pop: &Population,
        r: &mut Reader,
    ) -> Result<Self> {
        let bad = |what| Error::Checkpoint { what };
        let changed = match r.u64()? {
            0 => false,
            1 => true,
            _ => return Err(bad("invalid refresh flag")),
        };
        if !m.is_power_of_two() || m < 64 {
            return Err(bad("invalid maximum size"));
        }
        let counts = r.u64s()?;
        if counts.len() as u64 != m
            || counts.iter().try_fold(0u64, |a, &c| a.checked_add(c)) != Some(pop.n)
        {
            return Err(bad("counts do not add up"));
        }
        let mut s = Self::with_size(kernel, &counts, m, pop.memory_budget)?;
        let nb = r.u64()?;
        if nb != s.part.blocks.len() as u64 {
            // (also a checkpoint of a gravitational kernel written before its partition
            // became log-linear, 2026-12-07)
            return Err(bad(
                "block count differs from the partition (a checkpoint of another partition)",
            ));
        }
        let mut leaves = Vec::new();
        try_reserve(&mut leaves, s.part.blocks.len())?;
        for id in 0..s.part.blocks.len() {
            let h = r.f64()?;
            let i = s.intensity_of(id);
            // Î at least I (an overflowed I holds an infinite Î)
            if h.partial_cmp(&i).is_none_or(|o| o.is_lt()) {
                return Err(bad("block majorant outside its band"));
            }
            leaves.push(h);
        }
        s.hats = QuadSums::new(&leaves)?;
        s.allot_all();
        s.changed = changed;
        Ok(s)
    }
}
