//! Modifier chains at a hit, in Radiance's order: the tracer walks from the hit surface's
//! modifier over its patterns and textures (which change the [`ShadingPoint`]) to a
//! material, which first applies its own chain and then shades; a mixture shades both of
//! its chains and blends them. Shadow rays crossing a surface walk the same chain for the
//! transmission they keep.

use super::ray::{Hit, HitRef, Ray, NO_INST};
use super::sampler::Sampler;
use super::shading::ShadingPoint;
use super::trace::Tracer;
use crate::cal::LANES;
use crate::color::{sanitize, Color};
use crate::geometry::SurfaceRef;
use crate::light::emission::EmissionPlan;
use crate::light::SourceSample;
use crate::material::MatId;
use crate::modifier::datapat::{DataLanes, DataPattern};
use crate::modifier::frame::ALONG_RAY;
use crate::modifier::{MixCoefficient, ModRef, ModifierKind};
use crate::scene::object::ModId;
use crate::scene::sets::HitInfo;
use crate::scene::transform::Transform;
use crate::scene::world::DistantObject;
use crate::{FHUGE, FTINY};
use glam::DVec3;

thread_local! {
    /// Each render thread's lanes for [`Tracer::sample_patterns`] (no buffer made per
    /// shading point).
    static LANE_SCRATCH: std::cell::RefCell<DataLanes> = std::cell::RefCell::default();
}

/// Where a sample's source is met, for its pattern colour ([`Tracer::sample_pattern`]).
enum SourceAt<'a> {
    /// A source without patterns: colour 1.
    Plain,
    /// The source's patterns (its whole chain) at a shading point on it.
    Patterns(ShadingPoint<'a>, &'a [ModId]),
    /// A chain to walk at the hit on the source.
    Walk(Ray, Hit, ModRef),
    /// A distant source seen along the ray.
    Distant(Ray, &'a DistantObject),
}

/// Where a walk over patterns and textures stopped.
enum End<'s> {
    /// `void`: no material.
    Void,
    /// A material.
    Material(MatId),
    /// A mixture: its coefficient and its two chains.
    Mixture(&'s dyn MixCoefficient, ModRef, ModRef),
}

/// A mixture's foreground share at `sp`, clamped to [0, 1]; 0 (the background) where it
/// cannot be computed.
fn mix_share(coef: &dyn MixCoefficient, sp: &ShadingPoint) -> f64 {
    match coef.coefficient(sp) {
        Some(c) if c.is_finite() => c.clamp(0.0, 1.0),
        _ => 0.0,
    }
}

