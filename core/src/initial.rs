//! Initial states every front end builds the same way: a size distribution turned
//! into the start a scheme takes (counts on a size grid, samples of the number or of
//! the mass distribution), and the particle velocities of a gas.
//!
//! A front end (the C ABI, the CLI, Python) draws a start here and passes it to a
//! registry build, so the same seed gives the same start everywhere.
//!
//! **Quantile lattices.** N particles from a continuous distribution are the quantiles
//! `F⁻¹((k + u)/N)`, `k = 0..N−1`, of the distribution the scheme samples (the number
//! distribution for the integer-size schemes and direct simulation, the mass
//! distribution `x c(x)/M1` for the mass-flow schemes, Lécot et al. 2019 §3; Eibeck &
//! Wagner 2000 eq. 5.1): `u = 1/2` (the centred lattice) for a scheme that draws no
//! random numbers (deterministic QMC), a uniform per replica otherwise — a randomly
//! shifted lattice, so the initial moments are unbiased even where the quantile sum is
//! singular ([`lattice_shift`]).
//!
//! # Example
//! ```
//! use coagula_core::initial::{self, Distribution};
//! use coagula_core::random::{Purpose, substream};
//! use coagula_core::scheme::registry;
//! // 4096 particles from an exponential number distribution of mean 1, for direct
//! // simulation (samples of the number distribution) at concentration 1
//! let dsa = registry::find("dsa").unwrap();
//! let start = Distribution::Exponential { mean: 1.0 }.start(dsa, 4096, 1.0, 1.0, 0.5).unwrap();
//! let init = start.init();
//! // 1000 monomers and 10 dimers at temperature 1, from the seed policy's velocity stream
//! let mut rng = substream(7, 0, Purpose::Velocities);
//! let (sizes, velocities) = initial::maxwellian(&[1000, 10], &[1.0, 1.0], &mut rng).unwrap();
//! assert_eq!(sizes.len(), 1010);
//! assert_eq!(velocities.len(), 3 * 1010);
//! ```

use crate::error::{Error, Result};
use crate::memory::try_reserve;
use crate::random::normal;
use alloc::vec::Vec;
use rand_core::Rng;

/// A number distribution of particle sizes (its concentration is given apart).
#[derive(Clone, Debug, PartialEq)]
pub enum Distribution {
    /// Every particle of size `size`.
    Monodisperse {
        /// The size (> 0; an integer for the integer-size schemes).
        size: f64,
    },
    /// `c(x) ∝ e^{−x/μ}`.
    Exponential {
        /// The mean μ > 0.
        mean: f64,
    },
    /// Log-normal of median `median` and geometric standard deviation `gsd` ∈ (1, 100).
    Lognormal {
        /// The median size.
        median: f64,
        /// The geometric standard deviation.
        gsd: f64,
    },
    /// An explicit list of particle sizes (each finite and > 0; at least 2).
    Sizes(Vec<f64>),
    /// Counts of integer sizes: `counts[i − 1]` particles of size i (at least 2).
    Counts(Vec<u64>),
}

pub(crate) fn out_of_range(name: &'static str, value: f64, range: &'static str) -> Error {
    Error::OutOfRange { name, value, range }
}

impl Distribution {
    /// Checks the parameters.
    pub fn check(&self) -> Result<()> {
        match self {
            Distribution::Monodisperse { size } => {
                crate::error::positive("size", *size).map(|_| ())
            }
            Distribution::Exponential { mean } => crate::error::positive("mean", *mean).map(|_| ()),
            Distribution::Lognormal { median, gsd } => {
                crate::error::positive("median", *median)?;
                if !(gsd.is_finite() && *gsd > 1.0 && *gsd < 100.0) {
                    return Err(out_of_range("gsd", *gsd, "(1, 100)"));
                }
                Ok(())
            }
            Distribution::Sizes(x) => {
                if x.len() < 2 {
                    return Err(Error::BufferLength {
                        name: "sizes (at least 2)",
                        expected: 2,
                        got: x.len(),
                    });
                }
                for &v in x {
                    crate::error::positive("size", v)?;
                }
                Ok(())
            }
            Distribution::Counts(c) => match c.iter().try_fold(0u64, |a, &b| a.checked_add(b)) {
                Some(t) if t >= 2 => Ok(()),
                _ => Err(Error::OutOfRange {
                    name: "total of the counts",
                    value: 0.0,
                    range: "[2, 2^64)",
                }),
            },
        }
    }

    /// Whether the distribution is continuous (a start from it is a quantile lattice).
    pub fn is_continuous(&self) -> bool {
        matches!(
            self,
            Distribution::Exponential { .. } | Distribution::Lognormal { .. }
        )
    }

