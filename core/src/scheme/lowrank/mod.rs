//! Low-rank Monte Carlo for Smoluchowski-class equations (Osinsky 2023, §2–3). Its
//! baselines, the inverse method and acceptance–rejection, are in
//! [`baseline`](crate::scheme::baseline).
//!
//! State: counts `N_i` of particles of integer size `i = 1..M` in a volume V; each
//! unordered pair of distinct particles coagulates at rate `K(i, j)/V` (Osinsky 2023 §2).
//!
//! **Proposals.** The kernel is bounded by `K ≤ A + Aᵀ` with `A(i, j) = Σ_{k<R} a_k(i)
//! b_k(j)` (see [`crate::kernel`]). Ordered pairs of particles (p, q) are proposed at rate
//! `A(x_p, x_q)/V`: with `u^k_i = a_k(i) N_i` and `v^k_j = b_k(j) N_j` the total proposal
//! rate is `S_A / V`, `S_A = Σ_k (Σ_i u^k_i)(Σ_j v^k_j)`. Pick k ∝ `U_k V_k`, then i by
//! descending the partial sums of `u^k` and j by those of `v^k`. An unordered pair is
//! thus proposed at rate `(A + Aᵀ)/V`; accepting with `K/(A + Aᵀ)` gives rate `K/V`, and a
//! proposal of the particle with itself (i = j, probability `1/N_i`) is rejected.
//!
//! **Time step.** Proposals form a Poisson process of rate `S_A / V`, so the waiting time
//! is exponential with mean `V / S_A`. (The seed's listing writes `−2V ln U / S_A`, which
//! would halve every rate; the constant-kernel test `N(t)/V = 1/(1 + t/2)` in this
//! module's tests decides for `V / S_A`.)
//!
//! **One engine, many rules.** The scheme is [`LowRankMc`]: an event loop (the clock,
//! the population with its particle doubling, the kernel) over three parts —
//! * the **bound** ([`bound`]): the kernel's factors, validated, and their coarsening to
//!   size buckets;
//! * a **proposal engine** ([`ProposalEngine`]) that stores the particles and draws
//!   pairs at rate `Â/V`: [`TreeEngine`] keeps the paper's per-size weights in one
//!   segment tree (all 2R vectors together, so a count change walks a single path;
//!   8-ary [`WideTree`] or the paper's [`BinaryTree`], see [`trees`]), [`BucketedEngine`]
//!   the bound coarsened to log-linear buckets (≤ 1/32 wide) with integer weights, O(1)
//!   alias tables over ≤ ~900 buckets and lazily emptied slots (see [`bucketed`]);
//! * an **event rule** ([`EventRule`]) that accepts a proposed pair and names its
//!   outcome: [`Coagulate`] (accept with `K/(Â + Âᵀ)`, squeezed with the kernel's
//!   acceptance floor; merge).
//!
//! [`Bucketed`] (the default and fastest layout) and [`LowRank`] (the per-size trees)
//! are that scheme with the coagulation rule; `coagula bench lowrank` times both against
//! the paper.
//!
//! **Growth.** When `i + j > M`, M doubles (arrays and tree grow; the only allocation,
//! bounded by a caller-set size limit). When fewer than `N0/2` particles remain, every
//! count, N and V double (particle doubling), which keeps the statistical error constant
//! at constant cost.
//!
//! # Example
//! ```
//! use coagula_core::kernel::Coagulation;
//! use coagula_core::scheme::{Scheme, lowrank::LowRank};
//! let mut rng = rand_pcg::Pcg64Mcg::new(7);
//! // constant kernel K = 1 from 10^4 monomers: n_1(t) → 1/(1 + t/2)^2
//! let mut sim = LowRank::<_, 1>::monodisperse(Coagulation::constant(1.0).unwrap(), 10_000).unwrap();
//! sim.advance_to(1.0, &mut rng).unwrap();
//! let m0 = sim.moment(0.0);
//! assert!((m0 - 1.0 / 1.5).abs() < 0.02);
//! ```

