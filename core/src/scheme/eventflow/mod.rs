//! Event-driven particle schemes of Eibeck & Wagner (2000, §5): the mass flow algorithm
//! ([`Mfa`]) and direct simulation, the Marcus–Lushnikov process ([`Dsa`]), both with
//! the product majorant `K(x, y) ≤ h(x) h(y)` of the kernel module, and — beyond the
//! paper — spontaneous fragmentation events (rate `Ḟ(x)` per particle, the
//! fragmentation kernels of the mass-flow scheme), so that coagulation–fragmentation
//! runs event by event, with no time-step bias.
//!
//! Both schemes hold a list of particle sizes (continuous sizes; integer sizes are
//! integer-valued doubles, exact while below 2^53) and sample particles with weights
//! `h(x)` (and `h(x)/x`, `Ḟ(x)`) from flat sum trees kept in the same workspace: every
//! node is recomputed from its two children on an update, so the rates never drift and a
//! tree rebuilt from the sizes is bit for bit the one kept up to date. The workspace can
//! be the caller's ([`Mfa::new_in`], [`Dsa::new_in`], [`workspace_len`]); no event
//! allocates, and a direct simulation that would grow past its capacity (fragmentation
//! adds particles) stops with [`Error::Capacity`], the state as
//! before the event.
//!
//! A proposal whose kernel value exceeds `h(x) h(y)` is counted in
//! [`StepReport::bound_violations`](super::StepReport::bound_violations) and accepted
//! (the run is then biased where the majorant fails, and the report says how often); with
//! `with_strict_bound(true)` it is an error instead
//! ([`Error::BoundExceeded`]), the state as before.
//!
//! # Example
//! ```
//! use coagula_core::kernel::{Coagulation, NoFragmentation};
//! use coagula_core::observe::Observe;
//! use coagula_core::scheme::Scheme;
//! use coagula_core::scheme::eventflow::{Dsa, Mfa};
//! let k = Coagulation::constant(1.0).unwrap();
//! let mut rng = rand_pcg::Pcg64Mcg::new(1);
//! // 4096 monomers in volume 4096 (n_1(0) = 1): M0(1) = 1/(1 + 1/2)
//! let mut dsa = Dsa::new(k, NoFragmentation, &[1.0; 4096], 4096.0, 4096).unwrap();
//! dsa.advance_to(1.0, &mut rng).unwrap();
//! assert!((dsa.moment(0.0) - 2.0 / 3.0).abs() < 0.02);
//! // the mass flow algorithm: 4096 particles each carrying mass 1/4096, M2(1) = 2
//! let mut mfa = Mfa::new(k, NoFragmentation, &[1.0; 4096], 1.0).unwrap();
//! mfa.advance_to(1.0, &mut rng).unwrap();
//! assert!((mfa.moment(2.0) - 2.0).abs() < 0.1);
//! ```

mod dsa;
mod dsa_counts;
mod entry;
mod groups;
mod mfa;

pub use dsa::Dsa;
pub use dsa_counts::DsaCounts;
pub use entry::{DsaCountsEntry, DsaEntry, MfaEntry};
pub use mfa::Mfa;

use crate::error::{Error, Result};
use crate::random::unit_f64;
use alloc::vec::Vec;
use rand_core::Rng;

/// `f64`s of workspace a scheme with room for `capacity` particles needs: the sizes and
/// three sum trees of `2 · capacity.next_power_of_two()` nodes (the mass flow algorithm
/// uses all three, direct simulation two; one length serves both). `None` on overflow.
pub const fn workspace_len(capacity: usize) -> Option<usize> {
    let cap = if capacity == 0 { 1 } else { capacity };
    let Some(tcap) = cap.checked_next_power_of_two() else {
        return None;
    };
    match tcap.checked_mul(6) {
        Some(t) => t.checked_add(cap),
        None => None,
    }
}

