//! Pictures in memory and on disk.
//!
//! An [`Image`] is a grid of linear radiance RGB values (`f32`), stored row by row with row 0 the
//! **top** scanline, plus the Radiance [`Header`] that travels with it. The formats:
//!
//! - [`hdr`]: Radiance RGBE pictures (`.hdr`, `.pic`, `.unf`, …), byte-compatible with what
//!   `rpict` writes and readable in every form Radiance reads (new and old run-length encoding,
//!   flat scanlines, all 8 orientations, RGBE and XYZE).
//! - [`exr`]: OpenEXR, 32-bit float RGB, the header kept as text attributes.
//! - [`png`]: an 8-bit, automatically exposed sRGB preview.
//! - [`output`]: atomic file creation (temporary file in the same directory, then rename), so a
//!   reader never sees a half-written picture.
//!
//! [`write_picture`] and [`read_picture`] choose the format from the file name (and, when
//! reading, from the file's magic bytes).

pub mod exr;
pub mod hdr;
pub mod output;
pub mod png;
pub mod rle;

use std::fmt;
use std::path::{Path, PathBuf};

/// The `FORMAT=` value of an RGBE picture.
pub const FORMAT_RGBE: &str = "32-bit_rle_rgbe";
/// The `FORMAT=` value of an XYZE picture (`rpict -pXYZ`).
pub const FORMAT_XYZE: &str = "32-bit_rle_xyze";
/// Radiance's standard RGB primaries and white point, as `PRIMARIES=` writes them.
pub const STD_PRIMARIES: &str = "0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333";

/// A picture in memory. Row 0 is the TOP scanline; pixels left to right; linear radiance RGB.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Number of pixels per row.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// `width * height` pixels, row 0 (the top) first, each row left to right.
    pub pixels: Vec<[f32; 3]>,
    /// The Radiance header that goes with the pixels.
    pub header: Header,
}

impl Image {
    /// A black picture with a default header.
    pub fn new(width: usize, height: usize) -> Image {
        Image {
            width,
            height,
            pixels: vec![[0.0; 3]; width * height],
            header: Header::default(),
        }
    }

    /// A picture from pixels given top row first; `None` if `pixels.len() != width * height`.
    pub fn from_pixels(width: usize, height: usize, pixels: Vec<[f32; 3]>) -> Option<Image> {
        (width.checked_mul(height) == Some(pixels.len())).then(|| Image {
            width,
            height,
            pixels,
            header: Header::default(),
        })
    }

    /// The pixel at column `x`, row `y_from_top`. Panics when out of range.
    #[inline]
    pub fn get(&self, x: usize, y_from_top: usize) -> [f32; 3] {
        assert!(
            x < self.width && y_from_top < self.height,
            "pixel ({x}, {y_from_top}) outside {}x{}",
            self.width,
            self.height
        );
        self.pixels[y_from_top * self.width + x]
    }

    /// Set the pixel at column `x`, row `y_from_top`. Panics when out of range.
    #[inline]
    pub fn set(&mut self, x: usize, y_from_top: usize, c: [f32; 3]) {
        assert!(
            x < self.width && y_from_top < self.height,
            "pixel ({x}, {y_from_top}) outside {}x{}",
            self.width,
            self.height
        );
        self.pixels[y_from_top * self.width + x] = c;
    }

    /// Row `y_from_top` as a slice of `width` pixels. Panics when out of range.
    #[inline]
    pub fn row(&self, y_from_top: usize) -> &[[f32; 3]] {
        &self.pixels[y_from_top * self.width..(y_from_top + 1) * self.width]
    }

    /// Row `y_from_top` as a mutable slice of `width` pixels. Panics when out of range.
    #[inline]
    pub fn row_mut(&mut self, y_from_top: usize) -> &mut [[f32; 3]] {
        let w = self.width;
        &mut self.pixels[y_from_top * w..(y_from_top + 1) * w]
    }
}

