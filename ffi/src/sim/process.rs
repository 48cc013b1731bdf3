//! Processes beside coagulation (core's `process` module): a particle source, removal
//! at a power of size, growth (monomer attachment on integer sizes, splitting on real
//! ones), and their books. The rules live in
//! core; these calls translate.

use super::coag_sim;
use crate::status::{COAG_INVALID_ARGUMENT, COAG_UNSUPPORTED, fail, guard};
use crate::util::{handle, handle_mut, write_sized};
use coagula_core::initial::Distribution;
use coagula_core::process::{Processes, Source, UserRate};
use std::ffi::c_void;

/// A source's sizes: every particle of size `p1` (nucleation).
pub const COAG_SOURCE_MONODISPERSE: i32 = 0;
/// A source's sizes: exponential of mean `p1` (rounded to integers ≥ 1 on an
/// integer-size scheme).
pub const COAG_SOURCE_EXPONENTIAL: i32 = 1;
/// A source's sizes: log-normal of median `p1` and geometric standard deviation `p2`
/// (rounded likewise).
pub const COAG_SOURCE_LOGNORMAL: i32 = 2;

/// The books of a sim's processes (see `coag_sim_books`). The caller sets
/// `struct_size` to `sizeof(coag_books)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct coag_books {
    /// `sizeof(coag_books)` as the caller compiled it.
    pub struct_size: usize,
    /// Particles when the books started (the processes were set or the host replaced
    /// the state), doubled with every particle doubling since.
    pub initial_number: u64,
    /// Their mass (sizes summed).
    pub initial_mass: f64,
    /// Particles the source injected.
    pub injected_number: u64,
    /// Their mass.
    pub injected_mass: f64,
    /// Particles removed.
    pub removed_number: u64,
    /// Their mass.
    pub removed_mass: f64,
    /// Mass gained by monomer attachment.
    pub grown_mass: f64,
    /// Merges by coagulation.
    pub merged: u64,
    /// Particle doublings since the books started.
    pub doublings: u64,
}

const BOOKS_V1: usize = std::mem::size_of::<coag_books>();

fn current(s: &coag_sim) -> Processes {
    s.sim.processes().cloned().unwrap_or_default()
}

