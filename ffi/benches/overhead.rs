//! Cost of one `advance_to` through the C ABI against the same call in Rust: a step
//! with no event (pure call overhead) and a step with ~10 events from a fresh sim
//! (low-rank MC, constant kernel, 10^4 particles: rate N²/2V = 5000 per unit time).

use coagula::*;
use coagula_core::kernel::Coagulation;
use coagula_core::scheme::Scheme;
use coagula_core::scheme::lowrank::LowRank;
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use rand_pcg::Pcg64Mcg;
use std::hint::black_box;

const N0: u64 = 10_000;

/// A C-ABI sim freed on drop.
struct CSim(*mut coag_sim);

impl CSim {
    fn new(k: *const coag_kernel, seed: u64) -> Self {
        let mut s = std::ptr::null_mut();
        unsafe {
            let mut o = std::ptr::null_mut();
            assert_eq!(coag_options_new(&mut o), COAG_OK);
            assert_eq!(coag_options_set_count(o, c"seed".as_ptr(), seed), COAG_OK);
            assert_eq!(
                coag_sim_new_counts(
                    c"lowrank-tree".as_ptr(),
                    k,
                    std::ptr::null(),
                    o,
                    [N0].as_ptr(),
                    1,
                    N0 as f64,
                    &mut s
                ),
                COAG_OK
            );
            coag_options_free(o);
        }
        CSim(s)
    }
}

impl Drop for CSim {
    fn drop(&mut self) {
        unsafe { coag_sim_free(self.0) }
    }
}

fn overhead(c: &mut Criterion) {
    let kernel = Coagulation::constant(1.0).unwrap();
    let mut k = std::ptr::null_mut();
    unsafe {
        assert_eq!(
            coag_kernel_new(c"constant".as_ptr(), [1.0].as_ptr(), 1, &mut k),
            COAG_OK
        )
    };

    let mut g = c.benchmark_group("advance_to/empty-step");
    let mut sim = LowRank::<_, 1>::monodisperse(kernel, N0).unwrap();
    let mut rng = Pcg64Mcg::new(1);
    g.bench_function("rust", |b| {
        b.iter(|| {
            let t = sim.time() + 1e-12;
            black_box(sim.advance_to(t, &mut rng).unwrap())
        })
    });
    let cs = CSim::new(k, 1);
    let mut rep = coag_step_report {
        struct_size: std::mem::size_of::<coag_step_report>(),
        ..Default::default()
    };
    let mut t = 0.0;
    g.bench_function("c-abi", |b| {
        b.iter(|| unsafe {
            t += 1e-12;
            black_box(coag_sim_advance_to(cs.0, t, &mut rep))
        })
    });
    g.finish();

    let mut g = c.benchmark_group("advance_to/10-events");
    let mut seed = 0u128;
    g.bench_function("rust", |b| {
        b.iter_batched(
            || {
                seed += 1;
                (
                    LowRank::<_, 1>::monodisperse(kernel, N0).unwrap(),
                    Pcg64Mcg::new(seed),
                )
            },
            |(mut s, mut r)| {
                black_box(s.advance_to(2e-3, &mut r).unwrap());
                s
            },
            BatchSize::SmallInput,
        )
    });
    let mut seed = 0u64;
    g.bench_function("c-abi", |b| {
        b.iter_batched(
            || {
                seed += 1;
                CSim::new(k, seed)
            },
            |s| {
                let mut rep = coag_step_report {
                    struct_size: std::mem::size_of::<coag_step_report>(),
                    ..Default::default()
                };
                black_box(unsafe { coag_sim_advance_to(s.0, 2e-3, &mut rep) });
                s
            },
            BatchSize::SmallInput,
        )
    });
    g.finish();
    unsafe { coag_kernel_free(k) };
}

criterion_group!(benches, overhead);
criterion_main!(benches);
