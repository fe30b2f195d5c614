//! How a light source's surface shapes the light it sends: the patterns of its chain (an
//! ies2rad luminaire's `brightdata`), decided once per source.
//!
//! Every shading point asks, for each sample of each source, for the pattern colour the
//! source sends toward it ([`crate::render::trace::Tracer::sample_pattern`]). Walking the
//! source's chain for each answer (its surface's modifiers, its material, the material's
//! own modifiers), finding the source's surface along the sample again and building the
//! whole hit cost more than the pattern's own arithmetic. So the chain is read once: when
//! it holds patterns only (no texture, whose perturbation later patterns would see, and no
//! mixture), its patterns are listed in the order the walk meets them, with whether any of
//! them may read the hit point or the path's length (the channels `Px Py Pz T Ts`). When
//! none does, the sample's own direction and distance give the pattern everything it reads
//! (the source is flat: its normal is the same at every point), and the source is not
//! intersected again. The colours are multiplied in the walk's order, so every result is
//! bit-identical.

use std::sync::OnceLock;

use super::source::LightSet;
#[cfg(test)]
use crate::color::Color;
use crate::scene::object::ModId;
use glam::DVec3;

/// A source's emission chain as [`LightSet::emission`] decided it.
#[derive(Clone, Debug)]
pub enum EmissionPlan {
    /// Walk the chain at every sample (it holds a texture or a mixture).
    Walk,
    /// The chain's patterns, in order; `along`: some pattern may read a channel of
    /// [`crate::modifier::frame::ALONG_RAY`], so the hit on the source is found exactly;
    /// `flat`: the source's normal, the same everywhere (a polygon or a ring).
    Patterns {
        mods: Vec<ModId>,
        along: bool,
        flat: Option<DVec3>,
    },
}

impl LightSet {
    /// Source `si`'s emission plan, made by `make` at its first use (None for a set built
    /// without plans: the caller walks the chain).
    pub fn emission(
        &self,
        si: usize,
        make: impl FnOnce() -> EmissionPlan,
    ) -> Option<&EmissionPlan> {
        self.emission.get(si).map(|p| p.get_or_init(make))
    }

    /// One empty plan per source (at the end of collecting them).
    pub(super) fn plan_slots(&mut self) {
        self.emission = (0..self.sources.len()).map(|_| OnceLock::new()).collect();
    }
}

