//! The registry entries and facade controls of Eibeck & Wagner's schemes: the mass
//! flow algorithm, direct simulation over particles and over size counts.

use super::{Dsa, DsaCounts, Mfa, workspace_len};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::scheme::facade::{
    Blank, Boxed, Controls, Init, InitKind, Law, Memory, Model, ModelKind, Options, Reach,
    Register, RegistryFragmentation, RegistryKernel, Samples, SchemeInfo, Simulation, State,
    count_controls, number_volume,
};
use crate::scheme::tag;
use alloc::boxed::Box;
use alloc::vec;
use rand_core::Rng;

fn sizes_only() -> Error {
    Error::Unsupported {
        what: "initial state: this scheme starts from particle sizes",
    }
}

/// Direct simulation's particle capacity under `opts`: the initial number `n`, four
/// times it with fragmentation, unless given.
fn dsa_capacity(n: usize, fragments: bool, opts: &Options) -> usize {
    match opts.capacity() {
        0 if !fragments => n.max(1),
        0 => n.saturating_mul(4).max(1),
        c => c,
    }
}

/// The smallest size of `init` (1 when it holds none).
fn smallest(init: &Init<'_>) -> (f64, usize, f64) {
    match *init {
        Init::Sizes { sizes, mass } => (
            sizes.iter().copied().reduce(f64::min).unwrap_or(1.0),
            sizes.len(),
            mass,
        ),
        _ => (1.0, 1, 1.0),
    }
}

/// The registry entry of [`Mfa`].
pub struct MfaEntry;

impl Register for MfaEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "mfa",
        paper: "Eibeck & Wagner 2000, §4 (the mass flow algorithm)",
        summary: "event-driven mass flow algorithm, gel by truncation, fragmentation events",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Sizes],
        sizes: Samples::Mass,
        fragmentation: true,
        options: &["truncation", "strict-bound", "sampler", "memory-budget"],
        memory: Memory::Fixed,
        tag: tag::MFA,
        observables: &[],
        law: Law::MassFlow,
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
        let (kernel, frag) = model.kernels()?;
        let &Init::Sizes { sizes, mass } = init else {
            return Err(sizes_only());
        };
        let s = Mfa::new(kernel, frag, sizes, mass)?;
        let s = configure_mfa(s, opts)?;
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn build_in<'a, K, F, G>(
        model: Model<K, F>,
        init: &Init<'_>,
        opts: &Options,
        workspace: &'a mut [f64],
    ) -> Result<Box<dyn Simulation<K, F, G> + 'a>>
    where
        K: RegistryKernel,
        F: RegistryFragmentation,
        G: Rng + ?Sized + 'static,
    {
        let (kernel, frag) = model.kernels()?;
        let &Init::Sizes { sizes, mass } = init else {
            return Err(sizes_only());
        };
        let s = Mfa::new_in(kernel, frag, sizes, mass, workspace)?;
        let s = configure_mfa(s, opts)?;
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn workspace_len(particles: usize, _opts: &Options, _fragments: bool) -> Option<usize> {
        workspace_len(particles)
    }

    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        // seven doubles a particle, which never grow
        reach.bytes(0, 0, 56, 0)
    }

    fn blank(init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        // the mass flow algorithm's checkpoint is for its initial number of particles
        let (size, n, mass) = smallest(init);
        Blank::Sizes {
            size,
            n,
            mass,
            capacity: 0,
        }
    }
}

fn configure_mfa<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>(
    s: Mfa<K, F, B>,
    opts: &Options,
) -> Result<Mfa<K, F, B>> {
    let s = s
        .with_truncation(opts.truncation())?
        .with_strict_bound(opts.strict_bound());
    match opts.sampler() {
        Some(x) => s.with_sampler(x),
        None => Ok(s),
    }
}

/// The registry entry of [`Dsa`].
pub struct DsaEntry;

