//! Langevin particle tracking with specular or absorbing walls (Maftei, Bossy & Jabir
//! 2016; SPEC §7): batches of independent trajectories of
//! `dX = U dt, dU = b(t, X, U) dt + σ dW` kept out of an excluded region, with the
//! paper's discretisation, statistics over the batch, Richardson–Romberg extrapolation
//! and collision kernels estimated from first hits ([`kernel`]).
//!
//! Geometry:
//! * `D = 1` — the half-line `x ≥ 0` with a wall at 0 ([`Config::line`]); options: a
//!   periodic border at `x = L` and a bound on the velocity (the paper's test problem
//!   has both, see [`paper`]);
//! * `D ≥ 2` — the outside of the ball `|x| ≤ δ` ([`Config::ball`]): the free path's
//!   first intersection with the sphere gives the collision time θ and normal n.
//!
//! One step of length h from `(t, x, u)` (SPEC §7): the free position `x + h u`; if
//! the straight path hits the wall at `θ = t + s` (`0 ≤ s < h`), the velocity diffuses
//! to θ, `U_θ− = u + b(t, x, u) s + σ √s Z⁻`; a specular wall reflects it,
//! `U_θ = U_θ− − 2 (U_θ−·n) n`, mirrors the free position in the tangent plane, and
//! diffuses on to the end of the step, `U_θ + b(θ, X_θ, U_θ)(h − s) + σ √(h − s) Z⁺`;
//! an absorbing wall stops the trajectory at `(X_θ, U_θ−)`. Without a hit,
//! `u + b(t, x, u) h + σ √h Z`. A velocity bound, when set, applies to `U_θ−` as well.
//! One choice beyond the paper: a trajectory standing on the wall (`x = 0`) and moving
//! into it hits at `θ = t_i`; the paper's strict `t_i < θ` would mirror its position
//! without flipping its velocity. The bias in `E f(X_T, U_T)` is `C h + O(h²)`
//! (the paper's conjecture 33), so [`richardson_romberg`] of the runs at h and h/2
//! is `O(h²)`.
//!
//! Randomness: every trajectory has its own generator, the seed policy's
//! [`generator`](crate::random::generator)`(key, id)` for its id `first_id + i`, with
//! the key drawn from the caller's RNG when the batch is built. So a trajectory's path
//! depends on nothing but the key and its id: the same for any split of the batch
//! across threads or ranks, any order of stepping, any split of `advance_to` calls at
//! points of the time grid, and a checkpoint.
//!
//! Time grid: steps end at the multiples of `dt`; a target between two grid points
//! ends a shortened step there (the next step goes on to the grid).
//!
//! ```
//! use coagula_core::langevin::{Batch, Config, Scalar, Wall};
//! use coagula_core::scheme::Scheme;
//! use rand_pcg::Pcg64Mcg;
//! // free Brownian velocity (b = 0, σ = 1) next to a specular wall at 0
//! let cfg = Config::line(0.01, 1.0, Wall::Specular).unwrap();
//! let mut rng = Pcg64Mcg::new(7);
//! let mut batch = Batch::new(cfg, Scalar(|_t, _x, _u| 0.0), 10_000, ([0.5], [-1.0]), &mut rng).unwrap();
//! batch.advance_to(1.0, &mut rng).unwrap();
//! // reflection is an isometry: E U_T² = u0² + σ² T exactly
//! let u2 = batch.statistics(|_x, u| u[0] * u[0]);
//! assert!((u2.mean() - 2.0).abs() < 5.0 * u2.std_error());
//! assert!(batch.positions().all(|x| x[0] >= 0.0));
//! ```

pub mod kernel;
pub mod paper;

use crate::error::{Error, Result, finite};
use crate::observe::Replicas;
use crate::random::{Generator, NormalZiggurat, Xoshiro256PlusPlus};
use crate::scheme::{Budget, Scheme, StepReport, check_target};
use alloc::vec::Vec;
use rand_core::Rng;

/// The velocity drift `b(t, x, u)` of a `D`-dimensional Langevin model.
pub trait Drift<const D: usize> {
    /// The drift at time `t`, position `x`, velocity `u`.
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D];
}

impl<const D: usize, T: Drift<D> + ?Sized> Drift<D> for &T {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        (**self).drift(t, x, u)
    }
}

/// A one-dimensional drift from a closure `|t, x, u| b`.
#[derive(Clone, Copy, Debug)]
pub struct Scalar<F>(pub F);

impl<F: Fn(f64, f64, f64) -> f64> Drift<1> for Scalar<F> {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; 1], u: &[f64; 1]) -> [f64; 1] {
        [(self.0)(t, x[0], u[0])]
    }
}

/// A `D`-dimensional drift from a closure `|t, &x, &u| b`.
#[derive(Clone, Copy, Debug)]
pub struct Field<F>(pub F);

impl<const D: usize, F: Fn(f64, &[f64; D], &[f64; D]) -> [f64; D]> Drift<D> for Field<F> {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        (self.0)(t, x, u)
    }
}

/// Linear friction `b = −u / τ`: the velocity is an Ornstein–Uhlenbeck process and, with
/// `σ = √(2 D) / τ`, the position a Brownian motion of diffusivity D at times ≫ τ
/// (the Brownian limit of [`kernel`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// The relaxation rate `1/τ`.
    pub rate: f64,
}

