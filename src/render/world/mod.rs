//! From primitives to a renderable scene: modifiers resolved to materials, surfaces to
//! geometry in f64 relative to the scene origin ([`crate::scene::world`]), and the BVH over
//! them. The builder lives here, above the scene's geometry, because it parses materials
//! and modifiers; [`Scene`] is the geometry with them.

mod mapped;
mod obj;
mod sets;

use crate::geometry::bvh::Bvh;
use crate::geometry::source::DistantSource;
use crate::geometry::Surface;
use crate::material::{MatId, Material, MaterialLookup, MATERIAL_TYPES};
use crate::modifier::{
    func::FuncShared, ModRef, ModifierDef, ModifierKind, ModifierLookup, ModifierTypes, SceneFiles,
};
use crate::scene::error::SceneError;
use crate::scene::image::SceneImage;
pub use crate::scene::object::{Object, Objects};
use crate::scene::primitive::{Location, Primitive};
use crate::scene::reader::{ReadOptions, KNOWN_TYPES};
use crate::scene::sets::{
    flatten, map_box, placement_boxes, placement_count, Child, ObjectSet, MAX_PLACEMENTS,
};
use crate::scene::transform::Transform;
use crate::scene::world::surface_counts_ok;
pub use crate::scene::world::{length_tolerance, DistantObject, SceneGeometry, SURFACE_TYPES};
use glam::DVec3;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A scene ready for rendering: its geometry ([`SceneGeometry`], which it dereferences to)
/// with the materials, modifiers and functions its surfaces refer to.
pub struct Scene {
    /// Surfaces, sources, instances and the BVH.
    pub geom: SceneGeometry,
    /// Materials, indexed by [`MatId`].
    pub materials: Vec<MaterialDef>,
    /// Patterns, textures and mixtures, indexed by [`crate::modifier::ModId`].
    pub modifiers: Vec<ModifierDef>,
    /// The function language program of the scene's patterns and materials, None when
    /// no primitive uses functions.
    pub functions: Option<Arc<FuncShared>>,
}

impl std::ops::Deref for Scene {
    type Target = SceneGeometry;

    fn deref(&self) -> &SceneGeometry {
        &self.geom
    }
}

impl std::ops::DerefMut for Scene {
    fn deref_mut(&mut self) -> &mut SceneGeometry {
        &mut self.geom
    }
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

impl Scene {
    /// The first fatal error of a function evaluation (rpict would have stopped): renders
    /// stop early and the tools report it.
    pub fn fatal_error(&self) -> Option<&str> {
        self.functions.as_ref().and_then(|f| f.fatal())
    }
}

pub(super) struct Modifiers {
    /// The current definition of each modifier name.
    current: HashMap<String, ModRef>,
    /// Names defined with an unsupported type, for a precise error.
    unsupported: HashMap<String, (String, Location)>,
    /// The patterns, textures and mixtures defined so far.
    pub(super) defs: Vec<ModifierDef>,
    /// The files modifiers read, found along the RAYPATH.
    pub(super) files: SceneFiles,
}

/// A name space put aside while another file's names are bound.
pub(super) type SavedNames = (HashMap<String, ModRef>, HashMap<String, (String, Location)>);

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
    /// Start a fresh name space (an instanced file's), returning the current one.
    pub(super) fn enter(&mut self) -> SavedNames {
        (
            std::mem::take(&mut self.current),
            std::mem::take(&mut self.unsupported),
        )
    }

    /// Go back to a name space put aside by [`Modifiers::enter`].
    pub(super) fn leave(&mut self, saved: SavedNames) {
        (self.current, self.unsupported) = saved;
    }

    /// Define `name` as `r` (a later definition replaces an earlier one for what follows).
    fn define(&mut self, name: &str, r: ModRef) {
        self.unsupported.remove(name);
        self.current.insert(name.to_string(), r);
    }

