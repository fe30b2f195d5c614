//! Radiance data files (`.dat`): N-dimensional arrays of values on a grid, interpolated and
//! extrapolated exactly as Radiance does. The library behind `brightdata`, `colordata`,
//! `texdata` and `mixdata` (which also need the function language), and, through
//! [`super::picdata`], behind `colorpict` and `mixpict`.
//!
//! # Format
//! ASCII tokens separated by white space; `#` starts a comment to the end of the line
//! anywhere (`12#x` is `12`).
//! ```text
//! N                          number of dimensions, 1..=6
//! beg end n                  per dimension: n >= 2 evenly spaced points from beg to end
//!                            (beg > end allowed), or, when beg == end,
//! beg beg n p1 .. pn         n explicit, strictly monotonic coordinates
//! v1 .. v(n1*..*nN)          the values, row-major: the LAST dimension varies fastest
//! ```
//! Values are kept as `f32`, as Radiance does. Errors name the file, the line and the
//! reason: a token that is not a number, a file that ends early, a dimension count or size
//! out of range, explicit coordinates that are not strictly monotonic, more than
//! [`MAX_VALUES`] values, or a value that is not finite (or too large for `f32`). Anything
//! after the last value is ignored, as Radiance does.
//!
//! # Interpolation ([`DataArray::interp`])
//! Per dimension with coordinate p, the fractional index is x = (p − beg)/(end − beg)·(n − 1)
//! (even spacing) or, for explicit coordinates, x = i + (p − p_i)/(p_{i+1} − p_i) with i the
//! interval holding p (the first or last interval outside the range). With i = trunc(x)
//! clamped to [0, n − 2], the weights of the values at i and i + 1 are
//! - linear, c0 = i + 1 − x, c1 = x − i, for i − 1 ≤ x ≤ i + 2 (interpolation, and one grid
//!   step of linear extrapolation beyond either end);
//! - c1 = 1/(x − i), c0 = −2·c1 below that (continuous at x = −1);
//! - c0 = 1/(i − 1 − x), c1 = −2·c0 above it (discontinuous at x = n: the weights jump from
//!   (−1, 2) to (−⅓, ⅔), as in Radiance).
//!
//! Both tails decay like 1/|x|. Dimensions combine multilinearly (the first dimension's
//! weights apply to the interpolated sub-arrays). Nothing is clamped: results may be
//! negative.
//!
//! # Use (for the function-language wiring)
//! `DataArray::load(path)` (or [`super::files::SceneFiles::data`], which finds the file on
//! the RAYPATH and reads it once per scene), `dims()` (one coordinate expression per
//! dimension), then `interp(&coords)` per ray.

use std::path::Path;

/// Most dimensions a data file may have (Radiance's MAXDDIM).
pub const MAX_DIMS: usize = 6;

/// Most values a data file may hold (2^28: 1 GiB of `f32`).
pub const MAX_VALUES: usize = 1 << 28;

/// The grid of one dimension.
#[derive(Clone, Debug, PartialEq)]
pub enum Axis {
    /// `n` points evenly spaced from `beg` to `end` (either order).
    Even {
        /// First coordinate.
        beg: f64,
        /// Last coordinate.
        end: f64,
        /// Number of points (>= 2, or 1 for a picture one pixel wide).
        n: usize,
    },
    /// Explicit, strictly monotonic coordinates (at least 2).
    Explicit(Vec<f64>),
}

impl Axis {
    /// Number of grid points.
    pub fn len(&self) -> usize {
        match self {
            Axis::Even { n, .. } => *n,
            Axis::Explicit(p) => p.len(),
        }
    }

    /// Never true (an axis has at least one point).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The fractional index of coordinate `p` on this axis.
    fn index(&self, p: f64) -> f64 {
        match self {
            Axis::Even { beg, end, n } => (p - beg) / (end - beg) * (*n as f64 - 1.0),
            Axis::Explicit(c) => {
                let n = c.len();
                let up = c[n - 1] > c[0];
                // Number of coordinates at or "before" p, minus one, clamped to [0, n-2].
                let before = if up {
                    c.partition_point(|&q| q <= p)
                } else {
                    c.partition_point(|&q| q >= p)
                };
                let i = before.saturating_sub(1).min(n - 2);
                i as f64 + (p - c[i]) / (c[i + 1] - c[i])
            }
        }
    }
}

