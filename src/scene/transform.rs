//! Affine transforms in `xform`'s argument language.
//!
//! Words: `-t x y z` translate, `-rx/-ry/-rz deg` rotate about an axis (right-handed),
//! `-s f` uniform scale, `-mx/-my/-mz` mirror one axis, and `-i n`, which repeats the group
//! of transforms that follows it (up to the next `-i`) `n` times. Transforms apply in the
//! order given. The same words follow file names in `instance`, `mesh` and pattern/texture
//! primitives.

use glam::{DMat4, DVec3};

use super::primitive::Primitive;

/// An affine transform built from xform words, with the words kept for re-emission.
#[derive(Clone, Debug, PartialEq)]
pub struct Transform {
    m: DMat4,
    /// `m`'s inverse (patterns on instanced surfaces map every hit through it).
    inv: DMat4,
    scale: f64,
    mirrors: bool,
    invert: bool,
    words: Vec<String>,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::identity()
    }
}

/// Surface types that `-m` and `-n` apply to.
pub const SURFACE_TYPES: &[&str] = &[
    "polygon", "cone", "sphere", "ring", "cylinder", "cup", "bubble", "tube", "source", "instance",
    "mesh",
];

/// Non-surface types whose string arguments end with transform words (real `xform` appends
/// its transform to these). The text types are not among them: xform moves their frame
/// (the first nine reals) instead.
pub const TRANSFORMABLE_TYPES: &[&str] = &[
    "brightfunc",
    "colorfunc",
    "texfunc",
    "mixfunc",
    "colorpict",
    "brightdata",
    "colordata",
    "texdata",
    "mixdata",
    "mixpict",
    "specfunc",
    "specdata",
    "specpict",
    "plasfunc",
    "metfunc",
    "transfunc",
    "BRTDfunc",
    "plasdata",
    "metdata",
    "transdata",
    "BSDF",
    "aBSDF",
    "WGMDfunc",
    "prism1",
    "prism2",
    "ashik2",
];

/// Whether `ptype` is a surface (or instance/mesh) type.
pub fn is_surface(ptype: &str) -> bool {
    SURFACE_TYPES.contains(&ptype)
}

fn parse_num(opt: &str, w: Option<&String>) -> Result<f64, String> {
    let w = w.ok_or_else(|| format!("missing argument for {opt}"))?;
    if !super::lexer::is_real(w) {
        return Err(format!("bad argument for {opt}: '{w}' is not a number"));
    }
    w.parse::<f64>()
        .map_err(|_| format!("bad argument for {opt}: '{w}' is not a number"))
}

/// One elementary operation (point map matrix, mirror flip, scale factor).
fn op_matrix(
    word: &str,
    words: &[String],
    i: usize,
) -> Result<Option<(DMat4, usize, bool, f64)>, String> {
    let rot = |deg: f64| deg.to_radians();
    Ok(Some(match word {
        "-t" => {
            let x = parse_num(word, words.get(i + 1))?;
            let y = parse_num(word, words.get(i + 2))?;
            let z = parse_num(word, words.get(i + 3))?;
            (DMat4::from_translation(DVec3::new(x, y, z)), 4, false, 1.0)
        }
        "-rx" => (
            DMat4::from_rotation_x(rot(parse_num(word, words.get(i + 1))?)),
            2,
            false,
            1.0,
        ),
        "-ry" => (
            DMat4::from_rotation_y(rot(parse_num(word, words.get(i + 1))?)),
            2,
            false,
            1.0,
        ),
        "-rz" => (
            DMat4::from_rotation_z(rot(parse_num(word, words.get(i + 1))?)),
            2,
            false,
            1.0,
        ),
        "-s" => {
            let s = parse_num(word, words.get(i + 1))?;
            if s == 0.0 {
                return Err("scale factor 0 for -s".to_string());
            }
            (DMat4::from_scale(DVec3::splat(s)), 2, s < 0.0, s.abs())
        }
        "-mx" => (DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)), 1, true, 1.0),
        "-my" => (DMat4::from_scale(DVec3::new(1.0, -1.0, 1.0)), 1, true, 1.0),
        "-mz" => (DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)), 1, true, 1.0),
        _ => return Ok(None),
    }))
}

