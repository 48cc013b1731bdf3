//! The object-safe facade over every scheme, and the one registry that builds them.
//!
//! The C ABI, the CLI and the conformance tests reach every scheme through
//! [`Simulation`] trait objects made by [`build`]; the list of schemes is [`SCHEMES`].
//! Adding a scheme is one entry in [`SCHEMES`], one arm in [`build`] and one
//! [`Facet`] impl (what the scheme can read and replace) — the front ends pick it up.
//!
//! The facade is generic over the kernel type `K`, the fragmentation kernel `F` and the
//! generator `G`, so a front end fixes them once (the C ABI: its kernel handles and its
//! random source; the CLI: the built-in kernels and [`crate::random::Generator`]). Dispatch
//! is dynamic per call (`advance_to`, an observation), never per random draw or kernel
//! evaluation: inside a call the scheme runs monomorphised.
//!
//! # Example
//! ```
//! use coagula_core::kernel::{Coagulation, NoFragmentation};
//! use coagula_core::random::{Generator, generator};
//! use coagula_core::scheme::registry::{self, Init, Options, SchemeId, Simulation};
//! let k = Coagulation::constant(1.0).unwrap();
//! let init = Init::Counts { counts: &[10_000], volume: 10_000.0 };
//! let mut rng = generator(7, 0);
//! // the same set-up on every size-count scheme of the registry
//! for info in registry::SCHEMES.iter().filter(|s| s.accepts(&init)) {
//!     let mut sim: Box<dyn Simulation<_, _, Generator>> =
//!         registry::build(info.id, k, NoFragmentation, &init, &Options::default()).unwrap();
//!     sim.advance_to(1.0, &mut rng).unwrap();
//!     // N(t)/V = 1/(1 + t/2) for K = 1
//!     assert!((sim.moment(0.0) - 1.0 / 1.5).abs() < 0.02, "{}", info.name);
//! }
//! ```

use super::baseline::{AcceptanceRejection, Inverse};
use super::eventflow::{Dsa, DsaCounts, Mfa};
use super::lowrank::{
    AutoBucketed, BinaryTree, EventRule, LowRank, LowRankMc, LowRankSizes, ProposalEngine,
};
use super::massflow::{MassFlow, PointSource, Sorting};
use super::{Budget, Scheme, StepReport};
use crate::checkpoint::{Checkpoint, Reader, Writer};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::observe::Observe;
use alloc::borrow::Cow;
use alloc::boxed::Box;
use core::marker::PhantomData;
use rand_core::Rng;

/// Identifies a scheme of the registry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SchemeId {
    /// Lécot et al. 2019: time-driven mass flow (QMC, MC, RQMC).
    MassFlow,
    /// Osinsky 2023: low-rank MC, bucketed layout (the default low-rank layout).
    LowRank,
    /// Osinsky 2023: low-rank MC with the paper's per-size trees (8-ary layout).
    LowRankTree,
    /// Osinsky 2023: low-rank MC with the paper's binary segment trees (for comparison).
    LowRankBinaryTree,
    /// The inverse method (Gillespie on sizes), low-rank's baseline.
    Inverse,
    /// Acceptance–rejection with the kernel's supremum, low-rank's baseline.
    Rejection,
    /// Eibeck & Wagner 2000: the event-driven mass flow algorithm.
    Mfa,
    /// Eibeck & Wagner 2000: direct simulation (Marcus–Lushnikov).
    Dsa,
    /// Direct simulation over size counts (integer sizes).
    DsaCounts,
    /// Osinsky 2023: low-rank MC over particle sizes (continuous or sparse).
    LowRankSizes,
}

/// What a scheme's state is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateKind {
    /// Particle sizes (read with [`State::Sizes`], replaced with `set_sizes`).
    Sizes,
    /// Counts `N_i` of integer sizes in a volume (`set_counts`).
    Counts,
}

/// One registered scheme.
#[derive(Clone, Copy, Debug)]
pub struct SchemeInfo {
    /// Its identifier.
    pub id: SchemeId,
    /// Its name in the CLI and the C ABI's documentation.
    pub name: &'static str,
    /// Its state.
    pub state: StateKind,
    /// What it is, in one line.
    pub summary: &'static str,
}

impl SchemeInfo {
    /// Whether the scheme starts from `init` (counts or sizes).
    pub fn accepts(&self, init: &Init<'_>) -> bool {
        matches!(
            (self.state, init),
            (StateKind::Counts, Init::Counts { .. }) | (StateKind::Sizes, Init::Sizes { .. })
        )
    }
}

