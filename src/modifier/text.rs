//! The text patterns `brighttext`, `colortext` and the mixture `mixtext` (Radiance's
//! text.c rules; fonts and spacing in [`super::font`]).
//!
//! ```text
//! mod brighttext id  2 font textfile            0  11+ Ox Oy Oz Rx Ry Rz Dx Dy Dz fore back [spacing]
//! mod brighttext id  N font . word1 word2 ..    0  11+ (same)
//! mod colortext  id  (same strings)             0  15+ O R D fr fg fb br bg bb [spacing]
//! void mixtext   id  4 fore back font textfile  0  9+ O R D [spacing]    (or fore back font . words)
//! ```
//! O is the text's upper-left corner, R one character cell to the right, D one line down.
//! A text file holds one text line per line (the newline stripped; lines longer than 511
//! bytes are split); inline words are joined by single spaces into one line. Font and text
//! files are found along the RAYPATH ([`super::files::SceneFiles`]).
//!
//! There is no function file and no transform: the point is the hit in world coordinates
//! (in the instance's or mesh's own frame when the hit came through one). v = P − O is
//! written in the oblique (R, D) basis with dual vectors (x = v·r*, r* ⊥ D, r*·R = 1;
//! y = v·d*, d* ⊥ R, d*·D = 1); the normal component is ignored. x < 0 or y < 0 is
//! background. Line `trunc(y)`, glyph height gy = (line + 1 − y)·255, position along the
//! line h = x·255 (uniform spacing) or x·(mwidth + 255·|spacing|).
//!
//! `brighttext`/`colortext` are patterns: the foreground colour inside glyphs, the
//! background outside. `mixtext` is a mixture with coefficient 1 inside glyphs (the
//! foreground modifier) and 0 outside (the background).

use super::files::SceneFiles;
use super::font::{Font, CELL};
use super::{MixCoefficient, ModifierKind, ModifierLookup, Pattern};
use crate::color::Color;
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use glam::DVec3;
use std::sync::Arc;

/// Text-file lines longer than this are split (Radiance's line buffer).
pub const MAX_LINE: usize = 511;

/// Laid-out text in its frame: the geometry shared by the three types.
///
/// The lines are packed (every line's bytes one after the other, one glyph origin per
/// byte, and a start and a width per line): a text of many short lines costs about 9 bytes
/// a character and 12 a line, not an allocation or two per line.
#[derive(Debug)]
pub struct Text {
    font: Arc<Font>,
    /// Every line's bytes, one after the other.
    bytes: Vec<u8>,
    /// The glyph origin of each byte ([`NO_GLYPH`]: none).
    origins: Vec<i64>,
    /// Where each line starts in `bytes`, and a last entry: the end of the last line.
    starts: Vec<u32>,
    /// Each line's width in font units.
    widths: Vec<i64>,
    origin: DVec3,
    /// Dual of R: x = (P − O)·rstar.
    rstar: DVec3,
    /// Dual of D: y = (P − O)·dstar.
    dstar: DVec3,
    /// Font units per unit of x along a line.
    hscale: f64,
}

/// The origin of a byte without a glyph.
const NO_GLYPH: i64 = i64::MIN;

/// Most bytes a text may hold (its lines' starts are 32-bit).
const MAX_TEXT_BYTES: usize = u32::MAX as usize;

