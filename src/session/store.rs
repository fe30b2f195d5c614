//! Where a session's new ambient values go: an append-only ambient log (Tessera's format)
//! written in batches of N_A values under one flush policy, used by `tpict --amb-log` and by
//! `tpiece` (each worker's own log) alike; a worker's store also reads back the values other
//! processes append to theirs ([`Peers`]).
//!
//! `auto` (workers' default) adapts N_A: it keeps running means of the cost of one new value
//! (c_v, thread-seconds) and of one sync (c_s, a log write plus reading the peers) and sets
//! N_A = c_s / (0.1·c_v), clamped to 1..=256, so that syncing costs at most about 10% of the
//! time spent making values and values are shared as early as that allows.

use crate::ambient::cache::{CachedValue, ValueSink};
use crate::ambient::log::LogWriter;
use crate::ambient::Ambient;
use anyhow::Result;
use glam::DVec3;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How N_A (values per log write) is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlushPolicy {
    /// A fixed N_A.
    Fixed(usize),
    /// Adapted at run time.
    Auto,
}

/// Overhead share `auto` aims for.
const AUTO_SHARE: f64 = 0.1;
const AUTO_MAX: usize = 256;

/// N_A for [`FlushPolicy::Auto`] from the mean cost of one sync `c_s` and of one new value
/// `c_v` (seconds): syncing every N_A values costs at most `AUTO_SHARE` of the time spent
/// making them, clamped to 1..=`AUTO_MAX`.
pub fn auto_flush(c_s: f64, c_v: f64) -> usize {
    if c_v.is_nan() || c_v <= 0.0 || !c_s.is_finite() {
        return AUTO_MAX;
    }
    (c_s.max(0.0) / (AUTO_SHARE * c_v))
        .ceil()
        .clamp(1.0, AUTO_MAX as f64) as usize
}

/// What a store did (read by a worker's heartbeat).
#[derive(Debug, Default)]
pub struct StoreCounters {
    /// Nanoseconds syncing (writing the own log, reading the peers').
    pub sync_ns: AtomicU64,
    /// Values read from peers.
    pub shared_in: AtomicU64,
    /// Values written to the own log.
    pub shared_out: AtomicU64,
    /// Current N_A.
    pub flush_every: AtomicU64,
}

/// Add a duration to a nanosecond counter.
pub fn add_time(c: &AtomicU64, d: Duration) {
    c.fetch_add(d.as_nanos() as u64, Ordering::Relaxed);
}

/// The values other processes make, read back into this session's cache.
pub trait Peers: Send + Sync {
    /// Insert what the peers appended since the last look; `wait` blocks for a read already
    /// running elsewhere (otherwise that makes this a no-op); `list` also looks for new
    /// peers. Returns the number of values inserted.
    fn read(&self, wait: bool, list: bool) -> u64;

    /// Records read from the peers and skipped as invalid (non-finite or absurd values).
    fn rejected(&self) -> u64 {
        0
    }
}

/// A session's ambient log: its new values go out in batches (the cache's
/// [`ValueSink`], installed with [`AmbientStore::install`]).
pub struct AmbientStore {
    ambient: Arc<Ambient>,
    writer: Mutex<LogWriter>,
    origin: DVec3,
    policy: FlushPolicy,
    flush_every: AtomicUsize,
    /// Running mean of one sync's cost, seconds.
    sync_cost: Mutex<Option<f64>>,
    error: Mutex<Option<String>>,
    peers: Option<Box<dyn Peers>>,
    counters: Arc<StoreCounters>,
}

impl AmbientStore {
    /// A store appending to `writer` the values of `ambient` (positions relative to the
    /// scene `origin`) under `policy`, reading `peers` at every sync.
    pub fn new(
        ambient: Arc<Ambient>,
        writer: LogWriter,
        origin: DVec3,
        policy: FlushPolicy,
        peers: Option<Box<dyn Peers>>,
    ) -> AmbientStore {
        let first = match policy {
            FlushPolicy::Fixed(n) => n.max(1),
            FlushPolicy::Auto => 1,
        };
        let counters = Arc::new(StoreCounters::default());
        counters.flush_every.store(first as u64, Ordering::Relaxed);
        AmbientStore {
            ambient,
            writer: Mutex::new(writer),
            origin,
            policy,
            flush_every: AtomicUsize::new(first),
            sync_cost: Mutex::new(None),
            error: Mutex::new(None),
            peers,
            counters,
        }
    }

    /// The store's counters.
    pub fn counters(&self) -> &Arc<StoreCounters> {
        &self.counters
    }

    /// Send the cache's new values to this store from now on.
    pub fn install(self: &Arc<Self>) {
        self.ambient.cache.set_sink(Box::new(Sink(self.clone())));
    }

