//! Low-rank Monte Carlo over particle *sizes*: continuous sizes, or integer sizes however
//! sparse, with memory and cost independent of the largest size.
//!
//! The size-count layouts ([`Bucketed`](super::Bucketed), [`LowRank`](super::LowRank))
//! keep a count for every integer size up to the largest, M. When the distribution is
//! broad — Golovin's kernel from an exponential start discretised finely, where M
//! reaches 2^27 — that array, not the particles, is the memory and the cost of every
//! observation. This scheme keeps the particles themselves:
//!
//! * the sizes `y_1..y_n` (finite, positive doubles; integer sizes are exact below
//!   2^53) in one array, in a volume V (concentration `Σ_i δ_{y_i} / V`, as direct
//!   simulation's);
//! * log-linear *buckets* read off a size's bits: the exponent and the top 5 bits of
//!   the mantissa, so every octave is cut into 32 buckets and a bucket spans at most
//!   1/32 of its lower end (every integer below 64 is a bucket of its own). Each bucket
//!   lists its particles;
//! * a bucket's bound is taken from the particles it holds: `â_k(b)` is the largest
//!   factor `a_k(y)` of the particles that entered it since it was last empty (and
//!   `ǎ_k(b)` the smallest, for the squeeze). No monotonicity of the factors is
//!   assumed: the bound only ever covers the particles present, so `Â(b, c) = Σ_k
//!   â_k(b) b̂_k(c) ≥ A(y_p, y_q)` for every pair in the two buckets;
//! * the weights `â_k(b) n_b` (and `b̂_k(b) n_b`) sit in a binary sum tree over the
//!   buckets whose every node is recomputed from its two children, so the tree is a
//!   function of the buckets alone and never drifts.
//!
//! A proposal picks a component k ∝ `U_k V_k`, a bucket of side u by `â_k n` and one of
//! side v by `b̂_k n` (two descents of a tree of ~2^11 leaves, resident in L2), a
//! uniform particle of each; the pair with itself is rejected, other pairs are accepted
//! with `K/(Â + Âᵀ)`, squeezed with the kernel's acceptance floor. Every ordered pair of
//! distinct particles is thus proposed at rate `Â(b_p, b_q)/V` and an unordered pair
//! coagulates at rate `K/V`, as in the size-count layouts ([`super`] for the rate's
//! derivation). A merge moves three particles between buckets (O(log buckets)); when
//! fewer than `N0/2` particles remain every particle is copied and V doubles
//! (Osinsky's particle doubling). Memory is O(particles + buckets): 16 bytes per
//! particle (28 with the lists' slack, which a shrinking list gives back), and a finite
//! double has at most 65 504 buckets.
//!
//! Proposal times are drawn one exponential per proposal (the size-count layouts'
//! batches are not used), so a run does not depend on where a host stops it.
//!
//! # Example
//! ```
//! use coagula_core::kernel::Coagulation;
//! use coagula_core::observe::Observe;
//! use coagula_core::scheme::{Scheme, lowrank::LowRankSizes};
//! let mut rng = rand_pcg::Pcg64Mcg::new(7);
//! // Golovin's kernel K = x + y from the exponential start c(x, 0) = e^{-x}: 4096
//! // samples of Exp(1) (inverse CDF at a midpoint rule) in volume 4096
//! let n = 4096;
//! let sizes: Vec<f64> = (0..n).map(|i| -(1.0 - (i as f64 + 0.5) / n as f64).ln()).collect();
//! let mut sim = LowRankSizes::<_, 1, 2>::new(Coagulation::additive(), &sizes, n as f64).unwrap();
//! sim.advance_to(1.0, &mut rng).unwrap();
//! // M0(t) = e^{-t}; one run's standard deviation at this N is about 0.006
//! assert!((sim.moment(0.0) - (-1.0f64).exp()).abs() < 0.03);
//! ```

use super::bound::{SUB_BITS, factors_at};
use super::proposal::rank_mismatch;
use super::rule::{SPOT_CHECK, floor_of, thin};
use super::trees::{BinaryTree, ProposalTree, Weights};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::{below, unit_f64};
use crate::scheme::population::{DEFAULT_MEMORY_BUDGET, shrink_spare, try_reserve, within_budget};
use crate::scheme::{Budget, Pending, Scheme, StepReport, check_target, check_time, next_proposal};
use alloc::vec::Vec;
use rand_core::Rng;

