//! Tests of [`coagulation`](super).

use super::*;

/// A coefficient scales the rate and every bound by the same factor, so the bounds
/// still hold and stay as tight (the acceptance ratios do not move).
#[test]
fn coefficients_scale_the_rate_and_the_bounds() {
    use crate::kernel::{check_low_rank, check_majorant, log_grid};
    let grid = log_grid(1.0, 1e6, 60);
    for base in [
        Coagulation::constant(2.0).unwrap(),
        Coagulation::additive(),
        Coagulation::multiplicative(),
        Coagulation::product(0.8).unwrap(),
        Coagulation::homogeneous(1.5).unwrap(),
        Coagulation::free_molecular(),
        Coagulation::brownian(),
    ] {
        let base = base.with_min_size(1.0).unwrap();
        let k = base.with_coefficient(3.5).unwrap();
        assert_eq!(k.coefficient(), 3.5);
        for &(x, y) in &[(1.0, 1.0), (2.0, 7.0), (1e5, 3.0)] {
            let (r, r0) = (k.rate(x, y), base.rate(x, y));
            assert!((r - 3.5 * r0).abs() <= 1e-14 * r, "{} {x} {y}", k.name());
            let (l, l0) = (
                k.low_rank_bound(x, y).unwrap(),
                base.low_rank_bound(x, y).unwrap(),
            );
            assert!((l - 3.5 * l0).abs() <= 1e-14 * l, "{}", k.name());
            let (h, h0) = (k.majorant(x).unwrap(), base.majorant(x).unwrap());
            assert!(
                (h * h - 3.5 * h0 * h0).abs() <= 1e-13 * h * h,
                "{}",
                k.name()
            );
        }
        let (m, m0) = (
            check_majorant(&k, &grid).unwrap(),
            check_majorant(&base, &grid).unwrap(),
        );
        assert_eq!(m.violations + m.monotonicity_violations, 0, "{}", k.name());
        assert!((m.worst_acceptance - m0.worst_acceptance).abs() < 1e-12);
        let (l, l0) = (
            check_low_rank(&k, &grid).unwrap(),
            check_low_rank(&base, &grid).unwrap(),
        );
        assert_eq!(l.violations, 0, "{}", k.name());
        assert!((l.worst_acceptance - l0.worst_acceptance).abs() < 1e-12);
        assert_eq!(k.low_rank_floor(), base.low_rank_floor());
    }
    // coefficients compose; bad ones are refused
    let k = Coagulation::additive().with_coefficient(2.0).unwrap();
    assert_eq!(k.with_coefficient(2.0).unwrap().rate(1.0, 1.0), 8.0);
    for b in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(Coagulation::brownian().with_coefficient(b).is_err());
    }
    let huge = Coagulation::additive().with_coefficient(1e308).unwrap();
    assert!(huge.with_coefficient(1e10).is_err());
}

/// The physical kernels against hand-computed values: air at 300 K, and soot-like
/// spheres (ρ = 1800 kg/m³) of 1 nm³ monomers.
#[test]
fn physical_kernels_match_their_formulas() {
    let kb = 1.380_649e-23;
    let b = Coagulation::brownian_continuum(300.0, 1.8e-5).unwrap();
    let want = 2.0 * kb * 300.0 / (3.0 * 1.8e-5) * 4.0;
    assert!((b.rate(5.0, 5.0) - want).abs() < 1e-12 * want);
    assert_eq!(b.homogeneity(), 0.0);
    let v0 = 1e-27;
    let f = Coagulation::free_molecular_physical(300.0, 1800.0, v0).unwrap();
    // two monomers: (3/4π)^{1/6} (6kT/ρ)^{1/2} (2/v0)^{1/2} (2 v0^{1/3})²
    let want = libm::pow(3.0 / (4.0 * core::f64::consts::PI), 1.0 / 6.0)
        * libm::sqrt(6.0 * kb * 300.0 / 1800.0)
        * libm::sqrt(2.0 / v0)
        * 4.0
        * libm::pow(v0, 2.0 / 3.0);
    assert!(
        (f.rate(1.0, 1.0) - want).abs() < 1e-12 * want,
        "{} {want}",
        f.rate(1.0, 1.0)
    );
    assert!(Coagulation::brownian_continuum(0.0, 1e-5).is_err());
    assert!(Coagulation::free_molecular_physical(300.0, f64::NAN, v0).is_err());
    assert!(Coagulation::free_molecular_physical(300.0, 1000.0, -1.0).is_err());
}

