//! Virtual sources (a light's image in a flat mirror): only the samples whose path crosses
//! the mirror itself are offered to the direct calculation, so the adaptive shadow test
//! (`-dt`) never credits light a mirror cannot relay.

mod common;

use common::scene_from_text;

use glam::DVec3;
use tessera::light::LightSet;
use tessera::radopt::RenderParams;
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
        lights.sample(
            &scene,
            virt,
            p - scene.origin,
            1.0,
            0.05,
            0.0,
            &mut rng,
            &mut out,
        );
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
