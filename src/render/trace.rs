//! The ray tracer: intersection (with antimatter and coincident-surface rules), material
//! dispatch, spawned rays with Radiance's depth and weight limits, shadow rays, ambient.

use super::ray::{Hit, Ray, RayKind, MAX_ANTIMATTER};
use super::sampler::Sampler;
use super::shading::ShadingPoint;
use crate::color::{bright, sanitize, Color};
use crate::light::direct::direct;
use crate::light::source::LightSet;
use crate::material::emitter::EmitterKind;
use crate::material::{MatId, Material};
use crate::options::render::RenderParams;
use crate::render::ray::HitRef;
use crate::render::world::Scene;
use glam::DVec3;

/// Everything a ray needs to be traced.
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Rendering parameters.
    pub params: &'a RenderParams,
    /// Light sources (real and virtual).
    pub lights: &'a LightSet,
    /// The indirect-light calculation (None: constant `-av` ambient only).
    pub ambient: Option<&'a dyn IndirectLight>,
    /// Fill the cache only (the ambient overture): the picture's colour is discarded, so
    /// the indirect-light calculation decides how much direct light eye paths need
    /// ([`IndirectLight::direct_plan`]). Points inside a new value's sampling (level > 0)
    /// are lit as always: the value needs their light.
    pub fill_only: bool,
    /// The session's memo of the cells its frames sample at every pixel (None: computed
    /// for each region rendered).
    pub cells: Option<&'a super::lightcells::CellMemo>,
}

/// How far a shadow ray toward a sample at distance `dist` needs to look: the sample lies on
/// (or, for cylinders, behind) the source surface, so nothing beyond it can matter; the slack
/// covers rounding. Bounding the ray lets the BVH prune everything behind the source.
/// Distant sources (`dist` infinite) keep an unbounded ray. `eps` is the scene's length
/// tolerance.
#[inline]
fn shadow_reach(dist: f64, eps: f64) -> f64 {
    if dist.is_finite() {
        dist * (1.0 + 1e-6) + 16.0 * eps
    } else {
        f64::INFINITY
    }
}

/// How direct light is gathered at a hit ([`IndirectLight::direct_plan`]).
pub enum DirectPlan {
    /// None at all.
    Skip,
    /// A rough estimate: direct light at this ray weight.
    Estimate {
        /// The ray weight to gather at (fewer source partitions, weak sources untested).
        weight: f64,
    },
    /// All of it, reusing shadow rays within a sample's footprint when a query is given.
    Full(Option<crate::light::viscache::VisQuery>),
}

/// The indirect-light calculation a tracer asks for light it does not trace itself (the
/// ambient calculation, `crate::ambient::Ambient`, implements it). Its policies — how a
/// value's sample paths gather direct light, what the overture needs — live behind it.
pub trait IndirectLight: Sync {
    /// Indirect light reflected with coefficient `refl` at `hit` whose ray-facing,
    /// unperturbed normal is `normal`, at a surface that sends light of brightness `other`
    /// besides (direct, specular, emitted).
    fn reflected(
        &self,
        tr: &Tracer,
        ray: &Ray,
        hit: &Hit,
        req: IndirectRequest,
        rng: &mut Sampler,
    ) -> Color;

    /// How direct light is gathered at `hit` of `ray` (`fill_only`: for the overture).
    fn direct_plan(&self, ray: &Ray, hit: &Hit, fill_only: bool) -> DirectPlan;

    /// The table of shadow answers the calculation's threads share
    /// ([`crate::light::viscache`]); None: each thread keeps its own.
    fn shadow_table(&self) -> Option<&crate::light::viscache::VisTable> {
        None
    }

    /// Count `n` shadow rays answered from a footprint's cache instead of traced.
    fn count_reused_shadows(&self, n: u64);
}

/// What a material asks of the indirect light ([`IndirectLight::reflected`]).
#[derive(Clone, Copy, Debug)]
pub struct IndirectRequest {
    /// Reflection coefficient of the indirect light.
    pub refl: Color,
    /// Ray-facing, unperturbed normal.
    pub normal: DVec3,
    /// Brightness of the surface's other light.
    pub other: f64,
}

/// Largest colour component (Radiance's `intens`).
#[inline]
fn intens(c: Color) -> f64 {
    c.max_element()
}

