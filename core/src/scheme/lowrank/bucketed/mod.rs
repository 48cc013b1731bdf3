//! Low-rank Monte Carlo over size *buckets*: the default, fastest layout.
//!
//! The paper's algorithm keeps one weight per integer size in segment trees of M leaves;
//! at M = 2^22 those trees (and the factor tables beside them) are hundreds of
//! megabytes, and every collision walks three root-to-leaf paths of 2R rows through
//! them. This layout keeps the same proposal scheme but coarsens the *bound*:
//!
//! * Sizes are grouped into log-linear buckets: every size below 64 is its own bucket;
//!   above, each octave `[2^g, 2^{g+1})` is cut into 32 buckets of equal width, so a
//!   bucket spans at most 1/32 of its lower end. 2^32 sizes need 897 buckets.
//! * The bound uses each bucket's largest factor, `â_k(x) = max_{y ∈ bucket(x)} a_k(y)`
//!   (and likewise b̂), so `Â = Σ_k â_k b̂_kᵀ ≥ A` is still rank R and `K ≤ Â + Âᵀ`. The
//!   acceptance `K/(Â + Âᵀ)` absorbs the coarsening; a bucket is at most 3 % wide, so
//!   for power-law factors the acceptance drops by a few per cent at most. For kernels
//!   whose bound is exact (`K = A + Aᵀ`), a squeeze with the buckets' smallest factors
//!   decides almost every proposal without evaluating K.
//! * The factors are quantised upwards to integers, `â = q · s_row`, so every weight
//!   `q · slots` and every row total is an exact `u64`: no rounding drift and no ghost
//!   weights.
//! * Proposals come from Walker alias tables over the buckets (≤ ~900 columns, so they
//!   sit in L1/L2 whatever M is): one random word picks the component k *and* side u's
//!   bucket from a joint table over (k, bucket) pairs, a second picks side v's bucket
//!   from component k's table. The tables are rebuilt, O(buckets), only at resyncs,
//!   particle doublings, M doublings and when the overflow (below) gets large: about
//!   once per 40 000 collisions on the paper's rows.
//! * A bucket holds *slots*, at least as many as its particles. A proposal picks a
//!   uniform slot of the chosen bucket and is rejected when the slot is empty; every real
//!   pair keeps its proposal rate `Â/V`, so this is exact thinning. Removals therefore
//!   never change a weight, a new particle usually fills a free slot (a full bucket grows
//!   by 1/16), and the slots are reset to the particles (a *resync*) when the
//!   empties left by removals pass 1/64 of a row's weight, at every particle doubling,
//!   and — an O(1) test per event — when the slots pass `3n/2` (this bounds every
//!   alias weight below `5 · 2^60`, checked in release builds) or the removals' empties
//!   pass `n/8` (what keeps a small system's acceptance high). An empty singleton
//!   bucket keeps no slot.
//! * Slots grown since the tables were built form an *overflow*: the proposal process
//!   splits exactly into a main stream (pairs of slots the tables know, `Σ_k M_k
//!   M_{R+k}` in row weights) and an overflow stream (pairs with a grown slot, `Σ_k
//!   (O_k T_{R+k} + M_k O_{R+k})`, `T = M + O`). A geometric countdown says which
//!   stream each proposal belongs to; the overflow stream scans its ≤ 32 buckets. A
//!   growth thus costs a rate update instead of a rebuild, which lets buckets grow by
//!   1/16 and resync at 1/64 of empties. Below 4096 particles the overflow may carry
//!   half the rate before a rebuild (1/16 above).
//! * A bucket is in *grid* mode (slot = (size x, level ℓ), full iff ℓ < N_x, read from a
//!   `u32` count array — right when at least 3/4 of its slots are full) or in *list* mode
//!   (slot s = the s-th entry of a list of its particles' offsets — right for sparse
//!   buckets in the tail). The mode is chosen at each resync.
//! * The acceptance `K/(Â + Âᵀ)` is squeezed with the kernel's
//!   [floor](crate::kernel::CoagulationKernel::low_rank_floor) ρ (`K ≥ ρ (A + Aᵀ)`): a
//!   uniform below ρ times the bound built from the buckets' smallest factors accepts
//!   without evaluating K (ρ = 1 for exact bounds, 1/√2 for the ballistic kernel).
//!
//! A proposal costs two alias draws, up to two slot draws and reads and a squeeze; a
//! collision adds O(1) count/list work — independent of M. Once the slots or the count
//! array are beyond the caches, whole proposals are drawn a few ahead (both slots
//! always) and their slots prefetched; the queue of them is part of the checkpoint.
//! Proposal times come in batches (see `clock`): one gamma variate per batch, not an
//! exponential per proposal (below 4096 particles, where almost every event changes the
//! rates, one ziggurat exponential per proposal).
//!
//! **Small systems.** A small system changes its distribution at almost every event,
//! so this engine keeps growing buckets and resyncing and rebuilding its tables (a
//! 1000-particle run paid 2–3× the per-event cost of a 10^6-particle one). The
//! [`CountedEngine`](super::CountedEngine) keeps the same buckets and bound with the
//! buckets' exact counts in a sum tree instead; the registry's `lowrank` scheme
//! ([`AutoBucketed`](super::AutoBucketed)) runs it up to
//! [`COUNTED_UP_TO`](super::COUNTED_UP_TO) initial particles.
//!
//! Why the layout is shaped so — the measurements behind each step — is in
//! `docs/design/bucketed-layout.md`.
//!
//! This is the proposal engine [`BucketedEngine`]; the scheme is
//! [`Bucketed`](super::Bucketed), the event loop of [`LowRankMc`](super::LowRankMc) with
//! the coagulation rule over it. M doubling and particle doubling work as for
//! [`LowRank`](super::LowRank). Allocation happens when M doubles, when the particles
//! double, and when a bucket's list outgrows its capacity (amortised).
//!
//! # Example
//! ```
//! use coagula_core::kernel::Coagulation;
//! use coagula_core::scheme::{Scheme, lowrank::Bucketed};
//! let mut rng = rand_pcg::Pcg64Mcg::new(7);
//! // additive kernel K = x + y (rank 1: W = 2R = 2) from 10^4 monomers:
//! // M0(t) = e^{-t}
//! let mut sim = Bucketed::<_, 1, 2>::monodisperse(Coagulation::additive(), 10_000).unwrap();
//! sim.advance_to(1.0, &mut rng).unwrap();
//! // one run's standard deviation is 4.3e-3: 0.025 is 5.8 of them
//! assert!((sim.moment(0.0) - (-1.0f64).exp()).abs() < 0.025);
//! ```

