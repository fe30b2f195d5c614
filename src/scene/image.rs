//! Scene images: a built scene's top-level geometry (its surfaces, their names and places,
//! and the BVH) in one read-only file that processes map instead of building it, so that
//! every worker on a node shares one copy through the page cache (docs/batch.md, "One copy
//! of the scene per node"). The image also holds the text of the scene's other primitives
//! (materials, modifiers, distant sources, instances) and the fingerprint of all of them:
//! a process that maps it reads no scene file and parses no surface.
//!
//! Layout (little-endian): a 64-byte header — `TSSCNIMG`, the format version (u32), the
//! number of sections (u32), the file's length (u64), the 32-byte key (the job's scene
//! fingerprint), the CRC-32 of every byte after the header (u32) and 4 zero bytes — then
//! a table of `(offset u64, count u64)` per section, then the sections, each at an offset
//! that is a multiple of 16. Section 0 is JSON ([`Meta`]: the crate version, origin, sizes,
//! the distinct modifier and file names, the warnings); the others are arrays of plain
//! values ([`crate::geometry::plain`]): objects, polygon records, polygon vertices, the
//! other surfaces' fields, names, the BVH's nodes, leaf slots and chunk roots.
//!
//! An image is written once (to a temporary name, synced, renamed into place) and never
//! changed: a mapping of it stays valid. Opening one checks that it is a regular file within
//! [`MAX_IMAGE`] bytes, its header, length, checksum, version, key and the Tessera version
//! that wrote it; then, before use, every index in it (surface kinds and indices, polygon
//! vertex ranges, material and modifier ids, name ends, BVH children and leaves) against
//! the arrays it indexes. A damaged or foreign image is refused with the reason.

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::object::{Objects, KIND_CONE, KIND_POLYGON, KIND_RING, KIND_SPHERE, MAX_OF_KIND};
use super::world::SceneGeometry;
use crate::geometry::bvh::{tree_in_bounds, Bvh};
use crate::geometry::cone::Cone;
use crate::geometry::plain::{bytes_of, Backing, Plain, Slab};
use crate::geometry::ring::Ring;
use crate::geometry::sphere::Sphere;
use crate::scene::object::ModRef;
use crate::scene::primitive::Primitive;
use crate::scene::reader::{parse_scene_text, ReadOptions};
use crate::scene::world::SURFACE_TYPES;

/// The first bytes of a scene image.
pub const MAGIC: &[u8; 8] = b"TSSCNIMG";
/// The format's version.
pub const VERSION: u32 = 1;
/// The largest image read (64 GiB).
pub const MAX_IMAGE: u64 = 64 << 30;
/// Header bytes.
const HEADER: usize = 64;
/// Sections, in this order.
const SECTIONS: usize = 14;
const S_META: usize = 0;
const S_OBJECTS: usize = 1;
const S_POLYS: usize = 2;
const S_VERTS: usize = 3;
const S_SPHERES: usize = 4;
const S_CONES: usize = 5;
const S_RINGS: usize = 6;
const S_NAMES: usize = 7;
const S_NAME_END: usize = 8;
const S_MODIFIER: usize = 9;
const S_PLACE: usize = 10;
const S_NODES: usize = 11;
const S_SLOTS: usize = 12;
const S_CHUNKS: usize = 13;

/// The small parts of an image.
#[derive(Serialize, Deserialize)]
struct Meta {
    /// The Tessera version that wrote it (another version's image is refused).
    tessera: String,
    origin: [f64; 3],
    size: f64,
    eps: f64,
    bvh_lo: [f64; 3],
    bvh_hi: [f64; 3],
    bvh_pad: f64,
    bvh_eps: f64,
    bvh_count: u64,
    objects: u64,
    placements: u64,
    modifiers: Vec<String>,
    files: Vec<String>,
    warnings: Vec<String>,
    /// The fingerprint of all the scene's primitives (before the files they read).
    prims_fingerprint: [u8; 32],
    /// The scene text of the primitives other than finite surfaces (materials, modifiers,
    /// distant sources, instances): what a process builds itself.
    rest: String,
    /// The length and CRC-32 of the scene file the primitives were written to, if any (a
    /// job's `scene.rad`: a process that maps the image checks that it is unchanged).
    scene_file: Option<(u64, u32)>,
}

