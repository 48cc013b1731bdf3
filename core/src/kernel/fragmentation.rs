//! Fragmentation kernels in the mass-flow form of Lécot et al. (2019, §2).
//!
//! `F(x, y)` is the rate at which a particle of size `x + y` splits into `x` and `y`. The
//! mass-flow schemes follow a particle's mass, so they need the size-biased view: a
//! particle of size x breaks, keeping a piece y with density
//! `F̃(x, y) = (y / x) F(x − y, y)`, at total rate `Ḟ(x) = ∫₀ˣ F̃(x, y) dy`, and the
//! piece is drawn as `y = F̂_x⁻¹(u)` with `F̂_x(y) = ∫₀ʸ F̃(x, z) dz / Ḟ(x)`.

use crate::error::{Error, Result, positive};

/// `Ḟ(x)` checked: finite, `≥ 0` and, where the kernel declares `sup Ḟ`
/// ([`FragmentationKernel::sup_rate`]), at most that (a declared bound that does not
/// hold is an error, as a coagulation kernel above its bound is:
/// [`Error::BoundExceeded`]).
#[inline]
pub fn checked_break_rate<F: FragmentationKernel + ?Sized>(f: &F, x: f64) -> Result<f64> {
    checked_break_rate_within(f, x, break_rate_bound(f))
}

/// The largest `Ḟ(x)` [`checked_break_rate_within`] accepts: the declared supremum
/// (with a few ulps for rounding), or the largest double (a loop computes it once; a
/// finite bound makes one range test also refuse NaN and infinity).
pub fn break_rate_bound<F: FragmentationKernel + ?Sized>(f: &F) -> f64 {
    f.sup_rate().map_or(f64::MAX, |sup| {
        (sup * (1.0 + 4.0 * f64::EPSILON)).min(f64::MAX)
    })
}

/// [`checked_break_rate`] against a bound from [`break_rate_bound`].
#[inline]
pub fn checked_break_rate_within<F: FragmentationKernel + ?Sized>(
    f: &F,
    x: f64,
    bound: f64,
) -> Result<f64> {
    let r = f.total_rate(x);
    // (`bound` is finite: the range test refuses NaN and ±infinity too)
    if (0.0..=bound).contains(&r) {
        Ok(r)
    } else {
        Err(break_rate_error(f, r))
    }
}

#[cold]
fn break_rate_error<F: FragmentationKernel + ?Sized>(f: &F, r: f64) -> Error {
    match f.sup_rate() {
        Some(sup) if r.is_finite() && r > 0.0 => Error::BoundExceeded {
            name: "fragmentation supremum (sup_rate)",
            rate: r,
            bound: sup,
        },
        _ => Error::InvalidRate {
            name: "fragmentation rate",
            value: r,
        },
    }
}

/// A fragmentation kernel given by its total mass-flow rate and piece distribution.
pub trait FragmentationKernel {
    /// Total rate `Ḟ(x)` at which a particle of size x breaks (mass-flow view).
    fn total_rate(&self, x: f64) -> f64;

    /// The inverse `F̂_x⁻¹(u)`, `u ∈ [0, 1)`, of the size-biased piece distribution: the
    /// size kept by the followed mass after a break-up of a particle of size x.
    fn inverse_piece(&self, x: f64, u: f64) -> f64;

    /// `sup_x Ḟ(x)` if known (for the stability condition of time-driven schemes).
    fn sup_rate(&self) -> Option<f64> {
        None
    }

    /// True for the kernel that never breaks anything ([`NoFragmentation`]).
    fn is_none(&self) -> bool {
        false
    }

    /// A fingerprint of the kernel and its parameters (for checkpoints); 0 for a
    /// kernel that cannot say.
    fn fingerprint(&self) -> u64 {
        0
    }
}

/// The built-in fragmentation kernels as one type: what the registry's front ends
/// hold (the CLI's `[fragmentation]`, the C ABI's fragmentation handle, Python's).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Fragmentation {
    /// Pure coagulation.
    #[default]
    None,
    /// `F(x, y) = 2λ/(x + y)` (Lécot et al. 2019, §4).
    BinaryUniform(BinaryUniform),
}

impl FragmentationKernel for Fragmentation {
    fn total_rate(&self, x: f64) -> f64 {
        match self {
            Fragmentation::None => 0.0,
            Fragmentation::BinaryUniform(f) => f.total_rate(x),
        }
    }
    fn inverse_piece(&self, x: f64, u: f64) -> f64 {
        match self {
            Fragmentation::None => x,
            Fragmentation::BinaryUniform(f) => f.inverse_piece(x, u),
        }
    }
    fn sup_rate(&self) -> Option<f64> {
        match self {
            Fragmentation::None => Some(0.0),
            Fragmentation::BinaryUniform(f) => f.sup_rate(),
        }
    }
    fn is_none(&self) -> bool {
        matches!(self, Fragmentation::None)
    }
    fn fingerprint(&self) -> u64 {
        match self {
            Fragmentation::None => 0,
            Fragmentation::BinaryUniform(f) => f.fingerprint(),
        }
    }
}

/// No fragmentation: pure coagulation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoFragmentation;

impl FragmentationKernel for NoFragmentation {
    fn total_rate(&self, _x: f64) -> f64 {
        0.0
    }
    fn inverse_piece(&self, x: f64, _u: f64) -> f64 {
        x
    }
    fn sup_rate(&self) -> Option<f64> {
        Some(0.0)
    }
    fn is_none(&self) -> bool {
        true
    }
}