/// `n` sizes drawn independently from a distribution given by its inverse CDF (the
/// exponential start `c0(x) = e^{−x}` of direct simulation is `|u| -ln(1 − u)`; the
/// mass flow algorithm wants samples of the *mass* distribution `x c0(x) / M1`).
/// Errors on a sample that is not finite and positive.
pub fn sample_sizes<R: Rng + ?Sized>(
    n: usize,
    inverse_cdf: impl Fn(f64) -> f64,
    rng: &mut R,
) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    out.try_reserve_exact(n).map_err(|_| Error::Capacity {
        name: "initial sizes",
        capacity: n,
    })?;
    for _ in 0..n {
        // u in (0, 1), never 0 or 1, where inverse CDFs of unbounded laws diverge
        let u = ((rng.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64);
        out.push(crate::error::positive(
            "initial size (inverse CDF)",
            inverse_cdf(u),
        )?);
    }
    Ok(out)
}

pub use super::facade::Sampler;

/// Particle sizes and `T` sum trees of weights over them, in one workspace:
/// `[sizes: cap | tree 0: 2·tcap | tree 1 | ...]`. Tree nodes: 1 is the root, node i
/// has children 2i and 2i + 1, leaf p sits at `tcap + p`; leaves from `n` on are 0.
/// With [`Sampler::Groups`] the trees stay unused and `groups` draws instead.
pub(crate) struct Store<B, const T: usize> {
    ws: B,
    cap: usize,
    tcap: usize,
    n: usize,
    groups: Vec<groups::Groups>,
}

impl<B: AsRef<[f64]> + AsMut<[f64]>, const T: usize> Store<B, T> {
    /// Words needed for `cap` particles.
    pub(crate) fn words(cap: usize) -> Option<usize> {
        let tcap = cap.max(1).checked_next_power_of_two()?;
        tcap.checked_mul(2 * T)?.checked_add(cap.max(1))
    }

    /// An empty store of capacity `cap` in `ws` (zeroed here).
    pub(crate) fn new(mut ws: B, cap: usize) -> Result<Self> {
        let need = Self::words(cap).ok_or(Error::Overflow {
            name: "event-driven workspace",
        })?;
        let got = ws.as_ref().len();
        if got < need {
            return Err(Error::BufferLength {
                name: "event-driven workspace (f64s)",
                expected: need,
                got,
            });
        }
        ws.as_mut()[..need].fill(0.0);
        Ok(Store {
            ws,
            cap: cap.max(1),
            tcap: cap.max(1).next_power_of_two(),
            n: 0,
            groups: Vec::new(),
        })
    }

    /// The sampler in use.
    pub(crate) fn sampler(&self) -> Sampler {
        if self.groups.is_empty() {
            Sampler::SumTree
        } else {
            Sampler::Groups
        }
    }

    /// Switches to `sampler`, built from the current weights (nothing changes on error).
    pub(crate) fn set_sampler(&mut self, sampler: Sampler) -> Result<()> {
        match sampler {
            Sampler::SumTree => {
                if !self.groups.is_empty() {
                    // the trees were left behind: build them from the weights
                    let mut w: Vec<[f64; T]> = Vec::new();
                    w.try_reserve_exact(self.n).map_err(|_| Error::Capacity {
                        name: "sum trees (rebuilding them)",
                        capacity: self.cap,
                    })?;
                    w.extend(
                        (0..self.n).map(|i| core::array::from_fn(|t| self.group_weight(t, i))),
                    );
                    self.groups.clear();
                    let n = self.n;
                    for t in 0..T {
                        let (cap, tcap) = (self.cap, self.tcap);
                        let o = cap + t * 2 * tcap;
                        let nodes = &mut self.ws.as_mut()[o..o + 2 * tcap];
                        nodes.fill(0.0);
                        for (i, wi) in w.iter().enumerate().take(n) {
                            nodes[tcap + i] = wi[t];
                        }
                        for j in (1..tcap).rev() {
                            nodes[j] = nodes[2 * j] + nodes[2 * j + 1];
                        }
                    }
                }
            }
            Sampler::Groups => {
                if self.groups.is_empty() {
                    let mut gs = Vec::new();
                    gs.try_reserve_exact(T).map_err(|_| Error::Capacity {
                        name: "group sampler tables",
                        capacity: self.cap,
                    })?;
                    for t in 0..T {
                        let mut g = groups::Groups::new(self.cap)?;
                        g.fill((0..self.n).map(|i| self.weight(t, i)));
                        gs.push(g);
                    }
                    self.groups = gs;
                }
            }
        }
        Ok(())
    }

