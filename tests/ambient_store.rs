//! Ambient stores on disk: Radiance's ambient file format (checked against real `rpict -af`
//! and `lookamb`) and Tessera's append-only log (torn tails, corruption, fingerprints,
//! concurrent append + read by two processes).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use glam::DVec3;
use proptest::prelude::*;
use tessera::ambient::log::{
    AmbLogError, LogHeader, LogReader, LogTail, LogWriter, FRAME_PREFIX, PAYLOAD_SIZE,
};
use tessera::ambient::radfile::{
    self, read_file, read_records_from, write_file, AmbFileError, RECORD_SIZE,
};
use tessera::ambient::{AmbRecord, ValueId};

// ------------------------------------------------------------------------------------------
// Helpers
// ------------------------------------------------------------------------------------------

/// A small deterministic PRNG (SplitMix64).
struct Rng(u64);

impl Rng {
    fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn f(&mut self) -> f64 {
        (self.u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [a, b).
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// A random record that passes `is_valid()`.
fn random_record(rng: &mut Rng, origin: u64, seq: u64) -> AmbRecord {
    let ndir = rng.unit();
    let udir = ndir.any_orthonormal_vector();
    let r0 = rng.range(0.01, 5.0) as f32;
    let r1 = r0 * rng.range(1.0, 3.0) as f32;
    let scale = 10f64.powf(rng.range(-4.0, 2.0));
    AmbRecord {
        id: ValueId { origin, seq },
        pos: DVec3::new(
            rng.range(-100.0, 100.0),
            rng.range(-100.0, 100.0),
            rng.range(-100.0, 100.0),
        ),
        ndir,
        udir,
        lvl: (rng.u64() % 8) as u8,
        weight: rng.range(0.001, 1.0) as f32,
        rad: [r0, r1],
        gpos: [rng.range(-5.0, 5.0) as f32, rng.range(-5.0, 5.0) as f32],
        gdir: [rng.range(-5.0, 5.0) as f32, rng.range(-5.0, 5.0) as f32],
        corral: rng.u64() as u32,
        val: [
            (rng.f() * scale) as f32,
            (rng.f() * scale) as f32,
            (rng.f() * scale) as f32,
        ],
        reach: rng.range(1.0, 2.0) as f32,
        share: rng.range(1.0, 2.0) as f32,
    }
}

fn records(seed: u64, origin: u64, n: usize) -> Vec<AmbRecord> {
    let mut rng = Rng(seed);
    (0..n as u64)
        .map(|i| random_record(&mut rng, origin, i))
        .collect()
}

/// Bit-exact equality (NaN-safe).
fn same_bits(a: &AmbRecord, b: &AmbRecord) -> bool {
    let v = |x: DVec3| x.to_array().map(f64::to_bits);
    let f = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    a.id == b.id
        && v(a.pos) == v(b.pos)
        && v(a.ndir) == v(b.ndir)
        && v(a.udir) == v(b.udir)
        && a.lvl == b.lvl
        && a.weight.to_bits() == b.weight.to_bits()
        && f(&a.rad) == f(&b.rad)
        && f(&a.gpos) == f(&b.gpos)
        && f(&a.gdir) == f(&b.gdir)
        && a.corral == b.corral
        && f(&a.val) == f(&b.val)
}

/// Assert `got` equals `want` within the Radiance format's precision.
fn assert_close_radiance(want: &AmbRecord, got: &AmbRecord) {
    let rel = |a: f64, b: f64, t: f64| (a - b).abs() <= t * a.abs().max(b.abs()) + 1e-30;
    for (a, b) in want.pos.to_array().iter().zip(got.pos.to_array()) {
        assert!(rel(*a, b, 1e-9), "pos {} vs {}", want.pos, got.pos);
    }
    for (a, b) in [(want.ndir, got.ndir), (want.udir, got.udir)] {
        let ang = a.dot(b).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(ang <= 0.006, "direction {a} vs {b}: {ang}°");
    }
    assert_eq!(want.lvl, got.lvl);
    assert_eq!(want.corral, got.corral);
    let pairs = [
        (want.weight, got.weight),
        (want.rad[0], got.rad[0]),
        (want.rad[1], got.rad[1]),
        (want.gpos[0], got.gpos[0]),
        (want.gpos[1], got.gpos[1]),
        (want.gdir[0], got.gdir[0]),
        (want.gdir[1], got.gdir[1]),
    ];
    for (a, b) in pairs {
        assert!(rel(a as f64, b as f64, 1e-7), "{a} vs {b}");
    }
    // RGBE: 8-bit mantissas relative to the largest component.
    let m = want.val.iter().fold(0f32, |m, v| m.max(*v)) as f64;
    for (a, b) in want.val.iter().zip(got.val) {
        assert!(
            (*a as f64 - b as f64).abs() <= m / 128.0,
            "val {:?} vs {:?}",
            want.val,
            got.val
        );
    }
}

fn tmpdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("tempdir")
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes")
}

/// Rows of `lookamb -h -d file`: 21 numbers each.
fn lookamb_rows(bin: &Path, file: &Path) -> Vec<[f64; 21]> {
    let out = common::run_ok(
        common::radiance(bin, "lookamb")
            .args(["-h", "-d"])
            .arg(file),
    );
    let text = String::from_utf8(out).expect("lookamb output is text");
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .map(|t| {
                    t.parse()
                        .unwrap_or_else(|_| panic!("bad number {t} in {l}"))
                })
                .collect();
            assert_eq!(v.len(), 21, "lookamb -d line: {l}");
            let mut a = [0.0; 21];
            a.copy_from_slice(&v);
            a
        })
        .collect()
}

