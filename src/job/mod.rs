//! The batch toolkit's job directory protocol, shared by `tplan`, `tpiece`, `tmerge`,
//! `tassemble` and `tstat` (the full protocol and why each step is safe on NFS:
//! `docs/batch.md`).
//!
//! ```text
//! JOB/manifest.json            what to render (written once by tplan, then read-only)
//! JOB/scene.rad                the scene, flattened (inline commands and xform expanded)
//! JOB/files/                   files the scene reads by relative name (.cal, .dat, pictures,
//!                              fonts, text), copied by tplan; workers look here first
//! JOB/tasks/<task>.todo        a tile nobody has claimed
//! JOB/tasks/<task>.claim.<owner>   claimed by a worker incarnation
//! JOB/tasks/<task>.done        finished (its result is in tiles/)
//! JOB/tasks/<piece>.todo       a part of a tile split off while it rendered (job::piece),
//!                              in the same states as a tile
//! JOB/tiles/<task>.tile        a tile's pixels (written to a temporary, fsynced, renamed)
//! JOB/amb/<owner>.log          each worker's append-only ambient log (one writer)
//! JOB/workers/<owner>.json     each worker's heartbeat and counters (rewritten atomically)
//! JOB/merged/store.json        the merged ambient store's index (names its store file)
//! JOB/merged/store-<n>.log     a merged store (Tessera's ambient log format)
//! JOB/budget/f<frame>.json     with -axt: each frame's -aa, decided once (job::budget)
//! JOB/logs/                    free for batch-system output (slurm/)
//! ```
//!
//! A task is `f<frame>-t<tile>` (five digits each); an owner is `<worker-id>.<nonce>` where
//! the nonce (8 hex digits) makes every worker process distinct even when two share an id.
//! Every state change is one `rename(2)` inside one directory, so exactly one process wins
//! each race, and nothing depends on file locks, `O_APPEND` across hosts, or clocks agreeing.

pub mod assemble;
pub mod budget;
pub mod cli;
pub mod commit;
pub mod finish;
pub mod heartbeat;
mod jobscene;
pub mod manifest;
pub mod merge;
pub mod path;
pub mod piece;
pub mod plan;
pub mod points;
pub mod probe;
pub mod rad;
pub mod share;
pub mod sheet;
pub mod siblings;
pub mod split;
pub mod status;
pub mod task;
pub mod tile;
pub mod worker;

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// A job directory.
#[derive(Clone, Debug)]
pub struct JobDir {
    root: PathBuf,
}

impl JobDir {
    /// The job directory at `root` (not checked).
    pub fn new(root: impl Into<PathBuf>) -> JobDir {
        JobDir { root: root.into() }
    }
    /// The directory itself.
    pub fn root(&self) -> &Path {
        &self.root
    }
    /// `manifest.json`.
    pub fn manifest(&self) -> PathBuf {
        self.root.join("manifest.json")
    }
    /// A file in the job root.
    pub fn file(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }
    /// `tasks/`.
    pub fn tasks(&self) -> PathBuf {
        self.root.join("tasks")
    }
    /// `tiles/`.
    pub fn tiles(&self) -> PathBuf {
        self.root.join("tiles")
    }
    /// `amb/`.
    pub fn amb(&self) -> PathBuf {
        self.root.join("amb")
    }
    /// `workers/`.
    pub fn workers(&self) -> PathBuf {
        self.root.join("workers")
    }
    /// `merged/`.
    pub fn merged(&self) -> PathBuf {
        self.root.join("merged")
    }
    /// The result file of a task.
    pub fn tile_file(&self, task: &str) -> PathBuf {
        self.tiles().join(format!("{task}.tile"))
    }
    /// The ambient log of a worker incarnation.
    pub fn amb_log(&self, owner: &str) -> PathBuf {
        self.amb().join(format!("{owner}.log"))
    }
    /// The heartbeat file of a worker incarnation.
    pub fn worker_file(&self, owner: &str) -> PathBuf {
        self.workers().join(format!("{owner}.json"))
    }
    /// Every subdirectory a job has.
    pub fn subdirs(&self) -> [PathBuf; 6] {
        [
            self.tasks(),
            self.tiles(),
            self.amb(),
            self.workers(),
            self.merged(),
            self.root.join("logs"),
        ]
    }
}

/// The name of a task: `f<frame>-t<tile>`.
pub fn task_name(frame: u32, tile: usize) -> String {
    format!("f{frame:05}-t{tile:05}")
}

/// Parse a task name back to (frame, tile).
pub fn parse_task_name(name: &str) -> Option<(u32, usize)> {
    let rest = name.strip_prefix('f')?;
    let (f, t) = rest.split_once("-t")?;
    if f.len() != 5 || t.len() != 5 {
        return None;
    }
    if !f.bytes().all(|b| b.is_ascii_digit()) || !t.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((f.parse().ok()?, t.parse().ok()?))
}

/// Longest worker id.
pub const MAX_ID_LEN: usize = 64;

/// Largest picture side accepted (a frame's, a point job's rows).
pub const MAX_RES: usize = 1 << 15;

