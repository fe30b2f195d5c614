//! Tessera's append-only ambient log: one file per writing process, read by any number of
//! other processes while it grows, without locks.
//!
//! Layout (all integers little-endian; byte by byte in `docs/ambient-formats.md`):
//!
//! ```text
//! header:  "TSRAMBLOG\n" | version u32 | fingerprint [u8;32] | options_len u32 | options (UTF-8)
//!          | CRC32 of all the header bytes before it (u32)
//! frames:  payload_len u32 | CRC32(payload) u32 | payload (141 bytes; 137 in version 2, 133
//!          in version 1)
//! payload: id.origin u64 | id.seq u64 | pos 3×f64 | ndir 3×f64 | udir 3×f64 | lvl u8
//!          | weight f32 | rad 2×f32 | gpos 2×f32 | gdir 2×f32 | corral u32 | val 3×f32
//!          | reach f32 (from version 2; absent in version 1 and read as 1)
//!          | share f32 (from version 3; absent before and read as 1)
//! ```
//!
//! A writer ([`LogWriter`]) queues records and appends each batch with one `write()`, so a
//! reader sees whole batches, or a prefix of the last one (a torn tail). A reader
//! ([`LogReader`]) returns whole, CRC-valid records, stops without error at a torn tail and
//! resumes from there on its next call; a frame whose CRC or length is wrong, with bytes after
//! it, is reported as corruption at its offset. The header's fingerprint (a hash of the scene
//! and the options that change ambient values, supplied by the caller) is checked on open, so
//! a stale log is refused unless forced.

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{AmbRecord, ValueId};

/// Magic bytes at the start of every log.
pub const LOG_MAGIC: &[u8; 10] = b"TSRAMBLOG\n";
/// Version of the log format written by this code (versions 1 and 2 are read too).
pub const LOG_VERSION: u32 = 3;
/// Size of a record payload as written (version 3).
pub const PAYLOAD_SIZE: usize = 141;
/// Size of a version-2 record payload (without `share`).
pub const PAYLOAD_SIZE_V2: usize = 137;
/// Size of a version-1 record payload (without `reach`): the shortest payload accepted.
pub const PAYLOAD_SIZE_V1: usize = 133;
/// Size of a frame's prefix (length and CRC).
pub const FRAME_PREFIX: usize = 8;
/// Longest option text accepted in a header.
const MAX_OPTIONS: usize = 1 << 20;
/// Longest payload accepted in a frame (longer ones are corruption).
const MAX_PAYLOAD: usize = 1 << 16;
/// Size of the fixed part of the header (magic, version, fingerprint, options length).
const HEADER_FIXED: usize = 10 + 4 + 32 + 4;

/// Errors of the ambient log. Each names the file; corruption names the byte offset.
#[derive(Debug, thiserror::Error)]
pub enum AmbLogError {
    /// An I/O error.
    #[error("ambient log {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The file does not start with the log's magic bytes.
    #[error("ambient log {path}: not a Tessera ambient log (bad magic bytes)")]
    NotALog {
        /// The file.
        path: PathBuf,
    },
    /// The file ends inside the header.
    #[error(
        "ambient log {path}: header truncated ({len} bytes; a complete header is at least {need})"
    )]
    HeaderTruncated {
        /// The file.
        path: PathBuf,
        /// Length of the file.
        len: u64,
        /// Bytes needed for a complete header.
        need: u64,
    },
    /// The header is damaged (bad CRC, bad option text).
    #[error("ambient log {path}: corrupt header at byte {offset}: {reason}")]
    HeaderCorrupt {
        /// The file.
        path: PathBuf,
        /// Byte offset of the problem.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// The log was written by another version of the format.
    #[error("ambient log {path}: format version {found}, this program reads version {expected}")]
    Version {
        /// The file.
        path: PathBuf,
        /// The file's version.
        found: u32,
        /// [`LOG_VERSION`].
        expected: u32,
    },
    /// The log was made for another scene or other ambient options.
    #[error(
        "ambient log {path} was made for another scene or other ambient options: its fingerprint \
         is {found}, the current scene and options give {expected}; remove the file, use another \
         one, or force its use"
    )]
    Fingerprint {
        /// The file.
        path: PathBuf,
        /// The file's fingerprint (hex).
        found: String,
        /// The expected fingerprint (hex).
        expected: String,
    },
    /// A frame with a bad length or CRC, followed by more data.
    #[error("ambient log {path}: corrupt record at byte {offset}: {reason}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// Byte offset of the corrupt frame.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
}

