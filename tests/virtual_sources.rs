//! Virtual sources (a light's image in a flat mirror): only the samples whose path crosses
//! the mirror itself are offered to the direct calculation, so the adaptive shadow test
//! (`-dt`) never credits light a mirror cannot relay. Later generations (`-dr` 2, 3): light
//! relayed by two and three mirrors in turn, against real rpict on periscopes whose target
//! is lit only through all their mirrors (means within 1% at `-ab 0`, 2% at `-ab 1`).

mod common;

use common::*;

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

/// Three mirrors of a periscope: a lamp facing up; mirror A above it sends its light along
/// +x, mirror B turns it down, mirror C turns it along +y onto a wall under a plate. Shades
/// keep the lamp's light from B and from the wall except through the mirrors: the wall is
/// lit only through A, B and C in turn (`-dr 3`), the floor under B through A and B.
const PERISCOPE: &str = "void light lamp 0 0 3 50 50 50
void plastic grey 0 0 5 .5 .5 .5 0 0
void mirror silver 0 0 3 .9 .9 .9
grey polygon floor 0 0 12  -5 -4 0  5 -4 0  5 4 0  -5 4 0
lamp polygon panel 0 0 12  -3.5 -.5 3  -2.5 -.5 3  -2.5 .5 3  -3.5 .5 3
silver polygon mirA 0 0 12  -4 -1 3.5  -4 1 3.5  -2 1 5.5  -2 -1 5.5
silver polygon mirB 0 0 12  2 -1 5.5  2 1 5.5  4 1 3.5  4 -1 3.5
silver polygon mirC 0 0 12  2 -1 2  4 -1 2  4 1 0  2 1 0
grey polygon baffle 0 0 12  -5 -4 2.9  1 -4 2.9  1 4 2.9  -5 4 2.9
grey polygon shade 0 0 12  -2.3 -4 2.9  -2.3 -4 3.8  -2.3 4 3.8  -2.3 4 2.9
grey polygon wall 0 0 12  1 4 0  5 4 0  5 4 3  1 4 3
grey polygon plate 0 0 12  1 1.2 2.2  1 4 2.2  5 4 2.2  5 1.2 2.2
";

#[test]
fn generations_follow_the_mirrors_that_see_each_other() {
    let scene = scene_from_text(PERISCOPE);
    let count = |dr: i32| {
        let lights = LightSet::collect(&scene, dr);
        let mut by_gen = [0usize; 5];
        for s in &lights.sources {
            by_gen[s.relay.as_ref().map_or(0, |r| r.generation as usize)] += 1;
        }
        assert!(lights.warnings.is_empty(), "{:?}", lights.warnings);
        (lights, by_gen)
    };
    // The lamp is in front of all three mirrors: three images of the first generation.
    let (_, g1) = count(1);
    assert_eq!(g1, [1, 3, 0, 0, 0]);
    // Second generation: the image in A is seen by B and (past the baffle, which the
    // shadow rays find) by C, the image in B by C; the image in C lies behind A and B, and
    // A sees nothing of B's.
    let (l2, g2) = count(2);
    let name = |o: usize| scene.objects.name(o).to_string();
    let pairs = |l: &LightSet, g: u32| {
        let mut v: Vec<Vec<String>> = l
            .sources
            .iter()
            .enumerate()
            .filter(|(_, s)| s.relay.as_ref().is_some_and(|r| r.generation == g))
            .map(|(i, _)| {
                let mut c: Vec<String> = l.relays(i).map(|r| name(r.obj)).collect();
                c.reverse();
                c
            })
            .collect();
        v.sort();
        v
    };
    assert_eq!(g2[..3], [1, 3, 3]);
    assert_eq!(
        pairs(&l2, 2),
        [["mirA", "mirB"], ["mirA", "mirC"], ["mirB", "mirC"]]
    );
    // Third generation: A, B, C in turn only; nothing more at -dr 4.
    let (l3, g3) = count(3);
    assert_eq!(g3[..4], [1, 3, 3, 1]);
    assert_eq!(pairs(&l3, 3), [["mirA", "mirB", "mirC"]]);
    let (_, g4) = count(4);
    assert_eq!(g4, [1, 3, 3, 1, 0]);
    // The third-generation image is the lamp reflected in A, then B, then C, with the three
    // mirrors' reflectance; a point on the wall folds back to the lamp's side of A.
    let (si, s) = l3
        .sources
        .iter()
        .enumerate()
        .find(|(_, s)| s.relay.as_ref().is_some_and(|r| r.generation == 3))
        .unwrap();
    let chain: Vec<String> = l3.relays(si).map(|r| name(r.obj)).collect();
    assert_eq!(chain, ["mirC", "mirB", "mirA"]);
    assert!((s.emitter.radiance.x - 50.0 * 0.9f64.powi(3)).abs() < 1e-9);
    let p = DVec3::new(3.0, 3.9, 1.0) - scene.origin;
    let mut rng = Sampler::for_pixel(0, 0, 0, 0);
    let mut out = Vec::new();
    let how = Partition {
        weight: 1.0,
        ds: 0.1,
        dj: 0.0,
    };
    l3.sample(&scene, (si, p), how, &mut rng, &mut out);
    assert!(!out.is_empty(), "the wall sees the lamp through C, B and A");
    for smp in &out {
        // Each sample's path crosses C, B and A in turn and its last leg reaches the lamp.
        let (org, dir, rest) = l3.relay_path(&scene, si, p, smp.dir, smp.dist).unwrap();
        let end = org + dir * rest + scene.origin;
        assert!((end.z - 3.0).abs() < 1e-6, "{end}");
        assert!(end.x >= -3.5 - 1e-6 && end.x <= -2.5 + 1e-6, "{end}");
    }
}

