//! Wavefront OBJ files read directly as meshes, following `obj2mesh`'s rules
//! (radiance-formats.md §7.3), so that `mod mesh id 1 file.obj [xf] 0 0` (or a `.obj` given
//! to tpict or tplan next to the scene files) renders what `obj2mesh -a materials` and a
//! `mesh` primitive render.
//!
//! - Statements: `v x y z` (further words ignored), `vn x y z` (normalised; a zero normal is
//!   an error), `vt u v`, `f` with `v`, `v/t`, `v//n` or `v/t/n` references (1-based,
//!   negative counts back from the last one read, 0 or empty = none), `usemtl name`, `g name`
//!   (its first word; `g` alone clears the group), `o` and `usemap` (ignored), `#` comments.
//!   Other statements are counted and reported in one warning.
//! - A face of more than three vertices is projected on the plane of its dominant axis and
//!   cut by ear clipping (the first ear found walking the outline from its last vertex);
//!   the triangles keep the face's orientation. Normals and (u,v) are kept for a triangle
//!   only when all three of its vertices have them.
//! - A triangle whose three normals all point behind its face normal `(v2−v1)×(v3−v2)` is
//!   turned over (v1↔v3); one whose normals are all within 0.999995 (cosine) of the face
//!   normal loses them (it is flat). A triangle of zero area is skipped with a warning.
//! - Each triangle's modifier name is the current `usemtl` name, else the group name, else
//!   none; names are resolved by the scene builder.
//!
//! Why not the `tobj` crate: it drops `usemtl` names that no MTL library defines (obj2mesh's
//! materials come from Radiance files, not MTL), ends groups at `o`, keeps normals and
//! (u,v) aligned with vertices only when every vertex of a model has them (obj2mesh decides
//! per triangle) and reports errors without line numbers. obj2mesh's statement set is
//! small, so it is read here, line by line.

use glam::{DVec3, Vec3};
use std::collections::HashMap;

use crate::geometry::trimesh::{MeshTri, HAS_NORMAL, HAS_UV};

/// Cosine within which a triangle's vertex normals count as its face normal.
const COSTOL: f64 = 0.999995;

/// Most distinct modifier names (triangle modifiers are 16-bit indices).
const MAX_NAMES: usize = 32000;

/// An OBJ file converted to triangles.
#[derive(Debug, Default)]
pub struct ObjMesh {
    /// Vertex positions.
    pub pos: Vec<DVec3>,
    /// Vertex normals (unit; zero without [`HAS_NORMAL`]).
    pub normal: Vec<Vec3>,
    /// Vertex (u,v).
    pub uv: Vec<[f64; 2]>,
    /// [`HAS_NORMAL`] | [`HAS_UV`] per vertex.
    pub flags: Vec<u8>,
    /// Triangles; `modifier` indexes [`ObjMesh::names`], −1 = no name.
    pub tris: Vec<MeshTri>,
    /// The modifier names triangles use, with the line that set each first.
    pub names: Vec<(String, u32)>,
    /// Warnings (`file:line: ...`).
    pub warnings: Vec<String>,
}

/// A face corner: position, (u,v) and normal indices (0-based).
type Corner = (usize, Option<usize>, Option<usize>);

struct Reader<'a> {
    file: &'a str,
    pos: Vec<DVec3>,
    uv: Vec<[f64; 2]>,
    normals: Vec<DVec3>,
    out: ObjMesh,
    verts: HashMap<Corner, u32>,
    name_ids: HashMap<String, i16>,
}

fn number(word: Option<&str>, what: &str) -> Result<f64, String> {
    let w = word.ok_or_else(|| format!("missing {what}"))?;
    match w.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("bad {what} '{w}'")),
    }
}