/// The header of an ambient log.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogHeader {
    /// Format version ([`LOG_VERSION`] for new logs).
    pub version: u32,
    /// Caller-supplied hash of the scene content and the options that change ambient values.
    pub fingerprint: [u8; 32],
    /// Option text, informational only.
    pub options: String,
}

impl LogHeader {
    /// A header for a new log of the current version.
    pub fn new(fingerprint: [u8; 32], options: &str) -> LogHeader {
        LogHeader {
            version: LOG_VERSION,
            fingerprint,
            options: options.to_string(),
        }
    }

    /// The header's bytes as written at the start of a log.
    pub fn to_bytes(&self) -> Vec<u8> {
        let opts = self.options.as_bytes();
        let mut b = Vec::with_capacity(HEADER_FIXED + opts.len() + 4);
        b.extend_from_slice(LOG_MAGIC);
        b.extend_from_slice(&self.version.to_le_bytes());
        b.extend_from_slice(&self.fingerprint);
        b.extend_from_slice(&(opts.len() as u32).to_le_bytes());
        b.extend_from_slice(opts);
        let crc = crc32fast::hash(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }
}

/// Lowercase hex of a fingerprint.
pub fn fingerprint_hex(f: &[u8; 32]) -> String {
    f.iter().map(|b| format!("{b:02x}")).collect()
}

/// Parse a header from the start of `data` (`file_len` is the file's length, for messages).
/// Returns the header and its size in bytes.
fn parse_header(path: &Path, data: &[u8], file_len: u64) -> Result<(LogHeader, u64), AmbLogError> {
    let truncated = |need: usize| AmbLogError::HeaderTruncated {
        path: path.to_path_buf(),
        len: file_len,
        need: need as u64,
    };
    let magic_len = LOG_MAGIC.len().min(data.len());
    if data[..magic_len] != LOG_MAGIC[..magic_len] {
        return Err(AmbLogError::NotALog {
            path: path.to_path_buf(),
        });
    }
    if data.len() < HEADER_FIXED {
        return Err(truncated(HEADER_FIXED + 4));
    }
    let u32at = |o: usize| u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]);
    let version = u32at(10);
    if !(1..=LOG_VERSION).contains(&version) {
        return Err(AmbLogError::Version {
            path: path.to_path_buf(),
            found: version,
            expected: LOG_VERSION,
        });
    }
    let mut fingerprint = [0u8; 32];
    fingerprint.copy_from_slice(&data[14..46]);
    let olen = u32at(46) as usize;
    if olen > MAX_OPTIONS {
        return Err(AmbLogError::HeaderCorrupt {
            path: path.to_path_buf(),
            offset: 46,
            reason: format!("option text length {olen} is too large"),
        });
    }
    let end = HEADER_FIXED + olen;
    if data.len() < end + 4 {
        return Err(truncated(end + 4));
    }
    let crc = u32at(end);
    if crc != crc32fast::hash(&data[..end]) {
        return Err(AmbLogError::HeaderCorrupt {
            path: path.to_path_buf(),
            offset: end as u64,
            reason: "header CRC mismatch".into(),
        });
    }
    let options = String::from_utf8(data[HEADER_FIXED..end].to_vec()).map_err(|_| {
        AmbLogError::HeaderCorrupt {
            path: path.to_path_buf(),
            offset: HEADER_FIXED as u64,
            reason: "option text is not UTF-8".into(),
        }
    })?;
    Ok((
        LogHeader {
            version,
            fingerprint,
            options,
        },
        (end + 4) as u64,
    ))
}