/// Every scheme, in the order front ends list them.
pub const SCHEMES: &[SchemeInfo] = &[
    SchemeInfo {
        id: SchemeId::MassFlow,
        name: "massflow",
        state: StateKind::Sizes,
        summary: "Lecot et al. 2019: time-driven mass flow, QMC/MC/RQMC, coagulation-fragmentation",
    },
    SchemeInfo {
        id: SchemeId::LowRank,
        name: "lowrank",
        state: StateKind::Counts,
        summary: "Osinsky 2023: low-rank Monte Carlo, bucketed layout (the default)",
    },
    SchemeInfo {
        id: SchemeId::LowRankTree,
        name: "lowrank-tree",
        state: StateKind::Counts,
        summary: "Osinsky 2023: low-rank Monte Carlo with per-size segment trees",
    },
    SchemeInfo {
        id: SchemeId::LowRankBinaryTree,
        name: "lowrank-binary-tree",
        state: StateKind::Counts,
        summary: "Osinsky 2023: low-rank Monte Carlo with the paper's binary segment trees",
    },
    SchemeInfo {
        id: SchemeId::Inverse,
        name: "inverse",
        state: StateKind::Counts,
        summary: "inverse method (Gillespie on sizes), the low-rank baseline",
    },
    SchemeInfo {
        id: SchemeId::Rejection,
        name: "rejection",
        state: StateKind::Counts,
        summary: "acceptance-rejection with the kernel's supremum, the low-rank baseline",
    },
    SchemeInfo {
        id: SchemeId::Mfa,
        name: "mfa",
        state: StateKind::Sizes,
        summary: "Eibeck & Wagner 2000: event-driven mass flow algorithm, gel by truncation, fragmentation events",
    },
    SchemeInfo {
        id: SchemeId::Dsa,
        name: "dsa",
        state: StateKind::Sizes,
        summary: "Eibeck & Wagner 2000: direct simulation (Marcus-Lushnikov), fragmentation events",
    },
    // (appended: a scheme's place in this list is its code in C-ABI checkpoints)
    SchemeInfo {
        id: SchemeId::DsaCounts,
        name: "dsa-counts",
        state: StateKind::Counts,
        summary: "Eibeck & Wagner 2000: direct simulation over size counts (integer sizes, no doubling)",
    },
    SchemeInfo {
        id: SchemeId::LowRankSizes,
        name: "lowrank-sizes",
        state: StateKind::Sizes,
        summary: "Osinsky 2023: low-rank Monte Carlo over particle sizes (continuous or sparse; memory O(particles))",
    },
];

impl SchemeId {
    /// The registry entry.
    pub fn info(self) -> &'static SchemeInfo {
        SCHEMES.iter().find(|s| s.id == self).unwrap_or(&SCHEMES[0])
    }

    /// The name (`"lowrank"`, ...).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The scheme of a name, if registered.
    pub fn from_name(name: &str) -> Option<Self> {
        SCHEMES.iter().find(|s| s.name == name).map(|s| s.id)
    }
}

/// The initial state.
#[derive(Clone, Copy, Debug)]
pub enum Init<'a> {
    /// `counts[i − 1] = N_i` particles of size i in volume `volume`.
    Counts {
        /// The counts.
        counts: &'a [u64],
        /// The volume V > 0.
        volume: f64,
    },
    /// Particle sizes carrying the total mass `mass`: for the mass-flow schemes
    /// (`massflow`, `mfa`) samples of the initial *mass* distribution `x c0(x) / M1`,
    /// each particle carrying `mass / N`; for direct simulation (`dsa`) samples of the
    /// *number* distribution, in the volume `Σ sizes / mass`.
    Sizes {
        /// The sizes (each finite and > 0).
        sizes: &'a [f64],
        /// The mass M1 > 0 they carry.
        mass: f64,
    },
}

