//! The size-count population shared by the low-rank schemes and their baselines: the
//! particle number N, its doubling reference N0, the volume V, the size limit and the
//! memory budget — with the rules they obey, in one place:
//!
//! * **validation**: counts with at least one particle and no overflow, a positive finite
//!   volume ([`Population::new`]);
//! * **particle doubling**: when fewer than `N0/2` particles remain, every count, N and
//!   V double, which keeps the statistical error constant at constant cost
//!   ([`Population::doubling_due`], [`Population::double`]);
//! * **size limit**: a merge beyond it is [`Error::Capacity`] ([`Population::merged`]);
//! * **memory**: growth is checked against the budget and allocates with `try_reserve`,
//!   so running out is [`Error::Capacity`] with the state as before, never an abort.

use crate::error::{Error, Result};
use alloc::vec::Vec;

#[cfg(feature = "std")]
pub use crate::memory::machine_memory_budget;
pub use crate::memory::{DEFAULT_MEMORY_BUDGET, DEFAULT_SIZE_LIMIT, default_memory_budget};
pub(crate) use crate::memory::{shrink_spare, try_reserve, try_resize, within_budget};

/// Refuses counts that reach past the size limit (`counts.len()` sizes).
pub(crate) fn check_within_limit(counts: &[u64], limit: u64) -> Result<()> {
    if counts.len() as u64 > limit {
        return Err(Error::Capacity {
            name: "maximum particle size (size-limit)",
            capacity: usize::try_from(limit).unwrap_or(usize::MAX),
        });
    }
    Ok(())
}

/// N, N0, V and the limits of a size-count population (the counts themselves live in
/// each scheme's own layout).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Population {
    /// Simulation particles now.
    pub n: u64,
    /// The particle-doubling reference: doubling happens when `n < n0 / 2`.
    pub n0: u64,
    /// The volume V.
    pub volume: f64,
    /// Largest particle size allowed.
    pub size_limit: u64,
    /// Bytes the growing tables may use.
    pub memory_budget: usize,
    /// Whether particle doubling is on (off while processes beside coagulation run:
    /// `docs/design/processes.md`). Not part of a checkpoint: the facade sets it.
    pub doubling: bool,
}

impl Population {
    /// The population of `counts[i − 1] = N_i` in `volume`, with the default limits
    /// (no particle at all is a valid, empty system); errors for an overflowing total
    /// or a volume that is not positive and finite.
    pub fn new(counts: &[u64], volume: f64) -> Result<Self> {
        crate::error::positive("volume", volume)?;
        let n = check_counts(counts)?;
        Ok(Population {
            n,
            n0: n,
            volume,
            size_limit: DEFAULT_SIZE_LIMIT,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            doubling: true,
        })
    }

    /// The same population with a memory budget of `bytes`.
    pub fn with_memory_budget(mut self, bytes: usize) -> Self {
        self.memory_budget = bytes;
        self
    }

    /// Fewer than `N0/2` particles remain: the counts must double.
    #[inline]
    pub fn doubling_due(&self) -> bool {
        self.doubling && self.n < self.n0 / 2
    }

    /// Doubles N and V (the scheme doubles its counts).
    #[inline]
    pub fn double(&mut self) {
        self.n *= 2;
        self.volume *= 2.0;
    }

    /// The size of `x` merged with `y`, or [`Error::Capacity`] beyond the size limit
    /// (saturating: a limit near `u64::MAX` cannot let the sum wrap).
    #[inline]
    pub fn merged(&self, x: u64, y: u64) -> Result<u64> {
        self.check_size(x.saturating_add(y))
    }

