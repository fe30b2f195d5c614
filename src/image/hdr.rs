//! Radiance RGBE pictures (`.hdr`, `.pic`): the header, the resolution line and the pixels.
//!
//! # Writing
//! The header is `#?RADIANCE`, the command lines, `SOFTWARE=`, `FRAME=`, `TILED=`, `VIEW=`,
//! `PIXASPECT=`, `PRIMARIES=` (Radiance's standard primaries when unset; omitted for XYZE), the
//! other variables, `EXPOSURE=` (only when it is not 1), `FORMAT=`, a blank line, then the
//! resolution line `-Y       32 +X       32` (top scanline first, left to right).
//!
//! Scanlines use the new run-length encoding: a `02 02 hi lo` marker, then the R, G, B and E
//! bytes of the line as four separate streams of packets. A packet is either a run (count byte
//! `128 + n`, then the byte to repeat, `4 <= n <= 127`; 2 or 3 equal bytes standing alone before a
//! long run or the end of the line are also written as a run) or a literal (count byte `n`,
//! `1 <= n <= 128`, then `n` bytes). Lines narrower than 17 or wider than 32767 pixels are flat
//! (4 bytes per pixel). The output is byte-identical to Radiance 6.0a's.
//!
//! # Reading
//! Any header line order; `EXPOSURE=` and `PIXASPECT=` multiply; CRLF line ends; all 8
//! resolution-line orientations (the image is returned top row first); new RLE, old RLE
//! (`1 1 1 n` repeat pixels with growing shifts) and flat scanlines, mixed freely line by line;
//! RGBE and XYZE (values kept, format recorded). Truncated or corrupt data gives an error, never
//! a panic.

use std::io::{self, BufRead, Read, Write};
use std::path::Path;

use super::rle::{encode_row, read_scanline};
pub use super::rle::{float_to_rgbe, rgbe_to_float};
use super::{Header, Image, ImageError, FORMAT_RGBE, FORMAT_XYZE, STD_PRIMARIES};

/// Header lines longer than this are refused (Radiance itself splits long lines at 2048 bytes).
const MAX_HEADER_LINE: u64 = 1 << 20;
/// Largest accepted picture side (Radiance stores sizes in an `int`).
const MAX_SIDE: u64 = i32::MAX as u64;
/// Largest accepted pixel count when reading (2^32: 48 GiB as floats, beyond any machine we run
/// on); it keeps a corrupt size from overflowing.
const MAX_PIXELS: usize = if usize::BITS >= 64 {
    1usize.wrapping_shl(32)
} else {
    usize::MAX / 16
};

// ---------------------------------------------------------------------------------------------
// Writing

/// Format like C's `%e` (`2.000000e+00`).
fn c_exp(x: f64) -> String {
    let s = format!("{x:.6e}");
    match s.split_once('e') {
        Some((mant, exp)) => {
            let (sign, digits) = match exp.strip_prefix('-') {
                Some(d) => ('-', d),
                None => ('+', exp),
            };
            format!("{mant}e{sign}{digits:0>2}")
        }
        None => s, // inf / NaN
    }
}

/// Header text without line breaks: a `\n` or `\r` inside a value would end the line (or, as an
/// empty line, the header) early, so they become spaces.
fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// The complete header and resolution line `write_hdr` writes for `img`.
pub fn header_bytes(img: &Image) -> Vec<u8> {
    header_bytes_for(&img.header, img.width, img.height)
}

/// The header `h` and the resolution line of a `width` × `height` picture, as
/// [`header_bytes`].
pub fn header_bytes_for(h: &Header, width: usize, height: usize) -> Vec<u8> {
    let xyze = h.is_xyze();
    let mut s = String::with_capacity(512);
    s.push_str("#?RADIANCE\n");
    for c in &h.commands {
        let c = one_line(c);
        if !c.trim().is_empty() {
            s.push_str(&c);
            s.push('\n');
        }
    }
    if let Some(sw) = &h.software {
        s.push_str(&format!("SOFTWARE= {}\n", one_line(sw.trim())));
    }
    if let Some(f) = h.frame {
        s.push_str(&format!("FRAME={f}\n"));
    }
    if let Some((x, y)) = h.tiled {
        s.push_str(&format!("TILED= {x} {y}\n"));
    }
    if let Some(v) = &h.view {
        s.push_str(&format!("VIEW= {}\n", one_line(v.trim())));
    }
    if let Some(pa) = h.pixaspect {
        s.push_str(&format!("PIXASPECT={pa:.6}\n"));
    }
    if !xyze {
        let p = h
            .primaries
            .as_deref()
            .map(str::trim)
            .unwrap_or(STD_PRIMARIES);
        s.push_str(&format!("PRIMARIES= {}\n", one_line(p)));
    }
    for (name, value) in &h.extra {
        let name = one_line(name.trim());
        if !name.is_empty() {
            s.push_str(&format!("{name}={}\n", one_line(value)));
        }
    }
    if h.exposure.is_finite() && h.exposure > 0.0 && h.exposure != 1.0 {
        s.push_str(&format!("EXPOSURE={}\n", c_exp(h.exposure)));
    }
    s.push_str(&format!(
        "FORMAT={}\n\n",
        if xyze { FORMAT_XYZE } else { FORMAT_RGBE }
    ));
    s.push_str(&format!("-Y {height:8} +X {width:8}\n"));
    s.into_bytes()
}

