//! The exact solutions by name: one spelling for every front end.

use super::Exact;
use crate::error::{Error, Result};

/// The exact solutions by name, as every front end spells them (the CLI's `exact
/// --solution`, Python's `coagula.exact`): `constant`, `additive`, `multiplicative`
/// (Flory), `marcus-lushnikov`, `coag-frag` (with binary fragmentation),
/// `constant-exponential`,
/// `golovin` (the additive kernel from the exponential start).
pub const NAMES: &[&str] = &[
    "constant",
    "additive",
    "multiplicative",
    "marcus-lushnikov",
    "coag-frag",
    "constant-exponential",
    "golovin",
];

impl Exact {
    /// The solution of a name of [`NAMES`] for coefficient 1 (scale it with
    /// [`with_coefficient`](Self::with_coefficient)). Errors: an unknown name
    /// ([`Error::UnknownName`], listing them).
    pub fn named(name: &str) -> Result<Self> {
        Ok(match name {
            "constant" => Exact::constant(1.0)?,
            "additive" => Exact::additive(),
            "multiplicative" => Exact::multiplicative(),
            "marcus-lushnikov" => Exact::marcus_lushnikov(),
            "coag-frag" => Exact::coagulation_fragmentation(),
            "constant-exponential" => Exact::constant_exponential(1.0)?,
            "golovin" => Exact::additive_exponential(),
            _ => {
                return Err(Error::UnknownName {
                    what: "exact solution",
                    known: NAMES,
                });
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name builds a solution of its own (no two names give the same one), and
    /// an unknown name is refused with the list.
    #[test]
    fn every_name_builds_its_solution() {
        let all: alloc::vec::Vec<Exact> = NAMES.iter().map(|n| Exact::named(n).unwrap()).collect();
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(
            Exact::named("golovin").unwrap(),
            Exact::additive_exponential()
        );
        let e = Exact::named("gollovin").unwrap_err();
        assert!(matches!(e, Error::UnknownName { .. }));
    }
}
