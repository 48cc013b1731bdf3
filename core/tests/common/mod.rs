//! Shared by the conformance tests: replica runs of any size-count scheme and the
//! family-wise thresholds (see `docs/design/statistical-tests.md`).
#![allow(dead_code)]

use coagula_core::Error;
use coagula_core::kernel::{Coagulation, NoFragmentation};
use coagula_core::observe::{Replicas, TEST_ALPHA, student_t_threshold};
use coagula_core::scheme::registry::{self, Init, Options, SchemeId, SchemeInfo, Simulation};
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// The facade as the tests instantiate it.
pub type Sim = dyn Simulation<Coagulation, NoFragmentation, Pcg64Mcg>;

/// The registry's size-count schemes (every one the tests must cover).
pub fn count_schemes() -> impl Iterator<Item = &'static SchemeInfo> {
    let probe = Init::Counts {
        counts: &[1],
        volume: 1.0,
    };
    registry::SCHEMES.iter().filter(move |s| s.accepts(&probe))
}

/// Scheme `id` from `counts` in volume `v`; `None` when the kernel lacks the bound the
/// scheme needs (acceptance–rejection without a supremum).
pub fn build(id: SchemeId, k: Coagulation, counts: &[u64], v: f64) -> Option<Box<Sim>> {
    let init = Init::Counts { counts, volume: v };
    match registry::build(id, k, NoFragmentation, &init, &Options::default()) {
        Ok(s) => Some(s),
        Err(Error::Unsupported { .. }) => None,
        Err(e) => panic!("{}: {e}", id.name()),
    }
}

/// Replica statistics of N/V, n_1, n_2 read through the facade's `Observe`, at each of
/// `times`; replica r runs on `Pcg64Mcg::seed_from_u64(seed · 0x9e3779b9 ^ r)`.
pub fn facade_replicas(
    seed: u64,
    reps: u64,
    times: &[f64],
    make: impl Fn() -> Box<Sim>,
) -> Vec<[Replicas; 3]> {
    let mut stats = vec![[Replicas::new(), Replicas::new(), Replicas::new()]; times.len()];
    for r in 0..reps {
        let mut rng = Pcg64Mcg::seed_from_u64(seed.wrapping_mul(0x9e37_79b9) ^ r);
        let mut s = make();
        for (ti, &t) in times.iter().enumerate() {
            s.advance_to(t, &mut rng).unwrap();
            let obs = [
                s.particles() as f64 / s.volume(),
                s.number_density(1.0),
                s.number_density(2.0),
            ];
            for (st, x) in stats[ti].iter_mut().zip(obs) {
                st.push(x);
            }
        }
    }
    stats
}

/// The threshold in SE for a mean of `reps` replicas at the suite's false-alarm rate.
pub fn z_max(reps: u64) -> f64 {
    student_t_threshold(TEST_ALPHA, reps - 1)
}

/// The observables' names, in the order of [`replicas`].
pub const LABELS: [&str; 3] = ["N/V", "N1/V", "N2/V"];

/// Mass `Σ i N_i` of a count vector `counts[i − 1] = N_i`.
pub fn mass(counts: &[u64]) -> u64 {
    counts
        .iter()
        .enumerate()
        .map(|(i, &c)| (i as u64 + 1) * c)
        .sum()
}
