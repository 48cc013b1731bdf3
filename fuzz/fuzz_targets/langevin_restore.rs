//! Restore from arbitrary bytes into a Langevin batch of every kind: refused with the
//! batch unchanged, or a valid state that steps on (`coagula_fuzz::langevin_restore`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| coagula_fuzz::langevin_restore(data));
