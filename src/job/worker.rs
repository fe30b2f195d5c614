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

use super::commit::{commit_loop, CommitTarget, Finished};
use super::heartbeat::{add_time, beat_interval, read_record, Beat, StaleWatcher};
use super::manifest::{FramePlan, Manifest};
use super::plan::TileRect;
use super::task::{self, TaskState};
use super::tile::{self, ResultDir, TileMeta};
use super::{check_worker_id, default_worker_id, JobDir};
use crate::render::RenderProgress;
use crate::session::store::FlushPolicy;
use crate::session::{Region, Session};
use anyhow::{anyhow, bail, Context, Result};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Worker settings (`tpiece` options).
#[derive(Clone, Debug)]
pub struct WorkerOptions {
    /// `--worker-id` (default: see [`default_worker_id`]).
    pub worker_id: Option<String>,
    /// `--amb-flush N|auto`.
    pub amb_flush: FlushPolicy,
    /// `--threads N`: tile loops, each rendering its own tile on one thread, all sharing
    /// one scene and one ambient cache (default: `SLURM_CPUS_PER_TASK`, else every core).
    pub threads: Option<usize>,
    /// Wait for tiles other workers hold (and re-claim them if they die) instead of
    /// exiting when nothing is claimable (`--no-wait` turns it off).
    pub wait: bool,
    /// Print one line per tile.
    pub verbose: bool,
    /// Map the job's scene image (`--no-scene-image` turns it off: build the scene and
    /// leave the image alone).
    pub scene_image: bool,
}

impl Default for WorkerOptions {
    fn default() -> Self {
        WorkerOptions {
            worker_id: None,
            amb_flush: FlushPolicy::Auto,
            threads: None,
            wait: true,
            verbose: true,
            scene_image: true,
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

/// The shortest wait between two looks at `tasks/` while other workers hold every tile left.
const MIN_POLL: f64 = 0.02;

/// Run a worker on a job until every tile is done (or, without `wait`, until nothing is
/// claimable): `--threads` tile loops on threads of their own, each claiming and rendering
/// its own tiles on one thread, sharing the scene, the ambient cache and the store.
pub fn run_worker(job: &JobDir, wo: &WorkerOptions) -> Result<WorkerSummary> {
    let m = Manifest::load(job)?;
    let worker_id = wo.worker_id.clone().unwrap_or_else(default_worker_id);
    check_worker_id(&worker_id)?;
    let owner = format!("{worker_id}.{:08x}", super::merge::rand_u32());
    let (loops, cut) = crate::runinfo::thread_count(wo.threads);
    if let Some(w) = cut {
        eprintln!("tpiece: warning: {w}");
    }
    if loops == 1 && m.threads_expected >= 2 && m.split {
        eprintln!(
            "tpiece: warning: the job was planned for workers of {} tile loops (tplan --threads), \
             whose loops split its few tiles among themselves; a single-thread worker ends \
             frames later",
            m.threads_expected
        );
    }
    let start = super::jobscene::SceneStart {
        amb_flush: wo.amb_flush,
        scene_image: wo.scene_image,
        verbose: wo.verbose,
    };
    let session = super::jobscene::start_session(job, &m, &owner, &start)?;
    let beat = Arc::new(Beat::new(job, &worker_id, &owner, &session, loops));
    beat.write(None, None);
    let beater = beat.spawn(beat_interval(m.lease_seconds));
    let all = m.tasks();
    // A point job's rays, read once for every loop.
    let rays = match &m.points {
        Some(p) => super::points::load_rays(job, p)?,
        None => Vec::new(),
    };
    let stop = AtomicBool::new(false);
    let taken = Mutex::new(HashSet::new());
    let siblings = super::siblings::Siblings::default();
    let pending = AtomicUsize::new(0);
    let results = ResultDir::open(&job.tiles())?;
    let tasks_dir = job.tasks();
    let outcomes: Vec<Result<()>> = std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::channel();
        let target = CommitTarget {
            tasks_dir: &tasks_dir,
            owner: &owner,
            counters: &beat.counters,
            verbose: wo.verbose,
            stop: &stop,
            pending: &pending,
        };
        let committer = scope.spawn(move || commit_loop(rx, results, target));
        let handles: Vec<_> = (0..loops)
            .map(|index| {
                let (m, owner, worker_id, session, beat, all, stop, taken, pending, rays) = (
                    &m, &owner, &worker_id, &session, &beat, &all, &stop, &taken, &pending, &rays,
                );
                let siblings = &siblings;
                let commit = tx.clone();
                scope.spawn(move || -> Result<()> {
                    let here = Session::here_pool()?;
                    let mut worker = Worker {
                        job,
                        m,
                        tasks_dir: job.tasks(),
                        owner,
                        worker_id,
                        session,
                        wo,
                        beat,
                        here,
                        index,
                        stop,
                        taken,
                        siblings,
                        all,
                        cursor: 0,
                        first_scan: true,
                        idle_since: None,
                        watcher: StaleWatcher::new(m.lease_seconds),
                        done_count: 0,
                        commit,
                        pending,
                        budget_aa: Default::default(),
                        rays,
                    };
                    let r = worker.work();
                    if r.is_err() {
                        // The other loops stop after their tile.
                        stop.store(true, Ordering::Relaxed);
                    }
                    r
                })
            })
            .collect();
        drop(tx);
        let mut out: Vec<Result<()>> = handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(anyhow!("a tile loop of {owner} panicked")))
            })
            .collect();
        // The committer ends when the loops (its senders) have ended; its error first: a
        // loop that stopped on it has none of its own.
        let committed = committer
            .join()
            .unwrap_or_else(|_| Err(anyhow!("the tile committer of {owner} panicked")));
        out.insert(0, committed);
        out
    });
    let result = outcomes
        .into_iter()
        .find(|r| r.is_err())
        .unwrap_or(Ok(()))
        .and_then(|()| session.finish())
        .map(|()| WorkerSummary {
            owner: owner.clone(),
            tiles: beat.counters.tiles_done.load(Ordering::Relaxed),
            reclaimed: beat.counters.reclaimed.load(Ordering::Relaxed),
        });
    beater.stop();
    match &result {
        Ok(_) => beat.write(Some("finished"), None),
        Err(e) => beat.write(Some("failed"), Some(format!("{e:#}"))),
    }
    result
}

