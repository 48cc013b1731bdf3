//! What a size-count run's memory is sized by, predicted before the run: the largest
//! size its tables must cover, the particles it holds at most, and those of them in
//! sparsely held sizes (where the bucketed layout keeps per-particle lists).
//!
//! The integer-size schemes keep tables indexed by size, which grow with the largest
//! particle, so what a run holds at its end is set by how far the sizes grow — not by
//! the start. [`Reach`] carries that prediction from a front end (which knows the end
//! time and, where one exists, the exact solution) to each scheme's
//! [`memory_estimate`](crate::scheme::facade::Register::memory_estimate), which turns
//! it into bytes by its own layout. Figures against peak memory:
//! `docs/results/memory-estimate.md`.

use super::model::Init;
use crate::kernel::CoagulationKernel;

/// A size held fewer times than this is *sparse*: the bucketed layout's buckets there
/// are in list mode (a grid-mode bucket needs three quarters of its slots full, which
/// Poisson-scattered counts reach only at some tens a size).
pub const SPARSE_COUNT: f64 = 64.0;

/// Where a size-count run is expected to go (sizes in the scheme's integer units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// The start's largest size (what the tables are first built for).
    pub start: u64,
    /// The largest size its tables must cover (at least `start`).
    pub largest: u64,
    /// Simulation particles at most (the initial number: particle doubling keeps
    /// `N ≤ N0`).
    pub particles: u64,
    /// The start's total size `Σ i N_i` (what a scheme without particle doubling
    /// conserves: no cluster grows past it).
    pub mass: f64,
    /// The predicted mean size and `M2/M1` at the end (0: not predicted).
    pub mean: f64,
    /// See `mean`.
    pub m2_over_m1: f64,
    /// Particles expected in sparsely held sizes (fewer than [`SPARSE_COUNT`] a size).
    pub sparse: u64,
    /// The rank of the kernel's low-rank bound (0: none), which sizes the per-size
    /// factor tables of the tree layouts.
    pub rank: usize,
    /// Whether the kernel runs on block majorants where the scheme chooses its engine
    /// (`lowrank`; see `lowrank::prefers_blocks`): their tables, not the bucketed ones.
    pub blocks: bool,
    /// Whether the kernel's block majorants cut the size axis into log-linear strips
    /// (`CoagulationKernel::log_linear_blocks`): a few hundred blocks an octave, not
    /// about one a size.
    pub log_linear: bool,
}

impl Reach {
    /// The start itself: the tables as a build from `init` allocates them.
    pub fn at_start(init: &Init<'_>, rank: usize) -> Self {
        let (largest, particles, mass) = match *init {
            Init::Counts { counts, .. } | Init::Temperatures { counts, .. } => (
                counts.len() as u64,
                counts.iter().fold(0u64, |a, &c| a.saturating_add(c)),
                counts
                    .iter()
                    .enumerate()
                    .map(|(i, &c)| (i + 1) as f64 * c as f64)
                    .sum(),
            ),
            Init::Velocities { sizes, .. } => (
                sizes.iter().copied().max().unwrap_or(0),
                sizes.len() as u64,
                sizes.iter().map(|&x| x as f64).sum(),
            ),
            Init::Sizes { sizes, .. } => (0, sizes.len() as u64, sizes.iter().sum()),
        };
        Reach {
            start: largest,
            largest,
            particles,
            mass,
            mean: 0.0,
            m2_over_m1: 0.0,
            sparse: 0,
            rank,
            blocks: false,
            log_linear: false,
        }
    }

    /// The reach of a run that ends with mean size `mean` and second-moment ratio
    /// `m2_over_m1 = M2/M1` (both in the scheme's units), from the start `self`.
    ///
    /// The largest of N particles of a distribution with an exponential tail of scale
    /// θ is about θ ln N; for the exponential itself θ = M2/(2 M1), and the measured
    /// largest of the Golovin, Brownian and linear runs in
    /// `docs/results/memory-estimate.md` is 0.42–0.63 (M2/M1) ln N. The particles held
    /// sparsely are those at sizes where an exponential of mean `mean` over N particles
    /// has fewer than [`SPARSE_COUNT`] a size: `min(N, SPARSE_COUNT · mean)`.
    pub fn ending_at(self, mean: f64, m2_over_m1: f64) -> Self {
        let n = self.particles.max(2) as f64;
        let largest = 0.5 * m2_over_m1 * libm::log(n);
        // (an infinite prediction — an end time far past any the tables can reach —
        // saturates, so that it is refused, not ignored)
        if largest.is_nan() || mean.is_nan() || mean <= 0.0 {
            return self;
        }
        let sparse = (SPARSE_COUNT * mean).min(n);
        Reach {
            largest: self.largest.max(largest.min(u64::MAX as f64 / 4.0) as u64),
            sparse: self.sparse.max(sparse as u64),
            mean,
            m2_over_m1,
            ..self
        }
    }

