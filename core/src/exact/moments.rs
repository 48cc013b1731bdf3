//! The moment equations of the kernels whose moments close (Smoluchowski's equation
//! with the constant or the additive kernel; with binary uniform fragmentation, Lécot et
//! al. 2019 §4), stepped by explicit Euler: a reference for combinations the closed
//! forms of [`Exact`](super::Exact) do not cover, and the expectation of a time-driven
//! scheme's moments (for the linear ones exactly; its O(Δt) bias against the exact
//! solution in general).

/// A kernel whose moment equations close: `K = b` or `K = b (x + y)`, with binary
/// uniform fragmentation at rate λ (constant kernel only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ClosedMoments {
    /// `K = b`, fragmentation λ (0: none).
    Constant {
        /// b.
        b: f64,
        /// λ.
        lambda: f64,
    },
    /// `K = b (x + y)`.
    Additive {
        /// b.
        b: f64,
    },
}

impl ClosedMoments {
    /// `dM/dt` for `M = [M0, M1, M2, M3]`.
    fn rate(self, m: [f64; 4]) -> [f64; 4] {
        match self {
            // 1/2 ∫∫ [(x+y)^p − x^p − y^p] K c c, plus break-up: a particle of size x
            // splits at rate λ into two uniform pieces (M0 +λM0, M2 −λM2/3, M3 −λM3/2)
            ClosedMoments::Constant { b, lambda } => [
                lambda * m[0] - 0.5 * b * m[0] * m[0],
                0.0,
                b * m[1] * m[1] - lambda * m[2] / 3.0,
                3.0 * b * m[1] * m[2] - 0.5 * lambda * m[3],
            ],
            ClosedMoments::Additive { b } => [
                -b * m[1] * m[0],
                0.0,
                2.0 * b * m[1] * m[2],
                3.0 * b * (m[1] * m[3] + m[2] * m[2]),
            ],
        }
    }

    /// `steps` explicit Euler steps of size h from `m`.
    ///
    /// ```
    /// use coagula_core::exact::ClosedMoments;
    /// // K = 1 from monomers: M2 = 1 + t exactly, also for Euler (M2 is linear in t)
    /// let k = ClosedMoments::Constant { b: 1.0, lambda: 0.0 };
    /// assert!((k.euler([1.0; 4], 0.01, 100)[2] - 2.0).abs() < 1e-12);
    /// ```
    pub fn euler(self, mut m: [f64; 4], h: f64, steps: u64) -> [f64; 4] {
        for _ in 0..steps {
            let d = self.rate(m);
            for k in 0..4 {
                m[k] += h * d[k];
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the exact solutions as Δt → 0 (first order), and the linear M2 of the
    /// constant kernel exactly.
    #[test]
    fn euler_converges_to_the_exact_moments() {
        let c = ClosedMoments::Constant {
            b: 1.0,
            lambda: 0.0,
        };
        assert!((c.euler([1.0; 4], 0.01, 100)[2] - 2.0).abs() < 1e-12);
        let err = |h: f64| c.euler([1.0; 4], h, (1.0 / h).round() as u64)[0] - 1.0 / 1.5;
        assert!((err(0.01) / err(0.005) - 2.0).abs() < 0.05);
        // Lécot's test: M2 → 3 − 2 e^{−1/3}
        let f = ClosedMoments::Constant {
            b: 1.0,
            lambda: 1.0,
        };
        let m = f.euler([1.0; 4], 1e-4, 10_000);
        assert!((m[2] - (3.0 - 2.0 * libm::exp(-1.0 / 3.0))).abs() < 1e-4);
        // additive: M0 = e^{−t}
        let a = ClosedMoments::Additive { b: 2.0 };
        let m = a.euler([1.0; 4], 1e-5, 50_000);
        assert!((m[0] - libm::exp(-1.0)).abs() < 1e-5);
    }
}
