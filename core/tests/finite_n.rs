//! The exact finite-N reference: the master equation of the Marcus–Lushnikov process
//! *with the particle-doubling rule*, for N0 = V = 32 monomers, solved by
//! uniformisation; every size-count scheme of the registry, and low-rank over particle
//! sizes (`lowrank-sizes`), must reproduce its E[N/V], E[N1/V] and
//! E[N2/V] within the suite's family-wise tolerance over 6000 replicas. The scheme
//! without doubling (`dsa-counts`, and `dsa` over particles) is checked against the same
//! master equation without the doubling rule: the plain Marcus–Lushnikov process.
//!
//! The large-N exact solutions cannot see O(1/N) errors (a wrong same-particle rule, a
//! doubling applied at the wrong moment, a rate off by N/(N−1)); at N = 32 such an
//! error moves these expectations by ~3 %, i.e. by many standard errors: with 6000
//! replicas the standard error of N/V at t = 2 is 0.17 % of it (a 3 % shift is 18 SE
//! against a threshold of 4.9), that of N2/V 0.6 % (its 3.2 % finite-N offset alone is
//! 5.5 SE).
//!
//! **Why (N, N1, N2, d) is a Markov chain.** Every unordered pair of distinct particles
//! coagulates at rate K(x, y)/V. For the constant and the additive kernel the rates of
//! the pair classes (1,1), (1,2), (1,≥3), (2,2), (2,≥3), (≥3,≥3) depend only on
//! N, N1, N2 and the total mass M (for K = x + y the sums over the class ≥3 need only
//! its count N − N1 − N2 and its mass M − N1 − 2N2), and the doubling rule — when fewer
//! than N0/2 particles remain, every count and V double — depends only on N. With
//! d doublings so far, V = M = 32 · 2^d.

use crate::common;

use coagula_core::kernel::Coagulation;
use coagula_core::kernel::NoFragmentation;
use coagula_core::observe::Replicas;
use coagula_core::scheme::facade::{Init, Model, Options, SchemeId};
use coagula_core::scheme::registry;
use std::collections::HashMap;

const N0: u64 = 32;
const REPLICAS: u64 = 6_000;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Constant,
    Additive,
}

/// State (N, N1, N2, d).
type State = (u64, u64, u64, u32);

/// The most doublings the state space holds (t ≤ 30 for the constant kernel, N/V ≈
/// 2/(2 + t), needs 4; t ≤ 8 for the additive one, N/V ≈ e^{-t}, about 12).
fn dmax(kind: Kind) -> u32 {
    match kind {
        Kind::Constant => 14,
        Kind::Additive => 26,
    }
}

/// The outgoing transitions of a state: (target, rate).
fn transitions(kind: Kind, (n, n1, n2, d): State, doubling: bool) -> Vec<(State, f64)> {
    let v = (N0 << d) as f64;
    let m = N0 << d; // total mass
    let nr = n - n1 - n2;
    let mr = (m - n1 - 2 * n2) as f64;
    let (n1f, n2f, nrf) = (n1 as f64, n2 as f64, nr as f64);
    let pairs = |a: f64| a * (a - 1.0) / 2.0;
    // (class rates, effect on (N1, N2))
    let classes: [(f64, i64, i64); 6] = match kind {
        Kind::Constant => [
            (pairs(n1f), -2, 1),
            (n1f * n2f, -1, -1),
            (n1f * nrf, -1, 0),
            (pairs(n2f), 0, -2),
            (n2f * nrf, 0, -1),
            (pairs(nrf), 0, 0),
        ],
        Kind::Additive => [
            (pairs(n1f) * 2.0, -2, 1),
            (n1f * n2f * 3.0, -1, -1),
            (n1f * (nrf + mr), -1, 0),
            (pairs(n2f) * 4.0, 0, -2),
            (n2f * (2.0 * nrf + mr), 0, -1),
            // Σ over pairs of the class ≥ 3 of (x + y) = (Nr − 1) Mr
            (if nr >= 2 { (nrf - 1.0) * mr } else { 0.0 }, 0, 0),
        ],
    };
    let mut out = Vec::new();
    for (rate, d1, d2) in classes {
        if rate <= 0.0 {
            continue;
        }
        let (mut t, mut t1, mut t2) = (n - 1, (n1 as i64 + d1) as u64, (n2 as i64 + d2) as u64);
        let mut td = d;
        if doubling && t < N0 / 2 {
            // particle doubling
            t *= 2;
            t1 *= 2;
            t2 *= 2;
            td += 1;
        }
        out.push(((t, t1, t2, td), rate / v));
    }
    out
}

