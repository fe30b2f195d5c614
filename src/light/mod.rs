//! Light sources and direct lighting.
//!
//! [`source`] turns every surface whose material is `light`, `glow` (positive radius),
//! `illum` or `spotlight` into a [`source::Source`] (plus virtual sources reflected in
//! mirrors), and samples them by partitions (`-ds`, `-dj`). [`direct`] estimates the direct
//! light at a shading point with adaptive shadow testing (`-dt`, `-dc`); [`viscache`] reuses
//! the shadow rays of ambient samples' hits within their footprints; [`emission`] reads
//! each source's chain of patterns once.

pub mod direct;
pub mod emission;
pub mod source;
pub mod virtuals;
pub mod viscache;

pub use source::{LightSet, Source, SourceSample};
