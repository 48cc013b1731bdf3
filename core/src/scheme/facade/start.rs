//! The start of a registry build drawn from a size distribution
//! ([`Distribution`](crate::initial::Distribution)): counts on a size grid, samples of
//! the number or of the mass distribution — whichever the scheme's entry takes
//! ([`SchemeInfo::sizes`]) — or counts at temperatures and a Maxwellian gas (Osinsky
//! 2023 §§4–5). The quantile lattices are `initial`'s; what a scheme takes is the
//! registry's, so the choice between them is made here.

use super::{Init, InitKind, Samples, SchemeInfo};
use crate::error::{Error, Result};
use crate::initial::{Distribution, counts_on_grid, maxwellian_of_seed, out_of_range, quantiles};
use alloc::vec;
use alloc::vec::Vec;

/// A start a registry build borrows ([`Start::init`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// Counts and volume.
    Counts {
        /// `counts[i − 1] = N_i`.
        counts: Vec<u64>,
        /// The volume.
        volume: f64,
    },
    /// Particle sizes and the mass they carry.
    Sizes {
        /// The sizes.
        sizes: Vec<f64>,
        /// The mass M1.
        mass: f64,
    },
    /// Counts at temperatures, and the volume (temperature models).
    Temperatures {
        /// `counts[i − 1] = N_i`.
        counts: Vec<u64>,
        /// `temperatures[i − 1] = T_i`.
        temperatures: Vec<f64>,
        /// The volume.
        volume: f64,
    },
    /// Particles with velocities, and the volume (gases).
    Velocities {
        /// The sizes.
        sizes: Vec<u64>,
        /// Three components per particle.
        velocities: Vec<f64>,
        /// The volume.
        volume: f64,
    },
}

impl Start {
    /// The initial state of a build.
    pub fn init(&self) -> Init<'_> {
        match self {
            Start::Counts { counts, volume } => Init::Counts {
                counts,
                volume: *volume,
            },
            Start::Sizes { sizes, mass } => Init::Sizes { sizes, mass: *mass },
            Start::Temperatures {
                counts,
                temperatures,
                volume,
            } => Init::Temperatures {
                counts,
                temperatures,
                volume: *volume,
            },
            Start::Velocities {
                sizes,
                velocities,
                volume,
            } => Init::Velocities {
                sizes,
                velocities,
                volume: *volume,
            },
        }
    }
}