use super::bound::{
    MAX_PARTICLES, SINGLE, bucket_extremes, bucket_of, bucket_range, count_len, each_in_list,
    quantise_up, quantum, width_bits,
};
use super::proposal::{Candidate, Low, Outcome, ProposalEngine, rank_mismatch};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::{below, geometric, open_unit};
use crate::sample::alias::{Alias, AliasScratch};
use crate::scheme::population::{Population, shrink_spare, try_reserve, within_budget};
use alloc::borrow::Cow;
use alloc::vec;
use alloc::vec::Vec;
use rand_core::Rng;

/// A full bucket grows by 1/2^GROW of its slots.
const GROW: u32 = 4;
/// One bucket: its particles, slots and bound data for the `2R` factor rows
/// `[a_0 .. a_{R−1}, b_0 .. b_{R−1}]`, kept together so a proposal touches one record.
///
/// A bucket is either in *grid* mode — its slots are `width × cap` pairs (size x, level
/// ℓ) and slot (x, ℓ) holds a particle iff `ℓ < N_x` — or in *list* mode, where slot s
/// holds the particle `lists[..][s]` if `s < len`. Removals never touch the tables (the
/// slot empties); an addition takes a free slot or grows the bucket.
#[derive(Clone, Copy, Debug)]
struct Bucket<const W: usize> {
    /// Slots (`≥ n`); the tables' weights are `q · slots`. A proposal picks a uniform
    /// slot of the chosen bucket and is rejected when the slot is empty — exact
    /// thinning, since every real pair keeps its proposal rate `Â/V`.
    slots: u64,
    /// Slots the proposal tables were built with (`≤ slots`): the main stream draws
    /// slots below `tab`, the overflow stream the ones grown since (`tab..slots`).
    tab: u64,
    /// Particles.
    n: u64,
    /// Grid mode: the level count `cap ≥ max N_x` (0 for an empty singleton bucket,
    /// which then has no slots).
    cap: u64,
    /// Smallest size of the bucket.
    lo: u64,
    /// Particles when the bucket's mode was last judged from its counts (a list
    /// bucket is judged again only when this changed by more than 1/8).
    judged: u64,
    /// log2 of the bucket's width.
    sh: u32,
    /// Grid mode (else list mode; buckets below `SINGLE` are always grids).
    grid: bool,
    /// Quantised largest factor (table weight of one particle).
    q: [u64; W],
    /// `q · scale`: the bound's factor as a double.
    hi: [f64; W],
    /// Smallest factor over the bucket (for the squeeze).
    min: [f64; W],
}

