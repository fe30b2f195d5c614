//! Light-source records and their sampling.

use crate::color::Color;
use crate::geometry::any_perpendicular;
use crate::geometry::cone::ConeKind;
use crate::geometry::SurfaceRef;
use crate::material::emitter::{Emitter, EmitterKind};
use crate::material::Material;
use crate::render::sampler::Sampler;
use crate::render::world::Scene;
use crate::FTINY;
use glam::DVec3;
use std::f64::consts::PI;

/// Shape of a source, as used for sampling.
#[derive(Clone, Debug)]
pub enum SourceShape {
    /// A planar polygon, sampled over its bounding rectangle in the plane
    /// (`center + u·[u0,u1] + v·[v0,v1]`); samples outside the polygon are dropped.
    Polygon {
        /// Unit front normal.
        normal: DVec3,
        /// Rectangle origin.
        corner: DVec3,
        /// Rectangle edge vectors.
        eu: DVec3,
        /// Rectangle edge vectors.
        ev: DVec3,
        /// What sampling reads at every shading point, computed once ([`PolygonRect`]).
        rect: PolygonRect,
    },
    /// A disk or annulus.
    Ring {
        /// Centre.
        center: DVec3,
        /// Unit front normal.
        normal: DVec3,
        /// Inner radius.
        r0: f64,
        /// Outer radius.
        r1: f64,
    },
    /// A sphere (sampled by the cone of directions it subtends).
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// An open cylinder (sampled over its area).
    Cylinder {
        /// Axis start.
        p0: DVec3,
        /// Axis end.
        p1: DVec3,
        /// Radius.
        radius: f64,
    },
    /// A distant source.
    Distant {
        /// Unit direction toward the source.
        dir: DVec3,
        /// Half angular diameter in radians.
        half_angle: f64,
        /// Its cosine (the sampled cone's edge).
        cos_max: f64,
        /// Solid angle.
        solid_angle: f64,
    },
}

/// A mirror that relays a source (virtual source).
#[derive(Clone, Debug)]
pub struct Relay {
    /// Mirror object.
    pub obj: usize,
    /// Unit front normal of the mirror plane.
    pub normal: DVec3,
    /// Plane offset: `normal · x = offset` on the mirror.
    pub offset: f64,
    /// Index of the source it reflects (real, or virtual of the generation before).
    pub parent: usize,
    /// Index of the real source at the end of the chain.
    pub real: usize,
    /// Its generation (1: the image of a real source).
    pub generation: u32,
}

/// A light source.
#[derive(Clone, Debug)]
pub struct Source {
    /// The emitting object (None for distant sources).
    pub obj: Option<usize>,
    /// Index of the distant source (for distant ones).
    pub distant: Option<usize>,
    /// Sampling shape.
    pub shape: SourceShape,
    /// The emitting material.
    pub emitter: Emitter,
    /// Centre (relative frame), for proximity and spot tests.
    pub center: DVec3,
    /// Set for virtual sources (reflections of `real` in a mirror).
    pub relay: Option<Relay>,
}

/// A polygon source's rectangle as sampling reads it, computed once when the source is
/// collected (the same operations in the same order as at each shading point before, so
/// every sample is bit-identical).
#[derive(Clone, Copy, Debug)]
pub struct PolygonRect {
    /// The rectangle's centre, `corner + (eu + ev) · 0.5`.
    mid: DVec3,
    /// `|eu|` and `|ev|`.
    lu: f64,
    lv: f64,
    /// `|eu × ev|`.
    area: f64,
    /// The polygon is a quadrilateral with its rectangle's area: it IS the rectangle, and
    /// every sample lies on it (no per-sample inside test).
    fills: bool,
}

impl PolygonRect {
    /// `poly`: the polygon's vertex count and area.
    fn new(corner: DVec3, eu: DVec3, ev: DVec3, poly: (usize, f64)) -> Self {
        let area = eu.cross(ev).length();
        PolygonRect {
            mid: corner + (eu + ev) * 0.5,
            lu: eu.length(),
            lv: ev.length(),
            area,
            fills: poly.0 == 4 && (poly.1 - area).abs() <= 1e-9 * poly.1,
        }
    }
}

