//! Simulation handles: every scheme behind one `coag_sim`, stepped with
//! `coag_sim_advance_to`.

use crate::kernel::{Fragmentation, Kernel, coag_fragmentation, coag_kernel};
use crate::rng::{Pcg64, Source, coag_rng_callback};
use crate::{
    COAG_INVALID_ARGUMENT, COAG_UNSUPPORTED, Fail, fail, guard, non_null, slice, slice_mut, write,
};
use coagula_core::checkpoint::{Checkpoint, Reader, Writer};
use coagula_core::kernel::CoagulationKernel;
use coagula_core::qmc::Randomization;
use coagula_core::scheme::lowrank::{AcceptanceRejection, Inverse, LowRank};
use coagula_core::scheme::massflow::{MassFlow, PointSource, Sorting};
use coagula_core::scheme::{Scheme, StepReport};
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

/// Osinsky's low-rank Monte Carlo.
pub const COAG_METHOD_LOWRANK: i32 = 0;
/// Inverse method (Gillespie on sizes).
pub const COAG_METHOD_INVERSE: i32 = 1;
/// Acceptance–rejection.
pub const COAG_METHOD_REJECTION: i32 = 2;

/// Configuration of the time-driven mass-flow scheme (Lécot et al. 2019).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_massflow_config {
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

/// Configuration of the size-count schemes (Osinsky 2023).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_lowrank_config {
    /// `COAG_METHOD_*`.
    pub method: i32,
    /// Simulation volume V (> 0); 0 means "the number of particles" (so that the
    /// initial counts per volume are concentrations).
    pub volume: f64,
    /// Largest particle size allowed (0: the default, 2^32).
    pub size_limit: u64,
    /// Seed of the sim's random stream.
    pub seed: u64,
    /// Stream id.
    pub stream: u64,
}

/// What one `coag_sim_advance_to` call did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct coag_step_report {
    /// Time reached.
    pub time: f64,
    /// Accepted events (coagulations and break-ups).
    pub events: u64,
    /// Proposals, accepted or not.
    pub proposals: u64,
    /// Proposals rejected by thinning.
    pub rejections: u64,
    /// Always 0: a kernel above its declared bound is an error (`COAG_INVALID_RATE`).
    pub bound_violations: u64,
    /// Probabilities above 1 that were clipped (time-driven scheme).
    pub clipped: u64,
    /// Particle-number doublings.
    pub doublings: u64,
}

impl From<StepReport> for coag_step_report {
    fn from(r: StepReport) -> Self {
        coag_step_report {
            time: r.time,
            events: r.events,
            proposals: r.proposals,
            rejections: r.rejections,
            bound_violations: r.bound_violations,
            clipped: r.clipped,
            doublings: r.doublings,
        }
    }
}

pub(crate) enum Engine {
    MassFlow(Box<MassFlow<Kernel, Fragmentation>>),
    LowRank1(Box<LowRank<Kernel, 1>>),
    LowRank2(Box<LowRank<Kernel, 2>>),
    LowRank3(Box<LowRank<Kernel, 3>>),
    LowRank4(Box<LowRank<Kernel, 4>>),
    Inverse(Box<Inverse<Kernel>>),
    Rejection(Box<AcceptanceRejection<Kernel>>),
}

/// Opaque simulation handle (`coag_sim` in C).
pub struct coag_sim {
    engine: Engine,
    /// The sim's own stream (kept even while a callback is installed).
    pcg: Pcg64,
    callback: Option<(unsafe extern "C" fn(*mut c_void) -> u64, *mut c_void)>,
}

macro_rules! with_engine {
    ($e:expr, $s:ident => $body:expr) => {
        match $e {
            Engine::MassFlow($s) => $body,
            Engine::LowRank1($s) => $body,
            Engine::LowRank2($s) => $body,
            Engine::LowRank3($s) => $body,
            Engine::LowRank4($s) => $body,
            Engine::Inverse($s) => $body,
            Engine::Rejection($s) => $body,
        }
    };
}

macro_rules! with_counts_engine {
    ($e:expr, $s:ident => $body:expr, $other:expr) => {
        match $e {
            Engine::LowRank1($s) => $body,
            Engine::LowRank2($s) => $body,
            Engine::LowRank3($s) => $body,
            Engine::LowRank4($s) => $body,
            Engine::Inverse($s) => $body,
            Engine::Rejection($s) => $body,
            Engine::MassFlow(_) => $other,
        }
    };
}

