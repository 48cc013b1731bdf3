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
//! * Or Hall's (1980, J. Atmos. Sci. 37:2486, Table 1) tabulated efficiencies
//!   ([`Collection::Hall`]): collector radii R = 10, 20, 30, 40, 50, 60, 70, 100, 150,
//!   200, 300 µm against r/R = 0.05, 0.10, …, 1.00, bilinear in (R, r/R) between the
//!   nodes and clamped to the table's edges outside it (R below 10 µm takes the 10 µm
//!   row, above 300 µm the 300 µm row; r/R below 0.05 the 0.05 column). The clamp is a
//!   choice, not Hall's: below 10 µm it gives E ≈ 0.03 near r = R where Long's formula
//!   gives its floor 10⁻³, and below r/R = 0.05 it keeps the 0.05 column where Bott's
//!   extension of the table sets E = 0 at r/R = 0 — size 1 should be a drop of 10 µm
//!   or more (`unit-radius`) where that matters. The values above 1 near r/R = 1 (wake
//!   capture, up to 4.0) are Hall's. The table was read from public transcriptions
//!   (of cloud and aerosol codes: CARMA's, a Python bin model's, PySDM's, a Fortran
//!   bin model's): the first two agree at every node with the values here; PySDM's
//!   has 10⁻³ at R = 30 µm, r/R = 0.05 (10⁻⁴ here); the Fortran one has 0.96, 0.96,
//!   0.97, 0.98 at (70 µm, 0.65), (70, 0.70), (100, 0.25), (150, 0.20) (0.95, 0.95,
//!   0.95, 0.97 here, as the other three). The paper itself was not in reach.
//!
//! The kernel vanishes on the diagonal (equal drops fall together) and `E` is 10⁻³
//! for small drops, so the low-rank bound `E_max π (r_x + r_y)² (v_x + v_y)` (rank 3,
//! `E_max` = 1.125 with Long's efficiency, 4 with Hall's) is loose by orders of
//! magnitude there: block majorants
//! (`docs/design/block-majorants.md`). `v` and `(r_x + r_y)²` are non-decreasing in
//! each size, and `E` is up to R = 50 µm (it falls to 1 past it), so over a block
//! `[x0, x1] × [y0, y1]` the kernel is at most `E_b π (r_x1 + r_y1)² (v_hi − v_lo)`:
//! `E_b` the efficiency at the block's largest radii clamped to 50 µm (and at least 1
//! when the block reaches past 50 µm), `v_hi − v_lo` the largest velocity difference
//! of its corners — a bound, not the supremum. With Hall's efficiency `E_b` is the
//! largest table node of the cells the block's collector radii and ratios r/R meet
//! (a bilinear interpolant is at most its cell's largest node).

use libm::{cbrt, pow};

/// Water density, g/cm³.
const RHO: f64 = 1.0;
/// Long's efficiency formula holds for collector radii up to this (cm).
const LONG_R_MAX: f64 = 50e-4;
/// A bound on the efficiency: Long's factor `4.5·10⁴ R²` at R = 50 µm (the efficiency
/// itself reaches 1.0575 there, at r = R).
pub const E_MAX: f64 = 4.5e4 * LONG_R_MAX * LONG_R_MAX;

/// The collision efficiency law.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Collection {
    /// Long 1974 in Simmel's form (the module docs).
    Long,
    /// Hall 1980, Table 1, bilinear (the module docs).
    Hall,
}

/// Hall's collector radii (µm), ascending.
const HALL_R: [f64; 11] = [
    10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 100.0, 150.0, 200.0, 300.0,
];

