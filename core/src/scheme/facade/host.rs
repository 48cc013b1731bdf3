//! A population built from a host's class numbers, for every kind of state
//! ([`Simulation::set_classes`]; the projection the other way is
//! [`crate::classes::Classes::project`] over [`Observe::points`]).

use super::{Law, Simulation, State};
use crate::classes::Classes;
use crate::error::{Error, Result};
use crate::memory::{try_reserve, within_budget};
use alloc::vec::Vec;
use rand_core::Rng;

/// Largest exact integer of a double: pivots of integer-size schemes stay below it.
const EXACT: f64 = 9_007_199_254_740_992.0;

/// [`Simulation::set_classes`].
pub(super) fn set_classes<K, F, G, S>(
    sim: &mut S,
    classes: &Classes,
    numbers: &[f64],
    rng: &mut G,
) -> Result<()>
where
    S: Simulation<K, F, G> + ?Sized,
    G: Rng + ?Sized,
{
    match sim.info().law {
        Law::Temperature | Law::Gas => Err(Error::Unsupported {
            what: "classes: a temperature or gas state is more than particle numbers per size (build a new simulation instead)",
        }),
        Law::MassFlow | Law::TimeStepped => mass_weighted(sim, classes, numbers, rng),
        Law::FiniteN => {
            let integer = matches!(sim.state(), State::Counts(..));
            let volume = sim.volume();
            if integer {
                for &x in classes.pivots() {
                    if !((1.0..EXACT).contains(&x) && x == libm::floor(x)) {
                        return Err(Error::OutOfRange {
                            name: "pivot (a scheme of integer sizes takes integer pivots)",
                            value: x,
                            range: "{1, 2, …, 2^53 − 1}",
                        });
                    }
                }
            }
            let counts = classes.counts(numbers, volume, rng)?;
            if integer {
                let (mut sizes, mut kept) = (Vec::new(), Vec::new());
                try_reserve(&mut sizes, counts.len())?;
                try_reserve(&mut kept, counts.len())?;
                for (&x, &c) in classes.pivots().iter().zip(&counts) {
                    if c > 0 {
                        sizes.push(x as u64);
                        kept.push(c);
                    }
                }
                sim.set_pairs(&sizes, &kept, volume)
            } else {
                let total = counts
                    .iter()
                    .try_fold(0u64, |a, &c| a.checked_add(c))
                    .ok_or(Error::Overflow {
                        name: "particle number",
                    })?;
                let len = usize::try_from(total).map_err(|_| Error::Overflow {
                    name: "particle number",
                })?;
                within_budget(
                    len.checked_mul(core::mem::size_of::<f64>()),
                    crate::memory::default_memory_budget(),
                )?;
                let mut sizes = Vec::new();
                try_reserve(&mut sizes, len)?;
                for (&x, &c) in classes.pivots().iter().zip(&counts) {
                    sizes.extend(core::iter::repeat_n(x, c as usize));
                }
                sim.set_sizes(&sizes)
            }
        }
    }
}

/// The mass-flow schemes: their particles carry equal mass, so class i gets the
/// particle fraction `x_i N_i / M` of its mass, placed by systematic sampling (one
/// uniform offset, N equally spaced points on the cumulative mass): every class's
/// expected particle number is exact, and the scheme keeps its particle number.
fn mass_weighted<K, F, G, S>(
    sim: &mut S,
    classes: &Classes,
    numbers: &[f64],
    rng: &mut G,
) -> Result<()>
where
    S: Simulation<K, F, G> + ?Sized,
    G: Rng + ?Sized,
{
    classes.check_numbers(numbers)?;
    let mass: f64 = numbers
        .iter()
        .zip(classes.pivots())
        .map(|(n, x)| n * x)
        .sum();
    crate::error::positive(
        "mass of the class numbers (a mass-flow state carries mass)",
        mass,
    )?;
    let n = usize::try_from(sim.particles()).map_err(|_| Error::Overflow {
        name: "particle number",
    })?;
    let now = sim.moment(1.0);
    if n == 0 || now.is_nan() || now <= 0.0 {
        return Err(Error::Unsupported {
            what: "classes: this mass-flow state has no particles left to carry the mass",
        });
    }
    // the mass parameter over the mass the particles now represent: 1 for massflow,
    // N0/N for mfa, whose particles past b_N left as gel
    let scale = (now + sim.gel_mass().unwrap_or(0.0)) / now;
    // (the cumulative mass is summed in the order `mass` was, so it ends at `mass`
    // exactly and every point `< mass` lands in a class that has mass)
    let mut sizes = Vec::new();
    try_reserve(&mut sizes, n)?;
    let offset = crate::random::unit_f64(rng.next_u64());
    let mut class = 0usize;
    let mut upto = numbers[0] * classes.pivots()[0];
    for k in 0..n {
        let target = (k as f64 + offset) / n as f64 * mass;
        while upto <= target && class + 1 < classes.len() {
            class += 1;
            upto += numbers[class] * classes.pivots()[class];
        }
        sizes.push(classes.pivots()[class]);
    }
    // (checked before the state changes: set_mass refuses only a bad mass)
    let mass = crate::error::positive("mass parameter", mass * scale)?;
    sim.set_sizes(&sizes)?;
    sim.set_mass(mass)
}
