//! Stepping schemes, all behind one interface: [`Scheme::advance_to`].
//!
//! A host time integrator calls `advance_to(t, rng)` once per outer step: time-driven
//! schemes take their steps up to `t`, event-driven ones process every event before `t`
//! and stop exactly at `t`, keeping the time of their next proposal (already drawn) for
//! the next call — so a run stopped at 0.7 and 1.3 on its way to 2 is bit for bit the
//! run that went to 2 in one call. The returned [`StepReport`] says what happened;
//! observables are read between calls.
//!
//! [`Scheme::advance_within`] bounds the work of one call by a [`Budget`] (a number of
//! proposals or particle updates, and a cancellation callback): past it the call returns
//! with `interrupted` set, the state consistent at the time reached, and the host may
//! call again (the run is the same as an uninterrupted one).
//!
//! Schemes:
//! * [`massflow`] — the time-driven mass-flow scheme of Lécot et al. (2019): QMC, MC,
//!   RQMC;
//! * [`lowrank`] — Osinsky's low-rank Monte Carlo (Osinsky 2023), in the bucketed and
//!   the per-size tree layouts;
//! * [`baseline`] — the inverse method and acceptance–rejection, low-rank's baselines;
//! * [`eventflow`] — the event-driven mass flow algorithm and direct simulation of
//!   Eibeck & Wagner (2000), with fragmentation events.
//!
//! Shared below them: [`population`] (the size-count population: validation, particle
//! doubling, size limit, memory budget) and [`registry`] (the object-safe facade over
//! every scheme, and the one place that builds them).

pub(crate) mod clock;

pub(crate) use crate::random::{Ziggurat, exp1, open_unit};
pub mod baseline;
pub mod eventflow;
pub mod facade;
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
    /// Proposals where the kernel exceeded its declared bound. The size-count schemes
    /// make a violated bound an error (`Error::BoundExceeded`, the state as before the
    /// event), so for them it is 0; the event-driven particle schemes (`eventflow`)
    /// count a kernel above its product majorant here and accept the proposal, unless
    /// built with a strict bound.
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
    /// The call stopped before its target time because its [`Budget`] ran out or was
    /// cancelled; `time` is the time reached.
    pub interrupted: bool,
}

/// Checkpoint tags of the schemes (a checkpoint of one scheme is refused by another).
pub(crate) mod tag {
    pub const MASSFLOW: u64 = 1;
    pub const LOWRANK: u64 = 2;
    pub const INVERSE: u64 = 3;
    pub const REJECTION: u64 = 4;
    pub const BUCKETED: u64 = 5;
    pub const MFA: u64 = 6;
    pub const DSA: u64 = 7;
    pub const DSA_COUNTS: u64 = 8;
    pub const LANGEVIN: u64 = 9;
    pub const TEMPERATURE: u64 = 10;
    pub const UNIFORM: u64 = 11;
    pub const DSMC: u64 = 12;
    pub const LOWRANK_SIZES: u64 = 13;
    pub const BUCKETED_COUNTED: u64 = 14;
    // registry entries whose scheme shares its engine's tag with another entry
    pub const LOWRANK_BINARY: u64 = 15;
    pub const TEMPERATURE_REJECTION: u64 = 16;
    pub const DSMC_REJECTION: u64 = 17;
    // the block-majorant engine
    pub const BLOCKS: u64 = 18;
}

impl StepReport {
    /// Writes the report into a checkpoint.
    pub(crate) fn save(&self, w: &mut crate::checkpoint::Writer) {
        w.f64(self.time);
        for v in [
            self.events,
            self.proposals,
            self.rejections,
            self.bound_violations,
            self.clipped,
            self.doublings,
            self.removed,
            self.bounces,
        ] {
            w.u64(v);
        }
    }