mod auto;
pub mod blocks;
pub mod bound;
pub mod bucketed;
mod counted;
pub mod dsmc;
mod edit;
mod entry;
pub mod proposal;
pub mod rule;
pub mod sizes;
pub mod temperature;
pub mod tree;
pub mod trees;
pub mod uniform;

pub use super::population::{DEFAULT_MEMORY_BUDGET, DEFAULT_SIZE_LIMIT};
pub use auto::{AutoBucketed, BucketMode, prefers_blocks};
pub use blocks::BlockEngine;
pub use bound::MAX_PARTICLES;
pub use bucketed::BucketedEngine;
pub use counted::CountedEngine;
pub use entry::{
    BinaryTreeEntry, BlocksEntry, BucketedEntry, DsmcEntry, DsmcRejectionEntry, SizesEntry,
    TemperatureEntry, TemperatureRejectionEntry, TreeEntry,
};
pub use proposal::{Candidate, Low, Outcome, ProposalEngine};
pub use rule::{Coagulate, EventRule, Reweighed, SPOT_CHECK};
pub use sizes::LowRankSizes;
pub use temperature::{Collide, TemperatureMc, TemperatureRejection, Temperatures};
pub use tree::TreeEngine;
pub use trees::{BinaryTree, ProposalTree, WideTree};
pub use uniform::UniformEngine;

use super::clock::Batch;
use super::population::Population;
use super::{Budget, Pending, Scheme, StepReport, Ziggurat, check_target};
use crate::checkpoint::{Checkpoint, Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use alloc::borrow::Cow;
use core::marker::PhantomData;
use rand_core::Rng;

/// Low-rank Monte Carlo (Osinsky 2023) over the proposal engine `E` with the event rule
/// `Rl` (see the module docs). Use it through [`Bucketed`] or [`LowRank`].
pub struct LowRankMc<K, const R: usize, E, Rl = Coagulate> {
    kernel: K,
    pub(crate) engine: E,
    rule: Rl,
    pub(crate) pop: Population,
    time: f64,
    /// Where the proposal clock stands (kept between calls).
    clock: Clock,
    /// Proposal times in batches (see `clock`): faster, but a trajectory then depends
    /// on where the host stops it (the cut at a target time draws). On by default.
    batched: bool,
    totals: StepReport,
    zig: Ziggurat,
    _rank: PhantomData<[(); R]>,
}

/// The proposal clock of a low-rank scheme between two proposals.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Clock {
    /// The rate must be refreshed from the engine (at the start, after an event that
    /// changed it, after the state was replaced).
    Stale,
    /// No proposal will ever come (fewer than two particles, or a zero rate).
    Idle,
    /// The rate is fresh (mean waiting time given); the next proposal is not yet drawn.
    Rate(f64),
    /// The next proposal, already drawn.
    Next(Pending),
}

impl Clock {
    fn save(&self, w: &mut Writer) {
        match *self {
            Clock::Stale => w.u64(0),
            Clock::Idle => w.u64(1),
            Clock::Rate(m) => {
                w.u64(2);
                w.f64(m);
            }
            Clock::Next(p) => {
                w.u64(3);
                Pending::save(&Some(p), w);
            }
        }
    }

    fn read(r: &mut Reader, now: f64) -> Result<Clock> {
        let bad = |what| Error::Checkpoint { what };
        Ok(match r.u64()? {
            0 => Clock::Stale,
            1 => Clock::Idle,
            2 => {
                let m = r.f64()?;
                if !(m > 0.0 && m.is_finite()) {
                    return Err(bad("invalid mean waiting time"));
                }
                Clock::Rate(m)
            }
            3 => Clock::Next(Pending::read(r, now)?.ok_or(bad("invalid pending proposal"))?),
            _ => return Err(bad("invalid clock")),
        })
    }
}

/// Low-rank MC with the paper's per-size trees ([`WideTree`] by default, [`BinaryTree`]
/// for comparison).
pub type LowRank<K, const R: usize, T = WideTree<R>> = LowRankMc<K, R, TreeEngine<R, T>>;

