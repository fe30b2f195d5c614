//! Planar polygons (`x1 y1 z1 x2 y2 z2 ...`, at least 3 vertices, CCW seen from the front).
//!
//! The normal is the sum of the fan cross products from vertex 0 (area-weighted, so concave
//! polygons and seam-joined holes work), a duplicated closing vertex is dropped and the plane
//! offset is the average over all vertices. The inside test is an even–odd crossing test in
//! the 2-D projection that drops the dominant normal axis; points within `FTINY` of an edge
//! count as inside, so adjacent polygons leave no cracks.

use glam::DVec3;

use super::plain::Plain;
use crate::scene::primitive::Primitive;
use crate::FTINY;

/// Relative tolerance for the non-planar-vertex warning (Radiance's `VERTEPS`).
const VERTEPS: f64 = 1e-5;

/// Per-edge data of the 2-D projection (made on the fly from the vertices; only each
/// edge's length is stored, in [`Vertex::len`]).
#[derive(Clone, Copy, Debug)]
struct Edge2 {
    /// Start vertex.
    a: [f64; 2],
    /// End minus start.
    e: [f64; 2],
    /// Squared length.
    len2: f64,
    /// Length.
    len: f64,
}

/// A vertex with the projected length of the edge that starts at it (its square root is
/// the one costly part of an edge: the rest is made again at each test, bit for bit).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Vertex {
    p: DVec3,
    len: f64,
}

// SAFETY: `#[repr(C)]` of four f64 (32 bytes, no padding, any bits).
unsafe impl Plain for Vertex {}

/// A planar polygon's plain record, stored in the relative frame (96 bytes; its vertices,
/// 32 bytes each, lie in a pool: `pool[first..first + count]`). What only set-up and light
/// sources read (bounds, centroid) is computed when asked. [`PolyRef`] is a record with its
/// vertices, [`PolygonBuf`] one that owns them.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct Polygon {
    /// Unit normal, or the zero vector when the area is zero (then it is never hit).
    pub normal: DVec3,
    /// Plane offset: the plane is `normal · x = offset` (average over the vertices).
    pub offset: f64,
    /// Area (of the even–odd region, holes excluded).
    pub area: f64,
    /// 2-D bounding box of the projection, grown by the length tolerance.
    lo2: [f64; 2],
    hi2: [f64; 2],
    /// The scene's length tolerance: hits at `t <= eps` are ignored and points within `eps`
    /// of an edge are inside.
    pub(crate) eps: f64,
    /// Index of the first vertex in the pool.
    pub(crate) first: u32,
    /// Number of vertices (at least 3), without a duplicated closing vertex.
    pub(crate) count: u32,
    /// Index of the first kept coordinate of the 2-D projection (0–2).
    iu: u8,
    /// Index of the second kept coordinate of the 2-D projection (0–2).
    iv: u8,
    /// For a convex polygon, the sign of its turn in the projection (+1 counter-clockwise,
    /// −1 clockwise): the inside test is then one half-plane test per edge. 0 for concave
    /// polygons, polygons with holes and degenerate ones (the general crossing test).
    convex: i8,
    /// Non-zero for a convex polygon whose projection is an axis-aligned rectangle: its edge
    /// tests are the bounding-box test.
    is_box: u8,
    _pad: [u8; 4],
}

// SAFETY: `#[repr(C)]`: 10 f64, 2 u32, 4 one-byte fields and 4 bytes of explicit padding
// (96 bytes, no implicit padding); any bits are a value (indices are checked on loading).
unsafe impl Plain for Polygon {}

const _: () = assert!(std::mem::size_of::<Polygon>() == 96);

/// A polygon record with its vertices.
#[derive(Clone, Copy, Debug)]
pub struct PolyRef<'a> {
    rec: &'a Polygon,
    verts: &'a [Vertex],
}

impl std::ops::Deref for PolyRef<'_> {
    type Target = Polygon;

    fn deref(&self) -> &Polygon {
        self.rec
    }
}

