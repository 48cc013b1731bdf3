//! Inverse method (Gillespie on sizes) baseline (Osinsky 2023, §2).
//!
//! With `r_i = Σ_j K(i, j) N_j` and `s_i = N_i (r_i − K(i, i))` (pairs of distinct
//! particles), the total collision rate is `S / (2V)`, `S = Σ_i s_i`. Each event draws i ∝
//! `s_i`, then j ∝ `K(i, j) (N_j − δ_ij)`, both by a linear scan over the occupied sizes.
//! The row sums `r_k` are kept up to date incrementally: after an event only `N_i`,
//! `N_j`, `N_{i+j}` change, so every `r_k` moves by `Σ_m K(k, m) ΔN_m` — O(#occupied)
//! kernel evaluations per event (the row of i is reused from the j scan).
//!
//! Kernel values between sizes up to [`CACHE_DIM`] are cached in a size-indexed
//! matrix (filled on first use, at most 32 MB), so an update costs a load and a
//! multiply-add rather than a kernel evaluation — as an honest baseline should.
//!
//! Every kernel value an event needs (the rows of both colliding sizes and of the
//! merged size) is evaluated and validated before anything changes, so a kernel that
//! returns NaN or a negative rate makes `advance_to` fail with the state as it was
//! before that event.

use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::scheme::population::{
    DEFAULT_MEMORY_BUDGET, Population, rate_overflow, try_reserve, try_resize, within_budget,
};
use crate::scheme::{Budget, Pending, Scheme, StepReport, check_target, exp1, open_unit};
use alloc::vec;
use alloc::vec::Vec;
use rand_core::Rng;

mod edit;

const NONE: u32 = u32::MAX;

/// Kernel values `K(x, y)` for `x, y ≤ CACHE_DIM` are cached (`CACHE_DIM²` doubles).
pub const CACHE_DIM: usize = 2048;

/// Inverse (Gillespie-on-sizes) method over the occupied sizes. O(#occupied) per event.
///
/// ```
/// use coagula_core::kernel::Coagulation;
/// use coagula_core::scheme::{Scheme, baseline::Inverse};
/// let mut rng = rand_pcg::Pcg64Mcg::new(5);
/// let mut sim = Inverse::monodisperse(Coagulation::constant(1.0).unwrap(), 10_000).unwrap();
/// sim.advance_to(1.0, &mut rng).unwrap();
/// assert!((sim.moment(0.0) - 1.0 / 1.5).abs() < 0.02);
/// ```
pub struct Inverse<K> {
    kernel: K,
    /// Occupied sizes, their counts, row sums r and diagonal K(i, i).
    size: Vec<u64>,
    count: Vec<u64>,
    row: Vec<f64>,
    diag: Vec<f64>,
    /// `slot[size - 1]` = position in the occupied arrays, or NONE.
    slot: Vec<u32>,
    /// Scratch: K(i, ·), K(j, ·) and K(i + j, ·) over the occupied slots.
    scratch: Vec<f64>,
    scratch_j: Vec<f64>,
    scratch_m: Vec<f64>,
    /// `K(x, y)` at `(x − 1) · dim + y − 1` for `x, y ≤ dim`, or −1 when not yet
    /// evaluated; `dim` doubles with the largest size, up to `cache_max`.
    cache: Vec<f64>,
    dim: usize,
    /// Largest `dim`: [`CACHE_DIM`], or less for few particles (the occupied sizes are
    /// then few, and a 32 MB table per small system would cost more than it saves).
    cache_max: usize,
    /// N, N0, V, the size limit and the memory budget.
    pop: Population,
    time: f64,
    /// The next event, drawn at the current rate (kept between calls).
    pending: Option<Pending>,
    totals: StepReport,
}