fn new_sim(engine: Engine, seed: u64, stream: u64, out: *mut *mut coag_sim) -> Result<(), Fail> {
    let sim = coag_sim {
        engine,
        pcg: Pcg64::new(seed, stream),
        callback: None,
    };
    write(out, Box::into_raw(Box::new(sim)));
    Ok(())
}

/// A reference to a live handle.
fn handle<'a, T>(p: *const T, name: &str) -> Result<&'a T, Fail> {
    non_null(p, name)?;
    // SAFETY: non-null; the C caller passes a live handle (documented contract).
    Ok(unsafe { &*p })
}

fn handle_mut<'a, T>(p: *mut T, name: &str) -> Result<&'a mut T, Fail> {
    non_null(p, name)?;
    // SAFETY: non-null; a live handle, used by one thread at a time (contract).
    Ok(unsafe { &mut *p })
}

/// Writes the default mass-flow configuration: Δt = 0.01, mass 1, Niederreiter points,
/// no randomisation, adaptive sort, seed 0, stream 0.
///
/// # Safety
/// `out` must be NULL or valid for writing the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_massflow_default_config(out: *mut coag_massflow_config) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        write(
            out,
            coag_massflow_config {
                dt: 0.01,
                mass: 1.0,
                points: COAG_POINTS_NIEDERREITER,
                randomization: COAG_RANDOMIZATION_NONE,
                full_sort: 0,
                seed: 0,
                stream: 0,
            },
        );
        Ok(())
    })
}

/// Writes the default size-count configuration: low-rank method, volume = number of
/// particles, default size limit, seed 0, stream 0.
///
/// # Safety
/// `out` must be NULL or valid for writing the struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_lowrank_default_config(out: *mut coag_lowrank_config) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        write(
            out,
            coag_lowrank_config {
                method: COAG_METHOD_LOWRANK,
                volume: 0.0,
                size_limit: 0,
                seed: 0,
                stream: 0,
            },
        );
        Ok(())
    })
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
        let c = *handle(config, "config")?;
        let k = handle(kernel, "kernel")?.k;
        let f = if frag.is_null() {
            Fragmentation::None
        } else {
            handle(frag, "frag")?.f
        };
        let x = slice(sizes, n, "sizes")?;
        non_null(out, "out")?;
        let kind = match c.randomization {
            COAG_RANDOMIZATION_NONE => None,
            COAG_RANDOMIZATION_SHIFT => Some(Randomization::DigitalShift),
            COAG_RANDOMIZATION_MATOUSEK => Some(Randomization::Matousek),
            COAG_RANDOMIZATION_OWEN => Some(Randomization::Owen),
            r => return fail(COAG_INVALID_ARGUMENT, format!("unknown randomization {r}")),
        };
        // the scrambling draws from a stream of its own, so the sim's stream is the same
        // with and without it
        let mut scramble_rng = Source::Pcg(Pcg64::new(c.seed ^ 0x5c4a_3b1e_0000_0001, c.stream));
        let points = match (c.points, kind) {
            (COAG_POINTS_NIEDERREITER, None) => PointSource::niederreiter(),
            (COAG_POINTS_SOBOL, None) => PointSource::sobol(),
            (COAG_POINTS_NIEDERREITER, Some(r)) => {
                PointSource::randomized_niederreiter(r, &mut scramble_rng)
            }
            (COAG_POINTS_SOBOL, Some(r)) => PointSource::randomized_sobol(r, &mut scramble_rng),
            (COAG_POINTS_MONTE_CARLO, None) => PointSource::monte_carlo(),
            (COAG_POINTS_MONTE_CARLO, Some(_)) => {
                return fail(
                    COAG_INVALID_ARGUMENT,
                    "Monte Carlo points cannot be randomised",
                );
            }
            (p, _) => return fail(COAG_INVALID_ARGUMENT, format!("unknown points {p}")),
        };
        let sorting = if c.full_sort != 0 {
            Sorting::Full
        } else {
            Sorting::Adaptive
        };
        let mf = MassFlow::new(k, f, x, c.mass, c.dt, points)?.with_sorting(sorting);
        new_sim(Engine::MassFlow(Box::new(mf)), c.seed, c.stream, out)
    })
}

