//! The methods low-rank Monte Carlo is measured against (Osinsky 2023, §2): the inverse
//! method ([`Inverse`], Gillespie on sizes) and acceptance–rejection with the kernel's
//! supremum ([`AcceptanceRejection`]). Both are exact simulations of the same
//! Marcus–Lushnikov process, with particle doubling, on the shared size-count
//! [`population`](super::population).

mod entry;
mod inverse;
mod rejection;

pub use entry::{InverseEntry, RejectionEntry};
pub use inverse::{CACHE_DIM, Inverse};
pub use rejection::AcceptanceRejection;

crate::scheme::population::observe_counts!([K: crate::kernel::CoagulationKernel] Inverse<K>);
crate::scheme::population::observe_counts!([K: crate::kernel::CoagulationKernel] AcceptanceRejection<K>);