#[test]
fn constructors_reject_bad_parameters() {
    assert!(Coagulation::constant(0.0).is_err());
    assert!(Coagulation::constant(-1.0).is_err());
    assert!(Coagulation::constant(f64::NAN).is_err());
    assert!(Coagulation::product(0.0).is_err());
    assert!(Coagulation::product(1.5).is_err());
    assert!(Coagulation::product(f64::NAN).is_err());
    assert!(Coagulation::homogeneous(1.0).is_err());
    assert!(Coagulation::homogeneous(2.5).is_err());
    assert!(Coagulation::homogeneous(f64::INFINITY).is_err());
    assert!(Coagulation::brownian().with_min_size(-1.0).is_err());
    assert!(Coagulation::brownian().with_min_size(f64::NAN).is_err());
}

#[test]
fn rates_match_their_formulas() {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    assert!(close(
        Coagulation::constant(2.5).unwrap().rate(3.0, 7.0),
        2.5
    ));
    assert!(close(Coagulation::additive().rate(3.0, 7.0), 10.0));
    assert!(close(Coagulation::multiplicative().rate(3.0, 7.0), 21.0));
    assert!(close(
        Coagulation::product(0.5).unwrap().rate(4.0, 9.0),
        6.0
    ));
    // γ = 2 is x y
    let h2 = Coagulation::homogeneous(2.0).unwrap();
    for &(x, y) in &[(1.0, 1.0), (3.0, 7.0), (1e-6, 1e6), (1e9, 2.0)] {
        assert!(close(h2.rate(x, y), x * y), "{x} {y} {}", h2.rate(x, y));
    }
    // γ = 1.5 at (1, 1): 2 / (2^1.5 − 2)
    let h15 = Coagulation::homogeneous(1.5).unwrap();
    assert!(close(h15.rate(1.0, 1.0), 2.0 / (pow(2.0, 1.5) - 2.0)));
    // symmetric and homogeneous of degree γ
    assert!(close(h15.rate(2.0, 5.0), h15.rate(5.0, 2.0)));
    assert!(close(
        h15.rate(6.0, 15.0),
        pow(3.0, 1.5) * h15.rate(2.0, 5.0)
    ));
    // free molecular at (1, 8): sqrt(1 + 1/8) (1 + 2)^2
    assert!(close(
        Coagulation::free_molecular().rate(1.0, 8.0),
        sqrt(1.125) * 9.0
    ));
    // Brownian at (1, 1) = 4, homogeneous of degree 0
    let b = Coagulation::brownian();
    assert!(close(b.rate(1.0, 1.0), 4.0));
    assert!(close(b.rate(5.0, 40.0), b.rate(1.0, 8.0)));
}

#[test]
fn low_rank_bounds_are_exact_where_spec_says() {
    let exact = [
        Coagulation::constant(3.0).unwrap(),
        Coagulation::additive(),
        Coagulation::multiplicative(),
        Coagulation::product(0.8).unwrap(),
        Coagulation::brownian(),
    ];
    for k in exact {
        for &(x, y) in &[(1.0, 1.0), (2.0, 9.0), (1e5, 3.0), (0.01, 7.0)] {
            let a = k.low_rank_bound(x, y).unwrap();
            let r = k.rate(x, y);
            assert!(
                (a - r).abs() <= 1e-12 * r,
                "{} {x} {y}: {a} vs {r}",
                k.name()
            );
        }
    }
    // Ballistic: K / (A + Aᵀ) = sqrt(1/x+1/y) / (x^{-1/2} + y^{-1/2}) ∈ [1/√2, 1]
    let k = Coagulation::free_molecular();
    let acc = k.rate(1.0, 1.0) / k.low_rank_bound(1.0, 1.0).unwrap();
    assert!((acc - 1.0 / sqrt(2.0)).abs() < 1e-12);
}

#[test]
fn fast_cube_root_is_within_an_ulp_of_libm() {
    // a multiplicative sweep over the whole normal range, plus sizes 1..10^5
    let mut x = f64::MIN_POSITIVE;
    let mut worst = 0.0f64;
    while x < f64::MAX / 1.001 {
        let (a, b) = (cbrt(x), libm::cbrt(x));
        worst = worst.max((a - b).abs() / (b * f64::EPSILON));
        x *= 1.000_731;
    }
    for i in 1..100_000 {
        let x = f64::from(i);
        let (a, b) = (cbrt(x), libm::cbrt(x));
        worst = worst.max((a - b).abs() / (b * f64::EPSILON));
    }
    assert!(worst <= 1.0, "worst error {worst} ulp");
    for x in [0.0, -8.0, 1e-310, f64::INFINITY, f64::NAN] {
        let (a, b) = (cbrt(x), libm::cbrt(x));
        assert!(a == b || (a.is_nan() && b.is_nan()), "{x}");
    }
    assert_eq!(cbrt(27.0), 3.0);
}

