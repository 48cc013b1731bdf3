//! `coagula.Simulation`: every population scheme of the registry behind one class,
//! as the C ABI's `coag_sim` is. The sim steps with the interpreter detached (threads
//! run their own sims in parallel) and reads out as numpy arrays; a call on a sim that
//! is already in a call (a kernel callback stepping its own sim, or a second thread)
//! is refused, never a deadlock.

use crate::arrays::{counts_arg, reals_arg};
use crate::initial::Initial;
use crate::kernel::{PyCoag, PyFrag, coagulation_of, fragmentation_of, model_of};
use crate::report::Report;
use crate::{CoagulaError, py_err};
use coagula_core::checkpoint::Writer;
use coagula_core::classes::Classes;
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::facade::{
    Blank, KEYS, Kind, Options, SchemeId, Simulation as Facade, State, Value, peek_stream,
};
use coagula_core::scheme::registry;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use std::sync::{Mutex, TryLockError};

/// The facade as Python instantiates it.
type Dyn = dyn Facade<PyCoag, PyFrag, Generator>;

/// Two arrays side by side (sizes and what each has).
pub(crate) type Columns<'py, A, B> = PyResult<(Bound<'py, A>, Bound<'py, B>)>;

/// A sim and its own random stream.
struct Cell {
    sim: Box<Dyn>,
    rng: Generator,
    /// A host's functions as given (core keeps the functions, not the Python
    /// objects): for `processes` and pickling.
    user: crate::process::Kept,
}

/// Core's options from keyword arguments (`memory_budget=…` is core's
/// `memory-budget`), each converted by the kind core declares for its key and
/// checked by core.
pub(crate) fn options_of(kw: Option<&Bound<'_, PyDict>>) -> PyResult<Options> {
    let mut o = Options::default();
    let Some(kw) = kw else { return Ok(o) };
    for (k, v) in kw.iter() {
        let name: String = k.extract()?;
        let key = name.replace('_', "-");
        let Some(spec) = KEYS.iter().find(|s| s.name == key) else {
            let known: Vec<String> = KEYS.iter().map(|s| s.name.replace('-', "_")).collect();
            return Err(PyValueError::new_err(format!(
                "{name} is not an option (coagula.options() lists them: {})",
                known.join(", ")
            )));
        };
        let bad = |what: &str| PyValueError::new_err(format!("option {name}: expected {what}"));
        let text: String;
        let value = match spec.kind {
            Kind::Real => Value::Real(v.extract::<f64>().map_err(|_| bad("a real number"))?),
            Kind::Count => {
                if v.is_instance_of::<pyo3::types::PyBool>() {
                    return Err(bad("an integer >= 0"));
                }
                // 1e6-style floats are counts when they are integers
                match v.extract::<u64>() {
                    Ok(n) => Value::Count(n),
                    Err(_) => {
                        let x: f64 = v.extract().map_err(|_| bad("an integer >= 0"))?;
                        if !(x >= 0.0 && x.fract() == 0.0 && x < 1.8446744073709552e19) {
                            return Err(bad("an integer >= 0"));
                        }
                        Value::Count(x as u64)
                    }
                }
            }
            Kind::Flag => Value::Flag(v.extract::<bool>().map_err(|_| bad("True or False"))?),
            Kind::Name(names) => {
                text = v
                    .extract::<String>()
                    .map_err(|_| bad(&format!("one of {}", names.join(", "))))?;
                Value::Name(&text)
            }
        };
        o.set(spec.name, value).map_err(py_err)?;
    }
    Ok(o)
}

/// One population simulation of any registry scheme (`coagula.schemes()` lists them
/// with the initial states, options and observables each takes).
///
/// `Simulation(scheme, kernel, init, *, fragmentation=None, seed=0, **options)`:
/// `kernel` a `Kernel`, a `UserKernel` or a built-in kernel's name; `init` an
/// `Initial`; `options` core's settings by name (`dt=…`, `memory_budget=…`,
/// `coagula.options()` lists them). The seed (and `stream`) start the sim's own
/// random stream: the same seed gives the same bits as the CLI's first replica and a
/// C `coag_sim` with that seed.
///
/// >>> import coagula
/// >>> sim = coagula.Simulation("lowrank", coagula.Kernel("additive"),
/// ...                          coagula.Initial.monodisperse(1, particles=10_000), seed=7)
/// >>> report = sim.advance_to(0.5)
/// >>> round(sim.moment(0), 2)   # exact: exp(-0.5) = 0.607
/// 0.61
#[pyclass(module = "coagula", name = "Simulation", frozen)]
pub struct Sim {
    cell: Mutex<Cell>,
    scheme: SchemeId,
    /// What it was built with, for pickling: the kernel and fragmentation objects
    /// and the options as keywords.
    kernel: Py<PyAny>,
    frag: Py<PyAny>,
    options: Py<PyDict>,
}

