//! The regime sweep: every size-count scheme from N0 = 32, 100, 1000 and 10^5 monomers
//! in count vectors much longer than N0 (so M ≫ N0 from the start, the case where the
//! bucketed layout once lost its slot bookkeeping), run through at least six particle
//! doublings, against the per-size tree layout (Welch) and, at N0 = 10^5, against the
//! exact Smoluchowski solution (whose O(1/N) offset is far below the standard error
//! there). The inverse method costs O(N) per event, 10^10 operations per replica at
//! N0 = 10^5 with the additive kernel (three minutes of CI): it runs the three smaller
//! cases here, the finite-N reference in `finite_n.rs`, and the exact solutions at
//! N0 = 32768 in `coagula validate`. A property test runs every scheme over random small systems and checks the
//! invariants that hold for every run: mass conserved up to doubling, no particle lost,
//! the same seed giving the same state.

use crate::common;

use crate::common::{LABELS, Sim, mass, z_max};
use coagula_core::exact::Exact;
use coagula_core::kernel::Coagulation;
use coagula_core::observe::Replicas;
use coagula_core::scheme::facade::{SchemeId, State};
use proptest::prelude::*;
use rand_pcg::Pcg64Mcg;

/// (N0, length of the count vector, replicas).
const CASES: [(u64, usize, u64); 4] = [
    (32, 4096, 2000),
    (100, 8192, 1000),
    (1000, 1 << 16, 200),
    (100_000, 1 << 20, 8),
];

type Stats = Vec<[Replicas; 3]>;

/// Every size-count scheme of the registry on one case: (name, stats).
fn run_all(
    kernel: Coagulation,
    (n0, len, reps): (u64, usize, u64),
    times: &[f64],
) -> Vec<(&'static str, Stats)> {
    let mut init = vec![0u64; len];
    init[0] = n0;
    let v = n0 as f64;
    let init = &init;
    common::count_schemes()
        .enumerate()
        .filter(|(_, info)| n0 < 100_000 || info.name != "inverse")
        .filter_map(|(i, info)| {
            common::build(info, kernel, init, v)?;
            let start = std::time::Instant::now();
            let st = common::facade_replicas(11 + i as u64, reps, times, || {
                common::build(info, kernel, init, v).unwrap()
            });
            eprintln!(
                "N0 {n0} len {len} {}: {:.2} s",
                info.name,
                start.elapsed().as_secs_f64()
            );
            Some((info.name, st))
        })
        .collect()
}

