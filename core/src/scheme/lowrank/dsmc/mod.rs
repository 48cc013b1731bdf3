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
//! probability a `Sticking` model gives (default: never, as in the paper's test),
//! aggregates into one particle of size `i + j` with the momentum-conserving velocity.
//!
//! It is the low-rank event loop with the rule [`Collisions`]:
//!
//! * **Speed classes.** The particles of a size are kept in classes of speed: class q
//!   holds `|V|² ∈ [2^{q/2}, 2^{(q+1)/2})`, and `W_q = 2^{(q+1)/4}` bounds its speeds
//!   within a factor `2^{1/4}`. A particle's bound `W_k` is its class's. Particles at
//!   rest (`|V|² < 2^{−1022}`) share one class of bound `2^{−511}`; the moving speeds
//!   of one size must lie within a factor `2^{128}` of each other (else
//!   [`Error::Capacity`], where a gas or a collision would pass it).
//! * **Bound.** A pair's rate integrated over `e` is
//!   `(π/4)(i^{1/3} + j^{1/3})² |V_k − V_l| / V ≤ (π/4)(i^{1/3} + j^{1/3})² (W_k + W_l) / V`.
//!   Summed over the particles of sizes i and j that is `A_ij + A_ji` with
//!   `A_ij = (π/4) (i^{1/3} + j^{1/3})² S_i N_j`, `S_i = Σ_k W_k` over size i: rank 3,
//!   `a(i) = (π/4)(S_i/N_i)(i^{2/3}, 2 i^{1/3}, 1)`, `b(j) = (1, j^{1/3}, j^{2/3})`.
//!   [`Gas`] is the kernel with these factors.
//! * **Proposals (per-size trees).** The engine draws the first size from the `a`
//!   weights (∝ `S_i`) and the second from the `b` weights (∝ `N_j`); the rule takes the
//!   first particle ∝ `W_k` (a class ∝ `n_q W_q`, then uniformly in it) and the second
//!   uniformly, so an unordered pair is proposed at rate ∝ `W_k + W_l`, and accepts with
//!   `|V_k − V_l| / (W_k + W_l)` (about 0.6 for Maxwellian speeds; the seed's per-size
//!   maxima give about 0.23 at 10^5 particles per size). The direction then comes from
//!   its conditional law, density ∝ `|g·e|` (`cos θ = sqrt(U)` from `ĝ`); the seed's
//!   eq. 42 draws `e` uniformly and accepts `|g·e|` against twice the bound: the same
//!   process at half the acceptance, kept as [`Directions::Uniform`] (on the
//!   acceptance–rejection engine below that is the seed's eq. 43, the paper's
//!   baseline).
//! * **Acceptance–rejection engine** ([`RejectionDsmc`]): the factors use each size's
//!   largest class bound instead of the mean (`a(i) = (π/4) max_k W_k (…)`), pairs are
//!   uniform, and the rule accepts with the pair's rate over the engine's bound `2 max A`
//!   (the seed's eq. 43 takes `2 max_i (i^{1/3} + M^{1/3})² max_k |V_k|`, at least as
//!   large up to the class factor `2^{1/4}`).
//! * Every collision moves its particles between classes as their speeds change (O(1))
//!   and rewrites the factor rows of the sizes touched (O(log M)). No stale bound is
//!   ever kept.
//! * No particle doubling (its copies would not be independent).
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

use super::proposal::{Candidate, Low, Outcome, ProposalEngine};
use super::rule::{EventRule, Reweighed};
use super::trees::WideTree;
use super::{LowRankMc, TreeEngine, UniformEngine};
use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::kernel::gas::{NeverStick, Sticking, check_restitution};
use crate::kernel::temperature::size_cbrt;
use crate::random::{below, open_unit, unit_f64};
use crate::scheme::population::try_reserve;
use alloc::vec::Vec;
use rand_core::Rng;

/// `π/4`.
const QUARTER_PI: f64 = core::f64::consts::FRAC_PI_4;

/// Low-rank DSMC on the per-size trees.
pub type LowRankDsmc<S = NeverStick> = LowRankMc<Gas<S>, 3, TreeEngine<3, WideTree<3>>, Collisions>;
/// DSMC on the acceptance–rejection engine: the baseline.
pub type RejectionDsmc<S = NeverStick> = LowRankMc<Gas<S>, 3, UniformEngine<3>, Collisions>;

