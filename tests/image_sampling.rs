//! Adaptive image sampling (`-ps`, `-pt`): any tiling renders the same pixels, and border
//! samples shared by neighbouring cells are traced once.

use std::path::Path;
use std::sync::atomic::Ordering;
use tessera::light::LightSet;
use tessera::options::RenderParams;
use tessera::render::lightcells::CellMemo;
use tessera::render::world::Scene;
use tessera::render::{cell_size, render_region, FrameSetup, RenderProgress, Tracer};
use tessera::scene::{read_scene_files, ReadOptions};
use tessera::view::{normaspect, read_view_file, View};

/// Renders regions of the `curved` scene at `-ab 0`.
struct Curved {
    scene: Scene,
    lights: LightSet,
    view: View,
    params: RenderParams,
}

impl Curved {
    fn load() -> Curved {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes");
        let file = dir.join("curved.rad").to_string_lossy().into_owned();
        let prims = read_scene_files(&[file], &ReadOptions::from_env()).unwrap();
        let scene = Scene::build(&prims).unwrap();
        let params = RenderParams {
            av: [0.05; 3],
            ..RenderParams::default()
        };
        let lights = LightSet::collect(&scene, params.dr);
        let view = read_view_file(&dir.join("curved.vf"), &View::default()).unwrap();
        Curved {
            scene,
            lights,
            view,
            params,
        }
    }

    /// Pixels of region `[x0, x1) × [y0, y1)` of a `res`-wide picture at `-ps ps`, and the
    /// rays traced.
    fn region(&self, res: usize, ps: usize, r: [usize; 4]) -> (Vec<[f32; 3]>, u64, usize, usize) {
        render(
            &self.scene,
            &self.lights,
            &self.params,
            &self.view,
            res,
            ps,
            r,
            None,
        )
    }
}

/// Pixels of region `[x0, x1) × [y0, y1)` of a `res`-wide picture of `scene` at `-ps ps`
/// (`-pj .67 -pt .05`), the rays traced and the picture's size; `memo`, when given, keeps
/// the small sources' cells between calls (as a session's tiles share them).
#[allow(clippy::too_many_arguments)]
fn render(
    scene: &Scene,
    lights: &LightSet,
    params: &RenderParams,
    view: &View,
    res: usize,
    ps: usize,
    r: [usize; 4],
    memo: Option<&CellMemo>,
) -> (Vec<[f32; 3]>, u64, usize, usize) {
    let vf = view.frame().unwrap();
    let (mut x, mut y, mut pa) = (res, res, 1.0);
    normaspect(vf.aspect(), &mut pa, &mut x, &mut y);
    let mut tracer = Tracer::new(scene, params, lights);
    tracer.cells = memo;
    let fs = FrameSetup {
        view: &vf,
        xres: x,
        yres: y,
        pj: 0.67,
        ps,
        pt: 0.05,
        frame: 0,
        irradiance: false,
        overture: 0,
        aa: None,
    };
    let progress = RenderProgress::default();
    let [x0, y0, x1, y1] = r;
    let px = render_region(&tracer, &fs, x0, y0, x1.min(x), y1.min(y), &progress);
    (px, progress.rays.load(Ordering::Relaxed), x, y)
}

#[test]
fn any_tiling_renders_the_same_pixels() {
    let c = Curved::load();
    for ps in [2, 4, 5] {
        let (full, _, w, h) = c.region(100, ps, [0, 0, usize::MAX, usize::MAX]);
        // Tiles cut across cells (the cell side is cell_size(ps)) at uneven places.
        let xs = [0, 7, 33, 34, 61, w];
        let ys = [0, 1, 29, h];
        for yy in ys.windows(2) {
            for xx in xs.windows(2) {
                let (tile, _, _, _) = c.region(100, ps, [xx[0], yy[0], xx[1], yy[1]]);
                let tw = xx[1] - xx[0];
                for (i, p) in tile.iter().enumerate() {
                    let (x, y) = (xx[0] + i % tw, yy[0] + i / tw);
                    assert_eq!(*p, full[y * w + x], "-ps {ps}: pixel ({x}, {y})");
                }
            }
        }
    }
}

#[test]
fn border_samples_are_traced_once() {
    // Rendered whole, the picture traces fewer rays than as single-cell-row strips (each
    // strip traces its top and bottom rows itself), and less than half of tracing every pixel.
    let c = Curved::load();
    // (At 160 pixels: at 96 the scene's disk and tube lights are small enough to be sampled
    // at every pixel, small_light_sources_are_never_interpolated_away.)
    let (_, every, w, h) = c.region(160, 1, [0, 0, usize::MAX, usize::MAX]);
    let (_, whole, _, _) = c.region(160, 4, [0, 0, w, h]);
    let side = cell_size(4);
    let strips: u64 = (0..h)
        .step_by(side)
        .map(|y| c.region(160, 4, [0, y, w, y + side]).1)
        .sum();
    assert!(whole < strips, "whole {whole}, strips {strips}");
    assert!(2 * whole < every, "whole {whole}, every pixel {every}");
}

