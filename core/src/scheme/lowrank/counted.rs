//! The bucketed layout for small systems: the same buckets and the same bound (each
//! bucket's largest factors), but the proposal weights are the buckets' exact particle
//! counts, `u^k_b = â_k(b) n_b` and `v^k_b = b̂_k(b) n_b`, in an 8-ary sum tree over the
//! buckets (three levels up to 512 buckets, four up to the 897 of 2^32 sizes) that every
//! event updates along three paths.
//!
//! A small system changes its distribution at almost every event. The slot engine
//! ([`BucketedEngine`](super::BucketedEngine)) then keeps growing buckets, refreshing
//! its overflow stream and resyncing and rebuilding its alias tables every few events;
//! here nothing is ever stale: no empty slot, no overflow, no resync, no table to
//! rebuild. A singleton bucket holds only its count; a wider one lists its particles'
//! offsets (a uniform particle is a uniform entry). It holds O(particles + buckets)
//! whatever the largest size M; M is still bounded by the memory budget, at 8 bytes
//! per size, because `counts()` returns a dense vector of M counts.
//!
//! The tree ([`WideTree`], as the per-size layout's) adds each change to its sums and
//! is rebuilt from the counts every [`REBUILD`](super::trees::REBUILD) updates; a
//! checkpoint holds it, so a restored run continues bit for bit.
//!
//! The scheme is [`BucketedCounted`](super::BucketedCounted); the registry's `lowrank`
//! ([`AutoBucketed`](super::AutoBucketed)) runs it for small systems.
//!
//! # Example
//! ```
//! use coagula_core::kernel::Coagulation;
//! use coagula_core::scheme::{Scheme, lowrank::BucketedCounted};
//! let mut rng = rand_pcg::Pcg64Mcg::new(7);
//! // 200 monomers of the constant kernel K = 1: M0(t) = 2 / (2 + t)
//! let k = Coagulation::constant(1.0).unwrap();
//! let mut sum = 0.0;
//! for _ in 0..100 {
//!     let mut sim = BucketedCounted::<_, 1, 2>::monodisperse(k, 200).unwrap();
//!     sim.advance_to(2.0, &mut rng).unwrap();
//!     sum += sim.moment(0.0);
//! }
//! // the mean of 100 runs: M0(2) = 0.5, standard error about 0.0016 (0.01 is 6 of them)
//! assert!((sum / 100.0 - 0.5).abs() < 0.01, "{}", sum / 100.0);
//! ```

use super::bound::{
    MAX_PARTICLES, SINGLE, bucket_extremes, bucket_of, bucket_range, each_in_list, width_bits,
};
use super::proposal::{Candidate, Low, Outcome, ProposalEngine, rank_mismatch};
use super::tree::{check_restored, checked_rate, descend_leaves, tree_rate};
use super::trees::{ProposalTree, Weights, WideTree};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::below;
use crate::scheme::population::{Population, try_reserve, within_budget};
use alloc::borrow::Cow;
use alloc::vec::Vec;
use rand_core::Rng;

/// A bucket and its particle's index in the bucket, on each side of a proposal.
pub type Loc = ((usize, u64), (usize, u64));

/// The counted bucketed proposal engine (see the module docs). `W` must be `2R`.
#[derive(Clone, Debug)]
pub struct CountedEngine<const R: usize, const W: usize> {
    /// Exact factor extremes per bucket, `[max, min]` per row.
    raw: Vec<[[f64; W]; 2]>,
    /// Particles per bucket.
    n: Vec<u64>,
    /// Offsets `x − lo` of the particles of buckets `≥ SINGLE` (index `b − SINGLE`).
    lists: Vec<Vec<u32>>,
    /// Sum tree over the buckets' weights.
    tree: WideTree<R>,
    /// The tree's leaf count (a power of two, at least the buckets).
    leaves: usize,
    /// Current maximum size M (a power of two).
    m: u64,
}

