//! The mass flow algorithm (Eibeck & Wagner 2000, §5; SPEC §5).
//!
//! N particles `x_1..x_n` (n = N at the start), each carrying the mass `M1/N` of the
//! initial mass `M1`: the number concentration is `(M1/N) Σ_i δ_{x_i} / x_i`. With the
//! product majorant h:
//! 1. wait an exponential time of rate `λ = (M1/N) Σ_i h(x_i) · Σ_j h(x_j)/x_j + Σ_i Ḟ(x_i)`;
//! 2. coagulation (probability of its share of λ): pick i ∝ h(x_i) and, independently,
//!    j ∝ h(x_j)/x_j (i = j allowed: the generator sums over all ordered pairs); with
//!    probability `K(x_i, x_j) / (h(x_i) h(x_j))`, `x_i ← x_i + x_j` if that is at most
//!    the truncation `b_N`, else particle i leaves the system (into the gel);
//! 3. fragmentation (beyond the paper): pick i ∝ `Ḟ(x_i)`, `x_i ← F̂⁻¹_{x_i}(u)` — the
//!    size the followed mass keeps, as in the time-driven mass-flow scheme.
//!
//! Estimators: `M_m = (M1/N) Σ_i x_i^{m−1}`, `C(a, b) = (M1/N) Σ_{a ≤ x_i ≤ b} 1/x_i`,
//! gel mass `M1 (1 − n/N)` (E–W 6.14).

use super::super::{Budget, Pending, Scheme, StepReport, check_target, next_proposal};
use super::{Sampler, Store, accept, break_rate, majorant, read_sizes};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::random::unit_f64;
use crate::scheme::check_pending;
use alloc::vec::Vec;
use rand_core::Rng;

/// Trees: h(x), h(x)/x, Ḟ(x).
const H: usize = 0;
const HX: usize = 1;
const FR: usize = 2;

/// The weights `[h, h/x, Ḟ]` of a size already validated.
#[inline]
fn raw_weights<K: CoagulationKernel, F: FragmentationKernel>(k: &K, f: &F, x: f64) -> [f64; 3] {
    let h = k.majorant(x).unwrap_or(0.0);
    [h, h / x, if f.is_none() { 0.0 } else { f.total_rate(x) }]
}

/// The mass flow algorithm. See the module docs; `B` is the workspace (an owned
/// `Vec<f64>`, or the caller's storage with [`Mfa::new_in`]).
pub struct Mfa<K, F, B = Vec<f64>> {
    kernel: K,
    frag: F,
    store: Store<B, 3>,
    /// N, the particles at the start.
    n0: usize,
    /// M1, the mass the N particles carried at the start.
    mass: f64,
    /// b_N: a coagulation beyond it removes the particle.
    truncation: f64,
    strict: bool,
    time: f64,
    pending: Option<Pending>,
    totals: StepReport,
}

