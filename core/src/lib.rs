//! # coagula-core
//!
//! Stochastic particle simulation of coagulation, fragmentation and agglomeration
//! (Smoluchowski-class population balances). This crate is `#![no_std]` + `alloc`:
//! randomness comes from the caller (any [`rand_core::Rng`]), floating point goes through
//! [`libm`] so results do not depend on the platform, and errors are values
//! ([`Error`]), never panics.
//!
//! Modules:
//! * [`checkpoint`] — save and restore a scheme's state into a caller buffer;
//! * [`classes`] — host coupling on size classes: projection onto a grid keeping number
//!   and mass (fixed pivot), populations from class numbers, per-class source terms;
//! * [`kernel`] — coagulation kernels with their bounds, fragmentation kernels;
//! * [`exact`] — exact solutions used as validation targets;
//! * [`initial`] — initial states every front end draws the same way;
//! * [`sample`] — weighted samplers: the flat-array sum tree ([`tree`]) and Walker alias
//!   tables;
//! * [`random`] — random variates and the seed policy (`seed, stream → generator`);
//! * [`observe`] — the observation trait every population scheme implements, moments,
//!   concentrations, gel mass and replica statistics;
//! * [`qmc`] — digital (t,s)-sequences in base 2 (Niederreiter, Sobol'), their
//!   randomisations, and the point sources the quasi-Monte Carlo schemes draw from;
//! * [`langevin`] — Langevin particle tracking with specular or absorbing walls (Maftei
//!   et al. 2016): trajectory batches, Richardson–Romberg, kernels from first hits;
//! * [`scheme`] — the stepping schemes behind one `advance_to` interface, the shared
//!   size-count population, and the registry with the object-safe facade
//!   ([`scheme::registry`]) that the C ABI and the CLI are written over.
//!
//! # Example
//! ```
//! use coagula_core::exact::Exact;
//! // constant kernel K = 1 from a monodisperse start: M2(t) = 1 + t
//! let m2 = Exact::constant(1.0).unwrap().moment(2, 3.0).unwrap();
//! assert!((m2 - 4.0).abs() < 1e-12);
//! ```
#![no_std]
#![warn(missing_docs)]
// Numerical code indexes parallel arrays (factors, counts, tree rows); index loops read
// closer to the equations than zipped iterators.
#![allow(clippy::needless_range_loop)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub mod checkpoint;
pub mod classes;
pub mod error;
pub mod exact;
pub mod initial;
pub mod kernel;
pub mod langevin;
pub mod memory;
pub mod observe;
pub mod process;
pub mod qmc;
pub mod random;
pub mod sample;
pub mod scheme;
/// The flat-array sum tree (also at [`sample::sum_tree`]).
pub use sample::sum_tree as tree;

pub use error::{Error, Result};
