//! The options handle: core's settings by name (`coag_option_info_get` lists the
//! keys), validated by core as they are set.

use crate::status::{Fail, guard};
use crate::util::{handle, handle_mut, non_null, text, write};
use coagula_core::scheme::facade::{Options, Value};
use std::ffi::c_char;

/// Opaque options handle (`coag_options` in C): the settings a sim is built with.
#[derive(Clone, Debug, Default)]
pub struct coag_options {
    pub(crate) o: Options,
}

/// The options of a handle that may be NULL (every default).
///
/// # Safety
/// `p` NULL or live.
pub(crate) unsafe fn options_of(p: *const coag_options) -> Result<Options, Fail> {
    if p.is_null() {
        return Ok(Options::default());
    }
    // SAFETY: non-null; live by contract.
    Ok(unsafe { handle(p, "options") }?.o.clone())
}

/// New options, every key at its default. Free with `coag_options_free`.
///
/// # Safety
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_new(out: *mut *mut coag_options) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(coag_options::default()))) };
        Ok(())
    })
}

/// A copy of `options`. Free with `coag_options_free`.
///
/// # Safety
/// `options` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_clone(
    options: *const coag_options,
    out: *mut *mut coag_options,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let o = unsafe { handle(options, "options") }?.clone();
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(o))) };
        Ok(())
    })
}

/// Releases an options handle (NULL is a no-op).
///
/// # Safety
/// `options` NULL or a live handle not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_free(options: *mut coag_options) {
    if !options.is_null() {
        // SAFETY: made by Box::into_raw in coag_options_new/clone, freed once (contract).
        drop(unsafe { Box::from_raw(options) });
    }
}

/// # Safety
/// `options` NULL or live; `key` NULL or NUL-terminated.
unsafe fn set(
    options: *mut coag_options,
    key: *const c_char,
    v: impl FnOnce() -> Result<Value<'static>, Fail>,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let key = unsafe { text(key, "key") }?;
        // SAFETY: NULL checked; live by contract.
        let (o, _busy) = unsafe { handle_mut(options, "options") }?;
        o.o.set(key, v()?)?;
        Ok(())
    })
}

/// Sets option `key` to the real `value` (the kinds of `coag_option_info_get`; a count
/// given as a real with no fractional part is accepted, 1e6 included). Errors (nothing
/// changes): an unknown key, a value of the wrong kind or out of range
/// (`COAG_INVALID_ARGUMENT`, core's message naming the key).
///
/// # Safety
/// `options` NULL or live; `key` NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_set_real(
    options: *mut coag_options,
    key: *const c_char,
    value: f64,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { set(options, key, || Ok(Value::Real(value))) }
}

/// Sets option `key` to the integer `value` (see `coag_options_set_real`).
///
/// # Safety
/// `options` NULL or live; `key` NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_set_count(
    options: *mut coag_options,
    key: *const c_char,
    value: u64,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { set(options, key, || Ok(Value::Count(value))) }
}

/// Sets option `key` on (non-zero) or off (see `coag_options_set_real`).
///
/// # Safety
/// `options` NULL or live; `key` NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_set_flag(
    options: *mut coag_options,
    key: *const c_char,
    value: i32,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { set(options, key, || Ok(Value::Flag(value != 0))) }
}

/// Sets option `key` to the name `value` (see `coag_options_set_real`).
///
/// # Safety
/// `options` NULL or live; `key` and `value` NULL or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_options_set_name(
    options: *mut coag_options,
    key: *const c_char,
    value: *const c_char,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let key = unsafe { text(key, "key") }?;
        let value = unsafe { text(value, "value") }?;
        // SAFETY: NULL checked; live by contract.
        let (o, _busy) = unsafe { handle_mut(options, "options") }?;
        o.o.set(key, Value::Name(value))?;
        Ok(())
    })
}
