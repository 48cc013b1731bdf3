//! The step report: what one advance did, and the books of a handle.

use crate::status::{COAG_INVALID_ARGUMENT, Fail, fail, guard};
use crate::util::write_sized;
use coagula_core::scheme::StepReport;

/// What one advance did, or the books of every advance so far. The caller sets
/// `struct_size` (or calls `coag_step_report_init`) before passing it; the library
/// writes the fields that fit.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct coag_step_report {
    /// `sizeof(coag_step_report)` as the caller compiled it.
    pub struct_size: usize,
    /// Time reached.
    pub time: f64,
    /// Accepted events (coagulations, break-ups, collisions).
    pub events: u64,
    /// Proposals, accepted or not.
    pub proposals: u64,
    /// Proposals rejected by thinning.
    pub rejections: u64,
    /// Proposals where the kernel exceeded its declared bound: always 0 except for the
    /// event-driven schemes without the `strict-bound` option (elsewhere, and with it,
    /// a kernel above its bound is an error, `COAG_INVALID_RATE`).
    pub bound_violations: u64,
    /// Probabilities above 1 that were clipped (time-driven scheme).
    pub clipped: u64,
    /// Particle-number doublings.
    pub doublings: u64,
    /// Particles that left the system (0 for the schemes that keep every particle).
    pub removed: u64,
    /// Collisions that bounced instead of merging (0 for pure coagulation).
    pub bounces: u64,
}

/// Bytes of the first version (the smallest `struct_size` accepted).
pub(crate) const STEP_REPORT_V1: usize = std::mem::size_of::<coag_step_report>();

fn report_of(r: StepReport) -> coag_step_report {
    coag_step_report {
        struct_size: STEP_REPORT_V1,
        time: r.time,
        events: r.events,
        proposals: r.proposals,
        rejections: r.rejections,
        bound_violations: r.bound_violations,
        clipped: r.clipped,
        doublings: r.doublings,
        removed: r.removed,
        bounces: r.bounces,
    }
}

/// Checks the `struct_size` of a caller's report before anything changes.
///
/// # Safety
/// `out` NULL or readable for a `size_t`.
pub(crate) unsafe fn check_report(out: *const coag_step_report) -> Result<(), Fail> {
    if out.is_null() {
        return Ok(());
    }
    // SAFETY: non-null; a report begins with its size_t struct_size (contract).
    let size = unsafe { out.cast::<usize>().read_unaligned() };
    if size < STEP_REPORT_V1 {
        return fail(
            COAG_INVALID_ARGUMENT,
            format!(
                "report->struct_size is {size}: set it to sizeof(coag_step_report) (or call coag_step_report_init)"
            ),
        );
    }
    Ok(())
}

/// Writes `r` into the caller's report, as many bytes as its `struct_size` says.
///
/// # Safety
/// `out` non-null and valid for `out->struct_size` bytes (caller contract).
pub(crate) unsafe fn write_report(out: *mut coag_step_report, r: StepReport) -> Result<(), Fail> {
    // SAFETY: forwarded contract.
    unsafe { check_report(out) }?;
    // SAFETY: non-null (caller); a report begins with its size_t struct_size.
    let size = unsafe { out.cast::<usize>().read_unaligned() };
    // (a larger report is from a newer header: the fields this library knows are
    // written, `struct_size` is left as the caller set it)
    let v = report_of(r);
    let n = size.min(STEP_REPORT_V1);
    // SAFETY: `n ≤ size` bytes are writable at out (contract) and readable from v.
    unsafe {
        std::ptr::copy_nonoverlapping(
            (&v as *const coag_step_report).cast::<u8>().add(8),
            out.cast::<u8>().add(8),
            n - 8,
        )
    };
    Ok(())
}

/// Zero-fills a step report of `size` bytes (`sizeof(coag_step_report)`) and sets its
/// `struct_size`.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_step_report_init(out: *mut coag_step_report, size: usize) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe {
            write_sized(
                out,
                size,
                STEP_REPORT_V1,
                coag_step_report::default(),
                "step report",
            )
        }
    })
}
