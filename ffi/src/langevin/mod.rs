//! C ABI of the Langevin trajectory batches (`core::langevin`, Maftei et al. 2016):
//! `coag_langevin` handles on the verbs of the sims (advance with work limit and
//! cancellation, clone, the one checkpoint envelope), the drift as one of core's
//! built-ins or a C callback, statistics over the batch, and collision kernels from
//! first hits.

/// Runs `$e` with `$b` bound to the batch of whichever dimension.
macro_rules! with_batch {
    ($h:expr, $b:ident => $e:expr) => {
        match $h {
            Inner::D1($b) => $e,
            Inner::D2($b) => $e,
            Inner::D3($b) => $e,
        }
    };
}

mod first_hits;
mod read;

pub use first_hits::*;
pub use read::*;

use crate::report::{check_report, coag_step_report, write_report};
use crate::status::{COAG_INTERRUPTED, COAG_INVALID_ARGUMENT, Fail, fail, guard};
use crate::util::{
    check_workspace, handle, handle_mut, non_null, read_config, slice, write, write_sized,
};
use coagula_core::langevin::{
    Batch, BuiltinDrift, Config, Drift, Friction, VelocityBound, Wall, workspace_len,
};
use coagula_core::scheme::Budget;
use std::ffi::c_void;

/// A drift callback: writes `b(t, x, u)` (`dim` components) to `out` and returns 0; any
/// other return value stops the call with `COAG_INVALID_RATE` (as a NaN does). It runs
/// on the calling thread during `coag_langevin_advance_to` (or `coag_first_hit_kernel`)
/// and must not call into the batch whose call invoked it.
pub type coag_drift_fn = Option<
    unsafe extern "C" fn(
        t: f64,
        x: *const f64,
        u: *const f64,
        dim: usize,
        out: *mut f64,
        user_data: *mut c_void,
    ) -> i32,
>;

/// An observable `f(x, u)` for `coag_langevin_mean`.
pub type coag_observable_fn = Option<
    unsafe extern "C" fn(x: *const f64, u: *const f64, dim: usize, user_data: *mut c_void) -> f64,
>;

/// Specular reflection at the wall.
pub const COAG_WALL_SPECULAR: i32 = 0;
/// Absorption at the wall (the trajectory stops at its first hit).
pub const COAG_WALL_ABSORBING: i32 = 1;

/// No velocity bound.
pub const COAG_BOUND_NONE: i32 = 0;
/// Velocities past the bound are clamped to it.
pub const COAG_BOUND_CLAMP: i32 = 1;
/// Velocities past the bound are reflected at it.
pub const COAG_BOUND_REFLECT: i32 = 2;

/// b = 0.
pub const COAG_DRIFT_ZERO: i32 = 0;
/// b = −rate u (Ornstein–Uhlenbeck velocity; `friction_rate` = 1/τ).
pub const COAG_DRIFT_FRICTION: i32 = 1;
/// The test problem of Maftei et al. (2016): b = cos(2πx) + cos(2πu)/2 (dim 1).
pub const COAG_DRIFT_MAFTEI2016: i32 = 2;
/// The C callback `drift_fn` with `drift_user_data`.
pub const COAG_DRIFT_CALLBACK: i32 = 3;

/// A Langevin batch's configuration. Fill it with `coag_langevin_default_config`, which
/// sets `struct_size`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_langevin_config {
    /// `sizeof(coag_langevin_config)` as the caller compiled it.
    pub struct_size: usize,
    /// Dimension 1 (the half-line x ≥ 0, wall at 0), 2 or 3 (outside the ball |x| ≤ radius).
    pub dim: u32,
    /// `COAG_WALL_*`.
    pub wall: i32,
    /// Time step > 0.
    pub dt: f64,
    /// Noise amplitude σ ≥ 0.
    pub sigma: f64,
    /// dim 2 or 3: the excluded ball's radius > 0; dim 1: 0.
    pub radius: f64,
    /// dim 1: a periodic border at x = period (positions move back by it); 0 = none.
    pub period: f64,
    /// `COAG_BOUND_*`.
    pub bound_kind: i32,
    /// The velocity bound (> 0) for `COAG_BOUND_CLAMP` and `COAG_BOUND_REFLECT`.
    pub bound: f64,
    /// `COAG_DRIFT_*`.
    pub drift: i32,
    /// `COAG_DRIFT_FRICTION`: the rate 1/τ.
    pub friction_rate: f64,
    /// `COAG_DRIFT_CALLBACK`: the drift.
    pub drift_fn: coag_drift_fn,
    /// `COAG_DRIFT_CALLBACK`: passed to `drift_fn`, never dereferenced by coagula.
    pub drift_user_data: *mut c_void,
}

