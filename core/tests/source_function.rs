//! A source rate given as a host's function of time with a bound (issue 42): thinning
//! within the source's share is exact for any rate under the bound — the same finite-N
//! chain as the equivalent schedule, on every scheme that takes processes; a value
//! above the bound is an error that changes nothing; split runs keep their bits.

use crate::common;
use crate::growth::same_bits_split;
use crate::processes::{
    chain_failures, checkpoint, monomers, process_schemes, rng, scheduled_reference, sim,
};

use coagula_core::Error;
use coagula_core::kernel::Coagulation;
use coagula_core::process::{Processes, UserRate};

/// The step function of `a_scheduled_source_follows_the_finite_n_master_equation`.
fn steps(t: f64) -> f64 {
    if t < 0.2 {
        0.3
    } else if t < 0.7 {
        2.0
    } else if t < 1.5 {
        0.0
    } else {
        0.8
    }
}

/// The rate as a function, drawn against a bound 1.5 times its largest value, follows
/// the finite-N chain of the same schedule: a source kept with the bound's probability
/// instead of the rate's (no thinning) would double the inflow; a bound per particle
/// instead of per volume would be off by V = 16.
#[test]
fn a_source_rate_function_follows_the_finite_n_master_equation() {
    let lambda = 0.5;
    let pieces = [(0.0, 0.3), (0.2, 2.0), (0.7, 0.0), (1.5, 0.8)];
    let times = [0.7, 1.5, 2.5];
    let exact = scheduled_reference(&pieces, lambda, 16, 16.0, &times);
    let procs = || {
        let f = UserRate::new(steps, 3.0, 11).unwrap();
        Processes::default()
            .with_source(monomers(0.0).with_rate_function(f).unwrap())
            .with_removal(lambda, 0.0)
            .unwrap()
    };
    let failures = chain_failures(procs, &times, &exact, 3000, 0x5f0e << 40);
    assert!(failures.is_empty(), "{failures}");
}

/// A schedule and a function are one or the other; a rate above the bound is an error
/// that leaves the state, the clock and the books as they were.
#[test]
fn a_source_rate_function_out_of_its_bound_changes_nothing() {
    let f = UserRate::new(|t: f64| if t < 1.0 { 0.5 } else { 4.0 }, 1.0, 12).unwrap();
    assert!(
        monomers(1.0)
            .with_schedule(&[1.0], &[2.0])
            .unwrap()
            .with_rate_function(f.clone())
            .is_err()
    );
    assert!(
        monomers(1.0)
            .with_rate_function(f.clone())
            .unwrap()
            .with_schedule(&[1.0], &[2.0])
            .is_err()
    );
    for id in process_schemes() {
        let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[40], 40.0);
        let src = monomers(0.0).with_rate_function(f.clone()).unwrap();
        s.set_processes(Some(Processes::default().with_source(src)))
            .unwrap();
        let mut g = rng(8);
        let e = s.advance_to(20.0, &mut g).unwrap_err();
        assert!(
            matches!(e, Error::BoundExceeded { .. }),
            "{}: {e}",
            id.label()
        );
        let (before, t, books) = (common::state_bits(&*s), s.time(), s.books());
        assert!(t >= 1.0, "{}: {t}", id.label());
        assert!(s.advance_to(30.0, &mut g).is_err());
        assert_eq!(common::state_bits(&*s), before, "{}", id.label());
        assert_eq!((s.time(), s.books()), (t, books), "{}", id.label());
    }
}

/// Split through checkpoints = unbroken, with a smooth rate function; another tag is
/// another function: refused.
#[test]
fn split_runs_with_a_rate_function_keep_their_bits() {
    let procs = |tag| {
        let f = UserRate::new(|t: f64| 1.0 + (3.0 * t).sin(), 2.0, tag).unwrap();
        Processes::default()
            .with_source(monomers(0.0).with_rate_function(f).unwrap())
            .with_removal(0.3, 0.0)
            .unwrap()
    };
    for id in process_schemes() {
        let make = |tag| {
            let mut s = sim(id, Coagulation::constant(1.0).unwrap(), &[50, 10], 30.0);
            s.set_processes(Some(procs(tag))).unwrap();
            s
        };
        let whole = same_bits_split(|| make(1), &[0.4, 1.7], 3.0, 4, &id.label());
        assert!(
            whole.books().unwrap().injected_number > 20,
            "{}",
            id.label()
        );
        let mut other = make(2);
        assert!(
            other.restore_checkpoint(&checkpoint(&*whole)).is_err(),
            "{}",
            id.label()
        );
    }
}
