//! The ambient calculation's mathematics: the Hessian estimator and radii, super-sampling and
//! gradient extrapolation, measured through the library against `-aa 0` references.

use glam::DVec3;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use tessera::ambient::compute::Ambient;
use tessera::ambient::hemisphere::{cell_variances, super_sample_shares};
use tessera::ambient::hessian::{hessian, hessian_radii};
use tessera::ambient::settings::AmbientSettings;
use tessera::light::LightSet;
use tessera::options::RenderParams;
use tessera::render::world::Scene;
use tessera::render::{render_region, FrameSetup, RenderProgress, Tracer};
use tessera::scene::{read_scene_files, ReadOptions};
use tessera::view::{normaspect, read_view_file, View};

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes")
}

/// A loaded scene with its view.
struct Setup {
    scene: Scene,
    lights: LightSet,
    view: View,
}

fn load(rad: &str, vf: &str) -> Setup {
    let dir = scenes();
    let prims = read_scene_files(
        &[dir.join(rad).to_string_lossy().into_owned()],
        &ReadOptions::from_env(),
    )
    .unwrap();
    let scene = Scene::build(&prims).unwrap();
    let lights = LightSet::collect(&scene, RenderParams::default().dr);
    let view = read_view_file(&dir.join(vf), &View::default()).unwrap();
    Setup {
        scene,
        lights,
        view,
    }
}

/// Options for one render.
#[derive(Clone, Copy)]
struct Opts {
    res: usize,
    ab: i32,
    aa: f64,
    ad: i32,
    as_: i32,
    gradients: bool,
    hessian: bool,
    reach: bool,
    grad_radii: bool,
    glows: bool,
    hessian_cells: usize,
    overture: usize,
    /// Largest share reach (1: Radiance's rule).
    share_max: f64,
    /// Share of the divisions super-sampled at `-as 0`.
    as0_split: f64,
    /// `-st` (rough specular reflections below it go into the ambient term).
    st: f64,
    frame: u32,
}

impl Default for Opts {
    fn default() -> Opts {
        Opts {
            res: 48,
            ab: 1,
            aa: 0.15,
            ad: 128,
            as_: 0,
            gradients: true,
            hessian: true,
            reach: true,
            grad_radii: false,
            glows: true,
            hessian_cells: tessera::ambient::settings::HESSIAN_CELLS,
            overture: 0,
            share_max: tessera::ambient::settings::SHARE_MAX,
            as0_split: tessera::ambient::settings::AS0_SPLIT,
            st: RenderParams::default().st,
            frame: 0,
        }
    }
}

/// Render through the library (one thread, `-ps 1 -pj 0`, deterministic); pixels and
/// new-value count.
fn render(s: &Setup, o: Opts) -> (Vec<[f64; 3]>, u64) {
    let params = RenderParams {
        ab: o.ab,
        aa: o.aa,
        ad: o.ad,
        as_: o.as_,
        st: o.st,
        amb: AmbientSettings {
            gradients: o.gradients,
            hessian: o.hessian,
            reach: o.reach,
            gradient_radii: o.grad_radii,
            glow_sampling: o.glows,
            hessian_cells: o.hessian_cells,
            share_max: o.share_max,
            as0_split: o.as0_split,
            ..AmbientSettings::default()
        },
        ..RenderParams::default()
    };
    let amb = Ambient::new(&params, s.scene.size, 1).unwrap();
    let vf = s.view.frame().unwrap();
    let (mut x, mut y, mut pa) = (o.res, o.res, 1.0);
    normaspect(vf.aspect(), &mut pa, &mut x, &mut y);
    let tracer = Tracer::new(&s.scene, &params, &s.lights).with_ambient(Some(&amb));
    let fs = FrameSetup {
        view: &vf,
        xres: x,
        yres: y,
        pj: 0.0,
        ps: 1,
        pt: 0.05,
        frame: o.frame,
        irradiance: false,
        overture: o.overture,
        aa: None,
    };
    // Cached values on one thread: the cache sees its values in one order, so every figure
    // (and with it every comparison below) is the same on every run; several threads let the
    // order, and the new-value counts, vary from run to run. Uncached references (`-aa 0`)
    // are seeded per pixel and the same on any number of threads.
    let threads = if o.aa > 0.0 { 1 } else { 0 };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let px = pool.install(|| render_region(&tracer, &fs, 0, 0, x, y, &RenderProgress::default()));
    let nv = amb
        .stats
        .new_values
        .iter()
        .map(|v| v.load(Ordering::Relaxed))
        .sum();
    (
        px.iter()
            .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
            .collect(),
        nv,
    )
}

