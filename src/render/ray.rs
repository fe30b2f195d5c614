//! Rays and hits.

use crate::material::MatId;
pub use crate::scene::sets::{HitRef, NO_INST};
use glam::DVec3;

/// What a ray is for. Radiance's `crtype` bits, reduced to what the shading rules need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// From the eye.
    Primary,
    /// Pure specular reflection (mirror direction).
    Reflected,
    /// Pure specular transmission (straight through or refracted).
    Transmitted,
    /// A sample of a rough specular reflection lobe (sources are invisible to it).
    SpecReflected,
    /// A sample of a rough specular transmission lobe (sources are invisible to it).
    SpecTransmitted,
    /// An indirect (ambient) sample (sources are invisible to it).
    Ambient,
    /// A shadow ray toward a light source.
    Shadow,
}

/// What a ray knows of the cached ambient value whose sampling it belongs to: set on a
/// value's sample rays by the ambient calculation, passed on to the rays they spawn, read by
/// the tracer (specular splits, glows) and direct light (shadow reuse). Outside a value's
/// sampling it is [`SamplePath::NONE`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplePath {
    /// True for a cached ambient value's sample ray and everything it spawns: its result is
    /// averaged with the value's other samples, so specular splits follow one branch
    /// ([`crate::render::trace::Tracer::split`]).
    pub on: bool,
    /// The radius of the sample's footprint per unit distance travelled (the hemisphere cell
    /// it stands for), kept by the rays the sample ray spawns; 0: no footprint.
    pub spread: f64,
    /// The distance from the sample ray's origin to this ray's origin.
    pub reach: f64,
    /// True for a cached value's sample ray when the value samples the scene's glows
    /// explicitly (`Ambient::glow_light`): such a ray does not see their emission. Not passed
    /// on to the rays it spawns.
    pub glow_sampled: bool,
}

impl SamplePath {
    /// Not on a cached value's sample path.
    pub const NONE: SamplePath = SamplePath {
        on: false,
        spread: 0.0,
        reach: 0.0,
        glow_sampled: false,
    };

    /// The path state a ray spawned at distance `t` from this ray's origin inherits.
    pub fn spawned(&self, t: f64) -> SamplePath {
        SamplePath {
            on: self.on,
            spread: self.spread,
            reach: if self.spread > 0.0 {
                self.reach + t
            } else {
                0.0
            },
            glow_sampled: false,
        }
    }
}

/// Up to this many antimatter volumes may contain a ray at once.
pub const MAX_ANTIMATTER: usize = 4;

/// A ray in the scene's relative frame.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin (relative to the scene origin).
    pub org: DVec3,
    /// Unit direction.
    pub dir: DVec3,
    /// Maximum distance (aft clipping plane), `f64::INFINITY` for none.
    pub tmax: f64,
    /// Kind of this ray.
    pub kind: RayKind,
    /// True when this ray or an ancestor is an ambient or specular-sample ray: light sources
    /// are then not seen (direct lighting counts them).
    pub sources_hidden: bool,
    /// Product of the coefficients along the path (Radiance's `rweight`).
    pub weight: f64,
    /// Number of reflections/transmissions so far.
    pub depth: u32,
    /// Ambient bounce level.
    pub amb_level: u32,
    /// Factor a survivor of Russian roulette must multiply its result by.
    pub gain: f64,
    /// The cached ambient value whose sampling this ray belongs to, if any.
    pub sample: SamplePath,
    /// Antimatter materials whose volumes contain the ray origin.
    pub antimatter: [Option<MatId>; MAX_ANTIMATTER],
    /// Length of the path before this ray's origin (its ancestors', from the eye): with the
    /// hit distance, the pattern variable `T`.
    pub prior: f64,
}

impl Ray {
    /// A primary ray.
    pub fn primary(org: DVec3, dir: DVec3, tmax: f64) -> Ray {
        Ray {
            org,
            dir,
            tmax,
            kind: RayKind::Primary,
            sources_hidden: false,
            weight: 1.0,
            depth: 0,
            amb_level: 0,
            gain: 1.0,
            sample: SamplePath::NONE,
            antimatter: [None; MAX_ANTIMATTER],
            prior: 0.0,
        }
    }

    /// A shadow ray (unlimited length).
    pub fn shadow(org: DVec3, dir: DVec3) -> Ray {
        Ray {
            kind: RayKind::Shadow,
            ..Ray::primary(org, dir, f64::INFINITY)
        }
    }
}

impl Hit {
    /// The surface hit.
    #[inline]
    pub fn href(&self) -> HitRef {
        HitRef {
            inst: self.inst,
            obj: self.obj,
        }
    }

    /// True for a surface of the scene itself (not instanced): only those can be light
    /// sources.
    #[inline]
    pub fn is_top(&self) -> bool {
        self.inst == NO_INST
    }
}

/// A ray–surface hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Index of the object in [`crate::render::world::Scene::objects`], or in the set of placement
    /// `inst`.
    pub obj: usize,
    /// The placement of an instanced surface ([`crate::render::world::Scene::placements`]), or
    /// [`NO_INST`] for the scene's own surfaces.
    pub inst: u32,
    /// Distance from the ray origin.
    pub t: f64,
    /// Hit point (relative frame).
    pub point: DVec3,
    /// Unit front-side surface normal (not flipped toward the ray).
    pub normal: DVec3,
    /// True when the ray hit the back side (`dir · normal > 0`).
    pub back: bool,
    /// True for planar surfaces.
    pub flat: bool,
    /// Material used to shade this hit (may differ from the object's for antimatter exits).
    pub material: Option<MatId>,
    /// Antimatter state after this hit (for continuing rays).
    pub antimatter: [Option<MatId>; MAX_ANTIMATTER],
}

/// `Hit::obj` of a point that is no surface of the scene (the ray origin of `ttrace -I`).
pub const NO_OBJECT: usize = usize::MAX;
