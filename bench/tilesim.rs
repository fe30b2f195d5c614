//! tilesim: how well would a frame's tile plan keep P workers busy?
//!
//! Replays a tile plan on P identical virtual workers using measured per-tile costs, and
//! reports makespan, busy and idle time, speed-up and efficiency for each P.
//!
//! ```text
//! cargo bench --bench tilesim -- COSTS.json [--workers 1,2,4,...,256] [--tiles-per-worker 20]
//!                                [--sync-cost SECONDS] [--json OUT] [--lpt]
//!                                [--bands SHARE:SIZE,...]
//! cargo bench --bench tilesim -- --self-test      (also what it does without COSTS.json)
//! cargo bench --bench tilesim -- --write-synthetic OUT.json [--size WxH]
//!                                [--hot-corner tl|tr|bl|br | --hot-at U,V] [--hot-radius R]
//! ```
//!
//! COSTS.json is what `tstat JOBDIR --costs 0` writes:
//! `{"width": W, "height": H, "tiles": [{"x0","y0","w","h","seconds"}, ...]}`, the tiles
//! covering the picture exactly, `seconds` the CPU time a worker spent rendering the tile.
//!
//! Method:
//! 1. The measured costs become a per-pixel cost map: each measured tile's seconds are
//!    spread uniformly over its pixels (summed-area table, so any rectangle's cost is
//!    four look-ups).
//! 2. For each P, the plan `tplan` would make (`plan_tiles(W, H, tiles, 4)`, largest tiles
//!    first, edges on the `-ps 4` grid; `tiles` is `tplan`'s default for P workers given the
//!    frame's measured cost and the per-tile overhead — `--sync-cost`, else
//!    `plan::TILE_OVERHEAD` — or `--tiles-per-worker` · P) is costed on the map, plus `--sync-cost` per tile, and replayed
//!    in plan order: a min-heap holds the workers' finish times; the worker that is free
//!    first takes the next tile.
//! 3. The same is done for a naive plan: a uniform grid with about as many tiles, taken
//!    in reading order. With `--lpt`, also the shrinking plan's tiles sorted by decreasing
//!    cost (an oracle: it needs the costs before rendering, e.g. from the previous frame).
//!    With `--bands`, also a band plan with other row shares and tile sizes than
//!    `plan_tiles` (see `plan_bands`), to try changes to the plan before making them.
//!
//! Reported per plan and P: `T1` = the work (sum of the cost map, no per-tile overhead),
//! makespan, busy = the sum of the tile costs including `--sync-cost`, idle = P · makespan −
//! busy, speed-up = T1 / makespan, efficiency = speed-up / P and the idle fraction =
//! idle / (P · makespan). With `--sync-cost 0`, efficiency = 1 − idle fraction; otherwise
//! the per-tile overhead counts as a loss too.
//!
//! Assumptions (also printed in the output header):
//! - the workers are identical (same speed, all available from time 0);
//! - tile costs do not depend on the worker count: the measured costs come from one real
//!   run, so effects such as workers sharing (or not sharing) ambient values are not
//!   modelled;
//! - the cost per pixel is uniform inside each measured tile;
//! - claiming a tile and writing its result cost nothing beyond `--sync-cost` per tile
//!   (no claim latency, no contention).

#[path = "tilesim_split.rs"]
mod split;
#[path = "tilesim_sweep.rs"]
mod sweep;

use serde::Deserialize;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::process::ExitCode;
use tessera::job::plan::{check_cover, plan_tiles, tiles_for_cost, TileRect, TILE_OVERHEAD};

/// The sample grid of the plans (`-ps 4`, rpict's default).
pub(crate) const GRID: usize = 4;

const ASSUMPTIONS: [&str; 4] = [
    "identical workers, all available from time 0",
    "tile costs independent of the worker count (measured in one real run; ambient sharing \
     between workers is not modelled)",
    "cost per pixel uniform within each measured tile",
    "no claim latency or contention beyond --sync-cost per tile",
];

const DEFAULT_WORKERS: [usize; 9] = [1, 2, 4, 8, 16, 32, 64, 128, 256];

// ---------------------------------------------------------------------------------------
// Input

#[derive(Deserialize)]
struct MeasuredTile {
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
    seconds: f64,
}

#[derive(Deserialize)]
struct Costs {
    width: usize,
    height: usize,
    tiles: Vec<MeasuredTile>,
}

/// Per-pixel cost map of a `width × height` picture, stored as a summed-area table.
pub(crate) struct CostMap {
    pub(crate) width: usize,
    pub(crate) height: usize,
    /// `sat[y·(width+1) + x]` = cost of the pixels `[0, x) × [0, y)`.
    sat: Vec<f64>,
}

