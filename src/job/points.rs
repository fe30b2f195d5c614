//! Jobs over point sets (`tplan --points FILE`): a job whose tasks are chunks of rays
//! instead of tiles of a picture, traced by `tpiece` with the same claims, leases, logs and
//! shared ambient store, and written by `tassemble` in input order as `ttrace` writes them.
//!
//! The rays are laid out on the job's one frame, a grid of `2·per_row` × `rows` "pixels":
//! ray `k` sits in row `k / per_row`, column `k % per_row`, and its value (three channels
//! in double precision) is kept as two f32 pixels, `hi` and `lo = value − hi`, so that the
//! tile machinery (claims, results, checks) carries it unchanged and the values come back
//! with 48 bits, enough for ttrace's seven printed digits. A task is `rows_per_task` rows:
//! `per_row · rows_per_task` rays (the chunk). Each ray's random numbers depend only on its
//! record number, so at `-ab 0` the results are byte-identical to one `ttrace` run however
//! the rays are split.

use super::JobDir;
use crate::options::rtrace::Format;
use crate::ttrace::records::{FieldWriter, InRay, RayReader};
use anyhow::{anyhow, bail, Context, Result};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The rays file in a job directory: six little-endian f64 per ray.
pub const RAYS_FILE: &str = "points.bin";
/// Most rays per row of the layout.
const MAX_PER_ROW: usize = 1024;
/// Bytes per ray in [`RAYS_FILE`].
const RAY_BYTES: u64 = 48;

/// A point job's plan and output (the manifest's `points`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointsPlan {
    /// Rays in the job.
    pub count: u64,
    /// Rays per row of the layout.
    pub per_row: usize,
    /// Rows per task.
    pub rows_per_task: usize,
    /// `-I`: irradiance at each ray's origin.
    pub at_origin: bool,
    /// `-ld`: rays end at their direction's length.
    pub limit_distance: bool,
    /// Output format letter (`a`, `f`, `d`).
    pub output: char,
    /// Output specifiers (of `v`, `o`, `d`).
    pub spec: String,
    /// Write a header.
    pub header: bool,
}

impl PointsPlan {
    /// The plan for `count` rays: chunks of `chunk` rays (default: about sixteen tasks per
    /// worker, at most 4096 rays each).
    pub fn new(count: u64, workers: usize, chunk: Option<usize>) -> Result<PointsPlan> {
        if count == 0 {
            bail!("the points file holds no rays");
        }
        let chunk = match chunk {
            Some(0) => bail!("--chunk must be at least 1"),
            Some(c) => c as u64,
            None => count.div_ceil(16 * workers.max(1) as u64).clamp(1, 4096),
        };
        let per_row = chunk.min(MAX_PER_ROW as u64) as usize;
        let rows_per_task = chunk.div_ceil(per_row as u64) as usize;
        let rows = count.div_ceil(per_row as u64);
        if rows > super::MAX_RES as u64 {
            bail!(
                "{count} rays in rows of {per_row} need {rows} rows (at most {}): \
                 use a larger --chunk",
                super::MAX_RES
            );
        }
        Ok(PointsPlan {
            count,
            per_row,
            rows_per_task,
            at_origin: false,
            limit_distance: false,
            output: 'a',
            spec: "v".into(),
            header: true,
        })
    }

    /// The frame's size in pixels.
    pub fn frame_size(&self) -> (usize, usize) {
        (
            2 * self.per_row,
            self.count.div_ceil(self.per_row as u64) as usize,
        )
    }

    /// Check a plan read from a manifest.
    pub fn validate(&self) -> Result<()> {
        if self.count == 0
            || self.per_row == 0
            || self.per_row > MAX_PER_ROW
            || self.rows_per_task == 0
            || !matches!(self.output, 'a' | 'f' | 'd')
            || self.spec.is_empty()
            || self.spec.chars().any(|c| !"vod".contains(c))
        {
            bail!("points: an invalid plan");
        }
        if self.count.div_ceil(self.per_row as u64) > super::MAX_RES as u64 {
            bail!("points: too many rows");
        }
        Ok(())
    }

    fn format(&self) -> Format {
        match self.output {
            'f' => Format::Float,
            'd' => Format::Double,
            _ => Format::Ascii,
        }
    }
}

/// Read a points file as ttrace reads its input (`format`); a zero direction is refused (a
/// flush request has no meaning in a job).
pub fn read_points(path: &std::path::Path, format: Format) -> Result<Vec<InRay>> {
    let f = std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut r = RayReader::new(std::io::BufReader::new(f), format);
    let mut out = Vec::new();
    while let Some(ray) = r.next_ray().map_err(|e| {
        anyhow!(
            "{}: {}",
            path.display(),
            e.to_string().replace("standard input, ", "")
        )
    })? {
        if ray.dir == DVec3::ZERO {
            bail!(
                "{}: record {}: a zero direction (rtrace's flush request) has no meaning in a job",
                path.display(),
                r.records
            );
        }
        out.push(ray);
    }
    Ok(out)
}

