//! Tests for views: ray generation (checked against Radiance's `vwrays` when installed),
//! the inverse mapping, normaspect, cropview, view files and picture headers.

use std::process::Command;

use glam::DVec3;
use proptest::prelude::*;
use tessera::options::OptError;
use tessera::view::{normaspect, parse_view_line, read_view_file, View, ViewType};

mod common;
use common::radiance_bin;

fn words(s: &str) -> Vec<String> {
    s.split_whitespace().map(String::from).collect()
}

fn view_of(s: &str) -> View {
    let mut v = View::default();
    v.apply_words(&words(s)).unwrap();
    v
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol * (1.0 + b.length())
}

/// Run vwrays for a view and return one (origin, dir) per pixel, top scanline first.
fn vwrays(bin: &std::path::Path, opts: &str, x: usize, y: usize) -> Vec<(DVec3, DVec3)> {
    let out = Command::new(bin.join("vwrays"))
        .args([
            "-fa",
            "-pj",
            "0",
            "-pa",
            "0",
            "-x",
            &x.to_string(),
            "-y",
            &y.to_string(),
        ])
        .args(words(opts))
        .output()
        .expect("run vwrays");
    assert!(
        out.status.success(),
        "vwrays failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| {
            let n: Vec<f64> = l.split_whitespace().map(|w| w.parse().unwrap()).collect();
            (DVec3::new(n[0], n[1], n[2]), DVec3::new(n[3], n[4], n[5]))
        })
        .collect()
}

