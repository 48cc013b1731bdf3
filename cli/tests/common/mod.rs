//! Helpers shared by the `coagula` binary's end-to-end tests.
#![allow(dead_code)]

use std::process::Command;

/// The binary under test.
pub fn coagula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_coagula"))
}

/// The example scenarios of `examples/`, sorted.
pub fn examples() -> Vec<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    assert!(v.len() >= 8, "examples/ has the scenarios");
    v
}

/// The JSON a successful run printed on standard output.
pub fn json_of(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON on standard output")
}

/// Asserts a run succeeded, showing its standard error if not.
pub fn succeeded(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