/// Header information of a Radiance picture.
///
/// The reader fills the named fields from the matching `VAR=value` lines (in any order, anywhere
/// in the header), keeps every line that is not a `VAR=value` line in `commands`, and every other
/// variable in `extra`. The writer puts them back in the order `rpict` uses (see
/// [`hdr::write_hdr`]).
///
/// `Header::default()` is an empty RGBE header: exposure 1, format `32-bit_rle_rgbe`.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// Command lines (`oconv scene.rad`, `rpict -x 32 ...`) and any other non-variable lines,
    /// verbatim, in order. The `#?RADIANCE` magic line is not included.
    pub commands: Vec<String>,
    /// The `SOFTWARE=` value, without the leading space (`RADIANCE 6.0a`). When a file has
    /// several, the last one is kept here and the earlier ones go to `extra`.
    pub software: Option<String>,
    /// The `VIEW=` value (`-vtv -vp ...`), trimmed. Several `VIEW=` lines are joined with a
    /// space, which keeps Radiance's meaning (later options override earlier ones).
    pub view: Option<String>,
    /// `FRAME=` (the last one when several).
    pub frame: Option<u32>,
    /// `PIXASPECT=`: the reader keeps the product of all of them; the writer writes it if `Some`.
    pub pixaspect: Option<f64>,
    /// Product of all `EXPOSURE=` values (1.0 when absent). The reader keeps pixel values as
    /// stored (it does not divide); true radiance is `pixel / exposure`.
    pub exposure: f64,
    /// The `PRIMARIES=` value (eight numbers as text), trimmed. `None` means Radiance's standard
    /// primaries ([`STD_PRIMARIES`]): the reader gives `None` for a line with exactly that text,
    /// and the writer writes that line for `None` (except for XYZE pictures).
    pub primaries: Option<String>,
    /// The pixel format, `32-bit_rle_rgbe` or `32-bit_rle_xyze`.
    pub format: String,
    /// `TILED= X Y` (rpiece / rxpiece pictures).
    pub tiled: Option<(u32, u32)>,
    /// Every other `VAR=value` line, in order: the name, and the text after `=` exactly as in
    /// the file (it may start with a space, as in `("CAPDATE", " 2026:11:22 02:49:21")`).
    pub extra: Vec<(String, String)>,
}

impl Default for Header {
    fn default() -> Header {
        Header {
            commands: Vec::new(),
            software: None,
            view: None,
            frame: None,
            pixaspect: None,
            exposure: 1.0,
            primaries: None,
            format: FORMAT_RGBE.to_string(),
            tiled: None,
            extra: Vec::new(),
        }
    }
}

impl Header {
    /// The value of the first `extra` variable called `name`, if any.
    pub fn extra_value(&self, name: &str) -> Option<&str> {
        self.extra
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// True for an XYZE picture.
    pub fn is_xyze(&self) -> bool {
        self.format == FORMAT_XYZE
    }
}

/// Picture file kinds by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PictureFormat {
    /// Radiance RGBE (`.hdr`, `.pic`, `.unf` and anything not listed below).
    Hdr,
    /// OpenEXR (`.exr`).
    Exr,
    /// PNG preview (`.png`).
    Png,
}

impl PictureFormat {
    /// `.exr` → Exr, `.png` → Png (either case), anything else → Hdr.
    pub fn from_path(p: &Path) -> PictureFormat {
        match p
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
        {
            Some(e) if e == "exr" => PictureFormat::Exr,
            Some(e) if e == "png" => PictureFormat::Png,
            _ => PictureFormat::Hdr,
        }
    }
}

/// Extensions of picture formats Tessera does not write: naming one as the output would
/// put RGBE data in a file that claims to be something else.
const FOREIGN_PICTURES: [&str; 10] = [
    "jpg", "jpeg", "tif", "tiff", "bmp", "gif", "webp", "ppm", "pgm", "tga",
];

/// Check an output picture's name before anything is rendered: an extension of a format
/// Tessera does not write (`.jpg`, `.tif`, ...) and a folder that does not exist are
/// refused, with what to do instead.
pub fn check_output_path(p: &Path) -> Result<(), String> {
    if let Some(e) = p.extension().and_then(|e| e.to_str()) {
        if FOREIGN_PICTURES.contains(&e.to_ascii_lowercase().as_str()) {
            return Err(format!(
                "{}: Tessera writes Radiance pictures (.hdr, or any other name), .exr and \
                 .png, not .{e}",
                p.display()
            ));
        }
    }
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!(
            "{}: the folder {} does not exist",
            p.display(),
            dir.display()
        ));
    }
    Ok(())
}