mod edit;

/// A size's bucket key: its exponent field and the top `SUB_BITS` bits of its mantissa.
#[inline(always)]
fn key(y: f64) -> u32 {
    (y.to_bits() >> (52 - SUB_BITS)) as u32
}

/// Bytes per particle: the size, its place in its bucket's list and the list entry with
/// its slack (a list's capacity stays below 4 times its length plus 16).
const PARTICLE_BYTES: usize = 8 + 4 + 4 * 4;

/// One bucket: its particles and the bound they set.
#[derive(Clone, Debug, PartialEq)]
struct Bucket<const W: usize> {
    /// The particles (indices into the size array).
    list: Vec<u32>,
    /// Largest factor per row `[a_0 .. a_{R−1}, b_0 .. b_{R−1}]` over the particles that
    /// entered since the bucket was last empty (0 when empty).
    hi: [f64; W],
    /// Smallest factor per row over the same particles (+inf when empty).
    lo: [f64; W],
}

impl<const W: usize> Bucket<W> {
    fn empty() -> Self {
        Bucket {
            list: Vec::new(),
            hi: [0.0; W],
            lo: [f64::INFINITY; W],
        }
    }

    /// Takes the factors `f` of a particle entering the bucket into its bound.
    #[inline]
    fn widen(&mut self, f: &[f64; W]) {
        for r in 0..W {
            self.hi[r] = self.hi[r].max(f[r]);
            self.lo[r] = self.lo[r].min(f[r]);
        }
    }

    /// The tree's leaf: `[â_k n, b̂_k n]`.
    #[inline]
    fn leaf<const R: usize>(&self) -> Weights<R> {
        let n = self.list.len() as f64;
        let mut w = [[0.0; R]; 2];
        for k in 0..R {
            w[0][k] = self.hi[k] * n;
            w[1][k] = self.hi[R + k] * n;
        }
        w
    }
}

/// `Σ_k f_k(u) g_k(v) + f_k(v) g_k(u)` over the rows of two buckets' factor arrays.
#[inline(always)]
fn symmetric<const R: usize, const W: usize>(u: &[f64; W], v: &[f64; W]) -> f64 {
    let mut s = 0.0;
    for k in 0..R {
        s += u[k] * v[R + k] + v[k] * u[R + k];
    }
    s
}

/// The factors of size y as one row array `[a, b]`, validated.
#[inline]
fn row_factors<K: CoagulationKernel + ?Sized, const R: usize, const W: usize>(
    kernel: &K,
    y: f64,
) -> Result<[f64; W]> {
    let (a, b) = factors_at::<K, R>(kernel, y)?;
    let mut f = [0.0; W];
    f[..R].copy_from_slice(&a);
    f[R..].copy_from_slice(&b);
    Ok(f)
}

/// `S_A = Σ_k U_k V_k` of a tree over `n` particles: proposals arrive at rate `S_A / V`
/// (0 below two particles).
#[inline]
fn rate_sum<const R: usize>(tree: &BinaryTree<R>, n: usize) -> f64 {
    if n < 2 {
        return 0.0;
    }
    let t = tree.totals();
    (0..R).map(|k| t[0][k] * t[1][k]).sum()
}

/// Buckets, their particles and the tree over them: everything a state of given sizes
/// determines (built whole, then installed, so a failure changes nothing).
struct Layout<const R: usize, const W: usize> {
    /// The particle sizes.
    sizes: Vec<f64>,
    /// `at[i]`: the place of particle i in its bucket's list.
    at: Vec<u32>,
    /// Bucket `b` holds the sizes of key `base + b`.
    buckets: Vec<Bucket<W>>,
    base: u32,
    tree: BinaryTree<R>,
    leaves: usize,
}

