//! Initial states as Python objects: a size distribution of core's `initial` module
//! (turned into the start the chosen scheme takes — counts, samples of the number or
//! of the mass distribution — by core, as the CLI and the C ABI do), or an explicit
//! state (counts, sizes, counts at temperatures, particles with velocities).

use crate::arrays::{counts_arg, reals_arg};
use crate::py_err;
use coagula_core::initial::{Distribution, lattice_shift};
use coagula_core::scheme::facade::{Options, SchemeInfo, Start};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

#[derive(Clone, Debug)]
enum What {
    /// A distribution, its simulation particles and number concentration, and the
    /// temperatures of a temperature model's or a gas's sizes (empty otherwise).
    Distribution {
        dist: Distribution,
        particles: usize,
        concentration: f64,
        temperatures: Vec<f64>,
    },
    /// A state as given.
    Given(Start),
}

/// An initial state: build one with the static methods (`Initial.exponential(mean,
/// particles=…)`, `Initial.counts(counts, volume)`, …) and pass it as `init=` to a
/// `Simulation`. A distribution becomes what the scheme takes (counts on the integer
/// sizes, or the quantile lattice of the number or the mass distribution, shifted by
/// a uniform of the seed for schemes that draw random numbers, centred for
/// deterministic QMC), as `coagula run` does.
///
/// >>> import coagula
/// >>> init = coagula.Initial.monodisperse(1, particles=1000)
/// >>> sim = coagula.Simulation("lowrank", "additive", init, seed=1)
/// >>> sim.particles
/// 1000
#[pyclass(module = "coagula", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Initial {
    what: What,
}

fn particles_of(n: u64) -> PyResult<usize> {
    usize::try_from(n)
        .ok()
        .filter(|&n| n >= 1)
        .ok_or_else(|| PyValueError::new_err(format!("particles must be >= 1 (got {n})")))
}

impl Initial {
    fn distribution(
        dist: Distribution,
        particles: u64,
        concentration: f64,
        temperatures: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        dist.check().map_err(py_err)?;
        Ok(Initial {
            what: What::Distribution {
                dist,
                particles: particles_of(particles)?,
                concentration,
                temperatures: temperatures.unwrap_or_default(),
            },
        })
    }

    /// The start scheme `info` takes under `opts` (its seed and stream).
    pub(crate) fn start(&self, info: &SchemeInfo, opts: &Options) -> PyResult<Start> {
        match &self.what {
            What::Given(s) => Ok(s.clone()),
            What::Distribution {
                dist,
                particles,
                concentration,
                temperatures,
            } => {
                // the start's particles must fit the memory budget before they are
                // drawn (10^12 particles would otherwise end the interpreter)
                let bytes = (*particles as u64).saturating_mul(8);
                if bytes > opts.memory_budget() as u64 {
                    return Err(pyo3::exceptions::PyMemoryError::new_err(format!(
                        "particles = {particles}: the start alone needs {bytes} bytes, above the memory budget of {} (the memory_budget option)",
                        opts.memory_budget()
                    )));
                }
                let r = if temperatures.is_empty() {
                    let shift = lattice_shift(info.randomised(opts), opts.seed(), opts.stream());
                    dist.start(info, *particles, *concentration, 1.0, shift)
                } else {
                    dist.start_at_temperatures(
                        info,
                        *particles,
                        *concentration,
                        temperatures,
                        opts.seed(),
                        opts.stream(),
                    )
                };
                r.map_err(py_err)
            }
        }
    }
}

#[pymethods]
impl Initial {
    /// Every particle of size `size` (an integer for the integer-size schemes), at
    /// number concentration `concentration`; with `temperatures` (one per size up to
    /// `size`) the start of a temperature model or a gas.
    #[staticmethod]
    #[pyo3(signature = (size=1.0, *, particles, concentration=1.0, temperatures=None))]
    fn monodisperse(
        size: f64,
        particles: u64,
        concentration: f64,
        temperatures: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        Self::distribution(
            Distribution::Monodisperse { size },
            particles,
            concentration,
            temperatures,
        )
    }

