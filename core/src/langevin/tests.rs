use super::kernel::{FirstHits, first_hit_kernel, free_flight};
use super::*;
use crate::checkpoint::Checkpoint;
use crate::observe::{TEST_ALPHA, student_t_threshold};
use alloc::vec;
use alloc::vec::Vec;
use approx::assert_abs_diff_eq;

fn rng() -> crate::random::Generator {
    crate::random::generator(3, 0)
}

/// `|mean − exact| < t·SE` at the suite's false-alarm rate.
fn check(name: &str, r: &Replicas, exact: f64) {
    let thr = student_t_threshold(TEST_ALPHA, r.count() - 1);
    let (m, se) = (r.mean(), r.std_error());
    assert!(
        (m - exact).abs() < thr * se,
        "{name}: {m} ± {se} against {exact} (threshold {thr} SE)"
    );
}

fn discrete_ou(x0: f64, u0: f64, gamma: f64, sigma: f64, h: f64, steps: usize) -> [f64; 5] {
    euler_moments(x0, u0, gamma, sigma, h, steps as u64)
}

/// Far from the wall, the batch is the Euler scheme of an Ornstein–Uhlenbeck velocity:
/// its mean, variances and covariance match the scheme's exact moments (a wrong noise
/// factor, a missing √h or a drift applied twice fails by many SE).
#[test]
fn free_motion_has_the_discrete_schemes_moments() {
    let (gamma, sigma, h, steps) = (0.7, 1.3, 0.05, 40);
    let cfg = Config::line(h, sigma, Wall::Specular).unwrap();
    let mut b = Batch::new(
        cfg,
        Friction { rate: gamma },
        20_000,
        ([1e6], [0.5]),
        &mut rng(),
    )
    .unwrap();
    b.advance_to(h * steps as f64).unwrap();
    let [mx, mu, vxx, vxu, vuu] = discrete_ou(1e6, 0.5, gamma, sigma, h, steps);
    check("E x", &b.statistics(|x, _| x[0] - 1e6), mx - 1e6);
    check("E u", &b.statistics(|_, u| u[0]), mu);
    check(
        "Var x",
        &b.statistics(|x, _| (x[0] - mx) * (x[0] - mx)),
        vxx,
    );
    check(
        "Cov x u",
        &b.statistics(|x, u| (x[0] - mx) * (u[0] - mu)),
        vxu,
    );
    check(
        "Var u",
        &b.statistics(|_, u| (u[0] - mu) * (u[0] - mu)),
        vuu,
    );
    assert_eq!(b.totals().events, 0);
}

/// With b = 0 a specular wall is a mirror: the reflected scheme is the free scheme
/// folded, `(X, U) = sign(X_free) (X_free, U_free)` in law, so `E X²`, `E XU`, `E U²`
/// and `E |X|` are the free Gaussian's. Not flipping the velocity, or flipping it
/// without the split noise, changes `E XU` and `E |X|`.
#[test]
fn specular_wall_folds_the_free_motion() {
    let (sigma, h, steps) = (1.0, 0.02, 50);
    let cfg = Config::line(h, sigma, Wall::Specular).unwrap();
    let zero = Scalar(|_, _, _| 0.0);
    let mut b = Batch::new(cfg, zero, 20_000, ([0.3], [-0.8]), &mut rng()).unwrap();
    b.advance_to(h * steps as f64).unwrap();
    let [mx, mu, vxx, vxu, vuu] = discrete_ou(0.3, -0.8, 0.0, sigma, h, steps);
    assert!(b.hit_statistics().mean() > 0.3, "few hits");
    check("E X^2", &b.statistics(|x, _| x[0] * x[0]), vxx + mx * mx);
    check("E XU", &b.statistics(|x, u| x[0] * u[0]), vxu + mx * mu);
    check("E U^2", &b.statistics(|_, u| u[0] * u[0]), vuu + mu * mu);
    check(
        "E |X|",
        &b.statistics(|x, _| x[0]),
        folded_normal_mean(mx, vxx),
    );
    assert!(b.positions().all(|x| x[0] >= 0.0));
}

