//! Radiance font files (`.fnt`) and the spacing of text lines: the library behind
//! `brighttext`, `colortext` and `mixtext` ([`super::text`]).
//!
//! # Format
//! ASCII integers separated by white space, `#` comments to the end of the line. A
//! sequence of glyphs `code nverts x1 y1 … xn yn`: `code` 1..=255 (each at most once),
//! `0 <= nverts <= 32000`, coordinates 0..=255 in a 255-unit cell with (0, 0) at the bottom
//! left. The polygon closes implicitly; holes and separate parts are joined by coincident
//! edges. `nverts = 0` is an existing, empty glyph (a space); an absent code has no glyph.
//! Errors name the file, the line and the reason.
//!
//! A glyph's extents are the minimum and maximum of its vertices. The font's `mwidth` and
//! `mheight` are the integer means (truncated) of the widths and heights of the glyphs whose
//! width and height are both non-zero.
//!
//! # Spacing ([`Font::layout`])
//! A line's characters get origins in font units along the line:
//! - **uniform** (spacing 0): every character with a glyph (a space too) advances 255, a
//!   character without a glyph advances nothing;
//! - **squeezed** (spacing s < 0): with c = trunc(|s|·255) and half = c/2 (integer), the ink
//!   boxes (glyph extents) are packed left to right with a gap of 2·half, the first box
//!   starting at 2·half; a space (empty glyph) takes `mwidth` units after a gap of half;
//!   characters without a glyph take no room;
//! - **proportional** (s > 0): the line is cut into segments, each ending after a
//!   character followed by at least 3 spaces (the spaces belong to the segment); each
//!   segment is squeezed as above, then stretched to (its character count)·(mwidth + c) by
//!   spreading the integer difference evenly over its characters (the first ones get the
//!   remainder), so each segment starts at a column of width mwidth + c.
//!
//! A point at font units (h, gy) of a line is inside the text if, for some character with
//! origin ≤ h and h − origin < 255, its glyph contains (h − origin, gy) ([`Glyph::contains`]).

use super::data::Tokens;
use std::path::Path;

/// Size of a glyph cell in font units.
pub const CELL: i64 = 255;

/// Where glyph extents start (see [`Glyph::new`]).
pub const CENTRE: i32 = 128;

/// Most vertices of one glyph.
pub const MAX_VERTS: i64 = 32000;

/// Segments of a proportionally spaced line end after this many spaces.
const SEGMENT_SPACES: usize = 3;

/// One character's outline.
#[derive(Clone, Debug, PartialEq)]
pub struct Glyph {
    /// Vertices (x, y) in font units.
    pub verts: Vec<[i32; 2]>,
    /// Smallest x.
    pub left: i32,
    /// Largest x.
    pub right: i32,
    /// Smallest y.
    pub bottom: i32,
    /// Largest y.
    pub top: i32,
}

impl Glyph {
    /// A glyph from its vertices. Its extents start at the cell's centre (128, 128) and
    /// grow to hold every vertex: as in Radiance (measured with rtrace 6.0a), a glyph
    /// entirely left of x = 128 still reaches 128 on the right, and so on.
    pub fn new(verts: Vec<[i32; 2]>) -> Glyph {
        let (mut l, mut r, mut b, mut t) = (CENTRE, CENTRE, CENTRE, CENTRE);
        for &[x, y] in &verts {
            l = l.min(x);
            r = r.max(x);
            b = b.min(y);
            t = t.max(y);
        }
        Glyph {
            verts,
            left: l,
            right: r,
            bottom: b,
            top: t,
        }
    }

    /// Whether the glyph has no outline (a space).
    pub fn is_empty(&self) -> bool {
        self.verts.is_empty()
    }