/// The event loop over block majorants ([`blocks`]): for kernels that no low-rank bound
/// fits (the rank parameter is unused).
pub type Blocks<K> = LowRankMc<K, 1, BlockEngine>;

/// Low-rank MC over size buckets, the default and fastest layout for large systems (see
/// [`bucketed`]). `W` must be `2R`.
pub type Bucketed<K, const R: usize, const W: usize> = LowRankMc<K, R, BucketedEngine<R, W>>;

/// Low-rank MC over size buckets with exact bucket counts in a sum tree: the bucketed
/// layout for small systems (see [`CountedEngine`]). `W` must be `2R`.
pub type BucketedCounted<K, const R: usize, const W: usize> = LowRankMc<K, R, CountedEngine<R, W>>;

/// Initial particle numbers up to this run on [`BucketedCounted`] in an
/// [`AutoBucketed`] (the registry's `lowrank`); above, on [`Bucketed`]. Measured
/// crossover: `docs/design/bucketed-layout.md`.
pub const COUNTED_UP_TO: u64 = 1 << 14;

impl<K, const R: usize, E, Rl> core::fmt::Debug for LowRankMc<K, R, E, Rl> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("LowRankMc")
            .field("rank", &R)
            .field("engine", &core::any::type_name::<E>())
            .field("particles", &self.pop.n)
            .field("volume", &self.pop.volume)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K, const R: usize, E, Rl> LowRankMc<K, R, E, Rl>
