//! The built-in coagulation kernels (Eibeck & Wagner 2000 §6, Osinsky 2023 eqs. 24 and 27) and their bounds.

use super::CoagulationKernel;
use crate::error::{Error, Result, finite, positive};
use libm::{pow, sqrt};

/// Cube root for the kernels' hot path: a bit-level first guess (within about 4 %),
/// two Halley steps (cubic convergence: ~1e-4, then ~1e-13) and a Newton step written
/// as a small correction, so the result is within about 1 ulp (the tests compare it
/// with `libm::cbrt`). About 20 instructions against ~140 for the correctly rounded
/// `libm` routine, which handles zero, negative, subnormal and non-finite input here.
#[inline]
pub(crate) fn cbrt(x: f64) -> f64 {
    if !(f64::MIN_POSITIVE..=f64::MAX).contains(&x) {
        return libm::cbrt(x);
    }
    // a third of the exponent (and mantissa, linearly), re-biased: 2/3 of 1023 · 2^52,
    // lowered to centre the guess's error
    let mut y = f64::from_bits(x.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y - (y - x / (y * y)) * (1.0 / 3.0)
}

/// Sizes whose cube roots are tabulated (the sizes of most collisions).
pub(crate) const CBRT_TABLE: usize = 1024;

/// `CUBE_ROOTS[i] = i^{1/3}` for `i < CBRT_TABLE`, computed at compile time by Newton's
/// method from an integer first guess (the tests compare it with `libm::cbrt`).
static CUBE_ROOTS: [f64; CBRT_TABLE] = {
    let mut t = [0.0; CBRT_TABLE];
    let mut i = 1;
    while i < CBRT_TABLE {
        let x = i as f64;
        let mut y = 1.0;
        while (y + 1.0) * (y + 1.0) * (y + 1.0) <= x {
            y += 1.0;
        }
        let mut k = 0;
        while k < 60 {
            y -= (y * y * y - x) / (3.0 * y * y);
            k += 1;
        }
        t[i] = y;
        i += 1;
    }
    t
};

/// `i^{1/3}` of a size: from the table below [`CBRT_TABLE`], else [`cbrt`].
#[inline]
pub(crate) fn size_cbrt(i: u64) -> f64 {
    match CUBE_ROOTS.get(i as usize) {
        Some(&c) if i > 0 => c,
        _ => cbrt(i as f64),
    }
}

/// `x^{1/3}`: from the table when `x` is an integer below [`CBRT_TABLE`] (the sizes of
/// most collisions of an integer-size scheme; within an ulp of [`cbrt`]), else [`cbrt`].
#[inline]
fn cbrt_of(x: f64) -> f64 {
    if x >= 1.0 && x < CBRT_TABLE as f64 && x == (x as u64) as f64 {
        CUBE_ROOTS[x as usize]
    } else {
        cbrt(x)
    }
}

/// `c²` of the free-molecular majorant `h(x) = c (x^{2/3} + x^{-1/2})`, valid for all
/// `x > 0`: the supremum of `K(x,y) / ((x^{2/3}+x^{-1/2})(y^{2/3}+y^{-1/2}))` is
/// 1.421874 (attained near x = 2.14, y = 0.467; found by maximisation and checked on a
/// grid by the tests), rounded up.
const FM_ALL_SIZES_C2: f64 = 1.4219;

/// `K(1,1) = 4√2`: the supremum of `K(x,y)/(x y)^{2/3}` over `x, y ≥ 1`. By homogeneity
/// (degree 1/6 against 4/3) the supremum over `x, y ≥ s` is `4√2 s^{-7/6}`.
const FM_UNIT_C2: f64 = 5.656_854_249_492_381;

/// The Boltzmann constant k_B in J/K (exact since the 2019 SI).
pub const BOLTZMANN: f64 = 1.380_649e-23;

/// A built-in coagulation kernel, with a product majorant and a low-rank bound.
///
/// Constructors validate their parameters. Bounds hold for all sizes `x > 0` unless
/// [`with_min_size`](Self::with_min_size) narrows them to `x ≥ s` (which tightens the
/// additive and free-molecular majorants).
///
/// | kernel | majorant h(x) | low-rank A(x, y) | R |
/// |---|---|---|---|
/// | constant K0 | √K0 | K0/2 | 1 |
/// | additive x + y | x + c, c = max(0, √(2s) − s, 1 − s) (c = 1 for s = 0) | x | 1 |
/// | multiplicative x y | x | x y / 2 | 1 |
/// | product (x y)^a | x^a | (x y)^a / 2 | 1 |
/// | homogeneous-γ | c (x + x^{γ−1}) (x for γ = 2) | c² x y^{γ−1} | 1 |
/// | free molecular | c (x^{2/3} + x^{−1/2}) (s = 0), √(4√2 s^{−7/6}) x^{2/3} (s > 0) | (x^{1/3}+y^{1/3})² y^{−1/2} | 3 |
/// | Brownian | x^{1/3} + x^{−1/3} | 1 + (x/y)^{1/3} | 2 |
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coagulation {
    kind: Kind,
    /// The coefficient b of `K = b K_kind` (1 unless set by `with_coefficient`).
    scale: f64,
    min_size: f64,
    /// Additive: the shift c; homogeneous: c² of the bound; free molecular: c².
    c: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Constant(f64),
    Additive,
    Multiplicative,
    Product(f64),
    Homogeneous(f64),
    FreeMolecular,
    Brownian,
    Atmospheric,
    /// Gravitational collection; the unit radius r0 (m) and the efficiency law.
    Gravitational(f64, gravitational::Collection),
}

impl Coagulation {
    /// A fingerprint of the kernel and every parameter (equal for equal kernels): what
    /// a checkpoint records so that it is restored only under the same kernel.
    fn fingerprint_of(&self) -> u64 {
        let (tag, p) = match self.kind {
            Kind::Constant(k0) => (1, k0),
            Kind::Additive => (2, 0.0),
            Kind::Multiplicative => (3, 0.0),
            Kind::Product(a) => (4, a),
            Kind::Homogeneous(g) => (5, g),
            Kind::FreeMolecular => (6, 0.0),
            Kind::Brownian => (7, 0.0),
            Kind::Atmospheric => (8, 0.0),
            Kind::Gravitational(r0, gravitational::Collection::Long) => (9, r0),
            Kind::Gravitational(r0, gravitational::Collection::Hall) => (10, r0),
        };
        crate::checkpoint::fingerprint([
            tag,
            p.to_bits(),
            self.scale.to_bits(),
            self.min_size.to_bits(),
            self.c.to_bits(),
        ])
    }
}

impl Coagulation {
    /// `K = k0` (k0 > 0).
    pub fn constant(k0: f64) -> Result<Self> {
        positive("k0", k0)?;
        Ok(Self::new(Kind::Constant(k0)))
    }

    /// `K = x + y`.
    pub fn additive() -> Self {
        Self::new(Kind::Additive).with_c_additive(0.0)
    }

    /// `K = x y` (gels at t = 1 from a monodisperse start).
    pub fn multiplicative() -> Self {
        Self::new(Kind::Multiplicative)
    }

    /// `K = (x y)^a`, `0 < a ≤ 1` (gelling for a > 1/2; Eibeck–Wagner eq. 6.4).
    pub fn product(a: f64) -> Result<Self> {
        finite("a", a)?;
        if !(a > 0.0 && a <= 1.0) {
            return Err(Error::OutOfRange {
                name: "a",
                value: a,
                range: "(0, 1]",
            });
        }
        Ok(Self::new(Kind::Product(a)))
    }

    /// `K = 2 (x y)^γ / ((x + y)^γ − x^γ − y^γ)`, `1 < γ ≤ 2` (Eibeck–Wagner eq. 6.6;
    /// γ = 2 gives `x y`).
    pub fn homogeneous(gamma: f64) -> Result<Self> {
        finite("gamma", gamma)?;
        if !(gamma > 1.0 && gamma <= 2.0) {
            return Err(Error::OutOfRange {
                name: "gamma",
                value: gamma,
                range: "(1, 2]",
            });
        }
        let mut k = Self::new(Kind::Homogeneous(gamma));
        k.c = homogeneous_bound_c2(gamma);
        Ok(k)
    }

    /// Free-molecular (ballistic) kernel `K = √(1/x + 1/y) (x^{1/3} + y^{1/3})²`
    /// (Eibeck–Wagner eq. 6.2, Osinsky eq. 24).
    pub fn free_molecular() -> Self {
        let mut k = Self::new(Kind::FreeMolecular);
        k.c = FM_ALL_SIZES_C2;
        k
    }

    /// Brownian (continuum) kernel `K = (x^{1/3} + y^{1/3})(x^{−1/3} + y^{−1/3})`
    /// (Osinsky eq. 27).
    pub fn brownian() -> Self {
        Self::new(Kind::Brownian)
    }

    /// The "atmospheric" kernel of integer sizes (see [`atmospheric`](crate::kernel::atmospheric)):
    /// `K(i, j) = (i + j)(i^{1/3} + j^{1/3})^{2/3} / ((i j)^{5/9} |i^{2/3} − j^{2/3}|)`,
    /// `K(i, i) = 4`, with the rank-2 bound `A(x, y) = 0.2556 x^{−5/9} + 2.38125 (x y)^{2/9}`
    /// (loose: the acceptance falls as the sizes grow) and exact suprema over blocks of
    /// integer sizes. Sizes are integers from 1 (the bounds hold there only).
    pub fn atmospheric() -> Self {
        Coagulation {
            min_size: 1.0,
            ..Self::new(Kind::Atmospheric)
        }
    }

    /// Gravitational collection of water drops with Long's efficiency (see
    /// [`gravitational`](crate::kernel::gravitational)), in m³/s, for drop volumes in
    /// units of a drop of radius `unit_radius` (m, in [1e-8, 1e-2]): `K = E(R, r) π (r_x
    /// + r_y)² |v_x − v_y|`, with a rank-3 bound (`E ≤ 1.125`, `|v_x − v_y| ≤ v_x + v_y`)
    /// and block bounds (`sup_block`, for the `blocks` engine); no product majorant.
    pub fn gravitational(unit_radius: f64) -> Result<Self> {
        finite("unit radius", unit_radius)?;
        if !(1e-8..=1e-2).contains(&unit_radius) {
            return Err(Error::OutOfRange {
                name: "unit radius",
                value: unit_radius,
                range: "[1e-8, 1e-2] m",
            });
        }
        Ok(Self::new(Kind::Gravitational(
            unit_radius,
            gravitational::Collection::Long,
        )))
    }

    /// [`gravitational`](Self::gravitational) with Hall's (1980) tabulated collision
    /// efficiencies instead of Long's (see [`gravitational`](crate::kernel::gravitational));
    /// the rank-3 bound takes `E ≤ 4` (Hall's largest, wake capture of equal drops).
    pub fn gravitational_hall(unit_radius: f64) -> Result<Self> {
        let k = Self::gravitational(unit_radius)?;
        Ok(Self::new(Kind::Gravitational(
            k.unit_radius(),
            gravitational::Collection::Hall,
        )))
    }

    /// The kernel for sizes counted in units of `unit` of this kernel's sizes:
    /// `K'(i, j) = K(i·unit, j·unit)` — for a homogeneous kernel the coefficient times
    /// `unit^λ` ([`homogeneity`](Self::homogeneity)), for the gravitational one the unit
    /// radius times `unit^{1/3}`.
    /// Errors: a unit that is not positive, and any unit but 1 for the atmospheric
    /// kernel, which is defined on integer sizes only.
    pub fn in_size_unit(self, unit: f64) -> Result<Self> {
        positive("size unit", unit)?;
        match self.kind {
            Kind::Atmospheric if unit != 1.0 => Err(Error::OutOfRange {
                name: "size unit of the atmospheric kernel (integer sizes: start from counts at resolution 1)",
                value: unit,
                range: "1",
            }),
            Kind::Gravitational(r0, law) => Ok(Coagulation {
                kind: Kind::Gravitational(Self::gravitational(r0 * cbrt(unit))?.unit_radius(), law),
                ..self
            }),
            _ => self.with_coefficient(libm::pow(unit, self.homogeneity())),
        }
    }

    /// The gravitational kernel's unit radius (m); NaN for the other kernels.
    fn unit_radius(&self) -> f64 {
        match self.kind {
            Kind::Gravitational(r0, _) => r0,
            _ => f64::NAN,
        }
    }

    fn new(kind: Kind) -> Self {
        Coagulation {
            kind,
            scale: 1.0,
            min_size: 0.0,
            c: 0.0,
        }
    }

    fn with_c_additive(mut self, s: f64) -> Self {
        // (x + c)(y + c) ≥ x + y for x, y ≥ s  ⇔  (c + s)² ≥ 2s and s ≥ 1 − c.
        self.c = if s == 0.0 {
            1.0
        } else {
            (sqrt(2.0 * s) - s).max(1.0 - s).max(0.0)
        };
        self
    }

    /// Narrows the bounds to sizes `x ≥ s` (`s ≥ 0`; e.g. 1 for integer sizes), which
    /// tightens the majorants of the additive and free-molecular kernels.
    pub fn with_min_size(mut self, s: f64) -> Result<Self> {
        finite("min_size", s)?;
        if s < 0.0 {
            return Err(Error::OutOfRange {
                name: "min_size",
                value: s,
                range: "[0, inf)",
            });
        }
        if self.kind == Kind::Atmospheric && s < 1.0 {
            return Err(Error::OutOfRange {
                name: "min_size",
                value: s,
                range: "[1, inf) for the atmospheric kernel (integer sizes)",
            });
        }
        self.min_size = s;
        match self.kind {
            Kind::Additive => self = self.with_c_additive(s),
            Kind::FreeMolecular => {
                self.c = if s > 0.0 {
                    FM_UNIT_C2 * pow(s, -7.0 / 6.0)
                } else {
                    FM_ALL_SIZES_C2
                };
            }
            _ => {}
        }
        Ok(self)
    }

    /// Multiplies the kernel by a coefficient `b > 0` (finite): `K = b K_kind`, e.g.
    /// Golovin's `K = b (x + y)`. The bounds scale with it (the majorant by `√b`, the
    /// low-rank factors `a_k` by `b`), the acceptance floor does not. Coefficients
    /// compose: `with_coefficient(2)` twice is `4 K`.
    ///
    /// ```
    /// use coagula_core::kernel::{Coagulation, CoagulationKernel};
    /// let golovin = Coagulation::additive().with_coefficient(1.5).unwrap();
    /// assert_eq!(golovin.rate(1.0, 3.0), 6.0);
    /// assert!(Coagulation::additive().with_coefficient(0.0).is_err());
    /// ```
    pub fn with_coefficient(mut self, b: f64) -> Result<Self> {
        positive("coefficient", b)?;
        let scale = self.scale * b;
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::OutOfRange {
                name: "coefficient",
                value: b,
                range: "a product with the kernel's coefficient in (0, inf)",
            });
        }
        self.scale = scale;
        Ok(self)
    }

    /// The coefficient b of `K = b K_kind` (1 for the plain kernels).
    pub fn coefficient(&self) -> f64 {
        self.scale
    }

    /// The degree λ of homogeneity, `K(s x, s y) = s^λ K(x, y)`: 0 (constant,
    /// Brownian), 1 (additive), 2 (multiplicative), 2a (product), γ (homogeneous-γ),
    /// 1/6 (free molecular); NaN for the gravitational kernel, which is not
    /// homogeneous. A front end that measures sizes in units of δ uses
    /// [`in_size_unit`](Self::in_size_unit).
    pub fn homogeneity(&self) -> f64 {
        match self.kind {
            Kind::Constant(_) | Kind::Brownian => 0.0,
            Kind::Additive => 1.0,
            Kind::Multiplicative => 2.0,
            Kind::Product(a) => 2.0 * a,
            Kind::Homogeneous(g) => g,
            Kind::FreeMolecular => 1.0 / 6.0,
            Kind::Atmospheric => -5.0 / 9.0,
            // (not homogeneous: see in_size_unit)
            Kind::Gravitational(..) => f64::NAN,
        }
    }

    /// The Brownian (continuum-regime) kernel in physical units,
    /// `K(v, w) = (2 k_B T / 3 μ) (v^{1/3} + w^{1/3})(v^{−1/3} + w^{−1/3})` in m³/s, for
    /// gas temperature `temperature` (K) and dynamic viscosity `viscosity` (Pa·s),
    /// without slip correction (Friedlander, *Smoke, Dust and Haze*, eq. 7.12). The
    /// kernel is homogeneous of degree 0, so sizes may be counted in any volume unit
    /// (e.g. monomers).
    ///
    /// ```
    /// use coagula_core::kernel::{Coagulation, CoagulationKernel};
    /// // air at 293.15 K: 8 k_B T / 3 μ ≈ 6.0e-16 m³/s between equal spheres
    /// let k = Coagulation::brownian_continuum(293.15, 1.81e-5).unwrap();
    /// assert!((k.rate(1.0, 1.0) - 5.96e-16).abs() < 0.01e-16);
    /// ```
    pub fn brownian_continuum(temperature: f64, viscosity: f64) -> Result<Self> {
        positive("temperature", temperature)?;
        positive("viscosity", viscosity)?;
        Self::brownian().with_coefficient(2.0 * BOLTZMANN * temperature / (3.0 * viscosity))
    }

    /// The free-molecular (kinetic-regime) kernel in physical units for sizes counted
    /// in monomers of volume `monomer_volume` (m³):
    /// `K(v, w) = (3/4π)^{1/6} (6 k_B T / ρ)^{1/2} (1/v + 1/w)^{1/2} (v^{1/3} + w^{1/3})²`
    /// in m³/s, for temperature `temperature` (K) and particle material density
    /// `density` (kg/m³) (Friedlander, eq. 7.25; Seinfeld & Pandis, eq. 13.49). With
    /// `v = v0 x` this is `(3/4π)^{1/6} (6 k_B T/ρ)^{1/2} v0^{1/6}` times
    /// [`free_molecular`](Self::free_molecular).
    pub fn free_molecular_physical(
        temperature: f64,
        density: f64,
        monomer_volume: f64,
    ) -> Result<Self> {
        positive("temperature", temperature)?;
        positive("density", density)?;
        positive("monomer_volume", monomer_volume)?;
        let c = pow(3.0 / (4.0 * core::f64::consts::PI), 1.0 / 6.0)
            * sqrt(6.0 * BOLTZMANN * temperature / density)
            * pow(monomer_volume, 1.0 / 6.0);
        Self::free_molecular().with_coefficient(c)
    }

    /// A short name of the kernel (`"constant"`, `"additive"`, ...).
    pub fn name(&self) -> &'static str {
        match self.kind {
            Kind::Constant(_) => "constant",
            Kind::Additive => "additive",
            Kind::Multiplicative => "multiplicative",
            Kind::Product(_) => "product",
            Kind::Homogeneous(_) => "homogeneous",
            Kind::FreeMolecular => "free-molecular",
            Kind::Brownian => "brownian",
            Kind::Atmospheric => "atmospheric",
            Kind::Gravitational(_, gravitational::Collection::Long) => "gravitational",
            Kind::Gravitational(_, gravitational::Collection::Hall) => "gravitational-hall",
        }
    }
}

