//! Exact solutions of the Smoluchowski equation, the validation targets of
//! every scheme.
//!
//! All but the two exponential starts begin from the monodisperse state `n_1(0) = 1`
//! (`c(x, 0) = δ(x − 1)`), in the rate
//! convention of the library (each unordered pair coagulates at rate `K/V`).
//!
//! | solution | n_k(t) | moments |
//! |---|---|---|
//! | constant K = K0 | `(τ/2)^{k−1} / (1+τ/2)^{k+1}`, τ = K0 t | M0 = 1/(1+τ/2), M2 = 1+τ, M3 = 1+3τ+3τ²/2 |
//! | additive K = x+y | `k^{k−1}/k! T^{k−1} e^{−kT} e^{−t}`, T = 1−e^{−t} | M0 = e^{−t}, M2 = e^{2t}, M3 = 3e^{4t} − 2e^{3t} |
//! | multiplicative (Flory) | `k^{k−2}/k! t^{k−1} e^{−kt}` (t ≤ 1), `k^{k−2}/k! e^{−k}/t` (t > 1) | M0 = 1−t/2 or 1/(2t), M1 = 1 or 1/t, M2 = 1/(1−t), M3 = 1/(1−t)³ |
//! | multiplicative, Marcus–Lushnikov limit | `k^{k−2}/k! t^{k−1} e^{−kt}` for all t | M_m(t) = (t*/t) M_m^{pre}(t*), t* e^{−t*} = t e^{−t} |
//! | coagulation–fragmentation K=1, F=2/(x+y) | — | M0 = 2/(1+e^{−t}), M2 = 3−2e^{−t/3}, M3 = 18−36e^{−t/3}+19e^{−t/2} |
//! | constant K = K0, exponential start c(x,0) = e^{−x} | `c(x,t) = 4/(2+τ)² e^{−2x/(2+τ)}` | M0 = 2/(2+τ), M2 = 2+τ, M3 = 6+6τ+3τ²/2 |
//! | additive K = x+y, exponential start (Golovin) | `(1−T) e^{−(1+T)x} I_1(2x√T)/(x√T)` | M0 = e^{−t}, M2 = 2e^{2t}, M3 = 12e^{4t} − 6e^{3t} |
//!
//! A kernel coefficient b (`K = b K_0`) is [`Exact::with_coefficient`]: time runs b times
//! faster.
//!
//! References: Eibeck & Wagner (2000) eqs. 6.8–6.11; Lécot et al. (2019) §4. The
//! coagulation–fragmentation M0 follows from `M0' = M0 − M0²/2` (every particle breaks at
//! rate 1; pairs merge at rate 1).
//!
//! # Example
//! ```
//! use coagula_core::exact::Exact;
//! let flory = Exact::multiplicative();
//! assert!((flory.gel_mass(2.0).unwrap() - 0.5).abs() < 1e-15);
//! let ml = Exact::marcus_lushnikov();
//! // mass of the sol in the Marcus–Lushnikov limit is t*/t
//! let tstar = coagula_core::exact::dual_time(2.0).unwrap();
//! assert!((ml.moment(1, 2.0).unwrap() - tstar / 2.0).abs() < 1e-14);
//! ```

mod balance;
mod moments;
mod named;
mod sectional;

pub use balance::Balance;
pub use moments::ClosedMoments;
pub use named::NAMES;
pub use sectional::{Books, MAX_PIVOTS, Sectional};

use crate::error::{Error, Result, finite};
use libm::{exp, lgamma, log};

