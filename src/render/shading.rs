//! The shading point: one record made per hit, which the modifiers of the hit surface's
//! chain read and change in Radiance's order before its material shades it.
//!
//! Radiance's rules (docs/architecture.md, "Modifier chains"): a ray starts at a hit with
//! pattern colour 1 and perturbation 0; walking from the surface's modifier toward its
//! material, a pattern multiplies the colour, a texture adds to the perturbation, a mixture
//! chooses between two chains; the material first applies its own modifiers the same way,
//! then shades with the colour (which multiplies the material's colour, emission,
//! transmission or reflectance) and the perturbed normal.

use super::ray::{Hit, Ray, RayKind};
use crate::color::Color;
use crate::scene::transform::Transform;
use crate::FTINY;
use glam::DVec3;

/// Everything modifiers and materials know of a hit.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint<'s> {
    /// The hit: position (relative to the scene origin), geometric front-side normal
    /// (`hit.normal`, not turned toward the ray), side, distance, object, antimatter state.
    pub hit: Hit,
    /// The ray's unit direction.
    pub dir: DVec3,
    /// The perturbed front-side normal: `hit.normal` until a texture perturbs it, then
    /// `normalize(hit.normal + pert)`, reflected about the ray direction where the
    /// perturbation would turn it to the other side of the ray (Radiance's rule).
    pub normal: DVec3,
    /// The sum of the textures' perturbations.
    pub pert: DVec3,
    /// The product of the patterns' colours.
    pub pcol: Color,
    /// Surface coordinates where the surface has them (mesh `u v`), else None.
    pub uv: Option<[f64; 2]>,
    /// The hit object's own transform (an instance's or a mesh's), or None for surfaces
    /// given in the scene's own frame. Patterns evaluate in the frame it defines.
    pub transform: Option<&'s Transform>,
    /// The scene origin: `hit.point + origin` is the hit in the scene file's coordinates.
    pub origin: DVec3,
    /// Length of the whole path from the eye to the hit (pattern variable `T`).
    pub path_len: f64,
    /// Length of this ray to the hit; for shadow rays crossing transmitters, from the
    /// shadow ray's origin (pattern variable `Ts`).
    pub ray_len: f64,
}

impl<'s> ShadingPoint<'s> {
    /// The shading point of `hit` along `ray`, before any modifier; `origin` is the scene
    /// origin the hit's coordinates are relative to.
    pub fn new(ray: &Ray, hit: &Hit, origin: DVec3) -> ShadingPoint<'s> {
        ShadingPoint {
            hit: *hit,
            dir: ray.dir,
            normal: hit.normal,
            pert: DVec3::ZERO,
            pcol: Color::ONE,
            uv: None,
            transform: None,
            origin,
            path_len: ray.prior + hit.t,
            ray_len: if ray.kind == RayKind::Shadow {
                ray.prior + hit.t
            } else {
                hit.t
            },
        }
    }

    /// The hit point in the scene file's coordinates (world, not relative to the origin).
    pub fn world_point(&self) -> DVec3 {
        self.hit.point + self.origin
    }

    /// Multiply the pattern colour (a pattern's effect).
    pub fn scale_colour(&mut self, c: Color) {
        self.pcol *= c;
    }

    /// Add a texture's perturbation and recompute the perturbed normal.
    pub fn perturb(&mut self, d: DVec3) {
        self.pert += d;
        self.normal = perturbed_normal(self.hit.normal, self.pert, self.dir);
    }

    /// Whether a texture perturbed the normal (`|pert| > FTINY`, as Radiance's materials
    /// test).
    pub fn is_perturbed(&self) -> bool {
        self.pert.length_squared() > FTINY * FTINY
    }

    /// The perturbed normal turned toward the ray's side of the surface (what materials
    /// shade with), given whether the hit is on the back side.
    pub fn facing_normal(&self) -> DVec3 {
        if self.hit.back {
            -self.normal
        } else {
            self.normal
        }
    }
}

/// `normalize(n + pert)` for a front normal `n`, reflected about the ray direction `dir`
/// when the perturbation turned it to the other side of the ray; `n` itself when the sum
/// vanishes (Radiance warns "illegal normal perturbation" and keeps the unperturbed normal)
/// or the perturbation is below `FTINY`.
pub fn perturbed_normal(n: DVec3, pert: DVec3, dir: DVec3) -> DVec3 {
    if pert.length_squared() <= FTINY * FTINY {
        return n;
    }
    let p = (n + pert).normalize_or_zero();
    if p == DVec3::ZERO || !p.is_finite() {
        return n;
    }
    let side = n.dot(dir);
    let pside = p.dot(dir);
    if side * pside < 0.0 {
        // Reflect about the ray direction: the normal stays on the geometric side.
        (p - 2.0 * pside * dir).normalize_or_zero()
    } else {
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::ray::MAX_ANTIMATTER;

    fn hit(normal: DVec3) -> Hit {
        Hit {
            obj: 0,
            inst: crate::render::ray::NO_INST,
            t: 1.0,
            point: DVec3::ZERO,
            normal,
            back: false,
            flat: true,
            material: None,
            antimatter: [None; MAX_ANTIMATTER],
        }
    }

    #[test]
    fn patterns_multiply_and_textures_add() {
        let ray = Ray::primary(DVec3::new(0.0, 0.0, 1.0), -DVec3::Z, f64::INFINITY);
        let mut sp = ShadingPoint::new(&ray, &hit(DVec3::Z), DVec3::ZERO);
        assert_eq!(sp.normal, DVec3::Z);
        assert!(!sp.is_perturbed());
        sp.scale_colour(Color::new(0.5, 1.0, 2.0));
        sp.scale_colour(Color::new(0.5, 0.5, 0.5));
        assert_eq!(sp.pcol, Color::new(0.25, 0.5, 1.0));
        sp.perturb(DVec3::new(0.1, 0.0, 0.0));
        sp.perturb(DVec3::new(0.0, 0.2, 0.0));
        assert!(sp.is_perturbed());
        let want = DVec3::new(0.1, 0.2, 1.0).normalize();
        assert!((sp.normal - want).length() < 1e-12);
    }

    #[test]
    fn a_perturbation_never_turns_the_normal_to_the_rays_side() {
        // A grazing ray: a strong perturbation along the ray would put the normal on the
        // ray's side; it is reflected about the ray direction instead.
        let dir = DVec3::new(1.0, 0.0, -0.1).normalize();
        let n = DVec3::Z;
        let p = perturbed_normal(n, DVec3::new(-20.0, 0.0, 0.0), dir);
        assert!((p.length() - 1.0).abs() < 1e-12);
        assert!(p.dot(dir) * n.dot(dir) > 0.0, "{p}");
        // A perturbation that cancels the normal keeps it.
        assert_eq!(perturbed_normal(n, -n, dir), n);
        // Below FTINY nothing changes, bit for bit.
        assert_eq!(perturbed_normal(n, DVec3::splat(1e-9), dir), n);
    }
}
