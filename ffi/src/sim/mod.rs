//! The one simulation handle: every population scheme of the registry behind one
//! `coag_sim`, chosen by its registry name, built from the initial state it takes
//! (`coag_sim_new_counts`, `_sizes`, `_temperatures`, `_velocities`, `_maxwellian`),
//! with the same verbs for all — advance with work limits, cancellation, a host random
//! stream, reseed, clone, one checkpoint envelope.

mod advance;
mod checkpoint;
mod classes;
mod process;
mod read;
mod write;

pub use advance::*;
pub use checkpoint::*;
pub use classes::*;
pub use process::*;
pub use read::*;
pub use write::*;

use crate::kernel::{Fragmentation, Kernel, coag_fragmentation, coag_kernel};
use crate::options::{coag_options, options_of};
use crate::rng::{Generator, Source};
use crate::status::{COAG_CAPACITY, COAG_UNSUPPORTED, Fail, fail, guard};
use crate::util::{
    check_workspace, handle, non_null, slice, text, workspace_bytes, write, zeroed_workspace,
};
use coagula_core::random::generator;
use coagula_core::scheme::facade::{Init, Options, SchemeId, Simulation};
use coagula_core::scheme::registry;
use std::ffi::{c_char, c_void};

/// The facade over every scheme, as the C ABI instantiates it.
pub(crate) type Dyn = dyn Simulation<Kernel, Fragmentation, Source>;

/// A host callback polled during `coag_sim_advance_to`: non-zero cancels the call.
pub type coag_cancel_callback = Option<unsafe extern "C" fn(user_data: *mut c_void) -> i32>;

/// Opaque simulation handle (`coag_sim` in C).
pub struct coag_sim {
    pub(crate) sim: Box<Dyn>,
    /// The sim's own stream (kept even while a callback is installed).
    pub(crate) own: Generator,
    pub(crate) callback: Option<(unsafe extern "C" fn(*mut c_void) -> u64, *mut c_void)>,
    /// Work units per `coag_sim_advance_to` (0: no limit) and the cancellation poll.
    pub(crate) work_limit: u64,
    pub(crate) cancel: Option<(unsafe extern "C" fn(*mut c_void) -> i32, *mut c_void)>,
}

/// The inputs every constructor shares: the scheme, its physics and its options.
struct Inputs {
    id: SchemeId,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    options: Options,
}

impl Inputs {
    /// # Safety
    /// Each pointer NULL or valid (`scheme` NUL-terminated, handles live).
    unsafe fn read(
        scheme: *const c_char,
        kernel: *const coag_kernel,
        frag: *const coag_fragmentation,
        options: *const coag_options,
    ) -> Result<Inputs, Fail> {
        // SAFETY (all): NULL checked where required; valid by contract.
        let name = unsafe { text(scheme, "scheme") }?;
        let id = registry::find(name)?;
        non_null(kernel, "kernel")?;
        let options = unsafe { options_of(options) }?;
        Ok(Inputs {
            id,
            kernel,
            frag,
            options,
        })
    }

    /// Builds the sim from `init` and writes the handle to `out`.
    ///
    /// # Safety
    /// The handles live; `out` checked non-null and writable.
    unsafe fn build(&self, init: &Init<'_>, out: *mut *mut coag_sim) -> Result<(), Fail> {
        // SAFETY: forwarded contract.
        let k = unsafe { handle(self.kernel, "kernel") }?;
        let f = unsafe { Fragmentation::of(self.frag) }?;
        let sim = registry::build(self.id, k.model(f)?, init, &self.options)?;
        // SAFETY: forwarded contract.
        unsafe { finish(sim, &self.options, out) };
        Ok(())
    }
}

