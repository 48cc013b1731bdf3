//! The checks that turn a scenario into a [`Plan`]: every value, before any work
//! starts. The kernel's parameters and the scheme's options are core's to check (its
//! table of built-in kernels, its option keys and its registry entries' capabilities);
//! what is checked here belongs to the scenario itself — output times, observables,
//! replicas, the initial distribution and the memory the run will hold.

use super::plan::{Observable, Plan, exact_of};
use super::{InitKind, Scenario, ScenarioError, Source, Spacing};
use coagula_core::initial::Distribution;
use coagula_core::kernel::builtin::{self, Builtin};
use coagula_core::kernel::{BinaryUniform, Coagulation, Fragmentation};
use coagula_core::scheme::facade::{InitKind as Takes, Law, Model, ModelKind, Options, Value};
use coagula_core::scheme::registry;

fn positive(src: &Source<'_>, key: &str, v: f64) -> Result<f64, ScenarioError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(src.at(key, format!("{v} must be finite and > 0")))
    }
}

fn require<T: Copy>(
    src: &Source<'_>,
    key: &str,
    v: Option<T>,
    why: &str,
) -> Result<T, ScenarioError> {
    v.ok_or_else(|| src.at(key, format!("missing: {why}")))
}

fn refuse<T>(src: &Source<'_>, key: &str, v: &Option<T>, why: &str) -> Result<(), ScenarioError> {
    if v.is_some() {
        Err(src.at(key, format!("not used here ({why})")))
    } else {
        Ok(())
    }
}

/// A TOML value as one of core's option values.
fn value_of(v: &toml::Value) -> Result<Value<'_>, String> {
    Ok(match v {
        toml::Value::Float(x) => Value::Real(*x),
        toml::Value::Integer(i) => match u64::try_from(*i) {
            Ok(n) => Value::Count(n),
            Err(_) => Value::Real(*i as f64),
        },
        toml::Value::Boolean(b) => Value::Flag(*b),
        toml::Value::String(s) => Value::Name(s),
        other => return Err(format!("{other} is not a number, a flag or a name")),
    })
}

/// The built-in kernel of `[kernel]`: `kind` and its parameters by name (core checks
/// them).
fn kernel_of(s: &Scenario, src: &Source<'_>) -> Result<(String, Builtin), ScenarioError> {
    let kind = match s.kernel.get("kind") {
        Some(toml::Value::String(k)) => k.clone(),
        Some(_) => return Err(src.at("kernel.kind", "must be a name")),
        None => return Err(src.at("kernel.kind", "missing: the kernel's name")),
    };
    let mut params = Vec::new();
    for (k, v) in &s.kernel {
        if k == "kind" {
            continue;
        }
        let x = match v {
            toml::Value::Float(x) => *x,
            toml::Value::Integer(i) => *i as f64,
            _ => return Err(src.at(&format!("kernel.{k}"), "must be a number")),
        };
        params.push((k.as_str(), x));
    }
    let b = builtin::make(&kind, &params).map_err(|e| {
        // name the parameter: the one the kernel does not have, or the one core's
        // message names
        let key = match builtin::find(&kind) {
            None => "kernel.kind".to_string(),
            Some(info) => params
                .iter()
                .map(|(k, _)| *k)
                .find(|k| !info.params.iter().any(|p| p.name == *k))
                .or(match e {
                    coagula_core::Error::KernelParameter { param, .. } if !param.is_empty() => {
                        Some(param)
                    }
                    _ => None,
                })
                .or_else(|| {
                    params
                        .iter()
                        .map(|(k, _)| *k)
                        .find(|k| e.to_string().contains(*k))
                })
                .map_or_else(|| "kernel".to_string(), |k| format!("kernel.{k}")),
        };
        src.at(&key, e)
    })?;
    Ok((kind, b))
}

/// The options of `[scheme]` (every key but `name`), checked by core.
fn options_of(s: &Scenario, src: &Source<'_>) -> Result<Options, ScenarioError> {
    let mut o = Options::default();
    for (k, v) in &s.scheme {
        if k == "name" {
            continue;
        }
        let key = format!("scheme.{k}");
        let v = value_of(v).map_err(|m| src.at(&key, m))?;
        o.set(k, v).map_err(|e| src.at(&key, e))?;
    }
    Ok(o)
}

