//! No step of a fixed-size scheme allocates: a counting global allocator records every
//! allocation made on the test's thread while a step runs, for every point source
//! (QMC, Sobol', MC, RQMC re-randomised per block with each randomisation, a single
//! randomisation), both sortings, with and without fragmentation, in an owned workspace
//! and in caller-owned storage, through the concrete type and through the facade.
//! A checkpoint restore into caller-owned storage allocates nothing either.

use coagula_core::checkpoint::{Checkpoint, Reader, Writer};
use coagula_core::kernel::{BinaryUniform, Coagulation, FragmentationKernel, NoFragmentation};
use coagula_core::qmc::Randomization;
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::Scheme;
use coagula_core::scheme::facade::{Init, Model, Options, Simulation};
use coagula_core::scheme::massflow::{MassFlow, PointSource, Sorting, workspace_len};
use coagula_core::scheme::registry;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    /// Allocations on this thread while `COUNTING` is set.
    static COUNT: Cell<u64> = const { Cell::new(0) };
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

fn note() {
    // (`try_with`: the thread-locals may be gone while the thread shuts down)
    let _ = COUNTING.try_with(|on| {
        if on.get() {
            let _ = COUNT.try_with(|c| c.set(c.get() + 1));
        }
    });
}

// SAFETY: every call is forwarded to the system allocator unchanged; the counter only
// touches const-initialised thread-locals, which never allocate.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        // SAFETY: forwarded; `ptr` came from this allocator (i.e. from System).
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded; `ptr` came from System.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations `f` makes on this thread.
fn allocations(f: impl FnOnce()) -> u64 {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|on| on.set(true));
    f();
    COUNTING.with(|on| on.set(false));
    COUNT.with(|c| c.get())
}

fn sources() -> Vec<(&'static str, PointSource)> {
    let mut key = generator(3, 0);
    vec![
        ("niederreiter", PointSource::niederreiter()),
        ("sobol", PointSource::sobol()),
        ("monte-carlo", PointSource::monte_carlo()),
        (
            "rqmc-owen",
            PointSource::randomized_niederreiter(Randomization::Owen, &mut key),
        ),
        (
            "rqmc-matousek",
            PointSource::randomized_niederreiter(Randomization::Matousek, &mut key),
        ),
        (
            "rqmc-shift-sobol",
            PointSource::randomized_sobol(Randomization::DigitalShift, &mut key),
        ),
    ]
}

fn steps_allocate_nothing<F: FragmentationKernel + Copy>(frag: F) {
    let k = Coagulation::additive();
    let n = 1 << 10;
    for (name, src) in sources() {
        for sorting in [Sorting::Adaptive, Sorting::Full] {
            // owned workspace
            let mut a = MassFlow::new(k, frag, &vec![1.0; n], 1.0, 0.01, src.clone())
                .unwrap()
                .with_sorting(sorting);
            // caller-owned workspace
            let mut buf = vec![0.0; workspace_len(n).unwrap()];
            let mut b =
                MassFlow::new_in(k, frag, &vec![1.0; n], 1.0, 0.01, src.clone(), &mut buf[..])
                    .unwrap()
                    .with_sorting(sorting);
            let mut rng = generator(1, 0);
            // 50 steps (with a shorter last one), then a few calls step by step
            let got = allocations(|| {
                a.advance_to(0.495, &mut rng).unwrap();
                b.advance_to(0.495, &mut rng).unwrap();
                for h in 1..=5 {
                    a.advance_to(0.5 + 0.01 * f64::from(h), &mut rng).unwrap();
                    b.advance_to(0.5 + 0.01 * f64::from(h), &mut rng).unwrap();
                }
            });
            assert_eq!(got, 0, "{name} {sorting:?}: {got} allocations in 110 steps");
            assert!(a.totals().events > 0 && b.totals().events > 0);
        }
    }
}

#[test]
fn mass_flow_steps_allocate_nothing() {
    steps_allocate_nothing(NoFragmentation);
    steps_allocate_nothing(BinaryUniform::new(1.0).unwrap());
}

