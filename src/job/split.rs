//! When a worker splits the task it renders ([`super::piece`]; docs/batch.md, "Splitting a
//! tile in progress").
//!
//! Before each cell the renderer asks [`Splitter::hook`]. At most every [`CHECK_SECONDS`] of
//! rendering it looks whether anything is left to claim: the plan's last task still `todo`
//! (one `stat`), else any `todo` entry in `tasks/` (one listing). When nothing is, and what is
//! left of its task, estimated from its seconds per cell so far, is at least twice
//! [`MIN_PIECE_SECONDS`], it gives away half of what is left: the lower half of the bands
//! below the one in progress when there are two or more, else the right half of the cells
//! left in the band in progress (and below it). The piece is made once (its `.made` marker
//! created with `O_EXCL`), then its `todo` entry, before the renderer skips those cells (the
//! worker's committer syncs `tasks/` before it writes the task's result); when that fails
//! (another process made the same piece, a full disk), or when this worker no longer holds
//! the task (it was taken over after the lease), nothing is cut.
//!
//! While another tile loop of the same worker waits for work ([`super::siblings`]), the
//! renderer looks every [`SIBLING_CHECK_SECONDS`] instead, without reading `tasks/` (the
//! waiting loop found nothing to claim there), splits down to pieces of
//! [`SIBLING_MIN_PIECE_SECONDS`], and wakes the waiting loops when it has made one.

use super::piece::piece_name;
use super::plan::TileRect;
use crate::render::splitting::{Cut, SplitPoint};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Seconds of rendering between two looks at `tasks/`.
pub const CHECK_SECONDS: f64 = 0.05;

/// The least estimated cost of each part of a split, seconds: a piece costs a claim, a
/// result and an idle worker's poll (20–100 ms) before it starts.
pub const MIN_PIECE_SECONDS: f64 = 0.05;

/// Seconds of rendering between two looks at `tasks/` while a sibling loop of this worker
/// waits for work ([`super::siblings`]).
pub const SIBLING_CHECK_SECONDS: f64 = 0.001;

/// The least estimated cost of each part of a split while a sibling loop waits: the sibling
/// is woken at once, so a piece costs two creates, a claim and a result (about 1 ms).
/// Replayed on 16 loops a worker (`bench/tilesim --sweep --loops 16 --ps 1 --local`), 1 ms
/// looks and 2 ms pieces kept frames of 0.1–10 CPU-s within 5% of their best plan in 3× as
/// many cases as 2 ms and 10 ms did, with three tiles a loop.
pub const SIBLING_MIN_PIECE_SECONDS: f64 = 0.002;

/// Test builds with `TESSERA_FAULT_SPLIT_EAGER`: the fewest cells left that are split.
const EAGER_MIN_CELLS: usize = 16;

/// One task's splitting while it renders.
pub struct Splitter<'a> {
    tasks: PathBuf,
    /// The `todo` entry of the plan's last task.
    last_todo: PathBuf,
    /// This task's claim entry (gone when another worker took the task over).
    claim: PathBuf,
    frame: u32,
    tile: usize,
    start: Instant,
    last_look: Instant,
    /// Test builds: split whenever nothing is left to claim and at least
    /// [`EAGER_MIN_CELLS`] cells are, whatever the estimate (`TESSERA_FAULT_SPLIT_EAGER`).
    eager: bool,
    /// The worker's other tile loops, when it has any to tell.
    siblings: Option<&'a super::siblings::Siblings>,
    /// Names of the pieces made.
    pub made: Vec<String>,
}