/// The leaf of bucket `b` of `buckets` (zero beyond them).
#[inline]
fn leaf_of<const R: usize, const W: usize>(buckets: &[Bucket<W>], b: usize) -> Weights<R> {
    buckets.get(b).map_or([[0.0; R]; 2], |x| x.leaf::<R>())
}

/// Leaves of a tree over `buckets` buckets (a power of two, at least 8).
fn leaves_for(buckets: usize) -> usize {
    buckets.next_power_of_two().max(8)
}

/// Bytes of a state of `n` particles (room for `cap`) over `buckets` buckets.
fn bytes_for<const R: usize, const W: usize>(cap: usize, buckets: usize) -> Option<usize> {
    let per = core::mem::size_of::<Bucket<W>>() + 16 * 4;
    cap.checked_mul(PARTICLE_BYTES)?
        .checked_add(buckets.checked_mul(per)?)?
        .checked_add(<BinaryTree<R> as ProposalTree<R>>::bytes(leaves_for(
            buckets,
        ))?)
}

impl<const R: usize, const W: usize> Layout<R, W> {
    /// The layout of `sizes` (validated: finite, positive, valid factors) in bucket
    /// order of arrival, within `budget` bytes.
    fn build<K: CoagulationKernel + ?Sized>(
        kernel: &K,
        sizes: &[f64],
        budget: usize,
    ) -> Result<Self> {
        if sizes.is_empty() {
            // (not a capacity: nothing ran out; the bucket layout spans the sizes it
            // holds, so it needs one)
            return Err(Error::Unsupported {
                what: "an empty list of sizes: lowrank-sizes holds at least one particle (dsa and mfa take an empty system)",
            });
        }
        if sizes.len() >= u32::MAX as usize {
            return Err(Error::Capacity {
                name: "particles (below 2^32 - 1)",
                capacity: u32::MAX as usize - 1,
            });
        }
        let mut base = u32::MAX;
        let mut top = 0;
        for &y in sizes {
            crate::error::positive("size", y)?;
            base = base.min(key(y));
            top = top.max(key(y));
        }
        let nb = (top - base + 1) as usize;
        within_budget(bytes_for::<R, W>(sizes.len(), nb), budget)?;
        let mut buckets = Vec::new();
        try_reserve(&mut buckets, nb)?;
        buckets.resize(nb, Bucket::empty());
        let mut at = Vec::new();
        try_reserve(&mut at, sizes.len())?;
        for (i, &y) in sizes.iter().enumerate() {
            let f = row_factors::<K, R, W>(kernel, y)?;
            let b = &mut buckets[(key(y) - base) as usize];
            at.push(b.list.len() as u32);
            try_reserve(&mut b.list, 1)?;
            b.list.push(i as u32);
            b.widen(&f);
        }
        let mut own = Vec::new();
        try_reserve(&mut own, sizes.len())?;
        own.extend_from_slice(sizes);
        let leaves = leaves_for(nb);
        let tree = BinaryTree::build(leaves, |b| {
            buckets.get(b).map_or([[0.0; R]; 2], |x| x.leaf::<R>())
        })?;
        Ok(Layout {
            sizes: own,
            at,
            buckets,
            base,
            tree,
            leaves,
        })
    }
}

/// Low-rank Monte Carlo over particle sizes (see the module docs). `W` must be `2R`.
pub struct LowRankSizes<K, const R: usize, const W: usize> {
    kernel: K,
    /// The kernel's acceptance floor ρ (`K ≥ ρ (Â + Âᵀ)` at the factors).
    floor: f64,
    /// The particles, their buckets and the tree.
    p: Layout<R, W>,
    volume: f64,
    /// Particle doubling happens when fewer than `n0 / 2` particles remain.
    n0: usize,
    /// Whether particle doubling is on (off while processes run).
    doubling: bool,
    memory_budget: usize,
    time: f64,
    pending: Option<Pending>,
    /// Proposals so far (every [`SPOT_CHECK`]-th evaluates the kernel).
    proposals: u64,
    totals: StepReport,
}