/// `(1 + r)^γ − 1 − r^γ` without cancellation for small r.
fn homogeneous_den_unit(gamma: f64, r: f64) -> f64 {
    libm::expm1(gamma * libm::log1p(r)) - pow(r, gamma)
}

/// `K(1, r) = 2 r^γ / ((1+r)^γ − 1 − r^γ)` for `0 < r ≤ 1`.
fn homogeneous_unit(gamma: f64, r: f64) -> f64 {
    2.0 * pow(r, gamma) / homogeneous_den_unit(gamma, r)
}

/// Supremum over r of `K(1, r) / (r + r^{γ−1})` (`0 < r ≤ 1` by symmetry), which makes
/// `K(x, y) ≤ c² (x y^{γ−1} + x^{γ−1} y)`. The limit at r → 0 is 2/γ for γ < 2 (1/2 for
/// γ = 2); interior values are scanned on a fine log grid and refined, then raised by
/// 1e-9 relative for rounding.
fn homogeneous_bound_c2(gamma: f64) -> f64 {
    let ratio = |r: f64| homogeneous_unit(gamma, r) / (r + pow(r, gamma - 1.0));
    let mut best = if gamma < 2.0 { 2.0 / gamma } else { 0.5 };
    let n = 4000;
    let (lo, hi) = (-40.0_f64, 0.0_f64); // ln r
    let mut best_i = n;
    for i in 0..=n {
        let lr = lo + (hi - lo) * i as f64 / n as f64;
        let v = ratio(libm::exp(lr));
        if v > best {
            best = v;
            best_i = i;
        }
    }
    // golden-section refinement around the best grid point
    let h = (hi - lo) / n as f64;
    let centre = lo + (hi - lo) * best_i as f64 / n as f64;
    let (mut a, mut b) = ((centre - h).max(lo), (centre + h).min(hi));
    let g = 0.618_033_988_749_894_9;
    for _ in 0..80 {
        let c1 = b - g * (b - a);
        let c2 = a + g * (b - a);
        let (v1, v2) = (ratio(libm::exp(c1)), ratio(libm::exp(c2)));
        best = best.max(v1).max(v2);
        if v1 > v2 {
            b = c2;
        } else {
            a = c1;
        }
    }
    best * (1.0 + 1e-9)
}

