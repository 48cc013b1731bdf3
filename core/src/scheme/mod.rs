//! Stepping schemes, all behind one interface: [`Scheme::advance_to`].
//!
//! A host time integrator calls `advance_to(t, rng)` once per outer step: time-driven
//! schemes take their steps up to `t`, event-driven ones process every event before `t`
//! and stop exactly at `t` (the exponential waiting times are memoryless, so the residual
//! wait is simply redrawn). The returned [`StepReport`] says what happened; observables
//! are read between calls.
//!
//! Schemes:
//! * [`massflow`] — the time-driven mass-flow scheme of Lécot et al. (2019): QMC, MC,
//!   RQMC;
//! * [`lowrank`] — Osinsky's low-rank Monte Carlo (Osinsky 2023), in the bucketed and
//!   the per-size tree layouts;
//! * [`baseline`] — the inverse method and acceptance–rejection, low-rank's baselines.
//!
//! Shared below them: [`population`] (the size-count population: validation, particle
//! doubling, size limit, memory budget) and [`registry`] (the object-safe facade over
//! every scheme, and the one place that builds them).

pub(crate) mod clock;

pub(crate) use crate::random::{Ziggurat, exp1, open_unit};
pub mod baseline;
pub mod lowrank;
pub mod massflow;
pub mod population;
pub mod registry;

use crate::error::Result;
use rand_core::Rng;

/// What one call of [`Scheme::advance_to`] did. `#[non_exhaustive]`: schemes to come
/// add what they report; build one with `StepReport::default()`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct StepReport {
    /// Time reached (the requested time on success).
    pub time: f64,
    /// Accepted events (coagulations, fragmentations).
    pub events: u64,
    /// Proposals, accepted or not.
    pub proposals: u64,
    /// Proposals rejected by thinning (including same-particle rejections).
    pub rejections: u64,
    /// Proposals where the kernel exceeded its declared bound. Always 0 since a
    /// violated bound became an error (`Error::BoundExceeded`, the state as before the
    /// event); kept for the C ABI's step report.
    pub bound_violations: u64,
    /// Time steps whose probabilities exceeded 1 and were clipped (time-driven schemes).
    pub clipped: u64,
    /// Times the particle number was doubled (size-count schemes).
    pub doublings: u64,
    /// Particles that left the system (beyond a truncation size, into a gel, absorbed
    /// by a wall); 0 for the schemes that keep every particle.
    pub removed: u64,
    /// Collisions that bounced instead of merging (schemes with restitution, specular
    /// walls); 0 for pure coagulation.
    pub bounces: u64,
}

impl StepReport {
    /// Adds the counts of `other` (time is taken from `other`).
    pub fn accumulate(&mut self, other: &StepReport) {
        self.time = other.time;
        self.events += other.events;
        self.proposals += other.proposals;
        self.rejections += other.rejections;
        self.bound_violations += other.bound_violations;
        self.clipped += other.clipped;
        self.doublings += other.doublings;
        self.removed += other.removed;
        self.bounces += other.bounces;
    }
}

/// The stepping interface shared by every scheme.
pub trait Scheme {
    /// Current simulation time.
    fn time(&self) -> f64;

    /// Runs until time `t ≥ self.time()`. Errors (a time in the past, a capacity
    /// exceeded, a kernel returning NaN) leave the state as it was before the failing
    /// event.
    fn advance_to<R: Rng + ?Sized>(&mut self, t: f64, rng: &mut R) -> Result<StepReport>;
}

/// Validates a target time against the current time.
pub(crate) fn check_target(now: f64, t: f64) -> Result<()> {
    crate::error::finite("t", t)?;
    if t < now {
        return Err(crate::error::Error::TimeBackwards { now, requested: t });
    }
    Ok(())
}