/// The declared acceptance floor holds on a grid (up to rounding) and is attained
/// (not just a loose number): `min K / (A + Aᵀ)` over the grid lies within 1e-9 of it.
#[test]
fn acceptance_floors_hold_and_are_tight() {
    let grid: alloc::vec::Vec<f64> = (0..60)
        .map(|i| libm::pow(10.0, f64::from(i) / 10.0))
        .collect();
    for k in [
        Coagulation::constant(2.0).unwrap(),
        Coagulation::additive(),
        Coagulation::multiplicative(),
        Coagulation::brownian(),
        Coagulation::free_molecular(),
    ] {
        let rho = k.low_rank_floor();
        let mut worst = f64::INFINITY;
        for &x in &grid {
            for &y in &grid {
                let ratio = k.rate(x, y) / k.low_rank_bound(x, y).unwrap();
                // up to rounding of the two evaluations
                assert!(
                    ratio >= rho * (1.0 - 1e-14),
                    "{} {x} {y}: {ratio} < {rho}",
                    k.name()
                );
                worst = worst.min(ratio);
            }
        }
        assert!(worst - rho < 1e-9, "{}: floor {rho}, min {worst}", k.name());
    }
    let h = Coagulation::homogeneous(1.5).unwrap();
    assert_eq!(h.low_rank_floor(), 0.0);
}

#[test]
fn homogeneous_constant_is_at_least_both_candidates() {
    for &g in &[1.05, 1.2, 1.5, 1.8, 2.0] {
        let c2 = homogeneous_bound_c2(g);
        let at_one = 1.0 / (pow(2.0, g) - 2.0);
        assert!(c2 >= at_one, "γ={g}: {c2} < {at_one}");
        if g < 2.0 {
            assert!(c2 >= 2.0 / g);
        } else {
            assert!((c2 - 0.5).abs() < 1e-6);
        }
    }
}

/// The corner rule of `sup_rate` against a dense grid scan of each square.
#[test]
fn sup_rate_is_attained_at_a_corner() {
    let kernels = [
        Coagulation::constant(2.0).unwrap(),
        Coagulation::additive(),
        Coagulation::multiplicative(),
        Coagulation::product(0.7).unwrap(),
        Coagulation::homogeneous(1.3).unwrap(),
        Coagulation::homogeneous(2.0).unwrap(),
        Coagulation::free_molecular(),
        Coagulation::brownian(),
    ];
    for k in kernels {
        for &(lo, hi) in &[(1.0, 2.0), (1.0, 512.0), (0.01, 3.0), (5.0, 1e6)] {
            let sup = k.sup_rate(lo, hi).unwrap();
            let n = 120;
            for a in 0..=n {
                for b in 0..=n {
                    let x = lo * libm::pow(hi / lo, a as f64 / n as f64);
                    let y = lo * libm::pow(hi / lo, b as f64 / n as f64);
                    assert!(
                        k.rate(x, y) <= sup * (1.0 + 1e-12),
                        "{} [{lo},{hi}] at ({x},{y})",
                        k.name()
                    );
                }
            }
        }
    }
}

/// The corner rule of `sup_block` against a dense grid scan of rectangles on and off
/// the diagonal.
#[test]
fn sup_block_is_attained_at_a_corner() {
    let kernels = [
        Coagulation::constant(2.0).unwrap(),
        Coagulation::additive(),
        Coagulation::multiplicative(),
        Coagulation::product(0.7).unwrap(),
        Coagulation::homogeneous(1.3).unwrap(),
        Coagulation::free_molecular(),
        Coagulation::brownian(),
    ];
    for k in kernels {
        for &(x0, x1, y0, y1) in &[
            (1.0, 2.0, 3.0, 9.0),
            (0.01, 3.0, 1.0, 2.0),
            (5.0, 1e6, 1.0, 1e3),
        ] {
            let sup = k.sup_block(x0, x1, y0, y1).unwrap();
            let n = 80;
            let mut max = 0.0_f64;
            for a in 0..=n {
                for b in 0..=n {
                    let x = x0 * libm::pow(x1 / x0, a as f64 / n as f64);
                    let y = y0 * libm::pow(y1 / y0, b as f64 / n as f64);
                    max = max.max(k.rate(x, y));
                }
            }
            assert!(
                sup >= max * (1.0 - 1e-12) && sup <= max * (1.0 + 1e-12),
                "{} {sup} {max}",
                k.name()
            );
        }
    }
}

#[test]
fn additive_shift_is_tight_at_the_minimum_size() {
    // for s = 1, c = √2 − 1 and K(1,1) = h(1)²
    let k = Coagulation::additive().with_min_size(1.0).unwrap();
    let h = k.majorant(1.0).unwrap();
    assert!((h * h - 2.0).abs() < 1e-12);
    // for s = 0 the shift is 1
    assert_eq!(Coagulation::additive().majorant(0.0), Some(1.0));
}