/// Errors from reading or writing pictures. Messages name the file (when there is one) and the
/// reason, e.g. `out.hdr: truncated picture: end of file in scanline 7 of 32`.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The operating system refused a read or write.
    #[error("{}{source}", prefix(.path))]
    Io {
        /// The file, if the error concerns one (`None` for streams).
        path: Option<PathBuf>,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The data is not a valid picture of the expected kind (bad header, corrupt or truncated
    /// pixel data, unsupported format).
    #[error("{}{reason}", prefix(.path))]
    Format {
        /// The file, if the error concerns one (`None` for streams).
        path: Option<PathBuf>,
        /// What is wrong.
        reason: String,
    },
    /// The picture cannot be written (e.g. it has no pixels, or `pixels.len()` does not match).
    #[error("{}{reason}", prefix(.path))]
    Invalid {
        /// The file being written, if any.
        path: Option<PathBuf>,
        /// What is wrong.
        reason: String,
    },
}

fn prefix(path: &Option<PathBuf>) -> String {
    match path {
        Some(p) => format!("{}: ", p.display()),
        None => String::new(),
    }
}

impl ImageError {
    /// A format error without a file name.
    pub fn format(reason: impl fmt::Display) -> ImageError {
        ImageError::Format {
            path: None,
            reason: reason.to_string(),
        }
    }

    /// Attach `path` to the error (replacing any path it had).
    pub fn with_path(self, p: &Path) -> ImageError {
        let path = Some(p.to_path_buf());
        match self {
            ImageError::Io { source, .. } => ImageError::Io { path, source },
            ImageError::Format { reason, .. } => ImageError::Format { path, reason },
            ImageError::Invalid { reason, .. } => ImageError::Invalid { path, reason },
        }
    }

    /// The file the error concerns, if known.
    pub fn path(&self) -> Option<&Path> {
        match self {
            ImageError::Io { path, .. }
            | ImageError::Format { path, .. }
            | ImageError::Invalid { path, .. } => path.as_deref(),
        }
    }
}

impl From<std::io::Error> for ImageError {
    fn from(source: std::io::Error) -> ImageError {
        ImageError::Io { path: None, source }
    }
}

/// Check that `img` can be written: at least one pixel, and `pixels.len() == width * height`.
pub(crate) fn check_writable(img: &Image) -> Result<(), String> {
    if img.width == 0 || img.height == 0 {
        return Err(format!(
            "cannot write an empty {}x{} picture",
            img.width, img.height
        ));
    }
    if img.width.checked_mul(img.height) != Some(img.pixels.len()) {
        return Err(format!(
            "picture is {}x{} but has {} pixels",
            img.width,
            img.height,
            img.pixels.len()
        ));
    }
    Ok(())
}

/// Write a picture to `path` atomically (temp file in the same directory, then rename), format by
/// extension ([`PictureFormat::from_path`]). `None` writes RGBE to standard output.
///
/// An existing file is replaced (callers that must not clobber use
/// [`output::write_atomic_noclobber`] themselves); a partial file is never left behind.
pub fn write_picture(path: Option<&Path>, img: &Image) -> Result<(), ImageError> {
    let Some(path) = path else {
        use std::io::Write;
        check_writable(img).map_err(|reason| ImageError::Invalid { path: None, reason })?;
        let stdout = std::io::stdout();
        let mut w = std::io::BufWriter::with_capacity(1 << 16, stdout.lock());
        let res = hdr::write_hdr(&mut w, img).and_then(|()| w.flush());
        return res.map_err(|source| ImageError::Io {
            path: Some(PathBuf::from("<stdout>")),
            source,
        });
    };
    match PictureFormat::from_path(path) {
        PictureFormat::Hdr => hdr::write_hdr_file(path, img),
        PictureFormat::Exr => exr::write_exr(path, img),
        PictureFormat::Png => png::write_png(path, img),
    }
}

/// Read a picture. OpenEXR files (recognised by their magic bytes, or by a `.exr` name) go
/// through [`exr::read_exr`]; everything else is read as a Radiance picture.
pub fn read_picture(path: &Path) -> Result<Image, ImageError> {
    let mut magic = [0u8; 4];
    let is_exr_magic = {
        use std::io::Read;
        let mut f = std::fs::File::open(path).map_err(|source| ImageError::Io {
            path: Some(path.to_path_buf()),
            source,
        })?;
        let mut n = 0;
        while n < 4 {
            match f.read(&mut magic[n..]) {
                Ok(0) => break,
                Ok(k) => n += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(source) => {
                    return Err(ImageError::Io {
                        path: Some(path.to_path_buf()),
                        source,
                    })
                }
            }
        }
        n == 4 && magic == [0x76, 0x2f, 0x31, 0x01]
    };
    if is_exr_magic
        || (PictureFormat::from_path(path) == PictureFormat::Exr && magic[..2] != *b"#?")
    {
        exr::read_exr(path)
    } else {
        hdr::read_hdr_file(path)
    }
}
