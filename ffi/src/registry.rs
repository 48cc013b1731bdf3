//! Core's tables as C reads them: the registry's schemes and their capabilities, the
//! options, and the built-in kernels with their parameters. Nothing here restates a
//! rule: every answer is read from core.

use crate::status::{COAG_INVALID_ARGUMENT, Fail, fail, guard};
use crate::util::{c_strings, non_null, text, write, write_sized};
use coagula_core::kernel::builtin::{BUILTINS, Family};
use coagula_core::scheme::facade::{InitKind, KEYS, Kind, Law, Memory, ModelKind, Samples};
use coagula_core::scheme::registry::{self, SCHEMES};
use std::ffi::{CString, c_char};
use std::sync::OnceLock;

/// `coag_scheme_info.model`: a coagulation kernel (with fragmentation).
pub const COAG_MODEL_COAGULATION: i32 = 0;
/// A temperature model (Osinsky 2023 §4): counts with partial temperatures.
pub const COAG_MODEL_TEMPERATURE: i32 = 1;
/// A gas (Osinsky 2023 §5): particles with velocities.
pub const COAG_MODEL_GAS: i32 = 2;

/// `coag_scheme_info.inits` bit: counts of integer sizes (`coag_sim_new_counts`).
pub const COAG_INIT_COUNTS: u32 = 1;
/// Particle sizes (`coag_sim_new_sizes`).
pub const COAG_INIT_SIZES: u32 = 2;
/// Counts with temperatures (`coag_sim_new_temperatures`).
pub const COAG_INIT_TEMPERATURES: u32 = 4;
/// Particles with velocities (`coag_sim_new_velocities`, `coag_sim_new_maxwellian`).
pub const COAG_INIT_VELOCITIES: u32 = 8;

/// `coag_scheme_info.sizes`: the scheme takes no sizes.
pub const COAG_SAMPLES_NONE: i32 = 0;
/// Its sizes are samples of the mass distribution (mass-flow schemes).
pub const COAG_SAMPLES_MASS: i32 = 1;
/// Its sizes are samples of the number distribution (direct simulation).
pub const COAG_SAMPLES_NUMBER: i32 = 2;

/// `coag_scheme_info.memory`: fixed at construction (may run in a caller workspace).
pub const COAG_MEMORY_FIXED: i32 = 0;
/// Grows within the `memory-budget` option.
pub const COAG_MEMORY_GROWING: i32 = 1;

/// `coag_scheme_info.law`: the finite-N coagulation process itself (Marcus–Lushnikov).
pub const COAG_LAW_FINITE_N: i32 = 0;
/// A stochastic weighted (mass-flow) process (Eibeck & Wagner 2000).
pub const COAG_LAW_MASS_FLOW: i32 = 1;
/// A time-stepping scheme (an O(Δt) bias; Lécot et al. 2019).
pub const COAG_LAW_TIME_STEPPED: i32 = 2;
/// Temperature-dependent coagulation (Osinsky 2023 §4).
pub const COAG_LAW_TEMPERATURE: i32 = 3;
/// DSMC of a gas (Osinsky 2023 §5).
pub const COAG_LAW_GAS: i32 = 4;

/// A registry scheme's capabilities (`coag_scheme_info`); the strings are static.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_scheme_info {
    /// `sizeof(coag_scheme_info)` as the caller compiled it.
    pub struct_size: usize,
    /// Its registry name (what `coag_sim_new_*` takes).
    pub name: *const c_char,
    /// The paper and section it implements.
    pub paper: *const c_char,
    /// What it is, in one line.
    pub summary: *const c_char,
    /// `COAG_MODEL_*`: the physics it takes.
    pub model: i32,
    /// `COAG_INIT_*` bits: the initial states it builds from.
    pub inits: u32,
    /// `COAG_SAMPLES_*`: what its sizes are samples of.
    pub sizes: i32,
    /// Non-zero when it breaks particles (takes a fragmentation kernel).
    pub fragmentation: i32,
    /// `COAG_MEMORY_*`.
    pub memory: i32,
    /// `COAG_LAW_*`: the process it simulates.
    pub law: i32,
    /// Its checkpoint tag.
    pub tag: u64,
    /// The options that apply besides `seed` and `stream` (`coag_scheme_option`).
    pub option_count: usize,
    /// Its named observables (`coag_scheme_observable`, `coag_sim_observable`).
    pub observable_count: usize,
}