/// Sets the sim's particle source: `rate` particles per unit volume and time (finite,
/// ≥ 0), sizes of `kind` (`COAG_SOURCE_*`) with parameters `p1`, `p2` (unused ones
/// ignored). Processes run on the finite-N schemes with coagulation alone (lowrank,
/// lowrank-tree, lowrank-binary-tree, lowrank-blocks, lowrank-sizes, inverse,
/// rejection, dsa, dsa-counts) and inside the steps of `massflow` (with fragmentation
/// too; its books count mass, its particle number stays N); elsewhere
/// `COAG_UNSUPPORTED`. Setting any process starts the books from the state now.
/// Errors leave the sim unchanged.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_source(
    sim: *mut coag_sim,
    rate: f64,
    kind: i32,
    p1: f64,
    p2: f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let sizes = match kind {
            COAG_SOURCE_MONODISPERSE => Distribution::Monodisperse { size: p1 },
            COAG_SOURCE_EXPONENTIAL => Distribution::Exponential { mean: p1 },
            COAG_SOURCE_LOGNORMAL => Distribution::Lognormal {
                median: p1,
                gsd: p2,
            },
            _ => {
                return fail(
                    COAG_INVALID_ARGUMENT,
                    format!("source kind {kind}: not one of COAG_SOURCE_*"),
                );
            }
        };
        let p = current(s).with_source(Source::new(rate, sizes)?);
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Sets the sim's particle source with listed sizes: `rate` particles per unit volume
/// and time, each of a size drawn uniformly from the `len` sizes (at least 2, each
/// finite and > 0; rounded to integers ≥ 1 on an integer-size scheme). A mixture: an
/// emission and a background inflow as one source, a size listed twice drawn twice as
/// often. As `coag_sim_set_source` otherwise.
///
/// # Safety
/// `sim` NULL or live; `sizes` valid for `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_source_sizes(
    sim: *mut coag_sim,
    rate: f64,
    sizes: *const f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let x = unsafe { crate::util::slice(sizes, len, "sizes") }?;
        let p = current(s).with_source(Source::new(rate, Distribution::Sizes(x.to_vec()))?);
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Gives the sim's source a piecewise-constant rate: `rates[k]` particles per unit
/// volume and time from `times[k]` to `times[k + 1]`, the last rate after the last
/// time, the rate it was set with before the first (`len` of each; times finite, ≥ 0,
/// strictly ascending; rates finite, ≥ 0). Exact: a candidate drawn with one piece's
/// bound that would pass a change is void there and drawn afresh. Set a source first
/// (`coag_sim_set_source` or `_set_source_sizes`; else `COAG_INVALID_ARGUMENT`). As
/// `coag_sim_set_source` otherwise.
///
/// # Safety
/// `sim` NULL or live; `times` and `rates` valid for `len` doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_source_schedule(
    sim: *mut coag_sim,
    times: *const f64,
    rates: *const f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let t = unsafe { crate::util::slice(times, len, "times") }?;
        let r = unsafe { crate::util::slice(rates, len, "rates") }?;
        let mut p = current(s);
        let Some(source) = p.source.take() else {
            return fail(
                COAG_INVALID_ARGUMENT,
                "schedule: the sim has no source (set one first)".to_string(),
            );
        };
        p.source = Some(source.with_schedule(t, r)?);
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Gives the sim's source a host's rate function of time: `S(t) = rate(t, user_data)`
/// particles per unit volume and time (NULL: back to the rate the source was set with),
/// at most `bound` (finite, > 0) at every time. Exact for any rate within the bound:
/// candidates come at the bound and a source event is kept with `S(t)/bound`; a value
/// above the bound is `COAG_INVALID_RATE` from the advance that met it, the state as
/// before the event. Not with a schedule. Set a source first (else
/// `COAG_INVALID_ARGUMENT`). `tag`, the callback's contract and the rest as
/// `coag_sim_set_removal_callback`.
///
/// # Safety
/// `sim` NULL or live; `rate` NULL or callable with `user_data` while set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_source_callback(
    sim: *mut coag_sim,
    rate: coag_rate_callback,
    user_data: *mut c_void,
    bound: f64,
    tag: u64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let mut p = current(s);
        let Some(source) = p.source.take() else {
            return fail(
                COAG_INVALID_ARGUMENT,
                "source callback: the sim has no source (set one first)".to_string(),
            );
        };
        let source = match rate {
            Some(f) => source.with_rate_function(user_rate(f, user_data, bound, tag)?)?,
            None => source.without_rate_function(),
        };
        p.source = Some(source);
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Sets removal at `λ(x) = coefficient · x^exponent` per particle (coefficient finite,
/// ≥ 0; exponent in [−10, 1]): dilution and outflow at exponent 0, deposition and
/// sedimentation at a power of size. Dilution with a background population is this and
/// a source of rate `λ n_b` with the background's sizes. As `coag_sim_set_source`
/// otherwise.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_removal(
    sim: *mut coag_sim,
    coefficient: f64,
    exponent: f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let p = current(s).with_removal(coefficient, exponent)?;
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Sets growth `G(x) = coefficient · x^exponent` (exponent in [−10, 1]): on an
/// integer-size scheme by monomer attachment (a particle of size i gains a monomer at
/// rate G(i), exact); on a scheme over real sizes by Strang splitting of the step that
/// `coag_sim_set_growth_step` set before (without one: `COAG_UNSUPPORTED`). As
/// `coag_sim_set_source` otherwise.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_growth(
    sim: *mut coag_sim,
    coefficient: f64,
    exponent: f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let p = current(s).with_growth(coefficient, exponent)?;
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Sets the splitting step of growth on real sizes (finite, > 0; call it before
/// `coag_sim_set_growth` or `coag_sim_set_growth_callback` on such a scheme): every
/// particle grows by a step at the times (k + ½)·step — in closed form for a power of
/// size, by a fourth-order Runge–Kutta step with a host's rate — and coagulation and the
/// other processes run exactly in between; second order in the step at its multiples.
/// Not used on integer sizes. An advance over more than 2^24 steps is refused
/// (`COAG_INVALID_ARGUMENT`: each step rebuilds the state). As `coag_sim_set_source`
/// otherwise.
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_growth_step(sim: *mut coag_sim, step: f64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let p = current(s).with_growth_step(step)?;
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// A host's rate as a function of one number, `rate(x, user_data)` — a particle's size
/// (removal, growth) or the time (a source) — at most the bound given with it (a value above it is `COAG_INVALID_RATE` from the
/// advance that met it, the state as before the event).
pub type coag_rate_callback = Option<unsafe extern "C" fn(x: f64, user_data: *mut c_void) -> f64>;

/// The callback's user data, moved into core's closure (the host keeps it valid and
/// callable from the thread that advances the sim while it is set).
struct HostData(*mut c_void);
// SAFETY: the host's contract (above): core calls the function on the thread that
// advances the sim, one call at a time.
unsafe impl Send for HostData {}
// SAFETY: as above.
unsafe impl Sync for HostData {}

fn user_rate(
    rate: unsafe extern "C" fn(f64, *mut c_void) -> f64,
    user_data: *mut c_void,
    bound: f64,
    tag: u64,
) -> Result<UserRate, crate::status::Fail> {
    let data = HostData(user_data);
    Ok(UserRate::new(
        move |x| {
            let d = &data;
            // SAFETY: the host's callback and data, valid while set (contract).
            unsafe { rate(x, d.0) }
        },
        bound,
        tag,
    )?)
}

/// Sets a host's removal rate per particle, `rate(x, user_data)` (NULL: none), at most
/// `bound` (finite, > 0) at every size, beside `coag_sim_set_removal`'s power (the two
/// add up). `tag` names the function in checkpoints: a checkpoint restores only into a
/// sim whose callback has the same tag and bound. The thinning draws a particle
/// uniformly and keeps it with `rate(x)/bound`, so the run is exact for any rate
/// within the bound. The callback and `user_data` must stay valid while set and must
/// not call back into this sim (`COAG_REENTRANT`). As `coag_sim_set_source` otherwise.
///
/// # Safety
/// `sim` NULL or live; `rate` NULL or callable with `user_data` while set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_removal_callback(
    sim: *mut coag_sim,
    rate: coag_rate_callback,
    user_data: *mut c_void,
    bound: f64,
    tag: u64,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { set_user(sim, false, rate, user_data, bound, tag) }
}

/// A host's removal (`grow` false) or growth rate set on `sim`.
///
/// # Safety
/// As the two setters'.
unsafe fn set_user(
    sim: *mut coag_sim,
    grow: bool,
    rate: coag_rate_callback,
    user_data: *mut c_void,
    bound: f64,
    tag: u64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let mut p = current(s);
        let r = match rate {
            Some(f) => Some(user_rate(f, user_data, bound, tag)?),
            None => None,
        };
        if grow {
            p.user_growth = r;
        } else {
            p.user_removal = r;
        }
        s.sim.set_processes(Some(p))?;
        Ok(())
    })
}

