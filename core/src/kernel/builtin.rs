//! The built-in kernels in one table, which every front end reads: the CLI's
//! `[kernel]` table, the C ABI's `coag_kernel_new`, Python's `coagula.Kernel`, the
//! fuzzers and the tests. A kernel is a name and its parameters, each with a default
//! (or required), a unit and what it means; [`make`] builds it by name.
//!
//! Three families: coagulation kernels (Eibeck & Wagner 2000 §6; Osinsky 2023 eqs.
//! 24, 27; Friedlander, *Smoke, Dust and Haze*, eqs. 7.12 and 7.25), the temperature
//! models of Osinsky 2023 §4 (see [`temperature`](super::temperature)) and the
//! hard-sphere gas of §5 (see [`gas`](super::gas)). Which family a scheme takes is its
//! registry entry's `model`.
//!
//! A kernel's convention is that of the Smoluchowski equation with the ½ of the gain
//! term: `dc_k/dt = ½ Σ_{i+j=k} K(i, j) c_i c_j − c_k Σ_j K(k, j) c_j`, so each
//! unordered pair of particles in a volume V coagulates at rate `K/V`.
//!
//! # Example
//! ```
//! use coagula_core::kernel::builtin::{self, Builtin};
//! use coagula_core::kernel::CoagulationKernel;
//! let Builtin::Coagulation(k) = builtin::make("additive", &[("coefficient", 1.5)]).unwrap() else {
//!     unreachable!()
//! };
//! assert_eq!(k.rate(1.0, 3.0), 6.0);
//! // a parameter the kernel does not have is refused, by name
//! assert!(builtin::make("constant", &[("gamma", 1.5)]).is_err());
//! // and a required one that is missing
//! assert!(builtin::make("product", &[]).is_err());
//! ```

use super::Coagulation;
use super::gas::HardSpheres;
use super::temperature::{Ballistic, ClosedForm, TemperatureModel};
use crate::error::{Error, Result};

/// What kind of physics a built-in describes (and a registry scheme takes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// A coagulation kernel `K(x, y)`.
    Coagulation,
    /// A temperature model: collision, aggregation and energy rates of partial
    /// temperatures (Osinsky 2023 §4).
    Temperature,
    /// A gas of particles with velocities (Osinsky 2023 §5).
    Gas,
}

/// A parameter of a built-in kernel.
#[derive(Clone, Copy, Debug)]
pub struct Param {
    /// Its name.
    pub name: &'static str,
    /// Its default (`None`: required).
    pub default: Option<f64>,
    /// Its unit (`""`: dimensionless).
    pub unit: &'static str,
    /// What it is, with its admissible range.
    pub doc: &'static str,
}

/// A built-in kernel.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinInfo {
    /// Its name.
    pub name: &'static str,
    /// What it is.
    pub family: Family,
    /// The formula.
    pub formula: &'static str,
    /// Where it comes from.
    pub source: &'static str,
    /// Its parameters, in the order positional values give them.
    pub params: &'static [Param],
    /// Units of the rate and the time: `""` for dimensionless kernels (time in the
    /// kernel's units), else the physical units.
    pub units: &'static str,
}

const COEFFICIENT: Param = Param {
    name: "coefficient",
    default: Some(1.0),
    unit: "",
    doc: "the coefficient b > 0 multiplying the kernel",
};

/// The gravitational kernels' unit radius.
const UNIT_RADIUS: Param = Param {
    name: "unit-radius",
    default: Some(1e-6),
    unit: "m",
    doc: "radius r0 of the drop of size 1, in [1e-8, 1e-2] m (sizes are volumes in its units)",
};

const MIN_SIZE: Param = Param {
    name: "min-size",
    default: Some(0.0),
    unit: "",
    doc: "smallest particle size the low-rank bound must hold for (>= 0): 0, the default, for every size x > 0; 1 for integer sizes >= 1 only (the integer-size schemes), a tighter bound and fewer rejections",
};

