//! Direct simulation over size counts: the Marcus–Lushnikov process of [`Dsa`](super::Dsa)
//! for integer sizes, its state held as counts `N_k` of particles of size k (the
//! state of the size-count schemes) instead of a list of particles.
//!
//! The algorithm is direct simulation's, with the product majorant h: proposals at rate
//! `(Σ_k h(k) N_k)² / (2V)`; sizes k and l drawn independently with probability
//! `h(k) N_k / Σ h N` from one sum tree over the sizes — a particle drawn by weight h,
//! then its size; when k = l the two draws are the same particle with probability
//! `1/N_k`, which is rejected as direct simulation rejects i = j; accepted with
//! `K(k, l) / (h(k) h(l))`, `N_k, N_l → N_k − 1, N_l − 1`, `N_{k+l} → N_{k+l} + 1`.
//! No particle doubling: the process is the Marcus–Lushnikov process of the initial
//! particles, so its law is the finite-N master equation's.
//!
//! Why a second representation: the tree has one leaf per size (a few thousand where
//! [`Dsa`](super::Dsa) has one per particle, 10^6 from 10^6 monomers) and stays in
//! cache, so a proposal costs what a low-rank proposal costs. The size table doubles
//! when a merge passes it (bounded by the memory budget and the size limit).
//!
//! What an event costs, and what keeps it small: the tree is 8-ary with a node per
//! cache line (both draws descend it side by side; the three moved leaves are
//! recomputed level by level), a kernel whose low-rank form is exact is evaluated
//! from factors cached per size (no cube roots for the Brownian kernel), and waiting
//! times come from the ziggurat. The figures are in `docs/results/eventflow-samplers.md`.

use super::super::population::{
    DEFAULT_MEMORY_BUDGET, Population, check_counts, dense_from_pairs, try_reserve, try_resize,
    within_budget,
};
use super::super::{Budget, Pending, Scheme, StepReport, check_target};
use super::{accept, majorant};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::{Ziggurat, below};
use crate::sample::wide_tree::WideTree;
use crate::scheme::check_pending;
use alloc::borrow::Cow;
use alloc::vec::Vec;
use rand_core::Rng;

mod edit;

/// Sizes below this start the table (the tree's smallest length).
const MIN_TABLE: usize = 64;

/// Bytes per size: the count, h and two tree nodes, and `2R` cached factors for a
/// kernel of rank R whose low-rank form is exact.
fn bytes_per_size(rank: usize) -> usize {
    8 + 8 + 16 + 16 * rank
}

/// The rank R whose factors `a_r, b_r` are cached per size: the kernel's rank when
/// its low-rank form is exact (`K = Σ_r a_r(x) b_r(y) + a_r(y) b_r(x)`), so a proposal
/// evaluates K from the table with `2R` products instead of calling the kernel (the
/// Brownian kernel's cube roots were a quarter of the time); 0 otherwise.
fn cached_rank<K: CoagulationKernel>(kernel: &K) -> usize {
    let r = kernel.rank();
    if kernel.low_rank_is_exact() && (1..=crate::kernel::MAX_RANK).contains(&r) {
        r
    } else {
        0
    }
}

/// Writes size `x`'s factors `[a_0 … a_{R−1}, b_0 … b_{R−1}]` into `out` (length 2R).
fn size_factors<K: CoagulationKernel>(kernel: &K, x: f64, out: &mut [f64]) {
    let r = out.len() / 2;
    let (a, b) = out.split_at_mut(r);
    kernel.factors(x, a, b);
}

/// Direct simulation over size counts (see the module docs).
pub struct DsaCounts<K> {
    kernel: K,
    /// `counts[k − 1] = N_k`, for k up to M (a power of two).
    counts: Vec<u64>,
    /// `h(k)` at `k − 1` (NaN where the kernel gives no valid majorant: such a size
    /// cannot be made, see `event`).
    h: Vec<f64>,
    /// `h(k) N_k` at leaf `k − 1`.
    tree: WideTree,
    /// The cached rank R (see [`cached_rank`]), and `fac[2R(k − 1)..2Rk]` = size k's
    /// factors `a_0 … a_{R−1}, b_0 … b_{R−1}` (empty when R = 0).
    rank: usize,
    fac: Vec<f64>,
    pop: Population,
    strict: bool,
    time: f64,
    pending: Option<Pending>,
    totals: StepReport,
}

