//! The test problem of Maftei, Bossy & Jabir (2016), section 4.2 (SPEC §7): drift
//! `b(x, u) = cos(2πx) + 0.5 cos(2πu)`, σ = 1, `f(x, u) = (10 − u)² (1 − x)`,
//! T = 3.2, a wall at 0, a periodic border at x = 1 and velocities kept in [−10, 10].
//!
//! The paper leaves two things open, and [`Choices`] makes them explicit:
//! * the periodic border: we read it as `x ↦ x − 1` past 1 (the position lives on
//!   [0, 1), a trajectory leaving at 1 comes back at 0+ next to the wall); the
//!   alternative of no border at all is [`Choices::free`];
//! * the velocity bound: "the velocity process was defined on [−10, 10]" without the
//!   rule; we reflect at ±10 ([`VelocityBound::Reflect`]) by default and measure
//!   clamping and no bound (docs/results/maftei2016-reproduction.md).
//!
//! ```
//! use coagula_core::langevin::{paper, richardson_romberg, Wall};
//! let mut run = |dt, first_id| {
//!     let mut b = paper::batch(Wall::Specular, dt, paper::Choices::default(), 4000, 9, first_id).unwrap();
//!     b.advance_to(paper::T).unwrap();
//!     (b.statistics(|x, u| paper::observable(x[0], u[0])), b.hit_statistics())
//! };
//! let (coarse, hits) = run(0.1, 0);
//! let (fine, _) = run(0.05, 4000); // independent trajectories
//! let rr = richardson_romberg(&coarse, &fine);
//! let (lo, hi) = rr.ci95();
//! assert!(lo < rr.mean && rr.mean < hi);
//! assert!(hits.mean() > 1.0 && hits.mean() < 1.3); // the paper: 1.14 hits per trajectory
//! ```

use super::{Batch, Config, Drift, VelocityBound, Wall};
use crate::error::Result;

/// Final time of the test problem.
pub const T: f64 = 3.2;
/// Noise amplitude of the test problem.
pub const SIGMA: f64 = 1.0;
/// Start `(x0, u0)` of the specular runs.
pub const SPECULAR_START: (f64, f64) = (0.5, -1.5);
/// Start `(x0, u0)` of the absorbing runs.
pub const ABSORBING_START: (f64, f64) = (0.5, 1.0);
/// The paper's reference `E f(X_T, U_T)` with a specular wall (a PDE solve).
pub const SPECULAR_REFERENCE: f64 = 49.8609;
/// The paper's reference with an absorbing wall (Monte Carlo at its finest step).
pub const ABSORBING_REFERENCE: f64 = 64.5406;
/// The paper's mean number of wall hits per specular trajectory.
pub const HITS_PER_TRAJECTORY: f64 = 1.14;
/// The paper's fraction of absorbed trajectories.
pub const ABSORBED_FRACTION: f64 = 0.30;

/// `f(x, u) = (10 − u)² (1 − x)`.
#[inline]
pub fn observable(x: f64, u: f64) -> f64 {
    (10.0 - u) * (10.0 - u) * (1.0 - x)
}

/// The drift `cos(2πx) + 0.5 cos(2πu)`, with [`cos_2pi`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PaperDrift;

impl Drift<1> for PaperDrift {
    #[inline(always)]
    fn drift(&self, _t: f64, x: &[f64; 1], u: &[f64; 1]) -> [f64; 1] {
        [cos_2pi(x[0]) + 0.5 * cos_2pi(u[0])]
    }
}

