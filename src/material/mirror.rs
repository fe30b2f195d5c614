//! `mirror`: pure specular reflection that also projects light sources (virtual sources).

use super::{expect_args, reflect, MatId, MaterialLookup};
use crate::color::Color;
use crate::render::ray::{Ray, RayKind};
use crate::render::sampler::Sampler;
use crate::render::shading::ShadingPoint;
use crate::render::trace::Tracer;
use glam::DVec3;

/// A mirror: reflectance per channel and an optional alternate material.
#[derive(Clone, Debug)]
pub struct Mirror {
    /// Reflectance.
    pub color: Color,
    /// Material used for every ray except those relaying virtual sources.
    pub alternate: Option<MatId>,
    /// True when the alternate is named `void`: the mirror is then invisible to those rays.
    pub alternate_void: bool,
}

impl Mirror {
    /// Parse `mirror` (0 or 1 string, 3 reals).
    pub fn parse(
        sargs: &[String],
        rargs: &[f64],
        lookup: &dyn MaterialLookup,
    ) -> Result<Mirror, String> {
        expect_args("mirror", sargs, rargs, 0..=1, &[3])?;
        let (alternate, alternate_void) = match sargs.first() {
            Some(name) => {
                let id = lookup.material(name)?;
                (id, id.is_none())
            }
            None => (None, false),
        };
        Ok(Mirror {
            color: DVec3::new(rargs[0], rargs[1], rargs[2]),
            alternate,
            alternate_void,
        })
    }

    /// Shade a hit on the mirror itself (no alternate): one reflected ray. A mirror reflects
    /// from its front only: seen from behind it is black, or invisible with `-bv-` (both
    /// measured with rpict).
    pub fn shade(&self, tr: &Tracer, ray: &Ray, sp: &ShadingPoint, rng: &mut Sampler) -> Color {
        let hit = &sp.hit;
        if hit.back {
            return if tr.params.bv {
                Color::ZERO
            } else {
                tr.pass_through(ray, hit, rng)
            };
        }
        let dir = reflect(ray.dir, sp.normal);
        let color = self.color * sp.pcol;
        match tr.spawn(ray, hit, dir, RayKind::Reflected, color) {
            Some(r) => color * tr.trace(&r, rng),
            None => Color::ZERO,
        }
    }
}