/// Partitions of a flat source `size` across (its larger side) whose centre lies at
/// squared distance `d2` (at least `eps²`): `(1, 1)` when certainly `size / d ≤ thr`
/// ([`partitions`]' test, `d = max(√d2, eps)`), decided without the square root; else
/// `partitions(su / d, sv / d)` computed as it always was. The margin of 10⁻⁹ is far
/// above the rounding of either test, so the answer is the one [`partitions`] gives.
#[inline]
fn flat_partitions(
    (su, sv): (f64, f64),
    d2: f64,
    eps: f64,
    (ds, weight): (f64, f64),
) -> (usize, usize) {
    if ds > 0.0 {
        let thr = ds / weight.clamp(1e-3, 1.0);
        let size = su.max(sv);
        let bound = thr * thr * d2.max(eps * eps) * (1.0 - 1e-9);
        if size.is_finite() && bound.is_finite() && size * size <= bound {
            return (1, 1);
        }
    }
    let d = d2.sqrt().max(eps);
    partitions(su / d, sv / d, ds, weight)
}

/// How finely a source is partitioned and jittered from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct Partition {
    /// The weight of the ray at the shading point (a lighter ray takes fewer partitions).
    pub weight: f64,
    /// `-ds`: the partition size relative to the distance.
    pub ds: f64,
    /// `-dj`: the jitter within a partition (0: its centre).
    pub dj: f64,
}

/// One sample of a source seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct SourceSample {
    /// Index of the source.
    pub src: usize,
    /// Unit direction from the shading point toward the sample.
    pub dir: DVec3,
    /// Distance to the sample point (`f64::INFINITY` for distant sources).
    pub dist: f64,
    /// Solid angle the sample stands for.
    pub omega: f64,
    /// Radiance arriving from the sample if unoccluded (includes mirror reflectance).
    pub radiance: Color,
}

/// All sources of a scene.
#[derive(Clone, Debug, Default)]
pub struct LightSet {
    /// Real sources first, then virtual ones.
    pub sources: Vec<Source>,
    /// Warnings produced while collecting sources.
    pub warnings: Vec<String>,
    /// [`LightSet::sampled_glows`]: (source index, radius, object), by object.
    glows: Vec<(usize, f64, usize)>,
    /// Each source's emission plan ([`super::emission`]), made at its first use.
    pub(super) emission: Vec<std::sync::OnceLock<super::emission::EmissionPlan>>,
}

/// Map the unit square to the unit disk, area-preserving (Shirley & Chiu 1997).
pub fn square_to_disk(a: f64, b: f64) -> (f64, f64) {
    let (x, y) = (2.0 * a - 1.0, 2.0 * b - 1.0);
    if x == 0.0 && y == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if x * x > y * y {
        (x, (PI / 4.0) * (y / x))
    } else {
        (y, PI / 2.0 - (PI / 4.0) * (x / y))
    };
    (r * phi.cos(), r * phi.sin())
}

/// Per-axis partition counts for a source of angular sizes (a, b) radians: each axis is halved
/// until its part subtends at most `-ds` (scaled up for low-weight rays), as Radiance's counts
/// show (size/distance 0.4 at `-ds .25` gives 2×2 partitions, 0.8 gives 4×4), limited to 64.
fn partitions(a: f64, b: f64, ds: f64, weight: f64) -> (usize, usize) {
    if ds <= 0.0 {
        return (1, 1);
    }
    let thr = ds / weight.clamp(1e-3, 1.0);
    let halvings = |size: f64| -> usize {
        let mut n = 1usize;
        while size / n as f64 > thr && n < 64 {
            n *= 2;
        }
        n
    };
    let (mut na, mut nb) = (halvings(a), halvings(b));
    while na * nb > 64 {
        if na >= nb {
            na /= 2;
        } else {
            nb /= 2;
        }
    }
    (na, nb)
}

/// Position within stratum `i` of `n`, with jitter fraction `dj`.
#[inline]
fn strat(i: usize, n: usize, dj: f64, rng: &mut Sampler) -> f64 {
    let j = if dj > 0.0 {
        dj * (rng.uniform() - 0.5)
    } else {
        0.0
    };
    ((i as f64 + 0.5 + j) / n as f64).clamp(0.0, 1.0 - 1e-12)
}

