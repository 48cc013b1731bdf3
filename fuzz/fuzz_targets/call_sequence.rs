//! Random call sequences over live handles of every scheme, with random arguments
//! (NaN, infinities, huge and tiny values included). After each successful call the
//! invariants hold: a sim's time is finite and where the call put it, moments are
//! finite (or `COAG_CAPACITY`), and under pure coagulation an advance keeps the mass
//! concentration M1 and does not raise the number concentration M0. A failed call
//! leaves the sim as it was. No call returns `COAG_PANIC`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| coagula_fuzz::call_sequence::run(data));
