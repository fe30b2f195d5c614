//! The `tpict` driver: rpict's command line in, Radiance pictures out.

use crate::ambient::Ambient;
use crate::image::{output, write_picture, Header, Image};
use crate::light::LightSet;
use crate::options::{defaults_text, parse_rpict_args, Command, RpictOptions};
use crate::render::{render_region, FrameSetup, RenderProgress, Tracer};
use crate::runinfo::{frame_name, process_cpu_seconds, process_origin_id, thread_count, SOFTWARE};
use crate::scene::{read_scene_files, ReadOptions, Scene};
use crate::view::{normaspect, parse_view_line, View};
use anyhow::{anyhow, bail, Context, Result};
use std::io::{BufRead, IsTerminal, Write};
use std::path::Path;
use std::sync::atomic::Ordering;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Where messages go (stderr, or the `-e` file).
pub struct Log {
    sink: Mutex<Box<dyn Write + Send>>,
    warnings: bool,
}

impl Log {
    /// Messages to stderr.
    pub fn stderr() -> Log {
        Log {
            sink: Mutex::new(Box::new(std::io::stderr())),
            warnings: true,
        }
    }

    /// Print one message line.
    pub fn say(&self, msg: &str) {
        if let Ok(mut s) = self.sink.lock() {
            let _ = writeln!(s, "{msg}");
            let _ = s.flush();
        }
    }

    /// Print a warning unless `-w-`.
    pub fn warn(&self, msg: &str) {
        if self.warnings {
            self.say(&format!("tpict: warning - {msg}"));
        }
    }
}

/// Run tpict with `args` (without the program name); returns the exit status.
pub fn run(args: &[String]) -> i32 {
    let log = Log::stderr();
    match run_inner(args, log) {
        Ok(()) => 0,
        Err((log, e)) => {
            log.say(&format!("tpict: error: {e:#}"));
            1
        }
    }
}

fn run_inner(args: &[String], mut log: Log) -> std::result::Result<(), (Log, anyhow::Error)> {
    let cmd = match parse_rpict_args(args) {
        Ok(c) => c,
        Err(e) => return Err((log, anyhow!(e))),
    };
    let opts = match cmd {
        Command::PrintDefaults(o) => {
            print!("{}", defaults_text(&o));
            return Ok(());
        }
        Command::PrintVersion => {
            println!("{SOFTWARE} (Radiance 6.0a rpict compatible)");
            return Ok(());
        }
        Command::Render(o) => *o,
    };
    log.warnings = opts.run.warnings;
    if let Some(ef) = &opts.run.error_file {
        match std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(ef)
        {
            Ok(mut f) => {
                let _ = writeln!(
                    f,
                    "*** PID {}: tpict {}",
                    std::process::id(),
                    args.join(" ")
                );
                log.sink = Mutex::new(Box::new(f));
            }
            Err(e) => {
                return Err((log, anyhow!("cannot open error file {ef}: {e}")));
            }
        }
    }
    match render_command(args, &opts, &log) {
        Ok(()) => Ok(()),
        Err(e) => Err((log, e)),
    }
}

/// Load and build the scene named by the options.
pub fn load_scene(opts: &RpictOptions, log: &Log) -> Result<(Scene, LightSet, [u8; 32])> {
    let mut ro = ReadOptions::from_env();
    ro.allow_commands |= opts.run.allow_commands;
    let files = if opts.scene_files.is_empty() {
        if opts.run.sequence_start.is_some() {
            bail!("no scene files given (with -S, views come from standard input, so the scene cannot)");
        }
        vec!["-".to_string()]
    } else {
        opts.scene_files.clone()
    };
    let prims = read_scene_files(&files, &ro)?;
    let fp = crate::ambient::fingerprint::fingerprint(&prims, &opts.params);
    let scene = Scene::build(&prims)?;
    for w in &scene.warnings {
        log.warn(w);
    }
    let lights = LightSet::collect(&scene, opts.params.dr);
    for w in &lights.warnings {
        log.warn(w);
    }
    if lights.sources.is_empty() {
        log.warn("no light sources found");
    }
    Ok((scene, lights, fp))
}

