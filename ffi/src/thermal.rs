//! C ABI of the temperature-dependent low-rank Monte Carlo (Osinsky 2023 §4,
//! `coagula_core::scheme::lowrank::thermal`): `coag_thermal` handles over the paper's
//! ballistic kernels or the model family with a closed form, on the low-rank engine or
//! the acceptance–rejection baseline.

use crate::sim::coag_step_report;
use crate::sim::{handle, handle_mut, write_report, write_sized};
use crate::{
    COAG_BUFFER_TOO_SMALL, COAG_INVALID_ARGUMENT, Fail, fail, guard, non_null, read_config, slice,
    slice_mut, write,
};
use coagula_core::checkpoint::{Checkpoint, fingerprint};
use coagula_core::kernel::temperature::{Ballistic, ClosedForm, PairRates, TemperatureKernel};
use coagula_core::random::{Generator, generator};
use coagula_core::scheme::lowrank::{TemperatureMc, TemperatureRejection, Temperatures};
use coagula_core::scheme::{Budget, Scheme};

/// The paper's ballistic kernels (restitution ε, barrier a, exponent λ).
pub const COAG_THERMAL_BALLISTIC: i32 = 0;
/// The model family with a closed form (constants c, γ; `coag_thermal_model_exact`).
pub const COAG_THERMAL_MODEL: i32 = 1;

/// Low-rank Monte Carlo on per-size trees (the default).
pub const COAG_THERMAL_LOWRANK: i32 = 0;
/// Acceptance–rejection on uniform pairs (the baseline).
pub const COAG_THERMAL_REJECTION: i32 = 1;

/// A temperature-dependent simulation's configuration. Fill it with
/// `coag_thermal_default_config`, which sets `struct_size`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_thermal_config {
    /// `sizeof(coag_thermal_config)` as the caller compiled it.
    pub struct_size: usize,
    /// `COAG_THERMAL_BALLISTIC` or `COAG_THERMAL_MODEL`.
    pub kernel: i32,
    /// `COAG_THERMAL_LOWRANK` or `COAG_THERMAL_REJECTION`.
    pub engine: i32,
    /// Ballistic: restitution coefficient ε ∈ (0, 1].
    pub restitution: f64,
    /// Ballistic: aggregation barrier a ≥ 0.
    pub barrier: f64,
    /// Ballistic: barrier exponent λ (finite).
    pub barrier_exponent: f64,
    /// ClosedForm: the constant c > 0.
    pub model_c: f64,
    /// ClosedForm: the exponent γ ≥ 0.
    pub model_gamma: f64,
    /// Largest particle size allowed (0: the library's default).
    pub size_limit: u64,
    /// The random stream: the seed policy's `(seed, stream)`.
    pub seed: u64,
    /// See `seed`.
    pub stream: u64,
}

const THERMAL_CONFIG_V1: usize = std::mem::size_of::<coag_thermal_config>();

fn default_thermal() -> coag_thermal_config {
    coag_thermal_config {
        struct_size: THERMAL_CONFIG_V1,
        kernel: COAG_THERMAL_BALLISTIC,
        engine: COAG_THERMAL_LOWRANK,
        restitution: 0.99,
        barrier: 0.1,
        barrier_exponent: 0.4,
        model_c: 1.0,
        model_gamma: 0.0,
        size_limit: 0,
        seed: 0,
        stream: 0,
    }
}

/// Writes the default configuration (the paper's ballistic kernels ε = 0.99, a = 0.1,
/// λ = 0.4, the low-rank engine, seed 0) into `out`, a struct of `size` bytes.
///
/// # Safety
/// `out` must be NULL or valid for writing `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_default_config(
    out: *mut coag_thermal_config,
    size: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, THERMAL_CONFIG_V1, default_thermal(), "out") }
    })
}

/// The kernels a C caller can choose.
#[derive(Clone, Copy, Debug)]
enum Kernels {
    Ballistic(Ballistic),
    ClosedForm(ClosedForm),
}

