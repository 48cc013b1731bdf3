//! The gas of low-rank DSMC (Osinsky 2023, §5): hard spheres of diameter `i^{1/3}`
//! for size i, whose collisions bounce with restitution coefficient ε or, with the
//! probability a [`Sticking`] model gives, aggregate. [`HardSpheres`] is that physics
//! as a registry model takes it (`Model::Gas`); the particles' velocities are the
//! initial state.
//!
//! # Example
//! ```
//! use coagula_core::kernel::gas::{HardSpheres, Sticking};
//! let gas = HardSpheres::new(0.9, 0.05).unwrap();
//! // below the sticking speed a collision aggregates
//! assert_eq!(gas.sticking().probability(1, 2, 0.01), 1.0);
//! assert_eq!(gas.sticking().probability(1, 2, 0.1), 0.0);
//! assert!(HardSpheres::new(1.5, 0.0).is_err());
//! ```

use crate::error::{Error, Result};

/// The probability that a collision aggregates (see the module docs).
pub trait Sticking {
    /// The probability in [0, 1] that particles of sizes `i`, `j` colliding with normal
    /// relative speed `gn = |(V_k − V_l)·e|` stick.
    fn probability(&self, i: u64, j: u64, gn: f64) -> f64;
}

/// Collisions never aggregate (the paper's test).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NeverStick;

impl Sticking for NeverStick {
    #[inline]
    fn probability(&self, _i: u64, _j: u64, _gn: f64) -> f64 {
        0.0
    }
}

/// Collisions aggregate when their normal relative speed is below `speed` (a barrier
/// model: `W = μ speed²/2` of normal kinetic energy).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StickBelow {
    /// The threshold normal relative speed (≥ 0).
    pub speed: f64,
}

impl Sticking for StickBelow {
    #[inline]
    fn probability(&self, _i: u64, _j: u64, gn: f64) -> f64 {
        if gn < self.speed { 1.0 } else { 0.0 }
    }
}

/// Hard spheres with restitution coefficient ε ∈ (0, 1] that stick when their normal
/// relative speed is below `stick_speed` (0: never, the paper's test).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HardSpheres {
    restitution: f64,
    stick_speed: f64,
}

impl HardSpheres {
    /// The gas for ε ∈ (0, 1] and a sticking speed ≥ 0 (finite).
    pub fn new(restitution: f64, stick_speed: f64) -> Result<Self> {
        check_restitution(restitution)?;
        if !(stick_speed >= 0.0 && stick_speed.is_finite()) {
            return Err(Error::OutOfRange {
                name: "stick speed",
                value: stick_speed,
                range: "[0, inf)",
            });
        }
        Ok(HardSpheres {
            restitution,
            stick_speed,
        })
    }

    /// The restitution coefficient ε.
    pub fn restitution(&self) -> f64 {
        self.restitution
    }

    /// The sticking model.
    pub fn sticking(&self) -> StickBelow {
        StickBelow {
            speed: self.stick_speed,
        }
    }

    /// A fingerprint of the parameters (for checkpoints).
    pub fn fingerprint(&self) -> u64 {
        crate::checkpoint::fingerprint([
            0x4841_5244_5350_4852, // "HARDSPHR"
            self.restitution.to_bits(),
            self.stick_speed.to_bits(),
        ])
    }
}

/// Checks a restitution coefficient: ε ∈ (0, 1].
pub(crate) fn check_restitution(eps: f64) -> Result<()> {
    if eps > 0.0 && eps <= 1.0 {
        Ok(())
    } else {
        Err(Error::OutOfRange {
            name: "restitution coefficient",
            value: eps,
            range: "(0, 1]",
        })
    }
}
