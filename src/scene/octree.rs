//! Octrees written by Radiance's `oconv` (radiance-formats.md §6): a header, the magic
//! `283 + objsize`, the cube, the scene file names (none: a frozen octree), the object
//! count, the tree (skipped: Tessera builds its own BVH) and, when frozen, the scene's
//! primitives themselves.
//!
//! An unfrozen octree's files are read again with the scene reader: a relative name is
//! looked up along the RAYPATH (Radiance reads them from the current directory, RAYPATH's
//! default) and, failing that, beside the octree. The number of primitives read must be the
//! octree's object count (Radiance: "octree stale?").

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;

use super::binio::BinReader;
use super::error::SceneError;
use super::primitive::{append_prims, Location, Primitive};
use super::reader::{parse_scene_text, read_text_files, ReadOptions};

/// Scene files read for an unfrozen octree: the name in its header and the path found.
pub type ScenePaths = Vec<(String, PathBuf)>;

/// Deepest tree accepted (oconv's resolution limit of 16384 gives about 15 levels).
const MAX_DEPTH: usize = 128;

/// An octree file, parsed.
#[derive(Debug)]
pub struct OctreeFile {
    /// Header lines after `#?RADIANCE` (the commands that made it).
    pub header: Vec<String>,
    /// Cube origin and size.
    pub cube: (DVec3, f64),
    /// Scene files of an unfrozen octree (empty when frozen).
    pub files: Vec<String>,
    /// Number of objects.
    pub nobjects: usize,
    /// The primitives of a frozen octree.
    pub prims: Vec<Primitive>,
}

/// Whether the bytes start like a Radiance octree: a text header (with or without
/// `#?RADIANCE`: older oconv wrote none) naming the octree format, or, in headers older
/// than the FORMAT line (1991), with no FORMAT at all and an octree's magic number
/// (284–291) right after the header's blank line.
pub fn looks_like_octree(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(1 << 16)];
    let Some(end) = head.windows(2).position(|w| w == b"\n\n") else {
        return false;
    };
    let text = &head[..end];
    if text
        .iter()
        .any(|&b| b < b' ' && !matches!(b, b'\n' | b'\t' | b'\r'))
    {
        return false;
    }
    let mut formats = text
        .split(|&b| b == b'\n')
        .filter_map(|l| l.strip_prefix(b"FORMAT="));
    match formats.next() {
        Some(f) => f == b"Radiance_octree",
        None => head
            .get(end + 2..end + 4)
            .is_some_and(|m| (284..=291).contains(&i16::from_be_bytes([m[0], m[1]]))),
    }
}

/// Skip a tree (pre-order: 0 empty, 1 leaf of `count` indices of `objsize` bytes, 2 eight
/// children), checking leaf counts against `limit` when given.
pub fn skip_tree(r: &mut BinReader, objsize: usize, limit: Option<usize>) -> Result<(), String> {
    // Pending children per open level.
    let mut stack: Vec<u8> = vec![1];
    while let Some(top) = stack.last_mut() {
        if *top == 0 {
            stack.pop();
            continue;
        }
        *top -= 1;
        let at = r.pos();
        match r.byte("a tree node")? {
            0 => {}
            1 => {
                let max = limit.map_or(u32::MAX as u64, |l| l as u64);
                let n = r.count(objsize, max, "leaf object count")?;
                for _ in 0..n {
                    let i = r.int(objsize, "a leaf object index")?;
                    if i < 0 || limit.is_some_and(|l| i as u64 >= l as u64) {
                        return Err(format!(
                            "bad object index {i} in a tree leaf at byte {}",
                            r.pos()
                        ));
                    }
                }
            }
            2 => {
                if stack.len() >= MAX_DEPTH {
                    return Err(format!("tree deeper than {MAX_DEPTH} levels at byte {at}"));
                }
                stack.push(8);
            }
            t => return Err(format!("bad tree node type {t} at byte {at}")),
        }
    }
    Ok(())
}

