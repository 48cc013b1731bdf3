//! Exact solutions of the Smoluchowski equation (SPEC §3), the validation targets of
//! every scheme.
//!
//! All start from the monodisperse state `n_1(0) = 1` (`c(x, 0) = δ(x − 1)`), in the rate
//! convention of SPEC §1 (each unordered pair coagulates at rate `K/V`).
//!
//! | solution | n_k(t) | moments |
//! |---|---|---|
//! | constant K = K0 | `(τ/2)^{k−1} / (1+τ/2)^{k+1}`, τ = K0 t | M0 = 1/(1+τ/2), M2 = 1+τ, M3 = 1+3τ+3τ²/2 |
//! | additive K = x+y | `k^{k−1}/k! T^{k−1} e^{−kT} e^{−t}`, T = 1−e^{−t} | M0 = e^{−t}, M2 = e^{2t}, M3 = 3e^{4t} − 2e^{3t} |
//! | multiplicative (Flory) | `k^{k−2}/k! t^{k−1} e^{−kt}` (t ≤ 1), `k^{k−2}/k! e^{−k}/t` (t > 1) | M0 = 1−t/2 or 1/(2t), M1 = 1 or 1/t, M2 = 1/(1−t), M3 = 1/(1−t)³ |
//! | multiplicative, Marcus–Lushnikov limit | `k^{k−2}/k! t^{k−1} e^{−kt}` for all t | M_m(t) = (t*/t) M_m^{pre}(t*), t* e^{−t*} = t e^{−t} |
//! | coagulation–fragmentation K=1, F=2/(x+y) | — | M0 = 2/(1+e^{−t}), M2 = 3−2e^{−t/3}, M3 = 18−36e^{−t/3}+19e^{−t/2} |
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

use crate::error::{Error, Result, finite};
use libm::{exp, lgamma, log};

/// An exact solution (see the module docs for the formulas).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Exact {
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
        Ok(Exact::Constant { k0 })
    }
    /// Additive kernel `K = x + y`.
    pub fn additive() -> Self {
        Exact::Additive
    }
    /// Multiplicative kernel, Flory's solution (gel at t = 1).
    pub fn multiplicative() -> Self {
        Exact::Multiplicative
    }
    /// Multiplicative kernel, Marcus–Lushnikov limit.
    pub fn marcus_lushnikov() -> Self {
        Exact::MarcusLushnikov
    }
    /// Coagulation–fragmentation test of Lécot et al. (K = 1, F = 2/(x+y)).
    pub fn coagulation_fragmentation() -> Self {
        Exact::CoagulationFragmentation
    }

    /// The gelation time, if the solution gels.
    pub fn gel_time(&self) -> Option<f64> {
        match self {
            Exact::Multiplicative | Exact::MarcusLushnikov => Some(1.0),
            _ => None,
        }
    }

    /// Concentration `n_k(t)` of size k ≥ 1. Errors for k = 0, a bad t, or a solution
    /// known only through its moments.
    pub fn number_density(&self, k: u64, t: f64) -> Result<f64> {
        check_time(t)?;
        if k == 0 {
            return Err(Error::OutOfRange {
                name: "k",
                value: 0.0,
                range: "1, 2, ...",
            });
        }
        let km1 = (k - 1) as f64;
        Ok(match *self {
            Exact::Constant { k0 } => {
                let half = 0.5 * k0 * t;
                if k == 1 {
                    1.0 / ((1.0 + half) * (1.0 + half))
                } else if half == 0.0 {
                    0.0
                } else {
                    exp(km1 * log(half) - (k as f64 + 1.0) * libm::log1p(half))
                }
            }
            Exact::Additive => {
                let tau = -libm::expm1(-t);
                if k == 1 {
                    exp(-tau - t)
                } else if tau == 0.0 {
                    0.0
                } else {
                    exp(log_power_over_factorial(k, km1) + km1 * log(tau) - k as f64 * tau - t)
                }
            }
            Exact::Multiplicative if t > 1.0 => {
                exp(log_power_over_factorial(k, k as f64 - 2.0) - k as f64) / t
            }
            Exact::Multiplicative | Exact::MarcusLushnikov => {
                if k == 1 {
                    exp(-t)
                } else if t == 0.0 {
                    0.0
                } else {
                    exp(log_power_over_factorial(k, k as f64 - 2.0) + km1 * log(t) - k as f64 * t)
                }
            }
            Exact::CoagulationFragmentation => {
                return Err(Error::Unsupported {
                    what: "n_k(t) of the coagulation-fragmentation test (moments only)",
                });
            }
        })
    }

    /// The moment `M_m(t) = Σ k^m n_k(t)` for m = 0..=3 (infinite where it diverges,
    /// e.g. M2 of Flory's solution for t ≥ 1). Other orders are
    /// [`Error::Unsupported`].
    pub fn moment(&self, m: u32, t: f64) -> Result<f64> {
        check_time(t)?;
        if m > 3 {
            return Err(Error::Unsupported {
                what: "exact moments of order above 3",
            });
        }
        Ok(match *self {
            Exact::Constant { k0 } => {
                let tau = k0 * t;
                [
                    1.0 / (1.0 + 0.5 * tau),
                    1.0,
                    1.0 + tau,
                    1.0 + 3.0 * tau + 1.5 * tau * tau,
                ][m as usize]
            }
            Exact::Additive => [
                exp(-t),
                1.0,
                exp(2.0 * t),
                3.0 * exp(4.0 * t) - 2.0 * exp(3.0 * t),
            ][m as usize],
            Exact::Multiplicative => {
                if t < 1.0 {
                    pre_gel_multiplicative(m, t)
                } else {
                    [0.5 / t, 1.0 / t, f64::INFINITY, f64::INFINITY][m as usize]
                }
            }
            Exact::MarcusLushnikov => {
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
            Exact::CoagulationFragmentation => [
                2.0 / (1.0 + exp(-t)),
                1.0,
                3.0 - 2.0 * exp(-t / 3.0),
                18.0 - 36.0 * exp(-t / 3.0) + 19.0 * exp(-t / 2.0),
            ][m as usize],
        })
    }

    /// Gel mass at time t: `1 − 1/t` (Flory, t > 1), `1 − t*/t` (Marcus–Lushnikov),
    /// 0 for non-gelling solutions.
    pub fn gel_mass(&self, t: f64) -> Result<f64> {
        check_time(t)?;
        Ok(match self {
            Exact::Multiplicative if t > 1.0 => 1.0 - 1.0 / t,
            Exact::MarcusLushnikov if t > 1.0 => 1.0 - dual_time(t)? / t,
            _ => 0.0,
        })
    }
}