impl<K> core::fmt::Debug for Inverse<K> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Inverse")
            .field("occupied", &self.size.len())
            .field("particles", &self.pop.n)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel> Inverse<K> {
    /// Starts from `n0` monomers in volume `n0`.
    pub fn monodisperse(kernel: K, n0: u64) -> Result<Self> {
        Self::new(kernel, &[n0], n0 as f64)
    }

    /// Starts from `counts[i - 1] = N_i` in volume `volume`.
    pub fn new(kernel: K, counts: &[u64], volume: f64) -> Result<Self> {
        Self::new_with_memory_budget(kernel, counts, volume, DEFAULT_MEMORY_BUDGET)
    }

    /// [`new`](Self::new) with a memory budget of `bytes` (see
    /// [`with_memory_budget`](Self::with_memory_budget)), which the initial size index
    /// must already fit.
    pub fn new_with_memory_budget(
        kernel: K,
        counts: &[u64],
        volume: f64,
        bytes: usize,
    ) -> Result<Self> {
        let pop = Population::new(counts, volume)?.with_memory_budget(bytes);
        let n = pop.n;
        let len = counts.len().next_power_of_two();
        within_budget(len.checked_mul(core::mem::size_of::<u32>()), bytes)?;
        let mut s = Inverse {
            kernel,
            size: Vec::new(),
            count: Vec::new(),
            row: Vec::new(),
            diag: Vec::new(),
            slot: Vec::new(),
            scratch: Vec::new(),
            scratch_j: Vec::new(),
            scratch_m: Vec::new(),
            cache: Vec::new(),
            dim: 0,
            cache_max: (n.min(CACHE_DIM as u64) as usize)
                .next_power_of_two()
                .clamp(64, CACHE_DIM),
            pop,
            time: 0.0,
            pending: None,
            totals: StepReport::default(),
        };
        try_resize(&mut s.slot, len, NONE)?;
        for (i, &c) in counts.iter().enumerate() {
            if c > 0 {
                let d = s.rate(i as u64 + 1, i as u64 + 1)?;
                s.slot[i] = s.size.len() as u32;
                s.size.push(i as u64 + 1);
                s.count.push(c);
                s.row.push(0.0);
                s.diag.push(d);
            }
        }
        for a in 0..s.size.len() {
            let mut r = 0.0;
            for b in 0..s.size.len() {
                r += s.rate(s.size[a], s.size[b])? * s.count[b] as f64;
            }
            s.row[a] = r;
        }
        Ok(s)
    }

    /// Sets the largest particle size allowed.
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.pop.size_limit = limit;
        self
    }

    /// `K(x, y)`, validated, from the cache when both sizes are within it.
    #[inline]
    fn rate(&mut self, x: u64, y: u64) -> Result<f64> {
        let (xi, yi) = (x as usize - 1, y as usize - 1);
        if xi.max(yi) >= self.dim {
            if xi.max(yi) >= self.cache_max {
                return crate::kernel::checked_rate(&self.kernel, x as f64, y as f64);
            }
            self.grow_cache(xi.max(yi) + 1);
        }
        let v = self.cache[xi * self.dim + yi];
        if v >= 0.0 {
            return Ok(v);
        }
        let v = crate::kernel::checked_rate(&self.kernel, x as f64, y as f64)?;
        self.cache[xi * self.dim + yi] = v;
        self.cache[yi * self.dim + xi] = v;
        Ok(v)
    }

    /// Re-lays the cache out for sizes up to `need` (a power of two, at least 64).
    #[cold]
    fn grow_cache(&mut self, need: usize) {
        let dim = need.next_power_of_two().clamp(64, self.cache_max);
        let mut cache = Vec::new();
        if try_resize(&mut cache, dim * dim, -1.0).is_err() {
            // no memory for a larger cache: evaluate beyond it directly
            self.cache_max = self.dim.max(1);
            return;
        }
        for x in 0..self.dim {
            cache[x * dim..x * dim + self.dim]
                .copy_from_slice(&self.cache[x * self.dim..(x + 1) * self.dim]);
        }
        self.cache = cache;
        self.dim = dim;
    }

    /// Counts per size `[N_1, ..., N_M]`.
    pub fn counts(&self) -> Vec<u64> {
        let mut c = vec![0u64; self.size.iter().copied().max().unwrap_or(0) as usize];
        for (s, n) in self.size.iter().zip(&self.count) {
            c[*s as usize - 1] = *n;
        }
        c
    }

    /// Calls `f(size, N)` for every occupied size, ascending (sorting the occupied
    /// sizes: O(occupied) memory, no count vector).
    pub fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        let mut order: Vec<u32> = (0..self.size.len() as u32).collect();
        order.sort_unstable_by_key(|&a| self.size[a as usize]);
        for a in order {
            f(self.size[a as usize], self.count[a as usize]);
        }
    }

    /// Current number of simulation particles N.
    pub fn particles(&self) -> u64 {
        self.pop.n
    }

    /// The simulation volume V.
    pub fn volume(&self) -> f64 {
        self.pop.volume
    }

    /// Largest size present.
    pub fn max_size(&self) -> u64 {
        self.size.iter().copied().max().unwrap_or(0)
    }

    /// Number of occupied sizes.
    pub fn occupied(&self) -> usize {
        self.size.len()
    }

    /// The moment `Σ_i i^m N_i / V`.
    pub fn moment(&self, m: f64) -> f64 {
        let w = 1.0 / self.pop.volume;
        crate::observe::moment(
            self.size
                .iter()
                .zip(&self.count)
                .map(|(&s, &c)| (s as f64, c as f64 * w)),
            m,
        )
    }

    /// Totals over the whole run.
    pub fn totals(&self) -> StepReport {
        self.totals
    }
}

