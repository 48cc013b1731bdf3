//! The object-safe facade every front end holds, and what a registry entry is.
//!
//! This module sits below the schemes and names none of them: a scheme module
//! implements [`Controls`] (what a host can read and replace) and [`Register`] (its
//! registry entry: [`SchemeInfo`], the capabilities as data, and how to build it);
//! [`registry`](super::registry) lists the entries. A front end (the C ABI, the CLI,
//! Python, the tests) holds a `Box<dyn Simulation<K, F, G>>` and never names a scheme
//! type.
//!
//! The facade is generic over the coagulation kernel type `K`, the fragmentation
//! kernel `F` and the generator `G`, so a front end fixes them once (the C ABI: its
//! kernel handles and its random source; the CLI: the built-in kernels and
//! [`crate::random::Generator`]). Dispatch is dynamic per call (`advance_to`, an
//! observation), never per random draw or kernel evaluation: inside a call the scheme
//! runs monomorphised.

mod adapter;
mod driven;
mod envelope;
mod host;
mod model;
mod options;
mod reach;
mod start;

pub(crate) use adapter::count_controls;
pub use adapter::{Boxed, Controls};
pub use envelope::{ENVELOPE_MAGIC, peek_stream, read_envelope, write_envelope};
pub use model::Blank;
pub use model::{Init, InitKind, Model, ModelKind, Samples, number_volume};
pub use options::{
    BucketMode, Directions, GENERAL, KEY_NAMES, KEYS, Key, Kind, Options, Points, Sampler, Sorting,
    Value, key_index,
};
pub use reach::{Reach, SPARSE_COUNT};
pub use start::Start;

use super::{Budget, StepReport};
use crate::checkpoint::{Reader, Writer};
use crate::error::Result;
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::observe::Observe;
use alloc::borrow::Cow;
use alloc::boxed::Box;
use rand_core::Rng;

/// Whether a scheme's memory is fixed at construction (it may run in a caller's
/// workspace) or grows within a memory budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Memory {
    /// Fixed: `registry::workspace_len` gives the doubles a caller provides.
    Fixed,
    /// Grows with `try_reserve` within the `memory-budget` option.
    Growing,
}

/// What kind of process a scheme simulates, for the tests that hold every scheme to
/// its law.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Law {
    /// The finite-N coagulation process itself (Marcus–Lushnikov): every pair of
    /// particles coagulates at rate `K/V`, exactly, so a small system follows the
    /// exact master equation (with particle doubling where the scheme has it, which
    /// keeps the law of the concentrations).
    FiniteN,
    /// A stochastic weighted (mass-flow) process whose expectation solves the
    /// Smoluchowski equation as N grows (Eibeck & Wagner 2000).
    MassFlow,
    /// A time-stepping scheme: exact only as Δt → 0 (an O(Δt) bias; Lécot et al.
    /// 2019).
    TimeStepped,
    /// Temperature-dependent coagulation (Osinsky 2023 §4): the finite-N process of
    /// counts and partial temperatures.
    Temperature,
    /// Direct simulation Monte Carlo of a gas (Osinsky 2023 §5).
    Gas,
}

/// A registry entry: a scheme's name, paper and capabilities, as data every front end
/// reads.
#[derive(Clone, Copy, Debug)]
pub struct SchemeInfo {
    /// Its name in the CLI, the C ABI and Python (unique).
    pub name: &'static str,
    /// The paper and section it implements.
    pub paper: &'static str,
    /// What it is, in one line.
    pub summary: &'static str,
    /// The physics it takes.
    pub model: ModelKind,
    /// The initial states it builds from.
    pub inits: &'static [InitKind],
    /// What its [`Init::Sizes`] are samples of.
    pub sizes: Samples,
    /// Whether it breaks particles (a coagulation model's fragmentation kernel).
    pub fragmentation: bool,
    /// The option keys that apply (besides [`GENERAL`]).
    pub options: &'static [&'static str],
    /// Fixed or growing memory.
    pub memory: Memory,
    /// Its checkpoint tag (a checkpoint of another scheme is refused).
    pub tag: u64,
    /// The names [`Observe::observable`] answers besides the common ones.
    pub observables: &'static [&'static str],
    /// The law it simulates.
    pub law: Law,
}

impl PartialEq for SchemeInfo {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl Eq for SchemeInfo {}

impl SchemeInfo {
    /// Whether the scheme builds from `init`.
    pub fn accepts(&self, init: &Init<'_>) -> bool {
        self.inits.contains(&init.kind())
    }

