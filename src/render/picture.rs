//! The pixel loop: pixel jitter (`-pj`), adaptive image sampling (`-ps`, `-pt`) on a global
//! cell grid, and threads. Every pixel sample is seeded by its global pixel position and the
//! frame number alone, and cells lie on a grid fixed by the full image, so any region renders
//! to exactly the same pixels whatever the thread count or tiling.

use super::ray::Ray;
use super::sampler::Sampler;
use super::shading::ShadingPoint;
use super::trace::Tracer;
use crate::color::{bright, sanitize, Color};
use crate::material::normal::NormalKind;
use crate::material::Material;
use crate::view::ViewFrame;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;

/// What a picture render needs besides the tracer.
pub struct FrameSetup<'a> {
    /// The view.
    pub view: &'a ViewFrame,
    /// Full picture width.
    pub xres: usize,
    /// Full picture height.
    pub yres: usize,
    /// Pixel jitter fraction (`-pj`).
    pub pj: f64,
    /// Sample spacing (`-ps`); 1 traces every pixel.
    pub ps: usize,
    /// Relative difference that forces subdivision (`-pt`).
    pub pt: f64,
    /// Frame number (seeds the random numbers).
    pub frame: u32,
    /// Irradiance output (`-i`).
    pub irradiance: bool,
    /// Pixel step of the overture: a first pass over every `overture`-th pixel row and column
    /// that only fills the ambient cache (its colours are discarded), so that the picture's
    /// own pass interpolates every pixel from all the values around it. 0: no overture.
    pub overture: usize,
    /// `-aa` of this frame when it varies with time (`-ax`): the session sets it before
    /// rendering. None: the options' `-aa`.
    pub aa: Option<f64>,
}

/// Counters updated while rendering.
#[derive(Debug, Default)]
pub struct RenderProgress {
    /// Rays traced so far.
    pub rays: AtomicU64,
    /// Cell rows (or pixel rows with `-ps 1`) finished.
    pub rows_done: AtomicUsize,
    /// Cell rows in all.
    pub rows_total: AtomicUsize,
}

/// A traced sample: colour and distance of the first hit (for the depth test).
#[derive(Clone, Copy, Debug)]
pub(super) struct Sample {
    pub(super) color: Color,
    dist: f64,
}

/// Where pixel `(px, py_top)`'s sample lies (image coordinates in [0, 1], y from the
/// bottom: its jitter), with the pixel's random numbers ready for the rest of its path.
pub(super) fn sample_point(fs: &FrameSetup, px: usize, py_top: usize) -> (Sampler, f64, f64) {
    let mut rng = Sampler::for_pixel(fs.frame, px as u32, py_top as u32, 0);
    let yb = fs.yres - 1 - py_top;
    let (r1, r2) = rng.next2();
    let x = (px as f64 + 0.5 + fs.pj * (0.5 - r1)) / fs.xres as f64;
    let y = (yb as f64 + 0.5 + fs.pj * (0.5 - r2)) / fs.yres as f64;
    (rng, x, y)
}

pub(super) fn sample_pixel(
    tr: &Tracer,
    fs: &FrameSetup,
    px: usize,
    py_top: usize,
    rays: &mut u64,
) -> Sample {
    let (mut rng, x, y) = sample_point(fs, px, py_top);
    let Some((org, dir, tmax)) = fs.view.ray(x, y) else {
        return Sample {
            color: Color::ZERO,
            dist: 0.0,
        };
    };
    let ray = Ray::primary(org - tr.scene.origin, dir, tmax);
    // The first hit's distance comes with the traced colour (one intersection, not two).
    let (color, dist) = if fs.irradiance {
        let dist = tr.intersect(&ray).map(|h| h.t).unwrap_or(f64::INFINITY);
        (irradiance(tr, &ray, &mut rng), dist)
    } else {
        tr.trace_dist(&ray, &mut rng)
    };
    *rays += rng.rays;
    Sample {
        color: sanitize(color),
        dist,
    }
}