/// Settings of [`build`]; each scheme reads the ones that apply to it.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Options {
    /// Largest particle size (size-count schemes).
    pub size_limit: u64,
    /// Memory budget in bytes of the growing schemes.
    pub memory_budget: usize,
    /// Time step (time-driven schemes).
    pub dt: f64,
    /// Point source (mass flow).
    pub points: PointSource,
    /// Sorting strategy (mass flow).
    pub sorting: Sorting,
    /// Proposal times in batches (low-rank schemes; on by default: faster, but a run
    /// then depends on where it is stopped — see
    /// [`LowRankMc::with_batched_clock`](super::lowrank::LowRankMc::with_batched_clock)).
    pub batched_clock: bool,
    /// Particle capacity of direct simulation (fragmentation adds particles); 0 means
    /// the initial number without fragmentation and four times it with.
    pub capacity: usize,
    /// Truncation `b_N` of the mass flow algorithm (infinite: none).
    pub truncation: f64,
    /// Event-driven schemes: a kernel value above the product majorant is an error
    /// instead of a counted violation.
    pub strict_bound: bool,
    /// Event-driven schemes: how particles are drawn by weight (`None`: the scheme's
    /// default, the faster in our measurements — groups for mfa, the sum tree for dsa).
    pub sampler: Option<super::eventflow::Sampler>,
    /// The bucketed low-rank scheme's engine (`None`, the default: chosen by the
    /// initial particle number; see [`AutoBucketed`]).
    pub bucket_mode: Option<super::lowrank::BucketMode>,
}

impl Default for Options {
    /// Size limit 2^32, memory budget 2 GiB, Δt = 0.01, Niederreiter points, adaptive
    /// sorting, batched proposal times.
    fn default() -> Self {
        Options {
            size_limit: super::lowrank::DEFAULT_SIZE_LIMIT,
            memory_budget: super::lowrank::DEFAULT_MEMORY_BUDGET,
            dt: 0.01,
            points: PointSource::niederreiter(),
            sorting: Sorting::Adaptive,
            batched_clock: true,
            capacity: 0,
            truncation: f64::INFINITY,
            strict_bound: false,
            sampler: None,
            bucket_mode: None,
        }
    }
}

impl Options {
    /// Sets the size limit.
    pub fn with_size_limit(mut self, limit: u64) -> Self {
        self.size_limit = limit;
        self
    }
    /// Sets the memory budget in bytes.
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.memory_budget = bytes;
        self
    }
    /// Sets the time step.
    pub fn with_dt(mut self, dt: f64) -> Self {
        self.dt = dt;
        self
    }
    /// Sets the point source.
    pub fn with_points(mut self, points: PointSource) -> Self {
        self.points = points;
        self
    }
    /// Draws low-rank proposal times in batches (faster for large systems; a run then
    /// depends on where it is stopped, see [`Options::batched_clock`]).
    pub fn with_batched_clock(mut self, on: bool) -> Self {
        self.batched_clock = on;
        self
    }

    /// Sets the particle capacity of direct simulation (0: automatic).
    pub fn with_capacity(mut self, particles: usize) -> Self {
        self.capacity = particles;
        self
    }

    /// Sets the truncation `b_N` of the mass flow algorithm.
    pub fn with_truncation(mut self, b: f64) -> Self {
        self.truncation = b;
        self
    }

    /// Sets how the event-driven schemes draw particles by weight.
    pub fn with_sampler(mut self, sampler: super::eventflow::Sampler) -> Self {
        self.sampler = Some(sampler);
        self
    }

    /// Pins the bucketed low-rank scheme's engine (`None`: chosen by size).
    pub fn with_bucket_mode(mut self, mode: Option<super::lowrank::BucketMode>) -> Self {
        self.bucket_mode = mode;
        self
    }

    /// Makes a kernel above its product majorant an error (event-driven schemes).
    pub fn with_strict_bound(mut self, strict: bool) -> Self {
        self.strict_bound = strict;
        self
    }

    /// Sets the mass-flow sorting strategy.
    pub fn with_sorting(mut self, sorting: Sorting) -> Self {
        self.sorting = sorting;
        self
    }
}