/// A size-count sim (Osinsky 2023): `counts[i]` particles of size `i + 1`, `len`
/// entries, with `config.method` choosing low-rank MC, the inverse method or
/// acceptance–rejection. The low-rank method needs a kernel with a low-rank bound of
/// rank 1..4; acceptance–rejection needs the kernel's supremum.
///
/// # Safety
/// Pointers must be NULL or valid (`counts` for `len` values).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_lowrank_new(
    config: *const coag_lowrank_config,
    kernel: *const coag_kernel,
    counts: *const u64,
    len: usize,
    out: *mut *mut coag_sim,
) -> i32 {
    guard(|| {
        let c = *handle(config, "config")?;
        let k = handle(kernel, "kernel")?.k;
        let n = slice(counts, len, "counts")?;
        non_null(out, "out")?;
        let total: u64 = n.iter().fold(0u64, |a, &b| a.saturating_add(b));
        let volume = if c.volume == 0.0 {
            total as f64
        } else {
            c.volume
        };
        let limit = if c.size_limit == 0 {
            coagula_core::scheme::lowrank::DEFAULT_SIZE_LIMIT
        } else {
            c.size_limit
        };
        let engine = match c.method {
            COAG_METHOD_LOWRANK => match k.rank() {
                1 => Engine::LowRank1(Box::new(LowRank::new(k, n, volume)?.with_size_limit(limit))),
                2 => Engine::LowRank2(Box::new(LowRank::new(k, n, volume)?.with_size_limit(limit))),
                3 => Engine::LowRank3(Box::new(LowRank::new(k, n, volume)?.with_size_limit(limit))),
                4 => Engine::LowRank4(Box::new(LowRank::new(k, n, volume)?.with_size_limit(limit))),
                r => {
                    return fail(
                        COAG_UNSUPPORTED,
                        format!("low-rank method: kernel rank {r} (need 1..4)"),
                    );
                }
            },
            COAG_METHOD_INVERSE => {
                Engine::Inverse(Box::new(Inverse::new(k, n, volume)?.with_size_limit(limit)))
            }
            COAG_METHOD_REJECTION => Engine::Rejection(Box::new(
                AcceptanceRejection::new(k, n, volume)?.with_size_limit(limit),
            )),
            m => return fail(COAG_INVALID_ARGUMENT, format!("unknown method {m}")),
        };
        new_sim(engine, c.seed, c.stream, out)
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

/// Runs the sim until time `t` (≥ its current time): time-driven schemes take steps of
/// Δt (a last shorter one lands on t), event-driven schemes process every event before
/// t. `report` may be NULL.
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
        let s = handle_mut(sim, "sim")?;
        let mut rng = match s.callback {
            Some((f, d)) => Source::Callback(f, d),
            None => Source::Pcg(s.pcg.clone()),
        };
        let r = with_engine!(&mut s.engine, e => e.advance_to(t, &mut rng));
        if let Source::Pcg(p) = rng {
            s.pcg = p;
        }
        let r = r?;
        if !report.is_null() {
            write(report, coag_step_report::from(r));
        }
        Ok(())
    })
}

/// The sim's current time.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_time(sim: *const coag_sim, out: *mut f64) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        write(out, with_engine!(&s.engine, e => e.time()));
        Ok(())
    })
}

/// Totals of every `coag_sim_advance_to` so far.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_totals(sim: *const coag_sim, out: *mut coag_step_report) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        write(
            out,
            coag_step_report::from(with_engine!(&s.engine, e => e.totals())),
        );
        Ok(())
    })
}

/// The moment `M_m` (any real order m) of the number concentration.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_moment(sim: *const coag_sim, m: f64, out: *mut f64) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        if !m.is_finite() {
            return fail(COAG_INVALID_ARGUMENT, "moment order must be finite");
        }
        write(out, with_engine!(&s.engine, e => e.moment(m)));
        Ok(())
    })
}

/// The number concentration of sizes in `[a, b]`.
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
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        if a.is_nan() || b.is_nan() {
            return fail(COAG_INVALID_ARGUMENT, "concentration bounds are NaN");
        }
        let v = match &s.engine {
            Engine::MassFlow(e) => e.concentration(a, b),
            other => {
                let (counts, v) = counts_of(other);
                coagula_core::observe::sum_concentration(
                    counts
                        .iter()
                        .enumerate()
                        .map(|(i, &c)| ((i + 1) as f64, c as f64 / v)),
                    a,
                    b,
                )
            }
        };
        write(out, v);
        Ok(())
    })
}

