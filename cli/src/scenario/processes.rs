//! `[source]`, `[sink]` and `[growth]`: the processes beside coagulation (core's
//! `process` module), in the scenario's units, turned into the simulation's.
//!
//! Sizes in a scenario are in its own units; an integer-size scheme from a continuous
//! start runs on a grid where size i stands for `i · resolution` (`unit`). A source's
//! sizes are divided by `unit`; a removal rate `c x^p` becomes `c unit^p i^p`; growth
//! `dx/dt = g x^q` becomes monomer attachment at `g unit^{q−1} i^q` per particle. Rates
//! per unit volume are the scenario's (the simulation's volume is N0 / c0 in them).

use super::plan::{ExactRef, Plan};
use super::{InitKind, Scenario, ScenarioError, Source};
use coagula_core::exact::{Balance, Exact};
use coagula_core::initial::Distribution;
use coagula_core::process::{Processes, Source as Inflow};
use coagula_core::scheme::facade::SchemeId;
use serde::{Deserialize, Serialize};

/// `[source]`: particles injected at `rate` per unit volume and time.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SourceSpec {
    /// Particles per unit volume and time (≥ 0).
    pub rate: f64,
    /// Their sizes: `monodisperse` (nucleation; `size`, default 1), `exponential`
    /// (`mean`), `lognormal` (`median`, `gsd`) or `sizes` (drawn uniformly from the
    /// list `sizes`: a mixture, e.g. an emission and a background inflow, a size listed
    /// twice drawn twice as often).
    pub kind: InitKind,
    /// Monodisperse size.
    pub size: Option<f64>,
    /// Exponential mean.
    pub mean: Option<f64>,
    /// Log-normal median.
    pub median: Option<f64>,
    /// Log-normal geometric standard deviation (> 1).
    pub gsd: Option<f64>,
    /// The list of a `sizes` source (at least 2 entries).
    pub sizes: Option<Vec<f64>>,
    /// A piecewise-constant rate: `rates[k]` from `times[k]` on (`rate` before the
    /// first time).
    pub times: Option<Vec<f64>>,
    /// The rates of the schedule, one per time.
    pub rates: Option<Vec<f64>>,
}

/// `[sink]`: removal at `rate · x^exponent` per particle (dilution and outflow at
/// exponent 0, the default; deposition at a power of size, at most 1).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct SinkSpec {
    /// The coefficient (≥ 0).
    pub rate: f64,
    /// The exponent p ∈ [−10, 1] (default 0).
    pub exponent: Option<f64>,
}

/// `[growth]`: `dx/dt = rate · x^exponent`, as monomer attachment on the integer-size
/// schemes (exact there), by Strang splitting of step `step` on real sizes (needed
/// there; core's `Processes::with_growth_step`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct GrowthSpec {
    /// The coefficient (≥ 0).
    pub rate: f64,
    /// The exponent q ∈ [−10, 1] (default 0: constant growth; 1: linear).
    pub exponent: Option<f64>,
    /// The splitting step on real sizes (time; not used on integer sizes).
    pub step: Option<f64>,
}

