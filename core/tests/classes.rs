//! Host coupling on size classes (issue 42), on every scheme of the registry: the
//! projection keeps number and mass to rounding; a population built from class numbers
//! has them in expectation (exactly in mass for the mass-flow schemes); bad input is
//! refused with the state unchanged; temperature and gas states refuse.

use crate::common;

use coagula_core::classes::{Classes, rates};
use coagula_core::kernel::Coagulation;
use coagula_core::observe::Replicas;
use coagula_core::scheme::facade::{Law, State};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// Integer pivots 1..=8, then a ratio of 1.5 to past 1e4.
fn grid() -> Classes {
    let mut x: Vec<f64> = (1..=8).map(f64::from).collect();
    while x[x.len() - 1] < 1e4 {
        let next = (x[x.len() - 1] * 1.5).round();
        x.push(next);
    }
    Classes::new(&x).unwrap()
}

fn mass(c: &Classes, n: &[f64]) -> f64 {
    n.iter().zip(c.pivots()).map(|(a, x)| a * x).sum()
}

#[test]
fn every_scheme_projects_keeping_number_and_mass_and_builds_back() {
    let c = grid();
    for info in registry::SCHEMES.iter().copied() {
        let Some(mut s) = common::standard(info, 2048, Coagulation::constant(1.0).unwrap()) else {
            continue;
        };
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        s.advance_to(2.0, &mut rng).unwrap();
        let mut n = vec![0.0; c.len()];
        let out = s.project(&c, &mut n).unwrap();
        let (m0, m1) = (s.moment(0.0), s.moment(1.0));
        let n_all = n.iter().sum::<f64>() + out.below_number + out.above_number;
        let m_all = mass(&c, &n) + out.below_mass + out.above_mass;
        assert!(
            (n_all / m0 - 1.0).abs() < 1e-12,
            "{}: {n_all} vs {m0}",
            info.name
        );
        assert!(
            (m_all / m1 - 1.0).abs() < 1e-12,
            "{}: {m_all} vs {m1}",
            info.name
        );
        // the grid starts at the smallest size and reaches past the largest
        assert_eq!(out.below_number, 0.0, "{}", info.name);
        let before = common::state_bits(&*s);
        let r = s.set_classes(&c, &n, &mut rng);
        match info.law {
            Law::Temperature | Law::Gas => {
                assert!(r.is_err(), "{}", info.name);
                assert_eq!(common::state_bits(&*s), before, "{}", info.name);
                continue;
            }
            _ => r.unwrap_or_else(|e| panic!("{}: {e}", info.name)),
        }
        let mut back = vec![0.0; c.len()];
        s.project(&c, &mut back).unwrap();
        match info.law {
            // the classes' mass exactly; the number within the placement's rounding
            Law::MassFlow | Law::TimeStepped => {
                assert!(
                    (mass(&c, &back) / mass(&c, &n) - 1.0).abs() < 1e-12,
                    "{}",
                    info.name
                );
                let (a, b) = (back.iter().sum::<f64>(), n.iter().sum::<f64>());
                assert!((a / b - 1.0).abs() < 0.05, "{}: {a} vs {b}", info.name);
            }
            // every class within one particle of N_i V
            _ => {
                let v = s.volume();
                for (i, (a, b)) in back.iter().zip(&n).enumerate() {
                    assert!(
                        (a - b).abs() * v <= 1.0 + 1e-9,
                        "{} class {i}: {a} vs {b}",
                        info.name
                    );
                }
            }
        }
        // the run goes on from the new population
        s.advance_to(3.0, &mut rng).unwrap();
    }
}

