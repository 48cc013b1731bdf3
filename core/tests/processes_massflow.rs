//! Sources, removal and growth in the time-driven mass flow (issue 42; the update is
//! `core/src/scheme/massflow/processes.rs`): the books balance to rounding, exact
//! solutions are met once the step's O(Δt) bias is removed by Richardson extrapolation
//! (every replica run at Δt and Δt/2 with the same seed, `2 m(Δt/2) − m(Δt)`), a split
//! run through a checkpoint keeps its bits, and hostile parameters give errors that
//! leave the state as it was.

use crate::common;

use coagula_core::exact::Balance;
use coagula_core::initial::Distribution;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::{Replicas, student_t_threshold};
use coagula_core::process::{Processes, Source};
use coagula_core::scheme::facade::{Init, Model, Options, Points};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// A massflow sim of the sizes `x` (mass `mass`) at step `dt` on `points`.
fn sim(k: f64, x: &[f64], mass: f64, dt: f64, points: Points) -> Box<common::Sim> {
    let info = registry::find("massflow").unwrap();
    let model = Model::coagulation(Coagulation::constant(k).unwrap(), NoFragmentation);
    let opts = Options::default().with_dt(dt).with_points(points);
    registry::build(info, model, &Init::Sizes { sizes: x, mass }, &opts).unwrap()
}

/// `n` sizes, a share `a` of them (so of the mass) at size `lo`, the rest at `hi`.
fn two_sizes(n: usize, a: f64, lo: f64, hi: f64) -> Vec<f64> {
    let k = (a * n as f64) as usize;
    (0..n).map(|i| if i < k { lo } else { hi }).collect()
}

/// Replica means of M0, M1, M2 at `t` from the sizes `x` (mass 1) under the kernel
/// `K = k` and `procs`, on Monte Carlo points, Richardson-extrapolated from Δt = 0.02
/// and 0.01.
fn extrapolated(k: f64, x: &[f64], procs: &Processes, t: f64) -> [Replicas; 3] {
    let dt = 0.02;
    let mut out = [Replicas::new(), Replicas::new(), Replicas::new()];
    for r in 0..REPS {
        let mut m = [[0.0; 3]; 2];
        for (j, h) in [dt, dt / 2.0].into_iter().enumerate() {
            let mut s = sim(k, x, 1.0, h, Points::MonteCarlo);
            s.set_processes(Some(procs.clone())).unwrap();
            s.advance_to(t, &mut Pcg64Mcg::seed_from_u64(0x4d46 + r))
                .unwrap();
            for (o, v) in m[j].iter_mut().enumerate() {
                *v = s.moment(o as f64);
            }
        }
        for o in 0..3 {
            out[o].push(2.0 * m[1][o] - m[0][o]);
        }
    }
    out
}

/// Student t at 1e-7 per check (the suite's family is full at 1e-6 per check:
/// `docs/design/statistical-tests.md`).
fn check(what: &str, st: &[Replicas], want: &[f64], reps: u64) {
    check_orders(what, &[0, 1, 2], st, want, reps);
}

/// [`check`] of the moments of the given orders.
fn check_orders(what: &str, orders: &[usize], st: &[Replicas], want: &[f64], reps: u64) {
    let z = student_t_threshold(1e-7, reps - 1);
    for ((st, &want), &o) in st.iter().zip(want).zip(orders) {
        if st.std_error() == 0.0 {
            // M1 is the same in every replica: the mass update is deterministic (a
            // quadrature of the processes' mass rates over the sizes, which do not
            // move it when only coagulation does); what remains after the
            // extrapolation is O(Δt²), here below 1e-5 of it
            let rel = (st.mean() - want).abs() / want.abs();
            println!(
                "{what} M{o}: {} vs {want} (deterministic, {rel:.1e})",
                st.mean()
            );
            assert!(rel <= 1e-5, "{what} M{o}: {} vs exact {want}", st.mean());
            continue;
        }
        let zz = (st.mean() - want) / st.std_error();
        println!(
            "{what} M{o}: {} ± {} vs {want} ({zz:+.2} SE)",
            st.mean(),
            st.std_error()
        );
        assert!(
            zz.abs() <= z,
            "{what} M{o}: {} vs exact {want} ({zz:.1} SE > {z:.2})",
            st.mean()
        );
    }
}