/// Number of records `lookamb -h` prints.
fn lookamb_count(bin: &Path, file: &Path) -> usize {
    let out = common::run_ok(common::radiance(bin, "lookamb").arg("-h").arg(file));
    String::from_utf8_lossy(&out)
        .lines()
        .filter(|l| l.starts_with("Position:"))
        .count()
}

/// Compare a record with a `lookamb -d` row (px py pz nx ny nz ux uy uz lvl wt urad vrad r g
/// b pgu pgv dgu dgv corral) within what lookamb prints (%f or %e with 6 decimals).
fn assert_matches_row(r: &AmbRecord, row: &[f64; 21], what: &str) {
    let ours = [
        r.pos.x,
        r.pos.y,
        r.pos.z,
        r.ndir.x,
        r.ndir.y,
        r.ndir.z,
        r.udir.x,
        r.udir.y,
        r.udir.z,
        r.lvl as f64,
        r.weight as f64,
        r.rad[0] as f64,
        r.rad[1] as f64,
        r.val[0] as f64,
        r.val[1] as f64,
        r.val[2] as f64,
        r.gpos[0] as f64,
        r.gpos[1] as f64,
        r.gdir[0] as f64,
        r.gdir[1] as f64,
        r.corral as f64,
    ];
    for (i, (a, b)) in ours.iter().zip(row).enumerate() {
        let tol = 1.5e-6 + 2e-6 * a.abs();
        assert!(
            (a - b).abs() <= tol,
            "{what}: column {i}: ours {a}, lookamb {b}\nrecord {r:?}\nrow {row:?}"
        );
    }
}

// ------------------------------------------------------------------------------------------
// Radiance ambient files
// ------------------------------------------------------------------------------------------