/// `k`'s block bound is at least the kernel at every integer pair of each block.
fn sup_block_holds(k: &Coagulation, blocks: &[(f64, f64, f64, f64)]) {
    for &(x0, x1, y0, y1) in blocks {
        let sup = k.sup_block(x0, x1, y0, y1).unwrap();
        for x in x0 as u32..=x1 as u32 {
            for y in y0 as u32..=y1 as u32 {
                assert!(k.rate(f64::from(x), f64::from(y)) <= sup, "{x} {y}");
            }
        }
    }
}

/// The gravitational kernel through `Coagulation`: its rank-3 bound holds (and is
/// loose: below 1 % at near-equal small drops), its block bound holds on integer
/// blocks, a change of size unit is the same kernel, and bad radii are refused.
#[test]
fn gravitational_bounds_and_units() {
    let k = Coagulation::gravitational(1e-5).unwrap();
    assert_eq!(k.name(), "gravitational");
    assert!(!k.low_rank_is_loose() && !k.low_rank_is_exact() && !k.integer_sizes());
    // thin strips next to the diagonal for block majorants; not for the atmospheric
    // kernel, which peaks there, nor (same bits as before) for the others
    assert!(k.log_linear_blocks());
    assert!(!Coagulation::atmospheric().log_linear_blocks());
    assert!(!Coagulation::constant(1.0).unwrap().log_linear_blocks());
    assert!(k.majorant(2.0).is_none());
    let (mut a, mut b, mut c, mut d) = ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
    let mut worst = f64::INFINITY;
    for i in 0..60 {
        for j in 0..60 {
            let (x, y) = (1.2f64.powi(i), 1.2f64.powi(j));
            k.factors(x, &mut a, &mut b);
            k.factors(y, &mut c, &mut d);
            let bound: f64 = (0..3).map(|q| a[q] * d[q] + c[q] * b[q]).sum();
            let r = k.rate(x, y);
            assert!(r <= bound * (1.0 + 1e-12), "{x} {y}: {r} > {bound}");
            if i != j {
                worst = worst.min(r / bound);
            }
        }
    }
    assert!(worst < 0.01, "{worst}");
    sup_block_holds(
        &k,
        &[
            (1.0, 4.0, 5.0, 8.0),
            (1.0, 4.0, 1.0, 4.0),
            (30.0, 60.0, 1.0, 2.0),
        ],
    );
    // sizes in units of 8: the unit radius doubles
    let k8 = k.in_size_unit(8.0).unwrap();
    assert_eq!(
        k8.rate(1.0, 3.0),
        Coagulation::gravitational(2e-5).unwrap().rate(1.0, 3.0)
    );
    assert!((k8.rate(1.0, 3.0) / k.rate(8.0, 24.0) - 1.0).abs() < 1e-12);
    assert_ne!(k.fingerprint(), k8.fingerprint());
    for bad in [0.0, -1e-6, 1.0, f64::NAN] {
        assert!(Coagulation::gravitational(bad).is_err(), "{bad}");
    }
    // Hall's efficiencies: another kernel (name, fingerprint), the same units rule,
    // its bounds hold on integer blocks, and R = r = 70 µm takes Hall's 4.0
    let h = Coagulation::gravitational_hall(1e-5).unwrap();
    assert_eq!(h.name(), "gravitational-hall");
    assert_ne!(h.fingerprint(), k.fingerprint());
    assert_eq!(h.in_size_unit(8.0).unwrap().name(), "gravitational-hall");
    assert!(Coagulation::gravitational_hall(1.0).is_err());
    sup_block_holds(
        &h,
        &[
            (1.0, 4.0, 5.0, 8.0),
            (100.0, 125.0, 100.0, 125.0),
            (300.0, 400.0, 20.0, 40.0),
            (1.0, 2.0, 1000.0, 1200.0),
        ],
    );
    let r = 70e-6;
    assert_eq!(
        crate::kernel::gravitational::efficiency_of(
            crate::kernel::gravitational::Collection::Hall,
            r,
            r
        ),
        4.0
    );
    // the atmospheric kernel lives on integer sizes: no other unit
    assert!(Coagulation::atmospheric().in_size_unit(1.0 / 64.0).is_err());
    assert!(Coagulation::atmospheric().in_size_unit(1.0).is_ok());
    // the homogeneous kernels: in_size_unit is the coefficient δ^λ
    let add = Coagulation::additive().in_size_unit(2.0).unwrap();
    assert_eq!(
        add.rate(1.0, 2.0),
        2.0 * Coagulation::additive().rate(1.0, 2.0)
    );
}