fn render_command(args: &[String], opts: &RpictOptions, log: &Log) -> Result<()> {
    if opts.picture.pm != 0.0 || opts.picture.pd != 0.0 {
        bail!("-pm (motion blur) and -pd (depth of field) are not supported yet; use -pm 0 -pd 0");
    }
    let (scene, lights, fingerprint) = load_scene(opts, log)?;
    let ambient = Ambient::new(&opts.params, scene.size, process_origin_id());
    let my_origin = ambient.as_ref().map(|a| a.cache.next_id().origin);
    let amb_file = match (&ambient, &opts.run.amb_file) {
        (Some(a), Some(_)) if !a.cached() => {
            log.warn("-aa 0 disables the cache: the ambient file is not used");
            None
        }
        (Some(a), Some(af)) => {
            load_ambient_file(a, Path::new(af), scene.origin, log)?;
            Some(af.clone())
        }
        _ => None,
    };
    let log_sink = match (&ambient, &opts.run.amb_log) {
        (Some(a), Some(_)) if !a.cached() => {
            log.warn("-aa 0 disables the cache: the ambient log is not used");
            None
        }
        (Some(a), Some(path)) => Some(open_ambient_log(
            a,
            Path::new(path),
            fingerprint,
            opts,
            scene.origin,
        )?),
        (None, Some(_)) => {
            log.warn("--amb-log has no effect without -ab > 0");
            None
        }
        _ => None,
    };
    let ctx = RenderCtx {
        scene: &scene,
        lights: &lights,
        ambient: ambient.as_ref(),
    };
    let threads = thread_count(opts.run.threads);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start render threads")?;
    let command_line = format!("tpict {}", args.join(" "));
    let stats = Mutex::new(RunStats {
        software: SOFTWARE.to_string(),
        threads,
        ..RunStats::default()
    });
    let started = Instant::now();
    let result = render_frames(opts, &ctx, &pool, &command_line, log, &stats);
    if let Some(sink) = &log_sink {
        sink.finish()?;
    }
    if let (Some(a), Some(af), Some(me)) = (&ambient, &amb_file, my_origin) {
        save_ambient_file(a, Path::new(af), scene.origin, me, &opts.params)?;
    }
    if let Some(path) = &opts.run.stats_file {
        let mut st = stats.into_inner().unwrap_or_default();
        st.wall_seconds = started.elapsed().as_secs_f64();
        st.cpu_seconds = process_cpu_seconds();
        if let Some(a) = &ambient {
            st.ambient = Some(AmbientReport::from_stats(a));
        }
        st.rays_per_second = if st.wall_seconds > 0.0 {
            st.total_rays as f64 / st.wall_seconds
        } else {
            0.0
        };
        let text = serde_json::to_string_pretty(&st).context("encoding statistics")?;
        output::write_atomic(Path::new(path), |f| f.write_all(text.as_bytes()))
            .with_context(|| format!("cannot write statistics file {path}"))?;
    }
    result
}

/// Appends this process's new ambient values to a Tessera ambient log, one write per
/// `--amb-flush` values.
pub struct LogSink {
    writer: Mutex<crate::ambient::log::LogWriter>,
    every: usize,
    origin: glam::DVec3,
    error: Mutex<Option<String>>,
}

impl LogSink {
    /// Flush what is pending and report the first error met while rendering.
    pub fn finish(&self) -> Result<()> {
        if let Ok(mut w) = self.writer.lock() {
            w.flush().map_err(|e| anyhow!("ambient log: {e}"))?;
        }
        match self.error.lock().ok().and_then(|mut e| e.take()) {
            Some(e) => Err(anyhow!("ambient log: {e}")),
            None => Ok(()),
        }
    }
}

