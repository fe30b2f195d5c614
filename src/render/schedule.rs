//! How the threads of one render share a region's work ([`super::render_region`]), so
//! that no thread sits idle at the end of a pass while others finish large jobs:
//! - `-ps 1` passes (the picture's, and the overture's, which at `-ps 1` samples every
//!   pixel) are cut into runs of [`RUN`] pixels in reading order, which rayon hands out as
//!   it would whole rows (a thread works through its part of the picture in order, an idle
//!   one takes half of what another has left). The threads work far apart, so they seldom
//!   compute ambient values for the same spot at once, and a pass ends on runs of a few
//!   pixels instead of rows (whole rows leave about half a row's time idle per thread: some
//!   4% of a 173-row pass on 16 threads). Runs handed out in reading order from one queue
//!   would put the threads side by side: on 2 threads the overture then makes 7% more
//!   values.
//! - At `-ps` above 1 an odd band reuses the border samples of the even bands on both
//!   sides of it. [`run_bands`] starts an odd band as soon as those two are done (before
//!   any further even band), and the even bands otherwise in an order that spreads them
//!   over the region (halves, then quarters, ...). There is no wave boundary between the
//!   even and the odd bands (with one, 22 even bands on 16 threads run in two rounds of
//!   which the second is under half full, and the odd bands again): threads wait only when
//!   every band left is an odd band whose neighbours are still running.
//!
//! A render on one thread does not come here: it renders its bands in reading order, one at
//! a time, with the overture just ahead of them ([`super::splitting::in_order`]),
//! and hands each band's rows on as it finishes them. A pixel's value never depends on the
//! job it falls in.

use std::sync::{Condvar, Mutex};

/// Pixels in one job of a `-ps 1` pass (the picture's or the overture's).
pub const RUN: usize = 16;

/// The order in which [`run_bands`] hands out `m` even bands on several threads: by
/// bit-reversed index (0, m/2, m/4, 3m/4, ...), so that the bands being rendered at once
/// lie far apart.
pub fn spread_order(m: usize) -> Vec<usize> {
    let bits = m.next_power_of_two().trailing_zeros();
    (0..m.next_power_of_two())
        .map(|i| {
            if bits == 0 {
                0
            } else {
                i.reverse_bits() >> (usize::BITS - bits)
            }
        })
        .filter(|&i| i < m)
        .collect()
}

/// Which bands are taken and done ([`run_bands`]).
struct Bands<J> {
    jobs: Vec<Option<J>>,
    done: Vec<bool>,
    /// The even bands in the order they are handed out ([`spread_order`]).
    evens: Vec<usize>,
    /// The next of `evens` to hand out.
    next_even: usize,
    /// Bands not yet handed out.
    left: usize,
}

impl<J> Bands<J> {
    /// The band to run next, if one can start now: the first odd band whose neighbours are
    /// done, else the next even band (each even band is handed out once, in `evens`).
    /// `Err(())` when bands are left but none can start.
    fn pick(&mut self) -> Result<Option<(usize, J)>, ()> {
        if self.left == 0 {
            return Ok(None);
        }
        let n = self.jobs.len();
        let ready = (1..n).step_by(2).find(|&b| {
            self.jobs[b].is_some() && self.done[b - 1] && (b + 1 >= n || self.done[b + 1])
        });
        let b = match ready {
            Some(b) => b,
            None => {
                let Some(&b) = self.evens.get(self.next_even) else {
                    return Err(());
                };
                self.next_even += 1;
                b
            }
        };
        self.left -= 1;
        Ok(self.jobs[b].take().map(|j| (b, j)))
    }
}

/// Marks band `b` done when dropped, even if its job panicked, so that no thread waits for
/// it forever ([`run_bands`]).
struct Done<'a, J> {
    state: &'a Mutex<Bands<J>>,
    changed: &'a Condvar,
    b: usize,
}