impl TemperatureKernel for Kernels {
    fn rates(&self, i: u64, ti: f64, j: u64, tj: f64) -> PairRates {
        match self {
            Kernels::Ballistic(k) => k.rates(i, ti, j, tj),
            Kernels::ClosedForm(k) => k.rates(i, ti, j, tj),
        }
    }
    fn collision(&self, i: u64, ti: f64, j: u64, tj: f64) -> f64 {
        match self {
            Kernels::Ballistic(k) => k.collision(i, ti, j, tj),
            Kernels::ClosedForm(k) => k.collision(i, ti, j, tj),
        }
    }
    fn factors(&self, i: u64, t: f64, a: &mut [f64; 3], b: &mut [f64; 3]) {
        match self {
            Kernels::Ballistic(k) => k.factors(i, t, a, b),
            Kernels::ClosedForm(k) => k.factors(i, t, a, b),
        }
    }
}

enum Inner {
    LowRank(TemperatureMc<Kernels>),
    Rejection(TemperatureRejection<Kernels>),
}

/// Runs `$body` with `$s` bound to the scheme of either engine.
macro_rules! with_scheme {
    ($inner:expr, $s:ident => $body:expr) => {
        match $inner {
            Inner::LowRank($s) => $body,
            Inner::Rejection($s) => $body,
        }
    };
}

/// Opaque handle of a temperature-dependent simulation (`coag_thermal` in C).
pub struct coag_thermal {
    inner: Inner,
    rng: Generator,
    /// A fingerprint of the configuration (kernel, its parameters, engine) that a
    /// checkpoint must match.
    print: u64,
}

fn bad(msg: impl Into<String>) -> Fail {
    Fail(COAG_INVALID_ARGUMENT, msg.into())
}

fn kernels(c: &coag_thermal_config) -> Result<Kernels, Fail> {
    Ok(match c.kernel {
        COAG_THERMAL_BALLISTIC => Kernels::Ballistic(Ballistic::new(
            c.restitution,
            c.barrier,
            c.barrier_exponent,
        )?),
        COAG_THERMAL_MODEL => Kernels::ClosedForm(ClosedForm::new(c.model_c, c.model_gamma)?),
        k => {
            return Err(bad(format!(
                "kernel {k} (COAG_THERMAL_BALLISTIC or COAG_THERMAL_MODEL)"
            )));
        }
    })
}

/// A simulation from `counts[i − 1] = N_i` particles of size i at partial temperatures
/// `temperatures[i − 1] = T_i` (finite, ≥ 0), `len` entries each, in volume `volume`
/// (number densities `N_i / V`). Free with `coag_thermal_free`.
///
/// # Safety
/// Pointers must be NULL or valid; `counts` and `temperatures` hold `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_new(
    config: *const coag_thermal_config,
    counts: *const u64,
    temperatures: *const f64,
    len: usize,
    volume: f64,
    out: *mut *mut coag_thermal,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; valid otherwise (contract).
        let c = unsafe { read_config(config, "config", THERMAL_CONFIG_V1, default_thermal()) }?;
        non_null(out, "out")?;
        // SAFETY: forwarded contract.
        let n = unsafe { slice(counts, len, "counts") }?;
        // SAFETY: forwarded contract.
        let t = unsafe { slice(temperatures, len, "temperatures") }?;
        if len == 0 {
            return Err(bad("len is 0: no particles"));
        }
        let k = kernels(&c)?;
        let thermal = Temperatures::new(k, t)?;
        let limit = |s: u64| if c.size_limit == 0 { s } else { c.size_limit };
        if c.size_limit != 0 && (len as u64) > c.size_limit {
            return Err(bad(format!(
                "len {len} exceeds size_limit {}",
                c.size_limit
            )));
        }
        let inner = match c.engine {
            COAG_THERMAL_LOWRANK => {
                let s = TemperatureMc::new(thermal, n, volume)?;
                let l = limit(s_limit(&s));
                Inner::LowRank(s.with_size_limit(l))
            }
            COAG_THERMAL_REJECTION => {
                let s = TemperatureRejection::new(thermal, n, volume)?;
                let l = limit(s_limit(&s));
                Inner::Rejection(s.with_size_limit(l))
            }
            e => {
                return Err(bad(format!(
                    "engine {e} (COAG_THERMAL_LOWRANK or COAG_THERMAL_REJECTION)"
                )));
            }
        };
        let print = fingerprint([
            c.kernel as u64,
            c.engine as u64,
            c.restitution.to_bits(),
            c.barrier.to_bits(),
            c.barrier_exponent.to_bits(),
            c.model_c.to_bits(),
            c.model_gamma.to_bits(),
        ]);
        let h = coag_thermal {
            inner,
            rng: generator(c.seed, c.stream),
            print,
        };
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, Box::into_raw(Box::new(h))) };
        Ok(())
    })
}

