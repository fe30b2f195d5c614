//! A Radiance picture as 2-D data: the library behind `colorpict` and `mixpict` (which also
//! need the function language).
//!
//! # Reading (Radiance's rules)
//! - The header ends at the first empty line; its first byte must be printable. `FORMAT=`
//!   must be `32-bit_rle_rgbe` or absent: anything else, `32-bit_rle_xyze` included, is
//!   refused ("bad picture file"). `PIXASPECT=` values multiply. Everything else is ignored,
//!   `EXPOSURE=` and `COLORCORR=` included: values are the raw decoded RGBE,
//!   (m + 0.5)·2^(e − 136).
//! - Any of the 8 resolution-line orientations (pixels are placed by their display
//!   position); flat, new-RLE and old-RLE scanlines; old `.pic` files without `#?RADIANCE`.
//!   (All by [`crate::image::hdr::read_hdr`].)
//!
//! # Mapping
//! Dimension 0 is v (rows, 0 = bottom), dimension 1 is u (columns, 0 = left). With
//! a = PIXASPECT (pixel height/width), xr × yr pixels: if xr ≤ yr·a, v ∈ [0, a·yr/xr] and
//! u ∈ [0, 1]; else v ∈ [0, 1] and u ∈ [0, xr/(yr·a)]: the shorter side spans 1. Pixel
//! centres lie on a grid including both edges (column k at u = k·umax/(xr − 1)); each
//! channel is interpolated bilinearly with the tails of [`super::data`] (no tiling, no
//! clamping). A side of one pixel is constant along that side.
//!
//! # Use (for the function-language wiring)
//! `PictData::load(path)` (or [`super::files::SceneFiles::picture`]), `extent()` for
//! (umax, vmax), then `lookup(u, v)` → (r, g, b) per ray, u from the first coordinate
//! expression and v from the second.

use super::data::{Axis, DataArray};
use crate::image::hdr::read_hdr;
use crate::image::{Image, FORMAT_RGBE};
use std::path::Path;

/// A picture as three 2-D data arrays (red, green, blue) over (v, u).
#[derive(Clone, Debug, PartialEq)]
pub struct PictData {
    /// Where it came from (for messages).
    pub name: String,
    channels: [DataArray; 3],
    umax: f64,
    vmax: f64,
    width: usize,
    height: usize,
}

impl PictData {
    /// Read a picture file.
    pub fn load(path: &Path) -> Result<PictData, String> {
        let name = path.display().to_string();
        let f =
            std::fs::File::open(path).map_err(|e| format!("{name}: cannot read picture: {e}"))?;
        let mut r = std::io::BufReader::with_capacity(1 << 16, f);
        PictData::read(&mut r, &name)
    }

    /// Read a picture from `r`; `name` is used in messages.
    pub fn read<R: std::io::BufRead>(r: &mut R, name: &str) -> Result<PictData, String> {
        let img = read_hdr(r).map_err(|e| format!("{name}: bad picture file: {e}"))?;
        if img.header.format != FORMAT_RGBE {
            return Err(format!(
                "{name}: bad picture file: pixel format {} (only {FORMAT_RGBE} is accepted)",
                img.header.format
            ));
        }
        PictData::from_image(&img, name)
    }

    /// The data of a picture in memory (values as stored, the header's PIXASPECT applied;
    /// the format is not checked).
    pub fn from_image(img: &Image, name: &str) -> Result<PictData, String> {
        let (xr, yr) = (img.width, img.height);
        let a = img.header.pixaspect.unwrap_or(1.0);
        if !(a.is_finite() && a > 0.0) {
            return Err(format!("{name}: bad picture file: PIXASPECT {a}"));
        }
        let (umax, vmax) = if xr as f64 <= yr as f64 * a {
            (1.0, a * yr as f64 / xr as f64)
        } else {
            (xr as f64 / (yr as f64 * a), 1.0)
        };
        let axes = vec![
            Axis::Even {
                beg: 0.0,
                end: vmax,
                n: yr,
            },
            Axis::Even {
                beg: 0.0,
                end: umax,
                n: xr,
            },
        ];
        // Rows bottom first (v = 0 at the bottom), columns left to right.
        let channel = |c: usize| -> Vec<f32> {
            (0..yr)
                .rev()
                .flat_map(|y| img.row(y).iter().map(move |p| p[c]))
                .collect()
        };
        let make = |c: usize| {
            DataArray::from_parts(name, axes.clone(), channel(c))
                .ok_or_else(|| format!("{name}: bad picture size {xr}x{yr}"))
        };
        Ok(PictData {
            name: name.to_string(),
            channels: [make(0)?, make(1)?, make(2)?],
            umax,
            vmax,
            width: xr,
            height: yr,
        })
    }

    /// The extent of the coordinates, (umax, vmax): the shorter side spans 1.
    pub fn extent(&self) -> (f64, f64) {
        (self.umax, self.vmax)
    }