    /// The same run in a scheme without particle doubling: its particles fall to
    /// `mass/mean` by the end, and no cluster passes the start's mass (a gel included).
    pub fn without_doubling(self) -> Self {
        if !(self.mean > 0.0 && self.mass > 0.0) {
            return self;
        }
        let start = Reach {
            largest: self.start,
            sparse: 0,
            particles: ((self.mass / self.mean) as u64).clamp(1, self.particles.max(1)),
            ..self
        };
        let mut r = start.ending_at(self.mean, self.m2_over_m1);
        r.particles = self.particles;
        // (a predicted gel: all the mass)
        let cap = self.mass.min(u64::MAX as f64 / 4.0) as u64;
        r.largest = if self.largest >= cap {
            cap
        } else {
            r.largest.min(cap)
        };
        r.largest = r.largest.max(self.start);
        r
    }

    /// The reach at time `t` of a coagulation from this start, by the mean-field
    /// (monodisperse) approximation of the mean size where no exact solution is known:
    /// the number concentration `n` obeys `dn/dt = −½ K(s, s) n²` with `s = ρ/n` the
    /// mean size and ρ the (conserved) mass concentration, and the tail is taken as
    /// exponential (`M2/M1 = 2s`). For the Brownian kernel, where `K(s, s) = 4` for every
    /// s, this is Smoluchowski's own `n = n0/(1 + 2 n0 t)`, within 8 % of the measured
    /// M0 at the end of Osinsky's table 1. `volume` and `mass` are the start's (its
    /// counts' volume and `Σ i N_i`). A kernel that gels in the approximation stops at
    /// all the mass in one particle.
    pub fn mean_field<K: CoagulationKernel + ?Sized>(
        self,
        kernel: &K,
        volume: f64,
        mass: f64,
        t: f64,
    ) -> Self {
        self.mean_field_of(|s| diagonal_rate(kernel, s), volume, mass, t)
    }

    /// [`mean_field`](Self::mean_field) with the diagonal rate `K(s, s)` given as a
    /// function of the mean size s (a temperature model's aggregation rate at a fixed
    /// temperature: with cooling, the real rate falls and this over-predicts).
    pub fn mean_field_of(
        self,
        diagonal: impl Fn(f64) -> f64,
        volume: f64,
        mass: f64,
        t: f64,
    ) -> Self {
        let n0 = self.particles as f64;
        if !(volume > 0.0 && mass > 0.0 && n0 > 0.0 && t > 0.0 && t.is_finite()) {
            return self;
        }
        let rho = mass / volume;
        let all = mass; // the whole simulated mass in one particle
        // u = 1/n: du/dt = ½ K(ρu, ρu), integrated by the midpoint rule with steps
        // that change u by 2 % at most
        let f = |u: f64| 0.5 * diagonal(rho * u);
        let (mut u, mut time) = (volume / n0, 0.0);
        for _ in 0..200_000 {
            if time >= t || rho * u >= all {
                break;
            }
            let d = f(u);
            if !(d.is_finite() && d > 0.0) {
                break;
            }
            let h = (0.02 * u / d).min(t - time);
            let mid = f(u + 0.5 * h * d);
            if !(mid.is_finite() && mid > 0.0) {
                break;
            }
            u += h * mid;
            time += h;
        }
        let mean = (rho * u).min(all);
        self.ending_at(mean, 2.0 * mean)
    }

    /// The length a size table reaches that a build makes `first` long (for the
    /// start's largest size) and that doubles when a size passes its end: `first` while
    /// the sizes stay within it, else √2 times the largest size (a table doubled past
    /// the largest size is one to two times it; √2 is the middle on a log scale).
    pub fn table_len(&self, first: u64) -> u64 {
        if self.largest <= first {
            return first;
        }
        ((self.largest as f64 * core::f64::consts::SQRT_2) as u64).max(first)
    }

    /// The bytes of tables of `per_size` bytes a size (over
    /// [`table_len`](Self::table_len) of `first`), `per_particle` a particle and
    /// `per_sparse` a sparsely held particle.
    pub fn bytes(&self, first: u64, per_size: u64, per_particle: u64, per_sparse: u64) -> u64 {
        self.table_len(first)
            .saturating_mul(per_size)
            .saturating_add(self.particles.saturating_mul(per_particle))
            .saturating_add(self.sparse.saturating_mul(per_sparse))
    }
}

/// Gauss–Laguerre nodes and weights (6 points): `∫₀^∞ e^{−ξ} f(ξ) dξ ≈ Σ w_k f(ξ_k)`.
const LAGUERRE: [(f64, f64); 6] = [
    (0.222_846_604_179_261, 0.458_964_673_949_963),
    (1.188_932_101_672_623, 0.417_000_830_772_121),
    (2.992_736_326_059_314, 0.113_373_382_074_045),
    (5.775_143_569_104_511, 0.010_399_197_453_149),
    (9.837_467_418_382_59, 0.000_261_017_202_815),
    (15.982_873_980_601_702, 0.000_000_898_547_906),
];

