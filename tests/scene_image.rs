//! Scene images (src/scene/image.rs): a scene built with its top level taken from an image
//! traces exactly like the scene built from its primitives, and a damaged, foreign or
//! inconsistent image is refused with the reason, never used.

use std::sync::Arc;

use glam::DVec3;
use tessera::geometry::plain::{Aligned, Backing};
use tessera::render::world::Scene;
use tessera::scene::image::{encode, Rest, SceneImage};
use tessera::scene::reader::parse_scene_text;
use tessera::scene::{Primitive, ReadOptions};

/// Every kind of finite surface, a pattern, a distant source, an instance-free scene with
/// a polygon of many vertices and a zero-area one (a warning).
const SCENE: &str = "
void plastic red 0 0 5 .7 .1 .1 0 0
void brightfunc stripes 2 and(1,1) . 0 0
stripes plastic striped 0 0 5 .5 .5 .5 0 0
void light lamp 0 0 3 10 10 10
red polygon floor 0 0 12 -5 -5 0  5 -5 0  5 5 0  -5 5 0
striped polygon wall 0 0 18 -5 5 0  0 5 0  5 5 0  5 5 3  0 5 4  -5 5 3
red polygon flat 0 0 9 0 0 1  1 1 1  2 2 1
red sphere ball 0 0 4 1 1 1 .5
red bubble inner 0 0 4 -1 1 1 .4
striped cone horn 0 0 8 2 -2 0 2 -2 1 .5 .2
red cylinder post 0 0 7 -2 -2 0 -2 -2 2 .2
red tube pipe 0 0 7 -3 0 0 -3 0 2 .1
lamp ring shade 0 0 8 0 0 2.9 0 0 -1 .1 .4
lamp source sun 0 0 4 1 1 1 .5
";

fn prims(text: &str) -> Vec<Primitive> {
    parse_scene_text(text, "scene.rad", &ReadOptions::default()).unwrap()
}

fn image_of(text: &str, key: &[u8; 32]) -> Vec<u8> {
    let p = prims(text);
    let scene = Scene::build(&p).unwrap();
    encode(key, &Rest::of(&p, [1; 32]), &scene.geom)
}

fn open(bytes: &[u8], key: &[u8; 32]) -> Result<SceneImage, String> {
    let keep: Arc<dyn Backing> = Arc::new(Aligned::new(bytes));
    SceneImage::from_backing(keep, key)
}

/// The scene built from an image alone: its own primitives (all but the finite surfaces)
/// and its geometry.
fn mapped(image: &SceneImage) -> Result<Scene, String> {
    let (rest, fp) = image.rest(&ReadOptions::default())?;
    assert_eq!(fp, [1; 32]);
    assert!(rest
        .iter()
        .all(|p| !["polygon", "sphere", "cone", "ring"].contains(&p.ptype.as_str())));
    Scene::build_with_image(rest, &ReadOptions::default(), image).unwrap()
}

/// Rays from a grid of points in many directions: what each scene hits, where, its normal,
/// material and chain.
fn trace_all(s: &Scene) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..400 {
        let t = i as f64 * 0.731;
        let org =
            DVec3::new(4.0 * t.sin(), 4.0 * (1.3 * t).cos(), 1.5 + (0.7 * t).sin()) - s.origin;
        let dir = DVec3::new((2.1 * t).cos(), (1.7 * t).sin(), (0.9 * t).cos() - 0.3).normalize();
        let hit = s.closest(org, dir, 1e10, |_, _| false);
        out.push(match hit {
            None => "miss".into(),
            Some((r, t)) => {
                let (p, n, flat) = s.hit_geom(r, org, dir, t);
                let o = &s.objects[r.obj];
                format!(
                    "{} {t:?} {p:?} {n:?} {flat} {:?} {:?} {} {}",
                    r.obj,
                    o.material(),
                    o.chain(),
                    s.objects.name(r.obj),
                    s.objects.loc(r.obj)
                )
            }
        });
    }
    out
}

