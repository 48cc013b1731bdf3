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

use super::proposal::{Candidate, Outcome, ProposalEngine};
use super::rule::{EventRule, Reweighed};
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

/// How a collision's direction `e` is drawn (the same process either way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Directions {
    /// Integrated out: a pair is proposed against the bound of its rate averaged over
    /// `e`, accepted with `|V_k − V_l|` over it, and `e` then drawn from its conditional
    /// law. Half the proposals of [`Uniform`](Self::Uniform).
    #[default]
    Conditional,
    /// Uniform on the sphere, and the pair accepted on `|(V_k − V_l)·e|` against twice
    /// that bound: the seed's eqs. 42 (per-size trees) and 43 (acceptance–rejection),
    /// kept as the paper's baseline.
    Uniform,
}

/// The particles of one speed class.
#[derive(Clone, Debug)]
struct Class {
    /// `2^{(q+1)/4}`, a little above (so that rounding never lets a speed pass it).
    w: f64,
    v: Vec<[f64; 3]>,
}

impl Class {
    fn new(q: i32) -> Self {
        Class {
            w: class_bound(q),
            v: Vec::new(),
        }
    }
}

/// The particles of one size, by speed class.
///
/// `classes[0]` is the class of the particles (almost) at rest, [`Q_MIN`]; after it the
/// classes are dense: `classes[d]` is class `base + d − 1` (empty ones included), so a
/// class is found by a subtraction. The counts and the sum `S = Σ_q n_q W_q` are kept
/// up to date at every move: `W_q = R_r 2^h` with `q + 1 = 4h + r` and `R_r = 2^{r/4}`
/// (rounded up), so the moving classes' part of `S` is `2^a Σ_r R_r X_r` with integers
/// `X_r = Σ_{q ≡ r} n_q 2^{h − a}` (`a` the lowest occupied `h`), updated exactly; the
/// class at rest adds `n_0 W_{Q_MIN}`. `S` is the rounding of these: the same for the
/// same particles however they came there (a restored checkpoint goes on bit for bit).
/// A size whose speeds span so many octaves that an `X_r` does not fit in 128 bits
/// (about 2^87 with 2^40 particles) falls back to summing its classes in order at every
/// move; one whose moving classes would span more than [`MAX_CLASSES`] is refused.
#[derive(Clone, Debug)]
struct Species {
    /// The class of `classes[1]`.
    base: i32,
    /// The class at rest, then the moving classes (empty until the first `reserve`).
    classes: Vec<Class>,
    /// Particles.
    n: usize,
    /// `Σ_q n_q W_q` (0 when empty).
    s: f64,
    /// The largest bound of an occupied class (0 when empty).
    top: f64,
    /// The occupied moving classes are within `lo..end` (indices into `classes`, the
    /// first and one past the last occupied; `lo == end` when none is).
    lo: usize,
    end: usize,
    /// Whether `x` holds the sums (else `s` is summed class by class).
    exact: bool,
    /// The `h` of the lowest occupied moving class, and `X_r`.
    anchor: i32,
    x: [u128; 4],
}

impl Default for Species {
    /// No particles (the fields as `resum` leaves them).
    fn default() -> Self {
        Species {
            base: 0,
            classes: Vec::new(),
            n: 0,
            s: 0.0,
            top: 0.0,
            lo: 1,
            end: 1,
            exact: true,
            anchor: 0,
            x: [0; 4],
        }
    }
}

/// A little above 1: class bounds are rounded up by it.
const MARGIN: f64 = 1.0 + 1e-12;

/// `2^{r/4}` for r = 0..3 (each within half an ulp; [`MARGIN`] covers it).
const ROOTS: [f64; 4] = [
    1.0,
    1.189_207_115_002_721,
    core::f64::consts::SQRT_2,
    1.681_792_830_507_429,
];

/// The mantissa bits of √2.
const SQRT2_MANTISSA: u64 = core::f64::consts::SQRT_2.to_bits() & ((1 << 52) - 1);

/// The class at rest: `|v|² < 2^{−1022}` (zero or subnormal), bound `2^{−511}`.
const Q_MIN: i32 = -2045;

/// The most moving classes one size may span: speeds within a factor `2^{128}`.
const MAX_CLASSES: usize = 512;

/// The speed class of `v`: `q` with `|v|² ∈ [2^{q/2}, 2^{(q+1)/2})`, or [`Q_MIN`] for
/// `|v|² < 2^{−1022}`. `|v|²` must be finite.
#[inline]
fn class_of(v: &[f64; 3]) -> i32 {
    let s = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    debug_assert!(s.is_finite(), "a speed without a class");
    let bits = s.to_bits();
    let field = ((bits >> 52) & 0x7ff) as i32;
    if field == 0 || !s.is_finite() {
        Q_MIN
    } else {
        2 * (field - 1023) + i32::from(bits & ((1 << 52) - 1) >= SQRT2_MANTISSA)
    }
}

