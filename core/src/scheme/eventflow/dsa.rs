//! Direct simulation, the Marcus–Lushnikov process (Eibeck & Wagner 2000, §5; SPEC §5).
//!
//! Particles `y_1..y_n` in a volume V (number concentration `Σ_i δ_{y_i} / V`); each
//! unordered pair coagulates at rate `K(y_i, y_j)/V`. With the product majorant h:
//! 1. wait an exponential time of rate `λ = (Σ_i h(y_i))² / (2V) + Σ_i Ḟ(y_i)`;
//! 2. coagulation (probability of its share of λ): pick i and j ∝ h independently;
//!    i = j is rejected; with probability `K(y_i, y_j) / (h(y_i) h(y_j))`,
//!    `y_i, y_j → y_i + y_j`;
//! 3. fragmentation (beyond the paper): pick i ∝ `Ḟ(y_i)`; it breaks into `y` and
//!    `y_i − y`, with `y = F̂⁻¹_{y_i}(u)` drawn from the size-biased piece distribution.
//!    For a symmetric binary split of density p this gives the right split: the
//!    unordered pair {y, y_i − y} then has density `q(y) + q(y_i − y) = 2 p(y)`, with
//!    `q(y) = 2 p(y) y / y_i` the size-biased density — the number-based split's.
//!
//! **The rate's factor 2.** Each ordered pair (i, j), i ≠ j, is proposed at rate
//! `λ h_i h_j / (Σh)² = h_i h_j / (2V)`, each unordered pair twice as often, and accepted
//! with `K/(h_i h_j)`: rate `K/V`, the convention of SPEC §1 and E–W eq. 2.2. The seed
//! prints the proposal rate as `(1/N)(Σh)²`, which would double every rate; the
//! constant-kernel solution decides for `1/(2V)`: with the printed rate, M0(1) from
//! monomers is 1/2 instead of 2/3 (`dsa_rate_factor_two_is_decided_by_the_constant_kernel`
//! in the tests shows both).
//!
//! Estimators: `M_m = Σ_i y_i^m / V`, `C(a, b) = #{a ≤ y_i ≤ b} / V`; gel mass: the
//! largest cluster's mass over V (E–W 6.15).

use super::super::{Budget, Pending, Scheme, StepReport, check_target, next_proposal};
use super::{Sampler, Store, accept, break_rate, majorant, read_sizes};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::random::unit_f64;
use crate::scheme::check_pending;
use alloc::vec::Vec;
use rand_core::Rng;

/// Trees: h(y), Ḟ(y).
const H: usize = 0;
const FR: usize = 1;

/// The weights `[h, Ḟ]` of a size already validated.
#[inline]
fn raw_weights<K: CoagulationKernel, F: FragmentationKernel>(k: &K, f: &F, y: f64) -> [f64; 2] {
    [
        k.majorant(y).unwrap_or(0.0),
        if f.is_none() { 0.0 } else { f.total_rate(y) },
    ]
}

/// Direct simulation. See the module docs; `B` is the workspace (an owned `Vec<f64>`,
/// or the caller's storage with [`Dsa::new_in`]).
pub struct Dsa<K, F, B = Vec<f64>> {
    kernel: K,
    frag: F,
    store: Store<B, 2>,
    volume: f64,
    strict: bool,
    time: f64,
    pending: Option<Pending>,
    totals: StepReport,
}