impl<'a> Splitter<'a> {
    /// A splitter for task `task` of tile `tile` of frame `frame`, claimed by `owner`;
    /// `last` is the name of the plan's last task.
    pub fn new(
        tasks: &Path,
        (task, owner): (&str, &str),
        last: &str,
        frame: u32,
        tile: usize,
    ) -> Splitter<'a> {
        let now = Instant::now();
        Splitter {
            tasks: tasks.to_path_buf(),
            last_todo: tasks.join(format!("{last}.todo")),
            claim: super::task::entry(tasks, task, &super::task::TaskState::Claimed(owner.into())),
            frame,
            tile,
            start: now,
            last_look: now,
            eager: crate::fault::injected("SPLIT_EAGER"),
            siblings: None,
            made: Vec::new(),
        }
    }

    /// Split sooner and finer while one of the worker's other loops waits, and wake them
    /// when a piece is made.
    pub fn with_siblings(mut self, siblings: &'a super::siblings::Siblings) -> Splitter<'a> {
        self.siblings = Some(siblings);
        self
    }

    /// The renderer's hook: a cut when part of the task was given away as a new piece.
    pub fn hook(&mut self, at: &SplitPoint) -> Option<Cut> {
        if at.done == 0 {
            return None;
        }
        if self.eager && at.cells_left() < EAGER_MIN_CELLS {
            return None;
        }
        // A sibling loop waits only when its last look at `tasks/` found nothing to claim.
        let waiting = self.siblings.is_some_and(|s| s.idle() > 0);
        if !self.eager {
            let (gap, least) = if waiting {
                (SIBLING_CHECK_SECONDS, SIBLING_MIN_PIECE_SECONDS)
            } else {
                (CHECK_SECONDS, MIN_PIECE_SECONDS)
            };
            if self.last_look.elapsed().as_secs_f64() < gap {
                return None;
            }
            self.last_look = Instant::now();
            let left = self.start.elapsed().as_secs_f64() / at.done as f64 * at.cells_left() as f64;
            if left < 2.0 * least {
                return None;
            }
        }
        let (cut, rect) = choose(at)?;
        if !waiting && !self.nothing_to_claim() {
            return None;
        }
        // One piece for each waiting sibling, whichever loops make them (asked before any
        // file is looked at: while the pieces are on their way, the other loops read none).
        let sibling = self.siblings.filter(|_| waiting);
        if sibling.is_some_and(|s| !s.offer()) {
            return None;
        }
        // Only the task's owner splits it (a worker resumed after its lease ran out does not).
        let name = piece_name(self.frame, self.tile, &rect);
        if !self.claim.exists() || !create_todo(&self.tasks, &name) {
            if let Some(s) = sibling {
                s.withdraw();
            }
            return None;
        }
        self.made.push(name);
        if let Some(s) = self.siblings {
            s.made_piece();
        }
        Some(cut)
    }

    /// Whether no `todo` entry is left in `tasks/`.
    fn nothing_to_claim(&self) -> bool {
        if self.last_todo.exists() {
            return false;
        }
        let Ok(dir) = std::fs::read_dir(&self.tasks) else {
            return false;
        };
        !dir.flatten().any(|e| {
            e.file_name()
                .to_str()
                .is_some_and(|n| n.ends_with(".todo") && !n.starts_with('.'))
        })
    }
}

/// The cut for what is left at `at`, and the piece it makes: half the bands below the one in
/// progress when there are two or more, else half the cells left in this band (with the
/// same columns below).
pub fn choose(at: &SplitPoint) -> Option<(Cut, TileRect)> {
    let rows = at.rows_left();
    if rows.len() >= 2 {
        let k = rows[rows.len() / 2];
        let rect = TileRect {
            x0: at.x0,
            y0: k,
            w: at.x1 - at.x0,
            h: at.y1 - k,
        };
        return Some((Cut::Rows(k), rect));
    }
    let cols = at.columns_left();
    if cols.len() < 2 {
        return None;
    }
    let q = cols[cols.len() / 2];
    let rect = TileRect {
        x0: q,
        y0: at.band.0,
        w: at.x1 - q,
        h: at.y1 - at.band.0,
    };
    Some((Cut::Cols(q), rect))
}

/// Create the piece `name`: first its marker `tasks/<name>.made` (`O_EXCL`: each piece is
/// made once, whatever state it has reached since, by whichever process), then its
/// `tasks/<name>.todo`; whether it was made. Other processes see both at once; the worker's
/// committer syncs `tasks/` before it writes the result of the task the piece came from
/// (`super::commit`), so the render thread does not wait for the disk.
fn create_todo(tasks: &Path, name: &str) -> bool {
    let create = |suffix: &str| {
        crate::safefile::shared_write()
            .create_new(true)
            .open(tasks.join(format!("{name}.{suffix}")))
    };
    create(MADE).is_ok() && create("todo").is_ok()
}

/// The suffix of a piece's marker in `tasks/` (not a state: listings skip it).
pub const MADE: &str = "made";