impl Text {
    /// Lay out `lines` with `font` in the frame (O, R, D) with `spacing`.
    pub fn new<'a>(
        font: Arc<Font>,
        lines: impl IntoIterator<Item = &'a [u8]>,
        o: DVec3,
        r: DVec3,
        d: DVec3,
        spacing: Option<f64>,
    ) -> Result<Text, String> {
        let n = r.cross(d);
        let rs = d.cross(n);
        let ds = n.cross(r);
        let (rd, dd) = (r.dot(rs), d.dot(ds));
        if n.length_squared() == 0.0 || !(rd.is_normal() && dd.is_normal()) {
            return Err("illegal motion vector".into());
        }
        // With a spacing argument (even 0) the scale is mwidth + 255·|spacing| (Radiance
        // 6.0a, measured), without one 255.
        let hscale = match spacing {
            None => CELL as f64,
            Some(s) => font.mwidth() as f64 + CELL as f64 * s.abs(),
        };
        let (mut bytes, mut origins, mut starts, mut widths) =
            (Vec::new(), Vec::new(), vec![0u32], Vec::new());
        for l in lines {
            if bytes.len() + l.len() > MAX_TEXT_BYTES {
                return Err(format!("text of more than {MAX_TEXT_BYTES} bytes"));
            }
            let lay = font.layout(l, spacing.unwrap_or(0.0));
            bytes.extend_from_slice(l);
            origins.extend(lay.origins.iter().map(|o| o.unwrap_or(NO_GLYPH)));
            starts.push(bytes.len() as u32);
            widths.push(lay.width);
        }
        bytes.shrink_to_fit();
        origins.shrink_to_fit();
        starts.shrink_to_fit();
        widths.shrink_to_fit();
        Ok(Text {
            font,
            bytes,
            origins,
            starts,
            widths,
            origin: o,
            rstar: rs / rd,
            dstar: ds / dd,
            hscale,
        })
    }

    /// Whether the point `p` (in the text's frame) is inside a glyph.
    pub fn inside(&self, p: DVec3) -> bool {
        let v = p - self.origin;
        let (x, y) = (v.dot(self.rstar), v.dot(self.dstar));
        if !(x >= 0.0 && y >= 0.0) {
            return false;
        }
        let line = y.trunc();
        let Some(&width) = self.widths.get(line as usize).filter(|_| line < 1e10) else {
            return false;
        };
        let k = line as usize;
        let (a, b) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        let gy = (line + 1.0 - y) * CELL as f64;
        let h = x * self.hscale;
        if h >= width as f64 {
            return false;
        }
        let (text, origins) = (&self.bytes[a..b], &self.origins[a..b]);
        text.iter().zip(origins).any(|(&c, &o)| {
            if o == NO_GLYPH {
                return false;
            }
            let dx = h - o as f64;
            dx >= 0.0 && dx < CELL as f64 && self.font.glyph(c).is_some_and(|g| g.contains(dx, gy))
        })
    }

    /// Whether the shading point is inside a glyph (world coordinates, or the local frame of
    /// the object's transform when it has one).
    pub fn inside_at(&self, sp: &ShadingPoint) -> bool {
        let w = sp.world_point();
        let p = match sp.transform {
            Some(t) => t.inverse().transform_point3(w),
            None => w,
        };
        self.inside(p)
    }
}

/// `brighttext` and `colortext`: the foreground colour inside glyphs, the background
/// outside.
#[derive(Debug)]
pub struct TextPattern {
    /// The text.
    pub text: Text,
    /// Colour inside glyphs.
    pub fore: Color,
    /// Colour outside.
    pub back: Color,
}

impl Pattern for TextPattern {
    fn colour(&self, sp: &ShadingPoint) -> Option<Color> {
        Some(if self.text.inside_at(sp) {
            self.fore
        } else {
            self.back
        })
    }
}

/// `mixtext`'s coefficient: 1 inside glyphs, 0 outside.
#[derive(Debug)]
pub struct TextMix {
    /// The text.
    pub text: Text,
}

impl MixCoefficient for TextMix {
    fn coefficient(&self, sp: &ShadingPoint) -> Option<f64> {
        Some(if self.text.inside_at(sp) { 1.0 } else { 0.0 })
    }
}

/// The bytes of a text file (found along the RAYPATH), at most [`MAX_TEXT_BYTES`].
pub fn read_text_file(files: &SceneFiles, name: &str) -> Result<Vec<u8>, String> {
    let path = files.find(name)?;
    crate::safefile::read_bounded_following(&path, MAX_TEXT_BYTES as u64)
        .map_err(|e| format!("{}: cannot read text file: {e}", path.display()))
}

