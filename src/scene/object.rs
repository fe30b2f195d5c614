//! The finite surfaces of a scene or of an instanced set, with their materials.
//!
//! What rendering reads of a surface (its geometry, material and modifier chain) is kept in
//! a small [`Object`]; what only messages and `-ae`/`-ai` read (its name, its modifier's
//! name as written, where it was defined) is kept apart in [`Objects`], compactly: the
//! names in one string, each modifier name and file name once. A surface of a large
//! instanced octree costs its geometry and about 30 bytes more.

use std::collections::HashMap;
use std::ops::Deref;
use std::sync::Arc;

use glam::DVec3;

use super::primitive::Location;
use crate::geometry::cone::Cone;
use crate::geometry::plain::{Plain, Slab};
use crate::geometry::polygon::{Polygon, Vertex};
use crate::geometry::ring::Ring;
use crate::geometry::sphere::Sphere;
use crate::geometry::{Surface, SurfaceRef};

/// Index of a material in [`crate::render::world::Scene::materials`] (defined here, below the
/// materials, so that the scene's structures need not know them).
pub type MatId = usize;

/// Index of a modifier in [`crate::render::world::Scene::modifiers`].
pub type ModId = usize;

/// What a modifier name refers to at the point of use (Radiance resolves names to the
/// latest definition before the user).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModRef {
    /// `void`: the end of a chain (no material: the surface is invisible).
    Void,
    /// A material: its index in the scene's materials (a [`MatId`]).
    Material(usize),
    /// A pattern, texture or mixture.
    Modifier(ModId),
}

/// A finite surface with its material: a plain record of 16 bytes ([`Objects`] holds the
/// surfaces by kind; [`Objects::surface`] finds an object's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct Object {
    /// The surface's kind (the top two bits: [`KIND_POLYGON`] …) and its index in the
    /// array of that kind.
    shape: u32,
    /// The material its modifier chain ends in ([`NO_MATERIAL`]: a chain that ends in
    /// `void` (such surfaces are invisible) or a mixture).
    material: u32,
    /// Its modifier, the start of its chain ([`ModRef::encode`]).
    chain: u32,
    _pad: u32,
}

// SAFETY: `#[repr(C)]` of four u32 (no padding, any bits; indices are checked on loading).
unsafe impl Plain for Object {}

/// [`Object`]'s kind of a polygon.
pub const KIND_POLYGON: u32 = 0;
/// [`Object`]'s kind of a sphere or bubble.
pub const KIND_SPHERE: u32 = 1;
/// [`Object`]'s kind of a cone, cup, cylinder or tube.
pub const KIND_CONE: u32 = 2;
/// [`Object`]'s kind of a ring.
pub const KIND_RING: u32 = 3;
/// The most surfaces of one kind a list holds (the index has 30 bits).
pub const MAX_OF_KIND: usize = 1 << 30;
/// [`Object`]'s material for none.
const NO_MATERIAL: u32 = u32::MAX;

impl ModRef {
    /// As one number: `void` is `u32::MAX`, a material its id, a modifier its id with the
    /// top bit set. Ids of 2³¹ − 1 and more have no encoding.
    pub fn encode(self) -> Option<u32> {
        match self {
            ModRef::Void => Some(u32::MAX),
            ModRef::Material(i) => u32::try_from(i).ok().filter(|&i| i < 1 << 31),
            ModRef::Modifier(i) => u32::try_from(i)
                .ok()
                .filter(|&i| i < (1 << 31) - 1)
                .map(|i| i | 1 << 31),
        }
    }

    /// What [`ModRef::encode`] made.
    pub fn decode(c: u32) -> ModRef {
        if c == u32::MAX {
            ModRef::Void
        } else if c & 1 << 31 != 0 {
            ModRef::Modifier((c & !(1 << 31)) as usize)
        } else {
            ModRef::Material(c as usize)
        }
    }
}

impl Object {
    /// The material its modifier chain ends in, or None for a chain that ends in `void` or
    /// a mixture.
    #[inline]
    pub fn material(&self) -> Option<MatId> {
        (self.material != NO_MATERIAL).then_some(self.material as usize)
    }

    /// Its modifier: the start of its chain.
    #[inline]
    pub fn chain(&self) -> ModRef {
        ModRef::decode(self.chain)
    }

    /// The surface's kind ([`KIND_POLYGON`] …).
    #[inline]
    pub fn kind(&self) -> u32 {
        self.shape >> 30
    }

    /// The surface's index among those of its kind.
    #[inline]
    pub fn index(&self) -> usize {
        (self.shape & (MAX_OF_KIND as u32 - 1)) as usize
    }
}

