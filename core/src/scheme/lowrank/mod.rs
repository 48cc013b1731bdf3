//! Low-rank Monte Carlo for Smoluchowski-class equations (Osinsky 2023, §2–3). Its
//! baselines, the inverse method and acceptance–rejection, are in
//! [`baseline`](crate::scheme::baseline).
//!
//! State: counts `N_i` of particles of integer size `i = 1..M` in a volume V; each
//! unordered pair of distinct particles coagulates at rate `K(i, j)/V` (SPEC §1).
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
//! **Trees.** All 2R vectors live in *one* tree, so a count change walks a single path
//! and updates every component at once. [`LowRank`] keeps the paper's per-size weights,
//! 8-ary with child sums in one cache line per node and component ([`WideTree`]), or the
//! paper's binary layout ([`BinaryTree`]) for comparison (see [`trees`] for the
//! measurements and the drift control).
//!
//! **Buckets (fastest).** [`Bucketed`] runs the same proposal scheme against a bound
//! coarsened to log-linear size buckets (≤ 1/32 wide): integer weights, O(1) alias
//! tables over ≤ ~900 buckets that stay in cache whatever M is, lazy removals (an empty
//! slot is rejected — exact thinning), a squeeze with the kernel's acceptance floor, and
//! a bucket picks its particle from a count grid or a list in O(1). `coagula bench
//! lowrank` times both against the paper.
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

pub mod bucketed;
pub mod trees;

pub use super::population::{DEFAULT_MEMORY_BUDGET, DEFAULT_SIZE_LIMIT};
pub use bucketed::Bucketed;
pub use trees::{BinaryTree, ProposalTree, WideTree};

pub(crate) use super::population::{
    check_counts, rate_overflow, try_reserve, try_resize, within_budget,
};
pub(crate) use crate::kernel::bounded_rate;

use super::{Scheme, StepReport, Ziggurat, check_target, open_unit};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use alloc::vec::Vec;
use rand_core::Rng;
use trees::Weights;

/// Low-rank Monte Carlo with a rank-`R` bound (Osinsky 2023). See the module docs.
///
/// `T` is the proposal-tree layout ([`WideTree`] by default, [`BinaryTree`] for
/// comparison).
pub struct LowRank<K, const R: usize, T = WideTree<R>> {
    kernel: K,
    exact_bound: bool,
    /// `counts[i - 1] = N_i`, length M.
    counts: Vec<u64>,
    /// `fab[i - 1] = [[a_0(i), ..], [b_0(i), ..]]`: the weights of one particle of size i
    /// (packed so that an update reads one cache line).
    fab: Vec<Weights<R>>,
    /// Proposal tree over the weights `u^k_i = a_k(i) N_i`, `v^k_i = b_k(i) N_i`.
    tree: T,
    /// Current maximum size M (a power of two; the tree's leaf count).
    m: usize,
    size_limit: u64,
    n: u64,
    n0: u64,
    volume: f64,
    time: f64,
    totals: StepReport,
    zig: Ziggurat,
    memory_budget: usize,
}

impl<K, const R: usize, T> core::fmt::Debug for LowRank<K, R, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("LowRank")
            .field("rank", &R)
            .field("max_size", &self.m)
            .field("particles", &self.n)
            .field("volume", &self.volume)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

/// The low-rank factors `(a(x), b(x))` of size x; a negative or non-finite one is an
/// error.
pub(crate) fn factors_at<K: CoagulationKernel, const R: usize>(
    kernel: &K,
    x: f64,
) -> Result<([f64; R], [f64; R])> {
    let (mut a, mut b) = ([0.0; R], [0.0; R]);
    kernel.factors(x, &mut a, &mut b);
    for &v in a.iter().chain(&b) {
        if !(v >= 0.0 && v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "low-rank factor",
                value: v,
            });
        }
    }
    Ok((a, b))
}

/// A kernel whose bound is exact (or whose acceptance a squeeze decides) is still
/// evaluated when the run's `SPOT_CHECK`-th proposal (and every multiple) is accepted
/// without it, so a kernel that turns NaN or exceeds its bound is caught
/// (deterministic: the random stream is the same with or without the check).
pub(crate) const SPOT_CHECK: u64 = 1024;

impl<K: CoagulationKernel, const R: usize, T: ProposalTree<R>> LowRank<K, R, T> {
    /// Starts from `n0` monomers in volume `V = n0` (so `n_1(0) = 1`).
    pub fn monodisperse(kernel: K, n0: u64) -> Result<Self> {
        Self::new(kernel, &[n0], n0 as f64)
    }