where
    K: CoagulationKernel,
    E: ProposalEngine<R>,
    Rl: EventRule<K>,
{
    /// Starts from `n0` monomers in volume `V = n0` (so `n_1(0) = 1`).
    pub fn monodisperse(kernel: K, n0: u64) -> Result<Self> {
        Self::new(kernel, &[n0], n0 as f64)
    }

    /// Starts from `counts[i − 1] = N_i` in volume `volume`.
    ///
    /// Errors: the kernel's rank is not `R` (for the bucketed layout: or `W ≠ 2R`), a
    /// factor is negative or not finite, the counts are all zero (or, bucketed, add up to
    /// more than [`MAX_PARTICLES`]), the volume is not positive.
    pub fn new(kernel: K, counts: &[u64], volume: f64) -> Result<Self> {
        Self::new_with_memory_budget(kernel, counts, volume, DEFAULT_MEMORY_BUDGET)
    }

    /// [`new`](Self::new) with a memory budget of `bytes` (see
    /// [`with_memory_budget`](Self::with_memory_budget)), which the initial tables must
    /// already fit.
    pub fn new_with_memory_budget(
        kernel: K,
        counts: &[u64],
        volume: f64,
        bytes: usize,
    ) -> Result<Self> {
        if Rl::REWEIGHS && !E::REWEIGHS {
            return Err(Error::Unsupported {
                what: "this event rule moves the bound's factors: use the per-size tree engine",
            });
        }
        Rl::check_counts(&kernel, counts)?;
        let pop = Population::new(counts, volume)?.with_memory_budget(bytes);
        let engine = E::build(&kernel, counts, &pop)?;
        Ok(LowRankMc {
            rule: Rl::for_kernel(&kernel),
            kernel,
            engine,
            pop,
            time: 0.0,
            clock: Clock::Stale,
            batched: true,
            totals: StepReport::default(),
            zig: Ziggurat::new(),
            _rank: PhantomData,
        })
    }

    /// Sets the largest particle size allowed (default [`DEFAULT_SIZE_LIMIT`]); a
    /// collision that would pass it makes `advance_to` fail with [`Error::Capacity`].
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.pop.size_limit = limit;
        self
    }

    /// Whether proposal times are drawn in batches where the engine allows (one gamma
    /// variate per batch, a beta variate per rate change, instead of an exponential per
    /// proposal; see `clock`). On by default: exact, and 1.2–1.5× faster for large
    /// systems, but cutting a batch at a target time draws random numbers, so a run
    /// stopped on its way differs (in law it is the same process) from one that did
    /// not stop. Off, every proposal has its own exponential waiting time and the time
    /// of the next one is kept across calls: a run stopped at 0.7 and 1.3 on its way to
    /// 2 is then bit for bit the run that went to 2 in one call (what a host that
    /// splits time as it likes needs; the C ABI's default).
    pub fn with_batched_clock(mut self, on: bool) -> Self {
        self.batched = on;
        self
    }

    /// Sets the memory budget in bytes (default [`DEFAULT_MEMORY_BUDGET`]): growing the
    /// size table past it makes `advance_to` fail with [`Error::Capacity`], the state
    /// as before the event. (The bucketed layout's particle lists, at most 8 bytes per
    /// particle, are sized by the initial particles.)
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.pop.memory_budget = bytes;
        self
    }

    /// The counts: `counts()[i − 1] = N_i` (number densities `n_i = N_i / V`), for
    /// `i = 1..=M`.
    pub fn counts(&self) -> Cow<'_, [u64]> {
        self.engine.counts()
    }

    /// The kernel (for a rule with per-size state, e.g. temperatures: that state).
    pub fn kernel(&self) -> &K {
        &self.kernel
    }

    /// The simulation volume V.
    pub fn volume(&self) -> f64 {
        self.pop.volume
    }

    /// Current number of simulation particles N.
    pub fn particles(&self) -> u64 {
        self.pop.n
    }

    /// Current maximum size M (the size table's length).
    pub fn max_size(&self) -> usize {
        self.engine.max_size() as usize
    }

    /// The moment `Σ_i i^m N_i / V` (from the occupied sizes: no count vector).
    pub fn moment(&self, m: f64) -> f64 {
        crate::observe::moment_of_pairs(|f| self.engine.for_each_count(f), self.pop.volume, m)
    }

    /// Calls `f(size, N)` for every occupied size, ascending, without building the
    /// count vector.
    pub fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        self.engine.for_each_count(f)
    }

    /// Totals over the whole run.
    pub fn totals(&self) -> StepReport {
        self.totals
    }

    /// Replaces the kernel (e.g. new parameters between outer steps): the bound is
    /// recomputed and the engine rebuilt from the counts, with the particle-doubling
    /// reference kept. Errors (rank differs, invalid factors) leave the scheme
    /// unchanged.
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        Rl::check_counts(&kernel, &self.engine.counts())?;
        let engine = E::build(&kernel, &self.engine.counts(), &self.pop)?;
        self.rule = Rl::for_kernel(&kernel);
        self.kernel = kernel;
        self.engine = engine;
        self.clock = Clock::Stale;
        Ok(())
    }

    /// Replaces the counts `N_i = counts[i − 1]` and the volume (a host that applies
    /// growth or nucleation between steps); the particle number becomes the new
    /// reference for particle doubling. Time, totals, size limit and memory budget are
    /// kept. Errors (as for [`new`](Self::new), or a size beyond the size limit) leave
    /// the scheme unchanged.
    pub fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        if counts.len() as u64 > self.pop.size_limit {
            return Err(Error::Capacity {
                name: "maximum particle size",
                capacity: usize::try_from(self.pop.size_limit).unwrap_or(usize::MAX),
            });
        }
        Rl::check_counts(&self.kernel, counts)?;
        let fresh = Population {
            size_limit: self.pop.size_limit,
            memory_budget: self.pop.memory_budget,
            doubling: self.pop.doubling,
            ..Population::new(counts, volume)?
        };
        self.engine = E::build(&self.kernel, counts, &fresh)?;
        self.pop = fresh;
        self.clock = Clock::Stale;
        Ok(())
    }

    /// Turns particle doubling on or off (kept across `set_counts`; a checkpoint does
    /// not carry it).
    pub fn set_doubling(&mut self, on: bool) {
        self.pop.doubling = on;
    }

    /// Sets the clock (finite, not negative): a host that keeps its own time origin.
    /// The next proposal is drawn afresh from the new time.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = super::check_time(t)?;
        self.clock = Clock::Stale;
        Ok(())
    }

    /// [`set_counts`](Self::set_counts) from `(size, count)` pairs (each size at most
    /// once, within the size limit).
    pub fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
        let dense = super::population::dense_from_pairs(
            sizes,
            counts,
            self.pop.size_limit,
            self.pop.memory_budget,
        )?;
        self.set_counts(&dense, volume)
    }

    /// The checkpoint tag: the engine's, and the rule's above it when it has state.
    fn tag() -> u64 {
        Rl::TAG.map_or(E::TAG, |t| (t << 8) | E::TAG)
    }

    /// The mean waiting time between proposals and whether proposals happen at all,
    /// after the engine's refresh.
    #[inline]
    fn refresh<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Result<(bool, f64)> {
        let sa = self.engine.refresh(&self.pop, rng)?;
        // a rate so small that V / S_A overflows: no proposal before any finite time
        let mean_dt = self.pop.volume / sa;
        Ok((sa > 0.0 && self.pop.n >= 2 && mean_dt.is_finite(), mean_dt))
    }

    /// Books a failed call's report (the state and time are already those before the
    /// failing proposal) and passes the error on.
    fn fail(&mut self, e: Error, rep: &mut StepReport) -> Error {
        rep.time = self.time;
        self.totals.accumulate(rep);
        e
    }

    /// One proposal; returns whether it was accepted (and then whether the proposal
    /// rate must be refreshed). `self.time` already includes the waiting time.
    #[inline(always)]
    fn propose<G: Rng + ?Sized>(
        &mut self,
        rng: &mut G,
        rep: &mut StepReport,
        budget: &mut Budget<'_>,
    ) -> Result<bool> {
        let Some(c) = self.engine.propose(rng) else {
            rep.rejections += 1;
            return Ok(false);
        };
        let spot = (self.totals.proposals.wrapping_add(rep.proposals)).is_multiple_of(SPOT_CHECK);
        let engine = &self.engine;
        let bounds = || engine.bounds(&c.at);
        let Some(outcome) = self
            .rule
            .decide(&self.kernel, &c, bounds, E::LOW, spot, rng)?
        else {
            rep.rejections += 1;
            return Ok(false);
        };
        if let Outcome::Merge { size } = outcome {
            self.pop.check_size(size)?;
        }
        if Rl::REWEIGHS {
            let engine = &self.engine;
            self.rule
                .plan(&mut self.kernel, (c.x, c.y), &outcome, &|s| engine.count(s))?;
        }
        let merged = match outcome {
            Outcome::Merge { .. } => {
                self.engine.prepare(&self.kernel, &outcome, &self.pop)?;
                self.engine.apply(&c, &outcome);
                self.pop.n -= 1;
                true
            }
            Outcome::Bounce => {
                rep.bounces += 1;
                false
            }
        };
        if Rl::REWEIGHS {
            for s in self.rule.commit(&mut self.kernel) {
                self.engine.reweigh(&self.kernel, s);
            }
            if self.rule.refactor_due() {
                self.engine.refactor(&self.kernel);
            }
        }
        if Rl::DOUBLES && merged && self.pop.doubling_due() {
            self.pop.double();
            self.engine.double(&self.pop);
            rep.doublings += 1;
            budget.doubled(self.time);
        }
        self.engine.settle(&self.pop);
        Ok(true)
    }
}

