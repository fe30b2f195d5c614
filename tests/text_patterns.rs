//! Text patterns, data files and pictures against real Radiance (skipped without it):
//! - point sweeps: Tessera's text layout (`Text::inside`) against rtrace on a glow surface
//!   with `brighttext`, for every spacing mode, text files and inline words, oblique frames;
//!   `DataArray::interp` against rtrace's `brightdata` and `PictData::lookup` against
//!   `colorpict` (both need the function language in scenes, so the libraries are compared
//!   directly), tails and picture orientations included;
//! - pictures: a lit floor with `brighttext`, `colortext` and `mixtext`, rendered by rpict
//!   and tpict at `-ab 0` and `-ab 1` (`-ps 1 -pj 0`) and compared reduced.
//!
//! The font is this test's own (block letters written below), never Radiance's.

mod common;

use common::*;
use glam::DVec3;
use std::path::Path;
use std::sync::Arc;
use tessera::image::read_picture;
use tessera::modifier::data::DataArray;
use tessera::modifier::font::Font;
use tessera::modifier::picdata::PictData;
use tessera::modifier::text::{split_lines, Text};

/// Block letters I T E O (with a hole joined by seam edges) L A, and a space.
const FONT: &str = "# test font\n32 0\n\
73 5 153 222 153 48 102 48 102 222 153 222\n\
84 8 30 222 225 222 225 190 145 190 145 48 110 48 110 190 30 190\n\
69 12 50 48 210 48 210 80 85 80 85 120 180 120 180 150 85 150 85 190 210 190 210 222 50 222\n\
79 10 40 48 215 48 215 222 40 222 40 48 80 85 80 185 175 185 175 85 80 85\n\
76 6 50 48 200 48 200 80 85 80 85 222 50 222\n\
65 3 20 48 235 48 128 222\n";

const TEXT_FILE: &str = "TO  IT\nLOT    ITE\n\nA LIE\n";

/// Lines without a run of 3 or more spaces after a character: one segment each under
/// proportional spacing (see the known difference in docs/patterns-data.md).
const TEXT_FILE_ONE_SEGMENT: &str = "TO  IT\nLOT ITE\n\n A LIE\n";

