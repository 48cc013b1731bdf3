//! Reading a sim: its time, books, observables (moments, concentrations, named
//! ones), its state (counts, occupied sizes, particle sizes, per-size values,
//! velocities).

use super::coag_sim;
use crate::report::{coag_step_report, write_report};
use crate::status::{
    COAG_BUFFER_TOO_SMALL, COAG_CAPACITY, COAG_INVALID_ARGUMENT, COAG_UNSUPPORTED, Fail, fail,
    guard,
};
use crate::util::{disjoint, handle, non_null, slice_mut, text, write, write_opt};
use coagula_core::scheme::facade::{InitKind, State};
use std::ffi::c_char;

/// Runs `f` on a live sim (read-only) and writes its result to `out`.
///
/// # Safety
/// `sim` NULL or live; `out` NULL or writable.
unsafe fn read<T>(
    sim: *const coag_sim,
    out: *mut T,
    f: impl FnOnce(&coag_sim) -> Result<T, Fail>,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        let v = f(s)?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, v) };
        Ok(())
    })
}

/// The sim's current time.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_time(sim: *const coag_sim, out: *mut f64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { read(sim, out, |s| Ok(s.sim.time())) }
}

/// Totals of every `coag_sim_advance_to` so far (`out->struct_size` must be set).
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_totals(sim: *const coag_sim, out: *mut coag_step_report) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        non_null(out, "out")?;
        // SAFETY: non-null; writable for its struct_size (contract).
        unsafe { write_report(out, s.sim.totals()) }
    })
}

/// The moment `M_m` (any real order m) of the number concentration; a result that
/// overflows a double (e.g. M_{1e6}) is `COAG_CAPACITY`.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_moment(sim: *const coag_sim, m: f64, out: *mut f64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if !m.is_finite() {
                return fail(COAG_INVALID_ARGUMENT, "moment order must be finite");
            }
            finite_result(s.sim.moment(m), || {
                format!("moment of order {}", coagula_core::error::Short(m))
            })
        })
    }
}

/// The number concentration of sizes in `[a, b]` (the sum concentration C(t, a, b));
/// `a > b` or a NaN bound is `COAG_INVALID_ARGUMENT`, a sum that overflows a double
/// (counts in a tiny volume) `COAG_CAPACITY`.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_concentration(
    sim: *const coag_sim,
    a: f64,
    b: f64,
    out: *mut f64,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if a.is_nan() || b.is_nan() {
                return fail(COAG_INVALID_ARGUMENT, "concentration bounds are NaN");
            }
            if a > b {
                return fail(
                    COAG_INVALID_ARGUMENT,
                    format!(
                        "concentration bounds a = {} > b = {}",
                        coagula_core::error::Short(a),
                        coagula_core::error::Short(b)
                    ),
                );
            }
            // + 0.0 turns an empty sum's −0.0 into 0
            finite_result(s.sim.concentration(a, b) + 0.0, || {
                "concentration (counts over a tiny volume)".into()
            })
        })
    }
}