/// Read and parse the header of the open file `f`.
fn read_header(path: &Path, f: &mut File) -> Result<(LogHeader, u64), AmbLogError> {
    let io_err = |source| AmbLogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let len = f.metadata().map_err(io_err)?.len();
    f.seek(SeekFrom::Start(0)).map_err(io_err)?;
    let mut data = Vec::new();
    f.take((HEADER_FIXED + MAX_OPTIONS + 4) as u64)
        .read_to_end(&mut data)
        .map_err(io_err)?;
    parse_header(path, &data, len)
}

/// Check a header's fingerprint against `expect`.
fn check_fingerprint(
    path: &Path,
    h: &LogHeader,
    expect: &[u8; 32],
    force: bool,
) -> Result<(), AmbLogError> {
    if !force && h.fingerprint != *expect {
        return Err(AmbLogError::Fingerprint {
            path: path.to_path_buf(),
            found: fingerprint_hex(&h.fingerprint),
            expected: fingerprint_hex(expect),
        });
    }
    Ok(())
}

/// Encode a record's payload (full precision, little-endian).
pub fn encode_payload(r: &AmbRecord) -> [u8; PAYLOAD_SIZE] {
    let mut b = [0u8; PAYLOAD_SIZE];
    let mut o = 0;
    let mut put = |bytes: &[u8]| {
        b[o..o + bytes.len()].copy_from_slice(bytes);
        o += bytes.len();
    };
    put(&r.id.origin.to_le_bytes());
    put(&r.id.seq.to_le_bytes());
    for v in [r.pos, r.ndir, r.udir] {
        for c in v.to_array() {
            put(&c.to_le_bytes());
        }
    }
    put(&[r.lvl]);
    put(&r.weight.to_le_bytes());
    for c in r.rad.iter().chain(&r.gpos).chain(&r.gdir) {
        put(&c.to_le_bytes());
    }
    put(&r.corral.to_le_bytes());
    for c in r.val {
        put(&c.to_le_bytes());
    }
    put(&r.reach.to_le_bytes());
    put(&r.share.to_le_bytes());
    debug_assert_eq!(o, PAYLOAD_SIZE);
    b
}

/// Decode a payload: at least [`PAYLOAD_SIZE_V1`] bytes (a version-1 payload, whose `reach`
/// is 1; a version-2 payload has no `share`, read as 1); bytes after the version-3 fields
/// are ignored.
pub fn decode_payload(b: &[u8]) -> Option<AmbRecord> {
    if b.len() < PAYLOAD_SIZE_V1 {
        return None;
    }
    let mut o = 0;
    let mut take = |n: usize| {
        let s = &b[o..o + n];
        o += n;
        s
    };
    let u64_ = |s: &[u8]| u64::from_le_bytes(s.try_into().unwrap_or([0; 8]));
    let f64_ = |s: &[u8]| f64::from_le_bytes(s.try_into().unwrap_or([0; 8]));
    let f32_ = |s: &[u8]| f32::from_le_bytes(s.try_into().unwrap_or([0; 4]));
    let origin = u64_(take(8));
    let seq = u64_(take(8));
    let mut vecs = [DVec3::ZERO; 3];
    for v in &mut vecs {
        *v = DVec3::new(f64_(take(8)), f64_(take(8)), f64_(take(8)));
    }
    let lvl = take(1)[0];
    let weight = f32_(take(4));
    let mut f6 = [0f32; 6];
    for v in &mut f6 {
        *v = f32_(take(4));
    }
    let corral = u32::from_le_bytes(take(4).try_into().unwrap_or([0; 4]));
    let val = [f32_(take(4)), f32_(take(4)), f32_(take(4))];
    let reach = if b.len() >= PAYLOAD_SIZE_V2 {
        f32_(take(4))
    } else {
        1.0
    };
    let share = if b.len() >= PAYLOAD_SIZE {
        f32_(take(4))
    } else {
        1.0
    };
    Some(AmbRecord {
        id: ValueId { origin, seq },
        pos: vecs[0],
        ndir: vecs[1],
        udir: vecs[2],
        lvl,
        weight,
        rad: [f6[0], f6[1]],
        gpos: [f6[2], f6[3]],
        gdir: [f6[4], f6[5]],
        corral,
        val,
        reach,
        share,
    })
}

