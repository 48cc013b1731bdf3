use super::*;
use crate::checkpoint::Checkpoint;
use crate::exact::Exact;
use crate::kernel::{BinaryUniform, Coagulation, NoFragmentation};
use crate::observe::{Observe, Replicas};
use crate::scheme::{Budget, Scheme};
use alloc::vec;
use alloc::vec::Vec;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// The trees after any sequence of sets, pushes and removals are bit for bit the trees
/// built afresh from the same sizes, and sampling follows the weights.
#[test]
fn store_trees_match_a_rebuild_and_sample_by_weight() {
    let w = |x: f64| [x, 1.0 / x];
    let mut rng = Pcg64Mcg::new(1);
    let mut s: Store<Vec<f64>, 2> = Store::new(vec![0.0; 1000], 37).unwrap();
    let init: Vec<f64> = (1..=20).map(f64::from).collect();
    s.fill(&init, w);
    for step in 0..2000u64 {
        let r = crate::random::below(&mut rng, 3);
        let n = s.len();
        if r == 0 && n < s.capacity() {
            let x = 1.0 + crate::random::below(&mut rng, 50) as f64;
            s.push(x, w(x));
        } else if r == 1 && n > 1 {
            s.swap_remove(crate::random::below(&mut rng, n as u64) as usize);
        } else if n > 0 {
            let i = crate::random::below(&mut rng, n as u64) as usize;
            let x = 0.5 + step as f64 % 7.0;
            s.set(i, x, w(x));
        }
        let mut fresh: Store<Vec<f64>, 2> = Store::new(vec![0.0; 1000], 37).unwrap();
        let sizes = s.sizes().to_vec();
        fresh.fill(&sizes, w);
        assert_eq!(
            s.ws[..Store::<Vec<f64>, 2>::words(37).unwrap()],
            fresh.ws[..Store::<Vec<f64>, 2>::words(37).unwrap()]
        );
    }
    // frequencies: sizes 1, 2, 3 with weights 1, 2, 3 in tree 0
    let mut s: Store<Vec<f64>, 2> = Store::new(vec![0.0; 100], 3).unwrap();
    s.fill(&[1.0, 2.0, 3.0], w);
    let mut hits = [0u32; 3];
    let draws = 60_000;
    for _ in 0..draws {
        hits[s.sample(0, &mut rng)] += 1;
    }
    for (i, &h) in hits.iter().enumerate() {
        let p = (i + 1) as f64 / 6.0;
        let sd = (draws as f64 * p * (1.0 - p)).sqrt();
        assert!(
            (f64::from(h) - draws as f64 * p).abs() < 5.0 * sd,
            "{hits:?}"
        );
    }
}

/// The group sampler after any sequence of sets, pushes and removals — weights over
/// 600 binades, zeros, subnormals, jumps above its window and falls far below it —
/// keeps its invariants (every particle in its binade's group, group totals the exact
/// sums), and draws by weight, the zero weights never.
#[test]
fn group_sampler_keeps_its_invariants_and_samples_by_weight() {
    use super::groups::Groups;
    let mut rng = Pcg64Mcg::new(3);
    let cap = 300;
    let mut g = Groups::new(cap).unwrap();
    let pick = |rng: &mut Pcg64Mcg, step: u64| -> f64 {
        match crate::random::below(rng, 8) {
            0 => 0.0,
            1 => 5e-324 * (1 + crate::random::below(rng, 1000)) as f64,
            // the window follows a weight that climbs far above it, then sinks back
            2 => {
                let s = (step / 10) as i32;
                let e = if s < 600 { s - 300 } else { 900 - s };
                libm::ldexp(1.0 + unit_f64(rng.next_u64()), e)
            }
            _ => libm::ldexp(
                1.0 + unit_f64(rng.next_u64()),
                crate::random::below(rng, 40) as i32 - 20,
            ),
        }
    };
    g.fill((0..50).map(f64::from));
    let mut w: Vec<f64> = (0..50).map(f64::from).collect();
    for step in 0..12_000u64 {
        let r = crate::random::below(&mut rng, 3);
        let n = w.len();
        if r == 0 && n < cap {
            let q = pick(&mut rng, step);
            g.push(q);
            w.push(q);
        } else if r == 1 && n > 1 {
            let i = crate::random::below(&mut rng, n as u64) as usize;
            g.swap_remove(i);
            w.swap_remove(i);
        } else if n > 0 {
            let i = crate::random::below(&mut rng, n as u64) as usize;
            let q = pick(&mut rng, step);
            g.set(i, q);
            w[i] = q;
        }
        g.check();
        for (i, &q) in w.iter().enumerate() {
            assert_eq!(g.weight(i).to_bits(), q.to_bits());
        }
        let exact: f64 = w.iter().sum();
        approx::assert_relative_eq!(g.total(), exact, max_relative = 1e-12);
    }
    // frequencies: weights 1, 2, 3, 0, 6 (two binades share none), 5e-324
    let w = [1.0, 2.0, 3.0, 0.0, 6.0, 5e-324];
    g.fill(w.iter().copied());
    let mut hits = [0u32; 6];
    let draws = 120_000;
    for _ in 0..draws {
        hits[g.sample(&mut rng)] += 1;
    }
    assert_eq!(hits[3], 0, "a zero weight was drawn: {hits:?}");
    for (i, &h) in hits.iter().enumerate() {
        let p = w[i] / 12.0;
        let sd = (draws as f64 * p * (1.0 - p)).sqrt().max(1.0);
        assert!(
            (f64::from(h) - draws as f64 * p).abs() < 5.0 * sd,
            "{i}: {hits:?}"
        );
    }
}

