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
use super::font::{Font, LineLayout, CELL};
use super::{MixCoefficient, ModifierKind, ModifierLookup, Pattern};
use crate::color::Color;
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use glam::DVec3;
use std::sync::Arc;

/// Text-file lines longer than this are split (Radiance's line buffer).
pub const MAX_LINE: usize = 511;

/// Laid-out text in its frame: the geometry shared by the three types.
#[derive(Debug)]
pub struct Text {
    font: Arc<Font>,
    lines: Vec<(Vec<u8>, LineLayout)>,
    origin: DVec3,
    /// Dual of R: x = (P − O)·rstar.
    rstar: DVec3,
    /// Dual of D: y = (P − O)·dstar.
    dstar: DVec3,
    /// Font units per unit of x along a line.
    hscale: f64,
}

impl Text {
    /// Lay out `lines` with `font` in the frame (O, R, D) with `spacing`.
    pub fn new(
        font: Arc<Font>,
        lines: Vec<Vec<u8>>,
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
        let lines = lines
            .into_iter()
            .map(|l| {
                let lay = font.layout(&l, spacing.unwrap_or(0.0));
                (l, lay)
            })
            .collect();
        Ok(Text {
            font,
            lines,
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
        let Some((text, lay)) = self.lines.get(line as usize).filter(|_| line < 1e9) else {
            return false;
        };
        let gy = (line + 1.0 - y) * CELL as f64;
        let h = x * self.hscale;
        if h >= lay.width as f64 {
            return false;
        }
        text.iter().zip(&lay.origins).any(|(&c, o)| {
            let Some(o) = *o else { return false };
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

/// The lines of a text file (found along the RAYPATH): one per line, newline stripped,
/// lines longer than [`MAX_LINE`] bytes split.
pub fn read_text_file(files: &SceneFiles, name: &str) -> Result<Vec<Vec<u8>>, String> {
    let path = files.find(name)?;
    let bytes = std::fs::read(&path)
        .map_err(|e| format!("{}: cannot read text file: {e}", path.display()))?;
    Ok(split_lines(&bytes))
}

/// Text-file bytes as lines (see [`read_text_file`]).
pub fn split_lines(bytes: &[u8]) -> Vec<Vec<u8>> {
    let mut lines = Vec::new();
    let mut rest = bytes;
    while !rest.is_empty() {
        let (line, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(k) => (&rest[..k], &rest[k + 1..]),
            None => (rest, &rest[rest.len()..]),
        };
        if line.is_empty() {
            lines.push(Vec::new());
        }
        for part in line.chunks(MAX_LINE) {
            lines.push(part.to_vec());
        }
        rest = next;
    }
    lines
}

/// Font and text from string arguments `font textfile` or `font . word ...`.
fn font_and_lines(
    sargs: &[String],
    files: &SceneFiles,
) -> Result<(Arc<Font>, Vec<Vec<u8>>), String> {
    let font = files.font(&sargs[0])?;
    let lines = if sargs.len() == 2 {
        read_text_file(files, &sargs[1])?
    } else {
        vec![sargs[2..].join(" ").into_bytes()]
    };
    Ok((font, lines))
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
    let (font, lines) = font_and_lines(strings, files)?;
    let (o, r, d) = frame(&p.rargs);
    Text::new(font, lines, o, r, d, spacing)
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
            vec![words.as_bytes().to_vec()],
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
        let t = Text::new(f.clone(), vec![b"AI".to_vec()], o, r, d, None).unwrap();
        assert!(t.inside(o + 1.5 * r + 0.5 * d + DVec3::new(0.0, 0.0, 3.0)));
        assert!(!t.inside(o + 1.3 * r + 0.5 * d));
        let e = Text::new(f, vec![], o, r, 2.0 * r, None).unwrap_err();
        assert_eq!(e, "illegal motion vector");
    }

    #[test]
    fn text_file_lines() {
        assert_eq!(
            split_lines(b"AB\n\nCD"),
            vec![b"AB".to_vec(), vec![], b"CD".to_vec()]
        );
        let long = vec![b'x'; 600];
        let l = split_lines(&long);
        assert_eq!((l.len(), l[0].len(), l[1].len()), (2, 511, 89));
        assert_eq!(split_lines(b"A\n").len(), 1);
    }
}