impl<J> Drop for Done<'_, J> {
    fn drop(&mut self) {
        let mut st = self.state.lock().unwrap_or_else(|e| e.into_inner());
        st.done[self.b] = true;
        self.changed.notify_all();
    }
}

/// Run the bands `jobs` (band `b` shares its top border with band `b − 1` and its bottom
/// with band `b + 1`; an odd band reuses what its even neighbours sampled) on the current
/// rayon pool's threads: on one thread the even bands in order, then the odd ones; on more,
/// an odd band as soon as both its neighbours are done, else the next even band in
/// [`spread_order`].
pub fn run_bands<J: Send>(jobs: Vec<J>, f: impl Fn(J) + Sync) {
    let threads = rayon::current_num_threads();
    if threads <= 1 || jobs.len() <= 2 {
        let (even, odd): (Vec<_>, Vec<_>) =
            jobs.into_iter().enumerate().partition(|(b, _)| b % 2 == 0);
        even.into_iter().chain(odd).for_each(|(_, j)| f(j));
        return;
    }
    let n = jobs.len();
    let state = Mutex::new(Bands {
        jobs: jobs.into_iter().map(Some).collect(),
        done: vec![false; n],
        evens: spread_order(n.div_ceil(2))
            .into_iter()
            .map(|i| 2 * i)
            .collect(),
        next_even: 0,
        left: n,
    });
    let changed = Condvar::new();
    let work = || loop {
        let (b, job) = {
            let mut st = state.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                match st.pick() {
                    Ok(Some(picked)) => break picked,
                    Ok(None) => return,
                    Err(()) => st = changed.wait(st).unwrap_or_else(|e| e.into_inner()),
                }
            }
        };
        let _done = Done {
            state: &state,
            changed: &changed,
            b,
        };
        f(job);
    };
    rayon::scope(|s| {
        for _ in 0..threads.min(n) {
            s.spawn(|_| work());
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn spread_order_is_a_permutation_that_starts_far_apart() {
        for m in [0, 1, 2, 3, 7, 8, 22, 100] {
            let mut o = spread_order(m);
            if m >= 4 {
                assert_eq!(&o[..2], &[0, m.next_power_of_two() / 2]);
            }
            o.sort_unstable();
            assert_eq!(o, (0..m).collect::<Vec<_>>());
        }
    }

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    #[test]
    fn one_thread_keeps_the_order() {
        let order = Mutex::new(Vec::new());
        pool(1).install(|| run_bands((0..7).collect(), |j| order.lock().unwrap().push(j)));
        assert_eq!(*order.lock().unwrap(), vec![0, 2, 4, 6, 1, 3, 5]);
    }

    /// Every band runs once, and an odd band only after both its neighbours ended.
    #[test]
    fn odd_bands_wait_for_their_neighbours() {
        for (threads, n) in [(2, 9), (4, 10), (8, 3), (3, 44)] {
            let ended: Vec<AtomicUsize> = (0..n).map(|_| AtomicUsize::new(0)).collect();
            let clock = AtomicUsize::new(1);
            let started: Vec<AtomicUsize> = (0..n).map(|_| AtomicUsize::new(0)).collect();
            pool(threads).install(|| {
                run_bands((0..n).collect(), |b: usize| {
                    started[b].store(clock.fetch_add(1, Ordering::SeqCst), Ordering::SeqCst);
                    std::thread::sleep(std::time::Duration::from_micros(200 * (b as u64 % 3)));
                    ended[b].store(clock.fetch_add(1, Ordering::SeqCst), Ordering::SeqCst);
                })
            });
            for b in 0..n {
                assert!(ended[b].load(Ordering::SeqCst) > 0, "band {b} did not run");
                if b % 2 == 1 {
                    let s = started[b].load(Ordering::SeqCst);
                    assert!(ended[b - 1].load(Ordering::SeqCst) < s);
                    if b + 1 < n {
                        assert!(ended[b + 1].load(Ordering::SeqCst) < s);
                    }
                }
            }
        }
    }
}
