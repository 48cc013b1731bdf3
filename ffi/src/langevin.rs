//! C ABI of the Langevin trajectory batches (`core::langevin`, Maftei et al. 2016):
//! `coag_langevin` handles, the drift as a built-in or a C callback, statistics over the
//! batch, checkpoints, and collision kernels from first hits.

use crate::sim::{
    check_workspace, coag_step_report, handle, handle_mut, write_report, write_sized,
};
use crate::{
    COAG_INVALID_ARGUMENT, Fail, fail, guard, non_null, read_config, slice, slice_mut, write,
};
use coagula_core::checkpoint::Checkpoint;
use coagula_core::langevin::kernel::{FirstHits, first_hit_kernel};
use coagula_core::langevin::{Batch, Config, Drift, VelocityBound, Wall, paper, workspace_len};
use coagula_core::observe::Replicas;
use coagula_core::scheme::{Budget, Scheme};
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

/// The drift of a C configuration.
#[derive(Clone, Copy)]
struct FfiDrift {
    kind: i32,
    rate: f64,
    f: coag_drift_fn,
    user: *mut c_void,
}

impl<const D: usize> Drift<D> for FfiDrift {
    #[inline]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        match self.kind {
            COAG_DRIFT_FRICTION => core::array::from_fn(|k| -self.rate * u[k]),
            COAG_DRIFT_MAFTEI2016 => {
                core::array::from_fn(|_| paper::cos_2pi(x[0]) + 0.5 * paper::cos_2pi(u[0]))
            }
            COAG_DRIFT_CALLBACK => {
                let mut out = [f64::NAN; D];
                let Some(f) = self.f else { return out };
                // SAFETY: the caller's callback contract (valid for the handle's life);
                // x, u and out hold D doubles.
                let status =
                    unsafe { f(t, x.as_ptr(), u.as_ptr(), D, out.as_mut_ptr(), self.user) };
                if status != 0 {
                    out = [f64::NAN; D];
                }
                out
            }
            _ => [0.0; D],
        }
    }
}

/// The library's storage or the caller's.
enum Store {
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

enum Inner {
    D1(Batch<1, FfiDrift, Store>),
    D2(Batch<2, FfiDrift, Store>),
    D3(Batch<3, FfiDrift, Store>),
}

/// A batch of Langevin trajectories (opaque).
pub struct coag_langevin {
    inner: Inner,
    dim: usize,
    n: usize,
    /// The caller's workspace (address, bytes), or (0, 0): caller arrays passed to the
    /// handle must not overlap it.
    caller: (usize, usize),
}

/// Refuses a caller array `[p, p + bytes)` that overlaps the handle's workspace or
/// `other` (another array of the same call).
fn disjoint(
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

macro_rules! with_batch {
    ($h:expr, $b:ident => $e:expr) => {
        match $h {
            Inner::D1($b) => $e,
            Inner::D2($b) => $e,
            Inner::D3($b) => $e,
        }
    };
}

fn bad(msg: impl Into<String>) -> Fail {
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

fn drift_of<const D: usize>(c: &coag_langevin_config) -> Result<FfiDrift, Fail> {
    match c.drift {
        COAG_DRIFT_ZERO => {}
        COAG_DRIFT_FRICTION => {
            if !(c.friction_rate.is_finite() && c.friction_rate >= 0.0) {
                return Err(bad("friction_rate must be finite and >= 0"));
            }
        }
        COAG_DRIFT_MAFTEI2016 => {
            if D != 1 {
                return Err(bad("COAG_DRIFT_MAFTEI2016 is one-dimensional"));
            }
        }
        COAG_DRIFT_CALLBACK => {
            if c.drift_fn.is_none() {
                return fail(crate::COAG_NULL_PARAMETER, "drift_fn is NULL");
            }
        }
        x => return Err(bad(format!("unknown drift {x}"))),
    }
    Ok(FfiDrift {
        kind: c.drift,
        rate: c.friction_rate,
        f: c.drift_fn,
        user: c.drift_user_data,
    })
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
            crate::COAG_CAPACITY,
            "first_id + n - 1 overflows".into(),
        ));
    }
    let n = usize::try_from(n).map_err(|_| bad("n does not fit in memory"))?;
    let d = c.dim as usize;
    macro_rules! make {
        ($D:literal, $V:ident) => {{
            let (cfg, drift) = parts::<$D>(c)?;
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
            v.try_reserve_exact(len)
                .map_err(|_| Fail(crate::COAG_CAPACITY, format!("cannot allocate {len} words")))?;
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
    if !h.is_null() {
        // SAFETY: a live handle from Box::into_raw (contract).
        drop(unsafe { Box::from_raw(h) });
    }
}

/// Steps every trajectory to time `t` (steps end at the multiples of dt; a target
/// between two ends a shortened step). `report` may be NULL. A drift returning NaN,
/// infinity or a non-zero status is `COAG_INVALID_RATE`, with the batch as it was.
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
        // SAFETY: forwarded contract.
        let h = unsafe { handle_mut(h, "h") }?;
        if !report.is_null() {
            // validate the report before the run (a bad one must not cost the run)
            // SAFETY: non-null; valid (contract).
            unsafe { write_report(report, Default::default()) }?;
        }
        let mut rng = coagula_core::random::generator(0, 0);
        let rep = with_batch!(&mut h.inner, b => b.advance_within(t, &mut Budget::unlimited(), &mut rng))?;
        if !report.is_null() {
            // SAFETY: as above.
            unsafe { write_report(report, rep) }?;
        }
        Ok(())
    })
}