#[cfg(test)]
impl LightSet {
    /// The same set without emission plans: every sample walks its source's chain.
    pub fn without_plans(mut self) -> LightSet {
        self.emission.clear();
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::source::Partition;
    use crate::options::render::RenderParams;
    use crate::render::sampler::Sampler;
    use crate::render::trace::Tracer;
    use crate::render::world::Scene;
    use glam::DVec3;

    const CAL: &str = "theta = acos(Dz) * 180 / 3.14159265358979;\n\
        flat(v) = A1 * v / Rdot;\n\
        along = 1 + .5 * sin(Px * 3) * cos(Py * 2) + .01 * T;\n\
        wave = .05 * sin(Py * 5);\n";

    /// Sources of every kind of plan: patterns reading only the direction and the normal
    /// through a pattern frame (a polygon, a ring, and a sphere, which is not flat), a
    /// pattern reading the point and the path's length, and a texture in the chain.
    const SCENE: &str = "void brightdata dist 6 flat dist.dat lum.cal theta -rz 30 0 1 2.5\n\
        dist light lum 0 0 3 10 10 10\n\
        lum polygon p1 0 0 12 .7 .7 2.5 .7 1.3 2.5 1.3 1.3 2.5 1.3 .7 2.5\n\
        lum ring r1 0 0 8 3 3 2.5 0 0 -1 0 .2\n\
        lum sphere s1 0 0 4 4 1 2.6 .1\n\
        void brightfunc pfun 2 along lum.cal 0 0\n\
        pfun light lum2 0 0 3 5 5 5\n\
        lum2 polygon p2 0 0 12 2 .5 2.4 2 1 2.4 2.5 1 2.4 2.5 .5 2.4\n\
        void texfunc wavy 4 wave wave wave lum.cal 0 0\n\
        wavy brightdata dist2 6 flat dist.dat lum.cal theta -rz 30 0 1 2.5\n\
        dist2 light lum3 0 0 3 8 8 8\n\
        lum3 polygon p3 0 0 12 .5 3 2.5 .5 3.4 2.5 .9 3.4 2.5 .9 3 2.5\n\
        void plastic grey 0 0 5 .5 .5 .5 0 0\n\
        grey polygon floor 0 0 12 -1 -1 0 -1 5 0 6 5 0 6 -1 0\n";

    #[test]
    fn plans_give_the_walks_colours_bit_for_bit() {
        let scene = Scene::from_text(
            SCENE,
            &[
                ("lum.cal", CAL),
                ("dist.dat", "1\n0 180 7\n8 7.6 6.4 4.6 2.6 .9 .3\n"),
            ],
        );
        let params = RenderParams::default();
        let planned = LightSet::collect(&scene, 0);
        let walked = planned.clone().without_plans();
        assert_eq!(planned.sources.len(), 5);
        let (a, b) = (
            Tracer::new(&scene, &params, &planned),
            Tracer::new(&scene, &params, &walked),
        );
        let mut rng = Sampler::for_pixel(0, 1, 2, 3);
        let mut samples = Vec::new();
        let mut compared = 0;
        for i in 0..400 {
            let f = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0;
            let p = DVec3::new(-0.5 + 6.0 * f(1), -0.5 + 5.0 * f(2), 2.2 * f(3));
            samples.clear();
            let how = Partition {
                weight: 1.0,
                ds: 0.2,
                dj: 0.7,
            };
            for si in 0..planned.sources.len() {
                planned.sample(&scene, (si, p), how, &mut rng, &mut samples);
            }
            for s in &samples {
                let (x, y) = (a.sample_pattern(p, s), b.sample_pattern(p, s));
                assert_eq!(
                    x.to_array().map(f64::to_bits),
                    y.to_array().map(f64::to_bits),
                    "source {} from {p}: {x:?} against {y:?}",
                    s.src
                );
                assert_ne!(x, Color::ONE, "source {} has no pattern", s.src);
                compared += 1;
            }
        }
        assert!(compared > 1000, "{compared}");
        // The plans made: the texture's source walks; only the pattern reading the point
        // and T finds the hit exactly (the sphere too, not being flat).
        let plan = |si: usize| planned.emission(si, || unreachable!()).unwrap().clone();
        let along = |si: usize| match plan(si) {
            EmissionPlan::Patterns { along, mods, .. } => {
                assert_eq!(mods.len(), 1);
                Some(along)
            }
            EmissionPlan::Walk => None,
        };
        assert_eq!(
            (0..5).map(along).collect::<Vec<_>>(),
            [Some(false), Some(false), Some(false), Some(true), None]
        );
    }

    /// The samples of a shading point's sources, their patterns computed together
    /// ([`Tracer::sample_patterns`]), take the colours each gets alone, bit for bit: eleven
    /// luminaires of one ies2rad-like distribution in their own frames (one with another
    /// multiplier: another shape), a colour one, two whose function fails at some
    /// directions (left to the machine, lane by lane), a texture's walk and plain sources
    /// between them; samples without a coefficient keep their radiance. The samples of all
    /// sources at once ([`LightSet::sample_all`]) are those of each in turn.
    #[test]
    fn patterns_in_lanes_are_each_samples_own() {
        let mut text = String::new();
        for i in 0..16 {
            let (x, y) = (0.7 * (i % 4) as f64, 0.9 * (i / 4) as f64);
            let (kind, funcs, files) = match i {
                8 => ("colordata", "flat flat flat", "dist.dat dist.dat dist.dat"),
                9 | 10 => ("brightdata", "odd", "dist.dat"),
                _ => ("brightdata", "flat", "dist.dat"),
            };
            let k = funcs.split(' ').count() * 2 + 6 + if i % 3 == 0 { 2 } else { 0 };
            let rz = if i % 3 == 0 { " -rz 30" } else { "" };
            let a1 = if i == 5 { 1.5 } else { 2.5 };
            text += &format!(
                "void {kind} d{i} {k} {funcs} {files} lum.cal theta{rz} -t {x} {y} 0 0 1 {a1}\n\
                 d{i} light l{i} 0 0 3 10 10 10\n\
                 l{i} polygon q{i} 0 0 12 {x} {y} 2.5 {x} {y1} 2.5 {x1} {y1} 2.5 {x1} {y} 2.5\n",
                y1 = y + 0.3,
                x1 = x + 0.3,
            );
            if i == 12 {
                text += "void light plain 0 0 3 4 4 4\n\
                    plain polygon pp 0 0 12 3 3 2.6 3 3.2 2.6 3.2 3.2 2.6 3.2 3 2.6\n";
            }
        }
        text += &SCENE[SCENE.find("void texfunc").unwrap()..];
        // Sources of the other shapes and kinds: a ring, a sphere, a glow of some reach
        // (a triangle: samples off it are dropped), a spotlight.
        text += "void light lr 0 0 3 5 5 5\n\
            lr ring rr 0 0 8 3.5 1 2.5 0 0 -1 0 .15\n\
            lr sphere ss 0 0 4 3.5 2 2.4 .08\n\
            void glow gl 0 0 4 2 2 2 3\n\
            gl polygon gp 0 0 9 3 4 2.5 3.3 4 2.5 3 4.3 2.5\n\
            void spotlight spt 0 0 7 6 6 6 40 0 0 -1\n\
            spt polygon sq 0 0 12 2 4 2.5 2 4.2 2.5 2.2 4.2 2.5 2.2 4 2.5\n";
        let cal = format!("{CAL}odd(v) = v * sqrt(Dx);\n");
        let scene = Scene::from_text(
            &text,
            &[
                ("lum.cal", cal.as_str()),
                ("dist.dat", "1\n0 180 7\n8 7.6 6.4 4.6 2.6 .9 .3\n"),
            ],
        );
        let params = RenderParams::default();
        let lights = LightSet::collect(&scene, 0);
        assert_eq!(lights.sources.len(), 22);
        let tr = Tracer::new(&scene, &params, &lights);
        let mut rng = Sampler::for_pixel(0, 1, 2, 3);
        let (mut samples, mut compared, mut failed) = (Vec::new(), 0, 0);
        for i in 0..500 {
            let f = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0;
            let p = DVec3::new(-0.5 + 4.0 * f(1), -0.5 + 5.0 * f(2), 2.2 * f(3));
            samples.clear();
            let how = Partition {
                weight: 1.0,
                ds: if i % 2 == 0 { 0.0 } else { 0.3 },
                dj: 0.7,
            };
            let mut rng_all = rng.clone();
            for si in 0..lights.sources.len() {
                lights.sample(&scene, (si, p), how, &mut rng, &mut samples);
            }
            // All sources at once: the same samples, the same draws.
            let mut all = Vec::new();
            lights.sample_all(&scene, p, how, &mut rng_all, &mut all);
            let key = |s: &crate::light::SourceSample| {
                let v = [s.dir.x, s.dir.y, s.dir.z, s.dist, s.omega, s.radiance.x];
                (s.src, v.map(f64::to_bits))
            };
            assert_eq!(
                all.iter().map(key).collect::<Vec<_>>(),
                samples.iter().map(key).collect::<Vec<_>>()
            );
            assert_eq!(rng_all.uniform().to_bits(), rng.clone().uniform().to_bits());
            let wanted: Vec<Color> = (0..samples.len())
                .map(|k| match (k * 7 + i as usize) % 5 {
                    0 => Color::ZERO,
                    _ => Color::ONE,
                })
                .collect();
            let mut together = samples.clone();
            tr.sample_patterns(p, &mut together, &wanted);
            for (k, s) in samples.iter().enumerate() {
                let alone = match wanted[k] == Color::ZERO {
                    true => s.radiance,
                    false => s.radiance * tr.sample_pattern(p, s),
                };
                failed += usize::from(alone == s.radiance && wanted[k] != Color::ZERO);
                assert_eq!(
                    together[k].radiance.to_array().map(f64::to_bits),
                    alone.to_array().map(f64::to_bits),
                    "sample {k} of source {} from {p}",
                    s.src
                );
                compared += 1;
            }
        }
        assert!(
            compared > 4000 && failed > 100,
            "{compared} compared, {failed} plain"
        );
    }
}