/// A polygon that owns its vertices (what [`PolygonBuf::new`] makes; a scene keeps the record
/// and moves the vertices into its pool).
#[derive(Clone, Debug)]
pub struct PolygonBuf {
    /// The record (`first` is 0).
    pub rec: Polygon,
    /// Its vertices.
    pub verts: Box<[Vertex]>,
}

impl PolygonBuf {
    /// The polygon with its vertices.
    #[inline]
    pub fn r(&self) -> PolyRef<'_> {
        PolyRef {
            rec: &self.rec,
            verts: &self.verts,
        }
    }

    /// Use the scene's length tolerance `eps` (instead of `FTINY`).
    pub(crate) fn set_eps(&mut self, eps: f64) {
        let rec = &mut self.rec;
        rec.eps = eps;
        let mut lo2 = [f64::INFINITY; 2];
        let mut hi2 = [f64::NEG_INFINITY; 2];
        for v in self.verts.iter() {
            let a = rec.project(v.p);
            for k in 0..2 {
                lo2[k] = lo2[k].min(a[k]);
                hi2[k] = hi2[k].max(a[k]);
            }
        }
        for k in 0..2 {
            rec.lo2[k] = lo2[k] - eps;
            rec.hi2[k] = hi2[k] + eps;
        }
    }
}

impl Polygon {
    /// This record with its vertices in `pool`. The record's range must lie in the pool
    /// (scenes check it when they load one).
    #[inline]
    pub fn with<'a>(&'a self, pool: &'a [Vertex]) -> PolyRef<'a> {
        let a = self.first as usize;
        PolyRef {
            rec: self,
            verts: &pool[a..a + self.count as usize],
        }
    }

    /// [`PolyRef::intersect`] of this record with its vertices in `pool`: the vertices are
    /// only read when the plane is hit inside the projection's box (never for boxes).
    #[inline]
    pub fn intersect_in(&self, pool: &[Vertex], org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let (t, p) = self.plane_hit(org, dir, tmax)?;
        (self.is_box != 0 || self.with(pool).inside_edges(p)).then_some(t)
    }

