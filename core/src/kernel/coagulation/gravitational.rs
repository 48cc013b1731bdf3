//! Gravitational collection of water drops (differential sedimentation):
//! `K(x, y) = E(R, r) π (r_x + r_y)² |v(r_x) − v(r_y)|` in m³/s, for drops of volume
//! `x` and `y` in units of a drop of radius `r0` (`r_x = r0 x^{1/3}`), R the larger
//! radius and r the smaller.
//!
//! * Terminal velocity: the power law in mass that Simmel, Trautmann & Tetzlaff (2002,
//!   Atmos. Res. 61:135, Table 2) fitted to Beard (1976): `v = α m^β` with m in g and
//!   v in cm/s — α = 4.5795·10⁵, β = 2/3 below r = 67.215 µm; 4962, 1/3 to 755.82 µm;
//!   1732, 1/6 to 1738.92 µm; 917 cm/s above (continuous at the breaks, increasing).
//! * Collision efficiency: Long (1974, J. Atmos. Sci. 31:1040) in Simmel's form, as
//!   Shima et al. (2009, Q. J. R. Meteorol. Soc. 135:1307) used it, radii in cm:
//!   `E = max(4.5·10⁴ R² (1 − 3·10⁻⁴ / r), 10⁻³)` for R ≤ 50 µm, 1 above
//!   (coalescence efficiency 1). Its largest value is 1.0575, at R = r = 50 µm; the
//!   bounds use 1.125 (the formula's factor at R = 50 µm).
//!
//! The kernel vanishes on the diagonal (equal drops fall together) and `E` is 10⁻³
//! for small drops, so the low-rank bound `E_max π (r_x + r_y)² (v_x + v_y)` (rank 3,
//! `E_max` = 1.125) is loose by orders of magnitude there: block majorants
//! (`docs/design/block-majorants.md`). `v` and `(r_x + r_y)²` are non-decreasing in
//! each size, and `E` is up to R = 50 µm (it falls to 1 past it), so over a block
//! `[x0, x1] × [y0, y1]` the kernel is at most `E_b π (r_x1 + r_y1)² (v_hi − v_lo)`:
//! `E_b` the efficiency at the block's largest radii clamped to 50 µm (and at least 1
//! when the block reaches past 50 µm), `v_hi − v_lo` the largest velocity difference
//! of its corners — a bound, not the supremum.

use libm::{cbrt, pow};

/// Water density, g/cm³.
const RHO: f64 = 1.0;
/// Long's efficiency formula holds for collector radii up to this (cm).
const LONG_R_MAX: f64 = 50e-4;
/// A bound on the efficiency: Long's factor `4.5·10⁴ R²` at R = 50 µm (the efficiency
/// itself reaches 1.0575 there, at r = R).
pub const E_MAX: f64 = 4.5e4 * LONG_R_MAX * LONG_R_MAX;

/// Terminal velocity (m/s) of a drop of radius `r` (m): Simmel et al. 2002, Table 2.
pub fn velocity(r: f64) -> f64 {
    let rc = r * 100.0; // cm
    let m = RHO * 4.0 / 3.0 * core::f64::consts::PI * rc * rc * rc; // g
    let v = if rc < 67.215e-4 {
        4.5795e5 * pow(m, 2.0 / 3.0)
    } else if rc < 755.82e-4 {
        4962.0 * cbrt(m)
    } else if rc < 1738.92e-4 {
        1732.0 * pow(m, 1.0 / 6.0)
    } else {
        917.0
    };
    v / 100.0
}

/// Long's collision efficiency of radii `a`, `b` (m), either order.
pub fn efficiency(a: f64, b: f64) -> f64 {
    let (big, small) = if a >= b { (a, b) } else { (b, a) };
    let (rc, sc) = (big * 100.0, small * 100.0);
    if rc <= LONG_R_MAX {
        (4.5e4 * rc * rc * (1.0 - 3e-4 / sc)).max(1e-3)
    } else {
        1.0
    }
}

