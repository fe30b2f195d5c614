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

use glam::{DAffine3, DMat3, DMat4, DVec3};
use std::path::{Path, PathBuf};

use super::build::{Builder, Object, Scene};
use super::error::SceneError;
use super::primitive::Primitive;
use super::transform::{parse_transform, Transform};
use crate::geometry::bvh::Bvh;
use crate::geometry::trimesh::TriMesh;
use crate::material::MatId;
use crate::modifier::ModRef;

/// `Hit::inst` of a surface of the scene itself.
pub const NO_INST: u32 = u32::MAX;

/// Most placements (expanded instances) a scene may have.
pub const MAX_PLACEMENTS: usize = 1 << 22;

/// Deepest nesting of instances.
pub const MAX_NESTING: usize = 32;

/// A surface the tracer hit: an object of the scene (`inst == NO_INST`) or object `obj` of
/// placement `inst`'s set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HitRef {
    /// Placement index, or [`NO_INST`].
    pub inst: u32,
    /// Object (or triangle) index.
    pub obj: usize,
}

impl HitRef {
    /// An object of the scene itself.
    pub fn top(obj: usize) -> HitRef {
        HitRef { inst: NO_INST, obj }
    }

    /// A total order key (scene objects first, in index order).
    pub fn key(&self) -> (u32, usize) {
        (self.inst.wrapping_add(1), self.obj)
    }
}

/// The modifier a mesh triangle refers to, resolved.
#[derive(Clone, Debug)]
pub struct MeshModifier {
    /// The start of its chain.
    pub chain: ModRef,
    /// The material its chain ends in.
    pub material: Option<MatId>,
    /// Its name.
    pub name: String,
}

/// What a set holds.
pub enum SetGeom {
    /// Surfaces with their materials (an octree).
    Objects(Vec<Object>),
    /// Triangles (a mesh) and their modifiers by object index of the mesh's scene.
    Mesh {
        /// The triangles.
        mesh: TriMesh,
        /// Modifiers by object index (None: not a modifier).
        mods: Vec<Option<MeshModifier>>,
    },
}

/// An instance inside a set (or in the scene): which set, placed how, shaded how.
#[derive(Clone, Debug)]
pub struct Child {
    /// The set.
    pub set: usize,
    /// Set file coordinates → coordinates of the file holding the instance.
    pub xf: Transform,
    /// The instance's modifier (`ModRef::Void`: the set's own materials).
    pub chain: ModRef,
    /// The material that chain ends in.
    pub material: Option<MatId>,
    /// The modifier's name.
    pub modifier: String,
}

/// One octree or mesh file, read and built once.
pub struct ObjectSet {
    /// The file as named.
    pub file: String,
    /// Its surfaces or triangles.
    pub geom: SetGeom,
    /// The bottom-level BVH over them.
    pub bvh: Bvh,
    /// The origin its geometry is relative to (the file's coordinates).
    pub origin: DVec3,
    /// Bounds of its own geometry (relative to `origin`), None when it has none.
    pub bounds: Option<(DVec3, DVec3)>,
    /// Bounds with its instances' (the file's coordinates).
    pub full: Option<(DVec3, DVec3)>,
    /// The instances it holds.
    pub children: Vec<Child>,
    /// Surfaces once every nested instance is expanded.
    pub expanded: u64,
    /// An OBJ file's modifier names, bound where it is first placed
    /// ([`super::obj::bind_names`]).
    pub unbound: Option<super::obj::ObjNames>,
}

impl ObjectSet {
    /// Nearest hit of object `j` along a ray in the set's frame.
    #[inline]
    pub fn intersect(&self, j: usize, o: DVec3, d: DVec3, tmax: f64) -> Option<f64> {
        match &self.geom {
            SetGeom::Objects(objs) => objs[j].surface.intersect(o, d, tmax),
            SetGeom::Mesh { mesh, .. } => mesh.intersect(j, o, d, tmax),
        }
    }

