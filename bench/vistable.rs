//! vistable: what a shadow-reuse query costs when threads share the table.
//!
//! ```text
//! cargo bench --bench vistable -- [--queries N] [--cubes C] [--work W] [--repeat R]
//!     [--threads T] [--separate]
//! ```
//!
//! `tpict -n` and a worker's tile loops share one shadow-reuse table
//! ([`tessera::light::viscache`]); the ambient sample rays of every thread hit the same
//! walls and ceilings, so they query the same cubes. This times `--queries` queries a
//! thread (default 2,000,000) over `--cubes` cubes (default 20,000: cubes of one level
//! along a room's surfaces, picked with a skew, as rays pick surfaces unevenly), each
//! query after `--work` nanoseconds of arithmetic (default 300: the rest of a sample
//! ray's shading between two queries; 0 measures the queries alone). Every cube is lit,
//! so after its first shadow rays it answers from the table. Prints the nanoseconds a
//! query adds to the work (the fastest of `--repeat` passes, default 3, minus the work
//! alone timed on its own). With `--threads T` (default 1) T threads query at once, each
//! its own sequence; `--separate` gives each thread a table of its own, as processes
//! have: the difference to the shared figure is what sharing one table costs.

#[path = "args.rs"]
mod args;

use glam::DVec3;
use std::process::ExitCode;
use std::time::Instant;
use tessera::color::Color;
use tessera::light::viscache::{shadow, VisQuery, VisTable};
use tessera::render::sampler::Sampler;

/// Spin for about `iters` dependent multiply-adds; returns a value the caller keeps.
#[inline(never)]
fn work(iters: u64, seed: f64) -> f64 {
    let mut x = seed;
    for _ in 0..iters {
        x = x * 0.999_999_9 + 1e-9;
    }
    x
}

/// The query points of one thread: cube centres, the cube index squared-skewed.
fn points(cubes: usize, n: usize, seed: u32) -> Vec<DVec3> {
    let mut rng = Sampler::for_pixel(0, seed, 0, 0);
    (0..n)
        .map(|_| {
            let u = rng.uniform();
            let c = ((u * u) * cubes as f64) as usize;
            // Cubes of side 0.125 along a 20 m strip of wall, 8 across.
            DVec3::new(
                (c / 8) as f64 * 0.125 + 0.06,
                (c % 8) as f64 * 0.125 + 0.06,
                0.06,
            )
        })
        .collect()
}

fn run(tables: &[VisTable], pts: &[Vec<DVec3>], iters: u64) -> (f64, f64) {
    let t0 = Instant::now();
    let mut sink = 0.0;
    std::thread::scope(|s| {
        let hs: Vec<_> = pts
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let table = &tables[k % tables.len()];
                s.spawn(move || {
                    let mut acc = 0.0;
                    for (i, &pt) in p.iter().enumerate() {
                        acc += work(iters, i as f64);
                        if let Some(q) = VisQuery::new(1, 7, false, 0.1, pt) {
                            let (c, _) = shadow(Some(table), &q, 0, || Color::ONE);
                            acc += c.x;
                        }
                    }
                    acc
                })
            })
            .collect();
        for h in hs {
            sink += h.join().unwrap_or(0.0);
        }
    });
    (t0.elapsed().as_secs_f64(), sink)
}

fn main() -> ExitCode {
    let args = args::bench_args();
    let (mut queries, mut cubes, mut work_ns, mut repeat, mut threads) =
        (2_000_000usize, 20_000usize, 300.0f64, 3usize, 1usize);
    let mut separate = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut num = |name: &str| args::number(&mut it, name, true);
        let r = match a.as_str() {
            "--queries" => num("--queries").map(|v| queries = (v as usize).max(1)),
            "--cubes" => num("--cubes").map(|v| cubes = (v as usize).max(1)),
            "--work" => num("--work").map(|v| work_ns = v),
            "--repeat" => num("--repeat").map(|v| repeat = (v as usize).max(1)),
            "--threads" => num("--threads").map(|v| threads = (v as usize).clamp(1, 256)),
            "--separate" => {
                separate = true;
                Ok(())
            }
            other => Err(format!("unknown argument {other}")),
        };
        if let Err(e) = r {
            eprintln!("vistable: {e}");
            return ExitCode::FAILURE;
        }
    }
    // Calibrate the work loop: iterations per nanosecond.
    let cal = 20_000_000u64;
    let t0 = Instant::now();
    std::hint::black_box(work(cal, 1.0));
    let per_ns = cal as f64 / (t0.elapsed().as_secs_f64() * 1e9);
    let iters = (work_ns * per_ns).round() as u64;
    let pts: Vec<Vec<DVec3>> = (0..threads)
        .map(|k| points(cubes, queries, k as u32))
        .collect();
    // The work alone, on as many threads.
    let mut alone = f64::INFINITY;
    for _ in 0..repeat {
        let t0 = Instant::now();
        std::thread::scope(|s| {
            for p in &pts {
                s.spawn(move || {
                    let mut acc = 0.0;
                    for i in 0..p.len() {
                        acc += work(iters, i as f64);
                    }
                    std::hint::black_box(acc)
                });
            }
        });
        alone = alone.min(t0.elapsed().as_secs_f64());
    }
    let mut best = f64::INFINITY;
    for _ in 0..repeat {
        // Fresh tables each pass: every pass learns its cubes again.
        let tables: Vec<VisTable> = (0..if separate { threads } else { 1 })
            .map(|_| VisTable::default())
            .collect();
        let (t, sink) = run(&tables, &pts, iters);
        std::hint::black_box(sink);
        best = best.min(t);
    }
    println!(
        "threads {threads} ({}), {queries} queries each over {cubes} cubes, work {work_ns} ns: \
         {:.1} ns a query ({:.1} ns with the work)",
        if separate {
            "a table each"
        } else {
            "one table"
        },
        (best - alone) * 1e9 / queries as f64,
        best * 1e9 / queries as f64
    );
    ExitCode::SUCCESS
}
