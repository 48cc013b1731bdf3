//! The CLI's scenario parser on arbitrary text (and arbitrary `--set` overrides): a
//! scenario is loaded or refused with a message, never a panic or a hang.
#![no_main]

#[path = "../../cli/src/scenario/mod.rs"]
#[allow(dead_code, unused_imports)]
mod scenario;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // an optional override after a line "#--set key=value"
    let (text, overrides) = match text.split_once("\n#--set ") {
        Some((t, o)) => match scenario::parse_override(o.trim()) {
            Ok(kv) => (t, vec![kv]),
            Err(_) => (t, Vec::new()),
        },
        None => (text, Vec::new()),
    };
    let src = scenario::Source {
        name: "fuzz.toml",
        text,
        overrides: &overrides,
        drops: &[],
    };
    match scenario::load(&src) {
        Ok(plan) => drop(plan),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
});
