//! Block majorants (`lowrank-blocks`, issue 45) on a kernel no low-rank bound fits.
//!
//! The conformance suite reaches the scheme through the registry (its checkpoints,
//! seeds, refusals, value pin) and the finite-N reference checks its O(1/N) law on the
//! constant and the additive kernel (`finite_n.rs`: a same-size rule off by a factor 2
//! on the diagonal blocks, or a block's pairs counted twice, moves those expectations
//! by many SE). Here: the atmospheric kernel against the inverse method, which uses no
//! bound at all, and the errors a wrong bound must give.

use crate::common::z_max;
use coagula_core::Error;
use coagula_core::kernel::{Coagulation, CoagulationKernel};
use coagula_core::observe::Replicas;
use coagula_core::scheme::lowrank::Blocks;
use coagula_core::scheme::{Scheme, registry};
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// The observables compared: M0, M2 and the number density in three size classes.
const LABELS: [&str; 5] = ["M0", "M2", "n(1)", "n(2..4)", "n(5..16)"];

fn observe(s: &crate::common::Sim) -> [f64; 5] {
    let v = s.volume();
    let mut c = [0.0; 3];
    s.for_each_count(&mut |x, n| {
        let k = match x {
            1 => 0,
            2..=4 => 1,
            5..=16 => 2,
            _ => return,
        };
        c[k] += n as f64 / v;
    })
    .unwrap();
    [s.moment(0.0), s.moment(2.0), c[0], c[1], c[2]]
}

/// The atmospheric kernel from 2000 monomers (V = 2000) at t = 2 and 20: M0, M2 and
/// three classes of `lowrank-blocks` against `inverse` (no bound: the exact law by
/// another road), Welch's z on 48 replicas each at the suite's threshold (5.62 SE;
/// 10 comparisons). By t = 20 the particles are a fifth of the start and the largest
/// sizes pass 100, so blocks of every level are drawn.
#[test]
fn the_atmospheric_kernel_agrees_with_the_inverse_method() {
    let (n0, reps, times) = (2000u64, 48u64, [2.0, 20.0]);
    let k = Coagulation::atmospheric();
    let mut stats = vec![vec![vec![Replicas::new(); 5]; times.len()]; 2];
    for (si, name) in ["lowrank-blocks", "inverse"].into_iter().enumerate() {
        let info = registry::find(name).unwrap();
        for r in 0..reps {
            let mut rng = Pcg64Mcg::seed_from_u64(0x45_0000 + 1000 * si as u64 + r);
            let mut s = crate::common::build(info, k, &[n0], n0 as f64).unwrap();
            for (ti, &t) in times.iter().enumerate() {
                s.advance_to(t, &mut rng).unwrap();
                for (st, x) in stats[si][ti].iter_mut().zip(observe(&*s)) {
                    st.push(x);
                }
            }
        }
    }
    let z = z_max(reps);
    let mut failures = String::new();
    for (ti, &t) in times.iter().enumerate() {
        for (oi, label) in LABELS.iter().enumerate() {
            let (a, b) = (&stats[0][ti][oi], &stats[1][ti][oi]);
            let se = (a.std_error().powi(2) + b.std_error().powi(2)).sqrt();
            let d = (a.mean() - b.mean()) / se;
            println!(
                "t = {t}: {label} blocks {:.6} ± {:.6}, inverse {:.6} ± {:.6}, z = {d:+.2}",
                a.mean(),
                a.std_error(),
                b.mean(),
                b.std_error()
            );
            if d.is_nan() || d.abs() > z {
                failures.push_str(&format!("t = {t} {label}: z = {d:.2}\n"));
            }
        }
    }
    // the run reached the sizes it was meant to test
    assert!(stats[0][1][0].mean() < 0.3, "{}", stats[0][1][0].mean());
    assert!(failures.is_empty(), "{failures}");
}