const REPS: u64 = 16;
const N: usize = 4096;

/// The constant kernel with a monomer source and dilution: the closed form of the
/// moment equations (`exact::Balance`).
#[test]
fn a_source_and_dilution_follow_the_closed_form() {
    let (s, lambda, t) = (0.5, 0.25, 2.0);
    let procs = Processes::default()
        .with_source(Source::new(s, Distribution::Monodisperse { size: 1.0 }).unwrap())
        .with_removal(lambda, 0.0)
        .unwrap();
    let x = vec![1.0; N];
    let st = extrapolated(1.0, &x, &procs, t);
    let e = Balance::new(1.0, [1.0, 1.0, 1.0], s, 1.0, lambda, 0.0).unwrap();
    let want = [0, 1, 2].map(|m| e.moment(m, t).unwrap());
    check("source + dilution", &st, &want, REPS);
}

/// Linear growth `dx/dt = g x` with the constant kernel: M0 as without growth,
/// `M1 = M1(0) e^{gt}` (every particle's mass grows alike: no jumps).
#[test]
fn linear_growth_scales_the_mass() {
    let (g, t) = (0.3, 1.5);
    let procs = Processes::default().with_growth(g, 1.0).unwrap();
    let x = vec![1.0; N];
    let st = extrapolated(1.0, &x, &procs, t);
    let e = Balance::new(1.0, [1.0, 1.0, 1.0], 0.0, 1.0, 0.0, g).unwrap();
    let m0 = e.moment(0, t).unwrap();
    let m1 = e.moment(1, t).unwrap();
    assert!((m1 - libm::exp(g * t)).abs() < 1e-12);
    // (no closed form of M2 with growth here: M0 and M1 only)
    check("linear growth", &st[..2], &[m0, m1], REPS);
}

/// Size-dependent removal alone (coagulation off: K = 1e-12), from equal masses at
/// sizes 1 and 3: `n(x, t) = n(x, 0) e^{−λ(x) t}`, which needs the jumps between the
/// two sizes (γ differs).
#[test]
fn size_dependent_removal_is_exponential_per_size() {
    let (c, t) = (0.4, 2.0);
    let procs = Processes::default().with_removal(c, 1.0).unwrap();
    let x = two_sizes(N, 0.5, 1.0, 3.0);
    let st = extrapolated(1e-12, &x, &procs, t);
    // mass 1/2 at each size: number 1/2 and 1/6
    let (a, b) = (0.5 * libm::exp(-c * t), 0.5 * libm::exp(-3.0 * c * t));
    let want = [a + b / 3.0, a + b, a + 3.0 * b];
    check("removal c x", &st, &want, REPS);
}

/// Constant growth `dx/dt = g` alone (coagulation off), from equal masses at sizes 1
/// and 3: every size moves by `g t`, the number stays, `M1 = M1(0) + g t M0`.
#[test]
fn constant_growth_moves_every_size() {
    let (g, t) = (0.5, 2.0);
    let procs = Processes::default().with_growth(g, 0.0).unwrap();
    let x = two_sizes(N, 0.5, 1.0, 3.0);
    let st = extrapolated(1e-12, &x, &procs, t);
    // numbers 1/2 at 1 and 1/6 at 3, moved to 1 + g t and 3 + g t
    let (n1, n3, d) = (0.5, 1.0 / 6.0, g * t);
    let want = [
        n1 + n3,
        n1 * (1.0 + d) + n3 * (3.0 + d),
        n1 * (1.0 + d) * (1.0 + d) + n3 * (3.0 + d) * (3.0 + d),
    ];
    check("growth g", &st, &want, REPS);
}