    /// Whether option `key` applies.
    pub fn takes_option(&self, key: &str) -> bool {
        self.options.contains(&key) || GENERAL.contains(&key)
    }

    /// A built-in kernel as this scheme runs it: a coagulation kernel that takes a
    /// `min-size` (its bound depends on it: additive, free-molecular) has its low-rank
    /// bound taken from size 1 on an integer-size scheme (one that builds from counts;
    /// a tighter bound, fewer rejections); every other pairing as it is. What the CLI
    /// and Python build with, so that the same seed gives the same bits — and the same
    /// checkpoint bytes — from both and from a C caller who sets `min-size` to 1 (a
    /// kernel without the parameter is the C caller's as it is).
    pub fn runs(
        &self,
        b: crate::kernel::builtin::Builtin,
    ) -> crate::error::Result<crate::kernel::builtin::Builtin> {
        use crate::kernel::builtin::{self, Builtin};
        let takes_min_size = |name: &str| {
            builtin::find(name).is_some_and(|i| i.params.iter().any(|p| p.name == "min-size"))
        };
        match b {
            Builtin::Coagulation(k)
                if self.inits.contains(&InitKind::Counts) && takes_min_size(k.name()) =>
            {
                Ok(Builtin::Coagulation(k.with_min_size(1.0)?))
            }
            b => Ok(b),
        }
    }

    /// Whether the scheme takes the processes `_p` beside coagulation
    /// ([`crate::process`]): the finite-N schemes over counts take a source, removal
    /// and growth by monomer attachment; those over real sizes (`lowrank-sizes`, `dsa`)
    /// a source, removal and growth by splitting (which needs its step: the sim checks
    /// that, [`Simulation::set_processes`]); all of them with coagulation alone (no
    /// fragmentation kernel). The mass-flow, time-stepped, temperature and gas schemes
    /// take none yet (`docs/design/processes.md`).
    pub fn takes_processes(&self, _p: &crate::process::Processes) -> crate::error::Result<()> {
        if !matches!(self.law, Law::FiniteN | Law::TimeStepped) {
            return Err(crate::Error::Unsupported {
                what: "processes beside coagulation on this scheme (they run on the finite-N schemes — lowrank, lowrank-tree, lowrank-binary-tree, lowrank-blocks, lowrank-sizes, inverse, rejection, dsa, dsa-counts — and on massflow)",
            });
        }
        Ok(())
    }

    /// How the scheme takes growth (see [`GrowthKind`]).
    pub fn growth_kind(&self) -> GrowthKind {
        if self.law == Law::TimeStepped {
            GrowthKind::InStep
        } else if self.inits.contains(&InitKind::Counts) {
            GrowthKind::Attachment
        } else {
            GrowthKind::Split
        }
    }

    /// Whether processes run beside a fragmentation kernel: only inside the mass
    /// flow's own steps (elsewhere a fragmentation would raise the particle number,
    /// and the thinning bound of the driver would not hold).
    pub fn processes_with_fragmentation(&self) -> bool {
        self.law == Law::TimeStepped
    }

    /// Whether a run under `opts` draws random numbers beyond its start: every
    /// scheme but the time-stepped one on deterministic QMC points (Lécot et al.
    /// 2019). A start from a distribution is the centred quantile lattice for a
    /// scheme that does not, a randomly shifted one for a scheme that does
    /// ([`initial::lattice_shift`](crate::initial::lattice_shift)).
    pub fn randomised(&self, opts: &Options) -> bool {
        self.law != Law::TimeStepped
            || opts.points() == Points::MonteCarlo
            || opts.randomization() != crate::qmc::Randomization::None
    }
}

/// How a scheme takes growth ([`SchemeInfo::growth_kind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GrowthKind {
    /// Monomer attachment on integer sizes: exact, no step.
    Attachment,
    /// Real sizes, split off by a step the caller sets
    /// ([`Processes::with_growth_step`](crate::process::Processes::with_growth_step)).
    Split,
    /// Inside the scheme's own time step (the time-driven mass flow).
    InStep,
}

/// A registered scheme as [`registry::SCHEMES`](super::registry::SCHEMES) holds it.
pub type SchemeId = &'static SchemeInfo;

/// The kernel types the registry accepts (`Send`, so that every sim is: a host
/// steps its cells on threads of its own).
pub trait RegistryKernel: CoagulationKernel + Clone + Send + 'static {}
impl<K: CoagulationKernel + Clone + Send + 'static> RegistryKernel for K {}

/// The fragmentation kernel types the registry accepts.
pub trait RegistryFragmentation: FragmentationKernel + Clone + Send + 'static {}
impl<F: FragmentationKernel + Clone + Send + 'static> RegistryFragmentation for F {}

