//! The `tpict` driver: rpict's command line in, Radiance pictures out.

use crate::ambient::Ambient;
use crate::image::{output, write_picture, Header, Image};
use crate::options::{defaults_text, parse_rpict_args, Command, RpictOptions, RunParams};
use crate::render::RenderProgress;
use crate::runinfo::{frame_name, process_cpu_seconds, SOFTWARE};
use crate::scene::ReadOptions;
use crate::session::{Region, SceneSource, Session};
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
            log.say(&crate::runinfo::printable(&format!("tpict: error: {e:#}")));
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
        Command::PrintHelp => {
            print!("{}", crate::options::rpict::help_text());
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

/// Read the scene named by the options and start the render session, its warnings logged.
pub fn start_session(opts: &RpictOptions, log: &Log) -> Result<Session> {
    let mut ro = ReadOptions::from_env();
    ro.allow_commands |= opts.run.allow_commands;
    ro.obj_material.clone_from(&opts.run.obj_material);
    if let Some(n) = opts.run.max_primitives {
        ro.max_primitives = n;
    }
    let files = if opts.scene_files.is_empty() {
        if opts.run.sequence_start.is_some() {
            bail!("no scene files given (with -S, views come from standard input, so the scene cannot)");
        }
        vec!["-".to_string()]
    } else {
        opts.scene_files.clone()
    };
    let source = SceneSource::read(&files, &ro, &opts.params)?;
    let session = Session::start(opts.params.clone(), source, opts.run.threads)?;
    for w in &session.warnings {
        log.warn(w);
    }
    Ok(session)
}

/// Attach the ambient stores the run options ask for (`-af`, `--amb-log`); returns the
/// ambient file to append to at the end.
fn open_stores(session: &mut Session, run: &RunParams, log: &Log) -> Result<Option<String>> {
    let uncached = session.ambient.is_some() && session.cached_ambient().is_none();
    let amb_file = match &run.amb_file {
        Some(_) if uncached => {
            log.warn("-aa 0 disables the cache: the ambient file is not used");
            None
        }
        Some(af) if session.ambient.is_some() => {
            if let Some(w) = session.load_ambient_file(Path::new(af))? {
                log.warn(&w);
            }
            Some(af.clone())
        }
        _ => None,
    };
    match &run.amb_log {
        Some(_) if uncached => log.warn("-aa 0 disables the cache: the ambient log is not used"),
        Some(path) if session.ambient.is_some() => {
            if let Some(w) = session.open_log(Path::new(path), run.amb_force, run.amb_flush)? {
                log.warn(&w);
            }
        }
        Some(_) => log.warn("--amb-log has no effect without -ab > 0"),
        None => {}
    }
    Ok(amb_file)
}

fn render_command(args: &[String], opts: &RpictOptions, log: &Log) -> Result<()> {
    if opts.picture.pm != 0.0 || opts.picture.pd != 0.0 {
        bail!("-pm (motion blur) and -pd (depth of field) are not supported yet; use -pm 0 -pd 0");
    }
    if let Some(why) = opts.params.refused() {
        bail!("{why}");
    }
    if opts.params.axt.is_some() && opts.params.ax.is_some() {
        bail!("-axt and -ax/-axg both choose -aa per frame: give one of them");
    }
    if opts.params.axm.is_some() {
        bail!(
            "-axm needs the views of the frames ahead, which a view sequence on standard input \
             does not give: plan a batch job (tplan --frames/--path) instead"
        );
    }
    let mut session = start_session(opts, log)?;
    let amb_file = open_stores(&mut session, &opts.run, log)?;
    let run = Run {
        opts,
        session: &session,
        command_line: format!("tpict {}", args.join(" ")),
        log,
        budget_aa: Mutex::new(opts.params.axt.map(|b| b.start)),
        stats: Mutex::new(RunStats {
            software: SOFTWARE.to_string(),
            threads: session.threads,
            ..RunStats::default()
        }),
    };
    let started = Instant::now();
    let result = match opts.run.sequence_start {
        None => run.render_single(),
        Some(start) => run.render_sequence(start),
    };
    session.finish()?;
    if let Some(af) = &amb_file {
        session.save_ambient_file(Path::new(af))?;
    }
    if let Some(path) = &opts.run.stats_file {
        let mut st = run.stats.into_inner().unwrap_or_default();
        st.wall_seconds = started.elapsed().as_secs_f64();
        st.cpu_seconds = process_cpu_seconds();
        if let Some(a) = &session.ambient {
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

/// What every frame of a run shares: the options, the session, the log and the statistics.
struct Run<'a> {
    opts: &'a RpictOptions,
    session: &'a Session,
    command_line: String,
    log: &'a Log,
    stats: Mutex<RunStats>,
    /// `-axt`: the accuracy of the next frame.
    budget_aa: Mutex<Option<f64>>,
}

impl Run<'_> {
    /// One picture of the options' view, to `-o` (never clobbered) or standard output.
    /// A Radiance picture is written as its rows are finished (to a temporary file beside
    /// `-o`, or one that is copied to standard output at the end), so that a one-thread
    /// render never holds the whole frame; nothing is written when the render fails.
    fn render_single(&self) -> Result<()> {
        use crate::image::PictureFormat;
        let out = self.opts.run.output.as_deref();
        if let Some(o) = out {
            if Path::new(o).exists() {
                bail!("cannot open output file \"{o}\": File exists");
            }
            crate::image::check_output_path(Path::new(o)).map_err(anyhow::Error::msg)?;
        }
        let view = &self.opts.picture.view;
        match out {
            Some(o) if PictureFormat::from_path(Path::new(o)) == PictureFormat::Hdr => {
                let path = Path::new(o);
                let mut failed = None;
                let written = output::write_atomic_noclobber(path, |f| {
                    let mut stream = Stream::new(std::io::BufWriter::new(f));
                    match self.render_view(view, None, &mut stream) {
                        Ok(()) => stream.finish()?.flush(),
                        Err(e) => {
                            failed = Some(e);
                            Err(std::io::Error::other("render failed"))
                        }
                    }
                });
                if let Some(e) = failed {
                    return Err(e);
                }
                written.with_context(|| format!("cannot write {}", path.display()))
            }
            Some(o) => {
                let img = self.render_image(view, None)?;
                write_new_picture(Path::new(o), &img)
            }
            None => {
                // Spooled, so that a render that fails writes nothing.
                let Ok(mut spool) = tempfile::tempfile() else {
                    let img = self.render_image(view, None)?;
                    return Ok(write_picture(None, &img)?);
                };
                let mut stream = Stream::new(std::io::BufWriter::new(&mut spool));
                self.render_view(view, None, &mut stream)?;
                stream
                    .finish()
                    .and_then(|mut w| w.flush())
                    .context("cannot write the picture to a temporary file")?;
                use std::io::Seek;
                spool
                    .rewind()
                    .context("cannot read the picture's temporary file")?;
                let stdout = std::io::stdout();
                let mut lock = stdout.lock();
                std::io::copy(&mut spool, &mut lock)
                    .and_then(|_| lock.flush())
                    .context("cannot write the picture to standard output")?;
                Ok(())
            }
        }
    }

    /// `-S`: one picture per view line of standard input, frames numbered from `start`.
    fn render_sequence(&self, start: u32) -> Result<()> {
        let stdin = std::io::stdin();
        let mut frame = start;
        let mut base = self.opts.picture.view.clone();
        for line in stdin.lock().lines() {
            let line = line.context("reading views from standard input")?;
            let Some(view) = parse_view_line(&line, &base)? else {
                continue;
            };
            base = view.clone();
            let n = frame;
            frame += 1;
            if self.opts.run.report_interval > 0.0 {
                self.log
                    .say(&format!("FRAME {n}: {}", view.to_radiance_string()));
            }
            match &self.opts.run.output {
                Some(pattern) => self.render_frame_file(&view, n, &frame_name(pattern, n)?)?,
                None => {
                    let img = self.render_frame(&view, n)?;
                    write_picture(None, &img)?;
                }
            }
        }
        if frame == start {
            // As rpict: standard input held no view line (`VIEW=`, `rview ...`).
            self.log.warn("no output produced");
        }
        Ok(())
    }

    /// One frame of a sequence with its header.
    fn render_frame(&self, view: &View, n: u32) -> Result<Image> {
        self.render_image(view, Some(n))
    }

    /// One picture of `view` in memory; `frame`: its number in a sequence (`FRAME=`).
    fn render_image(&self, view: &View, frame: Option<u32>) -> Result<Image> {
        let mut collect = Collect(None);
        self.render_view(view, frame, &mut collect)?;
        collect
            .0
            .ok_or_else(|| anyhow!("the render produced no picture"))
    }

    /// One frame of a sequence to its own file, claimed first as rpict does: a frame whose
    /// file exists belongs to another process (or is done) and is skipped.
    fn render_frame_file(&self, view: &View, n: u32, name: &str) -> Result<()> {
        let path = Path::new(name);
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
        {
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => return Ok(()),
            Err(e) => bail!("cannot create output file \"{name}\": {e}"),
        }
        let img = match self.render_frame(view, n) {
            Ok(img) => img,
            Err(e) => {
                let _ = std::fs::remove_file(path);
                return Err(e);
            }
        };
        // Replace the claimed (empty) file atomically with the picture.
        if let Err(e) = write_picture(Some(path), &img) {
            let _ = std::fs::remove_file(path);
            return Err(anyhow!(e));
        }
        Ok(())
    }

    /// Render one view at the options' resolution into `out`: its header, then its rows
    /// as they are finished. `frame`: the frame's number in a sequence (`FRAME=`; None: a
    /// single picture, seeded as frame 0).
    fn render_view(
        &self,
        view: &View,
        numbered: Option<u32>,
        out: &mut (dyn FrameOut + Send),
    ) -> Result<()> {
        let frame = numbered.unwrap_or(0);
        let (opts, session) = (self.opts, self.session);
        let vf = view.frame().map_err(|e| anyhow!("bad view: {e}"))?;
        let mut pa = opts.picture.pa;
        let (mut x, mut y) = (opts.picture.x, opts.picture.y);
        normaspect(vf.aspect(), &mut pa, &mut x, &mut y);
        if x == 0 || y == 0 {
            bail!("resolution {x}x{y} is empty");
        }
        crate::runinfo::check_picture_memory(x, y, crate::runinfo::available_memory())
            .map_err(|e| anyhow!(e))?;
        let mut fs = opts
            .picture
            .frame_setup(&session.params, &vf, (x, y), frame);
        // -S numbers frames from its start (default 1): the position in the animation.
        let first = opts.run.sequence_start.unwrap_or(frame);
        fs.aa = session.params.frame_accuracy(frame.saturating_sub(first));
        let budget = session.params.axt;
        if budget.is_some() {
            fs.aa = *self.budget_aa.lock().unwrap_or_else(|e| e.into_inner());
        }
        let mut header = Header {
            software: Some(SOFTWARE.to_string()),
            view: Some(view.to_radiance_string()),
            pixaspect: if (0.995..=1.005).contains(&pa) {
                None
            } else {
                Some(pa)
            },
            exposure: 1.0,
            format: "32-bit_rle_rgbe".to_string(),
            extra: session.ambient_header(),
            commands: vec![self.command_line.clone()],
            frame: numbered,
            ..Header::default()
        };
        if let (Some(aa), true) = (fs.aa, session.cached_ambient().is_some()) {
            // The frame's own -aa when it varies (-ax, -axg, -axt).
            header
                .extra
                .push(("TESSERA_FRAME_AA".to_string(), format!(" {aa}")));
        }
        out.begin(header, x, y)?;
        let cpu0 = crate::runinfo::process_cpu_seconds();
        let progress = RenderProgress::default();
        let start = Instant::now();
        let region = Region {
            x0: 0,
            y0: 0,
            x1: x,
            y1: y,
        };
        self.with_reports(&progress, start, || {
            session.render_rows(&fs, region, &progress, &mut |rows| out.rows(rows))
        })?;
        out.done()?;
        if let (Some(b), Some(aa), Some(c0), Some(c1)) =
            (budget, fs.aa, cpu0, crate::runinfo::process_cpu_seconds())
        {
            let next = b.next(aa, c1 - c0);
            *self.budget_aa.lock().unwrap_or_else(|e| e.into_inner()) = Some(next);
            if self.opts.run.report_interval > 0.0 {
                self.log.say(&format!(
                    "frame {frame}: -aa {aa:.4} took {:.2} CPU s; next -aa {next:.4}",
                    c1 - c0
                ));
            }
        }
        if let Ok(mut st) = self.stats.lock() {
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
        Ok(())
    }

    /// Run `render` while a progress bar (on a terminal) or `-t` reports show its progress.
    fn with_reports<T>(
        &self,
        progress: &RenderProgress,
        start: Instant,
        render: impl FnOnce() -> T,
    ) -> T {
        let interval = self.opts.run.report_interval;
        let ambient = self.session.ambient.as_deref();
        let bar = if std::io::stderr().is_terminal() && interval <= 0.0 {
            let b = indicatif::ProgressBar::new(100);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:40} {percent:>3}% {elapsed} ETA {eta}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            Some(b)
        } else {
            None
        };
        let done = std::sync::atomic::AtomicBool::new(false);
        let out = std::thread::scope(|s| {
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
                    let pct =
                        100.0 * progress.rows_done.load(Ordering::Relaxed) as f64 / total as f64;
                    if let Some(b) = &bar {
                        b.set_position(pct as u64);
                    }
                    if interval > 0.0 && last.elapsed().as_secs_f64() >= interval {
                        last = Instant::now();
                        self.log.say(&report_line(progress, pct, start, ambient));
                    }
                }
            });
            let out = render();
            done.store(true, Ordering::Relaxed);
            reporter.thread().unpark();
            let _ = reporter.join();
            out
        });
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        if interval > 0.0 {
            self.log.say(&report_line(progress, 100.0, start, ambient));
        }
        out
    }
}

