//! What a scheme implements for the facade ([`Controls`]) and the box that turns it
//! into a [`Simulation`] ([`Boxed`]).

use super::driven::Driver;
use super::model::{Blank, Init, Model};
use super::options::{BucketMode, Options};
use super::{
    GrowthKind, Register, RegistryFragmentation, RegistryKernel, SchemeInfo, Simulation, State,
};
use crate::checkpoint::{Checkpoint, Reader, Writer};
use crate::error::{Error, Result};
use crate::observe::Observe;
use crate::process::{Books, Processes};
use crate::scheme::{Budget, Scheme, StepReport};
use alloc::boxed::Box;
use alloc::vec::Vec;
use core::marker::PhantomData;
use rand_core::Rng;

/// What a scheme exposes to the facade beyond [`Scheme`], [`Observe`] and
/// [`Checkpoint`]: its state and what can be replaced. The defaults refuse.
pub trait Controls<K, F> {
    /// The state.
    fn state(&self) -> State<'_>;
    /// The occupied sizes and their counts, ascending.
    fn for_each_count(&self, _f: &mut dyn FnMut(u64, u64)) -> Result<()> {
        Err(Error::Unsupported {
            what: "counts: this scheme's state is particle sizes (use the sizes)",
        })
    }
    /// Largest size the state can hold now.
    fn max_size(&self) -> Option<u64> {
        None
    }
    /// The bucketed low-rank scheme's engine.
    fn engine(&self) -> Option<BucketMode> {
        None
    }
    /// A per-size quantity by name.
    fn size_values(&self, _name: &str, _f: &mut dyn FnMut(u64, f64)) -> Result<()> {
        Err(Error::Unsupported {
            what: "per-size values: this scheme keeps none (the temperature-dependent schemes and DSMC keep \"temperature\")",
        })
    }
    /// The particles' velocities.
    fn velocities(&self, _f: &mut dyn FnMut(u64, &[f64; 3])) -> Result<()> {
        Err(Error::Unsupported {
            what: "velocities: only the DSMC schemes' particles carry them",
        })
    }
    /// Replaces counts and volume.
    fn set_counts(&mut self, _counts: &[u64], _volume: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "counts: this scheme's state is not counts of integer sizes alone (a temperature or gas state is set by building a new simulation)",
        })
    }
    /// Replaces the state from `(size, count)` pairs.
    fn set_pairs(&mut self, _sizes: &[u64], _counts: &[u64], _volume: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "pairs: this scheme's state is not counts of integer sizes alone",
        })
    }
    /// Replaces the sizes.
    fn set_sizes(&mut self, _sizes: &[f64]) -> Result<()> {
        Err(Error::Unsupported {
            what: "sizes: this scheme's state is not a list of particle sizes (a counts scheme takes set_counts; a temperature or gas state is set by building a new simulation)",
        })
    }
    /// Replaces the coagulation kernel.
    fn set_kernel(&mut self, _kernel: K) -> Result<()> {
        Err(Error::Unsupported {
            what: "kernel: this scheme's physics is a temperature model or a gas, not a coagulation kernel",
        })
    }
    /// Replaces the fragmentation kernel.
    fn set_fragmentation(&mut self, _frag: F) -> Result<()> {
        Err(Error::Unsupported {
            what: "fragmentation: only massflow, mfa and dsa break particles",
        })
    }
    /// Changes the time step.
    fn set_dt(&mut self, _dt: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "dt: event-driven schemes have no time step",
        })
    }
    /// Sets the clock.
    fn set_time(&mut self, t: f64) -> Result<()>;
    /// Turns particle doubling on or off (off while processes run); a scheme that never
    /// doubles ignores it.
    fn set_doubling(&mut self, _on: bool) {}
    /// Whether the scheme edits single particles cheaply (an O(buckets) or O(1) draw,
    /// an O(1) or O(log N) edit): processes then need no state replacement.
    fn edits(&self) -> bool {
        false
    }
    /// Whether [`draw_particle`](Self::draw_particle) draws by mass too (not only
    /// uniformly).
    fn draws_by_mass(&self) -> bool {
        false
    }
    /// A particle drawn uniformly (`by_mass`: in proportion to its size): its size and
    /// a handle for [`remove_drawn`](Self::remove_drawn) (schemes that edit).
    fn draw_particle<G: Rng + ?Sized>(&self, _by_mass: bool, _rng: &mut G) -> Option<(f64, u64)> {
        None
    }
    /// Removes the particle a draw returned (schemes that edit).
    fn remove_drawn(&mut self, _x: f64, _handle: u64) -> Result<()> {
        Err(Error::Unsupported {
            what: "single-particle edits on this scheme",
        })
    }
    /// Adds a particle of size `x` (an integer on an integer-size scheme; schemes that
    /// edit).
    fn add_particle(&mut self, _x: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "single-particle edits on this scheme",
        })
    }
    /// Whether the scheme runs the processes inside its own steps (the time-driven
    /// mass flow: [`advance_processes`](Self::advance_processes)) rather than as
    /// events the driver draws over its clock.
    fn runs_processes(&self) -> bool {
        false
    }
    /// Advances to `t` within `budget` with `procs` in the scheme's own steps, entered
    /// in `books` (schemes that [`run processes`](Self::runs_processes)).
    fn advance_processes<G: Rng + ?Sized>(
        &mut self,
        _procs: &Processes,
        _books: &mut Books,
        _t: f64,
        _budget: &mut Budget<'_>,
        _rng: &mut G,
    ) -> Result<StepReport> {
        Err(Error::Unsupported {
            what: "processes inside this scheme's steps (the driver runs them)",
        })
    }
    /// The mass the scheme carries apart from its state (the mass flow's M1), where
    /// its books start.
    fn carried_mass(&self) -> Option<f64> {
        None
    }
    /// Changes the total mass.
    fn set_mass(&mut self, _mass: f64) -> Result<()> {
        Err(Error::Unsupported {
            what: "mass: only the mass-flow schemes (massflow, mfa) carry a mass apart from their state",
        })
    }
}