/// The number concentrations of the half-open size classes `[edges[i], edges[i+1])`
/// into `out[i]`, `i < n_edges − 1`: adjacent classes add up to the class they split
/// (the closed `coag_sim_concentration` counts a shared edge in both). `edges` must be
/// strictly increasing and not NaN (±infinity allowed), `n_edges ≥ 2`, and `out` hold
/// `n_edges − 1` doubles; nothing is written on an error.
///
/// # Safety
/// `sim` NULL or live; `edges` valid for `n_edges` doubles; `out` valid for
/// `n_edges − 1` doubles and not overlapping `edges`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_class_concentrations(
    sim: *const coag_sim,
    edges: *const f64,
    n_edges: usize,
    out: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        if n_edges < 2 {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!("size classes: {n_edges} edges (at least 2 make one class)"),
            );
        }
        // SAFETY: NULL and length checked; readable by contract.
        let e = unsafe { crate::util::slice(edges, n_edges, "edges") }?;
        if let Some(i) = e.iter().position(|x| x.is_nan()) {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!("size classes: edges[{i}] is NaN"),
            );
        }
        if let Some(i) = e.windows(2).position(|w| w[0] >= w[1]) {
            return fail(
                COAG_INVALID_ARGUMENT,
                format!(
                    "size classes: edges[{i}] = {} ≥ edges[{}] = {} (edges must increase)",
                    coagula_core::error::Short(e[i]),
                    i + 1,
                    coagula_core::error::Short(e[i + 1])
                ),
            );
        }
        let values = e
            .windows(2)
            .map(|w| {
                // + 0.0 turns an empty sum's −0.0 into 0
                finite_result(s.sim.class_concentration(w[0], w[1]) + 0.0, || {
                    "size class concentration (counts over a tiny volume)".into()
                })
            })
            .collect::<Result<Vec<f64>, Fail>>()?;
        // (overlap is checked on the addresses, before a `&mut` to `out` exists)
        non_null(out, "out")?;
        let (e0, o0) = (edges as usize, out as usize);
        let (le, lo) = (n_edges * 8, (n_edges - 1) * 8);
        if e0 < o0.saturating_add(lo) && o0 < e0.saturating_add(le) {
            return fail(COAG_INVALID_ARGUMENT, "edges and out overlap");
        }
        // SAFETY: NULL and length checked, disjoint from `edges`; writable by contract.
        let o = unsafe { slice_mut(out, n_edges - 1, "out") }?;
        o.copy_from_slice(&values);
        Ok(())
    })
}

/// Gel mass estimate: for the integer-size and direct-simulation schemes the largest
/// cluster's mass per volume (Eibeck & Wagner eq. 6.15), for the mass flow algorithm
/// the mass past its truncation; 0 for the time-driven mass-flow scheme, whose
/// particles never leave. Before gelation this is not a gel mass (it tends to 0 as N
/// grows).
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_gel_mass(sim: *const coag_sim, out: *mut f64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            finite_result(s.sim.gel_mass().unwrap_or(0.0), || "gel mass".into())
        })
    }
}

/// `v` when finite; else `COAG_CAPACITY` naming `what` (an observable that overflows a
/// double — e.g. M_{1e6}, large sizes, counts in a tiny volume — is not a number the
/// host can use).
fn finite_result(v: f64, what: impl FnOnce() -> String) -> Result<f64, Fail> {
    if v.is_finite() {
        Ok(v)
    } else {
        fail(
            COAG_CAPACITY,
            format!("{} overflows a double ({v})", what()),
        )
    }
}

/// Number of simulation particles.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_particle_count(sim: *const coag_sim, out: *mut u64) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { read(sim, out, |s| Ok(s.sim.particles())) }
}

/// Length of the sim's state vector: the number of particles (mass-flow: read with
/// `coag_sim_get_sizes`) or the largest occupied size (size-count schemes: the dense
/// vector `coag_sim_get_counts` fills; 0 for an empty system). Nothing is allocated:
/// a state whose largest size is huge but whose occupied sizes are few is better read
/// with `coag_sim_occupied` and `coag_sim_get_pairs`.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_state_len(sim: *const coag_sim, out: *mut usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if let Some(n) = particle_sizes_len(s) {
                return Ok(n);
            }
            let mut largest = 0u64;
            s.sim.for_each_count(&mut |size, _| largest = size)?;
            usize::try_from(largest).or_else(|_| {
                fail(
                    COAG_CAPACITY,
                    "state length: the largest size does not fit size_t",
                )
            })
        })
    }
}

/// The number of particles of a mass-flow sim (its state is its sizes; `None` for a
/// size-count sim, whose dense state is not built to find out).
fn particle_sizes_len(s: &coag_sim) -> Option<usize> {
    if !s.sim.info().inits.contains(&InitKind::Sizes) {
        return None;
    }
    match s.sim.state() {
        State::Sizes(x) => Some(x.len()),
        State::Counts(..) => None,
    }
}

/// The number of occupied sizes of a size-count sim (the pairs `coag_sim_get_pairs`
/// writes), or of particles of a mass-flow sim.
///
/// # Safety
/// `sim` must be NULL or live; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_occupied(sim: *const coag_sim, out: *mut usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe {
        read(sim, out, |s| {
            if let Some(n) = particle_sizes_len(s) {
                return Ok(n);
            }
            let mut n = 0usize;
            s.sim.for_each_count(&mut |_, _| n += 1)?;
            Ok(n)
        })
    }
}

