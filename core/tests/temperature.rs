//! Temperature-dependent low-rank Monte Carlo (Osinsky 2023 §4; `scheme::lowrank::temperature`):
//! the model family's closed form, the exact finite-N reference where the family is a
//! pure death process, the energy each event moves (to rounding, event by event), the
//! ballistic model against a deterministic solve of its equations, checkpoints, bad
//! input.

use crate::common::z_max;
use coagula_core::Error;
use coagula_core::kernel::temperature::{Ballistic, ClosedForm, TemperatureKernel, integrate};
use coagula_core::observe::Replicas;
use coagula_core::scheme::lowrank::{
    BinaryTree, BucketedEngine, Collide, LowRankMc, ProposalEngine, TemperatureMc, Temperatures,
    TreeEngine, UniformEngine, WideTree,
};
use coagula_core::scheme::{Budget, Scheme};
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

fn rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed.wrapping_mul(0x9e37_79b9))
}

/// The scheme on engine E.
type On<TK, E> = LowRankMc<Temperatures<TK>, 3, E, Collide>;

/// The model family on engine E from `n0` monomers at density 1 and temperature `t0`.
fn model_sim<E: ProposalEngine<3>>(gamma: f64, t0: f64, n0: u64) -> On<ClosedForm, E> {
    let k = Temperatures::new(ClosedForm::new(1.0, gamma).unwrap(), &[t0]).unwrap();
    On::<ClosedForm, E>::new(k, &[n0], n0 as f64).unwrap()
}

/// The engines every statistical test runs on: the per-size trees and the
/// acceptance–rejection baseline.
macro_rules! on_each_engine {
    ($f:ident) => {{
        let mut failures = $f::<TreeEngine<3, WideTree<3>>>("tree");
        failures.push_str(&$f::<UniformEngine<3>>("rejection"));
        assert!(failures.is_empty(), "{failures}");
    }};
}

/// N(t) and the mean temperature of the family for γ = 0, 1/2, 1 against the closed
/// form (TEMPERATURE.md), 32 replicas of 20 000 monomers, Student t on the replicas'
/// own SE at the suite's false-alarm rate (12 checks). A factor 2 in the collision rate
/// moves N(4) by ~30 % (hundreds of SE: the SE is ~0.1 %); a bounce that does not cool
/// (γ ignored) leaves the mean temperature at its γ = 0 value, 2.2× the γ = 1 one at
/// t = 4.
#[test]
fn model_family_matches_its_closed_form() {
    on_each_engine!(model_family);
}

fn model_family<E: ProposalEngine<3>>(engine: &str) -> String {
    let reps = 32u64;
    let z = z_max(reps);
    let times = [1.0, 4.0];
    let mut failures = String::new();
    for (g, gamma) in [0.0, 0.5, 1.0].into_iter().enumerate() {
        let exact = ClosedForm::new(1.0, gamma).unwrap();
        let mut stats = vec![[Replicas::new(), Replicas::new()]; times.len()];
        for r in 0..reps {
            let mut sim = model_sim::<E>(gamma, 1.0, 20_000);
            let mut rng = rng(100 * g as u64 + r);
            for (ti, &t) in times.iter().enumerate() {
                sim.advance_to(t, &mut rng).unwrap();
                stats[ti][0].push(sim.moment(0.0));
                stats[ti][1].push(sim.mean_temperature());
            }
        }
        for (ti, &t) in times.iter().enumerate() {
            let e = exact.exact(1.0, 1.0, t);
            for (name, st, want) in [
                ("N", &stats[ti][0], e.number()),
                ("mean T", &stats[ti][1], e.mean_temperature()),
            ] {
                let zz = (st.mean() - want) / st.std_error();
                println!(
                    "{engine} γ = {gamma} t = {t} {name}: {} ± {} vs {want} ({zz:+.2} SE)",
                    st.mean(),
                    st.std_error()
                );
                if zz.is_nan() || zz.abs() > z {
                    failures.push_str(&format!(
                        "{engine} γ = {gamma} t = {t} {name}: {} vs {want} ({zz:.1} SE > {z:.2})\n",
                        st.mean()
                    ));
                }
            }
        }
    }
    failures
}

