//! A finite surface of a scene or of an instanced set, with its material.

use super::primitive::Location;
use crate::geometry::Surface;
use crate::material::MatId;
use crate::modifier::ModRef;

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
    /// Identifier.
    pub name: String,
    /// Modifier name as written.
    pub modifier: String,
    /// Where it was defined.
    pub loc: Location,
}