/// A registered scheme `S` (entry `E`) behind the facade, with what the facade keeps
/// beside it: the physics, the settings as built and as they stand, and the blank a
/// clone is built from.
pub struct Boxed<E, S, K, F> {
    s: S,
    /// The processes beside coagulation, when set.
    driver: Option<Driver>,
    model: Model<K, F>,
    built: Options,
    opts: Options,
    blank: Blank,
    _entry: PhantomData<fn() -> E>,
}

impl<E: Register, S, K, F> Boxed<E, S, K, F>
where
    K: RegistryKernel,
    F: RegistryFragmentation,
{
    /// `s` built from `init` under `model` and `opts`.
    pub fn new(s: S, model: Model<K, F>, init: &Init<'_>, opts: &Options) -> Self {
        let fragments = model.fragments();
        Boxed {
            s,
            driver: None,
            model,
            built: opts.clone(),
            opts: opts.clone(),
            blank: E::blank(init, opts, fragments),
            _entry: PhantomData,
        }
    }

    /// Into the facade.
    pub fn boxed<'a, G>(self) -> Box<dyn Simulation<K, F, G> + 'a>
    where
        S: Scheme + Observe + Checkpoint + Controls<K, F> + Send + 'a,
        E: 'a,
        G: Rng + ?Sized + 'static,
    {
        Box::new(self)
    }
}

impl<E, S, K, F> Boxed<E, S, K, F>
where
    S: Controls<K, F>,
{
    /// The host replaced the state: the processes' books start from it (and doubling
    /// stays off while they run).
    fn rebase(&mut self) -> Result<()> {
        match &mut self.driver {
            Some(d) => {
                self.s.set_doubling(false);
                d.rebase(&self.s)
            }
            None => Ok(()),
        }
    }
}

impl<E, S: Observe, K, F> Observe for Boxed<E, S, K, F> {
    fn volume(&self) -> f64 {
        self.s.volume()
    }
    fn particles(&self) -> u64 {
        self.s.particles()
    }
    fn moment(&self, order: f64) -> f64 {
        self.s.moment(order)
    }
    fn concentration(&self, a: f64, b: f64) -> f64 {
        self.s.concentration(a, b)
    }
    fn number_density(&self, x: f64) -> f64 {
        self.s.number_density(x)
    }
    fn points(&self, f: &mut dyn FnMut(f64, f64)) {
        self.s.points(f)
    }
    fn gel_mass(&self) -> Option<f64> {
        self.s.gel_mass()
    }
    fn observable(&self, name: &str) -> Option<f64> {
        self.s.observable(name)
    }
}