    /// Reads a report written by [`save`](Self::save).
    pub(crate) fn read(r: &mut crate::checkpoint::Reader) -> Result<StepReport> {
        Ok(StepReport {
            time: r.f64()?,
            events: r.u64()?,
            proposals: r.u64()?,
            rejections: r.u64()?,
            bound_violations: r.u64()?,
            clipped: r.u64()?,
            doublings: r.u64()?,
            removed: r.u64()?,
            bounces: r.u64()?,
            interrupted: false,
        })
    }

    /// Adds the counts of `other` (time is taken from `other`).
    pub fn accumulate(&mut self, other: &StepReport) {
        self.time = other.time;
        // saturating: counters restored from a checkpoint may stand anywhere
        self.events = self.events.saturating_add(other.events);
        self.proposals = self.proposals.saturating_add(other.proposals);
        self.rejections = self.rejections.saturating_add(other.rejections);
        self.bound_violations = self.bound_violations.saturating_add(other.bound_violations);
        self.clipped = self.clipped.saturating_add(other.clipped);
        self.doublings = self.doublings.saturating_add(other.doublings);
        self.removed = self.removed.saturating_add(other.removed);
        self.bounces = self.bounces.saturating_add(other.bounces);
        self.interrupted = other.interrupted;
    }
}

/// Work units between two polls of a [`Budget`]'s cancellation callback.
pub const POLL_EVERY: u64 = 1 << 14;

/// What one call of [`Scheme::advance_within`] may do: a number of work units
/// (proposals of an event-driven scheme, particle updates of a time-driven one — N per
/// time step) and an optional cancellation callback, polled every [`POLL_EVERY`]
/// units (and before a time step). A call always makes progress while a unit is left:
/// a time step is taken whole when at least one unit remains.
///
/// ```
/// use coagula_core::kernel::Coagulation;
/// use coagula_core::scheme::{Budget, Scheme, lowrank::LowRank};
/// let mut sim = LowRank::<_, 1>::monodisperse(Coagulation::constant(1.0).unwrap(), 10_000).unwrap();
/// let mut rng = rand_pcg::Pcg64Mcg::new(3);
/// // at most 1000 proposals per call: call again until the target is reached
/// let mut calls = 0;
/// loop {
///     calls += 1;
///     let rep = sim.advance_within(1.0, &mut Budget::work(1000), &mut rng).unwrap();
///     if !rep.interrupted {
///         break;
///     }
///     assert!(rep.time < 1.0);
/// }
/// assert!(calls > 1);
/// assert_eq!(sim.time(), 1.0);
/// ```
pub struct Budget<'a> {
    left: u64,
    until_poll: u64,
    cancel: Option<&'a mut dyn FnMut() -> bool>,
    /// Stop after a particle doubling (the process layer's thinning bound holds only
    /// until one: `docs/design/processes.md`).
    halt_at_doubling: bool,
    /// The units left when a doubling halted the call (`left` is 0 until resumed), and
    /// the time of the doubling.
    halted: Option<(u64, f64)>,
}

impl core::fmt::Debug for Budget<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Budget")
            .field("left", &self.left)
            .field("cancel", &self.cancel.is_some())
            .finish()
    }
}

impl<'a> Budget<'a> {
    /// No limit (what [`Scheme::advance_to`] uses).
    pub fn unlimited() -> Self {
        Self::work(u64::MAX)
    }

    /// At most `units` work units.
    pub fn work(units: u64) -> Self {
        Budget {
            left: units,
            until_poll: POLL_EVERY,
            cancel: None,
            halt_at_doubling: false,
            halted: None,
        }
    }

    /// Adds a cancellation callback: returning `true` stops the call at the next poll.
    pub fn with_cancel(mut self, cancel: &'a mut dyn FnMut() -> bool) -> Self {
        self.cancel = Some(cancel);
        self
    }

    /// No limit and no callback: a call may run to its target in any order of work.
    pub(crate) fn is_unlimited(&self) -> bool {
        self.left == u64::MAX && self.cancel.is_none()
    }