#[test]
fn a_scene_from_its_image_traces_like_the_built_one() {
    let key = [7u8; 32];
    let p = prims(SCENE);
    let built = Scene::build(&p).unwrap();
    let rest = Rest::of(&p, [1; 32]);
    let bytes = encode(&key, &rest, &built.geom);
    let image = open(&bytes, &key).unwrap();
    let from_image = mapped(&image).unwrap();
    assert!(from_image.objects.len() >= 8);
    assert_eq!(from_image.objects.len(), built.objects.len());
    assert_eq!(from_image.origin, built.origin);
    assert_eq!(from_image.eps, built.eps);
    assert_eq!(from_image.warnings, built.warnings);
    assert!(built.warnings.iter().any(|w| w.contains("zero area")));
    assert_eq!(from_image.distant.len(), 1);
    let (a, b) = (trace_all(&built), trace_all(&from_image));
    assert!(a.iter().filter(|h| *h != "miss").count() > 100);
    assert_eq!(a, b);
    // Encoding the scene from the image gives the same bytes.
    assert_eq!(encode(&key, &rest, &from_image.geom), bytes);
}

#[test]
fn damaged_foreign_or_inconsistent_images_are_refused() {
    let key = [3u8; 32];
    let good = image_of(SCENE, &key);
    assert!(open(&good, &key).is_ok());
    let refused = |b: &[u8], k: &[u8; 32], want: &str| {
        let e = open(b, k)
            .err()
            .unwrap_or_else(|| panic!("accepted ({want})"));
        assert!(e.contains(want), "{e} (wanted {want})");
    };
    refused(&good, &[4u8; 32], "fingerprint");
    refused(&good[..good.len() - 16], &key, "length");
    refused(b"not an image", &key, "not a scene image");
    let mut flipped = good.clone();
    let k = flipped.len() / 2;
    flipped[k] ^= 0x10;
    refused(&flipped, &key, "checksum");
    let mut version = good.clone();
    version[8] = 99;
    refused(&version, &key, "version");
    // Damage that keeps the checksum valid (as a foreign writer could): each index is
    // checked before use.
    let fix_crc = |b: &mut Vec<u8>| {
        let c = crc32fast::hash(&b[64..]);
        b[56..60].copy_from_slice(&c.to_le_bytes());
    };
    let section = |b: &[u8], s: usize| {
        let at = 64 + 16 * s;
        let off = u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) as usize;
        let n = u64::from_le_bytes(b[at + 8..at + 16].try_into().unwrap()) as usize;
        (off, n)
    };
    let later = |b: &[u8]| mapped(&open(b, &key).unwrap()).err().unwrap();
    // An object's index beyond its kind's array (section 1, the objects: 16 bytes each).
    let mut bad = good.clone();
    let (off, _) = section(&bad, 1);
    bad[off..off + 4].copy_from_slice(&0x3fff_ffffu32.to_le_bytes());
    fix_crc(&mut bad);
    assert!(later(&bad).contains("does not have"));
    // A material id beyond the scene's materials.
    let mut bad = good.clone();
    bad[off + 4..off + 8].copy_from_slice(&1000u32.to_le_bytes());
    fix_crc(&mut bad);
    assert!(later(&bad).contains("does not have"));
    // A polygon's vertex range beyond the pool (section 2: 96-byte records; `first` at 80).
    let mut bad = good.clone();
    let (poff, _) = section(&bad, 2);
    bad[poff + 80..poff + 84].copy_from_slice(&u32::MAX.to_le_bytes());
    fix_crc(&mut bad);
    assert!(later(&bad).contains("polygon"));
    // A BVH node whose child points back at itself (section 11: 80-byte nodes;
    // child_base_idx at 16).
    let mut bad = good.clone();
    let (noff, nn) = section(&bad, 11);
    assert!(nn > 0);
    bad[noff + 16..noff + 20].copy_from_slice(&0u32.to_le_bytes());
    bad[noff + 15] = 0xff;
    fix_crc(&mut bad);
    assert!(later(&bad).contains("BVH"));
}