/// Without noise or drift the path is a billiard: hit at t = 1, velocity flipped, at
/// t = 3 the position is 2; an absorbing wall stops it at 0 with velocity −1.
#[test]
fn deterministic_bounce_and_absorption() {
    for wall in [Wall::Specular, Wall::Absorbing] {
        let cfg = Config::line(0.3, 0.0, wall).unwrap();
        let mut b = Batch::new(cfg, Scalar(|_, _, _| 0.0), 1, ([1.0], [-1.0]), &mut rng()).unwrap();
        let rep = b.advance_to(3.0).unwrap();
        let (x, u) = (
            b.positions().next().unwrap()[0],
            b.velocities().next().unwrap()[0],
        );
        assert_abs_diff_eq!(b.first_hits().next().unwrap(), 1.0, epsilon = 1e-12);
        assert_eq!(rep.events, 1);
        match wall {
            Wall::Specular => {
                assert_abs_diff_eq!(x, 2.0, epsilon = 1e-12);
                assert_eq!(u, 1.0);
                assert_eq!(rep.bounces, 1);
            }
            Wall::Absorbing => {
                assert_eq!((x, u), (0.0, -1.0));
                assert_eq!((rep.removed, b.absorbed()), (1, 1));
                assert_eq!(rep.proposals, 4, "steps stop at the hit");
            }
        }
    }
}

/// A ball in 3-D without noise: the glancing path from (3, 0.5, 0) along −x hits the
/// unit sphere at (√0.75, 0.5, 0), leaves along the mirrored direction, and ends on
/// the exact billiard path whatever the step.
#[test]
fn ball_reflection_is_the_billiard_path() {
    let zero = Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]);
    for dt in [0.7, 0.1, 0.013] {
        let cfg = Config::<3>::ball(1.0, dt, 0.0, Wall::Specular).unwrap();
        let mut b = Batch::new(
            cfg,
            zero,
            1,
            ([3.0, 0.5, 0.0], [-1.0, 0.0, 0.0]),
            &mut rng(),
        )
        .unwrap();
        b.advance_to(4.0).unwrap();
        let c = libm::sqrt(0.75);
        let s = 3.0 - c; // time of the hit
        let n = [c, 0.5, 0.0];
        let v = [-1.0 + 2.0 * c * n[0], 2.0 * c * n[1], 0.0]; // u − 2(u·n)n
        let x = b.positions().next().unwrap();
        let u = b.velocities().next().unwrap();
        for k in 0..3 {
            assert_abs_diff_eq!(x[k], n[k] + (4.0 - s) * v[k], epsilon = 1e-12);
            assert_abs_diff_eq!(u[k], v[k], epsilon = 1e-12);
        }
        assert_abs_diff_eq!(b.first_hits().next().unwrap(), s, epsilon = 1e-12);
    }
}

/// Reflections are isometries and the noise is isotropic: with b = 0,
/// `E |U_T|² = |u0|² + D σ² T` in 2-D and 3-D however often the ball is hit, and no
/// position ends inside the ball.
#[test]
fn ball_keeps_the_velocity_variance() {
    fn run<const D: usize>() {
        let zero = Field(|_, _: &[f64; D], _: &[f64; D]| [0.0; D]);
        let cfg = Config::<D>::ball(1.0, 0.02, 1.0, Wall::Specular).unwrap();
        let mut x0 = [0.0; D];
        x0[0] = 1.2;
        let mut u0 = [0.0; D];
        u0[0] = -2.0;
        let mut b = Batch::new(cfg, zero, 20_000, (x0, u0), &mut rng()).unwrap();
        b.advance_to(1.0).unwrap();
        assert!(b.hit_statistics().mean() > 0.5);
        check("E |U|^2", &b.statistics(|_, u| dot(u, u)), 4.0 + D as f64);
        assert!(
            b.positions()
                .all(|x| libm::sqrt(dot(&x, &x)) >= 1.0 - 1e-12)
        );
    }
    run::<2>();
    run::<3>();
}

