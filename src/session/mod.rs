//! One render session, the same for `tpict` and `tpiece`: the scene (read, fingerprinted,
//! built), its lights, the render threads, the ambient calculation with this process's
//! origin id, and the ambient stores its values go to (a Radiance ambient file `-af`, an
//! ambient log under one flush policy: [`store`]). The front ends only decide what to render
//! (whole views, or a job's tiles) and where the pixels go.
//!
//! ```text
//! SceneSource::read(files, params)   primitives + ambient fingerprint
//!   -> Session::start(params, source, threads)   scene, lights, pool, Ambient
//!   -> open_log / attach_store / load_ambient_file   (optional ambient stores)
//!   -> render(frame setup, region)      pixels, on the session's threads
//!   -> finish / save_ambient_file      flush the stores
//! ```

mod lookahead;
pub mod store;

use crate::ambient::cache::CachedValue;
use crate::ambient::log::{LogHeader, LogReader, LogWriter};
use crate::ambient::Ambient;
use crate::light::LightSet;
use crate::options::RenderParams;
use crate::render::splitting::{render_region_split, Cut, SplitPoint};
use crate::render::world::Scene;
use crate::render::{render_region, render_region_rows, FrameSetup, RenderProgress, Tracer};
use crate::runinfo::{process_origin_id, thread_count};
use crate::scene::{read_scene_files, Primitive, ReadOptions};
use anyhow::{Context, Result};
use std::path::Path;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use store::{AmbientStore, FlushPolicy};

/// The header variable recording Tessera's ambient settings in pictures.
pub const AMBIENT_HEADER_VAR: &str = "TESSERA_AMBIENT";

/// A scene as read: its primitives and the fingerprint of them with the ambient options.
pub struct SceneSource {
    /// The primitives, inline commands and `xform` expanded.
    pub prims: Vec<Primitive>,
    /// [`crate::ambient::fingerprint::fingerprint`] of the primitives and the parameters.
    pub fingerprint: [u8; 32],
    /// Where files named by modifiers (fonts, data files, pictures) are looked up (the
    /// RAYPATH the scene was read with).
    pub raypath: Vec<std::path::PathBuf>,
    /// Whether inline commands may run (in the scene files of instanced octrees).
    pub allow_commands: bool,
}

impl SceneSource {
    /// Read scene files (`-` is standard input) and fingerprint them with `params`.
    pub fn read(files: &[String], ro: &ReadOptions, params: &RenderParams) -> Result<SceneSource> {
        let prims = read_scene_files(files, ro)?;
        if prims.is_empty() {
            let names: Vec<&str> = files
                .iter()
                .map(|f| if f == "-" { "<stdin>" } else { f.as_str() })
                .collect();
            let names = if names.is_empty() {
                "<stdin>".to_string()
            } else {
                names.join(" ")
            };
            anyhow::bail!("{names}: the scene is empty (no primitives were read)");
        }
        let fingerprint = crate::ambient::fingerprint::fingerprint(&prims, params);
        Ok(SceneSource {
            prims,
            fingerprint,
            raypath: ro.raypath.clone(),
            allow_commands: ro.allow_commands,
        })
    }
}

/// A pixel region `[x0, x1) × [y0, y1)` of a picture (y from the top).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// Left column.
    pub x0: usize,
    /// Top row.
    pub y0: usize,
    /// Column after the right edge.
    pub x1: usize,
    /// Row after the bottom edge.
    pub y1: usize,
}

/// What rendering shares across frames and tiles (see the module docs).
pub struct Session {
    /// The rendering parameters.
    pub params: RenderParams,
    /// The scene.
    pub scene: Scene,
    /// Its light sources.
    pub lights: LightSet,
    /// The scene's and parameters' ambient fingerprint.
    pub fingerprint: [u8; 32],
    /// The ambient calculation (`-ab` > 0), kept across frames and tiles.
    pub ambient: Option<Arc<Ambient>>,
    /// Render threads.
    pub threads: usize,
    /// Warnings met while building the scene and collecting its lights.
    pub warnings: Vec<String>,
    origin_id: u64,
    pool: rayon::ThreadPool,
    store: Option<Arc<AmbientStore>>,
    /// The cells each frame samples at every pixel (small light sources), once per frame.
    cells: crate::render::lightcells::CellMemo,
}