/// RMS relative luminance-ish error (channel mean), floored at 1% like radcompare.
fn rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let mut s = 0.0;
    for (p, q) in a.iter().zip(b) {
        let x = (p[0] + p[1] + p[2]) / 3.0;
        let y = (q[0] + q[1] + q[2]) / 3.0;
        let den = (0.25 * (x + y) * (x + y)).max(1e-4);
        s += (x - y) * (x - y) / den;
    }
    (s / a.len() as f64).sqrt()
}

/// A high-sample `-aa 0` reference (averaged over frames).
fn reference(s: &Setup, res: usize, ad: i32, frames: u32) -> Vec<[f64; 3]> {
    reference_st(s, res, ad, frames, RenderParams::default().st)
}

/// [`reference`] at another `-st`.
fn reference_st(s: &Setup, res: usize, ad: i32, frames: u32, st: f64) -> Vec<[f64; 3]> {
    let mut acc = vec![[0.0; 3]; 0];
    for f in 0..frames {
        let (p, _) = render(
            s,
            Opts {
                res,
                aa: 0.0,
                ad,
                st,
                frame: 1000 + f,
                ..Opts::default()
            },
        );
        if acc.is_empty() {
            acc = vec![[0.0; 3]; p.len()];
        }
        for (a, q) in acc.iter_mut().zip(&p) {
            for c in 0..3 {
                a[c] += q[c] / frames as f64;
            }
        }
    }
    acc
}

/// The picture size [`render`] uses for `res` with this scene's view.
fn dims(s: &Setup, res: usize) -> (usize, usize) {
    let vf = s.view.frame().unwrap();
    let (mut x, mut y, mut pa) = (res, res, 1.0);
    normaspect(vf.aspect(), &mut pa, &mut x, &mut y);
    (x, y)
}

/// k×k block means of a `w`-wide picture (the reduction of Radiance's test suite: the
/// reference's per-pixel noise averages out, the cache's errors, which span many pixels, do
/// not).
fn reduce(p: &[[f64; 3]], w: usize, k: usize) -> Vec<[f64; 3]> {
    let h = p.len() / w;
    let (w2, h2) = (w / k, h / k);
    let f = 1.0 / (k * k) as f64;
    let mut out = vec![[0.0; 3]; w2 * h2];
    for y in 0..k * h2 {
        for x in 0..k * w2 {
            for c in 0..3 {
                out[(y / k) * w2 + x / k][c] += f * p[y * w + x][c];
            }
        }
    }
    out
}

/// Mean error and new-value count over `frames` seeds.
fn mean_err(s: &Setup, reference: &[[f64; 3]], o: Opts, frames: u32) -> (f64, f64) {
    mean_err_with(s, reference, o, frames, &rms)
}

/// An error measure between a picture and its reference.
type ErrFn<'a> = dyn Fn(&[[f64; 3]], &[[f64; 3]]) -> f64 + 'a;

/// [`mean_err`] with another error measure.
fn mean_err_with(
    s: &Setup,
    reference: &[[f64; 3]],
    o: Opts,
    frames: u32,
    err: &ErrFn<'_>,
) -> (f64, f64) {
    let mut e = 0.0;
    let mut n = 0.0;
    for f in 0..frames {
        let (p, nv) = render(s, Opts { frame: f, ..o });
        e += err(&p, reference);
        n += nv as f64;
    }
    (e / frames as f64, n / frames as f64)
}

/// [`mean_err`] of the pictures reduced k×k (block means of `o.res`-wide pictures).
fn mean_reduced_err(
    s: &Setup,
    reference: &[[f64; 3]],
    o: Opts,
    frames: u32,
    k: usize,
) -> (f64, f64) {
    let (w, _) = dims(s, o.res);
    let reduced = |a: &[[f64; 3]], b: &[[f64; 3]]| rms(&reduce(a, w, k), &reduce(b, w, k));
    mean_err_with(s, reference, o, frames, &reduced)
}