impl LightSet {
    /// Collect the sources of a scene; `relays` is the number of virtual-source generations
    /// (`-dr`; see [`super::virtuals`]).
    pub fn collect(scene: &Scene, relays: i32) -> LightSet {
        let mut set = LightSet::default();
        for (i, o) in scene.objects.iter().enumerate() {
            let Some(m) = o.material() else { continue };
            let Material::Emitter(e) = scene.material(m) else {
                continue;
            };
            if !e.is_source() {
                continue;
            }
            let shape = match scene.objects.shape(o) {
                SurfaceRef::Polygon(p) => {
                    if p.area <= 0.0 {
                        continue;
                    }
                    let n = p.normal;
                    let eu0 = p
                        .verts()
                        .zip(p.verts().skip(1))
                        .map(|(a, b)| b - a)
                        .find(|d| d.length_squared() > scene.eps * scene.eps)
                        .unwrap_or_else(|| any_perpendicular(n));
                    let u = (eu0 - eu0.dot(n) * n).normalize();
                    let v = n.cross(u);
                    let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
                    let centroid = p.centroid();
                    for q in p.verts() {
                        let d = q - centroid;
                        u0 = u0.min(d.dot(u));
                        u1 = u1.max(d.dot(u));
                        v0 = v0.min(d.dot(v));
                        v1 = v1.max(d.dot(v));
                    }
                    let (corner, eu, ev) =
                        (centroid + u * u0 + v * v0, u * (u1 - u0), v * (v1 - v0));
                    SourceShape::Polygon {
                        normal: n,
                        corner,
                        eu,
                        ev,
                        rect: PolygonRect::new(corner, eu, ev, (p.len(), p.area)),
                    }
                }
                SurfaceRef::Ring(r) => SourceShape::Ring {
                    center: r.center,
                    normal: r.normal,
                    r0: r.r0,
                    r1: r.r1,
                },
                SurfaceRef::Sphere(s) => SourceShape::Sphere {
                    center: s.center,
                    radius: s.radius,
                },
                SurfaceRef::Cone(c) if c.kind == ConeKind::Cylinder => SourceShape::Cylinder {
                    p0: c.p0,
                    p1: c.p1,
                    radius: c.r0,
                },
                SurfaceRef::Cone(_) => {
                    set.warnings.push(format!(
                        "{}: cones, cups and tubes cannot be light sources; '{}' only glows when seen",
                        scene.objects.loc(i),
                        scene.objects.name(i)
                    ));
                    continue;
                }
            };
            let center = shape_center(&shape);
            set.sources.push(Source {
                obj: Some(i),
                distant: None,
                shape,
                emitter: e.clone(),
                center,
                relay: None,
            });
        }
        for (i, d) in scene.distant.iter().enumerate() {
            let Some(m) = d.material else { continue };
            let Material::Emitter(e) = scene.material(m) else {
                continue;
            };
            if !e.is_source() {
                continue;
            }
            set.sources.push(Source {
                obj: None,
                distant: Some(i),
                shape: SourceShape::Distant {
                    dir: d.source.dir,
                    half_angle: (d.source.angle_deg * 0.5).to_radians(),
                    cos_max: (d.source.angle_deg * 0.5).to_radians().cos(),
                    solid_angle: d.source.solid_angle,
                },
                emitter: e.clone(),
                center: DVec3::ZERO,
                relay: None,
            });
        }
        if relays > 0 {
            set.add_virtual(scene, relays);
        }
        set.glows = set
            .sources
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match (&s.emitter.kind, s.obj) {
                (&EmitterKind::Glow { maxrad }, Some(obj))
                    if maxrad > 0.0 && s.relay.is_none() && s.distant.is_none() =>
                {
                    Some((i, maxrad, obj))
                }
                _ => None,
            })
            .collect();
        set.glows.sort_by_key(|g| g.2);
        set.plan_slots();
        set
    }

    /// The local, real glow sources with a radius of influence (`glow` with radius > 0):
    /// beyond that radius they light a point only through its ambient (indirect) light, and a
    /// cached value samples them explicitly there (`Ambient::glow_light`).
    pub fn sampled_glows(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.glows.iter().map(|&(i, r, _)| (i, r))
    }

    /// True when object `obj` is one of [`LightSet::sampled_glows`].
    pub fn is_sampled_glow(&self, obj: usize) -> bool {
        self.glows.binary_search_by_key(&obj, |g| g.2).is_ok()
    }

    /// Append the samples of source `si` seen from point `p` (relative frame) to `out`,
    /// partitioned as `how` says. `scene` is used to drop polygon samples outside the
    /// polygon.
    pub fn sample(
        &self,
        scene: &Scene,
        (si, p): (usize, DVec3),
        how: Partition,
        rng: &mut Sampler,
        out: &mut Vec<SourceSample>,
    ) {
        self.sample_within(scene, (si, p), how, rng, out, true)
    }

    /// [`LightSet::sample`] of every source in order: the same samples, with the real
    /// polygon sources (the common luminaires) sampled inline, one after another.
    pub fn sample_all(
        &self,
        scene: &Scene,
        p: DVec3,
        how: Partition,
        rng: &mut Sampler,
        out: &mut Vec<SourceSample>,
    ) {
        for (si, src) in self.sources.iter().enumerate() {
            let plain = src.relay.is_none()
                && !matches!(src.emitter.kind, EmitterKind::Glow { .. })
                && matches!(src.shape, SourceShape::Polygon { .. });
            if plain {
                sample_polygon(scene, (si, src), (src.center, p), how, rng, out);
            } else {
                self.sample(scene, (si, p), how, rng, out);
            }
        }
    }

    /// [`LightSet::sample`] of a glow from any distance (ray weight 1, full jitter): its
    /// radius of influence is ignored (each sample's `dist` tells the caller how far its
    /// point is).
    pub fn sample_glow(
        &self,
        scene: &Scene,
        (si, p): (usize, DVec3),
        ds: f64,
        rng: &mut Sampler,
        out: &mut Vec<SourceSample>,
    ) {
        let how = Partition {
            weight: 1.0,
            ds,
            dj: 1.0,
        };
        self.sample_within(scene, (si, p), how, rng, out, false)
    }

    fn sample_within(
        &self,
        scene: &Scene,
        (si, p): (usize, DVec3),
        how: Partition,
        rng: &mut Sampler,
        out: &mut Vec<SourceSample>,
        glow_radius: bool,
    ) {
        let Partition { weight, ds, dj } = how;
        let src = &self.sources[si];
        // Virtual sources: sample the real source from the point folded through the
        // mirrors, then map the directions back.
        let (q, real_center) = match &src.relay {
            Some(r) => match self.fold(si, p, scene.eps) {
                Some(q) => (q, self.sources[r.real].center),
                None => return,
            },
            None => (p, src.center),
        };
        if let EmitterKind::Glow { maxrad } = src.emitter.kind {
            // A virtual source's centre is the mirrored one: the distance is the path's length.
            if glow_radius && (p - src.center).length() > maxrad {
                return;
            }
        }
        let start = out.len();
        let mut push = |dir: DVec3, dist: f64, omega: f64, _at: DVec3| {
            push_sample((si, src), (real_center, q), (dir, dist, omega), out);
        };
        match &src.shape {
            SourceShape::Polygon { .. } => {
                sample_polygon(scene, (si, src), (real_center, q), how, rng, out);
            }
            SourceShape::Ring {
                center,
                normal,
                r0,
                r1,
            } => {
                let d2 = (*center - q).length_squared();
                let size = 2.0 * r1;
                let (nr, nphi) = flat_partitions((size, size), d2, scene.eps, (ds, weight));
                let u = any_perpendicular(*normal);
                let v = normal.cross(u);
                let cell = PI * (r1 * r1 - r0 * r0) / (nr * nphi) as f64;
                for i in 0..nr {
                    for j in 0..nphi {
                        // Concentric map: one partition aims at the centre, like Radiance.
                        let (x, y) = square_to_disk(strat(i, nr, dj, rng), strat(j, nphi, dj, rng));
                        let rho2 = x * x + y * y;
                        let r = (r0 * r0 + rho2 * (r1 * r1 - r0 * r0)).sqrt();
                        let (c, sn) = if rho2 > 0.0 {
                            let rho = rho2.sqrt();
                            (x / rho, y / rho)
                        } else {
                            (1.0, 0.0)
                        };
                        let s = *center + u * (r * c) + v * (r * sn);
                        let Some((dir, dist, cos_s)) = toward_front(q, s, *normal, scene.eps)
                        else {
                            continue;
                        };
                        push(dir, dist, cell * cos_s / (dist * dist), s);
                    }
                }
            }
            SourceShape::Sphere { center, radius } => {
                let w = *center - q;
                let d = w.length();
                if d <= *radius * (1.0 + 1e-9) {
                    return;
                }
                let axis = w / d;
                let sin_max = radius / d;
                let cos_max = (1.0 - sin_max * sin_max).max(0.0).sqrt();
                // Radiance never partitions spherical sources (measured with rpict -dt 0).
                let (na, nb) = (1, 1);
                let total = 2.0 * PI * (1.0 - cos_max);
                let omega = total / (na * nb) as f64;
                for i in 0..na {
                    for j in 0..nb {
                        let dir =
                            cone_dir(axis, cos_max, strat(i, na, dj, rng), strat(j, nb, dj, rng));
                        let dist = sphere_dist(q, dir, *center, *radius).unwrap_or(d);
                        push(dir, dist, omega, q + dir * dist);
                    }
                }
            }
            SourceShape::Cylinder { p0, p1, radius } => {
                // Seen from q, a cylinder projects to a rectangle of length |axis| and width
                // 2r lying in the plane through its axis that faces q; sample that rectangle
                // and weight each cell by the cylinder's projected area toward the sample.
                let axis = *p1 - *p0;
                let len = axis.length();
                let a = axis / len;
                let c = (*p0 + *p1) * 0.5;
                let w = c - q;
                let wperp = w - a * w.dot(a);
                if wperp.length() <= *radius {
                    return;
                }
                let b = a.cross(wperp).normalize();
                let d = w.length().max(scene.eps);
                let (na, nb) = partitions(len / d, 2.0 * radius / d, ds, weight);
                let cell = 2.0 * radius * len / (na * nb) as f64;
                for i in 0..na {
                    for j in 0..nb {
                        let t = strat(i, na, dj, rng);
                        let u = strat(j, nb, dj, rng) - 0.5;
                        let s = *p0 + axis * t + b * (2.0 * radius * u);
                        let v = s - q;
                        let dist = v.length();
                        if dist <= scene.eps {
                            continue;
                        }
                        let dir = v / dist;
                        let proj = (1.0 - dir.dot(a).powi(2)).max(0.0).sqrt();
                        push(dir, dist, cell * proj / (dist * dist), s);
                    }
                }
            }
            SourceShape::Distant {
                dir,
                half_angle,
                cos_max,
                solid_angle,
            } => {
                // Radiance never partitions distant sources (measured with rpict -dt 0).
                let (na, nb) = (1, 1);
                let cos_max = *cos_max;
                let omega = solid_angle / (na * nb) as f64;
                for i in 0..na {
                    for j in 0..nb {
                        let d = if *half_angle <= 0.0 {
                            *dir
                        } else {
                            cone_dir(*dir, cos_max, strat(i, na, dj, rng), strat(j, nb, dj, rng))
                        };
                        push(d, f64::INFINITY, omega, q + d * 1e10);
                    }
                }
            }
        }
        if src.relay.is_some() {
            // Map the directions back, and keep only the samples whose path crosses every
            // mirror of the chain: the others cannot be relayed, whatever else is in the
            // way, and would otherwise reach the adaptive shadow test's untested estimate.
            let mut kept = start;
            for i in start..out.len() {
                let dir = self.unfold_dir(si, out[i].dir);
                if self.relay_path(scene, si, p, dir, out[i].dist).is_some() {
                    out[i].dir = dir;
                    out.swap(kept, i);
                    kept += 1;
                }
            }
            out.truncate(kept);
        }
    }
}

