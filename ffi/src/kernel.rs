//! Kernel and fragmentation handles: the built-in kernels of core's table (by name and
//! parameters), and user kernels from C function pointers with their bound information.

use crate::status::{COAG_INVALID_ARGUMENT, COAG_UNSUPPORTED, Fail, fail, guard};
use crate::util::{non_null, slice, text, write};
use coagula_core::kernel::builtin::{self, Builtin};
use coagula_core::kernel::{
    BinaryUniform, Coagulation, CoagulationKernel, FragmentationKernel, MAX_RANK,
};
use coagula_core::scheme::facade::Model;
use std::ffi::{c_char, c_void};

/// `K(x, y)` from C.
pub type coag_rate_fn = Option<unsafe extern "C" fn(x: f64, y: f64, user_data: *mut c_void) -> f64>;
/// `h(x)` (product majorant) or `Ḟ(x)` (fragmentation rate) from C.
pub type coag_unary_fn = Option<unsafe extern "C" fn(x: f64, user_data: *mut c_void) -> f64>;
/// Low-rank factors from C: write `a_k(x)` to `a[k]` and `b_k(x)` to `b[k]`, `k < rank`.
pub type coag_factors_fn =
    Option<unsafe extern "C" fn(x: f64, a: *mut f64, b: *mut f64, user_data: *mut c_void)>;
/// `sup K(x, y)` over `lo ≤ x, y ≤ hi` from C (acceptance–rejection).
pub type coag_sup_fn =
    Option<unsafe extern "C" fn(lo: f64, hi: f64, user_data: *mut c_void) -> f64>;
/// `sup K(x, y)` over the block `x0 ≤ x ≤ x1`, `y0 ≤ y ≤ y1` from C (block majorants).
pub type coag_block_sup_fn =
    Option<unsafe extern "C" fn(x0: f64, x1: f64, y0: f64, y1: f64, user_data: *mut c_void) -> f64>;
/// `F̂_x⁻¹(u)` (size of the followed piece after a break-up of x) from C.
pub type coag_piece_fn =
    Option<unsafe extern "C" fn(x: f64, u: f64, user_data: *mut c_void) -> f64>;

/// A user coagulation kernel: the rate and whichever bounds the chosen scheme needs.
/// Unused bounds may be NULL (0 for `rank`). A bound violated at run time makes
/// `coag_sim_advance_to` fail with `COAG_INVALID_RATE`, the sim as before the event.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_user_kernel {
    /// `K(x, y) ≥ 0`, symmetric. Required.
    pub rate: coag_rate_fn,
    /// Product majorant `h(x)`, `K ≤ h(x) h(y)`, `h(x)/x` non-increasing (optional).
    pub majorant: coag_unary_fn,
    /// Rank R of the low-rank bound (0 = none, at most 8).
    pub rank: u32,
    /// Low-rank factors, `K ≤ A + Aᵀ`, `A(i, j) = Σ_k a_k(i) b_k(j)` (needed by the
    /// low-rank scheme when `rank > 0`).
    pub factors: coag_factors_fn,
    /// Non-zero when `K = A + Aᵀ` exactly (no acceptance test is then needed).
    pub low_rank_exact: i32,
    /// `sup K` on a square (needed by acceptance–rejection; optional otherwise).
    pub sup: coag_sup_fn,
    /// Passed to every callback; never dereferenced by coagula.
    pub user_data: *mut c_void,
}

// SAFETY: the struct is function pointers and the host's `user_data`, which coagula
// never dereferences; the header's contract is that a sim may be stepped on any
// thread and its callbacks are callable there (a host stepping cells on threads
// of its own relies on it). Needed because every sim of the registry is `Send`.
unsafe impl Send for coag_user_kernel {}

/// A user fragmentation kernel.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct coag_user_fragmentation {
    /// Total break-up rate `Ḟ(x) ≥ 0`. Required.
    pub rate: coag_unary_fn,
    /// Inverse of the size-biased piece distribution, `u ∈ (0, 1]`. Required.
    pub inverse_piece: coag_piece_fn,
    /// `sup Ḟ` if known, or a negative value if not. A declared supremum is checked:
    /// a rate above it stops the call with `COAG_INVALID_RATE` — so a zero-initialised
    /// struct, which declares 0 (no break-up at all), must set this field.
    pub sup_rate: f64,
    /// Passed to every callback.
    pub user_data: *mut c_void,
}

