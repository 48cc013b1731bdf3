//! Low-rank direct simulation Monte Carlo (Osinsky 2023, §5): every particle carries its
//! own 3-D velocity; particles of sizes i and j (masses i and j, diameters `i^{1/3}`,
//! `j^{1/3}`) with velocities `V_k`, `V_l` collide along a direction `e` (uniform on the
//! unit sphere) at rate
//!
//! ```text
//! C_kl(e) = (π/2) (i^{1/3} + j^{1/3})² |(V_k − V_l)·e| / V,
//! ```
//!
//! whose average over `e` is the hard-sphere rate `π (R_i + R_j)² |V_k − V_l| / V`
//! (`R = i^{1/3}/2`). A collision bounces with restitution coefficient ε (momentum
//! conserved, the normal relative kinetic energy multiplied by ε²) or, with the
//! probability a [`Sticking`] model gives (default: never, as in the paper's test),
//! aggregates into one particle of size `i + j` with the momentum-conserving velocity.
//!
//! It is the low-rank event loop with the rule [`Collisions`]:
//!
//! * **Bound.** A pair's rate integrated over `e` is `(π/4)(i^{1/3} + j^{1/3})² |V_k − V_l| / V`.
//!   With `w_i ≥ max |V|` over the size-i particles,
//!   `A_ij = (π/4) w_i (i^{1/3} + j^{1/3})²` (rank 3: `a = (π/4) w_i (i^{2/3}, 2 i^{1/3}, 1)`,
//!   `b = (1, j^{1/3}, j^{2/3})`), and `A_ij + A_ji` bounds it since
//!   `|V_k − V_l| ≤ w_i + w_j`. [`Gas`] is the kernel over the current maxima.
//! * **Proposals.** The engine draws sizes at rate `(A + Aᵀ) N_i N_j / V`; the rule picks
//!   two distinct particles of those sizes uniformly and accepts with the pair's rate
//!   over the engine's bound (on the trees, `|V_k − V_l| ≥ U (w_i + w_j)`), then draws
//!   the direction from its conditional law, density ∝ `|g·e|` (`cos θ = sqrt(U)`
//!   from `ĝ`). The seed's eq. 42 draws `e` uniformly and accepts `|g·e| ≥ U (w_i + w_j)`
//!   with the bound doubled: the same process, at half the acceptance.
//! * **Maxima.** A particle that leaves a collision faster than its size's `w` raises it
//!   (that size's factor row is rewritten, O(log M)); every `max(N, 1024)` collisions
//!   all maxima are recomputed from the particles (O(N + M)), so a maximum left by a
//!   particle that slowed down does not keep costing rejections.
//! * No particle doubling (its copies would not be independent).
//!
//! On the per-size tree engine this is the paper's low-rank DSMC ([`LowRankDsmc`]); on
//! the acceptance–rejection engine ([`RejectionDsmc`]: uniform pairs, one bound
//! `2 max A`) its baseline (the seed's eq. 43 takes `2 max_i (i^{1/3} + M^{1/3})² w_i`;
//! the engine's separable maximum is at least that and at most ~1.5× larger).
//!
//! # Example
//! ```
//! use coagula_core::scheme::Scheme;
//! use coagula_core::scheme::lowrank::dsmc::{Gas, LowRankDsmc};
//! let mut rng = rand_pcg::Pcg64Mcg::new(5);
//! // 20 000 monomers at T = 1 (Maxwellian), restitution 0.9, number density 0.1
//! let gas = Gas::maxwellian(0.9, &[20_000], &[1.0], &mut rng).unwrap();
//! let mut sim = LowRankDsmc::new_gas(gas, 200_000.0).unwrap();
//! let (e0, p0) = (sim.energy(), sim.momentum());
//! sim.advance_to(10.0, &mut rng).unwrap();
//! // the gas cools by Haff's law, T(t) = T0 / (1 + t/τ)² with
//! // τ = 3 / (2 sqrt(π) n σ² (1 − ε²) sqrt(T0)) ≈ 44.5 here: T(10)/T0 ≈ 0.666
//! let ratio = sim.energy() / e0;
//! assert!((ratio - 0.666).abs() < 0.01, "{ratio}");
//! // momentum is conserved by every collision
//! let p = sim.momentum();
//! assert!((0..3).all(|k| (p[k] - p0[k]).abs() < 1e-9 * 20_000.0));
//! ```

