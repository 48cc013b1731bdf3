//! Simulation handles: every scheme behind one `coag_sim`, stepped with
//! `coag_sim_advance_to`.

use crate::kernel::{Fragmentation, Kernel, coag_fragmentation, coag_kernel};
use crate::rng::{DEGENERATE, Generator, STUCK_AFTER, Source, coag_rng_callback};
use crate::{
    COAG_INTERRUPTED, COAG_INVALID_ARGUMENT, COAG_RNG_FAILURE, COAG_UNSUPPORTED, Fail, fail, guard,
    non_null, read_config, slice, slice_mut, write,
};
use coagula_core::checkpoint::{Reader, Writer};
use coagula_core::kernel::CoagulationKernel;
use coagula_core::qmc::Randomization;
use coagula_core::random::{Purpose, generator, substream};
use coagula_core::scheme::lowrank::BucketMode;
use coagula_core::scheme::massflow::{PointSource, Sorting};
use coagula_core::scheme::registry::{self, Init, Options, SchemeId, Simulation, State};
use coagula_core::scheme::{Budget, StepReport};
use std::ffi::c_void;

/// Niederreiter's (1,3)-sequence (Lécot et al.'s choice).
pub const COAG_POINTS_NIEDERREITER: i32 = 0;
/// Sobol' (Joe–Kuo), dimensions 1–3.
pub const COAG_POINTS_SOBOL: i32 = 1;
/// Pseudo-random points (Monte Carlo).
pub const COAG_POINTS_MONTE_CARLO: i32 = 2;

/// No randomisation of the sequence.
pub const COAG_RANDOMIZATION_NONE: i32 = 0;
/// Random digital shift.
pub const COAG_RANDOMIZATION_SHIFT: i32 = 1;
/// Matoušek's linear scrambling plus a shift.
pub const COAG_RANDOMIZATION_MATOUSEK: i32 = 2;
/// Owen's nested scrambling (hash-based).
pub const COAG_RANDOMIZATION_OWEN: i32 = 3;

/// Osinsky's low-rank Monte Carlo, bucketed layout (the default and fastest layout).
pub const COAG_METHOD_LOWRANK: i32 = 0;
/// Inverse method (Gillespie on sizes).
pub const COAG_METHOD_INVERSE: i32 = 1;
/// Acceptance–rejection.
pub const COAG_METHOD_REJECTION: i32 = 2;
/// Osinsky's low-rank Monte Carlo with the paper's per-size segment trees.
pub const COAG_METHOD_LOWRANK_TREE: i32 = 3;
/// Direct simulation (Marcus–Lushnikov, Eibeck & Wagner 2000) over size counts: the
/// finite-N process itself, no particle doubling (the kernel needs a product majorant).
pub const COAG_METHOD_DSA_COUNTS: i32 = 4;

/// `coag_counts_config.bucket_mode`: the bucketed low-rank method chooses its engine by
/// the initial particle number (exact bucket counts up to 16384 particles, slots and
/// alias tables above), and again when the counts are replaced.
pub const COAG_BUCKET_AUTO: i32 = 0;
/// The slot engine (slots and alias tables: O(1) per proposal, fastest for large
/// systems), kept through `coag_sim_set_counts`.
pub const COAG_BUCKET_SLOTS: i32 = 1;
/// The counted engine (exact bucket counts in a sum tree: fastest for small systems),
/// kept through `coag_sim_set_counts`.
pub const COAG_BUCKET_COUNTED: i32 = 2;

/// The `COAG_METHOD_*` codes and the registry's schemes they name.
const METHODS: [(i32, SchemeId); 5] = [
    (COAG_METHOD_LOWRANK, SchemeId::LowRank),
    (COAG_METHOD_INVERSE, SchemeId::Inverse),
    (COAG_METHOD_REJECTION, SchemeId::Rejection),
    (COAG_METHOD_LOWRANK_TREE, SchemeId::LowRankTree),
    (COAG_METHOD_DSA_COUNTS, SchemeId::DsaCounts),
];

/// Eibeck & Wagner's event-driven mass flow algorithm (particles carry mass `M1 / N`).
pub const COAG_EVENTFLOW_MFA: i32 = 0;
/// Eibeck & Wagner's direct simulation over a list of particles (Marcus–Lushnikov).
pub const COAG_EVENTFLOW_DSA: i32 = 1;
/// Osinsky's low-rank Monte Carlo over a list of particles (continuous or sparse sizes;
/// memory O(particles), particle doubling; the kernel needs a low-rank bound, every
/// built-in kernel has one). Like direct simulation, its sizes are samples of the
/// number distribution in the volume `Σ sizes / mass`. No caller-owned workspace (it
/// grows its size buckets), no fragmentation; capacity, truncation, sampler and
/// strict bound must stay 0.
pub const COAG_EVENTFLOW_LOWRANK: i32 = 2;

/// The `COAG_EVENTFLOW_*` codes and the registry's schemes they name.
const EVENTFLOW: [(i32, SchemeId); 3] = [
    (COAG_EVENTFLOW_MFA, SchemeId::Mfa),
    (COAG_EVENTFLOW_DSA, SchemeId::Dsa),
    (COAG_EVENTFLOW_LOWRANK, SchemeId::LowRankSizes),
];

/// The scheme's default weighted sampler (the faster in our measurements: groups for
/// the mass flow algorithm, the sum tree for direct simulation).
pub const COAG_SAMPLER_DEFAULT: i32 = 0;
/// A sum tree over the particles.
pub const COAG_SAMPLER_TREE: i32 = 1;
/// Eibeck & Wagner's group acceptance–rejection (one group per binade of the weight).
pub const COAG_SAMPLER_GROUPS: i32 = 2;

/// Configuration of the time-driven mass-flow scheme (Lécot et al. 2019). Fill it with
/// `coag_massflow_default_config`, which sets `struct_size`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_massflow_config {
    /// `sizeof(coag_massflow_config)` as the caller compiled it (the ABI's growth rule:
    /// fields are only ever appended).
    pub struct_size: usize,
    /// Time step Δt > 0.
    pub dt: f64,
    /// Total mass M1 carried by the particles (> 0).
    pub mass: f64,
    /// `COAG_POINTS_*`.
    pub points: i32,
    /// `COAG_RANDOMIZATION_*` (for `NIEDERREITER` and `SOBOL`; RQMC when not NONE).
    pub randomization: i32,
    /// Non-zero: a full sort every step instead of the adaptive merge.
    pub full_sort: i32,
    /// Seed of the sim's random stream (MC points, scrambling).
    pub seed: u64,
    /// Stream id (independent streams for equal seeds).
    pub stream: u64,
}

/// Configuration of the size-count schemes (low-rank, inverse, acceptance–rejection).
/// Fill it with `coag_counts_default_config`, which sets `struct_size`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_counts_config {
    /// `sizeof(coag_counts_config)` as the caller compiled it.
    pub struct_size: usize,
    /// `COAG_METHOD_*`.
    pub method: i32,
    /// Simulation volume V (> 0); 0 means "the number of particles" (so that the
    /// initial counts per volume are concentrations; 1 for an empty system).
    pub volume: f64,
    /// Largest particle size allowed (0: the default, 2^32).
    pub size_limit: u64,
    /// Memory budget in bytes for the growing size tables (0: half of the machine's
    /// physical memory, at least 256 MiB; 2 GiB where the machine cannot say).
    pub memory_budget: u64,
    /// Seed of the sim's random stream.
    pub seed: u64,
    /// Stream id.
    pub stream: u64,
    /// Non-zero: low-rank proposal times in batches (1.2–1.5× faster for large systems,
    /// but a run then depends on where the host stops it). 0, the default: every
    /// proposal has its own waiting time and the next one is kept between calls, so a
    /// run stopped at 0.7 and 1.3 on its way to 2 is bit for bit the run that went to 2
    /// in one call. (Appended in 0.1: a caller compiled against a header without it
    /// gets 0.)
    pub batched_clock: i32,
    /// Ignored: the tail padding of the struct before `bucket_mode` was appended, which
    /// an older caller passes uninitialised (so `bucket_mode` starts past its size).
    pub reserved: i32,
    /// `COAG_BUCKET_*`: the bucketed low-rank method's engine (`COAG_METHOD_LOWRANK`
    /// only; other methods need `COAG_BUCKET_AUTO`). A pinned sim keeps its engine and
    /// restores only checkpoints that engine wrote. (Appended in 0.1: a caller compiled
    /// against a header without it passes a smaller `struct_size` and gets
    /// `COAG_BUCKET_AUTO`.)
    pub bucket_mode: i32,
}

/// Configuration of the event-driven schemes over particle sizes: the mass flow
/// algorithm and direct simulation (Eibeck & Wagner 2000), low-rank Monte Carlo over
/// sizes (`COAG_EVENTFLOW_LOWRANK`, Osinsky 2023: sizes as for direct simulation). Fill it with
/// `coag_eventflow_default_config`, which sets `struct_size`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_eventflow_config {
    /// `sizeof(coag_eventflow_config)` as the caller compiled it.
    pub struct_size: usize,
    /// `COAG_EVENTFLOW_*`.
    pub method: i32,
    /// The mass M1 > 0 of the initial particles: the mass flow algorithm's particles
    /// each carry `M1 / N` (the sizes are samples of the mass distribution); direct
    /// simulation's are real particles in the volume `Σ sizes / M1` (the sizes are
    /// samples of the number distribution).
    pub mass: f64,
    /// Truncation `b_N` of the mass flow algorithm: particles larger than it leave
    /// (the gel); 0 means none (infinite). Not used by direct simulation.
    pub truncation: f64,
    /// Particle capacity of direct simulation (fragmentation adds particles); 0: the
    /// initial number without fragmentation, four times it with.
    pub capacity: u64,
    /// `COAG_SAMPLER_*`.
    pub sampler: i32,
    /// Non-zero: a kernel value above the product majorant `h(x) h(y)` is an error
    /// (`COAG_INVALID_RATE`) instead of a counted violation (the step report's
    /// `bound_violations`).
    pub strict_bound: i32,
    /// Seed of the sim's random stream.
    pub seed: u64,
    /// Stream id.
    pub stream: u64,
}