/// A velocity whose components and `|v|²` are finite (`|v|² = inf` has no class).
fn finite_speed(v: &[f64; 3]) -> bool {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).is_finite()
}

/// `(h, r)` with `q + 1 = 4h + r`, `0 ≤ r < 4`.
#[inline]
fn class_parts(q: i32) -> (i32, usize) {
    ((q + 1).div_euclid(4), (q + 1).rem_euclid(4) as usize)
}

/// The bound of class q: `2^{(q+1)/4}`, a little above.
fn class_bound(q: i32) -> f64 {
    let (h, r) = class_parts(q);
    libm::scalbn(ROOTS[r] * MARGIN, h)
}

impl Species {
    /// The index of class `q` in `classes`, if within the range.
    #[inline]
    fn index(&self, q: i32) -> Option<usize> {
        if self.classes.is_empty() {
            return None;
        }
        if q == Q_MIN {
            return Some(0);
        }
        usize::try_from(i64::from(q) - i64::from(self.base) + 1)
            .ok()
            .filter(|&d| d >= 1 && d < self.classes.len())
    }

    /// The class at index `d`.
    #[inline]
    fn q(&self, d: usize) -> i32 {
        if d == 0 {
            Q_MIN
        } else {
            self.base + (d - 1) as i32
        }
    }

    /// `2^a Σ_r R_r X_r`, rounded, plus the class at rest.
    fn exact_sum(&self) -> f64 {
        let mut t = 0.0;
        for (r, &x) in self.x.iter().enumerate() {
            // (the same rounding as `x as f64`, in hardware when it fits 64 bits)
            let x = u64::try_from(x).map_or(x as f64, |x| x as f64);
            t += ROOTS[r] * MARGIN * x;
        }
        libm::scalbn(t, self.anchor) + self.rest()
    }

    /// `S` after a move that kept `x`, `lo`, `end` and `top` right.
    #[inline]
    fn settle(&mut self) {
        if self.exact {
            self.s = self.exact_sum();
        } else {
            self.resum();
        }
    }

    /// The last occupied class (the class at rest when no moving one is).
    #[inline]
    fn last_class(&self) -> usize {
        if self.lo < self.end { self.end - 1 } else { 0 }
    }

    /// `n_0 W_{Q_MIN}`.
    #[inline]
    fn rest(&self) -> f64 {
        self.classes.first().map_or(0.0, |c| c.v.len() as f64 * c.w)
    }

    /// Recomputes everything from the classes (a function of their contents only).
    fn resum(&mut self) {
        let moving = || {
            self.classes
                .iter()
                .enumerate()
                .skip(1)
                .filter(|(_, c)| !c.v.is_empty())
        };
        let still = self.classes.first().map_or(0, |c| c.v.len());
        let (lo, end) = match (moving().next(), moving().next_back()) {
            (Some((lo, _)), Some((hi, _))) => (lo, hi + 1),
            _ => (1, 1),
        };
        let anchor = if lo < end {
            class_parts(self.q(lo)).0
        } else {
            0
        };
        let (mut n, mut x, mut exact) = (still, [0u128; 4], true);
        for (d, c) in moving() {
            n += c.v.len();
            let (h, r) = class_parts(self.q(d));
            let add = 1u128
                .checked_shl((h - anchor) as u32)
                .and_then(|p| p.checked_mul(c.v.len() as u128))
                .and_then(|p| p.checked_add(x[r]));
            match add {
                Some(v) => x[r] = v,
                None => exact = false,
            }
        }
        (self.n, self.lo, self.end) = (n, lo, end);
        (self.exact, self.anchor, self.x) = (exact, anchor, x);
        self.top = if n > 0 {
            self.classes[self.last_class()].w
        } else {
            0.0
        };
        self.s = if n == 0 {
            0.0
        } else if exact {
            self.exact_sum()
        } else {
            let moving: f64 = self.classes[lo..end]
                .iter()
                .map(|c| c.v.len() as f64 * c.w)
                .sum();
            moving + self.rest()
        };
    }