/// Sets a host's growth rate `rate(x, user_data)` (NULL: none), at most `bound` at
/// every size, beside `coag_sim_set_growth`'s power: monomers per unit time at size i
/// on integer sizes, `dx/dt` on real sizes (split: set `coag_sim_set_growth_step`
/// first; integrated by a fourth-order Runge–Kutta step). As
/// `coag_sim_set_removal_callback` otherwise.
///
/// # Safety
/// `sim` NULL or live; `rate` NULL or callable with `user_data` while set.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_growth_callback(
    sim: *mut coag_sim,
    rate: coag_rate_callback,
    user_data: *mut c_void,
    bound: f64,
    tag: u64,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { set_user(sim, true, rate, user_data, bound, tag) }
}

/// Removes every process (and the books).
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_clear_processes(sim: *mut coag_sim) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.sim.set_processes(None)?;
        Ok(())
    })
}

/// Writes the books of the sim's processes into `out` (`struct_size` bytes): what was
/// injected, removed and grown since the books started, so that the mass
/// `initial + injected − removed + grown` and the number
/// `initial + injected − removed − merged` are the state's (exactly on integer sizes).
/// A step's flows are the books after it minus before. `COAG_UNSUPPORTED` when no
/// process is set.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or valid for `out->struct_size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_books(sim: *const coag_sim, out: *mut coag_books) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        crate::util::non_null(out, "out")?;
        // SAFETY: non-null; a coag_books begins with its size_t struct_size (contract).
        let size = unsafe { out.cast::<usize>().read_unaligned() };
        let Some(b) = s.sim.books() else {
            return fail(
                COAG_UNSUPPORTED,
                "books: no process is set on this sim".to_string(),
            );
        };
        let v = coag_books {
            struct_size: BOOKS_V1,
            initial_number: b.initial_number,
            initial_mass: b.initial_mass,
            injected_number: b.injected_number,
            injected_mass: b.injected_mass,
            removed_number: b.removed_number,
            removed_mass: b.removed_mass,
            grown_mass: b.grown_mass,
            merged: b.merged,
            doublings: b.doublings,
        };
        // SAFETY: forwarded contract (`size` bytes writable at out).
        unsafe { write_sized(out, size, BOOKS_V1, v, "books") }
    })
}
