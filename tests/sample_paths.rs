//! Specular splits below a cached value's sample ray follow one branch
//! (`Tracer::split`): the expectation over many draws equals the whole tree's result.

mod common;

use common::scene_from_text;

use glam::DVec3;
use tessera::light::LightSet;
use tessera::options::RenderParams;
use tessera::render::ray::{Ray, RayKind};
use tessera::render::sampler::Sampler;
use tessera::render::Tracer;

/// A water drop and a glass pane between a glowing disk (ahead) and a glowing strip (behind
/// the viewer, seen in reflection); glows of radius 0 are not light sources, so every
/// light arrives through the specular rays themselves.
const SCENE: &str = "void glow ahead 0 0 4 5 4 3 0\n\
void glow behind 0 0 4 1 2 3 0\n\
void dielectric water 0 0 5 .98 .99 .95 1.33 0\n\
void glass pane 0 0 3 .9 .9 .9\n\
water sphere drop 0 0 4 0 0 0 1\n\
pane polygon window 0 0 12 -3 -3 2 3 -3 2 3 3 2 -3 3 2\n\
ahead ring disk 0 0 8 0 0 10 0 0 -1 0 6\n\
behind ring strip 0 0 8 0 0 -10 0 0 1 0 8\n";

#[test]
fn one_branch_per_split_keeps_the_expectation() {
    let scene = scene_from_text(SCENE);
    let params = RenderParams::default();
    let lights = LightSet::collect(&scene, params.dr);
    let tracer = Tracer::new(&scene, &params, &lights);
    for (k, org) in [
        DVec3::new(0.3, 0.2, -5.0),
        DVec3::new(0.8, -0.1, -5.0),
        DVec3::new(2.0, 1.0, -5.0),
    ]
    .into_iter()
    .enumerate()
    {
        let target = DVec3::new(org.x * 0.1, org.y * 0.1, 0.0);
        let dir = (target - org).normalize();
        let mut ray = Ray::primary(org - scene.origin, dir, f64::INFINITY);
        // A descendant of a sample ray (the sample ray's own split stays whole).
        ray.kind = RayKind::Transmitted;
        ray.weight = 0.5;
        let mut rng = Sampler::for_pixel(0, k as u32, 0, 0);
        let whole = tracer.trace(&ray, &mut rng);
        let whole_rays = rng.rays;
        ray.sample.on = true;
        let n = 20_000;
        let mut sum = tessera::color::Color::ZERO;
        let mut rays = 0;
        for i in 0..n {
            let mut rng = Sampler::for_pixel(1, k as u32, i, 0);
            sum += tracer.trace(&ray, &mut rng);
            rays += rng.rays;
        }
        let mean = sum / n as f64;
        let per_path = rays as f64 / n as f64;
        eprintln!("origin {org}: whole {whole} ({whole_rays} rays), one branch {mean} ({per_path:.1} rays)");
        assert!(
            whole.max_element() > 0.1,
            "the setup must see light: {whole}"
        );
        for c in 0..3 {
            let rel = (mean[c] - whole[c]).abs() / whole[c];
            assert!(rel < 0.02, "channel {c}: {} vs {}", mean[c], whole[c]);
        }
        assert!(
            per_path < 0.5 * whole_rays as f64,
            "{per_path} vs {whole_rays} rays"
        );
    }
}