/// What one `coag_sim_advance_to` call did. The caller sets `struct_size` (or calls
/// `coag_step_report_init`) before passing it; the library writes the fields that fit.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct coag_step_report {
    /// `sizeof(coag_step_report)` as the caller compiled it.
    pub struct_size: usize,
    /// Time reached.
    pub time: f64,
    /// Accepted events (coagulations and break-ups).
    pub events: u64,
    /// Proposals, accepted or not.
    pub proposals: u64,
    /// Proposals rejected by thinning.
    pub rejections: u64,
    /// Proposals where the kernel exceeded its declared bound: always 0 except for the
    /// event-driven schemes without `strict_bound` (elsewhere, and with it, a kernel
    /// above its bound is an error, `COAG_INVALID_RATE`).
    pub bound_violations: u64,
    /// Probabilities above 1 that were clipped (time-driven scheme).
    pub clipped: u64,
    /// Particle-number doublings.
    pub doublings: u64,
    /// Particles that left the system (0 for the schemes that keep every particle).
    pub removed: u64,
    /// Collisions that bounced instead of merging (0 for pure coagulation).
    pub bounces: u64,
}

/// Bytes of the first version of each config (the smallest `struct_size` accepted).
const MASSFLOW_CONFIG_V1: usize = std::mem::size_of::<coag_massflow_config>();
const COUNTS_CONFIG_V1: usize = std::mem::offset_of!(coag_counts_config, batched_clock);
const EVENTFLOW_CONFIG_V1: usize = std::mem::size_of::<coag_eventflow_config>();
const STEP_REPORT_V1: usize = std::mem::size_of::<coag_step_report>();

fn report_of(r: StepReport) -> coag_step_report {
    coag_step_report {
        struct_size: STEP_REPORT_V1,
        time: r.time,
        events: r.events,
        proposals: r.proposals,
        rejections: r.rejections,
        bound_violations: r.bound_violations,
        clipped: r.clipped,
        doublings: r.doublings,
        removed: r.removed,
        bounces: r.bounces,
    }
}

/// Writes `r` into the caller's report, as many bytes as its `struct_size` says.
///
/// # Safety
/// `out` non-null and valid for `out->struct_size` bytes (caller contract).
pub(crate) unsafe fn write_report(out: *mut coag_step_report, r: StepReport) -> Result<(), Fail> {
    // SAFETY: non-null (caller); a report begins with its size_t struct_size.
    let size = unsafe { out.cast::<usize>().read_unaligned() };
    if size < STEP_REPORT_V1 {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!(
                "report->struct_size is {size}: set it to sizeof(coag_step_report) (or call coag_step_report_init)"
            ),
        );
    }
    // (a larger report is from a newer header: the fields this library knows are
    // written, `struct_size` is left as the caller set it)
    let v = report_of(r);
    let n = size.min(STEP_REPORT_V1);
    // SAFETY: `n ≤ size` bytes are writable at out (contract) and readable from v.
    unsafe {
        std::ptr::copy_nonoverlapping(
            (&v as *const coag_step_report).cast::<u8>().add(8),
            out.cast::<u8>().add(8),
            n - 8,
        )
    };
    Ok(())
}

/// The facade over every scheme, as the C ABI instantiates it.
type Dyn = dyn Simulation<Kernel, Fragmentation, Source>;

/// A host callback polled during `coag_sim_advance_to`: non-zero cancels the call.
pub type coag_cancel_callback = Option<unsafe extern "C" fn(user_data: *mut c_void) -> i32>;

/// How a sim was configured: the config struct it was made with.
#[derive(Clone, Copy, Debug)]
enum Config {
    MassFlow(coag_massflow_config),
    Counts(coag_counts_config),
    EventFlow(coag_eventflow_config),
}

/// Opaque simulation handle (`coag_sim` in C).
pub struct coag_sim {
    sim: Box<Dyn>,
    /// The sim's own stream (kept even while a callback is installed).
    own: Generator,
    callback: Option<(unsafe extern "C" fn(*mut c_void) -> u64, *mut c_void)>,
    /// The configuration it was made with (what a checkpoint must match) ...
    built: Config,
    /// ... and as it stands (Δt, mass, volume changed by the setters since).
    config: Config,
    /// The current kernels (for clones and checkpoint fingerprints).
    kernel: Kernel,
    frag: Fragmentation,
    /// Work units per `coag_sim_advance_to` (0: no limit) and the cancellation poll.
    work_limit: u64,
    cancel: Option<(unsafe extern "C" fn(*mut c_void) -> i32, *mut c_void)>,
    /// The initial number of particles of a mass flow algorithm sim (its checkpoints
    /// are for that number: a clone is built with it); 0 for other sims.
    n0: usize,
}

/// # Safety
/// `out` checked non-null and writable (caller contract).
unsafe fn new_sim(
    sim: Box<Dyn>,
    config: Config,
    kernel: Kernel,
    frag: Fragmentation,
    out: *mut *mut coag_sim,
) -> Result<(), Fail> {
    let (seed, stream) = match config {
        Config::MassFlow(c) => (c.seed, c.stream),
        Config::Counts(c) => (c.seed, c.stream),
        Config::EventFlow(c) => (c.seed, c.stream),
    };
    let sim = coag_sim {
        sim,
        own: generator(seed, stream),
        callback: None,
        built: config,
        config,
        kernel,
        frag,
        work_limit: 0,
        cancel: None,
        n0: 0,
    };
    // SAFETY: the function's contract.
    unsafe { write(out, Box::into_raw(Box::new(sim))) };
    Ok(())
}

/// A reference to a live handle.
///
/// # Safety
/// A non-null `p` must be a live handle, not mutated for `'a`.
pub(crate) unsafe fn handle<'a, T>(p: *const T, name: &str) -> Result<&'a T, Fail> {
    non_null(p, name)?;
    // SAFETY: non-null; the function's contract.
    Ok(unsafe { &*p })
}

/// # Safety
/// A non-null `p` must be a live handle used by this thread alone for `'a`.
pub(crate) unsafe fn handle_mut<'a, T>(p: *mut T, name: &str) -> Result<&'a mut T, Fail> {
    non_null(p, name)?;
    // SAFETY: non-null; the function's contract.
    Ok(unsafe { &mut *p })
}

/// Writes `value` into a caller struct of `size` bytes (`sizeof` as the caller compiled
/// it): the fields this library knows, at most `size` bytes, with `struct_size` set to
/// what was written. A caller built against an older header (smaller struct) is never
/// written past its end; `size` below the first version's is refused.
///
/// # Safety
/// A non-null `out` must be valid for writing `size` bytes; T is a repr(C) struct of
/// numbers beginning with a `usize`.
pub(crate) unsafe fn write_sized<T: Copy>(
    out: *mut T,
    size: usize,
    v1: usize,
    value: T,
    name: &str,
) -> Result<(), Fail> {
    non_null(out, "out")?;
    if size < v1 {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!(
                "{name}: size {size} is below the struct's first version ({v1} bytes); pass sizeof the struct"
            ),
        );
    }
    let n = size.min(std::mem::size_of::<T>());
    // SAFETY: `n ≤ size` bytes writable at out (contract), `n ≤ size_of::<T>()` readable
    // from value; then the leading usize (in bounds: n ≥ v1 > 8).
    unsafe {
        std::ptr::copy_nonoverlapping((&value as *const T).cast::<u8>(), out.cast::<u8>(), n);
        out.cast::<usize>().write_unaligned(n);
    }
    Ok(())
}

/// Zero-fills a step report of `size` bytes (`sizeof(coag_step_report)`) and sets its
/// `struct_size`.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_step_report_init(out: *mut coag_step_report, size: usize) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            write_sized(
                out,
                size,
                STEP_REPORT_V1,
                coag_step_report::default(),
                "step report",
            )
        }
    })
}

fn default_massflow() -> coag_massflow_config {
    coag_massflow_config {
        struct_size: MASSFLOW_CONFIG_V1,
        dt: 0.01,
        mass: 1.0,
        points: COAG_POINTS_NIEDERREITER,
        randomization: COAG_RANDOMIZATION_NONE,
        full_sort: 0,
        seed: 0,
        stream: 0,
    }
}

fn default_counts() -> coag_counts_config {
    coag_counts_config {
        struct_size: COUNTS_CONFIG_V1,
        method: COAG_METHOD_LOWRANK,
        volume: 0.0,
        size_limit: 0,
        memory_budget: 0,
        seed: 0,
        stream: 0,
        batched_clock: 0,
        reserved: 0,
        bucket_mode: COAG_BUCKET_AUTO,
    }
}

fn default_eventflow() -> coag_eventflow_config {
    coag_eventflow_config {
        struct_size: EVENTFLOW_CONFIG_V1,
        method: COAG_EVENTFLOW_MFA,
        mass: 1.0,
        truncation: 0.0,
        capacity: 0,
        sampler: COAG_SAMPLER_DEFAULT,
        strict_bound: 0,
        seed: 0,
        stream: 0,
    }
}

/// Writes the default event-driven configuration into a struct of `size` bytes
/// (`sizeof(coag_eventflow_config)`), with `struct_size` set: the mass flow
/// algorithm, mass 1, no truncation, automatic capacity, the default sampler, bound
/// violations counted, seed 0, stream 0.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_eventflow_default_config(
    out: *mut coag_eventflow_config,
    size: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            write_sized(
                out,
                size,
                EVENTFLOW_CONFIG_V1,
                default_eventflow(),
                "eventflow config",
            )
        }
    })
}

/// The registry options of an event-driven config (checked).
fn eventflow_options(c: &coag_eventflow_config) -> Result<Options, Fail> {
    let mut o = Options::default()
        .with_strict_bound(c.strict_bound != 0)
        .with_memory_budget(coagula_core::scheme::population::machine_memory_budget());
    match c.sampler {
        COAG_SAMPLER_DEFAULT => {}
        COAG_SAMPLER_TREE => o = o.with_sampler(coagula_core::scheme::eventflow::Sampler::SumTree),
        COAG_SAMPLER_GROUPS => o = o.with_sampler(coagula_core::scheme::eventflow::Sampler::Groups),
        x => return fail(COAG_INVALID_ARGUMENT, format!("unknown sampler {x}")),
    }
    if c.truncation != 0.0 {
        if c.truncation.is_nan() || c.truncation < 0.0 {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!(
                    "truncation {} (b_N > 0, or 0 for none)",
                    coagula_core::error::Short(c.truncation)
                ),
            );
        }
        o = o.with_truncation(c.truncation);
    }
    let Ok(cap) = usize::try_from(c.capacity) else {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!("capacity {} does not fit this machine", c.capacity),
        );
    };
    Ok(o.with_capacity(cap))
}