/// Bytes charged to the memory budget for maximum size `m` and up to `n` particles
/// (the doubling reference: doublings fill the lists up to it): the tables over the
/// buckets, the lists, and the dense vector of M counts that `counts()` returns (so
/// that a budget also bounds M, as the slot engine's count array does); `None` past
/// M = 2^36 (list offsets are `u32`).
fn bytes_for<const R: usize, const W: usize>(m: u64, n: u64) -> Option<usize> {
    // (list offsets are u32: a bucket of M at most 2^32 wide)
    if m > 1 << 36 {
        return None;
    }
    let buckets = bucket_of(m) + 1;
    let dense = usize::try_from(m)
        .ok()?
        .checked_mul(core::mem::size_of::<u64>())?;
    let per_bucket = core::mem::size_of::<[[f64; W]; 2]>()
        + core::mem::size_of::<u64>()
        + core::mem::size_of::<Vec<u32>>();
    let tree = <WideTree<R> as ProposalTree<R>>::bytes(leaves_for(buckets))?;
    let lists = usize::try_from(n)
        .ok()?
        .checked_mul(core::mem::size_of::<u32>())?;
    buckets
        .checked_mul(per_bucket)?
        .checked_add(tree)?
        .checked_add(lists)?
        .checked_add(dense)
}

/// The tree's leaves for `nb` buckets (bucket b ≥ 1 is leaf b − 1: bucket 0 holds no
/// size): a power of two, at least 8.
fn leaves_for(nb: usize) -> usize {
    nb.saturating_sub(1).next_power_of_two().max(8)
}

/// The weights of bucket b from its bounds and count (zero past the buckets).
#[inline(always)]
fn leaf_of<const R: usize, const W: usize>(
    raw: &[[[f64; W]; 2]],
    n: &[u64],
    b: usize,
) -> Weights<R> {
    let mut w = [[0.0; R]; 2];
    if let (Some(ext), Some(&n)) = (raw.get(b), n.get(b)) {
        let n = n as f64;
        for k in 0..R {
            w[0][k] = ext[0][k] * n;
            w[1][k] = ext[0][R + k] * n;
        }
    }
    w
}

impl<const R: usize, const W: usize> CountedEngine<R, W> {
    /// The engine over `counts[i − 1] = N_i` (the caller checked the rank and the
    /// particle number).
    fn with_counts<K: CoagulationKernel>(
        kernel: &K,
        counts: &[u64],
        pop: &Population,
    ) -> Result<Self> {
        let m = (counts.len() as u64).next_power_of_two().max(64);
        within_budget(bytes_for::<R, W>(m, pop.n0), pop.memory_budget)?;
        let mut s = Self::empty(kernel, m)?;
        for (i, &c) in counts.iter().enumerate() {
            let x = i as u64 + 1;
            let b = bucket_of(x);
            s.n[b] += c;
            if let Some(list) = b.checked_sub(SINGLE as usize).map(|l| &mut s.lists[l]) {
                let c = usize::try_from(c).map_err(|_| Error::Capacity {
                    name: "particles (address space)",
                    capacity: usize::MAX,
                })?;
                try_reserve(list, c)?;
                list.extend(core::iter::repeat_n((x - bucket_range(b).0) as u32, c));
            }
        }
        s.tree = WideTree::build(s.leaves, |l| s.leaf(l))?;
        Ok(s)
    }

    /// No particles, the bounds of the buckets up to `m`, and a tree to be built.
    fn empty<K: CoagulationKernel>(kernel: &K, m: u64) -> Result<Self> {
        let nb = bucket_of(m) + 1;
        let mut s = CountedEngine {
            raw: Vec::new(),
            n: Vec::new(),
            lists: Vec::new(),
            tree: WideTree::build(8, |_| [[0.0; R]; 2])?,
            leaves: leaves_for(nb),
            m,
        };
        s.extend(kernel, nb)?;
        Ok(s)
    }

    /// Extends the bounds, counts and lists to `nb` buckets (new buckets are empty, so
    /// the caller's tree needs only more leaves); on error nothing has changed.
    fn extend<K: CoagulationKernel>(&mut self, kernel: &K, nb: usize) -> Result<()> {
        let mut raw = Vec::new();
        try_reserve(&mut raw, nb.saturating_sub(self.raw.len()))?;
        for b in self.raw.len()..nb {
            raw.push(bucket_extremes::<K, R, W>(kernel, b)?);
        }
        let lists = nb.saturating_sub(SINGLE as usize);
        try_reserve(&mut self.raw, raw.len())?;
        let (more_n, more_lists) = (
            nb.saturating_sub(self.n.len()),
            lists.saturating_sub(self.lists.len()),
        );
        try_reserve(&mut self.n, more_n)?;
        try_reserve(&mut self.lists, more_lists)?;
        self.raw.extend(raw);
        self.n.resize(nb, 0);
        self.lists.resize_with(lists, Vec::new);
        Ok(())
    }