    /// Whether the point (x, y) (font units, relative to the cell) is inside the outline:
    /// the point is moved to the centre of its unit square (floor + ½), then the edges
    /// crossed by a ray toward +x are counted (odd = inside). Coincident edges cancel, which
    /// joins holes and parts.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        if self.verts.len() < 3 || !(x.is_finite() && y.is_finite()) {
            return false;
        }
        let (fx, fy) = (x.floor(), y.floor());
        if fx < self.left as f64
            || fx >= self.right as f64
            || fy < self.bottom as f64
            || fy >= self.top as f64
        {
            return false;
        }
        // Doubled coordinates: the test point is odd, vertices even, all exact integers.
        let tx = 2 * fx as i64 + 1;
        let ty = 2 * fy as i64 + 1;
        let n = self.verts.len();
        let mut inside = false;
        for k in 0..n {
            let a = self.verts[k];
            let b = self.verts[(k + 1) % n];
            let (ax, ay) = (2 * a[0] as i64, 2 * a[1] as i64);
            let (bx, by) = (2 * b[0] as i64, 2 * b[1] as i64);
            if (ay > ty) == (by > ty) {
                continue;
            }
            // Upward edge (lo → hi): the crossing is right of the point when the point is
            // left of the edge.
            let ((lx, ly), (hx, hy)) = if ay < by {
                ((ax, ay), (bx, by))
            } else {
                ((bx, by), (ax, ay))
            };
            let cross = (hx - lx) * (ty - ly) - (hy - ly) * (tx - lx);
            if cross > 0 {
                inside = !inside;
            }
        }
        inside
    }
}

/// A font: glyphs by character code.
#[derive(Clone, Debug, PartialEq)]
pub struct Font {
    /// Where it came from (for messages).
    pub name: String,
    glyphs: Vec<Option<Glyph>>,
    mwidth: i64,
    mheight: i64,
}

/// The origins of a line's characters (font units; None for characters without a glyph)
/// and the line's width.
#[derive(Clone, Debug, PartialEq)]
pub struct LineLayout {
    /// One origin per byte of the line.
    pub origins: Vec<Option<i64>>,
    /// Font units from the line's start to its end.
    pub width: i64,
}

impl Font {
    /// Read a font file.
    pub fn load(path: &Path) -> Result<Font, String> {
        let name = path.display().to_string();
        let text = std::fs::read(path).map_err(|e| format!("{name}: cannot read font: {e}"))?;
        Font::parse(&text, &name)
    }

    /// Parse font-file text; `name` is used in messages.
    pub fn parse(text: &[u8], name: &str) -> Result<Font, String> {
        let mut t = Tokens::new(text, name);
        let mut glyphs: Vec<Option<Glyph>> = vec![None; 256];
        let (mut ngv, mut sw, mut sh) = (0i64, 0i64, 0i64);
        while let Some(w) = t.next_word() {
            let s = std::str::from_utf8(w).unwrap_or("");
            let code = match s.parse::<i64>() {
                Ok(v) if crate::scene::lexer::is_int(s) => v,
                _ => {
                    return Err(t.err(format!(
                        "bad character code '{}' (not an integer)",
                        String::from_utf8_lossy(w)
                    )))
                }
            };
            if !(1..=255).contains(&code) {
                return Err(t.err(format!("illegal character code {code} (must be 1 to 255)")));
            }
            if glyphs[code as usize].is_some() {
                return Err(t.err(format!("character {code} is defined twice")));
            }
            let what = format!("vertex count of character {code}");
            let nv = t.int(&what)?;
            if !(0..=MAX_VERTS).contains(&nv) {
                return Err(t.err(format!("bad {what} {nv} (must be 0 to {MAX_VERTS})")));
            }
            let mut verts = Vec::with_capacity(nv as usize);
            for k in 1..=nv {
                let mut xy = [0i32; 2];
                for (c, axis) in xy.iter_mut().zip(["x", "y"]) {
                    let what = format!("{axis} of vertex {k} of character {code}");
                    let v = t.int(&what)?;
                    if !(0..=255).contains(&v) {
                        return Err(t.err(format!("{what} is {v} (must be 0 to 255)")));
                    }
                    *c = v as i32;
                }
                verts.push(xy);
            }
            let g = Glyph::new(verts);
            let (w, h) = ((g.right - g.left) as i64, (g.top - g.bottom) as i64);
            if w != 0 && h != 0 {
                ngv += 1;
                sw += w;
                sh += h;
            }
            glyphs[code as usize] = Some(g);
        }
        if glyphs.iter().all(Option::is_none) {
            return Err(t.err("no characters in font file"));
        }
        let (mwidth, mheight) = if ngv > 0 {
            (sw / ngv, sh / ngv)
        } else {
            (0, 0)
        };
        Ok(Font {
            name: name.to_string(),
            glyphs,
            mwidth,
            mheight,
        })
    }

