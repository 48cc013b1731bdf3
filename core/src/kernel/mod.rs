//! Coagulation and fragmentation kernels, with the bounds the stepping schemes need.
//!
//! A coagulation kernel `K(x, y)` is the rate constant of the pair (x, y) (in a
//! particle system of volume V each unordered pair coagulates at rate `K/V`). Schemes
//! that sample by thinning need a bound on K:
//!
//! * a **product majorant** `K(x, y) ≤ h(x) h(y)` with `h(x)/x` non-increasing — the
//!   mass flow algorithm and direct simulation of Eibeck & Wagner (2000), eqs. 3.1–3.2;
//! * a **low-rank bound** `K ≤ A + Aᵀ`, `A(i, j) = Σ_{k<R} a_k(i) b_k(j)` — Osinsky's
//!   low-rank Monte Carlo (2023).
//!
//! Built-in kernels ([`Coagulation`]) carry both; a kernel of your own implements
//! [`CoagulationKernel`] (any `Fn(f64, f64) -> f64` already does, without bounds), or is
//! wrapped in [`UserKernel`] to attach bounds. [`check_majorant`] and [`check_low_rank`]
//! verify a bound on a grid of sizes and report the worst acceptance ratio — run them on
//! your own kernels.
//!
//! Fragmentation kernels ([`FragmentationKernel`]) are given, as in Lécot et al. (2019,
//! §2), by the total break-up rate `Ḟ(x)` and the inverse of the size-biased piece
//! distribution `F̂_x⁻¹(u)`.
//!
//! # Example
//! ```
//! use coagula_core::kernel::{Coagulation, CoagulationKernel};
//! let k = Coagulation::brownian();
//! let (x, y) = (1.0, 8.0);
//! let rate = k.rate(x, y); // (1 + 2)(1 + 1/2) = 4.5
//! assert!((rate - 4.5).abs() < 1e-12);
//! let h = |s| k.majorant(s).unwrap();
//! assert!(rate <= h(x) * h(y));
//! ```

pub mod builtin;
mod check;
mod coagulation;
mod fragmentation;
pub mod gas;
pub mod temperature;

pub use check::{BoundCheck, check_low_rank, check_majorant, log_grid};
pub use coagulation::{BOLTZMANN, Coagulation, atmospheric, gravitational};
pub use fragmentation::{
    BinaryUniform, Fragmentation, FragmentationKernel, NoFragmentation, UserFragmentation,
    break_rate_bound, checked_break_rate, checked_break_rate_within,
};

use crate::error::{Error, Result};

/// The largest rank of a low-rank bound (number of factor pairs `a_k, b_k`).
pub const MAX_RANK: usize = 8;

/// A symmetric coagulation kernel `K(x, y) ≥ 0`, optionally with bounds.
///
/// Only [`rate`](Self::rate) is required. A scheme that needs a bound asks for it and
/// returns [`Error::Unsupported`] if the kernel has none.
pub trait CoagulationKernel {
    /// The rate constant `K(x, y)`.
    fn rate(&self, x: f64, y: f64) -> f64;

    /// The product majorant `h(x)`, with `K(x, y) ≤ h(x) h(y)` and `h(x)/x`
    /// non-increasing, or `None` when the kernel has none.
    fn majorant(&self, _x: f64) -> Option<f64> {
        None
    }

    /// The rank R of the low-rank bound `K ≤ A + Aᵀ`, `A(i, j) = Σ_k a_k(i) b_k(j)`, or 0
    /// when the kernel has none. At most [`MAX_RANK`].
    fn rank(&self) -> usize {
        0
    }

    /// Writes `a_k(x)` into `a[k]` and `b_k(x)` into `b[k]` for `k < self.rank()`.
    /// Both slices have length at least `self.rank()`. All factors must be `≥ 0`.
    fn factors(&self, _x: f64, _a: &mut [f64], _b: &mut [f64]) {}

    /// The smallest size for which the bounds are guaranteed (0 means all `x > 0`).
    fn min_size(&self) -> f64 {
        0.0
    }

    /// True when the low-rank bound equals the kernel (`K = A + Aᵀ` exactly), so a
    /// scheme may accept every proposal without evaluating K.
    fn low_rank_is_exact(&self) -> bool {
        false
    }

