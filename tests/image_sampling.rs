//! Adaptive image sampling (`-ps`, `-pt`): any tiling renders the same pixels, and border
//! samples shared by neighbouring cells are traced once.

use std::path::Path;
use std::sync::atomic::Ordering;
use tessera::light::LightSet;
use tessera::options::RenderParams;
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
        let vf = self.view.frame().unwrap();
        let (mut x, mut y, mut pa) = (res, res, 1.0);
        normaspect(vf.aspect(), &mut pa, &mut x, &mut y);
        let tracer = Tracer::new(&self.scene, &self.params, &self.lights);
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
    let (_, every, w, h) = c.region(96, 1, [0, 0, usize::MAX, usize::MAX]);
    let (_, whole, _, _) = c.region(96, 4, [0, 0, w, h]);
    let side = cell_size(4);
    let strips: u64 = (0..h)
        .step_by(side)
        .map(|y| c.region(96, 4, [0, y, w, y + side]).1)
        .sum();
    assert!(whole < strips, "whole {whole}, strips {strips}");
    assert!(2 * whole < every, "whole {whole}, every pixel {every}");
}
