//! Collision kernels from first hits of the relative motion (Maftei et al. 2016 §4;
//! `coagula_core::langevin::kernel`).

use super::{
    COAG_DRIFT_MAFTEI2016, COAG_DRIFT_ZERO, bad, coag_drift_fn, coag_langevin_config,
    default_langevin, drift_of,
};
use crate::status::guard;
use crate::util::{non_null, read_config, write};
use coagula_core::langevin::kernel::{FirstHits, first_hit_kernel};
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
}

const FIRST_HITS_V1: usize = std::mem::size_of::<coag_first_hits>();

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
        let k = match c.dim {
            2 => first_hit_kernel::<2, _>(&fh, &drift_of::<2>(&lc)?, seed, first_id)?,
            3 => first_hit_kernel::<3, _>(&fh, &drift_of::<3>(&lc)?, seed, first_id)?,
            d => return Err(bad(format!("dim {d} (2 or 3)"))),
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