impl<const D: usize> Drift<D> for Friction {
    #[inline(always)]
    fn drift(&self, _t: f64, _x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        core::array::from_fn(|k| -self.rate * u[k])
    }
}

/// Relaxation towards a simple shear flow, `b = −(u − (γ̇ x₂, 0, …)) / τ`: the relative
/// motion of two particles of relaxation time τ in the flow `u_f = (γ̇ y, 0, 0)`
/// (`D ≥ 2`; in one dimension it is [`Friction`]). With `σ = 0` and τ → 0 the first-hit
/// kernel tends to Smoluchowski's orthokinetic `(4/3) γ̇ R³` (3-D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shear {
    /// The relaxation rate `1/τ`.
    pub rate: f64,
    /// The shear rate γ̇.
    pub shear: f64,
}

impl<const D: usize> Drift<D> for Shear {
    #[inline(always)]
    fn drift(&self, _t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        core::array::from_fn(|k| {
            let fluid = if k == 0 && D > 1 {
                self.shear * x[1]
            } else {
                0.0
            };
            -self.rate * (u[k] - fluid)
        })
    }
}

/// What the wall does to a trajectory that reaches it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wall {
    /// Specular reflection (elastic collision of the two particles).
    Specular,
    /// Absorption (agglomeration): the trajectory stops at its first hit.
    Absorbing,
}

/// What happens to a velocity past the bound `v` (`D = 1`, or each component for
/// `D ≥ 2`). The paper cuts its velocities at ±10 without saying how; [`paper`]
/// measures the choices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VelocityBound {
    /// No bound.
    None,
    /// `u ↦ ±v` past the bound.
    Clamp(f64),
    /// Reflection at the bound: `u ↦ 2v − u` (`−2v − u` below `−v`).
    Reflect(f64),
}

/// The parameters of a batch: step, noise, wall, geometry and options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config<const D: usize> {
    dt: f64,
    sigma: f64,
    wall: Wall,
    radius: f64,
    period: Option<f64>,
    bound: VelocityBound,
}

fn positive(name: &'static str, v: f64) -> Result<f64> {
    finite(name, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(Error::OutOfRange {
            name,
            value: v,
            range: "(0, inf)",
        })
    }
}

fn check_dt_sigma(dt: f64, sigma: f64) -> Result<()> {
    positive("dt", dt)?;
    finite("sigma", sigma)?;
    if sigma < 0.0 {
        return Err(Error::OutOfRange {
            name: "sigma",
            value: sigma,
            range: "[0, inf)",
        });
    }
    Ok(())
}

impl Config<1> {
    /// The half-line `x ≥ 0` with a wall at 0, step `dt > 0`, noise `σ ≥ 0`.
    pub fn line(dt: f64, sigma: f64, wall: Wall) -> Result<Self> {
        Self::half_line(dt, sigma, wall)
    }
}

impl<const D: usize> Config<D> {
    /// [`Config::line`] for a dimension given as a parameter: an error unless `D = 1`.
    pub fn half_line(dt: f64, sigma: f64, wall: Wall) -> Result<Self> {
        if D != 1 {
            return Err(Error::Unsupported {
                what: "a half-line in more than one dimension (use Config::ball)",
            });
        }
        check_dt_sigma(dt, sigma)?;
        Ok(Config {
            dt,
            sigma,
            wall,
            radius: 0.0,
            period: None,
            bound: VelocityBound::None,
        })
    }

    /// A periodic border at `x = L > 0` (one dimension): a position past it moves back
    /// by multiples of L (the paper's "periodic border at x = 1").
    pub fn with_period(mut self, length: f64) -> Result<Self> {
        if D != 1 {
            return Err(Error::Unsupported {
                what: "a periodic border in more than one dimension",
            });
        }
        self.period = Some(positive("period", length)?);
        Ok(self)
    }
}

impl<const D: usize> Config<D> {
    /// The outside of the ball `|x| ≤ δ` (`δ > 0`) in `D ≥ 2` dimensions, step `dt > 0`,
    /// noise `σ ≥ 0`.
    pub fn ball(radius: f64, dt: f64, sigma: f64, wall: Wall) -> Result<Self> {
        if D < 2 {
            return Err(Error::Unsupported {
                what: "a ball in one dimension (use Config::line)",
            });
        }
        if D > 3 {
            return Err(Error::Dimension {
                requested: D,
                max: 3,
            });
        }
        positive("radius", radius)?;
        check_dt_sigma(dt, sigma)?;
        Ok(Config {
            dt,
            sigma,
            wall,
            radius,
            period: None,
            bound: VelocityBound::None,
        })
    }

    /// A bound on the velocity (each component).
    pub fn with_velocity_bound(mut self, bound: VelocityBound) -> Result<Self> {
        if let VelocityBound::Clamp(v) | VelocityBound::Reflect(v) = bound {
            positive("velocity bound", v)?;
        }
        self.bound = bound;
        Ok(self)
    }

    /// The time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The noise amplitude σ.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The wall.
    pub fn wall(&self) -> Wall {
        self.wall
    }

    /// The excluded ball's radius δ (0 for the half-line).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The periodic border, if any.
    pub fn period(&self) -> Option<f64> {
        self.period
    }