impl Session {
    /// Build the scene and its lights, start `threads` render threads (see
    /// [`thread_count`]) and the ambient calculation.
    pub fn start(
        params: RenderParams,
        source: SceneSource,
        threads: Option<usize>,
    ) -> Result<Session> {
        // Without an image nothing is refused.
        Session::start_core(params, source, threads, None)?.map_err(|m| anyhow::anyhow!(m))
    }

    /// [`Session::start`] with the scene's top-level surfaces and BVH taken from a scene
    /// image made for it ([`crate::scene::image`]). The inner error says why the image was
    /// refused (the primitives are used up: read the scene again and start without it).
    pub fn start_with_image(
        params: RenderParams,
        source: SceneSource,
        threads: Option<usize>,
        image: &crate::scene::image::SceneImage,
    ) -> Result<std::result::Result<Session, String>> {
        Session::start_core(params, source, threads, Some(image))
    }

    fn start_core(
        params: RenderParams,
        source: SceneSource,
        threads: Option<usize>,
        image: Option<&crate::scene::image::SceneImage>,
    ) -> Result<std::result::Result<Session, String>> {
        let ro = ReadOptions {
            allow_commands: source.allow_commands,
            raypath: source.raypath.clone(),
            ..ReadOptions::default()
        };
        let scene = match image {
            None => Scene::build_taking(source.prims, &ro)?,
            Some(image) => match Scene::build_with_image(source.prims, &ro, image)? {
                Ok(scene) => scene,
                Err(why) => return Ok(Err(why)),
            },
        };
        let fingerprint =
            crate::ambient::fingerprint::with_inputs(source.fingerprint, &scene.inputs)
                .map_err(|e| anyhow::anyhow!("cannot read a scene input: {e}"))?;
        let mut warnings = scene.warnings.clone();
        let lights = LightSet::collect(&scene, params.dr);
        warnings.extend(lights.warnings.iter().cloned());
        if lights.sources.is_empty() {
            warnings.push("no light sources found".into());
        }
        let origin_id = process_origin_id();
        let ambient = Ambient::new(&params, scene.size, origin_id).map(Arc::new);
        let (threads, cut) = thread_count(threads);
        warnings.extend(cut);
        // The calling thread is one of the pool's threads, so that rendering a region runs
        // on it directly instead of waking another thread and waiting for it (a worker
        // renders thousands of tiles); a thread already in a pool gets a pool of its own.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .use_current_thread()
            .build()
            .or_else(|_| rayon::ThreadPoolBuilder::new().num_threads(threads).build())
            .context("cannot start render threads")?;
        Ok(Ok(Session {
            params,
            scene,
            lights,
            fingerprint,
            ambient,
            threads,
            warnings,
            origin_id,
            pool,
            store: None,
            cells: Default::default(),
        }))
    }

    /// The ambient calculation when it caches its values (stores apply only then).
    pub fn cached_ambient(&self) -> Option<&Arc<Ambient>> {
        self.ambient.as_ref().filter(|a| a.cached())
    }

    /// The header of ambient logs written for this session.
    pub fn log_header(&self) -> LogHeader {
        LogHeader::new(
            self.fingerprint,
            &crate::ambient::fingerprint::options_text(&self.params),
        )
    }

