//! `tstat`: progress and the seed paper's metrics.
//!
//! Per worker and aggregated: T_spec (rendering not spent making ambient values), T_amb
//! (making new ambient values), T_idle (waiting with nothing to claim), T_sync (ambient log
//! writes and reads), extensive ambient computations, values shared in and out, tiles.
//! Worker liveness shown here is judged from the heartbeat's wall-clock time and is only
//! informational: workers themselves never judge staleness by clocks (see heartbeat.rs).

use super::heartbeat::{read_record, WorkerRecord};
use super::manifest::Manifest;
use super::task::{self, TaskState};
use super::{tile, JobDir};
use anyhow::{Context, Result};
use serde::Serialize;

/// Progress of one frame.
#[derive(Debug, Default, Serialize)]
pub struct FrameProgress {
    /// Frame number.
    pub frame: u32,
    /// Tiles in the plan.
    pub tiles: usize,
    /// Not claimed.
    pub todo: usize,
    /// Claimed.
    pub claimed: usize,
    /// Done.
    pub done: usize,
    /// Tiles of the plan with no task entry at all: the job directory was damaged (an entry
    /// is always in one of the three states).
    pub missing: usize,
    /// Sums over the frame's finished tiles (their results): CPU seconds, render wall
    /// seconds, rays, new ambient values and the seconds spent making them (T_amb).
    pub cpu_seconds: f64,
    /// Render wall seconds (summed over tiles).
    pub wall_seconds: f64,
    /// Rays traced.
    pub rays: u64,
    /// Ambient values computed (extensive computations).
    pub new_values: u64,
    /// Seconds spent computing them.
    pub ambient_seconds: f64,
    /// The frame's own `-aa` when it varies (`-ax`, `-axg`, `-axt` once decided).
    pub aa: Option<f64>,
}

/// Aggregated metrics (sums over workers).
#[derive(Debug, Default, Serialize)]
pub struct Aggregate {
    /// Worker incarnations seen.
    pub workers: usize,
    /// Workers whose heartbeat is recent and who have not ended.
    pub live: usize,
    /// Workers that have not ended but whose heartbeat is older than the lease (dead, or
    /// on a host whose clock disagrees: informational).
    pub stale: usize,
    /// Workers that have not ended and whose heartbeat is late (more than three beat
    /// intervals) but within the lease: perhaps dead, their tiles not yet re-claimable.
    #[serde(default)]
    pub suspect: usize,
    /// Done tiles that no heartbeat counts yet (a worker died between finishing a tile and
    /// its next beat): the plan's done entries minus the heartbeats' sum, when positive.
    #[serde(default)]
    pub unreported_tiles: u64,
    /// Tiles rendered.
    pub tiles_done: u64,
    /// Tiles re-claimed from stale (or earlier) owners.
    pub reclaimed: u64,
    /// Pieces split off tiles while they rendered.
    #[serde(default)]
    pub split: u64,
    /// ΣT_spec.
    pub t_spec: f64,
    /// ΣT_amb.
    pub t_amb: f64,
    /// ΣT_idle.
    pub t_idle: f64,
    /// ΣT_sync.
    pub t_sync: f64,
    /// Σ CPU seconds.
    pub cpu_seconds: f64,
    /// Extensive ambient computations.
    pub new_values: u64,
    /// Values read from others.
    pub shared_in: u64,
    /// Values written for others.
    pub shared_out: u64,
    /// Invalid ambient records skipped (docs/robustness.md).
    pub rejected: u64,
    /// Rays.
    pub rays: u64,
    /// From the first worker's start to the last heartbeat (seconds).
    pub wall_seconds: f64,
}