    /// The picture's size in pixels (width, height).
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The colour at (u, v): each channel interpolated with Radiance's rules (module docs).
    pub fn lookup(&self, u: f64, v: f64) -> [f64; 3] {
        let c = [v, u];
        [
            self.channels[0].interp(&c),
            self.channels[1].interp(&c),
            self.channels[2].interp(&c),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::hdr::{rgbe_to_float, write_hdr};

    /// The 4×2 picture of radiance-formats.md §4: red = column + 1, green = row + 1 from the
    /// bottom, blue 0.
    fn four_by_two(aspect: Option<f64>) -> Vec<u8> {
        let mut img = Image::new(4, 2);
        for y in 0..2 {
            for x in 0..4 {
                img.set(x, 1 - y, [(x + 1) as f32, (y + 1) as f32, 0.0]);
            }
        }
        img.header.pixaspect = aspect;
        let mut out = Vec::new();
        write_hdr(&mut out, &img).unwrap();
        out
    }

    fn close(a: [f64; 3], r: f64, g: f64) -> bool {
        (a[0] - r).abs() < 1e-3 && (a[1] - g).abs() < 1e-3
    }

    #[test]
    fn verified_values_of_the_reference() {
        let p = PictData::read(&mut &four_by_two(None)[..], "t.hdr").unwrap();
        assert_eq!(p.extent(), (2.0, 1.0));
        for (u, v, r, g) in [
            (0.0, 0.0, 1.0039, 1.0039),
            (0.6667, 0.0, 2.0078, 1.0078),
            (2.0, 1.0, 4.0156, 2.0156),
            (1.0, 0.5, 2.5078, 1.5078),
            (3.0, 0.0, 1.4353, 0.2924),
            (-1.0, 0.0, 0.0, 0.6667),
        ] {
            let got = p.lookup(u, v);
            assert!(close(got, r, g), "({u},{v}): {got:?} != {r} {g}");
        }
        // The row discontinuity: u = 2.66 → 5.01, u = 2.667 → 1.67 (red, bottom row).
        assert!((p.lookup(2.66, 0.0)[0] - 5.01).abs() < 0.01);
        assert!((p.lookup(2.667, 0.0)[0] - 1.67).abs() < 0.01);
        let q = PictData::read(&mut &four_by_two(Some(2.0))[..], "t.hdr").unwrap();
        assert_eq!(q.extent(), (1.0, 1.0));
        // Decoded values are exactly the RGBE ones.
        let want = rgbe_to_float([128, 64, 0, 130])[0] as f64; // red 2, green 1
        assert_eq!(q.lookup(1.0 / 3.0, 0.0)[0], want);
    }

    #[test]
    fn header_rules() {
        let base = four_by_two(None);
        let text = String::from_utf8_lossy(&base).into_owned();
        // EXPOSURE and COLORCORR are ignored; PIXASPECT multiplies.
        let with = |extra: &str| -> Vec<u8> {
            let cut = text.find("FORMAT=").unwrap();
            let mut v = base[..cut].to_vec();
            v.extend_from_slice(extra.as_bytes());
            v.extend_from_slice(&base[cut..]);
            v
        };
        let a = PictData::read(&mut &base[..], "a").unwrap();
        let b = PictData::read(
            &mut &with("EXPOSURE=4\nCOLORCORR= 2 2 2\nPIXASPECT=2\nPIXASPECT=0.5\n")[..],
            "b",
        )
        .unwrap();
        assert_eq!(a.lookup(0.7, 0.3), b.lookup(0.7, 0.3));
        assert_eq!(b.extent(), (2.0, 1.0));
        // Replace header text (the pixel bytes stay as they are).
        let edit = |from: &str, to: &str| -> Vec<u8> {
            let head = text.find("\n\n").unwrap();
            let mut v = text[..head].replace(from, to).into_bytes();
            v.extend_from_slice(&base[head..]);
            v
        };
        let e = PictData::read(&mut &edit("rgbe", "xyze")[..], "x.hdr").unwrap_err();
        assert!(e.contains("x.hdr: bad picture file"), "{e}");
        assert!(PictData::read(&mut &edit("32-bit_rle_rgbe", "ascii")[..], "o").is_err());
        // No FORMAT line and no magic line: an old .pic.
        let no_magic = edit("#?RADIANCE\n", "");
        let no_format = {
            let t = String::from_utf8_lossy(&no_magic).into_owned();
            let head = t.find("\n\n").unwrap();
            let mut v = t[..head]
                .replace("\nFORMAT=32-bit_rle_rgbe", "")
                .into_bytes();
            v.extend_from_slice(&no_magic[head..]);
            v
        };
        assert!(!String::from_utf8_lossy(&no_format).contains("FORMAT"));
        let o = PictData::read(&mut &no_format[..], "o.pic").unwrap();
        assert_eq!(o.lookup(0.3, 0.6), a.lookup(0.3, 0.6));
    }

    #[test]
    fn tall_pictures_span_one_horizontally() {
        let mut img = Image::new(2, 5);
        img.header.pixaspect = Some(0.5);
        let p = PictData::from_image(&img, "t").unwrap();
        // xr = 2 <= yr·a = 2.5: u ∈ [0,1], v ∈ [0, 1.25].
        assert_eq!(p.extent(), (1.0, 1.25));
        let one = Image::new(1, 1);
        let q = PictData::from_image(&one, "t").unwrap();
        assert_eq!(q.lookup(5.0, -3.0), [0.0; 3]);
    }
}