impl<K, F, B> core::fmt::Debug for Dsa<K, F, B> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Dsa")
            .field("particles", &self.store.n)
            .field("capacity", &self.store.cap)
            .field("volume", &self.volume)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel> Dsa<K, F> {
    /// The particles `sizes` (samples of the initial *number* distribution) in volume
    /// `volume`, with room for `capacity ≥ sizes.len()` particles (fragmentation adds
    /// particles; pure coagulation needs no more than the start), in a workspace
    /// allocated once.
    ///
    /// Errors: a size or the volume not finite and positive, a capacity below the
    /// number of particles, a kernel without a product majorant (`Unsupported`) or
    /// not finite at a size, a fragmentation rate not finite.
    pub fn new(kernel: K, frag: F, sizes: &[f64], volume: f64, capacity: usize) -> Result<Self> {
        let len = super::workspace_len(capacity).ok_or(Error::Overflow {
            name: "event-driven workspace",
        })?;
        let mut ws = Vec::new();
        crate::scheme::population::try_resize(&mut ws, len, 0.0)?;
        Self::new_in(kernel, frag, sizes, volume, capacity, ws)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Dsa<K, F, B> {
    /// [`new`](Dsa::new) in storage the caller owns: at least
    /// [`workspace_len`](super::workspace_len)`(capacity)` doubles; no event allocates.
    pub fn new_in(
        kernel: K,
        frag: F,
        sizes: &[f64],
        volume: f64,
        capacity: usize,
        workspace: B,
    ) -> Result<Self> {
        crate::error::positive("volume", volume)?;
        if capacity < sizes.len() || capacity == 0 {
            return Err(Error::Capacity {
                name: "particles (capacity below the initial number)",
                capacity,
            });
        }
        let mut s = Dsa {
            kernel,
            frag,
            store: Store::new(workspace, capacity)?,
            volume,
            strict: false,
            time: 0.0,
            pending: None,
            totals: StepReport::default(),
        };
        s.replace(sizes)?;
        Ok(s)
    }

    /// Makes a kernel value above the majorant an error instead of a counted
    /// violation.
    pub fn with_strict_bound(mut self, strict: bool) -> Self {
        self.strict = strict;
        self
    }

    /// Draws particles with `sampler` (the default is [`Sampler::SumTree`]).
    pub fn with_sampler(mut self, sampler: Sampler) -> Result<Self> {
        self.set_sampler(sampler)?;
        Ok(self)
    }

    /// Changes the sampler; the state and the next proposal stay (nothing changes on
    /// error).
    pub fn set_sampler(&mut self, sampler: Sampler) -> Result<()> {
        self.store.set_sampler(sampler)
    }

    /// The sampler in use.
    pub fn sampler(&self) -> Sampler {
        self.store.sampler()
    }

    /// The weights of a particle of size y: `[h, Ḟ]`, validated.
    #[inline]
    fn weights(&self, y: f64) -> Result<[f64; 2]> {
        Ok([majorant(&self.kernel, y)?, break_rate(&self.frag, y)?])
    }

    fn replace(&mut self, sizes: &[f64]) -> Result<()> {
        if sizes.len() > self.store.capacity() {
            return Err(Error::Capacity {
                name: "particles (the workspace's capacity)",
                capacity: self.store.capacity(),
            });
        }
        for &y in sizes {
            crate::error::positive("size", y)?;
            self.weights(y)?;
        }
        let (k, f) = (&self.kernel, &self.frag);
        self.store.fill(sizes, |y| raw_weights(k, f, y));
        self.pending = None;
        Ok(())
    }

    /// The particle sizes (in storage order, not sorted).
    pub fn sizes(&self) -> &[f64] {
        self.store.sizes()
    }

    /// The particles' capacity.
    pub fn capacity(&self) -> usize {
        self.store.capacity()
    }

    /// Replaces the sizes (at most the capacity, each finite and positive; the volume
    /// stays); the next proposal is drawn afresh.
    pub fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        self.replace(sizes)
    }

    /// A particle drawn uniformly: its size and index, for
    /// [`remove_drawn`](Self::remove_drawn) (the processes' single-particle edits).
    pub fn draw_particle<G: Rng + ?Sized>(&self, rng: &mut G) -> Option<(f64, u64)> {
        let n = self.store.len();
        if n == 0 {
            return None;
        }
        let i = crate::random::below(rng, n as u64) as usize;
        Some((self.store.size(i), i as u64))
    }

    /// Removes the particle of size `x` a draw returned `index` for (nothing changed
    /// since: else an error, nothing removed); O(log N). The next proposal is drawn
    /// afresh.
    pub fn remove_drawn(&mut self, x: f64, index: u64) -> Result<()> {
        let i = usize::try_from(index)
            .ok()
            .filter(|&i| i < self.store.len() && self.store.size(i) == x)
            .ok_or(Error::IndexOutOfRange {
                name: "drawn particle (of that size)",
                index,
                limit: self.store.len() as u64,
            })?;
        self.store.swap_remove(i);
        self.pending = None;
        Ok(())
    }

    /// Adds a particle of size `x` (finite, > 0, within the capacity; on error nothing
    /// changed); O(log N). The next proposal is drawn afresh.
    pub fn add_particle(&mut self, x: f64) -> Result<()> {
        crate::error::positive("size", x)?;
        let w = self.weights(x)?;
        if self.store.len() == self.store.capacity() {
            return Err(Error::Capacity {
                name: "particles (the workspace's capacity)",
                capacity: self.store.capacity(),
            });
        }
        self.store.push(x, w);
        self.pending = None;
        Ok(())
    }

    /// Replaces the coagulation kernel (it needs a product majorant).
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        for &y in self.store.sizes() {
            majorant(&kernel, y)?;
        }
        self.kernel = kernel;
        let k = &self.kernel;
        self.store.refill_tree(H, |y| k.majorant(y).unwrap_or(0.0));
        self.pending = None;
        Ok(())
    }

    /// Replaces the fragmentation kernel.
    pub fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        for &y in self.store.sizes() {
            break_rate(&frag, y)?;
        }
        self.frag = frag;
        let f = &self.frag;
        self.store
            .refill_tree(FR, |y| if f.is_none() { 0.0 } else { f.total_rate(y) });
        self.pending = None;
        Ok(())
    }

    /// Sets the clock (finite, not negative); the next proposal is drawn afresh.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = super::super::check_time(t)?;
        self.pending = None;
        Ok(())
    }

    /// The rates of coagulation proposals and of fragmentation events.
    #[inline]
    fn rates(&self) -> (f64, f64) {
        let a = self.store.total(H);
        // fewer than two particles cannot coagulate (every proposal would be i = j)
        let c = if self.store.len() < 2 {
            0.0
        } else {
            a * (a / (2.0 * self.volume))
        };
        (c, self.store.total(FR))
    }

    /// One proposal; `Ok(true)` when the state changed.
    #[inline]
    fn event<R: Rng + ?Sized>(
        &mut self,
        coag: f64,
        total: f64,
        rep: &mut StepReport,
        rng: &mut R,
    ) -> Result<bool> {
        if unit_f64(rng.next_u64()) * total < coag {
            let i = self.store.sample(H, rng);
            let j = self.store.sample(H, rng);
            if i == j {
                rep.rejections += 1;
                return Ok(false);
            }
            let (yi, yj) = (self.store.size(i), self.store.size(j));
            let hh = self.store.weight(H, i) * self.store.weight(H, j);
            let k = self.kernel.rate(yi, yj);
            if !accept(k, hh, self.strict, &mut rep.bound_violations, rng)? {
                rep.rejections += 1;
                return Ok(false);
            }
            let s = yi + yj;
            if !s.is_finite() {
                return Err(Error::Overflow {
                    name: "particle size (a coagulation passed the largest f64)",
                });
            }
            let w = self.weights(s)?;
            self.store.set(i, s, w);
            self.store.swap_remove(j);
        } else {
            let i = self.store.sample(FR, rng);
            let y = self.store.size(i);
            let piece = self.frag.inverse_piece(y, unit_f64(rng.next_u64()));
            if !(piece > 0.0 && piece.is_finite() && piece <= y) {
                return Err(Error::InvalidRate {
                    name: "fragment size (must lie in (0, y])",
                    value: piece,
                });
            }
            let rest = y - piece;
            if rest.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
                // u within rounding of 1: no split (probability ~2^-53)
                rep.rejections += 1;
                return Ok(false);
            }
            if self.store.len() == self.store.capacity() {
                return Err(Error::Capacity {
                    name: "particles (fragmentation filled the workspace: give a larger capacity)",
                    capacity: self.store.capacity(),
                });
            }
            let (wp, wr) = (self.weights(piece)?, self.weights(rest)?);
            self.store.set(i, piece, wp);
            self.store.push(rest, wr);
        }
        Ok(true)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Scheme
    for Dsa<K, F, B>
{
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
            let (coag, frag) = self.rates();
            let total = coag + frag;
            if !total.is_finite() {
                // an overflowing rate must not read as "nothing can happen"
                break Err(Error::InvalidRate {
                    name: "total event rate (overflows a double)",
                    value: total,
                });
            }
            let next = next_proposal(
                &mut self.pending,
                &mut self.time,
                t,
                total,
                budget,
                &mut rep,
                rng,
            );
            let p = match next {
                Ok(Some(p)) => p,
                Ok(None) => break Ok(()),
                Err(e) => break Err(e),
            };
            match self.event(coag, total, &mut rep, rng) {
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

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    crate::observe::Observe for Dsa<K, F, B>
{
    fn volume(&self) -> f64 {
        self.volume
    }
    fn particles(&self) -> u64 {
        self.store.len() as u64
    }
    fn moment(&self, order: f64) -> f64 {
        let w = 1.0 / self.volume;
        crate::observe::moment(self.store.sizes().iter().map(|&y| (y, w)), order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        let w = 1.0 / self.volume;
        crate::observe::sum_concentration(self.store.sizes().iter().map(|&y| (y, w)), a, b)
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        let w = 1.0 / self.volume;
        for &x in self.store.sizes() {
            f(x, w);
        }
    }
    /// The largest cluster's mass over V (E–W 6.15).
    fn gel_mass(&self) -> Option<f64> {
        Some(self.store.sizes().iter().copied().fold(0.0, f64::max) / self.volume)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    crate::checkpoint::Checkpoint for Dsa<K, F, B>
{
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::DSA);
        w.u64(self.store.capacity() as u64);
        w.f64(self.volume);
        w.u64(u64::from(self.strict));
        w.f64(self.time);
        Pending::save(&self.pending, w);
        self.totals.save(w);
        w.u64(self.store.len() as u64);
        for &y in self.store.sizes() {
            w.f64(y);
        }
        self.store.save_sampler(w);
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, tag::DSA)?;
        // (the capacity it was written with: any state that fits restores, so a run
        // that filled its workspace can move to a larger one)
        let _ = r.u64()?;
        let (volume, strict, time) = (r.f64()?, r.u64()?, r.f64()?);
        if !(volume > 0.0 && volume.is_finite()) || strict > 1 || !(time >= 0.0 && time.is_finite())
        {
            return Err(bad("invalid volume, flag or time"));
        }
        let pending = Pending::read(r, time)?;
        let totals = StepReport::read(r)?;
        let ys = read_sizes(r, self.store.capacity())?;
        let (k, f) = (&self.kernel, &self.frag);
        let sampler = self.store.read_sampler(r, &ys, |y| raw_weights(k, f, y))?;
        r.finish()?;
        let mut a = 0.0;
        let mut f = 0.0;
        for &y in &ys {
            let w = self.weights(y).map_err(|_| {
                bad("a size where the kernel's majorant or the break-up rate is invalid")
            })?;
            a += w[0];
            f += w[1];
        }
        let coag = if ys.len() < 2 {
            0.0
        } else {
            a * (a / (2.0 * volume))
        };
        check_pending(&pending, coag + f)?;
        self.replace(&ys)?;
        self.store.install_sampler(sampler);
        self.volume = volume;
        self.strict = strict == 1;
        self.time = time;
        self.pending = pending;
        self.totals = totals;
        Ok(())
    }
}
