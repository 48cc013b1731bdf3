//! Memory: the default size limit and memory budget of the growing schemes, and
//! allocation that reports a refusal as [`Error::Capacity`] (the state as before),
//! never an abort.

use crate::error::{Error, Result};
use alloc::vec::Vec;

/// Largest size the size-count schemes allow by default (2^32).
pub const DEFAULT_SIZE_LIMIT: u64 = 1 << 32;

/// Memory the growing size-count schemes may use by default: 2 GiB (their per-size
/// arrays, trees and particle lists; set with `with_memory_budget`). Growth beyond it,
/// or an allocation the system refuses, is [`Error::Capacity`] with the state as
/// before the event — never an abort. (The core has no way to ask the machine; a host
/// that knows its memory sets the budget.)
pub const DEFAULT_MEMORY_BUDGET: usize = 2 << 30;

/// The default memory budget of `Options`: the
/// machine's ([`machine_memory_budget`]) with the `std` feature, else
/// [`DEFAULT_MEMORY_BUDGET`].
pub fn default_memory_budget() -> usize {
    #[cfg(feature = "std")]
    {
        machine_memory_budget()
    }
    #[cfg(not(feature = "std"))]
    {
        DEFAULT_MEMORY_BUDGET
    }
}

/// A memory budget from what this machine has: half of its physical memory (Linux:
/// `MemTotal` in `/proc/meminfo`), at least 256 MiB; [`DEFAULT_MEMORY_BUDGET`] where the
/// machine cannot say. The C ABI and the CLI use it when no budget is given. Read
/// once per process (a host that builds a simulation per grid cell would otherwise
/// read `/proc/meminfo` for each).
#[cfg(feature = "std")]
pub fn machine_memory_budget() -> usize {
    static BUDGET: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *BUDGET.get_or_init(read_machine_budget)
}

#[cfg(feature = "std")]
fn read_machine_budget() -> usize {
    let total_kib = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        m.lines()
            .find(|l| l.starts_with("MemTotal:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<u64>().ok())
    });
    match total_kib {
        Some(kib) => usize::try_from(kib.saturating_mul(1024) / 2)
            .unwrap_or(usize::MAX)
            .max(256 << 20),
        None => DEFAULT_MEMORY_BUDGET,
    }
}

/// `Err(Capacity)` unless `bytes` (None: overflowed) fits the budget.
pub(crate) fn within_budget(bytes: Option<usize>, budget: usize) -> Result<()> {
    match bytes {
        Some(b) if b <= budget => Ok(()),
        _ => Err(Error::Capacity {
            name: "memory budget in bytes (raise the option memory-budget)",
            capacity: budget,
        }),
    }
}

/// Grows `v` to `len` copies of `value` through `try_reserve` (a refused allocation is
/// `Err(Capacity)`, `v` unchanged).
pub(crate) fn try_resize<T: Clone>(v: &mut Vec<T>, len: usize, value: T) -> Result<()> {
    if len > v.len() {
        try_reserve(v, len - v.len())?;
        v.resize(len, value);
    }
    Ok(())
}

/// Gives back the spare capacity of `v` when it passes 4 times its length plus 16: `v`
/// moves to an allocation of twice its length, if one is to be had (an allocation that
/// fails leaves `v` as it was). Lists that empty out then hold O(their length), not
/// their largest length ever. Contents and order are unchanged.
pub(crate) fn shrink_spare<T: Copy>(v: &mut Vec<T>) {
    if v.capacity() > v.len().saturating_mul(4).saturating_add(16) {
        let mut w = Vec::new();
        if w.try_reserve_exact(v.len().saturating_mul(2)).is_ok() {
            w.extend_from_slice(v);
            *v = w;
        }
    }
}

/// `v.try_reserve(additional)`, a refusal mapped to `Err(Capacity)`.
pub(crate) fn try_reserve<T>(v: &mut Vec<T>, additional: usize) -> Result<()> {
    v.try_reserve(additional).map_err(|_| Error::Capacity {
        name: "memory (the allocator refused)",
        capacity: v.len().saturating_add(additional),
    })
}
