//! The registry entries and facade controls of Osinsky's low-rank schemes (2023): the
//! bucketed layout, the per-size trees (8-ary and binary), low-rank over particle
//! sizes, the temperature-dependent scheme (§4) and low-rank DSMC (§5), each with its
//! acceptance–rejection baseline where the paper times one.

use super::dsmc::{Collisions, Gas, LowRankDsmc, RejectionDsmc};
use super::temperature::{Collide, TemperatureMc, TemperatureRejection, Temperatures};
use super::{
    AutoBucketed, BinaryTree, BucketMode, COUNTED_UP_TO, Coagulate, LowRank, LowRankMc,
    LowRankSizes, ProposalEngine,
};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::kernel::gas::{NeverStick, Sticking};
use crate::kernel::temperature::{TemperatureKernel, TemperatureModel};
use crate::scheme::facade::{
    Blank, Boxed, Controls, Init, InitKind, Law, Memory, Model, ModelKind, Options, Reach,
    Register, RegistryFragmentation, RegistryKernel, Samples, SchemeInfo, Simulation, State,
    count_controls, number_volume,
};
use crate::scheme::population::check_within_limit;
use crate::scheme::tag;
use alloc::boxed::Box;
use alloc::vec;
use rand_core::Rng;

/// Runs `$body` with `$R` (and `$W = 2R`) bound to the kernel's rank, 1..=4.
macro_rules! by_rank {
    ($rank:expr, $R:ident, $W:ident => $body:expr) => {
        match $rank {
            1 => {
                const $R: usize = 1;
                const $W: usize = 2;
                $body
            }
            2 => {
                const $R: usize = 2;
                const $W: usize = 4;
                $body
            }
            3 => {
                const $R: usize = 3;
                const $W: usize = 6;
                $body
            }
            4 => {
                const $R: usize = 4;
                const $W: usize = 8;
                $body
            }
            _ => Err(Error::Unsupported {
                what: "low-rank layouts: the kernel needs a low-rank bound of rank 1..4 (lowrank and lowrank-blocks run a kernel of another rank, or none, on block majorants when it bounds blocks)",
            }),
        }
    };
}

fn counts_of<'a>(init: &Init<'a>, opts: &Options) -> Result<(&'a [u64], f64)> {
    match *init {
        Init::Counts { counts, volume } => {
            check_within_limit(counts, opts.size_limit())?;
            Ok((counts, volume))
        }
        _ => Err(Error::Unsupported {
            what: "initial state: this scheme starts from counts of integer sizes",
        }),
    }
}

const COUNT_OPTIONS: &[&str] = &["size-limit", "memory-budget", "batched-clock"];

/// The bucketed layout at `reach`: a `u32` count a size in a table that doubles from
/// 64 sizes, and a `u32` list entry (6 bytes with the lists' growth slack) per sparse
/// particle; up to [`COUNTED_UP_TO`] particles (or pinned) the counted engine, with a
/// dense `u64` a size and a list entry per particle.
fn bucketed_memory(opts: &Options, reach: &Reach) -> u64 {
    let blocks = match opts.engine() {
        Some(mode) => mode == BucketMode::Blocks,
        None => reach.blocks,
    };
    if blocks {
        return blocks_memory(reach);
    }
    let first = reach.start.max(1).next_power_of_two().max(64);
    let counted = match opts.engine() {
        Some(mode) => mode == BucketMode::Counted,
        None => reach.particles <= COUNTED_UP_TO,
    };
    if counted {
        reach.bytes(first, 8, 6, 0)
    } else {
        reach.bytes(first, 4, 0, 6)
    }
}