/// A kernel that claims a supremum below its values: the rate would be cut where the
/// claim is wrong, so the scheme errors out (naming the bound) instead of simulating
/// the wrong law, and the state is as before the failing proposal.
#[test]
fn a_block_bound_below_the_kernel_is_an_error() {
    #[derive(Clone, Copy)]
    struct Liar;
    impl CoagulationKernel for Liar {
        fn rate(&self, x: f64, y: f64) -> f64 {
            x + y
        }
        fn sup_block(&self, x0: f64, _x1: f64, y0: f64, _y1: f64) -> Option<f64> {
            // the smallest corner: below the kernel on every block wider than one size
            Some(x0 + y0)
        }
    }
    let mut s = Blocks::new(Liar, &[500, 200, 50], 500.0).unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let e = s.advance_to(50.0, &mut rng).unwrap_err();
    assert!(matches!(e, Error::BoundExceeded { .. }), "{e:?}");
    let (n, t) = (s.particles(), s.time());
    let again = s.advance_to(50.0, &mut rng).unwrap_err();
    assert!(matches!(again, Error::BoundExceeded { .. }));
    // (a refused proposal changes nothing: a second attempt fails where the first did,
    // or later)
    assert!(s.particles() <= n && s.time() >= t);

    // without a block bound at all: refused at construction, by name
    let none = |x: f64, y: f64| x * y;
    let e = Blocks::new(none, &[10], 10.0).unwrap_err();
    assert!(format!("{e}").contains("sup_block"), "{e}");
    // the atmospheric kernel on real sizes: refused by the registry
    let sizes = [1.0, 2.5, 3.0];
    let init = coagula_core::scheme::facade::Init::Sizes {
        sizes: &sizes,
        mass: 6.5,
    };
    let model = coagula_core::scheme::facade::Model::coagulation(
        Coagulation::atmospheric(),
        coagula_core::kernel::NoFragmentation,
    );
    let r = registry::build::<_, _, Pcg64Mcg>(
        registry::find("lowrank-sizes").unwrap(),
        model,
        &init,
        &Default::default(),
    );
    let e = r.err().expect("refused");
    assert!(format!("{e}").contains("integer sizes"), "{e}");
}

/// Checkpoint split = unbroken run on the atmospheric kernel, through a doubling and a
/// growth of the largest size (the majorants' lazy values travel in the checkpoint).
#[test]
fn a_split_run_keeps_its_bits() {
    use coagula_core::checkpoint::Checkpoint;
    fn bytes(s: &impl Checkpoint) -> Vec<u8> {
        let mut buf = vec![0u8; s.checkpoint_len()];
        let n = s.save_to(&mut buf).unwrap();
        buf.truncate(n);
        buf
    }
    let k = Coagulation::atmospheric();
    let make = || {
        Blocks::new(k, &[3000], 3000.0)
            .unwrap()
            .with_batched_clock(false)
    };
    let mut a = make();
    let mut ra = Pcg64Mcg::seed_from_u64(9);
    a.advance_to(40.0, &mut ra).unwrap();
    let mut b = make();
    let mut rb = Pcg64Mcg::seed_from_u64(9);
    for t in [3.0, 11.0, 27.5] {
        b.advance_to(t, &mut rb).unwrap();
        let buf = bytes(&b);
        let mut c = make();
        c.restore_from(&buf).unwrap();
        b = c;
    }
    b.advance_to(40.0, &mut rb).unwrap();
    assert!(a.totals().doublings >= 1, "{:?}", a.totals());
    assert!(a.max_size() > 64);
    assert_eq!(a.counts(), b.counts());
    assert_eq!(bytes(&a), bytes(&b));
}

