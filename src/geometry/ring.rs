//! Rings and disks (`cx cy cz nx ny nz r0 r1`).

use glam::DVec3;

use super::{disk_bounds, perp_frame, turn_fraction, vec_at};
use crate::scene::primitive::Primitive;
use crate::FTINY;

/// A flat annulus around `center` in the plane with unit `normal` (a disk when `r0 == 0`).
/// A point of the plane is on the ring when `r0 <= distance <= r1`.
#[derive(Clone, Debug)]
pub struct Ring {
    /// Centre (relative frame).
    pub center: DVec3,
    /// Unit normal (the front side).
    pub normal: DVec3,
    /// Inner radius (>= 0).
    pub r0: f64,
    /// Outer radius (> r0).
    pub r1: f64,
    /// Perpendicular frame for the `u` coordinate.
    e1: DVec3,
    e2: DVec3,
    /// The scene's length tolerance: hits at `t <= eps` are ignored.
    pub(crate) eps: f64,
}

impl Ring {
    /// Build from a `ring` primitive. Radii given in decreasing order are swapped (as
    /// Radiance does); negative or equal radii and a zero normal are errors.
    pub fn from_primitive(p: &Primitive, origin: DVec3) -> Result<Ring, String> {
        if p.rargs.len() != 8 {
            return Err(format!("bad # arguments for ring \"{}\"", p.name));
        }
        let (mut r0, mut r1) = (p.rargs[6], p.rargs[7]);
        if r0 > r1 {
            std::mem::swap(&mut r0, &mut r1);
        }
        Ring::new(vec_at(&p.rargs, 0) - origin, vec_at(&p.rargs, 3), r0, r1)
            .map_err(|e| format!("{e} for ring \"{}\"", p.name))
    }

    /// Build directly (relative frame); `normal` need not be unit length.
    pub fn new(center: DVec3, normal: DVec3, r0: f64, r1: f64) -> Result<Ring, String> {
        if !(r0 >= 0.0 && r1 > r0 && r1.is_finite()) {
            return Err("illegal radii".to_string());
        }
        let len = normal.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err("unknown orientation".to_string());
        }
        let normal = normal / len;
        let (e1, e2) = perp_frame(normal);
        Ok(Ring {
            center,
            normal,
            r0,
            r1,
            e1,
            e2,
            eps: FTINY,
        })
    }

    /// Nearest intersection distance in `(eps, tmax)`; `|n·d| <= FTINY` is a miss.
    #[inline]
    pub fn intersect(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let denom = self.normal.dot(dir);
        if denom.abs() <= FTINY {
            return None;
        }
        let oc = org - self.center;
        let t = -self.normal.dot(oc) / denom;
        if !(t > self.eps && t < tmax) {
            return None;
        }
        let d2 = (oc + dir * t).length_squared();
        if d2 >= self.r0 * self.r0 && d2 <= self.r1 * self.r1 {
            Some(t)
        } else {
            None
        }
    }

    /// `(u, v)`: angle around the centre as a fraction of a turn, distance / `r1`.
    pub fn uv_at(&self, p: DVec3) -> (f64, f64) {
        let v = p - self.center;
        (turn_fraction(v, self.e1, self.e2), v.length() / self.r1)
    }

    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        disk_bounds(self.center, self.normal, self.r1)
    }

    /// Area π(r1² − r0²).
    pub fn area(&self) -> f64 {
        std::f64::consts::PI * (self.r1 * self.r1 - self.r0 * self.r0)
    }
}

impl Ring {
    /// Words in [`Ring::to_words`].
    pub(crate) const WORDS: usize = 15;

    /// Its fields as numbers (a scene image stores them).
    pub(crate) fn to_words(&self) -> [f64; Self::WORDS] {
        let (c, n, a, b) = (self.center, self.normal, self.e1, self.e2);
        [
            c.x, c.y, c.z, n.x, n.y, n.z, self.r0, self.r1, a.x, a.y, a.z, b.x, b.y, b.z, self.eps,
        ]
    }

    /// What [`Ring::to_words`] made; None for non-finite values.
    pub(crate) fn from_words(w: &[f64]) -> Option<Ring> {
        let w: &[f64; Self::WORDS] = w.try_into().ok()?;
        let v = |i: usize| DVec3::new(w[i], w[i + 1], w[i + 2]);
        let r = Ring {
            center: v(0),
            normal: v(3),
            r0: w[6],
            r1: w[7],
            e1: v(8),
            e2: v(11),
            eps: w[14],
        };
        (w.iter().all(|x| x.is_finite()) && r.eps > 0.0).then_some(r)
    }
}
