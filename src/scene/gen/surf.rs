//! Built-in `gensurf`: a parametric surface tessellated into polygons.
//!
//! `gensurf mat name 'x(s,t)' 'y(s,t)' 'z(s,t)' m n [-s] [-i] [-e expr] [-f file]`: the
//! grid s = i/m, t = j/n (m, n rounded); cells in s-major order, each made of two
//! triangles or, when they are coplanar, one quad, named `name.1, 2, …` as gensurf 6.0a
//! does. A `valid(s,t)` function (two parameters, from `-e` or `-f`) ≤ 0 removes a
//! vertex and the polygons touching it. `-i` reverses the normals.
//!
//! `-s` adds, before each polygon, `mat texfunc Phong 4 surf_dx surf_dy surf_dz surf.cal
//! 0 13 axis m1 m2 m3 m4` (the polygon then takes `Phong` as modifier): vertex normals
//! from central differences of the grid (the grid is evaluated one step beyond [0,1];
//! one-sided differences next to invalid vertices), fitted over the cell's four corners
//! as N(u,w) = m1·uw + m2·u + m3·w + m4, where `axis` is the dominant axis of the corner
//! normals' sum and (u, w) are the next two axes cyclically; m4 is reduced by the
//! polygon's own normal; a singular fit gives no texture. `-s` on a grid where
//! `valid(s,t)` removes vertices is not built in (reported as unsupported): the real
//! program's textures next to removed vertices are not reproduced.
//!
//! Not built in: data files for z (or for x, y, z named alike) and `-` (standard input),
//! reported as unsupported; `-o` (Wavefront output, not a scene) is refused.

use glam::DVec3;

use super::funcs::{CalDef, Funcs};
use super::{count, g12, value, ArgError, GenContext};
use crate::scene::primitive::Primitive;

/// Parsed gensurf arguments.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfArgs {
    pub material: String,
    pub name: String,
    pub funcs: [String; 3],
    pub m: usize,
    pub n: usize,
    pub defs: Vec<CalDef>,
    pub smooth: bool,
    pub invert: bool,
}

const USAGE: &str =
    "usage: gensurf material name x(s,t) y(s,t) z(s,t) m n [-s][-i][-e expr][-f file]";

/// Most grid points accepted.
const MAX_POINTS: usize = 50_000_000;

/// Parse the arguments after the word `gensurf`.
pub fn parse_gensurf_args(args: &[String]) -> Result<SurfArgs, ArgError> {
    const P: &str = "gensurf";
    let bad = |s: String| ArgError::Bad(format!("gensurf: {s}"));
    if args.len() < 7 {
        return Err(bad(format!("too few arguments; {USAGE}")));
    }
    let z = &args[4];
    if z == "-" || std::path::Path::new(z).is_file() {
        return Err(ArgError::Unsupported(format!(
            "gensurf data input ('{z}') is not built in"
        )));
    }
    let mut a = SurfArgs {
        material: args[0].clone(),
        name: args[1].clone(),
        funcs: [args[2].clone(), args[3].clone(), z.clone()],
        m: count(P, "m", &args[5])?,
        n: count(P, "n", &args[6])?,
        defs: Vec::new(),
        smooth: false,
        invert: false,
    };
    if (a.m + 3).saturating_mul(a.n + 3) > MAX_POINTS {
        return Err(bad(format!("grid {} × {} is too large", a.m, a.n)));
    }
    let mut i = 7;
    while i < args.len() {
        match args[i].as_str() {
            "-e" => a.defs.push(CalDef::Expr(value(P, args, i)?.to_string())),
            "-f" => a.defs.push(CalDef::File(value(P, args, i)?.to_string())),
            "-s" | "-i" => {
                if args[i] == "-s" {
                    a.smooth = true;
                } else {
                    a.invert = true;
                }
                i += 1;
                continue;
            }
            "-o" => {
                return Err(bad(
                    "-o writes a Wavefront OBJ file, not a scene".to_string()
                ))
            }
            w => return Err(bad(format!("bad option '{w}'; {USAGE}"))),
        }
        i += 2;
    }
    Ok(a)
}

/// The evaluated grid, with one extra row and column on every side.
struct Grid {
    m: usize,
    n: usize,
    pts: Vec<DVec3>,
    valid: Vec<bool>,
}