/// The bucketed proposal engine (see the module docs). `W` must be `2R`.
pub struct BucketedEngine<const R: usize, const W: usize> {
    /// Exact factor extremes per bucket, before quantisation: `[max, min]`.
    raw: Vec<[[f64; W]; 2]>,
    buckets: Vec<Bucket<W>>,
    scale: [f64; W],
    /// Largest quantised factor: `qmax · n0 ≤ 2^60`. The resync rules keep the slots
    /// below `5 n ≤ 5 n0` (see [`Bucketed::n_resync`]), so every row weight stays below
    /// `5 · 2^60 < 2^63`; the sums are also computed with checked arithmetic.
    qmax: u64,
    /// `counts[x] = N_x` for the sizes `x` of grid-mode buckets (`counts[0]` unused).
    /// A list-mode bucket's particles live only in its list (one memory access less
    /// per event at large M); its entries here are stale until a resync restores them.
    counts: Vec<u32>,
    /// Offsets `x − lo` of the particles of list-mode buckets `≥ SINGLE` (index
    /// `b − SINGLE`).
    lists: Vec<Vec<u32>>,
    /// `Σ_b q_r(b) slots_b` per row: the tables' weight, kept current on every change.
    row_total: [u64; W],
    /// Planned empty-slot weight per row: the empties at the last resync plus the
    /// headroom of later growth (removals' empties come on top).
    base_slack: [u64; W],
    /// Side u: one table over (component k, bucket b) pairs, id `k · 2^16 + b`,
    /// weight ∝ `â_k(b) slots_b Σ_j b̂_k(j) slots_j`, so one draw picks both.
    joint: Alias,
    /// Side v: one table over the buckets per component, weight `q_{R+k}(b) tab_b`.
    side_v: Vec<Alias>,
    /// Side u per component, weight `q_k(b) tab_b` (for the overflow stream; built
    /// only for `R > 1` — with one component the joint table is side u's).
    side_u: Vec<Alias>,
    /// `Σ_b q_r(b) tab_b`: the rows' weights as the tables have them.
    main: [u64; W],
    /// Buckets grown since the tables were built (`slots > tab`).
    over: heapless::Vec<usize, OVER_MAX>,
    /// Rate of the overflow stream (pairs with a grown slot), in the units of `S_A`.
    over_rate: f64,
    /// Probability that a proposal belongs to the overflow stream.
    over_p: f64,
    /// Main-stream proposals before the next overflow one (geometric).
    countdown: u64,
    /// A bucket grew: the rates (not the tables) must be recomputed.
    rates_changed: bool,
    scratch: AliasScratch,
    /// The next proposals' slots, drawn ahead so their memory can be prefetched.
    ahead: heapless::Deque<Ahead, { AHEAD + 1 }>,
    /// Draw proposals ahead (the count array is at least [`PIPELINE_COUNTS`] long, or
    /// the slots at least [`PIPELINE_SLOTS`]).
    pipeline: bool,
    /// Events since the last resync.
    since_resync: u64,
    /// `Σ_b slots_b`.
    slots_total: u64,
    /// Planned empty slots: the grid empties at the last resync plus the headroom of
    /// later growth (removals' empties come on top).
    planned: u64,
    /// A resync is due (checked in the cold path) once the particle number falls below
    /// this: the slots then exceed `3n/2` (the hard rule that bounds every weight) or
    /// the empties left by removals exceed `n/8` (the rule that keeps small systems'
    /// acceptance high). Recomputed whenever the slots change.
    n_resync: u64,
    /// An internal integer invariant failed (a weight would pass 2^63): every later
    /// call returns this error instead of a wrong result.
    poisoned: Option<Error>,
    /// Weights changed since the tables and `S_A` were last built.
    rates_stale: bool,
    /// Current maximum size M (a power of two).
    m: u64,
}

impl<const R: usize, const W: usize> core::fmt::Debug for BucketedEngine<R, W> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("BucketedEngine")
            .field("rank", &R)
            .field("max_size", &self.m)
            .field("buckets", &self.buckets.len())
            .finish_non_exhaustive()
    }
}

