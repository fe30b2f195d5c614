//! From primitives to a renderable scene: modifiers resolved to materials, surfaces to
//! geometry in f64 relative to the scene origin, and the BVH over them.

use super::error::SceneError;
use super::primitive::{Location, Primitive};
use crate::geometry::bvh::Bvh;
use crate::geometry::source::DistantSource;
use crate::geometry::Surface;
use crate::material::{MatId, Material, MaterialLookup, MATERIAL_TYPES};
use crate::modifier::{
    func::FuncShared, ModRef, ModifierDef, ModifierKind, ModifierLookup, ModifierTypes, SceneFiles,
};
use crate::scene::reader::KNOWN_TYPES;
use crate::FTINY;
use glam::DVec3;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// Surface primitive types (finite ones go into the BVH; `source` is distant).
pub const SURFACE_TYPES: &[&str] = &[
    "polygon", "sphere", "bubble", "cone", "cup", "cylinder", "tube", "ring", "source",
];

/// A finite surface with its material.
#[derive(Clone, Debug)]
pub struct Object {
    /// Geometry (relative to [`Scene::origin`]).
    pub surface: Surface,
    /// The material its modifier chain ends in, or None for a chain that ends in `void`
    /// (such surfaces are invisible) or a mixture.
    pub material: Option<MatId>,
    /// Its modifier: the start of its chain.
    pub chain: ModRef,
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
    /// The material its modifier chain ends in.
    pub material: Option<MatId>,
    /// Its modifier: the start of its chain.
    pub chain: ModRef,
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
    /// Its own modifier chain (patterns and textures applied before it shades).
    pub chain: ModRef,
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

/// The length tolerance of a scene of size `size`: Radiance's `FTINY` for scenes of a unit
/// and larger, `FTINY · size` below, so that a scene scaled down renders the same picture
/// (an absolute 1e-6 is a tenth of a scene of 1e-5).
pub fn length_tolerance(size: f64) -> f64 {
    if size.is_finite() && size > 0.0 {
        FTINY * size.min(1.0)
    } else {
        FTINY
    }
}

/// A scene ready for rendering.
pub struct Scene {
    /// Scene origin: every coordinate in geometry is relative to it.
    pub origin: DVec3,
    /// Size of the scene's bounding cube (like the octree cube of oconv).
    pub size: f64,
    /// The scene's length tolerance ([`length_tolerance`]): the minimum hit distance, the
    /// polygons' edge tolerance and the slack of shadow rays.
    pub eps: f64,
    /// Materials, indexed by [`MatId`].
    pub materials: Vec<MaterialDef>,
    /// Patterns, textures and mixtures, indexed by [`crate::modifier::ModId`].
    pub modifiers: Vec<ModifierDef>,
    /// Finite surfaces, indexed as in the BVH.
    pub objects: Vec<Object>,
    /// Distant sources.
    pub distant: Vec<DistantObject>,
    /// Acceleration structure over `objects`.
    pub bvh: Bvh,
    /// Warnings (degenerate geometry dropped, zero areas), each naming file:line.
    pub warnings: Vec<String>,
    /// The function language program of the scene's patterns and materials, None when
    /// no primitive uses functions.
    pub functions: Option<Arc<FuncShared>>,
    /// The files its primitives read by relative name (data files, pictures, fonts, text
    /// and function files): the name as given and the path found along the RAYPATH.
    pub inputs: Vec<(String, PathBuf)>,
}

impl Scene {
    /// The first fatal error of a function evaluation (rpict would have stopped): renders
    /// stop early and the tools report it.
    pub fn fatal_error(&self) -> Option<&str> {
        self.functions.as_ref().and_then(|f| f.fatal())
    }
}

struct Modifiers {
    /// The current definition of each modifier name.
    current: HashMap<String, ModRef>,
    /// Names defined with an unsupported type, for a precise error.
    unsupported: HashMap<String, (String, Location)>,
    /// The patterns, textures and mixtures defined so far.
    defs: Vec<ModifierDef>,
    /// The files modifiers read, found along the RAYPATH.
    files: SceneFiles,
}

impl ModifierLookup for Modifiers {
    fn modref(&self, name: &str) -> Result<ModRef, String> {
        if name == "void" {
            return Ok(ModRef::Void);
        }
        if let Some((t, loc)) = self.unsupported.get(name) {
            return Err(format!(
                "modifier '{name}' is of unsupported primitive type {t} (defined at {loc})"
            ));
        }
        match self.current.get(name) {
            Some(r) => Ok(*r),
            None => Err(format!("unknown modifier '{name}'")),
        }
    }

