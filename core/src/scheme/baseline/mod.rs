//! The methods low-rank Monte Carlo is measured against (Osinsky 2023, §2): the inverse
//! method ([`Inverse`], Gillespie on sizes) and acceptance–rejection with the kernel's
//! supremum ([`AcceptanceRejection`]). Both are exact simulations of the same
//! Marcus–Lushnikov process, with particle doubling, on the shared size-count
//! [`population`](super::population).

mod inverse;
mod rejection;

pub use inverse::{CACHE_DIM, Inverse};
pub use rejection::AcceptanceRejection;
