//! The fragmentation kernels a scenario can name, as one type for the registry.

use coagula_core::kernel::{BinaryUniform, FragmentationKernel};

/// No fragmentation, or binary uniform break-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Frag {
    /// Pure coagulation.
    None,
    /// `F(x, y) = 2λ/(x+y)` (Lécot et al. 2019, §4).
    Binary(BinaryUniform),
}

impl FragmentationKernel for Frag {
    fn total_rate(&self, x: f64) -> f64 {
        match self {
            Frag::None => 0.0,
            Frag::Binary(f) => f.total_rate(x),
        }
    }
    fn inverse_piece(&self, x: f64, u: f64) -> f64 {
        match self {
            Frag::None => x,
            Frag::Binary(f) => f.inverse_piece(x, u),
        }
    }
    fn sup_rate(&self) -> Option<f64> {
        match self {
            Frag::None => Some(0.0),
            Frag::Binary(f) => f.sup_rate(),
        }
    }
    fn is_none(&self) -> bool {
        matches!(self, Frag::None)
    }
}