/// A text file's lines: one per line, newline stripped, lines longer than [`MAX_LINE`]
/// bytes split.
pub fn split_lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = bytes;
    let mut parts: std::slice::Chunks<'_, u8> = [].chunks(MAX_LINE);
    let mut empty = false;
    std::iter::from_fn(move || loop {
        if empty {
            empty = false;
            return Some(&[][..]);
        }
        if let Some(p) = parts.next() {
            return Some(p);
        }
        if rest.is_empty() {
            return None;
        }
        let (line, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(k) => (&rest[..k], &rest[k + 1..]),
            None => (rest, &rest[rest.len()..]),
        };
        empty = line.is_empty();
        parts = line.chunks(MAX_LINE);
        rest = next;
    })
}

/// Font and text from string arguments `font textfile` or `font . word ...`.
fn font_and_text(sargs: &[String], files: &SceneFiles) -> Result<(Arc<Font>, Vec<u8>), String> {
    let font = files.font(&sargs[0])?;
    let text = if sargs.len() == 2 {
        read_text_file(files, &sargs[1])?
    } else {
        sargs[2..].join(" ").into_bytes()
    };
    Ok((font, text))
}

/// O, R, D from the first nine reals.
fn frame(r: &[f64]) -> (DVec3, DVec3, DVec3) {
    (
        DVec3::new(r[0], r[1], r[2]),
        DVec3::new(r[3], r[4], r[5]),
        DVec3::new(r[6], r[7], r[8]),
    )
}

/// The text of a primitive whose strings from `first` on are `font textfile|. words` and
/// whose reals are O R D, `colours` more, and an optional spacing.
fn parse_text(
    p: &Primitive,
    first: usize,
    colours: usize,
    files: &SceneFiles,
) -> Result<Text, String> {
    let strings = &p.sargs[first.min(p.sargs.len())..];
    if strings.len() < 2 {
        let want = if first > 0 {
            "fore back font textfile (or fore back font . words)"
        } else {
            "font textfile (or font . words)"
        };
        return Err(format!("needs the string arguments {want}"));
    }
    if !p.iargs.is_empty() {
        return Err("takes no integer arguments".into());
    }
    let n = 9 + colours;
    if p.rargs.len() != n && p.rargs.len() != n + 1 {
        return Err(format!(
            "takes {n} or {} real arguments (O R D{} [spacing]), got {}",
            n + 1,
            match colours {
                2 => " fore back",
                6 => " fore-rgb back-rgb",
                _ => "",
            },
            p.rargs.len()
        ));
    }
    let spacing = p.rargs.get(n).copied();
    let (font, text) = font_and_text(strings, files)?;
    let (o, r, d) = frame(&p.rargs);
    if strings.len() == 2 {
        Text::new(font, split_lines(&text), o, r, d, spacing)
    } else {
        Text::new(font, [&text[..]], o, r, d, spacing)
    }
}

/// Parser of `brighttext`.
pub fn parse_brighttext(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let text = parse_text(p, 0, 2, l.files())?;
    let (f, b) = (p.rargs[9], p.rargs[10]);
    Ok(ModifierKind::Pattern(Box::new(TextPattern {
        text,
        fore: Color::new(f, f, f),
        back: Color::new(b, b, b),
    })))
}

/// Parser of `colortext`.
pub fn parse_colortext(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let text = parse_text(p, 0, 6, l.files())?;
    let r = &p.rargs;
    Ok(ModifierKind::Pattern(Box::new(TextPattern {
        text,
        fore: Color::new(r[9], r[10], r[11]),
        back: Color::new(r[12], r[13], r[14]),
    })))
}

