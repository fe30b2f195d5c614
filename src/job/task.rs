//! Task states and their transitions, each one `rename(2)` inside `tasks/`:
//!
//! ```text
//! <task>.todo ──claim──▶ <task>.claim.<owner> ──complete──▶ <task>.done
//!                              │        ▲
//!                              └reclaim─┘  (stale lease, or an earlier incarnation of the
//!                                           same worker id; the new owner's name)
//! <task>.claim.<owner> ──release──▶ <task>.todo   (the owner could not write its result)
//! ```
//!
//! Of several processes renaming the same entry exactly one succeeds; the others get
//! `ENOENT`. On NFS a retransmitted rename can report `ENOENT` although it succeeded, so a
//! failed rename is followed by a check of whether the target name exists.

use super::check_owner;
use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};

/// The state of a task as read from its entry name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TaskState {
    /// Not claimed.
    Todo,
    /// Claimed by an owner.
    Claimed(String),
    /// Finished.
    Done,
}

/// Parse a `tasks/` entry name (a tile's or a piece's, [`super::piece`]) into (task, state);
/// None for anything else (temporary files, hand-made junk).
pub fn parse_entry(name: &str) -> Option<(String, TaskState)> {
    let (task, rest) = name.split_once('.')?;
    super::piece::parse(task)?;
    let state = match rest {
        "todo" => TaskState::Todo,
        "done" => TaskState::Done,
        _ => {
            let owner = rest.strip_prefix("claim.")?;
            check_owner(owner).ok()?;
            TaskState::Claimed(owner.to_string())
        }
    };
    Some((task.to_string(), state))
}

/// The entry path of a task in a state.
pub fn entry(tasks: &Path, task: &str, state: &TaskState) -> PathBuf {
    match state {
        TaskState::Todo => tasks.join(format!("{task}.todo")),
        TaskState::Done => tasks.join(format!("{task}.done")),
        TaskState::Claimed(o) => tasks.join(format!("{task}.claim.{o}")),
    }
}

/// Rename `from` to `to`; Ok(true) if this call moved it, Ok(false) if `from` was gone (someone
/// else won), errors otherwise.
fn rename_once(from: &Path, to: &Path) -> io::Result<bool> {
    match std::fs::rename(from, to) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            // NFS: a retried rename may fail although the first attempt succeeded.
            Ok(to.exists() && !from.exists())
        }
        Err(e) => Err(e),
    }
}

/// Try to claim a todo task; true when this process now owns it.
pub fn claim(tasks: &Path, task: &str, owner: &str) -> io::Result<bool> {
    rename_once(
        &entry(tasks, task, &TaskState::Todo),
        &entry(tasks, task, &TaskState::Claimed(owner.into())),
    )
}

/// Take over a task claimed by `old` (stale, or our own earlier incarnation).
pub fn reclaim(tasks: &Path, task: &str, old: &str, owner: &str) -> io::Result<bool> {
    rename_once(
        &entry(tasks, task, &TaskState::Claimed(old.into())),
        &entry(tasks, task, &TaskState::Claimed(owner.into())),
    )
}

/// Mark an owned task done. False when it was re-claimed meanwhile (its result, already
/// written, is still valid: results are idempotent).
pub fn complete(tasks: &Path, task: &str, owner: &str) -> io::Result<bool> {
    rename_once(
        &entry(tasks, task, &TaskState::Claimed(owner.into())),
        &entry(tasks, task, &TaskState::Done),
    )
}

/// Give an owned task back (for example when its result could not be written).
pub fn release(tasks: &Path, task: &str, owner: &str) -> io::Result<bool> {
    rename_once(
        &entry(tasks, task, &TaskState::Claimed(owner.into())),
        &entry(tasks, task, &TaskState::Todo),
    )
}

/// A snapshot of every task's state. A task seen in two states (a rename observed halfway
/// through a directory listing) keeps the most advanced one: done > claimed > todo.
pub fn scan(tasks: &Path) -> io::Result<HashMap<String, TaskState>> {
    let mut out: HashMap<String, TaskState> = HashMap::new();
    for e in std::fs::read_dir(tasks)? {
        let e = e?;
        let name = e.file_name();
        let Some((task, state)) = name.to_str().and_then(parse_entry) else {
            continue;
        };
        let rank = |s: &TaskState| match s {
            TaskState::Todo => 0,
            TaskState::Claimed(_) => 1,
            TaskState::Done => 2,
        };
        match out.get(&task) {
            Some(old) if rank(old) >= rank(&state) => {}
            _ => {
                out.insert(task, state);
            }
        }
    }
    Ok(out)
}

/// A tile's pieces in a snapshot: by (frame, tile), each piece's rectangle and state.
pub type Pieces = HashMap<(u32, usize), Vec<(super::plan::TileRect, TaskState)>>;

