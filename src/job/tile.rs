//! Tile results: `tiles/<task>.tile`.
//!
//! ```text
//! "TSRTILE1\n" | meta_len u32 LE | meta (JSON, UTF-8) | w·h·3 f32 LE (rows from the top)
//! | CRC32 of every byte before it (u32 LE)
//! ```
//!
//! A result is written to a temporary file in `tiles/`, fsynced, then renamed over its name
//! (and the directory fsynced: [`ResultDir`]), so readers see a whole result or none; two workers finishing the same tile write equal
//! pixels (every pixel is seeded by its position and frame alone) and the later rename wins.

use anyhow::{anyhow, bail, Result};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 9] = b"TSRTILE1\n";

/// What a tile result records besides its pixels.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TileMeta {
    /// Task name.
    pub task: String,
    /// Frame number.
    pub frame: u32,
    /// Tile index in the frame's plan.
    pub tile: usize,
    /// Left column.
    pub x0: usize,
    /// Top row.
    pub y0: usize,
    /// Width.
    pub w: usize,
    /// Height.
    pub h: usize,
    /// Job fingerprint (hex).
    pub fingerprint: String,
    /// The worker incarnation that rendered it.
    pub owner: String,
    /// Wall-clock seconds spent rendering.
    pub wall_seconds: f64,
    /// CPU seconds (all threads) spent rendering, when known.
    pub cpu_seconds: f64,
    /// Rays traced.
    pub rays: u64,
    /// New (extensive) ambient values computed while rendering it.
    pub new_values: u64,
    /// Seconds (summed over threads) spent computing them.
    pub ambient_seconds: f64,
}

