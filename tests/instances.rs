//! Instances and meshes against real Radiance (tests/scenes/instances): octrees made by
//! real `oconv` (unfrozen) and `oconv -f` (frozen), nested instances, the octree's own
//! materials (`void`) and a modifier replacing them, meshes made by real `obj2mesh` with
//! normals and (u,v); tpict's pictures against rpict's on the same octree at `-ab 0` and
//! `-ab 1` (`-ps 1 -pj 0`), under Radiance's test-suite tolerances. A scene of thousands of
//! instances renders; a scene moved 1e6 away or scaled renders the same picture; damaged
//! octrees and meshes, instance loops and missing files are one error line naming the
//! file. Skips (with a message) when Radiance is not installed.

mod common;

use common::*;
use std::path::Path;
use std::process::{Command, Output};
use tessera::image::{read_picture, Image};

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/instances");

/// A sphere of 24×12 quads (two triangles each) with normals and (u,v), in group `ball`
/// with material `stripes`, and a flat quad without normals or (u,v) in material `green`.
fn ball_obj() -> String {
    let (nu, nv) = (24, 12);
    let mut s = String::from("g ball\n");
    for j in 0..=nv {
        let th = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..=nu {
            let ph = std::f64::consts::TAU * i as f64 / nu as f64;
            let (x, y, z) = (th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            s += &format!("v {x:.6} {y:.6} {:.6}\nvn {x:.6} {y:.6} {z:.6}\n", z + 1.2);
            s += &format!(
                "vt {:.6} {:.6}\n",
                i as f64 / nu as f64,
                j as f64 / nv as f64
            );
        }
    }
    s += "usemtl stripes\n";
    let idx = |i: usize, j: usize| j * (nu + 1) + i + 1;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j));
            s += &format!("f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}\n");
            s += &format!("f {a}/{a}/{a} {c}/{c}/{c} {d}/{d}/{d}\n");
        }
    }
    let base = (nv + 1) * (nu + 1);
    s += "usemtl green\nv -3 -3 0.01\nv -1 -3 0.01\nv -1 -1 0.01\nv -3 -1 0.01\n";
    s += &format!("f {} {} {} {}\n", base + 1, base + 2, base + 3, base + 4);
    s
}

/// A work folder with the scene files, the octrees (`obj.oct`, `objf.oct` frozen,
/// `pobj.oct`, `row.oct` frozen over pobj.oct) and the mesh `ball.rtm`, all made by real
/// Radiance.
fn workdir(bin: &Path) -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    for e in std::fs::read_dir(SRC).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), t.path().join(e.file_name())).unwrap();
    }
    let oconv = |args: &[&str], out: &str| {
        let data = run_ok(radiance(bin, "oconv").current_dir(t.path()).args(args));
        std::fs::write(t.path().join(out), data).unwrap();
    };
    oconv(&["obj.rad"], "obj.oct");
    oconv(&["-f", "obj.rad"], "objf.oct");
    oconv(&["pobj.rad"], "pobj.oct");
    oconv(&["-f", "row.rad"], "row.oct");
    std::fs::write(t.path().join("ball.obj"), ball_obj()).unwrap();
    run_ok(radiance(bin, "obj2mesh").current_dir(t.path()).args([
        "-a",
        "ballmat.rad",
        "ball.obj",
        "ball.rtm",
    ]));
    t
}

fn opts<'a>(view: &'a str, ab: &'a str) -> Vec<&'a str> {
    vec![
        "-vf", view, "-x", "256", "-y", "200", "-ab", ab, "-ps", "1", "-pj", "0", "-av", ".05",
        ".05", ".05",
    ]
}

