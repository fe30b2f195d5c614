//! Radiance's own ambient file format (`rpict -af file`, read by `lookamb`).
//!
//! A file is a text header (`#?RADIANCE`, the option line, `SOFTWARE=`, optional
//! `CAPDATE=`/`GMT=`, `WAVELENGTH_SPLITS= 780 588 480 380`, `NCOMP=3`,
//! `FORMAT=Radiance_ambval`, a blank line), the 2-byte big-endian magic 561, then fixed-size
//! records of `64 + NCOMP` bytes (67 for RGB). Every field is big-endian and host
//! independent: floats are "portable floats" (a 4-byte signed mantissa scaled by `2^31 - 1`
//! and a signed exponent byte), directions are 32-bit codes, the value is an RGBE colour.
//! The byte layout is documented in `docs/ambient-formats.md`.
//!
//! Reading never panics on bad input: a bad header or magic is an [`AmbFileError`] naming the
//! file and byte offset; a partial record at the end is ignored and reported in
//! [`ReadReport`]; records failing [`AmbRecord::is_valid`] are counted and skipped.
//! Only `NCOMP=3` files are supported (Radiance's default `-cs 3`).

use std::fs::File;
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{AmbRecord, ValueId};
use crate::image::hdr::{float_to_rgbe, rgbe_to_float};

/// The magic number written right after the header (big-endian, 2 bytes).
pub const AMB_MAGIC: u16 = 561;
/// The value of the header's `FORMAT=` line.
pub const AMB_FORMAT: &str = "Radiance_ambval";
/// Size in bytes of one record with three colour components.
pub const RECORD_SIZE: usize = 67;
/// Largest header accepted when reading (a file without a blank line in its first MiB is
/// not an ambient file).
const MAX_HEADER: u64 = 1 << 20;

/// Errors reading a Radiance ambient file. Each names the file and, where it applies, the
/// byte offset of the problem.
#[derive(Debug, thiserror::Error)]
pub enum AmbFileError {
    /// The file could not be opened or read.
    #[error("ambient file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The text header is malformed or describes an unsupported file.
    #[error("ambient file {path}: bad header at byte {offset}: {reason}")]
    Header {
        /// The file.
        path: PathBuf,
        /// Byte offset of the offending line (or of the end of the data).
        offset: u64,
        /// What is wrong.
        reason: String,
    },
    /// The two bytes after the header are not the magic number 561.
    #[error("ambient file {path}: bad magic number at byte {offset}: {found} (expected 561)")]
    Magic {
        /// The file.
        path: PathBuf,
        /// Byte offset of the magic number.
        offset: u64,
        /// What was found there (or -1 if the file ends before it).
        found: i32,
    },
    /// A requested start offset is not at a record boundary.
    #[error("ambient file {path}: offset {offset} is not at a record boundary (records start at {data_offset}, {record_size} bytes each)")]
    Offset {
        /// The file.
        path: PathBuf,
        /// The requested offset.
        offset: u64,
        /// Where the first record starts.
        data_offset: u64,
        /// Size of one record.
        record_size: usize,
    },
}

/// The information lines of a Radiance ambient file's header.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RadHeader {
    /// Every header line after `#?RADIANCE` (option line, `SOFTWARE=`, `NCOMP=`, ...), without
    /// line ends or the terminating blank line.
    pub lines: Vec<String>,
    /// Number of colour components (`NCOMP=`, 3 when absent).
    pub ncomp: usize,
}

/// What [`read_file`] found besides the records.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadReport {
    /// Records returned (valid ones).
    pub records: usize,
    /// Whole records skipped because they failed [`AmbRecord::is_valid`].
    pub invalid: usize,
    /// Bytes of a partial record at the end, ignored.
    pub trailing_bytes: u64,
    /// Byte offset of the first record (just after the magic number).
    pub data_offset: u64,
    /// Byte offset just past the last whole record (where a later read can resume).
    pub next_offset: u64,
}

// ---------------------------------------------------------------------------------------
// Portable floats
// ---------------------------------------------------------------------------------------

/// `2^31 - 1`, the scale of a portable float's mantissa.
const PF_SCALE: f64 = 2147483647.0;

