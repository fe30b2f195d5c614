//! Triangle meshes (Radiance's compiled `.rtm` meshes): shared vertices in f64 relative to
//! the mesh's own origin, optional per-vertex normals and (u,v).
//!
//! The intersection follows the polygon rules: a triangle parallel to the ray
//! (`|n·d| <= FTINY`) is missed, hits at `t <= eps` are ignored and points within `eps` of
//! an edge count as inside, so neighbouring triangles leave no cracks. The front is the
//! counter-clockwise side, the geometric normal `(v1 − v0) × (v2 − v0)` normalised.

use glam::{DVec3, Vec3};

use super::plain::{Plain, Slab};
use crate::FTINY;

/// A vertex has a normal.
pub const HAS_NORMAL: u8 = 2;
/// A vertex has (u,v).
pub const HAS_UV: u8 = 4;

/// A triangle: three vertex indices (counter-clockwise seen from the front) and its
/// modifier (an object index into the mesh's scene, −1 for void): 16 bytes of plain data.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct MeshTri {
    /// Vertex indices.
    pub v: [u32; 3],
    /// Modifier object index, −1 = void.
    pub modifier: i32,
}

// SAFETY: `#[repr(C)]` of four 32-bit integers (no padding, any bits; indices are checked
// where a mesh is loaded from a scene image).
unsafe impl Plain for MeshTri {}

/// A triangle mesh. Its arrays are [`Slab`]s (owned, or lent by a scene image).
#[derive(Debug, Default)]
pub struct TriMesh {
    /// Vertex positions (relative to the mesh origin).
    pub pos: Slab<DVec3>,
    /// Vertex normals (zero where absent).
    pub normal: Slab<Vec3>,
    /// Vertex (u,v).
    pub uv: Slab<[f64; 2]>,
    /// [`HAS_NORMAL`] | [`HAS_UV`] per vertex.
    pub flags: Slab<u8>,
    /// Triangles.
    pub tris: Slab<MeshTri>,
    /// Length tolerance (minimum hit distance, edge tolerance).
    pub eps: f64,
}

impl TriMesh {
    #[inline]
    fn verts(&self, i: usize) -> [DVec3; 3] {
        let v = self.tris[i].v;
        [
            self.pos[v[0] as usize],
            self.pos[v[1] as usize],
            self.pos[v[2] as usize],
        ]
    }

    /// Bounds of triangle `i`.
    pub fn bounds(&self, i: usize) -> (DVec3, DVec3) {
        let [a, b, c] = self.verts(i);
        (a.min(b).min(c), a.max(b).max(c))
    }

    /// Unit geometric normal of triangle `i` (zero for a degenerate one).
    #[inline]
    pub fn normal(&self, i: usize) -> DVec3 {
        let [a, b, c] = self.verts(i);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Nearest intersection distance with triangle `i`, `eps < t < tmax`.
    #[inline]
    pub fn intersect(&self, i: usize, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let [a, b, c] = self.verts(i);
        let n = (b - a).cross(c - a);
        let nl = n.length();
        if nl.is_nan() || nl <= 0.0 {
            return None;
        }
        let nu = n / nl;
        let dn = nu.dot(dir);
        if dn.abs() <= FTINY {
            return None;
        }
        let oa = org - a;
        let t = -nu.dot(oa) / dn;
        if !(t > self.eps && t < tmax) {
            return None;
        }
        // The hit relative to vertex a.
        let p = oa + dir * t;
        let eps = self.eps;
        let inside = |e: DVec3, q: DVec3| -> bool {
            let s = e.cross(q).dot(nu);
            s >= -eps * e.length()
        };
        (inside(b - a, p) && inside(c - b, p - (b - a)) && inside(a - c, p - (c - a))).then_some(t)
    }

    /// Barycentric weights of `point` (relative frame) in triangle `i`, clamped to the
    /// triangle.
    fn weights(&self, i: usize, point: DVec3) -> [f64; 3] {
        let [a, b, c] = self.verts(i);
        let n = (b - a).cross(c - a);
        let n2 = n.length_squared();
        if n2.is_nan() || n2 <= 0.0 {
            return [1.0 / 3.0; 3];
        }
        let wa = (c - b).cross(point - b).dot(n) / n2;
        let wb = (a - c).cross(point - c).dot(n) / n2;
        let wc = 1.0 - wa - wb;
        let w = [wa.max(0.0), wb.max(0.0), wc.max(0.0)];
        let s = w[0] + w[1] + w[2];
        if s > 0.0 {
            [w[0] / s, w[1] / s, w[2] / s]
        } else {
            [1.0 / 3.0; 3]
        }
    }

    /// The smooth normal (unit, mesh frame) and the (u,v) at `point` of triangle `i`: each
    /// only when all three vertices have it (Radiance's rule).
    pub fn interpolate(&self, i: usize, point: DVec3) -> (Option<DVec3>, Option<[f64; 2]>) {
        let v = self.tris[i].v.map(|k| k as usize);
        let all = |f: u8| v.iter().all(|&k| self.flags[k] & f != 0);
        let (hn, huv) = (all(HAS_NORMAL), all(HAS_UV));
        if !hn && !huv {
            return (None, None);
        }
        let w = self.weights(i, point);
        let n = hn.then(|| {
            let s: DVec3 = (0..3).map(|j| self.normal[v[j]].as_dvec3() * w[j]).sum();
            s.normalize_or_zero()
        });
        let uv = huv.then(|| {
            let mut r = [0.0; 2];
            for j in 0..3 {
                r[0] += self.uv[v[j]][0] * w[j];
                r[1] += self.uv[v[j]][1] * w[j];
            }
            r
        });
        (n.filter(|n| *n != DVec3::ZERO), uv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> TriMesh {
        TriMesh {
            pos: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ]
            .into(),
            normal: vec![Vec3::Z; 4].into(),
            uv: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].into(),
            flags: vec![HAS_NORMAL | HAS_UV; 4].into(),
            tris: vec![
                MeshTri {
                    v: [0, 1, 2],
                    modifier: 0,
                },
                MeshTri {
                    v: [0, 2, 3],
                    modifier: 0,
                },
            ]
            .into(),
            eps: FTINY,
        }
    }

    #[test]
    fn hits_normals_and_no_cracks() {
        let m = square();
        assert_eq!(m.normal(0), DVec3::Z);
        let down = -DVec3::Z;
        let t = m
            .intersect(0, DVec3::new(0.75, 0.25, 1.0), down, 10.0)
            .unwrap();
        assert!((t - 1.0).abs() < 1e-12);
        assert!(m
            .intersect(1, DVec3::new(0.75, 0.25, 1.0), down, 10.0)
            .is_none());
        // On the shared diagonal: both triangles count it.
        let o = DVec3::new(0.5, 0.5, 1.0);
        assert!(m.intersect(0, o, down, 10.0).is_some() && m.intersect(1, o, down, 10.0).is_some());
        // Parallel and behind.
        assert!(m
            .intersect(0, DVec3::new(-1.0, 0.5, 0.0), DVec3::X, 10.0)
            .is_none());
        assert!(m
            .intersect(0, DVec3::new(0.75, 0.25, -1.0), down, 10.0)
            .is_none());
        let (n, uv) = m.interpolate(0, DVec3::new(0.75, 0.25, 0.0));
        assert_eq!(n, Some(DVec3::Z));
        let uv = uv.unwrap();
        assert!((uv[0] - 0.75).abs() < 1e-12 && (uv[1] - 0.25).abs() < 1e-12);
    }
}
