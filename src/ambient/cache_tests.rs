//! Tests of the irradiance cache (`cache.rs`).

use super::*;

fn value(pos: DVec3, rad: f64, reach: f64, seq: u64) -> CachedValue {
    CachedValue {
        id: ValueId { origin: 1, seq },
        pos,
        n: DVec3::Z,
        u: DVec3::X,
        lvl: 0,
        weight: 1.0,
        rad: [rad, rad],
        gpos: [0.0; 2],
        gdir: [0.0; 2],
        corral: 0,
        val: Color::splat(1.0),
        reach,
        share: 1.0,
    }
}

/// Values no renderer makes (infinite or astronomically large radii, non-finite
/// positions or light) are refused and counted, at once: filing one would touch
/// unboundedly many cells.
#[test]
fn absurd_values_are_refused() {
    let c = AmbientCache::new(0.01, 0.2, 1).with_max_radius(20.0);
    c.insert(value(DVec3::ZERO, 0.5, 1.0, 1));
    for (i, v) in [
        value(DVec3::ZERO, 21.0, 1.0, 7),
        value(DVec3::ZERO, f64::INFINITY, 1.0, 2),
        value(DVec3::ZERO, 1e300, 1.0, 3),
        value(DVec3::ZERO, f64::NAN, 1.0, 4),
        value(DVec3::new(f64::INFINITY, 0.0, 0.0), 0.5, 1.0, 5),
        CachedValue {
            val: Color::new(f64::NAN, 0.0, 0.0),
            ..value(DVec3::ZERO, 0.5, 1.0, 6)
        },
    ]
    .into_iter()
    .enumerate()
    {
        c.insert(v);
        assert_eq!(c.refused(), i as u64 + 1);
    }
    assert_eq!(c.len(), 1);
    let mut found = 0;
    c.for_each_near(DVec3::ZERO, |_, _| true, |_| found += 1);
    assert_eq!(found, 1);
}

/// Every lookup finds exactly the values whose reach sphere holds the point (brute force
/// over random values of many sizes, positions on and near cell boundaries), and `all`
/// returns each value once although it is filed in up to eight cells.
#[test]
fn lookups_find_exactly_the_values_in_reach() {
    exact_lookups(DVec3::ZERO, 0.01, 1.0);
}

/// The same far from the origin, where the single-precision test is not trusted (cells
/// beyond `NEAR_RANGE` cell sizes) or only just is.
#[test]
fn lookups_far_from_the_origin_find_exactly_the_values_in_reach() {
    // Cells of about 10⁻⁵: 10¹¹ cell sizes from the origin.
    exact_lookups(DVec3::new(1e6, -3e5, 2e5), 1e-5, 1e-3);
    // Cells of about 10⁻²: 10⁸.
    exact_lookups(DVec3::new(1e6, 1e6, -1e6), 0.01, 1.0);
}

/// The single-precision test's rounding stays well inside its margin wherever it is
/// trusted: points and centres of cells up to `NEAR_RANGE` cell sizes from the origin,
/// of sizes 2⁻³⁰ to 2³⁰; beyond, it is not trusted.
#[test]
fn the_single_precision_test_errs_less_than_its_margin() {
    let mut rnd = crate::hash::test_uniform(17);
    let mut worst = 0f64;
    for _ in 0..200_000 {
        let s = 2f64.powi((rnd() * 60.0) as i32 - 30);
        let k = |r: f64| ((10f64.powf(r * 9.0) as i64) as f64) * if r < 0.5 { -1.0 } else { 1.0 };
        let key: Key = (0, k(rnd()) as i64, k(rnd()) as i64, k(rnd()) as i64);
        let corner = DVec3::new(key.1 as f64, key.2 as f64, key.3 as f64);
        let p = (corner + DVec3::new(rnd(), rnd(), rnd())) * s;
        let c = (corner + DVec3::new(rnd(), rnd(), rnd()) * 2.0 - DVec3::splat(0.5)) * s;
        if (p / s).floor() != corner {
            continue;
        }
        let (q, e) = (local(&key, p / s), local(&key, c / s));
        let d = [e[0] - q[0], e[1] - q[1], e[2] - q[2]];
        let single = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) as f64;
        let exact = (p - c).length_squared() / (s * s);
        worst = worst.max((single - exact).abs());
        assert_eq!(margin(&key), NEAR_MARGIN);
    }
    assert!(worst < NEAR_MARGIN as f64 / 4.0, "rounding {worst}");
    assert_eq!(margin(&(0, 2_000_000_000, 0, 0)), f32::INFINITY);
    assert_eq!(margin(&(3, 0, -2_000_000_000, 5)), f32::INFINITY);
    assert_eq!(margin(&(3, 0, 0, i64::MIN)), f32::INFINITY);
}