/// The library's default size limit (what a scheme starts with).
fn s_limit<S>(_s: &S) -> u64 {
    coagula_core::scheme::lowrank::DEFAULT_SIZE_LIMIT
}

/// Frees a simulation (NULL is a no-op).
///
/// # Safety
/// `h` must be NULL or a live handle, not used afterwards.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_free(h: *mut coag_thermal) {
    if !h.is_null() {
        // SAFETY: a live handle from Box::into_raw (contract).
        drop(unsafe { Box::from_raw(h) });
    }
}

/// Advances to time `t`; `report` (may be NULL) gets the call's totals (`events`
/// counts collisions, `bounces` those that bounced). On error (a capacity, a kernel
/// rate that is not finite) the simulation is as before the failing event.
///
/// # Safety
/// `h` a live handle used by this thread alone; `report` NULL or valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_advance_to(
    h: *mut coag_thermal,
    t: f64,
    report: *mut coag_step_report,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_advance(h, t, report) }
}

/// The time, the number of simulation particles, the volume and the largest size the
/// state arrays cover (`coag_thermal_state`'s `len`); any out pointer may be NULL.
///
/// # Safety
/// `h` a live handle; out pointers NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_info(
    h: *const coag_thermal,
    time: *mut f64,
    particles: *mut u64,
    volume: *mut f64,
    max_size: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        let (t, n, v, m) =
            with_scheme!(&h.inner, s => (s.time(), s.particles(), s.volume(), s.max_size()));
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
            if !max_size.is_null() {
                write(max_size, m);
            }
        }
        Ok(())
    })
}

/// The moment `Σ i^m N_i / V` (`m` finite), the mean temperature `Σ N_i T_i / N` and
/// the energy density `Σ N_i T_i / V`; any out pointer may be NULL.
///
/// # Safety
/// `h` a live handle; out pointers NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_observe(
    h: *const coag_thermal,
    m: f64,
    moment: *mut f64,
    mean_temperature: *mut f64,
    energy: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        if !m.is_finite() {
            return Err(bad(format!("moment order {m} (finite)")));
        }
        let (mo, mt, e) =
            with_scheme!(&h.inner, s => (s.moment(m), s.mean_temperature(), s.energy()));
        // SAFETY: each written only when non-null (contract: writable).
        unsafe {
            if !moment.is_null() {
                write(moment, mo);
            }
            if !mean_temperature.is_null() {
                write(mean_temperature, mt);
            }
            if !energy.is_null() {
                write(energy, e);
            }
        }
        Ok(())
    })
}