/// Unfrozen and frozen octrees, void and modified instances, rotated, scaled and mirrored;
/// tpict reads the scene file, the octree oconv made of it, and a frozen octree of it.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn octree_instances_void_and_modified() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg("inst.rad"));
    std::fs::write(d.join("inst.oct"), oct).unwrap();
    let frozen = run_ok(
        radiance(&bin, "oconv")
            .current_dir(d)
            .args(["-f", "inst.rad"]),
    );
    std::fs::write(d.join("instf.oct"), frozen).unwrap();
    for ab in ["0", "1"] {
        let tol = if ab == "0" { &SUITE } else { &AMBIENT };
        check_against_rpict(
            &bin,
            d,
            &["inst.rad"],
            "inst.oct",
            &opts("inst.vf", ab),
            tol,
        );
    }
    check_against_rpict(
        &bin,
        d,
        &["instf.oct"],
        "instf.oct",
        &opts("inst.vf", "0"),
        &SUITE,
    );
    // The unfrozen octree is its scene file: the same picture, bit for bit.
    let o = opts("inst.vf", "0");
    run_ok(tpict_in(d).args(&o).args(["-o", "a.hdr", "inst.rad"]));
    run_ok(tpict_in(d).args(&o).args(["-o", "b.hdr", "inst.oct"]));
    let (a, b) = (
        read_picture(&d.join("a.hdr")).unwrap(),
        read_picture(&d.join("b.hdr")).unwrap(),
    );
    assert!(a.pixels == b.pixels, "inst.oct renders unlike inst.rad");
}

/// Octrees as older oconv wrote them: the header starts with the command line (no
/// `#?RADIANCE`), and before 1991 had no FORMAT line either. rpict instances them; tpict
/// reads them, as instances and as the scene, like the octree they were cut from.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn octrees_with_older_headers() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let frozen = std::fs::read(d.join("objf.oct")).unwrap();
    let no_magic = frozen
        .strip_prefix(b"#?RADIANCE\n".as_slice())
        .unwrap()
        .to_vec();
    assert!(
        no_magic.starts_with(b"oconv"),
        "oconv's header: {:?}",
        &no_magic[..20]
    );
    std::fs::write(d.join("old.oct"), &no_magic).unwrap();
    let text = String::from_utf8_lossy(&no_magic[..no_magic.len().min(4000)]).to_string();
    let format_line = "FORMAT=Radiance_octree\n";
    let at = text.find(format_line).expect("a FORMAT line");
    let mut oldest = no_magic.clone();
    oldest.drain(at..at + format_line.len());
    std::fs::write(d.join("oldest.oct"), &oldest).unwrap();
    for oct in ["old.oct", "oldest.oct"] {
        let scene = format!(
            "void light white 0 0 3 50 50 50\nwhite sphere lamp 0 0 4 0 0 6 0.5\n\
             void plastic grey 0 0 5 .5 .5 .5 0 0\n\
             grey polygon floor 0 0 12 -10 -10 0 10 -10 0 10 10 0 -10 10 0\n\
             void instance i1 7 {oct} -rz 30 -t 1 0 0 0 0\n"
        );
        let rad = format!("use-{oct}.rad");
        std::fs::write(d.join(&rad), scene).unwrap();
        let top = run_ok(radiance(&bin, "oconv").current_dir(d).arg(&rad));
        let top_name = format!("use-{oct}");
        std::fs::write(d.join(&top_name), top).unwrap();
        check_against_rpict(&bin, d, &[&rad], &top_name, &opts("inst.vf", "0"), &SUITE);
        // As the scene itself: the same picture as the octree it was cut from.
        let o = opts("inst.vf", "0");
        let (a, b) = (format!("a-{oct}.hdr"), format!("b-{oct}.hdr"));
        run_ok(tpict_in(d).args(&o).args(["-o", &a, "objf.oct"]));
        // Named without `.oct`: recognised by its header.
        let plain = format!("{oct}-scene");
        std::fs::copy(d.join(oct), d.join(&plain)).unwrap();
        run_ok(tpict_in(d).args(&o).args(["-o", &b, &plain]));
        let (pa, pb) = (
            read_picture(&d.join(&a)).unwrap(),
            read_picture(&d.join(&b)).unwrap(),
        );
        assert!(pa.pixels == pb.pixels, "{oct} renders unlike objf.oct");
    }
}

/// An octree holding instances (row.oct, frozen, one of them modified), instanced twice
/// (once modified: the outermost modifier wins), with patterns in the octrees' own
/// coordinates.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn nested_instances_with_patterns() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg("nest.rad"));
    std::fs::write(d.join("nest.oct"), oct).unwrap();
    for ab in ["0", "1"] {
        let tol = if ab == "0" { &SUITE } else { &AMBIENT };
        check_against_rpict(
            &bin,
            d,
            &["nest.rad"],
            "nest.oct",
            &opts("inst.vf", ab),
            tol,
        );
    }
}

