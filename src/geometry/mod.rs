//! Surfaces (polygon, sphere/bubble, cone/cup/cylinder/tube, ring, distant source) and the BVH.
//!
//! All geometry is stored in `f64` **relative to a scene origin** chosen by the caller (for
//! example the centre of the scene bounds): constructors take that origin and subtract it from
//! every position, so that coordinates stay small and rounding errors stay far below
//! [`FTINY`]. Rays handed to [`Surface::intersect`] and [`bvh::Bvh`] are in the same relative
//! frame and have unit-length directions.
//!
//! Robustness rules (after Radiance):
//! - spawned rays start exactly at the previous hit point; every intersector rejects
//!   `t <= FTINY`;
//! - a plane (polygon, ring) with `|n·d| <= FTINY` is parallel to the ray and never hit;
//! - quadratic surfaces are solved with the origin first moved along the ray to the point
//!   closest to the surface centre, with a cancellation-free discriminant, so that rays from
//!   far away or from the surface itself keep full precision;
//! - polygon points within `FTINY` of an edge count as inside, so neighbours leave no cracks.
//!
//! What is tested to hold (`tests/geometry.rs`): a scene translated by (1e6, −1e6, 1e6) with
//! the origin at its centre behaves like the untranslated one (hit distances agree to 1e-6);
//! with the origin left at (0,0,0) the same scene still gives no self-hits, no escapes through
//! the corners of a closed room and no cracks between adjacent polygons, because f64 keeps
//! about 1e-10 absolute precision at 1e6. That margin shrinks with distance: at about 1e9–1e10
//! from the origin rounding reaches `FTINY` and self-hits become possible, so callers should
//! always pass the scene centre as the origin.

use glam::DVec3;

use crate::scene::primitive::Primitive;

pub mod bvh;
mod bvh_build;
mod bvh_window;
pub mod cone;
pub mod plain;
pub mod polygon;
pub mod ring;
pub mod source;
pub mod sphere;
pub mod trimesh;

/// A finite surface that owns its data (what a primitive builds; a scene's objects keep
/// them in arrays by kind, [`crate::scene::object::Objects`], and lend [`SurfaceRef`]s).
#[derive(Clone, Debug)]
pub enum Surface {
    /// A planar polygon (possibly concave, possibly with seam-joined holes).
    Polygon(polygon::PolygonBuf),
    /// A sphere or bubble.
    Sphere(sphere::Sphere),
    /// A cone, cup, cylinder or tube (open-ended).
    Cone(cone::Cone),
    /// A ring or disk.
    Ring(ring::Ring),
}

/// A finite surface as tracing sees it: borrowed from a scene's arrays or from a
/// [`Surface`].
#[derive(Clone, Copy, Debug)]
pub enum SurfaceRef<'a> {
    /// A planar polygon with its vertices.
    Polygon(polygon::PolyRef<'a>),
    /// A sphere or bubble.
    Sphere(&'a sphere::Sphere),
    /// A cone, cup, cylinder or tube.
    Cone(&'a cone::Cone),
    /// A ring or disk.
    Ring(&'a ring::Ring),
}

/// Geometry at a hit point.
#[derive(Clone, Copy, Debug)]
pub struct HitGeom {
    /// The hit point (relative frame).
    pub point: DVec3,
    /// Unit surface normal pointing to the surface's FRONT (outside), NOT flipped toward the ray.
    pub normal: DVec3,
    /// Surface-local coordinates (u,v) where meaningful, (0,0) otherwise: for cones
    /// `u` = angle around the axis / 2π in `[0,1)` and `v` = fraction of the way from `p0` to
    /// `p1`; for rings `u` = the same angle fraction and `v` = distance from the centre / `r1`.
    pub uv: (f64, f64),
}

/// Read a 3-vector from `r[i..i + 3]` (the caller has checked the length).
pub(crate) fn vec_at(r: &[f64], i: usize) -> DVec3 {
    DVec3::new(r[i], r[i + 1], r[i + 2])
}

/// Check that every real argument is finite.
pub(crate) fn check_finite(p: &Primitive) -> Result<(), String> {
    if p.rargs.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!(
            "non-finite real argument for {} \"{}\"",
            p.ptype, p.name
        ))
    }
}

/// Roots of `a·t² + 2·b·t + c = 0` in ascending order, computed without cancellation.
///
/// A slightly negative discriminant (relative to the size of its terms) counts as a double
/// root, a clearly negative one as no root. With `a == 0` the single linear root is returned
/// twice. Never returns NaN.
pub(crate) fn quadratic_half(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return None;
    }
    let mut disc = b * b - a * c;
    if disc < 0.0 {
        if disc >= -1e-12 * (b * b + (a * c).abs()) {
            disc = 0.0;
        } else {
            return None;
        }
    }
    let sq = disc.sqrt();
    let q = if b >= 0.0 { -(b + sq) } else { -b + sq };
    if a == 0.0 {
        // Linear: 2 b t + c = 0.
        if b == 0.0 {
            return None;
        }
        let t = -c / (2.0 * b);
        return Some((t, t));
    }
    let t1 = q / a;
    let t2 = if q != 0.0 { c / q } else { t1 };
    let (lo, hi) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
    if lo.is_nan() || hi.is_nan() {
        return None;
    }
    Some((lo, hi))
}