fn counts_of(e: &Engine) -> (Vec<u64>, f64) {
    match e {
        Engine::LowRank1(s) => (s.counts().to_vec(), s.volume()),
        Engine::LowRank2(s) => (s.counts().to_vec(), s.volume()),
        Engine::LowRank3(s) => (s.counts().to_vec(), s.volume()),
        Engine::LowRank4(s) => (s.counts().to_vec(), s.volume()),
        Engine::Inverse(s) => (s.counts(), s.volume()),
        Engine::Rejection(s) => (s.counts(), s.volume()),
        Engine::MassFlow(_) => (Vec::new(), 1.0),
    }
}

/// Gel mass estimate: for size-count schemes the largest cluster's mass per volume
/// (Eibeck & Wagner eq. 6.15); 0 for the mass-flow scheme, whose particles never leave.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_gel_mass(sim: *const coag_sim, out: *mut f64) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        let v = match &s.engine {
            Engine::MassFlow(_) => 0.0,
            other => {
                let (counts, v) = counts_of(other);
                counts
                    .iter()
                    .rposition(|&c| c > 0)
                    .map_or(0.0, |i| (i + 1) as f64 / v)
            }
        };
        write(out, v);
        Ok(())
    })
}

/// Number of simulation particles.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_particle_count(sim: *const coag_sim, out: *mut u64) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        let n = match &s.engine {
            Engine::MassFlow(e) => e.sizes().len() as u64,
            other => counts_of(other).0.iter().sum(),
        };
        write(out, n);
        Ok(())
    })
}

/// Length of the sim's state vector: the number of particles (mass-flow: read with
/// `coag_sim_get_sizes`) or the number of size classes (size-count schemes: read with
/// `coag_sim_get_counts`).
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_state_len(sim: *const coag_sim, out: *mut usize) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        let n = match &s.engine {
            Engine::MassFlow(e) => e.sizes().len(),
            other => counts_of(other).0.len(),
        };
        write(out, n);
        Ok(())
    })
}

/// Copies the particle sizes of a mass-flow sim (sorted ascending) into `buf`, which
/// must hold `coag_sim_state_len` values.
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
        let s = handle(sim, "sim")?;
        let Engine::MassFlow(e) = &s.engine else {
            return fail(
                COAG_UNSUPPORTED,
                "sizes: not a mass-flow sim (use coag_sim_get_counts)",
            );
        };
        let x = e.sizes();
        if len < x.len() {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!("sizes: buffer of {len} for {} particles", x.len()),
            );
        }
        let out = slice_mut(buf, len, "buf")?;
        out[..x.len()].copy_from_slice(x);
        Ok(())
    })
}

/// Replaces the particle sizes of a mass-flow sim (same number, each finite and > 0):
/// a host applying growth or nucleation between steps.
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
        let s = handle_mut(sim, "sim")?;
        let x = slice(sizes, len, "sizes")?;
        let Engine::MassFlow(e) = &mut s.engine else {
            return fail(
                COAG_UNSUPPORTED,
                "sizes: not a mass-flow sim (use coag_sim_set_counts)",
            );
        };
        e.set_sizes(x)?;
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
        let s = handle(sim, "sim")?;
        if matches!(s.engine, Engine::MassFlow(_)) {
            return fail(
                COAG_UNSUPPORTED,
                "counts: a mass-flow sim has sizes (use coag_sim_get_sizes)",
            );
        }
        let (counts, v) = counts_of(&s.engine);
        if len < counts.len() {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!("counts: buffer of {len} for {} sizes", counts.len()),
            );
        }
        let out = slice_mut(buf, len, "buf")?;
        out[..counts.len()].copy_from_slice(&counts);
        out[counts.len()..].iter_mut().for_each(|c| *c = 0);
        if !volume.is_null() {
            write(volume, v);
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
        let s = handle_mut(sim, "sim")?;
        let n = slice(counts, len, "counts")?;
        with_counts_engine!(&mut s.engine, e => e.set_counts(n, volume)?, {
            return fail(COAG_UNSUPPORTED, "counts: a mass-flow sim has sizes (use coag_sim_set_sizes)");
        });
        Ok(())
    })
}

