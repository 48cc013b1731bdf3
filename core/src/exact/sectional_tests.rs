//! The sectional reference against the closed forms it must reproduce: M0 and M1 of
//! the moment equations (exact on any grid for a constant kernel), M2 converging as the
//! grid is refined, and the books balancing the mass to rounding.

use super::*;
use crate::exact::Exact;
use crate::kernel::Coagulation;

fn constant() -> Coagulation {
    Coagulation::constant(1.0).unwrap()
}

fn monomers(ratio: f64) -> Sectional<Coagulation> {
    let mut s = Sectional::new(
        constant(),
        Sectional::<Coagulation>::grid(32, 1e5, ratio).unwrap(),
    )
    .unwrap();
    s.set_number(0, 1.0).unwrap();
    s
}

/// The mass balance: M1 = M1(0) + injected − removed + grown − lost, to rounding.
fn balanced(s: &Sectional<Coagulation>, m1_0: f64) {
    let b = s.books();
    let want = m1_0 + b.injected_mass - b.removed_mass + b.grown_mass - b.lost_mass;
    assert!(
        (s.moment(1.0) - want).abs() <= 1e-12 * want.abs().max(1.0),
        "{} vs {want}",
        s.moment(1.0)
    );
}

#[test]
fn constant_kernel_moments_and_convergence() {
    let e = Exact::constant(1.0).unwrap();
    let mut err = [0.0; 3];
    for (q, ratio) in [1.2, 1.1, 1.05].into_iter().enumerate() {
        let mut s = monomers(ratio);
        s.advance_to(4.0, 4e-3).unwrap();
        // number and mass: exact on any grid (the fixed pivot keeps both)
        assert!((s.moment(0.0) - e.moment(0, 4.0).unwrap()).abs() < 1e-10);
        assert!((s.moment(1.0) - 1.0).abs() < 1e-12);
        balanced(&s, 1.0);
        err[q] = (s.moment(2.0) / e.moment(2, 4.0).unwrap() - 1.0).abs();
    }
    std::println!("M2(4) relative error at ratios 1.2, 1.1, 1.05: {err:?}");
    // M2 converges as the grid is refined (a wrong split would not)
    assert!(err[2] < err[1] && err[1] < err[0], "{err:?}");
    assert!(err[2] < 5e-3, "{err:?}");
}

#[test]
fn a_monomer_source_follows_the_riccati_solution() {
    // dM0/dt = S − K M0²/2 from M0(0) = 0: M0 = sqrt(2S/K) tanh(t sqrt(SK/2));
    // M1 = S t (monomers of size 1)
    let (src, t) = (0.7, 3.0);
    let mut s = Sectional::new(
        constant(),
        Sectional::<Coagulation>::grid(32, 1e5, 1.1).unwrap(),
    )
    .unwrap()
    .with_source(src, 1.0)
    .unwrap();
    s.advance_to(t, 1e-3).unwrap();
    let m0 = libm::sqrt(2.0 * src) * libm::tanh(t * libm::sqrt(src / 2.0));
    assert!(
        (s.moment(0.0) - m0).abs() < 1e-10,
        "{} vs {m0}",
        s.moment(0.0)
    );
    assert!((s.moment(1.0) - src * t).abs() < 1e-10);
    let b = s.books();
    assert!((b.injected_number - src * t).abs() < 1e-10);
    balanced(&s, 0.0);
}

#[test]
fn dilution_follows_the_bernoulli_solution() {
    // dM0/dt = −λ M0 − K M0²/2: 1/M0 = (1/M0(0) + K/(2λ)) e^{λt} − K/(2λ); M1 = e^{−λt}
    let (lambda, t) = (0.4, 2.5);
    let mut s = monomers(1.1).with_removal(|_| lambda).unwrap();
    s.advance_to(t, 1e-3).unwrap();
    let inv = (1.0 + 0.5 / lambda) * libm::exp(lambda * t) - 0.5 / lambda;
    assert!((s.moment(0.0) - 1.0 / inv).abs() < 1e-10);
    assert!((s.moment(1.0) - libm::exp(-lambda * t)).abs() < 1e-10);
    balanced(&s, 1.0);
}

#[test]
fn linear_growth_with_the_constant_kernel() {
    // M0 as without growth; M1 = M1(0) e^{g t}
    let (g, t) = (0.3, 2.0);
    let mut s = monomers(1.05).with_growth(|x| g * x).unwrap();
    s.advance_to(t, 1e-3).unwrap();
    let e = Exact::constant(1.0).unwrap();
    assert!((s.moment(0.0) - e.moment(0, t).unwrap()).abs() < 1e-10);
    assert!(
        (s.moment(1.0) - libm::exp(g * t)).abs() < 1e-9,
        "{}",
        s.moment(1.0)
    );
    balanced(&s, 1.0);
}

