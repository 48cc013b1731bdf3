//! The registry's `lowrank` scheme: the bucketed layout with the engine chosen by the
//! system's size — [`BucketedCounted`] up to [`COUNTED_UP_TO`] initial particles (exact
//! bucket counts in a sum tree: nothing stale when almost every event changes the
//! distribution), [`Bucketed`] above (slots and alias tables: O(1) per proposal) — or
//! by the kernel: block majorants ([`Blocks`](super::Blocks)) for a kernel that says
//! its low-rank bound is loose (`CoagulationKernel::low_rank_is_loose`) or has none,
//! and bounds blocks (`CoagulationKernel::sup_block`).
//!
//! The choice is made per scheme, not per proposal: each variant is a whole
//! [`LowRankMc`] with its own event loop, so neither pays for the other's code (a
//! dispatch inside the engine cost the large systems 20 %; see
//! `docs/design/bucketed-layout.md`). Replacing the counts chooses again, and a
//! checkpoint restores into whichever engine wrote it. A caller who measured its own
//! crossover pins the engine with [`AutoBucketed::with_mode`]; a pinned scheme keeps its
//! engine through `set_counts` and refuses a checkpoint the other engine wrote.

use super::{
    BlockEngine, Bucketed, BucketedCounted, COUNTED_UP_TO, Coagulate, LowRankMc, ProposalEngine,
};
use crate::checkpoint::{Checkpoint, Reader, Writer};
use crate::error::Result;
use crate::kernel::CoagulationKernel;
use crate::observe::Observe;
use crate::scheme::{Budget, Scheme, StepReport};
use alloc::borrow::Cow;
use rand_core::Rng;

pub use crate::scheme::facade::BucketMode;

/// The low-rank scheme with its engine chosen by the kernel (block majorants, see
/// [`prefers_blocks`]) and the initial particle number, or pinned (see the module
/// docs). `W` must be `2R`.
///
/// # Example
/// ```
/// use coagula_core::kernel::Coagulation;
/// use coagula_core::scheme::{Scheme, lowrank::{AutoBucketed, BucketMode}};
/// let k = Coagulation::constant(1.0).unwrap();
/// let small = AutoBucketed::<_, 1, 2>::new(k, &[500], 500.0).unwrap();
/// let large = AutoBucketed::<_, 1, 2>::new(k, &[1 << 20], 1e6).unwrap();
/// assert_eq!((small.mode(), large.mode()), (BucketMode::Counted, BucketMode::Slots));
/// // pinned: the slot engine for a small system
/// let pinned = small.with_mode(Some(BucketMode::Slots)).unwrap();
/// assert_eq!((pinned.mode(), pinned.pinned()), (BucketMode::Slots, Some(BucketMode::Slots)));
/// ```
pub struct AutoBucketed<K, const R: usize, const W: usize> {
    engine: Engine<K, R, W>,
    /// The engine the caller pinned (`None`: chosen by size).
    pin: Option<BucketMode>,
}

/// The scheme in use.
#[allow(clippy::large_enum_variant)] // (one per simulation; boxing adds a pointer chase)
enum Engine<K, const R: usize, const W: usize> {
    /// Above [`COUNTED_UP_TO`] initial particles, or pinned.
    Slots(Bucketed<K, R, W>),
    /// Up to [`COUNTED_UP_TO`] initial particles, or pinned.
    Counted(BucketedCounted<K, R, W>),
    /// For a loose or missing low-rank bound, or pinned.
    Blocks(LowRankMc<K, R, BlockEngine>),
}

/// `$body` with `$s` bound to whichever scheme is in use.
macro_rules! either {
    ($self:expr, $s:ident => $body:expr) => {
        match $self {
            Engine::Slots($s) => $body,
            Engine::Counted($s) => $body,
            Engine::Blocks($s) => $body,
        }
    };
}

/// Whether `kernel` runs on block majorants when not pinned: its low-rank bound is
/// loose, missing or of a rank above the low-rank engines' 4, and it bounds blocks.
pub fn prefers_blocks<K: CoagulationKernel>(kernel: &K) -> bool {
    (kernel.low_rank_is_loose() || !(1..=4).contains(&kernel.rank()))
        && kernel.sup_block(1.0, 2.0, 1.0, 2.0).is_some()
}

