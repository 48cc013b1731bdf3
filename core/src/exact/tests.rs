//! The exact solutions' own checks.

use super::*;

/// Σ k^m n_k summed until the terms are negligible (with a k^{-3/2}-tail estimate
/// for post-gel Flory, whose terms decay as a power law).
fn summed_moment(e: &Exact, m: i32, t: f64, kmax: u64) -> f64 {
    let mut s = 0.0;
    for k in 1..=kmax {
        s += libm::pow(k as f64, m as f64) * e.number_density(k, t).unwrap();
    }
    s
}

#[test]
fn moments_agree_with_summed_densities() {
    let cases: [(Exact, f64, u64); 7] = [
        (Exact::constant(1.0).unwrap(), 2.0, 4000),
        (Exact::constant(2.5).unwrap(), 0.7, 4000),
        (Exact::additive(), 0.5, 4000),
        (Exact::additive(), 1.5, 200_000),
        (Exact::multiplicative(), 0.5, 4000),
        (Exact::marcus_lushnikov(), 2.0, 4000),
        (Exact::marcus_lushnikov(), 4.0, 4000),
    ];
    for (e, t, kmax) in cases {
        for m in 0..=3 {
            let exact = e.moment(m, t).unwrap();
            let sum = summed_moment(&e, m as i32, t, kmax);
            assert!(
                (sum - exact).abs() <= 1e-9 * exact,
                "{e:?} t={t} M{m}: sum {sum} vs closed form {exact}"
            );
        }
    }
}

#[test]
fn flory_post_gel_moments_agree_with_sums_and_tail() {
    // n_k ~ e^{-k} k^{k-2}/k! / t ~ k^{-5/2} / (t √(2π)): the tails of M0 and M1
    // beyond K are ≈ (2/3) K^{-3/2} / (t√(2π)) and 2 K^{-1/2} / (t√(2π)).
    let e = Exact::multiplicative();
    let t = 2.0;
    let kmax = 1_000_000u64;
    let c = 1.0 / (t * libm::sqrt(2.0 * core::f64::consts::PI));
    let kf = kmax as f64 + 0.5;
    let m0 = summed_moment(&e, 0, t, kmax) + c * (2.0 / 3.0) * libm::pow(kf, -1.5);
    let m1 = summed_moment(&e, 1, t, kmax) + c * 2.0 * libm::pow(kf, -0.5);
    assert!((m0 - e.moment(0, t).unwrap()).abs() < 1e-8, "M0 {m0}");
    assert!((m1 - e.moment(1, t).unwrap()).abs() < 1e-6, "M1 {m1}");
    assert_eq!(e.moment(2, t).unwrap(), f64::INFINITY);
}

/// The densities satisfy the discrete Smoluchowski equation: compare a central
/// difference of n_k with the right-hand side. The gain sum is finite; the loss
/// `n_k Σ_j K(k, j) n_j` is written through the moments of the sol plus, after
/// gelation, the mass `g` of a gel that still absorbs sol particles
/// (`K(k, gel) n_gel = k g` for K = x y).
#[test]
fn densities_solve_smoluchowski() {
    type K = fn(f64, f64) -> f64;
    // (solution, kernel, t, loss rate per particle of size k from M0, M1, gel)
    type Loss = fn(f64, f64, f64, f64) -> f64;
    let cases: [(Exact, K, Loss, f64, f64); 6] = [
        (
            Exact::constant(1.0).unwrap(),
            |_, _| 1.0,
            |_, m0, _, _| m0,
            0.8,
            0.0,
        ),
        (
            Exact::constant(2.0).unwrap(),
            |_, _| 2.0,
            |_, m0, _, _| 2.0 * m0,
            3.0,
            0.0,
        ),
        (
            Exact::additive(),
            |x, y| x + y,
            |k, m0, m1, _| k * m0 + m1,
            0.6,
            0.0,
        ),
        (
            Exact::multiplicative(),
            |x, y| x * y,
            |k, _, m1, g| k * (m1 + g),
            0.5,
            0.0,
        ),
        // Flory after gelation: the sol loses only to the sol (no gel term)
        (
            Exact::multiplicative(),
            |x, y| x * y,
            |k, _, m1, g| k * (m1 + g),
            2.5,
            0.0,
        ),
        // Marcus–Lushnikov limit: the gel of mass 1 − t*/t absorbs sol particles
        (
            Exact::marcus_lushnikov(),
            |x, y| x * y,
            |k, _, m1, g| k * (m1 + g),
            2.5,
            1.0 - dual_time(2.5).unwrap() / 2.5,
        ),
    ];
    for (e, kern, loss, t, gel) in cases {
        let n = |j: u64| e.number_density(j, t).unwrap();
        let (m0, m1) = (e.moment(0, t).unwrap(), e.moment(1, t).unwrap());
        for k in 1..=25u64 {
            let h = 1e-5;
            let dn = (e.number_density(k, t + h).unwrap() - e.number_density(k, t - h).unwrap())
                / (2.0 * h);
            let mut gain = 0.0;
            for i in 1..k {
                gain += 0.5 * kern(i as f64, (k - i) as f64) * n(i) * n(k - i);
            }
            let rhs = gain - n(k) * loss(k as f64, m0, m1, gel);
            let scale = n(k) * (1.0 + k as f64);
            assert!(
                (dn - rhs).abs() <= 1e-6 * scale,
                "{e:?} t={t} k={k}: dn/dt {dn} vs rhs {rhs}"
            );
        }
    }
}