/// Mean and standard error of `f` over `reps` replicas.
fn replicas(reps: u64, mut f: impl FnMut(&mut Pcg64Mcg) -> f64) -> Replicas {
    let mut r = Replicas::new();
    for i in 0..reps {
        // seed_from_u64 scrambles the seed: raw consecutive MCG states give
        // correlated streams
        r.push(f(&mut Pcg64Mcg::seed_from_u64(
            0x5eed ^ i.wrapping_mul(0x9e37_79b9),
        )));
    }
    r
}

fn z(r: &Replicas, want: f64) -> f64 {
    (r.mean() - want) / r.std_error()
}

/// Replicas per statistical check, and the suite's per-check threshold for them
/// (Student t at `TEST_ALPHA`: 5.6 SE for 64 replicas).
const REPS: u64 = 64;
fn zmax() -> f64 {
    crate::observe::student_t_threshold(crate::observe::TEST_ALPHA, REPS - 1)
}

/// The seed's factor 2 (SPEC §5): with the proposal rate `(Σh)²/(2V)` direct simulation
/// matches `M0(t) = 1/(1 + t/2)` for K = 1; the rate the seed prints, `(Σh)²/V`, is the
/// same as K = 2 here, and that run misses the K = 1 solution by ~100 standard errors
/// (M0(1) = 1/2 instead of 2/3) while matching the K = 2 one.
#[test]
fn dsa_rate_factor_two_is_decided_by_the_constant_kernel() {
    let n = 2048;
    let run = |k0: f64| {
        replicas(REPS, |rng| {
            let k = Coagulation::constant(k0).unwrap();
            let mut s = Dsa::new(k, NoFragmentation, &vec![1.0; n], n as f64, n).unwrap();
            s.advance_to(1.0, rng).unwrap();
            s.moment(0.0)
        })
    };
    let (ours, doubled) = (run(1.0), run(2.0));
    let m0 = |k0: f64| Exact::constant(k0).unwrap().moment(0, 1.0).unwrap();
    assert!(z(&ours, m0(1.0)).abs() < zmax(), "{ours:?}");
    assert!(z(&doubled, m0(1.0)).abs() > 10.0 * zmax(), "{doubled:?}");
    assert!(z(&doubled, m0(2.0)).abs() < zmax(), "{doubled:?}");
}