// SAFETY: as for `coag_user_kernel`.
unsafe impl Send for coag_user_fragmentation {}

/// A coagulation kernel as a sim holds it: built in, or a C callback (with what
/// `coag_kernel_set_user_blocks` added).
#[derive(Clone, Copy, Debug)]
pub enum Kernel {
    Builtin(Coagulation),
    User(coag_user_kernel, UserBlocks),
}

/// A C kernel's supremum over blocks and whether its low-rank bound is loose.
#[derive(Clone, Copy, Debug, Default)]
pub struct UserBlocks {
    sup_block: coag_block_sup_fn,
    loose: bool,
}

/// What a `coag_kernel` handle holds: a coagulation kernel, or the physics of the
/// temperature-dependent and DSMC schemes (core's built-in table).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Physics {
    Coagulation(Kernel),
    Other(Builtin),
}

/// Opaque kernel handle (`coag_kernel` in C).
#[derive(Debug)]
pub struct coag_kernel {
    pub(crate) k: Physics,
}

impl coag_kernel {
    /// The coagulation kernel (`COAG_UNSUPPORTED` for a temperature model or a gas).
    pub(crate) fn coagulation(&self) -> Result<Kernel, Fail> {
        match self.k {
            Physics::Coagulation(k) => Ok(k),
            Physics::Other(_) => fail(
                COAG_UNSUPPORTED,
                "kernel: a temperature model or a gas is not a coagulation kernel",
            ),
        }
    }

    /// The model a sim is built under, with `frag`.
    pub(crate) fn model(&self, frag: Fragmentation) -> Result<Model<Kernel, Fragmentation>, Fail> {
        Ok(match self.k {
            Physics::Coagulation(k) => Model::coagulation(k, frag),
            Physics::Other(b) => Model::of_builtin(b, Kernel::Builtin, frag)?,
        })
    }
}

impl CoagulationKernel for Kernel {
    /// A built-in kernel's parameters; for a C callback what it declares (its code is
    /// not stored).
    fn fingerprint(&self) -> u64 {
        match self {
            Kernel::Builtin(c) => c.fingerprint(),
            Kernel::User(u, b) => coagula_core::checkpoint::fingerprint([
                0x5553_4552, // "USER"
                u64::from(u.rank),
                u.low_rank_exact as u64,
                u64::from(u.majorant.is_some()),
                u64::from(u.factors.is_some()),
                u64::from(u.sup.is_some()),
                u64::from(b.sup_block.is_some()),
                u64::from(b.loose),
            ]),
        }
    }
    #[inline]
    fn rate(&self, x: f64, y: f64) -> f64 {
        match self {
            Kernel::Builtin(k) => k.rate(x, y),
            // SAFETY: validated non-null at construction; the host keeps the function
            // and its user_data valid (documented contract).
            Kernel::User(u, _) => u.rate.map_or(f64::NAN, |f| unsafe { f(x, y, u.user_data) }),
        }
    }
    fn majorant(&self, x: f64) -> Option<f64> {
        match self {
            Kernel::Builtin(k) => k.majorant(x),
            // SAFETY: as for `rate`.
            Kernel::User(u, _) => u.majorant.map(|f| unsafe { f(x, u.user_data) }),
        }
    }
    fn rank(&self) -> usize {
        match self {
            Kernel::Builtin(k) => k.rank(),
            Kernel::User(u, _) => {
                if u.factors.is_some() {
                    u.rank as usize
                } else {
                    0
                }
            }
        }
    }
    fn factors(&self, x: f64, a: &mut [f64], b: &mut [f64]) {
        match self {
            Kernel::Builtin(k) => k.factors(x, a, b),
            Kernel::User(u, _) => {
                if let Some(f) = u.factors {
                    // the callback writes `rank` values into each buffer; give it
                    // full-size scratch so a sloppy callback cannot overrun
                    let (mut sa, mut sb) = ([f64::NAN; MAX_RANK], [f64::NAN; MAX_RANK]);
                    // SAFETY: scratch buffers of MAX_RANK ≥ rank elements; contract as
                    // for `rate`.
                    unsafe { f(x, sa.as_mut_ptr(), sb.as_mut_ptr(), u.user_data) };
                    let r = a.len().min(b.len());
                    a[..r].copy_from_slice(&sa[..r]);
                    b[..r].copy_from_slice(&sb[..r]);
                }
            }
        }
    }
    fn low_rank_is_exact(&self) -> bool {
        match self {
            Kernel::Builtin(k) => k.low_rank_is_exact(),
            Kernel::User(u, _) => u.low_rank_exact != 0,
        }
    }
    fn low_rank_floor(&self) -> f64 {
        match self {
            Kernel::Builtin(k) => k.low_rank_floor(),
            Kernel::User(u, _) => f64::from(u8::from(u.low_rank_exact != 0)),
        }
    }
    fn sup_rate(&self, lo: f64, hi: f64) -> Option<f64> {
        match self {
            Kernel::Builtin(k) => k.sup_rate(lo, hi),
            // SAFETY: as for `rate`.
            Kernel::User(u, _) => u.sup.map(|f| unsafe { f(lo, hi, u.user_data) }),
        }
    }
    fn sup_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> Option<f64> {
        match self {
            Kernel::Builtin(k) => k.sup_block(x0, x1, y0, y1),
            // SAFETY: as for `rate`.
            Kernel::User(u, b) => match b.sup_block {
                Some(f) => Some(unsafe { f(x0, x1, y0, y1, u.user_data) }),
                // the supremum over the square around the block
                None => self.sup_rate(x0.min(y0), x1.max(y1)),
            },
        }
    }
    fn inf_block(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        match self {
            Kernel::Builtin(k) => k.inf_block(x0, x1, y0, y1),
            // (no squeeze for a user kernel: it changes the cost, never the draws)
            Kernel::User(..) => 0.0,
        }
    }
    fn low_rank_is_loose(&self) -> bool {
        match self {
            Kernel::Builtin(k) => k.low_rank_is_loose(),
            Kernel::User(_, b) => b.loose,
        }
    }
    fn log_linear_blocks(&self) -> bool {
        match self {
            Kernel::Builtin(k) => k.log_linear_blocks(),
            Kernel::User(..) => false,
        }
    }
    fn integer_sizes(&self) -> bool {
        match self {
            Kernel::Builtin(k) => k.integer_sizes(),
            Kernel::User(..) => false,
        }
    }
    fn min_size(&self) -> f64 {
        match self {
            Kernel::Builtin(k) => k.min_size(),
            Kernel::User(..) => 0.0,
        }
    }
    /// A built-in kernel's claim passes on (its buckets are bounded from their two
    /// ends); a C callback's factors are evaluated at every size.
    fn monotone_factors(&self) -> bool {
        match self {
            Kernel::Builtin(k) => k.monotone_factors(),
            Kernel::User(..) => false,
        }
    }
}

