//! The fingerprint of a scene and the options that change ambient values: a store made for
//! one fingerprint is refused for another (unless forced), so stale values are never reused.
//!
//! Covered: every primitive in order (modifier, type, identifier, all arguments — so any
//! change of geometry or material changes it) and `-ab -aa -ar -ad -as -av -aw` and the
//! `-ae/-ai` lists. Not covered: the view, resolution and pixel options, which do not change
//! ambient values. The digest is 256 bits from four independently seeded 64-bit FNV-1a
//! streams with a final avalanche mix (a content check, not a cryptographic hash).

use crate::options::render::RenderParams;
use crate::scene::primitive::Primitive;

struct Hasher([u64; 4]);

impl Hasher {
    fn new() -> Hasher {
        Hasher([
            0xcbf2_9ce4_8422_2325,
            0x8422_2325_cbf2_9ce4,
            0x9e37_79b9_7f4a_7c15,
            0xd6e8_feb8_6659_fd93,
        ])
    }
    fn bytes(&mut self, b: &[u8]) {
        // The four streams side by side (independent chains of multiplications).
        let [mut h0, mut h1, mut h2, mut h3] = self.0;
        for &x in b {
            let x = x as u64;
            h0 = (h0 ^ x).wrapping_mul(0x0100_0000_01b3);
            h1 = (h1 ^ x ^ 1 << 8).wrapping_mul(0x0100_0000_01b3);
            h2 = (h2 ^ x ^ 2 << 8).wrapping_mul(0x0100_0000_01b3);
            h3 = (h3 ^ x ^ 3 << 8).wrapping_mul(0x0100_0000_01b3);
        }
        self.0 = [h0, h1, h2, h3];
    }
    fn str(&mut self, s: &str) {
        self.bytes(&(s.len() as u64).to_le_bytes());
        self.bytes(s.as_bytes());
    }
    fn f64(&mut self, v: f64) {
        // -0.0 and 0.0 hash alike.
        let v = if v == 0.0 { 0.0 } else { v };
        self.bytes(&v.to_bits().to_le_bytes());
    }
    fn finish(self) -> [u8; 32] {
        let mut out = [0u8; 32];
        for (i, mut h) in self.0.into_iter().enumerate() {
            h ^= h >> 33;
            h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
            h ^= h >> 33;
            h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
            h ^= h >> 33;
            out[i * 8..i * 8 + 8].copy_from_slice(&h.to_le_bytes());
        }
        out
    }
}