impl<K, const R: usize, E, Rl> Scheme for LowRankMc<K, R, E, Rl>
where
    K: CoagulationKernel,
    E: ProposalEngine<R>,
    Rl: EventRule<K>,
{
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        LowRankMc::totals(self)
    }

    fn advance_within<G: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport> {
        check_target(self.time, t)?;
        let mut rep = StepReport::default();
        'epoch: loop {
            let (mut at, mean_dt) = match self.clock {
                Clock::Stale => {
                    let (live, mean_dt) = self.refresh(rng).map_err(|e| self.fail(e, &mut rep))?;
                    self.clock = if live {
                        Clock::Rate(mean_dt)
                    } else {
                        Clock::Idle
                    };
                    continue;
                }
                Clock::Idle => {
                    self.time = t;
                    break;
                }
                Clock::Rate(mean_dt) => {
                    if let Err(e) = Pending::check(self.time, mean_dt) {
                        // (a state a checkpoint can hold: refreshed again next call)
                        self.clock = Clock::Stale;
                        return Err(self.fail(e, &mut rep));
                    }
                    if self.batched
                        && self.engine.batches(&self.pop)
                        && let Some(batch) = Batch::plan(self.time, mean_dt, t, rng)
                    {
                        if self.run_batch(&batch, budget, &mut rep, rng)? {
                            break;
                        }
                        continue;
                    }
                    (self.time + self.zig.sample(rng) * mean_dt, mean_dt)
                }
                Clock::Next(p) => (p.at, p.mean_dt),
            };
            // proposals at a constant rate until an event changes it (the clock in
            // locals; written back when the loop leaves)
            loop {
                if at > t {
                    self.clock = Clock::Next(Pending { at, mean_dt });
                    self.time = t;
                    break 'epoch;
                }
                if !budget.take(1) {
                    self.clock = Clock::Next(Pending { at, mean_dt });
                    rep.interrupted = true;
                    break 'epoch;
                }
                let before = self.time;
                self.time = at;
                rep.proposals += 1;
                match self.propose(rng, &mut rep, budget) {
                    Ok(true) => {
                        rep.events += 1;
                        if self.engine.needs_refresh() || self.pop.n < 2 {
                            self.clock = Clock::Stale;
                            continue 'epoch;
                        }
                    }
                    Ok(false) => {
                        if E::REFRESH_AFTER_REJECT && self.engine.needs_refresh() {
                            self.clock = Clock::Stale;
                            continue 'epoch;
                        }
                    }
                    Err(e) => {
                        // the state is as before the proposal, which stays pending
                        self.time = before;
                        self.clock = Clock::Next(Pending { at, mean_dt });
                        return Err(self.fail(e, &mut rep));
                    }
                }
                if at + mean_dt <= at {
                    self.clock = Clock::Stale;
                    let e = Pending::check(at, mean_dt).err().unwrap_or(Error::Empty);
                    return Err(self.fail(e, &mut rep));
                }
                at += self.zig.sample(rng) * mean_dt;
            }
        }
        rep.time = self.time;
        self.totals.accumulate(&rep);
        Ok(rep)
    }
}

