//! Sets built from a scene image ([`crate::scene::image`]): the set's surfaces or triangles
//! and its BVH are the image's arrays, its other primitives come from the text the image
//! keeps; the set's file is not read. Anything in the image that does not fit the scene
//! (another file at this place, an index out of range) refuses the image: the builder
//! records why and stops, and the caller builds the scene without it.

use super::Builder;
use crate::scene::error::SceneError;
use crate::scene::image::SceneImage;
use crate::scene::obj::ObjNames;
use crate::scene::primitive::Location;
use crate::scene::reader::parse_scene_text;
use crate::scene::sets::*;

impl Builder<'_> {
    /// Record why the image is refused; the error stops the build.
    pub(super) fn refuse(&mut self, why: String, loc: &Location) -> SceneError {
        let e = SceneError::syntax(loc.clone(), format!("scene image: {why}"));
        self.refused.get_or_insert(why);
        e
    }

    /// The set the scene begins to load as its `started`-th (`name`) from the image; `obj`
    /// is `Some(default modifier)` for an OBJ file.
    pub(super) fn mapped_set(
        &mut self,
        image: &SceneImage,
        started: usize,
        name: &str,
        obj: Option<Option<&str>>,
        loc: &Location,
    ) -> Result<ObjectSet, SceneError> {
        let Some(k) = image.set_begun(started) else {
            let why = format!("it has fewer sets than the scene ('{name}')");
            return Err(self.refuse(why, loc));
        };
        let Some((file, source)) = image.set_source(k) else {
            return Err(self.refuse(format!("it has no set {k}"), loc));
        };
        if file != name {
            let why = format!("its set {k} is '{file}', the scene's '{name}'");
            return Err(self.refuse(why, loc));
        }
        let Some((origin, eps, bounds, full)) = image.set_frame(k) else {
            return Err(self.refuse(format!("set {k} has no frame"), loc));
        };
        let framed = Some((origin, 1.0, eps));
        let set = |geom, bvh, children, expanded, placements, source| ObjectSet {
            file: name.to_string(),
            geom,
            bvh,
            origin,
            bounds,
            full,
            children,
            expanded,
            placements,
            unbound: None,
            source,
            started,
        };
        match (source, obj) {
            (SetSource::Octree { rest, used }, None) => {
                for n in &used {
                    if let Ok(p) = self.mods.files.find(n) {
                        self.mods.files.note_input(n, p);
                    }
                }
                let mut prims = match parse_scene_text(&rest, name, &self.opts) {
                    Ok(p) => p,
                    Err(e) => return Err(self.refuse(format!("set {k}: {e}"), loc)),
                };
                let level = self.in_own_namespace(|b| b.level(&mut prims, framed))?;
                drop(prims);
                let (objects, bvh) =
                    match image.set_objects(k, self.materials.len(), self.mods.defs.len()) {
                        Ok(x) => x,
                        Err(e) => return Err(self.refuse(format!("set {k}: {e}"), loc)),
                    };
                let expanded = expanded_of(&self.sets, objects.len(), &level.children);
                let placements = placements_of(&self.sets, &level.children);
                let source = SetSource::Octree { rest, used };
                Ok(set(
                    SetGeom::Objects(Box::new(objects)),
                    bvh,
                    level.children,
                    expanded,
                    placements,
                    source,
                ))
            }
            (SetSource::Mesh { prims: text }, None) => {
                let mut prims = match parse_scene_text(&text, name, &self.opts) {
                    Ok(p) => p,
                    Err(e) => return Err(self.refuse(format!("set {k}: {e}"), loc)),
                };
                let level = self.in_own_namespace(|b| b.level(&mut prims, framed))?;
                let mods = self.mesh_modifiers(&level.defined, &prims);
                let (mesh, bvh) = match image.set_mesh(k, mods.len()) {
                    Ok(x) => x,
                    Err(e) => return Err(self.refuse(format!("set {k}: {e}"), loc)),
                };
                let bad = mesh.tris.iter().any(|t| {
                    usize::try_from(t.modifier)
                        .is_ok_and(|m| mods.get(m).is_none_or(|m| m.is_none()))
                });
                if bad {
                    let why = format!("set {k}: a triangle's modifier is not a modifier");
                    return Err(self.refuse(why, loc));
                }
                let expanded = mesh.tris.len() as u64;
                let geom = SetGeom::Mesh {
                    mesh: Box::new(mesh),
                    mods,
                };
                Ok(set(
                    geom,
                    bvh,
                    Vec::new(),
                    expanded,
                    0,
                    SetSource::Mesh { prims: text },
                ))
            }
            (SetSource::Obj { names }, Some(default)) => {
                let (mesh, bvh) = match image.set_mesh(k, names.len() + 1) {
                    Ok(x) => x,
                    Err(e) => return Err(self.refuse(format!("set {k}: {e}"), loc)),
                };
                let expanded = mesh.tris.len() as u64;
                let geom = SetGeom::Mesh {
                    mesh: Box::new(mesh),
                    mods: Vec::new(),
                };
                let source = SetSource::Obj {
                    names: names.clone(),
                };
                let mut s = set(geom, bvh, Vec::new(), expanded, 0, source);
                s.unbound = Some(ObjNames {
                    file: name.to_string(),
                    names,
                    default: default.map(str::to_string),
                });
                Ok(s)
            }
            _ => Err(self.refuse(format!("set {k} ('{name}') is of another kind"), loc)),
        }
    }
}