    /// The mean size.
    pub fn mean(&self) -> f64 {
        match self {
            Distribution::Monodisperse { size } => *size,
            Distribution::Exponential { mean } => *mean,
            Distribution::Lognormal { median, gsd } => {
                let s = libm::log(*gsd);
                median * libm::exp(0.5 * s * s)
            }
            Distribution::Sizes(x) => x.iter().sum::<f64>() / x.len() as f64,
            Distribution::Counts(c) => {
                let (mut m, mut n) = (0.0, 0.0);
                for (k, &v) in c.iter().enumerate() {
                    m += (k + 1) as f64 * v as f64;
                    n += v as f64;
                }
                m / n
            }
        }
    }

    /// The particles an explicit list gives (`None` for a continuous distribution and a
    /// monodisperse one, which take N from the caller).
    pub fn particles(&self) -> Option<u64> {
        match self {
            Distribution::Sizes(x) => Some(x.len() as u64),
            Distribution::Counts(c) => Some(c.iter().fold(0u64, |a, &b| a.saturating_add(b))),
            _ => None,
        }
    }

    /// The inverse CDF at `u ∈ (0, 1)` of the number distribution (`mass = false`) or
    /// of the mass distribution `x c(x)/M1` (continuous distributions only).
    pub fn inverse(&self, u: f64, mass: bool) -> f64 {
        match (self, mass) {
            (Distribution::Exponential { mean }, false) => -mean * libm::log1p(-u),
            // the mass distribution of an exponential is μ Γ(2, 1)
            (Distribution::Exponential { mean }, true) => mean * gamma2_inverse(u),
            (Distribution::Lognormal { median, gsd }, m) => {
                let s = libm::log(*gsd);
                // the mass distribution of a log-normal is log-normal with its
                // ln-median shifted by σ²
                let med = if m {
                    median * libm::exp(s * s)
                } else {
                    *median
                };
                med * libm::exp(s * normal_inverse(u))
            }
            _ => f64::NAN,
        }
    }

