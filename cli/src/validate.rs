//! `coagula validate`: rerun the reproduction cases and compare with references.

use coagula_core::exact::Exact;
use coagula_core::kernel::{Coagulation, CoagulationKernel};
use coagula_core::observe::{Replicas, moment_of_counts};
use coagula_core::observe::{TEST_ALPHA, student_t_threshold};
use coagula_core::scheme::Scheme;
use coagula_core::scheme::lowrank::{AcceptanceRejection, Bucketed, Inverse, LowRank};
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;
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

#[derive(Clone, Copy)]
enum Method {
    LowRank,
    Bucketed,
    Rejection,
    Inverse,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::LowRank => "lowrank",
            Method::Bucketed => "lowrank-bucketed",
            Method::Rejection => "rejection",
            Method::Inverse => "inverse",
        }
    }
}

/// `(n_1, M0)` at time t from `n0` monomers, one replica.
fn one<K: CoagulationKernel + Copy, const R: usize, const W: usize>(
    method: Method,
    k: K,
    n0: u64,
    t: f64,
    seed: u64,
) -> (f64, f64) {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let (counts, v) = match method {
        Method::LowRank => {
            let mut s = LowRank::<K, R>::monodisperse(k, n0).expect("valid");
            s.advance_to(t, &mut rng).expect("runs");
            (s.counts().to_vec(), s.volume())
        }
        Method::Bucketed => {
            let mut s = Bucketed::<K, R, W>::monodisperse(k, n0).expect("valid");
            s.advance_to(t, &mut rng).expect("runs");
            (s.counts(), s.volume())
        }
        Method::Rejection => {
            let mut s = AcceptanceRejection::monodisperse(k, n0).expect("valid");
            s.advance_to(t, &mut rng).expect("runs");
            (s.counts(), s.volume())
        }
        Method::Inverse => {
            let mut s = Inverse::monodisperse(k, n0).expect("valid");
            s.advance_to(t, &mut rng).expect("runs");
            (s.counts(), s.volume())
        }
    };
    (
        counts.first().copied().unwrap_or(0) as f64 / v,
        moment_of_counts(&counts, v, 0.0),
    )
}

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
        for method in [
            Method::LowRank,
            Method::Bucketed,
            Method::Rejection,
            Method::Inverse,
        ] {
            let vals: Vec<(f64, f64)> = (0..reps)
                .into_par_iter()
                .map(|s| one::<_, 1, 2>(method, k, n0, t, s * 7919 + 1))
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
                        method.name(),
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
            let mut rng = Pcg64Mcg::new(99);
            let n0 = 10_000_000;
            let fm = Coagulation::free_molecular()
                .with_min_size(1.0)
                .expect("valid");
            for bucketed in [false, true] {
                let events = match (name, bucketed) {
                    ("brownian", false) => {
                        let mut s = LowRank::<_, 2>::monodisperse(Coagulation::brownian(), n0)
                            .expect("valid");
                        s.advance_to(t, &mut rng).expect("runs").events
                    }
                    ("brownian", true) => {
                        let mut s = Bucketed::<_, 2, 4>::monodisperse(Coagulation::brownian(), n0)
                            .expect("valid");
                        s.advance_to(t, &mut rng).expect("runs").events
                    }
                    ("ballistic", false) => {
                        let mut s = LowRank::<_, 3>::monodisperse(fm, n0).expect("valid");
                        s.advance_to(t, &mut rng).expect("runs").events
                    }
                    ("ballistic", true) => {
                        let mut s = Bucketed::<_, 3, 6>::monodisperse(fm, n0).expect("valid");
                        s.advance_to(t, &mut rng).expect("runs").events
                    }
                    (_, false) => {
                        let mut s = LowRank::<_, 1>::monodisperse(Coagulation::additive(), n0)
                            .expect("valid");
                        s.advance_to(t, &mut rng).expect("runs").events
                    }
                    (_, true) => {
                        let mut s = Bucketed::<_, 1, 2>::monodisperse(Coagulation::additive(), n0)
                            .expect("valid");
                        s.advance_to(t, &mut rng).expect("runs").events
                    }
                } as f64;
                let tol = 0.05 * 10f64.powf(paper.log10().floor());
                let method = if bucketed {
                    "lowrank-bucketed"
                } else {
                    "lowrank"
                };
                out.push(Case {
                    case: format!("osinsky2023/{method}-{name}-table-t={t}"),
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
