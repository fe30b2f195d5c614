//! Compiled meshes (`.rtm`) written by Radiance's `obj2mesh` (radiance-formats.md §7): a
//! header, the magic `319 + objsize`, the cube, the (u,v) limits, a tree (skipped), the
//! materials' scene (frozen, as in an octree) and patches of up to 256 quantised vertices
//! (positions, optional normal codes and (u,v)) with their triangles and the triangles
//! joining them to other patches.

use std::sync::Arc;

use glam::{DVec3, Vec3};

use super::binio::BinReader;
use super::octree::{read_frozen_scene, skip_tree};
use super::primitive::Primitive;

pub use crate::geometry::trimesh::{MeshTri, HAS_NORMAL, HAS_UV};

/// A mesh file, decoded.
#[derive(Debug, Default)]
pub struct MeshFile {
    /// Header lines after `#?RADIANCE`.
    pub header: Vec<String>,
    /// The materials (and patterns) triangles refer to.
    pub prims: Vec<Primitive>,
    /// Vertex positions (the file's coordinates).
    pub pos: Vec<DVec3>,
    /// Vertex normals (unit; zero where [`HAS_NORMAL`] is not set).
    pub normal: Vec<Vec3>,
    /// Vertex (u,v) (zero where [`HAS_UV`] is not set).
    pub uv: Vec<[f64; 2]>,
    /// [`HAS_NORMAL`] | [`HAS_UV`] per vertex.
    pub flags: Vec<u8>,
    /// Triangles.
    pub tris: Vec<MeshTri>,
}

/// Decode a normal code (radiance-formats.md §7.1); None for code 0.
pub fn decode_normal(code: u32) -> Option<Vec3> {
    if code == 0 {
        return None;
    }
    const SCALE: f64 = 11584.5;
    let d1 = ((code >> 5) & 0x1fff) as f64 / SCALE;
    let d2 = ((code >> 18) & 0x1fff) as f64 / SCALE;
    let d3 = (1.0 - d1 * d1 - d2 * d2).max(0.0).sqrt();
    let f1x = code & 8 != 0;
    let f2z = code & 16 != 0;
    // (d1, d2, derived) → axes.
    let (a1, a2, a3) = match (f2z, f1x) {
        (false, false) => (1, 0, 2),
        (false, true) => (0, 1, 2),
        (true, false) => (1, 2, 0),
        (true, true) => (0, 2, 1),
    };
    let mut v = [0.0f64; 3];
    v[a1] = d1;
    v[a2] = d2;
    v[a3] = d3;
    for (i, c) in v.iter_mut().enumerate() {
        if code & (1 << i) != 0 {
            *c = -*c;
        }
    }
    let n = DVec3::from(v).normalize_or_zero();
    (n != DVec3::ZERO).then(|| n.as_vec3())
}

