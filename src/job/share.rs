//! Sharing ambient values between workers through the job directory.
//!
//! Each worker appends the values it computes to its own log, `amb/<owner>.log` (one writer
//! per file, so `O_APPEND` atomicity across hosts is never needed), one `write()` per N_A
//! values. At every write, and at least twice per heartbeat interval, it reads the records
//! other workers have appended since it last looked (each log from the offset it reached:
//! whole CRC-valid records only, a torn tail is read later) and inserts those it has not seen
//! (deduplicated by value id). Before it computes a new value (a cache lookup found none), it
//! also reads the logs it knows once more and retries the lookup, so a value another worker
//! wrote a moment ago is used instead of computed again. A worker starting late first loads
//! the merged store and then only the log tails after the offsets the store includes.
//!
//! `--amb-flush auto` adapts N_A: it keeps running means of the cost of one new value (c_v,
//! thread-seconds) and of one sync (c_s, a log write plus reading every other log) and sets
//! N_A = c_s / (0.1·c_v), clamped to 1..=256, so that syncing costs at most about 10% of the time
//! spent making values and values are shared as early as that allows.

use super::heartbeat::Counters;
use super::JobDir;
use crate::ambient::cache::{CachedValue, ValueSink};
use crate::ambient::log::{AmbLogError, LogHeader, LogReader, LogWriter};
use crate::ambient::{Ambient, ValueId};
use anyhow::Result;
use glam::DVec3;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// How N_A is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlushPolicy {
    /// A fixed N_A.
    Fixed(usize),
    /// Adapted at run time.
    Auto,
}

/// Overhead share `--amb-flush auto` aims for.
const AUTO_SHARE: f64 = 0.1;
const AUTO_MAX: usize = 256;

struct Readers {
    logs: HashMap<String, LogReader>,
    refused: HashSet<String>,
    seen: HashSet<ValueId>,
}

/// One worker's end of the sharing.
pub struct Share {
    job: JobDir,
    own_name: String,
    fingerprint: [u8; 32],
    origin: DVec3,
    ambient: Arc<Ambient>,
    writer: Mutex<LogWriter>,
    readers: Mutex<Readers>,
    policy: FlushPolicy,
    flush_every: std::sync::atomic::AtomicUsize,
    /// Running mean of one sync's cost, seconds.
    sync_cost: Mutex<Option<f64>>,
    counters: Arc<Counters>,
    error: Mutex<Option<String>>,
    warnings: Mutex<Vec<String>>,
}

impl Share {
    /// Open the worker's own log, load the merged store and every other log, and return the
    /// sharing state (install it with [`Share::install`]).
    #[allow(clippy::too_many_arguments)]
    pub fn open(
        job: &JobDir,
        owner: &str,
        fingerprint: [u8; 32],
        options: &str,
        origin: DVec3,
        ambient: Arc<Ambient>,
        policy: FlushPolicy,
        counters: Arc<Counters>,
    ) -> Result<Arc<Share>> {
        let own_name = format!("{owner}.log");
        let header = LogHeader::new(fingerprint, options);
        let writer = LogWriter::open(&job.amb_log(owner), &header, false)?;
        let first = match policy {
            FlushPolicy::Fixed(n) => n.max(1),
            FlushPolicy::Auto => 1,
        };
        counters.amb_flush.store(first as u64, Ordering::Relaxed);
        let share = Arc::new(Share {
            job: job.clone(),
            own_name,
            fingerprint,
            origin,
            ambient,
            writer: Mutex::new(writer),
            readers: Mutex::new(Readers {
                logs: HashMap::new(),
                refused: HashSet::new(),
                seen: HashSet::new(),
            }),
            policy,
            flush_every: std::sync::atomic::AtomicUsize::new(first),
            sync_cost: Mutex::new(None),
            counters,
            error: Mutex::new(None),
            warnings: Mutex::new(Vec::new()),
        });
        // The merged store first, then only the log tails after it.
        let t = Instant::now();
        if let Some(store) = super::merge::load_store(job, &fingerprint, false)? {
            let mut rd = share.readers.lock().unwrap_or_else(|e| e.into_inner());
            let mut n = 0;
            for r in &store.records {
                if rd.seen.insert(r.id) {
                    share
                        .ambient
                        .cache
                        .insert(CachedValue::from_record(r, origin));
                    n += 1;
                }
            }
            share.counters.shared_in.fetch_add(n, Ordering::Relaxed);
            for (name, off) in &store.index.logs {
                if *name == share.own_name {
                    continue;
                }
                let path = job.amb().join(name);
                if let Ok(mut r) = LogReader::open(&path, Some(&fingerprint), false) {
                    r.set_offset(*off);
                    rd.logs.insert(name.clone(), r);
                }
            }
        }
        share.sync_in(true);
        super::heartbeat::add_time(&share.counters.sync_ns, t.elapsed());
        Ok(share)
    }

