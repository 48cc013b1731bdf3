//! The acceptance–rejection engine: a list of particles, ordered pairs of distinct
//! particles drawn uniformly, and one bound for every pair, `2 Â_max` with
//! `Â_max = Σ_k max_i a_k(i) · max_j b_k(j)` over the occupied sizes (Osinsky 2023's
//! acceptance–rejection baseline, here as a [`ProposalEngine`] so that any event rule —
//! plain coagulation, the temperature-dependent collisions — runs on it unchanged and
//! can be timed side by side with the low-rank engines).
//!
//! Proposals arrive at rate `Â_max N (N − 1)/V` (each unordered pair at `2 Â_max/V`), a
//! rule accepts with `K/(2 Â_max)`. The maxima are raised at once when a factor grows
//! (a merged size, a reweighed one) and lowered to the occupied sizes' maxima every
//! `max(M, 1024)` events (a stale maximum is still a bound: it only costs
//! rejections).

use super::proposal::{Candidate, Low, Outcome, ProposalEngine, rank_mismatch};
use super::trees::Weights;
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::random::below;
use crate::scheme::population::{
    Population, rate_overflow, try_reserve, try_resize, within_budget,
};
use alloc::borrow::Cow;
use alloc::vec::Vec;
use rand_core::Rng;

/// Events between recomputations of the factor maxima (at least; `M` if larger).
const RECOMPUTE: u64 = 1024;

/// The acceptance–rejection engine (see the module docs).
pub struct UniformEngine<const R: usize> {
    /// The particles' sizes (capacity N0: a doubling never passes it).
    sizes: Vec<u64>,
    /// `counts[i − 1] = N_i`, length M.
    counts: Vec<u64>,
    /// `fab[i − 1]`: the factors of size i.
    fab: Vec<Weights<R>>,
    /// The bound's factor maxima `[max a_k, max b_k]` (at least over the occupied sizes).
    max: Weights<R>,
    m: usize,
    /// Events since the maxima were last recomputed.
    since: u64,
}

impl<const R: usize> core::fmt::Debug for UniformEngine<R> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UniformEngine")
            .field("rank", &R)
            .field("particles", &self.sizes.len())
            .field("max_size", &self.m)
            .finish_non_exhaustive()
    }
}

impl<const R: usize> UniformEngine<R> {
    fn bytes_for(m: usize, n0: u64) -> Option<usize> {
        let per_size = core::mem::size_of::<u64>() + core::mem::size_of::<Weights<R>>();
        let list = usize::try_from(n0).ok()?.checked_mul(8)?;
        m.checked_mul(per_size)?.checked_add(list)
    }

    /// `Â_max = Σ_k max a_k · max b_k`.
    #[inline]
    fn amax(&self) -> f64 {
        (0..R).map(|k| self.max[0][k] * self.max[1][k]).sum()
    }

    #[inline]
    fn raise(&mut self, idx: usize) {
        for p in 0..2 {
            for k in 0..R {
                self.max[p][k] = self.max[p][k].max(self.fab[idx][p][k]);
            }
        }
    }

    /// The maxima over the occupied sizes.
    fn occupied_max(counts: &[u64], fab: &[Weights<R>]) -> Weights<R> {
        let mut max: Weights<R> = [[0.0; R]; 2];
        for (c, f) in counts.iter().zip(fab) {
            if *c > 0 {
                for p in 0..2 {
                    for k in 0..R {
                        max[p][k] = max[p][k].max(f[p][k]);
                    }
                }
            }
        }
        max
    }

    fn extend_factors<K: CoagulationKernel>(&mut self, kernel: &K, m: usize) -> Result<()> {
        super::bound::extend_rows(kernel, &mut self.fab, m)
    }

    /// The engine over the particle list `sizes` (validated by the caller) for `n0`.
    fn from_sizes<K: CoagulationKernel>(
        kernel: &K,
        sizes: Vec<u64>,
        m: usize,
        pop: &Population,
    ) -> Result<Self> {
        if kernel.rank() != R || R == 0 {
            return Err(rank_mismatch());
        }
        within_budget(Self::bytes_for(m, pop.n0), pop.memory_budget)?;
        let mut s = UniformEngine {
            sizes,
            counts: Vec::new(),
            fab: Vec::new(),
            max: [[0.0; R]; 2],
            m,
            since: 0,
        };
        try_resize(&mut s.counts, m, 0)?;
        for &x in &s.sizes {
            s.counts[x as usize - 1] += 1;
        }
        s.extend_factors(kernel, m)?;
        s.max = Self::occupied_max(&s.counts, &s.fab);
        Ok(s)
    }
}

impl<const R: usize> ProposalEngine<R> for UniformEngine<R> {
    /// The two particles' places in the list.
    type Loc = (usize, usize);
    const TAG: u64 = crate::scheme::tag::UNIFORM;
    const LOW: Low = Low::Factors;
    const REWEIGHS: bool = true;