/// Event-driven coagulation–fragmentation (K = 1, F = 2/(x + y), monodisperse start,
/// Lécot §4): `M2(t) = 3 − 2 e^{−t/3}` and `M3(t) = 18 − 36 e^{−t/3} + 19 e^{−t/2}`
/// from both schemes, with no time step to bias them (the issue asks for 4 SE; the
/// suite's threshold for 64 replicas is 5.6: both are printed); and the DSA's M0
/// approaches its equilibrium from 1 (M0' = M0 − M0²/2 gives `M0(t) = 2/(1 + e^{−t})`).
#[test]
fn coagulation_fragmentation_event_driven() {
    let e = Exact::coagulation_fragmentation();
    let n = 2048;
    let t = 1.0;
    let k = Coagulation::constant(1.0).unwrap();
    let f = BinaryUniform::new(1.0).unwrap();
    let mut mfa = [Replicas::new(), Replicas::new()];
    let mut dsa = [Replicas::new(), Replicas::new(), Replicas::new()];
    for r in 0..REPS {
        let mut rng = Pcg64Mcg::seed_from_u64(0xc0f ^ r.wrapping_mul(0x9e37_79b9));
        let mut s = Mfa::new(k, f, &vec![1.0; n], 1.0).unwrap();
        s.advance_to(t, &mut rng).unwrap();
        mfa[0].push(s.moment(2.0));
        mfa[1].push(s.moment(3.0));
        let mut s = Dsa::new(k, f, &vec![1.0; n], n as f64, 4 * n).unwrap();
        s.advance_to(t, &mut rng).unwrap();
        approx::assert_relative_eq!(s.moment(1.0), 1.0, max_relative = 1e-12);
        dsa[0].push(s.moment(2.0));
        dsa[1].push(s.moment(3.0));
        dsa[2].push(s.moment(0.0));
    }
    for (name, st, m) in [
        ("mfa M2", &mfa[0], 2),
        ("mfa M3", &mfa[1], 3),
        ("dsa M2", &dsa[0], 2),
        ("dsa M3", &dsa[1], 3),
    ] {
        let want = e.moment(m, t).unwrap();
        let zz = z(st, want);
        std::println!(
            "{name}: {} ± {} vs {want} ({zz:+.2} SE)",
            st.mean(),
            st.std_error()
        );
        assert!(zz.abs() < zmax(), "{name}: {st:?} vs {want}");
    }
    let want0 = 2.0 / (1.0 + libm::exp(-t));
    assert!(
        z(&dsa[2], want0).abs() < zmax(),
        "dsa M0 {:?} vs {want0}",
        dsa[2]
    );
}

/// The mass flow algorithm on the multiplicative kernel with truncation b_N = N: the
/// gel mass `1 − n/N` approaches `1 − 1/t` past the gel point (E–W Fig. 5), and the
/// particles that left are counted.
#[test]
fn mfa_multiplicative_gel_mass() {
    let n = 4096;
    let k = Coagulation::multiplicative();
    let mut s = Mfa::new(k, NoFragmentation, &vec![1.0; n], 1.0)
        .unwrap()
        .with_truncation(n as f64)
        .unwrap();
    let mut rng = Pcg64Mcg::new(3);
    s.advance_to(2.0, &mut rng).unwrap();
    let g = s.gel_mass().unwrap();
    assert!((g - 0.5).abs() < 0.05, "gel mass {g} vs 1/2");
    assert_eq!(s.totals().removed, (n - s.particles() as usize) as u64);
}

