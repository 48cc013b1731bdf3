//! C ABI of coagula (`libcoagula`).
//!
//! Conventions (repeated in `include/coagula.h` and the README):
//! * Every function returns an `int` status (`COAG_OK = 0`, or one of the `COAG_*`
//!   codes below); results go to out-parameters, which come last and are written only
//!   on success. `coag_last_error_message` copies the message of the last failure on the
//!   calling thread.
//! * Handles (`coag_kernel`, `coag_fragmentation`, `coag_sim`) are created by
//!   `coag_*_new*` and released by the matching `coag_*_free`; freeing NULL is a no-op.
//!   A sim copies what it needs from the kernel and fragmentation handles, which may be
//!   freed right after the sim is created.
//! * Every pointer is checked for NULL and every buffer comes with its length; a buffer
//!   that is too small is an error (`COAG_BUFFER_TOO_SMALL`), never an overrun.
//! * A failed call leaves the handle as it was (for `coag_sim_advance_to`: as it was
//!   before the failing event), and the handle stays usable.
//! * No Rust panic crosses the boundary: it is caught and reported as `COAG_PANIC`.
//! * Threading: a handle may be used by one thread at a time; different handles are
//!   independent. User callbacks are called on the calling thread, during the call,
//!   and must not call into the handle whose call invoked them (not even to read it:
//!   that handle is being changed) nor free it.
//! * `user_data` pointers are stored, never dereferenced by coagula; they must stay
//!   valid as long as a handle that uses them (including sims made from a user kernel).

#![allow(non_camel_case_types)]
#![deny(unsafe_op_in_unsafe_fn)]

mod dsmc;
mod kernel;
mod langevin;
mod rng;
mod sim;
mod thermal;

pub use dsmc::*;
pub use kernel::*;
pub use langevin::*;
pub use sim::*;
pub use thermal::*;

use coagula_core::Error;
use std::cell::RefCell;
use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Success.
pub const COAG_OK: i32 = 0;
/// A required pointer argument was NULL.
pub const COAG_NULL_PARAMETER: i32 = 1;
/// An argument is outside its admissible range (NaN, negative rate, bad enum value).
pub const COAG_INVALID_ARGUMENT: i32 = 2;
/// A caller buffer is too small (or has the wrong length).
pub const COAG_BUFFER_TOO_SMALL: i32 = 3;
/// A capacity (maximum particle size) would be exceeded.
pub const COAG_CAPACITY: i32 = 4;
/// A kernel returned a negative or non-finite rate at run time.
pub const COAG_INVALID_RATE: i32 = 5;
/// The operation does not apply to this scheme or kernel (e.g. no low-rank bound).
pub const COAG_UNSUPPORTED: i32 = 6;
/// A target time lies before the current time.
pub const COAG_TIME_BACKWARDS: i32 = 7;
/// A checkpoint buffer is malformed or belongs to another scheme or configuration.
pub const COAG_BAD_CHECKPOINT: i32 = 8;
/// A panic was caught inside the library (a bug: please report it).
pub const COAG_PANIC: i32 = 9;
/// `coag_sim_advance_to` stopped before its target time: its work limit was spent or
/// its cancellation callback asked (the sim is consistent at the time reached; call
/// again to continue). Not an error of the sim.
pub const COAG_INTERRUPTED: i32 = 10;
/// The host's random callback is degenerate (returned the same word 8 times in a row);
/// the call was undone.
pub const COAG_RNG_FAILURE: i32 = 11;

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

fn set_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = msg);
}

/// Maps a core error to a status code (and records its message).
pub(crate) fn status_of(e: &Error) -> i32 {
    set_error(e.to_string());
    match e {
        Error::BufferLength { .. } => COAG_BUFFER_TOO_SMALL,
        Error::Capacity { .. } | Error::Overflow { .. } => COAG_CAPACITY,
        Error::InvalidRate { .. } | Error::BoundExceeded { .. } => COAG_INVALID_RATE,
        Error::Unsupported { .. } => COAG_UNSUPPORTED,
        Error::TimeBackwards { .. } => COAG_TIME_BACKWARDS,
        Error::Checkpoint { .. } => COAG_BAD_CHECKPOINT,
        _ => COAG_INVALID_ARGUMENT,
    }
}

