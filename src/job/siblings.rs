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
//! `tasks/` like any other task. Other processes find pieces by their poll, as before. The
//! loops make one piece for each waiting sibling ([`Siblings::offer`]), not one each.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// The shared state of a worker's tile loops.
#[derive(Default)]
pub struct Siblings {
    idle: AtomicUsize,
    state: Mutex<State>,
    wake: Condvar,
}

#[derive(Default)]
struct State {
    /// Pieces made so far (a loop's wait ends when it changes).
    made: u64,
    /// Pieces being made or made for waiting loops and not yet claimed by one: a busy loop
    /// splits for a waiting sibling only while fewer are than loops wait.
    offers: usize,
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

    /// A loop stops waiting (it claimed a task, most likely a piece offered to it, or the
    /// job ended).
    pub fn end_idle(&self) {
        let _ = self
            .idle
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |n| n.checked_sub(1));
        let mut s = self.lock();
        s.offers = s.offers.saturating_sub(1);
    }

    /// Take the right to make a piece for a waiting loop: whether fewer pieces are offered
    /// than loops wait.
    pub fn offer(&self) -> bool {
        let mut s = self.lock();
        let free = s.offers < self.idle();
        if free {
            s.offers += 1;
        }
        free
    }

    /// Give back an [`Siblings::offer`] whose piece was not made.
    pub fn withdraw(&self) {
        let mut s = self.lock();
        s.offers = s.offers.saturating_sub(1);
    }

    /// Wait up to `timeout` or until a sibling makes a piece; whether one was made. A wait
    /// that ends without one forgets the offers: their pieces went to other workers.
    pub fn wait(&self, timeout: Duration) -> bool {
        let s = self.lock();
        let before = s.made;
        let (mut s, _) = self
            .wake
            .wait_timeout_while(s, timeout, |s| s.made == before)
            .unwrap_or_else(|e| e.into_inner());
        let woken = s.made != before;
        if !woken {
            s.offers = 0;
        }
        woken
    }

    /// Pieces announced so far.
    pub fn pieces(&self) -> u64 {
        self.lock().made
    }

    /// A piece was made: wake every waiting loop.
    pub fn made_piece(&self) {
        self.lock().made += 1;
        self.wake.notify_all();
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
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
    fn one_offer_for_each_waiting_loop() {
        let s = Siblings::default();
        assert!(!s.offer(), "nobody waits");
        s.begin_idle();
        s.begin_idle();
        assert!(s.offer() && s.offer());
        assert!(!s.offer(), "two loops wait, two pieces are coming");
        s.withdraw();
        assert!(s.offer(), "a piece not made frees its offer");
        // A loop that claims a task takes an offer with it.
        s.end_idle();
        assert!(!s.offer(), "one loop waits, one piece is coming");
        // A wait that ends without a piece forgets the offers (others took the pieces).
        assert!(!s.wait(Duration::from_millis(1)));
        assert!(s.offer());
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