    fn files(&self) -> &SceneFiles {
        &self.files
    }
}

impl Modifiers {
    /// Define `name` as `r` (a later definition replaces an earlier one for what follows).
    fn define(&mut self, name: &str, r: ModRef) {
        self.unsupported.remove(name);
        self.current.insert(name.to_string(), r);
    }

    /// The material a chain starting at `r` ends in: patterns and textures lead on to their
    /// modifier; `void` and mixtures end in none.
    fn terminal(&self, mut r: ModRef) -> Option<MatId> {
        // Names resolve to earlier definitions, so a chain never loops; bound it anyway.
        for _ in 0..=self.defs.len() {
            match r {
                ModRef::Void => return None,
                ModRef::Material(m) => return Some(m),
                ModRef::Modifier(id) => match *self.defs[id].kind {
                    ModifierKind::Mixture { .. } => return None,
                    _ => r = self.defs[id].next,
                },
            }
        }
        None
    }

    /// Check a material's own modifier chain: patterns and textures only (a material or a
    /// mixture there is an error, as in Radiance).
    fn material_chain(&self, name: &str) -> Result<ModRef, String> {
        let first = self.modref(name)?;
        let mut r = first;
        for _ in 0..=self.defs.len() {
            match r {
                ModRef::Void => return Ok(first),
                ModRef::Material(_) => {
                    return Err(format!(
                        "modifier chain '{name}' reaches a material: a material may be \
                         modified by patterns and textures only (conflicting material)"
                    ))
                }
                ModRef::Modifier(id) => match *self.defs[id].kind {
                    ModifierKind::Mixture { .. } => {
                        return Err(format!(
                            "modifier chain '{name}' holds the mixture '{}': a material may \
                             be modified by patterns and textures only",
                            self.defs[id].name
                        ))
                    }
                    _ => r = self.defs[id].next,
                },
            }
        }
        Ok(first)
    }
}

impl MaterialLookup for Modifiers {
    fn material(&self, name: &str) -> Result<Option<MatId>, String> {
        if name == "void" {
            return Ok(None);
        }
        match self.modref(name)? {
            ModRef::Void => Ok(None),
            ModRef::Material(m) => Ok(Some(m)),
            ModRef::Modifier(id) => Err(format!(
                "'{name}' is a pattern, texture or mixture ({}), not a material",
                self.defs[id].name
            )),
        }
    }

    fn files(&self) -> &SceneFiles {
        &self.files
    }
}

/// What `mod alias name [target]` defines (Radiance's rules): without a target, `mod`
/// itself; with one, the target with the alias's modifier in place of its own (`inherit`:
/// the target's own), so `void alias` drops a material's patterns.
fn alias(
    p: &Primitive,
    mods: &mut Modifiers,
    materials: &mut Vec<MaterialDef>,
) -> Result<ModRef, String> {
    let Some(target) = p.sargs.first() else {
        return mods.modref(&p.modifier);
    };
    let r = mods.modref(target)?;
    if p.modifier == "inherit" {
        return Ok(r);
    }
    match r {
        ModRef::Void => Ok(ModRef::Void),
        ModRef::Material(id) => {
            let chain = mods.material_chain(&p.modifier)?;
            if chain == materials[id].chain {
                return Ok(r);
            }
            let mut def = materials[id].clone();
            def.chain = chain;
            def.name = p.name.clone();
            def.loc = p.loc.clone();
            def.order = materials.len();
            materials.push(def);
            Ok(ModRef::Material(materials.len() - 1))
        }
        ModRef::Modifier(id) => {
            let next = mods.modref(&p.modifier)?;
            let src = &mods.defs[id];
            if matches!(*src.kind, ModifierKind::Mixture { .. }) && next != ModRef::Void {
                return Err("a mixture's modifier must be void".into());
            }
            let def = ModifierDef {
                kind: src.kind.clone(),
                next,
                name: p.name.clone(),
            };
            mods.defs.push(def);
            Ok(ModRef::Modifier(mods.defs.len() - 1))
        }
    }
}

impl Scene {
    /// Build a scene from primitives in definition order, with Tessera's modifier types;
    /// files that modifiers name are looked up in the current directory (Radiance's default
    /// RAYPATH).
    pub fn build(prims: &[Primitive]) -> Result<Scene, SceneError> {
        Scene::build_with(prims, &ModifierTypes::standard())
    }