/// An event-driven sim over the `n` particle sizes `sizes` (each finite and > 0): the
/// mass flow algorithm or direct simulation (Eibeck & Wagner 2000), or low-rank Monte
/// Carlo over sizes (Osinsky 2023), as `config.method` says (see
/// `coag_eventflow_config` for what the sizes mean). Eibeck & Wagner's schemes need a
/// product majorant `h(x)`, `K(x, y) ≤ h(x) h(y)`, low-rank a low-rank bound (every
/// built-in kernel has both; a user kernel declares them, else `COAG_UNSUPPORTED`). `frag` may be
/// NULL (pure coagulation); with it, break-ups are events at rate `Ḟ(x)` (no time
/// step).
///
/// # Safety
/// Pointers must be NULL or valid (`sizes` for `n` doubles).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_eventflow_new(
    config: *const coag_eventflow_config,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    sizes: *const f64,
    n: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY: NULL is checked; otherwise valid by the caller's contract.
        let (c, id, k, f, x) = unsafe { eventflow_inputs(config, kernel, frag, sizes, n) }?;
        non_null(out, "out")?;
        let c = resolve_eventflow(c, id, n, &f)?;
        let opts = eventflow_options(&c)?;
        let init = Init::Sizes {
            sizes: x,
            mass: c.mass,
        };
        let sim = registry::build(id, k, f, &init, &opts)?;
        // SAFETY: `out` checked non-null; writable (contract).
        unsafe { new_sim(sim, Config::EventFlow(c), k, f, out) }.map(|()| {
            // SAFETY: just written, a live handle.
            unsafe { (**out).n0 = if id == SchemeId::Mfa { n } else { 0 } };
        })
    })
}

/// The inputs of an event-driven constructor: the config (method known), the kernel,
/// the fragmentation kernel (NULL: none) and the sizes.
///
/// # Safety
/// Each pointer NULL or valid (`sizes` for `n` doubles), as the constructors document.
unsafe fn eventflow_inputs<'a>(
    config: *const coag_eventflow_config,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    sizes: *const f64,
    n: usize,
) -> Result<
    (
        coag_eventflow_config,
        SchemeId,
        Kernel,
        Fragmentation,
        &'a [f64],
    ),
    Fail,
> {
    // SAFETY (all four): NULL is checked; otherwise valid by the caller's contract.
    let c = unsafe { read_config(config, "config", EVENTFLOW_CONFIG_V1, default_eventflow()) }?;
    let k = unsafe { handle(kernel, "kernel") }?.k;
    let f = if frag.is_null() {
        Fragmentation::None
    } else {
        unsafe { handle(frag, "frag") }?.f
    };
    let x = unsafe { slice(sizes, n, "sizes") }?;
    Ok((c, eventflow_id(&c)?, k, f, x))
}

/// The registry's scheme of an event-driven config's `COAG_EVENTFLOW_*` method.
fn eventflow_id(c: &coag_eventflow_config) -> Result<SchemeId, Fail> {
    match EVENTFLOW.iter().find(|(m, _)| *m == c.method) {
        Some(&(_, id)) => Ok(id),
        None => fail(
            COAG_INVALID_ARGUMENT,
            format!("unknown eventflow method {}", c.method),
        ),
    }
}

/// Bytes of caller-owned workspace an event-driven sim of `n` particles needs under
/// `config` and `frag` (NULL: none) — for `coag_eventflow_new_in` with the same
/// arguments: the particles and the sum trees (direct simulation: for its capacity).
/// The group sampler's index tables (`COAG_SAMPLER_GROUPS`, the mass flow algorithm's
/// default) are allocated by the library besides.
///
/// # Safety
/// Pointers must be NULL or valid; `out` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_eventflow_workspace_size(
    config: *const coag_eventflow_config,
    frag: *const coag_fragmentation,
    n: usize,
    out: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL is checked; otherwise valid by the caller's contract.
        let c = unsafe { read_config(config, "config", EVENTFLOW_CONFIG_V1, default_eventflow()) }?;
        let f = if frag.is_null() {
            Fragmentation::None
        } else {
            unsafe { handle(frag, "frag") }?.f
        };
        non_null(out, "out")?;
        let bytes = eventflow_workspace(&c, eventflow_id(&c)?, n, &f)?.1;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, bytes) };
        Ok(())
    })
}

/// The resolved configuration and the workspace bytes of an event-driven sim.
fn eventflow_workspace(
    c: &coag_eventflow_config,
    id: SchemeId,
    n: usize,
    f: &Fragmentation,
) -> Result<(coag_eventflow_config, usize), Fail> {
    let c = resolve_eventflow(*c, id, n, f)?;
    if id == SchemeId::LowRankSizes {
        return fail(
            COAG_UNSUPPORTED,
            "caller-owned workspace: low-rank over sizes grows its size buckets (use coag_eventflow_new)",
        );
    }
    // (what the constructor would refuse, the query refuses)
    eventflow_options(&c)?;
    // (the registry's rule: N particles, or direct simulation's capacity, resolved)
    let particles = match id {
        SchemeId::Mfa => n,
        _ => usize::try_from(c.capacity).unwrap_or(usize::MAX),
    };
    let len = coagula_core::scheme::eventflow::workspace_len(particles);
    Ok((c, workspace_bytes_for(len, n)?))
}

/// `coag_eventflow_new` in memory the caller owns: `workspace` (aligned for `double`,
/// `workspace_bytes` ≥ `coag_eventflow_workspace_size` for the same config, frag and
/// n) holds the particles and their sum trees for the sim's whole life; no step
/// allocates (the group sampler's index tables excepted: allocated here). The caller
/// keeps the buffer alive and untouched until `coag_sim_free`; the sim zeroes it
/// first, so after a refused construction its contents are lost. `sizes` must not
/// overlap it. A clone (`coag_sim_clone`) lives in memory the library owns.
///
/// # Safety
/// Pointers must be NULL or valid; `workspace` valid for `workspace_bytes` bytes and
/// used by nothing else until the sim is freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_eventflow_new_in(
    config: *const coag_eventflow_config,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    sizes: *const f64,
    n: usize,
    workspace: *mut c_void,
    workspace_bytes: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY: NULL is checked; otherwise valid by the caller's contract.
        let (c, id, k, f, x) = unsafe { eventflow_inputs(config, kernel, frag, sizes, n) }?;
        non_null(out, "out")?;
        let (c, need) = eventflow_workspace(&c, id, n, &f)?;
        check_workspace(workspace, workspace_bytes, need, x)?;
        // what can be refused without the kernel, before the caller's memory is zeroed
        if x.is_empty() || x.iter().any(|&v| !(v > 0.0 && v.is_finite())) {
            return fail(
                COAG_INVALID_ARGUMENT,
                "sizes: at least one, each finite and > 0",
            );
        }
        if c.truncation > 0.0 && x.iter().any(|&v| v > c.truncation) {
            return fail(
                COAG_INVALID_ARGUMENT,
                "truncation b_N below the largest initial size",
            );
        }
        if id == SchemeId::Dsa && (n as u64) > c.capacity {
            return fail(
                crate::COAG_CAPACITY,
                format!("capacity {} below the {n} initial particles", c.capacity),
            );
        }
        let opts = eventflow_options(&c)?;
        let init = Init::Sizes {
            sizes: x,
            mass: c.mass,
        };
        // SAFETY: checked by check_workspace; valid and exclusively the sim's until
        // coag_sim_free (contract)
        let ws = unsafe { zeroed_workspace(workspace, need) };
        let sim = registry::build_in(id, k, f, &init, &opts, ws)?;
        // SAFETY: `out` checked non-null; writable (contract).
        unsafe { new_sim(sim, Config::EventFlow(c), k, f, out) }.map(|()| {
            // SAFETY: just written, a live handle.
            unsafe { (**out).n0 = if id == SchemeId::Mfa { n } else { 0 } };
        })
    })
}

/// An event-driven configuration as it runs, each setting in one canonical form, so
/// that a checkpoint's configuration record matches exactly the sims that run the same
/// way: the default sampler named (groups for the mass flow algorithm, the sum tree
/// for direct simulation), no truncation as 0, direct simulation's automatic capacity
/// resolved (the registry's rule: the initial number, four times it with
/// fragmentation), `strict_bound` 0 or 1. Refused: a truncation for direct simulation
/// or a capacity for the mass flow algorithm (settings they do not have), and a
/// capacity whose workspace exceeds the machine's memory budget.
fn resolve_eventflow(
    c: coag_eventflow_config,
    id: SchemeId,
    n: usize,
    f: &Fragmentation,
) -> Result<coag_eventflow_config, Fail> {
    let mut c = c;
    c.strict_bound = i32::from(c.strict_bound != 0);
    if c.truncation == f64::INFINITY || c.truncation == 0.0 {
        c.truncation = 0.0; // (also −0.0)
    }
    if id == SchemeId::LowRankSizes {
        let unused = [
            (
                c.capacity != 0,
                "capacity: low-rank over sizes never adds particles (leave it 0)",
            ),
            (
                c.truncation != 0.0,
                "truncation: low-rank over sizes keeps every particle (leave it 0)",
            ),
            (
                c.sampler != COAG_SAMPLER_DEFAULT,
                "sampler: low-rank over sizes draws from its bound's buckets (leave it COAG_SAMPLER_DEFAULT)",
            ),
            (
                c.strict_bound != 0,
                "strict_bound: low-rank over sizes always refuses a kernel above its bound (leave it 0)",
            ),
            (
                !matches!(f, Fragmentation::None),
                "fragmentation: low-rank over sizes only coagulates (pass NULL)",
            ),
        ];
        if let Some((_, why)) = unused.iter().find(|(set, _)| *set) {
            return fail(COAG_INVALID_ARGUMENT, *why);
        }
        within_machine_budget(n)?;
        return Ok(c);
    }
    let mfa = id == SchemeId::Mfa;
    c.sampler = match (c.sampler, mfa) {
        (COAG_SAMPLER_DEFAULT, true) => COAG_SAMPLER_GROUPS,
        (COAG_SAMPLER_DEFAULT, false) => COAG_SAMPLER_TREE,
        (x, _) => x,
    };
    if mfa {
        if c.capacity != 0 {
            return fail(
                COAG_INVALID_ARGUMENT,
                "capacity: the mass flow algorithm keeps its initial number of particles (capacity is for direct simulation; leave it 0)",
            );
        }
        within_machine_budget(n)?;
        return Ok(c);
    }
    if c.truncation != 0.0 {
        return fail(
            COAG_INVALID_ARGUMENT,
            "truncation: direct simulation keeps every particle (b_N is for the mass flow algorithm; leave it 0)",
        );
    }
    if c.capacity == 0 {
        let auto = if matches!(f, Fragmentation::None) {
            n.max(1)
        } else {
            n.saturating_mul(4).max(1)
        };
        c.capacity = auto as u64;
    }
    within_machine_budget(usize::try_from(c.capacity).unwrap_or(usize::MAX))?;
    Ok(c)
}