/// A source with an exponential size distribution alone (coagulation off): `M0 = M0(0)
/// + S t`, `M1 = M1(0) + S μ t`, `M2 = M2(0) + 2 S μ² t` — the injected sizes come
/// from the mass distribution (`Γ(2)`), not the number distribution.
#[test]
fn an_exponential_source_injects_its_moments() {
    let (s, mu, t) = (0.8, 2.0, 1.5);
    let procs = Processes::default()
        .with_source(Source::new(s, Distribution::Exponential { mean: mu }).unwrap());
    let x = vec![1.0; N];
    let st = extrapolated(1e-12, &x, &procs, t);
    let want = [1.0 + s * t, 1.0 + s * mu * t, 1.0 + 2.0 * s * mu * mu * t];
    check("exponential source", &st, &want, REPS);
}

/// The books: the mass the scheme carries is `initial + injected − removed + grown`
/// to rounding, after every call, on every process set and on QMC and MC points; the
/// number is the scheme's N (mass-flow particles are never injected or removed).
#[test]
fn the_books_balance_to_rounding() {
    let src = Source::new(
        0.5,
        Distribution::Lognormal {
            median: 2.0,
            gsd: 1.5,
        },
    )
    .unwrap();
    let cases = [
        Processes::default().with_source(src.clone()),
        Processes::default().with_removal(0.3, 0.5).unwrap(),
        Processes::default().with_growth(0.2, 1.0 / 3.0).unwrap(),
        Processes::default()
            .with_source(src)
            .with_removal(0.3, -0.5)
            .unwrap()
            .with_growth(0.2, 2.0 / 3.0)
            .unwrap(),
    ];
    for points in [Points::Niederreiter, Points::MonteCarlo] {
        for (i, p) in cases.iter().enumerate() {
            let x = two_sizes(1024, 0.3, 1.0, 5.0);
            let mut s = sim(1.0, &x, 2.0, 0.05, points);
            s.set_processes(Some(p.clone())).unwrap();
            let mut g = Pcg64Mcg::seed_from_u64(5);
            for k in 1..=10 {
                s.advance_to(0.3 * f64::from(k), &mut g).unwrap();
                let b = s.books().unwrap();
                let m1 = s.moment(1.0);
                assert!(
                    (b.current_mass() - m1).abs() <= 1e-12 * m1,
                    "case {i} {points:?}: books {} vs M1 {m1}",
                    b.current_mass()
                );
                assert_eq!(b.current_number(), 1024);
                assert_eq!(b.initial_mass, 2.0);
            }
            let b = s.books().unwrap();
            assert!(
                b.injected_mass + b.removed_mass + b.grown_mass > 0.1,
                "case {i}: {b:?}"
            );
            assert!(s.totals().events > 0);
        }
    }
}

