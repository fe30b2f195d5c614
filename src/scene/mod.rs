//! The scene language: lexer → primitives (with inline commands, `xform` and the built-in
//! generators of [`gen`]) → the scene's geometry ([`world`]), under its materials
//! ([`crate::render::world`]).
pub mod primitive;
pub use primitive::{Location, Primitive};
pub mod error;
pub mod gen;
pub mod image;
/// The built-in genbox (now in [`gen::genbox`]).
pub use gen::genbox;
pub mod lexer;
pub mod reader;
pub mod transform;
pub mod xform;
pub use error::SceneError;
pub use octree::read_scene_files;
pub use reader::{parse_scene_text, ReadOptions};
pub use transform::{parse_transform, Transform};
pub mod binio;
pub mod instance;
pub mod obj;
pub mod object;
pub mod octree;
pub mod rtm;
pub mod sets;
pub mod world;
pub use world::SceneGeometry;
