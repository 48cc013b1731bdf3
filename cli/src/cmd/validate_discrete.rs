//! The `discrete` reference of `coagula validate`: the discrete Smoluchowski equations
//! integrated directly on the integer sizes 1..m (`coagula_core::exact::Sectional::
//! discrete`), for a kernel without a closed form (the atmospheric kernel of the block
//! majorants' cases, issue 45).
//!
//! It takes a coagulation scenario over integer sizes from monomers (size unit 1), no
//! sources, sinks or growth. The largest size m is the first of 512, 1024, 2048, 4096
//! whose lost mass (what passes m) stays below 1e-12 of M1 (a case beyond 4096 is
//! refused). RK4 runs in 20 pieces whose ends crowd towards the start (the rates fall
//! as particles merge), each piece at a step of 0.1 over the fastest loss rate of any
//! size; the same run at half the step gives the step's error, which must stay below
//! 1e-6 of the value (or the case is refused), and the finer run is the reference. The
//! convergence measured is in `docs/design/block-majorants.md`.

use super::validate_sectional::fastest_loss;
use crate::scenario::{InitKind, Observable, Plan};
use coagula_core::exact::Sectional;
use coagula_core::initial::Distribution;
use coagula_core::kernel::Coagulation;
use coagula_core::scheme::facade::Model;

/// The largest sizes tried, in order.
const SIZES: [usize; 4] = [512, 1024, 2048, 4096];
/// The step over the fastest loss rate (RK4 is stable to 2.78).
const STEP: f64 = 0.1;

/// The discrete solution's value of `o` at `t` for `plan` (see the module docs).
pub(super) fn reference(plan: &Plan, o: &Observable, t: f64) -> Result<f64, String> {
    let (coarse, fine) = cached(plan, t)?;
    let (a, b) = (value(&coarse, o)?, value(&fine, o)?);
    if (a - b).abs() > 1e-6 * b.abs() {
        return Err(format!(
            "the discrete solution has not converged in its step: {b} against {a} at twice the step"
        ));
    }
    Ok(b)
}

fn value(s: &Sectional<Coagulation>, o: &Observable) -> Result<f64, String> {
    Ok(match *o {
        Observable::Moment(k) => s.moment(k),
        Observable::Density(k) => s.concentration(k as f64, k as f64 + 1.0),
        // C(a, b): the sizes in [a, b]; C[a, b): those in [a, b)
        Observable::Concentration(a, b) => s.concentration(a, b.floor() + 1.0),
        Observable::Class(a, b) => s.concentration(a, b),
        _ => {
            return Err(format!(
                "the discrete reference gives moments and concentrations, not {}",
                o.name()
            ));
        }
    })
}

/// The solutions at the step and at half of it, per scenario and time.
type Solved = (String, u64, Sectional<Coagulation>, Sectional<Coagulation>);

thread_local! {
    static SOLVED: std::cell::RefCell<Vec<Solved>> = const { std::cell::RefCell::new(Vec::new()) };
}

fn cached(plan: &Plan, t: f64) -> Result<(Sectional<Coagulation>, Sectional<Coagulation>), String> {
    let key = format!("{:?}", plan.scenario);
    let hit = SOLVED.with(|c| {
        c.borrow()
            .iter()
            .find(|(k, tb, _, _)| *k == key && *tb == t.to_bits())
            .map(|(_, _, a, b)| (a.clone(), b.clone()))
    });
    if let Some(v) = hit {
        return Ok(v);
    }
    let kernel = checked(plan)?;
    for m in SIZES {
        let coarse = solve(kernel, plan.c0, m, t, STEP)?;
        let m1 = plan.c0;
        if coarse.books().lost_mass > 1e-12 * m1 {
            continue;
        }
        let fine = solve(kernel, plan.c0, m, t, STEP / 2.0)?;
        SOLVED.with(|c| {
            c.borrow_mut()
                .push((key, t.to_bits(), coarse.clone(), fine.clone()))
        });
        return Ok((coarse, fine));
    }
    Err(format!(
        "the discrete solution loses more than 1e-12 of the mass past size {} by t = {t}",
        SIZES[SIZES.len() - 1]
    ))
}

/// The kernel of a scenario the reference takes (see the module docs).
fn checked(plan: &Plan) -> Result<Coagulation, String> {
    let s = &plan.scenario;
    let monomers = matches!(
        (&plan.dist, s.initial.kind),
        (Distribution::Monodisperse { size }, InitKind::Monodisperse)
            if *size == 1.0 && plan.size_unit == 1.0
    );
    if !monomers {
        return Err("the discrete reference starts from monomers of size 1".into());
    }
    if s.source.is_some() || s.sink.is_some() || s.growth.is_some() {
        return Err("the discrete reference takes coagulation alone".into());
    }
    match plan.model {
        Model::Coagulation { kernel, .. } => Ok(kernel),
        _ => Err("the discrete reference takes a coagulation kernel".into()),
    }
}

/// The discrete equations on sizes 1..=m from `c0` monomers to `t`, RK4 at `step`
/// over the fastest loss rate, in 20 pieces ending at `t (k/20)²`.
fn solve(
    kernel: Coagulation,
    c0: f64,
    m: usize,
    t: f64,
    step: f64,
) -> Result<Sectional<Coagulation>, String> {
    let mut s = Sectional::discrete(kernel, m).map_err(|e| e.to_string())?;
    s.set_number(0, c0).map_err(|e| e.to_string())?;
    let pieces = 20;
    for k in 1..=pieces {
        let end = t * (f64::from(k) / f64::from(pieces)).powi(2);
        let dt = step / fastest_loss(&s, None, None).max(1e-12);
        s.advance_to(end, dt).map_err(|e| e.to_string())?;
    }
    Ok(s)
}