/// Which engine `lowrank` runs: block majorants for a kernel whose low-rank bound is
/// loose (the atmospheric one) or missing (a kernel of rank 0 that bounds blocks), the
/// bucketed engines otherwise; the `engine` option forces either, and a checkpoint of
/// one engine restores into a scheme on another unless that one is pinned.
#[test]
fn lowrank_chooses_block_majorants_for_a_loose_or_missing_bound() {
    use coagula_core::scheme::facade::{BucketMode, Init, Model, Options};
    use coagula_core::scheme::lowrank::AutoBucketed;
    let lowrank = registry::find("lowrank").unwrap();
    let engine = |k: Coagulation, opts: &Options| {
        let init = Init::Counts {
            counts: &[1000],
            volume: 1000.0,
        };
        let model = Model::coagulation(k, coagula_core::kernel::NoFragmentation);
        registry::build::<_, _, Pcg64Mcg>(lowrank, model, &init, opts).map(|s| s.engine())
    };
    let auto = Options::default();
    let atm = Coagulation::atmospheric();
    assert_eq!(engine(atm, &auto).unwrap(), Some(BucketMode::Blocks));
    let pinned = Options::default().with_engine(Some(BucketMode::Counted));
    assert_eq!(engine(atm, &pinned).unwrap(), Some(BucketMode::Counted));
    // a tight low-rank bound keeps the bucketed engines (the Osinsky rows)
    for k in [
        Coagulation::constant(1.0).unwrap(),
        Coagulation::additive(),
        Coagulation::brownian(),
    ] {
        assert_eq!(engine(k, &auto).unwrap(), Some(BucketMode::Counted));
        let forced = Options::default().with_engine(Some(BucketMode::Blocks));
        assert_eq!(engine(k, &forced).unwrap(), Some(BucketMode::Blocks));
    }

    // no low-rank bound at all: blocks, and the low-rank-only layouts refuse it by name
    #[derive(Clone, Copy, Debug)]
    struct Bounded;
    impl CoagulationKernel for Bounded {
        fn rate(&self, x: f64, y: f64) -> f64 {
            (x * y).sqrt()
        }
        fn sup_block(&self, _x0: f64, x1: f64, _y0: f64, y1: f64) -> Option<f64> {
            Some((x1 * y1).sqrt())
        }
    }
    use coagula_core::observe::Observe;
    let mut s = AutoBucketed::<_, 1, 2>::new(Bounded, &[400], 400.0).unwrap();
    assert_eq!(s.mode(), BucketMode::Blocks);
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    s.advance_to(3.0, &mut rng).unwrap();
    assert!(s.particles() < 400);
    let e = s.set_mode(Some(BucketMode::Slots)).unwrap_err();
    assert!(format!("{e}").contains("rank"), "{e}");
    assert_eq!(s.mode(), BucketMode::Blocks);

    // checkpoints move between engines unless pinned
    use coagula_core::checkpoint::Checkpoint;
    let mut a = AutoBucketed::<_, 2, 4>::new(atm, &[3000], 3000.0).unwrap();
    a.advance_to(5.0, &mut rng).unwrap();
    let mut buf = vec![0u8; a.checkpoint_len()];
    let n = a.save_to(&mut buf).unwrap();
    let mut b = AutoBucketed::<_, 2, 4>::new(atm, &[10], 10.0)
        .unwrap()
        .with_mode(Some(BucketMode::Counted))
        .unwrap();
    let e = b.restore_from(&buf[..n]).unwrap_err();
    assert!(format!("{e}").contains("pinned"), "{e}");
    assert_eq!(b.mode(), BucketMode::Counted);
    b.set_mode(None).unwrap();
    b.restore_from(&buf[..n]).unwrap();
    assert_eq!(b.mode(), BucketMode::Blocks);
    assert_eq!(b.counts(), a.counts());
    assert_eq!(b.time(), a.time());
}

/// A cloud-like start: `n0` drops with volumes geometric of mean `mean` (in units of
/// the size-1 drop), counts rounded.
fn cloud_counts(n0: u64, mean: f64) -> Vec<u64> {
    let q = 1.0 - 1.0 / mean;
    let mut counts = Vec::new();
    let mut p = 1.0 - q;
    while counts.len() < 50 * mean as usize {
        counts.push((n0 as f64 * p).round() as u64);
        p *= q;
    }
    counts
}