/// A list of objects with their surfaces, names, modifier names and places. Dereferences
/// to the slice of [`Object`]s (indexed as in the BVH). The large arrays are [`Slab`]s: a
/// scene image lends them to every process that maps it.
#[derive(Clone, Debug, Default)]
pub struct Objects {
    pub(crate) list: Slab<Object>,
    /// Polygon records and the pool of their vertices.
    pub(crate) polys: Slab<Polygon>,
    pub(crate) verts: Slab<Vertex>,
    /// The other kinds (few in real scenes).
    pub(crate) spheres: Vec<Sphere>,
    pub(crate) cones: Vec<Cone>,
    pub(crate) rings: Vec<Ring>,
    /// Every name, one after the other (UTF-8).
    pub(crate) names: Slab<u8>,
    /// Where each object's name ends in `names`.
    pub(crate) name_end: Slab<u64>,
    /// Each object's modifier name (an index into `modifiers`).
    pub(crate) modifier: Slab<u32>,
    /// Each object's file (an index into `files`) and line.
    pub(crate) place: Slab<[u32; 2]>,
    /// The distinct modifier names.
    pub(crate) modifiers: Vec<Box<str>>,
    /// The distinct files.
    pub(crate) files: Vec<Arc<str>>,
    /// While objects are added: the index of each modifier name and file.
    pub(crate) modifier_ids: HashMap<Box<str>, u32>,
    pub(crate) file_ids: HashMap<Arc<str>, u32>,
}

impl Deref for Objects {
    type Target = [Object];

    fn deref(&self) -> &[Object] {
        &self.list
    }
}

impl<'a> IntoIterator for &'a Objects {
    type Item = &'a Object;
    type IntoIter = std::slice::Iter<'a, Object>;

    fn into_iter(self) -> Self::IntoIter {
        self.list.iter()
    }
}

/// The index of `key` in `table`, added when new.
fn intern<K, Q>(
    ids: &mut HashMap<K, u32>,
    table: &mut Vec<K>,
    key: &Q,
    make: impl Fn(&Q) -> K,
) -> u32
where
    K: std::borrow::Borrow<Q> + std::hash::Hash + Eq + Clone,
    Q: std::hash::Hash + Eq + ?Sized,
{
    if let Some(&k) = ids.get(key) {
        return k;
    }
    // More than 2³² distinct names cannot occur: a set holds at most 2³² objects.
    let k = u32::try_from(table.len()).unwrap_or(u32::MAX);
    let v = make(key);
    table.push(v.clone());
    ids.insert(v, k);
    k
}

impl Objects {
    /// An empty list with room for `n` objects.
    pub fn with_capacity(n: usize) -> Objects {
        Objects {
            list: Vec::with_capacity(n).into(),
            name_end: Vec::with_capacity(n).into(),
            modifier: Vec::with_capacity(n).into(),
            place: Vec::with_capacity(n).into(),
            ..Objects::default()
        }
    }

    /// Add a surface with its material, its chain, its name, modifier name as written and
    /// place. Errors when a list would hold more than [`MAX_OF_KIND`] surfaces of a kind or
    /// an id has no encoding.
    pub fn push(
        &mut self,
        surface: Surface,
        material: Option<MatId>,
        chain: ModRef,
        name: &str,
        modifier: &str,
        loc: &Location,
    ) -> Result<(), String> {
        let (kind, index) = match surface {
            Surface::Polygon(mut p) => {
                let first = u32::try_from(self.verts.len())
                    .ok()
                    .filter(|f| f.checked_add(p.rec.count).is_some())
                    .ok_or("more than 2^32 polygon vertices in one file")?;
                p.rec.first = first;
                self.verts.with_vec(|v| v.extend_from_slice(&p.verts));
                self.polys.push(p.rec);
                (KIND_POLYGON, self.polys.len())
            }
            Surface::Sphere(s) => {
                self.spheres.push(s);
                (KIND_SPHERE, self.spheres.len())
            }
            Surface::Cone(c) => {
                self.cones.push(c);
                (KIND_CONE, self.cones.len())
            }
            Surface::Ring(r) => {
                self.rings.push(r);
                (KIND_RING, self.rings.len())
            }
        };
        if index > MAX_OF_KIND {
            return Err(format!(
                "more than {MAX_OF_KIND} surfaces of a kind in one file"
            ));
        }
        let material = match material {
            None => NO_MATERIAL,
            Some(m) => u32::try_from(m)
                .ok()
                .filter(|&m| m != NO_MATERIAL)
                .ok_or("too many materials")?,
        };
        let chain = chain.encode().ok_or("too many modifiers")?;
        self.list.push(Object {
            shape: kind << 30 | (index - 1) as u32,
            material,
            chain,
            _pad: 0,
        });
        self.names
            .with_vec(|v| v.extend_from_slice(name.as_bytes()));
        self.name_end.push(self.names.len() as u64);
        let m = intern(
            &mut self.modifier_ids,
            &mut self.modifiers,
            modifier,
            |s: &str| Box::from(s),
        );
        self.modifier.push(m);
        let f = intern(
            &mut self.file_ids,
            &mut self.files,
            &*loc.file,
            |s: &str| Arc::from(s),
        );
        self.place.push([f, loc.line]);
        Ok(())
    }