/// `-i`: irradiance at the first opaque, non-emitting surface, as if it were white and
/// Lambertian. As in rpict, rays pass straight through transparent materials (`trans`,
/// `trans2`, `glass`, `dielectric`, `interface`, a `BRTDfunc` where its transmission is not
/// zero) and surfaces without a material, and the irradiance
/// is that of the surface behind them; light sources show their radiance.
pub(crate) fn irradiance(tr: &Tracer, ray: &Ray, rng: &mut Sampler) -> Color {
    let mut ray = *ray;
    let mut hit = None;
    // Bound the walk through stacked transparent surfaces, as pass_through does.
    for _ in 0..1000 {
        let Some(h) = tr.intersect(&ray) else {
            return tr.trace(&ray, rng);
        };
        let through = match h.material.map(|m| tr.scene.material(m)) {
            None => true,
            Some(Material::Emitter(_) | Material::Antimatter(_)) => return tr.trace(&ray, rng),
            // A BRTDfunc lets the ray through where it transmits (measured with rtrace -i).
            Some(Material::Brtd(b)) => {
                let sp = ShadingPoint::new(&ray, &h, tr.scene.origin);
                b.shadow_transmission(&sp).max_element() > 0.0
            }
            Some(m) => irradiance_ignores(m),
        };
        if !through {
            hit = Some(h);
            break;
        }
        ray.org = h.point;
        ray.tmax -= h.t;
        ray.antimatter = h.antimatter;
        ray.prior += h.t;
        if ray.tmax <= tr.scene.eps {
            return Color::ZERO;
        }
    }
    let Some(hit) = hit else {
        return Color::ZERO;
    };
    let n = if hit.back { -hit.normal } else { hit.normal };
    white_lambertian(tr, &ray, &hit, n, rng)
}

/// `rtrace -I`: the irradiance at point `p` (relative frame) on a white Lambertian surface
/// facing the unit normal `n` that is no surface of the scene: the light arriving at `p`
/// from the hemisphere around `n`.
pub(crate) fn irradiance_at(tr: &Tracer, p: DVec3, n: DVec3, rng: &mut Sampler) -> Color {
    // A ray arriving at p against the normal, from one unit away.
    let ray = Ray::primary(p + n, -n, f64::INFINITY);
    let hit = super::ray::Hit {
        obj: super::ray::NO_OBJECT,
        inst: super::ray::NO_INST,
        t: 1.0,
        point: p,
        normal: n,
        back: false,
        flat: true,
        material: None,
        antimatter: ray.antimatter,
    };
    white_lambertian(tr, &ray, &hit, n, rng)
}

/// Irradiance at a hit with normal `n` (facing the ray): direct light and indirect light as
/// a white Lambertian surface reflects them, times π.
fn white_lambertian(
    tr: &Tracer,
    ray: &Ray,
    hit: &super::ray::Hit,
    n: DVec3,
    rng: &mut Sampler,
) -> Color {
    let coef = move |l: DVec3, omega: f64| -> Color {
        let c = n.dot(l);
        if c > 0.0 {
            Color::splat(c * omega / std::f64::consts::PI)
        } else {
            Color::ZERO
        }
    };
    let d = tr.direct(ray, hit, (n, tr.constant_ambient(Color::ONE)), &coef, rng);
    let l = d + tr.ambient(ray, hit, Color::ONE, n, bright(d), rng);
    l * std::f64::consts::PI
}

/// Materials an irradiance ray passes straight through (rpict's rule for `-i`).
fn irradiance_ignores(m: &Material) -> bool {
    match m {
        Material::Normal(n) => n.kind == NormalKind::Trans,
        Material::Glass(_) | Material::Dielectric(_) => true,
        Material::Mirror(_)
        | Material::Emitter(_)
        | Material::Antimatter(_)
        | Material::Ashik(_)
        | Material::Brdf(_)
        | Material::Brtd(_) => false,
    }
}

fn bigdiff(a: &Sample, b: &Sample, pt: f64) -> bool {
    for c in 0..3 {
        let (x, y) = (a.color[c], b.color[c]);
        if (x - y).abs() > pt * 0.5 * (x + y) + 1e-12 {
            return true;
        }
    }
    let (da, db) = (a.dist, b.dist);
    if da.is_finite() != db.is_finite() {
        return true;
    }
    da.is_finite() && (da - db).abs() > pt * 0.5 * (da + db)
}