/// Hall's efficiencies: row k for collector radius `HALL_R[k]`, column j for
/// r/R = 0.05 (j + 1).
#[rustfmt::skip]
const HALL_E: [[f64; 20]; 11] = [
    [1e-4, 1e-4, 1e-4, 0.014, 0.017, 0.019, 0.022, 0.027, 0.030, 0.033, 0.035, 0.037, 0.038, 0.038, 0.037, 0.036, 0.035, 0.032, 0.029, 0.027],
    [1e-4, 1e-4, 0.005, 0.016, 0.022, 0.03, 0.043, 0.052, 0.064, 0.072, 0.079, 0.082, 0.080, 0.076, 0.067, 0.057, 0.048, 0.040, 0.033, 0.027],
    [1e-4, 0.002, 0.02, 0.04, 0.085, 0.17, 0.27, 0.40, 0.50, 0.55, 0.58, 0.59, 0.58, 0.54, 0.51, 0.49, 0.47, 0.45, 0.47, 0.52],
    [0.001, 0.07, 0.28, 0.50, 0.62, 0.68, 0.74, 0.78, 0.80, 0.80, 0.80, 0.78, 0.77, 0.76, 0.77, 0.77, 0.78, 0.79, 0.95, 1.4],
    [0.005, 0.40, 0.60, 0.70, 0.78, 0.83, 0.86, 0.88, 0.90, 0.90, 0.90, 0.90, 0.89, 0.88, 0.88, 0.89, 0.92, 1.01, 1.3, 2.3],
    [0.05, 0.43, 0.64, 0.77, 0.84, 0.87, 0.89, 0.90, 0.91, 0.91, 0.91, 0.91, 0.91, 0.92, 0.93, 0.95, 1.0, 1.03, 1.7, 3.0],
    [0.20, 0.58, 0.75, 0.84, 0.88, 0.90, 0.92, 0.94, 0.95, 0.95, 0.95, 0.95, 0.95, 0.95, 0.97, 1.0, 1.02, 1.04, 2.3, 4.0],
    [0.50, 0.79, 0.91, 0.95, 0.95, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    [0.77, 0.93, 0.97, 0.97, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    [0.87, 0.96, 0.98, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    [0.97, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
];

/// The largest of Hall's efficiencies (R = 70 µm, r = R).
pub const HALL_E_MAX: f64 = 4.0;

impl Collection {
    /// A bound on the efficiency at every pair of radii.
    pub fn e_max(self) -> f64 {
        match self {
            Collection::Long => E_MAX,
            Collection::Hall => HALL_E_MAX,
        }
    }
}

/// The cell of a clamped coordinate on an ascending grid: the index of its left node
/// and the weight of the right one.
fn cell(grid: &[f64], v: f64) -> (usize, f64) {
    let v = v.clamp(grid[0], grid[grid.len() - 1]);
    let i = grid.partition_point(|&g| g <= v).clamp(1, grid.len() - 1) - 1;
    (i, (v - grid[i]) / (grid[i + 1] - grid[i]))
}

/// Hall's ratio nodes r/R = 0.05 (j + 1).
const HALL_Q: [f64; 20] = [
    0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75, 0.80,
    0.85, 0.90, 0.95, 1.00,
];

/// The first node at or above a clamped coordinate.
fn upper(grid: &[f64], v: f64) -> usize {
    let v = v.clamp(grid[0], grid[grid.len() - 1]);
    grid.partition_point(|&g| g < v).min(grid.len() - 1)
}

/// Hall's efficiency at collector radius `big` ≥ collected radius `small` (m).
fn hall(big: f64, small: f64) -> f64 {
    if big.is_nan() || big <= 0.0 {
        return 0.0;
    }
    let (i, u) = cell(&HALL_R, big * 1e6);
    let (j, w) = cell(&HALL_Q, small / big);
    let e = |a: usize, b: usize| HALL_E[a][b];
    (1.0 - u) * ((1.0 - w) * e(i, j) + w * e(i, j + 1))
        + u * ((1.0 - w) * e(i + 1, j) + w * e(i + 1, j + 1))
}

/// The largest of Hall's efficiencies over collector radii in `[r0, r1]` and ratios in
/// `[q0, q1]`: the largest node of the cells the rectangle meets (a bilinear
/// interpolant is at most its cell's largest node).
fn hall_bound(r0: f64, r1: f64, q0: f64, q1: f64) -> f64 {
    hall_nodes(r0, r1, q0, q1).fold(0.0, f64::max)
}

/// The least of Hall's efficiencies over the same rectangle: the least node of the
/// cells it meets (a bilinear interpolant is at least its cell's least node).
fn hall_floor(r0: f64, r1: f64, q0: f64, q1: f64) -> f64 {
    hall_nodes(r0, r1, q0, q1).fold(f64::INFINITY, f64::min)
}

/// The table's nodes of the cells that collector radii in `[r0, r1]` and ratios in
/// `[q0, q1]` meet: from the last node at or below each lower end to the first at or
/// above each upper end.
fn hall_nodes(r0: f64, r1: f64, q0: f64, q1: f64) -> impl Iterator<Item = f64> {
    let (i0, _) = cell(&HALL_R, r0 * 1e6);
    let i1 = upper(&HALL_R, r1 * 1e6).max(i0);
    let (j0, _) = cell(&HALL_Q, q0);
    let j1 = upper(&HALL_Q, q1).max(j0);
    HALL_E[i0..=i1]
        .iter()
        .flat_map(move |row| row[j0..=j1].iter().copied())
}

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
    efficiency_of(Collection::Long, a, b)
}

/// The collision efficiency of `law` for radii `a`, `b` (m), either order.
pub fn efficiency_of(law: Collection, a: f64, b: f64) -> f64 {
    let (big, small) = if a >= b { (a, b) } else { (b, a) };
    if law == Collection::Hall {
        return hall(big, small);
    }
    let (rc, sc) = (big * 100.0, small * 100.0);
    if rc <= LONG_R_MAX {
        (4.5e4 * rc * rc * (1.0 - 3e-4 / sc)).max(1e-3)
    } else {
        1.0
    }
}

/// The kernel (m³/s) for radii `a`, `b` (m) with Long's efficiency.
pub fn rate_of_radii(a: f64, b: f64) -> f64 {
    rate_with(Collection::Long, a, b)
}

/// The kernel (m³/s) for radii `a`, `b` (m) with the efficiency of `law`.
pub fn rate_with(law: Collection, a: f64, b: f64) -> f64 {
    let s = a + b;
    efficiency_of(law, a, b) * core::f64::consts::PI * s * s * (velocity(a) - velocity(b)).abs()
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
    bound_with(Collection::Long, a0, a1, b0, b1)
}

/// [`bound_of_radii`] with the efficiency of `law` (Hall's: the largest table node of
/// the cells the block's collector radii and ratios meet).
pub fn bound_with(law: Collection, a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let dv = (velocity(b1) - velocity(a0))
        .max(velocity(a1) - velocity(b0))
        .max(0.0);
    let s = a1 + b1;
    let e = match law {
        Collection::Long => efficiency_bound(a1.max(b1), a1.min(b1)),
        Collection::Hall => {
            // R = max(a, b) over the block; r/R = min/max is extreme at a corner,
            // and reaches 1 where the two ranges meet
            let q = |a: f64, b: f64| a.min(b) / a.max(b);
            let corners = [q(a0, b0), q(a0, b1), q(a1, b0), q(a1, b1)];
            let q0 = corners.into_iter().fold(1.0, f64::min);
            let q1 = if a0 <= b1 && b0 <= a1 {
                1.0
            } else {
                corners.into_iter().fold(0.0, f64::max)
            };
            hall_bound(a0.max(b0), a1.max(b1), q0, q1)
        }
    };
    e * core::f64::consts::PI * s * s * dv
}

/// A lower bound of the kernel over radii `a ∈ [a0, a1]`, `b ∈ [b0, b1]` (m), the
/// squeeze of block majorants: for ranges apart (`a1 < b0`, or the other way round)
/// `E_lo π (a0 + b0)² (v(b0) − v(a1))`, each factor at its least (v and the radii
/// non-decreasing; Long's `E` rises with both radii to R = 50 µm and is 1 past it), so
/// `E_lo` is Long's efficiency at the least radii, or 1 past 50 µm, or the least node
/// of Hall's table over the cells the block's collector radii and ratios meet; lowered
/// by 1e-9 against rounding. 0 where the ranges meet (the kernel vanishes on the
/// diagonal) and where the velocity difference is within 1e-6 of the velocities
/// (rounding).
pub fn inf_with(law: Collection, a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let ((a0, a1), (b0, b1)) = if a1 < b0 {
        ((a0, a1), (b0, b1))
    } else {
        ((b0, b1), (a0, a1))
    };
    if !(a0 <= a1 && a1 < b0 && b0 <= b1) {
        return 0.0;
    }
    let (v_lo, v_hi) = (velocity(a1), velocity(b0));
    let dv = v_hi - v_lo;
    if dv.is_nan() || dv <= 1e-6 * v_hi {
        return 0.0;
    }
    let cap = LONG_R_MAX / 100.0;
    // (the collector is b, the collected a)
    let e = if law == Collection::Hall {
        hall_floor(b0, b1, a0 / b1, a1 / b0)
    } else if b0 > cap {
        1.0
    } else if b1 > cap {
        efficiency(b0, a0).min(1.0)
    } else {
        efficiency(b0, a0)
    };
    let s = a0 + b0;
    e * core::f64::consts::PI * s * s * dv * (1.0 - 1e-9)
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

    #[test]
    fn hall_efficiency_values() {
        // at the nodes, the table; between them, bilinear; clamped outside; symmetric
        assert_eq!(efficiency_of(Collection::Hall, 70e-6, 70e-6), 4.0);
        assert!((efficiency_of(Collection::Hall, 30e-6, 15e-6) - 0.55).abs() < 1e-12);
        assert!((efficiency_of(Collection::Hall, 20e-6, 2e-6) - 1e-4).abs() < 1e-15);
        let mid = efficiency_of(Collection::Hall, 25e-6, 12.5e-6);
        assert!((mid - 0.5 * (0.072 + 0.55)).abs() < 1e-12, "{mid}");
        assert_eq!(efficiency_of(Collection::Hall, 1e-3, 1e-4), 1.0);
        assert_eq!(
            efficiency_of(Collection::Hall, 5e-6, 4e-6),
            efficiency_of(Collection::Hall, 10e-6, 8e-6)
        );
        assert_eq!(
            efficiency_of(Collection::Hall, 12e-6, 40e-6),
            efficiency_of(Collection::Hall, 40e-6, 12e-6)
        );
        for row in HALL_E {
            for v in row {
                assert!(v > 0.0 && v <= HALL_E_MAX);
            }
        }
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
            for law in [Collection::Long, Collection::Hall] {
                let bound = bound_with(law, a0, a1, b0, b1);
                let n = 24;
                for i in 0..=n {
                    for j in 0..=n {
                        let a = a0 + (a1 - a0) * f64::from(i) / f64::from(n);
                        let b = b0 + (b1 - b0) * f64::from(j) / f64::from(n);
                        let k = rate_with(law, a, b);
                        assert!(k <= bound * (1.0 + 1e-12), "{law:?} {a} {b}: {k} > {bound}");
                    }
                }
            }
        }
    }

    /// The squeeze is below every kernel value in the block (random blocks apart and
    /// meeting, scanned on a grid, both orders), 0 where it must be, and within a
    /// modest factor of the block's least value where the ranges lie apart (a squeeze
    /// of 0 everywhere would pass the first check and save nothing).
    #[test]
    fn block_squeeze_holds() {
        let mut seed = 11u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut apart = 0;
        for _ in 0..400 {
            let a0 = 1e-6 * pow(3000.0, next());
            let a1 = a0 * (1.0 + 0.5 * next());
            let b0 = a1 * (1.0 + 2.0 * next()) * if next() < 0.2 { 0.3 } else { 1.0 };
            let b1 = b0 * (1.0 + 0.5 * next());
            for law in [Collection::Long, Collection::Hall] {
                let inf = inf_with(law, a0, a1, b0, b1);
                assert_eq!(inf, inf_with(law, b0, b1, a0, a1));
                let mut min = f64::INFINITY;
                let n = 24;
                for i in 0..=n {
                    for j in 0..=n {
                        let a = a0 + (a1 - a0) * f64::from(i) / f64::from(n);
                        let b = b0 + (b1 - b0) * f64::from(j) / f64::from(n);
                        min = min.min(rate_with(law, a, b));
                    }
                }
                assert!(
                    inf <= min,
                    "{law:?} [{a0}, {a1}] x [{b0}, {b1}]: {inf} > {min}"
                );
                if a1 < b0 && velocity(b0) > velocity(a1) * (1.0 + 1e-3) {
                    apart += 1;
                    // radii within 1.5 each: (a0+b0)²/(a1+b1)² ≥ 1/2.25, E within its
                    // rise over the block (Hall's: its cells' nodes); the velocity gap
                    // itself is exact at the corner
                    let within = if law == Collection::Long { 40.0 } else { 400.0 };
                    assert!(
                        inf >= min / within,
                        "{law:?} [{a0}, {a1}] x [{b0}, {b1}]: {inf} vs {min}"
                    );
                } else if !(a1 < b0 || b1 < a0) {
                    assert_eq!(inf, 0.0);
                }
            }
        }
        assert!(apart > 400, "{apart}");
    }
}
