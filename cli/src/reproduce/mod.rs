//! `coagula reproduce`: the papers' experiments that are more than a scenario (grids
//! of runs, fitted slopes, figures). One module per paper.

pub mod eibeck2000;
pub mod lecot2019;
pub mod lecot2019_dt;
pub mod maftei2016;
pub mod osinsky2023;