/// Write `img` as a Radiance RGBE picture (header, resolution line, RLE scanlines), top row
/// first. Fails with `InvalidInput` for a picture without pixels or with a pixel count that
/// does not match its size. Large pictures are encoded on several threads (rayon), in batches so
/// memory stays bounded; the bytes do not depend on the thread count. Writes in large blocks,
/// so `w` need not be buffered.
pub fn write_hdr<W: Write>(w: &mut W, img: &Image) -> io::Result<()> {
    super::check_writable(img).map_err(|msg| io::Error::new(io::ErrorKind::InvalidInput, msg))?;
    let mut rows = HdrRows::new(w, &img.header, img.width, img.height)?;
    rows.rows(&img.pixels)?;
    rows.finish().map(drop)
}

/// A Radiance RGBE picture written a block of rows at a time, as a render finishes them:
/// the header and resolution line first ([`HdrRows::new`]), then the rows top first
/// ([`HdrRows::rows`]); the bytes are those [`write_hdr`] writes for the whole picture.
pub struct HdrRows<W: Write> {
    w: W,
    width: usize,
    /// Rows still to come.
    left: usize,
}

impl<W: Write> HdrRows<W> {
    /// Write the header `h` of a `width` × `height` picture to `w`. Fails with `InvalidInput`
    /// for an empty size.
    pub fn new(mut w: W, h: &Header, width: usize, height: usize) -> io::Result<Self> {
        if width == 0 || height == 0 || width.checked_mul(height).is_none() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("cannot write an empty {width}x{height} picture"),
            ));
        }
        w.write_all(&header_bytes_for(h, width, height))?;
        Ok(HdrRows {
            w,
            width,
            left: height,
        })
    }

    /// Write whole rows (`width` pixels each, top first). Large blocks are encoded on
    /// several threads (rayon) in batches, so memory stays bounded; the bytes do not depend
    /// on the thread count. Fails with `InvalidInput` for a partial row or rows beyond the
    /// picture's height.
    pub fn rows(&mut self, pixels: &[[f32; 3]]) -> io::Result<()> {
        use rayon::prelude::*;
        let width = self.width;
        let n = pixels.len() / width;
        if !pixels.len().is_multiple_of(width) || n > self.left {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "{} pixels are not whole rows of {width} within the {} rows left",
                    pixels.len(),
                    self.left
                ),
            ));
        }
        self.left -= n;
        // Rows per parallel task (about 64K pixels) and per batch written out at once.
        let block = (65536 / width).clamp(1, n.max(1));
        let batch = block * 4 * rayon::current_num_threads().max(1);
        for rows in pixels.chunks(batch * width) {
            let encoded: Vec<Vec<u8>> = rows
                .par_chunks(block * width)
                .map(|blk| {
                    let mut out = Vec::with_capacity(blk.len() * 4 + 64);
                    let mut comp: [Vec<u8>; 4] = std::array::from_fn(|_| Vec::with_capacity(width));
                    for row in blk.chunks_exact(width) {
                        encode_row(row, &mut out, &mut comp);
                    }
                    out
                })
                .collect();
            for e in &encoded {
                self.w.write_all(e)?;
            }
        }
        Ok(())
    }

    /// The writer, once every row was written; fails with `InvalidInput` while rows are
    /// missing.
    pub fn finish(self) -> io::Result<W> {
        if self.left > 0 {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("the picture lacks its last {} rows", self.left),
            ));
        }
        Ok(self.w)
    }
}

/// Write `img` as an RGBE picture to `path`, atomically (see [`super::output::write_atomic`]).
pub fn write_hdr_file(path: &Path, img: &Image) -> Result<(), ImageError> {
    super::check_writable(img).map_err(|reason| ImageError::Invalid {
        path: Some(path.to_path_buf()),
        reason,
    })?;
    super::output::write_atomic(path, |f| write_hdr(f, img)).map_err(|source| ImageError::Io {
        path: Some(path.to_path_buf()),
        source,
    })
}

