//! What a host that drives a scheme step by step relies on (issue 14):
//! * an event-driven run does not depend on where the host stops it (the next proposal
//!   time is kept, not redrawn) — with the exact clock every scheme offers;
//! * a per-call budget interrupts a call with the state consistent at the time reached,
//!   and calling again continues the same run, bit for bit;
//! * a cancellation callback stops a call;
//! * rates whose waiting times cannot move the clock, a time step below the clock's
//!   resolution and a degenerate random stream are errors or bounded calls, never a
//!   hang.

use crate::common;

use coagula_core::Error;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::scheme::Budget;
use coagula_core::scheme::facade::{Init, Model, Options, SchemeId, Simulation, State};
use coagula_core::scheme::registry;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::{Infallible, TryRng};

type Sim = dyn Simulation<Coagulation, NoFragmentation, Pcg64Mcg>;

/// Scheme `id` from 3000 monomers plus a few larger particles, with the exact clock.
fn counts_sim(id: SchemeId, k: Coagulation) -> Option<Box<Sim>> {
    let counts = [3000, 40, 0, 7];
    let init = Init::Counts {
        counts: &counts,
        volume: 3000.0,
    };
    // a budget of 256 MiB: a run whose sizes run away reaches it in milliseconds, not
    // after growing to half the machine's memory (the default)
    let mut opts = Options::default().with_memory_budget(256 << 20);
    if id.takes_option("batched-clock") {
        opts = opts.with_batched_clock(false);
    }
    match registry::build(id, Model::coagulation(k, NoFragmentation), &init, &opts) {
        Ok(s) => Some(s),
        Err(Error::Unsupported { .. }) => None,
        Err(e) => panic!("{}: {e}", id.name),
    }
}

fn massflow_sim() -> Box<Sim> {
    let sizes: Vec<f64> = (0..256).map(|i| 1.0 + (i % 7) as f64).collect();
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    let opts = Options::default().with_dt(0.05);
    registry::build(
        registry::find("massflow").unwrap(),
        Model::coagulation(Coagulation::additive(), NoFragmentation),
        &init,
        &opts,
    )
    .unwrap()
}

/// Everything observable: time, state bits and totals.
fn snapshot(s: &Sim) -> (u64, Vec<u64>, u64, u64, u64) {
    let state = match s.state() {
        State::Counts(c, v) => c.iter().copied().chain([v.to_bits()]).collect::<Vec<u64>>(),
        State::Sizes(x) => x.iter().map(|v| v.to_bits()).collect(),
    };
    let t = s.totals();
    (
        s.time().to_bits(),
        state,
        t.events,
        t.proposals,
        t.doublings,
    )
}

fn kernels() -> [Coagulation; 3] {
    [
        Coagulation::constant(1.0).unwrap(),
        Coagulation::additive(),
        Coagulation::brownian(),
    ]
}

#[test]
fn stopping_on_the_way_does_not_change_an_event_driven_run() {
    let mut checked = 0;
    for k in kernels() {
        for info in common::count_schemes() {
            let Some(mut a) = counts_sim(info, k) else {
                continue;
            };
            let mut b = counts_sim(info, k).unwrap();
            let (mut ra, mut rb) = (Pcg64Mcg::new(5), Pcg64Mcg::new(5));
            a.advance_to(2.0, &mut ra).unwrap();
            for t in [0.7, 1.3, 1.3, 2.0] {
                b.advance_to(t, &mut rb).unwrap();
            }
            assert!(a.totals().events > 1000, "{}", info.name);
            assert_eq!(snapshot(&*a), snapshot(&*b), "{} {k:?}", info.name);
            checked += 1;
        }
    }
    assert!(checked >= 14, "{checked}");
}