    /// Starts from `counts[i - 1] = N_i` in volume `volume`.
    ///
    /// Errors: the kernel's rank is not `R`, a factor is negative or not finite, the
    /// counts are all zero, the volume is not positive.
    pub fn new(kernel: K, counts: &[u64], volume: f64) -> Result<Self> {
        if kernel.rank() != R || R == 0 {
            return Err(Error::Unsupported {
                what: "kernel rank differs from the scheme's R (or the kernel has no low-rank bound)",
            });
        }
        crate::error::positive("volume", volume)?;
        let n = check_counts(counts)?;
        let m = counts.len().next_power_of_two().max(64);
        within_budget(Self::bytes_for(m), DEFAULT_MEMORY_BUDGET)?;
        let mut s = LowRank {
            exact_bound: kernel.low_rank_is_exact(),
            kernel,
            counts: Vec::new(),
            fab: Vec::new(),
            tree: T::build(8, |_| [[0.0; R]; 2])?,
            m,
            size_limit: DEFAULT_SIZE_LIMIT,
            n,
            n0: n,
            volume,
            time: 0.0,
            totals: StepReport::default(),
            zig: Ziggurat::new(),
            memory_budget: DEFAULT_MEMORY_BUDGET,
        };
        try_resize(&mut s.counts, m, 0)?;
        s.counts[..counts.len()].copy_from_slice(counts);
        s.extend_factors(m)?;
        s.tree = T::build(m, |idx| s.leaf_value(idx))?;
        Ok(s)
    }

    /// Sets the memory budget in bytes (default [`DEFAULT_MEMORY_BUDGET`]): growing the
    /// size table past it makes `advance_to` fail with [`Error::Capacity`], the state
    /// as before the event.
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.memory_budget = bytes;
        self
    }

    /// Bytes of the per-size arrays and the tree for maximum size `m`.
    fn bytes_for(m: usize) -> Option<usize> {
        let per_size = core::mem::size_of::<u64>() + core::mem::size_of::<Weights<R>>();
        m.checked_mul(per_size)?.checked_add(T::bytes(m)?)
    }

    /// Sets the largest particle size allowed (default [`DEFAULT_SIZE_LIMIT`]); a
    /// collision that would pass it makes `advance_to` fail with [`Error::Capacity`].
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.size_limit = limit;
        self
    }

    /// Computes the factor tables for sizes `fab.len() + 1 ..= m`, validating them
    /// (nothing to do when the tables already cover `m`).
    fn extend_factors(&mut self, m: usize) -> Result<()> {
        let start = self.fab.len();
        if m <= start {
            return Ok(());
        }
        // validate all before the table changes
        let mut new = Vec::new();
        try_reserve(&mut new, m - start)?;
        for i in start + 1..=m {
            let (a, b) = factors_at::<K, R>(&self.kernel, i as f64)?;
            new.push([a, b]);
        }
        try_reserve(&mut self.fab, new.len())?;
        self.fab.extend(new);
        Ok(())
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
        self.counts[idx] = (self.counts[idx] as i64 + delta) as u64;
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
    fn grow(&mut self, new_m: usize) -> Result<()> {
        // the old tree lives on while the new one is built
        let bytes = Self::bytes_for(new_m).and_then(|b| b.checked_add(T::bytes(self.m)?));
        within_budget(bytes, self.memory_budget)?;
        self.extend_factors(new_m)?;
        let more = new_m - self.counts.len();
        try_reserve(&mut self.counts, more)?;
        let tree = T::build(new_m, |idx| self.leaf_value(idx))?;
        self.counts.resize(new_m, 0);
        self.m = new_m;
        self.tree = tree;
        Ok(())
    }

    fn double_particles(&mut self) {
        for c in &mut self.counts {
            *c *= 2;
        }
        // doubling every leaf doubles every partial sum exactly
        self.tree.double();
        self.n *= 2;
        self.volume *= 2.0;
    }

    /// One proposal; returns whether it was accepted. `self.time` must already include
    /// the waiting time.
    #[inline]
    fn propose<Rn: Rng + ?Sized>(&mut self, rng: &mut Rn, rep: &mut StepReport) -> Result<bool> {
        let root = self.tree.totals();
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
        let tu = root[0][k] * crate::tree::unit_f64(rng.next_u64());
        let tv = root[1][k] * crate::tree::unit_f64(rng.next_u64());
        let (i, j) = self.tree.descend_pair(k, tu, tv);
        if self.counts[i] == 0 || self.counts[j] == 0 {
            // a ghost weight left by rounding (see `trees`): thinning rejects it
            rep.rejections += 1;
            return Ok(false);
        }
        let spot =
            self.exact_bound && (self.totals.proposals + rep.proposals).is_multiple_of(SPOT_CHECK);
        if !self.exact_bound || spot {
            let (x, y) = ((i + 1) as f64, (j + 1) as f64);
            let mut bound = 0.0;
            for kk in 0..R {
                bound += self.fab[i][0][kk] * self.fab[j][1][kk]
                    + self.fab[j][0][kk] * self.fab[i][1][kk];
            }
            let c = bounded_rate(&self.kernel, x, y, bound, "low-rank bound")?;
            if !spot && bound * open_unit(rng) > c {
                rep.rejections += 1;
                return Ok(false);
            }
        }
        if i == j && (self.counts[i] as f64) * open_unit(rng) < 1.0 {
            rep.rejections += 1;
            return Ok(false);
        }
        let new_idx = i + j + 1; // size (i+1) + (j+1) has index i + j + 1
        if new_idx as u64 + 1 > self.size_limit {
            return Err(Error::Capacity {
                name: "maximum particle size",
                capacity: self.size_limit as usize,
            });
        }
        if new_idx >= self.m {
            self.grow(2 * self.m)?;
        }
        if i == j {
            self.change(i, -2);
        } else {
            self.change(i, -1);
            self.change(j, -1);
        }
        self.change(new_idx, 1);
        self.n -= 1;
        if self.n < self.n0 / 2 {
            self.double_particles();
            rep.doublings += 1;
        }
        if self.tree.wants_rebuild() {
            self.rebuild();
        }
        Ok(true)
    }

    /// Number densities `n_i = N_i / V` are `counts()[i - 1] / volume()`.
    pub fn counts(&self) -> &[u64] {
        &self.counts
    }

    /// The simulation volume V.
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// Current number of simulation particles N.
    pub fn particles(&self) -> u64 {
        self.n
    }

    /// Current maximum size M (the arrays' length).
    pub fn max_size(&self) -> usize {
        self.m
    }

    /// The moment `Σ_i i^m N_i / V`.
    pub fn moment(&self, m: f64) -> f64 {
        crate::observe::moment_of_counts(&self.counts, self.volume, m)
    }

    /// Totals over the whole run.
    pub fn totals(&self) -> StepReport {
        self.totals
    }
}

