//! C ABI of low-rank DSMC (Osinsky 2023 §5, `coagula_core::scheme::lowrank::dsmc`):
//! `coag_dsmc` handles over particles with 3-D velocities, restitution and an optional
//! sticking threshold, on the low-rank engine or the acceptance–rejection baseline.

use crate::sim::{coag_step_report, handle, write_sized};
use crate::thermal::{Framed, framed_advance, framed_restore, framed_save, framed_size};
use crate::{
    COAG_BUFFER_TOO_SMALL, COAG_INVALID_ARGUMENT, Fail, fail, guard, non_null, read_config, slice,
    slice_mut, write,
};
use coagula_core::checkpoint::{Checkpoint, fingerprint};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::lowrank::dsmc::{Collisions, Gas, StickBelow};
use coagula_core::scheme::lowrank::{LowRankMc, TreeEngine, UniformEngine, WideTree};
use coagula_core::scheme::{Budget, Scheme};

/// Low-rank DSMC on per-size trees (the default).
pub const COAG_DSMC_LOWRANK: i32 = 0;
/// Acceptance–rejection on uniform pairs (the baseline).
pub const COAG_DSMC_REJECTION: i32 = 1;

/// A DSMC simulation's configuration. Fill it with `coag_dsmc_default_config`, which
/// sets `struct_size`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_dsmc_config {
    /// `sizeof(coag_dsmc_config)` as the caller compiled it.
    pub struct_size: usize,
    /// `COAG_DSMC_LOWRANK` or `COAG_DSMC_REJECTION`.
    pub engine: i32,
    /// Restitution coefficient ε ∈ (0, 1].
    pub restitution: f64,
    /// Collisions whose normal relative speed is below this aggregate (≥ 0; 0: never,
    /// the paper's test).
    pub stick_speed: f64,
    /// The random stream: the seed policy's `(seed, stream)`.
    pub seed: u64,
    /// See `seed`.
    pub stream: u64,
}

const DSMC_CONFIG_V1: usize = std::mem::size_of::<coag_dsmc_config>();

fn default_dsmc() -> coag_dsmc_config {
    coag_dsmc_config {
        struct_size: DSMC_CONFIG_V1,
        engine: COAG_DSMC_LOWRANK,
        restitution: 0.99,
        stick_speed: 0.0,
        seed: 0,
        stream: 0,
    }
}

/// Writes the default configuration (low-rank, ε = 0.99, no sticking, seed 0) into
/// `out`, a struct of `size` bytes.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_default_config(out: *mut coag_dsmc_config, size: usize) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, DSMC_CONFIG_V1, default_dsmc(), "out") }
    })
}

type Tree = TreeEngine<3, WideTree<3>>;

enum Inner {
    LowRank(LowRankMc<Gas<StickBelow>, 3, Tree, Collisions>),
    Rejection(LowRankMc<Gas<StickBelow>, 3, UniformEngine<3>, Collisions>),
}

macro_rules! with_dsmc {
    ($inner:expr, $s:ident => $body:expr) => {
        match $inner {
            Inner::LowRank($s) => $body,
            Inner::Rejection($s) => $body,
        }
    };
}

/// Opaque handle of a DSMC simulation (`coag_dsmc` in C).
pub struct coag_dsmc {
    inner: Inner,
    rng: Generator,
    print: u64,
}

fn bad(msg: impl Into<String>) -> Fail {
    Fail(COAG_INVALID_ARGUMENT, msg.into())
}

/// # Safety
/// `out` checked non-null and writable (caller contract).
unsafe fn finish(
    c: &coag_dsmc_config,
    gas: Gas<StickBelow>,
    volume: f64,
    out: *mut *mut coag_dsmc,
) -> Result<(), Fail> {
    let inner = match c.engine {
        COAG_DSMC_LOWRANK => Inner::LowRank(LowRankMc::new_gas(gas, volume)?),
        COAG_DSMC_REJECTION => Inner::Rejection(LowRankMc::new_gas(gas, volume)?),
        e => {
            return Err(bad(format!(
                "engine {e} (COAG_DSMC_LOWRANK or COAG_DSMC_REJECTION)"
            )));
        }
    };
    let h = coag_dsmc {
        inner,
        rng: generator(c.seed, c.stream),
        print: fingerprint([
            c.engine as u64,
            c.restitution.to_bits(),
            c.stick_speed.to_bits(),
        ]),
    };
    // SAFETY: the caller checked out non-null; writable (contract).
    unsafe { write(out, Box::into_raw(Box::new(h))) };
    Ok(())
}