impl<K> core::fmt::Debug for DsaCounts<K> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("DsaCounts")
            .field("particles", &self.pop.n)
            .field("max_size", &self.counts.len())
            .field("volume", &self.pop.volume)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel> DsaCounts<K> {
    /// Starts from `n0` monomers in volume `n0` (so `n_1(0) = 1`).
    pub fn monodisperse(kernel: K, n0: u64) -> Result<Self> {
        Self::new(kernel, &[n0], n0 as f64)
    }

    /// Starts from `counts[k − 1] = N_k` in volume `volume`.
    ///
    /// Errors: no particle or an overflowing total, a volume that is not finite and
    /// positive, a kernel without a product majorant (`Unsupported`) or one not valid at
    /// an occupied size, tables past the memory budget.
    pub fn new(kernel: K, counts: &[u64], volume: f64) -> Result<Self> {
        Self::new_with_memory_budget(kernel, counts, volume, DEFAULT_MEMORY_BUDGET)
    }

    /// [`new`](Self::new) with a memory budget of `bytes` for the size table (32 bytes
    /// a size, 16R more for a kernel whose rank-R low-rank form is exact), which the
    /// initial table must fit.
    pub fn new_with_memory_budget(
        kernel: K,
        counts: &[u64],
        volume: f64,
        bytes: usize,
    ) -> Result<Self> {
        let pop = Population::new(counts, volume)?.with_memory_budget(bytes);
        let mut s = DsaCounts {
            kernel,
            counts: Vec::new(),
            h: Vec::new(),
            tree: WideTree::default(),
            rank: 0,
            fac: Vec::new(),
            pop,
            strict: false,
            time: 0.0,
            pending: None,
            totals: StepReport::default(),
        };
        s.fill(counts)?;
        Ok(s)
    }

    /// Sets the largest particle size allowed; a merge past it makes `advance_to` fail
    /// with [`Error::Capacity`], the state as before.
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.pop.size_limit = limit;
        self
    }

    /// Sets the memory budget of the size table (32 bytes a size, 16R more for a kernel
    /// whose rank-R low-rank form is exact).
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.pop.memory_budget = bytes;
        self
    }

    /// Makes a kernel value above the majorant an error instead of a counted
    /// violation.
    pub fn with_strict_bound(mut self, strict: bool) -> Self {
        self.strict = strict;
        self
    }

    /// Builds the table for `counts` (validated first; nothing changes on error).
    fn fill(&mut self, counts: &[u64]) -> Result<()> {
        let t = table(
            &self.kernel,
            counts,
            self.pop.size_limit,
            self.pop.memory_budget,
        )?;
        self.install(t);
        self.pending = None;
        Ok(())
    }

    /// Takes the tables of `t`.
    fn install(&mut self, t: Tables) {
        self.counts = t.counts;
        self.h = t.h;
        self.tree = t.tree;
        self.rank = t.rank;
        self.fac = t.fac;
    }

    /// Doubles the table until size `s` fits (within the memory budget).
    fn grow(&mut self, s: u64) -> Result<()> {
        let need = usize::try_from(s)
            .ok()
            .and_then(usize::checked_next_power_of_two)
            .ok_or(Error::Overflow { name: "size table" })?;
        within_budget(
            need.checked_mul(bytes_per_size(self.rank)),
            self.pop.memory_budget,
        )?;
        let old = self.counts.len();
        let w = 2 * self.rank;
        // (every allocation before any table changes: a failure leaves them as they
        // were, the same length)
        try_reserve(&mut self.counts, need.saturating_sub(old))?;
        try_reserve(&mut self.h, need.saturating_sub(old))?;
        let fac_more = (need * w).saturating_sub(self.fac.len());
        try_reserve(&mut self.fac, fac_more)?;
        self.tree.resize_zero(need)?;
        try_resize(&mut self.counts, need, 0)?;
        try_resize(&mut self.h, need, f64::NAN)?;
        try_resize(&mut self.fac, need * w, 0.0)?;
        for k in old..need {
            let x = (k + 1) as f64;
            self.h[k] = majorant(&self.kernel, x).unwrap_or(f64::NAN);
            if w > 0 {
                size_factors(&self.kernel, x, &mut self.fac[k * w..(k + 1) * w]);
            }
        }
        Ok(())
    }

    /// The counts `[N_1, …, N_L]` up to the largest occupied size L.
    pub fn counts(&self) -> Cow<'_, [u64]> {
        Cow::Borrowed(&self.counts[..self.largest() as usize])
    }

    /// The largest occupied size.
    fn largest(&self) -> u64 {
        self.counts
            .iter()
            .rposition(|&c| c > 0)
            .map_or(0, |i| i as u64 + 1)
    }

    /// Calls `f(size, N)` for every occupied size, ascending.
    pub fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        for (i, &c) in self.counts.iter().enumerate() {
            if c > 0 {
                f(i as u64 + 1, c);
            }
        }
    }

    /// The simulation volume V.
    pub fn volume(&self) -> f64 {
        self.pop.volume
    }

    /// The size table's length M.
    pub fn max_size(&self) -> u64 {
        self.counts.len() as u64
    }

    /// Replaces the counts and the volume; time, totals and limits stay, the next
    /// proposal is drawn afresh. Errors (as for [`new`](Self::new)) change nothing.
    pub fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        let pop = Population::new(counts, volume)?;
        self.fill(counts)?;
        self.pop.n = pop.n;
        self.pop.n0 = pop.n;
        self.pop.volume = volume;
        Ok(())
    }

    /// Replaces the state by `counts[i]` particles of size `sizes[i]` in `volume`.
    pub fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
        let dense = dense_from_pairs(sizes, counts, self.pop.size_limit, self.pop.memory_budget)?;
        self.set_counts(&dense, volume)
    }

    /// Replaces the coagulation kernel (it needs a product majorant at every occupied
    /// size); the next proposal is drawn afresh.
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        let largest = self.largest() as usize;
        let t = table(
            &kernel,
            &self.counts[..largest],
            self.pop.size_limit,
            self.pop.memory_budget,
        )?;
        self.kernel = kernel;
        self.install(t);
        self.pending = None;
        Ok(())
    }

    /// Direct simulation never doubles its particles: nothing to turn on or off.
    pub fn set_doubling(&mut self, _on: bool) {}

    /// Sets the clock (finite, not negative); the next proposal is drawn afresh.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = super::super::check_time(t)?;
        self.pending = None;
        Ok(())
    }

    /// One proposal; `Ok(true)` when the state changed (errors change nothing).
    #[inline]
    fn event<R: Rng + ?Sized>(&mut self, rep: &mut StepReport, rng: &mut R) -> Result<bool> {
        let (k, l) = self.tree.sample_pair_rng(rng)?;
        if k == l {
            // the same particle with probability 1/N_k
            let nk = self.counts[k];
            if nk < 2 || below(rng, nk) == 0 {
                rep.rejections += 1;
                return Ok(false);
            }
        }
        let (x, y) = (k as u64 + 1, l as u64 + 1);
        let hh = self.h[k] * self.h[l];
        let kv = if self.rank > 0 {
            self.cached_rate(k, l)
        } else {
            self.kernel.rate(x as f64, y as f64)
        };
        if !accept(kv, hh, self.strict, &mut rep.bound_violations, rng)? {
            rep.rejections += 1;
            return Ok(false);
        }
        let s = self.pop.merged(x, y)?;
        if s as usize > self.counts.len() {
            self.grow(s)?;
        }
        let m = s as usize - 1;
        let hm = self.h[m];
        let wm = hm * (self.counts[m] + 1) as f64;
        if !(wm >= 0.0 && wm.is_finite()) {
            return Err(Error::InvalidRate {
                name: "product majorant h(x) of a merged size",
                value: hm,
            });
        }
        self.counts[k] -= 1;
        self.counts[l] -= 1;
        self.counts[m] += 1;
        self.pop.n -= 1;
        let weight = |i: usize| {
            let c = self.counts[i];
            (i, if c == 0 { 0.0 } else { self.h[i] * c as f64 })
        };
        let moved = self.tree.update_many([weight(k), weight(l), weight(m)]);
        if moved.is_err() {
            // (not reached: the weights were checked above) leave the state as it was
            self.counts[k] += 1;
            self.counts[l] += 1;
            self.counts[m] -= 1;
            self.pop.n += 1;
        }
        moved?;
        Ok(true)
    }

    /// `K(k + 1, l + 1)` from the cached factors (the kernel's low-rank form is exact).
    #[inline]
    fn cached_rate(&self, k: usize, l: usize) -> f64 {
        let r = self.rank;
        let fk = &self.fac[2 * r * k..2 * r * (k + 1)];
        let fl = &self.fac[2 * r * l..2 * r * (l + 1)];
        let mut s = 0.0;
        for q in 0..r {
            s += fk[q] * fl[r + q] + fl[q] * fk[r + q];
        }
        s
    }
}