impl<K: CoagulationKernel> Scheme for Inverse<K> {
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        Inverse::totals(self)
    }

    fn advance_within<R: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut R,
    ) -> Result<StepReport> {
        check_target(self.time, t)?;
        let mut rep = StepReport::default();
        let result = loop {
            let occ = self.size.len();
            let mut total = 0.0;
            for a in 0..occ {
                total += self.count[a] as f64 * (self.row[a] - self.diag[a]).max(0.0);
            }
            // the next event: kept from the last call, or drawn at the rate just summed
            let next = match self.pending {
                Some(p) => p,
                None => {
                    if !total.is_finite() {
                        break Err(rate_overflow(total));
                    }
                    if self.pop.n < 2 || total <= 0.0 {
                        self.time = t;
                        break Ok(());
                    }
                    let mean_dt = 2.0 * self.pop.volume / total;
                    if let Err(e) = Pending::check(self.time, mean_dt) {
                        break Err(e);
                    }
                    let p = Pending::after(self.time, mean_dt, exp1(rng));
                    self.pending = Some(p);
                    p
                }
            };
            if next.at > t {
                self.time = t;
                break Ok(());
            }
            if !budget.take(1) {
                rep.interrupted = true;
                break Ok(());
            }
            // i ∝ s_i
            let mut u = total * open_unit(rng);
            let mut ia = occ - 1;
            for a in 0..occ {
                u -= self.count[a] as f64 * (self.row[a] - self.diag[a]).max(0.0);
                if u <= 0.0 {
                    ia = a;
                    break;
                }
            }
            // j ∝ K(i, j)(N_j − δ_ij), keeping K(i, ·) for the row update
            let xi = self.size[ia];
            self.scratch.clear();
            let mut wsum = 0.0;
            let mut failed = None;
            for b in 0..occ {
                match self.rate(xi, self.size[b]) {
                    Ok(k) => {
                        self.scratch.push(k);
                        let nb = self.count[b] - u64::from(b == ia);
                        wsum += k * nb as f64;
                    }
                    Err(e) => {
                        failed = Some(e);
                        break;
                    }
                }
            }
            if let Some(e) = failed {
                break Err(e);
            }
            let mut v = wsum * open_unit(rng);
            let mut ja = occ - 1;
            for b in 0..occ {
                let nb = self.count[b] - u64::from(b == ia);
                v -= self.scratch[b] * nb as f64;
                if v <= 0.0 && nb > 0 {
                    ja = b;
                    break;
                }
            }
            let xj = self.size[ja];
            let merged = match self.pop.merged(xi, xj) {
                Ok(m) => m,
                Err(e) => break Err(e),
            };
            // every kernel value the event needs, validated before anything changes
            let dm = match self.event_rows(xj, merged) {
                Ok(d) => d,
                Err(e) => break Err(e),
            };
            if let Err(e) = self.reserve_size(merged) {
                break Err(e);
            }
            rep.proposals += 1;
            self.time = next.at;
            self.pending = None;
            self.apply_event(ia, ja, merged, dm);
            self.pop.n -= 1;
            rep.events += 1;
            if self.pop.doubling_due() {
                for a in 0..self.size.len() {
                    self.count[a] *= 2;
                    self.row[a] *= 2.0;
                }
                self.pop.double();
                rep.doublings += 1;
                budget.doubled(self.time);
            }
        };
        rep.time = self.time;
        self.totals.accumulate(&rep);
        result.map(|()| rep)
    }
}

