//! Tests of the picture formats (`tessera::image`): RGBE encoding, the Radiance HDR reader and
//! writer (against files written by real Radiance 6.0a in `tests/data/`), OpenEXR, PNG and
//! atomic output. Tests named "live" run real Radiance programs (`getinfo`, `pvalue`) when they
//! can be found (`tests/common::radiance_bin`) and are skipped otherwise.

use std::io::{BufReader, Cursor, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

mod common;

use tessera::image::hdr::{float_to_rgbe, read_hdr, rgbe_to_float, write_hdr};
use tessera::image::output::{write_atomic, write_atomic_noclobber};
use tessera::image::{
    exr, png, read_picture, write_picture, Header, Image, ImageError, PictureFormat, FORMAT_XYZE,
};

// ---------------------------------------------------------------------------------------------
// Helpers

/// A small deterministic random generator (xorshift64*).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// A random picture with a mix of smooth areas (runs after RGBE quantisation), noise, black
/// pixels and a wide range of magnitudes.
fn random_image(w: usize, h: usize, seed: u64) -> Image {
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let mut img = Image::new(w, h);
    let mut cur = [0.5f32; 3];
    for p in img.pixels.iter_mut() {
        match rng.below(8) {
            0 => cur = [0.0; 3],
            1..=3 => {
                let scale = 10f32.powi(rng.below(12) as i32 - 6);
                cur = [rng.unit() * scale, rng.unit() * scale, rng.unit() * scale];
            }
            _ => {} // repeat the previous colour
        }
        *p = cur;
    }
    img
}

fn quantised(c: [f32; 3]) -> [f32; 3] {
    rgbe_to_float(float_to_rgbe(c))
}

fn to_bytes(img: &Image) -> Vec<u8> {
    let mut v = Vec::new();
    write_hdr(&mut v, img).unwrap();
    v
}

fn from_bytes(b: &[u8]) -> Result<Image, ImageError> {
    read_hdr(&mut Cursor::new(b))
}

/// The bytes after the resolution line (header end is the first "\n\n", then one more line).
fn pixel_data(file: &[u8]) -> &[u8] {
    let hdr_end = file.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
    let res_end = hdr_end + file[hdr_end..].iter().position(|&b| b == b'\n').unwrap() + 1;
    &file[res_end..]
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Parse `pvalue` text output: each line's numbers.
fn parse_numbers(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
        .collect()
}

/// `a` matches a value printed by pvalue with 4 significant digits.
fn close_to_printed(a: f32, printed: f64) -> bool {
    (a as f64 - printed).abs() <= 6e-4 * printed.abs() + 1e-30
}

fn header_with_magic(lines: &[&str], res: &str) -> Vec<u8> {
    let mut v = b"#?RADIANCE\n".to_vec();
    for l in lines {
        v.extend_from_slice(l.as_bytes());
        v.push(b'\n');
    }
    v.push(b'\n');
    v.extend_from_slice(res.as_bytes());
    v.push(b'\n');
    v
}

// ---------------------------------------------------------------------------------------------
// RGBE pixels

#[test]
fn rgbe_known_values() {
    let c = rgbe_to_float([0xff, 0xfe, 0xfe, 0x7e]);
    for (got, want) in c.iter().zip([0.24951, 0.24854, 0.24854]) {
        assert!((got - want).abs() < 5e-6, "{c:?}");
    }
    assert_eq!(
        float_to_rgbe([0.24951, 0.24854, 0.24854]),
        [0xff, 0xfe, 0xfe, 0x7e]
    );
    assert_eq!(float_to_rgbe([1.0, 0.5, 0.25]), [128, 64, 32, 129]);
    assert_eq!(
        rgbe_to_float([128, 64, 32, 129]),
        [128.5 / 128.0, 64.5 / 128.0, 32.5 / 128.0]
    );
    assert_eq!(float_to_rgbe([9e-33, 9e-33, 9e-33]), [0, 0, 0, 0]);
    // f32 1e-32 is a little above the f64 threshold 1e-32, as in Radiance (float colours)
    assert_ne!(float_to_rgbe([1e-32, 0.0, 0.0]), [0, 0, 0, 0]);
    assert_eq!(float_to_rgbe([f32::NAN, -3.0, f32::INFINITY]), [0, 0, 0, 0]);
    assert_eq!(float_to_rgbe([-1.0, 2.0, f32::NAN]), [0, 128, 0, 130]);
    // every valid (normalised) RGBE pixel survives decode + encode
    for e in [30u8, 60, 128, 200, 255] {
        // (below about 23 the values are under 1e-32)
        for m in [128u8, 129, 200, 255] {
            let p = [m, m / 3, 255 - m, e];
            assert_eq!(float_to_rgbe(rgbe_to_float(p)), p);
        }
    }
}

#[test]
fn non_finite_pixels_are_written_as_black_components() {
    let mut img = Image::new(20, 1);
    img.set(0, 0, [f32::NAN, 1.0, f32::INFINITY]);
    img.set(1, 0, [-1.0, -1.0, -1.0]);
    let back = from_bytes(&to_bytes(&img)).unwrap();
    assert!(back.pixels.iter().flatten().all(|v| v.is_finite()));
    assert_eq!(back.get(0, 0)[0], 0.0 * 1.0 + (0.5 / 256.0) * 2.0);
    assert_eq!(back.get(1, 0), [0.0; 3]);
}

// ---------------------------------------------------------------------------------------------
// HDR writer and reader

#[test]
fn round_trip_every_width() {
    for w in 1..=40 {
        for h in [1, 2, 5] {
            let img = random_image(w, h, (w * 100 + h) as u64);
            let back = from_bytes(&to_bytes(&img)).unwrap_or_else(|e| panic!("{w}x{h}: {e}"));
            assert_eq!((back.width, back.height), (w, h));
            for (i, (a, b)) in img.pixels.iter().zip(&back.pixels).enumerate() {
                assert_eq!(quantised(*a), *b, "{w}x{h} pixel {i}");
                let m = a[0].max(a[1]).max(a[2]);
                for k in 0..3 {
                    assert!(
                        (a[k] - b[k]).abs() <= m / 128.0 + 1e-30,
                        "{w}x{h} pixel {i}: {a:?} vs {b:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn round_trip_wide_lines() {
    // 32767 is the widest RLE line, 32768 must be flat.
    for w in [32767usize, 32768] {
        let img = random_image(w, 1, w as u64);
        let bytes = to_bytes(&img);
        let pix = pixel_data(&bytes);
        if w == 32768 {
            assert_eq!(pix.len(), w * 4, "flat");
        } else {
            assert_eq!(&pix[..4], &[2, 2, 0x7f, 0xff]);
        }
        let back = from_bytes(&bytes).unwrap();
        let want: Vec<_> = img.pixels.iter().map(|&c| quantised(c)).collect();
        assert_eq!(back.pixels, want);
    }
}

#[test]
fn flat_below_17_rle_from_17() {
    let img16 = random_image(16, 3, 1);
    assert_eq!(pixel_data(&to_bytes(&img16)).len(), 16 * 3 * 4);
    let img17 = Image::new(17, 3);
    // black line: marker + 4 runs of 17
    assert_eq!(
        pixel_data(&to_bytes(&img17))[..12],
        [2, 2, 0, 17, 0x91, 0, 0x91, 0, 0x91, 0, 0x91, 0]
    );
}

#[test]
fn rle_bytes_48_wide_example() {
    // R, G, B all different from pixel to pixel (one literal of 48 each); exponent 7e, 46 x 7f, 7e.
    let mut img = Image::new(48, 1);
    for i in 0..48 {
        let e = if i == 0 || i == 47 { 0x7e } else { 0x7f };
        img.set(
            i,
            0,
            rgbe_to_float([128 + i as u8, i as u8, 2 * i as u8, e]),
        );
    }
    let bytes = to_bytes(&img);
    let pix = pixel_data(&bytes);
    let mut want = vec![0x02, 0x02, 0x00, 0x30];
    want.push(0x30);
    want.extend((0..48).map(|i| 128 + i as u8));
    want.push(0x30);
    want.extend(0..48u8);
    want.push(0x30);
    want.extend((0..48).map(|i| 2 * i as u8));
    want.extend([0x01, 0x7e, 0xae, 0x7f, 0x01, 0x7e]);
    assert_eq!(pix, &want[..]);
}

#[test]
fn header_written_in_radiance_order() {
    let mut img = Image::new(2, 3);
    img.header = Header {
        commands: vec!["oconv scene.rad".into(), "tpict -x 2 -y 3 scene.oct".into()],
        software: Some("Tessera 0.1".into()),
        view: Some("-vtv -vp 0 0 0 -vd 0 1 0".into()),
        frame: Some(7),
        pixaspect: Some(0.630415),
        exposure: 2.0,
        primaries: None,
        format: "32-bit_rle_rgbe".into(),
        tiled: Some((4, 3)),
        extra: vec![("CAPDATE".into(), " 2026:01:02 03:04:05".into())],
    };
    let bytes = to_bytes(&img);
    let text = String::from_utf8_lossy(&bytes[..bytes.len() - pixel_data(&bytes).len()]);
    assert_eq!(
        text,
        "#?RADIANCE\noconv scene.rad\ntpict -x 2 -y 3 scene.oct\nSOFTWARE= Tessera 0.1\nFRAME=7\n\
         TILED= 4 3\nVIEW= -vtv -vp 0 0 0 -vd 0 1 0\nPIXASPECT=0.630415\n\
         PRIMARIES= 0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333\n\
         CAPDATE= 2026:01:02 03:04:05\nEXPOSURE=2.000000e+00\nFORMAT=32-bit_rle_rgbe\n\n\
         -Y        3 +X        2\n"
    );
    // and it reads back to the same header and size
    let back = from_bytes(&bytes).unwrap();
    assert_eq!(back.header, img.header);

    // A default header: no EXPOSURE, standard primaries.
    let plain = to_bytes(&Image::new(32, 32));
    assert!(plain.starts_with(
        b"#?RADIANCE\nPRIMARIES= 0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333\n\
          FORMAT=32-bit_rle_rgbe\n\n-Y       32 +X       32\n"
    ));
}

#[test]
fn header_values_cannot_break_the_header() {
    let mut img = Image::new(1, 1);
    img.header.commands = vec!["two\nlines".into(), "".into()];
    img.header.view = Some("-vp 1 2 3\n\n".into());
    let back = from_bytes(&to_bytes(&img)).unwrap();
    assert_eq!(back.header.commands, ["two lines"]);
    assert_eq!(back.header.view.as_deref(), Some("-vp 1 2 3"));
}

#[test]
fn header_any_order_crlf_and_products() {
    let mut file = b"#?RADIANCE\r\nEXPOSURE=2\r\nsome command -x\r\nPIXASPECT=0.5\r\nFORMAT= 32-bit_rle_rgbe \r\n\
        VIEW= -vtv -vp 1 2 3\r\nCOLORCORR= 1 1 1\r\nEXPOSURE=1.5e+00\r\nPIXASPECT=2.5\r\nFRAME=12\r\n\
        TILED= 4 5\r\nVIEW= -vh 30\r\nSOFTWARE= RADIANCE 6.0a\r\n\r\n-Y 1 +X 2\r\n"
        .to_vec();
    file.extend([128, 0, 0, 129, 0, 0, 0, 0]);
    let img = from_bytes(&file).unwrap();
    let h = &img.header;
    assert_eq!(h.exposure, 3.0);
    assert_eq!(h.pixaspect, Some(1.25));
    assert_eq!(h.format, "32-bit_rle_rgbe");
    assert_eq!(h.view.as_deref(), Some("-vtv -vp 1 2 3 -vh 30"));
    assert_eq!(h.frame, Some(12));
    assert_eq!(h.tiled, Some((4, 5)));
    assert_eq!(h.software.as_deref(), Some("RADIANCE 6.0a"));
    assert_eq!(h.commands, ["some command -x"]);
    assert_eq!(h.extra, [("COLORCORR".to_string(), " 1 1 1".to_string())]);
    assert_eq!(
        img.pixels,
        [[128.5 / 128.0, 0.5 / 128.0, 0.5 / 128.0], [0.0; 3]]
    );
}

#[test]
fn header_errors() {
    let res_and_pixel = |hdr: &[u8]| {
        let mut v = hdr.to_vec();
        v.extend(b"-Y 1 +X 1\n");
        v.extend([128, 128, 128, 128]);
        v
    };
    assert!(from_bytes(&res_and_pixel(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")).is_ok());
    // no FORMAT line: RGBE assumed, as Radiance does
    assert!(from_bytes(&res_and_pixel(b"#?RADIANCE\n\n")).is_ok());
    let e = from_bytes(&res_and_pixel(b"#?RADIANCE\nFORMAT=Radiance_spectra\n\n")).unwrap_err();
    assert!(e.to_string().contains("unsupported pixel format"), "{e}");
    assert!(from_bytes(b"").is_err());
    assert!(from_bytes(b"\x89PNG\r\n\x1a\n")
        .unwrap_err()
        .to_string()
        .contains("not a Radiance picture"));
    assert!(from_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n").is_err()); // no blank line
    assert!(from_bytes(b"#?RADIANCE\n\n-Y 1 +X 1").is_err()); // resolution line unfinished
    assert!(from_bytes(b"#?RADIANCE\n\n+Z 1 +X 1\n\x80\x80\x80\x80").is_err());
    // A huge size in a tiny file fails, without a huge allocation: on the free memory
    // (about 60 GiB to read) before any pixel, or on the data where that much is free.
    let t = std::time::Instant::now();
    let e = from_bytes(b"#?RADIANCE\n\n-Y 1 +X 2000000000\n\x80\x80\x80\x80\x01\x01\x01\x02")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("truncated") || e.contains("more than this machine has free"),
        "{e}"
    );
    assert!(from_bytes(b"#?RADIANCE\n\n-Y 2000000000 +X 2000000000\n\x80\x80\x80\x80").is_err());
    assert!(t.elapsed().as_secs() < 5);
    // Long header lines are fine (Radiance itself copes with them).
    let long = format!("#?RADIANCE\n{}\n\n", "x".repeat(5000));
    let img = from_bytes(&res_and_pixel(long.as_bytes())).unwrap();
    assert_eq!(img.header.commands[0].len(), 5000);
}

/// Pixel value used by the orientation tests: unique per (x, y_from_top).
fn orient_value(x: usize, y_top: usize) -> [u8; 4] {
    [128 + (x * 10 + y_top) as u8, 7, 9, 130]
}

/// Build a flat picture in the given orientation, independently of the reader's logic: the file
/// lists scanlines along the major axis (the first in the resolution line), '-' meaning the
/// coordinate decreases. Picture coordinates: x from the left, y from the bottom.
fn oriented_file(res_fmt: &str, w: usize, h: usize) -> Vec<u8> {
    let t: Vec<&str> = res_fmt.split_whitespace().collect();
    let (s1, a1, s2) = (&t[0][..1], &t[0][1..], &t[1][..1]);
    let res = if a1 == "Y" {
        format!("{}Y {h} {}X {w}", s1, s2)
    } else {
        format!("{}X {w} {}Y {h}", s1, s2)
    };
    let mut v = header_with_magic(&["FORMAT=32-bit_rle_rgbe"], &res);
    let coord = |sign: &str, n: usize, i: usize| if sign == "-" { n - 1 - i } else { i };
    if a1 == "Y" {
        for j in 0..h {
            let y = coord(s1, h, j);
            for i in 0..w {
                let x = coord(s2, w, i);
                v.extend(orient_value(x, h - 1 - y));
            }
        }
    } else {
        for j in 0..w {
            let x = coord(s1, w, j);
            for i in 0..h {
                let y = coord(s2, h, i);
                v.extend(orient_value(x, h - 1 - y));
            }
        }
    }
    v
}

const ORIENTATIONS: [&str; 8] = [
    "-Y +X", "-Y -X", "+Y +X", "+Y -X", "+X +Y", "+X -Y", "-X +Y", "-X -Y",
];

#[test]
fn all_eight_orientations() {
    let (w, h) = (4, 3);
    for o in ORIENTATIONS {
        let img = from_bytes(&oriented_file(o, w, h)).unwrap_or_else(|e| panic!("{o}: {e}"));
        assert_eq!((img.width, img.height), (w, h), "{o}");
        for y in 0..h {
            for x in 0..w {
                assert_eq!(
                    img.get(x, y),
                    rgbe_to_float(orient_value(x, y)),
                    "{o} at ({x},{y})"
                );
            }
        }
    }
}

#[test]
fn old_rle_and_mixed_scanlines() {
    let (a, b, c, d) = (
        [200, 10, 10, 128],
        [10, 200, 10, 129],
        [10, 10, 200, 127],
        [150, 150, 150, 131],
    );
    let rep = |n: u8| [1u8, 1, 1, n];
    // width 20, three scanlines: old RLE, new RLE, flat.
    let mut v = header_with_magic(&["FORMAT=32-bit_rle_rgbe"], "-Y 3 +X 20");
    // old: a x11, b x4, c, d x4
    for p in [a, rep(10), b, rep(3), c, d, rep(3)] {
        v.extend(p);
    }
    // new: all d (one run of 20 per component)
    v.extend([2, 2, 0, 20]);
    for dk in d {
        v.extend([128 + 20, dk]);
    }
    // flat: alternating a, b
    for i in 0..20 {
        v.extend(if i % 2 == 0 { a } else { b });
    }
    let img = from_bytes(&v).unwrap();
    let f = rgbe_to_float;
    let row0: Vec<_> = std::iter::repeat_n(f(a), 11)
        .chain(std::iter::repeat_n(f(b), 4))
        .chain([f(c)])
        .chain(std::iter::repeat_n(f(d), 4))
        .collect();
    assert_eq!(img.row(0), &row0[..]);
    assert!(img.row(1).iter().all(|&p| p == f(d)));
    assert!(img
        .row(2)
        .iter()
        .enumerate()
        .all(|(i, &p)| p == if i % 2 == 0 { f(a) } else { f(b) }));

    // Shifted counts: 44 + (1 << 8) = 300 repeats, then 2.
    let mut v = header_with_magic(&[], "-Y 1 +X 304");
    for p in [a, rep(44), rep(1), b, rep(2)] {
        v.extend(p);
    }
    let img = from_bytes(&v).unwrap();
    assert!(img.row(0)[..301].iter().all(|&p| p == f(a)));
    assert!(img.row(0)[301..].iter().all(|&p| p == f(b)));

    // Repeats overrunning the line, or with nothing to repeat, are errors.
    let mut v = header_with_magic(&[], "-Y 1 +X 4");
    v.extend(a);
    v.extend(rep(4));
    assert!(from_bytes(&v).is_err());
    let mut v = header_with_magic(&[], "-Y 1 +X 4");
    v.extend(rep(4));
    assert!(from_bytes(&v).is_err());
}

#[test]
fn corrupt_rle_is_an_error() {
    let base = header_with_magic(&[], "-Y 1 +X 20");
    let cases: [&[u8]; 4] = [
        &[2, 2, 0, 21, 0x94, 1, 0x94, 1, 0x94, 1, 0x94, 1], // length mismatch
        &[2, 2, 0, 20, 0x95, 1, 0x94, 1, 0x94, 1, 0x94, 1], // run overruns
        &[2, 2, 0, 20, 0x00, 0x94, 1, 0x94, 1, 0x94, 1],    // zero-length literal
        &[2, 2, 0, 20, 21, 1, 2, 3],                        // literal overruns
    ];
    for c in cases {
        let mut v = base.clone();
        v.extend(c);
        v.extend([0u8; 100]);
        assert!(from_bytes(&v).is_err(), "{c:?}");
    }
}

#[test]
fn truncated_files_are_errors() {
    for (w, h) in [(20, 4), (5, 3)] {
        let bytes = to_bytes(&random_image(w, h, 99));
        assert!(from_bytes(&bytes).is_ok());
        for n in 0..bytes.len() {
            let e = from_bytes(&bytes[..n]);
            assert!(
                e.is_err(),
                "{w}x{h} truncated to {n} of {} bytes read fine",
                bytes.len()
            );
        }
        let e = from_bytes(&bytes[..bytes.len() - 1])
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
    }
}

#[test]
fn concatenated_pictures_read_one_after_another() {
    let (p1, mut p2) = (random_image(20, 2, 1), random_image(3, 4, 2));
    p2.header.frame = Some(2);
    let mut stream = to_bytes(&p1);
    stream.extend(to_bytes(&p2));
    let mut r = BufReader::new(Cursor::new(stream));
    let a = read_hdr(&mut r).unwrap();
    let b = read_hdr(&mut r).unwrap();
    assert_eq!((a.width, b.width, b.header.frame), (20, 3, Some(2)));
    assert!(read_hdr(&mut r).is_err());
}

// ---------------------------------------------------------------------------------------------
// Files written by real Radiance (tests/data, see its README.md)

#[test]
fn reads_rpict_pfilt_and_flat_pictures() {
    for (name, w, h) in [
        ("img_rpict32", 32, 32),
        ("img_pfilt", 32, 32),
        ("img_flat16", 16, 16),
        ("img_pixaspect", 24, 20),
        ("img_xyze", 8, 8), // -x 16 -y 8 fitted to the square view
    ] {
        let img = read_picture(&data(&format!("{name}.hdr"))).unwrap();
        assert_eq!((img.width, img.height), (w, h), "{name}");
        let want = parse_numbers(&std::fs::read_to_string(data(&format!("{name}.txt"))).unwrap());
        assert_eq!(want.len(), w * h, "{name}");
        for (i, (p, v)) in img.pixels.iter().zip(&want).enumerate() {
            for k in 0..3 {
                assert!(
                    close_to_printed(p[k], v[k]),
                    "{name} pixel {i}: {p:?} vs {v:?}"
                );
            }
        }
        let hd = &img.header;
        assert_eq!(hd.software.as_deref(), Some("RADIANCE 6.0a"), "{name}");
        assert!(hd
            .view
            .as_deref()
            .unwrap()
            .starts_with("-vtv -vp 0 -6 1 -vd 0 1 -0.15 -vu 0 0 1"));
        assert_eq!(hd.commands[0], "oconv img_scene.rad");
        assert!(hd.commands[1].starts_with("rpict -vp 0 -6 1"));
        assert_eq!(hd.extra[0].0, "CAPDATE");
        assert_eq!(hd.extra[1].0, "GMT");
        match name {
            "img_pfilt" => {
                assert_eq!(hd.exposure, 2.0);
                assert_eq!(hd.commands[2], "pfilt -1 -e 2");
            }
            "img_pixaspect" => assert_eq!(hd.pixaspect, Some(0.756498)),
            "img_xyze" => {
                assert_eq!(hd.format, FORMAT_XYZE);
                assert_eq!(hd.primaries, None);
            }
            _ => {
                assert_eq!(hd.exposure, 1.0);
                assert_eq!(hd.pixaspect, None);
                assert_eq!(hd.primaries, None); // the standard primaries
                let raw = std::fs::read(data(&format!("{name}.hdr"))).unwrap();
                assert!(raw.windows(20).any(|w| w == b"PRIMARIES= 0.6400 0."));
            }
        }
    }
    // pfilt -1 -e 2 doubled the stored values
    let a = read_picture(&data("img_rpict32.hdr")).unwrap();
    let b = read_picture(&data("img_pfilt.hdr")).unwrap();
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for k in 0..3 {
            assert!((q[k] - 2.0 * p[k]).abs() <= 0.02 * q[k] + 1e-6);
        }
    }
}

#[test]
fn reads_x_major_picture_from_pvalue() {
    // "+X 32 -Y 32": scanlines are columns, RLE-encoded. pvalue printed "x y r g b" with y from
    // the bottom.
    let img = read_picture(&data("img_xmajor.hdr")).unwrap();
    assert_eq!((img.width, img.height), (32, 32));
    let want = parse_numbers(&std::fs::read_to_string(data("img_xmajor.txt")).unwrap());
    assert_eq!(want.len(), 32 * 32);
    for v in &want {
        let (x, y) = (v[0] as usize, v[1] as usize);
        let p = img.get(x, 31 - y);
        for k in 0..3 {
            assert!(
                close_to_printed(p[k], v[2 + k]),
                "({x},{y}): {p:?} vs {v:?}"
            );
        }
    }
}

#[test]
fn rewrites_radiance_pictures_byte_for_byte() {
    // Our RLE encoder makes exactly the bytes Radiance made.
    for name in [
        "img_rpict32",
        "img_pfilt",
        "img_flat16",
        "img_pixaspect",
        "img_xyze",
    ] {
        let orig = std::fs::read(data(&format!("{name}.hdr"))).unwrap();
        let img = from_bytes(&orig).unwrap();
        let again = to_bytes(&img);
        assert_eq!(pixel_data(&again), pixel_data(&orig), "{name}");
        assert_eq!(from_bytes(&again).unwrap(), img, "{name}");
    }
}

// ---------------------------------------------------------------------------------------------
// Files, formats, atomic output

#[test]
fn picture_format_by_extension() {
    assert_eq!(
        PictureFormat::from_path(Path::new("a/b.exr")),
        PictureFormat::Exr
    );
    assert_eq!(
        PictureFormat::from_path(Path::new("b.EXR")),
        PictureFormat::Exr
    );
    assert_eq!(
        PictureFormat::from_path(Path::new("b.png")),
        PictureFormat::Png
    );
    for p in ["x.hdr", "x.pic", "x.unf", "x", "x.tif"] {
        assert_eq!(
            PictureFormat::from_path(Path::new(p)),
            PictureFormat::Hdr,
            "{p}"
        );
    }
}

#[test]
fn write_and_read_picture_files() {
    let d = tempfile::tempdir().unwrap();
    let mut img = random_image(33, 9, 5);
    img.header.view = Some("-vtv -vp 1 2 3".into());
    for name in ["a.hdr", "a.pic", "a.unf"] {
        let p = d.path().join(name);
        write_picture(Some(&p), &img).unwrap();
        let back = read_picture(&p).unwrap();
        assert_eq!(back.header, img.header);
        assert_eq!(
            back.pixels,
            img.pixels.iter().map(|&c| quantised(c)).collect::<Vec<_>>()
        );
    }
    // overwrite allowed
    write_picture(Some(&d.path().join("a.hdr")), &Image::new(2, 2)).unwrap();
    assert_eq!(read_picture(&d.path().join("a.hdr")).unwrap().width, 2);
    let mut names: Vec<_> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    names.sort();
    assert_eq!(names, ["a.hdr", "a.pic", "a.unf"]);
}

#[test]
fn errors_name_the_file() {
    let d = tempfile::tempdir().unwrap();
    let missing = d.path().join("nope.hdr");
    let e = read_picture(&missing).unwrap_err();
    assert!(e.to_string().contains("nope.hdr"), "{e}");
    let junk = d.path().join("junk.hdr");
    std::fs::write(&junk, b"#?RADIANCE\n\n-Y 2 +X 2\n\x80").unwrap();
    let e = read_picture(&junk).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("junk.hdr") && msg.contains("truncated"),
        "{msg}"
    );
    let e =
        write_picture(Some(&d.path().join("no/such/dir/x.hdr")), &Image::new(1, 1)).unwrap_err();
    assert!(e.to_string().contains("x.hdr"), "{e}");
    let e = write_picture(Some(&d.path().join("empty.hdr")), &Image::new(0, 3)).unwrap_err();
    assert!(e.to_string().contains("empty.hdr"), "{e}");
    assert!(!d.path().join("empty.hdr").exists());
}

#[test]
fn write_atomic_leaves_no_file_on_error() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("out.hdr");
    let r = write_atomic(&p, |f| {
        write_hdr(f, &random_image(20, 20, 3))?;
        Err(std::io::Error::other("renderer died"))
    });
    assert!(r.is_err());
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
    // a picture with a wrong pixel count fails inside write_hdr: nothing left either
    let mut bad = Image::new(4, 4);
    bad.pixels.pop();
    assert!(write_picture(Some(&p), &bad).is_err());
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
    // no-clobber
    write_atomic_noclobber(&p, |f| f.write_all(b"x")).unwrap();
    let e = write_atomic_noclobber(&p, |f| f.write_all(b"y")).unwrap_err();
    assert_eq!(e.kind(), std::io::ErrorKind::AlreadyExists);
    assert_eq!(std::fs::read(&p).unwrap(), b"x");
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 1);
}

#[test]
fn exr_round_trip() {
    let d = tempfile::tempdir().unwrap();
    let mut img = random_image(37, 11, 8);
    img.set(3, 4, [1e-20, 3.5e5, 0.123_456_79]);
    img.header = Header {
        commands: vec!["oconv a.rad".into(), "tpict -x 37".into()],
        software: Some("Tessera".into()),
        view: Some("-vtv -vp 0 -6 1 -vd 0 1 0 -vh 40".into()),
        frame: Some(3),
        pixaspect: Some(0.756498),
        exposure: 0.25,
        primaries: Some("0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290".into()),
        format: "32-bit_rle_rgbe".into(),
        tiled: Some((2, 2)),
        extra: vec![
            ("CAPDATE".into(), " 2026:01:02 03:04:05".into()),
            ("X".into(), "1".into()),
        ],
    };
    let p = d.path().join("pic.exr");
    write_picture(Some(&p), &img).unwrap();
    let back = read_picture(&p).unwrap();
    assert_eq!(back, img); // float pixels exactly, header complete
    let back2 = exr::read_exr(&p).unwrap();
    assert_eq!(back2.pixels, img.pixels);

    // default header round trip
    let plain = Image::new(3, 2);
    exr::write_exr(&p, &plain).unwrap();
    assert_eq!(exr::read_exr(&p).unwrap(), plain);

    // not an EXR
    let junk = d.path().join("junk.exr");
    std::fs::write(&junk, b"\x76\x2f\x31\x01garbage").unwrap();
    let e = read_picture(&junk).unwrap_err();
    assert!(e.to_string().contains("junk.exr"), "{e}");
}

#[test]
fn png_preview() {
    let d = tempfile::tempdir().unwrap();
    let mut img = random_image(23, 17, 4);
    img.set(0, 0, [f32::NAN, f32::INFINITY, -1.0]);
    let p = d.path().join("prev.png");
    write_picture(Some(&p), &img).unwrap();
    let dec = ::image::ImageReader::open(&p)
        .unwrap()
        .decode()
        .unwrap()
        .to_rgb8();
    assert_eq!(dec.dimensions(), (23, 17));
    assert_eq!(dec.get_pixel(0, 0).0, [0, 0, 0]);
    assert_eq!(dec.into_raw(), png::tone_map(&img));
    // a uniform grey picture maps to 18% grey whatever its level
    for level in [1e-4f32, 1.0, 3e4] {
        let mut g = Image::new(4, 4);
        g.pixels.iter_mut().for_each(|p| *p = [level; 3]);
        assert!(png::tone_map(&g).iter().all(|&b| b == 118), "{level}");
    }
}

// ---------------------------------------------------------------------------------------------
// Live checks against real Radiance

/// A Radiance program, if Radiance is installed (see `tests/common`: `TESSERA_RADIANCE_BIN`,
/// PATH; with `TESSERA_REQUIRE_RADIANCE=1` a missing Radiance fails instead of skipping).
fn radiance(name: &str) -> Option<PathBuf> {
    common::radiance_bin().map(|bin| bin.join(name))
}

fn run(prog: &Path, args: &[&str], stdin: &[u8]) -> Vec<u8> {
    let mut child = Command::new(prog)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let data = stdin.to_vec();
    let feeder = std::thread::spawn(move || {
        let _ = input.write_all(&data);
    });
    let out = child.wait_with_output().unwrap();
    feeder.join().unwrap();
    assert!(
        out.status.success(),
        "{} {args:?}: {}",
        prog.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn live_getinfo_and_pvalue_read_our_pictures() {
    let (Some(getinfo), Some(pvalue)) = (radiance("getinfo"), radiance("pvalue")) else {
        return;
    };
    let d = tempfile::tempdir().unwrap();
    for (w, h) in [(37, 5), (9, 4), (17, 3)] {
        let mut img = random_image(w, h, (w * h) as u64);
        img.header.commands = vec!["tpict -x 37 -y 5 scene.oct".into()];
        img.header.software = Some("Tessera 0.1".into());
        img.header.view = Some("-vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45".into());
        img.header.exposure = 0.5;
        let p = d.path().join("live.hdr");
        write_picture(Some(&p), &img).unwrap();
        let ps = p.to_str().unwrap();

        let info = String::from_utf8(run(&getinfo, &[ps], b"")).unwrap();
        for want in [
            "tpict -x 37 -y 5 scene.oct",
            "SOFTWARE= Tessera 0.1",
            "VIEW= -vtv -vp 0 0 0",
            "EXPOSURE=5.000000e-01",
            "FORMAT=32-bit_rle_rgbe",
        ] {
            assert!(info.contains(want), "getinfo lacks {want:?}:\n{info}");
        }
        let dims = String::from_utf8(run(&getinfo, &["-d", ps], b"")).unwrap();
        let dims: Vec<&str> = dims.split_whitespace().collect();
        assert_eq!(
            dims[1..],
            ["-Y", &h.to_string(), "+X", &w.to_string()],
            "{dims:?}"
        );

        let vals =
            parse_numbers(&String::from_utf8(run(&pvalue, &["-h", "-H", "-d", ps], b"")).unwrap());
        assert_eq!(vals.len(), w * h);
        for (i, (p, v)) in img.pixels.iter().zip(&vals).enumerate() {
            let q = quantised(*p);
            for k in 0..3 {
                assert!(
                    close_to_printed(q[k], v[k]),
                    "{w}x{h} pixel {i}: ours {q:?}, pvalue {v:?}"
                );
            }
        }
        // exact check through binary floats
        let raw = run(&pvalue, &["-h", "-H", "-d", "-df", ps], b"");
        let floats: Vec<f32> = raw
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes(b.try_into().unwrap()))
            .collect();
        let ours: Vec<f32> = img.pixels.iter().flat_map(|&c| quantised(c)).collect();
        assert_eq!(floats, ours);
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn live_pixel_bytes_match_radiance_encoder() {
    // pvalue -r encodes the same floats with Radiance's own setcolr + fwritecolrs.
    let Some(pvalue) = radiance("pvalue") else {
        return;
    };
    for (w, h, seed) in [
        (48, 6, 1u64),
        (17, 4, 2),
        (16, 3, 3),
        (200, 3, 4),
        (1000, 2, 5),
    ] {
        let img = random_image(w, h, seed);
        let floats: Vec<u8> = img
            .pixels
            .iter()
            .flatten()
            .flat_map(|v| v.to_ne_bytes())
            .collect();
        let theirs = run(
            &pvalue,
            &[
                "-r",
                "-h",
                "-H",
                "-df",
                "-y",
                &h.to_string(),
                "+x",
                &w.to_string(),
            ],
            &floats,
        );
        let ours = to_bytes(&img);
        assert_eq!(pixel_data(&ours), pixel_data(&theirs), "{w}x{h}");
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn live_orientations_agree_with_pvalue() {
    let Some(pvalue) = radiance("pvalue") else {
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let (w, h) = (4, 3);
    for o in ORIENTATIONS {
        let p = d.path().join("o.hdr");
        std::fs::write(&p, oriented_file(o, w, h)).unwrap();
        let img = read_picture(&p).unwrap();
        // pvalue prints "x y r g b" with y from the bottom, in file order
        let vals = parse_numbers(
            &String::from_utf8(run(&pvalue, &["-h", "-H", p.to_str().unwrap()], b"")).unwrap(),
        );
        assert_eq!(vals.len(), w * h, "{o}");
        for v in vals {
            let (x, y) = (v[0] as usize, v[1] as usize);
            let ours = img.get(x, h - 1 - y);
            for k in 0..3 {
                assert!(
                    close_to_printed(ours[k], v[2 + k]),
                    "{o} ({x},{y}): {ours:?} vs {v:?}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Robustness

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]

    #[test]
    fn read_hdr_never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..400)) {
        let _ = from_bytes(&bytes);
    }

    #[test]
    fn read_hdr_never_panics_on_arbitrary_pixel_data(
        res in proptest::sample::select(vec!["-Y 3 +X 20", "+X 20 -Y 3", "-Y 2 +X 5", "+Y 1 -X 300", "-Y 4 +X 9"]),
        bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..600),
    ) {
        let mut v = header_with_magic(&["FORMAT=32-bit_rle_rgbe"], res);
        // bias towards the RLE marker so the RLE decoder gets exercised
        if bytes.len() > 4 && bytes[0] < 128 {
            v.extend([2, 2, 0, 20]);
        }
        v.extend(&bytes);
        if let Ok(img) = from_bytes(&v) {
            proptest::prop_assert_eq!(img.pixels.len(), img.width * img.height);
        }
    }

    #[test]
    fn write_read_round_trip(w in 1usize..60, h in 1usize..4, seed in 0u64..1000) {
        let img = random_image(w, h, seed);
        let back = from_bytes(&to_bytes(&img)).unwrap();
        let want: Vec<_> = img.pixels.iter().map(|&c| quantised(c)).collect();
        proptest::prop_assert_eq!(back.pixels, want);
    }
}

/// Timing of a large picture (random data, a worst case for RLE): run with
/// `cargo test --release --test image_formats -- --ignored big_picture_speed --nocapture`.
#[test]
#[ignore]
fn big_picture_speed() {
    let img = random_image(4096, 4096, 42);
    let t = std::time::Instant::now();
    let bytes = to_bytes(&img);
    let wt = t.elapsed();
    let t = std::time::Instant::now();
    let back = from_bytes(&bytes).unwrap();
    let rt = t.elapsed();
    eprintln!(
        "4096x4096: write {wt:?}, read {rt:?}, {} bytes",
        bytes.len()
    );
    assert_eq!(back.width, 4096);
    // Timing depends on the machine and its load: printed, not asserted.
}

/// Inputs the fuzzer (`tests/fuzz.rs`) found, kept as regression tests: each is refused
/// with an error, none aborts or panics.
#[test]
fn fuzz_findings_are_refused() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-regressions");
    // An EXR header declaring a layer of about 2.5e9 pixels: the reader aborted allocating
    // 29 GB.
    let e = tessera::image::exr::read_exr(&dir.join("exr-huge-layer.exr")).unwrap_err();
    assert!(e.to_string().contains("OpenEXR"), "{e}");
    // A damaged ZIP block makes the exr crate's inflater (zune-inflate) ask for 5.6 GB
    // (zeroed, so untouched pages): under a memory limit the process aborted; without one
    // it is an error. Decoding runs on the calling thread (no rayon pool to abort in).
    let e = tessera::image::exr::read_exr(&dir.join("exr-decoder-panic.exr")).unwrap_err();
    assert!(e.to_string().contains("OpenEXR"), "{e}");
}