/// For γ = 0 every size keeps `T_k = k T0` exactly, so every pair aggregates at rate
/// `c sqrt(T0)/V` (and bounces at the same rate, moving nothing): N is a pure death
/// process with particle doubling. Its master equation (states (N, doublings), solved
/// by RK4 to 1e-10) gives E[N/V] and E[T̄] = T0 E[V/N] (the mass density is 1) at
/// N0 = 16, where the finite-N effects are ~5 %: a rate off by N/(N−1), a bounce
/// counted as an aggregation, a doubling at the wrong moment are all many SE (6000
/// replicas: SE ~0.2 %).
#[test]
fn gamma_zero_matches_the_finite_n_master_equation() {
    on_each_engine!(finite_n);
}

fn finite_n<E: ProposalEngine<3>>(engine: &str) -> String {
    const N0: usize = 16;
    const D: usize = 8;
    let (t0, times) = (4.0, [0.5, 2.0, 6.0]);
    let k = libm::sqrt(t0); // c sqrt(T0), c = 1
    // p[d][n]: probability of n particles after d doublings
    let rates = |p: &Vec<[f64; N0 + 1]>| {
        let mut dp = vec![[0.0; N0 + 1]; D];
        for d in 0..D {
            let v = (N0 << d) as f64;
            for n in 2..=N0 {
                let out = p[d][n] * k * (n * (n - 1)) as f64 / (2.0 * v);
                dp[d][n] -= out;
                let m = n - 1;
                if m < N0 / 2 {
                    if d + 1 < D {
                        dp[d + 1][2 * m] += out;
                    }
                } else {
                    dp[d][m] += out;
                }
            }
        }
        dp
    };
    let mut p = vec![[0.0; N0 + 1]; D];
    p[0][N0] = 1.0;
    let h = 1e-3;
    let mut now = 0.0;
    let mut want = Vec::new();
    for &t in &times {
        while now < t - 1e-12 {
            let axpy = |a: &Vec<[f64; N0 + 1]>, b: &Vec<[f64; N0 + 1]>, s: f64| {
                let mut o = a.clone();
                for (x, y) in o.iter_mut().zip(b) {
                    for (u, w) in x.iter_mut().zip(y) {
                        *u += s * w;
                    }
                }
                o
            };
            let k1 = rates(&p);
            let k2 = rates(&axpy(&p, &k1, h / 2.0));
            let k3 = rates(&axpy(&p, &k2, h / 2.0));
            let k4 = rates(&axpy(&p, &k3, h));
            for d in 0..D {
                for n in 0..=N0 {
                    p[d][n] += h / 6.0 * (k1[d][n] + 2.0 * k2[d][n] + 2.0 * k3[d][n] + k4[d][n]);
                }
            }
            now += h;
        }
        let total: f64 = p.iter().flatten().sum();
        assert!((total - 1.0).abs() < 1e-9, "probability lost: {total}");
        let (mut en, mut et) = (0.0, 0.0);
        for (d, row) in p.iter().enumerate() {
            let v = (N0 << d) as f64;
            for (n, &pn) in row.iter().enumerate().skip(1) {
                en += pn * n as f64 / v;
                et += pn * t0 * v / n as f64;
            }
        }
        assert!(p[D - 1].iter().sum::<f64>() < 1e-12, "doubling cap reached");
        want.push([en, et]);
    }
    let reps = 6000u64;
    let mut stats = vec![[Replicas::new(), Replicas::new()]; times.len()];
    for r in 0..reps {
        let mut sim = model_sim::<E>(0.0, t0, N0 as u64);
        let mut rng = rng(7 + r);
        for (ti, &t) in times.iter().enumerate() {
            sim.advance_to(t, &mut rng).unwrap();
            stats[ti][0].push(sim.particles() as f64 / sim.volume());
            stats[ti][1].push(sim.mean_temperature());
        }
    }
    let z = z_max(reps);
    let mut failures = String::new();
    for (ti, &t) in times.iter().enumerate() {
        for (q, name) in ["N/V", "mean T"].into_iter().enumerate() {
            let st = &stats[ti][q];
            let zz = (st.mean() - want[ti][q]) / st.std_error();
            println!(
                "{engine} t = {t} {name}: {} ± {} vs {} ({zz:+.2} SE)",
                st.mean(),
                st.std_error(),
                want[ti][q]
            );
            if zz.is_nan() || zz.abs() > z {
                failures.push_str(&format!("{engine} t = {t} {name}: {zz:.1} SE > {z:.2}\n"));
            }
        }
    }
    failures
}