fn sticking(c: &coag_dsmc_config) -> Result<StickBelow, Fail> {
    if !(c.stick_speed >= 0.0 && c.stick_speed.is_finite()) {
        return Err(bad(format!("stick_speed {} (finite, >= 0)", c.stick_speed)));
    }
    Ok(StickBelow {
        speed: c.stick_speed,
    })
}

/// A simulation of `n` particles of sizes `sizes[p] ≥ 1` with velocities
/// `velocities[3p .. 3p + 3]` (finite) in volume `volume`. Free with `coag_dsmc_free`.
///
/// # Safety
/// Pointers must be NULL or valid; `sizes` holds `n` values, `velocities` `3n`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_new(
    config: *const coag_dsmc_config,
    sizes: *const u64,
    velocities: *const f64,
    n: usize,
    volume: f64,
    out: *mut *mut coag_dsmc,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; valid otherwise (contract).
        let c = unsafe { read_config(config, "config", DSMC_CONFIG_V1, default_dsmc()) }?;
        non_null(out, "out")?;
        // SAFETY: forwarded contract.
        let s = unsafe { slice(sizes, n, "sizes") }?;
        let len = n.checked_mul(3).ok_or_else(|| bad("3 n overflows"))?;
        // SAFETY: forwarded contract.
        let v = unsafe { slice(velocities, len, "velocities") }?;
        let vel: Vec<[f64; 3]> = v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let gas = Gas::from_particles(c.restitution, sticking(&c)?, s, &vel)?;
        // SAFETY: out checked non-null (contract: writable).
        unsafe { finish(&c, gas, volume, out) }
    })
}

/// A simulation of `counts[i − 1]` particles of size i with Maxwellian velocities at
/// temperature `temperatures[i − 1]` (each component normal with variance `T_i / i`,
/// drawn from the configuration's stream), `len` entries each, in volume `volume`.
///
/// # Safety
/// Pointers must be NULL or valid; `counts` and `temperatures` hold `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_new_maxwellian(
    config: *const coag_dsmc_config,
    counts: *const u64,
    temperatures: *const f64,
    len: usize,
    volume: f64,
    out: *mut *mut coag_dsmc,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; valid otherwise (contract).
        let c = unsafe { read_config(config, "config", DSMC_CONFIG_V1, default_dsmc()) }?;
        non_null(out, "out")?;
        // SAFETY: forwarded contract.
        let n = unsafe { slice(counts, len, "counts") }?;
        // SAFETY: forwarded contract.
        let t = unsafe { slice(temperatures, len, "temperatures") }?;
        let total = n.iter().try_fold(0u64, |a, &b| a.checked_add(b));
        if total.is_none_or(|t| t > 1 << 32) {
            return Err(bad("more than 2^32 particles"));
        }
        // (the velocities draw from a stream of their own, so that the run's stream
        // is the configuration's as for coag_dsmc_new)
        let mut vr = generator(c.seed, c.stream ^ 0x5645_4c4f_4349_5459);
        let gas = Gas::maxwellian(c.restitution, n, t, &mut vr)?.with_sticking(sticking(&c)?);
        // SAFETY: out checked non-null (contract: writable).
        unsafe { finish(&c, gas, volume, out) }
    })
}

/// Frees a simulation (NULL is a no-op).
///
/// # Safety
/// `h` must be NULL or a live handle, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_free(h: *mut coag_dsmc) {
    if !h.is_null() {
        // SAFETY: a live handle from Box::into_raw (contract).
        drop(unsafe { Box::from_raw(h) });
    }
}

/// Advances to time `t`; `report` (may be NULL) gets the call's totals (`events`:
/// collisions, `bounces`: those that did not aggregate).
///
/// # Safety
/// `h` a live handle used by this thread alone; `report` NULL or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_advance_to(
    h: *mut coag_dsmc,
    t: f64,
    report: *mut coag_step_report,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_advance(h, t, report) }
}

/// The time, the number of particles and the volume; any out pointer may be NULL.
///
/// # Safety
/// `h` a live handle; out pointers NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_info(
    h: *const coag_dsmc,
    time: *mut f64,
    particles: *mut u64,
    volume: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        let (t, n, v) = with_dsmc!(&h.inner, s => (s.time(), s.particles(), s.volume()));
        // SAFETY: each written only when non-null (contract: writable).
        unsafe {
            if !time.is_null() {
                write(time, t);
            }
            if !particles.is_null() {
                write(particles, n);
            }
            if !volume.is_null() {
                write(volume, v);
            }
        }
        Ok(())
    })
}