impl Sim {
    /// The sim for a call: refused while another call holds it.
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, Cell>> {
        match self.cell.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::WouldBlock) => Err(CoagulaError::new_err(
                "this Simulation is already in a call (a kernel callback stepping or reading its own simulation, or another thread): a Simulation takes one call at a time",
            )),
            // a panic never crosses into Python (PyO3 turns it into an exception), but
            // a poisoned lock would leave a sim in an unknown state: refuse it
            Err(TryLockError::Poisoned(_)) => Err(CoagulaError::new_err(
                "this Simulation was left in an unknown state by an internal error; build a new one",
            )),
        }
    }

    fn with<R>(&self, f: impl FnOnce(&mut Cell) -> R) -> PyResult<R> {
        Ok(f(&mut *self.lock()?))
    }

    fn build(
        scheme: &str,
        kernel: &Bound<'_, PyAny>,
        init: Option<&Initial>,
        blank: Option<&Blank>,
        frag: Option<&Bound<'_, PyAny>>,
        kw: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Sim> {
        let py = kernel.py();
        let id = registry::find(scheme).map_err(py_err)?;
        let opts = options_of(kw)?;
        let model = model_of(kernel, fragmentation_of(frag)?, Some(id))?;
        crate::kernel::clear_raised();
        let sim = match (init, blank) {
            (Some(init), _) => {
                let start = init.start(id, &opts)?;
                registry::build(id, model, &start.init(), &opts)
            }
            (None, Some(b)) => b.build(|i, o| registry::build(id, model, i, o), &opts),
            (None, None) => unreachable!("a build has an initial state or a blank"),
        }
        .map_err(|e| crate::kernel::with_raised(py, py_err(e), "while the sim was built"))?;
        let rng = generator(opts.seed(), opts.stream());
        let options = match kw {
            Some(d) => d.copy()?,
            None => PyDict::new(py),
        };
        Ok(Sim {
            cell: Mutex::new(Cell {
                sim,
                rng,
                user: [None, None, None],
            }),
            scheme: id,
            kernel: kernel.clone().unbind(),
            frag: frag.map_or_else(|| py.None(), |f| f.clone().unbind()),
            options: options.unbind(),
        })
    }

    /// The checkpoint envelope with the sim's stream.
    fn checkpoint(cell: &Cell) -> PyResult<Vec<u8>> {
        let mut w = Writer::new(&mut []);
        cell.sim.save_checkpoint(Some(cell.rng.parts()), &mut w);
        let mut buf = vec![0u8; w.needed()];
        let mut w = Writer::new(&mut buf);
        cell.sim.save_checkpoint(Some(cell.rng.parts()), &mut w);
        w.finish().map_err(py_err)?;
        Ok(buf)
    }

    fn restore_into(cell: &mut Cell, data: &[u8]) -> PyResult<()> {
        // the stream first, so that nothing changes when it is bad
        let rng = match peek_stream(data)
            .map_err(py_err)?
            .map(Generator::from_parts)
        {
            Some(Some(g)) => g,
            _ => {
                return Err(CoagulaError::new_err(
                    "checkpoint: no valid random stream (not written by Simulation.save)",
                ));
            }
        };
        cell.sim.restore_checkpoint(data).map_err(py_err)?;
        cell.rng = rng;
        Ok(())
    }
}