const LANGEVIN_CONFIG_V1: usize = std::mem::size_of::<coag_langevin_config>();

fn default_langevin() -> coag_langevin_config {
    coag_langevin_config {
        struct_size: LANGEVIN_CONFIG_V1,
        dim: 1,
        wall: COAG_WALL_SPECULAR,
        dt: 0.01,
        sigma: 1.0,
        radius: 0.0,
        period: 0.0,
        bound_kind: COAG_BOUND_NONE,
        bound: 0.0,
        drift: COAG_DRIFT_ZERO,
        friction_rate: 0.0,
        drift_fn: None,
        drift_user_data: std::ptr::null_mut(),
    }
}

/// Writes the default configuration (dim 1, specular, dt 0.01, σ 1, no border, no
/// bound, b = 0) into `out`, a struct of `size` bytes (`sizeof(coag_langevin_config)`).
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_default_config(
    out: *mut coag_langevin_config,
    size: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            write_sized(
                out,
                size,
                LANGEVIN_CONFIG_V1,
                default_langevin(),
                "langevin config",
            )
        }
    })
}

/// The drift of a C configuration: one of core's built-in drifts, or a C callback.
#[derive(Clone, Copy)]
pub(crate) enum FfiDrift {
    Builtin(BuiltinDrift),
    Callback(
        unsafe extern "C" fn(f64, *const f64, *const f64, usize, *mut f64, *mut c_void) -> i32,
        *mut c_void,
    ),
}

impl FfiDrift {
    /// A fingerprint (for checkpoints): a callback's is its kind only (code is not
    /// stored).
    fn fingerprint(&self) -> u64 {
        match self {
            FfiDrift::Builtin(b) => b.fingerprint(),
            FfiDrift::Callback(..) => 0x4341_4c4c, // "CALL"
        }
    }
}

impl<const D: usize> Drift<D> for FfiDrift {
    #[inline]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        match *self {
            FfiDrift::Builtin(b) => b.drift(t, x, u),
            FfiDrift::Callback(f, user) => {
                let mut out = [f64::NAN; D];
                // SAFETY: the caller's callback contract (valid for the handle's life);
                // x, u and out hold D doubles.
                let status = unsafe { f(t, x.as_ptr(), u.as_ptr(), D, out.as_mut_ptr(), user) };
                if status != 0 {
                    out = [f64::NAN; D];
                }
                out
            }
        }
    }
}