/// Parse one face reference (`v`, `v/t`, `v//n`, `v/t/n`) against the counts read so far.
fn corner(word: &str, nv: usize, nt: usize, nn: usize) -> Result<Corner, String> {
    let mut parts = word.split('/');
    let index = |part: Option<&str>, n: usize, what: &str| -> Result<Option<usize>, String> {
        let s = part.unwrap_or("");
        if s.is_empty() {
            return Ok(None);
        }
        let k: i64 = s
            .parse()
            .map_err(|_| format!("bad {what} index '{s}' in '{word}'"))?;
        let i = match k {
            0 => return Ok(None),
            k if k > 0 => k - 1,
            k => n as i64 + k,
        };
        if i < 0 || i >= n as i64 {
            return Err(format!(
                "{what} index {k} in '{word}' is out of range ({n} read so far)"
            ));
        }
        Ok(Some(i as usize))
    };
    let v = index(parts.next(), nv, "vertex")?
        .ok_or_else(|| format!("face reference '{word}' has no vertex"))?;
    let t = index(parts.next(), nt, "texture")?;
    let n = index(parts.next(), nn, "normal")?;
    if parts.next().is_some() {
        return Err(format!("bad face reference '{word}'"));
    }
    Ok((v, t, n))
}

/// Twice the signed area of a 2-D triangle.
fn area2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// Most vertices of one OBJ face.
pub const MAX_FACE_VERTICES: usize = 4096;

/// Cut a simple polygon (counter-clockwise 2-D points) into triangles by ear clipping:
/// indices into `p`. None when no ear can be found (a self-intersecting outline).
fn ear_clip(p: &[[f64; 2]]) -> Option<Vec<[usize; 3]>> {
    let mut v: Vec<usize> = (0..p.len()).collect();
    let mut out = Vec::with_capacity(p.len().saturating_sub(2));
    let mut tries = 2 * v.len();
    let mut at = v.len() - 1;
    while v.len() > 2 {
        if tries == 0 {
            return None;
        }
        tries -= 1;
        let n = v.len();
        let u = if at >= n { 0 } else { at };
        let m = (u + 1) % n;
        let w = (m + 1) % n;
        at = m;
        let (a, b, c) = (p[v[u]], p[v[m]], p[v[w]]);
        if area2(a, b, c) <= 0.0 {
            continue;
        }
        let inside = v.iter().enumerate().any(|(k, &q)| {
            k != u
                && k != m
                && k != w
                && area2(a, b, p[q]) >= 0.0
                && area2(b, c, p[q]) >= 0.0
                && area2(c, a, p[q]) >= 0.0
        });
        if inside {
            continue;
        }
        out.push([v[u], v[m], v[w]]);
        v.remove(m);
        tries = 2 * v.len();
        at = m;
    }
    Some(out)
}

impl Reader<'_> {
    fn vertex(&mut self, c: Corner) -> u32 {
        if let Some(&k) = self.verts.get(&c) {
            return k;
        }
        let k = self.out.pos.len() as u32;
        let m = &mut self.out;
        m.pos.push(self.pos[c.0]);
        let mut f = 0;
        match c.2 {
            Some(n) => {
                m.normal.push(self.normals[n].as_vec3());
                f |= HAS_NORMAL;
            }
            None => m.normal.push(Vec3::ZERO),
        }
        match c.1 {
            Some(t) => {
                m.uv.push(self.uv[t]);
                f |= HAS_UV;
            }
            None => m.uv.push([0.0; 2]),
        }
        m.flags.push(f);
        self.verts.insert(c, k);
        k
    }

    /// Add one triangle (obj2mesh's per-triangle rules).
    fn triangle(&mut self, mut t: [Corner; 3], modifier: i16, line: u32) {
        if t.iter().any(|c| c.1.is_none()) {
            for c in &mut t {
                c.1 = None;
            }
        }
        if t.iter().any(|c| c.2.is_none()) {
            for c in &mut t {
                c.2 = None;
            }
        }
        let [p1, p2, p3] = t.map(|c| self.pos[c.0]);
        let fnorm = (p2 - p1).cross(p3 - p2);
        let len = fnorm.length();
        if !len.is_finite() || len <= 0.0 {
            self.out.warnings.push(format!(
                "{}:{line}: degenerate (zero-area) triangle skipped",
                self.file
            ));
            return;
        }
        let mut fnorm = fnorm / len;
        if t[0].2.is_some() {
            let dots = |t: &[Corner; 3], f: DVec3| t.map(|c| self.normals[c.2.unwrap_or(0)].dot(f));
            if dots(&t, fnorm).iter().all(|&d| d < 0.0) {
                t.swap(0, 2);
                fnorm = -fnorm;
            }
            if dots(&t, fnorm).iter().all(|&d| d > COSTOL) {
                for c in &mut t {
                    c.2 = None;
                }
            }
        }
        let v = t.map(|c| self.vertex(c));
        self.out.tris.push(MeshTri {
            v,
            modifier: modifier.into(),
        });
    }

    /// Cut a face into triangles.
    fn face(&mut self, corners: &[Corner], modifier: i16, line: u32) {
        if corners.len() == 3 {
            self.triangle([corners[0], corners[1], corners[2]], modifier, line);
            return;
        }
        let p: Vec<DVec3> = corners.iter().map(|c| self.pos[c.0]).collect();
        // Newell's normal: its dominant axis is the one dropped.
        let mut n = DVec3::ZERO;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            n += DVec3::new(
                (a.y - b.y) * (a.z + b.z),
                (a.z - b.z) * (a.x + b.x),
                (a.x - b.x) * (a.y + b.y),
            );
        }
        let ax = n.abs().max_position();
        let (i, j) = [(1, 2), (2, 0), (0, 1)][ax];
        let flip = n[ax] < 0.0;
        let mut q: Vec<[f64; 2]> = p.iter().map(|v| [v[i], v[j]]).collect();
        if flip {
            q.reverse();
        }
        let Some(tris) = ear_clip(&q) else {
            self.out.warnings.push(format!(
                "{}:{line}: face of {} vertices could not be cut into triangles (self-intersecting?); skipped",
                self.file,
                corners.len()
            ));
            return;
        };
        let last = corners.len() - 1;
        for tri in tris {
            let k = if flip {
                [last - tri[2], last - tri[1], last - tri[0]]
            } else {
                tri
            };
            self.triangle(k.map(|k| corners[k]), modifier, line);
        }
    }

    fn name_id(&mut self, name: &str, line: u32) -> Result<i16, String> {
        if let Some(&k) = self.name_ids.get(name) {
            return Ok(k);
        }
        if self.out.names.len() >= MAX_NAMES {
            return Err(format!("more than {MAX_NAMES} modifier names"));
        }
        let k = self.out.names.len() as i16;
        self.out.names.push((name.to_string(), line));
        self.name_ids.insert(name.to_string(), k);
        Ok(k)
    }
}