/// The output times of `[output]`.
fn times_of(s: &Scenario, src: &Source<'_>) -> Result<Vec<f64>, ScenarioError> {
    let o = &s.output;
    let times: Vec<f64> = match (&o.times, o.t_end, o.count) {
        (Some(t), None, None) => {
            refuse(src, "output.t-start", &o.t_start, "explicit times")?;
            refuse(src, "output.spacing", &o.spacing, "explicit times")?;
            t.clone()
        }
        (None, Some(end), Some(count)) => {
            let end = positive(src, "output.t-end", end)?;
            if count == 0 || count > 100_000 {
                return Err(src.at("output.count", format!("{count} must be in 1..=100000")));
            }
            match o.spacing.unwrap_or_default() {
                Spacing::Linear => {
                    refuse(
                        src,
                        "output.t-start",
                        &o.t_start,
                        "linear spacing starts at 0",
                    )?;
                    (1..=count)
                        .map(|i| end * f64::from(i) / f64::from(count))
                        .collect()
                }
                Spacing::Log => {
                    let start = positive(
                        src,
                        "output.t-start",
                        require(
                            src,
                            "output.t-start",
                            o.t_start,
                            "log spacing needs a first time",
                        )?,
                    )?;
                    if start >= end {
                        return Err(src.at(
                            "output.t-start",
                            format!("{start} must be below t-end {end}"),
                        ));
                    }
                    if count < 2 {
                        return Err(src.at("output.count", "log spacing needs at least 2 times"));
                    }
                    (0..count)
                        .map(|i| start * (end / start).powf(f64::from(i) / f64::from(count - 1)))
                        .collect()
                }
            }
        }
        _ => {
            return Err(src.at(
                "output",
                "give either times = [...] or t-end and count (not both)",
            ));
        }
    };
    if times.is_empty() || times.len() > 100_000 {
        return Err(src.at("output.times", "give 1 to 100000 output times"));
    }
    for w in times.windows(2) {
        if w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater) {
            return Err(src.at(
                "output.times",
                format!("must increase ({} then {})", w[0], w[1]),
            ));
        }
    }
    for &t in &times {
        if !(t.is_finite() && t > 0.0) {
            return Err(src.at("output.times", format!("{t} must be finite and > 0")));
        }
    }
    Ok(times)
}

/// The number of simulation particles of `[initial]` (a count: `1e6` is one).
fn particles_of(s: &Scenario, src: &Source<'_>) -> Result<u64, ScenarioError> {
    let p = require(
        src,
        "initial.particles",
        s.initial.particles,
        "the number of simulation particles",
    )?;
    if !(p.fract() == 0.0 && (2.0..=(1u64 << 40) as f64).contains(&p)) {
        return Err(src.at(
            "initial.particles",
            format!("{p} must be an integer in 2..=2^40"),
        ));
    }
    Ok(p as u64)
}

/// The initial distribution of `[initial]`.
fn distribution_of(s: &Scenario, src: &Source<'_>) -> Result<Distribution, ScenarioError> {
    let i = &s.initial;
    for (key, v, kind) in [
        ("initial.size", i.size.is_some(), InitKind::Monodisperse),
        ("initial.mean", i.mean.is_some(), InitKind::Exponential),
        ("initial.median", i.median.is_some(), InitKind::Lognormal),
        ("initial.gsd", i.gsd.is_some(), InitKind::Lognormal),
        ("initial.sizes", i.sizes.is_some(), InitKind::Sizes),
        ("initial.counts", i.counts.is_some(), InitKind::Counts),
    ] {
        if v && i.kind != kind {
            return Err(src.at(key, format!("not used by kind = {:?}", i.kind)));
        }
    }
    let d = match i.kind {
        InitKind::Monodisperse => Distribution::Monodisperse {
            size: i.size.unwrap_or(1.0),
        },
        InitKind::Exponential => Distribution::Exponential {
            mean: i.mean.unwrap_or(1.0),
        },
        InitKind::Lognormal => Distribution::Lognormal {
            median: require(src, "initial.median", i.median, "the median size")?,
            gsd: require(
                src,
                "initial.gsd",
                i.gsd,
                "the geometric standard deviation (> 1)",
            )?,
        },
        InitKind::Sizes => Distribution::Sizes(
            i.sizes
                .clone()
                .ok_or_else(|| src.at("initial.sizes", "missing: the list of particle sizes"))?,
        ),
        InitKind::Counts => Distribution::Counts(
            i.counts
                .clone()
                .ok_or_else(|| src.at("initial.counts", "missing: counts[i-1] of size i"))?,
        ),
    };
    let key = match i.kind {
        InitKind::Monodisperse => "initial.size",
        InitKind::Exponential => "initial.mean",
        InitKind::Lognormal => "initial.gsd",
        InitKind::Sizes => "initial.sizes",
        InitKind::Counts => "initial.counts",
    };
    d.check().map_err(|e| src.at(key, e))?;
    Ok(d)
}