    /// Units left.
    pub fn left(&self) -> u64 {
        self.left
    }

    /// Takes `units` (at least one must be left; the rest is taken as far as it goes);
    /// `false` when the budget is spent or the callback cancels.
    #[inline(always)]
    pub(crate) fn take(&mut self, units: u64) -> bool {
        if self.left == 0 {
            return false;
        }
        self.left = self.left.saturating_sub(units);
        if self.until_poll > units {
            self.until_poll -= units;
            return true;
        }
        self.poll()
    }

    /// A particle doubling happened: when the call is to halt at one, the budget reads
    /// as spent (the scheme stops before its next proposal, as when work runs out)
    /// until [`resume`](Self::resume).
    #[inline]
    pub(crate) fn doubled(&mut self, at: f64) {
        if self.halt_at_doubling && self.halted.is_none() {
            self.halted = Some((self.left, at));
            self.left = 0;
        }
    }

    /// Whether calls stop after a particle doubling (see [`doubled`](Self::doubled)).
    pub(crate) fn set_halt_at_doubling(&mut self, on: bool) {
        self.halt_at_doubling = on;
    }

    /// Gives back the units a doubling held; the time of the doubling that halted the
    /// call, if one did since the last resume.
    pub(crate) fn resume(&mut self) -> Option<f64> {
        let (left, at) = self.halted.take()?;
        self.left = left;
        Some(at)
    }

    /// Polls the callback (before a costly unit, e.g. a time step).
    #[cold]
    pub(crate) fn poll(&mut self) -> bool {
        self.until_poll = POLL_EVERY;
        if let Some(f) = self.cancel.as_mut()
            && f()
        {
            self.left = 0;
            return false;
        }
        true
    }
}

/// The stepping interface shared by every scheme.
pub trait Scheme {
    /// Current simulation time.
    fn time(&self) -> f64;

    /// Totals of every call so far (the books: events, proposals, removals, …; what a
    /// checkpoint carries over).
    fn totals(&self) -> StepReport;

    /// Runs until time `t ≥ self.time()`, or until `budget` is spent (then the report
    /// says `interrupted`, its time is the time reached and the state is consistent
    /// there; calling again continues the same run). Errors (a time in the past, a
    /// capacity exceeded, a kernel returning NaN, a rate so large that waiting times
    /// vanish) leave the state as it was before the failing event.
    fn advance_within<R: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut R,
    ) -> Result<StepReport>;

    /// Runs until time `t ≥ self.time()` ([`advance_within`](Self::advance_within)
    /// with no budget).
    fn advance_to<R: Rng + ?Sized>(&mut self, t: f64, rng: &mut R) -> Result<StepReport> {
        self.advance_within(t, &mut Budget::unlimited(), rng)
    }
}

/// The pending proposal of an event-driven scheme: its time and the mean waiting time
/// it was drawn with. Kept between calls (a call stopping at `t` leaves it for the next
/// one), forgotten when the state is replaced from outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pending {
    /// Time of the next proposal.
    pub at: f64,
    /// Mean waiting time between proposals at the current rate.
    pub mean_dt: f64,
}

impl Pending {
    /// Checks that waiting times of mean `mean_dt` move a clock standing at `now`: an
    /// error for a zero or non-finite mean, or one so small against `now` (huge rates, a
    /// late time) that `now + mean_dt == now` and no target could ever be reached.
    #[inline]
    pub(crate) fn check(now: f64, mean_dt: f64) -> Result<()> {
        if mean_dt > 0.0 && mean_dt.is_finite() && now + mean_dt > now {
            Ok(())
        } else {
            Err(crate::error::Error::InvalidRate {
                name: "mean waiting time between proposals (zero, or below the resolution of the current time: the rates are too large)",
                value: mean_dt,
            })
        }
    }