    /// Unit front normal of object `j` at point `p` (the set's frame), and whether the
    /// surface is flat.
    pub fn normal(&self, j: usize, p: DVec3) -> (DVec3, bool) {
        match &self.geom {
            SetGeom::Objects(objs) => (objs[j].surface.normal_at(p), objs[j].surface.is_flat()),
            SetGeom::Mesh { mesh, .. } => (mesh.normal(j), true),
        }
    }

    /// Chain, material and modifier name of object `j`.
    pub fn shading(&self, j: usize) -> (ModRef, Option<MatId>, &str) {
        match &self.geom {
            SetGeom::Objects(objs) => (objs[j].chain, objs[j].material, &objs[j].modifier),
            SetGeom::Mesh { mesh, mods } => {
                let k = mesh.tris[j].modifier;
                match usize::try_from(k)
                    .ok()
                    .and_then(|k| mods.get(k))
                    .and_then(|m| m.as_ref())
                {
                    Some(m) => (m.chain, m.material, &m.name),
                    None => (ModRef::Void, None, "void"),
                }
            }
        }
    }
}

/// A non-void instance's modifier, shading everything below it.
#[derive(Clone, Debug)]
pub struct Override {
    /// The start of its chain.
    pub chain: ModRef,
    /// The material it ends in.
    pub material: Option<MatId>,
    /// Its name.
    pub modifier: String,
    /// The frame its patterns see (the file holding the instance; None: the world).
    pub frame: Option<Transform>,
}

/// A set placed in the scene (one path of nested instances).
pub struct Placement {
    /// The set.
    pub set: usize,
    /// Set-relative → scene-relative coordinates.
    pub to_world: DAffine3,
    /// Scene-relative → set-relative coordinates.
    pub to_local: DAffine3,
    /// The set's file coordinates → world (the patterns' frame with a void modifier).
    pub frame: Transform,
    /// The outermost non-void instance modifier on the path, if any.
    pub over: Option<Override>,
}

/// What shading needs of a hit surface.
pub struct HitInfo<'s> {
    /// The start of its modifier chain.
    pub chain: ModRef,
    /// The material that chain ends in.
    pub material: Option<MatId>,
    /// The modifier's name (for `-ae`/`-ai`).
    pub modifier: &'s str,
    /// The frame its patterns see (None: the world).
    pub frame: Option<&'s Transform>,
}

