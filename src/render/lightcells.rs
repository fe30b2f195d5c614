//! Light sources that adaptive image sampling could miss: the cells of the sampling grid
//! where a small source appears are sampled at every pixel.
//!
//! With `-ps N` the first samples lie about N pixels apart; a luminaire a pixel or two wide
//! (a downlight across a hall, the sun's disc) falls between them more often than not and
//! is interpolated away with the ceiling or sky around it. rpict loses such sources less
//! often than its spacing suggests; Tessera does not leave it to chance: every local source
//! whose image is at most [`SMALL`] cells across in one direction, and every distant source
//! of at most [`MAX_DISTANT_DEG`], has the cells its projected bounds touch (and their
//! neighbours) sampled at every pixel. The cells depend on the frame alone (view, scene,
//! sources), never on the region rendered, so tiles and threads keep their pixels; a
//! session computes them once per frame ([`CellMemo`]), not once per tile.

use std::collections::HashSet;
use std::sync::{Arc, Mutex};

use glam::DVec3;

use super::picture::FrameSetup;
use super::trace::Tracer;
use crate::light::source::LightSet;
use crate::render::world::Scene;
use crate::view::{View, ViewFrame};

/// A source at most this many cells across (in its narrower direction) is small.
const SMALL: f64 = 2.0;

/// Most cells one source marks (a long thin source seen along its length stops here).
const MAX_CELLS: usize = 4096;

/// Largest distant source treated as small, in degrees (the sun is 0.5; skies are 180).
const MAX_DISTANT_DEG: f64 = 5.0;

/// Frames a [`CellMemo`] keeps (the tile loops of a worker may be on as many
/// frames at once).
const MEMO_FRAMES: usize = 8;

/// What a frame's sources depend on besides the scene and its sources: the view, the
/// picture's size, the cell side and whether pixels hold irradiance (`-i`).
type FrameKey = (View, usize, usize, usize, bool);

/// What a frame's small light sources ask of its pixels: the cells sampled at every pixel,
/// and the sources drawn by their coverage ([`super::srcdraw`]).
#[derive(Debug, Default)]
pub struct FrameSources {
    /// Cells (column, row) sampled at every pixel.
    pub cells: HashSet<(usize, usize)>,
    /// Sources drawn by coverage.
    pub drawn: Vec<super::srcdraw::Drawn>,
}

impl FrameSources {
    /// Both, for frame `fs` with sampling cells of side `cell`.
    pub fn compute(tr: &Tracer, fs: &FrameSetup, cell: usize) -> FrameSources {
        FrameSources {
            cells: source_cells(tr, fs.view, fs.xres, fs.yres, cell),
            drawn: super::srcdraw::frame_sources(tr, fs),
        }
    }
}

/// The small sources of the frames a session rendered last: one computation per frame,
/// however many tiles it is cut into. Only for one scene and one set of sources (a
/// session's).
#[derive(Default)]
pub struct CellMemo {
    frames: Mutex<Vec<(FrameKey, Arc<FrameSources>)>>,
}

impl CellMemo {
    /// [`FrameSources::compute`] for this frame, computed on its first tile.
    pub fn frame(&self, tr: &Tracer, fs: &FrameSetup, cell: usize) -> Arc<FrameSources> {
        let key = (fs.view.view.clone(), fs.xres, fs.yres, cell, fs.irradiance);
        let found = |f: &Vec<(FrameKey, Arc<FrameSources>)>| {
            f.iter().find(|(k, _)| *k == key).map(|(_, c)| c.clone())
        };
        if let Some(c) = self.frames.lock().ok().and_then(|f| found(&f)) {
            return c;
        }
        // Computed without the lock (another thread may compute the same: the same set).
        let c = Arc::new(FrameSources::compute(tr, fs, cell));
        if let Ok(mut f) = self.frames.lock() {
            if found(&f).is_none() {
                if f.len() >= MEMO_FRAMES {
                    f.remove(0);
                }
                f.push((key, c.clone()));
            }
        }
        c
    }
}

/// The cells (column, row of the grid of side `cell` pixels, rows from the top) to sample at
/// every pixel in a picture of `xres × yres`.
pub fn source_cells(
    tr: &Tracer,
    view: &ViewFrame,
    xres: usize,
    yres: usize,
    cell: usize,
) -> HashSet<(usize, usize)> {
    let mut out = HashSet::new();
    if cell <= 1 || xres == 0 || yres == 0 {
        return out;
    }
    for_each_outline(tr.scene, tr.lights, view.view.vp, |pts| {
        mark(&mut out, view, pts, xres, yres, cell);
    });
    out
}

/// Call `f` with world points outlining each real source: a local source's bounding box
/// corners, a small distant source's disc seen from the view point.
fn for_each_outline(scene: &Scene, lights: &LightSet, vp: DVec3, mut f: impl FnMut(&[DVec3])) {
    for s in &lights.sources {
        if s.relay.is_some() {
            continue;
        }
        if let Some(obj) = s.obj {
            let Some(o) = scene.objects.get(obj) else {
                continue;
            };
            let (lo, hi) = scene.objects.shape(o).bounds();
            let (lo, hi) = (lo + scene.origin, hi + scene.origin);
            f(&super::srcdraw::box_corners(lo, hi));
        } else if let Some(d) = s.distant.and_then(|i| scene.distant.get(i)) {
            let src = &d.source;
            if !(src.angle_deg > 0.0 && src.angle_deg <= MAX_DISTANT_DEG) {
                continue;
            }
            let r = (0.5 * src.angle_deg).to_radians().tan();
            let u = crate::geometry::any_perpendicular(src.dir);
            let v = src.dir.cross(u);
            f(
                &[(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.0, 0.0)]
                    .map(|(a, b)| vp + src.dir + (u * a + v * b) * r),
            );
        }
    }
}

/// Mark the cells under the projection of `pts` when it is small; nothing when any point
/// cannot be located (behind the view: such a source is large or out of sight).
fn mark(
    out: &mut HashSet<(usize, usize)>,
    view: &ViewFrame,
    pts: &[DVec3],
    xres: usize,
    yres: usize,
    cell: usize,
) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in pts {
        let Some((x, y, _)) = view.locate(*p) else {
            return;
        };
        // Pixels, y from the top.
        let (px, py) = (x * xres as f64, (1.0 - y) * yres as f64);
        x0 = x0.min(px);
        x1 = x1.max(px);
        y0 = y0.min(py);
        y1 = y1.max(py);
    }
    let c = cell as f64;
    if !(x1 >= 0.0 && y1 >= 0.0 && x0 <= xres as f64 && y0 <= yres as f64) {
        return;
    }
    if (x1 - x0).min(y1 - y0) > SMALL * c {
        return;
    }
    // The cells of the pixels within a pixel of the bounds (a jittered sample strays up to
    // half a pixel from its own).
    let cells = |a: f64, b: f64, n: usize| {
        let a = (a - 1.0).clamp(0.0, n as f64 - 1.0) as usize / cell;
        let b = (b + 1.0).clamp(0.0, n as f64 - 1.0) as usize / cell;
        (a, b)
    };
    let (cx0, cx1) = cells(x0, x1, xres);
    let (cy0, cy1) = cells(y0, y1, yres);
    if (cx1 + 1 - cx0).saturating_mul(cy1 + 1 - cy0) > MAX_CELLS {
        return;
    }
    for cy in cy0..=cy1 {
        for cx in cx0..=cx1 {
            out.insert((cx, cy));
        }
    }
}
