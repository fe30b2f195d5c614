//! Robustness and analytic checks of tpict through the real binary: degenerate geometry and
//! grazing views never give non-finite pixels; a scene moved far from the origin renders the
//! same; a diffuse plane under a sphere light has the radiance ρ/π·E of the inverse-square
//! and cosine laws, and beside a mirror it gains the mirror's reflectance times the
//! irradiance of the light's image (a virtual source); a concave polygon with a hole covers exactly its pixels.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use tessera::image::{read_picture, Image};

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/cli")
}

fn tpict_in(dir: &Path) -> Command {
    let mut c = Command::new(tpict_bin());
    c.current_dir(dir)
        .env_remove("TESSERA_ALLOW_COMMANDS")
        .env_remove("SLURM_CPUS_PER_TASK")
        .env("RAYPATH", ".")
        .stdin(Stdio::null());
    c
}

fn workdir() -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    for f in [
        "room.rad",
        "room.vf",
        "lamp.rad",
        "mirrorlamp.rad",
        "degenerate.rad",
    ] {
        std::fs::copy(scenes().join(f), t.path().join(f)).unwrap();
    }
    t
}

/// Render with `args` (ending with the scene files) into `out` and read it back.
fn render(dir: &Path, args: &[&str], out: &str) -> Image {
    run_ok(tpict_in(dir).args(["-o", out]).args(args));
    read_picture(&dir.join(out)).unwrap()
}

// ---------------------------------------------------------------------------------------
// Degenerate geometry