#[test]
fn a_population_from_classes_has_their_numbers_in_expectation() {
    // 0.37 per unit volume at 3 and 0.21 at 17, volume 100 (counts schemes: 37 and 21
    // exactly) or volume 10 (3.7 and 2.1: rounded); the mass-flow schemes place their
    // 2000 particles on the mass 0.37·3 + 0.21·17 = 4.68
    let c = Classes::new(&[1.0, 3.0, 17.0]).unwrap();
    let target = [0.0, 0.37, 0.21];
    for info in registry::SCHEMES.iter().copied() {
        if matches!(info.law, Law::Temperature | Law::Gas) {
            continue;
        }
        let reps = 400;
        let (mut m0, mut n3) = (Replicas::new(), Replicas::new());
        for r in 0..reps {
            let Some(mut s) = common::standard(info, 2048, Coagulation::constant(1.0).unwrap())
            else {
                break;
            };
            let mut rng = Pcg64Mcg::seed_from_u64(0xc1a5 ^ r);
            s.set_classes(&c, &target, &mut rng).unwrap();
            m0.push(s.moment(0.0));
            n3.push(s.number_density(3.0));
            if matches!(info.law, Law::MassFlow | Law::TimeStepped) {
                assert!((s.moment(1.0) / 4.68 - 1.0).abs() < 1e-12, "{}", info.name);
            }
        }
        if m0.count() == 0 {
            continue;
        }
        let z = common::z_max(reps);
        for (what, st, want) in [("M0", &m0, 0.58), ("n(3)", &n3, 0.37)] {
            let se = st.std_error();
            // a rounding that is exact has no spread: then it must be exact
            let ok = if se == 0.0 {
                (st.mean() - want).abs() < 1e-12
            } else {
                (st.mean() - want).abs() < z * se
            };
            assert!(ok, "{} {what}: {} ± {se} vs {want}", info.name, st.mean());
        }
    }
}

#[test]
fn bad_classes_leave_the_state_unchanged() {
    let c = grid();
    for info in registry::SCHEMES.iter().copied() {
        let Some(mut s) = common::standard(info, 256, Coagulation::constant(1.0).unwrap()) else {
            continue;
        };
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        s.advance_to(0.5, &mut rng).unwrap();
        let before = common::state_bits(&*s);
        let mut good = vec![0.0; c.len()];
        good[0] = 0.5;
        let mut nan = good.clone();
        nan[3] = f64::NAN;
        let mut neg = good.clone();
        neg[1] = -1.0;
        let half = Classes::new(&[1.0, 2.5]).unwrap();
        for (what, cl, nums) in [
            ("NaN", &c, nan.as_slice()),
            ("negative", &c, neg.as_slice()),
            ("short", &c, &good[..3]),
            ("zeros", &c, &vec![0.0; c.len()][..]),
        ] {
            // an empty population is fine for the size-count schemes, not for a mass flow
            if what == "zeros" && !matches!(info.law, Law::MassFlow | Law::TimeStepped) {
                continue;
            }
            assert!(
                s.set_classes(cl, nums, &mut rng).is_err(),
                "{} {what}",
                info.name
            );
            assert_eq!(common::state_bits(&*s), before, "{} {what}", info.name);
        }
        if matches!(s.state(), State::Counts(..)) {
            assert!(
                s.set_classes(&half, &[0.1, 0.1], &mut rng).is_err(),
                "{}",
                info.name
            );
            assert_eq!(
                common::state_bits(&*s),
                before,
                "{} non-integer pivot",
                info.name
            );
        }
        assert!(s.project(&c, &mut [0.0; 2]).is_err());
    }
}

#[test]
fn class_rates_over_a_step_close_the_number_budget() {
    // the constant kernel from 4000 monomers: over a step, the rates per class sum to
    // the change of M0 and their mass to 0 (coagulation keeps the mass)
    let c = grid();
    let info = registry::find("lowrank").unwrap();
    let mut s = common::standard(info, 4096, Coagulation::constant(1.0).unwrap()).unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let (mut a, mut b, mut r) = (vec![0.0; c.len()], vec![0.0; c.len()], vec![0.0; c.len()]);
    s.project(&c, &mut a).unwrap();
    let m0 = s.moment(0.0);
    s.advance_to(0.25, &mut rng).unwrap();
    s.project(&c, &mut b).unwrap();
    rates(&a, &b, 0.25, &mut r).unwrap();
    let dm0 = (s.moment(0.0) - m0) / 0.25;
    assert!((r.iter().sum::<f64>() - dm0).abs() < 1e-9 * dm0.abs());
    assert!(mass(&c, &r).abs() < 1e-9);
    assert!(dm0 < 0.0);
}