/// Wraps a built sim in a handle (its own stream from the options' seed and stream).
///
/// # Safety
/// `out` checked non-null and writable.
unsafe fn finish(sim: Box<Dyn>, options: &Options, out: *mut *mut coag_sim) {
    let s = coag_sim {
        sim,
        own: generator(options.seed(), options.stream()),
        callback: None,
        work_limit: 0,
        cancel: None,
    };
    // SAFETY: the function's contract.
    unsafe { write(out, Box::into_raw(Box::new(s))) };
}

/// A sim of registry scheme `scheme` (`coag_scheme_*` list the names and what each
/// takes) from counts: `counts[i]` particles of size `i + 1`, `len` entries, in volume
/// `volume`, under coagulation kernel `kernel` with fragmentation `frag` (NULL: none)
/// and `options` (NULL: every default; the seed and stream of the options start the
/// sim's own random stream). Errors: an unknown scheme, a kernel, initial state or
/// option the scheme does not take (`COAG_UNSUPPORTED`, naming what), bad values.
///
/// # Safety
/// Pointers NULL or valid; `counts` valid for `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_new_counts(
    scheme: *const c_char,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    options: *const coag_options,
    counts: *const u64,
    len: usize,
    volume: f64,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let inp = unsafe { Inputs::read(scheme, kernel, frag, options) }?;
        let counts = unsafe { slice(counts, len, "counts") }?;
        non_null(out, "out")?;
        unsafe { inp.build(&Init::Counts { counts, volume }, out) }
    })
}

/// A sim of scheme `scheme` from `n` particle sizes (each finite and > 0) carrying the
/// mass `mass`: samples of the mass distribution for the mass-flow schemes, of the
/// number distribution (in the volume `Σ sizes / mass`) for direct simulation and
/// low-rank over sizes (`coag_scheme_info.sizes` says which). See
/// `coag_sim_new_counts`.
///
/// # Safety
/// Pointers NULL or valid; `sizes` valid for `n` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_new_sizes(
    scheme: *const c_char,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    options: *const coag_options,
    sizes: *const f64,
    n: usize,
    mass: f64,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let inp = unsafe { Inputs::read(scheme, kernel, frag, options) }?;
        let sizes = unsafe { slice(sizes, n, "sizes") }?;
        non_null(out, "out")?;
        unsafe { inp.build(&Init::Sizes { sizes, mass }, out) }
    })
}

/// Bytes of caller-owned workspace a sim of a fixed-memory scheme
/// (`COAG_MEMORY_FIXED`) from `n` sizes needs under `options` and `frag` (NULL: none),
/// for `coag_sim_new_sizes_in`; `COAG_UNSUPPORTED` for a growing scheme. The LAPACK
/// `lwork` habit: query, allocate, construct.
///
/// # Safety
/// Pointers NULL or valid; `out` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_workspace_size(
    scheme: *const c_char,
    frag: *const coag_fragmentation,
    options: *const coag_options,
    n: usize,
    out: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let id = registry::find(unsafe { text(scheme, "scheme") }?)?;
        let f = unsafe { Fragmentation::of(frag) }?;
        let o = unsafe { options_of(options) }?;
        non_null(out, "out")?;
        let len = workspace_for(
            id,
            n,
            &o,
            !coagula_core::kernel::FragmentationKernel::is_none(&f),
        )?;
        let bytes = workspace_bytes::<f64>(Some(len), n)?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, bytes) };
        Ok(())
    })
}

/// The workspace doubles of `n` sizes for scheme `id`.
fn workspace_for(id: SchemeId, n: usize, o: &Options, fragments: bool) -> Result<usize, Fail> {
    if id.memory != coagula_core::scheme::facade::Memory::Fixed {
        return fail(
            COAG_UNSUPPORTED,
            format!(
                "workspace: scheme {} grows within the memory-budget option and runs in no caller workspace",
                id.name
            ),
        );
    }
    registry::workspace_len(id, n, o, fragments).ok_or_else(|| {
        Fail(
            COAG_CAPACITY,
            format!("integer overflow in workspace size ({n} particles)"),
        )
    })
}