    /// The weights of leaf `l` (bucket `l + 1`; zero past the buckets).
    #[inline(always)]
    fn leaf(&self, l: usize) -> Weights<R> {
        leaf_of(&self.raw, &self.n, l + 1)
    }

    /// Adds `dn` particles' weights to bucket b's leaf.
    #[inline(always)]
    fn update(&mut self, b: usize, dn: f64) {
        let ext = &self.raw[b][0];
        let mut d = [[0.0; R]; 2];
        for k in 0..R {
            d[0][k] = ext[k] * dn;
            d[1][k] = ext[R + k] * dn;
        }
        self.tree.add(b - 1, &d, &d);
    }

    /// The size in slot `s` of bucket `b` (`s < n_b`).
    #[inline(always)]
    fn occupant(&self, b: usize, s: u64) -> u64 {
        match b.checked_sub(SINGLE as usize) {
            None => b as u64,
            Some(l) => bucket_range(b).0 + u64::from(self.lists[l][s as usize]),
        }
    }

    /// Removes the particle in slot `s` of bucket `b` (the tree is the caller's).
    #[inline(always)]
    fn remove(&mut self, b: usize, s: u64) {
        self.n[b] -= 1;
        if let Some(l) = b.checked_sub(SINGLE as usize) {
            self.lists[l].swap_remove(s as usize);
        }
    }

    /// Adds a particle of size x to its bucket (which exists; the tree is the
    /// caller's), and returns the bucket.
    #[inline(always)]
    fn insert(&mut self, x: u64) -> usize {
        let b = bucket_of(x);
        self.n[b] += 1;
        if let Some(l) = b.checked_sub(SINGLE as usize) {
            self.lists[l].push((x - bucket_range(b).0) as u32);
        }
        b
    }

    /// The proposal rate `S_A`.
    #[inline]
    pub(super) fn rate(&self) -> f64 {
        tree_rate(&self.tree.totals())
    }

    /// Every redundant piece of state agrees (for tests): the lists with the counts,
    /// no particle above M, the tree with one rebuilt from the counts (to rounding).
    #[cfg(test)]
    pub(super) fn check_invariants(&self, n: u64) {
        assert_eq!(self.n.iter().sum::<u64>(), n, "particle number");
        assert_eq!(self.n.len(), bucket_of(self.m) + 1, "buckets");
        for (l, list) in self.lists.iter().enumerate() {
            let b = l + SINGLE as usize;
            assert_eq!(list.len() as u64, self.n[b], "bucket {b} list");
            let lo = bucket_range(b).0;
            assert!(list.iter().all(|&o| lo + u64::from(o) <= self.m));
        }
        let fresh = WideTree::build(self.leaves, |l| self.leaf(l)).unwrap();
        check_restored(&self.tree, &fresh).unwrap();
    }
}

impl<const R: usize, const W: usize> ProposalEngine<R> for CountedEngine<R, W> {
    type Loc = Loc;
    const TAG: u64 = crate::scheme::tag::BUCKETED_COUNTED;
    const LOW: Low = Low::Factors;

    fn build<K: CoagulationKernel>(kernel: &K, counts: &[u64], pop: &Population) -> Result<Self> {
        if kernel.rank() != R || R == 0 || W != 2 * R {
            return Err(rank_mismatch());
        }
        if pop.n0 > MAX_PARTICLES {
            return Err(Error::OutOfRange {
                name: "initial particle number",
                value: pop.n0 as f64,
                range: "[1, 2^32 - 1]",
            });
        }
        Self::with_counts(kernel, counts, pop)
    }

    #[inline]
    fn refresh<G: Rng + ?Sized>(&mut self, _pop: &Population, _rng: &mut G) -> Result<f64> {
        checked_rate(&self.tree.totals())
    }

