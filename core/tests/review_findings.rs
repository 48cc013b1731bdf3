//! Regression tests for the independent reviews' findings (issue 40), one test per
//! item fixed; each failed on the code before its fix.

use crate::common::{Sim, count_schemes};
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::scheme::facade::{Init, Model, Options};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;

/// `set_counts({2^63}, V = 1)` then a short advance: the per-size trees added a signed
/// change to the count through `i64` (debug: overflow panic; release: a wrapped count).
/// Every size-count scheme keeps the mass exactly.
#[test]
fn counts_past_two_to_the_63_stay_exact() {
    let k = Coagulation::constant(1.0).unwrap();
    for info in count_schemes() {
        let id = registry::find(info.name).unwrap();
        let init = Init::Counts {
            counts: &[4],
            volume: 1.0,
        };
        let mut s: Box<Sim> = registry::build(
            id,
            Model::coagulation(k, NoFragmentation),
            &init,
            &Options::default(),
        )
        .unwrap();
        let big = 1u64 << 63;
        if s.set_counts(&[big], 1.0).is_err() {
            continue; // refused up front: nothing to run
        }
        let mut rng = Pcg64Mcg::new(3);
        // ~K N^2 / (2V) = 2^125 events per unit time: 1e-37 is a few events
        match s.advance_to(1e-37, &mut rng) {
            Ok(_) => {}
            Err(e) => {
                // a refusal must leave the state as it was
                let mut mass = 0u128;
                s.for_each_count(&mut |size, c| mass += u128::from(size) * u128::from(c))
                    .unwrap();
                assert_eq!(mass, u128::from(big), "{}: {e}", info.name);
                continue;
            }
        }
        let mut mass = 0u128;
        let mut events = 0u128;
        s.for_each_count(&mut |size, c| {
            mass += u128::from(size) * u128::from(c);
            if size > 1 {
                events += u128::from(c) * u128::from(size - 1);
            }
        })
        .unwrap();
        assert_eq!(mass, u128::from(big), "{}: mass changed", info.name);
        assert!(events < 1_000_000, "{}: {events} events", info.name);
    }
}

/// Golovin's M3 where `e^{4t}` overflows: infinite, not NaN (`inf − inf`).
#[test]
fn golovin_moments_overflow_to_infinity() {
    use coagula_core::exact::Exact;
    for e in [Exact::additive(), Exact::additive_exponential()] {
        let v = e.moment(3, 300.0).unwrap();
        assert!(v.is_infinite() && v > 0.0, "M3(300) = {v}");
        assert!(e.moment(2, 300.0).unwrap().is_finite());
    }
    // and unchanged where finite: M3(1) of the exponential start is 12e^4 − 6e^3
    let v = Exact::additive_exponential().moment(3, 1.0).unwrap();
    let want = 12.0 * 1f64.exp().powi(4) - 6.0 * 1f64.exp().powi(3);
    assert!((v - want).abs() <= 1e-12 * want, "{v} vs {want}");
}

/// An empty system is valid on every scheme that starts from counts (a host drains a
/// cell and refills it), and its moments and concentrations are +0, not −0 (an empty
/// `sum()` of floats).
#[test]
fn an_empty_system_is_valid_and_its_moments_are_plus_zero() {
    let k = Coagulation::constant(1.0).unwrap();
    for info in count_schemes() {
        let id = registry::find(info.name).unwrap();
        for counts in [&[][..], &[0, 0, 0][..]] {
            let init = Init::Counts {
                counts,
                volume: 1.0,
            };
            let mut s: Box<Sim> = registry::build(
                id,
                Model::coagulation(k, NoFragmentation),
                &init,
                &Options::default(),
            )
            .unwrap_or_else(|e| panic!("{}: {e}", info.name));
            let rep = s.advance_to(1.0, &mut Pcg64Mcg::new(1)).unwrap();
            assert_eq!(rep.events, 0, "{}", info.name);
            for m in [0.0, 1.0, 2.0] {
                let v = s.moment(m);
                assert_eq!(v.to_bits(), 0, "{}: M{m} = {v:?}", info.name);
            }
        }
    }
}