/// The library's storage or the caller's.
pub(crate) enum Store {
    Owned(Vec<u64>),
    Caller(&'static mut [u64]),
}

impl AsRef<[u64]> for Store {
    fn as_ref(&self) -> &[u64] {
        match self {
            Store::Owned(v) => v,
            Store::Caller(s) => s,
        }
    }
}

impl AsMut<[u64]> for Store {
    fn as_mut(&mut self) -> &mut [u64] {
        match self {
            Store::Owned(v) => v,
            Store::Caller(s) => s,
        }
    }
}

pub(crate) enum Inner {
    D1(Batch<1, FfiDrift, Store>),
    D2(Batch<2, FfiDrift, Store>),
    D3(Batch<3, FfiDrift, Store>),
}

/// A batch of Langevin trajectories (opaque).
pub struct coag_langevin {
    pub(crate) inner: Inner,
    pub(crate) dim: usize,
    pub(crate) n: usize,
    /// The caller's workspace (address, bytes), or (0, 0): caller arrays passed to the
    /// handle must not overlap it.
    pub(crate) caller: (usize, usize),
    /// The drift's fingerprint (what a checkpoint must be restored under).
    pub(crate) drift: u64,
    /// Trajectory steps per `coag_langevin_advance_to` (0: no limit) and the
    /// cancellation poll.
    pub(crate) work_limit: u64,
    pub(crate) cancel: Option<(unsafe extern "C" fn(*mut c_void) -> i32, *mut c_void)>,
}

/// Refuses a caller array `[p, p + bytes)` that overlaps the handle's workspace or
/// `other` (another array of the same call).
pub(crate) fn disjoint(
    h: &coag_langevin,
    p: usize,
    bytes: usize,
    other: (usize, usize),
    name: &str,
) -> Result<(), Fail> {
    let overlap = |(a, an): (usize, usize)| {
        an > 0 && bytes > 0 && p < a.saturating_add(an) && a < p.saturating_add(bytes)
    };
    if overlap(h.caller) || overlap(other) {
        return Err(bad(format!(
            "{name} overlaps the batch's workspace or another array of the call"
        )));
    }
    Ok(())
}

pub(crate) fn bad(msg: impl Into<String>) -> Fail {
    Fail(COAG_INVALID_ARGUMENT, msg.into())
}

/// Checks a configuration's enums and builds the core configuration and drift.
fn parts<const D: usize>(c: &coag_langevin_config) -> Result<(Config<D>, FfiDrift), Fail> {
    let wall = match c.wall {
        COAG_WALL_SPECULAR => Wall::Specular,
        COAG_WALL_ABSORBING => Wall::Absorbing,
        x => return Err(bad(format!("unknown wall {x}"))),
    };
    let cfg = if D == 1 {
        if c.radius != 0.0 {
            return Err(bad("radius must be 0 in one dimension (the wall is at 0)"));
        }
        let line = Config::<D>::half_line(c.dt, c.sigma, wall)?;
        if c.period != 0.0 {
            line.with_period(c.period)?
        } else {
            line
        }
    } else {
        if c.period != 0.0 {
            return Err(bad("a periodic border is for dim 1 only"));
        }
        Config::<D>::ball(c.radius, c.dt, c.sigma, wall)?
    };
    Ok((cfg.with_velocity_bound(bound_of(c)?)?, drift_of::<D>(c)?))
}

fn bound_of(c: &coag_langevin_config) -> Result<VelocityBound, Fail> {
    Ok(match c.bound_kind {
        COAG_BOUND_NONE => VelocityBound::None,
        COAG_BOUND_CLAMP => VelocityBound::Clamp(c.bound),
        COAG_BOUND_REFLECT => VelocityBound::Reflect(c.bound),
        x => return Err(bad(format!("unknown velocity bound kind {x}"))),
    })
}

pub(crate) fn drift_of<const D: usize>(c: &coag_langevin_config) -> Result<FfiDrift, Fail> {
    let b = match c.drift {
        COAG_DRIFT_ZERO => BuiltinDrift::Zero,
        COAG_DRIFT_FRICTION => BuiltinDrift::Friction(Friction {
            rate: c.friction_rate,
        }),
        COAG_DRIFT_MAFTEI2016 => BuiltinDrift::Paper,
        COAG_DRIFT_CALLBACK => {
            let Some(f) = c.drift_fn else {
                return fail(crate::status::COAG_NULL_PARAMETER, "drift_fn is NULL");
            };
            return Ok(FfiDrift::Callback(f, c.drift_user_data));
        }
        x => return Err(bad(format!("unknown drift {x}"))),
    };
    b.check(D)?;
    Ok(FfiDrift::Builtin(b))
}

/// Reads the config, the start and the dimension.
///
/// # Safety
/// Pointers NULL or valid (`x0`, `u0`: `dim` doubles).
unsafe fn inputs(
    config: *const coag_langevin_config,
    x0: *const f64,
    u0: *const f64,
) -> Result<(coag_langevin_config, Vec<f64>, Vec<f64>), Fail> {
    // SAFETY: NULL checked; otherwise valid (contract).
    let c = unsafe { read_config(config, "config", LANGEVIN_CONFIG_V1, default_langevin()) }?;
    if !(1..=3).contains(&c.dim) {
        return Err(bad(format!("dim {} (1, 2 or 3)", c.dim)));
    }
    let d = c.dim as usize;
    // SAFETY: NULL checked; `dim` readable doubles (contract).
    let x = unsafe { slice(x0, d, "x0") }?.to_vec();
    // SAFETY: as above.
    let u = unsafe { slice(u0, d, "u0") }?.to_vec();
    Ok((c, x, u))
}

fn build(
    c: &coag_langevin_config,
    n: u64,
    x: &[f64],
    u: &[f64],
    seed: u64,
    first_id: u64,
    store: impl FnOnce(usize) -> Result<Store, Fail>,
) -> Result<coag_langevin, Fail> {
    if n.checked_sub(1)
        .and_then(|m| first_id.checked_add(m))
        .is_none()
        && n > 0
    {
        return Err(Fail(
            crate::status::COAG_CAPACITY,
            "first_id + n - 1 overflows".into(),
        ));
    }
    let n = usize::try_from(n).map_err(|_| bad("n does not fit in memory"))?;
    let d = c.dim as usize;
    let print: u64;
    macro_rules! make {
        ($D:literal, $V:ident) => {{
            let (cfg, drift) = parts::<$D>(c)?;
            print = drift.fingerprint();
            let xs: [f64; $D] = core::array::from_fn(|k| x[k]);
            let us: [f64; $D] = core::array::from_fn(|k| u[k]);
            // what the constructor refuses, before the caller's memory is touched
            cfg.check_start(&xs, &us)?;
            if n == 0 {
                return Err(bad("n must be at least 1"));
            }
            let ws = store(workspace_len($D, n).ok_or_else(|| bad("workspace overflows"))?)?;
            Inner::$V(Batch::with_starts_in(
                cfg,
                drift,
                n,
                seed,
                first_id,
                |_| (xs, us),
                ws,
            )?)
        }};
    }
    let inner = match d {
        1 => make!(1, D1),
        2 => make!(2, D2),
        _ => make!(3, D3),
    };
    Ok(coag_langevin {
        inner,
        dim: d,
        n,
        caller: (0, 0),
        drift: print,
        work_limit: 0,
        cancel: None,
    })
}

/// A batch of `n ≥ 1` trajectories, all starting at `(x0, u0)` (`dim` doubles each), in
/// memory the library owns. Trajectory i has its own generator, the seed policy's
/// `(seed, first_id + i)`: shares of an ensemble built with disjoint `first_id` ranges
/// give the same paths as the whole. Free with `coag_langevin_free`.
///
/// # Safety
/// Pointers must be NULL or valid; `x0`, `u0` hold `config->dim` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_new(
    config: *const coag_langevin_config,
    n: u64,
    x0: *const f64,
    u0: *const f64,
    seed: u64,
    first_id: u64,
    out: *mut *mut coag_langevin,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let (c, x, u) = unsafe { inputs(config, x0, u0) }?;
        non_null(out, "out")?;
        let h = build(&c, n, &x, &u, seed, first_id, |len| {
            let mut v = Vec::new();
            v.try_reserve_exact(len).map_err(|_| {
                Fail(
                    crate::status::COAG_CAPACITY,
                    format!("cannot allocate {len} words"),
                )
            })?;
            v.resize(len, 0);
            Ok(Store::Owned(v))
        })?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(h))) };
        Ok(())
    })
}

