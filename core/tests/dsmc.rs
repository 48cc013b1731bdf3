//! Low-rank DSMC (Osinsky 2023 §5; `scheme::lowrank::dsmc`): every collision conserves
//! momentum and loses `(1 − ε²)` of its normal relative kinetic energy, to rounding;
//! the waiting time to the first collision from a fixed state has the exact mean
//! `1/R`, `R = Σ_{k<l} π (R_k + R_l)² |V_k − V_l| / V`; elastic collisions keep a
//! Maxwellian and equilibrate partial temperatures; Haff's law; the low-rank and the
//! acceptance–rejection engines agree; checkpoints, bad input.

use crate::common::z_max;
use coagula_core::Error;
use coagula_core::kernel::gas::{NeverStick, StickBelow, Sticking};
use coagula_core::observe::Replicas;
use coagula_core::scheme::lowrank::BinaryTree;
use coagula_core::scheme::lowrank::dsmc::{
    Collisions, Directions, Gas, LowRankDsmc, RejectionDsmc,
};
use coagula_core::scheme::lowrank::{LowRankMc, ProposalEngine, TreeEngine, UniformEngine};
use coagula_core::scheme::{Budget, Scheme};
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::{Rng, SeedableRng};

type On<S, E> = LowRankMc<Gas<S>, 3, E, Collisions>;

fn rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed.wrapping_mul(0x9e37_79b9) ^ 0xd5)
}

/// The elements of `a` not in `b` (as multisets, by `key`).
fn diff<T: Copy, K: Ord>(a: &[T], b: &[T], key: impl Fn(&T) -> K) -> Vec<T> {
    let mut bk: Vec<K> = b.iter().map(&key).collect();
    bk.sort();
    let mut used = vec![false; bk.len()];
    let mut out = Vec::new();
    for x in a {
        let k = key(x);
        let start = bk.partition_point(|y| *y < k);
        match (start..bk.len()).find(|&i| bk[i] == k && !used[i]) {
            Some(i) => used[i] = true,
            None => out.push(*x),
        }
    }
    out
}

/// All particles as (size, velocity), in the scheme's order.
fn particles<S: Sticking + Clone, E: ProposalEngine<3>>(s: &On<S, E>) -> Vec<(u64, [f64; 3])> {
    let mut out = Vec::new();
    for size in 1..=s.max_size() as u64 {
        for v in s.kernel().velocities(size) {
            out.push((size, *v));
        }
    }
    out
}

/// Every event, one at a time: a bounce changes two particles, conserves momentum to
/// rounding and changes the energy by exactly `−(1 − ε²) μ (g·e)²/2`, where `e` is
/// the direction of the first particle's change and `g` the relative velocity before;
/// a merge conserves mass and momentum. On both engines, with sticking on.
#[test]
fn every_collision_conserves_momentum_and_loses_its_share() {
    for d in [Directions::Conditional, Directions::Uniform] {
        check_events::<TreeEngine<3, BinaryTree<3>>>(d);
        check_events::<UniformEngine<3>>(d);
    }
}

