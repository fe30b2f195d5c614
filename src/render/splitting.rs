//! A region rendered on one thread in reading order ([`in_order`]): every one-thread render
//! ([`super::render_region_rows`], which hands each band on as it is done), and a region
//! whose unstarted part can be given away while it renders (the batch workers' tile
//! splitting, `job::piece`).
//!
//! [`render_region_split`] renders the cells of the sampling grid band by band, top to bottom,
//! each band's cells left to right, and before each cell asks a hook whether to cut: either
//! the rows from a band start below the band in progress ([`Cut::Rows`]), or the columns from
//! a cell start right of the next cell, in the band in progress and every band below
//! ([`Cut::Cols`]). What is cut is not rendered (its pixels stay zero). Every sample depends on
//! its pixel alone and cells lie on the picture's grid, so the pixels rendered are exactly
//! those [`super::render_region`] gives (on one thread, where nothing is cut, the same
//! render; on several, with indirect light, up to the order in which ambient values are
//! made).

use super::lightcells::FrameSources;
use super::picture::{
    cell_size, draw_sources, frame_sources, overture, overture_rows, render_cell, sample_pixel,
    to_f32, CellEdges, CellScratch, FrameSetup, RenderProgress, Sample,
};
use super::trace::Tracer;
use std::sync::atomic::Ordering;
use std::sync::Arc;

/// Where a splittable render stands, before its next cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitPoint {
    /// First column of the region.
    pub x0: usize,
    /// End (exclusive) of the columns still to render in this band and those below.
    pub x1: usize,
    /// End (exclusive) of the rows still to render.
    pub y1: usize,
    /// The rows of the band in progress, `[band.0, band.1)`.
    pub band: (usize, usize),
    /// The first column of the next cell (in the band in progress).
    pub next_x: usize,
    /// The side of a cell in pixels (1 at `-ps 1`).
    pub cell: usize,
    /// Cells rendered so far.
    pub done: usize,
}

impl SplitPoint {
    /// The cell starts of the band in progress from the next cell on.
    pub fn columns_left(&self) -> Vec<usize> {
        let c = self.cell.max(1);
        let mut v = vec![self.next_x];
        let mut x = (self.next_x / c + 1) * c;
        while x < self.x1 {
            v.push(x);
            x += c;
        }
        v.retain(|&x| x < self.x1);
        v
    }

    /// The band starts below the band in progress.
    pub fn rows_left(&self) -> Vec<usize> {
        let c = self.cell.max(1);
        let mut v = Vec::new();
        let mut y = self.band.1;
        while y < self.y1 {
            v.push(y);
            y = (y / c + 1) * c;
        }
        v
    }

    /// Cells still to render (the next one included).
    pub fn cells_left(&self) -> usize {
        let c = self.cell.max(1);
        let per_band = self.x1.div_ceil(c).saturating_sub(self.x0 / c);
        self.columns_left().len() + self.rows_left().len() * per_band
    }
}

/// Asked before each cell where a render stands; what it returns is given away.
pub type SplitHook<'a> = dyn FnMut(&SplitPoint) -> Option<Cut> + 'a;

/// What a hook gives away.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    /// The rows from this one (a band start below the band in progress) to the end.
    Rows(usize),
    /// The columns from this one (a cell start after the next cell's) to the end, in the
    /// band in progress and every band below.
    Cols(usize),
}

/// Render `[x0, x1) × [y0, y1)` as [`super::render_region`] does, on the calling thread in
/// reading order, asking `hook` before each cell whether to give part of what is left away.
/// A cut outside what is left is ignored.
pub fn render_region_split(
    tr: &Tracer,
    fs: &FrameSetup,
    (x0, y0, x1, y1): (usize, usize, usize, usize),
    progress: &RenderProgress,
    hook: &mut SplitHook<'_>,
) -> Vec<[f32; 3]> {
    let w = x1.saturating_sub(x0);
    let h = y1.saturating_sub(y0);
    let mut out = vec![[0f32; 3]; w * h];
    if w == 0 || h == 0 {
        return out;
    }
    let emit = &mut |by0: usize, band: &[[f32; 3]], _: &FrameSources| {
        let at = (by0 - y0) * w;
        out[at..at + band.len()].copy_from_slice(band);
    };
    let src = in_order(tr, fs, (x0, y0, x1, y1), progress, Some(hook), emit);
    // Over the whole region, the parts given away included (their pieces draw them too).
    draw_sources(tr, fs, &src, (x0, y0, x1, y1), &mut out, progress);
    out
}

