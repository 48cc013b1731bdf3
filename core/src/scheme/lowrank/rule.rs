//! Event rules: what happens to a proposed pair. A rule sees the candidate (sizes, the
//! bound and its squeeze base) and the kernel, accepts or rejects — the thinning that
//! turns proposals at rate `Â + Âᵀ` into events at rate K — and names the outcome.
//!
//! [`Coagulate`] is plain coagulation (Osinsky 2023): accept with `K/(Â + Âᵀ)`,
//! squeezed with the kernel's acceptance floor ρ (`K ≥ ρ (Â + Âᵀ)`, so a uniform below
//! `ρ · low` accepts without evaluating K), and merge the pair.
//!
//! A rule may also carry per-size state in its kernel and change the bound's factors
//! after an event ([`EventRule::REWEIGHS`]): the temperature-dependent scheme
//! ([`temperature`](super::temperature)) keeps a partial temperature per size, lets a collision
//! bounce ([`Outcome::Bounce`]) or merge, and moves the factor rows of the sizes whose
//! temperature changed. Such a rule runs on an engine that can reweigh a size (the
//! per-size trees).

use super::proposal::{Candidate, Low, Outcome};
use crate::checkpoint::{Reader, Writer};
use crate::error::Result;
use crate::kernel::{CoagulationKernel, bounded_rate};
use crate::random::open_unit;
use rand_core::Rng;

/// A kernel whose acceptance the squeeze decides is still evaluated when the run's
/// `SPOT_CHECK`-th proposal (and every multiple) is accepted without it, so a kernel
/// that turns NaN or exceeds its bound is caught (deterministic: the random stream is
/// the same with or without the check).
pub const SPOT_CHECK: u64 = 1024;

/// The sizes whose bound factors a rule changed after an event (at most three: the
/// pair and the merged size).
pub type Reweighed = heapless::Vec<u64, 3>;

/// Decides proposals (see the module docs).
pub trait EventRule<K>: Sized {
    /// The rule for `kernel` (e.g. its acceptance floor).
    fn for_kernel(kernel: &K) -> Self;

    /// Accepts (`Some(outcome)`) or rejects (`None`) candidate `c`; `bounds()` gives
    /// `(bound, low)` at the pair (see [`ProposalEngine::bounds`](super::ProposalEngine::bounds)),
    /// `low` says what the engine's `low` is. `spot` asks for
    /// a kernel evaluation even if the squeeze accepts (see [`SPOT_CHECK`]). A kernel
    /// that returns an invalid rate or exceeds the bound is an error.
    fn decide<L, G: Rng + ?Sized>(
        &mut self,
        kernel: &K,
        c: &Candidate<L>,
        bounds: impl FnOnce() -> (f64, f64),
        low: Low,
        spot: bool,
        rng: &mut G,
    ) -> Result<Option<Outcome>>;

    /// Whether the rule changes the bound's factors after events (then the engine must
    /// support [`ProposalEngine::reweigh`](super::ProposalEngine::reweigh); a scheme
    /// refuses the pair otherwise).
    const REWEIGHS: bool = false;

    /// The checkpoint tag of a scheme with this rule, when it differs from the
    /// engine's (the rule's state is part of the checkpoint).
    const TAG: Option<u64> = None;

    /// The fallible part of an accepted event, before anything changes: `count(s)` is
    /// the number of size-s particles before the event. A rule with per-size state
    /// computes and validates its new state here (and reserves memory in `kernel`,
    /// which must not change what the kernel computes); the event is refused on error.
    fn plan(
        &mut self,
        _kernel: &mut K,
        _c: (u64, u64),
        _outcome: &Outcome,
        _count: &dyn Fn(u64) -> u64,
    ) -> Result<()> {
        Ok(())
    }

    /// Installs what [`plan`](Self::plan) computed, after the engine applied the event;
    /// returns the sizes whose factors changed (the scheme reweighs them).
    fn commit(&mut self, _kernel: &mut K) -> Reweighed {
        Reweighed::new()
    }

    /// Whether every factor row must be re-read from the kernel now (after
    /// [`commit`](Self::commit); e.g. per-size maxima recomputed from scratch): the
    /// scheme then calls [`ProposalEngine::refactor`](super::ProposalEngine::refactor).
    fn refactor_due(&mut self) -> bool {
        false
    }

    /// Whether the scheme doubles its particles when half are gone (Osinsky §2). A rule
    /// whose particles carry more than a size (DSMC's velocities) says no: copies would
    /// not be independent.
    const DOUBLES: bool = true;