impl CostMap {
    /// Spread each tile's seconds uniformly over its pixels. The tiles must cover the
    /// picture exactly.
    fn new(costs: &Costs) -> Result<CostMap, String> {
        let (w, h) = (costs.width, costs.height);
        if w == 0 || h == 0 {
            return Err(format!("empty picture {w}x{h}"));
        }
        let rects: Vec<TileRect> = costs
            .tiles
            .iter()
            .map(|t| TileRect {
                x0: t.x0,
                y0: t.y0,
                w: t.w,
                h: t.h,
            })
            .collect();
        check_cover(w, h, &rects).map_err(|e| format!("measured tiles: {e}"))?;
        let stride = w + 1;
        let mut sat = vec![0.0f64; stride * (h + 1)];
        for (i, t) in costs.tiles.iter().enumerate() {
            if !t.seconds.is_finite() || t.seconds < 0.0 {
                return Err(format!("measured tile {i}: seconds = {}", t.seconds));
            }
            let density = t.seconds / (t.w * t.h) as f64;
            for y in t.y0..t.y0 + t.h {
                let row = (y + 1) * stride + 1;
                sat[row + t.x0..row + t.x0 + t.w].fill(density);
            }
        }
        for y in 1..=h {
            let mut run = 0.0;
            for x in 1..=w {
                run += sat[y * stride + x];
                sat[y * stride + x] = run + sat[(y - 1) * stride + x];
            }
        }
        Ok(CostMap {
            width: w,
            height: h,
            sat,
        })
    }

    /// Cost of the pixels of `t`.
    pub(crate) fn cost(&self, t: &TileRect) -> f64 {
        let s = self.width + 1;
        let (x0, y0, x1, y1) = (t.x0, t.y0, t.x0 + t.w, t.y0 + t.h);
        let v = self.sat[y1 * s + x1] - self.sat[y0 * s + x1] - self.sat[y1 * s + x0]
            + self.sat[y0 * s + x0];
        v.max(0.0)
    }

    /// Cost of the whole picture.
    pub(crate) fn total(&self) -> f64 {
        self.sat[self.height * (self.width + 1) + self.width]
    }
}

// ---------------------------------------------------------------------------------------
// Plans

/// A grid of about `tiles` equal, nearly square tiles (widths and heights differ by at most
/// one pixel), in reading order.
fn plan_grid(width: usize, height: usize, tiles: usize) -> Vec<TileRect> {
    let n = tiles.max(1) as f64;
    let rows = ((n * height as f64 / width as f64).sqrt().round() as usize).clamp(1, height);
    let cols = ((n / rows as f64).round() as usize).clamp(1, width);
    let mut out = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        let (y0, y1) = (height * r / rows, height * (r + 1) / rows);
        for c in 0..cols {
            let (x0, x1) = (width * c / cols, width * (c + 1) / cols);
            out.push(TileRect {
                x0,
                y0,
                w: x1 - x0,
                h: y1 - y0,
            });
        }
    }
    out
}

/// The band plan of `plan_tiles` with other parameters, to try changes to it: the picture is
/// cut top to bottom into bands holding `share` of the rows each (shares are normalised),
/// and band k's tiles have about `size_k · b` pixels, b chosen so that the plan has about
/// `tiles` tiles. `plan_tiles` uses the shares and sizes
/// `[(0.5, 2), (0.25, 1), (0.125, 0.5), (0.0625, 0.25), (0.03125, 0.125), (0.03125, 0.0625)]`
/// with b = 1.25·area/tiles (so about 1.4× the tiles), farthest-point order in each band.
fn plan_bands(width: usize, height: usize, tiles: usize, bands: &[(f64, f64)]) -> Vec<TileRect> {
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let tiles = tiles.max(1);
    if tiles == 1 || bands.is_empty() {
        return vec![TileRect {
            x0: 0,
            y0: 0,
            w: width,
            h: height,
        }];
    }
    let area = (width * height) as f64;
    let total_share: f64 = bands.iter().map(|b| b.0).sum();
    let per_area: f64 = bands.iter().map(|b| b.0 / total_share / b.1).sum();
    let base = per_area * area / tiles as f64;
    let mut out = Vec::new();
    let mut acc = 0.0;
    let mut r0 = 0;
    for (k, &(share, size)) in bands.iter().enumerate() {
        acc += share / total_share;
        let r1 = if k + 1 == bands.len() {
            height
        } else {
            ((acc * height as f64).round() as usize).min(height)
        };
        if r1 <= r0 {
            continue;
        }
        let tile_area = base * size;
        let side = tile_area.sqrt().max(1.0);
        let rows = r1 - r0;
        let nrows = ((rows as f64 / side).round() as usize).clamp(1, rows);
        for b in 0..nrows {
            let (y0, y1) = (r0 + rows * b / nrows, r0 + rows * (b + 1) / nrows);
            let h = y1 - y0;
            let ncols = (((width * h) as f64 / tile_area).round() as usize).clamp(1, width);
            for c in 0..ncols {
                let (x0, x1) = (width * c / ncols, width * (c + 1) / ncols);
                out.push(TileRect {
                    x0,
                    y0,
                    w: x1 - x0,
                    h,
                });
            }
        }
        r0 = r1;
    }
    out
}

/// Parse `SHARE:SIZE,SHARE:SIZE,...` (see `plan_bands`).
fn parse_bands(spec: &str) -> Result<Vec<(f64, f64)>, String> {
    spec.split(',')
        .map(|b| {
            let (s, z) = b
                .split_once(':')
                .ok_or(format!("--bands: {b:?} is not SHARE:SIZE"))?;
            match (s.trim().parse::<f64>(), z.trim().parse::<f64>()) {
                (Ok(s), Ok(z)) if s > 0.0 && z > 0.0 && s.is_finite() && z.is_finite() => {
                    Ok((s, z))
                }
                _ => Err(format!("--bands: {b:?}: expected positive numbers")),
            }
        })
        .collect()
}

