//! Restore from arbitrary bytes into a sim of every scheme: a checkpoint is either
//! refused (`COAG_BAD_CHECKPOINT`, or `COAG_CAPACITY` past the memory budget) with the
//! sim unchanged, or accepted as a valid state that a bounded advance takes to a
//! status. The first byte picks the scheme and whether the bytes are resealed with a
//! correct checksum (to reach the state's own validation).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| coagula_fuzz::checkpoint_restore(data));
