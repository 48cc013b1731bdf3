//! Machine words holding the base-2 digits of a point coordinate: `u32` (32 digits,
//! at most 2^32 points) and `u64` (64 digits, 2^64 points).
//!
//! Digit 1 (weight 1/2) is the most significant bit of the word. The hash-based Owen
//! scramble follows B. Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4),
//! 2020 (Laine–Karras permutation of the bit-reversed word).

use core::fmt::Debug;
use core::hash::Hash;
use core::ops::{BitAnd, BitOr, BitXor, BitXorAssign, Shl, Shr};

mod sealed {
    pub trait Sealed {}
    impl Sealed for u32 {}
    impl Sealed for u64 {}
}

/// A word of base-2 digits: `u32` or `u64` (sealed).
///
/// The word `x` stands for the point coordinate `x / 2^BITS` in `[0, 1)`.
pub trait Word:
    sealed::Sealed
    + Copy
    + Eq
    + Ord
    + Default
    + Debug
    + Hash
    + Send
    + Sync
    + 'static
    + BitXor<Output = Self>
    + BitXorAssign
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Shl<u32, Output = Self>
    + Shr<u32, Output = Self>
{
    /// Number of digits (32 or 64).
    const BITS: u32;
    /// The zero word.
    const ZERO: Self;
    /// The word 1 (the least significant digit).
    const ONE: Self;

    /// The coordinate as `f64` in `[0, 1)`: `x * 2^-32` exactly for `u32`; the top 53
    /// digits (`(x >> 11) * 2^-53`, exact, never rounds up to 1) for `u64`.
    fn to_unit(self) -> f64;

    /// The low `BITS` bits of `x`.
    fn from_u64(x: u64) -> Self;

    /// The word zero-extended to `u64`.
    fn to_u64(self) -> u64;

    /// Hash-based nested uniform (Owen) scramble of the digits with the given seed:
    /// each digit is flipped or not according to a hash of the seed and of all more
    /// significant digits (Burley 2020). A bijection of `[0, 2^BITS)` that maps every
    /// elementary dyadic interval onto an elementary dyadic interval of the same
    /// length, hence keeps the (t,m,s)-net property.
    fn nested_scramble(self, seed: Self) -> Self;
}

impl Word for u32 {
    const BITS: u32 = 32;
    const ZERO: Self = 0;
    const ONE: Self = 1;

    #[inline]
    fn to_unit(self) -> f64 {
        self as f64 * (1.0 / 4_294_967_296.0)
    }

    #[inline]
    fn from_u64(x: u64) -> Self {
        x as u32
    }

    #[inline]
    fn to_u64(self) -> u64 {
        u64::from(self)
    }

    #[inline]
    fn nested_scramble(self, seed: Self) -> Self {
        // Burley (2020), listing 3/4: Laine–Karras permutation on reversed bits, in
        // which every bit depends only on itself and on less significant bits.
        let mut x = self.reverse_bits();
        x = x.wrapping_add(seed);
        x ^= x.wrapping_mul(0x6c50_b47c);
        x ^= x.wrapping_mul(0xb82f_1e52);
        x ^= x.wrapping_mul(0xc7af_e638);
        x ^= x.wrapping_mul(0x8d22_f6e6);
        x.reverse_bits()
    }
}

impl Word for u64 {
    const BITS: u32 = 64;
    const ZERO: Self = 0;
    const ONE: Self = 1;

    #[inline]
    fn to_unit(self) -> f64 {
        (self >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    #[inline]
    fn from_u64(x: u64) -> Self {
        x
    }

    #[inline]
    fn to_u64(self) -> u64 {
        self
    }

    #[inline]
    fn nested_scramble(self, seed: Self) -> Self {
        // The 64-bit analogue of Burley's Laine–Karras hash: addition of the seed,
        // then `x ^= x * c` with even constants (bit i of `x * c` depends only on bits
        // below i), then a multiplication by an odd seed-dependent constant (which
        // keeps bit i = own bit xor function of lower bits), and a final round.
        let mut x = self.reverse_bits();
        x = x.wrapping_add(seed);
        x ^= x.wrapping_mul(0x6c50_b47c_e9b5_7a0e);
        x ^= x.wrapping_mul(0xb82f_1e52_94d0_49bc);
        x = x.wrapping_mul((seed >> 31) | 1);
        x ^= x.wrapping_mul(0xc7af_e638_bf58_476c);
        x ^= x.wrapping_mul(0x8d22_f6e6_9e37_79b8);
        x.reverse_bits()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Owen property: outputs of two words that agree in their top k digits agree in
    /// their top k digits, and differ in digit k+1 iff the inputs do.
    fn check_nested<W: Word>(rng: &mut Pcg64) {
        for _ in 0..2000 {
            let seed = W::from_u64(rng.next_u64());
            let x = W::from_u64(rng.next_u64());
            let y = W::from_u64(rng.next_u64());
            let (sx, sy) = (x.nested_scramble(seed), y.nested_scramble(seed));
            let k = (x ^ y).to_u64().leading_zeros() - (64 - W::BITS); // common prefix
            let ks = (sx ^ sy).to_u64().leading_zeros() - (64 - W::BITS);
            assert_eq!(k, ks, "prefix length must be preserved exactly");
        }
    }

    #[test]
    fn nested_scramble_is_owen_type() {
        let mut rng = Pcg64::seed_from_u64(1);
        check_nested::<u32>(&mut rng);
        check_nested::<u64>(&mut rng);
    }

    #[test]
    fn to_unit_is_below_one() {
        assert!(u64::MAX.to_unit() < 1.0);
        assert!(u32::MAX.to_unit() < 1.0);
        assert_eq!((1u64 << 63).to_unit(), 0.5);
        assert_eq!((1u32 << 31).to_unit(), 0.5);
    }
}