/// Render the pixels of the region `[x0, x1) × [y0, y1)` of the full picture (y counted from
/// the top), returned row by row from the top. Uses the current rayon pool: on one thread
/// the bands in reading order ([`super::splitting::in_order`]), on more the
/// schedule of [`super::schedule`].
pub fn render_region(
    tr: &Tracer,
    fs: &FrameSetup,
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
    progress: &RenderProgress,
) -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    render_region_rows(tr, fs, (x0, y0, x1, y1), progress, &mut |rows| {
        append_rows(&mut out, rows)
    });
    out.resize(x1.saturating_sub(x0) * y1.saturating_sub(y0), [0f32; 3]);
    out
}

/// Append rows handed on by [`render_region_rows`] to `out`; the first block moves in
/// whole (no second buffer of a frame's size when one block is the whole region).
pub fn append_rows(out: &mut Vec<[f32; 3]>, rows: Vec<[f32; 3]>) {
    if out.is_empty() {
        *out = rows;
    } else {
        out.extend_from_slice(&rows);
    }
}

/// [`render_region`], its rows handed to `sink` top first as they are finished: on one
/// thread a band at a time (so a frame's pixels are never all held at once), on more the
/// whole region at once.
pub fn render_region_rows(
    tr: &Tracer,
    fs: &FrameSetup,
    (x0, y0, x1, y1): (usize, usize, usize, usize),
    progress: &RenderProgress,
    sink: &mut dyn FnMut(Vec<[f32; 3]>),
) {
    if rayon::current_num_threads() > 1 {
        sink(render_parallel(tr, fs, (x0, y0, x1, y1), progress));
    } else if x1 > x0 && y1 > y0 {
        // The bands in reading order, each drawn and handed on when done.
        let region = (x0, y0, x1, y1);
        super::splitting::in_order(tr, fs, region, progress, None, &mut |by0, band, src| {
            let mut rows = band.to_vec();
            let by1 = by0 + band.len() / (x1 - x0);
            draw_sources(tr, fs, src, (x0, by0, x1, by1), &mut rows, progress);
            sink(rows);
        });
    }
}

