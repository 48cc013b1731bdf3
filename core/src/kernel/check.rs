//! Numerical verification of kernel bounds on a grid of sizes.

use super::CoagulationKernel;
use crate::error::{Error, Result};
use alloc::vec::Vec;

/// What [`check_majorant`] or [`check_low_rank`] found on a grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundCheck {
    /// Number of pairs (x, y) evaluated.
    pub pairs: usize,
    /// Pairs where `K > bound` (beyond a relative rounding tolerance of 1e-12).
    pub violations: usize,
    /// The largest `K / bound` (≤ 1 when the bound holds).
    pub max_ratio: f64,
    /// The smallest `K / bound`: the worst acceptance probability of thinning.
    pub worst_acceptance: f64,
    /// Where the worst acceptance occurs.
    pub worst_at: (f64, f64),
    /// Grid points where `h(x)/x` increases (majorant check only; must be 0).
    pub monotonicity_violations: usize,
}

/// `n` sizes spaced evenly in log between `lo` and `hi` (inclusive).
pub fn log_grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let (a, b) = (libm::log(lo), libm::log(hi));
    (0..n)
        .map(|i| {
            if n == 1 {
                lo
            } else {
                libm::exp(a + (b - a) * i as f64 / (n - 1) as f64)
            }
        })
        .collect()
}

fn scan<K, B>(k: &K, grid: &[f64], bound: B) -> Result<BoundCheck>
where
    K: CoagulationKernel + ?Sized,
    B: Fn(f64, f64) -> f64,
{
    let mut out = BoundCheck {
        pairs: 0,
        violations: 0,
        max_ratio: 0.0,
        worst_acceptance: f64::INFINITY,
        worst_at: (f64::NAN, f64::NAN),
        monotonicity_violations: 0,
    };
    for (i, &x) in grid.iter().enumerate() {
        for &y in &grid[i..] {
            let kv = super::checked_rate(k, x, y)?;
            let b = bound(x, y);
            if !(b >= 0.0 && b.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "kernel bound",
                    value: b,
                });
            }
            out.pairs += 1;
            if kv > b * (1.0 + 1e-12) {
                out.violations += 1;
            }
            let r = if b > 0.0 {
                kv / b
            } else if kv > 0.0 {
                f64::INFINITY
            } else {
                1.0
            };
            out.max_ratio = out.max_ratio.max(r);
            if r < out.worst_acceptance {
                out.worst_acceptance = r;
                out.worst_at = (x, y);
            }
        }
    }
    Ok(out)
}

/// Checks `K(x, y) ≤ h(x) h(y)` on all pairs of `grid` and that `h(x)/x` is
/// non-increasing along the sorted grid. Errors if the kernel has no majorant or
/// returns an invalid rate.
pub fn check_majorant<K: CoagulationKernel + ?Sized>(k: &K, grid: &[f64]) -> Result<BoundCheck> {
    let h = |x: f64| {
        k.majorant(x).ok_or(Error::Unsupported {
            what: "product majorant",
        })
    };
    let mut sorted: Vec<f64> = grid.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut hs = Vec::with_capacity(sorted.len());
    for &x in &sorted {
        hs.push(h(x)?);
    }
    let mut report = scan(k, grid, |x, y| {
        // h was validated above for every grid point
        k.majorant(x).unwrap_or(f64::NAN) * k.majorant(y).unwrap_or(f64::NAN)
    })?;
    for i in 1..sorted.len() {
        let (a, b) = (hs[i - 1] / sorted[i - 1], hs[i] / sorted[i]);
        if b > a * (1.0 + 1e-12) {
            report.monotonicity_violations += 1;
        }
    }
    Ok(report)
}

/// Checks `K(x, y) ≤ A(x, y) + A(y, x)` on all pairs of `grid` and that every factor is
/// non-negative. Errors if the kernel has no low-rank bound, a factor is negative or
/// not finite, or the kernel returns an invalid rate.
pub fn check_low_rank<K: CoagulationKernel + ?Sized>(k: &K, grid: &[f64]) -> Result<BoundCheck> {
    let r = k.rank();
    if r == 0 || r > super::MAX_RANK {
        return Err(Error::Unsupported {
            what: "low-rank bound",
        });
    }
    let (mut a, mut b) = ([0.0; super::MAX_RANK], [0.0; super::MAX_RANK]);
    for &x in grid {
        k.factors(x, &mut a[..r], &mut b[..r]);
        for &v in a[..r].iter().chain(&b[..r]) {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Error::InvalidRate {
                    name: "low-rank factor",
                    value: v,
                });
            }
        }
    }
    scan(k, grid, |x, y| k.low_rank_bound(x, y).unwrap_or(f64::NAN))
}