/// The errors of the checks that need no other part of the scenario (kernel, output
/// times, observables, initial condition, options, run), all of them: a file with
/// several mistakes is told of each at once, not one per attempt.
fn independent_errors(s: &Scenario, src: &Source<'_>) -> Vec<ScenarioError> {
    let mut errors = Vec::new();
    let mut keep = |r: Result<(), ScenarioError>| {
        if let Err(e) = r {
            errors.push(e);
        }
    };
    keep(kernel_of(s, src).map(drop));
    keep(options_of(s, src).map(drop));
    keep(times_of(s, src).map(drop));
    keep(distribution_of(s, src).map(drop));
    for n in &s.output.observables {
        keep(
            Observable::parse(n)
                .map(drop)
                .map_err(|m| src.at("output.observables", m)),
        );
    }
    if s.run.replicas == 0 || s.run.replicas > 1_000_000 {
        keep(Err(src.at(
            "run.replicas",
            format!("{} must be in 1..=1000000", s.run.replicas),
        )));
    }
    errors
}

/// Checks every value and builds the plan.
pub(super) fn check(s: Scenario, src: &Source<'_>) -> Result<Plan, ScenarioError> {
    let errors = independent_errors(&s, src);
    if errors.len() > 1 {
        return Err(ScenarioError {
            message: format!(
                "{} errors:\n{}",
                errors.len(),
                errors
                    .iter()
                    .map(|e| format!("  {}", e.message))
                    .collect::<Vec<_>>()
                    .join("\n")
            ),
        });
    }
    let name = match s.scheme.get("name") {
        Some(toml::Value::String(n)) => n.clone(),
        Some(_) => return Err(src.at("scheme.name", "must be a name")),
        None => return Err(src.at("scheme.name", "missing: a scheme of the registry")),
    };
    let scheme =
        registry::find(&name).map_err(|e| src.at("scheme.name", format!("{name:?}: {e}")))?;
    let counts_scheme = scheme.inits.contains(&Takes::Counts);
    let mut options = options_of(&s, src)?;
    // core's verdict on the options this entry takes, placed at the key
    options
        .check_for(scheme.name, scheme.options)
        .map_err(|e| match e {
            coagula_core::Error::OptionNotApplicable { key, .. } => {
                src.at(&format!("scheme.{key}"), e)
            }
            e => src.at("scheme", e),
        })?;
    let (kernel_name, builtin) = kernel_of(&s, src)?;
    let units = builtin::find(&kernel_name).map_or("", |b| b.units);

    // fragmentation
    let frag = match &s.fragmentation {
        None => Fragmentation::None,
        Some(f) => {
            let rate = positive(src, "fragmentation.rate", f.rate.unwrap_or(1.0))?;
            match f.kind {
                super::FragKind::BinaryUniform => Fragmentation::BinaryUniform(
                    BinaryUniform::new(rate).map_err(|e| src.at("fragmentation.rate", e))?,
                ),
            }
        }
    };
    if !matches!(frag, Fragmentation::None) && !scheme.fragmentation {
        return Err(src.at(
            "fragmentation",
            format!("scheme {name} only coagulates (its registry entry takes no fragmentation)"),
        ));
    }
    if let (Builtin::Coagulation(_), ModelKind::Temperature | ModelKind::Gas)
    | (Builtin::Temperature(_) | Builtin::Gas(_), ModelKind::Coagulation) =
        (builtin, scheme.model)
    {
        return Err(src.at(
            "kernel.kind",
            format!(
                "{kernel_name}: scheme {name} takes a {:?} model",
                scheme.model
            ),
        ));
    }

    // output times, on the time step's grid for a time-stepped scheme
    let times = times_of(&s, src)?;
    let t_end = *times.last().expect("non-empty");
    if scheme.law == Law::TimeStepped {
        if !s.scheme.contains_key("dt") {
            return Err(src.at(
                "scheme.dt",
                "missing: the time step of the time-driven scheme",
            ));
        }
        let dt = options.dt();
        // every output time on the Δt grid: otherwise the scheme takes a partial step
        // and is not the P-step scheme asked for
        for &t in &times {
            let k = (t / dt).round();
            if k < 1.0 || (k * dt - t).abs() > 1e-9 * t {
                return Err(src.at(
                    "scheme.dt",
                    format!("output time {t} is not a multiple of Δt = {dt} (choose times on the step grid)"),
                ));
            }
        }
        if t_end / dt > 1e8 {
            return Err(src.at(
                "scheme.dt",
                format!("{} steps to t = {t_end}: more than 1e8", t_end / dt),
            ));
        }
    }

    // observables
    let o = &s.output;
    if o.observables.is_empty() {
        return Err(src.at(
            "output.observables",
            "name at least one, e.g. [\"M0\", \"M2\"]",
        ));
    }
    let mut observables = Vec::new();
    for n in &o.observables {
        let ob = Observable::parse(n).map_err(|m| src.at("output.observables", m))?;
        match &ob {
            Observable::Gel if scheme.law == Law::TimeStepped => {
                return Err(src.at(
                    "output.observables",
                    "gel: the time-driven mass-flow scheme has no gel estimate (use M1)",
                ));
            }
            Observable::Density(_)
                if matches!(s.initial.kind, InitKind::Exponential | InitKind::Lognormal) =>
            {
                return Err(src.at(
                    "output.observables",
                    format!(
                        "{n}: a continuous start has no integer sizes (use C(a,b) for a size range)"
                    ),
                ));
            }
            Observable::Density(_) if s.fragmentation.is_some() => {
                return Err(src.at(
                    "output.observables",
                    format!(
                        "{n}: fragmentation makes sizes non-integer (use C(a,b) for a size range)"
                    ),
                ));
            }
            Observable::Named(x) if !scheme.observables.contains(&x.as_str()) => {
                return Err(src.at(
                    "output.observables",
                    format!(
                        "{x:?}: scheme {name} has the named observables {:?}",
                        scheme.observables
                    ),
                ));
            }
            _ => {}
        }
        observables.push(ob);
    }

    // run
    let r = &s.run;
    if r.replicas == 0 || r.replicas > 1_000_000 {
        return Err(src.at(
            "run.replicas",
            format!("{} must be in 1..=1000000", r.replicas),
        ));
    }
    if r.threads > 1024 {
        return Err(src.at("run.threads", format!("{} must be in 0..=1024", r.threads)));
    }

    // the initial condition
    let i = &s.initial;
    let c0 = positive(src, "initial.concentration", i.concentration.unwrap_or(1.0))?;
    let dist = distribution_of(&s, src)?;
    let particles = match dist.particles() {
        Some(n) => {
            if counts_scheme || scheme.inits.contains(&Takes::Temperatures) {
                refuse(
                    src,
                    "initial.particles",
                    &i.particles,
                    "the list gives the particles",
                )?;
            }
            match i.particles {
                Some(_) => particles_of(&s, src)?,
                None => n,
            }
        }
        None => particles_of(&s, src)?,
    };
    let continuous = dist.is_continuous();
    if !continuous || !counts_scheme {
        refuse(
            src,
            "initial.resolution",
            &i.resolution,
            "only an integer-size scheme from a continuous distribution has a size grid",
        )?;
    }
    let unit = if continuous && counts_scheme {
        positive(
            src,
            "initial.resolution",
            i.resolution.unwrap_or(1.0 / 64.0),
        )?
    } else {
        1.0
    };
    if continuous && counts_scheme && dist.grid_bias(unit) > 1e-3 {
        return Err(src.at(
            "initial.resolution",
            format!(
                "{unit}: the particles below half a grid cell would be rounded up (a mass bias up to {:.1e}): use a finer resolution",
                dist.grid_bias(unit)
            ),
        ));
    }
    // temperatures of the temperature models and gases: one per size
    let temperatures = match scheme.model {
        ModelKind::Coagulation => {
            refuse(
                src,
                "initial.temperature",
                &i.temperature,
                "a coagulation kernel has no temperatures",
            )?;
            refuse(
                src,
                "initial.temperatures",
                &i.temperatures,
                "a coagulation kernel has no temperatures",
            )?;
            Vec::new()
        }
        _ => {
            let sizes = match &dist {
                Distribution::Monodisperse { size }
                    if size.fract() == 0.0 && *size >= 1.0 && *size <= 1e7 =>
                {
                    *size as usize
                }
                Distribution::Counts(c) => c.len(),
                _ => {
                    return Err(src.at(
                        "initial.kind",
                        "a temperature model or a gas starts from a monodisperse integer size or counts",
                    ));
                }
            };
            match (&i.temperatures, i.temperature) {
                (Some(_), Some(_)) => {
                    return Err(src.at(
                        "initial.temperatures",
                        "give temperature or temperatures, not both",
                    ));
                }
                (Some(t), None) if t.len() == sizes => t.clone(),
                (Some(t), None) => {
                    return Err(src.at(
                        "initial.temperatures",
                        format!("{} temperatures for {sizes} sizes", t.len()),
                    ));
                }
                (None, t) => vec![t.unwrap_or(1.0); sizes],
            }
        }
    };

    // the replicas' stream: seed and stream set per replica (what the seed policy says)
    options = options.with_stream(r.seed, 0);
    if scheme.law == Law::TimeStepped && !counts_scheme && particles > 1 << 30 {
        return Err(src.at(
            "initial.particles",
            format!("{particles}: the mass-flow scheme takes at most 2^30"),
        ));
    }

    // the kernel in the simulation's size units: K(iδ, jδ) (δ^λ K(i, j) for a homogeneous
    // kernel); integer
    // sizes narrow the bounds to x ≥ 1
    let model = Model::of_builtin(builtin, |k| k, frag).map_err(|e| src.at("fragmentation", e))?;
    let (model, coefficient) = match model {
        Model::Coagulation {
            kernel,
            fragmentation,
        } => {
            let b = kernel.coefficient();
            let kernel = if unit != 1.0 {
                kernel
                    .in_size_unit(unit)
                    .map_err(|e| src.at("initial.resolution", e))?
            } else {
                kernel
            };
            // as the scheme runs it (core's rule: min-size 1 on integer sizes)
            let kernel: Coagulation = match scheme.runs(Builtin::Coagulation(kernel)) {
                Ok(Builtin::Coagulation(k)) => k,
                Ok(_) => kernel,
                Err(e) => return Err(src.at("kernel", e)),
            };
            (Model::coagulation(kernel, fragmentation), b)
        }
        m => (m, 1.0),
    };

    // a plan that builds: the centred start of replica 0 through the registry's checks,
    // with the memory of the replicas that run at once
    let mut plan = Plan {
        title: s.title.clone().unwrap_or_else(|| "scenario".into()),
        scheme,
        kernel_name,
        coefficient,
        units,
        model,
        dist,
        particles: particles as usize,
        c0,
        temperatures,
        size_unit: unit,
        options,
        times,
        observables,
        replicas: r.replicas,
        seed: r.seed,
        threads: r.threads,
        exact: None,
        memory: 0,
        memory_basis: String::new(),
        warnings: Vec::new(),
        classes: Vec::new(),
        log_axes: false,
        processes: None,
        scenario: s,
    };
    plan.processes = super::processes::of(&plan.scenario, src, scheme, unit)?;
    if scheme.law == Law::TimeStepped && !plan.randomised() && plan.replicas > 1 {
        return Err(src.at(
            "run.replicas",
            "deterministic QMC points give identical replicas: randomise them (randomization = \"owen\") or use points = \"mc\"",
        ));
    }
    let threads = if plan.threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        plan.threads
    };
    let concurrent = threads.min(plan.replicas as usize).max(1) as u64;
    let budget = coagula_core::scheme::population::machine_memory_budget() as u64;
    // a first bound before a start over particle sizes is built: its sizes (8 bytes a
    // particle) and the sims' particles (at least 48 bytes each)
    if !scheme.inits.contains(&Takes::Counts)
        && particles.saturating_mul(56).saturating_mul(concurrent) > budget
    {
        return Err(src.at(
            "initial.particles",
            format!(
                "{particles} particles x {concurrent} replicas at once need more than this machine's memory budget of {:.1} GiB",
                budget as f64 / (1u64 << 30) as f64
            ),
        ));
    }
    let start = plan.start(0.5, 0).map_err(|m| src.at("initial", m))?;
    // the values kept: replicas x times x observables
    let kept = plan
        .replicas
        .saturating_mul(plan.times.len() as u64)
        .saturating_mul(plan.observables.len() as u64);
    if kept > 1 << 25 {
        return Err(src.at(
            "run.replicas",
            format!(
                "{} replicas x {} times x {} observables: more than 2^25 values to keep",
                plan.replicas,
                plan.times.len(),
                plan.observables.len()
            ),
        ));
    }
    // a build of the centred start: every check of the scheme's constructor
    plan.build(&start, 0).map_err(|m| src.at("scheme", m))?;
    // direct simulation (over counts or particles) is the Marcus–Lushnikov process
    let mu = match &plan.dist {
        Distribution::Monodisperse { size } => *size,
        d if d.is_continuous() => d.mean(),
        _ => 1.0,
    };
    plan.exact = match plan.model {
        // (a closed form of coagulation alone does not hold with processes)
        _ if plan.processes.is_some() => super::processes::exact(&plan),
        Model::Coagulation { fragmentation, .. } if plan.units.is_empty() => exact_of(
            &plan.scenario,
            &plan.kernel_name,
            plan.coefficient,
            fragmentation,
            c0,
            mu,
            plan.scheme.law == Law::FiniteN,
        ),
        _ => None,
    };
    super::memory::estimate(&mut plan, &start, concurrent, budget)
        .map_err(|(key, m)| src.at(key, m))?;
    super::memory::gel_warning(&mut plan);
    plan.log_axes = plan.scenario.output.log_axes.unwrap_or(
        plan.scenario.output.spacing == Some(Spacing::Log) && plan.scenario.output.times.is_none(),
    );
    plan.classes = match plan.scenario.output.classes.clone() {
        Some(e) => {
            if !(2..=201).contains(&e.len())
                || e.iter().any(|x| !(x.is_finite() && *x > 0.0))
                || e.windows(2).any(|w| w[0] >= w[1])
            {
                return Err(src.at(
                    "output.classes",
                    "class edges: 2 to 201 finite sizes > 0, strictly increasing",
                ));
            }
            e
        }
        None => default_classes(&plan),
    };
    Ok(plan)
}

