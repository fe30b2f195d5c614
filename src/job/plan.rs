//! The tile plan of a frame: rectangles that cover the picture exactly, ordered largest
//! first and shrinking toward the end, so that the last tiles handed out are small and the
//! workers finish together (Koholka et al.'s and the seed paper's answer to idle time at the
//! end of a frame).
//!
//! The picture is cut, top to bottom, into four bands holding 1/2, 1/4, 1/8 and 1/8 of its
//! rows. Tiles in band k have about `2^(1-k)·b` pixels (b = 1.25·area / tiles, so that the
//! plan has about `tiles` tiles in all): band 0 holds a quarter of the tiles at twice the mean
//! size, band 3 half of them at a quarter of b. Inside a band, tiles are as square as the
//! row count allows; widths differ by at most one pixel. Tile boundaries never change
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
        self.w * self.h
    }
}

/// Default number of tiles per expected worker (Radiance's own notes measured 16% idle time
/// with 5 tiles per CPU).
pub const TILES_PER_WORKER: usize = 20;

/// Plan about `tiles` tiles (at least one) over a `width × height` picture, largest first.
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
    let shares = [0.5, 0.25, 0.125, 0.125];
    let mut bounds = [0usize; 5];
    let mut acc = 0.0;
    for (k, s) in shares.iter().enumerate() {
        acc += s;
        bounds[k + 1] = ((acc * height as f64).round() as usize).min(height);
    }
    bounds[4] = height;
    let mut out = Vec::new();
    for k in 0..4 {
        let (r0, r1) = (bounds[k], bounds[k + 1]);
        if r1 <= r0 {
            continue;
        }
        let tile_area = base * 0.5f64.powi(k as i32 - 1);
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
    }
    out
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

/// Check that `tiles` cover the `width × height` picture exactly once; the error names the
/// first problem.
pub fn check_cover(width: usize, height: usize, tiles: &[TileRect]) -> Result<(), String> {
    let total: usize = tiles.iter().map(|t| t.area()).sum();
    if total != width * height {
        return Err(format!(
            "tiles cover {total} pixels, the picture has {}",
            width * height
        ));
    }
    // Equal areas with no overlap imply an exact cover; overlap is checked row span by row
    // span on a coverage bitmap.
    let mut seen = vec![false; width * height];
    for (i, t) in tiles.iter().enumerate() {
        if t.w == 0 || t.h == 0 || t.x0 + t.w > width || t.y0 + t.h > height {
            return Err(format!(
                "tile {i} ({}x{} at {},{}) is empty or outside the {width}x{height} picture",
                t.w, t.h, t.x0, t.y0
            ));
        }
        for y in t.y0..t.y0 + t.h {
            for s in &mut seen[y * width + t.x0..y * width + t.x0 + t.w] {
                if *s {
                    return Err(format!("tile {i} overlaps another tile at row {y}"));
                }
                *s = true;
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
        assert!((60..=110).contains(&p.len()), "{} tiles", p.len());
        let first = p[0].area() as f64;
        let last = p[p.len() - 1].area() as f64;
        assert!(first / last > 4.0, "{first} vs {last}");
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