impl<K: CoagulationKernel, const R: usize, T: ProposalTree<R>> Scheme for LowRank<K, R, T> {
    fn time(&self) -> f64 {
        self.time
    }

    fn advance_to<Rn: Rng + ?Sized>(&mut self, t: f64, rng: &mut Rn) -> Result<StepReport> {
        check_target(self.time, t)?;
        let mut rep = StepReport::default();
        loop {
            let root = self.tree.totals();
            let mut sa = 0.0;
            for k in 0..R {
                sa += root[0][k] * root[1][k];
            }
            if !sa.is_finite() {
                // weights past f64::MAX: no waiting time can be drawn
                rep.time = self.time;
                self.totals.accumulate(&rep);
                return Err(rate_overflow(sa));
            }
            if sa <= 0.0 || self.n < 2 {
                self.time = t;
                break;
            }
            let dt = self.zig.sample(rng) * self.volume / sa;
            if self.time + dt > t {
                self.time = t;
                break;
            }
            let before = self.time;
            self.time += dt;
            rep.proposals += 1;
            match self.propose(rng, &mut rep) {
                Ok(true) => rep.events += 1,
                Ok(false) => {}
                Err(e) => {
                    self.time = before;
                    rep.time = self.time;
                    self.totals.accumulate(&rep);
                    return Err(e);
                }
            }
        }
        rep.time = self.time;
        self.totals.accumulate(&rep);
        Ok(rep)
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

impl<K: CoagulationKernel, const R: usize, T: ProposalTree<R>> crate::checkpoint::Checkpoint
    for LowRank<K, R, T>
{
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::{header, save_report, tag};
        header(w, tag::LOWRANK);
        w.u64(R as u64);
        w.u64(self.m as u64);
        w.u64(self.size_limit);
        w.u64(self.n);
        w.u64(self.n0);
        w.f64(self.volume);
        w.f64(self.time);
        save_report(w, &self.totals);
        w.u64s(&self.counts);
        self.tree.save(w);
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::{check_header, read_report, tag};
        check_header(r, tag::LOWRANK)?;
        if r.u64()? != R as u64 {
            return Err(Error::Checkpoint {
                what: "different rank",
            });
        }
        let m = r.usize()?;
        if !m.is_power_of_two() || m < 64 {
            return Err(Error::Checkpoint {
                what: "invalid maximum size",
            });
        }
        let (size_limit, n, n0) = (r.u64()?, r.u64()?, r.u64()?);
        let (volume, time) = (r.f64()?, r.f64()?);
        let totals = read_report(r)?;
        let counts = r.u64s()?;
        if counts.len() != m || counts.iter().try_fold(0u64, |a, &c| a.checked_add(c)) != Some(n) {
            return Err(Error::Checkpoint {
                what: "counts do not add up",
            });
        }
        within_budget(Self::bytes_for(m), self.memory_budget)?;
        let tree = T::load(m, r)?;
        // a checkpoint taken before the size table grew has a smaller M: the factor
        // table keeps its longer prefix (it depends only on the kernel)
        self.extend_factors(m)?;
        self.m = m;
        self.size_limit = size_limit;
        self.n = n;
        self.n0 = n0;
        self.volume = volume;
        self.time = time;
        self.totals = totals;
        self.counts = counts;
        self.tree = tree;
        Ok(())
    }
}

impl<K: CoagulationKernel, const R: usize, T: ProposalTree<R>> LowRank<K, R, T> {
    /// Replaces the kernel (e.g. new parameters between outer steps): the factor tables
    /// and the tree are rebuilt. Errors (rank differs, invalid factors) leave the scheme
    /// unchanged.
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        if kernel.rank() != R {
            return Err(Error::Unsupported {
                what: "kernel rank differs from the scheme's R",
            });
        }
        let old = core::mem::replace(&mut self.kernel, kernel);
        let old_fab = core::mem::take(&mut self.fab);
        if let Err(e) = self.extend_factors(self.m) {
            self.kernel = old;
            self.fab = old_fab;
            return Err(e);
        }
        self.exact_bound = self.kernel.low_rank_is_exact();
        self.rebuild();
        Ok(())
    }