/// Bytes of caller memory `coag_langevin_new_in` needs for `n` trajectories of
/// `config->dim` dimensions.
///
/// # Safety
/// Pointers must be NULL or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_workspace_size(
    config: *const coag_langevin_config,
    n: u64,
    out: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; otherwise valid (contract).
        let c = unsafe { read_config(config, "config", LANGEVIN_CONFIG_V1, default_langevin()) }?;
        non_null(out, "out")?;
        if !(1..=3).contains(&c.dim) {
            return Err(bad(format!("dim {} (1, 2 or 3)", c.dim)));
        }
        let bytes = usize::try_from(n)
            .ok()
            .and_then(|n| workspace_len(c.dim as usize, n))
            .and_then(|w| w.checked_mul(8))
            .filter(|&b| b <= isize::MAX as usize)
            .ok_or_else(|| bad(format!("workspace for {n} trajectories overflows")))?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, bytes) };
        Ok(())
    })
}

/// `coag_langevin_new` in memory the caller owns: `workspace` (aligned for `double`,
/// `workspace_bytes` ≥ `coag_langevin_workspace_size`) holds every trajectory for the
/// batch's whole life; no step allocates. The caller keeps it alive and untouched until
/// `coag_langevin_free`.
///
/// # Safety
/// Pointers must be NULL or valid; `workspace` valid for `workspace_bytes` bytes and used
/// by nothing else until the batch is freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_new_in(
    config: *const coag_langevin_config,
    n: u64,
    x0: *const f64,
    u0: *const f64,
    seed: u64,
    first_id: u64,
    workspace: *mut c_void,
    workspace_bytes: usize,
    out: *mut *mut coag_langevin,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let (c, x, u) = unsafe { inputs(config, x0, u0) }?;
        non_null(out, "out")?;
        let mut h = build(&c, n, &x, &u, seed, first_id, |len| {
            let bytes = len
                .checked_mul(8)
                .filter(|&b| b <= isize::MAX as usize)
                .ok_or_else(|| bad(format!("workspace for {n} trajectories overflows")))?;
            check_workspace(workspace, workspace_bytes, bytes, &[])?;
            // SAFETY: checked (non-null, aligned, large enough); the caller's memory for
            // the batch's life (contract).
            let s = unsafe {
                std::ptr::write_bytes(workspace.cast::<u8>(), 0, bytes);
                std::slice::from_raw_parts_mut(workspace.cast::<u64>(), len)
            };
            Ok(Store::Caller(s))
        })?;
        h.caller = (workspace as usize, workspace_bytes);
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(h))) };
        Ok(())
    })
}