impl Grid {
    /// Index of grid point (i, j), i in -1..=m+1, j in -1..=n+1.
    fn idx(&self, i: isize, j: isize) -> usize {
        (i + 1) as usize * (self.n + 3) + (j + 1) as usize
    }
    fn p(&self, i: isize, j: isize) -> DVec3 {
        self.pts[self.idx(i, j)]
    }
    fn ok(&self, i: isize, j: isize) -> bool {
        self.valid[self.idx(i, j)]
    }

    /// Vertex normal ∂P/∂s × ∂P/∂t (unit) by differences, one-sided next to invalid
    /// neighbours.
    fn normal(&self, i: isize, j: isize) -> DVec3 {
        if !self.ok(i, j) {
            return DVec3::ZERO;
        }
        let lo_i = if self.ok(i - 1, j) { i - 1 } else { i };
        let hi_i = if self.ok(i + 1, j) { i + 1 } else { i };
        let lo_j = if self.ok(i, j - 1) { j - 1 } else { j };
        let hi_j = if self.ok(i, j + 1) { j + 1 } else { j };
        let ds = self.p(hi_i, j) - self.p(lo_i, j);
        let dt = self.p(i, hi_j) - self.p(i, lo_j);
        ds.cross(dt).normalize_or_zero()
    }
}