fn blank_tuple<'py>(py: Python<'py>, b: &Blank) -> PyResult<Bound<'py, PyTuple>> {
    Ok(match b {
        Blank::Counts(c, v) => ("counts", c.clone(), *v).into_pyobject(py)?,
        Blank::Sizes {
            size,
            n,
            mass,
            capacity,
        } => ("sizes", *size, *n, *mass, *capacity)
            .into_pyobject(py)?
            .into_any()
            .cast_into::<PyTuple>()?,
        Blank::Temperatures => ("temperatures",).into_pyobject(py)?,
        Blank::Velocities => ("velocities",).into_pyobject(py)?,
    }
    .into_any()
    .cast_into::<PyTuple>()?)
}

fn blank_of(t: &Bound<'_, PyTuple>) -> PyResult<Blank> {
    let kind: String = t.get_item(0)?.extract()?;
    Ok(match kind.as_str() {
        "counts" => Blank::Counts(t.get_item(1)?.extract()?, t.get_item(2)?.extract()?),
        "sizes" => {
            let n: usize = t.get_item(2)?.extract()?;
            let capacity: usize = t.get_item(4)?.extract()?;
            // a pickle's blank is as many particles as the sim held: within what memory
            // can hold (a crafted one must not end the interpreter)
            if n > (1 << 36) || capacity > (1 << 36) {
                return Err(PyValueError::new_err(
                    "not a pickled coagula.Simulation (its blank holds more than 2^36 particles)",
                ));
            }
            Blank::Sizes {
                size: t.get_item(1)?.extract()?,
                n,
                mass: t.get_item(3)?.extract()?,
                capacity,
            }
        }
        "temperatures" => Blank::Temperatures,
        "velocities" => Blank::Velocities,
        _ => return Err(PyValueError::new_err("not a pickled coagula.Simulation")),
    })
}

#[pymethods]
impl Sim {
    #[new]
    #[pyo3(signature = (scheme, kernel, init, *, fragmentation=None, **options))]
    fn new(
        scheme: &str,
        kernel: &Bound<'_, PyAny>,
        init: PyRef<'_, Initial>,
        fragmentation: Option<&Bound<'_, PyAny>>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        Sim::build(scheme, kernel, Some(&init), None, fragmentation, options)
    }

