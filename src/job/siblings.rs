//! What the tile loops of one worker process tell each other without the job directory:
//! how many of them wait for work, and a wake-up when one of them has made a piece
//! (docs/batch.md, "Splitting a tile in progress").
//!
//! A loop that finds nothing to claim counts itself idle until it claims a task again. A
//! loop rendering a task sees that count before each cell: while a sibling waits, it may
//! split every [`super::split::SIBLING_CHECK_SECONDS`] instead of every
//! [`super::split::CHECK_SECONDS`], without reading `tasks/` (the waiting sibling found
//! nothing to claim there), down to pieces of [`super::split::SIBLING_MIN_PIECE_SECONDS`];
//! when it has made a piece it wakes the waiting siblings at once, and they claim it through
//! `tasks/` like any other task. Other processes find pieces by their poll, as before.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// The shared state of a worker's tile loops.
#[derive(Default)]
pub struct Siblings {
    idle: AtomicUsize,
    /// Pieces made so far (a loop's wait ends when it changes).
    made: Mutex<u64>,
    wake: Condvar,
}

impl Siblings {
    /// Loops waiting for work now.
    pub fn idle(&self) -> usize {
        self.idle.load(Ordering::Relaxed)
    }

    /// A loop starts waiting for work.
    pub fn begin_idle(&self) {
        self.idle.fetch_add(1, Ordering::Relaxed);
    }

    /// A loop stops waiting (it claimed a task, or the job ended).
    pub fn end_idle(&self) {
        let _ = self
            .idle
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1));
    }

    /// Wait up to `timeout` or until a sibling makes a piece; whether one was made.
    pub fn wait(&self, timeout: Duration) -> bool {
        let made = self.made.lock().unwrap_or_else(|e| e.into_inner());
        let before = *made;
        let (made, _) = self
            .wake
            .wait_timeout_while(made, timeout, |m| *m == before)
            .unwrap_or_else(|e| e.into_inner());
        *made != before
    }

    /// Pieces announced so far.
    pub fn pieces(&self) -> u64 {
        *self.made.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A piece was made: wake every waiting loop.
    pub fn made_piece(&self) {
        *self.made.lock().unwrap_or_else(|e| e.into_inner()) += 1;
        self.wake.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;
    use std::time::Instant;

    #[test]
    fn idle_count_never_goes_below_zero() {
        let s = Siblings::default();
        s.end_idle();
        assert_eq!(s.idle(), 0);
        s.begin_idle();
        s.begin_idle();
        assert_eq!(s.idle(), 2);
        s.end_idle();
        assert_eq!(s.idle(), 1);
    }

    #[test]
    fn a_piece_wakes_a_waiting_loop_before_its_timeout() {
        let s = Arc::new(Siblings::default());
        let t = {
            let s = s.clone();
            std::thread::spawn(move || {
                let start = Instant::now();
                let woke = s.wait(Duration::from_secs(30));
                (woke, start.elapsed())
            })
        };
        // Keep announcing until the waiter has seen one (it may not be waiting yet).
        while !t.is_finished() {
            s.made_piece();
            std::thread::sleep(Duration::from_millis(5));
        }
        let (woke, took) = t.join().unwrap();
        assert!(woke);
        assert!(took < Duration::from_secs(10), "{took:?}");
        // Without a piece the wait ends by its timeout and says so.
        assert!(!s.wait(Duration::from_millis(10)));
    }
}