    /// A floor `ρ ∈ [0, 1]` of the acceptance: `K(x, y) ≥ ρ (A(x, y) + A(y, x))` for all
    /// sizes (≥ [`min_size`](Self::min_size)). Low-rank schemes accept a proposal whose
    /// uniform falls below `ρ` times a cheap lower bound of `A + Aᵀ` without evaluating
    /// K. The default is 1 when the bound is exact and 0 (no floor) otherwise; a floor
    /// that is too high biases the results.
    fn low_rank_floor(&self) -> f64 {
        if self.low_rank_is_exact() { 1.0 } else { 0.0 }
    }

    /// True when every factor `a_k`, `b_k` is monotone in x (non-decreasing or
    /// non-increasing) on all of `x ≥ 1`, whatever [`min_size`](Self::min_size) says
    /// (the buckets of integer sizes start at 1), so that its extremes over a range of
    /// sizes are at the range's two ends. A bucketed scheme then bounds a bucket of sizes from
    /// its two ends instead of evaluating every size in it (O(1) instead of O(width)
    /// per bucket, so a growing largest size M costs O(log M) factor evaluations, not
    /// O(M)). The default, false, evaluates every size. A kernel that claims it falsely
    /// gets bounds below its factors and errors out ([`crate::Error::BoundExceeded`]) or
    /// biases the results.
    fn monotone_factors(&self) -> bool {
        false
    }

    /// `sup K(x, y)` over `lo ≤ x, y ≤ hi`, if known (acceptance–rejection needs it).
    fn sup_rate(&self, _lo: f64, _hi: f64) -> Option<f64> {
        None
    }

    /// `sup K(x, y)` over the block `x0 ≤ x ≤ x1`, `y0 ≤ y ≤ y1` of sizes, if known: the
    /// bound of a block-majorant scheme (`docs/design/block-majorants.md`). A scheme on
    /// integer sizes asks only for blocks with integer ends and needs the supremum over
    /// the integer pairs in them. The default bounds the block by the square around it
    /// through [`sup_rate`](Self::sup_rate) (valid, but loose far from the diagonal).
    fn sup_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<f64> {
        self.sup_rate(x0.min(y0), x1.max(y1))
    }

    /// A lower bound of K over the block `x0 ≤ x ≤ x1`, `y0 ≤ y ≤ y1` of sizes (over its
    /// integer pairs on integer ends, as [`sup_block`](Self::sup_block)); 0, the
    /// default, when none is known. A block-majorant scheme accepts a proposal whose
    /// uniform falls below it without evaluating K — the decision K would give, on the
    /// same draws, so it changes the cost and never the results — provided it holds:
    /// the scheme's spot checks evaluate K on one in 1024 of the proposals the squeeze
    /// accepted ([`crate::Error::BoundExceeded`] where K is below the bound there), so a
    /// bound far above K is caught early, one slightly above it on a corner of a block
    /// perhaps never. The built-in bounds are checked by scans in their tests. A bound
    /// at or above the block's `sup_block` squeezes nothing.
    fn inf_block(&self, _x0: f64, _x1: f64, _y0: f64, _y1: f64) -> f64 {
        0.0
    }

    /// Whether the kernel is defined on integer sizes only (its values or bounds do
    /// not hold between them): the registry refuses it for schemes over real sizes.
    /// False by default.
    fn integer_sizes(&self) -> bool {
        false
    }

    /// Whether the low-rank bound is loose somewhere (the acceptance `K / (A + Aᵀ)`
    /// falls towards 0 on part of the size range), so that a scheme that can choose
    /// prefers block majorants ([`sup_block`](Self::sup_block)) when the kernel has
    /// them. False by default.
    fn low_rank_is_loose(&self) -> bool {
        false
    }

    /// Whether block majorants may stop cutting the size axis next to the diagonal at
    /// *log-linear strips* — a strip at most 1/32 of its smallest size wide, as the
    /// buckets of the bucketed layout — instead of strips of 4 sizes: true for a kernel
    /// that varies little across such a strip, so that a block there is bounded nearly
    /// as tightly. The block engine then keeps about 190 more blocks per added octave
    /// of sizes instead of 1.25 per size (`docs/design/block-majorants.md`). Only the acceptance
    /// depends on it, never the law. False by default.
    fn log_linear_blocks(&self) -> bool {
        false
    }