/// A frozen scene (radiance-formats.md §6.4): the writer's type names up to an empty one,
/// then objects up to the byte 0xFF, each with a type index, its modifier's object index
/// (−1 = void, otherwise an earlier object), identifier, strings and reals. The primitives
/// name their modifiers by identifier (the object at that index is the latest definition of
/// that name before the user, so the usual name binding gives the same modifier).
pub fn read_frozen_scene(
    r: &mut BinReader,
    objsize: usize,
    file: &Arc<str>,
) -> Result<Vec<Primitive>, String> {
    let mut types: Vec<&str> = Vec::new();
    loop {
        let t = r.string("the type table")?;
        if t.is_empty() {
            break;
        }
        if types.len() >= 255 {
            return Err(r.bad("more than 255 types in the type table"));
        }
        types.push(t);
    }
    let mut prims: Vec<Primitive> = Vec::new();
    loop {
        let at = r.pos();
        let ti = r.byte("an object type")?;
        if ti == 0xff {
            break;
        }
        let Some(&ptype) = types.get(ti as usize) else {
            return Err(format!("reference to unknown type {ti} at byte {at}"));
        };
        let mi = r.int(objsize, "a modifier index")?;
        let modifier = if mi == -1 {
            "void".to_string()
        } else if mi >= 0 && (mi as u64) < prims.len() as u64 {
            prims[mi as usize].name.clone()
        } else {
            return Err(format!(
                "bad modifier index {mi} (object {}) at byte {at}",
                prims.len()
            ));
        };
        let name = r.string("an identifier")?.to_string();
        let ns = r.count(2, i16::MAX as u64, "string argument count")?;
        let mut sargs = Vec::with_capacity(ns.min(r.remaining()));
        for _ in 0..ns {
            sargs.push(r.string("a string argument")?.to_string());
        }
        let nr = r.count(2, i16::MAX as u64, "real argument count")?;
        let mut rargs = Vec::with_capacity(nr.min(r.remaining() / 5));
        for _ in 0..nr {
            rargs.push(r.real("a real argument")?);
        }
        let line = u32::try_from(prims.len() + 1).unwrap_or(u32::MAX);
        prims.push(Primitive {
            modifier,
            ptype: ptype.to_string(),
            name,
            sargs,
            iargs: Vec::new(),
            rargs,
            loc: Location::new(file.clone(), line),
        });
    }
    Ok(prims)
}

/// Parse an octree's bytes (`name`: the file, for locations).
pub fn parse_octree(bytes: &[u8], name: &str) -> Result<OctreeFile, String> {
    let mut r = BinReader::new(bytes, "octree");
    let header = r.header("Radiance_octree")?;
    let at = r.pos();
    let magic = r.int(2, "the magic number")?;
    let objsize = magic - 283;
    if !(1..=8).contains(&objsize) {
        return Err(format!(
            "incompatible octree format (magic number {magic} at byte {at})"
        ));
    }
    let objsize = objsize as usize;
    let mut org = DVec3::ZERO;
    for i in 0..3 {
        org[i] = r.text_real("the cube origin")?;
    }
    let size = r.text_real("the cube size")?;
    let mut files = Vec::new();
    loop {
        let f = r.string("a scene file name")?;
        if f.is_empty() {
            break;
        }
        files.push(f.to_string());
    }
    let nobjects = r.count(objsize, u32::MAX as u64, "object count")?;
    skip_tree(&mut r, objsize, Some(nobjects))?;
    let mut prims = Vec::new();
    if files.is_empty() {
        let file: Arc<str> = Arc::from(name);
        prims = read_frozen_scene(&mut r, objsize, &file)?;
        if prims.len() != nobjects {
            return Err(format!(
                "bad object count: {} objects for a count of {nobjects}",
                prims.len()
            ));
        }
    }
    Ok(OctreeFile {
        header,
        cube: (org, size),
        files,
        nobjects,
        prims,
    })
}

/// Where an unfrozen octree's scene file `f` is: along the RAYPATH, else beside the
/// octree.
fn scene_file_path(f: &str, octree: &Path, opts: &ReadOptions) -> PathBuf {
    let p = Path::new(f);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let dirs: Vec<PathBuf> = if opts.raypath.is_empty() {
        vec![PathBuf::from(".")]
    } else {
        opts.raypath.clone()
    };
    if let Some(found) = dirs.iter().map(|d| d.join(p)).find(|c| c.is_file()) {
        return found;
    }
    let beside = octree.parent().map(|d| d.join(p));
    match beside {
        Some(b) if b.is_file() => b,
        // Not found: "./name" (never "-", which the reader takes for standard input).
        _ => Path::new(".").join(p),
    }
}

/// The primitives of the octree at `path` (named `name`): the frozen scene, or its scene
/// files read again. Every problem is one error naming the file.
pub fn octree_primitives(
    path: &Path,
    name: &str,
    opts: &ReadOptions,
) -> Result<(Vec<Primitive>, ScenePaths), SceneError> {
    let loc = Location::new(name, 0);
    let io = |reason: String| SceneError::Io {
        loc: loc.clone(),
        path: name.to_string(),
        reason,
    };
    let bytes = std::fs::read(path).map_err(|e| io(e.to_string()))?;
    let oct = parse_octree(&bytes, name).map_err(|m| SceneError::syntax(loc.clone(), m))?;
    if oct.files.is_empty() {
        return Ok((oct.prims, Vec::new()));
    }
    let mut prims = Vec::new();
    let mut used = Vec::new();
    for f in &oct.files {
        if let Some(cmd) = f.strip_prefix('!') {
            let text = format!("!{cmd}\n");
            prims.extend(parse_scene_text(&text, name, opts)?);
            continue;
        }
        let p = scene_file_path(f, path, opts);
        let shown = p.to_string_lossy().into_owned();
        prims.extend(read_text_files(&[shown], opts)?);
        used.push((f.clone(), p));
    }
    if prims.len() != oct.nobjects {
        return Err(SceneError::syntax(
            loc,
            format!(
                "bad object count; octree stale? ({} primitives in {} for a count of {})",
                prims.len(),
                oct.files.join(" "),
                oct.nobjects
            ),
        ));
    }
    Ok((prims, used))
}