/// What a `coag_fragmentation` handle holds.
#[derive(Clone, Copy, Debug)]
pub enum Fragmentation {
    None,
    Binary(BinaryUniform),
    User(coag_user_fragmentation),
}

impl Fragmentation {
    /// The kernel of a handle that may be NULL (none).
    ///
    /// # Safety
    /// `frag` NULL or live.
    pub(crate) unsafe fn of(frag: *const coag_fragmentation) -> Result<Fragmentation, Fail> {
        if frag.is_null() {
            return Ok(Fragmentation::None);
        }
        // SAFETY: non-null; live by contract.
        Ok(unsafe { crate::util::handle(frag, "frag") }?.f)
    }
}

/// Opaque fragmentation handle (`coag_fragmentation` in C).
#[derive(Debug)]
pub struct coag_fragmentation {
    pub(crate) f: Fragmentation,
}

impl FragmentationKernel for Fragmentation {
    fn total_rate(&self, x: f64) -> f64 {
        match self {
            Fragmentation::None => 0.0,
            Fragmentation::Binary(b) => b.total_rate(x),
            // SAFETY: validated non-null at construction; host keeps them valid.
            Fragmentation::User(u) => u.rate.map_or(f64::NAN, |f| unsafe { f(x, u.user_data) }),
        }
    }
    fn inverse_piece(&self, x: f64, u: f64) -> f64 {
        match self {
            Fragmentation::None => x,
            Fragmentation::Binary(b) => b.inverse_piece(x, u),
            // SAFETY: as above.
            Fragmentation::User(d) => d
                .inverse_piece
                .map_or(f64::NAN, |f| unsafe { f(x, u, d.user_data) }),
        }
    }
    fn sup_rate(&self) -> Option<f64> {
        match self {
            Fragmentation::None => Some(0.0),
            Fragmentation::Binary(b) => b.sup_rate(),
            Fragmentation::User(u) => (u.sup_rate >= 0.0).then_some(u.sup_rate),
        }
    }
    fn is_none(&self) -> bool {
        matches!(self, Fragmentation::None)
    }
    fn fingerprint(&self) -> u64 {
        match self {
            Fragmentation::None => 0,
            Fragmentation::Binary(b) => b.fingerprint(),
            Fragmentation::User(u) => {
                coagula_core::checkpoint::fingerprint([2, u.sup_rate.to_bits()])
            }
        }
    }
}