/// The hemisphere mesh of a point at height `h` under an infinite uniform plane: the
/// irradiance does not change under tangential displacement, so the Hessian is ~0 and the
/// radii are huge. A sphere-like cap (a spot of brightness) gives a finite radius.
#[test]
fn hessian_of_a_plane_is_nearly_zero() {
    let (m, nphi) = (12, 38);
    let (n, u, v) = (DVec3::Z, DVec3::X, DVec3::Y);
    let h = 2.0;
    let mut pts = Vec::new();
    for j in 0..m {
        for k in 0..nphi {
            let s2 = (j as f64 + 0.5) / m as f64;
            let (st, ct) = (s2.sqrt(), (1.0 - s2).sqrt());
            let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
            let d = DVec3::new(st * phi.cos(), st * phi.sin(), ct);
            pts.push(d * (h / ct));
        }
    }
    let b = vec![1.0; m * nphi];
    let hp = hessian(&pts, &b, (m, nphi), (n, u, v), usize::MAX).unwrap();
    eprintln!("plane Hessian {hp:?}");
    // Against the scale of a surface at distance h: 1/h².
    assert!(hp.iter().all(|x| x.abs() < 0.05 / (h * h)), "{hp:?}");
    // A bright band on one side (x > 0): the irradiance changes along x, not y.
    let b2: Vec<f64> = pts
        .iter()
        .map(|p| if p.x > 0.0 { 1.0 } else { 0.01 })
        .collect();
    let hb = hessian(&pts, &b2, (m, nphi), (n, u, v), usize::MAX).unwrap();
    let (ang, r0, r1) = hessian_radii(&hb).unwrap();
    eprintln!("half-bright Hessian {hb:?}: angle {ang}, radii {r0} {r1}");
    assert!(r0 <= r1 && r0.is_finite() && r0 > 0.0);
    // Nearer surfaces curve irradiance more: halving the distance shrinks the radius.
    let near: Vec<DVec3> = pts.iter().map(|p| *p * 0.5).collect();
    let hn = hessian(&near, &b2, (m, nphi), (n, u, v), usize::MAX).unwrap();
    let (_, rn0, _) = hessian_radii(&hn).unwrap();
    assert!(rn0 < r0, "{rn0} vs {r0}");
    // Radii follow (4/|λ|)^¼.
    let (_, a, b) = hessian_radii(&[4.0, 0.0, 0.25]).unwrap();
    assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
    let (ang, _, _) = hessian_radii(&[0.25, 0.0, 4.0]).unwrap();
    assert!(
        (ang.sin().abs() - 1.0).abs() < 1e-9,
        "first eigenvector along v: {ang}"
    );
    assert!(hessian_radii(&[0.0, 0.0, 0.0]).is_none());
}

#[test]
fn cell_variance_wraps_in_phi() {
    let (m, nphi) = (3, 4);
    let mut b = vec![0.0; m * nphi];
    b[nphi] = 1.0; // ring 1, column 0: its neighbours include column 3 (wrapped).
    let v = cell_variances(&b, m, nphi);
    assert!(v[nphi + 3] > 0.0 && v[nphi + 1] > 0.0 && v[2 * nphi + 3] > 0.0);
    assert_eq!(v[nphi + 2], 0.0);
    assert!(v[nphi] > 0.0);
}