/// How a scan of frames ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LogTail {
    /// Every byte was a whole, valid frame.
    Clean,
    /// The data ends inside a frame (a batch still being written, or a crash): `bytes` bytes
    /// from `offset` on were left for a later read.
    Torn {
        /// Offset of the incomplete frame.
        offset: u64,
        /// How many bytes of it are present.
        bytes: u64,
    },
    /// A frame with a bad length or CRC, with data after it; reading stops there.
    Corrupt {
        /// Offset of the bad frame.
        offset: u64,
        /// What is wrong.
        reason: String,
    },
}

/// What a scan of frames found: the valid records, the bytes of whole frames, how the scan
/// ended, and how many whole, CRC-valid frames held an invalid record
/// ([`AmbRecord::is_valid`]: non-finite or absurd values, as a crafted or damaged log may
/// hold), which are skipped.
struct Scan {
    records: Vec<AmbRecord>,
    used: usize,
    tail: LogTail,
    invalid: u64,
}

/// Scan frames in `data` (which starts at file offset `base`).
fn scan_frames(data: &[u8], base: u64) -> Scan {
    let (out, pos, tail, invalid) = scan_frames_inner(data, base);
    Scan {
        records: out,
        used: pos,
        tail,
        invalid,
    }
}

fn scan_frames_inner(data: &[u8], base: u64) -> (Vec<AmbRecord>, usize, LogTail, u64) {
    let mut out = Vec::new();
    let mut invalid = 0u64;
    let mut pos = 0usize;
    loop {
        let rest = &data[pos..];
        if rest.is_empty() {
            return (out, pos, LogTail::Clean, invalid);
        }
        let offset = base + pos as u64;
        let torn = LogTail::Torn {
            offset,
            bytes: rest.len() as u64,
        };
        // A zero-filled tail (what a crash can leave after a file was extended) is torn too.
        if rest.len() < FRAME_PREFIX || rest.iter().all(|&b| b == 0) {
            return (out, pos, torn, invalid);
        }
        let len = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]) as usize;
        let crc = u32::from_le_bytes([rest[4], rest[5], rest[6], rest[7]]);
        if !(PAYLOAD_SIZE_V1..=MAX_PAYLOAD).contains(&len) {
            let reason = format!("bad frame length {len}");
            return (out, pos, LogTail::Corrupt { offset, reason }, invalid);
        }
        if rest.len() < FRAME_PREFIX + len {
            return (out, pos, torn, invalid);
        }
        let payload = &rest[FRAME_PREFIX..FRAME_PREFIX + len];
        let actual = crc32fast::hash(payload);
        if actual != crc {
            let reason = format!("CRC mismatch (stored {crc:08x}, computed {actual:08x})");
            return (out, pos, LogTail::Corrupt { offset, reason }, invalid);
        }
        match decode_payload(payload) {
            Some(r) if r.is_valid() => out.push(r),
            Some(_) => invalid += 1,
            None => {
                let reason = "payload too short".to_string();
                return (out, pos, LogTail::Corrupt { offset, reason }, invalid);
            }
        }
        pos += FRAME_PREFIX + len;
    }
}

/// Append one framed record to `buf`.
fn push_frame(buf: &mut Vec<u8>, r: &AmbRecord) {
    let payload = encode_payload(r);
    buf.extend_from_slice(&(PAYLOAD_SIZE as u32).to_le_bytes());
    buf.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
    buf.extend_from_slice(&payload);
}

/// A whole log file's bytes: `header` then one frame per record (for stores written at
/// once, e.g. by `tmerge`).
pub fn encode_log(header: &LogHeader, records: &[AmbRecord]) -> Vec<u8> {
    let mut b = header.to_bytes();
    b.reserve(records.len() * (FRAME_PREFIX + PAYLOAD_SIZE));
    for r in records {
        push_frame(&mut b, r);
    }
    b
}

/// The writer of one ambient log: owns the file and appends batches of records.
#[derive(Debug)]
pub struct LogWriter {
    path: PathBuf,
    file: File,
    header: LogHeader,
    /// Framed records not yet written.
    buf: Vec<u8>,
    pending: usize,
    /// File length after the last successful flush.
    end: u64,
    fsync: bool,
    /// Test hook (`TESSERA_FAULT_LOG_ENOSPC` set when the log is opened): every flush fails
    /// as on a full disk.
    fault_enospc: bool,
}