impl<K, const R: usize, E, Rl> LowRankMc<K, R, E, Rl>
where
    K: CoagulationKernel,
    E: ProposalEngine<R>,
    Rl: EventRule<K>,
{
    /// Runs the proposals of one batch (the clock stands at `Rate`); returns whether
    /// the call is over (the batch reached the target time, or the budget ran out).
    fn run_batch<G: Rng + ?Sized>(
        &mut self,
        batch: &Batch,
        budget: &mut Budget<'_>,
        rep: &mut StepReport,
        rng: &mut G,
    ) -> Result<bool> {
        let mut k = 0;
        while k < batch.len {
            if !budget.take(1) {
                // the arrivals after the k-th are memoryless: redrawn on the next call
                self.time = batch.time_of(k, rng);
                rep.interrupted = true;
                return Ok(true);
            }
            k += 1;
            rep.proposals += 1;
            match self.propose(rng, rep, budget) {
                Ok(true) => {
                    rep.events += 1;
                    if self.engine.needs_refresh() || self.pop.n < 2 {
                        self.time = batch.time_of(k, rng);
                        self.clock = Clock::Stale;
                        return Ok(false);
                    }
                }
                Ok(false) => {
                    if E::REFRESH_AFTER_REJECT && self.engine.needs_refresh() {
                        self.time = batch.time_of(k, rng);
                        self.clock = Clock::Stale;
                        return Ok(false);
                    }
                }
                Err(e) => {
                    self.time = batch.time_of(k - 1, rng);
                    return Err(self.fail(e, rep));
                }
            }
        }
        self.time = batch.end;
        Ok(batch.last)
    }
}