/// What an image keeps of a scene's primitives: their fingerprint and the text of all but
/// the finite surfaces, so that a process that maps the image reads no scene file.
pub struct Rest {
    /// [`crate::ambient::fingerprint::fingerprint`] of all the primitives.
    pub fingerprint: [u8; 32],
    /// The primitives other than finite surfaces, as scene text.
    pub text: String,
    /// The length and CRC-32 of the file that holds all the primitives as text, if any.
    pub scene_file: Option<(u64, u32)>,
}

impl Rest {
    /// The rest of `prims`, whose fingerprint is `fingerprint`.
    pub fn of(prims: &[Primitive], fingerprint: [u8; 32]) -> Rest {
        let kept: Vec<Primitive> = prims
            .iter()
            .filter(|p| !(SURFACE_TYPES.contains(&p.ptype.as_str()) && p.ptype != "source"))
            .cloned()
            .collect();
        let mut text = String::new();
        super::primitive::write_text(&kept, &mut text);
        Rest {
            fingerprint,
            text,
            scene_file: None,
        }
    }
}

/// An opened scene image (checked: header, checksum, key, version; its indices are
/// checked when its parts are taken).
pub struct SceneImage {
    keep: Arc<dyn Backing>,
    table: Vec<(usize, usize)>,
    meta: Meta,
}

/// Append `s`'s bytes at the next multiple of 16, recording `(offset, count)`.
fn section<T: Plain>(out: &mut Vec<u8>, table: &mut Vec<(u64, u64)>, s: &[T]) {
    out.resize(out.len().next_multiple_of(16), 0);
    table.push((out.len() as u64, s.len() as u64));
    out.extend_from_slice(bytes_of(s));
}

/// The bytes of an image of `geom` (only its top level: the sets its instances place are
/// built by each process) under `key`.
pub fn encode(key: &[u8; 32], rest: &Rest, geom: &SceneGeometry) -> Vec<u8> {
    let o = &geom.objects;
    let b = &geom.bvh;
    let meta = Meta {
        tessera: env!("CARGO_PKG_VERSION").to_string(),
        origin: geom.origin.to_array(),
        size: geom.size,
        eps: geom.eps,
        bvh_lo: b.lo.to_array(),
        bvh_hi: b.hi.to_array(),
        bvh_pad: b.pad,
        bvh_eps: b.eps,
        bvh_count: b.count as u64,
        objects: o.len() as u64,
        placements: geom.placements.len() as u64,
        modifiers: o.modifiers.iter().map(|m| m.to_string()).collect(),
        files: o.files.iter().map(|f| f.to_string()).collect(),
        warnings: geom.warnings.clone(),
        prims_fingerprint: rest.fingerprint,
        rest: rest.text.clone(),
        scene_file: rest.scene_file,
    };
    let json = serde_json::to_vec(&meta).unwrap_or_default();
    let words = |n: usize, w: &mut dyn FnMut(&mut Vec<f64>)| {
        let mut v = Vec::with_capacity(n);
        w(&mut v);
        v
    };
    let spheres = words(o.spheres.len() * Sphere::WORDS, &mut |v| {
        o.spheres.iter().for_each(|s| v.extend(s.to_words()))
    });
    let cones = words(o.cones.len() * Cone::WORDS, &mut |v| {
        o.cones.iter().for_each(|s| v.extend(s.to_words()))
    });
    let rings = words(o.rings.len() * Ring::WORDS, &mut |v| {
        o.rings.iter().for_each(|s| v.extend(s.to_words()))
    });
    let mut out = vec![0u8; HEADER + SECTIONS * 16];
    let mut table = Vec::with_capacity(SECTIONS);
    section(&mut out, &mut table, &json);
    section(&mut out, &mut table, &o.list);
    section(&mut out, &mut table, &o.polys);
    section(&mut out, &mut table, &o.verts);
    section(&mut out, &mut table, &spheres);
    section(&mut out, &mut table, &cones);
    section(&mut out, &mut table, &rings);
    section(&mut out, &mut table, &o.names);
    section(&mut out, &mut table, &o.name_end);
    section(&mut out, &mut table, &o.modifier);
    section(&mut out, &mut table, &o.place);
    section(&mut out, &mut table, &b.nodes);
    section(&mut out, &mut table, &b.slots);
    section(&mut out, &mut table, &b.chunks);
    out.resize(out.len().next_multiple_of(16), 0);
    for (k, (off, n)) in table.iter().enumerate() {
        let at = HEADER + 16 * k;
        out[at..at + 8].copy_from_slice(&off.to_le_bytes());
        out[at + 8..at + 16].copy_from_slice(&n.to_le_bytes());
    }
    let len = out.len() as u64;
    out[0..8].copy_from_slice(MAGIC);
    out[8..12].copy_from_slice(&VERSION.to_le_bytes());
    out[12..16].copy_from_slice(&(SECTIONS as u32).to_le_bytes());
    out[16..24].copy_from_slice(&len.to_le_bytes());
    out[24..56].copy_from_slice(key);
    let crc = crc32fast::hash(&out[HEADER..]);
    out[56..60].copy_from_slice(&crc.to_le_bytes());
    out
}

