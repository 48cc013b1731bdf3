//! Shared by the conformance tests: replica runs of any size-count scheme and the
//! family-wise thresholds (see `docs/design/statistical-tests.md`).
#![allow(dead_code)]

use coagula_core::observe::{Replicas, TEST_ALPHA, student_t_threshold};
use coagula_core::scheme::Scheme;
use rand_pcg::Pcg64Mcg;
use rand_pcg::rand_core::SeedableRng;

/// `(N, N1, N2, V)` of a count vector `counts[i − 1] = N_i`.
pub fn counts_observation(counts: &[u64], v: f64) -> (u64, u64, u64, f64) {
    let at = |i: usize| counts.get(i).copied().unwrap_or(0);
    (counts.iter().sum(), at(0), at(1), v)
}

/// Replica statistics of N/V, N1/V, N2/V at each of `times`: `make` builds a fresh
/// scheme, `observe` returns `(N, N1, N2, V)`; replica r runs on
/// `Pcg64Mcg::seed_from_u64(seed · 0x9e3779b9 ^ r)`.
pub fn replicas<S: Scheme>(
    seed: u64,
    reps: u64,
    times: &[f64],
    make: impl Fn() -> S,
    observe: impl Fn(&S) -> (u64, u64, u64, f64),
) -> Vec<[Replicas; 3]> {
    let mut stats = vec![[Replicas::new(), Replicas::new(), Replicas::new()]; times.len()];
    for r in 0..reps {
        let mut rng = Pcg64Mcg::seed_from_u64(seed.wrapping_mul(0x9e37_79b9) ^ r);
        let mut s = make();
        for (ti, &t) in times.iter().enumerate() {
            s.advance_to(t, &mut rng).unwrap();
            let (n, n1, n2, v) = observe(&s);
            for (st, x) in stats[ti].iter_mut().zip([n, n1, n2]) {
                st.push(x as f64 / v);
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