    /// [`Scene::build`] with files that modifiers name (fonts, text, data files, pictures)
    /// looked up along `raypath` (empty: the current directory).
    pub fn build_on(prims: &[Primitive], raypath: &[PathBuf]) -> Result<Scene, SceneError> {
        Scene::build_in(prims, &ModifierTypes::standard(), raypath)
    }

    /// [`Scene::build`] with the modifier types `types`.
    pub fn build_with(prims: &[Primitive], types: &ModifierTypes) -> Result<Scene, SceneError> {
        Scene::build_in(prims, types, &[])
    }

    /// [`Scene::build`] with the modifier types `types` and files looked up along
    /// `raypath`.
    pub fn build_in(
        prims: &[Primitive],
        types: &ModifierTypes,
        raypath: &[PathBuf],
    ) -> Result<Scene, SceneError> {
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
        let eps = length_tolerance(size);

        let mut mods = Modifiers {
            current: HashMap::new(),
            unsupported: HashMap::new(),
            defs: Vec::new(),
            files: SceneFiles::new(raypath),
        };
        let mut materials: Vec<MaterialDef> = Vec::new();
        let mut objects = Vec::new();
        let mut distant = Vec::new();
        let mut warnings = Vec::new();
        for p in prims {
            let t = p.ptype.as_str();
            if t == "alias" {
                let r = alias(p, &mut mods, &mut materials).map_err(|m| err(p, m))?;
                mods.define(&p.name, r);
                continue;
            }
            if SURFACE_TYPES.contains(&t) {
                let chain = mods.modref(&p.modifier).map_err(|m| err(p, m))?;
                let material = mods.terminal(chain);
                if t == "source" {
                    let source = DistantSource::from_primitive(p)
                        .map_err(|m| err(p, format!("source {}: {m}", p.name)))?;
                    distant.push(DistantObject {
                        source,
                        material,
                        chain,
                        name: p.name.clone(),
                        modifier: p.modifier.clone(),
                    });
                } else {
                    let surface = match Surface::from_primitive_warn(p, origin) {
                        Ok((mut s, w)) => {
                            if let Some(w) = w {
                                warnings.push(format!("{}: {w}", p.loc));
                            }
                            s.set_eps(eps);
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
                        chain,
                        name: p.name.clone(),
                        modifier: p.modifier.clone(),
                        loc: p.loc.clone(),
                    });
                }
                continue;
            }
            if MATERIAL_TYPES.contains(&t) {
                let chain = mods
                    .material_chain(&p.modifier)
                    .map_err(|m| err(p, format!("{t} {}: {m}", p.name)))?;
                let material = Material::parse(p, &mods)
                    .map_err(|m| err(p, format!("{t} {}: {m}", p.name)))?;
                let id = materials.len();
                materials.push(MaterialDef {
                    material,
                    chain,
                    name: p.name.clone(),
                    order: id,
                    loc: p.loc.clone(),
                });
                mods.define(&p.name, ModRef::Material(id));
                continue;
            }
            if let Some(parse) = types.get(t) {
                let kind = parse(p, &mods).map_err(|m| err(p, format!("{t} {}: {m}", p.name)))?;
                let next = mods.modref(&p.modifier).map_err(|m| err(p, m))?;
                if matches!(kind, ModifierKind::Mixture { .. }) && next != ModRef::Void {
                    return Err(err(
                        p,
                        format!("{t} {}: a mixture's modifier must be void", p.name),
                    ));
                }
                let id = mods.defs.len();
                mods.defs.push(ModifierDef {
                    kind: std::sync::Arc::new(kind),
                    next,
                    name: p.name.clone(),
                });
                mods.define(&p.name, ModRef::Modifier(id));
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
        let bvh = Bvh::build(&bounds, eps);
        let functions = mods.files.functions().finish();
        let inputs = mods.files.relative_inputs();
        Ok(Scene {
            origin,
            size,
            eps,
            materials,
            modifiers: mods.defs,
            objects,
            distant,
            bvh,
            warnings,
            functions,
            inputs,
        })
    }

    /// The material of a material id.
    #[inline]
    pub fn material(&self, id: MatId) -> &Material {
        &self.materials[id].material
    }
}
