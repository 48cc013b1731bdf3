//! The CI smoke run of the scenario-parser fuzz target (`fuzz/`): every input of its
//! committed corpus and every reproducer under `fuzz/regressions/` is loaded (or
//! refused with a message) through the CLI's own parser, as the target does.

// (scenario.rs's own unit tests, compiled here too, need the built-in examples)
#[path = "../src/examples.rs"]
#[allow(dead_code)]
mod examples;
#[path = "../src/frag.rs"]
#[allow(dead_code)]
mod frag;
#[path = "../src/scenario.rs"]
#[allow(dead_code)]
mod scenario;

use std::path::Path;

#[test]
fn scenario_parser_corpus_and_regressions() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut n = 0;
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join("scenario_parser")) else {
            continue;
        };
        for e in entries.filter_map(|e| e.ok()) {
            let data = std::fs::read(e.path()).unwrap();
            n += 1;
            let Ok(text) = std::str::from_utf8(&data) else {
                continue;
            };
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
            if let Err(e) = scenario::load(&src) {
                assert!(!e.to_string().is_empty());
            }
        }
    }
    assert!(n >= 10, "{n} inputs");
}