    /// The velocity bound.
    pub fn velocity_bound(&self) -> VelocityBound {
        self.bound
    }

    /// Checks that `(x, u)` is an admissible start: finite, and outside the wall
    /// (`x ≥ 0`, `x < L` with a period; `|x| ≥ δ` for a ball).
    pub fn check_start(&self, x: &[f64; D], u: &[f64; D]) -> Result<()> {
        for k in 0..D {
            finite("start position", x[k])?;
            finite("start velocity", u[k])?;
        }
        if D == 1 {
            let range = if self.period.is_some() {
                "[0, period)"
            } else {
                "[0, inf)"
            };
            if x[0] < 0.0 || self.period.is_some_and(|l| x[0] >= l) {
                return Err(Error::OutOfRange {
                    name: "start position",
                    value: x[0],
                    range,
                });
            }
        } else {
            let r = libm::sqrt(dot(x, x));
            if r < self.radius {
                return Err(Error::OutOfRange {
                    name: "start position |x| (inside the excluded ball)",
                    value: r,
                    range: "[radius, inf)",
                });
            }
        }
        if let VelocityBound::Clamp(v) | VelocityBound::Reflect(v) = self.bound
            && u.iter().any(|c| c.abs() > v)
        {
            return Err(Error::OutOfRange {
                name: "start velocity (beyond the velocity bound)",
                value: u.iter().fold(0.0, |m: f64, c| m.max(c.abs())),
                range: "[-bound, bound]",
            });
        }
        Ok(())
    }
}

#[inline(always)]
fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    let mut s = 0.0;
    for k in 0..D {
        s += a[k] * b[k];
    }
    s
}

/// Words of one trajectory's record: position, velocity, generator, hits, first hit.
pub const fn record_words(d: usize) -> usize {
    2 * d + 6
}

/// `u64` words of workspace a batch of `n` trajectories in `D` dimensions needs: the
/// records and a copy of each, which an error restores; `None` on overflow.
pub const fn workspace_len(d: usize, n: usize) -> Option<usize> {
    match n.checked_mul(record_words(d)) {
        Some(w) => w.checked_mul(2),
        None => None,
    }
}

/// Offsets inside a record.
struct Layout<const D: usize>;

impl<const D: usize> Layout<D> {
    const W: usize = record_words(D);
    const RNG: usize = 2 * D;
    const HITS: usize = 2 * D + 4;
    const FIRST: usize = 2 * D + 5;
}

/// One trajectory, unpacked from its record for stepping.
struct Traj<const D: usize> {
    x: [f64; D],
    u: [f64; D],
    rng: Generator,
    hits: u64,
    first: f64,
}

impl<const D: usize> Traj<D> {
    #[inline(always)]
    fn load(rec: &[u64]) -> Self {
        let x = core::array::from_fn(|k| f64::from_bits(rec[k]));
        let u = core::array::from_fn(|k| f64::from_bits(rec[D + k]));
        let s = [
            rec[Layout::<D>::RNG],
            rec[Layout::<D>::RNG + 1],
            rec[Layout::<D>::RNG + 2],
            rec[Layout::<D>::RNG + 3],
        ];
        Traj {
            x,
            u,
            rng: Xoshiro256PlusPlus::from_parts_unchecked(s),
            hits: rec[Layout::<D>::HITS],
            first: f64::from_bits(rec[Layout::<D>::FIRST]),
        }
    }

    #[inline(always)]
    fn store(&self, rec: &mut [u64]) {
        for k in 0..D {
            rec[k] = self.x[k].to_bits();
            rec[D + k] = self.u[k].to_bits();
        }
        let s = self.rng.parts();
        rec[Layout::<D>::RNG..Layout::<D>::RNG + 4].copy_from_slice(&s);
        rec[Layout::<D>::HITS] = self.hits;
        rec[Layout::<D>::FIRST] = self.first.to_bits();
    }

    /// Absorbed (stopped at the wall).
    #[inline(always)]
    fn stopped(&self, wall: Wall) -> bool {
        wall == Wall::Absorbing && self.hits > 0
    }
}

/// Trajectories stepped side by side when a call has no budget.
const LANES: usize = 8;

/// Largest grid index `t / dt`: below 2^52 an `f64` index counts exactly, so every step
/// moves the clock forward.
const MAX_STEP_INDEX: f64 = 4_503_599_627_370_496.0;

/// What one step did.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Hit {
    None,
    Bounce,
    Absorbed,
}

/// A batch of independent trajectories in storage `B` (an owned `Vec<u64>`, or the
/// caller's memory through [`Batch::with_starts_in`]). It implements [`Scheme`]: the budget
/// counts trajectory-steps.
pub struct Batch<const D: usize, Dr, B = Vec<u64>> {
    cfg: Config<D>,
    drift: Dr,
    ws: B,
    n: usize,
    key: u64,
    first_id: u64,
    time: f64,
    totals: StepReport,
}

impl<const D: usize, Dr> core::fmt::Debug for Batch<D, Dr, Vec<u64>> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Batch")
            .field("dim", &D)
            .field("cfg", &self.cfg)
            .field("trajectories", &self.n)
            .field("time", &self.time)
            .finish()
    }
}

