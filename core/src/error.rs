//! The one error type of coagula.
//!
//! Every fallible call returns [`Result<T, Error>`](Result). The enum is small and
//! `Copy` (as `rand_distr`'s errors are), so it crosses the C ABI as a status code plus
//! a message without allocation.

use core::fmt;

/// Everything that can go wrong in coagula.
///
/// Each variant carries the name of the offending parameter (a `&'static str`) and,
/// where it helps, the value that was rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is NaN or infinite.
    NotFinite {
        /// Name of the parameter.
        name: &'static str,
    },
    /// A parameter lies outside its admissible range.
    OutOfRange {
        /// Name of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// Human-readable description of the admissible range, e.g. `"(0.5, 1)"`.
        range: &'static str,
    },
    /// A kernel (coagulation or fragmentation rate, or a bound) returned a negative
    /// or NaN value.
    InvalidRate {
        /// Which quantity was being evaluated.
        name: &'static str,
        /// The value that was returned.
        value: f64,
    },
    /// A buffer has the wrong length.
    BufferLength {
        /// Name of the buffer.
        name: &'static str,
        /// Length that was expected (or the minimum length).
        expected: usize,
        /// Length that was given.
        got: usize,
    },
    /// A caller-set capacity would be exceeded.
    Capacity {
        /// What ran out (e.g. `"max size M"`).
        name: &'static str,
        /// The capacity in force.
        capacity: usize,
    },
    /// A count must be a power of two (or of the sequence's base) and is not.
    NotPowerOfTwo {
        /// Name of the parameter.
        name: &'static str,
        /// The rejected value.
        value: u64,
    },
    /// A requested dimension is not supported.
    Dimension {
        /// The requested dimension.
        requested: usize,
        /// The largest supported dimension.
        max: usize,
    },
    /// An index is past the end of what can be generated (e.g. point 2^bits of a
    /// digital sequence).
    IndexOutOfRange {
        /// Name of the index.
        name: &'static str,
        /// The rejected index.
        index: u64,
        /// The first index that is not allowed.
        limit: u64,
    },
    /// A sampling structure is empty (total weight zero), so nothing can be drawn.
    Empty,
    /// A time argument lies before the current time of a simulation.
    TimeBackwards {
        /// Current time of the simulation.
        now: f64,
        /// Requested time.
        requested: f64,
    },
    /// A feature is not available for this kernel (e.g. no low-rank bound is known).
    Unsupported {
        /// What is missing.
        what: &'static str,
    },
    /// A checkpoint buffer is malformed or belongs to another scheme or configuration.
    Checkpoint {
        /// What is wrong with it.
        what: &'static str,
    },
    /// Integer overflow of a size or a count.
    Overflow {
        /// What overflowed.
        name: &'static str,
    },
    /// A setting's value is of the wrong kind or outside its range.
    OptionValue {
        /// The setting's key.
        key: &'static str,
        /// What it takes.
        expected: &'static str,
    },
    /// A name (of a scheme, an option, a built-in kernel) that is not known.
    UnknownName {
        /// What kind of name.
        what: &'static str,
        /// The names that are.
        known: &'static [&'static str],
    },
    /// A checkpoint was written under another value of a setting that must match.
    CheckpointOption {
        /// The setting's key.
        key: &'static str,
    },
    /// A setting was given to a scheme it does not apply to.
    OptionNotApplicable {
        /// The setting's key.
        key: &'static str,
        /// The scheme's registry name.
        scheme: &'static str,
    },
    /// A parameter of a built-in kernel is unknown (`param` empty), given twice or
    /// missing.
    KernelParameter {
        /// The kernel.
        kernel: &'static str,
        /// The parameter (empty: one the kernel does not have).
        param: &'static str,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A kernel returned a rate above the bound it declared (the low-rank bound, or
    /// the supremum acceptance–rejection proposes with), or below the acceptance floor
    /// it declared (an exact low-rank claim): a scheme built on that bound would be
    /// biased, so it stops instead.
    BoundExceeded {
        /// Which bound was exceeded.
        name: &'static str,
        /// The kernel's value.
        rate: f64,
        /// The declared bound at that pair.
        bound: f64,
    },
}

