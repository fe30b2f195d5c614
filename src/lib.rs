//! Tessera: a Radiance-compatible renderer (`tpict`) and batch toolkit.
//!
//! The pipeline, in the order a render runs through it:
//! - [`options`]: Radiance's own option language (`-ab 2 -vp x y z -i+`, `@file`), shared by
//!   `tpict`, view files and job manifests; render, picture and run parameters.
//! - [`view`]: view types, the view frame and the pixel ↔ ray mapping.
//! - [`scene`]: the scene language (lexer → primitives → scene), inline commands, `xform`,
//!   `genbox`.
//! - [`geometry`]: one file per surface kind, plus the BVH wrapper (obvhs).
//! - [`cal`]: Radiance's function language (`.cal` files and the expressions of patterns,
//!   textures, mixtures and procedural materials), compiled once and evaluated per ray.
//! - [`material`] and [`modifier`]: materials, and the patterns, textures and mixtures that
//!   modify them (the chain the tracer walks over a shading point).
//! - [`light`]: light sources and direct lighting.
//! - [`ambient`]: indirect light: the irradiance cache with gradients, its settings and its
//!   stores (Radiance's ambient files, Tessera's append-only logs).
//! - [`render`]: the ray tracer, shading points and modifier chains, per-pixel sampling and
//!   the pixel loop.
//! - [`session`]: one render session (scene, lights, threads, ambient calculation and its
//!   stores), used by `tpict` and `tpiece` alike.
//! - [`image`]: pictures in memory and the `hdr`, `exr` and `png` formats.
//! - [`tpict`]: the rpict-compatible driver behind the `tpict` binary.
//! - [`runinfo`]: what every tool shares about the running program (software name,
//!   threads, CPU time, frame names).
//! - [`rif`]: `rad` input files (`.rif`) and the rpict options rad derives from them.
//! - [`job`]: the batch toolkit's job directory: plan, workers, merge, assembly, status.

pub mod ambient;
pub mod cal;
pub mod color;
pub mod fault;
pub mod geometry;
pub mod hash;
pub mod image;
pub mod job;
pub mod light;
pub mod material;
pub mod modifier;
pub mod options;
pub mod prefetch;
pub mod render;
pub mod rif;
pub mod runinfo;
pub mod safefile;
pub mod scene;
pub mod session;
pub mod tpict;
pub mod ttrace;
pub mod view;
pub mod zeroed;

/// Radiance's intersection tolerance (`FTINY` in a double build).
pub const FTINY: f64 = 1e-6;
/// Radiance's "infinite" distance (`FHUGE`).
pub const FHUGE: f64 = 1e10;
