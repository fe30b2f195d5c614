//! Light-leak ("corral") protection of the irradiance cache, measured in a room split by a
//! thin opaque wall: a bright lamp close to the wall on one side, a dim lamp far from it on
//! the other. With a coarse cache (`-ar 4`: every value's radius is clamped to 1.6 m, a fifth
//! of the scene's size, and reaches `aa·r` ≈ 0.5 m) values made on the bright floor next to
//! the wall reach across it; the
//! irradiance on the dark floor next to the wall, cache against pure Monte Carlo (`-aa 0`),
//! shows the leak and its cure. `--amb-corral off` switches the protection off.

mod common;

use common::*;
use std::path::Path;
use std::process::Command;
use tessera::image::read_picture;

/// 8 × 4 × 3 m room, white walls (ρ = 0.6), partition at x = 4 from floor to ceiling.
const ROOM: &str = "void plastic white 0 0 5 .6 .6 .6 0 0\n\
void light bright 0 0 3 200 200 200\n\
void light dim 0 0 3 2 2 2\n\
white polygon floor 0 0 12  0 0 0  8 0 0  8 4 0  0 4 0\n\
white polygon ceiling 0 0 12  0 0 3  0 4 3  8 4 3  8 0 3\n\
white polygon south 0 0 12  0 0 0  0 0 3  8 0 3  8 0 0\n\
white polygon north 0 0 12  0 4 0  8 4 0  8 4 3  0 4 3\n\
white polygon west 0 0 12  0 0 0  0 4 0  0 4 3  0 0 3\n\
white polygon east 0 0 12  8 0 0  8 0 3  8 4 3  8 4 0\n\
white polygon partition 0 0 12  4 0 0  4 4 0  4 4 3  4 0 3\n\
bright polygon lamp 0 0 12  3.3 1.5 2.99  3.3 2.5 2.99  3.8 2.5 2.99  3.8 1.5 2.99\n\
dim polygon dimlamp 0 0 12  6.5 1.5 2.99  6.5 2.5 2.99  7.5 2.5 2.99  7.5 1.5 2.99\n";

/// Irradiance (`-i`) at `-ab 1` with values far too large for the partition.
const AMB: &[&str] = &[
    "-i", "-ab", "1", "-ad", "512", "-as", "0", "-ar", "4", "-ps", "1", "-pj", "0", "-w-",
];