/// The tables of a size-count state (see the fields of [`DsaCounts`]).
struct Tables {
    counts: Vec<u64>,
    h: Vec<f64>,
    tree: WideTree,
    rank: usize,
    fac: Vec<f64>,
}

/// The size table of `counts` under `kernel`: the counts padded to a power of two, `h`
/// at every size, the tree of `h(k) N_k`. Errors: no particle or an overflowing total,
/// a size past `limit`, tables past `budget`, a kernel without a valid majorant at an
/// occupied size, a weight that overflows.
fn table<K: CoagulationKernel>(
    kernel: &K,
    counts: &[u64],
    limit: u64,
    budget: usize,
) -> Result<Tables> {
    check_counts(counts)?;
    let largest = counts
        .iter()
        .rposition(|&c| c > 0)
        .map_or(0, |i| i as u64 + 1);
    if largest > limit {
        return Err(Error::Capacity {
            name: "maximum particle size",
            capacity: usize::try_from(limit).unwrap_or(usize::MAX),
        });
    }
    let m = counts.len().max(MIN_TABLE).next_power_of_two();
    let rank = cached_rank(kernel);
    within_budget(m.checked_mul(bytes_per_size(rank)), budget)?;
    for (i, &c) in counts.iter().enumerate() {
        if c > 0 {
            let h = majorant(kernel, (i + 1) as f64)?;
            crate::error::finite("h(k) N_k", h * c as f64)?;
        }
    }
    let mut full = Vec::new();
    try_resize(&mut full, m, 0u64)?;
    full[..counts.len()].copy_from_slice(counts);
    let mut h = Vec::new();
    try_resize(&mut h, m, f64::NAN)?;
    for (k, hk) in h.iter_mut().enumerate() {
        *hk = majorant(kernel, (k + 1) as f64).unwrap_or(f64::NAN);
    }
    let mut w = Vec::new();
    try_resize(&mut w, m, 0.0)?;
    for ((wk, &c), &hk) in w.iter_mut().zip(&full).zip(&h) {
        if c > 0 {
            *wk = hk * c as f64;
        }
    }
    let mut fac = Vec::new();
    try_resize(&mut fac, m * 2 * rank, 0.0)?;
    if rank > 0 {
        for (k, f) in fac.chunks_exact_mut(2 * rank).enumerate() {
            size_factors(kernel, (k + 1) as f64, f);
        }
    }
    Ok(Tables {
        counts: full,
        h,
        tree: WideTree::from_weights(&w)?,
        rank,
        fac,
    })
}

