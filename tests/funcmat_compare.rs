//! The function and data materials and the anisotropic/translucent ones against real
//! Radiance (rpict from pyradiance), tests/scenes/funcmat: a room with two lamps and, per
//! scene, two spheres and a panel of the materials under test.
//!
//! - funcs.rad: `plasfunc`, `metfunc` (with a transform), `transfunc` over lobes.cal;
//! - data.rad: `plasdata`, `metdata` (with a transform), `transdata` over lobe.dat;
//! - brtd.rad: `BRTDfunc` with mirror, straight-through and directional parts, and one with
//!   diffuse parts only under a pattern;
//! - aniso.rad: `ashik2` (orientation by expressions and fixed), `trans2`, `plastic2` and
//!   `metal2` oriented by expressions with transforms.
//!
//! Pictures are compared as Radiance's test suite does (reduced to 128×128 with pfilt,
//! relative RMS and largest relative difference per pixel) and by mean luminance. Both
//! renderers are deterministic at `-ab 0 -pj 0`; the tolerances hold the measured figures
//! (docs/functions.md, "Function and data materials") with a margin. Skips (with a
//! message) when Radiance is not installed. Errors in these primitives' arguments are
//! tested at the end.

mod common;

use common::*;
use std::path::Path;
use std::process::{Command, Stdio};
use tessera::image::read_picture;

/// Deterministic pictures without sampled specular rays: measured rms ≤ 0.0009, max ≤
/// 0.009, mean ≤ 0.011% (the RGBE rounding of the two pictures).
const EXACT: Tol = Tol {
    size: "128",
    rms: 0.005,
    max: 0.05,
    mean: 0.001,
};

/// Pictures with sampled rough specular rays (one ray per pixel at `-ss 1` in each
/// renderer, different random numbers): measured rms 0.019, max 0.45, mean 0.02%.
const SAMPLED: Tol = Tol {
    size: "128",
    rms: 0.05,
    max: 1.0,
    mean: 0.003,
};

/// With indirect light (`-ab 1`, each renderer's own ambient cache): measured rms ≤
/// 0.033, max ≤ 0.80, mean ≤ 0.08% (the cache's dependence on thread timing moves
/// tpict's mean by about 0.015%). Radiance's suite tolerances, mean within 0.5%.
const INDIRECT: Tol = Tol {
    size: "128",
    rms: 0.10,
    max: 1.50,
    mean: 0.005,
};

fn scenes() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/funcmat")
}

fn check(scene: &str, ab: &str, tol: &Tol) {
    check_with(scene, ab, &[], tol)
}