/// Encode a tile result.
pub fn encode(meta: &TileMeta, pixels: &[[f32; 3]]) -> Result<Vec<u8>> {
    if pixels.len() != meta.w * meta.h {
        bail!(
            "tile {}: {} pixels for {}x{}",
            meta.task,
            pixels.len(),
            meta.w,
            meta.h
        );
    }
    let json = serde_json::to_vec(meta)?;
    let mut b = Vec::with_capacity(MAGIC.len() + 8 + json.len() + pixels.len() * 12);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&(json.len() as u32).to_le_bytes());
    b.extend_from_slice(&json);
    for p in pixels {
        for c in p {
            let v = if c.is_finite() { *c } else { 0.0 };
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    Ok(b)
}

/// Decode and check a tile result (magic, CRC, sizes, finite pixels).
pub fn decode(bytes: &[u8]) -> Result<(TileMeta, Vec<[f32; 3]>)> {
    if bytes.len() < MAGIC.len() + 8 || &bytes[..MAGIC.len()] != MAGIC {
        bail!("not a Tessera tile result");
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    let stored = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    let actual = crc32fast::hash(body);
    if stored != actual {
        bail!("CRC mismatch (stored {stored:08x}, computed {actual:08x}): truncated or damaged");
    }
    let n = MAGIC.len();
    let len = u32::from_le_bytes([body[n], body[n + 1], body[n + 2], body[n + 3]]) as usize;
    let meta_end = n + 4 + len;
    if meta_end > body.len() {
        bail!("metadata length {len} runs past the end");
    }
    let meta: TileMeta =
        serde_json::from_slice(&body[n + 4..meta_end]).map_err(|e| anyhow!("bad metadata: {e}"))?;
    let px = &body[meta_end..];
    let want = meta
        .w
        .checked_mul(meta.h)
        .and_then(|a| a.checked_mul(12))
        .ok_or_else(|| anyhow!("tile size overflows"))?;
    if px.len() != want {
        bail!(
            "{} bytes of pixels for a {}x{} tile (expected {want})",
            px.len(),
            meta.w,
            meta.h
        );
    }
    let mut pixels = Vec::with_capacity(meta.w * meta.h);
    for c in px.chunks_exact(12) {
        let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
        let p = [f(0), f(4), f(8)];
        if p.iter().any(|v| !v.is_finite() || *v < 0.0) {
            bail!("a pixel is negative or not finite");
        }
        pixels.push(p);
    }
    Ok((meta, pixels))
}

/// The `tiles/` directory of a job as one worker writes into it: kept open, so that a batch
/// of results costs one `open`, one `fsync` and one `rename` each and one `fsync` of the
/// directory ([`ResultDir::stage`], [`ResultDir::commit`]).
pub struct ResultDir {
    dir: PathBuf,
    handle: Option<File>,
}

impl ResultDir {
    /// Open `dir` (its handle is kept for the directory fsync; a file system that refuses to
    /// open directories gets none, as `sync_dir` is best effort).
    pub fn open(dir: &Path) -> Result<ResultDir> {
        Ok(ResultDir {
            dir: dir.to_path_buf(),
            handle: crate::safefile::open_dir(dir).ok(),
        })
    }
}

/// A tile result written to its temporary but not yet durable or visible
/// ([`ResultDir::stage`]).
#[derive(Debug)]
pub struct Staged {
    tmp: PathBuf,
    path: PathBuf,
    file: File,
}

impl ResultDir {
    /// Write the result `name` to its temporary `.<name>.<tag>.tmp` without syncing it: the
    /// first step of a group commit ([`ResultDir::commit`]), which makes a batch of results
    /// durable and visible with one directory sync.
    pub fn stage(
        &self,
        name: &str,
        tag: &str,
        meta: &TileMeta,
        pixels: &[[f32; 3]],
    ) -> Result<Staged> {
        let path = self.dir.join(name);
        let err = |e: std::io::Error| anyhow!("cannot write tile result {}: {e}", path.display());
        let bytes = encode(meta, pixels)?;
        if crate::fault::injected("TILE_ENOSPC") {
            // Test hook: behave as a full disk would.
            return Err(anyhow!(
                "cannot write tile result {}: No space left on device (os error 28, injected)",
                path.display()
            ));
        }
        let tmp = self.dir.join(format!(".{name}.{tag}.tmp"));
        let written = (|| {
            let mut f = crate::safefile::shared_write()
                .create(true)
                .truncate(true)
                .open(&tmp)?;
            f.write_all(&bytes)?;
            Ok(f)
        })();
        match written {
            Ok(file) => Ok(Staged { tmp, path, file }),
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                Err(err(e))
            }
        }
    }

    /// Make staged results durable and visible: each file's data is synced and the file
    /// closed, then renamed to its name, then the directory is synced once for all of
    /// them. Returns, per staged result in order, whether it is now in place (or the
    /// error; its temporary is removed).
    pub fn commit(&self, staged: Vec<Staged>) -> Vec<Result<()>> {
        let out: Vec<Result<()>> = staged
            .into_iter()
            .map(|st| {
                let Staged { tmp, path, file } = st;
                let r = file.sync_all().and_then(|()| {
                    drop(file);
                    std::fs::rename(&tmp, &path)
                });
                r.map_err(|e| {
                    let _ = std::fs::remove_file(&tmp);
                    anyhow!("cannot write tile result {}: {e}", path.display())
                })
            })
            .collect();
        if out.iter().any(|r| r.is_ok()) {
            if let Some(h) = &self.handle {
                let _ = h.sync_all();
            }
        }
        out
    }
}

/// The largest tile result read: a tile of the largest picture a job may plan, with its
/// header.
pub const MAX_TILE_BYTES: u64 = (super::MAX_RES as u64).pow(2) * 12 + (1 << 16);

/// Read and check a tile result file.
pub fn read(path: &Path) -> Result<(TileMeta, Vec<[f32; 3]>)> {
    let bytes = crate::safefile::read_bounded(path, MAX_TILE_BYTES)
        .map_err(|e| anyhow!("cannot read {}: {e}", path.display()))?;
    decode(&bytes).map_err(|e| anyhow!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_damage() {
        let meta = TileMeta {
            task: "f00000-t00002".into(),
            w: 3,
            h: 2,
            x0: 5,
            ..TileMeta::default()
        };
        let px: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 0.5, 1e-3]).collect();
        let b = encode(&meta, &px).unwrap();
        let (m, p) = decode(&b).unwrap();
        assert_eq!((m, p), (meta.clone(), px.clone()));
        for cut in 0..b.len() {
            assert!(decode(&b[..cut]).is_err(), "truncated at {cut}");
        }
        for i in 0..b.len() {
            let mut c = b.clone();
            c[i] ^= 0x10;
            assert!(decode(&c).is_err(), "flipped byte {i}");
        }
        assert!(encode(&meta, &px[..5]).is_err());
    }
}
