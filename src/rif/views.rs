//! rad's views: standard view ids (`X`, `xZ`, `XYZh`, ...) expanded from the zone, labelled
//! views and unnamed views (`docs/rif.md`).

use crate::view::{fmt_g, read_view_file, View};
use std::path::Path;

/// The zone of a rif file: interior or exterior, and its box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Zone {
    /// `I[nterior]` (views from inside) or `E[xterior]`.
    pub interior: bool,
    /// Minimum corner.
    pub min: [f64; 3],
    /// Maximum corner.
    pub max: [f64; 3],
}

impl Zone {
    /// Extent along each axis.
    pub fn extent(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.max[i] - self.min[i])
    }

    /// Mean extent (rad's `asz`).
    pub fn mean_size(&self) -> f64 {
        self.extent().iter().sum::<f64>() / 3.0
    }

    fn centre(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| 0.5 * (self.min[i] + self.max[i]))
    }
}

/// A view of a rif file: its name (label, standard id or ordinal) and rpict view options.
#[derive(Debug, Clone, PartialEq)]
pub struct RadView {
    /// The name used in picture names (`<root>_<name>.hdr`).
    pub name: String,
    /// rpict view options.
    pub words: Vec<String>,
}

impl RadView {
    /// The view rpict gets from these options: applied to rpict's default view, `-vf` files
    /// read as rad's rpict reads them (relative to the current directory), and checked
    /// (finite, a valid view). A name that is no standard view id and has no options is
    /// refused: rad renders nothing for it.
    pub fn resolve(&self) -> Result<View, String> {
        if self.words.is_empty() {
            return Err(format!(
                "view '{}' is neither a standard view id (such as X, xyZ or Zl) nor followed \
                 by view options",
                self.name
            ));
        }
        let named = |e: String| format!("view '{}': {e}", self.name);
        let mut v = View::default();
        let mut i = 0;
        while i < self.words.len() {
            let w = &self.words[i..];
            if w[0] == "-vf" {
                let f = w
                    .get(1)
                    .ok_or_else(|| named("-vf needs a view file name".into()))?;
                v = read_view_file(Path::new(f), &v).map_err(|e| named(e.to_string()))?;
                i += 2;
                continue;
            }
            i += v
                .apply_option(w)
                .map_err(|e| named(e.to_string()))?
                .unwrap_or(1);
        }
        v.frame().map_err(|e| named(e.to_string()))?;
        Ok(v)
    }
}

/// The axes of a standard view id with their signs, and its type letter, if `id` is one
/// (`[Xx]?[Yy]?[Zz]?[vlcahs]?`, at least one axis letter).
fn standard_id(id: &str) -> Option<([i32; 3], char)> {
    let mut axes = [0i32; 3];
    let mut chars = id.chars().peekable();
    for (i, (lo, hi)) in [('x', 'X'), ('y', 'Y'), ('z', 'Z')].into_iter().enumerate() {
        match chars.peek() {
            Some(&c) if c == lo => axes[i] = -1,
            Some(&c) if c == hi => axes[i] = 1,
            _ => continue,
        }
        chars.next();
    }
    let vt = match chars.next() {
        None => 'v',
        Some(c) if "vlcahs".contains(c) => c,
        Some(_) => return None,
    };
    if chars.next().is_some() || axes == [0, 0, 0] {
        return None;
    }
    Some((axes, vt))
}

/// The up vector rad uses for a standard view along `axes` with `UP` = `up` (axis index
/// and sign; None = unset): a view along the up axis only turns to the next axis.
fn view_up(axes: [i32; 3], up: Option<(usize, i32)>) -> [f64; 3] {
    let (axis, sign) = up.unwrap_or((2, 1));
    let only = |a: usize| (0..3).all(|i| (i == a) == (axes[i] != 0));
    let (axis, sign) = if only(axis) {
        ((axis + 2) % 3, 1)
    } else {
        (axis, sign)
    };
    let mut v = [0.0; 3];
    v[axis] = sign as f64;
    v
}

fn push3(words: &mut Vec<String>, opt: &str, v: [f64; 3]) {
    words.push(opt.to_string());
    words.extend(v.iter().map(|x| fmt_g(*x + 0.0, 6)));
}