    /// Buckets u and v from the tree, then a uniform particle of each (a singleton
    /// bucket's slot is drawn only when both sides are in it, for the same-particle
    /// test).
    #[inline]
    fn propose<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Option<Candidate<Loc>> {
        let (lu, lv) = descend_leaves(&self.tree, rng);
        let (bu, bv) = (lu + 1, lv + 1);
        let (nu, nv) = (
            self.n.get(bu).copied().unwrap_or(0),
            self.n.get(bv).copied().unwrap_or(0),
        );
        if nu == 0 || nv == 0 {
            // a ghost weight left by rounding: thinning rejects it
            return None;
        }
        let single = SINGLE as usize;
        let su = if bu >= single || bu == bv {
            below(rng, nu)
        } else {
            0
        };
        let sv = if bv >= single || bu == bv {
            below(rng, nv)
        } else {
            0
        };
        if bu == bv && su == sv {
            // the particle with itself
            return None;
        }
        Some(Candidate {
            x: self.occupant(bu, su),
            y: self.occupant(bv, sv),
            at: ((bu, su), (bv, sv)),
        })
    }

    #[inline]
    fn bounds(&self, &((bu, _), (bv, _)): &Loc) -> (f64, f64) {
        let (gu, gv) = (&self.raw[bu], &self.raw[bv]);
        let (mut bound, mut low) = (0.0, 0.0);
        for k in 0..R {
            bound += gu[0][k] * gv[0][R + k] + gv[0][k] * gu[0][R + k];
            low += gu[1][k] * gv[1][R + k] + gv[1][k] * gu[1][R + k];
        }
        (bound, low)
    }