/// An error of the FFI layer itself: a status and its message.
pub(crate) struct Fail(pub i32, pub String);

impl From<Error> for Fail {
    fn from(e: Error) -> Self {
        let code = status_of(&e);
        Fail(code, e.to_string())
    }
}

pub(crate) fn fail<T>(code: i32, msg: impl Into<String>) -> Result<T, Fail> {
    Err(Fail(code, msg.into()))
}

thread_local! {
    /// Where the last panic inside a library call on this thread happened.
    static PANIC_AT: RefCell<String> = const { RefCell::new(String::new()) };
    /// Whether this thread is inside a library call (so a panic is the library's).
    static IN_CALL: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Installs, once, a panic hook that keeps the library's panics off the host's stderr:
/// a panic inside a library call is reported only as `COAG_PANIC` and its message
/// (`coag_last_error_message`); any other panic goes to the hook that was there before.
fn silence_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if IN_CALL.with(|c| c.get()) {
                // where, for the message of COAG_PANIC (a bug report needs it)
                let at = info
                    .location()
                    .map(|l| format!("{}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                PANIC_AT.with(|p| *p.borrow_mut() = at);
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `f` inside a panic boundary and turns its result into a status code.
pub(crate) fn guard(f: impl FnOnce() -> Result<(), Fail>) -> i32 {
    silence_panics();
    let outer = IN_CALL.with(|c| c.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    IN_CALL.with(|c| c.set(outer));
    match result {
        Ok(Ok(())) => COAG_OK,
        Ok(Err(Fail(code, msg))) => {
            set_error(msg);
            code
        }
        Err(p) => {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            let at = PANIC_AT.with(|p| std::mem::take(&mut *p.borrow_mut()));
            set_error(format!("internal error (panic at {at}): {msg}"));
            COAG_PANIC
        }
    }
}

/// A panic inside a library call, for the panic-hook test only (not part of the C
/// ABI): returns the status the boundary makes of it.
#[doc(hidden)]
pub fn panic_inside_a_call_for_tests() -> i32 {
    guard(|| panic!("a panic inside a library call"))
}

/// Checks a pointer argument for NULL.
pub(crate) fn non_null<T>(p: *const T, name: &str) -> Result<(), Fail> {
    if p.is_null() {
        fail(COAG_NULL_PARAMETER, format!("{name} is NULL"))
    } else {
        Ok(())
    }
}

/// The library version as a NUL-terminated static string.
#[unsafe(no_mangle)]
pub extern "C" fn coag_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// The name of a status code (e.g. `"COAG_OK"`), a static NUL-terminated string;
/// `"COAG_UNKNOWN"` for a value that is not a status.
#[unsafe(no_mangle)]
pub extern "C" fn coag_status_name(status: i32) -> *const c_char {
    let s: &'static str = match status {
        COAG_OK => "COAG_OK\0",
        COAG_NULL_PARAMETER => "COAG_NULL_PARAMETER\0",
        COAG_INVALID_ARGUMENT => "COAG_INVALID_ARGUMENT\0",
        COAG_BUFFER_TOO_SMALL => "COAG_BUFFER_TOO_SMALL\0",
        COAG_CAPACITY => "COAG_CAPACITY\0",
        COAG_INVALID_RATE => "COAG_INVALID_RATE\0",
        COAG_UNSUPPORTED => "COAG_UNSUPPORTED\0",
        COAG_TIME_BACKWARDS => "COAG_TIME_BACKWARDS\0",
        COAG_BAD_CHECKPOINT => "COAG_BAD_CHECKPOINT\0",
        COAG_PANIC => "COAG_PANIC\0",
        COAG_INTERRUPTED => "COAG_INTERRUPTED\0",
        COAG_RNG_FAILURE => "COAG_RNG_FAILURE\0",
        _ => "COAG_UNKNOWN\0",
    };
    s.as_ptr().cast()
}

/// Copies the message of the last failed call on this thread into `buf` (NUL-terminated)
/// and its length without the NUL into `*out_len` (if not NULL). When `buf_len` is too
/// small the message is truncated to fit and `COAG_BUFFER_TOO_SMALL` is returned (with
/// `*out_len` the full length); `buf` may be NULL with `buf_len` 0 to query the length.
///
/// # Safety
/// `buf` must be NULL or point to `buf_len` writable bytes; `out_len` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_last_error_message(
    buf: *mut c_char,
    buf_len: usize,
    out_len: *mut usize,
) -> i32 {
    let msg = LAST_ERROR.with(|e| e.borrow().clone());
    if !out_len.is_null() {
        // SAFETY: checked non-null; the caller guarantees it is writable.
        unsafe { *out_len = msg.len() };
    }
    if buf.is_null() {
        return if buf_len == 0 {
            COAG_OK
        } else {
            COAG_NULL_PARAMETER
        };
    }
    if buf_len == 0 {
        return COAG_BUFFER_TOO_SMALL;
    }
    let n = msg.len().min(buf_len - 1);
    // SAFETY: buf has buf_len ≥ n + 1 writable bytes (caller contract, checked above).
    unsafe {
        std::ptr::copy_nonoverlapping(msg.as_ptr(), buf.cast::<u8>(), n);
        *buf.add(n) = 0;
    }
    if n < msg.len() {
        COAG_BUFFER_TOO_SMALL
    } else {
        COAG_OK
    }
}

/// Writes `v` through `out`.
///
/// # Safety
/// `out` must be non-null (checked with [`non_null`]) and valid for a write of `T`.
pub(crate) unsafe fn write<T>(out: *mut T, v: T) {
    // SAFETY: the caller's contract.
    unsafe { out.write(v) };
}

/// A slice from a (pointer, length) pair; NULL is allowed only with length 0.
///
/// # Safety
/// A non-null `p` must point to `len` readable, initialised elements that stay
/// valid and unmutated for `'a`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, len: usize, name: &str) -> Result<&'a [T], Fail> {
    if len == 0 {
        return Ok(&[]);
    }
    non_null(p, name)?;
    if len
        .checked_mul(std::mem::size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!("{name}: length {len} is not a buffer length"),
        );
    }
    // SAFETY: non-null, length in range, and the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// A mutable slice from a (pointer, length) pair.
///
/// # Safety
/// A non-null `p` must point to `len` writable elements, not aliased for `'a`.
pub(crate) unsafe fn slice_mut<'a, T>(
    p: *mut T,
    len: usize,
    name: &str,
) -> Result<&'a mut [T], Fail> {
    if len == 0 {
        return Ok(&mut []);
    }
    non_null(p, name)?;
    if len
        .checked_mul(std::mem::size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!("{name}: length {len} is not a buffer length"),
        );
    }
    // SAFETY: non-null, length in range, and the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Reads a caller's config struct that starts with a `size_t struct_size` (the ABI's