impl Tracer<'_> {
    /// Apply the patterns and textures of the chain from `r` to `sp`; where it ends.
    fn walk(&self, sp: &mut ShadingPoint, mut r: ModRef) -> End<'_> {
        // Names resolve to earlier definitions, so a chain never loops; bound it anyway.
        for _ in 0..=self.scene.modifiers.len() {
            match r {
                ModRef::Void => return End::Void,
                ModRef::Material(m) => return End::Material(m),
                ModRef::Modifier(id) => {
                    let def = &self.scene.modifiers[id];
                    match &*def.kind {
                        ModifierKind::Pattern(p) => {
                            if let Some(c) = p.colour(sp) {
                                sp.scale_colour(sanitize(c));
                            }
                        }
                        ModifierKind::Texture(t) => {
                            if let Some(d) = t.perturbation(sp).filter(|d| d.is_finite()) {
                                sp.perturb(d);
                            }
                        }
                        ModifierKind::Mixture {
                            coef,
                            foreground,
                            background,
                        } => {
                            if !def.pattern_like {
                                return End::Mixture(coef.as_ref(), *foreground, *background);
                            }
                            // Neither side reaches a material: blend what each side's
                            // patterns and textures do, and go on (Radiance's raymixture).
                            let c = mix_share(coef.as_ref(), sp);
                            let (mut f, mut b) = (*sp, *sp);
                            if c > FTINY {
                                self.walk(&mut f, *foreground);
                            }
                            if c < 1.0 - FTINY {
                                self.walk(&mut b, *background);
                            }
                            sp.pcol = f.pcol * c + b.pcol * (1.0 - c);
                            let pert = f.pert * c + b.pert * (1.0 - c);
                            if pert != sp.pert {
                                sp.perturb(pert - sp.pert);
                            }
                        }
                    }
                    r = def.next;
                }
            }
        }
        End::Void
    }

    /// The pattern colour of a light source's surface where a ray toward it hits it: the
    /// patterns of its chain and of its material's own chain (Radiance shades a shadow
    /// ray's hit on a source like any hit, so `brightfunc` skies and `brightdata`
    /// luminaires shape the emitted light). One for sources without patterns.
    pub fn emission_pattern(&self, ray: &Ray, hit: &Hit, chain: ModRef) -> Color {
        if !self.patterned(chain) {
            return Color::ONE;
        }
        let own = |m: MatId| self.scene.materials[m].chain;
        let mut sp = ShadingPoint::new(ray, hit, self.scene.origin);
        if let End::Material(m) = self.walk(&mut sp, chain) {
            let c = own(m);
            if c != ModRef::Void {
                self.walk(&mut sp, c);
            }
        }
        sp.pcol
    }

    /// Whether the chain from `chain` holds patterns or textures (its own or its material's).
    fn patterned(&self, chain: ModRef) -> bool {
        match chain {
            ModRef::Void => false,
            ModRef::Material(m) => self.scene.materials[m].chain != ModRef::Void,
            ModRef::Modifier(_) => true,
        }
    }

    /// The pattern colour of sample `s`'s source toward the shading point `p` (relative
    /// frame): [`Tracer::emission_pattern`] where a shadow ray along the sample reaches the
    /// source (from the mirror, for a virtual source). It belongs in the sample's unoccluded
    /// potential, as Radiance's `srcvalue` ray puts it there, so that the adaptive shadow
    /// test (`-dt`) orders, stops and estimates by the light a patterned source (an ies2rad
    /// `brightdata` luminaire) really sends toward `p`; the shadow ray then brings only the
    /// transmission. One for sources without patterns.
    pub fn sample_pattern(&self, p: DVec3, s: &SourceSample) -> Color {
        self.source_colour(self.source_at(p, s))
    }

    /// [`Tracer::sample_pattern`] of each sample `k` whose `wanted[k]` is not zero, times
    /// its radiance: the same colours, but the samples of consecutive sources whose one
    /// pattern is a data pattern of the same shape (the luminaires of one ies2rad file
    /// placed many times) are computed together ([`DataLanes`]).
    pub fn sample_patterns(&self, p: DVec3, samples: &mut [SourceSample], wanted: &[Color]) {
        // The thread's lanes, borrowed for the call (a nested call, which patterns never
        // make, would take lanes of its own).
        LANE_SCRATCH.with(|l| match l.try_borrow_mut() {
            Ok(mut lanes) => self.sample_patterns_in(p, samples, wanted, &mut lanes),
            Err(_) => self.sample_patterns_in(p, samples, wanted, &mut DataLanes::default()),
        })
    }

    fn sample_patterns_in(
        &self,
        p: DVec3,
        samples: &mut [SourceSample],
        wanted: &[Color],
        lanes: &mut DataLanes,
    ) {
        lanes.clear();
        let mut which = [0usize; LANES];
        let mut pats: [Option<&DataPattern>; LANES] = [None; LANES];
        for k in 0..samples.len().min(wanted.len()) {
            if wanted[k] == Color::ZERO {
                continue;
            }
            let at = self.source_at(p, &samples[k]);
            let (SourceAt::Patterns(sp, _), Some(d)) = (&at, self.one_data_pattern(&at)) else {
                samples[k].radiance *= self.source_colour(at);
                continue;
            };
            let shape = DataLanes::shape_of(d);
            if shape.is_none() {
                samples[k].radiance *= self.source_colour(at);
                continue;
            }
            if lanes.shape() != shape || lanes.len() == LANES {
                self.flush_lanes(p, lanes, (&which, &pats), samples);
            }
            which[lanes.len()] = k;
            pats[lanes.len()] = Some(d);
            if !lanes.push(d, sp) {
                samples[k].radiance *= self.source_colour(at);
            }
        }
        self.flush_lanes(p, lanes, (&which, &pats), samples);
    }

    /// The data pattern of a source met at `at` whose chain is that one pattern.
    fn one_data_pattern(&self, at: &SourceAt) -> Option<&DataPattern> {
        match at {
            SourceAt::Patterns(_, &[id]) => match &*self.scene.modifiers[id].kind {
                ModifierKind::Pattern(pat) => pat.as_data(),
                _ => None,
            },
            _ => None,
        }
    }

    /// The colours of the samples `which` in `lanes` (then emptied), times their radiance.
    fn flush_lanes(
        &self,
        p: DVec3,
        lanes: &mut DataLanes,
        (which, pats): (&[usize; LANES], &[Option<&DataPattern>; LANES]),
        samples: &mut [SourceSample],
    ) {
        if lanes.is_empty() {
            return;
        }
        let n = lanes.len();
        let mut out = [None; LANES];
        if pats[..n].iter().all(Option::is_some) {
            lanes.colours(|l| pats[l].expect("every lane has its pattern"), &mut out);
        }
        for (&k, c) in which[..n].iter().zip(out.iter()) {
            let pcol = match c {
                Some(c) => {
                    let mut pcol = Color::ONE;
                    if let Some(c) = c {
                        pcol *= sanitize(*c);
                    }
                    pcol
                }
                // Computed alone, by the machine.
                None => self.sample_pattern(p, &samples[k]),
            };
            samples[k].radiance *= pcol;
        }
        lanes.clear();
    }

    /// The pattern colour of a source met at `at` ([`Tracer::sample_pattern`]).
    fn source_colour(&self, at: SourceAt) -> Color {
        match at {
            SourceAt::Plain => Color::ONE,
            SourceAt::Patterns(sp, mods) => self.patterns_colour(&sp, mods),
            SourceAt::Walk(ray, hit, chain) => self.emission_pattern(&ray, &hit, chain),
            SourceAt::Distant(ray, d) => self.distant_pattern(&ray, d),
        }
    }

    /// The patterns `mods` at `sp`, in order, without the walk.
    fn patterns_colour(&self, sp: &ShadingPoint, mods: &[ModId]) -> Color {
        let mut pcol = Color::ONE;
        for &id in mods {
            if let ModifierKind::Pattern(p) = &*self.scene.modifiers[id].kind {
                if let Some(c) = p.colour(sp) {
                    pcol *= sanitize(c);
                }
            }
        }
        pcol
    }

    /// Where sample `s`'s source is met from the shading point `p`, for its pattern.
    fn source_at<'a>(&'a self, p: DVec3, s: &SourceSample) -> SourceAt<'a> {
        let src = &self.lights.sources[s.src];
        let chain = match (src.obj, src.distant) {
            (Some(o), _) => self.scene.hit_info(HitRef::top(o)).chain,
            (None, Some(d)) => self.scene.distant[d].chain,
            (None, None) => return SourceAt::Plain,
        };
        if !self.patterned(chain) {
            return SourceAt::Plain;
        }
        // The leg of the path that reaches the source.
        let Some((org, dir, reach)) = self.lights.relay_path(self.scene, s.src, p, s.dir, s.dist)
        else {
            return SourceAt::Plain;
        };
        let ray = Ray::shadow(org, dir);
        match (src.obj, src.distant) {
            (Some(o), _) => {
                let plan = self.lights.emission(s.src, || self.emission_plan(chain, o));
                let r = HitRef::top(o);
                // A flat source's normal is the same everywhere: patterns that read
                // nothing along the ray need not the exact hit (`light::emission`), which
                // lies at the sample's own distance with the surface's normal
                // ([`SceneGeometry::hit_geom`]'s point, normal and flatness for it).
                if let Some(EmissionPlan::Patterns {
                    mods,
                    along: false,
                    flat: Some(normal),
                }) = plan
                {
                    if reach.is_finite() {
                        let hit = Hit {
                            obj: o,
                            inst: NO_INST,
                            t: reach,
                            point: org + dir * reach,
                            normal: *normal,
                            back: normal.dot(dir) > 0.0,
                            flat: true,
                            material: self.scene.ref_material(r),
                            antimatter: ray.antimatter,
                        };
                        let sp = ShadingPoint::new(&ray, &hit, self.scene.origin);
                        return SourceAt::Patterns(sp, mods);
                    }
                }
                let surface = self.scene.objects.surface(o);
                let exact = match plan {
                    Some(EmissionPlan::Patterns { along, .. }) => {
                        *along
                            || !reach.is_finite()
                            || !matches!(surface, SurfaceRef::Polygon(_) | SurfaceRef::Ring(_))
                    }
                    _ => true,
                };
                let t = if exact {
                    let limit = if reach.is_finite() {
                        reach * (1.0 + 1e-6) + 16.0 * self.scene.eps
                    } else {
                        FHUGE
                    };
                    surface.intersect(org, dir, limit).unwrap_or(reach)
                } else {
                    reach
                };
                let (point, normal, flat) = self.scene.hit_geom(r, org, dir, t);
                let hit = Hit {
                    obj: o,
                    inst: NO_INST,
                    t,
                    point,
                    normal,
                    back: normal.dot(dir) > 0.0,
                    flat,
                    material: self.scene.ref_material(r),
                    antimatter: ray.antimatter,
                };
                match plan {
                    Some(EmissionPlan::Patterns { mods, .. }) => {
                        SourceAt::Patterns(ShadingPoint::new(&ray, &hit, self.scene.origin), mods)
                    }
                    _ => SourceAt::Walk(ray, hit, chain),
                }
            }
            (None, Some(d)) => SourceAt::Distant(ray, &self.scene.distant[d]),
            (None, None) => SourceAt::Plain,
        }
    }

    /// The emission plan of source object `o`, whose chain starts at `chain`: its patterns
    /// when the chain (up to the material, then the material's own) holds nothing else.
    fn emission_plan(&self, chain: ModRef, o: usize) -> EmissionPlan {
        let surface = self.scene.objects.surface(o);
        let flat = surface.is_flat().then(|| surface.normal_at(DVec3::ZERO));
        let mut mods = Vec::new();
        let mut along = false;
        let mut r = chain;
        let mut own = true;
        // Names resolve to earlier definitions, so a chain never loops; bound it anyway.
        for _ in 0..=2 * self.scene.modifiers.len() + 2 {
            match r {
                ModRef::Void => return EmissionPlan::Patterns { mods, along, flat },
                ModRef::Material(m) => {
                    if !own {
                        return EmissionPlan::Patterns { mods, along, flat };
                    }
                    own = false;
                    r = self.scene.materials[m].chain;
                }
                ModRef::Modifier(id) => {
                    let def = &self.scene.modifiers[id];
                    let ModifierKind::Pattern(p) = &*def.kind else {
                        return EmissionPlan::Walk;
                    };
                    along |= p.reads().is_none_or(|c| c & ALONG_RAY != 0);
                    mods.push(id);
                    r = def.next;
                }
            }
        }
        EmissionPlan::Walk
    }

    /// [`Tracer::emission_pattern`] of distant source `d` seen along `ray`'s direction: the
    /// hit lies at Radiance's "infinite" distance, facing the ray.
    pub fn distant_pattern(&self, ray: &Ray, d: &DistantObject) -> Color {
        let hit = Hit {
            obj: 0,
            inst: crate::render::ray::NO_INST,
            t: FHUGE,
            point: ray.org + ray.dir * FHUGE,
            normal: -ray.dir,
            back: false,
            flat: true,
            material: d.material,
            antimatter: ray.antimatter,
        };
        self.emission_pattern(ray, &hit, d.chain)
    }

    /// Shade a hit: its surface's modifier chain, then its material. An antimatter exit
    /// face (shaded with the antimatter's first listed material) skips the surface's chain.
    pub fn shade_hit(&self, ray: &Ray, hit: &Hit, rng: &mut Sampler) -> Color {
        let info = self.scene.hit_info(hit.href());
        let mut sp = ShadingPoint::new(ray, hit, self.scene.origin);
        if !hit.is_top() {
            self.instanced(&mut sp, info.frame);
        }
        if hit.material != info.material {
            return match hit.material {
                Some(m) => self.shade_material(ray, &sp, m, rng),
                None => self.pass_through(ray, hit, rng),
            };
        }
        self.shade_chain(ray, &mut sp, info.chain, rng)
    }

    /// What an instanced hit adds to its shading point: the frame its patterns see, and
    /// for a mesh triangle the interpolated normal (a perturbation of the geometric one)
    /// and (u,v).
    fn instanced<'s>(&self, sp: &mut ShadingPoint<'s>, frame: Option<&'s Transform>) {
        sp.transform = frame;
        let (n, uv) = self.scene.mesh_detail(sp.hit.href(), sp.hit.point);
        sp.uv = uv;
        if let Some(n) = n {
            sp.perturb(n - sp.hit.normal);
        }
    }

    /// Shade `sp` by the chain from `r`.
    pub fn shade_chain(
        &self,
        ray: &Ray,
        sp: &mut ShadingPoint,
        r: ModRef,
        rng: &mut Sampler,
    ) -> Color {
        match self.walk(sp, r) {
            End::Void => self.pass_through(ray, &sp.hit, rng),
            End::Material(m) => self.shade_material(ray, sp, m, rng),
            End::Mixture(coef, fg, bg) => {
                let c = mix_share(coef, sp);
                let mut result = Color::ZERO;
                for (share, side) in [(c, fg), (1.0 - c, bg)] {
                    if share > FTINY {
                        let mut r = *ray;
                        r.weight *= share;
                        let mut s = *sp;
                        result += self.shade_chain(&r, &mut s, side, rng) * share;
                    }
                }
                result
            }
        }
    }

    /// Shade `sp` with material `m` after the material's own patterns and textures.
    pub fn shade_material(
        &self,
        ray: &Ray,
        sp: &ShadingPoint,
        m: MatId,
        rng: &mut Sampler,
    ) -> Color {
        let chain = self.scene.materials[m].chain;
        if chain == ModRef::Void {
            return self.shade(ray, sp, m, rng);
        }
        let mut own = *sp;
        // A material's chain holds patterns and textures only (checked when the scene is
        // built), so the walk ends in void.
        self.walk(&mut own, chain);
        self.shade(ray, &own, m, rng)
    }

    /// What a shadow ray keeps when it crosses `hit` (not its target), through the hit
    /// surface's chain.
    pub(super) fn shadow_through(&self, ray: &Ray, hit: &Hit) -> Color {
        let info = self.scene.hit_info(hit.href());
        // A surface whose chain ends in a material that never transmits stops the ray
        // whatever its patterns make of the point: no shading point is built for it.
        let chain = if hit.material != info.material {
            hit.material.map_or(ModRef::Void, ModRef::Material)
        } else {
            info.chain
        };
        if self.always_blocks(chain) {
            return Color::ZERO;
        }
        self.shadow_shaded(ray, hit, &info)
    }

    /// [`Tracer::shadow_through`] by shading the point (`info`: the hit's).
    fn shadow_shaded(&self, ray: &Ray, hit: &Hit, info: &HitInfo) -> Color {
        let mut sp = ShadingPoint::new(ray, hit, self.scene.origin);
        if !hit.is_top() {
            self.instanced(&mut sp, info.frame);
        }
        if hit.material != info.material {
            return match hit.material {
                Some(m) => self.shadow_material(&sp, m),
                None => Color::ONE,
            };
        }
        self.shadow_chain(&mut sp, info.chain)
    }

    fn shadow_chain(&self, sp: &mut ShadingPoint, r: ModRef) -> Color {
        match self.walk(sp, r) {
            End::Void => Color::ONE,
            End::Material(m) => self.shadow_material(sp, m),
            End::Mixture(coef, fg, bg) => {
                let c = mix_share(coef, sp);
                let (mut a, mut b) = (*sp, *sp);
                self.shadow_chain(&mut a, fg) * c + self.shadow_chain(&mut b, bg) * (1.0 - c)
            }
        }
    }

    /// Whether a shadow ray stops at every surface of chain `r`, wherever it hits: the
    /// chain reaches, through patterns and textures only (no mixture), a material that
    /// never transmits ([`Tracer::never_transmits`]).
    fn always_blocks(&self, mut r: ModRef) -> bool {
        // Names resolve to earlier definitions, so a chain never loops; bound it anyway.
        for _ in 0..=self.scene.modifiers.len() {
            match r {
                ModRef::Void => return false,
                ModRef::Material(m) => return self.never_transmits(m),
                ModRef::Modifier(id) => {
                    let def = &self.scene.modifiers[id];
                    if matches!(&*def.kind, ModifierKind::Mixture { .. }) {
                        return false;
                    }
                    r = def.next;
                }
            }
        }
        false
    }

    pub(super) fn shadow_material(&self, sp: &ShadingPoint, m: MatId) -> Color {
        let chain = self.scene.materials[m].chain;
        if chain == ModRef::Void {
            return self.shadow_transmission(sp, m);
        }
        let mut own = *sp;
        self.walk(&mut own, chain);
        self.shadow_transmission(&own, m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::LightSet;
    use crate::options::render::RenderParams;
    use crate::render::world::Scene;

    /// One surface of each kind of chain, side by side at z = 0 (x from i to i + 1, in
    /// the scene's coordinates; the tracer's are relative to its origin), and whether
    /// shadow rays always stop there.
    const SURFACES: [(&str, bool); 10] = [
        ("grey", true),
        ("rough", true),
        ("clear", false),
        ("opaque_trans", true),
        ("pane", false),
        ("half", false),
        ("mirror_pane", false),
        ("mirror", true),
        ("steel", true),
        ("void", false),
    ];

    const SCENE: &str = "void plastic grey 0 0 5 .5 .5 .5 0 0\n\
        void brightfunc spots 2 spots p.cal 0 0\n\
        spots plastic rough 0 0 5 .6 .6 .6 0 0\n\
        spots trans clear 0 0 7 .8 .8 .8 0 0 .6 .3\n\
        void trans opaque_trans 0 0 7 .8 .8 .8 0 0 0 0\n\
        void glass pane 0 0 3 .9 .9 .9\n\
        void mixfunc half 4 clear void mix p.cal 0 0\n\
        void mirror mirror_pane 1 pane 0 3 .9 .9 .9\n\
        void mirror mirror 0 0 3 .9 .9 .9\n\
        spots metal steel 0 0 5 .7 .7 .7 .9 0\n";

    #[test]
    fn surfaces_that_always_block_shade_to_no_transmission() {
        let mut text = SCENE.to_string();
        for (i, (m, _)) in SURFACES.iter().enumerate() {
            let (a, b) = (i as f64, i as f64 + 1.0);
            text += &format!("{m} polygon s{i} 0 0 12 {a} 0 0 {b} 0 0 {b} 1 0 {a} 1 0\n");
        }
        let cal = "spots = .5 + .5 * sin(Px * 7) * sin(Py * 5);\nmix = .5 + .3 * sin(Px * 3);\n";
        let scene = Scene::from_text(&text, &[("p.cal", cal)]);
        let params = RenderParams::default();
        let lights = LightSet::collect(&scene, 0);
        let tr = Tracer::new(&scene, &params, &lights);
        for (i, &(m, blocks)) in SURFACES.iter().enumerate() {
            let mut shaded_zero = 0;
            for k in 0..25 {
                let (x, y) = (
                    i as f64 + 0.1 + 0.15 * (k % 5) as f64,
                    0.1 + 0.15 * (k / 5) as f64,
                );
                let ray = Ray::shadow(
                    DVec3::new(x, y, 1.0) - scene.origin,
                    DVec3::new(0.1, 0.05, -1.0).normalize(),
                );
                let hit = match tr.intersect(&ray) {
                    Some(h) => h,
                    // A void surface is invisible: no ray stops there.
                    None if m == "void" => continue,
                    None => panic!("{m}: no hit from ({x}, {y})"),
                };
                let info = scene.hit_info(hit.href());
                assert_eq!(tr.always_blocks(info.chain), blocks, "{m}");
                let shaded = tr.shadow_shaded(&ray, &hit, &info);
                if blocks {
                    assert_eq!(tr.shadow_through(&ray, &hit), Color::ZERO, "{m}");
                    assert_eq!(shaded, Color::ZERO, "{m} at ({x}, {y})");
                } else {
                    assert_eq!(tr.shadow_through(&ray, &hit), shaded, "{m}");
                }
                shaded_zero += usize::from(shaded == Color::ZERO);
            }
            // The surfaces that let light through do so where these rays cross them.
            if !blocks && m != "void" {
                assert!(shaded_zero < 25, "{m}: no transmission anywhere");
            }
        }
    }
}