/// The engine for `kernel` and `Σ counts` initial particles.
fn mode_for<K: CoagulationKernel>(kernel: &K, counts: &[u64]) -> BucketMode {
    if prefers_blocks(kernel) {
        return BucketMode::Blocks;
    }
    let n0 = counts
        .iter()
        .try_fold(0u64, |a, &c| a.checked_add(c))
        .unwrap_or(u64::MAX);
    if n0 > COUNTED_UP_TO {
        BucketMode::Slots
    } else {
        BucketMode::Counted
    }
}

/// A scheme on engine `E` with `from`'s kernel, limits, clock option, time and totals,
/// holding `counts` in `volume` (as `set_counts` would).
fn carried<K: CoagulationKernel + Clone, const R: usize, E1, E2>(
    from: &LowRankMc<K, R, E1>,
    counts: &[u64],
    volume: f64,
) -> Result<LowRankMc<K, R, E2>>
where
    E1: ProposalEngine<R>,
    E2: ProposalEngine<R>,
{
    let mut s = LowRankMc::<K, R, E2>::new_with_memory_budget(
        from.kernel.clone(),
        &[2],
        1.0,
        from.pop.memory_budget,
    )?
    .with_size_limit(from.pop.size_limit)
    .with_batched_clock(from.batched);
    s.set_counts(counts, volume)?;
    s.time = from.time;
    s.totals = from.totals;
    Ok(s)
}

impl<K: CoagulationKernel + Clone, const R: usize, const W: usize> AutoBucketed<K, R, W> {
    /// Starts from `counts[i − 1] = N_i` in `volume` (errors as
    /// [`LowRankMc::new`]), on the engine for `Σ N_i` particles.
    pub fn new(kernel: K, counts: &[u64], volume: f64) -> Result<Self> {
        Self::new_with_memory_budget(kernel, counts, volume, super::DEFAULT_MEMORY_BUDGET)
    }

    /// [`new`](Self::new) with the growing tables capped at `budget` bytes.
    pub fn new_with_memory_budget(
        kernel: K,
        counts: &[u64],
        volume: f64,
        budget: usize,
    ) -> Result<Self> {
        Self::new_with_mode(kernel, counts, volume, budget, None)
    }

    /// [`new_with_memory_budget`](Self::new_with_memory_budget) on the engine `pin`
    /// (`None`: chosen by the kernel and the particle number), pinned as by
    /// [`with_mode`](Self::with_mode).
    pub fn new_with_mode(
        kernel: K,
        counts: &[u64],
        volume: f64,
        budget: usize,
        pin: Option<BucketMode>,
    ) -> Result<Self> {
        let engine = match pin.unwrap_or_else(|| mode_for(&kernel, counts)) {
            BucketMode::Slots => Engine::Slots(Bucketed::new_with_memory_budget(
                kernel, counts, volume, budget,
            )?),
            BucketMode::Counted => Engine::Counted(BucketedCounted::new_with_memory_budget(
                kernel, counts, volume, budget,
            )?),
            BucketMode::Blocks => Engine::Blocks(LowRankMc::new_with_memory_budget(
                kernel, counts, volume, budget,
            )?),
        };
        Ok(AutoBucketed { engine, pin })
    }

    /// Pins the engine (`Some`) or lets the size choose it (`None`, the default): the
    /// state moves to the pinned engine if it is not there (time, totals and options
    /// carry over); later `set_counts` keep it, and a checkpoint of the other engine is
    /// refused. Meant at construction, for a caller who measured its own crossover. An
    /// error (the other engine's memory budget) drops the scheme; see
    /// [`set_mode`](Self::set_mode) to keep it.
    pub fn with_mode(mut self, pin: Option<BucketMode>) -> Result<Self> {
        self.set_mode(pin)?;
        Ok(self)
    }