/// A parallel view straight down on the floor, `width` × 2 m centred on (`x`, 2), at 16
/// pixels per metre; picture columns run along +x.
fn floor_view(x: f64, width: f64) -> Vec<String> {
    let px = (16.0 * width).round().to_string();
    [
        "-vtl",
        "-vp",
        &x.to_string(),
        "2",
        "2.5",
        "-vd",
        "0",
        "0",
        "-1",
        "-vu",
        "0",
        "1",
        "0",
        "-vh",
        &width.to_string(),
        "-vv",
        "2",
        "-x",
        &px,
        "-y",
        "32",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

fn room_dir() -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    std::fs::write(t.path().join("room.rad"), ROOM).unwrap();
    t
}

/// Render the room under Radiance's interpolation rule (no share reach, which would make
/// the lit side's values sparser); returns the mean irradiance (red channel, all channels
/// are equal) of every 4-pixel (¼ m) column band, left to right.
fn bands(dir: &Path, view: &[String], extra: &[&str], corral: bool, name: &str) -> Vec<f64> {
    bands_share(dir, view, extra, corral, "1", name)
}

/// [`bands`] with the share reach limited to `share_max` (`--amb-share-max`).
fn bands_share(
    dir: &Path,
    view: &[String],
    extra: &[&str],
    corral: bool,
    share_max: &str,
    name: &str,
) -> Vec<f64> {
    let out = dir.join(name);
    let _ = std::fs::remove_file(&out);
    let mut c = Command::new(tpict_bin());
    c.current_dir(dir).args(view).args(AMB).args(extra);
    c.args(["--amb-share-max", share_max]);
    c.args(["--amb-corral", if corral { "on" } else { "off" }]);
    run_ok(c.args(["-o", name, "room.rad"]));
    let img = read_picture(&out).unwrap();
    assert_finite(&img);
    let nb = img.width / 4;
    let mut sum = vec![0.0; nb];
    for y in 0..img.height {
        for x in 0..img.width {
            sum[(x / 4).min(nb - 1)] += img.pixels[y * img.width + x][0] as f64;
        }
    }
    sum.iter().map(|s| s / (4 * img.height) as f64).collect()
}

fn rel(a: f64, truth: f64) -> f64 {
    (a - truth) / truth
}

/// Both sides in one picture (x from 3 to 5 m; values are made in pixel order, so lit and
/// dark values compete for the lookups next to the wall). Measured over several runs (two
/// threads): dark band next to the wall 0.0874–0.0876 with corral vs 0.0882 by Monte Carlo
/// (−0.9%), 0.252–0.263 without (+186% to +198%); the lit band by the wall loses 4–5%
/// without corral (dark values leak the other way) and 0.1% with it.
#[test]
fn wall_stops_light_leaking_across_in_one_picture() {
    let t = room_dir();
    let view = floor_view(4.0, 2.0);
    let truth = bands(t.path(), &view, &["-aa", "0"], true, "truth.hdr");
    let with = bands(t.path(), &view, &["-aa", ".3"], true, "corral.hdr");
    let without = bands(t.path(), &view, &["-aa", ".3"], false, "leak.hdr");
    eprintln!("truth   {truth:.4?}\ncorral  {with:.4?}\nleaking {without:.4?}");
    // Band 4 is the dark floor from x = 4 to 4.25, band 3 the lit floor just before the wall.
    let (dark, lit) = (4, 3);
    assert!(
        truth[lit] > 50.0 * truth[dark],
        "the scene lost its contrast: {truth:?}"
    );
    // Without the protection the dark side next to the wall is far too bright...
    assert!(
        rel(without[dark], truth[dark]) > 0.5,
        "no leak to cure: {} vs {}",
        without[dark],
        truth[dark]
    );
    // ...with it, every band agrees with the Monte Carlo truth within 5%. Measured: 0.9% at
    // most, on either side of the wall. The truth's own noise (512 rays per pixel, 128 pixels
    // per band) is a fraction of that; 5% leaves room for the thread-dependent order in which
    // values are made, and is still 37 times smaller than the smallest leak measured.
    for (i, (a, b)) in with.iter().zip(&truth).enumerate() {
        assert!(rel(*a, *b).abs() < 0.05, "band {i}: {a} vs truth {b}");
    }
    // The share reach (the lit side's indirect light is a few percent of its light there)
    // keeps the protection: the flags are set for the wider reach.
    let share = bands_share(t.path(), &view, &["-aa", ".3"], true, "3", "share.hdr");
    eprintln!("share   {share:.4?}");
    for (i, (a, b)) in share.iter().zip(&truth).enumerate() {
        assert!(rel(*a, *b).abs() < 0.05, "band {i}: {a} vs truth {b}");
    }
}

/// Values made on the lit side by one process, saved with `-af` (their flags in Radiance's
/// file format) and used by a second process rendering only the dark side: the flags are
/// carried by the file and the leak test applies to loaded values. Measured: dark band next
/// to the wall 0.0878–0.0879 with corral (−0.5%), 0.874–0.900 without (+890% to +920%), by
/// Monte Carlo 0.0883; 6 of the 11 lit values carry flags.
#[test]
fn flags_travel_in_the_ambient_file_and_stop_the_leak() {
    let t = room_dir();
    let lit = floor_view(3.5, 1.0);
    let dark = floor_view(4.5, 1.0);
    let truth = bands(t.path(), &dark, &["-aa", "0"], true, "truth.hdr");
    let mut results = Vec::new();
    for corral in [true, false] {
        let af = if corral { "corral.amb" } else { "leak.amb" };
        let args = ["-aa", ".3", "-af", af];
        bands(t.path(), &lit, &args, corral, &format!("lit-{af}.hdr"));
        let (_, records, _) = tessera::ambient::radfile::read_file(&t.path().join(af)).unwrap();
        let flagged = records.iter().filter(|r| r.corral != 0).count();
        eprintln!("{af}: {} values, {flagged} flagged", records.len());
        // Values whose reach crosses the partition carry flags; without corral none do.
        for r in &records {
            let near = 4.0 - r.pos.x < 0.3 * r.rad[0] as f64;
            if corral && near {
                assert_ne!(r.corral, 0, "value by the wall without flags: {r:?}");
            }
            if !corral {
                assert_eq!(r.corral, 0);
            }
        }
        if corral {
            assert!(flagged > 0);
        }
        results.push(bands(
            t.path(),
            &dark,
            &args,
            corral,
            &format!("dark-{af}.hdr"),
        ));
    }
    let (with, without) = (&results[0], &results[1]);
    eprintln!("truth   {truth:.4?}\ncorral  {with:.4?}\nleaking {without:.4?}");
    assert!(
        rel(without[0], truth[0]) > 0.5,
        "no leak to cure: {} vs {}",
        without[0],
        truth[0]
    );
    // Same tolerance and reasoning as above (measured: 0.9% at most).
    for (i, (a, b)) in with.iter().zip(&truth).enumerate() {
        assert!(rel(*a, *b).abs() < 0.05, "band {i}: {a} vs truth {b}");
    }
}

/// A value's flags survive both stores: Radiance's record (byte 59) and Tessera's log payload.
#[test]
fn flags_round_trip_through_both_record_formats() {
    use glam::DVec3;
    use tessera::ambient::cache::CachedValue;
    use tessera::ambient::{log, radfile, ValueId};
    let v = CachedValue {
        id: ValueId { origin: 7, seq: 3 },
        pos: DVec3::new(0.5, 0.25, 0.0),
        n: DVec3::Z,
        u: DVec3::X,
        lvl: 0,
        weight: 1.0,
        rad: [1.5, 2.0],
        gpos: [0.1, -0.2],
        gdir: [0.0, 0.05],
        corral: 0x8000_7ff1,
        val: DVec3::new(0.3, 0.2, 0.1),
        reach: 1.0,
        share: 1.0,
    };
    let origin = DVec3::new(10.0, -3.0, 1.0);
    let rec = v.to_record(origin);
    assert_eq!(rec.corral, v.corral);
    let from_rad = radfile::decode_record(&radfile::encode_record(&rec));
    let from_log = log::decode_payload(&log::encode_payload(&rec)).unwrap();
    for r in [from_rad, from_log] {
        let back = CachedValue::from_record(&r, origin);
        assert_eq!(back.corral, v.corral);
        assert!((back.pos - v.pos).length() < 1e-4);
    }
}