/// An exact solution (see the module docs for the formulas), for a kernel coefficient
/// b ([`with_coefficient`](Exact::with_coefficient)): the solution of `b K` at time t is
/// that of `K` at time `b t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact {
    kind: Kind,
    /// The kernel coefficient b (time runs b times faster).
    rate: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Constant kernel `K = K0`.
    Constant {
        /// The kernel constant.
        k0: f64,
    },
    /// Additive kernel `K = x + y`.
    Additive,
    /// Multiplicative kernel `K = x y`, Flory's post-gel continuation (the limit of the
    /// mass flow algorithm).
    Multiplicative,
    /// Multiplicative kernel, the limit of the Marcus–Lushnikov process (direct
    /// simulation): the pre-gel formula for all t.
    MarcusLushnikov,
    /// Constant kernel `K = 1` with binary uniform fragmentation `F = 2/(x+y)`
    /// (Lécot et al. §4): moments only.
    CoagulationFragmentation,
    /// Constant kernel `K = K0` from the exponential start `c(x, 0) = e^{−x}`.
    ConstantExponential {
        /// The kernel constant.
        k0: f64,
    },
    /// Golovin's additive kernel `K = x + y` from the exponential start.
    AdditiveExponential,
    /// The constant kernel with a source, dilution and linear growth: moments only.
    Balance(Balance),
}

fn check_time(t: f64) -> Result<f64> {
    finite("t", t)?;
    if t < 0.0 {
        return Err(Error::OutOfRange {
            name: "t",
            value: t,
            range: "[0, inf)",
        });
    }
    Ok(t)
}