    /// [`with_mode`](Self::with_mode) in place; errors leave the scheme unchanged.
    /// Unpinning (`None`) keeps the engine in use until the counts are replaced.
    pub fn set_mode(&mut self, pin: Option<BucketMode>) -> Result<()> {
        if let Some(mode) = pin
            && mode != self.mode()
        {
            let counts = self.counts().into_owned();
            self.engine = self.on(mode, &counts, self.volume())?;
        }
        self.pin = pin;
        Ok(())
    }

    /// See [`LowRankMc::with_size_limit`].
    pub fn with_size_limit(self, limit: u64) -> Self {
        let engine = match self.engine {
            Engine::Slots(s) => Engine::Slots(s.with_size_limit(limit)),
            Engine::Counted(s) => Engine::Counted(s.with_size_limit(limit)),
            Engine::Blocks(s) => Engine::Blocks(s.with_size_limit(limit)),
        };
        AutoBucketed { engine, ..self }
    }

    /// See [`LowRankMc::with_batched_clock`].
    pub fn with_batched_clock(self, on: bool) -> Self {
        let engine = match self.engine {
            Engine::Slots(s) => Engine::Slots(s.with_batched_clock(on)),
            Engine::Counted(s) => Engine::Counted(s.with_batched_clock(on)),
            Engine::Blocks(s) => Engine::Blocks(s.with_batched_clock(on)),
        };
        AutoBucketed { engine, ..self }
    }

    /// The engine in use.
    pub fn mode(&self) -> BucketMode {
        match self.engine {
            Engine::Slots(_) => BucketMode::Slots,
            Engine::Counted(_) => BucketMode::Counted,
            Engine::Blocks(_) => BucketMode::Blocks,
        }
    }

    /// The pinned engine, if any (see [`with_mode`](Self::with_mode)).
    pub fn pinned(&self) -> Option<BucketMode> {
        self.pin
    }

