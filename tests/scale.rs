//! Scale invariance: the demo scene scaled by 1e-6 … 1e6 (`!xform -s S`, the view point
//! scaled with it) renders the same picture. Radiance's absolute tolerance (FTINY = 1e-6)
//! is a tenth of a scene of 1e-5; Tessera's length tolerance follows the scene's size below
//! a unit (docs/robustness.md, "Tiny and huge scenes").

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use tessera::image::{read_picture, Image};

const SCALES: [f64; 5] = [1e-6, 1e-3, 1.0, 1e3, 1e6];

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("demo")
}

/// The demo picture at scale `s` with `opts`.
fn render(dir: &Path, s: f64, opts: &[&str]) -> Image {
    let scene = dir.join(format!("s{s:e}.rad"));
    std::fs::write(
        &scene,
        format!("!xform -s {s:e} {}\n", demo().join("demo.rad").display()),
    )
    .unwrap();
    let out = dir.join(format!("s{s:e}.hdr"));
    let vp: Vec<String> = [7.6, 0.35, 2.1]
        .iter()
        .map(|v| format!("{:e}", v * s))
        .collect();
    let mut c = Command::new(tpict_bin());
    c.current_dir(demo())
        .env("RAYPATH", ".")
        .stdin(Stdio::null())
        .args(["-vtv", "-vp", &vp[0], &vp[1], &vp[2]])
        .args([
            "-vd", "-5.2", "4.6", "-1.5", "-vu", "0", "0", "1", "-vh", "80", "-vv", "60",
        ])
        .args(["-x", "64", "-y", "48", "-ps", "1", "-pj", "0"])
        .args(opts)
        .arg("-o")
        .arg(&out)
        .arg(&scene);
    run_ok(&mut c);
    let img = read_picture(&out).unwrap();
    assert_finite(&img);
    img
}

/// Every scale against scale 1: downsampled RMS and mean luminance within the limits.
fn check(opts: &[&str], rms_max: f64, mean_max: f64) {
    let t = tempfile::tempdir().unwrap();
    let reference = render(t.path(), 1.0, opts);
    let r = reduce(&reference, 16, 12);
    for s in SCALES.into_iter().filter(|&s| s != 1.0) {
        let img = render(t.path(), s, opts);
        let c = compare(&reduce(&img, 16, 12), &r, 0.01);
        eprintln!("scale {s:e} {opts:?}: {c:?}");
        assert!(c.rms < rms_max, "scale {s:e}: relative RMS {}", c.rms);
        assert!(
            c.mean_lum < mean_max,
            "scale {s:e}: mean luminance differs by {}",
            c.mean_lum
        );
    }
}

/// Direct light only: the pictures agree to rounding (before the scene-relative tolerance,
/// scale 1e-6 was 18% too bright and the ceiling light vanished).
#[test]
fn direct_light_is_the_same_at_every_scale() {
    check(&["-ab", "0"], 0.005, 0.001);
}

/// With an ambient bounce: the cache places its values slightly differently at each scale
/// (rounding), so the limits are statistical: measured mean differences 0.05% and below,
/// the limit 1.5% (before the fix: 36% at scale 1e-6).
#[test]
fn indirect_light_is_the_same_at_every_scale() {
    check(
        &["-ab", "1", "-aa", ".1", "-ad", "256", "-as", "64"],
        0.04,
        0.015,
    );
}
