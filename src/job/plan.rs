//! The tile plan of a frame: rectangles that cover the picture exactly, ordered largest
//! first and shrinking toward the end, so that the last tiles handed out are small and the
//! workers finish together (Koholka et al.'s and the seed paper's answer to idle time at the
//! end of a frame).
//!
//! The picture is cut, top to bottom, into six bands holding 1/2, 1/4, 1/8, 1/16, 1/32 and
//! 1/32 of its rows. Tiles in band k have about `2^(1-k)·b` pixels (b = 1.25·area / tiles, at
//! least 64 pixels), so each of the first five bands holds a fifth of `tiles` and the last
//! 2/5: about 1.4 × `tiles` in all, the last ones a sixteenth of b. (`bench/tilesim`, replaying
//! a 10× hot spot in the corner handed out last, measured 98% simulated efficiency at 16 and
//! 64 workers with these bands against 94% and 92% with four bands of 1/2, 1/4, 1/8, 1/8;
//! see docs/benchmarks.md.) Inside a band, tiles are as square as the
//! row count allows. Within a band the tiles are handed
//! out in farthest-point order (each next tile is the one farthest from every tile handed out
//! before it), so tiles rendered at the same time by different workers are far apart and a
//! tile's neighbours are usually rendered after it is finished and its ambient values are
//! shared — fewer values are computed twice.
//!
//! Every tile edge inside the picture lies on the sampling grid (a multiple of the cell side,
//! [`crate::render::cell_size`] of `-ps`): adaptive image sampling works on cells of that grid
//! fixed by the full picture, and a tile renders every cell it touches, so a tile edge through
//! a cell would trace that cell in both tiles. On the grid each cell is traced by one tile;
//! only the samples on an edge between two tiles are traced by both. (Pixels never depend on
//! the tiling: every pixel is seeded by its position alone.)
//!
//! The default tile count ([`tiles_for_cost`]) balances a worker's share of the per-tile
//! overhead (claiming, writing and syncing the result: [`TILE_OVERHEAD`]) against the tail
//! of the frame ([`TAIL`]), for the frame's cost as the cost probe estimates it
//! (`super::probe`); tiles split while they render (`super::split`) shorten the tail further.

use serde::{Deserialize, Serialize};

/// One tile: the pixel rectangle `[x0, x0+w) × [y0, y0+h)`, y counted from the top row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct TileRect {
    /// Left column.
    pub x0: usize,
    /// Top row.
    pub y0: usize,
    /// Width in pixels.
    pub w: usize,
    /// Height in pixels.
    pub h: usize,
}

impl TileRect {
    /// Number of pixels.
    pub fn area(&self) -> usize {
        self.w.saturating_mul(self.h)
    }
}

/// Most `tiles` per expected worker (the plan then has about 1.4 × 80 tiles per worker,
/// fewer where tiles would cost too little: [`default_tiles`]). Radiance's own notes
/// measured 16% idle time with 5 tiles per CPU; replaying the tile costs of a 16-worker
/// `-ab 2` job of the demo scene (whose mirror and glass make a few tiles cost 20× the mean),
/// `bench/tilesim` gives 83% efficiency at 16 workers with 20 and 99% with 40 or 80
/// (docs/benchmarks.md).
pub const TILES_PER_WORKER: usize = 80;

/// CPU seconds a worker spends on a tile besides rendering it: claiming it, writing,
/// fsyncing and renaming its result, marking it done (`bench/jobcost.sh`: 32×32 tiles
/// against one tile at `-ab 0`, docs/benchmarks.md "Job cost").
pub const TILE_OVERHEAD: f64 = 0.8e-3;

/// A lower bound of the CPU seconds one pixel costs at `-ab` `ab`, from the cheapest
/// benchmark scene (`tests/scenes/daffodil` at `-ps 4`, rpict's defaults otherwise: 0.75,
/// 1.6 and 7.6 µs at `-ab` 0, 1 and 2; docs/benchmarks.md "Job cost"). Scenes cost more
/// per pixel, never much less, so tiles planned with it cost at least what the 2% rule
/// needs.
pub fn pixel_cost_floor(ab: i32) -> f64 {
    match ab {
        ..=0 => 0.75e-6,
        1 => 1.5e-6,
        _ => 7.5e-6,
    }
}