use super::proposal::{Candidate, ProposalEngine};
use super::rule::{EventRule, Outcome, Reweighed};
use super::trees::WideTree;
use super::{LowRankMc, TreeEngine, UniformEngine};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::kernel::temperature::size_cbrt;
use crate::random::{below, normal, open_unit, unit_f64};
use crate::scheme::population::try_reserve;
use alloc::vec::Vec;
use rand_core::Rng;

/// `π/4`.
const QUARTER_PI: f64 = core::f64::consts::FRAC_PI_4;

/// Collisions between recomputations of the speed maxima (at least; N if larger).
const RECOMPUTE: u64 = 1024;

/// A maximum is stored this much above the speed it covers, so that rounding in
/// `|(V_k − V_l)·e|` never exceeds `w_i + w_j`.
const MARGIN: f64 = 1.0 + 1e-12;

/// The probability that a collision aggregates (see the module docs).
pub trait Sticking {
    /// The probability in [0, 1] that particles of sizes `i`, `j` colliding with normal
    /// relative speed `gn = |(V_k − V_l)·e|` stick.
    fn probability(&self, i: u64, j: u64, gn: f64) -> f64;
}

/// Collisions never aggregate (the paper's test).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NeverStick;

impl Sticking for NeverStick {
    #[inline]
    fn probability(&self, _i: u64, _j: u64, _gn: f64) -> f64 {
        0.0
    }
}

/// Collisions aggregate when their normal relative speed is below `speed` (a barrier
/// model: `W = μ speed²/2` of normal kinetic energy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StickBelow {
    /// The threshold normal relative speed (≥ 0).
    pub speed: f64,
}

impl Sticking for StickBelow {
    #[inline]
    fn probability(&self, _i: u64, _j: u64, gn: f64) -> f64 {
        if gn < self.speed { 1.0 } else { 0.0 }
    }
}

/// Low-rank DSMC on the per-size trees.
pub type LowRankDsmc<S = NeverStick> = LowRankMc<Gas<S>, 3, TreeEngine<3, WideTree<3>>, Collisions>;
/// DSMC on the acceptance–rejection engine: the baseline.
pub type RejectionDsmc<S = NeverStick> = LowRankMc<Gas<S>, 3, UniformEngine<3>, Collisions>;

/// The particles' velocities by size, the restitution coefficient and the sticking
/// model: the DSMC kernel (its factors are those of the current speed maxima).
#[derive(Clone, Debug)]
pub struct Gas<S = NeverStick> {
    restitution: f64,
    sticking: S,
    /// `v[i − 1]`: the velocities of the size-i particles.
    v: Vec<Vec<[f64; 3]>>,
    /// `w[i − 1] ≥ max |V|` over them (0 for a size never held).
    w: Vec<f64>,
    /// Collisions since the maxima were recomputed.
    since: u64,
}

fn norm(v: &[f64; 3]) -> f64 {
    libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

fn check_restitution(eps: f64) -> Result<()> {
    if eps > 0.0 && eps <= 1.0 {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            name: "restitution coefficient",
            value: eps,
            range: "(0, 1]",
        })
    }
}

impl Gas<NeverStick> {
    /// `counts[i − 1]` particles of size i with Maxwellian velocities at temperature
    /// `temperatures[i − 1]` (each component normal with variance `T_i / i`), drawn
    /// from `rng`; collisions never stick. Errors: ε outside (0, 1], lengths differ,
    /// a temperature not finite or negative, more particles than memory allows.
    pub fn maxwellian<G: Rng + ?Sized>(
        restitution: f64,
        counts: &[u64],
        temperatures: &[f64],
        rng: &mut G,
    ) -> Result<Self> {
        if counts.len() != temperatures.len() {
            return Err(Error::BufferLength {
                name: "temperatures",
                expected: counts.len(),
                got: temperatures.len(),
            });
        }
        let mut sizes = Vec::new();
        let mut vel = Vec::new();
        for (i, (&c, &t)) in counts.iter().zip(temperatures).enumerate() {
            if !(t >= 0.0 && t.is_finite()) {
                return Err(Error::OutOfRange {
                    name: "temperature",
                    value: t,
                    range: "[0, inf)",
                });
            }
            let c = usize::try_from(c).map_err(|_| Error::Capacity {
                name: "particles (address space)",
                capacity: usize::MAX,
            })?;
            try_reserve(&mut sizes, c)?;
            try_reserve(&mut vel, c)?;
            let sd = libm::sqrt(t / (i + 1) as f64);
            for _ in 0..c {
                sizes.push(i as u64 + 1);
                vel.push([sd * normal(rng), sd * normal(rng), sd * normal(rng)]);
            }
        }
        Gas::from_particles(restitution, NeverStick, &sizes, &vel)
    }
}

