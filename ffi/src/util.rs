//! Pointer, string, buffer and struct helpers every entry point validates its input
//! with, and the guard against a call re-entering a handle that is mid-call.

use crate::status::{
    COAG_BUFFER_TOO_SMALL, COAG_INVALID_ARGUMENT, COAG_NULL_PARAMETER, COAG_REENTRANT, Fail, fail,
};
use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_void};

/// Checks a pointer argument for NULL.
pub(crate) fn non_null<T>(p: *const T, name: &str) -> Result<(), Fail> {
    if p.is_null() {
        fail(COAG_NULL_PARAMETER, format!("{name} is NULL"))
    } else {
        Ok(())
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

/// Writes `v` through `out` when it is not NULL.
///
/// # Safety
/// `out` NULL or valid for a write of `T`.
pub(crate) unsafe fn write_opt<T>(out: *mut T, v: T) {
    if !out.is_null() {
        // SAFETY: the caller's contract.
        unsafe { out.write(v) };
    }
}

fn check_len<T>(len: usize, name: &str) -> Result<(), Fail> {
    if len
        .checked_mul(std::mem::size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!("{name}: length {len} is not a buffer length"),
        );
    }
    Ok(())
}

/// A slice from a (pointer, length) pair; NULL is allowed only with length 0.
///
/// # Safety
/// A non-null `p` must point to `len` readable, initialised elements that stay valid
/// and unmutated for `'a`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, len: usize, name: &str) -> Result<&'a [T], Fail> {
    if len == 0 {
        return Ok(&[]);
    }
    non_null(p, name)?;
    check_len::<T>(len, name)?;
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
    check_len::<T>(len, name)?;
    // SAFETY: non-null, length in range, and the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Refuses two caller buffers that overlap.
pub(crate) fn disjoint<A, B>(a: &[A], b: &[B], what: &str) -> Result<(), Fail> {
    let (a0, b0) = (a.as_ptr() as usize, b.as_ptr() as usize);
    let (la, lb) = (std::mem::size_of_val(a), std::mem::size_of_val(b));
    if la > 0 && lb > 0 && a0 < b0.saturating_add(lb) && b0 < a0.saturating_add(la) {
        return fail(COAG_INVALID_ARGUMENT, format!("{what} overlap"));
    }
    Ok(())
}

/// A C string argument as UTF-8.
///
/// # Safety
/// A non-null `p` must point to a NUL-terminated string valid for `'a`.
pub(crate) unsafe fn text<'a>(p: *const c_char, name: &str) -> Result<&'a str, Fail> {
    non_null(p, name)?;
    // SAFETY: non-null and NUL-terminated (contract).
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str()
        .or_else(|_| fail(COAG_INVALID_ARGUMENT, format!("{name} is not UTF-8")))
}

/// NUL-terminated copies of static strings, made once and kept for the life of the
/// process (what the table queries hand out).
pub(crate) fn c_strings(all: impl Iterator<Item = &'static str>) -> Vec<CString> {
    all.map(|s| CString::new(s).unwrap_or_default()).collect()
}

/// Writes `value` into a caller struct of `size` bytes (`sizeof` as the caller compiled
/// it): the fields this library knows, at most `size` bytes, with `struct_size` set to
/// what was written. A caller built against an older header (smaller struct) is never
/// written past its end; `size` below the first version's is refused.
///
/// # Safety
/// A non-null `out` must be valid for writing `size` bytes; T is a repr(C) struct of
/// plain data beginning with a `usize`.
pub(crate) unsafe fn write_sized<T: Copy>(
    out: *mut T,
    size: usize,
    v1: usize,
    value: T,
    name: &str,
) -> Result<(), Fail> {
    non_null(out, "out")?;
    if size < v1 {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!(
                "{name}: size {size} is below the struct's first version ({v1} bytes); pass sizeof the struct"
            ),
        );
    }
    let n = size.min(std::mem::size_of::<T>());
    // SAFETY: `n ≤ size` bytes writable at out (contract), `n ≤ size_of::<T>()` readable
    // from value; then the leading usize (in bounds: n ≥ v1 > 8).
    unsafe {
        std::ptr::copy_nonoverlapping((&value as *const T).cast::<u8>(), out.cast::<u8>(), n);
        out.cast::<usize>().write_unaligned(n);
    }
    Ok(())
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

thread_local! {
    /// The handles of this thread that are inside a call (a callback of that call
    /// calling back into the same handle is refused: `COAG_REENTRANT`).
    static BUSY: RefCell<Vec<usize>> = const { RefCell::new(Vec::new()) };
}

/// Marks a handle busy for the life of the value.
pub(crate) struct Busy(usize);

impl Drop for Busy {
    fn drop(&mut self) {
        BUSY.with(|b| {
            let mut b = b.borrow_mut();
            if let Some(i) = b.iter().rposition(|&p| p == self.0) {
                b.swap_remove(i);
            }
        });
    }
}

fn check_idle<T>(p: *const T, name: &str) -> Result<(), Fail> {
    if BUSY.with(|b| b.borrow().contains(&(p as usize))) {
        return fail(
            COAG_REENTRANT,
            format!(
                "{name} is in the middle of another call (a callback called back into the handle whose call invoked it): refused, nothing changed"
            ),
        );
    }
    Ok(())
}

/// A reference to a live handle that is not mid-call.
///
/// # Safety
/// A non-null `p` must be a live handle, not mutated for `'a`.
pub(crate) unsafe fn handle<'a, T>(p: *const T, name: &str) -> Result<&'a T, Fail> {
    non_null(p, name)?;
    check_idle(p, name)?;
    // SAFETY: non-null; the function's contract.
    Ok(unsafe { &*p })
}

/// A mutable reference to a live handle that is not mid-call, marked busy until the
/// returned guard drops (the caller keeps it for the call).
///
/// # Safety
/// A non-null `p` must be a live handle used by this thread alone for `'a`.
pub(crate) unsafe fn handle_mut<'a, T>(p: *mut T, name: &str) -> Result<(&'a mut T, Busy), Fail> {
    non_null(p, name)?;
    check_idle(p, name)?;
    BUSY.with(|b| b.borrow_mut().push(p as usize));
    // SAFETY: non-null; the function's contract.
    Ok((unsafe { &mut *p }, Busy(p as usize)))
}