/// Super-sampling shares follow the standard deviation (a brightness twice as high draws twice
/// the rays, not four times), reach two cells beyond a bright one through the blur, and are
/// zero on a uniform hemisphere.
#[test]
fn super_sample_shares_follow_the_blurred_deviation() {
    let (m, nphi) = (8, 24);
    let mut b = vec![1.0; m * nphi];
    assert!(super_sample_shares(&b, m, nphi).iter().all(|&s| s == 0.0));
    b[4 * nphi + 10] = 50.0;
    let s1 = super_sample_shares(&b, m, nphi);
    let v = cell_variances(&b, m, nphi);
    // Two columns away: no variance of its own, but a share from the blur.
    assert_eq!(v[4 * nphi + 12], 0.0);
    assert!(s1[4 * nphi + 12] > 0.0);
    // Three away: nothing.
    assert_eq!(s1[4 * nphi + 13], 0.0);
    // The bright cell and its neighbours get the largest shares.
    let max = s1.iter().cloned().fold(0.0, f64::max);
    assert_eq!(s1[4 * nphi + 10], max);
    assert!(s1[4 * nphi + 11] > 0.3 * max);
    // Linear in the contrast: doubling every difference doubles every share.
    let b2: Vec<f64> = b.iter().map(|x| 1.0 + 2.0 * (x - 1.0)).collect();
    let s2 = super_sample_shares(&b2, m, nphi);
    for (a, c) in s1.iter().zip(&s2) {
        assert!((c - 2.0 * a).abs() <= 1e-9 * (1.0 + a), "{a} {c}");
    }
    // Wraps in φ like the variances: column 0 next to column nphi − 1.
    let mut b3 = vec![1.0; m * nphi];
    b3[4 * nphi] = 50.0;
    let s3 = super_sample_shares(&b3, m, nphi);
    assert!(s3[4 * nphi + nphi - 2] > 0.0 && s3[4 * nphi + 2] > 0.0);
}

/// Gradient extrapolation reduces the error of the cached picture against an uncached
/// (`-aa 0`) reference at the same `-aa` (spheres scene, 48×48, -ab 1, averaged over seeds).
#[test]
fn gradients_reduce_interpolation_error() {
    let s = load("spheres.rad", "spheres.vf");
    let reference = reference(&s, 48, 512, 2);
    let base = Opts {
        aa: 0.25,
        ..Opts::default()
    };
    let (with, n1) = mean_err(&s, &reference, base, 3);
    let (without, n2) = mean_err(
        &s,
        &reference,
        Opts {
            gradients: false,
            ..base
        },
        3,
    );
    eprintln!("gradients on: rms {with:.4} ({n1} values); off: rms {without:.4} ({n2} values)");
    assert!(with < without, "gradients should help: {with} vs {without}");
}

/// The overture (a first pass that only fills the cache) lowers the error of the cached
/// picture: every pixel then interpolates from the values on all its sides, not only from
/// those made before it. The gain grows with the pixels per value, so this needs 128×128
/// (curved scene, -ab 1 -st 1, pictures reduced 4×4 against an `-aa 0 -ad 1024` reference).
///
/// Spread, measured over 40 seeds (frames 0–39, `bench`-style, one render each way): the
/// error ratio (with / without) has mean 0.833 and standard deviation 0.067 per frame,
/// the value-count ratio mean 1.036 and deviation 0.018 (the overture makes about 4% more
/// values). Over the 4 frames here the deviations are about 0.033 and 0.009, so the limits
/// 0.96 and 1.075 sit 3.8 and 4.3 deviations above the means: a false failure less than
/// once in 10,000 seeds (Radiance's suite's rule).
#[test]
fn overture_reduces_interpolation_error() {
    let s = load("curved.rad", "curved.vf");
    let reference = reference_st(&s, 128, 1024, 1, 1.0);
    let base = Opts {
        res: 128,
        aa: 0.2,
        ad: 256,
        st: 1.0,
        ..Opts::default()
    };
    let (without, n1) = mean_reduced_err(&s, &reference, base, 4, 4);
    let (with, n2) = mean_reduced_err(
        &s,
        &reference,
        Opts {
            overture: 1,
            ..base
        },
        4,
        4,
    );
    eprintln!("overture off: rms {without:.4} ({n1} values); on: rms {with:.4} ({n2} values)");
    assert!(
        with < 0.96 * without,
        "the overture should help: {with} vs {without}"
    );
    assert!(
        n2 <= n1 * 1.075,
        "the overture made too many values: {n2} vs {n1}"
    );
}

