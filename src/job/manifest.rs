//! The job manifest (`manifest.json`) and job creation (`tplan`).

use super::plan::{
    check_cover, default_tiles, pixel_cost_floor, plan_fixed, plan_tiles, tiles_for_loops, TileRect,
};
use super::{check_plain_name, hex32, parse_hex32, task_name, JobDir};
use crate::options::{parse_rpict_args, Command, PictureParams, RenderParams, RpictOptions};
use crate::render::world::Scene;
use crate::scene::{read_scene_files, Primitive, ReadOptions};
use crate::view::{normaspect, parse_view_line, View};
use anyhow::{anyhow, bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The manifest's `format` value.
pub const FORMAT: &str = "tessera-job";
/// The manifest version written and read by this code.
pub const VERSION: u32 = 1;
/// Default lease: a claimed tile whose worker's heartbeat has not changed for this long (as
/// seen by another worker's own clock) may be re-claimed.
pub const DEFAULT_LEASE: f64 = 180.0;
/// Longest lease accepted (30 days): a worker's clocks and timers hold it as a duration.
pub const MAX_LEASE: f64 = 30.0 * 86400.0;
pub use super::MAX_RES;
/// Most frames and tiles per frame (task names have five digits).
const MAX_INDEX: usize = 99_999;

/// One frame of a job.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FramePlan {
    /// Frame number (seeds the frame's random numbers; tasks are named after it).
    pub index: u32,
    /// The view.
    pub view: View,
    /// Picture width (after `-pa` adjustment).
    pub xres: usize,
    /// Picture height.
    pub yres: usize,
    /// Pixel aspect ratio written to the picture header.
    pub pixaspect: f64,
    /// The tiles, in the order workers take them.
    pub tiles: Vec<TileRect>,
}

/// The job manifest.
///
/// Manifests written before the options split (an `options` object holding tpict's whole
/// command line) still read: their render and picture parameters are taken from it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ManifestFile")]
pub struct Manifest {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// The program that made the job.
    pub software: String,
    /// The `tplan` command line (for picture headers).
    pub command: String,
    /// The rendering parameters (the light transport; hashed into the fingerprint).
    pub params: RenderParams,
    /// The picture parameters (the first frame's view, resolution, pixel options).
    pub picture: PictureParams,
    /// The flattened scene, a file name in the job directory.
    pub scene_file: String,
    /// The scene files as given to tplan (informational).
    pub scene_sources: Vec<String>,
    /// Number of primitives in the flattened scene.
    pub primitives: usize,
    /// Fingerprint of the scene and the options that change ambient values (hex).
    pub fingerprint: String,
    /// Lease in seconds (see [`DEFAULT_LEASE`]).
    pub lease_seconds: f64,
    /// Workers the plan was made for.
    pub workers_expected: usize,
    /// Tile loops per worker the plan was made for (`tplan --threads`; manifests without
    /// it: 1).
    #[serde(default = "one")]
    pub threads_expected: usize,
    /// The default plan's estimate of the first frame's CPU seconds ([`super::probe`]), when
    /// it was planned that way (informational).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_cost_estimate: Option<f64>,
    /// For a job made from a rif file: rad's last step, which `tassemble` applies
    /// ([`super::finish`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub finish: Option<super::finish::Finish>,
    /// For a job over a point set: its rays' layout and output ([`super::points`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<super::points::PointsPlan>,
    /// Whether workers may split a tile while it renders ([`super::piece`]; `tplan
    /// --no-split` turns it off; never for point jobs). Manifests without it: yes.
    #[serde(default = "yes")]
    pub split: bool,
    /// The frames.
    pub frames: Vec<FramePlan>,
}

fn yes() -> bool {
    true
}

fn one() -> usize {
    1
}

/// A manifest as stored: today's (`params`, `picture`) or one written before the options
/// split (`options`, tpict's command line, of which only render and picture parameters are
/// used).
#[derive(Deserialize)]
struct ManifestFile {
    format: String,
    version: u32,
    software: String,
    command: String,
    params: Option<RenderParams>,
    picture: Option<PictureParams>,
    options: Option<OldOptions>,
    scene_file: String,
    scene_sources: Vec<String>,
    primitives: usize,
    fingerprint: String,
    lease_seconds: f64,
    workers_expected: usize,
    #[serde(default = "one")]
    threads_expected: usize,
    #[serde(default)]
    frame_cost_estimate: Option<f64>,
    #[serde(default)]
    finish: Option<super::finish::Finish>,
    #[serde(default)]
    points: Option<super::points::PointsPlan>,
    #[serde(default = "yes")]
    split: bool,
    frames: Vec<FramePlan>,
}

