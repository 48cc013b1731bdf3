//! What a registry build takes besides its settings: the physics ([`Model`]) and the
//! initial state ([`Init`]).

use crate::error::{Error, Result};
use crate::kernel::builtin::Builtin;
use crate::kernel::gas::HardSpheres;
use crate::kernel::temperature::TemperatureModel;
use crate::kernel::{CoagulationKernel, FragmentationKernel};

/// The physics of a simulation: a coagulation kernel with fragmentation, a
/// temperature model (Osinsky 2023 §4), or a hard-sphere gas (§5). A scheme takes one
/// kind ([`SchemeInfo::model`](super::SchemeInfo::model)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model<K, F> {
    /// A coagulation kernel and a fragmentation kernel (`NoFragmentation` or
    /// `Fragmentation::None` for pure coagulation).
    Coagulation {
        /// The coagulation kernel.
        kernel: K,
        /// The fragmentation kernel.
        fragmentation: F,
    },
    /// A temperature model: the partial temperatures come with the initial state.
    Temperature(TemperatureModel),
    /// A gas of hard spheres: the velocities come with the initial state.
    Gas(HardSpheres),
}

/// The kind of a [`Model`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelKind {
    /// [`Model::Coagulation`].
    Coagulation,
    /// [`Model::Temperature`].
    Temperature,
    /// [`Model::Gas`].
    Gas,
}

impl<K, F> Model<K, F> {
    /// A coagulation model: `kernel` with `fragmentation`.
    pub fn coagulation(kernel: K, fragmentation: F) -> Self {
        Model::Coagulation {
            kernel,
            fragmentation,
        }
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel> Model<K, F> {
    /// The kind.
    pub fn kind(&self) -> ModelKind {
        match self {
            Model::Coagulation { .. } => ModelKind::Coagulation,
            Model::Temperature(_) => ModelKind::Temperature,
            Model::Gas(_) => ModelKind::Gas,
        }
    }

    /// Whether particles break up (a coagulation model with a fragmentation kernel).
    pub fn fragments(&self) -> bool {
        matches!(self, Model::Coagulation { fragmentation, .. } if !fragmentation.is_none())
    }

    /// A fingerprint of the physics and its parameters (what a checkpoint must be
    /// restored under).
    pub fn fingerprint(&self) -> u64 {
        match self {
            Model::Coagulation {
                kernel,
                fragmentation,
            } => crate::checkpoint::fingerprint([
                1,
                kernel.fingerprint(),
                fragmentation.fingerprint(),
            ]),
            Model::Temperature(m) => crate::checkpoint::fingerprint([2, m.fingerprint()]),
            Model::Gas(g) => crate::checkpoint::fingerprint([3, g.fingerprint()]),
        }
    }

    /// The coagulation and fragmentation kernels (what the coagulation schemes build
    /// from). Errors: another kind of model (the registry checks the kind first).
    pub fn kernels(&self) -> Result<(K, F)>
    where
        K: Clone,
        F: Clone,
    {
        match self {
            Model::Coagulation {
                kernel,
                fragmentation,
            } => Ok((kernel.clone(), fragmentation.clone())),
            _ => Err(Error::Unsupported {
                what: "model: this scheme takes a coagulation kernel",
            }),
        }
    }

    /// The model of a built-in kernel (its coagulation kernel through `wrap`, a front
    /// end's kernel type) with `fragmentation`. Errors: fragmentation with a temperature
    /// model or a gas (only coagulation kernels break particles).
    pub fn of_builtin(
        b: Builtin,
        wrap: impl FnOnce(crate::kernel::Coagulation) -> K,
        fragmentation: F,
    ) -> Result<Self> {
        match b {
            Builtin::Coagulation(k) => Ok(Model::Coagulation {
                kernel: wrap(k),
                fragmentation,
            }),
            _ if !fragmentation.is_none() => Err(Error::Unsupported {
                what: "fragmentation with a temperature model or a gas (only coagulation kernels take a fragmentation kernel)",
            }),
            Builtin::Temperature(m) => Ok(Model::Temperature(m)),
            Builtin::Gas(g) => Ok(Model::Gas(g)),
        }
    }
}

/// The initial state of a build.
#[derive(Clone, Copy, Debug)]
pub enum Init<'a> {
    /// `counts[i − 1] = N_i` particles of size i in volume `volume`.
    Counts {
        /// The counts.
        counts: &'a [u64],
        /// The volume V > 0.
        volume: f64,
    },
    /// Particle sizes. What they are samples of is the scheme's
    /// ([`SchemeInfo::sizes`](super::SchemeInfo::sizes)): for the mass-flow schemes
    /// samples of the mass distribution `x c0(x) / M1`, each particle carrying
    /// `mass / N`; for direct simulation and low-rank over sizes samples of the number
    /// distribution, in the volume `Σ sizes / mass`.
    Sizes {
        /// The sizes (each finite and > 0).
        sizes: &'a [f64],
        /// The mass M1 > 0 they carry.
        mass: f64,
    },
    /// Counts with the partial temperature of each size (temperature models):
    /// `counts[i − 1]` particles of size i at `temperatures[i − 1]`.
    Temperatures {
        /// The counts.
        counts: &'a [u64],
        /// The temperatures (finite, ≥ 0), as many as counts.
        temperatures: &'a [f64],
        /// The volume V > 0.
        volume: f64,
    },
    /// Particles with velocities (a gas): particle p has size `sizes[p] ≥ 1` and
    /// velocity `velocities[3p..3p + 3]`.
    Velocities {
        /// The sizes.
        sizes: &'a [u64],
        /// Three components per particle.
        velocities: &'a [f64],
        /// The volume V > 0.
        volume: f64,
    },
}

/// The kind of an [`Init`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitKind {
    /// [`Init::Counts`].
    Counts,
    /// [`Init::Sizes`].
    Sizes,
    /// [`Init::Temperatures`].
    Temperatures,
    /// [`Init::Velocities`].
    Velocities,
}