impl<E, S, K, F, G> Simulation<K, F, G> for Boxed<E, S, K, F>
where
    E: Register,
    S: Scheme + Observe + Checkpoint + Controls<K, F> + Send,
    K: RegistryKernel,
    F: RegistryFragmentation,
    G: Rng + ?Sized + 'static,
{
    fn info(&self) -> &'static SchemeInfo {
        E::INFO
    }
    fn time(&self) -> f64 {
        self.s.time()
    }
    fn totals(&self) -> StepReport {
        self.s.totals()
    }
    fn advance_to(&mut self, t: f64, rng: &mut G) -> Result<StepReport> {
        match &mut self.driver {
            Some(d) => d.advance(&mut self.s, t, &mut Budget::unlimited(), rng),
            None => self.s.advance_to(t, rng),
        }
    }
    fn advance_within(
        &mut self,
        t: f64,
        budget: &mut Budget<'_>,
        rng: &mut G,
    ) -> Result<StepReport> {
        match &mut self.driver {
            Some(d) => d.advance(&mut self.s, t, budget, rng),
            None => self.s.advance_within(t, budget, rng),
        }
    }
    fn set_processes(&mut self, procs: Option<Processes>) -> Result<()> {
        let Some(procs) = procs.filter(|p| !p.is_empty()) else {
            self.driver = None;
            self.s.set_doubling(true);
            return Ok(());
        };
        E::INFO.takes_processes(&procs)?;
        if self.model.fragments() && !E::INFO.processes_with_fragmentation() {
            // a fragmentation raises the particle number: the thinning bound would not hold
            return Err(Error::Unsupported {
                what: "processes beside coagulation with a fragmentation kernel on this scheme (they run with coagulation alone here; massflow takes both)",
            });
        }
        if E::INFO.growth_kind() == GrowthKind::InStep && procs.growth_step.is_some() {
            return Err(Error::Unsupported {
                what: "a growth step on the mass flow (it grows the sizes in its own step, dt)",
            });
        }
        let integer = matches!(self.s.state(), State::Counts(..));
        if E::INFO.growth_kind() == GrowthKind::Split
            && procs.grows()
            && procs.growth_step.is_none()
        {
            return Err(Error::Unsupported {
                what: "growth on real sizes without a growth step (it is split: set the step first); on the integer-size schemes, lowrank among them, growth is exact monomer attachment",
            });
        }
        let mut d = Driver::new(procs, integer, 0, 0.0);
        d.rebase(&self.s)?;
        d.start(self.s.time(), self.driver.as_ref());
        self.driver = Some(d);
        // the processes set the particle number: no doubling while they run
        self.s.set_doubling(false);
        Ok(())
    }
    fn processes(&self) -> Option<&Processes> {
        self.driver.as_ref().map(Driver::processes)
    }
    fn books(&self) -> Option<Books> {
        self.driver.as_ref().map(Driver::books)
    }
    fn state(&self) -> State<'_> {
        self.s.state()
    }
    fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> Result<()> {
        self.s.for_each_count(f)
    }
    fn max_size(&self) -> Option<u64> {
        self.s.max_size()
    }
    fn engine(&self) -> Option<BucketMode> {
        self.s.engine()
    }
    fn size_values(&self, name: &str, f: &mut dyn FnMut(u64, f64)) -> Result<()> {
        self.s.size_values(name, f)
    }
    fn velocities(&self, f: &mut dyn FnMut(u64, &[f64; 3])) -> Result<()> {
        self.s.velocities(f)
    }
    fn set_counts(&mut self, counts: &[u64], volume: f64) -> Result<()> {
        self.s.set_counts(counts, volume)?;
        self.rebase()
    }
    fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> Result<()> {
        self.s.set_pairs(sizes, counts, volume)?;
        self.rebase()
    }
    fn set_sizes(&mut self, sizes: &[f64]) -> Result<()> {
        self.s.set_sizes(sizes)?;
        self.rebase()
    }
    fn set_kernel(&mut self, kernel: K) -> Result<()> {
        let Model::Coagulation { fragmentation, .. } = &self.model else {
            return Controls::<K, F>::set_kernel(&mut self.s, kernel);
        };
        let fragmentation = fragmentation.clone();
        self.s.set_kernel(kernel.clone())?;
        self.model = Model::Coagulation {
            kernel,
            fragmentation,
        };
        Ok(())
    }
    fn set_fragmentation(&mut self, frag: F) -> Result<()> {
        let Model::Coagulation { kernel, .. } = &self.model else {
            return Controls::<K, F>::set_fragmentation(&mut self.s, frag);
        };
        let kernel = kernel.clone();
        self.s.set_fragmentation(frag.clone())?;
        self.model = Model::Coagulation {
            kernel,
            fragmentation: frag,
        };
        Ok(())
    }
    fn set_dt(&mut self, dt: f64) -> Result<()> {
        self.s.set_dt(dt)?;
        self.opts.update_dt(dt);
        Ok(())
    }
    fn set_time(&mut self, t: f64) -> Result<()> {
        self.s.set_time(t)?;
        if let Some(d) = &mut self.driver {
            d.forget(t);
        }
        Ok(())
    }
    fn set_mass(&mut self, mass: f64) -> Result<()> {
        self.s.set_mass(mass)?;
        self.rebase()
    }
    fn options(&self) -> &Options {
        &self.opts
    }
    fn model(&self) -> &Model<K, F> {
        &self.model
    }
    fn save(&self, w: &mut Writer) {
        self.s.save(w)
    }
    fn restore(&mut self, r: &mut Reader) -> Result<()> {
        self.s.restore(r)
    }
    fn save_checkpoint(&self, stream: Option<[u64; 4]>, w: &mut Writer) {
        // the records carry the capacity the state has (the option's 0 means "the
        // initial number", which a clone built from a blank would read differently)
        // (a scheme that takes no memory budget records the library's default, not
        // the machine's: a restore ignores the budget, and the same state then
        // writes the same bytes on every machine)
        let held = |o: &Options| {
            let o = match self.blank {
                Blank::Sizes { capacity, .. } if capacity > 0 => o.clone().with_capacity(capacity),
                _ => o.clone(),
            };
            if E::INFO.takes_option("memory-budget") {
                o
            } else {
                o.with_memory_budget(crate::memory::DEFAULT_MEMORY_BUDGET)
            }
        };
        let (built, now) = (held(&self.built).words(), held(&self.opts).words());
        let procs = self.driver.as_ref().map(Driver::record);
        let mut records: [&[u64]; 3] = [&built, &now, &[]];
        let used = match &procs {
            Some(p) => {
                records[2] = p;
                3
            }
            None => 2,
        };
        super::envelope::write_envelope(
            w,
            E::INFO.tag,
            &records[..used],
            self.model.fingerprint(),
            stream,
            |w| self.s.save(w),
        );
    }
    fn restore_checkpoint(&mut self, buf: &[u8]) -> Result<Option<[u64; 4]>> {
        let mut out = None;
        let (s, built, opts) = (&mut self.s, &self.built, &self.opts);
        let driver = &self.driver;
        let mut records = None;
        let mut procs = None;
        super::envelope::read_envelope(
            buf,
            E::INFO.tag,
            self.model.fingerprint(),
            |words| {
                let (settings, rest) = words.split_at(words.len().min(2));
                let r = super::envelope::check_records(built, opts, settings)?;
                procs = match (driver, rest) {
                    (None, []) => None,
                    (Some(d), [p]) => Some(d.read_record(p)?),
                    (None, _) => {
                        return Err(Error::Checkpoint {
                            what: "written with processes beside coagulation: set the same processes before restoring",
                        });
                    }
                    (Some(_), _) => {
                        return Err(Error::Checkpoint {
                            what: "written without processes beside coagulation (or with a malformed process record)",
                        });
                    }
                };
                records = Some(r);
                Ok(())
            },
            |stream, r| {
                out = stream;
                s.restore(r)
            },
        )?;
        if let Some((b, o)) = records {
            self.built = b;
            self.opts = o;
        }
        if let (Some(d), Some(record)) = (&mut self.driver, procs) {
            d.install(record);
            self.s.set_doubling(false);
        }
        Ok(out)
    }
    fn blank(&self) -> Blank {
        // of a size the state holds where it has sizes (a kernel or truncation changed
        // since the build allows that one); only a sizes blank reads the state: a
        // counts state may be too big to list
        let mut blank = self.blank.clone();
        if let Blank::Sizes { size, .. } = &mut blank
            && let State::Sizes(x) = self.s.state()
            && let Some(m) = x.iter().copied().reduce(f64::min)
        {
            *size = m;
        }
        blank
    }
    fn built(&self) -> &Options {
        &self.built
    }
    fn duplicate(&self) -> Result<Box<dyn Simulation<K, F, G>>> {
        // built under the build's settings (a call may have changed dt since; the
        // checkpoint's second record carries the settings now)
        let blank = <Self as Simulation<K, F, G>>::blank(self);
        let mut fresh = blank.build(
            |init, opts| E::build::<K, F, G>(self.model.clone(), init, opts),
            &self.built,
        )?;
        fresh.set_processes(self.driver.as_ref().map(|d| d.processes().clone()))?;
        let mut w = Writer::new(&mut []);
        <Self as Simulation<K, F, G>>::save_checkpoint(self, None, &mut w);
        let mut buf: Vec<u8> = Vec::new();
        buf.try_reserve_exact(w.needed())
            .map_err(|_| Error::Capacity {
                name: "clone: checkpoint buffer (memory)",
                capacity: w.needed(),
            })?;
        buf.resize(w.needed(), 0);
        let mut w = Writer::new(&mut buf);
        <Self as Simulation<K, F, G>>::save_checkpoint(self, None, &mut w);
        w.finish()?;
        fresh.restore_checkpoint(&buf)?;
        Ok(fresh)
    }
}

