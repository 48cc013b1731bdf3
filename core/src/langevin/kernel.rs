//! Collision kernels from particle tracking: the rate at which pairs meet, estimated
//! from the first hits of their relative motion on the sphere `|x| = R` (`R = r1 + r2`),
//! for any drift — where no closed form exists (shear, turbulence) this is the kernel.
//!
//! The relative position starts uniform in the shell `R < |x| < L` (concentration 1
//! outside the sphere), the relative velocity Maxwellian (each component N(0, s²)); the
//! absorbing sphere counts first hits, and the kernel averaged over the window
//! `[t_a, t_b)` is the number of first hits in it per unit concentration and time. The
//! estimator draws `|x|` uniform on `[R, L]` (not by volume) and weights each trajectory
//! by the shell area `S_D |x|^{D−1} (L − R)`, which puts the trajectories where the hits
//! come from. L must be far enough that pairs from beyond it cannot meet before `t_b`.
//!
//! References for checking ([`smoluchowski`], [`free_flight`]):
//! * diffusion (the Brownian limit of [`Friction`](super::Friction), `D = σ²τ²/2`):
//!   `K(t) = 4π D R (1 + R / √(π D t))`, Smoluchowski's kernel `4π(D1 + D2)(r1 + r2)`
//!   with its transient; the Langevin kernel approaches it as `√(D τ) / R → 0`;
//! * free flight (`σ = 0`, `b = 0`): `K = π R² ⟨|v|⟩` exactly, at every time and step.
//!
//! ```
//! use coagula_core::langevin::kernel::{first_hit_kernel, free_flight, FirstHits};
//! use coagula_core::langevin::Field;
//! let p = FirstHits { radius: 1.0, outer: 12.0, from: 0.5, to: 1.0, dt: 0.05,
//!                     sigma: 0.0, velocity_sd: 1.0, trajectories: 20_000 };
//! let zero = Field(|_t, _x: &[f64; 3], _u: &[f64; 3]| [0.0; 3]);
//! let k = first_hit_kernel::<3, _>(&p, &zero, 11, 0).unwrap();
//! let exact = free_flight(3, 1.0, 1.0); // π R² ⟨|v|⟩ = 5.013
//! assert!((k.estimate.mean - exact).abs() < 5.0 * k.estimate.std_error);
//! ```

use super::{Batch, Config, Drift, Estimate, Wall};
use crate::error::{Error, Result, finite};
use crate::observe::Replicas;
use crate::random::{NormalZiggurat, Purpose, substream};
use crate::scheme::Budget;
use core::f64::consts::PI;
use rand_core::Rng;

/// A first-hit kernel estimation: geometry, window, step, noise, initial velocities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstHits {
    /// Collision radius `R = r1 + r2`.
    pub radius: f64,
    /// Outer radius `L > R` of the shell the pairs start in.
    pub outer: f64,
    /// Start of the window `t_a ≥ 0`.
    pub from: f64,
    /// End of the window `t_b > t_a` (the run's final time).
    pub to: f64,
    /// Time step.
    pub dt: f64,
    /// Noise amplitude of the relative velocity.
    pub sigma: f64,
    /// Standard deviation `s` of each initial relative velocity component.
    pub velocity_sd: f64,
    /// Trajectories.
    pub trajectories: u64,
}

/// The kernel estimate: mean and standard error over trajectories, and the hits counted
/// in the window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelEstimate {
    /// Window-averaged kernel (per unit concentration and time).
    pub estimate: Estimate,
    /// First hits inside the window.
    pub hits: u64,
    /// Statistics of the per-trajectory values (to merge shares of an ensemble).
    pub replicas: Replicas,
}

/// Trajectories per batch of the estimation.
const CHUNK: usize = 4096;

impl FirstHits {
    fn check(&self) -> Result<()> {
        for (name, v) in [
            ("radius", self.radius),
            ("outer radius", self.outer),
            ("window start", self.from),
            ("window end", self.to),
            ("velocity sd", self.velocity_sd),
        ] {
            finite(name, v)?;
        }
        if !(self.radius > 0.0 && self.outer > self.radius) {
            return Err(Error::OutOfRange {
                name: "outer radius (must exceed the collision radius > 0)",
                value: self.outer,
                range: "(radius, inf)",
            });
        }
        if !(self.from >= 0.0 && self.to > self.from) {
            return Err(Error::OutOfRange {
                name: "window end (must exceed its start >= 0)",
                value: self.to,
                range: "(from, inf)",
            });
        }
        if self.velocity_sd < 0.0 {
            return Err(Error::OutOfRange {
                name: "velocity sd",
                value: self.velocity_sd,
                range: "[0, inf)",
            });
        }
        if self.trajectories == 0 {
            return Err(Error::Empty);
        }
        Ok(())
    }

    /// Start of trajectory `id`: `(x, u, weight)`.
    fn start<const D: usize>(&self, key: u64, id: u64) -> ([f64; D], [f64; D], f64) {
        let mut g = substream(key, id, Purpose::Initial);
        let span = self.outer - self.radius;
        let r = self.radius + span * crate::random::unit_f64(g.next_u64());
        let mut dir = [0.0; D];
        let mut norm2 = 0.0;
        while norm2 < 1e-12 {
            norm2 = 0.0;
            for c in dir.iter_mut() {
                *c = NormalZiggurat::sample(&mut g);
                norm2 += *c * *c;
            }
        }
        let norm = libm::sqrt(norm2);
        let mut x: [f64; D] = core::array::from_fn(|k| r * dir[k] / norm);
        // rounding may put |x| a hair inside the sphere when r ≈ R
        while x.iter().map(|c| c * c).sum::<f64>() < self.radius * self.radius {
            for c in x.iter_mut() {
                *c *= 1.0 + f64::EPSILON;
            }
        }
        let u = core::array::from_fn(|_| self.velocity_sd * NormalZiggurat::sample(&mut g));
        let area = if D == 2 {
            2.0 * PI * r
        } else {
            4.0 * PI * r * r
        };
        (x, u, area * span)
    }
}