    /// Use a Tessera ambient log shared with other processes (`--amb-log`): refuse it when
    /// its fingerprint does not match (unless `force`), load its values, and append this
    /// session's new values to it every `flush` values. Needs a cached ambient calculation.
    /// Returns a warning when the log held invalid records (skipped).
    pub fn open_log(&mut self, path: &Path, force: bool, flush: usize) -> Result<Option<String>> {
        let Some(a) = self.cached_ambient().cloned() else {
            return Ok(None);
        };
        let mut warning = None;
        if path.exists() {
            let mut r = LogReader::open(path, Some(&self.fingerprint), force)?;
            for rec in r.read_available()? {
                a.cache
                    .insert(CachedValue::from_record(&rec, self.scene.origin));
            }
            if r.invalid() > 0 {
                warning = Some(format!(
                    "ambient log {}: {} invalid records skipped",
                    path.display(),
                    r.invalid()
                ));
            }
        }
        let writer = LogWriter::open(path, &self.log_header(), force)?;
        let origin = self.scene.origin;
        let policy = FlushPolicy::Fixed(flush);
        self.attach_store(Arc::new(AmbientStore::new(a, writer, origin, policy, None)));
        Ok(warning)
    }

    /// Send this session's new ambient values to `store` from now on.
    pub fn attach_store(&mut self, store: Arc<AmbientStore>) {
        store.install();
        self.store = Some(store);
    }

    /// The ambient store, if one is attached.
    pub fn store(&self) -> Option<&Arc<AmbientStore>> {
        self.store.as_ref()
    }

    /// Flush the ambient store and report its first write error.
    pub fn finish(&self) -> Result<()> {
        match &self.store {
            Some(s) => s.finish(),
            None => Ok(()),
        }
    }

    /// Run `f` on the session's render threads (its rayon pool).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }

    /// A tracer over the session's scene, lights and ambient calculation.
    pub fn tracer(&self) -> Tracer<'_> {
        let mut t = Tracer::new(&self.scene, &self.params, &self.lights)
            .with_ambient(self.ambient.as_deref());
        t.cells = Some(&self.cells);
        t
    }

    /// Render a region of a frame on the session's threads, its rows handed to `sink` top
    /// first as they are finished (on one thread a band at a time:
    /// [`crate::render::render_region_rows`]). Fails when a function evaluation met an
    /// error rpict treats as fatal (the render stops at the next row); the rows already
    /// handed over are then not the whole region.
    pub fn render_rows(
        &self,
        fs: &FrameSetup,
        r: Region,
        progress: &RenderProgress,
        sink: &mut (dyn FnMut(Vec<[f32; 3]>) + Send),
    ) -> Result<()> {
        if let (Some(a), Some(aa)) = (&self.ambient, fs.aa) {
            a.set_accuracy(aa);
        }
        let tracer = self.tracer();
        self.pool.install(|| {
            render_region_rows(&tracer, fs, (r.x0, r.y0, r.x1, r.y1), progress, &mut *sink)
        });
        if let Some(e) = self.scene.fatal_error() {
            anyhow::bail!("{e}");
        }
        Ok(())
    }

    /// A pool of one thread, the calling one, for [`Session::render_here`]: each of a
    /// worker's tile loops makes one on its own thread.
    pub fn here_pool() -> Result<rayon::ThreadPool> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .use_current_thread()
            .build()
            .context("cannot start a render thread")
    }

    /// Render a region of a frame on the calling thread alone, through `here` (a pool made
    /// by [`Session::here_pool`] on this thread), at the frame's `-aa` for this thread only:
    /// several threads may render regions of one session at once, each at its own accuracy
    /// (a worker's tile loops, which share the scene and the ambient cache).
    pub fn render_here(
        &self,
        here: &rayon::ThreadPool,
        fs: &FrameSetup,
        r: Region,
        progress: &RenderProgress,
    ) -> Result<Vec<[f32; 3]>> {
        self.render_on(here, fs, |tracer| {
            render_region(tracer, fs, r.x0, r.y0, r.x1, r.y1, progress)
        })
    }

    /// [`Session::render_here`] on the calling thread in reading order, with `hook` asked
    /// before each cell whether to give part of the region away
    /// ([`crate::render::splitting`]); the pixels given away stay zero.
    pub fn render_here_split(
        &self,
        here: &rayon::ThreadPool,
        fs: &FrameSetup,
        r: Region,
        progress: &RenderProgress,
        hook: &mut (dyn FnMut(&SplitPoint) -> Option<Cut> + Send),
    ) -> Result<Vec<[f32; 3]>> {
        self.render_on(here, fs, |tracer| {
            render_region_split(tracer, fs, (r.x0, r.y0, r.x1, r.y1), progress, hook)
        })
    }

    /// Run `render` through `here` at the frame's `-aa` for this thread only; a fatal scene
    /// error met while rendering is the result.
    fn render_on(
        &self,
        here: &rayon::ThreadPool,
        fs: &FrameSetup,
        render: impl FnOnce(&Tracer) -> Vec<[f32; 3]> + Send,
    ) -> Result<Vec<[f32; 3]>> {
        let tracer = self.tracer();
        let run = || render(&tracer);
        let pixels = here.install(|| match &self.ambient {
            Some(a) => a.with_accuracy(fs.aa, run),
            None => run(),
        });
        if let Some(e) = self.scene.fatal_error() {
            anyhow::bail!("{e}");
        }
        Ok(pixels)
    }

    /// New ambient values made so far and the nanoseconds spent making them.
    pub fn ambient_work(&self) -> (u64, u64) {
        self.ambient
            .as_ref()
            .map(|a| (a.stats.made(), a.stats.amb_nanos.load(Ordering::Relaxed)))
            .unwrap_or((0, 0))
    }

    /// The picture header's record of Tessera's ambient settings (`TESSERA_AMBIENT=` with
    /// every setting as an option), when the ambient calculation runs.
    pub fn ambient_header(&self) -> Vec<(String, String)> {
        self.ambient
            .as_ref()
            .map(|a| {
                vec![(
                    AMBIENT_HEADER_VAR.to_string(),
                    format!(" {}", a.settings().to_text()),
                )]
            })
            .unwrap_or_default()
    }

    /// Load the values of a Radiance ambient file (`-af`) into the cache, if the file
    /// exists; returns a warning about invalid records or trailing bytes.
    pub fn load_ambient_file(&self, path: &Path) -> Result<Option<String>> {
        let Some(a) = self.cached_ambient() else {
            return Ok(None);
        };
        if !path.exists() {
            return Ok(None);
        }
        let (_, records, report) = crate::ambient::radfile::read_file(path)
            .with_context(|| format!("cannot read ambient file {}", path.display()))?;
        for r in &records {
            a.cache
                .insert(CachedValue::from_record(r, self.scene.origin));
        }
        Ok((report.invalid > 0 || report.trailing_bytes > 0).then(|| {
            format!(
                "ambient file {}: ignored {} invalid records and {} trailing bytes",
                path.display(),
                report.invalid,
                report.trailing_bytes
            )
        }))
    }

    /// Append this session's new values to a Radiance ambient file (`-af`), creating it
    /// with a header when it does not exist. The new values go out in one write.
    pub fn save_ambient_file(&self, path: &Path) -> Result<()> {
        use crate::ambient::radfile;
        use std::io::Write;
        let Some(a) = self.cached_ambient() else {
            return Ok(());
        };
        let mine: Vec<_> = a
            .cache
            .all()
            .into_iter()
            .filter(|v| v.id.origin == self.origin_id)
            .map(|v| v.to_record(self.scene.origin))
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
            let p = &self.params;
            let line = format!(
                "tpict -av {} {} {} -aw {} -ab {} -aa {} -ad {} -as {} -ar {}",
                p.av[0], p.av[1], p.av[2], p.aw, p.ab, p.aa, p.ad, p.as_, p.ar
            );
            let mut out = Vec::new();
            radfile::write_header(&mut out, &line, crate::runinfo::SOFTWARE)?;
            out.extend_from_slice(&bytes);
            crate::image::output::write_atomic(path, |f| f.write_all(&out))
                .with_context(|| format!("cannot write ambient file {}", path.display()))?;
        }
        Ok(())
    }
}