/// Parse a mesh file's bytes (`name`: the file, for locations).
pub fn parse_mesh(bytes: &[u8], name: &str) -> Result<MeshFile, String> {
    let mut r = BinReader::new(bytes, "mesh");
    let header = r.header("Radiance_tmesh")?;
    let at = r.pos();
    let magic = r.int(2, "the magic number")?;
    let objsize = magic - 319;
    if !(1..=8).contains(&objsize) {
        return Err(format!(
            "incompatible mesh format (magic number {magic} at byte {at})"
        ));
    }
    let objsize = objsize as usize;
    let mut org = DVec3::ZERO;
    for i in 0..3 {
        org[i] = r.text_real("the cube origin")?;
    }
    let size = r.text_real("the cube size")?;
    if size <= 0.0 {
        return Err(format!("bad cube size {size}"));
    }
    let mut lim = [0.0f64; 4];
    for l in lim.iter_mut() {
        *l = r.real("the (u,v) limits")?;
    }
    skip_tree(&mut r, objsize, None)?;
    let file: Arc<str> = Arc::from(name);
    let prims = read_frozen_scene(&mut r, objsize, &file)?;
    let npatches = r.count(4, 1 << 24, "patch count")?;
    let mut m = MeshFile {
        header,
        prims,
        ..MeshFile::default()
    };
    // First vertex of each patch and its vertex count.
    let mut base: Vec<(u32, u32)> = Vec::new();
    // Triangles with (patch << 8 | local) vertex ids, resolved when all patches are read.
    let mut raw: Vec<MeshTri> = Vec::new();
    let scale = size / 4294967296.0;
    let material = |r: &BinReader, k: i64, nprims: usize| -> Result<i16, String> {
        if k == -1 || (k >= 0 && (k as usize) < nprims) {
            Ok(k as i16)
        } else {
            Err(r.bad(format!("bad triangle material {k}")))
        }
    };
    for p in 0..npatches as u32 {
        let flags = r.byte("patch flags")?;
        if flags & 1 == 0 || flags & !7 != 0 {
            return Err(r.bad(format!("bad patch flags {flags}")));
        }
        let nv = r.count(2, 256, "patch vertex count")?;
        let first = m.pos.len() as u32;
        base.push((first, nv as u32));
        for _ in 0..nv {
            let mut q = DVec3::ZERO;
            for i in 0..3 {
                q[i] = r.uint(4, "a vertex position")? as f64;
            }
            m.pos.push(org + (q + 0.5) * scale);
        }
        let mut vflags = vec![0u8; nv];
        m.normal.extend(std::iter::repeat_n(Vec3::ZERO, nv));
        m.uv.extend(std::iter::repeat_n([0.0; 2], nv));
        if flags & 2 != 0 {
            for (k, f) in vflags.iter_mut().enumerate() {
                if let Some(n) = decode_normal(r.uint(4, "a normal code")? as u32) {
                    m.normal[first as usize + k] = n;
                    *f |= HAS_NORMAL;
                }
            }
        }
        if flags & 4 != 0 {
            for (k, f) in vflags.iter_mut().enumerate() {
                let qu = r.uint(4, "a vertex u")?;
                let qv = r.uint(4, "a vertex v")?;
                if qu != 0 {
                    let u = lim[0] + (lim[1] - lim[0]) * (qu as f64 + 0.5) / 4294967296.0;
                    let v = lim[2] + (lim[3] - lim[2]) * (qv as f64 + 0.5) / 4294967296.0;
                    m.uv[first as usize + k] = [u, v];
                    *f |= HAS_UV;
                }
            }
        }
        m.flags.extend(vflags);
        let local = |r: &mut BinReader| -> Result<u32, String> {
            let at = r.pos();
            let v = r.byte("a triangle vertex")? as usize;
            if v >= nv {
                return Err(format!("bad local vertex {v} (of {nv}) at byte {at}"));
            }
            Ok(p << 8 | v as u32)
        };
        let nt = r.count(2, 512, "patch triangle count")?;
        let start = raw.len();
        for _ in 0..nt {
            let v = [local(&mut r)?, local(&mut r)?, local(&mut r)?];
            raw.push(MeshTri { v, modifier: -1 });
        }
        let k = r.int(2, "the material count")?;
        if k > 1 {
            if k as usize != nt {
                return Err(r.bad(format!("bad material count {k} for {nt} triangles")));
            }
            for t in &mut raw[start..] {
                let mk = r.int(2, "a triangle material")?;
                t.modifier = material(&r, mk, m.prims.len())?.into();
            }
        } else {
            let mk = r.int(2, "the patch material")?;
            let mk = material(&r, mk, m.prims.len())?;
            for t in &mut raw[start..] {
                t.modifier = mk.into();
            }
        }
        let nj1 = r.count(2, 256, "single joiner count")?;
        for _ in 0..nj1 {
            let v1 = r.uint(4, "a joiner vertex")? as u32;
            let v = [v1, local(&mut r)?, local(&mut r)?];
            let mk = r.int(2, "a joiner material")?;
            let modifier = material(&r, mk, m.prims.len())?;
            raw.push(MeshTri {
                v,
                modifier: modifier.into(),
            });
        }
        let nj2 = r.count(2, 256, "double joiner count")?;
        for _ in 0..nj2 {
            let v1 = r.uint(4, "a joiner vertex")? as u32;
            let v2 = r.uint(4, "a joiner vertex")? as u32;
            let v = [v1, v2, local(&mut r)?];
            let mk = r.int(2, "a joiner material")?;
            let modifier = material(&r, mk, m.prims.len())?;
            raw.push(MeshTri {
                v,
                modifier: modifier.into(),
            });
        }
    }
    for t in &mut raw {
        for v in &mut t.v {
            let (p, l) = ((*v >> 8) as usize, *v & 0xff);
            match base.get(p) {
                Some(&(first, n)) if l < n => *v = first + l,
                _ => return Err(format!("bad vertex id {:#x} in a triangle", *v)),
            }
        }
    }
    m.tris = raw;
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_verified_normal_codes() {
        let n = decode_normal(0x1204_0000).unwrap();
        assert!((n.x - 0.0995).abs() < 2e-4 && n.y == 0.0 && (n.z - 0.995).abs() < 1e-3);
        assert_eq!(decode_normal(8).unwrap(), Vec3::Z);
        assert!(decode_normal(0).is_none());
        // Signs.
        assert_eq!(decode_normal(8 | 4).unwrap(), -Vec3::Z);
    }
}