impl CoagulationKernel for Coagulation {
    fn fingerprint(&self) -> u64 {
        self.fingerprint_of()
    }

    fn rate(&self, x: f64, y: f64) -> f64 {
        self.scale * self.unit_rate(x, y)
    }

    fn majorant(&self, x: f64) -> Option<f64> {
        self.unit_majorant(x).map(|h| sqrt(self.scale) * h)
    }

    fn rank(&self) -> usize {
        match self.kind {
            Kind::FreeMolecular => 3,
            Kind::Brownian | Kind::Atmospheric => 2,
            Kind::Gravitational(..) => 3,
            _ => 1,
        }
    }

    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        self.unit_factors(x, a, b);
        if self.scale != 1.0 {
            let r = self.rank();
            for ak in &mut a[..r] {
                *ak *= self.scale;
            }
        }
    }

    fn min_size(&self) -> f64 {
        self.min_size
    }

    /// Every built-in kernel's factors are constants or powers `c x^p` (see
    /// `unit_factors`), monotone in x.
    fn monotone_factors(&self) -> bool {
        true
    }

    fn low_rank_is_exact(&self) -> bool {
        !matches!(
            self.kind,
            Kind::FreeMolecular
                | Kind::Homogeneous(_)
                | Kind::Atmospheric
                | Kind::Gravitational(..)
        )
    }

    /// The atmospheric kernel. Not the gravitational one: its rank-3 bound is loose for
    /// near-equal small drops, but on a cloud-like start (mean radius 30 µm) the
    /// low-rank engine accepts 19–49 % and ran faster than block majorants
    /// (`docs/design/block-majorants.md`), so `lowrank` keeps it unless forced.
    fn low_rank_is_loose(&self) -> bool {
        self.kind == Kind::Atmospheric
    }

    /// The gravitational kernels: smooth across a log-linear strip (the fall speeds'
    /// difference vanishes on the diagonal, so a diagonal block's supremum is that of
    /// its corners). The atmospheric kernel is not (it peaks next to the diagonal);
    /// the others keep the integer partition, and the bits the block engine drew for
    /// them before.
    fn log_linear_blocks(&self) -> bool {
        matches!(self.kind, Kind::Gravitational(..))
    }

    fn integer_sizes(&self) -> bool {
        self.kind == Kind::Atmospheric
    }

    /// Ballistic: `K / (A + Aᵀ) = sqrt(1/x + 1/y) / (x^{-1/2} + y^{-1/2}) ≥ 1/√2` (equality
    /// at x = y), lowered by 1e-12 against rounding. The coefficient cancels.
    fn low_rank_floor(&self) -> f64 {
        match self.kind {
            Kind::FreeMolecular => core::f64::consts::FRAC_1_SQRT_2 * (1.0 - 1e-12),
            Kind::Homogeneous(_) | Kind::Atmospheric | Kind::Gravitational(..) => 0.0,
            _ => 1.0,
        }
    }

    /// Every built-in kernel is, along each axis, monotone or decreasing-then-increasing
    /// (quasi-convex), so its supremum over a square is attained at a corner.
    /// The atmospheric kernel's square on integer sizes: see [`atmospheric`](crate::kernel::atmospheric).
    fn sup_rate(&self, lo: f64, hi: f64) -> Option<f64> {
        if self.kind == Kind::Atmospheric {
            return Some(self.scale * atmospheric::sup_block(lo, hi, lo, hi));
        }
        if let Kind::Gravitational(..) = self.kind {
            return self.sup_block(lo, hi, lo, hi);
        }
        let corners = [self.rate(lo, lo), self.rate(lo, hi), self.rate(hi, hi)];
        Some(corners.into_iter().fold(0.0, f64::max))
    }

    /// The atmospheric kernel's, on integer sizes, from
    /// [`atmospheric::inf_block`](crate::kernel::atmospheric::inf_block), the
    /// gravitational kernels' from
    /// [`gravitational::inf_with`](crate::kernel::gravitational::inf_with); 0 for the
    /// others.
    fn inf_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        if self.kind == Kind::Atmospheric {
            return self.scale * atmospheric::inf_block(x0, x1, y0, y1);
        }
        if let Kind::Gravitational(r0, law) = self.kind {
            let r = |x: f64| r0 * cbrt(x);
            return self.scale * gravitational::inf_with(law, r(x0), r(x1), r(y0), r(y1));
        }
        0.0
    }

    /// Quasi-convex along each axis (as for [`sup_rate`](Self::sup_rate)): the supremum
    /// over a block is at one of its four corners; the atmospheric kernel's, on integer
    /// sizes, from [`atmospheric::sup_block`](crate::kernel::atmospheric::sup_block).
    fn sup_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<f64> {
        if self.kind == Kind::Atmospheric {
            return Some(self.scale * atmospheric::sup_block(x0, x1, y0, y1));
        }
        if let Kind::Gravitational(r0, law) = self.kind {
            let r = |x: f64| r0 * cbrt(x);
            let b = gravitational::bound_with(law, r(x0), r(x1), r(y0), r(y1));
            return Some(self.scale * b);
        }
        let corners = [
            self.rate(x0, y0),
            self.rate(x0, y1),
            self.rate(x1, y0),
            self.rate(x1, y1),
        ];
        Some(corners.into_iter().fold(0.0, f64::max))
    }
}

