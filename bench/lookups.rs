//! lookups: what one irradiance-cache lookup costs, on the values of a real ambient file.
//!
//! ```text
//! cargo bench --bench lookups -- FILE.amb [--aa A] [--lookups N] [--repeat R] [--threads T]
//!     [--separate]
//! ```
//!
//! Reads the values of a Radiance ambient file (as `-af` writes it), files them in an
//! [`AmbientCache`] of accuracy `--aa` (default 0.15) whose base cell is made from the
//! smallest radius, and times `--lookups` lookups (default 2,000,000): each at a value's
//! position moved by up to its reach in a random direction, of the value's level plus one
//! (as the lookups of its own hemisphere's rays are), taking every value the cache hands on.
//! Prints the nanoseconds per lookup (the fastest of `--repeat` passes, default 3) and the
//! values handed on per lookup, so that a change of the cache's layout can be measured
//! apart from the rest of a render. With `--threads T` (default 1), T threads look up at
//! once, each its own rotation of the same points, and the time is the wall time of T
//! lookups each: above the one-thread figure by what the threads cost each other (lines of
//! the cache that every lookup writes move between cores). `--separate` gives each thread
//! a cache of its own holding the same values, as processes have: the difference to the
//! shared figure is what sharing one cache costs.

#[path = "args.rs"]
mod args;

use glam::DVec3;
use std::process::ExitCode;
use std::time::Instant;
use tessera::ambient::cache::{AmbientCache, CachedValue};
use tessera::ambient::radfile::read_file;

fn main() -> ExitCode {
    let args = args::bench_args();
    let mut file = None;
    let (mut aa, mut lookups, mut repeat, mut threads) = (0.15f64, 2_000_000usize, 3usize, 1usize);
    let mut separate = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut num = |name: &str| args::number(&mut it, name, false);
        let r = match a.as_str() {
            "--aa" => num("--aa").map(|v| aa = v),
            "--lookups" => num("--lookups").map(|v| lookups = v as usize),
            "--repeat" => num("--repeat").map(|v| repeat = (v as usize).max(1)),
            "--threads" => num("--threads").map(|v| threads = (v as usize).clamp(1, 256)),
            "--separate" => {
                separate = true;
                Ok(())
            }
            f if file.is_none() && !f.starts_with("--") => {
                file = Some(f.to_string());
                Ok(())
            }
            other => Err(format!("unknown argument {other}")),
        };
        if let Err(e) = r {
            eprintln!("lookups: {e}");
            return ExitCode::from(2);
        }
    }
    let Some(file) = file else {
        eprintln!(
            "usage: cargo bench --bench lookups -- FILE.amb [--aa A] [--lookups N] [--repeat R] \
             [--threads T] [--separate]"
        );
        return ExitCode::from(2);
    };
    let records = match read_file(std::path::Path::new(&file)) {
        Ok((_, r, _)) => r,
        Err(e) => {
            eprintln!("lookups: {file}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let vals: Vec<CachedValue> = records
        .iter()
        .map(|r| CachedValue::from_record(r, DVec3::ZERO))
        .collect();
    if vals.is_empty() {
        eprintln!("lookups: {file}: no values");
        return ExitCode::FAILURE;
    }
    let minrad = vals.iter().map(|v| v.rad[0]).fold(f64::INFINITY, f64::min);
    let filed = || {
        let cache = AmbientCache::new(minrad, aa, 1);
        vals.iter().for_each(|v| cache.insert(*v));
        cache
    };
    let t = Instant::now();
    let cache = filed();
    let filing = t.elapsed().as_secs_f64();
    let own: Vec<AmbientCache> = if separate {
        (0..threads).map(|_| filed()).collect()
    } else {
        Vec::new()
    };
    // The lookup points: a fixed pseudo-random sequence (splitmix64).
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<(DVec3, u32)> = (0..lookups)
        .map(|_| {
            let v = &vals[(rnd() * vals.len() as f64) as usize % vals.len()];
            let d = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or(DVec3::X);
            let r = aa * v.rad[1] * v.reach * rnd();
            (v.pos + d * r, v.lvl + 1)
        })
        .collect();
    let mut best = f64::INFINITY;
    let mut handed = 0usize;
    for _ in 0..repeat {
        let t = Instant::now();
        let counts: Vec<usize> = std::thread::scope(|scope| {
            let runs: Vec<_> = (0..threads)
                .map(|i| {
                    let (cache, points) = (own.get(i).unwrap_or(&cache), &points);
                    scope.spawn(move || {
                        let mut handed = 0usize;
                        let start = i * points.len() / threads;
                        let (a, b) = points.split_at(start);
                        for &(p, level) in b.iter().chain(a) {
                            cache.for_each_near(
                                p,
                                |l, _| l <= level,
                                |v| {
                                    std::hint::black_box(v);
                                    handed += 1;
                                },
                            );
                        }
                        handed
                    })
                })
                .collect();
            runs.into_iter().map(|r| r.join().unwrap_or(0)).collect()
        });
        best = best.min(t.elapsed().as_secs_f64());
        handed = counts.iter().sum::<usize>() / threads;
    }
    println!(
        "{} values from {file}, -aa {aa}: filed in {:.1} ms; {lookups} lookups on each of \
         {threads} thread(s){}: {:.0} ns each (fastest of {repeat}), {:.1} values handed on per \
         lookup",
        vals.len(),
        filing * 1e3,
        if separate { ", each its own cache" } else { "" },
        best / lookups as f64 * 1e9,
        handed as f64 / lookups as f64
    );
    ExitCode::SUCCESS
}