/// The kernel (m³/s) for radii `a`, `b` (m).
pub fn rate_of_radii(a: f64, b: f64) -> f64 {
    let s = a + b;
    efficiency(a, b) * core::f64::consts::PI * s * s * (velocity(a) - velocity(b)).abs()
}

/// The largest efficiency over collector radii in `[.., big]` and collected radii in
/// `[.., small]` (small ≤ big): E rises with both radii up to R = 50 µm, where it
/// reaches its maximum and falls to 1 beyond.
fn efficiency_bound(big: f64, small: f64) -> f64 {
    let cap = LONG_R_MAX / 100.0;
    let below = efficiency(big.min(cap), small.min(big.min(cap)));
    if big > cap { below.max(1.0) } else { below }
}

/// A bound on the kernel over radii `a ∈ [a0, a1]`, `b ∈ [b0, b1]` (m): see the module
/// docs.
pub fn bound_of_radii(a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let dv = (velocity(b1) - velocity(a0))
        .max(velocity(a1) - velocity(b0))
        .max(0.0);
    let s = a1 + b1;
    let e = efficiency_bound(a1.max(b1), a1.min(b1));
    e * core::f64::consts::PI * s * s * dv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_is_continuous_and_increasing() {
        for r_um in [67.215, 755.82, 1738.92] {
            let r = r_um * 1e-6;
            let (lo, hi) = (velocity(r * (1.0 - 1e-9)), velocity(r * (1.0 + 1e-9)));
            assert!((hi / lo - 1.0).abs() < 2e-3, "{r_um} µm: {lo} vs {hi}");
        }
        let mut last = 0.0;
        for k in 0..400 {
            let v = velocity(1e-6 * 1.02f64.powi(k));
            assert!(v >= last, "{k}");
            last = v;
        }
        // 10 µm: Stokes' 2 g ρ r² / 9 μ = 1.2 cm/s; radius 1 mm: Gunn & Kinzer (1949)
        // measured 6.49 m/s, the power-law fit gives 6.95 (within 10 %)
        assert!(
            (velocity(10e-6) - 0.0121).abs() < 0.001,
            "{}",
            velocity(10e-6)
        );
        assert!(
            (velocity(1e-3) / 6.49 - 1.0).abs() < 0.1,
            "{}",
            velocity(1e-3)
        );
    }

    #[test]
    fn long_efficiency_values() {
        // R = 30 µm, r = 10 µm: 4.5e4 · 9e-6 · (1 − 0.3) = 0.2835
        assert!((efficiency(30e-6, 10e-6) - 0.2835).abs() < 1e-12);
        assert_eq!(efficiency(10e-6, 30e-6), efficiency(30e-6, 10e-6));
        // small drops: the floor; past 50 µm: 1
        assert_eq!(efficiency(5e-6, 2e-6), 1e-3);
        assert_eq!(efficiency(60e-6, 2e-6), 1.0);
        assert!(efficiency(50e-6, 50e-6) <= E_MAX);
    }

    /// The block bound is above every kernel value in the block (random blocks,
    /// scanned on a grid), and within a modest factor of it off the diagonal.
    #[test]
    fn block_bound_holds() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..300 {
            let a0 = 1e-6 * pow(3000.0, next());
            let a1 = a0 * (1.0 + 3.0 * next());
            let b0 = 1e-6 * pow(3000.0, next());
            let b1 = b0 * (1.0 + 3.0 * next());
            let bound = bound_of_radii(a0, a1, b0, b1);
            let n = 24;
            for i in 0..=n {
                for j in 0..=n {
                    let a = a0 + (a1 - a0) * f64::from(i) / f64::from(n);
                    let b = b0 + (b1 - b0) * f64::from(j) / f64::from(n);
                    let k = rate_of_radii(a, b);
                    assert!(k <= bound * (1.0 + 1e-12), "{a} {b}: {k} > {bound}");
                }
            }
        }
    }
}