/// Adjacent half-open size classes add up to the class they split, on every scheme,
/// and the closed `C(a, b)` would count the shared edge twice (the review's
/// `C(1,2) + C(2,4) − C(1,4) = n2`).
#[test]
fn adjacent_half_open_classes_add_up_to_the_whole() {
    use crate::common::standard;
    let k = Coagulation::constant(1.0).unwrap();
    for &info in registry::SCHEMES {
        let Some(mut s) = standard(info, 256, k) else {
            continue;
        };
        s.advance_to(0.5, &mut Pcg64Mcg::new(7)).unwrap();
        // edges on integer sizes (where the closed form double counts) and between them
        let edges = [0.5, 1.0, 2.0, 2.5, 4.0, 7.0, 1e9];
        let whole = s.class_concentration(edges[0], edges[edges.len() - 1]);
        assert!(whole > 0.0, "{}", info.name);
        let parts: f64 = edges
            .windows(2)
            .map(|w| s.class_concentration(w[0], w[1]))
            .sum();
        assert!(
            (parts - whole).abs() <= 1e-12 * whole,
            "{}: classes {parts} vs whole {whole}",
            info.name
        );
        // a class is its closed form minus its upper edge's points
        let (closed, edge) = (s.concentration(2.0, 4.0), s.concentration(4.0, 4.0));
        let half = s.class_concentration(2.0, 4.0);
        assert!(
            (closed - edge - half).abs() <= 1e-12 * closed.max(1.0),
            "{}",
            info.name
        );
        // degenerate and NaN classes are empty
        assert_eq!(s.class_concentration(3.0, 3.0), 0.0);
        assert_eq!(s.class_concentration(4.0, 3.0), 0.0);
        assert_eq!(s.class_concentration(f64::NAN, 3.0), 0.0);
    }
    // on integer sizes, n2 is in [2, 4) and not in [1, 2)
    let s =
        crate::common::build(registry::find("inverse").unwrap(), k, &[5, 3, 2, 1], 1.0).unwrap();
    assert_eq!(s.class_concentration(1.0, 2.0), 5.0);
    assert_eq!(s.class_concentration(2.0, 4.0), 5.0);
    assert_eq!(s.class_concentration(1.0, 4.0), 10.0);
    assert_eq!(s.concentration(1.0, 2.0) + s.concentration(2.0, 4.0), 14.0);
}

/// `set_pairs({1: 5000, 1000: 3, 2^30: 1})` took 8.4 GB and 10 s on the bucketed low
/// rank and then every advance failed: a largest size whose dense counts would take
/// more than half the memory budget is refused up front, the state unchanged.
#[test]
fn set_pairs_without_room_to_grow_is_refused_up_front() {
    use coagula_core::scheme::facade::Options;
    let k = Coagulation::constant(1.0).unwrap();
    for name in ["lowrank", "inverse", "dsa-counts"] {
        let id = registry::find(name).unwrap();
        // a budget of 64 MiB: 2^23 sizes of dense counts would take all of it
        let opts = Options::default().with_memory_budget(64 << 20);
        let init = Init::Counts {
            counts: &[100],
            volume: 1.0,
        };
        let mut s: Box<Sim> =
            registry::build(id, Model::coagulation(k, NoFragmentation), &init, &opts).unwrap();
        let e = s
            .set_pairs(&[1, 1000, 1 << 23], &[5000, 3, 1], 1.0)
            .unwrap_err();
        assert!(
            matches!(e, coagula_core::Error::Capacity { .. }),
            "{name}: {e}"
        );
        assert_eq!(s.particles(), 100, "{name}: state unchanged");
        // below the half it is taken
        s.set_pairs(&[1, 1000, 1 << 20], &[5000, 3, 1], 1.0)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.particles(), 5004);
    }
}

/// A first-hit kernel estimate of 2^50 trajectories never returned: within a work
/// budget it stops (no estimate), and an unlimited small one is as before.
#[test]
fn first_hit_kernel_honours_a_work_budget() {
    use coagula_core::langevin::Field;
    use coagula_core::langevin::kernel::{FirstHits, first_hit_kernel, first_hit_kernel_within};
    use coagula_core::scheme::Budget;
    let p = FirstHits {
        radius: 0.5,
        outer: 10.0,
        from: 0.4,
        to: 1.0,
        dt: 0.1,
        sigma: 0.0,
        velocity_sd: 1.0,
        trajectories: 1 << 50,
    };
    let zero = Field(|_, _: &[f64; 3], _: &[f64; 3]| [0.0; 3]);
    let r = first_hit_kernel_within::<3, _>(&p, &zero, 5, 0, &mut Budget::work(1_000_000));
    assert!(r.unwrap().is_none());
    let small = FirstHits {
        trajectories: 2000,
        ..p
    };
    let a = first_hit_kernel::<3, _>(&small, &zero, 5, 0).unwrap();
    let b = first_hit_kernel_within::<3, _>(&small, &zero, 5, 0, &mut Budget::work(2000 * 10))
        .unwrap()
        .expect("exactly enough units");
    assert_eq!(a.estimate.mean.to_bits(), b.estimate.mean.to_bits());
    // one chunk's worth of trajectories with one unit too few: stopped, not run whole
    // (a chunk was charged after the fact before: any chunk ran on one unit left)
    let mut short = Budget::work(2000 * 10 - 1);
    let r = first_hit_kernel_within::<3, _>(&small, &zero, 5, 0, &mut short).unwrap();
    assert!(r.is_none());
    assert!(
        short.left() < 10,
        "the covered trajectories ran: {}",
        short.left()
    );
    // one trajectory longer than the budget: nothing runs
    let long = FirstHits {
        trajectories: 1,
        to: 1e6,
        dt: 1e-6,
        ..p
    };
    let mut one = Budget::work(1000);
    assert!(
        first_hit_kernel_within::<3, _>(&long, &zero, 5, 0, &mut one)
            .unwrap()
            .is_none()
    );
    assert_eq!(one.left(), 1000);
}
