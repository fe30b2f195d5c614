//! Modifier chains through the library: test-only pattern, texture and mixture types
//! registered with `ModifierTypes` (Tessera's own Radiance types come with the function
//! language) show that the tracer applies a surface's chain in Radiance's order, that a
//! material's own chain applies too, that aliases keep or drop it, and that wrong chains are
//! refused with the file and line.

use glam::DVec3;
use tessera::color::Color;
use tessera::light::LightSet;
use tessera::modifier::{
    MixCoefficient, ModifierKind, ModifierLookup, ModifierTypes, Pattern, Texture,
};
use tessera::options::RenderParams;
use tessera::render::ray::Ray;
use tessera::render::sampler::Sampler;
use tessera::render::shading::ShadingPoint;
use tessera::render::world::Scene;
use tessera::render::Tracer;
use tessera::scene::{parse_scene_text, Primitive, ReadOptions};

#[derive(Debug)]
struct Constant(Color);
impl Pattern for Constant {
    fn colour(&self, _: &ShadingPoint) -> Option<Color> {
        Some(self.0)
    }
}

#[derive(Debug)]
struct Tilt(DVec3);
impl Texture for Tilt {
    fn perturbation(&self, _: &ShadingPoint) -> Option<DVec3> {
        Some(self.0)
    }
}

#[derive(Debug)]
struct Share(f64);
impl MixCoefficient for Share {
    fn coefficient(&self, _: &ShadingPoint) -> Option<f64> {
        Some(self.0)
    }
}

fn three(p: &Primitive) -> Result<[f64; 3], String> {
    match p.rargs[..] {
        [a, b, c] => Ok([a, b, c]),
        _ => Err(format!("takes 3 real arguments, got {}", p.rargs.len())),
    }
}

/// The test types: `test-pattern` (a constant colour), `test-texture` (a constant
/// perturbation), `test-mixture` (2 strings: foreground, background; 1 real: its share).
fn types() -> ModifierTypes {
    ModifierTypes::standard()
        .with("test-pattern", |p, _| {
            Ok(ModifierKind::Pattern(Box::new(Constant(
                DVec3::from_array(three(p)?),
            ))))
        })
        .with("test-texture", |p, _| {
            Ok(ModifierKind::Texture(Box::new(Tilt(DVec3::from_array(
                three(p)?,
            )))))
        })
        .with("test-mixture", |p, l: &dyn ModifierLookup| {
            if p.sargs.len() != 2 || p.rargs.len() != 1 {
                return Err("takes 2 strings and 1 real".into());
            }
            Ok(ModifierKind::Mixture {
                coef: Box::new(Share(p.rargs[0])),
                foreground: l.modref(&p.sargs[0])?,
                background: l.modref(&p.sargs[1])?,
            })
        })
}

/// A scene from text in which the primitive types `colorfunc`, `texfunc` and `mixfunc`
/// stand for the test types (the reader knows only Radiance's type names).
fn scene(text: &str) -> Result<Scene, String> {
    let mut prims =
        parse_scene_text(text, "test.rad", &ReadOptions::default()).map_err(|e| e.to_string())?;
    for p in &mut prims {
        let t = match p.ptype.as_str() {
            "colorfunc" => "test-pattern",
            "texfunc" => "test-texture",
            "mixfunc" => "test-mixture",
            _ => continue,
        };
        p.ptype = t.into();
    }
    Scene::build_with(&prims, &types()).map_err(|e| e.to_string())
}

/// A floor z = 0 under a distant source straight above (a sun of 1 radiance unit), seen
/// from above at a slant: `mats` defines what the floor's modifier `floor` is.
fn floor_scene(mats: &str) -> String {
    format!(
        "void light sun_mat 0 0 3 1000 1000 1000\n\
         sun_mat source sun 0 0 4 0 0 1 1\n\
         {mats}\n\
         floor polygon ground 0 0 12 -10 -10 0 10 -10 0 10 10 0 -10 10 0\n"
    )
}

/// The radiance toward the eye from the floor's centre (one primary ray, `-ab 0`).
fn look(text: &str) -> Color {
    let s = scene(text).unwrap();
    let params = RenderParams {
        dj: 0.0,
        ..RenderParams::default()
    };
    let lights = LightSet::collect(&s, params.dr);
    let tr = Tracer::new(&s, &params, &lights);
    let org = DVec3::new(0.0, -1.0, 1.0) - s.origin;
    let ray = Ray::primary(org, DVec3::new(0.0, 1.0, -1.0).normalize(), f64::INFINITY);
    tr.trace(&ray, &mut Sampler::for_pixel(0, 1, 1, 0))
}

fn close(a: Color, b: Color, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol * b.abs().max_element().max(1e-30)
}

#[test]
fn a_pattern_multiplies_the_material_colour() {
    let plain = look(&floor_scene("void plastic floor 0 0 5 .4 .2 .8 0 0"));
    let patterned = look(&floor_scene(
        "void colorfunc half 0 0 3 .5 .25 1\nhalf plastic floor 0 0 5 .8 .8 .8 0 0",
    ));
    assert!(plain.min_element() > 0.0, "{plain}");
    assert_eq!(
        patterned, plain,
        "pattern × colour = the premultiplied colour"
    );
    // On the surface instead of the material, and patterns on patterns (order-free).
    let on_surface = look(&floor_scene(
        "void plastic white 0 0 5 .8 .8 .8 0 0\n\
         white colorfunc a 0 0 3 1 .5 1\n\
         a colorfunc floor 0 0 3 .5 .5 1",
    ));
    assert_eq!(on_surface, plain);
    // A pattern on a light scales its emission.
    let seen_light = {
        let s = "void colorfunc dim 0 0 3 .5 .5 .5\n\
                 dim glow g 0 0 4 2 2 2 0\n\
                 g polygon lamp 0 0 12 -1 -1 0 1 -1 0 1 1 0 -1 1 0\n";
        let s = scene(s).unwrap();
        let params = RenderParams::default();
        let lights = LightSet::collect(&s, params.dr);
        let tr = Tracer::new(&s, &params, &lights);
        let ray = Ray::primary(
            DVec3::new(0.0, 0.0, 1.0) - s.origin,
            -DVec3::Z,
            f64::INFINITY,
        );
        tr.trace(&ray, &mut Sampler::for_pixel(0, 0, 0, 0))
    };
    assert_eq!(seen_light, Color::splat(1.0));
}

