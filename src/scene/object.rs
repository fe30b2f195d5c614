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

use super::primitive::Location;
use crate::geometry::Surface;

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

/// A finite surface with its material.
#[derive(Clone, Debug)]
pub struct Object {
    /// Geometry (relative to [`super::Scene::origin`]).
    pub surface: Surface,
    /// The material its modifier chain ends in, or None for a chain that ends in `void`
    /// (such surfaces are invisible) or a mixture.
    pub material: Option<MatId>,
    /// Its modifier: the start of its chain.
    pub chain: ModRef,
}

/// A list of objects with their names, modifier names and places. Dereferences to the
/// slice of [`Object`]s (indexed as in the BVH).
#[derive(Clone, Debug, Default)]
pub struct Objects {
    list: Vec<Object>,
    /// Every name, one after the other.
    names: String,
    /// Where each object's name ends in `names`.
    name_end: Vec<usize>,
    /// Each object's modifier name (an index into `modifiers`).
    modifier: Vec<u32>,
    /// Each object's file (an index into `files`) and line.
    place: Vec<(u32, u32)>,
    /// The distinct modifier names.
    modifiers: Vec<Box<str>>,
    /// The distinct files.
    files: Vec<Arc<str>>,
    /// While objects are added: the index of each modifier name and file.
    modifier_ids: HashMap<Box<str>, u32>,
    file_ids: HashMap<Arc<str>, u32>,
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
            list: Vec::with_capacity(n),
            name_end: Vec::with_capacity(n),
            modifier: Vec::with_capacity(n),
            place: Vec::with_capacity(n),
            ..Objects::default()
        }
    }

    /// Add an object with its name, modifier name as written and place.
    pub fn push(&mut self, object: Object, name: &str, modifier: &str, loc: &Location) {
        self.list.push(object);
        self.names.push_str(name);
        self.name_end.push(self.names.len());
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
        self.place.push((f, loc.line));
    }

    /// Done adding: free what only adding needs.
    pub fn finish(&mut self) {
        self.modifier_ids = HashMap::new();
        self.file_ids = HashMap::new();
        self.names.shrink_to_fit();
    }

    /// Object `i`'s identifier.
    pub fn name(&self, i: usize) -> &str {
        let start = if i == 0 { 0 } else { self.name_end[i - 1] };
        self.names.get(start..self.name_end[i]).unwrap_or("")
    }

    /// Object `i`'s modifier name as written.
    pub fn modifier(&self, i: usize) -> &str {
        &self.modifiers[self.modifier[i] as usize]
    }

    /// Where object `i` was defined.
    pub fn loc(&self, i: usize) -> Location {
        let (f, line) = self.place[i];
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
        let o = |m| Object {
            surface: s.clone(),
            material: m,
            chain: ModRef::Void,
        };
        objs.push(o(Some(1)), "ball", "red", &a);
        objs.push(o(None), "", "void", &b);
        objs.push(o(Some(2)), "ball2", "red", &a);
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
        assert_eq!(objs[2].material, Some(2));
        // What rendering reads stays small (the large surfaces are boxed).
        assert!(
            std::mem::size_of::<Object>() <= 96,
            "{}",
            std::mem::size_of::<Object>()
        );
    }
}