/// Counts a list bucket's particles into `cs` (indexed by offset from the bucket's
/// smallest size), overwriting what was there.
fn tally<T: Copy + From<u8> + core::ops::AddAssign>(cs: &mut [T], list: &[u32]) {
    cs.fill(T::from(0));
    for &off in list {
        cs[off as usize] += T::from(1);
    }
}

/// Count-array length (1 MiB of `u32`) from which proposals are drawn ahead and
/// prefetched (`docs/design/bucketed-layout.md`).
const PIPELINE_COUNTS: usize = 1 << 18;
/// Slots (4 MiB of list entries) from which proposals are drawn ahead: the lists are
/// then beyond the caches.
const PIPELINE_SLOTS: u64 = 1 << 20;
/// Proposals drawn ahead in a pipeline.
const AHEAD: usize = 4;

/// A main-stream proposal drawn ahead: component k, side u's bucket and slot, side v's
/// bucket and slot (its slot drawn whatever the bucket: it may fill or empty before
/// the draw is used).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Ahead {
    k: usize,
    bu: usize,
    su: u64,
    bv: usize,
    sv: u64,
}

/// Hints the cache to fetch `r` (no effect on the program's meaning).
#[inline(always)]
fn prefetch<T>(r: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint — it never faults and reads nothing the program
    // sees; the pointer comes from a live reference.
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(
            (r as *const T).cast::<i8>(),
        );
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = r;
}

/// The two proposal streams' rates, in the units of `S_A`.
#[derive(Clone, Copy, Debug)]
struct StreamRates {
    over: f64,
    total: f64,
}

/// Below this many particles the overflow stream may carry up to half the proposal
/// rate before the tables are rebuilt (above, 1/16).
const SMALL_N: u64 = 4096;

/// Most buckets in the overflow before the tables are rebuilt (each overflow proposal
/// scans them).
const OVER_MAX: usize = 32;

impl<const R: usize, const W: usize> BucketedEngine<R, W> {
    /// Whether proposals are drawn ahead (for tests).
    #[cfg(test)]
    pub(super) fn pipelined(&self) -> bool {
        self.pipeline
    }

    /// The engine over `counts[i − 1] = N_i` (see [`ProposalEngine::build`]); the
    /// doubling reference `pop.n0` sets the quantisation (`qmax · n0 ≤ 2^60`).
    fn with_counts<K: CoagulationKernel>(
        kernel: &K,
        counts: &[u64],
        pop: &Population,
    ) -> Result<Self> {
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
        let m = (counts.len() as u64).next_power_of_two().max(64);
        within_budget(
            count_len(m).checked_mul(core::mem::size_of::<u32>()),
            pop.memory_budget,
        )?;
        let mut s = BucketedEngine {
            raw: Vec::new(),
            buckets: Vec::new(),
            scale: [1.0; W],
            qmax: ((1u64 << 60) / pop.n0.max(1)).min(1 << 53),
            counts: Vec::new(),
            lists: Vec::new(),
            row_total: [0; W],
            base_slack: [0; W],
            joint: Alias::default(),
            side_v: vec![Alias::default(); R],
            side_u: vec![Alias::default(); if R > 1 { R } else { 0 }],
            main: [0; W],
            over: heapless::Vec::new(),
            over_rate: 0.0,
            over_p: 0.0,
            countdown: u64::MAX,
            rates_changed: false,
            scratch: AliasScratch::default(),
            ahead: heapless::Deque::new(),
            pipeline: false,
            since_resync: 0,
            slots_total: 0,
            planned: 0,
            n_resync: 0,
            poisoned: None,
            rates_stale: true,
            m,
        };
        crate::scheme::population::try_resize(&mut s.counts, count_len(m), 0)?;
        s.extend_buckets(kernel, m)?;
        for (i, &c) in counts.iter().enumerate() {
            s.counts[i + 1] = c as u32;
            s.buckets[bucket_of(i as u64 + 1)].n += c;
        }
        s.requantise();
        Ok(s)
    }