/// Everything tstat reports.
#[derive(Debug, Default, Serialize)]
pub struct JobStatus {
    /// Job directory.
    pub job: String,
    /// Number of frames.
    pub frame_count: usize,
    /// Per frame.
    pub frames: Vec<FrameProgress>,
    /// Tiles in all.
    pub tiles: usize,
    /// Done in all (a tile with the pieces split off it).
    pub done: usize,
    /// Pieces split off tiles while they rendered ([`super::piece`]).
    #[serde(default)]
    pub pieces: usize,
    /// Of those, done.
    #[serde(default)]
    pub pieces_done: usize,
    /// Estimated seconds left (None before the first tile).
    pub eta_seconds: Option<f64>,
    /// The job's lease (seconds a silent worker keeps its tiles).
    pub lease_seconds: f64,
    /// Per worker.
    pub workers: Vec<WorkerRecord>,
    /// Per worker (same order): the state `tstat` shows: the worker's own (`finished`,
    /// `failed`) or, for a worker that says it is `running` or `idle`, that state when its
    /// heartbeat is fresh, `suspect` when it missed three beats, `stale` after the lease.
    pub shown_state: Vec<String>,
    /// Sums.
    pub aggregate: Aggregate,
    /// With a baseline job: its wall time, and this job's speed-up and efficiency.
    pub baseline: Option<Baseline>,
    /// Heartbeat files left out as implausible (crafted or damaged), each with why.
    #[serde(default)]
    pub bad_heartbeats: Vec<String>,
}

/// Comparison with a one-worker job.
#[derive(Debug, Default, Serialize)]
pub struct Baseline {
    /// Baseline job directory.
    pub job: String,
    /// Its wall time.
    pub wall_seconds: f64,
    /// Its extensive ambient computations.
    pub new_values: u64,
    /// Baseline wall / this wall.
    pub speedup: f64,
    /// Speed-up / workers.
    pub efficiency: f64,
    /// This job's new values / the baseline's.
    pub new_values_ratio: f64,
}

/// Read the job's state.
pub fn status(job: &JobDir) -> Result<JobStatus> {
    let m = Manifest::load(job)?;
    let states = task::scan(&job.tasks())
        .with_context(|| format!("cannot list {}", job.tasks().display()))?;
    let pieces = super::task::pieces(&states);
    let mut st = JobStatus {
        job: job.root().display().to_string(),
        ..JobStatus::default()
    };
    st.frame_count = m.frames.len();
    st.lease_seconds = m.lease_seconds;
    let mut remaining_px = 0usize;
    let mut done_px = 0usize;
    for f in &m.frames {
        let mut p = FrameProgress {
            frame: f.index,
            tiles: f.tiles.len(),
            aa: super::assemble::frame_accuracy(job, &m, f.index)?,
            ..FrameProgress::default()
        };
        for (i, r) in f.tiles.iter().enumerate() {
            match super::task::tile_state(&states, &pieces, f.index, i) {
                Some(TaskState::Done) => {
                    p.done += 1;
                    done_px += r.area();
                    for name in super::task::task_names(&pieces, f.index, i) {
                        if let Ok((meta, _)) = tile::read(&job.tile_file(&name)) {
                            p.cpu_seconds += meta.cpu_seconds;
                            p.wall_seconds += meta.wall_seconds;
                            p.rays += meta.rays;
                            p.new_values += meta.new_values;
                            p.ambient_seconds += meta.ambient_seconds;
                        }
                    }
                }
                Some(TaskState::Claimed(_)) => {
                    p.claimed += 1;
                    remaining_px += r.area();
                }
                Some(TaskState::Todo) => {
                    p.todo += 1;
                    remaining_px += r.area();
                }
                None => {
                    p.missing += 1;
                    remaining_px += r.area();
                }
            }
        }
        st.tiles += p.tiles;
        st.done += p.done;
        st.frames.push(p);
    }
    for v in pieces.values() {
        st.pieces += v.len();
        st.pieces_done += v.iter().filter(|(_, s)| *s == TaskState::Done).count();
    }
    let mut names: Vec<_> = std::fs::read_dir(job.workers())
        .with_context(|| format!("cannot list {}", job.workers().display()))?
        .flatten()
        .filter_map(|e| e.file_name().to_str().map(String::from))
        .filter(|n| n.ends_with(".json") && !n.starts_with('.'))
        .collect();
    names.sort();
    let now = super::unix_now();
    let a = &mut st.aggregate;
    let mut first = f64::INFINITY;
    let mut last: f64 = 0.0;
    for n in names {
        let Some(r) = read_record(&job.workers().join(&n)) else {
            continue;
        };
        let stem = n.strip_suffix(".json").unwrap_or(&n);
        if let Some(why) = r.implausible(stem) {
            st.bad_heartbeats.push(format!("{n}: {why}"));
            continue;
        }
        a.workers += 1;
        let mut shown = r.state.clone();
        if r.state == "running" || r.state == "idle" {
            let silent = now - r.updated_unix;
            if silent >= m.lease_seconds {
                a.stale += 1;
                shown = "stale".into();
            } else if silent > 3.0 * super::heartbeat::beat_interval(m.lease_seconds).as_secs_f64()
            {
                a.suspect += 1;
                shown = "suspect".into();
            } else {
                a.live += 1;
            }
        }
        st.shown_state.push(shown);
        a.tiles_done += r.tiles_done;
        a.reclaimed += r.reclaimed;
        a.split += r.split;
        a.t_spec += r.t_spec;
        a.t_amb += r.t_amb;
        a.t_idle += r.t_idle;
        a.t_sync += r.t_sync;
        a.cpu_seconds += r.cpu_seconds;
        a.new_values += r.new_values;
        a.shared_in += r.shared_in;
        a.shared_out += r.shared_out;
        a.rejected += r.rejected;
        a.rays += r.rays;
        first = first.min(r.started_unix);
        last = last.max(r.updated_unix);
        st.workers.push(r);
    }
    if first.is_finite() {
        a.wall_seconds = (last - first).max(0.0);
    }
    // Results: of the plan's tiles that are done with their pieces, and of the pieces.
    a.unreported_tiles = ((st.done + st.pieces_done) as u64).saturating_sub(a.tiles_done);
    let busy = a.t_spec + a.t_amb;
    if done_px > 0 && busy > 0.0 {
        let per_px = busy / done_px as f64;
        st.eta_seconds = Some(remaining_px as f64 * per_px / a.live.max(1) as f64);
    }
    Ok(st)
}