/// The expectations `[E N/V, E N1/V, E N2/V]` at each of `times`, by uniformisation
/// of the master equation from N0 monomers (time split into pieces with Λ·Δt ≤ 20,
/// Poisson series cut where its tail is below 1e-16).
fn reference(kind: Kind, times: &[f64], doubling: bool) -> Vec<[f64; 3]> {
    // enumerate the reachable states
    let start: State = (N0, N0, 0, 0);
    let mut index: HashMap<State, usize> = HashMap::new();
    let mut states = vec![start];
    index.insert(start, 0);
    let mut edges: Vec<Vec<(usize, f64)>> = Vec::new();
    let mut i = 0;
    while i < states.len() {
        let s = states[i];
        let mut e = Vec::new();
        // states at the doubling cap are absorbing; their probability is checked
        if s.0 >= 2 && s.3 < dmax(kind) {
            for (t, r) in transitions(kind, s, doubling) {
                let j = *index.entry(t).or_insert_with(|| {
                    states.push(t);
                    states.len() - 1
                });
                e.push((j, r));
            }
        }
        edges.push(e);
        i += 1;
    }
    let out_rate: Vec<f64> = edges.iter().map(|e| e.iter().map(|x| x.1).sum()).collect();
    let lambda = out_rate.iter().copied().fold(0.0, f64::max) * 1.02;
    // the uniformised chain: stay with 1 − q_s/Λ, jump with r/Λ
    let stay: Vec<f64> = out_rate.iter().map(|q| 1.0 - q / lambda).collect();
    for e in &mut edges {
        for x in e.iter_mut() {
            x.1 /= lambda;
        }
    }
    let (mut term, mut next, mut acc) = (
        vec![0.0; states.len()],
        vec![0.0; states.len()],
        vec![0.0; states.len()],
    );
    let mut p = vec![0.0; states.len()];
    p[0] = 1.0;
    let mut now = 0.0;
    let mut results = Vec::new();
    for &t in times {
        while now < t {
            let dt = (t - now).min(20.0 / lambda);
            let a = lambda * dt;
            // Σ_k e^{−a} a^k/k! p P^k, P = I + Q/Λ; stop past the mode once the
            // weights are below 1e-18 (a ≤ 20: e^{-a} ≥ 2e-9, no underflow)
            term.copy_from_slice(&p);
            let mut weight = (-a).exp();
            for (x, y) in acc.iter_mut().zip(&term) {
                *x = y * weight;
            }
            let mut k = 0u32;
            while f64::from(k) < a || weight > 1e-18 {
                k += 1;
                next.fill(0.0);
                for (s, &ps) in term.iter().enumerate() {
                    if ps == 0.0 {
                        continue;
                    }
                    next[s] += ps * stay[s];
                    for &(j, r) in &edges[s] {
                        next[j] += ps * r;
                    }
                }
                core::mem::swap(&mut term, &mut next);
                weight *= a / f64::from(k);
                for (x, y) in acc.iter_mut().zip(&term) {
                    *x += y * weight;
                }
                assert!(k < 10_000, "uniformisation did not converge");
            }
            core::mem::swap(&mut p, &mut acc);
            now += dt;
        }
        let total: f64 = p.iter().sum();
        assert!((total - 1.0).abs() < 1e-10, "probability lost: {total}");
        let capped: f64 = states
            .iter()
            .zip(&p)
            .filter(|(s, _)| s.3 == dmax(kind))
            .map(|(_, &ps)| ps)
            .sum();
        assert!(
            capped < 1e-12,
            "{kind:?} t = {t}: doubling cap reached ({capped})"
        );
        let mut e = [0.0; 3];
        for (s, &ps) in states.iter().zip(&p) {
            let v = (N0 << s.3) as f64;
            e[0] += ps * s.0 as f64 / v;
            e[1] += ps * s.1 as f64 / v;
            e[2] += ps * s.2 as f64 / v;
        }
        results.push(e);
    }
    results
}

/// A particle scheme of the registry from `N0` particles of size 1 in volume `N0`.
fn sizes_sim(id: SchemeId, kernel: Coagulation) -> Box<common::Sim> {
    let sizes = [1.0; N0 as usize];
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    registry::build(
        id,
        Model::coagulation(kernel, NoFragmentation),
        &init,
        &Options::default(),
    )
    .unwrap()
}

/// The times scheme `name` is compared at. The block engine's count tree and
/// partition are dense in sizes (`docs/design/block-majorants.md`): with the additive
/// kernel at t = 8 the 32 particles reach sizes near 2^17, and each replica rebuilds
/// structures over 2^18 sizes about a dozen times — 77 s of the suite's CPU for 6000
/// replicas (2026-12-07), where t ≤ 5 takes 4.5 s and still takes a replica through
/// about seven doublings and up to six growth rebuilds (M from 64 to the total mass,
/// 32 · 2^7). So there the block engine's last time is
/// 5 instead of 8 (as many comparisons: docs/design/statistical-tests.md).
fn times_for(name: &str, kind: Kind, times: &[f64]) -> Vec<f64> {
    if name == "lowrank-blocks" && kind == Kind::Additive {
        let mut t: Vec<f64> = times.iter().map(|&t| t.min(5.0)).collect();
        t.dedup();
        t
    } else {
        times.to_vec()
    }
}