#[test]
fn a_budget_interrupts_and_the_next_call_continues_the_same_run() {
    type Make = Box<dyn Fn() -> Box<Sim>>;
    let mut sims: Vec<(&str, Make, u64)> = vec![(
        "massflow",
        Box::new(massflow_sim),
        // particle updates: 256 per step, so a step at a time
        200,
    )];
    for info in common::count_schemes() {
        let id = info;
        let k = Coagulation::additive();
        if counts_sim(id, k).is_some() {
            sims.push((info.name, Box::new(move || counts_sim(id, k).unwrap()), 97));
        }
    }
    assert!(sims.len() >= 6);
    for (name, make, units) in sims {
        let (mut a, mut b) = (make(), make());
        let (mut ra, mut rb) = (Pcg64Mcg::new(9), Pcg64Mcg::new(9));
        a.advance_to(1.5, &mut ra).unwrap();
        let mut calls = 0u64;
        let mut proposals = 0;
        loop {
            calls += 1;
            let before = b.time();
            let rep = b
                .advance_within(1.5, &mut Budget::work(units), &mut rb)
                .unwrap();
            proposals += rep.proposals;
            assert_eq!(rep.time, b.time(), "{name}");
            assert!(b.time() >= before, "{name}");
            if !rep.interrupted {
                break;
            }
            assert!(b.time() < 1.5, "{name}: interrupted at the target");
            assert!(calls < 1_000_000, "{name}: no progress");
        }
        assert!(calls > 5, "{name}: {calls} calls");
        assert_eq!(proposals, b.totals().proposals, "{name}");
        assert_eq!(b.time(), 1.5, "{name}");
        assert_eq!(snapshot(&*a), snapshot(&*b), "{name}");
    }
}

#[test]
fn a_cancellation_callback_stops_the_call() {
    // (enough particles that the run to t = 1e6 takes more than 2 POLL_EVERY
    // proposals: about 4 10^4 events)
    let counts = [20_000, 40, 0, 7];
    let init = Init::Counts {
        counts: &counts,
        volume: 20_000.0,
    };
    let opts = Options::default().with_batched_clock(false);
    let k = Coagulation::constant(1.0).unwrap();
    let mut s: Box<Sim> = registry::build(
        registry::find("lowrank").unwrap(),
        Model::coagulation(k, NoFragmentation),
        &init,
        &opts,
    )
    .unwrap();
    let mut rng = Pcg64Mcg::new(1);
    let mut polls = 0;
    let mut cancel = || {
        polls += 1;
        polls >= 2
    };
    let rep = s
        .advance_within(
            1e6,
            &mut Budget::unlimited().with_cancel(&mut cancel),
            &mut rng,
        )
        .unwrap();
    assert!(rep.interrupted);
    assert_eq!(polls, 2);
    // polled before every POLL_EVERY-th proposal: the second poll stopped the call
    // before its proposal
    assert_eq!(rep.proposals, 2 * coagula_core::scheme::POLL_EVERY - 1);
    assert!(s.time() < 1e6);
    // the mass-flow scheme polls before each step
    let mut m = massflow_sim();
    let mut steps = 0;
    let mut cancel = || {
        steps += 1;
        steps > 3
    };
    let rep = m
        .advance_within(
            10.0,
            &mut Budget::unlimited().with_cancel(&mut cancel),
            &mut rng,
        )
        .unwrap();
    assert!(rep.interrupted);
    assert_eq!(m.time(), 3.0 * 0.05);
}

