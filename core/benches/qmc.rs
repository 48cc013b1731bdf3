//! Points per second of the QMC generators (dims 3 and 32, 32- and 64-bit words):
//! block fill (the scheme's access pattern), Gray-code iteration and random access.
use std::hint::black_box;

use coagula_core::qmc::{DigitalSequence, Niederreiter2, Randomization, Scrambled, Sobol, Word};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand_core::SeedableRng;

const M: u32 = 14;

fn bench_seq<S: DigitalSequence>(c: &mut Criterion, name: &str, seq: &S) {
    let d = seq.dim();
    let n = 1usize << M;
    let mut g = c.benchmark_group(format!("{name}/dim{d}"));
    g.throughput(Throughput::Elements(n as u64));
    let mut buf = vec![0.0; n * d];
    g.bench_function(BenchmarkId::new("block_f64", n), |b| {
        let mut blk = 0;
        b.iter(|| {
            seq.block(blk, M, &mut buf).unwrap();
            blk += 1;
            black_box(&buf);
        })
    });
    let mut p = vec![0.0; d];
    g.bench_function(BenchmarkId::new("gray_iter_f64", n), |b| {
        let mut it = seq.gray_iter();
        b.iter(|| {
            for _ in 0..n {
                it.next_into(&mut p).unwrap();
                black_box(&p);
            }
        })
    });
    g.bench_function(BenchmarkId::new("random_access_f64", n), |b| {
        let mut idx: u64 = 1 << 20;
        b.iter(|| {
            for _ in 0..n {
                seq.point(idx, &mut p).unwrap();
                idx += 1;
                black_box(&p);
            }
        })
    });
    g.finish();
}

fn all<W: Word>(c: &mut Criterion, w: &str) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
    for d in [3, 32] {
        bench_seq(c, &format!("sobol{w}"), &Sobol::<W>::new(d).unwrap());
        let nd = Niederreiter2::<W>::new(d).unwrap();
        bench_seq(c, &format!("nied2_{w}"), &nd);
        let owen = Scrambled::new(nd, Randomization::Owen, &mut rng);
        bench_seq(c, &format!("nied2_owen{w}"), &owen);
    }
}

fn benches(c: &mut Criterion) {
    all::<u32>(c, "32");
    all::<u64>(c, "64");
}

criterion_group! {
    name = qmc;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_secs(1));
    targets = benches
}
criterion_main!(qmc);