/// The `options` object of a manifest written before the options split.
#[derive(Deserialize)]
struct OldOptions {
    params: RenderParams,
    #[serde(flatten)]
    picture: PictureParams,
}

impl TryFrom<ManifestFile> for Manifest {
    type Error = String;
    fn try_from(f: ManifestFile) -> std::result::Result<Manifest, String> {
        let (params, picture) = match (f.params, f.picture, f.options) {
            (Some(r), Some(p), _) => (r, p),
            (None, None, Some(o)) => (o.params, o.picture),
            _ => return Err("missing field `params` or `picture`".into()),
        };
        Ok(Manifest {
            format: f.format,
            version: f.version,
            software: f.software,
            command: f.command,
            params,
            picture,
            scene_file: f.scene_file,
            scene_sources: f.scene_sources,
            primitives: f.primitives,
            fingerprint: f.fingerprint,
            lease_seconds: f.lease_seconds,
            workers_expected: f.workers_expected,
            threads_expected: f.threads_expected,
            frame_cost_estimate: f.frame_cost_estimate,
            finish: f.finish,
            points: f.points,
            split: f.split,
            frames: f.frames,
        })
    }
}

/// The largest manifest read (99,999 frames of many tiles stay far below it).
pub const MAX_MANIFEST_BYTES: u64 = 1 << 30;

impl Manifest {
    /// Read and validate `JOB/manifest.json`.
    pub fn load(job: &JobDir) -> Result<Manifest> {
        let path = job.manifest();
        let text = crate::safefile::read_text_bounded(&path, MAX_MANIFEST_BYTES)
            .with_context(|| format!("cannot read job manifest {}", path.display()))?;
        let m: Manifest = serde_json::from_str(&text).map_err(|e| {
            anyhow!(
                "{}:{}:{}: bad job manifest: {e}",
                path.display(),
                e.line(),
                e.column()
            )
        })?;
        m.validate()
            .map_err(|e| anyhow!("{}: invalid job manifest: {e}", path.display()))?;
        Ok(m)
    }

    /// Check everything a hand-edited or hostile manifest could get wrong.
    pub fn validate(&self) -> Result<()> {
        if self.format != FORMAT {
            bail!("format is '{}', expected '{FORMAT}'", self.format);
        }
        if self.version != VERSION {
            bail!(
                "version {} (this program reads version {VERSION})",
                self.version
            );
        }
        check_plain_name(&self.scene_file).context("scene_file")?;
        if let Some(f) = &self.finish {
            f.validate()?;
        }
        if let Some(p) = &self.points {
            p.validate()?;
            let size = p.frame_size();
            if self.frames.len() != 1 || (self.frames[0].xres, self.frames[0].yres) != size {
                bail!("points: the frame does not hold the plan's rays");
            }
        }
        if parse_hex32(&self.fingerprint).is_none() {
            bail!("fingerprint must be 64 hex digits");
        }
        if !(self.lease_seconds.is_finite() && self.lease_seconds > 0.0)
            || self.lease_seconds > MAX_LEASE
        {
            bail!("lease_seconds must be a positive number of seconds, at most {MAX_LEASE}");
        }
        if self.frames.is_empty() {
            bail!("no frames");
        }
        if self.frames.len() > MAX_INDEX {
            bail!("{} frames (at most {MAX_INDEX})", self.frames.len());
        }
        let mut seen = std::collections::HashSet::new();
        for f in &self.frames {
            let n = f.index;
            if n as usize > MAX_INDEX {
                bail!("frame {n}: index above {MAX_INDEX}");
            }
            if !seen.insert(n) {
                bail!("frame {n} appears twice");
            }
            if f.xres == 0 || f.yres == 0 || f.xres > MAX_RES || f.yres > MAX_RES {
                bail!("frame {n}: resolution {}x{} out of range", f.xres, f.yres);
            }
            if !(f.pixaspect.is_finite() && f.pixaspect > 0.0) {
                bail!("frame {n}: bad pixaspect");
            }
            f.view
                .frame()
                .map_err(|e| anyhow!("frame {n}: bad view: {e}"))?;
            if f.tiles.is_empty() || f.tiles.len() > MAX_INDEX {
                bail!("frame {n}: {} tiles", f.tiles.len());
            }
            check_cover(f.xres, f.yres, &f.tiles).map_err(|e| anyhow!("frame {n}: {e}"))?;
        }
        Ok(())
    }