    /// `c(x) ∝ e^{−x/mean}`.
    #[staticmethod]
    #[pyo3(signature = (mean=1.0, *, particles, concentration=1.0))]
    fn exponential(mean: f64, particles: u64, concentration: f64) -> PyResult<Self> {
        Self::distribution(
            Distribution::Exponential { mean },
            particles,
            concentration,
            None,
        )
    }

    /// Log-normal of median `median` and geometric standard deviation `gsd`.
    #[staticmethod]
    #[pyo3(signature = (median, gsd, *, particles, concentration=1.0))]
    fn lognormal(median: f64, gsd: f64, particles: u64, concentration: f64) -> PyResult<Self> {
        Self::distribution(
            Distribution::Lognormal { median, gsd },
            particles,
            concentration,
            None,
        )
    }

    /// `counts[i]` particles of size `i + 1` in volume `volume` (the integer-size
    /// schemes take them as they are; the others sample them); with `temperatures`
    /// (one per size) the start of a temperature model, or of a gas (velocities
    /// Maxwellian, drawn from the seed).
    #[staticmethod]
    #[pyo3(signature = (counts, volume=1.0, *, temperatures=None))]
    fn counts(
        counts: &Bound<'_, PyAny>,
        volume: f64,
        temperatures: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let counts = counts_arg("counts", counts)?;
        match temperatures {
            None => Ok(Initial {
                what: What::Given(Start::Counts { counts, volume }),
            }),
            Some(t) => {
                let temperatures = reals_arg("temperatures", t)?;
                if temperatures.len() != counts.len() {
                    return Err(PyValueError::new_err(format!(
                        "temperatures: one per size ({} counts), got {}",
                        counts.len(),
                        temperatures.len()
                    )));
                }
                let total = counts.iter().fold(0u64, |a, &b| a.saturating_add(b));
                if !(volume > 0.0 && volume.is_finite()) {
                    return Err(PyValueError::new_err(format!(
                        "volume must be finite and > 0 (got {volume})"
                    )));
                }
                Self::distribution(
                    Distribution::Counts(counts),
                    total.max(1),
                    total as f64 / volume,
                    Some(temperatures),
                )
            }
        }
    }

    /// Particle sizes carrying mass `mass` (what they are samples of is the scheme's:
    /// `coagula.schemes()` gives each scheme's `samples`).
    #[staticmethod]
    #[pyo3(signature = (sizes, mass))]
    fn sizes(sizes: &Bound<'_, PyAny>, mass: f64) -> PyResult<Self> {
        Ok(Initial {
            what: What::Given(Start::Sizes {
                sizes: reals_arg("sizes", sizes)?,
                mass,
            }),
        })
    }

    /// Particles of integer sizes `sizes` with velocities (an array of shape (n, 3))
    /// in volume `volume`: the start of a gas (the dsmc schemes).
    #[staticmethod]
    #[pyo3(signature = (sizes, velocities, volume=1.0))]
    fn velocities(
        sizes: &Bound<'_, PyAny>,
        velocities: &Bound<'_, PyAny>,
        volume: f64,
    ) -> PyResult<Self> {
        let sizes = counts_arg("sizes", sizes)?;
        let v = crate::arrays::vectors_arg("velocities", velocities)?;
        if v.len() != 3 * sizes.len() {
            return Err(PyValueError::new_err(format!(
                "velocities: shape ({}, 3) for {} sizes, got {} values",
                sizes.len(),
                sizes.len(),
                v.len()
            )));
        }
        Ok(Initial {
            what: What::Given(Start::Velocities {
                sizes,
                velocities: v,
                volume,
            }),
        })
    }

    fn __repr__(&self) -> String {
        match &self.what {
            What::Distribution {
                dist, particles, ..
            } => format!("coagula.Initial({dist:?}, particles={particles})"),
            What::Given(Start::Counts { counts, volume }) => {
                format!(
                    "coagula.Initial.counts(<{} sizes>, volume={volume})",
                    counts.len()
                )
            }
            What::Given(Start::Sizes { sizes, mass }) => {
                format!(
                    "coagula.Initial.sizes(<{} sizes>, mass={mass})",
                    sizes.len()
                )
            }
            What::Given(_) => "coagula.Initial(<explicit state>)".into(),
        }
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Initial>()
}
