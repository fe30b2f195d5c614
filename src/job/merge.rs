//! The merged ambient store (`tmerge`): every worker log's whole records, deduplicated by
//! value id, in one compacted file that later workers, frames and jobs load instead of
//! re-reading every log from its start.
//!
//! `merged/store.json` (the index) names the store file and the byte offset of every worker
//! log up to which the store includes it:
//!
//! ```json
//! {"format": "tessera-ambient-store", "version": 1, "fingerprint": "…",
//!  "store": "store-1a2b3c4d.log", "records": 1234, "logs": {"w1.0a1b2c3d.log": 98765}}
//! ```
//!
//! A merge reads the current index and store, reads each log from its recorded offset (whole
//! records only: a torn tail is left for the next merge), writes a new store under a new
//! unique name (temporary, fsync, rename without replacing), then renames a new index over
//! `store.json`, and finally removes the store it replaced. Readers therefore always find a
//! complete store named by a complete index; a reader that opens an index whose store was just
//! removed reads the index again. Two merges at once each publish a complete store (the later
//! index wins; the other store file is left behind unused). Merging twice without new log
//! data writes nothing.

use super::JobDir;
use crate::ambient::log::{encode_log, LogHeader, LogReader, LogTail, LOG_MAGIC};
use crate::ambient::{AmbRecord, ValueId};
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// `format` of `store.json`.
pub const STORE_FORMAT: &str = "tessera-ambient-store";

/// The store index (`merged/store.json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StoreIndex {
    /// [`STORE_FORMAT`].
    pub format: String,
    /// 1.
    pub version: u32,
    /// Fingerprint of the scene and ambient options (hex).
    pub fingerprint: String,
    /// The store file in `merged/`.
    pub store: String,
    /// Records in the store.
    pub records: u64,
    /// Worker log name → byte offset included.
    pub logs: BTreeMap<String, u64>,
}

/// A loaded store: its index and records.
pub struct Store {
    /// The index.
    pub index: StoreIndex,
    /// The records.
    pub records: Vec<AmbRecord>,
}

fn index_path(job: &JobDir) -> PathBuf {
    job.merged().join("store.json")
}

/// Load the current merged store, if there is one.
pub fn load_store(job: &JobDir, fingerprint: &[u8; 32], force: bool) -> Result<Option<Store>> {
    let ip = index_path(job);
    for _attempt in 0..20 {
        let text = match crate::safefile::read_text_bounded(&ip, 1 << 20) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(anyhow!("cannot read {}: {e}", ip.display())),
        };
        let index: StoreIndex = serde_json::from_str(&text)
            .map_err(|e| anyhow!("{}:{}: bad store index: {e}", ip.display(), e.line()))?;
        if index.format != STORE_FORMAT || index.version != 1 {
            bail!("{}: not a version-1 store index", ip.display());
        }
        super::check_plain_name(&index.store)
            .with_context(|| format!("{}: store", ip.display()))?;
        for name in index.logs.keys() {
            super::check_plain_name(name).with_context(|| format!("{}: log name", ip.display()))?;
        }
        let sp = job.merged().join(&index.store);
        let mut reader = match LogReader::open(&sp, Some(fingerprint), force) {
            Ok(r) => r,
            Err(crate::ambient::log::AmbLogError::Io { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                // Replaced by a concurrent merge between our two reads: read the index again.
                std::thread::sleep(std::time::Duration::from_millis(20));
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        let records = reader.read_available()?;
        if *reader.tail() != LogTail::Clean {
            bail!(
                "merged store {} is damaged: {:?}",
                sp.display(),
                reader.tail()
            );
        }
        return Ok(Some(Store { index, records }));
    }
    bail!(
        "{}: the store it names keeps disappearing (merges running in a loop?)",
        ip.display()
    )
}

/// Write a store and publish it with an index; returns the store file name.
fn publish(
    job: &JobDir,
    header: &LogHeader,
    records: &[AmbRecord],
    mut index: StoreIndex,
) -> Result<String> {
    let bytes = encode_log(header, records);
    let dir = job.merged();
    // A job whose merged/ was deleted gets it back (its index is gone with it: the merge
    // reads every log from the start).
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut tmp = tempfile::Builder::new()
        .prefix(".store-")
        .suffix(".tmp")
        .tempfile_in(&dir)
        .with_context(|| format!("cannot create a store in {}", dir.display()))?;
    use std::io::Write;
    tmp.write_all(&bytes)
        .and_then(|()| tmp.as_file().sync_all())
        .with_context(|| format!("cannot write a store in {}", dir.display()))?;
    let mut name = String::new();
    let mut tmp = Some(tmp);
    for _ in 0..100 {
        let cand = format!("store-{:08x}.log", rand_u32());
        let t = tmp.take().ok_or_else(|| anyhow!("store temporary lost"))?;
        match t.persist_noclobber(dir.join(&cand)) {
            Ok(_) => {
                name = cand;
                break;
            }
            Err(e) if e.error.kind() == std::io::ErrorKind::AlreadyExists => tmp = Some(e.file),
            Err(e) => {
                return Err(anyhow!(
                    "cannot name the store in {}: {}",
                    dir.display(),
                    e.error
                ))
            }
        }
    }
    if name.is_empty() {
        bail!("cannot find a free store name in {}", dir.display());
    }
    index.store = name.clone();
    index.records = records.len() as u64;
    let json = serde_json::to_string_pretty(&index)?;
    super::write_file_atomic(&index_path(job), json.as_bytes())
        .with_context(|| format!("cannot write {}", index_path(job).display()))?;
    super::sync_dir(&dir);
    Ok(name)
}

/// A random 32-bit number (process id, time and a counter through a mixer).
pub fn rand_u32() -> u32 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0);
    let mut x = t
        ^ ((std::process::id() as u64) << 32)
        ^ COUNTER.fetch_add(0x9E37_79B9_7F4A_7C15, Ordering::Relaxed);
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^= x >> 33;
    x as u32
}