/// Compares the schemes of each case with the tree layout (Welch, degrees of freedom
/// at least R − 1) and, at N0 = 10^5, every scheme with `exact`.
fn sweep(name: &str, kernel: Coagulation, exact: Exact, times: &[f64]) {
    let mut failures = String::new();
    for case in CASES {
        let runs = run_all(kernel, case, times);
        let (n0, _, reps) = case;
        let expected = if n0 < 100_000 { 6 } else { 5 };
        assert!(runs.len() >= expected, "every size-count scheme ran");
        let z = z_max(reps);
        let tree = &runs
            .iter()
            .find(|(n, _)| *n == "lowrank-tree")
            .expect("the tree layout is registered")
            .1;
        for (scheme, stats) in &runs {
            for (ti, &t) in times.iter().enumerate() {
                for q in 0..3 {
                    let (a, b) = (&tree[ti][q], &stats[ti][q]);
                    // (direct simulation over counts does not double: its small-N law
                    // is the plain Marcus–Lushnikov process, checked against its exact
                    // master equation in finite_n.rs, not the doubling tree's)
                    if *scheme != "lowrank-tree" && *scheme != "dsa-counts" {
                        let se = (a.std_error().powi(2) + b.std_error().powi(2)).sqrt();
                        let d = b.mean() - a.mean();
                        if d.abs() > z * se + 1e-15 {
                            failures.push_str(&format!(
                                "{name} N0={n0} {scheme} t={t} {}: {} vs tree {} ({:.1} SE > {z:.2})\n",
                                LABELS[q],
                                b.mean(),
                                a.mean(),
                                d / se
                            ));
                        }
                    }
                    if n0 == 100_000 {
                        let e = match q {
                            0 => exact.moment(0, t).unwrap(),
                            _ => exact.number_density(q as u64, t).unwrap(),
                        };
                        let zz = (b.mean() - e) / b.std_error();
                        if zz.is_nan() || zz.abs() > z {
                            failures.push_str(&format!(
                                "{name} N0={n0} {scheme} t={t} {}: {} vs exact {e} ({zz:.1} SE > {z:.2})\n",
                                LABELS[q],
                                b.mean()
                            ));
                        }
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures}");
}

/// Constant kernel to t = 130: N/V ≈ 2/(2 + t) = 1/66, six doublings or more.
#[test]
fn constant_kernel_regime_sweep() {
    sweep(
        "constant",
        Coagulation::constant(1.0).unwrap(),
        Exact::constant(1.0).unwrap(),
        &[2.0, 20.0, 130.0],
    );
}

/// Additive kernel to t = 4.5: N/V = e^{-t} = 1/90, six doublings or more, sizes
/// growing towards the count vector's end.
#[test]
fn additive_kernel_regime_sweep() {
    sweep(
        "additive",
        Coagulation::additive(),
        Exact::additive(),
        &[0.5, 2.0, 4.5],
    );
}

/// Runs scheme `id` to `t` twice with the same seed, through the facade; checks the
/// invariants of a run (skips a scheme the kernel cannot drive).
fn invariants(
    id: SchemeId,
    k: Coagulation,
    init: &[u64],
    v: f64,
    t: f64,
    seed: u64,
    mass0: u64,
) -> Result<(), TestCaseError> {
    if common::build(id, k, init, v).is_none() {
        return Ok(());
    }
    let run = || {
        let mut s = common::build(id, k, init, v).unwrap();
        let mut rng = <Pcg64Mcg as rand_pcg::rand_core::SeedableRng>::seed_from_u64(seed);
        let rep = s.advance_to(t, &mut rng);
        (s, rep)
    };
    let counts = |s: &Sim| match s.state() {
        State::Counts(c, _) => c.into_owned(),
        State::Sizes(_) => unreachable!("a size-count scheme"),
    };
    let (a, ra) = run();
    let (b, rb) = run();
    let ra = ra.map_err(|e| TestCaseError::fail(format!("{e}")))?;
    prop_assert_eq!(Ok(ra), rb, "same seed, same report");
    let (ca, cb) = (counts(&*a), counts(&*b));
    prop_assert_eq!(&ca, &cb, "same seed, same counts");
    prop_assert_eq!(a.time(), t);
    let m = mass(&ca);
    prop_assert!(
        m.is_multiple_of(mass0) && (m / mass0).is_power_of_two(),
        "mass {} from {}",
        m,
        mass0
    );
    prop_assert!(ca.iter().sum::<u64>() >= 1);
    prop_assert_eq!(1u64 << ra.doublings, m / mass0);
    prop_assert_eq!(a.particles(), ca.iter().sum::<u64>());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random small systems (up to 40 sizes, up to 30 particles each), one of three
    /// kernels, a random end time and seed: every scheme runs, conserves mass up to
    /// doubling (the report's doublings say by how much) and is deterministic.
    #[test]
    fn random_small_systems_keep_their_invariants(
        init in proptest::collection::vec(0u64..30, 1..40),
        kernel in 0usize..3,
        t in 0.0f64..3.0,
        seed in any::<u64>(),
    ) {
        let mut init = init;
        if init.iter().sum::<u64>() < 2 {
            init[0] += 2;
        }
        let v = init.iter().sum::<u64>() as f64;
        let mass0 = mass(&init);
        let init = &init;
        let (k, t) = match kernel {
            0 => (Coagulation::constant(1.0).unwrap(), t),
            1 => (Coagulation::additive(), t / 20.0),
            _ => (Coagulation::brownian(), t),
        };
        for info in common::count_schemes() {
            invariants(info, k, init, v, t, seed, mass0)?;
        }
    }
}