/// Copies the state: `counts[i − 1] = N_i` and `temperatures[i − 1] = T_i` for
/// `i = 1..=len`, where `len` must be the `max_size` of `coag_thermal_info`. Either
/// array may be NULL.
///
/// # Safety
/// `h` a live handle; each non-null array valid for `len` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_state(
    h: *const coag_thermal,
    counts: *mut u64,
    temperatures: *mut f64,
    len: usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        let m = with_scheme!(&h.inner, s => s.max_size());
        if len != m {
            return fail(
                COAG_BUFFER_TOO_SMALL,
                format!("len {len}: the state covers sizes 1..={m} (coag_thermal_info)"),
            );
        }
        let lc = if counts.is_null() { 0 } else { len };
        let lt = if temperatures.is_null() { 0 } else { len };
        // SAFETY: NULL allowed (length 0 then); valid otherwise (contract).
        let cs = unsafe { slice_mut(counts, lc, "counts") }?;
        // SAFETY: as above.
        let ts = unsafe { slice_mut(temperatures, lt, "temperatures") }?;
        with_scheme!(&h.inner, s => {
            let c = s.counts();
            for (o, v) in cs.iter_mut().zip(c.iter()) {
                *o = *v;
            }
            for (i, o) in ts.iter_mut().enumerate() {
                *o = s.temperature(i as u64 + 1);
            }
        });
        Ok(())
    })
}

/// Bytes before the scheme's checkpoint: the configuration's fingerprint and the
/// random stream's state.
pub(crate) const HEAD: usize = 8 + 32;

/// A handle whose checkpoint is framed: a fingerprint of its configuration and its
/// random stream, then the scheme's own checkpoint.
pub(crate) trait Framed {
    /// The configuration's fingerprint.
    fn print(&self) -> u64;
    /// The handle's stream.
    fn stream(&self) -> &Generator;
    /// Replaces the handle's stream.
    fn set_stream(&mut self, g: Generator);
    /// The scheme's checkpoint length.
    fn scheme_len(&self) -> usize;
    /// Saves the scheme into `buf`.
    fn save_scheme(&self, buf: &mut [u8]) -> coagula_core::Result<usize>;
    /// Restores the scheme from `buf` (unchanged on error).
    fn restore_scheme(&mut self, buf: &[u8]) -> coagula_core::Result<()>;
    /// Advances the scheme to `t` on the handle's stream.
    fn advance(&mut self, t: f64) -> coagula_core::Result<coagula_core::scheme::StepReport>;
}

/// `coag_*_advance_to` of a framed handle: `report` (may be NULL) is validated before
/// the run and gets its totals.
///
/// # Safety
/// `h` NULL or a live handle used by this thread alone; `report` NULL or valid.
pub(crate) unsafe fn framed_advance<H: Framed>(
    h: *mut H,
    t: f64,
    report: *mut coag_step_report,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle_mut(h, "h") }?;
        if !report.is_null() {
            // SAFETY: non-null; valid (contract).
            unsafe { write_report(report, Default::default()) }?;
        }
        let rep = h.advance(t)?;
        if !report.is_null() {
            // SAFETY: as above.
            unsafe { write_report(report, rep) }?;
        }
        Ok(())
    })
}

/// `coag_*_checkpoint_size` of a framed handle.
///
/// # Safety
/// `h` NULL or a live handle; `out` NULL or writable.
pub(crate) unsafe fn framed_size<H: Framed>(h: *const H, out: *mut usize) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, h.scheme_len() + HEAD) };
        Ok(())
    })
}

/// `coag_*_save` of a framed handle.
///
/// # Safety
/// `h` NULL or a live handle; `buf` valid for `len` bytes; `written` NULL or writable.
pub(crate) unsafe fn framed_save<H: Framed>(
    h: *const H,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle(h, "h") }?;
        // SAFETY: as above.
        let b = unsafe { slice_mut(buf, len, "buf") }?;
        if b.len() < HEAD {
            return fail(COAG_BUFFER_TOO_SMALL, format!("buf of {len} bytes"));
        }
        let (front, rest) = b.split_at_mut(HEAD);
        let n = h.save_scheme(rest)?;
        front[..8].copy_from_slice(&h.print().to_le_bytes());
        for (k, w) in h.stream().parts().iter().enumerate() {
            front[8 + 8 * k..16 + 8 * k].copy_from_slice(&w.to_le_bytes());
        }
        if !written.is_null() {
            // SAFETY: non-null; writable (contract).
            unsafe { write(written, HEAD + n) };
        }
        Ok(())
    })
}