fn check_events<E: ProposalEngine<3>>(directions: Directions) {
    let eps = 0.8;
    let sizes: Vec<u64> = (0..400).map(|p| 1 + p % 5).collect();
    let mut r0 = rng(1);
    let vel: Vec<[f64; 3]> = (0..400)
        .map(|_| {
            let mut v = [0.0; 3];
            for c in &mut v {
                *c = 2.0 * (r0.next_u64() as f64 / u64::MAX as f64) - 1.0;
            }
            v
        })
        .collect();
    let gas = Gas::from_particles(eps, StickBelow { speed: 0.05 }, &sizes, &vel)
        .unwrap()
        .with_directions(directions);
    let mut s = On::<_, E>::new_gas(gas, 4000.0).unwrap();
    let mut rng = rng(2);
    let (mut bounces, mut merges) = (0, 0);
    while bounces < 300 || merges < 3 {
        let before = particles(&s);
        let (p0, e0) = (s.momentum(), s.energy() * s.volume());
        let mass0: u64 = before.iter().map(|p| p.0).sum();
        let rep = s
            .advance_within(1e9, &mut Budget::work(1), &mut rng)
            .unwrap();
        if rep.events == 0 {
            continue;
        }
        let after = particles(&s);
        let p1 = s.momentum();
        let scale: f64 = before.iter().map(|p| p.0 as f64).sum::<f64>() * 2.0;
        for k in 0..3 {
            assert!(
                (p1[k] - p0[k]).abs() < 1e-12 * scale,
                "momentum {p0:?} -> {p1:?}"
            );
        }
        if rep.bounces == 1 {
            bounces += 1;
            assert_eq!(before.len(), after.len());
            // (particles move between speed classes: compare as multisets)
            let key = |p: &(u64, [f64; 3])| (p.0, p.1.map(f64::to_bits));
            let gone = diff(&before, &after, key);
            let came = diff(&after, &before, key);
            assert!(
                gone.len() == 2 && came.len() == 2,
                "a bounce changed {gone:?} into {came:?}"
            );
            // pair each new velocity with its old one: the two changes are parallel
            let delta = |n: &(u64, [f64; 3]), o: &(u64, [f64; 3])| -> [f64; 3] {
                [n.1[0] - o.1[0], n.1[1] - o.1[1], n.1[2] - o.1[2]]
            };
            let cross = |d: [f64; 3], d2: [f64; 3]| {
                let c = [
                    d[1] * d2[2] - d[2] * d2[1],
                    d[2] * d2[0] - d[0] * d2[2],
                    d[0] * d2[1] - d[1] * d2[0],
                ];
                c.iter().map(|x| x.abs()).fold(0.0, f64::max)
            };
            // which new velocity is whose: with equal masses both pairings are
            // collisions along some e, so the check passes if one pairing explains the
            // change (parallel changes and the energy share)
            let got = s.energy() * s.volume() - e0;
            let explains = |ia: usize, ib: usize| -> bool {
                if came[ia].0 != gone[0].0 || came[ib].0 != gone[1].0 {
                    return false;
                }
                let (a_old, a_new, b_old, b_new) = (gone[0], came[ia], gone[1], came[ib]);
                let (ma, mb) = (a_old.0 as f64, b_old.0 as f64);
                let d = delta(&a_new, &a_old);
                let dn = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let e: Vec<f64> = d.iter().map(|x| x / dn).collect();
                let gn: f64 = (0..3).map(|k| (a_old.1[k] - b_old.1[k]) * e[k]).sum();
                let want = -(1.0 - eps * eps) * ma * mb / (ma + mb) * gn * gn / 2.0;
                cross(d, delta(&b_new, &b_old)) < 1e-12 * (1.0 + dn * dn)
                    && (got - want).abs() < 1e-11 * e0
            };
            assert!(
                explains(0, 1) || explains(1, 0),
                "energy changed by {got}: no collision explains {gone:?} -> {came:?}"
            );
        } else {
            merges += 1;
            assert_eq!(after.len() + 1, before.len());
            let mass1: u64 = after.iter().map(|p| p.0).sum();
            assert_eq!(mass0, mass1, "mass");
        }
    }
    assert_eq!(s.particles(), s.kernel().counts().iter().sum::<u64>());
}

/// Elastic collisions (ε = 1) from sizes 1–3 at partial temperatures 0.5, 1, 2: the
/// energy is conserved to rounding, the partial temperatures equilibrate to the mean
/// (within the replicas' threshold at t = 150, ~100 collisions per particle) and the
/// velocity components stay Gaussian (kurtosis 3; a non-Maxwellian gas from wrong
/// collision laws drifts away from it).
#[test]
fn elastic_collisions_equilibrate_a_maxwellian() {
    let reps = 16u64;
    let (mut t1, mut t3, mut kurt) = (Replicas::new(), Replicas::new(), Replicas::new());
    let mut mean_t = 0.0;
    for r in 0..reps {
        let mut rng = rng(100 + r);
        let gas = Gas::maxwellian(1.0, &[3000, 1500, 500], &[0.5, 1.0, 2.0], &mut rng).unwrap();
        let mut s = LowRankDsmc::new_gas(gas, 5000.0 / 0.1).unwrap();
        let e0 = s.energy();
        mean_t = s.mean_temperature();
        s.advance_to(150.0, &mut rng).unwrap();
        assert!(
            (s.energy() / e0 - 1.0).abs() < 1e-11,
            "energy not conserved"
        );
        t1.push(s.temperature(1) / s.mean_temperature());
        t3.push(s.temperature(3) / s.mean_temperature());
        // kurtosis of the monomers' x components, scaled by their variance
        let v: Vec<[f64; 3]> = s.kernel().velocities(1).copied().collect();
        let m2 = v.iter().map(|u| u[0] * u[0]).sum::<f64>() / v.len() as f64;
        let m4 = v.iter().map(|u| u[0].powi(4)).sum::<f64>() / v.len() as f64;
        kurt.push(m4 / (m2 * m2));
    }
    let z = z_max(reps);
    for (name, st, want) in [
        ("T1 / T", &t1, 1.0),
        ("T3 / T", &t3, 1.0),
        ("kurtosis", &kurt, 3.0),
    ] {
        let zz = (st.mean() - want) / st.std_error();
        println!(
            "{name}: {} ± {} vs {want} ({zz:+.2} SE)",
            st.mean(),
            st.std_error()
        );
        assert!(zz.abs() < z, "{name}: {zz:.1} SE");
    }
    assert!(
        mean_t > 0.7 && mean_t < 1.0,
        "initial mean temperature {mean_t}"
    );
}