impl<K, const R: usize, E, Rl> Checkpoint for LowRankMc<K, R, E, Rl>
where
    K: CoagulationKernel,
    E: ProposalEngine<R>,
    Rl: EventRule<K>,
{
    /// The common fields (rank, M, size limit, N, N0, V, time, totals), then the
    /// engine's state. The kernel is not stored: restore into a scheme built with the
    /// same kernel.
    fn save(&self, w: &mut Writer) {
        use crate::checkpoint::header;
        header(w, Self::tag());
        w.u64(R as u64);
        w.u64(self.engine.max_size());
        w.u64(self.pop.size_limit);
        w.u64(self.pop.n);
        w.u64(self.pop.n0);
        w.f64(self.pop.volume);
        w.f64(self.time);
        self.clock.save(w);
        self.totals.save(w);
        self.rule.save(&self.kernel, w);
        self.engine.save(w);
    }

    fn restore(&mut self, r: &mut Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, Self::tag())?;
        if r.u64()? != R as u64 {
            return Err(bad("different rank"));
        }
        let m = r.u64()?;
        if !m.is_power_of_two() || !(64..=1 << 62).contains(&m) {
            return Err(bad("invalid maximum size"));
        }
        let (size_limit, n, n0) = (r.u64()?, r.u64()?, r.u64()?);
        let (volume, time) = (r.f64()?, r.f64()?);
        if !(volume > 0.0 && volume.is_finite() && time >= 0.0 && time.is_finite() && n <= n0)
            || size_limit == 0
        {
            return Err(bad(
                "invalid volume, time, particle number or reference, or size limit",
            ));
        }
        let clock = Clock::read(r, time)?;
        let totals = StepReport::read(r)?;
        let pop = Population {
            n,
            n0,
            volume,
            size_limit,
            memory_budget: self.pop.memory_budget,
            doubling: self.pop.doubling,
        };
        let kernel = self.rule.load(&self.kernel, r)?;
        let engine = E::load(kernel.as_ref().unwrap_or(&self.kernel), m, &pop, r)?;
        r.finish()?;
        Rl::check_counts(kernel.as_ref().unwrap_or(&self.kernel), &engine.counts())
            .map_err(|_| bad("the counts do not match the rule's state"))?;
        // no particle past the size limit (the constructors' check)
        let mut largest = 0;
        engine.for_each_count(&mut |s, _| largest = s);
        if largest > size_limit {
            return Err(bad("a particle is larger than the size limit"));
        }
        // a clock that resumes without a refresh needs an engine that can
        let rate = engine.rate_now();
        let fits = |mean_dt: f64| {
            pop.n >= 2 && rate.is_some_and(|sa| (pop.volume / sa).to_bits() == mean_dt.to_bits())
        };
        let consistent = match clock {
            Clock::Stale => true,
            // (a zero rate leaves bucketed tables stale: no rate to compare then)
            Clock::Idle => {
                pop.n < 2 || rate.is_none_or(|r| r == 0.0 || !(pop.volume / r).is_finite())
            }
            Clock::Rate(m) => fits(m),
            Clock::Next(p) => fits(p.mean_dt),
        };
        if !consistent {
            return Err(bad("the clock does not match the engine's rate"));
        }
        if let Some(kernel) = kernel {
            self.kernel = kernel;
        }
        self.engine = engine;
        self.pop = pop;
        self.time = time;
        self.clock = clock;
        self.totals = totals;
        Ok(())
    }
}

use crate::scheme::population::observe_counts;

observe_counts!([K: CoagulationKernel, const R: usize, E: ProposalEngine<R>] LowRankMc<K, R, E, Coagulate>);
observe_counts!(
    [TK: crate::kernel::temperature::TemperatureKernel + Clone, E: ProposalEngine<3>]
    LowRankMc<temperature::Temperatures<TK>, 3, E, temperature::Collide>,
    observable = entry::temperature_observable
);
observe_counts!(
    [S: crate::kernel::gas::Sticking + Clone, E: ProposalEngine<3>]
    LowRankMc<dsmc::Gas<S>, 3, E, dsmc::Collisions>,
    observable = entry::gas_observable
);

#[cfg(test)]
mod tests;