/// Every built-in kernel.
pub const BUILTINS: &[BuiltinInfo] = &[
    BuiltinInfo {
        name: "constant",
        family: Family::Coagulation,
        formula: "K = b",
        source: "Smoluchowski 1916",
        params: &[COEFFICIENT],
        units: "",
    },
    BuiltinInfo {
        name: "additive",
        family: Family::Coagulation,
        formula: "K = b (x + y)",
        source: "Golovin 1963",
        params: &[COEFFICIENT, MIN_SIZE],
        units: "",
    },
    BuiltinInfo {
        name: "multiplicative",
        family: Family::Coagulation,
        formula: "K = b x y",
        source: "McLeod 1962 (gels at t = 1/(b M2(0)))",
        params: &[COEFFICIENT],
        units: "",
    },
    BuiltinInfo {
        name: "product",
        family: Family::Coagulation,
        formula: "K = b (x y)^a",
        source: "Eibeck & Wagner 2000 §6.3",
        params: &[
            Param {
                name: "a",
                default: None,
                unit: "",
                doc: "the exponent a in (0, 1]",
            },
            COEFFICIENT,
        ],
        units: "",
    },
    BuiltinInfo {
        name: "homogeneous",
        family: Family::Coagulation,
        formula: "K = b 2 (x y)^g / ((x + y)^g - x^g - y^g)",
        source: "Lecot et al. 2019 §4",
        params: &[
            Param {
                name: "gamma",
                default: None,
                unit: "",
                doc: "the homogeneity g in (1, 2]",
            },
            COEFFICIENT,
        ],
        units: "",
    },
    BuiltinInfo {
        name: "free-molecular",
        family: Family::Coagulation,
        formula: "K = b (1/x + 1/y)^(1/2) (x^(1/3) + y^(1/3))^2",
        source: "Eibeck & Wagner 2000 eq. 6.2; Osinsky 2023 eq. 24 (ballistic)",
        params: &[COEFFICIENT, MIN_SIZE],
        units: "",
    },
    BuiltinInfo {
        name: "brownian",
        family: Family::Coagulation,
        formula: "K = b (x^(1/3) + y^(1/3)) (x^(-1/3) + y^(-1/3))",
        source: "Osinsky 2023 eq. 27",
        params: &[COEFFICIENT],
        units: "",
    },
    BuiltinInfo {
        name: "atmospheric",
        family: Family::Coagulation,
        formula: "K = b (i + j) (i^(1/3) + j^(1/3))^(2/3) / ((i j)^(5/9) |i^(2/3) - j^(2/3)|), K(i, i) = 4 b (integer sizes)",
        source: "Dyachenko, Matveev & Valiakhmetov, arXiv 2501.10206 (2025); docs/design/block-majorants.md",
        params: &[COEFFICIENT],
        units: "",
    },
    BuiltinInfo {
        name: "gravitational",
        family: Family::Coagulation,
        formula: "K = E(R, r) pi (r_x + r_y)^2 |v(r_x) - v(r_y)|, r_x = r0 x^(1/3); v: Simmel et al. 2002 Table 2 (Beard 1976); E: Long 1974",
        source: "Long 1974; Simmel, Trautmann & Tetzlaff 2002; Shima et al. 2009; docs/design/block-majorants.md",
        params: &[UNIT_RADIUS, COEFFICIENT],
        units: "m^3/s; time in s; sizes in volume units of a drop of radius r0",
    },
    BuiltinInfo {
        name: "gravitational-hall",
        family: Family::Coagulation,
        formula: "K = E(R, r) pi (r_x + r_y)^2 |v(r_x) - v(r_y)|, r_x = r0 x^(1/3); v: Simmel et al. 2002 Table 2 (Beard 1976); E: Hall 1980 Table 1, bilinear in (R, r/R), clamped at its edges",
        source: "Hall 1980; Simmel, Trautmann & Tetzlaff 2002; docs/design/block-majorants.md",
        params: &[UNIT_RADIUS, COEFFICIENT],
        units: "m^3/s; time in s; sizes in volume units of a drop of radius r0",
    },
    BuiltinInfo {
        name: "brownian-continuum",
        family: Family::Coagulation,
        formula: "K = (2 k_B T / 3 mu) (v^(1/3) + w^(1/3)) (v^(-1/3) + w^(-1/3))",
        source: "Friedlander, Smoke, Dust and Haze, eq. 7.12 (no slip correction)",
        params: &[
            Param {
                name: "temperature",
                default: None,
                unit: "K",
                doc: "gas temperature T > 0",
            },
            Param {
                name: "viscosity",
                default: None,
                unit: "Pa s",
                doc: "gas dynamic viscosity mu > 0",
            },
        ],
        units: "m^3/s; time in s; sizes in any volume unit",
    },
    BuiltinInfo {
        name: "free-molecular-physical",
        family: Family::Coagulation,
        formula: "K = (3/4pi)^(1/6) (6 k_B T / rho)^(1/2) (1/v + 1/w)^(1/2) (v^(1/3) + w^(1/3))^2",
        source: "Friedlander eq. 7.25; Seinfeld & Pandis eq. 13.49",
        params: &[
            Param {
                name: "temperature",
                default: None,
                unit: "K",
                doc: "gas temperature T > 0",
            },
            Param {
                name: "density",
                default: None,
                unit: "kg/m^3",
                doc: "particle material density rho > 0",
            },
            Param {
                name: "monomer-diameter",
                default: None,
                unit: "m",
                doc: "diameter of a monomer (sizes count monomers) > 0",
            },
        ],
        units: "m^3/s; time in s; sizes in monomers",
    },
    BuiltinInfo {
        name: "temperature-ballistic",
        family: Family::Temperature,
        formula: "Maxwellian hard spheres of diameter i^(1/3) with an aggregation barrier W = a (r_i r_j / (r_i + r_j))^lambda and restitution e",
        source: "Osinsky 2023 §4 and appendix A",
        params: &[
            Param {
                name: "restitution",
                default: Some(0.99),
                unit: "",
                doc: "restitution coefficient e in (0, 1]",
            },
            Param {
                name: "barrier",
                default: Some(0.1),
                unit: "",
                doc: "aggregation barrier a >= 0",
            },
            Param {
                name: "barrier-exponent",
                default: Some(0.4),
                unit: "",
                doc: "barrier exponent lambda (finite)",
            },
        ],
        units: "",
    },
    BuiltinInfo {
        name: "temperature-closed-form",
        family: Family::Temperature,
        formula: "C_agg = C_res = c sqrt((T_i/i + T_j/j)/2), B = C_agg (T_i + T_j), D_agg = C_agg T_i, D_res = gamma C_agg T_i",
        source: "the family with a closed-form solution (docs/design/temperature.md)",
        params: &[
            Param {
                name: "c",
                default: Some(1.0),
                unit: "",
                doc: "the constant c > 0",
            },
            Param {
                name: "gamma",
                default: Some(0.0),
                unit: "",
                doc: "the exponent gamma >= 0",
            },
        ],
        units: "",
    },
    BuiltinInfo {
        name: "hard-spheres",
        family: Family::Gas,
        formula: "collision rate (pi/2) (i^(1/3) + j^(1/3))^2 |(V_k - V_l).e| / V; bounce with restitution e, stick below a normal speed",
        source: "Osinsky 2023 §5",
        params: &[
            Param {
                name: "restitution",
                default: Some(0.99),
                unit: "",
                doc: "restitution coefficient e in (0, 1]",
            },
            Param {
                name: "stick-speed",
                default: Some(0.0),
                unit: "",
                doc: "collisions whose normal relative speed is below it aggregate (>= 0; 0: never)",
            },
        ],
        units: "",
    },
];

