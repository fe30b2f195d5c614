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
//! row count allows; widths differ by at most one pixel. Within a band the tiles are handed
//! out in farthest-point order (each next tile is the one farthest from every tile handed out
//! before it), so tiles rendered at the same time by different workers are far apart and a
//! tile's neighbours are usually rendered after it is finished and its ambient values are
//! shared — fewer values are computed twice. Tile boundaries never change
//! pixels (every pixel is seeded by its position alone), so the plan is free to be any
//! rectangles.

use serde::{Deserialize, Serialize};

/// One tile: the pixel rectangle `[x0, x0+w) × [y0, y0+h)`, y counted from the top row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
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

/// Default `tiles` per expected worker (the plan then has about 1.4 × 80 tiles per worker,
/// fewer where the 64-pixel floor applies). Radiance's own notes measured 16% idle time with
/// 5 tiles per CPU; replaying the tile costs of a 16-worker `-ab 2` job of the demo scene
/// (whose mirror and glass make a few tiles cost 20× the mean), `bench/tilesim` gives 83%
/// efficiency at 16 workers with 40 and 99% with 80 (docs/benchmarks.md).
pub const TILES_PER_WORKER: usize = 80;

/// Smallest planned tile area in pixels (tiny tiles cost more to claim and write than to
/// render).
pub const MIN_TILE_AREA: f64 = 64.0;

/// Plan about 1.4 × `tiles` tiles (at least one) over a `width × height` picture, largest first.
pub fn plan_tiles(width: usize, height: usize, tiles: usize) -> Vec<TileRect> {
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let tiles = tiles.max(1);
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
    // Row shares of the four bands, rounded so that they add up to `height`.
    let shares = [0.5, 0.25, 0.125, 0.0625, 0.03125, 0.03125];
    let mut bounds = [0usize; 7];
    let mut acc = 0.0;
    for (k, s) in shares.iter().enumerate() {
        acc += s;
        bounds[k + 1] = ((acc * height as f64).round() as usize).min(height);
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
        for b in 0..nbands {
            let y0 = r0 + rows * b / nbands;
            let y1 = r0 + rows * (b + 1) / nbands;
            let h = y1 - y0;
            let ncols = ((width * h) as f64 / tile_area).round() as usize;
            let ncols = ncols.clamp(1, width);
            for c in 0..ncols {
                let x0 = width * c / ncols;
                let x1 = width * (c + 1) / ncols;
                out.push(TileRect {
                    x0,
                    y0,
                    w: x1 - x0,
                    h,
                });
            }
        }
        spread(&mut out[band_start..]);
    }
    out
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
            for p in y * width + t.x0..y * width + t.x0 + t.w {
                let (word, bit) = (p / 64, 1u64 << (p % 64));
                if seen[word] & bit != 0 {
                    return Err(format!("tile {i} overlaps another tile at row {y}"));
                }
                seen[word] |= bit;
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
            let p = plan_tiles(w, h, n);
            check_cover(w, h, &p).unwrap();
            assert!(p.first().unwrap().area() >= p.last().unwrap().area());
        }
        let p = plan_tiles(640, 480, 80);
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
        p.pop();
        assert!(check_cover(10, 10, &p).is_err());
    }
}