/// A value's interpolation reach (up to 2 × -aa where its Hessian radii were shrunk by -ar's
/// largest radius or the aspect limit) averages more values' noise into each pixel. The glassy
/// room's values are noisy (the sunlit floor patch) and mostly clamped at the largest radius;
/// the new-value count stays that of reach 1 (within 5%).
#[test]
fn reach_reduces_noise_where_radii_were_clamped() {
    let s = load("glassy.rad", "glassy.vf");
    let reference = reference(&s, 48, 1024, 2);
    let base = Opts {
        aa: 0.2,
        ad: 256,
        overture: 1,
        ..Opts::default()
    };
    let (with, n1) = mean_reduced_err(&s, &reference, base, 3, 2);
    let (without, n2) = mean_reduced_err(
        &s,
        &reference,
        Opts {
            reach: false,
            ..base
        },
        3,
        2,
    );
    eprintln!("reach on: rms {with:.4} ({n1} values); off: rms {without:.4} ({n2} values)");
    assert!(with < without, "the reach should help: {with} vs {without}");
    assert!((n1 - n2).abs() <= 0.05 * n2, "value counts {n1} vs {n2}");
}

/// The gradient no longer shrinks Hessian radii (Radiance's `rad ≤ 1/|gpos|`): the Hessian
/// sets them from the light's variation, and a gradient made noisy by a few bright cells
/// shrank them for noise. Fewer values, at about the same error.
#[test]
fn hessian_radii_are_not_shrunk_by_the_gradient() {
    let s = load("spheres.rad", "spheres.vf");
    let reference = reference(&s, 48, 1024, 2);
    let base = Opts {
        aa: 0.15,
        ad: 256,
        as_: 128,
        overture: 1,
        ..Opts::default()
    };
    let (free, n1) = mean_reduced_err(&s, &reference, base, 3, 2);
    let (limited, n2) = mean_reduced_err(
        &s,
        &reference,
        Opts {
            grad_radii: true,
            ..base
        },
        3,
        2,
    );
    eprintln!(
        "gradient limit off: rms {free:.4} ({n1} values); on: rms {limited:.4} ({n2} values)"
    );
    assert!(n1 < 0.9 * n2, "fewer values expected: {n1} vs {n2}");
    assert!(free < 1.15 * limited, "error {free} vs {limited}");
}

/// A small glow with a radius of influence (the mirrors scene's neon ball), seen by a value's
/// sample rays from beyond that radius, is a few bright cells among hundreds: the value's
/// largest source of noise. Sampled as a light source instead (`Ambient::glow_light`), the
/// error against the pure Monte Carlo reference falls, at the same expectation.
#[test]
fn glows_beyond_their_radius_are_sampled_explicitly() {
    let s = load("mirrors.rad", "mirrors.vf");
    let reference = reference(&s, 40, 1024, 2);
    let base = Opts {
        res: 40,
        aa: 0.2,
        ad: 256,
        overture: 1,
        ..Opts::default()
    };
    let (on, n1) = mean_reduced_err(&s, &reference, base, 3, 2);
    let (off, n2) = mean_reduced_err(
        &s,
        &reference,
        Opts {
            glows: false,
            ..base
        },
        3,
        2,
    );
    // The picture's mean agrees with the reference's (the light is counted once).
    let mean = |p: &[[f64; 3]]| p.iter().map(|c| c[0] + c[1] + c[2]).sum::<f64>();
    let (p, _) = render(&s, base);
    let m = mean(&p) / mean(&reference);
    eprintln!("glow sampling on: rms {on:.4} ({n1} values, mean ratio {m:.4}); off: rms {off:.4} ({n2} values)");
    assert!(
        on < 0.75 * off,
        "explicit glow sampling should cut the error: {on} vs {off}"
    );
    assert!((m - 1.0).abs() < 0.02, "mean ratio {m}");
}

