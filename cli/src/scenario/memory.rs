//! What a run will hold, predicted before it starts (core's [`Reach`] from the exact
//! solution or the mean-field mean size, turned into bytes by each scheme), and the
//! warning of a run far past its gel point.

use super::plan::{Observable, Plan};
use coagula_core::kernel::CoagulationKernel;
use coagula_core::kernel::temperature::TemperatureKernel;
use coagula_core::scheme::facade::{Init, Memory, Model, ModelKind, Reach, Start};
use coagula_core::scheme::registry;

/// What the sims will hold at most (summed over those running at once), from how far
/// the sizes grow by the end time: the exact solution's M1/M0 and M2/M1 where one is
/// known, else the mean-field approximation of the mean size (core's [`Reach`]); each
/// scheme turns that into bytes by its own layout. Refuses a run above the budget.
///
/// The error names the key to change: the end time when the growth is what does not
/// fit, else the particles.
pub fn estimate(
    plan: &mut Plan,
    start: &Start,
    concurrent: u64,
    budget: u64,
) -> Result<(), (&'static str, String)> {
    let init = start.init();
    let rank = match &plan.model {
        Model::Coagulation { kernel, .. } => kernel.rank(),
        _ => 0,
    };
    let mut reach = Reach::at_start(&init, rank);
    if let Model::Coagulation { kernel, .. } = &plan.model {
        reach.blocks = coagula_core::scheme::lowrank::prefers_blocks(kernel);
        reach.log_linear = kernel.log_linear_blocks();
    }
    let end = plan.times.last().copied().unwrap_or(0.0);
    plan.memory_basis = "at start".into();
    let grows =
        plan.scheme.memory == Memory::Growing && plan.scheme.model == ModelKind::Coagulation;
    let fragments = plan.model.fragments();
    if let (true, Init::Counts { counts, volume }, Model::Coagulation { kernel, .. }) =
        (grows, init, &plan.model)
    {
        // the whole simulated mass, in grid units: no cluster passes it
        let all = counts
            .iter()
            .enumerate()
            .map(|(i, &c)| (i + 1) as f64 * c as f64)
            .sum::<f64>();
        let exact = plan.exact.and_then(|e| {
            let m = |k: f64| e.value(&Observable::Moment(k), end);
            Some((m(0.0)?, m(1.0)?, m(2.0)?))
        });
        if fragments {
            plan.memory_basis = "at start (fragmentation keeps the sizes bounded)".into();
        } else if let Some((m0, m1, m2)) = exact {
            reach = reach.ending_at(m1 / m0 / plan.size_unit, m2 / m1 / plan.size_unit);
            // past a gel point the gel holds most of the mass (the sol's moments, which
            // the exact solution gives, miss it): all the mass of the N0 particles the
            // doublings keep, N0 M1(0)/M0(t)
            let gel = plan.exact.and_then(|e| e.solution.gel_time());
            let mass = plan
                .exact
                .and_then(|e| e.value(&Observable::Moment(1.0), 0.0));
            if let (Some(tg), Some(mass)) = (gel, mass)
                && end > tg
            {
                let gel = reach.particles as f64 * mass / m0 / plan.size_unit;
                reach.largest = reach.largest.max(gel.min(u64::MAX as f64 / 4.0) as u64);
            }
            plan.memory_basis = format!(
                "at t = {}, largest size about {:.3e} from the exact solution",
                coagula_core::error::Short(end),
                reach.largest as f64 * plan.size_unit
            );
        } else {
            reach = reach.mean_field(kernel, volume, all, end);
            plan.memory_basis = format!(
                "at t = {}, largest size about {:.3e} from the mean-field mean size",
                coagula_core::error::Short(end),
                reach.largest as f64 * plan.size_unit
            );
        }
    }
    if let (
        Memory::Growing,
        Init::Temperatures {
            counts,
            temperatures,
            volume,
        },
        Model::Temperature(tm),
    ) = (plan.scheme.memory, init, &plan.model)
    {
        // the aggregation rate with the temperature per unit size held at the start's
        // (aggregation adds the partners' temperatures: the closed-form model keeps
        // T_i/i exactly, a cooling gas falls below it, so this over-predicts there)
        let (mut mass, mut heat) = (0.0, 0.0);
        for (i, (&c, &t)) in counts.iter().zip(temperatures).enumerate() {
            mass += (i + 1) as f64 * c as f64;
            heat += c as f64 * t;
        }
        let per_size = heat / mass;
        let diagonal = |s: f64| {
            let i = s.round().clamp(1.0, u64::MAX as f64 / 4.0) as u64;
            let t = per_size * i as f64;
            tm.rates(i, t, i, t).aggregation
        };
        reach = reach.mean_field_of(diagonal, volume, mass, end);
        plan.memory_basis = format!(
            "at t = {}, largest size about {:.3e} from the mean-field mean size at the start's temperature per unit size",
            coagula_core::error::Short(end),
            reach.largest as f64
        );
    }
    let per = registry::memory_estimate(plan.scheme, &init, &plan.options, fragments, &reach);
    plan.memory = per.saturating_mul(concurrent);
    if plan.memory > budget {
        let key = if reach.largest > reach.start {
            "output.t-end"
        } else {
            "initial.particles"
        };
        return Err((
            key,
            format!(
                "the run needs about {:.1} GiB ({concurrent} replicas at once, {}), above this machine's memory budget of {:.1} GiB: fewer particles, replicas or threads, or an earlier end",
                plan.memory as f64 / (1u64 << 30) as f64,
                plan.memory_basis,
                budget as f64 / (1u64 << 30) as f64
            ),
        ));
    }
    Ok(())
}

/// Warns of a run past four times a gel time (the multiplicative kernel): its cost per
/// unit of time grows about e-fold, most proposals being the gel's and rejected (issue
/// 40: 148 M proposals by t = 13, 99.99 % rejected).
pub fn gel_warning(plan: &mut Plan) {
    let (Some(e), Some(&t)) = (plan.exact, plan.times.last()) else {
        return;
    };
    if let Some(tg) = e.solution.gel_time()
        && t > 4.0 * tg
        && plan.scheme.model == ModelKind::Coagulation
    {
        plan.warnings.push(format!(
            "the run goes past the gel point t = {} to t = {}: there the gel's collisions dominate and the cost grows about e-fold per unit of time (most proposals are the gel's, and rejected); end near the gel point for a run that finishes",
            coagula_core::error::Short(tg),
            coagula_core::error::Short(t)
        ));
    }
}
