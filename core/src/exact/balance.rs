//! The constant kernel with a monomer source, dilution and linear growth: the moment
//! equations stay closed (the reference of `docs/design/processes.md`).
//!
//! With `K = k0`, particles injected at rate S (per unit volume) of size `xs`, removal
//! at λ per particle and growth `dx/dt = g x`:
//!
//! * `M0' = S − k0 M0²/2 − λ M0`, a Riccati equation with constant coefficients: with
//!   `m± = (−λ ± √(λ² + 2 k0 S))/k0` and `γ = √(λ² + 2 k0 S)` (`m₊` evaluated as
//!   `2S/(λ + γ)`, which keeps its digits when `k0 S ≪ λ²`),
//!   `M0 = (m₊ − A m₋ e^{−γt})/(1 − A e^{−γt})`, `A = (M0(0) − m₊)/(M0(0) − m₋)`
//!   (at S = λ = 0 the pure-coagulation `M0(0)/(1 + k0 M0(0) t/2)`);
//! * `M1' = S xs − (λ − g) M1` (coagulation keeps mass);
//! * without growth `M2' = k0 M1² + S ⟨xs²⟩ − λ M2`, integrated in closed form below.
//!
//! The injected sizes may be a mixture (a list drawn uniformly, as PartMC's emission
//! with a background inflow): `xs` is then their mean and `⟨xs²⟩` their mean square
//! ([`Balance::with_source_sizes`]).
//!
//! On integer sizes growth is monomer attachment at rate `g i`; the mean of that chain
//! follows `M1' = g M1` exactly, and M0 does not see it (the constant kernel does not
//! depend on sizes).

use crate::error::{Error, Result};
use libm::{exp, expm1, sqrt};

/// The parameters (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Balance {
    /// The kernel constant.
    pub k0: f64,
    /// M0, M1, M2 at t = 0.
    pub start: [f64; 3],
    /// The source rate per unit volume.
    pub source: f64,
    /// The injected particles' size (their mean, for a mixture).
    pub size: f64,
    /// Their mean square size (`size²` for one size).
    pub size_square: f64,
    /// The removal rate per particle.
    pub removal: f64,
    /// The linear growth rate (`dx/dt = g x`).
    pub growth: f64,
}

impl Balance {
    /// Checks the parameters: k0 > 0, the rest finite and ≥ 0, M0(0) > 0 or S > 0.
    pub fn new(
        k0: f64,
        start: [f64; 3],
        source: f64,
        size: f64,
        removal: f64,
        growth: f64,
    ) -> Result<Self> {
        crate::error::positive("k0", k0)?;
        for (name, v) in [
            ("M0(0)", start[0]),
            ("M1(0)", start[1]),
            ("M2(0)", start[2]),
            ("source rate", source),
            ("removal rate", removal),
            ("growth rate", growth),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::OutOfRange {
                    name,
                    value: v,
                    range: "[0, inf)",
                });
            }
        }
        crate::error::positive("source size", size)?;
        Ok(Balance {
            k0,
            start,
            source,
            size,
            size_square: size * size,
            removal,
            growth,
        })
    }

    /// The injected sizes drawn uniformly from `sizes` (each finite and > 0, at least
    /// one): their mean and mean square replace the one size.
    pub fn with_source_sizes(mut self, sizes: &[f64]) -> Result<Self> {
        if sizes.is_empty() {
            return Err(Error::BufferLength {
                name: "source sizes",
                expected: 1,
                got: 0,
            });
        }
        let (mut m1, mut m2) = (0.0, 0.0);
        for &x in sizes {
            crate::error::positive("source size", x)?;
            m1 += x;
            m2 += x * x;
        }
        let n = sizes.len() as f64;
        self.size = m1 / n;
        self.size_square = m2 / n;
        Ok(self)
    }

    /// `M_m(t)` for m = 0, 1 and (without growth) 2.
    pub fn moment(&self, m: u32, t: f64) -> Result<f64> {
        let (k, s, x, l) = (self.k0, self.source, self.size, self.removal);
        match m {
            0 => Ok(self.m0(t)),
            1 => Ok(linear(self.start[1], s * x, l - self.growth, t)),
            2 if self.growth == 0.0 => {
                let m20 = self.start[2];
                if l == 0.0 {
                    let m10 = self.start[1];
                    let q = s * x;
                    let coag = if q > 0.0 {
                        {
                            let m1 = m10 + q * t;
                            k * (m1 * m1 * m1 - m10 * m10 * m10) / (3.0 * q)
                        }
                    } else {
                        k * m10 * m10 * t
                    };
                    return Ok(m20 + coag + s * self.size_square * t);
                }
                // M1 = a + b e^{−λs}; ∫0^t e^{λs}(k M1² + S x²) ds
                let a = s * x / l;
                let b = self.start[1] - a;
                let el = exp(-l * t);
                let integral = (k * a * a + s * self.size_square) * expm1(l * t) / l
                    + 2.0 * k * a * b * t
                    + k * b * b * (-expm1(-l * t)) / l;
                Ok(el * (m20 + integral))
            }
            _ => Err(Error::Unsupported {
                what: "exact moments with a source, removal and growth: M0, M1 and (without growth) M2",
            }),
        }
    }

    fn m0(&self, t: f64) -> f64 {
        let (k, s, l, u0) = (self.k0, self.source, self.removal, self.start[0]);
        let gamma = sqrt(l * l + 2.0 * k * s);
        if gamma == 0.0 {
            return u0 / (1.0 + 0.5 * k * u0 * t);
        }
        // (m₊ = (γ − λ)/k0 without the cancellation of γ − λ when k0 S ≪ λ²)
        let (mp, mm) = (2.0 * s / (gamma + l), (-gamma - l) / k);
        let a = (u0 - mp) / (u0 - mm);
        let e = a * exp(-gamma * t);
        (mp - mm * e) / (1.0 - e)
    }
}