/// What a merge did.
#[derive(Debug, Default, Serialize)]
pub struct MergeReport {
    /// Worker logs read.
    pub logs: usize,
    /// Records added by this merge.
    pub added: u64,
    /// Records in the store after it.
    pub total: u64,
    /// Duplicate records skipped.
    pub duplicates: u64,
    /// Logs whose last record was incomplete (left for the next merge).
    pub torn: Vec<String>,
    /// Logs with a damaged record (read up to it), with the reason.
    pub corrupt: Vec<String>,
    /// Logs with whole records skipped as invalid (non-finite or absurd values), with the
    /// count.
    pub invalid: Vec<(String, u64)>,
    /// Logs refused (another fingerprint), with the reason.
    pub refused: Vec<String>,
    /// The store file now published (None when nothing changed).
    pub written: Option<String>,
}

/// Merge every worker log into the store (see the module documentation).
pub fn merge(job: &JobDir, fingerprint: &[u8; 32], options: &str) -> Result<MergeReport> {
    let prev = load_store(job, fingerprint, false)?;
    let mut report = MergeReport::default();
    let (mut index, mut records) = match prev {
        Some(s) => (s.index, s.records),
        None => (
            StoreIndex {
                format: STORE_FORMAT.into(),
                version: 1,
                fingerprint: super::hex32(fingerprint),
                ..StoreIndex::default()
            },
            Vec::new(),
        ),
    };
    let old_store = index.store.clone();
    let mut seen: HashSet<ValueId> = records.iter().map(|r| r.id).collect();
    let before = index.logs.clone();
    let mut names: Vec<String> = Vec::new();
    for e in std::fs::read_dir(job.amb())
        .with_context(|| format!("cannot list {}", job.amb().display()))?
    {
        let e = e?;
        if let Some(n) = e.file_name().to_str() {
            if n.ends_with(".log") && !n.starts_with('.') {
                names.push(n.to_string());
            }
        }
    }
    names.sort();
    for name in names {
        let path = job.amb().join(&name);
        if !crate::safefile::is_plain_file(&path) {
            report.refused.push(format!("{name}: not a regular file"));
            continue;
        }
        let mut r = match LogReader::open(&path, Some(fingerprint), false) {
            Ok(r) => r,
            Err(crate::ambient::log::AmbLogError::HeaderTruncated { .. }) => {
                // Being created right now: next time.
                report.torn.push(name.clone());
                continue;
            }
            Err(e) => {
                report.refused.push(format!("{name}: {e}"));
                continue;
            }
        };
        report.logs += 1;
        if let Some(&off) = index.logs.get(&name) {
            r.set_offset(off);
        }
        for rec in r.read_available()? {
            if seen.insert(rec.id) {
                records.push(rec);
                report.added += 1;
            } else {
                report.duplicates += 1;
            }
        }
        if r.invalid() > 0 {
            report.invalid.push((name.clone(), r.invalid()));
        }
        match r.tail() {
            LogTail::Clean => {}
            LogTail::Torn { .. } => report.torn.push(name.clone()),
            LogTail::Corrupt { offset, reason } => report
                .corrupt
                .push(format!("{name}: byte {offset}: {reason}")),
        }
        index.logs.insert(name, r.offset());
    }
    report.total = records.len() as u64;
    if report.added == 0 && index.logs == before && !old_store.is_empty() {
        return Ok(report);
    }
    let header = LogHeader::new(*fingerprint, options);
    let name = publish(job, &header, &records, index)?;
    if !old_store.is_empty() && old_store != name {
        let _ = std::fs::remove_file(job.merged().join(&old_store));
    }
    report.written = Some(name);
    Ok(report)
}

