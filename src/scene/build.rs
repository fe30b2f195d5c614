//! From primitives to a renderable scene: modifiers resolved to materials, surfaces to
//! geometry in f64 relative to the scene origin, and the BVH over them.

use super::error::SceneError;
use super::primitive::{Location, Primitive};
use crate::geometry::bvh::Bvh;
use crate::geometry::source::DistantSource;
use crate::geometry::Surface;
use crate::material::{MatId, Material, MaterialLookup, MATERIAL_TYPES};
use crate::scene::reader::KNOWN_TYPES;
use glam::DVec3;
use std::collections::HashMap;

/// Surface primitive types (finite ones go into the BVH; `source` is distant).
pub const SURFACE_TYPES: &[&str] = &[
    "polygon", "sphere", "bubble", "cone", "cup", "cylinder", "tube", "ring", "source",
];

/// A finite surface with its material.
#[derive(Clone, Debug)]
pub struct Object {
    /// Geometry (relative to [`Scene::origin`]).
    pub surface: Surface,
    /// Material, or None for a `void` modifier (such surfaces are invisible).
    pub material: Option<MatId>,
    /// Identifier.
    pub name: String,
    /// Modifier name as written.
    pub modifier: String,
    /// Where it was defined.
    pub loc: Location,
}

/// A distant `source` with its material.
#[derive(Clone, Debug)]
pub struct DistantObject {
    /// Direction and size.
    pub source: DistantSource,
    /// Material.
    pub material: Option<MatId>,
    /// Identifier.
    pub name: String,
    /// Modifier name as written.
    pub modifier: String,
}

/// A material together with its name and where it was defined.
#[derive(Clone, Debug)]
pub struct MaterialDef {
    /// The material.
    pub material: Material,
    /// Identifier.
    pub name: String,
    /// Order of definition (later definitions win coincident-surface ties).
    pub order: usize,
    /// Where it was defined.
    pub loc: Location,
}

/// Whether a surface primitive has the argument counts its type needs (a wrong count is a
/// fatal error; degenerate geometry with the right counts is dropped with a warning, as
/// oconv does).
fn surface_counts_ok(p: &Primitive) -> bool {
    if !p.sargs.is_empty() || !p.iargs.is_empty() {
        return false;
    }
    let n = p.rargs.len();
    match p.ptype.as_str() {
        "polygon" => n >= 9 && n.is_multiple_of(3),
        "sphere" | "bubble" | "source" => n == 4,
        "cone" | "cup" | "ring" => n == 8,
        "cylinder" | "tube" => n == 7,
        _ => false,
    }
}

/// A scene ready for rendering.
pub struct Scene {
    /// Scene origin: every coordinate in geometry is relative to it.
    pub origin: DVec3,
    /// Size of the scene's bounding cube (like the octree cube of oconv).
    pub size: f64,
    /// Materials, indexed by [`MatId`].
    pub materials: Vec<MaterialDef>,
    /// Finite surfaces, indexed as in the BVH.
    pub objects: Vec<Object>,
    /// Distant sources.
    pub distant: Vec<DistantObject>,
    /// Acceleration structure over `objects`.
    pub bvh: Bvh,
    /// Warnings (degenerate geometry dropped, zero areas), each naming file:line.
    pub warnings: Vec<String>,
}

struct Modifiers {
    current: HashMap<String, Option<MatId>>,
    /// Names defined with an unsupported type, for a precise error.
    unsupported: HashMap<String, (String, Location)>,
}

impl MaterialLookup for Modifiers {
    fn material(&self, name: &str) -> Result<Option<MatId>, String> {
        if name == "void" {
            return Ok(None);
        }
        if let Some((t, loc)) = self.unsupported.get(name) {
            return Err(format!(
                "modifier '{name}' is of unsupported primitive type {t} (defined at {loc})"
            ));
        }
        match self.current.get(name) {
            Some(m) => Ok(*m),
            None => Err(format!("unknown modifier '{name}'")),
        }
    }
}