    /// The material a chain starting at `r` ends in: patterns, textures and mixtures that
    /// act as patterns lead on to their modifier; `void` and other mixtures end in none.
    pub(super) fn terminal(&self, mut r: ModRef) -> Option<MatId> {
        // Names resolve to earlier definitions, so a chain never loops; bound it anyway.
        for _ in 0..=self.defs.len() {
            match r {
                ModRef::Void => return None,
                ModRef::Material(m) => return Some(m),
                ModRef::Modifier(id) => {
                    let d = &self.defs[id];
                    if matches!(*d.kind, ModifierKind::Mixture { .. }) && !d.pattern_like {
                        return None;
                    }
                    r = d.next;
                }
            }
        }
        None
    }

    /// Whether shading the chain from `r` reaches a material (a mixture that is not
    /// pattern-like does, through its sides).
    fn reaches_material(&self, r: ModRef) -> bool {
        match r {
            ModRef::Void => false,
            ModRef::Material(_) => true,
            ModRef::Modifier(id) => {
                let d = &self.defs[id];
                if matches!(*d.kind, ModifierKind::Mixture { .. }) && !d.pattern_like {
                    return true;
                }
                self.terminal(r).is_some()
            }
        }
    }

    /// Whether a mixture of `kind` acts as a pattern: neither side reaches a material.
    fn pattern_like(&self, kind: &ModifierKind) -> bool {
        match kind {
            ModifierKind::Mixture {
                foreground,
                background,
                ..
            } => !self.reaches_material(*foreground) && !self.reaches_material(*background),
            _ => false,
        }
    }

    /// Check a material's own modifier chain: patterns, textures and mixtures of them only
    /// (a material there, or a mixture whose sides reach one, is an error, as in Radiance:
    /// "conflicting material").
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
                ModRef::Modifier(id) => {
                    let d = &self.defs[id];
                    if matches!(*d.kind, ModifierKind::Mixture { .. }) && !d.pattern_like {
                        return Err(format!(
                            "modifier chain '{name}' holds the mixture '{}' of materials: a \
                             material may be modified by patterns, textures and mixtures of \
                             them only (conflicting material)",
                            d.name
                        ));
                    }
                    r = d.next;
                }
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

/// State shared while building a scene and the sets it instances: the modifiers (one
/// name space per file, definitions shared), the materials, the sets read so far.
pub(super) struct Builder<'t> {
    pub(super) mods: Modifiers,
    pub(super) materials: Vec<MaterialDef>,
    pub(super) warnings: Vec<String>,
    types: &'t ModifierTypes,
    pub(super) opts: ReadOptions,
    pub(super) sets: Vec<ObjectSet>,
    pub(super) set_ids: HashMap<PathBuf, usize>,
    /// The files being read (instance loops are refused).
    pub(super) loading: Vec<PathBuf>,
    /// The scene image the sets come from (with the top level's surfaces), if any.
    pub(super) image: Option<&'t SceneImage>,
    /// Why the image was refused, if it was (the build then stops).
    pub(super) refused: Option<String>,
    /// Sets begun so far.
    pub(super) started: usize,
}

/// The objects of one file's primitives (the scene, or an instanced octree or mesh).
pub(super) struct Level {
    pub(super) origin: DVec3,
    pub(super) size: f64,
    pub(super) eps: f64,
    pub(super) objects: Objects,
    pub(super) distant: Vec<DistantObject>,
    /// Its instances and meshes.
    pub(super) children: Vec<Child>,
    /// Bounds of everything, instances included (the file's coordinates).
    pub(super) full: Option<(DVec3, DVec3)>,
    /// The modifier each primitive defined.
    pub(super) defined: Vec<Option<ModRef>>,
}