/// The names of the built-in kernels, in table order.
pub const NAMES: [&str; BUILTINS.len()] = {
    let mut out = [""; BUILTINS.len()];
    let mut i = 0;
    while i < BUILTINS.len() {
        out[i] = BUILTINS[i].name;
        i += 1;
    }
    out
};

fn unknown() -> Error {
    Error::UnknownName {
        what: "kernel",
        known: &NAMES,
    }
}

/// A built-in kernel, built: what a registry model is made of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Builtin {
    /// A coagulation kernel.
    Coagulation(Coagulation),
    /// A temperature model.
    Temperature(TemperatureModel),
    /// A hard-sphere gas.
    Gas(HardSpheres),
}

/// The table entry of a name.
pub fn find(name: &str) -> Option<&'static BuiltinInfo> {
    BUILTINS.iter().find(|b| b.name == name)
}

/// Builds the kernel `name` from `(parameter, value)` pairs; a parameter left out
/// takes its default. Errors: an unknown kernel (`Error::UnknownName`, listing the names), a
/// parameter it does not have or given twice, a required one missing
/// ([`Error::KernelParameter`]), a value outside its range.
pub fn make(name: &str, values: &[(&str, f64)]) -> Result<Builtin> {
    let info = find(name).ok_or(unknown())?;
    let mut v = [f64::NAN; 4];
    let mut given = [false; 4];
    for &(p, x) in values {
        let i = info
            .params
            .iter()
            .position(|q| q.name == p)
            .ok_or(Error::KernelParameter {
                kernel: info.name,
                param: "",
                why: "is not a parameter of this kernel (its table entry lists them)",
            })?;
        if given[i] {
            return Err(Error::KernelParameter {
                kernel: info.name,
                param: info.params[i].name,
                why: "is given twice",
            });
        }
        given[i] = true;
        v[i] = x;
    }
    build(info, &v, &given)
}