fn mean(p: &std::path::Path) -> f64 {
    let img = tessera::image::read_picture(p).unwrap();
    img.pixels.iter().map(|c| c[1] as f64).sum::<f64>() / img.pixels.len() as f64
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn later_generations_match_rpict() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    // Without C, the wall and the plate: the floor under B is lit through A and B.
    let two: String = PERISCOPE
        .lines()
        .filter(|l| !["mirC", "wall", "plate"].iter().any(|w| l.contains(w)))
        .map(|l| format!("{l}\n"))
        .collect();
    for (name, text) in [("peri2", two.as_str()), ("peri3", PERISCOPE)] {
        std::fs::write(d.join(format!("{name}.rad")), text).unwrap();
        let oct = run_ok(
            radiance(&bin, "oconv")
                .current_dir(d)
                .arg(format!("{name}.rad")),
        );
        std::fs::write(d.join(format!("{name}.oct")), oct).unwrap();
    }
    // The floor under B (lit through A and B) and the wall (through A, B and C).
    let floor = "-vp 3 -9 2.5 -vd 0 1 -.35 -vu 0 0 1 -vh 60 -vv 45";
    let wall = "-vp 3 2.5 1 -vd 0 1 0 -vu 0 0 1 -vh 60 -vv 45";
    for (scene, view, dr, dark) in [("peri2", floor, "2", "1"), ("peri3", wall, "3", "2")] {
        let (rad, oct) = (format!("{scene}.rad"), format!("{scene}.oct"));
        let mut means = Vec::new();
        for (ab, tol, bound) in [("0", &SUITE, 0.01), ("1", &AMBIENT, 0.02)] {
            let mut opts: Vec<&str> = view.split_whitespace().collect();
            opts.extend([
                "-x", "128", "-y", "96", "-ps", "1", "-pj", "0", "-dj", "0", "-ds", ".1", "-dt",
                "0", "-ab", ab, "-ad", "256", "-aa", ".15", "-dr", dr,
            ]);
            check_against_rpict(&bin, d, &[&rad], &oct, &opts, tol);
            let name = format!("{rad}{}", opts.join(""));
            let (ours, reference) = (
                mean(&d.join(format!("ours-{name}.hdr"))),
                mean(&d.join(format!("ref-{name}.hdr"))),
            );
            assert!(
                (ours / reference - 1.0).abs() < bound,
                "-dr {dr} -ab {ab}: mean {ours} against rpict's {reference}"
            );
            means.push(ours);
        }
        // One generation fewer leaves the target dark: its light comes through the last
        // generation.
        let mut opts: Vec<&str> = view.split_whitespace().collect();
        opts.extend([
            "-x", "32", "-y", "24", "-ps", "1", "-pj", "0", "-dj", "0", "-ds", ".1", "-dt", "0",
            "-ab", "0", "-dr", dark,
        ]);
        let out = d.join(format!("dark-{dr}.hdr"));
        run_ok(tpict_in(d).args(&opts).arg("-o").arg(&out).arg(&rad));
        assert!(means[0] > 1e-3);
        assert_eq!(mean(&out), 0.0, "-dr {dark}");
    }
}

/// A spotlight aimed at a mirror lights the floor only through it: the cone is tested from
/// the real spotlight toward the point folded through the mirror (it was tested from the
/// image, and the floor stayed black). Against rpict at `-ab 0`.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn a_spotlights_image_keeps_its_cone() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(
        d.join("spot.rad"),
        "void spotlight spot 0 0 7 200 200 200 30 1 0 -.3
void plastic grey 0 0 5 .5 .5 .5 0 0
void mirror silver 0 0 3 .9 .9 .9
grey polygon floor 0 0 12  -5 -4 0  5 -4 0  5 4 0  -5 4 0
spot ring bulb 0 0 8  -2 0 3  1 0 -1  0 .1
silver polygon mir 0 0 12  2 2 4  2 2 0.01  2 -2 0.01  2 -2 4
grey polygon block 0 0 12  -1.5 -4 0.01 -1.5 -4 2 -1.5 4 2 -1.5 4 0.01
",
    )
    .unwrap();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg("spot.rad"));
    std::fs::write(d.join("spot.oct"), oct).unwrap();
    let opts: Vec<&str> = "-vp 0 -7 6 -vd 0 1 -1 -vu 0 0 1 -vh 70 -vv 60 -x 128 -y 96 -ps 1 \
         -pj 0 -dj 0 -ds .1 -dt 0 -ab 0 -dr 1"
        .split_whitespace()
        .collect();
    check_against_rpict(&bin, d, &["spot.rad"], "spot.oct", &opts, &SUITE);
    let name = format!("spot.rad{}", opts.join(""));
    let (ours, reference) = (
        mean(&d.join(format!("ours-{name}.hdr"))),
        mean(&d.join(format!("ref-{name}.hdr"))),
    );
    assert!(reference > 0.0);
    assert!(
        (ours / reference - 1.0).abs() < 0.01,
        "mean {ours} against rpict's {reference}"
    );
}