/// A scheme's state, read through the facade.
#[derive(Clone, Debug)]
pub enum State<'a> {
    /// Particle sizes (ascending for the time-driven mass flow; in storage order for
    /// the event-driven schemes).
    Sizes(&'a [f64]),
    /// Counts, `N_i` at index `i − 1`, and the volume.
    Counts(Cow<'a, [u64]>, f64),
}

/// Every scheme behind one object-safe interface (see the module docs).
pub trait Simulation<K, F, G: ?Sized>: Observe {
    /// Which scheme this is.
    fn id(&self) -> SchemeId;
    /// Current time.
    fn time(&self) -> f64;
    /// [`Scheme::totals`]: the books of every call so far.
    fn totals(&self) -> StepReport;
    /// [`Scheme::advance_to`].
    fn advance_to(&mut self, t: f64, rng: &mut G) -> Result<StepReport>;
    /// [`Scheme::advance_within`]: at most `budget`'s work, then `interrupted`.
    fn advance_within(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport>;
    /// The state (sizes or counts; the counts as a dense vector up to the largest size:
    /// see [`for_each_count`](Self::for_each_count) for the occupied sizes only).
    fn state(&self) -> State<'_>;
    /// Calls `f(size, N)` for every occupied size, ascending, without a dense count
    /// vector (size-count schemes; others: `Unsupported`).
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()>;
    /// Largest size the state can hold now (size-count schemes' M), if any.
    fn max_size(&self) -> Option<u64>;
    /// The engine the bucketed low-rank scheme runs (others: `None`).
    fn bucket_mode(&self) -> Option<super::lowrank::BucketMode>;
    /// Replaces counts and volume (size-count schemes; others: `Unsupported`).
    fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()>;
    /// Replaces the state by `counts[i]` particles of size `sizes[i]` in `volume`
    /// (size-count schemes; acceptance–rejection builds no count vector).
    fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()>;
    /// Replaces the sizes (mass flow; others: `Unsupported`).
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()>;
    /// Replaces the coagulation kernel.
    fn set_kernel(&mut self, kernel: K) -> Result<()>;
    /// Replaces the fragmentation kernel (mass flow; others: `Unsupported`).
    fn set_fragmentation(&mut self, frag: F) -> Result<()>;
    /// Changes the time step (time-driven schemes; others: `Unsupported`).
    fn set_dt(&mut self, dt: f64) -> Result<()>;
    /// Sets the clock (finite, not negative); an event-driven scheme draws its next
    /// proposal afresh.
    fn set_time(&mut self, t: f64) -> Result<()>;
    /// Changes the total mass the particles carry (mass flow; others: `Unsupported`).
    fn set_mass(&mut self, mass: f64) -> Result<()>;
    /// Writes the full state ([`Checkpoint::save`]).
    fn save(&self, w: &mut Writer);
    /// Restores a state written by `save` of the same scheme and set-up.
    fn restore(&mut self, r: &mut Reader) -> Result<()>;
}

/// What a scheme exposes to the facade beyond [`Scheme`], [`Observe`] and
/// [`Checkpoint`]: its state and what can be replaced. The defaults refuse.
pub trait Facet<K, F> {
    /// The state.
    fn state(&self) -> State<'_>;
    /// The occupied sizes and their counts, ascending.
    fn for_each_count(&self, _f: &mut dyn FnMut(u64, u64)) -> Result<()> {
        Err(Error::Unsupported {
            what: "counts: this scheme's state is particle sizes (use the sizes)",
        })
    }
    /// Largest size the state can hold now.
    fn max_size(&self) -> Option<u64> {
        None
    }
    /// The bucketed low-rank scheme's engine.
    fn bucket_mode(&self) -> Option<super::lowrank::BucketMode> {
        None
    }
    /// Replaces counts and volume.
    fn set_counts(&mut self, _counts: &[u64], _volume: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "counts: this scheme's state is particle sizes (use set_sizes)",
        })
    }
    /// Replaces the state from `(size, count)` pairs.
    fn set_pairs(&mut self, _sizes: &[u64], _counts: &[u64], _volume: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "pairs: this scheme's state is particle sizes (use set_sizes)",
        })
    }
    /// Replaces the sizes.
    fn set_sizes(&mut self, _sizes: &[f64]) -> Result<()> {
        Err(Error::Unsupported {
            what: "sizes: this scheme's state is counts of integer sizes (use set_counts)",
        })
    }
    /// Replaces the coagulation kernel.
    fn set_kernel(&mut self, kernel: K) -> Result<()>;
    /// Replaces the fragmentation kernel.
    fn set_fragmentation(&mut self, _frag: F) -> Result<()> {
        Err(Error::Unsupported {
            what: "fragmentation: only the mass-flow scheme breaks particles",
        })
    }
    /// Changes the time step.
    fn set_dt(&mut self, _dt: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "dt: event-driven schemes have no time step",
        })
    }
    /// Sets the clock.
    fn set_time(&mut self, t: f64) -> Result<()>;
    /// Changes the total mass.
    fn set_mass(&mut self, _mass: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "mass: a size-count scheme's mass is its counts (use set_counts)",
        })
    }
}

/// A registered scheme behind the facade.
struct Entry<S, K, F> {
    s: S,
    id: SchemeId,
    _kf: PhantomData<fn(K, F)>,
}

