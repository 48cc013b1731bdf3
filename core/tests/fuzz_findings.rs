//! The situations of the C-ABI fuzzing campaigns' findings 2–4 and 9–12 (docs/results/fuzzing.md),
//! rebuilt on every size-count scheme through the facade. The byte-level reproducers of
//! findings 1–4 were lost to a `crash-*` ignore pattern that also matched
//! `fuzz/regressions/`; these tests are not those inputs: the ones for findings 3 and 4
//! pass on the code before their fixes too (the fuzzer's paths went through
//! `set_counts` and clones of states these simple runs do not reach), so they guard
//! the properties, not the exact defects.

use crate::common::{Sim, build, count_schemes};
use coagula_core::checkpoint::{Reader, Writer};
use coagula_core::kernel::Coagulation;
use coagula_core::scheme::facade::State;
use rand_pcg::Pcg64Mcg;

fn save(s: &Sim) -> Vec<u8> {
    let mut w = Writer::new(&mut []);
    s.save(&mut w);
    let mut buf = vec![0u8; w.needed()];
    let mut w = Writer::new(&mut buf);
    s.save(&mut w);
    w.finish().unwrap();
    buf
}

fn counts(s: &Sim) -> Vec<u64> {
    match s.state() {
        State::Counts(c, _) => c.into_owned(),
        State::Sizes(_) => unreachable!("a size-count scheme"),
    }
}

/// Finding 3: a sim that has doubled its particles restores from its own checkpoint
/// (the bucketed layout refused it: a bucket's remembered particle count was bounded by
/// N0, but doublings double it).
#[test]
fn a_doubled_sim_restores_from_its_own_checkpoint() {
    let k = Coagulation::constant(1.0).unwrap();
    for info in count_schemes() {
        let Some(mut a) = build(info, k, &[64], 64.0) else {
            continue;
        };
        let mut rng = Pcg64Mcg::new(3);
        for h in 1..=40 {
            a.advance_to(f64::from(h), &mut rng).unwrap();
            let buf = save(&*a);
            let mut b = build(info, k, &[64], 64.0).unwrap();
            b.restore(&mut Reader::new(&buf))
                .unwrap_or_else(|e| panic!("{} at t = {h}: {e}", info.name));
            assert_eq!(counts(&*b), counts(&*a), "{}", info.name);
        }
        // (direct simulation over counts never doubles: it checks the restores only)
        if info.name != "dsa-counts" {
            assert!(a.totals().doublings > 0, "{}: no doubling", info.name);
        }
    }
}

/// Finding 4: an advance refused because the rate is too large to move the clock leaves
/// a state that restores (the low-rank clock was left at a mean wait of 0, and a clone
/// refused it), and the sim runs again once the kernel is sane: K0 = 1e300, whose waits
/// are below the resolution of the clock at t = 1.
#[test]
fn a_sim_refused_for_a_huge_rate_restores_and_runs_on() {
    let huge = Coagulation::constant(1e300).unwrap();
    let sane = Coagulation::constant(1.0).unwrap();
    for (volume, t0) in [(1.0, 1.0)] {
        for info in count_schemes() {
            let Some(mut a) = build(info, huge, &[3000, 40], volume) else {
                continue;
            };
            let mut rng = Pcg64Mcg::new(5);
            a.set_time(t0).unwrap();
            let r = a.advance_to(t0 + 1.0, &mut rng);
            assert!(
                matches!(r, Err(coagula_core::Error::InvalidRate { .. })),
                "{} V = {volume}: {r:?}",
                info.name
            );
            let buf = save(&*a);
            let mut b = build(info, huge, &[3000, 40], volume).unwrap();
            b.restore(&mut Reader::new(&buf))
                .unwrap_or_else(|e| panic!("{} V = {volume}: {e}", info.name));
            b.set_kernel(sane).unwrap();
            b.set_time(0.0).unwrap();
            let rep = b
                .advance_within(1.0, &mut coagula_core::scheme::Budget::work(1000), &mut rng)
                .unwrap();
            assert!(rep.proposals > 0, "{}", info.name);
        }
    }
}