/// `2^k` as an exact f64, for `-1022 <= k <= 1023`.
fn pow2(k: i32) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// Split a finite non-zero `x` into `m * 2^e` with `0.5 <= |m| < 1` (C's `frexp`).
fn frexp(x: f64) -> (f64, i32) {
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    if exp == 0 {
        // Subnormal: scale into the normal range first.
        let (m, e) = frexp(x * pow2(64));
        return (m, e - 64);
    }
    let m = f64::from_bits((bits & !(0x7ff << 52)) | (1022 << 52));
    (m, exp - 1022)
}

/// Encode a float as Radiance's 5-byte portable float: the mantissa `trunc(m * (2^31 - 1))`
/// (with `x = m * 2^e`, `0.5 <= |m| < 1`) as a big-endian signed 32-bit integer, then `e` as
/// a signed byte. Exponents above 127 saturate to `±(2^31 - 1), 127`; below -128 give 0.
/// NaN is written as 0 and infinities saturate.
pub fn encode_portable_float(x: f64) -> [u8; 5] {
    let (mant, exp): (i32, i8) = if x == 0.0 || x.is_nan() {
        (0, 0)
    } else if x.is_infinite() {
        (if x > 0.0 { i32::MAX } else { -i32::MAX }, 127)
    } else {
        let (m, e) = frexp(x);
        if e > 127 {
            (if x > 0.0 { i32::MAX } else { -i32::MAX }, 127)
        } else if e < -128 {
            (0, 0)
        } else {
            ((m * PF_SCALE) as i32, e as i8)
        }
    };
    let b = mant.to_be_bytes();
    [b[0], b[1], b[2], b[3], exp as u8]
}

/// Decode a 5-byte portable float: 0 when the mantissa `m` is 0, otherwise
/// `(m + 0.5 - [m < 0]) / (2^31 - 1) * 2^e`.
pub fn decode_portable_float(b: [u8; 5]) -> f64 {
    let m = i32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    if m == 0 {
        return 0.0;
    }
    let e = b[4] as i8 as i32;
    let mf = m as f64 + if m < 0 { -0.5 } else { 0.5 };
    mf / PF_SCALE * pow2(e)
}

// ---------------------------------------------------------------------------------------
// Direction codes
// ---------------------------------------------------------------------------------------

/// Scale of a stored direction component: `(2^13 - 0.5) * sqrt(2)`.
const DC_SCALE: f64 = 11584.5;
/// Flag: the first stored component is x (else y).
const F1X: u32 = 8;
/// Flag: the second stored component is z (else the larger of x and y).
const F2Z: u32 = 16;
/// Largest value of a 13-bit stored component.
const DC_MAX: u32 = 0x1fff;

/// Encode a direction as Radiance's 32-bit direction code (the vector is normalised first;
/// zero or non-finite vectors give code 0). Bits 0–2: signs of x, y, z; bit 3: the first
/// stored component is x (else y); bit 4: the second is z (else the larger of x, y); bits
/// 5–17 and 18–30: the two stored components as `round(|c| * 11584.5)`. The largest
/// component is not stored. Angular error ≤ 0.006°. Sign bits follow the sign bit of each
/// component (so `-0.0` keeps its sign and decoded codes re-encode to the same code).
pub fn encode_direction(v: DVec3) -> u32 {
    let len = v.length();
    if !(len.is_finite() && len > 0.0) {
        return 0;
    }
    let v = v / len;
    let mut code = 0u32;
    if v.x.is_sign_negative() {
        code |= 1;
    }
    if v.y.is_sign_negative() {
        code |= 2;
    }
    if v.z.is_sign_negative() {
        code |= 4;
    }
    let cd = [
        v.x.abs() * DC_SCALE,
        v.y.abs() * DC_SCALE,
        v.z.abs() * DC_SCALE,
    ];
    let (first, cm) = if cd[0] <= cd[1] {
        code |= F1X;
        (cd[0], cd[1])
    } else {
        (cd[1], cd[0])
    };
    let second = if cd[2] <= cm {
        code |= F2Z;
        cd[2]
    } else {
        cm
    };
    let q = |c: f64| ((c + 0.5) as u32).min(DC_MAX);
    code | q(first) << 5 | q(second) << 18
}