    /// Computes the exact factor extremes of the buckets needed for sizes up to `m`
    /// (every size of a bucket is evaluated, or its two ends when the kernel's factors
    /// are monotone: see `bound::bucket_extremes`).
    fn extend_buckets<K: CoagulationKernel>(&mut self, kernel: &K, m: u64) -> Result<()> {
        let nb = bucket_of(m) + 1;
        let mut raw = Vec::new();
        try_reserve(&mut raw, nb.saturating_sub(self.raw.len()))?;
        for b in self.raw.len()..nb {
            raw.push(bucket_extremes::<K, R, W>(kernel, b)?);
        }
        self.raw.extend(raw);
        for b in self.buckets.len()..nb {
            self.buckets.push(Bucket {
                // grid mode (its counts are valid) until the resync that always
                // follows
                slots: 0,
                tab: 0,
                n: 0,
                cap: 0,
                grid: true,
                judged: 0,
                lo: if b == 0 { 0 } else { bucket_range(b).0 },
                sh: width_bits(b),
                q: [0; W],
                hi: [0.0; W],
                min: [0.0; W],
            });
        }
        self.lists
            .resize_with(nb.saturating_sub(SINGLE as usize), Vec::new);
        Ok(())
    }

    /// Re-derives the quantised bounds from `raw` and resyncs the buckets.
    fn requantise(&mut self) {
        self.quantise();
        self.resync();
    }

    /// The quantised bounds (`scale`, and each bucket's `q`, `hi`, `min`) from `raw`.
    fn quantise(&mut self) {
        let mut fmax = [0.0f64; W];
        for ext in &self.raw {
            for r in 0..W {
                fmax[r] = fmax[r].max(ext[0][r]);
            }
        }
        // a power of two, so integer-valued factors quantise exactly: then a pair of
        // singleton buckets has bound = squeeze and needs no acceptance draw
        for r in 0..W {
            self.scale[r] = quantum(fmax[r], self.qmax);
        }
        for (bk, ext) in self.buckets.iter_mut().zip(&self.raw) {
            bk.min = ext[1];
            for r in 0..W {
                let q = quantise_up(ext[0][r], self.scale[r]);
                bk.q[r] = q;
                bk.hi[r] = q as f64 * self.scale[r];
            }
        }
    }

    /// Rebuilds the buckets: each bucket takes grid mode when at least 3/4 of its
    /// `width × max N_x` slots are full, list mode otherwise; the empty slots of lazy
    /// removals are dropped. A list bucket too sparse for a grid whatever its counts
    /// (`4n < 3 · width`) keeps its list as it is (a list has no empties) without
    /// reading the counts, so a resync costs O(grid sizes + particles in near-dense
    /// lists), not O(M).
    fn resync(&mut self) {
        self.since_resync = 0;
        for b in 1..self.buckets.len() {
            let width = 1u64 << width_bits(b);
            let (lo, hi) = bucket_range(b);
            if !self.buckets[b].grid {
                let bk = &mut self.buckets[b];
                // too sparse for a grid, or judged a list at a similar size before
                if 4 * bk.n < 3 * width || bk.n.abs_diff(bk.judged) <= bk.judged >> 3 {
                    bk.slots = bk.n;
                    // a list the distribution has moved past gives its memory back
                    shrink_spare(&mut self.lists[b - SINGLE as usize]);
                    continue;
                }
                // restore the counts from the list, to judge the bucket
                tally(
                    &mut self.counts[lo as usize..=hi as usize],
                    &self.lists[b - SINGLE as usize],
                );
            }
            let cs = &self.counts[lo as usize..=hi as usize];
            let n: u64 = cs.iter().map(|&c| u64::from(c)).sum();
            let mx = u64::from(cs.iter().copied().max().unwrap_or(0));
            let bk = &mut self.buckets[b];
            debug_assert_eq!(n, bk.n);
            bk.judged = n;
            if b < SINGLE as usize || (n > 0 && 4 * n >= 3 * width * mx) {
                // an empty singleton keeps no slot: its weight would only make
                // proposals land on nothing
                bk.grid = true;
                bk.cap = mx;
                bk.slots = width * bk.cap;
                if b >= SINGLE as usize {
                    // a grid bucket keeps no list (rebuilt from the counts if it turns
                    // back into one)
                    let list = &mut self.lists[b - SINGLE as usize];
                    list.clear();
                    shrink_spare(list);
                }
            } else {
                bk.grid = false;
                bk.cap = 0;
                let list = &mut self.lists[b - SINGLE as usize];
                list.clear();
                for (off, &c) in cs.iter().enumerate() {
                    list.extend(core::iter::repeat_n(off as u32, c as usize));
                }
                shrink_spare(list);
                bk.slots = n;
            }
        }
        // (the bucket counts, not `self.n`: M doubles in the middle of an event, with
        // the colliding pair removed and the merged particle not yet inserted)
        let particles: u64 = self.buckets.iter().map(|bk| bk.n).sum();
        self.slots_total = self.buckets.iter().map(|bk| bk.slots).sum();
        self.planned = self.slots_total - particles;
        for r in 0..W {
            match (self.weight(r, |bk| bk.slots), self.weight(r, |bk| bk.n)) {
                (Some(total), Some(live)) => {
                    self.row_total[r] = total;
                    self.base_slack[r] = total - live;
                }
                _ => self.poison(),
            }
        }
        self.set_resync_threshold();
        self.rates_stale = true;
    }