impl SceneImage {
    /// Open and check the image at `path` for the scene of fingerprint `key`.
    pub fn open(path: &Path, key: &[u8; 32]) -> Result<SceneImage, String> {
        let file = crate::safefile::open_regular(path, false).map_err(|e| e.to_string())?;
        let len = file.metadata().map_err(|e| e.to_string())?.len();
        if len > MAX_IMAGE {
            return Err(format!("{len} bytes, more than a scene image may have"));
        }
        // SAFETY: images are written once under a temporary name and renamed into place,
        // never changed in place (module docs), so the mapped bytes do not change.
        let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| e.to_string())?;
        SceneImage::from_backing(Arc::new(map), key)
    }

    /// Check the bytes of an image (what [`SceneImage::open`] maps).
    pub fn from_backing(keep: Arc<dyn Backing>, key: &[u8; 32]) -> Result<SceneImage, String> {
        let b = keep.bytes();
        if b.len() < HEADER + SECTIONS * 16 || &b[0..8] != MAGIC {
            return Err("not a scene image".into());
        }
        let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap_or([0; 4]));
        let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap_or([0; 8]));
        let version = u32_at(8);
        if version != VERSION {
            return Err(format!(
                "format version {version} (this Tessera reads {VERSION})"
            ));
        }
        if u32_at(12) as usize != SECTIONS || u64_at(16) != b.len() as u64 {
            return Err("truncated or damaged (its length is not the one recorded)".into());
        }
        if crc32fast::hash(&b[HEADER..]) != u32_at(56) {
            return Err("damaged (checksum mismatch)".into());
        }
        if &b[24..56] != key {
            return Err("made for another scene or options (fingerprint differs)".into());
        }
        let mut table = Vec::with_capacity(SECTIONS);
        for k in 0..SECTIONS {
            let (off, n) = (u64_at(HEADER + 16 * k), u64_at(HEADER + 16 * k + 8));
            let (Ok(off), Ok(n)) = (usize::try_from(off), usize::try_from(n)) else {
                return Err("damaged section table".into());
            };
            table.push((off, n));
        }
        let (off, n) = table[S_META];
        let json = off
            .checked_add(n)
            .and_then(|end| b.get(off..end))
            .ok_or("damaged section table")?;
        let meta: Meta = serde_json::from_slice(json).map_err(|e| format!("damaged: {e}"))?;
        if meta.tessera != env!("CARGO_PKG_VERSION") {
            return Err(format!(
                "written by Tessera {} (this is {})",
                meta.tessera,
                env!("CARGO_PKG_VERSION")
            ));
        }
        Ok(SceneImage { keep, table, meta })
    }

    fn slab<T: Plain>(&self, k: usize) -> Result<Slab<T>, String> {
        let (off, n) = self.table[k];
        Slab::shared(&self.keep, off, n).map_err(|e| format!("section {k}: {e}"))
    }

    /// The scene origin, the size of its bounding cube and its length tolerance.
    pub fn frame(&self) -> (DVec3, f64, f64) {
        let m = &self.meta;
        (DVec3::from_array(m.origin), m.size, m.eps)
    }

    /// The primitives other than finite surfaces (read with `ro`, which only gives the
    /// limits: the text has no commands), and the fingerprint of all of them.
    pub fn rest(&self, ro: &ReadOptions) -> Result<(Vec<Primitive>, [u8; 32]), String> {
        let prims =
            parse_scene_text(&self.meta.rest, "scene.img", ro).map_err(|e| e.to_string())?;
        Ok((prims, self.meta.prims_fingerprint))
    }

    /// The length and CRC-32 of the scene file its primitives were written to, if any.
    pub fn scene_file(&self) -> Option<(u64, u32)> {
        self.meta.scene_file
    }

    /// The warnings the build gave.
    pub fn warnings(&self) -> &[String] {
        &self.meta.warnings
    }

    /// The number of placements of instanced sets the BVH holds after the objects.
    pub fn placements(&self) -> usize {
        self.meta.placements as usize
    }

    /// The top level's objects, checked against `materials` materials and `modifiers`
    /// modifiers.
    pub fn objects(&self, materials: usize, modifiers: usize) -> Result<Objects, String> {
        let m = &self.meta;
        let words = |k: usize, w: usize| -> Result<Slab<f64>, String> {
            let s = self.slab::<f64>(k)?;
            if s.len() % w != 0 {
                return Err(format!("section {k}: not whole records"));
            }
            Ok(s)
        };
        let decode = |k: usize, w: usize| -> Result<Vec<Vec<f64>>, String> {
            Ok(words(k, w)?.chunks_exact(w).map(|c| c.to_vec()).collect())
        };
        let spheres = decode(S_SPHERES, Sphere::WORDS)?
            .iter()
            .map(|w| Sphere::from_words(w))
            .collect::<Option<Vec<_>>>()
            .ok_or("a damaged sphere")?;
        let cones = decode(S_CONES, Cone::WORDS)?
            .iter()
            .map(|w| Cone::from_words(w))
            .collect::<Option<Vec<_>>>()
            .ok_or("a damaged cone")?;
        let rings = decode(S_RINGS, Ring::WORDS)?
            .iter()
            .map(|w| Ring::from_words(w))
            .collect::<Option<Vec<_>>>()
            .ok_or("a damaged ring")?;
        let o = Objects {
            list: self.slab(S_OBJECTS)?,
            polys: self.slab(S_POLYS)?,
            verts: self.slab(S_VERTS)?,
            spheres,
            cones,
            rings,
            names: self.slab(S_NAMES)?,
            name_end: self.slab(S_NAME_END)?,
            modifier: self.slab(S_MODIFIER)?,
            place: self.slab(S_PLACE)?,
            modifiers: m.modifiers.iter().map(|s| s.as_str().into()).collect(),
            files: m.files.iter().map(|s| s.as_str().into()).collect(),
            ..Objects::default()
        };
        let n = o.list.len();
        if n as u64 != m.objects
            || o.name_end.len() != n
            || o.modifier.len() != n
            || o.place.len() != n
        {
            return Err("object counts disagree".into());
        }
        if o.polys.len() > MAX_OF_KIND || !o.polys.iter().all(|p| p.valid_in(o.verts.len())) {
            return Err("a damaged polygon".into());
        }
        let kinds = [
            (KIND_POLYGON, o.polys.len()),
            (KIND_SPHERE, o.spheres.len()),
            (KIND_CONE, o.cones.len()),
            (KIND_RING, o.rings.len()),
        ];
        let id_ok = |r: ModRef| match r {
            ModRef::Void => true,
            ModRef::Material(i) => i < materials,
            ModRef::Modifier(i) => i < modifiers,
        };
        for ob in o.list.iter() {
            let ok = kinds
                .iter()
                .any(|&(k, len)| ob.kind() == k && ob.index() < len)
                && ob.material().is_none_or(|i| i < materials)
                && id_ok(ob.chain());
            if !ok {
                return Err("an object refers to what the scene does not have".into());
            }
        }
        let mut prev = 0;
        for &e in o.name_end.iter() {
            if e < prev || e > o.names.len() as u64 {
                return Err("damaged names".into());
            }
            prev = e;
        }
        if o.modifier.iter().any(|&i| i as usize >= o.modifiers.len())
            || o.place.iter().any(|&[f, _]| f as usize >= o.files.len())
        {
            return Err("damaged modifier names or places".into());
        }
        Ok(o)
    }

    /// The BVH over the objects and then the placements: `boxes` of them.
    pub fn bvh(&self, boxes: usize) -> Result<Bvh, String> {
        let m = &self.meta;
        let bvh = Bvh {
            nodes: self.slab(S_NODES)?,
            slots: self.slab(S_SLOTS)?,
            chunks: self.slab(S_CHUNKS)?,
            lo: DVec3::from_array(m.bvh_lo),
            hi: DVec3::from_array(m.bvh_hi),
            pad: m.bvh_pad,
            eps: m.bvh_eps,
            count: m.bvh_count as usize,
        };
        if bvh.count != boxes
            || !tree_in_bounds(&bvh.nodes)
            || bvh.chunks.iter().any(|&r| r as usize >= bvh.nodes.len())
            || bvh
                .slots
                .iter()
                .any(|&s| s != u32::MAX && s as usize >= boxes.max(bvh.chunks.len()))
            || ![bvh.pad, bvh.eps].iter().all(|x| x.is_finite())
            || !(bvh.lo.is_finite() && bvh.hi.is_finite())
        {
            return Err("a damaged BVH".into());
        }
        Ok(bvh)
    }
}
