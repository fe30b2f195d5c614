//! Instances (`mod instance id 1+ octree [xf] 0 0`) and meshes (`mod mesh id 1+ file.rtm
//! [xf] 0 0`): a two-level BVH.
//!
//! Each distinct file is read and built **once** into an [`ObjectSet`]: its surfaces (or
//! triangles) in f64 relative to the set's own origin, with their own BVH (the bottom
//! level), and the instances it holds in turn ([`Child`]). The scene flattens every path of
//! nested instances into [`Placement`]s: a set with the composed transform, relative to the
//! scene origin. The scene's BVH (the top level) holds its own surfaces and one box per
//! placement; a ray reaching a placement's box is taken into the set's frame (f64, the
//! direction renormalised, distances scaled), traced against the set's BVH, and the hit
//! distance is scaled back, so coincident-surface ties and distance limits compare in world
//! units.
//!
//! Radiance's rules (radiance-formats.md §6.5, §7.2): with modifier `void` the set's own
//! materials shade and patterns see the set's coordinates; otherwise the instance's modifier
//! shades every hit and patterns see the coordinates of the file holding the instance
//! (world, at the top). The outermost non-void instance wins. Light sources inside instances
//! are not sources (they shine only where rays see them, as rpict). A mesh triangle with
//! normals at all three vertices shades with the interpolated normal (a perturbation of the
//! geometric one); with (u,v) at all three, `Lu Lv` are interpolated.

use glam::DVec3;
use std::path::PathBuf;

use super::object::MatId;
pub use super::sets::*;
pub use super::sets::{HitRef, NO_INST};
use super::world::SceneGeometry;

impl SceneGeometry {
    /// Closest hit along a ray (relative frame, unit direction) within `tmax`, with the
    /// coincident-surface preference `prefer(new, old)`.
    #[inline]
    pub fn closest(
        &self,
        org: DVec3,
        dir: DVec3,
        tmax: f64,
        prefer: impl Fn(HitRef, HitRef) -> bool,
    ) -> Option<(HitRef, f64)> {
        if self.placements.is_empty() {
            return self
                .bvh
                .closest(
                    org,
                    dir,
                    tmax,
                    |i| self.objects.intersect(i, org, dir, tmax),
                    |a, b| prefer(HitRef::top(a), HitRef::top(b)),
                )
                .map(|(i, t)| (HitRef::top(i), t));
        }
        let n = self.objects.len();
        let href = |i: usize, j: u32| {
            if i < n {
                HitRef::top(i)
            } else {
                HitRef {
                    inst: (i - n) as u32,
                    obj: j as usize,
                }
            }
        };
        self.bvh
            .closest_sub(
                org,
                dir,
                tmax,
                |i, reach| {
                    if i < n {
                        self.objects.intersect(i, org, dir, tmax).map(|t| (t, 0))
                    } else {
                        self.placement_hit(i - n, (org, dir), (tmax, reach), &prefer)
                    }
                },
                |a, b| prefer(href(a.0, a.1), href(b.0, b.1)),
            )
            .map(|(i, j, t)| (href(i, j), t))
    }

    /// The ray in placement `p`'s frame: origin, unit direction, local length per world
    /// length.
    #[inline]
    fn local_ray(&self, p: &Placement, org: DVec3, dir: DVec3) -> (DVec3, DVec3, f64) {
        let o = p.to_local.transform_point3(org);
        let d = p.to_local.transform_vector3(dir);
        let k = d.length();
        (o, d / k, k)
    }

    /// The closest hit of placement `pi` before `tmax`, searched only as far as `reach`
    /// (world lengths; [`crate::geometry::bvh::Bvh::closest_sub`]): a hit of the set beyond it cannot win, but its
    /// own choice among surfaces within its tie window of its closest hit must see that
    /// window whole, so the set's search goes that much farther (never past `tmax`), and
    /// the placement gives the hit it would give searching up to `tmax` whenever that hit
    /// lies within `reach`.
    fn placement_hit(
        &self,
        pi: usize,
        (org, dir): (DVec3, DVec3),
        (tmax, reach): (f64, f64),
        prefer: &impl Fn(HitRef, HitRef) -> bool,
    ) -> Option<(f64, u32)> {
        let p = &self.placements[pi];
        let set = &self.sets[p.set];
        let (o, d, k) = self.local_ray(p, org, dir);
        if !(k > 0.0 && k.is_finite()) {
            return None;
        }
        let tl = (tmax * k).min(reach * k + 2.0 * set.bvh.eps);
        let inst = pi as u32;
        // Hits within the scene's tolerance in world units are no hits (the top level would
        // drop them; refusing them here keeps the set's search from pruning on them).
        let eps = self.eps;
        let (j, t) = set.bvh.closest(
            o,
            d,
            tl,
            |j| set.intersect(j, o, d, tl).filter(|&t| t / k > eps),
            |a, b| prefer(HitRef { inst, obj: a }, HitRef { inst, obj: b }),
        )?;
        Some((t / k, j as u32))
    }

