//! Scene images: a built scene's geometry (the surfaces of its top level and of every set
//! its instances place, or a mesh set's triangles, their names and places, and each
//! level's BVH) in one read-only file that processes map instead of building it, so that
//! every worker on a node shares one copy through the page cache (docs/batch.md, "One copy
//! of the scene per node"). The image also holds the text of each level's other
//! primitives (materials, modifiers, distant sources, instances; a mesh's modifiers; an
//! OBJ file's modifier names) and the fingerprint of all the scene's: a process that maps
//! it reads no scene or instanced file and parses no surface.
//!
//! Layout (little-endian): a 64-byte header — `TSSCNIMG`, the format version (u32), the
//! number of sections (u32), the file's length (u64), the 32-byte key (the job's scene
//! fingerprint), the CRC-32 of every byte after the header (u32) and 4 zero bytes — then
//! a table of `(offset u64, count u64)` per section, then the sections, each at an offset
//! that is a multiple of 16. Section 0 is JSON ([`Meta`]: the crate version, origin, sizes,
//! the distinct modifier and file names, the warnings, the primitives' text, each set's
//! file, kind and numbers); then [`PER_LEVEL`] sections per level (the top, then the sets
//! in the order they were finished), arrays of plain values ([`crate::geometry::plain`]):
//! objects, polygon records, polygon vertices, the other surfaces' fields, names (or a
//! mesh's vertices, normals, (u,v), flags and triangles), the BVH's nodes, leaf slots and
//! chunk roots.
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
use super::sets::{ObjectSet, SetGeom, SetSource};
use super::world::SceneGeometry;
use crate::geometry::bvh::{tree_in_bounds, Bvh};
use crate::geometry::cone::Cone;
use crate::geometry::plain::{bytes_of, Backing, Plain, Slab};
use crate::geometry::ring::Ring;
use crate::geometry::sphere::Sphere;
use crate::geometry::trimesh::TriMesh;
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
/// Section 0 is the JSON; then each level (the top, then each set in the order it was
/// loaded) has [`PER_LEVEL`] sections, from `1 + PER_LEVEL · level`.
const PER_LEVEL: usize = 13;
/// The most sets an image holds.
const MAX_SETS: usize = 1 << 20;
// A level of surfaces.
const O_LIST: usize = 0;
const O_POLYS: usize = 1;
const O_VERTS: usize = 2;
const O_SPHERES: usize = 3;
const O_CONES: usize = 4;
const O_RINGS: usize = 5;
const O_NAMES: usize = 6;
const O_NAME_END: usize = 7;
const O_MODIFIER: usize = 8;
const O_PLACE: usize = 9;
// A level of triangles (a mesh set).
const M_POS: usize = 0;
const M_NORMAL: usize = 1;
const M_UV: usize = 2;
const M_FLAGS: usize = 3;
const M_TRIS: usize = 4;
// Every level's BVH.
const B_NODES: usize = 10;
const B_SLOTS: usize = 11;
const B_CHUNKS: usize = 12;

/// A BVH's numbers (its bounds as the bits of f64: an empty one's are infinite, which JSON
/// cannot hold).
#[derive(Serialize, Deserialize)]
struct BvhMeta {
    lo: [u64; 3],
    hi: [u64; 3],
    pad: f64,
    eps: f64,
    count: u64,
}

impl BvhMeta {
    fn of(b: &Bvh) -> BvhMeta {
        BvhMeta {
            lo: b.lo.to_array().map(f64::to_bits),
            hi: b.hi.to_array().map(f64::to_bits),
            pad: b.pad,
            eps: b.eps,
            count: b.count as u64,
        }
    }
}