/// Frees a batch (NULL is a no-op); caller memory is left to the caller.
///
/// # Safety
/// `h` must be NULL or a live handle, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_free(h: *mut coag_langevin) {
    // SAFETY: NULL checked; live by contract; refused while mid-call.
    if !h.is_null() && unsafe { handle(h, "h") }.is_ok() {
        // SAFETY: a live handle from Box::into_raw (contract).
        drop(unsafe { Box::from_raw(h) });
    }
}

/// Steps every trajectory to time `t` (steps end at the multiples of dt; a target
/// between two ends a shortened step). `report` may be NULL. A drift returning NaN,
/// infinity or a non-zero status is `COAG_INVALID_RATE`, with the batch as it was.
/// With `coag_langevin_set_work_limit` or `coag_langevin_set_cancel_callback`, a call
/// that spends its trajectory steps or is cancelled returns `COAG_INTERRUPTED` with the
/// batch at the grid point reached; calling again continues the same run. The batch
/// takes no generator: each trajectory's noise is its own stream of the seed.
///
/// # Safety
/// `h` a live handle used by this thread alone; `report` NULL or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_advance_to(
    h: *mut coag_langevin,
    t: f64,
    report: *mut coag_step_report,
) -> i32 {
    guard(|| {
        // validate the report before the run (a bad one must not cost the run)
        // SAFETY: NULL or readable (contract).
        unsafe { check_report(report) }?;
        // SAFETY: forwarded contract.
        let (h, _busy) = unsafe { handle_mut(h, "h") }?;
        let host_cancel = h.cancel;
        let mut cancel = || {
            host_cancel.is_some_and(|(f, d)| {
                // SAFETY: the host registered the callback and user_data and keeps
                // them valid while installed.
                unsafe { f(d) != 0 }
            })
        };
        let units = if h.work_limit == 0 {
            u64::MAX
        } else {
            h.work_limit
        };
        let mut budget = Budget::work(units);
        if host_cancel.is_some() {
            budget = budget.with_cancel(&mut cancel);
        }
        let rep = with_batch!(&mut h.inner, b => b.advance_within(t, &mut budget))?;
        if !report.is_null() {
            // SAFETY: non-null, validated; writable (contract).
            unsafe { write_report(report, rep) }?;
        }
        if rep.interrupted {
            return fail(
                COAG_INTERRUPTED,
                format!(
                    "interrupted at t = {} on the way to {} (work limit or cancellation): call again to continue",
                    coagula_core::error::Short(rep.time),
                    coagula_core::error::Short(t)
                ),
            );
        }
        Ok(())
    })
}

/// Sets the trajectory steps one `coag_langevin_advance_to` may take (0: no limit,
/// the default); past it the call returns `COAG_INTERRUPTED`, the batch at the grid
/// point reached.
///
/// # Safety
/// `h` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_set_work_limit(h: *mut coag_langevin, units: u64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (h, _busy) = unsafe { handle_mut(h, "h") }?;
        h.work_limit = units;
        Ok(())
    })
}

/// Installs a callback polled during `coag_langevin_advance_to` (every 16384 trajectory
/// steps): a non-zero return stops the call with `COAG_INTERRUPTED`. `cancel` NULL
/// removes it.
///
/// # Safety
/// `h` NULL or live; `cancel` and `user_data` valid while installed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_set_cancel_callback(
    h: *mut coag_langevin,
    cancel: crate::sim::coag_cancel_callback,
    user_data: *mut c_void,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (h, _busy) = unsafe { handle_mut(h, "h") }?;
        h.cancel = cancel.map(|f| (f, user_data));
        Ok(())
    })
}

/// A new batch that is an exact copy of `h` (trajectories, time, books, drift, limits
/// and callbacks) in memory the library owns: the two continue identically and
/// independently.
///
/// # Safety
/// `h` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_clone(
    h: *const coag_langevin,
    out: *mut *mut coag_langevin,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let h = unsafe { handle(h, "h") }?;
        non_null(out, "out")?;
        let inner = match &h.inner {
            Inner::D1(b) => Inner::D1(owned(b.duplicate()?)),
            Inner::D2(b) => Inner::D2(owned(b.duplicate()?)),
            Inner::D3(b) => Inner::D3(owned(b.duplicate()?)),
        };
        let copy = coag_langevin {
            inner,
            dim: h.dim,
            n: h.n,
            caller: (0, 0),
            drift: h.drift,
            work_limit: h.work_limit,
            cancel: h.cancel,
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(copy))) };
        Ok(())
    })
}

/// A batch in owned storage as the handle's storage type.
fn owned<const D: usize>(b: Batch<D, FfiDrift, Vec<u64>>) -> Batch<D, FfiDrift, Store> {
    b.map_storage(Store::Owned)
}