impl Distribution {
    /// The start of scheme `info` with `n` simulation particles (ignored for explicit
    /// lists, which give theirs) at number concentration `c0`: counts on a grid where
    /// size i stands for `i · grid` (integer-size schemes; `grid` 1 except from a
    /// continuous distribution), or the samples the scheme takes
    /// ([`SchemeInfo::sizes`]), the quantile lattice shifted by `shift ∈ [0, 1)`.
    /// Errors: the distribution's own, sizes off the integer grid or past `limit` or
    /// 1e7 grid units (a dense start), a scheme that takes neither counts nor sizes.
    pub fn start(
        &self,
        info: &SchemeInfo,
        n: usize,
        c0: f64,
        grid: f64,
        shift: f64,
    ) -> Result<Start> {
        self.check()?;
        crate::error::positive("concentration", c0)?;
        crate::error::positive("grid", grid)?;
        let counts_scheme = info.inits.contains(&InitKind::Counts);
        let mass = match info.sizes {
            Samples::Mass => true,
            Samples::Number => false,
            Samples::None if counts_scheme => false,
            Samples::None => {
                return Err(Error::Unsupported {
                    what: "initial distribution: this scheme starts from counts with temperatures or particles with velocities",
                });
            }
        };
        // (allocations that fail are a capacity error, not an abort)
        let lattice = |n: usize| -> Result<Vec<f64>> {
            let mut v = Vec::new();
            crate::memory::try_reserve(&mut v, n)?;
            v.extend((0..n).map(|k| self.inverse((k as f64 + shift) / n as f64, mass)));
            Ok(v)
        };
        let filled = |n: usize, x: f64| -> Result<Vec<f64>> {
            let mut v = Vec::new();
            crate::memory::try_reserve(&mut v, n)?;
            v.resize(n, x);
            Ok(v)
        };
        Ok(match self {
            Distribution::Monodisperse { size } => {
                if counts_scheme {
                    if libm::trunc(*size) != *size || *size > 1e7 {
                        return Err(out_of_range(
                            "size",
                            *size,
                            "integers up to 1e7 (integer-size schemes)",
                        ));
                    }
                    let mut counts = vec![0u64; *size as usize];
                    counts[*size as usize - 1] = n as u64;
                    Start::Counts {
                        counts,
                        volume: n as f64 / c0,
                    }
                } else {
                    Start::Sizes {
                        sizes: filled(n, *size)?,
                        mass: c0 * size,
                    }
                }
            }
            Distribution::Exponential { .. } | Distribution::Lognormal { .. } => {
                let xs = lattice(n)?;
                if counts_scheme {
                    Start::Counts {
                        counts: counts_on_grid(xs.iter().copied(), grid)?,
                        volume: n as f64 / c0,
                    }
                } else {
                    Start::Sizes {
                        sizes: xs,
                        mass: c0 * self.mean(),
                    }
                }
            }
            Distribution::Sizes(x) => {
                let mean = self.mean();
                if counts_scheme {
                    if x.iter().any(|v| libm::trunc(*v) != *v) {
                        return Err(Error::Unsupported {
                            what: "sizes that are not integers on an integer-size scheme",
                        });
                    }
                    Start::Counts {
                        counts: counts_on_grid(x.iter().copied(), 1.0)?,
                        volume: x.len() as f64 / c0,
                    }
                } else if mass {
                    let mut pairs: Vec<(f64, f64)> = x.iter().map(|&v| (v, 1.0)).collect();
                    Start::Sizes {
                        sizes: quantiles(x.len(), &mut pairs, true),
                        mass: c0 * mean,
                    }
                } else {
                    // samples of the number distribution as given, in the volume n / c0
                    Start::Sizes {
                        sizes: x.clone(),
                        mass: c0 * mean,
                    }
                }
            }
            Distribution::Counts(c) => {
                let total = self.particles().unwrap_or(0);
                if counts_scheme {
                    Start::Counts {
                        counts: c.clone(),
                        volume: total as f64 / c0,
                    }
                } else {
                    let mut pairs: Vec<(f64, f64)> = c
                        .iter()
                        .enumerate()
                        .filter(|&(_, &v)| v > 0)
                        .map(|(k, &v)| ((k + 1) as f64, v as f64))
                        .collect();
                    Start::Sizes {
                        sizes: quantiles(n, &mut pairs, mass),
                        mass: c0 * self.mean(),
                    }
                }
            }
        })
    }

    /// The start of a temperature-dependent scheme or a gas (Osinsky 2023 §§4–5) from
    /// a monodisperse integer size or counts, `n` particles of a monodisperse start, at
    /// number concentration `c0`, size i at temperature `temperatures[i − 1]` (one per
    /// size); a gas's velocities Maxwellian ([`maxwellian_of_seed`]) from the velocity
    /// stream of `(seed, stream)`. Errors: another distribution, lengths that differ,
    /// the checks of the draw.
    pub fn start_at_temperatures(
        &self,
        info: &SchemeInfo,
        n: usize,
        c0: f64,
        temperatures: &[f64],
        seed: u64,
        stream: u64,
    ) -> Result<Start> {
        self.check()?;
        crate::error::positive("concentration", c0)?;
        let counts = match self {
            Distribution::Monodisperse { size } if libm::trunc(*size) == *size && *size <= 1e7 => {
                let mut c = vec![0u64; *size as usize];
                c[*size as usize - 1] = n as u64;
                c
            }
            Distribution::Counts(c) => c.clone(),
            _ => {
                return Err(Error::Unsupported {
                    what: "initial distribution: a temperature model or a gas starts from a monodisperse integer size or counts",
                });
            }
        };
        if temperatures.len() != counts.len() {
            return Err(Error::BufferLength {
                name: "temperatures (one per size)",
                expected: counts.len(),
                got: temperatures.len(),
            });
        }
        let total = counts.iter().fold(0u64, |a, &b| a.saturating_add(b));
        let volume = total as f64 / c0;
        if info.inits.contains(&InitKind::Velocities) {
            let (sizes, velocities) = maxwellian_of_seed(&counts, temperatures, seed, stream)?;
            Ok(Start::Velocities {
                sizes,
                velocities,
                volume,
            })
        } else if info.inits.contains(&InitKind::Temperatures) {
            Ok(Start::Temperatures {
                counts,
                temperatures: temperatures.to_vec(),
                volume,
            })
        } else {
            Err(Error::Unsupported {
                what: "initial temperatures: this scheme takes a coagulation kernel",
            })
        }
    }
}