/// Solve the 4×4 system `a x = b` (three right-hand sides) with partial pivoting; None if
/// singular.
fn solve4(mut a: [[f64; 4]; 4], mut b: [DVec3; 4]) -> Option<[DVec3; 4]> {
    let scale = a
        .iter()
        .flat_map(|r| r.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for c in 0..4 {
        let p = (c..4).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[p][c].abs() <= 1e-12 * scale.max(1e-300) {
            return None;
        }
        a.swap(c, p);
        b.swap(c, p);
        for r in 0..4 {
            if r != c {
                let f = a[r][c] / a[c][c];
                let pivot_row = a[c];
                for (x, p) in a[r].iter_mut().zip(pivot_row).skip(c) {
                    *x -= f * p;
                }
                b[r] -= f * b[c];
            }
        }
    }
    Some([0, 1, 2, 3].map(|k| b[k] / a[k][k]))
}

impl SurfArgs {
    fn grid(&self, cx: &GenContext) -> Result<Grid, ArgError> {
        let f = Funcs::compile(
            "gensurf",
            &self.defs,
            &[
                ("x", "s,t", &self.funcs[0]),
                ("y", "s,t", &self.funcs[1]),
                ("z", "s,t", &self.funcs[2]),
            ],
            cx.raypath,
        )?;
        let (m, n) = (self.m, self.n);
        let mut g = Grid {
            m,
            n,
            pts: Vec::with_capacity((m + 3) * (n + 3)),
            valid: Vec::with_capacity((m + 3) * (n + 3)),
        };
        for i in -1..=(m as isize + 1) {
            for j in -1..=(n as isize + 1) {
                let (s, t) = (i as f64 / m as f64, j as f64 / n as f64);
                let inside = i >= 0 && j >= 0 && i <= m as isize && j <= n as isize;
                let ok = match f.valid {
                    Some(v) => f.call_ref(v, "valid(s,t)", &[s, t]).map(|v| v > 0.0),
                    None => Ok(true),
                };
                // Points beyond the grid only serve the normals: an evaluation error
                // there counts as an invalid vertex.
                let val = ok.and_then(|ok| {
                    if !ok {
                        return Ok(None);
                    }
                    Ok(Some(DVec3::new(
                        f.call(0, &[s, t])?,
                        f.call(1, &[s, t])?,
                        f.call(2, &[s, t])?,
                    )))
                });
                let val = match val {
                    Ok(v) => v,
                    Err(_) if !inside => None,
                    Err(e) => return Err(e),
                };
                g.valid.push(val.is_some());
                g.pts.push(val.unwrap_or(DVec3::ZERO));
            }
        }
        Ok(g)
    }

    /// The primitives, as real gensurf prints them.
    pub fn generate(&self, cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
        let g = self.grid(cx)?;
        if self.smooth && (0..=g.m as isize).any(|i| (0..=g.n as isize).any(|j| !g.ok(i, j))) {
            return Err(ArgError::Unsupported(
                "gensurf -s with vertices that valid(s,t) removes is not built in".to_string(),
            ));
        }
        let loc = cx.loc;
        // At most two triangles a cell (reserved, then shrunk in place: a growing list
        // would hold up to three times its size while it moves).
        let cells = g.m.saturating_mul(g.n);
        let mut out = Vec::with_capacity(cells.saturating_mul(2).min(cx.max_primitives) + 4);
        let mut k = 0usize;
        for i in 0..g.m as isize {
            for j in 0..g.n as isize {
                let odd = !g.ok(i, j) || !g.ok(i + 1, j + 1);
                let even = !odd && (!g.ok(i + 1, j) || !g.ok(i, j + 1));
                let odd_layout = odd || (!even && j % 2 == 1);
                let mut c = if odd_layout {
                    [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                } else {
                    [(i + 1, j), (i + 1, j + 1), (i, j), (i, j + 1)]
                };
                if self.invert {
                    c.swap(1, 2);
                }
                let p = c.map(|(a, b)| g.p(a, b));
                let ok = c.map(|(a, b)| g.ok(a, b));
                let tri_a = (ok[0] && ok[1] && ok[2])
                    .then(|| (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero())
                    .filter(|v| *v != DVec3::ZERO);
                let tri_b = (ok[1] && ok[2] && ok[3])
                    .then(|| (p[2] - p[3]).cross(p[1] - p[3]).normalize_or_zero())
                    .filter(|v| *v != DVec3::ZERO);
                // Texture fit over the four corners.
                let fit = if self.smooth {
                    let sign = if self.invert { -1.0 } else { 1.0 };
                    let nv = c.map(|(a, b)| sign * g.normal(a, b));
                    let sum = nv[0] + nv[1] + nv[2] + nv[3];
                    let s = sum.abs();
                    let axis = if s.x > s.y && s.x > s.z {
                        0
                    } else if s.y > s.z {
                        1
                    } else {
                        2
                    };
                    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                    let a = p.map(|q| [q[u] * q[w], q[u], q[w], 1.0]);
                    solve4(a, nv).map(|m| (axis, m))
                } else {
                    None
                };
                let mut emit = |pts: &[DVec3], face: DVec3, out: &mut Vec<Primitive>| {
                    k += 1;
                    let mut modifier = self.material.as_str();
                    if let Some((axis, m)) = fit {
                        let mut r = vec![axis as f64];
                        let m4 = m[3] - face;
                        for v in [m[0], m[1], m[2], m4] {
                            r.extend([g12(v.x), g12(v.y), g12(v.z)]);
                        }
                        out.push(Primitive {
                            modifier: self.material.clone(),
                            ptype: "texfunc".into(),
                            name: "Phong".into(),
                            sargs: ["surf_dx", "surf_dy", "surf_dz", "surf.cal"]
                                .map(String::from)
                                .to_vec(),
                            iargs: Vec::new(),
                            rargs: r,
                            loc: loc.clone(),
                        });
                        modifier = "Phong";
                    }
                    let r = pts
                        .iter()
                        .flat_map(|q| [g12(q.x), g12(q.y), g12(q.z)])
                        .collect();
                    out.push(super::prim(
                        modifier,
                        "polygon",
                        format!("{}.{k}", self.name),
                        r,
                        loc,
                    ));
                };
                match (tri_a, tri_b) {
                    (Some(na), Some(nb)) if na.dot(nb) >= 1.0 - 1e-12 => {
                        emit(&[p[0], p[1], p[3], p[2]], 0.5 * (na + nb), &mut out)
                    }
                    (a, b) => {
                        if let Some(na) = a {
                            emit(&[p[0], p[1], p[2]], na, &mut out);
                        }
                        if let Some(nb) = b {
                            emit(&[p[2], p[1], p[3]], nb, &mut out);
                        }
                    }
                }
            }
            cx.check_made("gensurf", out.len())?;
        }
        out.shrink_to_fit();
        Ok(out)
    }
}

/// Parse and generate in one step.
pub fn gensurf(args: &[String], cx: &GenContext) -> Result<Vec<Primitive>, ArgError> {
    parse_gensurf_args(args)?.generate(cx)
}
