//! How the threads of one render share a region's work ([`super::render_region`]).
//!
//! Two losses at the end of a frame made `tpict -n T` scale worse than T processes on
//! tiles: with `-ps 1` every job was a whole pixel row, so the frame ended with threads
//! idle while the last rows finished (on a 173-row picture and 16 threads, about half a
//! row's time each, some 4% of the frame); with `-ps` above 1 the sampling bands ran in
//! two waves, the even bands and then the odd ones (which reuse the even bands' border
//! samples), with every thread waiting between them for the slowest even band (22 even
//! bands on 16 threads: two rounds of which the second is under half full, then the same
//! again for the odd bands). Now:
//! - [`pixel_jobs`] cuts `-ps 1` regions into jobs in reading order that shrink toward the
//!   end (whole rows while many remain, then down to [`MIN_PIXELS`] pixels), and
//!   [`run_in_order`] hands them out in that order: the frame ends on jobs of a few pixels;
//! - [`run_bands`] starts an odd band as soon as the even bands on both sides of it are
//!   done (before any further even band), and even bands in order otherwise, so there is
//!   no wave boundary: threads wait only when every band left is an odd band whose
//!   neighbours are still running.
//!
//! On one thread both keep the order of the single-thread render (reading order; the even
//! bands, then the odd ones), so a one-thread picture is bit-identical to before, with
//! indirect light too. A pixel's value never depends on the job it falls in.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};

/// The smallest job of [`pixel_jobs`], in pixels.
pub const MIN_PIXELS: usize = 8;

/// Jobs left per thread below which [`pixel_jobs`] makes its jobs smaller than a row.
const JOBS_PER_THREAD: usize = 4;

/// The jobs of a `-ps 1` region of `n` pixels in rows of `w`, as `(first pixel, pixels)`
/// in reading order: whole rows while at least [`JOBS_PER_THREAD`] rows per thread
/// remain, then jobs of a `JOBS_PER_THREAD`·`threads`-th of what remains (at least
/// [`MIN_PIXELS`]). One thread: one job per row, as before.
pub fn pixel_jobs(n: usize, w: usize, threads: usize) -> Vec<(usize, usize)> {
    let w = w.max(1);
    let mut jobs = Vec::with_capacity(n / w + 64);
    let mut at = 0;
    while at < n {
        let left = n - at;
        let len = if threads <= 1 {
            w - at % w
        } else {
            (left / (JOBS_PER_THREAD * threads))
                .max(MIN_PIXELS)
                .min(w - at % w)
        };
        let len = len.min(left);
        jobs.push((at, len));
        at += len;
    }
    jobs
}

/// Run `f` on every job on the current rayon pool's threads, each thread taking the next
/// job in the order given.
pub fn run_in_order<J: Send>(jobs: Vec<J>, f: impl Fn(J) + Sync) {
    let threads = rayon::current_num_threads().min(jobs.len()).max(1);
    let slots: Vec<Mutex<Option<J>>> = jobs.into_iter().map(|j| Mutex::new(Some(j))).collect();
    let next = AtomicUsize::new(0);
    let work = || loop {
        let i = next.fetch_add(1, Ordering::Relaxed);
        let Some(slot) = slots.get(i) else { return };
        let job = slot.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(job) = job {
            f(job);
        }
    };
    if threads == 1 {
        work();
    } else {
        rayon::scope(|s| {
            for _ in 0..threads {
                s.spawn(|_| work());
            }
        });
    }
}

/// Which bands are taken and done ([`run_bands`]).
struct Bands<J> {
    jobs: Vec<Option<J>>,
    done: Vec<bool>,
    /// The next even band to hand out.
    next_even: usize,
    /// Bands not yet handed out.
    left: usize,
}

impl<J> Bands<J> {
    /// The band to run next, if one can start now: the first odd band whose neighbours are
    /// done, else the next even band. `Err(())` when bands are left but none can start.
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
                while self.next_even < n && self.jobs[self.next_even].is_none() {
                    self.next_even += 2;
                }
                if self.next_even >= n {
                    return Err(());
                }
                self.next_even
            }
        };
        self.left -= 1;
        Ok(self.jobs[b].take().map(|j| (b, j)))
    }
}

/// Run the bands `jobs` (band `b` shares its top border with band `b − 1` and its bottom
/// with band `b + 1`; an odd band reuses what its even neighbours sampled) on the current
/// rayon pool's threads: on one thread the even bands in order, then the odd ones; on more,
/// an odd band as soon as both its neighbours are done, else the next even band.
pub fn run_bands<J: Send>(jobs: Vec<J>, f: impl Fn(J) + Sync) {
    let threads = rayon::current_num_threads();
    if threads <= 1 || jobs.len() <= 2 {
        let mut jobs: Vec<Option<J>> = jobs.into_iter().map(Some).collect();
        let order = (0..jobs.len()).step_by(2).chain((1..jobs.len()).step_by(2));
        for b in order.collect::<Vec<_>>() {
            if let Some(j) = jobs[b].take() {
                f(j);
            }
        }
        return;
    }
    let n = jobs.len();
    let state = Mutex::new(Bands {
        jobs: jobs.into_iter().map(Some).collect(),
        done: vec![false; n],
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
        // Marks the band done even if `f` panics, so that no thread waits for it forever.
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

    #[test]
    fn pixel_jobs_cover_the_region_in_order_and_shrink() {
        for (n, w, t) in [
            (0, 5, 4),
            (7, 3, 1),
            (256 * 173, 256, 16),
            (1000, 1000, 2),
            (37, 5, 8),
        ] {
            let jobs = pixel_jobs(n, w, t);
            let mut at = 0;
            for &(a, len) in &jobs {
                assert_eq!(a, at);
                assert!(len >= 1 && len <= w);
                // A job never crosses a row's end.
                assert!(a % w + len <= w, "{n} {w} {t}: job ({a}, {len})");
                at += len;
            }
            assert_eq!(at, n);
            if t == 1 {
                assert!(jobs
                    .iter()
                    .all(|&(a, len)| a % w == 0 && (len == w || a + len == n)));
            }
        }
        let jobs = pixel_jobs(256 * 173, 256, 16);
        assert_eq!(jobs[0].1, 256);
        assert!(jobs.last().unwrap().1 <= MIN_PIXELS);
        assert!(jobs.len() < 2 * 173 + 100, "{} jobs", jobs.len());
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
        pool(1).install(|| run_in_order((0..10).collect(), |j| order.lock().unwrap().push(j)));
        assert_eq!(*order.lock().unwrap(), (0..10).collect::<Vec<_>>());
        order.lock().unwrap().clear();
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

    #[test]
    fn every_job_runs_once_on_many_threads() {
        let count: Vec<AtomicUsize> = (0..500).map(|_| AtomicUsize::new(0)).collect();
        pool(4).install(|| {
            run_in_order((0..500).collect(), |j: usize| {
                count[j].fetch_add(1, Ordering::Relaxed);
            })
        });
        assert!(count.iter().all(|c| c.load(Ordering::Relaxed) == 1));
    }
}
