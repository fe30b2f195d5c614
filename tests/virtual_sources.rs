//! Virtual sources (a light's image in a flat mirror): only the samples whose path crosses
//! the mirror itself are offered to the direct calculation, so the adaptive shadow test
//! (`-dt`) never credits light a mirror cannot relay.

mod common;

use common::scene_from_text;

use glam::DVec3;
use tessera::light::source::Partition;
use tessera::light::LightSet;
use tessera::options::RenderParams;
use tessera::render::sampler::Sampler;

/// A square light 2 units above a small mirror (1 × 1, at z = 0, facing up); the light's
/// image is at z = -2.
const SCENE: &str = "void light panel 0 0 3 10 10 10\n\
void mirror silver 0 0 3 .8 .8 .8\n\
panel polygon lamp 0 0 12 -.5 -.5 2 -.5 .5 2 .5 .5 2 .5 -.5 2\n\
silver polygon mir 0 0 12 -.5 -.5 0 .5 -.5 0 .5 .5 0 -.5 .5 0\n";

#[test]
fn virtual_samples_are_offered_only_through_the_mirror() {
    let scene = scene_from_text(SCENE);
    let lights = LightSet::collect(&scene, RenderParams::default().dr);
    let virt = (0..lights.sources.len())
        .find(|&i| lights.sources[i].relay.is_some())
        .expect("the mirror relays the light");
    let count = |p: DVec3| {
        let mut rng = Sampler::for_pixel(0, 0, 0, 0);
        let mut out = Vec::new();
        // -ds .05: the image is split into several partitions seen from these points.
        let how = Partition {
            weight: 1.0,
            ds: 0.05,
            dj: 0.0,
        };
        lights.sample(&scene, (virt, p - scene.origin), how, &mut rng, &mut out);
        out
    };
    // Right above the mirror: the image is seen through it.
    let above = count(DVec3::new(0.0, 0.0, 1.0));
    assert!(!above.is_empty());
    // Far to the side at a low height: every path to the image crosses the plane z = 0
    // outside the mirror.
    assert!(count(DVec3::new(4.0, 0.0, 0.5)).is_empty());
    // Partly: near the mirror's edge only some partitions are seen through it.
    let edge = count(DVec3::new(0.9, 0.0, 1.0));
    assert!(
        !edge.is_empty() && edge.len() < above.len(),
        "{} {}",
        edge.len(),
        above.len()
    );
    // Every sample offered crosses the mirror before reaching the image.
    for p in [DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.9, 0.0, 1.0)] {
        for s in count(p) {
            let q = p + s.dir * (p.z / -s.dir.z);
            assert!(q.x.abs() <= 0.5 + 1e-9 && q.y.abs() <= 0.5 + 1e-9, "{q}");
        }
    }
}

/// The glows a cached value samples explicitly (`LightSet::sampled_glows`): real, local glows
/// with a radius of influence; not a glow of radius 0 (never a source), not a light, and not
/// a glow's image in a mirror (its light reaches a value through the mirror's own samples).
/// `sample_glow` samples one from beyond that radius, where `sample` gives nothing.
#[test]
fn sampled_glows_are_the_real_glows_with_a_radius() {
    let scene = scene_from_text(
        "void light panel 0 0 3 10 10 10\n\
         void glow neon 0 0 4 5 1 1 1.5\n\
         void glow faint 0 0 4 1 1 1 0\n\
         void mirror silver 0 0 3 .8 .8 .8\n\
         panel polygon lamp 0 0 12 -.5 -.5 4 -.5 .5 4 .5 .5 4 .5 -.5 4\n\
         neon sphere ball 0 0 4 0 0 1 .2\n\
         faint sphere dim 0 0 4 3 0 1 .2\n\
         silver polygon mir 0 0 12 -2 -2 0 2 -2 0 2 2 0 -2 2 0\n",
    );
    let lights = LightSet::collect(&scene, RenderParams::default().dr);
    let glows: Vec<(usize, f64)> = lights.sampled_glows().collect();
    assert_eq!(glows.len(), 1, "only the neon ball: {glows:?}");
    let (si, maxrad) = glows[0];
    assert_eq!(maxrad, 1.5);
    let ball = lights.sources[si].obj.expect("a local source");
    assert!(lights.is_sampled_glow(ball));
    // The other objects (the faint glow, the panel, the mirror) are not.
    let others = (0..scene.objects.len()).filter(|&o| o != ball);
    assert!(others.clone().count() >= 3);
    for o in others {
        assert!(!lights.is_sampled_glow(o), "object {o}");
    }
    // The ball's image in the mirror is a (virtual) source, but not a sampled glow.
    assert!(lights
        .sources
        .iter()
        .any(|s| s.relay.as_ref().is_some_and(|r| r.real == si)));
    // From 3 units away (beyond the radius): `sample` gives nothing, `sample_glow` a point
    // on the ball, with its solid angle.
    let p = DVec3::new(0.0, 3.0, 1.0) - scene.origin;
    let mut rng = Sampler::for_pixel(0, 0, 0, 0);
    let mut out = Vec::new();
    let how = Partition {
        weight: 1.0,
        ds: 0.2,
        dj: 0.0,
    };
    lights.sample(&scene, (si, p), how, &mut rng, &mut out);
    assert!(out.is_empty());
    lights.sample_glow(&scene, (si, p), 0.2, &mut rng, &mut out);
    assert_eq!(out.len(), 1);
    let s = out[0];
    assert!(s.dist > 2.7 && s.dist < 3.0, "distance {}", s.dist);
    let omega = 2.0 * std::f64::consts::PI * (1.0 - (1.0 - (0.2f64 / 3.0).powi(2)).sqrt());
    assert!((s.omega - omega).abs() < 1e-9 * omega);
}
