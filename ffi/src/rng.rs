//! The randomness of a sim: its own xoshiro256++ stream (from core's seed policy,
//! `coagula_core::random::generator`, and checkpointed with it), or a host callback
//! returning random 64-bit words.

pub(crate) use coagula_core::random::Generator;
use rand_core::{Infallible, Rng, TryRng};
use std::ffi::c_void;

/// A host callback returning 64 uniformly random bits per call.
pub type coag_rng_callback = Option<unsafe extern "C" fn(user_data: *mut c_void) -> u64>;

/// The source a sim draws from.
#[derive(Clone, Debug)]
pub(crate) enum Source {
    Own(Generator),
    Callback(unsafe extern "C" fn(*mut c_void) -> u64, *mut c_void),
}

/// One word from a host callback (out of line: the sim's own stream is the hot path).
#[cold]
#[inline(never)]
fn call(f: unsafe extern "C" fn(*mut c_void) -> u64, d: *mut c_void) -> u64 {
    // SAFETY: the host registered this callback and user_data for this purpose and
    // guarantees both stay valid while the sim uses them.
    unsafe { f(d) }
}

impl TryRng for Source {
    type Error = Infallible;

    #[inline]
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok((self.try_next_u64()? >> 32) as u32)
    }

    #[inline(always)]
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        Ok(match self {
            Source::Own(p) => p.next_u64(),
            Source::Callback(f, d) => call(*f, *d),
        })
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let w = self.try_next_u64()?.to_le_bytes();
            chunk.copy_from_slice(&w[..chunk.len()]);
        }
        Ok(())
    }
}