impl<S: Sticking> Gas<S> {
    /// Particles of sizes `sizes[p] ≥ 1` with velocities `velocities[p]` (finite).
    pub fn from_particles(
        restitution: f64,
        sticking: S,
        sizes: &[u64],
        velocities: &[[f64; 3]],
    ) -> Result<Self> {
        check_restitution(restitution)?;
        if sizes.len() != velocities.len() {
            return Err(Error::BufferLength {
                name: "velocities",
                expected: sizes.len(),
                got: velocities.len(),
            });
        }
        let m = sizes.iter().copied().max().unwrap_or(0);
        if sizes.contains(&0) {
            return Err(Error::OutOfRange {
                name: "particle size",
                value: 0.0,
                range: "[1, inf)",
            });
        }
        let m = usize::try_from(m)
            .ok()
            .filter(|&m| m <= sizes.len().max(1 << 20))
            .ok_or(Error::Capacity {
                name: "largest particle size of a DSMC gas (at most max(N, 2^20))",
                capacity: sizes.len().max(1 << 20),
            })?;
        let mut v: Vec<Vec<[f64; 3]>> = Vec::new();
        try_reserve(&mut v, m)?;
        v.resize(m, Vec::new());
        for (&s, vel) in sizes.iter().zip(velocities) {
            if vel.iter().any(|c| !c.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "particle velocity",
                    value: vel
                        .iter()
                        .copied()
                        .find(|c| !c.is_finite())
                        .unwrap_or(f64::NAN),
                });
            }
            let list = &mut v[s as usize - 1];
            try_reserve(list, 1)?;
            list.push(*vel);
        }
        let mut gas = Gas {
            restitution,
            sticking,
            v,
            w: Vec::new(),
            since: 0,
        };
        try_reserve(&mut gas.w, m)?;
        gas.w.resize(m, 0.0);
        gas.recompute();
        Ok(gas)
    }

    /// The same particles with another sticking model.
    pub fn with_sticking<S2: Sticking>(self, sticking: S2) -> Gas<S2> {
        Gas {
            restitution: self.restitution,
            sticking,
            v: self.v,
            w: self.w,
            since: self.since,
        }
    }

    /// The counts `N_i` at index `i − 1`.
    pub fn counts(&self) -> Vec<u64> {
        self.v.iter().map(|l| l.len() as u64).collect()
    }

    /// The velocities of the size-`size` particles.
    pub fn velocities(&self, size: u64) -> &[[f64; 3]] {
        usize::try_from(size.wrapping_sub(1))
            .ok()
            .and_then(|i| self.v.get(i))
            .map_or(&[], |l| l.as_slice())
    }

    /// The restitution coefficient.
    pub fn restitution(&self) -> f64 {
        self.restitution
    }

    /// The speed bound `w_size` of a size.
    #[inline]
    fn w_of(&self, size: u64) -> f64 {
        self.w.get(size as usize - 1).copied().unwrap_or(0.0)
    }

    /// Recomputes every size's maximum from its particles.
    fn recompute(&mut self) {
        for (w, l) in self.w.iter_mut().zip(&self.v) {
            *w = l.iter().map(norm).fold(0.0, f64::max) * MARGIN;
        }
    }

    /// Total momentum `Σ m V` and kinetic energy `Σ m |V|²/2`, and the partial
    /// temperature `m ⟨|V|²⟩/3` of size i.
    fn totals(&self) -> ([f64; 3], f64) {
        let (mut p, mut e) = ([0.0; 3], 0.0);
        for (i, l) in self.v.iter().enumerate() {
            let m = (i + 1) as f64;
            for v in l {
                for k in 0..3 {
                    p[k] += m * v[k];
                }
                e += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            }
        }
        (p, e)
    }
}

impl<S: Sticking> CoagulationKernel for Gas<S> {
    /// The bound `(π/4)(x^{1/3} + y^{1/3})² (w_x + w_y)` (the rate of a pair depends on
    /// its velocities and a direction).
    fn rate(&self, x: f64, y: f64) -> f64 {
        let (i, j) = (x as u64, y as u64);
        let d = size_cbrt(i) + size_cbrt(j);
        QUARTER_PI * d * d * (self.w_of(i) + self.w_of(j))
    }