#[test]
fn radfile_round_trip_random_records() {
    let dir = tmpdir();
    let p = dir.path().join("r.amb");
    let recs = records(1, 0, 500);
    write_file(&p, "tessera -ab 1", "Tessera test", &recs).unwrap();
    let (h, got, rep) = read_file(&p).unwrap();
    assert_eq!(h.ncomp, 3);
    assert_eq!(h.lines[0], "tessera -ab 1");
    assert!(h.lines.iter().any(|l| l == "FORMAT=Radiance_ambval"));
    assert_eq!(rep.records, 500);
    assert_eq!(rep.invalid, 0);
    assert_eq!(rep.trailing_bytes, 0);
    let len = std::fs::metadata(&p).unwrap().len();
    assert_eq!(rep.next_offset, len);
    assert_eq!(len, rep.data_offset + 500 * RECORD_SIZE as u64);
    for (a, b) in recs.iter().zip(&got) {
        assert_close_radiance(a, b);
        assert_eq!(b.id, ValueId::default());
        // Encoding what was decoded gives the same bytes.
        assert_eq!(radfile::encode_record(b), radfile::encode_record(a));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn radfile_record_precision(seed in any::<u64>()) {
        let r = records(seed, 0, 1)[0];
        let b = radfile::decode_record(&radfile::encode_record(&r));
        assert_close_radiance(&r, &b);
        prop_assert!(b.is_valid());
    }

    #[test]
    fn portable_float_precision(x in -1e30f64..1e30) {
        let y = radfile::decode_portable_float(radfile::encode_portable_float(x));
        prop_assert!((x - y).abs() <= x.abs() * 1e-9, "{} -> {}", x, y);
    }

    #[test]
    fn radfile_garbage_never_panics(body in proptest::collection::vec(any::<u8>(), 0..400)) {
        let dir = tmpdir();
        let p = dir.path().join("g.amb");
        let mut data = b"#?RADIANCE\nFORMAT=Radiance_ambval\n\n\x02\x31".to_vec();
        data.extend_from_slice(&body);
        std::fs::write(&p, &data).unwrap();
        let (_, recs, rep) = read_file(&p).unwrap();
        prop_assert_eq!(rep.records + rep.invalid, body.len() / RECORD_SIZE);
        prop_assert_eq!(recs.len(), rep.records);
        prop_assert_eq!(rep.trailing_bytes as usize, body.len() % RECORD_SIZE);
        // Any prefix of the file either errors or reads cleanly.
        let _ = std::fs::write(&p, &body);
        let _ = read_file(&p);
    }
}

#[test]
fn radfile_partial_tail_invalid_records_and_resume() {
    let dir = tmpdir();
    let p = dir.path().join("t.amb");
    let recs = records(2, 0, 10);
    let mut bad = recs[3];
    bad.weight = 0.0;
    let mut all = recs.clone();
    all.insert(4, bad);
    write_file(&p, "x", "y", &all).unwrap();
    let full = std::fs::read(&p).unwrap();
    let (_, got, rep) = read_file(&p).unwrap();
    assert_eq!((rep.records, rep.invalid), (10, 1));
    assert_eq!(got.len(), 10);
    // Cut the file at every byte inside the last record: the records before are read.
    for cut in 1..RECORD_SIZE {
        let len = full.len() - cut;
        std::fs::write(&p, &full[..len]).unwrap();
        let (_, got, rep) = read_file(&p).unwrap();
        assert_eq!(got.len(), 9);
        assert_eq!(rep.trailing_bytes as usize, RECORD_SIZE - cut);
        assert_eq!(rep.next_offset as usize, full.len() - RECORD_SIZE);
    }
    // Streaming reads resume at record boundaries as the file grows.
    let start = read_file(&p).unwrap().2.data_offset;
    std::fs::write(&p, &full[..start as usize + 3 * RECORD_SIZE + 5]).unwrap();
    let (a, off) = read_records_from(&p, 0).unwrap();
    assert_eq!(a.len(), 3);
    assert_eq!(off, start + 3 * RECORD_SIZE as u64);
    std::fs::write(&p, &full).unwrap();
    let (b, off2) = read_records_from(&p, off).unwrap();
    assert_eq!(a.len() + b.len(), 10, "one invalid record skipped");
    assert_eq!(off2, full.len() as u64);
    assert!(matches!(
        read_records_from(&p, off + 1),
        Err(AmbFileError::Offset { .. })
    ));
}

#[test]
fn radfile_bad_header_and_magic_are_errors() {
    let dir = tmpdir();
    let p = dir.path().join("h.amb");
    write_file(&p, "x", "y", &records(3, 0, 2)).unwrap();
    let full = std::fs::read(&p).unwrap();
    let start = read_file(&p).unwrap().2.data_offset as usize;
    // Every cut inside the header or magic is an error (never a panic).
    for cut in 0..start {
        std::fs::write(&p, &full[..cut]).unwrap();
        assert!(read_file(&p).is_err(), "cut at {cut}");
    }
    let mut bad = full.clone();
    bad[start - 1] = 0x2d; // magic 557, the stale documented value
    std::fs::write(&p, &bad).unwrap();
    let e = read_file(&p).unwrap_err();
    assert!(
        matches!(e, AmbFileError::Magic { offset, found: 557, .. } if offset as usize == start - 2),
        "{e}"
    );
    assert!(e.to_string().contains("h.amb"), "{e}");
    let text = String::from_utf8_lossy(&full[..start - 2]).replace("Radiance_ambval", "ascii");
    std::fs::write(&p, text).unwrap();
    let e = read_file(&p).unwrap_err();
    assert!(matches!(e, AmbFileError::Header { .. }), "{e}");
    assert!(e.to_string().contains("FORMAT=ascii"), "{e}");
    assert!(matches!(
        read_file(&dir.path().join("missing.amb")),
        Err(AmbFileError::Io { .. })
    ));
}

/// A file written by real `rpict -af` imports with the count and values `lookamb` reports.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn radfile_reads_rpict_ambient_file() {
    let Some(bin) = common::radiance_bin() else {
        return;
    };
    for (rad, vf) in [("spheres.rad", "spheres.vf"), ("mirrors.rad", "mirrors.vf")] {
        check_rpict_file(&bin, rad, vf);
    }
}