#[cfg(test)]
mod tests {
    use super::*;

    fn at(band: (usize, usize), next_x: usize, x1: usize, y1: usize) -> SplitPoint {
        SplitPoint {
            x0: 2,
            x1,
            y1,
            band,
            next_x,
            cell: 6,
            done: 1,
        }
    }

    /// A task `f0000-t0000` claimed by `me` in a fresh `tasks/`, with the plan's last task
    /// still `todo`.
    fn claimed_task() -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let tasks = dir.path().join("tasks");
        std::fs::create_dir(&tasks).unwrap();
        std::fs::write(tasks.join("f0000-t0000.claim.me"), b"").unwrap();
        std::fs::write(tasks.join("f0000-t0001.todo"), b"").unwrap();
        (dir, tasks)
    }

    #[test]
    fn a_waiting_sibling_makes_the_owner_split_soon_and_finely() {
        let (_dir, tasks) = claimed_task();
        // 40 bands of 6 rows, one done after 3–6 ms: an estimate of 0.12–0.24 s left, above
        // the sibling threshold of 2 × 10 ms; without a waiting sibling the owner does not
        // look before 50 ms.
        let point = SplitPoint {
            x0: 0,
            x1: 6,
            y1: 246,
            band: (0, 6),
            next_x: 6,
            cell: 6,
            done: 1,
        };
        let siblings = super::super::siblings::Siblings::default();
        let mut alone = Splitter::new(&tasks, ("f0000-t0000", "me"), "f0000-t0001", 0, 0);
        let mut helped = Splitter::new(&tasks, ("f0000-t0000", "me"), "f0000-t0001", 0, 0)
            .with_siblings(&siblings);
        std::thread::sleep(std::time::Duration::from_millis(3));
        assert_eq!(alone.hook(&point), None, "no look before 50 ms");
        assert_eq!(helped.hook(&point), None, "no sibling waits");
        siblings.begin_idle();
        let before = siblings.pieces();
        std::thread::sleep(std::time::Duration::from_millis(3));
        let cut = helped.hook(&point);
        // The plan's last task is still `todo` in `tasks/`: only the waiting sibling's word
        // that nothing is left to claim lets the owner split.
        assert_eq!(cut, Some(Cut::Rows(126)), "{:?}", helped.made);
        assert_eq!(helped.made.len(), 1);
        assert!(tasks.join(format!("{}.todo", helped.made[0])).is_file());
        assert_eq!(
            siblings.pieces(),
            before + 1,
            "the waiting loops were woken"
        );
        // Once the claim is gone (another worker took the task over), nothing is cut.
        std::fs::remove_file(tasks.join("f0000-t0000.claim.me")).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(3));
        assert_eq!(helped.hook(&point), None);
    }

    #[test]
    fn bands_go_first_then_cells() {
        // Region [2, 40) × [3, 40): band [6, 12) in progress, bands 12, 18, 24, 30, 36 left.
        let p = at((6, 12), 14, 40, 40);
        assert_eq!(p.rows_left(), vec![12, 18, 24, 30, 36]);
        let (cut, r) = choose(&p).unwrap();
        assert_eq!(cut, Cut::Rows(24));
        assert_eq!(
            r,
            TileRect {
                x0: 2,
                y0: 24,
                w: 38,
                h: 16
            }
        );
        // The last band in progress: the cells from 14 are 14, 18, 24, 30, 36.
        let p = at((36, 40), 14, 40, 40);
        assert_eq!(p.columns_left(), vec![14, 18, 24, 30, 36]);
        assert_eq!(p.cells_left(), 5);
        let (cut, r) = choose(&p).unwrap();
        assert_eq!(cut, Cut::Cols(24));
        assert_eq!(
            r,
            TileRect {
                x0: 24,
                y0: 36,
                w: 16,
                h: 4
            }
        );
        // One band below: cells of this band and the band below.
        let p = at((30, 36), 30, 40, 40);
        assert_eq!(p.cells_left(), 2 + 7);
        assert_eq!(choose(&p).unwrap().0, Cut::Cols(36));
        // One cell left: nothing to give.
        assert_eq!(choose(&at((36, 40), 36, 40, 40)), None);
    }
}