    fn rank(&self) -> usize {
        3
    }

    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        let i = x as u64;
        let c = size_cbrt(i);
        let w = QUARTER_PI * self.w_of(i);
        a[..3].copy_from_slice(&[w * c * c, 2.0 * w * c, w]);
        b[..3].copy_from_slice(&[1.0, c, c * c]);
    }

    fn min_size(&self) -> f64 {
        1.0
    }
}

/// What an accepted collision changes, from `plan` to `commit`.
#[derive(Clone, Copy, Debug, Default)]
enum Pending {
    #[default]
    None,
    /// Particles `(x, k)` and `(y, l)` leave with these velocities.
    Bounce {
        x: u64,
        k: usize,
        vk: [f64; 3],
        y: u64,
        l: usize,
        vl: [f64; 3],
    },
    /// Particles `(x, k)` and `(y, l)` become one of size `x + y` with velocity `v`.
    Merge {
        x: u64,
        k: usize,
        y: u64,
        l: usize,
        v: [f64; 3],
    },
}

/// The DSMC collision rule (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Collisions {
    /// The accepted pair: particle indices within their sizes, direction, `(V_k − V_l)·e`.
    k: usize,
    l: usize,
    e: [f64; 3],
    gn: f64,
    pending: Pending,
    refactor: bool,
}

/// A direction uniform on the unit sphere (Marsaglia 1972).
#[inline]
fn direction<G: Rng + ?Sized>(rng: &mut G) -> [f64; 3] {
    loop {
        let u1 = 2.0 * unit_f64(rng.next_u64()) - 1.0;
        let u2 = 2.0 * unit_f64(rng.next_u64()) - 1.0;
        let s = u1 * u1 + u2 * u2;
        if s < 1.0 {
            let r = 2.0 * libm::sqrt(1.0 - s);
            return [u1 * r, u2 * r, 1.0 - 2.0 * s];
        }
    }
}

/// A collision direction for relative velocity `g` (`|g| = gabs`): `e` with density
/// ∝ `|g·e|` on the unit sphere, and `g·e`. For `g = 0` any direction (`g·e = 0`).
#[inline]
fn oriented<G: Rng + ?Sized>(g: &[f64; 3], gabs: f64, rng: &mut G) -> ([f64; 3], f64) {
    let r = direction(rng);
    if gabs.is_nan() || gabs <= 0.0 {
        return (r, 0.0);
    }
    let gh = [g[0] / gabs, g[1] / gabs, g[2] / gabs];
    let c = libm::sqrt(unit_f64(rng.next_u64()));
    // a uniform direction perpendicular to ĝ from r (r ∥ ĝ has probability 0; its
    // rounding remnant is caught by the length test)
    let rg = r[0] * gh[0] + r[1] * gh[1] + r[2] * gh[2];
    let mut p = [r[0] - rg * gh[0], r[1] - rg * gh[1], r[2] - rg * gh[2]];
    let pl = norm(&p);
    if pl.is_nan() || pl <= 1e-8 {
        return (gh, gabs);
    }
    let sn = libm::sqrt((1.0 - c * c).max(0.0)) / pl;
    for (pk, gk) in p.iter_mut().zip(gh) {
        *pk = c * gk + sn * *pk;
    }
    (p, gabs * c)
}

fn bad_velocity(v: f64) -> Error {
    Error::InvalidRate {
        name: "particle velocity after a collision",
        value: v,
    }
}

impl<S: Sticking + Clone> EventRule<Gas<S>> for Collisions {
    const REWEIGHS: bool = true;
    const DOUBLES: bool = false;
    const TAG: Option<u64> = Some(crate::checkpoint::tag::DSMC);

    fn for_kernel(_kernel: &Gas<S>) -> Self {
        Collisions::default()
    }