impl<'a> Tracer<'a> {
    /// A tracer over a scene.
    pub fn new(scene: &'a Scene, params: &'a RenderParams, lights: &'a LightSet) -> Tracer<'a> {
        Tracer {
            scene,
            params,
            lights,
            ambient: None,
            fill_only: false,
            cells: None,
        }
    }

    fn is_transparent(&self, m: Option<MatId>) -> bool {
        match m {
            None => true,
            Some(id) => match self.scene.material(id) {
                Material::Normal(n) => n.trans > 0.0,
                Material::Brdf(b) => b.trans > 0.0,
                Material::Brtd(_) => true,
                Material::Ashik(_) => false,
                Material::Glass(_) | Material::Dielectric(_) | Material::Antimatter(_) => true,
                Material::Emitter(e) => matches!(e.kind, EmitterKind::Illum { .. }),
                Material::Mirror(_) => false,
            },
        }
    }

    /// Radiance's rule for coincident surfaces: a material beats none, opaque beats
    /// transparent, front-facing beats back-facing, else the later-defined material wins.
    fn prefer(&self, a: HitRef, b: HitRef, org: DVec3, dir: DVec3, tmax: f64) -> bool {
        let scene = self.scene;
        let (ma, mb) = (scene.ref_material(a), scene.ref_material(b));
        if ma.is_some() != mb.is_some() {
            return ma.is_some();
        }
        let (ta, tb) = (self.is_transparent(ma), self.is_transparent(mb));
        if ta != tb {
            return !ta;
        }
        let (fa, fb) = (
            scene.facing(a, org, dir, tmax),
            scene.facing(b, org, dir, tmax),
        );
        if fa != fb {
            return fa;
        }
        let order = |m: Option<MatId>| m.map(|i| self.scene.materials[i].order).unwrap_or(0);
        order(ma) > order(mb) || (order(ma) == order(mb) && a.key() > b.key())
    }

    fn cuts(&self, am: &[Option<MatId>; MAX_ANTIMATTER], m: Option<MatId>) -> bool {
        let Some(m) = m else { return false };
        am.iter().flatten().any(|&a| match self.scene.material(a) {
            Material::Antimatter(list) => list.contains(&Some(m)),
            _ => false,
        })
    }

    /// Closest hit along a ray, honouring antimatter volumes.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let scene = self.scene;
        let mut org = ray.org;
        let dir = ray.dir;
        let mut travelled = 0.0;
        let mut am = ray.antimatter;
        for _ in 0..256 {
            let tmax = ray.tmax - travelled;
            if tmax <= scene.eps {
                return None;
            }
            let (r, t) = scene.closest(org, dir, tmax, |a, b| self.prefer(a, b, org, dir, tmax))?;
            let (point, normal, flat) = scene.hit_geom(r, org, dir, t);
            let material = scene.ref_material(r);
            let back = normal.dot(dir) > 0.0;
            let mut hit = Hit {
                obj: r.obj,
                inst: r.inst,
                t: travelled + t,
                point,
                normal,
                back,
                flat,
                material,
                antimatter: am,
            };
            let advance = |org: &mut DVec3, travelled: &mut f64| {
                *org = point;
                *travelled += t;
            };
            if self.cuts(&am, material) {
                advance(&mut org, &mut travelled);
                continue;
            }
            if let Some(m) = material {
                if let Material::Antimatter(list) = scene.material(m) {
                    if !back {
                        // Entering the volume.
                        if let Some(slot) = am.iter_mut().find(|s| s.is_none()) {
                            *slot = Some(m);
                        }
                        advance(&mut org, &mut travelled);
                        continue;
                    }
                    // Leaving: if the exit point lies inside a cut object, the exit face is
                    // shaded with the first listed modifier.
                    let was_inside = am.contains(&Some(m));
                    // Rays leaving the exit face go back into the antimatter volume.
                    let inside_state = am;
                    if let Some(slot) = am.iter_mut().find(|s| **s == Some(m)) {
                        *slot = None;
                    }
                    if was_inside {
                        let mut probe = *ray;
                        probe.org = point;
                        probe.tmax = f64::INFINITY;
                        probe.antimatter = am;
                        if let Some(next) = self.intersect(&probe) {
                            if next.back && next.material.is_some() && list.contains(&next.material)
                            {
                                hit.material = list.first().copied().flatten();
                                hit.normal = -normal;
                                hit.back = false;
                                hit.antimatter = inside_state;
                                return Some(hit);
                            }
                        }
                    }
                    advance(&mut org, &mut travelled);
                    continue;
                }
            }
            hit.antimatter = am;
            return Some(hit);
        }
        None
    }

