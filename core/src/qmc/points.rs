//! Point sources for the quasi-Monte Carlo schemes: which digital sequence a scheme's
//! steps take their points from, unrandomised, randomised once, or re-randomised per
//! block (RQMC), or pseudo-random points (MC).

use crate::error::Result;
use crate::qmc::{DigitalSequence, Niederreiter2, Randomization, Scrambled, Sobol};
use rand_core::Rng;

/// Where the points of each step come from.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub enum PointSource {
    /// Niederreiter's base-2 (1,3)-sequence (Lécot et al.'s choice).
    Niederreiter(Niederreiter2<u64>),
    /// Sobol' with Joe–Kuo direction numbers, dimensions 1–3.
    Sobol(Sobol<u64>),
    /// Niederreiter's sequence under one randomisation for the whole run. Biased as an
    /// RQMC estimator (see the module docs); kept for comparison.
    ScrambledNiederreiter(Scrambled<Niederreiter2<u64>>),
    /// Sobol' under one randomisation for the whole run (biased, see above).
    ScrambledSobol(Scrambled<Sobol<u64>>),
    /// Niederreiter's sequence with an independent randomisation of every block (RQMC):
    /// block n is block n of the sequence randomised (with the kind of `work`) by random
    /// parameters drawn from `(key, n)`; `work` is re-randomised in place per block.
    RerandomizedNiederreiter {
        /// The sequence under its current block's randomisation.
        work: Scrambled<Niederreiter2<u64>>,
        /// Key of the per-block random parameters.
        key: u64,
    },
    /// Sobol' with an independent randomisation of every block (RQMC).
    RerandomizedSobol {
        /// The sequence under its current block's randomisation.
        work: Scrambled<Sobol<u64>>,
        /// Key of the per-block random parameters.
        key: u64,
    },
    /// Pseudo-random points from the caller's RNG (MC).
    MonteCarlo,
}

impl PointSource {
    /// Niederreiter's sequence in dimension 3.
    pub fn niederreiter() -> Self {
        PointSource::Niederreiter(Niederreiter2::dim3())
    }

    /// Sobol' in dimension 3.
    pub fn sobol() -> Self {
        PointSource::Sobol(Sobol::new(3).expect("dimension 3 is supported"))
    }

    /// Niederreiter's sequence randomised by `kind`, independently for every step, with
    /// the key drawn from `rng` (one replica; build R of them for R independent
    /// replicas).
    pub fn randomized_niederreiter<R: Rng + ?Sized>(kind: Randomization, rng: &mut R) -> Self {
        let seq = Niederreiter2::dim3();
        let key = rng.next_u64();
        PointSource::RerandomizedNiederreiter {
            work: Scrambled::new(seq, kind, &mut BlockRng::new(key, 0)),
            key,
        }
    }

    /// Sobol' randomised by `kind`, independently for every step, key drawn from `rng`.
    pub fn randomized_sobol<R: Rng + ?Sized>(kind: Randomization, rng: &mut R) -> Self {
        let seq = Sobol::new(3).expect("dimension 3 is supported");
        let key = rng.next_u64();
        PointSource::RerandomizedSobol {
            work: Scrambled::new(seq, kind, &mut BlockRng::new(key, 0)),
            key,
        }
    }

    /// Pseudo-random points (Monte Carlo).
    pub fn monte_carlo() -> Self {
        PointSource::MonteCarlo
    }

    /// Identifies the point set: kind, and for randomised sequences the fingerprint of
    /// their random parameters.
    pub fn fingerprint(&self) -> u64 {
        match self {
            PointSource::Niederreiter(_) => 1,
            PointSource::Sobol(_) => 2,
            PointSource::ScrambledNiederreiter(s) => {
                crate::checkpoint::fingerprint([3, s.fingerprint()])
            }
            PointSource::ScrambledSobol(s) => crate::checkpoint::fingerprint([4, s.fingerprint()]),
            PointSource::MonteCarlo => 5,
            PointSource::RerandomizedNiederreiter { work, key } => {
                crate::checkpoint::fingerprint([6, kind_code(work.kind()), *key])
            }
            PointSource::RerandomizedSobol { work, key } => {
                crate::checkpoint::fingerprint([7, kind_code(work.kind()), *key])
            }
        }
    }

    /// Writes block `n` (`2^m` points of dimension 3, row-major) into `out`; nothing for
    /// Monte Carlo points, which the scheme draws itself.
    pub(crate) fn block(&mut self, n: u64, m: u32, out: &mut [f64]) -> Result<()> {
        match self {
            PointSource::Niederreiter(s) => s.block(n, m, out),
            PointSource::Sobol(s) => s.block(n, m, out),
            PointSource::ScrambledNiederreiter(s) => s.block(n, m, out),
            PointSource::ScrambledSobol(s) => s.block(n, m, out),
            PointSource::MonteCarlo => Ok(()),
            PointSource::RerandomizedNiederreiter { work, key } => {
                work.rerandomize(&mut BlockRng::new(*key, n));
                work.block(n, m, out)
            }
            PointSource::RerandomizedSobol { work, key } => {
                work.rerandomize(&mut BlockRng::new(*key, n));
                work.block(n, m, out)
            }
        }
    }
}

fn kind_code(kind: Randomization) -> u64 {
    match kind {
        Randomization::None => 0,
        Randomization::DigitalShift => 1,
        Randomization::Matousek => 2,
        Randomization::Owen => 3,
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014) started at a hash of `(key, block)`: the
/// random parameters of one block's randomisation, independent between blocks.
struct BlockRng(u64);

impl BlockRng {
    fn new(key: u64, block: u64) -> Self {
        let mut r = BlockRng(key);
        let k = r.next();
        let mut r = BlockRng(k ^ block);
        let s = r.next();
        BlockRng(s)
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

impl rand_core::TryRng for BlockRng {
    type Error = core::convert::Infallible;
    fn try_next_u32(&mut self) -> core::result::Result<u32, Self::Error> {
        Ok((self.next() >> 32) as u32)
    }
    fn try_next_u64(&mut self) -> core::result::Result<u64, Self::Error> {
        Ok(self.next())
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> core::result::Result<(), Self::Error> {
        for c in dst.chunks_mut(8) {
            let w = self.next().to_le_bytes();
            c.copy_from_slice(&w[..c.len()]);
        }
        Ok(())
    }
}