const RADIANCE_VIEWS: &[&str] = &[
    "-vtv -vp 1 2 3 -vd 0 2 0 -vh 50 -vv 40 -vo 1 -vs 0.25 -vl -0.1",
    "-vtv -vp 0.5 -1 2 -vd 1 1 -0.3 -vu 0 0 1 -vh 120 -vv 90",
    "-vtv -vd 0 0 -3 -vu 0 1 0 -vh 100 -vv 80 -vo 0.5 -va 4 -vs -0.4",
    "-vtl -vp 1 2 3 -vd 0 2 0 -vh 12 -vv 10 -vo 0.5 -vs 0.1 -vl -0.2",
    "-vtl -vp 0 0 0 -vd 1 -1 -1 -vu 0 1 0 -vh 3 -vv 7",
    "-vta -vp 1 2 3 -vd 0 2 0 -vh 120 -vv 100 -vo 0.5 -vs 0.1 -vl -0.2",
    "-vta -vd 1 0 0 -vh 360 -vv 360",
    "-vta -vd 1 0 0 -vh 180 -vv 180 -vo 1 -va 3",
    "-vtl -vd 0 1 0 -vh 4 -vv 4 -vo 1 -va 3",
    "-vta -vd 0 0 -1 -vu 0 1 0 -vh 200 -vv 150 -vs -0.3",
    "-vth -vp 1 2 3 -vd 0 2 0 -vh 120 -vv 100 -vo 0.5 -vs 0.1 -vl -0.2",
    "-vth -vd 1 1 1 -vh 180 -vv 180",
    "-vts -vp 1 2 3 -vd 0 2 0 -vh 120 -vv 100 -vo 0.5 -vs 0.1 -vl -0.2",
    "-vts -vd -1 0.2 0.3 -vh 300 -vv 250 -vl 0.3",
    "-vtc -vp 1 2 3 -vd 0 2 0 -vh 120 -vv 100 -vo 0.5 -vs 0.1 -vl -0.2",
    "-vtc -vd 1 1 0 -vh 360 -vv 120 -vo 2 -va 5",
];

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn rays_match_vwrays() {
    let Some(bin) = radiance_bin() else {
        eprintln!("skipping: Radiance not found");
        return;
    };
    let (nx, ny) = (7usize, 5usize);
    for opts in RADIANCE_VIEWS {
        let f = view_of(opts).frame().unwrap();
        let rays = vwrays(&bin, opts, nx, ny);
        assert_eq!(rays.len(), nx * ny, "{opts}");
        for j in 0..ny {
            for i in 0..nx {
                let (ro, rd) = rays[j * nx + i];
                let x = (i as f64 + 0.5) / nx as f64;
                let y = 1.0 - (j as f64 + 0.5) / ny as f64;
                match f.ray(x, y) {
                    None => assert!(
                        rd == DVec3::ZERO,
                        "{opts}: pixel {i},{j} outside for us, vwrays gives {rd}"
                    ),
                    Some((o, d, tmax)) => {
                        // vwrays scales directions to the aft clip distance when -va is set.
                        let d = if tmax.is_finite() { d * tmax } else { d };
                        assert!(
                            close(o, ro, 2e-5) && close(d, rd, 2e-5),
                            "{opts}: pixel {i},{j}: ours {o} {d}, vwrays {ro} {rd}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn normaspect_matches_vwrays() {
    let Some(bin) = radiance_bin() else {
        eprintln!("skipping: Radiance not found");
        return;
    };
    let cases = [
        ("-vh 60 -vv 60", 64, 48, 1.0),
        ("-vh 60 -vv 40", 64, 64, 1.0),
        ("-vh 30 -vv 70", 100, 100, 1.0),
        ("-vtc -vh 360 -vv 90", 512, 512, 1.0),
        ("-vth -vh 180 -vv 180", 300, 200, 1.0),
        ("-vtl -vh 10 -vv 3", 640, 480, 1.0),
        ("-vh 60 -vv 40", 64, 64, 0.5),
        ("-vts -vh 200 -vv 100", 333, 222, 1.3),
    ];
    for (opts, x, y, pa) in cases {
        let f = view_of(opts).frame().unwrap();
        let (mut xx, mut yy, mut p) = (x, y, pa);
        normaspect(f.aspect(), &mut p, &mut xx, &mut yy);
        let out = Command::new(bin.join("vwrays"))
            .args([
                "-d",
                "-x",
                &x.to_string(),
                "-y",
                &y.to_string(),
                "-pa",
                &pa.to_string(),
            ])
            .args(words(opts))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).trim().to_string();
        assert_eq!(text, format!("-x {xx} -y {yy}"), "{opts} {x}x{y} pa {pa}");
    }
}

#[test]
fn normaspect_verified_facts() {
    let f = view_of("-vh 60 -vv 60").frame().unwrap();
    let (mut x, mut y, mut pa) = (64, 48, 1.0);
    normaspect(f.aspect(), &mut pa, &mut x, &mut y);
    assert_eq!((x, y), (48, 48));
    let f = view_of("-vh 60 -vv 40").frame().unwrap();
    let (mut x, mut y, mut pa) = (64, 64, 0.0);
    normaspect(f.aspect(), &mut pa, &mut x, &mut y);
    assert_eq!((x, y), (64, 64));
    assert!((pa - 0.630415).abs() < 1e-6, "{pa}");
}

#[test]
fn known_directions_give_known_pixels() {
    // For each type: the view direction is the image centre, and the right/up edges are
    // where the projection's definition puts them.
    let cases: &[(&str, f64)] = &[
        ("-vtv -vh 90 -vv 90", 45.0),
        ("-vta -vh 180 -vv 180", 90.0),
        ("-vth -vh 180 -vv 180", 90.0),
        ("-vts -vh 180 -vv 180", 90.0),
        ("-vtc -vh 180 -vv 90", 90.0),
    ];
    for (opts, edge_deg) in cases {
        let base = format!("{opts} -vp 1 2 3 -vd 1 0 0 -vu 0 0 1");
        let f = view_of(&base).frame().unwrap();
        let (x, y, _) = f.locate(DVec3::new(11.0, 2.0, 3.0)).unwrap();
        assert!(
            (x - 0.5).abs() < 1e-12 && (y - 0.5).abs() < 1e-12,
            "{opts}: {x} {y}"
        );
        // Right is vd × vu = (1,0,0)×(0,0,1) = (0,-1,0).
        let a = edge_deg.to_radians();
        let p = DVec3::new(1.0 + a.cos(), 2.0 - a.sin(), 3.0);
        let (x, y, t) = f.locate(p).unwrap();
        assert!(
            (x - 1.0).abs() < 1e-9 && (y - 0.5).abs() < 1e-9,
            "{opts}: {x} {y}"
        );
        assert!((t - 1.0).abs() < 1e-9, "{opts}: distance {t}");
        let (o, d, tmax) = f.ray(1.0, 0.5).unwrap();
        assert!(close(o + d, p, 1e-9), "{opts}: {o} {d}");
        assert_eq!(tmax, f64::INFINITY);
        if !opts.contains("-vtc") {
            // Up edge: vunit = (0,0,1).
            let p = DVec3::new(1.0 + a.cos(), 2.0, 3.0 + a.sin());
            let (x, y, _) = f.locate(p).unwrap();
            assert!(
                (x - 0.5).abs() < 1e-9 && (y - 1.0).abs() < 1e-9,
                "{opts}: {x} {y}"
            );
        }
    }
    // Cylindrical vertical is perspective: 45° up at -vv 90 is the top edge.
    let f = view_of("-vtc -vh 180 -vv 90 -vd 1 0 0").frame().unwrap();
    let (_, y, _) = f.locate(DVec3::new(1.0, 0.0, 1.0)).unwrap();
    assert!((y - 1.0).abs() < 1e-9);
    // Parallel: world-unit sizes, shift moves the window.
    let f = view_of("-vtl -vp 1 2 3 -vd 1 0 0 -vh 4 -vv 2 -vs 0.25 -vl -0.5")
        .frame()
        .unwrap();
    let (x, y, t) = f.locate(DVec3::new(6.0, 0.0, 3.0)).unwrap();
    assert!((x - 0.75).abs() < 1e-12 && (y - 1.0).abs() < 1e-12 && (t - 5.0).abs() < 1e-12);
    // A 360° angular fisheye: straight behind is on the circle, outside the circle is None.
    let f = view_of("-vta -vh 360 -vv 360").frame().unwrap();
    assert!(f.ray(0.02, 0.02).is_none());
    let (_, d, _) = f.ray(1.0, 0.5).unwrap();
    assert!(close(d, DVec3::new(0.0, -1.0, 0.0), 1e-9), "{d}");
    // Hemispherical: behind is invisible.
    let f = view_of("-vth -vh 180 -vv 180").frame().unwrap();
    assert!(f.locate(DVec3::new(0.0, -1.0, 0.2)).is_none());
    assert!(f.ray(0.01, 0.99).is_none());
    // Perspective: behind is invisible.
    let f = View::default().frame().unwrap();
    assert!(f.locate(DVec3::new(0.0, -1.0, 0.0)).is_none());
}

#[test]
fn clipping_distances() {
    // Perspective clips are planes: the origin lies on the fore plane and the aft distance
    // grows off-axis (verified with rpict on a glow wall).
    let f = view_of("-vh 90 -vv 90 -vo 1 -va 5").frame().unwrap();
    let (o, d, t) = f.ray(1.0, 0.5).unwrap();
    assert!((o.y - 1.0).abs() < 1e-12);
    assert!(((o + t * d).y - 5.0).abs() < 1e-9);
    // Fisheye clips are spheres.
    let f = view_of("-vta -vh 180 -vv 180 -vo 1 -va 5").frame().unwrap();
    let (o, d, t) = f.ray(0.9, 0.3).unwrap();
    assert!((o.length() - 1.0).abs() < 1e-12 && ((o + t * d).length() - 5.0).abs() < 1e-9);
    // Cylindrical clips are cylinders around the view axis... of the horizontal distance.
    let f = view_of("-vtc -vh 180 -vv 90 -vo 1 -va 5").frame().unwrap();
    let (o, d, t) = f.ray(0.8, 0.9).unwrap();
    let e = o + t * d;
    assert!(((o.x * o.x + o.y * o.y).sqrt() - 1.0).abs() < 1e-12);
    assert!(((e.x * e.x + e.y * e.y).sqrt() - 5.0).abs() < 1e-9);
}

#[test]
fn frame_rejects_bad_views() {
    let cases = [
        ("-vd 0 0 0", "zero view direction"),
        ("-vu 0 2 0", "view up parallel"),
        ("-vh 180", "illegal horizontal view size"),
        ("-vh 0", "illegal horizontal view size"),
        ("-vv -3", "illegal vertical view size"),
        ("-vtc -vh 361", "illegal horizontal"),
        ("-vtc -vv 180", "illegal vertical"),
        ("-vta -vh 360.5", "illegal horizontal"),
        ("-vth -vh 181", "illegal horizontal"),
        ("-vts -vh 360", "illegal horizontal"),
        ("-vtl -vh 0.000001", "illegal horizontal"),
        ("-vo 2 -va 1", "fore/aft"),
        ("-vo -1", "fore/aft"),
        ("-va -1", "fore/aft"),
    ];
    for (opts, msg) in cases {
        let e = view_of(opts).frame().unwrap_err();
        assert!(e.to_string().contains(msg), "{opts}: {e}");
    }
    for ok in [
        "-vtc -vh 360 -vv 179",
        "-vth -vh 180 -vv 180",
        "-vts -vh 359",
        "-vs 5",
    ] {
        view_of(ok).frame().unwrap();
    }
}

#[test]
fn crop_tiles_reproduce_parent_rays() {
    let views = [
        "-vtv -vp 1 2 3 -vd 0 2 0 -vh 50 -vv 40 -vs 0.25 -vl -0.1",
        "-vtl -vd 1 1 0 -vh 12 -vv 10 -vs 0.1",
        "-vta -vh 300 -vv 200 -vl 0.2",
        "-vth -vh 180 -vv 160",
        "-vts -vh 300 -vv 250 -vs -0.2",
        "-vtc -vh 360 -vv 100 -vl 0.1",
    ];
    for opts in views {
        let v = view_of(opts);
        let f = v.frame().unwrap();
        let (xd, yd) = (4, 3);
        for tx in 0..xd {
            for ty in 0..yd {
                let (x0, x1) = (tx as f64 / xd as f64, (tx + 1) as f64 / xd as f64);
                let (y0, y1) = (ty as f64 / yd as f64, (ty + 1) as f64 / yd as f64);
                let tv = v.crop(x0, y0, x1, y1).unwrap();
                let tf = tv.frame().unwrap();
                // Aspect of the tile: the parent's scaled by the tile's proportions.
                let want = f.aspect() * (y1 - y0) / (x1 - x0);
                assert!((tf.aspect() - want).abs() < 1e-9 * want, "{opts}");
                for (px, py) in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7), (0.0, 1.0)] {
                    let a = tf.ray(px, py);
                    let b = f.ray(x0 + px * (x1 - x0), y0 + py * (y1 - y0));
                    match (a, b) {
                        (Some((o1, d1, _)), Some((o2, d2, _))) => assert!(
                            close(o1, o2, 1e-9) && close(d1, d2, 1e-9),
                            "{opts} tile {tx},{ty} at {px},{py}"
                        ),
                        (None, None) => {}
                        _ => panic!("{opts} tile {tx},{ty}: visibility differs at {px},{py}"),
                    }
                }
            }
        }
    }
    assert!(View::default().crop(0.5, 0.0, 0.5, 1.0).is_err());
    assert!(View::default().crop(-0.1, 0.0, 0.5, 1.0).is_err());
}

#[test]
fn radiance_string_form() {
    let v = view_of("-vd 0 3 0 -vp 0 0 0.1");
    assert_eq!(
        v.to_radiance_string(),
        "-vtv -vp 0 0 0.1 -vd 0 3 0 -vu 0 0 1 -vh 45 -vv 45 -vo 0 -va 0 -vs 0 -vl 0"
    );
    let v = view_of("-vta -vp 3 2 5 -vd -0.268328 -0.357771 -0.894427 -vu 0 1 0 -vh 1234567");
    assert!(v
        .to_radiance_string()
        .starts_with("-vta -vp 3 2 5 -vd -0.268328 -0.357771 -0.894427 -vu 0 1 0 -vh 1.23457e+06"));
    // And it parses back.
    let back = view_of(&View::default().to_radiance_string());
    assert_eq!(back, View::default());
}

#[test]
fn view_option_errors() {
    let mut v = View::default();
    let e = v.apply_option(&words("-vp 1 abc 3")).unwrap_err();
    assert_eq!(e.to_string(), "option -vp: expected 3 numbers, got 'abc'");
    let e = v.apply_option(&words("-vd 1 2")).unwrap_err();
    assert!(
        e.to_string().contains("-vd") && e.to_string().contains("3 numbers"),
        "{e}"
    );
    let e = v.apply_option(&words("-vh nan")).unwrap_err();
    assert!(e.to_string().contains("'nan'"), "{e}");
    let e = v.apply_option(&words("-vtx")).unwrap_err();
    assert!(e.to_string().contains("-vtx"), "{e}");
    assert_eq!(v.apply_option(&words("-vf x")).unwrap(), None);
    assert_eq!(v.apply_option(&words("-x 4")).unwrap(), None);
    assert_eq!(v.apply_option(&words("-vtc")).unwrap(), Some(1));
    assert_eq!(v.vtype, ViewType::Cylindrical);
}

#[test]
fn view_files() {
    let dir = tempfile::tempdir().unwrap();
    // examp.vp from the examples, plus some noise.
    let p = dir.path().join("examp.vp");
    std::fs::write(
        &p,
        "rview -vp 3 2 5 -vd -0.268328 -0.357771 -0.894427 -vu 0 1 0 -vh 45 -vv 45 -x 470 -y 470\n",
    )
    .unwrap();
    let v = read_view_file(&p, &View::default()).unwrap();
    assert_eq!(v.vp, DVec3::new(3.0, 2.0, 5.0));
    assert_eq!(v.vd, DVec3::new(-0.268328, -0.357771, -0.894427));
    assert_eq!(v.vu, DVec3::Y);
    // Several lines apply in order; non-view lines and a leading directory are fine.
    let p2 = dir.path().join("multi.vf");
    std::fs::write(
        &p2,
        "# comment\nVIEW= -vta -vh 180 -vv 180\nsomething -vp 9 9 9\n/usr/bin/rpict -vp 1 2 3 -x 5 scene.oct\n",
    )
    .unwrap();
    let v = read_view_file(&p2, &View::default()).unwrap();
    assert_eq!(v.vtype, ViewType::Angular);
    assert_eq!(v.vh, 180.0);
    assert_eq!(v.vp, DVec3::new(1.0, 2.0, 3.0));
    // Bad numbers name file:line.
    let p3 = dir.path().join("bad.vf");
    std::fs::write(&p3, "VIEW= -vh 30\n\nVIEW= -vp 1 x 3\n").unwrap();
    let e = read_view_file(&p3, &View::default()).unwrap_err();
    assert!(e.to_string().contains("bad.vf:3:"), "{e}");
    assert!(e.to_string().contains("-vp"), "{e}");
    // No view at all.
    let p4 = dir.path().join("none.vf");
    std::fs::write(&p4, "hello\n").unwrap();
    let e = read_view_file(&p4, &View::default()).unwrap_err();
    assert!(matches!(e, OptError::NoView(_)), "{e}");
    assert!(e.to_string().contains("none.vf"));
    // Missing file.
    let e = read_view_file(&dir.path().join("missing.vf"), &View::default()).unwrap_err();
    assert!(e.to_string().contains("missing.vf"), "{e}");
}

#[test]
fn view_from_picture_header() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("pic.hdr");
    let mut data = b"#?RADIANCE\noconv s.rad\nrpict -vd 0 3 0 -x 4 -y 4 -vp 0 0 0.1\nSOFTWARE= RADIANCE 6.0a\nVIEW= -vtv -vp 0 0 0.1 -vd 0 3 0 -vu 0 0 1 -vh 30 -vv 45 -vo 0 -va 0 -vs 0 -vl 0\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 4\n".to_vec();
    // Binary pixel data, including something that would look like a view line.
    data.extend_from_slice(&[0x02, 0x02, 0x00, 0x04, 0xff, 0x00, 0x80]);
    data.extend_from_slice(b"\nVIEW= -vp 7 7 7\n");
    std::fs::write(&p, data).unwrap();
    let v = read_view_file(&p, &View::default()).unwrap();
    assert_eq!(v.vp, DVec3::new(0.0, 0.0, 0.1));
    assert_eq!(v.vd, DVec3::new(0.0, 3.0, 0.0));
    assert_eq!(v.vh, 30.0);
}

#[test]
fn view_lines() {
    let base = view_of("-vh 20");
    assert_eq!(parse_view_line("FRAME=3", &base).unwrap(), None);
    let v = parse_view_line("VIEW= -vp 1 1 1", &base).unwrap().unwrap();
    assert_eq!((v.vp, v.vh), (DVec3::ONE, 20.0));
    let v = parse_view_line("  rvu -vtl -vh 3", &base).unwrap().unwrap();
    assert_eq!((v.vtype, v.vh), (ViewType::Parallel, 3.0));
    assert!(parse_view_line("pinterp -vp 1", &base).is_err());
    assert_eq!(parse_view_line("rpicture -vp 1 2 3", &base).unwrap(), None);
    assert_eq!(parse_view_line("", &base).unwrap(), None);
}

#[test]
fn view_serde_roundtrip() {
    let v = view_of("-vta -vp 1 2 3 -vd 0.5 -1 2 -vh 100 -va 4");
    let s = serde_json::to_string(&v).unwrap();
    let back: View = serde_json::from_str(&s).unwrap();
    assert_eq!(v, back);
}

fn any_type() -> impl Strategy<Value = ViewType> {
    prop_oneof![
        Just(ViewType::Perspective),
        Just(ViewType::Parallel),
        Just(ViewType::Angular),
        Just(ViewType::Hemispherical),
        Just(ViewType::Planisphere),
        Just(ViewType::Cylindrical),
    ]
}

fn unit() -> impl Strategy<Value = DVec3> {
    (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0)
        .prop_filter("nonzero", |(a, b, c)| a * a + b * b + c * c > 0.01)
        .prop_map(|(a, b, c)| DVec3::new(a, b, c).normalize())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn ray_locate_round_trip(
        vtype in any_type(),
        vp in (-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0),
        vd in unit(),
        vu in unit(),
        vh in 10.0f64..170.0,
        vv in 10.0f64..170.0,
        vs in -0.5f64..0.5,
        vl in -0.5f64..0.5,
        vo in 0.0f64..0.5,
        x in 0.0f64..1.0,
        y in 0.0f64..1.0,
        t in 0.1f64..10.0,
    ) {
        prop_assume!(vd.cross(vu).length() > 0.1);
        let v = View { vtype, vp: DVec3::new(vp.0, vp.1, vp.2), vd, vu, vh, vv, vo, va: 0.0, vs, vl };
        let f = v.frame().unwrap();
        if let Some((o, d, tmax)) = f.ray(x, y) {
            prop_assert!((d.length() - 1.0).abs() < 1e-9);
            prop_assert_eq!(tmax, f64::INFINITY);
            let p = o + t * d;
            let (lx, ly, lt) = f.locate(p).expect("visible point");
            prop_assert!((lx - x).abs() < 1e-7 && (ly - y).abs() < 1e-7, "{} {} vs {} {}", lx, ly, x, y);
            prop_assert!((lt - t).abs() < 1e-7 * (1.0 + t), "{} vs {}", lt, t);
            let (o2, d2, _) = f.ray(lx, ly).unwrap();
            prop_assert!(close(o2 + lt * d2, p, 1e-7));
        }
    }

    #[test]
    fn view_words_never_panic(ws in proptest::collection::vec(
        prop_oneof![
            Just("-vp".to_string()), Just("-vtv".to_string()), Just("-vh".to_string()),
            Just("-vt".to_string()), Just("-vtä".to_string()), Just("NaN".to_string()),
            Just("1e999".to_string()), Just("-vd".to_string()), Just("0".to_string()),
            "\\PC{0,8}", "-v\\PC{0,3}",
        ], 0..12)) {
        let mut v = View::default();
        if v.apply_words(&ws).is_ok() {
            if let Ok(f) = v.frame() {
                let _ = f.ray(0.3, 0.7);
                let _ = f.locate(DVec3::new(1.0, 2.0, 3.0));
            }
        }
        let _ = parse_view_line(&ws.join(" "), &View::default());
        let _ = parse_view_line(&format!("VIEW= {}", ws.join(" ")), &View::default());
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn view_from_real_rpict_picture() {
    let Some(bin) = radiance_bin() else {
        eprintln!("skipping: Radiance not found");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let rad = dir.path().join("w.rad");
    std::fs::write(
        &rad,
        "void glow g 0 0 4 1 1 1 0\ng polygon w 0 0 12 -100 5 -100 100 5 -100 100 5 100 -100 5 100\n",
    )
    .unwrap();
    let oct = dir.path().join("w.oct");
    let out = Command::new(bin.join("oconv")).arg(&rad).output().unwrap();
    assert!(out.status.success());
    std::fs::write(&oct, out.stdout).unwrap();
    let opts = "-vta -vp 0.5 -1 0.25 -vd 0.1 2 0.3 -vu 0 0 1 -vh 170 -vv 150 -vo 0.1 -vs 0.2";
    let pic = dir.path().join("p.hdr");
    let raypath = std::env::var("RAYPATH")
        .unwrap_or_else(|_| format!(".:{}", bin.parent().unwrap_or(&bin).join("lib").display()));
    let status = Command::new(bin.join("rpict"))
        .args(words(opts))
        .args(["-x", "8", "-y", "8", "-w-", "-o"])
        .arg(&pic)
        .arg(&oct)
        .env("RAYPATH", raypath)
        .status()
        .unwrap();
    assert!(status.success());
    let v = read_view_file(&pic, &View::default()).unwrap();
    assert_eq!(v, view_of(opts));
    // Our VIEW= text equals the one rpict wrote.
    let text = std::fs::read(&pic).unwrap();
    let header =
        String::from_utf8_lossy(&text[..text.windows(2).position(|w| w == b"\n\n").unwrap()])
            .to_string();
    let line = header.lines().find(|l| l.starts_with("VIEW=")).unwrap();
    assert_eq!(line, format!("VIEW= {}", v.to_radiance_string()));
}