    /// The relative mass bias of putting a continuous distribution on a grid of `grid`:
    /// the share of particles below half a cell (each rounded up to size 1, gaining at
    /// most a cell) times `grid / mean`. 0 for a discrete distribution.
    pub fn grid_bias(&self, grid: f64) -> f64 {
        if !self.is_continuous() {
            return 0.0;
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.inverse(mid, false) < 0.5 * grid {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo * grid / self.mean()
    }
}

/// The shift of the quantile lattice of replica `replica`: 1/2 for a scheme that draws
/// no random numbers (`randomised` false: deterministic QMC points), else a uniform from
/// the seed policy's `Purpose::Initial` stream of `(seed, replica)`.
pub fn lattice_shift(randomised: bool, seed: u64, replica: u64) -> f64 {
    if randomised {
        let mut g = crate::random::substream(seed, replica, crate::random::Purpose::Initial);
        crate::random::unit_f64(g.next_u64())
    } else {
        0.5
    }
}

/// Counts of integer sizes from sizes measured in units of `grid` (rounded to the
/// nearest multiple, at least 1). Errors: a size past 1e7 grid units (a dense start).
pub fn counts_on_grid(sizes: impl Iterator<Item = f64>, grid: f64) -> Result<Vec<u64>> {
    let mut counts: Vec<u64> = Vec::new();
    for x in sizes {
        let i = libm::round(x / grid).max(1.0);
        if i.is_nan() || i > 1e7 {
            return Err(out_of_range(
                "size in grid units (a dense start holds at most 1e7 sizes)",
                i,
                "[1, 1e7]",
            ));
        }
        let i = i as usize;
        if counts.len() < i {
            let more = i - counts.len();
            try_reserve(&mut counts, more)?;
            counts.resize(i, 0);
        }
        counts[i - 1] += 1;
    }
    Ok(counts)
}

/// `n` quantiles of the distribution of weighted sizes `pairs` (size, count), each
/// count weighted by its size when `mass` (the mass distribution) or by 1, taken at
/// `(k + 1/2)/n`.
pub(crate) fn quantiles(n: usize, pairs: &mut [(f64, f64)], mass: bool) -> Vec<f64> {
    let weight = |x: f64| if mass { x } else { 1.0 };
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = pairs.iter().map(|&(x, w)| weight(x) * w).sum();
    let mut out = Vec::with_capacity(n);
    let (mut i, mut cum) = (0usize, weight(pairs[0].0) * pairs[0].1);
    for k in 0..n {
        let u = (k as f64 + 0.5) / n as f64 * total;
        while cum < u && i + 1 < pairs.len() {
            i += 1;
            cum += weight(pairs[i].0) * pairs[i].1;
        }
        out.push(pairs[i].0);
    }
    out
}

/// The Gamma(2, 1) CDF `1 − (1 + x) e^{−x}`, without cancellation for small x (its
/// series `x²/2 − x³/3 + x⁴/8 − x⁵/30` below 1e-3).
fn gamma2_cdf(x: f64) -> f64 {
    if x < 1e-3 {
        x * x * (0.5 - x * (1.0 / 3.0 - x * (0.125 - x / 30.0)))
    } else {
        -libm::expm1(-x) - x * libm::exp(-x)
    }
}

/// Inverse CDF of the Gamma(2, 1) law (the mass distribution x e^{−x} of an
/// exponential number distribution): Newton on `gamma2_cdf(x) = u` from `√(2u)` (small
/// u) or `−ln(1−u) + 1` (the CDF is convex then concave, so a few more steps).
pub fn gamma2_inverse(u: f64) -> f64 {
    let mut x = if u < 0.1 {
        libm::sqrt(2.0 * u)
    } else {
        1.0 - libm::log1p(-u)
    };
    for _ in 0..100 {
        let d = x * libm::exp(-x);
        if d <= 0.0 {
            break;
        }
        let next = (x - (gamma2_cdf(x) - u) / d).max(0.5 * x);
        let done = (next - x).abs() <= 4.0 * f64::EPSILON * x;
        x = next;
        if done {
            break;
        }
    }
    x
}

/// Inverse of the standard normal CDF (Acklam's rational approximation, relative
/// error below 1.2e-9, refined by one Halley step on `erfc`, so close to full
/// precision).
pub fn normal_inverse(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let lo = 0.02425;
    let x = if p < lo {
        let q = libm::sqrt(-2.0 * libm::log(p));
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - lo {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = libm::sqrt(-2.0 * libm::log(1.0 - p));
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // one Halley step: e = Φ(x) − p with Φ(x) = erfc(−x/√2)/2
    let e = 0.5 * libm::erfc(-x / core::f64::consts::SQRT_2) - p;
    let u = e * libm::sqrt(2.0 * core::f64::consts::PI) * libm::exp(0.5 * x * x);
    x - u / (1.0 + 0.5 * x * u)
}

/// [`maxwellian`] drawn from the seed policy's velocity stream of `(seed, stream)`
/// (`random::substream(seed, stream, Purpose::Velocities)`): what every front end
/// uses, so the same seed gives the same gas everywhere.
pub fn maxwellian_of_seed(
    counts: &[u64],
    temperatures: &[f64],
    seed: u64,
    stream: u64,
) -> Result<(Vec<u64>, Vec<f64>)> {
    let mut rng = crate::random::substream(seed, stream, crate::random::Purpose::Velocities);
    maxwellian(counts, temperatures, &mut rng)
}

/// `counts[i − 1]` particles of size i with Maxwellian velocities at temperature
/// `temperatures[i − 1]`: each component normal with variance `T_i / i` (Osinsky 2023
/// §5), drawn in the order of the sizes, three components a particle. Returns the
/// sizes and the velocities (three per particle). Errors: lengths that differ, a
/// temperature not finite or negative, more particles than memory allows.
pub fn maxwellian<G: Rng + ?Sized>(
    counts: &[u64],
    temperatures: &[f64],
    rng: &mut G,
) -> Result<(Vec<u64>, Vec<f64>)> {
    if counts.len() != temperatures.len() {
        return Err(Error::BufferLength {
            name: "temperatures (one per size of the counts)",
            expected: counts.len(),
            got: temperatures.len(),
        });
    }
    let total = counts
        .iter()
        .try_fold(0u64, |a, &c| a.checked_add(c))
        .and_then(|n| usize::try_from(n).ok())
        .and_then(|n| n.checked_mul(3).map(|_| n))
        .ok_or(Error::Capacity {
            name: "particles (address space)",
            capacity: usize::MAX / 3,
        })?;
    for &t in temperatures {
        if !(t >= 0.0 && t.is_finite()) {
            return Err(Error::OutOfRange {
                name: "temperature",
                value: t,
                range: "[0, inf)",
            });
        }
    }
    let mut sizes = Vec::new();
    let mut vel = Vec::new();
    try_reserve(&mut sizes, total)?;
    try_reserve(&mut vel, 3 * total)?;
    for (i, (&c, &t)) in counts.iter().zip(temperatures).enumerate() {
        let sd = libm::sqrt(t / (i + 1) as f64);
        for _ in 0..c {
            sizes.push(i as u64 + 1);
            vel.extend_from_slice(&[sd * normal(rng), sd * normal(rng), sd * normal(rng)]);
        }
    }
    Ok((sizes, vel))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inverse CDFs invert their CDFs, over the tails as well.
    #[test]
    fn inverse_cdfs_invert() {
        for &u in &[1e-12, 1e-9, 1e-5, 0.01, 0.3, 0.5, 0.9, 0.999_999] {
            let x = gamma2_inverse(u);
            let f = gamma2_cdf(x);
            assert!((f - u).abs() <= 1e-13 * u, "gamma2 u={u} x={x} F={f}");
            // the small-x series agrees with the closed form where both are accurate
            let y: f64 = 9e-4;
            let closed = -libm::expm1(-y) - y * libm::exp(-y);
            assert!((gamma2_cdf(y) - closed).abs() < 1e-15 * gamma2_cdf(y) * 1e3);
            let z = normal_inverse(u);
            let p = 0.5 * libm::erfc(-z / core::f64::consts::SQRT_2);
            assert!(
                (p - u).abs() < 1e-13 * u.max(1e-3),
                "normal u={u} z={z} Φ={p}"
            );
        }
    }
}