    /// Reserves room for one more particle in each class of `qs` (room for two where a
    /// class is listed once: both particles of a bounce may go to one class), the range
    /// of moving classes rebuilt around them if needed. Errors: the memory, or moving
    /// classes spanning more than [`MAX_CLASSES`].
    fn reserve(&mut self, qs: &[i32]) -> Result<()> {
        if self.classes.is_empty() {
            try_reserve(&mut self.classes, 1)?;
            self.classes.push(Class::new(Q_MIN));
            (self.lo, self.end) = (1, 1);
        }
        // (checked whatever the range: the refusal depends on the particles alone, so
        // a state that was reached also loads, in any order)
        let (first, last) = self.moving_span(qs);
        if first <= last && (last - first) as usize >= MAX_CLASSES {
            return Err(Error::Capacity {
                name: "speed classes of one size (speeds within a factor 2^128)",
                capacity: MAX_CLASSES,
            });
        }
        if qs.iter().any(|&q| self.index(q).is_none()) {
            self.make_room(qs)?;
        }
        for &q in qs {
            if let Some(d) = self.index(q) {
                try_reserve(&mut self.classes[d].v, 2)?;
            }
        }
        Ok(())
    }

    /// Rebuilds the moving classes' range to span the occupied ones and `qs` (a few
    /// more below: speeds of a cooling gas keep falling); the empty classes outside
    /// are dropped. Nothing a sum depends on changes.
    #[cold]
    fn make_room(&mut self, qs: &[i32]) -> Result<()> {
        let (first, last) = self.moving_span(qs);
        if first > last {
            return Ok(());
        }
        let from = first.saturating_sub(4).max(Q_MIN + 1);
        let mut classes = Vec::new();
        try_reserve(&mut classes, (last - from) as usize + 2)?;
        classes.push(core::mem::replace(&mut self.classes[0], Class::new(Q_MIN)));
        for q in from..=last {
            let kept = self.index(q).filter(|&d| d > 0);
            classes.push(match kept {
                Some(d) => core::mem::replace(&mut self.classes[d], Class::new(q)),
                None => Class::new(q),
            });
        }
        (self.classes, self.base) = (classes, from);
        // (the same contents: lo and end shift, the sums come out the same)
        self.resum();
        Ok(())
    }

    /// The lowest and highest of the occupied moving classes and the moving classes of
    /// `qs` (`first > last` when there are none).
    fn moving_span(&self, qs: &[i32]) -> (i32, i32) {
        let (mut first, mut last) = if self.lo < self.end {
            (self.q(self.lo), self.q(self.end - 1))
        } else {
            (i32::MAX, i32::MIN)
        };
        for &q in qs.iter().filter(|&&q| q != Q_MIN) {
            (first, last) = (first.min(q), last.max(q));
        }
        (first, last)
    }

    /// Adds a particle (room reserved by `reserve`).
    fn insert(&mut self, v: [f64; 3]) {
        let q = class_of(&v);
        let d = self.index(q).expect("class reserved");
        self.classes[d].v.push(v);
        self.n += 1;
        if d == 0 {
            // (at rest: the moving classes' sums stand)
            if self.lo == self.end {
                self.top = self.classes[0].w;
            }
            self.settle();
            return;
        }
        let (h, r) = class_parts(q);
        if self.lo == self.end {
            // the first moving particle
            (self.lo, self.end, self.top) = (d, d + 1, self.classes[d].w);
            (self.exact, self.anchor, self.x) = (true, h, [0; 4]);
            self.x[r] = 1;
            self.s = self.exact_sum();
            return;
        }
        self.lo = self.lo.min(d);
        if d >= self.end {
            (self.end, self.top) = (d + 1, self.classes[d].w);
        }
        if self.exact && !self.add_exact(h, r) {
            // (past 128 bits: the fallback)
            self.exact = false;
        }
        self.settle();
    }

    /// Adds `2^h` to `X_r` (moving the anchor down if needed); false on overflow.
    fn add_exact(&mut self, h: i32, r: usize) -> bool {
        if h < self.anchor {
            let shift = (self.anchor - h) as u32;
            if self
                .x
                .iter()
                .any(|&x| x != 0 && (shift >= 128 || x.leading_zeros() < shift))
            {
                return false;
            }
            for x in &mut self.x {
                *x = x.checked_shl(shift).unwrap_or(0);
            }
            self.anchor = h;
        }
        match 1u128
            .checked_shl((h - self.anchor) as u32)
            .and_then(|p| p.checked_add(self.x[r]))
        {
            Some(v) => {
                self.x[r] = v;
                true
            }
            None => false,
        }
    }