#[test]
fn grazing_rays_coplanar_faces_and_zero_area_polygons_stay_finite() {
    let t = workdir();
    let p = t.path();
    // Views: eye exactly in the floor plane, eye a hair above it, looking along the coplanar
    // faces, edge-on to the wall, straight down a parallel view through the zero-area
    // polygons, and from inside the half-buried light sphere.
    let views: &[&[&str]] = &[
        &[
            "-vp", "-3", "-3", "0", "-vd", "1", "1", "0", "-vh", "90", "-vv", "60",
        ],
        &[
            "-vp", "-3", "-3", "1e-9", "-vd", "1", "1", "0", "-vh", "90", "-vv", "60",
        ],
        &[
            "-vp", "0", "-3", "1e-12", "-vd", "0", "1", "-1e-9", "-vh", "120", "-vv", "120",
        ],
        &[
            "-vp", "-3", "1", "1", "-vd", "1", "0", "0", "-vh", "60", "-vv", "60",
        ],
        &[
            "-vtl", "-vp", "0", "0", "3", "-vd", "0", "0", "-1", "-vu", "0", "1", "0", "-vh", "6",
            "-vv", "6",
        ],
        &[
            "-vtl", "-vp", "-4", "1", "0.5", "-vd", "1", "0", "0", "-vh", "4", "-vv", "2",
        ],
        &[
            "-vta", "-vp", "0", "0", "1e-9", "-vd", "0", "0", "1", "-vu", "0", "1", "0", "-vh",
            "180", "-vv", "180",
        ],
        &[
            "-vth", "-vp", "2", "-2", "0", "-vd", "0", "0", "1", "-vu", "0", "1", "0", "-vh",
            "180", "-vv", "180",
        ],
        &[
            "-vp", "1.5", "1.5", "0.1", "-vd", "0", "0", "-1", "-vu", "0", "1", "0", "-vh", "120",
            "-vv", "120",
        ],
    ];
    let samplings: &[&[&str]] = &[
        &["-ps", "1", "-pj", "0"],
        &["-ps", "4", "-pj", ".67", "-dj", ".7"],
        &["-ps", "1", "-i"],
    ];
    for (k, v) in views.iter().enumerate() {
        for (s, sampling) in samplings.iter().enumerate() {
            let out = format!("v{k}_{s}.hdr");
            let mut args: Vec<&str> =
                vec!["-x", "40", "-y", "40", "-ab", "0", "-av", ".1", ".1", ".1"];
            args.extend_from_slice(v);
            args.extend_from_slice(sampling);
            args.push("degenerate.rad");
            let img = render(p, &args, &out);
            for (i, q) in img.pixels.iter().enumerate() {
                assert!(
                    q.iter().all(|c| c.is_finite() && *c >= 0.0),
                    "view {v:?} {sampling:?}: pixel {i} is {q:?}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Translation invariance

#[test]
fn scene_far_from_origin_renders_the_same() {
    let t = workdir();
    let p = t.path();
    std::fs::write(p.join("far.rad"), "!xform -t 1e6 -1e6 1e6 room.rad\n").unwrap();
    let common = ["-x", "96", "-y", "96", "-ps", "1", "-pj", "0", "-ab", "0"];
    let view = [
        "-vd", "0", "1", "-0.3", "-vu", "0", "0", "1", "-vh", "40", "-vv", "40",
    ];
    let mut a = common.to_vec();
    a.extend_from_slice(&view);
    a.extend_from_slice(&["-vp", "0", "-4", "1.5", "room.rad"]);
    let near = render(p, &a, "near.hdr");
    let mut b = common.to_vec();
    b.extend_from_slice(&view);
    b.extend_from_slice(&["-vp", "1000000", "-1000004", "1000001.5", "far.rad"]);
    let far = render(p, &b, "far.hdr");
    assert_finite(&far);
    assert!(
        near.pixels.iter().filter(|q| q[0] > 0.01).count() > near.pixels.len() / 2,
        "mostly black picture"
    );
    assert_eq!((near.width, near.height), (far.width, far.height));
    let c = compare(&near.pixels_f64(), &far.pixels_f64(), 0.01);
    eprintln!("translated: {c:?}");
    // Pixels differing by more than 2% (an edge may move by a hair).
    let differing = near
        .pixels_f64()
        .iter()
        .zip(far.pixels_f64())
        .filter(|(x, y)| compare(&[**x], &[*y], 0.01).max > 0.02)
        .count();
    assert!(
        differing <= near.pixels.len() / 100,
        "{differing} of {} pixels differ by more than 2%",
        near.pixels.len()
    );
    assert!(c.rms < 0.02, "relative RMS {}", c.rms);
    assert!(
        c.mean_lum < 0.002,
        "mean luminance differs by {}",
        c.mean_lum
    );
}

// ---------------------------------------------------------------------------------------
// Analytic direct lighting

/// Lamp scene (tests/scenes/cli/lamp.rad): sphere `light` of radiance 100 and radius .1 at
/// (0, 0, 2) over a plastic floor z = 0 of reflectance .5 (spec 0, rough 0). At (x, y, 0):
/// E = π L (r/d)² cos θ (exact for a sphere above the horizon), L_floor = ρ/π · E.
fn floor_radiance(x: f64, y: f64) -> f64 {
    let (l, r, h, rho) = (100.0, 0.1, 2.0, 0.5);
    let d2 = x * x + y * y + h * h;
    let e = std::f64::consts::PI * l * r * r / d2 * (h / d2.sqrt());
    rho / std::f64::consts::PI * e
}

/// Every pixel of an n × n parallel view straight down (centred on x = `cx`, y = 0, `size`
/// units square) is within 1% of `want(x, y)` in every channel.
fn assert_floor_view(img: &Image, n: usize, cx: f64, size: f64, want: fn(f64, f64) -> f64) {
    assert_eq!((img.width, img.height), (n, n));
    for j in 0..n {
        for i in 0..n {
            let x = cx + ((i as f64 + 0.5) / n as f64 - 0.5) * size;
            let y = (0.5 - (j as f64 + 0.5) / n as f64) * size;
            let want = want(x, y);
            for c in img.get(i, j) {
                let rel = (c as f64 - want).abs() / want;
                assert!(
                    rel < 0.01,
                    "pixel ({i},{j}) at ({x:.2},{y:.2}): {c}, want {want:.5} ({:.2}% off)",
                    rel * 100.0
                );
            }
        }
    }
}

#[test]
fn diffuse_plane_under_sphere_light_follows_inverse_square_and_cosine() {
    let t = workdir();
    let p = t.path();
    // Parallel view from z = 1 (below the lamp) straight down, 8 units square: points up to
    // 5.6 units from below the lamp (cos θ down to .34).
    let n = 11;
    let size = 8.0;
    let img = render(
        p,
        &[
            "-vtl", "-vp", "0", "0", "1", "-vd", "0", "0", "-1", "-vu", "0", "1", "0", "-vh", "8",
            "-vv", "8", "-x", "11", "-y", "11", "-ps", "1", "-pj", "0", "-ab", "0", "-av", "0",
            "0", "0", "lamp.rad",
        ],
        "lamp.hdr",
    );
    assert_floor_view(&img, n, 0.0, size, floor_radiance);
    // A narrow perspective view from above the lamp, off to the side, looking down at a
    // few floor points: the pixel at the image centre sees the point on the view axis.
    for (x, y) in [(1.0, 0.5), (-2.0, 1.5), (0.3, -3.0)] {
        let vp = [x + 0.5, y, 3.0];
        let vd = [x - vp[0], y - vp[1], -vp[2]];
        let args: Vec<String> = [
            "-vtv", "-vh", "1", "-vv", "1", "-x", "3", "-y", "3", "-ps", "1", "-pj", "0", "-ab",
            "0", "-av", "0", "0", "0",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain(["-vp".to_string()])
        .chain(vp.iter().map(|v| v.to_string()))
        .chain(["-vd".to_string()])
        .chain(vd.iter().map(|v| v.to_string()))
        .chain(["lamp.rad".to_string()])
        .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let img = render(p, &args, &format!("persp_{x}_{y}.hdr"));
        let want = floor_radiance(x, y);
        for c in img.get(1, 1) {
            let rel = (c as f64 - want).abs() / want;
            assert!(rel < 0.01, "point ({x},{y}): {c}, want {want:.5}");
        }
    }
}

/// The floor of `mirrorlamp.rad` at (x, y, 0): the lamp's irradiance plus the mirror's
/// reflectance (.6) times that of its image at (6, 0, 2); every path to the image crosses
/// the mirror plane x = 3 on the mirror (|y| < 10, 0 < z < 10).
fn mirror_floor_radiance(x: f64, y: f64) -> f64 {
    let (l, r, h, rho, rho_m) = (100.0, 0.1, 2.0, 0.5, 0.6);
    let e = |dx: f64| {
        let d2 = dx * dx + y * y + h * h;
        std::f64::consts::PI * l * r * r / d2 * (h / d2.sqrt())
    };
    rho / std::f64::consts::PI * (e(x) + rho_m * e(x - 6.0))
}

#[test]
fn virtual_source_in_a_mirror_adds_its_reflectance_times_the_image() {
    let t = workdir();
    let p = t.path();
    // Parallel view straight down over x in [-3, 2], y in [-2.5, 2.5]: the image's share of
    // the irradiance goes from 6% (x = -3) to 42% (x = 2).
    let n = 11;
    let args: Vec<&str> = "-vtl -vp -0.5 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 5 -vv 5 -x 11 -y 11 \
        -ps 1 -pj 0 -ab 0 -av 0 0 0 -dt 0 mirrorlamp.rad"
        .split_whitespace()
        .collect();
    let img = render(p, &args, "mirrorlamp.hdr");
    assert_floor_view(&img, n, -0.5, 5.0, mirror_floor_radiance);
}

/// A mirror shelf with an alternate material under a lamp, a grey floor and back wall, seen
/// by a view that never sees the shelf itself; `shelf` is the shelf's material line.
fn shelf_scene(shelf: &str) -> String {
    format!(
        "void light bright 0 0 3 50 50 50\n\
         bright sphere lamp 0 0 4 0 0 2 0.1\n\
         void plastic grey 0 0 5 .5 .5 .5 0 0\n\
         void plastic blue 0 0 5 .1 .2 .6 0 0\n\
         {shelf}\n\
         grey polygon floor 0 0 12 -5 -5 0 5 -5 0 5 5 0 -5 5 0\n\
         grey polygon back 0 0 12 -5 3 0 5 3 0 5 3 4 -5 3 4\n\
         shelfmat polygon shelf 0 0 12 -1 1 1 1 1 1 1 2 1 -1 2 1\n"
    )
}

/// Rays descended from an ambient sample see a mirror, not its alternate material (as rpict
/// does): a picture of the wall just above the shelf (whose indirect light comes partly off
/// the shelf; the view does not see the shelf) is the same with `mirror shelfmat 1 blue` as with a bare mirror, and differs
/// from the one where the shelf is made of the alternate itself. A mirror seen from behind is
/// black (`-bv+`) or invisible (`-bv-`).
#[test]
fn mirrors_alternate_is_not_seen_by_ambient_rays_and_mirrors_have_no_back() {
    let t = workdir();
    let p = t.path();
    for (name, shelf) in [
        ("alt", "void mirror shelfmat 1 blue 0 3 .8 .8 .8"),
        ("bare", "void mirror shelfmat 0 0 3 .8 .8 .8"),
        ("blue", "void plastic shelfmat 0 0 5 .1 .2 .6 0 0"),
    ] {
        std::fs::write(p.join(format!("shelf_{name}.rad")), shelf_scene(shelf)).unwrap();
    }
    let args = |scene: &str| -> Vec<String> {
        "-vtv -vp 0 -1 1.5 -vd 0 1 0 -vu 0 0 1 -vh 40 -vv 10 -x 24 -y 8 -ps 1 -pj 0 \
         -ab 1 -aa 0 -ad 256"
            .split_whitespace()
            .map(String::from)
            .chain([scene.to_string()])
            .collect()
    };
    let pic = |name: &str| {
        let a = args(&format!("shelf_{name}.rad"));
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        render(p, &a, &format!("{name}.hdr"))
    };
    let (alt, bare, blue) = (pic("alt"), pic("bare"), pic("blue"));
    assert_eq!(
        alt.pixels, bare.pixels,
        "ambient rays must see the mirror, not its alternate"
    );
    let sum = |img: &Image| -> f64 { img.pixels.iter().map(|p| p[1] as f64).sum() };
    let diff: f64 = alt
        .pixels
        .iter()
        .zip(&blue.pixels)
        .map(|(a, b)| (a[1] - b[1]).abs() as f64)
        .sum::<f64>()
        / sum(&alt);
    assert!(
        diff > 0.01,
        "the mirror's indirect light must differ from blue's: {diff}"
    );
    // From below the shelf, looking up through it at the lamp: black, or the lamp with -bv-.
    let below = |extra: &str, out: &str| {
        let a: Vec<String> = "-vtv -vp 0 1.9 0.5 -vd 0 -1.9 1.5 -vu 0 0 1 -vh 1 -vv 1 -x 1 -y 1 \
            -ps 1 -pj 0 -ab 0"
            .split_whitespace()
            .chain(extra.split_whitespace())
            .map(String::from)
            .chain(["shelf_bare.rad".to_string()])
            .collect();
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        render(p, &a, out).get(0, 0)
    };
    assert_eq!(below("", "back.hdr"), [0.0; 3], "a mirror has no back");
    let through = below("-bv-", "back_invisible.hdr");
    assert!(
        through[0] > 0.0,
        "-bv- sees through a mirror's back: {through:?}"
    );
}

// ---------------------------------------------------------------------------------------
// Polygon coverage

/// Outer boundary (counter-clockwise from above): a U with a slanted edge.
const OUTER: &[(f64, f64)] = &[
    (-4.0, -4.0),
    (4.0, -4.0),
    (4.0, 2.0),
    (3.0, 4.0),
    (2.0, 4.0),
    (2.0, 0.0),
    (-2.0, 0.0),
    (-3.0, 4.0),
    (-4.0, 4.0),
];
/// Hole in the bottom bar (clockwise from above), joined to the outer boundary by a seam
/// from (-4, -4).
const HOLE: &[(f64, f64)] = &[(-1.0, -3.0), (0.0, -1.0), (1.0, -3.0)];

fn inside_ring(pt: (f64, f64), ring: &[(f64, f64)]) -> bool {
    let mut inside = false;
    for k in 0..ring.len() {
        let a = ring[k];
        let b = ring[(k + 1) % ring.len()];
        if (a.1 > pt.1) != (b.1 > pt.1) {
            let x = a.0 + (pt.1 - a.1) / (b.1 - a.1) * (b.0 - a.0);
            if pt.0 < x {
                inside = !inside;
            }
        }
    }
    inside
}

fn dist_to_ring(pt: (f64, f64), ring: &[(f64, f64)]) -> f64 {
    let mut best = f64::INFINITY;
    for k in 0..ring.len() {
        let a = ring[k];
        let b = ring[(k + 1) % ring.len()];
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let s = (((pt.0 - a.0) * dx + (pt.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        let (cx, cy) = (a.0 + s * dx, a.1 + s * dy);
        best = best.min(((pt.0 - cx).powi(2) + (pt.1 - cy).powi(2)).sqrt());
    }
    best
}

#[test]
fn concave_polygon_with_hole_covers_exactly_its_pixels() {
    let t = workdir();
    let p = t.path();
    let mut verts: Vec<(f64, f64)> = OUTER.to_vec();
    verts.push(OUTER[0]);
    verts.extend_from_slice(HOLE);
    verts.push(HOLE[0]);
    let coords: Vec<String> = verts.iter().map(|(x, y)| format!("{x} {y} 0")).collect();
    let scene = format!(
        "void light glowing\n0\n0\n3 2 3 4\n\nglowing polygon shape\n0\n0\n{} {}\n",
        3 * verts.len(),
        coords.join("\n")
    );
    std::fs::write(p.join("shape.rad"), scene).unwrap();
    let (n, size) = (100usize, 10.0);
    let img = render(
        p,
        &[
            "-vtl",
            "-vp",
            "0",
            "0",
            "1",
            "-vd",
            "0",
            "0",
            "-1",
            "-vu",
            "0",
            "1",
            "0",
            "-vh",
            "10",
            "-vv",
            "10",
            "-x",
            "100",
            "-y",
            "100",
            "-ps",
            "1",
            "-pj",
            "0",
            "-ab",
            "0",
            "-av",
            "0",
            "0",
            "0",
            "shape.rad",
        ],
        "shape.hdr",
    );
    assert_eq!((img.width, img.height), (n, n));
    let half = 0.5 * size / n as f64;
    let (mut checked, mut lit) = (0, 0);
    for j in 0..n {
        for i in 0..n {
            let x = ((i as f64 + 0.5) / n as f64 - 0.5) * size;
            let y = (0.5 - (j as f64 + 0.5) / n as f64) * size;
            let pt = (x, y);
            if dist_to_ring(pt, OUTER) < half || dist_to_ring(pt, HOLE) < half {
                continue;
            }
            let inside = inside_ring(pt, OUTER) && !inside_ring(pt, HOLE);
            let want = if inside { [2.0, 3.0, 4.0] } else { [0.0; 3] };
            let got = img.get(i, j);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= 0.02 * want[c] + 1e-6,
                    "pixel ({i},{j}) at ({x:.3},{y:.3}) is {got:?}, want {want:?} ({})",
                    if inside { "inside" } else { "outside" }
                );
            }
            checked += 1;
            lit += inside as usize;
        }
    }
    assert!(
        checked > n * n * 3 / 4 && lit > n * n / 4,
        "{checked} checked, {lit} lit"
    );
}

// ---------------------------------------------------------------------------------------
// Zero-area surfaces Radiance only warns about

const LIT_FLOOR: &str =
    "void light bright\n0\n0\n3 50 50 50\n\nbright sphere lamp\n0\n0\n4 0 0 2 .2\n\n\
                         void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n\n\
                         grey polygon floor\n0\n0\n12 -5 -5 0  5 -5 0  5 5 0  -5 5 0\n";

const FROM_ABOVE: &[&str] = &[
    "-vp", "0", "-3", "3", "-vd", "0", "1", "-1", "-vh", "60", "-vv", "60", "-x", "32", "-y", "32",
    "-ab", "0",
];

/// A ring whose inner and outer radii are equal has no area. oconv only warns ("illegal
/// radii for ring") and rpict renders the scene without it.
#[test]
fn zero_width_ring_is_skipped_with_a_warning() {
    let t = workdir();
    let p = t.path();
    let scene = format!("{LIT_FLOOR}\ngrey ring thin\n0\n0\n8 0 0 .5  0 0 1  .5 .5\n");
    std::fs::write(p.join("ring.rad"), &scene).unwrap();
    std::fs::write(p.join("plain.rad"), LIT_FLOOR).unwrap();
    let o = Command::new(tpict_bin())
        .current_dir(p)
        .args(FROM_ABOVE)
        .args(["-o", "ring.hdr", "ring.rad"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "tpict failed: {err}");
    assert!(err.contains("thin"), "no warning naming the ring: {err}");
    let ring = read_picture(&p.join("ring.hdr")).unwrap();
    let plain = render(p, &[FROM_ABOVE, &["plain.rad"]].concat(), "plain.hdr");
    assert_finite(&ring);
    assert_eq!(
        ring.pixels, plain.pixels,
        "the zero-width ring changed the picture"
    );
}

/// A light polygon with zero area: Radiance's rpict stops ("zero source area"); tpict may
/// refuse it too (one located line, exit 1) or render, but never with a non-finite pixel.
#[test]
fn zero_area_light_polygon_is_refused_or_harmless() {
    let t = workdir();
    let p = t.path();
    let scene = format!(
        "{LIT_FLOOR}\nbright polygon sliver\n0\n0\n9 -1 0 1  0 0 1  1 0 1\n\
         bright polygon speck\n0\n0\n9 1 1 1  1 1 1  1 1 1\n"
    );
    std::fs::write(p.join("zl.rad"), scene).unwrap();
    let o = Command::new(tpict_bin())
        .current_dir(p)
        .args(FROM_ABOVE)
        .args(["-ps", "1", "-o", "zl.hdr", "zl.rad"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    if o.status.success() {
        let img = read_picture(&p.join("zl.hdr")).unwrap();
        assert_finite(&img);
        assert!(img.pixels.iter().any(|q| q[0] > 0.01), "black picture");
    } else {
        assert_eq!(o.status.code(), Some(1));
        let lines: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
        assert_eq!(lines.len(), 1, "{err}");
        assert!(lines[0].contains("zl.rad:"), "{err}");
        assert!(!p.join("zl.hdr").exists());
    }
}

/// Primitives of astronomical size (a sky sphere of radius 1e20, coordinates of 1e25,
/// polygon vertices of ±1e300) made the BVH build panic inside obvhs (its f32 box areas
/// overflowed); a light of radiance 1e308 gave infinite pixels in EXR output. Both now
/// render: the lamp inside the huge sphere is seen, every pixel is finite.
#[test]
fn astronomical_sizes_and_radiances_render_finite_pictures() {
    let t = tempfile::tempdir().unwrap();
    let p = t.path();
    std::fs::write(
        p.join("huge.rad"),
        "void plastic gray 0 0 5 .5 .5 .5 0 0\n\
         void light bright 0 0 3 10 10 10\n\
         bright sphere lamp 0 0 4 0 0 1 .2\n\
         gray sphere sky 0 0 4 0 0 1 1e20\n",
    )
    .unwrap();
    // Coordinates no renderer can resolve next to a lamp of radius 0.2 (rpict's own output
    // is not a number here): no panic, finite pixels.
    std::fs::write(
        p.join("extreme.rad"),
        "void plastic gray 0 0 5 .5 .5 .5 0 0\n\
         void light bright 0 0 3 10 10 10\n\
         bright sphere lamp 0 0 4 0 0 1 .2\n\
         gray sphere far 0 0 4 1e25 0 0 1\n\
         gray polygon wide 0 0 9 -1e300 0 -1 1e300 0 -1 0 1e300 -1\n",
    )
    .unwrap();
    std::fs::write(
        p.join("hot.rad"),
        "void light hot 0 0 3 1e308 1e308 1e308\n\
         hot sphere lamp 0 0 4 0 0 0 .5\n",
    )
    .unwrap();
    let view = [
        "-vp", "0", "-5", "0", "-vd", "0", "1", "0", "-x", "24", "-y", "24",
    ];
    let finite = |img: &Image| img.pixels.iter().flatten().all(|v| v.is_finite());
    // Every pixel traced: the lamp is under two pixels wide, and adaptive sampling may pass
    // between it (its quincunx at the default -ps 4 has one sample per 18 pixels).
    let mut args: Vec<&str> = view.to_vec();
    args.extend([
        "-ps", "1", "-vu", "0", "0", "1", "-vh", "60", "-vv", "60", "huge.rad",
    ]);
    let huge = render(p, &args, "huge.hdr");
    assert!(finite(&huge));
    let brightest = huge.pixels.iter().flatten().fold(0f32, |m, &v| m.max(v));
    assert!(brightest > 5.0, "the lamp is seen: {brightest}");
    let mut args: Vec<&str> = view.to_vec();
    args.push("extreme.rad");
    assert!(finite(&render(p, &args, "extreme.hdr")));
    for out in ["hot.exr", "hot.hdr"] {
        let mut args: Vec<&str> = view.to_vec();
        args.push("hot.rad");
        let img = render(p, &args, out);
        assert!(finite(&img), "{out}");
        assert!(
            img.pixels.iter().flatten().any(|&v| v > 1e30),
            "{out}: the light is seen"
        );
    }
}

/// Input that cannot be scene text is refused before it exhausts memory: reading
/// `/dev/zero` as a scene grew to 4 GB in 10 s; now its first NUL byte ends the read, and a
/// line longer than 64 MiB is refused too, both with the file named.
#[test]
fn binary_and_endless_input_is_refused_early() {
    let t = tempfile::tempdir().unwrap();
    let p = t.path();
    let zero = tpict_in(p)
        .args(["-x", "8", "-y", "8", "/dev/zero"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&zero.stderr);
    assert!(!zero.status.success());
    assert!(
        err.contains("/dev/zero") && err.contains("binary data"),
        "{err}"
    );
    let mut long = b"void plastic m 0 0 5 .5 .5 .5 0 0\n".to_vec();
    long.resize(long.len() + (64 << 20) + 16, b'a');
    std::fs::write(p.join("long.rad"), &long).unwrap();
    let out = tpict_in(p)
        .args(["-x", "8", "-y", "8", "long.rad"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("long.rad") && err.contains("longer than 64 MiB"),
        "{err}"
    );
}

/// `-n` beyond a few threads per core is cut down with a warning (`-n 10000` took 91 s
/// for a 16×16 picture); the picture is the same.
#[test]
fn absurd_thread_counts_are_capped() {
    let t = workdir();
    let p = t.path();
    let out = tpict_in(p)
        .args(["-vf", "room.vf", "-x", "16", "-y", "16", "-n", "100000"])
        .args(["-o", "many.hdr", "room.rad"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("100000 threads requested"), "{err}");
    let one = render(
        p,
        &[
            "-vf", "room.vf", "-x", "16", "-y", "16", "-n", "1", "room.rad",
        ],
        "one.hdr",
    );
    let many = read_picture(&p.join("many.hdr")).unwrap();
    assert_eq!(one.pixels, many.pixels);
}

/// A picture used as a pattern whose header claims more pixels than memory can hold (a
/// run-length picture is small on disk: 20000² made a 9.4 GB reader) is refused before a
/// pixel is decoded, naming the file; the render fails cleanly with no output.
#[test]
fn pictures_too_large_for_memory_are_refused_before_decoding() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    // 60000 x 60000 = 3.6e9 pixels: about 107 GiB to read, beyond any machine here.
    std::fs::write(
        d.join("big.hdr"),
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 60000 +X 60000\n",
    )
    .unwrap();
    std::fs::write(d.join("pic.cal"), "u = Px; v = Py;\n").unwrap();
    std::fs::write(
        d.join("s.rad"),
        "void colorpict pic 7 red green blue big.hdr pic.cal u v 0 0\n\
         pic plastic p 0 0 5 1 1 1 0 0\n\
         p sphere s 0 0 4 0 0 0 1\n\
         void light l 0 0 3 1 1 1\n\
         l sphere sun 0 0 4 0 0 5 .5\n",
    )
    .unwrap();
    let o = tpict_in(d)
        .args([
            "-vp", "0", "-5", "0", "-vd", "0", "1", "0", "-x", "8", "-y", "8", "-o", "out.hdr",
        ])
        .arg("s.rad")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("big.hdr") && err.contains("GiB"), "{err}");
    assert!(!d.join("out.hdr").exists());
}