/// Σ_s N_s T_s of a scheme.
fn total_energy<TK: TemperatureKernel + Clone, E: ProposalEngine<3>>(sim: &On<TK, E>) -> f64 {
    sim.energy() * sim.volume()
}

/// Every event moves the total energy `Σ N_s T_s` by exactly its share of the
/// population equations: an aggregation i + j by `(B − D^agg_ij − D^agg_ji)/C^agg`
/// (i = j: `(B − 2 D^agg_ii)/C^agg`), a bounce by `−(D^res_ij + D^res_ji)/C^res`
/// (i = j: `−2 D^res_ii/C^res`) — to rounding, event by event, unless a temperature
/// was clipped at 0 or a size emptied (its last particle takes its energy `T_i`). The O(1/N) part of the update rules (which size's count divides,
/// the same-size case) shows here directly. The ballistic kernels with a high barrier
/// (so that both outcomes are frequent) from a polydisperse, unequal-temperature start.
#[test]
fn every_event_moves_the_energy_by_its_share() {
    energy_shares::<TreeEngine<3, BinaryTree<3>>>();
    energy_shares::<UniformEngine<3>>();
}

fn energy_shares<E: ProposalEngine<3>>() {
    let model = Ballistic::new(0.8, 0.3, 0.4).unwrap();
    let temps = [1.0, 0.5, 2.0, 0.2, 1.5, 0.7];
    let counts = [160, 80, 48, 24, 16, 12];
    let k = Temperatures::new(model, &temps).unwrap();
    let mut sim = On::<_, E>::new(k, &counts, 80.0).unwrap();
    // (stop before the first particle doubling, which doubles every count)
    let n0: u64 = counts.iter().sum();
    let mut rng = rng(3);
    let (mut merges, mut bounces, mut same, mut checked) = (0, 0, 0, 0);
    while (merges < 100 || bounces < 100) && sim.particles() > n0 / 2 + 1 {
        let before_counts = sim.counts().into_owned();
        let before_temps: Vec<f64> = (1..=before_counts.len() as u64)
            .map(|s| sim.temperature(s))
            .collect();
        let e0 = total_energy(&sim);
        let rep = sim
            .advance_within(f64::INFINITY.min(1e9), &mut Budget::work(1), &mut rng)
            .unwrap();
        if rep.events == 0 {
            continue;
        }
        let counts = sim.counts().into_owned();
        let tb = |s: u64| before_temps.get(s as usize - 1).copied().unwrap_or(0.0);
        let nb = |s: u64| before_counts.get(s as usize - 1).copied().unwrap_or(0);
        // the pair: sizes whose count fell (merge) or whose temperature moved (bounce)
        let mut fell = Vec::new();
        for s in 1..=counts.len() as u64 {
            let d = nb(s) as i64 - counts[s as usize - 1] as i64;
            for _ in 0..d.max(0) {
                fell.push(s);
            }
        }
        let de = total_energy(&sim) - e0;
        let (x, y, expect, clipped) = if fell.len() == 2 {
            merges += 1;
            let (x, y) = (fell[0], fell[1]);
            let r = model.rates(x, tb(x), y, tb(y));
            let gain = r.energy_gain / r.aggregation;
            let loss = if x == y {
                same += 1;
                2.0 * r.aggregation_loss[0] / r.aggregation
            } else {
                (r.aggregation_loss[0] + r.aggregation_loss[1]) / r.aggregation
            };
            // (a size that empties takes its whole energy, not the share)
            let clipped = [x, y].iter().any(|&s| sim.temperature(s) == 0.0);
            (x, y, gain - loss, clipped)
        } else {
            assert!(fell.is_empty(), "an event removed {fell:?}");
            bounces += 1;
            let moved: Vec<u64> = (1..=counts.len() as u64)
                .filter(|&s| sim.temperature(s).to_bits() != tb(s).to_bits())
                .collect();
            if moved.is_empty() {
                continue; // a bounce that moved nothing representable
            }
            let (x, y) = if moved.len() == 1 {
                (moved[0], moved[0])
            } else {
                assert_eq!(moved.len(), 2, "a bounce moved {moved:?}");
                (moved[0], moved[1])
            };
            let r = model.rates(x, tb(x), y, tb(y));
            let loss = if x == y {
                2.0 * r.restitution_loss[0] / r.restitution
            } else {
                (r.restitution_loss[0] + r.restitution_loss[1]) / r.restitution
            };
            let clipped = [x, y].iter().any(|&s| sim.temperature(s) == 0.0);
            (x, y, -loss, clipped)
        };
        if clipped {
            continue;
        }
        checked += 1;
        let scale = e0.abs().max(1.0);
        assert!(
            (de - expect).abs() <= 1e-10 * scale,
            "pair ({x}, {y}): energy moved by {de}, share {expect}"
        );
    }
    println!("{merges} merges ({same} same-size), {bounces} bounces, {checked} checked");
    assert!(merges >= 100 && same >= 5 && bounces >= 100 && checked >= 150);
}