const SCHEME_INFO_V1: usize = std::mem::size_of::<coag_scheme_info>();

/// The strings handed to C, made once.
struct Strings {
    schemes: Vec<[CString; 3]>,
    options: Vec<Vec<CString>>,
    observables: Vec<Vec<CString>>,
    keys: Vec<[CString; 3]>,
    builtins: Vec<[CString; 4]>,
    params: Vec<Vec<[CString; 3]>>,
}

fn strings() -> &'static Strings {
    static S: OnceLock<Strings> = OnceLock::new();
    S.get_or_init(|| {
        let three = |a: &'static str, b: &'static str, c: &'static str| {
            let v = c_strings([a, b, c].into_iter());
            [v[0].clone(), v[1].clone(), v[2].clone()]
        };
        Strings {
            schemes: SCHEMES
                .iter()
                .map(|s| three(s.name, s.paper, s.summary))
                .collect(),
            options: SCHEMES
                .iter()
                .map(|s| c_strings(s.options.iter().copied()))
                .collect(),
            observables: SCHEMES
                .iter()
                .map(|s| c_strings(s.observables.iter().copied()))
                .collect(),
            keys: KEYS
                .iter()
                .map(|k| three(k.name, k.default, k.doc))
                .collect(),
            builtins: BUILTINS
                .iter()
                .map(|b| {
                    let v = c_strings([b.name, b.formula, b.source, b.units].into_iter());
                    [v[0].clone(), v[1].clone(), v[2].clone(), v[3].clone()]
                })
                .collect(),
            params: BUILTINS
                .iter()
                .map(|b| {
                    b.params
                        .iter()
                        .map(|p| three(p.name, p.unit, p.doc))
                        .collect()
                })
                .collect(),
        }
    })
}

/// The static C string of scheme `i`'s name.
pub(crate) fn scheme_name(i: usize) -> *const c_char {
    strings().schemes[i][0].as_ptr()
}

fn index_of(i: usize, len: usize, what: &str) -> Result<usize, Fail> {
    if i < len {
        Ok(i)
    } else {
        fail(
            COAG_INVALID_ARGUMENT,
            format!("{what} index {i}: there are {len}"),
        )
    }
}

/// The number of schemes in the registry.
///
/// # Safety
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_scheme_count(out: *mut usize) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, SCHEMES.len()) };
        Ok(())
    })
}

/// The index of the scheme named `name` (an unknown name is `COAG_INVALID_ARGUMENT`,
/// whose message lists the names).
///
/// # Safety
/// `name` NULL or NUL-terminated; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_scheme_find(name: *const c_char, out: *mut usize) -> i32 {
    guard(|| {
        // SAFETY: forwarded contract.
        let name = unsafe { text(name, "name") }?;
        non_null(out, "out")?;
        let id = registry::find(name)?;
        let i = SCHEMES.iter().position(|s| s.name == id.name).unwrap_or(0);
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, i) };
        Ok(())
    })
}