/// Meshes from obj2mesh: smooth normals, (u,v) patterns, a triangle without either, the
/// mesh's materials and a modifier replacing them.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn meshes_with_normals_and_uv() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg("mesh.rad"));
    std::fs::write(d.join("mesh.oct"), oct).unwrap();
    for ab in ["0", "1"] {
        let tol = if ab == "0" { &SUITE } else { &AMBIENT };
        check_against_rpict(
            &bin,
            d,
            &["mesh.rad"],
            "mesh.oct",
            &opts("mesh.vf", ab),
            tol,
        );
    }
}

/// 2,500 instances (a 50×50 grid, alternately of two octrees) under a light.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn a_large_instance_count_renders() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let mut s = String::from(
        "void light white 0 0 3 20 20 20\nwhite sphere lamp 0 0 4 25 25 40 3\n\
         void plastic grey 0 0 5 .5 .5 .5 0 0\n\
         grey polygon floor 0 0 12 -1 -1 0 51 -1 0 51 51 0 -1 51 0\n",
    );
    for i in 0..50 {
        for j in 0..50 {
            let f = if (i + j) % 2 == 0 {
                "obj.oct"
            } else {
                "pobj.oct"
            };
            s += &format!(
                "void instance g{i}.{j} 9 {f} -rz {} -s 0.4 -t {} {} 0 0 0\n",
                (i * 37 + j * 11) % 360,
                i as f64 + 0.5,
                j as f64 + 0.5
            );
        }
    }
    std::fs::write(d.join("many.rad"), s).unwrap();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg("many.rad"));
    std::fs::write(d.join("many.oct"), oct).unwrap();
    let o = [
        "-vp", "25", "-20", "30", "-vd", "0", "1", "-1", "-vh", "60", "-vv", "50", "-x", "256",
        "-y", "200", "-ab", "0", "-ps", "1", "-pj", "0", "-av", ".05", ".05", ".05",
    ];
    check_against_rpict(&bin, d, &["many.rad"], "many.oct", &o, &SUITE);
}

/// Instances nested 24 deep, each level holding two of the one below (2²⁴ spheres from
/// 114-byte octrees): refused at the instance that makes the placements pass the limit
/// (naming its file and line), before anything is flattened, in little time and memory.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn multiplying_instances_are_refused_at_the_line_that_crosses_the_limit() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let oconv = |k: usize, text: String| {
        let rad = format!("l{k}.rad");
        std::fs::write(d.join(&rad), text).unwrap();
        let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg(&rad));
        std::fs::write(d.join(format!("l{k}.oct")), oct).unwrap();
    };
    oconv(
        0,
        "void plastic red 0 0 5 .5 .1 .1 0 0\nred sphere s 0 0 4 0 0 0 .4\n".into(),
    );
    for k in 1..=24 {
        let j = k - 1;
        oconv(
            k,
            format!(
                "# level {k}: two of level {j}\n\n\n\nvoid instance a 1 l{j}.oct 0 0\n\n\
                 void instance b 5 l{j}.oct -t 1 0 0 0 0\n"
            ),
        );
    }
    std::fs::write(d.join("top.rad"), "void instance top 1 l24.oct 0 0\n").unwrap();
    let start = std::time::Instant::now();
    // Level k places 2^k spheres: level 23's second instance makes 2^23 > 2^22.
    fails_with(d, &["top.rad"], "l23.rad:7: instance b: more than 4194304");
    assert!(start.elapsed().as_secs() < 20, "{:?}", start.elapsed());
}