    /// The glyph of character `c`, if the font has one.
    pub fn glyph(&self, c: u8) -> Option<&Glyph> {
        self.glyphs[c as usize].as_ref()
    }

    /// Number of characters with a glyph (empty ones included).
    pub fn count(&self) -> usize {
        self.glyphs.iter().filter(|g| g.is_some()).count()
    }

    /// Mean glyph width (font units).
    pub fn mwidth(&self) -> i64 {
        self.mwidth
    }

    /// Mean glyph height (font units).
    pub fn mheight(&self) -> i64 {
        self.mheight
    }

    /// The origins of the characters of `line` with `spacing` (module docs): uniform when
    /// c = trunc(spacing·255) is 0, squeezed by |c| when negative, proportional when
    /// positive.
    pub fn layout(&self, line: &[u8], spacing: f64) -> LineLayout {
        let c = (spacing * CELL as f64) as i64;
        if c < 0 {
            let sq = self.squeezed(line, -c);
            LineLayout {
                width: sq.end + sq.half,
                origins: sq.origins,
            }
        } else if c > 0 {
            self.proportional(line, c)
        } else {
            let mut origins = Vec::with_capacity(line.len());
            let mut pos = 0;
            for &ch in line {
                match self.glyph(ch) {
                    Some(_) => {
                        origins.push(Some(pos));
                        pos += CELL;
                    }
                    None => origins.push(None),
                }
            }
            LineLayout {
                origins,
                width: pos,
            }
        }
    }

    /// Squeezed spacing with a gap of `c` units (module docs).
    fn squeezed(&self, line: &[u8], c: i64) -> Squeezed {
        let half = c / 2;
        let mut origins = Vec::with_capacity(line.len());
        // Where the last ink box (or space) ended.
        let mut end = 0i64;
        let mut first = None;
        let mut last_space = false;
        for &ch in line {
            match self.glyph(ch) {
                None => origins.push(None),
                Some(g) if g.is_empty() => {
                    origins.push(Some(end));
                    first.get_or_insert(half);
                    end += self.mwidth;
                    last_space = true;
                }
                Some(g) => {
                    let o = end + 2 * half - g.left as i64;
                    origins.push(Some(o));
                    first.get_or_insert(g.left as i64);
                    end = o + g.right as i64;
                    last_space = false;
                }
            }
        }
        Squeezed {
            origins,
            end,
            half,
            // The width proportional spacing stretches (fitted to Radiance 6.0a, module
            // docs).
            width: if last_space {
                end
            } else {
                end + first.unwrap_or(0)
            },
        }
    }

    /// Proportional spacing: squeezed segments stretched to whole columns of mwidth + c.
    fn proportional(&self, line: &[u8], c: i64) -> LineLayout {
        let column = self.mwidth + c;
        let mut origins = Vec::with_capacity(line.len());
        let mut start = 0usize;
        let mut width = line.len() as i64 * column;
        while start < line.len() {
            let end = segment_end(line, start);
            let seg = &line[start..end];
            let sq = self.squeezed(seg, c);
            let n = seg.len() as i64;
            let base = start as i64 * column;
            let extra = n * column - sq.width;
            // Gap k (before character k, k = 1..n; gap n trails) gets extra/n, truncated;
            // the last |remainder| gaps get one unit more.
            let (each, rest) = (extra / n, extra % n);
            let mut shift = 0;
            for (k, o) in sq.origins.iter().enumerate() {
                let k = k as i64;
                if k > 0 {
                    shift += each + if k > n - rest.abs() { rest.signum() } else { 0 };
                }
                origins.push(o.map(|o| base + o + shift));
            }
            width = width.max(base + sq.end + shift + sq.half);
            start = end;
        }
        LineLayout { origins, width }
    }
}