/// A scheme's registry entry: its [`SchemeInfo`] and how to build it. The registry
/// checks what the info declares (the model and initial-state kinds, fragmentation,
/// the options that apply) before calling [`build`](Self::build).
pub trait Register {
    /// The capabilities.
    const INFO: &'static SchemeInfo;

    /// Builds the scheme (the kinds already checked against [`INFO`](Self::INFO)).
    fn build<K, F, G>(
        model: Model<K, F>,
        init: &Init<'_>,
        opts: &Options,
    ) -> Result<Box<dyn Simulation<K, F, G>>>
    where
        K: RegistryKernel,
        F: RegistryFragmentation,
        G: Rng + ?Sized + 'static;

    /// Builds the scheme in a caller's workspace of
    /// [`workspace_len`](Self::workspace_len) doubles (schemes of fixed memory).
    fn build_in<'a, K, F, G>(
        _model: Model<K, F>,
        _init: &Init<'_>,
        _opts: &Options,
        _workspace: &'a mut [f64],
    ) -> Result<Box<dyn Simulation<K, F, G> + 'a>>
    where
        K: RegistryKernel,
        F: RegistryFragmentation,
        G: Rng + ?Sized + 'static,
    {
        Err(crate::Error::Unsupported {
            what: "caller-owned workspace: only the fixed-size schemes run in one (the growing ones take a memory budget)",
        })
    }

    /// Doubles of caller workspace the scheme needs for `particles` particles
    /// (fixed-memory schemes, which start from sizes).
    fn workspace_len(_particles: usize, _opts: &Options, _fragments: bool) -> Option<usize> {
        None
    }

    /// Bytes the scheme will hold at most in a run from `init` that goes as far as
    /// `reach` says (its largest size, particles and sparsely held particles; the
    /// start itself with [`Reach::at_start`]): what a front end sums over the sims it
    /// runs at once to refuse a run that cannot fit. An estimate, within a factor 2 of
    /// the peak when `reach` is right (`docs/results/memory-estimate.md`).
    fn memory_estimate(init: &Init<'_>, opts: &Options, fragments: bool, reach: &Reach) -> u64;

    /// The smallest initial state of the same shape as `init` (what a clone is built
    /// from before the original's checkpoint is restored into it).
    fn blank(init: &Init<'_>, opts: &Options, fragments: bool) -> Blank;
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

/// Every scheme behind one object-safe interface (see the module docs). `Send`: a sim
/// moves to the thread that steps it (every scheme owns its state).
pub trait Simulation<K, F, G: ?Sized>: Observe + Send {
    /// The registry entry.
    fn info(&self) -> &'static SchemeInfo;
    /// Current time.
    fn time(&self) -> f64;
    /// The books of every call so far ([`Scheme::totals`](super::Scheme::totals)).
    fn totals(&self) -> StepReport;
    /// Runs until time `t` ([`Scheme::advance_to`](super::Scheme::advance_to)).
    fn advance_to(&mut self, t: f64, rng: &mut G) -> Result<StepReport>;
    /// At most `budget`'s work, then `interrupted`
    /// ([`Scheme::advance_within`](super::Scheme::advance_within)).
    fn advance_within(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport>;
    /// Sets the processes beside coagulation ([`crate::process`]; `None` or empty
    /// processes: none), with books starting from the state now. Errors: a scheme that
    /// does not take them ([`SchemeInfo::takes_processes`]); nothing changes then.
    fn set_processes(&mut self, procs: Option<crate::process::Processes>) -> Result<()>;
    /// The processes set, if any.
    fn processes(&self) -> Option<&crate::process::Processes>;
    /// The processes' books (what was injected, removed and grown), if processes are
    /// set. A step's flows are the difference of the books after and before it.
    fn books(&self) -> Option<crate::process::Books>;
    /// The state (sizes or counts; the counts as a dense vector up to the largest size:
    /// see [`for_each_count`](Self::for_each_count) for the occupied sizes only).
    fn state(&self) -> State<'_>;
    /// Calls `f(size, N)` for every occupied size, ascending, without a dense count
    /// vector (integer-size schemes; others: `Unsupported`).
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()>;
    /// Largest size the state can hold now (integer-size schemes' M), if any.
    fn max_size(&self) -> Option<u64>;
    /// The engine the bucketed low-rank scheme runs (others: `None`).
    fn engine(&self) -> Option<BucketMode>;
    /// Calls `f(size, value)` for every occupied size with a per-size quantity by name
    /// (`"temperature"`: the partial temperature of the temperature-dependent schemes,
    /// the kinetic temperature of a gas's sizes); `Unsupported` where there is none.
    fn size_values(&self, name: &str, f: &mut dyn FnMut(u64, f64)) -> Result<()>;
    /// Calls `f(size, velocity)` for every particle of a gas (others: `Unsupported`).
    fn velocities(&self, f: &mut dyn FnMut(u64, &[f64; 3])) -> Result<()>;
    /// Replaces counts and volume (integer-size schemes; others: `Unsupported`).
    fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()>;
    /// Replaces the state by `counts[i]` particles of size `sizes[i]` in `volume`
    /// (integer-size schemes).
    fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()>;
    /// Replaces the sizes (schemes over particle sizes; others: `Unsupported`).
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()>;
    /// Replaces the coagulation kernel (coagulation models).
    fn set_kernel(&mut self, kernel: K) -> Result<()>;
    /// Replaces the fragmentation kernel (schemes that break particles).
    fn set_fragmentation(&mut self, frag: F) -> Result<()>;
    /// Changes the time step (time-driven schemes; others: `Unsupported`).
    fn set_dt(&mut self, dt: f64) -> Result<()>;
    /// Sets the clock (finite, not negative); an event-driven scheme draws its next
    /// proposal afresh.
    fn set_time(&mut self, t: f64) -> Result<()>;
    /// Changes the total mass the particles carry (mass-flow schemes).
    fn set_mass(&mut self, mass: f64) -> Result<()>;
    /// The settings as they stand (as built, with the setters' changes).
    fn options(&self) -> &Options;
    /// The physics.
    fn model(&self) -> &Model<K, F>;
    /// Writes the scheme's state ([`Checkpoint::save`](crate::checkpoint::Checkpoint::save)).
    fn save(&self, w: &mut Writer);
    /// Restores a state written by `save` of the same scheme and set-up.
    fn restore(&mut self, r: &mut Reader) -> Result<()>;
    /// Writes the one checkpoint envelope every front end uses: the scheme, the
    /// settings as built and as they stand, the physics' fingerprint, the front end's
    /// random stream (its generator's words, if it has one) and the state; sealed with
    /// a checksum (see [`write_envelope`]).
    fn save_checkpoint(&self, stream: Option<[u64; 4]>, w: &mut Writer);
    /// Restores an envelope written by [`save_checkpoint`](Self::save_checkpoint) of a
    /// sim of the same scheme, settings and physics (the stream, the memory budget and
    /// the capacity may differ), returning the stream it carries; on error the sim is
    /// unchanged.
    fn restore_checkpoint(&mut self, buf: &[u8]) -> Result<Option<[u64; 4]>>;
    /// The smallest initial state of this sim's shape ([`Blank::build`] builds a sim
    /// its checkpoint restores into: what a clone is, and what a front end that
    /// pickles a sim keeps beside the checkpoint, with [`built`](Self::built)).
    fn blank(&self) -> Blank;
    /// The settings as built (before any setter's change).
    fn built(&self) -> &Options;
    /// An exact copy in memory the library owns (a sim in caller workspace included):
    /// the two continue identically and independently.
    fn duplicate(&self) -> Result<Box<dyn Simulation<K, F, G>>>;
    /// Projects the population onto a host's size classes keeping number and mass
    /// ([`Classes::project`](crate::classes::Classes::project) over
    /// [`points`](Observe::points)): `numbers` gets the numbers per unit volume at the
    /// pivots; what lies outside the grid is returned.
    fn project(
        &self,
        classes: &crate::classes::Classes,
        numbers: &mut [f64],
    ) -> Result<crate::classes::Outside> {
        classes.project(|f| self.points(f), numbers)
    }
    /// Replaces the population by the class numbers per unit volume `numbers` at the
    /// pivots of `classes` (see [`crate::classes`]): size-count and size schemes get
    /// `N_i V` particles of size `x_i` (integer pivots for integer sizes), rounded
    /// without bias with draws from `rng`; the mass-flow schemes keep their particle
    /// number and place it on the classes' mass by systematic sampling, with the
    /// classes' total mass. Processes' books start afresh as after `set_pairs`.
    /// Temperature and gas states: `Unsupported`. On error nothing changes.
    fn set_classes(
        &mut self,
        classes: &crate::classes::Classes,
        numbers: &[f64],
        rng: &mut G,
    ) -> Result<()>
    where
        G: Rng,
    {
        host::set_classes(self, classes, numbers, rng)
    }
}