/// The default `tiles` for a `width × height` frame and `workers` expected workers, when a
/// pixel costs `pixel_cost` CPU seconds: [`tiles_for_cost`] with the frame's cost and
/// [`TILE_OVERHEAD`].
pub fn default_tiles(width: usize, height: usize, workers: usize, pixel_cost: f64) -> usize {
    let frame = (width * height) as f64 * pixel_cost;
    tiles_for_cost(width * height, workers, frame, TILE_OVERHEAD)
}

/// Tiles per tile loop of the default plan for workers of two or more loops that may split
/// tiles ([`tiles_for_loops`]).
pub const TILES_PER_LOOP: usize = 3;

/// The default `tiles` for `workers` tile loops in all, run by workers of `threads` loops
/// each that split tiles while they render ([`super::split`], [`super::siblings`]):
/// [`TILES_PER_LOOP`] per loop, whatever the frame costs, kept within a sixteenth of the
/// area as in [`tiles_for_tail`]. A worker's loops share the end of a tile at once (a loop
/// that waits gets half of a sibling's rest within milliseconds), so the tail that more
/// tiles would shorten is short already and each further tile costs its overhead: replayed
/// by `bench/tilesim --sweep --loops 16 --ps 1` on four cost maps over frames of 0.1–1000
/// CPU-s on 2–64 loops, three a loop came within 5% of the best tile count in 176 of the 192
/// cases (worst 1.17×) where the cost rule of [`tiles_for_cost`] did in 103 (worst 1.26×;
/// docs/benchmarks.md, "Scaling and the default plan"). `None` for single-thread workers
/// (`threads` < 2), which balance only through other processes' polls and want the cost
/// rule.
pub fn tiles_for_loops(area: usize, workers: usize, threads: usize) -> Option<usize> {
    (threads >= 2).then(|| most_tiles(area, workers, TILES_PER_LOOP))
}

/// `per_worker` tiles for each of `workers`, kept within a sixteenth of the `area` (the
/// plan's bands keep tiles of at least [`MIN_TILE_AREA`] pixels) and at least one.
fn most_tiles(area: usize, workers: usize, per_worker: usize) -> usize {
    per_worker
        .saturating_mul(workers.max(1))
        .min((area / 16).max(1))
}

/// The tail of a frame, the time the last worker still renders after the others are done,
/// modelled as `TAIL · P · cost / tiles`: P times a mean tile's cost, scaled. With more
/// workers the end waits for the slowest of more last tiles, and a tile's cost varies with
/// what it sees (mirrors, glass, the cache's warm-up: 20× the mean in the demo at `-ab 2`).
/// Fitted by `bench/tilesim --sweep` on four measured and synthetic cost maps
/// (docs/benchmarks.md, "Scaling and the default plan").
pub const TAIL: f64 = 0.35;

/// `tiles` for a frame of `area` pixels costing `frame_cost` CPU seconds, `workers` expected
/// workers and `overhead` seconds per tile: the count that minimises a worker's modelled
/// wall time `cost/P + overhead · 1.4 · tiles / P + TAIL · P · cost / tiles` (its share of
/// the work and of the plan's tile overhead, and the tail), that is
/// `P · sqrt(TAIL · cost / (1.4 · overhead))` tiles: a number of tiles per worker that grows
/// as the square root of the frame's cost. Kept within 1, [`TILES_PER_WORKER`] × `workers`
/// and a sixteenth of the area (the plan's bands keep tiles of at least [`MIN_TILE_AREA`]
/// pixels, so asking for more only makes every band's tiles the smallest). Cheap frames get
/// few tiles (a tile's overhead would cost more than the balance gains), expensive frames
/// many.
pub fn tiles_for_cost(area: usize, workers: usize, frame_cost: f64, overhead: f64) -> usize {
    tiles_for_tail(area, workers, frame_cost, overhead, TAIL)
}

/// [`tiles_for_cost`] with another tail factor than [`TAIL`] (for `tilesim --sweep --tail`).
pub fn tiles_for_tail(
    area: usize,
    workers: usize,
    frame_cost: f64,
    overhead: f64,
    tail: f64,
) -> usize {
    let workers = workers.max(1);
    let most = most_tiles(area, workers, TILES_PER_WORKER);
    let best = workers as f64 * (tail * frame_cost / (PLANNED_PER_TILE * overhead)).sqrt();
    if !best.is_finite() || area == 0 {
        return most;
    }
    (best.round() as usize).clamp(1, most)
}

/// Tiles [`plan_tiles`] makes per requested tile (where the 64-pixel floor does not apply).
pub const PLANNED_PER_TILE: f64 = 1.4;