/// The occupied sizes of a size-count sim and their counts, ascending (`sizes` and
/// `counts` must not overlap: `COAG_INVALID_ARGUMENT`): `sizes[i]` has
/// `counts[i]` particles, for `i < *written` (= `coag_sim_occupied`); both buffers hold
/// `len` values (`COAG_BUFFER_TOO_SMALL` below the occupied count, nothing written).
/// No dense vector is built: O(occupied sizes) however large the sizes are. The volume
/// goes to `*volume` (may be NULL); `written` may be NULL.
///
/// # Safety
/// `sim` NULL or live; `sizes` and `counts` valid for `len` values; `volume` and
/// `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_get_pairs(
    sim: *const coag_sim,
    sizes: *mut u64,
    counts: *mut u64,
    len: usize,
    volume: *mut f64,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let mut n = 0usize;
        s.sim.for_each_count(&mut |_, _| n += 1)?;
        if len < n {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("pairs: buffers of {len} for {n} occupied sizes"),
            );
        }
        let (a, b) = (sizes as usize, counts as usize);
        let bytes = len.saturating_mul(8);
        if len > 0 && a < b.saturating_add(bytes) && b < a.saturating_add(bytes) {
            return fail(COAG_INVALID_ARGUMENT, "pairs: sizes and counts overlap");
        }
        // SAFETY: NULL checked; `len` writable values by contract; not overlapping.
        let out_s = unsafe { slice_mut(sizes, len, "sizes") }?;
        let out_c = unsafe { slice_mut(counts, len, "counts") }?;
        let mut i = 0;
        s.sim.for_each_count(&mut |size, c| {
            if i < len {
                out_s[i] = size;
                out_c[i] = c;
            }
            i += 1;
        })?;
        if !volume.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(volume, s.sim.volume()) };
        }
        if !written.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(written, n) };
        }
        Ok(())
    })
}

/// Copies the particle sizes of a sim over particle sizes into `buf`, which must hold
/// `coag_sim_state_len` values: sorted ascending for the time-driven mass-flow
/// scheme, in storage order for the event-driven ones.
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_get_sizes(
    sim: *const coag_sim,
    buf: *mut f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        // (a size-count sim is refused before its dense counts are built)
        let sizes = if particle_sizes_len(s).is_some() {
            Some(s.sim.state())
        } else {
            None
        };
        let Some(State::Sizes(x)) = sizes else {
            return fail(
                COAG_UNSUPPORTED,
                "sizes: this sim's state is counts of integer sizes (use coag_sim_get_counts)",
            );
        };
        if len < x.len() {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("sizes: buffer of {len} for {} particles", x.len()),
            );
        }
        // SAFETY: NULL checked; `len` writable doubles by contract.
        let out = unsafe { slice_mut(buf, len, "buf") }?;
        out[..x.len()].copy_from_slice(x);
        Ok(())
    })
}

/// Copies the counts `N_i` (`buf[i]` for size `i + 1`) of a size-count sim into `buf`
/// (at least `coag_sim_state_len` entries; extra entries are zeroed) and its volume into
/// `*volume` (may be NULL).
///
/// # Safety
/// `sim` NULL or live; `buf` valid for `len` values; `volume` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_get_counts(
    sim: *const coag_sim,
    buf: *mut u64,
    len: usize,
    volume: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; live by contract.
        let s = unsafe { handle(sim, "sim") }?;
        // the largest occupied size first (nothing allocated), then the counts straight
        // into the caller's buffer
        let mut largest = 0u64;
        if s.sim.for_each_count(&mut |size, _| largest = size).is_err() {
            return fail(
                COAG_UNSUPPORTED,
                "counts: this sim's state is particle sizes (use coag_sim_get_sizes)",
            );
        }
        if (len as u64) < largest {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("counts: buffer of {len} for sizes up to {largest}"),
            );
        }
        // SAFETY: NULL checked; `len` writable values by contract.
        let out = unsafe { slice_mut(buf, len, "buf") }?;
        out.iter_mut().for_each(|c| *c = 0);
        s.sim
            .for_each_count(&mut |size, c| out[size as usize - 1] = c)?;
        if !volume.is_null() {
            // SAFETY: non-null; writable by contract.
            unsafe { write(volume, s.sim.volume()) };
        }
        Ok(())
    })
}

