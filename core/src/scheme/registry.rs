//! The registry: the list of every scheme, and the one way to build one.
//!
//! Each scheme module owns its entry (a type implementing
//! [`Register`], with its
//! [`SchemeInfo`](super::facade::SchemeInfo)); this module only
//! lists them. The C ABI, the CLI, Python and the tests find a scheme here by name
//! ([`find`]), read its capabilities (`SchemeInfo`: initial states, physics,
//! options, memory, checkpoint tag, observables, law) and build it ([`build`]); what a
//! scheme's info declares is checked here, once, for every front end.
//!
//! # Example
//! ```
//! use coagula_core::kernel::{Coagulation, NoFragmentation};
//! use coagula_core::random::{Generator, generator};
//! use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
//! use coagula_core::scheme::registry;
//! let model = Model::Coagulation {
//!     kernel: Coagulation::constant(1.0).unwrap(),
//!     fragmentation: NoFragmentation,
//! };
//! let init = Init::Counts { counts: &[10_000], volume: 10_000.0 };
//! let mut rng = generator(7, 0);
//! // the same set-up on every scheme of the registry that takes it
//! for &info in registry::SCHEMES.iter().filter(|s| s.accepts(&init) && s.model == model.kind()) {
//!     let mut sim: Box<dyn Simulation<_, _, Generator>> =
//!         registry::build(info, model, &init, &Options::default()).unwrap();
//!     sim.advance_to(1.0, &mut rng).unwrap();
//!     // N(t)/V = 1/(1 + t/2) for K = 1
//!     assert!((sim.moment(0.0) - 1.0 / 1.5).abs() < 0.02, "{}", info.name);
//! }
//! ```

use super::baseline::{InverseEntry, RejectionEntry};
use super::eventflow::{DsaCountsEntry, DsaEntry, MfaEntry};
use super::facade::{
    Init, Model, Options, Reach, Register, RegistryFragmentation, RegistryKernel, SchemeId,
    Simulation,
};
use super::lowrank::{
    BinaryTreeEntry, BlocksEntry, BucketedEntry, DsmcEntry, DsmcRejectionEntry, SizesEntry,
    TemperatureEntry, TemperatureRejectionEntry, TreeEntry,
};
use super::massflow::MassFlowEntry;
use crate::error::{Error, Result};
use alloc::boxed::Box;
use rand_core::Rng;

/// Lists the entries: [`SCHEMES`], [`NAMES`] and the dispatch by entry.
macro_rules! registry {
    ($($e:ty),* $(,)?) => {
        /// Every scheme, in the order front ends list them.
        pub const SCHEMES: &[SchemeId] = &[$(<$e as Register>::INFO),*];

        /// Every scheme's name, in the order of [`SCHEMES`].
        pub const NAMES: &[&str] = &[$(<$e as Register>::INFO.name),*];

        fn dispatch_build<K, F, G>(
            id: SchemeId,
            model: Model<K, F>,
            init: &Init<'_>,
            opts: &Options,
        ) -> Result<Box<dyn Simulation<K, F, G>>>
        where
            K: RegistryKernel,
            F: RegistryFragmentation,
            G: Rng + ?Sized + 'static,
        {
            $(if id.name == <$e as Register>::INFO.name {
                return <$e as Register>::build::<K, F, G>(model, init, opts);
            })*
            Err(unknown())
        }

        fn dispatch_build_in<'a, K, F, G>(
            id: SchemeId,
            model: Model<K, F>,
            init: &Init<'_>,
            opts: &Options,
            workspace: &'a mut [f64],
        ) -> Result<Box<dyn Simulation<K, F, G> + 'a>>
        where
            K: RegistryKernel,
            F: RegistryFragmentation,
            G: Rng + ?Sized + 'static,
        {
            $(if id.name == <$e as Register>::INFO.name {
                return <$e as Register>::build_in::<K, F, G>(model, init, opts, workspace);
            })*
            Err(unknown())
        }

        fn dispatch_workspace_len(id: SchemeId, particles: usize, opts: &Options, fragments: bool) -> Option<usize> {
            $(if id.name == <$e as Register>::INFO.name {
                return <$e as Register>::workspace_len(particles, opts, fragments);
            })*
            None
        }

        fn dispatch_memory(id: SchemeId, init: &Init<'_>, opts: &Options, fragments: bool, reach: &Reach) -> u64 {
            $(if id.name == <$e as Register>::INFO.name {
                return <$e as Register>::memory_estimate(init, opts, fragments, reach);
            })*
            0
        }
    };
}

registry!(
    MassFlowEntry,
    BucketedEntry,
    TreeEntry,
    BinaryTreeEntry,
    BlocksEntry,
    InverseEntry,
    RejectionEntry,
    MfaEntry,
    DsaEntry,
    DsaCountsEntry,
    SizesEntry,
    TemperatureEntry,
    TemperatureRejectionEntry,
    DsmcEntry,
    DsmcRejectionEntry,
);

fn unknown() -> Error {
    Error::UnknownName {
        what: "scheme",
        known: NAMES,
    }
}

/// The scheme of a name. Errors: no scheme has it ([`Error::UnknownName`], which lists
/// the names).
pub fn find(name: &str) -> Result<SchemeId> {
    SCHEMES
        .iter()
        .copied()
        .find(|s| s.name == name)
        .ok_or_else(unknown)
}