impl<K: CoagulationKernel> Scheme for DsaCounts<K> {
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        self.totals
    }

    fn advance_within<R: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut R,
    ) -> Result<StepReport> {
        check_target(self.time, t)?;
        let mut rep = StepReport::default();
        let out = loop {
            let p = match self.pending {
                Some(p) => p,
                None => {
                    // the mean waiting time 2V / (Σ h N)² with one division (the
                    // rate's two divisions were a tenth of an event's time)
                    let a = self.tree.total();
                    let aa = a * a;
                    if self.pop.n < 2 || aa.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater)
                    {
                        self.time = t;
                        break Ok(());
                    }
                    let mean = (2.0 * self.pop.volume) / aa;
                    // the rate 1 / mean must be a finite double
                    if mean.is_nan() || mean < 1.0 / f64::MAX {
                        break Err(Error::InvalidRate {
                            name: "total event rate (overflows a double)",
                            value: 1.0 / mean,
                        });
                    }
                    if let Err(e) = Pending::check(self.time, mean) {
                        break Err(e);
                    }
                    Pending::after(self.time, mean, Ziggurat::new().sample(rng))
                }
            };
            self.pending = Some(p);
            if p.at > t {
                self.time = t;
                break Ok(());
            }
            if !budget.take(1) {
                rep.interrupted = true;
                break Ok(());
            }
            rep.proposals += 1;
            match self.event(&mut rep, rng) {
                Ok(changed) => {
                    rep.events += u64::from(changed);
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

impl<K: CoagulationKernel> crate::observe::Observe for DsaCounts<K> {
    fn volume(&self) -> f64 {
        self.pop.volume
    }
    fn particles(&self) -> u64 {
        self.pop.n
    }
    fn moment(&self, order: f64) -> f64 {
        // (as the other size-count schemes sum it: the same bits from the same counts)
        crate::observe::moment_of_pairs(|f| self.for_each_count(f), self.pop.volume, order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        let w = 1.0 / self.pop.volume;
        crate::observe::sum_concentration(
            self.counts
                .iter()
                .enumerate()
                .filter(|(_, c)| **c > 0)
                .map(|(i, &c)| ((i + 1) as f64, c as f64 * w)),
            a,
            b,
        )
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        let w = 1.0 / self.pop.volume;
        self.for_each_count(&mut |s, c| f(s as f64, c as f64 * w));
    }
    /// The largest cluster's mass over V (E–W 6.15).
    fn gel_mass(&self) -> Option<f64> {
        Some(self.largest() as f64 / self.pop.volume)
    }
}

impl<K: CoagulationKernel> crate::checkpoint::Checkpoint for DsaCounts<K> {
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::DSA_COUNTS);
        w.u64(self.pop.size_limit);
        w.f64(self.pop.volume);
        w.u64(u64::from(self.strict));
        w.f64(self.time);
        Pending::save(&self.pending, w);
        self.totals.save(w);
        w.u64s(&self.counts);
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, tag::DSA_COUNTS)?;
        let (limit, volume, strict, time) = (r.u64()?, r.f64()?, r.u64()?, r.f64()?);
        if limit < 2
            || !(volume > 0.0 && volume.is_finite())
            || strict > 1
            || !(time >= 0.0 && time.is_finite())
        {
            return Err(bad("invalid size limit, volume, flag or time"));
        }
        let pending = Pending::read(r, time)?;
        let totals = StepReport::read(r)?;
        let counts = r.u64s()?;
        r.finish()?;
        let m = counts.len();
        if !m.is_power_of_two() || m < MIN_TABLE {
            return Err(bad("invalid size table"));
        }
        if counts
            .iter()
            .rposition(|&c| c > 0)
            .is_some_and(|i| i as u64 >= limit)
        {
            return Err(bad("a particle is larger than the size limit"));
        }
        let pop = Population::new(&counts, volume).map_err(|_| bad("no particle, or too many"))?;
        let t = table(&self.kernel, &counts, limit, self.pop.memory_budget).map_err(|_| {
            bad("a size where the kernel's majorant is invalid, or past the budget")
        })?;
        let a = t.tree.total();
        let rate = if pop.n < 2 {
            0.0
        } else {
            a * (a / (2.0 * volume))
        };
        check_pending(&pending, rate)?;
        self.install(t);
        self.pop.n = pop.n;
        self.pop.n0 = self.pop.n0.max(pop.n);
        self.pop.volume = volume;
        self.pop.size_limit = limit;
        self.strict = strict == 1;
        self.time = time;
        self.pending = pending;
        self.totals = totals;
        Ok(())
    }
}