impl<S: Observe, K, F> Observe for Entry<S, K, F> {
    fn volume(&self) -> f64 {
        self.s.volume()
    }
    fn particles(&self) -> u64 {
        self.s.particles()
    }
    fn moment(&self, order: f64) -> f64 {
        self.s.moment(order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        self.s.concentration(a, b)
    }
    fn number_density(&self, x: f64) -> f64 {
        self.s.number_density(x)
    }
    fn gel_mass(&self) -> Option<f64> {
        self.s.gel_mass()
    }
}

impl<S, K, F, G> Simulation<K, F, G> for Entry<S, K, F>
where
    S: Scheme + Observe + Checkpoint + Facet<K, F>,
    G: Rng + ?Sized,
{
    fn id(&self) -> SchemeId {
        self.id
    }
    fn time(&self) -> f64 {
        self.s.time()
    }
    fn totals(&self) -> StepReport {
        self.s.totals()
    }
    fn advance_to(&mut self, t: f64, rng: &mut G) -> Result<StepReport> {
        self.s.advance_to(t, rng)
    }
    fn advance_within(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport> {
        self.s.advance_within(t, budget, rng)
    }
    fn state(&self) -> State<'_> {
        self.s.state()
    }
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()> {
        self.s.for_each_count(f)
    }
    fn max_size(&self) -> Option<u64> {
        self.s.max_size()
    }
    fn bucket_mode(&self) -> Option<super::lowrank::BucketMode> {
        self.s.bucket_mode()
    }
    fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        self.s.set_counts(counts, volume)
    }
    fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
        self.s.set_pairs(sizes, counts, volume)
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        self.s.set_sizes(sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        self.s.set_kernel(kernel)
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        self.s.set_fragmentation(frag)
    }
    fn set_dt(&mut self, dt: f64) -> Result<()> {
        self.s.set_dt(dt)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        self.s.set_time(t)
    }
    fn set_mass(&mut self, mass: f64) -> Result<()> {
        self.s.set_mass(mass)
    }
    fn save(&self, w: &mut Writer) {
        self.s.save(w)
    }
    fn restore(&mut self, r: &mut Reader) -> Result<()> {
        self.s.restore(r)
    }
}

/// The kernel types the registry accepts.
pub trait RegistryKernel: CoagulationKernel + Clone + 'static {}
impl<K: CoagulationKernel + Clone + 'static> RegistryKernel for K {}

fn boxed<'a, S, K, F, G>(s: S, id: SchemeId) -> Box<dyn Simulation<K, F, G> + 'a>
where
    S: Scheme + Observe + Checkpoint + Facet<K, F> + 'a,
    K: 'a,
    F: 'a,
    G: Rng + ?Sized + 'a,
{
    Box::new(Entry {
        s,
        id,
        _kf: PhantomData,
    })
}

/// Runs `$body` with `$R` (and `$W = 2R`) bound to the kernel's rank, 1..=4.
macro_rules! by_rank {
    ($rank:expr, $R:ident, $W:ident => $body:expr) => {
        match $rank {
            1 => {
                const $R: usize = 1;
                const $W: usize = 2;
                $body
            }
            2 => {
                const $R: usize = 2;
                const $W: usize = 4;
                $body
            }
            3 => {
                const $R: usize = 3;
                const $W: usize = 6;
                $body
            }
            4 => {
                const $R: usize = 4;
                const $W: usize = 8;
                $body
            }
            _ => Err(Error::Unsupported {
                what: "low-rank schemes: the kernel needs a low-rank bound of rank 1..4",
            }),
        }
    };
}

