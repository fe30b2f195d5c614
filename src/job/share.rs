//! Sharing ambient values between workers through the job directory.
//!
//! Each worker appends the values it computes to its own log, `amb/<owner>.log` (one writer
//! per file, so `O_APPEND` atomicity across hosts is never needed), one `write()` per N_A
//! values: the session's [`AmbientStore`] under its flush policy (`--amb-flush N|auto`,
//! see [`crate::session::store`]). At every write, and at least twice per heartbeat
//! interval, it reads the records other workers have appended since it last looked (each log
//! from the offset it reached: whole CRC-valid records only, a torn tail is read later) and
//! inserts those it has not seen (deduplicated by value id): the [`JobPeers`] here. Before it
//! computes a new value (a cache lookup found none), it also reads the logs it knows once
//! more and retries the lookup, so a value another worker wrote a moment ago is used instead
//! of computed again. A worker starting late first loads the merged store and then only the
//! log tails after the offsets the store includes.

use super::JobDir;
use crate::ambient::cache::CachedValue;
use crate::ambient::log::{AmbLogError, LogReader, LogWriter};
use crate::ambient::{Ambient, ValueId};
use crate::session::store::{add_time, AmbientStore, FlushPolicy, Peers};
use crate::session::Session;
use anyhow::{anyhow, Result};
use glam::DVec3;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

struct Readers {
    logs: HashMap<String, LogReader>,
    /// Invalid records already counted, per log.
    invalid: HashMap<String, u64>,
    refused: HashSet<String>,
    seen: HashSet<ValueId>,
}

/// The other workers' logs of a job, read into this worker's cache.
pub struct JobPeers {
    job: JobDir,
    own_name: String,
    fingerprint: [u8; 32],
    origin: DVec3,
    ambient: Arc<Ambient>,
    readers: Mutex<Readers>,
    warnings: Mutex<Vec<String>>,
    /// Invalid records skipped in the peers' logs.
    rejected: AtomicU64,
}

/// Open the worker's own log, load the merged store and every other log, and return the
/// session's ambient store for the job (attach it with [`Session::attach_store`]).
pub fn open_share(
    job: &JobDir,
    owner: &str,
    session: &Session,
    policy: FlushPolicy,
) -> Result<Arc<AmbientStore>> {
    let ambient = session
        .cached_ambient()
        .cloned()
        .ok_or_else(|| anyhow!("no ambient values to share"))?;
    let writer = LogWriter::open(&job.amb_log(owner), &session.log_header(), false)?;
    let t = Instant::now();
    let peers = JobPeers {
        job: job.clone(),
        own_name: format!("{owner}.log"),
        fingerprint: session.fingerprint,
        origin: session.scene.origin,
        ambient: ambient.clone(),
        readers: Mutex::new(Readers {
            logs: HashMap::new(),
            refused: HashSet::new(),
            invalid: HashMap::new(),
            seen: HashSet::new(),
        }),
        warnings: Mutex::new(Vec::new()),
        rejected: AtomicU64::new(0),
    };
    // The merged store first, then only the log tails after it.
    let mut n = peers.load_merged()?;
    n += peers.read(true, true);
    let origin = session.scene.origin;
    let store = AmbientStore::new(ambient, writer, origin, policy, Some(Box::new(peers)));
    store.counters().shared_in.fetch_add(n, Ordering::Relaxed);
    add_time(&store.counters().sync_ns, t.elapsed());
    Ok(Arc::new(store))
}

impl JobPeers {
    /// Insert the merged store's values and start each log it includes after the offset it
    /// reached. Returns the number of values inserted.
    fn load_merged(&self) -> Result<u64> {
        let Some(store) = super::merge::load_store(&self.job, &self.fingerprint, false)? else {
            return Ok(0);
        };
        let mut rd = self.readers.lock().unwrap_or_else(|e| e.into_inner());
        let mut n = 0;
        for r in &store.records {
            if rd.seen.insert(r.id) {
                self.ambient
                    .cache
                    .insert(CachedValue::from_record(r, self.origin));
                n += 1;
            }
        }
        for (name, off) in &store.index.logs {
            if *name == self.own_name {
                continue;
            }
            let path = self.job.amb().join(name);
            if let Ok(mut r) = LogReader::open(&path, Some(&self.fingerprint), false) {
                r.set_offset(*off);
                rd.logs.insert(name.clone(), r);
            }
        }
        Ok(n)
    }

    /// Open the logs of `amb/` not yet known (a directory listing).
    fn list_logs(&self, rd: &mut Readers) {
        let Ok(dir) = std::fs::read_dir(self.job.amb()) else {
            return;
        };
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
            // A job's logs are its workers' regular files: not links, FIFOs or devices.
            if !crate::safefile::is_plain_file(&e.path()) {
                self.warn(format!(
                    "ignoring ambient log {}: not a regular file",
                    e.path().display()
                ));
                rd.refused.insert(name);
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

    fn warn(&self, w: String) {
        if let Ok(mut v) = self.warnings.lock() {
            if !v.contains(&w) {
                eprintln!("tpiece: warning - {w}");
                v.push(w);
            }
        }
    }
}

impl Peers for JobPeers {
    fn read(&self, wait: bool, list: bool) -> u64 {
        let mut rd = if wait {
            self.readers.lock().unwrap_or_else(|e| e.into_inner())
        } else {
            match self.readers.try_lock() {
                Ok(g) => g,
                Err(_) => return 0,
            }
        };
        let rd = &mut *rd;
        if list {
            self.list_logs(rd);
        }
        let mut added = 0;
        for (name, r) in rd.logs.iter_mut() {
            let Ok(records) = r.read_available() else {
                continue;
            };
            let counted = rd.invalid.entry(name.clone()).or_insert(0);
            if r.invalid() > *counted {
                let new = r.invalid() - *counted;
                *counted = r.invalid();
                self.rejected.fetch_add(new, Ordering::Relaxed);
                self.warn(format!(
                    "ambient log {name}: {} invalid records skipped",
                    r.invalid()
                ));
            }
            for rec in records {
                if rd.seen.insert(rec.id) {
                    self.ambient
                        .cache
                        .insert(CachedValue::from_record(&rec, self.origin));
                    added += 1;
                }
            }
        }
        added
    }

    fn rejected(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }
}
