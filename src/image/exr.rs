//! OpenEXR pictures: 32-bit float R, G, B channels, ZIP-compressed scanlines.
//!
//! The Radiance header travels as layer attributes, so a picture survives a round trip through
//! EXR unchanged:
//!
//! | attribute            | type   | content                                          |
//! |----------------------|--------|--------------------------------------------------|
//! | `radiance.commands`  | text   | the command lines, joined with newlines          |
//! | `software`           | text   | `SOFTWARE=` (the standard OpenEXR attribute)     |
//! | `radiance.view`      | text   | `VIEW=` (`-vtv -vp ...`)                         |
//! | `radiance.frame`     | int    | `FRAME=`                                         |
//! | `radiance.pixaspect` | text   | `PIXASPECT=` (also the standard `pixelAspectRatio`) |
//! | `radiance.exposure`  | text   | the `EXPOSURE=` product, when not 1              |
//! | `radiance.primaries` | text   | `PRIMARIES=` (also the standard `chromaticities`) |
//! | `radiance.format`    | text   | `32-bit_rle_rgbe` or `32-bit_rle_xyze`           |
//! | `radiance.tiled`     | text   | `TILED=` as `X Y`                                |
//! | `radiance.extra`     | text   | other variables, one `NAME=value` per line       |
//!
//! Pixel values are written as they are (no exposure applied, non-finite values kept). Files
//! written by other programs are read from their first layer with R, G and B channels (any
//! sample type); the standard `pixelAspectRatio`, `chromaticities` and `software` attributes
//! fill the header when the `radiance.*` ones are absent.

use std::io;
use std::path::Path;

use ::exr::meta::attribute::{AttributeValue, Chromaticities, Text};
use ::exr::prelude::{self as x, ReadChannels, ReadLayers, ReadSpecificChannel, WritableImage};

use super::{Header, Image, ImageError, FORMAT_RGBE, FORMAT_XYZE};

const A_COMMANDS: &str = "radiance.commands";
const A_VIEW: &str = "radiance.view";
const A_FRAME: &str = "radiance.frame";
const A_PIXASPECT: &str = "radiance.pixaspect";
const A_EXPOSURE: &str = "radiance.exposure";
const A_PRIMARIES: &str = "radiance.primaries";
const A_FORMAT: &str = "radiance.format";
const A_TILED: &str = "radiance.tiled";
const A_EXTRA: &str = "radiance.extra";

/// EXR text is Latin-1; characters outside it become `?`.
fn text(s: &str) -> Text {
    Text::new_or_none(s).unwrap_or_else(|| {
        let latin1: String = s
            .chars()
            .map(|c| if (c as u32) < 256 { c } else { '?' })
            .collect();
        Text::new_or_panic(latin1)
    })
}

fn parse_primaries(p: &str) -> Option<Chromaticities> {
    let v: Vec<f32> = p
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .ok()?;
    (v.len() == 8).then(|| Chromaticities {
        red: x::Vec2(v[0], v[1]),
        green: x::Vec2(v[2], v[3]),
        blue: x::Vec2(v[4], v[5]),
        white: x::Vec2(v[6], v[7]),
    })
}

fn exr_io_error(e: x::Error) -> io::Error {
    match e {
        x::Error::Io(e) => e,
        other => io::Error::other(other.to_string()),
    }
}

/// Write `img` as an OpenEXR file (float RGB, header as attributes, see the module docs),
/// atomically.
pub fn write_exr(path: &Path, img: &Image) -> Result<(), ImageError> {
    super::check_writable(img).map_err(|reason| ImageError::Invalid {
        path: Some(path.to_path_buf()),
        reason,
    })?;
    let h = &img.header;
    let mut la = x::LayerAttributes::default();
    let mut put = |name: &str, v: AttributeValue| {
        la.other.insert(text(name), v);
    };
    if !h.commands.is_empty() {
        put(
            A_COMMANDS,
            AttributeValue::Text(text(&h.commands.join("\n"))),
        );
    }
    if let Some(v) = &h.view {
        put(A_VIEW, AttributeValue::Text(text(v)));
    }
    if let Some(f) = h.frame {
        match i32::try_from(f) {
            Ok(f) => put(A_FRAME, AttributeValue::I32(f)),
            Err(_) => put(A_FRAME, AttributeValue::Text(text(&f.to_string()))),
        }
    }
    if let Some(pa) = h.pixaspect {
        put(A_PIXASPECT, AttributeValue::Text(text(&pa.to_string())));
    }
    if h.exposure != 1.0 {
        put(
            A_EXPOSURE,
            AttributeValue::Text(text(&h.exposure.to_string())),
        );
    }
    if let Some(p) = &h.primaries {
        put(A_PRIMARIES, AttributeValue::Text(text(p)));
    }
    put(
        A_FORMAT,
        AttributeValue::Text(text(if h.is_xyze() {
            FORMAT_XYZE
        } else {
            FORMAT_RGBE
        })),
    );
    if let Some((tx, ty)) = h.tiled {
        put(A_TILED, AttributeValue::Text(text(&format!("{tx} {ty}"))));
    }
    if !h.extra.is_empty() {
        let lines: Vec<String> = h.extra.iter().map(|(n, v)| format!("{n}={v}")).collect();
        put(A_EXTRA, AttributeValue::Text(text(&lines.join("\n"))));
    }
    la.software_name = h.software.as_deref().map(text);

    let (w, pixels) = (img.width, &img.pixels);
    let channels = x::SpecificChannels::rgb(|p: x::Vec2<usize>| {
        let c = pixels[p.y() * w + p.x()];
        (c[0], c[1], c[2])
    });
    let layer = x::Layer::new(
        (img.width, img.height),
        la,
        x::Encoding::SMALL_LOSSLESS,
        channels,
    );
    let mut image = x::Image::from_layer(layer);
    if let Some(pa) = h.pixaspect {
        image.attributes.pixel_aspect = pa as f32;
    }
    if !h.is_xyze() {
        image.attributes.chromaticities =
            parse_primaries(h.primaries.as_deref().unwrap_or(super::STD_PRIMARIES));
    }
    super::output::write_atomic(path, |f| {
        image.write().to_unbuffered(f).map_err(exr_io_error)
    })
    .map_err(|source| ImageError::Io {
        path: Some(path.to_path_buf()),
        source,
    })
}

