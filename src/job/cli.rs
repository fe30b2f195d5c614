//! Command lines of the toolkit's binaries (clap, `--long` options). Each `*_main` returns
//! the process exit status; errors are printed as `<program>: error: ...`.

use super::manifest::{create_job, Manifest, PlanRequest};
use super::worker::{run_worker, WorkerOptions};
use super::JobDir;
use crate::session::store::FlushPolicy;
use anyhow::{anyhow, bail, Context, Result};
use clap::Parser;
use std::path::PathBuf;

fn finish(program: &str, r: Result<i32>) -> i32 {
    match r {
        Ok(code) => code,
        Err(e) => {
            eprintln!(
                "{}",
                crate::runinfo::printable(&format!("{program}: error: {e:#}"))
            );
            1
        }
    }
}

fn command_line() -> String {
    let args: Vec<String> = std::env::args().collect();
    let mut line = args
        .first()
        .map(|a| {
            std::path::Path::new(a)
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .unwrap_or_default();
    for a in args.iter().skip(1) {
        line.push(' ');
        line.push_str(a);
    }
    line
}

/// `tplan`: make a job directory.
#[derive(Parser, Debug)]
#[command(
    name = "tplan",
    version,
    about = "Make a Tessera job directory: the scene, the options and the tile plan",
    after_help = "Example: tplan --workers 8 -o job -- -vf view.vf -x 1024 -y 768 -ab 2 scene.rad"
)]
struct TplanArgs {
    /// Tiles per frame (default: as many as keep the per-tile overhead
    /// within 2% of the frame's estimated cost, at most 80 per expected
    /// worker; see docs/batch.md).
    #[arg(long, conflicts_with = "tile_size", verbatim_doc_comment)]
    tiles: Option<usize>,
    /// Fixed tile size WxH (in reading order instead of largest first).
    #[arg(long, value_name = "WxH", verbatim_doc_comment)]
    tile_size: Option<String>,
    /// Cores the plan is made for: the tile loops of all the job's
    /// workers (default plan).
    #[arg(long, default_value_t = 4, verbatim_doc_comment)]
    workers: usize,
    /// Tile loops each worker runs (its tpiece --threads; default plan):
    /// with 2 or more, 3 tiles per loop, which the loops split among
    /// themselves as they finish; with 1, as many as the frame's
    /// estimated cost asks for.
    #[arg(long, default_value_t = 1, verbatim_doc_comment)]
    threads: usize,
    /// View file with one view per line: one frame per view (each on
    /// top of the previous).
    #[arg(long, value_name = "VIEWFILE", verbatim_doc_comment)]
    frames: Option<PathBuf>,
    /// A keyframed camera path: a file of key view lines (each on top
    /// of the previous); with --path-frames N, N frames spread along it
    /// (docs/animation.md).
    #[arg(long, value_name = "KEYFILE", requires = "path_frames", conflicts_with_all = ["frames", "rif"], verbatim_doc_comment)]
    path: Option<PathBuf>,
    /// Frames along --path.
    #[arg(long, value_name = "N", requires = "path", verbatim_doc_comment)]
    path_frames: Option<usize>,
    /// Seconds a claimed tile's worker may stay silent before another
    /// worker takes it over.
    #[arg(long, value_name = "SECONDS", default_value_t = super::manifest::DEFAULT_LEASE, verbatim_doc_comment)]
    lease: f64,
    /// Never split a tile while it renders (by default a worker gives
    /// part of its tile to idle workers when nothing is left to claim:
    /// docs/batch.md).
    #[arg(long, verbatim_doc_comment)]
    no_split: bool,
    /// Seed the job's ambient store from a Tessera store/log or a
    /// Radiance ambient file.
    #[arg(long, value_name = "FILE", verbatim_doc_comment)]
    ambient: Option<PathBuf>,
    /// Accept an ambient store made for another scene or other options.
    #[arg(long, verbatim_doc_comment)]
    amb_force: bool,
    /// Run a scene's inline commands other than xform and genbox
    /// through `sh` (as `--allow-commands` after `--`).
    #[arg(long, verbatim_doc_comment)]
    allow_commands: bool,
    /// A job over the rays of FILE (origin and direction per record, as
    /// ttrace reads them, in the format of -f): its tasks are chunks of
    /// rays; the arguments after `--` are rtrace's options and the
    /// scene (docs/ttrace.md).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["frames", "path", "rif", "tiles", "tile_size"], verbatim_doc_comment)]
    points: Option<PathBuf>,
    /// With --points: rays per task (default: about sixteen tasks per
    /// worker, at most 4096 rays each).
    #[arg(long, value_name = "N", requires = "points", verbatim_doc_comment)]
    chunk: Option<usize>,
    /// Make the job from a `rad` input file: its scene, materials,
    /// views and the rpict options rad derives (docs/rif.md); scene
    /// files may follow after `--`.
    #[arg(long, value_name = "FILE", verbatim_doc_comment)]
    rif: Option<PathBuf>,
    /// With --rif: render only this view (a view name of the file or a
    /// standard view id); default: every view of the file, one frame
    /// each.
    #[arg(long, value_name = "NAME", requires = "rif", verbatim_doc_comment)]
    view: Option<String>,
    /// With --rif: a `VAR=value` assignment applied after the file (as rad's
    /// arguments).
    #[arg(
        long = "set",
        value_name = "VAR=VALUE",
        requires = "rif",
        verbatim_doc_comment
    )]
    set: Vec<String>,
    /// With --rif: print the rpict options rad would use, one line per
    /// view, and make no job.
    #[arg(long, requires = "rif", verbatim_doc_comment)]
    print: bool,
    /// The job directory to create (must not exist, or be empty).
    #[arg(
        verbatim_doc_comment,
        short = 'o',
        long = "output",
        value_name = "JOBDIR",
        required_unless_present = "print"
    )]
    output: Option<PathBuf>,
    /// rpict options and scene files (after `--`); with --rif,
    /// more scene files.
    #[arg(
        verbatim_doc_comment,
        last = true,
        required_unless_present = "rif",
        value_name = "RPICT-OPTIONS-AND-SCENE"
    )]
    rest: Vec<String>,
}