/// One repeat group of a transform: the product of its options, applied `count` times.
#[derive(Clone, Copy, Debug)]
pub struct Group {
    m: DMat4,
    scale: f64,
    mirror: bool,
    /// How often it applies: the `-i N` that opened it (1 for the first group).
    pub count: u64,
}

#[cfg(test)]
thread_local! {
    /// Group applications on this thread (tests count the work of `xform -a`).
    pub(crate) static APPLICATIONS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// A transform's running product, built group by group ([`TransformState::apply`]).
#[derive(Clone, Copy, Debug)]
pub struct TransformState {
    m: DMat4,
    scale: f64,
    mirrors: bool,
}

impl Default for TransformState {
    fn default() -> Self {
        TransformState {
            m: DMat4::IDENTITY,
            scale: 1.0,
            mirrors: false,
        }
    }
}

impl TransformState {
    /// Apply `g` once more (the repeat groups are applied one application at a time, so a
    /// state that has taken `k` applications takes the `k+1`-th in one step: `xform -a`
    /// builds its copies incrementally, in linear time, with the same arithmetic).
    pub fn apply(&mut self, g: &Group) {
        #[cfg(test)]
        APPLICATIONS.with(|c| c.set(c.get() + 1));
        self.m = g.m * self.m;
        self.scale *= g.scale;
        self.mirrors ^= g.mirror;
    }

    /// Apply `g` `g.count` times.
    pub fn apply_group(&mut self, g: &Group) {
        for _ in 0..g.count {
            self.apply(g);
        }
    }

    /// The transform of this state, with its `words` (as [`Transform::words`]).
    pub fn finish(&self, words: Vec<String>) -> Transform {
        Transform {
            m: self.m,
            inv: self.m.inverse(),
            scale: self.scale,
            mirrors: self.mirrors,
            invert: false,
            words,
        }
    }
}

/// Parse transform words from the start of `words` into repeat groups, stopping at the
/// first word that is not part of a transform. Returns the groups and how many words they
/// consumed. Errors name the bad option and word.
pub fn parse_groups(words: &[String]) -> Result<(Vec<Group>, usize), String> {
    let mut groups = Vec::new();
    let mut group = Group {
        m: DMat4::IDENTITY,
        scale: 1.0,
        mirror: false,
        count: 1,
    };
    let mut i = 0;
    while i < words.len() {
        let w = words[i].as_str();
        if w == "-i" {
            let n = words
                .get(i + 1)
                .ok_or_else(|| "missing argument for -i".to_string())?;
            let c: u64 = n
                .parse()
                .map_err(|_| format!("bad argument for -i: '{n}' is not a non-negative integer"))?;
            if c > 1_000_000 {
                return Err(format!("repeat count {c} for -i is too large"));
            }
            groups.push(group);
            group = Group {
                m: DMat4::IDENTITY,
                scale: 1.0,
                mirror: false,
                count: c,
            };
            i += 2;
            continue;
        }
        match op_matrix(w, words, i)? {
            Some((m, n, mir, s)) => {
                group.m = m * group.m;
                group.scale *= s;
                group.mirror ^= mir;
                i += n;
            }
            None => break,
        }
    }
    groups.push(group);
    Ok((groups, i))
}

/// The words real xform appends to a transformed primitive's arguments for `words`: `-i 1`
/// prepended unless they start with `-i`.
pub fn appended_words(words: &[String]) -> Vec<String> {
    let mut out: Vec<String> = words.to_vec();
    if !out.is_empty() && out[0] != "-i" {
        out.splice(0..0, ["-i".to_string(), "1".to_string()]);
    }
    out
}

/// Parse transform words from the start of `words`, stopping at the first word that is not
/// part of a transform. Returns the transform and how many words it consumed. Errors name
/// the bad option and word.
pub fn parse_transform(words: &[String]) -> Result<(Transform, usize), String> {
    let (groups, used) = parse_groups(words)?;
    let mut state = TransformState::default();
    for g in &groups {
        state.apply_group(g);
    }
    Ok((state.finish(appended_words(&words[..used])), used))
}

impl Transform {
    /// The identity (no words).
    pub fn identity() -> Transform {
        Transform {
            m: DMat4::IDENTITY,
            inv: DMat4::IDENTITY,
            scale: 1.0,
            mirrors: false,
            invert: false,
            words: Vec::new(),
        }
    }

    /// A transform given by its matrix (points as column vectors), overall positive scale
    /// and whether it mirrors; no words (the composed transform of nested instances).
    pub fn from_matrix(m: DMat4, scale: f64, mirrors: bool) -> Transform {
        Transform {
            m,
            inv: m.inverse(),
            scale,
            mirrors,
            invert: false,
            words: Vec::new(),
        }
    }

    /// Transform a point.
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.m.transform_point3(p)
    }

    /// Transform a direction (no translation; scaled and mirrored like the geometry).
    pub fn vector(&self, v: DVec3) -> DVec3 {
        self.m.transform_vector3(v)
    }

    /// The overall (positive) scale factor.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Whether the transform mirrors (determinant < 0).
    pub fn mirrors(&self) -> bool {
        self.mirrors
    }

    /// The 4x4 matrix mapping points (column vectors).
    pub fn matrix(&self) -> DMat4 {
        self.m
    }

    /// The inverse of [`Transform::matrix`] (computed once).
    pub fn inverse(&self) -> DMat4 {
        self.inv
    }

    /// The words as real xform appends them to arguments (`-i 1` prepended unless the words
    /// already start with `-i`; empty for the identity given by no words).
    pub fn words(&self) -> &[String] {
        &self.words
    }

    /// Whether surfaces are turned inside out (xform's `-I`).
    pub fn inverts(&self) -> bool {
        self.invert
    }

    /// Set xform's `-I` (turn surfaces inside out: sphere↔bubble, cone↔cup,
    /// cylinder↔tube, ring normals negated, polygon vertex order reversed). Not part of the
    /// words, exactly as real xform leaves it out of appended arguments.
    pub fn with_invert(mut self, invert: bool) -> Transform {
        self.invert = invert;
        self
    }

    /// Apply to one primitive per its type (see module docs of the reader for the rules,
    /// which follow real xform): polygon vertices (order reversed when the transform
    /// mirrors xor inverts), sphere/bubble centre and radius, cone/cup/cylinder/tube ends and
    /// radii, ring centre, normal (transformed as a vector, not renormalised, negated by
    /// `-I`) and radii, source direction (transformed as a vector, not renormalised);
    /// instance, mesh and pattern-like types get the words appended to their string
    /// arguments, except the text types, whose origin (a point) and right and down vectors
    /// are transformed; everything else is unchanged. Errors on wrong argument counts.
    pub fn apply(&self, p: &Primitive) -> Result<Primitive, String> {
        let mut q = p.clone();
        let r = &p.rargs;
        let bad = |what: &str| format!("bad {} \"{}\": {}", p.ptype, p.name, what);
        let pt = |i: usize| self.point(DVec3::new(r[i], r[i + 1], r[i + 2]));
        let vc = |i: usize| self.vector(DVec3::new(r[i], r[i + 1], r[i + 2]));
        let put = |out: &mut Vec<f64>, i: usize, v: DVec3| {
            out[i] = v.x;
            out[i + 1] = v.y;
            out[i + 2] = v.z;
        };
        let swap = |a: &str, b: &str| -> String {
            if !self.invert {
                p.ptype.clone()
            } else if p.ptype == a {
                b.to_string()
            } else {
                a.to_string()
            }
        };
        match p.ptype.as_str() {
            "polygon" => {
                if r.len() < 9 || !r.len().is_multiple_of(3) {
                    return Err(bad("need 3n reals, n >= 3"));
                }
                let n = r.len() / 3;
                let mut verts: Vec<DVec3> = (0..n).map(|k| pt(3 * k)).collect();
                if self.mirrors ^ self.invert {
                    verts.reverse();
                }
                for (k, v) in verts.into_iter().enumerate() {
                    put(&mut q.rargs, 3 * k, v);
                }
            }
            "sphere" | "bubble" => {
                if r.len() != 4 {
                    return Err(bad("need 4 reals"));
                }
                put(&mut q.rargs, 0, pt(0));
                q.rargs[3] = r[3] * self.scale;
                q.ptype = swap("sphere", "bubble");
            }
            "cone" | "cup" | "cylinder" | "tube" => {
                let want = if matches!(p.ptype.as_str(), "cone" | "cup") {
                    8
                } else {
                    7
                };
                if r.len() != want {
                    return Err(bad(&format!("need {want} reals")));
                }
                put(&mut q.rargs, 0, pt(0));
                put(&mut q.rargs, 3, pt(3));
                for (qk, rk) in q.rargs[6..].iter_mut().zip(&r[6..]) {
                    *qk = rk * self.scale;
                }
                q.ptype = if want == 8 {
                    swap("cone", "cup")
                } else {
                    swap("cylinder", "tube")
                };
            }
            "ring" => {
                if r.len() != 8 {
                    return Err(bad("need 8 reals"));
                }
                put(&mut q.rargs, 0, pt(0));
                let mut n = vc(3);
                if self.invert {
                    n = -n;
                }
                put(&mut q.rargs, 3, n);
                q.rargs[6] = r[6] * self.scale;
                q.rargs[7] = r[7] * self.scale;
            }
            "source" => {
                if r.len() != 4 {
                    return Err(bad("need 4 reals"));
                }
                put(&mut q.rargs, 0, vc(0));
            }
            "instance" | "mesh" => {
                if p.sargs.is_empty() {
                    return Err(bad("missing file name"));
                }
                q.sargs.extend(self.words.iter().cloned());
            }
            "brighttext" | "colortext" | "mixtext" => {
                // No transform words: the origin moves as a point, the right and down
                // vectors as vectors (real xform's rule).
                if r.len() < 9 {
                    return Err(bad("need at least 9 reals"));
                }
                put(&mut q.rargs, 0, pt(0));
                put(&mut q.rargs, 3, vc(3));
                put(&mut q.rargs, 6, vc(6));
            }
            t if TRANSFORMABLE_TYPES.contains(&t) => {
                q.sargs.extend(self.words.iter().cloned());
            }
            _ => {}
        }
        Ok(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn order_and_repeat() {
        let (t, n) = parse_transform(&w("-i 2 -rx 30 -t 1 2 3 file")).unwrap();
        assert_eq!(n, 8);
        let p = t.point(DVec3::new(1.0, 0.0, 0.0));
        assert!((p - DVec3::new(3.0, 2.232_050_807_57, 6.598_076_211_35)).length() < 1e-9);
        assert_eq!(t.words(), &w("-i 2 -rx 30 -t 1 2 3")[..]);
    }

    #[test]
    fn scale_and_mirror() {
        let (t, _) = parse_transform(&w("-s -2 -mx")).unwrap();
        assert_eq!(t.scale(), 2.0);
        assert!(!t.mirrors());
        let (t, _) = parse_transform(&w("-s 2 -my -t 1 0 0")).unwrap();
        assert!(t.mirrors());
        assert_eq!(t.words()[..2], w("-i 1")[..]);
        let (t, n) = parse_transform(&w("-i 0 -mx")).unwrap();
        assert_eq!(n, 3);
        assert!(!t.mirrors());
    }

    #[test]
    fn text_frames_move_with_the_transform() {
        // Real xform: `-rz 90 -t 1 2 3 -s 2` on O (0,1,0), R (1,0,0), D (0,-1,0) gives
        // O (0,4,6), R (0,2,0), D (2,0,0); the strings are unchanged.
        let (t, _) = parse_transform(&w("-rz 90 -t 1 2 3 -s 2")).unwrap();
        let p = Primitive {
            modifier: "void".into(),
            ptype: "brighttext".into(),
            name: "t".into(),
            sargs: w("helvet.fnt . AI"),
            iargs: vec![],
            rargs: vec![0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 2.0, 0.5],
            loc: crate::scene::Location::new("t", 1),
        };
        let q = t.apply(&p).unwrap();
        assert_eq!(q.sargs, p.sargs);
        let want = [0.0, 4.0, 6.0, 0.0, 2.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.5];
        for (a, b) in q.rargs.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{:?}", q.rargs);
        }
        let mut short = p.clone();
        short.rargs.truncate(3);
        assert!(t.apply(&short).is_err());
    }

    #[test]
    fn errors() {
        assert!(parse_transform(&w("-t 1 2")).is_err());
        assert!(parse_transform(&w("-rx abc")).is_err());
        assert!(parse_transform(&w("-s 0")).is_err());
        assert!(parse_transform(&w("-i -1 -mx")).is_err());
        let (t, n) = parse_transform(&w("foo -t 1 2 3")).unwrap();
        assert_eq!(n, 0);
        assert!(t.words().is_empty());
    }
}