/// Refuses an event-driven workspace for `particles` (sizes and trees) past the memory
/// budget the size-count schemes grow within (half the machine's memory).
fn within_machine_budget(particles: usize) -> Result<(), Fail> {
    let budget = coagula_core::scheme::population::machine_memory_budget();
    match coagula_core::scheme::eventflow::workspace_len(particles)
        .and_then(|l| l.checked_mul(std::mem::size_of::<f64>()))
    {
        Some(b) if b <= budget => Ok(()),
        b => fail(
            crate::COAG_CAPACITY,
            format!(
                "{particles} particles: {} bytes of workspace, past the memory budget of {budget} bytes",
                b.map_or("more than 2^64".to_string(), |b| b.to_string())
            ),
        ),
    }
}

/// Writes the default mass-flow configuration into a struct of `size` bytes
/// (`sizeof(coag_massflow_config)`), with `struct_size` set: Δt = 0.01, mass 1,
/// Niederreiter points, no randomisation, adaptive sort, seed 0, stream 0.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_massflow_default_config(
    out: *mut coag_massflow_config,
    size: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            write_sized(
                out,
                size,
                MASSFLOW_CONFIG_V1,
                default_massflow(),
                "massflow config",
            )
        }
    })
}

/// Writes the default size-count configuration into a struct of `size` bytes
/// (`sizeof(coag_counts_config)`), with `struct_size` set: the bucketed low-rank
/// method, volume = number of particles, default size limit, the machine's memory
/// budget (0: half its physical memory), seed 0, stream 0.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_counts_default_config(
    out: *mut coag_counts_config,
    size: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            write_sized(
                out,
                size,
                COUNTS_CONFIG_V1,
                default_counts(),
                "counts config",
            )
        }
    })
}

/// The point source of a mass-flow config (the scrambling draws from its own stream
/// of the seed policy, so the sim's stream is the same with and without it).
fn points_of(c: &coag_massflow_config) -> Result<PointSource, Fail> {
    let kind = match c.randomization {
        COAG_RANDOMIZATION_NONE => None,
        COAG_RANDOMIZATION_SHIFT => Some(Randomization::DigitalShift),
        COAG_RANDOMIZATION_MATOUSEK => Some(Randomization::Matousek),
        COAG_RANDOMIZATION_OWEN => Some(Randomization::Owen),
        r => return fail(COAG_INVALID_ARGUMENT, format!("unknown randomization {r}")),
    };
    let mut scramble = substream(c.seed, c.stream, Purpose::Scrambling);
    Ok(match (c.points, kind) {
        (COAG_POINTS_NIEDERREITER, None) => PointSource::niederreiter(),
        (COAG_POINTS_SOBOL, None) => PointSource::sobol(),
        (COAG_POINTS_NIEDERREITER, Some(r)) => {
            PointSource::randomized_niederreiter(r, &mut scramble)
        }
        (COAG_POINTS_SOBOL, Some(r)) => PointSource::randomized_sobol(r, &mut scramble),
        (COAG_POINTS_MONTE_CARLO, None) => PointSource::monte_carlo(),
        (COAG_POINTS_MONTE_CARLO, Some(_)) => {
            return fail(
                COAG_INVALID_ARGUMENT,
                "Monte Carlo points cannot be randomised",
            );
        }
        (p, _) => return fail(COAG_INVALID_ARGUMENT, format!("unknown points {p}")),
    })
}

/// The inputs of a mass-flow constructor: the config, the kernel, the fragmentation
/// kernel (NULL: none) and the sizes.
///
/// # Safety
/// Each pointer NULL or valid (`sizes` for `n` doubles), as the constructors document.
unsafe fn massflow_inputs<'a>(
    config: *const coag_massflow_config,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    sizes: *const f64,
    n: usize,
) -> Result<(coag_massflow_config, Kernel, Fragmentation, &'a [f64]), Fail> {
    // SAFETY (all four): NULL is checked; otherwise valid by the caller's contract.
    let c = unsafe { read_config(config, "config", MASSFLOW_CONFIG_V1, default_massflow()) }?;
    let k = unsafe { handle(kernel, "kernel") }?.k;
    let f = if frag.is_null() {
        Fragmentation::None
    } else {
        unsafe { handle(frag, "frag") }?.f
    };
    let x = unsafe { slice(sizes, n, "sizes") }?;
    Ok((c, k, f, x))
}

/// The registry options of a mass-flow config.
fn massflow_options(c: &coag_massflow_config) -> Result<Options, Fail> {
    Ok(Options::default()
        .with_dt(c.dt)
        .with_points(points_of(c)?)
        .with_sorting(if c.full_sort != 0 {
            Sorting::Full
        } else {
            Sorting::Adaptive
        }))
}

/// A time-driven mass-flow sim (Lécot et al. 2019) over the `n` particle sizes `sizes`
/// (n a power of two ≥ 2). `frag` may be NULL (pure coagulation).
///
/// # Safety
/// Pointers must be NULL or valid (`sizes` for `n` doubles).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_massflow_new(
    config: *const coag_massflow_config,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    sizes: *const f64,
    n: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY: NULL is checked; otherwise valid by the caller's contract.
        let (c, k, f, x) = unsafe { massflow_inputs(config, kernel, frag, sizes, n) }?;
        non_null(out, "out")?;
        let opts = massflow_options(&c)?;
        let init = Init::Sizes {
            sizes: x,
            mass: c.mass,
        };
        let sim = registry::build(SchemeId::MassFlow, k, f, &init, &opts)?;
        // SAFETY: `out` checked non-null; writable (contract).
        unsafe { new_sim(sim, Config::MassFlow(c), k, f, out) }
    })
}

/// Bytes of caller-owned workspace a mass-flow sim of `n` particles needs (for
/// `coag_massflow_new_in`): `6 n` doubles. The LAPACK `lwork` habit: query, allocate,
/// construct.
///
/// # Safety
/// `out` must be NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_massflow_workspace_size(n: usize, out: *mut usize) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        let Some(bytes) = coagula_core::scheme::massflow::workspace_len(n)
            .and_then(|l| l.checked_mul(std::mem::size_of::<f64>()))
            .filter(|&b| b <= isize::MAX as usize)
        else {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!("workspace for {n} particles overflows"),
            );
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, bytes) };
        Ok(())
    })
}

/// Bytes of a workspace of `len` doubles (`None`: it overflows), refused past
/// `isize::MAX`.
fn workspace_bytes_for(len: Option<usize>, n: usize) -> Result<usize, Fail> {
    match len
        .and_then(|l| l.checked_mul(std::mem::size_of::<f64>()))
        .filter(|&b| b <= isize::MAX as usize)
    {
        Some(b) => Ok(b),
        None => fail(
            COAG_INVALID_ARGUMENT,
            format!("workspace for {n} particles overflows"),
        ),
    }
}

/// Checks a caller workspace for `need` bytes: non-null, aligned for `double`, large
/// enough, not overlapping `sizes`.
pub(crate) fn check_workspace(
    workspace: *mut c_void,
    bytes: usize,
    need: usize,
    sizes: &[f64],
) -> Result<(), Fail> {
    non_null(workspace, "workspace")?;
    if !(workspace as usize).is_multiple_of(std::mem::align_of::<f64>()) {
        return fail(COAG_INVALID_ARGUMENT, "workspace is not aligned for double");
    }
    if bytes < need {
        return fail(
            crate::COAG_BUFFER_TOO_SMALL,
            format!(
                "workspace: {bytes} bytes for {} particles, {need} needed",
                sizes.len()
            ),
        );
    }
    let (w0, s0) = (workspace as usize, sizes.as_ptr() as usize);
    if !sizes.is_empty() && w0 < s0.saturating_add(8 * sizes.len()) && s0 < w0.saturating_add(need)
    {
        return fail(COAG_INVALID_ARGUMENT, "sizes overlap the workspace");
    }
    Ok(())
}

/// The caller's workspace as a slice of doubles, zeroed (so that it is initialised).
///
/// # Safety
/// `workspace` passed [`check_workspace`] for `need` bytes, and is valid and used by
/// nothing else for the life of the sim built on it.
unsafe fn zeroed_workspace(workspace: *mut c_void, need: usize) -> &'static mut [f64] {
    // SAFETY: the function's contract.
    unsafe {
        std::ptr::write_bytes(workspace.cast::<u8>(), 0, need);
        std::slice::from_raw_parts_mut(workspace.cast::<f64>(), need / 8)
    }
}

/// `coag_massflow_new` in memory the caller owns: `workspace` (aligned for `double`,
/// `workspace_bytes` ≥ `coag_massflow_workspace_size(n)`) holds the particles, the
/// points and the scratch for the sim's whole life; no step allocates. The caller keeps
/// the buffer alive and untouched until `coag_sim_free` (the sim zeroes it first);
/// `sizes` must not overlap it.
///
/// # Safety
/// Pointers must be NULL or valid; `workspace` valid for `workspace_bytes` bytes and
/// used by nothing else until the sim is freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_massflow_new_in(
    config: *const coag_massflow_config,
    kernel: *const coag_kernel,
    frag: *const coag_fragmentation,
    sizes: *const f64,
    n: usize,
    workspace: *mut c_void,
    workspace_bytes: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY: NULL is checked; otherwise valid by the caller's contract.
        let (c, k, f, x) = unsafe { massflow_inputs(config, kernel, frag, sizes, n) }?;
        non_null(out, "out")?;
        let need = workspace_bytes_for(coagula_core::scheme::massflow::workspace_len(n), n)?;
        check_workspace(workspace, workspace_bytes, need, x)?;
        // everything the construction can refuse, before the caller's memory is zeroed
        coagula_core::scheme::massflow::check_setup(x, c.mass, c.dt)?;
        let opts = massflow_options(&c)?;
        let init = Init::Sizes {
            sizes: x,
            mass: c.mass,
        };
        // SAFETY: checked by check_workspace; valid and exclusively the sim's until
        // coag_sim_free (contract)
        let ws = unsafe { zeroed_workspace(workspace, need) };
        let sim = registry::build_in(SchemeId::MassFlow, k, f, &init, &opts, ws)?;
        // SAFETY: `out` checked non-null; writable (contract).
        unsafe { new_sim(sim, Config::MassFlow(c), k, f, out) }
    })
}