/// Block majorants: the count tree and its caps (24 bytes a size) and the blocks (about
/// [`BLOCKS_PER_SIZE`](super::blocks::BLOCKS_PER_SIZE) a size, 72 bytes each: the block,
/// two list entries, its bounds and its majorant in the sum tree), and while M doubles
/// the old tables beside the new ones (half as many). A log-linear partition has a
/// few hundred blocks an octave: its tables, counted exactly, are the count tree's.
fn blocks_memory(reach: &Reach) -> u64 {
    let first = reach.start.max(64).next_power_of_two();
    if reach.log_linear {
        let m = reach.table_len(first).max(64).checked_next_power_of_two();
        return m
            .and_then(super::blocks::BlockEngine::log_linear_bytes)
            .map_or(u64::MAX, |b| (b as u64).saturating_mul(3) / 2);
    }
    let per = (24.0 + 72.0 * super::blocks::BLOCKS_PER_SIZE) * 1.5;
    reach.bytes(first, per as u64, 0, 0)
}

/// Per-size segment trees, 8-ary: a count and 2R factors a size, the tree's 2R
/// weights a leaf with a seventh more for the levels above (18R bytes a size), and
/// while the tables double the old tree beside the new one (9R more; `TreeEngine::grow`
/// counts it against the budget too).
fn tree_memory(_opts: &Options, reach: &Reach) -> u64 {
    let first = reach.start.max(1).next_power_of_two().max(8);
    reach.bytes(first, 8 + 43 * reach.rank as u64, 0, 0)
}

/// The paper's binary segment trees: a count and 2R factors a size, 2R weights in each
/// of the 2M nodes, and the old tree beside the new one while they double.
fn binary_tree_memory(_opts: &Options, reach: &Reach) -> u64 {
    let first = reach.start.max(1).next_power_of_two();
    reach.bytes(first, 8 + 64 * reach.rank as u64, 0, 0)
}

/// An entry of low-rank MC over counts: the layouts differ only in their engine. With
/// `blocks: true` a kernel of rank 0 or above 4 that bounds blocks builds the scheme
/// at R = 1, where it runs on block majorants (the `lowrank` entry's automatic choice,
/// [`prefers_blocks`](super::auto::prefers_blocks)).
macro_rules! counts_entry {
    ($entry:ident, $name:expr, $paper:expr, $summary:expr, $tag:expr, $options:expr,
     memory: $memory:path, blocks: $blocks:literal,
     |$k:ident, $counts:ident, $volume:ident, $opts:ident| $make:expr) => {
        #[doc = concat!("The registry entry `", $name, "`.")]
        pub struct $entry;

        impl Register for $entry {
            const INFO: &'static SchemeInfo = &SchemeInfo {
                name: $name,
                paper: $paper,
                summary: $summary,
                model: ModelKind::Coagulation,
                inits: &[InitKind::Counts],
                sizes: Samples::None,
                fragmentation: false,
                options: $options,
                memory: Memory::Growing,
                tag: $tag,
                observables: &[],
                law: Law::FiniteN,
            };

            fn build<K, F, G>(
                model: Model<K, F>,
                init: &Init<'_>,
                opts: &Options,
            ) -> Result<Box<dyn Simulation<K, F, G>>>
            where
                K: RegistryKernel,
                F: RegistryFragmentation,
                G: Rng + ?Sized + 'static,
            {
                let ($k, _) = model.kernels()?;
                let ($counts, $volume) = counts_of(init, opts)?;
                let $opts = opts;
                let rank = match $k.rank() {
                    0 | 5.. if $blocks && super::auto::prefers_blocks(&$k) => 1,
                    r => r,
                };
                by_rank!(rank, R, W => {
                    let _ = W;
                    let s = $make;
                    Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
                })
            }

            fn memory_estimate(
                _init: &Init<'_>,
                opts: &Options,
                _fragments: bool,
                reach: &Reach,
            ) -> u64 {
                $memory(opts, reach)
            }

            fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
                Blank::Counts(vec![2], 1.0)
            }
        }
    };
}

counts_entry!(
    BucketedEntry,
    "lowrank",
    "Osinsky 2023, §2-3 (bucketed layout)",
    "low-rank Monte Carlo, bucketed layout (the default)",
    tag::BUCKETED,
    &["size-limit", "memory-budget", "batched-clock", "engine"],
    memory: bucketed_memory,
    blocks: true,
    |k, counts, volume, opts| AutoBucketed::<K, R, W>::new_with_mode(
        k,
        counts,
        volume,
        opts.memory_budget(),
        opts.engine()
    )?
    .with_size_limit(opts.size_limit())
    .with_batched_clock(opts.batched_clock())
);