/// Read an OBJ file's text (`file`: its name, for warnings `file:line: ...`); an error is
/// its line and message.
pub fn parse_obj(text: &str, file: &str) -> Result<ObjMesh, (u32, String)> {
    let mut r = Reader {
        file,
        pos: Vec::new(),
        uv: Vec::new(),
        normals: Vec::new(),
        out: ObjMesh::default(),
        verts: HashMap::new(),
        name_ids: HashMap::new(),
    };
    let mut material: Option<(String, u32)> = None;
    let mut group: Option<(String, u32)> = None;
    let mut unknown = 0usize;
    let mut first_unknown = 0u32;
    for (k, raw) in text.lines().enumerate() {
        let line = (k + 1) as u32;
        let at = |m: String| (line, m);
        let mut words = raw.split_whitespace();
        let Some(key) = words.next() else { continue };
        match key {
            "v" => {
                let mut p = DVec3::ZERO;
                for (c, axis) in ["x", "y", "z"].iter().enumerate() {
                    p[c] = number(words.next(), &format!("vertex {axis}")).map_err(at)?;
                }
                r.pos.push(p);
            }
            "vn" => {
                let mut n = DVec3::ZERO;
                for (c, axis) in ["x", "y", "z"].iter().enumerate() {
                    n[c] = number(words.next(), &format!("normal {axis}")).map_err(at)?;
                }
                let n = n.normalize_or_zero();
                if n == DVec3::ZERO {
                    return Err(at("zero normal".into()));
                }
                r.normals.push(n);
            }
            "vt" => {
                let u = number(words.next(), "texture u").map_err(at)?;
                let v = number(words.next(), "texture v").map_err(at)?;
                r.uv.push([u, v]);
            }
            "f" => {
                let corners: Vec<Corner> = words
                    .map(|w| corner(w, r.pos.len(), r.uv.len(), r.normals.len()))
                    .collect::<Result<_, _>>()
                    .map_err(at)?;
                if corners.len() < 3 {
                    return Err(at(format!("face of {} vertices", corners.len())));
                }
                // Ear clipping takes time growing as the square of a face's vertices
                // (200,000 took 111 s): faces beyond any modelled polygon are refused.
                if corners.len() > MAX_FACE_VERTICES {
                    return Err(at(format!(
                        "face of {} vertices (at most {MAX_FACE_VERTICES}: split it, or \
                         triangulate the model when exporting it)",
                        corners.len()
                    )));
                }
                let modifier = match material.as_ref().or(group.as_ref()) {
                    Some((name, l)) => {
                        let (name, l) = (name.clone(), *l);
                        r.name_id(&name, l).map_err(at)?
                    }
                    None => -1,
                };
                r.face(&corners, modifier, line);
            }
            "usemtl" => {
                let name = words
                    .next()
                    .ok_or_else(|| at("usemtl without a name".into()))?;
                material = Some((name.to_string(), line));
            }
            "g" => group = words.next().map(|g| (g.to_string(), line)),
            "o" | "usemap" => {}
            _ if key.starts_with('#') => {}
            _ => {
                if unknown == 0 {
                    first_unknown = line;
                }
                unknown += 1;
            }
        }
    }
    if unknown > 0 {
        r.out.warnings.push(format!(
            "{file}:{first_unknown}: {unknown} unrecognised statement(s) ignored"
        ));
    }
    Ok(r.out)
}