/// `coag_*_restore` of a framed handle: the fingerprint must match; on error the
/// handle is unchanged.
///
/// # Safety
/// `h` NULL or a live handle used by this thread alone; `buf` valid for `len` bytes.
pub(crate) unsafe fn framed_restore<H: Framed>(h: *mut H, buf: *const u8, len: usize) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let h = unsafe { handle_mut(h, "h") }?;
        // SAFETY: as above.
        let b = unsafe { slice(buf, len, "buf") }?;
        if b.len() < HEAD {
            return fail(crate::COAG_BAD_CHECKPOINT, "checkpoint too short");
        }
        let word = |i: usize| {
            let mut w = [0u8; 8];
            w.copy_from_slice(&b[8 * i..8 * i + 8]);
            u64::from_le_bytes(w)
        };
        if word(0) != h.print() {
            return fail(
                crate::COAG_BAD_CHECKPOINT,
                "checkpoint of another configuration (kernel, parameters or engine)",
            );
        }
        let rng = Generator::from_parts([word(1), word(2), word(3), word(4)]).ok_or_else(|| {
            Fail(
                crate::COAG_BAD_CHECKPOINT,
                "invalid random stream state".into(),
            )
        })?;
        h.restore_scheme(&b[HEAD..])?;
        h.set_stream(rng);
        Ok(())
    })
}

impl Framed for coag_thermal {
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
        with_scheme!(&self.inner, s => s.checkpoint_len())
    }
    fn save_scheme(&self, buf: &mut [u8]) -> coagula_core::Result<usize> {
        with_scheme!(&self.inner, s => s.save_to(buf))
    }
    fn restore_scheme(&mut self, buf: &[u8]) -> coagula_core::Result<()> {
        with_scheme!(&mut self.inner, s => s.restore_from(buf))
    }
    fn advance(&mut self, t: f64) -> coagula_core::Result<coagula_core::scheme::StepReport> {
        let rng = &mut self.rng;
        with_scheme!(&mut self.inner, s => s.advance_within(t, &mut Budget::unlimited(), rng))
    }
}

/// Bytes a checkpoint of the simulation needs now.
///
/// # Safety
/// `h` a live handle; `out` writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_checkpoint_size(
    h: *const coag_thermal,
    out: *mut usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_size(h, out) }
}

/// Saves the simulation (state, temperatures, clock, random stream) into `buf`;
/// `written` (may be NULL) gets the bytes used.
///
/// # Safety
/// `h` a live handle; `buf` valid for `len` bytes; `written` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_save(
    h: *const coag_thermal,
    buf: *mut u8,
    len: usize,
    written: *mut usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_save(h, buf, len, written) }
}

/// Restores a checkpoint of a simulation with the same configuration (kernel, its
/// parameters, engine); on error the simulation is unchanged.
///
/// # Safety
/// `h` a live handle used by this thread alone; `buf` valid for `len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_restore(
    h: *mut coag_thermal,
    buf: *const u8,
    len: usize,
) -> i32 {
    // SAFETY: forwarded contract.
    unsafe { framed_restore(h, buf, len) }
}

/// The model family's closed form from `n_1(0) = n0`, `T_1(0) = t0` (c > 0, γ ≥ 0):
/// the number density `N(t)` and the mean temperature at time `t ≥ 0`.
///
/// # Safety
/// Out pointers writable (either may be NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_thermal_model_exact(
    c: f64,
    gamma: f64,
    n0: f64,
    t0: f64,
    t: f64,
    number: *mut f64,
    mean_temperature: *mut f64,
) -> i32 {
    guard(|| {
        let m = ClosedForm::new(c, gamma)?;
        for (name, v) in [("n0", n0), ("t0", t0), ("t", t)] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(bad(format!("{name} = {v} (finite, >= 0)")));
            }
        }
        let e = m.exact(n0, t0, t);
        // SAFETY: each written only when non-null (contract: writable).
        unsafe {
            if !number.is_null() {
                write(number, e.number());
            }
            if !mean_temperature.is_null() {
                write(mean_temperature, e.mean_temperature());
            }
        }
        Ok(())
    })
}