/// The batch's time, dimension and number of trajectories (any out pointer may be NULL).
///
/// # Safety
/// `h` a live handle; out pointers NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_info(
    h: *const coag_langevin,
    time: *mut f64,
    dim: *mut usize,
    n: *mut u64,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        let t = with_batch!(&h.inner, b => b.time());
        // SAFETY: each written only when non-null (contract: writable).
        unsafe {
            if !time.is_null() {
                write(time, t);
            }
            if !dim.is_null() {
                write(dim, h.dim);
            }
            if !n.is_null() {
                write(n, h.n as u64);
            }
        }
        Ok(())
    })
}

/// Copies the state: positions and velocities (`n·dim` doubles each, trajectory-major),
/// hits (`n`) and first-hit times (`n`, +inf when none); `len` is `n`. Any of the four
/// arrays may be NULL.
///
/// # Safety
/// `h` a live handle; each non-null array valid for its length.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_state(
    h: *const coag_langevin,
    x: *mut f64,
    u: *mut f64,
    hits: *mut u64,
    first_hit: *mut f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        if len != h.n {
            return fail(
                crate::COAG_BUFFER_TOO_SMALL,
                format!("len {len}: the batch has {} trajectories", h.n),
            );
        }
        let d = h.dim;
        let nd = h.n.checked_mul(d).ok_or_else(|| bad("length overflows"))?;
        // (no array may overlap the workspace or another: they are written while the
        // records are read)
        let arrays = [
            (x as usize, if x.is_null() { 0 } else { nd * 8 }, "x"),
            (u as usize, if u.is_null() { 0 } else { nd * 8 }, "u"),
            (
                hits as usize,
                if hits.is_null() { 0 } else { h.n * 8 },
                "hits",
            ),
            (
                first_hit as usize,
                if first_hit.is_null() { 0 } else { h.n * 8 },
                "first_hit",
            ),
        ];
        for (i, &(p, b, name)) in arrays.iter().enumerate() {
            for &(q, c, _) in &arrays[i + 1..] {
                disjoint(h, p, b, (q, c), name)?;
            }
            disjoint(h, p, b, (0, 0), name)?;
        }
        // SAFETY (all four): NULL allowed (then skipped: length 0); valid otherwise.
        let xs = unsafe { slice_mut(x, if x.is_null() { 0 } else { nd }, "x") }?;
        let us = unsafe { slice_mut(u, if u.is_null() { 0 } else { nd }, "u") }?;
        let hs = unsafe { slice_mut(hits, if hits.is_null() { 0 } else { h.n }, "hits") }?;
        let fs = unsafe {
            slice_mut(
                first_hit,
                if first_hit.is_null() { 0 } else { h.n },
                "first_hit",
            )
        }?;
        with_batch!(&h.inner, b => {
            for (i, p) in b.positions().enumerate() {
                if !xs.is_empty() {
                    xs[i * d..(i + 1) * d].copy_from_slice(&p);
                }
            }
            for (i, v) in b.velocities().enumerate() {
                if !us.is_empty() {
                    us[i * d..(i + 1) * d].copy_from_slice(&v);
                }
            }
            for (i, k) in b.hits().enumerate() {
                if !hs.is_empty() {
                    hs[i] = k;
                }
            }
            for (i, t) in b.first_hits().enumerate() {
                if !fs.is_empty() {
                    fs[i] = t;
                }
            }
        });
        Ok(())
    })
}

