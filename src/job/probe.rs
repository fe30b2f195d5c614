//! The cost probe of `tplan`'s default plan: render a few small blocks of the first frame
//! with the job's own settings, on one thread and within a time budget, and estimate what
//! the whole frame costs.
//!
//! A plan needs the frame's cost: few tiles for a cheap frame (each tile costs a worker
//! about [`super::plan::TILE_OVERHEAD`] besides its pixels), many for an expensive one (so
//! that the workers finish together). A lower bound of the cost per pixel
//! ([`super::plan::pixel_cost_floor`]) is right for cheap frames and far too low for real
//! scenes with indirect light (the bench office at `-ab 2` costs 170× the bound). The probe
//! measures instead.
//!
//! At each of the probe's places (the centres of a 4 × 4 grid over the frame, spread out,
//! until the budget is spent; at least one place) it renders a 3 × 3 patch of [`BLOCK`]²
//! blocks (on the `-ps` grid) in reading order, as a tile renders its rows, and counts the
//! blocks after the first: the first starts from what the cache holds (at the first place
//! nothing), the others find the values of the blocks before them and make only those a
//! tile would make there. At `-ab 0` every block is a fair sample.
//!
//! With one bounce the marching blocks are close to what the frame costs: their estimate
//! was 1.1–1.9× the frame's CPU on the demo and the three scenes of
//! `bench/realscenes.sh` at 256–320 pixels (docs/benchmarks.md, "Scaling and the default
//! plan"). From `-ab 2` on a pixel's values need deeper ones that the whole frame shares,
//! and a few blocks make them for themselves alone: the marching blocks alone estimate
//! 12–19× too high. So the counted blocks are rendered once more, their values now in the
//! cache: a pixel that makes no value costs less than the frame's mean, and from `-ab 2`
//! on the estimate is the geometric mean of the two passes, whose ratio to either is the
//! square root of theirs: 0.6–1.4× the frame's CPU on the demo, the office and the hall
//! (the first probe, of cold blocks far apart, was 59–153× too high there, and planned a
//! 6 CPU-s frame like a 900 CPU-s one). The estimate scales with the pixel count while the
//! frame's values do not, so small frames come out low and large ones high. The tile rule
//! takes the square root of the estimate ([`super::plan::tiles_for_cost`]): a factor 2 in
//! the estimate is 1.4 in the tile count.

use crate::ambient::Ambient;
use crate::light::LightSet;
use crate::options::RenderParams;
use crate::render::world::Scene;
use crate::render::{render_region, FrameSetup, RenderProgress, Tracer};
use crate::runinfo::{process_origin_id, thread_cpu_nanos};
use crate::session::Session;
use anyhow::Result;
use std::time::Instant;

/// Side of a probe block in pixels (rounded up to the `-ps` cell).
pub const BLOCK: usize = 8;

/// Wall seconds the probe may take (it stops after the place that passes it).
pub const BUDGET: f64 = 0.1;

/// Blocks on a side of the patch rendered at each place.
pub const PATCH: usize = 3;

/// What the probe measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Probe {
    /// Pixels of the blocks counted (each patch's blocks after its first).
    pub pixels: usize,
    /// Blocks rendered (every patch's first too).
    pub blocks: usize,
    /// CPU seconds the counted blocks took.
    pub cpu_seconds: f64,
    /// CPU seconds they took again with their values in the cache (from `-ab 2` on, when
    /// values were made; else `cpu_seconds`).
    pub warm_seconds: f64,
    /// Estimated CPU seconds of the whole frame.
    pub frame_seconds: f64,
}

/// The blocks' order over the 4 × 4 grid: each next one far from those before it.
const ORDER: [usize; 16] = [5, 15, 0, 10, 12, 3, 9, 6, 2, 13, 8, 7, 14, 1, 11, 4];

/// Probe the frame `fs` of `scene` with `params` within `budget` wall seconds.
pub fn probe(scene: &Scene, params: &RenderParams, fs: &FrameSetup, budget: f64) -> Result<Probe> {
    let (w, h) = (fs.xres, fs.yres);
    if w == 0 || h == 0 {
        return Ok(Probe::default());
    }
    let lights = LightSet::collect(scene, params.dr);
    let ambient = Ambient::new(params, scene.size, process_origin_id());
    let tracer = Tracer::new(scene, params, &lights).with_ambient(ambient.as_ref());
    let here = Session::here_pool()?;
    let cell = crate::render::cell_size(fs.ps.max(1));
    let side = BLOCK.div_ceil(cell) * cell;
    let start = Instant::now();
    let mut p = Probe::default();
    // Every block with its CPU seconds and whether it is its patch's first.
    let mut rendered = Vec::new();
    let (made0, _) = crate::ambient::compute::thread_work();
    for &k in &ORDER {
        if p.blocks > 0 && start.elapsed().as_secs_f64() >= budget {
            break;
        }
        let (gx, gy) = (k % 4, k / 4);
        // The patch around the centre of grid cell (gx, gy), its corner on the cell grid.
        let cx = (2 * gx + 1) * w / 8;
        let cy = (2 * gy + 1) * h / 8;
        let patch = PATCH * side;
        let px0 =
            (cx.saturating_sub(patch / 2) / cell * cell).min(w.saturating_sub(patch) / cell * cell);
        let py0 =
            (cy.saturating_sub(patch / 2) / cell * cell).min(h.saturating_sub(patch) / cell * cell);
        for j in 0..PATCH {
            for i in 0..PATCH {
                let (x0, y0) = (px0 + i * side, py0 + j * side);
                if x0 >= w || y0 >= h {
                    continue;
                }
                let b = (x0, y0, (x0 + side).min(w), (y0 + side).min(h));
                rendered.push((b, block_seconds(&here, &tracer, fs, b), i + j == 0));
                p.blocks += 1;
            }
        }
        if let Some(e) = scene.fatal_error() {
            anyhow::bail!("{e}");
        }
    }
    // The blocks after each patch's first; the first ones where a frame is too small for
    // more.
    let later = rendered.iter().any(|r| !r.2);
    let counted: Vec<_> = rendered.into_iter().filter(|r| !r.2 || !later).collect();
    for &(b, t, _) in &counted {
        p.cpu_seconds += t;
        p.pixels += (b.2 - b.0) * (b.3 - b.1);
    }
    let (made1, _) = crate::ambient::compute::thread_work();
    p.warm_seconds = if params.ab >= 2 && made1 > made0 {
        counted
            .iter()
            .map(|&(b, _, _)| block_seconds(&here, &tracer, fs, b))
            .sum::<f64>()
            .min(p.cpu_seconds)
    } else {
        p.cpu_seconds
    };
    if p.pixels > 0 {
        let per_pixel = (p.cpu_seconds * p.warm_seconds).sqrt() / p.pixels as f64;
        p.frame_seconds = per_pixel * (w * h) as f64;
    }
    Ok(p)
}

/// CPU seconds this thread takes to render the block `(x0, y0, x1, y1)`.
fn block_seconds(
    here: &rayon::ThreadPool,
    tracer: &Tracer,
    fs: &FrameSetup,
    (x0, y0, x1, y1): (usize, usize, usize, usize),
) -> f64 {
    let progress = RenderProgress::default();
    let t0 = thread_cpu_nanos();
    here.install(|| render_region(tracer, fs, x0, y0, x1, y1, &progress));
    thread_cpu_nanos().saturating_sub(t0) as f64 * 1e-9
}
