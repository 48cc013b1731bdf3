//! The proposal engine: how a low-rank scheme stores its particles and draws ordered
//! pairs at rate `Â(x_p, x_q)/V` from a rank-R bound `Â = Σ_k â_k b̂_kᵀ`.
//!
//! Two layouts implement it: [`TreeEngine`](super::TreeEngine) (the paper's per-size
//! weights in one segment tree) and [`BucketedEngine`](super::BucketedEngine) (the bound
//! coarsened to size buckets, alias tables, lazily emptied slots). The event loop in
//! [`LowRankMc`](super::LowRankMc) owns the clock, the population and the kernel; an
//! [`EventRule`](super::rule::EventRule) decides each proposal. A new rule (a
//! temperature-dependent rate, a DSMC collision with velocities) reuses either engine.

use crate::checkpoint::{Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::scheme::population::Population;
use alloc::borrow::Cow;
use rand_core::Rng;

/// A proposed ordered pair of distinct particles: their sizes and where the engine keeps
/// them. The bound at the pair comes from [`ProposalEngine::bounds`], only when a rule
/// asks (for an exact bound on the per-size layout it never does, and the factor rows —
/// cache misses at large M — are not touched).
#[derive(Clone, Copy, Debug)]
pub struct Candidate<L> {
    /// Size of the first particle.
    pub x: u64,
    /// Size of the second particle.
    pub y: u64,
    /// The engine's handle on the two particles.
    pub at: L,
}

/// What an accepted proposal does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Outcome {
    /// The two particles merge into one of size `size`.
    Merge {
        /// The merged size.
        size: u64,
    },
    /// The two particles collide and separate (no count changes; a rule with per-size
    /// state may change it).
    Bounce,
}

/// What an engine's `low` (the second of [`ProposalEngine::bounds`]) is, and so how a
/// rule may accept without evaluating the kernel (a squeeze: a uniform under a lower
/// bound of K accepts, the same decision the kernel would give, on the same draws).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Low {
    /// Built from the smallest factors the engine's coarsening allows: `K ≥ ρ · low`
    /// with the kernel's acceptance floor ρ.
    Factors,
    /// Always the bound itself (the per-size layout's factor bound): `K ≥ ρ · low`.
    Bound,
    /// The kernel's infimum over the proposal's block
    /// ([`CoagulationKernel::inf_block`]):
    /// `K ≥ low`, whatever ρ.
    Infimum,
}

/// A particle layout that proposes pairs from a rank-R bound (see the module docs).
///
/// The event loop calls, per proposal, [`propose`](Self::propose); after a rule accepts
/// with an outcome, [`prepare`](Self::prepare) (the fallible part, before anything
/// changes), [`apply`](Self::apply), then [`double`](Self::double) when the population
/// is due for particle doubling, and [`settle`](Self::settle). Before the first
/// proposal and whenever [`needs_refresh`](Self::needs_refresh) says so it calls
/// [`refresh`](Self::refresh) for the current total rate.
pub trait ProposalEngine<const R: usize>: Sized {
    /// Where a candidate's particles live.
    type Loc: Copy;
    /// The checkpoint tag of a scheme on this engine.
    const TAG: u64;

    /// The engine over `counts[i − 1] = N_i` for the population `pop` (validated by the
    /// caller), with the kernel's bound. Errors: a kernel without a rank-R bound,
    /// invalid factors, the memory budget.
    fn build<K: CoagulationKernel>(kernel: &K, counts: &[u64], pop: &Population) -> Result<Self>;

    /// Prepares the proposal process (rebuilds what an event left stale) and returns
    /// `S_A`: proposals then arrive at rate `S_A / V`. Errors: a total rate that
    /// overflowed, a failed internal invariant.
    fn refresh<G: Rng + ?Sized>(&mut self, pop: &Population, rng: &mut G) -> Result<f64>;

    /// Whether proposal times may be drawn in batches (the rate stays fixed until an
    /// accepted event asks for a refresh). By default no: every event changes the
    /// rate.
    #[inline]
    fn batches(&self, _pop: &Population) -> bool {
        false
    }

    /// An accepted event changed the proposal rate: refresh before the next proposal.
    /// By default always.
    #[inline]
    fn needs_refresh(&self) -> bool {
        true
    }

    /// Whether a rejected proposal may also have changed the proposal rate (an engine
    /// that tightens its majorant when it draws): the loop then asks
    /// [`needs_refresh`](Self::needs_refresh) after rejections too.
    const REFRESH_AFTER_REJECT: bool = false;

    /// What the engine's `low` at a pair is (the second of [`bounds`](Self::bounds)).
    const LOW: Low;

    /// Draws one proposal; `None` when thinning rejects it (an empty slot, a rounding
    /// ghost, the particle paired with itself).
    fn propose<G: Rng + ?Sized>(&mut self, rng: &mut G) -> Option<Candidate<Self::Loc>>;

