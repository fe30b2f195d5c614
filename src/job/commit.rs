//! A worker's group commit of finished tiles, off its render threads.
//!
//! Finishing a tile takes a worker one `fsync` of the result's data, one of the `tiles/`
//! directory and three renames (docs/batch.md, "Why each step is safe on NFS"). Each sync
//! waits for the disk or the file server: 4 and 8 ms on this machine's disk, a round trip
//! on NFS. Done on a render thread, that wait is lost to rendering and makes small tiles
//! expensive, so a plan could not have as many as good balance needs.
//!
//! Instead the tile loops hand each finished tile to one committer thread per worker and
//! go on rendering. The committer takes every tile handed over since its last round, writes
//! their temporaries, syncs each one's data, renames them to their names, syncs `tiles/`
//! **once** for the whole batch, and only then marks each task done. When a tile of the
//! batch gave pieces away, `tasks/` is synced first, so that their entries are durable
//! before a result with their holes is. The order of the protocol is unchanged (data
//! durable before the name, the name durable before `done`); a tile waiting in the
//! committer is still claimed, so a worker killed meanwhile loses it to the lease like a
//! tile it was rendering. If a result cannot be written (a full disk),
//! its tile is released to `todo`, the worker's loops stop after their tile, and the worker
//! exits with the error.

use super::heartbeat::Counters;
use super::task;
use super::tile::{ResultDir, TileMeta};
use anyhow::{anyhow, Result};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::Receiver;

/// A rendered tile on its way to the job directory.
pub struct Finished {
    /// The task name.
    pub name: String,
    /// The result's metadata.
    pub meta: TileMeta,
    /// Its pixels.
    pub pixels: Vec<[f32; 3]>,
    /// It gave pieces away while it rendered: their entries in `tasks/` are made durable
    /// before its result is written ([`super::split`]).
    pub gave_pieces: bool,
}

/// Where the committer writes and whom it tells.
pub struct CommitTarget<'a> {
    /// `tasks/`.
    pub tasks_dir: &'a Path,
    /// The worker's owner name.
    pub owner: &'a str,
    /// The worker's counters (tiles done).
    pub counters: &'a Counters,
    /// Print one line per tile.
    pub verbose: bool,
    /// Set when a result could not be written: the tile loops stop after their tile.
    pub stop: &'a AtomicBool,
    /// Tiles handed over and not yet committed: lowered as each is done or failed.
    pub pending: &'a AtomicUsize,
}

/// Commit tiles from `rx` in batches until every sender is gone; the first error.
pub fn commit_loop(rx: Receiver<Finished>, results: ResultDir, t: CommitTarget) -> Result<()> {
    let mut first_error: Option<anyhow::Error> = None;
    let fail = |name: &str, e: anyhow::Error, first: &mut Option<anyhow::Error>| {
        let _ = task::release(t.tasks_dir, name, t.owner);
        t.stop.store(true, Ordering::Relaxed);
        if first.is_none() {
            *first = Some(e.context(format!("tile {name} released for another worker")));
        }
    };
    while let Ok(one) = rx.recv() {
        let mut batch = vec![one];
        batch.extend(rx.try_iter());
        let batch_len = batch.len();
        // A result with holes is written only once the pieces that fill them are durable.
        if batch.iter().any(|f| f.gave_pieces) {
            if let Ok(d) = crate::safefile::open_dir(t.tasks_dir) {
                let _ = d.sync_all();
            }
        }
        let mut staged = Vec::with_capacity(batch.len());
        let mut kept = Vec::with_capacity(batch.len());
        for f in batch {
            match results.stage(&format!("{}.tile", f.name), t.owner, &f.meta, &f.pixels) {
                Ok(s) => {
                    staged.push(s);
                    kept.push(f);
                }
                Err(e) => fail(&f.name, e, &mut first_error),
            }
        }
        t.pending
            .fetch_sub(batch_len - kept.len(), Ordering::SeqCst);
        for (f, r) in kept.into_iter().zip(results.commit(staged)) {
            if let Err(e) = r {
                fail(&f.name, e, &mut first_error);
                t.pending.fetch_sub(1, Ordering::SeqCst);
                continue;
            }
            match task::complete(t.tasks_dir, &f.name, t.owner) {
                Ok(completed) => {
                    t.counters.tiles_done.fetch_add(1, Ordering::Relaxed);
                    if t.verbose {
                        report(t.owner, &f.meta, completed);
                    }
                }
                Err(e) => {
                    t.stop.store(true, Ordering::Relaxed);
                    first_error.get_or_insert_with(|| {
                        anyhow!(
                            "cannot mark {} done in {}: {e}",
                            f.name,
                            t.tasks_dir.display()
                        )
                    });
                }
            }
            t.pending.fetch_sub(1, Ordering::SeqCst);
        }
    }
    first_error.map_or(Ok(()), Err)
}

/// One line about a finished tile.
fn report(owner: &str, meta: &TileMeta, completed: bool) {
    eprintln!(
        "tpiece {owner}: {} {}x{} at {},{} in {:.2}s{}{}",
        meta.task,
        meta.w,
        meta.h,
        meta.x0,
        meta.y0,
        meta.wall_seconds,
        if meta.new_values > 0 {
            format!(", {} new ambient values", meta.new_values)
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