impl<K, const R: usize, const W: usize> core::fmt::Debug for LowRankSizes<K, R, W> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("LowRankSizes")
            .field("particles", &self.p.sizes.len())
            .field("buckets", &self.p.buckets.len())
            .field("volume", &self.volume)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> LowRankSizes<K, R, W> {
    /// The particles `sizes` (samples of the initial *number* distribution, each finite
    /// and positive) in volume `volume`, with the default memory budget.
    ///
    /// Errors: no particles, a size or the volume not finite and positive, a kernel
    /// whose low-rank bound is not of rank R (or `W ≠ 2R`), a factor that is negative
    /// or not finite at a size, the memory budget.
    pub fn new(kernel: K, sizes: &[f64], volume: f64) -> Result<Self> {
        Self::new_with_memory_budget(kernel, sizes, volume, DEFAULT_MEMORY_BUDGET)
    }

    /// [`new`](Self::new) with a memory budget of `bytes` (the particles, their buckets
    /// and the tree; a bucket added later is checked against it too).
    pub fn new_with_memory_budget(
        kernel: K,
        sizes: &[f64],
        volume: f64,
        bytes: usize,
    ) -> Result<Self> {
        if W != 2 * R || kernel.rank() != R {
            return Err(rank_mismatch());
        }
        crate::error::positive("volume", volume)?;
        let l = Layout::<R, W>::build(&kernel, sizes, bytes)?;
        Ok(LowRankSizes {
            floor: floor_of(&kernel),
            kernel,
            n0: l.sizes.len(),
            doubling: true,
            p: l,
            volume,
            memory_budget: bytes,
            time: 0.0,
            pending: None,
            proposals: 0,
            totals: StepReport::default(),
        })
    }

    fn install(&mut self, l: Layout<R, W>) {
        self.n0 = l.sizes.len();
        self.p = l;
        self.pending = None;
    }

    /// The particle sizes (in storage order, not sorted).
    pub fn sizes(&self) -> &[f64] {
        &self.p.sizes
    }

    /// The buckets in use (from the smallest size's to the largest's).
    pub fn buckets(&self) -> usize {
        self.p.buckets.len()
    }

    /// Replaces the sizes (each finite and positive; the volume stays, and the
    /// particle-doubling reference becomes their number); the next proposal is drawn
    /// afresh. Nothing changes on error.
    pub fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        let l = Layout::build(&self.kernel, sizes, self.memory_budget)?;
        self.install(l);
        Ok(())
    }

    /// Replaces the coagulation kernel (same rank); every bucket's bound is taken
    /// afresh from the particles it holds. Nothing changes on error.
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        if kernel.rank() != R {
            return Err(rank_mismatch());
        }
        let l = Layout::build(&kernel, &self.p.sizes, self.memory_budget)?;
        self.floor = floor_of(&kernel);
        self.kernel = kernel;
        let n0 = self.n0;
        self.install(l);
        self.n0 = n0;
        Ok(())
    }

    /// Turns particle doubling on or off (not carried by a checkpoint).
    pub fn set_doubling(&mut self, on: bool) {
        self.doubling = on;
    }

    /// Sets the clock (finite, not negative); the next proposal is drawn afresh.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = check_time(t)?;
        self.pending = None;
        Ok(())
    }

    #[inline]
    fn rate_sum(&self) -> f64 {
        rate_sum(&self.p.tree, self.p.sizes.len())
    }

    /// The bucket of key `k`, added (with the tree grown) if it is new; fallible, and
    /// nothing observable changes (empty buckets carry no weight).
    fn bucket_for(&mut self, k: u32) -> Result<usize> {
        let b = k.checked_sub(self.p.base).ok_or(Error::Overflow {
            name: "bucket below the smallest (a size shrank)",
        })? as usize;
        if b < self.p.buckets.len() {
            return Ok(b);
        }
        within_budget(bytes_for::<R, W>(self.n0, b + 1), self.memory_budget)?;
        let more = b + 1 - self.p.buckets.len();
        try_reserve(&mut self.p.buckets, more)?;
        if b >= self.p.leaves {
            let leaves = leaves_for(b + 1);
            let bs = &self.p.buckets;
            let tree = BinaryTree::build(leaves, |i| {
                bs.get(i).map_or([[0.0; R]; 2], |x| x.leaf::<R>())
            })?;
            self.p.tree = tree;
            self.p.leaves = leaves;
        }
        self.p.buckets.resize(b + 1, Bucket::empty());
        Ok(b)
    }

    #[inline]
    fn bucket_of(&self, y: f64) -> usize {
        (key(y) - self.p.base) as usize
    }

    #[inline]
    fn touch(&mut self, b: usize) {
        let leaf = self.p.buckets[b].leaf::<R>();
        self.p.tree.add(b, &leaf, &leaf);
    }

    /// Takes particle i (of size `sizes[i]`, factors `f`) out of its bucket's list.
    #[inline]
    fn leave(&mut self, i: usize) {
        let b = self.bucket_of(self.p.sizes[i]);
        let pos = self.p.at[i] as usize;
        let bucket = &mut self.p.buckets[b];
        bucket.list.swap_remove(pos);
        if let Some(&moved) = bucket.list.get(pos) {
            self.p.at[moved as usize] = pos as u32;
        }
        if bucket.list.is_empty() {
            *bucket = Bucket::empty();
        } else {
            shrink_spare(&mut bucket.list);
        }
        self.touch(b);
    }

    /// Puts particle i into bucket b (room reserved), with its factors `f`.
    #[inline]
    fn enter(&mut self, i: usize, b: usize, f: &[f64; W]) {
        let bucket = &mut self.p.buckets[b];
        self.p.at[i] = bucket.list.len() as u32;
        bucket.list.push(i as u32);
        bucket.widen(f);
        self.touch(b);
    }

    /// Merges particle j into particle i. Nothing changes on error.
    fn merge(&mut self, i: usize, j: usize) -> Result<()> {
        let z = self.p.sizes[i] + self.p.sizes[j];
        if !z.is_finite() {
            return Err(Error::Overflow {
                name: "particle size (a coagulation passed the largest f64)",
            });
        }
        let f = row_factors::<K, R, W>(&self.kernel, z)?;
        let bz = self.bucket_for(key(z))?;
        try_reserve(&mut self.p.buckets[bz].list, 1)?;
        self.leave(i);
        self.p.sizes[i] = z;
        self.enter(i, bz, &f);
        // particle j leaves; the last particle takes its index
        self.leave(j);
        self.take_last_into(j);
        Ok(())
    }

    /// Copies every particle and doubles V (Osinsky's particle doubling). Nothing
    /// changes on error.
    fn double(&mut self) -> Result<()> {
        let volume = 2.0 * self.volume;
        if !volume.is_finite() {
            return Err(Error::Overflow {
                name: "volume (particle doubling passed the largest f64)",
            });
        }
        let n = self.p.sizes.len();
        try_reserve(&mut self.p.sizes, n)?;
        try_reserve(&mut self.p.at, n)?;
        for b in &mut self.p.buckets {
            let len = b.list.len();
            try_reserve(&mut b.list, len)?;
        }
        for i in 0..n {
            let y = self.p.sizes[i];
            let b = self.bucket_of(y);
            let list = &mut self.p.buckets[b].list;
            self.p.at.push(list.len() as u32);
            list.push((n + i) as u32);
            self.p.sizes.push(y);
        }
        let bs = &self.p.buckets;
        self.p.tree.refill(|i| leaf_of::<R, W>(bs, i));
        self.volume = volume;
        Ok(())
    }

    /// One proposal at total `s = S_A`; `Ok(true)` when two particles merged.
    #[inline]
    fn propose<G: Rng + ?Sized>(&mut self, s: f64, rng: &mut G) -> Result<bool> {
        let t = self.p.tree.totals();
        let mut k = 0;
        if R > 1 {
            let mut r = unit_f64(rng.next_u64()) * s;
            while k + 1 < R && r >= t[0][k] * t[1][k] {
                r -= t[0][k] * t[1][k];
                k += 1;
            }
            while k > 0 && t[0][k] * t[1][k] <= 0.0 {
                k -= 1;
            }
        }
        let tu = unit_f64(rng.next_u64()) * t[0][k];
        let tv = unit_f64(rng.next_u64()) * t[1][k];
        let (bu, bv) = self.p.tree.descend_pair(k, tu, tv);
        let (lu, lv) = (&self.p.buckets[bu], &self.p.buckets[bv]);
        if lu.list.is_empty() || lv.list.is_empty() {
            // (a positive leaf holds particles; kept for safety)
            return Ok(false);
        }
        let i = lu.list[below(rng, lu.list.len() as u64) as usize] as usize;
        let j = lv.list[below(rng, lv.list.len() as u64) as usize] as usize;
        if i == j {
            return Ok(false);
        }
        let bound = symmetric::<R, W>(&lu.hi, &lv.hi);
        let low = symmetric::<R, W>(&lu.lo, &lv.lo);
        self.proposals = self.proposals.wrapping_add(1);
        let spot = self.proposals.is_multiple_of(SPOT_CHECK);
        let (x, y) = (self.p.sizes[i], self.p.sizes[j]);
        if !thin(self.floor, &self.kernel, x, y, bound, low, spot, rng)? {
            return Ok(false);
        }
        self.merge(i, j)?;
        Ok(true)
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> Scheme for LowRankSizes<K, R, W> {
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        self.totals
    }

    fn advance_within<G: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport> {
        check_target(self.time, t)?;
        let mut rep = StepReport::default();
        let out = loop {
            if self.doubling && self.p.sizes.len() < self.n0 / 2 {
                if let Err(e) = self.double() {
                    break Err(e);
                }
                rep.doublings += 1;
                budget.doubled(self.time);
                self.pending = None;
            }
            let s = self.rate_sum();
            let rate = s / self.volume;
            if !rate.is_finite() {
                break Err(Error::InvalidRate {
                    name: "total proposal rate (overflows a double)",
                    value: rate,
                });
            }
            let next = next_proposal(
                &mut self.pending,
                &mut self.time,
                t,
                rate,
                budget,
                &mut rep,
                rng,
            );
            let p = match next {
                Ok(Some(p)) => p,
                Ok(None) => break Ok(()),
                Err(e) => break Err(e),
            };
            match self.propose(s, rng) {
                Ok(changed) => {
                    if changed {
                        rep.events += 1;
                    } else {
                        rep.rejections += 1;
                    }
                    self.time = p.at;
                    self.pending = None;
                }
                Err(e) => break Err(e),
            }
        };
        rep.time = self.time;
        self.totals.accumulate(&rep);
        out.map(|()| rep)
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> crate::observe::Observe
    for LowRankSizes<K, R, W>
{
    fn volume(&self) -> f64 {
        self.volume
    }
    fn particles(&self) -> u64 {
        self.p.sizes.len() as u64
    }
    fn moment(&self, order: f64) -> f64 {
        let w = 1.0 / self.volume;
        crate::observe::moment(self.p.sizes.iter().map(|&y| (y, w)), order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        let w = 1.0 / self.volume;
        crate::observe::sum_concentration(self.p.sizes.iter().map(|&y| (y, w)), a, b)
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        let w = 1.0 / self.volume;
        for &x in &self.p.sizes {
            f(x, w);
        }
    }
    /// The largest cluster's mass over V (E–W 6.15).
    fn gel_mass(&self) -> Option<f64> {
        Some(self.p.sizes.iter().copied().fold(0.0, f64::max) / self.volume)
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> crate::checkpoint::Checkpoint
    for LowRankSizes<K, R, W>
{
    fn save(&self, w: &mut Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::LOWRANK_SIZES);
        w.u64(R as u64);
        w.f64(self.volume);
        w.u64(self.n0 as u64);
        w.f64(self.time);
        Pending::save(&self.pending, w);
        self.totals.save(w);
        w.u64(self.proposals);
        w.u64(u64::from(self.p.base));
        w.f64s(&self.p.sizes);
        w.u64(self.p.at.len() as u64);
        for &p in &self.p.at {
            w.u64(u64::from(p));
        }
        w.u64(self.p.buckets.len() as u64);
        for b in &self.p.buckets {
            for r in 0..W {
                w.f64(b.hi[r]);
                w.f64(b.lo[r]);
            }
        }
    }

    fn restore(&mut self, r: &mut Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, tag::LOWRANK_SIZES)?;
        if r.u64()? != R as u64 {
            return Err(bad("another rank"));
        }
        let (volume, n0, time) = (r.f64()?, r.usize()?, r.f64()?);
        if !(volume > 0.0 && volume.is_finite() && time >= 0.0 && time.is_finite()) {
            return Err(bad("invalid volume or time"));
        }
        let pending = Pending::read(r, time)?;
        let totals = StepReport::read(r)?;
        let proposals = r.u64()?;
        let base = u32::try_from(r.u64()?).map_err(|_| bad("invalid bucket base"))?;
        let sizes = r.f64s()?;
        let n = sizes.len();
        if n == 0 || n >= u32::MAX as usize || n0 < n || n0 >= u32::MAX as usize {
            return Err(bad("particle number out of range"));
        }
        let nat = r.usize()?;
        if nat != n {
            return Err(bad("places do not match the particles"));
        }
        let mut at = Vec::new();
        try_reserve(&mut at, n).map_err(|_| bad("cannot allocate the places"))?;
        for _ in 0..n {
            at.push(u32::try_from(r.u64()?).map_err(|_| bad("invalid place"))?);
        }
        let nb = r.usize()?;
        if nb == 0 || nb > (1 << 16) {
            return Err(bad("bucket count out of range"));
        }
        within_budget(bytes_for::<R, W>(n0, nb), self.memory_budget)?;
        let mut buckets: Vec<Bucket<W>> = Vec::new();
        try_reserve(&mut buckets, nb)?;
        for _ in 0..nb {
            let mut b = Bucket::empty();
            for r_ in 0..W {
                b.hi[r_] = r.f64()?;
                b.lo[r_] = r.f64()?;
            }
            buckets.push(b);
        }
        r.finish()?;
        // the lists, from each particle's bucket and place
        let mut len = Vec::new();
        try_reserve(&mut len, nb)?;
        len.resize(nb, 0usize);
        for &y in &sizes {
            if !(y > 0.0 && y.is_finite()) {
                return Err(bad("a size that is not finite and positive"));
            }
            let b = key(y)
                .checked_sub(base)
                .map(|b| b as usize)
                .filter(|&b| b < nb)
                .ok_or(bad("a size outside the buckets"))?;
            len[b] += 1;
        }
        for (b, &l) in buckets.iter_mut().zip(&len) {
            try_reserve(&mut b.list, l)?;
            b.list.resize(l, u32::MAX);
        }
        for (i, (&y, &p)) in sizes.iter().zip(&at).enumerate() {
            let b = &mut buckets[(key(y) - base) as usize];
            match b.list.get_mut(p as usize) {
                Some(slot) if *slot == u32::MAX => *slot = i as u32,
                _ => return Err(bad("places are not a permutation of each bucket")),
            }
            let f = row_factors::<K, R, W>(&self.kernel, y)
                .map_err(|_| bad("a size where the kernel's factors are invalid"))?;
            for (r_, &v) in f.iter().enumerate() {
                if !(b.lo[r_] <= v && v <= b.hi[r_]) {
                    return Err(bad("a bucket's bound does not cover its particles"));
                }
            }
        }
        for b in &buckets {
            let ok = if b.list.is_empty() {
                b.hi == [0.0; W] && b.lo == [f64::INFINITY; W]
            } else {
                b.hi.iter()
                    .zip(&b.lo)
                    .all(|(&h, &l)| h.is_finite() && l >= 0.0 && l <= h)
            };
            if !ok {
                return Err(bad("an invalid bucket bound"));
            }
        }
        let leaves = leaves_for(nb);
        let tree = BinaryTree::build(leaves, |i| {
            buckets.get(i).map_or([[0.0; R]; 2], |x| x.leaf::<R>())
        })?;
        let s = rate_sum(&tree, n);
        crate::scheme::check_pending(&pending, s / volume)?;
        self.p = Layout {
            sizes,
            at,
            buckets,
            base,
            tree,
            leaves,
        };
        self.volume = volume;
        self.n0 = n0;
        self.time = time;
        self.pending = pending;
        self.proposals = proposals;
        self.totals = totals;
        Ok(())
    }
}