/// Run rtrace on `scene` (written to `dir`) for rays straight down onto z = 0 at the
/// points; the first channel of each value, or all three.
fn rtrace(bin: &Path, dir: &Path, scene: &str, points: &[(f64, f64)]) -> Vec<[f64; 3]> {
    std::fs::write(dir.join("probe.rad"), scene).unwrap();
    let oct = run_ok(radiance(bin, "oconv").current_dir(dir).arg("probe.rad"));
    std::fs::write(dir.join("probe.oct"), oct).unwrap();
    let input: String = points
        .iter()
        .map(|(x, y)| format!("{x:e} {y:e} 1 0 0 -1\n"))
        .collect();
    let mut child = radiance(bin, "rtrace")
        .current_dir(dir)
        .args(["-h", "-ov", "-ab", "0", "probe.oct"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let feeder = std::thread::spawn(move || {
        use std::io::Write;
        stdin.write_all(input.as_bytes()).unwrap();
    });
    let out = child.wait_with_output().unwrap();
    feeder.join().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let vals: Vec<[f64; 3]> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|w| w.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(vals.len(), points.len(), "rtrace output: {text}");
    vals
}

/// A glow floor under a pattern named `pat` (defined in `defs`).
fn glow_floor(defs: &str) -> String {
    format!(
        "{defs}\npat glow g 0 0 4 1 1 1 0\n\
         g polygon floor 0 0 12 -50 -50 0 50 -50 0 50 50 0 -50 50 0\n"
    )
}

fn write_inputs(dir: &Path) {
    std::fs::write(dir.join("block.fnt"), FONT).unwrap();
    std::fs::write(dir.join("lines.txt"), TEXT_FILE).unwrap();
    std::fs::write(dir.join("segment.txt"), TEXT_FILE_ONE_SEGMENT).unwrap();
}

/// Sweep the text of `strings` / `reals` (a brighttext with fore 2, back 0.5) through
/// rtrace and compare with Tessera's layout of the same text.
fn sweep_text(bin: &Path, dir: &Path, strings: &str, frame: [f64; 9], spacing: Option<f64>) {
    let mut reals: Vec<f64> = frame.to_vec();
    reals.extend([2.0, 0.5]);
    reals.extend(spacing);
    let rtext: Vec<String> = reals.iter().map(|r| r.to_string()).collect();
    let nsargs = strings.split_whitespace().count();
    let defs = format!(
        "void brighttext pat\n{nsargs} {strings}\n0\n{} {}",
        reals.len(),
        rtext.join(" ")
    );
    let words: Vec<&str> = strings.split_whitespace().collect();
    let font = Arc::new(Font::load(&dir.join(words[0])).unwrap());
    let lines = if words.len() == 2 {
        let bytes = std::fs::read(dir.join(words[1])).unwrap();
        split_lines(&bytes).map(|l| l.to_vec()).collect::<Vec<_>>()
    } else {
        vec![words[2..].join(" ").into_bytes()]
    };
    let v = |k: usize| DVec3::new(frame[k], frame[k + 1], frame[k + 2]);
    let text = Text::new(
        font,
        lines.iter().map(|l| &l[..]),
        v(0),
        v(3),
        v(6),
        spacing,
    )
    .unwrap();
    // Points over the text's area, a grid dense enough to cross every glyph edge.
    let mut pts = Vec::new();
    let (o, r, d) = (v(0), v(3), v(6));
    for j in 0..60 {
        for i in 0..400 {
            let p = o + r * (-0.2 + 11.0 * i as f64 / 400.0) + d * (-0.1 + 4.2 * j as f64 / 60.0);
            pts.push((p.x, p.y));
        }
    }
    let got = rtrace(bin, dir, &glow_floor(&defs), &pts);
    let mut bad = Vec::new();
    let mut fore = 0;
    for (k, (&(x, y), val)) in pts.iter().zip(&got).enumerate() {
        let radiance_inside = (val[0] - 2.0).abs() < 1e-3;
        assert!(
            radiance_inside || (val[0] - 0.5).abs() < 1e-3,
            "rtrace value {val:?} at ({x}, {y})"
        );
        fore += radiance_inside as usize;
        if radiance_inside != text.inside(DVec3::new(x, y, 0.0)) {
            bad.push((k, x, y, radiance_inside));
        }
    }
    eprintln!(
        "{strings} spacing {spacing:?}: {} points, {fore} inside, {} differ",
        pts.len(),
        bad.len()
    );
    assert!(fore > 500, "too few points inside glyphs: {fore}");
    // Points within rounding of a glyph edge may go either way.
    assert!(
        bad.len() <= pts.len() / 2000,
        "differing points: {:?}",
        &bad[..bad.len().min(10)]
    );
}

const FRAME: [f64; 9] = [0.0, 2.0, 0.0, 0.5, 0.0, 0.0, 0.0, -0.5, 0.0];

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn text_layout_matches_rtrace() {
    let Some(bin) = radiance_bin() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_inputs(dir);
    for spacing in [None, Some(0.0), Some(-0.2), Some(-0.45)] {
        sweep_text(&bin, dir, "block.fnt lines.txt", FRAME, spacing);
    }
    for spacing in [Some(0.15), Some(0.2), Some(0.4)] {
        sweep_text(&bin, dir, "block.fnt segment.txt", FRAME, spacing);
    }
    sweep_text(&bin, dir, "block.fnt . TIE  LOT A", FRAME, None);
    sweep_text(&bin, dir, "block.fnt . TIE  LOT A", FRAME, Some(-0.3));
    sweep_text(&bin, dir, "block.fnt . TIE  LOT A", FRAME, Some(0.3));
    // An oblique, rotated frame.
    let oblique = [1.0, -1.0, 0.0, 0.3, 0.2, 0.0, 0.15, -0.45, 0.0];
    sweep_text(&bin, dir, "block.fnt lines.txt", oblique, Some(-0.25));
    sweep_text(&bin, dir, "block.fnt segment.txt", oblique, Some(0.25));
}

/// Coordinates sweeping a range of fractional indices well past both ends.
fn sweep(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 2e-6 * a.abs().max(b.abs()).max(1.0)
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn data_interpolation_matches_rtrace() {
    let Some(bin) = radiance_bin() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let files = [
        ("explicit.dat", "1\n0 0 3 0 1 4\n10 20 50\n"),
        ("even.dat", "# descending\n1\n5 -3 5\n2 -1 4.5 8 3\n"),
        (
            "two.dat",
            "2\n0 0 3 -1 0.5 2\n4 1 4\n1 2 3 5\n-2 0 2 1\n7 3 3 9\n",
        ),
    ];
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
        let d = DataArray::load(&dir.join(name)).unwrap();
        let pts: Vec<(f64, f64)> = if d.dims() == 1 {
            sweep(-9.0, 14.0, 461)
                .into_iter()
                .map(|x| (x, 0.0))
                .collect()
        } else {
            let mut v = Vec::new();
            for y in sweep(-3.0, 7.0, 41) {
                for x in sweep(-4.0, 5.0, 37) {
                    v.push((x, y));
                }
            }
            v
        };
        let coords = if d.dims() == 1 { ". Px" } else { ". Px Py" };
        let n = 3 + d.dims();
        let defs = format!("void brightdata pat\n{n} noop {name} {coords}\n0\n0");
        let got = rtrace(&bin, dir, &glow_floor(&defs), &pts);
        for (&(x, y), g) in pts.iter().zip(&got) {
            let c = if d.dims() == 1 { vec![x] } else { vec![x, y] };
            let ours = d.interp(&c);
            assert!(
                close(ours, g[0]),
                "{name} at {c:?}: ours {ours}, rtrace {}",
                g[0]
            );
        }
        eprintln!("{name}: {} points agree", pts.len());
    }
}

/// A picture file with resolution line `res` (scanlines flat, in file order), each pixel's
/// value a function of its display position (x from the left, y from the bottom).
fn oriented_picture(res: &str, w: usize, h: usize, extra_header: &str) -> Vec<u8> {
    let mut out =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n{extra_header}\n{res}\n").into_bytes();
    let tok: Vec<&str> = res.split_whitespace().collect();
    let y_major = tok[0].ends_with('Y');
    let (d1, d2) = (tok[0].starts_with('-'), tok[2].starts_with('-'));
    let (lines, len) = if y_major { (h, w) } else { (w, h) };
    for s in 0..lines {
        for i in 0..len {
            let (x, y) = if y_major {
                let y = if d1 { lines - 1 - s } else { s };
                let x = if d2 { len - 1 - i } else { i };
                (x, y)
            } else {
                let x = if d1 { lines - 1 - s } else { s };
                let y = if d2 { len - 1 - i } else { i };
                (x, y)
            };
            let c = [
                (x + 1) as f32,
                (y + 1) as f32 * 0.5,
                ((x * 7 + y * 3) % 5) as f32 + 0.25,
            ];
            out.extend_from_slice(&tessera::image::hdr::float_to_rgbe(c));
        }
    }
    out
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn picture_lookup_matches_rtrace() {
    let Some(bin) = radiance_bin() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let mut cases: Vec<(String, Vec<u8>)> = Vec::new();
    for res in [
        "-Y 3 +X 5",
        "+Y 3 +X 5",
        "-Y 3 -X 5",
        "+Y 3 -X 5",
        "+X 5 -Y 3",
        "-X 5 +Y 3",
        "+X 5 +Y 3",
        "-X 5 -Y 3",
    ] {
        cases.push((res.into(), oriented_picture(res, 5, 3, "")));
    }
    // Pixel aspect (multiplied), exposure and colour correction (ignored).
    cases.push((
        "aspect".into(),
        oriented_picture(
            "-Y 4 +X 3",
            3,
            4,
            "PIXASPECT=0.5\nEXPOSURE=3\nCOLORCORR=2 2 2\nPIXASPECT=4\n",
        ),
    ));
    // A run-length encoded picture.
    let mut img = tessera::image::Image::new(40, 20);
    for y in 0..20 {
        for x in 0..40 {
            img.set(x, y, [x as f32 * 0.1, (y / 3) as f32, 1.0]);
        }
    }
    let mut rle = Vec::new();
    tessera::image::hdr::write_hdr(&mut rle, &img).unwrap();
    cases.push(("rle".into(), rle));
    for (k, (what, bytes)) in cases.iter().enumerate() {
        let name = format!("p{k}.hdr");
        std::fs::write(dir.join(&name), bytes).unwrap();
        let p = PictData::load(&dir.join(&name)).unwrap();
        let (umax, vmax) = p.extent();
        let mut pts = Vec::new();
        for v in sweep(-0.7 * vmax, 1.8 * vmax, 23) {
            for u in sweep(-0.9 * umax, 2.1 * umax, 31) {
                pts.push((u, v));
            }
        }
        let defs = format!("void colorpict pat\n7 red green blue {name} . Px Py\n0\n0");
        let got = rtrace(&bin, dir, &glow_floor(&defs), &pts);
        for (&(u, v), g) in pts.iter().zip(&got) {
            // rayinit.cal's red, green and blue are max(x, 0).
            let ours = p.lookup(u, v).map(|x| x.max(0.0));
            for c in 0..3 {
                assert!(
                    close(ours[c], g[c]),
                    "{what} at ({u},{v}) channel {c}: ours {ours:?}, rtrace {g:?}"
                );
            }
        }
        eprintln!(
            "picture {what}: extent {umax}x{vmax}, {} points agree",
            pts.len()
        );
    }
}

// ---------------------------------------------------------------------------------------
// Pictures

const RES: &str = "160";

/// A floor lit by a sphere lamp, its middle part modified by `pattern` (which defines the
/// modifier `floormat` and may use the materials `white`, `red`, `blue`).
fn lit_scene(pattern: &str) -> String {
    format!(
        "void light lampmat 0 0 3 60 60 60\n\
         lampmat sphere lamp 0 0 4 1.5 -1.6 2.6 0.25\n\
         void plastic white 0 0 5 .75 .75 .75 0 0\n\
         void plastic red 0 0 5 .8 .15 .1 0 0\n\
         void plastic blue 0 0 5 .1 .2 .7 .04 .05\n\
         {pattern}\n\
         floormat polygon floor 0 0 12 -1 -1 0 4 -1 0 4 2 0 -1 2 0\n\
         white polygon wall 0 0 12 -1 2 0 4 2 0 4 2 2 -1 2 2\n"
    )
}

fn render_both(bin: &Path, scene: &str, ab: &str, tag: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_inputs(dir);
    std::fs::write(dir.join("scene.rad"), scene).unwrap();
    let oct = run_ok(radiance(bin, "oconv").current_dir(dir).arg("scene.rad"));
    std::fs::write(dir.join("scene.oct"), oct).unwrap();
    let mut args: Vec<&str> = vec![
        "-vtv", "-vp", "1.5", "0.2", "3.2", "-vd", "0", "0.15", "-1", "-vu", "0", "1", "0", "-vh",
        "70", "-vv", "60", "-x", RES, "-y", RES, "-ps", "1", "-pj", "0", "-ab", ab, "-av", ".05",
        ".05", ".05",
    ];
    if ab != "0" {
        args.extend(["-ad", "256", "-as", "0", "-aa", ".15", "-ar", "32"]);
    }
    let reference = run_ok(
        radiance(bin, "rpict")
            .current_dir(dir)
            .args(&args)
            .arg("scene.oct"),
    );
    std::fs::write(dir.join("ref.hdr"), reference).unwrap();
    run_ok(
        std::process::Command::new(tpict_bin())
            .current_dir(dir)
            .env("RAYPATH", ".")
            .args(&args)
            .args(["-w-", "-o", "ours.hdr", "scene.rad"]),
    );
    let ours = read_picture(&dir.join("ours.hdr")).unwrap();
    let theirs = read_picture(&dir.join("ref.hdr")).unwrap();
    assert_finite(&ours);
    assert_eq!((ours.width, ours.height), (theirs.width, theirs.height));
    let (w, h) = (ours.width / 4, ours.height / 4);
    let c = compare(&reduce(&ours, w, h), &reduce(&theirs, w, h), 0.02);
    eprintln!("{tag} -ab {ab}: {c:?}");
    if std::env::var("TESSERA_KEEP_COMPARE").is_ok() {
        let keep = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("text_{tag}_ab{ab}"));
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::copy(dir.join("ours.hdr"), keep.join("ours.hdr")).unwrap();
        std::fs::copy(dir.join("ref.hdr"), keep.join("ref.hdr")).unwrap();
    }
    let (rms, max) = if ab == "0" { (0.03, 0.25) } else { (0.08, 0.5) };
    assert!(
        c.rms <= rms,
        "{tag} -ab {ab}: relative RMS {:.4} > {rms}",
        c.rms
    );
    assert!(
        c.max <= max,
        "{tag} -ab {ab}: max relative difference {:.3} > {max}",
        c.max
    );
    assert!(
        c.mean_lum <= 0.02,
        "{tag} -ab {ab}: mean luminance differs by {:.2}%",
        100.0 * c.mean_lum
    );
}

const SCENES: &[(&str, &str)] = &[
    (
        "brighttext",
        "void brighttext bt 2 block.fnt lines.txt 0 11 -0.6 1.7 0 0.5 0 0 0 -0.55 0 1 0.25\n\
         bt alias floormat white",
    ),
    (
        "colortext_squeezed",
        "void colortext ct 4 block.fnt . TOTAL LIE 0 16 -0.8 1.6 0 0.45 0 0 0.05 -0.6 0 \
         1 0.2 0.1 0.2 0.4 1 -0.25\n\
         ct plastic floormat 0 0 5 .7 .7 .7 0 0",
    ),
    (
        "mixtext_proportional",
        "void mixtext mt 4 red blue block.fnt segment.txt 0 10 -0.6 1.7 0 0.5 0 0 0 -0.55 0 0.2\n\
         void alias floormat mt",
    ),
    (
        "mixtext_zero_spacing",
        "void mixtext mt 6 white void block.fnt . IT TO 0 10 -0.5 1.5 0 0.6 0 0 0 -0.8 0 0\n\
         void alias floormat mt",
    ),
];

fn render_case(k: usize, ab: &str) {
    let Some(bin) = radiance_bin() else { return };
    let (tag, pattern) = SCENES[k];
    render_both(&bin, &lit_scene(pattern), ab, tag);
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn brighttext_against_rpict() {
    render_case(0, "0");
    render_case(0, "1");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn colortext_squeezed_against_rpict() {
    render_case(1, "0");
    render_case(1, "1");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn mixtext_proportional_against_rpict() {
    render_case(2, "0");
    render_case(2, "1");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn mixtext_with_a_void_side_and_zero_spacing_against_rpict() {
    render_case(3, "0");
    render_case(3, "1");
}

// ---------------------------------------------------------------------------------------
// Parsers and Radiance's own font

mod parsers {
    use proptest::prelude::*;
    use tessera::modifier::data::DataArray;
    use tessera::modifier::font::Font;
    use tessera::modifier::picdata::PictData;

    proptest! {
        #[test]
        fn data_parser_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let _ = DataArray::parse(&bytes, "fuzz.dat");
        }

        #[test]
        fn data_like_text_never_panics(
            words in proptest::collection::vec(
                prop_oneof![
                    Just("1".to_string()), Just("2".to_string()), Just("0".to_string()),
                    Just("#".to_string()), Just("\n".to_string()), Just("-3".to_string()),
                    Just("1e308".to_string()), Just("nan".to_string()), Just("6".to_string()),
                    (-5.0f64..5.0).prop_map(|v| v.to_string()),
                ],
                0..40,
            )
        ) {
            let text = words.join(" ");
            if let Ok(d) = DataArray::parse(text.as_bytes(), "fuzz.dat") {
                let c = vec![0.3; d.dims()];
                prop_assert!(d.interp(&c).is_finite());
            }
        }

        #[test]
        fn font_parser_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            if let Ok(f) = Font::parse(&bytes, "fuzz.fnt") {
                let l = f.layout(&bytes, -0.3);
                prop_assert_eq!(l.origins.len(), bytes.len());
                let _ = f.layout(&bytes, 0.3);
            }
        }

        #[test]
        fn font_like_text_never_panics(
            nums in proptest::collection::vec(0i64..300, 0..60),
            spacing in -1.0f64..1.0,
        ) {
            let text: Vec<String> = nums.iter().map(|n| n.to_string()).collect();
            if let Ok(f) = Font::parse(text.join(" ").as_bytes(), "fuzz.fnt") {
                let line: Vec<u8> = nums.iter().map(|&n| (n % 256) as u8).collect();
                let l = f.layout(&line, spacing);
                prop_assert_eq!(l.origins.len(), line.len());
                for c in 1..=255u8 {
                    if let Some(g) = f.glyph(c) {
                        let _ = g.contains(100.5, 100.5);
                    }
                }
            }
        }

        #[test]
        fn picture_reader_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
            let mut v = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 3\n".to_vec();
            v.extend_from_slice(&bytes);
            if let Ok(p) = PictData::read(&mut &v[..], "fuzz.hdr") {
                let _ = p.lookup(0.5, 0.5);
            }
        }

        /// A data file written from an array reads back to the same values and
        /// interpolates the same.
        #[test]
        fn data_files_round_trip(
            n1 in 2usize..5, n2 in 2usize..5,
            vals in proptest::collection::vec(-1e3f32..1e3, 16),
            beg in -5.0f64..5.0, len in 0.5f64..4.0,
            p in proptest::collection::vec(-10.0f64..10.0, 2),
        ) {
            let values: Vec<f32> = vals.iter().cycle().take(n1 * n2).copied().collect();
            let coords: Vec<String> = (0..n2).map(|k| (beg + k as f64 * len).to_string()).collect();
            let text = format!(
                "2\n{beg} {} {n1}\n0 0 {n2} {}\n{}\n",
                beg + len,
                coords.join(" "),
                values.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(" ")
            );
            let d = DataArray::parse(text.as_bytes(), "rt.dat").unwrap();
            prop_assert_eq!(d.values(), &values[..]);
            prop_assert_eq!(d.dims(), 2);
            let again = DataArray::from_parts("rt.dat", d.axes().to_vec(), values).unwrap();
            prop_assert_eq!(d.interp(&p), again.interp(&p));
        }
    }
}

/// Radiance's helvet.fnt, where Radiance's library folder has it (the pyradiance wheel
/// does not ship fonts: the test then skips).
fn helvet() -> Option<std::path::PathBuf> {
    let lib = radiance_bin_quiet()?
        .parent()?
        .join("lib")
        .join("helvet.fnt");
    if lib.is_file() {
        Some(lib)
    } else {
        eprintln!("skipping: no helvet.fnt in Radiance's lib folder");
        None
    }
}

#[test]
fn helvet_values_of_the_reference() {
    let Some(path) = helvet() else { return };
    let f = Arc::new(Font::load(&path).unwrap());
    assert_eq!(f.count(), 91);
    assert_eq!((f.mwidth(), f.mheight()), (171, 163));
    let i = f.glyph(b'I').unwrap();
    assert_eq!((i.left, i.right, i.bottom, i.top), (102, 153, 48, 222));
    // brighttext helvet.fnt . AI, reals 0 1 0 1 0 0 0 -1 0 2 0.5 on z = 0.
    let o = DVec3::new(0.0, 1.0, 0.0);
    let t = Text::new(f.clone(), [&b"AI"[..]], o, DVec3::X, -DVec3::Y, None).unwrap();
    let inside = |x: f64, y: f64| t.inside(DVec3::new(x, y, 0.0));
    assert!(inside(1.502, 0.5294));
    assert!(!inside(1.3, 0.5294));
    assert!(inside(0.502, 0.8));
    assert!(!inside(0.502, 0.3));
    assert!(!inside(-0.1, 0.5) && !inside(0.5, 1.1));
    // Spacing -0.2 on II: ink at [50, 101) and [151, 202).
    let l = f.layout(b"II", -0.2);
    let ink: Vec<i64> = l.origins.iter().map(|o| o.unwrap() + 102).collect();
    assert_eq!(ink, vec![50, 151]);
}

#[test]
fn scenes_with_text_patterns_report_bad_files_and_arguments() {
    use tessera::render::world::Scene;
    use tessera::scene::{parse_scene_text, ReadOptions};
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    write_inputs(dir);
    std::fs::write(dir.join("bad.fnt"), "65 3 1 2 3 4 5 999\n").unwrap();
    let build = |pattern: &str| -> Result<Scene, String> {
        let text = format!(
            "{pattern}\nvoid plastic white 0 0 5 .5 .5 .5 0 0\n\
             pat alias m white\nm polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n"
        );
        let prims = parse_scene_text(&text, "t.rad", &ReadOptions::default()).unwrap();
        Scene::build_on(&prims, &[dir.to_path_buf()]).map_err(|e| e.to_string())
    };
    let ok = "void brighttext pat 3 block.fnt . TO 0 11 0 1 0 1 0 0 0 -1 0 2 0.5";
    build(ok).unwrap();
    let cases = [
        (
            "void brighttext pat 3 none.fnt . TO 0 11 0 1 0 1 0 0 0 -1 0 2 0.5",
            "cannot find file 'none.fnt' on RAYPATH",
        ),
        (
            "void brighttext pat 3 bad.fnt . TO 0 11 0 1 0 1 0 0 0 -1 0 2 0.5",
            "bad.fnt:1: y of vertex 3 of character 65 is 999",
        ),
        (
            "void brighttext pat 2 block.fnt none.txt 0 11 0 1 0 1 0 0 0 -1 0 2 0.5",
            "cannot find file 'none.txt'",
        ),
        (
            "void brighttext pat 3 block.fnt . TO 0 10 0 1 0 1 0 0 0 -1 0 2",
            "takes 11 or 12 real arguments",
        ),
        (
            "void colortext pat 3 block.fnt . TO 0 11 0 1 0 1 0 0 0 -1 0 2 0.5",
            "takes 15 or 16 real arguments",
        ),
        (
            "void brighttext pat 3 block.fnt . TO 0 11 0 1 0 1 0 0 2 0 0 2 0.5",
            "illegal motion vector",
        ),
        (
            "void mixtext pat 4 white nothing block.fnt lines.txt 0 9 0 1 0 1 0 0 0 -1 0",
            "unknown modifier",
        ),
        (
            "void brighttext pat 1 block.fnt 0 11 0 1 0 1 0 0 0 -1 0 2 0.5",
            "needs the string arguments",
        ),
    ];
    for (pattern, want) in cases {
        let e = build(pattern).err().unwrap();
        assert!(e.contains("t.rad:1") && e.contains(want), "{pattern}: {e}");
    }
}
