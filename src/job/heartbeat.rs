//! Worker heartbeats (`workers/<owner>.json`) and the lease rule.
//!
//! Each worker rewrites its file atomically every lease/8 seconds (at most every 10 s), with
//! a beat counter that grows by one each time, its state and its counters. A claimed tile is
//! stale when another worker has seen its owner's beat **unchanged for the lease** on its own
//! monotonic clock: nothing compares clocks of different hosts and nothing reads file
//! modification times, so NFS attribute caching, coarse mtimes and skewed clocks cannot make a
//! live worker look dead. (The wall-clock times in the file are for people and `tstat`.)

use super::JobDir;
use crate::ambient::Ambient;
use crate::runinfo::process_cpu_seconds;
use crate::session::store::AmbientStore;
use crate::session::Session;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A worker's heartbeat file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorkerRecord {
    /// Worker id (shared by incarnations, e.g. a requeued SLURM task).
    pub worker_id: String,
    /// `<worker-id>.<nonce>`.
    pub owner: String,
    /// Host name.
    pub host: String,
    /// Process id.
    pub pid: u32,
    /// `running`, `idle` (waiting for other workers' tiles), `finished` or `failed`.
    pub state: String,
    /// Grows by one at every heartbeat.
    pub beat: u64,
    /// Wall clock at start (Unix seconds; informational).
    pub started_unix: f64,
    /// Wall clock at this beat (Unix seconds; informational).
    pub updated_unix: f64,
    /// Render threads.
    pub threads: usize,
    /// Tiles rendered (results written).
    pub tiles_done: u64,
    /// Seconds rendering tiles (wall clock).
    pub t_render: f64,
    /// The seed paper's T_spec: rendering time not spent making ambient values.
    pub t_spec: f64,
    /// The seed paper's T_amb: time making new ambient values (thread-seconds / threads).
    pub t_amb: f64,
    /// The seed paper's T_idle: waiting with nothing to claim.
    pub t_idle: f64,
    /// Time writing and reading ambient logs.
    pub t_sync: f64,
    /// Extensive ambient computations (new values).
    pub new_values: u64,
    /// Values read from other workers' logs and the merged store.
    pub shared_in: u64,
    /// Values appended to this worker's log.
    pub shared_out: u64,
    /// Current N_A (values per log write).
    pub amb_flush: u64,
    /// Tiles this worker took over from a stale (or earlier) owner.
    #[serde(default)]
    pub reclaimed: u64,
    /// Pieces this worker split off the tiles it rendered ([`super::piece`]).
    #[serde(default)]
    pub split: u64,
    /// Ambient records read from other workers' logs or the merged store and skipped as
    /// invalid, and values the cache refused (docs/robustness.md).
    #[serde(default)]
    pub rejected: u64,
    /// Rays traced.
    pub rays: u64,
    /// CPU seconds of the process.
    pub cpu_seconds: f64,
    /// Error that ended the worker, if any.
    pub error: Option<String>,
}

/// Largest count a heartbeat may report (tiles, values, rays): far beyond any real job.
const MAX_COUNT: u64 = 1 << 53;
/// Largest number of seconds a heartbeat may report (durations; Unix times up to about
/// the year 5000).
const MAX_SECONDS: f64 = 1e11;

impl WorkerRecord {
    /// Why the record cannot be a worker's own heartbeat in the file `file_stem.json`: an
    /// owner that is not the file's name, a time that is not finite or out of range, a
    /// count beyond any real job. None when it is plausible.
    pub fn implausible(&self, file_stem: &str) -> Option<String> {
        if self.owner != file_stem {
            return Some(format!(
                "its owner '{}' is not the file's name",
                self.owner.escape_debug()
            ));
        }
        let times = [
            ("started_unix", self.started_unix),
            ("updated_unix", self.updated_unix),
            ("t_render", self.t_render),
            ("t_spec", self.t_spec),
            ("t_amb", self.t_amb),
            ("t_idle", self.t_idle),
            ("t_sync", self.t_sync),
            ("cpu_seconds", self.cpu_seconds),
        ];
        for (name, v) in times {
            if !(v.is_finite() && (0.0..=MAX_SECONDS).contains(&v)) {
                return Some(format!("{name} {v} is out of range"));
            }
        }
        let counts = [
            ("tiles_done", self.tiles_done),
            ("new_values", self.new_values),
            ("shared_in", self.shared_in),
            ("shared_out", self.shared_out),
            ("reclaimed", self.reclaimed),
            ("rejected", self.rejected),
            ("rays", self.rays),
        ];
        for (name, v) in counts {
            if v > MAX_COUNT {
                return Some(format!("{name} {v} is out of range"));
            }
        }
        if self.threads > 1 << 16 {
            return Some(format!("threads {} is out of range", self.threads));
        }
        None
    }
}