/// Gravitational collection with Long's efficiency (drops of 20 µm as size 1: the
/// inverse method's cost grows with the square of the distinct sizes; Shima et al.
/// 2009's start: volume-mean radius 30.531 µm, 2^23 drops per m³) from 2000 drops: `lowrank-blocks` (block bounds from the monotone factors) against `inverse`
/// at t = 200 and 500 s (by then 9 drops in 10 have merged), M0, M2 and three classes,
/// Welch's z on 48 replicas each.
#[test]
fn gravitational_collection_agrees_with_the_inverse_method() {
    let k = Coagulation::gravitational(2e-5).unwrap();
    let counts = cloud_counts(2000, (30.531f64 / 20.0).powi(3));
    let n0: u64 = counts.iter().sum();
    let volume = n0 as f64 / 8_388_608.0;
    let (reps, times) = (48u64, [200.0, 500.0]);
    let classes = |s: &crate::common::Sim| {
        let v = s.volume();
        let mut c = [0.0; 3];
        s.for_each_count(&mut |x, n| {
            let k = match x {
                1..=3 => 0,
                4..=15 => 1,
                16..=255 => 2,
                _ => return,
            };
            c[k] += n as f64 / v;
        })
        .unwrap();
        [s.moment(0.0), s.moment(2.0), c[0], c[1], c[2]]
    };
    let mut stats = vec![vec![vec![Replicas::new(); 5]; times.len()]; 2];
    for (si, name) in ["lowrank-blocks", "inverse"].into_iter().enumerate() {
        let info = registry::find(name).unwrap();
        for r in 0..reps {
            let mut rng = Pcg64Mcg::seed_from_u64(0x46_0000 + 1000 * si as u64 + r);
            let mut s = crate::common::build(info, k, &counts, volume).unwrap();
            for (ti, &t) in times.iter().enumerate() {
                s.advance_to(t, &mut rng).unwrap();
                for (st, x) in stats[si][ti].iter_mut().zip(classes(&*s)) {
                    st.push(x);
                }
            }
        }
    }
    let z = z_max(reps);
    let mut failures = String::new();
    for (ti, &t) in times.iter().enumerate() {
        for (oi, label) in ["M0", "M2", "C[1,4)", "C[4,16)", "C[16,256)"]
            .iter()
            .enumerate()
        {
            let (a, b) = (&stats[0][ti][oi], &stats[1][ti][oi]);
            let se = (a.std_error().powi(2) + b.std_error().powi(2)).sqrt();
            let d = (a.mean() - b.mean()) / se;
            println!(
                "t = {t}: {label} blocks {:.6e}, inverse {:.6e}, z = {d:+.2}",
                a.mean(),
                b.mean()
            );
            if d.is_nan() || d.abs() > z {
                failures.push_str(&format!("t = {t} {label}: z = {d:.2}\n"));
            }
        }
    }
    // the run merged a good part of the drops by the end
    let m0 = stats[0][1][0].mean() * volume / n0 as f64;
    assert!(m0 < 0.2, "{m0}");
    assert!(failures.is_empty(), "{failures}");
}

/// After a particle doubling every block's majorant still bounds its intensity: a
/// diagonal block's distinct pairs grow more than fourfold (2R (2R − 1) against
/// 4 R (R − 1)), which a plain rescale misses. Restoring a checkpoint checks `Î ≥ I`
/// on every block, so a checkpoint right after each doubling must restore.
#[test]
fn majorants_bound_the_intensities_after_a_doubling() {
    use coagula_core::checkpoint::Checkpoint;
    let k = Coagulation::constant(1.0).unwrap();
    // 64 particles of distinct sizes: every diagonal block starts with one particle a size
    let counts = vec![1u64; 64];
    let mut s = Blocks::new(k, &counts, 64.0)
        .unwrap()
        .with_batched_clock(false);
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    let mut t = 0.0;
    let mut seen = 0;
    while seen < 3 && t < 1e4 {
        t += 0.01;
        s.advance_to(t, &mut rng).unwrap();
        if s.totals().doublings > seen {
            seen = s.totals().doublings;
            let mut buf = vec![0u8; s.checkpoint_len()];
            let n = s.save_to(&mut buf).unwrap();
            let mut c = Blocks::new(k, &[2], 1.0).unwrap();
            c.restore_from(&buf[..n])
                .unwrap_or_else(|e| panic!("after doubling {seen}: {e}"));
        }
    }
    assert!(seen >= 3, "{seen} doublings");
}