/// Pre-gel moments of the multiplicative kernel, t < 1.
fn pre_gel_multiplicative(m: u32, t: f64) -> f64 {
    let d = 1.0 - t;
    [1.0 - 0.5 * t, 1.0, 1.0 / d, 1.0 / (d * d * d)][m as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Σ k^m n_k summed until the terms are negligible (with a k^{-3/2}-tail estimate
    /// for post-gel Flory, whose terms decay as a power law).
    fn summed_moment(e: &Exact, m: i32, t: f64, kmax: u64) -> f64 {
        let mut s = 0.0;
        for k in 1..=kmax {
            s += libm::pow(k as f64, m as f64) * e.number_density(k, t).unwrap();
        }
        s
    }

    #[test]
    fn moments_agree_with_summed_densities() {
        let cases: [(Exact, f64, u64); 7] = [
            (Exact::constant(1.0).unwrap(), 2.0, 4000),
            (Exact::constant(2.5).unwrap(), 0.7, 4000),
            (Exact::additive(), 0.5, 4000),
            (Exact::additive(), 1.5, 200_000),
            (Exact::multiplicative(), 0.5, 4000),
            (Exact::marcus_lushnikov(), 2.0, 4000),
            (Exact::marcus_lushnikov(), 4.0, 4000),
        ];
        for (e, t, kmax) in cases {
            for m in 0..=3 {
                let exact = e.moment(m, t).unwrap();
                let sum = summed_moment(&e, m as i32, t, kmax);
                assert!(
                    (sum - exact).abs() <= 1e-9 * exact,
                    "{e:?} t={t} M{m}: sum {sum} vs closed form {exact}"
                );
            }
        }
    }

    #[test]
    fn flory_post_gel_moments_agree_with_sums_and_tail() {
        // n_k ~ e^{-k} k^{k-2}/k! / t ~ k^{-5/2} / (t √(2π)): the tails of M0 and M1
        // beyond K are ≈ (2/3) K^{-3/2} / (t√(2π)) and 2 K^{-1/2} / (t√(2π)).
        let e = Exact::multiplicative();
        let t = 2.0;
        let kmax = 1_000_000u64;
        let c = 1.0 / (t * libm::sqrt(2.0 * core::f64::consts::PI));
        let kf = kmax as f64 + 0.5;
        let m0 = summed_moment(&e, 0, t, kmax) + c * (2.0 / 3.0) * libm::pow(kf, -1.5);
        let m1 = summed_moment(&e, 1, t, kmax) + c * 2.0 * libm::pow(kf, -0.5);
        assert!((m0 - e.moment(0, t).unwrap()).abs() < 1e-8, "M0 {m0}");
        assert!((m1 - e.moment(1, t).unwrap()).abs() < 1e-6, "M1 {m1}");
        assert_eq!(e.moment(2, t).unwrap(), f64::INFINITY);
    }

    /// The densities satisfy the discrete Smoluchowski equation: compare a central
    /// difference of n_k with the right-hand side. The gain sum is finite; the loss
    /// `n_k Σ_j K(k, j) n_j` is written through the moments of the sol plus, after
    /// gelation, the mass `g` of a gel that still absorbs sol particles
    /// (`K(k, gel) n_gel = k g` for K = x y).
    #[test]
    fn densities_solve_smoluchowski() {
        type K = fn(f64, f64) -> f64;
        // (solution, kernel, t, loss rate per particle of size k from M0, M1, gel)
        type Loss = fn(f64, f64, f64, f64) -> f64;
        let cases: [(Exact, K, Loss, f64, f64); 6] = [
            (
                Exact::constant(1.0).unwrap(),
                |_, _| 1.0,
                |_, m0, _, _| m0,
                0.8,
                0.0,
            ),
            (
                Exact::constant(2.0).unwrap(),
                |_, _| 2.0,
                |_, m0, _, _| 2.0 * m0,
                3.0,
                0.0,
            ),
            (
                Exact::additive(),
                |x, y| x + y,
                |k, m0, m1, _| k * m0 + m1,
                0.6,
                0.0,
            ),
            (
                Exact::multiplicative(),
                |x, y| x * y,
                |k, _, m1, g| k * (m1 + g),
                0.5,
                0.0,
            ),
            // Flory after gelation: the sol loses only to the sol (no gel term)
            (
                Exact::multiplicative(),
                |x, y| x * y,
                |k, _, m1, g| k * (m1 + g),
                2.5,
                0.0,
            ),
            // Marcus–Lushnikov limit: the gel of mass 1 − t*/t absorbs sol particles
            (
                Exact::marcus_lushnikov(),
                |x, y| x * y,
                |k, _, m1, g| k * (m1 + g),
                2.5,
                1.0 - dual_time(2.5).unwrap() / 2.5,
            ),
        ];
        for (e, kern, loss, t, gel) in cases {
            let n = |j: u64| e.number_density(j, t).unwrap();
            let (m0, m1) = (e.moment(0, t).unwrap(), e.moment(1, t).unwrap());
            for k in 1..=25u64 {
                let h = 1e-5;
                let dn = (e.number_density(k, t + h).unwrap()
                    - e.number_density(k, t - h).unwrap())
                    / (2.0 * h);
                let mut gain = 0.0;
                for i in 1..k {
                    gain += 0.5 * kern(i as f64, (k - i) as f64) * n(i) * n(k - i);
                }
                let rhs = gain - n(k) * loss(k as f64, m0, m1, gel);
                let scale = n(k) * (1.0 + k as f64);
                assert!(
                    (dn - rhs).abs() <= 1e-6 * scale,
                    "{e:?} t={t} k={k}: dn/dt {dn} vs rhs {rhs}"
                );
            }
        }
    }

    /// The moments of the coagulation–fragmentation test solve their own ODEs, derived
    /// from the equation: M0' = M0 − M0²/2, M2' = M1² − M2/3, M3' = 3 M1 M2 − M3/2.
    #[test]
    fn coagulation_fragmentation_moments_solve_their_odes() {
        let e = Exact::coagulation_fragmentation();
        for &t in &[0.0, 0.01, 0.3, 1.0, 5.0, 40.0] {
            let m = |k, t: f64| e.moment(k, t.max(0.0)).unwrap();
            let h = 1e-5;
            let d = |k| (m(k, t + h) - m(k, t - h)) / (2.0 * h);
            if t > 0.0 {
                assert!((d(0) - (m(0, t) - 0.5 * m(0, t) * m(0, t))).abs() < 1e-8);
                assert!((d(2) - (1.0 - m(2, t) / 3.0)).abs() < 1e-8);
                assert!((d(3) - (3.0 * m(2, t) - 0.5 * m(3, t))).abs() < 1e-7);
            }
        }
        for k in 0..=3 {
            assert!(
                (e.moment(k, 0.0).unwrap() - 1.0).abs() < 1e-15,
                "M{k}(0) = 1"
            );
        }
        assert!(e.number_density(1, 1.0).is_err());
    }

    /// Moment ODEs of the pure coagulation solutions (independent of the summation).
    #[test]
    fn coagulation_moments_solve_their_odes() {
        let h = 1e-5;
        let cst = Exact::constant(1.5).unwrap();
        let add = Exact::additive();
        let mul = Exact::multiplicative();
        for &t in &[0.2, 0.5, 0.9] {
            let d = |e: &Exact, k| {
                (e.moment(k, t + h).unwrap() - e.moment(k, t - h).unwrap()) / (2.0 * h)
            };
            let m = |e: &Exact, k| e.moment(k, t).unwrap();
            // constant: M0' = −K0 M0²/2, M2' = K0 M1², M3' = 3 K0 M1 M2
            assert!((d(&cst, 0) + 0.75 * m(&cst, 0) * m(&cst, 0)).abs() < 1e-8);
            assert!((d(&cst, 2) - 1.5).abs() < 1e-8);
            assert!((d(&cst, 3) - 4.5 * m(&cst, 2)).abs() < 1e-7);
            // additive: M0' = −M0 M1, M2' = 2 M1 M2, M3' = 3 (M1 M3 + M2²)
            assert!((d(&add, 0) + m(&add, 0)).abs() < 1e-8);
            assert!((d(&add, 2) - 2.0 * m(&add, 2)).abs() < 1e-7);
            assert!((d(&add, 3) - 3.0 * (m(&add, 3) + m(&add, 2) * m(&add, 2))).abs() < 1e-6);
            // multiplicative (pre-gel): M0' = −M1²/2, M2' = M2², M3' = 3 M2 M3
            assert!((d(&mul, 0) + 0.5).abs() < 1e-8);
            assert!((d(&mul, 2) - m(&mul, 2) * m(&mul, 2)).abs() < 1e-5);
            assert!((d(&mul, 3) - 3.0 * m(&mul, 2) * m(&mul, 3)).abs() < 1e-3 * m(&mul, 3));
        }
    }

    #[test]
    fn dual_time_solves_its_equation() {
        for &t in &[1.0001, 1.5, 2.0, 5.0, 30.0, 700.0] {
            let s = dual_time(t).unwrap();
            assert!(s > 0.0 && s < 1.0);
            let lhs = log(s) - s;
            let rhs = log(t) - t;
            assert!(
                (lhs - rhs).abs() <= 1e-13 * rhs.abs().max(1.0),
                "t={t} t*={s}"
            );
        }
        assert_eq!(dual_time(0.5).unwrap(), 0.5);
        assert!(dual_time(-1.0).is_err());
        assert!(dual_time(f64::NAN).is_err());
    }

    #[test]
    fn gel_masses() {
        assert_eq!(Exact::multiplicative().gel_mass(0.5).unwrap(), 0.0);
        assert!((Exact::multiplicative().gel_mass(4.0).unwrap() - 0.75).abs() < 1e-15);
        let ml = Exact::marcus_lushnikov();
        let g = ml.gel_mass(3.0).unwrap();
        assert!((g - (1.0 - ml.moment(1, 3.0).unwrap())).abs() < 1e-14);
        // the Marcus–Lushnikov gel grows faster than Flory's
        assert!(g > Exact::multiplicative().gel_mass(3.0).unwrap());
        assert_eq!(Exact::additive().gel_mass(9.0).unwrap(), 0.0);
        assert!(Exact::additive().moment(4, 1.0).is_err());
        assert!(Exact::additive().number_density(0, 1.0).is_err());
        assert!(Exact::constant(0.0).is_err());
    }
}
