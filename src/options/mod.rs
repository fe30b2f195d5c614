//! Radiance's option language and Tessera's options, in three kinds:
//!
//! - [`words`]: the syntax shared by every parser (tpict's command line, view files and view
//!   lines, job manifests' options): word splitting, `@file`/`$VAR` expansion, booleans,
//!   numbers, and [`OptError`].
//! - [`render`]: [`RenderParams`], what changes the light transport (`-d* -s* -l* -a* -i -u
//!   -bv -m*` and the ambient settings [`crate::ambient::settings::AmbientSettings`]).
//! - [`schedule`]: `-ax`/`-axg`, ambient accuracy that varies from frame to frame.
//! - [`picture`]: [`PictureParams`], how a picture is made of that light (view, resolution,
//!   `-p*`, the overture).
//! - [`run`]: [`RunParams`], how one tpict process runs (threads, output, `-S`, `-e`, `-t`,
//!   `--stats`, the ambient files `-af`/`--amb-log`).
//! - [`rpict`]: tpict's (rpict's) command line, [`RpictOptions`] = the three kinds plus the
//!   scene files; [`defaults`]: the `-defaults` text.
//!
//! Job manifests keep render and picture parameters; run parameters belong to one process.

pub mod defaults;
pub mod picture;
pub mod render;
pub mod rpict;
pub mod rtrace;
pub mod run;
pub mod schedule;
pub mod words;

pub use defaults::defaults_text;
pub use picture::PictureParams;
pub use render::RenderParams;
pub use rpict::{parse_rpict_args, to_args, Command, RpictOptions};
pub use run::RunParams;
pub use words::{bool_option, expand_args, parse_f64, split_words, OptError};