/// The capabilities of scheme `index` into a struct of `size` bytes
/// (`sizeof(coag_scheme_info)`).
///
/// # Safety
/// `out` NULL or valid for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_scheme_info_get(
    index: usize,
    out: *mut coag_scheme_info,
    size: usize,
) -> i32 {
    guard(|| {
        let i = index_of(index, SCHEMES.len(), "scheme")?;
        let s = SCHEMES[i];
        let strs = &strings().schemes[i];
        let inits = s.inits.iter().fold(0u32, |a, k| {
            a | match k {
                InitKind::Counts => COAG_INIT_COUNTS,
                InitKind::Sizes => COAG_INIT_SIZES,
                InitKind::Temperatures => COAG_INIT_TEMPERATURES,
                InitKind::Velocities => COAG_INIT_VELOCITIES,
            }
        });
        let info = coag_scheme_info {
            struct_size: SCHEME_INFO_V1,
            name: strs[0].as_ptr(),
            paper: strs[1].as_ptr(),
            summary: strs[2].as_ptr(),
            model: match s.model {
                ModelKind::Coagulation => COAG_MODEL_COAGULATION,
                ModelKind::Temperature => COAG_MODEL_TEMPERATURE,
                ModelKind::Gas => COAG_MODEL_GAS,
            },
            inits,
            sizes: match s.sizes {
                Samples::None => COAG_SAMPLES_NONE,
                Samples::Mass => COAG_SAMPLES_MASS,
                Samples::Number => COAG_SAMPLES_NUMBER,
            },
            fragmentation: i32::from(s.fragmentation),
            memory: match s.memory {
                Memory::Fixed => COAG_MEMORY_FIXED,
                Memory::Growing => COAG_MEMORY_GROWING,
            },
            law: match s.law {
                Law::FiniteN => COAG_LAW_FINITE_N,
                Law::MassFlow => COAG_LAW_MASS_FLOW,
                Law::TimeStepped => COAG_LAW_TIME_STEPPED,
                Law::Temperature => COAG_LAW_TEMPERATURE,
                Law::Gas => COAG_LAW_GAS,
            },
            tag: s.tag,
            option_count: s.options.len(),
            observable_count: s.observables.len(),
        };
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, SCHEME_INFO_V1, info, "scheme info") }
    })
}

/// The name of option `i` (< `option_count`) that applies to scheme `index`.
///
/// # Safety
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_scheme_option(
    index: usize,
    i: usize,
    out: *mut *const c_char,
) -> i32 {
    guard(|| {
        let s = index_of(index, SCHEMES.len(), "scheme")?;
        let v = &strings().options[s];
        let j = index_of(i, v.len(), "option")?;
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, v[j].as_ptr()) };
        Ok(())
    })
}

/// The name of observable `i` (< `observable_count`) of scheme `index`.
///
/// # Safety
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_scheme_observable(
    index: usize,
    i: usize,
    out: *mut *const c_char,
) -> i32 {
    guard(|| {
        let s = index_of(index, SCHEMES.len(), "scheme")?;
        let v = &strings().observables[s];
        let j = index_of(i, v.len(), "observable")?;
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, v[j].as_ptr()) };
        Ok(())
    })
}

/// `coag_option_info.kind`: a finite real (`coag_options_set_real`).
pub const COAG_OPTION_REAL: i32 = 0;
/// A non-negative integer (`coag_options_set_count`).
pub const COAG_OPTION_COUNT: i32 = 1;
/// On or off (`coag_options_set_flag`).
pub const COAG_OPTION_FLAG: i32 = 2;
/// A name (`coag_options_set_name`).
pub const COAG_OPTION_NAME: i32 = 3;

/// An option's description (`coag_option_info`); the strings are static.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_option_info {
    /// `sizeof(coag_option_info)` as the caller compiled it.
    pub struct_size: usize,
    /// Its key.
    pub name: *const c_char,
    /// `COAG_OPTION_*`.
    pub kind: i32,
    /// Non-zero when a checkpoint written under another value is refused.
    pub must_match: i32,
    /// Its default, as text.
    pub default_value: *const c_char,
    /// What it does.
    pub doc: *const c_char,
}

const OPTION_INFO_V1: usize = std::mem::size_of::<coag_option_info>();

/// The number of option keys.
///
/// # Safety
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_option_count(out: *mut usize) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, KEYS.len()) };
        Ok(())
    })
}

/// Option key `index` into a struct of `size` bytes (`sizeof(coag_option_info)`).
///
/// # Safety
/// `out` NULL or valid for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_option_info_get(
    index: usize,
    out: *mut coag_option_info,
    size: usize,
) -> i32 {
    guard(|| {
        let i = index_of(index, KEYS.len(), "option")?;
        let k = &KEYS[i];
        let s = &strings().keys[i];
        let info = coag_option_info {
            struct_size: OPTION_INFO_V1,
            name: s[0].as_ptr(),
            kind: match k.kind {
                Kind::Real => COAG_OPTION_REAL,
                Kind::Count => COAG_OPTION_COUNT,
                Kind::Flag => COAG_OPTION_FLAG,
                Kind::Name(_) => COAG_OPTION_NAME,
            },
            must_match: i32::from(k.must_match),
            default_value: s[1].as_ptr(),
            doc: s[2].as_ptr(),
        };
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, OPTION_INFO_V1, info, "option info") }
    })
}