impl LogWriter {
    /// Create a new log (fails if it exists) or reopen an existing one for appending after
    /// checking its header's fingerprint matches `header.fingerprint` (error
    /// [`AmbLogError::Fingerprint`] unless `force`; a forced reopen keeps the file's own
    /// header). A torn tail left by a crash is truncated first. A corrupt frame with data
    /// after it is an error unless `force`, which truncates the log there. A file whose header
    /// is truncated (a crash while creating it) is an error unless `force`, which rewrites it.
    pub fn open(path: &Path, header: &LogHeader, force: bool) -> Result<LogWriter, AmbLogError> {
        let io_err = |source| AmbLogError::Io {
            path: path.to_path_buf(),
            source,
        };
        match OpenOptions::new()
            .read(true)
            .append(true)
            .create_new(true)
            .open(path)
        {
            Ok(mut file) => {
                let bytes = header.to_bytes();
                file.write_all(&bytes).map_err(io_err)?;
                return Ok(Self::new(path, file, header.clone(), bytes.len() as u64));
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
            Err(e) => return Err(io_err(e)),
        }
        let mut file = OpenOptions::new()
            .read(true)
            .append(true)
            .open(path)
            .map_err(io_err)?;
        let (file_header, start) = match read_header(path, &mut file) {
            Ok(h) => h,
            Err(AmbLogError::HeaderTruncated { .. }) if force => {
                file.set_len(0).map_err(io_err)?;
                let bytes = header.to_bytes();
                file.write_all(&bytes).map_err(io_err)?;
                return Ok(Self::new(path, file, header.clone(), bytes.len() as u64));
            }
            Err(e) => return Err(e),
        };
        check_fingerprint(path, &file_header, &header.fingerprint, force)?;
        file.seek(SeekFrom::Start(start)).map_err(io_err)?;
        let mut data = Vec::new();
        file.read_to_end(&mut data).map_err(io_err)?;
        let Scan { used, tail, .. } = scan_frames(&data, start);
        let end = start + used as u64;
        match tail {
            LogTail::Clean => {}
            LogTail::Torn { .. } => file.set_len(end).map_err(io_err)?,
            LogTail::Corrupt { offset, reason } => {
                if !force {
                    return Err(AmbLogError::Corrupt {
                        path: path.to_path_buf(),
                        offset,
                        reason,
                    });
                }
                file.set_len(end).map_err(io_err)?;
            }
        }
        Ok(Self::new(path, file, file_header, end))
    }

    fn new(path: &Path, file: File, header: LogHeader, end: u64) -> LogWriter {
        LogWriter {
            path: path.to_path_buf(),
            file,
            header,
            buf: Vec::new(),
            pending: 0,
            end,
            fsync: false,
            fault_enospc: crate::fault::injected("LOG_ENOSPC"),
        }
    }

    /// The log's header (the file's own, for a forced reopen).
    pub fn header(&self) -> &LogHeader {
        &self.header
    }

    /// The log's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether [`flush`](Self::flush) also calls `fsync` (default: no).
    pub fn set_fsync(&mut self, on: bool) {
        self.fsync = on;
    }

    /// Queue a record; nothing is written until [`flush`](Self::flush) (batching: the caller
    /// flushes every N values).
    pub fn push(&mut self, r: &AmbRecord) {
        push_frame(&mut self.buf, r);
        self.pending += 1;
    }

    /// Append all queued records with one `write()` call (so a concurrent reader sees whole
    /// batches or a torn tail), then `fsync` if enabled. Returns how many records were
    /// written. On failure the file is cut back to its previous length (best effort) and the
    /// records stay queued.
    pub fn flush(&mut self) -> Result<usize, AmbLogError> {
        if self.pending == 0 {
            return Ok(0);
        }
        let res = if self.fault_enospc {
            Err(io::Error::from_raw_os_error(28))
        } else {
            self.file.write_all(&self.buf).and_then(|_| {
                if self.fsync {
                    self.file.sync_data()
                } else {
                    Ok(())
                }
            })
        };
        if let Err(source) = res {
            let _ = self.file.set_len(self.end);
            return Err(AmbLogError::Io {
                path: self.path.clone(),
                source,
            });
        }
        self.end += self.buf.len() as u64;
        self.buf.clear();
        Ok(std::mem::take(&mut self.pending))
    }

    /// Number of queued records.
    pub fn pending(&self) -> usize {
        self.pending
    }

    /// Length of the log after the last flush.
    pub fn len(&self) -> u64 {
        self.end
    }

    /// True when the log holds only its header (as of the last flush) and nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.pending == 0 && self.end == self.header.to_bytes().len() as u64
    }
}