    /// Removes the particle at `idx` of class index `d` (swapping the last in).
    fn remove(&mut self, d: usize, idx: usize) {
        self.classes[d].v.swap_remove(idx);
        self.n -= 1;
        if d == 0 {
            if self.n == 0 {
                self.resum();
            } else {
                self.settle();
            }
            return;
        }
        if self.exact {
            let (h, r) = class_parts(self.q(d));
            self.x[r] -= 1u128 << (h - self.anchor);
        }
        if self.classes[d].v.is_empty() {
            if d + 1 == self.end {
                self.end = (self.lo..d)
                    .rev()
                    .find(|&e| !self.classes[e].v.is_empty())
                    .map_or(self.lo, |e| e + 1);
            }
            if d == self.lo {
                self.lo = (d + 1..self.end)
                    .find(|&e| !self.classes[e].v.is_empty())
                    .unwrap_or(self.end);
            }
            if self.lo == self.end {
                // no moving particle left
                self.resum();
                return;
            }
            self.top = self.classes[self.end - 1].w;
            let h = class_parts(self.q(self.lo)).0;
            if self.exact && h > self.anchor {
                // (exact: nothing is left below the new lowest class)
                let shift = (h - self.anchor) as u32;
                for x in &mut self.x {
                    *x = x.checked_shr(shift).unwrap_or(0);
                }
                self.anchor = h;
            }
        }
        self.settle();
    }

    /// The particle at `global` in the order of the classes (those at rest first).
    #[inline]
    fn locate(&self, mut global: usize) -> (usize, usize) {
        let still = self.classes[0].v.len();
        if global < still {
            return (0, global);
        }
        global -= still;
        for d in self.lo..self.end {
            let len = self.classes[d].v.len();
            if global < len {
                return (d, global);
            }
            global -= len;
        }
        // (past the end: the last particle)
        let last = self.last_class();
        (last, self.classes[last].v.len().saturating_sub(1))
    }

    /// The global index of particle `(d, idx)`.
    fn global(&self, d: usize, idx: usize) -> usize {
        if d == 0 {
            return idx;
        }
        self.classes[0].v.len()
            + self.classes[self.lo..d]
                .iter()
                .map(|c| c.v.len())
                .sum::<usize>()
            + idx
    }

