//! Acceptance–rejection baseline (Osinsky 2023, §2): two distinct particles uniformly,
//! accepted with `K(i, j) / C_max`; time advances at every proposal.

use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::scheme::population::{
    DEFAULT_MEMORY_BUDGET, Population, bad_handle, rate_overflow, try_reserve, within_budget,
};
use crate::scheme::{Budget, Pending, Scheme, StepReport, check_target, exp1, open_unit};
use crate::tree::Weight;
use alloc::vec::Vec;
use rand_core::Rng;

/// Acceptance–rejection on a list of particle sizes: O(1) per proposal.
///
/// `C_max = sup K` over sizes `1..=max present` comes from
/// [`CoagulationKernel::sup_rate`] and is recomputed whenever the largest size grows.
/// Proposals arrive at rate `C_max N (N − 1) / (2V)`.
///
/// ```
/// use coagula_core::kernel::Coagulation;
/// use coagula_core::scheme::{Scheme, baseline::AcceptanceRejection};
/// let mut rng = rand_pcg::Pcg64Mcg::new(3);
/// let mut sim = AcceptanceRejection::monodisperse(Coagulation::constant(1.0).unwrap(), 10_000).unwrap();
/// sim.advance_to(1.0, &mut rng).unwrap();
/// assert!((sim.moment(0.0) - 1.0 / 1.5).abs() < 0.02);
/// ```
pub struct AcceptanceRejection<K> {
    kernel: K,
    sizes: Vec<u64>,
    /// N (= the list's length), N0, V, the size limit and the memory budget.
    pop: Population,
    time: f64,
    /// The next proposal, drawn at the current rate (kept between calls).
    pending: Option<Pending>,
    max_present: u64,
    cmax: f64,
    totals: StepReport,
}

impl<K> core::fmt::Debug for AcceptanceRejection<K> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("AcceptanceRejection")
            .field("particles", &self.sizes.len())
            .field("max_size", &self.max_present)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel> AcceptanceRejection<K> {
    /// Starts from `n0` monomers in volume `n0`.
    pub fn monodisperse(kernel: K, n0: u64) -> Result<Self> {
        Self::new(kernel, &[n0], n0 as f64)
    }

    /// Starts from `counts[i - 1] = N_i` in volume `volume`. Errors if the kernel has no
    /// `sup_rate` (or a NaN one), the counts are empty, the volume is not positive, or
    /// the particle list (8 bytes a particle) would pass
    /// [`DEFAULT_MEMORY_BUDGET`] (see
    /// [`new_with_memory_budget`](Self::new_with_memory_budget) for more).
    pub fn new(kernel: K, counts: &[u64], volume: f64) -> Result<Self> {
        Self::new_with_memory_budget(kernel, counts, volume, DEFAULT_MEMORY_BUDGET)
    }

    /// [`new`](Self::new) with a memory budget of `bytes` for the particle list: the
    /// list of N0 sizes, 8 bytes each, must fit it (a particle doubling never lets the
    /// list pass N0). A refused allocation is [`Error::Capacity`] too, never an abort.
    pub fn new_with_memory_budget(
        kernel: K,
        counts: &[u64],
        volume: f64,
        bytes: usize,
    ) -> Result<Self> {
        let pop = Population::new(counts, volume)?.with_memory_budget(bytes);
        let sizes = Self::particle_list(counts, pop.n, bytes)?;
        let max_present = sizes.iter().copied().max().unwrap_or(1);
        let mut s = AcceptanceRejection {
            kernel,
            sizes,
            pop,
            time: 0.0,
            pending: None,
            max_present,
            cmax: 0.0,
            totals: StepReport::default(),
        };
        s.cmax = s.sup(max_present)?;
        Ok(s)
    }

    /// The sizes of `n` particles given by `counts`, in a list checked against the
    /// budget and allocated with `try_reserve`.
    fn particle_list(counts: &[u64], n: u64, budget: usize) -> Result<Vec<u64>> {
        let len = usize::try_from(n).map_err(|_| Error::Capacity {
            name: "particles (address space)",
            capacity: usize::MAX,
        })?;
        within_budget(len.checked_mul(core::mem::size_of::<u64>()), budget)?;
        let mut sizes = Vec::new();
        try_reserve(&mut sizes, len)?;
        for (i, &c) in counts.iter().enumerate() {
            sizes.extend(core::iter::repeat_n(i as u64 + 1, c as usize));
        }
        Ok(sizes)
    }

    /// Sets the largest particle size allowed.
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.pop.size_limit = limit;
        self
    }

    fn sup(&self, max: u64) -> Result<f64> {
        let c = self
            .kernel
            .sup_rate(1.0, max as f64)
            .ok_or(Error::Unsupported {
                what: "sup of the kernel (needed by acceptance-rejection)",
            })?;
        if !(c >= 0.0 && c.is_finite()) {
            return Err(Error::InvalidRate {
                name: "kernel supremum",
                value: c,
            });
        }
        Ok(c)
    }

    /// Counts per size, `[N_1, ..., N_max]` (O(N)).
    pub fn counts(&self) -> Vec<u64> {
        let mut c = alloc::vec![0u64; self.max_present as usize];
        for &s in &self.sizes {
            c[s as usize - 1] += 1;
        }
        c
    }

    /// Calls `f(size, N)` for every occupied size, ascending (a sorted copy of the
    /// particle list: no count vector).
    pub fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        let mut sizes = self.sizes.clone();
        sizes.sort_unstable();
        let mut i = 0;
        while i < sizes.len() {
            let j = i + sizes[i..].iter().take_while(|&&s| s == sizes[i]).count();
            f(sizes[i], (j - i) as u64);
            i = j;
        }
    }

    /// The particle sizes.
    pub fn sizes(&self) -> &[u64] {
        &self.sizes
    }

    /// Current number of simulation particles N.
    pub fn particles(&self) -> u64 {
        self.sizes.len() as u64
    }

    /// The simulation volume V.
    pub fn volume(&self) -> f64 {
        self.pop.volume
    }

    /// Largest size present.
    pub fn max_size(&self) -> u64 {
        self.max_present
    }

    /// The moment `Σ_p x_p^m / V` (O(N)).
    pub fn moment(&self, m: f64) -> f64 {
        let w = 1.0 / self.pop.volume;
        crate::observe::moment(self.sizes.iter().map(|&s| (s as f64, w)), m)
    }

    /// Totals over the whole run.
    pub fn totals(&self) -> StepReport {
        self.totals
    }
}