    /// Records the peers held and this store skipped as invalid.
    pub fn rejected(&self) -> u64 {
        self.peers.as_ref().map_or(0, |p| p.rejected())
    }

    /// Write out pending values and read the peers' (one sync).
    pub fn sync(&self) {
        let t = Instant::now();
        self.flush_own();
        if let Some(p) = &self.peers {
            let n = p.read(false, true);
            self.counters.shared_in.fetch_add(n, Ordering::Relaxed);
        }
        let dt = t.elapsed();
        add_time(&self.counters.sync_ns, dt);
        if self.policy == FlushPolicy::Auto {
            self.adapt(dt.as_secs_f64());
        }
    }

    /// Write out pending values without reading the peers (one `write()` if any are
    /// pending, nothing otherwise): what a worker does before a tile counts as done. The
    /// peers are read at every sync, before each new value, and by the heartbeat thread.
    pub fn flush(&self) {
        let t = Instant::now();
        self.flush_own();
        add_time(&self.counters.sync_ns, t.elapsed());
    }

    fn flush_own(&self) {
        let mut w = self.writer.lock().unwrap_or_else(|e| e.into_inner());
        match w.flush() {
            Ok(n) => {
                self.counters
                    .shared_out
                    .fetch_add(n as u64, Ordering::Relaxed);
            }
            Err(e) => {
                let mut slot = self.error.lock().unwrap_or_else(|e| e.into_inner());
                slot.get_or_insert(e.to_string());
            }
        }
    }

    fn adapt(&self, cost: f64) {
        let mut sc = self.sync_cost.lock().unwrap_or_else(|e| e.into_inner());
        let c_s = match *sc {
            None => cost,
            Some(m) => 0.8 * m + 0.2 * cost,
        };
        *sc = Some(c_s);
        let s = &self.ambient.stats;
        let made = s.made();
        if made < 4 {
            return;
        }
        let c_v = s.amb_nanos.load(Ordering::Relaxed) as f64 * 1e-9 / made as f64;
        if c_v <= 0.0 {
            return;
        }
        let n = auto_flush(c_s, c_v);
        self.flush_every.store(n, Ordering::Relaxed);
        self.counters.flush_every.store(n as u64, Ordering::Relaxed);
    }

    /// Values queued but not yet written.
    pub fn pending(&self) -> usize {
        self.writer.lock().map(|w| w.pending()).unwrap_or(0)
    }

    /// Flush everything and report the first write error met since the start.
    pub fn finish(&self) -> Result<()> {
        self.flush_own();
        match self.error.lock().ok().and_then(|mut e| e.take()) {
            Some(e) => Err(anyhow::anyhow!("ambient log: {e}")),
            None => Ok(()),
        }
    }

    /// The first write error, if any (kept).
    pub fn error(&self) -> Option<String> {
        self.error.lock().ok().and_then(|e| e.clone())
    }
}

struct Sink(Arc<AmbientStore>);

impl ValueSink for Sink {
    fn refresh(&self) -> u64 {
        let s = &self.0;
        let Some(p) = &s.peers else {
            return 0;
        };
        let t = Instant::now();
        let n = p.read(false, false);
        s.counters.shared_in.fetch_add(n, Ordering::Relaxed);
        add_time(&s.counters.sync_ns, t.elapsed());
        n
    }

    fn accept(&self, v: &CachedValue) {
        let s = &self.0;
        let due = {
            let mut w = s.writer.lock().unwrap_or_else(|e| e.into_inner());
            w.push(&v.to_record(s.origin));
            w.pending() >= s.flush_every.load(Ordering::Relaxed)
        };
        if due {
            s.sync();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::auto_flush;

    #[test]
    fn auto_flush_keeps_syncing_near_a_tenth_of_the_value_time() {
        // A sync as cheap as a tenth of a value: share every value.
        assert_eq!(auto_flush(0.001, 0.01), 1);
        assert_eq!(auto_flush(0.0, 0.01), 1);
        // A sync costing five values: every 50 values (5 / 50 = 10%).
        assert_eq!(auto_flush(0.05, 0.01), 50);
        // Slower syncs give larger batches, up to the cap.
        assert!(auto_flush(0.2, 0.01) > auto_flush(0.05, 0.01));
        assert_eq!(auto_flush(100.0, 0.01), 256);
        // Nonsense costs never give 0 or panic.
        assert_eq!(auto_flush(f64::NAN, 0.01), 256);
        assert_eq!(auto_flush(0.01, 0.0), 256);
        assert_eq!(auto_flush(0.01, f64::NAN), 256);
    }
}
