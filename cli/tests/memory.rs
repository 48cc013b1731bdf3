//! The memory a run says it will hold is within a factor 2 of what it held: the
//! estimate printed before the run (`memory_estimate` in the JSON) against the
//! process's peak resident memory less its resident memory before the run, on runs
//! that hold at least 16 MiB (below that the process's own threads and allocator
//! dominate). One run per way the estimate is made: the exact solution's moments with
//! particle doubling, past a gel point, the mean-field mean size (of a kernel and of a
//! temperature model), a scheme without doubling, and the tree, inverse and mass-flow
//! layouts.
//! Figures: docs/results/memory-estimate.md.

mod common;

use common::{coagula, json_of};

/// A scenario file of `kernel` from `particles` monomers to `t` (one replica).
fn monomers(kernel: &str, particles: u64, t: f64) -> std::path::PathBuf {
    let path = std::env::temp_dir().join(format!(
        "coagula-memory-{kernel}-{particles}-{t}-{}.toml",
        std::process::id()
    ));
    std::fs::write(
        &path,
        format!(
            "[kernel]\nkind = \"{kernel}\"\n[initial]\nkind = \"monodisperse\"\nparticles = {particles}\n[scheme]\nname = \"lowrank\"\n[output]\ntimes = [{t:?}]\nobservables = [\"M0\"]\n[run]\nreplicas = 1\n"
        ),
    )
    .unwrap();
    path
}

/// Runs `args` and checks the estimate against the memory held.
fn within_two(args: &[&str]) {
    let out = coagula()
        .args(args)
        .args(["--quiet", "--threads", "1", "--json", "-"])
        .output()
        .unwrap();
    let j = json_of(&out);
    let estimate = j["memory_estimate"].as_f64().unwrap();
    let (before, peak) = (j["resident_before"].as_f64(), j["resident_peak"].as_f64());
    if cfg!(target_os = "linux") {
        let held = peak.expect("Linux reports the peak") - before.unwrap();
        assert!(held >= 16.0 * 1048576.0, "{args:?}: held only {held} bytes");
        let ratio = estimate / held;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "{args:?}: estimated {estimate} bytes ({}), held {held}: ratio {ratio}",
            j["memory_basis"]
        );
    } else {
        assert!(estimate > 0.0);
    }
}

#[test]
fn the_estimate_from_the_exact_moments_is_within_two() {
    within_two(&[
        "run",
        "quickstart-golovin",
        "--replicas",
        "1",
        "--set",
        "output.t-end=5",
    ]);
}

#[test]
fn the_estimate_past_a_gel_point_counts_the_gel() {
    within_two(&[
        "run",
        "multiplicative-gelation",
        "--replicas",
        "1",
        "--particles",
        "200000",
    ]);
}

#[test]
fn the_mean_field_estimate_is_within_two() {
    within_two(&[
        "run",
        "osinsky2023-table1-brownian",
        "--particles",
        "2000000",
    ]);
}

#[test]
fn the_estimate_of_a_scheme_without_doubling_is_within_two() {
    let f = monomers("additive", 1_000_000, 8.0);
    within_two(&["run", f.to_str().unwrap(), "--scheme", "dsa-counts"]);
    std::fs::remove_file(f).ok();
}

#[test]
fn the_estimates_of_the_tree_and_inverse_layouts_are_within_two() {
    let f = monomers("constant", 1_000_000, 1e5);
    within_two(&["run", f.to_str().unwrap(), "--scheme", "lowrank-tree"]);
    std::fs::remove_file(f).ok();
    let f = monomers("additive", 20_000, 6.0);
    within_two(&["run", f.to_str().unwrap(), "--scheme", "inverse"]);
    std::fs::remove_file(f).ok();
}

#[test]
fn the_temperature_estimate_is_within_two() {
    // the closed-form model, where aggregation keeps the temperature per unit size
    let path =
        std::env::temp_dir().join(format!("coagula-memory-temp-{}.toml", std::process::id()));
    std::fs::write(
        &path,
        "[kernel]\nkind = \"temperature-closed-form\"\n[initial]\nkind = \"monodisperse\"\nparticles = 1000000\ntemperature = 1.0\n[scheme]\nname = \"temperature\"\n[output]\ntimes = [100000.0]\nobservables = [\"M0\"]\n[run]\nreplicas = 1\n",
    )
    .unwrap();
    within_two(&["run", path.to_str().unwrap()]);
    std::fs::remove_file(path).ok();
}

#[test]
fn a_particle_scheme_holds_what_it_started_with() {
    within_two(&[
        "run",
        "constant-exponential-massflow",
        "--m",
        "19",
        "--replicas",
        "1",
        "--dt",
        "0.05",
    ]);
}