impl<K: CoagulationKernel> Inverse<K> {
    /// Fills `scratch_j = K(·, x_j)` and `scratch_m = K(·, merged)` over the occupied
    /// slots (`scratch` already holds `K(x_i, ·)`) and returns `K(merged, merged)`; an
    /// invalid kernel value is an error, with nothing changed.
    fn event_rows(&mut self, xj: u64, merged: u64) -> Result<f64> {
        let (mut kj, mut km) = (
            core::mem::take(&mut self.scratch_j),
            core::mem::take(&mut self.scratch_m),
        );
        kj.clear();
        km.clear();
        let mut fill = || -> Result<f64> {
            for a in 0..self.size.len() {
                let x = self.size[a];
                kj.push(self.rate(x, xj)?);
                km.push(self.rate(x, merged)?);
            }
            self.rate(merged, merged)
        };
        let d = fill();
        self.scratch_j = kj;
        self.scratch_m = km;
        d
    }

    /// Makes room in the size index for size `x` (the only allocation of an event).
    /// Also makes room for one more occupied size, so that the event itself
    /// allocates nothing.
    fn reserve_size(&mut self, x: u64) -> Result<()> {
        let need = usize::try_from(x).unwrap_or(usize::MAX);
        if need > self.slot.len() {
            let len = need.checked_next_power_of_two().unwrap_or(usize::MAX);
            within_budget(
                len.checked_mul(core::mem::size_of::<u32>()),
                self.pop.memory_budget,
            )?;
            try_resize(&mut self.slot, len, NONE)?;
        }
        try_reserve(&mut self.size, 1)?;
        try_reserve(&mut self.count, 1)?;
        try_reserve(&mut self.row, 1)?;
        try_reserve(&mut self.diag, 1)
    }

    /// Sets the memory budget in bytes of the size index (default
    /// [`DEFAULT_MEMORY_BUDGET`]): a size beyond it makes
    /// `advance_to` fail with [`Error::Capacity`], the state as before the event.
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.pop.memory_budget = bytes;
        self
    }

    /// Applies a collision of the particles in slots `ia` and `ja` (equal for two
    /// particles of one size) into size `merged`, with the rows of `event_rows`:
    /// infallible, so an event is applied whole or not at all.
    fn apply_event(&mut self, ia: usize, ja: usize, merged: u64, dm: f64) {
        let occ = self.size.len();
        for a in 0..occ {
            self.row[a] += self.scratch_m[a] - self.scratch[a] - self.scratch_j[a];
        }
        self.count[ia] -= 1;
        self.count[ja] -= 1;
        let mi = merged as usize - 1;
        if self.slot[mi] == NONE {
            // a new occupied size: its row from scratch (it includes itself)
            let mut r = dm;
            for b in 0..occ {
                r += self.scratch_m[b] * self.count[b] as f64;
            }
            self.slot[mi] = occ as u32;
            self.size.push(merged);
            self.count.push(1);
            self.row.push(r);
            self.diag.push(dm);
        } else {
            self.count[self.slot[mi] as usize] += 1;
        }
        // emptied slots go, the higher index first so the other keeps its place
        let (hi, lo) = (ia.max(ja), ia.min(ja));
        if self.count[hi] == 0 {
            self.remove_slot(hi);
        }
        if lo != hi && self.count[lo] == 0 {
            self.remove_slot(lo);
        }
    }

    /// Swap-removes occupied slot `a` (its count is zero).
    fn remove_slot(&mut self, a: usize) {
        let last = self.size.len() - 1;
        self.slot[self.size[a] as usize - 1] = NONE;
        if a != last {
            self.slot[self.size[last] as usize - 1] = a as u32;
        }
        self.size.swap_remove(a);
        self.count.swap_remove(a);
        self.row.swap_remove(a);
        self.diag.swap_remove(a);
    }
}