/// The instance scene moved 1e6 away, or scaled by 1e3 and 1e-3 (instances, their
/// transforms and the view with it), renders the same picture.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn instances_moved_far_away_or_scaled_render_the_same() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let render = |xf: &str, vp: [f64; 3], s: f64, out: &str| -> Image {
        std::fs::write(
            d.join("w.rad"),
            format!("!xform {xf} inst.rad\n!xform {xf} mesh.rad\n"),
        )
        .unwrap();
        let vp: Vec<String> = vp.iter().map(|v| format!("{v:e}")).collect();
        let vh = format!("{}", 60);
        let _ = s;
        run_ok(
            tpict_in(d)
                .args([
                    "-vtv", "-vp", &vp[0], &vp[1], &vp[2], "-vd", "0", "1", "-0.6",
                ])
                .args([
                    "-vh", &vh, "-vv", "45", "-x", "96", "-y", "72", "-ab", "0", "-ps", "1",
                ])
                .args(["-pj", "0", "-o", out, "w.rad"]),
        );
        let img = read_picture(&d.join(out)).unwrap();
        assert_finite(&img);
        img
    };
    let base = render("-t 0 0 0", [0.0, -12.0, 8.0], 1.0, "base.hdr");
    let r = reduce(&base, 24, 18);
    for (xf, vp, s, out) in [
        (
            "-t 1e6 -1e6 1e6",
            [1e6, -1e6 - 12.0, 1e6 + 8.0],
            1.0,
            "far.hdr",
        ),
        ("-s 1e3", [0.0, -12e3, 8e3], 1e3, "big.hdr"),
        ("-s 1e-3", [0.0, -12e-3, 8e-3], 1e-3, "small.hdr"),
    ] {
        let img = render(xf, vp, s, out);
        let c = compare(&reduce(&img, 24, 18), &r, 0.01);
        eprintln!("{xf}: {c:?}");
        assert!(c.rms < 0.005, "{xf}: relative RMS {}", c.rms);
        assert!(
            c.mean_lum < 0.001,
            "{xf}: mean luminance differs by {}",
            c.mean_lum
        );
    }
}

/// A sparse set (a crown of small triangles over a thin trunk, like a tree) placed 40
/// times, rotated about z by every kind of angle, renders as the same triangles written
/// out as polygons: the scene's tree holds each placement in a box narrowed to its set's
/// parts (`scene::sets::placement_boxes`), and no surface may fall outside it. Needs no
/// Radiance.
#[test]
fn rotated_sparse_meshes_render_like_their_polygons() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    let mut rnd = tessera::hash::test_uniform(11);
    // Triangles of the set: a trunk of two thin quads' triangles, then the crown's.
    let mut tris: Vec<[[f64; 3]; 3]> = vec![
        [[-0.1, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.0, 3.0]],
        [[-0.1, 0.0, 0.0], [0.1, 0.0, 3.0], [-0.1, 0.0, 3.0]],
    ];
    for _ in 0..120 {
        let (r, a, z) = (
            2.0 * rnd().sqrt(),
            std::f64::consts::TAU * rnd(),
            3.0 + 2.0 * rnd(),
        );
        let (x, y) = (r * a.cos(), r * a.sin());
        tris.push([
            [x, y, z],
            [x + 0.3 * rnd(), y + 0.3 * rnd(), z + 0.3 * (rnd() - 0.5)],
            [x - 0.3 * rnd(), y + 0.3 * rnd(), z + 0.3 * rnd()],
        ]);
    }
    let mut obj = String::new();
    for tri in &tris {
        for v in tri {
            obj += &format!("v {:.6} {:.6} {:.6}\n", v[0], v[1], v[2]);
        }
    }
    for k in 0..tris.len() {
        obj += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    }
    std::fs::write(d.join("crown.obj"), obj).unwrap();
    let head = "void light sun 0 0 3 5e5 5e5 5e5\nsun source s 0 0 4 .3 -.4 .8 .5\n\
                void plastic leaf 0 0 5 .3 .5 .2 0 0\n\
                leaf polygon ground 0 0 12 -40 -40 0 40 -40 0 40 40 0 -40 40 0\n";
    let (mut inst, mut flat) = (head.to_string(), head.to_string());
    for k in 0..40 {
        let a = (k * 37 % 360) as f64 + if k % 3 == 0 { 0.0 } else { 0.5 };
        let (x, y) = ((k % 8) as f64 * 7.0 - 24.0, (k / 8) as f64 * 7.0 - 10.0);
        inst += &format!("void mesh c{k} 9 crown.obj -m leaf -rz {a} -t {x} {y} 0\n0\n0\n");
        let (s, c) = a.to_radians().sin_cos();
        for (j, tri) in tris.iter().enumerate() {
            flat += &format!("leaf polygon p{k}_{j} 0 0 9");
            for v in tri {
                let w = [c * v[0] - s * v[1] + x, s * v[0] + c * v[1] + y, v[2]];
                flat += &format!(" {:.9} {:.9} {:.9}", w[0], w[1], w[2]);
            }
            flat += "\n";
        }
    }
    std::fs::write(d.join("inst.rad"), inst).unwrap();
    std::fs::write(d.join("flat.rad"), flat).unwrap();
    let render = |scene: &str, out: &str| -> Image {
        run_ok(tpict_in(d).args([
            "-vp", "0", "-45", "4", "-vd", "0", "1", "-0.05", "-vh", "70", "-vv", "45", "-x",
            "160", "-y", "100", "-ab", "0", "-av", ".1", ".1", ".1", "-ps", "1", "-pj", "0", "-o",
            out, scene,
        ]));
        let img = read_picture(&d.join(out)).unwrap();
        assert_finite(&img);
        img
    };
    let a = render("inst.rad", "inst.hdr");
    let b = render("flat.rad", "flat.hdr");
    let c = compare(&reduce(&a, 160, 100), &reduce(&b, 160, 100), 0.01);
    eprintln!("instanced against flat: {c:?}");
    assert!(c.rms < 0.01, "relative RMS {}", c.rms);
    assert!(
        c.mean_lum < 0.002,
        "mean luminance differs by {}",
        c.mean_lum
    );
}