fn box_corners(lo: DVec3, hi: DVec3) -> impl Iterator<Item = DVec3> {
    (0..8).map(move |k| {
        DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// The bounds of box `(lo, hi)` after `f`.
pub fn map_box(b: (DVec3, DVec3), f: impl Fn(DVec3) -> DVec3) -> (DVec3, DVec3) {
    box_corners(b.0, b.1).map(f).fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// Grow `acc` by `b`.
pub fn union(acc: &mut Option<(DVec3, DVec3)>, b: (DVec3, DVec3)) {
    *acc = Some(match *acc {
        None => b,
        Some((lo, hi)) => (lo.min(b.0), hi.max(b.1)),
    });
}

/// Whether a mesh file name names a Wavefront OBJ file (`.obj`, any case).
pub fn is_obj_name(name: &str) -> bool {
    name.len() > 4 && name[name.len() - 4..].eq_ignore_ascii_case(".obj")
}

/// The default modifier of a mesh primitive naming an OBJ file (`file.obj -m NAME ...`):
/// for its triangles with no modifier name or an undefined one.
pub fn obj_default(p: &Primitive) -> Option<&str> {
    (p.ptype == "mesh" && p.sargs.len() >= 3 && is_obj_name(&p.sargs[0]) && p.sargs[1] == "-m")
        .then(|| p.sargs[2].as_str())
}

/// The transform of an instance or mesh primitive's string arguments after the file name
/// (and after an OBJ mesh's `-m NAME`).
pub fn instance_transform(p: &Primitive) -> Result<Transform, String> {
    if p.sargs.is_empty() || !p.iargs.is_empty() || !p.rargs.is_empty() {
        return Err(format!(
            "bad # arguments for {} \"{}\" (want 1+ strings: a file and a transform)",
            p.ptype, p.name
        ));
    }
    let skip = if obj_default(p).is_some() { 3 } else { 1 };
    let words = &p.sargs[skip.min(p.sargs.len())..];
    let xf = if words.is_empty() {
        Transform::identity()
    } else {
        let (xf, used) = parse_transform(words)?;
        if used != words.len() {
            return Err(format!("bad transform at word '{}'", words[used]));
        }
        xf
    };
    if !(xf.scale().is_finite() && xf.scale() > 0.0 && xf.matrix().is_finite()) {
        return Err("singular transform".into());
    }
    Ok(xf)
}

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
            r => r.map_err(err)?,
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
        let (prims, used) = super::octree::octree_primitives(path, name, &self.opts)?;
        for (n, p) in used {
            self.mods.files.note_input(&n, p);
        }
        let level = self.in_own_namespace(|b| b.level(&prims))?;
        if !level.distant.is_empty() {
            self.warnings.push(format!(
                "{name}: {} distant source(s) inside an instanced octree ignored",
                level.distant.len()
            ));
        }
        let bounds: Vec<(DVec3, DVec3)> =
            level.objects.iter().map(|o| o.surface.bounds()).collect();
        let mut direct = None;
        for b in &bounds {
            union(&mut direct, *b);
        }
        let bvh = Bvh::build(&bounds, level.eps);
        let expanded = level.objects.len() as u64
            + level
                .children
                .iter()
                .map(|c| self.sets[c.set].expanded)
                .fold(0u64, u64::saturating_add);
        Ok(ObjectSet {
            file: name.to_string(),
            geom: SetGeom::Objects(level.objects),
            bvh,
            origin: level.origin,
            bounds: direct,
            full: level.full,
            children: level.children,
            expanded,
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
        let file =
            super::rtm::parse_mesh(&bytes, name).map_err(|m| SceneError::syntax(loc.clone(), m))?;
        drop(bytes);
        let level = self.in_own_namespace(|b| b.level(&file.prims))?;
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
        pos: pos.iter().map(|p| *p - origin).collect(),
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
        unbound: None,
    }
}

/// Flatten the scene's instances into placements relative to `origin`.
pub fn flatten(sets: &[ObjectSet], top: &[Child], origin: DVec3) -> Result<Vec<Placement>, String> {
    let mut out = Vec::new();
    // (child, composed file → world matrix, its scale, mirrors, override)
    let mut stack: Vec<(&Child, DMat4, f64, bool, Option<Override>)> = top
        .iter()
        .rev()
        .map(|c| (c, DMat4::IDENTITY, 1.0, false, None))
        .collect();
    while let Some((c, parent, pscale, pmirror, over)) = stack.pop() {
        let m = parent * c.xf.matrix();
        let scale = pscale * c.xf.scale();
        let mirrors = pmirror != c.xf.mirrors();
        let over = over.or_else(|| {
            (c.chain != ModRef::Void).then(|| Override {
                chain: c.chain,
                material: c.material,
                modifier: c.modifier.clone(),
                frame: (parent != DMat4::IDENTITY)
                    .then(|| Transform::from_matrix(parent, pscale, pmirror)),
            })
        });
        let set = &sets[c.set];
        if set.bounds.is_some() {
            if out.len() >= MAX_PLACEMENTS {
                return Err(format!(
                    "more than {MAX_PLACEMENTS} instance placements (nested instances multiply)"
                ));
            }
            let lin = DMat3::from_mat4(m);
            let translation = m.transform_point3(set.origin) - origin;
            let to_world = DAffine3::from_mat3_translation(lin, translation);
            let to_local = to_world.inverse();
            if !(to_local.is_finite() && to_world.is_finite()) {
                return Err(format!("singular transform of instance of {}", set.file));
            }
            out.push(Placement {
                set: c.set,
                to_world,
                to_local,
                frame: Transform::from_matrix(m, scale, mirrors),
                over: over.clone(),
            });
        }
        for g in set.children.iter().rev() {
            stack.push((g, m, scale, mirrors, over.clone()));
        }
    }
    Ok(out)
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
                modifier: &o.modifier,
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