/// The particles' velocities by size and speed class, the restitution coefficient and
/// the sticking model: the DSMC kernel (see the module docs).
#[derive(Clone, Debug)]
pub struct Gas<S = NeverStick> {
    restitution: f64,
    sticking: S,
    /// `species[i − 1]`: the size-i particles.
    species: Vec<Species>,
    /// Factors from the mean class bound (the per-size trees draw the first particle ∝
    /// its bound) rather than the largest (any engine).
    weighted: bool,
    directions: Directions,
}

pub use crate::scheme::facade::Directions;

mod collide;
mod species;

pub use collide::Collisions;
use species::*;

fn norm(v: &[f64; 3]) -> f64 {
    libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

impl Gas<NeverStick> {
    /// `counts[i − 1]` particles of size i with Maxwellian velocities at temperature
    /// `temperatures[i − 1]` ([`crate::initial::maxwellian`]), drawn from `rng`;
    /// collisions never stick. Errors: ε outside (0, 1], lengths differ, a temperature
    /// not finite or negative, more particles than memory allows.
    pub fn maxwellian<G: Rng + ?Sized>(
        restitution: f64,
        counts: &[u64],
        temperatures: &[f64],
        rng: &mut G,
    ) -> Result<Self> {
        let (sizes, vel) = crate::initial::maxwellian(counts, temperatures, rng)?;
        Gas::from_particles(restitution, NeverStick, &sizes, vel.as_chunks::<3>().0)
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
        if sizes.contains(&0) {
            return Err(Error::OutOfRange {
                name: "particle size",
                value: 0.0,
                range: "[1, inf)",
            });
        }
        let m = sizes.iter().copied().max().unwrap_or(0);
        let m = usize::try_from(m)
            .ok()
            .filter(|&m| m <= sizes.len().max(1 << 20))
            .ok_or(Error::Capacity {
                name: "largest particle size of a DSMC gas (at most max(N, 2^20))",
                capacity: sizes.len().max(1 << 20),
            })?;
        let mut species: Vec<Species> = Vec::new();
        try_reserve(&mut species, m)?;
        species.resize(m, Species::default());
        for (&s, vel) in sizes.iter().zip(velocities) {
            if !finite_speed(vel) {
                // bad input, not a bad rate: the component that is not finite, else |v|²
                let value = vel
                    .iter()
                    .copied()
                    .find(|c| !c.is_finite())
                    .unwrap_or(vel[0] * vel[0] + vel[1] * vel[1] + vel[2] * vel[2]);
                return Err(Error::OutOfRange {
                    name: "particle velocity (components and |v|²)",
                    value,
                    range: "finite",
                });
            }
            let sp = &mut species[s as usize - 1];
            sp.reserve(&[class_of(vel)])?;
            sp.insert(*vel);
        }
        Ok(Gas {
            restitution,
            sticking,
            species,
            weighted: false,
            directions: Directions::Conditional,
        })
    }

    /// The same particles with another sticking model.
    pub fn with_sticking<S2: Sticking>(self, sticking: S2) -> Gas<S2> {
        Gas {
            restitution: self.restitution,
            sticking,
            species: self.species,
            weighted: self.weighted,
            directions: self.directions,
        }
    }

    /// The same particles with collision directions drawn as `directions` says (a
    /// setting, like the restitution: a checkpoint restores into a scheme built with
    /// the same).
    pub fn with_directions(mut self, directions: Directions) -> Self {
        self.directions = directions;
        self
    }

    /// How collision directions are drawn.
    pub fn directions(&self) -> Directions {
        self.directions
    }

    /// `π/4`, or twice that when directions are uniform (the bound of a rate before
    /// `e` is averaged out).
    #[inline]
    fn scale(&self) -> f64 {
        match self.directions {
            Directions::Conditional => QUARTER_PI,
            Directions::Uniform => 2.0 * QUARTER_PI,
        }
    }

    /// The counts `N_i` at index `i − 1`.
    pub fn counts(&self) -> Vec<u64> {
        self.species.iter().map(|s| s.n as u64).collect()
    }

    /// The velocities of the size-`size` particles (by speed class).
    pub fn velocities(&self, size: u64) -> impl Iterator<Item = &[f64; 3]> {
        usize::try_from(size.wrapping_sub(1))
            .ok()
            .and_then(|i| self.species.get(i))
            .into_iter()
            .flat_map(|s| s.classes.iter().flat_map(|c| c.v.iter()))
    }

    /// The restitution coefficient.
    pub fn restitution(&self) -> f64 {
        self.restitution
    }

    /// The speed bound of size `size`: the largest bound of its non-empty speed classes
    /// (at most `2^{1/4}` above its fastest particle, or `2^{−511}` when all are at rest
    /// or within `2^{−511}` of it; 0 when there are none).
    pub fn speed_bound(&self, size: u64) -> f64 {
        self.species(size).map_or(0.0, |s| s.top)
    }

    /// The acceptance–rejection engine's bound `2 Σ_k max a_k max b_k` (from the
    /// factors of [`CoagulationKernel::factors`] over the occupied sizes) over the
    /// seed's eq. 43 bound `2 (π/4) max_i (i^{1/3} + M^{1/3})² max_{p of size i} |V_p|`
    /// (M the largest size): how many times more proposals our baseline's rejections
    /// cost than the paper's (Osinsky 2023 §5, `coagula bench dsmc`).
    pub fn bound_over_eq43(&self) -> f64
    where
        S: Sticking,
    {
        let m = self.species.len() as f64;
        let (mut amax, mut bmax) = ([0.0f64; 3], [0.0f64; 3]);
        let mut eq43 = 0.0f64;
        for (i, sp) in self.species.iter().enumerate() {
            if sp.n == 0 {
                continue;
            }
            let size = i as u64 + 1;
            let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
            self.factors(size as f64, &mut a, &mut b);
            for k in 0..3 {
                amax[k] = amax[k].max(a[k]);
                bmax[k] = bmax[k].max(b[k]);
            }
            let fastest = self
                .velocities(size)
                .map(|v| libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
                .fold(0.0, f64::max);
            let d = libm::cbrt(size as f64) + libm::cbrt(m);
            eq43 = eq43.max(d * d * fastest);
        }
        let ours: f64 = 2.0 * (0..3).map(|k| amax[k] * bmax[k]).sum::<f64>();
        ours / (2.0 * QUARTER_PI * eq43)
    }

    #[inline]
    fn species(&self, size: u64) -> Option<&Species> {
        self.species
            .get(usize::try_from(size.wrapping_sub(1)).ok()?)
    }

    /// Total momentum `Σ m V` and kinetic energy `Σ m |V|²/2`.
    fn totals(&self) -> ([f64; 3], f64) {
        let (mut p, mut e) = ([0.0; 3], 0.0);
        for (i, sp) in self.species.iter().enumerate() {
            let m = (i + 1) as f64;
            for v in sp.classes.iter().flat_map(|c| c.v.iter()) {
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
    /// The bound `(π/4)(x^{1/3} + y^{1/3})² (w_x + w_y)` (twice that with
    /// [`Directions::Uniform`]) with `w` the factors' speed (the rate of a pair depends
    /// on its velocities).
    fn rate(&self, x: f64, y: f64) -> f64 {
        let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
        let (mut a2, mut b2) = ([0.0; 3], [0.0; 3]);
        self.factors(x, &mut a, &mut b);
        self.factors(y, &mut a2, &mut b2);
        (0..3).map(|k| a[k] * b2[k] + a2[k] * b[k]).sum()
    }

    fn rank(&self) -> usize {
        3
    }

    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        let i = x as u64;
        let c = size_cbrt(i);
        let w = match self.species(i) {
            Some(sp) if sp.n > 0 => {
                if self.weighted {
                    sp.s / sp.n as f64
                } else {
                    sp.top
                }
            }
            _ => 0.0,
        };
        let w = self.scale() * w;
        a[..3].copy_from_slice(&[w * c * c, 2.0 * w * c, w]);
        b[..3].copy_from_slice(&[1.0, c, c * c]);
    }

    fn min_size(&self) -> f64 {
        1.0
    }
}

impl<S, E> LowRankMc<Gas<S>, 3, E, Collisions>
where
    S: Sticking + Clone,
    E: ProposalEngine<3>,
{
    /// The scheme over the particles of `gas` in volume `volume` (on the per-size
    /// trees the first particle of a pair is drawn ∝ its speed bound; see the module
    /// docs).
    pub fn new_gas(mut gas: Gas<S>, volume: f64) -> Result<Self> {
        gas.weighted = E::LOW == Low::Bound;
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
        let (mut n, mut s) = (0usize, 0.0);
        for v in self.kernel().velocities(size) {
            n += 1;
            s += v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        }
        if n == 0 {
            return 0.0;
        }
        size as f64 * s / (3.0 * n as f64)
    }
}

#[cfg(test)]
mod tests;