/// `coag_builtin_info.family`: a coagulation kernel.
pub const COAG_FAMILY_COAGULATION: i32 = 0;
/// A temperature model.
pub const COAG_FAMILY_TEMPERATURE: i32 = 1;
/// A gas.
pub const COAG_FAMILY_GAS: i32 = 2;

/// A built-in kernel of core's table (`coag_builtin_info`); the strings are static.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_builtin_info {
    /// `sizeof(coag_builtin_info)` as the caller compiled it.
    pub struct_size: usize,
    /// Its name (what `coag_kernel_new` takes).
    pub name: *const c_char,
    /// `COAG_FAMILY_*`.
    pub family: i32,
    /// The formula.
    pub formula: *const c_char,
    /// Where it comes from.
    pub source: *const c_char,
    /// Units of the rate and the time ("" for dimensionless kernels).
    pub units: *const c_char,
    /// Its parameters (`coag_builtin_param`), in the order `coag_kernel_new` takes them.
    pub param_count: usize,
}

const BUILTIN_INFO_V1: usize = std::mem::size_of::<coag_builtin_info>();

/// A parameter of a built-in kernel (`coag_builtin_param`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_param_info {
    /// `sizeof(coag_param_info)` as the caller compiled it.
    pub struct_size: usize,
    /// Its name.
    pub name: *const c_char,
    /// Non-zero when it has a default (else it is required).
    pub has_default: i32,
    /// The default (NaN when required).
    pub default_value: f64,
    /// Its unit ("" for dimensionless).
    pub unit: *const c_char,
    /// What it is, with its range.
    pub doc: *const c_char,
}

const PARAM_INFO_V1: usize = std::mem::size_of::<coag_param_info>();

/// The number of built-in kernels.
///
/// # Safety
/// `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_builtin_count(out: *mut usize) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        // SAFETY: checked non-null; writable (contract).
        unsafe { write(out, BUILTINS.len()) };
        Ok(())
    })
}

/// Built-in kernel `index` into a struct of `size` bytes (`sizeof(coag_builtin_info)`).
///
/// # Safety
/// `out` NULL or valid for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_builtin_info_get(
    index: usize,
    out: *mut coag_builtin_info,
    size: usize,
) -> i32 {
    guard(|| {
        let i = index_of(index, BUILTINS.len(), "kernel")?;
        let b = &BUILTINS[i];
        let s = &strings().builtins[i];
        let info = coag_builtin_info {
            struct_size: BUILTIN_INFO_V1,
            name: s[0].as_ptr(),
            family: match b.family {
                Family::Coagulation => COAG_FAMILY_COAGULATION,
                Family::Temperature => COAG_FAMILY_TEMPERATURE,
                Family::Gas => COAG_FAMILY_GAS,
            },
            formula: s[1].as_ptr(),
            source: s[2].as_ptr(),
            units: s[3].as_ptr(),
            param_count: b.params.len(),
        };
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, BUILTIN_INFO_V1, info, "kernel info") }
    })
}

/// Parameter `param` of built-in kernel `index` into a struct of `size` bytes
/// (`sizeof(coag_param_info)`).
///
/// # Safety
/// `out` NULL or valid for `size` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_builtin_param(
    index: usize,
    param: usize,
    out: *mut coag_param_info,
    size: usize,
) -> i32 {
    guard(|| {
        let i = index_of(index, BUILTINS.len(), "kernel")?;
        let j = index_of(param, BUILTINS[i].params.len(), "parameter")?;
        let p = &BUILTINS[i].params[j];
        let s = &strings().params[i][j];
        let info = coag_param_info {
            struct_size: PARAM_INFO_V1,
            name: s[0].as_ptr(),
            has_default: i32::from(p.default.is_some()),
            default_value: p.default.unwrap_or(f64::NAN),
            unit: s[1].as_ptr(),
            doc: s[2].as_ptr(),
        };
        // SAFETY: forwarded contract.
        unsafe { write_sized(out, size, PARAM_INFO_V1, info, "parameter info") }
    })
}
