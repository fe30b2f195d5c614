//! Shards of data read by many threads and written rarely, each behind a lock whose readers
//! write only a cache line of their own (a "big reader" lock, striped by thread).
//!
//! A reader adds one to its own stripe's count of that shard's readers (a line no other
//! reader writes, as long as there are no more threads than [`STRIPES`]), then checks that
//! no writer holds the shard; a writer marks the shard and waits until every stripe's count
//! of it is zero. Both sides use sequentially consistent operations, so a reader and a
//! writer cannot both miss each other. Writers exclude each other through their mark.
//! Readers are many and short, writers few (an ambient value filed), so a writer's scan of
//! the stripes, one cache miss each, costs little; a reader that finds a writer steps back
//! and waits for it, so a steady stream of readers cannot starve a writer.
//!
//! A `std::sync::RwLock` instead writes its lock word at every read lock and unlock, so
//! threads reading the same shards move that line between their cores at every read: two
//! threads looking up in one irradiance cache took 1.35× as long a lookup as two with a
//! cache each (`cargo bench --bench lookups -- FILE --threads 2 [--separate]`, 2 cores),
//! where with this lock they take as long.
//!
//! As with `std::sync::RwLock`, a thread must not take a shard's lock while it already
//! holds it.

use super::striped::{thread_index, threads_indexed};
use std::cell::UnsafeCell;
use std::ops::{Deref, DerefMut};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering::SeqCst};

/// Stripes of reader counts; threads beyond it share stripes, still correctly.
pub const STRIPES: usize = 64;

/// Shards a [`Sharded`] may have (one reader count per shard in a stripe).
pub const MAX_SHARDS: usize = 64;

/// One stripe's reader count of every shard: 256 bytes, on lines no other stripe uses.
#[repr(align(128))]
struct Stripe([AtomicU32; MAX_SHARDS]);

/// A shard's writer mark, on a line of its own.
#[repr(align(128))]
struct Mark(AtomicBool);

/// A shard's data, on lines of its own.
#[repr(align(128))]
struct Slot<T>(UnsafeCell<T>);

/// This thread's stripe.
#[inline(always)]
fn my_stripe() -> usize {
    thread_index() % STRIPES
}

/// Stripes any thread may be counting in now: a writer need not look beyond them.
fn stripes_in_use() -> usize {
    threads_indexed().min(STRIPES)
}

/// Spin briefly, then give the core away: the other side holds its lock for a short while,
/// unless it was descheduled.
#[inline]
fn back_off(spins: &mut u32) {
    if *spins < 64 {
        std::hint::spin_loop();
        *spins += 1;
    } else {
        std::thread::yield_now();
    }
}

/// `n` shards of `T`, each readable by many threads at once and writable by one.
pub struct Sharded<T> {
    readers: Box<[Stripe]>,
    marks: Box<[Mark]>,
    data: Box<[Slot<T>]>,
}

// SAFETY: a shard's data is reached only through the guards below, which give shared access
// to readers while no writer holds the shard and exclusive access to one writer while no
// reader does (the protocol of the module's docs).
unsafe impl<T: Send + Sync> Sync for Sharded<T> {}
// SAFETY: the data moves with the value; the counts and marks are atomics.
unsafe impl<T: Send> Send for Sharded<T> {}

impl<T> Sharded<T> {
    /// Shards made by `make`, at most [`MAX_SHARDS`] of them.
    pub fn new(n: usize, mut make: impl FnMut() -> T) -> Sharded<T> {
        assert!(n <= MAX_SHARDS, "at most {MAX_SHARDS} shards");
        Sharded {
            readers: (0..STRIPES)
                .map(|_| Stripe(std::array::from_fn(|_| AtomicU32::new(0))))
                .collect(),
            marks: (0..n).map(|_| Mark(AtomicBool::new(false))).collect(),
            data: (0..n).map(|_| Slot(UnsafeCell::new(make()))).collect(),
        }
    }