/// Entry point of `tplan`.
pub fn tplan_main() -> i32 {
    let a = match TplanArgs::try_parse() {
        Ok(a) => a,
        Err(e) => return tplan_usage_error(e),
    };
    finish("tplan", tplan(a))
}

/// clap's answer to a bad tplan command line, except for the common slip of giving rpict's
/// options or the scene without `--` before them: one line saying so.
fn tplan_usage_error(e: clap::Error) -> i32 {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    let arg = match e.get(ContextKind::InvalidArg) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        _ => None,
    };
    let hint = "put rpict's options and the scene after `--`, e.g. tplan -o job -- -vf \
                view.vf -ab 1 scene.rad";
    match (e.kind(), arg) {
        (ErrorKind::UnknownArgument, Some(a)) if a.starts_with('-') && !a.starts_with("--") => {
            // clap names the first letter of `-vf`: show the word as given.
            let word = std::env::args()
                .skip(1)
                .find(|w| w.starts_with(&a))
                .unwrap_or(a);
            eprintln!("tplan: error: '{word}' is an rpict option: {hint}");
            2
        }
        (ErrorKind::UnknownArgument, Some(a)) if !a.starts_with('-') => {
            eprintln!("tplan: error: '{a}': {hint}");
            2
        }
        _ => e.exit(),
    }
}

fn parse_size(s: &str) -> Result<(usize, usize)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| anyhow!("--tile-size '{s}': expected WxH, e.g. 64x48"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<usize>()
            .ok()
            .filter(|n| *n > 0)
            .ok_or_else(|| anyhow!("--tile-size '{s}': '{v}' is not a positive integer"))
    };
    Ok((p(w)?, p(h)?))
}