#[test]
fn waiting_times_that_cannot_move_the_clock_are_errors() {
    // K = 1e300: the mean wait between proposals is ~1e-303, below the resolution of
    // any time past 1e-287
    for info in common::count_schemes() {
        let Some(mut s) = counts_sim(info, Coagulation::constant(1e300).unwrap()) else {
            continue;
        };
        let mut rng = Pcg64Mcg::new(2);
        let r = s.advance_to(1.0, &mut rng);
        if info.name == "dsa-counts" {
            // without doubling every particle merges within ~1e-300 (the waits stay
            // resolvable near t = 0): one particle left, then nothing can happen
            assert!(r.is_ok() && s.particles() == 1, "{}: {r:?}", info.name);
            continue;
        }
        assert!(
            matches!(r, Err(Error::InvalidRate { .. } | Error::Capacity { .. })),
            "{}: {r:?}",
            info.name
        );
    }
    // a time step that cannot move the mass-flow clock
    let mut m = massflow_sim();
    let mut rng = Pcg64Mcg::new(2);
    m.advance_to(1.0, &mut rng).unwrap();
    m.set_dt(1e-300).unwrap();
    let r = m.advance_to(2.0, &mut rng);
    assert!(matches!(r, Err(Error::OutOfRange { .. })), "{r:?}");
    assert_eq!(m.time(), 1.0);
}

/// A generator stuck on one word (a broken host callback).
struct Stuck(u64);

impl TryRng for Stuck {
    type Error = Infallible;
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok(self.0 as u32)
    }
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        Ok(self.0)
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        dst.fill(self.0 as u8);
        Ok(())
    }
}

#[test]
fn a_stuck_random_stream_cannot_hang_a_call() {
    type StuckSim = dyn Simulation<Coagulation, NoFragmentation, Stuck>;
    let mut built = 0;
    for word in [0, u64::MAX, 0x8000_0000_0000_0000, 0x0123_4567_89ab_cdef] {
        for &info in registry::SCHEMES {
            for batched in [false, true] {
                let mut opts = crate::common::options_for(info);
                if info.takes_option("batched-clock") {
                    opts = opts.with_batched_clock(batched);
                }
                if info.takes_option("dt") {
                    opts = opts.with_dt(0.1);
                }
                // sizes a stuck stream runs away with stop at 256 MiB, not at half the
                // machine's memory (the default)
                if info.takes_option("memory-budget") {
                    opts = opts.with_memory_budget(256 << 20);
                }
                // every scheme from its standard start (a particle list from 4 sizes)
                let start = crate::common::Start::monomers(4);
                let init = start.init(info);
                let model = crate::common::model_for(info, Coagulation::additive());
                let mut s: Box<StuckSim> = match registry::build(info, model, &init, &opts) {
                    Ok(s) => s,
                    Err(Error::Unsupported { .. }) => continue,
                    Err(e) => panic!("{e}"),
                };
                // bounded by the budget, whatever the stream does
                let mut rng = Stuck(word);
                let r = s.advance_within(2.0, &mut Budget::work(1 << 14), &mut rng);
                if let Ok(rep) = r {
                    assert!(rep.proposals <= 1 << 14, "{}", info.name);
                }
                built += 1;
            }
        }
    }
    // every scheme of the registry (the particle-list ones from sizes), both clocks,
    // each word
    assert_eq!(built, 4 * 2 * registry::SCHEMES.len(), "schemes skipped");
}

#[test]
fn occupied_sizes_without_a_count_vector_match_the_dense_state() {
    for k in kernels() {
        for info in common::count_schemes() {
            let Some(mut s) = counts_sim(info, k) else {
                continue;
            };
            s.advance_to(1.5, &mut Pcg64Mcg::new(4)).unwrap();
            let mut pairs = Vec::new();
            s.for_each_count(&mut |size, n| pairs.push((size, n)))
                .unwrap();
            let State::Counts(dense, v) = s.state() else {
                panic!("counts")
            };
            let want: Vec<(u64, u64)> = dense
                .iter()
                .enumerate()
                .filter(|(_, n)| **n > 0)
                .map(|(i, &n)| (i as u64 + 1, n))
                .collect();
            assert_eq!(pairs, want, "{}", info.name);
            assert!(pairs.len() > 5, "{}: {} sizes", info.name, pairs.len());
            // the moments from the occupied sizes are the dense ones, bit for bit
            for m in [0.0, 1.0, 2.0, 0.5] {
                let dense_m = coagula_core::observe::moment_of_counts(&dense, v, m);
                let got = s.moment(m);
                if matches!(info.name, "inverse" | "rejection") {
                    // (summed in their own order: occupied slots, particles)
                    assert!((got - dense_m).abs() <= 1e-12 * dense_m, "{}", info.name);
                } else {
                    assert_eq!(got.to_bits(), dense_m.to_bits(), "{} M{m}", info.name);
                }
            }
            assert!(s.for_each_count(&mut |_, _| {}).is_ok());
        }
    }
    assert!(massflow_sim().for_each_count(&mut |_, _| {}).is_err());
}