    /// The plane and box part of the hit test: the distance and the projected point when
    /// the ray meets the plane within `(eps, tmax)` inside the projection's box.
    #[inline(always)]
    fn plane_hit(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<(f64, [f64; 2])> {
        let denom = self.normal.dot(dir);
        if denom.abs() <= FTINY {
            return None;
        }
        let t = (self.offset - self.normal.dot(org)) / denom;
        if !(t > self.eps && t < tmax) {
            return None;
        }
        let p = self.project(org + dir * t);
        if p[0] < self.lo2[0] || p[0] > self.hi2[0] || p[1] < self.lo2[1] || p[1] > self.hi2[1] {
            return None;
        }
        Some((t, p))
    }

    /// A point's coordinates in the projection.
    #[inline(always)]
    fn project(&self, p: DVec3) -> [f64; 2] {
        [p[self.iu as usize], p[self.iv as usize]]
    }

    /// Whether the record is usable with a pool of `pool` vertices: its range lies in it,
    /// it has at least 3 vertices and its projection axes are axes.
    pub(crate) fn valid_in(&self, pool: usize) -> bool {
        self.count >= 3
            && (self.first as usize).saturating_add(self.count as usize) <= pool
            && self.iu < 3
            && self.iv < 3
    }
}

impl PolygonBuf {
    /// Build from a `polygon` primitive. Fewer than 9 or a non-multiple of 3 real arguments
    /// is an error. Returns a warning for zero area or non-planar vertices.
    pub fn from_primitive(p: &Primitive, origin: DVec3) -> Result<(Self, Option<String>), String> {
        let r = &p.rargs;
        if r.len() < 9 || !r.len().is_multiple_of(3) {
            return Err(format!("bad # arguments for polygon \"{}\"", p.name));
        }
        let verts: Vec<DVec3> = r
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]) - origin)
            .collect();
        let (poly, warn) = PolygonBuf::new(verts)?;
        Ok((
            poly,
            warn.map(|w| format!("{w} for polygon \"{}\"", p.name)),
        ))
    }

    /// Build from vertices already in the relative frame. Returns a warning text ("zero
    /// area", "non-planar vertex") when appropriate.
    pub fn new(mut verts: Vec<DVec3>) -> Result<(Self, Option<String>), String> {
        if verts.len() < 3 {
            return Err("fewer than 3 vertices".to_string());
        }
        if verts.iter().any(|v| !v.is_finite()) {
            return Err("non-finite vertex".to_string());
        }
        // A last vertex repeating the first closes the polygon explicitly: drop it. "Repeats"
        // is within FTINY, relative to the polygon's extent below a unit, so that a scene
        // scaled down keeps its shapes.
        let (lo, hi) = verts.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        let close = FTINY * (hi - lo).max_element().min(1.0);
        if verts.len() > 3 && verts[0].distance(verts[verts.len() - 1]) <= close {
            verts.pop();
        }
        let n = verts.len();
        let v0 = verts[0];
        let mut sum = DVec3::ZERO;
        for i in 1..n - 1 {
            sum += (verts[i] - v0).cross(verts[i + 1] - v0);
        }
        let mut size: f64 = 0.0;
        for v in &verts {
            size = size.max(v.distance(v0));
        }
        let slen = sum.length();
        let mut warn = None;
        let (normal, area) = if slen > 0.0 && slen > 1e-12 * size * size {
            (sum / slen, 0.5 * slen)
        } else {
            warn = Some("zero area".to_string());
            (DVec3::ZERO, 0.0)
        };
        let offset = verts.iter().map(|v| normal.dot(*v)).sum::<f64>() / n as f64;
        if warn.is_none()
            && verts
                .iter()
                .any(|v| (normal.dot(*v) - offset).abs() > VERTEPS * size)
        {
            warn = Some("non-planar vertex".to_string());
        }
        // Projection: drop the dominant normal axis.
        let an = normal.abs();
        let drop = if an.x >= an.y && an.x >= an.z {
            0
        } else if an.y >= an.z {
            1
        } else {
            2
        };
        let (iu, iv) = match drop {
            0 => (1u8, 2u8),
            1 => (2, 0),
            _ => (0, 1),
        };
        let edges: Vec<Edge2> = (0..n)
            .map(|i| edge_of(verts[i], verts[(i + 1) % n], iu, iv, None))
            .collect();
        let convex = convex_turn(&edges);
        let is_box = convex.is_some()
            && edges.len() == 4
            && edges.iter().all(|ed| (ed.e[0] == 0.0) != (ed.e[1] == 0.0));
        let vertex = |i: usize| Vertex {
            p: verts[i],
            len: edges[i].len,
        };
        if n > u32::MAX as usize {
            return Err("too many vertices".to_string());
        }
        let verts: Box<[Vertex]> = (0..n).map(vertex).collect();
        let mut poly = PolygonBuf {
            rec: Polygon {
                normal,
                offset,
                area,
                lo2: [0.0; 2],
                hi2: [0.0; 2],
                eps: FTINY,
                first: 0,
                count: n as u32,
                iu,
                iv,
                convex: convex.map_or(0, |s| s as i8),
                is_box: u8::from(is_box),
                _pad: [0; 4],
            },
            verts,
        };
        poly.set_eps(FTINY);
        Ok((poly, warn))
    }
}

impl<'a> PolyRef<'a> {
    /// The number of vertices.
    pub fn len(&self) -> usize {
        self.verts.len()
    }