/// [`render_region`] on several threads.
fn render_parallel(
    tr: &Tracer,
    fs: &FrameSetup,
    (x0, y0, x1, y1): (usize, usize, usize, usize),
    progress: &RenderProgress,
) -> Vec<[f32; 3]> {
    let w = x1.saturating_sub(x0);
    let h = y1.saturating_sub(y0);
    let mut out = vec![[0f32; 3]; w * h];
    if w == 0 || h == 0 {
        return out;
    }
    let ps = cell_size(fs.ps);
    // Cells of the global grid: pixels [cx*ps, (cx+1)*ps) × [cy*ps, (cy+1)*ps).
    let cy0 = y0 / ps;
    let cy1 = y1.div_ceil(ps);
    let overture_rows = overture_rows(fs, y0, y1);
    let rows = if ps == 1 { h } else { cy1 - cy0 };
    progress
        .rows_total
        .store(overture_rows.len() + rows, Ordering::Relaxed);
    overture(tr, fs, x0, x1, &overture_rows, progress);
    let frame_src = frame_sources(tr, fs, ps);
    let draw = |out: &mut Vec<[f32; 3]>| {
        draw_sources(tr, fs, &frame_src, (x0, y0, x1, y1), out, progress);
    };
    if ps == 1 {
        // Runs of a few pixels in reading order, which rayon spreads over the threads as it
        // did the rows (super::schedule): the pass ends on runs, not on whole rows.
        out.par_chunks_mut(super::schedule::RUN)
            .enumerate()
            .with_max_len(1)
            .for_each(|(k, run)| {
                if tr.scene.fatal_error().is_some() {
                    return;
                }
                let at = k * super::schedule::RUN;
                let mut rays = 0;
                for (i, px) in run.iter_mut().enumerate() {
                    let p = at + i;
                    let s = sample_pixel(tr, fs, x0 + p % w, y0 + p / w, &mut rays);
                    *px = to_f32(s.color);
                }
                progress.rays.fetch_add(rays, Ordering::Relaxed);
                // The rows whose last pixel this run rendered.
                let rows = (at + run.len()) / w - at / w;
                progress.rows_done.fetch_add(rows, Ordering::Relaxed);
            });
        draw(&mut out);
        return out;
    }
    let cx0 = x0 / ps;
    let cx1 = x1.div_ceil(ps);
    // Cells where a small light source appears are sampled at every pixel.
    let full = &frame_src.cells;
    // Samples on the cell borders are shared: a cell takes its left column from the cell
    // before it in its band, and its top and bottom rows from the band lines it shares with
    // the bands above and below. Even bands (their lines disjoint) run before the odd band
    // between them, which reuses the lines they filled. A sample depends only on its
    // pixel, so sharing changes no pixel, only how often a border sample is traced.
    let lx0 = cx0 * ps;
    let line_len = (cx1 * ps).min(fs.xres - 1) + 1 - lx0;
    // Each line is made when a band first needs it and dropped after the odd band that
    // shares it, so that only the lines of the bands in progress are held.
    let lines: Vec<Mutex<Vec<Option<Sample>>>> =
        (cy0..=cy1).map(|_| Mutex::new(Vec::new())).collect();
    // Each band writes its own rows of `out`.
    let band = |(cy, rows): (usize, &mut [[f32; 3]])| {
        let mut rays = 0;
        if tr.scene.fatal_error().is_some() {
            return;
        }
        let b = cy - cy0;
        let ry0 = (cy * ps).max(y0);
        let mut top = lines[b].lock().unwrap_or_else(|e| e.into_inner());
        let mut bottom = lines[b + 1].lock().unwrap_or_else(|e| e.into_inner());
        for line in [&mut *top, &mut *bottom] {
            if line.is_empty() {
                line.resize(line_len, None);
            }
        }
        let mut left = Vec::new();
        let mut scratch = CellScratch::default();
        for cx in cx0..cx1 {
            let mut edges = CellEdges {
                top: &mut top[cx * ps - lx0..],
                bottom: &mut bottom[cx * ps - lx0..],
                left: &mut left,
            };
            render_cell(
                tr,
                fs,
                (cx, cy, ps, full.contains(&(cx, cy))),
                &mut edges,
                &mut scratch,
                &mut rays,
                &mut |x, y, c| {
                    if x >= x0 && x < x1 && y >= ry0 && y < y1 {
                        if let Some(px) = rows.get_mut((y - ry0) * w + (x - x0)) {
                            *px = to_f32(c);
                        }
                    }
                },
            );
        }
        if b % 2 == 1 {
            // Both even neighbours of an odd band ran before it (super::schedule), so no
            // band reads its two lines again: they go (40 bytes a pixel of a line).
            *top = Vec::new();
            *bottom = Vec::new();
        }
        progress.rays.fetch_add(rays, Ordering::Relaxed);
        progress.rows_done.fetch_add(1, Ordering::Relaxed);
    };
    // The rows of each band: [max(cy*ps, y0), min((cy+1)*ps, y1)).
    let mut bands = Vec::with_capacity(cy1 - cy0);
    let mut rest = &mut out[..];
    for cy in cy0..cy1 {
        let n = (((cy + 1) * ps).min(y1) - (cy * ps).max(y0)) * w;
        let (rows, r) = std::mem::take(&mut rest).split_at_mut(n);
        rest = r;
        bands.push((cy, rows));
    }
    // Even bands before the odd bands between them (super::schedule).
    super::schedule::run_bands(bands, band);
    draw(&mut out);
    out
}

/// The frame's small light sources: the cells sampled at every pixel, and the sources drawn
/// by their coverage once a region's pixels are done ([`draw_sources`]).
pub(super) fn frame_sources(
    tr: &Tracer,
    fs: &FrameSetup,
    ps: usize,
) -> std::sync::Arc<super::lightcells::FrameSources> {
    match tr.cells {
        Some(memo) => memo.frame(tr, fs, ps),
        None => std::sync::Arc::new(super::lightcells::FrameSources::compute(tr, fs, ps)),
    }
}

/// Draw the frame's small light sources over the pixels `out` of `region` (x0, y0, x1, y1).
pub(super) fn draw_sources(
    tr: &Tracer,
    fs: &FrameSetup,
    src: &super::lightcells::FrameSources,
    region: (usize, usize, usize, usize),
    out: &mut [[f32; 3]],
    progress: &RenderProgress,
) {
    if !src.drawn.is_empty() && tr.scene.fatal_error().is_none() {
        let mut rays = 0;
        super::srcdraw::draw(tr, fs, &src.drawn, region, out, &mut rays);
        progress.rays.fetch_add(rays, Ordering::Relaxed);
    }
}