// ---------------------------------------------------------------------------------------------
// Reading

fn bad(reason: impl std::fmt::Display) -> ImageError {
    ImageError::format(reason)
}

/// Read one line (including its `\n`) of at most `max` bytes. `Ok(None)` at end of input.
fn read_line<R: BufRead>(r: &mut R, max: u64, what: &str) -> Result<Option<Vec<u8>>, ImageError> {
    let mut line = Vec::new();
    let n = (&mut *r).take(max).read_until(b'\n', &mut line)?;
    if n == 0 {
        return Ok(None);
    }
    if line.last() != Some(&b'\n') {
        if n as u64 >= max {
            return Err(bad(format!("{what} longer than {max} bytes")));
        }
        return Err(bad(format!("truncated {what} (no end of line)")));
    }
    Ok(Some(line))
}

/// Strip a trailing `\n` and `\r`.
fn chomp(line: &[u8]) -> &[u8] {
    let line = line.strip_suffix(b"\n").unwrap_or(line);
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// Split a `VAR=value` line: the name is a C identifier directly followed by `=`.
fn split_var(line: &str) -> Option<(&str, &str)> {
    let eq = line.find('=')?;
    let name = &line[..eq];
    let mut chars = name.chars();
    let first = chars.next()?;
    if !(first.is_ascii_alphabetic() || first == '_')
        || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
    {
        return None;
    }
    Some((name, &line[eq + 1..]))
}

/// The first whitespace-separated word of `s` as a number.
fn first_number<T: std::str::FromStr>(s: &str) -> Option<T> {
    s.split_whitespace().next()?.parse().ok()
}

/// Read the header up to and including the blank line that ends it.
pub fn read_header<R: BufRead>(r: &mut R) -> Result<Header, ImageError> {
    match r.fill_buf()?.first() {
        None => return Err(bad("empty file, not a Radiance picture")),
        Some(&b) if !(0x20..0x7f).contains(&b) => {
            return Err(bad(
                "not a Radiance picture (binary data where the header should be)",
            ))
        }
        _ => {}
    }
    let mut h = Header {
        format: String::new(),
        ..Header::default()
    };
    let mut first = true;
    loop {
        let Some(raw) = read_line(r, MAX_HEADER_LINE, "header line")? else {
            return Err(bad(
                "truncated header (no blank line before the pixel data)",
            ));
        };
        let line = chomp(&raw);
        if line.is_empty() {
            break;
        }
        let was_first = std::mem::replace(&mut first, false);
        if was_first && line.starts_with(b"#?") {
            continue; // magic line: #?RADIANCE
        }
        let text = String::from_utf8_lossy(line);
        let Some((name, value)) = split_var(&text) else {
            h.commands.push(text.into_owned());
            continue;
        };
        let keep = |h: &mut Header| h.extra.push((name.to_string(), value.to_string()));
        match name {
            "FORMAT" => {
                let f = value.trim();
                if f != FORMAT_RGBE && f != FORMAT_XYZE {
                    return Err(bad(format!(
                        "unsupported pixel format '{f}' (expected {FORMAT_RGBE} or {FORMAT_XYZE})"
                    )));
                }
                h.format = f.to_string();
            }
            "EXPOSURE" => match first_number::<f64>(value) {
                Some(e) => h.exposure *= e,
                None => keep(&mut h),
            },
            "PIXASPECT" => match first_number::<f64>(value) {
                Some(a) => h.pixaspect = Some(h.pixaspect.unwrap_or(1.0) * a),
                None => keep(&mut h),
            },
            "SOFTWARE" => {
                if let Some(old) = h.software.replace(value.trim().to_string()) {
                    h.extra.push(("SOFTWARE".into(), format!(" {old}")));
                }
            }
            "VIEW" => {
                let v = value.trim();
                h.view = Some(match h.view.take() {
                    Some(old) if !v.is_empty() => format!("{old} {v}"),
                    Some(old) => old,
                    None => v.to_string(),
                });
            }
            "FRAME" => match first_number::<u32>(value) {
                Some(f) => h.frame = Some(f),
                None => keep(&mut h),
            },
            "PRIMARIES" => {
                let p = value.trim();
                // The standard primaries are what `None` stands for (and what the writer writes).
                h.primaries = (p != STD_PRIMARIES).then(|| p.to_string());
            }
            "TILED" => {
                let mut it = value.split_whitespace().map(str::parse::<u32>);
                match (it.next(), it.next()) {
                    (Some(Ok(x)), Some(Ok(y))) => h.tiled = Some((x, y)),
                    _ => keep(&mut h),
                }
            }
            _ => keep(&mut h),
        }
    }
    if h.format.is_empty() {
        h.format = FORMAT_RGBE.to_string(); // Radiance accepts pictures without FORMAT=
    }
    Ok(h)
}

/// Placement of the file's scanlines in the picture (Radiance's resolution-line orientation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Orientation {
    /// Scanlines are rows (`±Y H ±X W`); otherwise columns (`±X W ±Y H`).
    y_major: bool,
    /// `-X`: x decreases along the file (right to left).
    x_decr: bool,
    /// `-Y`: y decreases along the file (top to bottom; y counts up from the bottom).
    y_decr: bool,
}

