//! Estimates from replicas: Richardson–Romberg extrapolation and the exact moments
//! of the Euler scheme (Maftei et al. 2016).

use super::*;

/// A Monte Carlo estimate: mean, standard error and the number of samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The estimate.
    pub mean: f64,
    /// Its standard error.
    pub std_error: f64,
    /// Samples (trajectories) behind it.
    pub count: u64,
}

impl Estimate {
    /// From replica statistics.
    pub fn of(r: &Replicas) -> Self {
        Estimate {
            mean: r.mean(),
            std_error: r.std_error(),
            count: r.count(),
        }
    }

    /// The two-sided 95% confidence interval (normal quantile: the counts are large).
    pub fn ci95(&self) -> (f64, f64) {
        let h = 1.959_963_984_540_054 * self.std_error;
        (self.mean - h, self.mean + h)
    }
}

/// Richardson–Romberg extrapolation `2 E f(X^{h/2}) − E f(X^h)` of two independent
/// runs, the coarse one at step h and the fine one at h/2, with its standard error
/// `√(4 SE_fine² + SE_coarse²)`: the `C h` term of the bias cancels.
pub fn richardson_romberg(coarse: &Replicas, fine: &Replicas) -> Estimate {
    let (c, f) = (Estimate::of(coarse), Estimate::of(fine));
    Estimate {
        mean: 2.0 * f.mean - c.mean,
        std_error: libm::sqrt(4.0 * f.std_error * f.std_error + c.std_error * c.std_error),
        count: c.count + f.count,
    }
}

/// Exact mean and covariance `[E x, E u, Var x, Cov(x, u), Var u]` of the scheme away
/// from walls with the linear drift `b = −γ u` after `steps` steps of length h from
/// `(x0, u0)`: `x' = x + h u`, `u' = (1 − γh) u + σ √h Z` (one dimension). The scheme's
/// own moments, not the SDE's: a test against them has no time-step bias.
pub fn euler_moments(x0: f64, u0: f64, gamma: f64, sigma: f64, h: f64, steps: u64) -> [f64; 5] {
    let (mut mx, mut mu) = (x0, u0);
    let (mut vxx, mut vxu, mut vuu) = (0.0, 0.0, 0.0);
    let a = 1.0 - gamma * h;
    for _ in 0..steps {
        (vxx, vxu, vuu) = (
            vxx + 2.0 * h * vxu + h * h * vuu,
            a * (vxu + h * vuu),
            a * a * vuu + sigma * sigma * h,
        );
        (mx, mu) = (mx + h * mu, a * mu);
    }
    [mx, mu, vxx, vxu, vuu]
}

/// `E |Y|` for `Y ~ N(m, v)`: with `b = 0` a specular wall at 0 folds the free motion,
/// so this is `E X_T` of the reflected scheme (`m`, `v` from [`euler_moments`]).
pub fn folded_normal_mean(m: f64, v: f64) -> f64 {
    let s = libm::sqrt(v);
    s * libm::sqrt(2.0 / core::f64::consts::PI) * libm::exp(-m * m / (2.0 * v))
        + m * libm::erf(m / (s * core::f64::consts::SQRT_2))
}
