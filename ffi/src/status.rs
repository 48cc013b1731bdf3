//! Status codes, the last error message of each thread, and the panic boundary every
//! entry point runs inside.

use coagula_core::Error;
use std::cell::RefCell;
use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Success.
pub const COAG_OK: i32 = 0;
/// A required pointer argument was NULL.
pub const COAG_NULL_PARAMETER: i32 = 1;
/// An argument is outside its admissible range (NaN, negative rate, unknown name).
pub const COAG_INVALID_ARGUMENT: i32 = 2;
/// A caller buffer is too small (or has the wrong length).
pub const COAG_BUFFER_TOO_SMALL: i32 = 3;
/// A capacity (maximum particle size, memory budget) would be exceeded.
pub const COAG_CAPACITY: i32 = 4;
/// A kernel returned a negative or non-finite rate at run time.
pub const COAG_INVALID_RATE: i32 = 5;
/// The operation, option or input does not apply to this scheme or kernel.
pub const COAG_UNSUPPORTED: i32 = 6;
/// A target time lies before the current time.
pub const COAG_TIME_BACKWARDS: i32 = 7;
/// A checkpoint buffer is malformed or belongs to another scheme or configuration.
pub const COAG_BAD_CHECKPOINT: i32 = 8;
/// A panic was caught inside the library (a bug: please report it).
pub const COAG_PANIC: i32 = 9;
/// An advance stopped before its target time: its work limit was spent or its
/// cancellation callback asked (the handle is consistent at the time reached; call
/// again to continue). Not an error of the handle.
pub const COAG_INTERRUPTED: i32 = 10;
/// The host's random callback is degenerate (returned the same word 8 times in a row);
/// the call was undone.
pub const COAG_RNG_FAILURE: i32 = 11;
/// A call on a handle that is in the middle of another call (a callback calling back
/// into the handle whose call invoked it): refused, nothing changed.
pub const COAG_REENTRANT: i32 = 12;

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

pub(crate) fn set_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = msg);
}

/// Maps a core error to a status code.
pub(crate) fn status_of(e: &Error) -> i32 {
    match e {
        Error::BufferLength { .. } => COAG_BUFFER_TOO_SMALL,
        Error::Capacity { .. } | Error::Overflow { .. } => COAG_CAPACITY,
        Error::InvalidRate { .. } | Error::BoundExceeded { .. } => COAG_INVALID_RATE,
        Error::Unsupported { .. } | Error::OptionNotApplicable { .. } => COAG_UNSUPPORTED,
        Error::TimeBackwards { .. } => COAG_TIME_BACKWARDS,
        Error::Checkpoint { .. } | Error::CheckpointOption { .. } => COAG_BAD_CHECKPOINT,
        _ => COAG_INVALID_ARGUMENT,
    }
}

/// An error of the FFI layer: a status and its message.
pub(crate) struct Fail(pub i32, pub String);

impl From<Error> for Fail {
    fn from(e: Error) -> Self {
        Fail(status_of(&e), e.to_string())
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
        COAG_REENTRANT => "COAG_REENTRANT\0",
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