/// Counters a worker updates while it runs (read by its heartbeat thread; the ambient
/// store keeps its own, [`crate::session::store::StoreCounters`]).
#[derive(Debug, Default)]
pub struct Counters {
    /// Tiles written.
    pub tiles_done: AtomicU64,
    /// Nanoseconds rendering.
    pub render_ns: AtomicU64,
    /// Nanoseconds idle.
    pub idle_ns: AtomicU64,
    /// Tiles re-claimed from other owners.
    pub reclaimed: AtomicU64,
    /// Pieces split off tiles while they rendered ([`super::piece`]).
    pub split: AtomicU64,
    /// Rays traced.
    pub rays: AtomicU64,
}

pub use crate::session::store::add_time;

/// How often a worker with lease `lease` beats.
pub fn beat_interval(lease: f64) -> Duration {
    Duration::from_secs_f64((lease / 8.0).clamp(0.05, 10.0))
}

/// Read a heartbeat file (None when missing or unreadable, e.g. being replaced).
pub fn read_record(path: &Path) -> Option<WorkerRecord> {
    let text = crate::safefile::read_text_bounded(path, 1 << 16).ok()?;
    serde_json::from_str(&text).ok()
}

/// What a worker has seen of other workers' beats.
#[derive(Debug)]
pub struct StaleWatcher {
    lease: Duration,
    seen: HashMap<String, (Option<(u64, String)>, Instant)>,
}

impl StaleWatcher {
    /// A watcher for a lease of `lease` seconds.
    pub fn new(lease: f64) -> StaleWatcher {
        StaleWatcher {
            lease: Duration::from_secs_f64(lease),
            seen: HashMap::new(),
        }
    }

    /// Observe `owner`'s heartbeat (`None` when its file is missing or unreadable) and
    /// return whether its claims are stale: its beat has not changed for a whole lease since
    /// this watcher first saw that beat, or its state is `finished`/`failed` (a worker that
    /// ended cannot hold a tile).
    pub fn is_stale(&mut self, owner: &str, rec: Option<&WorkerRecord>) -> bool {
        if let Some(r) = rec {
            if r.state == "finished" || r.state == "failed" {
                return true;
            }
        }
        let key = rec.map(|r| (r.beat, r.state.clone()));
        let now = Instant::now();
        let entry = self
            .seen
            .entry(owner.to_string())
            .or_insert((key.clone(), now));
        if entry.0 != key {
            *entry = (key, now);
            return false;
        }
        now.duration_since(entry.1) >= self.lease
    }
}

/// What the heartbeat thread writes: the worker's record, its counters and those of its
/// ambient calculation and store.
pub(super) struct Beat {
    job: JobDir,
    record: Mutex<WorkerRecord>,
    pub(super) counters: Arc<Counters>,
    ambient: Option<Arc<Ambient>>,
    store: Option<Arc<AmbientStore>>,
    threads: usize,
    start_cpu: f64,
}

impl Beat {
    pub(super) fn new(
        job: &JobDir,
        worker_id: &str,
        owner: &str,
        session: &Session,
        loops: usize,
    ) -> Beat {
        Beat {
            job: job.clone(),
            record: Mutex::new(WorkerRecord {
                worker_id: worker_id.to_string(),
                owner: owner.to_string(),
                host: crate::runinfo::host_name(),
                pid: std::process::id(),
                state: "running".into(),
                started_unix: super::unix_now(),
                threads: loops,
                ..WorkerRecord::default()
            }),
            counters: Arc::new(Counters::default()),
            ambient: session.ambient.clone(),
            store: session.store().cloned(),
            threads: loops,
            start_cpu: process_cpu_seconds().unwrap_or(0.0),
        }
    }