fn check_rpict_file(bin: &Path, rad: &str, vf: &str) {
    let dir = tmpdir();
    let oct = dir.path().join("s.oct");
    let amb = dir.path().join("s.amb");
    let octdata = common::run_ok(
        common::radiance(bin, "oconv")
            .arg(rad)
            .current_dir(scenes_dir()),
    );
    std::fs::write(&oct, octdata).unwrap();
    common::run_ok(
        common::radiance(bin, "rpict")
            .args(["-vf", vf, "-x", "32", "-y", "32", "-ab", "2", "-af"])
            .arg(&amb)
            .arg(&oct)
            .current_dir(scenes_dir()),
    );
    let (h, recs, rep) = read_file(&amb).unwrap();
    assert!(h.lines[0].starts_with("rpict "), "{:?}", h.lines);
    assert_eq!(rep.invalid, 0);
    assert_eq!(rep.trailing_bytes, 0);
    assert!(recs.len() > 50, "only {} records", recs.len());
    assert_eq!(recs.len(), lookamb_count(bin, &amb));
    let rows = lookamb_rows(bin, &amb);
    assert_eq!(recs.len(), rows.len());
    for (i, (r, row)) in recs.iter().zip(&rows).enumerate() {
        assert_matches_row(r, row, &format!("{rad}: record {i}"));
    }
    assert!(recs.iter().any(|r| r.lvl > 0), "-ab 2 makes level-1 values");
    // Re-encoding gives Radiance's bytes exactly.
    let data = std::fs::read(&amb).unwrap();
    let body = &data[rep.data_offset as usize..];
    for (r, chunk) in recs.iter().zip(body.chunks_exact(RECORD_SIZE)) {
        let enc = radfile::encode_record(r);
        assert_eq!(enc[..], chunk[..], "record bytes");
    }
}

/// A file written by Tessera is read by `lookamb -h` and `lookamb -h -d` with the same values.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn lookamb_reads_our_file() {
    let Some(bin) = common::radiance_bin() else {
        return;
    };
    let dir = tmpdir();
    let p = dir.path().join("ours.amb");
    let recs = records(4, 0, 200);
    write_file(
        &p,
        "tpict -ab 1 -aa 0.2 -ar 64 -ad 512 -as 128 scene.oct",
        "Tessera 0.1",
        &recs,
    )
    .unwrap();
    assert_eq!(lookamb_count(&bin, &p), recs.len());
    let rows = lookamb_rows(&bin, &p);
    assert_eq!(rows.len(), recs.len());
    let (_, back, _) = read_file(&p).unwrap();
    for (i, ((want, got), row)) in recs.iter().zip(&back).zip(&rows).enumerate() {
        assert_close_radiance(want, got);
        assert_matches_row(got, row, &format!("record {i}"));
    }
}

// ------------------------------------------------------------------------------------------
// Tessera's ambient log
// ------------------------------------------------------------------------------------------

const FP: [u8; 32] = [7; 32];

fn header() -> LogHeader {
    LogHeader::new(FP, "-ab 1 -aa 0.2 -ar 64 -ad 512 -as 128")
}

fn write_log(p: &Path, recs: &[AmbRecord], batch: usize) {
    let mut w = LogWriter::open(p, &header(), false).unwrap();
    for chunk in recs.chunks(batch) {
        for r in chunk {
            w.push(r);
        }
        assert_eq!(w.pending(), chunk.len());
        assert_eq!(w.flush().unwrap(), chunk.len());
        assert_eq!(w.pending(), 0);
    }
}

const FRAME: usize = FRAME_PREFIX + PAYLOAD_SIZE;