/// Append a sample of source `si` toward `dir` (from `q`; `real_center` is the real
/// source's centre) unless its solid angle or direction is unusable or a spotlight's cone
/// leaves `q` out.
#[inline(always)]
fn push_sample(
    (si, src): (usize, &Source),
    (real_center, q): (DVec3, DVec3),
    (dir, dist, mut omega): (DVec3, f64, f64),
    out: &mut Vec<SourceSample>,
) {
    if omega.is_nan() || omega <= 0.0 || !dir.is_finite() {
        return;
    }
    let spot = src.emitter.spot_factor(real_center, q);
    let focal = src.emitter.focal_distance();
    if focal > 0.0 && dist.is_finite() {
        // A spotlight's area is seen as if from its focal point behind the source.
        omega *= (dist / (dist + focal)).powi(2);
    }
    if spot <= 0.0 {
        return;
    }
    out.push(SourceSample {
        src: si,
        dir,
        dist,
        omega,
        radiance: src.emitter.radiance * spot,
    });
}

/// The samples of polygon source `si` seen from `q` ([`LightSet::sample`]'s polygons; also
/// taken inline for every real polygon source by [`LightSet::sample_all`]).
#[inline(always)]
fn sample_polygon(
    scene: &Scene,
    (si, src): (usize, &Source),
    (real_center, q): (DVec3, DVec3),
    how: Partition,
    rng: &mut Sampler,
    out: &mut Vec<SourceSample>,
) {
    let SourceShape::Polygon {
        normal,
        corner,
        eu,
        ev,
        rect,
    } = &src.shape
    else {
        return;
    };
    let Partition { weight, ds, dj } = how;
    let d2 = (rect.mid - q).length_squared();
    let (nu, nv) = flat_partitions((rect.lu, rect.lv), d2, scene.eps, (ds, weight));
    let cell = rect.area / (nu * nv) as f64;
    // A polygon that fills its rectangle needs no per-sample inside test.
    let obj = match rect.fills {
        true => None,
        false => src.obj.map(|i| scene.objects.surface(i)),
    };
    for i in 0..nu {
        for j in 0..nv {
            let s = *corner + *eu * strat(i, nu, dj, rng) + *ev * strat(j, nv, dj, rng);
            let Some((dir, dist, cos_s)) = toward_front(q, s, *normal, scene.eps) else {
                continue;
            };
            // Keep only aim points that lie on the polygon.
            if let Some(surf) = obj {
                match surf.intersect(q, dir, dist * (1.0 + 1e-9) + scene.eps) {
                    Some(t) if (t - dist).abs() <= 1e-7 * dist + scene.eps => {}
                    _ => continue,
                }
            }
            let omega = cell * cos_s / (dist * dist);
            push_sample((si, src), (real_center, q), (dir, dist, omega), out);
        }
    }
}