/// Read scene files in order ("-" = stdin) into the flat list of primitives, expanding
/// inline commands. Errors about a file that cannot be opened are located at `path:0`.
/// An octree (a `.oct` name, or a Radiance header naming the octree format) gives its
/// primitives: a frozen octree's own, an unfrozen one's scene files read again
/// (this module). A `.obj` file becomes a mesh primitive placing it
/// ([`super::reader::obj_scene_primitive`], read by [`super::obj`] when the scene is built).
pub fn read_scene_files(
    paths: &[String],
    opts: &ReadOptions,
) -> Result<Vec<Primitive>, SceneError> {
    let mut out = Vec::new();
    for p in paths {
        if p.starts_with('!') {
            // A command in place of a file (`'!xform ... chair.obj'` is no OBJ file).
            append_prims(&mut out, read_text_files(std::slice::from_ref(p), opts)?);
            continue;
        }
        if super::sets::is_obj_name(p) {
            if let Err(e) = std::fs::metadata(p) {
                return Err(SceneError::Io {
                    loc: Location::new(p.as_str(), 0),
                    path: p.clone(),
                    reason: e.to_string(),
                });
            }
            out.push(super::reader::obj_scene_primitive(
                p,
                opts.obj_material.as_deref(),
            ));
            continue;
        }
        if p != "-" && is_octree(Path::new(p), p) {
            let (prims, _) = octree_primitives(Path::new(p), p, opts)?;
            append_prims(&mut out, prims);
            continue;
        }
        append_prims(&mut out, read_text_files(std::slice::from_ref(p), opts)?);
    }
    Ok(out)
}

/// Whether `path` (named `named`) is to be read as an octree.
fn is_octree(path: &Path, named: &str) -> bool {
    if named.ends_with(".oct") {
        return true;
    }
    let mut head = Vec::new();
    match std::fs::File::open(path) {
        Ok(f) => {
            let _ = f.take(1 << 16).read_to_end(&mut head);
            looks_like_octree(&head)
        }
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The verified frozen octree of radiance-formats.md §6.4, built by hand.
    fn frozen() -> Vec<u8> {
        let mut b = b"#?RADIANCE\noconv -f s.rad\nFORMAT=Radiance_octree\n\n".to_vec();
        b.extend([0x01, 0x1f]);
        for s in ["-1.00001", "-1.00001", "-1.00001", "2.00002", ""] {
            b.extend(s.as_bytes());
            b.push(0);
        }
        b.extend([0, 0, 0, 2, 1, 0, 0, 0, 1, 0, 0, 0, 1]);
        for s in [
            "polygon", "cone", "sphere", "texfunc", "ring", "cylinder", "instance",
        ] {
            b.extend(s.as_bytes());
            b.push(0);
        }
        for s in ["cup", "bubble", "tube", "mesh", "alias", "plastic", ""] {
            b.extend(s.as_bytes());
            b.push(0);
        }
        b.extend([0x0c, 0xff, 0xff, 0xff, 0xff]);
        b.extend(b"red\0");
        b.extend([
            0, 0, 0, 5, 0x59, 0x99, 0x99, 0x98, 0, 0x66, 0x66, 0x66, 0x65, 0xfd,
        ]);
        b.extend([0x66, 0x66, 0x66, 0x65, 0xfd, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        b.extend([0x02, 0, 0, 0, 0]);
        b.extend(b"ball\0");
        b.extend([0, 0, 0, 4]);
        b.extend([0; 15]);
        b.extend([0x3f, 0xff, 0xff, 0xff, 0x01, 0xff]);
        b
    }

    #[test]
    fn a_frozen_octree() {
        let o = parse_octree(&frozen(), "s.oct").unwrap();
        assert!(o.files.is_empty());
        assert_eq!(o.nobjects, 2);
        assert!((o.cube.1 - 2.00002).abs() < 1e-12);
        assert_eq!(o.prims.len(), 2);
        assert_eq!(o.prims[0].ptype, "plastic");
        assert_eq!(o.prims[1].modifier, "red");
        assert_eq!(o.prims[1].ptype, "sphere");
        assert!((o.prims[1].rargs[3] - 1.0).abs() < 1e-8);
        assert!(looks_like_octree(&frozen()));
    }

    #[test]
    fn damaged_octrees_are_errors() {
        let good = frozen();
        for n in 0..good.len() {
            assert!(
                parse_octree(&good[..n], "s.oct").is_err(),
                "truncated at {n}"
            );
        }
        let mut bad = good.clone();
        let m = bad.iter().position(|&b| b == 0x1f).unwrap();
        bad[m] = 0x30;
        assert!(parse_octree(&bad, "s.oct")
            .unwrap_err()
            .contains("incompatible"));
        // A modifier index pointing forward.
        let mut fwd = good.clone();
        let i = fwd.windows(4).position(|w| w == b"ball").unwrap() - 4;
        fwd[i..i + 4].copy_from_slice(&[0, 0, 0, 7]);
        assert!(parse_octree(&fwd, "s.oct")
            .unwrap_err()
            .contains("modifier index"));
    }
}