    /// Send this process's new values to the log from now on.
    pub fn install(self: &Arc<Self>) {
        self.ambient.cache.set_sink(Box::new(SinkRef(self.clone())));
    }

    /// Read what other workers appended since the last look; `wait` blocks for the reader
    /// lock (otherwise a sync already running elsewhere makes this a no-op). Returns the
    /// number of new values inserted.
    pub fn sync_in(&self, wait: bool) -> u64 {
        self.read_logs(wait, true)
    }

    /// Like [`sync_in`](Self::sync_in); `list` also looks for new logs (a directory listing),
    /// otherwise only the logs already open are read (one read per log).
    fn read_logs(&self, wait: bool, list: bool) -> u64 {
        let mut rd = if wait {
            self.readers.lock().unwrap_or_else(|e| e.into_inner())
        } else {
            match self.readers.try_lock() {
                Ok(g) => g,
                Err(_) => return 0,
            }
        };
        let rd = &mut *rd;
        let dir = if list {
            std::fs::read_dir(self.job.amb()).ok()
        } else {
            None
        };
        if let Some(dir) = dir {
            for e in dir.flatten() {
                let Some(name) = e.file_name().to_str().map(String::from) else {
                    continue;
                };
                if !name.ends_with(".log")
                    || name.starts_with('.')
                    || name == self.own_name
                    || rd.logs.contains_key(&name)
                    || rd.refused.contains(&name)
                {
                    continue;
                }
                match LogReader::open(&e.path(), Some(&self.fingerprint), false) {
                    Ok(r) => {
                        rd.logs.insert(name, r);
                    }
                    // A log being created: try again at the next sync.
                    Err(AmbLogError::HeaderTruncated { .. }) => {}
                    Err(err) => {
                        self.warn(format!("ignoring ambient log: {err}"));
                        rd.refused.insert(name);
                    }
                }
            }
        }
        let mut added = 0;
        for r in rd.logs.values_mut() {
            let Ok(records) = r.read_available() else {
                continue;
            };
            for rec in records {
                if rd.seen.insert(rec.id) {
                    self.ambient
                        .cache
                        .insert(CachedValue::from_record(&rec, self.origin));
                    added += 1;
                }
            }
        }
        self.counters.shared_in.fetch_add(added, Ordering::Relaxed);
        added
    }

    /// Write out pending values and read the others' (one sync).
    pub fn sync(&self) {
        let t = Instant::now();
        self.flush_own();
        self.sync_in(false);
        let dt = t.elapsed();
        super::heartbeat::add_time(&self.counters.sync_ns, dt);
        if self.policy == FlushPolicy::Auto {
            self.adapt(dt.as_secs_f64());
        }
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
        self.counters.amb_flush.store(n as u64, Ordering::Relaxed);
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

    fn warn(&self, w: String) {
        if let Ok(mut v) = self.warnings.lock() {
            if !v.contains(&w) {
                eprintln!("tpiece: warning - {w}");
                v.push(w);
            }
        }
    }
}

/// N_A for `--amb-flush auto` from the mean cost of one sync `c_s` and of one new value
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

struct SinkRef(Arc<Share>);

impl ValueSink for SinkRef {
    fn refresh(&self) -> u64 {
        let t = Instant::now();
        let n = self.0.read_logs(false, false);
        super::heartbeat::add_time(&self.0.counters.sync_ns, t.elapsed());
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