impl crate::ambient::cache::ValueSink for std::sync::Arc<LogSink> {
    fn accept(&self, v: &crate::ambient::cache::CachedValue) {
        if let Ok(mut w) = self.writer.lock() {
            w.push(&v.to_record(self.origin));
            if w.pending() >= self.every {
                if let Err(e) = w.flush() {
                    if let Ok(mut slot) = self.error.lock() {
                        slot.get_or_insert(e.to_string());
                    }
                }
            }
        }
    }
}

/// Open (or create) a Tessera ambient log: refuse it when its fingerprint does not match
/// the scene and ambient options (unless `--amb-force`), load its values into the cache and
/// append this process's new values to it.
pub fn open_ambient_log(
    a: &Ambient,
    path: &Path,
    fingerprint: [u8; 32],
    opts: &RpictOptions,
    origin: glam::DVec3,
) -> Result<std::sync::Arc<LogSink>> {
    use crate::ambient::log::{LogHeader, LogReader, LogWriter};
    let header = LogHeader::new(
        fingerprint,
        &crate::ambient::fingerprint::options_text(&opts.params),
    );
    if path.exists() {
        let mut r = LogReader::open(path, Some(&fingerprint), opts.run.amb_force)?;
        for rec in r.read_available()? {
            a.cache
                .insert(crate::ambient::cache::CachedValue::from_record(
                    &rec, origin,
                ));
        }
    }
    let writer = LogWriter::open(path, &header, opts.run.amb_force)?;
    let sink = std::sync::Arc::new(LogSink {
        writer: Mutex::new(writer),
        every: opts.run.amb_flush.max(1),
        origin,
        error: Mutex::new(None),
    });
    a.cache.set_sink(Box::new(sink.clone()));
    Ok(sink)
}

/// Load the values of a Radiance ambient file (`-af`) into the cache, if the file exists.
pub fn load_ambient_file(a: &Ambient, path: &Path, origin: glam::DVec3, log: &Log) -> Result<()> {
    if !path.exists() {
        return Ok(());
    }
    let (_, records, report) = crate::ambient::radfile::read_file(path)
        .with_context(|| format!("cannot read ambient file {}", path.display()))?;
    for r in &records {
        a.cache
            .insert(crate::ambient::cache::CachedValue::from_record(r, origin));
    }
    if report.invalid > 0 || report.trailing_bytes > 0 {
        log.warn(&format!(
            "ambient file {}: ignored {} invalid records and {} trailing bytes",
            path.display(),
            report.invalid,
            report.trailing_bytes
        ));
    }
    Ok(())
}

/// Append this process's new values to a Radiance ambient file (`-af`), creating it with a
/// header when it does not exist. The new values go out in one write.
pub fn save_ambient_file(
    a: &Ambient,
    path: &Path,
    origin: glam::DVec3,
    my_origin: u64,
    params: &crate::options::RenderParams,
) -> Result<()> {
    use crate::ambient::radfile;
    let mine: Vec<_> = a
        .cache
        .all()
        .into_iter()
        .filter(|v| v.id.origin == my_origin)
        .map(|v| v.to_record(origin))
        .collect();
    let mut bytes = Vec::with_capacity(mine.len() * radfile::RECORD_SIZE);
    for r in &mine {
        radfile::write_record(&mut bytes, r)?;
    }
    if path.exists() {
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .with_context(|| format!("cannot append to ambient file {}", path.display()))?;
        f.write_all(&bytes)
            .with_context(|| format!("cannot append to ambient file {}", path.display()))?;
    } else {
        let line = format!(
            "tpict -av {} {} {} -aw {} -ab {} -aa {} -ad {} -as {} -ar {}",
            params.av[0],
            params.av[1],
            params.av[2],
            params.aw,
            params.ab,
            params.aa,
            params.ad,
            params.as_,
            params.ar
        );
        let mut out = Vec::new();
        radfile::write_header(&mut out, &line, SOFTWARE)?;
        out.extend_from_slice(&bytes);
        output::write_atomic(path, |f| f.write_all(&out))
            .with_context(|| format!("cannot write ambient file {}", path.display()))?;
    }
    Ok(())
}

