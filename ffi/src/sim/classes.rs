//! Host coupling on size classes (core's `classes` module): the population projected
//! onto a host's pivots keeping number and mass, a population built from class
//! numbers, and the change per class over a step as rates. The rules live in core;
//! these calls translate.

use super::coag_sim;
use crate::rng::Source;
use crate::status::guard;
use crate::util::{disjoint, handle, handle_mut, slice, slice_mut};
use coagula_core::classes::{Classes, rates};

/// Projects the sim's population onto the `len` pivots (finite, > 0, strictly
/// ascending): `numbers[i]` gets the number per unit volume at `pivots[i]`, each
/// particle split between the two pivots around it so that number and mass are kept
/// (fixed pivot, Kumar & Ramkrishna 1996). What lies below the first pivot or above
/// the last is not classed: `outside` (NULL or 4 doubles) gets its number and mass per
/// unit volume, below then above (`{N_below, M_below, N_above, M_above}`). On error
/// nothing is written.
///
/// # Safety
/// `sim` NULL or live; `pivots` and `numbers` valid for `len` doubles each; `outside`
/// NULL or valid for 4 doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_project(
    sim: *const coag_sim,
    pivots: *const f64,
    len: usize,
    numbers: *mut f64,
    outside: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable / writable by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let x = unsafe { slice(pivots, len, "pivots") }?;
        let classes = Classes::new(x)?;
        let out = unsafe { slice_mut(numbers, len, "numbers") }?;
        disjoint(x, out, "pivots and numbers")?;
        let spill = if outside.is_null() {
            None
        } else {
            // SAFETY: non-null; 4 writable doubles by contract.
            Some(unsafe { slice_mut(outside, 4, "outside") }?)
        };
        if let Some(o) = &spill {
            disjoint(out, o, "numbers and outside")?;
        }
        let o = s.sim.project(&classes, out)?;
        if let Some(w) = spill {
            w.copy_from_slice(&[o.below_number, o.below_mass, o.above_number, o.above_mass]);
        }
        Ok(())
    })
}

/// Replaces the sim's population by `numbers[i]` particles per unit volume at
/// `pivots[i]` (`len` of each; pivots finite, > 0, strictly ascending; numbers
/// finite, ≥ 0). Size-count schemes (integer pivots) and size schemes get
/// `numbers[i] × volume` particles of size `pivots[i]`, the fraction rounded up with
/// its own probability (draws from the sim's random stream or its host callback), so
/// each class's expected count is exact; the mass-flow schemes keep their particle
/// number and place it on the classes' mass, with that total mass. The processes'
/// books start afresh. Temperature and gas sims: `COAG_UNSUPPORTED`. Errors leave the
/// sim unchanged.
///
/// # Safety
/// `sim` NULL or live; `pivots` and `numbers` valid for `len` doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_set_classes(
    sim: *mut coag_sim,
    pivots: *const f64,
    numbers: *const f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live / readable by contract.
        let (s, _busy) = unsafe { handle_mut(sim, "sim") }?;
        let x = unsafe { slice(pivots, len, "pivots") }?;
        let n = unsafe { slice(numbers, len, "numbers") }?;
        let classes = Classes::new(x)?;
        let mut rng = match s.callback {
            Some((f, d)) => Source::callback(f, d),
            None => Source::Own(s.own.clone()),
        };
        let r = s.sim.set_classes(&classes, n, &mut rng);
        // (the stream moves on only when the population was replaced)
        if let (Ok(()), Source::Own(p)) = (&r, rng) {
            s.own = p;
        }
        r?;
        Ok(())
    })
}

/// The change per class over a step as rates a host's transport equation adds:
/// `out[i] = (after[i] − before[i]) / dt` for `len` classes (`dt` finite, > 0), with
/// `before` and `after` from `coag_sim_project` around the step. `out` may be
/// `before` or `after`. On error nothing is written.
///
/// # Safety
/// `before`, `after` and `out` valid for `len` doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_class_rates(
    before: *const f64,
    after: *const f64,
    len: usize,
    dt: f64,
    out: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: readable by contract; copied before `out` is written (it may alias).
        let b = unsafe { slice(before, len, "before") }?.to_vec();
        let a = unsafe { slice(after, len, "after") }?.to_vec();
        let o = unsafe { slice_mut(out, len, "out") }?;
        rates(&b, &a, dt, o)?;
        Ok(())
    })
}
