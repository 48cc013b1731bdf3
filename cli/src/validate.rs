//! `coagula validate`: rerun the reproduction cases and compare with references.

use crate::options;
use coagula_core::exact::Exact;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::Replicas;
use coagula_core::observe::{TEST_ALPHA, student_t_threshold};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::registry::{self, Init, SchemeId, Simulation};
use rayon::prelude::*;
use serde::Serialize;

/// One line of the validation table.
#[derive(Clone, Debug, Serialize)]
pub struct Case {
    pub case: String,
    pub quantity: String,
    pub reference: f64,
    pub value: f64,
    pub error: f64,
    pub tolerance: f64,
    pub pass: bool,
}

/// Runs every case (a subset with `quick`), prints a table or JSON, and returns whether
/// all passed.
pub fn run(quick: bool, json: bool) -> bool {
    let start = std::time::Instant::now();
    let mut cases = Vec::new();
    crate::lecot::cases(quick, &mut cases);
    osinsky_cases(quick, &mut cases);
    let all = cases.iter().all(|c| c.pass);
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&cases).expect("cases serialise")
        );
    } else {
        println!(
            "{:<44} {:<78} {:>13} {:>13} {:>10} {:>10} {:>5}",
            "case", "quantity", "reference", "ours", "error", "tolerance", "pass"
        );
        for c in &cases {
            println!(
                "{:<44} {:<78} {:>13.6e} {:>13.6e} {:>10.2e} {:>10.2e} {:>5}",
                c.case,
                c.quantity,
                c.reference,
                c.value,
                c.error,
                c.tolerance,
                if c.pass { "pass" } else { "FAIL" }
            );
        }
        let failed = cases.iter().filter(|c| !c.pass).count();
        println!(
            "\nvalidate: {} passed, {failed} failed ({:.0} s)",
            cases.len() - failed,
            start.elapsed().as_secs_f64()
        );
    }
    all
}

/// `(n_1, M0)` at time t from `n0` monomers, one replica of scheme `id`.
fn one(id: SchemeId, k: Coagulation, n0: u64, t: f64, seed: u64) -> (f64, f64) {
    let mut rng = generator(seed, 0);
    let init = Init::Counts {
        counts: &[n0],
        volume: n0 as f64,
    };
    let mut s: Box<Sim> =
        registry::build(id, k, NoFragmentation, &init, &options()).expect("valid");
    s.advance_to(t, &mut rng).expect("runs");
    (s.number_density(1.0), s.moment(0.0))
}

/// The facade as the CLI instantiates it.
type Sim = dyn Simulation<Coagulation, NoFragmentation, Generator>;

fn osinsky_cases(quick: bool, out: &mut Vec<Case>) {
    let n0: u64 = if quick { 1 << 13 } else { 1 << 16 };
    let reps = 16u64;
    let setups: [(&str, Coagulation, Exact, f64); 3] = [
        (
            "constant",
            Coagulation::constant(1.0).expect("valid"),
            Exact::constant(1.0).expect("valid"),
            2.0,
        ),
        ("additive", Coagulation::additive(), Exact::additive(), 1.5),
        (
            "multiplicative",
            Coagulation::multiplicative(),
            Exact::multiplicative(),
            0.8,
        ),
    ];
    for (name, k, e, t) in setups {
        let counts = Init::Counts {
            counts: &[1],
            volume: 1.0,
        };
        for info in registry::SCHEMES.iter().filter(|s| s.accepts(&counts)) {
            let vals: Vec<(f64, f64)> = (0..reps)
                .into_par_iter()
                .map(|s| one(info.id, k, n0, t, s * 7919 + 1))
                .collect();
            for (q, idx, exact) in [
                ("n_1", 0, e.number_density(1, t).expect("valid")),
                ("M0", 1, e.moment(0, t).expect("valid")),
            ] {
                let mut r = Replicas::new();
                for v in &vals {
                    r.push(if idx == 0 { v.0 } else { v.1 });
                }
                // Student t on the replicas' own SE, at the suite's false-alarm rate
                let z = student_t_threshold(TEST_ALPHA, r.count() - 1);
                let tol = z * r.std_error();
                out.push(Case {
                    case: format!(
                        "osinsky2023/{}-{name}-N0=2^{}",
                        info.name,
                        n0.trailing_zeros()
                    ),
                    quantity: format!(
                        "{q}(t={t}), {reps} replicas (reference: exact; tol {z:.2} SE)"
                    ),
                    reference: exact,
                    value: r.mean(),
                    error: (r.mean() - exact).abs(),
                    tolerance: tol,
                    pass: (r.mean() - exact).abs() <= tol,
                });
            }
        }
    }
    if !quick {
        // the paper's workloads that fit: collisions from 1e7 monomers (2 significant
        // digits in the paper, so the tolerance is half a unit in the last digit)
        let rows: [(&str, f64, f64); 3] = [
            ("brownian", 10.0, 2.3e7),
            ("ballistic", 1.0, 1.1e7),
            ("linear", 1.0, 7.6e6),
        ];
        for (name, t, paper) in rows {
            let n0 = 10_000_000;
            let k = crate::bench::paper_kernel(name);
            let init = Init::Counts {
                counts: &[n0],
                volume: n0 as f64,
            };
            for id in [SchemeId::LowRankTree, SchemeId::LowRank] {
                let mut rng = generator(99, 0);
                let mut s: Box<Sim> =
                    registry::build(id, k, NoFragmentation, &init, &options()).expect("valid");
                let events = s.advance_to(t, &mut rng).expect("runs").events as f64;
                let tol = 0.05 * 10f64.powf(paper.log10().floor());
                out.push(Case {
                    case: format!("osinsky2023/{}-{name}-table-t={t}", id.name()),
                    quantity: "collisions from 1e7 monomers (reference: paper, 2 digits)".into(),
                    reference: paper,
                    value: events,
                    error: (events - paper).abs(),
                    tolerance: tol,
                    pass: (events - paper).abs() <= tol,
                });
            }
        }
    }
}
