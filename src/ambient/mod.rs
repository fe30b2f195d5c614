//! Indirect irradiance ("ambient") values and their stores.
//!
//! - [`compute`]: the calculation's facade ([`Ambient`]): set-up, a request for indirect
//!   light (interpolate, else compute and cache a new value), `-av`/`-aw`, the share reach.
//! - [`lookup`]: interpolation of cached values (Radiance's acceptance tests and weights).
//! - [`sample`]: a new value (hemisphere sampling, super-sampling, radii, reach).
//! - [`radii`]: a new value's frame, radii, gradients and reach.
//! - [`hemisphere`]: statistics of a value's cells (outlier limit, variances, gradients).
//! - [`corral`]: the light-leak flags and test.
//! - [`hessian`]: the irradiance Hessian that gives a new value its anisotropic radii.
//! - [`settings`]: Tessera's own settings of the calculation (options beside rpict's).
//! - [`cache`]: the in-memory cache shared by render threads.
//! - [`AmbRecord`]: one cached irradiance value, as Radiance's AMBVAL plus a stable id.
//! - [`radfile`]: Radiance's own ambient file format (`-af`, read by `lookamb`).
//! - [`log`]: Tessera's append-only, CRC-framed log for sharing values between processes.

pub mod cache;
pub mod compute;
pub mod corral;
pub mod fingerprint;
pub mod hemisphere;
pub mod hessian;
pub mod log;
pub mod lookup;
pub mod radfile;
pub mod radii;
pub mod sample;
pub mod settings;
pub mod sharded;
pub mod striped;

pub use compute::Ambient;

use glam::DVec3;

/// A stable identity for an ambient value: the process (or worker) that made it and a
/// sequence number within that origin, so that merged stores can deduplicate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ValueId {
    /// Identifier of the producing process/worker (e.g. a hash of host, pid and start time).
    pub origin: u64,
    /// Sequence number within the origin.
    pub seq: u64,
}

/// One indirect irradiance value (Radiance's AMBVAL fields plus an id).
/// Positions and directions are in absolute scene coordinates (not relative to a scene
/// origin), so stores are independent of how a renderer chose its origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbRecord {
    /// Stable identity (0/0 for values read from Radiance files).
    pub id: ValueId,
    /// Position.
    pub pos: DVec3,
    /// Unit surface normal (unperturbed, facing the ray side).
    pub ndir: DVec3,
    /// Unit first principal direction (tangent); the second is `ndir × udir`.
    pub udir: DVec3,
    /// Ambient bounce level of the parent ray.
    pub lvl: u8,
    /// Weight of the parent ray (0 < weight <= 1).
    pub weight: f32,
    /// Anisotropic radii along u and v (rad[0] <= rad[1]).
    pub rad: [f32; 2],
    /// Positional gradient along u and v.
    pub gpos: [f32; 2],
    /// Rotational gradient about u and v.
    pub gdir: [f32; 2],
    /// 32 azimuth-sector light-leak flags.
    pub corral: u32,
    /// Irradiance-like value (RGB).
    pub val: [f32; 3],
    /// Interpolation reach in units of `-aa` (≥ 1; Tessera's log only, 1 for Radiance files).
    pub reach: f32,
    /// Share reach (≥ 1; Tessera's log only, 1 for Radiance files and log versions 1–2).
    pub share: f32,
}

impl AmbRecord {
    /// Radiance's `ambvalOK` checks and more, for every record read from any store (a job
    /// directory is shared by many users' processes): finite values of sane magnitude
    /// (below 1e10), unit directions, 0 < weight <= 1, 0 < rad0 <= rad1 (+tolerance),
    /// non-negative values, finite reach and share of at least 1. The radii's bound by the
    /// scene's size is the cache's check ([`cache::AmbientCache::insert`]).
    pub fn is_valid(&self) -> bool {
        let fin = |v: f64| v.is_finite() && v.abs() < 1e10;
        let fin32 = |v: f32| v.is_finite() && v.abs() < 1e10;
        let unit = |d: DVec3| d.is_finite() && (d.length_squared() - 1.0).abs() < 1e-2;
        self.pos.to_array().iter().all(|&v| fin(v))
            && unit(self.ndir)
            && unit(self.udir)
            && self.weight > 0.0
            && self.weight <= 1.0
            && self.rad[0] > 0.0
            && self.rad[0] <= self.rad[1] + 1e-6
            && self.rad.iter().all(|&v| fin32(v))
            && self.gpos.iter().all(|&v| fin32(v))
            && self.gdir.iter().all(|&v| fin32(v))
            && self.val.iter().all(|&v| fin32(v) && v >= 0.0)
            && self.reach.is_finite()
            && self.reach >= 1.0
            && self.share.is_finite()
            && self.share >= 1.0
    }
}