    /// A fingerprint of the kernel and its parameters, which a checkpoint records so
    /// that it is restored only under the same kernel; 0 (the default) for a kernel
    /// that cannot say (closures: their checkpoints are not checked against a change).
    fn fingerprint(&self) -> u64 {
        0
    }

    /// The low-rank bound `Ã(x, y) = A(x, y) + A(y, x)` evaluated from the factors, or
    /// `None` when the kernel has no low-rank bound.
    fn low_rank_bound(&self, x: f64, y: f64) -> Option<f64> {
        let r = self.rank();
        if r == 0 || r > MAX_RANK {
            return None;
        }
        let (mut ax, mut bx, mut ay, mut by) = (
            [0.0; MAX_RANK],
            [0.0; MAX_RANK],
            [0.0; MAX_RANK],
            [0.0; MAX_RANK],
        );
        self.factors(x, &mut ax[..r], &mut bx[..r]);
        self.factors(y, &mut ay[..r], &mut by[..r]);
        let mut s = 0.0;
        for k in 0..r {
            s += ax[k] * by[k] + ay[k] * bx[k];
        }
        Some(s)
    }
}

impl<F: Fn(f64, f64) -> f64> CoagulationKernel for F {
    fn rate(&self, x: f64, y: f64) -> f64 {
        self(x, y)
    }
}

/// A user kernel with optional bounds, built from closures.
///
/// ```
/// use coagula_core::kernel::{UserKernel, CoagulationKernel, check_majorant, log_grid};
/// // K = (x y)^(3/4) with the majorant h = x^(3/4)
/// let k = UserKernel::new(|x: f64, y: f64| (x * y).powf(0.75))
///     .with_majorant(|x: f64| x.powf(0.75))
///     .with_low_rank(1, |x: f64, a: &mut [f64], b: &mut [f64]| {
///         a[0] = 0.5 * x.powf(0.75);
///         b[0] = x.powf(0.75);
///     })
///     .unwrap();
/// let report = check_majorant(&k, &log_grid(1.0, 1e6, 40)).unwrap();
/// assert!(report.violations == 0);
/// assert!((k.low_rank_bound(2.0, 3.0).unwrap() - k.rate(2.0, 3.0)).abs() < 1e-12);
/// ```
#[derive(Clone)]
pub struct UserKernel<F, H = (), L = ()> {
    rate: F,
    majorant: H,
    factors: L,
    rank: usize,
    min_size: f64,
}

impl<F> core::fmt::Debug for UserKernel<F> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UserKernel")
            .field("rank", &self.rank)
            .field("min_size", &self.min_size)
            .finish_non_exhaustive()
    }
}

/// An optional majorant closure (implementation detail of [`UserKernel`]).
pub trait MaybeMajorant {
    /// `h(x)`, if present.
    fn eval(&self, x: f64) -> Option<f64>;
}
impl MaybeMajorant for () {
    fn eval(&self, _x: f64) -> Option<f64> {
        None
    }
}
/// A majorant closure `h` attached to a [`UserKernel`].
#[derive(Clone, Copy, Debug)]
pub struct Majorant<H>(pub H);
impl<H: Fn(f64) -> f64> MaybeMajorant for Majorant<H> {
    fn eval(&self, x: f64) -> Option<f64> {
        Some((self.0)(x))
    }
}

/// Optional low-rank factors (implementation detail of [`UserKernel`]).
pub trait MaybeFactors {
    /// Fills the factors; returns false when absent.
    fn eval(&self, x: f64, a: &mut [f64], b: &mut [f64]) -> bool;
}
impl MaybeFactors for () {
    fn eval(&self, _x: f64, _a: &mut [f64], _b: &mut [f64]) -> bool {
        false
    }
}
/// Low-rank factor closure attached to a [`UserKernel`].
#[derive(Clone, Copy, Debug)]
pub struct Factors<L>(pub L);
impl<L: Fn(f64, &mut [f64], &mut [f64])> MaybeFactors for Factors<L> {
    fn eval(&self, x: f64, a: &mut [f64], b: &mut [f64]) -> bool {
        (self.0)(x, a, b);
        true
    }
}

