//! Cones, cups, cylinders and tubes (open-ended, no caps, like Radiance).
//!
//! `cone`/`cup`: `x0 y0 z0 x1 y1 z1 r0 r1`; `cylinder`/`tube`: `x0 y0 z0 x1 y1 z1 r`.
//! Cups and tubes have inward normals. Both radii negative (or a negative cylinder radius)
//! flips the type with a warning; mixed signs or both radii zero are illegal.

use glam::DVec3;

use super::{disk_bounds, perp_frame, pick_root, quadratic_half, turn_fraction, vec_at};
use crate::scene::primitive::Primitive;
use crate::FTINY;

/// Which of the four cone-family types a [`Cone`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConeKind {
    /// Outward-facing cone frustum.
    Cone,
    /// Inward-facing cone frustum.
    Cup,
    /// Outward-facing cylinder.
    Cylinder,
    /// Inward-facing cylinder.
    Tube,
}

impl ConeKind {
    /// True for the inward-facing kinds (cup, tube).
    pub fn inward(self) -> bool {
        matches!(self, ConeKind::Cup | ConeKind::Tube)
    }

    fn flipped(self) -> ConeKind {
        match self {
            ConeKind::Cone => ConeKind::Cup,
            ConeKind::Cup => ConeKind::Cone,
            ConeKind::Cylinder => ConeKind::Tube,
            ConeKind::Tube => ConeKind::Cylinder,
        }
    }
}

/// An open cone frustum or cylinder from `p0` (radius `r0`) to `p1` (radius `r1`).
#[derive(Clone, Debug)]
pub struct Cone {
    /// The type (cylinder and tube have `r0 == r1`).
    pub kind: ConeKind,
    /// Start of the axis (relative frame).
    pub p0: DVec3,
    /// End of the axis (relative frame).
    pub p1: DVec3,
    /// Radius at `p0` (>= 0).
    pub r0: f64,
    /// Radius at `p1` (>= 0; not both zero).
    pub r1: f64,
    /// Unit axis from `p0` to `p1`.
    pub axis: DVec3,
    /// Axis length.
    pub len: f64,
    /// Radius slope `(r1 − r0) / len`.
    slope: f64,
    /// Axis midpoint (used to move ray origins close before solving).
    mid: DVec3,
    /// Perpendicular frame for the `u` coordinate.
    e1: DVec3,
    e2: DVec3,
    /// The scene's length tolerance: hits at `t <= eps` are ignored.
    pub(crate) eps: f64,
}

impl Cone {
    /// Build from a cone/cup/cylinder/tube primitive. Returns Radiance's warning for
    /// negative radii (the type is flipped), if any.
    pub fn from_primitive(p: &Primitive, origin: DVec3) -> Result<(Cone, Option<String>), String> {
        let (mut kind, cyl) = match p.ptype.as_str() {
            "cone" => (ConeKind::Cone, false),
            "cup" => (ConeKind::Cup, false),
            "cylinder" => (ConeKind::Cylinder, true),
            "tube" => (ConeKind::Tube, true),
            other => return Err(format!("type \"{other}\" is not a cone")),
        };
        let need = if cyl { 7 } else { 8 };
        if p.rargs.len() != need {
            return Err(format!("bad # arguments for {} \"{}\"", p.ptype, p.name));
        }
        let (mut r0, mut r1) = if cyl {
            (p.rargs[6], p.rargs[6])
        } else {
            (p.rargs[6], p.rargs[7])
        };
        let mut warn = None;
        if r0 <= 0.0 && r1 <= 0.0 && (r0 < 0.0 || r1 < 0.0) {
            let what = if cyl { "radius" } else { "radii" };
            warn = Some(format!("negative {what} for {} \"{}\"", p.ptype, p.name));
            r0 = -r0;
            r1 = -r1;
            kind = kind.flipped();
        }
        if r0 < 0.0 || r1 < 0.0 || (r0 == 0.0 && r1 == 0.0) {
            return Err(format!("illegal radii for {} \"{}\"", p.ptype, p.name));
        }
        Cone::new(
            kind,
            vec_at(&p.rargs, 0) - origin,
            vec_at(&p.rargs, 3) - origin,
            r0,
            r1,
        )
        .map_err(|e| format!("{e} for {} \"{}\"", p.ptype, p.name))
        .map(|c| (c, warn))
    }