impl Init<'_> {
    /// The kind.
    pub fn kind(&self) -> InitKind {
        match self {
            Init::Counts { .. } => InitKind::Counts,
            Init::Sizes { .. } => InitKind::Sizes,
            Init::Temperatures { .. } => InitKind::Temperatures,
            Init::Velocities { .. } => InitKind::Velocities,
        }
    }
}

/// The volume in which samples of the number distribution `sizes` carry the mass
/// `mass`: `Σ sizes / mass` (direct simulation, low-rank over sizes). Errors: a mass
/// or a total that is not finite and positive.
pub fn number_volume(sizes: &[f64], mass: f64) -> Result<f64> {
    crate::error::positive("mass", mass)?;
    // each size first: a NaN or negative one is named as such, not as a bad total
    if let Some(&x) = sizes.iter().find(|&&x| !(x > 0.0 && x.is_finite())) {
        return Err(Error::OutOfRange {
            name: "initial particle size",
            value: x,
            range: "(0, inf)",
        });
    }
    let total: f64 = sizes.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::OutOfRange {
            name: "total size of the initial particles",
            value: total,
            range: "(0, inf)",
        });
    }
    crate::error::positive("volume (total size / mass)", total / mass)
}

/// What [`Init::Sizes`] holds samples of, for a scheme that starts from sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Samples {
    /// The scheme takes no sizes.
    None,
    /// Samples of the mass distribution `x c0(x) / M1` (mass-flow schemes).
    Mass,
    /// Samples of the number distribution (direct simulation).
    Number,
}

/// An initial state the facade owns: the smallest of the same shape that a scheme
/// builds from, for a clone (built, then the original's checkpoint restored into it).
#[derive(Clone, Debug, PartialEq)]
pub enum Blank {
    /// Counts and volume.
    Counts(alloc::vec::Vec<u64>, f64),
    /// `n` particles of size `size` carrying `mass`.
    Sizes {
        /// The size.
        size: f64,
        /// How many.
        n: usize,
        /// The mass.
        mass: f64,
        /// The particle capacity to build with (direct simulation: the original's,
        /// which its checkpoint is for; 0 for the other schemes).
        capacity: usize,
    },
    /// Two monomers at temperature 1.
    Temperatures,
    /// Two monomers at rest.
    Velocities,
}

impl Blank {
    /// Builds a sim from this blank under `built` (the settings as built, with the
    /// capacity a sizes blank records): `build` gets the initial state and the
    /// settings. What a clone, and a front end rebuilding a sim to restore a
    /// checkpoint into (Python's pickling), build before restoring.
    pub fn build<R>(
        &self,
        build: impl FnOnce(&Init<'_>, &super::Options) -> Result<R>,
        built: &super::Options,
    ) -> Result<R> {
        let (counts, sizes, velocities);
        let init = match self {
            Blank::Counts(c, v) => Init::Counts {
                counts: c,
                volume: *v,
            },
            Blank::Sizes { size, n, mass, .. } => {
                let mut v = alloc::vec::Vec::new();
                crate::memory::try_reserve(&mut v, *n)?;
                v.resize(*n, *size);
                sizes = v;
                Init::Sizes {
                    sizes: &sizes,
                    mass: *mass,
                }
            }
            Blank::Temperatures => Init::Temperatures {
                counts: &[2],
                temperatures: &[1.0],
                volume: 1.0,
            },
            Blank::Velocities => {
                counts = [1u64, 1];
                velocities = [0.0; 6];
                Init::Velocities {
                    sizes: &counts,
                    velocities: &velocities,
                    volume: 1.0,
                }
            }
        };
        let opts = match self {
            Blank::Sizes { capacity, .. } if *capacity > 0 => {
                built.clone().with_capacity(*capacity)
            }
            _ => built.clone(),
        };
        build(&init, &opts)
    }
}