fn check_with(scene: &str, ab: &str, extra: &[&str], tol: &Tol) {
    let Some(bin) = radiance_bin() else { return };
    let dir = scenes();
    let files = ["room.rad", scene];
    let tmp = tempfile::tempdir().unwrap();
    let oct = tmp.path().join("scene.oct");
    let octdata = run_ok(radiance(&bin, "oconv").current_dir(&dir).args(files));
    std::fs::write(&oct, octdata).unwrap();
    let mut args = vec![
        "-vf", "room.vf", "-x", "256", "-y", "256", "-ab", ab, "-av", ".05", ".05", ".05", "-ps",
        "1", "-pj", "0",
    ];
    args.extend_from_slice(extra);
    let reff = tmp.path().join("ref.hdr");
    let data = run_ok(
        radiance(&bin, "rpict")
            .current_dir(&dir)
            .args(&args)
            .arg(&oct),
    );
    std::fs::write(&reff, data).unwrap();
    let ours = tmp.path().join("ours.hdr");
    run_ok(
        Command::new(tpict_bin())
            .current_dir(&dir)
            .args(&args)
            .arg("-o")
            .arg(&ours)
            .args(files),
    );
    assert_like_reference(
        &bin,
        &ours,
        &reff,
        tol,
        &format!("{scene} -ab {ab} {extra:?}"),
    );
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn plasfunc_metfunc_transfunc() {
    check("funcs.rad", "0", &EXACT);
    check("funcs.rad", "1", &INDIRECT);
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn plasdata_metdata_transdata() {
    check("data.rad", "0", &EXACT);
    check("data.rad", "1", &INDIRECT);
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn brtdfunc() {
    check("brtd.rad", "0", &EXACT);
    check("brtd.rad", "1", &INDIRECT);
}

/// `-i`: irradiance rays pass through `trans2` and through a `BRTDfunc` that transmits;
/// the other materials are shaded white (measured: rms 0.09%, mean 0.02%, all three).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn irradiance_through_the_new_materials() {
    for scene in ["funcs.rad", "brtd.rad", "aniso.rad"] {
        check_with(scene, "0", &["-i"], &EXACT);
    }
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ashik2_trans2_and_oriented_plastic2_metal2() {
    check("aniso.rad", "0", &SAMPLED);
    check("aniso.rad", "1", &INDIRECT);
}

// ---------------------------------------------------------------------------------------
// Errors

const LAMP: &str =
    "void light bright\n0\n0\n3 100 100 100\n\nbright sphere lamp\n0\n0\n4 0 0 2 .1\n";

/// Render `text` (as `mat.rad`, with lobes.cal and lobe.dat beside it) and return the
/// error, asserting that tpict failed and wrote no picture.
fn error_of(text: &str) -> String {
    let t = tempfile::tempdir().unwrap();
    for f in ["lobes.cal", "lobe.dat"] {
        std::fs::copy(scenes().join(f), t.path().join(f)).unwrap();
    }
    std::fs::write(t.path().join("mat.rad"), format!("{LAMP}\n{text}")).unwrap();
    let o = Command::new(tpict_bin())
        .current_dir(t.path())
        .args([
            "-vp", "0", "0", "5", "-vd", "0", "0", "-1", "-vu", "0", "1", "0",
        ])
        .args(["-x", "8", "-y", "8", "-o", "out.hdr", "mat.rad"])
        .env("RAYPATH", ".")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "tpict succeeded; stderr:\n{err}");
    assert!(!t.path().join("out.hdr").exists(), "a picture was written");
    err
}

fn assert_has(err: &str, want: &[&str]) {
    for w in want {
        assert!(err.contains(w), "error should contain '{w}': {err}");
    }
}

const FLOOR: &str = "m polygon floor\n0\n0\n12 -9 -9 0 9 -9 0 9 9 0 -9 9 0\n";

#[test]
fn missing_function_and_data_files_are_named() {
    let e = error_of(&format!(
        "void plasfunc m\n2 refl nosuch.cal\n0\n5 .5 .5 .5 .1 1\n{FLOOR}"
    ));
    assert_has(
        &e,
        &["mat.rad:11", "nosuch.cal", "cannot find function file"],
    );
    let e = error_of(&format!(
        "void metdata m\n5 dval nosuch.dat lobes.cal dcos delev\n0\n5 .5 .5 .5 .1 1\n{FLOOR}"
    ));
    assert_has(&e, &["mat.rad:11", "nosuch.dat"]);
    let e = error_of(&format!(
        "void plastic2 m\n4 circx circy 0 nosuch.cal\n0\n6 .5 .5 .5 .05 .1 .2\n{FLOOR}"
    ));
    assert_has(&e, &["mat.rad:11", "nosuch.cal"]);
}

#[test]
fn wrong_argument_counts_are_named() {
    for (text, want) in [
        (
            "void plasfunc m\n1 refl\n0\n5 .5 .5 .5 .1 1\n",
            "bad # arguments",
        ),
        (
            "void transfunc m\n2 tlobe lobes.cal\n0\n5 .5 .5 .5 .1 1\n",
            "bad # arguments",
        ),
        (
            "void BRTDfunc m\n9 0 0 0 0 0 0 0 0 0\n0\n9 0 0 0 0 0 0 0 0 0\n",
            "bad # arguments",
        ),
        (
            "void ashik2 m\n4 1 0 0 .\n0\n6 .5 .5 .5 .1 .1 .1\n",
            "8 real argument",
        ),
        (
            "void trans2 m\n4 1 0 0 .\n0\n6 .5 .5 .5 .1 .1 .1\n",
            "8 real argument",
        ),
        (
            "void plasdata m\n4 dval lobe.dat lobes.cal dcos\n0\n5 .5 .5 .5 .1 1\n",
            "2 dimension",
        ),
    ] {
        let e = error_of(&format!("{text}{FLOOR}"));
        assert_has(&e, &["mat.rad:11", want]);
    }
}

#[test]
fn undefined_names_and_bad_expressions_stop_with_a_message() {
    // A syntax error in an orientation expression: a load-time error with the line.
    let e = error_of(&format!(
        "void metal2 m\n4 Px*(2 1 0 .\n0\n6 .5 .5 .5 .9 .1 .2\n{FLOOR}"
    ));
    assert_has(&e, &["mat.rad:11", "')' expected"]);
    // An undefined variable met while rendering: the render stops naming it.
    let e = error_of(&format!(
        "void BRTDfunc m\n10 nosuchvar 0 0 0 0 0 0 0 0 .\n0\n9 .5 .5 .5 0 0 0 0 0 0\n{FLOOR}"
    ));
    assert_has(&e, &["nosuchvar", "undefined"]);
    // An undefined function as a BRDF.
    let e = error_of(&format!(
        "void plasfunc m\n2 nosuchfunc lobes.cal\n0\n5 .5 .5 .5 .1 1\n{FLOOR}"
    ));
    assert_has(&e, &["nosuchfunc", "undefined"]);
}

/// A function that returns NaN or infinity (here `sqrt` of a negative number, a division by zero and an overflowing `exp`) never
/// reaches a pixel: the specular part is skipped for that light sample.
#[test]
fn non_finite_function_values_never_reach_a_pixel() {
    let t = tempfile::tempdir().unwrap();
    std::fs::write(
        t.path().join("bad.cal"),
        "nan(lx,ly,lz,om) = sqrt(-1 - lx*lx);\ninf(lx,ly,lz,om) = 1/(lx-lx) + exp(1e4*(1+lx*lx));\n",
    )
    .unwrap();
    let text = format!(
        "{LAMP}\nvoid plasfunc m\n2 nan bad.cal\n0\n5 .5 .5 .5 .5 1\n\
         void metfunc n\n2 inf bad.cal\n0\n5 .5 .5 .5 .5 1\n\
         m polygon floor\n0\n0\n12 -9 -9 0 0 -9 0 0 9 0 -9 9 0\n\
         n polygon floor2\n0\n0\n12 0 -9 0 9 -9 0 9 9 0 0 9 0\n"
    );
    std::fs::write(t.path().join("nan.rad"), text).unwrap();
    let o = Command::new(tpict_bin())
        .current_dir(t.path())
        .args([
            "-vp", "0", "0", "5", "-vd", "0", "0", "-1", "-vu", "0", "1", "0",
        ])
        .args(["-x", "16", "-y", "16", "-o", "out.hdr", "nan.rad"])
        .env("RAYPATH", ".")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = read_picture(&t.path().join("out.hdr")).unwrap();
    assert_finite(&img);
    // The diffuse part is still there.
    assert!(img.pixels.iter().all(|p| p[0] > 0.0));
}

/// One pixel looking at a 2×2 panel at the origin from (0, 0, ±1), with `scene` (files
/// `f.cal` and `g.cal` beside it) and `opts`: the pixel's colour.
fn point_value(scene: &str, from_below: bool, opts: &[&str]) -> [f64; 3] {
    let t = tempfile::tempdir().unwrap();
    std::fs::write(t.path().join("f.cal"), "cst(lx,ly,lz,om) = A5;\n").unwrap();
    std::fs::write(
        t.path().join("g.cal"),
        "cst(lx,ly,lz,om) = A10;\ncst2(lx,ly,lz,om) = 2*A10;\n",
    )
    .unwrap();
    let panel = "pf polygon fl 0 0 12 -1 -1 0 1 -1 0 1 1 0 -1 1 0\n";
    std::fs::write(t.path().join("s.rad"), format!("{scene}\n{panel}")).unwrap();
    let (z, d) = if from_below { ("-1", "1") } else { ("1", "-1") };
    let o = Command::new(tpict_bin())
        .current_dir(t.path())
        .args(["-vp", "0", "0", z, "-vd", "0", "0", d, "-vu", "0", "1", "0"])
        .args([
            "-vh", ".001", "-vv", ".001", "-x", "1", "-y", "1", "-ab", "0",
        ])
        .args(opts)
        .args(["-o", "out.hdr", "s.rad"])
        .env("RAYPATH", ".")
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = read_picture(&t.path().join("out.hdr")).unwrap();
    let p = img.pixels[0];
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

/// Values measured with rtrace 6.0 (a 1° distant source of radiance 1000 toward (0.3, 0,
/// ±1), `-ab 0 -dj 0 -ds 0`, or only the constant ambient `-av 1 1 1`), checked without
/// Radiance to the precision of a picture's pixel (RGBE, 0.4%).
#[test]
fn point_values_match_rtrace() {
    let above = "void light sl 0 0 3 1000 1000 1000\nsl source s 0 0 4 0.3 0 1 1\n";
    let below = "void light sl 0 0 3 1000 1000 1000\nsl source s 0 0 4 0.3 0 -1 1\n";
    let dark = ["-av", "0", "0", "0", "-dj", "0", "-ds", "0"];
    let amb = ["-av", "1", "1", "1"];
    let plas = "void plasfunc pf 2 cst f.cal 0 5 .5 .6 .7 .2 2";
    let met = "void metfunc pf 2 cst f.cal 0 5 .5 .6 .7 .2 2";
    let tf = "void transfunc pf 2 cst f.cal 0 7 .5 .6 .7 .2 .5 .3 2";
    let brtd = "void brightfunc pat 2 .5 . 0 0\npat BRTDfunc pf 10 .1 .2 .3 .25 .15 .05 \
                cst cst2 cst g.cal 0 10 .3 .4 .5 .1 .1 .1 .2 .3 .4 1.5";
    for (what, scene, below_view, opts, want) in [
        (
            "plasfunc",
            format!("{above}{plas}"),
            false,
            &dark[..],
            [0.1208387, 0.1266741, 0.1325095],
        ),
        (
            "metfunc",
            format!("{above}{met}"),
            false,
            &dark[..],
            [0.0750078, 0.0900094, 0.1050109],
        ),
        (
            "transfunc front",
            format!("{above}{tf}"),
            false,
            &dark[..],
            [0.0375039, 0.0404216, 0.0433393],
        ),
        (
            "transfunc through",
            format!("{below}{tf}"),
            false,
            &dark[..],
            [0.0170866, 0.0205039, 0.0239212],
        ),
        (
            "transfunc ambient",
            tf.to_string(),
            false,
            &amb[..],
            [0.5, 0.6, 0.7],
        ),
        (
            "BRTDfunc front",
            format!("{above}{brtd}"),
            false,
            &dark[..],
            [0.3546732, 0.7020522, 0.3619675],
        ),
        (
            "BRTDfunc through",
            format!("{above}{brtd}"),
            true,
            &dark[..],
            [0.3510261, 0.6984052, 0.3583204],
        ),
        (
            "BRTDfunc ambient front",
            brtd.to_string(),
            false,
            &amb[..],
            [0.25, 0.35, 0.45],
        ),
        (
            "BRTDfunc ambient back",
            brtd.to_string(),
            true,
            &amb[..],
            [0.15, 0.2, 0.25],
        ),
    ] {
        let got = point_value(&scene, below_view, opts);
        for c in 0..3 {
            assert!(
                (got[c] / want[c] - 1.0).abs() < 0.01,
                "{what}: {got:?}, rtrace {want:?}"
            );
        }
    }
}