/// A size-count sim: `counts[i]` particles of size `i + 1`, `len` entries, with
/// `config.method` choosing the scheme — low-rank Monte Carlo (bucketed layout, the
/// default, or the per-size tree layout; the kernel needs a low-rank bound of rank
/// 1..4), the inverse method, or acceptance–rejection (the kernel needs its supremum).
///
/// # Safety
/// Pointers must be NULL or valid (`counts` for `len` values).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_counts_new(
    config: *const coag_counts_config,
    kernel: *const coag_kernel,
    counts: *const u64,
    len: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        // SAFETY (all three): NULL is checked; otherwise valid by the caller's contract.
        let mut c = unsafe { read_config(config, "config", COUNTS_CONFIG_V1, default_counts()) }?;
        // (an older caller's tail padding)
        c.reserved = 0;
        let k = unsafe { handle(kernel, "kernel") }?.k;
        let n = unsafe { slice(counts, len, "counts") }?;
        non_null(out, "out")?;
        let Some(&(_, id)) = METHODS.iter().find(|(m, _)| *m == c.method) else {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!("unknown method {}", c.method),
            );
        };
        let total: u64 = n.iter().fold(0u64, |a, &b| a.saturating_add(b));
        // the configuration as given is what a checkpoint must match (a host rebuilding
        // a sim to restore into may pass placeholder counts); resolved, what runs
        let given = c;
        if c.volume == 0.0 {
            // (an empty system: volume 1)
            c.volume = total.max(1) as f64;
        }
        c.batched_clock = i32::from(c.batched_clock != 0);
        if c.size_limit == 0 {
            c.size_limit = Options::default().size_limit;
        }
        let init = Init::Counts {
            counts: n,
            volume: c.volume,
        };
        let sim = registry::build(id, k, Fragmentation::None, &init, &counts_options(&c)?)?;
        let mut given = given;
        given.batched_clock = c.batched_clock;
        // SAFETY: `out` checked non-null; writable (contract).
        unsafe { new_sim(sim, Config::Counts(c), k, Fragmentation::None, out) }.map(|()| {
            // SAFETY: just written, a live handle.
            unsafe { (**out).built = Config::Counts(given) };
        })
    })
}

/// The engine a `COAG_BUCKET_*` code pins (`None`: chosen by size).
fn bucket_mode_of(code: i32) -> Result<Option<BucketMode>, Fail> {
    match code {
        COAG_BUCKET_AUTO => Ok(None),
        COAG_BUCKET_SLOTS => Ok(Some(BucketMode::Slots)),
        COAG_BUCKET_COUNTED => Ok(Some(BucketMode::Counted)),
        m => fail(
            COAG_INVALID_ARGUMENT,
            format!("unknown bucket_mode {m} (COAG_BUCKET_AUTO, _SLOTS or _COUNTED)"),
        ),
    }
}

/// The registry options of a counts config (volume and size limit resolved).
/// Errors: an unknown `bucket_mode`, or a pin on a method without engines.
fn counts_options(c: &coag_counts_config) -> Result<Options, Fail> {
    let mode = bucket_mode_of(c.bucket_mode)?;
    if mode.is_some() && c.method != COAG_METHOD_LOWRANK {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!(
                "bucket_mode {}: only the bucketed low-rank method (COAG_METHOD_LOWRANK) has engines; pass COAG_BUCKET_AUTO",
                c.bucket_mode
            ),
        );
    }
    let budget = match c.memory_budget {
        0 => coagula_core::scheme::population::machine_memory_budget(),
        b => usize::try_from(b).unwrap_or(usize::MAX),
    };
    Ok(Options::default()
        .with_memory_budget(budget)
        .with_size_limit(c.size_limit)
        .with_batched_clock(c.batched_clock != 0)
        .with_bucket_mode(mode))
}

/// The `COAG_METHOD_*` of a size-count sim (`COAG_UNSUPPORTED` for a mass-flow sim).
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_method(sim: *const coag_sim, out: *mut i32) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let id = s.sim.id();
        let Some(&(m, _)) = METHODS.iter().find(|(_, i)| *i == id) else {
            return fail(
                COAG_UNSUPPORTED,
                "method: a sim over particle sizes (mass flow, mfa, dsa, lowrank-sizes) has no COAG_METHOD (an event-driven sim's is in coag_sim_eventflow_config)",
            );
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, m) };
        Ok(())
    })
}

/// The engine a bucketed low-rank sim runs now: `COAG_BUCKET_SLOTS` or
/// `COAG_BUCKET_COUNTED` (chosen by size unless the config pinned it;
/// `COAG_UNSUPPORTED` for any other method).
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_bucket_mode(sim: *const coag_sim, out: *mut i32) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let m = match s.sim.bucket_mode() {
            Some(BucketMode::Slots) => COAG_BUCKET_SLOTS,
            Some(BucketMode::Counted) => COAG_BUCKET_COUNTED,
            None => {
                return fail(
                    COAG_UNSUPPORTED,
                    format!(
                        "bucket_mode: a {} sim has no bucket engines (only COAG_METHOD_LOWRANK)",
                        s.sim.id().name()
                    ),
                );
            }
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, m) };
        Ok(())
    })
}

/// Releases a sim (NULL is a no-op).
///
/// # Safety
/// `sim` must be NULL or a handle from a `coag_*_new` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_free(sim: *mut coag_sim) {
    if !sim.is_null() {
        // SAFETY: created by Box::into_raw, freed once (caller contract).
        drop(unsafe { Box::from_raw(sim) });
    }
}

/// Runs `f` on a live sim (read-only) and writes its result to `out`.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
unsafe fn read<T>(
    sim: *const coag_sim,
    out: *mut T,
    f: impl FnOnce(&coag_sim) -> Result<T, Fail>,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let v = f(s)?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, v) };
        Ok(())
    })
}

/// Runs the sim until time `t` (≥ its current time): time-driven schemes take steps of
/// Δt (a last shorter one lands on t), event-driven schemes process every event before
/// t (and keep the time of the next one for the next call: see
/// `coag_counts_config.batched_clock`). `report` may be NULL; otherwise its
/// `struct_size` must be set.
///
/// Bounded calls: with `coag_sim_set_work_limit` or `coag_sim_set_cancel_callback`, a
/// call that spends its work units or is cancelled returns `COAG_INTERRUPTED` with the
/// sim consistent at the time reached (written to `report->time`, read with
/// `coag_sim_time`); calling again continues the same run. With a host random
/// callback (`coag_sim_set_rng_callback`) that turns out stuck (the same word 8 times
/// in a row), the call returns `COAG_RNG_FAILURE` and the sim is as before the call.
///
/// # Safety
/// `sim` must be NULL or live; `report` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_advance_to(
    sim: *mut coag_sim,
    t: f64,
    report: *mut coag_step_report,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        if !report.is_null() {
            // validate the report before the sim changes
            // SAFETY: non-null; readable by contract.
            let size = unsafe { report.cast::<usize>().read_unaligned() };
            if size < STEP_REPORT_V1 {
                return fail(
                    COAG_INVALID_ARGUMENT,
                    format!(
                        "report->struct_size is {size}: set it to sizeof(coag_step_report) (or call coag_step_report_init)"
                    ),
                );
            }
        }
        let mut rng = match s.callback {
            Some((f, d)) => Source::callback(f, d),
            None => Source::Own(s.own.clone()),
        };
        // a host stream may turn out stuck: the state before the call, to go back to
        let before = if s.callback.is_some() {
            let mut w = Writer::new(&mut []);
            s.sim.save(&mut w);
            let mut buf = Vec::new();
            if buf.try_reserve_exact(w.needed()).is_err() {
                return fail(
                    crate::COAG_CAPACITY,
                    format!(
                        "a host random callback needs a snapshot of the sim ({} bytes) the allocator refused",
                        w.needed()
                    ),
                );
            }
            buf.resize(w.needed(), 0);
            s.sim.save(&mut Writer::new(&mut buf));
            Some(buf)
        } else {
            None
        };
        // (a nested call on this thread — a callback advancing another sim — keeps
        // the outer call's flag)
        let outer_flag = DEGENERATE.with(|c| c.replace(false));
        let host_cancel = s.cancel;
        let mut cancel = || {
            DEGENERATE.with(|c| c.get())
                || host_cancel.is_some_and(|(f, d)| {
                    // SAFETY: the host registered the callback and user_data and keeps
                    // them valid while installed.
                    unsafe { f(d) != 0 }
                })
        };
        let units = if s.work_limit == 0 {
            u64::MAX
        } else {
            s.work_limit
        };
        let mut budget = Budget::work(units).with_cancel(&mut cancel);
        let r = s.sim.advance_within(t, &mut budget, &mut rng);
        let degenerate = DEGENERATE.with(|c| c.replace(outer_flag));
        if degenerate {
            if let Some(buf) = before {
                s.sim.restore(&mut Reader::new(&buf))?;
            }
            return fail(
                COAG_RNG_FAILURE,
                format!(
                    "the host random callback returned the same word {STUCK_AFTER} times in a row: the call was undone"
                ),
            );
        }
        if let Source::Own(p) = rng {
            s.own = p;
        }
        let r = r?;
        if !report.is_null() {
            // SAFETY: non-null, validated size; writable by contract.
            unsafe { write_report(report, r) }?;
        }
        if r.interrupted {
            return fail(
                COAG_INTERRUPTED,
                format!(
                    "interrupted at t = {} on the way to {} (work limit or cancellation): call again to continue",
                    coagula_core::error::Short(r.time),
                    coagula_core::error::Short(t)
                ),
            );
        }
        Ok(())
    })
}

/// Sets the work one `coag_sim_advance_to` may do: `units` proposals (event-driven
/// schemes) or particle updates (mass flow: N per time step; a step is taken whole
/// while a unit is left); 0 removes the limit (the default). Past it the call returns
/// `COAG_INTERRUPTED`, the sim consistent at the time reached.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_work_limit(sim: *mut coag_sim, units: u64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.work_limit = units;
        Ok(())
    })
}