/// Where a frame's pixels go ([`Run::render_view`]): its header and size first, then its
/// rows top first as the render finishes them.
trait FrameOut {
    /// The frame's header and size, before any row.
    fn begin(&mut self, header: Header, width: usize, height: usize) -> Result<()>;
    /// Finished rows (whole rows, top first).
    fn rows(&mut self, rows: Vec<[f32; 3]>);
    /// The render is over: the first error met while taking its rows, if any.
    fn done(&mut self) -> Result<()>;
}

/// The frame as a picture in memory.
struct Collect(Option<Image>);

impl FrameOut for Collect {
    fn begin(&mut self, header: Header, width: usize, height: usize) -> Result<()> {
        self.0 = Some(Image {
            width,
            height,
            pixels: Vec::new(),
            header,
        });
        Ok(())
    }

    fn rows(&mut self, rows: Vec<[f32; 3]>) {
        if let Some(img) = &mut self.0 {
            crate::render::picture::append_rows(&mut img.pixels, rows);
        }
    }

    fn done(&mut self) -> Result<()> {
        Ok(())
    }
}

/// The frame written as a Radiance picture as its rows come.
struct Stream<W: Write> {
    w: Option<W>,
    rows: Option<crate::image::hdr::HdrRows<W>>,
    err: Option<std::io::Error>,
}