/// Check a worker id: 1–64 characters of `A-Z a-z 0-9 _ -` (no path separators, dots or
/// `..`, so ids can never name a file outside the job).
pub fn check_worker_id(id: &str) -> Result<()> {
    if id.is_empty() || id.len() > MAX_ID_LEN {
        bail!("worker id '{id}' must have 1 to {MAX_ID_LEN} characters");
    }
    if let Some(c) = id
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '-'))
    {
        bail!("worker id '{id}' contains '{c}'; only letters, digits, '_' and '-' are allowed");
    }
    Ok(())
}

/// Check an owner name `<worker-id>.<8 hex digits>`.
pub fn check_owner(owner: &str) -> Result<()> {
    let Some((id, nonce)) = owner.rsplit_once('.') else {
        bail!("owner '{owner}' lacks its '.<nonce>'");
    };
    check_worker_id(id)?;
    if nonce.len() != 8 || !nonce.bytes().all(|b| b.is_ascii_hexdigit()) {
        bail!("owner '{owner}': the nonce must be 8 hex digits");
    }
    Ok(())
}

/// The default worker id: `$SLURM_ARRAY_JOB_ID-$SLURM_ARRAY_TASK_ID` under a SLURM array,
/// `$SLURM_JOB_ID` under another SLURM job, else `<host>-<pid>` (characters outside the
/// allowed set become `_`).
pub fn default_worker_id() -> String {
    let var = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    let raw = match (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
        (Some(j), Some(t)) => format!("{j}-{t}"),
        _ => match var("SLURM_JOB_ID") {
            Some(j) => j,
            None => {
                let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
                    .ok()
                    .or_else(|| var("HOSTNAME"))
                    .unwrap_or_else(|| "host".into());
                format!("{}-{}", host.trim(), std::process::id())
            }
        },
    };
    let mut id: String = raw
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    id.truncate(MAX_ID_LEN);
    if id.is_empty() {
        id.push('w');
    }
    id
}

/// Fingerprint bytes as lowercase hex.
pub fn hex32(f: &[u8; 32]) -> String {
    crate::ambient::log::fingerprint_hex(f)
}

/// Parse 64 hex digits.
pub fn parse_hex32(s: &str) -> Option<[u8; 32]> {
    if s.len() != 64 {
        return None;
    }
    let mut out = [0u8; 32];
    for (i, o) in out.iter_mut().enumerate() {
        *o = u8::from_str_radix(s.get(2 * i..2 * i + 2)?, 16).ok()?;
    }
    Some(out)
}

/// Seconds since the Unix epoch (informational only: never used to judge staleness).
pub fn unix_now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// The length and CRC-32 of a regular file, read in pieces (a large scene is not held).
pub fn file_crc(path: &Path) -> Result<(u64, u32)> {
    use std::io::Read;
    let mut f = crate::safefile::open_regular(path, false)
        .with_context(|| format!("cannot open {}", path.display()))?;
    let mut h = crc32fast::Hasher::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut len = 0u64;
    loop {
        let n = f
            .read(&mut buf)
            .with_context(|| format!("cannot read {}", path.display()))?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
        len += n as u64;
    }
    Ok((len, h.finalize()))
}

/// Write `bytes` to `path` atomically (temporary in the same directory, fsync, rename).
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    crate::image::output::write_atomic(path, |f| f.write_all(bytes))
}

/// fsync a directory so that a rename in it is durable (best effort: some file systems
/// refuse to open directories for this).
pub fn sync_dir(dir: &Path) {
    if let Ok(f) = crate::safefile::open_dir(dir) {
        let _ = f.sync_all();
    }
}

/// A file name with no directory part, not `.`/`..`, not hidden.
pub fn check_plain_name(name: &str) -> Result<()> {
    if name.is_empty()
        || name.contains('/')
        || name.contains('\\')
        || name.starts_with('.')
        || name.contains('\0')
    {
        bail!("'{name}' must be a plain file name inside the job directory");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        assert_eq!(task_name(3, 17), "f00003-t00017");
        assert_eq!(parse_task_name("f00003-t00017"), Some((3, 17)));
        assert_eq!(parse_task_name("f3-t17"), None);
        assert_eq!(parse_task_name("f00003-t0001x"), None);
        for bad in ["", "..", "a/b", "a.b", "x y", &"z".repeat(65)] {
            assert!(check_worker_id(bad).is_err(), "{bad:?}");
        }
        check_worker_id("123-4").unwrap();
        check_owner("123-4.0a1b2c3d").unwrap();
        assert!(check_owner("123-4.0a1b2c3").is_err());
        assert!(check_owner("../x.0a1b2c3d").is_err());
        check_worker_id(&default_worker_id()).unwrap();
        let f = [0xa5u8; 32];
        assert_eq!(parse_hex32(&hex32(&f)), Some(f));
    }

    #[test]
    fn plain_names() {
        check_plain_name("scene.rad").unwrap();
        for bad in ["", "../x", "a/b", ".hidden", "..", "/etc/passwd"] {
            assert!(check_plain_name(bad).is_err(), "{bad}");
        }
    }
}
