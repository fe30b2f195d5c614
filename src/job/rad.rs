//! `trad`: a `.rif` file rendered on this machine from start to finish, as `rad` does: a job
//! planned from the file (`tplan --rif`), local workers (`tpiece`), the ambient logs merged
//! (`tmerge`), and each view's picture assembled and finished as rad's pfilt step would
//! (`tassemble`) into rad's picture names, `<PICTURE>_<view>.hdr`.
//!
//! It runs the toolkit's own programs from the folder it lives in, so a run is exactly what
//! those commands do by hand (docs/rif.md).

use anyhow::{anyhow, bail, Context, Result};
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::{Child, Command};

/// `trad`: render a rif file end to end on this machine.
#[derive(Parser, Debug)]
#[command(
    name = "trad",
    version,
    about = "Render a rad input file (.rif) on this machine, as rad does.\n\
             It plans, runs local workers, merges, assembles and finishes (rad's pfilt\n\
             step); the pictures go to rad's names."
)]
pub struct TradArgs {
    /// The rad input file.
    rif: PathBuf,
    /// Render only this view (a view name of the file or a standard
    /// view id).
    #[arg(long, value_name = "NAME", verbatim_doc_comment)]
    view: Option<String>,
    /// A `VAR=value` assignment applied after the file (as rad's
    /// arguments).
    #[arg(long = "set", value_name = "VAR=VALUE", verbatim_doc_comment)]
    set: Vec<String>,
    /// Worker processes (each holds the scene once).
    #[arg(long, default_value_t = 1, value_name = "N", verbatim_doc_comment)]
    workers: usize,
    /// Tile loops per worker (default: the cores divided among the
    /// workers).
    #[arg(long, value_name = "T", verbatim_doc_comment)]
    threads: Option<usize>,
    /// The job directory (default: `<PICTURE>.job`, removed after a
    /// successful run unless --keep-job); it must not exist.
    #[arg(long, value_name = "DIR", verbatim_doc_comment)]
    job: Option<PathBuf>,
    /// Keep the job directory (its tiles, logs and merged ambient
    /// store).
    #[arg(long, verbatim_doc_comment)]
    keep_job: bool,
    /// Write the rendered pictures without rad's last step (reduction
    /// and exposure).
    #[arg(long, verbatim_doc_comment)]
    raw: bool,
    /// Print each command before running it.
    #[arg(long, short, verbatim_doc_comment)]
    verbose: bool,
    /// More scene files, added after the file's (as rad's octree
    /// inputs).
    #[arg(last = true, value_name = "SCENE", verbatim_doc_comment)]
    rest: Vec<String>,
}

/// A sibling program of this one.
fn program(name: &str) -> Result<PathBuf> {
    let exe = std::env::current_exe().context("cannot find this program's folder")?;
    let dir = exe
        .parent()
        .ok_or_else(|| anyhow!("cannot find this program's folder"))?;
    let p = dir.join(name);
    if !p.is_file() {
        bail!(
            "{} is missing (trad runs the toolkit's programs beside it)",
            p.display()
        );
    }
    Ok(p)
}

fn run(verbose: bool, mut c: Command, what: &str) -> Result<()> {
    if verbose {
        eprintln!("trad: {c:?}");
    }
    let st = c.status().with_context(|| format!("cannot start {what}"))?;
    if !st.success() {
        bail!("{what} failed ({st})");
    }
    Ok(())
}

fn spawn(verbose: bool, mut c: Command, what: &str) -> Result<Child> {
    if verbose {
        eprintln!("trad: {c:?}");
    }
    c.spawn().with_context(|| format!("cannot start {what}"))
}

/// Run `trad`.
pub fn trad(a: TradArgs) -> Result<i32> {
    if a.workers == 0 || a.threads == Some(0) {
        bail!("--workers and --threads must be at least 1");
    }
    // The views and picture names, as rad names them.
    let ro = crate::scene::ReadOptions::from_env();
    let plan = crate::rif::load(&a.rif, &a.set, &a.rest, &ro)?;
    let views = plan
        .select(a.view.as_deref())
        .map_err(|e| anyhow!("{}: {e}", a.rif.display()))?;
    let pictures: Vec<PathBuf> = views
        .iter()
        .map(|v| PathBuf::from(format!("{}_{}.hdr", plan.picture_root, v.name)))
        .collect();
    for p in &pictures {
        crate::image::check_output_path(p).map_err(anyhow::Error::msg)?;
    }
    let job = a
        .job
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("{}.job", plan.picture_root)));
    if job.exists() {
        bail!(
            "the job directory {} exists (remove it, or name another with --job)",
            job.display()
        );
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = a.threads.unwrap_or((cores / a.workers).max(1));
    // Plan.
    let mut c = Command::new(program("tplan")?);
    c.arg("--rif").arg(&a.rif);
    if let Some(v) = &a.view {
        c.args(["--view", v]);
    }
    for s in &a.set {
        c.args(["--set", s]);
    }
    c.args(["--workers", &(a.workers * threads).to_string()])
        .arg("-o")
        .arg(&job);
    if !a.rest.is_empty() {
        c.arg("--").args(&a.rest);
    }
    run(a.verbose, c, "tplan")?;
    // Work.
    let tpiece = program("tpiece")?;
    let mut children = Vec::new();
    for w in 0..a.workers {
        let mut c = Command::new(&tpiece);
        c.arg(&job)
            .args(["--threads", &threads.to_string(), "-q"])
            .args(["--worker-id", &format!("trad-{}-{w}", std::process::id())]);
        children.push(spawn(a.verbose, c, "tpiece")?);
    }
    let mut failed = 0;
    for mut ch in children {
        if !ch.wait().map(|s| s.success()).unwrap_or(false) {
            failed += 1;
        }
    }
    if failed > 0 {
        bail!(
            "{failed} of {} workers failed; the job is kept in {} (run tpiece on it to finish)",
            a.workers,
            job.display()
        );
    }
    // Merge (the store a later render of the same scene may reuse: tplan --ambient).
    let mut c = Command::new(program("tmerge")?);
    c.arg(&job);
    run(a.verbose, c, "tmerge")?;
    // Assemble and finish each view.
    let tassemble = program("tassemble")?;
    for (n, p) in pictures.iter().enumerate() {
        let mut c = Command::new(&tassemble);
        c.arg(&job)
            .args(["--frame", &n.to_string()])
            .arg("-o")
            .arg(p)
            .arg("--force");
        if a.raw {
            c.arg("--raw");
        }
        run(a.verbose, c, "tassemble")?;
        eprintln!("trad: view {}: {}", views[n].name, p.display());
    }
    if !a.keep_job {
        remove_job(&job)?;
    }
    Ok(0)
}

fn remove_job(job: &Path) -> Result<()> {
    std::fs::remove_dir_all(job).with_context(|| format!("cannot remove {}", job.display()))
}

/// Entry point of `trad`.
pub fn trad_main() -> i32 {
    let a = TradArgs::parse();
    match trad(a) {
        Ok(c) => c,
        Err(e) => {
            eprintln!(
                "{}",
                crate::runinfo::printable(&format!("trad: error: {e:#}"))
            );
            1
        }
    }
}