impl<F: Fn(f64, f64) -> f64> UserKernel<F> {
    /// A kernel with rate `K(x, y) = rate(x, y)` and no bounds yet.
    pub fn new(rate: F) -> Self {
        UserKernel {
            rate,
            majorant: (),
            factors: (),
            rank: 0,
            min_size: 0.0,
        }
    }
}

impl<F, H, L> UserKernel<F, H, L> {
    /// Attaches the product majorant `h`.
    pub fn with_majorant<H2: Fn(f64) -> f64>(self, h: H2) -> UserKernel<F, Majorant<H2>, L> {
        UserKernel {
            rate: self.rate,
            majorant: Majorant(h),
            factors: self.factors,
            rank: self.rank,
            min_size: self.min_size,
        }
    }

    /// Attaches low-rank factors: `factors(x, a, b)` writes `a_k(x)`, `b_k(x)` for
    /// `k < rank`. Errors if `rank` is 0 or above [`MAX_RANK`].
    pub fn with_low_rank<L2: Fn(f64, &mut [f64], &mut [f64])>(
        self,
        rank: usize,
        factors: L2,
    ) -> Result<UserKernel<F, H, Factors<L2>>> {
        if rank == 0 || rank > MAX_RANK {
            return Err(Error::OutOfRange {
                name: "rank",
                value: rank as f64,
                range: "1..=8",
            });
        }
        Ok(UserKernel {
            rate: self.rate,
            majorant: self.majorant,
            factors: Factors(factors),
            rank,
            min_size: self.min_size,
        })
    }

    /// Declares that the bounds hold only for sizes `≥ min_size`.
    pub fn with_min_size(mut self, min_size: f64) -> Result<Self> {
        crate::error::finite("min_size", min_size)?;
        if min_size < 0.0 {
            return Err(Error::OutOfRange {
                name: "min_size",
                value: min_size,
                range: "[0, inf)",
            });
        }
        self.min_size = min_size;
        Ok(self)
    }
}

impl<F, H, L> CoagulationKernel for UserKernel<F, H, L>
where
    F: Fn(f64, f64) -> f64,
    H: MaybeMajorant,
    L: MaybeFactors,
{
    fn rate(&self, x: f64, y: f64) -> f64 {
        (self.rate)(x, y)
    }
    fn majorant(&self, x: f64) -> Option<f64> {
        self.majorant.eval(x)
    }
    fn rank(&self) -> usize {
        self.rank
    }
    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        self.factors.eval(x, a, b);
    }
    fn min_size(&self) -> f64 {
        self.min_size
    }
}

/// Evaluates `K(x, y)` and turns a negative or non-finite value into an error.
pub fn checked_rate<K: CoagulationKernel + ?Sized>(k: &K, x: f64, y: f64) -> Result<f64> {
    let r = k.rate(x, y);
    if r >= 0.0 && r.is_finite() {
        Ok(r)
    } else {
        Err(Error::InvalidRate {
            name: "coagulation kernel",
            value: r,
        })
    }
}

/// `K(x, y)` validated against a proposal bound: a negative or non-finite value is
/// [`Error::InvalidRate`](crate::Error::InvalidRate), a value above `bound` (beyond
/// rounding) is [`Error::BoundExceeded`](crate::Error::BoundExceeded) — a capped rate
/// would bias the run silently.
#[inline]
pub(crate) fn bounded_rate<K: CoagulationKernel + ?Sized>(
    kernel: &K,
    x: f64,
    y: f64,
    bound: f64,
    name: &'static str,
) -> Result<f64> {
    let c = kernel.rate(x, y);
    if !(c >= 0.0 && c.is_finite()) {
        return Err(crate::Error::InvalidRate {
            name: "coagulation kernel",
            value: c,
        });
    }
    if c > bound * (1.0 + 1e-12) {
        return Err(crate::Error::BoundExceeded {
            name,
            rate: c,
            bound,
        });
    }
    Ok(c)
}