    /// Radiance arriving along a ray.
    pub fn trace(&self, ray: &Ray, rng: &mut Sampler) -> Color {
        self.trace_dist(ray, rng).0
    }

    /// The light of a specular split: a ray per branch `(direction, kind, coefficient)`,
    /// each weighted by its coefficient.
    ///
    /// Below a cached value's sample ray ([`Ray::sample_path`], the sample ray's own split
    /// excepted) one branch is followed instead, chosen with probability in proportion to
    /// its coefficient's brightness and divided by it: the same expectation for one ray per
    /// split instead of a tree of them. A sample ray that enters a glass sphere otherwise
    /// spawns rays at every internal reflection until their weight falls below `-lw`, each
    /// lit where it lands. The added variance is averaged with the value's hundreds of other
    /// samples. The sample ray's own split stays whole: choosing there (a window pane's
    /// reflection against the sky behind it) cost 10–15% more error on the glassy scene for
    /// 4% fewer instructions.
    pub fn split(
        &self,
        ray: &Ray,
        hit: &Hit,
        branches: &[(DVec3, RayKind, Color)],
        rng: &mut Sampler,
    ) -> Color {
        let mut result = Color::ZERO;
        if ray.sample.on && ray.kind != RayKind::Ambient {
            let total: f64 = branches.iter().map(|b| bright(b.2).max(0.0)).sum();
            if !(total > 0.0 && total.is_finite()) {
                return result;
            }
            let mut u = rng.uniform() * total;
            let last = branches.iter().rposition(|b| bright(b.2) > 0.0);
            for (i, &(dir, kind, coef)) in branches.iter().enumerate() {
                let b = bright(coef).max(0.0);
                if b <= 0.0 {
                    continue;
                }
                if u < b || Some(i) == last {
                    let c = coef * (total / b);
                    if let Some(r) = self.spawn(ray, hit, dir, kind, c) {
                        result += c * self.trace(&r, rng);
                    }
                    return result;
                }
                u -= b;
            }
            return result;
        }
        for &(dir, kind, coef) in branches {
            if let Some(r) = self.spawn(ray, hit, dir, kind, coef) {
                result += coef * self.trace(&r, rng);
            }
        }
        result
    }

    /// [`Tracer::trace`] that also returns the distance of the first hit (infinite when the
    /// ray hits nothing), so that the pixel loop need not intersect primary rays twice.
    pub fn trace_dist(&self, ray: &Ray, rng: &mut Sampler) -> (Color, f64) {
        rng.rays += 1;
        let (c, dist) = match self.intersect(ray) {
            Some(hit) => (self.shade_hit(ray, &hit, rng), hit.t),
            None => (self.escaped(ray), f64::INFINITY),
        };
        (sanitize(c * ray.gain), dist)
    }

    /// A ray that left the scene: distant sources and glows.
    fn escaped(&self, ray: &Ray) -> Color {
        if ray.tmax.is_finite() {
            return Color::ZERO;
        }
        let mut fallback = None;
        for d in &self.scene.distant {
            if !d.source.hit_by(ray.dir) {
                continue;
            }
            let Some(m) = d.material else { continue };
            match self.scene.material(m) {
                Material::Emitter(e) => {
                    let glowish =
                        matches!(e.kind, EmitterKind::Glow { .. } | EmitterKind::Illum { .. });
                    let v = self.emitter_value(ray, e, f64::INFINITY);
                    let v = if v == Color::ZERO {
                        v
                    } else {
                        v * self.distant_pattern(ray, d)
                    };
                    if glowish {
                        fallback.get_or_insert(v);
                    } else {
                        return v;
                    }
                }
                _ => continue,
            }
        }
        fallback.unwrap_or(Color::ZERO)
    }

    fn emitter_value(&self, ray: &Ray, e: &crate::material::emitter::Emitter, dist: f64) -> Color {
        let visible = match e.kind {
            EmitterKind::Glow { maxrad } => {
                if ray.sources_hidden {
                    if maxrad > 0.0 {
                        dist > maxrad
                    } else {
                        maxrad == 0.0
                    }
                } else {
                    true
                }
            }
            _ => !ray.sources_hidden,
        };
        if !visible || (!self.params.dv && ray.kind != RayKind::Shadow && e.is_source()) {
            return Color::ZERO;
        }
        e.radiance
    }