/// Values spread over a cube of side `4·scale` about `offset`, of radii from
/// `0.01·scale` to `2·scale`.
fn exact_lookups(offset: DVec3, minrad: f64, scale: f64) {
    let aa = 0.2;
    let cache = AmbientCache::new(minrad, aa, 1);
    let mut rng = crate::render::sampler::Sampler::for_pixel(0, 1, 2, 3);
    let mut rnd = || rng.uniform();
    let mut vals = Vec::new();
    for seq in 0..400 {
        // Positions snapped near multiples of the base cell size half of the time.
        let mut pos = DVec3::new(rnd(), rnd(), rnd()) * 4.0 - DVec3::splat(2.0);
        if seq % 2 == 0 {
            pos = (pos / 0.004).round() * 0.004 + DVec3::splat(1e-12 * (rnd() - 0.5));
        }
        let pos = pos * scale + offset;
        let v = value(pos, (0.01 + rnd() * rnd() * 2.0) * scale, 1.0 + rnd(), seq);
        cache.insert(v);
        vals.push(v);
    }
    for _ in 0..3000 {
        let v = vals[(rnd() * vals.len() as f64) as usize % vals.len()];
        let r = aa * v.rad[0] * v.reach;
        // Points inside the value's reach, some right at its edge.
        let dir = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or(DVec3::X);
        let t = if rnd() < 0.3 { 0.999_999 } else { rnd() };
        let p = v.pos + dir * (r * t);
        let mut found = Vec::new();
        cache.for_each_near(p, |_, _| true, |c| found.push(c.id.seq));
        found.sort_unstable();
        let mut want: Vec<u64> = vals
            .iter()
            .filter(|c| {
                let rr = aa * c.rad[0] * c.reach;
                (p - c.pos).length_squared() < rr * rr
            })
            .map(|c| c.id.seq)
            .collect();
        want.sort_unstable();
        assert_eq!(found, want, "at {p}");
    }
    let mut all: Vec<u64> = cache.all().iter().map(|c| c.id.seq).collect();
    all.sort_unstable();
    assert_eq!(all, (0..400).collect::<Vec<_>>());
    assert_eq!(cache.len(), 400);
}

#[test]
fn lookups_hand_on_only_usable_values_in_filing_order() {
    // Values of levels 0-3 and weights 0.1-1 around one point, shared and private: the
    // level-and-weight test sees each value's own level and weight, and the values that
    // pass come in the order of an unfiltered lookup.
    let cache = AmbientCache::new(0.01, 0.2, 1);
    let mut rng = crate::render::sampler::Sampler::for_pixel(4, 5, 6, 7);
    let mut rnd = || rng.uniform();
    let mut make = |seq: u64| {
        let pos = DVec3::new(rnd(), rnd(), rnd()) * 0.2;
        let mut v = value(pos, 0.5 + rnd(), 1.0, seq);
        v.lvl = (seq % 4) as u32;
        v.weight = 0.1 + 0.9 * rnd();
        v
    };
    let vals: Vec<CachedValue> = (0..300).map(&mut make).collect();
    vals.iter().for_each(|v| cache.insert(*v));
    begin_private();
    let own: Vec<CachedValue> = (300..400).map(&mut make).collect();
    own.iter().for_each(|v| cache.insert(*v));
    let by_seq = |seq: u64| {
        let k = seq as usize;
        if k < 300 {
            vals[k]
        } else {
            own[k - 300]
        }
    };
    let p = DVec3::splat(0.1);
    let mut every = Vec::new();
    cache.for_each_near(p, |_, _| true, |c| every.push(c.id.seq));
    assert!(every.len() > 200, "{} values in reach", every.len());
    for (level, rweight) in [(0, 1.0), (1, 0.5), (2, 0.3), (3, 0.9)] {
        let usable = |lvl: u32, w: f64| lvl < level || (lvl == level && w >= 0.9 * rweight);
        let mut seen = Vec::new();
        cache.for_each_near(p, usable, |c| {
            assert!(usable(c.lvl, c.weight), "value {} handed on", c.id.seq);
            seen.push(c.id.seq);
        });
        let want: Vec<u64> = every
            .iter()
            .copied()
            .filter(|&q| {
                let v = by_seq(q);
                usable(v.lvl, v.weight)
            })
            .collect();
        assert_eq!(seen, want, "level {level}, weight {rweight}");
    }
    assert_eq!(end_private().len(), 100);
}

/// Values of several ambient levels filed in one cell, interleaved, are handed on in the
/// order they were filed whatever levels the lookup may use (the cell keeps them in a span
/// per level), also when more are in reach than a cell hands on without allocating; a
/// level the lookup may not use, or a weight below its threshold, is left out.
#[test]
fn values_of_several_levels_come_in_filing_order() {
    for count in [7u64, 150] {
        let c = AmbientCache::new(0.01, 0.2, 1);
        for seq in 0..count {
            // Same radius (so the same grid level and cell), levels 0..3 interleaved.
            let p = DVec3::new(0.001 * seq as f64 / count as f64, 0.0, 0.0);
            c.insert(CachedValue {
                lvl: ((seq * 7) % 4) as u32,
                weight: if seq % 5 == 0 { 0.1 } else { 1.0 },
                ..value(p, 0.5, 1.0, seq)
            });
        }
        for (level, least) in [(3u32, 0.0), (2, 0.0), (1, 0.5), (0, 0.0)] {
            let usable = |l: u32, w: f64| l < level || (l == level && w >= least);
            let mut got = Vec::new();
            c.for_each_near(DVec3::ZERO, usable, |v| got.push(v.id.seq));
            let want: Vec<u64> = (0..count)
                .filter(|s| usable(((s * 7) % 4) as u32, if s % 5 == 0 { 0.1 } else { 1.0 }))
                .collect();
            assert_eq!(got, want, "{count} values, lookup at level {level}");
        }
    }
}