impl<W: Write> Stream<W> {
    fn new(w: W) -> Self {
        Stream {
            w: Some(w),
            rows: None,
            err: None,
        }
    }

    /// The writer, once the whole picture went through it.
    fn finish(self) -> std::io::Result<W> {
        if let Some(e) = self.err {
            return Err(e);
        }
        match self.rows {
            Some(r) => r.finish(),
            None => Err(std::io::Error::other("no picture was rendered")),
        }
    }
}

impl<W: Write> FrameOut for Stream<W> {
    fn begin(&mut self, header: Header, width: usize, height: usize) -> Result<()> {
        let w = self
            .w
            .take()
            .ok_or_else(|| anyhow!("a second picture into one output"))?;
        self.rows = Some(crate::image::hdr::HdrRows::new(w, &header, width, height)?);
        Ok(())
    }

    fn rows(&mut self, rows: Vec<[f32; 3]>) {
        if self.err.is_some() {
            return;
        }
        if let Some(r) = &mut self.rows {
            if let Err(e) = r.rows(&rows) {
                self.err = Some(e);
            }
        }
    }

    fn done(&mut self) -> Result<()> {
        match self.err.take() {
            Some(e) => Err(anyhow!("cannot write the picture: {e}")),
            None => Ok(()),
        }
    }
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
    /// Values the cache refused (non-finite or absurd values from a damaged store; records
    /// that fail validation when read are counted in the warnings).
    pub refused_values: u64,
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
            refused_values: a.cache.refused(),
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