/// Installs a callback polled during `coag_sim_advance_to` (every 16384 proposals, and
/// before every mass-flow step): a non-zero return stops the call with
/// `COAG_INTERRUPTED`, the sim consistent at the time reached. `cancel` NULL removes it.
/// The callback must not call into this sim (it is being changed) nor free it.
///
/// # Safety
/// `sim` NULL or live; `cancel` and `user_data` valid while installed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_cancel_callback(
    sim: *mut coag_sim,
    cancel: coag_cancel_callback,
    user_data: *mut c_void,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.cancel = cancel.map(|f| (f, user_data));
        Ok(())
    })
}

/// The sim's current time.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_time(sim: *const coag_sim, out: *mut f64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { read(sim, out, |s| Ok(s.sim.time())) }
}

/// Totals of every `coag_sim_advance_to` so far (`out->struct_size` must be set).
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_totals(sim: *const coag_sim, out: *mut coag_step_report) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        // SAFETY: non-null; writable for its struct_size (contract).
        unsafe { write_report(out, s.sim.totals()) }
    })
}

/// The moment `M_m` (any real order m) of the number concentration; a result that
/// overflows a double (e.g. M_{1e6}) is `COAG_CAPACITY`.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_moment(sim: *const coag_sim, m: f64, out: *mut f64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if !m.is_finite() {
                return fail(COAG_INVALID_ARGUMENT, "moment order must be finite");
            }
            finite_result(s.sim.moment(m), || {
                format!("moment of order {}", coagula_core::error::Short(m))
            })
        })
    }
}

/// The number concentration of sizes in `[a, b]` (the sum concentration C(t, a, b));
/// `a > b` or a NaN bound is `COAG_INVALID_ARGUMENT`, a sum that overflows a double
/// (counts in a tiny volume) `COAG_CAPACITY`.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_concentration(
    sim: *const coag_sim,
    a: f64,
    b: f64,
    out: *mut f64,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if a.is_nan() || b.is_nan() {
                return fail(COAG_INVALID_ARGUMENT, "concentration bounds are NaN");
            }
            if a > b {
                return fail(
                    COAG_INVALID_ARGUMENT,
                    format!(
                        "concentration bounds a = {} > b = {}",
                        coagula_core::error::Short(a),
                        coagula_core::error::Short(b)
                    ),
                );
            }
            // + 0.0 turns an empty sum's −0.0 into 0
            finite_result(s.sim.concentration(a, b) + 0.0, || {
                "concentration (counts over a tiny volume)".into()
            })
        })
    }
}

/// Gel mass estimate: for size-count schemes the largest cluster's mass per volume
/// (Eibeck & Wagner eq. 6.15); 0 for the mass-flow scheme, whose particles never leave.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_gel_mass(sim: *const coag_sim, out: *mut f64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            finite_result(s.sim.gel_mass().unwrap_or(0.0), || "gel mass".into())
        })
    }
}

/// `v` when finite; else `COAG_CAPACITY` naming `what` (an observable that overflows a
/// double — e.g. M_{1e6}, large sizes, counts in a tiny volume — is not a number the
/// host can use).
fn finite_result(v: f64, what: impl FnOnce() -> String) -> Result<f64, Fail> {
    if v.is_finite() {
        Ok(v)
    } else {
        fail(
            crate::COAG_CAPACITY,
            format!("{} overflows a double ({v})", what()),
        )
    }
}

/// Number of simulation particles.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_particle_count(sim: *const coag_sim, out: *mut u64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { read(sim, out, |s| Ok(s.sim.particles())) }
}

/// Length of the sim's state vector: the number of particles (mass-flow: read with
/// `coag_sim_get_sizes`) or the largest occupied size (size-count schemes: the dense
/// vector `coag_sim_get_counts` fills; 0 for an empty system). Nothing is allocated:
/// a state whose largest size is huge but whose occupied sizes are few is better read
/// with `coag_sim_occupied` and `coag_sim_get_pairs`.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_state_len(sim: *const coag_sim, out: *mut usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if let Some(n) = particle_sizes_len(s) {
                return Ok(n);
            }
            let mut largest = 0u64;
            s.sim.for_each_count(&mut |size, _| largest = size)?;
            usize::try_from(largest).or_else(|_| {
                fail(
                    crate::COAG_CAPACITY,
                    "state length: the largest size does not fit size_t",
                )
            })
        })
    }
}

/// The number of particles of a mass-flow sim (its state is its sizes; `None` for a
/// size-count sim, whose dense state is not built to find out).
fn particle_sizes_len(s: &coag_sim) -> Option<usize> {
    if s.sim.id().info().state != registry::StateKind::Sizes {
        return None;
    }
    match s.sim.state() {
        State::Sizes(x) => Some(x.len()),
        State::Counts(..) => None,
    }
}

/// The number of occupied sizes of a size-count sim (the pairs `coag_sim_get_pairs`
/// writes), or of particles of a mass-flow sim.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_occupied(sim: *const coag_sim, out: *mut usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if let Some(n) = particle_sizes_len(s) {
                return Ok(n);
            }
            let mut n = 0usize;
            s.sim.for_each_count(&mut |_, _| n += 1)?;
            Ok(n)
        })
    }
}

/// The occupied sizes of a size-count sim and their counts, ascending (`sizes` and
/// `counts` must not overlap: `COAG_INVALID_ARGUMENT`): `sizes[i]` has
/// `counts[i]` particles, for `i < *written` (= `coag_sim_occupied`); both buffers hold
/// `len` values (`COAG_BUFFER_TOO_SMALL` below the occupied count, nothing written).
/// No dense vector is built: O(occupied sizes) however large the sizes are. The volume
/// goes to `*volume` (may be NULL); `written` may be NULL.
///
/// # Safety
/// `sim` NULL or live; `sizes` and `counts` valid for `len` values; `volume` and
/// `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_get_pairs(
    sim: *const coag_sim,
    sizes: *mut u64,
    counts: *mut u64,
    len: usize,
    volume: *mut f64,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let mut n = 0usize;
        s.sim.for_each_count(&mut |_, _| n += 1)?;
        if len < n {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!("pairs: buffers of {len} for {n} occupied sizes"),
            );
        }
        let (a, b) = (sizes as usize, counts as usize);
        let bytes = len.saturating_mul(8);
        if len > 0 && a < b.saturating_add(bytes) && b < a.saturating_add(bytes) {
            return fail(COAG_INVALID_ARGUMENT, "pairs: sizes and counts overlap");
        }
        // SAFETY: NULL checked; `len` writable values by contract; not overlapping.
        let out_s = unsafe { slice_mut(sizes, len, "sizes") }?;
        let out_c = unsafe { slice_mut(counts, len, "counts") }?;
        let mut i = 0;
        s.sim.for_each_count(&mut |size, c| {
            if i < len {
                out_s[i] = size;
                out_c[i] = c;
            }
            i += 1;
        })?;
        if !volume.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(volume, s.sim.volume()) };
        }
        if !written.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(written, n) };
        }
        Ok(())
    })
}

/// Replaces the state of a size-count sim by `counts[i]` particles of size `sizes[i]`
/// (`len` pairs, any order, each size ≥ 1 and within the size limit, a size at most
/// once) in volume `volume`, as `coag_sim_set_counts` does — without a dense vector
/// from the host. Acceptance–rejection builds its particle list from them directly;
/// the low-rank and inverse schemes keep tables up to the largest size anyway and
/// build from a count vector within the memory budget (`COAG_CAPACITY` past it).
/// Errors leave the sim unchanged.
///
/// # Safety
/// `sim` NULL or live; `sizes` and `counts` valid for `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_pairs(
    sim: *mut coag_sim,
    sizes: *const u64,
    counts: *const u64,
    len: usize,
    volume: f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        let xs = unsafe { slice(sizes, len, "sizes") }?;
        let cs = unsafe { slice(counts, len, "counts") }?;
        if !matches!(s.config, Config::Counts(_)) {
            return fail(
                COAG_UNSUPPORTED,
                "pairs: a mass-flow sim has sizes (use coag_sim_set_sizes)",
            );
        }
        s.sim.set_pairs(xs, cs, volume)?;
        if let Config::Counts(c) = &mut s.config {
            c.volume = volume;
        }
        Ok(())
    })
}

/// Copies the particle sizes of a sim over particle sizes into `buf`, which must hold
/// `coag_sim_state_len` values: sorted ascending for the time-driven mass-flow
/// scheme, in storage order for the event-driven ones.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_get_sizes(
    sim: *const coag_sim,
    buf: *mut f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        // (a size-count sim is refused before its dense counts are built)
        let sizes = if particle_sizes_len(s).is_some() {
            Some(s.sim.state())
        } else {
            None
        };
        let Some(State::Sizes(x)) = sizes else {
            return fail(
                COAG_UNSUPPORTED,
                "sizes: not a mass-flow sim (use coag_sim_get_counts)",
            );
        };
        if len < x.len() {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!("sizes: buffer of {len} for {} particles", x.len()),
            );
        }
        // SAFETY: NULL checked; `len` writable doubles by contract.
        let out = unsafe { slice_mut(buf, len, "buf") }?;
        out[..x.len()].copy_from_slice(x);
        Ok(())
    })
}

/// Replaces the particle sizes of a sim over particle sizes (each finite and > 0): a
/// host applying growth or nucleation between steps. The time-driven mass-flow scheme
/// takes the same number of sizes; the mass flow algorithm at most its initial number
/// N (the rest count as gone to the gel), each at most its truncation `b_N`; direct
/// simulation at most its capacity (its volume stays).
///
/// # Safety
/// `sim` NULL or live; `sizes` valid for `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_sizes(
    sim: *mut coag_sim,
    sizes: *const f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        let x = unsafe { slice(sizes, len, "sizes") }?;
        s.sim.set_sizes(x)?;
        Ok(())
    })
}

/// Copies the counts `N_i` (`buf[i]` for size `i + 1`) of a size-count sim into `buf`
/// (at least `coag_sim_state_len` entries; extra entries are zeroed) and its volume into
/// `*volume` (may be NULL).
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` values; `volume` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_get_counts(
    sim: *const coag_sim,
    buf: *mut u64,
    len: usize,
    volume: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        // the largest occupied size first (nothing allocated), then the counts straight
        // into the caller's buffer
        let mut largest = 0u64;
        if s.sim.for_each_count(&mut |size, _| largest = size).is_err() {
            return fail(
                COAG_UNSUPPORTED,
                "counts: a mass-flow sim has sizes (use coag_sim_get_sizes)",
            );
        }
        if (len as u64) < largest {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!("counts: buffer of {len} for sizes up to {largest}"),
            );
        }
        // SAFETY: NULL checked; `len` writable values by contract.
        let out = unsafe { slice_mut(buf, len, "buf") }?;
        out.iter_mut().for_each(|c| *c = 0);
        s.sim
            .for_each_count(&mut |size, c| out[size as usize - 1] = c)?;
        if !volume.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(volume, s.sim.volume()) };
        }
        Ok(())
    })
}

/// Replaces the counts and the volume of a size-count sim (a host applying growth or
/// nucleation between steps). The new particle number becomes the reference for
/// particle doubling.
///
/// # Safety
/// `sim` NULL or live; `counts` valid for `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_counts(
    sim: *mut coag_sim,
    counts: *const u64,
    len: usize,
    volume: f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        let n = unsafe { slice(counts, len, "counts") }?;
        s.sim.set_counts(n, volume)?;
        if let Config::Counts(c) = &mut s.config {
            c.volume = volume;
        }
        Ok(())
    })
}