/// An OBJ set's modifier names waiting to be bound.
#[derive(Debug)]
pub struct ObjNames {
    /// The file as named.
    pub(crate) file: String,
    /// The names triangles use and the line that set each first.
    pub(crate) names: Vec<(String, u32)>,
    /// The default modifier (`-m`, `--obj-material`), the last entry of the set's modifiers.
    pub(crate) default: Option<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_are_cut_and_references_resolved() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nvt 0 0\nvn 0 0 1\n\
                    g grp\nf 1 2 3 4\nusemtl red\nf -5/1/1 -4/1/1 -3/1/1 5/1/1 4/1/1\n";
        let m = parse_obj(text, "t.obj").unwrap();
        assert_eq!(m.tris.len(), 2 + 3);
        assert_eq!(
            m.names,
            vec![("grp".to_string(), 8), ("red".to_string(), 10)]
        );
        assert!(m.tris[..2].iter().all(|t| t.modifier == 0));
        assert!(m.tris[2..].iter().all(|t| t.modifier == 1));
        for t in &m.tris {
            let [a, b, c] = t.v.map(|k| m.pos[k as usize]);
            assert!((b - a).cross(c - a).z > 0.0, "orientation kept");
        }
        // Flat normals (all along the face normal) are dropped; uv kept.
        assert!(m.flags.iter().all(|f| f & HAS_NORMAL == 0));
        assert!(m.flags.iter().skip(4).all(|f| f & HAS_UV != 0));
    }

    #[test]
    fn a_clockwise_face_keeps_its_orientation_and_reversed_normals_turn_it() {
        let text = "v 0 0 0\nv 0 1 0\nv 1 1 0\nv 1 0 0\nvn 0 0 1\nf 1 2 3 4\n\
                    f 1//1 2//1 3//1\n";
        let m = parse_obj(text, "t.obj").unwrap();
        assert_eq!(m.tris.len(), 3);
        let z = |t: &MeshTri| {
            let [a, b, c] = t.v.map(|k| m.pos[k as usize]);
            (b - a).cross(c - a).z
        };
        assert!(z(&m.tris[0]) < 0.0 && z(&m.tris[1]) < 0.0);
        // Its normals point along +z, its face along −z: turned over, then flat.
        assert!(z(&m.tris[2]) > 0.0);
    }

    #[test]
    fn errors_name_the_line() {
        for (text, want) in [
            ("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "t.obj:3: vertex index 3"),
            ("v 0 0 x\n", "t.obj:1: bad vertex z 'x'"),
            ("v 0 0\n", "t.obj:1: missing vertex z"),
            ("vn 0 0 0\n", "t.obj:1: zero normal"),
            ("v 0 0 0\nf 1 1\n", "t.obj:2: face of 2 vertices"),
            ("v 0 0 0\nf 1/a 1 1\n", "t.obj:2: bad texture index 'a'"),
            ("v 0 0 nan\n", "t.obj:1: bad vertex z"),
        ] {
            let (line, e) = parse_obj(text, "t.obj").unwrap_err();
            let e = format!("t.obj:{line}: {e}");
            assert!(e.starts_with(want), "{e}");
        }
    }
}