/// growth rule: a struct from an older header is shorter; its missing fields take
/// their defaults from `default`). A size below `min` (the first version's) or above
/// ours (a newer header than this library) is refused.
///
/// # Safety
/// A non-null `p` must point to at least `struct_size` readable bytes.
pub(crate) unsafe fn read_config<T: Copy>(
    p: *const T,
    name: &str,
    min: usize,
    default: T,
) -> Result<T, Fail> {
    non_null(p, name)?;
    // SAFETY: non-null; every config begins with a size_t (caller contract).
    let size = unsafe { p.cast::<usize>().read_unaligned() };
    let ours = std::mem::size_of::<T>();
    if size < min || size > ours {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!(
                "{name}->struct_size is {size}: set it to sizeof the struct (this library: {min}..={ours} bytes); use the *_default_config function"
            ),
        );
    }
    let mut out = default;
    // SAFETY: `size ≤ size_of::<T>()` bytes are readable at p (contract) and writable
    // in `out`; T is plain old data (a repr(C) struct of numbers).
    unsafe {
        std::ptr::copy_nonoverlapping(p.cast::<u8>(), (&mut out as *mut T).cast::<u8>(), size)
    };
    Ok(out)
}

/// Exact solutions (Eibeck & Wagner 2000 eqs. 6.8-6.11; Lécot et al. 2019 §4), validation targets for hosts.
pub const COAG_EXACT_CONSTANT: i32 = 0;
/// Additive kernel `K = x + y`.
pub const COAG_EXACT_ADDITIVE: i32 = 1;
/// Multiplicative kernel, Flory's solution.
pub const COAG_EXACT_MULTIPLICATIVE: i32 = 2;
/// Multiplicative kernel, Marcus–Lushnikov limit.
pub const COAG_EXACT_MARCUS_LUSHNIKOV: i32 = 3;
/// Lécot's coagulation–fragmentation test (moments only).
pub const COAG_EXACT_COAG_FRAG: i32 = 4;