/// The dual time `t*` of the Marcus–Lushnikov limit: for `t > 1` the root in `(0, 1)` of
/// `t* e^{−t*} = t e^{−t}`; for `t ≤ 1`, `t* = t`.
pub fn dual_time(t: f64) -> Result<f64> {
    check_time(t)?;
    if t <= 1.0 {
        return Ok(t);
    }
    // In v = ln t*: f(v) = v − e^v − (ln t − t) is increasing on v < 0. Bisect on
    // [ln(MIN_POSITIVE), 0] (t* can be as small as 1e-300 for t ≈ 700), then Newton.
    let target = log(t) - t;
    let f = |v: f64| v - exp(v) - target;
    let (mut lo, mut hi) = (log(f64::MIN_POSITIVE), 0.0);
    if f(lo) > 0.0 {
        // t* would underflow: the sol has vanished to double precision
        return Ok(0.0);
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut v = 0.5 * (lo + hi);
    for _ in 0..3 {
        let d = 1.0 - exp(v);
        if d > 0.0 {
            let next = v - f(v) / d;
            if next < 0.0 {
                v = next;
            }
        }
    }
    let s = exp(v);
    Ok(s)
}

/// `ln(k^{p} / k!)` for integer k ≥ 1.
fn log_power_over_factorial(k: u64, p: f64) -> f64 {
    let kf = k as f64;
    p * log(kf) - lgamma(kf + 1.0)
}

impl Exact {
    /// Constant kernel `K = k0 > 0`.
    pub fn constant(k0: f64) -> Result<Self> {
        crate::error::positive("k0", k0)?;
        Ok(Self::of(Kind::Constant { k0 }))
    }
    /// Additive kernel `K = x + y`.
    pub fn additive() -> Self {
        Self::of(Kind::Additive)
    }
    /// Multiplicative kernel, Flory's solution (gel at t = 1).
    pub fn multiplicative() -> Self {
        Self::of(Kind::Multiplicative)
    }
    /// Multiplicative kernel, Marcus–Lushnikov limit.
    pub fn marcus_lushnikov() -> Self {
        Self::of(Kind::MarcusLushnikov)
    }
    /// Coagulation–fragmentation test of Lécot et al. (K = 1, F = 2/(x+y)).
    pub fn coagulation_fragmentation() -> Self {
        Self::of(Kind::CoagulationFragmentation)
    }
    /// Constant kernel `K = k0 > 0` from the exponential start `c(x, 0) = e^{−x}`
    /// (M0 = M1 = 1, continuous sizes): with τ = k0 t,
    /// `c(x, t) = 4/(2+τ)² exp(−2x/(2+τ))`, `M_m = Γ(m+1) ((2+τ)/2)^{m−1}`
    /// (M0 = 2/(2+τ), M2 = 2+τ, M3 = 6+6τ+3τ²/2).
    ///
    /// ```
    /// use coagula_core::exact::Exact;
    /// let e = Exact::constant_exponential(1.0).unwrap();
    /// assert!((e.moment(2, 3.0).unwrap() - 5.0).abs() < 1e-14);
    /// assert!((e.density(0.0, 2.0).unwrap() - 0.25).abs() < 1e-15);
    /// ```
    pub fn constant_exponential(k0: f64) -> Result<Self> {
        crate::error::positive("k0", k0)?;
        Ok(Self::of(Kind::ConstantExponential { k0 }))
    }
    /// Golovin's solution for the additive kernel `K = x + y` from the exponential start
    /// `c(x, 0) = e^{−x}` (Golovin 1963; Scott 1968, eq. 2.19): with `T = 1 − e^{−t}`,
    /// `c(x, t) = (1 − T) e^{−(1+T) x} I_1(2x√T) / (x√T)`; M0 = e^{−t}, M1 = 1,
    /// M2 = 2 e^{2t}, M3 = 12 e^{4t} − 6 e^{3t}. A coefficient b (`K = b (x + y)`) is
    /// [`with_coefficient`](Self::with_coefficient).
    ///
    /// ```
    /// use coagula_core::exact::Exact;
    /// let g = Exact::additive_exponential().with_coefficient(1.5).unwrap();
    /// // K = 1.5 (x + y): M0 = e^{-1.5 t}
    /// assert!((g.moment(0, 2.0).unwrap() - (-3.0f64).exp()).abs() < 1e-15);
    /// ```
    pub fn additive_exponential() -> Self {
        Self::of(Kind::AdditiveExponential)
    }

    fn of(kind: Kind) -> Self {
        Exact { kind, rate: 1.0 }
    }

    /// The constant kernel `K = k0` from moments `start` (M0, M1, M2) with a source of
    /// `source` particles of size `size` per unit volume and time, removal at `removal`
    /// per particle and growth `dx/dt = growth · x`: M0, M1 and (without growth) M2
    /// (see [`Balance`]); moments only.
    pub fn balance(b: Balance) -> Self {
        Self::of(Kind::Balance(b))
    }

    /// The solution for the kernel `b K` (b > 0 finite; coefficients compose): every
    /// quantity at time t is the original's at `b t` (the equation's right-hand side
    /// scales with b). The coagulation–fragmentation test refuses a coefficient (its
    /// fragmentation rate would not scale with it).
    pub fn with_coefficient(mut self, b: f64) -> Result<Self> {
        crate::error::positive("coefficient", b)?;
        if matches!(self.kind, Kind::CoagulationFragmentation | Kind::Balance(_)) {
            return Err(Error::Unsupported {
                what: "a kernel coefficient for the coagulation-fragmentation test or a balance with processes (give the rates themselves)",
            });
        }
        let r = self.rate * b;
        if !(r.is_finite() && r > 0.0) {
            return Err(Error::OutOfRange {
                name: "coefficient",
                value: b,
                range: "a product with the solution's coefficient in (0, inf)",
            });
        }
        self.rate = r;
        Ok(self)
    }

    /// Whether the solution is of continuous sizes (the exponential starts: use
    /// [`density`](Self::density)) rather than integer ones
    /// ([`number_density`](Self::number_density)).
    pub fn is_continuous(&self) -> bool {
        matches!(
            self.kind,
            Kind::ConstantExponential { .. } | Kind::AdditiveExponential
        )
    }

    /// The gelation time, if the solution gels.
    pub fn gel_time(&self) -> Option<f64> {
        match self.kind {
            Kind::Multiplicative | Kind::MarcusLushnikov => Some(1.0 / self.rate),
            _ => None,
        }
    }

    /// The time of the unit-coefficient solution.
    fn scaled(&self, t: f64) -> Result<f64> {
        check_time(t)?;
        Ok(t * self.rate)
    }

    /// Density `c(x, t)` of a continuous-size solution (the exponential starts) at size
    /// x ≥ 0 (at 0 its limit). Errors for x < 0 or not finite, a bad t, or a solution of
    /// integer sizes.
    pub fn density(&self, x: f64, t: f64) -> Result<f64> {
        let t = self.scaled(t)?;
        finite("x", x)?;
        if x < 0.0 {
            return Err(Error::OutOfRange {
                name: "x",
                value: x,
                range: "[0, inf)",
            });
        }
        Ok(match self.kind {
            Kind::ConstantExponential { k0 } => {
                let s = 1.0 + 0.5 * k0 * t;
                exp(-x / s) / (s * s)
            }
            Kind::AdditiveExponential => {
                let tt = -libm::expm1(-t);
                if tt == 0.0 {
                    exp(-x)
                } else if x == 0.0 {
                    // I1(z)/(x√T) → 1 as x → 0, and 1 − T = e^{−t}
                    exp(-t)
                } else {
                    // (1−T) e^{−(1+T)x} I1(z)/(x√T), z = 2x√T, with I1 scaled by e^{−z}:
                    // the exponent is −(1−√T)² x
                    let r = libm::sqrt(tt);
                    let z = 2.0 * x * r;
                    let d = 1.0 - r;
                    exp(-t) * exp(-d * d * x) * bessel_i1e(z) / (x * r)
                }
            }
            _ => {
                return Err(Error::Unsupported {
                    what: "c(x, t) of a solution of integer sizes (use the number density n_k)",
                });
            }
        })
    }

    /// Concentration `n_k(t)` of size k ≥ 1. Errors for k = 0, a bad t, or a solution
    /// known only through its moments.
    pub fn number_density(&self, k: u64, t: f64) -> Result<f64> {
        let t = self.scaled(t)?;
        if k == 0 {
            return Err(Error::OutOfRange {
                name: "k",
                value: 0.0,
                range: "1, 2, ...",
            });
        }
        let km1 = (k - 1) as f64;
        Ok(match self.kind {
            Kind::Constant { k0 } => {
                let half = 0.5 * k0 * t;
                if k == 1 {
                    1.0 / ((1.0 + half) * (1.0 + half))
                } else if half == 0.0 {
                    0.0
                } else {
                    exp(km1 * log(half) - (k as f64 + 1.0) * libm::log1p(half))
                }
            }
            Kind::Additive => {
                let tau = -libm::expm1(-t);
                if k == 1 {
                    exp(-tau - t)
                } else if tau == 0.0 {
                    0.0
                } else {
                    exp(log_power_over_factorial(k, km1) + km1 * log(tau) - k as f64 * tau - t)
                }
            }
            Kind::Multiplicative if t > 1.0 => {
                exp(log_power_over_factorial(k, k as f64 - 2.0) - k as f64) / t
            }
            Kind::Multiplicative | Kind::MarcusLushnikov => {
                if k == 1 {
                    exp(-t)
                } else if t == 0.0 {
                    0.0
                } else {
                    exp(log_power_over_factorial(k, k as f64 - 2.0) + km1 * log(t) - k as f64 * t)
                }
            }
            Kind::Balance(_) => {
                return Err(Error::Unsupported {
                    what: "n_k(t) with a source, removal or growth (moments only)",
                });
            }
            Kind::CoagulationFragmentation => {
                return Err(Error::Unsupported {
                    what: "n_k(t) of the coagulation-fragmentation test (moments only)",
                });
            }
            Kind::ConstantExponential { .. } | Kind::AdditiveExponential => {
                return Err(Error::Unsupported {
                    what: "n_k(t) of a continuous-size solution (use the density c(x, t))",
                });
            }
        })
    }

    /// The moment `M_m(t) = Σ k^m n_k(t)` for m = 0..=3 (infinite where it diverges,
    /// e.g. M2 of Flory's solution for t ≥ 1). Other orders are
    /// [`Error::Unsupported`].
    pub fn moment(&self, m: u32, t: f64) -> Result<f64> {
        let t = self.scaled(t)?;
        if m > 3 {
            return Err(Error::Unsupported {
                what: "exact moments of order above 3",
            });
        }
        Ok(match self.kind {
            Kind::Constant { k0 } => {
                let tau = k0 * t;
                [
                    1.0 / (1.0 + 0.5 * tau),
                    1.0,
                    1.0 + tau,
                    1.0 + 3.0 * tau + 1.5 * tau * tau,
                ][m as usize]
            }
            Kind::Additive => [
                exp(-t),
                1.0,
                exp(2.0 * t),
                // e^{3t}(3e^t − 2): no inf − inf (NaN) where e^{4t} overflows
                exp(3.0 * t) * (3.0 * exp(t) - 2.0),
            ][m as usize],
            Kind::Multiplicative => {
                if t < 1.0 {
                    pre_gel_multiplicative(m, t)
                } else {
                    [0.5 / t, 1.0 / t, f64::INFINITY, f64::INFINITY][m as usize]
                }
            }
            Kind::MarcusLushnikov => {
                if t <= 1.0 {
                    if t == 1.0 && m >= 2 {
                        f64::INFINITY
                    } else {
                        pre_gel_multiplicative(m, t)
                    }
                } else {
                    let s = dual_time(t)?;
                    s / t * pre_gel_multiplicative(m, s)
                }
            }
            Kind::CoagulationFragmentation => [
                2.0 / (1.0 + exp(-t)),
                1.0,
                3.0 - 2.0 * exp(-t / 3.0),
                18.0 - 36.0 * exp(-t / 3.0) + 19.0 * exp(-t / 2.0),
            ][m as usize],
            Kind::ConstantExponential { k0 } => {
                let s = 1.0 + 0.5 * k0 * t;
                [1.0 / s, 1.0, 2.0 * s, 6.0 * s * s][m as usize]
            }
            Kind::AdditiveExponential => [
                exp(-t),
                1.0,
                2.0 * exp(2.0 * t),
                6.0 * exp(3.0 * t) * (2.0 * exp(t) - 1.0),
            ][m as usize],
            Kind::Balance(b) => b.moment(m, t)?,
        })
    }

    /// Gel mass at time t: `1 − 1/t` (Flory, t > 1), `1 − t*/t` (Marcus–Lushnikov),
    /// 0 for non-gelling solutions.
    pub fn gel_mass(&self, t: f64) -> Result<f64> {
        let t = self.scaled(t)?;
        Ok(match self.kind {
            Kind::Multiplicative if t > 1.0 => 1.0 - 1.0 / t,
            Kind::MarcusLushnikov if t > 1.0 => 1.0 - dual_time(t)? / t,
            _ => 0.0,
        })
    }
}

/// Pre-gel moments of the multiplicative kernel, t < 1.
fn pre_gel_multiplicative(m: u32, t: f64) -> f64 {
    let d = 1.0 - t;
    [1.0 - 0.5 * t, 1.0, 1.0 / d, 1.0 / (d * d * d)][m as usize]
}

/// `e^{−z} I_1(z)` for z ≥ 0: the power series `Σ (z/2)^{2k+1} / (k! (k+1)!)` (positive
/// terms, no cancellation) up to z = 40, Hankel's asymptotic series above
/// (`I_1(z) ≈ e^z/√(2πz) Σ (−1)^k a_k(1) z^{−k}`, whose terms fall below 1e-17 long
/// before they turn), so the relative error is a few ulp everywhere.
pub(crate) fn bessel_i1e(z: f64) -> f64 {
    if z.is_nan() || z <= 0.0 {
        return 0.0;
    }
    if z <= 40.0 {
        let h = 0.5 * z;
        let q = h * h;
        let mut term = h;
        let mut sum = term;
        let mut k = 0.0;
        while term > 1e-17 * sum {
            k += 1.0;
            term *= q / (k * (k + 1.0));
            sum += term;
        }
        sum * exp(-z)
    } else {
        // a_k(ν) = Π_{j=1..k} (4ν² − (2j−1)²) / (k! 8^k), ν = 1
        let mut term = 1.0;
        let mut sum = 1.0;
        for j in 1..30 {
            let jf = f64::from(j);
            let odd = 2.0 * jf - 1.0;
            term *= -(4.0 - odd * odd) / (8.0 * jf * z);
            sum += term;
            if term.abs() < 1e-17 * sum {
                break;
            }
        }
        sum / libm::sqrt(2.0 * core::f64::consts::PI * z)
    }
}

#[cfg(test)]
mod tests;
