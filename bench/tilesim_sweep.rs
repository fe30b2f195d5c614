//! `tilesim --sweep`: the default plan against the best `--tiles` for frames from 0.1 to
//! 1000 CPU-seconds and every worker count.
//!
//! The measured cost map is scaled to each frame cost. For each P, the default plan
//! (`tiles_for_cost` of the frame's cost times `--estimate-factor`, the cost probe's bias;
//! with `--split` and `--loops` of 2 or more, `tiles_for_loops`, as `tplan --threads`) and
//! plans of every tile count from 1 to 80 P (a geometric series, 12 a doubling) are
//! replayed with `--sync-cost` per tile on the render thread; each makespan gets
//! `--startup` seconds (a worker reading its scene). Printed: the best count, its wall time,
//! the default's, and their ratio.

use super::split::{simulate_split, SplitParams};
use super::{simulate, CostMap};
use std::io::Write;
use tessera::job::plan::{plan_tiles, tiles_for_loops, tiles_for_tail, TILES_PER_WORKER};

/// The frame costs swept by default, CPU seconds (`--frame-costs` for others).
pub const FRAME_COSTS: [f64; 5] = [0.1, 1.0, 10.0, 100.0, 1000.0];

/// One row: frame cost, P, default tiles and wall, best tiles and wall.
pub struct Row {
    pub cost: f64,
    pub workers: usize,
    pub default_tiles: usize,
    pub default_wall: f64,
    pub best_tiles: usize,
    pub best_wall: f64,
}

#[allow(clippy::too_many_arguments)]
fn wall(
    map: &CostMap,
    scale: f64,
    tiles: usize,
    p: usize,
    sync: f64,
    startup: f64,
    split: Option<SplitParams>,
    grid: usize,
) -> (usize, f64) {
    let plan = plan_tiles(map.width, map.height, tiles, grid);
    if let Some(sp) = split {
        return (
            plan.len(),
            startup + simulate_split(map, scale, &plan, p, sync, sp),
        );
    }
    let costs: Vec<f64> = plan.iter().map(|t| map.cost(t) * scale + sync).collect();
    (plan.len(), startup + simulate(&costs, p).0)
}

/// Sweep the frame costs and worker counts; with `counts`, one line per frame cost, P and
/// tile count tried (`cost P requested planned wall`, tab-separated).
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    map: &CostMap,
    (costs, workers): (&[f64], &[usize]),
    sync: f64,
    startup: f64,
    estimate: f64,
    split: Option<SplitParams>,
    tail: f64,
    grid: usize,
    mut counts: Option<&mut dyn std::io::Write>,
) -> Vec<Row> {
    let mut rows = Vec::new();
    let total = map.total().max(f64::MIN_POSITIVE);
    let area = map.width * map.height;
    for &cost in costs {
        let scale = cost / total;
        for &p in workers {
            // `tplan --threads T`'s default: workers of several loops that split, a few
            // tiles a loop; single-thread workers, the cost rule.
            let loops = split.map_or(1, |sp| sp.loops.min(p));
            let n = tiles_for_loops(area, p, loops)
                .unwrap_or_else(|| tiles_for_tail(area, p, cost * estimate, sync, tail));
            let (default_tiles, default_wall) = wall(map, scale, n, p, sync, startup, split, grid);
            let (mut best_tiles, mut best_wall) = (default_tiles, default_wall);
            let mut k = 1.0f64;
            while k <= (TILES_PER_WORKER * p) as f64 {
                let (t, w) = wall(
                    map,
                    scale,
                    k.round() as usize,
                    p,
                    sync,
                    startup,
                    split,
                    grid,
                );
                if let Some(out) = counts.as_mut() {
                    let _ = writeln!(out, "{cost}\t{p}\t{}\t{t}\t{w}", k.round());
                }
                if w < best_wall {
                    (best_tiles, best_wall) = (t, w);
                }
                k *= 2f64.powf(1.0 / 12.0);
            }
            rows.push(Row {
                cost,
                workers: p,
                default_tiles,
                default_wall,
                best_tiles,
                best_wall,
            });
        }
    }
    rows
}

/// Print the rows as a table.
pub fn print(rows: &[Row], sync: f64, startup: f64, estimate: f64) {
    println!(
        "tilesim --sweep: per-tile cost {:.2} ms, start-up {startup} s, default plan from {estimate}× the frame's cost",
        sync * 1e3
    );
    println!(
        "{:>9} {:>5} {:>9} {:>10} {:>9} {:>10} {:>8}",
        "frame CPU-s", "P", "default", "wall s", "best", "wall s", "ratio"
    );
    for r in rows {
        println!(
            "{:>11} {:>5} {:>9} {:>10.4} {:>9} {:>10.4} {:>8.3}",
            r.cost,
            r.workers,
            r.default_tiles,
            r.default_wall,
            r.best_tiles,
            r.best_wall,
            r.default_wall / r.best_wall
        );
    }
    let worst = rows
        .iter()
        .map(|r| r.default_wall / r.best_wall)
        .fold(1.0, f64::max);
    println!("worst ratio of the default plan's wall time to the best plan's: {worst:.3}");
}