    #[inline(always)]
    fn group_weight(&self, t: usize, i: usize) -> f64 {
        self.groups[t].weight(i)
    }

    /// Writes the sampler's own state (the group sampler's order).
    pub(crate) fn save_sampler(&self, w: &mut crate::checkpoint::Writer) {
        w.u64(u64::from(!self.groups.is_empty()));
        for g in &self.groups {
            g.save(w);
        }
    }

    /// Reads what [`save_sampler`](Self::save_sampler) wrote for particles of weights
    /// `weights` (`weights(x)` for the restored sizes `xs`), into a value to install
    /// with [`install_sampler`](Self::install_sampler) once everything is checked.
    pub(crate) fn read_sampler(
        &self,
        r: &mut crate::checkpoint::Reader,
        xs: &[f64],
        weights: impl Fn(f64) -> [f64; T],
    ) -> Result<Vec<groups::Groups>> {
        let bad = |what| Error::Checkpoint { what };
        match r.u64()? {
            0 if self.groups.is_empty() => Ok(Vec::new()),
            1 if !self.groups.is_empty() => {
                let mut gs = Vec::new();
                for t in 0..T {
                    gs.push(groups::Groups::read(
                        r,
                        self.cap,
                        xs.iter().map(|&x| weights(x)[t]),
                    )?);
                }
                Ok(gs)
            }
            0 | 1 => Err(bad("written with the other particle sampler")),
            _ => Err(bad("invalid particle sampler")),
        }
    }