impl Builder<'_> {
    /// Objects, distant sources and instances of `prims` (names bound in the current name
    /// space), relative to the centre of their bounds.
    ///
    /// The real and string arguments of each finite surface are freed once it is built (the
    /// text of a large mesh or `gensurf` would otherwise be held until the whole scene is).
    ///
    /// With `framed` (the origin, size and length tolerance of a scene image, which holds
    /// the finite surfaces) the finite surfaces are skipped: the level has no objects, the
    /// rest (materials, modifiers, distant sources, instances) is built as usual.
    pub(super) fn level(
        &mut self,
        prims: &mut [Primitive],
        framed: Option<(DVec3, f64, f64)>,
    ) -> Result<Level, SceneError> {
        let err = |p: &Primitive, msg: String| SceneError::syntax(p.loc.clone(), msg);
        // Pass 1: bounds of finite geometry, to choose the origin. Surfaces are parsed once
        // with a zero origin for bounds, then re-parsed relative to the chosen origin.
        // Instanced files are read and built here (their bounds count).
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut pending: Vec<(usize, Transform)> = Vec::new();
        let mut nsurf = 0;
        for p in prims.iter() {
            if p.ptype == "instance" || p.ptype == "mesh" {
                let (set, xf) = self.child_set(p)?;
                if let Some(full) = self.sets[set].full {
                    let (a, b) = map_box(full, |c| xf.point(c));
                    lo = lo.min(a);
                    hi = hi.max(b);
                }
                pending.push((set, xf));
            } else if framed.is_none()
                && SURFACE_TYPES.contains(&p.ptype.as_str())
                && p.ptype != "source"
            {
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
                nsurf += 1;
            }
        }
        let full = (lo.x.is_finite() && hi.x.is_finite()).then_some((lo, hi));
        let (origin, size) = if let Some((lo, hi)) = full {
            let c = (lo + hi) * 0.5;
            let ext = (hi - lo).max_element();
            (c, if ext > 0.0 { ext } else { 1.0 })
        } else {
            (DVec3::ZERO, 1.0)
        };
        let eps = length_tolerance(size);
        let (origin, size, eps) = framed.unwrap_or((origin, size, eps));

        let mut objects = Objects::with_capacity(nsurf);
        let mut distant = Vec::new();
        let mut children = Vec::new();
        let mut defined = Vec::with_capacity(prims.len());
        let mut pending = pending.into_iter();
        // Placements the instances so far make once flattened.
        let mut placed = 0u64;
        let (mods, materials) = (&mut self.mods, &mut self.materials);
        for p in prims {
            let t = p.ptype.as_str();
            let mut def = None;
            if t == "alias" {
                let r = alias(p, mods, materials).map_err(|m| err(p, m))?;
                mods.define(&p.name, r);
                def = Some(r);
            } else if t == "instance" || t == "mesh" {
                let chain = mods.modref(&p.modifier).map_err(|m| err(p, m))?;
                if let Some((set, xf)) = pending.next() {
                    placed = placed.saturating_add(placement_count(&self.sets[set]));
                    if placed > MAX_PLACEMENTS as u64 {
                        return Err(err(
                            p,
                            format!(
                                "{t} {}: more than {MAX_PLACEMENTS} instance placements \
                                 (nested instances multiply: this one places {} and the \
                                 file's instances up to it {placed})",
                                p.name,
                                placement_count(&self.sets[set])
                            ),
                        ));
                    }
                    obj::bind_names(mods, &mut self.sets[set])?;
                    children.push(Child {
                        set,
                        xf,
                        chain,
                        material: mods.terminal(chain),
                        modifier: p.modifier.clone(),
                    });
                }
            } else if SURFACE_TYPES.contains(&t) {
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
                } else if framed.is_some() {
                    // The scene image holds it.
                } else {
                    let surface = match Surface::from_primitive_warn(p, origin) {
                        Ok((mut s, w)) => {
                            if let Some(w) = w {
                                self.warnings.push(format!("{}: {w}", p.loc));
                            }
                            s.set_eps(eps);
                            s
                        }
                        Err(m) if !surface_counts_ok(p) => {
                            return Err(err(p, format!("{t} {}: {m}", p.name)))
                        }
                        Err(m) => {
                            self.warnings
                                .push(format!("{}: {t} {} dropped: {m}", p.loc, p.name));
                            defined.push(None);
                            continue;
                        }
                    };
                    objects
                        .push(surface, material, chain, &p.name, &p.modifier, &p.loc)
                        .map_err(|m| err(p, m))?;
                    p.rargs = Vec::new();
                    p.sargs = Vec::new();
                    p.name = String::new();
                    p.modifier = String::new();
                }
            } else if MATERIAL_TYPES.contains(&t) {
                let chain = mods
                    .material_chain(&p.modifier)
                    .map_err(|m| err(p, format!("{t} {}: {m}", p.name)))?;
                let material = Material::parse(p, &*mods)
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
                def = Some(ModRef::Material(id));
            } else if let Some(parse) = self.types.get(t) {
                let kind = parse(p, &*mods).map_err(|m| err(p, format!("{t} {}: {m}", p.name)))?;
                let next = mods.modref(&p.modifier).map_err(|m| err(p, m))?;
                let pattern_like = mods.pattern_like(&kind);
                if matches!(kind, ModifierKind::Mixture { .. })
                    && !pattern_like
                    && next != ModRef::Void
                {
                    return Err(err(
                        p,
                        format!(
                            "{t} {}: the modifier of a mixture of materials must be void",
                            p.name
                        ),
                    ));
                }
                let id = mods.defs.len();
                mods.defs.push(ModifierDef {
                    kind: std::sync::Arc::new(kind),
                    next,
                    name: p.name.clone(),
                    pattern_like,
                });
                mods.define(&p.name, ModRef::Modifier(id));
                def = Some(ModRef::Modifier(id));
            } else if KNOWN_TYPES.contains(&t) {
                // Every other type Radiance knows (BSDFs, prisms, ...) is not implemented.
                return Err(err(
                    p,
                    format!(
                        "unsupported primitive type {t} ({} {t} {})",
                        p.modifier, p.name
                    ),
                ));
            } else {
                return Err(err(p, format!("unknown primitive type '{t}'")));
            }
            defined.push(def);
        }
        objects.finish();
        Ok(Level {
            origin,
            size,
            eps,
            objects,
            distant,
            children,
            full,
            defined,
        })
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
            if matches!(*src.kind, ModifierKind::Mixture { .. })
                && !src.pattern_like
                && next != ModRef::Void
            {
                return Err("the modifier of a mixture of materials must be void".into());
            }
            let def = ModifierDef {
                kind: src.kind.clone(),
                next,
                name: p.name.clone(),
                pattern_like: src.pattern_like,
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

    /// [`Scene::build`] with files that modifiers name (fonts, text, data files, pictures,
    /// instanced octrees and meshes) looked up along `raypath` (empty: the current
    /// directory).
    pub fn build_on(prims: &[Primitive], raypath: &[PathBuf]) -> Result<Scene, SceneError> {
        Scene::build_in(prims, &ModifierTypes::standard(), raypath)
    }

    /// A scene from the text of a scene file, with the files it reads (name, contents)
    /// written to a temporary folder on its RAYPATH (unit tests).
    #[cfg(test)]
    pub(crate) fn from_text(text: &str, files: &[(&str, &str)]) -> Scene {
        use crate::scene::reader::{parse_scene_text, ReadOptions};
        let dir = tempfile::tempdir().expect("a temporary folder");
        for (name, contents) in files {
            std::fs::write(dir.path().join(name), contents).expect("a test file written");
        }
        let opts = ReadOptions {
            raypath: vec![dir.path().to_path_buf()],
            ..ReadOptions::default()
        };
        let prims = parse_scene_text(text, "t.rad", &opts).expect("the test scene parses");
        Scene::build_on(&prims, &opts.raypath).expect("the test scene builds")
    }

    /// [`Scene::build_on`] with the reader's options (the RAYPATH, and whether the scene
    /// files of instanced octrees may run inline commands).
    pub fn build_read(prims: &[Primitive], opts: &ReadOptions) -> Result<Scene, SceneError> {
        Scene::build_opts(prims, &ModifierTypes::standard(), opts)
    }

    /// [`Scene::build_read`] that frees the arguments and names of the finite surfaces as it
    /// builds them, and the primitives before the BVH is built: what renderers use, which
    /// need the primitives no more once the scene is built.
    pub fn build_taking(prims: Vec<Primitive>, opts: &ReadOptions) -> Result<Scene, SceneError> {
        Scene::build_opts_taking(prims, &ModifierTypes::standard(), opts)
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
        let opts = ReadOptions {
            allow_commands: false,
            raypath: raypath.to_vec(),
            ..ReadOptions::default()
        };
        Scene::build_opts(prims, types, &opts)
    }

    /// [`Scene::build`] with the modifier types `types` and the reader's options.
    pub fn build_opts(
        prims: &[Primitive],
        types: &ModifierTypes,
        opts: &ReadOptions,
    ) -> Result<Scene, SceneError> {
        Scene::build_opts_taking(prims.to_vec(), types, opts)
    }

    /// [`Scene::build_opts`] freeing the primitives as it goes ([`Scene::build_taking`]).
    fn build_opts_taking(
        prims: Vec<Primitive>,
        types: &ModifierTypes,
        opts: &ReadOptions,
    ) -> Result<Scene, SceneError> {
        // Without an image nothing is refused.
        Scene::build_core(prims, types, opts, None)?
            .map_err(|m| SceneError::syntax(Location::new("<scene>", 0), m))
    }

    /// [`Scene::build_taking`] with the top level's finite surfaces and BVH taken from a
    /// scene image made for these primitives ([`crate::scene::image`]) instead of built.
    /// The outer error is the scene's; the inner one says why the image was refused (then
    /// build the scene without it).
    pub fn build_with_image(
        prims: Vec<Primitive>,
        opts: &ReadOptions,
        image: &SceneImage,
    ) -> Result<Result<Scene, String>, SceneError> {
        Scene::build_core(prims, &ModifierTypes::standard(), opts, Some(image))
    }

    fn build_core(
        mut prims: Vec<Primitive>,
        types: &ModifierTypes,
        opts: &ReadOptions,
        image: Option<&SceneImage>,
    ) -> Result<Result<Scene, String>, SceneError> {
        let mut b = Builder {
            mods: Modifiers {
                current: HashMap::new(),
                unsupported: HashMap::new(),
                defs: Vec::new(),
                files: SceneFiles::new(&opts.raypath),
            },
            materials: Vec::new(),
            warnings: Vec::new(),
            types,
            opts: opts.clone(),
            sets: Vec::new(),
            set_ids: HashMap::new(),
            loading: Vec::new(),
            image,
            refused: None,
            started: 0,
        };
        let mut level = match b.level(&mut prims, image.map(|i| i.frame())) {
            Ok(level) => level,
            Err(e) => {
                return match b.refused.take() {
                    Some(why) => Ok(Err(why)),
                    None => Err(e),
                }
            }
        };
        if let Some(image) = image {
            if image.sets() != b.sets.len() {
                let why = format!("it has {} sets, the scene {}", image.sets(), b.sets.len());
                return Ok(Err(why));
            }
        }
        let first = prims.first().map(|p| p.loc.clone());
        drop(prims);
        let placements = if level.children.is_empty() {
            Vec::new()
        } else {
            flatten(&b.sets, &level.children, level.origin).map_err(|m| {
                let loc = first.unwrap_or_else(|| Location::new("<scene>", 0));
                SceneError::syntax(loc, m)
            })?
        };
        let bvh = if let Some(image) = image {
            let taken = image
                .objects(b.materials.len(), b.mods.defs.len())
                .and_then(|o| {
                    if image.placements() != placements.len() {
                        return Err("its instance placements differ from the scene's".into());
                    }
                    Ok((image.bvh(o.len() + placements.len())?, o))
                });
            match taken {
                Ok((bvh, objects)) => {
                    level.objects = objects;
                    b.warnings = image.warnings().to_vec();
                    bvh
                }
                Err(e) => return Ok(Err(e)),
            }
        } else {
            let mut all: Vec<(DVec3, DVec3)> = (0..level.objects.len())
                .map(|i| level.objects.surface(i).bounds())
                .collect();
            all.extend(placement_boxes(&b.sets, &placements));
            Bvh::build(&all, level.eps)
        };
        let functions = b.mods.files.functions().finish();
        let inputs = b.mods.files.relative_inputs();
        Ok(Ok(Scene {
            geom: SceneGeometry {
                origin: level.origin,
                size: level.size,
                eps: level.eps,
                objects: level.objects,
                distant: level.distant,
                bvh,
                warnings: b.warnings,
                inputs,
                sets: b.sets,
                placements,
            },
            materials: b.materials,
            modifiers: b.mods.defs,
            functions,
        }))
    }

    /// The material of a material id.
    #[inline]
    pub fn material(&self, id: MatId) -> &Material {
        &self.materials[id].material
    }
}
