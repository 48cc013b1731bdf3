//! Collision kernels from first hits of the relative motion (Maftei et al. 2016 §4;
//! `coagula_core::langevin::kernel`).

use super::{
    COAG_DRIFT_MAFTEI2016, COAG_DRIFT_ZERO, bad, coag_drift_fn, coag_langevin_config,
    default_langevin, drift_of,
};
use crate::status::{COAG_INTERRUPTED, fail, guard};
use crate::util::{non_null, read_config, write};
use coagula_core::langevin::kernel::{FirstHits, first_hit_kernel_within};
use coagula_core::scheme::Budget;
use std::ffi::c_void;

/// A first-hit kernel estimation (see `coag_first_hit_kernel`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_first_hits {
    /// `sizeof(coag_first_hits)` as the caller compiled it.
    pub struct_size: usize,
    /// Dimension, 2 or 3.
    pub dim: u32,
    /// Collision radius R = r1 + r2 > 0.
    pub radius: f64,
    /// Outer radius L > R of the shell the pairs start in.
    pub outer: f64,
    /// Window [from, to) of the hits counted (to > from ≥ 0; the run's final time).
    pub from: f64,
    /// End of the window.
    pub to: f64,
    /// Time step > 0.
    pub dt: f64,
    /// Noise amplitude of the relative velocity.
    pub sigma: f64,
    /// Standard deviation of each initial relative velocity component.
    pub velocity_sd: f64,
    /// Trajectories (≥ 1).
    pub trajectories: u64,
    /// `COAG_DRIFT_ZERO`, `COAG_DRIFT_FRICTION` or `COAG_DRIFT_CALLBACK`.
    pub drift: i32,
    /// `COAG_DRIFT_FRICTION`: the rate 1/τ.
    pub friction_rate: f64,
    /// `COAG_DRIFT_CALLBACK`: the relative drift.
    pub drift_fn: coag_drift_fn,
    /// `COAG_DRIFT_CALLBACK`: passed to `drift_fn`.
    pub drift_user_data: *mut c_void,
    /// At most this many trajectory steps (a trajectory to `to` is `⌈to / dt⌉` of
    /// them; trajectories run in chunks, each only when the limit still covers it);
    /// 0: no limit. When the limit cannot cover the next trajectory the call returns
    /// `COAG_INTERRUPTED` and no estimate. (Added in version 2 of the struct: a caller
    /// compiled against version 1 gets no limit. Zero the whole struct before setting
    /// its fields, so that fields added later read as their defaults.)
    pub work_limit: u64,
    /// Polled between chunks of at most 4096 trajectories: non-zero stops the call
    /// with `COAG_INTERRUPTED` (NULL: none).
    pub cancel: crate::sim::coag_cancel_callback,
    /// Passed to `cancel`.
    pub cancel_user_data: *mut c_void,
}

/// The struct before `work_limit` and `cancel` (the smallest size accepted).
const FIRST_HITS_V1: usize = std::mem::offset_of!(coag_first_hits, work_limit);

/// The collision kernel of the relative motion, averaged over `[from, to)`, from the
/// first hits of the sphere |x| = R by pairs starting uniformly in R < |x| < L with
/// Maxwellian velocities (see `coagula_core::langevin::kernel`): its estimate, standard
/// error and the hits counted. Trajectories `first_id..` of `seed`.
///
/// # Safety
/// `p` valid for `p->struct_size` bytes; out pointers writable (`hits` may be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_first_hit_kernel(
    p: *const coag_first_hits,
    seed: u64,
    first_id: u64,
    mean: *mut f64,
    std_error: *mut f64,
    hits: *mut u64,
) -> i32 {
    guard(|| {
        let zero = coag_first_hits {
            struct_size: FIRST_HITS_V1,
            dim: 3,
            radius: 0.0,
            outer: 0.0,
            from: 0.0,
            to: 0.0,
            dt: 0.0,
            sigma: 0.0,
            velocity_sd: 0.0,
            trajectories: 0,
            drift: COAG_DRIFT_ZERO,
            friction_rate: 0.0,
            drift_fn: None,
            drift_user_data: std::ptr::null_mut(),
            work_limit: 0,
            cancel: None,
            cancel_user_data: std::ptr::null_mut(),
        };
        // SAFETY: NULL checked; valid otherwise (contract).
        let c = unsafe { read_config(p, "p", FIRST_HITS_V1, zero) }?;
        non_null(mean, "mean")?;
        non_null(std_error, "std_error")?;
        if c.drift == COAG_DRIFT_MAFTEI2016 {
            return Err(bad("COAG_DRIFT_MAFTEI2016 is one-dimensional"));
        }
        let lc = coag_langevin_config {
            drift: c.drift,
            friction_rate: c.friction_rate,
            drift_fn: c.drift_fn,
            drift_user_data: c.drift_user_data,
            ..default_langevin()
        };
        let fh = FirstHits {
            radius: c.radius,
            outer: c.outer,
            from: c.from,
            to: c.to,
            dt: c.dt,
            sigma: c.sigma,
            velocity_sd: c.velocity_sd,
            trajectories: c.trajectories,
        };
        let mut cancel = || {
            c.cancel.is_some_and(|f| {
                // SAFETY: the host passed the callback and user_data for this call.
                unsafe { f(c.cancel_user_data) != 0 }
            })
        };
        let units = if c.work_limit == 0 {
            u64::MAX
        } else {
            c.work_limit
        };
        let mut budget = Budget::work(units).with_cancel(&mut cancel);
        let k = match c.dim {
            2 => first_hit_kernel_within::<2, _>(
                &fh,
                &drift_of::<2>(&lc)?,
                seed,
                first_id,
                &mut budget,
            )?,
            3 => first_hit_kernel_within::<3, _>(
                &fh,
                &drift_of::<3>(&lc)?,
                seed,
                first_id,
                &mut budget,
            )?,
            d => return Err(bad(format!("dim {d} (2 or 3)"))),
        };
        let Some(k) = k else {
            return fail(
                COAG_INTERRUPTED,
                format!(
                    "first-hit kernel: the work limit of {} trajectory steps or the cancel callback stopped it before its {} trajectories (no estimate)",
                    c.work_limit, c.trajectories
                ),
            );
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe {
            write(mean, k.estimate.mean);
            write(std_error, k.estimate.std_error);
            if !hits.is_null() {
                write(hits, k.hits);
            }
        }
        Ok(())
    })
}