fn output(c: &mut Command) -> Output {
    c.output().expect("cannot run tpict")
}

/// tpict fails with exit status 1 and one error line that holds `want`.
fn fails_with(dir: &Path, files: &[&str], want: &str) {
    let o = output(
        tpict_in(dir)
            .args([
                "-x", "8", "-y", "8", "-vp", "0", "-12", "8", "-vd", "0", "1", "-0.6",
            ])
            .args(["-o", "out.hdr"])
            .args(files),
    );
    assert_one_error_line(&o, &format!("{files:?}"), want, &dir.join("out.hdr"));
}

/// Damaged octrees and meshes (truncated, wrong magic, wrong format), an octree that
/// instances itself, a stale unfrozen octree, missing files: one error line naming the file,
/// never a panic.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn bad_octrees_and_meshes_are_one_line_errors() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let scene = |name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    let frozen = std::fs::read(d.join("objf.oct")).unwrap();
    let mesh = std::fs::read(d.join("ball.rtm")).unwrap();
    // Truncated at several points, as the scene's octree and as an instanced one.
    for n in [0, 5, 40, frozen.len() / 3, frozen.len() - 1] {
        std::fs::write(d.join("cut.oct"), &frozen[..n]).unwrap();
        fails_with(d, &["cut.oct"], "cut.oct");
        scene("i.rad", "void instance i 1 cut.oct 0 0\n");
        fails_with(d, &["i.rad"], "cut.oct");
    }
    for n in [0, 30, 100, mesh.len() / 2, mesh.len() - 1] {
        std::fs::write(d.join("cut.rtm"), &mesh[..n]).unwrap();
        scene("m.rad", "void mesh m 1 cut.rtm 0 0\n");
        fails_with(d, &["m.rad"], "cut.rtm");
    }
    // Wrong magic numbers, and a file of another format.
    let head = frozen.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
    let mut bad = frozen.clone();
    bad[head] = 0x7f;
    std::fs::write(d.join("magic.oct"), &bad).unwrap();
    fails_with(d, &["magic.oct"], "magic.oct");
    let mhead = mesh.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
    let mut bad = mesh.clone();
    bad[mhead + 1] ^= 0x10;
    std::fs::write(d.join("magic.rtm"), &bad).unwrap();
    scene("m.rad", "void mesh m 1 magic.rtm 0 0\n");
    fails_with(d, &["m.rad"], "magic.rtm");
    scene("m.rad", "void mesh m 1 obj.oct 0 0\n");
    fails_with(d, &["m.rad"], "obj.oct");
    scene("i.rad", "void instance i 1 ball.rtm 0 0\n");
    fails_with(d, &["i.rad"], "ball.rtm");
    // Missing files.
    scene("i.rad", "void instance i 1 nowhere.oct 0 0\n");
    fails_with(d, &["i.rad"], "nowhere.oct");
    scene("m.rad", "void mesh m 1 nowhere.rtm 0 0\n");
    fails_with(d, &["m.rad"], "nowhere.rtm");
    std::fs::copy(d.join("obj.oct"), d.join("moved.oct")).unwrap();
    std::fs::rename(d.join("obj.rad"), d.join("obj.rad.away")).unwrap();
    fails_with(d, &["moved.oct"], "obj.rad");
    // A stale unfrozen octree: its scene file changed after oconv.
    std::fs::write(
        d.join("obj.rad"),
        std::fs::read_to_string(d.join("obj.rad.away")).unwrap()
            + "red sphere extra 0 0 4 0 0 3 .1\n",
    )
    .unwrap();
    fails_with(d, &["moved.oct"], "octree stale");
    // An octree that instances itself: made over a placeholder, then copied over it.
    scene("self.rad", "void instance me 1 self.oct 0 0\n");
    std::fs::copy(d.join("objf.oct"), d.join("self.oct")).unwrap();
    let me = run_ok(
        radiance(&bin, "oconv")
            .current_dir(d)
            .args(["-f", "self.rad"]),
    );
    std::fs::write(d.join("self.oct"), me).unwrap();
    fails_with(d, &["self.rad"], "instance loop");
    // Bad instance arguments.
    scene("i.rad", "void instance i 3 obj.oct -t 1 0 0\n");
    fails_with(d, &["i.rad"], "i.rad:1");
    scene("i.rad", "void instance i 0 0 0\n");
    fails_with(d, &["i.rad"], "i.rad:1");
}