    /// The proposal after one at `now`, `e` (an Exp(1) variate) mean waiting times later.
    #[inline(always)]
    pub(crate) fn after(now: f64, mean_dt: f64, e: f64) -> Pending {
        Pending {
            at: now + e * mean_dt,
            mean_dt,
        }
    }

    /// Writes an optional pending proposal.
    pub(crate) fn save(p: &Option<Pending>, w: &mut crate::checkpoint::Writer) {
        match p {
            Some(p) => {
                w.u64(1);
                w.f64(p.at);
                w.f64(p.mean_dt);
            }
            None => w.u64(0),
        }
    }

    /// Reads an optional pending proposal, which must lie at or after `now`. It may lie
    /// at +inf: a mean wait near the largest double times an exponential variate above
    /// 1 overflows, a proposal that never comes, and the scheme holds it (fuzzing
    /// finding 11: a clone of such a sim was refused).
    pub(crate) fn read(r: &mut crate::checkpoint::Reader, now: f64) -> Result<Option<Pending>> {
        let bad = |what| crate::error::Error::Checkpoint { what };
        match r.u64()? {
            0 => Ok(None),
            1 => {
                let (at, mean_dt) = (r.f64()?, r.f64()?);
                if !(at >= now && mean_dt > 0.0 && mean_dt.is_finite()) {
                    return Err(bad("invalid pending proposal"));
                }
                Ok(Some(Pending { at, mean_dt }))
            }
            _ => Err(bad("invalid flag")),
        }
    }
}

/// The next proposal of an event-driven scheme whose proposals come at `rate` (finite):
/// the pending one, else one an exponential wait after `time`. `Ok(None)` when none
/// comes by `t` — the clock then stands at `t`, and a drawn proposal stays pending — or
/// when `budget` is spent (`rep.interrupted`); otherwise the proposal is counted in
/// `rep.proposals`, left pending (a caller that stops before carrying it out resumes
/// with it) and returned. Errors: a mean wait that cannot move the clock.
#[inline]
pub(crate) fn next_proposal<R: Rng + ?Sized>(
    pending: &mut Option<Pending>,
    time: &mut f64,
    t: f64,
    rate: f64,
    budget: &mut Budget<'_>,
    rep: &mut StepReport,
    rng: &mut R,
) -> crate::error::Result<Option<Pending>> {
    let p = match *pending {
        Some(p) => p,
        None => {
            if rate.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
                // nothing can happen any more (too few particles, or zero weights)
                *time = t;
                return Ok(None);
            }
            let mean = 1.0 / rate;
            Pending::check(*time, mean)?;
            Pending::after(*time, mean, Ziggurat::new().sample(rng))
        }
    };
    *pending = Some(p);
    if p.at > t {
        *time = t;
        return Ok(None);
    }
    if !budget.take(1) {
        rep.interrupted = true;
        return Ok(None);
    }
    rep.proposals += 1;
    Ok(Some(p))
}

/// Validates a time a host sets (`set_time`): finite and not negative.
pub(crate) fn check_time(t: f64) -> Result<f64> {
    crate::error::finite("t", t)?;
    if t < 0.0 {
        return Err(crate::error::Error::OutOfRange {
            name: "t",
            value: t,
            range: "[0, inf)",
        });
    }
    Ok(t)
}

/// Validates a target time against the current time.
pub(crate) fn check_target(now: f64, t: f64) -> Result<()> {
    crate::error::finite("t", t)?;
    if t < now {
        return Err(crate::error::Error::TimeBackwards { now, requested: t });
    }
    Ok(())
}

/// Checks a restored pending proposal against the rate of the restored state.
pub(crate) fn check_pending(p: &Option<Pending>, rate: f64) -> Result<()> {
    if let Some(p) = p
        && !(rate > 0.0 && (p.mean_dt * rate - 1.0).abs() <= 1e-9)
    {
        return Err(crate::error::Error::Checkpoint {
            what: "pending proposal at another rate than the state's",
        });
    }
    Ok(())
}