counts_entry!(
    TreeEntry,
    "lowrank-tree",
    "Osinsky 2023, §2-3 (per-size segment trees, 8-ary)",
    "low-rank Monte Carlo with per-size segment trees",
    tag::LOWRANK,
    COUNT_OPTIONS,
    memory: tree_memory,
    blocks: false,
    |k, counts, volume, opts| LowRank::<K, R>::new_with_memory_budget(
        k,
        counts,
        volume,
        opts.memory_budget()
    )?
    .with_size_limit(opts.size_limit())
    .with_batched_clock(opts.batched_clock())
);

counts_entry!(
    BinaryTreeEntry,
    "lowrank-binary-tree",
    "Osinsky 2023, §2-3 (the paper's binary segment trees)",
    "low-rank Monte Carlo with the paper's binary segment trees",
    tag::LOWRANK_BINARY,
    COUNT_OPTIONS,
    memory: binary_tree_memory,
    blocks: false,
    |k, counts, volume, opts| LowRank::<K, R, BinaryTree<R>>::new_with_memory_budget(
        k,
        counts,
        volume,
        opts.memory_budget()
    )?
    .with_size_limit(opts.size_limit())
    .with_batched_clock(opts.batched_clock())
);

/// The registry entry of [`Blocks`](super::Blocks): block majorants over integer sizes.
pub struct BlocksEntry;

impl Register for BlocksEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "lowrank-blocks",
        paper: "Dyachenko, Matveev & Valiakhmetov 2025 (mosaic blocks); Osinsky 2023, §2 (event loop)",
        summary: "Monte Carlo over block majorants, for kernels no low-rank bound fits",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Counts],
        sizes: Samples::None,
        fragmentation: false,
        options: COUNT_OPTIONS,
        memory: Memory::Growing,
        tag: tag::BLOCKS,
        observables: &[],
        law: Law::FiniteN,
    };

    fn build<K, F, G>(
        model: Model<K, F>,
        init: &Init<'_>,
        opts: &Options,
    ) -> Result<Box<dyn Simulation<K, F, G>>>
    where
        K: RegistryKernel,
        F: RegistryFragmentation,
        G: Rng + ?Sized + 'static,
    {
        let (k, _) = model.kernels()?;
        let (counts, volume) = counts_of(init, opts)?;
        let s = super::Blocks::new_with_memory_budget(k, counts, volume, opts.memory_budget())?
            .with_size_limit(opts.size_limit())
            .with_batched_clock(opts.batched_clock());
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    /// See `blocks_memory`.
    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        blocks_memory(reach)
    }

    fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        Blank::Counts(vec![2], 1.0)
    }
}

/// The registry entry of [`LowRankSizes`].
pub struct SizesEntry;

impl Register for SizesEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "lowrank-sizes",
        paper: "Osinsky 2023, §2-3 (over particle sizes)",
        summary: "low-rank Monte Carlo over particle sizes (continuous or sparse; memory O(particles))",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Sizes],
        sizes: Samples::Number,
        fragmentation: false,
        options: &["memory-budget"],
        memory: Memory::Growing,
        tag: tag::LOWRANK_SIZES,
        observables: &[],
        law: Law::FiniteN,
    };

    fn build<K, F, G>(
        model: Model<K, F>,
        init: &Init<'_>,
        opts: &Options,
    ) -> Result<Box<dyn Simulation<K, F, G>>>
    where
        K: RegistryKernel,
        F: RegistryFragmentation,
        G: Rng + ?Sized + 'static,
    {
        let (k, _) = model.kernels()?;
        let &Init::Sizes { sizes, mass } = init else {
            return Err(Error::Unsupported {
                what: "initial state: lowrank-sizes starts from particle sizes",
            });
        };
        let v = number_volume(sizes, mass)?;
        by_rank!(k.rank(), R, W => {
            let s = LowRankSizes::<K, R, W>::new_with_memory_budget(k, sizes, v, opts.memory_budget())?;
            Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
        })
    }

    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        // a size, a bucket offset and R factors a particle, which never grow (the
        // buckets, fewer than a thousand, are negligible)
        reach.bytes(0, 0, 8 * 7, 0)
    }

    fn blank(init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        let size = match *init {
            Init::Sizes { sizes, .. } => sizes.iter().copied().reduce(f64::min).unwrap_or(1.0),
            _ => 1.0,
        };
        Blank::Sizes {
            size,
            n: 1,
            mass: size,
            capacity: 0,
        }
    }
}