/// The ballistic model at the paper's parameters against a deterministic solve of its
/// equations (sizes truncated at 64, RK4, Δt = 0.2; at t = 300, Δt = 0.025 moves the
/// three observables by less than 1e-13 relative and L = 128 by nothing): N, the mean temperature and M2 up to t = 300, 8 replicas of 20 000
/// monomers (9 checks). The full comparison to t = 1000 is `coagula validate
/// osinsky2023/`. A bounce that does not cool leaves T̄(300) at 1 instead of ~0.8 (tens
/// of SE); N and M2 see the aggregation rate.
#[test]
fn ballistic_model_matches_its_equations() {
    on_each_engine!(ballistic);
}

fn ballistic<E: ProposalEngine<3>>(engine: &str) -> String {
    let model = Ballistic::paper();
    let n1 = 0.3 / core::f64::consts::PI;
    let times = [30.0, 100.0, 300.0];
    // deterministic: n_k and e_k = n_k T_k
    let l = 64;
    let mut n = vec![0.0; l];
    let mut e = vec![0.0; l];
    n[0] = n1;
    e[0] = n1;
    let h = 0.2;
    let mut now = 0.0;
    let mut want = Vec::new();
    for &t in &times {
        integrate(&model, &mut n, &mut e, now, t, h).unwrap();
        now = t;
        let nn: f64 = n.iter().sum();
        let m2: f64 = n
            .iter()
            .enumerate()
            .map(|(k, x)| ((k + 1) * (k + 1)) as f64 * x)
            .sum();
        let et: f64 = e.iter().sum();
        want.push([nn, et / nn, m2]);
    }
    let reps = 8u64;
    let mut stats = vec![[Replicas::new(), Replicas::new(), Replicas::new()]; times.len()];
    for r in 0..reps {
        let k = Temperatures::new(model, &[1.0]).unwrap();
        let n0 = 20_000u64;
        let mut sim = On::<_, E>::new(k, &[n0], n0 as f64 / n1).unwrap();
        let mut rng = rng(50 + r);
        for (ti, &t) in times.iter().enumerate() {
            sim.advance_to(t, &mut rng).unwrap();
            stats[ti][0].push(sim.moment(0.0));
            stats[ti][1].push(sim.mean_temperature());
            stats[ti][2].push(sim.moment(2.0));
        }
    }
    let z = z_max(reps);
    let mut failures = String::new();
    for (ti, &t) in times.iter().enumerate() {
        for (q, name) in ["N", "mean T", "M2"].into_iter().enumerate() {
            let st = &stats[ti][q];
            let zz = (st.mean() - want[ti][q]) / st.std_error();
            println!(
                "{engine} t = {t} {name}: {} ± {} vs ODE {} ({zz:+.2} SE)",
                st.mean(),
                st.std_error(),
                want[ti][q]
            );
            if zz.is_nan() || zz.abs() > z {
                failures.push_str(&format!("{engine} t = {t} {name}: {zz:.1} SE > {z:.2}\n"));
            }
        }
    }
    failures
}