/// Finding 9: rates that overflow to infinity in the per-size tree (K0 ≈ 7e305, counts up
/// to 255, the fuzzer's case) make a state the scheme holds but refuses to advance; a
/// clone of it (checkpoint and restore) failed because restore compared the tree's sums
/// with a tolerance that infinity never meets. Every count scheme now either refuses to
/// build it or holds it, restores it, refuses to advance it (the state unchanged) and
/// runs on after a sane kernel.
#[test]
fn a_state_with_overflowed_rates_clones_and_recovers() {
    let huge = Coagulation::constant(f64::from_bits(0x7f7f_7f7f_7f7f_7f7b)).unwrap();
    let sane = Coagulation::constant(1.0).unwrap();
    let start = [255, 115, 255, 115, 115, 115, 115, 141];
    let mut held = 0;
    for info in count_schemes() {
        let Some(mut a) = build(info, sane, &[60], 60.0) else {
            continue;
        };
        if a.set_kernel(huge).is_err() || a.set_counts(&start, 1.0).is_err() {
            continue;
        }
        held += 1;
        let buf = save(&*a);
        let mut b = build(info, huge, &[60], 60.0).unwrap();
        b.restore(&mut Reader::new(&buf))
            .unwrap_or_else(|e| panic!("{}: {e}", info.name));
        assert_eq!(save(&*b), buf, "{}", info.name);
        let mut rng = Pcg64Mcg::new(11);
        assert!(b.advance_to(1.0, &mut rng).is_err(), "{}", info.name);
        assert_eq!(
            save(&*b),
            buf,
            "{}: a refused advance changed it",
            info.name
        );
        b.set_kernel(sane).unwrap();
        let rep = b
            .advance_within(1.0, &mut coagula_core::scheme::Budget::work(1000), &mut rng)
            .unwrap();
        assert!(rep.proposals > 0, "{}", info.name);
    }
    assert!(held >= 2, "only {held} schemes held the state");
}

/// Finding 10: a kernel constant near the largest double (0x7f7f…7f, ≈ 3.4e305) with 13
/// monomers in a volume of 4.8e-4 made the bucketed layout's alias weights overflow a
/// u64 (`ck · 2^61` went to infinity before the division by `S_A`): a panic in a build
/// with overflow checks, a bucket silently never drawn without them. Every count scheme
/// now returns from these calls (Ok or Err), never a panic.
#[test]
fn kernels_near_the_largest_double_do_not_overflow_the_tables() {
    let huge = Coagulation::constant(f64::from_bits(0x7f7f_7f7f_7f7f_7f7f)).unwrap();
    let sane = Coagulation::constant(1.0).unwrap();
    let v = f64::from_bits(0x3f3f_3f3f_3f3f_3f3f);
    let mut ran = 0;
    for info in count_schemes() {
        // (a 1 MiB budget, as the fuzzer's sims: the default 2 GiB lets the size table
        // grow for seconds at this rate)
        let init = coagula_core::scheme::facade::Init::Counts {
            counts: &[60],
            volume: 60.0,
        };
        let opts = coagula_core::scheme::facade::Options::default().with_memory_budget(1 << 20);
        let Ok(mut a) = coagula_core::scheme::registry::build::<_, _, Pcg64Mcg>(
            info,
            coagula_core::scheme::facade::Model::coagulation(
                sane,
                coagula_core::kernel::NoFragmentation,
            ),
            &init,
            &opts,
        ) else {
            continue;
        };
        if a.set_kernel(huge).is_err() {
            continue;
        }
        let mut rng = Pcg64Mcg::new(12);
        if a.set_counts(&[13], v).is_err() {
            continue;
        }
        ran += 1;
        // (bounded calls: the waits at this rate are ~1e-300, the C ABI's work limit)
        for h in [47.0, 47.0, 13.0] {
            let _ = a.advance_within(
                a.time() + h / 64.0,
                &mut coagula_core::scheme::Budget::work(2000),
                &mut rng,
            );
        }
    }
    assert!(ran >= 2, "only {ran} schemes took the state");
}