/// At `-ad 2048` the Hessian's mesh (26 × 80 cells) is thinned to 256 cells. When each kept
/// vertex was a mere point sample of the grid, what lay between kept vertices was lost and
/// some values under the spheres got radii several times too large (a band of pixels 60%
/// too bright; at 128², 1.59% against 0.51% for the full mesh). Each kept vertex now stands for its block
/// (mean brightness, nearest hit): the thinned mesh's error stays near the full mesh's.
#[test]
fn a_thinned_hessian_mesh_errs_like_the_full_one_at_high_ad() {
    let s = load("spheres.rad", "spheres.vf");
    let reference = reference_st(&s, 64, 2048, 2, 1.0);
    let base = Opts {
        res: 64,
        aa: 0.15,
        ad: 2048,
        as_: 512,
        st: 1.0,
        overture: 1,
        ..Opts::default()
    };
    let (thin, n1) = mean_reduced_err(&s, &reference, base, 2, 2);
    let (full, n2) = mean_reduced_err(
        &s,
        &reference,
        Opts {
            hessian_cells: usize::MAX,
            ..base
        },
        2,
        2,
    );
    eprintln!("thinned mesh: rms {thin:.4} ({n1} values); full: rms {full:.4} ({n2} values)");
    // Measured: 0.95 × the full mesh's error; point samples gave 1.17 ×.
    assert!(thin < 1.1 * full, "thinned {thin} vs full {full}");
}

/// The share reach: where the indirect light is a small part of a surface's light (the
/// spheres' floor is lit directly; the mirrors scene's walls too, and there a glow's radius
/// of influence is a seam the reach must not cross), values serve farther, so far fewer are
/// made, for a small rise of the picture's error (the time saved buys more than that back:
/// docs/ambient.md). Measured (3 frames, 64², 2×2 reduced): spheres 1.04% with 688 values
/// and 1.07% with 362; mirrors 0.91% with 953 and 1.32% with 356 (1.86% with 271 values
/// when the reach may cross the glow's radius, before the mirror relayed the spotlight).
/// The mirrors scene's spotlight has lit the wall through the mirror (its virtual source, as
/// in rpict) since its cone is tested from the real spotlight: a sharp-edged pool of direct
/// light, across which the share reach errs more (1.21% before).
#[test]
fn the_share_reach_makes_fewer_values_where_direct_light_dominates() {
    for (rad, vf, ad) in [
        ("spheres.rad", "spheres.vf", 256),
        ("mirrors.rad", "mirrors.vf", 512),
    ] {
        let s = load(rad, vf);
        let reference = reference_st(&s, 64, 2048, 2, 1.0);
        let base = Opts {
            res: 64,
            aa: 0.15,
            ad,
            as_: 128,
            st: 1.0,
            overture: 1,
            share_max: 1.0,
            ..Opts::default()
        };
        let (radiance, n1) = mean_reduced_err(&s, &reference, base, 3, 2);
        let (share, n2) = mean_reduced_err(
            &s,
            &reference,
            Opts {
                share_max: 3.0,
                ..base
            },
            3,
            2,
        );
        eprintln!("{rad}: Radiance's rule rms {radiance:.4} ({n1} values); share reach: rms {share:.4} ({n2} values)");
        assert!(n2 < 0.7 * n1, "{rad}: {n2} values vs {n1}");
        assert!(share < 1.55 * radiance, "{rad}: {share} vs {radiance}");
    }
}

/// `-as 0`: a cached value spends a quarter of its `-ad` rays on super-sampling, where its
/// first rays differed most: the same rays per value, less noise where a bright patch (the
/// sunlit floor in glassy) crosses the hemisphere.
#[test]
fn as0_super_samples_a_quarter_of_the_divisions() {
    let s = load("glassy.rad", "glassy.vf");
    let reference = reference_st(&s, 48, 2048, 2, 1.0);
    let base = Opts {
        res: 48,
        aa: 0.3,
        ad: 256,
        as_: 0,
        st: 1.0,
        overture: 1,
        as0_split: 0.0,
        ..Opts::default()
    };
    let (plain, n1) = mean_reduced_err(&s, &reference, base, 3, 2);
    let (split, n2) = mean_reduced_err(
        &s,
        &reference,
        Opts {
            as0_split: 0.25,
            ..base
        },
        3,
        2,
    );
    eprintln!(
        "-as 0 as Radiance: rms {plain:.4} ({n1} values); split: rms {split:.4} ({n2} values)"
    );
    assert!(split < 0.9 * plain, "{split} vs {plain}");
    // The divisions are exact: 192 + 64 rays, against 256.
    let params = RenderParams {
        ab: 1,
        aa: 0.2,
        ad: 256,
        as_: 0,
        ..RenderParams::default()
    };
    assert_eq!(
        tessera::ambient::compute::split_divisions(&params),
        (192.0, 64.0)
    );
    let uncached = RenderParams {
        aa: 0.0,
        ..params.clone()
    };
    assert_eq!(
        tessera::ambient::compute::split_divisions(&uncached),
        (256.0, 0.0)
    );
    let explicit = RenderParams { as_: 128, ..params };
    assert_eq!(
        tessera::ambient::compute::split_divisions(&explicit),
        (256.0, 128.0)
    );
}