/// The solution of `y' = q − r y`, `y(0) = y0`.
fn linear(y0: f64, q: f64, r: f64, t: f64) -> f64 {
    if r == 0.0 {
        y0 + q * t
    } else {
        // y0 e^{−rt} + q (1 − e^{−rt})/r
        y0 * exp(-r * t) - q * expm1(-r * t) / r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed forms against the moment equations integrated by RK4.
    #[test]
    fn the_closed_forms_solve_the_moment_equations() {
        for (s, l, g) in [
            (0.7, 0.0, 0.0),
            (0.0, 0.4, 0.0),
            (0.5, 0.25, 0.0),
            (0.3, 0.2, 0.1),
            (0.0, 0.0, 0.0),
        ] {
            let b = Balance::new(1.3, [2.0, 3.0, 5.5], s, 2.0, l, g).unwrap();
            let f = |y: [f64; 3]| {
                [
                    s - 0.5 * 1.3 * y[0] * y[0] - l * y[0],
                    s * 2.0 - (l - g) * y[1],
                    1.3 * y[1] * y[1] + s * 4.0 - l * y[2],
                ]
            };
            let (mut y, h) = (b.start, 1e-4);
            for _ in 0..30_000 {
                let k1 = f(y);
                let k2 = f(core::array::from_fn(|i| y[i] + 0.5 * h * k1[i]));
                let k3 = f(core::array::from_fn(|i| y[i] + 0.5 * h * k2[i]));
                let k4 = f(core::array::from_fn(|i| y[i] + h * k3[i]));
                y = core::array::from_fn(|i| {
                    y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
                });
            }
            let t = 3.0;
            let orders = if g == 0.0 { 3 } else { 2 };
            for m in 0..orders {
                let e = b.moment(m as u32, t).unwrap();
                assert!(
                    (e - y[m]).abs() < 1e-9 * y[m].abs().max(1.0),
                    "S {s} λ {l} g {g} M{m}: {e} vs {}",
                    y[m]
                );
            }
            if g > 0.0 {
                assert!(b.moment(2, t).is_err());
            }
        }
        assert!(Balance::new(0.0, [1.0; 3], 1.0, 1.0, 0.0, 0.0).is_err());
        assert!(
            Balance::new(1.0, [1.0; 3], 1.0, 1.0, 0.0, 0.0)
                .unwrap()
                .with_source_sizes(&[])
                .is_err()
        );
        assert!(Balance::new(1.0, [1.0; 3], -1.0, 1.0, 0.0, 0.0).is_err());
        assert!(Balance::new(1.0, [1.0; 3], 1.0, 0.0, 0.0, 0.0).is_err());
    }

    /// PartMC's emission-and-dilution test in its own units (1e9 m^-3, s, the initial
    /// particle's volume): a mixture source, dilution and a kernel so small that the
    /// moments are those without coagulation, `M = S/λ + (M(0) − S/λ) e^{−λt}` with
    /// the source's mean (square) size — which a cancelling `m₊ = (γ − λ)/k0` lost.
    #[test]
    fn a_mixture_source_with_dilution_and_a_negligible_kernel() {
        let sizes = [7.8817, 35.947, 35.947];
        let (s, l, t) = (4.5e-5, 3e-5, 86_400.0);
        let b = Balance::new(1e-12, [1.0, 1.0, 1.0], s, 1.0, l, 0.0)
            .unwrap()
            .with_source_sizes(&sizes)
            .unwrap();
        let mean = sizes.iter().sum::<f64>() / 3.0;
        let square = sizes.iter().map(|x| x * x).sum::<f64>() / 3.0;
        let e = exp(-l * t);
        for (m, q) in [(0, s), (1, s * mean), (2, s * square)] {
            let free = q / l + (1.0 - q / l) * e;
            let got = b.moment(m, t).unwrap();
            // coagulation changes M0 by about k0 M0² t / 2 ≈ 1e-7 of it
            assert!((got / free - 1.0).abs() < 1e-6, "M{m}: {got} vs {free}");
        }
    }
}