/// Pixels of a whole `res`-wide picture of `scene` at `-ps ps` (`-ab 0`).
fn picture(scene: &Scene, view: &View, res: usize, ps: usize) -> Vec<[f32; 3]> {
    let params = RenderParams::default();
    let lights = LightSet::collect(scene, params.dr);
    let all = [0, 0, usize::MAX, usize::MAX];
    render(scene, &lights, &params, view, res, ps, all, None).0
}

/// Downlights a pixel or two wide across a dark hall, and a sun disc of 0.5° low in a dark
/// sky: at `-ps 4` their pixels are the ones every pixel traced shows (before, the
/// first samples 4 pixels apart found one downlight in eight and the picture was half as
/// bright as rpict's).
#[test]
fn small_light_sources_are_never_interpolated_away() {
    let mut text = String::from(
        "void plastic grey 0 0 5 .3 .3 .3 0 0\n\
         grey polygon ceiling 0 0 12 -40 -5 8 40 -5 8 40 40 8 -40 40 8\n\
         grey polygon floor 0 0 12 -40 -5 0 -40 40 0 40 40 0 40 -5 0\n\
         void light lamp 0 0 3 500 500 500\n\
         void light sunlight 0 0 3 1e5 1e5 1e5\n\
         sunlight source sun 0 0 4 .3 1 .12 .5\n",
    );
    for i in 0..12 {
        let (x, y) = (-8.0 + 1.5 * i as f64, 15.0 + 1.5 * i as f64);
        text.push_str(&format!(
            "lamp polygon d{i} 0 0 12 {x} {y} 7.99 {x} {y1} 7.99 {x1} {y1} 7.99 {x1} {y} 7.99\n",
            y1 = y + 0.2,
            x1 = x + 0.2
        ));
    }
    let prims =
        tessera::scene::parse_scene_text(&text, "hall.rad", &ReadOptions::default()).unwrap();
    let scene = Scene::build(&prims).unwrap();
    let view = hall_view("-vp 0 0 1.6 -vd 0 1 .1 -vu 0 0 1 -vh 70 -vv 50");
    let every = picture(&scene, &view, 320, 1);
    let adaptive = picture(&scene, &view, 320, 4);
    let bright = |p: &[[f32; 3]]| p.iter().filter(|c| c[0] > 100.0).count();
    let lamps = every.iter().filter(|c| c[0] > 100.0 && c[0] < 1e4).count();
    let suns = every.iter().filter(|c| c[0] >= 1e4).count();
    assert!(
        lamps >= 12 && suns >= 1,
        "{lamps} lamp and {suns} sun pixels"
    );
    assert_eq!(bright(&adaptive), bright(&every));
    for (a, e) in adaptive.iter().zip(&every) {
        if e[0] > 100.0 {
            assert_eq!(a, e);
        }
    }
    tiles_share_the_cells(&scene, &view, &adaptive);
}

fn hall_view(words: &str) -> View {
    let mut view = View::default();
    view.apply_words(&words.split(' ').map(String::from).collect::<Vec<_>>())
        .unwrap();
    view
}

/// Tiles of the hall rendered through one memo of the cells (computed on the first tile,
/// as a session does once per frame) are the whole picture's pixels, also when the memo
/// saw another view first.
fn tiles_share_the_cells(scene: &Scene, view: &View, whole: &[[f32; 3]]) {
    let params = RenderParams::default();
    let lights = LightSet::collect(scene, params.dr);
    let memo = CellMemo::default();
    let other = hall_view("-vp 0 0 1.6 -vd .3 1 .1 -vu 0 0 1 -vh 70 -vv 50");
    let (_, _, w, h) = render(scene, &lights, &params, view, 320, 4, [0, 0, 1, 1], None);
    render(
        scene,
        &lights,
        &params,
        &other,
        320,
        4,
        [0, 0, 9, 9],
        Some(&memo),
    );
    for (x, y) in [(0, 0), (137, 0), (0, 61), (137, 61)] {
        let x1 = if x == 0 { 137 } else { w };
        let y1 = if y == 0 { 61 } else { h };
        let r = [x, y, x1, y1];
        let (tile, _, _, _) = render(scene, &lights, &params, view, 320, 4, r, Some(&memo));
        let tw = x1 - x;
        for (i, p) in tile.iter().enumerate() {
            let (px, py) = (x + i % tw, y + i / tw);
            assert_eq!(*p, whole[py * w + px], "pixel ({px}, {py})");
        }
    }
}

