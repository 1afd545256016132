//! Cache hints for the batched lookups: a prefetch of the line holding an address, so that the
//! independent cache misses of a block of rays overlap instead of adding up.

/// A prefetch hint for the cache line holding `ptr` (x86-64 `prefetcht0`; nothing elsewhere). A
/// prefetch never faults, so any address is allowed, and it has no effect on results.
#[inline(always)]
pub(crate) fn prefetch_line(ptr: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `prefetcht0` only hints the cache; it never faults or reads into registers, so it
    // is sound for any address (SSE is part of the x86-64 baseline).
    #[allow(unused_unsafe)]
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(ptr.cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = ptr;
}

/// [`prefetch_line`] of every line that `value` occupies (at most two for a value of up to 64
/// bytes).
#[inline(always)]
pub(crate) fn prefetch_value<T>(value: *const T) {
    let start: *const u8 = value.cast();
    prefetch_line(start);
    prefetch_line(start.wrapping_add(std::mem::size_of::<T>().saturating_sub(1)));
}