/// Builds the kernel `name` from values in the order of its table entry's
/// parameters (a C caller's array); fewer values than parameters leave the rest at
/// their defaults.
pub fn make_positional(name: &str, values: &[f64]) -> Result<Builtin> {
    let info = find(name).ok_or(unknown())?;
    if values.len() > info.params.len() {
        return Err(Error::BufferLength {
            name: "kernel parameters (more than the kernel has)",
            expected: info.params.len(),
            got: values.len(),
        });
    }
    let mut v = [f64::NAN; 4];
    let mut given = [false; 4];
    for (i, &x) in values.iter().enumerate() {
        v[i] = x;
        given[i] = true;
    }
    build(info, &v, &given)
}

fn build(info: &'static BuiltinInfo, v: &[f64; 4], given: &[bool; 4]) -> Result<Builtin> {
    let mut p = [0.0; 4];
    for (i, q) in info.params.iter().enumerate() {
        p[i] = if given[i] {
            crate::error::finite(q.name, v[i])?
        } else {
            q.default.ok_or(Error::KernelParameter {
                kernel: info.name,
                param: q.name,
                why: "is required",
            })?
        };
    }
    let coag = |k: Coagulation, b: f64| k.with_coefficient(b).map(Builtin::Coagulation);
    Ok(match info.name {
        "constant" => coag(Coagulation::constant(1.0)?, p[0])?,
        "additive" => coag(Coagulation::additive().with_min_size(p[1])?, p[0])?,
        "multiplicative" => coag(Coagulation::multiplicative(), p[0])?,
        "product" => coag(Coagulation::product(p[0])?, p[1])?,
        "homogeneous" => coag(Coagulation::homogeneous(p[0])?, p[1])?,
        "free-molecular" => coag(Coagulation::free_molecular().with_min_size(p[1])?, p[0])?,
        "brownian" => coag(Coagulation::brownian(), p[0])?,
        "atmospheric" => coag(Coagulation::atmospheric(), p[0])?,
        "gravitational" => coag(Coagulation::gravitational(p[0])?, p[1])?,
        "gravitational-hall" => coag(Coagulation::gravitational_hall(p[0])?, p[1])?,
        "brownian-continuum" => Builtin::Coagulation(Coagulation::brownian_continuum(p[0], p[1])?),
        "free-molecular-physical" => {
            let d = crate::error::positive("monomer-diameter", p[2])?;
            let v0 = core::f64::consts::PI / 6.0 * d * d * d;
            Builtin::Coagulation(Coagulation::free_molecular_physical(p[0], p[1], v0)?)
        }
        "temperature-ballistic" => Builtin::Temperature(TemperatureModel::Ballistic(
            Ballistic::new(p[0], p[1], p[2])?,
        )),
        "temperature-closed-form" => {
            Builtin::Temperature(TemperatureModel::ClosedForm(ClosedForm::new(p[0], p[1])?))
        }
        "hard-spheres" => Builtin::Gas(HardSpheres::new(p[0], p[1])?),
        _ => return Err(unknown()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::CoagulationKernel;

    /// Every entry builds from its defaults plus its required parameters, names no
    /// parameter twice, and has at most four (the builders' arrays).
    #[test]
    fn every_entry_builds() {
        for b in BUILTINS {
            assert!(b.params.len() <= 4, "{}", b.name);
            let mut vals = alloc::vec::Vec::new();
            for (i, p) in b.params.iter().enumerate() {
                assert!(
                    !b.params[..i].iter().any(|q| q.name == p.name),
                    "{}",
                    b.name
                );
                if p.default.is_none() {
                    vals.push((p.name, if p.name == "gamma" { 1.5 } else { 0.5 }));
                }
            }
            let k = make(b.name, &vals).unwrap_or_else(|e| panic!("{}: {e}", b.name));
            let fam = match k {
                Builtin::Coagulation(_) => Family::Coagulation,
                Builtin::Temperature(_) => Family::Temperature,
                Builtin::Gas(_) => Family::Gas,
            };
            assert_eq!(fam, b.family, "{}", b.name);
        }
    }

    #[test]
    fn positional_values_follow_the_table() {
        let Builtin::Coagulation(k) = make_positional("product", &[0.5, 2.0]).unwrap() else {
            panic!()
        };
        assert!((k.rate(4.0, 1.0) - 4.0).abs() < 1e-12);
        assert!(make_positional("product", &[]).is_err());
        assert!(make_positional("constant", &[1.0, 2.0]).is_err());
        assert_eq!(make("no-such-kernel", &[]), Err(unknown()));
        assert!(make("constant", &[("coefficient", f64::NAN)]).is_err());
        assert!(make("constant", &[("coefficient", 1.0), ("coefficient", 2.0)]).is_err());
    }
}
