//! Wavefront OBJ files read directly (tests/scenes/obj): `model.obj` has quads, a
//! non-convex pentagon and a hexagon (ear clipping), smooth normals, (u,v) under a pattern
//! on `Lu Lv`, two `usemtl` materials, a group name as a modifier, negative indices, a
//! triangle turned over by its normals and triangles whose normals are dropped. tpict
//! reading it (as a scene file next to `mat.rad`, and placed twice by `mesh` primitives
//! naming it) against rpict on what real `obj2mesh -a mat.rad` made of it, at `-ab 0` and
//! `-ab 1` (`-ps 1 -pj 0`), under Radiance's test-suite tolerances; the triangles against
//! obj2mesh's; a job renders tpict's picture; bad files are one error line. Skips (with a
//! message) when Radiance is not installed, except for the tests that need only tpict.

mod common;

use common::*;
use glam::DVec3;
use std::path::Path;
use std::process::Command;
use tessera::image::read_picture;

const SRC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/obj");

fn copy_scenes(to: &Path) {
    for e in std::fs::read_dir(SRC).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

/// A work folder with the scene files and `model.rtm`, made by real obj2mesh.
fn workdir(bin: &Path) -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    copy_scenes(t.path());
    run_ok(radiance(bin, "obj2mesh").current_dir(t.path()).args([
        "-a",
        "mat.rad",
        "model.obj",
        "model.rtm",
    ]));
    t
}

fn opts<'a>(view: &'a str, ab: &'a str) -> Vec<&'a str> {
    vec![
        "-vf", view, "-x", "256", "-y", "200", "-ab", ab, "-ps", "1", "-pj", "0", "-av", ".05",
        ".05", ".05",
    ]
}

fn oconv(bin: &Path, dir: &Path, files: &[&str], out: &str) {
    let data = run_ok(radiance(bin, "oconv").current_dir(dir).args(files));
    std::fs::write(dir.join(out), data).unwrap();
}

/// The OBJ as a scene file after its materials: tpict against rpict on obj2mesh's mesh.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn an_obj_scene_file_renders_as_obj2mesh_and_mesh() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    std::fs::write(d.join("one.rad"), "void mesh model 1 model.rtm 0 0\n").unwrap();
    oconv(&bin, d, &["light.rad", "one.rad"], "one.oct");
    for ab in ["0", "1"] {
        let tol = if ab == "0" { &SUITE } else { &AMBIENT };
        check_against_rpict(
            &bin,
            d,
            &["light.rad", "mat.rad", "model.obj"],
            "one.oct",
            &opts("view.vf", ab),
            tol,
        );
    }
}

/// `mesh` primitives naming the OBJ file, one moved and turned, against the same naming
/// obj2mesh's mesh.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn mesh_primitives_naming_an_obj_file() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    oconv(&bin, d, &["light.rad", "rtm.rad"], "two.oct");
    for ab in ["0", "1"] {
        let tol = if ab == "0" { &SUITE } else { &AMBIENT };
        check_against_rpict(
            &bin,
            d,
            &["light.rad", "mat.rad", "objmesh.rad"],
            "two.oct",
            &opts("view2.vf", ab),
            tol,
        );
    }
}

/// A triangle as its three corners, starting at the smallest (orientation kept).
fn canonical(t: [DVec3; 3]) -> [[i64; 3]; 3] {
    let q = t.map(|p| (p * 1e4).round().as_i64vec3().to_array());
    let k = (0..3).min_by_key(|&k| q[k]).unwrap();
    [q[k], q[(k + 1) % 3], q[(k + 2) % 3]]
}

/// The triangles (corners, orientation, whether normals and (u,v) are kept, the modifier's
/// name) are obj2mesh's.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn triangles_are_obj2mesh_s() {
    let Some(bin) = radiance_bin() else { return };
    let t = workdir(&bin);
    let d = t.path();
    let rtm =
        tessera::scene::rtm::parse_mesh(&std::fs::read(d.join("model.rtm")).unwrap(), "m").unwrap();
    let text = std::fs::read_to_string(d.join("model.obj")).unwrap();
    let obj = tessera::scene::obj::parse_obj(&text, "model.obj").unwrap();
    let key = |pos: &[DVec3], flags: &[u8], v: [u32; 3], name: &str| {
        let f = v.map(|k| flags[k as usize]);
        let all = |b: u8| f.iter().all(|x| x & b != 0);
        (
            canonical(v.map(|k| pos[k as usize])),
            all(2),
            all(4),
            name.to_string(),
        )
    };
    let mut a: Vec<_> = rtm
        .tris
        .iter()
        .map(|t| {
            let name = usize::try_from(t.modifier).map_or("void", |k| rtm.prims[k].name.as_str());
            key(&rtm.pos, &rtm.flags, t.v, name)
        })
        .collect();
    let mut b: Vec<_> = obj
        .tris
        .iter()
        .map(|t| {
            let name = usize::try_from(t.modifier).map_or("void", |k| obj.names[k].0.as_str());
            key(&obj.pos, &obj.flags, t.v, name)
        })
        .collect();
    a.sort();
    b.sort();
    assert_eq!(a.len(), b.len(), "triangle counts");
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x, y);
    }
}

