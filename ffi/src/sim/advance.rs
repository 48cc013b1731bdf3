//! Stepping a sim: `coag_sim_advance_to` with its work limit, cancellation callback
//! and host random stream; reseeding the sim's own stream.

use super::{coag_cancel_callback, coag_sim};
use crate::report::{check_report, coag_step_report, write_report};
use crate::rng::{DEGENERATE, STUCK_AFTER, Source, coag_rng_callback};
use crate::status::{COAG_CAPACITY, COAG_INTERRUPTED, COAG_RNG_FAILURE, fail, guard};
use crate::util::handle_mut;
use coagula_core::checkpoint::{Reader, Writer};
use coagula_core::random::generator;
use coagula_core::scheme::Budget;
use std::ffi::c_void;

/// Runs the sim until time `t` (≥ its current time): time-driven schemes take steps of
/// Δt (a last shorter one lands on t), event-driven schemes process every event before
/// t (and keep the time of the next one for the next call: see the `batched-clock`
/// option). `report` may be NULL; otherwise its `struct_size` must be set.
///
/// Bounded calls: with `coag_sim_set_work_limit` or `coag_sim_set_cancel_callback`, a
/// call that spends its work units or is cancelled returns `COAG_INTERRUPTED` with the
/// sim consistent at the time reached (written to `report->time`, read with
/// `coag_sim_time`); calling again continues the same run. With a host random
/// callback (`coag_sim_set_rng_callback`) that turns out stuck (the same word 8 times
/// in a row), the call returns `COAG_RNG_FAILURE` and the sim is as before the call.
/// A callback (kernel, random, cancel) that calls back into this sim gets
/// `COAG_REENTRANT`.
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
        // validate the report before the sim changes
        // SAFETY: NULL or readable by contract.
        unsafe { check_report(report) }?;
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
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
                    COAG_CAPACITY,
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.work_limit = units;
        Ok(())
    })
}

/// Installs a callback polled during `coag_sim_advance_to` (every 16384 proposals, and
/// before every mass-flow step): a non-zero return stops the call with
/// `COAG_INTERRUPTED`, the sim consistent at the time reached. `cancel` NULL removes it.
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.cancel = cancel.map(|f| (f, user_data));
        Ok(())
    })
}

/// Makes the sim draw its random numbers from `next(user_data)` (64 random bits per
/// call) instead of its own stream; `next` NULL switches back to the own stream, which
/// resumes where it stopped. Randomness drawn from a callback is not part of a
/// checkpoint. Each call that draws from a callback first snapshots the sim (O(state)),
/// to undo the call if the stream turns out stuck: once the callback has returned the
/// same word 8 times in a row, the call stops at its next cancellation poll (after
/// the current mass-flow step — 2N words with Monte Carlo points — or within 16384
/// proposals of the event-driven schemes) and returns `COAG_RNG_FAILURE` with the
/// sim as before it.
/// The time-driven mass flow with QMC or RQMC points draws nothing from the stream
/// (its points are the sequence, its randomisations keyed by the seed, see
/// `coag_sim_reseed`), so it never calls `next`; with Monte Carlo points it does.
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
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.callback = next.map(|f| (f, user_data));
        Ok(())
    })
}

/// Restarts the sim's own random stream from `seed` and `stream` (core's seed policy,
/// `coagula_core::random::generator`, the same as the CLI's and Python's).
///
/// # Safety
/// `sim` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_reseed(sim: *mut coag_sim, seed: u64, stream: u64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        s.own = generator(seed, stream);
        Ok(())
    })
}