impl<const D: usize, Dr: Drift<D>> Batch<D, Dr, Vec<u64>> {
    /// `n ≥ 1` trajectories from `start = (x0, u0)`, in a workspace it allocates once
    /// ([`workspace_len`]); the generators' key is drawn from `rng`, the ids are `0..n`.
    pub fn new<R: Rng + ?Sized>(
        cfg: Config<D>,
        drift: Dr,
        n: usize,
        start: ([f64; D], [f64; D]),
        rng: &mut R,
    ) -> Result<Self> {
        Self::with_starts(cfg, drift, n, rng.next_u64(), 0, |_| start)
    }

    /// `n ≥ 1` trajectories, trajectory `i` with id `first_id + i` starting from
    /// `start(i)`, the generators keyed by `key`: a slice of a larger ensemble (a
    /// thread's or a rank's share gives the same paths as the whole).
    pub fn with_starts(
        cfg: Config<D>,
        drift: Dr,
        n: usize,
        key: u64,
        first_id: u64,
        start: impl FnMut(usize) -> ([f64; D], [f64; D]),
    ) -> Result<Self> {
        let len = workspace_len(D, n).ok_or(Error::Overflow {
            name: "Langevin workspace",
        })?;
        let mut ws = Vec::new();
        ws.try_reserve_exact(len).map_err(|_| Error::Capacity {
            name: "memory for the Langevin workspace (u64 words)",
            capacity: len,
        })?;
        ws.resize(len, 0);
        Batch::with_starts_in(cfg, drift, n, key, first_id, start, ws)
    }
}

impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> Batch<D, Dr, B> {
    /// [`with_starts`](Batch::with_starts) in storage the caller owns: `ws` holds at
    /// least [`workspace_len`]`(D, n)` words (overwritten; any excess is left alone).
    ///
    /// ```
    /// use coagula_core::langevin::{workspace_len, Batch, Config, Friction, Wall};
    /// let cfg = Config::<3>::ball(1.0, 0.01, 1.0, Wall::Absorbing).unwrap();
    /// let mut ws = vec![0u64; workspace_len(3, 100).unwrap()]; // the caller's memory
    /// let b = Batch::with_starts_in(cfg, Friction { rate: 1.0 }, 100, 42, 0,
    ///     |i| ([2.0 + i as f64, 0.0, 0.0], [-1.0, 0.0, 0.0]), &mut ws[..]).unwrap();
    /// assert_eq!(b.len(), 100);
    /// ```
    pub fn with_starts_in(
        cfg: Config<D>,
        drift: Dr,
        n: usize,
        key: u64,
        first_id: u64,
        mut start: impl FnMut(usize) -> ([f64; D], [f64; D]),
        mut ws: B,
    ) -> Result<Self> {
        if n == 0 {
            return Err(Error::Empty);
        }
        if D == 0 || D > 3 {
            return Err(Error::Dimension {
                requested: D,
                max: 3,
            });
        }
        if D == 1 && cfg.radius != 0.0 {
            return Err(Error::Unsupported {
                what: "a ball in one dimension",
            });
        }
        first_id.checked_add(n as u64 - 1).ok_or(Error::Overflow {
            name: "trajectory id",
        })?;
        let need = workspace_len(D, n).ok_or(Error::Overflow {
            name: "Langevin workspace",
        })?;
        let got = ws.as_ref().len();
        if got < need {
            return Err(Error::BufferLength {
                name: "Langevin workspace (u64 words)",
                expected: need,
                got,
            });
        }
        let w = Layout::<D>::W;
        // every start is checked before the workspace is written
        for i in 0..n {
            let (x, u) = start(i);
            cfg.check_start(&x, &u)?;
        }
        let recs = &mut ws.as_mut()[..need];
        for i in 0..n {
            let (x, u) = start(i);
            let t = Traj {
                x,
                u,
                rng: crate::random::generator(key, first_id + i as u64),
                hits: 0,
                first: f64::INFINITY,
            };
            t.store(&mut recs[i * w..(i + 1) * w]);
        }
        Ok(Batch {
            cfg,
            drift,
            ws,
            n,
            key,
            first_id,
            time: 0.0,
            totals: StepReport::default(),
        })
    }

    /// Number of trajectories.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false (a batch has at least one trajectory).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The configuration.
    pub fn config(&self) -> &Config<D> {
        &self.cfg
    }

    /// The drift.
    pub fn drift(&self) -> &Dr {
        &self.drift
    }

    /// The generators' key and the first trajectory's id.
    pub fn key(&self) -> (u64, u64) {
        (self.key, self.first_id)
    }

    /// Counts over the batch's life (events = wall hits, bounces = specular ones,
    /// removed = absorbed trajectories, proposals = trajectory-steps).
    pub fn totals(&self) -> StepReport {
        self.totals
    }

    fn records(&self) -> &[u64] {
        &self.ws.as_ref()[..self.n * Layout::<D>::W]
    }

    fn trajs(&self) -> impl Iterator<Item = Traj<D>> + '_ {
        self.records().chunks_exact(Layout::<D>::W).map(Traj::load)
    }

    /// Positions now (an absorbed trajectory's is where it hit the wall).
    pub fn positions(&self) -> impl Iterator<Item = [f64; D]> + '_ {
        self.trajs().map(|t| t.x)
    }

    /// Velocities now (an absorbed trajectory's is `U_θ−`, its velocity at the hit).
    pub fn velocities(&self) -> impl Iterator<Item = [f64; D]> + '_ {
        self.trajs().map(|t| t.u)
    }

    /// Wall hits of each trajectory so far (0 or 1 for an absorbing wall).
    pub fn hits(&self) -> impl Iterator<Item = u64> + '_ {
        self.trajs().map(|t| t.hits)
    }

    /// Time of each trajectory's first hit (`+inf` if none yet).
    pub fn first_hits(&self) -> impl Iterator<Item = f64> + '_ {
        self.trajs().map(|t| t.first)
    }

    /// Mean, variance and standard error of `f(X, U)` over the trajectories (absorbed
    /// ones at their hit, as the paper's absorption scheme returns them).
    pub fn statistics(&self, mut f: impl FnMut(&[f64; D], &[f64; D]) -> f64) -> Replicas {
        let mut r = Replicas::new();
        for t in self.trajs() {
            r.push(f(&t.x, &t.u));
        }
        r
    }

    /// Wall hits per trajectory: their mean and standard error.
    pub fn hit_statistics(&self) -> Replicas {
        let mut r = Replicas::new();
        for h in self.hits() {
            r.push(h as f64);
        }
        r
    }

    /// Trajectories absorbed so far (0 for a specular wall).
    pub fn absorbed(&self) -> usize {
        if self.cfg.wall == Wall::Absorbing {
            self.trajs().filter(|t| t.hits > 0).count()
        } else {
            0
        }
    }

    /// One step of length `h` from time `t`.
    #[inline(always)]
    fn step(cfg: &Config<D>, drift: &Dr, t: f64, h: f64, tr: &mut Traj<D>) -> Result<Hit> {
        let b = drift.drift(t, &tr.x, &tr.u);
        let mut xf = [0.0; D];
        for k in 0..D {
            xf[k] = tr.x[k] + h * tr.u[k];
        }
        // time s into the step at which the straight path meets the wall, and the
        // outward normal there
        let mut contact: Option<(f64, [f64; D], [f64; D])> = None;
        if D == 1 {
            let (x, u) = (tr.x[0], tr.u[0]);
            if xf[0] < 0.0 || (x == 0.0 && u < 0.0) {
                let mut xt = [0.0; D];
                xt[0] = 0.0;
                let mut n = [0.0; D];
                n[0] = 1.0;
                contact = Some(((-x / u).clamp(0.0, h), xt, n));
            }
        } else {
            let c = dot(&tr.x, &tr.x) - cfg.radius * cfg.radius;
            let bq = dot(&tr.x, &tr.u);
            let a = dot(&tr.u, &tr.u);
            if !(a.is_finite() && (bq * bq).is_finite()) {
                return Err(Error::InvalidRate {
                    name: "velocity (too large to find the wall: |u|² overflows)",
                    value: a,
                });
            }
            if bq < 0.0 && a > 0.0 {
                let disc = bq * bq - a * c;
                let s = if c <= 0.0 {
                    Some(0.0)
                } else if disc >= 0.0 {
                    // the smaller root, in the form without cancellation
                    let s = c / (libm::sqrt(disc) - bq);
                    (s < h).then_some(s)
                } else {
                    None
                };
                if let Some(s) = s {
                    let mut xt = [0.0; D];
                    for k in 0..D {
                        xt[k] = tr.x[k] + s * tr.u[k];
                    }
                    let r = libm::sqrt(dot(&xt, &xt));
                    let n = core::array::from_fn(|k| xt[k] / r);
                    contact = Some((s, xt, n));
                }
            }
        }
        let sig = cfg.sigma;
        let Some((s, xt, n)) = contact else {
            let sh = sig * libm::sqrt(h);
            let mut u = [0.0; D];
            for k in 0..D {
                u[k] = tr.u[k] + b[k] * h + sh * NormalZiggurat::sample(&mut tr.rng);
            }
            Self::finish(cfg, tr, xf, u)?;
            return Ok(Hit::None);
        };
        let ss = sig * libm::sqrt(s);
        let mut um = [0.0; D];
        for k in 0..D {
            um[k] = Self::bounded(
                cfg,
                tr.u[k] + b[k] * s + ss * NormalZiggurat::sample(&mut tr.rng),
            );
        }
        if !um.iter().all(|v| v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "velocity at a wall hit (the drift returned NaN or infinity)",
                value: um
                    .iter()
                    .copied()
                    .find(|v| !v.is_finite())
                    .unwrap_or(f64::NAN),
            });
        }
        tr.hits = tr.hits.saturating_add(1); // (restored counts may stand anywhere)
        if tr.first == f64::INFINITY {
            tr.first = (t + s).min(t + h);
        }
        if cfg.wall == Wall::Absorbing {
            tr.x = xt;
            tr.u = um;
            return Ok(Hit::Absorbed);
        }
        // reflect the velocity, mirror the free position in the tangent plane
        let un = dot(&um, &n);
        let ut: [f64; D] = core::array::from_fn(|k| um[k] - 2.0 * un * n[k]);
        let mut d = 0.0;
        for k in 0..D {
            d += (xf[k] - xt[k]) * n[k];
        }
        for k in 0..D {
            xf[k] -= 2.0 * d * n[k];
        }
        if D == 1 {
            xf[0] = xf[0].abs();
        }
        let b2 = drift.drift(t + s, &xt, &ut);
        let sr = sig * libm::sqrt(h - s);
        let mut u = [0.0; D];
        for k in 0..D {
            u[k] = ut[k] + b2[k] * (h - s) + sr * NormalZiggurat::sample(&mut tr.rng);
        }
        Self::finish(cfg, tr, xf, u)?;
        Ok(Hit::Bounce)
    }

    /// A velocity component with the bound applied.
    #[inline(always)]
    fn bounded(cfg: &Config<D>, mut u: f64) -> f64 {
        match cfg.bound {
            VelocityBound::None => {}
            VelocityBound::Clamp(v) => u = u.clamp(-v, v),
            VelocityBound::Reflect(v) => {
                if u > v {
                    u = 2.0 * v - u;
                } else if u < -v {
                    u = -2.0 * v - u;
                }
                u = u.clamp(-v, v);
            }
        }
        u
    }

    /// Applies the options to the new state and stores it, or fails on a non-finite
    /// velocity (a drift returning NaN or infinity).
    #[inline(always)]
    fn finish(cfg: &Config<D>, tr: &mut Traj<D>, mut x: [f64; D], mut u: [f64; D]) -> Result<()> {
        for k in 0..D {
            if !u[k].is_finite() {
                return Err(Error::InvalidRate {
                    name: "velocity after a step (the drift returned NaN or infinity)",
                    value: u[k],
                });
            }
            u[k] = Self::bounded(cfg, u[k]);
        }
        if D == 1
            && let Some(l) = cfg.period
        {
            // one period back without a branch (a trajectory crosses the border at
            // random steps); more periods are rare and reduced exactly by fmod
            x[0] -= l * f64::from(u8::from(x[0] >= l));
            if x[0] >= l {
                x[0] = libm::fmod(x[0], l);
            }
        }
        if let Some(&bad) = x.iter().find(|v| !v.is_finite()) {
            return Err(Error::InvalidRate {
                name: "position after a step (the velocity overflowed)",
                value: bad,
            });
        }
        tr.x = x;
        tr.u = u;
        Ok(())
    }

    /// `t` moved onto the grid point `k dt` within 1e-9 dt of it (targets such as 0.7
    /// with dt = 0.1, which is 7 dt only up to rounding, step as the grid point).
    #[inline]
    fn snap(dt: f64, t: f64) -> f64 {
        let g = libm::round(t / dt) * dt;
        if (g - t).abs() <= 1e-9 * dt { g } else { t }
    }

    /// The index k of the first grid point `k dt` after `s` (snapped).
    #[inline]
    fn first_grid(dt: f64, s: f64) -> f64 {
        let k = libm::round(s / dt);
        if k * dt <= s { k + 1.0 } else { k }
    }
}

impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> Scheme for Batch<D, Dr, B> {
    fn time(&self) -> f64 {
        self.time
    }
    fn totals(&self) -> StepReport {
        Batch::totals(self)
    }

    /// Steps every trajectory to `t`. With no budget each trajectory goes through all
    /// its steps in turn (its record stays in cache); with a budget the batch goes
    /// step by step and may stop at a grid point. A drift returning NaN or infinity is
    /// an error and the batch returns to its state at the start of the call.
    fn advance_within<R: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        _rng: &mut R,
    ) -> Result<StepReport> {
        check_target(self.time, t)?;
        let (n, w, dt) = (self.n, Layout::<D>::W, self.cfg.dt);
        let t0 = self.time;
        let mut rep = StepReport::default();
        let (cfg, drift) = (&self.cfg, &self.drift);
        let (recs, snap) = self.ws.as_mut()[..2 * n * w].split_at_mut(n * w);
        let restore = |recs: &mut [u64], snap: &[u64], upto: usize| {
            recs[..upto * w].copy_from_slice(&snap[..upto * w]);
        };
        let tally = |rep: &mut StepReport, h: Hit| match h {
            Hit::None => {}
            Hit::Bounce => {
                rep.events += 1;
                rep.bounces += 1;
            }
            Hit::Absorbed => {
                rep.events += 1;
                rep.removed += 1;
            }
        };
        // steps run over the snapped span [s0, e]; the time reached is the caller's t
        let (s0, e) = (Self::snap(dt, t0), Self::snap(dt, t));
        if e / dt > MAX_STEP_INDEX {
            return Err(Error::OutOfRange {
                name: "t / dt (the grid index must stay below 2^52 to move the clock)",
                value: e / dt,
                range: "[0, 2^52]",
            });
        }
        let k0 = Self::first_grid(dt, s0);
        if budget.is_unlimited() {
            // LANES trajectories step side by side: their chains (the velocity waits
            // for the drift, which waits for the velocity) overlap in the pipeline
            let mut g = 0;
            while g < n {
                let m = LANES.min(n - g);
                snap[g * w..(g + m) * w].copy_from_slice(&recs[g * w..(g + m) * w]);
                let mut lanes: [Traj<D>; LANES] = core::array::from_fn(|l| {
                    let i = g + l.min(m - 1);
                    Traj::load(&recs[i * w..(i + 1) * w])
                });
                let mut now = s0;
                let mut k = k0;
                while now < e {
                    let end = (k * dt).min(e);
                    k += 1.0;
                    let h = end - now;
                    for tr in lanes[..m].iter_mut() {
                        if tr.stopped(cfg.wall) {
                            continue;
                        }
                        match Self::step(cfg, drift, now, h, tr) {
                            Ok(hit) => tally(&mut rep, hit),
                            Err(e) => {
                                restore(recs, snap, g + m);
                                return Err(e);
                            }
                        }
                        rep.proposals += 1;
                    }
                    now = end;
                }
                for (l, tr) in lanes[..m].iter().enumerate() {
                    tr.store(&mut recs[(g + l) * w..(g + l + 1) * w]);
                }
                g += m;
            }
            self.time = t;
        } else {
            let mut now = s0;
            let mut first = true;
            let mut k = k0;
            while now < e {
                if !budget.take(n as u64) {
                    rep.interrupted = true;
                    break;
                }
                let end = (k * dt).min(e);
                k += 1.0;
                for i in 0..n {
                    let rec = &mut recs[i * w..(i + 1) * w];
                    if first {
                        snap[i * w..(i + 1) * w].copy_from_slice(rec);
                    }
                    let mut tr = Traj::<D>::load(rec);
                    if tr.stopped(cfg.wall) {
                        continue;
                    }
                    match Self::step(cfg, drift, now, end - now, &mut tr) {
                        Ok(h) => tally(&mut rep, h),
                        Err(e) => {
                            restore(recs, snap, if first { i } else { n });
                            self.time = t0;
                            return Err(e);
                        }
                    }
                    rep.proposals += 1;
                    tr.store(rec);
                }
                first = false;
                now = end;
                self.time = if now >= e { t } else { now };
            }
            if now >= e {
                // (also when t snaps onto the grid point the batch stands at)
                self.time = t;
            }
        }
        rep.time = self.time;
        self.totals.accumulate(&rep);
        Ok(rep)
    }
}

impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> crate::checkpoint::Checkpoint
    for Batch<D, Dr, B>
{
    /// The configuration, key, time, counts and every record (the drift is code: the
    /// restoring batch brings its own).
    fn save(&self, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::header;
        use crate::scheme::tag;
        header(w, tag::LANGEVIN);
        w.u64(D as u64);
        w.u64(self.n as u64);
        let c = &self.cfg;
        w.f64(c.dt);
        w.f64(c.sigma);
        w.u64(u64::from(c.wall == Wall::Absorbing));
        w.f64(c.radius);
        w.f64(c.period.unwrap_or(0.0));
        let (kind, v) = match c.bound {
            VelocityBound::None => (0, 0.0),
            VelocityBound::Clamp(v) => (1, v),
            VelocityBound::Reflect(v) => (2, v),
        };
        w.u64(kind);
        w.f64(v);
        w.u64(self.key);
        w.u64(self.first_id);
        w.f64(self.time);
        self.totals.save(w);
        w.u64(self.totals.removed);
        w.u64(self.totals.bounces);
        w.u64s(self.records());
    }

    /// Refuses a checkpoint of another dimension or size, an invalid configuration or
    /// an invalid record (non-finite state, a zero generator, a first hit after the
    /// time); on error the batch is unchanged.
    fn restore(&mut self, r: &mut crate::checkpoint::Reader) -> Result<()> {
        use crate::checkpoint::check_header;
        use crate::scheme::tag;
        let bad = |what| Error::Checkpoint { what };
        check_header(r, tag::LANGEVIN)?;
        if r.u64()? != D as u64 || r.u64()? != self.n as u64 {
            return Err(bad("a batch of another dimension or size"));
        }
        let (dt, sigma, absorbing, radius, period) =
            (r.f64()?, r.f64()?, r.u64()?, r.f64()?, r.f64()?);
        let (kind, v) = (r.u64()?, r.f64()?);
        let wall = match absorbing {
            0 => Wall::Specular,
            1 => Wall::Absorbing,
            _ => return Err(bad("invalid wall")),
        };
        let invalid = |_| bad("invalid configuration");
        let mut cfg = if D == 1 {
            if radius != 0.0 {
                return Err(bad("invalid configuration"));
            }
            let c = Config::<D>::half_line(dt, sigma, wall).map_err(invalid)?;
            if period != 0.0 {
                c.with_period(period).map_err(invalid)?
            } else {
                c
            }
        } else {
            if period != 0.0 {
                return Err(bad("invalid configuration"));
            }
            Config::<D>::ball(radius, dt, sigma, wall).map_err(invalid)?
        };
        let bound = match kind {
            0 if v == 0.0 => VelocityBound::None,
            1 => VelocityBound::Clamp(v),
            2 => VelocityBound::Reflect(v),
            _ => return Err(bad("invalid velocity bound")),
        };
        cfg = cfg.with_velocity_bound(bound).map_err(invalid)?;
        let (key, first_id, time) = (r.u64()?, r.u64()?, r.f64()?);
        if first_id.checked_add(self.n as u64 - 1).is_none() {
            return Err(bad("invalid trajectory ids"));
        }
        crate::scheme::check_time(time).map_err(|_| bad("invalid time"))?;
        if Self::snap(cfg.dt, time) / cfg.dt > MAX_STEP_INDEX {
            return Err(bad("a time beyond 2^52 steps"));
        }
        let mut totals = StepReport::read(r)?;
        totals.removed = r.u64()?;
        totals.bounces = r.u64()?;
        if totals.time.is_nan() || totals.time > time {
            return Err(bad("totals after the time"));
        }
        let w = Layout::<D>::W;
        if r.u64()? != (self.n * w) as u64 {
            return Err(bad("records of the wrong length"));
        }
        // read into the copy half of the workspace (no allocation), check, then swap in
        let (recs, snap) = self.ws.as_mut()[..2 * self.n * w].split_at_mut(self.n * w);
        for v in snap.iter_mut() {
            *v = r.u64()?;
        }
        r.finish()?;
        let horizon = Self::snap(cfg.dt, time) + cfg.dt;
        for rec in snap.chunks_exact(w) {
            let t = Traj::<D>::load(rec);
            let stopped = t.stopped(wall);
            // a mirrored position may sit within rounding of the wall
            let r2 = dot(&t.x, &t.x);
            let placed = if D == 1 {
                if stopped {
                    t.x[0] == 0.0
                } else {
                    cfg.check_start(&t.x, &t.u).is_ok()
                }
            } else {
                r2 >= cfg.radius * cfg.radius * (1.0 - 1e-9)
                    && t.u.iter().all(|v| v.is_finite())
                    && match cfg.bound {
                        VelocityBound::None => true,
                        VelocityBound::Clamp(v) | VelocityBound::Reflect(v) => {
                            t.u.iter().all(|c| c.abs() <= v)
                        }
                    }
            };
            let ok = t.x.iter().chain(&t.u).all(|v| v.is_finite())
                && placed
                && t.rng.parts() != [0; 4]
                && (t.first == f64::INFINITY || (t.first >= 0.0 && t.first <= horizon))
                && (t.hits == 0) == (t.first == f64::INFINITY)
                && (wall == Wall::Specular || t.hits <= 1);
            if !ok {
                return Err(bad("an invalid trajectory record"));
            }
        }
        recs.copy_from_slice(snap);
        self.cfg = cfg;
        self.key = key;
        self.first_id = first_id;
        self.time = time;
        self.totals = totals;
        Ok(())
    }
}

