//! C ABI of coagula (`libcoagula`).
//!
//! The full ABI (opaque handles per scheme, status codes, checkpoints) arrives with the
//! schemes; this crate currently exports the library version and the exact solutions,
//! which a C host can already use as validation targets.

use coagula_core::exact::Exact;

/// Status code: success.
pub const COAG_OK: i32 = 0;
/// Status code: an argument was NULL.
pub const COAG_NULL_PARAMETER: i32 = 1;
/// Status code: an argument was outside its admissible range.
pub const COAG_INVALID_ARGUMENT: i32 = 2;

/// The library version as a NUL-terminated static string.
#[unsafe(no_mangle)]
pub extern "C" fn coag_version() -> *const core::ffi::c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// Exact moment `M_m(t)` of the constant-kernel solution (K = k0, n_1(0) = 1), written to
/// `*out` on success. Returns `COAG_OK`, `COAG_NULL_PARAMETER` or
/// `COAG_INVALID_ARGUMENT` (k0 ≤ 0, t < 0, NaN, m > 3); `*out` is untouched on error.
///
/// # Safety
/// `out` must be NULL or point to writable memory for one `double`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_exact_constant_moment(k0: f64, m: u32, t: f64, out: *mut f64) -> i32 {
    if out.is_null() {
        return COAG_NULL_PARAMETER;
    }
    match Exact::constant(k0).and_then(|e| e.moment(m, t)) {
        Ok(v) => {
            // SAFETY: checked non-null; the caller guarantees it is writable.
            unsafe { *out = v };
            COAG_OK
        }
        Err(_) => COAG_INVALID_ARGUMENT,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exports_behave() {
        let v = unsafe { core::ffi::CStr::from_ptr(coag_version()) };
        assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
        let mut out = -1.0;
        assert_eq!(
            unsafe { coag_exact_constant_moment(1.0, 2, 3.0, &mut out) },
            COAG_OK
        );
        assert_eq!(out, 4.0);
        assert_eq!(
            unsafe { coag_exact_constant_moment(-1.0, 2, 3.0, &mut out) },
            COAG_INVALID_ARGUMENT
        );
        assert_eq!(out, 4.0);
        assert_eq!(
            unsafe { coag_exact_constant_moment(1.0, 2, 3.0, core::ptr::null_mut()) },
            COAG_NULL_PARAMETER
        );
    }
}
