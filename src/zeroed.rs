//! Tables of atomic words that start at zero, allocated already zeroed: the system hands out
//! fresh zero pages, so a page of a large table that nothing writes never becomes part of
//! the process's resident memory (the ambient cache's per-level occupancy bits, the
//! shadow-reuse table). Filling the table with zeros one word at a time would touch every
//! page at once.

use std::sync::atomic::AtomicU64;

/// `n` atomic words, all zero.
pub fn atomic_u64s(n: usize) -> Box<[AtomicU64]> {
    let zeroed = Box::<[AtomicU64]>::new_zeroed_slice(n);
    // SAFETY: the slice was allocated zeroed, and all-zero bytes are a valid AtomicU64 (the
    // type has the bit validity of u64; `new_zeroed_slice` gives it its own alignment).
    unsafe { zeroed.assume_init() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::Ordering::Relaxed;

    #[test]
    fn tables_start_at_zero_and_take_writes() {
        for n in [0, 1, 7, 1 << 16] {
            let t = atomic_u64s(n);
            assert_eq!(t.len(), n);
            assert!(t.iter().all(|w| w.load(Relaxed) == 0));
            if n > 0 {
                t[n - 1].store(u64::MAX, Relaxed);
                assert_eq!(t[n - 1].load(Relaxed), u64::MAX);
            }
        }
    }
}