/// Finding 11: a mean wait near the largest double (K0 = 1e-307, one pair in V = 10:
/// 1e308) times an exponential variate above 1 puts the pending proposal at +inf; the
/// sim holds it (the proposal never comes) but a clone refused it. Every count scheme
/// now restores such a state, the proposal still pending.
#[test]
fn a_proposal_pending_at_infinity_restores() {
    let tiny = Coagulation::constant(1e-307).unwrap();
    let mut at_inf = 0;
    for info in count_schemes() {
        for seed in 0..16 {
            let Some(mut a) = build(info, tiny, &[2], 10.0) else {
                break;
            };
            let mut rng = Pcg64Mcg::new(seed);
            if a.advance_to(1.0, &mut rng).is_err() {
                continue;
            }
            let buf = save(&*a);
            let mut b = build(info, tiny, &[2], 10.0).unwrap();
            b.restore(&mut Reader::new(&buf))
                .unwrap_or_else(|e| panic!("{} seed {seed}: {e}", info.name));
            assert_eq!(save(&*b), buf, "{}", info.name);
            at_inf += 1;
        }
    }
    assert!(at_inf > 16, "{at_inf} restores");
}

/// Finding 2: step counters restored near 2^64 saturate in the next advance instead of
/// overflowing (the checkpoint is edited where it holds the event counter).
#[test]
fn counters_near_the_top_of_u64_saturate() {
    let k = Coagulation::additive();
    for info in count_schemes() {
        let Some(mut a) = build(info, k, &[4096], 4096.0) else {
            continue;
        };
        let mut rng = Pcg64Mcg::new(8);
        a.advance_to(0.5, &mut rng).unwrap();
        let events = a.totals().events;
        let mut buf = save(&*a);
        let at: Vec<usize> = (0..buf.len() - 7)
            .filter(|&i| buf[i..i + 8] == events.to_le_bytes())
            .collect();
        // the event counter, and the proposal counter when every proposal was accepted
        assert!(
            matches!(at.len(), 1 | 2),
            "{}: the event counter's place",
            info.name
        );
        for i in at {
            buf[i..i + 8].copy_from_slice(&(u64::MAX - 2).to_le_bytes());
        }
        // (the facade's save() writes no checksum: the edited bytes are read as they are)
        let mut b = build(info, k, &[4096], 4096.0).unwrap();
        b.restore(&mut Reader::new(&buf))
            .unwrap_or_else(|e| panic!("{}: {e}", info.name));
        assert_eq!(b.totals().events, u64::MAX - 2);
        b.advance_to(1.0, &mut rng).unwrap();
        assert_eq!(b.totals().events, u64::MAX, "{}", info.name);
    }
}

/// Finding 12: a state stopped by the work budget right after a particle doubling
/// restores. The doubling's resync rebuilds the buckets' slots (dropping the empties of
/// removals) and leaves the proposal tables stale until the next proposal; a bucket's
/// table slots `tab` may then exceed its slots, which restore refused ("bucket slots
/// inconsistent"), so a host could not clone the sim. Two monomers in a volume of
/// 8e-256 under the additive kernel, calls of 500 units, as the fuzzer had it.
#[test]
fn a_state_stopped_after_a_doubling_restores() {
    use coagula_core::scheme::Budget;
    let k = Coagulation::additive();
    let v = 8.154920269121583e-256;
    let mut restored = 0;
    for info in count_schemes() {
        for seed in 0..32 {
            let Some(mut a) = build(info, k, &[2], v) else {
                break;
            };
            let mut rng = Pcg64Mcg::new(seed);
            for h in [205.0, 460.0] {
                let mut budget = Budget::work(500);
                if a.advance_within(h / 64.0, &mut budget, &mut rng).is_err() {
                    break;
                }
                let buf = save(&*a);
                let mut b = build(info, k, &[2], v).unwrap();
                b.restore(&mut Reader::new(&buf))
                    .unwrap_or_else(|e| panic!("{} seed {seed}: {e}", info.name));
                assert_eq!(save(&*b), buf, "{}", info.name);
                restored += 1;
            }
        }
    }
    assert!(restored > 32, "{restored} restores");
}