    /// The point, front normal and flatness of a hit at distance `t` along a ray.
    #[inline]
    pub fn hit_geom(&self, r: HitRef, org: DVec3, dir: DVec3, t: f64) -> (DVec3, DVec3, bool) {
        let point = org + dir * t;
        if r.inst == NO_INST {
            let s = self.objects.surface(r.obj);
            return (point, s.normal_at(point), s.is_flat());
        }
        let p = &self.placements[r.inst as usize];
        let local = p.to_local.transform_point3(point);
        let (n, flat) = self.sets[p.set].normal(r.obj, local);
        (
            point,
            p.to_world.transform_vector3(n).normalize_or_zero(),
            flat,
        )
    }

    /// Whether the surface of `r` is hit from its front along a ray (for ties).
    pub fn facing(&self, r: HitRef, org: DVec3, dir: DVec3, tmax: f64) -> bool {
        if r.inst == NO_INST {
            let s = self.objects.surface(r.obj);
            return match s.intersect(org, dir, tmax) {
                Some(t) => s.normal_at(org + dir * t).dot(dir) < 0.0,
                None => false,
            };
        }
        let p = &self.placements[r.inst as usize];
        let set = &self.sets[p.set];
        let (o, d, k) = self.local_ray(p, org, dir);
        match set.intersect(r.obj, o, d, tmax * k) {
            Some(t) => set.normal(r.obj, o + d * t).0.dot(d) < 0.0,
            None => false,
        }
    }

    /// The shading of a hit surface: chain, material, modifier name and pattern frame.
    #[inline]
    pub fn hit_info(&self, r: HitRef) -> HitInfo<'_> {
        if r.inst == NO_INST {
            let o = &self.objects[r.obj];
            return HitInfo {
                chain: o.chain(),
                material: o.material(),
                modifier: self.objects.modifier(r.obj),
                frame: None,
            };
        }
        let p = &self.placements[r.inst as usize];
        if let Some(over) = &p.over {
            return HitInfo {
                chain: over.chain,
                material: over.material,
                modifier: &over.modifier,
                frame: over.frame.as_ref(),
            };
        }
        let (chain, material, modifier) = self.sets[p.set].shading(r.obj);
        HitInfo {
            chain,
            material,
            modifier,
            frame: Some(&p.frame),
        }
    }

    /// The material of a hit surface.
    #[inline]
    pub fn ref_material(&self, r: HitRef) -> Option<MatId> {
        if r.inst == NO_INST {
            self.objects[r.obj].material()
        } else {
            self.hit_info(r).material
        }
    }

    /// For a mesh triangle: the interpolated normal (world, unit) and (u,v) at `point`.
    pub fn mesh_detail(&self, r: HitRef, point: DVec3) -> (Option<DVec3>, Option<[f64; 2]>) {
        if r.inst == NO_INST {
            return (None, None);
        }
        let p = &self.placements[r.inst as usize];
        let SetGeom::Mesh { mesh, .. } = &self.sets[p.set].geom else {
            return (None, None);
        };
        let local = p.to_local.transform_point3(point);
        let (n, uv) = mesh.interpolate(r.obj, local);
        let n = n
            .map(|n| p.to_world.transform_vector3(n).normalize_or_zero())
            .filter(|n| *n != DVec3::ZERO);
        (n, uv)
    }

    /// Surfaces once every instance is expanded (the scene's own and every placement's).
    pub fn expanded_surfaces(&self) -> u64 {
        let inst: u64 = self
            .placements
            .iter()
            .map(|p| match &self.sets[p.set].geom {
                SetGeom::Objects(o) => o.len() as u64,
                SetGeom::Mesh { mesh, .. } => mesh.tris.len() as u64,
            })
            .sum();
        self.objects.len() as u64 + inst
    }

    /// The instanced files (name as given), for reports.
    pub fn instanced_files(&self) -> Vec<PathBuf> {
        self.sets.iter().map(|s| PathBuf::from(&s.file)).collect()
    }
}
