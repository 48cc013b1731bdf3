//! The time-driven mass-flow scheme's registry entry and facade controls.

use super::{MassFlow, workspace_len};
use crate::error::{Error, Result};
use crate::kernel::{CoagulationKernel, FragmentationKernel};
use crate::process::{Books, Processes};
use crate::scheme::facade::{
    Blank, Boxed, Controls, Init, InitKind, Memory, Model, ModelKind, Options, Reach, Register,
    RegistryFragmentation, RegistryKernel, Samples, SchemeInfo, Simulation, State,
};
use crate::scheme::{Budget, StepReport, tag};
use alloc::boxed::Box;
use rand_core::Rng;

/// The registry entry of [`MassFlow`].
pub struct MassFlowEntry;

impl Register for MassFlowEntry {
    const INFO: &'static SchemeInfo = &SchemeInfo {
        name: "massflow",
        paper: "Lécot, L'Ecuyer, El Haddad & Tarhini 2019, §3",
        summary: "time-driven mass flow, QMC/MC/RQMC, coagulation-fragmentation",
        model: ModelKind::Coagulation,
        inits: &[InitKind::Sizes],
        sizes: Samples::Mass,
        fragmentation: true,
        options: &["dt", "points", "randomization", "sorting", "memory-budget"],
        memory: Memory::Fixed,
        tag: tag::MASSFLOW,
        observables: &[],
        law: crate::scheme::facade::Law::TimeStepped,
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
            return Err(unsupported());
        };
        let s = MassFlow::new(kernel, frag, sizes, mass, opts.dt(), opts.point_source()?)?
            .with_sorting(opts.sorting());
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
            return Err(unsupported());
        };
        let s = MassFlow::new_in(
            kernel,
            frag,
            sizes,
            mass,
            opts.dt(),
            opts.point_source()?,
            workspace,
        )?
        .with_sorting(opts.sorting());
        Ok(Boxed::<Self, _, _, _>::new(s, model, init, opts).boxed())
    }

    fn workspace_len(particles: usize, _opts: &Options, _fragments: bool) -> Option<usize> {
        workspace_len(particles)
    }

    fn memory_estimate(_init: &Init<'_>, _opts: &Options, _fragments: bool, reach: &Reach) -> u64 {
        // sizes, masses and the sort's workspace: 48 bytes a particle, which never grow
        reach.bytes(0, 0, 48, 0)
    }

    fn blank(init: &Init<'_>, _opts: &Options, _fragments: bool) -> Blank {
        match *init {
            Init::Sizes { sizes, mass } => Blank::Sizes {
                size: sizes.iter().copied().reduce(f64::min).unwrap_or(1.0),
                n: sizes.len(),
                mass,
                capacity: 0,
            },
            _ => Blank::Counts(alloc::vec![2], 1.0),
        }
    }
}

fn unsupported() -> Error {
    Error::Unsupported {
        what: "initial state: the mass-flow scheme starts from sizes",
    }
}

impl<K: CoagulationKernel, F: FragmentationKernel, B: AsRef<[f64]> + AsMut<[f64]>> Controls<K, F>
    for MassFlow<K, F, B>
{
    fn state(&self) -> State<'_> {
        State::Sizes(self.sizes())
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        MassFlow::set_sizes(self, sizes)
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        MassFlow::set_kernel(self, kernel);
        Ok(())
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        MassFlow::set_fragmentation(self, frag);
        Ok(())
    }
    fn set_dt(&mut self, dt: f64) -> Result<()> {
        MassFlow::set_dt(self, dt)
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        MassFlow::set_time(self, t)
    }
    fn set_mass(&mut self, mass: f64) -> Result<()> {
        MassFlow::set_mass(self, mass)
    }
    fn runs_processes(&self) -> bool {
        true
    }
    fn advance_processes<G: Rng + ?Sized>(
        &mut self,
        procs: &Processes,
        books: &mut Books,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport> {
        MassFlow::advance_processes(self, procs, books, t, budget, rng)
    }
    fn carried_mass(&self) -> Option<f64> {
        Some(self.mass())
    }
}