/// An entry of the temperature-dependent scheme (Osinsky 2023 §4) on engine `$scheme`.
macro_rules! temperature_entry {
    ($entry:ident, $name:expr, $summary:expr, $scheme:ident, $tag:expr,
     memory: ($per_size:expr, $per_particle:expr)) => {
        #[doc = concat!("The registry entry `", $name, "`.")]
        pub struct $entry;

        impl Register for $entry {
            const INFO: &'static SchemeInfo = &SchemeInfo {
                name: $name,
                paper: "Osinsky 2023, §4 and appendix A",
                summary: $summary,
                model: ModelKind::Temperature,
                inits: &[InitKind::Temperatures],
                sizes: Samples::None,
                fragmentation: false,
                options: &["size-limit", "memory-budget"],
                memory: Memory::Growing,
                tag: $tag,
                observables: &["mean-temperature", "energy"],
                law: Law::Temperature,
            };

            fn build<K, F, G>(
                model: Model<K, F>,
                init: &Init<'_>,
                opts: &Options,
            ) -> Result<Box<dyn Simulation<K, F, G>>>
            where
                K: RegistryKernel,
                F: RegistryFragmentation,
                G: Rng + ?Sized + 'static,
            {
                let Model::Temperature(m) = model else {
                    return Err(Error::Unsupported {
                        what: "model: this scheme takes a temperature model",
                    });
                };
                let &Init::Temperatures {
                    counts,
                    temperatures,
                    volume,
                } = init
                else {
                    return Err(Error::Unsupported {
                        what: "initial state: this scheme starts from counts and temperatures",
                    });
                };
                if temperatures.len() != counts.len() {
                    return Err(Error::BufferLength {
                        name: "temperatures (one per size of the counts)",
                        expected: counts.len(),
                        got: temperatures.len(),
                    });
                }
                check_within_limit(counts, opts.size_limit())?;
                // one monomorphisation per model: the kernel is evaluated per proposal,
                // and a match there cost 5-10 % (docs/results/registry-ab.md)
                macro_rules! with {
                    ($k:expr) => {{
                        let kernel = Temperatures::new($k, temperatures)?;
                        let s = $scheme::<_>::new_with_memory_budget(
                            kernel,
                            counts,
                            volume,
                            opts.memory_budget(),
                        )?
                        .with_size_limit(opts.size_limit());
                        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
                    }};
                }
                match m {
                    TemperatureModel::Ballistic(b) => with!(b),
                    TemperatureModel::ClosedForm(c) => with!(c),
                }
            }

            fn memory_estimate(
                _init: &Init<'_>,
                _opts: &Options,
                _fragments: bool,
                reach: &Reach,
            ) -> u64 {
                let first = reach.start.max(1).next_power_of_two().max(8);
                reach.bytes(first, $per_size, $per_particle, 0)
            }

            fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
                Blank::Temperatures
            }
        }
    };
}

temperature_entry!(
    TemperatureEntry,
    "temperature",
    "temperature-dependent low-rank Monte Carlo on per-size trees",
    TemperatureMc,
    tag::TEMPERATURE,
    // a temperature, a count and 3 × 2 factors a size, and the 8-ary trees' weights
    memory: (8 + 8 + 48 + 55, 0)
);
temperature_entry!(
    TemperatureRejectionEntry,
    "temperature-rejection",
    "temperature-dependent acceptance-rejection (uniform pairs), the paper's baseline",
    TemperatureRejection,
    tag::TEMPERATURE_REJECTION,
    // a temperature, a count and 3 × 2 factors a size, and a list entry a particle
    memory: (8 + 8 + 48, 8)
);