/// Haff's law for the homogeneous cooling of a monodisperse gas (unit mass and
/// diameter, density 0.1, ε = 0.95): `T(t) = T0 / (1 + t/τ)²`,
/// `τ = 3 / (2 sqrt(π) n σ² (1 − ε²) sqrt(T0))` with the first Sonine correction of the
/// cooling rate, `1 + 3 a2/16`, `a2 = 16 (1 − ε)(1 − 2ε²)/(81 − 17ε + 30ε²(1 − ε))`
/// (van Noije & Ernst 1998; −0.18 % here, 4.7 SE at t = τ without it), each replica
/// against its own `T0`; 32 replicas of 10 000 particles at t = τ/4, τ/2, τ (3 checks).
#[test]
fn homogeneous_cooling_follows_haffs_law() {
    let (eps, dens, n) = (0.95f64, 0.1, 10_000u64);
    let tau1 = 3.0 / (2.0 * std::f64::consts::PI.sqrt() * dens * (1.0 - eps * eps));
    let a2 = 16.0 * (1.0 - eps) * (1.0 - 2.0 * eps * eps)
        / (81.0 - 17.0 * eps + 30.0 * eps * eps * (1.0 - eps));
    let zeta = 1.0 + 3.0 * a2 / 16.0;
    let fractions = [0.25, 0.5, 1.0];
    let reps = 32u64;
    let mut st = [Replicas::new(); 3];
    for r in 0..reps {
        let mut rng = rng(200 + r);
        let gas = Gas::maxwellian(eps, &[n], &[1.0], &mut rng).unwrap();
        let mut s = LowRankDsmc::new_gas(gas, n as f64 / dens).unwrap();
        let t0 = s.mean_temperature();
        for (i, f) in fractions.iter().enumerate() {
            let t = f * tau1;
            s.advance_to(t, &mut rng).unwrap();
            let haff = t0 / (1.0 + zeta * t * t0.sqrt() / tau1).powi(2);
            st[i].push(s.mean_temperature() / haff - 1.0);
        }
    }
    let z = z_max(reps);
    for (i, f) in fractions.iter().enumerate() {
        let zz = st[i].mean() / st[i].std_error();
        println!(
            "t = {f} τ: T / Haff − 1 = {:.2e} ± {:.2e} ({zz:+.2} SE)",
            st[i].mean(),
            st[i].std_error()
        );
        assert!(zz.abs() < z, "t = {f} τ: {zz:.1} SE");
    }
}