/// Estimates the window-averaged collision kernel of the relative motion with `drift`
/// (in `D` = 2 or 3 dimensions) from first hits, trajectories `first_id..` under `key`
/// (shares of one estimation with disjoint ids merge through
/// [`KernelEstimate::replicas`]).
pub fn first_hit_kernel<const D: usize, Dr: Drift<D>>(
    p: &FirstHits,
    drift: &Dr,
    key: u64,
    first_id: u64,
) -> Result<KernelEstimate> {
    first_hit_kernel_within::<D, Dr>(p, drift, key, first_id, &mut Budget::unlimited())
        .map(|k| k.expect("an unlimited budget is never spent"))
}

/// [`first_hit_kernel`] within `budget`, counted in trajectory steps (a trajectory to
/// `to` takes `⌈to / dt⌉`; a chunk of trajectories runs only if the budget covers all of
/// it, cut to the trajectories it covers, so the work never passes the budget; the
/// cancellation callback is polled between chunks of at most 4096 trajectories):
/// `None` when the budget cannot cover the next trajectory or the callback cancels
/// (no estimate: a partial one would be from fewer trajectories than asked). The
/// chunking does not change the estimate's bits.
pub fn first_hit_kernel_within<const D: usize, Dr: Drift<D>>(
    p: &FirstHits,
    drift: &Dr,
    key: u64,
    first_id: u64,
    budget: &mut Budget<'_>,
) -> Result<Option<KernelEstimate>> {
    p.check()?;
    // (a float-to-integer cast saturates; the batch refuses t / dt past 2^52)
    let steps = libm::ceil(p.to / p.dt) as u64;
    let cfg = Config::<D>::ball(p.radius, p.dt, p.sigma, Wall::Absorbing)?;
    first_id
        .checked_add(p.trajectories - 1)
        .ok_or(Error::Overflow {
            name: "trajectory id",
        })?;
    let chunk = CHUNK.min(usize::try_from(p.trajectories).unwrap_or(CHUNK));
    let len = super::workspace_len(D, chunk).ok_or(Error::Overflow {
        name: "Langevin workspace",
    })?;
    let mut ws = alloc::vec::Vec::new();
    ws.try_reserve_exact(len).map_err(|_| Error::Capacity {
        name: "memory for the Langevin workspace (u64 words)",
        capacity: len,
    })?;
    ws.resize(len, 0u64);
    let (mut rep, mut hits) = (Replicas::new(), 0u64);
    let width = p.to - p.from;
    let mut done = 0u64;
    while done < p.trajectories {
        // a chunk runs whole: it is cut to the trajectories the budget still covers
        // (none: stop), so the work never passes the budget
        if !budget.poll() {
            return Ok(None);
        }
        let fit = usize::try_from(budget.left() / steps.max(1)).unwrap_or(usize::MAX);
        let m = chunk.min((p.trajectories - done) as usize).min(fit);
        if m == 0 {
            return Ok(None);
        }
        budget.take((m as u64).saturating_mul(steps.max(1)));
        let id0 = first_id + done;
        let mut b = Batch::with_starts_in(
            cfg,
            drift,
            m,
            key,
            id0,
            |i| {
                let (x, u, _) = p.start::<D>(key, id0 + i as u64);
                (x, u)
            },
            &mut ws[..],
        )?;
        b.advance_to(p.to)?;
        for (i, t) in b.first_hits().enumerate() {
            let inside = t >= p.from && t < p.to;
            let w = if inside {
                hits += 1;
                p.start::<D>(key, id0 + i as u64).2
            } else {
                0.0
            };
            rep.push(w / width);
        }
        done += m as u64;
    }
    Ok(Some(KernelEstimate {
        estimate: Estimate::of(&rep),
        hits,
        replicas: rep,
    }))
}

/// Smoluchowski's kernel averaged over `[from, to)`: the mean of
/// `4π D R (1 + R / √(π D t))`, the first-hit rate of a diffusion of diffusivity D on an
/// absorbing sphere of radius R from a uniform start (3-D).
pub fn smoluchowski(diffusivity: f64, radius: f64, from: f64, to: f64) -> f64 {
    let (d, r) = (diffusivity, radius);
    let transient = 2.0 * r * (libm::sqrt(to) - libm::sqrt(from)) / libm::sqrt(PI * d);
    4.0 * PI * d * r * (to - from + transient) / (to - from)
}

/// The free-flight kernel `π R² ⟨|v|⟩` (3-D) or `2 R ⟨|v|⟩` (2-D) of Maxwellian relative
/// velocities with component standard deviation `s`.
pub fn free_flight(dim: usize, radius: f64, s: f64) -> f64 {
    if dim == 2 {
        2.0 * radius * s * libm::sqrt(PI / 2.0)
    } else {
        PI * radius * radius * s * libm::sqrt(8.0 / PI)
    }
}

/// Smoluchowski's orthokinetic kernel `(4/3) γ̇ R³` of a simple shear flow (3-D,
/// straight streamlines, no diffusion).
pub fn orthokinetic(shear: f64, radius: f64) -> f64 {
    4.0 / 3.0 * shear * radius * radius * radius
}