/// Every bit of a temperature sim's state.
fn state_bits<TK: TemperatureKernel + Clone, E: ProposalEngine<3>>(s: &On<TK, E>) -> Vec<u64> {
    let mut v: Vec<u64> = s.counts().iter().copied().collect();
    v.extend(s.kernel().temperatures().iter().map(|t| t.to_bits()));
    v.push(s.time().to_bits());
    v.push(s.volume().to_bits());
    v
}

/// Bad input is an error, never a panic: invalid temperatures, the bucketed engine
/// (which cannot move factors), a kernel whose rate leaves the bound.
#[test]
fn bad_input_is_refused() {
    let m = ClosedForm::new(1.0, 0.5).unwrap();
    for t in [f64::NAN, -1.0, f64::INFINITY] {
        assert!(matches!(
            Temperatures::new(m, &[1.0, t]),
            Err(Error::OutOfRange { .. })
        ));
    }
    assert!(ClosedForm::new(0.0, 0.5).is_err() && ClosedForm::new(1.0, -0.1).is_err());
    assert!(Ballistic::new(0.0, 0.1, 0.4).is_err() && Ballistic::new(0.9, -1.0, 0.4).is_err());
    let k = Temperatures::new(m, &[1.0]).unwrap();
    let r = LowRankMc::<_, 3, BucketedEngine<3, 6>, Collide>::new(k.clone(), &[100], 100.0);
    assert!(matches!(r, Err(Error::Unsupported { .. })));

    /// A kernel whose collision rate is twice what its bound allows.
    #[derive(Clone, Copy)]
    struct Liar(ClosedForm);
    impl TemperatureKernel for Liar {
        fn rates(
            &self,
            i: u64,
            ti: f64,
            j: u64,
            tj: f64,
        ) -> coagula_core::kernel::temperature::PairRates {
            let mut r = self.0.rates(i, ti, j, tj);
            r.collision *= 4.0;
            r
        }
        fn factors(&self, i: u64, t: f64, a: &mut [f64; 3], b: &mut [f64; 3]) {
            self.0.factors(i, t, a, b)
        }
    }
    let k = Temperatures::new(Liar(m), &[1.0]).unwrap();
    let mut sim = TemperatureMc::<_>::new(k, &[100], 100.0).unwrap();
    let before = state_bits(&sim);
    let err = sim.advance_to(10.0, &mut rng(1)).unwrap_err();
    assert!(matches!(err, Error::BoundExceeded { .. }), "{err}");
    assert_eq!(
        state_bits(&sim),
        before,
        "the refused event changed nothing"
    );
}

/// The acceptance–rejection engine under plain coagulation: K = 1 from 20 000
/// monomers, N(t)/V = 1/(1 + t/2) and M2 = 1 + t within the suite's threshold over 32
/// replicas (a factor 2 in the proposal rate is ~100 SE).
#[test]
fn rejection_engine_runs_plain_coagulation() {
    use coagula_core::kernel::Coagulation;
    let reps = 32u64;
    let (mut m0, mut m2) = (Replicas::new(), Replicas::new());
    for r in 0..reps {
        let k = Coagulation::constant(1.0).unwrap();
        let mut sim = LowRankMc::<_, 1, UniformEngine<1>>::monodisperse(k, 20_000).unwrap();
        sim.advance_to(2.0, &mut rng(900 + r)).unwrap();
        m0.push(sim.moment(0.0));
        m2.push(sim.moment(2.0));
    }
    let z = z_max(reps);
    for (name, st, want) in [("M0", &m0, 0.5), ("M2", &m2, 3.0)] {
        let zz = (st.mean() - want) / st.std_error();
        println!(
            "{name}: {} ± {} vs {want} ({zz:+.2} SE)",
            st.mean(),
            st.std_error()
        );
        assert!(zz.abs() <= z, "{name}: {zz:.1} SE");
    }
}