    /// The particle number after adding a particle of `size` (a single-particle edit),
    /// or `Err` for size 0 ([`Error::OutOfRange`]), a size past the limit
    /// ([`Self::check_size`]) or a number past u64 ([`Error::Overflow`]).
    pub fn check_added(&self, size: u64) -> Result<u64> {
        if size == 0 {
            return Err(Error::OutOfRange {
                name: "size",
                value: 0.0,
                range: "1 or more",
            });
        }
        self.check_size(size)?;
        self.n.checked_add(1).ok_or(Error::Overflow {
            name: "particle number",
        })
    }

    /// `Err(Capacity)` for a particle beyond the size limit (or at `u64::MAX`, where a
    /// saturated sum lands).
    #[inline]
    pub fn check_size(&self, size: u64) -> Result<u64> {
        if size > self.size_limit || size == u64::MAX {
            return Err(Error::Capacity {
                name: "maximum particle size",
                capacity: usize::try_from(self.size_limit).unwrap_or(usize::MAX),
            });
        }
        Ok(size)
    }

    /// `Err(Capacity)` unless `bytes` (None: overflowed) fits the memory budget.
    pub fn within_budget(&self, bytes: Option<usize>) -> Result<()> {
        within_budget(bytes, self.memory_budget)
    }
}

/// Checks `(size, count)` pairs (sizes ≥ 1, within `size_limit`, each at most once)
/// and returns the largest size.
pub(crate) fn check_pairs(sizes: &[u64], counts: &[u64], size_limit: u64) -> Result<u64> {
    if sizes.len() != counts.len() {
        return Err(Error::BufferLength {
            name: "counts (one per size)",
            expected: sizes.len(),
            got: counts.len(),
        });
    }
    let mut sorted: Vec<u64> = Vec::new();
    try_reserve(&mut sorted, sizes.len())?;
    sorted.extend_from_slice(sizes);
    sorted.sort_unstable();
    if sorted.first() == Some(&0) {
        return Err(Error::OutOfRange {
            name: "size",
            value: 0.0,
            range: "1 or more",
        });
    }
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return Err(Error::OutOfRange {
            name: "size (given twice)",
            value: sorted
                .windows(2)
                .find(|w| w[0] == w[1])
                .map_or(0.0, |w| w[0] as f64),
            range: "each size at most once",
        });
    }
    let largest = sorted.last().copied().unwrap_or(0);
    if largest > size_limit {
        return Err(Error::Capacity {
            name: "maximum particle size",
            capacity: usize::try_from(size_limit).unwrap_or(usize::MAX),
        });
    }
    Ok(largest)
}

/// The dense count vector of `(size, count)` pairs (for the schemes whose own tables
/// run up to the largest size), refused up front when it would take more than half
/// the memory budget: the tables built from it, and their first growth when a merge
/// passes the largest size, would then pass the budget, so the state could be set but
/// not run (issue 40: `{1: 5000, 1000: 3, 2^30: 1}` took 8.4 GB and 10 s, then every
/// advance failed).
pub(crate) fn dense_from_pairs(
    sizes: &[u64],
    counts: &[u64],
    size_limit: u64,
    budget: usize,
) -> Result<Vec<u64>> {
    let largest = check_pairs(sizes, counts, size_limit)?;
    let len = usize::try_from(largest).unwrap_or(usize::MAX);
    within_budget(len.checked_mul(2 * core::mem::size_of::<u64>()), budget)?;
    let mut dense = Vec::new();
    try_resize(&mut dense, len, 0u64)?;
    for (&s, &c) in sizes.iter().zip(counts) {
        dense[s as usize - 1] = c;
    }
    Ok(dense)
}

/// Validates an initial count vector and returns its particle number: the number and
/// the total mass `Σ i N_i` must fit 64 bits (sizes are 64-bit integers, so a larger
/// mass could only fail later, at a merge). An empty system (no particle) is valid: it
/// stays as it is until a host puts particles in (`set_counts`).
pub(crate) fn check_counts(counts: &[u64]) -> Result<u64> {
    let mut n: u64 = 0;
    let mut mass: u64 = 0;
    for (i, &c) in counts.iter().enumerate() {
        n = n.checked_add(c).ok_or(Error::Overflow {
            name: "particle number",
        })?;
        mass = (i as u64 + 1)
            .checked_mul(c)
            .and_then(|m| mass.checked_add(m))
            .ok_or(Error::Overflow {
                name: "total mass (sum of i N_i)",
            })?;
    }
    Ok(n)
}