fn tplan(a: TplanArgs) -> Result<i32> {
    if a.workers == 0 {
        bail!("--workers must be at least 1");
    }
    if a.tiles == Some(0) {
        bail!("--tiles must be at least 1");
    }
    if a.threads == 0 || a.threads > a.workers {
        bail!(
            "--threads {} must be from 1 to --workers ({}): the tile loops of each worker, \
             out of all the job's loops",
            a.threads,
            a.workers
        );
    }
    let output = match (&a.rif, a.output.clone()) {
        (Some(_), _) if a.print => return rif_print(&a),
        (_, Some(o)) => o,
        (_, None) => bail!("--output JOBDIR is required"),
    };
    let (rest, views, finish) = match &a.rif {
        Some(_) => {
            if a.frames.is_some() {
                bail!("--frames and --rif do not go together: the rif file's views are the frames");
            }
            rif_job_args(&a)?
        }
        None => (a.rest.clone(), None, None),
    };
    let req = PlanRequest {
        tiles: a.tiles,
        tile_size: a.tile_size.as_deref().map(parse_size).transpose()?,
        workers: Some(a.workers),
        threads: Some(a.threads),
        frames: a.frames.map(|p| p.display().to_string()),
        views,
        path: a
            .path
            .as_ref()
            .map(|p| (p.display().to_string(), a.path_frames.unwrap_or(0))),
        lease: Some(a.lease),
        no_split: a.no_split,
        ambient: a.ambient.map(|p| p.display().to_string()),
        amb_force: a.amb_force,
        args: if a.allow_commands {
            std::iter::once("--allow-commands".to_string())
                .chain(rest)
                .collect()
        } else {
            rest
        },
        command: command_line(),
        finish,
        points: a
            .points
            .as_ref()
            .map(|p| (p.display().to_string(), a.chunk)),
    };
    let m = create_job(&output, &req)?;
    let tiles: usize = m.frames.iter().map(|f| f.tiles.len()).sum();
    let f0 = &m.frames[0];
    eprintln!(
        "tplan: job {}: {} frame(s) of {}x{}, {} tiles, {} primitives, lease {} s",
        output.display(),
        m.frames.len(),
        f0.xres,
        f0.yres,
        tiles,
        m.primitives,
        m.lease_seconds
    );
    let default_plan = a.tiles.is_none() && a.tile_size.is_none() && m.points.is_none();
    if default_plan && m.frame_cost_estimate.is_none() && m.threads_expected >= 2 && m.split {
        eprintln!(
            "tplan: the default plan for workers of {} tile loops: {:.1} tiles per loop, which \
             a worker's loops split among themselves (docs/batch.md, \"The tile plan\")",
            m.threads_expected,
            f0.tiles.len() as f64 / a.workers.max(1) as f64
        );
    }
    if let Some(c) = m.frame_cost_estimate {
        eprintln!(
            "tplan: the default plan: {:.1} tiles per worker for a frame estimated at {c:.2} \
             CPU-s by the cost probe (docs/batch.md, \"The tile plan\")",
            f0.tiles.len() as f64 / a.workers.max(1) as f64
        );
    }
    Ok(0)
}

/// The rif file's plan, its selected views and the view each gives rpict (checked: an
/// unknown name, a missing view file or a view that is no view is an error).
type RifViews = (
    crate::rif::derive::RadPlan,
    Vec<crate::rif::views::RadView>,
    Vec<crate::view::View>,
);

fn rif_plan(a: &TplanArgs) -> Result<RifViews> {
    let path = a.rif.as_ref().expect("--rif");
    let mut ro = crate::scene::ReadOptions::from_env();
    ro.allow_commands |= a.allow_commands;
    let plan = crate::rif::load(path, &a.set, &a.rest, &ro)?;
    for w in &plan.warnings {
        eprintln!("tplan: warning - {w}");
    }
    let views = plan
        .select(a.view.as_deref())
        .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let resolved = views
        .iter()
        .map(|v| v.resolve())
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    // As rad, write OPTFILE (even for --print): the options refer to it as @file.
    if let Some((name, text)) = plan.optfile() {
        crate::image::output::write_atomic(std::path::Path::new(&name), |f| {
            std::io::Write::write_all(f, text.as_bytes())
        })
        .with_context(|| format!("cannot write OPTFILE {name}"))?;
    }
    Ok((plan, views, resolved))
}