#[test]
fn aliases_keep_or_drop_a_materials_chain() {
    let plain = look(&floor_scene("void plastic floor 0 0 5 .8 .8 .8 0 0"));
    let half = look(&floor_scene("void plastic floor 0 0 5 .4 .4 .4 0 0"));
    let base = "void colorfunc half 0 0 3 .5 .5 .5\nhalf plastic m 0 0 5 .8 .8 .8 0 0";
    let kept = look(&floor_scene(&format!("{base}\ninherit alias floor m")));
    let dropped = look(&floor_scene(&format!("{base}\nvoid alias floor m")));
    assert_eq!(kept, half);
    assert_eq!(dropped, plain);
}

#[test]
fn a_texture_tilts_the_shading_normal() {
    let plain = look(&floor_scene("void plastic floor 0 0 5 .5 .5 .5 0 0"));
    let tilted = look(&floor_scene(
        "void texfunc tilt 0 0 3 .5 0 0\ntilt plastic floor 0 0 5 .5 .5 .5 0 0",
    ));
    // The sun is straight above: the diffuse light falls with the cosine of the tilt.
    let want = plain * (1.0 / 1.25f64.sqrt());
    assert!(close(tilted, want, 1e-9), "{tilted} vs {want}");
}

#[test]
fn a_mixture_blends_its_two_chains() {
    let mixed = look(&floor_scene(
        "void plastic red 0 0 5 .8 0 0 0 0\n\
         void plastic blue 0 0 5 0 0 .8 0 0\n\
         void mixfunc floor 2 red blue 0 1 .25",
    ));
    let blend = look(&floor_scene("void plastic floor 0 0 5 .2 0 .6 0 0"));
    assert!(close(mixed, blend, 1e-9), "{mixed} vs {blend}");
    // Out-of-range shares are clamped: all foreground.
    let all = look(&floor_scene(
        "void plastic red 0 0 5 .8 0 0 0 0\n\
         void plastic blue 0 0 5 0 0 .8 0 0\n\
         void mixfunc floor 2 red blue 0 1 7",
    ));
    let red = look(&floor_scene("void plastic floor 0 0 5 .8 0 0 0 0"));
    assert!(close(all, red, 1e-12), "{all} vs {red}");
}

/// A mixture whose sides reach no material acts as a pattern (Radiance's raymixture): in a
/// material's own chain, and on a surface with the material as the mixture's modifier.
#[test]
fn a_mixture_of_patterns_acts_as_a_pattern() {
    let want = look(&floor_scene("void plastic floor 0 0 5 .8 .6 .6 0 0"));
    let in_chain = look(&floor_scene(
        "void colorfunc red 0 0 3 1 0 0
\
         void mixfunc mx 2 red void 0 1 .25
\
         mx plastic floor 0 0 5 .8 .8 .8 0 0",
    ));
    assert!(close(in_chain, want, 1e-9), "{in_chain} vs {want}");
    let on_surface = look(&floor_scene(
        "void colorfunc red 0 0 3 1 0 0
\
         void plastic white 0 0 5 .8 .8 .8 0 0
\
         white mixfunc floor 2 red void 0 1 .25",
    ));
    assert!(close(on_surface, want, 1e-9), "{on_surface} vs {want}");
}

#[test]
fn wrong_chains_are_refused_with_file_and_line() {
    let err = |text: &str| scene(&floor_scene(text)).err().unwrap_or_default();
    let e = err("void plastic a 0 0 5 .5 .5 .5 0 0\na plastic floor 0 0 5 .5 .5 .5 0 0");
    assert!(
        e.contains("test.rad:4") && e.contains("conflicting material"),
        "{e}"
    );
    let e = err("void plastic a 0 0 5 .5 .5 .5 0 0\n\
         void mixfunc m 2 a void 0 1 .5\n\
         m plastic floor 0 0 5 .5 .5 .5 0 0");
    assert!(e.contains("test.rad:5") && e.contains("mixture"), "{e}");
    let e = err("void plastic a 0 0 5 .5 .5 .5 0 0\n\
         a mixfunc floor 2 a void 0 1 .5");
    assert!(e.contains("must be void"), "{e}");
    let e = err("void colorfunc floor 0 0 2 1 1");
    assert!(e.contains("takes 3 real arguments"), "{e}");
    // Radiance's types Tessera lacks are refused as unsupported.
    let prims = parse_scene_text(
        &floor_scene("void specfunc floor 2 sf . 0 2 380 780"),
        "t.rad",
        &ReadOptions::default(),
    )
    .unwrap();
    let e = Scene::build(&prims).err().unwrap().to_string();
    assert!(
        e.contains("t.rad:3") && e.contains("unsupported primitive type specfunc"),
        "{e}"
    );
}