/// [`Controls`] of an integer-size scheme from its inherent `counts`, `volume`,
/// `max_size`, `for_each_count`, `set_counts`, `set_pairs`, `set_kernel` and
/// `set_time` (one definition for all of them).
macro_rules! count_controls {
    ([$($g:tt)*] $ty:ty, $counts:expr $(, engine = $engine:expr)? $(, edits = $edits:tt)?) => {
        impl<$($g)*, F> $crate::scheme::facade::Controls<K, F> for $ty {
            $(
                fn edits(&self) -> bool {
                    let _ = $edits;
                    <$ty>::edits(self)
                }
                fn draws_by_mass(&self) -> bool {
                    true
                }
                fn draw_particle<G: rand_core::Rng + ?Sized>(
                    &self,
                    by_mass: bool,
                    rng: &mut G,
                ) -> Option<(f64, u64)> {
                    <$ty>::draw_particle(self, by_mass, rng).map(|(x, h)| (x as f64, h))
                }
                // (the driver passes integer sizes to an integer-size scheme)
                fn remove_drawn(&mut self, x: f64, handle: u64) -> $crate::error::Result<()> {
                    <$ty>::remove_drawn(self, x as u64, handle)
                }
                fn add_particle(&mut self, x: f64) -> $crate::error::Result<()> {
                    <$ty>::add_particle(self, x as u64)
                }
            )?
            $(
                fn engine(&self) -> Option<$crate::scheme::facade::BucketMode> {
                    let f: fn(&Self) -> $crate::scheme::facade::BucketMode = $engine;
                    Some(f(self))
                }
            )?
            fn state(&self) -> $crate::scheme::facade::State<'_> {
                let f: fn(&Self) -> alloc::borrow::Cow<'_, [u64]> = $counts;
                $crate::scheme::facade::State::Counts(f(self), $crate::observe::Observe::volume(self))
            }
            fn max_size(&self) -> Option<u64> {
                Some(self.max_size() as u64)
            }
            fn for_each_count(&self, f: &mut dyn FnMut(u64, u64)) -> $crate::error::Result<()> {
                <$ty>::for_each_count(self, f);
                Ok(())
            }
            fn set_counts(&mut self, counts: &[u64], volume: f64) -> $crate::error::Result<()> {
                <$ty>::set_counts(self, counts, volume)
            }
            fn set_pairs(&mut self, sizes: &[u64], counts: &[u64], volume: f64) -> $crate::error::Result<()> {
                <$ty>::set_pairs(self, sizes, counts, volume)
            }
            fn set_kernel(&mut self, kernel: K) -> $crate::error::Result<()> {
                <$ty>::set_kernel(self, kernel)
            }
            fn set_time(&mut self, t: f64) -> $crate::error::Result<()> {
                <$ty>::set_time(self, t)
            }
            fn set_doubling(&mut self, on: bool) {
                <$ty>::set_doubling(self, on)
            }
        }
    };
}
pub(crate) use count_controls;