/// A trajectory's path depends on its key and id only: a batch split in two (as
/// threads or ranks split it), a run split at grid points, a budgeted run and a
/// checkpointed run all give the same bits as one run.
#[test]
fn splits_budgets_and_checkpoints_give_the_same_bits() {
    let cfg = paper::config(Wall::Specular, 0.1, paper::Choices::default()).unwrap();
    let start = |_| ([0.5], [-1.5]);
    let words = |b: &Batch<1, paper::PaperDrift>| b.records().to_vec();
    let mut whole = Batch::with_starts(cfg, paper::PaperDrift, 100, 9, 0, start).unwrap();
    whole.advance_to(3.2).unwrap();
    // two shares
    let mut a = Batch::with_starts(cfg, paper::PaperDrift, 37, 9, 0, start).unwrap();
    let mut c = Batch::with_starts(cfg, paper::PaperDrift, 63, 9, 37, start).unwrap();
    a.advance_to(3.2).unwrap();
    c.advance_to(3.2).unwrap();
    let mut joined = words(&a);
    joined.extend(words(&c));
    assert_eq!(joined, words(&whole));
    // split calls, a budget, and a checkpoint in the middle
    let mut s = Batch::with_starts(cfg, paper::PaperDrift, 100, 9, 0, start).unwrap();
    s.advance_to(0.7).unwrap();
    let rep = s.advance_within(3.2, &mut Budget::work(250)).unwrap();
    assert!(rep.interrupted && s.time() < 3.2);
    let mut buf = vec![0u8; s.checkpoint_len()];
    s.save_to(&mut buf).unwrap();
    let mut r = Batch::with_starts(cfg, paper::PaperDrift, 100, 1, 0, |_| ([0.9], [0.0])).unwrap();
    r.restore_from(&buf).unwrap();
    while r.time() < 3.2 {
        r.advance_within(3.2, &mut Budget::work(1000)).unwrap();
    }
    assert_eq!(words(&r), words(&whole));
    assert_eq!(r.totals().events, whole.totals().events);
}

/// A drift that returns NaN stops the call with an error and leaves the batch as it
/// was, with and without a budget.
#[test]
fn nan_drift_is_an_error_and_changes_nothing() {
    let bad = Scalar(|t: f64, _, _| if t > 0.45 { f64::NAN } else { 1.0 });
    let cfg = Config::line(0.1, 1.0, Wall::Specular).unwrap();
    for budget in [false, true] {
        let mut b = Batch::new(cfg, bad, 30, ([1.0], [0.0]), &mut rng()).unwrap();
        b.advance_to(0.3).unwrap();
        let before = b.records().to_vec();
        let err = if budget {
            b.advance_within(1.0, &mut Budget::work(1 << 20))
        } else {
            b.advance_to(1.0)
        };
        assert!(matches!(err, Err(Error::InvalidRate { .. })), "{err:?}");
        assert_eq!(b.records(), &before[..]);
        assert_eq!(b.time(), 0.3);
    }
}