/// What a set was built from and its numbers.
#[derive(Serialize, Deserialize)]
struct SetMeta {
    file: String,
    /// Its number in the order sets were begun.
    started: u64,
    /// 0: an octree's surfaces; 1: a compiled mesh; 2: an OBJ mesh.
    kind: u8,
    /// The octree's primitives other than surfaces, or the compiled mesh's primitives.
    text: String,
    /// The scene files an unfrozen octree read.
    used: Vec<String>,
    /// An OBJ's modifier names and lines.
    names: Vec<(String, u32)>,
    origin: [f64; 3],
    /// The length tolerance its surfaces were built with.
    eps: f64,
    bounds: Option<([f64; 3], [f64; 3])>,
    full: Option<([f64; 3], [f64; 3])>,
    /// Surfaces or triangles.
    count: u64,
    modifiers: Vec<String>,
    files: Vec<String>,
    bvh: BvhMeta,
}

/// The small parts of an image.
#[derive(Serialize, Deserialize)]
struct Meta {
    /// The Tessera version that wrote it (another version's image is refused).
    tessera: String,
    origin: [f64; 3],
    size: f64,
    eps: f64,
    bvh: BvhMeta,
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
    /// The sets the scene's instances place, in the order they were loaded.
    sets: Vec<SetMeta>,
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
        Rest {
            fingerprint,
            text: rest_text(prims),
            scene_file: None,
        }
    }
}

/// The scene text of the primitives other than finite surfaces.
pub fn rest_text(prims: &[Primitive]) -> String {
    let kept: Vec<Primitive> = prims
        .iter()
        .filter(|p| !(SURFACE_TYPES.contains(&p.ptype.as_str()) && p.ptype != "source"))
        .cloned()
        .collect();
    let mut text = String::new();
    super::primitive::write_text(&kept, &mut text);
    text
}

/// An opened scene image (checked: header, checksum, key, version; its indices are
/// checked when its parts are taken).
pub struct SceneImage {
    keep: Arc<dyn Backing>,
    table: Vec<(usize, usize)>,
    meta: Meta,
}

/// The sections being written: the bytes and each section's `(offset, count)`.
struct Out {
    bytes: Vec<u8>,
    table: Vec<(u64, u64)>,
}

impl Out {
    /// Append `s`'s bytes at the next multiple of 16 as the next section.
    fn section<T: Plain>(&mut self, s: &[T]) {
        self.bytes.resize(self.bytes.len().next_multiple_of(16), 0);
        self.table.push((self.bytes.len() as u64, s.len() as u64));
        self.bytes.extend_from_slice(bytes_of(s));
    }

    /// A level's surfaces (its first [`B_NODES`] sections).
    fn objects(&mut self, o: &Objects) {
        self.section(&o.list);
        self.section(&o.polys);
        self.section(&o.verts);
        let spheres: Vec<f64> = o.spheres.iter().flat_map(|s| s.to_words()).collect();
        let cones: Vec<f64> = o.cones.iter().flat_map(|c| c.to_words()).collect();
        let rings: Vec<f64> = o.rings.iter().flat_map(|r| r.to_words()).collect();
        self.section(&spheres);
        self.section(&cones);
        self.section(&rings);
        self.section(&o.names);
        self.section(&o.name_end);
        self.section(&o.modifier);
        self.section(&o.place);
    }

    /// A level's triangles (its first [`B_NODES`] sections).
    fn mesh(&mut self, m: &TriMesh) {
        self.section(&m.pos);
        self.section(&m.normal);
        self.section(&m.uv);
        self.section(&m.flags);
        self.section(&m.tris);
        for _ in M_TRIS + 1..B_NODES {
            self.section::<u8>(&[]);
        }
    }

    /// A level's BVH (its last sections).
    fn bvh(&mut self, b: &Bvh) {
        self.section(&b.nodes);
        self.section(&b.slots);
        self.section(&b.chunks);
    }
}