/// Same seed, same bits; a run split through a checkpoint at any call gives the bits
/// of the unbroken run.
#[test]
fn split_runs_through_checkpoints_keep_their_bits() {
    let p = Processes::default()
        .with_source(Source::new(0.5, Distribution::Exponential { mean: 1.5 }).unwrap())
        .with_removal(0.2, 1.0)
        .unwrap()
        .with_growth(0.1, 0.5)
        .unwrap();
    // (Δt and the split times in binary, so that the clock adds up exactly: a run
    // split off a multiple of Δt takes a shorter step there, as without processes)
    for points in [Points::Niederreiter, Points::MonteCarlo] {
        let x = two_sizes(512, 0.5, 1.0, 2.0);
        let run = |split: Option<f64>| {
            let mut s = sim(1.0, &x, 1.0, 0.03125, points);
            s.set_processes(Some(p.clone())).unwrap();
            let mut g = Pcg64Mcg::seed_from_u64(9);
            if let Some(at) = split {
                s.advance_to(at, &mut g).unwrap();
                let buf = crate::processes::checkpoint(&*s);
                let mut fresh = sim(1.0, &[7.0; 512], 3.0, 0.03125, points);
                fresh.set_processes(Some(p.clone())).unwrap();
                fresh.restore_checkpoint(&buf).unwrap();
                s = fresh;
            }
            s.advance_to(2.0, &mut g).unwrap();
            let mut bits = common::state_bits(&*s);
            let b = s.books().unwrap();
            bits.extend([b.injected_mass, b.removed_mass, b.grown_mass].map(f64::to_bits));
            bits.push(s.moment(1.0).to_bits());
            bits
        };
        let whole = run(None);
        assert!(whole == run(None), "{points:?}: same seed");
        for at in [0.03125, 0.625, 1.25] {
            let split = run(Some(at));
            let first = whole.iter().zip(&split).position(|(a, b)| a != b);
            assert!(
                whole == split,
                "{points:?}: split at {at}: first difference at {first:?} of {}",
                whole.len()
            );
        }
        // and a checkpoint written without processes is refused by a sim with them
        let plain = sim(1.0, &x, 1.0, 0.03125, points);
        let buf = crate::processes::checkpoint(&*plain);
        let mut with = sim(1.0, &x, 1.0, 0.03125, points);
        with.set_processes(Some(p.clone())).unwrap();
        assert!(with.restore_checkpoint(&buf).is_err());
    }
}

/// Hostile parameters: an error, and the state, mass and books as they were.
#[test]
fn a_refused_step_leaves_the_state_as_it_was() {
    let x = two_sizes(256, 0.5, 1.0, 2.0);
    // a removal that empties the population within a step, a growth that overflows,
    // a source of sizes near the largest double
    let cases = [
        Processes::default().with_removal(1e300, 0.0).unwrap(),
        Processes::default().with_growth(1e300, 1.0).unwrap(),
        Processes::default()
            .with_source(Source::new(1e300, Distribution::Monodisperse { size: 1e300 }).unwrap()),
    ];
    for (i, p) in cases.iter().enumerate() {
        let mut s = sim(1.0, &x, 1.0, 0.1, Points::MonteCarlo);
        s.set_processes(Some(p.clone())).unwrap();
        let before = common::state_bits(&*s);
        let (m1, books) = (s.moment(1.0), s.books().unwrap());
        let r = s.advance_to(1.0, &mut Pcg64Mcg::seed_from_u64(1));
        assert!(r.is_err(), "case {i}: {r:?}");
        let mut after = common::state_bits(&*s);
        // (the totals may count the refused step's start; the sizes, clock and mass
        // may not move)
        after.truncate(before.len() - 8);
        assert_eq!(&before[..before.len() - 8], &after[..], "case {i}");
        assert_eq!(s.moment(1.0).to_bits(), m1.to_bits(), "case {i}");
        assert_eq!(s.books().unwrap(), books, "case {i}");
    }
}

