//! Previews of an animation (docs/animation.md): a contact sheet of every frame in one PNG,
//! and a temporal exposure, the exposure of each frame's PNG following a smoothed average
//! over the neighbouring frames, so that a walkthrough's previews do not pump with every
//! frame's own average.

use crate::image::png::{auto_exposure, write_png_with};
use crate::image::Image;
use anyhow::Result;
use std::path::Path;

/// Frames on each side averaged by the temporal exposure.
pub const EXPOSURE_RADIUS: usize = 3;

/// Each frame's exposure multiplier smoothed over ±`radius` frames (geometric mean).
pub fn smoothed_exposures(frames: &[Image], radius: usize) -> Vec<f64> {
    let logs: Vec<f64> = frames.iter().map(|f| auto_exposure(f).ln()).collect();
    (0..logs.len())
        .map(|i| {
            let lo = i.saturating_sub(radius);
            let hi = (i + radius + 1).min(logs.len());
            (logs[lo..hi].iter().sum::<f64>() / (hi - lo) as f64).exp()
        })
        .collect()
}

/// `img` reduced by box filtering to `width` pixels across (aspect kept), at least 1×1.
pub fn thumbnail(img: &Image, width: usize) -> Image {
    let w = width.clamp(1, img.width.max(1));
    let h = ((img.height * w) as f64 / img.width.max(1) as f64)
        .round()
        .max(1.0) as usize;
    let mut t = Image::new(w, h);
    for y in 0..h {
        let (y0, y1) = (
            y * img.height / h,
            ((y + 1) * img.height / h).max(y * img.height / h + 1),
        );
        for x in 0..w {
            let (x0, x1) = (
                x * img.width / w,
                ((x + 1) * img.width / w).max(x * img.width / w + 1),
            );
            let mut sum = [0f64; 3];
            let mut n = 0.0f64;
            for yy in y0..y1.min(img.height) {
                for xx in x0..x1.min(img.width) {
                    let p = img.pixels[yy * img.width + xx];
                    for c in 0..3 {
                        sum[c] += if p[c].is_finite() { p[c] as f64 } else { 0.0 };
                    }
                    n += 1.0;
                }
            }
            t.pixels[y * w + x] = sum.map(|s| (s / n.max(1.0)) as f32);
        }
    }
    t
}

/// Write a contact sheet: every frame as a thumbnail `width` pixels across, in reading
/// order on a grid of about square proportions, each with its temporal exposure.
pub fn write_contact_sheet(path: &Path, frames: &[Image], width: usize) -> Result<()> {
    anyhow::ensure!(!frames.is_empty(), "no frames for a contact sheet");
    let ks = smoothed_exposures(frames, EXPOSURE_RADIUS);
    let thumbs: Vec<Image> = frames.iter().map(|f| thumbnail(f, width)).collect();
    let (tw, th) = (
        thumbs.iter().map(|t| t.width).max().unwrap_or(1),
        thumbs.iter().map(|t| t.height).max().unwrap_or(1),
    );
    let cols = (thumbs.len() as f64).sqrt().ceil() as usize;
    let rows = thumbs.len().div_ceil(cols);
    let gap = 2;
    let mut sheet = Image::new(cols * (tw + gap) - gap, rows * (th + gap) - gap);
    // Every thumbnail is scaled to its own smoothed exposure, then the sheet is written
    // with exposure 1.
    for (i, t) in thumbs.iter().enumerate() {
        let (ox, oy) = ((i % cols) * (tw + gap), (i / cols) * (th + gap));
        for y in 0..t.height {
            for x in 0..t.width {
                let p = t.pixels[y * t.width + x];
                sheet.pixels[(oy + y) * sheet.width + ox + x] = p.map(|c| c * ks[i] as f32);
            }
        }
    }
    write_png_with(path, &sheet, 1.0)?;
    Ok(())
}