/// The moments of the coagulation–fragmentation test solve their own ODEs, derived
/// from the equation: M0' = M0 − M0²/2, M2' = M1² − M2/3, M3' = 3 M1 M2 − M3/2.
#[test]
fn coagulation_fragmentation_moments_solve_their_odes() {
    let e = Exact::coagulation_fragmentation();
    for &t in &[0.0, 0.01, 0.3, 1.0, 5.0, 40.0] {
        let m = |k, t: f64| e.moment(k, t.max(0.0)).unwrap();
        let h = 1e-5;
        let d = |k| (m(k, t + h) - m(k, t - h)) / (2.0 * h);
        if t > 0.0 {
            assert!((d(0) - (m(0, t) - 0.5 * m(0, t) * m(0, t))).abs() < 1e-8);
            assert!((d(2) - (1.0 - m(2, t) / 3.0)).abs() < 1e-8);
            assert!((d(3) - (3.0 * m(2, t) - 0.5 * m(3, t))).abs() < 1e-7);
        }
    }
    for k in 0..=3 {
        assert!(
            (e.moment(k, 0.0).unwrap() - 1.0).abs() < 1e-15,
            "M{k}(0) = 1"
        );
    }
    assert!(e.number_density(1, 1.0).is_err());
}

/// Moment ODEs of the pure coagulation solutions (independent of the summation).
#[test]
fn coagulation_moments_solve_their_odes() {
    let h = 1e-5;
    let cst = Exact::constant(1.5).unwrap();
    let add = Exact::additive();
    let mul = Exact::multiplicative();
    for &t in &[0.2, 0.5, 0.9] {
        let d =
            |e: &Exact, k| (e.moment(k, t + h).unwrap() - e.moment(k, t - h).unwrap()) / (2.0 * h);
        let m = |e: &Exact, k| e.moment(k, t).unwrap();
        // constant: M0' = −K0 M0²/2, M2' = K0 M1², M3' = 3 K0 M1 M2
        assert!((d(&cst, 0) + 0.75 * m(&cst, 0) * m(&cst, 0)).abs() < 1e-8);
        assert!((d(&cst, 2) - 1.5).abs() < 1e-8);
        assert!((d(&cst, 3) - 4.5 * m(&cst, 2)).abs() < 1e-7);
        // additive: M0' = −M0 M1, M2' = 2 M1 M2, M3' = 3 (M1 M3 + M2²)
        assert!((d(&add, 0) + m(&add, 0)).abs() < 1e-8);
        assert!((d(&add, 2) - 2.0 * m(&add, 2)).abs() < 1e-7);
        assert!((d(&add, 3) - 3.0 * (m(&add, 3) + m(&add, 2) * m(&add, 2))).abs() < 1e-6);
        // multiplicative (pre-gel): M0' = −M1²/2, M2' = M2², M3' = 3 M2 M3
        assert!((d(&mul, 0) + 0.5).abs() < 1e-8);
        assert!((d(&mul, 2) - m(&mul, 2) * m(&mul, 2)).abs() < 1e-5);
        assert!((d(&mul, 3) - 3.0 * m(&mul, 2) * m(&mul, 3)).abs() < 1e-3 * m(&mul, 3));
    }
}

/// `I_1` against values from the defining series in high precision (mpmath,
/// 30 digits), across the switch between series and asymptotics at z = 40.
#[test]
fn bessel_i1_matches_reference_values() {
    let refs = [
        (1e-3, 5.000_000_625_000_026e-4),
        (1.0, 0.565_159_103_992_485),
        (10.0, 2_670.988_303_701_254_7),
        (39.0, 5.478_124_121_309_49e15),
        (41.0, 3.949_755_210_006_231e16),
        (120.0, 4.734_721_127_388_196e50),
    ];
    for (z, i1) in refs {
        let got = bessel_i1e(z) * exp(z);
        assert!((got - i1).abs() <= 1e-13 * i1, "I1({z}) = {got}, want {i1}");
    }
    assert_eq!(bessel_i1e(0.0), 0.0);
    assert_eq!(bessel_i1e(f64::NAN), 0.0);
}