/// The paper's polydisperse workload (N_k ∝ e^{−0.1(k−1)}, all T_k = 1, ε = 0.99,
/// density 0.1) on the low-rank and the acceptance–rejection engines: the mean
/// temperature and the temperature of sizes 1 and 10 at t = 5 agree (two-sample z on
/// 16 replicas each).
#[test]
fn low_rank_and_rejection_agree() {
    let counts: Vec<u64> = (0..40)
        .map(|k| (300.0 * (-0.1 * k as f64).exp()) as u64)
        .collect();
    let n: u64 = counts.iter().sum();
    let temps = vec![1.0; counts.len()];
    let reps = 16u64;
    let run = |tree: bool, r: u64| -> [f64; 3] {
        let mut rng = rng(300 + r + if tree { 0 } else { 1000 });
        let gas = Gas::maxwellian(0.99, &counts, &temps, &mut rng).unwrap();
        let v = n as f64 / 0.1;
        let obs = |t: f64, m: f64, t1: f64, t10: f64| [m / t, t1 / t, t10 / t];
        if tree {
            let mut s = LowRankDsmc::new_gas(gas, v).unwrap();
            let t = s.mean_temperature();
            s.advance_to(5.0, &mut rng).unwrap();
            obs(t, s.mean_temperature(), s.temperature(1), s.temperature(10))
        } else {
            let mut s = RejectionDsmc::new_gas(gas, v).unwrap();
            let t = s.mean_temperature();
            s.advance_to(5.0, &mut rng).unwrap();
            obs(t, s.mean_temperature(), s.temperature(1), s.temperature(10))
        }
    };
    let mut a = [Replicas::new(); 3];
    let mut b = [Replicas::new(); 3];
    for r in 0..reps {
        for (k, x) in run(true, r).into_iter().enumerate() {
            a[k].push(x);
        }
        for (k, x) in run(false, r).into_iter().enumerate() {
            b[k].push(x);
        }
    }
    let z = z_max(reps);
    for (k, name) in ["T(5)/T(0)", "T1/T(0)", "T10/T(0)"].into_iter().enumerate() {
        let se = (a[k].std_error().powi(2) + b[k].std_error().powi(2)).sqrt();
        let zz = (a[k].mean() - b[k].mean()) / se;
        println!(
            "{name}: low-rank {} vs rejection {} ({zz:+.2} SE)",
            a[k].mean(),
            b[k].mean()
        );
        assert!(zz.abs() < z, "{name}: {zz:.1} SE");
    }
    assert!(a[0].mean() < 1.0, "the gas cools");
}

/// Bad input is an error: ε outside (0, 1], NaN velocities, lengths that differ,
/// size 0, counts that do not match the gas, a sticking probability outside [0, 1].
#[test]
fn bad_input_is_refused() {
    let v = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
    for eps in [0.0, -0.5, 1.5, f64::NAN] {
        assert!(Gas::from_particles(eps, NeverStick, &[1, 1], &v).is_err());
    }
    assert!(Gas::from_particles(0.9, NeverStick, &[1, 1], &[[f64::NAN, 0.0, 0.0], v[1]]).is_err());
    assert!(Gas::from_particles(0.9, NeverStick, &[1], &v).is_err());
    // |v|² overflows: such a particle would land in the class of v = 0 (bound 0) and
    // every pair with it would fail the bound (review finding)
    assert!(Gas::from_particles(1.0, NeverStick, &[1, 1], &[[1e155, 0.0, 0.0], v[1]]).is_err());
    assert!(Gas::from_particles(0.9, NeverStick, &[0, 1], &v).is_err());
    assert!(Gas::maxwellian(0.9, &[10], &[1.0, 2.0], &mut rng(1)).is_err());
    assert!(Gas::maxwellian(0.9, &[10], &[-1.0], &mut rng(1)).is_err());
    let gas = Gas::from_particles(0.9, NeverStick, &[1, 1], &v).unwrap();
    let r = LowRankDsmc::new(gas.clone(), &[3], 10.0);
    assert!(matches!(r, Err(Error::Unsupported { .. })));
    let mut s = LowRankDsmc::new_gas(gas, 10.0).unwrap();
    assert!(s.set_counts(&[5], 10.0).is_err());
    /// A model that returns 2.
    #[derive(Clone, Copy)]
    struct Bad;
    impl Sticking for Bad {
        fn probability(&self, _: u64, _: u64, _: f64) -> f64 {
            2.0
        }
    }
    let gas = Gas::from_particles(0.9, Bad, &[1, 1], &v).unwrap();
    let mut s = LowRankDsmc::new_gas(gas, 10.0).unwrap();
    let before = particles(&s);
    let e = s.advance_to(1e6, &mut rng(2)).unwrap_err();
    assert!(matches!(e, Error::InvalidRate { .. }), "{e}");
    // (the clock stands at the last rejected proposal before the failing one)
    assert_eq!(
        particles(&s),
        before,
        "a refused collision changed the particles"
    );
}