impl Coagulation {
    /// The kernel with coefficient 1.
    fn unit_rate(&self, x: f64, y: f64) -> f64 {
        match self.kind {
            Kind::Constant(k0) => k0,
            Kind::Additive => x + y,
            Kind::Multiplicative => x * y,
            Kind::Product(a) => pow(x * y, a),
            Kind::Homogeneous(g) => {
                let (big, small) = if x >= y { (x, y) } else { (y, x) };
                pow(big, g) * homogeneous_unit(g, small / big)
            }
            Kind::FreeMolecular => {
                let s = cbrt_of(x) + cbrt_of(y);
                sqrt(1.0 / x + 1.0 / y) * s * s
            }
            Kind::Brownian => (cbrt(x) + cbrt(y)) * (1.0 / cbrt(x) + 1.0 / cbrt(y)),
            Kind::Atmospheric => atmospheric::rate(x, y, cbrt_of(x), cbrt_of(y)),
            Kind::Gravitational(r0, law) => {
                gravitational::rate_with(law, r0 * cbrt(x), r0 * cbrt(y))
            }
        }
    }

    /// The majorant with coefficient 1.
    fn unit_majorant(&self, x: f64) -> Option<f64> {
        Some(match self.kind {
            Kind::Gravitational(..) => return None,
            Kind::Constant(k0) => sqrt(k0),
            Kind::Additive => x + self.c,
            Kind::Multiplicative => x,
            Kind::Product(a) => pow(x, a),
            // γ = 2 is exactly x y
            Kind::Homogeneous(2.0) => x,
            Kind::Homogeneous(g) => sqrt(self.c) * (x + pow(x, g - 1.0)),
            Kind::FreeMolecular => {
                if self.min_size > 0.0 {
                    sqrt(self.c) * pow(x, 2.0 / 3.0)
                } else {
                    sqrt(self.c) * (pow(x, 2.0 / 3.0) + 1.0 / sqrt(x))
                }
            }
            Kind::Brownian => cbrt(x) + 1.0 / cbrt(x),
            Kind::Atmospheric => atmospheric::MAJORANT_C * (pow(x, 2.0 / 9.0) + pow(x, -5.0 / 9.0)),
        })
    }

