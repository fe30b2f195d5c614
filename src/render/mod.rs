//! The renderer: rays, per-pixel deterministic sampling, the tracer and the pixel loop.

pub mod chain;
pub mod lightcells;
pub mod picture;
pub mod ray;
pub mod sampler;
pub mod schedule;
pub mod shading;
pub mod splitting;
pub mod srcdraw;
pub mod trace;
pub mod world;

pub use picture::{cell_size, render_region, render_region_rows, FrameSetup, RenderProgress};
pub use trace::Tracer;