/// Decode a 32-bit direction code (see [`encode_direction`]); code 0 is the zero vector.
pub fn decode_direction(code: u32) -> DVec3 {
    if code == 0 {
        return DVec3::ZERO;
    }
    // (first, second, derived) axes for each F2Z<<1|F1X.
    const AXES: [[usize; 3]; 4] = [[1, 0, 2], [0, 1, 2], [1, 2, 0], [0, 2, 1]];
    let axes = AXES[((code >> 3) & 3) as usize];
    let d1 = ((code >> 5) & DC_MAX) as f64 / DC_SCALE;
    let d2 = ((code >> 18) & DC_MAX) as f64 / DC_SCALE;
    let d3 = (1.0 - d1 * d1 - d2 * d2).max(0.0).sqrt();
    let mut c = [0.0; 3];
    c[axes[0]] = d1;
    c[axes[1]] = d2;
    c[axes[2]] = d3;
    for (i, v) in c.iter_mut().enumerate() {
        if code & (1 << i) != 0 {
            *v = -*v;
        }
    }
    DVec3::from_array(c)
}

// ---------------------------------------------------------------------------------------
// Records
// ---------------------------------------------------------------------------------------

/// Encode one record in Radiance's 67-byte layout (see the module docs). The id is not
/// stored.
pub fn encode_record(r: &AmbRecord) -> [u8; RECORD_SIZE] {
    let mut b = [0u8; RECORD_SIZE];
    b[0] = r.lvl;
    let mut put = |off: usize, x: f64| b[off..off + 5].copy_from_slice(&encode_portable_float(x));
    put(1, r.weight as f64);
    put(6, r.pos.x);
    put(11, r.pos.y);
    put(16, r.pos.z);
    put(29, r.rad[0] as f64);
    put(34, r.rad[1] as f64);
    put(39, r.gpos[0] as f64);
    put(44, r.gpos[1] as f64);
    put(49, r.gdir[0] as f64);
    put(54, r.gdir[1] as f64);
    b[21..25].copy_from_slice(&encode_direction(r.ndir).to_be_bytes());
    b[25..29].copy_from_slice(&encode_direction(r.udir).to_be_bytes());
    b[59..63].copy_from_slice(&r.corral.to_be_bytes());
    b[63..67].copy_from_slice(&float_to_rgbe(r.val));
    b
}

/// Decode one 67-byte record (no validity check; the id is 0/0).
pub fn decode_record(b: &[u8; RECORD_SIZE]) -> AmbRecord {
    let pf = |off: usize| {
        let mut x = [0u8; 5];
        x.copy_from_slice(&b[off..off + 5]);
        decode_portable_float(x)
    };
    let u32at = |off: usize| u32::from_be_bytes([b[off], b[off + 1], b[off + 2], b[off + 3]]);
    AmbRecord {
        id: ValueId::default(),
        pos: DVec3::new(pf(6), pf(11), pf(16)),
        ndir: decode_direction(u32at(21)),
        udir: decode_direction(u32at(25)),
        lvl: b[0],
        weight: pf(1) as f32,
        rad: [pf(29) as f32, pf(34) as f32],
        gpos: [pf(39) as f32, pf(44) as f32],
        gdir: [pf(49) as f32, pf(54) as f32],
        corral: u32at(59),
        val: rgbe_to_float([b[63], b[64], b[65], b[66]]),
        reach: 1.0,
        share: 1.0,
    }
}

/// Write an ambient file header: `#?RADIANCE`, `options_line` (e.g. the renderer's
/// `-av .. -aw .. -ab ..` command line), `SOFTWARE= software`,
/// `WAVELENGTH_SPLITS= 780 588 480 380`, `NCOMP=3`, `FORMAT=Radiance_ambval`, a blank line,
/// then the 2-byte magic 561. All in one `write_all`. Newlines inside `options_line` or
/// `software` are replaced by spaces.
pub fn write_header<W: Write>(w: &mut W, options_line: &str, software: &str) -> io::Result<()> {
    let clean = |s: &str| s.replace(['\n', '\r'], " ");
    let mut h = String::from("#?RADIANCE\n");
    if !options_line.is_empty() {
        h.push_str(&clean(options_line));
        h.push('\n');
    }
    h.push_str(&format!("SOFTWARE= {}\n", clean(software)));
    h.push_str("WAVELENGTH_SPLITS= 780 588 480 380\nNCOMP=3\n");
    h.push_str(&format!("FORMAT={AMB_FORMAT}\n\n"));
    let mut bytes = h.into_bytes();
    bytes.extend_from_slice(&AMB_MAGIC.to_be_bytes());
    w.write_all(&bytes)
}