/// The job's rays file's bytes.
pub fn encode_rays(rays: &[InRay]) -> Vec<u8> {
    let mut b = Vec::with_capacity(rays.len() * RAY_BYTES as usize);
    for r in rays {
        for v in [r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z] {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b
}

/// Read the job's rays (checked against the plan's count).
pub fn load_rays(job: &JobDir, plan: &PointsPlan) -> Result<Vec<InRay>> {
    let path = job.file(RAYS_FILE);
    let want = plan.count * RAY_BYTES;
    let b = crate::safefile::read_bounded(&path, want)
        .map_err(|e| anyhow!("cannot read {}: {e}", path.display()))?;
    if b.len() as u64 != want {
        bail!(
            "{}: {} bytes, the manifest's {} rays need {want}",
            path.display(),
            b.len(),
            plan.count
        );
    }
    let mut rays = Vec::with_capacity(plan.count as usize);
    for rec in b.chunks_exact(RAY_BYTES as usize) {
        let v: Vec<f64> = rec
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        if v.iter().any(|x| !x.is_finite()) {
            bail!("{}: a ray that is not finite", path.display());
        }
        rays.push(InRay {
            org: DVec3::new(v[0], v[1], v[2]),
            dir: DVec3::new(v[3], v[4], v[5]),
        });
    }
    Ok(rays)
}

/// Split a (non-negative) value into the two pixels that carry it: `hi` the largest f32 not
/// above each channel, `lo` the rest (non-negative, as every tile pixel must be).
pub fn split(v: DVec3) -> [[f32; 3]; 2] {
    let mut hi = [0f32; 3];
    let mut lo = [0f32; 3];
    for c in 0..3 {
        let x = v[c].max(0.0);
        let mut h = x as f32;
        if h as f64 > x {
            h = h.next_down();
        }
        hi[c] = h;
        lo[c] = (x - h as f64) as f32;
    }
    [hi, lo]
}

/// The value two pixels carry.
pub fn join(hi: [f32; 3], lo: [f32; 3]) -> DVec3 {
    glam::Vec3::from_array(hi).as_dvec3() + glam::Vec3::from_array(lo).as_dvec3()
}

/// The records of a point job: every ray's results, in input order, as `ttrace` writes
/// them (after a header naming `command` when the plan asks for one).
pub fn records(plan: &PointsPlan, rays: &[InRay], pixels: &[[f32; 3]], command: &str) -> Vec<u8> {
    let mut w = FieldWriter::new(plan.format());
    if plan.header {
        w.out.extend_from_slice(
            format!(
                "#?RADIANCE\n{command}\nSOFTWARE= {}\nNCOMP=3\nFORMAT={}\n\n",
                crate::runinfo::SOFTWARE,
                plan.format().header_name()
            )
            .as_bytes(),
        );
    }
    let width = 2 * plan.per_row;
    for (k, r) in rays.iter().enumerate() {
        let (row, col) = (k / plan.per_row, k % plan.per_row);
        let at = row * width + 2 * col;
        let v = join(pixels[at], pixels[at + 1]);
        for c in plan.spec.chars() {
            match c {
                'v' => w.vec3(v),
                'o' => w.vec3(r.org),
                _ => w.vec3(r.dir.normalize_or_zero()),
            }
        }
        w.end();
    }
    w.out
}

/// A worker's task of a point job: the rays of the rows of `rect`, on the calling loop's
/// pool `here`, each value as two pixels ([`split`]); the columns past the last ray stay
/// black.
pub fn trace_chunk(
    (session, here): (&crate::session::Session, &rayon::ThreadPool),
    plan: &PointsPlan,
    rays: &[InRay],
    rect: &super::plan::TileRect,
    progress: &crate::render::picture::RenderProgress,
) -> Result<Vec<[f32; 3]>> {
    let kind = crate::ttrace::ValueKind {
        at_origin: plan.at_origin,
        at_hit: session.params.i,
        limit_distance: plan.limit_distance,
    };
    let tr = session.tracer();
    let run = || {
        let mut pixels = vec![[0f32; 3]; rect.w * rect.h];
        for row in 0..rect.h {
            for col in 0..plan.per_row {
                let k = (rect.y0 + row) * plan.per_row + col;
                let Some(r) = rays.get(k) else { break };
                let v = crate::ttrace::ray_value(&tr, kind, r, k as u64);
                let [hi, lo] = split(v);
                let at = row * rect.w + 2 * col;
                pixels[at] = hi;
                pixels[at + 1] = lo;
                progress
                    .rays
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        }
        pixels
    };
    let pixels = here.install(|| match &session.ambient {
        Some(a) => a.with_accuracy(None, run),
        None => run(),
    });
    if let Some(e) = session.scene.fatal_error() {
        bail!("{e}");
    }
    Ok(pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plans_and_values_round_trip() {
        let p = PointsPlan::new(100, 2, None).unwrap();
        assert_eq!((p.per_row, p.rows_per_task), (4, 1));
        assert_eq!(p.frame_size(), (8, 25));
        let p = PointsPlan::new(1_000_000, 4, Some(5000)).unwrap();
        assert_eq!((p.per_row, p.rows_per_task), (1024, 5));
        assert!(PointsPlan::new(0, 4, None).is_err());
        assert!(PointsPlan::new(100_000_000, 4, Some(10)).is_err());
        for v in [0.1234567891234, 1e-7, 123456.789012345, 0.0] {
            let d = DVec3::splat(v);
            let [hi, lo] = split(d);
            let back = join(hi, lo);
            assert!((back.x - v).abs() <= 1e-13 * v.abs(), "{v} {back}");
            assert_eq!(
                crate::ttrace::records::fmt_e(back.x),
                crate::ttrace::records::fmt_e(v)
            );
        }
    }
}