/// A lamp narrower than a pixel is drawn by the area it covers, as rpict draws it: each
/// pixel holds `(1 − c)·B + c·L` (`c` the covered fraction, `B` its sample, or 0 where
/// the sample point lies on the lamp), whatever the lamp's place among the pixels. Values
/// measured with rpict 6.0a on the same scene (`-ps 1 -pj 0`, 64², glow 2 behind): 9.531 ×
/// 4 on a corner, 17.06 × 2 on an edge, 30.69 on the sample point.
#[test]
fn sources_smaller_than_a_pixel_are_drawn_by_their_coverage() {
    let text = "void light lamp 0 0 3 100 100 100\n\
         lamp polygon sq 0 0 12 0.05 10 -0.05 0.05 10 0.05 -0.05 10 0.05 -0.05 10 -0.05\n\
         void glow bg 0 0 4 2 2 2 0\n\
         bg polygon wall 0 0 12 50 11 -50 50 11 50 -50 11 50 -50 11 -50\n";
    let prims =
        tessera::scene::parse_scene_text(text, "lamp.rad", &ReadOptions::default()).unwrap();
    let scene = Scene::build(&prims).unwrap();
    let params = RenderParams::default();
    let lights = LightSet::collect(&scene, params.dr);
    // Half the lamp's side in pixels: 0.005 of the image plane's tan, 2·tan 30° per 64.
    let half = 0.005 / (2.0 * 30f64.to_radians().tan() / 64.0);
    let side = 2.0 * half;
    let (bg, lamp) = (2.0, 100.0);
    // (view shift in x and z, expected pixels as (x, y from the top, value))
    let quarter = side * side / 4.0;
    let half_area = side * side / 2.0;
    // (x, y from the top, value)
    type Pixels = Vec<(usize, usize, f64)>;
    let cases: [(f64, f64, Pixels); 3] = [
        (
            0.0,
            0.0,
            [(31, 31), (32, 31), (31, 32), (32, 32)]
                .map(|(x, y)| (x, y, (1.0 - quarter) * bg + quarter * lamp))
                .to_vec(),
        ),
        (
            0.08,
            0.0,
            [(31, 31), (31, 32)]
                .map(|(x, y)| (x, y, (1.0 - half_area) * bg + half_area * lamp))
                .to_vec(),
        ),
        // On the sample point of pixel (31, 32): the sample saw the lamp, so no background.
        (0.09, 0.09, vec![(31, 32, side * side * lamp)]),
    ];
    for (dx, dz, want) in cases {
        let view = hall_view(&format!(
            "-vp {dx} 0 {dz} -vd 0 1 0 -vu 0 0 1 -vh 60 -vv 60"
        ));
        let vf = view.frame().unwrap();
        let tracer = Tracer::new(&scene, &params, &lights);
        let fs = FrameSetup {
            view: &vf,
            xres: 64,
            yres: 64,
            pj: 0.0,
            ps: 1,
            pt: 0.05,
            frame: 0,
            irradiance: false,
            overture: 0,
            aa: None,
        };
        let px = render_region(&tracer, &fs, 0, 0, 64, 64, &RenderProgress::default());
        // Tiles cut through the lamp's pixels draw the same pixels.
        for (tx, ty) in [(0, 0), (32, 0), (0, 32), (32, 32)] {
            let tile = render_region(
                &tracer,
                &fs,
                tx,
                ty,
                tx + 32,
                ty + 32,
                &RenderProgress::default(),
            );
            for (i, p) in tile.iter().enumerate() {
                let (x, y) = (tx + i % 32, ty + i / 32);
                assert_eq!(*p, px[y * 64 + x], "tile pixel ({x}, {y})");
            }
        }
        let mut seen = 0;
        for (i, p) in px.iter().enumerate() {
            let (x, y) = (i % 64, i / 64);
            let v = p[0] as f64;
            match want.iter().find(|w| (w.0, w.1) == (x, y)) {
                Some(w) => {
                    assert!(
                        (v - w.2).abs() < 1e-4 * w.2,
                        "({x}, {y}): {v} against {}",
                        w.2
                    );
                    seen += 1;
                }
                None => assert!((v - bg).abs() < 1e-5, "({x}, {y}): {v} ({dx}, {dz})"),
            }
        }
        assert_eq!(seen, want.len());
    }
}