/// Write one record (67 bytes, see [`encode_record`]).
pub fn write_record<W: Write>(w: &mut W, r: &AmbRecord) -> io::Result<()> {
    w.write_all(&encode_record(r))
}

/// Create (or replace) `path` with a header and `records`, in one buffered write.
pub fn write_file(
    path: &Path,
    options_line: &str,
    software: &str,
    records: &[AmbRecord],
) -> Result<(), AmbFileError> {
    let io_err = |source| AmbFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut buf = Vec::with_capacity(512 + records.len() * RECORD_SIZE);
    write_header(&mut buf, options_line, software).map_err(io_err)?;
    for r in records {
        write_record(&mut buf, r).map_err(io_err)?;
    }
    std::fs::write(path, buf).map_err(io_err)
}

// ---------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------

/// Parse a header (and the magic) from the start of `data`; returns the header and the offset
/// of the first record. `complete` says whether `data` holds the whole file.
fn parse_header(
    path: &Path,
    data: &[u8],
    complete: bool,
) -> Result<(RadHeader, u64), AmbFileError> {
    let herr = |offset: usize, reason: String| AmbFileError::Header {
        path: path.to_path_buf(),
        offset: offset as u64,
        reason,
    };
    let mut pos = 0usize;
    let mut lines = Vec::new();
    let mut ncomp = 3usize;
    let mut first = true;
    loop {
        let Some(nl) = data[pos..].iter().position(|&c| c == b'\n') else {
            let why = if complete {
                "file ends inside the header"
            } else {
                "no end of header in the first MiB"
            };
            return Err(herr(pos, why.into()));
        };
        let raw = &data[pos..pos + nl];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let line = String::from_utf8_lossy(raw).into_owned();
        let start = pos;
        pos += nl + 1;
        if first {
            if !raw.starts_with(b"#?") {
                return Err(herr(0, "not a Radiance file (no '#?' first line)".into()));
            }
            first = false;
            continue;
        }
        if raw.is_empty() {
            break;
        }
        if let Some(v) = line.strip_prefix("FORMAT=") {
            let v = v.trim();
            if v != AMB_FORMAT {
                return Err(herr(start, format!("FORMAT={v}, expected {AMB_FORMAT}")));
            }
        } else if let Some(v) = line.strip_prefix("NCOMP=") {
            ncomp = match v.trim().parse::<usize>() {
                Ok(n) if n == 3 => n,
                Ok(n) if (3..=24).contains(&n) => {
                    return Err(herr(start, format!("NCOMP={n} is not supported (only 3)")))
                }
                _ => return Err(herr(start, format!("bad NCOMP line '{line}'"))),
            };
        }
        lines.push(line);
    }
    if data.len() < pos + 2 {
        return Err(AmbFileError::Magic {
            path: path.to_path_buf(),
            offset: pos as u64,
            found: -1,
        });
    }
    let magic = u16::from_be_bytes([data[pos], data[pos + 1]]);
    if magic != AMB_MAGIC {
        return Err(AmbFileError::Magic {
            path: path.to_path_buf(),
            offset: pos as u64,
            found: magic as i32,
        });
    }
    Ok((RadHeader { lines, ncomp }, pos as u64 + 2))
}

/// Decode the whole records in `data`; returns (valid records, invalid count, bytes used).
fn decode_records(data: &[u8]) -> (Vec<AmbRecord>, usize, usize) {
    let mut out = Vec::with_capacity(data.len() / RECORD_SIZE);
    let mut invalid = 0;
    let chunks = data.chunks_exact(RECORD_SIZE);
    let used = data.len() - chunks.remainder().len();
    for c in chunks {
        let mut b = [0u8; RECORD_SIZE];
        b.copy_from_slice(c);
        let r = decode_record(&b);
        if r.is_valid() {
            out.push(r);
        } else {
            invalid += 1;
        }
    }
    (out, invalid, used)
}