    /// Build directly (relative frame). Radii must be >= 0 and not both zero, the axis must
    /// have non-zero length.
    pub fn new(kind: ConeKind, p0: DVec3, p1: DVec3, r0: f64, r1: f64) -> Result<Cone, String> {
        if !(r0 >= 0.0 && r1 >= 0.0 && r0.is_finite() && r1.is_finite()) || (r0 == 0.0 && r1 == 0.0)
        {
            return Err("illegal radii".to_string());
        }
        let a = p1 - p0;
        let len = a.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err("unknown orientation".to_string());
        }
        let axis = a / len;
        let (e1, e2) = perp_frame(axis);
        Ok(Cone {
            kind,
            p0,
            p1,
            r0,
            r1,
            axis,
            len,
            slope: (r1 - r0) / len,
            mid: (p0 + p1) * 0.5,
            e1,
            e2,
            eps: FTINY,
        })
    }

    /// Nearest intersection distance in `(eps, tmax)` with the open lateral surface.
    #[inline]
    pub fn intersect(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let dd = dir.length_squared();
        if dd == 0.0 {
            return None;
        }
        // Move the origin to the ray point closest to the axis midpoint.
        let t0 = (self.mid - org).dot(dir) / dd;
        let o = org + dir * t0 - self.p0;
        let w = self.axis;
        let k = self.slope;
        let oz = o.dot(w);
        let orad = o - w * oz;
        let dz = dir.dot(w);
        let drad = dir - w * dz;
        let rz = self.r0 + k * oz;
        let a = drad.length_squared() - k * k * dz * dz;
        let b = orad.dot(drad) - k * dz * rz;
        let c = orad.length_squared() - rz * rz;
        let roots = quadratic_half(a, b, c)?;
        let len = self.len;
        pick_root((t0 + roots.0, t0 + roots.1), self.eps, tmax, |t| {
            let z = oz + (t - t0) * dz;
            (0.0..=len).contains(&z)
        })
    }

    /// Front normal and (u, v) at a point on the surface.
    pub fn normal_uv_at(&self, p: DVec3) -> (DVec3, (f64, f64)) {
        let (z, radv) = self.axial(p);
        let u = turn_fraction(radv, self.e1, self.e2);
        let v = (z / self.len).clamp(0.0, 1.0);
        (self.normal_from(radv), (u, v))
    }

    /// Unit front normal at a point on the surface (no surface coordinates: the tracer's
    /// case, which saves the angle's atan2).
    pub fn normal_at(&self, p: DVec3) -> DVec3 {
        self.normal_from(self.axial(p).1)
    }

    /// A point's height along the axis from `p0` and its offset from the axis.
    #[inline]
    fn axial(&self, p: DVec3) -> (f64, DVec3) {
        let rel = p - self.p0;
        let z = rel.dot(self.axis);
        (z, rel - self.axis * z)
    }

    /// The front normal at a surface point whose offset from the axis is `radv`.
    #[inline]
    fn normal_from(&self, radv: DVec3) -> DVec3 {
        let rho = radv.length();
        let n = if rho > 0.0 {
            (radv / rho - self.axis * self.slope).normalize_or(radv / rho)
        } else if self.slope <= 0.0 {
            self.axis
        } else {
            -self.axis
        };
        if self.kind.inward() {
            -n
        } else {
            n
        }
    }

    /// Axis-aligned bounds (exact for the two end circles).
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let (a0, b0) = disk_bounds(self.p0, self.axis, self.r0);
        let (a1, b1) = disk_bounds(self.p1, self.axis, self.r1);
        (a0.min(a1), b0.max(b1))
    }

    /// Lateral area π(r0 + r1)·slant.
    pub fn area(&self) -> f64 {
        let dr = self.r1 - self.r0;
        std::f64::consts::PI * (self.r0 + self.r1) * (self.len * self.len + dr * dr).sqrt()
    }
}

impl Cone {
    /// Words in [`Cone::to_words`].
    pub(crate) const WORDS: usize = 26;

    /// Its fields as numbers (a scene image stores them).
    pub(crate) fn to_words(&self) -> [f64; Self::WORDS] {
        let kind = match self.kind {
            ConeKind::Cone => 0.0,
            ConeKind::Cup => 1.0,
            ConeKind::Cylinder => 2.0,
            ConeKind::Tube => 3.0,
        };
        let mut w = [0.0; Self::WORDS];
        w[0] = kind;
        for (k, v) in [self.p0, self.p1, self.axis, self.mid, self.e1, self.e2]
            .into_iter()
            .enumerate()
        {
            w[1 + 3 * k..4 + 3 * k].copy_from_slice(&v.to_array());
        }
        w[19..26].copy_from_slice(&[self.r0, self.r1, self.len, self.slope, self.eps, 0.0, 0.0]);
        w
    }

    /// What [`Cone::to_words`] made; None for non-finite or impossible values.
    pub(crate) fn from_words(w: &[f64]) -> Option<Cone> {
        let w: &[f64; Self::WORDS] = w.try_into().ok()?;
        let kind = match w[0] as u8 {
            _ if w[0].fract() != 0.0 => return None,
            0 => ConeKind::Cone,
            1 => ConeKind::Cup,
            2 => ConeKind::Cylinder,
            3 => ConeKind::Tube,
            _ => return None,
        };
        let v = |k: usize| DVec3::new(w[1 + 3 * k], w[2 + 3 * k], w[3 + 3 * k]);
        let c = Cone {
            kind,
            p0: v(0),
            p1: v(1),
            axis: v(2),
            mid: v(3),
            e1: v(4),
            e2: v(5),
            r0: w[19],
            r1: w[20],
            len: w[21],
            slope: w[22],
            eps: w[23],
        };
        (w.iter().all(|x| x.is_finite()) && c.len > 0.0 && c.eps > 0.0).then_some(c)
    }
}