    /// Shade a shading point with material `id` (its modifiers applied: see
    /// [`Tracer::shade_material`]).
    pub fn shade(&self, ray: &Ray, sp: &ShadingPoint, id: MatId, rng: &mut Sampler) -> Color {
        let hit = &sp.hit;
        match self.scene.material(id) {
            Material::Normal(n) => n.shade(self, ray, sp, rng),
            Material::Ashik(a) => a.shade(self, ray, sp, rng),
            Material::Brdf(b) => b.shade(self, ray, sp, rng),
            Material::Brtd(b) => b.shade(self, ray, sp, rng),
            Material::Glass(g) => g.shade(self, ray, sp, rng),
            Material::Dielectric(d) => d.shade(self, ray, sp, rng),
            Material::Mirror(mi) => {
                // Rays descended from an ambient sample see the mirror itself, whatever its
                // alternate material (measured with rpict: the indirect light off a mirror with
                // an alternate is that of the bare mirror); all other rays see the alternate.
                if ray.amb_level > 0 {
                    mi.shade(self, ray, sp, rng)
                } else if mi.alternate_void {
                    self.pass_through(ray, hit, rng)
                } else if let Some(alt) = mi.alternate {
                    self.shade_material(ray, sp, alt, rng)
                } else {
                    mi.shade(self, ray, sp, rng)
                }
            }
            Material::Emitter(e) => match e.kind {
                EmitterKind::Illum { alternate } => match alternate {
                    Some(alt) => self.shade_material(ray, sp, alt, rng),
                    None => self.pass_through(ray, hit, rng),
                },
                _ => {
                    // Flat sources emit from their front side only.
                    if hit.back && hit.flat {
                        return Color::ZERO;
                    }
                    // A glow source the value samples explicitly is not seen by its rays.
                    if ray.sample.glow_sampled
                        && hit.is_top()
                        && self.lights.is_sampled_glow(hit.obj)
                    {
                        return Color::ZERO;
                    }
                    let spot = e.spot_factor(hit.point, ray.org);
                    self.emitter_value(ray, e, hit.t) * spot * sp.pcol
                }
            },
            Material::Antimatter(_) => self.pass_through(ray, hit, rng),
        }
    }

    /// Continue a ray unchanged beyond a hit (invisible surfaces, back faces with `-bv-`).
    pub fn pass_through(&self, ray: &Ray, hit: &Hit, rng: &mut Sampler) -> Color {
        let mut r = *ray;
        r.org = hit.point;
        r.tmax = ray.tmax - hit.t;
        r.antimatter = hit.antimatter;
        r.prior += hit.t;
        r.gain = 1.0;
        if r.tmax <= self.scene.eps {
            return Color::ZERO;
        }
        // Not a reflection, but bound endless chains of invisible surfaces all the same.
        r.depth += 1;
        if r.depth > 1000 {
            return Color::ZERO;
        }
        self.trace(&r, rng)
    }