    /// The scheme's registry name.
    #[getter]
    fn scheme(&self) -> &'static str {
        self.scheme.name
    }

    /// Runs until time `t` with the interpreter detached and returns what happened
    /// (events, proposals, rejections, doublings, … as a dict). With `work_limit`,
    /// at most that many work units (proposals, or time steps), then
    /// `interrupted=True` and `time < t`; Ctrl-C interrupts likewise and raises
    /// `KeyboardInterrupt`. On an error the sim is as before the failing event.
    #[pyo3(signature = (t, *, work_limit=None))]
    fn advance_to<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        work_limit: Option<u64>,
    ) -> PyResult<Report> {
        let (out, signal, raised) = py.detach(|| -> PyResult<_> {
            let mut cell = self.lock()?;
            let Cell { sim, rng, .. } = &mut *cell;
            let (out, signal) =
                crate::with_signals(work_limit, |budget| sim.advance_within(t, budget, rng));
            Ok((out, signal, crate::kernel::take_raised()))
        })?;
        if let Some(e) = raised {
            let err = CoagulaError::new_err(format!(
                "a Python callback raised during advance_to({t}): {e}"
            ));
            err.set_cause(py, Some(e));
            return Err(err);
        }
        if let Some(e) = signal {
            return Err(e);
        }
        Ok(Report(out.map_err(py_err)?))
    }

    /// The current time.
    /// The engine the low-rank method runs now (`"slots"`, `"counted"`, `"blocks"`;
    /// the `engine` option pins one), or None for a scheme without engines.
    #[getter]
    fn engine(&self) -> PyResult<Option<&'static str>> {
        self.with(|c| c.sim.engine().map(|m| m.name()))
    }

    #[getter]
    fn time(&self) -> PyResult<f64> {
        self.with(|c| c.sim.time())
    }

    /// The books of every call so far (events, proposals, … as a dict).
    #[getter]
    fn totals(&self) -> PyResult<Report> {
        Ok(Report(self.with(|c| c.sim.totals())?))
    }

    /// The volume the particles are in.
    #[getter]
    fn volume(&self) -> PyResult<f64> {
        self.with(|c| c.sim.volume())
    }

    /// The number of simulation particles.
    #[getter]
    fn particles(&self) -> PyResult<u64> {
        self.with(|c| c.sim.particles())
    }

    /// The moment `M_k = Σ x^k / V` (per unit volume), any real order.
    fn moment(&self, k: f64) -> PyResult<f64> {
        self.with(|c| c.sim.moment(k))
    }

    /// The concentration of particles with `a ≤ x < b` (half-open: adjacent classes
    /// add up to their union).
    fn concentration(&self, a: f64, b: f64) -> PyResult<f64> {
        if a.is_nan() || b.is_nan() {
            return Err(PyValueError::new_err(format!(
                "concentration({a}, {b}): the class edges must be numbers"
            )));
        }
        self.with(|c| c.sim.class_concentration(a, b))
    }

    /// The number density at size `x` (integer sizes: `c_x`).
    fn number_density(&self, x: f64) -> PyResult<f64> {
        if x.is_nan() {
            return Err(PyValueError::new_err(
                "number_density(nan): the size must be a number",
            ));
        }
        self.with(|c| c.sim.number_density(x))
    }

    /// The gel mass estimate (the largest cluster per volume; the gel mass only past a
    /// gel point), or None where the scheme has none.
    fn gel_mass(&self) -> PyResult<Option<f64>> {
        self.with(|c| c.sim.gel_mass())
    }

    /// A named observable of the scheme (`coagula.schemes()` lists each scheme's:
    /// temperature, energy, …).
    fn observable(&self, name: &str) -> PyResult<f64> {
        let id = self.scheme;
        self.with(|c| c.sim.observable(name))?.ok_or_else(|| {
            PyValueError::new_err(format!(
                "{name} is not an observable of scheme {} (it has: {})",
                id.name,
                if id.observables.is_empty() {
                    "none besides the moments".to_string()
                } else {
                    id.observables.join(", ")
                }
            ))
        })
    }

    /// The particle sizes (a copy: a view would dangle once the sim steps), for the
    /// schemes over sizes; `ValueError` for the integer-size schemes (use `counts`).
    fn sizes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let v = self.with(|c| match c.sim.state() {
            State::Sizes(x) => Ok(x.to_vec()),
            State::Counts(..) => Err(PyValueError::new_err(
                "sizes: this scheme's state is counts of integer sizes (use counts() or pairs())",
            )),
        })??;
        Ok(PyArray1::from_vec(py, v))
    }

    /// The counts `N_i` of sizes `i = 1, 2, …` (`counts()[i - 1]`) as a uint64 array,
    /// for the integer-size schemes. Dense up to the largest occupied size: `pairs()`
    /// gives only the occupied sizes.
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u64>>> {
        let v = self.with(|c| -> PyResult<Vec<u64>> {
            if let State::Sizes(_) = c.sim.state() {
                return Err(PyValueError::new_err(
                    "counts: this scheme's state is particle sizes (use sizes())",
                ));
            }
            // from the occupied sizes, within the memory budget (a dense array up to a
            // size of 2^31 is 16 GiB)
            let mut largest = 0u64;
            c.sim
                .for_each_count(&mut |s, n| {
                    if n > 0 {
                        largest = largest.max(s);
                    }
                })
                .map_err(py_err)?;
            let budget = c.sim.options().memory_budget() as u64;
            if largest.saturating_mul(8) > budget {
                return Err(pyo3::exceptions::PyMemoryError::new_err(format!(
                    "counts(): the largest size is {largest}, a dense array of {} bytes, above the memory budget of {budget}; pairs() gives the occupied sizes only",
                    largest.saturating_mul(8)
                )));
            }
            let mut out = Vec::new();
            out.try_reserve_exact(largest as usize).map_err(|_| {
                pyo3::exceptions::PyMemoryError::new_err("counts(): no memory for the dense array")
            })?;
            out.resize(largest as usize, 0);
            c.sim
                .for_each_count(&mut |s, n| out[(s - 1) as usize] = n)
                .map_err(py_err)?;
            Ok(out)
        })??;
        Ok(PyArray1::from_vec(py, v))
    }

    /// The occupied sizes and their counts, ascending, as two uint64 arrays.
    fn pairs<'py>(&self, py: Python<'py>) -> Columns<'py, PyArray1<u64>, PyArray1<u64>> {
        let (mut s, mut n) = (Vec::new(), Vec::new());
        self.with(|c| {
            c.sim.for_each_count(&mut |size, count| {
                s.push(size);
                n.push(count);
            })
        })?
        .map_err(py_err)?;
        Ok((PyArray1::from_vec(py, s), PyArray1::from_vec(py, n)))
    }

    /// A per-size quantity by name (`"temperature"` of the temperature-dependent
    /// schemes and DSMC) as two arrays: the occupied sizes and the values.
    fn size_values<'py>(
        &self,
        py: Python<'py>,
        name: &str,
    ) -> Columns<'py, PyArray1<u64>, PyArray1<f64>> {
        let (mut s, mut v) = (Vec::new(), Vec::new());
        self.with(|c| {
            c.sim.size_values(name, &mut |size, x| {
                s.push(size);
                v.push(x);
            })
        })?
        .map_err(py_err)?;
        Ok((PyArray1::from_vec(py, s), PyArray1::from_vec(py, v)))
    }

    /// A gas's particles: their sizes and velocities (shape (n, 3)).
    fn velocities<'py>(&self, py: Python<'py>) -> Columns<'py, PyArray1<u64>, PyArray2<f64>> {
        let (mut s, mut v) = (Vec::new(), Vec::new());
        self.with(|c| {
            c.sim.velocities(&mut |size, u| {
                s.push(size);
                v.push(u.to_vec());
            })
        })?
        .map_err(py_err)?;
        let v = PyArray2::from_vec2(py, &v).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok((PyArray1::from_vec(py, s), v))
    }

    /// Replaces the sizes (schemes over sizes).
    fn set_sizes(&self, sizes: &Bound<'_, PyAny>) -> PyResult<()> {
        let x = reals_arg("sizes", sizes)?;
        self.with(|c| c.sim.set_sizes(&x))?.map_err(py_err)
    }

    /// Replaces counts and volume (integer-size schemes): `counts[i]` particles of
    /// size `i + 1`.
    #[pyo3(signature = (counts, volume))]
    fn set_counts(&self, counts: &Bound<'_, PyAny>, volume: f64) -> PyResult<()> {
        let n = counts_arg("counts", counts)?;
        self.with(|c| c.sim.set_counts(&n, volume))?.map_err(py_err)
    }

    /// Replaces the state by `counts[i]` particles of size `sizes[i]` in `volume`
    /// (integer-size schemes; sizes need not be dense).
    #[pyo3(signature = (sizes, counts, volume))]
    fn set_pairs(
        &self,
        sizes: &Bound<'_, PyAny>,
        counts: &Bound<'_, PyAny>,
        volume: f64,
    ) -> PyResult<()> {
        let s = counts_arg("sizes", sizes)?;
        let n = counts_arg("counts", counts)?;
        self.with(|c| c.sim.set_pairs(&s, &n, volume))?
            .map_err(py_err)
    }

    /// The population on a host's size classes: numbers per unit volume at `pivots`
    /// (ascending, > 0), each particle split between the two pivots around it keeping
    /// number and mass (fixed pivot, Kumar & Ramkrishna 1996); returns the numbers and
    /// a dict of what lies outside the grid (`below_number`, `below_mass`,
    /// `above_number`, `above_mass`).
    fn project<'py>(
        &self,
        py: Python<'py>,
        pivots: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyDict>)> {
        let classes = Classes::new(&reals_arg("pivots", pivots)?).map_err(py_err)?;
        let mut n = vec![0.0; classes.len()];
        let out = self
            .with(|c| c.sim.project(&classes, &mut n))?
            .map_err(py_err)?;
        let d = PyDict::new(py);
        d.set_item("below_number", out.below_number)?;
        d.set_item("below_mass", out.below_mass)?;
        d.set_item("above_number", out.above_number)?;
        d.set_item("above_mass", out.above_mass)?;
        Ok((PyArray1::from_vec(py, n), d))
    }

    /// Replaces the population by `numbers` per unit volume at `pivots` (the inverse of
    /// `project`): `numbers[i] × volume` particles of size `pivots[i]` (integer pivots
    /// on an integer-size scheme), rounded without bias with draws from the sim's own
    /// stream; a mass-flow scheme keeps its particle number and takes the classes'
    /// mass. On error the sim is unchanged.
    fn set_classes(&self, pivots: &Bound<'_, PyAny>, numbers: &Bound<'_, PyAny>) -> PyResult<()> {
        let classes = Classes::new(&reals_arg("pivots", pivots)?).map_err(py_err)?;
        let n = reals_arg("numbers", numbers)?;
        self.with(|c| {
            // (the stream moves on only when the population was replaced)
            let mut rng = c.rng.clone();
            let r = c.sim.set_classes(&classes, &n, &mut rng);
            if r.is_ok() {
                c.rng = rng;
            }
            r
        })?
        .map_err(py_err)
    }

    /// Replaces the coagulation kernel.
    fn set_kernel(&self, py: Python<'_>, kernel: &Bound<'_, PyAny>) -> PyResult<()> {
        let k = coagulation_of(kernel, Some(self.scheme))?;
        crate::kernel::clear_raised();
        self.with(|c| c.sim.set_kernel(k))?
            .map_err(|e| crate::kernel::with_raised(py, py_err(e), "in set_kernel"))
    }

    /// Replaces the fragmentation kernel (massflow, mfa, dsa).
    fn set_fragmentation(&self, fragmentation: &Bound<'_, PyAny>) -> PyResult<()> {
        let f = fragmentation_of(Some(fragmentation))?;
        self.with(|c| c.sim.set_fragmentation(f))?.map_err(py_err)
    }

    /// Changes the time step (time-driven schemes).
    fn set_dt(&self, dt: f64) -> PyResult<()> {
        self.with(|c| c.sim.set_dt(dt))?.map_err(py_err)
    }

    /// Sets the clock.
    fn set_time(&self, t: f64) -> PyResult<()> {
        self.with(|c| c.sim.set_time(t))?.map_err(py_err)
    }

    /// Sets the processes beside coagulation (all absent: none): `source` a dict
    /// (`rate` per unit volume and time, `kind` monodisperse/exponential/lognormal with
    /// `size`, `mean` or `median` and `gsd`), `removal` and `growth` a coefficient or
    /// `(coefficient, exponent)` (`c x^p` per particle; growth as monomer attachment on
    /// integer sizes, on real sizes by Strang splitting of step `growth_step`, which it
    /// needs there). The books start from the state now.
    #[pyo3(signature = (*, source=None, removal=None, growth=None, growth_step=None))]
    fn set_processes(
        &self,
        source: Option<&Bound<'_, PyAny>>,
        removal: Option<&Bound<'_, PyAny>>,
        growth: Option<&Bound<'_, PyAny>>,
        growth_step: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let p = crate::process::processes_of(source, removal, growth, growth_step)?;
        let user = crate::process::kept(source, removal, growth);
        self.with(|c| {
            c.sim.set_processes(p)?;
            c.user = user;
            Ok(())
        })?
        .map_err(py_err)
    }

    /// The processes set, as `set_processes`' keyword arguments (None: none).
    #[getter]
    fn processes<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let (p, user) = self.with(|c| {
            let user = crate::process::kept_clone(py, &c.user);
            (c.sim.processes().cloned(), user)
        })?;
        let Some(p) = p else { return Ok(None) };
        Ok(Some(crate::process::processes_dict(py, &p, &user)?))
    }

    /// The processes' books (None without processes): what was injected, removed and
    /// grown, and the merges, so that the state's mass is initial + injected − removed
    /// + grown and its number initial + injected − removed − merged.
    #[getter]
    fn books<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let b = self.with(|c| c.sim.books())?;
        b.map(|b| crate::process::books_dict(py, b)).transpose()
    }

    /// Changes the total mass the particles carry (massflow, mfa).
    fn set_mass(&self, mass: f64) -> PyResult<()> {
        self.with(|c| c.sim.set_mass(mass))?.map_err(py_err)
    }

    /// The whole state as bytes (the checkpoint envelope every front end writes,
    /// with the sim's random stream): `restore` continues bit-identically.
    fn save<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let buf = self.with(|c| Sim::checkpoint(c))??;
        Ok(PyBytes::new(py, &buf))
    }

    /// Restores bytes from `save` of a sim of the same scheme, settings and physics;
    /// on any error (`CoagulaError`) the sim is unchanged.
    fn restore(&self, data: &[u8]) -> PyResult<()> {
        self.with(|c| Sim::restore_into(c, data))?
    }

    /// An exact copy: the two continue identically and independently.
    fn clone(&self, py: Python<'_>) -> PyResult<Sim> {
        let (sim, rng, user) = self
            .with(|c| {
                c.sim.duplicate().map(|s| {
                    let user = crate::process::kept_clone(py, &c.user);
                    (s, c.rng.clone(), user)
                })
            })?
            .map_err(py_err)?;
        Ok(Sim {
            cell: Mutex::new(Cell { sim, rng, user }),
            scheme: self.scheme,
            kernel: self.kernel.clone_ref(py),
            frag: self.frag.clone_ref(py),
            options: self.options.bind(py).copy()?.unbind(),
        })
    }

    fn __copy__(&self, py: Python<'_>) -> PyResult<Sim> {
        self.clone(py)
    }

    fn __deepcopy__(&self, py: Python<'_>, _memo: &Bound<'_, PyAny>) -> PyResult<Sim> {
        self.clone(py)
    }

    /// Pickling: the scheme, the kernel objects, the options, the blank a sim of the
    /// same shape is built from, and the checkpoint (a `UserKernel` pickles if its
    /// callables do).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let (blank, data) = self.with(|c| (c.sim.blank(), Sim::checkpoint(c)))?;
        let f = py.import("coagula._coagula")?.getattr("_simulation")?;
        let args = (
            self.scheme.name,
            self.kernel.bind(py),
            self.frag.bind(py),
            self.options.bind(py),
            blank_tuple(py, &blank)?,
            PyBytes::new(py, &data?),
            self.processes(py)?,
        )
            .into_pyobject(py)?;
        Ok((f, args))
    }

    fn __repr__(&self) -> String {
        match self.cell.try_lock() {
            Ok(c) => format!(
                "coagula.Simulation({:?}, t={}, particles={})",
                self.scheme.name,
                c.sim.time(),
                c.sim.particles()
            ),
            Err(_) => format!("coagula.Simulation({:?}, <in a call>)", self.scheme.name),
        }
    }
}