/// The pieces of every tile in a snapshot of `tasks/` ([`super::task::scan`]): by (frame,
/// tile), each piece's rectangle and state, the rectangles in name order.
pub fn pieces(states: &HashMap<String, TaskState>) -> Pieces {
    let mut out: Pieces = HashMap::new();
    for (name, st) in states {
        if let Some(super::piece::TaskId {
            frame,
            tile,
            piece: Some(r),
        }) = super::piece::parse(name)
        {
            out.entry((frame, tile)).or_default().push((r, st.clone()));
        }
    }
    for v in out.values_mut() {
        v.sort_by_key(|(r, _)| (r.y0, r.x0, r.h, r.w));
    }
    out
}

/// The names of tile `tile` of frame `frame` and of the pieces split off it.
pub fn task_names(pieces: &Pieces, frame: u32, tile: usize) -> Vec<String> {
    let mut v = vec![super::task_name(frame, tile)];
    if let Some(ps) = pieces.get(&(frame, tile)) {
        v.extend(
            ps.iter()
                .map(|(r, _)| super::piece::piece_name(frame, tile, r)),
        );
    }
    v
}

/// The state of a tile with its pieces: done when the tile and every piece are done,
/// claimed when any of them is claimed (by the first such owner), else the tile's own.
pub fn tile_state(
    states: &HashMap<String, TaskState>,
    pieces: &Pieces,
    frame: u32,
    tile: usize,
) -> Option<TaskState> {
    let own = states.get(&super::task_name(frame, tile))?.clone();
    let mut claimed = None;
    let mut all_done = own == TaskState::Done;
    for (_, st) in pieces.get(&(frame, tile)).map_or(&[][..], |v| &v[..]) {
        match st {
            TaskState::Done => {}
            TaskState::Claimed(o) => {
                all_done = false;
                claimed.get_or_insert_with(|| o.clone());
            }
            TaskState::Todo => all_done = false,
        }
    }
    Some(if all_done {
        TaskState::Done
    } else if let TaskState::Claimed(o) = own {
        TaskState::Claimed(o)
    } else if let Some(o) = claimed {
        TaskState::Claimed(o)
    } else {
        own
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_parse() {
        assert_eq!(
            parse_entry("f00000-t00001.todo"),
            Some(("f00000-t00001".into(), TaskState::Todo))
        );
        assert_eq!(
            parse_entry("f00000-t00001.claim.w-1.0000abcd"),
            Some((
                "f00000-t00001".into(),
                TaskState::Claimed("w-1.0000abcd".into())
            ))
        );
        for bad in [
            "f00000-t00001.claim.../x.0000abcd",
            "f00000-t00001.claim.w",
            "x.todo",
            ".f00000-t00001.todo.tmp",
            "f00000-t00001",
        ] {
            assert_eq!(parse_entry(bad), None, "{bad}");
        }
    }

    #[test]
    fn tile_state_needs_every_piece() {
        let mut st = HashMap::new();
        st.insert("f00000-t00001".to_string(), TaskState::Done);
        let p = super::super::piece::piece_name(
            0,
            1,
            &super::super::plan::TileRect {
                x0: 0,
                y0: 6,
                w: 12,
                h: 6,
            },
        );
        st.insert(p.clone(), TaskState::Claimed("w.0000abcd".into()));
        let pc = pieces(&st);
        assert_eq!(
            tile_state(&st, &pc, 0, 1),
            Some(TaskState::Claimed("w.0000abcd".into()))
        );
        st.insert(p, TaskState::Done);
        let pc = pieces(&st);
        assert_eq!(tile_state(&st, &pc, 0, 1), Some(TaskState::Done));
        assert_eq!(tile_state(&st, &pc, 0, 2), None);
    }

    #[test]
    fn claim_race_has_one_winner() {
        let d = tempfile::tempdir().unwrap();
        for round in 0..50 {
            let task = super::super::task_name(0, round);
            std::fs::File::create(entry(d.path(), &task, &TaskState::Todo)).unwrap();
            let wins = std::sync::atomic::AtomicUsize::new(0);
            std::thread::scope(|s| {
                for t in 0..8 {
                    let (task, wins, dir) = (&task, &wins, d.path());
                    s.spawn(move || {
                        let owner = format!("w{t}.{:08x}", t);
                        if claim(dir, task, &owner).unwrap() {
                            wins.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                        }
                    });
                }
            });
            assert_eq!(wins.into_inner(), 1);
            // Reclaim races: exactly one of many takes over.
            let st = scan(d.path()).unwrap();
            let TaskState::Claimed(old) = st[&task].clone() else {
                panic!()
            };
            let wins = std::sync::atomic::AtomicUsize::new(0);
            std::thread::scope(|s| {
                for t in 0..8 {
                    let (task, wins, dir, old) = (&task, &wins, d.path(), &old);
                    s.spawn(move || {
                        let owner = format!("r{t}.{:08x}", t);
                        if reclaim(dir, task, old, &owner).unwrap() {
                            wins.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                        }
                    });
                }
            });
            assert_eq!(wins.into_inner(), 1);
        }
        let st = scan(d.path()).unwrap();
        assert_eq!(st.len(), 50);
        assert!(st
            .values()
            .all(|s| matches!(s, TaskState::Claimed(o) if o.starts_with('r'))));
    }
}