    /// The low-rank factors with coefficient 1.
    fn unit_factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        match self.kind {
            Kind::Constant(k0) => {
                a[0] = 0.5 * k0;
                b[0] = 1.0;
            }
            Kind::Additive => {
                a[0] = x;
                b[0] = 1.0;
            }
            Kind::Multiplicative => {
                a[0] = 0.5 * x;
                b[0] = x;
            }
            Kind::Product(p) => {
                let v = pow(x, p);
                a[0] = 0.5 * v;
                b[0] = v;
            }
            Kind::Homogeneous(g) => {
                a[0] = self.c * x;
                b[0] = pow(x, g - 1.0);
            }
            Kind::FreeMolecular => {
                // A(x, y) = (x^{1/3} + y^{1/3})² y^{-1/2}
                //         = x^{2/3} y^{-1/2} + 2 x^{1/3} y^{-1/6} + y^{1/6}
                let c = cbrt(x);
                let s6 = pow(x, 1.0 / 6.0);
                a[0] = c * c;
                b[0] = 1.0 / sqrt(x);
                a[1] = 2.0 * c;
                b[1] = 1.0 / s6;
                a[2] = 1.0;
                b[2] = s6;
            }
            Kind::Brownian => {
                // A(x, y) = 1 + (x / y)^{1/3}
                a[0] = 1.0;
                b[0] = 1.0;
                let c = cbrt(x);
                a[1] = c;
                b[1] = 1.0 / c;
            }
            Kind::Gravitational(r0, law) => {
                // A(x, y) = c (r_x² v_x + r_x² v_y + 2 r_x v_x r_y), c = E_max π:
                // A + Aᵀ = c (r_x + r_y)² (v_x + v_y)
                let r = r0 * cbrt(x);
                let v = gravitational::velocity(r);
                let c = law.e_max() * core::f64::consts::PI;
                a[0] = c * r * r * v;
                b[0] = 1.0;
                a[1] = c * r * r;
                b[1] = v;
                a[2] = 2.0 * c * r * v;
                b[2] = r;
            }
            Kind::Atmospheric => {
                let p = pow(x, 2.0 / 9.0);
                a[0] = atmospheric::A0 * pow(x, -5.0 / 9.0);
                b[0] = 1.0;
                a[1] = 0.5 * atmospheric::A1 * p;
                b[1] = p;
            }
        }
    }
}

pub mod atmospheric;
pub mod gravitational;
#[cfg(test)]
mod tests;