    /// M doubles when the merged size passes it: the new buckets' bounds and the larger
    /// tree are built before anything changes, so an error leaves the state as it was.
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
            let nb = bucket_of(2 * self.m) + 1;
            within_budget(bytes_for::<R, W>(2 * self.m, pop.n0), pop.memory_budget)?;
            // the larger tree first (the new buckets are empty: zero leaves)
            let leaves = leaves_for(nb);
            let tree = WideTree::build(leaves, |l| self.leaf(l))?;
            self.extend(kernel, nb)?;
            (self.tree, self.leaves) = (tree, leaves);
            self.m *= 2;
        }
        Ok(())
    }

    #[inline]
    fn apply(&mut self, c: &Candidate<Loc>, outcome: &Outcome) {
        let Outcome::Merge { size } = *outcome else {
            return;
        };
        let ((bu, su), (bv, sv)) = c.at;
        // the higher slot first, so a swap-remove cannot move the other
        if bu == bv && su < sv {
            self.remove(bv, sv);
            self.remove(bu, su);
        } else {
            self.remove(bu, su);
            self.remove(bv, sv);
        }
        let bx = self.insert(size);
        // one tree update per bucket touched, with its net change
        let net = |b: usize| {
            f64::from(u8::from(bx == b))
                - f64::from(u8::from(bu == b))
                - f64::from(u8::from(bv == b))
        };
        for (i, b) in [bu, bv, bx].into_iter().enumerate() {
            let first = [bu, bv, bx][..i].iter().all(|&o| o != b);
            let d = net(b);
            if first && d != 0.0 {
                self.update(b, d);
            }
        }
    }

    fn double(&mut self, _pop: &Population) {
        for c in &mut self.n {
            *c *= 2;
        }
        for list in &mut self.lists {
            list.extend_from_within(..);
        }
        // every leaf doubles exactly, and so every sum
        self.tree.double();
    }

    #[inline]
    fn settle(&mut self, _pop: &Population) {
        if self.tree.wants_rebuild() {
            let (raw, n) = (&self.raw, &self.n);
            self.tree.refill(|l| leaf_of(raw, n, l + 1));
        }
    }

    fn counts(&self) -> Cow<'_, [u64]> {
        let mut out = alloc::vec![0u64; self.m as usize];
        self.for_each_count(&mut |x, c| out[x as usize - 1] = c);
        Cow::Owned(out)
    }

    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        for (b, &c) in self.n.iter().enumerate().take(SINGLE as usize) {
            if c > 0 {
                f(b as u64, c);
            }
        }
        let mut scratch = Vec::new();
        for (l, list) in self.lists.iter().enumerate() {
            each_in_list(bucket_range(l + SINGLE as usize).0, list, &mut scratch, f);
        }
    }

    const EDITS: bool = true;

    fn draw_particle<G: Rng + ?Sized>(
        &self,
        by_mass: bool,
        n: u64,
        rng: &mut G,
    ) -> Option<(u64, (usize, u64))> {
        let counts = self.n.iter().copied().enumerate().skip(1);
        // (bounded as the slot engine's draw)
        for _ in 0..crate::random::MAX_TRIES {
            let b =
                crate::scheme::lowrank::edit::pick_bucket(counts.clone(), n, by_mass, self.m, rng)?;
            // a bucket's particles fill its slots 0..n_b: a uniform one
            let s = crate::random::below(rng, self.n[b]);
            let x = self.occupant(b, s);
            if !by_mass || crate::scheme::lowrank::edit::keep_by_mass(b, x, self.m, rng) {
                return Some((x, (b, s)));
            }
        }
        None
    }

    fn remove_particle(&mut self, (b, s): (usize, u64), _x: u64) {
        self.remove(b, s);
        self.update(b, -1.0);
    }

    fn add_particle<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        x: u64,
        pop: &Population,
    ) -> Result<()> {
        while x > self.m {
            let grow = Outcome::Merge { size: self.m + 1 };
            self.prepare(kernel, &grow, pop)?;
        }
        let b = self.insert(x);
        self.update(b, 1.0);
        Ok(())
    }

    fn rate_now(&self) -> Option<f64> {
        Some(self.rate())
    }

    fn max_size(&self) -> u64 {
        self.m
    }

    /// The bucket counts, every list in order and the tree as it is.
    fn save(&self, w: &mut Writer) {
        w.u64s(&self.n);
        for list in &self.lists {
            w.u64(list.len() as u64);
            for &off in list {
                w.u64(u64::from(off));
            }
        }
        self.tree.save(w);
    }

    fn load<K: CoagulationKernel>(
        kernel: &K,
        m: u64,
        pop: &Population,
        r: &mut Reader,
    ) -> Result<Self> {
        let bad = |what| Error::Checkpoint { what };
        // (doubling keeps n below n0; n0 bounds what the lists may grow to)
        if !m.is_power_of_two() || m < 64 || pop.n > pop.n0 || pop.n0 > MAX_PARTICLES {
            return Err(bad("invalid maximum size or particle number"));
        }
        let nb = bucket_of(m) + 1;
        within_budget(bytes_for::<R, W>(m, pop.n0), pop.memory_budget)?;
        let n = r.u64s()?;
        if n.len() != nb
            || n[0] != 0
            || n.iter().try_fold(0u64, |a, &c| a.checked_add(c)) != Some(pop.n)
            || n[..(SINGLE as usize).min(nb)]
                .iter()
                .enumerate()
                .any(|(b, &c)| c > 0 && b as u64 > m)
        {
            return Err(bad("bucket counts do not add up"));
        }
        let mut s = Self::empty(kernel, m)?;
        for (l, list) in s.lists.iter_mut().enumerate() {
            let b = l + SINGLE as usize;
            let len = r.usize()?;
            if len as u64 != n[b] {
                return Err(bad("bucket list of another length"));
            }
            let (lo, width) = (bucket_range(b).0, 1u64 << width_bits(b));
            try_reserve(list, len)?;
            for _ in 0..len {
                let off = r.u64()?;
                // (the bucket of M runs past M: no particle is larger than M)
                if off >= width || lo + off > m {
                    return Err(bad("list offset outside its bucket"));
                }
                list.push(off as u32);
            }
        }
        s.n = n;
        let tree = WideTree::load(s.leaves, r)?;
        check_restored(&tree, &WideTree::build(s.leaves, |l| s.leaf(l))?)?;
        // (a rate that overflows is a state the scheme holds: it refuses to advance it)
        s.tree = tree;
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Coagulation;

    /// Every ordered pair of distinct particles is proposed at its bound's rate
    /// `Σ_k â_k(b(x)) b̂_k(b(y))`, and a particle with itself (rejected) at its own: 2·10^6
    /// proposals from a spread of sizes over singleton and wide buckets, tallied per
    /// ordered size pair, against those rates by a chi-square test. A factor 2 on one
    /// side, a non-uniform slot or a bucket's wrong count moves it by tens of SE.
    fn proposals_match_the_pair_rates<K: CoagulationKernel, const R: usize, const W: usize>(
        kernel: K,
        seed: u64,
    ) {
        let init: Vec<u64> = (0..300u64)
            .map(|i| (1 + (i * 7) % 13) * u64::from(i % 3 != 1))
            .collect();
        let pop = Population::new(&init, 1000.0).unwrap();
        let mut s = CountedEngine::<R, W>::with_counts(&kernel, &init, &pop).unwrap();
        let mut rng = <rand_pcg::Pcg64Mcg as rand_core::SeedableRng>::seed_from_u64(seed);
        let m = init.len();
        let none = m * m;
        let rate = |x: usize, y: usize| {
            let (eu, ev) = (
                bucket_extremes::<K, R, W>(&kernel, bucket_of(x as u64)).unwrap(),
                bucket_extremes::<K, R, W>(&kernel, bucket_of(y as u64)).unwrap(),
            );
            (0..R).map(|k| eu[0][k] * ev[0][R + k]).sum::<f64>()
        };
        let mut obs = alloc::vec![0u64; m * m + 1];
        let draws = 2_000_000u64;
        for _ in 0..draws {
            match s.propose(&mut rng) {
                Some(c) => {
                    assert_eq!(c.x, s.occupant(c.at.0.0, c.at.0.1));
                    // the thinning bound is the proposal rate of the pair, both ways
                    let want = rate(c.x as usize, c.y as usize) + rate(c.y as usize, c.x as usize);
                    let got = s.bounds(&c.at).0;
                    assert!((got - want).abs() <= 1e-12 * want, "bound {got} vs {want}");
                    obs[(c.x as usize - 1) * m + c.y as usize - 1] += 1;
                }
                None => obs[none] += 1,
            }
        }
        let mut exp = alloc::vec![0.0f64; m * m + 1];
        for x in 1..=m {
            for y in 1..=m {
                let (nx, ny) = (init[x - 1] as f64, init[y - 1] as f64);
                let r = rate(x, y);
                exp[(x - 1) * m + y - 1] = nx * (ny - f64::from(u8::from(x == y))).max(0.0) * r;
            }
            exp[none] += init[x - 1] as f64 * rate(x, x);
        }
        let df = super::super::tests::assert_chi_square(&obs, &exp, draws);
        assert!(df > 1000.0, "{df} cells");
    }

    /// Every redundant piece of state agrees with the counts after every step, through
    /// M doublings and particle doublings, for small and long-running systems (as the
    /// slot engine's `small_systems_keep_their_weights_bounded`).
    #[test]
    fn invariants_hold_through_growth_and_doubling() {
        super::super::tests::through_small_systems::<CountedEngine<1, 2>, CountedEngine<2, 4>>(
            |s| s.engine.check_invariants(s.particles()),
            |s| s.engine.check_invariants(s.particles()),
        );
    }

    /// Only the same-particle draws (1/N of a bucket's self-pairs) are rejected for an
    /// exact bound: the acceptance of the constant kernel from N0 monomers to t = 64 is
    /// above 0.9 (measured 0.956 at N0 = 32; the slot engine's 0.65).
    #[test]
    fn small_systems_accept_almost_every_proposal() {
        for n0 in [32u64, 128, 256] {
            let acc = super::super::tests::small_system_acceptance::<CountedEngine<1, 2>>(n0);
            assert!(acc > 0.9, "N0 = {n0}: acceptance {acc}");
        }
    }

    #[test]
    fn proposals_match_the_pair_rates_rank1() {
        proposals_match_the_pair_rates::<_, 1, 2>(Coagulation::additive(), 31);
    }

    #[test]
    fn proposals_match_the_pair_rates_rank3() {
        let k = Coagulation::free_molecular().with_min_size(1.0).unwrap();
        proposals_match_the_pair_rates::<_, 3, 6>(k, 32);
    }
}