/// Refused input: no particle, NaN sizes, a truncation below the largest size, a
/// kernel without a majorant, a capacity too small; a full workspace is a capacity
/// error with the state as it was; a strict bound refuses a kernel above its majorant.
#[test]
fn refused_input_and_capacity() {
    let k = Coagulation::constant(1.0).unwrap();
    assert!(Mfa::new(k, NoFragmentation, &[], 1.0).is_err());
    assert!(Mfa::new(k, NoFragmentation, &[1.0, f64::NAN], 1.0).is_err());
    assert!(Dsa::new(k, NoFragmentation, &[1.0, -1.0], 2.0, 2).is_err());
    assert!(Dsa::new(k, NoFragmentation, &[1.0; 4], 4.0, 3).is_err());
    let m = Mfa::new(k, NoFragmentation, &[1.0, 5.0], 1.0).unwrap();
    assert!(m.with_truncation(4.0).is_err());
    let no_h = |x: f64, y: f64| x + y;
    assert!(matches!(
        Dsa::new(no_h, NoFragmentation, &[1.0; 4], 4.0, 4),
        Err(Error::Unsupported { .. })
    ));
    // fragmentation fills a workspace of capacity 8 from 8 particles: the call that
    // fails (one proposal per call) leaves sizes, time and totals as they were
    let f = BinaryUniform::new(1.0).unwrap();
    let mut s = Dsa::new(k, f, &[1.0; 8], 8.0, 8).unwrap();
    let mut rng = Pcg64Mcg::new(4);
    let failed = one_proposal_at_a_time(&mut s, &mut rng, |s| s.sizes().to_vec());
    assert!(matches!(failed, Error::Capacity { .. }), "{failed:?}");
    // a kernel above its declared majorant: counted, or an error when strict (the
    // state then as before the failing proposal)
    let liar = crate::kernel::UserKernel::new(|_: f64, _: f64| 2.0).with_majorant(|_: f64| 1.0);
    let mut s = Dsa::new(liar.clone(), NoFragmentation, &[1.0; 64], 64.0, 64).unwrap();
    let rep = s.advance_to(1.0, &mut rng).unwrap();
    assert!(rep.bound_violations > 0);
    let mut s = Dsa::new(liar, NoFragmentation, &[1.0; 64], 64.0, 64)
        .unwrap()
        .with_strict_bound(true);
    let failed = one_proposal_at_a_time(&mut s, &mut rng, |s| s.sizes().to_vec());
    assert!(matches!(failed, Error::BoundExceeded { .. }), "{failed:?}");
    // sizes below the kernel's min_size (where its majorant is not guaranteed): refused
    // at the start, and a fragment there fails its event with the state as before
    let k1 = Coagulation::additive().with_min_size(1.0).unwrap();
    assert!(Mfa::new(k1, NoFragmentation, &[0.1, 100.0], 1.0).is_err());
    let mut s = Dsa::new(k1, f, &[1.0; 16], 16.0, 64).unwrap();
    let failed = one_proposal_at_a_time(&mut s, &mut rng, |s| s.sizes().to_vec());
    assert!(matches!(failed, Error::OutOfRange { .. }), "{failed:?}");
    // a fragmentation kernel returning a piece larger than the particle (mass from
    // nothing): an error in both schemes
    let grow = crate::kernel::UserFragmentation::new(|_: f64| 1.0, |x: f64, _: f64| 2.0 * x, None)
        .unwrap();
    let mut m = Mfa::new(k, grow, &[1.0; 4], 1.0).unwrap();
    let failed = one_proposal_at_a_time(&mut m, &mut rng, |s| s.sizes().to_vec());
    assert!(matches!(failed, Error::InvalidRate { .. }), "{failed:?}");
    // one particle cannot coagulate: the DSA idles instead of proposing i = j
    let mut one = Dsa::new(k, NoFragmentation, &[1.0], 1.0, 1).unwrap();
    let rep = one.advance_to(10.0, &mut rng).unwrap();
    assert_eq!((rep.proposals, one.time()), (0, 10.0));
    // a truncation the sum passes removes the particle, even past the largest double
    let mut m = Mfa::new(k, NoFragmentation, &[1.5e308, 1.5e308], 1.5e308)
        .unwrap()
        .with_truncation(1.6e308)
        .unwrap();
    m.advance_to(100.0, &mut rng).unwrap();
    assert!(m.totals().removed > 0);
    // over size counts, a volume so small that the proposal rate overflows a double:
    // an error, the clock as before (not a run of zero waiting times)
    let mut c = DsaCounts::new(k, &[3000, 40], 2.2e-308).unwrap();
    assert!(matches!(
        c.advance_to(1.0, &mut rng),
        Err(Error::InvalidRate { .. })
    ));
    assert_eq!((c.time(), c.counts().into_owned()), (0.0, vec![3000, 40]));
}

/// Steps `s` one proposal per call until a call fails; checks that the failing call
/// left `state`, the time and the totals as they were, and returns its error.
fn one_proposal_at_a_time<S: Scheme + Observe, T: PartialEq + core::fmt::Debug>(
    s: &mut S,
    rng: &mut Pcg64Mcg,
    state: impl Fn(&S) -> T,
) -> Error {
    for _ in 0..1_000_000 {
        let before = (state(s), s.time().to_bits(), s.totals());
        match s.advance_within(1e6, &mut Budget::work(1), rng) {
            Ok(_) => {}
            Err(e) => {
                assert_eq!(
                    (state(s), s.time().to_bits(), s.totals().events),
                    (before.0, before.1, before.2.events)
                );
                return e;
            }
        }
    }
    panic!("no call failed");
}

