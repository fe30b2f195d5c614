//! `tassemble`: a frame's picture from its tile results.

use super::manifest::Manifest;
use super::{task_name, tile, JobDir};
use crate::image::{Header, Image};
use anyhow::{anyhow, Context, Result};

/// A tile that could not be used, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct MissingTile {
    /// Task name.
    pub task: String,
    /// Why (absent, damaged, from another plan).
    pub reason: String,
}

/// The frame's own `-aa` when it varies from frame to frame (`-ax`, `-axg`, `-axt`; for
/// `-axt` once decided), as `tpict -S` records it.
pub fn frame_accuracy(job: &JobDir, m: &Manifest, frame: u32) -> Result<Option<f64>> {
    match &m.params.axt {
        Some(b) => Ok(super::budget::read(job, b, frame)?.map(|r| r.aa)),
        None => Ok(m.params.frame_accuracy(frame)),
    }
}

/// The pixels of task `name`'s result, checked against its rectangle, frame and job; why
/// not otherwise.
fn read_result(
    job: &JobDir,
    m: &Manifest,
    frame: u32,
    name: &str,
    rect: &super::plan::TileRect,
) -> std::result::Result<Vec<[f32; 3]>, String> {
    let path = job.tile_file(name);
    if !path.exists() {
        return Err("no result".into());
    }
    let (meta, px) = tile::read(&path).map_err(|e| format!("{e:#}"))?;
    if (meta.x0, meta.y0, meta.w, meta.h) != (rect.x0, rect.y0, rect.w, rect.h)
        || meta.frame != frame
        || meta.fingerprint != m.fingerprint
    {
        return Err("result belongs to another plan or scene".into());
    }
    Ok(px)
}

/// The pieces split off the job's tiles (one listing of `tasks/`, for every frame assembled).
pub fn job_pieces(job: &JobDir) -> Result<super::task::Pieces> {
    let states = super::task::scan(&job.tasks())
        .map_err(|e| anyhow!("cannot list {}: {e}", job.tasks().display()))?;
    Ok(super::task::pieces(&states))
}

/// Assemble frame `frame`, `pieces` from [`job_pieces`]. Returns the picture and the tiles that were missing or invalid
/// (filled black). The caller decides whether a partial picture is acceptable.
pub fn assemble_frame(
    job: &JobDir,
    m: &Manifest,
    pieces: &super::task::Pieces,
    frame: u32,
    command: &str,
) -> Result<(Image, Vec<MissingTile>)> {
    let fp = m
        .frame(frame)
        .ok_or_else(|| anyhow!("the job has no frame {frame}"))?;
    let mut img = Image::new(fp.xres, fp.yres);
    let mut missing = Vec::new();
    // Pieces split off tiles while they rendered: pasted after their tile, largest first.
    for (i, tile_rect) in fp.tiles.iter().enumerate() {
        let of_tile: Vec<_> = pieces
            .get(&(frame, i))
            .map_or(&[][..], |v| &v[..])
            .iter()
            .map(|(r, _)| *r)
            .collect();
        for rect in super::piece::assemble_order(tile_rect, &of_tile) {
            let name = if rect == *tile_rect {
                task_name(frame, i)
            } else {
                super::piece::piece_name(frame, i, &rect)
            };
            match read_result(job, m, frame, &name, &rect) {
                Ok(px) => {
                    for row in 0..rect.h {
                        let dst = (rect.y0 + row) * fp.xres + rect.x0;
                        img.pixels[dst..dst + rect.w]
                            .copy_from_slice(&px[row * rect.w..(row + 1) * rect.w]);
                    }
                }
                Err(reason) => missing.push(MissingTile { task: name, reason }),
            }
        }
    }
    img.header = Header {
        software: Some(crate::runinfo::SOFTWARE.to_string()),
        view: Some(fp.view.to_radiance_string()),
        pixaspect: if (0.995..=1.005).contains(&fp.pixaspect) {
            None
        } else {
            Some(fp.pixaspect)
        },
        exposure: 1.0,
        format: "32-bit_rle_rgbe".to_string(),
        frame: (m.frames.len() > 1).then_some(frame),
        commands: vec![m.command.clone(), command.to_string()],
        ..Header::default()
    };
    let p = &m.params;
    if let Some(aa) = frame_accuracy(job, m, frame)? {
        img.header
            .extra
            .push(("TESSERA_FRAME_AA".into(), format!(" {aa}")));
    }
    if crate::ambient::settings::computes(p.ab, p.ad) {
        img.header.extra.push((
            crate::session::AMBIENT_HEADER_VAR.into(),
            format!(" {}", p.amb.to_text()),
        ));
    }
    if !missing.is_empty() {
        img.header.extra.push((
            "TESSERA_MISSING_TILES".into(),
            missing
                .iter()
                .map(|t| t.task.clone())
                .collect::<Vec<_>>()
                .join(" "),
        ));
    }
    Ok((img, missing))
}

/// The missing or invalid tiles of a frame, each with why, for a message.
pub fn missing_list(missing: &[MissingTile]) -> String {
    missing
        .iter()
        .map(|t| format!("{} ({})", t.task, t.reason))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The results of point job `job` (`p`: its plan) in input order, to `output` or standard
/// output; with `partial`, missing chunks as zeros, else an error message and status 1.
pub fn write_points(
    job: &JobDir,
    m: &Manifest,
    p: &super::points::PointsPlan,
    output: Option<&std::path::Path>,
    partial: bool,
    cmd: &str,
) -> Result<i32> {
    let pieces = job_pieces(job)?;
    let (img, missing) = assemble_frame(job, m, &pieces, 0, cmd)?;
    if !missing.is_empty() {
        let list = missing_list(&missing);
        if !partial {
            eprintln!(
                "tassemble: error: {} of {} chunks missing or invalid: {} (run tpiece on the \
                 job to trace them, or pass --partial to write zeros)",
                missing.len(),
                m.frames[0].tiles.len(),
                list
            );
            return Ok(1);
        }
        eprintln!(
            "tassemble: warning - {} chunks written as zeros: {}",
            missing.len(),
            list
        );
    }
    let rays = super::points::load_rays(job, p)?;
    let bytes = super::points::records(p, &rays, &img.pixels, &m.command);
    match output {
        Some(o) => crate::image::output::write_atomic(o, |f| std::io::Write::write_all(f, &bytes))
            .with_context(|| format!("cannot write {}", o.display()))?,
        None => {
            let mut out = std::io::stdout().lock();
            std::io::Write::write_all(&mut out, &bytes)
                .and_then(|()| std::io::Write::flush(&mut out))
                .context("cannot write the results")?;
        }
    }
    Ok(0)
}