/// Bad parameters and starts are errors, not panics.
#[test]
fn bad_input_is_refused() {
    let z = Scalar(|_, _, _| 0.0);
    assert!(Config::line(0.0, 1.0, Wall::Specular).is_err());
    assert!(Config::line(-0.1, 1.0, Wall::Specular).is_err());
    assert!(Config::line(f64::NAN, 1.0, Wall::Specular).is_err());
    assert!(Config::line(0.1, -1.0, Wall::Specular).is_err());
    assert!(Config::line(0.1, f64::INFINITY, Wall::Specular).is_err());
    let cfg = Config::line(0.1, 1.0, Wall::Specular).unwrap();
    assert!(cfg.with_period(0.0).is_err());
    assert!(cfg.with_velocity_bound(VelocityBound::Clamp(-1.0)).is_err());
    assert!(Config::<1>::ball(1.0, 0.1, 1.0, Wall::Specular).is_err());
    assert!(Config::<3>::ball(0.0, 0.1, 1.0, Wall::Specular).is_err());
    assert!(Config::<4>::ball(1.0, 0.1, 1.0, Wall::Specular).is_err());
    let mut r = rng();
    assert!(Batch::new(cfg, z, 0, ([1.0], [0.0]), &mut r).is_err());
    assert!(Batch::new(cfg, z, 5, ([-1.0], [0.0]), &mut r).is_err());
    assert!(Batch::new(cfg, z, 5, ([f64::NAN], [0.0]), &mut r).is_err());
    assert!(Batch::new(cfg, z, 5, ([1.0], [f64::INFINITY]), &mut r).is_err());
    let per = cfg.with_period(1.0).unwrap();
    assert!(Batch::new(per, z, 5, ([1.0], [0.0]), &mut r).is_err());
    let bounded = cfg
        .with_velocity_bound(VelocityBound::Reflect(10.0))
        .unwrap();
    assert!(Batch::new(bounded, z, 5, ([1.0], [11.0]), &mut r).is_err());
    let ball = Config::<3>::ball(1.0, 0.1, 1.0, Wall::Absorbing).unwrap();
    let fz = Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]);
    assert!(Batch::new(ball, fz, 5, ([0.5, 0.0, 0.0], [0.0; 3]), &mut r).is_err());
    let mut small = vec![0u64; workspace_len(3, 5).unwrap() - 1];
    assert!(matches!(
        Batch::with_starts_in(
            ball,
            fz,
            5,
            1,
            0,
            |_| ([2.0, 0.0, 0.0], [0.0; 3]),
            &mut small[..]
        ),
        Err(Error::BufferLength { .. })
    ));
    assert!(
        Batch::with_starts(ball, fz, 5, 1, u64::MAX - 2, |_| (
            [2.0, 0.0, 0.0],
            [0.0; 3]
        ))
        .is_err()
    );
    let mut b = Batch::new(cfg, z, 5, ([1.0], [0.0]), &mut r).unwrap();
    b.advance_to(1.0).unwrap();
    assert!(b.advance_to(0.5).is_err());
    assert!(b.advance_to(f64::NAN).is_err());
    // a checkpoint of another size, or a corrupted one, is refused and changes nothing
    let mut buf = vec![0u8; b.checkpoint_len()];
    b.save_to(&mut buf).unwrap();
    let mut other = Batch::new(cfg, z, 6, ([1.0], [0.0]), &mut r).unwrap();
    let before = other.records().to_vec();
    assert!(other.restore_from(&buf).is_err());
    buf[40] ^= 1;
    assert!(b.restore_from(&buf).is_err());
    assert_eq!(other.records(), &before[..]);
}