/// The processes of scenario `s` for `scheme`, in simulation units (`unit`: the size
/// one unit of the simulation stands for); `None` when it has none.
pub(super) fn of(
    s: &Scenario,
    src: &Source<'_>,
    scheme: SchemeId,
    unit: f64,
) -> Result<Option<Processes>, ScenarioError> {
    let mut p = Processes::default();
    if let Some(q) = &s.source {
        let not = |key: &str, v: Option<f64>, why: &str| match v {
            Some(_) => Err(src.at(&format!("source.{key}"), format!("not used here ({why})"))),
            None => Ok(()),
        };
        let need = |key: &str, v: Option<f64>| {
            v.ok_or_else(|| src.at(&format!("source.{key}"), "missing"))
        };
        if q.kind != InitKind::Sizes && q.sizes.is_some() {
            return Err(src.at(
                "source.sizes",
                "not used here (only a `sizes` source lists its sizes)",
            ));
        }
        let sizes = match q.kind {
            InitKind::Sizes => {
                for (key, v) in [
                    ("size", q.size),
                    ("mean", q.mean),
                    ("median", q.median),
                    ("gsd", q.gsd),
                ] {
                    not(key, v, "a `sizes` source lists its sizes")?;
                }
                let list = q
                    .sizes
                    .as_ref()
                    .ok_or_else(|| src.at("source.sizes", "missing"))?;
                Distribution::Sizes(list.iter().map(|x| x / unit).collect())
            }
            InitKind::Monodisperse => {
                not("mean", q.mean, "a monodisperse source has a size")?;
                not("median", q.median, "a monodisperse source has a size")?;
                not("gsd", q.gsd, "a monodisperse source has a size")?;
                Distribution::Monodisperse {
                    size: q.size.unwrap_or(1.0) / unit,
                }
            }
            InitKind::Exponential => {
                not("size", q.size, "an exponential source has a mean")?;
                not("median", q.median, "an exponential source has a mean")?;
                not("gsd", q.gsd, "an exponential source has a mean")?;
                Distribution::Exponential {
                    mean: need("mean", q.mean)? / unit,
                }
            }
            InitKind::Lognormal => {
                not("size", q.size, "a log-normal source has a median and gsd")?;
                not("mean", q.mean, "a log-normal source has a median and gsd")?;
                Distribution::Lognormal {
                    median: need("median", q.median)? / unit,
                    gsd: need("gsd", q.gsd)?,
                }
            }
            InitKind::Counts => {
                return Err(src.at(
                    "source.kind",
                    "a source draws its sizes from monodisperse, exponential, lognormal or sizes",
                ));
            }
        };
        let inflow = Inflow::new(q.rate, sizes).map_err(|e| src.at("source", e))?;
        let inflow = match (&q.times, &q.rates) {
            (None, None) => inflow,
            (Some(t), Some(r)) => inflow
                .with_schedule(t, r)
                .map_err(|e| src.at("source.times", e))?,
            (None, Some(_)) => {
                return Err(src.at("source.times", "missing (a schedule takes times and rates)"));
            }
            (Some(_), None) => {
                return Err(src.at("source.rates", "missing (a schedule takes times and rates)"));
            }
        };
        p = p.with_source(inflow);
    }
    if let Some(k) = &s.sink {
        let e = k.exponent.unwrap_or(0.0);
        let c = k.rate * unit.powf(e);
        p = p.with_removal(c, e).map_err(|e| src.at("sink", e))?;
    }
    if let Some(g) = &s.growth {
        let e = g.exponent.unwrap_or(0.0);
        let c = g.rate * unit.powf(e - 1.0);
        p = p.with_growth(c, e).map_err(|e| src.at("growth", e))?;
        use coagula_core::scheme::facade::GrowthKind;
        match (g.step, scheme.growth_kind()) {
            (Some(h), GrowthKind::Split) => {
                p = p
                    .with_growth_step(h)
                    .map_err(|e| src.at("growth.step", e))?;
            }
            (Some(_), GrowthKind::Attachment) => {
                return Err(src.at(
                    "growth.step",
                    "not used here (growth on integer sizes is monomer attachment, exact)",
                ));
            }
            (Some(_), GrowthKind::InStep) => {
                return Err(src.at(
                    "growth.step",
                    "not used here (the mass flow grows the sizes in its own step, scheme.dt)",
                ));
            }
            (None, GrowthKind::Split) => {
                return Err(src.at(
                    "growth.step",
                    "growth on real sizes needs a splitting step (second order in it at its multiples)",
                ));
            }
            (None, _) => {}
        }
    }
    if p.is_empty() {
        return Ok(None);
    }
    scheme
        .takes_processes(&p)
        .map_err(|e| src.at("scheme.name", e))?;
    if s.fragmentation.is_some() && !scheme.processes_with_fragmentation() {
        return Err(src.at(
            "fragmentation",
            "processes beside coagulation run with coagulation alone on this scheme (massflow takes both)",
        ));
    }
    Ok(Some(p))
}

/// The closed form of a scenario with processes, where one holds: the constant kernel
/// from a monodisperse start with a monodisperse or listed source, removal at a constant
/// rate and linear growth (`coagula_core::exact::Balance`), in the scenario's units.
pub(super) fn exact(plan: &Plan) -> Option<ExactRef> {
    let s = &plan.scenario;
    let x0 = match plan.dist {
        Distribution::Monodisperse { size } => size,
        _ => return None,
    };
    if plan.kernel_name != "constant" || !plan.units.is_empty() || s.fragmentation.is_some() {
        return None;
    }
    let (rate, size, list) = match &s.source {
        None => (0.0, 1.0, None),
        // (a scheduled source has no closed form here)
        Some(q) if q.times.is_some() => return None,
        Some(q) if q.kind == InitKind::Monodisperse => (q.rate, q.size.unwrap_or(1.0), None),
        // (an integer-size scheme rounds listed sizes that are not integers: no closed
        // form then)
        Some(q) if q.kind == InitKind::Sizes => {
            let integer = plan
                .scheme
                .inits
                .contains(&coagula_core::scheme::facade::InitKind::Counts);
            let list = q.sizes.as_deref()?;
            if integer
                && list
                    .iter()
                    .any(|&x| x / plan.size_unit != (x / plan.size_unit).round())
            {
                return None;
            }
            (q.rate, 1.0, Some(list))
        }
        Some(_) => return None,
    };
    let removal = match &s.sink {
        None => 0.0,
        Some(k) if k.exponent.unwrap_or(0.0) == 0.0 => k.rate,
        Some(_) => return None,
    };
    let growth = match &s.growth {
        None => 0.0,
        Some(g) if g.exponent == Some(1.0) => g.rate,
        Some(_) => return None,
    };
    let c0 = plan.c0;
    let b = Balance::new(
        plan.coefficient,
        [c0, c0 * x0, c0 * x0 * x0],
        rate,
        size,
        removal,
        growth,
    )
    .ok()?;
    let b = match list {
        Some(l) => b.with_source_sizes(l).ok()?,
        None => b,
    };
    Some(ExactRef {
        solution: Exact::balance(b),
        c0: 1.0,
        mu: 1.0,
        name: "constant kernel with a monomer source, dilution and linear growth (moment equations in closed form)",
    })
}
