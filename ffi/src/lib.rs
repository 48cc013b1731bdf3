//! C ABI of coagula (`libcoagula`).
//!
//! Conventions (repeated in `include/coagula.h` and the README):
//! * Every function returns an `int` status (`COAG_OK = 0`, or one of the `COAG_*`
//!   codes below); results go to out-parameters, which come last and are written only
//!   on success. `coag_last_error_message` copies the message of the last failure on the
//!   calling thread.
//! * Handles (`coag_kernel`, `coag_fragmentation`, `coag_options`, `coag_sim`,
//!   `coag_langevin`) are created by `coag_*_new*` and released by the matching
//!   `coag_*_free`; freeing NULL is a no-op. A sim copies what it needs from the kernel,
//!   fragmentation and options handles, which may be freed right after it is created.
//! * One `coag_sim` runs every population scheme of core's registry, chosen by name;
//!   `coag_scheme_*`, `coag_option_*` and `coag_builtin_*` read core's tables (the
//!   schemes and their capabilities, the options, the built-in kernels). The options
//!   and their checks are core's: the C ABI, the CLI and Python refuse the same mistake
//!   with the same message.
//! * Every pointer is checked for NULL and every buffer comes with its length; a buffer
//!   that is too small is an error (`COAG_BUFFER_TOO_SMALL`), never an overrun.
//! * A failed call leaves the handle as it was (for `coag_sim_advance_to`: as it was
//!   before the failing event), and the handle stays usable.
//! * No Rust panic crosses the boundary: it is caught and reported as `COAG_PANIC`.
//! * Threading: a handle may be used by one thread at a time; different handles are
//!   independent. User callbacks are called on the calling thread, during the call;
//!   a callback that calls into the handle whose call invoked it gets
//!   `COAG_REENTRANT` (and freeing it from there is ignored).
//! * `user_data` pointers are stored, never dereferenced by coagula; they must stay
//!   valid as long as a handle that uses them (including sims made from a user kernel).

#![allow(non_camel_case_types)]
#![deny(unsafe_op_in_unsafe_fn)]

mod exact;
mod kernel;
mod langevin;
mod options;
mod registry;
mod report;
mod rng;
mod sectional;
mod sim;
mod status;
mod util;

pub use exact::*;
pub use kernel::*;
pub use langevin::*;
pub use options::*;
pub use registry::*;
pub use report::*;
pub use rng::coag_rng_callback;
pub use sectional::*;
pub use sim::*;
pub use status::*;