/// `tplan --rif FILE --print`: rad's rpict options, one line per view.
fn rif_print(a: &TplanArgs) -> Result<i32> {
    let (plan, views, _) = rif_plan(a)?;
    for v in &views {
        println!("{}", plan.rpict_words(v).join(" "));
    }
    Ok(0)
}

/// The job's rpict arguments and frame views from a rif file. rad's `-af` (the job has its
/// own store), `-t` and `-e` (rpict's progress reports) are left out.
type RifJobArgs = (
    Vec<String>,
    Option<Vec<crate::view::View>>,
    Option<super::finish::Finish>,
);

fn rif_job_args(a: &TplanArgs) -> Result<RifJobArgs> {
    let (plan, views, resolved) = rif_plan(a)?;
    let mut args = Vec::new();
    let words = plan.rpict_words_inline(&views[0]);
    let mut i = 0;
    while i < words.len() {
        if matches!(words[i].as_str(), "-af" | "-t" | "-e") {
            eprintln!(
                "tplan: note - rad's {} {} is not used by a job",
                words[i],
                words.get(i + 1).map_or("", |s| s.as_str())
            );
            i += 2;
            continue;
        }
        args.push(words[i].clone());
        i += 1;
    }
    args.extend(plan.scene_files.iter().cloned());
    let (finish, warnings) = super::finish::Finish::from_rad(plan.supersample, &plan.pfilt)
        .with_context(|| format!("{}", a.rif.as_ref().expect("--rif").display()))?;
    for w in warnings {
        eprintln!("tplan: warning - {w}");
    }
    for (n, v) in views.iter().enumerate() {
        eprintln!(
            "tplan: frame {n}: view {} (tassemble finishes it as rad's {})",
            v.name,
            plan.pfilt_command(v, &format!("frame{n}.hdr"))
        );
    }
    Ok((args, Some(resolved), finish.changes().then_some(finish)))
}

/// `tpiece`: a worker.
#[derive(Parser, Debug)]
#[command(
    name = "tpiece",
    version,
    about = "Render a Tessera job's tiles until none is left (run as many as you like)"
)]
struct TpieceArgs {
    /// The job directory.
    job: PathBuf,
    /// Worker id (default: $SLURM_ARRAY_JOB_ID-$SLURM_ARRAY_TASK_ID,
    /// else host-pid).
    #[arg(long, verbatim_doc_comment)]
    worker_id: Option<String>,
    /// Ambient values per log write (N_A), or `auto` to adapt it at
    /// run time.
    #[arg(
        long,
        default_value = "auto",
        value_name = "N|auto",
        verbatim_doc_comment
    )]
    amb_flush: String,
    /// Tile loops, each rendering its own tiles on one thread over one
    /// shared scene and ambient cache (default: $SLURM_CPUS_PER_TASK,
    /// else every core).
    #[arg(long, verbatim_doc_comment)]
    threads: Option<usize>,
    /// Exit when nothing is claimable instead of waiting for (and, if
    /// they die, re-claiming) tiles other workers hold.
    #[arg(long, verbatim_doc_comment)]
    no_wait: bool,
    /// Print nothing but errors (no per-tile or waiting lines).
    #[arg(long, short, verbatim_doc_comment)]
    quiet: bool,
    /// Build the scene instead of mapping the job's scene image
    /// (JOB/scene.img), and leave the image alone. Pictures are the
    /// same either way; with the image every worker on a node shares
    /// one copy of the top-level geometry and starts sooner.
    #[arg(long, verbatim_doc_comment)]
    no_scene_image: bool,
}

/// Entry point of `tpiece`.
pub fn tpiece_main() -> i32 {
    let a = TpieceArgs::parse();
    finish("tpiece", tpiece(a))
}