impl Scene {
    /// Build a scene from primitives in definition order.
    pub fn build(prims: &[Primitive]) -> Result<Scene, SceneError> {
        let err = |p: &Primitive, msg: String| SceneError::syntax(p.loc.clone(), msg);
        // Pass 1: bounds of finite geometry, to choose the origin. Surfaces are parsed once
        // with a zero origin for bounds, then re-parsed relative to the chosen origin.
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in prims {
            if SURFACE_TYPES.contains(&p.ptype.as_str()) && p.ptype != "source" {
                let s = match Surface::from_primitive(p, DVec3::ZERO) {
                    Ok(s) => s,
                    Err(m) if !surface_counts_ok(p) => {
                        return Err(err(p, format!("{} {}: {m}", p.ptype, p.name)))
                    }
                    Err(_) => continue,
                };
                let (a, b) = s.bounds();
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        let (origin, size) = if lo.x.is_finite() && hi.x.is_finite() {
            let c = (lo + hi) * 0.5;
            let ext = (hi - lo).max_element();
            (c, if ext > 0.0 { ext } else { 1.0 })
        } else {
            (DVec3::ZERO, 1.0)
        };

        let mut mods = Modifiers {
            current: HashMap::new(),
            unsupported: HashMap::new(),
        };
        let mut materials: Vec<MaterialDef> = Vec::new();
        let mut objects = Vec::new();
        let mut distant = Vec::new();
        let mut warnings = Vec::new();
        for p in prims {
            let t = p.ptype.as_str();
            if t == "alias" {
                let target = p
                    .sargs
                    .first()
                    .ok_or_else(|| err(p, format!("alias {} names no original", p.name)))?;
                let m = mods.material(target).map_err(|m| err(p, m))?;
                if p.modifier != "void" && p.modifier != "inherit" {
                    // A pattern or texture modifier on the alias is not supported yet.
                    mods.material(&p.modifier).map_err(|m| err(p, m))?;
                    return Err(err(
                        p,
                        format!(
                            "alias {} with modifier '{}': modifying a material by another \
                             material is not supported",
                            p.name, p.modifier
                        ),
                    ));
                }
                mods.unsupported.remove(&p.name);
                mods.current.insert(p.name.clone(), m);
                continue;
            }
            if SURFACE_TYPES.contains(&t) {
                let material = mods.material(&p.modifier).map_err(|m| err(p, m))?;
                if t == "source" {
                    let source = DistantSource::from_primitive(p)
                        .map_err(|m| err(p, format!("source {}: {m}", p.name)))?;
                    distant.push(DistantObject {
                        source,
                        material,
                        name: p.name.clone(),
                        modifier: p.modifier.clone(),
                    });
                } else {
                    let surface = match Surface::from_primitive_warn(p, origin) {
                        Ok((s, w)) => {
                            if let Some(w) = w {
                                warnings.push(format!("{}: {w}", p.loc));
                            }
                            s
                        }
                        Err(m) if !surface_counts_ok(p) => {
                            return Err(err(p, format!("{t} {}: {m}", p.name)))
                        }
                        Err(m) => {
                            warnings.push(format!("{}: {t} {} dropped: {m}", p.loc, p.name));
                            continue;
                        }
                    };
                    objects.push(Object {
                        surface,
                        material,
                        name: p.name.clone(),
                        modifier: p.modifier.clone(),
                        loc: p.loc.clone(),
                    });
                }
                continue;
            }
            if MATERIAL_TYPES.contains(&t) {
                if p.modifier != "void" {
                    // Materials may only be modified by patterns/textures, which are not
                    // supported yet: report which.
                    mods.material(&p.modifier).map_err(|m| err(p, m))?;
                    return Err(err(
                        p,
                        format!(
                            "{t} {}: modifier '{}' must be a pattern or texture, which is not \
                             supported yet",
                            p.name, p.modifier
                        ),
                    ));
                }
                let material = Material::parse(t, &p.sargs, &p.rargs, &mods)
                    .map_err(|m| err(p, format!("{t} {}: {m}", p.name)))?;
                let id = materials.len();
                materials.push(MaterialDef {
                    material,
                    name: p.name.clone(),
                    order: id,
                    loc: p.loc.clone(),
                });
                mods.unsupported.remove(&p.name);
                mods.current.insert(p.name.clone(), Some(id));
                continue;
            }
            // Every other type Radiance knows (patterns, textures, mixtures, BSDFs, instances,
            // ...) is not implemented yet.
            if KNOWN_TYPES.contains(&t) {
                return Err(err(
                    p,
                    format!(
                        "unsupported primitive type {t} ({} {t} {})",
                        p.modifier, p.name
                    ),
                ));
            }
            return Err(err(p, format!("unknown primitive type '{t}'")));
        }
        let bounds: Vec<(DVec3, DVec3)> = objects.iter().map(|o| o.surface.bounds()).collect();
        let bvh = Bvh::build(&bounds);
        Ok(Scene {
            origin,
            size,
            materials,
            objects,
            distant,
            bvh,
            warnings,
        })
    }

    /// The material of a material id.
    #[inline]
    pub fn material(&self, id: MatId) -> &Material {
        &self.materials[id].material
    }
}
