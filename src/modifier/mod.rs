//! Surface modifiers: patterns, textures and mixtures, and the chains that link surfaces
//! through them to their materials.
//!
//! A modifier primitive of a registered type ([`ModifierTypes`]) becomes a
//! [`ModifierDef`]: what it does ([`ModifierKind`]) and the link to its own modifier. The
//! tracer walks a hit surface's chain in Radiance's order over a
//! [`crate::render::shading::ShadingPoint`]: a pattern multiplies its colour, a texture adds
//! to its perturbation, a mixture shades two chains and blends them, a material (after its
//! own chain) shades it. Adding a pattern type is one new file here with a parser and a
//! [`Pattern`] implementation, and one line in [`ModifierTypes::standard`]. Files a
//! modifier reads (fonts, text, data files, pictures) come through
//! [`ModifierLookup::files`]: found along the RAYPATH and read once per scene.

pub mod frame;

use crate::color::Color;
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use glam::DVec3;
use std::collections::HashMap;
use std::fmt::Debug;

pub mod data;
pub mod datapat;
pub mod files;
pub mod font;
pub mod func;
pub mod funcpat;
pub mod picdata;
pub mod text;

pub use files::SceneFiles;

pub use crate::scene::object::{ModId, ModRef};

/// A pattern: a colour that multiplies the shading point's pattern colour.
pub trait Pattern: Send + Sync + Debug {
    /// The colour at `sp`, or None for a computation error at this point (the pattern is
    /// then skipped for this ray, as Radiance does).
    fn colour(&self, sp: &ShadingPoint) -> Option<Color>;

    /// The ray channels the colour is computed from (a mask as
    /// [`frame::PatternFrame::channels_for`] takes), when nothing else of the shading point
    /// can change it: its pure forms' channels (where the machine takes over from them, it
    /// evaluates the same expressions, which read the same channels). None when unknown.
    fn reads(&self) -> Option<u32> {
        None
    }

    /// The pattern as a data pattern, which may compute its colour for several points at
    /// once ([`datapat::DataLanes`]).
    fn as_data(&self) -> Option<&datapat::DataPattern> {
        None
    }
}

/// A texture: a vector added to the shading point's normal perturbation.
pub trait Texture: Send + Sync + Debug {
    /// The perturbation at `sp` (world frame), or None for a computation error.
    fn perturbation(&self, sp: &ShadingPoint) -> Option<DVec3>;
}

/// A mixture's coefficient: how much of the foreground chain a point shows.
pub trait MixCoefficient: Send + Sync + Debug {
    /// The foreground's share at `sp` (clamped to [0, 1] by the tracer), or None for a
    /// computation error (the background is shown).
    fn coefficient(&self, sp: &ShadingPoint) -> Option<f64>;
}

/// What a modifier does.
#[derive(Debug)]
pub enum ModifierKind {
    /// Multiplies the pattern colour.
    Pattern(Box<dyn Pattern>),
    /// Adds to the normal perturbation.
    Texture(Box<dyn Texture>),
    /// Shades `foreground` with weight c and `background` with 1 − c and adds them; a side
    /// that reaches no material lets the ray through.
    Mixture {
        /// The foreground's share.
        coef: Box<dyn MixCoefficient>,
        /// The foreground chain.
        foreground: ModRef,
        /// The background chain.
        background: ModRef,
    },
}

/// A modifier of the scene.
#[derive(Debug)]
pub struct ModifierDef {
    /// What it does (shared by its aliases).
    pub kind: std::sync::Arc<ModifierKind>,
    /// Its own modifier: the next link of the chain.
    pub next: ModRef,
    /// Identifier.
    pub name: String,
    /// A mixture neither side of which reaches a material: it acts as a pattern and
    /// texture (the sides' colours and perturbations blended) and the chain goes on to
    /// its modifier, as Radiance's `raymixture` does. False for everything else.
    pub pattern_like: bool,
}

/// What a modifier's parser may ask of the scene read so far.
pub trait ModifierLookup {
    /// The current definition of a modifier name (`void` → [`ModRef::Void`]), or an error.
    fn modref(&self, name: &str) -> Result<ModRef, String>;

    /// The files modifiers read (fonts, text files, data files, pictures): found along the
    /// RAYPATH the scene was read with, each read once per scene.
    fn files(&self) -> &SceneFiles;
}

/// Parses a modifier primitive of one type into what it does.
pub type ModifierParser = fn(&Primitive, &dyn ModifierLookup) -> Result<ModifierKind, String>;

/// The modifier types a scene reader knows, by primitive type name.
#[derive(Clone, Default)]
pub struct ModifierTypes {
    parsers: HashMap<String, ModifierParser>,
}

impl ModifierTypes {
    /// The types Tessera implements: the text patterns `brighttext` and `colortext` and the
    /// mixture `mixtext` ([`text`]). Radiance's other patterns, textures and mixtures
    /// (`brightfunc`, `colorfunc`, `texfunc`, `mixfunc`, the `*data` and `*pict` types) need
    /// the function language and are not implemented yet (their data files and pictures are
    /// read by [`data`] and [`picdata`]): a scene that uses one is refused with its file,
    /// line and type.
    pub fn standard() -> ModifierTypes {
        ModifierTypes::default()
            .with("brighttext", text::parse_brighttext)
            .with("colortext", text::parse_colortext)
            .with("mixtext", text::parse_mixtext)
            .with("brightfunc", funcpat::parse_brightfunc)
            .with("colorfunc", funcpat::parse_colorfunc)
            .with("texfunc", funcpat::parse_texfunc)
            .with("mixfunc", funcpat::parse_mixfunc)
            .with("brightdata", datapat::parse_brightdata)
            .with("colordata", datapat::parse_colordata)
            .with("colorpict", datapat::parse_colorpict)
            .with("texdata", datapat::parse_texdata)
            .with("mixdata", datapat::parse_mixdata)
            .with("mixpict", datapat::parse_mixpict)
    }

    /// These types and `name`, parsed by `parser` (a type of the same name is replaced).
    pub fn with(mut self, name: &str, parser: ModifierParser) -> ModifierTypes {
        self.parsers.insert(name.to_string(), parser);
        self
    }

    /// The parser of type `name`.
    pub fn get(&self, name: &str) -> Option<ModifierParser> {
        self.parsers.get(name).copied()
    }
}
