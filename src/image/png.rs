//! 8-bit PNG previews of a picture.
//!
//! # Tone mapping
//! A fixed, documented operator (global, linear exposure with clipping):
//!
//! 1. Luminance of each pixel `L = 0.265074·R + 0.670114·G + 0.064811·B` (Radiance's `bright()`
//!    weights). Components that are negative, NaN or infinite count as 0.
//! 2. Log-average luminance `Lavg = exp(mean(ln L))` over the pixels with `L > 1e-9` (black
//!    pixels, such as an empty background, are left out so they do not drag the exposure up).
//! 3. Exposure `k = 0.18 / Lavg` (the "key" 0.18 of Reinhard et al. 2002): the log-average maps to
//!    18% grey. With no non-black pixel, `k = 1`.
//! 4. Each component `v = clamp(k·c, 0, 1)`, encoded with the sRGB transfer curve and rounded to
//!    8 bits.
//!
//! The header's `EXPOSURE=` is not used: the preview exposes itself.

use std::io;
use std::path::Path;

use ::image::codecs::png::PngEncoder;
use ::image::{ExtendedColorType, ImageEncoder};

use super::{Image, ImageError};
use crate::color::LUMINANCE_WEIGHTS;

/// The key value: the log-average luminance is mapped to this linear value.
pub const KEY: f64 = 0.18;

/// Size of the linear → sRGB lookup table (linear values are quantised to 1/65535).
const LUT_SIZE: usize = 1 << 16;

#[inline]
fn clean(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 {
        v
    } else {
        0.0
    }
}

/// The sRGB transfer curve (IEC 61966-2-1) for a linear value in [0, 1].
pub fn srgb_encode(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The exposure multiplier `k` the operator picks for `img` (see the module docs).
pub fn auto_exposure(img: &Image) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for p in &img.pixels {
        let l = LUMINANCE_WEIGHTS[0] * clean(p[0]) as f64
            + LUMINANCE_WEIGHTS[1] * clean(p[1]) as f64
            + LUMINANCE_WEIGHTS[2] * clean(p[2]) as f64;
        if l > 1e-9 && l.is_finite() {
            sum += l.ln();
            n += 1;
        }
    }
    if n == 0 {
        return 1.0;
    }
    let k = KEY / (sum / n as f64).exp();
    if k.is_finite() && k > 0.0 {
        k
    } else {
        1.0
    }
}

/// The 8-bit sRGB preview of `img` as packed RGB bytes, top row first.
pub fn tone_map(img: &Image) -> Vec<u8> {
    tone_map_with(img, auto_exposure(img))
}

/// [`tone_map`] with the exposure multiplier `k` given (e.g. one smoothed over the frames
/// of an animation).
pub fn tone_map_with(img: &Image, k: f64) -> Vec<u8> {
    let k = if k.is_finite() && k > 0.0 {
        k as f32
    } else {
        1.0
    };
    let lut: Vec<u8> = (0..LUT_SIZE)
        .map(|i| {
            (srgb_encode(i as f64 / (LUT_SIZE - 1) as f64) * 255.0)
                .round()
                .clamp(0.0, 255.0) as u8
        })
        .collect();
    let scale = (LUT_SIZE - 1) as f32;
    let mut out = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        for &c in p {
            let v = (clean(c) * k).min(1.0); // clean() also removes a NaN from inf * 0
            let v = if v.is_nan() { 0.0 } else { v };
            out.push(lut[(v * scale + 0.5) as usize]);
        }
    }
    out
}

/// Write an 8-bit sRGB PNG preview of `img` (tone-mapped as the module docs describe),
/// atomically.
pub fn write_png(path: &Path, img: &Image) -> Result<(), ImageError> {
    write_png_with(path, img, auto_exposure(img))
}

/// [`write_png`] with the exposure multiplier `k` given.
pub fn write_png_with(path: &Path, img: &Image, k: f64) -> Result<(), ImageError> {
    let invalid = |reason: String| ImageError::Invalid {
        path: Some(path.to_path_buf()),
        reason,
    };
    super::check_writable(img).map_err(invalid)?;
    let (w, h) = match (u32::try_from(img.width), u32::try_from(img.height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => {
            return Err(invalid(format!(
                "{}x{} is too large for PNG",
                img.width, img.height
            )))
        }
    };
    let bytes = tone_map_with(img, k);
    super::output::write_atomic(path, |f| {
        let mut bw = io::BufWriter::new(f);
        PngEncoder::new(&mut bw)
            .write_image(&bytes, w, h, ExtendedColorType::Rgb8)
            .map_err(|e| match e {
                ::image::ImageError::IoError(e) => e,
                other => io::Error::other(other.to_string()),
            })?;
        io::Write::flush(&mut bw)
    })
    .map_err(|source| ImageError::Io {
        path: Some(path.to_path_buf()),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_maps_log_average_to_key() {
        let mut img = Image::new(2, 1);
        img.set(0, 0, [2.0, 2.0, 2.0]);
        img.set(1, 0, [8.0, 8.0, 8.0]);
        // log-average of 2 and 8 is 4
        assert!((auto_exposure(&img) - KEY / 4.0).abs() < 1e-6);
        // black pixels and garbage are ignored
        let mut img2 = Image::new(4, 1);
        img2.set(0, 0, [4.0, 4.0, 4.0]);
        img2.set(1, 0, [f32::NAN, -1.0, f32::INFINITY]);
        assert!((auto_exposure(&img2) - KEY / 4.0).abs() < 1e-6);
        assert_eq!(auto_exposure(&Image::new(3, 3)), 1.0);
    }

    #[test]
    fn tone_map_values() {
        let mut img = Image::new(3, 1);
        img.set(0, 0, [1.0, 1.0, 1.0]);
        img.set(1, 0, [100.0, f32::NAN, -5.0]);
        img.set(2, 0, [f32::INFINITY, 0.0, 1e-30]);
        let b = tone_map(&img);
        assert_eq!(b.len(), 9);
        assert_eq!(&b[3..], &[255, 0, 0, 0, 0, 0]);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        assert!((srgb_encode(0.18) * 255.0 - 117.6).abs() < 0.5);
    }
}