/// A Monte Carlo estimate: mean, standard error and the number of samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The estimate.
    pub mean: f64,
    /// Its standard error.
    pub std_error: f64,
    /// Samples (trajectories) behind it.
    pub count: u64,
}

impl Estimate {
    /// From replica statistics.
    pub fn of(r: &Replicas) -> Self {
        Estimate {
            mean: r.mean(),
            std_error: r.std_error(),
            count: r.count(),
        }
    }

    /// The two-sided 95% confidence interval (normal quantile: the counts are large).
    pub fn ci95(&self) -> (f64, f64) {
        let h = 1.959_963_984_540_054 * self.std_error;
        (self.mean - h, self.mean + h)
    }
}

/// Richardson–Romberg extrapolation `2 E f(X^{h/2}) − E f(X^h)` of two independent
/// runs, the coarse one at step h and the fine one at h/2, with its standard error
/// `√(4 SE_fine² + SE_coarse²)`: the `C h` term of the bias cancels.
pub fn richardson_romberg(coarse: &Replicas, fine: &Replicas) -> Estimate {
    let (c, f) = (Estimate::of(coarse), Estimate::of(fine));
    Estimate {
        mean: 2.0 * f.mean - c.mean,
        std_error: libm::sqrt(4.0 * f.std_error * f.std_error + c.std_error * c.std_error),
        count: c.count + f.count,
    }
}

/// Exact mean and covariance `[E x, E u, Var x, Cov(x, u), Var u]` of the scheme away
/// from walls with the linear drift `b = −γ u` after `steps` steps of length h from
/// `(x0, u0)`: `x' = x + h u`, `u' = (1 − γh) u + σ √h Z` (one dimension). The scheme's
/// own moments, not the SDE's: a test against them has no time-step bias.
pub fn euler_moments(x0: f64, u0: f64, gamma: f64, sigma: f64, h: f64, steps: u64) -> [f64; 5] {
    let (mut mx, mut mu) = (x0, u0);
    let (mut vxx, mut vxu, mut vuu) = (0.0, 0.0, 0.0);
    let a = 1.0 - gamma * h;
    for _ in 0..steps {
        (vxx, vxu, vuu) = (
            vxx + 2.0 * h * vxu + h * h * vuu,
            a * (vxu + h * vuu),
            a * a * vuu + sigma * sigma * h,
        );
        (mx, mu) = (mx + h * mu, a * mu);
    }
    [mx, mu, vxx, vxu, vuu]
}

/// `E |Y|` for `Y ~ N(m, v)`: with `b = 0` a specular wall at 0 folds the free motion,
/// so this is `E X_T` of the reflected scheme (`m`, `v` from [`euler_moments`]).
pub fn folded_normal_mean(m: f64, v: f64) -> f64 {
    let s = libm::sqrt(v);
    s * libm::sqrt(2.0 / core::f64::consts::PI) * libm::exp(-m * m / (2.0 * v))
        + m * libm::erf(m / (s * core::f64::consts::SQRT_2))
}

#[cfg(test)]
mod tests;
