//! The exact solutions on every size-count scheme of the registry (constant, additive
//! and multiplicative kernels from monomers: n_1..n_4 and M0 within the replicas'
//! standard errors), and the schemes' agreement where no solution is known.

use coagula_core::exact::Exact;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::Replicas;
use coagula_core::scheme::facade::{Init, Model, Options, SchemeId, Simulation};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;

const REPLICAS: u64 = 16;
const N0: u64 = 1 << 13;

/// Tolerance in standard errors, from 16 replicas' own SE: Student t with 15 degrees of
/// freedom at the suite's two-sided false-alarm rate per comparison (`t = 7.90`). A
/// wrong rate (factor 2) is still off by tens of SE.
fn z() -> f64 {
    coagula_core::observe::student_t_threshold(coagula_core::observe::TEST_ALPHA, REPLICAS - 1)
}

/// The same for a Welch comparison of two 16-replica means (Welch–Satterthwaite
/// degrees of freedom are at least 15).
fn z2() -> f64 {
    z()
}

use crate::common::count_schemes;

/// Runs R replicas of scheme `id` (through the registry's facade) to each time in
/// `times`, and returns for each time the replica statistics of `n_1..n_kmax` (index
/// 0..kmax) followed by M0 and M2.
fn run(id: SchemeId, kernel: Coagulation, times: &[f64], kmax: usize) -> Vec<Vec<Replicas>> {
    let mut stats = vec![vec![Replicas::new(); kmax + 2]; times.len()];
    let tag = id.tag as u128;
    for rep in 0..REPLICAS {
        let mut rng = Pcg64Mcg::new(
            0x1234_5678_9abc_def0 ^ (rep as u128 * 0x9e37_79b9_7f4a_7c15) ^ (tag << 100),
        );
        let init = Init::Counts {
            counts: &[N0],
            volume: N0 as f64,
        };
        let mut s: Box<dyn Simulation<_, _, Pcg64Mcg>> = registry::build(
            id,
            Model::coagulation(kernel, NoFragmentation),
            &init,
            &Options::default(),
        )
        .unwrap();
        for (ti, &t) in times.iter().enumerate() {
            s.advance_to(t, &mut rng).unwrap();
            for k in 1..=kmax {
                stats[ti][k - 1].push(s.number_density(k as f64));
            }
            stats[ti][kmax].push(s.moment(0.0));
            stats[ti][kmax + 1].push(s.moment(2.0));
        }
    }
    stats
}

fn within(name: &str, r: &Replicas, exact: f64, failures: &mut String) {
    let se = r.std_error();
    let err = (r.mean() - exact).abs();
    // a floor for quantities whose spread is zero at this N (e.g. tiny n_k)
    let tol = z() * se + 1e-12;
    if err > tol {
        failures.push_str(&format!(
            "{name}: mean {} exact {exact} |err| {err:.3e} > {:.2} SE = {tol:.3e}\n",
            r.mean(),
            z()
        ));
    }
}

fn check_exact(kernel: Coagulation, exact: Exact, times: &[f64]) {
    let kmax = 4;
    let mut failures = String::new();
    for method in count_schemes() {
        let stats = run(method, kernel, times, kmax);
        for (ti, &t) in times.iter().enumerate() {
            for k in 1..=kmax {
                let e = exact.number_density(k as u64, t).unwrap();
                within(
                    &format!("{} {exact:?} t={t} n_{k}", method.name),
                    &stats[ti][k - 1],
                    e,
                    &mut failures,
                );
            }
            let e = exact.moment(0, t).unwrap();
            within(
                &format!("{} {exact:?} t={t} M0", method.name),
                &stats[ti][kmax],
                e,
                &mut failures,
            );
        }
    }
    assert!(failures.is_empty(), "{failures}");
}

#[test]
fn constant_kernel_matches_exact_solution() {
    check_exact(
        Coagulation::constant(1.0).unwrap(),
        Exact::constant(1.0).unwrap(),
        &[0.5, 2.0, 6.0],
    );
}

#[test]
fn additive_kernel_matches_exact_solution() {
    // t = 1.5: N has fallen below N0/2 at t = ln 2, so particle doubling is exercised
    check_exact(Coagulation::additive(), Exact::additive(), &[0.3, 1.5]);
}

#[test]
fn multiplicative_kernel_matches_exact_solution_before_gelation() {
    check_exact(
        Coagulation::multiplicative(),
        Exact::multiplicative(),
        &[0.4, 0.8],
    );
}

/// Brownian (R = 2, exact bound) and ballistic (R = 3, thinning) have no exact
/// solution: the three methods must agree (Welch statistic below `z2()`).
#[test]
fn methods_agree_for_brownian_and_ballistic_kernels() {
    fn compare(kernel: Coagulation, times: &[f64], failures: &mut String) {
        let kmax = 3;
        let lr = run(registry::find("lowrank-tree").unwrap(), kernel, times, kmax);
        for other in count_schemes().filter(|&s| s.name != "lowrank-tree") {
            let st = run(other, kernel, times, kmax);
            for ti in 0..times.len() {
                for q in 0..kmax + 2 {
                    let (a, b) = (&lr[ti][q], &st[ti][q]);
                    let se =
                        libm::sqrt(a.std_error() * a.std_error() + b.std_error() * b.std_error());
                    let d = (a.mean() - b.mean()).abs();
                    if d > z2() * se + 1e-12 {
                        failures.push_str(&format!(
                            "lowrank-tree vs {} t={} quantity {q}: {} vs {} (diff {d:.3e} > {:.2} SE {se:.3e})\n",
                            other.name,
                            times[ti],
                            a.mean(),
                            b.mean(),
                            z2()
                        ));
                    }
                }
            }
        }
    }
    let mut failures = String::new();
    compare(Coagulation::brownian(), &[1.0, 4.0], &mut failures);
    compare(
        Coagulation::free_molecular().with_min_size(1.0).unwrap(),
        &[1.0, 3.0],
        &mut failures,
    );
    assert!(failures.is_empty(), "{failures}");
}

/// Acceptance–rejection needs the kernel's supremum (Osinsky 2023 §2): a kernel
/// without one is refused at construction, not run on a wrong bound.
#[test]
fn rejection_refuses_a_kernel_without_a_supremum() {
    let no_sup = |x: f64, y: f64| x + y;
    assert!(coagula_core::scheme::baseline::AcceptanceRejection::monodisperse(no_sup, 10).is_err());
}
