//! OBJ files as object sets: read by [`crate::scene::obj`], their modifier names bound
//! where they are placed.

use super::sets::mesh_object_set;
use super::{Builder, Modifiers};
use crate::modifier::{ModRef, ModifierLookup};
use crate::scene::error::SceneError;
use crate::scene::obj::{parse_obj, ObjNames};
use crate::scene::primitive::Location;
use crate::scene::sets::{MeshModifier, ObjectSet, SetGeom};

impl Builder<'_> {
    /// The set of a mesh primitive naming an OBJ file, its names not yet bound
    /// ([`bind_names`] binds them where the mesh is placed). Triangles without a name use
    /// `default` (when given).
    pub(super) fn obj_set(
        &mut self,
        name: &str,
        path: &std::path::Path,
        default: Option<&str>,
    ) -> Result<ObjectSet, SceneError> {
        let loc = Location::new(name, 0);
        let text = std::fs::read(path).map_err(|e| SceneError::Io {
            loc: loc.clone(),
            path: name.to_string(),
            reason: e.to_string(),
        })?;
        let text = String::from_utf8_lossy(&text);
        let obj = parse_obj(&text, name)
            .map_err(|(line, m)| SceneError::syntax(Location::new(name, line), m))?;
        self.warnings.extend(obj.warnings);
        let mut tris = obj.tris;
        if default.is_some() {
            let k = obj.names.len() as i16;
            for t in tris.iter_mut().filter(|t| t.modifier < 0) {
                t.modifier = k.into();
            }
        }
        let mesh = crate::geometry::trimesh::TriMesh {
            pos: obj.pos.into(),
            normal: obj.normal.into(),
            uv: obj.uv.into(),
            flags: obj.flags.into(),
            tris: tris.into(),
            eps: 0.0,
        };
        let mut set = mesh_object_set(
            name,
            mesh,
            Vec::new(),
            crate::scene::sets::SetSource::Obj {
                names: obj.names.clone(),
            },
        );
        set.unbound = Some(ObjNames {
            file: name.to_string(),
            names: obj.names,
            default: default.map(str::to_string),
        });
        Ok(set)
    }
}

/// Bind an OBJ set's modifier names in the name space where it is first placed (what is
/// defined before the mesh primitive, as obj2mesh's `-a` files): `void` is void, an
/// undefined name takes the default or is an error naming the line that set it.
pub(super) fn bind_names(mods: &Modifiers, set: &mut ObjectSet) -> Result<(), SceneError> {
    let Some(b) = set.unbound.take() else {
        return Ok(());
    };
    let resolve = |n: &str| -> Result<Option<MeshModifier>, String> {
        let chain = mods.modref(n)?;
        Ok((chain != ModRef::Void).then(|| MeshModifier {
            chain,
            material: mods.terminal(chain),
            name: n.to_string(),
        }))
    };
    let fallback = match &b.default {
        Some(d) => Some(resolve(d).map_err(|m| {
            SceneError::syntax(
                Location::new(b.file.as_str(), 0),
                format!("default modifier: {m}"),
            )
        })?),
        None => None,
    };
    let mut out = Vec::with_capacity(b.names.len() + 1);
    for (n, line) in &b.names {
        let at = |m: String| SceneError::syntax(Location::new(b.file.as_str(), *line), m);
        out.push(match resolve(n) {
            Ok(m) => m,
            Err(e) if e.starts_with("unknown modifier") => match &fallback {
                Some(f) => f.clone(),
                None => {
                    return Err(at(format!(
                        "undefined modifier '{n}' (define it before the OBJ file, or give \
                         a default with --obj-material)"
                    )))
                }
            },
            Err(e) => return Err(at(e)),
        });
    }
    out.extend(fallback);
    if let SetGeom::Mesh { mods, .. } = &mut set.geom {
        *mods = out;
    }
    Ok(())
}