impl<K, F, B> core::fmt::Debug for Mfa<K, F, B> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Mfa")
            .field("particles", &self.store.n)
            .field("n0", &self.n0)
            .field("mass", &self.mass)
            .field("truncation", &self.truncation)
            .field("time", &self.time)
            .finish_non_exhaustive()
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel> Mfa<K, F> {
    /// N = `sizes.len()` particles (samples of the initial *mass* distribution
    /// `x c0(x) / M1`) carrying the total mass `mass`, no truncation, in a workspace
    /// allocated once.
    ///
    /// Errors: no particle, a size or the mass not finite and positive, a kernel
    /// without a product majorant (`Unsupported`) or one not finite at a size, a
    /// fragmentation rate not finite.
    pub fn new(kernel: K, frag: F, sizes: &[f64], mass: f64) -> Result<Self> {
        let len = super::workspace_len(sizes.len()).ok_or(Error::Overflow {
            name: "event-driven workspace",
        })?;
        let mut ws = Vec::new();
        crate::scheme::population::try_resize(&mut ws, len, 0.0)?;
        Self::new_in(kernel, frag, sizes, mass, ws)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Mfa<K, F, B> {
    /// [`new`](Mfa::new) in storage the caller owns: at least
    /// [`workspace_len`](super::workspace_len)`(N)` doubles; no event allocates.
    pub fn new_in(kernel: K, frag: F, sizes: &[f64], mass: f64, workspace: B) -> Result<Self> {
        if sizes.is_empty() {
            return Err(Error::OutOfRange {
                name: "number of particles",
                value: 0.0,
                range: "[1, inf)",
            });
        }
        crate::error::positive("mass", mass)?;
        let mut s = Mfa {
            kernel,
            frag,
            store: Store::new(workspace, sizes.len())?,
            n0: sizes.len(),
            mass,
            truncation: f64::INFINITY,
            strict: false,
            time: 0.0,
            pending: None,
            totals: StepReport::default(),
        };
        s.replace(sizes)?;
        s.store.set_sampler(Sampler::Groups)?;
        Ok(s)
    }

    /// Sets the truncation `b_N` (a coagulation that would pass it removes the
    /// particle). Errors: NaN, or below the largest size now.
    pub fn with_truncation(mut self, b: f64) -> Result<Self> {
        self.set_truncation(b)?;
        Ok(self)
    }

    /// Changes the truncation (see [`with_truncation`](Self::with_truncation)).
    pub fn set_truncation(&mut self, b: f64) -> Result<()> {
        let largest = self.store.sizes().iter().copied().fold(0.0, f64::max);
        if b.is_nan() || b < largest {
            return Err(Error::OutOfRange {
                name: "truncation b_N",
                value: b,
                range: "[largest size, inf]",
            });
        }
        self.truncation = b;
        Ok(())
    }

    /// Makes a kernel value above the majorant an error instead of a counted
    /// violation.
    pub fn with_strict_bound(mut self, strict: bool) -> Self {
        self.strict = strict;
        self
    }

    /// Draws particles with `sampler` (the default is [`Sampler::Groups`]).
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

    /// The weights of a particle of size x: `[h, h/x, Ḟ]`, validated.
    #[inline]
    fn weights(&self, x: f64) -> Result<[f64; 3]> {
        let h = majorant(&self.kernel, x)?;
        let hx = crate::error::finite("h(x)/x (a size too small for its majorant)", h / x)?;
        Ok([h, hx, break_rate(&self.frag, x)?])
    }

    /// Replaces the particles (validated first; nothing changes on error).
    fn replace(&mut self, sizes: &[f64]) -> Result<()> {
        if sizes.len() > self.n0 {
            return Err(Error::BufferLength {
                name: "sizes (at most the initial number of particles)",
                expected: self.n0,
                got: sizes.len(),
            });
        }
        for &x in sizes {
            crate::error::positive("size", x)?;
            if x > self.truncation {
                return Err(Error::OutOfRange {
                    name: "size",
                    value: x,
                    range: "(0, truncation b_N]",
                });
            }
            self.weights(x)?;
        }
        let (k, f) = (&self.kernel, &self.frag);
        self.store.fill(sizes, |x| raw_weights(k, f, x));
        self.pending = None;
        Ok(())
    }

    /// The particle sizes (in storage order, not sorted).
    pub fn sizes(&self) -> &[f64] {
        self.store.sizes()
    }

    /// Replaces the sizes: at most N of them (the rest count as removed, in the gel),
    /// each finite, positive and at most `b_N`; the next proposal is drawn afresh.
    pub fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        self.replace(sizes)
    }

    /// Replaces the coagulation kernel (it needs a product majorant).
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        for &x in self.store.sizes() {
            let h = majorant(&kernel, x)?;
            crate::error::finite("h(x)/x", h / x)?;
        }
        self.kernel = kernel;
        let k = &self.kernel;
        self.store.refill_tree(H, |x| k.majorant(x).unwrap_or(0.0));
        self.store
            .refill_tree(HX, |x| k.majorant(x).unwrap_or(0.0) / x);
        self.pending = None;
        Ok(())
    }

    /// Replaces the fragmentation kernel.
    pub fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        for &x in self.store.sizes() {
            break_rate(&frag, x)?;
        }
        self.frag = frag;
        let f = &self.frag;
        self.store
            .refill_tree(FR, |x| if f.is_none() { 0.0 } else { f.total_rate(x) });
        self.pending = None;
        Ok(())
    }

    /// Sets the clock (finite, not negative); the next proposal is drawn afresh.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        self.time = super::super::check_time(t)?;
        self.pending = None;
        Ok(())
    }

    /// Changes the mass M1 the N particles carry (finite and positive).
    pub fn set_mass(&mut self, mass: f64) -> Result<()> {
        self.mass = crate::error::positive("mass", mass)?;
        self.pending = None;
        Ok(())
    }

    /// M1, the mass the N initial particles carry.
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// N, the number of particles at the start.
    pub fn initial_particles(&self) -> usize {
        self.n0
    }

    /// The rates of coagulation proposals and of fragmentation events.
    #[inline]
    fn rates(&self) -> (f64, f64) {
        let c = self.mass / self.n0 as f64 * self.store.total(H) * self.store.total(HX);
        (c, self.store.total(FR))
    }

    /// The rates' total, or an error when it is not finite (a rate that overflows
    /// must not read as "nothing can happen").
    fn total(coag: f64, frag: f64) -> Result<f64> {
        let t = coag + frag;
        if t.is_finite() {
            Ok(t)
        } else {
            Err(Error::InvalidRate {
                name: "total event rate (overflows a double)",
                value: t,
            })
        }
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
            let j = self.store.sample(HX, rng);
            let (xi, xj) = (self.store.size(i), self.store.size(j));
            let hh = self.store.weight(H, i) * self.store.weight(H, j);
            let k = self.kernel.rate(xi, xj);
            if !accept(k, hh, self.strict, &mut rep.bound_violations, rng)? {
                rep.rejections += 1;
                return Ok(false);
            }
            let s = xi + xj;
            if s > self.truncation {
                self.store.swap_remove(i);
                rep.removed += 1;
            } else {
                if !s.is_finite() {
                    // (no truncation: past b_N the particle would have left)
                    return Err(Error::Overflow {
                        name: "particle size (a coagulation passed the largest f64)",
                    });
                }
                let w = self.weights(s)?;
                self.store.set(i, s, w);
            }
        } else {
            let i = self.store.sample(FR, rng);
            let x = self.store.size(i);
            let piece = self.frag.inverse_piece(x, unit_f64(rng.next_u64()));
            if !(piece > 0.0 && piece <= x) {
                return Err(Error::InvalidRate {
                    name: "fragment size (must lie in (0, x])",
                    value: piece,
                });
            }
            let w = self.weights(piece)?;
            self.store.set(i, piece, w);
        }
        Ok(true)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Scheme
    for Mfa<K, F, B>
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
            let total = match Self::total(coag, frag) {
                Ok(t) => t,
                Err(e) => break Err(e),
            };
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
    crate::observe::Observe for Mfa<K, F, B>
{
    /// 1: each particle carries the mass `M1 / N` instead of living in a volume.
    fn volume(&self) -> f64 {
        1.0
    }
    fn particles(&self) -> u64 {
        self.store.len() as u64
    }
    fn moment(&self, order: f64) -> f64 {
        crate::observe::mass_flow_moment(self.store.sizes(), self.mass, self.n0, order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        let w = self.mass / self.n0 as f64;
        crate::observe::sum_concentration(self.store.sizes().iter().map(|&x| (x, w / x)), a, b)
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        let w = self.mass / self.n0 as f64;
        for &x in self.store.sizes() {
            f(x, w / x);
        }
    }
    /// `M1 (1 − n/N)`: the mass of the particles that left past `b_N` (E–W 6.14).
    fn gel_mass(&self) -> Option<f64> {
        Some(self.mass * (1.0 - self.store.len() as f64 / self.n0 as f64))
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>
    crate::checkpoint::Checkpoint for Mfa<K, F, B>
{
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::MFA);
        w.u64(self.n0 as u64);
        w.f64(self.mass);
        w.f64(self.truncation);
        w.u64(u64::from(self.strict));
        w.f64(self.time);
        Pending::save(&self.pending, w);
        self.totals.save(w);
        w.u64(self.store.len() as u64);
        for &x in self.store.sizes() {
            w.f64(x);
        }
        self.store.save_sampler(w);
    }

    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, tag::MFA)?;
        if r.u64()? != self.n0 as u64 {
            return Err(bad("a different initial number of particles"));
        }
        let (mass, truncation, strict) = (r.f64()?, r.f64()?, r.u64()?);
        let time = r.f64()?;
        if !(mass > 0.0 && mass.is_finite())
            || truncation.is_nan()
            || truncation <= 0.0
            || strict > 1
            || !(time >= 0.0 && time.is_finite())
        {
            return Err(bad("invalid mass, truncation, flag or time"));
        }
        let pending = Pending::read(r, time)?;
        let totals = StepReport::read(r)?;
        let xs = read_sizes(r, self.n0)?;
        let (k, f) = (&self.kernel, &self.frag);
        let sampler = self.store.read_sampler(r, &xs, |x| raw_weights(k, f, x))?;
        r.finish()?;
        let (old_mass, old_b) = (self.mass, self.truncation);
        self.mass = mass;
        self.truncation = truncation;
        let checked = xs
            .iter()
            .try_for_each(|&x| {
                if x > truncation {
                    return Err(bad("a size beyond the truncation"));
                }
                self.weights(x).map(|_| ())
            })
            .and_then(|()| {
                // the rate the pending proposal was drawn at, from plain sums
                let (mut a, mut b, mut f) = (0.0, 0.0, 0.0);
                for &x in &xs {
                    let w = self.weights(x)?;
                    a += w[0];
                    b += w[1];
                    f += w[2];
                }
                check_pending(&pending, mass / self.n0 as f64 * a * b + f)
            });
        if let Err(e) = checked {
            self.mass = old_mass;
            self.truncation = old_b;
            return Err(match e {
                Error::Checkpoint { .. } => e,
                _ => bad("a size where the kernel's majorant or the break-up rate is invalid"),
            });
        }
        self.replace(&xs)?;
        self.store.install_sampler(sampler);
        self.strict = strict == 1;
        self.time = time;
        self.pending = pending;
        self.totals = totals;
        Ok(())
    }
}