    /// Replaces the counts `N_i = counts[i − 1]` and the volume (a host that applies
    /// growth or nucleation between steps). The particle number becomes the new
    /// reference for particle doubling. Errors leave the scheme unchanged.
    pub fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        crate::error::positive("volume", volume)?;
        let n = check_counts(counts)?;
        if counts.len() as u64 > self.size_limit {
            return Err(Error::Capacity {
                name: "maximum particle size",
                capacity: self.size_limit as usize,
            });
        }
        let m = counts.len().next_power_of_two().max(self.m);
        let bytes = Self::bytes_for(m).and_then(|b| b.checked_add(T::bytes(self.m)?));
        within_budget(bytes, self.memory_budget)?;
        self.extend_factors(m)?;
        let mut fresh = Vec::new();
        try_resize(&mut fresh, m, 0)?;
        fresh[..counts.len()].copy_from_slice(counts);
        let fab = &self.fab;
        let tree = T::build(m, |idx| scale(&fab[idx], fresh[idx] as f64))?;
        self.m = m;
        self.counts = fresh;
        self.tree = tree;
        self.n = n;
        self.n0 = n;
        self.volume = volume;
        Ok(())
    }
}

#[cfg(test)]
mod tests;

/// [`Observe`](crate::observe::Observe) for a size-count scheme from its inherent
/// `counts`, `volume`, `moment` and `totals` (one definition for all four).
macro_rules! observe_counts {
    ([$($g:tt)*] $ty:ty) => {
        impl<$($g)*> crate::observe::Observe for $ty {
            fn volume(&self) -> f64 {
                <$ty>::volume(self)
            }
            fn particles(&self) -> u64 {
                <$ty>::particles(self)
            }
            fn moment(&self, order: f64) -> f64 {
                <$ty>::moment(self, order)
            }
            fn concentration(&self, a: f64, b: f64) -> f64 {
                crate::observe::concentration_of_counts(&self.counts(), <$ty>::volume(self), a, b)
            }
            fn gel_mass(&self) -> Option<f64> {
                Some(crate::observe::largest_of_counts(&self.counts(), <$ty>::volume(self)))
            }
            fn totals(&self) -> StepReport {
                <$ty>::totals(self)
            }
        }
    };
}

observe_counts!([K: CoagulationKernel, const R: usize, T: ProposalTree<R>] LowRank<K, R, T>);
observe_counts!([K: CoagulationKernel, const R: usize, const W: usize] Bucketed<K, R, W>);
observe_counts!([K: CoagulationKernel] crate::scheme::baseline::Inverse<K>);
observe_counts!([K: CoagulationKernel] crate::scheme::baseline::AcceptanceRejection<K>);
