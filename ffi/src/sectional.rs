//! Core's deterministic reference for a host (`coagula_core::exact::Sectional`): the
//! fixed-pivot sectional solution (Kumar & Ramkrishna 1996) of coagulation with a
//! source at one size, removal and growth at powers of size, on the host's pivots, by
//! RK4. A host checks its particle coupling against it (`examples/c/plug_flow.c`). The
//! numerics live in core; these calls translate.

use crate::kernel::{Kernel, coag_kernel};
use crate::status::guard;
use crate::util::{handle, handle_mut, non_null, slice, slice_mut, write};
use coagula_core::exact::Sectional;

/// Opaque sectional solution handle (`coag_sectional` in C).
pub struct coag_sectional {
    s: Sectional<Kernel>,
}

/// A sectional solution on the `len` pivots (finite, > 0, strictly ascending; at most
/// 4096) under the coagulation kernel `kernel`, with no particles, at t = 0. Free it
/// with `coag_sectional_free`.
///
/// # Safety
/// `kernel` NULL or live; `pivots` valid for `len` doubles; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_new(
    kernel: *const coag_kernel,
    pivots: *const f64,
    len: usize,
    out: *mut *mut coag_sectional,
) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        // SAFETY: NULL checked; live / readable by contract.
        let k = unsafe { handle(kernel, "kernel") }?.coagulation()?;
        let x = unsafe { slice(pivots, len, "pivots") }?;
        let s = Sectional::new(k, x.to_vec())?;
        // SAFETY: checked non-null; writable by contract.
        unsafe { write(out, Box::into_raw(Box::new(coag_sectional { s }))) };
        Ok(())
    })
}

/// Frees a sectional solution (NULL is a no-op).
///
/// # Safety
/// `s` NULL or from `coag_sectional_new`, freed once.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_free(s: *mut coag_sectional) {
    if !s.is_null() {
        // SAFETY: created by Box::into_raw in coag_sectional_new (caller contract).
        drop(unsafe { Box::from_raw(s) });
    }
}

/// Sets the processes beside coagulation: a source of `source_rate` particles per unit
/// volume and time at size `source_size` (rate 0: none), removal at
/// `removal_coefficient · x^removal_exponent` and growth `dx/dt = growth_coefficient ·
/// x^growth_exponent` (coefficients 0: none), evaluated at the pivots. Replaces any set
/// before; on error nothing changes.
///
/// # Safety
/// `s` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_set_processes(
    s: *mut coag_sectional,
    source_rate: f64,
    source_size: f64,
    removal_coefficient: f64,
    removal_exponent: f64,
    growth_coefficient: f64,
    growth_exponent: f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (h, _busy) = unsafe { handle_mut(s, "sectional") }?;
        let power = |c: f64, p: f64| move |x: f64| if c == 0.0 { 0.0 } else { c * x.powf(p) };
        // (rate 0: no source, whatever the size)
        let size = if source_rate == 0.0 {
            h.s.pivots()[0]
        } else {
            source_size
        };
        let next =
            h.s.clone()
                .with_source(source_rate, size)?
                .with_removal(power(removal_coefficient, removal_exponent))?
                .with_growth(power(growth_coefficient, growth_exponent))?;
        h.s = next;
        Ok(())
    })
}

/// Replaces the numbers per unit volume at the pivots (`len` of them, each finite and
/// ≥ 0); on error nothing changes.
///
/// # Safety
/// `s` NULL or live; `numbers` valid for `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_set_numbers(
    s: *mut coag_sectional,
    numbers: *const f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let (h, _busy) = unsafe { handle_mut(s, "sectional") }?;
        let n = unsafe { slice(numbers, len, "numbers") }?;
        let mut next = h.s.clone();
        if n.len() != next.pivots().len() {
            Err(coagula_core::Error::BufferLength {
                name: "numbers (one per pivot)",
                expected: next.pivots().len(),
                got: n.len(),
            })?;
        }
        for (i, &v) in n.iter().enumerate() {
            next.set_number(i, v)?;
        }
        h.s = next;
        Ok(())
    })
}

/// Adds `number` particles per unit volume of size `size`, split between the two
/// pivots around it keeping number and mass (past the last pivot: refused).
///
/// # Safety
/// `s` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_add(s: *mut coag_sectional, size: f64, number: f64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (h, _busy) = unsafe { handle_mut(s, "sectional") }?;
        h.s.add_at(size, number)?;
        Ok(())
    })
}

/// Integrates to time `t` (not before the current time) by RK4 with steps of at most
/// `dt` (finite, > 0). A step whose numbers turn negative or not finite is an error
/// (lower `dt`); on error nothing changes.
///
/// # Safety
/// `s` NULL or live.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_advance_to(s: *mut coag_sectional, t: f64, dt: f64) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let (h, _busy) = unsafe { handle_mut(s, "sectional") }?;
        let mut next = h.s.clone();
        next.advance_to(t, dt)?;
        h.s = next;
        Ok(())
    })
}

/// Writes the numbers per unit volume at the pivots into `out` (`len` = the number of
/// pivots).
///
/// # Safety
/// `s` NULL or live; `out` valid for `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_numbers(
    s: *const coag_sectional,
    out: *mut f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / writable by contract.
        let h = unsafe { handle(s, "sectional") }?;
        let n = h.s.numbers();
        if len != n.len() {
            Err(coagula_core::Error::BufferLength {
                name: "out (one per pivot)",
                expected: n.len(),
                got: len,
            })?;
        }
        let o = unsafe { slice_mut(out, len, "out") }?;
        o.copy_from_slice(n);
        Ok(())
    })
}

/// The moment `Σ x_i^order N_i` per unit volume, and the time, of a sectional solution
/// (either output may be NULL).
///
/// # Safety
/// `s` NULL or live; `moment` and `time` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sectional_moment(
    s: *const coag_sectional,
    order: f64,
    moment: *mut f64,
    time: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let h = unsafe { handle(s, "sectional") }?;
        if !order.is_finite() {
            Err(coagula_core::Error::NotFinite { name: "order" })?;
        }
        // SAFETY: each NULL or writable by contract.
        unsafe {
            crate::util::write_opt(moment, h.s.moment(order));
            crate::util::write_opt(time, h.s.time());
        }
        Ok(())
    })
}