/// Checks a caller workspace for `need` bytes: non-null, aligned for `double`, large
/// enough, not overlapping `sizes`.
pub(crate) fn check_workspace(
    workspace: *mut c_void,
    bytes: usize,
    need: usize,
    sizes: &[f64],
) -> Result<(), Fail> {
    non_null(workspace, "workspace")?;
    if !(workspace as usize).is_multiple_of(std::mem::align_of::<f64>()) {
        return fail(COAG_INVALID_ARGUMENT, "workspace is not aligned for double");
    }
    if bytes < need {
        return fail(
            COAG_BUFFER_TOO_SMALL,
            format!(
                "workspace: {bytes} bytes for {} particles, {need} needed",
                sizes.len()
            ),
        );
    }
    let (w0, s0) = (workspace as usize, sizes.as_ptr() as usize);
    if !sizes.is_empty() && w0 < s0.saturating_add(8 * sizes.len()) && s0 < w0.saturating_add(need)
    {
        return fail(COAG_INVALID_ARGUMENT, "sizes overlap the workspace");
    }
    Ok(())
}

/// The caller's workspace as a slice of `T`, zeroed (so that it is initialised).
///
/// # Safety
/// `workspace` passed [`check_workspace`] for `need` bytes, is aligned for `T`, and is
/// valid and used by nothing else for the life of the handle built on it.
pub(crate) unsafe fn zeroed_workspace<T>(workspace: *mut c_void, need: usize) -> &'static mut [T] {
    // SAFETY: the function's contract.
    unsafe {
        std::ptr::write_bytes(workspace.cast::<u8>(), 0, need);
        std::slice::from_raw_parts_mut(workspace.cast::<T>(), need / std::mem::size_of::<T>())
    }
}

/// Bytes of a workspace of `len` elements of `T` (`None`: it overflows), refused past
/// `isize::MAX`.
pub(crate) fn workspace_bytes<T>(len: Option<usize>, n: usize) -> Result<usize, Fail> {
    match len
        .and_then(|l| l.checked_mul(std::mem::size_of::<T>()))
        .filter(|&b| b <= isize::MAX as usize)
    {
        Some(b) => Ok(b),
        None => fail(
            COAG_INVALID_ARGUMENT,
            format!("workspace for {n} particles overflows"),
        ),
    }
}
