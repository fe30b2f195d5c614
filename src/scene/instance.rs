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
use std::path::{Path, PathBuf};

use super::build::{Builder, Scene};
use super::error::SceneError;
use super::primitive::Primitive;
pub use super::sets::*;
use super::transform::Transform;
use crate::geometry::bvh::Bvh;
use crate::geometry::trimesh::TriMesh;
use crate::material::MatId;
pub use crate::render::ray::{HitRef, NO_INST};

impl Builder<'_> {
    /// The set of an `instance` or `mesh` primitive (read and built on first use) and its
    /// transform.
    pub(super) fn child_set(&mut self, p: &Primitive) -> Result<(usize, Transform), SceneError> {
        let err =
            |m: String| SceneError::syntax(p.loc.clone(), format!("{} {}: {m}", p.ptype, p.name));
        let xf = instance_transform(p).map_err(err)?;
        let name = &p.sargs[0];
        let path = match self.mods.files.find(name) {
            // A `.obj` given on the command line is opened as given.
            Err(_) if &*p.loc.file == super::reader::COMMAND_LINE && Path::new(name).is_file() => {
                let path = PathBuf::from(name);
                self.mods.files.note_input(name, path.clone());
                path
            }
            r => r.map_err(|m| err(m + &super::reader::raypath_hint(name, &p.loc.file)))?,
        };
        let mut key = std::fs::canonicalize(&path).unwrap_or(path.clone());
        let obj = p.ptype == "mesh" && is_obj_name(name);
        if obj {
            // An OBJ's names are bound where it is first placed, with its default.
            key.as_mut_os_string()
                .push(format!("\0-m {}", obj_default(p).unwrap_or("")));
        }
        if let Some(&id) = self.set_ids.get(&key) {
            return Ok((id, xf));
        }
        if self.loading.contains(&key) {
            let chain: Vec<String> = self
                .loading
                .iter()
                .map(|k| k.display().to_string())
                .collect();
            return Err(err(format!(
                "instance loop: '{name}' instances itself ({} → {name})",
                chain.join(" → ")
            )));
        }
        if self.loading.len() >= MAX_NESTING {
            return Err(err(format!(
                "instances nested deeper than {MAX_NESTING} levels"
            )));
        }
        self.loading.push(key.clone());
        let set = if obj {
            self.obj_set(name, &path, obj_default(p))
        } else if p.ptype == "mesh" {
            self.mesh_set(name, &path)
        } else {
            self.octree_set(name, &path)
        };
        self.loading.pop();
        let set = set?;
        let id = self.sets.len();
        self.sets.push(set);
        self.set_ids.insert(key, id);
        Ok((id, xf))
    }

    /// Build `f` with a fresh name space (a file's names are its own).
    fn in_own_namespace<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        let saved = self.mods.enter();
        let r = f(self);
        self.mods.leave(saved);
        r
    }

    fn octree_set(&mut self, name: &str, path: &std::path::Path) -> Result<ObjectSet, SceneError> {
        let (mut prims, used) = super::octree::octree_primitives(path, name, &self.opts)?;
        for (n, p) in used {
            self.mods.files.note_input(&n, p);
        }
        let level = self.in_own_namespace(|b| b.level(&mut prims))?;
        // The primitives' text is not needed any more: free it before the BVH build, the
        // peak of a set's memory.
        drop(prims);
        if !level.distant.is_empty() {
            self.warnings.push(format!(
                "{name}: {} distant source(s) inside an instanced octree ignored",
                level.distant.len()
            ));
        }
        let objects = &level.objects;
        let mut direct = None;
        for o in objects {
            union(&mut direct, o.surface.bounds());
        }
        let bvh = Bvh::build_from(objects.len(), |i| objects[i].surface.bounds(), level.eps);
        let expanded = level.objects.len() as u64
            + level
                .children
                .iter()
                .map(|c| self.sets[c.set].expanded)
                .fold(0u64, u64::saturating_add);
        let placements = placements_of(&self.sets, &level.children);
        Ok(ObjectSet {
            file: name.to_string(),
            geom: SetGeom::Objects(level.objects),
            bvh,
            origin: level.origin,
            bounds: direct,
            full: level.full,
            children: level.children,
            expanded,
            placements,
            unbound: None,
        })
    }

    fn mesh_set(&mut self, name: &str, path: &std::path::Path) -> Result<ObjectSet, SceneError> {
        let loc = super::primitive::Location::new(name, 0);
        let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
            loc: loc.clone(),
            path: name.to_string(),
            reason: e.to_string(),
        })?;
        let mut file =
            super::rtm::parse_mesh(&bytes, name).map_err(|m| SceneError::syntax(loc.clone(), m))?;
        drop(bytes);
        let level = self.in_own_namespace(|b| b.level(&mut file.prims))?;
        let mods: Vec<Option<MeshModifier>> = level
            .defined
            .iter()
            .zip(&file.prims)
            .map(|(d, p)| {
                d.map(|chain| MeshModifier {
                    chain,
                    material: self.mods.terminal(chain),
                    name: p.name.clone(),
                })
            })
            .collect();
        for t in &file.tris {
            if let Ok(k) = usize::try_from(t.modifier) {
                if mods[k].is_none() {
                    return Err(SceneError::syntax(
                        loc,
                        format!(
                            "triangle modifier '{}' is not a modifier",
                            file.prims[k].name
                        ),
                    ));
                }
            }
        }
        Ok(mesh_object_set(
            name,
            file.pos,
            file.normal,
            file.uv,
            file.flags,
            file.tris,
            mods,
        ))
    }
}