    /// `Σ_b q_r(b) f(b)` in checked arithmetic, `None` when it reaches 2^63 (the alias
    /// tables' limit).
    fn weight(&self, r: usize, f: impl Fn(&Bucket<W>) -> u64) -> Option<u64> {
        let mut sum = 0u64;
        for bk in &self.buckets {
            sum = sum.checked_add(bk.q[r].checked_mul(f(bk))?)?;
        }
        (sum < 1 << 63).then_some(sum)
    }

    /// Records a failed integer invariant (see `poisoned`).
    #[cold]
    fn poison(&mut self) {
        self.poisoned = Some(Error::Overflow {
            name: "bucketed low-rank: slot weights (internal invariant)",
        });
    }

    /// The particle number below which a resync is due (see `n_resync`): the slots
    /// pass `3n/2`, or the removals' empties `slots − n − planned` pass `n/8`.
    fn set_resync_threshold(&mut self) {
        let hard = (2 * self.slots_total).div_ceil(3);
        let soft = (8 * self.slots_total.saturating_sub(self.planned)).div_ceil(9);
        self.n_resync = hard.max(soft);
    }

    /// Doubles every count, N and V, then resyncs: the doubled particles get their
    /// slots afresh (doubling the slots would double the empties too, and without a
    /// resync they would pile up doubling after doubling).
    #[cold]
    fn double_particles(&mut self) {
        // (saturating: the entries of list-mode buckets are stale, restored at the
        // resync below, and may hold any value — a stale count doubled over many
        // doublings passed 2^32, found by fuzzing; grid counts are at most n < 2^31)
        for c in &mut self.counts {
            *c = c.saturating_mul(2);
        }
        for bk in &mut self.buckets {
            bk.n *= 2;
            bk.judged = bk.judged.saturating_mul(2);
        }
        for l in &mut self.lists {
            l.extend_from_within(..);
        }
        self.resync();
    }

    /// Merges candidate `c` into one particle of size x (M already prepared).
    #[inline(always)]
    fn merge(&mut self, c: &Candidate<Loc>, x: u64) {
        let ((bu, su), (bv, sv)) = c.at;
        let grows = x > self.m;
        // list removals: the higher position first, so a swap-remove cannot move the other
        let ((b1, s1, x1), (b2, s2, x2)) = if bu == bv && su < sv {
            ((bv, sv, c.y), (bu, su, c.x))
        } else {
            ((bu, su, c.x), (bv, sv, c.y))
        };
        self.remove(b1, s1, x1);
        self.remove(b2, s2, x2);
        if grows {
            self.double_m();
        }
        self.insert(x);
    }

    /// After an event: resync once the slots pass `3n/2` or the removals' empties
    /// `n/8` (an O(1) test), and every 256 events once the empties left by removals pass
    /// 1/64 of a row's weight — but no sooner than M/64 events after the last one, so
    /// the O(M) resync stays O(1) per event when M ≫ N.
    #[inline(always)]
    fn after_event(&mut self, n: u64) {
        self.since_resync += 1;
        if n < self.n_resync {
            self.resync_for_slots(n);
        } else if n & 255 == 0 && self.since_resync >= self.counts.len() as u64 >> 6 {
            self.resync_if_sparse();
        }
    }

    /// The slots have passed `3n/2` (resync now: this bounds every weight) or the
    /// removals' empties `n/8` (resync once a quarter of the buckets' count of events
    /// has passed since the last one, so the O(buckets) resync stays O(1) per event).
    #[cold]
    fn resync_for_slots(&mut self, n: u64) {
        if 2 * self.slots_total > 3 * n
            || self.since_resync >= (self.buckets.len() as u64).div_ceil(4)
        {
            self.resync();
        }
    }