/// `fp` extended by the contents of the files the scene reads by relative name (function
/// files, data files, pictures, fonts: [`crate::render::world::Scene::inputs`]), so that a changed
/// `.cal` or data file refuses stored values. Unchanged when there are none.
pub fn with_inputs(
    fp: [u8; 32],
    inputs: &[(String, std::path::PathBuf)],
) -> Result<[u8; 32], String> {
    if inputs.is_empty() {
        return Ok(fp);
    }
    let mut sorted: Vec<&(String, std::path::PathBuf)> = inputs.iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    let mut h = Hasher::new();
    h.str("tessera-inputs-v1");
    h.bytes(&fp);
    for (name, path) in sorted {
        h.str(name);
        hash_file(&mut h, path).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(h.finish())
}

/// Hash a file's length and contents, read in blocks (a large mesh is not held twice).
fn hash_file(h: &mut Hasher, path: &std::path::Path) -> std::io::Result<()> {
    use std::io::Read;
    // A built-in library file counts as its text: the same as a copy of it on disk.
    if let Some(text) = crate::cal::builtin_library_text(path) {
        h.bytes(&(text.len() as u64).to_le_bytes());
        h.bytes(text.as_bytes());
        return Ok(());
    }
    let mut f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    h.bytes(&len.to_le_bytes());
    let mut buf = vec![0u8; 1 << 16];
    let mut seen = 0u64;
    loop {
        let n = match f.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        h.bytes(&buf[..n]);
        seen += n as u64;
    }
    if seen != len {
        return Err(std::io::Error::other("changed while it was read"));
    }
    Ok(())
}

/// Fingerprint of a scene's primitives and the ambient-relevant options.
pub fn fingerprint(prims: &[Primitive], params: &RenderParams) -> [u8; 32] {
    let mut h = Hasher::new();
    h.str("tessera-ambient-v2");
    h.bytes(&(prims.len() as u64).to_le_bytes());
    for p in prims {
        h.str(&p.modifier);
        h.str(&p.ptype);
        h.str(&p.name);
        h.bytes(&(p.sargs.len() as u64).to_le_bytes());
        for s in &p.sargs {
            h.str(s);
        }
        h.bytes(&(p.iargs.len() as u64).to_le_bytes());
        for i in &p.iargs {
            h.bytes(&i.to_le_bytes());
        }
        h.bytes(&(p.rargs.len() as u64).to_le_bytes());
        for r in &p.rargs {
            h.f64(*r);
        }
    }
    h.bytes(&params.ab.to_le_bytes());
    h.f64(params.aa);
    h.bytes(&params.ar.to_le_bytes());
    h.bytes(&params.ad.to_le_bytes());
    h.bytes(&params.as_.to_le_bytes());
    for v in params.av {
        h.f64(v);
    }
    h.bytes(&params.aw.to_le_bytes());
    h.str("ae");
    for m in &params.ae {
        h.str(m);
    }
    h.str("ai");
    for m in &params.ai {
        h.str(m);
    }
    h.str("tessera-settings");
    h.str(&params.amb.to_text());
    if let Some(ax) = &params.ax {
        h.str(&ax.to_words().join(" "));
    }
    if let Some(m) = &params.axm {
        h.str(&m.to_words().join(" "));
    }
    if let Some(b) = &params.axt {
        h.str(&b.to_words().join(" "));
    }
    h.finish()
}

/// The options text stored (informationally) with a store.
pub fn options_text(params: &RenderParams) -> String {
    let mut s = format!(
        "-ab {} -aa {} -ar {} -ad {} -as {} -av {} {} {} -aw {}",
        params.ab,
        params.aa,
        params.ar,
        params.ad,
        params.as_,
        params.av[0],
        params.av[1],
        params.av[2],
        params.aw
    );
    for m in &params.ae {
        s.push_str(&format!(" -ae {m}"));
    }
    for m in &params.ai {
        s.push_str(&format!(" -ai {m}"));
    }
    for w in [
        params.ax.map(|a| a.to_words()),
        params.axm.map(|m| m.to_words()),
    ]
    .into_iter()
    .flatten()
    {
        s.push(' ');
        s.push_str(&w.join(" "));
    }
    s.push(' ');
    s.push_str(&params.amb.to_text());
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Location;

    fn prim(r: f64) -> Primitive {
        Primitive {
            modifier: "void".into(),
            ptype: "plastic".into(),
            name: "m".into(),
            sargs: vec![],
            iargs: vec![],
            rargs: vec![r, 0.5, 0.5, 0.0, 0.0],
            loc: Location::new("x", 1),
        }
    }

    #[test]
    fn changes_with_geometry_materials_ambient_options_and_settings() {
        let p = RenderParams::default();
        let base = fingerprint(&[prim(0.5)], &p);
        assert_eq!(base, fingerprint(&[prim(0.5)], &p));
        assert_ne!(base, fingerprint(&[prim(0.51)], &p));
        assert_ne!(base, fingerprint(&[prim(0.5), prim(0.5)], &p));
        for change in [
            |p: &mut RenderParams| p.ab = 3,
            |p: &mut RenderParams| p.aa = 0.1,
            |p: &mut RenderParams| p.ar = 128,
            |p: &mut RenderParams| p.ad = 1024,
            |p: &mut RenderParams| p.as_ = 0,
            |p: &mut RenderParams| p.av = [0.1, 0.1, 0.1],
            |p: &mut RenderParams| p.aw = 2,
            |p: &mut RenderParams| p.ae = vec!["glass".into()],
            |p: &mut RenderParams| p.amb.share_max = 1.0,
            |p: &mut RenderParams| p.amb.corral = false,
            |p: &mut RenderParams| p.amb.hessian_cells = 64,
            |p: &mut RenderParams| p.amb.shadow_trust = 4,
            |p: &mut RenderParams| {
                p.ax = crate::options::schedule::AccuracySchedule::new(0.5, 0.1, 0.1, false).ok()
            },
        ] {
            let mut q = RenderParams::default();
            change(&mut q);
            assert_ne!(base, fingerprint(&[prim(0.5)], &q));
        }
        // View and pixel options do not matter.
        let q = RenderParams {
            dj: 0.7,
            ss: 4.0,
            ..RenderParams::default()
        };
        assert_eq!(base, fingerprint(&[prim(0.5)], &q));
    }

    #[test]
    fn input_files_are_hashed_as_whole_contents() {
        // The streams side by side and the file read in blocks give the digest of the
        // whole contents hashed one stream after the other (stores made before still match).
        let data: Vec<u8> = (0..200_000u32).map(|i| (i * 7 + i / 300) as u8).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("in.dat");
        std::fs::write(&path, &data).unwrap();
        let fp = [3u8; 32];
        let got = with_inputs(fp, &[("in.dat".into(), path)]).unwrap();
        let mut h = Hasher::new();
        let mut serial = |b: &[u8]| {
            for (i, s) in h.0.iter_mut().enumerate() {
                for &x in b {
                    *s ^= x as u64 ^ (i as u64) << 8;
                    *s = s.wrapping_mul(0x0100_0000_01b3);
                }
            }
        };
        for part in [
            &(17u64.to_le_bytes())[..],
            b"tessera-inputs-v1",
            &fp,
            &(6u64.to_le_bytes())[..],
            b"in.dat",
            &(data.len() as u64).to_le_bytes(),
            &data,
        ] {
            serial(part);
        }
        assert_eq!(got, h.finish());
        let missing = with_inputs(fp, &[("no".into(), dir.path().join("no"))]);
        assert!(missing.is_err());
    }
}