/// The object set of a mesh's triangles (file coordinates), relative to their centre.
pub(super) fn mesh_object_set(
    name: &str,
    pos: Vec<DVec3>,
    normal: Vec<glam::Vec3>,
    uv: Vec<[f64; 2]>,
    flags: Vec<u8>,
    tris: Vec<super::rtm::MeshTri>,
    mods: Vec<Option<MeshModifier>>,
) -> ObjectSet {
    let mut full = None;
    for p in &pos {
        union(&mut full, (*p, *p));
    }
    let (origin, size) = match full {
        Some((lo, hi)) => ((lo + hi) * 0.5, (hi - lo).max_element()),
        None => (DVec3::ZERO, 1.0),
    };
    let mut mesh = TriMesh {
        // In place: the file's positions are not kept twice.
        pos: pos.into_iter().map(|p| p - origin).collect(),
        normal,
        uv,
        flags,
        tris,
        eps: super::build::length_tolerance(size),
    };
    mesh.pos.shrink_to_fit();
    let bvh = Bvh::build_from(mesh.tris.len(), |i| mesh.bounds(i), mesh.eps);
    let expanded = mesh.tris.len() as u64;
    ObjectSet {
        file: name.to_string(),
        geom: SetGeom::Mesh { mesh, mods },
        bvh,
        origin,
        bounds: full.map(|(lo, hi)| (lo - origin, hi - origin)),
        full,
        children: Vec::new(),
        expanded,
        placements: 0,
        unbound: None,
    }
}

impl Scene {
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
                    |i| self.objects[i].surface.intersect(org, dir, tmax),
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
                |i| {
                    if i < n {
                        self.objects[i]
                            .surface
                            .intersect(org, dir, tmax)
                            .map(|t| (t, 0))
                    } else {
                        self.placement_hit(i - n, org, dir, tmax, &prefer)
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

    fn placement_hit(
        &self,
        pi: usize,
        org: DVec3,
        dir: DVec3,
        tmax: f64,
        prefer: &impl Fn(HitRef, HitRef) -> bool,
    ) -> Option<(f64, u32)> {
        let p = &self.placements[pi];
        let set = &self.sets[p.set];
        let (o, d, k) = self.local_ray(p, org, dir);
        if !(k > 0.0 && k.is_finite()) {
            return None;
        }
        let tl = tmax * k;
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
            let s = &self.objects[r.obj].surface;
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
            let s = &self.objects[r.obj].surface;
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
                chain: o.chain,
                material: o.material,
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
            self.objects[r.obj].material
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