/// A claimed task.
struct Claim {
    name: String,
    frame: u32,
    tile: usize,
    /// A piece's rectangle (None: the whole tile).
    piece: Option<TileRect>,
    /// Taken over from a stale owner.
    reclaimed: bool,
}

/// What to do next.
enum Next {
    /// Render this tile.
    Tile(Claim),
    /// Every tile is done.
    Done,
    /// A released tile is back in `todo`: claim again from the start.
    Retry,
    /// Other workers hold every remaining tile.
    Wait,
}

/// One tile loop's state while it takes tiles.
struct Worker<'a> {
    job: &'a JobDir,
    m: &'a Manifest,
    tasks_dir: PathBuf,
    owner: &'a str,
    worker_id: &'a str,
    session: &'a Session,
    wo: &'a WorkerOptions,
    beat: &'a Beat,
    /// This loop's one-thread pool (the loop's own thread).
    here: rayon::ThreadPool,
    /// This loop's number among the worker's loops (loop 0 speaks for the worker).
    index: usize,
    /// Set when a loop failed: the others stop after their tile.
    stop: &'a AtomicBool,
    /// Tasks the worker's loops have claimed (they share one owner name, so a loop must
    /// not take a sibling's claim for its own: see [`Worker::take`]).
    taken: &'a Mutex<HashSet<String>>,
    /// What the worker's loops tell each other: who waits, and when a piece was made.
    siblings: &'a super::siblings::Siblings,
    /// Every task in plan order.
    all: &'a [(String, u32, usize)],
    /// The next task to try to claim (todo entries never come back unless released, so the
    /// cursor only moves forward until then).
    cursor: usize,
    first_scan: bool,
    idle_since: Option<Instant>,
    watcher: StaleWatcher,
    /// Tasks done at the last scan of `tasks/`.
    done_count: usize,
    /// The worker's committer of finished tiles ([`super::commit`]).
    commit: std::sync::mpsc::Sender<Finished>,
    /// Tiles handed to the committer and not yet committed (or failed).
    pending: &'a AtomicUsize,
    /// `-axt`: the frames' accuracies read or decided so far ([`super::budget`]).
    budget_aa: std::cell::RefCell<HashMap<u32, f64>>,
    /// A point job's rays (empty for a picture job).
    rays: &'a [crate::ttrace::records::InRay],
}