/// Replaces the sim's coagulation kernel (e.g. new parameters between outer steps).
/// For the low-rank methods the new kernel must have the same rank.
///
/// # Safety
/// `sim` and `kernel` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_kernel(
    sim: *mut coag_sim,
    kernel: *const coag_kernel,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        let k = unsafe { handle(kernel, "kernel") }?.k;
        s.sim.set_kernel(k)?;
        s.kernel = k;
        Ok(())
    })
}

/// Replaces the fragmentation kernel of a mass-flow or event-driven sim (NULL: none).
/// Direct simulation's capacity stays what it was made with: one made without
/// fragmentation and an automatic capacity holds only its initial number of particles
/// (`COAG_CAPACITY` when break-ups pass it; set `capacity` to make room).
///
/// # Safety
/// `sim` NULL or live; `frag` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_fragmentation(
    sim: *mut coag_sim,
    frag: *const coag_fragmentation,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        let f = if frag.is_null() {
            Fragmentation::None
        } else {
            unsafe { handle(frag, "frag") }?.f
        };
        s.sim.set_fragmentation(f)?;
        s.frag = f;
        Ok(())
    })
}

/// Changes the time step of a mass-flow sim.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_dt(sim: *mut coag_sim, dt: f64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.sim.set_dt(dt)?;
        if let Config::MassFlow(c) = &mut s.config {
            c.dt = dt;
        }
        Ok(())
    })
}

/// Sets the sim's clock to `t` (finite, not negative): a host that keeps its own time
/// origin, e.g. after a restart. An event-driven scheme draws its next proposal afresh.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_time(sim: *mut coag_sim, t: f64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.sim.set_time(t)?;
        Ok(())
    })
}

/// Changes the total mass M1 a mass-flow sim's particles carry (finite, > 0): a host
/// adding mass (condensation, a feed) or removing it between steps; each particle
/// then carries `M1 / N` (the mass flow algorithm: likewise). `COAG_UNSUPPORTED` for a
/// size-count sim (its mass is its counts: use `coag_sim_set_counts` or
/// `coag_sim_set_pairs`) and for direct simulation (its mass is its sizes over its
/// volume: use `coag_sim_set_sizes`).
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_mass(sim: *mut coag_sim, mass: f64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.sim.set_mass(mass)?;
        match &mut s.config {
            Config::MassFlow(c) => c.mass = mass,
            Config::EventFlow(c) => c.mass = mass,
            Config::Counts(_) => {}
        }
        Ok(())
    })
}

/// The configuration of a mass-flow sim as it stands (what it was made with, with Δt
/// and the mass as `coag_sim_set_dt` and `coag_sim_set_mass` left them) into a struct
/// of `size` bytes (`sizeof(coag_massflow_config)`); `COAG_UNSUPPORTED` for a
/// size-count sim.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_massflow_config(
    sim: *const coag_sim,
    out: *mut coag_massflow_config,
    size: usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        config_out(
            sim,
            out,
            size,
            MASSFLOW_CONFIG_V1,
            "massflow config",
            |c| match c {
                Config::MassFlow(c) => Some(*c),
                _ => None,
            },
            "config: not a mass-flow sim (use coag_sim_counts_config or coag_sim_eventflow_config)",
        )
    }
}

/// The configuration of a size-count sim as it stands (the volume and size limit
/// resolved: never 0; the volume as given at construction or by the last
/// `coag_sim_set_counts` — doublings since are in `coag_sim_get_counts`) into a struct
/// of `size` bytes (`sizeof(coag_counts_config)`); `COAG_UNSUPPORTED` for a mass-flow
/// sim.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_counts_config(
    sim: *const coag_sim,
    out: *mut coag_counts_config,
    size: usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        config_out(
            sim,
            out,
            size,
            COUNTS_CONFIG_V1,
            "counts config",
            |c| match c {
                Config::Counts(c) => Some(*c),
                _ => None,
            },
            "config: not a size-count sim (use coag_sim_massflow_config or coag_sim_eventflow_config)",
        )
    }
}

/// The configuration of an event-driven sim over particle sizes as it stands (the
/// mass as `coag_sim_set_mass` left it) into a struct of `size` bytes
/// (`sizeof(coag_eventflow_config)`); `COAG_UNSUPPORTED` for other sims.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_eventflow_config(
    sim: *const coag_sim,
    out: *mut coag_eventflow_config,
    size: usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        config_out(
            sim,
            out,
            size,
            EVENTFLOW_CONFIG_V1,
            "eventflow config",
            |c| match c {
                Config::EventFlow(c) => Some(*c),
                _ => None,
            },
            "config: not an event-driven sim over particle sizes (use coag_sim_massflow_config or coag_sim_counts_config)",
        )
    }
}

/// Makes the sim draw its random numbers from `next(user_data)` (64 random bits per
/// call) instead of its own stream; `next` NULL switches back to the own stream, which
/// resumes where it stopped. Randomness drawn from a callback is not part of a
/// checkpoint. Each call that draws from a callback first snapshots the sim (O(state)),
/// to undo the call if the stream turns out stuck. The callback must not call into
/// this sim nor free it.
///
/// # Safety
/// `sim` NULL or live; `next` and `user_data` valid while installed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_rng_callback(
    sim: *mut coag_sim,
    next: coag_rng_callback,
    user_data: *mut c_void,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.callback = next.map(|f| (f, user_data));
        Ok(())
    })
}

/// Restarts the sim's own random stream from `seed` and `stream` (the seed policy of
/// `coagula_core::random::generator`, the same as the CLI's).
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_reseed(sim: *mut coag_sim, seed: u64, stream: u64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        s.own = generator(seed, stream);
        Ok(())
    })
}

/// Writes the sim's configuration of the kind `pick` finds into a caller struct of
/// `size` bytes (`COAG_UNSUPPORTED` with `refuse` for a sim of another kind).
///
/// # Safety
/// `sim` NULL or live; `out` NULL or valid for writing `size` bytes; T the config
/// struct of `v1`.
unsafe fn config_out<T: Copy>(
    sim: *const coag_sim,
    out: *mut T,
    size: usize,
    v1: usize,
    name: &str,
    pick: fn(&Config) -> Option<T>,
    refuse: &'static str,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let Some(c) = pick(&s.config) else {
            return fail(COAG_UNSUPPORTED, refuse);
        };
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, v1, c, name) }
    })
}

/// The first word of a format-1 C-ABI checkpoint (the generator's tag, no checksum):
/// recognised to say why it is refused.
const GENERATOR_TAG: u64 = u64::from_le_bytes(*b"XOSHI256");
/// The first word of a C-ABI checkpoint, and its format.
const CABI_MAGIC: u64 = u64::from_le_bytes(*b"COAGCABI");
const CABI_VERSION: u64 = 2;

/// A configuration as named words; the ones marked `true` must match on restore.
fn config_words(c: &Config) -> Vec<(&'static str, u64, bool)> {
    match *c {
        Config::MassFlow(c) => vec![
            ("kind (mass flow)", 0, true),
            ("mass", c.mass.to_bits(), true),
            ("dt", c.dt.to_bits(), true),
            ("points", c.points as u64, true),
            ("randomization", c.randomization as u64, true),
            ("full_sort", c.full_sort as u64, true),
            ("seed", c.seed, false),
            ("stream", c.stream, false),
        ],
        Config::Counts(c) => vec![
            ("kind (counts)", 1, true),
            ("method", c.method as u64, true),
            ("volume", c.volume.to_bits(), true),
            ("size_limit", c.size_limit, true),
            ("batched_clock", u64::from(c.batched_clock != 0), true),
            ("memory_budget", c.memory_budget, false),
            ("seed", c.seed, false),
            ("stream", c.stream, false),
        ],
        Config::EventFlow(c) => vec![
            ("kind (eventflow)", 2, true),
            ("method", c.method as u64, true),
            ("mass", c.mass.to_bits(), true),
            ("truncation", c.truncation.to_bits(), true),
            // (any capacity the state fits restores: a run that filled its
            // workspace can move to a larger one; the sim keeps its own)
            ("capacity", c.capacity, false),
            ("sampler", c.sampler as u64, true),
            ("strict_bound", u64::from(c.strict_bound != 0), true),
            ("seed", c.seed, false),
            ("stream", c.stream, false),
        ],
    }
}

/// The configuration back from its words (the kind already known from `like`).
fn config_from(like: &Config, w: &[u64]) -> Config {
    match *like {
        Config::MassFlow(c) => Config::MassFlow(coag_massflow_config {
            mass: f64::from_bits(w[1]),
            dt: f64::from_bits(w[2]),
            points: w[3] as i32,
            randomization: w[4] as i32,
            full_sort: w[5] as i32,
            seed: w[6],
            stream: w[7],
            ..c
        }),
        Config::Counts(c) => Config::Counts(coag_counts_config {
            method: w[1] as i32,
            volume: f64::from_bits(w[2]),
            size_limit: w[3],
            batched_clock: w[4] as i32,
            memory_budget: w[5],
            seed: w[6],
            stream: w[7],
            ..c
        }),
        Config::EventFlow(c) => Config::EventFlow(coag_eventflow_config {
            method: w[1] as i32,
            mass: f64::from_bits(w[2]),
            truncation: f64::from_bits(w[3]),
            capacity: w[4],
            sampler: w[5] as i32,
            strict_bound: w[6] as i32,
            seed: w[7],
            stream: w[8],
            ..c
        }),
    }
}

