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
//! Blocks of [`BLOCK`]² pixels (on the `-ps` grid) are taken at the centres of a 4 × 4
//! grid over the frame, spread out, until the budget is spent (at least one block). At
//! `-ab 0` the estimate is unbiased. With indirect light the probe starts from an empty
//! ambient cache and its blocks are far apart, so they share few values: it estimates
//! high (a real render reuses each value over many more pixels), which costs a plan a few
//! more tiles than it needs (bounded by [`super::plan::TILES_PER_WORKER`]), never fewer.

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

/// Wall seconds the probe may take (it stops after the block that passes it).
pub const BUDGET: f64 = 0.1;

/// What the probe measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Probe {
    /// Pixels rendered.
    pub pixels: usize,
    /// Blocks rendered.
    pub blocks: usize,
    /// CPU seconds they took.
    pub cpu_seconds: f64,
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
    for &k in &ORDER {
        if p.blocks > 0 && start.elapsed().as_secs_f64() >= budget {
            break;
        }
        let (gx, gy) = (k % 4, k / 4);
        // The block around the centre of grid cell (gx, gy), its corner on the cell grid.
        let cx = (2 * gx + 1) * w / 8;
        let cy = (2 * gy + 1) * h / 8;
        let x0 =
            (cx.saturating_sub(side / 2) / cell * cell).min(w.saturating_sub(side) / cell * cell);
        let y0 =
            (cy.saturating_sub(side / 2) / cell * cell).min(h.saturating_sub(side) / cell * cell);
        let (x1, y1) = ((x0 + side).min(w), (y0 + side).min(h));
        let progress = RenderProgress::default();
        let t0 = thread_cpu_nanos();
        here.install(|| render_region(&tracer, fs, x0, y0, x1, y1, &progress));
        let dt = thread_cpu_nanos().saturating_sub(t0) as f64 * 1e-9;
        p.cpu_seconds += dt;
        p.pixels += (x1 - x0) * (y1 - y0);
        p.blocks += 1;
        if let Some(e) = scene.fatal_error() {
            anyhow::bail!("{e}");
        }
    }
    if p.pixels > 0 {
        p.frame_seconds = p.cpu_seconds / p.pixels as f64 * (w * h) as f64;
    }
    Ok(p)
}