/// The interval and the weights of its two ends for fractional index `x` on an axis of
/// `n >= 2` points (Radiance's rules, see the module docs): `(i, c0, c1)`.
pub fn weights(x: f64, n: usize) -> (usize, f64, f64) {
    debug_assert!(n >= 2);
    let top = (n - 2) as f64;
    let t = x.trunc();
    let fi = if t.is_nan() { 0.0 } else { t.clamp(0.0, top) };
    let i = fi as usize;
    if x < fi - 1.0 {
        let c1 = 1.0 / (x - fi);
        (i, -2.0 * c1, c1)
    } else if x > fi + 2.0 {
        let c0 = 1.0 / (fi - 1.0 - x);
        (i, c0, -2.0 * c0)
    } else {
        (i, fi + 1.0 - x, x - fi)
    }
}

/// A data file's array.
#[derive(Clone, Debug, PartialEq)]
pub struct DataArray {
    /// Where it came from (for messages).
    pub name: String,
    axes: Vec<Axis>,
    values: Vec<f32>,
}

/// Tokens of an ASCII data or font file: words separated by white space, `#` comments to
/// the end of the line, each with its line number.
pub(crate) struct Tokens<'a> {
    text: &'a [u8],
    pos: usize,
    line: u32,
    /// File name for messages.
    pub name: &'a str,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(text: &'a [u8], name: &'a str) -> Tokens<'a> {
        Tokens {
            text,
            pos: 0,
            line: 1,
            name,
        }
    }

    /// An error at the current line.
    pub(crate) fn err(&self, reason: impl std::fmt::Display) -> String {
        format!("{}:{}: {reason}", self.name, self.line)
    }

    /// The next word, or None at the end.
    pub(crate) fn next_word(&mut self) -> Option<&'a [u8]> {
        let t = self.text;
        loop {
            match t.get(self.pos) {
                None => return None,
                Some(b'\n') => {
                    self.line += 1;
                    self.pos += 1;
                }
                Some(b'#') => {
                    while self.pos < t.len() && t[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                Some(c) if c.is_ascii_whitespace() => self.pos += 1,
                Some(_) => break,
            }
        }
        let start = self.pos;
        while self.pos < t.len() && !t[self.pos].is_ascii_whitespace() && t[self.pos] != b'#' {
            self.pos += 1;
        }
        Some(&t[start..self.pos])
    }

    fn word(&mut self, what: &str) -> Result<&'a [u8], String> {
        self.next_word()
            .ok_or_else(|| self.err(format!("unexpected end of file: missing {what}")))
    }

    /// The next word as an integer.
    pub(crate) fn int(&mut self, what: &str) -> Result<i64, String> {
        let w = self.word(what)?;
        let s = std::str::from_utf8(w).unwrap_or("");
        match s.parse::<i64>() {
            Ok(v) if crate::scene::lexer::is_int(s) => Ok(v),
            _ => Err(self.err(format!(
                "bad {what} '{}' (not an integer)",
                String::from_utf8_lossy(w)
            ))),
        }
    }

    /// The next word as a finite real.
    pub(crate) fn real(&mut self, what: &str) -> Result<f64, String> {
        let w = self.word(what)?;
        let s = std::str::from_utf8(w).unwrap_or("");
        match s.parse::<f64>() {
            Ok(v) if crate::scene::lexer::is_real(s) && v.is_finite() => Ok(v),
            Ok(_) if crate::scene::lexer::is_real(s) => {
                Err(self.err(format!("{what} '{s}' is not a finite number")))
            }
            _ => Err(self.err(format!(
                "bad {what} '{}' (not a number)",
                String::from_utf8_lossy(w)
            ))),
        }
    }
}

impl DataArray {
    /// Read a data file.
    pub fn load(path: &Path) -> Result<DataArray, String> {
        let name = path.display().to_string();
        let text =
            std::fs::read(path).map_err(|e| format!("{name}: cannot read data file: {e}"))?;
        DataArray::parse(&text, &name)
    }

