//! The Rust-side tests of the C ABI in one test binary (as core's `suite`): each file
//! its own binary compiled core's generic schemes once per file. `panic_hook.rs` stays
//! a binary of its own: it installs a process-wide panic hook.

#[path = "fuzz_replay.rs"]
mod fuzz_replay;
#[path = "handles.rs"]
mod handles;
#[path = "seed_policy.rs"]
mod seed_policy;