    /// False: a polygon has at least 3 vertices.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The vertices (relative frame), without a duplicated closing vertex.
    pub fn verts(&self) -> impl ExactSizeIterator<Item = DVec3> + Clone + 'a {
        self.verts.iter().map(|v| v.p)
    }

    /// Area-weighted centroid (vertex average when the area is zero).
    pub fn centroid(&self) -> DVec3 {
        let verts = self.verts;
        let n = verts.len();
        let vavg = verts.iter().map(|v| v.p).sum::<DVec3>() / n as f64;
        if self.area <= 0.0 {
            return vavg;
        }
        // Signed weights along the normal, so that holes subtract.
        let v0 = verts[0].p;
        let mut acc = DVec3::ZERO;
        let mut wsum = 0.0;
        for i in 1..n - 1 {
            let c = (verts[i].p - v0).cross(verts[i + 1].p - v0);
            let w = c.dot(self.normal);
            acc += (v0 + verts[i].p + verts[i + 1].p) * (w / 3.0);
            wsum += w;
        }
        if wsum != 0.0 {
            acc / wsum
        } else {
            vavg
        }
    }

    /// Nearest intersection distance in `(FTINY, tmax)`; `|n·d| <= FTINY` is a miss (and so is
    /// every ray for a zero-area polygon).
    #[inline]
    pub fn intersect(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let (t, p) = self.rec.plane_hit(org, dir, tmax)?;
        (self.is_box != 0 || self.inside_edges(p)).then_some(t)
    }

    /// Inside test for a point assumed to lie in the plane (even–odd, edges inclusive).
    pub fn contains(&self, p: DVec3) -> bool {
        self.area > 0.0 && self.contains_projected(self.project(p))
    }

    /// The edges in the projection, each made from its two vertices.
    #[inline]
    fn edges(&self) -> impl Iterator<Item = Edge2> + 'a {
        let v = self.verts;
        let n = v.len();
        let (iu, iv) = (self.iu, self.iv);
        (0..n).map(move |i| edge_of(v[i].p, v[(i + 1) % n].p, iu, iv, Some(v[i].len)))
    }

    /// Inside test in the projection; points within `FTINY` of an edge are inside. Convex
    /// polygons test the half-plane of each edge, grown by `FTINY` (which also admits points
    /// within about `FTINY / sin(half the corner angle)` of a corner); the others use
    /// [`Polygon::contains_crossing`].
    #[inline]
    fn contains_projected(&self, p: [f64; 2]) -> bool {
        if p[0] < self.lo2[0] || p[0] > self.hi2[0] || p[1] < self.lo2[1] || p[1] > self.hi2[1] {
            return false;
        }
        self.is_box != 0 || self.inside_edges(p)
    }

    /// [`PolyRef::contains_projected`] for a point inside the projection's box, of a
    /// polygon that is not a box.
    #[inline]
    fn inside_edges(&self, p: [f64; 2]) -> bool {
        if self.convex != 0 {
            let s = f64::from(self.convex);
            self.edges().all(|ed| {
                let cross = ed.e[0] * (p[1] - ed.a[1]) - ed.e[1] * (p[0] - ed.a[0]);
                s * cross >= -self.eps * ed.len
            })
        } else {
            self.contains_crossing(p)
        }
    }

    /// Even–odd crossing test in the projection; points within `FTINY` of an edge are inside.
    fn contains_crossing(&self, p: [f64; 2]) -> bool {
        let mut inside = false;
        for ed in self.edges() {
            let rx = p[0] - ed.a[0];
            let ry = p[1] - ed.a[1];
            // On-edge test: projection parameter within the segment, distance <= FTINY.
            let s = rx * ed.e[0] + ry * ed.e[1];
            let cross = ed.e[0] * ry - ed.e[1] * rx;
            if ed.len2 > 0.0 {
                if s >= -self.eps * ed.len
                    && s <= ed.len2 + self.eps * ed.len
                    && cross.abs() <= self.eps * ed.len
                {
                    return true;
                }
            } else if rx * rx + ry * ry <= self.eps * self.eps {
                return true;
            }
            // Crossing test with a half-open rule on y: edge spans p.y, crossing right of p.
            let ay = ed.a[1];
            let by = ed.a[1] + ed.e[1];
            if (ay > p[1]) != (by > p[1]) {
                // x of the edge at p.y is right of p.x ⇔ cross has the sign of e.y.
                if (cross > 0.0) == (ed.e[1] > 0.0) {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Axis-aligned bounds of the vertices.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.verts().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(v), hi.max(v)),
        )
    }
}