/// Replaces the sim's coagulation kernel (e.g. new parameters between outer steps).
/// For the low-rank method the new kernel must have the same rank.
///
/// # Safety
/// `sim` and `kernel` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_kernel(
    sim: *mut coag_sim,
    kernel: *const coag_kernel,
) -> i32 {
    guard(|| {
        let s = handle_mut(sim, "sim")?;
        let k = handle(kernel, "kernel")?.k;
        match &mut s.engine {
            Engine::MassFlow(e) => e.set_kernel(k),
            Engine::LowRank1(e) => e.set_kernel(k)?,
            Engine::LowRank2(e) => e.set_kernel(k)?,
            Engine::LowRank3(e) => e.set_kernel(k)?,
            Engine::LowRank4(e) => e.set_kernel(k)?,
            Engine::Inverse(e) => e.set_kernel(k)?,
            Engine::Rejection(e) => e.set_kernel(k)?,
        }
        Ok(())
    })
}

/// Replaces the fragmentation kernel of a mass-flow sim (NULL: none).
///
/// # Safety
/// `sim` NULL or live; `frag` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_fragmentation(
    sim: *mut coag_sim,
    frag: *const coag_fragmentation,
) -> i32 {
    guard(|| {
        let s = handle_mut(sim, "sim")?;
        let f = if frag.is_null() {
            Fragmentation::None
        } else {
            handle(frag, "frag")?.f
        };
        let Engine::MassFlow(e) = &mut s.engine else {
            return fail(
                COAG_UNSUPPORTED,
                "fragmentation: only the mass-flow scheme breaks particles",
            );
        };
        e.set_fragmentation(f);
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
        let s = handle_mut(sim, "sim")?;
        let Engine::MassFlow(e) = &mut s.engine else {
            return fail(
                COAG_UNSUPPORTED,
                "dt: event-driven schemes have no time step",
            );
        };
        e.set_dt(dt)?;
        Ok(())
    })
}

/// Makes the sim draw its random numbers from `next(user_data)` (64 random bits per
/// call) instead of its own stream; `next` NULL switches back to the own stream, which
/// resumes where it stopped. Randomness drawn from a callback is not part of a
/// checkpoint.
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
        let s = handle_mut(sim, "sim")?;
        s.callback = next.map(|f| (f, user_data));
        Ok(())
    })
}

/// Restarts the sim's own random stream from `seed` and `stream`.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_reseed(sim: *mut coag_sim, seed: u64, stream: u64) -> i32 {
    guard(|| {
        let s = handle_mut(sim, "sim")?;
        s.pcg = Pcg64::new(seed, stream);
        Ok(())
    })
}

fn save_sim(s: &coag_sim, w: &mut Writer) {
    for p in s.pcg.parts() {
        w.u64(p);
    }
    with_engine!(&s.engine, e => e.save(w));
}

/// Bytes a checkpoint of the sim needs now.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_checkpoint_size(sim: *const coag_sim, out: *mut usize) -> i32 {
    guard(|| {
        let s = handle(sim, "sim")?;
        non_null(out, "out")?;
        let mut w = Writer::new(&mut []);
        save_sim(s, &mut w);
        write(out, w.needed());
        Ok(())
    })
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
        let s = handle(sim, "sim")?;
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
        let out = slice_mut(buf, len, "buf")?;
        let mut w = Writer::new(out);
        save_sim(s, &mut w);
        let n = w.finish()?;
        if !written.is_null() {
            write(written, n);
        }
        Ok(())
    })
}

/// Restores a checkpoint into a sim made with the same scheme, kernel and
/// configuration. On error the sim is unchanged.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_restore(sim: *mut coag_sim, buf: *const u8, len: usize) -> i32 {
    guard(|| {
        let s = handle_mut(sim, "sim")?;
        let data = slice(buf, len, "buf")?;
        let mut r = Reader::new(data);
        let parts = [r.u64()?, r.u64()?, r.u64()?, r.u64()?];
        let pcg = Pcg64::from_parts(parts).ok_or(coagula_core::Error::Checkpoint {
            what: "bad random stream",
        })?;
        with_engine!(&mut s.engine, e => e.restore(&mut r)?);
        s.pcg = pcg;
        Ok(())
    })
}