/// Log-spaced class edges, 5 a decade (at most 60 classes): from half the smallest
/// size unit (integer sizes: size 1 is in the first class) or a thousandth of the
/// start's mean (continuous sizes), to 30 times the mass-weighted mean size `M2/M1` at
/// the last output time where the exact solution gives it, else 10^4 times the start's.
fn default_classes(plan: &Plan) -> Vec<f64> {
    let mean = plan.dist.mean();
    let mean = if mean.is_finite() && mean > 0.0 {
        mean
    } else {
        1.0
    };
    let integer = plan.scheme.inits.contains(&Takes::Counts);
    let lo = if integer {
        0.5 * plan.size_unit
    } else {
        mean / 1000.0
    };
    let t = plan.times.last().copied().unwrap_or(0.0);
    let m = |k: f64| plan.exact.and_then(|e| e.value(&Observable::Moment(k), t));
    let hi = match (m(1.0), m(2.0)) {
        (Some(m1), Some(m2)) if m1 > 0.0 && (m2 / m1).is_finite() => 30.0 * m2 / m1,
        _ => 1e4 * mean,
    };
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let classes = ((hi / lo).log10() * 5.0).ceil().clamp(1.0, 60.0) as usize;
    let mut edges: Vec<f64> = (0..=classes)
        .map(|i| lo * (hi / lo).powf(i as f64 / classes as f64))
        .collect();
    if integer {
        // on a size grid, edges at half cells: every class holds whole grid sizes
        let d = plan.size_unit;
        for x in edges.iter_mut() {
            *x = ((*x / d - 0.5).round().max(0.0) + 0.5) * d;
        }
        edges.dedup();
    }
    edges
}