    pub(super) fn set_state(&self, state: &str) {
        if let Ok(mut r) = self.record.lock() {
            r.state = state.into();
        }
    }

    pub(super) fn write(&self, state: Option<&str>, error: Option<String>) {
        let mut r = self.record.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = state {
            r.state = s.to_string();
        }
        if error.is_some() {
            r.error = error;
        }
        let c = &self.counters;
        let secs = |a: &std::sync::atomic::AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
        r.beat += 1;
        r.updated_unix = super::unix_now();
        r.tiles_done = c.tiles_done.load(Ordering::Relaxed);
        // Times are summed over the tile loops: per loop, as for a one-thread worker.
        let loops = self.threads.max(1) as f64;
        r.t_render = secs(&c.render_ns) / loops;
        r.t_idle = secs(&c.idle_ns) / loops;
        if let Some(s) = &self.store {
            let sc = s.counters();
            r.t_sync = secs(&sc.sync_ns);
            r.shared_in = sc.shared_in.load(Ordering::Relaxed);
            r.shared_out = sc.shared_out.load(Ordering::Relaxed);
            r.amb_flush = sc.flush_every.load(Ordering::Relaxed);
        }
        r.reclaimed = c.reclaimed.load(Ordering::Relaxed);
        r.split = c.split.load(Ordering::Relaxed);
        r.rays = c.rays.load(Ordering::Relaxed);
        if let Some(a) = &self.ambient {
            r.new_values = a.stats.made();
            r.rejected = self.store.as_ref().map_or(0, |s| s.rejected()) + a.cache.refused();
            // CPU of the threads that made the values: at most the process's CPU.
            r.t_amb = secs(&a.stats.amb_nanos) / loops;
        }
        r.t_spec = (r.t_render - r.t_amb).max(0.0);
        r.cpu_seconds = process_cpu_seconds()
            .map(|c| c - self.start_cpu)
            .unwrap_or(0.0);
        if let Ok(json) = serde_json::to_vec_pretty(&*r) {
            let _ = super::write_file_atomic(&self.job.worker_file(&r.owner), &json);
        }
    }

    /// Start the heartbeat thread: it writes the record every beat and syncs the ambient
    /// store twice per beat even when this worker makes no values.
    pub(super) fn spawn(self: &Arc<Self>, interval: Duration) -> Beater {
        let stop = Arc::new(AtomicBool::new(false));
        let (beat, stop2) = (self.clone(), stop.clone());
        let handle = std::thread::spawn(move || {
            let half = interval / 2;
            let mut last_beat = Instant::now();
            while !stop2.load(Ordering::Relaxed) {
                std::thread::park_timeout(half);
                if stop2.load(Ordering::Relaxed) {
                    break;
                }
                if let Some(s) = &beat.store {
                    s.sync();
                }
                if last_beat.elapsed() >= interval {
                    last_beat = Instant::now();
                    beat.write(None, None);
                }
            }
        });
        Beater { stop, handle }
    }
}

/// The running heartbeat thread.
pub(super) struct Beater {
    stop: Arc<AtomicBool>,
    handle: JoinHandle<()>,
}

impl Beater {
    pub(super) fn stop(self) {
        self.stop.store(true, Ordering::Relaxed);
        self.handle.thread().unpark();
        let _ = self.handle.join();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_only_after_a_full_unchanged_lease() {
        let mut w = StaleWatcher::new(0.2);
        let mut r = WorkerRecord {
            state: "running".into(),
            beat: 1,
            ..Default::default()
        };
        assert!(!w.is_stale("a", Some(&r)));
        std::thread::sleep(Duration::from_millis(120));
        r.beat = 2; // it beats: the clock starts again
        assert!(!w.is_stale("a", Some(&r)));
        std::thread::sleep(Duration::from_millis(120));
        assert!(!w.is_stale("a", Some(&r)));
        std::thread::sleep(Duration::from_millis(120));
        assert!(w.is_stale("a", Some(&r)));
        // A missing file counts from when it was first seen missing.
        assert!(!w.is_stale("b", None));
        std::thread::sleep(Duration::from_millis(220));
        assert!(w.is_stale("b", None));
        r.state = "finished".into();
        assert!(w.is_stale("c", Some(&r)));
    }
}