    /// The fingerprint as bytes.
    pub fn fingerprint_bytes(&self) -> [u8; 32] {
        parse_hex32(&self.fingerprint).unwrap_or([0; 32])
    }

    /// The frame with number `index`.
    pub fn frame(&self, index: u32) -> Option<&FramePlan> {
        self.frames.iter().find(|f| f.index == index)
    }

    /// Every task of the job in the order workers take them: frame by frame, each frame's
    /// tiles largest first.
    pub fn tasks(&self) -> Vec<(String, u32, usize)> {
        let mut out = Vec::new();
        for f in &self.frames {
            for i in 0..f.tiles.len() {
                out.push((task_name(f.index, i), f.index, i));
            }
        }
        out
    }

    /// The tile of a task.
    pub fn tile(&self, frame: u32, tile: usize) -> Option<&TileRect> {
        self.frame(frame)?.tiles.get(tile)
    }
}

/// What `tplan` was asked for.
#[derive(Clone, Debug, Default)]
pub struct PlanRequest {
    /// `--tiles N` (per frame).
    pub tiles: Option<usize>,
    /// `--tile-size W H`.
    pub tile_size: Option<(usize, usize)>,
    /// `--workers N` (default 4): sets the default tile count.
    pub workers: Option<usize>,
    /// `--threads T` (default 1): the tile loops of each worker, for the default tile count.
    pub threads: Option<usize>,
    /// `--frames VIEWFILE`: one view per line, each on top of the previous.
    pub frames: Option<String>,
    /// Views given directly, one frame each (a rif file's views); each stands alone.
    pub views: Option<Vec<View>>,
    /// `--path KEYFILE --path-frames N`: N frames along a keyframed camera path.
    pub path: Option<(String, usize)>,
    /// `--lease SECONDS`.
    pub lease: Option<f64>,
    /// `--no-split`: workers never split a tile while it renders.
    pub no_split: bool,
    /// `--ambient FILE`: seed the job's ambient store.
    pub ambient: Option<String>,
    /// Accept an ambient store with another fingerprint.
    pub amb_force: bool,
    /// The rpict options and scene files.
    pub args: Vec<String>,
    /// The full command line (for headers).
    pub command: String,
    /// A rif job's last step (rad's pfilt), applied by `tassemble`.
    pub finish: Option<super::finish::Finish>,
    /// `--points FILE [--chunk N]`: a job over the rays of FILE (the arguments are then
    /// rtrace's options and the scene).
    pub points: Option<(String, Option<usize>)>,
}

/// Write primitives back in Radiance's scene syntax (numbers in shortest round-trip form,
/// so reading the text gives identical primitives).
pub fn scene_text(prims: &[Primitive], sources: &[String]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Flattened by {} from: {}",
        crate::runinfo::SOFTWARE,
        sources.join(" ")
    );
    crate::scene::primitive::write_text(prims, &mut s);
    s
}

/// Create a job directory (`tplan`). The directory is assembled under a temporary name
/// beside `dir` and renamed into place, so a job directory is either complete or absent.
/// The job's scene image ([`crate::scene::image`]): the planner's built geometry, which
/// workers map instead of building it.
pub const SCENE_IMAGE: &str = "scene.img";

