//! Replacing what a host may replace between steps: the state (counts, pairs,
//! sizes), the kernels, the time step, the clock, the mass. Every setter checks its
//! input and leaves the sim as it was on error.

use super::coag_sim;
use crate::kernel::{Fragmentation, coag_fragmentation, coag_kernel};
use crate::status::guard;
use crate::util::{handle, handle_mut, slice};

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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let xs = unsafe { slice(sizes, len, "sizes") }?;
        let cs = unsafe { slice(counts, len, "counts") }?;
        s.sim.set_pairs(xs, cs, volume)?;
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let x = unsafe { slice(sizes, len, "sizes") }?;
        s.sim.set_sizes(x)?;
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let n = unsafe { slice(counts, len, "counts") }?;
        s.sim.set_counts(n, volume)?;
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let k = unsafe { handle(kernel, "kernel") }?.coagulation()?;
        s.sim.set_kernel(k)?;
        Ok(())
    })
}

/// Replaces the fragmentation kernel of a mass-flow or event-driven sim (NULL: none).
/// Direct simulation's capacity stays what it was made with: one made without
/// fragmentation and an automatic capacity holds only its initial number of particles
/// (`COAG_CAPACITY` when break-ups pass it; set the `capacity` option to make room).
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let f = unsafe { Fragmentation::of(frag) }?;
        s.sim.set_fragmentation(f)?;
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.sim.set_dt(dt)?;
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.sim.set_mass(mass)?;
        Ok(())
    })
}
