//! Reading a batch (time, state, means) and its checkpoint (core's envelope).

use super::{Inner, bad, coag_langevin, coag_observable_fn, disjoint};
use crate::status::{COAG_BUFFER_TOO_SMALL, COAG_INVALID_ARGUMENT, COAG_INVALID_RATE, fail, guard};
use crate::util::{handle, handle_mut, non_null, slice, slice_mut, write};
use coagula_core::checkpoint::Writer;
use coagula_core::observe::Replicas;
use std::ffi::c_void;

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
                COAG_BUFFER_TOO_SMALL,
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
/// number of absorbed trajectories. A batch of one trajectory has no standard error
/// (`COAG_INVALID_ARGUMENT`); an `f` whose mean or standard error is not finite is
/// `COAG_INVALID_RATE`; nothing is written on an error.
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
        if r.count() < 2 {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!(
                    "a mean and its standard error need at least 2 trajectories (the batch has {})",
                    r.count()
                ),
            );
        }
        let (m, se) = (r.mean(), r.std_error());
        if !(m.is_finite() && se.is_finite()) {
            return fail(
                COAG_INVALID_RATE,
                format!(
                    "the observable's mean over the trajectories is {m} ± {se}: f must return finite values"
                ),
            );
        }
        // SAFETY: checked non-null; writable (contract).
        unsafe {
            write(mean, m);
            write(std_error, se);
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
        let mut w = Writer::new(&mut []);
        with_batch!(&h.inner, b => b.save_envelope(h.drift, &mut w));
        let len = w.needed();
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, len) };
        Ok(())
    })
}

/// Saves the batch (configuration, time, every trajectory; the drift's fingerprint,
/// not the drift) in core's checkpoint envelope into `buf`; `written` (may be NULL)
/// gets the bytes used.
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
        let mut w = Writer::new(b);
        with_batch!(&h.inner, s => s.save_envelope(h.drift, &mut w));
        let n = w.finish()?;
        if !written.is_null() {
            // SAFETY: non-null; writable (contract).
            unsafe { write(written, n) };
        }
        Ok(())
    })
}

/// Restores a checkpoint into a batch of the same dimension, size and drift (a callback
/// drift: any callback); on error the batch is unchanged.
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
        let (h, _busy) = unsafe { handle_mut(h, "h") }?;
        disjoint(
            h,
            buf as usize,
            if buf.is_null() { 0 } else { len },
            (0, 0),
            "buf",
        )?;
        // SAFETY: as above.
        let b = unsafe { slice(buf, len, "buf") }?;
        let print = h.drift;
        with_batch!(&mut h.inner, s => s.restore_envelope(b, print))?;
        Ok(())
    })
}