/// `coag_sim_new_sizes` in memory the caller owns: `workspace` (aligned for `double`,
/// `workspace_bytes` ≥ `coag_sim_workspace_size` for the same scheme, frag, options
/// and n) holds the state for the sim's whole life; no step allocates (the group
/// sampler's index tables excepted). The caller keeps the buffer alive and untouched
/// until `coag_sim_free`; the sim zeroes it first, so after a refused construction its
/// contents are lost. `sizes` must not overlap it. A clone lives in memory the library
/// owns.
///
/// # Safety
/// Pointers NULL or valid; `workspace` valid for `workspace_bytes` bytes and used by
/// nothing else until the sim is freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_new_sizes_in(
    scheme: *const c_char,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    options: *const coag_options,
    sizes: *const f64,
    n: usize,
    mass: f64,
    workspace: *mut c_void,
    workspace_bytes_given: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let inp = unsafe { Inputs::read(scheme, kernel, frag, options) }?;
        let x = unsafe { slice(sizes, n, "sizes") }?;
        non_null(out, "out")?;
        let k = unsafe { handle(inp.kernel, "kernel") }?;
        let f = unsafe { Fragmentation::of(inp.frag) }?;
        let fragments = !coagula_core::kernel::FragmentationKernel::is_none(&f);
        let init = Init::Sizes { sizes: x, mass };
        let len = workspace_for(inp.id, n, &inp.options, fragments)?;
        let need = workspace_bytes::<f64>(Some(len), n)?;
        check_workspace(workspace, workspace_bytes_given, need, x)?;
        // SAFETY: checked: non-null, aligned, `need` bytes, disjoint from `sizes`; the
        // caller keeps it for the sim's life (contract).
        let ws = unsafe { zeroed_workspace::<f64>(workspace, need) };
        let sim = registry::build_in(inp.id, k.model(f)?, &init, &inp.options, ws)?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { finish(sim, &inp.options, out) };
        Ok(())
    })
}

/// A sim of a temperature scheme (`COAG_MODEL_TEMPERATURE`) under the temperature model
/// `kernel` (`coag_kernel_new("temperature-ballistic", …)` or
/// `"temperature-closed-form"`): `counts[i]` particles of size `i + 1` at partial
/// temperature `temperatures[i]` (finite, ≥ 0), `len` entries each, in volume
/// `volume`. See `coag_sim_new_counts`.
///
/// # Safety
/// Pointers NULL or valid; `counts` and `temperatures` valid for `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_new_temperatures(
    scheme: *const c_char,
    kernel: *const coag_kernel,
    options: *const coag_options,
    counts: *const u64,
    temperatures: *const f64,
    len: usize,
    volume: f64,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let inp = unsafe { Inputs::read(scheme, kernel, std::ptr::null(), options) }?;
        let counts = unsafe { slice(counts, len, "counts") }?;
        let temperatures = unsafe { slice(temperatures, len, "temperatures") }?;
        non_null(out, "out")?;
        let init = Init::Temperatures {
            counts,
            temperatures,
            volume,
        };
        unsafe { inp.build(&init, out) }
    })
}

/// A sim of a gas scheme (`COAG_MODEL_GAS`) under the gas `kernel`
/// (`coag_kernel_new("hard-spheres", …)`): `n` particles, particle p of size
/// `sizes[p] ≥ 1` with velocity `velocities[3p .. 3p + 3]` (finite), in volume
/// `volume`. See `coag_sim_new_counts`.
///
/// # Safety
/// Pointers NULL or valid; `sizes` valid for `n` values, `velocities` for `3 n`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_new_velocities(
    scheme: *const c_char,
    kernel: *const coag_kernel,
    options: *const coag_options,
    sizes: *const u64,
    velocities: *const f64,
    n: usize,
    volume: f64,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let inp = unsafe { Inputs::read(scheme, kernel, std::ptr::null(), options) }?;
        let sizes = unsafe { slice(sizes, n, "sizes") }?;
        let len = n
            .checked_mul(3)
            .ok_or_else(|| Fail(crate::status::COAG_INVALID_ARGUMENT, "3 n overflows".into()))?;
        let velocities = unsafe { slice(velocities, len, "velocities") }?;
        non_null(out, "out")?;
        let init = Init::Velocities {
            sizes,
            velocities,
            volume,
        };
        unsafe { inp.build(&init, out) }
    })
}