    fn build<K: CoagulationKernel>(kernel: &K, counts: &[u64], pop: &Population) -> Result<Self> {
        let m = counts.len().next_power_of_two().max(64);
        let n0 = usize::try_from(pop.n0).map_err(|_| Error::Capacity {
            name: "particles (address space)",
            capacity: usize::MAX,
        })?;
        within_budget(Self::bytes_for(m, pop.n0), pop.memory_budget)?;
        let mut sizes = Vec::new();
        try_reserve(&mut sizes, n0)?;
        for (i, &c) in counts.iter().enumerate() {
            sizes.extend(core::iter::repeat_n(i as u64 + 1, c as usize));
        }
        Self::from_sizes(kernel, sizes, m, pop)
    }

    #[inline]
    fn rate_now(&self) -> Option<f64> {
        let n = self.sizes.len() as f64;
        Some(self.amax() * n * (n - 1.0))
    }

    fn refresh<G: Rng + ?Sized>(&mut self, _pop: &Population, _rng: &mut G) -> Result<f64> {
        let sa = self.rate_now().unwrap_or(0.0);
        if !sa.is_finite() {
            return Err(rate_overflow(sa));
        }
        Ok(sa)
    }

    #[inline]
    fn propose<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Option<Candidate<(usize, usize)>> {
        let n = self.sizes.len() as u64;
        if n < 2 {
            return None;
        }
        let p = below(rng, n) as usize;
        let mut q = below(rng, n - 1) as usize;
        if q >= p {
            q += 1;
        }
        Some(Candidate {
            x: self.sizes[p],
            y: self.sizes[q],
            at: (p, q),
        })
    }

    /// `(2 Â_max, A(x, y) + A(y, x))`.
    #[inline]
    fn bounds(&self, &(p, q): &(usize, usize)) -> (f64, f64) {
        let (i, j) = (self.sizes[p] as usize - 1, self.sizes[q] as usize - 1);
        let mut low = 0.0;
        for k in 0..R {
            low += self.fab[i][0][k] * self.fab[j][1][k] + self.fab[j][0][k] * self.fab[i][1][k];
        }
        (2.0 * self.amax(), low)
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
            let new_m = 2 * self.m;
            within_budget(Self::bytes_for(new_m, pop.n0), pop.memory_budget)?;
            self.extend_factors(kernel, new_m)?;
            try_resize(&mut self.counts, new_m, 0)?;
            self.m = new_m;
        }
        Ok(())
    }

    #[inline]
    fn apply(&mut self, c: &Candidate<(usize, usize)>, outcome: &Outcome) {
        let Outcome::Merge { size } = *outcome else {
            return;
        };
        let (p, q) = c.at;
        self.counts[c.x as usize - 1] -= 1;
        self.counts[c.y as usize - 1] -= 1;
        self.counts[size as usize - 1] += 1;
        self.sizes[p] = size;
        self.sizes.swap_remove(q);
        self.raise(size as usize - 1);
    }

    fn double(&mut self, _pop: &Population) {
        // within the capacity N0 reserved at build
        self.sizes.extend_from_within(..);
        for c in &mut self.counts {
            *c *= 2;
        }
    }

    #[inline]
    fn settle(&mut self, _pop: &Population) {
        self.since += 1;
        if self.since >= RECOMPUTE.max(self.m as u64) {
            self.max = Self::occupied_max(&self.counts, &self.fab);
            self.since = 0;
        }
    }

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
        self.fab[idx] = [a, b];
        if self.counts[idx] > 0 {
            self.raise(idx);
        }
    }

    fn refactor<K: CoagulationKernel>(&mut self, kernel: &K) {
        super::bound::reread_rows(kernel, &mut self.fab);
        self.max = Self::occupied_max(&self.counts, &self.fab);
        self.since = 0;
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
        w.u64s(&self.sizes);
        w.f64s(
            self.max
                .iter()
                .flatten()
                .copied()
                .collect::<Vec<_>>()
                .as_slice(),
        );
        w.u64(self.since);
    }

    fn load<K: CoagulationKernel>(
        kernel: &K,
        m: u64,
        pop: &Population,
        r: &mut Reader,
    ) -> Result<Self> {
        let bad = |what| Error::Checkpoint { what };
        let m = usize::try_from(m).map_err(|_| bad("invalid maximum size"))?;
        let list = r.u64s()?;
        if list.len() as u64 != pop.n || list.iter().any(|&x| x == 0 || x > m as u64) {
            return Err(bad("particle list does not match the sizes"));
        }
        within_budget(Self::bytes_for(m, pop.n0), pop.memory_budget)?;
        let mut sizes = Vec::new();
        try_reserve(&mut sizes, usize::try_from(pop.n0).unwrap_or(usize::MAX))?;
        sizes.extend_from_slice(&list);
        let max = r.f64s()?;
        let since = r.u64()?;
        let mut s = Self::from_sizes(kernel, sizes, m, pop)?;
        // the stored maxima bound the occupied sizes' factors (a stale maximum may be
        // larger; a smaller one would not be a bound)
        if max.len() != 2 * R
            || max
                .iter()
                .enumerate()
                .any(|(i, &v)| !(v.is_finite() && v >= s.max[i / R][i % R]))
        {
            return Err(bad("factor maxima do not bound the sizes"));
        }
        for (i, &v) in max.iter().enumerate() {
            s.max[i / R][i % R] = v;
        }
        s.since = since.min(RECOMPUTE.max(m as u64));
        Ok(s)
    }
}