/// Stopping anywhere — by target times or by a work budget — is the run that went
/// through in one call, bit for bit; a checkpoint in between resumes it.
#[test]
fn split_runs_and_checkpoints_are_the_unbroken_run() {
    let k = Coagulation::additive();
    let f = BinaryUniform::new(0.5).unwrap();
    let n = 256;
    let one = {
        let mut s = Dsa::new(k, f, &vec![1.0; n], n as f64, 4 * n).unwrap();
        s.advance_to(2.0, &mut Pcg64Mcg::new(9)).unwrap();
        s.sizes().to_vec()
    };
    let mut s = Dsa::new(k, f, &vec![1.0; n], n as f64, 4 * n).unwrap();
    let mut rng = Pcg64Mcg::new(9);
    s.advance_to(0.7, &mut rng).unwrap();
    let mut buf = vec![0u8; s.checkpoint_len()];
    s.save_to(&mut buf).unwrap();
    let mut r = Dsa::new(k, f, &vec![1.0; n], n as f64, 4 * n).unwrap();
    r.restore_from(&buf).unwrap();
    let mut rng2 = rng.clone();
    loop {
        let rep = s
            .advance_within(2.0, &mut Budget::work(37), &mut rng)
            .unwrap();
        if !rep.interrupted {
            break;
        }
    }
    assert_eq!(s.sizes(), &one[..]);
    r.advance_to(1.3, &mut rng2).unwrap();
    r.advance_to(2.0, &mut rng2).unwrap();
    assert_eq!(r.sizes(), &one[..]);
    // the same for the mass flow algorithm
    let one = {
        let mut s = Mfa::new(k, f, &vec![1.0; n], 1.0).unwrap();
        s.advance_to(2.0, &mut Pcg64Mcg::new(9)).unwrap();
        s.sizes().to_vec()
    };
    let mut s = Mfa::new(k, f, &vec![1.0; n], 1.0).unwrap();
    let mut rng = Pcg64Mcg::new(9);
    s.advance_to(0.7, &mut rng).unwrap();
    let mut buf = vec![0u8; s.checkpoint_len()];
    s.save_to(&mut buf).unwrap();
    let mut r = Mfa::new(k, f, &vec![1.0; n], 1.0).unwrap();
    r.restore_from(&buf).unwrap();
    r.advance_to(2.0, &mut rng).unwrap();
    assert_eq!(r.sizes(), &one[..]);
    // a corrupted size is refused and changes nothing
    let mut bad = buf.clone();
    // (the last size sits before the sampler's word and the checksum)
    let at = bad.len() - 24;
    bad[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let body = bad.len() - 8;
    let sum = crate::checkpoint::checksum(&bad[..body]);
    bad[body..].copy_from_slice(&sum.to_le_bytes());
    let before = r.sizes().to_vec();
    assert!(r.restore_from(&bad).is_err());
    assert_eq!(r.sizes(), &before[..]);
}

/// Each scheme with the sampler that is not its default (DSA with groups, MFA with the
/// sum tree; the other tests run the defaults): the additive kernel from monomers
/// against its exact M0 and M2 at t = 1 (h = 1 + x spans several binades, h/x more),
/// and a split run through a checkpoint equal to the unbroken one.
#[test]
fn other_samplers_match_the_additive_kernel_and_checkpoint() {
    let k = Coagulation::additive();
    let e = Exact::additive();
    let n = 2048;
    let t = 1.0;
    let mut stats = [
        Replicas::new(),
        Replicas::new(),
        Replicas::new(),
        Replicas::new(),
    ];
    for r in 0..REPS {
        let mut rng = Pcg64Mcg::seed_from_u64(0x96 ^ r.wrapping_mul(0x9e37_79b9));
        let mut s = Dsa::new(k, NoFragmentation, &vec![1.0; n], n as f64, n)
            .unwrap()
            .with_sampler(Sampler::Groups)
            .unwrap();
        s.advance_to(t, &mut rng).unwrap();
        stats[0].push(s.moment(0.0));
        stats[1].push(s.moment(2.0));
        let mut s = Mfa::new(k, NoFragmentation, &vec![1.0; n], 1.0)
            .unwrap()
            .with_sampler(Sampler::SumTree)
            .unwrap();
        s.advance_to(t, &mut rng).unwrap();
        stats[2].push(s.moment(0.0));
        stats[3].push(s.moment(2.0));
    }
    for (name, st, m) in [
        ("dsa M0", &stats[0], 0),
        ("dsa M2", &stats[1], 2),
        ("mfa M0", &stats[2], 0),
        ("mfa M2", &stats[3], 2),
    ] {
        let want = e.moment(m, t).unwrap();
        let zz = z(st, want);
        std::println!(
            "{name}: {} ± {} vs {want} ({zz:+.2} SE)",
            st.mean(),
            st.std_error()
        );
        assert!(zz.abs() < zmax(), "{name}: {st:?} vs {want}");
    }
    // split runs through a checkpoint, with fragmentation (pushes) in the DSA
    let f = BinaryUniform::new(0.5).unwrap();
    let dsa = || {
        Dsa::new(k, f, &vec![1.0; 256], 256.0, 1024)
            .unwrap()
            .with_sampler(Sampler::Groups)
            .unwrap()
    };
    let mut one = dsa();
    one.advance_to(2.0, &mut Pcg64Mcg::new(4)).unwrap();
    let mut s = dsa();
    let mut rng = Pcg64Mcg::new(4);
    s.advance_to(0.9, &mut rng).unwrap();
    let mut buf = vec![0u8; s.checkpoint_len()];
    s.save_to(&mut buf).unwrap();
    let mut r = dsa();
    r.restore_from(&buf).unwrap();
    r.advance_to(2.0, &mut rng).unwrap();
    assert_eq!(r.sizes(), one.sizes());
    assert!(one.totals().events > 100);
    // a group order that is not a permutation is refused, the sim unchanged
    let mut bad = buf.clone();
    let body = bad.len() - 8;
    bad[body - 8..body].copy_from_slice(&u64::MAX.to_le_bytes());
    let sum = crate::checkpoint::checksum(&bad[..body]);
    bad[body..].copy_from_slice(&sum.to_le_bytes());
    let mut r = dsa();
    let before = r.sizes().to_vec();
    assert!(matches!(
        r.restore_from(&bad),
        Err(Error::Checkpoint { what }) if what.contains("permutation")
    ));
    assert_eq!(r.sizes(), &before[..]);
    // a tree-sampled sim refuses it, unchanged
    let mut tree = Dsa::new(k, f, &vec![1.0; 256], 256.0, 1024).unwrap();
    let before = tree.sizes().to_vec();
    assert!(tree.restore_from(&buf).is_err());
    assert_eq!(tree.sizes(), &before[..]);
    let mfa = || {
        Mfa::new(k, f, &vec![1.0; 256], 1.0)
            .unwrap()
            .with_sampler(Sampler::SumTree)
            .unwrap()
    };
    let mut one = mfa();
    one.advance_to(2.0, &mut Pcg64Mcg::new(5)).unwrap();
    let mut s = mfa();
    let mut rng = Pcg64Mcg::new(5);
    s.advance_to(1.1, &mut rng).unwrap();
    let mut buf = vec![0u8; s.checkpoint_len()];
    s.save_to(&mut buf).unwrap();
    let mut r = mfa();
    r.restore_from(&buf).unwrap();
    r.advance_to(2.0, &mut rng).unwrap();
    assert_eq!(r.sizes(), one.sizes());
}

/// Caller-owned workspace: the same run as the owned one.
#[test]
fn caller_workspace_is_the_owned_run() {
    let k = Coagulation::brownian();
    let n = 512;
    let mut ws = vec![0.0; workspace_len(n).unwrap()];
    let mut a = Dsa::new_in(k, NoFragmentation, &vec![1.0; n], n as f64, n, &mut ws[..]).unwrap();
    let mut b = Dsa::new(k, NoFragmentation, &vec![1.0; n], n as f64, n).unwrap();
    a.advance_to(3.0, &mut Pcg64Mcg::new(2)).unwrap();
    b.advance_to(3.0, &mut Pcg64Mcg::new(2)).unwrap();
    assert_eq!(a.sizes(), b.sizes());
    let small = vec![0.0; 10];
    assert!(matches!(
        Mfa::new_in(k, NoFragmentation, &vec![1.0; n], 1.0, small),
        Err(Error::BufferLength { .. })
    ));
}