#[test]
fn an_empty_system_is_valid_and_can_be_refilled() {
    for info in common::count_schemes() {
        let init = Init::Counts {
            counts: &[0, 0, 0],
            volume: 10.0,
        };
        let mut s: Box<Sim> = match registry::build(
            info,
            Model::coagulation(Coagulation::additive(), NoFragmentation),
            &init,
            &Options::default(),
        ) {
            Ok(s) => s,
            Err(Error::Unsupported { .. }) => continue,
            Err(e) => panic!("{}: {e}", info.name),
        };
        let mut rng = Pcg64Mcg::new(3);
        s.advance_to(2.0, &mut rng).unwrap();
        assert_eq!((s.particles(), s.moment(0.0), s.moment(1.0)), (0, 0.0, 0.0));
        assert_eq!(s.gel_mass(), Some(0.0));
        assert_eq!(s.concentration(0.0, 10.0), 0.0);
        let mut w = coagula_core::checkpoint::Writer::new(&mut []);
        s.save(&mut w);
        let mut buf = vec![0u8; w.needed()];
        s.save(&mut coagula_core::checkpoint::Writer::new(&mut buf));
        s.restore(&mut coagula_core::checkpoint::Reader::new(&buf))
            .unwrap();
        // drained, refilled, run on
        s.set_counts(&[500, 10], 500.0).unwrap();
        s.advance_to(3.0, &mut rng).unwrap();
        assert!(s.particles() < 510 && s.particles() > 0, "{}", info.name);
        s.set_counts(&[], 500.0).unwrap();
        s.advance_to(4.0, &mut rng).unwrap();
        assert_eq!(s.particles(), 0, "{}", info.name);
    }
}

/// Review of issue 14: a tree layout updated by differences (Brownian and
/// free-molecular factors are irrational) may hold weights a rounding away from a
/// rebuild, some below 0; restore must accept the checkpoints a long run leaves.
#[test]
fn long_runs_restore_from_their_own_checkpoints() {
    for k in [
        Coagulation::brownian(),
        Coagulation::free_molecular().with_min_size(1.0).unwrap(),
    ] {
        for info in common::count_schemes() {
            let Some(mut a) = counts_sim(info, k) else {
                continue;
            };
            let mut rng = Pcg64Mcg::new(8);
            let mut b = counts_sim(info, k).unwrap();
            for t in [5.0, 50.0, 400.0, 4000.0] {
                a.advance_to(t, &mut rng).unwrap();
                let mut w = coagula_core::checkpoint::Writer::new(&mut []);
                a.save(&mut w);
                let mut buf = vec![0u8; w.needed()];
                a.save(&mut coagula_core::checkpoint::Writer::new(&mut buf));
                b.restore(&mut coagula_core::checkpoint::Reader::new(&buf))
                    .unwrap_or_else(|e| panic!("{} {k:?} t = {t}: {e}", info.name));
                assert_eq!(snapshot(&*a), snapshot(&*b), "{}", info.name);
            }
            // (direct simulation over counts does not double: it merges its ~3000
            // particles down to a few hundred by t = 4000)
            let least = if info.name == "dsa-counts" {
                2_500
            } else {
                15_000
            };
            assert!(
                a.totals().events > least,
                "{}: {}",
                info.name,
                a.totals().events
            );
        }
    }
}