/// Measurements for the report (run with `--ignored --nocapture`): error against an `-aa 0`
/// reference and new-value counts with the isotropic and Hessian radii, with and without
/// super-sampling.
#[test]
#[ignore]
fn measure_radii_and_supersampling() {
    for (rad, vf) in [("spheres.rad", "spheres.vf"), ("curved.rad", "curved.vf")] {
        let s = load(rad, vf);
        let t0 = std::time::Instant::now();
        let reference = reference(&s, 48, 1024, 2);
        eprintln!("{rad}: reference in {:?}", t0.elapsed());
        for aa in [0.1, 0.15, 0.25] {
            for hessian in [false, true] {
                for as_ in [0, 128] {
                    let t = std::time::Instant::now();
                    let (e, n) = mean_err(
                        &s,
                        &reference,
                        Opts {
                            aa,
                            hessian,
                            as_,
                            ..Opts::default()
                        },
                        2,
                    );
                    eprintln!(
                        "{rad} -aa {aa} hessian {hessian} -as {as_}: rms {e:.4}, {n} values, {:.2}s",
                        t.elapsed().as_secs_f64() / 2.0
                    );
                }
            }
        }
        // Uncached: does super-sampling help the Monte Carlo estimate itself?
        for as_ in [0, 128] {
            let (e, _) = mean_err(
                &s,
                &reference,
                Opts {
                    aa: 0.0,
                    as_,
                    ..Opts::default()
                },
                1,
            );
            eprintln!("{rad} -aa 0 -as {as_}: rms {e:.4}");
        }
    }
}

/// The overture's tracer (`fill_only`) skips direct light at eye-path shading points (their
/// colour is discarded) but not inside a new value's sampling: the values it makes are the
/// ones a full pass makes.
#[test]
fn fill_only_tracer_skips_direct_light_of_eye_paths_only() {
    let s = load("spheres.rad", "spheres.vf");
    let params = RenderParams {
        ab: 1,
        aa: 0.2,
        ad: 64,
        ..RenderParams::default()
    };
    let vf = s.view.frame().unwrap();
    let (org, dir, tmax) = vf.ray(0.5, 0.2).unwrap();
    let ray = tessera::render::ray::Ray::primary(org - s.scene.origin, dir, tmax);
    let full = Tracer::new(&s.scene, &params, &s.lights);
    let fill = Tracer {
        fill_only: true,
        ..Tracer::new(&s.scene, &params, &s.lights)
    };
    let mut rng = tessera::render::sampler::Sampler::for_pixel(0, 1, 2, 0);
    let lit = full.trace(&ray, &mut rng);
    let mut rng = tessera::render::sampler::Sampler::for_pixel(0, 1, 2, 0);
    let unlit = fill.trace(&ray, &mut rng);
    assert!(lit.max_element() > 0.0, "the view's floor is lit: {lit}");
    assert_eq!(
        unlit,
        tessera::color::Color::ZERO,
        "no direct light, no -av"
    );
    // The same values: filling with either tracer makes identical caches.
    let values = |tr: &Tracer| {
        let amb = Ambient::new(&params, s.scene.size, 1).unwrap();
        let t = Tracer {
            ambient: Some(&amb),
            ..*tr
        };
        let mut rng = tessera::render::sampler::Sampler::for_pixel(0, 1, 2, 0);
        t.trace(&ray, &mut rng);
        let v = amb.cache.all();
        assert_eq!(v.len(), 1);
        (v[0].val, v[0].rad)
    };
    assert_eq!(values(&full), values(&fill));
}