fn tpiece(a: TpieceArgs) -> Result<i32> {
    let amb_flush = match a.amb_flush.as_str() {
        "auto" => FlushPolicy::Auto,
        n => {
            FlushPolicy::Fixed(n.parse::<usize>().ok().filter(|n| *n > 0).ok_or_else(|| {
                anyhow!("--amb-flush '{n}': expected a positive number or 'auto'")
            })?)
        }
    };
    if a.threads == Some(0) {
        bail!("--threads must be at least 1");
    }
    let wo = WorkerOptions {
        worker_id: a.worker_id,
        amb_flush,
        threads: a.threads,
        wait: !a.no_wait,
        verbose: !a.quiet,
        scene_image: !a.no_scene_image,
    };
    let s = run_worker(&JobDir::new(a.job), &wo)?;
    if !a.quiet {
        eprintln!(
            "tpiece {}: finished, {} tiles rendered ({} re-claimed)",
            s.owner, s.tiles, s.reclaimed
        );
    }
    Ok(0)
}

/// `tmerge`: merge ambient logs.
#[derive(Parser, Debug)]
#[command(
    name = "tmerge",
    version,
    about = "Merge a job's ambient logs into its store (safe while workers run)"
)]
struct TmergeArgs {
    /// The job directory.
    job: PathBuf,
    /// Also write the merged values in Radiance's ambient format (for
    /// rpict -af).
    #[arg(long, value_name = "FILE", verbatim_doc_comment)]
    export_radiance: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long, verbatim_doc_comment)]
    json: bool,
}

/// Entry point of `tmerge`.
pub fn tmerge_main() -> i32 {
    let a = TmergeArgs::parse();
    finish("tmerge", tmerge(a))
}

fn tmerge(a: TmergeArgs) -> Result<i32> {
    let job = JobDir::new(&a.job);
    let m = Manifest::load(&job)?;
    let fp = m.fingerprint_bytes();
    let opts = crate::ambient::fingerprint::options_text(&m.params);
    let r = super::merge::merge(&job, &fp, &opts)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        eprintln!(
            "tmerge: {} logs, {} values added ({} duplicates), {} in the store{}",
            r.logs,
            r.added,
            r.duplicates,
            r.total,
            if r.written.is_none() {
                " (unchanged)"
            } else {
                ""
            }
        );
        for t in &r.torn {
            eprintln!("tmerge: {t}: incomplete last record left for the next merge");
        }
        for c in &r.corrupt {
            eprintln!("tmerge: warning - damaged record, log read up to it: {c}");
        }
        for c in &r.refused {
            eprintln!("tmerge: warning - log refused: {c}");
        }
        for (name, n) in &r.invalid {
            eprintln!("tmerge: warning - {name}: {n} invalid records skipped");
        }
    }
    if let Some(path) = &a.export_radiance {
        let store = super::merge::load_store(&job, &fp, false)?;
        let recs = store.map(|s| s.records).unwrap_or_default();
        let p = &m.params;
        let line = format!(
            "tmerge -av {} {} {} -aw {} -ab {} -aa {} -ad {} -as {} -ar {}",
            p.av[0], p.av[1], p.av[2], p.aw, p.ab, p.aa, p.ad, p.as_, p.ar
        );
        super::merge::export_radiance(path, &recs, &line)?;
        eprintln!(
            "tmerge: {} values written to {} (Radiance format)",
            recs.len(),
            path.display()
        );
    }
    Ok(0)
}