/// A batch job over the OBJ scene: tplan copies the OBJ into the job (with the default
/// material given by --obj-material kept in its scene), a worker elsewhere without a
/// RAYPATH renders tpict's picture bit for bit.
#[test]
fn a_job_carries_its_obj_file() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    copy_scenes(d);
    // Without its group line the floor has no name: the default material shades it.
    let text = std::fs::read_to_string(d.join("model.obj")).unwrap();
    std::fs::write(d.join("plain.obj"), text.replace("g floor\n", "")).unwrap();
    let job = d.join("job");
    let view = ["-vf", "view.vf", "-x", "64", "-y", "50", "-ab", "0"];
    let scene = [
        "--obj-material",
        "blue",
        "light.rad",
        "mat.rad",
        "plain.obj",
    ];
    run_ok(
        Command::new(env!("CARGO_BIN_EXE_tplan"))
            .current_dir(d)
            .env("RAYPATH", ".")
            .args(["--tiles", "2", "--workers", "1", "--output", "job", "--"])
            .args(view)
            .args(scene),
    );
    assert!(
        job.join("files/plain.obj").is_file(),
        "plain.obj not in the job"
    );
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
            .args(["-o", "direct.hdr"])
            .args(scene),
    );
    let a = read_picture(&d.join("job.hdr")).unwrap();
    let b = read_picture(&d.join("direct.hdr")).unwrap();
    assert!(
        a.pixels == b.pixels,
        "the job's picture differs from tpict's"
    );
    // Without the default the floor's triangles are void: invisible, another picture.
    run_ok(
        tpict_in(d)
            .args(view)
            .args(["-o", "void.hdr"])
            .args(&scene[2..]),
    );
    let c = read_picture(&d.join("void.hdr")).unwrap();
    assert!(c.pixels != b.pixels);
}

/// tpict fails with exit status 1 and one error line that holds `want`.
fn fails_with(dir: &Path, files: &[&str], want: &str) {
    let o = tpict_in(dir)
        .args([
            "-x", "8", "-y", "8", "-vp", "0", "-12", "8", "-vd", "0", "1", "-0.6",
        ])
        .args(["-o", "out.hdr"])
        .args(files)
        .output()
        .unwrap();
    assert_one_error_line(&o, &format!("{files:?}"), want, &dir.join("out.hdr"));
}

/// Bad OBJ files, undefined modifiers and missing files: one error line naming the file
/// and line, never a panic.
#[test]
fn bad_obj_files_are_one_line_errors() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    copy_scenes(d);
    let bad = |name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    bad("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    bad("number.obj", "v 0 0 0\nv 1 0 zero\n");
    bad("normal.obj", "v 0 0 0\nvn 0 0 0\n");
    bad("ref.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n");
    bad(
        "nomat.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl chrome\nf 1 2 3\n",
    );
    bad("binary.obj", "v 0 0 \u{0}\u{ff}\n");
    let l = "light.rad";
    fails_with(
        d,
        &[l, "index.obj"],
        "index.obj:4: vertex index 4 in '4' is out of range",
    );
    fails_with(d, &[l, "number.obj"], "number.obj:2: bad vertex z 'zero'");
    fails_with(d, &[l, "normal.obj"], "normal.obj:2: zero normal");
    fails_with(d, &[l, "ref.obj"], "ref.obj:4: bad texture index 'x'");
    fails_with(
        d,
        &[l, "nomat.obj"],
        "nomat.obj:4: undefined modifier 'chrome'",
    );
    fails_with(d, &[l, "binary.obj"], "binary.obj:1: bad vertex z");
    // A face beyond 4096 vertices is refused at once (ear clipping 200,000 took 111 s).
    let mut big: String = (0..5000)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 5000.0;
            format!("v {} {} 0\n", a.cos(), a.sin())
        })
        .collect();
    big.push('f');
    for k in 1..=5000 {
        big.push_str(&format!(" {k}"));
    }
    big.push('\n');
    bad("bigface.obj", &big);
    let t0 = std::time::Instant::now();
    fails_with(
        d,
        &[l, "bigface.obj"],
        "bigface.obj:5001: face of 5000 vertices (at most 4096",
    );
    assert!(t0.elapsed().as_secs() < 5);
    fails_with(d, &[l, "missing.obj"], "missing.obj");
    // The materials after the OBJ come too late (obj2mesh's -a files come first).
    fails_with(
        d,
        &[l, "model.obj", "mat.rad"],
        "model.obj:3: undefined modifier 'floor'",
    );
    std::fs::write(d.join("ref.rad"), "void mesh m 1 gone.obj 0 0\n").unwrap();
    fails_with(d, &[l, "ref.rad"], "cannot find file 'gone.obj'");
    // A default material that is not defined.
    fails_with(
        d,
        &["--obj-material", "nothing", l, "nomat.obj"],
        "default modifier: unknown modifier 'nothing'",
    );
}