/// `SHARE:SIZE,...` as `--bands` takes it.
fn bands_spec(bands: &[(f64, f64)]) -> String {
    let v: Vec<String> = bands.iter().map(|(s, z)| format!("{s}:{z}")).collect();
    v.join(",")
}

// ---------------------------------------------------------------------------------------
// Simulation

/// A worker's next free time, ordered so that `BinaryHeap` pops the earliest (lowest id on
/// ties).
#[derive(PartialEq)]
struct Free(f64, usize);

impl Eq for Free {}

impl Ord for Free {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl PartialOrd for Free {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Replay `costs` (in claim order) on `workers` identical workers; returns the makespan and
/// each tile's start time.
pub(crate) fn simulate(costs: &[f64], workers: usize) -> (f64, Vec<f64>) {
    let mut heap: BinaryHeap<Free> = (0..workers.max(1)).map(|i| Free(0.0, i)).collect();
    let mut starts = Vec::with_capacity(costs.len());
    let mut makespan = 0.0f64;
    for &c in costs {
        let Free(t, id) = heap.pop().expect("at least one worker");
        starts.push(t);
        makespan = makespan.max(t + c);
        heap.push(Free(t + c, id));
    }
    (makespan, starts)
}

/// One plan's outcome with P workers.
struct Outcome {
    plan: &'static str,
    workers: usize,
    tiles: usize,
    work: f64,
    makespan: f64,
    busy: f64,
}

impl Outcome {
    fn idle(&self) -> f64 {
        self.workers as f64 * self.makespan - self.busy
    }
    fn speedup(&self) -> f64 {
        if self.makespan > 0.0 {
            self.work / self.makespan
        } else {
            1.0
        }
    }
    fn efficiency(&self) -> f64 {
        self.speedup() / self.workers as f64
    }
    fn idle_fraction(&self) -> f64 {
        let cap = self.workers as f64 * self.makespan;
        if cap > 0.0 {
            self.idle() / cap
        } else {
            0.0
        }
    }
}

fn run_plan(
    name: &'static str,
    map: &CostMap,
    plan: &[TileRect],
    workers: usize,
    sync: f64,
    lpt: bool,
) -> Outcome {
    let mut costs: Vec<f64> = plan.iter().map(|t| map.cost(t) + sync).collect();
    if lpt {
        costs.sort_by(|a, b| b.total_cmp(a));
    }
    let (makespan, _) = simulate(&costs, workers);
    Outcome {
        plan: name,
        workers,
        tiles: plan.len(),
        work: map.total(),
        makespan,
        busy: costs.iter().sum(),
    }
}

fn evaluate(map: &CostMap, args: &Args) -> Vec<Outcome> {
    let (tpw, sync) = (args.tpw, args.sync);
    let mut out = Vec::new();
    for &p in &args.workers {
        let tiles = match tpw {
            Some(n) => n * p,
            None => {
                let overhead = if sync > 0.0 { sync } else { TILE_OVERHEAD };
                tiles_for_cost(map.width * map.height, p, map.total(), overhead)
            }
        };
        let shrink = plan_tiles(map.width, map.height, tiles, GRID);
        let grid = plan_grid(map.width, map.height, shrink.len());
        out.push(run_plan("shrinking", map, &shrink, p, sync, false));
        out.push(run_plan("grid", map, &grid, p, sync, false));
        if args.lpt {
            out.push(run_plan("shrink-lpt", map, &shrink, p, sync, true));
        }
        if let Some(bands) = &args.bands {
            let alt = plan_bands(map.width, map.height, tiles, bands);
            out.push(run_plan("bands", map, &alt, p, sync, false));
        }
    }
    out
}

// ---------------------------------------------------------------------------------------
// Synthetic input

/// Parameters of the synthetic cost field.
struct Synthetic {
    width: usize,
    height: usize,
    /// Centre of the hot spot, as fractions of the width and height (0,0 = top left).
    at: (f64, f64),
    /// Radius of the hot spot as a fraction of the height (0: no hot spot).
    radius: f64,
}

/// A synthetic cost field: smooth variation across the picture (`1 + 0.5·u + 0.3·sin(π·v)`,
/// 1 to 1.8, u and v the pixel's position as fractions of width and height) times a hot
/// spot up to 10× as expensive (`1 + 9·exp(−d²/r²)`, d the distance to the spot's centre).
/// Measured on 16×16 tiles, scaled to 600 CPU-seconds in all.
fn synthetic(p: &Synthetic) -> serde_json::Value {
    let (width, height) = (p.width, p.height);
    let (cx, cy) = (p.at.0 * width as f64, p.at.1 * height as f64);
    let r2 = (p.radius * height as f64).powi(2);
    let field = |x: f64, y: f64| {
        let (u, v) = (x / width as f64, y / height as f64);
        let smooth = 1.0 + 0.5 * u + 0.3 * (std::f64::consts::PI * v).sin();
        let d2 = (x - cx).powi(2) + (y - cy).powi(2);
        let hot = if r2 > 0.0 { (-d2 / r2).exp() } else { 0.0 };
        smooth * (1.0 + 9.0 * hot)
    };
    let grid = tessera::job::plan::plan_fixed(width, height, 16, 16);
    let raw: Vec<f64> = grid
        .iter()
        .map(|t| {
            let mut s = 0.0;
            for y in t.y0..t.y0 + t.h {
                for x in t.x0..t.x0 + t.w {
                    s += field(x as f64 + 0.5, y as f64 + 0.5);
                }
            }
            s
        })
        .collect();
    let scale = 600.0 / raw.iter().sum::<f64>();
    let tiles: Vec<serde_json::Value> = grid
        .iter()
        .zip(&raw)
        .map(|(t, s)| {
            // Microsecond resolution, as a timer would give.
            let seconds = (s * scale * 1e6).round() / 1e6;
            serde_json::json!({"x0": t.x0, "y0": t.y0, "w": t.w, "h": t.h, "seconds": seconds})
        })
        .collect();
    serde_json::json!({"width": width, "height": height, "tiles": tiles})
}

// ---------------------------------------------------------------------------------------
// Self-test

/// xorshift64*: a small deterministic generator for the self-test.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// Brute force: a clock ticking one unit at a time; at each tick every idle worker, in id
/// order, takes the next tile. Integer costs only. Returns the makespan and start times.
fn simulate_ticks(costs: &[u64], workers: usize) -> (u64, Vec<u64>) {
    let mut left = vec![0u64; workers];
    let mut starts = Vec::new();
    let mut next = 0;
    let mut t = 0u64;
    loop {
        for l in left.iter_mut() {
            // Zero-cost tiles finish at once: the worker keeps claiming.
            while *l == 0 && next < costs.len() {
                starts.push(t);
                *l = costs[next];
                next += 1;
            }
        }
        if next == costs.len() && left.iter().all(|&l| l == 0) {
            return (t, starts);
        }
        t += 1;
        for l in left.iter_mut() {
            *l = l.saturating_sub(1);
        }
    }
}

fn uniform_costs(width: usize, height: usize, tw: usize, per_pixel: f64) -> Costs {
    Costs {
        width,
        height,
        tiles: tessera::job::plan::plan_fixed(width, height, tw, tw)
            .iter()
            .map(|t| MeasuredTile {
                x0: t.x0,
                y0: t.y0,
                w: t.w,
                h: t.h,
                seconds: per_pixel * t.area() as f64,
            })
            .collect(),
    }
}

fn self_test() -> Result<(), String> {
    let mut failures = Vec::new();
    let mut check = |name: &str, ok: bool, detail: String| {
        println!("{} {name}{}", if ok { "ok  " } else { "FAIL" }, detail);
        if !ok {
            failures.push(name.to_string());
        }
    };

    // 1. Uniform cost over the shrinking plan at P = 1: efficiency 1.
    let map = CostMap::new(&uniform_costs(640, 480, 37, 1e-3))?;
    for &tiles in &[1, 20, 80, 333] {
        let plan = plan_tiles(640, 480, tiles, GRID);
        let o = run_plan("shrinking", &map, &plan, 1, 0.0, false);
        check(
            &format!("uniform cost, {} tiles, P=1: efficiency 1", plan.len()),
            (o.efficiency() - 1.0).abs() < 1e-9 && o.idle().abs() < 1e-9,
            format!(" (efficiency {:.12})", o.efficiency()),
        );
    }
    // With a per-tile overhead, P = 1 loses exactly that overhead.
    let plan = plan_tiles(640, 480, 20, GRID);
    let o = run_plan("shrinking", &map, &plan, 1, 0.5, false);
    let want = map.total() / (map.total() + 0.5 * plan.len() as f64);
    check(
        "uniform cost, P=1, sync 0.5 s: efficiency T1/(T1 + n·0.5)",
        (o.efficiency() - want).abs() < 1e-12,
        format!(" ({:.6} vs {want:.6})", o.efficiency()),
    );

    // 2. One tile holding the whole picture: efficiency 1/P.
    let one = plan_tiles(640, 480, 1, GRID);
    for p in [1, 2, 3, 8, 256] {
        let o = run_plan("one", &map, &one, p, 0.0, false);
        check(
            &format!("single tile, P={p}: efficiency 1/P"),
            one.len() == 1 && (o.efficiency() - 1.0 / p as f64).abs() < 1e-12,
            format!(" ({:.6})", o.efficiency()),
        );
    }

    // 3. The cost map: rectangle sums agree with pixel-by-pixel sums on random covers.
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut worst = 0.0f64;
    for _ in 0..50 {
        let (w, h) = (1 + rng.below(40) as usize, 1 + rng.below(30) as usize);
        let measured = plan_tiles(w, h, 1 + rng.below(30) as usize, GRID);
        let costs = Costs {
            width: w,
            height: h,
            tiles: measured
                .iter()
                .map(|t| MeasuredTile {
                    x0: t.x0,
                    y0: t.y0,
                    w: t.w,
                    h: t.h,
                    seconds: rng.below(1000) as f64 / 10.0,
                })
                .collect(),
        };
        let map = CostMap::new(&costs)?;
        let mut density = vec![0.0; w * h];
        for t in &costs.tiles {
            for y in t.y0..t.y0 + t.h {
                for x in t.x0..t.x0 + t.w {
                    density[y * w + x] = t.seconds / (t.w * t.h) as f64;
                }
            }
        }
        let plan = plan_grid(w, h, 1 + rng.below(50) as usize);
        check_cover(w, h, &plan)?;
        let mut sum = 0.0;
        for t in &plan {
            let mut direct = 0.0;
            for y in t.y0..t.y0 + t.h {
                for x in t.x0..t.x0 + t.w {
                    direct += density[y * w + x];
                }
            }
            worst = worst.max((map.cost(t) - direct).abs());
            sum += map.cost(t);
        }
        let total: f64 = costs.tiles.iter().map(|t| t.seconds).sum();
        worst = worst
            .max((sum - total).abs())
            .max((map.total() - total).abs());
    }
    check(
        "cost map: rectangle sums = pixel sums (50 random cases)",
        worst < 1e-9,
        format!(" (worst difference {worst:.2e})"),
    );

    // 4. Event simulation = brute-force clock on small random cases.
    let mut mismatches = 0;
    for case in 0..500 {
        let n = rng.below(25) as usize;
        let p = 1 + rng.below(7) as usize;
        let costs: Vec<u64> = (0..n)
            .map(|_| {
                if case % 5 == 0 {
                    rng.below(3)
                } else {
                    1 + rng.below(20)
                }
            })
            .collect();
        let (m_ticks, s_ticks) = simulate_ticks(&costs, p);
        let costs_f: Vec<f64> = costs.iter().map(|&c| c as f64).collect();
        let (m_heap, s_heap) = simulate(&costs_f, p);
        let same = m_heap == m_ticks as f64
            && s_heap.len() == s_ticks.len()
            && s_heap.iter().zip(&s_ticks).all(|(a, &b)| *a == b as f64);
        if !same {
            mismatches += 1;
            if mismatches <= 3 {
                println!(
                    "     P={p} costs {costs:?}: heap {m_heap} {s_heap:?}, ticks {m_ticks} {s_ticks:?}"
                );
            }
        }
    }
    check(
        "event simulation = brute-force clock (500 random cases)",
        mismatches == 0,
        format!(" ({mismatches} mismatches)"),
    );

    // 5. plan_tiles and `plan_bands` with other parameters cover the picture. (plan_tiles
    // orders each band farthest-point first and floors tile areas at 64 pixels, so the two
    // are not compared tile by tile.)
    let default = parse_bands("0.5:2,0.25:1,0.125:0.5,0.0625:0.25,0.03125:0.125,0.03125:0.0625")?;
    let other = parse_bands("0.4:2,0.3:1,0.2:0.5,0.1:0.125")?;
    let mut bad = Vec::new();
    for &(w, h, n) in &[
        (640, 480, 80),
        (640, 480, 5120),
        (512, 512, 320),
        (17, 3, 40),
        (1, 1, 5),
        (1000, 7, 20),
        (7, 1000, 20),
        (1920, 1080, 1280),
    ] {
        if check_cover(w, h, &plan_tiles(w, h, n, GRID)).is_err()
            || check_cover(w, h, &plan_bands(w, h, n, &default)).is_err()
            || check_cover(w, h, &plan_bands(w, h, n, &other)).is_err()
        {
            bad.push(format!("{w}x{h}/{n}"));
        }
    }
    check(
        "plan_tiles and band plans cover the picture",
        bad.is_empty(),
        if bad.is_empty() {
            String::new()
        } else {
            format!(" ({})", bad.join(", "))
        },
    );

    // 6. The uniform grid covers the picture with about the requested count.
    let mut bad = Vec::new();
    for &(w, h, n) in &[
        (640, 480, 20),
        (640, 480, 5120),
        (17, 3, 40),
        (1, 1, 5),
        (1000, 7, 80),
    ] {
        let g = plan_grid(w, h, n);
        if check_cover(w, h, &g).is_err() {
            bad.push(format!("{w}x{h}/{n}"));
        }
    }
    check("uniform grid covers the picture", bad.is_empty(), {
        if bad.is_empty() {
            String::new()
        } else {
            format!(" ({})", bad.join(", "))
        }
    });

    // 7. Splitting: one tile of uniform cost (1 ms a pixel, 307 s) on P workers ends within
    //    5% of T1/P; with pieces that may never be made (MIN above
    //    the frame's cost) it is the replay without splitting.
    let total = map.total();
    for p in [1usize, 4, 16] {
        let sp = split::SplitParams {
            check: 0.05,
            min_piece: 0.05,
            wake: 0.05,
            cell: tessera::render::cell_size(GRID),
            loops: 1,
            local: (0.0, 0.0, 0.0),
        };
        let m = split::simulate_split(&map, 1.0, &one, p, 0.0, sp);
        let ideal = total / p as f64;
        check(
            &format!("single tile split on P={p}: near T1/P"),
            m >= ideal - 1e-9 && m <= ideal * 1.05,
            format!(" ({m:.3} s against {ideal:.3})"),
        );
        let never = split::SplitParams {
            min_piece: total,
            ..sp
        };
        let m = split::simulate_split(&map, 1.0, &one, p, 0.0, never);
        check(
            &format!("single tile, no split possible, P={p}: T1"),
            (m - total).abs() < 1e-6,
            format!(" ({m:.3} s against {total:.3})"),
        );
        // The same tile on one process of P loops whose siblings take pieces at once:
        // within 1% of T1/P, and not slower than P processes.
        let local = split::SplitParams {
            loops: p,
            local: (1e-4, 0.05, 1e-4),
            ..sp
        };
        let ml = split::simulate_split(&map, 1.0, &one, p, 0.0, local);
        check(
            &format!("single tile split among P={p} sibling loops: near T1/P"),
            ml >= ideal - 1e-9 && ml <= ideal * 1.01 && ml <= m.min(ideal * 1.05) + 1e-9,
            format!(" ({ml:.3} s against {ideal:.3})"),
        );
    }

    if failures.is_empty() {
        println!("tilesim self-test: all checks passed");
        Ok(())
    } else {
        Err(format!("{} check(s) failed", failures.len()))
    }
}

// ---------------------------------------------------------------------------------------
// Command line

struct Args {
    costs: Option<String>,
    workers: Vec<usize>,
    tpw: Option<usize>,
    sync: f64,
    json: Option<String>,
    lpt: bool,
    bands: Option<Vec<(f64, f64)>>,
    self_test: bool,
    synthetic: Option<String>,
    hot: Synthetic,
    /// `--sweep`: frame costs 0.1–1000 CPU-s, default plan against the best.
    sweep: bool,
    /// `--startup SECONDS` added to every makespan of the sweep.
    startup: f64,
    /// `--estimate-factor F`: the default plan sees F × the frame's cost.
    estimate: f64,
    /// `--frame-costs C,...`: the frame costs of the sweep (CPU seconds).
    frame_costs: Vec<f64>,
    /// `--split CHECK,MIN,WAKE`: replay with tiles split while they render.
    split: Option<split::SplitParams>,
    /// `--tail T`: the default plan's tail factor (else `plan::TAIL`).
    tail: f64,
    /// `--loops N`: tile loops per worker process in the `--split` replay.
    loops: usize,
    /// `--counts FILE`: the sweep's wall time of every tile count tried.
    counts: Option<String>,
    /// `--ps N`: the sweep's plans on `cell_size(N)` pixels and `--split`'s cells of as many,
    /// as `tplan` and `tpiece` make them at `-ps N` (else the plan grid [`GRID`] and cells of
    /// `cell_size(GRID)`).
    ps: Option<usize>,
    /// `--local CHECK,MIN,WAKE`: the sibling loops' splitting settings (else
    /// `SIBLING_CHECK_SECONDS`, `SIBLING_MIN_PIECE_SECONDS` and [`SIBLING_WAKE`]).
    local: Option<(f64, f64, f64)>,
}

const USAGE: &str = "usage: cargo bench --bench tilesim -- COSTS.json [--workers 1,2,4,...] \
[--tiles-per-worker N] [--sync-cost SECONDS] [--json OUT] [--lpt] [--bands SHARE:SIZE,...]
       cargo bench --bench tilesim -- COSTS.json --sweep [--workers ...] [--sync-cost S]
         [--startup S] [--estimate-factor F] [--frame-costs C,...] [--tail T]
         [--split CHECK,MIN,WAKE [--loops N]] [--counts FILE] [--ps N]
         [--local CHECK,MIN,WAKE]
       cargo bench --bench tilesim -- --self-test
       cargo bench --bench tilesim -- --write-synthetic OUT.json [--size WxH]
         [--hot-corner tl|tr|bl|br | --hot-at U,V] [--hot-radius FRACTION_OF_HEIGHT]";

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        costs: None,
        workers: DEFAULT_WORKERS.to_vec(),
        tpw: None,
        sync: 0.0,
        json: None,
        lpt: false,
        bands: None,
        self_test: false,
        synthetic: None,
        sweep: false,
        startup: 0.0,
        estimate: 1.0,
        frame_costs: sweep::FRAME_COSTS.to_vec(),
        split: None,
        tail: tessera::job::plan::TAIL,
        loops: 1,
        counts: None,
        ps: None,
        local: None,
        hot: Synthetic {
            width: 640,
            height: 480,
            at: (1.0, 1.0),
            radius: 0.25,
        },
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            // `cargo bench` appends --bench to the arguments of harness-less benches.
            "--bench" => {}
            "-h" | "--help" => return Err(String::new()),
            "--self-test" => a.self_test = true,
            "--lpt" => a.lpt = true,
            "--sweep" => a.sweep = true,
            "--tail" => {
                a.tail = match value("--tail")?.parse::<f64>() {
                    Ok(t) if t.is_finite() && t > 0.0 => t,
                    _ => return Err("--tail: expected a number > 0".into()),
                }
            }
            "--startup" | "--estimate-factor" => {
                let v = match value(&arg)?.parse::<f64>() {
                    Ok(s) if s.is_finite() && s >= 0.0 => s,
                    _ => return Err(format!("{arg}: expected a number >= 0")),
                };
                if arg == "--startup" {
                    a.startup = v;
                } else {
                    a.estimate = v.max(1e-9);
                }
            }
            "--split" => {
                let (check, min_piece, wake) = check_min_wake("--split", &value("--split")?)?;
                a.split = Some(split::SplitParams {
                    check,
                    min_piece,
                    wake,
                    cell: tessera::render::cell_size(GRID),
                    loops: 1,
                    local: (
                        tessera::job::split::SIBLING_CHECK_SECONDS,
                        tessera::job::split::SIBLING_MIN_PIECE_SECONDS,
                        SIBLING_WAKE,
                    ),
                });
            }
            "--loops" => {
                a.loops = match value("--loops")?.parse() {
                    Ok(n) if n > 0 => n,
                    _ => return Err("--loops: expected a positive integer".into()),
                }
            }
            "--local" => a.local = Some(check_min_wake("--local", &value("--local")?)?),
            "--ps" => {
                a.ps = match value("--ps")?.parse() {
                    Ok(n) if (1..=64).contains(&n) => Some(n),
                    _ => return Err("--ps: expected an integer from 1 to 64".into()),
                }
            }
            "--frame-costs" => {
                a.frame_costs = value("--frame-costs")?
                    .split(',')
                    .map(|s| match s.trim().parse::<f64>() {
                        Ok(c) if c.is_finite() && c > 0.0 => Ok(c),
                        _ => Err(format!("--frame-costs: bad cost {s:?}")),
                    })
                    .collect::<Result<_, _>>()?;
            }
            "--workers" => {
                a.workers = value("--workers")?
                    .split(',')
                    .map(|s| match s.trim().parse::<usize>() {
                        Ok(p) if p > 0 => Ok(p),
                        _ => Err(format!("--workers: bad count {s:?}")),
                    })
                    .collect::<Result<_, _>>()?;
            }
            "--tiles-per-worker" => {
                a.tpw = match value("--tiles-per-worker")?.parse() {
                    Ok(n) if n > 0 => Some(n),
                    _ => return Err("--tiles-per-worker: expected a positive integer".into()),
                }
            }
            "--sync-cost" => {
                a.sync = match value("--sync-cost")?.parse::<f64>() {
                    Ok(s) if s.is_finite() && s >= 0.0 => s,
                    _ => return Err("--sync-cost: expected seconds >= 0".into()),
                }
            }
            "--json" => a.json = Some(value("--json")?),
            "--counts" => a.counts = Some(value("--counts")?),
            "--bands" => a.bands = Some(parse_bands(&value("--bands")?)?),
            "--write-synthetic" => a.synthetic = Some(value("--write-synthetic")?),
            "--hot-corner" => {
                a.hot.at = match value("--hot-corner")?.as_str() {
                    "tl" => (0.0, 0.0),
                    "tr" => (1.0, 0.0),
                    "bl" => (0.0, 1.0),
                    "br" => (1.0, 1.0),
                    c => return Err(format!("--hot-corner {c}: expected tl, tr, bl or br")),
                }
            }
            "--hot-at" => {
                let v = value("--hot-at")?;
                a.hot.at = v
                    .split_once(',')
                    .and_then(|(u, v)| Some((u.trim().parse().ok()?, v.trim().parse().ok()?)))
                    .filter(|&(u, v): &(f64, f64)| u.is_finite() && v.is_finite())
                    .ok_or(format!("--hot-at {v}: expected U,V (fractions of W and H)"))?;
            }
            "--hot-radius" => {
                a.hot.radius = match value("--hot-radius")?.parse::<f64>() {
                    Ok(r) if r.is_finite() && r >= 0.0 => r,
                    _ => return Err("--hot-radius: expected a fraction of the height >= 0".into()),
                }
            }
            "--size" => {
                let v = value("--size")?;
                (a.hot.width, a.hot.height) = v
                    .split_once('x')
                    .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
                    .filter(|&(w, h): &(usize, usize)| w > 0 && h > 0)
                    .ok_or(format!("--size {v}: expected WxH"))?;
            }
            s if s.starts_with('-') => return Err(format!("unknown option {s}")),
            s => {
                if a.costs.replace(s.to_string()).is_some() {
                    return Err("more than one costs file".into());
                }
            }
        }
    }
    if let Some(sp) = &mut a.split {
        sp.loops = a.loops;
        if let Some(ps) = a.ps {
            sp.cell = tessera::render::cell_size(ps);
        }
        if let Some(l) = a.local {
            sp.local = l;
        }
    } else if a.loops > 1 || a.local.is_some() {
        return Err("--loops and --local need --split".into());
    }
    Ok(a)
}