/// Every prefix of a real octree and mesh is an error for the readers, never a panic.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn readers_refuse_every_truncation() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let frozen = std::fs::read(d.join("row.oct")).unwrap();
    assert!(tessera::scene::octree::parse_octree(&frozen, "row.oct").is_ok());
    for n in 0..frozen.len() {
        assert!(
            tessera::scene::octree::parse_octree(&frozen[..n], "row.oct").is_err(),
            "{n}"
        );
    }
    let mesh = std::fs::read(d.join("ball.rtm")).unwrap();
    let m = tessera::scene::rtm::parse_mesh(&mesh, "ball.rtm").unwrap();
    assert_eq!(m.tris.len(), 24 * 12 * 2 - 48 + 2, "triangles");
    assert!(m.flags.iter().any(|f| f & tessera::scene::rtm::HAS_UV != 0));
    for n in 0..mesh.len() {
        assert!(
            tessera::scene::rtm::parse_mesh(&mesh[..n], "ball.rtm").is_err(),
            "{n}"
        );
    }
}

/// A batch job over a scene of nested instances: tplan copies the octrees (and the scene
/// file of the unfrozen one) into the job, a worker elsewhere without a RAYPATH renders
/// tpict's picture.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn a_job_carries_its_instanced_files() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let job = d.join("job");
    let view = ["-vf", "inst.vf", "-x", "64", "-y", "50", "-ab", "0"];
    run_ok(
        Command::new(env!("CARGO_BIN_EXE_tplan"))
            .current_dir(d)
            .env("RAYPATH", ".")
            .args(["--tiles", "2", "--workers", "1", "--output", "job", "--"])
            .args(view)
            .arg("nest.rad"),
    );
    for f in ["row.oct", "pobj.oct", "pobj.rad"] {
        assert!(job.join("files").join(f).is_file(), "{f} not in the job");
    }
    let elsewhere = tempfile::tempdir().unwrap();
    run_ok(
        Command::new(env!("CARGO_BIN_EXE_tpiece"))
            .current_dir(elsewhere.path())
            .env_remove("RAYPATH")
            .arg(&job),
    );
    let pic = run_ok(Command::new(env!("CARGO_BIN_EXE_tassemble")).arg(&job));
    std::fs::write(d.join("job.hdr"), pic).unwrap();
    run_ok(
        tpict_in(d)
            .args(view)
            .args(["-o", "direct.hdr", "nest.rad"]),
    );
    let a = read_picture(&d.join("job.hdr")).unwrap();
    let b = read_picture(&d.join("direct.hdr")).unwrap();
    assert!(
        a.pixels == b.pixels,
        "the job's picture differs from tpict's"
    );
}

