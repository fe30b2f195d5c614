//! scene (under construction)
pub mod primitive;
pub use primitive::{Location, Primitive};