/// Pick the first root in `(eps, tmax)` from an ascending pair that also passes `ok`.
pub(crate) fn pick_root(
    roots: (f64, f64),
    eps: f64,
    tmax: f64,
    mut ok: impl FnMut(f64) -> bool,
) -> Option<f64> {
    [roots.0, roots.1]
        .into_iter()
        .find(|&t| t > eps && t < tmax && ok(t))
}

/// A unit vector perpendicular to the unit vector `n` (the tangent frame's first axis,
/// reversed).
pub fn any_perpendicular(n: DVec3) -> DVec3 {
    -perp_frame(n).0
}

/// Unit vectors `(e1, e2)` perpendicular to the unit vector `n` and to each other.
pub(crate) fn perp_frame(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.6 {
        DVec3::X
    } else if n.y.abs() < 0.6 {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let e1 = a.cross(n).normalize();
    let e2 = n.cross(e1);
    (e1, e2)
}

/// Angle of `v` in the plane `(e1, e2)` as a fraction of a turn, in `[0, 1)`.
pub(crate) fn turn_fraction(v: DVec3, e1: DVec3, e2: DVec3) -> f64 {
    let a = v.dot(e2).atan2(v.dot(e1)) / std::f64::consts::TAU;
    let f = if a < 0.0 { a + 1.0 } else { a };
    if f >= 1.0 || !f.is_finite() {
        0.0
    } else {
        f
    }
}

/// Bounds of a disk with centre `c`, unit normal `n`, radius `r`.
pub(crate) fn disk_bounds(c: DVec3, n: DVec3, r: f64) -> (DVec3, DVec3) {
    let ext = DVec3::new(
        (1.0 - n.x * n.x).max(0.0).sqrt(),
        (1.0 - n.y * n.y).max(0.0).sqrt(),
        (1.0 - n.z * n.z).max(0.0).sqrt(),
    ) * r;
    (c - ext, c + ext)
}

impl Surface {
    /// Build from a primitive of type polygon/sphere/bubble/cone/cup/cylinder/tube/ring.
    ///
    /// Errors (a message without location; the caller adds file:line): wrong argument counts,
    /// non-finite arguments, zero radius, illegal radii (mixed signs, equal ring radii),
    /// degenerate axis or ring normal, fewer than 3 vertices, unknown type. Radiance itself
    /// only warns about and drops most of these objects; the caller decides. A zero-area
    /// polygon is NOT an error (it is kept but never hit). Negative radii flip the type like
    /// Radiance (sphere ↔ bubble, cone ↔ cup, cylinder ↔ tube); [`Surface::from_primitive_warn`]
    /// also reports Radiance's warning text for those cases.
    pub fn from_primitive(p: &Primitive, origin: DVec3) -> Result<Surface, String> {
        Self::from_primitive_warn(p, origin).map(|(s, _)| s)
    }

    /// Like [`Surface::from_primitive`], also returning the warning Radiance would print
    /// (negative radius type flips, zero-area or non-planar polygons), if any.
    pub fn from_primitive_warn(
        p: &Primitive,
        origin: DVec3,
    ) -> Result<(Surface, Option<String>), String> {
        check_finite(p)?;
        match p.ptype.as_str() {
            "polygon" => polygon::PolygonBuf::from_primitive(p, origin)
                .map(|(s, w)| (Surface::Polygon(s), w)),
            "sphere" | "bubble" => {
                sphere::Sphere::from_primitive(p, origin).map(|(s, w)| (Surface::Sphere(s), w))
            }
            "cone" | "cup" | "cylinder" | "tube" => {
                cone::Cone::from_primitive(p, origin).map(|(s, w)| (Surface::Cone(s), w))
            }
            "ring" => ring::Ring::from_primitive(p, origin).map(|s| (Surface::Ring(s), None)),
            other => Err(format!("type \"{other}\" is not a finite surface")),
        }
    }

    /// Use the scene's length tolerance `eps` (FTINY until set): the minimum hit distance
    /// and the polygons' edge tolerance.
    pub fn set_eps(&mut self, eps: f64) {
        match self {
            Surface::Polygon(s) => s.set_eps(eps),
            Surface::Sphere(s) => s.eps = eps,
            Surface::Cone(s) => s.eps = eps,
            Surface::Ring(s) => s.eps = eps,
        }
    }

    /// The surface as tracing sees it.
    #[inline]
    pub fn as_ref(&self) -> SurfaceRef<'_> {
        match self {
            Surface::Polygon(s) => SurfaceRef::Polygon(s.r()),
            Surface::Sphere(s) => SurfaceRef::Sphere(s),
            Surface::Cone(s) => SurfaceRef::Cone(s),
            Surface::Ring(s) => SurfaceRef::Ring(s),
        }
    }

    /// [`SurfaceRef::intersect`].
    pub fn intersect(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        self.as_ref().intersect(org, dir, tmax)
    }

    /// [`SurfaceRef::hit_geom`].
    pub fn hit_geom(&self, org: DVec3, dir: DVec3, t: f64) -> HitGeom {
        self.as_ref().hit_geom(org, dir, t)
    }

    /// [`SurfaceRef::normal_at`].
    pub fn normal_at(&self, point: DVec3) -> DVec3 {
        self.as_ref().normal_at(point)
    }

    /// [`SurfaceRef::bounds`].
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.as_ref().bounds()
    }

    /// [`SurfaceRef::is_flat`].
    pub fn is_flat(&self) -> bool {
        self.as_ref().is_flat()
    }

    /// [`SurfaceRef::area`].
    pub fn area(&self) -> f64 {
        self.as_ref().area()
    }
}