/// Smallest planned tile area in pixels (tiny tiles cost more to claim and write than to
/// render).
pub const MIN_TILE_AREA: f64 = 64.0;

/// Cut points `0 = c_0 < c_1 < ... < c_n = len` near `len·i/n`, each on a multiple of
/// `grid` (the ends are exact); cuts that would meet are merged, so there may be fewer than
/// `n` parts.
fn cuts(len: usize, n: usize, grid: usize) -> Vec<usize> {
    let grid = grid.max(1);
    let mut out = vec![0];
    for i in 1..n {
        let exact = len * i / n;
        let snapped = ((exact + grid / 2) / grid * grid).min(len);
        if snapped > *out.last().unwrap_or(&0) && snapped < len {
            out.push(snapped);
        }
    }
    out.push(len);
    out
}

/// Plan about 1.4 × `tiles` tiles (at least one) over a `width × height` picture, largest
/// first, every edge inside the picture on the `grid` (`-ps`) lines.
pub fn plan_tiles(width: usize, height: usize, tiles: usize, grid: usize) -> Vec<TileRect> {
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let tiles = tiles.max(1);
    let grid = grid.max(1);
    let area = (width * height) as f64;
    if tiles == 1 {
        return vec![TileRect {
            x0: 0,
            y0: 0,
            w: width,
            h: height,
        }];
    }
    let base = 1.25 * area / tiles as f64;
    // Row shares of the six bands, on the grid, adding up to `height`.
    let shares = [0.5, 0.25, 0.125, 0.0625, 0.03125, 0.03125];
    let mut bounds = [0usize; 7];
    let mut acc = 0.0;
    for (k, s) in shares.iter().enumerate() {
        acc += s;
        let exact = (acc * height as f64).round() as usize;
        bounds[k + 1] = ((exact + grid / 2) / grid * grid).clamp(bounds[k], height);
    }
    bounds[6] = height;
    let mut out = Vec::new();
    for k in 0..6 {
        let band_start = out.len();
        let (r0, r1) = (bounds[k], bounds[k + 1]);
        if r1 <= r0 {
            continue;
        }
        let tile_area = (base * 0.5f64.powi(k as i32 - 1)).max(MIN_TILE_AREA);
        let side = tile_area.sqrt().max(1.0);
        let rows = r1 - r0;
        let nbands = ((rows as f64 / side).round() as usize).clamp(1, rows);
        let ys = cuts(rows, nbands, grid);
        for yw in ys.windows(2) {
            let (y0, h) = (r0 + yw[0], yw[1] - yw[0]);
            let ncols = ((width * h) as f64 / tile_area).round() as usize;
            let xs = cuts(width, ncols.clamp(1, width), grid);
            for xw in xs.windows(2) {
                out.push(TileRect {
                    x0: xw[0],
                    y0,
                    w: xw[1] - xw[0],
                    h,
                });
            }
        }
        spread(&mut out[band_start..]);
    }
    out
}

/// Whether every tile edge inside the `width × height` picture lies on a multiple of `grid`.
pub fn on_grid(width: usize, height: usize, tiles: &[TileRect], grid: usize) -> bool {
    let grid = grid.max(1);
    let ok = |v: usize, end: usize| v.is_multiple_of(grid) || v == end;
    tiles.iter().all(|t| {
        ok(t.x0, width) && ok(t.x0 + t.w, width) && ok(t.y0, height) && ok(t.y0 + t.h, height)
    })
}

/// Reorder tiles in farthest-point order, starting from the first.
fn spread(tiles: &mut [TileRect]) {
    let n = tiles.len();
    if n < 3 {
        return;
    }
    let c: Vec<(f64, f64)> = tiles
        .iter()
        .map(|t| {
            (
                t.x0 as f64 + 0.5 * t.w as f64,
                t.y0 as f64 + 0.5 * t.h as f64,
            )
        })
        .collect();
    let d2 = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2);
    let mut order = Vec::with_capacity(n);
    let mut taken = vec![false; n];
    let mut mind = vec![f64::INFINITY; n];
    let mut cur = 0;
    for _ in 0..n {
        taken[cur] = true;
        order.push(cur);
        let mut best = None;
        let mut best_d = -1.0;
        for i in 0..n {
            if taken[i] {
                continue;
            }
            mind[i] = mind[i].min(d2(c[i], c[cur]));
            if mind[i] > best_d {
                best_d = mind[i];
                best = Some(i);
            }
        }
        match best {
            Some(b) => cur = b,
            None => break,
        }
    }
    let copy: Vec<TileRect> = order.iter().map(|&i| tiles[i]).collect();
    tiles.copy_from_slice(&copy);
}