    /// Installs the group sampler's state read by [`read_sampler`](Self::read_sampler)
    /// (after `fill` with the same sizes).
    pub(crate) fn install_sampler(&mut self, gs: Vec<groups::Groups>) {
        if !gs.is_empty() {
            self.groups = gs;
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.n
    }

    pub(crate) fn capacity(&self) -> usize {
        self.cap
    }

    pub(crate) fn sizes(&self) -> &[f64] {
        &self.ws.as_ref()[..self.n]
    }

    #[inline(always)]
    pub(crate) fn size(&self, i: usize) -> f64 {
        self.ws.as_ref()[i]
    }

    #[inline(always)]
    fn tree(&self, t: usize) -> &[f64] {
        let o = self.cap + t * 2 * self.tcap;
        &self.ws.as_ref()[o..o + 2 * self.tcap]
    }

    /// The weight of particle `i` in tree `t`.
    #[inline(always)]
    pub(crate) fn weight(&self, t: usize, i: usize) -> f64 {
        if self.groups.is_empty() {
            self.tree(t)[self.tcap + i]
        } else {
            self.group_weight(t, i)
        }
    }

    /// The total weight of tree `t`.
    #[inline(always)]
    pub(crate) fn total(&self, t: usize) -> f64 {
        if self.groups.is_empty() {
            self.tree(t)[1]
        } else {
            self.groups[t].total()
        }
    }

    /// A particle drawn with probability proportional to its weight in tree `t` (which
    /// must have a positive total): the descent only ever enters a child of positive
    /// weight, so a rounding in `u` cannot land on an empty leaf.
    #[inline]
    pub(crate) fn sample<R: Rng + ?Sized>(&self, t: usize, rng: &mut R) -> usize {
        if !self.groups.is_empty() {
            return self.groups[t].sample(rng);
        }
        let nodes = self.tree(t);
        let mut u = unit_f64(rng.next_u64()) * nodes[1];
        let mut j = 1;
        while j < self.tcap {
            let (l, r) = (nodes[2 * j], nodes[2 * j + 1]);
            if (u < l && l > 0.0) || r <= 0.0 {
                j *= 2;
            } else {
                u -= l;
                j = 2 * j + 1;
            }
        }
        (j - self.tcap).min(self.n.saturating_sub(1))
    }

    #[inline(always)]
    fn set_leaf(&mut self, t: usize, i: usize, w: f64) {
        let o = self.cap + t * 2 * self.tcap;
        let nodes = &mut self.ws.as_mut()[o..o + 2 * self.tcap];
        let mut j = self.tcap + i;
        nodes[j] = w;
        j /= 2;
        while j >= 1 {
            nodes[j] = nodes[2 * j] + nodes[2 * j + 1];
            j /= 2;
        }
    }

    /// Sets particle `i < len` to size `x` with weights `w`.
    #[inline]
    pub(crate) fn set(&mut self, i: usize, x: f64, w: [f64; T]) {
        self.ws.as_mut()[i] = x;
        if !self.groups.is_empty() {
            for (g, &wt) in self.groups.iter_mut().zip(&w) {
                if g.weight(i) != wt {
                    g.set(i, wt);
                }
            }
            return;
        }
        for (t, &wt) in w.iter().enumerate() {
            if self.weight(t, i) != wt {
                self.set_leaf(t, i, wt);
            }
        }
    }

    /// Appends a particle (the caller has checked `len < capacity`).
    #[inline]
    pub(crate) fn push(&mut self, x: f64, w: [f64; T]) {
        let i = self.n;
        self.n += 1;
        if !self.groups.is_empty() {
            self.ws.as_mut()[i] = x;
            for (g, &wt) in self.groups.iter_mut().zip(&w) {
                g.push(wt);
            }
            return;
        }
        self.set(i, x, w);
    }

    /// Removes particle `i`: the last one takes its place.
    #[inline]
    pub(crate) fn swap_remove(&mut self, i: usize) {
        let last = self.n - 1;
        if !self.groups.is_empty() {
            let ws = self.ws.as_mut();
            ws[i] = ws[last];
            ws[last] = 0.0;
            for g in &mut self.groups {
                g.swap_remove(i);
            }
            self.n = last;
            return;
        }
        if i != last {
            let x = self.size(last);
            let mut w = [0.0; T];
            for (t, wt) in w.iter_mut().enumerate() {
                *wt = self.weight(t, last);
            }
            self.set(i, x, w);
        }
        self.set(last, 0.0, [0.0; T]);
        self.n = last;
    }

    /// Replaces every particle by `sizes` (at most the capacity) with weights
    /// `weights(x)`, building the trees bottom-up.
    pub(crate) fn fill(&mut self, sizes: &[f64], weights: impl Fn(f64) -> [f64; T]) {
        let (cap, tcap) = (self.cap, self.tcap);
        let ws = self.ws.as_mut();
        ws[..cap].fill(0.0);
        ws[..sizes.len()].copy_from_slice(sizes);
        let (xs, trees) = ws.split_at_mut(cap);
        self.n = sizes.len();
        if !self.groups.is_empty() {
            for (t, g) in self.groups.iter_mut().enumerate() {
                g.fill(xs[..sizes.len()].iter().map(|&x| weights(x)[t]));
            }
            return;
        }
        for (t, nodes) in trees.chunks_exact_mut(2 * tcap).take(T).enumerate() {
            nodes.fill(0.0);
            for (i, &x) in xs[..sizes.len()].iter().enumerate() {
                nodes[tcap + i] = weights(x)[t];
            }
            for j in (1..tcap).rev() {
                nodes[j] = nodes[2 * j] + nodes[2 * j + 1];
            }
        }
    }

    /// Recomputes tree `t` from the sizes with `weight(x)`.
    pub(crate) fn refill_tree(&mut self, t: usize, weight: impl Fn(f64) -> f64) {
        let (cap, tcap, n) = (self.cap, self.tcap, self.n);
        if !self.groups.is_empty() {
            let xs = &self.ws.as_ref()[..n];
            self.groups[t].fill(xs.iter().map(|&x| weight(x)));
            return;
        }
        let ws = self.ws.as_mut();
        let (xs, trees) = ws.split_at_mut(cap);
        let nodes = &mut trees[t * 2 * tcap..(t + 1) * 2 * tcap];
        nodes.fill(0.0);
        for (i, &x) in xs[..n].iter().enumerate() {
            nodes[tcap + i] = weight(x);
        }
        for j in (1..tcap).rev() {
            nodes[j] = nodes[2 * j] + nodes[2 * j + 1];
        }
    }
}

/// `h(x)` of the kernel, validated: finite and not negative; a kernel without a product
/// majorant is `Unsupported`.
#[inline]
pub(crate) fn majorant<K: crate::kernel::CoagulationKernel>(k: &K, x: f64) -> Result<f64> {
    if x < k.min_size() {
        // the kernel guarantees its majorant only from min_size on
        return Err(Error::OutOfRange {
            name: "particle size (below the kernel's min_size, where its majorant is not guaranteed)",
            value: x,
            range: "[kernel min_size, inf)",
        });
    }
    match k.majorant(x) {
        Some(h) if h >= 0.0 && h.is_finite() => Ok(h),
        Some(h) => Err(Error::InvalidRate {
            name: "product majorant h(x)",
            value: h,
        }),
        None => Err(Error::Unsupported {
            what: "event-driven schemes (mfa, dsa, dsa-counts): the kernel needs a product majorant h(x) with K(x, y) <= h(x) h(y)",
        }),
    }
}

/// `Ḟ(x)`, validated (0 without fragmentation; see
/// [`crate::kernel::checked_break_rate`]).
#[inline]
pub(crate) fn break_rate<F: crate::kernel::FragmentationKernel>(f: &F, x: f64) -> Result<f64> {
    if f.is_none() {
        return Ok(0.0);
    }
    crate::kernel::checked_break_rate(f, x)
}

/// The acceptance of a proposal of kernel value `k` under majorant `hh`: `Ok(true)` with
/// probability `k/hh`; a value above the majorant (beyond rounding) is counted in
/// `violations` and accepted, or, `strict`, an error.
#[inline]
pub(crate) fn accept<R: Rng + ?Sized>(
    k: f64,
    hh: f64,
    strict: bool,
    violations: &mut u64,
    rng: &mut R,
) -> Result<bool> {
    if !(k >= 0.0 && k.is_finite()) {
        return Err(Error::InvalidRate {
            name: "coagulation kernel",
            value: k,
        });
    }
    if k > hh * (1.0 + 1e-12) {
        if strict {
            return Err(Error::BoundExceeded {
                name: "product majorant h(x) h(y)",
                rate: k,
                bound: hh,
            });
        }
        *violations += 1;
        return Ok(true);
    }
    Ok(unit_f64(rng.next_u64()) * hh < k)
}

/// Reads a list of sizes for a restore, each finite and positive.
pub(crate) fn read_sizes(r: &mut crate::checkpoint::Reader, cap: usize) -> Result<Vec<f64>> {
    let bad = |what| Error::Checkpoint { what };
    let n = r.usize()?;
    if n > cap {
        return Err(bad("more particles than the workspace holds"));
    }
    let mut xs = Vec::new();
    xs.try_reserve_exact(n)
        .map_err(|_| bad("cannot allocate the sizes"))?;
    for _ in 0..n {
        let x = r.f64()?;
        if !(x > 0.0 && x.is_finite()) {
            return Err(bad("a size that is not finite and positive"));
        }
        xs.push(x);
    }
    Ok(xs)
}

#[cfg(test)]
mod tests;