/// Read a whole ambient file: its header, its valid records and a [`ReadReport`]. A partial
/// record at the end is ignored (reported as `trailing_bytes`); invalid records are skipped
/// and counted. A bad header or magic number is an error.
pub fn read_file(path: &Path) -> Result<(RadHeader, Vec<AmbRecord>, ReadReport), AmbFileError> {
    let data = std::fs::read(path).map_err(|source| AmbFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let (header, start) = parse_header(path, &data, true)?;
    let (records, invalid, used) = decode_records(&data[start as usize..]);
    let report = ReadReport {
        records: records.len(),
        invalid,
        trailing_bytes: (data.len() - start as usize - used) as u64,
        data_offset: start,
        next_offset: start + used as u64,
    };
    Ok((header, records, report))
}

/// Read only the header of an ambient file; returns it and the offset of the first record.
pub fn read_header(path: &Path) -> Result<(RadHeader, u64), AmbFileError> {
    let io_err = |source| AmbFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let f = File::open(path).map_err(io_err)?;
    let mut prefix = Vec::new();
    f.take(MAX_HEADER)
        .read_to_end(&mut prefix)
        .map_err(io_err)?;
    let complete = (prefix.len() as u64) < MAX_HEADER;
    parse_header(path, &prefix, complete)
}

/// Read the whole valid records from byte `offset` on (an offset before the first record
/// means "from the first record"), e.g. to pick up what another process appended since the
/// last read. Returns the records and the offset just past the last whole record, where the
/// next call can resume; a partial record at the end is left for later. Invalid records are
/// skipped. An offset that is not at a record boundary is an error.
pub fn read_records_from(path: &Path, offset: u64) -> Result<(Vec<AmbRecord>, u64), AmbFileError> {
    let io_err = |source| AmbFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (_, start) = read_header(path)?;
    let offset = offset.max(start);
    if (offset - start) % RECORD_SIZE as u64 != 0 {
        return Err(AmbFileError::Offset {
            path: path.to_path_buf(),
            offset,
            data_offset: start,
            record_size: RECORD_SIZE,
        });
    }
    let mut f = File::open(path).map_err(io_err)?;
    f.seek(SeekFrom::Start(offset)).map_err(io_err)?;
    let mut data = Vec::new();
    f.read_to_end(&mut data).map_err(io_err)?;
    let (records, _, used) = decode_records(&data);
    Ok((records, offset + used as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first record of the verified hex dump in radiance-facts.md §2.2 (file offset 0x134).
    const DUMP: [u8; RECORD_SIZE] = [
        0x00, 0x3f, 0xff, 0xff, 0xff, 0x01, 0x7b, 0x29, 0x9f, 0xff, 0xfa, 0x3f, 0xff, 0xff, 0xff,
        0x02, 0x7c, 0x7b, 0x30, 0x7f, 0x01, 0x00, 0x00, 0x00, 0x1a, 0x04, 0x44, 0x00, 0x14, 0x55,
        0xbb, 0x39, 0x7f, 0xff, 0x72, 0x36, 0x4f, 0xff, 0xff, 0x56, 0x64, 0x03, 0xff, 0x02, 0x61,
        0x15, 0x14, 0xff, 0x00, 0x96, 0x27, 0x8a, 0x81, 0xff, 0x47, 0x96, 0x4f, 0x7f, 0xff, 0x00,
        0xff, 0xfe, 0x00, 0xd4, 0xd3, 0xd3, 0x7e,
    ];

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn hex_dump_record_decodes() {
        let r = decode_record(&DUMP);
        assert_eq!(r.lvl, 0);
        assert_eq!(r.weight, 1.0);
        assert!(close(r.pos.x, 0.015034, 1e-6), "{}", r.pos.x);
        assert!(close(r.pos.y, 2.0, 1e-9));
        assert!(close(r.pos.z, 1.945019, 1e-6), "{}", r.pos.z);
        assert_eq!(r.ndir, DVec3::new(0.0, -1.0, 0.0));
        assert!(close(r.udir.x, 0.99972, 1e-5), "{}", r.udir);
        assert_eq!(r.udir.y, 0.0);
        assert!(close(r.udir.z, -0.02357, 1e-5), "{}", r.udir);
        assert!(close(r.rad[0] as f64, 0.334888, 1e-6), "{:?}", r.rad);
        assert!(close(r.rad[1] as f64, 0.446141, 1e-6), "{:?}", r.rad);
        assert!(close(r.gpos[0] as f64, 2.6997, 1e-4), "{:?}", r.gpos);
        assert!(close(r.gpos[1] as f64, 0.7585, 1e-4), "{:?}", r.gpos);
        assert!(close(r.gdir[0] as f64, -0.41346, 1e-5), "{:?}", r.gdir);
        assert!(close(r.gdir[1] as f64, 0.27964, 1e-5), "{:?}", r.gdir);
        assert_eq!(r.corral, 0x00fffe00);
        let k = (2f64).powi(126 - 136);
        for (v, m) in r.val.iter().zip([212.5, 211.5, 211.5]) {
            assert_eq!(*v as f64, m * k);
        }
        assert!(r.is_valid());
        // The encoding is deterministic for decoded values: the same bytes come back.
        assert_eq!(encode_record(&r), DUMP);
    }

    #[test]
    fn portable_float_edges() {
        for x in [0.0, 1.0, -1.0, 0.5, 2.0, 1e-30, -3.75e20, 123.456, -0.41346] {
            let y = decode_portable_float(encode_portable_float(x));
            assert!((x - y).abs() <= x.abs() * 1e-9, "{x} -> {y}");
        }
        assert_eq!(
            encode_portable_float(1.0),
            [0x3f, 0xff, 0xff, 0xff, 0x01],
            "1.0"
        );
        assert_eq!(encode_portable_float(f64::NAN), [0; 5]);
        assert_eq!(encode_portable_float(1e-50), [0; 5]);
        assert_eq!(
            encode_portable_float(1e50),
            [0x7f, 0xff, 0xff, 0xff, 0x7f],
            "overflow"
        );
        assert_eq!(
            encode_portable_float(f64::NEG_INFINITY),
            [0x80, 0x00, 0x00, 0x01, 0x7f]
        );
        // Sign extension of the mantissa's first byte and of the exponent.
        assert!(close(
            decode_portable_float([0x96, 0x27, 0x8a, 0x81, 0xff]),
            -0.41346,
            1e-5
        ));
    }

    #[test]
    fn direction_codes() {
        assert_eq!(encode_direction(DVec3::ZERO), 0);
        assert_eq!(decode_direction(0), DVec3::ZERO);
        assert_eq!(encode_direction(DVec3::new(0.0, -1.0, 0.0)), 0x1a);
        assert_eq!(encode_direction(DVec3::new(f64::NAN, 0.0, 1.0)), 0);
        let mut uniform = crate::hash::test_uniform(12345);
        let mut rnd = || uniform() * 2.0 - 1.0;
        let mut worst: f64 = 0.0;
        for _ in 0..100_000 {
            let v = DVec3::new(rnd(), rnd(), rnd());
            if v.length() < 1e-3 {
                continue;
            }
            let v = v.normalize();
            let code = encode_direction(v);
            let d = decode_direction(code);
            let ang = v.dot(d).clamp(-1.0, 1.0).acos().to_degrees();
            worst = worst.max(ang);
            // Decoding then re-encoding is stable (up to ties between the x and y axes).
            let d2 = decode_direction(encode_direction(d));
            assert!(d.dot(d2) > 0.999_999_99, "{v} {d} {d2}");
        }
        assert!(worst <= 0.006, "worst angle {worst}");
        for v in [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::Z,
            DVec3::NEG_Z,
            DVec3::new(1.0, 1.0, 0.0).normalize(),
            DVec3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            let d = decode_direction(encode_direction(v));
            assert!(v.dot(d) > 0.999_999_99, "{v} {d}");
        }
    }

    #[test]
    fn header_errors_do_not_panic() {
        let p = Path::new("x.amb");
        for data in [
            &b""[..],
            b"#?RADIANCE",
            b"#?RADIANCE\n",
            b"#?RADIANCE\nFORMAT=ascii\n\n\x02\x31",
            b"#?RADIANCE\nNCOMP=9999\n\n\x02\x31",
            b"#?RADIANCE\n\n\x02",
            b"#?RADIANCE\n\n\x02\x2d",
            b"hello\n\n\x02\x31",
        ] {
            assert!(parse_header(p, data, true).is_err(), "{data:?}");
        }
        let (h, off) = parse_header(p, b"#?RADIANCE\nrpict -ab 1\n\n\x02\x31", true).unwrap();
        assert_eq!(h.lines, vec!["rpict -ab 1".to_string()]);
        assert_eq!(h.ncomp, 3);
        assert_eq!(off, 26);
    }
}
