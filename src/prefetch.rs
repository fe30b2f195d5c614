//! Software prefetch: a hint that brings a value's cache lines in before it is read, so that
//! the misses of several values looked up together overlap instead of coming one after
//! another (the ambient cache's candidates, the shadow-reuse slots of a point's sources).

/// Bring the cache lines of `v` in (every line its bytes touch, at most four; nothing on
/// targets without a prefetch instruction). Reads nothing and changes nothing.
#[inline(always)]
pub fn prefetch<T>(v: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = v as *const T as *const i8;
        let offset = p as usize % 64;
        let lines = (offset + std::mem::size_of::<T>()).div_ceil(64).clamp(1, 4);
        let p = p.wrapping_sub(offset);
        for i in 0..lines {
            // SAFETY: a prefetch is a hint that reads nothing and cannot fault, whatever the
            // address; SSE is part of every x86_64 target.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64 * i)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}