/// The value `v` of option `name`: CHECK,MIN,WAKE seconds, CHECK > 0, MIN and WAKE >= 0.
fn check_min_wake(name: &str, v: &str) -> Result<(f64, f64, f64), String> {
    let f: Vec<f64> = v
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{name} {v}: expected CHECK,MIN,WAKE seconds"))?;
    match f[..] {
        [c, m, w] if c > 0.0 && m >= 0.0 && w >= 0.0 => Ok((c, m, w)),
        [_, _, _] => Err(format!("{name} {v}: CHECK > 0, MIN and WAKE >= 0")),
        _ => Err(format!("{name} {v}: expected CHECK,MIN,WAKE seconds")),
    }
}

/// Seconds before a woken sibling loop takes a new piece (a condition variable's wake-up
/// and its claim's rename; the claim's cost is the per-tile cost).
const SIBLING_WAKE: f64 = 1e-4;

fn run() -> Result<(), String> {
    let args = parse_args().map_err(|e| {
        if e.is_empty() {
            USAGE.to_string()
        } else {
            format!("{e}\n{USAGE}")
        }
    })?;
    if args.self_test {
        return self_test();
    }
    if let Some(out) = &args.synthetic {
        let v = synthetic(&args.hot);
        let text = serde_json::to_string(&v).map_err(|e| e.to_string())?;
        std::fs::write(out, text + "\n").map_err(|e| format!("{out}: {e}"))?;
        let h = &args.hot;
        println!(
            "tilesim: wrote {out} ({}x{}, hot spot at {},{} radius {} of the height)",
            h.width, h.height, h.at.0, h.at.1, h.radius
        );
        return Ok(());
    }
    let Some(path) = args.costs.as_deref() else {
        // A plain `cargo bench` runs every bench without arguments: check, don't fail.
        println!("tilesim: no COSTS.json given, running the self-test\n{USAGE}\n");
        return self_test();
    };
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let costs: Costs = serde_json::from_str(&text).map_err(|e| format!("{path}: {e}"))?;
    let map = CostMap::new(&costs).map_err(|e| format!("{path}: {e}"))?;
    if args.sweep {
        let sync = if args.sync > 0.0 {
            args.sync
        } else {
            TILE_OVERHEAD
        };
        let mut file = match &args.counts {
            Some(p) => Some(std::io::BufWriter::new(
                std::fs::File::create(p).map_err(|e| format!("{p}: {e}"))?,
            )),
            None => None,
        };
        let rows = sweep::sweep(
            &map,
            (&args.frame_costs, &args.workers),
            sync,
            args.startup,
            args.estimate,
            args.split,
            args.tail,
            args.ps.map_or(GRID, tessera::render::cell_size),
            file.as_mut().map(|f| f as &mut dyn std::io::Write),
        );
        if let Some(mut f) = file {
            use std::io::Write;
            f.flush().map_err(|e| format!("--counts: {e}"))?;
        }
        sweep::print(&rows, sync, args.startup, args.estimate);
        return Ok(());
    }
    let results = evaluate(&map, &args);

    println!(
        "tilesim: {path}: {}x{} picture, {} measured tiles, T1 = {:.3} CPU-s",
        map.width,
        map.height,
        costs.tiles.len(),
        map.total()
    );
    let count = match args.tpw {
        Some(n) => format!("{n} x P"),
        None => "tplan's default for the measured frame cost".into(),
    };
    let mut plans = format!(
        "shrinking = plan_tiles(W, H, {count}, grid {GRID}); grid = equal tiles, same count, \
         reading order"
    );
    if args.lpt {
        plans += "; shrink-lpt = shrinking tiles by decreasing cost (oracle)";
    }
    if let Some(b) = &args.bands {
        plans += &format!("; bands = band plan {}", bands_spec(b));
    }
    println!("plans: {plans}; sync cost {} s/tile", args.sync);
    println!("assumptions:");
    for a in ASSUMPTIONS {
        println!("  - {a}");
    }
    println!();
    println!(
        "{:<11} {:>4} {:>6} {:>11} {:>11} {:>11} {:>8} {:>7} {:>6}",
        "plan", "P", "tiles", "makespan s", "busy s", "idle s", "speed-up", "effic.", "idle%"
    );
    for o in &results {
        println!(
            "{:<11} {:>4} {:>6} {:>11.3} {:>11.3} {:>11.3} {:>8.2} {:>6.1}% {:>5.1}%",
            o.plan,
            o.workers,
            o.tiles,
            o.makespan,
            o.busy,
            o.idle(),
            o.speedup(),
            100.0 * o.efficiency(),
            100.0 * o.idle_fraction()
        );
    }

    if let Some(out) = &args.json {
        let rows: Vec<serde_json::Value> = results
            .iter()
            .map(|o| {
                serde_json::json!({
                    "plan": o.plan,
                    "workers": o.workers,
                    "tiles": o.tiles,
                    "work_seconds": o.work,
                    "makespan": o.makespan,
                    "busy": o.busy,
                    "idle": o.idle(),
                    "speedup": o.speedup(),
                    "efficiency": o.efficiency(),
                    "idle_fraction": o.idle_fraction(),
                })
            })
            .collect();
        let v = serde_json::json!({
            "input": path,
            "width": map.width,
            "height": map.height,
            "measured_tiles": costs.tiles.len(),
            "work_seconds": map.total(),
            "tiles_per_worker": args.tpw,
            "sync_cost": args.sync,
            "bands": args.bands.as_ref().map(|b| bands_spec(b)),
            "assumptions": ASSUMPTIONS,
            "results": rows,
        });
        let text = serde_json::to_string_pretty(&v).map_err(|e| e.to_string())?;
        std::fs::write(out, text + "\n").map_err(|e| format!("{out}: {e}"))?;
        println!("\ntilesim: wrote {out}");
    }
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("tilesim: {e}");
            ExitCode::FAILURE
        }
    }
}
