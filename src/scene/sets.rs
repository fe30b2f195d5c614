//! The data of instances and meshes (`instance.rs` reads and builds them): object sets
//! (one per distinct file), the instances they hold, their placements in the scene, and the
//! flattening of nested instances into placements.

use glam::{DAffine3, DMat3, DMat4, DVec3};

use super::object::Objects;
use super::object::{MatId, ModRef};
use super::primitive::Primitive;
use super::transform::{parse_transform, Transform};
use crate::geometry::bvh::Bvh;
use crate::geometry::trimesh::TriMesh;

/// Most placements (expanded instances) a scene may have.
pub const MAX_PLACEMENTS: usize = 1 << 22;

/// Deepest nesting of instances.
pub const MAX_NESTING: usize = 32;

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
    Objects(Box<Objects>),
    /// Triangles (a mesh) and their modifiers by object index of the mesh's scene.
    Mesh {
        /// The triangles.
        mesh: Box<TriMesh>,
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

/// What a set was built from beyond its geometry: what a scene image keeps to build the
/// set again without reading its file ([`crate::scene::image`]).
#[derive(Clone, Debug)]
pub enum SetSource {
    /// An octree's primitives (or its scene files') other than finite surfaces, as scene
    /// text, and the names of the scene files an unfrozen octree read.
    Octree {
        /// The text.
        rest: String,
        /// The scene files' names.
        used: Vec<String>,
    },
    /// A compiled mesh's primitives (its modifiers), as scene text.
    Mesh {
        /// The text.
        prims: String,
    },
    /// An OBJ file's modifier names and the line that set each first.
    Obj {
        /// The names.
        names: Vec<(String, u32)>,
    },
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
    /// Placements its nested instances make once flattened (saturating): known as soon as
    /// the set is built, so a scene whose instances multiply beyond [`MAX_PLACEMENTS`] is
    /// refused at the instance that crosses it, before anything is flattened.
    pub placements: u64,
    /// An OBJ file's modifier names, bound where it is first placed
    /// ([`super::obj::bind_names`]).
    pub unbound: Option<super::obj::ObjNames>,
    /// What it was built from ([`SetSource`]).
    pub source: SetSource,
    /// Its number in the order sets were begun (they are numbered in the order they are
    /// finished: a set's nested sets come first).
    pub started: usize,
}

impl ObjectSet {
    /// Nearest hit of object `j` along a ray in the set's frame.
    #[inline]
    pub fn intersect(&self, j: usize, o: DVec3, d: DVec3, tmax: f64) -> Option<f64> {
        match &self.geom {
            SetGeom::Objects(objs) => objs.intersect(j, o, d, tmax),
            SetGeom::Mesh { mesh, .. } => mesh.intersect(j, o, d, tmax),
        }
    }

    /// Unit front normal of object `j` at point `p` (the set's frame), and whether the
    /// surface is flat.
    pub fn normal(&self, j: usize, p: DVec3) -> (DVec3, bool) {
        match &self.geom {
            SetGeom::Objects(objs) => {
                let s = objs.surface(j);
                (s.normal_at(p), s.is_flat())
            }
            SetGeom::Mesh { mesh, .. } => (mesh.normal(j), true),
        }
    }

    /// Chain, material and modifier name of object `j`.
    pub fn shading(&self, j: usize) -> (ModRef, Option<MatId>, &str) {
        match &self.geom {
            SetGeom::Objects(objs) => (objs[j].chain(), objs[j].material(), objs.modifier(j)),
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

/// [`HitRef::inst`] of a surface of the scene itself.
pub const NO_INST: u32 = u32::MAX;

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

/// Surfaces a set holds once expanded: its own `own` and what each of `children` holds,
/// saturating.
pub fn expanded_of(sets: &[ObjectSet], own: usize, children: &[Child]) -> u64 {
    children
        .iter()
        .map(|c| sets[c.set].expanded)
        .fold(own as u64, u64::saturating_add)
}

/// The placements that `children` make once flattened (each child with geometry of its own
/// is one, plus what its set's instances make), saturating.
pub fn placements_of(sets: &[ObjectSet], children: &[Child]) -> u64 {
    children
        .iter()
        .map(|c| placement_count(&sets[c.set]))
        .fold(0u64, u64::saturating_add)
}

/// The placements one instance of `set` makes.
pub fn placement_count(set: &ObjectSet) -> u64 {
    u64::from(set.bounds.is_some()).saturating_add(set.placements)
}

/// The boxes of `placements` in the scene's frame, for the scene's tree: each placement's
/// set's bounds taken through its transform, narrowed to the bounds of the boxes of its
/// set's tree some levels below the root taken through it
/// ([`crate::geometry::bvh::Bvh::cover`]). A rotated set's box, or one round a sparse set
/// (a tree's crown above its trunk), then holds less empty space that rays cross without
/// meeting a surface. Two levels (at most 64 boxes a set) for up to 2^16 placements, one
/// level (8) for up to 2^19, none beyond, so that the work stays within about 2^25 points.
pub fn placement_boxes(sets: &[ObjectSet], placements: &[Placement]) -> Vec<(DVec3, DVec3)> {
    let depth = match placements.len() {
        0..=65_536 => 2,
        65_537..=524_288 => 1,
        _ => 0,
    };
    let mut covers: Vec<Option<Vec<(DVec3, DVec3)>>> = vec![None; sets.len()];
    placements
        .iter()
        .map(|p| {
            let set = &sets[p.set];
            let bb = set.bounds.unwrap_or((DVec3::ZERO, DVec3::ZERO));
            let whole = map_box(bb, |c| p.to_world.transform_point3(c));
            if depth == 0 {
                return whole;
            }
            let cover = covers[p.set].get_or_insert_with(|| set.bvh.cover(depth));
            let mut tight = None;
            for &b in cover.iter() {
                union(&mut tight, map_box(b, |c| p.to_world.transform_point3(c)));
            }
            // Both hold every surface of the set: so does their intersection.
            tight.map_or(whole, |(lo, hi): (DVec3, DVec3)| {
                (lo.max(whole.0), hi.min(whole.1))
            })
        })
        .collect()
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