impl<K: CoagulationKernel> crate::checkpoint::Checkpoint for Inverse<K> {
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::INVERSE);
        w.u64(self.pop.size_limit);
        w.u64(self.pop.n);
        w.u64(self.pop.n0);
        w.f64(self.pop.volume);
        w.f64(self.time);
        Pending::save(&self.pending, w);
        self.totals.save(w);
        w.u64s(&self.size);
        w.u64s(&self.count);
        w.f64s(&self.row);
        w.f64s(&self.diag);
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        check_header(r, tag::INVERSE)?;
        let (size_limit, n, n0) = (r.u64()?, r.u64()?, r.u64()?);
        let (volume, time) = (r.f64()?, r.f64()?);
        let pending = Pending::read(r, time)?;
        let totals = StepReport::read(r)?;
        let (size, count, row, diag) = (r.u64s()?, r.u64s()?, r.f64s()?, r.f64s()?);
        let k = size.len();
        if count.len() != k
            || row.len() != k
            || diag.len() != k
            || size.iter().any(|&s| s == 0 || s > size_limit)
        {
            return Err(Error::Checkpoint {
                what: "inconsistent occupied sizes",
            });
        }
        if count.iter().try_fold(0u64, |a, &c| a.checked_add(c)) != Some(n) {
            return Err(Error::Checkpoint {
                what: "counts do not add up",
            });
        }
        if !(volume > 0.0 && volume.is_finite() && time >= 0.0 && time.is_finite() && n <= n0)
            || count.contains(&0)
        {
            return Err(Error::Checkpoint {
                what: "invalid volume, time, particle number or count",
            });
        }
        r.finish()?;
        // the kernel's diagonal exactly, and the row sums Σ_b K(a, b) N_b up to the
        // rounding of their incremental updates (O(occupied²), as set_kernel)
        let mut fresh = Vec::new();
        try_resize(&mut fresh, k, 0.0)?;
        for a in 0..k {
            let x = size[a] as f64;
            if crate::kernel::checked_rate(&self.kernel, x, x)?.to_bits() != diag[a].to_bits() {
                return Err(Error::Checkpoint {
                    what: "diagonal rates do not match the kernel",
                });
            }
            for b in 0..k {
                fresh[a] +=
                    crate::kernel::checked_rate(&self.kernel, x, size[b] as f64)? * count[b] as f64;
            }
        }
        // (a row sum that overflows — a huge kernel times the counts — is a state the
        // scheme holds and refuses to advance from, with an error, until set_kernel or
        // set_counts rebuilds it: its kept row may be anything non-finite, or a finite
        // sum of differently rounded terms; a clone of it must restore. Found by
        // fuzzing: clones of such sims were refused.)
        let scale = fresh
            .iter()
            .filter(|w| w.is_finite())
            .fold(0.0f64, |a, &b| a.max(b));
        if row.iter().zip(&fresh).any(|(&g, &w)| {
            w.is_finite() && !(g.is_finite() && (g - w).abs() <= 1e-6 * w + 1e-9 * scale)
        }) {
            return Err(Error::Checkpoint {
                what: "row sums do not match the counts and the kernel",
            });
        }
        let max = size.iter().copied().max().unwrap_or(1) as usize;
        let len = max.checked_next_power_of_two().unwrap_or(usize::MAX);
        within_budget(
            len.checked_mul(core::mem::size_of::<u32>()),
            self.pop.memory_budget,
        )?;
        let mut slot = Vec::new();
        try_resize(&mut slot, len, NONE)?;
        for (a, &s) in size.iter().enumerate() {
            if slot[s as usize - 1] != NONE {
                return Err(Error::Checkpoint {
                    what: "a size occurs twice",
                });
            }
            slot[s as usize - 1] = a as u32;
        }
        // a kept event needs events to come, at the rate it was drawn from
        if let Some(p) = pending {
            let total: f64 = (0..k)
                .map(|a| count[a] as f64 * (row[a] - diag[a]).max(0.0))
                .sum();
            let live = n >= 2 && total > 0.0;
            if !live || (2.0 * volume / total).to_bits() != p.mean_dt.to_bits() {
                return Err(Error::Checkpoint {
                    what: "the pending event does not match the state's rate",
                });
            }
        }
        self.pop.size_limit = size_limit;
        self.pop.n = n;
        self.pop.n0 = n0;
        self.pop.volume = volume;
        self.time = time;
        self.pending = pending;
        self.totals = totals;
        self.size = size;
        self.count = count;
        self.row = row;
        self.diag = diag;
        self.slot = slot;
        Ok(())
    }
}

