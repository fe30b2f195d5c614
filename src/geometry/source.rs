//! Distant sources (`source`: `dx dy dz angle`).

use glam::DVec3;

use super::{check_finite, vec_at};
use crate::scene::primitive::Primitive;

/// A distant source: direction toward the source (unit), full angular diameter in degrees,
/// solid angle 2π(1−cos(angle/2)).
#[derive(Clone, Debug)]
pub struct DistantSource {
    /// Unit direction toward the source.
    pub dir: DVec3,
    /// Full angular diameter in degrees.
    pub angle_deg: f64,
    /// Solid angle 2π(1 − cos(angle/2)) in steradians (<= 0 for angles <= 0: never hit).
    pub solid_angle: f64,
}

impl DistantSource {
    /// Build from a `source` primitive (4 real arguments). A zero direction is an error.
    pub fn from_primitive(p: &Primitive) -> Result<DistantSource, String> {
        if p.rargs.len() != 4 {
            return Err(format!("bad # arguments for source \"{}\"", p.name));
        }
        check_finite(p)?;
        DistantSource::new(vec_at(&p.rargs, 0), p.rargs[3])
            .map_err(|e| format!("{e} for source \"{}\"", p.name))
    }

    /// Build from a direction (any non-zero length) and a full angle in degrees.
    pub fn new(dir: DVec3, angle_deg: f64) -> Result<DistantSource, String> {
        let len = dir.length();
        if !(len > 0.0 && len.is_finite() && angle_deg.is_finite()) {
            return Err("illegal direction".to_string());
        }
        let half = (angle_deg * 0.5).to_radians();
        Ok(DistantSource {
            dir: dir / len,
            angle_deg,
            solid_angle: std::f64::consts::TAU * (1.0 - half.cos()),
        })
    }

    /// Radiance's test: 2π(1 − dir·d) < solid_angle (with an angle-0 source never hit).
    /// `d` is the (unit) ray direction.
    pub fn hit_by(&self, d: DVec3) -> bool {
        self.angle_deg > 0.0 && std::f64::consts::TAU * (1.0 - self.dir.dot(d)) < self.solid_angle
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_and_sky() {
        let sun = DistantSource::new(DVec3::new(0.0, 0.0, 2.0), 0.5).unwrap();
        assert_eq!(sun.dir, DVec3::Z);
        let expect = std::f64::consts::TAU * (1.0 - (0.25f64).to_radians().cos());
        assert!((sun.solid_angle - expect).abs() < 1e-15);
        assert!(sun.hit_by(DVec3::Z));
        let off = (0.24f64).to_radians();
        assert!(sun.hit_by(DVec3::new(off.sin(), 0.0, off.cos())));
        let off = (0.26f64).to_radians();
        assert!(!sun.hit_by(DVec3::new(off.sin(), 0.0, off.cos())));
        let sky = DistantSource::new(DVec3::Z, 180.0).unwrap();
        assert!((sky.solid_angle - std::f64::consts::TAU).abs() < 1e-12);
        assert!(sky.hit_by(DVec3::new(0.0, 0.6, 0.8)));
        assert!(!sky.hit_by(DVec3::new(0.0, 0.8, -0.6)));
        let zero = DistantSource::new(DVec3::Z, 0.0).unwrap();
        assert!(!zero.hit_by(DVec3::Z));
        let neg = DistantSource::new(DVec3::Z, -1.0).unwrap();
        assert!(!neg.hit_by(DVec3::Z));
        assert!(DistantSource::new(DVec3::ZERO, 1.0).is_err());
        assert!(DistantSource::new(DVec3::Z, f64::NAN).is_err());
    }
}
