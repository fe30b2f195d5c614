//! `tilesim --split`: the replay of a plan when a worker may split the tile it renders.
//!
//! The model of `tpiece`'s splitting (docs/batch.md, "Splitting a tile in progress"):
//! - workers take pieces in order: the plan's tiles, then the pieces split off, first made
//!   first taken;
//! - a piece is rendered cell by cell in reading order (bands of `cell` rows, each band's
//!   cells left to right), each cell costing what the cost map says;
//! - while it renders, its owner looks every `check` seconds whether anything is left to
//!   claim; when nothing is, and its estimate of what is left of its piece (seconds per
//!   cell so far × cells left) is at least twice `min_piece`, it gives away, at the end of
//!   the cell in progress, the lower half of the bands below the next cell's when there are
//!   two or more, else the right half of the cells left in that band with the same columns
//!   below (`job::split::choose`);
//! - an idle worker sees a new piece `wake` seconds after it was made (its poll); the
//!   owner, when it ends its part first, takes the piece itself;
//! - every piece costs `sync` seconds more (claim, result write);
//! - with `loops` > 1, workers are tile loops of processes of `loops` each
//!   (`job::siblings`): when a loop finds nothing to claim, each busy sibling looks again
//!   `local.0` seconds later and splits down to pieces of `local.1` seconds, and an idle
//!   sibling takes a piece `local.2` seconds after it was made (its wake-up), where loops
//!   of other processes wait for their poll (`wake`).

use super::CostMap;
use std::cmp::Ordering;
use std::collections::{BinaryHeap, VecDeque};
use tessera::job::plan::TileRect;

/// The splitting rule's settings.
#[derive(Clone, Copy, Debug)]
pub struct SplitParams {
    /// Seconds between an owner's looks at the task list.
    pub check: f64,
    /// The least estimated cost of each half of a split.
    pub min_piece: f64,
    /// Seconds before an idle worker sees a new piece.
    pub wake: f64,
    /// Rows of a band of sampling cells (`cell_size(-ps)`).
    pub cell: usize,
    /// Tile loops per worker process (1: single-thread processes).
    pub loops: usize,
    /// For a process's own loops: the delay before a busy loop sees an idle sibling, the
    /// least piece, and the delay before a woken sibling takes a piece.
    pub local: (f64, f64, f64),
}

/// A cell of a piece's work in render order: its pixels and cost.
#[derive(Clone, Copy, Debug)]
struct Cell {
    x0: usize,
    y0: usize,
    cost: f64,
}

/// A piece: its cells in render order (bands top to bottom, cells left to right).
#[derive(Clone, Debug)]
struct Piece {
    cells: Vec<Cell>,
}

impl Piece {
    fn cost(&self) -> f64 {
        self.cells.iter().map(|c| c.cost).sum()
    }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Kind {
    Finish,
    Check,
    /// A busy loop's look after a sibling found nothing to claim.
    LocalCheck,
    Wake,
}

#[derive(PartialEq)]
struct Ev(f64, u64, Kind, usize, u64);

impl Eq for Ev {}
impl Ord for Ev {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}
impl PartialOrd for Ev {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

struct Busy {
    piece: Piece,
    start: f64,
}

/// The cells of `[x0, x1) × [a, b)` in render order.
fn cells_of(
    map: &CostMap,
    scale: f64,
    cell: usize,
    (x0, x1, a, b): (usize, usize, usize, usize),
) -> Vec<Cell> {
    let mut out = Vec::new();
    let mut y = a;
    while y < b {
        let y1 = ((y / cell + 1) * cell).min(b);
        let mut x = x0;
        while x < x1 {
            let xe = ((x / cell + 1) * cell).min(x1);
            let cost = map.cost(&TileRect {
                x0: x,
                y0: y,
                w: xe - x,
                h: y1 - y,
            }) * scale;
            out.push(Cell { x0: x, y0: y, cost });
            x = xe;
        }
        y = y1;
    }
    out
}

struct Sim {
    sync: f64,
    sp: SplitParams,
    todo: VecDeque<Piece>,
    busy: Vec<Option<Busy>>,
    gen: Vec<u64>,
    cgen: Vec<u64>,
    heap: BinaryHeap<Ev>,
    seq: u64,
    makespan: f64,
}

impl Sim {
    fn push(&mut self, t: f64, k: Kind, w: usize) {
        self.seq += 1;
        // A split changes when a piece ends (`gen`), not when its owner looks (`cgen`).
        let g = match k {
            Kind::Finish => self.gen[w],
            _ => self.cgen[w],
        };
        self.heap.push(Ev(t, self.seq, k, w, g));
    }

    /// The tile loops of worker `w`'s process (`w` among them).
    fn siblings(&self, w: usize) -> std::ops::Range<usize> {
        let n = self.sp.loops.max(1);
        let base = w / n * n;
        base..(base + n).min(self.busy.len())
    }

    fn start(&mut self, w: usize, t: f64) {
        let Some(p) = self.todo.pop_front() else {
            self.busy[w] = None;
            for s in self.siblings(w) {
                if self.busy[s].is_some() {
                    self.push(t + self.sp.local.0, Kind::LocalCheck, s);
                }
            }
            return;
        };
        self.gen[w] += 1;
        self.cgen[w] += 1;
        let end = t + p.cost() + self.sync;
        self.busy[w] = Some(Busy { piece: p, start: t });
        self.push(end, Kind::Finish, w);
        self.push(t + self.sp.check, Kind::Check, w);
        if self.siblings(w).any(|s| self.busy[s].is_none()) {
            self.push(t + self.sp.local.0, Kind::LocalCheck, w);
        }
    }

