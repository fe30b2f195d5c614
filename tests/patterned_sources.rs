//! Light sources whose emission a pattern shapes by direction (ies2rad luminaires: a `light`
//! polygon under `brightdata`) with the adaptive shadow test (`-dt`), against real rpict
//! (skipped without Radiance).
//!
//! The pattern belongs in each source sample's unoccluded potential, by which the samples
//! are ordered, tested and the untested ones estimated. Until issue 25 it was only in the
//! shadow ray's answer: at `-dt .07` a desk under such luminaires came out 41–45% too dark
//! where the distribution exceeds the light's radiance (ies_office: mean 0.84 of rpict's),
//! and too bright where it falls below it: how the same emission was split between the
//! light's radiance and the pattern's multiplier changed the picture. Each case checks the
//! whole-picture mean at `-dt .07` against rpict's and against tpict's own at `-dt 0`.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use tessera::image::read_picture;

/// This test's own luminous distribution: by the angle of the emitted direction from the
/// luminaire's normal, in degrees, and the value per unit of projected area (a flat
/// emitter's candela spread over its apparent size), times the first real argument.
const CAL: &str = "{ test distribution: emitted angle from the normal, per projected area }\n\
cos_out = -(Dx*Nx + Dy*Ny + Dz*Nz);\n\
out_angle = acos(if(cos_out - 1, 1, cos_out)) * 180 / 3.14159265358979;\n\
per_area(v) = if(cos_out - .02, A1 * v / cos_out, 0);\n";

/// The distribution's values from 0° to 90° every 15° (brightest straight down).
const DAT: &str = "1\n0 90 7\n8 7.6 6.4 4.6 2.6 .9 0\n";

/// A narrower one (for the room of many luminaires).
const DAT_NARROW: &str = "1\n0 90 7\n8 6 3 1 .3 .1 0\n";

/// The luminaire's material: the emission split as the light's radiance `rad` times the
/// pattern's multiplier `mult`.
fn luminaire(rad: f64, mult: f64) -> String {
    format!(
        "void brightdata lumdist 4 per_area lum.dat lum.cal out_angle 0 1 {mult}\n\
         lumdist light lumlight 0 0 3 {rad} {rad} {rad}\n\
         void plastic grey 0 0 5 .5 .5 .5 0 0\n"
    )
}

/// A 0.6 m square luminaire facing down at height 2.5, centred on (x, y).
fn panel(name: &str, x: f64, y: f64) -> String {
    let (x0, x1, y0, y1) = (x - 0.3, x + 0.3, y - 0.3, y + 0.3);
    format!(
        "lumlight polygon {name} 0 0 12 {x0} {y0} 2.5 {x0} {y1} 2.5 {x1} {y1} 2.5 {x1} {y0} 2.5\n"
    )
}

/// Two luminaires, a desk under the first, a floor and a back wall, seen from the front.
fn desk_scene(rad: f64, mult: f64) -> String {
    luminaire(rad, mult)
        + &panel("lum1", 1.0, 1.0)
        + &panel("lum2", 3.0, 1.0)
        + "void plastic wood 0 0 5 .45 .3 .18 .02 .05\n\
           grey polygon floor 0 0 12 0 0 0 4 0 0 4 2 0 0 2 0\n\
           grey polygon wall 0 0 12 0 2 0 4 2 0 4 2 3 0 2 3\n\
           wood polygon desk 0 0 12 .3 .5 .75 1.7 .5 .75 1.7 1.5 .75 .3 1.5 .75\n"
}

const DESK_VIEW: &[&str] = &[
    "-vtv", "-vp", "2", "-2.2", "2.2", "-vd", "0", "1", "-.65", "-vu", "0", "0", "1", "-vh", "75",
    "-vv", "60",
];

/// Twelve luminaires 2 m apart over an 8 × 6 m floor, seen from below them looking down.
fn room_scene(rad: f64, mult: f64) -> String {
    let mut s = luminaire(rad, mult);
    for x in [1, 3, 5, 7] {
        for y in [1, 3, 5] {
            s += &panel(&format!("lum{x}{y}"), x as f64, y as f64);
        }
    }
    s + "grey polygon floor 0 0 12 0 0 0 8 0 0 8 6 0 0 6 0\n\
         grey polygon wall 0 0 12 0 6 0 8 6 0 8 6 3 0 6 3\n"
}

const ROOM_VIEW: &[&str] = &[
    "-vtv", "-vp", "4", "3", "2.2", "-vd", "0", "0", "-1", "-vu", "0", "1", "0", "-vh", "110",
    "-vv", "90",
];

/// The direct-light options (rpict's defaults for the rest).
const OPTS: &[&str] = &[
    "-x", "128", "-y", "96", "-ab", "0", "-av", "0", "0", "0", "-ds", ".2", "-dj", "0", "-ps", "1",
    "-pj", "0",
];

/// How a case is rendered: the folder, the view, and how tpict is started there.
struct Case<'a> {
    bin: &'a Path,
    dir: &'a Path,
    view: &'a [&'a str],
    tpict: &'a dyn Fn() -> Command,
    tag: &'a str,
}