/// Plan tiles of a fixed size `tw × th` (the last row and column take what is left), in
/// reading order.
pub fn plan_fixed(width: usize, height: usize, tw: usize, th: usize) -> Vec<TileRect> {
    let (tw, th) = (tw.max(1), th.max(1));
    let mut out = Vec::new();
    let mut y0 = 0;
    while y0 < height {
        let h = th.min(height - y0);
        let mut x0 = 0;
        while x0 < width {
            let w = tw.min(width - x0);
            out.push(TileRect { x0, y0, w, h });
            x0 += w;
        }
        y0 += h;
    }
    out
}

/// Most pixels in a planned frame (16384 × 16384).
pub const MAX_PIXELS: usize = 1 << 28;

/// Check that `tiles` cover the `width × height` picture exactly once; the error names the
/// first problem.
pub fn check_cover(width: usize, height: usize, tiles: &[TileRect]) -> Result<(), String> {
    if width.checked_mul(height).is_none_or(|a| a > MAX_PIXELS) {
        return Err(format!("{width}x{height} pixels is more than {MAX_PIXELS}"));
    }
    let total = tiles.iter().fold(0usize, |a, t| a.saturating_add(t.area()));
    if total != width * height {
        return Err(format!(
            "tiles cover {total} pixels, the picture has {}",
            width * height
        ));
    }
    // Equal areas with no overlap imply an exact cover; overlap is checked on a coverage
    // bitmap (one bit per pixel).
    let mut seen = vec![0u64; (width * height).div_ceil(64)];
    for (i, t) in tiles.iter().enumerate() {
        if t.w == 0
            || t.h == 0
            || t.x0.saturating_add(t.w) > width
            || t.y0.saturating_add(t.h) > height
        {
            return Err(format!(
                "tile {i} ({}x{} at {},{}) is empty or outside the {width}x{height} picture",
                t.w, t.h, t.x0, t.y0
            ));
        }
        for y in t.y0..t.y0 + t.h {
            // The row's bits [p, end), a word at a time (every tool validates the plan at
            // start: a bit at a time cost a millisecond per megapixel).
            let (mut p, end) = (y * width + t.x0, y * width + t.x0 + t.w);
            while p < end {
                let (word, lo) = (p / 64, p % 64);
                let n = (64 - lo).min(end - p);
                let mask = if n == 64 {
                    u64::MAX
                } else {
                    ((1u64 << n) - 1) << lo
                };
                if seen[word] & mask != 0 {
                    return Err(format!("tile {i} overlaps another tile at row {y}"));
                }
                seen[word] |= mask;
                p += n;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plans_cover_exactly_and_shrink() {
        for &(w, h, n) in &[
            (640, 480, 80),
            (512, 512, 320),
            (17, 3, 40),
            (1, 1, 5),
            (1000, 7, 20),
            (7, 1000, 20),
            (160, 120, 80),
        ] {
            let p = plan_tiles(w, h, n, 1);
            check_cover(w, h, &p).unwrap();
            assert!(p.first().unwrap().area() >= p.last().unwrap().area());
        }
        let p = plan_tiles(640, 480, 80, 1);
        assert!((90..=135).contains(&p.len()), "{} tiles", p.len());
        let first = p[0].area() as f64;
        let last = p[p.len() - 1].area() as f64;
        assert!(first / last > 16.0, "{first} vs {last}");
        // Non-increasing by band.
        for w in p.windows(2) {
            assert!(w[1].area() as f64 <= w[0].area() as f64 * 1.6);
        }
    }

    #[test]
    fn plans_lie_on_the_sample_grid() {
        for &(w, h, n, g) in &[
            (1024, 1024, 1280, 4),
            (640, 440, 320, 4),
            (513, 257, 100, 4),
            (17, 3, 40, 4),
            (1000, 7, 20, 8),
            (7, 1000, 20, 3),
            (33, 33, 5000, 16),
            (1, 1, 5, 4),
        ] {
            let p = plan_tiles(w, h, n, g);
            check_cover(w, h, &p).unwrap();
            assert!(on_grid(w, h, &p, g), "{w}x{h} {n} tiles, grid {g}");
        }
        let p = plan_tiles(1024, 1024, 1280, 4);
        assert!(p.len() > 1200, "{} tiles", p.len());
        assert!(!on_grid(1024, 1024, &plan_fixed(1024, 1024, 30, 30), 4));
    }

    #[test]
    fn default_tile_counts_minimise_the_modelled_wall_time() {
        // Few tiles for a cheap frame, more for an expensive one, more for more workers.
        let cheap = default_tiles(1024, 1024, 16, pixel_cost_floor(0));
        let dear = default_tiles(1024, 1024, 16, 50e-6);
        // 0.79 CPU-s over 16 workers: about 16 tiles each.
        assert!((16..=400).contains(&cheap), "{cheap}");
        assert!(dear > 4 * cheap, "{dear} vs {cheap}");
        assert!(default_tiles(1024, 1024, 64, 50e-6) > dear);
        // A frame of 21 CPU-s or more: the most per worker.
        assert_eq!(default_tiles(1024, 1024, 16, 1e-3), 16 * TILES_PER_WORKER);
        assert_eq!(default_tiles(4, 4, 16, pixel_cost_floor(0)), 1);
        assert_eq!(default_tiles(4, 4, 16, f64::NAN), 1);
        assert_eq!(default_tiles(1, 1, 1, 0.0), 1);
        // The count is the model's optimum: within 1% of the best count's wall time.
        let wall = |n: f64, cost: f64, p: f64| {
            cost / p + TILE_OVERHEAD * PLANNED_PER_TILE * n / p + TAIL * p * cost / n
        };
        for (cost, p) in [
            (0.1, 2usize),
            (3.0, 16),
            (55.0, 16),
            (1000.0, 64),
            (0.1, 64),
        ] {
            let n = tiles_for_cost(1 << 20, p, cost, TILE_OVERHEAD) as f64;
            let best = (1..=TILES_PER_WORKER * p)
                .map(|k| wall(k as f64, cost, p as f64))
                .fold(f64::INFINITY, f64::min);
            assert!(
                wall(n, cost, p as f64) <= best * 1.01,
                "{cost} s, {p} workers: {n}"
            );
        }
    }

    #[test]
    fn workers_of_several_loops_get_a_few_tiles_a_loop() {
        assert_eq!(tiles_for_loops(1024 * 1024, 16, 1), None);
        assert_eq!(tiles_for_loops(1024 * 1024, 16, 0), None);
        assert_eq!(
            tiles_for_loops(1024 * 1024, 16, 2),
            Some(16 * TILES_PER_LOOP)
        );
        assert_eq!(
            tiles_for_loops(1024 * 1024, 64, 16),
            Some(64 * TILES_PER_LOOP)
        );
        // Never more than a sixteenth of the area, never none.
        assert_eq!(tiles_for_loops(32 * 32, 64, 16), Some(64));
        assert_eq!(tiles_for_loops(1, 4, 4), Some(1));
        assert_eq!(tiles_for_loops(1 << 20, 0, 4), Some(TILES_PER_LOOP));
    }

    #[test]
    fn fixed_plans_cover() {
        let p = plan_fixed(100, 37, 32, 16);
        check_cover(100, 37, &p).unwrap();
        assert_eq!(p.len(), 4 * 3);
    }

    #[test]
    fn bad_covers_are_named() {
        let mut p = plan_fixed(10, 10, 5, 5);
        p[1].x0 = 0;
        assert!(check_cover(10, 10, &p).unwrap_err().contains("overlap"));
        // Overlaps of one pixel are found anywhere in a word, also across word boundaries.
        for (w, x) in [(200, 63), (200, 64), (200, 0), (200, 127), (70, 69)] {
            let mut p = plan_fixed(w, 3, w, 1);
            p[1] = TileRect {
                x0: 0,
                y0: 1,
                w: x,
                h: 1,
            };
            p.push(TileRect {
                x0: x,
                y0: 1,
                w: w - x,
                h: 1,
            });
            if x > 0 {
                check_cover(w, 3, &p).unwrap();
                p[1].w += 1;
                p[2].w -= 1; // row 2 gives the pixel back: equal areas
                assert!(
                    check_cover(w, 3, &p).unwrap_err().contains("overlap"),
                    "{w} {x}"
                );
            }
        }
        check_cover(1023, 517, &plan_tiles(1023, 517, 300, 4)).unwrap();
        p.pop();
        assert!(check_cover(10, 10, &p).is_err());
    }
}