impl Register for DsaEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "dsa",
        paper: "Eibeck & Wagner 2000, §3 (direct simulation, Marcus-Lushnikov)",
        summary: "direct simulation over particles (Marcus-Lushnikov), fragmentation events",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Sizes],
        sizes: Samples::Number,
        fragmentation: true,
        options: &["capacity", "strict-bound", "sampler", "memory-budget"],
        memory: Memory::Fixed,
        tag: tag::DSA,
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
        let fragments = model.fragments();
        let (kernel, frag) = model.kernels()?;
        let &Init::Sizes { sizes, mass } = init else {
            return Err(sizes_only());
        };
        let cap = dsa_capacity(sizes.len(), fragments, opts);
        let s = Dsa::new(kernel, frag, sizes, number_volume(sizes, mass)?, cap)?;
        let s = configure_dsa(s, opts)?;
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn build_in<'a, K, F, G>(
        model: Model<K, F>,
        init: &Init<'_>,
        opts: &Options,
        workspace: &'a mut [f64],
    ) -> Result<Box<dyn Simulation<K, F, G> + 'a>>
    where
        K: RegistryKernel,
        F: RegistryFragmentation,
        G: Rng + ?Sized + 'static,
    {
        let fragments = model.fragments();
        let (kernel, frag) = model.kernels()?;
        let &Init::Sizes { sizes, mass } = init else {
            return Err(sizes_only());
        };
        let cap = dsa_capacity(sizes.len(), fragments, opts);
        let v = number_volume(sizes, mass)?;
        let s = Dsa::new_in(kernel, frag, sizes, v, cap, workspace)?;
        let s = configure_dsa(s, opts)?;
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn workspace_len(particles: usize, opts: &Options, fragments: bool) -> Option<usize> {
        workspace_len(dsa_capacity(particles, fragments, opts))
    }

    fn memory_estimate(_init: &Init<'_>, opts: &Options, fragments: bool, reach: &Reach) -> u64 {
        // seven doubles a particle of the capacity (room for fragments)
        let n = usize::try_from(reach.particles).unwrap_or(usize::MAX);
        8 * 7 * dsa_capacity(n, fragments, opts).max(n) as u64
    }

    fn blank(init: &Init<'_>, opts: &Options, fragments: bool) -> Blank {
        // one particle in volume 1 (a state may be empty, or sum past the largest
        // double; the checkpoint carries the volume), with the original's capacity
        let (size, n, _) = smallest(init);
        Blank::Sizes {
            size,
            n: 1,
            mass: size,
            capacity: dsa_capacity(n, fragments, opts),
        }
    }
}

fn configure_dsa<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>>(
    s: Dsa<K, F, B>,
    opts: &Options,
) -> Result<Dsa<K, F, B>> {
    let s = s.with_strict_bound(opts.strict_bound());
    match opts.sampler() {
        Some(x) => s.with_sampler(x),
        None => Ok(s),
    }
}

/// The registry entry of [`DsaCounts`].
pub struct DsaCountsEntry;

impl Register for DsaCountsEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "dsa-counts",
        paper: "Eibeck & Wagner 2000, §3 (direct simulation over size counts)",
        summary: "direct simulation over size counts (integer sizes, no doubling)",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Counts],
        sizes: Samples::None,
        fragmentation: false,
        options: &["size-limit", "memory-budget", "strict-bound"],
        memory: Memory::Growing,
        tag: tag::DSA_COUNTS,
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
        let &Init::Counts { counts, volume } = init else {
            return Err(Error::Unsupported {
                what: "initial state: dsa-counts starts from counts",
            });
        };
        crate::scheme::population::check_within_limit(counts, opts.size_limit())?;
        let s = DsaCounts::new_with_memory_budget(kernel, counts, volume, opts.memory_budget())?
            .with_size_limit(opts.size_limit())
            .with_strict_bound(opts.strict_bound());
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        // a doubling table of counts, rates, majorants and 2R cached factors a size
        // (`DsaCounts::grow`); no particle doubling: the system shrinks as it grows
        let reach = reach.without_doubling();
        let first = reach.start.max(1).next_power_of_two();
        reach.bytes(first, 32 + 16 * reach.rank as u64, 0, 0)
    }

    fn blank(_init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        // empty: a kernel's min_size may exclude size 1, and no majorant is needed at a
        // size nobody holds
        Blank::Counts(vec![0], 1.0)
    }
}

count_controls!([K: CoagulationKernel] DsaCounts<K>, |s| s.counts(), edits = true);

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Controls<K, F>
    for Mfa<K, F, B>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        Mfa::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        Mfa::set_kernel(self, kernel)
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        Mfa::set_fragmentation(self, frag)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        Mfa::set_time(self, t)
    }
    fn set_mass(&mut self, mass: f64) -> Result<()> {
        Mfa::set_mass(self, mass)
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Controls<K, F>
    for Dsa<K, F, B>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        Dsa::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        Dsa::set_kernel(self, kernel)
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        Dsa::set_fragmentation(self, frag)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        Dsa::set_time(self, t)
    }
    fn edits(&self) -> bool {
        true
    }
    fn draw_particle<G: rand_core::Rng + ?Sized>(
        &self,
        by_mass: bool,
        rng: &mut G,
    ) -> Option<(f64, u64)> {
        if by_mass {
            return None;
        }
        Dsa::draw_particle(self, rng)
    }
    fn remove_drawn(&mut self, x: f64, handle: u64) -> Result<()> {
        Dsa::remove_drawn(self, x, handle)
    }
    fn add_particle(&mut self, x: f64) -> Result<()> {
        Dsa::add_particle(self, x)
    }
    fn set_mass(&mut self, _mass: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "mass: direct simulation's mass is its sizes over its volume (set its sizes instead)",
        })
    }
}