    /// A child ray from `hit` in direction `dir` carrying coefficient `coef`, or None when
    /// Radiance's limits (`-lr`, `-lw`) stop it. Russian roulette applies when `-lr <= 0`.
    pub fn spawn(
        &self,
        parent: &Ray,
        hit: &Hit,
        dir: DVec3,
        kind: RayKind,
        coef: Color,
    ) -> Option<Ray> {
        let weight = parent.weight * intens(coef);
        let depth = parent.depth + 1;
        let lr = self.params.lr;
        let lw = self.params.lw;
        let mut gain = 1.0;
        if lr > 0 {
            if depth as i64 > lr as i64 || weight < lw {
                return None;
            }
        } else {
            if lr < 0 && depth as i64 > (-lr) as i64 {
                return None;
            }
            if weight < lw {
                // Deterministic roulette from the direction bits keeps this per-pixel exact.
                let bits = dir.x.to_bits()
                    ^ dir.y.to_bits().rotate_left(21)
                    ^ dir.z.to_bits().rotate_left(42);
                let u =
                    (bits.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64;
                if weight <= 0.0 || u >= weight / lw {
                    return None;
                }
                gain = lw / weight;
            }
        }
        Some(Ray {
            org: hit.point,
            dir,
            tmax: f64::INFINITY,
            kind,
            sources_hidden: parent.sources_hidden
                || matches!(
                    kind,
                    RayKind::SpecReflected | RayKind::SpecTransmitted | RayKind::Ambient
                ),
            weight: weight * gain,
            depth,
            amb_level: parent.amb_level,
            gain,
            sample: parent.sample.spawned(hit.t),
            antimatter: hit.antimatter,
            prior: parent.prior + hit.t,
        })
    }

    /// Direct light at a hit for a material coefficient function. `known` is the light the
    /// surface sends besides its direct light that is known before the shadow tests (its
    /// specular rays, the constant `-av` ambient): the adaptive shadow test (`-dt`) stops
    /// relative to it plus the direct light found so far, as rpict's does.
    pub fn direct(
        &self,
        ray: &Ray,
        hit: &Hit,
        (_normal, known): (DVec3, Color),
        coef: &dyn Fn(DVec3, f64) -> Color,
        rng: &mut Sampler,
    ) -> Color {
        let plan = match self.ambient {
            Some(a) => a.direct_plan(ray, hit, self.fill_only),
            // The colour of a fill-only pass is discarded; without an indirect-light
            // calculation nothing else needs the light.
            None if self.fill_only && ray.amb_level == 0 => DirectPlan::Skip,
            None => DirectPlan::Full(None),
        };
        match plan {
            DirectPlan::Skip => Color::ZERO,
            DirectPlan::Estimate { weight } => direct(self, (weight, known), hit, coef, rng, None),
            DirectPlan::Full(vis) => {
                direct(self, (ray.weight, known), hit, coef, rng, vis.as_ref())
            }
        }
    }

    /// The ambient light reflected with coefficient `refl` when it is the constant `-av`
    /// (no indirect-light calculation), known before any ray is traced; else zero.
    pub fn constant_ambient(&self, refl: Color) -> Color {
        match self.ambient {
            Some(_) => Color::ZERO,
            None => {
                let av = self.params.av;
                refl * DVec3::new(av[0], av[1], av[2])
            }
        }
    }

    /// Use an indirect-light calculation (the irradiance cache).
    pub fn with_ambient<A: IndirectLight>(mut self, ambient: Option<&'a A>) -> Tracer<'a> {
        self.ambient = ambient.map(|a| a as &dyn IndirectLight);
        self
    }

    /// Indirect (ambient) light reflected with coefficient `refl` about `normal` (facing the
    /// ray): the irradiance cache when `-ab` > 0, else the constant `-av` radiance.
    pub fn ambient(
        &self,
        ray: &Ray,
        hit: &Hit,
        refl: Color,
        normal: DVec3,
        other: f64,
        rng: &mut Sampler,
    ) -> Color {
        match self.ambient {
            Some(a) => {
                let req = IndirectRequest {
                    refl,
                    normal,
                    other,
                };
                a.reflected(self, ray, hit, req, rng)
            }
            None => {
                let av = self.params.av;
                refl * DVec3::new(av[0], av[1], av[2])
            }
        }
    }

    /// Transmission of a shadow ray from `org` in direction `dir` toward source `si` at
    /// distance `dist` (infinite for distant sources). The source's patterns are not in it:
    /// they belong to the sample's radiance ([`Tracer::sample_pattern`]).
    pub fn shadow(
        &self,
        (org, dir, dist): (DVec3, DVec3, f64),
        si: usize,
        antimatter: [Option<MatId>; MAX_ANTIMATTER],
        rng: &mut Sampler,
    ) -> Color {
        let src = &self.lights.sources[si];
        if let Some(relay) = &src.relay {
            // First leg: to the mirror, which must be hit from its front.
            let (t, hit) = self.shadow_walk(org, dir, dist, antimatter, rng, |h| {
                h.is_top() && h.obj == relay.obj
            });
            let Some(hit) = hit else {
                return Color::ZERO;
            };
            let travelled = (hit.point - org).length();
            if hit.back || travelled > dist {
                return Color::ZERO;
            }
            let rdir = crate::material::reflect(dir, relay.normal);
            let rest = if dist.is_finite() {
                dist - travelled
            } else {
                dist
            };
            // The mirrors' reflectances are already in the virtual source's radiance (its
            // potential), so the transmission here is that of the legs only. The next leg
            // leads to the source this one reflects: real, or the image in another mirror.
            let next = self.shadow((hit.point, rdir, rest), relay.parent, hit.antimatter, rng);
            return t * next;
        }
        self.shadow_real(org, dir, dist, si, antimatter, rng)
    }

    fn shadow_real(
        &self,
        org: DVec3,
        dir: DVec3,
        dist: f64,
        si: usize,
        am: [Option<MatId>; MAX_ANTIMATTER],
        rng: &mut Sampler,
    ) -> Color {
        let src = &self.lights.sources[si];
        let (t, hit) = self.shadow_walk(org, dir, dist, am, rng, |h| {
            h.is_top() && src.obj == Some(h.obj)
        });
        // The transmission only: the source's patterns toward the shading point are in the
        // sample's potential ([`Tracer::sample_pattern`]).
        match hit {
            // Flat sources emit from their front only.
            Some(h) if h.back && h.flat => Color::ZERO,
            Some(_) => t,
            // Left the scene: reached a distant source, missed a local one.
            None if src.distant.is_some() => t,
            None => Color::ZERO,
        }
    }

    /// True when an opaque surface blocks the segment from `org` along the unit `dir` within
    /// `dist` (transparent surfaces are crossed as by shadow rays): the ambient cache's
    /// light-leak test.
    pub fn occluded(
        &self,
        org: DVec3,
        dir: DVec3,
        dist: f64,
        am: [Option<MatId>; MAX_ANTIMATTER],
        rng: &mut Sampler,
    ) -> bool {
        let (t, _) = self.shadow_walk(org, dir, dist, am, rng, |_| false);
        t.max_element() <= 0.0
    }

    /// Walk a shadow ray through transparent surfaces (multiplying their transmission) until
    /// `is_target` accepts a hit. Returns the transmission so far and that hit; or the
    /// transmission and None when the ray leaves the scene (zero when blocked first).
    fn shadow_walk(
        &self,
        org: DVec3,
        dir: DVec3,
        dist: f64,
        am: [Option<MatId>; MAX_ANTIMATTER],
        rng: &mut Sampler,
        is_target: impl Fn(&Hit) -> bool,
    ) -> (Color, Option<Hit>) {
        let mut ray = Ray::shadow(org, dir);
        ray.antimatter = am;
        ray.tmax = shadow_reach(dist, self.scene.eps);
        let mut t = Color::ONE;
        for _ in 0..64 {
            rng.rays += 1;
            let Some(hit) = self.intersect(&ray) else {
                return (t, None);
            };
            if is_target(&hit) {
                return (t, Some(hit));
            }
            let tr = self.shadow_through(&ray, &hit);
            if tr.max_element() <= 0.0 {
                return (Color::ZERO, None);
            }
            t *= tr;
            ray.org = hit.point;
            ray.antimatter = hit.antimatter;
            ray.tmax -= hit.t;
            ray.prior += hit.t;
        }
        (Color::ZERO, None)
    }

    /// What a shadow ray keeps when it crosses a (non-target) shading point of material `m`
    /// (its modifiers applied).
    pub(super) fn shadow_transmission(&self, sp: &ShadingPoint, m: MatId) -> Color {
        match self.scene.material(m) {
            Material::Normal(n) => n.shadow_transmission(sp),
            Material::Brtd(b) => b.shadow_transmission(sp),
            Material::Glass(g) => g.shadow_transmission(sp),
            Material::Antimatter(_) => Color::ONE,
            Material::Mirror(mi) if mi.alternate_void => Color::ONE,
            Material::Mirror(mi) => match mi.alternate {
                Some(alt) => self.shadow_material(sp, alt),
                None => Color::ZERO,
            },
            _ => Color::ZERO,
        }
    }

    /// Whether [`Tracer::shadow_transmission`] of material `m` is zero whatever the
    /// shading point (a mirror's answer is its alternate's).
    pub(super) fn never_transmits(&self, mut m: MatId) -> bool {
        // Alternates name earlier materials, so this never loops; bound it anyway.
        for _ in 0..=self.scene.materials.len() {
            match self.scene.material(m) {
                Material::Normal(n) => return n.never_transmits(),
                Material::Brtd(_) | Material::Glass(_) | Material::Antimatter(_) => return false,
                Material::Mirror(mi) if mi.alternate_void => return false,
                Material::Mirror(mi) => match mi.alternate {
                    Some(alt) => m = alt,
                    None => return true,
                },
                _ => return true,
            }
        }
        false
    }
}