/// Builds scheme `id` from `init` with `opts` — the one place that names every scheme.
///
/// Errors: `init` is of the other kind (counts for a sizes scheme or the reverse), the
/// kernel lacks the bound the scheme needs (`Unsupported`), or the scheme's own
/// constructor refuses the set-up.
pub fn build<K, F, G>(
    id: SchemeId,
    kernel: K,
    frag: F,
    init: &Init<'_>,
    opts: &Options,
) -> Result<Box<dyn Simulation<K, F, G>>>
where
    K: RegistryKernel,
    F: FragmentationKernel + Clone + 'static,
    G: Rng + ?Sized + 'static,
{
    if !id.info().accepts(init) {
        return Err(Error::Unsupported {
            what: "initial state of the other kind (counts vs sizes) for this scheme",
        });
    }
    if let Init::Counts { counts, .. } = init {
        if !frag.is_none() {
            return Err(Error::Unsupported {
                what: "fragmentation: only the mass-flow scheme breaks particles",
            });
        }
        if counts.len() as u64 > opts.size_limit {
            return Err(Error::Capacity {
                name: "maximum particle size",
                capacity: usize::try_from(opts.size_limit).unwrap_or(usize::MAX),
            });
        }
    }
    match (id, *init) {
        (SchemeId::MassFlow, Init::Sizes { sizes, mass }) => {
            let s = MassFlow::new(kernel, frag, sizes, mass, opts.dt, opts.points.clone())?
                .with_sorting(opts.sorting);
            Ok(boxed(s, id))
        }
        (SchemeId::LowRank, Init::Counts { counts, volume }) => {
            by_rank!(kernel.rank(), R, W => {
                let s = AutoBucketed::<K, R, W>::new_with_mode(kernel, counts, volume, opts.memory_budget, opts.bucket_mode)?
                    .with_size_limit(opts.size_limit)
                    .with_batched_clock(opts.batched_clock);
                Ok(boxed::<_, K, F, G>(s, id))
            })
        }
        (SchemeId::LowRankTree, Init::Counts { counts, volume }) => {
            by_rank!(kernel.rank(), R, W => {
                let _ = W;
                let s = LowRank::<K, R>::new_with_memory_budget(kernel, counts, volume, opts.memory_budget)?
                    .with_size_limit(opts.size_limit)
                    .with_batched_clock(opts.batched_clock);
                Ok(boxed::<_, K, F, G>(s, id))
            })
        }
        (SchemeId::LowRankBinaryTree, Init::Counts { counts, volume }) => {
            by_rank!(kernel.rank(), R, W => {
                let _ = W;
                let s = LowRank::<K, R, BinaryTree<R>>::new_with_memory_budget(kernel, counts, volume, opts.memory_budget)?
                    .with_size_limit(opts.size_limit)
                    .with_batched_clock(opts.batched_clock);
                Ok(boxed::<_, K, F, G>(s, id))
            })
        }
        (SchemeId::Inverse, Init::Counts { counts, volume }) => {
            let s = Inverse::new_with_memory_budget(kernel, counts, volume, opts.memory_budget)?
                .with_size_limit(opts.size_limit);
            Ok(boxed(s, id))
        }
        (SchemeId::Rejection, Init::Counts { counts, volume }) => {
            let s = AcceptanceRejection::new_with_memory_budget(
                kernel,
                counts,
                volume,
                opts.memory_budget,
            )?
            .with_size_limit(opts.size_limit);
            Ok(boxed(s, id))
        }
        (SchemeId::DsaCounts, Init::Counts { counts, volume }) => {
            let s = DsaCounts::new_with_memory_budget(kernel, counts, volume, opts.memory_budget)?
                .with_size_limit(opts.size_limit)
                .with_strict_bound(opts.strict_bound);
            Ok(boxed(s, id))
        }
        (SchemeId::Mfa, Init::Sizes { sizes, mass }) => {
            let s = Mfa::new(kernel, frag, sizes, mass)?
                .with_truncation(opts.truncation)?
                .with_strict_bound(opts.strict_bound);
            let s = match opts.sampler {
                Some(x) => s.with_sampler(x)?,
                None => s,
            };
            Ok(boxed(s, id))
        }
        (SchemeId::LowRankSizes, Init::Sizes { sizes, mass }) => {
            if !frag.is_none() {
                return Err(Error::Unsupported {
                    what: "fragmentation: the low-rank schemes only coagulate",
                });
            }
            let v = dsa_volume(sizes, mass)?;
            by_rank!(kernel.rank(), R, W => {
                let s = LowRankSizes::<K, R, W>::new_with_memory_budget(kernel, sizes, v, opts.memory_budget)?;
                Ok(boxed::<_, K, F, G>(s, id))
            })
        }
        (SchemeId::Dsa, Init::Sizes { sizes, mass }) => {
            let cap = dsa_capacity(sizes.len(), &frag, opts);
            let s = Dsa::new(kernel, frag, sizes, dsa_volume(sizes, mass)?, cap)?
                .with_strict_bound(opts.strict_bound);
            let s = match opts.sampler {
                Some(x) => s.with_sampler(x)?,
                None => s,
            };
            Ok(boxed(s, id))
        }
        _ => Err(Error::Unsupported {
            what: "initial state of the other kind for this scheme",
        }),
    }
}

/// `f64`s of caller-owned workspace scheme `id` needs for `init`, for the fixed-size
/// schemes that can run in it ([`build_in`]); `None` for the growing schemes (they take
/// a memory budget instead, [`Options::memory_budget`]) or an overflowing size.
pub fn workspace_len(id: SchemeId, init: &Init<'_>) -> Option<usize> {
    workspace_len_with(id, init, &Options::default())
}

