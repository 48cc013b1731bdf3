//! The registry entries and facade controls of low-rank's baselines (Osinsky 2023 §2):
//! the inverse method and acceptance–rejection.

use super::{AcceptanceRejection, Inverse};
use crate::error::{Error, Result};
use crate::kernel::CoagulationKernel;
use crate::scheme::facade::{
    Blank, Boxed, Init, InitKind, Law, Memory, Model, ModelKind, Options, Register,
    RegistryFragmentation, RegistryKernel, Samples, SchemeInfo, Simulation, count_controls,
};
use crate::scheme::population::{check_within_limit, counts_memory};
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

    fn memory_estimate(init: &Init<'_>, _opts: &Options, _fragments: bool) -> u64 {
        counts_memory(init)
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

    fn memory_estimate(init: &Init<'_>, _opts: &Options, _fragments: bool) -> u64 {
        // one size per particle and the dense count vector of a read
        match *init {
            Init::Counts { counts, .. } => {
                let n = counts.iter().fold(0u64, |a, &c| a.saturating_add(c));
                n.saturating_mul(16)
                    .saturating_add(64 * counts.len() as u64)
            }
            _ => 0,
        }
    }

    fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        Blank::Counts(vec![2], 1.0)
    }
}

count_controls!([K: CoagulationKernel + Clone] Inverse<K>, |s| Cow::Owned(s.counts()));
count_controls!([K: CoagulationKernel] AcceptanceRejection<K>, |s| Cow::Owned(s.counts()));