/// Expand one `view=` value (`ordinal` counts the views from 1). `up` is `UP` parsed.
pub fn expand(value: &str, ordinal: usize, zone: &Zone, up: Option<(usize, i32)>) -> RadView {
    let mut words = super::split_words(value);
    if words.first().is_none_or(|w| w.starts_with('-')) {
        return RadView {
            name: ordinal.to_string(),
            words,
        };
    }
    let id = words.remove(0);
    let Some((axes, vt)) = standard_id(&id) else {
        if words.is_empty() {
            // Neither a standard view nor options: no view (rad renders nothing for it;
            // [`RadView::resolve`] refuses it).
            return RadView { name: id, words };
        }
        let mut out = Vec::new();
        if let Some((axis, sign)) = up {
            let mut v = [0.0; 3];
            v[axis] = sign as f64;
            push3(&mut out, "-vu", v);
        }
        out.extend(words);
        return RadView {
            name: id,
            words: out,
        };
    };
    let mult = if zone.interior { 0.45 } else { 2.0 };
    let (c, e) = (zone.centre(), zone.extent());
    let vp = [0, 1, 2].map(|i| c[i] + axes[i] as f64 * mult * e[i]);
    let vd = [0, 1, 2].map(|i| -(axes[i] as f64) * e[i]);
    let mut out = vec![format!("-vt{vt}")];
    push3(&mut out, "-vp", vp);
    push3(&mut out, "-vd", vd);
    push3(&mut out, "-vu", view_up(axes, up));
    let (h, v) = match vt {
        'l' => {
            let diag = e.iter().map(|x| x * x).sum::<f64>().sqrt();
            (fmt_g(diag, 3), fmt_g(diag, 3))
        }
        'a' | 'h' | 's' => ("180".into(), "180".into()),
        'c' => ("180".into(), "90".into()),
        _ => ("45".into(), "45".into()),
    };
    out.extend(["-vh".into(), h, "-vv".into(), v]);
    out.extend(words);
    RadView {
        name: id,
        words: out,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn j(v: &RadView) -> String {
        v.words.join(" ")
    }

    #[test]
    fn standard_views_as_rad_prints_them() {
        let zi = Zone {
            interior: true,
            min: [0.0; 3],
            max: [4.0, 5.0, 3.0],
        };
        assert_eq!(
            j(&expand("xZ", 1, &zi, None)),
            "-vtv -vp 0.2 2.5 2.85 -vd 4 0 -3 -vu 0 0 1 -vh 45 -vv 45"
        );
        assert_eq!(
            j(&expand("xyc", 1, &zi, None)),
            "-vtc -vp 0.2 0.25 1.5 -vd 4 5 0 -vu 0 0 1 -vh 180 -vv 90"
        );
        assert_eq!(
            j(&expand("Za -vu 0 1 0", 1, &zi, None)),
            "-vta -vp 2 2.5 2.85 -vd 0 0 -3 -vu 0 1 0 -vh 180 -vv 180 -vu 0 1 0"
        );
        assert_eq!(
            j(&expand("zl", 1, &zi, None)),
            "-vtl -vp 2 2.5 0.15 -vd 0 0 3 -vu 0 1 0 -vh 7.07 -vv 7.07"
        );
        let ze = Zone {
            interior: false,
            ..zi
        };
        let up = Some((1, -1));
        assert_eq!(
            j(&expand("X", 1, &ze, up)),
            "-vtv -vp 10 2.5 1.5 -vd -4 0 0 -vu 0 -1 0 -vh 45 -vv 45"
        );
        assert_eq!(
            j(&expand("Y", 1, &ze, up)),
            "-vtv -vp 2 12.5 1.5 -vd 0 -5 0 -vu 1 0 0 -vh 45 -vv 45"
        );
        let v = expand("myv -vp 1 1 1", 3, &ze, up);
        assert_eq!(
            (v.name.as_str(), j(&v).as_str()),
            ("myv", "-vu 0 -1 0 -vp 1 1 1")
        );
        let v = expand("-vp 2 2 2", 4, &ze, up);
        assert_eq!((v.name.as_str(), j(&v).as_str()), ("4", "-vp 2 2 2"));
        assert!(standard_id("nw").is_none());
        assert!(standard_id("v").is_none());
        assert!(standard_id("Xvv").is_none());
    }
}