/// Buffers [`render_cell`] reuses from cell to cell.
#[derive(Default)]
pub(super) struct CellScratch {
    grid: Vec<Option<Sample>>,
    known: Vec<Option<Sample>>,
    values: Vec<Option<Color>>,
    stack: Vec<(usize, usize, usize, usize, bool)>,
}

/// Samples a cell shares with its neighbours: its top and bottom rows (starting at the cell's
/// left column, in the band lines shared with the bands above and below) and its left column
/// (the right column of the cell before it, which the cell replaces with its own).
pub(super) struct CellEdges<'a> {
    pub(super) top: &'a mut [Option<Sample>],
    pub(super) bottom: &'a mut [Option<Sample>],
    pub(super) left: &'a mut Vec<Option<Sample>>,
}

/// The side in pixels of the cells of the adaptive sampling grid for `-ps` (1: every pixel
/// is traced). A cell's corners and centre form a quincunx whose nearest samples lie
/// `side/√2` apart; the side is the number of the form 2^a·3^b (a ≥ 1) nearest `ps·√2`, so
/// that spacing is within 20% of `ps` (`-ps 2`: 1.41), the spacing of rpict's quincunx at the same `-ps`
/// (about the same density of first samples, one per `ps²` pixels), and every region a cell
/// splits into is split in two or three and has a centre pixel ([`split`]).
pub fn cell_size(ps: usize) -> usize {
    if ps <= 1 {
        return 1;
    }
    let want = ps as f64 * std::f64::consts::SQRT_2;
    let mut best = 2;
    let mut a = 2;
    while a as f64 <= 2.0 * want {
        let mut n = a;
        while n as f64 <= 2.0 * want {
            if (n as f64 - want).abs() < (best as f64 - want).abs() {
                best = n;
            }
            n *= 3;
        }
        a *= 2;
    }
    best
}

/// The parts a region `[a, b]` of the sampling grid splits into (sharing their end points).
/// An even span `n` splits into `k` equal parts of even span, `k` the smallest prime factor
/// of `n/2` (a span of 2 into single pixels), so every part again has a centre pixel; an odd
/// span (at the picture's border) splits in two about its middle; a span of 0 or 1 stays.
fn split(a: usize, b: usize) -> impl Iterator<Item = (usize, usize)> {
    let n = b - a;
    let k = if n <= 1 {
        1
    } else if n % 2 == 1 || n == 2 {
        2
    } else {
        let m = n / 2;
        (2..=m).find(|d| m.is_multiple_of(*d)).unwrap_or(m)
    };
    let cut = move |i: usize| {
        if n % 2 == 1 && k == 2 && i == 1 {
            (a + b) / 2
        } else {
            a + n * i / k
        }
    };
    (0..k).map(move |i| (cut(i), cut(i + 1)))
}

/// The rows `[y0, y1)` of the overture's global grid of step `fs.overture` (none at 0).
pub(super) fn overture_rows(fs: &FrameSetup, y0: usize, y1: usize) -> Vec<usize> {
    match fs.overture {
        0 => Vec::new(),
        step => (y0.div_ceil(step) * step..y1).step_by(step).collect(),
    }
}

/// The overture pass of [`render_region`] (see [`FrameSetup::overture`]): samples the pixels
/// of the grid rows `rows` between columns `x0` and `x1` and discards their colours; the
/// ambient values they make stay in the cache. Each row counts in `progress`.
pub(super) fn overture(
    tr: &Tracer,
    fs: &FrameSetup,
    x0: usize,
    x1: usize,
    rows: &[usize],
    progress: &RenderProgress,
) {
    let step = fs.overture;
    if rows.is_empty() {
        return;
    }
    // Eye paths skip direct light (or, for the share reach, estimate it roughly): only the
    // ambient values this pass makes are kept.
    let tr = &Tracer {
        fill_only: true,
        ..*tr
    };
    // Runs of the grid's points in reading order, spread over the threads by rayon as the
    // pixels of a `-ps 1` region are (super::schedule).
    let xs: Vec<usize> = (x0.div_ceil(step) * step..x1).step_by(step).collect();
    if xs.is_empty() {
        progress.rows_done.fetch_add(rows.len(), Ordering::Relaxed);
        return;
    }
    let nx = xs.len();
    let n = rows.len() * nx;
    let run = super::schedule::RUN;
    (0..n.div_ceil(run))
        .into_par_iter()
        .with_max_len(1)
        .for_each(|k| {
            let (at, end) = (k * run, ((k + 1) * run).min(n));
            let mut rays = 0;
            for p in at..end {
                sample_pixel(tr, fs, xs[p % nx], rows[p / nx], &mut rays);
            }
            progress.rays.fetch_add(rays, Ordering::Relaxed);
            // The rows whose last point this run sampled.
            progress
                .rows_done
                .fetch_add(end / nx - at / nx, Ordering::Relaxed);
        });
}