/// Parse a resolution line: `{+-}Y H {+-}X W` or `{+-}X W {+-}Y H`. Returns (width, height,
/// orientation).
fn parse_resolution(line: &[u8]) -> Result<(usize, usize, Orientation), ImageError> {
    let text = String::from_utf8_lossy(chomp(line));
    let fail = || bad(format!("bad resolution line '{}'", text.escape_debug()));
    let tok: Vec<&str> = text.split_whitespace().collect();
    if tok.len() != 4 {
        return Err(fail());
    }
    let axis = |t: &str| -> Option<(bool, char)> {
        let b = t.as_bytes();
        if b.len() != 2 {
            return None;
        }
        let decr = match b[0] {
            b'-' => true,
            b'+' => false,
            _ => return None,
        };
        match b[1] {
            b'X' | b'Y' => Some((decr, b[1] as char)),
            _ => None,
        }
    };
    let num = |t: &str| -> Option<usize> {
        let n: u64 = t.parse().ok()?;
        (1..=MAX_SIDE).contains(&n).then_some(n as usize)
    };
    let (d1, a1) = axis(tok[0]).ok_or_else(fail)?;
    let (d2, a2) = axis(tok[2]).ok_or_else(fail)?;
    let (n1, n2) = (num(tok[1]).ok_or_else(fail)?, num(tok[3]).ok_or_else(fail)?);
    match (a1, a2) {
        ('Y', 'X') => Ok((
            n2,
            n1,
            Orientation {
                y_major: true,
                y_decr: d1,
                x_decr: d2,
            },
        )),
        ('X', 'Y') => Ok((
            n1,
            n2,
            Orientation {
                y_major: false,
                x_decr: d1,
                y_decr: d2,
            },
        )),
        _ => Err(fail()),
    }
}

fn eof_to_truncated(e: io::Error, line: usize, lines: usize) -> ImageError {
    if e.kind() == io::ErrorKind::UnexpectedEof {
        bad(format!(
            "truncated picture: end of file in scanline {} of {lines}",
            line + 1
        ))
    } else {
        ImageError::from(e)
    }
}

/// Read a Radiance picture (RGBE or XYZE). The pixels are returned top row first, left to
/// right, whatever the file's orientation; values are as stored (not divided by the exposure).
/// Reads exactly one picture, so several pictures concatenated in a stream can be read one
/// after the other.
pub fn read_hdr<R: BufRead>(r: &mut R) -> Result<Image, ImageError> {
    let header = read_header(r)?;
    let Some(resline) = read_line(r, 256, "resolution line")? else {
        return Err(bad("truncated picture: no resolution line"));
    };
    let (width, height, o) = parse_resolution(&resline)?;
    let total = width
        .checked_mul(height)
        .filter(|&t| t <= MAX_PIXELS)
        .ok_or_else(|| bad(format!("picture size {width}x{height} is too large")))?;
    // A valid run-length picture can be small on disk and huge in memory: check its pixels
    // against the memory there is before decoding (about 32 bytes a pixel: the encoded
    // pixels, the floats and a reader's copy), 2^30 pixels when that is unknown.
    let fits = crate::runinfo::available_memory()
        .map(|b| (b / 32) as usize)
        .unwrap_or(1 << 30);
    if total > fits {
        return Err(bad(format!(
            "picture size {width}x{height} needs about {:.1} GiB to read, more than this \
             machine has free",
            total as f64 * 32.0 / (1u64 << 30) as f64
        )));
    }
    let (line_len, lines) = if o.y_major {
        (width, height)
    } else {
        (height, width)
    };

    // Decode every scanline in file order; grow as data arrives so a bogus size in a short file
    // fails on the data instead of on a huge allocation.
    let mut raw: Vec<[u8; 4]> = Vec::with_capacity(total.min(1 << 22));
    let mut comp = Vec::new();
    for s in 0..lines {
        match read_scanline(r, line_len, &mut raw, &mut comp) {
            Ok(Ok(())) => {}
            Ok(Err(reason)) => {
                return Err(bad(format!(
                    "corrupt scanline {} of {lines}: {reason}",
                    s + 1
                )))
            }
            Err(e) => return Err(eof_to_truncated(e, s, lines)),
        }
    }

    let standard = Orientation {
        y_major: true,
        y_decr: true,
        x_decr: false,
    };
    let pixels: Vec<[f32; 3]> = if o == standard {
        raw.iter().map(|&p| rgbe_to_float(p)).collect()
    } else {
        let mut pixels = vec![[0.0f32; 3]; total];
        for (k, &p) in raw.iter().enumerate() {
            let (s, i) = (k / line_len, k % line_len);
            // (x, y) with y counted from the bottom, as Radiance's picture coordinates.
            let (x, y) = if o.y_major {
                let y = if o.y_decr { lines - 1 - s } else { s };
                let x = if o.x_decr { line_len - 1 - i } else { i };
                (x, y)
            } else {
                let x = if o.x_decr { lines - 1 - s } else { s };
                let y = if o.y_decr { line_len - 1 - i } else { i };
                (x, y)
            };
            pixels[(height - 1 - y) * width + x] = rgbe_to_float(p);
        }
        pixels
    };
    Ok(Image {
        width,
        height,
        pixels,
        header,
    })
}