/// The total momentum `Σ m V` (3 doubles), the kinetic energy density `Σ m |V|²/2 / V`
/// and the granular temperature `Σ m |V|² / (3N)`; any out pointer may be NULL.
///
/// # Safety
/// `h` a live handle; `momentum` NULL or valid for 3 doubles; others NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_observe(
    h: *const coag_dsmc,
    momentum: *mut f64,
    energy: *mut f64,
    mean_temperature: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        let (p, e, t) = with_dsmc!(&h.inner, s => (s.momentum(), s.energy(), s.mean_temperature()));
        let lm = if momentum.is_null() { 0 } else { 3 };
        // SAFETY: NULL allowed (length 0); valid for 3 doubles otherwise (contract).
        let m = unsafe { slice_mut(momentum, lm, "momentum") }?;
        m.copy_from_slice(&p[..lm]);
        // SAFETY: each written only when non-null (contract: writable).
        unsafe {
            if !energy.is_null() {
                write(energy, e);
            }
            if !mean_temperature.is_null() {
                write(mean_temperature, t);
            }
        }
        Ok(())
    })
}

/// Copies the particles, by size then in the library's order: `sizes` (`n`) and
/// `velocities` (`3n`), where `n` must be the particle count of `coag_dsmc_info`.
/// Either array may be NULL.
///
/// # Safety
/// `h` a live handle; each non-null array valid for its length.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_particles(
    h: *const coag_dsmc,
    sizes: *mut u64,
    velocities: *mut f64,
    n: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        let have = with_dsmc!(&h.inner, s => s.particles());
        if n as u64 != have {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("n {n}: the simulation has {have} particles (coag_dsmc_info)"),
            );
        }
        let ls = if sizes.is_null() { 0 } else { n };
        let lv = if velocities.is_null() { 0 } else { 3 * n };
        // SAFETY: NULL allowed (length 0); valid otherwise (contract).
        let so = unsafe { slice_mut(sizes, ls, "sizes") }?;
        // SAFETY: as above.
        let vo = unsafe { slice_mut(velocities, lv, "velocities") }?;
        let gas = with_dsmc!(&h.inner, s => s.kernel());
        let mut p = 0;
        for size in 1..=gas.counts().len() as u64 {
            for v in gas.velocities(size) {
                if !so.is_empty() {
                    so[p] = size;
                }
                if !vo.is_empty() {
                    vo[3 * p..3 * p + 3].copy_from_slice(v);
                }
                p += 1;
            }
        }
        Ok(())
    })
}

/// Bytes a checkpoint of the simulation needs now.
///
/// # Safety
/// `h` a live handle; `out` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_checkpoint_size(h: *const coag_dsmc, out: *mut usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_size(h, out) }
}

/// Saves the simulation (particles, clock, random stream) into `buf`; `written` (may
/// be NULL) gets the bytes used.
///
/// # Safety
/// `h` a live handle; `buf` valid for `len` bytes; `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_save(
    h: *const coag_dsmc,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_save(h, buf, len, written) }
}

/// Restores a checkpoint of a simulation with the same configuration (engine,
/// restitution, sticking); on error the simulation is unchanged.
///
/// # Safety
/// `h` a live handle used by this thread alone; `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_dsmc_restore(h: *mut coag_dsmc, buf: *const u8, len: usize) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_restore(h, buf, len) }
}

impl Framed for coag_dsmc {
    fn print(&self) -> u64 {
        self.print
    }
    fn stream(&self) -> &Generator {
        &self.rng
    }
    fn set_stream(&mut self, g: Generator) {
        self.rng = g;
    }
    fn scheme_len(&self) -> usize {
        with_dsmc!(&self.inner, s => s.checkpoint_len())
    }
    fn save_scheme(&self, buf: &mut [u8]) -> coagula_core::Result<usize> {
        with_dsmc!(&self.inner, s => s.save_to(buf))
    }
    fn restore_scheme(&mut self, buf: &[u8]) -> coagula_core::Result<()> {
        with_dsmc!(&mut self.inner, s => s.restore_from(buf))
    }
    fn advance(&mut self, t: f64) -> coagula_core::Result<coagula_core::scheme::StepReport> {
        let rng = &mut self.rng;
        with_dsmc!(&mut self.inner, s => s.advance_within(t, &mut Budget::unlimited(), rng))
    }
}