pub fn create_job(dir: &Path, req: &PlanRequest) -> Result<Manifest> {
    let (opts, points, rays) = match &req.points {
        Some((file, chunk)) => points_options(req, file, *chunk)?,
        None => match parse_rpict_args(&req.args).map_err(|e| anyhow!(e))? {
            Command::Render(o) => (*o, None, Vec::new()),
            _ => bail!("tplan needs render options and scene files after '--'"),
        },
    };
    let opts: RpictOptions = opts;
    if opts.run.sequence_start.is_some() {
        bail!("-S has no meaning in a job: give the frames' views with --frames VIEWFILE");
    }
    if opts.run.output.is_some() {
        bail!("-o has no meaning in a job: pictures come from tassemble");
    }
    if opts.run.amb_file.is_some() {
        bail!("-af has no meaning in a job: seed the job's ambient store with --ambient FILE");
    }
    if opts.run.amb_log.is_some() || opts.run.stats_file.is_some() {
        bail!("--amb-log and --stats have no meaning in a job: workers keep their own logs and statistics");
    }
    if opts.picture.pm != 0.0 || opts.picture.pd != 0.0 {
        bail!("-pm (motion blur) and -pd (depth of field) are not supported yet; use -pm 0 -pd 0");
    }
    if opts.params.axt.is_some() && opts.params.ax.is_some() {
        bail!("-axt and -ax/-axg both choose -aa per frame: give one of them");
    }
    if let Some(why) = opts.params.refused() {
        bail!("{why}");
    }
    if opts.scene_files.is_empty() {
        bail!("no scene files given (a job cannot read its scene from standard input)");
    }
    if dir.exists() {
        let empty = std::fs::read_dir(dir)
            .map(|mut d| d.next().is_none())
            .unwrap_or(false);
        if !empty {
            bail!(
                "job directory {} exists and is not empty; choose a new one",
                dir.display()
            );
        }
    }
    // Scene: read, check that it builds, flatten.
    let mut ro = ReadOptions::from_env();
    ro.allow_commands |= opts.run.allow_commands;
    ro.obj_material.clone_from(&opts.run.obj_material);
    if let Some(n) = opts.run.max_primitives {
        ro.max_primitives = n;
    }
    let prims = read_scene_files(&opts.scene_files, &ro)?;
    // What the job keeps of the primitives, before the build frees them.
    let scene_fingerprint = crate::ambient::fingerprint::fingerprint(&prims, &opts.params);
    let text = scene_text(&prims, &opts.scene_files);
    let mut rest = crate::scene::image::Rest::of(&prims, scene_fingerprint);
    rest.scene_file = Some((text.len() as u64, crc32fast::hash(text.as_bytes())));
    let primitives = prims.len();
    let scene = Scene::build_taking(prims, &ro)?;
    for w in &scene.warnings {
        eprintln!("tplan: warning - {w}");
    }
    let fingerprint = crate::ambient::fingerprint::with_inputs(scene_fingerprint, &scene.inputs)
        .map_err(|e| anyhow!("cannot read a scene input: {e}"))?;
    // Frames.
    let mut views: Vec<View> = Vec::new();
    match &req.frames {
        None if req.views.is_some() => views.extend(req.views.iter().flatten().cloned()),
        None if req.path.is_some() => {
            let (keyfile, n) = req.path.as_ref().expect("path");
            let keys = super::path::read_keys(keyfile, &opts.picture.view)?;
            views = super::path::frames(&keys, *n)?;
        }
        None => views.push(opts.picture.view.clone()),
        Some(vf) => {
            let content = std::fs::read_to_string(vf)
                .with_context(|| format!("cannot read frames file {vf}"))?;
            let mut base = opts.picture.view.clone();
            for (i, line) in content.lines().enumerate() {
                let v = parse_view_line(line, &base).map_err(|e| anyhow!("{vf}:{}: {e}", i + 1))?;
                if let Some(v) = v {
                    v.frame()
                        .map_err(|e| anyhow!("{vf}:{}: bad view: {e}", i + 1))?;
                    base = v.clone();
                    views.push(v);
                }
            }
            if views.is_empty() {
                bail!("frames file {vf} has no view lines");
            }
        }
    }
    let workers = req.workers.unwrap_or(4).max(1);
    let threads = req.threads.unwrap_or(1).clamp(1, workers);
    let mut frames = Vec::new();
    // The default plan: every frame's tiles from the first frame's measured cost per pixel.
    let mut per_pixel: Option<f64> = None;
    let mut frame_cost_estimate = None;
    for (i, v) in views.into_iter().enumerate() {
        let vfr = v.frame().map_err(|e| anyhow!("bad view: {e}"))?;
        let mut pa = opts.picture.pa;
        let (mut x, mut y) = (opts.picture.x, opts.picture.y);
        if points.is_none() {
            normaspect(vfr.aspect(), &mut pa, &mut x, &mut y);
        }
        if x == 0 || y == 0 || x > MAX_RES || y > MAX_RES {
            bail!("resolution {x}x{y} is out of range");
        }
        // Tile edges on the sampling grid (cells of `cell_size(-ps)` pixels): no cell is
        // traced by two tiles.
        let grid = crate::render::cell_size(opts.picture.ps.max(1));
        // Workers of several loops that split tiles: a few tiles a loop, whatever the frame
        // costs (no probe).
        let by_loops = tiles_for_loops(x * y, workers, threads).filter(|_| !req.no_split);
        let tiles = match (req.tile_size, req.tiles.or(by_loops)) {
            _ if points.is_some() => {
                plan_fixed(x, y, x, points.as_ref().map_or(1, |p| p.rows_per_task))
            }
            (Some((tw, th)), _) => plan_fixed(x, y, tw, th),
            (None, Some(n)) => plan_tiles(x, y, n, grid),
            (None, None) => {
                let floor = pixel_cost_floor(opts.params.ab);
                let cost = match per_pixel {
                    Some(c) => c,
                    None => {
                        let fs = opts
                            .picture
                            .frame_setup(&opts.params, &vfr, (x, y), i as u32);
                        let p =
                            super::probe::probe(&scene, &opts.params, &fs, super::probe::BUDGET)
                                .context("the cost probe of the default plan failed")?;
                        let c = (p.frame_seconds / (x * y) as f64).max(floor);
                        frame_cost_estimate = Some(c * (x * y) as f64);
                        per_pixel = Some(c);
                        c
                    }
                };
                let n = default_tiles(x, y, workers, cost);
                plan_tiles(x, y, n, grid)
            }
        };
        if tiles.len() > MAX_INDEX {
            bail!("{} tiles per frame (at most {MAX_INDEX})", tiles.len());
        }
        frames.push(FramePlan {
            index: i as u32,
            view: v,
            xres: x,
            yres: y,
            pixaspect: if (0.995..=1.005).contains(&pa) {
                1.0
            } else {
                pa
            },
            tiles,
        });
    }
    let RpictOptions {
        params,
        mut picture,
        scene_files: sources,
        ..
    } = opts;
    picture.view = frames[0].view.clone();
    let lease = req.lease.unwrap_or(DEFAULT_LEASE);
    if !(lease.is_finite() && lease > 0.0) || lease > MAX_LEASE {
        bail!("--lease must be a positive number of seconds, at most {MAX_LEASE} (30 days)");
    }
    let m = Manifest {
        format: FORMAT.into(),
        version: VERSION,
        software: crate::runinfo::SOFTWARE.into(),
        command: req.command.clone(),
        params,
        picture,
        scene_file: "scene.rad".into(),
        scene_sources: sources,
        primitives,
        fingerprint: hex32(&fingerprint),
        lease_seconds: lease,
        workers_expected: workers,
        threads_expected: threads,
        frame_cost_estimate,
        finish: req.finish.clone(),
        split: !req.no_split && points.is_none(),
        points,
        frames,
    };
    m.validate()?;
    // Build the directory under a temporary name, then rename it into place.
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent)
        .with_context(|| format!("cannot create {}", parent.display()))?;
    let tmp = tempfile::Builder::new()
        .prefix(".tplan-")
        .tempdir_in(&parent)
        .with_context(|| format!("cannot create a directory in {}", parent.display()))?;
    let job = JobDir::new(tmp.path());
    for d in job.subdirs() {
        std::fs::create_dir(&d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    super::write_file_atomic(&job.file("scene.rad"), text.as_bytes())
        .context("cannot write scene.rad")?;
    copy_inputs(&job, &scene.inputs)?;
    // The built geometry, which workers map instead of building (one copy per node).
    super::write_file_atomic(
        &job.file(SCENE_IMAGE),
        &crate::scene::image::encode(&fingerprint, &rest, &scene.geom),
    )
    .with_context(|| format!("cannot write {SCENE_IMAGE}"))?;
    if m.points.is_some() {
        super::write_file_atomic(
            &job.file(super::points::RAYS_FILE),
            &super::points::encode_rays(&rays),
        )
        .context("cannot write the job's rays")?;
    }
    for (name, _, _) in m.tasks() {
        std::fs::File::create(job.tasks().join(format!("{name}.todo")))
            .with_context(|| format!("cannot create task {name}"))?;
    }
    if let Some(a) = &req.ambient {
        super::merge::seed_store(&job, Path::new(a), &fingerprint, req.amb_force)?;
    }
    let json = serde_json::to_string_pretty(&m)?;
    super::write_file_atomic(&job.manifest(), json.as_bytes())
        .context("cannot write manifest.json")?;
    let tmp_path = tmp.keep();
    if dir.exists() {
        // An empty directory given by the user: replace it.
        std::fs::remove_dir(dir)
            .with_context(|| format!("cannot replace empty directory {}", dir.display()))?;
    }
    if let Err(e) = std::fs::rename(&tmp_path, dir) {
        let _ = std::fs::remove_dir_all(&tmp_path);
        return Err(anyhow!(
            "cannot create job directory {}: {e}",
            dir.display()
        ));
    }
    super::sync_dir(&parent);
    Ok(m)
}

/// A point job's options: rtrace's command line after `--` (its `-o` letters of `v`, `o`,
/// `d`), the rays of `file` read in its input format, and the plan of their chunks; the
/// job renders through the picture machinery, so the options are given as rpict's.
fn points_options(
    req: &PlanRequest,
    file: &str,
    chunk: Option<usize>,
) -> Result<(
    RpictOptions,
    Option<super::points::PointsPlan>,
    Vec<crate::ttrace::records::InRay>,
)> {
    use crate::options::rtrace::{parse_rtrace_args, Format, TraceCommand};
    let o = match parse_rtrace_args(&req.args).map_err(|e| anyhow!(e))? {
        TraceCommand::Trace(o) => *o,
        _ => bail!("tplan --points needs rtrace options and scene files after '--'"),
    };
    let t = &o.trace;
    if let Some(c) = t.spec.chars().find(|c| !"vod".contains(*c)) {
        bail!(
            "-o{}: a point job writes v (value), o (origin) and d (direction), not '{c}'",
            t.spec
        );
    }
    if t.flush > 0 || t.yres > 0 {
        bail!("-x and -y have no meaning in a point job (tassemble writes every record)");
    }
    let rays = super::points::read_points(Path::new(file), t.input)?;
    let workers = req.workers.unwrap_or(4).max(1);
    let mut plan = super::points::PointsPlan::new(rays.len() as u64, workers, chunk)?;
    plan.at_origin = t.irradiance_at_origin;
    plan.limit_distance = t.limit_distance;
    plan.output = match t.output {
        Format::Ascii => 'a',
        Format::Float => 'f',
        Format::Double => 'd',
    };
    plan.spec.clone_from(&t.spec);
    plan.header = t.header;
    let (x, y) = plan.frame_size();
    let picture = PictureParams {
        x,
        y,
        ps: 1,
        ..PictureParams::default()
    };
    let opts = RpictOptions {
        params: o.params,
        picture,
        run: o.run,
        scene_files: o.scene_files,
    };
    Ok((opts, Some(plan), rays))
}

/// Copy the files the scene's primitives read by relative name (function files, data
/// files, pictures, fonts, text) into `JOB/files/` under the same names, so that workers
/// find them whatever their directory and RAYPATH. Absolute names are left as they are
/// (a shared filesystem); names climbing out with `..` are refused.
fn copy_inputs(job: &JobDir, inputs: &[(String, std::path::PathBuf)]) -> Result<()> {
    let dir = job.root().join(INPUTS_DIR);
    for (name, path) in inputs {
        let rel = Path::new(name);
        // A name that climbs out (`../up.cal`) would be looked up by a worker from the
        // job's own folders, outside the job: it cannot be carried, so it is refused here
        // rather than failing on every worker later.
        if rel
            .components()
            .any(|c| matches!(c, std::path::Component::ParentDir))
        {
            bail!(
                "the scene reads '{name}' ({}), a name that climbs out with '..': a job \
                 carries the files a scene names inside its folders only; name it without \
                 '..' (put its folder on RAYPATH) or give an absolute path",
                path.display()
            );
        }
        if rel
            .components()
            .any(|c| !matches!(c, std::path::Component::Normal(_)))
        {
            continue;
        }
        let dest = dir.join(rel);
        if let Some(p) = dest.parent() {
            std::fs::create_dir_all(p).with_context(|| format!("cannot create {}", p.display()))?;
        }
        // A built-in library file (no RAYPATH held one) is written out: workers whose
        // RAYPATH holds Radiance's version read the planner's.
        match crate::cal::builtin_library_text(path) {
            Some(text) => std::fs::write(&dest, text)
                .with_context(|| format!("cannot write {} into the job", dest.display()))?,
            None => {
                std::fs::copy(path, &dest)
                    .with_context(|| format!("cannot copy {} into the job", path.display()))?;
            }
        }
    }
    Ok(())
}

/// Where a job keeps the files its scene reads by relative name ([`copy_inputs`]).
pub const INPUTS_DIR: &str = "files";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flattened_scene_reads_back_identically() {
        let src = "void plastic red\n0\n0\n5 .5 .1 .1 0 0\n\nred sphere ball\n0\n0\n4 1e-7 2.5 -3 0.1\nred alias other red\nvoid light l 0 0 3 100 100 100\n";
        let prims = crate::scene::parse_scene_text(src, "t.rad", &ReadOptions::default()).unwrap();
        let text = scene_text(&prims, &["t.rad".into()]);
        let back = crate::scene::parse_scene_text(&text, "f.rad", &ReadOptions::default()).unwrap();
        assert_eq!(prims.len(), back.len());
        for (a, b) in prims.iter().zip(&back) {
            assert_eq!(
                (&a.modifier, &a.ptype, &a.name),
                (&b.modifier, &b.ptype, &b.name)
            );
            assert_eq!(a.sargs, b.sargs);
            assert_eq!(a.rargs, b.rargs);
        }
    }
    #[test]
    fn manifests_from_before_the_options_split_still_read() {
        let mut picture = PictureParams {
            x: 40,
            ps: 2,
            ..PictureParams::default()
        };
        picture.view.vh = 30.0;
        let params = RenderParams {
            ab: 2,
            ..RenderParams::default()
        };
        let m = Manifest {
            format: FORMAT.into(),
            version: VERSION,
            software: "t".into(),
            command: "tplan".into(),
            params: params.clone(),
            picture: picture.clone(),
            scene_file: "scene.rad".into(),
            scene_sources: vec!["a.rad".into()],
            primitives: 3,
            fingerprint: "00".repeat(32),
            lease_seconds: 180.0,
            workers_expected: 2,
            threads_expected: 1,
            frame_cost_estimate: None,
            finish: None,
            points: None,
            split: true,
            frames: Vec::new(),
        };
        let now = serde_json::to_value(&m).unwrap();
        assert_eq!(serde_json::from_value::<Manifest>(now.clone()).unwrap(), m);
        // The old layout: tpict's whole command line under `options`.
        let mut old = now.clone();
        let o = old.as_object_mut().unwrap();
        let mut options = o.remove("picture").unwrap();
        let mut p = o.remove("params").unwrap();
        p.as_object_mut()
            .unwrap()
            .insert("af".into(), serde_json::Value::Null);
        let opts = options.as_object_mut().unwrap();
        opts.insert("params".into(), p);
        opts.remove("overture");
        for (k, v) in [
            ("report_interval", serde_json::json!(0.0)),
            ("warnings", serde_json::json!(true)),
            ("threads", serde_json::Value::Null),
            ("scene_files", serde_json::json!(["scene.rad"])),
        ] {
            opts.insert(k.into(), v);
        }
        o.insert("options".into(), options);
        assert_eq!(serde_json::from_value::<Manifest>(old).unwrap(), m);
        // Neither layout: refused.
        let mut none = now;
        none.as_object_mut().unwrap().remove("params");
        assert!(serde_json::from_value::<Manifest>(none).is_err());
    }
}
