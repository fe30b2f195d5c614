//! Spheres and bubbles (`cx cy cz radius`).

use glam::DVec3;

use super::{pick_root, quadratic_half, vec_at};
use crate::scene::primitive::Primitive;
use crate::FTINY;

/// A sphere (outward normal) or bubble (`inward`, normal toward the centre).
#[derive(Clone, Debug)]
pub struct Sphere {
    /// Centre (relative frame).
    pub center: DVec3,
    /// Radius, always > 0.
    pub radius: f64,
    /// True for a bubble: the front side is the inside.
    pub inward: bool,
    /// The scene's length tolerance: hits at `t <= eps` are ignored.
    pub(crate) eps: f64,
}

impl Sphere {
    /// Build from a `sphere` or `bubble` primitive. A negative radius flips the type (with a
    /// warning, like Radiance); zero radius and a wrong argument count are errors.
    pub fn from_primitive(
        p: &Primitive,
        origin: DVec3,
    ) -> Result<(Sphere, Option<String>), String> {
        if p.rargs.len() != 4 {
            return Err(format!("bad arguments for {} \"{}\"", p.ptype, p.name));
        }
        let mut inward = p.ptype == "bubble";
        let mut r = p.rargs[3];
        let mut warn = None;
        if r == 0.0 {
            return Err(format!("zero radius for {} \"{}\"", p.ptype, p.name));
        }
        if r < 0.0 {
            warn = Some(format!("negative radius for {} \"{}\"", p.ptype, p.name));
            r = -r;
            inward = !inward;
        }
        Ok((
            Sphere {
                center: vec_at(&p.rargs, 0) - origin,
                radius: r,
                inward,
                eps: FTINY,
            },
            warn,
        ))
    }

    /// Nearest intersection distance in `(eps, tmax)`.
    ///
    /// The origin is first moved along the ray to the point closest to the centre, and the
    /// discriminant is computed from the distance between that point and the centre, which
    /// keeps full precision for distant origins and for rays leaving the surface.
    #[inline]
    pub fn intersect(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let a = dir.length_squared();
        if a == 0.0 {
            return None;
        }
        let oc = org - self.center;
        let t0 = -oc.dot(dir) / a;
        let l = oc + dir * t0; // closest approach, perpendicular to dir
        let b = l.dot(dir); // ~0, kept for exactness
        let c = l.length_squared() - self.radius * self.radius;
        let roots = quadratic_half(a, b, c)?;
        pick_root((t0 + roots.0, t0 + roots.1), self.eps, tmax, |_| true)
    }

    /// Front normal at a point on the surface.
    pub fn normal_at(&self, p: DVec3) -> DVec3 {
        let n = (p - self.center).normalize_or(DVec3::Z);
        if self.inward {
            -n
        } else {
            n
        }
    }

    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let r = DVec3::splat(self.radius);
        (self.center - r, self.center + r)
    }

    /// Surface area 4πr².
    pub fn area(&self) -> f64 {
        4.0 * std::f64::consts::PI * self.radius * self.radius
    }
}

impl Sphere {
    /// Words in [`Sphere::to_words`].
    pub(crate) const WORDS: usize = 6;

    /// Its fields as numbers (a scene image stores them).
    pub(crate) fn to_words(&self) -> [f64; Self::WORDS] {
        let c = self.center;
        [
            c.x,
            c.y,
            c.z,
            self.radius,
            f64::from(u8::from(self.inward)),
            self.eps,
        ]
    }

    /// What [`Sphere::to_words`] made; None for non-finite or impossible values.
    pub(crate) fn from_words(w: &[f64]) -> Option<Sphere> {
        let w: &[f64; Self::WORDS] = w.try_into().ok()?;
        let s = Sphere {
            center: DVec3::new(w[0], w[1], w[2]),
            radius: w[3],
            inward: w[4] != 0.0,
            eps: w[5],
        };
        (w.iter().all(|x| x.is_finite()) && s.radius > 0.0 && s.eps > 0.0).then_some(s)
    }
}