impl<K: CoagulationKernel> Scheme for AcceptanceRejection<K> {
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        AcceptanceRejection::totals(self)
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
            let n = self.sizes.len() as u64;
            // the next proposal: kept from the last call, or drawn at the current rate
            let next = match self.pending {
                Some(p) => p,
                None => {
                    if n < 2 || self.cmax <= 0.0 {
                        self.time = t;
                        break Ok(());
                    }
                    let rate = self.cmax * (n * (n - 1)) as f64 / (2.0 * self.pop.volume);
                    if !rate.is_finite() {
                        break Err(rate_overflow(rate));
                    }
                    if let Err(e) = Pending::check(self.time, 1.0 / rate) {
                        break Err(e);
                    }
                    let p = Pending::after(self.time, 1.0 / rate, exp1(rng));
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
            rep.proposals += 1;
            let p = u64::uniform_below(rng, n) as usize;
            let mut q = u64::uniform_below(rng, n - 1) as usize;
            if q >= p {
                q += 1;
            }
            let (x, y) = (self.sizes[p], self.sizes[q]);
            let c = match crate::kernel::bounded_rate(
                &self.kernel,
                x as f64,
                y as f64,
                self.cmax,
                "supremum C_max",
            ) {
                Ok(c) => c,
                Err(e) => break Err(e),
            };
            if self.cmax * open_unit(rng) > c {
                self.time = next.at;
                rep.rejections += 1;
                // the rate is unchanged: the next proposal at the same mean waiting time
                if let Err(e) = Pending::check(next.at, next.mean_dt) {
                    self.pending = None;
                    break Err(e);
                }
                self.pending = Some(Pending::after(next.at, next.mean_dt, exp1(rng)));
                continue;
            }
            let merged = match self.pop.merged(x, y) {
                Ok(m) => m,
                Err(e) => break Err(e),
            };
            if merged > self.max_present {
                let c = match self.sup(merged) {
                    Ok(c) => c,
                    Err(e) => break Err(e),
                };
                self.max_present = merged;
                self.cmax = c;
            }
            self.time = next.at;
            self.pending = None;
            self.sizes[p] = merged;
            self.sizes.swap_remove(q);
            self.pop.n -= 1;
            rep.events += 1;
            if self.pop.doubling_due() {
                self.sizes.extend_from_within(..);
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

impl<K: CoagulationKernel> crate::checkpoint::Checkpoint for AcceptanceRejection<K> {
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::REJECTION);
        w.u64(self.pop.size_limit);
        w.u64(self.pop.n0);
        w.f64(self.pop.volume);
        w.f64(self.time);
        Pending::save(&self.pending, w);
        w.u64(self.max_present);
        w.f64(self.cmax);
        self.totals.save(w);
        w.u64s(&self.sizes);
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        check_header(r, tag::REJECTION)?;
        let (size_limit, n0) = (r.u64()?, r.u64()?);
        let (volume, time) = (r.f64()?, r.f64()?);
        let pending = Pending::read(r, time)?;
        let (max_present, cmax) = (r.u64()?, r.f64()?);
        let totals = StepReport::read(r)?;
        let mut sizes = r.u64s()?;
        if sizes.iter().any(|&s| s == 0 || s > max_present)
            || max_present > size_limit
            || !(volume > 0.0 && volume.is_finite() && time >= 0.0 && time.is_finite())
            || sizes.len() as u64 > n0
        {
            return Err(Error::Checkpoint {
                what: "inconsistent particle sizes, volume or time",
            });
        }
        r.finish()?;
        // the supremum as the kernel gives it for the largest size
        if self.sup(max_present)?.to_bits() != cmax.to_bits() {
            return Err(Error::Checkpoint {
                what: "the rate supremum does not match the kernel",
            });
        }
        // a kept proposal needs proposals to come, at the rate it was drawn from
        if let Some(p) = pending {
            let n = sizes.len() as u64;
            let rate = cmax * (n.saturating_mul(n.saturating_sub(1))) as f64 / (2.0 * volume);
            if n < 2
                || !(rate > 0.0 && rate.is_finite())
                || (1.0 / rate).to_bits() != p.mean_dt.to_bits()
            {
                return Err(Error::Checkpoint {
                    what: "the pending proposal does not match the state's rate",
                });
            }
        }
        // room for the doublings to come (the list never passes N0)
        within_budget(
            usize::try_from(n0)
                .ok()
                .and_then(|n| n.checked_mul(core::mem::size_of::<u64>())),
            self.pop.memory_budget,
        )?;
        let room = n0 as usize - sizes.len();
        try_reserve(&mut sizes, room)?;
        self.pop.size_limit = size_limit;
        self.pop.n = sizes.len() as u64;
        self.pop.n0 = n0;
        self.pop.volume = volume;
        self.time = time;
        self.pending = pending;
        self.max_present = max_present;
        self.cmax = cmax;
        self.totals = totals;
        self.sizes = sizes;
        Ok(())
    }
}

/// Single-particle edits, for processes beside coagulation (`docs/design/processes.md`):
/// the particle list takes an O(1) removal (swap-remove) and addition (push); a draw is
/// uniform in O(1), by mass in one pass over the list.
impl<K: CoagulationKernel> AcceptanceRejection<K> {
    /// Whether single-particle edits are supported (always).
    pub fn edits(&self) -> bool {
        true
    }

    /// A particle drawn uniformly (`by_mass`: in proportion to its size): its size and
    /// its place in the list, the handle for [`remove_drawn`](Self::remove_drawn).
    pub fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(u64, u64)> {
        let n = self.sizes.len() as u64;
        if n == 0 {
            return None;
        }
        let p = if by_mass {
            // (u128: a mass of up to 2^64 sizes of up to 2^64 each)
            let total: u128 = self.sizes.iter().map(|&s| u128::from(s)).sum();
            let mut k = crate::random::below_wide(rng, total)?;
            self.sizes.iter().position(|&s| {
                let hit = k < u128::from(s);
                k = k.wrapping_sub(u128::from(s));
                hit
            })?
        } else {
            u64::uniform_below(rng, n) as usize
        };
        Some((self.sizes[p], p as u64))
    }

    /// Removes the particle of size `x` that a draw returned `handle` for (nothing
    /// changed since; a handle that does not name a particle of size `x` is an error
    /// and changes nothing). The next proposal is drawn afresh.
    pub fn remove_drawn(&mut self, x: u64, handle: u64) -> Result<()> {
        let p = usize::try_from(handle)
            .ok()
            .filter(|&p| self.sizes.get(p) == Some(&x));
        let Some(p) = p else {
            return Err(bad_handle(
                handle,
                "a particle of the given size, from the last draw",
            ));
        };
        self.sizes.swap_remove(p);
        self.pop.n -= 1;
        self.pending = None;
        Ok(())
    }

    /// Adds a particle of size `x` (at least 1, within the size limit and the memory
    /// budget; a size past the largest raises the supremum). Errors leave the scheme
    /// unchanged. The next proposal is drawn afresh.
    pub fn add_particle(&mut self, x: u64) -> Result<()> {
        // N and the mass Σ x stay within u64, as every state set from counts (N times
        // the largest size bounds the mass; the exact sum only when that bound fails)
        let n = self.pop.check_added(x)?;
        if n.checked_mul(x.max(self.max_present)).is_none()
            && self
                .sizes
                .iter()
                .try_fold(x, |m, &s| m.checked_add(s))
                .is_none()
        {
            return Err(Error::Overflow {
                name: "total mass (sum of i N_i)",
            });
        }
        let cmax = if x > self.max_present {
            self.sup(x)?
        } else {
            self.cmax
        };
        let len = self.sizes.len() + 1;
        within_budget(
            len.checked_mul(core::mem::size_of::<u64>()),
            self.pop.memory_budget,
        )?;
        try_reserve(&mut self.sizes, 1)?;
        self.sizes.push(x);
        self.max_present = self.max_present.max(x);
        self.cmax = cmax;
        self.pop.n += 1;
        // (the reference of doubling, and what a checkpoint holds the list to)
        self.pop.n0 = self.pop.n0.max(self.pop.n);
        self.pending = None;
        Ok(())
    }

    /// Replaces the kernel (its supremum is recomputed). Errors leave the scheme
    /// unchanged.
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        let old = core::mem::replace(&mut self.kernel, kernel);
        match self.sup(self.max_present) {
            Ok(c) => {
                self.cmax = c;
                self.pending = None;
                Ok(())
            }
            Err(e) => {
                self.kernel = old;
                Err(e)
            }
        }
    }

    /// Replaces the state by `counts[i]` particles of size `sizes[i]` (each size at most
    /// once, within the size limit) in `volume`, straight into the particle list (no
    /// count vector, however large the sizes). Errors leave the scheme unchanged.
    pub fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
        crate::error::positive("volume", volume)?;
        let max = crate::scheme::population::check_pairs(sizes, counts, self.pop.size_limit)?;
        let (mut n, mut mass) = (0u64, 0u64);
        for (&s, &c) in sizes.iter().zip(counts) {
            n = n.checked_add(c).ok_or(Error::Overflow {
                name: "particle number",
            })?;
            mass = s
                .checked_mul(c)
                .and_then(|m| mass.checked_add(m))
                .ok_or(Error::Overflow {
                    name: "total mass (sum of i N_i)",
                })?;
        }
        let cmax = self.sup(max.max(1))?;
        let len = usize::try_from(n).map_err(|_| Error::Capacity {
            name: "particles (address space)",
            capacity: usize::MAX,
        })?;
        within_budget(
            len.checked_mul(core::mem::size_of::<u64>()),
            self.pop.memory_budget,
        )?;
        let mut list = Vec::new();
        try_reserve(&mut list, len)?;
        for (&s, &c) in sizes.iter().zip(counts) {
            list.extend(core::iter::repeat_n(s, c as usize));
        }
        self.sizes = list;
        self.pop.n = n;
        self.pop.n0 = n;
        self.pop.volume = volume;
        self.pending = None;
        self.max_present = max.max(1);
        self.cmax = cmax;
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
        self.time = crate::scheme::check_time(t)?;
        self.pending = None;
        Ok(())
    }

    /// Replaces the counts and the volume; the particle number becomes the reference
    /// for particle doubling. Errors leave the scheme unchanged.
    pub fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        let n = Population::new(counts, volume)?.n;
        let max = counts
            .iter()
            .rposition(|&c| c > 0)
            .map_or(1, |i| i as u64 + 1);
        let cmax = self.sup(max)?;
        let sizes = Self::particle_list(counts, n, self.pop.memory_budget)?;
        self.sizes = sizes;
        self.pop.n = n;
        self.pop.n0 = n;
        self.pop.volume = volume;
        self.pending = None;
        self.max_present = max;
        self.cmax = cmax;
        Ok(())
    }
}
