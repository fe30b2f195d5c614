//! Virtual sources: images of light sources in flat mirrors, over `-dr` generations.
//!
//! Generation 1 reflects every real source in every flat mirror it lies in front of;
//! generation `g` reflects each source of generation `g − 1` in every other flat mirror that
//! its image lies in front of and that can see it through its own mirrors (the image of a
//! source in mirror A, reflected in mirror B, is the light that travels source → A → B →
//! receiver). A source is never reflected twice in a row in the same mirror (that is the
//! source itself).
//!
//! Sampling a virtual source from a point `p` folds `p` through the source's mirrors (outer
//! mirror first) into the real source's frame, samples the real source from there, maps the
//! directions back and keeps only the samples whose unfolded path crosses every mirror of the
//! chain in turn, from its front ([`LightSet::relay_path`]): the others cannot be relayed.
//! The shadow ray of a sample follows the same path (`Tracer::shadow`).
//!
//! Whether a mirror can see a virtual source at all (Radiance's pretest, `-dp`) is decided
//! geometrically from points spread over the mirror toward points of the source's image;
//! occlusion is left to the shadow rays.

use super::source::{LightSet, Relay, Source, SourceShape};
use crate::color::Color;
use crate::geometry::SurfaceRef;
use crate::material::{reflect, Material};
use crate::render::world::Scene;
use crate::FTINY;
use glam::DVec3;

/// A leg of a path toward a source: its start, unit direction and length.
type Leg = (DVec3, DVec3, f64);

/// Most virtual sources a scene may have (all generations together); beyond it the later
/// generations are cut short, with a warning.
pub const MAX_VIRTUAL: usize = 4096;

/// A flat mirror that can relay sources.
struct MirrorPlane {
    obj: usize,
    normal: DVec3,
    offset: f64,
    color: Color,
    /// Points spread over the mirror (its visibility pretest).
    probes: Vec<DVec3>,
}

/// Reflect point `x` in the plane `normal · x = offset`.
#[inline]
fn mirror_point(x: DVec3, normal: DVec3, offset: f64) -> DVec3 {
    x - 2.0 * (normal.dot(x) - offset) * normal
}

/// Points spread over a flat mirror: its centre, and for each vertex (at most 64 of them)
/// points 2%, 35% and 70% of the way from the vertex to the centre.
fn probes(s: SurfaceRef) -> Vec<DVec3> {
    let (center, rim): (DVec3, Vec<DVec3>) = match s {
        SurfaceRef::Polygon(p) => (p.centroid(), p.verts().take(64).collect()),
        SurfaceRef::Ring(r) => {
            let u = crate::geometry::any_perpendicular(r.normal);
            let v = r.normal.cross(u);
            let rim = (0..16)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 16.0;
                    r.center + (u * a.cos() + v * a.sin()) * r.r1
                })
                .collect();
            (r.center, rim)
        }
        _ => return Vec::new(),
    };
    let mut out = vec![center];
    for v in rim {
        for f in [0.02, 0.35, 0.7] {
            out.push(v + (center - v) * f);
        }
    }
    out
}

/// Points of a real source's shape its image is tested toward, or None for a distant source.
fn key_points(shape: &SourceShape) -> Option<Vec<DVec3>> {
    Some(match *shape {
        SourceShape::Polygon { corner, eu, ev, .. } => vec![
            corner + (eu + ev) * 0.5,
            corner,
            corner + eu,
            corner + ev,
            corner + eu + ev,
        ],
        SourceShape::Ring {
            center, normal, r1, ..
        } => {
            let u = crate::geometry::any_perpendicular(normal);
            let v = normal.cross(u);
            vec![
                center,
                center + u * r1,
                center - u * r1,
                center + v * r1,
                center - v * r1,
            ]
        }
        SourceShape::Sphere { center, radius } => vec![
            center,
            center + DVec3::X * radius,
            center - DVec3::X * radius,
            center + DVec3::Y * radius,
            center - DVec3::Y * radius,
            center + DVec3::Z * radius,
            center - DVec3::Z * radius,
        ],
        SourceShape::Cylinder { p0, p1, .. } => vec![(p0 + p1) * 0.5, p0, p1],
        SourceShape::Distant { .. } => return None,
    })
}