/// An entry of low-rank DSMC (Osinsky 2023 §5) on engine `$scheme`.
macro_rules! dsmc_entry {
    ($entry:ident, $name:expr, $summary:expr, $scheme:ident, $tag:expr) => {
        #[doc = concat!("The registry entry `", $name, "`.")]
        pub struct $entry;

        impl Register for $entry {
            const INFO: &'static SchemeInfo = &SchemeInfo {
                name: $name,
                paper: "Osinsky 2023, §5",
                summary: $summary,
                model: ModelKind::Gas,
                inits: &[InitKind::Velocities],
                sizes: Samples::None,
                fragmentation: false,
                options: &["directions"],
                memory: Memory::Growing,
                tag: $tag,
                observables: &[
                    "energy",
                    "mean-temperature",
                    "momentum-x",
                    "momentum-y",
                    "momentum-z",
                ],
                law: Law::Gas,
            };

            fn build<K, F, G>(
                model: Model<K, F>,
                init: &Init<'_>,
                opts: &Options,
            ) -> Result<Box<dyn Simulation<K, F, G>>>
            where
                K: RegistryKernel,
                F: RegistryFragmentation,
                G: Rng + ?Sized + 'static,
            {
                let Model::Gas(g) = model else {
                    return Err(Error::Unsupported {
                        what: "model: this scheme takes a gas",
                    });
                };
                let &Init::Velocities {
                    sizes,
                    velocities,
                    volume,
                } = init
                else {
                    return Err(Error::Unsupported {
                        what: "initial state: this scheme starts from particles with velocities",
                    });
                };
                let (vel, rest) = velocities.as_chunks::<3>();
                if !rest.is_empty() || vel.len() != sizes.len() {
                    return Err(Error::BufferLength {
                        name: "velocities (three per particle)",
                        expected: sizes.len().saturating_mul(3),
                        got: velocities.len(),
                    });
                }
                // a gas that never sticks runs on `NeverStick` (the acceptance-rejection
                // engine's proposal loop is 30 % faster without the threshold:
                // docs/results/registry-ab.md)
                macro_rules! with {
                    ($stick:expr) => {{
                        let gas = Gas::from_particles(g.restitution(), $stick, sizes, vel)?
                            .with_directions(opts.directions());
                        let s = $scheme::new_gas(gas, volume)?;
                        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
                    }};
                }
                if g.sticking().speed > 0.0 {
                    with!(g.sticking())
                } else {
                    with!(NeverStick)
                }
            }

            fn memory_estimate(
                _init: &Init<'_>,
                _opts: &Options,
                _fragments: bool,
                reach: &Reach,
            ) -> u64 {
                // a velocity and a class entry a particle, a species (its classes and
                // trees' leaves) a size up to the largest
                reach.bytes(reach.start, 64, 40, 0)
            }

            fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
                Blank::Velocities
            }
        }
    };
}

dsmc_entry!(
    DsmcEntry,
    "dsmc",
    "low-rank direct simulation Monte Carlo of a hard-sphere gas (per-size trees)",
    LowRankDsmc,
    tag::DSMC
);
dsmc_entry!(
    DsmcRejectionEntry,
    "dsmc-rejection",
    "DSMC by acceptance-rejection (uniform pairs), the paper's baseline",
    RejectionDsmc,
    tag::DSMC_REJECTION
);

count_controls!([K: CoagulationKernel, const R: usize, E: ProposalEngine<R>] LowRankMc<K, R, E, Coagulate>, |s| s.counts(), edits = true);
count_controls!([K: CoagulationKernel + Clone, const R: usize, const W: usize] AutoBucketed<K, R, W>, |s| s.counts(), engine = |s| s.mode(), edits = true);