impl Drop for LogWriter {
    /// Queued records are flushed (errors ignored).
    fn drop(&mut self) {
        let _ = self.flush();
    }
}

/// A reader of an ambient log that another process may still be appending to.
#[derive(Debug)]
pub struct LogReader {
    path: PathBuf,
    file: File,
    header: LogHeader,
    data_offset: u64,
    offset: u64,
    tail: LogTail,
    invalid: u64,
}

impl LogReader {
    /// Open a log and read its header; `expect = Some(fingerprint)` refuses a mismatch
    /// ([`AmbLogError::Fingerprint`], naming both) unless `force`.
    pub fn open(
        path: &Path,
        expect: Option<&[u8; 32]>,
        force: bool,
    ) -> Result<LogReader, AmbLogError> {
        let mut file =
            crate::safefile::open_regular(path, true).map_err(|source| AmbLogError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        let (header, start) = read_header(path, &mut file)?;
        if let Some(f) = expect {
            check_fingerprint(path, &header, f, force)?;
        }
        Ok(LogReader {
            path: path.to_path_buf(),
            file,
            header,
            data_offset: start,
            offset: start,
            tail: LogTail::Clean,
            invalid: 0,
        })
    }

    /// The log's header.
    pub fn header(&self) -> &LogHeader {
        &self.header
    }

    /// Read the whole, CRC-valid records from the current offset on and advance past them;
    /// a later call resumes there (another process may be appending). A torn tail is left
    /// for later without error. At a corrupt frame reading stops: if records were read
    /// before it in this call they are returned (and [`tail`](Self::tail) reports the
    /// corruption); otherwise the result is [`AmbLogError::Corrupt`] with its offset.
    pub fn read_new(&mut self) -> Result<Vec<AmbRecord>, AmbLogError> {
        let records = self.read_available()?;
        if records.is_empty() {
            if let LogTail::Corrupt { offset, reason } = &self.tail {
                return Err(AmbLogError::Corrupt {
                    path: self.path.clone(),
                    offset: *offset,
                    reason: reason.clone(),
                });
            }
        }
        Ok(records)
    }

    /// Like [`read_new`](Self::read_new) but never reports corruption as an error: the
    /// records read are returned and [`tail`](Self::tail) says how the read ended.
    pub fn read_available(&mut self) -> Result<Vec<AmbRecord>, AmbLogError> {
        let io_err = |source| AmbLogError::Io {
            path: self.path.clone(),
            source,
        };
        self.file
            .seek(SeekFrom::Start(self.offset))
            .map_err(io_err)?;
        let mut data = Vec::new();
        (&self.file).read_to_end(&mut data).map_err(io_err)?;
        let scan = scan_frames(&data, self.offset);
        self.offset += scan.used as u64;
        self.tail = scan.tail;
        self.invalid += scan.invalid;
        Ok(scan.records)
    }

    /// Whole, CRC-valid records skipped so far because their values are invalid
    /// ([`AmbRecord::is_valid`]).
    pub fn invalid(&self) -> u64 {
        self.invalid
    }

    /// How the last read ended.
    pub fn tail(&self) -> &LogTail {
        &self.tail
    }

    /// Byte offset of the next frame to read.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// Set the offset of the next read (e.g. one saved earlier); offsets inside the header
    /// mean the first frame.
    pub fn set_offset(&mut self, off: u64) {
        self.offset = off.max(self.data_offset);
    }

    /// Offset of the first frame (the header's size).
    pub fn data_offset(&self) -> u64 {
        self.data_offset
    }
}

#[cfg(test)]
#[path = "log_tests.rs"]
mod tests;