    /// `(bound, low)` at a proposed pair: `bound`, what the acceptance divides by
    /// (`Â(x, y) + Â(y, x)`, or a block's `sup_block`), and `low ≤ bound`, what a rule
    /// squeezes with (see [`Low`]).
    fn bounds(&self, at: &Self::Loc) -> (f64, f64);

    /// The fallible part of applying `outcome` (growing the size table for a new
    /// largest size): on error nothing has changed.
    fn prepare<K: CoagulationKernel>(
        &mut self,
        kernel: &K,
        outcome: &Outcome,
        pop: &Population,
    ) -> Result<()>;

    /// Applies an accepted `outcome` of candidate `c` to the particles.
    fn apply(&mut self, c: &Candidate<Self::Loc>, outcome: &Outcome);

    /// Doubles every count (particle doubling; `pop` is already doubled).
    fn double(&mut self, pop: &Population);

    /// Housekeeping after an event (resyncs, drift control).
    fn settle(&mut self, pop: &Population);

    /// Calls `f(size, N)` for every occupied size, ascending, allocating no more than
    /// the particles of one bucket (no dense count vector).
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64));

    /// The counts, `N_i` at index `i − 1`, for `i = 1..=max_size()`.
    fn counts(&self) -> Cow<'_, [u64]>;

    /// Current maximum size M (a power of two).
    fn max_size(&self) -> u64;

    /// The total proposal rate `S_A` as the last refresh left it, when the engine's
    /// draw state is current (no refresh pending), without drawing: a restored clock
    /// that resumes without a refresh must match it (what a run that stopped between
    /// two proposals leaves; a crafted checkpoint that claims otherwise is refused).
    fn rate_now(&self) -> Option<f64>;

    /// Whether [`reweigh`](Self::reweigh) and [`count`](Self::count) are supported
    /// (needed by rules that move factors, [`EventRule::REWEIGHS`](super::EventRule::REWEIGHS)).
    const REWEIGHS: bool = false;

    /// The number of size-`size` particles (only called when [`REWEIGHS`](Self::REWEIGHS)).
    fn count(&self, _size: u64) -> u64 {
        0
    }

    /// Re-reads the factors of `size` from `kernel` (whose per-size state changed) and
    /// updates the proposal weights; the factors were validated by the rule (only
    /// called when [`REWEIGHS`](Self::REWEIGHS), for a size within [`max_size`](Self::max_size)).
    fn reweigh<K: CoagulationKernel>(&mut self, _kernel: &K, _size: u64) {}

    /// Re-reads every size's factors from `kernel` and rebuilds the proposal weights
    /// (only called when [`REWEIGHS`](Self::REWEIGHS)).
    fn refactor<K: CoagulationKernel>(&mut self, _kernel: &K) {}

    /// Whether the engine edits single particles for processes beside coagulation
    /// ([`draw_particle`](Self::draw_particle), [`remove_particle`](Self::remove_particle),
    /// [`add_particle`](Self::add_particle)); otherwise the facade reads and replaces
    /// the whole state.
    const EDITS: bool = false;

    /// A particle drawn uniformly (`by_mass`: in proportion to its size) from the `n`
    /// particles, its size and where it is; `None` without particles (or when a
    /// degenerate random stream rejects `MAX_TRIES` draws in a row: no event).
    fn draw_particle<G: Rng + ?Sized>(
        &self,
        _by_mass: bool,
        _n: u64,
        _rng: &mut G,
    ) -> Option<(u64, (usize, u64))> {
        None
    }

    /// Removes the particle of size `x` a draw found at `at` (nothing changed since).
    fn remove_particle(&mut self, _at: (usize, u64), _x: u64) {}

    /// Adds a particle of size `x`, growing M first as needed (the fallible part: on
    /// error no particle was added). `pop` is the population before the addition.
    fn add_particle<K: CoagulationKernel>(
        &mut self,
        _kernel: &K,
        _x: u64,
        _pop: &Population,
    ) -> Result<()> {
        Err(Error::Unsupported {
            what: "single-particle edits on this layout",
        })
    }

    /// The particle-number reference rose to `pop.n0` (the quantisation that depends on
    /// it is redone).
    fn rereference(&mut self, _pop: &Population) {}

    /// Writes the engine's state after the scheme's common fields.
    fn save(&self, w: &mut Writer);

    /// Reads an engine written by `save` for maximum size `m` and population `pop`,
    /// validating it; the caller installs it only on success.
    fn load<K: CoagulationKernel>(
        kernel: &K,
        m: u64,
        pop: &Population,
        r: &mut Reader,
    ) -> Result<Self>;
}

/// The error of a kernel whose rank is not the scheme's R.
pub(crate) fn rank_mismatch() -> Error {
    Error::Unsupported {
        what: "kernel rank differs from the scheme's R (or the kernel has no low-rank bound)",
    }
}