/// The projected edge from `a` to `b`; `len`, when given, is its length as computed before.
#[inline]
fn edge_of(a: DVec3, b: DVec3, iu: u8, iv: u8, len: Option<f64>) -> Edge2 {
    let (iu, iv) = (iu as usize, iv as usize);
    let a = [a[iu], a[iv]];
    let b = [b[iu], b[iv]];
    let e = [b[0] - a[0], b[1] - a[1]];
    let len2 = e[0] * e[0] + e[1] * e[1];
    Edge2 {
        a,
        e,
        len2,
        len: len.unwrap_or_else(|| len2.sqrt()),
    }
}

/// The turn sign (+1 counter-clockwise, −1 clockwise) of a strictly convex, simple polygon
/// given by its projected edges; None when any edge is degenerate, two consecutive edges are
/// collinear or turn the other way, or the edges wind around more than once.
fn convex_turn(edges: &[Edge2]) -> Option<f64> {
    let n = edges.len();
    if n < 3 || edges.iter().any(|e| e.len.is_nan() || e.len <= 0.0) {
        return None;
    }
    let mut sign = 0.0;
    let mut winding = 0.0;
    for i in 0..n {
        let (a, b) = (edges[i].e, edges[(i + 1) % n].e);
        let cross = a[0] * b[1] - a[1] * b[0];
        let dot = a[0] * b[0] + a[1] * b[1];
        // Strictly turning, relative to the edges' lengths.
        if cross.abs() <= 1e-12 * edges[i].len * edges[(i + 1) % n].len {
            return None;
        }
        let s = cross.signum();
        if sign == 0.0 {
            sign = s;
        } else if s != sign {
            return None;
        }
        winding += cross.atan2(dot);
    }
    // One turn around: the exterior angles sum to ±2π (a pentagram sums to ±4π).
    ((winding.abs() - 2.0 * std::f64::consts::PI).abs() < 1e-6).then_some(sign)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq() -> PolygonBuf {
        PolygonBuf::new(vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ])
        .unwrap()
        .0
    }

    #[test]
    fn square_basics() {
        let p = sq();
        let p = p.r();
        assert_eq!(p.normal, DVec3::Z);
        assert!((p.area - 1.0).abs() < 1e-15);
        assert!((p.centroid() - DVec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
        assert!(p.contains(DVec3::new(0.5, 0.5, 0.0)));
        assert!(p.contains(DVec3::new(1.0, 0.5, 0.0)));
        assert!(p.contains(DVec3::new(1.0 + 0.5e-6, 0.5, 0.0)));
        assert!(!p.contains(DVec3::new(1.0 + 2e-6, 0.5, 0.0)));
        assert!(p.contains(DVec3::new(1.0, 1.0, 0.0)));
        assert!(!p.contains(DVec3::new(-0.5, 0.5, 0.0)));
    }

    /// A polygon is a 96-byte record and 32 bytes a vertex; it keeps its vertices in
    /// order, and its bounds are theirs.
    #[test]
    fn compact_storage_keeps_vertices() {
        assert_eq!(std::mem::size_of::<Vertex>(), 32);
        for n in [3usize, 4, 7] {
            let verts: Vec<DVec3> = (0..n)
                .map(|i| {
                    let t = i as f64 * std::f64::consts::TAU / n as f64;
                    DVec3::new(t.cos(), 2.0 * t.sin(), 0.1 * t.cos() + 3.0)
                })
                .collect();
            let (p, _) = PolygonBuf::new(verts.clone()).unwrap();
            let p = p.r();
            assert_eq!(p.len(), n);
            assert_eq!(p.verts().collect::<Vec<_>>(), verts);
            let lo = verts.iter().fold(DVec3::INFINITY, |a, v| a.min(*v));
            let hi = verts.iter().fold(DVec3::NEG_INFINITY, |a, v| a.max(*v));
            assert_eq!(p.bounds(), (lo, hi));
            // Each stored edge length is the projection's.
            for (ed, k) in p.edges().zip(0..) {
                let a = p.project(verts[k]);
                let b = p.project(verts[(k + 1) % n]);
                assert_eq!(
                    ed.len,
                    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
                );
            }
        }
    }

    #[test]
    fn closing_vertex_dropped() {
        let (p, w) = PolygonBuf::new(vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
        ])
        .unwrap();
        let p = p.r();
        assert_eq!(p.len(), 3);
        assert!(w.is_none());
        assert!((p.area - 0.5).abs() < 1e-15);
    }

    #[test]
    fn crossing_rule_through_vertex_row() {
        // A ray level with a vertex (y = 1 at the reflex vertex of a chevron).
        let (p, _) = PolygonBuf::new(vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(4.0, 2.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ])
        .unwrap();
        let p = p.r();
        assert!(p.contains(DVec3::new(1.0, 1.0, 0.0)));
        assert!(p.contains(DVec3::new(3.0, 1.0, 0.0)));
        assert!(!p.contains(DVec3::new(2.0, 1.5, 0.0)));
        assert!(!p.contains(DVec3::new(-1.0, 1.0, 0.0)));
        assert!(!p.contains(DVec3::new(5.0, 1.0, 0.0)));
    }

    /// The half-plane test of convex polygons agrees with the crossing test everywhere but
    /// within a few `FTINY` of a corner; concave polygons, holes and stars keep the crossing
    /// test.
    #[test]
    fn convex_fast_path_agrees_with_the_crossing_test() {
        let mut rng = crate::render::sampler::Sampler::for_pixel(0, 4, 5, 6);
        let mut rnd = || rng.uniform();
        let mut tested = 0;
        for case in 0..40 {
            // A convex polygon: sorted random angles on an ellipse, in a random plane
            // orientation (either winding).
            let n = 3 + case % 6;
            let mut ang: Vec<f64> = (0..n).map(|_| rnd() * std::f64::consts::TAU).collect();
            ang.sort_by(f64::total_cmp);
            if case % 2 == 1 {
                ang.reverse();
            }
            let (a, b) = (0.5 + 2.0 * rnd(), 0.5 + 2.0 * rnd());
            let (ux, uy) = (
                DVec3::new(1.0, 0.3 * rnd(), 0.2),
                DVec3::new(-0.1, 1.0, 0.4 * rnd()),
            );
            let verts: Vec<DVec3> = ang
                .iter()
                .map(|t| ux * (a * t.cos()) + uy * (b * t.sin()))
                .collect();
            let Ok((p, _)) = PolygonBuf::new(verts.clone()) else {
                continue;
            };
            let p = p.r();
            if p.area <= 1e-3 || p.convex == 0 {
                continue;
            }
            tested += 1;
            for _ in 0..2000 {
                // Points near the polygon, many near its edges.
                let k = (rnd() * n as f64) as usize % n;
                let e0 = verts[k];
                let e1 = verts[(k + 1) % n];
                let q = if rnd() < 0.5 {
                    let t = rnd();
                    e0 + (e1 - e0) * t + p.normal.cross(e1 - e0).normalize() * (rnd() - 0.5) * 8e-6
                } else {
                    DVec3::new(rnd() * 6.0 - 3.0, rnd() * 6.0 - 3.0, 0.0)
                };
                let q = q - p.normal * (p.normal.dot(q) - p.offset);
                let pp = p.project(q);
                let in_box =
                    !(pp[0] < p.lo2[0] || pp[0] > p.hi2[0] || pp[1] < p.lo2[1] || pp[1] > p.hi2[1]);
                let fast = p.contains_projected(pp);
                let slow = in_box && p.contains_crossing(pp);
                if fast != slow {
                    let near = verts.iter().map(|v| v.distance(q)).fold(f64::MAX, f64::min);
                    assert!(
                        near < 200.0 * FTINY,
                        "case {case}: {q} differs, {near} from a corner"
                    );
                }
            }
        }
        assert!(tested >= 30, "only {tested} convex cases");
        // Not convex: a chevron, a pentagram.
        let chevron = PolygonBuf::new(vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(4.0, 2.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ])
        .unwrap()
        .0;
        assert_eq!(chevron.rec.convex, 0);
        let star: Vec<DVec3> = (0..5)
            .map(|i| {
                let t = i as f64 * 4.0 * std::f64::consts::PI / 5.0;
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        assert_eq!(PolygonBuf::new(star).unwrap().0.rec.convex, 0);
        assert_ne!(sq().rec.convex, 0);
    }
}