impl<K: CoagulationKernel, F, const R: usize, const W: usize> Controls<K, F>
    for LowRankSizes<K, R, W>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        LowRankSizes::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        LowRankSizes::set_kernel(self, kernel)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        LowRankSizes::set_time(self, t)
    }
    fn set_doubling(&mut self, on: bool) {
        LowRankSizes::set_doubling(self, on)
    }
    fn edits(&self) -> bool {
        true
    }
    fn draw_particle<G: Rng + ?Sized>(&self, by_mass: bool, rng: &mut G) -> Option<(f64, u64)> {
        if by_mass {
            return None;
        }
        LowRankSizes::draw_particle(self, rng)
    }
    fn remove_drawn(&mut self, x: f64, handle: u64) -> Result<()> {
        LowRankSizes::remove_drawn(self, x, handle)
    }
    fn add_particle(&mut self, x: f64) -> Result<()> {
        LowRankSizes::add_particle(self, x)
    }
}

impl<K, F, TK, E> Controls<K, F> for LowRankMc<Temperatures<TK>, 3, E, Collide>
where
    TK: TemperatureKernel + Clone,
    E: ProposalEngine<3>,
{
    fn state(&self) -> State<'_> {
        State::Counts(self.counts(), self.volume())
    }
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()> {
        LowRankMc::for_each_count(self, f);
        Ok(())
    }
    fn max_size(&self) -> Option<u64> {
        Some(LowRankMc::max_size(self) as u64)
    }
    fn size_values(&self, name: &str, f: &mut dyn FnMut(u64, f64)) -> Result<()> {
        if name != "temperature" {
            return Err(Error::Unsupported {
                what: "per-size values: the temperature-dependent schemes keep \"temperature\"",
            });
        }
        LowRankMc::for_each_count(self, &mut |s, _| f(s, self.temperature(s)));
        Ok(())
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        LowRankMc::set_time(self, t)
    }
}

impl<K, F, S, E> Controls<K, F> for LowRankMc<Gas<S>, 3, E, Collisions>
where
    S: Sticking + Clone,
    E: ProposalEngine<3>,
{
    fn state(&self) -> State<'_> {
        State::Counts(self.counts(), self.volume())
    }
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()> {
        LowRankMc::for_each_count(self, f);
        Ok(())
    }
    fn max_size(&self) -> Option<u64> {
        Some(LowRankMc::max_size(self) as u64)
    }
    fn size_values(&self, name: &str, f: &mut dyn FnMut(u64, f64)) -> Result<()> {
        if name != "temperature" {
            return Err(Error::Unsupported {
                what: "per-size values: DSMC keeps \"temperature\" (m <|V|^2>/3 of each size)",
            });
        }
        LowRankMc::for_each_count(self, &mut |s, _| f(s, self.temperature(s)));
        Ok(())
    }
    fn velocities(&self, f: &mut dyn FnMut(u64, &[f64; 3])) -> Result<()> {
        let mut sizes = alloc::vec::Vec::new();
        LowRankMc::for_each_count(self, &mut |s, _| sizes.push(s));
        for s in sizes {
            for v in self.kernel().velocities(s) {
                f(s, v);
            }
        }
        Ok(())
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        LowRankMc::set_time(self, t)
    }
}

/// The temperature scheme's named observables.
pub(super) fn temperature_observable<TK, E>(
    s: &LowRankMc<Temperatures<TK>, 3, E, Collide>,
    name: &str,
) -> Option<f64>
where
    TK: TemperatureKernel + Clone,
    E: ProposalEngine<3>,
{
    match name {
        "mean-temperature" => Some(s.mean_temperature()),
        "energy" => Some(s.energy()),
        _ => None,
    }
}

/// DSMC's named observables.
pub(super) fn gas_observable<S, E>(
    s: &LowRankMc<Gas<S>, 3, E, Collisions>,
    name: &str,
) -> Option<f64>
where
    S: Sticking + Clone,
    E: ProposalEngine<3>,
{
    let p = || s.momentum();
    match name {
        "energy" => Some(s.energy()),
        "mean-temperature" => Some(s.mean_temperature()),
        "momentum-x" => Some(p()[0]),
        "momentum-y" => Some(p()[1]),
        "momentum-z" => Some(p()[2]),
        _ => None,
    }
}