/// What every frame of a run shares: the scene, its lights and the irradiance cache.
pub struct RenderCtx<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its light sources.
    pub lights: &'a LightSet,
    /// The irradiance cache (`-ab` > 0), kept across frames.
    pub ambient: Option<&'a Ambient>,
}

/// Ambient counters in `--stats` output.
#[derive(Debug, Default, serde::Serialize)]
pub struct AmbientReport {
    /// Tessera's settings of the calculation, as options
    /// ([`crate::ambient::settings::AmbientSettings::to_text`]).
    pub settings: String,
    /// Cache lookups.
    pub lookups: u64,
    /// Lookups answered by interpolation.
    pub hits: u64,
    /// New values by ambient level.
    pub new_values_by_level: Vec<u64>,
    /// Values in the cache at the end.
    pub cached_values: u64,
    /// Hemisphere sample rays.
    pub sample_rays: u64,
    /// Seconds spent computing new values (the seed paper's T_amb, summed over threads).
    pub ambient_seconds: f64,
    /// New values with light-leak (corral) flags.
    pub corral_values: u64,
    /// Light-leak test rays traced at lookups.
    pub leak_tests: u64,
    /// Cached values rejected because a wall blocked the leak test.
    pub leak_rejects: u64,
    /// Shadow rays at sample hits answered from their footprint's cube, not traced.
    pub shadows_reused: u64,
}

impl AmbientReport {
    fn from_stats(a: &Ambient) -> AmbientReport {
        let (s, cached) = (&a.stats, a.cache.len());
        let mut levels: Vec<u64> = s
            .new_values
            .iter()
            .map(|v| v.load(Ordering::Relaxed))
            .collect();
        while levels.last() == Some(&0) {
            levels.pop();
        }
        AmbientReport {
            settings: a.settings().to_text(),
            lookups: s.lookups.load(Ordering::Relaxed),
            hits: s.hits.load(Ordering::Relaxed),
            new_values_by_level: levels,
            cached_values: cached,
            sample_rays: s.sample_rays.load(Ordering::Relaxed),
            ambient_seconds: s.amb_nanos.load(Ordering::Relaxed) as f64 * 1e-9,
            corral_values: s.corral_values.load(Ordering::Relaxed),
            leak_tests: s.leak_tests.load(Ordering::Relaxed),
            leak_rejects: s.leak_rejects.load(Ordering::Relaxed),
            shadows_reused: s.shadows_reused.load(Ordering::Relaxed),
        }
    }
}

/// Statistics written by `--stats FILE` (JSON).
#[derive(Debug, Default, serde::Serialize)]
pub struct RunStats {
    /// Producing software.
    pub software: String,
    /// Render threads.
    pub threads: usize,
    /// One entry per rendered frame.
    pub frames: Vec<FrameStats>,
    /// Rays traced in all frames (primary, reflected, transmitted and shadow rays).
    pub total_rays: u64,
    /// Wall-clock time of the whole run after the scene was loaded.
    pub wall_seconds: f64,
    /// CPU time (user + system) of the process, when the platform reports it.
    pub cpu_seconds: Option<f64>,
    /// `total_rays / wall_seconds`.
    pub rays_per_second: f64,
    /// Irradiance-cache counters (with `-ab` > 0).
    pub ambient: Option<AmbientReport>,
}