/// Richardson–Romberg arithmetic: `2 fine − coarse`, SE `√(4 SE_f² + SE_c²)`; on the
/// free Ornstein–Uhlenbeck scheme, whose bias is known exactly, it cancels the first
/// order: `Var u` at h and h/2 extrapolate to within O(h²) of the exact variance.
#[test]
fn richardson_romberg_cancels_the_first_order() {
    let mut c = Replicas::new();
    let mut f = Replicas::new();
    for v in [1.0, 3.0] {
        c.push(v);
    }
    for v in [2.0, 2.5, 3.0] {
        f.push(v);
    }
    let e = richardson_romberg(&c, &f);
    assert_abs_diff_eq!(e.mean, 2.0 * 2.5 - 2.0, epsilon = 1e-15);
    let se = libm::sqrt(4.0 * f.variance() / 3.0 + c.variance() / 2.0);
    assert_abs_diff_eq!(e.std_error, se, epsilon = 1e-15);
    // exact stationary variance σ²/(2γ) vs the scheme's σ²h/(1 − (1 − γh)²)
    let (g, s) = (1.0, 1.0);
    let exact = s * s / (2.0 * g);
    let bias = |h: f64| discrete_ou(0.0, 0.0, g, s, h, (400.0 / h) as usize)[4] - exact;
    for h in [0.2, 0.1, 0.05] {
        let rr = 2.0 * bias(h / 2.0) - bias(h);
        assert!(bias(h).abs() > 0.2 * h, "first-order bias {}", bias(h));
        assert!(rr.abs() < 0.3 * h * h, "h = {h}: RR bias {rr}");
    }
}

/// First hits of free flights (σ = 0, b = 0) from a uniform gas with Maxwellian
/// velocities give the gas-kinetic kernel `π R² ⟨|v|⟩` (3-D) or `2 R ⟨|v|⟩` (2-D)
/// exactly: the estimator's weights, geometry and window are right to the factor.
#[test]
fn first_hits_of_free_flights_give_the_kinetic_kernel() {
    let p = FirstHits {
        radius: 0.5,
        outer: 0.5 + 1.0 * 9.0,
        from: 0.4,
        to: 1.0,
        dt: 0.07,
        sigma: 0.0,
        velocity_sd: 1.0,
        trajectories: 40_000,
    };
    let k3 = first_hit_kernel::<3, _>(&p, &Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]), 5, 0)
        .unwrap();
    check("3-D free flight", &k3.replicas, free_flight(3, 0.5, 1.0));
    assert!(k3.hits > 100);
    let k2 = first_hit_kernel::<2, _>(&p, &Field(|_, _: &[f64; 2], _: &[f64; 2]| [0.0; 2]), 5, 0)
        .unwrap();
    check("2-D free flight", &k2.replicas, free_flight(2, 0.5, 1.0));
    // shares with disjoint ids merge to the whole
    let half = FirstHits {
        trajectories: 20_000,
        ..p
    };
    let zero3 = Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]);
    let mut a = first_hit_kernel::<3, _>(&half, &zero3, 5, 0)
        .unwrap()
        .replicas;
    let b = first_hit_kernel::<3, _>(&half, &zero3, 5, 20_000)
        .unwrap()
        .replicas;
    a.merge(&b);
    assert_abs_diff_eq!(
        a.mean(),
        k3.replicas.mean(),
        epsilon = 1e-12 * k3.replicas.mean()
    );
    assert!(first_hit_kernel::<3, _>(&FirstHits { outer: 0.4, ..p }, &zero3, 5, 0).is_err());
    assert!(first_hit_kernel::<3, _>(&FirstHits { to: 0.4, ..p }, &zero3, 5, 0).is_err());
}

/// `cos_2pi` is `cos(2πx)` to 1e-15 over a sweep of arguments (against `libm::cos` of
/// the exactly reduced argument, whose own rounding of 2πr is up to 4.4e-16), exact at the quarter
/// points, and NaN for NaN.
#[test]
fn cos_2pi_matches_libm() {
    let mut worst: f64 = 0.0;
    let mut g = rng();
    let mut xs: Vec<f64> = (0..200_000)
        .map(|_| 40.0 * (crate::random::unit_f64(g.next_u64()) - 0.5))
        .collect();
    xs.extend([
        0.0,
        0.25,
        0.5,
        0.75,
        1.0,
        -0.25,
        1e-300,
        0.125,
        3.999_999_999_999,
    ]);
    for x in xs {
        // the reference reduces exactly too (2π x itself rounds by ~1e-14 at |x| = 20)
        let r = x - (x as i64) as f64;
        let e = (paper::cos_2pi(x) - libm::cos(core::f64::consts::TAU * r)).abs();
        worst = worst.max(e);
    }
    assert!(worst < 1e-15, "worst {worst}");
    assert_eq!(paper::cos_2pi(0.0), 1.0);
    assert_eq!(paper::cos_2pi(1e17), 1.0);
    assert!(paper::cos_2pi(f64::NAN).is_nan());
    assert!(paper::cos_2pi(f64::INFINITY).is_nan());
}