/// Every kind of set (an unfrozen and a frozen octree, nested instances, a compiled mesh
/// and an OBJ mesh with and without a default modifier) built from a scene image traces
/// and shades exactly like the scene built from its files: the same hits, points, normals,
/// chains, materials, modifier names and mesh normals and (u,v).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn sets_from_a_scene_image_trace_like_built_ones() {
    use glam::DVec3;
    use tessera::render::world::Scene;
    use tessera::scene::image::{encode, Rest, SceneImage};
    use tessera::scene::{read_scene_files, ReadOptions};
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    std::fs::write(d.join("ball.obj"), ball_obj()).unwrap();
    let objscene =
        "void plastic stripes 0 0 5 .6 .6 .6 0 0\nvoid plastic green 0 0 5 .1 .6 .1 0 0\n\
                    void mesh b1 1 ball.obj 0 0\n\
                    void mesh b2 7 ball.obj -m green -t 3 0 0 0 0\n";
    std::fs::write(d.join("objs.rad"), objscene).unwrap();
    let ro = ReadOptions {
        raypath: vec![d.to_path_buf()],
        ..ReadOptions::default()
    };
    for scene in ["inst.rad", "nest.rad", "mesh.rad", "objs.rad"] {
        let prims = read_scene_files(&[d.join(scene).display().to_string()], &ro).unwrap();
        let rest = Rest::of(&prims, [5; 32]);
        let built = Scene::build_taking(prims, &ro).unwrap();
        assert!(!built.sets.is_empty(), "{scene}: no sets");
        let bytes = encode(&[9; 32], &rest, &built.geom);
        let keep: std::sync::Arc<dyn tessera::geometry::plain::Backing> =
            std::sync::Arc::new(tessera::geometry::plain::Aligned::new(&bytes));
        let image = SceneImage::from_backing(keep, &[9; 32]).unwrap();
        let (rest_prims, _) = image.rest(&ro).unwrap();
        let mapped = Scene::build_with_image(rest_prims, &ro, &image)
            .unwrap()
            .unwrap_or_else(|e| panic!("{scene}: refused: {e}"));
        assert_eq!(mapped.sets.len(), built.sets.len());
        assert_eq!(mapped.placements.len(), built.placements.len());
        assert_eq!(mapped.inputs, built.inputs, "{scene}");
        // Rays in the scene's relative frame (the origin is the centre of its bounds).
        let (lo, hi) = (
            DVec3::splat(-0.5 * built.size),
            DVec3::splat(0.5 * built.size),
        );
        let (c, r) = (DVec3::ZERO, built.size);
        let mut hits = 0;
        for i in 0..3000 {
            let f = i as f64;
            let org = c + DVec3::new((1.3 * f).sin(), (0.7 * f).cos(), (0.31 * f).sin()) * r;
            let aim = lo
                + (hi - lo)
                    * DVec3::new(
                        0.5 + 0.5 * (2.1 * f).sin(),
                        0.5 + 0.5 * (1.7 * f).cos(),
                        0.5 + 0.5 * (0.9 * f).sin(),
                    );
            let dir = (aim - org).normalize();
            let one = |s: &Scene| -> String {
                match s.closest(org, dir, 1e30, |_, _| false) {
                    None => "miss".into(),
                    Some((h, t)) => {
                        let (p, n, flat) = s.hit_geom(h, org, dir, t);
                        let info = s.hit_info(h);
                        let detail = s.mesh_detail(h, p);
                        format!(
                            "{h:?} {t:?} {p:?} {n:?} {flat} {:?} {:?} {} {detail:?}",
                            info.chain, info.material, info.modifier
                        )
                    }
                }
            };
            let (a, b) = (one(&built), one(&mapped));
            assert_eq!(a, b, "{scene}: ray {i}");
            hits += usize::from(a != "miss");
        }
        assert!(hits > 300, "{scene}: only {hits} hits");
    }
}