/// The error of a single-particle edit given a handle that does not name a particle
/// of the given size (`what`: what it should have named).
pub(crate) fn bad_handle(handle: u64, what: &'static str) -> Error {
    Error::OutOfRange {
        name: "particle handle",
        value: handle as f64,
        range: what,
    }
}

/// The error of a total proposal rate that overflowed (kernel values near `f64::MAX`
/// times many particles): no waiting time can be drawn from it.
pub(crate) fn rate_overflow(value: f64) -> Error {
    Error::InvalidRate {
        name: "total proposal rate (overflowed: the kernel's values are too large)",
        value,
    }
}

/// [`Observe`](crate::observe::Observe) for a size-count scheme from its inherent
/// `counts`, `volume`, `particles` and `moment` (one definition for all).
macro_rules! observe_counts {
    ([$($g:tt)*] $ty:ty $(, observable = $obs:path)?) => {
        impl<$($g)*> crate::observe::Observe for $ty {
            fn volume(&self) -> f64 {
                <$ty>::volume(self)
            }
            fn particles(&self) -> u64 {
                <$ty>::particles(self)
            }
            fn moment(&self, order: f64) -> f64 {
                <$ty>::moment(self, order)
            }
            fn concentration(&self, a: f64, b: f64) -> f64 {
                crate::observe::concentration_of_pairs(|f| self.for_each_count(f), <$ty>::volume(self), a, b)
            }
            fn points(&self, f: &mut dyn FnMut(f64, f64)) {
                let w = 1.0 / <$ty>::volume(self);
                self.for_each_count(&mut |s, c| f(s as f64, c as f64 * w));
            }
            fn gel_mass(&self) -> Option<f64> {
                Some(crate::observe::largest_of_pairs(|f| self.for_each_count(f), <$ty>::volume(self)))
            }
            $(
                fn observable(&self, name: &str) -> Option<f64> {
                    $obs(self, name)
                }
            )?
        }
    };
}
pub(crate) use observe_counts;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn population_rules() {
        // an empty system is valid (a host drains a cell and refills it later)
        assert_eq!(Population::new(&[0, 0], 1.0).unwrap().n, 0);
        assert!(Population::new(&[u64::MAX, 1], 1.0).is_err());
        assert!(Population::new(&[3], 0.0).is_err());
        assert!(Population::new(&[3], f64::INFINITY).is_err());
        let mut p = Population::new(&[6, 2], 8.0).unwrap();
        assert_eq!((p.n, p.n0), (8, 8));
        p.n = 4;
        assert!(!p.doubling_due());
        p.n = 3;
        assert!(p.doubling_due());
        p.double();
        assert_eq!((p.n, p.volume), (6, 16.0));
        assert_eq!(p.merged(3, 4).unwrap(), 7);
        p.size_limit = 6;
        assert!(matches!(p.merged(3, 4), Err(Error::Capacity { .. })));
        p.size_limit = u64::MAX;
        assert!(p.merged(u64::MAX - 1, 5).is_err());
        assert!(p.within_budget(None).is_err());
        assert!(p.within_budget(Some(10)).is_ok());
    }

    #[cfg(feature = "std")]
    #[test]
    fn the_machine_budget_is_a_sane_fraction() {
        let b = machine_memory_budget();
        assert!(b >= 256 << 20);
        if let Ok(m) = std::fs::read_to_string("/proc/meminfo") {
            let kib: u64 = m
                .lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
                .unwrap();
            assert_eq!(b as u64, (kib * 1024 / 2).max(256 << 20));
        }
    }
}