/// A number in a message, short: plain digits for moderate magnitudes, scientific
/// notation otherwise (Rust's plain `{}` writes 5e-324 as a 330-character decimal).
#[derive(Clone, Copy, Debug)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        let a = v.abs();
        if !v.is_finite() || a == 0.0 || (1e-5..1e16).contains(&a) {
            write!(f, "{v}")
        } else {
            write!(f, "{v:e}")
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::NotFinite { name } => write!(f, "{name} must be finite (got NaN or infinity)"),
            Error::OutOfRange { name, value, range } => {
                let value = Short(value);
                write!(
                    f,
                    "{name} = {value} is outside the admissible range {range}"
                )
            }
            Error::InvalidRate { name, value } => {
                let value = Short(value);
                write!(
                    f,
                    "{name} returned {value}; rates must be finite and non-negative"
                )
            }
            Error::BufferLength {
                name,
                expected,
                got,
            } => write!(f, "buffer {name} has length {got}, expected {expected}"),
            Error::Capacity { name, capacity } => {
                write!(f, "capacity exceeded: {name} would pass {capacity}")
            }
            Error::NotPowerOfTwo { name, value } => {
                write!(f, "{name} = {value} must be a power of two")
            }
            Error::Dimension { requested, max } => {
                write!(f, "dimension {requested} is not supported (maximum {max})")
            }
            Error::IndexOutOfRange { name, index, limit } => {
                write!(
                    f,
                    "{name} = {index} is out of range (must be below {limit})"
                )
            }
            Error::Empty => f.write_str("cannot sample: total weight is zero"),
            Error::TimeBackwards { now, requested } => write!(
                f,
                "requested time {} lies before the current time {}",
                Short(requested),
                Short(now)
            ),
            Error::Unsupported { what } => write!(f, "not supported: {what}"),
            Error::Checkpoint { what } => write!(f, "cannot restore checkpoint: {what}"),
            Error::Overflow { name } => write!(f, "integer overflow in {name}"),
            Error::OptionValue { key, expected } => {
                write!(f, "option {key}: expected {expected}")
            }
            Error::OptionNotApplicable { key, scheme } => write!(
                f,
                "option {key} does not apply to scheme {scheme} (its registry entry lists the options that do)"
            ),
            Error::CheckpointOption { key } => write!(
                f,
                "cannot restore checkpoint: it was written under another value of option {key}"
            ),
            Error::UnknownName { what, known } => {
                write!(f, "unknown {what}: the {what}s are ")?;
                list(f, known.iter().copied())
            }
            Error::KernelParameter {
                kernel, param: "", ..
            } => write!(
                f,
                "kernel {kernel} has no such parameter (the table of built-in kernels lists its parameters)"
            ),
            Error::KernelParameter { kernel, param, why } => {
                write!(f, "kernel {kernel}: parameter {param} {why}")
            }
            Error::BoundExceeded { name, rate, bound } => write!(
                f,
                "the kernel returned {}, {} its declared {name} {}: the bound must hold for every pair",
                Short(rate),
                if rate < bound { "below" } else { "above" },
                Short(bound)
            ),
        }
    }
}

/// Writes names separated by commas (`(none)` for none).
fn list<'a>(f: &mut fmt::Formatter<'_>, names: impl Iterator<Item = &'a str>) -> fmt::Result {
    let mut first = true;
    for n in names {
        if !first {
            f.write_str(", ")?;
        }
        f.write_str(n)?;
        first = false;
    }
    if first {
        f.write_str("(none)")?;
    }
    Ok(())
}

#[cfg(feature = "std")]
impl std::error::Error for Error {}

/// Shorthand used throughout the crate.
pub type Result<T> = core::result::Result<T, Error>;

/// Checks that `value` is finite, naming it in the error otherwise.
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NotFinite { name })
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(Error::OutOfRange {
            name,
            value,
            range: "(0, inf)",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers in messages stay short at the extremes of f64 (5e-324 would be a
    /// 330-character decimal with `{}`).
    #[test]
    fn messages_print_short_numbers() {
        use alloc::string::ToString;
        let e = Error::OutOfRange {
            name: "v",
            value: 5e-324,
            range: "(0, 1]",
        };
        assert_eq!(
            e.to_string(),
            "v = 5e-324 is outside the admissible range (0, 1]"
        );
        let e = Error::OutOfRange {
            name: "v",
            value: 1e300,
            range: "(0, 1]",
        };
        assert!(e.to_string().contains("1e300"));
        assert!(Short(2.5).to_string() == "2.5" && Short(f64::MIN_POSITIVE).to_string().len() < 30);
        assert_eq!(Short(0.0).to_string(), "0");
        assert_eq!(Short(f64::NAN).to_string(), "NaN");
    }
    use alloc::string::ToString;

    #[test]
    fn messages_name_the_parameter() {
        let e = positive("dt", -1.0).unwrap_err();
        assert!(e.to_string().contains("dt"));
        assert!(e.to_string().contains("-1"));
        let e = finite("a", f64::NAN).unwrap_err();
        assert_eq!(e, Error::NotFinite { name: "a" });
    }
}
