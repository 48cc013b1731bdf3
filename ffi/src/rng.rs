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
    /// A host callback, with the last word it returned and how often in a row.
    Callback {
        f: unsafe extern "C" fn(*mut c_void) -> u64,
        data: *mut c_void,
        last: u64,
        repeats: u32,
    },
}

/// A host stream that returned the same word this many times in a row is degenerate
/// (a real generator does so with probability 2⁻⁴⁴⁸).
pub(crate) const STUCK_AFTER: u32 = 8;

std::thread_local! {
    /// Set when a host stream on this thread turned out degenerate during a call (read
    /// by the call's cancellation poll and after it; cleared when a call starts).
    pub(crate) static DEGENERATE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

impl Source {
    /// A host callback as a fresh source.
    pub(crate) fn callback(f: unsafe extern "C" fn(*mut c_void) -> u64, data: *mut c_void) -> Self {
        Source::Callback {
            f,
            data,
            last: 0,
            repeats: 0,
        }
    }
}

/// One word from a host callback (out of line: the sim's own stream is the hot path),
/// watching for a stuck stream.
#[cold]
#[inline(never)]
fn call(
    f: unsafe extern "C" fn(*mut c_void) -> u64,
    d: *mut c_void,
    last: &mut u64,
    repeats: &mut u32,
) -> u64 {
    // SAFETY: the host registered this callback and user_data for this purpose and
    // guarantees both stay valid while the sim uses them.
    let w = unsafe { f(d) };
    if w == *last {
        *repeats += 1;
        if *repeats + 1 >= STUCK_AFTER {
            DEGENERATE.with(|c| c.set(true));
        }
    } else {
        (*last, *repeats) = (w, 0);
    }
    w
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
            Source::Callback {
                f,
                data,
                last,
                repeats,
            } => call(*f, *data, last, repeats),
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