    #[inline]
    fn decide<L, G: Rng + ?Sized>(
        &mut self,
        gas: &Gas<S>,
        c: &Candidate<L>,
        bounds: impl FnOnce() -> (f64, f64),
        _low_is_bound: bool,
        _spot: bool,
        rng: &mut G,
    ) -> Result<Option<Outcome>> {
        let (x, y) = (c.x, c.y);
        let (lx, ly) = (&gas.v[x as usize - 1], &gas.v[y as usize - 1]);
        // two distinct particles of the proposed sizes (the engine has already thinned
        // a size paired with itself by (N − 1)/N)
        let k = below(rng, lx.len() as u64) as usize;
        let l = if x == y {
            let l = below(rng, lx.len() as u64 - 1) as usize;
            l + usize::from(l >= k)
        } else {
            below(rng, ly.len() as u64) as usize
        };
        let (vk, vl) = (lx[k], ly[l]);
        let g = [vk[0] - vl[0], vk[1] - vl[1], vk[2] - vl[2]];
        let gabs = norm(&g);
        // the pair's rate integrated over e against the engine's bound at the pair: on
        // the per-size trees (π/4)(x^{1/3} + y^{1/3})² (w_x + w_y)
        let (bound, _) = bounds();
        let d = size_cbrt(x) + size_cbrt(y);
        let rate = QUARTER_PI * d * d * gabs;
        if rate.is_nan() || rate > bound * (1.0 + 1e-12) {
            // a speed past its size's maximum: an invariant broke (or a velocity is NaN)
            return Err(Error::BoundExceeded {
                name: "DSMC speed maxima",
                rate,
                bound,
            });
        }
        if rate < bound * open_unit(rng) {
            return Ok(None);
        }
        // the direction given the pair: density ∝ |g·e| on the sphere, i.e.
        // cos θ = sqrt(U) from ĝ (the sign of e does not matter), azimuth uniform
        let (e, gn) = oriented(&g, gabs, rng);
        (self.k, self.l, self.e, self.gn) = (k, l, e, gn);
        let p = gas.sticking.probability(x, y, gn.abs());
        if !(0.0..=1.0).contains(&p) {
            return Err(Error::InvalidRate {
                name: "sticking probability",
                value: p,
            });
        }
        Ok(Some(if p > 0.0 && open_unit(rng) <= p {
            Outcome::Merge {
                size: x.saturating_add(y),
            }
        } else {
            Outcome::Bounce
        }))
    }

    fn plan(
        &mut self,
        gas: &mut Gas<S>,
        (x, y): (u64, u64),
        outcome: &Outcome,
        _count: &dyn Fn(u64) -> u64,
    ) -> Result<()> {
        let (k, l, e, gn) = (self.k, self.l, self.e, self.gn);
        let vk = gas.v[x as usize - 1][k];
        let vl = gas.v[y as usize - 1][l];
        let (mx, my) = (x as f64, y as f64);
        self.pending = match *outcome {
            Outcome::Bounce => {
                // momentum along e exchanged, the normal relative velocity times −ε
                let q = (1.0 + gas.restitution) * gn / (mx + my);
                let mut nk = vk;
                let mut nl = vl;
                for d in 0..3 {
                    nk[d] -= q * my * e[d];
                    nl[d] += q * mx * e[d];
                }
                if let Some(&bad) = nk.iter().chain(&nl).find(|c| !c.is_finite()) {
                    return Err(bad_velocity(bad));
                }
                Pending::Bounce {
                    x,
                    k,
                    vk: nk,
                    y,
                    l,
                    vl: nl,
                }
            }
            Outcome::Merge { size } => {
                let mut v = [0.0; 3];
                for d in 0..3 {
                    v[d] = (mx * vk[d] + my * vl[d]) / (mx + my);
                }
                if let Some(&bad) = v.iter().find(|c| !c.is_finite()) {
                    return Err(bad_velocity(bad));
                }
                // room for the merged particle before anything changes
                let idx = usize::try_from(size - 1).map_err(|_| Error::Capacity {
                    name: "particle size",
                    capacity: usize::MAX,
                })?;
                if idx >= gas.v.len() {
                    let more = idx + 1 - gas.v.len();
                    try_reserve(&mut gas.v, more)?;
                    try_reserve(&mut gas.w, more)?;
                    gas.v.resize(idx + 1, Vec::new());
                    gas.w.resize(idx + 1, 0.0);
                }
                try_reserve(&mut gas.v[idx], 1)?;
                Pending::Merge { x, k, y, l, v }
            }
        };
        Ok(())
    }

    fn commit(&mut self, gas: &mut Gas<S>) -> Reweighed {
        let mut changed = Reweighed::new();
        let raise = |gas: &mut Gas<S>, size: u64, v: &[f64; 3], changed: &mut Reweighed| {
            let s = norm(v) * MARGIN;
            let w = &mut gas.w[size as usize - 1];
            if s > *w {
                *w = s;
                if !changed.contains(&size) {
                    let _ = changed.push(size);
                }
            }
        };
        match core::mem::take(&mut self.pending) {
            Pending::None => {}
            Pending::Bounce { x, k, vk, y, l, vl } => {
                gas.v[x as usize - 1][k] = vk;
                gas.v[y as usize - 1][l] = vl;
                raise(gas, x, &vk, &mut changed);
                raise(gas, y, &vl, &mut changed);
            }
            Pending::Merge { x, k, y, l, v } => {
                // (the larger index first when both are of one size)
                if x == y {
                    let list = &mut gas.v[x as usize - 1];
                    list.swap_remove(k.max(l));
                    list.swap_remove(k.min(l));
                } else {
                    gas.v[x as usize - 1].swap_remove(k);
                    gas.v[y as usize - 1].swap_remove(l);
                }
                let size = x + y;
                gas.v[size as usize - 1].push(v);
                raise(gas, size, &v, &mut changed);
            }
        }
        gas.since += 1;
        if gas.since >= RECOMPUTE.max(gas.v.iter().map(|l| l.len() as u64).sum()) {
            gas.recompute();
            gas.since = 0;
            self.refactor = true;
        }
        changed
    }