/// The rate the mean field takes at mean size s: `K(s, s)`, or, for a kernel that
/// vanishes on its diagonal (differential sedimentation: equal drops fall together),
/// its mean over two independent exponential sizes of mean s (Gauss–Laguerre) — the
/// diagonal alone would predict no growth at all.
fn diagonal_rate<K: CoagulationKernel + ?Sized>(kernel: &K, s: f64) -> f64 {
    let d = kernel.rate(s, s);
    if d > 0.0 {
        return d;
    }
    let mut mean = 0.0;
    for (x, wx) in LAGUERRE {
        for (y, wy) in LAGUERRE {
            mean += wx * wy * kernel.rate(s * x, s * y);
        }
    }
    mean
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Coagulation;

    #[test]
    fn the_mean_field_is_smoluchowskis_for_the_brownian_kernel() {
        // K(s, s) = 4: n = n0/(1 + 2 n0 t), so from n0 = 1 at t = 1e5 the mean size is
        // 1 + 2e5
        let k = Coagulation::brownian();
        let counts = [1_000_000u64];
        let start = Reach::at_start(
            &Init::Counts {
                counts: &counts,
                volume: 1e6,
            },
            2,
        );
        let r = start.mean_field(&k, 1e6, 1e6, 1e5);
        let mean = 2.0 * 1e5 + 1.0;
        let want = 0.5 * 2.0 * mean * libm::log(1e6);
        assert!(
            (r.largest as f64 / want - 1.0).abs() < 0.01,
            "{} vs {want}",
            r.largest
        );
        assert_eq!(r.sparse, 1_000_000, "every particle sparse at mean 2e5");
        assert_eq!(r.start, 1);
        assert!(r.table_len(64) > r.largest);
        // the constant kernel K = 1 (K(s,s) = 1): n = 1/(1 + t/2), mean 1 + t/2
        let k = Coagulation::constant(1.0).unwrap();
        let r = start.mean_field(&k, 1e6, 1e6, 200.0);
        let want = 101.0 * libm::log(1e6);
        assert!((r.largest as f64 / want - 1.0).abs() < 0.01);
        assert_eq!(r.sparse, (SPARSE_COUNT * 101.0) as u64);
    }

    /// A kernel that vanishes on its diagonal (gravitational collection) grows in the
    /// mean field through its mean over exponential sizes; the quadrature integrates
    /// the constant and additive kernels' means exactly (1 and 2s).
    #[test]
    fn a_kernel_vanishing_on_its_diagonal_grows_by_its_mean() {
        let k = Coagulation::gravitational(1e-5).unwrap();
        assert_eq!(k.rate(30.0, 30.0), 0.0);
        assert!(diagonal_rate(&k, 30.0) > 0.1 * k.rate(15.0, 45.0));
        let counts = [0u64, 0, 0, 0, 0, 0, 0, 0, 0, 1000];
        let init = Init::Counts {
            counts: &counts,
            volume: 1000.0 / 8_388_608.0,
        };
        let start = Reach::at_start(&init, 3);
        let r = start.mean_field(&k, 1000.0 / 8_388_608.0, 10_000.0, 1000.0);
        // (the diagonal alone keeps the start's mean, 10)
        assert!(r.mean > 12.0 && r.largest > 50, "{} {}", r.mean, r.largest);
        let c = Coagulation::constant(1.0).unwrap();
        let a = Coagulation::additive();
        let mean = |k: &Coagulation, s: f64| {
            let mut m = 0.0;
            for (x, wx) in LAGUERRE {
                for (y, wy) in LAGUERRE {
                    m += wx * wy * k.rate(s * x, s * y);
                }
            }
            m
        };
        assert!((mean(&c, 7.0) - 1.0).abs() < 1e-12);
        assert!((mean(&a, 7.0) - 14.0).abs() < 1e-9);
    }

    #[test]
    fn a_gelling_kernel_stops_at_all_the_mass_and_bad_input_keeps_the_start() {
        let k = Coagulation::multiplicative();
        let counts = [1000u64];
        let init = Init::Counts {
            counts: &counts,
            volume: 1000.0,
        };
        let start = Reach::at_start(&init, 1);
        let r = start.mean_field(&k, 1000.0, 1000.0, 1e6);
        assert!(r.largest as f64 <= 0.5 * 2000.0 * libm::log(1000.0) + 1.0);
        for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(start.mean_field(&k, 1000.0, 1000.0, t), start);
        }
        assert_eq!(start.table_len(64), 64);
        assert_eq!(start.ending_at(f64::NAN, 1.0), start);
    }
}