pub(super) fn to_f32(c: Color) -> [f32; 3] {
    // Finite and non-negative, and within f32's range: a radiance beyond it (a light of
    // 1e308) would otherwise become an infinite pixel.
    let c = sanitize(c).min(Color::splat(f32::MAX as f64));
    [c.x as f32, c.y as f32, c.z as f32]
}

/// Adaptive sampling of one grid cell; emits each pixel the cell owns exactly once.
pub(super) fn render_cell(
    tr: &Tracer,
    fs: &FrameSetup,
    (cx, cy, ps, full): (usize, usize, usize, bool),
    edges: &mut CellEdges,
    scratch: &mut CellScratch,
    rays: &mut u64,
    emit: &mut dyn FnMut(usize, usize, Color),
) {
    let xa = cx * ps;
    let ya = cy * ps;
    if xa >= fs.xres || ya >= fs.yres {
        return;
    }
    // Owned pixels: [xa, xe) × [ya, ye); corner samples at xa/xb and ya/yb.
    let xe = (xa + ps).min(fs.xres);
    let ye = (ya + ps).min(fs.yres);
    let xb = (xa + ps).min(fs.xres - 1);
    let yb = (ya + ps).min(fs.yres - 1);
    let gw = xb - xa + 1;
    let gh = yb - ya + 1;
    // `grid`: the samples this cell asked for (they alone decide its pixels, so a pixel never
    // depends on which neighbours were rendered with it); `known`: those and the ones its
    // neighbours traced on the shared borders, taken instead of tracing again.
    let CellScratch {
        grid,
        known,
        values,
        stack,
    } = scratch;
    for v in [&mut *grid, &mut *known] {
        v.clear();
        v.resize(gw * gh, None);
    }
    values.clear();
    values.resize(gw * gh, None);
    known[..gw].copy_from_slice(&edges.top[..gw]);
    known[(gh - 1) * gw..].copy_from_slice(&edges.bottom[..gw]);
    if edges.left.len() == gh {
        for (y, s) in edges.left.iter().enumerate() {
            known[y * gw] = *s;
        }
    }
    let mut get = |x: usize, y: usize, grid: &mut [Option<Sample>], rays: &mut u64| -> Sample {
        let k = (y - ya) * gw + (x - xa);
        if let Some(s) = grid[k] {
            return s;
        }
        let s = match known[k] {
            Some(s) => s,
            None => sample_pixel(tr, fs, x, y, rays),
        };
        grid[k] = Some(s);
        known[k] = Some(s);
        s
    };
    // Recursive subdivision with an explicit stack. A region is interpolated bilinearly from
    // its corners when its centre sample agrees with that interpolation (within -pt); else it
    // is split ([`split`]). Smooth gradients are therefore interpolated and only edges,
    // shadows and highlights are refined. A region split because an edge crosses it (its
    // corners disagree among themselves) passes `probe = false` to its parts: a part whose
    // own corners agree lies beside the edge and is interpolated without a centre sample. A
    // region whose corners agree but whose centre does not holds something smaller than
    // itself (a thin light, a highlight): all its parts are probed. A `full` cell (a small
    // light source appears in it: [`super::lightcells`]) is split down to its pixels.
    stack.clear();
    stack.push((xa, xb, ya, yb, true));
    while let Some((x0, x1, y0, y1, probe)) = stack.pop() {
        let c00 = get(x0, y0, grid, rays);
        let c10 = get(x1, y0, grid, rays);
        let c01 = get(x0, y1, grid, rays);
        let c11 = get(x1, y1, grid, rays);
        let small = x1 - x0 <= 1 && y1 - y0 <= 1;
        let xm = (x0 + x1) / 2;
        let ym = (y0 + y1) / 2;
        let bilinear = |x: usize, y: usize| -> Color {
            let fx = if x1 > x0 {
                (x - x0) as f64 / (x1 - x0) as f64
            } else {
                0.0
            };
            let fy = if y1 > y0 {
                (y - y0) as f64 / (y1 - y0) as f64
            } else {
                0.0
            };
            c00.color * ((1.0 - fx) * (1.0 - fy))
                + c10.color * (fx * (1.0 - fy))
                + c01.color * ((1.0 - fx) * fy)
                + c11.color * (fx * fy)
        };
        let corners = [c00, c10, c01, c11];
        let agree = (0..4).all(|i| (i + 1..4).all(|j| !bigdiff(&corners[i], &corners[j], fs.pt)));
        let refine = !small
            && (full
                || (probe || !agree) && {
                    let centre = get(xm, ym, grid, rays);
                    let predicted = Sample {
                        color: bilinear(xm, ym),
                        dist: if corners.iter().all(|c| c.dist.is_finite()) {
                            centre.dist
                        } else {
                            f64::INFINITY
                        },
                    };
                    bigdiff(&centre, &predicted, fs.pt)
                });
        if !refine {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let k = (y - ya) * gw + (x - xa);
                    if values[k].is_none() {
                        values[k] = Some(match grid[k] {
                            Some(s) => s.color,
                            None => bilinear(x, y),
                        });
                    }
                }
            }
            continue;
        }
        for (a, b) in split(x0, x1) {
            for (c, d) in split(y0, y1) {
                stack.push((a, b, c, d, agree));
            }
        }
    }
    edges.top[..gw].copy_from_slice(&known[..gw]);
    edges.bottom[..gw].copy_from_slice(&known[(gh - 1) * gw..]);
    edges.left.clear();
    edges.left.extend((0..gh).map(|y| known[y * gw + gw - 1]));
    // Sampled pixels keep their own sample; the others take the first interpolation that
    // reached them (the stack order is fixed, so this is deterministic).
    for y in ya..ye {
        for x in xa..xe {
            let k = (y - ya) * gw + (x - xa);
            let c = match grid[k] {
                Some(s) => s.color,
                None => values[k].unwrap_or(Color::ZERO),
            };
            emit(x, y, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_keep_rpicts_sample_spacing() {
        let sides: Vec<usize> = (1..=16).map(cell_size).collect();
        assert_eq!(
            sides,
            [1, 2, 4, 6, 8, 8, 8, 12, 12, 16, 16, 16, 18, 18, 24, 24]
        );
        for ps in 2..=16 {
            // Quincunx spacing side/√2 within 20% of -ps (-ps 2: 1.41, the nearest).
            let spacing = cell_size(ps) as f64 / std::f64::consts::SQRT_2;
            let off = (spacing / ps as f64 - 1.0).abs();
            assert!(off <= if ps == 2 { 0.3 } else { 0.2 }, "ps {ps}: {spacing}");
            // Regions split in two or three parts down to single pixels.
            let mut n = cell_size(ps);
            while n > 1 {
                let parts = split(0, n).count();
                assert!(parts == 2 || parts == 3, "ps {ps}: {n} into {parts}");
                n /= parts;
            }
        }
    }

    #[test]
    fn splits_tile_the_region_and_keep_centre_pixels() {
        for a in [0usize, 5, 12] {
            for n in 0..=40 {
                let parts: Vec<_> = split(a, a + n).collect();
                assert_eq!(parts.first().unwrap().0, a);
                assert_eq!(parts.last().unwrap().1, a + n);
                assert!(parts.windows(2).all(|w| w[0].1 == w[1].0), "{n}: {parts:?}");
                if n >= 2 {
                    assert!(parts.len() >= 2, "{n}: {parts:?}");
                }
                if n % 2 == 0 && n > 2 {
                    // Even parts: each has a centre pixel.
                    assert!(parts.iter().all(|p| (p.1 - p.0) % 2 == 0), "{n}: {parts:?}");
                }
            }
        }
        assert_eq!(split(0, 6).collect::<Vec<_>>(), [(0, 2), (2, 4), (4, 6)]);
        assert_eq!(split(0, 3).collect::<Vec<_>>(), [(0, 1), (1, 3)]);
        assert_eq!(split(0, 2).collect::<Vec<_>>(), [(0, 1), (1, 2)]);
    }
}
