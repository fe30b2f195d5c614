//! A counter that many render threads add to without sharing a cache line.
//!
//! The ambient counters that every lookup bumps (lookups, hits, reused shadow rays, leak
//! tests) were plain atomics in one cache line: with 16 threads each increment moved that
//! line between cores. Each thread now adds to its own padded slot (threads are spread over
//! [`SLOTS`] slots in the order they first count); a read sums the slots. Adding and
//! reading keep the `AtomicU64` method names, so the counters read as before.

use std::cell::Cell;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

/// Slots per counter (threads beyond it share slots, still correctly).
pub const SLOTS: usize = 32;

#[derive(Default)]
#[repr(align(128))]
struct Slot(AtomicU64);

/// A striped `u64` counter.
pub struct Striped {
    slots: Box<[Slot]>,
}

impl Default for Striped {
    fn default() -> Self {
        Striped {
            slots: (0..SLOTS).map(|_| Slot::default()).collect(),
        }
    }
}

impl std::fmt::Debug for Striped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.load(Ordering::Relaxed))
    }
}

static NEXT_THREAD: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// This thread's index ([`thread_index`]); `usize::MAX` until it is first asked for. A
    /// constant initialiser, so that reading it costs no lazy-init check.
    static THREAD_INDEX: Cell<usize> = const { Cell::new(usize::MAX) };
}

/// This thread's index among the threads that asked for one, in the order they first asked
/// (0, 1, 2, ...): the stripe it adds to, here and in [`super::sharded`].
#[inline(always)]
pub fn thread_index() -> usize {
    let i = THREAD_INDEX.with(Cell::get);
    if i != usize::MAX {
        i
    } else {
        first_index()
    }
}

/// A thread's index when it first asks (sequentially consistent: a thread's index is
/// handed out before anything it then does, which [`threads_indexed`] relies on).
#[cold]
#[inline(never)]
fn first_index() -> usize {
    let i = NEXT_THREAD.fetch_add(1, Ordering::SeqCst);
    THREAD_INDEX.with(|c| c.set(i));
    i
}

/// How many threads have an index so far (every index handed out is below it).
pub fn threads_indexed() -> usize {
    NEXT_THREAD.load(Ordering::SeqCst)
}

impl Striped {
    /// Add `n` (the order is ignored: counts are summed when read).
    #[inline]
    pub fn fetch_add(&self, n: u64, _order: Ordering) {
        self.slots[thread_index() % SLOTS]
            .0
            .fetch_add(n, Ordering::Relaxed);
    }

    /// The sum of every thread's additions so far.
    pub fn load(&self, _order: Ordering) -> u64 {
        self.slots
            .iter()
            .fold(0u64, |a, s| a.wrapping_add(s.0.load(Ordering::Relaxed)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_add_up() {
        let c = Striped::default();
        std::thread::scope(|s| {
            for _ in 0..40 {
                s.spawn(|| {
                    for _ in 0..1000 {
                        c.fetch_add(2, Ordering::Relaxed);
                    }
                });
            }
        });
        assert_eq!(c.load(Ordering::Relaxed), 80_000);
        assert!(std::mem::align_of::<Slot>() >= 128);
    }
}