/// Checks what `id`'s entry declares: the physics, the initial state, fragmentation and
/// the options given.
fn check<K: RegistryKernel, F: RegistryFragmentation>(
    id: SchemeId,
    model: &Model<K, F>,
    init: &Init<'_>,
    opts: &Options,
) -> Result<()> {
    if model.kind() != id.model {
        return Err(Error::Unsupported {
            what: match id.model {
                super::facade::ModelKind::Coagulation => {
                    "model: this scheme takes a coagulation kernel (a temperature model or a gas needs the temperature or dsmc schemes)"
                }
                super::facade::ModelKind::Temperature => {
                    "model: this scheme takes a temperature model (temperature-ballistic, temperature-closed-form)"
                }
                super::facade::ModelKind::Gas => "model: this scheme takes a gas (hard-spheres)",
            },
        });
    }
    if !id.accepts(init) {
        return Err(Error::Unsupported {
            what: "initial state of another kind than this scheme takes (its registry entry lists them: counts, sizes, temperatures or velocities)",
        });
    }
    if let Model::Coagulation { kernel, .. } = model
        && kernel.integer_sizes()
        && !matches!(init, Init::Counts { .. })
    {
        return Err(Error::Unsupported {
            what: "kernel of integer sizes (atmospheric): start from counts, on a scheme over integer sizes (lowrank-blocks, lowrank, inverse, ...)",
        });
    }
    if model.fragments() && !id.fragmentation {
        return Err(Error::Unsupported {
            what: "fragmentation: this scheme only coagulates (massflow, mfa and dsa break particles)",
        });
    }
    opts.check_for(id.name, id.options)
}

/// Builds scheme `id` under `model` from `init` with `opts`.
///
/// Errors: a model, initial state or option the entry does not take
/// (`Unsupported`, `OptionNotApplicable`), a kernel that lacks the bound the scheme
/// needs (`Unsupported`), or the scheme's own constructor refusing the set-up.
pub fn build<K, F, G>(
    id: SchemeId,
    model: Model<K, F>,
    init: &Init<'_>,
    opts: &Options,
) -> Result<Box<dyn Simulation<K, F, G>>>
where
    K: RegistryKernel,
    F: RegistryFragmentation,
    G: Rng + ?Sized + 'static,
{
    check(id, &model, init, opts)?;
    if id.memory == super::facade::Memory::Fixed {
        // the workspace the library allocates for a fixed-memory scheme, within the
        // memory budget (an allocation the system would grant lazily and then fail)
        let fragments = model.fragments();
        let Init::Sizes { sizes, .. } = init else {
            return Err(Error::Unsupported {
                what: "initial state of another kind than this scheme takes",
            });
        };
        let bytes = dispatch_workspace_len(id, sizes.len(), opts, fragments)
            .and_then(|n| n.checked_mul(core::mem::size_of::<f64>()))
            .ok_or(Error::Overflow {
                name: "workspace size",
            })?;
        if bytes > opts.memory_budget() {
            return Err(Error::Capacity {
                name: "workspace bytes within the memory-budget option",
                capacity: opts.memory_budget(),
            });
        }
    }
    dispatch_build(id, model, init, opts)
}

/// [`build`] in storage the caller owns: `workspace` holds at least
/// [`workspace_len`] doubles (for the same arguments) and is borrowed for the sim's
/// life; no step allocates (the facade's box is the only allocation, made here).
///
/// Errors: as for `build`; a growing scheme (`Unsupported`: give it a memory budget);
/// a workspace that is too small (`BufferLength`).
///
/// ```
/// use coagula_core::kernel::{Coagulation, NoFragmentation};
/// use coagula_core::random::{Generator, generator};
/// use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
/// use coagula_core::scheme::registry;
/// let sizes = [1.0; 256];
/// let init = Init::Sizes { sizes: &sizes, mass: 1.0 };
/// let mass_flow = registry::find("massflow").unwrap();
/// let opts = Options::default();
/// let mut ws = vec![0.0; registry::workspace_len(mass_flow, sizes.len(), &opts, false).unwrap()];
/// let model = Model::Coagulation {
///     kernel: Coagulation::constant(1.0).unwrap(),
///     fragmentation: NoFragmentation,
/// };
/// let mut sim: Box<dyn Simulation<_, _, Generator> + '_> =
///     registry::build_in(mass_flow, model, &init, &opts, &mut ws).unwrap();
/// sim.advance_to(0.5, &mut generator(1, 0)).unwrap();
/// assert!((sim.moment(2.0) - 1.5).abs() < 0.02);
/// ```
pub fn build_in<'a, K, F, G>(
    id: SchemeId,
    model: Model<K, F>,
    init: &Init<'_>,
    opts: &Options,
    workspace: &'a mut [f64],
) -> Result<Box<dyn Simulation<K, F, G> + 'a>>
where
    K: RegistryKernel,
    F: RegistryFragmentation,
    G: Rng + ?Sized + 'static,
{
    check(id, &model, init, opts)?;
    dispatch_build_in(id, model, init, opts, workspace)
}

/// Doubles of caller-owned workspace scheme `id` needs for `particles` initial
/// particles under `opts` (with fragmentation when `fragments`), for the fixed-size
/// schemes that can run in it ([`build_in`]); `None` for the growing schemes or a size
/// that overflows.
pub fn workspace_len(
    id: SchemeId,
    particles: usize,
    opts: &Options,
    fragments: bool,
) -> Option<usize> {
    dispatch_workspace_len(id, particles, opts, fragments)
}

/// Bytes scheme `id` will hold at most in a run from `init` under `opts` that goes as
/// far as `reach` (an estimate: see [`Register::memory_estimate`]; a front end sums it
/// over the sims it will run at once to refuse what cannot fit).
pub fn memory_estimate(
    id: SchemeId,
    init: &Init<'_>,
    opts: &Options,
    fragments: bool,
    reach: &Reach,
) -> u64 {
    dispatch_memory(id, init, opts, fragments, reach)
}