impl<K: CoagulationKernel> Inverse<K> {
    /// Replaces the kernel; every row sum is recomputed (O(occupied²)). Errors leave
    /// the scheme unchanged.
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        let counts = self.counts();
        let fresh = Inverse::new(kernel, &counts, self.pop.volume)?;
        self.install(fresh);
        Ok(())
    }

    /// Replaces the counts and the volume; the particle number becomes the reference
    /// for particle doubling. Errors leave the scheme unchanged.
    pub fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()>
    where
        K: Clone,
    {
        let fresh = Inverse::new(self.kernel.clone(), counts, volume)?;
        self.install(fresh);
        Ok(())
    }

    /// [`set_counts`](Self::set_counts) from `(size, count)` pairs (each size at most
    /// once, within the size limit).
    pub fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()>
    where
        K: Clone,
    {
        let dense = crate::scheme::population::dense_from_pairs(
            sizes,
            counts,
            self.pop.size_limit,
            self.pop.memory_budget,
        )?;
        self.set_counts(&dense, volume)
    }

    /// Turns particle doubling on or off (kept across `set_counts`; a checkpoint does
    /// not carry it).
    pub fn set_doubling(&mut self, on: bool) {
        self.pop.doubling = on;
    }

    /// Sets the clock (finite, not negative): a host that keeps its own time origin.
    /// The next event is drawn afresh from the new time.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = crate::scheme::check_time(t)?;
        self.pending = None;
        Ok(())
    }

    /// Takes the state of `fresh`, keeping time, totals and the size limit.
    fn install(&mut self, fresh: Inverse<K>) {
        let (time, totals, limit, budget, doubling) = (
            self.time,
            self.totals,
            self.pop.size_limit,
            self.pop.memory_budget,
            self.pop.doubling,
        );
        *self = fresh;
        self.time = time;
        self.pending = None;
        self.totals = totals;
        self.pop.size_limit = limit;
        self.pop.memory_budget = budget;
        self.pop.doubling = doubling;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Coagulation;

    /// The incrementally kept row sums equal a fresh evaluation of `Σ_j K(i, j) N_j`,
    /// with sizes inside the kernel cache, beyond it, and the cache growing on the way.
    #[test]
    fn cached_row_sums_match_direct_evaluation() {
        let mut init = alloc::vec![0u64; CACHE_DIM + 500];
        init[..40].fill(30);
        init[CACHE_DIM + 400..].fill(2);
        let v = init.iter().sum::<u64>() as f64;
        let mut s = Inverse::new(Coagulation::free_molecular(), &init, v).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::new(11);
        for i in 1..=40 {
            s.advance_to(f64::from(i) * 2e-4, &mut rng).unwrap();
            for a in 0..s.size.len() {
                let x = s.size[a] as f64;
                let direct: f64 = (0..s.size.len())
                    .map(|b| s.kernel.rate(x, s.size[b] as f64) * s.count[b] as f64)
                    .sum();
                assert!(
                    (s.row[a] - direct).abs() <= 1e-9 * direct,
                    "size {x}: {} vs {direct}",
                    s.row[a]
                );
            }
        }
        assert!(s.totals().events > 100);
        assert!(s.dim >= 64 && s.max_size() as usize > CACHE_DIM);
    }
}