/// With growth every size moves: the step marks the particles it moved and the
/// adaptive re-sort merges them into the grown rest; a full sort of the same sizes
/// gives the same bits (QMC and MC points, a power and a host's growth rate).
#[test]
fn the_adaptive_resort_keeps_the_bits_of_a_full_sort() {
    use coagula_core::process::UserRate;
    use coagula_core::scheme::facade::Sorting;
    let host = UserRate::new(|x| 0.1 + 0.05 * x.sqrt(), 1e6, 7).unwrap();
    let cases = [
        Processes::default().with_growth(0.2, 2.0 / 3.0).unwrap(),
        Processes::default()
            .with_user_growth(host)
            .with_removal(0.1, 1.0)
            .unwrap(),
    ];
    for points in [Points::Niederreiter, Points::MonteCarlo] {
        for (i, p) in cases.iter().enumerate() {
            let x = two_sizes(1024, 0.5, 1.0, 4.0);
            let run = |sorting| {
                let info = registry::find("massflow").unwrap();
                let model =
                    Model::coagulation(Coagulation::constant(1.0).unwrap(), NoFragmentation);
                let opts = Options::default()
                    .with_dt(0.05)
                    .with_points(points)
                    .with_sorting(sorting);
                let init = Init::Sizes {
                    sizes: &x,
                    mass: 1.0,
                };
                let mut s: Box<common::Sim> = registry::build(info, model, &init, &opts).unwrap();
                s.set_processes(Some(p.clone())).unwrap();
                s.advance_to(2.0, &mut Pcg64Mcg::seed_from_u64(3)).unwrap();
                common::state_bits(&*s)
            };
            assert!(
                run(Sorting::Adaptive) == run(Sorting::Full),
                "case {i} {points:?}"
            );
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Arbitrary process parameters, Δt and points on the mass flow (with a
    /// fragmentation-free constant kernel): a constructor or `set_processes` refuses,
    /// or the sim runs under a work limit; a refused advance or a checkpoint with one
    /// byte changed leaves the sizes, M1 and the books as they were.
    #[test]
    fn the_mass_flow_never_panics_with_processes(
        rate in crate::processes::hostile(),
        kind in 0usize..3,
        p1 in crate::processes::hostile(),
        p2 in crate::processes::hostile(),
        c in crate::processes::hostile(),
        p in crate::processes::hostile(),
        g in crate::processes::hostile(),
        q in crate::processes::hostile(),
        t in crate::processes::hostile(),
        dt in 1e-3f64..2.0,
        qmc in proptest::prelude::any::<bool>(),
        flip in proptest::prelude::any::<usize>(),
        value in proptest::prelude::any::<u8>(),
    ) {
        let sizes = match kind {
            0 => Distribution::Monodisperse { size: p1 },
            1 => Distribution::Exponential { mean: p1 },
            _ => Distribution::Lognormal { median: p1, gsd: p2 },
        };
        let mut procs = Processes::default();
        if let Ok(s) = Source::new(rate, sizes) {
            procs = procs.with_source(s);
        }
        if let Ok(r) = procs.clone().with_removal(c, p) {
            procs = r;
        }
        if let Ok(r) = procs.clone().with_growth(g, q) {
            procs = r;
        }
        let points = if qmc { Points::Niederreiter } else { Points::MonteCarlo };
        let mut s = sim(1.0, &two_sizes(64, 0.5, 1.0, 3.0), 1.0, dt, points);
        let before = common::state_bits(&*s);
        if s.set_processes(Some(procs)).is_err() {
            proptest::prop_assert_eq!(common::state_bits(&*s), before);
            return Ok(());
        }
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let t = if t.is_finite() { t.clamp(-1.0, 3.0) } else { t };
        let (m1, books) = (s.moment(1.0), s.books());
        let sizes = common::state_bits(&*s);
        let r = s.advance_within(t, &mut coagula_core::scheme::Budget::work(20_000), &mut rng);
        if r.is_err() && s.time() == 0.0 {
            // refused at the first step: nothing moved
            proptest::prop_assert_eq!(s.moment(1.0).to_bits(), m1.to_bits());
            proptest::prop_assert_eq!(s.books(), books);
            let now = common::state_bits(&*s);
            proptest::prop_assert_eq!(&now[..now.len() - 8], &sizes[..sizes.len() - 8]);
        }
        if let Some(b) = s.books() {
            let m1 = s.moment(1.0);
            proptest::prop_assert!((b.current_mass() - m1).abs() <= 1e-9 * m1.abs().max(1e-300));
        }
        common::corrupted_checkpoint(&mut *s, flip, value, &mut rng)?;
    }
}

/// A listed source (sizes 1 and 3, drawn uniformly) alone: its mass distribution puts
/// 1/4 of the injected mass at 1 and 3/4 at 3, so `M0 = 1 + S t`, `M2 = 1 + 5 S t`;
/// and a schedule whose change falls inside a step: M1 (deterministic) gains exactly
/// `μ ∫ S`.
#[test]
fn listed_and_scheduled_sources_inject_their_moments() {
    let (s, t) = (0.6, 1.5);
    let listed = Processes::default()
        .with_source(Source::new(s, Distribution::Sizes(vec![1.0, 3.0])).unwrap());
    let x = vec![1.0; N];
    let st = extrapolated(1e-12, &x, &listed, t);
    check_orders(
        "listed source",
        &[0, 2],
        &[st[0], st[2]],
        &[1.0 + s * t, 1.0 + 5.0 * s * t],
        REPS,
    );
    // S = 0.6 until 0.513, then 2.0: ∫_0^1.5 S = 0.3078 + 1.974
    let scheduled = Processes::default().with_source(
        Source::new(s, Distribution::Monodisperse { size: 2.0 })
            .unwrap()
            .with_schedule(&[0.513], &[2.0])
            .unwrap(),
    );
    let mut m = sim(1.0, &x, 1.0, 0.02, Points::Niederreiter);
    m.set_processes(Some(scheduled)).unwrap();
    m.advance_to(t, &mut Pcg64Mcg::seed_from_u64(1)).unwrap();
    let want = 1.0 + 2.0 * (0.6 * 0.513 + 2.0 * (1.5 - 0.513));
    assert!(
        (m.moment(1.0) - want).abs() < 1e-12 * want,
        "{} vs {want}",
        m.moment(1.0)
    );
}

/// QMC points drive the processes too: the source–dilution case from 2^14 particles,
/// Richardson-extrapolated in Δt, within 1e-3 of the closed form in M0 (one
/// deterministic run; Monte Carlo's one-replica spread here is 5e-3).
#[test]
fn qmc_points_meet_the_closed_form() {
    let (s, lambda, t) = (0.5, 0.25, 2.0);
    let procs = Processes::default()
        .with_source(Source::new(s, Distribution::Monodisperse { size: 1.0 }).unwrap())
        .with_removal(lambda, 0.0)
        .unwrap();
    let x = vec![1.0; 1 << 14];
    let m0 = [0.02, 0.01].map(|h| {
        let mut m = sim(1.0, &x, 1.0, h, Points::Niederreiter);
        m.set_processes(Some(procs.clone())).unwrap();
        m.advance_to(t, &mut Pcg64Mcg::seed_from_u64(1)).unwrap();
        m.moment(0.0)
    });
    let e = Balance::new(1.0, [1.0, 1.0, 1.0], s, 1.0, lambda, 0.0).unwrap();
    let want = e.moment(0, t).unwrap();
    let got = 2.0 * m0[1] - m0[0];
    println!("QMC M0: {got} vs {want}");
    assert!((got - want).abs() < 1e-3 * want, "{got} vs {want}");
}

/// Steps outside the scheme's first-order regime are refused, the state unchanged: a
/// removal that takes nearly all the mass in one step, and rates whose log-factors
/// differ by more than 1 between sizes (the jump probabilities would clip).
#[test]
fn stiff_steps_are_refused() {
    let x = two_sizes(256, 0.5, 1.0, 100.0);
    for (what, p) in [
        (
            "removed share",
            Processes::default().with_removal(20.0, 0.0).unwrap(),
        ),
        (
            "spread",
            Processes::default().with_removal(1.0, 1.0).unwrap(),
        ),
    ] {
        let mut s = sim(1.0, &x, 1.0, 1.0, Points::MonteCarlo);
        s.set_processes(Some(p)).unwrap();
        let before = common::state_bits(&*s);
        let e = s
            .advance_to(1.0, &mut Pcg64Mcg::seed_from_u64(1))
            .unwrap_err();
        assert!(e.to_string().contains("smaller dt"), "{what}: {e}");
        let after = common::state_bits(&*s);
        assert_eq!(
            &before[..before.len() - 8],
            &after[..after.len() - 8],
            "{what}"
        );
        // and a smaller step goes through
        s.set_dt(if what == "spread" { 0.005 } else { 0.05 })
            .unwrap();
        s.advance_to(1.0, &mut Pcg64Mcg::seed_from_u64(1)).unwrap();
    }
}
