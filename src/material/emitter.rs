//! Light-emitting materials: `light`, `glow`, `illum` and `spotlight`.

use super::{expect_args, MatId, MaterialLookup};
use crate::color::Color;
use crate::FTINY;
use glam::DVec3;

/// Which emitter.
#[derive(Clone, Debug, PartialEq)]
pub enum EmitterKind {
    /// A primary light source.
    Light,
    /// A glow: a source only within `maxrad` (0: never a source; < 0: never illuminates).
    Glow {
        /// The glow's radius of influence.
        maxrad: f64,
    },
    /// A secondary source that otherwise looks like its alternate material.
    Illum {
        /// Alternate material (None: invisible to non-source rays).
        alternate: Option<MatId>,
    },
    /// A light restricted to a cone.
    Spot {
        /// Cosine of the half cone angle.
        cos_half: f64,
        /// Unit spot direction.
        dir: DVec3,
        /// Focal distance behind the source (|d|).
        focal: f64,
    },
}

/// An emitting material.
#[derive(Clone, Debug)]
pub struct Emitter {
    /// Kind.
    pub kind: EmitterKind,
    /// Radiance (W/sr/m²) per channel.
    pub radiance: Color,
}

impl Emitter {
    /// Parse `light`, `glow`, `illum` or `spotlight`.
    pub fn parse(
        ptype: &str,
        sargs: &[String],
        rargs: &[f64],
        lookup: &dyn MaterialLookup,
    ) -> Result<Emitter, String> {
        let kind = match ptype {
            "light" => {
                expect_args(ptype, sargs, rargs, 0..=0, &[3])?;
                EmitterKind::Light
            }
            "glow" => {
                expect_args(ptype, sargs, rargs, 0..=0, &[4])?;
                EmitterKind::Glow { maxrad: rargs[3] }
            }
            "illum" => {
                expect_args(ptype, sargs, rargs, 0..=1, &[3])?;
                let alternate = match sargs.first() {
                    Some(name) => lookup.material(name)?,
                    None => None,
                };
                EmitterKind::Illum { alternate }
            }
            "spotlight" => {
                expect_args(ptype, sargs, rargs, 0..=0, &[7])?;
                let d = DVec3::new(rargs[4], rargs[5], rargs[6]);
                let len = d.length();
                if len <= FTINY {
                    return Err("spotlight: zero direction vector".into());
                }
                let angle = rargs[3];
                if !(angle > 0.0 && angle <= 360.0) {
                    return Err(format!("spotlight: cone angle {angle} out of range"));
                }
                EmitterKind::Spot {
                    cos_half: (angle.to_radians() * 0.5).cos(),
                    dir: d / len,
                    focal: len,
                }
            }
            _ => return Err(format!("{ptype} is not an emitter")),
        };
        Ok(Emitter {
            kind,
            radiance: DVec3::new(rargs[0], rargs[1], rargs[2]),
        })
    }

    /// True when surfaces of this material become light sources for direct lighting.
    pub fn is_source(&self) -> bool {
        match self.kind {
            EmitterKind::Glow { maxrad } => maxrad > 0.0,
            _ => true,
        }
    }

    /// Focal distance of a spotlight (0 for other emitters).
    pub fn focal_distance(&self) -> f64 {
        match self.kind {
            EmitterKind::Spot { focal, .. } => focal,
            _ => 0.0,
        }
    }

    /// 1 when a receiver at `receiver` lies inside a spotlight's cone (measured from the
    /// source centre, as Radiance does), else 0; always 1 for other emitters.
    pub fn spot_factor(&self, center: DVec3, receiver: DVec3) -> f64 {
        match self.kind {
            EmitterKind::Spot { cos_half, dir, .. } => {
                let w = (receiver - center).normalize_or_zero();
                if w.dot(dir) >= cos_half {
                    1.0
                } else {
                    0.0
                }
            }
            _ => 1.0,
        }
    }
}