/// # Safety
/// `out` checked non-null and writable (the C caller's contract).
unsafe fn new_kernel(k: Physics, out: *mut *mut coag_kernel) -> Result<(), Fail> {
    // SAFETY: the function's contract.
    unsafe { write(out, Box::into_raw(Box::new(coag_kernel { k }))) };
    Ok(())
}

/// A built-in kernel of core's table by name (`coag_builtin_count`/`coag_builtin_info`
/// list them: coagulation kernels, the temperature models and the hard-sphere gas) with
/// `n` parameters in the table's order (`coag_builtin_param`); parameters past `n` take
/// their defaults (`params` may be NULL with `n` 0). The kernel convention is that of
/// the Smoluchowski equation with the ½ of the gain term: each unordered pair of
/// particles in a volume V coagulates at rate `K/V`. Errors: an unknown name, a
/// required parameter missing, a value outside its range (`COAG_INVALID_ARGUMENT`).
///
/// # Safety
/// `name` NULL or NUL-terminated; `params` NULL or valid for `n` doubles; `out` NULL or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_kernel_new(
    name: *const c_char,
    params: *const f64,
    n: usize,
    out: *mut *mut coag_kernel,
) -> i32 {
    guard(|| {
        // SAFETY (both): NULL checked; valid by contract.
        let name = unsafe { text(name, "name") }?;
        let p = unsafe { slice(params, n, "params") }?;
        non_null(out, "out")?;
        let k = match builtin::make_positional(name, p)? {
            Builtin::Coagulation(c) => Physics::Coagulation(Kernel::Builtin(c)),
            b => Physics::Other(b),
        };
        // SAFETY: `out` checked non-null above; writable (caller contract).
        unsafe { new_kernel(k, out) }
    })
}

/// A user kernel from C callbacks (see `coag_user_kernel`). Errors: `rate` NULL,
/// `rank` above 8, `rank > 0` without `factors`.
///
/// # Safety
/// `desc` and `out` must be NULL or valid; the callbacks and `user_data` must stay
/// valid while any handle made from this kernel is alive.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_kernel_new_user(
    desc: *const coag_user_kernel,
    out: *mut *mut coag_kernel,
) -> i32 {
    guard(|| {
        non_null(desc, "desc")?;
        non_null(out, "out")?;
        // SAFETY: checked non-null; the caller guarantees it points to a descriptor.
        let d = unsafe { *desc };
        if d.rate.is_none() {
            return fail(COAG_INVALID_ARGUMENT, "user kernel: rate is NULL");
        }
        if d.rank as usize > MAX_RANK || (d.rank > 0 && d.factors.is_none()) {
            return fail(
                COAG_INVALID_ARGUMENT,
                "user kernel: rank above 8, or rank > 0 without factors",
            );
        }
        // SAFETY: `out` checked non-null above; writable (caller contract).
        unsafe {
            new_kernel(
                Physics::Coagulation(Kernel::User(d, UserBlocks::default())),
                out,
            )
        }
    })
}

/// Gives a user kernel (`coag_kernel_new_user`) its supremum over blocks of sizes, for
/// block majorants (`lowrank-blocks`, and `lowrank` when it picks them:
/// docs/design/block-majorants.md), and says whether its low-rank bound is loose
/// (non-zero `low_rank_loose`: `lowrank` then picks block majorants when `sup_block` is
/// given). `sup_block(x0, x1, y0, y1)` must bound `K(x, y)` over `x0 ≤ x ≤ x1`,
/// `y0 ≤ y ≤ y1`; a bound the kernel passes at run time makes `coag_sim_advance_to`
/// fail with `COAG_INVALID_RATE`. NULL `sup_block` restores the default (the `sup`
/// callback on the square around a block). Sims built from the handle before the call
/// keep what they had. Errors: a NULL handle (`COAG_INVALID_ARGUMENT`), a handle that
/// is not a user kernel (`COAG_UNSUPPORTED`); the handle is then unchanged.
///
/// # Safety
/// `kernel` must be NULL or a live handle not used by another thread meanwhile;
/// `sup_block` must stay valid while any sim made from the kernel is alive.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_kernel_set_user_blocks(
    kernel: *mut coag_kernel,
    sup_block: coag_block_sup_fn,
    low_rank_loose: i32,
) -> i32 {
    guard(|| {
        non_null(kernel, "kernel")?;
        // SAFETY: checked non-null; a live handle by contract, not shared meanwhile.
        let k = unsafe { &mut *kernel };
        match &mut k.k {
            Physics::Coagulation(Kernel::User(_, b)) => {
                *b = UserBlocks {
                    sup_block,
                    loose: low_rank_loose != 0,
                };
                Ok(())
            }
            _ => fail(
                COAG_UNSUPPORTED,
                "kernel: only a user kernel (coag_kernel_new_user) takes a block supremum",
            ),
        }
    })
}