fn attr_text(v: &AttributeValue) -> Option<String> {
    match v {
        AttributeValue::Text(t) => Some(t.to_string()),
        _ => None,
    }
}

/// Refuse a file whose layers declare more pixels than memory can hold (48 bytes a pixel,
/// the pixels and the decoder's buffers, against `MemAvailable`; 2^30 pixels when that is
/// unknown) before any pixel buffer is
/// allocated: a damaged header made the reader abort allocating 29 GB (found by
/// `tests/fuzz.rs`).
fn check_exr_size(path: &Path) -> Result<(), ImageError> {
    let meta = ::exr::meta::MetaData::read_from_file(path, false).map_err(|e| match e {
        x::Error::Io(source) => ImageError::Io {
            path: Some(path.to_path_buf()),
            source,
        },
        other => ImageError::Format {
            path: Some(path.to_path_buf()),
            reason: format!("OpenEXR: {other}"),
        },
    })?;
    let limit = crate::runinfo::available_memory()
        .map(|b| b / 48)
        .unwrap_or(1 << 30);
    for h in meta.headers.iter() {
        let px = (h.layer_size.width() as u64).saturating_mul(h.layer_size.height() as u64);
        if px > limit {
            return Err(ImageError::Format {
                path: Some(path.to_path_buf()),
                reason: format!(
                    "OpenEXR: a layer of {}x{} pixels is larger than memory can hold",
                    h.layer_size.width(),
                    h.layer_size.height()
                ),
            });
        }
    }
    Ok(())
}

/// Read an OpenEXR file: the first layer with R, G and B channels, top row first; the header
/// from the attributes (see the module docs).
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    check_exr_size(path)?;
    type Px = (usize, Vec<[f32; 3]>);
    let read = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .collect_pixels(
            |size: x::Vec2<usize>, _| -> Px {
                (size.width(), vec![[0.0; 3]; size.width() * size.height()])
            },
            |px: &mut Px, pos: x::Vec2<usize>, (r, g, b): (f32, f32, f32)| {
                let w = px.0;
                px.1[pos.y() * w + pos.x()] = [r, g, b];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_file(path);
    let image = read.map_err(|e| match e {
        x::Error::Io(source) => ImageError::Io {
            path: Some(path.to_path_buf()),
            source,
        },
        other => ImageError::Format {
            path: Some(path.to_path_buf()),
            reason: format!("OpenEXR: {other}"),
        },
    })?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let pixels = layer.channel_data.pixels.1.clone();

    let get = |name: &str| {
        let key = text(name);
        layer
            .attributes
            .other
            .get(&key)
            .or_else(|| image.attributes.other.get(&key))
    };
    let get_text = |name: &str| get(name).and_then(attr_text);
    let mut h = Header::default();
    if let Some(c) = get_text(A_COMMANDS) {
        h.commands = c.lines().map(str::to_string).collect();
    }
    h.software = layer
        .attributes
        .software_name
        .as_ref()
        .map(|t| t.to_string());
    h.view = get_text(A_VIEW);
    h.frame = match get(A_FRAME) {
        Some(AttributeValue::I32(f)) => u32::try_from(*f).ok(),
        Some(AttributeValue::Text(t)) => t.to_string().trim().parse().ok(),
        _ => None,
    };
    h.pixaspect = match get_text(A_PIXASPECT).and_then(|s| s.trim().parse().ok()) {
        Some(pa) => Some(pa),
        None => {
            let pa = image.attributes.pixel_aspect;
            (pa.is_finite() && pa > 0.0 && pa != 1.0).then_some(pa as f64)
        }
    };
    if let Some(e) = get_text(A_EXPOSURE).and_then(|s| s.trim().parse().ok()) {
        h.exposure = e;
    }
    h.primaries = get_text(A_PRIMARIES).or_else(|| {
        image.attributes.chromaticities.map(|c| {
            let s = format!(
                "{:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4} {:.4}",
                c.red.0, c.red.1, c.green.0, c.green.1, c.blue.0, c.blue.1, c.white.0, c.white.1
            );
            s
        })
    });
    // The standard primaries are what a Radiance writer assumes anyway: keep them implicit.
    if h.primaries.as_deref() == Some(super::STD_PRIMARIES) && get_text(A_PRIMARIES).is_none() {
        h.primaries = None;
    }
    if let Some(f) = get_text(A_FORMAT) {
        if f == FORMAT_XYZE {
            h.format = FORMAT_XYZE.to_string();
        }
    }
    if let Some(t) = get_text(A_TILED) {
        let v: Vec<u32> = t
            .split_whitespace()
            .filter_map(|s| s.parse().ok())
            .collect();
        if v.len() == 2 {
            h.tiled = Some((v[0], v[1]));
        }
    }
    if let Some(e) = get_text(A_EXTRA) {
        h.extra = e
            .lines()
            .filter_map(|l| {
                l.split_once('=')
                    .map(|(n, v)| (n.to_string(), v.to_string()))
            })
            .collect();
    }
    Ok(Image {
        width,
        height,
        pixels,
        header: h,
    })
}