#[test]
fn log_round_trip_bit_exact() {
    let dir = tmpdir();
    let p = dir.path().join("a.log");
    let mut recs = records(5, 42, 300);
    // Full precision, including values Radiance's format cannot hold.
    recs[0].pos = DVec3::new(1e-300, -0.1, f64::MAX);
    recs[1].val = [f32::NAN, -1.0, f32::INFINITY];
    recs[2].id = ValueId {
        origin: u64::MAX,
        seq: u64::MAX - 1,
    };
    write_log(&p, &recs, 64);
    // The payload holds any bits exactly ...
    for r in &recs[..3] {
        let back = tessera::ambient::log::decode_payload(&tessera::ambient::log::encode_payload(r));
        assert!(same_bits(r, &back.unwrap()));
    }
    // ... and the reader returns every valid record bit-exact, skipping (and counting) the
    // two whose values no renderer makes (docs/robustness.md).
    let mut r = LogReader::open(&p, Some(&FP), false).unwrap();
    assert_eq!(r.header(), &header());
    let got = r.read_new().unwrap();
    let valid: Vec<&AmbRecord> = recs.iter().filter(|r| r.is_valid()).collect();
    assert_eq!(valid.len(), recs.len() - 2);
    assert_eq!(got.len(), valid.len());
    assert!(valid.iter().zip(&got).all(|(a, b)| same_bits(a, b)));
    assert_eq!(r.invalid(), 2);
    assert_eq!(r.tail(), &LogTail::Clean);
    assert_eq!(r.offset(), std::fs::metadata(&p).unwrap().len());
    assert!(r.read_new().unwrap().is_empty());
    // Reopening for appending continues the same log.
    let more = records(6, 42, 10);
    {
        let mut w = LogWriter::open(&p, &header(), false).unwrap();
        assert!(!w.is_empty());
        for x in &more {
            w.push(x);
        }
        // Dropping the writer flushes what is queued.
    }
    let got = r.read_new().unwrap();
    assert!(more.iter().zip(&got).all(|(a, b)| same_bits(a, b)));
    assert_eq!(got.len(), 10);
    // Creating fresh, then an existing empty log.
    let q = dir.path().join("b.log");
    let w = LogWriter::open(&q, &header(), false).unwrap();
    assert!(w.is_empty());
    drop(w);
    let mut r = LogReader::open(&q, None, false).unwrap();
    assert!(r.read_new().unwrap().is_empty());
    r.set_offset(0);
    assert_eq!(r.offset(), r.data_offset());
}

#[test]
fn log_torn_tail_at_every_offset_then_resume() {
    let dir = tmpdir();
    let p = dir.path().join("t.log");
    let recs = records(7, 1, 6);
    write_log(&p, &recs, 3);
    let full = std::fs::read(&p).unwrap();
    let last = full.len() - FRAME;
    let extra = records(8, 1, 4);
    for cut in last..full.len() {
        std::fs::write(&p, &full[..cut]).unwrap();
        let mut r = LogReader::open(&p, Some(&FP), false).unwrap();
        let got = r.read_new().unwrap();
        assert_eq!(got.len(), 5, "cut at {cut}");
        assert!(recs.iter().zip(&got).all(|(a, b)| same_bits(a, b)));
        assert_eq!(r.offset() as usize, last);
        if cut > last {
            assert_eq!(
                r.tail(),
                &LogTail::Torn {
                    offset: last as u64,
                    bytes: (cut - last) as u64
                }
            );
        }
        // The writer reopens (truncating the torn tail) and appends; the reader resumes.
        let mut w = LogWriter::open(&p, &header(), false).unwrap();
        assert_eq!(w.len() as usize, last);
        for x in &extra {
            w.push(x);
        }
        w.flush().unwrap();
        let got = r.read_new().unwrap();
        assert_eq!(got.len(), extra.len(), "cut at {cut}");
        assert!(extra.iter().zip(&got).all(|(a, b)| same_bits(a, b)));
        assert_eq!(r.tail(), &LogTail::Clean);
        assert_eq!(
            std::fs::metadata(&p).unwrap().len() as usize,
            last + extra.len() * FRAME
        );
    }
    // A zero-filled tail (a crash after the file grew) is torn, not corrupt.
    let mut z = full.clone();
    z.extend_from_slice(&[0; 100]);
    std::fs::write(&p, &z).unwrap();
    let mut r = LogReader::open(&p, None, false).unwrap();
    assert_eq!(r.read_new().unwrap().len(), 6);
    assert!(matches!(r.tail(), LogTail::Torn { .. }));
    drop(LogWriter::open(&p, &header(), false).unwrap());
    assert_eq!(std::fs::read(&p).unwrap(), full);
}