    /// Object `i`'s surface.
    #[inline(always)]
    pub fn surface(&self, i: usize) -> SurfaceRef<'_> {
        self.shape(&self.list[i])
    }

    /// The nearest intersection of object `i`'s surface with a ray in `(eps, tmax)`
    /// ([`SurfaceRef::intersect`], without making the reference first).
    #[inline]
    pub fn intersect(&self, i: usize, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
        let o = self.list[i];
        let k = o.index();
        match o.kind() {
            KIND_POLYGON => self.polys[k].intersect_in(&self.verts, org, dir, tmax),
            KIND_SPHERE => self.spheres[k].intersect(org, dir, tmax),
            KIND_CONE => self.cones[k].intersect(org, dir, tmax),
            _ => self.rings[k].intersect(org, dir, tmax),
        }
    }

    /// The surface of an object of this list.
    #[inline(always)]
    pub fn shape(&self, o: &Object) -> SurfaceRef<'_> {
        let i = o.index();
        match o.kind() {
            KIND_POLYGON => SurfaceRef::Polygon(self.polys[i].with(&self.verts)),
            KIND_SPHERE => SurfaceRef::Sphere(&self.spheres[i]),
            KIND_CONE => SurfaceRef::Cone(&self.cones[i]),
            _ => SurfaceRef::Ring(&self.rings[i]),
        }
    }

    /// Done adding: free what only adding needs.
    pub fn finish(&mut self) {
        self.modifier_ids = HashMap::new();
        self.file_ids = HashMap::new();
        self.names.with_vec(|v| v.shrink_to_fit());
        self.verts.with_vec(|v| v.shrink_to_fit());
        self.polys.with_vec(|v| v.shrink_to_fit());
    }

    /// Object `i`'s identifier.
    pub fn name(&self, i: usize) -> &str {
        let start = if i == 0 { 0 } else { self.name_end[i - 1] } as usize;
        let end = self.name_end[i] as usize;
        self.names
            .get(start..end)
            .and_then(|b| std::str::from_utf8(b).ok())
            .unwrap_or("")
    }

    /// Object `i`'s modifier name as written.
    pub fn modifier(&self, i: usize) -> &str {
        &self.modifiers[self.modifier[i] as usize]
    }

    /// Where object `i` was defined.
    pub fn loc(&self, i: usize) -> Location {
        let [f, line] = self.place[i];
        Location {
            file: self.files[f as usize].clone(),
            line,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::Sphere;
    use glam::DVec3;

    #[test]
    fn labels_are_kept_apart_and_small() {
        let s = Surface::Sphere(Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
            inward: false,
            eps: 1e-6,
        });
        let mut objs = Objects::with_capacity(3);
        let (a, b) = (Location::new("a.rad", 3), Location::new("b.rad", 9));
        let v = ModRef::Void;
        objs.push(s.clone(), Some(1), v, "ball", "red", &a).unwrap();
        objs.push(s.clone(), None, v, "", "void", &b).unwrap();
        objs.push(s.clone(), Some(2), ModRef::Modifier(7), "ball2", "red", &a)
            .unwrap();
        objs.finish();
        assert_eq!(objs.len(), 3);
        assert_eq!(
            (objs.name(0), objs.name(1), objs.name(2)),
            ("ball", "", "ball2")
        );
        assert_eq!((objs.modifier(0), objs.modifier(1)), ("red", "void"));
        assert_eq!(objs.modifier(2), "red");
        assert_eq!(objs.loc(1), b);
        assert_eq!(objs.loc(2).to_string(), "a.rad:3");
        assert_eq!(objs.modifiers.len(), 2);
        assert_eq!(objs[2].material(), Some(2));
        assert_eq!(objs[1].material(), None);
        assert_eq!(objs[2].chain(), ModRef::Modifier(7));
        assert_eq!(objs[0].chain(), ModRef::Void);
        assert!(matches!(objs.surface(1), SurfaceRef::Sphere(_)));
        assert_eq!(std::mem::size_of::<Object>(), 16);
        for r in [
            ModRef::Void,
            ModRef::Material(0),
            ModRef::Modifier(5),
            ModRef::Material(9),
        ] {
            assert_eq!(ModRef::decode(r.encode().unwrap()), r);
        }
        assert_eq!(ModRef::Material(1 << 31).encode(), None);
    }
}