/// `tassemble`: build pictures from tiles.
#[derive(Parser, Debug)]
#[command(
    name = "tassemble",
    version,
    about = "Assemble a job's frame from its tiles (.hdr, .exr or .png; stdout: Radiance)"
)]
struct TassembleArgs {
    /// The job directory.
    job: PathBuf,
    /// Frame number.
    #[arg(
        long,
        default_value_t = 0,
        conflicts_with = "all_frames",
        verbatim_doc_comment
    )]
    frame: u32,
    /// Assemble every frame; -o is then a pattern with a printf-style
    /// %d (e.g. f%04d.hdr).
    #[arg(long, verbatim_doc_comment)]
    all_frames: bool,
    /// Output picture (format from the extension); default: Radiance
    /// picture on stdout.
    #[arg(short = 'o', long = "output", verbatim_doc_comment)]
    output: Option<PathBuf>,
    /// Fill missing tiles with black (and say so) instead of failing.
    #[arg(long, verbatim_doc_comment)]
    partial: bool,
    /// Also write a contact sheet of every frame (a PNG of thumbnails,
    /// each with the temporal exposure).
    #[arg(long, value_name = "PNG", verbatim_doc_comment)]
    contact_sheet: Option<PathBuf>,
    /// Thumbnail width of the contact sheet, in pixels.
    #[arg(long, default_value_t = 160, value_name = "PX", verbatim_doc_comment)]
    thumb_width: usize,
    /// PNG frames get an exposure smoothed over the neighbouring frames
    /// (±3) instead of their own.
    #[arg(long, verbatim_doc_comment)]
    temporal_exposure: bool,
    /// Replace an existing output picture (refused otherwise).
    #[arg(long, verbatim_doc_comment)]
    force: bool,
    /// For a job made from a rif file: write the rendered picture as it
    /// is, without rad's last step (the reduction by the supersampling
    /// factor and the EXPOSURE) that is otherwise applied.
    #[arg(long, verbatim_doc_comment)]
    raw: bool,
}

/// `tassemble` of a point job: every ray's results in input order, to `-o` or standard
/// output.
fn assemble_points(
    job: &JobDir,
    m: &Manifest,
    p: &super::points::PointsPlan,
    a: &TassembleArgs,
    cmd: &str,
) -> Result<i32> {
    if a.all_frames || a.contact_sheet.is_some() || a.frame != 0 {
        bail!("a point job has no frames or pictures: tassemble JOB [-o FILE]");
    }
    if let Some(o) = &a.output {
        if o.exists() && !a.force {
            bail!(
                "{} exists: tassemble replaces it only with --force",
                o.display()
            );
        }
    }
    super::assemble::write_points(job, m, p, a.output.as_deref(), a.partial, cmd)
}

/// Entry point of `tassemble`.
pub fn tassemble_main() -> i32 {
    let a = TassembleArgs::parse();
    finish("tassemble", tassemble(a))
}