/// The exponential-start solutions: the moments are the integrals of the density
/// (Gauss–Laguerre-free: a plain composite Simpson rule on a fine grid), and they
/// solve their moment ODEs; a coefficient is a time scale.
#[test]
fn exponential_start_solutions() {
    let sols = [
        Exact::constant_exponential(1.0).unwrap(),
        Exact::constant_exponential(2.5).unwrap(),
        Exact::additive_exponential(),
        Exact::additive_exponential().with_coefficient(0.5).unwrap(),
    ];
    for e in sols {
        assert!(e.is_continuous());
        assert!(e.number_density(1, 1.0).is_err());
        for &t in &[0.0, 0.3, 1.0, 2.0] {
            // integrate on (0, X] with X where the density is negligible; the
            // Golovin density is finite at 0 (I1(z)/x → √T)
            let x_max = 60.0 * e.moment(2, t).unwrap() / e.moment(1, t).unwrap() + 40.0;
            let n = 200_000;
            let h = x_max / n as f64;
            let mut sums = [0.0; 4];
            for i in 0..=n {
                let x = (i as f64 * h).max(1e-300);
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                let c = e.density(x, t).unwrap();
                for (m, s) in sums.iter_mut().enumerate() {
                    *s += w * c * libm::pow(x, m as f64);
                }
            }
            for (m, s) in sums.iter().enumerate() {
                let integral = s * h / 3.0;
                let exact = e.moment(m as u32, t).unwrap();
                assert!(
                    (integral - exact).abs() <= 1e-6 * exact,
                    "{e:?} t={t} M{m}: integral {integral} vs {exact}"
                );
            }
        }
    }
    // moment ODEs: constant M0' = −k0 M0²/2, M2' = k0, M3' = 3 k0 M2;
    // additive M0' = −M0, M2' = 2 M2, M3' = 3 (M3 + M2²)
    let h = 1e-5;
    let c = Exact::constant_exponential(2.0).unwrap();
    let g = Exact::additive_exponential();
    for &t in &[0.1, 0.7, 2.0] {
        let m = |e: &Exact, k, t: f64| e.moment(k, t).unwrap();
        let d = |e: &Exact, k| (m(e, k, t + h) - m(e, k, t - h)) / (2.0 * h);
        assert!((d(&c, 0) + m(&c, 0, t) * m(&c, 0, t)).abs() < 1e-8);
        assert!((d(&c, 2) - 2.0).abs() < 1e-7);
        assert!((d(&c, 3) - 6.0 * m(&c, 2, t)).abs() < 1e-6 * m(&c, 3, t));
        assert!((d(&g, 0) + m(&g, 0, t)).abs() < 1e-8);
        assert!((d(&g, 2) - 2.0 * m(&g, 2, t)).abs() < 1e-6 * m(&g, 2, t));
        let m2 = m(&g, 2, t);
        assert!((d(&g, 3) - 3.0 * (m(&g, 3, t) + m2 * m2)).abs() < 1e-6 * m(&g, 3, t));
    }
    // a coefficient is a time scale, for every kind
    let b = 1.7;
    for e in [
        Exact::additive(),
        Exact::multiplicative(),
        Exact::marcus_lushnikov(),
        g,
    ] {
        let s = e.with_coefficient(b).unwrap();
        for m in 0..=3 {
            let (x, y) = (s.moment(m, 0.4).unwrap(), e.moment(m, 0.4 * b).unwrap());
            assert!((x - y).abs() <= 1e-15 * y.abs(), "{e:?}");
        }
    }
    assert_eq!(
        Exact::multiplicative()
            .with_coefficient(2.0)
            .unwrap()
            .gel_time(),
        Some(0.5)
    );
    assert!(
        Exact::coagulation_fragmentation()
            .with_coefficient(2.0)
            .is_err()
    );
    assert!(g.with_coefficient(0.0).is_err());
    assert!(g.density(-1.0, 1.0).is_err());
    assert!((g.density(0.0, 1.0).unwrap() - (-1.0f64).exp()).abs() < 1e-15);
    assert!((g.density(1e-9, 1.0).unwrap() - (-1.0f64).exp()).abs() < 1e-8);
    assert!(Exact::additive().density(1.0, 1.0).is_err());
}

#[test]
fn dual_time_solves_its_equation() {
    for &t in &[1.0001, 1.5, 2.0, 5.0, 30.0, 700.0] {
        let s = dual_time(t).unwrap();
        assert!(s > 0.0 && s < 1.0);
        let lhs = log(s) - s;
        let rhs = log(t) - t;
        assert!(
            (lhs - rhs).abs() <= 1e-13 * rhs.abs().max(1.0),
            "t={t} t*={s}"
        );
    }
    assert_eq!(dual_time(0.5).unwrap(), 0.5);
    assert!(dual_time(-1.0).is_err());
    assert!(dual_time(f64::NAN).is_err());
}

#[test]
fn gel_masses() {
    assert_eq!(Exact::multiplicative().gel_mass(0.5).unwrap(), 0.0);
    assert!((Exact::multiplicative().gel_mass(4.0).unwrap() - 0.75).abs() < 1e-15);
    let ml = Exact::marcus_lushnikov();
    let g = ml.gel_mass(3.0).unwrap();
    assert!((g - (1.0 - ml.moment(1, 3.0).unwrap())).abs() < 1e-14);
    // the Marcus–Lushnikov gel grows faster than Flory's
    assert!(g > Exact::multiplicative().gel_mass(3.0).unwrap());
    assert_eq!(Exact::additive().gel_mass(9.0).unwrap(), 0.0);
    assert!(Exact::additive().moment(4, 1.0).is_err());
    assert!(Exact::additive().number_density(0, 1.0).is_err());
    assert!(Exact::constant(0.0).is_err());
}
