//! The registry entries and facade controls of low-rank's baselines (Osinsky 2023 §2):
//! the inverse method and acceptance–rejection.

use super::{AcceptanceRejection, Inverse};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::scheme::facade::{
    Blank, Boxed, Init, InitKind, Law, Memory, Model, ModelKind, Options, Reach, Register,
    RegistryFragmentation, RegistryKernel, Samples, SchemeInfo, Simulation, count_controls,
};
use crate::scheme::population::check_within_limit;
use crate::scheme::tag;
use alloc::borrow::Cow;
use alloc::boxed::Box;
use alloc::vec;
use rand_core::Rng;

fn counts_of<'a>(init: &Init<'a>) -> Result<(&'a [u64], f64)> {
    match *init {
        Init::Counts { counts, volume } => Ok((counts, volume)),
        _ => Err(Error::Unsupported {
            what: "initial state: this scheme starts from counts of integer sizes",
        }),
    }
}

/// The registry entry of [`Inverse`].
pub struct InverseEntry;

impl Register for InverseEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "inverse",
        paper: "Osinsky 2023, §2 (the inverse method, Gillespie on sizes)",
        summary: "inverse method (Gillespie on sizes), the low-rank baseline",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Counts],
        sizes: Samples::None,
        fragmentation: false,
        options: &["size-limit", "memory-budget"],
        memory: Memory::Growing,
        tag: tag::INVERSE,
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
        let (kernel, _) = model.kernels()?;
        let (counts, volume) = counts_of(init)?;
        check_within_limit(counts, opts.size_limit())?;
        let s = Inverse::new_with_memory_budget(kernel, counts, volume, opts.memory_budget())?
            .with_size_limit(opts.size_limit());
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        // a u32 slot a size (doubling), six words per occupied size (at most the
        // particles), and the kernel cache of up to CACHE_DIM² doubles, whose side
        // doubles with the largest size
        let first = reach.start.max(1).next_power_of_two();
        let occupied = reach.largest.min(reach.particles);
        let dim = reach
            .table_len(first)
            .min(reach.particles)
            .min(super::CACHE_DIM as u64);
        reach
            .bytes(first, 4, 0, 0)
            .saturating_add(occupied.saturating_mul(48))
            .saturating_add(dim.saturating_mul(dim).saturating_mul(8))
    }

    fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        Blank::Counts(vec![2], 1.0)
    }
}

/// The registry entry of [`AcceptanceRejection`].
pub struct RejectionEntry;

impl Register for RejectionEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "rejection",
        paper: "Osinsky 2023, §2 (acceptance-rejection with the kernel's supremum)",
        summary: "acceptance-rejection with the kernel's supremum, the low-rank baseline",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Counts],
        sizes: Samples::None,
        fragmentation: false,
        options: &["size-limit", "memory-budget"],
        memory: Memory::Growing,
        tag: tag::REJECTION,
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
        let (kernel, _) = model.kernels()?;
        let (counts, volume) = counts_of(init)?;
        check_within_limit(counts, opts.size_limit())?;
        let s = AcceptanceRejection::new_with_memory_budget(
            kernel,
            counts,
            volume,
            opts.memory_budget(),
        )?
        .with_size_limit(opts.size_limit());
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        // one size a particle, room for N0 (and the list's growth slack): nothing a size
        reach.bytes(0, 0, 12, 0)
    }

    fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        Blank::Counts(vec![2], 1.0)
    }
}

count_controls!([K: CoagulationKernel + Clone] Inverse<K>, |s| Cow::Owned(s.counts()), edits = true);
count_controls!([K: CoagulationKernel] AcceptanceRejection<K>, |s| Cow::Owned(s.counts()), edits = true);