/// [`workspace_len`] under `opts` (direct simulation's capacity).
pub fn workspace_len_with(id: SchemeId, init: &Init<'_>, opts: &Options) -> Option<usize> {
    match (id, init) {
        (SchemeId::MassFlow, Init::Sizes { sizes, .. }) => {
            super::massflow::workspace_len(sizes.len())
        }
        (SchemeId::Mfa, Init::Sizes { sizes, .. }) => super::eventflow::workspace_len(sizes.len()),
        (SchemeId::Dsa, Init::Sizes { sizes, .. }) => {
            // the capacity with fragmentation when it is automatic (the kernel is not
            // known here): a workspace for the larger case
            let cap = if opts.capacity == 0 {
                sizes.len().checked_mul(4)?
            } else {
                opts.capacity
            };
            super::eventflow::workspace_len(cap)
        }
        _ => None,
    }
}

/// Direct simulation's capacity under `opts`.
fn dsa_capacity<F: FragmentationKernel>(n: usize, frag: &F, opts: &Options) -> usize {
    match opts.capacity {
        0 if frag.is_none() => n.max(1),
        0 => n.saturating_mul(4).max(1),
        c => c,
    }
}

/// Direct simulation's volume: the one in which `sizes` carry `mass`.
fn dsa_volume(sizes: &[f64], mass: f64) -> Result<f64> {
    crate::error::positive("mass", mass)?;
    let total: f64 = sizes.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::InvalidRate {
            name: "total size of the initial particles (finite and positive)",
            value: total,
        });
    }
    crate::error::positive("volume (total size / mass)", total / mass)
}

/// [`build`] in storage the caller owns: `workspace` holds at least
/// [`workspace_len_with`] doubles (for the same `opts`; [`workspace_len`] for the
/// default options) and is borrowed for the sim's life; no step allocates
/// (the facade's box is the only allocation, made here).
///
/// Errors: as for `build`; a growing scheme (`Unsupported`: give it a memory budget);
/// a workspace that is too small (`BufferLength`).
///
/// ```
/// use coagula_core::kernel::{Coagulation, NoFragmentation};
/// use coagula_core::random::{Generator, generator};
/// use coagula_core::scheme::registry::{self, Init, Options, SchemeId, Simulation};
/// let sizes = [1.0; 256];
/// let init = Init::Sizes { sizes: &sizes, mass: 1.0 };
/// let mut ws = vec![0.0; registry::workspace_len(SchemeId::MassFlow, &init).unwrap()];
/// let k = Coagulation::constant(1.0).unwrap();
/// let mut sim: Box<dyn Simulation<_, _, Generator> + '_> = registry::build_in(
///     SchemeId::MassFlow, k, NoFragmentation, &init, &Options::default(), &mut ws,
/// ).unwrap();
/// sim.advance_to(0.5, &mut generator(1, 0)).unwrap();
/// assert!((sim.moment(2.0) - 1.5).abs() < 0.02);
/// ```
pub fn build_in<'a, K, F, G>(
    id: SchemeId,
    kernel: K,
    frag: F,
    init: &Init<'_>,
    opts: &Options,
    workspace: &'a mut [f64],
) -> Result<Box<dyn Simulation<K, F, G> + 'a>>
where
    K: CoagulationKernel + Clone + 'a,
    F: FragmentationKernel + Clone + 'a,
    G: Rng + ?Sized + 'a,
{
    match (id, *init) {
        (SchemeId::MassFlow, Init::Sizes { sizes, mass }) => {
            let s = MassFlow::new_in(
                kernel,
                frag,
                sizes,
                mass,
                opts.dt,
                opts.points.clone(),
                workspace,
            )?
            .with_sorting(opts.sorting);
            Ok(boxed(s, id))
        }
        (SchemeId::Mfa, Init::Sizes { sizes, mass }) => {
            let s = Mfa::new_in(kernel, frag, sizes, mass, workspace)?
                .with_truncation(opts.truncation)?
                .with_strict_bound(opts.strict_bound);
            let s = match opts.sampler {
                Some(x) => s.with_sampler(x)?,
                None => s,
            };
            Ok(boxed(s, id))
        }
        (SchemeId::Dsa, Init::Sizes { sizes, mass }) => {
            let cap = dsa_capacity(sizes.len(), &frag, opts);
            let v = dsa_volume(sizes, mass)?;
            let s = Dsa::new_in(kernel, frag, sizes, v, cap, workspace)?
                .with_strict_bound(opts.strict_bound);
            let s = match opts.sampler {
                Some(x) => s.with_sampler(x)?,
                None => s,
            };
            Ok(boxed(s, id))
        }
        (SchemeId::MassFlow | SchemeId::Mfa | SchemeId::Dsa, _) => Err(Error::Unsupported {
            what: "initial state of the other kind (counts vs sizes) for this scheme",
        }),
        _ => Err(Error::Unsupported {
            what: "caller-owned workspace: only the fixed-size schemes run in one (the growing ones take a memory budget)",
        }),
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Facet<K, F>
    for MassFlow<K, F, B>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        MassFlow::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        MassFlow::set_kernel(self, kernel);
        Ok(())
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        MassFlow::set_fragmentation(self, frag);
        Ok(())
    }
    fn set_dt(&mut self, dt: f64) -> Result<()> {
        MassFlow::set_dt(self, dt)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        MassFlow::set_time(self, t)
    }
    fn set_mass(&mut self, mass: f64) -> Result<()> {
        MassFlow::set_mass(self, mass)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Facet<K, F>
    for Mfa<K, F, B>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        Mfa::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        Mfa::set_kernel(self, kernel)
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        Mfa::set_fragmentation(self, frag)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        Mfa::set_time(self, t)
    }
    fn set_mass(&mut self, mass: f64) -> Result<()> {
        Mfa::set_mass(self, mass)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Facet<K, F>
    for Dsa<K, F, B>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        Dsa::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        Dsa::set_kernel(self, kernel)
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        Dsa::set_fragmentation(self, frag)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        Dsa::set_time(self, t)
    }
    fn set_mass(&mut self, _mass: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "mass: direct simulation's mass is its sizes over its volume (use set_sizes)",
        })
    }
}