/// Read a Radiance picture from a file; errors name the file.
pub fn read_hdr_file(path: &Path) -> Result<Image, ImageError> {
    let f = std::fs::File::open(path).map_err(|source| ImageError::Io {
        path: Some(path.to_path_buf()),
        source,
    })?;
    let mut r = io::BufReader::with_capacity(1 << 16, f);
    read_hdr(&mut r).map_err(|e| e.with_path(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_written_in_blocks_give_the_whole_pictures_bytes() {
        let (width, height) = (37, 11);
        let img = Image {
            width,
            height,
            pixels: (0..width * height)
                .map(|i| [i as f32 * 0.01, (i % 7) as f32, 0.5])
                .collect(),
            header: Header {
                commands: vec!["tpict -x 37".into()],
                ..Header::default()
            },
        };
        let mut whole = Vec::new();
        write_hdr(&mut whole, &img).unwrap();
        for block in [1, 2, 5, 11] {
            let mut rows = HdrRows::new(Vec::new(), &img.header, width, height).unwrap();
            for b in img.pixels.chunks(block * width) {
                rows.rows(b).unwrap();
            }
            assert_eq!(rows.finish().unwrap(), whole, "blocks of {block} rows");
        }
        // A partial row, rows past the end, a missing row or an empty size: errors.
        let mut rows = HdrRows::new(Vec::new(), &img.header, width, height).unwrap();
        assert!(rows.rows(&img.pixels[..width + 1]).is_err());
        assert!(rows.rows(&img.pixels[..width * 10]).is_ok());
        assert!(rows.rows(&img.pixels[..width * 2]).is_err());
        assert!(rows.finish().is_err());
        assert!(HdrRows::new(Vec::new(), &img.header, 0, 5).is_err());
    }

    #[test]
    fn c_exp_formats_like_printf() {
        assert_eq!(c_exp(2.0), "2.000000e+00");
        assert_eq!(c_exp(0.00123), "1.230000e-03");
        assert_eq!(c_exp(1.5e120), "1.500000e+120");
    }

    #[test]
    fn resolution_lines() {
        let (w, h, o) = parse_resolution(b"-Y       32 +X       48\n").unwrap();
        assert_eq!((w, h), (48, 32));
        assert_eq!(
            o,
            Orientation {
                y_major: true,
                y_decr: true,
                x_decr: false
            }
        );
        let (w, h, o) = parse_resolution(b"+X 3 -Y 2\r\n").unwrap();
        assert_eq!((w, h), (3, 2));
        assert_eq!(
            o,
            Orientation {
                y_major: false,
                y_decr: true,
                x_decr: false
            }
        );
        for bad in [
            &b"-Y 0 +X 3\n"[..],
            b"-Y 3 +Y 3\n",
            b"Y 3 X 3\n",
            b"-Y 3 +X\n",
            b"-Y -3 +X 3\n",
            b"-Y 3 +X 3 4\n",
        ] {
            assert!(
                parse_resolution(bad).is_err(),
                "{}",
                String::from_utf8_lossy(bad)
            );
        }
    }
}