/// A scheme's replicas: its name, whether it doubles, its times and the statistics at
/// each.
type Run = (&'static str, bool, Vec<f64>, Vec<[Replicas; 3]>);

/// Compares every size-count scheme of the registry, low-rank over sizes and direct
/// simulation over particles with the reference; returns the
/// z-scores and the failures.
fn check(kind: Kind, kernel: Coagulation, times: &[f64]) -> (String, String) {
    // the reference at every time some scheme is compared at
    let mut all = times.to_vec();
    all.extend(times_for("lowrank-blocks", kind, times));
    all.sort_by(f64::total_cmp);
    all.dedup();
    let exact = reference(kind, &all, true);
    let plain = reference(kind, &all, false);
    // family-wise: every comparison at TEST_ALPHA (see observe::TEST_ALPHA)
    let z_max = common::z_max(REPLICAS);
    let mut report = String::new();
    let mut failures = String::new();
    let mut runs: Vec<Run> = common::count_schemes()
        .enumerate()
        .filter_map(|(i, info)| {
            common::build(info, kernel, &[N0], N0 as f64)?;
            let make = || common::build(info, kernel, &[N0], N0 as f64).unwrap();
            let times = times_for(info.name, kind, times);
            let stats = common::facade_replicas(i as u64 + 1, REPLICAS, &times, make);
            Some((info.name, info.name != "dsa-counts", times, stats))
        })
        .collect();
    assert!(runs.len() >= 6, "every size-count scheme ran");
    // the particle schemes from 32 particles of size 1 in volume 32: low-rank over sizes
    // doubles, direct simulation does not
    let offset = registry::SCHEMES.len() as u64;
    for (i, id) in [
        registry::find("lowrank-sizes").unwrap(),
        registry::find("dsa").unwrap(),
    ]
    .into_iter()
    .enumerate()
    {
        let make = || sizes_sim(id, kernel);
        runs.push((
            id.name,
            id.name == "lowrank-sizes",
            times.to_vec(),
            common::facade_replicas(offset + i as u64 + 1, REPLICAS, times, make),
        ));
    }
    for (name, doubles, times, stats) in &runs {
        let exact = if *doubles { &exact } else { &plain };
        for (&t, stats) in times.iter().zip(stats) {
            let at = all.iter().position(|&a| a == t).unwrap();
            for (q, label) in ["N/V", "N1/V", "N2/V"].iter().enumerate() {
                let st = &stats[q];
                let z = (st.mean() - exact[at][q]) / st.std_error();
                report.push_str(&format!(
                    "{kind:?} {name} t={t} {label}: mean {:.6} exact {:.6} z {z:+.2}\n",
                    st.mean(),
                    exact[at][q]
                ));
                if z.is_nan() || z.abs() >= z_max {
                    failures.push_str(&format!(
                        "{kind:?} {name} t={t} {label}: mean {} exact {} z {z:.2} beyond {z_max:.2}\n",
                        st.mean(),
                        exact[at][q]
                    ));
                }
            }
        }
    }
    (report, failures)
}

/// The reference itself: at N0 → ∞ it tends to the Smoluchowski solution, and at
/// N0 = 32 it already lies within 5 % of it (n_2 at t = 2 is 3.2 % high: the O(1/N)
/// effect the schemes are checked on; a solver with a wrong rate or a lost doubling
/// would be off by far more).
#[test]
fn reference_is_close_to_smoluchowski() {
    let e = reference(Kind::Constant, &[2.0], true);
    // N/V → 1/(1 + t/2) = 0.5, n_1 → 1/(1 + t/2)^2 = 0.25, n_2 → (t/2)/(1+t/2)^3 = 0.125
    for (got, want) in e[0].iter().zip([0.5, 0.25, 0.125]) {
        approx::assert_relative_eq!(*got, want, max_relative = 0.05);
    }
    let e = reference(Kind::Additive, &[1.0], true);
    // N/V → e^{-1}, n_1 → e^{-τ} e^{-1} with τ = 1 − e^{-1}
    let tau = 1.0 - (-1.0f64).exp();
    for (got, want) in e[0]
        .iter()
        .zip([(-1.0f64).exp(), (-tau).exp() * (-1.0f64).exp()])
    {
        approx::assert_relative_eq!(*got, want, max_relative = 0.05);
    }
}

#[test]
fn constant_kernel_schemes_match_the_finite_n_reference() {
    let (report, failures) = check(
        Kind::Constant,
        Coagulation::constant(1.0).unwrap(),
        &[0.5, 2.0, 8.0, 30.0],
    );
    println!("{report}");
    assert!(failures.is_empty(), "{failures}");
}

/// Additive kernel to t = 8 (N/V ≈ e^{-t}, ~12 doublings, sizes up to ~2^17): at
/// t = 30 the largest size would pass 32 · 2^40, beyond any size limit, so the fourth
/// time of the constant kernel is left out here (and the block engine stops at t = 5:
/// see `times_for`).
#[test]
fn additive_kernel_schemes_match_the_finite_n_reference() {
    let (report, failures) = check(Kind::Additive, Coagulation::additive(), &[0.5, 2.0, 8.0]);
    println!("{report}");
    assert!(failures.is_empty(), "{failures}");
}