    /// Checks the memory budget for maximum size `m` and reserves the count array
    /// (before the event changes anything).
    #[cold]
    fn reserve_m(&mut self, m: u64, budget: usize) -> Result<()> {
        let len = count_len(m);
        within_budget(len.checked_mul(core::mem::size_of::<u32>()), budget)?;
        let more = len.saturating_sub(self.counts.len());
        try_reserve(&mut self.counts, more)
    }

    /// Doubles M (the new buckets' factors are already computed).
    #[cold]
    fn double_m(&mut self) {
        self.m *= 2;
        self.counts.resize(count_len(self.m), 0);
        self.requantise();
    }

    /// Resyncs once the empties left by removals pass 1/64 of a row's weight.
    #[cold]
    fn resync_if_sparse(&mut self) {
        for r in 0..W {
            let total = self.row_total[r];
            if total.saturating_sub(self.live(r) + self.base_slack[r]) > total >> 6 {
                self.resync();
                return;
            }
        }
    }

    /// Removes the particle of size x in slot s of bucket b (its slot stays, empty).
    #[inline(always)]
    fn remove(&mut self, b: usize, s: u64, x: u64) {
        let bk = &mut self.buckets[b];
        bk.n -= 1;
        if bk.grid {
            self.counts[x as usize] -= 1;
        } else {
            self.lists[b - SINGLE as usize].swap_remove(s as usize);
        }
    }

    /// Adds a particle of size x, growing its bucket's slots when none is free.
    #[inline(always)]
    fn insert(&mut self, x: u64) {
        let b = bucket_of(x);
        let bk = &mut self.buckets[b];
        bk.n += 1;
        if bk.grid {
            let c = self.counts[x as usize] + 1;
            self.counts[x as usize] = c;
            if u64::from(c) <= bk.cap {
                return;
            }
        } else {
            let list = &mut self.lists[b - SINGLE as usize];
            list.push((x - bk.lo) as u32);
            if list.len() as u64 <= bk.slots {
                return;
            }
        }
        self.grow(b);
    }

    /// Grows full bucket b by 1/16 of its slots (the grown slots join the overflow stream).
    #[cold]
    fn grow(&mut self, b: usize) {
        let bk = &mut self.buckets[b];
        let first = bk.slots == bk.tab;
        let extra = if bk.grid {
            let more = 1 + (bk.cap >> GROW);
            bk.cap += more;
            more << bk.sh
        } else {
            1 + (bk.slots >> GROW)
        };
        bk.slots += extra;
        let q = bk.q;
        // the new headroom is planned slack: only empties left by removals count
        // towards a resync
        self.slots_total += extra;
        self.planned += extra - 1;
        self.set_resync_threshold();
        for r in 0..W {
            let total = q[r]
                .checked_mul(extra)
                .and_then(|w| w.checked_add(self.row_total[r]))
                .filter(|&t| t < 1 << 63);
            match total {
                Some(t) => {
                    self.row_total[r] = t;
                    self.base_slack[r] += q[r] * (extra - 1);
                }
                None => self.poison(),
            }
        }
        // the grown slots join the overflow stream; the tables stay until the
        // overflow is too large
        if first && self.over.push(b).is_err() {
            // full: the tables must be rebuilt
            self.rates_stale = true;
        }
        self.rates_changed = true;
    }

    /// An accepted event changed the proposal rates (or left fewer than two
    /// particles): the clock must restart after a refresh.
    #[inline(always)]
    fn stale(&self) -> bool {
        self.rates_stale || self.rates_changed || self.poisoned.is_some()
    }

    /// The counts: `counts()[i − 1] = N_i`, for `i = 1..=M`.
    fn count_vec(&self) -> Vec<u64> {
        let mut out: Vec<u64> = self.counts[1..=self.m as usize]
            .iter()
            .map(|&c| u64::from(c))
            .collect();
        for (b, list) in self.lists.iter().enumerate() {
            let b = b + SINGLE as usize;
            if self.buckets[b].grid {
                continue;
            }
            let (lo, hi) = bucket_range(b);
            let hi = hi.min(self.m);
            if lo > hi {
                continue;
            }
            tally(&mut out[lo as usize - 1..hi as usize], list);
        }
        out
    }
}

/// Where a candidate's particles are: `(bucket, slot)` of each.
type Loc = ((usize, u64), (usize, u64));

mod draw;
mod engine;
mod tables;

#[cfg(test)]
mod tests;