/// Render `scene.oct` with rpict and `scene.rad` with tpict at `-dt dt`: (rpict, tpict).
fn render(case: &Case, dt: &str) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let reff = case.dir.join(format!("ref-{dt}.hdr"));
    let data = run_ok(
        radiance(case.bin, "rpict")
            .current_dir(case.dir)
            .args(case.view)
            .args(OPTS)
            .args(["-dt", dt, "scene.oct"]),
    );
    std::fs::write(&reff, data).unwrap();
    let ours = case.dir.join(format!("ours-{dt}.hdr"));
    run_ok(
        (case.tpict)()
            .args(case.view)
            .args(OPTS)
            .args(["-dt", dt, "-w-", "-o"])
            .arg(&ours)
            .arg("scene.rad"),
    );
    let (a, b) = (read_picture(&reff).unwrap(), read_picture(&ours).unwrap());
    assert_finite(&b);
    assert_eq!((a.width, a.height), (b.width, b.height));
    (a.pixels_f64(), b.pixels_f64())
}

/// tpict at `-dt .07` against rpict at `-dt .07` and against tpict at `-dt 0`: whole-picture
/// mean luminance within 1% of both.
fn check(case: &Case) {
    let (theirs, ours) = render(case, ".07");
    let (_, exact) = render(case, "0");
    let vs_rpict = compare(&ours, &theirs, 0.02).mean_lum;
    let vs_dt0 = compare(&ours, &exact, 0.02).mean_lum;
    let tag = case.tag;
    eprintln!(
        "{tag}: -dt .07 mean differs from rpict's by {:.2}%, from tpict's -dt 0 by {:.2}%",
        100.0 * vs_rpict,
        100.0 * vs_dt0
    );
    assert!(
        vs_rpict <= 0.01,
        "{tag}: -dt .07 mean differs from rpict's by {:.2}%",
        100.0 * vs_rpict
    );
    assert!(
        vs_dt0 <= 0.01,
        "{tag}: -dt .07 mean differs from -dt 0 by {:.2}%",
        100.0 * vs_dt0
    );
}

/// A scene of this test's own luminaires (`lum.cal`, `dat` as `lum.dat`) rendered both ways.
fn own_luminaires(scene: &str, dat: &str, view: &[&str], tag: &str) {
    let Some(bin) = radiance_bin() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("lum.cal"), CAL).unwrap();
    std::fs::write(dir.join("lum.dat"), dat).unwrap();
    std::fs::write(dir.join("scene.rad"), scene).unwrap();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(dir).arg("scene.rad"));
    std::fs::write(dir.join("scene.oct"), oct).unwrap();
    let tpict = || tpict_in(dir);
    check(&Case {
        bin: &bin,
        dir,
        view,
        tpict: &tpict,
        tag,
    });
}

/// The distribution above the light's radiance (up to 8/cos): before issue 25's fix the
/// mean was 23% below rpict's (the desk under the first luminaire about 40%).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn brightdata_luminaire_at_dt_matches_rpict() {
    own_luminaires(
        &desk_scene(1.0, 1.0),
        DAT,
        DESK_VIEW,
        "desk, pattern above 1",
    );
}

/// The light's radiance 4× and the pattern ¼ (below 1 at most angles) over twelve
/// luminaires: the untested samples, mostly far ones seen at wide angles, were credited the
/// unpatterned radiance, and the picture was 3.2% too bright.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn pattern_below_the_light_radiance_at_dt_matches_rpict() {
    own_luminaires(
        &room_scene(4.0, 0.25),
        DAT_NARROW,
        ROOM_VIEW,
        "room, pattern below 1",
    );
}

/// A 2-D (quadrant-symmetric) batwing distribution of this test's own, made into a
/// luminaire by real `ies2rad` (its `brightdata` over Radiance's `source.cal`, which tpict
/// then finds along Radiance's library path), two of them over the desk.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ies2rad_luminaire_at_dt_matches_rpict() {
    let Some(bin) = radiance_bin() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let ies = "IESNA:LM-63-1995\n[TEST] tessera regression test\n\
               [LUMINAIRE] 300x1200 batwing troffer\nTILT=NONE\n\
               1 2500 1 7 3 1 2 0.3 1.2 0\n1.0 1.0 28\n0 15 30 45 60 75 90\n0 45 90\n\
               600 640 700 560 300 90 0\n600 600 580 450 240 70 0\n\
               600 560 470 330 170 50 0\n";
    std::fs::write(dir.join("batwing.ies"), ies).unwrap();
    run_ok(radiance(&bin, "ies2rad").current_dir(dir).args([
        "-dm",
        "-t",
        "default",
        "-o",
        "batwing",
        "batwing.ies",
    ]));
    let scene = "!xform -t 1 1 2.5 batwing.rad\n\
                 !xform -t 3 1 2.5 -rz 90 batwing.rad\n\
                 void plastic grey 0 0 5 .5 .5 .5 0 0\n\
                 void plastic wood 0 0 5 .45 .3 .18 .02 .05\n\
                 grey polygon floor 0 0 12 0 0 0 4 0 0 4 2 0 0 2 0\n\
                 grey polygon wall 0 0 12 0 2 0 4 2 0 4 2 3 0 2 3\n\
                 wood polygon desk 0 0 12 .3 .5 .75 1.7 .5 .75 1.7 1.5 .75 .3 1.5 .75\n";
    std::fs::write(dir.join("scene.rad"), scene).unwrap();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(dir).arg("scene.rad"));
    std::fs::write(dir.join("scene.oct"), oct).unwrap();
    // tpict with the RAYPATH real Radiance has: the folder, then Radiance's library.
    let lib: PathBuf = bin.parent().map(|p| p.join("lib")).unwrap_or_default();
    let tpict = || {
        let mut c = Command::new(tpict_bin());
        c.current_dir(dir)
            .env("RAYPATH", format!(".:{}", lib.display()));
        c
    };
    check(&Case {
        bin: &bin,
        dir,
        view: DESK_VIEW,
        tpict: &tpict,
        tag: "ies2rad batwing",
    });
}