impl Worker<'_> {
    fn work(&mut self) -> Result<()> {
        // While waiting, look again after 20 ms, then 1.5× longer each time nothing changed
        // (up to a tenth of the lease, at most 0.25 s, or 0.1 s when tiles may be split and a
        // new piece is what it waits for), and after 20 ms again whenever another tile got
        // done: a worker notices the last tile's end within a fraction of the time it waited,
        // without scanning `tasks/` at a fixed high rate.
        let most = if self.m.split { 0.1 } else { 0.25 };
        let cap = (self.m.lease_seconds / 10.0).clamp(0.02, most);
        let mut poll = MIN_POLL;
        let mut done_seen = 0;
        loop {
            if self.stop.load(Ordering::Relaxed) {
                break;
            }
            let claim = match self.next()? {
                Next::Tile(c) => c,
                Next::Done => break,
                Next::Retry => continue,
                Next::Wait => {
                    if !self.wo.wait {
                        break;
                    }
                    if self.idle_since.is_none() {
                        if self.wo.verbose && self.index == 0 {
                            self.say_waiting();
                        }
                        poll = MIN_POLL;
                    } else if self.done_count > done_seen {
                        poll = MIN_POLL;
                    } else {
                        poll = (poll * 1.5).min(cap);
                    }
                    done_seen = self.done_count;
                    if self.idle_since.is_none() {
                        self.idle_since = Some(Instant::now());
                        self.siblings.begin_idle();
                    }
                    self.beat.set_state("idle");
                    // A sibling loop's new piece ends the wait at once.
                    if self.siblings.wait(Duration::from_secs_f64(poll)) {
                        poll = MIN_POLL;
                    }
                    continue;
                }
            };
            if self.end_idle() {
                self.beat.set_state("running");
            }
            self.do_tile(&claim)?;
        }
        self.end_idle();
        Ok(())
    }

    /// Say (once per wait) which tiles this worker waits for and when it may take them over.
    fn say_waiting(&self) {
        let Ok(states) = task::scan(&self.tasks_dir) else {
            return;
        };
        let mut owners: Vec<&str> = states
            .values()
            .filter_map(|s| match s {
                TaskState::Claimed(o) if o != self.owner => Some(o.as_str()),
                _ => None,
            })
            .collect();
        let held = owners.len();
        if held == 0 {
            // Only this worker's own tiles are open (its committer is writing them, or its
            // other loops render them): nothing to wait for from others.
            return;
        }
        owners.sort_unstable();
        owners.dedup();
        eprintln!(
            "tpiece: waiting for {held} tile(s) other workers hold ({}); a worker silent for \
             the lease ({:.0} s) loses its tiles to the waiting ones",
            owners.join(", "),
            self.m.lease_seconds
        );
    }

    /// Claim `name` with `rename` (a claim or a re-claim) unless a sibling loop already
    /// did. The loops share the owner name, and a rename that fails with `ENOENT` counts as
    /// won when its target exists (a retransmitted NFS rename, [`task::claim`]): a sibling's
    /// claim would look like this loop's own. So claims go one at a time through the
    /// worker's list of tasks its loops have taken, and a task on it is never tried again
    /// (a tile this worker released is not claimed by it again: it exits with the error).
    fn take(&self, name: &str, rename: impl FnOnce() -> Result<bool>) -> Result<bool> {
        let mut taken = self.taken.lock().unwrap_or_else(|e| e.into_inner());
        if taken.contains(name) {
            return Ok(false);
        }
        let won = rename()?;
        if won {
            taken.insert(name.to_string());
        }
        Ok(won)
    }

    /// Count the idle time that ends now; whether the worker was idle.
    fn end_idle(&mut self) -> bool {
        match self.idle_since.take() {
            Some(since) => {
                self.siblings.end_idle();
                add_time(&self.beat.counters.idle_ns, since.elapsed());
                true
            }
            None => false,
        }
    }

    /// The next tile to render: a `todo` tile in plan order, else one re-claimed from a stale
    /// owner.
    fn next(&mut self) -> Result<Next> {
        while self.cursor < self.all.len() {
            let (name, f, t) = &self.all[self.cursor];
            self.cursor += 1;
            let claimed = self.take(name, || {
                task::claim(&self.tasks_dir, name, self.owner)
                    .with_context(|| format!("cannot claim {name} in {}", self.tasks_dir.display()))
            })?;
            if claimed {
                return Ok(Next::Tile(Claim {
                    name: name.clone(),
                    frame: *f,
                    tile: *t,
                    piece: None,
                    reclaimed: false,
                }));
            }
        }
        let states = self.scan()?;
        self.done_count = states.values().filter(|s| **s == TaskState::Done).count();
        // Every entry done: the plan's tasks (all present, `scan` checked) and the pieces.
        if states.values().all(|s| *s == TaskState::Done) {
            return Ok(Next::Done);
        }
        // A todo entry can reappear only when a worker released its tile.
        if self
            .all
            .iter()
            .any(|(n, _, _)| states.get(n) == Some(&TaskState::Todo))
        {
            self.cursor = 0;
            return Ok(Next::Retry);
        }
        if let Some(c) = self.claim_piece(&states)? {
            return Ok(Next::Tile(c));
        }
        let reclaimed = self.reclaim_stale(&states)?;
        self.first_scan = false;
        Ok(reclaimed.map_or(Next::Wait, Next::Tile))
    }

    /// The state of every task. A directory listing made while other workers rename entries
    /// may miss an entry (POSIX leaves renamed entries unspecified during readdir): list
    /// again before concluding that entries are really missing.
    fn scan(&self) -> Result<HashMap<String, TaskState>> {
        let dir = &self.tasks_dir;
        let list = || task::scan(dir).with_context(|| format!("cannot list {}", dir.display()));
        let missing = |st: &HashMap<String, TaskState>| {
            self.all
                .iter()
                .filter(|(n, _, _)| !st.contains_key(n))
                .count()
        };
        let mut states = list()?;
        // Back off from 20 ms up to about 5 s in all: on NFS a client's cached listing
        // may lag the server for a while.
        for attempt in 0..8 {
            if missing(&states) == 0 {
                break;
            }
            std::thread::sleep(Duration::from_millis(20 << attempt));
            states = list()?;
        }
        let lost = missing(&states);
        if lost > 0 {
            bail!(
                "{}: {lost} of {} task entries are missing (was the job directory edited?)",
                dir.display(),
                self.all.len()
            );
        }
        Ok(states)
    }

    /// Claim a piece split off a tile ([`super::piece`]) that is `todo`, the first in
    /// name order.
    fn claim_piece(&mut self, states: &HashMap<String, TaskState>) -> Result<Option<Claim>> {
        let mut todo: Vec<(&String, super::piece::TaskId)> = states
            .iter()
            .filter(|(_, s)| **s == TaskState::Todo)
            .filter_map(|(n, _)| super::piece::parse(n).map(|id| (n, id)))
            .filter(|(_, id)| id.piece.is_some())
            .collect();
        todo.sort_by(|a, b| a.0.cmp(b.0));
        for (name, id) in todo {
            let claimed = self.take(name, || {
                task::claim(&self.tasks_dir, name, self.owner)
                    .with_context(|| format!("cannot claim {name} in {}", self.tasks_dir.display()))
            })?;
            if claimed {
                return Ok(Some(Claim {
                    name: name.clone(),
                    frame: id.frame,
                    tile: id.tile,
                    piece: id.piece,
                    reclaimed: false,
                }));
            }
        }
        Ok(None)
    }

    /// Re-claim a tile or piece whose owner is stale (or an earlier incarnation of this
    /// worker id, at the first scan).
    fn reclaim_stale(&mut self, states: &HashMap<String, TaskState>) -> Result<Option<Claim>> {
        let mut held: Vec<(&String, &String)> = states
            .iter()
            .filter_map(|(n, s)| match s {
                TaskState::Claimed(o) if o != self.owner => Some((n, o)),
                _ => None,
            })
            .collect();
        held.sort();
        for (name, o) in held {
            let Some(id) = super::piece::parse(name) else {
                continue;
            };
            let same_id = o.rsplit_once('.').map(|(id, _)| id) == Some(self.worker_id);
            let stale = (self.first_scan && same_id)
                || self
                    .watcher
                    .is_stale(o, read_record(&self.job.worker_file(o)).as_ref());
            if stale
                && self.take(name, || {
                    Ok(task::reclaim(&self.tasks_dir, name, o, self.owner)?)
                })?
            {
                self.beat.counters.reclaimed.fetch_add(1, Ordering::Relaxed);
                if self.wo.verbose {
                    eprintln!("tpiece {}: re-claimed {name} from {o}", self.owner);
                }
                return Ok(Some(Claim {
                    name: name.clone(),
                    frame: id.frame,
                    tile: id.tile,
                    piece: id.piece,
                    reclaimed: true,
                }));
            }
        }
        Ok(None)
    }

    /// Render a claimed tile, write its result and mark it done.
    fn do_tile(&mut self, c: &Claim) -> Result<()> {
        let name = &c.name;
        let fp = self
            .m
            .frame(c.frame)
            .ok_or_else(|| anyhow!("task {name}: no frame {}", c.frame))?;
        let tile_rect = *fp
            .tiles
            .get(c.tile)
            .ok_or_else(|| anyhow!("task {name}: no tile {}", c.tile))?;
        let rect = match c.piece {
            Some(p) if super::piece::in_tile(&p, &tile_rect) => p,
            Some(_) => bail!("task {name}: the piece lies outside its tile"),
            None => tile_rect,
        };
        let out = self.job.tile_file(name);
        // A re-claimed tile whose result was written before its owner died needs no render.
        if c.reclaimed && self.result_exists(&out, &rect) {
            task::complete(&self.tasks_dir, name, self.owner)?;
            return Ok(());
        }
        // A tile larger than the memory this process may still use (the machine's, its
        // control group's, its address-space limit) is handed back before it is rendered.
        // Asking costs five reads of /proc and /sys (a third of a small tile's overhead), so
        // only tiles that need a noticeable amount ask.
        let fits = crate::runinfo::check_memory_if_large(
            rect.w,
            rect.h,
            "plan the job with smaller tiles (tplan --tiles N or --tile-size)",
        );
        if let Err(e) = fits {
            let _ = task::release(&self.tasks_dir, name, self.owner);
            bail!("tile {name}: {e} (tile released)");
        }
        let (meta, pixels, gave_pieces) = self.render_tile(c, fp, &rect)?;
        // Values made for this tile go out before it counts as done (a write, no peer read:
        // the heartbeat thread and the value sink read the peers).
        if let Some(s) = self.session.store() {
            s.flush();
            if let Some(e) = s.error() {
                let _ = task::release(&self.tasks_dir, name, self.owner);
                bail!("ambient log: {e} (tile {name} released)");
            }
        }
        // The committer writes it and marks it done; this loop renders on.
        self.pending.fetch_add(1, Ordering::SeqCst);
        self.commit
            .send(Finished {
                name: name.clone(),
                meta,
                pixels,
                gave_pieces,
            })
            .map_err(|_| anyhow!("tile {name}: the worker's committer has stopped"))?;
        Ok(())
    }

    /// Whether `out` holds this job's result for the tile `rect`.
    fn result_exists(&self, out: &Path, rect: &TileRect) -> bool {
        match tile::read(out) {
            Ok((meta, _)) => {
                meta.fingerprint == self.m.fingerprint
                    && (meta.x0, meta.y0, meta.w, meta.h) == (rect.x0, rect.y0, rect.w, rect.h)
            }
            Err(_) => false,
        }
    }

    /// `-axt`: frame `frame`'s accuracy, read or decided once per frame.
    fn budget_accuracy(&self, frame: u32) -> Result<f64> {
        if let Some(&aa) = self.budget_aa.borrow().get(&frame) {
            return Ok(aa);
        }
        // The decision reads which earlier frames are done: first let the committer mark
        // this worker's finished tiles done.
        while self.pending.load(Ordering::SeqCst) > 0 && !self.stop.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(1));
        }
        let aa = super::budget::frame_accuracy(self.job, self.m, frame)?;
        self.budget_aa.borrow_mut().insert(frame, aa);
        Ok(aa)
    }

    /// Render the tile `rect` of frame `fp`: its pixels and the result's metadata.
    fn render_tile(
        &self,
        c: &Claim,
        fp: &FramePlan,
        rect: &TileRect,
    ) -> Result<(TileMeta, Vec<[f32; 3]>, bool)> {
        let vf = fp
            .view
            .frame()
            .map_err(|e| anyhow!("frame {}: bad view: {e}", c.frame))?;
        let mut fs = self
            .m
            .picture
            .frame_setup(&self.m.params, &vf, (fp.xres, fp.yres), fp.index);
        // Frames are numbered from 0 in the job: the index is the position in the animation.
        fs.aa = self.m.params.frame_accuracy(fp.index);
        if self.m.params.axt.is_some() {
            fs.aa = Some(self.budget_accuracy(fp.index)?);
        }
        if let Some(mo) = self.m.params.axm {
            // Every tile sets its accuracy: the previous tile's may have been relaxed.
            let base = fs.aa.unwrap_or(self.m.params.aa);
            let mut aa = base;
            if let Some(later) = self.m.frame(fp.index.saturating_add(mo.ahead)) {
                let lvf = later
                    .view
                    .frame()
                    .map_err(|e| anyhow!("frame {}: bad view: {e}", later.index))?;
                let region = Region {
                    x0: rect.x0,
                    y0: rect.y0,
                    x1: rect.x0 + rect.w,
                    y1: rect.y0 + rect.h,
                };
                let share = self
                    .session
                    .share_still_seen(&vf, (fp.xres, fp.yres), region, &lvf);
                if share < crate::options::schedule::MotionAccuracy::STAYING {
                    aa = base * mo.relax;
                }
            }
            fs.aa = Some(aa);
        }
        let (made0, nanos0) = crate::ambient::compute::thread_work();
        let cpu0 = crate::runinfo::thread_cpu_nanos();
        let t0 = Instant::now();
        let progress = RenderProgress::default();
        let region = Region {
            x0: rect.x0,
            y0: rect.y0,
            x1: rect.x0 + rect.w,
            y1: rect.y0 + rect.h,
        };
        let mut gave_pieces = false;
        let pixels = match &self.m.points {
            Some(p) => super::points::trace_chunk(
                (self.session, &self.here),
                p,
                self.rays,
                rect,
                &progress,
            )?,
            None if self.m.split => {
                let last = self.all.last().map_or("", |(n, _, _)| n.as_str());
                let mut sp = super::split::Splitter::new(
                    &self.tasks_dir,
                    (&c.name, self.owner),
                    last,
                    c.frame,
                    c.tile,
                )
                .with_siblings(self.siblings);
                let pixels = self.session.render_here_split(
                    &self.here,
                    &fs,
                    region,
                    &progress,
                    &mut |at| sp.hook(at),
                )?;
                if self.wo.verbose && !sp.made.is_empty() {
                    eprintln!(
                        "tpiece {}: {} split off {}",
                        self.owner,
                        c.name,
                        sp.made.join(", ")
                    );
                }
                self.beat
                    .counters
                    .split
                    .fetch_add(sp.made.len() as u64, Ordering::Relaxed);
                gave_pieces = !sp.made.is_empty();
                pixels
            }
            None => self
                .session
                .render_here(&self.here, &fs, region, &progress)?,
        };
        let wall = t0.elapsed();
        let counters = &self.beat.counters;
        add_time(&counters.render_ns, wall);
        let rays = progress.rays.load(Ordering::Relaxed);
        counters.rays.fetch_add(rays, Ordering::Relaxed);
        let (made1, nanos1) = crate::ambient::compute::thread_work();
        let meta = TileMeta {
            task: c.name.clone(),
            frame: c.frame,
            tile: c.tile,
            x0: rect.x0,
            y0: rect.y0,
            w: rect.w,
            h: rect.h,
            fingerprint: self.m.fingerprint.clone(),
            owner: self.owner.to_string(),
            wall_seconds: wall.as_secs_f64(),
            cpu_seconds: crate::runinfo::thread_cpu_nanos().saturating_sub(cpu0) as f64 * 1e-9,
            rays,
            new_values: made1 - made0,
            ambient_seconds: (nanos1 - nanos0) as f64 * 1e-9,
        };
        Ok((meta, pixels, gave_pieces))
    }
}