    /// Parse data-file text; `name` is used in messages.
    pub fn parse(text: &[u8], name: &str) -> Result<DataArray, String> {
        let mut t = Tokens::new(text, name);
        let nd = t.int("number of dimensions")?;
        if !(1..=MAX_DIMS as i64).contains(&nd) {
            return Err(t.err(format!(
                "bad number of dimensions {nd} (must be 1 to {MAX_DIMS})"
            )));
        }
        let mut axes = Vec::with_capacity(nd as usize);
        let mut total: usize = 1;
        for d in 1..=nd {
            let beg = t.real(&format!("start of dimension {d}"))?;
            let end = t.real(&format!("end of dimension {d}"))?;
            let n = t.int(&format!("size of dimension {d}"))?;
            if n < 2 {
                return Err(t.err(format!(
                    "dimension {d} has {n} points (at least 2 are needed)"
                )));
            }
            if n as u64 > MAX_VALUES as u64 || total.saturating_mul(n as usize) > MAX_VALUES {
                return Err(t.err(format!(
                    "too many values (more than {MAX_VALUES}) in dimension {d}"
                )));
            }
            let n = n as usize;
            total *= n;
            if beg == end {
                let mut p: Vec<f64> = Vec::with_capacity(n.min(1 << 16));
                for k in 1..=n {
                    let v = t.real(&format!("coordinate {k} of {n} of dimension {d}"))?;
                    if let (Some(&a), Some(&b)) = (p.get(p.len().wrapping_sub(2)), p.last()) {
                        if (b - a) * (v - b) <= 0.0 {
                            return Err(t.err(format!(
                                "coordinates of dimension {d} are not strictly monotonic \
                                 ({a}, {b}, {v})"
                            )));
                        }
                    } else if p.last() == Some(&v) {
                        return Err(t.err(format!(
                            "coordinates of dimension {d} are not strictly monotonic \
                             ({v} repeated)"
                        )));
                    }
                    p.push(v);
                }
                axes.push(Axis::Explicit(p));
            } else {
                axes.push(Axis::Even { beg, end, n });
            }
        }
        let mut values: Vec<f32> = Vec::with_capacity(total.min(1 << 20));
        for k in 1..=total {
            let v = t.real(&format!("value {k} of {total}"))?;
            let f = v as f32;
            if !f.is_finite() {
                return Err(t.err(format!(
                    "value {k} of {total} ({v:e}) is out of the range of single precision"
                )));
            }
            values.push(f);
        }
        // Anything after the last value is ignored, as Radiance does.
        Ok(DataArray {
            name: name.to_string(),
            axes,
            values,
        })
    }

    /// An array from its axes and values (row-major, last axis fastest). None if the value
    /// count does not match, an axis has no point or an explicit axis is not strictly
    /// monotonic.
    pub fn from_parts(name: &str, axes: Vec<Axis>, values: Vec<f32>) -> Option<DataArray> {
        let mut total = 1usize;
        for a in &axes {
            if a.is_empty() {
                return None;
            }
            if let Axis::Explicit(p) = a {
                let up = p.len() >= 2 && p[1] > p[0];
                let ok = p.len() >= 2
                    && p.windows(2)
                        .all(|w| if up { w[1] > w[0] } else { w[1] < w[0] });
                if !ok {
                    return None;
                }
            }
            total = total.checked_mul(a.len())?;
        }
        (total == values.len() && !axes.is_empty()).then(|| DataArray {
            name: name.to_string(),
            axes,
            values,
        })
    }

    /// Number of dimensions (the number of coordinates [`DataArray::interp`] takes).
    pub fn dims(&self) -> usize {
        self.axes.len()
    }

    /// The axes, first dimension first.
    pub fn axes(&self) -> &[Axis] {
        &self.axes
    }

    /// The values, row-major (last dimension fastest).
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The value at `coords` (one per dimension), interpolated and extrapolated with
    /// Radiance's rules (module docs). Panics if `coords.len() != self.dims()`.
    pub fn interp(&self, coords: &[f64]) -> f64 {
        assert_eq!(
            coords.len(),
            self.dims(),
            "{}: {} coordinates for a {}-dimensional data file",
            self.name,
            coords.len(),
            self.dims()
        );
        // One and two dimensions (ies2rad's distributions, pictures' neighbours) without
        // the general recursion: the same operations in the same order as it.
        let at = |k: usize| self.values.get(k).map_or(0.0, |&v| v as f64);
        let weights_on = |a: &Axis, x: f64| match a.len() {
            1 => None,
            n => Some(weights(a.index(x), n)),
        };
        let line = |w: Option<(usize, f64, f64)>, off: usize| match w {
            None => at(off),
            Some((i, c0, c1)) => c0 * at(off + i) + c1 * at(off + i + 1),
        };
        match self.axes.as_slice() {
            [a] => line(weights_on(a, coords[0]), 0),
            [a, b] => {
                let wb = weights_on(b, coords[1]);
                let m = b.len();
                match weights_on(a, coords[0]) {
                    None => line(wb, 0),
                    Some((i, c0, c1)) => c0 * line(wb, i * m) + c1 * line(wb, (i + 1) * m),
                }
            }
            _ => self.interp_general(coords),
        }
    }

