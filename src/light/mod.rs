//! Light sources and direct lighting.
//!
//! [`source`] turns every surface whose material is `light`, `glow` (positive radius),
//! `illum` or `spotlight` into a [`source::Source`] (plus virtual sources reflected in
//! mirrors), and samples them by partitions (`-ds`, `-dj`). [`direct`] estimates the direct
//! light at a shading point with adaptive shadow testing (`-dt`, `-dc`).

pub mod direct;
pub mod source;

pub use source::{LightSet, Source, SourceSample};
