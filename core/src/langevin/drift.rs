//! Velocity drifts `b(t, x, u)`: closures, linear friction, shear, and the built-in
//! drifts the C ABI and Python name (Maftei et al. 2016).

use super::*;

/// The velocity drift `b(t, x, u)` of a `D`-dimensional Langevin model.
pub trait Drift<const D: usize> {
    /// The drift at time `t`, position `x`, velocity `u`.
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D];
}

impl<const D: usize, T: Drift<D> + ?Sized> Drift<D> for &T {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        (**self).drift(t, x, u)
    }
}

/// A one-dimensional drift from a closure `|t, x, u| b`.
#[derive(Clone, Copy, Debug)]
pub struct Scalar<F>(pub F);

impl<F: Fn(f64, f64, f64) -> f64> Drift<1> for Scalar<F> {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; 1], u: &[f64; 1]) -> [f64; 1] {
        [(self.0)(t, x[0], u[0])]
    }
}

/// A `D`-dimensional drift from a closure `|t, &x, &u| b`.
#[derive(Clone, Copy, Debug)]
pub struct Field<F>(pub F);

impl<const D: usize, F: Fn(f64, &[f64; D], &[f64; D]) -> [f64; D]> Drift<D> for Field<F> {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        (self.0)(t, x, u)
    }
}

/// Linear friction `b = −u / τ`: the velocity is an Ornstein–Uhlenbeck process and, with
/// `σ = √(2 D) / τ`, the position a Brownian motion of diffusivity D at times ≫ τ
/// (the Brownian limit of [`kernel`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// The relaxation rate `1/τ`.
    pub rate: f64,
}

impl<const D: usize> Drift<D> for Friction {
    #[inline(always)]
    fn drift(&self, _t: f64, _x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        core::array::from_fn(|k| -self.rate * u[k])
    }
}

/// Relaxation towards a simple shear flow, `b = −(u − (γ̇ x₂, 0, …)) / τ`: the relative
/// motion of two particles of relaxation time τ in the flow `u_f = (γ̇ y, 0, 0)`
/// (`D ≥ 2`; in one dimension it is [`Friction`]). With `σ = 0` and τ → 0 the first-hit
/// kernel tends to Smoluchowski's orthokinetic `(4/3) γ̇ R³` (3-D).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shear {
    /// The relaxation rate `1/τ`.
    pub rate: f64,
    /// The shear rate γ̇.
    pub shear: f64,
}

impl<const D: usize> Drift<D> for Shear {
    #[inline(always)]
    fn drift(&self, _t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        core::array::from_fn(|k| {
            let fluid = if k == 0 && D > 1 {
                self.shear * x[1]
            } else {
                0.0
            };
            -self.rate * (u[k] - fluid)
        })
    }
}

/// The built-in drifts as one type (what the C ABI and Python name): none, linear
/// friction, or the test problem of Maftei et al. (2016, one-dimensional: the drift
/// `cos(2πx) + cos(2πu)/2` of [`paper::PaperDrift`], on the first component).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BuiltinDrift {
    /// `b = 0`.
    Zero,
    /// [`Friction`].
    Friction(Friction),
    /// [`paper::PaperDrift`] (dimension 1).
    Paper,
}

impl BuiltinDrift {
    /// Checks the drift for dimension `d`: a friction rate finite and ≥ 0, the paper's
    /// drift in one dimension only.
    pub fn check(&self, d: usize) -> Result<()> {
        match *self {
            BuiltinDrift::Friction(f) if !(f.rate.is_finite() && f.rate >= 0.0) => {
                Err(Error::OutOfRange {
                    name: "friction rate",
                    value: f.rate,
                    range: "[0, inf)",
                })
            }
            BuiltinDrift::Paper if d != 1 => Err(Error::Unsupported {
                what: "the drift of Maftei et al. 2016 is one-dimensional",
            }),
            _ => Ok(()),
        }
    }

    /// A fingerprint (for checkpoints).
    pub fn fingerprint(&self) -> u64 {
        match *self {
            BuiltinDrift::Zero => 0,
            BuiltinDrift::Friction(f) => crate::checkpoint::fingerprint([1, f.rate.to_bits()]),
            BuiltinDrift::Paper => 2,
        }
    }
}

impl<const D: usize> Drift<D> for BuiltinDrift {
    #[inline(always)]
    fn drift(&self, t: f64, x: &[f64; D], u: &[f64; D]) -> [f64; D] {
        match self {
            BuiltinDrift::Zero => [0.0; D],
            BuiltinDrift::Friction(f) => f.drift(t, x, u),
            BuiltinDrift::Paper => core::array::from_fn(|k| {
                if k == 0 {
                    paper::cos_2pi(x[0]) + 0.5 * paper::cos_2pi(u[0])
                } else {
                    0.0
                }
            }),
        }
    }
}