/// Unpickles a `Simulation`: built from its blank, its processes set, then its
/// checkpoint restored.
#[pyfunction]
#[pyo3(signature = (scheme, kernel, frag, options, blank, data, processes=None))]
fn _simulation(
    scheme: &str,
    kernel: &Bound<'_, PyAny>,
    frag: &Bound<'_, PyAny>,
    options: &Bound<'_, PyDict>,
    blank: &Bound<'_, PyTuple>,
    data: &[u8],
    processes: Option<&Bound<'_, PyDict>>,
) -> PyResult<Sim> {
    let b = blank_of(blank)?;
    let sim = Sim::build(scheme, kernel, None, Some(&b), Some(frag), Some(options))?;
    if let Some(p) = processes {
        let get = |k| p.get_item(k);
        let (s, r, g) = (get("source")?, get("removal")?, get("growth")?);
        let h = get("growth_step")?;
        let p = crate::process::processes_of(s.as_ref(), r.as_ref(), g.as_ref(), h.as_ref())?;
        let user = crate::process::kept(s.as_ref(), r.as_ref(), g.as_ref());
        sim.with(|c| {
            c.sim.set_processes(p)?;
            c.user = user;
            Ok(())
        })?
        .map_err(py_err)?;
    }
    sim.with(|c| Sim::restore_into(c, data))??;
    Ok(sim)
}

/// `class_rates(before, after, dt)`: the change per class over a step,
/// `(after − before) / dt`, as the source terms of a host's transport equation.
#[pyfunction]
fn class_rates<'py>(
    py: Python<'py>,
    before: &Bound<'py, PyAny>,
    after: &Bound<'py, PyAny>,
    dt: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (b, a) = (reals_arg("before", before)?, reals_arg("after", after)?);
    let mut out = vec![0.0; b.len()];
    coagula_core::classes::rates(&b, &a, dt, &mut out).map_err(py_err)?;
    Ok(PyArray1::from_vec(py, out))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(class_rates, m)?)?;
    m.add_class::<Sim>()?;
    m.add_class::<Report>()?;
    m.add_function(wrap_pyfunction!(_simulation, m)?)?;
    Ok(())
}
