//! Weighted samplers: the flat sum tree (`sum_tree`, also at `crate::tree`) and Walker
//! alias tables (`alias`, used by the bucketed low-rank layout).

pub(crate) mod alias;
pub mod sum_tree;
pub(crate) mod wide_tree;
