//! `tpiece`: the worker loop.
//!
//! 1. Load the manifest and the flattened scene; refuse to run if the scene or options no
//!    longer give the manifest's fingerprint.
//! 2. Start the heartbeat (and, with `-ab` > 0, ambient sharing: own log, merged store,
//!    other logs).
//! 3. Take over tiles still claimed by an earlier incarnation of the same worker id (a
//!    requeued SLURM task), then claim `todo` tiles in plan order.
//! 4. When nothing is left to claim: finish if every tile is done; otherwise watch the
//!    owners of the remaining claims and re-claim a tile whose owner's heartbeat has not
//!    changed for a lease (or whose owner has ended); wait (T_idle) while they are alive.
//! 5. A tile is rendered, its result written (temporary, fsync, rename), then its entry
//!    renamed to `done`. If the result cannot be written (disk full) the tile is released
//!    back to `todo` and the worker exits with the error.

use super::heartbeat::{
    add_time, beat_interval, read_record, Counters, StaleWatcher, WorkerRecord,
};
use super::manifest::Manifest;
use super::share::{FlushPolicy, Share};
use super::task::{self, TaskState};
use super::tile::{self, TileMeta};
use super::{check_worker_id, default_worker_id, JobDir};
use crate::ambient::Ambient;
use crate::light::LightSet;
use crate::render::{render_region, FrameSetup, RenderProgress, Tracer};
use crate::scene::{read_scene_files, ReadOptions, Scene};
use anyhow::{anyhow, bail, Context, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Worker settings (`tpiece` options).
#[derive(Clone, Debug)]
pub struct WorkerOptions {
    /// `--worker-id` (default: see [`default_worker_id`]).
    pub worker_id: Option<String>,
    /// `--amb-flush N|auto`.
    pub amb_flush: FlushPolicy,
    /// `--threads N` (default: `SLURM_CPUS_PER_TASK`, else every core).
    pub threads: Option<usize>,
    /// Wait for tiles other workers hold (and re-claim them if they die) instead of
    /// exiting when nothing is claimable (`--no-wait` turns it off).
    pub wait: bool,
    /// Print one line per tile.
    pub verbose: bool,
}

impl Default for WorkerOptions {
    fn default() -> Self {
        WorkerOptions {
            worker_id: None,
            amb_flush: FlushPolicy::Auto,
            threads: None,
            wait: true,
            verbose: true,
        }
    }
}

/// What a worker did.
#[derive(Debug, Default)]
pub struct WorkerSummary {
    /// Owner name.
    pub owner: String,
    /// Tiles rendered.
    pub tiles: u64,
    /// Tiles re-claimed from stale owners.
    pub reclaimed: u64,
}

struct Beat {
    job: JobDir,
    record: Mutex<WorkerRecord>,
    counters: Arc<Counters>,
    ambient: Option<Arc<Ambient>>,
    share: Option<Arc<Share>>,
    threads: usize,
    start_cpu: f64,
}

impl Beat {
    fn write(&self, state: Option<&str>, error: Option<String>) {
        let mut r = self.record.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = state {
            r.state = s.to_string();
        }
        if error.is_some() {
            r.error = error;
        }
        let c = &self.counters;
        let secs = |a: &std::sync::atomic::AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
        r.beat += 1;
        r.updated_unix = super::unix_now();
        r.tiles_done = c.tiles_done.load(Ordering::Relaxed);
        r.t_render = secs(&c.render_ns);
        r.t_idle = secs(&c.idle_ns);
        r.t_sync = secs(&c.sync_ns);
        r.shared_in = c.shared_in.load(Ordering::Relaxed);
        r.shared_out = c.shared_out.load(Ordering::Relaxed);
        r.amb_flush = c.amb_flush.load(Ordering::Relaxed);
        r.reclaimed = c.reclaimed.load(Ordering::Relaxed);
        r.rays = c.rays.load(Ordering::Relaxed);
        if let Some(a) = &self.ambient {
            r.new_values = a.stats.made();
            r.t_amb = secs(&a.stats.amb_nanos) / self.threads as f64;
        }
        r.t_spec = (r.t_render - r.t_amb).max(0.0);
        r.cpu_seconds = crate::runinfo::process_cpu_seconds()
            .map(|c| c - self.start_cpu)
            .unwrap_or(0.0);
        if let Ok(json) = serde_json::to_vec_pretty(&*r) {
            let _ = super::write_file_atomic(&self.job.worker_file(&r.owner), &json);
        }
    }
}

/// Run a worker on a job until every tile is done (or, without `wait`, until nothing is
/// claimable).
pub fn run_worker(job: &JobDir, wo: &WorkerOptions) -> Result<WorkerSummary> {
    let m = Manifest::load(job)?;
    let worker_id = wo.worker_id.clone().unwrap_or_else(default_worker_id);
    check_worker_id(&worker_id)?;
    let owner = format!("{worker_id}.{:08x}", super::merge::rand_u32());
    let tasks_dir = job.tasks();
    // Scene, checked against the manifest.
    let scene_path = job.file(&m.scene_file);
    let ro = ReadOptions {
        allow_commands: false,
        raypath: vec![job.root().to_path_buf()],
    };
    let prims = read_scene_files(&[scene_path.display().to_string()], &ro)?;
    let fp = crate::ambient::fingerprint::fingerprint(&prims, &m.params);
    if fp != m.fingerprint_bytes() {
        bail!(
            "{}: the scene or the manifest's options changed since the job was planned \
             (fingerprint {} instead of {}); plan a new job",
            scene_path.display(),
            super::hex32(&fp),
            m.fingerprint
        );
    }
    let scene = Scene::build(&prims)?;
    let lights = LightSet::collect(&scene, m.params.dr);
    let threads = crate::runinfo::thread_count(wo.threads);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("cannot start render threads")?;
    let origin_id = crate::runinfo::process_origin_id();
    let ambient = Ambient::new(&m.params, scene.size, origin_id).map(Arc::new);
    let counters = Arc::new(Counters::default());
    let share = match &ambient {
        Some(a) if a.cached() => Some(Share::open(
            job,
            &owner,
            fp,
            &crate::ambient::fingerprint::options_text(&m.params),
            scene.origin,
            a.clone(),
            wo.amb_flush,
            counters.clone(),
        )?),
        _ => None,
    };
    if let Some(s) = &share {
        s.install();
    }
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_default();
    let beat = Arc::new(Beat {
        job: job.clone(),
        record: Mutex::new(WorkerRecord {
            worker_id: worker_id.clone(),
            owner: owner.clone(),
            host,
            pid: std::process::id(),
            state: "running".into(),
            started_unix: super::unix_now(),
            threads,
            ..WorkerRecord::default()
        }),
        counters: counters.clone(),
        ambient: ambient.clone(),
        share: share.clone(),
        threads,
        start_cpu: crate::runinfo::process_cpu_seconds().unwrap_or(0.0),
    });
    beat.write(None, None);
    let stop = Arc::new(AtomicBool::new(false));
    let interval = beat_interval(m.lease_seconds);
    let beater = {
        let (beat, stop) = (beat.clone(), stop.clone());
        std::thread::spawn(move || {
            // Sync ambient values twice per beat even when this worker makes none.
            let half = interval / 2;
            let mut last_beat = Instant::now();
            while !stop.load(Ordering::Relaxed) {
                std::thread::park_timeout(half);
                if stop.load(Ordering::Relaxed) {
                    break;
                }
                if let Some(s) = &beat.share {
                    s.sync();
                }
                if last_beat.elapsed() >= interval {
                    last_beat = Instant::now();
                    beat.write(None, None);
                }
            }
        })
    };
    let result = work(
        job, &m, &owner, &worker_id, &tasks_dir, &scene, &lights, &ambient, &share, &counters,
        &pool, wo, &beat,
    );
    let result = result.and_then(|s| match &share {
        Some(sh) => sh.finish().map(|()| s),
        None => Ok(s),
    });
    stop.store(true, Ordering::Relaxed);
    beater.thread().unpark();
    let _ = beater.join();
    match &result {
        Ok(_) => beat.write(Some("finished"), None),
        Err(e) => beat.write(Some("failed"), Some(format!("{e:#}"))),
    }
    result
}

#[allow(clippy::too_many_arguments)]
fn work(
    job: &JobDir,
    m: &Manifest,
    owner: &str,
    worker_id: &str,
    tasks_dir: &std::path::Path,
    scene: &Scene,
    lights: &LightSet,
    ambient: &Option<Arc<Ambient>>,
    share: &Option<Arc<Share>>,
    counters: &Arc<Counters>,
    pool: &rayon::ThreadPool,
    wo: &WorkerOptions,
    beat: &Beat,
) -> Result<WorkerSummary> {
    let all = m.tasks();
    let mut summary = WorkerSummary {
        owner: owner.to_string(),
        ..WorkerSummary::default()
    };
    let mut watcher = StaleWatcher::new(m.lease_seconds);
    let poll = Duration::from_secs_f64((m.lease_seconds / 10.0).clamp(0.02, 0.25));
    let tracer = Tracer::new(scene, &m.params, lights).with_ambient(ambient.as_deref());
    let mut cursor = 0usize;
    let mut idle_since: Option<Instant> = None;
    let mut first_scan = true;
    loop {
        // Next todo tile in plan order (todo entries never come back, so the cursor only
        // moves forward).
        let mut mine: Option<(String, u32, usize, bool)> = None;
        while cursor < all.len() {
            let (name, f, t) = &all[cursor];
            cursor += 1;
            if task::claim(tasks_dir, name, owner)
                .with_context(|| format!("cannot claim {name} in {}", tasks_dir.display()))?
            {
                mine = Some((name.clone(), *f, *t, false));
                break;
            }
        }
        if mine.is_none() {
            // A directory listing made while other workers rename entries may miss an entry
            // (POSIX leaves renamed entries unspecified during readdir): list again before
            // concluding that entries are really missing.
            let mut states = task::scan(tasks_dir)
                .with_context(|| format!("cannot list {}", tasks_dir.display()))?;
            let missing = |st: &std::collections::HashMap<String, TaskState>| {
                all.iter().filter(|(n, _, _)| !st.contains_key(n)).count()
            };
            // Back off from 20 ms up to about 5 s in all: on NFS a client's cached listing
            // may lag the server for a while.
            for attempt in 0..8 {
                if missing(&states) == 0 {
                    break;
                }
                std::thread::sleep(Duration::from_millis(20 << attempt));
                states = task::scan(tasks_dir)
                    .with_context(|| format!("cannot list {}", tasks_dir.display()))?;
            }
            let lost = missing(&states);
            if lost > 0 {
                bail!(
                    "{}: {lost} of {} task entries are missing (was the job directory edited?)",
                    tasks_dir.display(),
                    all.len()
                );
            }
            if all
                .iter()
                .all(|(n, _, _)| states.get(n) == Some(&TaskState::Done))
            {
                break;
            }
            // A todo entry can reappear only when a worker released its tile.
            if all
                .iter()
                .any(|(n, _, _)| states.get(n) == Some(&TaskState::Todo))
            {
                cursor = 0;
                continue;
            }
            for (name, f, t) in &all {
                let Some(TaskState::Claimed(o)) = states.get(name) else {
                    continue;
                };
                if o == owner {
                    continue;
                }
                let same_id = o.rsplit_once('.').map(|(id, _)| id) == Some(worker_id);
                let stale = (first_scan && same_id)
                    || watcher.is_stale(o, read_record(&job.worker_file(o)).as_ref());
                if stale && task::reclaim(tasks_dir, name, o, owner)? {
                    mine = Some((name.clone(), *f, *t, true));
                    summary.reclaimed += 1;
                    counters.reclaimed.fetch_add(1, Ordering::Relaxed);
                    if wo.verbose {
                        eprintln!("tpiece {owner}: re-claimed {name} from {o}");
                    }
                    break;
                }
            }
            first_scan = false;
        }
        let Some((name, frame, ti, reclaimed)) = mine else {
            if !wo.wait {
                break;
            }
            idle_since.get_or_insert_with(Instant::now);
            beat.record.lock().map(|mut r| r.state = "idle".into()).ok();
            std::thread::sleep(poll);
            continue;
        };
        if let Some(since) = idle_since.take() {
            add_time(&counters.idle_ns, since.elapsed());
            beat.record
                .lock()
                .map(|mut r| r.state = "running".into())
                .ok();
        }
        let fp = m
            .frame(frame)
            .ok_or_else(|| anyhow!("task {name}: no frame {frame}"))?;
        let rect = *fp
            .tiles
            .get(ti)
            .ok_or_else(|| anyhow!("task {name}: no tile {ti}"))?;
        let out = job.tile_file(&name);
        // A re-claimed tile whose result was written before its owner died needs no render.
        if reclaimed {
            if let Ok((meta, _)) = tile::read(&out) {
                if meta.fingerprint == m.fingerprint
                    && (meta.x0, meta.y0, meta.w, meta.h) == (rect.x0, rect.y0, rect.w, rect.h)
                {
                    task::complete(tasks_dir, &name, owner)?;
                    continue;
                }
            }
        }
        let vf = fp
            .view
            .frame()
            .map_err(|e| anyhow!("frame {frame}: bad view: {e}"))?;
        let fs = FrameSetup {
            view: &vf,
            xres: fp.xres,
            yres: fp.yres,
            pj: m.picture.pj,
            ps: m.picture.ps,
            pt: m.picture.pt,
            frame: fp.index,
            irradiance: m.params.i,
            overture: m.picture.overture_step(&m.params),
        };
        let amb_before = ambient
            .as_ref()
            .map(|a| (a.stats.made(), a.stats.amb_nanos.load(Ordering::Relaxed)));
        let cpu0 = crate::runinfo::process_cpu_seconds().unwrap_or(0.0);
        let t0 = Instant::now();
        let progress = RenderProgress::default();
        let pixels = pool.install(|| {
            render_region(
                &tracer,
                &fs,
                rect.x0,
                rect.y0,
                rect.x0 + rect.w,
                rect.y0 + rect.h,
                &progress,
            )
        });
        let wall = t0.elapsed();
        add_time(&counters.render_ns, wall);
        let rays = progress.rays.load(Ordering::Relaxed);
        counters.rays.fetch_add(rays, Ordering::Relaxed);
        let (new_values, amb_secs) = match (ambient, amb_before) {
            (Some(a), Some((n0, t0))) => (
                a.stats.made() - n0,
                (a.stats.amb_nanos.load(Ordering::Relaxed) - t0) as f64 * 1e-9,
            ),
            _ => (0, 0.0),
        };
        let meta = TileMeta {
            task: name.clone(),
            frame,
            tile: ti,
            x0: rect.x0,
            y0: rect.y0,
            w: rect.w,
            h: rect.h,
            fingerprint: m.fingerprint.clone(),
            owner: owner.to_string(),
            wall_seconds: wall.as_secs_f64(),
            cpu_seconds: (crate::runinfo::process_cpu_seconds().unwrap_or(0.0) - cpu0).max(0.0),
            rays,
            new_values,
            ambient_seconds: amb_secs,
        };
        // Values made for this tile go out before it counts as done.
        if let Some(s) = share {
            s.sync();
            if let Some(e) = s.error() {
                let _ = task::release(tasks_dir, &name, owner);
                bail!("ambient log: {e} (tile {name} released)");
            }
        }
        if let Err(e) = tile::write(&out, &meta, &pixels) {
            let _ = task::release(tasks_dir, &name, owner);
            return Err(e.context(format!("tile {name} released for another worker")));
        }
        let completed = task::complete(tasks_dir, &name, owner)?;
        counters.tiles_done.fetch_add(1, Ordering::Relaxed);
        summary.tiles += 1;
        if wo.verbose {
            eprintln!(
                "tpiece {owner}: {name} {}x{} at {},{} in {:.2}s{}{}",
                rect.w,
                rect.h,
                rect.x0,
                rect.y0,
                wall.as_secs_f64(),
                if new_values > 0 {
                    format!(", {new_values} new ambient values")
                } else {
                    String::new()
                },
                if completed {
                    ""
                } else {
                    " (re-claimed meanwhile by another worker; result kept)"
                }
            );
        }
    }
    if let Some(since) = idle_since.take() {
        add_time(&counters.idle_ns, since.elapsed());
    }
    Ok(summary)
}