/// Evaluates `K(x, y)` of a coagulation kernel handle (`COAG_UNSUPPORTED` for a
/// temperature model or a gas, whose rates depend on more than two sizes).
///
/// # Safety
/// `kernel` must be NULL or a live handle; `out` NULL or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_kernel_rate(
    kernel: *const coag_kernel,
    x: f64,
    y: f64,
    out: *mut f64,
) -> i32 {
    guard(|| {
        // SAFETY: NULL checked; a live handle by contract.
        let k = unsafe { crate::util::handle(kernel, "kernel") }?.coagulation()?;
        non_null(out, "out")?;
        let v = coagula_core::kernel::checked_rate(&k, x, y)?;
        // SAFETY: checked non-null; writable by the caller's contract.
        unsafe { write(out, v) };
        Ok(())
    })
}

/// Releases a kernel handle (NULL is a no-op).
///
/// # Safety
/// `kernel` must be NULL or a handle from `coag_kernel_new_*` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_kernel_free(kernel: *mut coag_kernel) {
    if !kernel.is_null() {
        // SAFETY: created by Box::into_raw in new_kernel, freed once (caller contract).
        drop(unsafe { Box::from_raw(kernel) });
    }
}

/// # Safety
/// `out` checked non-null and writable (the C caller's contract).
unsafe fn new_frag(f: Fragmentation, out: *mut *mut coag_fragmentation) -> Result<(), Fail> {
    // SAFETY: the function's contract.
    unsafe { write(out, Box::into_raw(Box::new(coag_fragmentation { f }))) };
    Ok(())
}

/// Binary break-up into two uniform pieces at rate `lambda` per particle:
/// `F(x, y) = 2 lambda / (x + y)` (Lécot et al. §4 with lambda = 1).
///
/// # Safety
/// `out` must be NULL or valid for writing one pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_fragmentation_new_binary_uniform(
    lambda: f64,
    out: *mut *mut coag_fragmentation,
) -> i32 {
    guard(|| {
        non_null(out, "out")?;
        // SAFETY: `out` checked non-null above; writable (caller contract).
        unsafe { new_frag(Fragmentation::Binary(BinaryUniform::new(lambda)?), out) }
    })
}

/// A user fragmentation kernel from C callbacks (`rate` and `inverse_piece` required).
///
/// # Safety
/// As for `coag_kernel_new_user`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_fragmentation_new_user(
    desc: *const coag_user_fragmentation,
    out: *mut *mut coag_fragmentation,
) -> i32 {
    guard(|| {
        non_null(desc, "desc")?;
        non_null(out, "out")?;
        // SAFETY: checked non-null; the caller guarantees a valid descriptor.
        let d = unsafe { *desc };
        if d.rate.is_none() || d.inverse_piece.is_none() {
            return fail(
                COAG_INVALID_ARGUMENT,
                "user fragmentation: rate or inverse_piece is NULL",
            );
        }
        if d.sup_rate.is_nan() {
            return fail(COAG_INVALID_ARGUMENT, "user fragmentation: sup_rate is NaN");
        }
        // SAFETY: `out` checked non-null above; writable (caller contract).
        unsafe { new_frag(Fragmentation::User(d), out) }
    })
}

/// Releases a fragmentation handle (NULL is a no-op).
///
/// # Safety
/// `frag` must be NULL or a handle from `coag_fragmentation_new_*` not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn coag_fragmentation_free(frag: *mut coag_fragmentation) {
    if !frag.is_null() {
        // SAFETY: created by Box::into_raw in new_frag, freed once (caller contract).
        drop(unsafe { Box::from_raw(frag) });
    }
}