/// What [`in_order`] hands on for each band: its first row, its `w · rows` pixels (small
/// light sources not drawn yet) and the frame's small sources.
pub(super) type BandSink<'a> = dyn FnMut(usize, &[[f32; 3]], &FrameSources) + 'a;

/// The bands of `[x0, x1) × [y0, y1)` (not empty) in reading order on the calling thread,
/// each handed to `emit` when done; with `hook`, asked before each cell whether to give
/// part of what is left away (the pixels given away stay zero, the bands below a row cut
/// are not emitted). Returns the frame's small light sources.
pub(super) fn in_order(
    tr: &Tracer,
    fs: &FrameSetup,
    (x0, y0, x1, y1): (usize, usize, usize, usize),
    progress: &RenderProgress,
    mut hook: Option<&mut SplitHook<'_>>,
    emit: &mut BandSink<'_>,
) -> Arc<FrameSources> {
    let w = x1 - x0;
    let ps = cell_size(fs.ps);
    let frame_src = frame_sources(tr, fs, ps);
    // The overture runs band by band just ahead of the picture's pass (its rows up to one
    // overture step below the band), so that what is given away has not been filled yet.
    let rows = overture_rows(fs, y0, y1);
    let mut ov = 0;
    progress
        .rows_total
        .store(rows.len() + y1.div_ceil(ps) - y0 / ps, Ordering::Relaxed);
    let (mut xe, mut ye) = (x1, y1);
    let mut done = 0;
    let mut rays = 0;
    // Band lines shared by neighbouring bands and the cell column shared along a band, as in
    // render_region; here the bands run in order, so one line carries over.
    let lx0 = x0 / ps * ps;
    let line_len = (x1.div_ceil(ps) * ps).min(fs.xres - 1) + 1 - lx0;
    let mut top: Vec<Option<Sample>> = vec![None; line_len];
    let mut bottom: Vec<Option<Sample>> = vec![None; line_len];
    let mut left = Vec::new();
    let mut scratch = CellScratch::default();
    let mut band = Vec::with_capacity(w * ps);
    let mut cy = y0 / ps;
    while cy * ps < ye && tr.scene.fatal_error().is_none() {
        let (by0, by1) = ((cy * ps).max(y0), ((cy + 1) * ps).min(ye));
        let ahead = rows[ov..]
            .iter()
            .take_while(|&&y| y < (by1 + fs.overture).min(ye))
            .count();
        overture(tr, fs, x0, xe, &rows[ov..ov + ahead], progress);
        ov += ahead;
        left.clear();
        band.clear();
        band.resize((by1 - by0) * w, [0f32; 3]);
        let mut cx = x0 / ps;
        while cx * ps < xe {
            let next_x = (cx * ps).max(x0);
            if let Some(hook) = hook.as_mut() {
                let at = SplitPoint {
                    x0,
                    x1: xe,
                    y1: ye,
                    band: (by0, by1),
                    next_x,
                    cell: ps,
                    done,
                };
                match hook(&at) {
                    Some(Cut::Rows(k)) if k >= by1 && k < ye && k % ps == 0 => ye = k,
                    Some(Cut::Cols(q)) if q > next_x && q < xe && q % ps == 0 => xe = q,
                    _ => {}
                }
            }
            if ps == 1 {
                let s = sample_pixel(tr, fs, cx, cy, &mut rays);
                band[cx - x0] = to_f32(s.color);
            } else {
                let mut edges = CellEdges {
                    top: &mut top[cx * ps - lx0..],
                    bottom: &mut bottom[cx * ps - lx0..],
                    left: &mut left,
                };
                let full = frame_src.cells.contains(&(cx, cy));
                render_cell(
                    tr,
                    fs,
                    (cx, cy, ps, full),
                    &mut edges,
                    &mut scratch,
                    &mut rays,
                    &mut |x, y, c| {
                        if x >= x0 && x < xe && y >= by0 && y < by1 {
                            band[(y - by0) * w + (x - x0)] = to_f32(c);
                        }
                    },
                );
            }
            done += 1;
            cx += 1;
        }
        // The band's bottom line is the next band's top line.
        std::mem::swap(&mut top, &mut bottom);
        bottom.iter_mut().for_each(|s| *s = None);
        progress
            .rays
            .fetch_add(std::mem::take(&mut rays), Ordering::Relaxed);
        progress.rows_done.fetch_add(1, Ordering::Relaxed);
        if tr.scene.fatal_error().is_none() {
            emit(by0, &band, &frame_src);
        }
        cy += 1;
    }
    frame_src
}