impl LightSet {
    /// The mirrors source `si` is relayed by, from the one nearest the receiver to the one
    /// nearest the real source (none for a real source).
    pub fn relays(&self, si: usize) -> impl Iterator<Item = &Relay> + '_ {
        let mut s = si;
        std::iter::from_fn(move || {
            let r = self.sources[s].relay.as_ref()?;
            s = r.parent;
            Some(r)
        })
    }

    /// Point `p` folded through the mirrors of source `si` into the real source's frame, or
    /// None when it lies behind one of them (within `eps`).
    pub fn fold(&self, si: usize, p: DVec3, eps: f64) -> Option<DVec3> {
        let mut q = p;
        for r in self.relays(si) {
            let h = r.normal.dot(q) - r.offset;
            if h <= eps {
                return None;
            }
            q -= 2.0 * h * r.normal;
        }
        Some(q)
    }

    /// A direction of the real source's frame mapped into the receiver's frame of source
    /// `si` (the inverse of [`LightSet::fold`]'s reflections).
    pub fn unfold_dir(&self, si: usize, d: DVec3) -> DVec3 {
        match &self.sources[si].relay {
            Some(r) => reflect(self.unfold_dir(r.parent, d), r.normal),
            None => d,
        }
    }

    /// A point of the real source's frame mapped to its image as source `si`.
    fn image_point(&self, si: usize, x: DVec3) -> DVec3 {
        match &self.sources[si].relay {
            Some(r) => mirror_point(self.image_point(r.parent, x), r.normal, r.offset),
            None => x,
        }
    }

    /// The path from `p` toward source `si` along `dir` over the (unfolded) length `dist`:
    /// it must cross each of the source's mirrors in turn, from the front, within its
    /// length. Returns the last leg (its start, direction and remaining length), the one that
    /// reaches the real source; `(p, dir, dist)` for a real source; None when a mirror is
    /// missed.
    #[inline]
    pub fn relay_path(
        &self,
        scene: &Scene,
        si: usize,
        p: DVec3,
        dir: DVec3,
        dist: f64,
    ) -> Option<(DVec3, DVec3, f64)> {
        // Inline for the common case, a real source (every shading point asks, per sample).
        match self.sources[si].relay {
            None => Some((p, dir, dist)),
            Some(_) => self.mirror_path(scene, si, (p, dir, dist)),
        }
    }

    /// [`LightSet::relay_path`] through the mirrors of virtual source `si`, from the leg
    /// `(start, direction, length)`.
    fn mirror_path(&self, scene: &Scene, si: usize, leg: Leg) -> Option<Leg> {
        let (mut o, mut d, mut rest) = leg;
        for r in self.relays(si) {
            if d.dot(r.normal) >= -FTINY {
                return None;
            }
            let lim = if rest.is_finite() { rest } else { f64::MAX };
            let t = scene.objects.surface(r.obj).intersect(o, d, lim)?;
            o += d * t;
            d = reflect(d, r.normal);
            if rest.is_finite() {
                rest -= t;
            }
        }
        Some((o, d, rest))
    }

    /// True when some point of `mirror` sees source `si` through its mirrors (the real
    /// source's key points, or its direction for a distant one), the light arriving at the
    /// mirror's front.
    fn sees(&self, scene: &Scene, mirror: &MirrorPlane, si: usize) -> bool {
        let real = self.sources[si].relay.as_ref().map_or(si, |r| r.real);
        let targets = key_points(&self.sources[real].shape).map(|pts| {
            pts.into_iter()
                .map(|x| self.image_point(si, x))
                .collect::<Vec<_>>()
        });
        for &x in &mirror.probes {
            match (&targets, &self.sources[real].shape) {
                (Some(pts), _) => {
                    for &y in pts {
                        let w = y - x;
                        let dist = w.length();
                        if dist <= scene.eps {
                            continue;
                        }
                        let d = w / dist;
                        if d.dot(mirror.normal) > FTINY
                            && self.relay_path(scene, si, x, d, dist).is_some()
                        {
                            return true;
                        }
                    }
                }
                (None, SourceShape::Distant { dir, .. }) => {
                    let d = self.unfold_dir(si, *dir);
                    if d.dot(mirror.normal) > FTINY
                        && self.relay_path(scene, si, x, d, f64::INFINITY).is_some()
                    {
                        return true;
                    }
                }
                _ => {}
            }
        }
        false
    }

    /// Add the virtual sources of `generations` generations (`-dr`).
    pub(super) fn add_virtual(&mut self, scene: &Scene, generations: i32) {
        let mut mirrors = Vec::new();
        for (mi, o) in scene.objects.iter().enumerate() {
            let Some(m) = o.material() else { continue };
            let Material::Mirror(mirror) = scene.material(m) else {
                continue;
            };
            let (normal, point) = match scene.objects.shape(o) {
                SurfaceRef::Polygon(p) if p.area > 0.0 => (p.normal, p.centroid()),
                SurfaceRef::Ring(r) => (r.normal, r.center),
                _ => {
                    self.warnings.push(format!(
                        "{}: mirror '{}' is not flat and relays no light sources",
                        scene.objects.loc(mi),
                        scene.objects.name(mi)
                    ));
                    continue;
                }
            };
            mirrors.push(MirrorPlane {
                obj: mi,
                normal,
                offset: normal.dot(point),
                color: mirror.color,
                probes: probes(scene.objects.shape(o)),
            });
        }
        if mirrors.is_empty() {
            return;
        }
        let nreal = self.sources.len();
        let mut prev = 0..nreal;
        let mut added = 0usize;
        for generation in 1..=generations.max(0) as u32 {
            let start = self.sources.len();
            for mirror in &mirrors {
                for si in prev.clone() {
                    let s = &self.sources[si];
                    if s.obj == Some(mirror.obj)
                        || s.relay.as_ref().is_some_and(|r| r.obj == mirror.obj)
                    {
                        continue;
                    }
                    // Only sources (images) in front of the mirror are reflected.
                    let in_front = match s.shape {
                        SourceShape::Distant { dir, .. } => {
                            self.unfold_dir(si, dir).dot(mirror.normal) > FTINY
                        }
                        _ => mirror.normal.dot(s.center) - mirror.offset > scene.eps,
                    };
                    // Generation 1 is checked sample by sample; later ones need a mirror
                    // that sees the image through its mirrors.
                    if !in_front || (generation > 1 && !self.sees(scene, mirror, si)) {
                        continue;
                    }
                    if added == MAX_VIRTUAL {
                        self.warnings.push(format!(
                            "-dr {generations}: more than {MAX_VIRTUAL} virtual sources; \
                             generation {generation} is incomplete and later ones are left out"
                        ));
                        return;
                    }
                    let real = s.relay.as_ref().map_or(si, |r| r.real);
                    let mut e = s.emitter.clone();
                    e.radiance *= mirror.color;
                    let source = Source {
                        obj: s.obj,
                        distant: s.distant,
                        shape: s.shape.clone(),
                        emitter: e,
                        center: mirror_point(s.center, mirror.normal, mirror.offset),
                        relay: Some(Relay {
                            obj: mirror.obj,
                            normal: mirror.normal,
                            offset: mirror.offset,
                            parent: si,
                            real,
                            generation,
                        }),
                    };
                    self.sources.push(source);
                    added += 1;
                }
            }
            prev = start..self.sources.len();
            if prev.is_empty() {
                break;
            }
        }
    }
}
