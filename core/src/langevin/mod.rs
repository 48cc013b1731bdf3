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
//! use rand_pcg::Pcg64Mcg;
//! // free Brownian velocity (b = 0, σ = 1) next to a specular wall at 0
//! let cfg = Config::line(0.01, 1.0, Wall::Specular).unwrap();
//! let mut rng = Pcg64Mcg::new(7);
//! let mut batch = Batch::new(cfg, Scalar(|_t, _x, _u| 0.0), 10_000, ([0.5], [-1.0]), &mut rng).unwrap();
//! // each trajectory draws its noise from its own stream (the batch's key and its id)
//! batch.advance_to(1.0).unwrap();
//! // reflection is an isometry: E U_T² = u0² + σ² T exactly
//! let u2 = batch.statistics(|_x, u| u[0] * u[0]);
//! assert!((u2.mean() - 2.0).abs() < 5.0 * u2.std_error());
//! assert!(batch.positions().all(|x| x[0] >= 0.0));
//! ```

mod checkpoint;
mod drift;
mod estimate;
pub mod kernel;
pub mod paper;
mod step;

pub use drift::*;
pub use estimate::*;

use crate::error::{Error, Result, finite};
use crate::observe::Replicas;
use crate::random::{Generator, NormalZiggurat, Xoshiro256PlusPlus};
use crate::scheme::{Budget, StepReport, check_target};
use alloc::vec::Vec;
use rand_core::Rng;

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
                what: "a half-line in more than one dimension (use a ball: dimension 2 or 3)",
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
                what: "a ball in one dimension (use a line: dimension 1)",
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
/// caller's memory through [`Batch::with_starts_in`]). Its verbs are those of [`Scheme`](crate::scheme::Scheme) without a generator: the budget
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

impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> Batch<D, Dr, B> {
    /// Writes the batch in the one checkpoint envelope of every front end
    /// ([`crate::scheme::facade::write_envelope`]): no settings records (the batch's
    /// own checkpoint carries its configuration), `drift` the fingerprint of the drift
    /// (not stored: a closure or a callback is code), no random stream (each
    /// trajectory's stream is part of the state).
    pub fn save_envelope(&self, drift: u64, w: &mut crate::checkpoint::Writer) {
        use crate::checkpoint::Checkpoint;
        crate::scheme::facade::write_envelope(
            w,
            crate::scheme::tag::LANGEVIN,
            &[],
            drift,
            None,
            |w| self.save(w),
        );
    }

    /// Restores an envelope written by [`save_envelope`](Self::save_envelope) under the
    /// same drift fingerprint into a batch of the same dimension and size; on error the
    /// batch is unchanged.
    pub fn restore_envelope(&mut self, buf: &[u8], drift: u64) -> Result<()> {
        use crate::checkpoint::Checkpoint;
        crate::scheme::facade::read_envelope(
            buf,
            crate::scheme::tag::LANGEVIN,
            drift,
            |records| {
                if records.is_empty() {
                    Ok(())
                } else {
                    Err(Error::Checkpoint {
                        what: "a Langevin envelope has no settings records",
                    })
                }
            },
            |_, r| self.restore(r),
        )
    }
}

impl<const D: usize, Dr, B> Batch<D, Dr, B> {
    /// The same batch in another storage type holding the same words (a front end's
    /// storage enum).
    pub fn map_storage<B2>(self, f: impl FnOnce(B) -> B2) -> Batch<D, Dr, B2> {
        Batch {
            cfg: self.cfg,
            drift: self.drift,
            ws: f(self.ws),
            n: self.n,
            key: self.key,
            first_id: self.first_id,
            time: self.time,
            totals: self.totals,
        }
    }
}

impl<const D: usize, Dr: Drift<D> + Clone, B: AsRef<[u64]>> Batch<D, Dr, B> {
    /// An exact copy in storage of its own (a batch in caller memory included): the
    /// two continue identically and independently.
    pub fn duplicate(&self) -> Result<Batch<D, Dr, Vec<u64>>> {
        let src = self.ws.as_ref();
        let mut ws = Vec::new();
        ws.try_reserve_exact(src.len())
            .map_err(|_| Error::Capacity {
                name: "memory for the Langevin workspace (u64 words)",
                capacity: src.len(),
            })?;
        ws.extend_from_slice(src);
        Ok(Batch {
            cfg: self.cfg,
            drift: self.drift.clone(),
            ws,
            n: self.n,
            key: self.key,
            first_id: self.first_id,
            time: self.time,
            totals: self.totals,
        })
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

/// The stepping verbs of a batch. They take no generator: each trajectory draws its
/// noise from its own counter-based stream (the batch's key and the trajectory's id),
/// so a batch runs the same on any split of its calls, threads or ranks.
impl<const D: usize, Dr: Drift<D>, B: AsRef<[u64]> + AsMut<[u64]>> Batch<D, Dr, B> {
    /// The time reached.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps every trajectory to `t` ([`advance_within`](Self::advance_within) with
    /// no budget).
    pub fn advance_to(&mut self, t: f64) -> Result<StepReport> {
        self.advance_within(t, &mut Budget::unlimited())
    }

    /// Steps every trajectory to `t`, or until `budget` (trajectory steps, and a
    /// cancellation callback) is spent: then the report says `interrupted` and the
    /// batch stands at the grid point reached, consistent (calling again continues
    /// the same run). With no budget each trajectory goes through all its steps in
    /// turn (its record stays in cache); with a budget the batch goes step by step. A
    /// drift returning NaN or infinity is an error and the batch returns to its state
    /// at the start of the call.
    pub fn advance_within(&mut self, t: f64, budget: &mut Budget<'_>) -> Result<StepReport> {
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

#[cfg(test)]
mod tests;