/// The meta data of a set.
fn set_meta(set: &ObjectSet) -> SetMeta {
    let (kind, text, used, names) = match &set.source {
        SetSource::Octree { rest, used } => (0, rest.clone(), used.clone(), Vec::new()),
        SetSource::Mesh { prims } => (1, prims.clone(), Vec::new(), Vec::new()),
        SetSource::Obj { names } => (2, String::new(), Vec::new(), names.clone()),
    };
    let pair = |b: Option<(DVec3, DVec3)>| b.map(|(lo, hi)| (lo.to_array(), hi.to_array()));
    let (count, eps, modifiers, files) = match &set.geom {
        SetGeom::Objects(o) => (
            o.len() as u64,
            set.bvh.eps,
            o.modifiers.iter().map(|m| m.to_string()).collect(),
            o.files.iter().map(|f| f.to_string()).collect(),
        ),
        SetGeom::Mesh { mesh, .. } => (mesh.tris.len() as u64, mesh.eps, vec![], vec![]),
    };
    SetMeta {
        file: set.file.clone(),
        started: set.started as u64,
        kind,
        text,
        used,
        names,
        origin: set.origin.to_array(),
        eps,
        bounds: pair(set.bounds),
        full: pair(set.full),
        count,
        modifiers,
        files,
        bvh: BvhMeta::of(&set.bvh),
    }
}