/// A named observable of the sim's scheme (its `coag_scheme_observable` names: the
/// mean temperature, the kinetic energy density, the momentum of a gas, …); a name
/// the scheme does not have is `COAG_UNSUPPORTED`, a value that overflows a double
/// `COAG_CAPACITY`.
///
/// # Safety
/// `sim` NULL or live; `name` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_observable(
    sim: *const coag_sim,
    name: *const c_char,
    out: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY (both): NULL checked; valid by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let name = unsafe { text(name, "name") }?;
        non_null(out, "out")?;
        let Some(v) = s.sim.observable(name) else {
            return fail(
                COAG_UNSUPPORTED,
                format!(
                    "observable {name:?}: scheme {} has {:?}",
                    s.sim.info().name,
                    s.sim.info().observables
                ),
            );
        };
        let v = finite_result(v, || format!("observable {name}"))?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, v) };
        Ok(())
    })
}

/// A per-size quantity by name for every occupied size (`"temperature"`: the partial
/// temperatures of the temperature schemes, a gas's per-size kinetic temperature):
/// `sizes[i]` and `values[i]` for `i < *written` (= `coag_sim_occupied`), both buffers
/// of `len` (`COAG_BUFFER_TOO_SMALL` below it, nothing written; they must not
/// overlap). `COAG_UNSUPPORTED` for a scheme without it.
///
/// # Safety
/// `sim` NULL or live; `name` NUL-terminated; `sizes` and `values` valid for `len`
/// values; `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_size_values(
    sim: *const coag_sim,
    name: *const c_char,
    sizes: *mut u64,
    values: *mut f64,
    len: usize,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY (all): NULL checked; valid by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let name = unsafe { text(name, "name") }?;
        let mut n = 0usize;
        s.sim.size_values(name, &mut |_, _| n += 1)?;
        if len < n {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("size values: buffers of {len} for {n} occupied sizes"),
            );
        }
        let out_s = unsafe { slice_mut(sizes, len, "sizes") }?;
        let out_v = unsafe { slice_mut(values, len, "values") }?;
        disjoint(out_s, out_v, "sizes and values")?;
        let mut i = 0;
        s.sim.size_values(name, &mut |k, v| {
            if i < len {
                out_s[i] = k;
                out_v[i] = v;
            }
            i += 1;
        })?;
        // SAFETY: NULL or writable (contract).
        unsafe { write_opt(written, n) };
        Ok(())
    })
}

/// The particles of a gas: `sizes[p]` and `velocities[3p .. 3p + 3]` for
/// `p < n = coag_sim_particle_count` (`sizes` holds `len` values, `velocities`
/// `3 len`; `COAG_BUFFER_TOO_SMALL` below n). `COAG_UNSUPPORTED` for a scheme whose
/// particles carry no velocity.
///
/// # Safety
/// `sim` NULL or live; `sizes` valid for `len` values, `velocities` for `3 len`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_sim_velocities(
    sim: *const coag_sim,
    sizes: *mut u64,
    velocities: *mut f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY (all): NULL checked; valid by contract.
        let s = unsafe { handle(sim, "sim") }?;
        let n = usize::try_from(s.sim.particles()).unwrap_or(usize::MAX);
        s.sim.velocities(&mut |_, _| {})?;
        if len < n {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("velocities: buffers of {len} particles for {n}"),
            );
        }
        let l3 = len
            .checked_mul(3)
            .ok_or_else(|| Fail(COAG_INVALID_ARGUMENT, "3 len overflows".into()))?;
        let out_s = unsafe { slice_mut(sizes, len, "sizes") }?;
        let out_v = unsafe { slice_mut(velocities, l3, "velocities") }?;
        disjoint(out_s, out_v, "sizes and velocities")?;
        let mut p = 0;
        s.sim.velocities(&mut |k, v| {
            if p < len {
                out_s[p] = k;
                out_v[3 * p..3 * p + 3].copy_from_slice(v);
            }
            p += 1;
        })?;
        Ok(())
    })
}