    /// [`DataArray::interp`] by the general recursion (any number of dimensions).
    fn interp_general(&self, coords: &[f64]) -> f64 {
        // Each dimension's interval, weights and stride, once.
        let mut w = [(0usize, 1.0, 0.0, 0usize); MAX_DIMS];
        let mut stride = 1;
        for d in (0..self.axes.len()).rev() {
            let n = self.axes[d].len();
            let (i, c0, c1) = if n == 1 {
                (0, 1.0, 0.0)
            } else {
                weights(self.axes[d].index(coords[d]), n)
            };
            w[d] = (i, c0, c1, stride);
            stride *= n;
        }
        self.interp_from(&w[..self.axes.len()], 0)
    }

    /// The value at `offset` (of the dimensions before `w`) interpolated along the
    /// dimensions of `w` (interval, weights, stride).
    fn interp_from(&self, w: &[(usize, f64, f64, usize)], offset: usize) -> f64 {
        let Some((&(i, c0, c1, stride), rest)) = w.split_first() else {
            return self.values.get(offset).map_or(0.0, |&v| v as f64);
        };
        let at = |k: usize| self.interp_from(rest, offset + k * stride);
        if self.axes[self.axes.len() - w.len()].len() == 1 {
            return at(0);
        }
        c0 * at(i) + c1 * at(i + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    #[test]
    fn verified_values_of_the_reference() {
        // radiance-formats.md §3.2: file `1 / 0 0 3 0 1 4 / 10 20 50`.
        let d = DataArray::parse(b"1\n0 0 3 0 1 4\n10 20 50\n", "t.dat").unwrap();
        for (p, want) in [
            (2.0, 30.0),
            (-0.5, 5.0),
            (6.0, 70.0),
            (12.0, 17.142857),
            (0.0, 10.0),
            (4.0, 50.0),
        ] {
            let got = d.interp(&[p]);
            assert!(close(got, want, 1e-6), "p={p}: {got} != {want}");
        }
    }

    #[test]
    fn tails_and_the_upper_discontinuity() {
        // Even axis 0..3 with 4 points: x = p.
        let d = DataArray::parse(b"1 0 3 4  1 2 3 4", "t").unwrap();
        // One step of linear extrapolation on either side.
        assert!(close(d.interp(&[4.0]), 5.0, 1e-12));
        assert!(close(d.interp(&[-1.0]), 0.0, 1e-12));
        // Continuous at x = -1: c1 = 1/(x - 0), c0 = -2 c1.
        let x = -1.0 - 1e-9;
        assert!(close(d.interp(&[x]), 0.0, 1e-6));
        let x = -3.0;
        assert!(close(d.interp(&[x]), -2.0 / x + 2.0 / x, 1e-12));
        // Upper: i = 2, x = 4 (= n) is linear: c0 = -1, c1 = 2; just above it jumps.
        assert!(close(d.interp(&[4.0]), -3.0 + 8.0, 1e-12));
        let above = d.interp(&[4.0 + 1e-9]);
        assert!(close(above, -3.0 / 3.0 + 4.0 * 2.0 / 3.0, 1e-6), "{above}");
        // Descending even axis: beg > end.
        let r = DataArray::parse(b"1 3 0 4  4 3 2 1", "t").unwrap();
        assert!(close(r.interp(&[0.5]), 1.5, 1e-12));
    }

    #[test]
    fn one_and_two_dimensions_match_the_general_recursion_bit_for_bit() {
        let mut rnd = crate::hash::test_uniform(7);
        for case in 0..200 {
            let dims = 1 + case % 2;
            let axes: Vec<Axis> = (0..dims)
                .map(|_| {
                    let n = 1 + (rnd() * 6.0) as usize;
                    if rnd() < 0.5 {
                        Axis::Even {
                            beg: -1.0 + rnd(),
                            end: 2.0 + rnd(),
                            n,
                        }
                    } else {
                        let mut x = rnd();
                        Axis::Explicit(
                            (0..n.max(2))
                                .map(|_| {
                                    x += 0.1 + rnd();
                                    x
                                })
                                .collect(),
                        )
                    }
                })
                .collect();
            let total: usize = axes.iter().map(|a| a.len()).product();
            let values: Vec<f32> = (0..total).map(|_| (rnd() * 10.0 - 3.0) as f32).collect();
            let d = DataArray::from_parts("t", axes, values).unwrap();
            for _ in 0..50 {
                let c: Vec<f64> = (0..dims).map(|_| rnd() * 12.0 - 5.0).collect();
                assert_eq!(
                    d.interp(&c).to_bits(),
                    d.interp_general(&c).to_bits(),
                    "{c:?}"
                );
            }
        }
    }

    #[test]
    fn two_dimensions_are_multilinear_last_dimension_fastest() {
        // rows (dim 1) 0..1, columns (dim 2) 0..2.
        let d = DataArray::parse(b"2\n0 1 2\n0 2 3\n1 2 3\n10 20 30\n", "t").unwrap();
        assert_eq!(d.dims(), 2);
        assert!(close(d.interp(&[0.0, 1.0]), 2.0, 1e-12));
        assert!(close(d.interp(&[1.0, 2.0]), 30.0, 1e-12));
        assert!(close(d.interp(&[0.5, 0.5]), 0.5 * 1.5 + 0.5 * 15.0, 1e-12));
        // Explicit descending coordinates in the second dimension.
        let e = DataArray::parse(b"2\n0 1 2\n5 5 3 4 2 1\n1 2 3\n10 20 30\n", "t").unwrap();
        assert!(close(e.interp(&[0.0, 3.0]), 1.5, 1e-12));
    }

    #[test]
    fn trailing_data_is_ignored() {
        let d = DataArray::parse(b"1 0 1 2  1 2  3 x", "t").unwrap();
        assert_eq!(d.values(), &[1.0, 2.0]);
    }

    #[test]
    fn comments_and_numbers() {
        let d = DataArray::parse(b"# head\n1#dims\n0 1 2 # axis\n12#x\n1.5e1", "t").unwrap();
        assert_eq!(d.values(), &[12.0, 15.0]);
    }

    #[test]
    fn errors_name_file_line_and_reason() {
        let cases: &[(&[u8], &str)] = &[
            (
                b"",
                "t.dat:1: unexpected end of file: missing number of dimensions",
            ),
            (b"7", "t.dat:1: bad number of dimensions 7"),
            (
                b"1\n0 1 2\n1 x",
                "t.dat:3: bad value 2 of 2 'x' (not a number)",
            ),
            (
                b"1\n0 1 2\n1",
                "t.dat:3: unexpected end of file: missing value 2 of 2",
            ),
            (b"1\n0 1 1\n1", "t.dat:2: dimension 1 has 1 points"),
            (
                b"1\n0 0 3 0 1 1\n1 2 3",
                "t.dat:2: coordinates of dimension 1 are not",
            ),
            (
                b"1\n0 0 3 0 2 1\n1 2 3",
                "t.dat:2: coordinates of dimension 1 are not",
            ),
            (
                b"1\n0 1 2\n1 1e39",
                "t.dat:3: value 2 of 2 (1e39) is out of the range",
            ),
            (b"1\n0 1 2\n1 inf", "t.dat:3: bad value 2 of 2 'inf'"),
            (b"2\n0 1 65536\n0 1 65536\n", "t.dat:3: too many values"),
            (b"1\n0 1 2.5\n", "t.dat:2: bad size of dimension 1 '2.5'"),
        ];
        for (text, want) in cases {
            let e = DataArray::parse(text, "t.dat").unwrap_err();
            assert!(e.starts_with(want), "{e:?} should start with {want:?}");
        }
    }

    #[test]
    fn from_parts_checks_sizes() {
        let ax = Axis::Even {
            beg: 0.0,
            end: 1.0,
            n: 2,
        };
        assert!(DataArray::from_parts("x", vec![ax.clone()], vec![1.0, 2.0]).is_some());
        assert!(DataArray::from_parts("x", vec![ax], vec![1.0]).is_none());
        let ex = Axis::Explicit(vec![0.0, 0.0]);
        assert!(DataArray::from_parts("x", vec![ex], vec![1.0, 2.0]).is_none());
    }
}