/// Binary break-up into two uniformly distributed pieces at rate λ per particle:
/// `F(x, y) = 2λ / (x + y)` (Lécot §4 uses λ = 1).
///
/// Then `F̃(x, y) = 2λ y / x²`, `Ḟ ≡ λ` and `F̂_x⁻¹(u) = x √u`.
///
/// ```
/// use coagula_core::kernel::{BinaryUniform, FragmentationKernel};
/// let f = BinaryUniform::new(1.0).unwrap();
/// assert_eq!(f.total_rate(5.0), 1.0);
/// assert_eq!(f.inverse_piece(4.0, 0.25), 2.0);
/// assert_eq!(f.rate(1.0, 3.0), 0.5); // 2 / (1 + 3)
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinaryUniform {
    lambda: f64,
}

impl BinaryUniform {
    /// Break-up rate λ > 0 per particle.
    pub fn new(lambda: f64) -> Result<Self> {
        positive("lambda", lambda)?;
        Ok(BinaryUniform { lambda })
    }

    /// The break-up rate λ.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// The kernel itself, `F(x, y) = 2λ / (x + y)`.
    pub fn rate(&self, x: f64, y: f64) -> f64 {
        2.0 * self.lambda / (x + y)
    }
}

impl FragmentationKernel for BinaryUniform {
    fn total_rate(&self, _x: f64) -> f64 {
        self.lambda
    }
    fn inverse_piece(&self, x: f64, u: f64) -> f64 {
        x * libm::sqrt(u)
    }
    fn sup_rate(&self) -> Option<f64> {
        Some(self.lambda)
    }
    fn fingerprint(&self) -> u64 {
        crate::checkpoint::fingerprint([1, self.lambda.to_bits()])
    }
}

/// A fragmentation kernel from two closures: `total_rate(x)` and `inverse_piece(x, u)`,
/// with an optional known supremum of the rate.
#[derive(Clone, Copy)]
pub struct UserFragmentation<R, I> {
    total_rate: R,
    inverse_piece: I,
    sup_rate: Option<f64>,
}

impl<R, I> core::fmt::Debug for UserFragmentation<R, I> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("UserFragmentation")
            .field("sup_rate", &self.sup_rate)
            .finish_non_exhaustive()
    }
}

impl<R: Fn(f64) -> f64, I: Fn(f64, f64) -> f64> UserFragmentation<R, I> {
    /// Builds the kernel; `sup_rate`, if given, must be finite and `≥ 0`.
    pub fn new(total_rate: R, inverse_piece: I, sup_rate: Option<f64>) -> Result<Self> {
        if let Some(s) = sup_rate {
            crate::error::finite("sup_rate", s)?;
            if s < 0.0 {
                return Err(crate::error::Error::OutOfRange {
                    name: "sup_rate",
                    value: s,
                    range: "[0, inf)",
                });
            }
        }
        Ok(UserFragmentation {
            total_rate,
            inverse_piece,
            sup_rate,
        })
    }
}

impl<R: Fn(f64) -> f64, I: Fn(f64, f64) -> f64> FragmentationKernel for UserFragmentation<R, I> {
    fn total_rate(&self, x: f64) -> f64 {
        (self.total_rate)(x)
    }
    fn inverse_piece(&self, x: f64, u: f64) -> f64 {
        (self.inverse_piece)(x, u)
    }
    fn sup_rate(&self) -> Option<f64> {
        self.sup_rate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `F̃(x, y) = (y/x) F(x − y, y)` integrated numerically must give Ḟ, and its CDF
    /// evaluated at `F̂⁻¹(u)` must give back u.
    #[test]
    fn binary_uniform_is_consistent_with_its_kernel() {
        for &lambda in &[1.0, 2.5] {
            let f = BinaryUniform::new(lambda).unwrap();
            for &x in &[1e-6, 0.3, 1.0, 7.0, 1e9] {
                let n = 20_000;
                let h = x / n as f64;
                // midpoint rule for the CDF at several points
                let mut cdf = 0.0;
                let mut checkpoints = [0.1, 0.5, 0.9].into_iter().peekable();
                for i in 0..n {
                    let y = (i as f64 + 0.5) * h;
                    cdf += (y / x) * f.rate(x - y, y) * h;
                    if let Some(&u) = checkpoints.peek() {
                        // compare at the right end of this cell
                        let edge = (i + 1) as f64 * h;
                        let target = f.inverse_piece(x, u);
                        if edge >= target {
                            let got = cdf / f.total_rate(x);
                            assert!((got - u).abs() < 1e-3, "x={x} u={u} cdf={got}");
                            checkpoints.next();
                        }
                    }
                }
                assert!(
                    (cdf - f.total_rate(x)).abs() < 1e-6 * lambda,
                    "x={x}: {cdf}"
                );
            }
        }
    }

    #[test]
    fn bad_rates_are_rejected() {
        assert!(BinaryUniform::new(0.0).is_err());
        assert!(BinaryUniform::new(f64::NAN).is_err());
        assert!(UserFragmentation::new(|_| 1.0, |x, _| x, Some(-1.0)).is_err());
        let u = UserFragmentation::new(|x: f64| x, |x: f64, u: f64| x * u, None).unwrap();
        assert_eq!(u.total_rate(3.0), 3.0);
        assert_eq!(u.inverse_piece(3.0, 0.5), 1.5);
        assert!(NoFragmentation.is_none());
    }
}