    /// Checks that `counts` (`N_i` at index `i − 1`) agree with the state the kernel
    /// carries (DSMC: one velocity per particle); called wherever the counts are set.
    fn check_counts(_kernel: &K, _counts: &[u64]) -> Result<()> {
        Ok(())
    }

    /// Writes the rule's per-size state (in the checkpoint, before the engine).
    fn save(&self, _kernel: &K, _w: &mut Writer) {}

    /// Reads state written by [`save`](Self::save): `Some(kernel)` is `kernel` with the
    /// restored state, which the engine is then validated against and the scheme
    /// installs on success; `None` when the rule has no state.
    fn load(&self, _kernel: &K, _r: &mut Reader) -> Result<Option<K>> {
        Ok(None)
    }
}

/// Plain coagulation: accept with `K/(Â + Âᵀ)`, merge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coagulate {
    /// The acceptance floor ρ ∈ [0, 1] of the kernel.
    floor: f64,
}

impl<K: CoagulationKernel> EventRule<K> for Coagulate {
    fn for_kernel(kernel: &K) -> Self {
        Coagulate {
            floor: floor_of(kernel),
        }
    }

    #[inline(always)]
    fn decide<L, G: Rng + ?Sized>(
        &mut self,
        kernel: &K,
        c: &Candidate<L>,
        bounds: impl FnOnce() -> (f64, f64),
        low: Low,
        spot: bool,
        rng: &mut G,
    ) -> Result<Option<Outcome>> {
        let merge = Outcome::Merge {
            size: c.x.saturating_add(c.y),
        };
        if self.floor >= 1.0 && low == Low::Bound && !spot {
            // an exact bound on exact per-size factors: every pair is accepted, and the
            // bound is not even looked up
            return Ok(Some(merge));
        }
        // (a block's infimum bounds K itself)
        let floor = if low == Low::Infimum { 1.0 } else { self.floor };
        let (bound, low) = bounds();
        if !thin(floor, kernel, c.x as f64, c.y as f64, bound, low, spot, rng)? {
            return Ok(None);
        }
        Ok(Some(merge))
    }
}

/// The thinning of a proposal at a pair of sizes `x, y` whose bound is `bound` and whose
/// squeeze base is `low ≤ bound`: `Ok(true)` with probability `K(x, y)/bound`. A uniform
/// below `floor · low` accepts without evaluating K (`floor` is the kernel's acceptance
/// floor ρ, `K ≥ ρ · low`); `spot` evaluates K anyway (see [`SPOT_CHECK`]). A kernel that
/// returns an invalid rate or exceeds the bound is an error.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn thin<K: CoagulationKernel + ?Sized, G: Rng + ?Sized>(
    floor: f64,
    kernel: &K,
    x: f64,
    y: f64,
    bound: f64,
    low: f64,
    spot: bool,
    rng: &mut G,
) -> Result<bool> {
    // `floor · low ≥ bound`: the kernel equals the bound (an exact pair), accept; a
    // uniform under the bound that falls below the squeeze accepts without K (a NaN
    // squeeze never does: K is evaluated)
    let squeeze = floor * low;
    let sure = squeeze >= bound;
    let evaluated = !sure && {
        let u = bound * open_unit(rng);
        let under = u <= squeeze;
        !under && {
            let k = bounded_rate(
                kernel,
                x,
                y,
                bound,
                "proposal bound (low-rank A + Aᵀ, or a block's sup_block)",
            )?;
            if u > k {
                return Ok(false);
            }
            true
        }
    };
    if !evaluated && spot {
        // accepted without K: a spot check now and then, of the bound and of the floor
        // the acceptance relied on (a kernel below it, e.g. an exact low-rank claim
        // whose A + Aᵀ is twice the kernel, would be simulated at the wrong rate)
        let k = bounded_rate(
            kernel,
            x,
            y,
            bound,
            "proposal bound (low-rank A + Aᵀ, or a block's sup_block)",
        )?;
        let relied = squeeze.min(bound);
        if k < relied * (1.0 - 1e-9) {
            return Err(crate::Error::BoundExceeded {
                name: "acceptance floor ρ·(A + Aᵀ) (an exact low-rank kernel has ρ = 1), or lower bound over a block (inf_block)",
                rate: k,
                bound: relied,
            });
        }
    }
    Ok(true)
}

/// The acceptance floor ρ ∈ [0, 1] of `kernel` (1 for an exact bound).
pub(crate) fn floor_of<K: CoagulationKernel + ?Sized>(kernel: &K) -> f64 {
    if kernel.low_rank_is_exact() {
        1.0
    } else {
        let f = kernel.low_rank_floor();
        // (a NaN floor squeezes nothing)
        if f.is_nan() { 0.0 } else { f.clamp(0.0, 1.0) }
    }
}
