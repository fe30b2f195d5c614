//! A scene's geometry, below its materials: surfaces in f64 relative to the scene origin,
//! distant sources, the sets its instances place and the BVH over them. The renderable scene
//! ([`crate::render::world::Scene`]) adds the materials, modifiers and functions that the
//! surfaces' ids refer to; rays are traced here ([`super::instance`]).

use std::path::PathBuf;

use glam::DVec3;

use super::object::{MatId, ModRef, Objects};
use super::primitive::Primitive;
use super::sets::{ObjectSet, Placement};
use crate::geometry::bvh::Bvh;
use crate::geometry::source::DistantSource;
use crate::FTINY;

/// Surface primitive types (finite ones go into the BVH; `source` is distant).
pub const SURFACE_TYPES: &[&str] = &[
    "polygon", "sphere", "bubble", "cone", "cup", "cylinder", "tube", "ring", "source",
];

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

/// Whether a surface primitive has the argument counts its type needs (a wrong count is a
/// fatal error; degenerate geometry with the right counts is dropped with a warning, as
/// oconv does).
pub(crate) fn surface_counts_ok(p: &Primitive) -> bool {
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

/// A scene's geometry (what tracing needs; [`crate::render::world::Scene`] dereferences to
/// it).
pub struct SceneGeometry {
    /// Scene origin: every coordinate in geometry is relative to it.
    pub origin: DVec3,
    /// Size of the scene's bounding cube (like the octree cube of oconv).
    pub size: f64,
    /// The scene's length tolerance ([`length_tolerance`]): the minimum hit distance, the
    /// polygons' edge tolerance and the slack of shadow rays.
    pub eps: f64,
    /// Finite surfaces, indexed as in the BVH.
    pub objects: Objects,
    /// Distant sources.
    pub distant: Vec<DistantObject>,
    /// Acceleration structure over `objects`.
    pub bvh: Bvh,
    /// Warnings (degenerate geometry dropped, zero areas), each naming file:line.
    pub warnings: Vec<String>,
    /// The files its primitives read by relative name (data files, pictures, fonts, text
    /// and function files, instanced octrees and meshes and the scene files of unfrozen
    /// ones): the name as given and the path found along the RAYPATH.
    pub inputs: Vec<(String, PathBuf)>,
    /// The octrees and meshes its instances place, each read and built once.
    pub sets: Vec<ObjectSet>,
    /// Every placement of a set (nested instances flattened; [`super::instance`]).
    pub placements: Vec<Placement>,
}
