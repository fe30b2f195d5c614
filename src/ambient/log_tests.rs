//! Tests of the ambient log format (a child module of `log`).

use super::*;

#[test]
fn version_one_headers_are_read_and_later_versions_refused() {
    let h = LogHeader::new([0xcd; 32], "-ab 2");
    let with_version = |v: u32| {
        let mut b = h.to_bytes();
        b[10..14].copy_from_slice(&v.to_le_bytes());
        let n = b.len() - 4;
        let crc = crc32fast::hash(&b[..n]);
        b[n..].copy_from_slice(&crc.to_le_bytes());
        b
    };
    let v1 = with_version(1);
    let (got, len) = parse_header(Path::new("x"), &v1, v1.len() as u64).unwrap();
    assert_eq!((got.version, len), (1, v1.len() as u64));
    let v3 = with_version(LOG_VERSION + 1);
    assert!(matches!(
        parse_header(Path::new("x"), &v3, v3.len() as u64),
        Err(AmbLogError::Version { found, .. }) if found == LOG_VERSION + 1
    ));
}

/// A good record and copies with one poisoned field each (as a crafted or damaged log in
/// a shared job directory may hold): only the good ones are read, the others counted.
#[test]
fn invalid_records_are_skipped_and_counted() {
    let good = AmbRecord {
        id: ValueId { origin: 7, seq: 1 },
        pos: DVec3::new(1.0, 2.0, 3.0),
        ndir: DVec3::Z,
        udir: DVec3::X,
        lvl: 0,
        weight: 1.0,
        rad: [0.1, 0.2],
        gpos: [0.0; 2],
        gdir: [0.0; 2],
        corral: 0,
        val: [0.5, 0.5, 0.5],
        reach: 1.0,
        share: 1.0,
    };
    let bad = [
        AmbRecord {
            rad: [f32::INFINITY; 2],
            ..good
        },
        AmbRecord {
            val: [f32::NAN, 0.5, 0.5],
            ..good
        },
        AmbRecord {
            val: [3e38, 3e38, 3e38],
            ..good
        },
        AmbRecord {
            val: [-1.0, 0.5, 0.5],
            ..good
        },
        AmbRecord {
            ndir: DVec3::new(0.0, 0.0, 7.0),
            ..good
        },
        AmbRecord {
            pos: DVec3::new(f64::NAN, 0.0, 0.0),
            ..good
        },
        AmbRecord {
            share: f32::INFINITY,
            ..good
        },
    ];
    let mut records = vec![good];
    records.extend(bad);
    records.push(AmbRecord {
        id: ValueId { origin: 7, seq: 2 },
        ..good
    });
    let h = LogHeader::new([1; 32], "-ab 1");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("poisoned.log");
    std::fs::write(&path, encode_log(&h, &records)).unwrap();
    let mut r = LogReader::open(&path, Some(&[1; 32]), false).unwrap();
    let got = r.read_new().unwrap();
    assert_eq!(got.len(), 2);
    assert!(got.iter().all(|g| g.val == good.val && g.rad == good.rad));
    assert_eq!(r.invalid(), bad.len() as u64);
    assert_eq!(r.tail(), &LogTail::Clean);
}

#[test]
fn payload_layout() {
    let r = AmbRecord {
        id: ValueId { origin: 7, seq: 9 },
        pos: DVec3::new(1.0, 2.0, 3.0),
        ndir: DVec3::Z,
        udir: DVec3::X,
        lvl: 2,
        weight: 0.5,
        rad: [0.1, 0.2],
        gpos: [0.3, 0.4],
        gdir: [0.5, 0.6],
        corral: 0xdeadbeef,
        val: [1.0, 2.0, 3.0],
        reach: 1.5,
        share: 1.25,
    };
    let b = encode_payload(&r);
    assert_eq!(&b[0..8], &7u64.to_le_bytes());
    assert_eq!(&b[16..24], &1.0f64.to_le_bytes());
    assert_eq!(b[88], 2);
    assert_eq!(&b[89..93], &0.5f32.to_le_bytes());
    assert_eq!(&b[117..121], &0xdeadbeefu32.to_le_bytes());
    assert_eq!(&b[129..133], &3.0f32.to_le_bytes());
    assert_eq!(&b[133..137], &1.5f32.to_le_bytes());
    assert_eq!(&b[137..141], &1.25f32.to_le_bytes());
    assert_eq!(decode_payload(&b), Some(r));
    // A version-2 payload (no share) reads with share 1, a version-1 one (no reach
    // either) with reach 1 too.
    let v2 = decode_payload(&b[..PAYLOAD_SIZE_V2]).unwrap();
    assert_eq!(AmbRecord { share: 1.25, ..v2 }, r);
    let v1 = decode_payload(&b[..PAYLOAD_SIZE_V1]).unwrap();
    assert_eq!((v1.reach, v1.share), (1.0, 1.0));
    assert_eq!(
        AmbRecord {
            reach: 1.5,
            share: 1.25,
            ..v1
        },
        r
    );
    let h = LogHeader::new([0xab; 32], "-ab 1");
    let hb = h.to_bytes();
    assert_eq!(hb.len(), 50 + 5 + 4);
    assert_eq!(parse_header(Path::new("x"), &hb, 59).unwrap(), (h, 59));
}
