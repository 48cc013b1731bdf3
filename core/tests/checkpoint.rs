//! A run split by checkpoint and restore is bit-identical to the run without a break,
//! for every scheme; bad checkpoints are refused and leave the target unchanged.

use coagula_core::checkpoint::Checkpoint;
use coagula_core::kernel::{BinaryUniform, Coagulation};
use coagula_core::qmc::Randomization;
use coagula_core::scheme::Scheme;
use coagula_core::scheme::baseline::{AcceptanceRejection, Inverse};
use coagula_core::scheme::lowrank::{AutoBucketed, BucketMode, Bucketed, BucketedCounted, LowRank};
use coagula_core::scheme::massflow::{MassFlow, PointSource};
use rand_pcg::Pcg64Mcg;

/// Runs `make()` to `t1`, checkpoints, runs on to `t2`; restores the checkpoint into a
/// fresh `make()` and runs it to `t2` with the RNG as it was at the checkpoint.
fn split_equals_unbroken<S, F, O>(make: F, t1: f64, t2: f64, observe: O)
where
    S: Scheme + Checkpoint,
    F: Fn() -> S,
    O: Fn(&S) -> Vec<u64>,
{
    let mut a = make();
    let mut rng = Pcg64Mcg::new(11);
    a.advance_to(t1, &mut rng).unwrap();
    let mut buf = vec![0u8; a.checkpoint_len()];
    assert_eq!(a.save_to(&mut buf).unwrap(), buf.len());
    let rng_at_save = rng.clone();
    a.advance_to(t2, &mut rng).unwrap();

    let mut b = make();
    b.restore_from(&buf).unwrap();
    let mut rng_b = rng_at_save;
    b.advance_to(t2, &mut rng_b).unwrap();
    assert_eq!(observe(&a), observe(&b), "state differs after restore");
    assert_eq!(a.time().to_bits(), b.time().to_bits());

    // a truncated or foreign buffer is refused and changes nothing
    let mut c = make();
    let before = observe(&c);
    assert!(c.restore_from(&buf[..buf.len() / 2]).is_err());
    let mut wrong = buf.clone();
    wrong[0] ^= 1;
    assert!(c.restore_from(&wrong).is_err());
    assert_eq!(observe(&c), before);
    // too small a buffer for saving is an error
    assert!(a.save_to(&mut [0u8; 10]).is_err());
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn massflow_qmc_mc_and_rqmc() {
    let k = Coagulation::constant(1.0).unwrap();
    let f = BinaryUniform::new(1.0).unwrap();
    let scrambled = {
        let mut r = Pcg64Mcg::new(3);
        PointSource::randomized_niederreiter(Randomization::Owen, &mut r)
    };
    for src in [
        PointSource::niederreiter(),
        PointSource::monte_carlo(),
        scrambled,
    ] {
        let make = || MassFlow::new(k, f, &[1.0; 1024], 1.0, 0.01, src.clone()).unwrap();
        split_equals_unbroken(make, 0.3, 0.7, |s| bits(s.sizes()));
    }
    // restoring into a scheme with another randomisation is refused
    let mut r = Pcg64Mcg::new(4);
    let a = MassFlow::new(
        k,
        f,
        &[1.0; 64],
        1.0,
        0.01,
        PointSource::randomized_niederreiter(Randomization::Owen, &mut r),
    )
    .unwrap();
    let mut b = MassFlow::new(
        k,
        f,
        &[1.0; 64],
        1.0,
        0.01,
        PointSource::randomized_niederreiter(Randomization::Owen, &mut r),
    )
    .unwrap();
    let mut buf = vec![0u8; a.checkpoint_len()];
    a.save_to(&mut buf).unwrap();
    assert!(b.restore_from(&buf).is_err());
}

#[test]
fn lowrank_and_baselines() {
    let k = Coagulation::brownian();
    split_equals_unbroken(
        || LowRank::<_, 2>::monodisperse(k, 4000).unwrap(),
        1.0,
        5.0,
        |s| s.counts().to_vec(),
    );
    split_equals_unbroken(
        || Inverse::monodisperse(k, 2000).unwrap(),
        1.0,
        3.0,
        |s| s.counts(),
    );
    split_equals_unbroken(
        || AcceptanceRejection::monodisperse(k, 2000).unwrap(),
        1.0,
        3.0,
        |s| s.counts(),
    );
    // additive kernel: particle doubling and M doubling happen between the two halves
    let a = Coagulation::additive();
    split_equals_unbroken(
        || LowRank::<_, 1>::monodisperse(a, 4000).unwrap(),
        0.5,
        2.5,
        |s| s.counts().to_vec(),
    );
}

#[test]
fn bucketed_small_large_and_pipelined() {
    let k = Coagulation::brownian();
    // below 4096 particles: an exponential per proposal
    split_equals_unbroken(
        || Bucketed::<_, 2, 4>::monodisperse(k, 1000).unwrap(),
        1.0,
        5.0,
        |s| s.counts().into_owned(),
    );
    // batches, particle doublings and M doublings between the halves
    let a = Coagulation::additive();
    split_equals_unbroken(
        || Bucketed::<_, 1, 2>::monodisperse(a, 20_000).unwrap(),
        0.5,
        2.5,
        |s| s.counts().into_owned(),
    );
    // a count array past 2^18 sizes: proposals are drawn ahead, and those draws are
    // part of the state
    let mut probe = Bucketed::<_, 1, 2>::monodisperse(a, 100_000).unwrap();
    probe.advance_to(5.2, &mut Pcg64Mcg::new(11)).unwrap();
    assert!(probe.max_size() >= 1 << 18, "M = {}", probe.max_size());
    split_equals_unbroken(
        || Bucketed::<_, 1, 2>::monodisperse(a, 100_000).unwrap(),
        5.2,
        5.6,
        |s| s.counts().into_owned(),
    );
    // past 2^20 slots: whole proposals are drawn ahead from the start, and the queue
    // of them is part of the state (that it is non-empty at a save, and each of its
    // fields validated, is `bucketed::tests::restore_refuses_a_bad_queue_drawn_ahead`)
    let c = Coagulation::constant(1.0).unwrap();
    split_equals_unbroken(
        || Bucketed::<_, 1, 2>::monodisperse(c, 1 << 21).unwrap(),
        0.2,
        0.4,
        |s| s.counts().into_owned(),
    );
}

/// The counted bucketed engine: split = unbroken through M doublings and particle
/// doublings (its tree holds incremental sums, so the checkpoint keeps them), rank 1
/// and rank 3.
#[test]
fn bucketed_counted_split() {
    split_equals_unbroken(
        || BucketedCounted::<_, 1, 2>::monodisperse(Coagulation::additive(), 3000).unwrap(),
        1.0,
        3.0,
        |s| s.counts().into_owned(),
    );
    let k = Coagulation::free_molecular().with_min_size(1.0).unwrap();
    split_equals_unbroken(
        || BucketedCounted::<_, 3, 6>::monodisperse(k, 500).unwrap(),
        2.0,
        40.0,
        |s| s.counts().into_owned(),
    );
}

/// The registry's `lowrank` restores a checkpoint into whichever engine wrote it
/// (a host's clone builds a blank small system and restores into it), continues the
/// same run bit for bit, and chooses the engine again when the counts are replaced.
#[test]
fn auto_bucketed_restores_across_engines() {
    let k = Coagulation::constant(1.0).unwrap();
    for n0 in [40_000u64, 900] {
        let mut a = AutoBucketed::<_, 1, 2>::new(k, &[n0], n0 as f64).unwrap();
        let mode = if n0 > 16_384 {
            BucketMode::Slots
        } else {
            BucketMode::Counted
        };
        assert_eq!(a.mode(), mode);
        let mut rng = Pcg64Mcg::new(5);
        a.advance_to(1.0, &mut rng).unwrap();
        let mut buf = vec![0u8; a.checkpoint_len()];
        a.save_to(&mut buf).unwrap();
        let n_saved = coagula_core::observe::Observe::particles(&a);
        let rng_at_save = rng.clone();
        a.advance_to(2.0, &mut rng).unwrap();
        // a blank of the other engine takes the checkpoint
        let blank = if n0 > 16_384 { 2 } else { 1 << 15 };
        let mut b = AutoBucketed::<_, 1, 2>::new(k, &[blank], 1.0).unwrap();
        assert_ne!(b.mode(), mode);
        b.restore_from(&buf).unwrap();
        assert_eq!(b.mode(), mode);
        let mut rng_b = rng_at_save;
        b.advance_to(2.0, &mut rng_b).unwrap();
        assert_eq!(a.counts(), b.counts());
        assert_eq!(a.time().to_bits(), b.time().to_bits());
        // a checkpoint of the other engine that its own validation refuses (the particle
        // number, word 6 after magic, version, tag, rank, M and the size limit, one
        // more than its counts; resealed) leaves the target unchanged
        let mut c = AutoBucketed::<_, 1, 2>::new(k, &[blank], 1.0).unwrap();
        let mut bad = buf.clone();
        let n = u64::from_le_bytes(bad[48..56].try_into().unwrap());
        assert_eq!(n, n_saved);
        bad[48..56].copy_from_slice(&(n + 1).to_le_bytes());
        let body = bad.len() - 8;
        let sum = coagula_core::checkpoint::checksum(&bad[..body]);
        bad[body..].copy_from_slice(&sum.to_le_bytes());
        assert!(c.restore_from(&bad).is_err());
        assert_ne!(c.mode(), mode);
        assert_eq!(c.counts()[0], blank);
        assert_eq!(coagula_core::observe::Observe::particles(&c), blank);
    }
    // replacing the counts chooses the engine again; time and totals carry over
    let mut s = AutoBucketed::<_, 1, 2>::new(k, &[1000], 1000.0).unwrap();
    s.advance_to(0.5, &mut Pcg64Mcg::new(1)).unwrap();
    let (t, events) = (s.time(), coagula_core::scheme::Scheme::totals(&s).events);
    s.set_counts(&[50_000], 50_000.0).unwrap();
    assert_eq!(s.mode(), BucketMode::Slots);
    assert_eq!(
        (s.time(), coagula_core::scheme::Scheme::totals(&s).events),
        (t, events)
    );
    s.set_counts(&[300], 300.0).unwrap();
    assert_eq!(s.mode(), BucketMode::Counted);
    assert_eq!(coagula_core::observe::Observe::particles(&s), 300);
}

/// A pinned engine: chosen against the size, kept through `set_counts`, switched in
/// place with the state, time and totals carried over, and a checkpoint of the other
/// engine refused with the scheme unchanged; the registry's option pins it too.
#[test]
fn auto_bucketed_pinned_engine() {
    let k = Coagulation::constant(1.0).unwrap();
    let budget = coagula_core::scheme::lowrank::DEFAULT_MEMORY_BUDGET;
    for pin in [BucketMode::Slots, BucketMode::Counted] {
        for n0 in [900u64, 40_000] {
            let s = AutoBucketed::<_, 1, 2>::new_with_mode(k, &[n0], n0 as f64, budget, Some(pin))
                .unwrap();
            assert_eq!((s.mode(), s.pinned()), (pin, Some(pin)));
        }
    }
    let mut s = AutoBucketed::<_, 1, 2>::new_with_mode(
        k,
        &[40_000],
        40_000.0,
        budget,
        Some(BucketMode::Counted),
    )
    .unwrap();
    s.set_counts(&[300], 300.0).unwrap();
    s.set_counts(&[50_000], 50_000.0).unwrap();
    assert_eq!(s.mode(), BucketMode::Counted);
    // switching in place carries the state over exactly
    let mut rng = Pcg64Mcg::new(3);
    s.advance_to(0.5, &mut rng).unwrap();
    let (counts, t, events) = (
        s.counts().into_owned(),
        s.time(),
        coagula_core::scheme::Scheme::totals(&s).events,
    );
    assert!(events > 0);
    s.set_mode(Some(BucketMode::Slots)).unwrap();
    assert_eq!(
        (s.mode(), s.pinned()),
        (BucketMode::Slots, Some(BucketMode::Slots))
    );
    assert_eq!(s.counts().into_owned(), counts);
    assert_eq!(
        (s.time(), coagula_core::scheme::Scheme::totals(&s).events),
        (t, events)
    );
    // unpinned: the engine stays until the counts are replaced, then follows the size
    s.set_mode(None).unwrap();
    assert_eq!((s.mode(), s.pinned()), (BucketMode::Slots, None));
    s.set_counts(&[300], 300.0).unwrap();
    assert_eq!(s.mode(), BucketMode::Counted);
    // the counted engine's checkpoint into a scheme pinned to slots: refused, unchanged
    let mut a = AutoBucketed::<_, 1, 2>::new(k, &[900], 900.0).unwrap();
    a.advance_to(1.0, &mut Pcg64Mcg::new(4)).unwrap();
    let mut buf = vec![0u8; a.checkpoint_len()];
    a.save_to(&mut buf).unwrap();
    let mut p = AutoBucketed::<_, 1, 2>::new(k, &[700], 700.0)
        .unwrap()
        .with_mode(Some(BucketMode::Slots))
        .unwrap();
    let mut before = vec![0u8; p.checkpoint_len()];
    p.save_to(&mut before).unwrap();
    let err = p.restore_from(&buf).unwrap_err();
    assert!(
        matches!(err, coagula_core::Error::Checkpoint { .. }),
        "{err:?}"
    );
    let mut after = vec![0u8; p.checkpoint_len()];
    p.save_to(&mut after).unwrap();
    assert_eq!(before, after);
    // its own engine's checkpoint restores
    let mut b = AutoBucketed::<_, 1, 2>::new(k, &[700], 700.0)
        .unwrap()
        .with_mode(Some(BucketMode::Counted))
        .unwrap();
    b.restore_from(&buf).unwrap();
    assert_eq!(b.counts(), a.counts());
    // through the registry
    use coagula_core::kernel::NoFragmentation;
    use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
    use coagula_core::scheme::registry;
    for (pin, want) in [
        (None, BucketMode::Counted),
        (Some(BucketMode::Slots), BucketMode::Slots),
    ] {
        let init = Init::Counts {
            counts: &[900],
            volume: 900.0,
        };
        let opts = Options::default().with_engine(pin);
        let sim: Box<dyn Simulation<Coagulation, NoFragmentation, Pcg64Mcg>> = registry::build(
            registry::find("lowrank").unwrap(),
            Model::coagulation(k, NoFragmentation),
            &init,
            &opts,
        )
        .unwrap();
        assert_eq!(sim.engine(), Some(want));
        let tree: Box<dyn Simulation<Coagulation, NoFragmentation, Pcg64Mcg>> = registry::build(
            registry::find("lowrank-tree").unwrap(),
            Model::coagulation(k, NoFragmentation),
            &init,
            &Options::default(),
        )
        .unwrap();
        assert_eq!(tree.engine(), None);
    }
}

/// Review of issue 13: a checkpoint whose list entry names a size past M (the bucket of
/// M runs past it) was accepted, and the next `counts()` panicked. Restore now refuses
/// it, and the target is unchanged: for both bucketed engines, from 1000 monomers and
/// one particle of size 64 = M, alone in the list bucket 64..=65. `offset_at` finds
/// that particle's offset in the checkpoint; it is set to 1 (size 65 > M) and the
/// checkpoint resealed, so that the state's own check is what refuses it.
fn refuses_a_particle_past_the_maximum_size<S: Scheme + Checkpoint>(
    make: impl Fn(&[u64], f64) -> S,
    counts: impl Fn(&S) -> Vec<u64>,
    offset_at: impl Fn(&[u8]) -> usize,
) {
    let mut init = vec![0u64; 64];
    init[0] = 1000;
    init[63] = 1;
    let a = make(&init, 1001.0);
    let mut buf = vec![0u8; a.checkpoint_len()];
    a.save_to(&mut buf).unwrap();
    let mut b = make(&init, 1001.0);
    b.restore_from(&buf).unwrap();
    assert_eq!(counts(&a), counts(&b));
    let at = offset_at(&buf);
    assert_eq!(u64::from_le_bytes(buf[at..at + 8].try_into().unwrap()), 0);
    buf[at] = 1;
    let body = buf.len() - 8;
    let sum = coagula_core::checkpoint::checksum(&buf[..body]);
    buf[body..].copy_from_slice(&sum.to_le_bytes());
    let mut c = make(&[10], 10.0);
    let before = counts(&c);
    assert!(c.restore_from(&buf).is_err());
    assert_eq!(counts(&c), before);
}

#[test]
fn bucketed_restore_refuses_a_particle_past_the_maximum_size() {
    let k = Coagulation::constant(1.0).unwrap();
    refuses_a_particle_past_the_maximum_size(
        |init, v| Bucketed::<_, 1, 2>::new(k, init, v).unwrap(),
        |s| s.counts().into_owned(),
        // the word before the overflow stream (3 words) and the checksum
        |buf| buf.len() - 8 - 24 - 8,
    );
    refuses_a_particle_past_the_maximum_size(
        |init, v| BucketedCounted::<_, 1, 2>::new(k, init, v).unwrap(),
        |s| s.counts().into_owned(),
        // after the bucket's count (1) and its list's length (1): the only such run
        |buf| {
            let pattern: Vec<u8> = [1u64, 1, 0].iter().flat_map(|w| w.to_le_bytes()).collect();
            let hits: Vec<usize> = (0..buf.len() - 24)
                .filter(|&i| buf[i..i + 24] == pattern[..])
                .collect();
            assert_eq!(hits.len(), 1, "{hits:?}");
            hits[0] + 16
        },
    );
}

/// Low-rank over particle sizes from continuous sizes (buckets holding many sizes, so
/// the bounds the checkpoint keeps are history, not recomputable), through doublings:
/// rank 1 (exact bound) and rank 3 (squeezed).
#[test]
fn lowrank_sizes_split_from_continuous_sizes() {
    use coagula_core::scheme::lowrank::LowRankSizes;
    let n = 2000;
    let sizes: Vec<f64> = (0..n)
        .map(|i| -(1.0 - (i as f64 + 0.5) / n as f64).ln())
        .collect();
    let s = sizes.clone();
    split_equals_unbroken(
        move || LowRankSizes::<_, 1, 2>::new(Coagulation::additive(), &s, n as f64).unwrap(),
        0.6,
        2.0,
        |s| bits(s.sizes()),
    );
    split_equals_unbroken(
        move || {
            LowRankSizes::<_, 3, 6>::new(Coagulation::free_molecular(), &sizes, n as f64).unwrap()
        },
        0.6,
        2.0,
        |s| bits(s.sizes()),
    );
}

/// A checkpoint whose bucket bound does not cover its particles (a factor above the
/// bucket's largest, or a negative smallest) is refused, the target unchanged
/// (resealed, so that the state's own check is what refuses it).
#[test]
fn lowrank_sizes_restore_refuses_bounds_that_do_not_cover() {
    use coagula_core::scheme::lowrank::LowRankSizes;
    let k = Coagulation::additive();
    // one bucket: the last words before the checksum are its (hi, lo) for a_0 and b_0
    let sizes = [1.0; 100];
    let a = LowRankSizes::<_, 1, 2>::new(k, &sizes, 100.0).unwrap();
    assert_eq!(a.buckets(), 1);
    let mut buf = vec![0u8; a.checkpoint_len()];
    a.save_to(&mut buf).unwrap();
    let word = |buf: &[u8], i: usize| {
        f64::from_bits(u64::from_le_bytes(buf[i..i + 8].try_into().unwrap()))
    };
    let hi0 = buf.len() - 8 - 32;
    assert_eq!(
        (word(&buf, hi0), word(&buf, hi0 + 8)),
        (1.0, 1.0),
        "a_0 = x at x = 1"
    );
    let reseal = |mut b: Vec<u8>, at: usize, v: f64| {
        b[at..at + 8].copy_from_slice(&v.to_bits().to_le_bytes());
        let body = b.len() - 8;
        let sum = coagula_core::checkpoint::checksum(&b[..body]);
        b[body..].copy_from_slice(&sum.to_le_bytes());
        b
    };
    let mut c = LowRankSizes::<_, 1, 2>::new(k, &[2.0, 3.0], 5.0).unwrap();
    let before = bits(c.sizes());
    // the untouched checkpoint restores
    let mut d = LowRankSizes::<_, 1, 2>::new(k, &[2.0, 3.0], 5.0).unwrap();
    d.restore_from(&reseal(buf.clone(), hi0, 1.0)).unwrap();
    assert_eq!(bits(d.sizes()), bits(a.sizes()));
    for (at, v) in [
        (hi0, 0.5),
        (hi0 + 8, -1.0),
        (hi0 + 8, f64::NEG_INFINITY),
        (hi0 + 8, f64::NAN),
        (hi0, f64::INFINITY),
    ] {
        assert!(
            c.restore_from(&reseal(buf.clone(), at, v)).is_err(),
            "{v} at {at}"
        );
        assert_eq!(bits(c.sizes()), before);
    }
}