    /// Number of shards.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True when there are no shards.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Shared access to shard `i`, waiting while a writer holds it.
    #[inline(always)]
    pub fn read(&self, i: usize) -> Read<'_, T> {
        let count = &self.readers[my_stripe()].0[i];
        count.fetch_add(1, SeqCst);
        if self.marks[i].0.load(SeqCst) {
            self.wait_for_writer(count, i);
        }
        Read {
            count,
            data: &self.data[i].0,
        }
    }

    /// A reader counted in `count` that found shard `i` held by a writer: steps back until
    /// the writer is done, and returns counted again with no writer holding the shard.
    #[cold]
    #[inline(never)]
    fn wait_for_writer(&self, count: &AtomicU32, i: usize) {
        let mark = &self.marks[i].0;
        loop {
            count.fetch_sub(1, SeqCst);
            let mut spins = 0;
            while mark.load(SeqCst) {
                back_off(&mut spins);
            }
            count.fetch_add(1, SeqCst);
            if !mark.load(SeqCst) {
                return;
            }
        }
    }

    /// Exclusive access to shard `i`, waiting for other writers and for its readers.
    pub fn write(&self, i: usize) -> Write<'_, T> {
        let mark = &self.marks[i].0;
        let mut spins = 0;
        while mark
            .compare_exchange_weak(false, true, SeqCst, SeqCst)
            .is_err()
        {
            back_off(&mut spins);
        }
        for stripe in &self.readers[..stripes_in_use()] {
            let mut spins = 0;
            while stripe.0[i].load(SeqCst) != 0 {
                back_off(&mut spins);
            }
        }
        Write {
            mark,
            data: &self.data[i].0,
        }
    }

    /// Every shard, for exclusive use (no lock needed: `&mut self` rules out others).
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.data.iter_mut().map(|c| c.0.get_mut())
    }
}

/// A reader's hold of a shard ([`Sharded::read`]).
pub struct Read<'a, T> {
    count: &'a AtomicU32,
    data: &'a UnsafeCell<T>,
}

impl<T> Deref for Read<'_, T> {
    type Target = T;
    #[inline]
    fn deref(&self) -> &T {
        // SAFETY: while this reader is counted no writer holds the shard (module docs).
        unsafe { &*self.data.get() }
    }
}

impl<T> Drop for Read<'_, T> {
    #[inline]
    fn drop(&mut self) {
        self.count.fetch_sub(1, SeqCst);
    }
}

/// A writer's hold of a shard ([`Sharded::write`]).
pub struct Write<'a, T> {
    mark: &'a AtomicBool,
    data: &'a UnsafeCell<T>,
}

impl<T> Deref for Write<'_, T> {
    type Target = T;
    fn deref(&self) -> &T {
        // SAFETY: the writer holds the shard alone (module docs).
        unsafe { &*self.data.get() }
    }
}

impl<T> DerefMut for Write<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        // SAFETY: the writer holds the shard alone (module docs).
        unsafe { &mut *self.data.get() }
    }
}

impl<T> Drop for Write<'_, T> {
    fn drop(&mut self) {
        self.mark.store(false, SeqCst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writers keep an invariant (two fields equal) that readers check, while many threads
    /// read and write the same few shards; every write is counted once.
    #[test]
    fn readers_never_see_a_write_half_done() {
        let s = Sharded::new(3, || (0u64, 0u64));
        let threads = 2 * STRIPES + 3;
        std::thread::scope(|sc| {
            for t in 0..threads {
                let s = &s;
                sc.spawn(move || {
                    for k in 0..2000usize {
                        let i = (t + k) % 3;
                        if k % 7 == t % 7 {
                            let mut w = s.write(i);
                            w.0 += 1;
                            std::hint::black_box(&mut *w);
                            w.1 += 1;
                        } else {
                            let r = s.read(i);
                            let (a, b) = (r.0, std::hint::black_box(r.1));
                            assert_eq!(a, b, "a reader saw a write half done");
                        }
                    }
                });
            }
        });
        let mut s = s;
        let total: u64 = s.iter_mut().map(|v| v.0).sum();
        let expected: u64 = (0..threads)
            .map(|t| (0..2000usize).filter(|k| k % 7 == t % 7).count() as u64)
            .sum();
        assert_eq!(total, expected);
        assert!(s.iter_mut().all(|v| v.0 == v.1));
    }

    /// A writer gets in while readers keep coming (they step back for it).
    #[test]
    fn a_writer_is_not_starved() {
        let s = Sharded::new(1, || 0u32);
        let stop = AtomicBool::new(false);
        std::thread::scope(|sc| {
            for _ in 0..4 {
                sc.spawn(|| {
                    while !stop.load(SeqCst) {
                        let r = s.read(0);
                        std::hint::black_box(*r);
                    }
                });
            }
            for _ in 0..200 {
                *s.write(0) += 1;
            }
            stop.store(true, SeqCst);
        });
        assert_eq!(*s.read(0), 200);
    }

    #[test]
    fn layout_keeps_stripes_apart() {
        assert!(std::mem::align_of::<Stripe>() >= 128);
        assert!(std::mem::align_of::<Mark>() >= 128);
        assert_eq!(std::mem::size_of::<Stripe>() % 128, 0);
    }
}