#[test]
fn size_dependent_removal_alone_is_exact_per_pivot() {
    // no coagulation: n(x, t) = n0(x) e^{−λ(x) t}
    let zero = Coagulation::constant(1.0)
        .unwrap()
        .with_coefficient(1e-300)
        .unwrap();
    let grid = Sectional::<Coagulation>::grid(8, 100.0, 1.5).unwrap();
    let mut s = Sectional::new(zero, grid)
        .unwrap()
        .with_removal(|x| 0.1 * x)
        .unwrap();
    for i in 0..s.pivots().len() {
        s.set_number(i, 1.0 / (i + 1) as f64).unwrap();
    }
    s.advance_to(1.5, 1e-3).unwrap();
    for (i, (&x, &n)) in s.pivots().iter().zip(s.numbers()).enumerate() {
        let want = libm::exp(-0.1 * x * 1.5) / (i + 1) as f64;
        assert!((n / want - 1.0).abs() < 1e-9, "pivot {x}: {n} vs {want}");
    }
}

#[test]
fn bad_input_is_refused() {
    assert!(Sectional::<Coagulation>::grid(0, 10.0, 1.1).is_err());
    assert!(Sectional::<Coagulation>::grid(4, 10.0, 1.0).is_err());
    assert!(Sectional::<Coagulation>::grid(4, 1e300, 1.0001).is_err()); // too many pivots
    assert!(Sectional::new(constant(), alloc::vec![1.0, 1.0]).is_err());
    assert!(Sectional::new(constant(), alloc::vec![]).is_err());
    let mut s = monomers(1.2);
    assert!(s.set_number(10_000, 1.0).is_err());
    assert!(s.set_number(0, f64::NAN).is_err());
    assert!(s.add_at(1e300, 1.0).is_err());
    assert!(s.advance_to(-1.0, 0.1).is_err());
    assert!(s.advance_to(1.0, 0.0).is_err());
    // work refused up front, not run for days: 1e8 steps over ~100 pivots
    assert!(s.advance_to(1e4, 1e-4).is_err());
    assert_eq!(s.time(), 0.0);
    assert!(monomers(1.2).with_removal(|_| f64::NAN).is_err());
    assert!(monomers(1.2).with_growth(|_| -1.0).is_err());
    // a step too long for the rates leaves the state as it was
    let mut fast = monomers(1.2).with_removal(|_| 1e6).unwrap();
    let before = fast.numbers().to_vec();
    assert!(fast.advance_to(1.0, 0.5).is_err());
    assert_eq!(fast.numbers(), &before[..]);
    assert_eq!(fast.time(), 0.0);
}

/// The discrete equations on integer sizes: the constant kernel's n_k(t) and the
/// additive kernel's (Golovin from monomers) to RK4's accuracy, with nothing lost past
/// the last size while the tail is negligible — and booked when it is not.
#[test]
fn discrete_equations_match_the_exact_densities() {
    for (k, e, t) in [
        (constant(), Exact::constant(1.0).unwrap(), 3.0),
        (Coagulation::additive(), Exact::additive(), 1.0),
    ] {
        let mut s = Sectional::discrete(k, 512).unwrap();
        s.set_number(0, 1.0).unwrap();
        s.advance_to(t, 2e-3).unwrap();
        let mut worst = 0.0f64;
        for size in 1..=40u64 {
            let want = e.number_density(size, t).unwrap();
            let got = s.numbers()[size as usize - 1];
            worst = worst.max((got - want).abs() / want);
        }
        assert!(worst < 1e-9, "{} {worst}", k.name());
        assert!(s.books().lost_mass < 1e-20, "{:?}", s.books());
        balanced(&s, 1.0);
    }
    // a grid too short for the run: the mass past it is booked
    let mut s = Sectional::discrete(constant(), 8).unwrap();
    s.set_number(0, 1.0).unwrap();
    s.advance_to(4.0, 1e-2).unwrap();
    assert!(s.books().lost_mass > 1e-3, "{:?}", s.books());
    balanced(&s, 1.0);
    assert!(Sectional::discrete(constant(), 0).is_err());
    assert!(Sectional::discrete(constant(), MAX_PIVOTS + 1).is_err());
}