/// The registry's facade over caller-owned storage: stepping, observing, replacing the
/// sizes and restoring a checkpoint allocate nothing.
#[test]
fn the_facade_in_caller_storage_allocates_nothing_after_construction() {
    let sizes = vec![1.0; 512];
    let init = Init::Sizes {
        sizes: &sizes,
        mass: 1.0,
    };
    let k = Coagulation::constant(1.0).unwrap();
    let f = BinaryUniform::new(1.0).unwrap();
    let len = registry::workspace_len(
        registry::find("massflow").unwrap(),
        sizes.len(),
        &Options::default(),
        true,
    )
    .unwrap();
    assert_eq!(len, 6 * 512);
    let mut ws = vec![0.0; len];
    let opts = Options::default()
        .with_randomization(Randomization::Owen)
        .with_stream(4, 0);
    let mut sim: Box<dyn Simulation<_, _, Generator> + '_> = registry::build_in(
        registry::find("massflow").unwrap(),
        Model::coagulation(k, f),
        &init,
        &opts,
        &mut ws,
    )
    .unwrap();
    let mut rng = generator(2, 0);
    sim.advance_to(0.2, &mut rng).unwrap();
    let mut saved = vec![0u8; 1 << 16];
    let mut w = Writer::new(&mut saved);
    sim.save(&mut w);
    let used = w.finish().unwrap();
    let got = allocations(|| {
        sim.advance_to(0.7, &mut rng).unwrap();
        let _ = (
            sim.moment(2.0),
            sim.concentration(0.5, 2.0),
            sim.particles(),
        );
        sim.set_sizes(&sizes).unwrap();
        sim.set_dt(0.02).unwrap();
        sim.restore(&mut Reader::new(&saved[..used])).unwrap();
        sim.advance_to(0.9, &mut rng).unwrap();
    });
    assert_eq!(got, 0, "{got} allocations");
    // a growing scheme refuses caller storage: it takes a memory budget
    let counts = Init::Counts {
        counts: &[100],
        volume: 100.0,
    };
    assert!(
        registry::workspace_len(
            registry::find("lowrank").unwrap(),
            100,
            &Options::default(),
            false
        )
        .is_none()
    );
    let mut small = vec![0.0; 4];
    assert!(
        registry::build_in::<_, _, Generator>(
            registry::find("lowrank").unwrap(),
            Model::coagulation(k, f),
            &counts,
            &opts,
            &mut small
        )
        .is_err()
    );
    // too small a workspace is an error, not an overrun
    let mut short = vec![0.0; len - 1];
    assert!(
        registry::build_in::<_, _, Generator>(
            registry::find("massflow").unwrap(),
            Model::coagulation(k, f),
            &init,
            &opts,
            &mut short
        )
        .is_err()
    );
}

/// The counter works: a step of a growing scheme that adds a size class does allocate.
#[test]
fn the_counter_sees_allocations() {
    let got = allocations(|| {
        let v: Vec<u64> = (0..100).collect();
        assert_eq!(v.len(), 100);
    });
    assert!(got >= 1);
    // and a checkpoint of a mass-flow scheme through Checkpoint::save_to needs none
    let mut a = MassFlow::new(
        Coagulation::constant(1.0).unwrap(),
        NoFragmentation,
        &[1.0; 64],
        1.0,
        0.1,
        PointSource::niederreiter(),
    )
    .unwrap();
    a.advance_to(0.3, &mut generator(1, 0)).unwrap();
    let mut buf = vec![0u8; a.checkpoint_len()];
    assert_eq!(
        allocations(|| {
            a.save_to(&mut buf).unwrap();
        }),
        0
    );
}

/// No Langevin step allocates: a batch in caller-owned storage, 1-D (the paper's
/// problem, specular and absorbing, with and without a budget) and 3-D, and the
/// statistics over it.
#[test]
fn langevin_steps_do_not_allocate() {
    use coagula_core::langevin::{Batch, Config, Friction, Wall, paper, workspace_len};
    use coagula_core::scheme::Budget;
    for wall in [Wall::Specular, Wall::Absorbing] {
        let cfg = paper::config(wall, 0.05, paper::Choices::default()).unwrap();
        let mut ws = vec![0u64; workspace_len(1, 100).unwrap()];
        let mut b = Batch::with_starts_in(
            cfg,
            paper::PaperDrift,
            100,
            1,
            0,
            |_| ([0.5], [-1.5]),
            &mut ws[..],
        )
        .unwrap();
        let n = allocations(|| {
            b.advance_to(1.6).unwrap();
            b.advance_within(3.2, &mut Budget::work(1000)).unwrap();
            let _ = b.statistics(|x, u| paper::observable(x[0], u[0])).mean();
            let _ = b.hit_statistics();
        });
        assert_eq!(n, 0, "{wall:?}: {n} allocations");
    }
    let cfg = Config::<3>::ball(1.0, 0.01, 1.0, Wall::Specular).unwrap();
    let mut ws = vec![0u64; workspace_len(3, 64).unwrap()];
    let mut b = Batch::with_starts_in(
        cfg,
        Friction { rate: 1.0 },
        64,
        2,
        0,
        |_| ([1.5, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        &mut ws[..],
    )
    .unwrap();
    let n = allocations(|| {
        b.advance_to(1.0).unwrap();
    });
    assert_eq!(n, 0, "3-D: {n} allocations");
}
