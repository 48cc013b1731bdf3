//! One time step of the mass-flow scheme at N = 2^20 on Lécot's case (K = 1,
//! F = 2/(x+y), Δt = 1/400), with the adaptive re-sort and with a full sort; QMC
//! against MC, and QMC's points visited by particle (the default) against the same
//! points visited in their sequence order (through the randomisation wrapper with no
//! randomisation, which takes the block path).

use coagula_core::kernel::{BinaryUniform, Coagulation};
use coagula_core::qmc::{Niederreiter2, Randomization, Scrambled};
use coagula_core::scheme::Scheme;
use coagula_core::scheme::massflow::{MassFlow, PointSource, Sorting};
use criterion::{Criterion, criterion_group, criterion_main};
use rand_pcg::Pcg64Mcg;

fn step(c: &mut Criterion) {
    let mut g = c.benchmark_group("massflow-step-N2^20");
    g.sample_size(20);
    for (name, sorting, points) in [
        (
            "qmc-adaptive-sort",
            Sorting::Adaptive,
            PointSource::niederreiter(),
        ),
        ("qmc-full-sort", Sorting::Full, PointSource::niederreiter()),
        (
            "mc-adaptive-sort",
            Sorting::Adaptive,
            PointSource::monte_carlo(),
        ),
        (
            "qmc-sequence-order-adaptive-sort",
            Sorting::Adaptive,
            PointSource::ScrambledNiederreiter(Scrambled::new(
                Niederreiter2::dim3(),
                Randomization::None,
                &mut Pcg64Mcg::new(0),
            )),
        ),
    ] {
        let k = Coagulation::constant(1.0).unwrap();
        let f = BinaryUniform::new(1.0).unwrap();
        let dt = 1.0 / 400.0;
        let mut sim = MassFlow::new(k, f, &vec![1.0; 1 << 20], 1.0, dt, points)
            .unwrap()
            .with_sorting(sorting);
        let mut rng = Pcg64Mcg::new(1);
        // a realistic, polydisperse state
        sim.advance_to(0.25, &mut rng).unwrap();
        g.bench_function(name, |b| {
            b.iter(|| {
                let t = sim.time() + dt;
                sim.advance_to(t, &mut rng).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