/// Direction and distance from `q` to a point `s` of a flat emitter with front normal
/// `normal`, and the cosine at the emitter; None when `s` is within `eps` of `q` or seen
/// from behind.
#[inline]
fn toward_front(q: DVec3, s: DVec3, normal: DVec3, eps: f64) -> Option<(DVec3, f64, f64)> {
    let w = s - q;
    let dist = w.length();
    if dist <= eps {
        return None;
    }
    let dir = w / dist;
    let cos_s = -dir.dot(normal);
    (cos_s > FTINY).then_some((dir, dist, cos_s))
}

/// Centre of a source shape.
fn shape_center(s: &SourceShape) -> DVec3 {
    match s {
        SourceShape::Polygon { corner, eu, ev, .. } => *corner + (*eu + *ev) * 0.5,
        SourceShape::Ring { center, .. } | SourceShape::Sphere { center, .. } => *center,
        SourceShape::Cylinder { p0, p1, .. } => (*p0 + *p1) * 0.5,
        SourceShape::Distant { .. } => DVec3::ZERO,
    }
}

/// A direction inside the cone around `axis` with `cos θ >= cos_max`, uniform in solid angle
/// for uniform (a, b).
pub fn cone_dir(axis: DVec3, cos_max: f64, a: f64, b: f64) -> DVec3 {
    let (x, y) = square_to_disk(a, b);
    let r2 = x * x + y * y;
    if r2 == 0.0 {
        // The centre (every unjittered sample of an unpartitioned source): the axis.
        return (axis + DVec3::ZERO).normalize();
    }
    let cos_t = 1.0 - r2 * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (cphi, sphi) = if r2 > 0.0 {
        let r = r2.sqrt();
        (x / r, y / r)
    } else {
        (1.0, 0.0)
    };
    let u = any_perpendicular(axis);
    let v = axis.cross(u);
    (axis * cos_t + u * (sin_t * cphi) + v * (sin_t * sphi)).normalize()
}

/// Distance from `q` along `dir` to the sphere, if it is hit.
fn sphere_dist(q: DVec3, dir: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = q - c;
    let b = oc.dot(dir);
    let cc = oc.dot(oc) - r * r;
    let disc = b * b - cc;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 0.0).then_some(t)
}

#[cfg(test)]
#[path = "source_tests.rs"]
mod tests;