/// Read the records of an ambient store to seed a job with (`tplan --ambient FILE`): a
/// Tessera log or store (fingerprint checked unless `force`) or a Radiance ambient file
/// (which carries no fingerprint).
pub fn read_any_store(path: &Path, fingerprint: &[u8; 32], force: bool) -> Result<Vec<AmbRecord>> {
    let mut magic = [0u8; 10];
    let is_log = crate::safefile::open_regular(path, true)
        .and_then(|mut f| {
            use std::io::Read;
            f.read_exact(&mut magic)
        })
        .map(|()| &magic == LOG_MAGIC)
        .unwrap_or(false);
    if is_log {
        let mut r = LogReader::open(path, Some(fingerprint), force)?;
        Ok(r.read_available()?)
    } else {
        let (_, mut recs, _) = crate::ambient::radfile::read_file(path)
            .with_context(|| format!("cannot read ambient file {}", path.display()))?;
        // Radiance's records carry no id: give them stable ones, an origin named by the
        // records' content and their order, so that they stay distinct from each other
        // (deduplication is by id) and seeding from the same file twice yields the same ids.
        let mut h = crc32fast::Hasher::new();
        for r in &recs {
            for x in r.pos.to_array().iter().chain(&r.ndir.to_array()) {
                h.update(&x.to_le_bytes());
            }
            for x in r.val.iter().chain(&r.rad) {
                h.update(&x.to_le_bytes());
            }
        }
        let origin = (1u64 << 63) | (u64::from(h.finalize()) << 16) | 0x5261;
        for (seq, r) in recs.iter_mut().enumerate() {
            r.id = crate::ambient::ValueId {
                origin,
                seq: seq as u64,
            };
        }
        Ok(recs)
    }
}

/// Create a job's first store from an existing store file.
pub fn seed_store(job: &JobDir, path: &Path, fingerprint: &[u8; 32], force: bool) -> Result<u64> {
    let mut recs = read_any_store(path, fingerprint, force)?;
    let mut seen = HashSet::new();
    recs.retain(|r| seen.insert(r.id));
    let index = StoreIndex {
        format: STORE_FORMAT.into(),
        version: 1,
        fingerprint: super::hex32(fingerprint),
        ..StoreIndex::default()
    };
    let header = LogHeader::new(*fingerprint, &format!("seeded from {}", path.display()));
    publish(job, &header, &recs, index)?;
    Ok(recs.len() as u64)
}

/// Write records in Radiance's ambient format (for `rpict -af`), atomically.
pub fn export_radiance(path: &Path, records: &[AmbRecord], options_line: &str) -> Result<()> {
    use crate::ambient::radfile;
    let mut out = Vec::new();
    radfile::write_header(&mut out, options_line, crate::runinfo::SOFTWARE)?;
    for r in records {
        radfile::write_record(&mut out, r)?;
    }
    super::write_file_atomic(path, &out)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}