    /// See [`LowRankMc::counts`].
    pub fn counts(&self) -> Cow<'_, [u64]> {
        either!(&self.engine, s => s.counts())
    }

    /// See [`LowRankMc::max_size`].
    pub fn max_size(&self) -> usize {
        either!(&self.engine, s => s.max_size())
    }

    /// See [`LowRankMc::for_each_count`].
    pub fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) {
        either!(&self.engine, s => s.for_each_count(f))
    }

    /// See [`LowRankMc::set_kernel`].
    pub fn set_kernel(&mut self, kernel: K) -> Result<()> {
        either!(&mut self.engine, s => s.set_kernel(kernel))
    }

    /// See [`LowRankMc::edits`].
    pub fn edits(&self) -> bool {
        either!(&self.engine, s => s.edits())
    }

    /// See [`LowRankMc::draw_particle`].
    pub fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(u64, u64)> {
        either!(&self.engine, s => s.draw_particle(by_mass, rng))
    }

    /// See [`LowRankMc::remove_drawn`].
    pub fn remove_drawn(&mut self, x: u64, handle: u64) -> Result<()> {
        either!(&mut self.engine, s => s.remove_drawn(x, handle))
    }

    /// See [`LowRankMc::add_particle`].
    pub fn add_particle(&mut self, x: u64) -> Result<()> {
        either!(&mut self.engine, s => s.add_particle(x))
    }

    /// See [`LowRankMc::set_doubling`].
    pub fn set_doubling(&mut self, on: bool) {
        either!(&mut self.engine, s => s.set_doubling(on))
    }

    /// See [`LowRankMc::set_time`].
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        either!(&mut self.engine, s => s.set_time(t))
    }

    /// See [`LowRankMc::set_counts`]; unless pinned, the engine is chosen again for the
    /// new particle number (time, totals and limits carry over). Errors leave the scheme
    /// unchanged.
    pub fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        let mode = self
            .pin
            .unwrap_or_else(|| either!(&self.engine, s => mode_for(&s.kernel, counts)));
        if mode == self.mode() {
            return either!(&mut self.engine, s => s.set_counts(counts, volume));
        }
        self.engine = self.on(mode, counts, volume)?;
        Ok(())
    }

    /// See [`LowRankMc::set_pairs`] (the engine chosen as by
    /// [`set_counts`](Self::set_counts)).
    pub fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
        let (limit, budget) = either!(&self.engine, s => (s.pop.size_limit, s.pop.memory_budget));
        let dense = crate::scheme::population::dense_from_pairs(sizes, counts, limit, budget)?;
        self.set_counts(&dense, volume)
    }

    /// A scheme on engine `mode` holding `counts` in `volume`, with this one's kernel,
    /// options, time and totals (see `carried`).
    fn on(&self, mode: BucketMode, counts: &[u64], volume: f64) -> Result<Engine<K, R, W>> {
        Ok(match mode {
            BucketMode::Slots => {
                Engine::Slots(either!(&self.engine, s => carried(s, counts, volume))?)
            }
            BucketMode::Counted => {
                Engine::Counted(either!(&self.engine, s => carried(s, counts, volume))?)
            }
            BucketMode::Blocks => {
                Engine::Blocks(either!(&self.engine, s => carried(s, counts, volume))?)
            }
        })
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> Scheme for AutoBucketed<K, R, W> {
    fn time(&self) -> f64 {
        either!(&self.engine, s => s.time())
    }
    fn totals(&self) -> StepReport {
        either!(&self.engine, s => Scheme::totals(s))
    }

    fn advance_within<G: Rng + ?Sized>(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport> {
        either!(&mut self.engine, s => s.advance_within(t, budget, rng))
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> Observe for AutoBucketed<K, R, W> {
    fn volume(&self) -> f64 {
        either!(&self.engine, s => s.volume())
    }
    fn particles(&self) -> u64 {
        either!(&self.engine, s => s.particles())
    }
    fn moment(&self, order: f64) -> f64 {
        either!(&self.engine, s => s.moment(order))
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        either!(&self.engine, s => s.concentration(a, b))
    }
    fn number_density(&self, x: f64) -> f64 {
        either!(&self.engine, s => s.number_density(x))
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        either!(&self.engine, s => s.points(f))
    }
    fn gel_mass(&self) -> Option<f64> {
        either!(&self.engine, s => s.gel_mass())
    }
}

impl<K: CoagulationKernel + Clone, const R: usize, const W: usize> Checkpoint
    for AutoBucketed<K, R, W>
{
    fn save(&self, w: &mut Writer) {
        either!(&self.engine, s => s.save(w))
    }

    /// Into whichever engine wrote the checkpoint (its tag says which); errors leave
    /// the scheme unchanged.
    fn restore(&mut self, r: &mut Reader) -> Result<()> {
        let mut probe = r.clone();
        let tag = (probe.u64(), probe.u64(), probe.u64());
        let writer = match tag {
            (Ok(_), Ok(_), Ok(t)) => [
                (
                    LowRankMc::<K, R, super::BucketedEngine<R, W>>::tag(),
                    BucketMode::Slots,
                ),
                (
                    LowRankMc::<K, R, super::CountedEngine<R, W>, Coagulate>::tag(),
                    BucketMode::Counted,
                ),
                (LowRankMc::<K, R, BlockEngine>::tag(), BucketMode::Blocks),
            ]
            .into_iter()
            .find(|&(tag, _)| tag == t)
            .map(|(_, mode)| mode),
            _ => None,
        };
        match writer {
            Some(theirs) if theirs != self.mode() => {
                if let Some(pin) = self.pin {
                    return Err(crate::error::Error::Checkpoint {
                        what: match pin {
                            BucketMode::Slots => {
                                "another engine's; this scheme is pinned to the slot engine"
                            }
                            BucketMode::Counted => {
                                "another engine's; this scheme is pinned to the counted engine"
                            }
                            BucketMode::Blocks => {
                                "another engine's; this scheme is pinned to block majorants"
                            }
                        },
                    });
                }
                // (a blank of the writer's engine, with this one's kernel and options)
                let mut other = self.on(theirs, &[2], 1.0)?;
                either!(&mut other, s => s.restore(r))?;
                self.engine = other;
                Ok(())
            }
            _ => either!(&mut self.engine, s => s.restore(r)),
        }
    }
}

impl<K: CoagulationKernel, const R: usize, const W: usize> core::fmt::Debug
    for AutoBucketed<K, R, W>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        either!(&self.engine, s => s.fmt(f))
    }
}