/// A kernel that counts its evaluations, with or without the squeeze of the kernel it
/// wraps (`inf_block`; without, the default 0).
#[derive(Clone)]
struct Evaluations {
    k: Coagulation,
    squeeze: bool,
    calls: std::rc::Rc<std::cell::Cell<u64>>,
}

impl CoagulationKernel for Evaluations {
    fn rate(&self, x: f64, y: f64) -> f64 {
        self.calls.set(self.calls.get() + 1);
        self.k.rate(x, y)
    }
    fn sup_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<f64> {
        self.k.sup_block(x0, x1, y0, y1)
    }
    fn inf_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        if self.squeeze {
            self.k.inf_block(x0, x1, y0, y1)
        } else {
            0.0
        }
    }
    fn log_linear_blocks(&self) -> bool {
        self.k.log_linear_blocks()
    }
    fn integer_sizes(&self) -> bool {
        self.k.integer_sizes()
    }
}

/// The squeeze accepts without evaluating K only where K would accept, on the same
/// draws: with and without it, a seed gives the same counts, time and report, bit for
/// bit (the atmospheric kernel, and the gravitational ones, Long's and Hall's, on
/// their log-linear partition), with far fewer kernel evaluations. A lower bound above the kernel is
/// caught by the spot checks (`SPOT_CHECK`), by name.
#[test]
fn the_squeeze_changes_the_cost_not_the_bits() {
    let cases = [
        (Coagulation::atmospheric(), vec![3000u64], 3000.0, 40.0),
        (
            Coagulation::gravitational(2e-5).unwrap(),
            cloud_counts(3000, (30.531f64 / 20.0).powi(3)),
            3000.0 / 8_388_608.0,
            600.0,
        ),
        (
            Coagulation::gravitational_hall(2e-5).unwrap(),
            cloud_counts(3000, (30.531f64 / 20.0).powi(3)),
            3000.0 / 8_388_608.0,
            600.0,
        ),
    ];
    for (k, counts, volume, t) in cases {
        let run = |squeeze: bool| {
            let calls = std::rc::Rc::new(std::cell::Cell::new(0));
            let w = Evaluations {
                k,
                squeeze,
                calls: calls.clone(),
            };
            let mut s = Blocks::new(w, &counts, volume).unwrap();
            let mut rng = Pcg64Mcg::seed_from_u64(45);
            let rep = s.advance_to(t, &mut rng).unwrap();
            let mut state = Vec::new();
            s.for_each_count(&mut |x, n| state.push((x, n)));
            (state, s.time().to_bits(), format!("{rep:?}"), calls.get())
        };
        let (with, without) = (run(true), run(false));
        println!(
            "{}: {} kernel evaluations with the squeeze, {} without ({} sizes left)",
            k.name(),
            with.3,
            without.3,
            with.0.len()
        );
        assert_eq!(with.0, without.0, "{}", k.name());
        assert_eq!((with.1, &with.2), (without.1, &without.2), "{}", k.name());
        // (the run merged most of its particles)
        assert!(with.0.len() > 20, "{}: {}", k.name(), with.0.len());
        assert!(
            with.3 * 10 < without.3 * 9,
            "{}: {} evaluations with the squeeze, {} without",
            k.name(),
            with.3,
            without.3
        );
    }

    #[derive(Clone, Copy)]
    struct Above;
    impl CoagulationKernel for Above {
        fn rate(&self, x: f64, y: f64) -> f64 {
            x + y
        }
        fn sup_block(&self, _x0: f64, x1: f64, _y0: f64, y1: f64) -> Option<f64> {
            Some(x1 + y1)
        }
        fn inf_block(&self, _x0: f64, x1: f64, _y0: f64, y1: f64) -> f64 {
            // nearly the largest value: above the kernel on most of every block
            0.999 * (x1 + y1)
        }
    }
    let mut s = Blocks::new(Above, &[5000, 2000, 500], 5000.0).unwrap();
    let mut rng = Pcg64Mcg::seed_from_u64(4);
    let e = s.advance_to(50.0, &mut rng).unwrap_err();
    assert!(format!("{e}").contains("inf_block"), "{e}");
}
