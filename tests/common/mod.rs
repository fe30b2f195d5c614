//! Helpers shared by integration tests: finding real Radiance, running tpict, comparing
//! pictures with Radiance's own test-suite tolerances.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use tessera::image::Image;

/// The folder holding Radiance's binaries, or None (tests then skip, unless
/// `TESSERA_REQUIRE_RADIANCE=1`, as in CI, where a missing Radiance is a failure).
pub fn radiance_bin() -> Option<PathBuf> {
    let found = find_radiance();
    if found.is_none() && std::env::var("TESSERA_REQUIRE_RADIANCE").as_deref() == Ok("1") {
        panic!("Radiance not found but TESSERA_REQUIRE_RADIANCE=1 (set TESSERA_RADIANCE_BIN)");
    }
    if found.is_none() {
        eprintln!("skipping: Radiance not found (set TESSERA_RADIANCE_BIN to its bin folder)");
    }
    found
}

/// The folder holding Radiance's binaries, or None, without messages or panics.
pub fn radiance_bin_quiet() -> Option<PathBuf> {
    find_radiance()
}

fn find_radiance() -> Option<PathBuf> {
    if let Ok(d) = std::env::var("TESSERA_RADIANCE_BIN") {
        let p = PathBuf::from(d);
        if p.join("rpict").exists() {
            return Some(p);
        }
    }
    if let Ok(path) = std::env::var("PATH") {
        for d in std::env::split_paths(&path) {
            if d.join("rpict").exists() && d.join("oconv").exists() {
                return Some(d);
            }
        }
    }
    let p = PathBuf::from("/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin");
    if p.join("rpict").exists() {
        return Some(p);
    }
    // The venv `.ci/run` makes (where build.rs looks too).
    let venv = std::env::var_os("TESSERA_VENV")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/tessera-venv"))
        })?;
    std::fs::read_dir(venv.join("lib"))
        .ok()?
        .flatten()
        .map(|e| e.path().join("site-packages/pyradiance/bin"))
        .find(|d| d.join("rpict").exists() && d.join("oconv").exists())
}

/// A Command for a Radiance program with PATH and RAYPATH set up.
pub fn radiance(bin: &Path, prog: &str) -> Command {
    let mut c = Command::new(bin.join(prog));
    let lib = bin.parent().map(|p| p.join("lib")).unwrap_or_default();
    let path = std::env::var("PATH").unwrap_or_default();
    c.env("PATH", format!("{}:{path}", bin.display()));
    c.env("RAYPATH", format!(".:{}", lib.display()));
    c
}

/// Path of the tpict binary built for the tests.
pub fn tpict_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_tpict"))
}

/// Run a command, panicking with its stderr on failure; returns stdout.
pub fn run_ok(c: &mut Command) -> Vec<u8> {
    output_ok(c).stdout
}