/// Mean and standard error of `f(X, U)` over the trajectories (absorbed ones at their
/// hit); `f` NULL means the hits per trajectory. `absorbed` (may be NULL) gets the
/// number of absorbed trajectories.
///
/// # Safety
/// `h` a live handle; `f` NULL or a valid callback; out pointers NULL or writable
/// (`mean` and `std_error` required).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_mean(
    h: *const coag_langevin,
    f: coag_observable_fn,
    user_data: *mut c_void,
    mean: *mut f64,
    std_error: *mut f64,
    absorbed: *mut u64,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        non_null(mean, "mean")?;
        non_null(std_error, "std_error")?;
        let d = h.dim;
        let (r, a): (Replicas, usize) = with_batch!(&h.inner, b => {
            let r = match f {
                // SAFETY: the caller's callback contract; x and u hold dim doubles.
                Some(f) => b.statistics(|x, u| unsafe { f(x.as_ptr(), u.as_ptr(), d, user_data) }),
                None => b.hit_statistics(),
            };
            (r, b.absorbed())
        });
        // SAFETY: checked non-null; writable (contract).
        unsafe {
            write(mean, r.mean());
            write(std_error, r.std_error());
            if !absorbed.is_null() {
                write(absorbed, a as u64);
            }
        }
        Ok(())
    })
}

/// Bytes a checkpoint of the batch needs now.
///
/// # Safety
/// `h` a live handle; `out` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_checkpoint_size(
    h: *const coag_langevin,
    out: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        non_null(out, "out")?;
        let len = with_batch!(&h.inner, b => b.checkpoint_len());
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, len) };
        Ok(())
    })
}

/// Saves the batch (configuration, time, every trajectory; not the drift) into `buf`;
/// `written` (may be NULL) gets the bytes used.
///
/// # Safety
/// `h` a live handle; `buf` valid for `len` bytes; `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_save(
    h: *const coag_langevin,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        disjoint(
            h,
            buf as usize,
            if buf.is_null() { 0 } else { len },
            (0, 0),
            "buf",
        )?;
        // SAFETY: as above.
        let b = unsafe { slice_mut(buf, len, "buf") }?;
        let n = with_batch!(&h.inner, s => s.save_to(b))?;
        if !written.is_null() {
            // SAFETY: non-null; writable (contract).
            unsafe { write(written, n) };
        }
        Ok(())
    })
}

/// Restores a checkpoint into a batch of the same dimension and size (its drift stays);
/// on error the batch is unchanged.
///
/// # Safety
/// `h` a live handle used by this thread alone; `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_langevin_restore(
    h: *mut coag_langevin,
    buf: *const u8,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle_mut(h, "h") }?;
        disjoint(
            h,
            buf as usize,
            if buf.is_null() { 0 } else { len },
            (0, 0),
            "buf",
        )?;
        // SAFETY: as above.
        let b = unsafe { slice(buf, len, "buf") }?;
        with_batch!(&mut h.inner, s => s.restore_from(b))?;
        Ok(())
    })
}

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