/// The bytes of an image of `geom` (its top level and every set its instances place)
/// under `key`.
pub fn encode(key: &[u8; 32], rest: &Rest, geom: &SceneGeometry) -> Vec<u8> {
    let o = &geom.objects;
    let meta = Meta {
        tessera: env!("CARGO_PKG_VERSION").to_string(),
        origin: geom.origin.to_array(),
        size: geom.size,
        eps: geom.eps,
        bvh: BvhMeta::of(&geom.bvh),
        objects: o.len() as u64,
        placements: geom.placements.len() as u64,
        modifiers: o.modifiers.iter().map(|m| m.to_string()).collect(),
        files: o.files.iter().map(|f| f.to_string()).collect(),
        warnings: geom.warnings.clone(),
        prims_fingerprint: rest.fingerprint,
        rest: rest.text.clone(),
        scene_file: rest.scene_file,
        sets: geom.sets.iter().map(set_meta).collect(),
    };
    let json = serde_json::to_vec(&meta).unwrap_or_default();
    let sections = 1 + PER_LEVEL * (1 + geom.sets.len());
    let mut out = Out {
        bytes: vec![0u8; HEADER + sections * 16],
        table: Vec::with_capacity(sections),
    };
    out.section(&json);
    out.objects(o);
    out.bvh(&geom.bvh);
    for set in &geom.sets {
        match &set.geom {
            SetGeom::Objects(o) => out.objects(o),
            SetGeom::Mesh { mesh, .. } => out.mesh(mesh),
        }
        out.bvh(&set.bvh);
    }
    let Out {
        bytes: mut out,
        table,
    } = out;
    out.resize(out.len().next_multiple_of(16), 0);
    for (k, (off, n)) in table.iter().enumerate() {
        let at = HEADER + 16 * k;
        out[at..at + 8].copy_from_slice(&off.to_le_bytes());
        out[at + 8..at + 16].copy_from_slice(&n.to_le_bytes());
    }
    let len = out.len() as u64;
    out[0..8].copy_from_slice(MAGIC);
    out[8..12].copy_from_slice(&VERSION.to_le_bytes());
    out[12..16].copy_from_slice(&(sections as u32).to_le_bytes());
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
        if b.len() < HEADER || &b[0..8] != MAGIC {
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
        if u64_at(16) != b.len() as u64 {
            return Err("truncated or damaged (its length is not the one recorded)".into());
        }
        if crc32fast::hash(&b[HEADER..]) != u32_at(56) {
            return Err("damaged (checksum mismatch)".into());
        }
        if &b[24..56] != key {
            return Err("made for another scene or options (fingerprint differs)".into());
        }
        let sections = u32_at(12) as usize;
        if sections < 1 + PER_LEVEL || HEADER + 16 * sections > b.len() {
            return Err("damaged section table".into());
        }
        let mut table = Vec::with_capacity(sections);
        for k in 0..sections {
            let (off, n) = (u64_at(HEADER + 16 * k), u64_at(HEADER + 16 * k + 8));
            let (Ok(off), Ok(n)) = (usize::try_from(off), usize::try_from(n)) else {
                return Err("damaged section table".into());
            };
            table.push((off, n));
        }
        let (off, n) = table[0];
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
        if meta.sets.len() > MAX_SETS || sections != 1 + PER_LEVEL * (1 + meta.sets.len()) {
            return Err("damaged section table".into());
        }
        Ok(SceneImage { keep, table, meta })
    }

    /// Section `k` of level `level` as an array.
    fn slab<T: Plain>(&self, level: usize, k: usize) -> Result<Slab<T>, String> {
        let (off, n) = self.table[1 + PER_LEVEL * level + k];
        Slab::shared(&self.keep, off, n).map_err(|e| format!("level {level}, section {k}: {e}"))
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
        self.objects_at(0, m.objects, &m.modifiers, &m.files, materials, modifiers)
    }

    /// The top level's BVH over the objects and then the placements: `boxes` of them.
    pub fn bvh(&self, boxes: usize) -> Result<Bvh, String> {
        self.bvh_at(0, &self.meta.bvh, boxes)
    }

    /// The number of sets.
    pub fn sets(&self) -> usize {
        self.meta.sets.len()
    }

    /// The set begun as the `started`-th.
    pub fn set_begun(&self, started: usize) -> Option<usize> {
        self.meta
            .sets
            .iter()
            .position(|m| m.started == started as u64)
    }

    /// The number in the order sets were begun of set `k`.
    pub fn set_started(&self, k: usize) -> Option<usize> {
        self.meta.sets.get(k).map(|m| m.started as usize)
    }

    /// Set `k`'s file as named and what it was built from: the builder checks the name and
    /// builds the set's other primitives from the source.
    pub fn set_source(&self, k: usize) -> Option<(&str, SetSource)> {
        let m = self.meta.sets.get(k)?;
        let source = match m.kind {
            0 => SetSource::Octree {
                rest: m.text.clone(),
                used: m.used.clone(),
            },
            1 => SetSource::Mesh {
                prims: m.text.clone(),
            },
            _ => SetSource::Obj {
                names: m.names.clone(),
            },
        };
        Some((&m.file, source))
    }

    /// Set `k`'s origin and length tolerance, and its bounds (relative to the origin) and
    /// bounds with its instances' (the file's coordinates).
    #[allow(clippy::type_complexity)]
    pub fn set_frame(
        &self,
        k: usize,
    ) -> Option<(DVec3, f64, Option<(DVec3, DVec3)>, Option<(DVec3, DVec3)>)> {
        let m = self.meta.sets.get(k)?;
        let pair = |b: Option<([f64; 3], [f64; 3])>| {
            b.map(|(lo, hi)| (DVec3::from_array(lo), DVec3::from_array(hi)))
        };
        Some((
            DVec3::from_array(m.origin),
            m.eps,
            pair(m.bounds),
            pair(m.full),
        ))
    }

    /// Set `k`'s surfaces (an octree's), checked against `materials` materials and
    /// `modifiers` modifiers, with its BVH.
    pub fn set_objects(
        &self,
        k: usize,
        materials: usize,
        modifiers: usize,
    ) -> Result<(Objects, Bvh), String> {
        let m = self.meta.sets.get(k).ok_or("no such set")?;
        if m.kind != 0 {
            return Err(format!("set {k} is not an octree"));
        }
        let o = self.objects_at(1 + k, m.count, &m.modifiers, &m.files, materials, modifiers)?;
        let b = self.bvh_at(1 + k, &m.bvh, o.len())?;
        Ok((o, b))
    }

    /// Set `k`'s triangles (a mesh's) with its BVH, checked: vertex indices within the
    /// vertices, modifier indices below `modifiers` (or −1), per-vertex arrays of one
    /// length.
    pub fn set_mesh(&self, k: usize, modifiers: usize) -> Result<(TriMesh, Bvh), String> {
        let m = self.meta.sets.get(k).ok_or("no such set")?;
        if m.kind == 0 {
            return Err(format!("set {k} is not a mesh"));
        }
        let l = 1 + k;
        let mesh = TriMesh {
            pos: self.slab(l, M_POS)?,
            normal: self.slab(l, M_NORMAL)?,
            uv: self.slab(l, M_UV)?,
            flags: self.slab(l, M_FLAGS)?,
            tris: self.slab(l, M_TRIS)?,
            eps: m.eps,
        };
        let nv = mesh.pos.len();
        let ok = mesh.normal.len() == nv
            && mesh.uv.len() == nv
            && mesh.flags.len() == nv
            && mesh.tris.len() as u64 == m.count
            && m.eps.is_finite()
            && m.eps > 0.0
            && mesh.pos.iter().all(|p| p.is_finite())
            && mesh.tris.iter().all(|t| {
                t.v.iter().all(|&v| (v as usize) < nv)
                    && (t.modifier == -1 || (t.modifier >= 0 && (t.modifier as usize) < modifiers))
            });
        if !ok {
            return Err("a damaged mesh".into());
        }
        let b = self.bvh_at(l, &m.bvh, mesh.tris.len())?;
        Ok((mesh, b))
    }

    /// Level `level`'s objects (`count` of them), checked.
    fn objects_at(
        &self,
        level: usize,
        count: u64,
        modifier_names: &[String],
        file_names: &[String],
        materials: usize,
        modifiers: usize,
    ) -> Result<Objects, String> {
        // The other surfaces' records: `w` words each, decoded (and checked) by `decode`.
        fn records<T>(
            s: &[f64],
            w: usize,
            decode: impl Fn(&[f64]) -> Option<T>,
            what: &str,
        ) -> Result<Vec<T>, String> {
            if !s.len().is_multiple_of(w) {
                return Err(format!("damaged {what}s: not whole records"));
            }
            s.chunks_exact(w)
                .map(&decode)
                .collect::<Option<Vec<T>>>()
                .ok_or_else(|| format!("a damaged {what}"))
        }
        let spheres = records(
            &self.slab(level, O_SPHERES)?,
            Sphere::WORDS,
            Sphere::from_words,
            "sphere",
        )?;
        let cones = records(
            &self.slab(level, O_CONES)?,
            Cone::WORDS,
            Cone::from_words,
            "cone",
        )?;
        let rings = records(
            &self.slab(level, O_RINGS)?,
            Ring::WORDS,
            Ring::from_words,
            "ring",
        )?;
        let o = Objects {
            list: self.slab(level, O_LIST)?,
            polys: self.slab(level, O_POLYS)?,
            verts: self.slab(level, O_VERTS)?,
            spheres,
            cones,
            rings,
            names: self.slab(level, O_NAMES)?,
            name_end: self.slab(level, O_NAME_END)?,
            modifier: self.slab(level, O_MODIFIER)?,
            place: self.slab(level, O_PLACE)?,
            modifiers: modifier_names.iter().map(|s| s.as_str().into()).collect(),
            files: file_names.iter().map(|s| s.as_str().into()).collect(),
            modifier_ids: Default::default(),
            file_ids: Default::default(),
        };
        let n = o.list.len();
        if n as u64 != count || o.name_end.len() != n || o.modifier.len() != n || o.place.len() != n
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

    /// Level `level`'s BVH over `boxes` boxes, checked.
    fn bvh_at(&self, level: usize, m: &BvhMeta, boxes: usize) -> Result<Bvh, String> {
        let bvh = Bvh {
            nodes: self.slab(level, B_NODES)?,
            slots: self.slab(level, B_SLOTS)?,
            chunks: self.slab(level, B_CHUNKS)?,
            lo: DVec3::from_array(m.lo.map(f64::from_bits)),
            hi: DVec3::from_array(m.hi.map(f64::from_bits)),
            pad: m.pad,
            eps: m.eps,
            count: m.count as usize,
        };
        if bvh.count != boxes
            || !tree_in_bounds(&bvh.nodes)
            || bvh.chunks.iter().any(|&r| r as usize >= bvh.nodes.len())
            || bvh
                .slots
                .iter()
                .any(|&s| s != u32::MAX && s as usize >= boxes.max(bvh.chunks.len()))
            || ![bvh.pad, bvh.eps].iter().all(|x| x.is_finite())
            || !(bvh.nodes.is_empty() || bvh.lo.is_finite() && bvh.hi.is_finite())
        {
            return Err("a damaged BVH".into());
        }
        Ok(bvh)
    }
}