/// Add a baseline comparison.
pub fn with_baseline(mut st: JobStatus, base: &JobDir) -> Result<JobStatus> {
    let b = status(base)?;
    // Workers, not incarnations: a restarted worker (same id) counts once.
    let ids: std::collections::HashSet<&str> =
        st.workers.iter().map(|w| w.worker_id.as_str()).collect();
    let n = ids.len().max(1) as f64;
    let w = st.aggregate.wall_seconds;
    let speedup = if w > 0.0 {
        b.aggregate.wall_seconds / w
    } else {
        0.0
    };
    st.baseline = Some(Baseline {
        job: base.root().display().to_string(),
        wall_seconds: b.aggregate.wall_seconds,
        new_values: b.aggregate.new_values,
        speedup,
        efficiency: speedup / n,
        new_values_ratio: if b.aggregate.new_values > 0 {
            st.aggregate.new_values as f64 / b.aggregate.new_values as f64
        } else {
            0.0
        },
    });
    Ok(st)
}

/// Measured per-tile costs of a frame (for `bench/tilesim`): the picture size and every
/// tile with a valid result, with its CPU seconds (wall seconds when CPU time is unknown).
pub fn costs(job: &JobDir, frame: u32) -> Result<serde_json::Value> {
    let m = Manifest::load(job)?;
    let fp = m
        .frame(frame)
        .ok_or_else(|| anyhow::anyhow!("the job has no frame {frame}"))?;
    let states = task::scan(&job.tasks())
        .with_context(|| format!("cannot list {}", job.tasks().display()))?;
    let pieces = super::task::pieces(&states);
    let mut tiles = Vec::new();
    for (i, r) in fp.tiles.iter().enumerate() {
        // A tile with the pieces split off it: their costs together, over the tile.
        let (mut secs, mut values, mut any) = (0.0, 0, false);
        for name in super::task::task_names(&pieces, frame, i) {
            if let Ok((meta, _)) = tile::read(&job.tile_file(&name)) {
                secs += if meta.cpu_seconds > 0.0 {
                    meta.cpu_seconds
                } else {
                    meta.wall_seconds
                };
                values += meta.new_values;
                any = true;
            }
        }
        if any {
            tiles.push(serde_json::json!({
                "x0": r.x0, "y0": r.y0, "w": r.w, "h": r.h, "seconds": secs,
                "new_values": values
            }));
        }
    }
    Ok(serde_json::json!({"width": fp.xres, "height": fp.yres, "tiles": tiles}))
}