/// Statistics of one frame.
#[derive(Debug, Default, serde::Serialize)]
pub struct FrameStats {
    /// Frame number (0 without -S).
    pub frame: u32,
    /// Picture width.
    pub width: usize,
    /// Picture height.
    pub height: usize,
    /// Rays traced.
    pub rays: u64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

#[allow(clippy::too_many_arguments)]
fn render_frames(
    opts: &RpictOptions,
    ctx: &RenderCtx,
    pool: &rayon::ThreadPool,
    command_line: &str,
    log: &Log,
    stats: &Mutex<RunStats>,
) -> Result<()> {
    let command_line = command_line.to_string();
    match opts.run.sequence_start {
        None => {
            if let Some(o) = &opts.run.output {
                if Path::new(o).exists() {
                    bail!("cannot open output file \"{o}\": File exists");
                }
            }
            let mut img =
                pool.install(|| render_view(ctx, opts, &opts.picture.view, 0, log, stats))?;
            img.header.commands.push(command_line);
            match &opts.run.output {
                Some(o) => {
                    let path = Path::new(o);
                    write_new_picture(path, &img)?;
                }
                None => write_picture(None, &img)?,
            }
        }
        Some(start) => {
            let stdin = std::io::stdin();
            let mut frame = start;
            let mut base = opts.picture.view.clone();
            for line in stdin.lock().lines() {
                let line = line.context("reading views from standard input")?;
                let Some(view) = parse_view_line(&line, &base)? else {
                    continue;
                };
                base = view.clone();
                let n = frame;
                frame += 1;
                if opts.run.report_interval > 0.0 {
                    log.say(&format!("FRAME {n}: {}", view.to_radiance_string()));
                }
                match &opts.run.output {
                    Some(pattern) => {
                        let name = frame_name(pattern, n)?;
                        let path = Path::new(&name);
                        // Claim the frame as rpict does: create its file with O_EXCL; a frame
                        // whose file exists belongs to another process (or is done).
                        match std::fs::OpenOptions::new()
                            .write(true)
                            .create_new(true)
                            .open(path)
                        {
                            Ok(_) => {}
                            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                            Err(e) => bail!("cannot create output file \"{name}\": {e}"),
                        }
                        let rendered =
                            pool.install(|| render_view(ctx, opts, &view, n, log, stats));
                        let mut img = match rendered {
                            Ok(img) => img,
                            Err(e) => {
                                let _ = std::fs::remove_file(path);
                                return Err(e);
                            }
                        };
                        img.header.commands.push(command_line.clone());
                        img.header.frame = Some(n);
                        // Replace the claimed (empty) file atomically with the picture.
                        if let Err(e) = write_picture(Some(path), &img) {
                            let _ = std::fs::remove_file(path);
                            return Err(anyhow!(e));
                        }
                    }
                    None => {
                        let mut img =
                            pool.install(|| render_view(ctx, opts, &view, n, log, stats))?;
                        img.header.commands.push(command_line.clone());
                        img.header.frame = Some(n);
                        write_picture(None, &img)?;
                    }
                }
            }
            if frame == start {
                // As rpict: standard input held no view line (`VIEW=`, `rview ...`).
                log.warn("no output produced");
            }
        }
    }
    Ok(())
}

/// Write a picture to a path that must not exist yet (never clobbers).
fn write_new_picture(path: &Path, img: &Image) -> Result<()> {
    use crate::image::PictureFormat;
    match PictureFormat::from_path(path) {
        PictureFormat::Hdr => output::write_atomic_noclobber(path, |f| {
            let mut w = std::io::BufWriter::new(f);
            crate::image::hdr::write_hdr(&mut w, img)?;
            w.flush()
        })
        .with_context(|| format!("cannot write {}", path.display())),
        _ => {
            if path.exists() {
                bail!(
                    "cannot open output file \"{}\": File exists",
                    path.display()
                );
            }
            write_picture(Some(path), img).map_err(|e| anyhow!(e))
        }
    }
}

/// Render one view at the options' resolution into a picture with its header.
pub fn render_view(
    ctx: &RenderCtx,
    opts: &RpictOptions,
    view: &View,
    frame: u32,
    log: &Log,
    stats: &Mutex<RunStats>,
) -> Result<Image> {
    let vf = view.frame().map_err(|e| anyhow!("bad view: {e}"))?;
    let mut pa = opts.picture.pa;
    let (mut x, mut y) = (opts.picture.x, opts.picture.y);
    normaspect(vf.aspect(), &mut pa, &mut x, &mut y);
    if x == 0 || y == 0 {
        bail!("resolution {x}x{y} is empty");
    }
    let tracer = Tracer::new(ctx.scene, &opts.params, ctx.lights).with_ambient(ctx.ambient);
    let fs = FrameSetup {
        view: &vf,
        xres: x,
        yres: y,
        pj: opts.picture.pj,
        ps: opts.picture.ps,
        pt: opts.picture.pt,
        frame,
        irradiance: opts.params.i,
        overture: opts.picture.overture_step(&opts.params),
    };
    let progress = RenderProgress::default();
    let start = Instant::now();
    let bar = if std::io::stderr().is_terminal() && opts.run.report_interval <= 0.0 {
        let b = indicatif::ProgressBar::new(100);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {percent:>3}% {elapsed} ETA {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    };
    let done = std::sync::atomic::AtomicBool::new(false);
    let pixels = std::thread::scope(|s| {
        let reporter = s.spawn(|| {
            let mut last = Instant::now();
            while !done.load(Ordering::Relaxed) {
                // Parked rather than slept, so that the render's end (which unparks this
                // thread) is not delayed by up to 100 ms waiting for the join below.
                std::thread::park_timeout(Duration::from_millis(100));
                if done.load(Ordering::Relaxed) {
                    break;
                }
                let total = progress.rows_total.load(Ordering::Relaxed).max(1);
                let pct = 100.0 * progress.rows_done.load(Ordering::Relaxed) as f64 / total as f64;
                if let Some(b) = &bar {
                    b.set_position(pct as u64);
                }
                if opts.run.report_interval > 0.0
                    && last.elapsed().as_secs_f64() >= opts.run.report_interval
                {
                    last = Instant::now();
                    log.say(&report_line(&progress, pct, start, ctx.ambient));
                }
            }
        });
        let px = render_region(&tracer, &fs, 0, 0, x, y, &progress);
        done.store(true, Ordering::Relaxed);
        reporter.thread().unpark();
        let _ = reporter.join();
        px
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if opts.run.report_interval > 0.0 {
        log.say(&report_line(&progress, 100.0, start, ctx.ambient));
    }
    if let Ok(mut st) = stats.lock() {
        let rays = progress.rays.load(Ordering::Relaxed);
        st.total_rays += rays;
        st.frames.push(FrameStats {
            frame,
            width: x,
            height: y,
            rays,
            wall_seconds: start.elapsed().as_secs_f64(),
        });
    }
    let mut img = Image::new(x, y);
    img.pixels = pixels;
    img.header = Header {
        software: Some(SOFTWARE.to_string()),
        view: Some(view.to_radiance_string()),
        pixaspect: if (0.995..=1.005).contains(&pa) {
            None
        } else {
            Some(pa)
        },
        exposure: 1.0,
        format: "32-bit_rle_rgbe".to_string(),
        extra: ambient_header(ctx.ambient),
        ..Header::default()
    };
    Ok(img)
}

/// The picture header's record of Tessera's ambient settings (`TESSERA_AMBIENT=` with every
/// setting as an option), when the ambient calculation runs.
pub fn ambient_header(ambient: Option<&Ambient>) -> Vec<(String, String)> {
    ambient
        .map(|a| {
            vec![(
                AMBIENT_HEADER_VAR.to_string(),
                format!(" {}", a.settings().to_text()),
            )]
        })
        .unwrap_or_default()
}

/// The header variable of [`ambient_header`].
pub const AMBIENT_HEADER_VAR: &str = "TESSERA_AMBIENT";

fn report_line(p: &RenderProgress, pct: f64, start: Instant, amb: Option<&Ambient>) -> String {
    let hours = start.elapsed().as_secs_f64() / 3600.0;
    let mut line = format!(
        "tpict: {} rays, {:.2}% after {:.3}r hours (PID {})",
        p.rays.load(Ordering::Relaxed),
        pct,
        hours,
        std::process::id()
    );
    if let Some(a) = amb {
        let s = &a.stats;
        let made = s.made();
        line.push_str(&format!(
            "; ambient: {} lookups, {} interpolated, {} new values, {:.1}s making them",
            s.lookups.load(Ordering::Relaxed),
            s.hits.load(Ordering::Relaxed),
            made,
            s.amb_nanos.load(Ordering::Relaxed) as f64 * 1e-9
        ));
    }
    line
}