/// A squeezed line: origins, where its last ink box or space ends, half the gap, and the
/// width that proportional spacing stretches.
struct Squeezed {
    origins: Vec<Option<i64>>,
    end: i64,
    half: i64,
    width: i64,
}

/// The end (exclusive) of the proportional-spacing segment starting at `start`: after the
/// spaces following the first character that is followed by at least
/// [`SEGMENT_SPACES`] spaces, or the end of the line.
fn segment_end(line: &[u8], start: usize) -> usize {
    let mut k = start;
    while k < line.len() {
        if line[k] != b' ' {
            let spaces = line[k + 1..].iter().take_while(|&&b| b == b' ').count();
            if spaces >= SEGMENT_SPACES {
                return k + 1 + spaces;
            }
        }
        k += 1;
    }
    line.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `I` of the reference (x 102..153, y 48..222), `A`-like and a space.
    const FONT: &[u8] = b"# test\n32 0\n73 5 153 222 153 48 102 48 102 222 153 222\n\
        65 3 20 40 230 40 125 230\n";

    #[test]
    fn extents_means_and_counts() {
        let f = Font::parse(FONT, "t.fnt").unwrap();
        assert_eq!(f.count(), 3);
        let i = f.glyph(b'I').unwrap();
        assert_eq!((i.left, i.right, i.bottom, i.top), (102, 153, 48, 222));
        assert!(f.glyph(b' ').unwrap().is_empty());
        assert!(f.glyph(b'B').is_none());
        // Means over I (51×174) and A (210×190), truncated.
        assert_eq!(f.mwidth(), (51 + 210) / 2);
        assert_eq!(f.mheight(), (174 + 190) / 2);
    }

    #[test]
    fn point_in_glyph() {
        let f = Font::parse(FONT, "t.fnt").unwrap();
        let i = f.glyph(b'I').unwrap();
        assert!(i.contains(128.0, 135.0));
        assert!(i.contains(102.0, 48.0));
        assert!(!i.contains(153.0, 100.0));
        assert!(!i.contains(101.9, 100.0));
        assert!(!i.contains(128.0, 222.0));
        // A shape with a hole joined by coincident edges: a square 0..10 with a hole 3..7.
        let ring = Glyph::new(vec![
            [0, 0],
            [10, 0],
            [10, 10],
            [0, 10],
            [0, 0],
            [3, 3],
            [3, 7],
            [7, 7],
            [7, 3],
            [3, 3],
        ]);
        assert!(ring.contains(1.0, 5.0));
        assert!(ring.contains(8.0, 5.0));
        assert!(!ring.contains(5.0, 5.0));
    }

    #[test]
    fn uniform_and_squeezed_spacing() {
        let f = Font::parse(FONT, "t.fnt").unwrap();
        let u = f.layout(b"IBI", 0.0);
        assert_eq!(u.origins, vec![Some(0), None, Some(255)]);
        assert_eq!(u.width, 510);
        // The reference: spacing -0.2 on `II` puts the ink at [50,101) and [151,202).
        let s = f.layout(b"II", -0.2);
        let ink: Vec<i64> = s.origins.iter().map(|o| o.unwrap() + 102).collect();
        assert_eq!(ink, vec![50, 151]);
        // A space takes mwidth after half a gap; a missing glyph takes no room.
        let sp = f.layout(b"I IBI", -0.2);
        let o: Vec<Option<i64>> = sp.origins.clone();
        assert_eq!(o[0], Some(-52));
        assert_eq!(o[1], Some(101));
        assert_eq!(o[3], None);
        assert_eq!(o[2].unwrap() + 102, 101 + f.mwidth() + 50);
        assert_eq!(o[4].unwrap() + 102, o[2].unwrap() + 153 + 50);
    }

    #[test]
    fn glyph_extents_start_at_the_cell_centre() {
        // Measured with rtrace 6.0a: a glyph left of x = 128 still reaches 128.
        let g = Glyph::new(vec![[10, 10], [60, 10], [60, 110], [10, 110]]);
        assert_eq!((g.left, g.right, g.bottom, g.top), (10, 128, 10, 128));
        let f = Font::parse(b"65 4 10 10 60 10 60 110 10 110", "f").unwrap();
        assert_eq!(f.mwidth(), 118);
    }

    /// Ink starts (origin + left of the drawn outline) of `text` in a font of one glyph
    /// `A` drawn at x 10..60 (extents 10..128, mwidth 118) and a space.
    fn ink(text: &[u8], spacing: f64) -> Vec<i64> {
        let f = Font::parse(b"32 0\n65 4 10 10 60 10 60 110 10 110", "f").unwrap();
        let l = f.layout(text, spacing);
        text.iter()
            .zip(&l.origins)
            .filter(|(&c, _)| c == b'A')
            .map(|(_, o)| o.unwrap() + 10)
            .collect()
    }

    #[test]
    fn squeezed_and_proportional_spacing_as_measured_with_rtrace() {
        // Ink positions (font units) measured with rtrace 6.0a.
        assert_eq!(ink(b"AAAA", -0.2), vec![50, 218, 386, 554]);
        assert_eq!(ink(b"A  A", -0.2), vec![50, 454]);
        assert_eq!(ink(b" A", -0.2), vec![168]);
        assert_eq!(ink(b"AAAA", 0.2), vec![50, 217, 384, 550]);
        assert_eq!(ink(b"AAAAAA", 0.2), vec![50, 218, 386, 553, 720, 887]);
        assert_eq!(ink(b"A A", 0.2), vec![50, 364]);
        assert_eq!(ink(b"A  A", 0.2), vec![50, 524]);
        assert_eq!(ink(b"A   A", 0.2), vec![50, 726]);
        assert_eq!(ink(b"AA   AA", 0.2), vec![50, 249, 895, 1059]);
        assert_eq!(ink(b"AAA    AA", 0.2), vec![50, 247, 444, 1233, 1397]);
        assert_eq!(ink(b"A A    A", 0.2), vec![50, 408, 1233]);
        assert_eq!(ink(b" A", 0.2), vec![181]);
        assert_eq!(ink(b"  AA", 0.2), vec![325, 513]);
        // A spacing below one font unit is uniform.
        assert_eq!(ink(b"AA", -0.0001), vec![10, 265]);
        assert_eq!(segment_end(b"II   AI", 0), 5);
        assert_eq!(segment_end(b"I  I", 0), 4);
    }

    #[test]
    fn errors_name_file_line_and_reason() {
        let cases: &[(&[u8], &str)] = &[
            (b"", "f:1: no characters"),
            (b"0 0", "f:1: illegal character code 0"),
            (b"256 0", "f:1: illegal character code 256"),
            (b"65 0\n65 0", "f:2: character 65 is defined twice"),
            (b"65 -1", "f:1: bad vertex count of character 65 -1"),
            (
                b"65 2\n1 2 3",
                "f:2: unexpected end of file: missing y of vertex 2",
            ),
            (b"65 1 1 300", "f:1: y of vertex 1 of character 65 is 300"),
            (b"65 1 1 x", "f:1: bad y of vertex 1 of character 65 'x'"),
            (b"A 1 1 1", "f:1: bad character code 'A'"),
        ];
        for (text, want) in cases {
            let e = Font::parse(text, "f").unwrap_err();
            assert!(e.starts_with(want), "{e:?} should start with {want:?}");
        }
    }
}