    /// Owner `w`'s look at `t`: its periodic one, or (`local`) one after a sibling went idle.
    fn check(&mut self, w: usize, t: f64, local: bool) {
        let waiting = self.siblings(w).any(|s| self.busy[s].is_none());
        if self.todo.is_empty() && (waiting || !local) {
            let least = if waiting {
                self.sp.local.1
            } else {
                self.sp.min_piece
            };
            if let Some((mine, child)) = self.split(w, t, least) {
                let s = self.busy[w].as_ref().map_or(t, |b| b.start);
                self.gen[w] += 1;
                let end = s + mine.cost() + self.sync;
                self.busy[w] = Some(Busy {
                    piece: mine,
                    start: s,
                });
                self.todo.push_back(child);
                self.push(end, Kind::Finish, w);
                let mine = self.siblings(w);
                for i in 0..self.busy.len() {
                    if self.busy[i].is_none() {
                        let d = if mine.contains(&i) {
                            self.sp.local.2
                        } else {
                            self.sp.wake
                        };
                        self.push(t + d, Kind::Wake, i);
                    }
                }
                if waiting {
                    self.push(t + self.sp.local.0, Kind::LocalCheck, w);
                }
            }
        }
        if !local {
            self.push(t + self.sp.check, Kind::Check, w);
        }
    }

    /// The split worker `w`'s owner would make at `t` (at the end of the cell in progress,
    /// as `job::split` decides before each cell): the part it keeps and the new piece.
    fn split(&self, w: usize, t: f64, least: f64) -> Option<(Piece, Piece)> {
        let bz = self.busy[w].as_ref()?;
        let cells = &bz.piece.cells;
        let spent = t - bz.start;
        // The cell in progress: the first whose end lies after `spent`; the next one after it.
        let mut run = 0.0;
        let mut i = 0;
        while i < cells.len() && run + cells[i].cost <= spent {
            run += cells[i].cost;
            i += 1;
        }
        let next = i + 1;
        if next >= cells.len() {
            return None;
        }
        let left = spent / next as f64 * (cells.len() - next) as f64;
        if left < 2.0 * least {
            return None;
        }
        let nx = cells[next];
        let rest = &cells[next..];
        // Bands below the one of the next cell.
        let mut rows: Vec<usize> = rest.iter().filter(|c| c.y0 > nx.y0).map(|c| c.y0).collect();
        rows.dedup();
        let (keep, give): (Vec<Cell>, Vec<Cell>) = if rows.len() >= 2 {
            let k = rows[rows.len() / 2];
            cells.iter().partition(|c| c.y0 < k)
        } else {
            // Columns: the half of the cells left in this band, with the same columns below.
            let cols: Vec<usize> = rest
                .iter()
                .filter(|c| c.y0 == nx.y0)
                .map(|c| c.x0)
                .collect();
            if cols.len() < 2 {
                return None;
            }
            let q = cols[cols.len() / 2];
            let (mut keep, mut give) = (Vec::new(), Vec::new());
            for (j, c) in cells.iter().enumerate() {
                if j < next || c.y0 < nx.y0 || c.x0 < q {
                    keep.push(*c);
                } else {
                    give.push(*c);
                }
            }
            (keep, give)
        };
        (!give.is_empty()).then_some((Piece { cells: keep }, Piece { cells: give }))
    }

    fn run(&mut self, workers: usize) {
        for w in 0..workers {
            self.start(w, 0.0);
        }
        while let Some(Ev(t, _, kind, w, g)) = self.heap.pop() {
            match kind {
                Kind::Finish if g == self.gen[w] => {
                    self.makespan = self.makespan.max(t);
                    self.busy[w] = None;
                    self.start(w, t);
                }
                Kind::Check if g == self.cgen[w] && self.busy[w].is_some() => {
                    self.check(w, t, false)
                }
                Kind::LocalCheck if g == self.cgen[w] && self.busy[w].is_some() => {
                    self.check(w, t, true)
                }
                Kind::Wake if self.busy[w].is_none() => self.start(w, t),
                _ => {}
            }
        }
    }
}

/// Replay `plan` (its cost map scaled by `scale`) on `workers` workers with splitting; the
/// makespan.
pub fn simulate_split(
    map: &CostMap,
    scale: f64,
    plan: &[TileRect],
    workers: usize,
    sync: f64,
    sp: SplitParams,
) -> f64 {
    let workers = workers.max(1);
    let mut sim = Sim {
        sync,
        sp: SplitParams {
            cell: sp.cell.max(1),
            ..sp
        },
        todo: plan
            .iter()
            .map(|t| Piece {
                cells: cells_of(
                    map,
                    scale,
                    sp.cell.max(1),
                    (t.x0, t.x0 + t.w, t.y0, t.y0 + t.h),
                ),
            })
            .collect(),
        busy: (0..workers).map(|_| None).collect(),
        gen: vec![0; workers],
        cgen: vec![0; workers],
        heap: BinaryHeap::new(),
        seq: 0,
        makespan: 0.0,
    };
    sim.run(workers);
    sim.makespan
}