    /// A particle drawn ∝ its class bound, from `t ∈ [0, S)`.
    #[inline]
    fn weighted(&self, mut t: f64) -> (usize, usize) {
        let still = &self.classes[0];
        let weight = still.v.len() as f64 * still.w;
        if t < weight {
            let idx = (t / still.w) as usize;
            return (0, idx.min(still.v.len() - 1));
        }
        t -= weight;
        for d in self.lo..self.end {
            let c = &self.classes[d];
            let weight = c.v.len() as f64 * c.w;
            if t < weight {
                let idx = (t / c.w) as usize;
                return (d, idx.min(c.v.len() - 1));
            }
            t -= weight;
        }
        // (rounding past the last class)
        let last = self.last_class();
        (last, self.classes[last].v.len().saturating_sub(1))
    }
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
                return Err(Error::InvalidRate {
                    name: "particle velocity (|v|² must be finite)",
                    value: vel.iter().fold(0.0f64, |a, c| a.max(c.abs())),
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

/// A particle: size, class, index in the class.
type At = (u64, i32, usize);

/// What an accepted collision changes, from `plan` to `commit`.
#[derive(Clone, Copy, Debug, Default)]
enum Pending {
    #[default]
    None,
    /// The two particles leave with these velocities.
    Bounce {
        k: At,
        vk: [f64; 3],
        l: At,
        vl: [f64; 3],
    },
    /// The two particles become one of size `size` with velocity `v`.
    Merge {
        k: At,
        l: At,
        size: u64,
        v: [f64; 3],
    },
}

/// The DSMC collision rule (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Collisions {
    /// The accepted pair (class index, index in the class), its direction and
    /// `(V_k − V_l)·e`.
    k: (usize, usize),
    l: (usize, usize),
    e: [f64; 3],
    gn: f64,
    pending: Pending,
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

impl<S> Gas<S> {
    /// Removes the particle at `at`.
    fn remove(&mut self, (size, q, idx): At) {
        let sp = &mut self.species[size as usize - 1];
        let d = sp.index(q).expect("a particle's class");
        sp.remove(d, idx);
    }

    /// Removes particles `ats` (the later index first where two share a class).
    fn remove_both(&mut self, mut ats: [At; 2]) {
        if ats[0] < ats[1] {
            ats.swap(0, 1);
        }
        for at in ats {
            self.remove(at);
        }
    }
}

impl<S: Sticking + Clone> EventRule<Gas<S>> for Collisions {
    const REWEIGHS: bool = true;
    const DOUBLES: bool = false;
    const TAG: Option<u64> = Some(crate::scheme::tag::DSMC);

    fn for_kernel(_kernel: &Gas<S>) -> Self {
        Collisions::default()
    }

    #[inline]
    fn decide<L, G: Rng + ?Sized>(
        &mut self,
        gas: &Gas<S>,
        c: &Candidate<L>,
        bounds: impl FnOnce() -> (f64, f64),
        low_is_bound: bool,
        _spot: bool,
        rng: &mut G,
    ) -> Result<Option<Outcome>> {
        let (x, y) = (c.x, c.y);
        let (sx, sy) = (&gas.species[x as usize - 1], &gas.species[y as usize - 1]);
        if gas.weighted && !low_is_bound {
            return Err(Error::Unsupported {
                what: "a gas weighted for the per-size trees on another engine (use new_gas)",
            });
        }
        // the first particle ∝ its bound (weighted) or uniformly; the second uniformly
        // among the others
        let k = if gas.weighted {
            sx.weighted(sx.s * unit_f64(rng.next_u64()))
        } else {
            sx.locate(below(rng, sx.n as u64) as usize)
        };
        let l = if x == y {
            let r = below(rng, sx.n as u64 - 1) as usize;
            sx.locate(r + usize::from(r >= sx.global(k.0, k.1)))
        } else {
            sy.locate(below(rng, sy.n as u64) as usize)
        };
        let (ck, cl) = (&sx.classes[k.0], &sy.classes[l.0]);
        let (vk, vl) = (ck.v[k.1], cl.v[l.1]);
        let g = [vk[0] - vl[0], vk[1] - vl[1], vk[2] - vl[2]];
        let gabs = norm(&g);
        let uniform = gas.directions == Directions::Uniform;
        // |g| (the rate integrated over e), or |g·e| for a uniform e
        let speed = if uniform {
            let e = direction(rng);
            (self.e, self.gn) = (e, g[0] * e[0] + g[1] * e[1] + g[2] * e[2]);
            self.gn.abs()
        } else {
            gabs
        };
        let (rate, bound) = if gas.weighted {
            (speed, ck.w + cl.w)
        } else {
            // the pair's rate against the engine's bound
            let d = size_cbrt(x) + size_cbrt(y);
            (gas.scale() * d * d * speed, bounds().0)
        };
        if rate.is_nan() || rate > bound * (1.0 + 1e-12) {
            // a speed past its class's bound: an invariant broke
            return Err(Error::BoundExceeded {
                name: "DSMC speed bounds",
                rate,
                bound,
            });
        }
        if rate < bound * open_unit(rng) {
            return Ok(None);
        }
        if !uniform {
            // the direction given the pair: density ∝ |g·e| on the sphere, i.e.
            // cos θ = sqrt(U) from ĝ (the sign of e does not matter), azimuth uniform
            (self.e, self.gn) = oriented(&g, gabs, rng);
        }
        (self.k, self.l) = (k, l);
        let gn = self.gn;
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
        let (e, gn) = (self.e, self.gn);
        let (sx, sy) = (&gas.species[x as usize - 1], &gas.species[y as usize - 1]);
        let vk = sx.classes[self.k.0].v[self.k.1];
        let vl = sy.classes[self.l.0].v[self.l.1];
        // (by class: reserving may move the classes' indices)
        let k = (x, sx.q(self.k.0), self.k.1);
        let l = (y, sy.q(self.l.0), self.l.1);
        let (mx, my) = (x as f64, y as f64);
        self.pending = match *outcome {
            Outcome::Bounce => {
                // momentum along e exchanged, the normal relative velocity times −ε
                let q = (1.0 + gas.restitution) * gn / (mx + my);
                let (mut nk, mut nl) = (vk, vl);
                for d in 0..3 {
                    nk[d] -= q * my * e[d];
                    nl[d] += q * mx * e[d];
                }
                if !(finite_speed(&nk) && finite_speed(&nl)) {
                    return Err(bad_velocity(nk[0] + nl[0]));
                }
                // room in the classes they move to
                let (qk, ql) = (class_of(&nk), class_of(&nl));
                if x == y {
                    gas.species[x as usize - 1].reserve(&[qk, ql])?;
                } else {
                    gas.species[x as usize - 1].reserve(&[qk])?;
                    gas.species[y as usize - 1].reserve(&[ql])?;
                }
                Pending::Bounce {
                    k,
                    vk: nk,
                    l,
                    vl: nl,
                }
            }
            Outcome::Merge { size } => {
                let mut v = [0.0; 3];
                for d in 0..3 {
                    v[d] = (mx * vk[d] + my * vl[d]) / (mx + my);
                }
                if !finite_speed(&v) {
                    return Err(bad_velocity(v[0]));
                }
                let idx = usize::try_from(size - 1).map_err(|_| Error::Capacity {
                    name: "particle size",
                    capacity: usize::MAX,
                })?;
                if idx >= gas.species.len() {
                    let more = idx + 1 - gas.species.len();
                    try_reserve(&mut gas.species, more)?;
                    gas.species.resize(idx + 1, Species::default());
                }
                gas.species[idx].reserve(&[class_of(&v)])?;
                Pending::Merge { k, l, size, v }
            }
        };
        Ok(())
    }

    fn commit(&mut self, gas: &mut Gas<S>) -> Reweighed {
        let mut touched = Reweighed::new();
        let mut touch = |s: u64| {
            if !touched.contains(&s) {
                let _ = touched.push(s);
            }
        };
        match core::mem::take(&mut self.pending) {
            Pending::None => {}
            Pending::Bounce { k, vk, l, vl } => {
                // a particle that stays in its class is written in place (its size's
                // sums are unchanged); the others leave their classes (the later index
                // first) and join their new ones
                let (stay_k, stay_l) = (k.1 == class_of(&vk), l.1 == class_of(&vl));
                for (at, v, stay) in [(k, vk, stay_k), (l, vl, stay_l)] {
                    if stay {
                        let sp = &mut gas.species[at.0 as usize - 1];
                        let d = sp.index(at.1).expect("a particle's class");
                        sp.classes[d].v[at.2] = v;
                    }
                }
                match (stay_k, stay_l) {
                    (true, true) => {}
                    (false, true) => {
                        gas.remove(k);
                        gas.species[k.0 as usize - 1].insert(vk);
                        touch(k.0);
                    }
                    (true, false) => {
                        gas.remove(l);
                        gas.species[l.0 as usize - 1].insert(vl);
                        touch(l.0);
                    }
                    (false, false) => {
                        gas.remove_both([k, l]);
                        gas.species[k.0 as usize - 1].insert(vk);
                        gas.species[l.0 as usize - 1].insert(vl);
                        touch(k.0);
                        touch(l.0);
                    }
                }
            }
            Pending::Merge { k, l, size, v } => {
                gas.remove_both([k, l]);
                gas.species[size as usize - 1].insert(v);
                touch(k.0);
                touch(l.0);
                touch(size);
            }
        }
        touched
    }

    fn check_counts(gas: &Gas<S>, counts: &[u64]) -> Result<()> {
        let have = gas.species.iter().map(|s| s.n as u64);
        let agree = counts
            .iter()
            .copied()
            .chain(core::iter::repeat(0))
            .zip(have.chain(core::iter::repeat(0)))
            .take(counts.len().max(gas.species.len()))
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
        w.u64(gas.species.len() as u64);
        for sp in &gas.species {
            let occupied = || {
                sp.classes
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| !c.v.is_empty())
            };
            w.u64(occupied().count() as u64);
            for (d, c) in occupied() {
                w.u64(sp.q(d) as i64 as u64);
                w.f64s(&c.v.iter().flatten().copied().collect::<Vec<_>>());
            }
        }
    }

    fn load(&self, gas: &Gas<S>, r: &mut Reader) -> Result<Option<Gas<S>>> {
        let bad = |what| Error::Checkpoint { what };
        let m = r.u64()?;
        let mut species = Vec::new();
        for _ in 0..m {
            let nc = r.u64()?;
            let mut sp = Species::default();
            for _ in 0..nc {
                let q = i32::try_from(r.u64()? as i64).map_err(|_| bad("invalid speed class"))?;
                let flat = r.f64s()?;
                // (older checkpoints: `v = 0` in class i32::MIN and subnormal `|v|²` in
                // classes below Q_MIN, all now in Q_MIN)
                // (Q_MIN, and in older checkpoints i32::MIN and the classes below Q_MIN,
                // may be listed more than once: all are Q_MIN now)
                let low = q == i32::MIN || (-2200..=Q_MIN).contains(&q);
                if flat.len() % 3 != 0 || !(low || (Q_MIN..=2047).contains(&q)) {
                    return Err(bad("invalid speed class"));
                }
                let fits = |x: &[f64; 3]| {
                    finite_speed(x) && (class_of(x) == q || (low && class_of(x) == Q_MIN))
                };
                let v: Vec<[f64; 3]> = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                // (a class listed twice: its particles would be in the order of neither)
                let twice = !low
                    && !v.is_empty()
                    && sp.index(q).is_some_and(|d| !sp.classes[d].v.is_empty());
                if !v.iter().all(fits) || twice {
                    return Err(bad("particle velocities do not match their speed classes"));
                }
                for x in v {
                    sp.reserve(&[class_of(&x)])?;
                    sp.insert(x);
                }
            }
            try_reserve(&mut species, 1)?;
            species.push(sp);
        }
        Ok(Some(Gas {
            restitution: gas.restitution,
            sticking: gas.sticking.clone(),
            species,
            weighted: gas.weighted,
            directions: gas.directions,
        }))
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
        gas.weighted = E::LOW_IS_BOUND;
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
mod tests {
    use super::*;
    use crate::checkpoint::{Reader, Writer};
    use rand_core::SeedableRng;

    /// A velocity of speed about `10^e` in a random direction.
    fn velocity(rng: &mut rand_pcg::Pcg64Mcg, e: f64) -> [f64; 3] {
        let s = libm::pow(10.0, e);
        [s * normal(rng), s * normal(rng), s * normal(rng)]
    }

    /// Checks a species' counts, range, top and sum against its classes.
    fn check(sp: &Species) {
        let n: usize = sp.classes.iter().map(|c| c.v.len()).sum();
        assert_eq!(sp.n, n);
        // the sum kept up to date is the one recomputed from the contents, bit for bit
        let mut again = sp.clone();
        again.resum();
        assert_eq!(sp.s.to_bits(), again.s.to_bits());
        assert_eq!(
            (sp.lo, sp.end, sp.exact, sp.x, sp.top.to_bits()),
            (
                again.lo,
                again.end,
                again.exact,
                again.x,
                again.top.to_bits()
            )
        );
        if n == 0 {
            assert_eq!((sp.s, sp.top), (0.0, 0.0));
            return;
        }
        assert!(sp.classes.len() <= MAX_CLASSES + 6, "{}", sp.classes.len());
        let moving = &sp.classes[1..];
        let (lo, end) = (sp.lo - 1, sp.end - 1);
        assert!(
            moving[..lo]
                .iter()
                .chain(&moving[end..])
                .all(|c| c.v.is_empty())
        );
        if lo < end {
            assert!(!moving[lo].v.is_empty() && !moving[end - 1].v.is_empty());
            assert_eq!(sp.top, moving[end - 1].w);
        } else {
            assert_eq!(sp.top, sp.classes[0].w);
        }
        let naive: f64 = sp.classes.iter().map(|c| c.v.len() as f64 * c.w).sum();
        assert!((sp.s - naive).abs() <= 1e-12 * naive, "{} vs {naive}", sp.s);
        for (d, c) in sp.classes.iter().enumerate() {
            let q = sp.q(d);
            assert_eq!(sp.index(q), Some(d));
            assert_eq!(c.w, class_bound(q));
            for v in &c.v {
                assert_eq!(class_of(v), q);
                assert!(norm(v) < c.w);
            }
        }
    }

    /// Random inserts and removals, speeds about `10^{center ± spread/2}`, checked after
    /// each.
    fn moves(
        sp: &mut Species,
        (center, spread): (f64, f64),
        steps: usize,
        rng: &mut rand_pcg::Pcg64Mcg,
    ) {
        for step in 0..steps {
            let remove = sp.n > 0 && (step % 3 == 2 || unit_f64(rng.next_u64()) < 0.3);
            if remove {
                let (d, idx) = sp.locate(below(rng, sp.n as u64) as usize);
                sp.remove(d, idx);
            } else {
                let v = match step % 50 {
                    7 => [0.0; 3],
                    // (|v|² = 2e-320, subnormal)
                    8 => [1e-160, 0.0, -1e-160],
                    _ => {
                        let e = center + spread * (unit_f64(rng.next_u64()) - 0.5);
                        velocity(rng, e)
                    }
                };
                sp.reserve(&[class_of(&v)]).unwrap();
                sp.insert(v);
            }
            check(sp);
        }
    }

    #[test]
    fn class_sums_follow_every_move() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        // speeds over a few octaves and over 2^110 (sums past 128 bits at times), with
        // particles at rest (zero and subnormal |v|²) among them
        for spread in [2.0, 33.0] {
            let mut sp = Species::default();
            moves(&mut sp, (0.0, spread), 4000, &mut rng);
            // (the exact sums are the common case: at rest or not)
            if spread == 2.0 {
                assert!(sp.exact);
            }
        }
    }

    #[test]
    fn sums_fall_back_and_come_back() {
        let mut sp = Species::default();
        for _ in 0..4 {
            let v = [1.0, 0.0, 0.0];
            sp.reserve(&[class_of(&v)]).unwrap();
            sp.insert(v);
        }
        // at rest: still exact
        sp.reserve(&[Q_MIN]).unwrap();
        sp.insert([0.0; 3]);
        check(&sp);
        assert!(sp.exact);
        // 2^{-126} next to four at 1: X_0 would be 4 · 2^126
        let slow = [libm::scalbn(1.0, -126), 0.0, 0.0];
        sp.reserve(&[class_of(&slow)]).unwrap();
        sp.insert(slow);
        check(&sp);
        assert!(!sp.exact);
        let d = sp.index(class_of(&slow)).unwrap();
        sp.remove(d, 0);
        check(&sp);
        assert!(sp.exact);
        // speeds 2^128 apart are refused, and the species is as it was
        let before = sp.clone();
        let far = [libm::scalbn(1.0, -129), 0.0, 0.0];
        assert!(matches!(
            sp.reserve(&[class_of(&far)]),
            Err(Error::Capacity { .. })
        ));
        check(&sp);
        assert_eq!((sp.n, sp.s.to_bits()), (before.n, before.s.to_bits()));
    }

    /// The refusal of speeds 2^128 apart does not depend on the order the particles come
    /// in (classes 0 and −511 are 511 apart; −514, inside the padding a rebuild leaves
    /// below −511, is 514 from 0), and a bounce's two classes are reserved together.
    #[test]
    fn refusals_do_not_depend_on_order() {
        let at = |q: i32| [libm::sqrt(libm::exp2(f64::from(q) / 2.0 + 0.1)), 0.0, 0.0];
        for order in [[0, -511, -514], [-514, -511, 0], [-511, -514, 0]] {
            let mut sp = Species::default();
            let mut got = Vec::new();
            for q in order {
                assert_eq!(class_of(&at(q)), q);
                let r = sp.reserve(&[q]);
                if r.is_ok() {
                    sp.insert(at(q));
                }
                got.push(r.is_ok());
                check(&sp);
            }
            // whichever came first of 0 and −514, the other is refused; −511 fits
            let refused = got.iter().filter(|ok| !**ok).count();
            assert_eq!(refused, 1, "{order:?}: {got:?}");
        }
        // two classes at once, both outside the range: one rebuild holds both
        let mut sp = Species::default();
        sp.reserve(&[0]).unwrap();
        sp.insert(at(0));
        sp.reserve(&[-40, 60]).unwrap();
        sp.insert(at(-40));
        sp.insert(at(60));
        check(&sp);
        assert_eq!(sp.n, 3);
    }

    /// A size whose speeds drift down (a cooling gas) keeps a bounded range of classes:
    /// the empty ones above are dropped when the range is rebuilt.
    #[test]
    fn the_range_follows_the_speeds() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let mut sp = Species::default();
        for k in 0..60 {
            // speeds around 10^{-k}: the range would span 800 classes if never trimmed
            moves(&mut sp, (-f64::from(k), 1.0), 60, &mut rng);
            // (a few stay: the range moves down with particles in it all along)
            while sp.n > 3 {
                let (d, idx) = sp.locate(below(&mut rng, sp.n as u64) as usize);
                sp.remove(d, idx);
                check(&sp);
            }
        }
    }

    #[test]
    fn an_older_checkpoint_with_zero_speeds_loads() {
        // the format before the dense classes: v = 0 in class i32::MIN, classes in
        // the order they were made
        let mut buf = alloc::vec![0u8; 1024];
        let mut w = Writer::new(&mut buf);
        w.u64(1);
        w.u64(4);
        w.u64(class_of(&[2.0, 0.0, 0.0]) as i64 as u64);
        w.f64s(&[2.0, 0.0, 0.0]);
        w.u64(i32::MIN as i64 as u64);
        w.f64s(&[0.0; 6]);
        w.u64(class_of(&[0.5, 0.0, 0.0]) as i64 as u64);
        w.f64s(&[]);
        // |v|² = 2^{−1022.2} (subnormal): the old layout's class −2045, which is Q_MIN's
        // number
        let tiny = libm::sqrt(libm::exp2(-1022.2));
        w.u64(-2045i64 as u64);
        w.f64s(&[tiny, 0.0, 0.0]);
        let len = w.needed();
        let gas = Gas::from_particles(0.9, NeverStick, &[1], &[[1.0, 0.0, 0.0]]).unwrap();
        let mut r = Reader::new(&buf[..len]);
        let back = Collisions::default().load(&gas, &mut r).unwrap().unwrap();
        assert_eq!(back.counts(), alloc::vec![4]);
        let sp = &back.species[0];
        check(sp);
        assert_eq!(sp.classes[sp.index(Q_MIN).unwrap()].v.len(), 3);
        // a class listed twice is refused
        let mut buf = alloc::vec![0u8; 1024];
        let mut w = Writer::new(&mut buf);
        w.u64(1);
        w.u64(2);
        for _ in 0..2 {
            w.u64(class_of(&[2.0, 0.0, 0.0]) as i64 as u64);
            w.f64s(&[2.0, 0.0, 0.0]);
        }
        let len = w.needed();
        let mut r = Reader::new(&buf[..len]);
        assert!(matches!(
            Collisions::default().load(&gas, &mut r),
            Err(Error::Checkpoint { .. })
        ));
    }
}