/// Run a command, panicking with its stderr on failure; returns its whole output.
pub fn output_ok(c: &mut Command) -> std::process::Output {
    let out = c.output().expect("cannot start command");
    if !out.status.success() {
        panic!(
            "command {:?} failed ({}):\n{}",
            c,
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
    out
}

/// Box-filter a picture down to `w`×`h` (each output pixel averages the input pixels whose
/// centres fall inside it).
pub fn reduce(img: &Image, w: usize, h: usize) -> Vec<[f64; 3]> {
    let mut sum = vec![[0f64; 3]; w * h];
    let mut cnt = vec![0u32; w * h];
    for y in 0..img.height {
        let oy = y * h / img.height;
        for x in 0..img.width {
            let ox = x * w / img.width;
            let p = img.pixels[y * img.width + x];
            let k = oy * w + ox;
            for c in 0..3 {
                sum[k][c] += p[c] as f64;
            }
            cnt[k] += 1;
        }
    }
    for (s, n) in sum.iter_mut().zip(cnt) {
        for v in s.iter_mut() {
            *v /= n.max(1) as f64;
        }
    }
    sum
}

/// Pixels as f64 triples.
pub trait PixelsF64 {
    /// The pixels, top row first, as f64.
    fn pixels_f64(&self) -> Vec<[f64; 3]>;
}

impl PixelsF64 for Image {
    fn pixels_f64(&self) -> Vec<[f64; 3]> {
        self.pixels
            .iter()
            .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
            .collect()
    }
}

/// Radiance's test-suite comparison figures.
#[derive(Debug, Clone, Copy)]
pub struct Compare {
    /// RMS relative difference.
    pub rms: f64,
    /// Largest per-pixel relative difference.
    pub max: f64,
    /// Relative difference of the mean luminance.
    pub mean_lum: f64,
}

fn lum(p: [f64; 3]) -> f64 {
    0.265074126 * p[0] + 0.670114631 * p[1] + 0.064811243 * p[2]
}

/// Compare like `radcompare -rel REL`: per pixel, the channel mean and the largest channel,
/// relative difference² = (a−b)²/(¼(a²+2|ab|+b²)) with the denominator floored at REL².
pub fn compare(a: &[[f64; 3]], b: &[[f64; 3]], rel: f64) -> Compare {
    assert_eq!(a.len(), b.len());
    let rd2 = |x: f64, y: f64| -> f64 {
        let den = (0.25 * (x * x + 2.0 * (x * y).abs() + y * y)).max(rel * rel);
        (x - y) * (x - y) / den
    };
    let mut sum = 0.0;
    let mut n = 0usize;
    let mut max: f64 = 0.0;
    for (p, q) in a.iter().zip(b) {
        let ma = (p[0] + p[1] + p[2]) / 3.0;
        let mb = (q[0] + q[1] + q[2]) / 3.0;
        let xa = p[0].max(p[1]).max(p[2]);
        let xb = q[0].max(q[1]).max(q[2]);
        for d2 in [rd2(ma, mb), rd2(xa, xb)] {
            sum += d2;
            n += 1;
            max = max.max(d2.sqrt());
        }
    }
    let la: f64 = a.iter().map(|p| lum(*p)).sum::<f64>() / a.len() as f64;
    let lb: f64 = b.iter().map(|p| lum(*p)).sum::<f64>() / b.len() as f64;
    Compare {
        rms: (sum / n as f64).sqrt(),
        max,
        mean_lum: (la - lb).abs() / lb.abs().max(1e-12),
    }
}

/// Assert no pixel holds a non-finite or negative value.
pub fn assert_finite(img: &Image) {
    for (i, p) in img.pixels.iter().enumerate() {
        assert!(
            p.iter().all(|v| v.is_finite() && *v >= 0.0),
            "pixel {i} is {p:?}"
        );
    }
}

/// A scene built from Radiance scene text (written to a temporary file and read back as the
/// renderer reads its input).
pub fn scene_from_text(text: &str) -> tessera::render::world::Scene {
    use tessera::render::world::Scene;
    use tessera::scene::{read_scene_files, ReadOptions};
    let t = tempfile::tempdir().unwrap();
    let path = t.path().join("scene.rad");
    std::fs::write(&path, text).unwrap();
    let prims = read_scene_files(
        &[path.to_string_lossy().into_owned()],
        &ReadOptions::from_env(),
    )
    .unwrap();
    Scene::build(&prims).unwrap()
}

/// Tolerances for comparing two pictures after reducing both to `size`×`size` as Radiance's
/// test suite does (`pfilt -1 -r 1 -x size -y size -pa 1`): relative RMS, largest relative
/// difference and relative difference of the mean luminance.
pub struct Tol {
    pub size: &'static str,
    pub rms: f64,
    pub max: f64,
    pub mean: f64,
}

/// Radiance's test-suite tolerances at 128×128.
pub const SUITE: Tol = Tol {
    size: "128",
    rms: 0.10,
    max: 1.50,
    mean: 0.02,
};

/// Reduce `ours` and `reference` with real pfilt to `tol.size` (both must have the same
/// resolution), compare them and assert `tol`; `label` names the case in messages.
pub fn assert_like_reference(bin: &Path, ours: &Path, reference: &Path, tol: &Tol, label: &str) {
    let reduce = |p: &Path| {
        let data = run_ok(
            radiance(bin, "pfilt")
                .args(["-1", "-r", "1", "-x", tol.size, "-y", tol.size, "-pa", "1"])
                .arg(p),
        );
        let out = p.with_extension("small.hdr");
        std::fs::write(&out, data).unwrap();
        tessera::image::read_picture(&out).unwrap()
    };
    let full = tessera::image::read_picture(ours).unwrap();
    assert_finite(&full);
    let full_ref = tessera::image::read_picture(reference).unwrap();
    assert_eq!(
        (full.width, full.height),
        (full_ref.width, full_ref.height),
        "{label}: resolution differs"
    );
    let (a, b) = (reduce(ours), reduce(reference));
    let c = compare(&a.pixels_f64(), &b.pixels_f64(), 0.007);
    eprintln!("{label}: {c:?}");
    assert!(
        c.rms <= tol.rms,
        "{label}: relative RMS {:.4} > {}",
        c.rms,
        tol.rms
    );
    assert!(
        c.max <= tol.max,
        "{label}: max relative difference {:.3} > {}",
        c.max,
        tol.max
    );
    assert!(
        c.mean_lum <= tol.mean,
        "{label}: mean luminance differs by {:.3}%",
        100.0 * c.mean_lum
    );
}

/// A run that failed as bad input must: exit status 1, exactly one error line, which contains
/// `want`, no panic, and no output file at `out`; `what` names the case in messages.
pub fn assert_one_error_line(o: &std::process::Output, what: &str, want: &str, out: &Path) {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what} panicked: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
    assert_eq!(lines.len(), 1, "{what}: {err}");
    assert!(
        lines[0].contains(want),
        "{what}: want '{want}' in: {}",
        lines[0]
    );
    assert!(!out.exists(), "{what}: {} was written", out.display());
}

/// With indirect light two renderers' caches differ pixel by pixel: Radiance's tolerances
/// after reducing to 32×32.
pub const AMBIENT: Tol = Tol {
    size: "32",
    ..SUITE
};

/// tpict run in `dir` with `RAYPATH=.` (files are found there only).
pub fn tpict_in(dir: &Path) -> Command {
    let mut c = Command::new(tpict_bin());
    c.current_dir(dir).env("RAYPATH", ".");
    c
}

/// Render `input` (scene files or an octree) with tpict and `octree` with rpict, both in
/// `dir` with `opts`, and compare them as Radiance's test suite does.
pub fn check_against_rpict(
    bin: &Path,
    dir: &Path,
    input: &[&str],
    octree: &str,
    opts: &[&str],
    tol: &Tol,
) {
    let name = format!("{}{}", input.join("_"), opts.join(""));
    let reff = dir.join(format!("ref-{name}.hdr"));
    let data = run_ok(
        radiance(bin, "rpict")
            .current_dir(dir)
            .args(opts)
            .arg(octree),
    );
    std::fs::write(&reff, data).unwrap();
    let ours = dir.join(format!("ours-{name}.hdr"));
    run_ok(tpict_in(dir).args(opts).arg("-o").arg(&ours).args(input));
    assert_like_reference(bin, &ours, &reff, tol, &format!("{input:?} {opts:?}"));
}