/// `cos(2π x)` without branches: `a = |x − trunc(x)|` in [0, 1) (exact), then
/// `cos(2πa) = sin(2π s)` with `s = |a − ½| − ¼` in [−¼, ¼], and the Taylor polynomial
/// of `sin z` to degree 23 (by Estrin's scheme) on `z = 2πs ∈ [−π/2, π/2]`: absolutely
/// within 1e-15 of `libm::cos` (a test sweeps the range). The drift
/// evaluates it twice per step on the step's critical path (the velocity waits for
/// it): folds by `abs` instead of comparisons keep unpredictable branches out (two
/// mispredictions a call cost more than the polynomial). NaN for NaN and infinity.
#[inline]
pub fn cos_2pi(x: f64) -> f64 {
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        // |x| ≥ 2^52 is an integer (cos = 1); NaN and infinity give NaN
        return if x.is_finite() { 1.0 } else { f64::NAN };
    }
    let a = (x - (x as i64) as f64).abs(); // [0, 1), exact
    // cos(2πa) = −cos(2π|a − 1/2|) = sin(2π(|a − 1/2| − 1/4))
    let s = (a - 0.5).abs() - 0.25;
    sin_poly(core::f64::consts::TAU * s)
}

/// `Σ (−1)^k z^{2k+1} / (2k+1)!` for k ≤ 11: the remainder on [−π/2, π/2] is below
/// `(π/2)^25 / 25! < 1e-20`.
#[inline(always)]
fn sin_poly(z: f64) -> f64 {
    const C: [f64; 12] = [
        1.0,
        -1.0 / 6.0,
        1.0 / 120.0,
        -1.0 / 5_040.0,
        1.0 / 362_880.0,
        -1.0 / 39_916_800.0,
        1.0 / 6_227_020_800.0,
        -1.0 / 1_307_674_368_000.0,
        1.0 / 355_687_428_096_000.0,
        -1.0 / 121_645_100_408_832_000.0,
        1.0 / 51_090_942_171_709_440_000.0,
        -1.0 / 25_852_016_738_884_976_640_000.0,
    ];
    // Estrin's scheme in w = z²: four levels of multiply-adds instead of Horner's
    // eleven, which shortens the critical path
    let w = z * z;
    let w2 = w * w;
    let w4 = w2 * w2;
    let w8 = w4 * w4;
    let q0 = C[0] + C[1] * w;
    let q1 = C[2] + C[3] * w;
    let q2 = C[4] + C[5] * w;
    let q3 = C[6] + C[7] * w;
    let q4 = C[8] + C[9] * w;
    let q5 = C[10] + C[11] * w;
    let r0 = q0 + q1 * w2;
    let r1 = q2 + q3 * w2;
    let r2 = q4 + q5 * w2;
    z * ((r0 + r1 * w4) + r2 * w8)
}

/// The open points of the paper, made choices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Choices {
    /// Periodic border (the paper's: at 1).
    pub period: Option<f64>,
    /// Velocity bound (the paper's: ±10, rule not given).
    pub bound: VelocityBound,
}

impl Default for Choices {
    /// Period 1, velocities reflected at ±10.
    fn default() -> Self {
        Choices {
            period: Some(1.0),
            bound: VelocityBound::Reflect(10.0),
        }
    }
}

impl Choices {
    /// No periodic border and no velocity bound.
    pub fn free() -> Self {
        Choices {
            period: None,
            bound: VelocityBound::None,
        }
    }
}

/// The configuration of the test problem at step `dt`.
pub fn config(wall: Wall, dt: f64, choices: Choices) -> Result<Config<1>> {
    let mut c = Config::line(dt, SIGMA, wall)?;
    if let Some(l) = choices.period {
        c = c.with_period(l)?;
    }
    c.with_velocity_bound(choices.bound)
}

/// `n` trajectories of the test problem from the paper's start for `wall`, ids
/// `first_id..first_id + n` under `key`.
pub fn batch(
    wall: Wall,
    dt: f64,
    choices: Choices,
    n: usize,
    key: u64,
    first_id: u64,
) -> Result<Batch<1, PaperDrift>> {
    let (x0, u0) = match wall {
        Wall::Specular => SPECULAR_START,
        Wall::Absorbing => ABSORBING_START,
    };
    Batch::with_starts(
        config(wall, dt, choices)?,
        PaperDrift,
        n,
        key,
        first_id,
        |_| ([x0], [u0]),
    )
}
