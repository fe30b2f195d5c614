//! Pieces: parts of a tile split off while it renders (docs/batch.md, "Splitting a tile in
//! progress").
//!
//! When nothing is left to claim and a worker's tile still has much to render, the worker
//! gives part of what it has not started away as a new task, a *piece*, and renders the rest.
//! A piece is named after its tile and its own rectangle,
//! `f<frame>-t<tile>-r<x0>-<y0>-<w>-<h>` (five digits each), so any process reads its
//! rectangle from the name alone, and it goes through the same states as a tile
//! (`todo` → `claim.<owner>` → `done`; [`super::task`]). A piece can be split again.
//!
//! Every piece lies inside its tile, and a piece split off lies inside the rectangle of the
//! task it was split from; its owner renders that task's rectangle except the pieces it
//! gave away (their pixels stay zero in its result). So at every pixel the task of the
//! smallest area covering it has rendered it: [`assemble_order`] pastes a tile's results
//! largest first. A worker that takes over a task renders all of its rectangle (pieces a
//! dead owner split off are rendered twice, never lost).

use super::plan::TileRect;
use super::task_name;

/// A task's identity: its frame and tile, and for a piece its rectangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TaskId {
    /// Frame number.
    pub frame: u32,
    /// Tile index in the frame's plan.
    pub tile: usize,
    /// A piece's rectangle (None for the tile itself).
    pub piece: Option<TileRect>,
}

impl TaskId {
    /// The task name.
    pub fn name(&self) -> String {
        match &self.piece {
            None => task_name(self.frame, self.tile),
            Some(r) => piece_name(self.frame, self.tile, r),
        }
    }
}

/// The name of a piece of tile `tile` of frame `frame` covering `r`.
pub fn piece_name(frame: u32, tile: usize, r: &TileRect) -> String {
    format!(
        "{}-r{:05}-{:05}-{:05}-{:05}",
        task_name(frame, tile),
        r.x0,
        r.y0,
        r.w,
        r.h
    )
}

fn five_digits(s: &str) -> Option<usize> {
    (s.len() == 5 && s.bytes().all(|b| b.is_ascii_digit()))
        .then(|| s.parse().ok())
        .flatten()
}

/// Parse a task name (a tile's or a piece's). The rectangle of a piece is checked for size
/// (not empty, within [`super::MAX_RES`]), not against the plan: see [`in_tile`].
pub fn parse(name: &str) -> Option<TaskId> {
    let (tile_part, rest) = match name.get(13..) {
        Some(rest) if !rest.is_empty() => (&name[..13], Some(rest)),
        _ => (name, None),
    };
    let (frame, tile) = super::parse_task_name(tile_part)?;
    let piece = match rest {
        None => None,
        Some(r) => {
            let nums: Vec<&str> = r.strip_prefix("-r")?.split('-').collect();
            let [x0, y0, w, h] = nums[..] else {
                return None;
            };
            let r = TileRect {
                x0: five_digits(x0)?,
                y0: five_digits(y0)?,
                w: five_digits(w)?,
                h: five_digits(h)?,
            };
            let max = super::MAX_RES;
            if r.w == 0 || r.h == 0 || r.x0 + r.w > max || r.y0 + r.h > max {
                return None;
            }
            Some(r)
        }
    };
    Some(TaskId { frame, tile, piece })
}

/// Whether piece rectangle `p` lies inside tile `t` and is smaller.
pub fn in_tile(p: &TileRect, t: &TileRect) -> bool {
    p.x0 >= t.x0
        && p.y0 >= t.y0
        && p.x0 + p.w <= t.x0 + t.w
        && p.y0 + p.h <= t.y0 + t.h
        && p.area() < t.area()
}

/// The order in which a tile's results are pasted: the tile, then its pieces (those inside
/// it) by decreasing area, so that each pixel ends with the result of the smallest task
/// covering it. Pieces outside the tile are left out.
pub fn assemble_order(tile: &TileRect, pieces: &[TileRect]) -> Vec<TileRect> {
    let mut v: Vec<TileRect> = pieces
        .iter()
        .filter(|p| in_tile(p, tile))
        .copied()
        .collect();
    v.sort_by_key(|p| (std::cmp::Reverse(p.area()), p.y0, p.x0, p.h, p.w));
    v.insert(0, *tile);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(x0: usize, y0: usize, w: usize, h: usize) -> TileRect {
        TileRect { x0, y0, w, h }
    }

    #[test]
    fn names_round_trip_and_junk_is_refused() {
        let p = r(12, 30, 96, 18);
        let n = piece_name(3, 17, &p);
        assert_eq!(n, "f00003-t00017-r00012-00030-00096-00018");
        assert_eq!(
            parse(&n),
            Some(TaskId {
                frame: 3,
                tile: 17,
                piece: Some(p)
            })
        );
        assert_eq!(parse(&n).unwrap().name(), n);
        assert_eq!(
            parse("f00003-t00017"),
            Some(TaskId {
                frame: 3,
                tile: 17,
                piece: None
            })
        );
        for bad in [
            "f00003-t00017-",
            "f00003-t00017-r00012-00030-00096",
            "f00003-t00017-r00012-00030-00096-00018-00001",
            "f00003-t00017-r00012-00030-00096-00000",
            "f00003-t00017-r00012-00030-0096-00018",
            "f00003-t00017-r00012-00030-+0096-00018",
            "f00003-t00017-x00012-00030-00096-00018",
            "f00003-t00017-r99999-00030-00096-00018",
            "f00003-t0017-r00012-00030-00096-00018",
        ] {
            assert_eq!(parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn pieces_paste_largest_first_and_outsiders_are_dropped() {
        let t = r(0, 0, 24, 24);
        let order = assemble_order(
            &t,
            &[
                r(12, 12, 12, 6),
                r(0, 12, 24, 12),
                r(30, 0, 6, 6),
                r(0, 0, 24, 24),
            ],
        );
        assert_eq!(order, vec![t, r(0, 12, 24, 12), r(12, 12, 12, 6)]);
    }
}