/// Found by review: a budgeted call to a target that snaps onto the grid point the
/// batch stands at reaches it (a host looping `while time() < t` would spin); a target
/// beyond 2^52 steps is an error, not a hang; a huge velocity outside a ball is an
/// error, not a pass through the ball.
#[test]
fn edge_targets_and_velocities_are_handled() {
    let cfg = Config::line(0.1, 1.0, Wall::Specular).unwrap();
    let mut b = Batch::new(cfg, Scalar(|_, _, _| 0.0), 4, ([1.0], [0.0]), &mut rng()).unwrap();
    b.advance_to(0.3).unwrap();
    let t = 3.0 * 0.1; // 0.30000000000000004
    let rep = b.advance_within(t, &mut Budget::work(100)).unwrap();
    assert!(!rep.interrupted);
    assert_eq!(b.time(), t);
    assert!(matches!(b.advance_to(1e300), Err(Error::OutOfRange { .. })));
    assert_eq!(b.time(), t);
    let ball = Config::<3>::ball(1.0, 0.1, 0.0, Wall::Specular).unwrap();
    let zero = Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]);
    let mut fast = Batch::new(
        ball,
        zero,
        1,
        ([3.0, 0.0, 0.0], [-1e200, 0.0, 0.0]),
        &mut rng(),
    )
    .unwrap();
    assert!(fast.advance_to(1.0).is_err());
    assert_eq!(fast.positions().next().unwrap(), [3.0, 0.0, 0.0]);
}

/// Found by review: a crafted checkpoint (a position outside the domain, a time beyond
/// 2^52 steps) is refused and the batch is unchanged.
#[test]
fn crafted_checkpoints_are_refused() {
    let cfg = paper::config(Wall::Specular, 0.1, paper::Choices::default()).unwrap();
    let mut b = Batch::with_starts(cfg, paper::PaperDrift, 3, 9, 0, |_| ([0.5], [-1.5])).unwrap();
    b.advance_to(1.0).unwrap();
    let before = b.records().to_vec();
    let mut w = crate::checkpoint::Writer::new(&mut []);
    b.save(&mut w);
    let n = w.needed();
    let mut buf = vec![0u8; n];
    let mut w = crate::checkpoint::Writer::new(&mut buf);
    b.save(&mut w);
    // the layout: header (3), D, n, dt, sigma, wall, radius, period, bound kind and
    // value, key, first id, time, report (7), removed, bounces, length, records
    let words = |buf: &[u8]| -> Vec<u64> {
        buf.chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let put =
        |buf: &mut [u8], i: usize, v: u64| buf[8 * i..8 * i + 8].copy_from_slice(&v.to_le_bytes());
    assert_eq!(words(&buf)[14], 1.0f64.to_bits(), "time at word 14");
    let rec0 = 3 + 12 + 7 + 2 + 1;
    let mut outside = buf.clone();
    put(&mut outside, rec0, (-0.5f64).to_bits());
    let mut late = buf.clone();
    put(&mut late, 14, 1e300f64.to_bits());
    put(&mut late, 15, 1e300f64.to_bits());
    for bad in [outside, late] {
        let mut r = crate::checkpoint::Reader::new(&bad);
        assert!(b.restore(&mut r).is_err());
        assert_eq!(b.records(), &before[..]);
    }
    let mut r = crate::checkpoint::Reader::new(&buf);
    b.restore(&mut r).unwrap();
    assert_eq!(b.records(), &before[..]);
}