/// A sim of a gas scheme from `counts[i]` particles of size `i + 1` with Maxwellian
/// velocities at temperature `temperatures[i]` (each component normal with variance
/// `T_i / i`), drawn from the velocity stream of the options' seed and stream (core's
/// seed policy, as the CLI and Python draw them), `len` entries each, in volume
/// `volume`. See `coag_sim_new_velocities`.
///
/// # Safety
/// Pointers NULL or valid; `counts` and `temperatures` valid for `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_new_maxwellian(
    scheme: *const c_char,
    kernel: *const coag_kernel,
    options: *const coag_options,
    counts: *const u64,
    temperatures: *const f64,
    len: usize,
    volume: f64,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all): forwarded contract.
        let inp = unsafe { Inputs::read(scheme, kernel, std::ptr::null(), options) }?;
        let counts = unsafe { slice(counts, len, "counts") }?;
        let temperatures = unsafe { slice(temperatures, len, "temperatures") }?;
        non_null(out, "out")?;
        let (sizes, velocities) = coagula_core::initial::maxwellian_of_seed(
            counts,
            temperatures,
            inp.options.seed(),
            inp.options.stream(),
        )?;
        let init = Init::Velocities {
            sizes: &sizes,
            velocities: &velocities,
            volume,
        };
        unsafe { inp.build(&init, out) }
    })
}

/// Releases a sim (NULL is a no-op; a sim in the middle of a call — freed from its own
/// callback — is left alone).
///
/// # Safety
/// `sim` must be NULL or a handle from a `coag_sim_new_*` or `coag_sim_clone` not yet
/// freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_free(sim: *mut coag_sim) {
    // SAFETY: NULL checked; live by contract; refused while mid-call.
    if !sim.is_null() && unsafe { handle(sim, "sim") }.is_ok() {
        // SAFETY: made by Box::into_raw in finish or clone, freed once (contract).
        drop(unsafe { Box::from_raw(sim) });
    }
}

/// A new sim that is an exact copy of `sim` — state, settings, physics, own random
/// stream, host callbacks and limits — into `*out`: the two continue identically and
/// independently (a host forking a run, or trying a step it may discard). A sim in
/// caller-owned memory is copied into memory the library owns.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_clone(sim: *const coag_sim, out: *mut *mut coag_sim) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let copy = coag_sim {
            sim: s.sim.duplicate()?,
            own: s.own.clone(),
            callback: s.callback,
            work_limit: s.work_limit,
            cancel: s.cancel,
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(copy))) };
        Ok(())
    })
}

/// The sim's registry name (a static string).
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_scheme(sim: *const coag_sim, out: *mut *const c_char) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let i = registry::SCHEMES
            .iter()
            .position(|x| x.name == s.sim.info().name)
            .unwrap_or(0);
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, crate::registry::scheme_name(i)) };
        Ok(())
    })
}

/// The engine the `lowrank` scheme runs now (a static string: `"slots"`, `"counted"` or
/// `"blocks"`; chosen by the kernel and the particle number unless the `engine` option
/// pinned it);
/// `COAG_UNSUPPORTED` for every other scheme.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_engine(sim: *const coag_sim, out: *mut *const c_char) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let name = match s.sim.engine() {
            Some(mode) => mode.c_name(),
            None => {
                return fail(
                    COAG_UNSUPPORTED,
                    format!(
                        "engine: scheme {} has no engines to choose",
                        s.sim.info().name
                    ),
                );
            }
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, name.as_ptr()) };
        Ok(())
    })
}