fn tassemble(a: TassembleArgs) -> Result<i32> {
    let job = JobDir::new(&a.job);
    let m = Manifest::load(&job)?;
    let cmd = command_line();
    if a.all_frames && a.output.is_none() {
        bail!("--all-frames needs -o PATTERN with a %d");
    }
    if a.temporal_exposure && !a.all_frames {
        bail!("--temporal-exposure needs --all-frames -o PATTERN.png");
    }
    if let Some(p) = &m.points {
        return assemble_points(&job, &m, p, &a, &cmd);
    }
    let every = a.all_frames || a.contact_sheet.is_some();
    let frames: Vec<u32> = if every {
        m.frames.iter().map(|f| f.index).collect()
    } else {
        vec![a.frame]
    };
    // Where each frame goes: every frame with --all-frames, else only --frame (to -o or
    // standard output, unless only a contact sheet was asked for).
    let target = |f: u32| -> Result<Option<Option<PathBuf>>> {
        Ok(match &a.output {
            Some(p) if a.all_frames => Some(Some(PathBuf::from(crate::runinfo::frame_name(
                &p.display().to_string(),
                f,
            )?))),
            Some(p) if f == a.frame => Some(Some(p.clone())),
            None if f == a.frame && a.contact_sheet.is_none() => Some(None),
            _ => None,
        })
    };
    if let Some(p) = &a.output {
        crate::image::check_output_path(p).map_err(anyhow::Error::msg)?;
    }
    // Outputs are never replaced unless asked, as tpict's.
    if !a.force {
        for f in &frames {
            if let Some(Some(p)) = target(*f)? {
                if p.exists() {
                    bail!(
                        "{} exists: tassemble replaces a picture only with --force",
                        p.display()
                    );
                }
            }
        }
    }
    let mut failed = false;
    let mut pictures = Vec::new();
    let pieces = super::assemble::job_pieces(&job)?;
    for f in frames {
        let (mut img, missing) = super::assemble::assemble_frame(&job, &m, &pieces, f, &cmd)?;
        if let (Some(fin), false) = (&m.finish, a.raw) {
            img = fin.apply(&img);
        }
        if !missing.is_empty() {
            let list = super::assemble::missing_list(&missing);
            if !a.partial {
                eprintln!(
                    "tassemble: error: frame {f}: {} of {} tiles missing or invalid: {} \
                     (run tpiece on the job to render them, or pass --partial to fill them \
                     black)",
                    missing.len(),
                    m.frame(f).map(|p| p.tiles.len()).unwrap_or(0),
                    list
                );
                failed = true;
                continue;
            }
            eprintln!(
                "tassemble: warning - frame {f}: {} tiles filled black: {}",
                missing.len(),
                list
            );
        }
        pictures.push((target(f)?, img));
    }
    if failed {
        return Ok(1);
    }
    let ks = if a.temporal_exposure {
        let imgs: Vec<_> = pictures.iter().map(|(_, i)| i.clone()).collect();
        Some(super::sheet::smoothed_exposures(
            &imgs,
            super::sheet::EXPOSURE_RADIUS,
        ))
    } else {
        None
    };
    for (i, (to, img)) in pictures.iter().enumerate() {
        let Some(path) = to else { continue };
        match (path, &ks) {
            (Some(p), Some(ks)) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) => {
                crate::image::png::write_png_with(p, img, ks[i])?
            }
            _ => crate::image::write_picture(path.as_deref(), img)?,
        }
    }
    if let Some(sheet) = &a.contact_sheet {
        let imgs: Vec<_> = pictures.into_iter().map(|(_, i)| i).collect();
        super::sheet::write_contact_sheet(sheet, &imgs, a.thumb_width)?;
    }
    Ok(0)
}

/// `tstat`: progress and metrics.
#[derive(Parser, Debug)]
#[command(
    name = "tstat",
    version,
    about = "Progress and metrics of a Tessera job"
)]
struct TstatArgs {
    /// The job directory.
    job: PathBuf,
    /// JSON output.
    #[arg(long, verbatim_doc_comment)]
    json: bool,
    /// A one-worker job of the same plan: report speed-up and
    /// efficiency against it.
    #[arg(long, value_name = "JOBDIR", verbatim_doc_comment)]
    baseline: Option<PathBuf>,
    /// Print the measured per-tile costs of a frame (JSON, for
    /// bench/tilesim).
    #[arg(long, value_name = "FRAME", verbatim_doc_comment)]
    costs: Option<u32>,
}

/// Entry point of `tstat`.
pub fn tstat_main() -> i32 {
    let a = TstatArgs::parse();
    finish("tstat", tstat(a))
}

fn tstat(a: TstatArgs) -> Result<i32> {
    let job = JobDir::new(&a.job);
    if let Some(f) = a.costs {
        println!(
            "{}",
            serde_json::to_string_pretty(&super::status::costs(&job, f)?)?
        );
        return Ok(0);
    }
    let mut st = super::status::status(&job)?;
    if let Some(b) = &a.baseline {
        st = super::status::with_baseline(st, &JobDir::new(b))?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&st)?);
    } else {
        print!("{}", super::status::render_text(&st));
    }
    // A damaged job (task entries deleted) is an error for scripts that poll tstat.
    let missing: usize = st.frames.iter().map(|f| f.missing).sum();
    if missing > 0 {
        eprintln!("tstat: the job is damaged: {missing} task entries are missing from tasks/");
        return Ok(1);
    }
    Ok(0)
}