impl<K: CoagulationKernel, F, const R: usize, const W: usize> Facet<K, F>
    for LowRankSizes<K, R, W>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        LowRankSizes::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        LowRankSizes::set_kernel(self, kernel)
    }
    fn set_fragmentation(&mut self, _frag: F) -> Result<()> {
        Err(Error::Unsupported {
            what: "fragmentation: the low-rank schemes only coagulate",
        })
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        LowRankSizes::set_time(self, t)
    }
    fn set_mass(&mut self, _mass: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "mass: this scheme's mass is its sizes over its volume (use set_sizes)",
        })
    }
}

/// [`Facet`] of a size-count scheme from its inherent methods.
macro_rules! counts_facet {
    ([$($g:tt)*] $ty:ty, $counts:expr $(, mode = $mode:expr)?) => {
        impl<$($g)*, F> Facet<K, F> for $ty {
            $(
                fn bucket_mode(&self) -> Option<super::lowrank::BucketMode> {
                    let f: fn(&Self) -> super::lowrank::BucketMode = $mode;
                    Some(f(self))
                }
            )?
            fn state(&self) -> State<'_> {
                let f: fn(&Self) -> Cow<'_, [u64]> = $counts;
                State::Counts(f(self), self.volume())
            }
            fn max_size(&self) -> Option<u64> {
                Some(self.max_size() as u64)
            }
            fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()> {
                <$ty>::for_each_count(self, f);
                Ok(())
            }
            fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
                <$ty>::set_counts(self, counts, volume)
            }
            fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
                <$ty>::set_pairs(self, sizes, counts, volume)
            }
            fn set_kernel(&mut self, kernel: K) -> Result<()> {
                <$ty>::set_kernel(self, kernel)
            }
            fn set_time(&mut self, t: f64) -> Result<()> {
                <$ty>::set_time(self, t)
            }
        }
    };
}

counts_facet!([K: CoagulationKernel, const R: usize, E: ProposalEngine<R>, Rl: EventRule<K>] LowRankMc<K, R, E, Rl>, |s| s.counts());
counts_facet!([K: CoagulationKernel + Clone, const R: usize, const W: usize] AutoBucketed<K, R, W>, |s| s.counts(), mode = |s| s.mode());
counts_facet!([K: CoagulationKernel + Clone] Inverse<K>, |s| Cow::Owned(s.counts()));
counts_facet!([K: CoagulationKernel] AcceptanceRejection<K>, |s| Cow::Owned(s.counts()));
counts_facet!([K: CoagulationKernel] DsaCounts<K>, |s| s.counts());