#[test]
fn log_crc_corruption_detected() {
    let dir = tmpdir();
    let p = dir.path().join("c.log");
    let recs = records(9, 2, 10);
    write_log(&p, &recs, 10);
    let full = std::fs::read(&p).unwrap();
    let start = full.len() - 10 * FRAME;
    // Flip a byte in the payload of record 4 (followed by valid records).
    let bad_off = start + 4 * FRAME;
    for k in [FRAME_PREFIX, FRAME_PREFIX + 50, FRAME - 1, 5, 0] {
        let mut data = full.clone();
        data[bad_off + k] ^= 0x10;
        std::fs::write(&p, &data).unwrap();
        let mut r = LogReader::open(&p, Some(&FP), false).unwrap();
        let got = r.read_new().unwrap();
        assert_eq!(got.len(), 4, "flip at +{k}");
        assert!(recs.iter().zip(&got).all(|(a, b)| same_bits(a, b)));
        assert!(
            matches!(r.tail(), LogTail::Corrupt { offset, .. } if *offset as usize == bad_off),
            "{:?}",
            r.tail()
        );
        // The next read reports the corruption as an error naming the file and offset.
        let e = r.read_new().unwrap_err();
        assert!(
            matches!(e, AmbLogError::Corrupt { offset, .. } if offset as usize == bad_off),
            "{e}"
        );
        let msg = e.to_string();
        assert!(
            msg.contains("c.log") && msg.contains(&bad_off.to_string()),
            "{msg}"
        );
        assert_eq!(r.offset() as usize, bad_off);
        // A writer refuses to append after corruption unless forced (which cuts it off).
        assert!(matches!(
            LogWriter::open(&p, &header(), false),
            Err(AmbLogError::Corrupt { .. })
        ));
        drop(LogWriter::open(&p, &header(), true).unwrap());
        assert_eq!(std::fs::metadata(&p).unwrap().len() as usize, bad_off);
    }
}

#[test]
fn log_fingerprint_mismatch_refused_unless_forced() {
    let dir = tmpdir();
    let p = dir.path().join("f.log");
    write_log(&p, &records(10, 3, 5), 5);
    let other = [9u8; 32];
    let e = LogReader::open(&p, Some(&other), false).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, AmbLogError::Fingerprint { .. }));
    assert!(msg.contains("f.log"), "{msg}");
    assert!(msg.contains(&"07".repeat(32)), "{msg}");
    assert!(msg.contains(&"09".repeat(32)), "{msg}");
    assert!(msg.contains("force"), "{msg}");
    let mut r = LogReader::open(&p, Some(&other), true).unwrap();
    assert_eq!(r.read_new().unwrap().len(), 5);
    assert_eq!(r.header().fingerprint, FP);
    // The writer too.
    let h2 = LogHeader::new(other, "-ab 2");
    assert!(matches!(
        LogWriter::open(&p, &h2, false),
        Err(AmbLogError::Fingerprint { .. })
    ));
    let w = LogWriter::open(&p, &h2, true).unwrap();
    assert_eq!(
        w.header().fingerprint,
        FP,
        "a forced reopen keeps the file's header"
    );
}

