//! A sim's checkpoint: core's one envelope (scheme, settings as built and as they
//! stand, the physics' fingerprint, the sim's own random stream, the state), sealed
//! with a checksum.

use super::coag_sim;
use crate::status::{COAG_BAD_CHECKPOINT, COAG_BUFFER_TOO_SMALL, Fail, fail, guard};
use crate::util::{handle, handle_mut, non_null, slice, slice_mut, write, write_opt};
use coagula_core::checkpoint::Writer;
use coagula_core::random::Generator;
use coagula_core::scheme::facade::peek_stream;

fn save(s: &coag_sim, w: &mut Writer) {
    s.sim.save_checkpoint(Some(s.own.parts()), w);
}

/// Bytes a checkpoint of the sim needs now.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_checkpoint_size(sim: *const coag_sim, out: *mut usize) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let mut w = Writer::new(&mut []);
        save(s, &mut w);
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, w.needed()) };
        Ok(())
    })
}

/// Writes the sim's full state (including its own random stream) into `buf`;
/// `*written` (may be NULL) receives the bytes used. A sim restored from it with
/// `coag_sim_restore` continues bit-identically.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` bytes; `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_checkpoint(
    sim: *const coag_sim,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let mut need = Writer::new(&mut []);
        save(s, &mut need);
        if len < need.needed() {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!(
                    "checkpoint: buffer of {len} bytes, {} needed",
                    need.needed()
                ),
            );
        }
        // SAFETY: NULL checked; `len` writable bytes by contract.
        let out = unsafe { slice_mut(buf, len, "buf") }?;
        let mut w = Writer::new(out);
        save(s, &mut w);
        let n = w.finish()?;
        // SAFETY: NULL or writable (contract).
        unsafe { write_opt(written, n) };
        Ok(())
    })
}

/// Restores a checkpoint into a sim of the same scheme, settings and physics (the seed,
/// the stream, the memory budget and the capacity may differ; the sim takes the
/// checkpoint's random stream — except the time-driven mass flow on randomised QMC
/// points, whose scrambling is keyed by the seed and stream: there they must match, or
/// the restore is `COAG_BAD_CHECKPOINT`). A checkpoint that is corrupted (checksum), truncated,
/// of another format, scheme, setting or kernel, or whose state fails the checks its
/// scheme's constructor makes is `COAG_BAD_CHECKPOINT`; on any error the sim is
/// unchanged.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_restore(sim: *mut coag_sim, buf: *const u8, len: usize) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let data = unsafe { slice(buf, len, "buf") }?;
        // the stream first, so that nothing changes when it is bad
        let own = match peek_stream(data)?.map(Generator::from_parts) {
            Some(Some(g)) => g,
            _ => {
                return Err(Fail(
                    COAG_BAD_CHECKPOINT,
                    "checkpoint: no valid random stream (not written by coag_sim_checkpoint)"
                        .into(),
                ));
            }
        };
        s.sim.restore_checkpoint(data)?;
        s.own = own;
        Ok(())
    })
}