/// The human-readable report.
pub fn render_text(st: &JobStatus) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "job {}: {} of {} tiles done", st.job, st.done, st.tiles);
    if st.pieces > 0 {
        let _ = writeln!(
            s,
            "  {} piece(s) split off tiles while they rendered, {} done",
            st.pieces, st.pieces_done
        );
    }
    let missing: usize = st.frames.iter().map(|f| f.missing).sum();
    if missing > 0 {
        let _ = writeln!(
            s,
            "DAMAGED: {missing} tiles of the plan have no task entry in tasks/ (entries were \
             deleted); the job cannot finish as it is"
        );
    }
    for f in &st.frames {
        let _ = writeln!(
            s,
            "  frame {:>5}: {:>5} todo {:>5} claimed {:>5} done (of {}){}{}{}",
            f.frame,
            f.todo,
            f.claimed,
            f.done,
            f.tiles,
            f.aa.map(|aa| format!(", -aa {aa:.4}")).unwrap_or_default(),
            if f.done > 0 {
                format!(
                    ": {:.2} CPU-s, {} new ambient values in {:.2} CPU-s",
                    f.cpu_seconds, f.new_values, f.ambient_seconds
                )
            } else {
                String::new()
            },
            if f.missing > 0 {
                format!(", {} MISSING", f.missing)
            } else {
                String::new()
            }
        );
    }
    if let Some(e) = st.eta_seconds {
        if st.done < st.tiles {
            let _ = writeln!(s, "  ETA about {e:.0} s");
        }
    }
    let a = &st.aggregate;
    let _ = writeln!(
        s,
        "workers: {} seen, {} live, {} suspect, {} stale; {} tiles re-claimed; {:.2} wall-s",
        a.workers, a.live, a.suspect, a.stale, a.reclaimed, a.wall_seconds
    );
    if a.suspect > 0 {
        let _ = writeln!(
            s,
            "  {} worker(s) silent for more than three heartbeats: perhaps dead; their tiles \
             are re-claimed when the lease ({:.0} s) runs out",
            a.suspect, st.lease_seconds
        );
    }
    let _ = writeln!(
        s,
        "  times per render thread: T_spec, T_idle, T_sync in wall-s, T_amb in CPU-s"
    );
    let _ = writeln!(
        s,
        "  {:<28} {:>8} {:>5} {:>8} {:>8} {:>8} {:>8} {:>7} {:>7} {:>7}",
        "owner", "state", "tiles", "T_spec", "T_amb", "T_idle", "T_sync", "new", "in", "out"
    );
    for (i, w) in st.workers.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {:<28} {:>8} {:>5} {:>8.2} {:>8.2} {:>8.2} {:>8.3} {:>7} {:>7} {:>7}",
            w.owner,
            st.shown_state.get(i).unwrap_or(&w.state),
            w.tiles_done,
            w.t_spec,
            w.t_amb,
            w.t_idle,
            w.t_sync,
            w.new_values,
            w.shared_in,
            w.shared_out
        );
    }
    let _ = writeln!(
        s,
        "  {:<28} {:>8} {:>5} {:>8.2} {:>8.2} {:>8.2} {:>8.3} {:>7} {:>7} {:>7}",
        "aggregate",
        "",
        a.tiles_done,
        a.t_spec,
        a.t_amb,
        a.t_idle,
        a.t_sync,
        a.new_values,
        a.shared_in,
        a.shared_out
    );
    if a.unreported_tiles > 0 {
        let _ = writeln!(
            s,
            "  {:<28} {:>8} {:>5}   (done, in no heartbeat yet: a worker died before its next beat)",
            "unreported", "", a.unreported_tiles
        );
    }
    let per_cpu = if a.cpu_seconds > 0.0 {
        format!(", {:.0} rays per CPU-s", a.rays as f64 / a.cpu_seconds)
    } else {
        String::new()
    };
    let _ = writeln!(s, "  {:.2} CPU-s, {} rays{per_cpu}", a.cpu_seconds, a.rays);
    if a.rejected > 0 {
        let _ = writeln!(
            s,
            "  warning: {} invalid ambient records skipped (damaged or foreign logs in amb/)",
            a.rejected
        );
    }
    for b in &st.bad_heartbeats {
        let _ = writeln!(s, "  warning: heartbeat {b}: left out");
    }
    if let Some(b) = &st.baseline {
        let _ = writeln!(
            s,
            "baseline {}: wall {:.2} s; speed-up {:.2}, efficiency {:.0}%, extensive ambient computations ×{:.3}",
            b.job,
            b.wall_seconds,
            b.speedup,
            100.0 * b.efficiency,
            b.new_values_ratio
        );
    }
    s
}