impl SurfaceRef<'_> {
    /// Nearest intersection distance t with eps < t < tmax, or None (eps: the scene's length
    /// tolerance, [`Surface::set_eps`]).
    #[inline]
    pub fn intersect(self, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        match self {
            SurfaceRef::Polygon(s) => s.intersect(org, dir, tmax),
            SurfaceRef::Sphere(s) => s.intersect(org, dir, tmax),
            SurfaceRef::Cone(s) => s.intersect(org, dir, tmax),
            SurfaceRef::Ring(s) => s.intersect(org, dir, tmax),
        }
    }

    /// Geometry of the hit at distance t along (org, dir).
    pub fn hit_geom(&self, org: DVec3, dir: DVec3, t: f64) -> HitGeom {
        let point = org + dir * t;
        match self {
            SurfaceRef::Polygon(s) => HitGeom {
                point,
                normal: s.normal,
                uv: (0.0, 0.0),
            },
            SurfaceRef::Sphere(s) => HitGeom {
                point,
                normal: s.normal_at(point),
                uv: (0.0, 0.0),
            },
            SurfaceRef::Cone(s) => {
                let (normal, uv) = s.normal_uv_at(point);
                HitGeom { point, normal, uv }
            }
            SurfaceRef::Ring(s) => HitGeom {
                point,
                normal: s.normal,
                uv: s.uv_at(point),
            },
        }
    }

    /// Unit front normal at a point on the surface: [`SurfaceRef::hit_geom`] without the
    /// surface coordinates, which the tracer does not need.
    #[inline]
    pub fn normal_at(&self, point: DVec3) -> DVec3 {
        match self {
            SurfaceRef::Polygon(s) => s.normal,
            SurfaceRef::Sphere(s) => s.normal_at(point),
            SurfaceRef::Cone(s) => s.normal_at(point),
            SurfaceRef::Ring(s) => s.normal,
        }
    }

    /// Axis-aligned bounds (relative frame), not yet padded.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match self {
            SurfaceRef::Polygon(s) => s.bounds(),
            SurfaceRef::Sphere(s) => s.bounds(),
            SurfaceRef::Cone(s) => s.bounds(),
            SurfaceRef::Ring(s) => s.bounds(),
        }
    }

    /// True for planar surfaces (polygon, ring).
    pub fn is_flat(&self) -> bool {
        matches!(self, SurfaceRef::Polygon(_) | SurfaceRef::Ring(_))
    }

    /// Surface area.
    pub fn area(&self) -> f64 {
        match self {
            SurfaceRef::Polygon(s) => s.area,
            SurfaceRef::Sphere(s) => s.area(),
            SurfaceRef::Cone(s) => s.area(),
            SurfaceRef::Ring(s) => s.area(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadratic_basic() {
        // (t-1)(t-3) = t² - 4t + 3 → a=1, b=-2, c=3
        let (a, b) = quadratic_half(1.0, -2.0, 3.0).unwrap();
        assert!((a - 1.0).abs() < 1e-15 && (b - 3.0).abs() < 1e-15);
        // negative a: -(t-1)(t-3)
        let (a, b) = quadratic_half(-1.0, 2.0, -3.0).unwrap();
        assert!((a - 1.0).abs() < 1e-15 && (b - 3.0).abs() < 1e-15);
        assert!(quadratic_half(1.0, 0.0, 1.0).is_none());
        // linear 2t - 4 = 0
        assert_eq!(quadratic_half(0.0, 1.0, -4.0), Some((2.0, 2.0)));
        assert!(quadratic_half(0.0, 0.0, 1.0).is_none());
        assert!(quadratic_half(f64::NAN, 0.0, 1.0).is_none());
        // double root
        let (a, b) = quadratic_half(1.0, -1.0, 1.0).unwrap();
        assert_eq!((a, b), (1.0, 1.0));
    }

    #[test]
    fn frame_is_orthonormal() {
        for n in [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            DVec3::new(1.0, 2.0, -3.0).normalize(),
        ] {
            let (e1, e2) = perp_frame(n);
            assert!(e1.dot(n).abs() < 1e-15 && e2.dot(n).abs() < 1e-15);
            assert!(e1.dot(e2).abs() < 1e-15);
            assert!((e1.length() - 1.0).abs() < 1e-15 && (e2.length() - 1.0).abs() < 1e-15);
        }
    }
}
