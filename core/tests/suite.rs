//! The integration tests of coagula-core, one module per file, in one test binary: the
//! schemes' generic code is then compiled (at the test profile's opt-level) once
//! instead of once per file — most of CI's test build when each file was its own
//! binary. `no_alloc.rs` stays a binary of its own: it installs a counting global
//! allocator.

mod common;

#[path = "blocks.rs"]
mod blocks;
#[path = "checkpoint.rs"]
mod checkpoint;
#[path = "classes.rs"]
mod classes;
#[path = "conformance.rs"]
mod conformance;
#[path = "count_schemes.rs"]
mod count_schemes;
#[path = "dsmc.rs"]
mod dsmc;
#[path = "finite_n.rs"]
mod finite_n;
#[path = "finite_n_product.rs"]
mod finite_n_product;
#[path = "fuzz_findings.rs"]
mod fuzz_findings;
#[path = "growth.rs"]
mod growth;
#[path = "host_control.rs"]
mod host_control;
#[path = "kernel_bounds.rs"]
mod kernel_bounds;
#[path = "no_panic.rs"]
mod no_panic;
#[path = "particle_sizes.rs"]
mod particle_sizes;
#[path = "processes.rs"]
mod processes;
#[path = "processes_massflow.rs"]
mod processes_massflow;
#[path = "regime_sweep.rs"]
mod regime_sweep;
#[path = "regressions.rs"]
mod regressions;
#[path = "review_findings.rs"]
mod review_findings;
#[path = "source_function.rs"]
mod source_function;
#[path = "temperature.rs"]
mod temperature;
#[path = "value_stability.rs"]
mod value_stability;