#[test]
fn log_truncated_or_damaged_header_is_an_error() {
    let dir = tmpdir();
    let p = dir.path().join("h.log");
    write_log(&p, &[], 1);
    let full = std::fs::read(&p).unwrap();
    assert_eq!(full.len(), header().to_bytes().len());
    for cut in 0..full.len() {
        std::fs::write(&p, &full[..cut]).unwrap();
        let e = LogReader::open(&p, Some(&FP), false).unwrap_err();
        assert!(
            matches!(e, AmbLogError::HeaderTruncated { .. }),
            "cut {cut}: {e}"
        );
        assert!(matches!(
            LogWriter::open(&p, &header(), false),
            Err(AmbLogError::HeaderTruncated { .. })
        ));
    }
    // Forcing a writer rewrites a truncated header.
    std::fs::write(&p, &full[..20]).unwrap();
    drop(LogWriter::open(&p, &header(), true).unwrap());
    assert_eq!(std::fs::read(&p).unwrap(), full);
    // Damaged option text: CRC mismatch. Wrong magic, wrong version.
    let mut d = full.clone();
    d[52] ^= 1;
    std::fs::write(&p, &d).unwrap();
    assert!(matches!(
        LogReader::open(&p, None, true),
        Err(AmbLogError::HeaderCorrupt { .. })
    ));
    let mut d = full.clone();
    d[0] = b'X';
    std::fs::write(&p, &d).unwrap();
    assert!(matches!(
        LogReader::open(&p, None, true),
        Err(AmbLogError::NotALog { .. })
    ));
    let mut d = full.clone();
    d[10] = 99;
    std::fs::write(&p, &d).unwrap();
    let e = LogReader::open(&p, None, true).unwrap_err();
    assert!(matches!(e, AmbLogError::Version { found: 99, .. }), "{e}");
    // Creating never clobbers a file that is not a log.
    std::fs::write(
        &p,
        b"hello world, not a log at all, long enough to hold a header..",
    )
    .unwrap();
    assert!(matches!(
        LogWriter::open(&p, &header(), true),
        Err(AmbLogError::NotALog { .. })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn log_garbage_after_header_never_panics(
        body in proptest::collection::vec(any::<u8>(), 0..600),
        valid in 0usize..3,
    ) {
        let dir = tmpdir();
        let p = dir.path().join("g.log");
        write_log(&p, &records(11, 4, valid), 1);
        let mut data = std::fs::read(&p).unwrap();
        let start = data.len();
        data.extend_from_slice(&body);
        std::fs::write(&p, &data).unwrap();
        let mut r = LogReader::open(&p, Some(&FP), false).unwrap();
        let got = r.read_available().unwrap();
        prop_assert!(got.len() >= valid);
        prop_assert!(r.offset() as usize <= data.len());
        prop_assert!(r.offset() as usize >= start || got.len() == valid);
        let _ = r.read_new();
        let _ = r.read_new();
        // A writer reopening never panics either.
        let _ = LogWriter::open(&p, &header(), false);
        let _ = LogWriter::open(&p, &header(), true);
    }
}

// ------------------------------------------------------------------------------------------
// Two processes: one appends batches while the other reads
// ------------------------------------------------------------------------------------------

const CHILD_ENV: &str = "TESSERA_AMBLOG_CHILD_WRITER";
const BATCHES: usize = 20;
const BATCH: usize = 37;

/// The writer role of `log_concurrent_append_and_read_two_processes`: does nothing unless
/// the parent test started this binary with `CHILD_ENV` set to the log's path.
#[test]
fn log_child_writer() {
    let Ok(path) = std::env::var(CHILD_ENV) else {
        return;
    };
    let recs = records(12, 99, BATCHES * BATCH);
    let mut w = LogWriter::open(Path::new(&path), &header(), false).unwrap();
    for chunk in recs.chunks(BATCH) {
        for r in chunk {
            w.push(r);
        }
        w.flush().unwrap();
        std::thread::sleep(Duration::from_millis(15));
    }
}

#[test]
fn log_concurrent_append_and_read_two_processes() {
    let dir = tmpdir();
    let p = dir.path().join("shared.log");
    // The parent creates the log; the child reopens it and appends.
    drop(LogWriter::open(&p, &header(), false).unwrap());
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "log_child_writer",
            "--exact",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &p)
        .spawn()
        .expect("cannot start the writer process");
    let mut r = LogReader::open(&p, Some(&FP), false).unwrap();
    let mut got = Vec::new();
    let mut reads_with_data = 0;
    let t0 = Instant::now();
    let status = loop {
        let new = r.read_new().unwrap();
        if !new.is_empty() {
            reads_with_data += 1;
        }
        got.extend(new);
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        assert!(t0.elapsed() < Duration::from_secs(60), "writer hangs");
        std::thread::sleep(Duration::from_millis(3));
    };
    assert!(status.success(), "writer process failed: {status}");
    got.extend(r.read_new().unwrap());
    assert_eq!(r.tail(), &LogTail::Clean);
    let want = records(12, 99, BATCHES * BATCH);
    assert_eq!(got.len(), want.len());
    assert!(want.iter().zip(&got).all(|(a, b)| same_bits(a, b)));
    assert!(reads_with_data > 1, "the reads overlapped the writes");
}
