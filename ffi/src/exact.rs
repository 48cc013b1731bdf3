//! Exact solutions as validation targets for hosts (Eibeck & Wagner 2000 eqs.
//! 6.8-6.11; Lécot et al. 2019 §4).

use crate::status::{COAG_INVALID_ARGUMENT, Fail, fail, guard};
use crate::util::{non_null, write};

/// The constant kernel `K = 1` (a `COAG_EXACT_*` solution).
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
/// The solutions are those of coefficient 1 from monomers of concentration 1. For a
/// kernel `b K` (constant, additive or multiplicative) from monomers of concentration
/// `c0`, the solution is `c0 · M_m(b c0 t)`: evaluate at the scaled time `b c0 t` and
/// multiply by `c0` (the same holds for `coag_exact_density`). Lécot's
/// coagulation–fragmentation test has no such scaling (its break-up rate fixes the
/// time unit). Orders above 3 have no closed form here: `COAG_UNSUPPORTED`.
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

/// Exact concentration `n_k(t)` of a `COAG_EXACT_*` solution from `n_1(0) = 1`
/// (scaled to a coefficient b and concentration c0 as `coag_exact_moment` says;
/// `COAG_EXACT_COAG_FRAG` has moments only: `COAG_UNSUPPORTED`).
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
