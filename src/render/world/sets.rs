//! Instanced octrees and meshes read and built into object sets, once per file (the
//! tracing of their placements is [`crate::scene::instance`]'s).

use glam::DVec3;
use std::path::{Path, PathBuf};

use super::Builder;
use crate::geometry::bvh::Bvh;
use crate::geometry::trimesh::TriMesh;
use crate::scene::error::SceneError;
use crate::scene::primitive::Primitive;
use crate::scene::sets::*;
use crate::scene::transform::Transform;

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
            Err(_)
                if &*p.loc.file == crate::scene::reader::COMMAND_LINE
                    && Path::new(name).is_file() =>
            {
                let path = PathBuf::from(name);
                self.mods.files.note_input(name, path.clone());
                path
            }
            r => r.map_err(|m| err(m + &crate::scene::reader::raypath_hint(name, &p.loc.file)))?,
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
        // Sets are numbered as they are finished (a set's nested sets first), and put in a
        // scene image in that order; `started` numbers them as they are begun.
        let started = self.started;
        self.started += 1;
        let set = if let Some(image) = self.image {
            self.mapped_set(image, started, name, obj.then(|| obj_default(p)), &p.loc)
        } else if obj {
            self.obj_set(name, &path, obj_default(p))
        } else if p.ptype == "mesh" {
            self.mesh_set(name, &path)
        } else {
            self.octree_set(name, &path)
        };
        self.loading.pop();
        let mut set = set?;
        set.started = started;
        let id = self.sets.len();
        if let Some(image) = self.image {
            if image.set_started(id) != Some(started) {
                let why = format!("its set {id} is not the scene's ('{name}')");
                return Err(self.refuse(why, &p.loc));
            }
        }
        self.sets.push(set);
        self.set_ids.insert(key, id);
        Ok((id, xf))
    }

    /// A mesh's modifiers by object index of its file: what each of its primitives defined.
    pub(super) fn mesh_modifiers(
        &self,
        defined: &[Option<crate::modifier::ModRef>],
        prims: &[Primitive],
    ) -> Vec<Option<MeshModifier>> {
        defined
            .iter()
            .zip(prims)
            .map(|(d, p)| {
                d.map(|chain| MeshModifier {
                    chain,
                    material: self.mods.terminal(chain),
                    name: p.name.clone(),
                })
            })
            .collect()
    }

    /// Build `f` with a fresh name space (a file's names are its own).
    pub(super) fn in_own_namespace<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        let saved = self.mods.enter();
        let r = f(self);
        self.mods.leave(saved);
        r
    }

    fn octree_set(&mut self, name: &str, path: &std::path::Path) -> Result<ObjectSet, SceneError> {
        let (mut prims, used) = crate::scene::octree::octree_primitives(path, name, &self.opts)?;
        let source = SetSource::Octree {
            rest: crate::scene::image::rest_text(&prims),
            used: used.iter().map(|(n, _)| n.clone()).collect(),
        };
        for (n, p) in used {
            self.mods.files.note_input(&n, p);
        }
        let level = self.in_own_namespace(|b| b.level(&mut prims, None))?;
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
        for i in 0..objects.len() {
            union(&mut direct, objects.surface(i).bounds());
        }
        let bvh = Bvh::build_from(objects.len(), |i| objects.surface(i).bounds(), level.eps);
        let expanded = expanded_of(&self.sets, level.objects.len(), &level.children);
        let placements = placements_of(&self.sets, &level.children);
        Ok(ObjectSet {
            file: name.to_string(),
            geom: SetGeom::Objects(Box::new(level.objects)),
            bvh,
            origin: level.origin,
            bounds: direct,
            full: level.full,
            children: level.children,
            expanded,
            placements,
            unbound: None,
            source,
            started: 0,
        })
    }

    fn mesh_set(&mut self, name: &str, path: &std::path::Path) -> Result<ObjectSet, SceneError> {
        let loc = crate::scene::primitive::Location::new(name, 0);
        let bytes = std::fs::read(path).map_err(|e| SceneError::Io {
            loc: loc.clone(),
            path: name.to_string(),
            reason: e.to_string(),
        })?;
        let mut file = crate::scene::rtm::parse_mesh(&bytes, name)
            .map_err(|m| SceneError::syntax(loc.clone(), m))?;
        drop(bytes);
        let mut prims_text = String::new();
        crate::scene::primitive::write_text(&file.prims, &mut prims_text);
        let level = self.in_own_namespace(|b| b.level(&mut file.prims, None))?;
        let mods = self.mesh_modifiers(&level.defined, &file.prims);
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
        let mesh = TriMesh {
            pos: file.pos.into(),
            normal: file.normal.into(),
            uv: file.uv.into(),
            flags: file.flags.into(),
            tris: file.tris.into(),
            eps: 0.0,
        };
        Ok(mesh_object_set(
            name,
            mesh,
            mods,
            SetSource::Mesh { prims: prims_text },
        ))
    }
}

/// The object set of a mesh's triangles (file coordinates), relative to their centre.
/// `mesh` comes in the file's coordinates (its `eps` is set here).
pub(super) fn mesh_object_set(
    name: &str,
    mut mesh: TriMesh,
    mods: Vec<Option<MeshModifier>>,
    source: SetSource,
) -> ObjectSet {
    let mut full = None;
    for p in mesh.pos.iter() {
        union(&mut full, (*p, *p));
    }
    let (origin, size) = match full {
        Some((lo, hi)) => ((lo + hi) * 0.5, (hi - lo).max_element()),
        None => (DVec3::ZERO, 1.0),
    };
    // In place: the file's positions are not kept twice.
    mesh.pos.with_vec(|v| {
        v.iter_mut().for_each(|p| *p -= origin);
        v.shrink_to_fit();
    });
    mesh.eps = super::length_tolerance(size);
    let bvh = Bvh::build_from(mesh.tris.len(), |i| mesh.bounds(i), mesh.eps);
    let expanded = mesh.tris.len() as u64;
    ObjectSet {
        file: name.to_string(),
        geom: SetGeom::Mesh {
            mesh: Box::new(mesh),
            mods,
        },
        bvh,
        origin,
        bounds: full.map(|(lo, hi)| (lo - origin, hi - origin)),
        full,
        children: Vec::new(),
        expanded,
        placements: 0,
        unbound: None,
        source,
        started: 0,
    }
}