fn exact_of(solution: i32) -> Result<coagula_core::exact::Exact, Fail> {
    use coagula_core::exact::Exact;
    Ok(match solution {
        COAG_EXACT_CONSTANT => Exact::constant(1.0)?,
        COAG_EXACT_ADDITIVE => Exact::additive(),
        COAG_EXACT_MULTIPLICATIVE => Exact::multiplicative(),
        COAG_EXACT_MARCUS_LUSHNIKOV => Exact::marcus_lushnikov(),
        COAG_EXACT_COAG_FRAG => Exact::coagulation_fragmentation(),
        _ => {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!("unknown exact solution {solution}"),
            );
        }
    })
}

/// Exact moment `M_m(t)` (m = 0..3) of a `COAG_EXACT_*` solution from `n_1(0) = 1`.
///
/// # Safety
/// `out` must be NULL or valid for writing one `double`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_exact_moment(solution: i32, m: u32, t: f64, out: *mut f64) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        let v = exact_of(solution)?.moment(m, t)?;
        // SAFETY: checked non-null; writable by the caller's contract.
        unsafe { write(out, v) };
        Ok(())
    })
}

/// Exact concentration `n_k(t)` of a `COAG_EXACT_*` solution.
///
/// # Safety
/// `out` must be NULL or valid for writing one `double`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_exact_density(solution: i32, k: u64, t: f64, out: *mut f64) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        let v = exact_of(solution)?.number_density(k, t)?;
        // SAFETY: checked non-null; writable by the caller's contract.
        unsafe { write(out, v) };
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_and_messages() {
        let mut out = -1.0;
        assert_eq!(
            unsafe { coag_exact_moment(COAG_EXACT_CONSTANT, 2, 3.0, &mut out) },
            COAG_OK
        );
        assert_eq!(out, 4.0);
        assert_eq!(
            unsafe { coag_exact_moment(COAG_EXACT_CONSTANT, 2, -3.0, &mut out) },
            COAG_INVALID_ARGUMENT
        );
        assert_eq!(out, 4.0, "outputs untouched on error");
        let mut buf = [0 as c_char; 8];
        let mut len = 0usize;
        assert_eq!(
            unsafe { coag_last_error_message(buf.as_mut_ptr(), buf.len(), &mut len) },
            COAG_BUFFER_TOO_SMALL
        );
        assert!(len > 8);
        let mut big = vec![0 as c_char; len + 1];
        assert_eq!(
            unsafe { coag_last_error_message(big.as_mut_ptr(), big.len(), std::ptr::null_mut()) },
            COAG_OK
        );
        let msg = unsafe { std::ffi::CStr::from_ptr(big.as_ptr()) }
            .to_str()
            .unwrap();
        assert!(msg.contains("t = -3"), "{msg}");
        assert_eq!(
            unsafe { coag_exact_moment(99, 2, 1.0, &mut out) },
            COAG_INVALID_ARGUMENT
        );
        assert_eq!(
            unsafe { coag_exact_moment(0, 2, 1.0, std::ptr::null_mut()) },
            COAG_NULL_PARAMETER
        );
        let v = unsafe { std::ffi::CStr::from_ptr(coag_version()) };
        assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
    }
}