/// A fingerprint of a kernel: its kind and parameters (built-in kernels), or what a
/// user kernel declares (its callbacks are code, not stored).
fn kernel_fingerprint(k: &Kernel) -> u64 {
    match k {
        Kernel::Builtin(c) => c.fingerprint(),
        Kernel::User(u) => coagula_core::checkpoint::fingerprint([
            0x5553_4552, // "USER"
            u64::from(u.rank),
            u.low_rank_exact as u64,
            u64::from(u.majorant.is_some()),
            u64::from(u.factors.is_some()),
            u64::from(u.sup.is_some()),
        ]),
    }
}

fn frag_fingerprint(f: &Fragmentation) -> u64 {
    match f {
        Fragmentation::None => 0,
        Fragmentation::Binary(b) => {
            coagula_core::checkpoint::fingerprint([1, b.lambda().to_bits()])
        }
        Fragmentation::User(u) => coagula_core::checkpoint::fingerprint([2, u.sup_rate.to_bits()]),
    }
}

/// The index of a scheme in the registry (its code in a checkpoint).
fn scheme_code(id: SchemeId) -> u64 {
    registry::SCHEMES
        .iter()
        .position(|s| s.id == id)
        .unwrap_or(usize::MAX) as u64
}

/// A C-ABI checkpoint: magic and format, the scheme, both configurations and the
/// kernels' fingerprints, the sim's own stream, the scheme's state, and the checksum.
fn save_sim(s: &coag_sim, w: &mut Writer) {
    w.u64(CABI_MAGIC);
    w.u64(CABI_VERSION);
    w.u64(scheme_code(s.sim.id()));
    for c in [&s.built, &s.config] {
        for (_, v, _) in config_words(c) {
            w.u64(v);
        }
    }
    w.u64(kernel_fingerprint(&s.kernel));
    w.u64(frag_fingerprint(&s.frag));
    for p in s.own.parts() {
        w.u64(p);
    }
    s.sim.save(w);
    w.seal();
}

/// Bytes a checkpoint of the sim needs now.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_checkpoint_size(sim: *const coag_sim, out: *mut usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            let mut w = Writer::new(&mut []);
            save_sim(s, &mut w);
            Ok(w.needed())
        })
    }
}

/// Writes the sim's full state (including its own random stream) into `buf`;
/// `*written` (may be NULL) receives the bytes used. A sim restored from it with
/// `coag_sim_restore` continues bit-identically.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` bytes; `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_checkpoint(
    sim: *const coag_sim,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let mut need = Writer::new(&mut []);
        save_sim(s, &mut need);
        if len < need.needed() {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!(
                    "checkpoint: buffer of {len} bytes, {} needed",
                    need.needed()
                ),
            );
        }
        // SAFETY: NULL checked; `len` writable bytes by contract.
        let out = unsafe { slice_mut(buf, len, "buf") }?;
        let mut w = Writer::new(out);
        save_sim(s, &mut w);
        let n = w.finish()?;
        if !written.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(written, n) };
        }
        Ok(())
    })
}

/// Restores a checkpoint into a sim made with the same scheme and configuration
/// (`mass`, `dt`, points, randomisation and sorting; method, volume, size limit and
/// clock — seed, stream and memory budget may differ) and the same kernels as the sim
/// that wrote it has now. A checkpoint that is corrupted (checksum), truncated, of
/// another format, of another configuration, or whose state fails the checks its
/// scheme's constructor makes is `COAG_BAD_CHECKPOINT`; on any error the sim is
/// unchanged.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_restore(sim: *mut coag_sim, buf: *const u8, len: usize) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let s = unsafe { handle_mut(sim, "sim") }?;
        let data = unsafe { slice(buf, len, "buf") }?;
        let bad = |what: String| Fail(crate::COAG_BAD_CHECKPOINT, format!("checkpoint: {what}"));
        if data.len() >= 8 && data[..8] == GENERATOR_TAG.to_le_bytes() {
            return Err(bad(
                "format 1 (before checksums and configuration records) is not supported".into(),
            ));
        }
        let body = coagula_core::checkpoint::unseal(data)?;
        let mut r = Reader::new(body);
        if r.u64()? != CABI_MAGIC {
            return Err(bad("not a checkpoint of coagula's C ABI".into()));
        }
        let v = r.u64()?;
        if v != CABI_VERSION {
            return Err(bad(format!(
                "format {v} (this library reads format {CABI_VERSION})"
            )));
        }
        let code = r.u64()?;
        if code != scheme_code(s.sim.id()) {
            let other = registry::SCHEMES
                .get(code as usize)
                .map_or("an unknown scheme", |i| i.name);
            return Err(bad(format!(
                "of scheme {other}, restored into a {} sim",
                s.sim.id().name()
            )));
        }
        let ours = config_words(&s.built);
        let mut words = [Vec::new(), Vec::new()];
        for w in words.iter_mut() {
            for _ in 0..ours.len() {
                w.push(r.u64()?);
            }
        }
        for (i, &(name, v, must)) in ours.iter().enumerate() {
            if must && words[0][i] != v {
                return Err(bad(format!(
                    "made with another {name} ({} there, {} here)",
                    show(name, words[0][i]),
                    show(name, v)
                )));
            }
        }
        // the configuration as it stands may differ from the one made only where a
        // setter changes it (mass, Δt, volume, the stream): a record that claims
        // another method, point set, sampler… is forged
        for (i, &(name, _, _)) in ours.iter().enumerate() {
            if !settable(name) && words[1][i] != words[0][i] {
                return Err(bad(format!(
                    "its two configuration records disagree on {name}, which no call changes"
                )));
            }
        }
        // seed and stream are the stream's now in use; the memory budget stays this
        // sim's (the state was checked against it)
        // (and likewise an event-driven sim's capacity)
        let keep_budget = |c: Config| match (c, s.built) {
            (Config::Counts(mut c), Config::Counts(ours)) => {
                c.memory_budget = ours.memory_budget;
                Config::Counts(c)
            }
            (Config::EventFlow(mut c), Config::EventFlow(ours)) => {
                c.capacity = ours.capacity;
                Config::EventFlow(c)
            }
            (c, _) => c,
        };
        let built = keep_budget(config_from(&s.built, &words[0]));
        let current = keep_budget(config_from(&s.built, &words[1]));
        if r.u64()? != kernel_fingerprint(&s.kernel) {
            return Err(bad(
                "written under another coagulation kernel (kind, parameters or declared bounds)"
                    .into(),
            ));
        }
        if r.u64()? != frag_fingerprint(&s.frag) {
            return Err(bad("written under another fragmentation kernel".into()));
        }
        let parts = [r.u64()?, r.u64()?, r.u64()?, r.u64()?];
        let own = Generator::from_parts(parts).ok_or(coagula_core::Error::Checkpoint {
            what: "bad random stream",
        })?;
        s.sim.restore(&mut r)?;
        s.own = own;
        s.built = built;
        s.config = current;
        Ok(())
    })
}

/// Whether a configuration word may change after construction (by a setter, or as
/// the size-count constructor resolves a 0 into the value that runs).
fn settable(name: &str) -> bool {
    matches!(
        name,
        "mass" | "dt" | "volume" | "size_limit" | "memory_budget" | "capacity" | "seed" | "stream"
    )
}

/// A configuration word for a message: floats as numbers.
fn show(name: &str, w: u64) -> String {
    if matches!(name, "mass" | "dt" | "volume" | "truncation") {
        coagula_core::error::Short(f64::from_bits(w)).to_string()
    } else {
        (w as i64).to_string()
    }
}

/// A new sim that is an exact copy of `sim` — state, configuration, kernels, own random
/// stream, host callbacks and limits — into `*out`: the two continue identically and
/// independently (a host forking a run, or trying a step it may discard). A mass-flow
/// sim in caller-owned memory is copied into memory the library owns.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_clone(sim: *const coag_sim, out: *mut *mut coag_sim) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let id = s.sim.id();
        let state = if particle_sizes_len(s).is_some() {
            Some(s.sim.state())
        } else {
            None
        };
        // (the current configuration: its volume and size limit are resolved)
        let mut fresh = match (state, s.config) {
            (Some(State::Sizes(x)), Config::MassFlow(c)) => {
                let init = Init::Sizes {
                    sizes: x,
                    mass: c.mass,
                };
                registry::build(id, s.kernel, s.frag, &init, &massflow_options(&c)?)?
            }
            (Some(State::Sizes(x)), Config::EventFlow(c)) => {
                // a state of the same shape, replaced below: the mass flow algorithm's
                // checkpoint is for its initial number of particles, direct
                // simulation's for its capacity (in the configuration). The blank's
                // size is one the sim holds, or else one the kernel and the truncation
                // allow; direct simulation's blank is one particle in volume 1 (its
                // state may be empty, or sum past the largest double)
                let lo = s.kernel.min_size().max(f64::MIN_POSITIVE);
                let hi = if c.truncation > 0.0 {
                    c.truncation
                } else {
                    f64::INFINITY
                };
                let d = x
                    .iter()
                    .copied()
                    .reduce(f64::min)
                    .unwrap_or_else(|| 1.0f64.max(lo).min(hi));
                let (sizes, mass) = if id == SchemeId::Mfa {
                    (vec![d; s.n0], c.mass)
                } else {
                    (vec![d], d)
                };
                let init = Init::Sizes {
                    sizes: &sizes,
                    mass,
                };
                registry::build(id, s.kernel, s.frag, &init, &eventflow_options(&c)?)?
            }
            (_, Config::Counts(c)) => {
                // a trivial state of the same scheme and options, replaced below
                // (direct simulation over counts: empty, as a kernel's min_size may
                // exclude size 1 and no majorant is needed at a size nobody holds)
                let blank: &[u64] = if id == SchemeId::DsaCounts {
                    &[0]
                } else {
                    &[2]
                };
                let init = Init::Counts {
                    counts: blank,
                    volume: 1.0,
                };
                registry::build(id, s.kernel, s.frag, &init, &counts_options(&c)?)?
            }
            _ => return fail(COAG_UNSUPPORTED, "clone: unknown state"),
        };
        let mut w = Writer::new(&mut []);
        s.sim.save(&mut w);
        let mut buf = vec![0u8; w.needed()];
        s.sim.save(&mut Writer::new(&mut buf));
        fresh.restore(&mut Reader::new(&buf))?;
        let copy = coag_sim {
            sim: fresh,
            own: s.own.clone(),
            callback: s.callback,
            built: s.built,
            config: s.config,
            kernel: s.kernel,
            frag: s.frag,
            work_limit: s.work_limit,
            cancel: s.cancel,
            n0: s.n0,
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(copy))) };
        Ok(())
    })
}