    fn refactor_due(&mut self) -> bool {
        core::mem::take(&mut self.refactor)
    }

    fn check_counts(gas: &Gas<S>, counts: &[u64]) -> Result<()> {
        let agree = counts
            .iter()
            .copied()
            .chain(core::iter::repeat(0))
            .zip(
                gas.v
                    .iter()
                    .map(|l| l.len() as u64)
                    .chain(core::iter::repeat(0)),
            )
            .take(counts.len().max(gas.v.len()))
            .all(|(a, b)| a == b);
        if agree {
            Ok(())
        } else {
            Err(Error::Unsupported {
                what: "DSMC counts must be those of the gas's particles (build from the Gas)",
            })
        }
    }

    fn save(&self, gas: &Gas<S>, w: &mut Writer) {
        w.u64(gas.since);
        w.u64(gas.v.len() as u64);
        for l in &gas.v {
            w.f64s(&l.iter().flatten().copied().collect::<Vec<_>>());
        }
        w.f64s(&gas.w);
    }

    fn load(&self, gas: &Gas<S>, r: &mut Reader) -> Result<Option<Gas<S>>> {
        let bad = |what| Error::Checkpoint { what };
        let since = r.u64()?;
        let m = r.u64()?;
        let mut v = Vec::new();
        for _ in 0..m {
            let flat = r.f64s()?;
            if flat.len() % 3 != 0 || flat.iter().any(|c| !c.is_finite()) {
                return Err(bad("invalid particle velocities"));
            }
            try_reserve(&mut v, 1)?;
            v.push(
                flat.chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]])
                    .collect::<Vec<_>>(),
            );
        }
        let w = r.f64s()?;
        if w.len() != v.len()
            || v.iter()
                .zip(&w)
                .any(|(l, &wi)| !(wi.is_finite() && l.iter().all(|x| norm(x) * MARGIN <= wi)))
        {
            return Err(bad("speed maxima do not bound the particles"));
        }
        if since > RECOMPUTE.max(v.iter().map(|l| l.len() as u64).sum()) {
            return Err(bad("invalid collision counter"));
        }
        Ok(Some(Gas {
            restitution: gas.restitution,
            sticking: gas.sticking.clone(),
            v,
            w,
            since,
        }))
    }
}

impl<S, E> LowRankMc<Gas<S>, 3, E, Collisions>
where
    S: Sticking + Clone,
    E: ProposalEngine<3>,
{
    /// The scheme over the particles of `gas` in volume `volume`.
    pub fn new_gas(gas: Gas<S>, volume: f64) -> Result<Self> {
        let counts = gas.counts();
        Self::new(gas, &counts, volume)
    }

    /// Total momentum `Σ_p m_p V_p` (not divided by V).
    pub fn momentum(&self) -> [f64; 3] {
        self.kernel().totals().0
    }

    /// Kinetic energy density `Σ_p m_p |V_p|²/2 / V`.
    pub fn energy(&self) -> f64 {
        self.kernel().totals().1 / self.volume()
    }

    /// The granular temperature `Σ_p m_p |V_p|² / (3N)` (0 without particles).
    pub fn mean_temperature(&self) -> f64 {
        let n = self.particles();
        if n == 0 {
            return 0.0;
        }
        2.0 * self.kernel().totals().1 / (3.0 * n as f64)
    }

    /// The partial temperature `m ⟨|V|²⟩/3` of size `size` (0 when none).
    pub fn temperature(&self, size: u64) -> f64 {
        let l = self.kernel().velocities(size);
        if l.is_empty() {
            return 0.0;
        }
        let s: f64 = l
            .iter()
            .map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
            .sum();
        size as f64 * s / (3.0 * l.len() as f64)
    }
}