/// Parser of `mixtext`.
pub fn parse_mixtext(p: &Primitive, l: &dyn ModifierLookup) -> Result<ModifierKind, String> {
    let text = parse_text(p, 2, 0, l.files())?;
    Ok(ModifierKind::Mixture {
        coef: Box::new(TextMix { text }),
        foreground: l.modref(&p.sargs[0])?,
        background: l.modref(&p.sargs[1])?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference's `I` and an `A`-like triangle.
    const FONT: &[u8] = b"32 0\n73 5 153 222 153 48 102 48 102 222 153 222\n\
        65 3 20 40 230 40 125 230\n";

    fn text(words: &str, spacing: Option<f64>) -> Text {
        let f = Arc::new(Font::parse(FONT, "t.fnt").unwrap());
        Text::new(
            f,
            [words.as_bytes()],
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::X,
            -DVec3::Y,
            spacing,
        )
        .unwrap()
    }

    #[test]
    fn the_reference_points_of_ai() {
        let t = text("AI", None);
        let p = |x: f64, y: f64| t.inside(DVec3::new(x, y, 0.0));
        assert!(p(1.502, 0.5294)); // in I
        assert!(!p(1.3, 0.5294));
        assert!(p(0.502, 0.8)); // A
        assert!(!p(-0.1, 0.5));
        assert!(!p(0.5, 1.1)); // y < 0
        assert!(!p(2.1, 0.5)); // past the line
        assert!(!p(0.5, -0.5)); // no second line
    }

    #[test]
    fn squeezed_ink_ranges_of_ii() {
        let t = text("II", Some(-0.2));
        let hs = t.font.mwidth() as f64 + 0.2 * 255.0;
        // A point at font unit h along the line, in the middle of the glyph height.
        let at = |h: f64| t.inside(DVec3::new((h + 0.5) / hs, 1.0 - 135.0 / 255.0, 0.0));
        assert!(at(75.0));
        assert!(at(175.0));
        assert!(!at(140.0));
        assert!(at(50.0) && !at(49.0) && at(100.0) && !at(101.0));
        assert!(at(151.0) && !at(150.0) && at(201.0) && !at(202.0));
    }

    #[test]
    fn oblique_frames_and_bad_vectors() {
        let f = Arc::new(Font::parse(FONT, "t.fnt").unwrap());
        // R and D not perpendicular: the point O + 1.5 R + 0.5 D is in the I.
        let (o, r, d) = (
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.5, -1.0, 0.0),
        );
        let t = Text::new(f.clone(), [&b"AI"[..]], o, r, d, None).unwrap();
        assert!(t.inside(o + 1.5 * r + 0.5 * d + DVec3::new(0.0, 0.0, 3.0)));
        assert!(!t.inside(o + 1.3 * r + 0.5 * d));
        let e = Text::new(f, [], o, r, 2.0 * r, None).unwrap_err();
        assert_eq!(e, "illegal motion vector");
    }

    #[test]
    fn text_file_lines() {
        let lines = |b: &[u8]| split_lines(b).map(|l| l.to_vec()).collect::<Vec<_>>();
        assert_eq!(
            lines(b"AB\n\nCD"),
            vec![b"AB".to_vec(), vec![], b"CD".to_vec()]
        );
        let long = vec![b'x'; 600];
        let l = lines(&long);
        assert_eq!((l.len(), l[0].len(), l[1].len()), (2, 511, 89));
        assert_eq!(lines(b"A\n").len(), 1);
        assert_eq!(lines(b"\n\nA").len(), 3);
        assert!(lines(b"").is_empty());
    }

    /// A text of many short lines is packed: about 9 bytes a character and 12 a line.
    #[test]
    fn many_short_lines_are_packed() {
        let f = Arc::new(Font::parse(FONT, "t.fnt").unwrap());
        let src = b"AI\n".repeat(100_000);
        let t = Text::new(f, split_lines(&src), DVec3::ZERO, DVec3::X, -DVec3::Y, None).unwrap();
        assert_eq!(t.widths.len(), 100_000);
        let held = t.bytes.capacity()
            + 8 * t.origins.capacity()
            + 4 * t.starts.capacity()
            + 8 * t.widths.capacity();
        assert!(held <= 100_000 * (2 * 9 + 12 + 1), "{held}");
        // Line 77,777 still reads: its I.
        assert!(t.inside(DVec3::new(1.502, -77_777.470_6, 0.0)));
        assert!(!t.inside(DVec3::new(1.3, -77_777.470_6, 0.0)));
        assert!(!t.inside(DVec3::new(1.502, -100_000.470_6, 0.0)));
    }
}
