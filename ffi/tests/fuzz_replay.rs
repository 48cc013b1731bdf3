//! The CI smoke run of the C-ABI fuzz targets (`fuzz/`): every input of their committed
//! corpora and every crash reproducer under `fuzz/regressions/` runs through the
//! target's own code (the same functions `cargo fuzz` drives, without libFuzzer's
//! mutation and instrumentation). The campaigns themselves run with
//! `fuzz/campaign.sh` (docs/design/fuzzing.md).

#[path = "../../fuzz/src/lib.rs"]
#[allow(dead_code)]
mod fuzz;

use std::path::{Path, PathBuf};

/// The files of `fuzz/{corpus,regressions}/<target>/`, sorted.
fn inputs(target: &str) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut files = Vec::new();
    for dir in ["corpus", "regressions"] {
        if let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) {
            files.extend(entries.filter_map(|e| e.ok()).map(|e| e.path()));
        }
    }
    files.sort();
    files
}

#[test]
fn checkpoint_restore_corpus_and_regressions() {
    let files = inputs("checkpoint_restore");
    assert!(files.len() >= 30, "{} inputs", files.len());
    for f in files {
        fuzz::checkpoint_restore(&std::fs::read(&f).unwrap());
    }
}

/// The committed seeds are checkpoints of today's format: were they stale, every
/// count-scheme seed would be refused at its configuration record and a campaign would
/// never reach the state's own validation (as happened once, unnoticed, for 5 · 10^6
/// executions at half the coverage).
#[test]
fn checkpoint_restore_seeds_are_current() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/checkpoint_restore");
    let seeds = fuzz::seeds();
    assert_eq!(seeds.len(), 6 * (fuzz::kinds() + 1) + 2);
    for (name, data) in seeds {
        let committed = std::fs::read(dir.join(&name)).unwrap_or_default();
        assert!(
            committed == data,
            "{name} is stale: regenerate with `cargo run --bin seed_corpus corpus/checkpoint_restore` in fuzz/"
        );
    }
}

#[test]
fn langevin_restore_corpus_and_regressions() {
    let files = inputs("langevin_restore");
    assert!(files.len() >= 24, "{} inputs", files.len());
    for f in files {
        fuzz::langevin_restore(&std::fs::read(&f).unwrap());
    }
}

/// The committed Langevin seeds are checkpoints of today's format.
#[test]
fn langevin_restore_seeds_are_current() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/langevin_restore");
    for (name, data) in fuzz::langevin_seeds() {
        let committed = std::fs::read(dir.join(&name)).unwrap_or_default();
        assert!(
            committed == data,
            "{name} is stale: regenerate with `cargo run --bin seed_corpus corpus/langevin_restore langevin` in fuzz/"
        );
    }
}

#[test]
fn call_sequence_corpus_and_regressions() {
    let files = inputs("call_sequence");
    assert!(files.len() >= 10, "{} inputs", files.len());
    for f in files {
        fuzz::call_sequence::run(&std::fs::read(&f).unwrap());
    }
}
