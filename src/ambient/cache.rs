//! The in-memory irradiance cache shared by all render threads.
//!
//! Values are kept in a multi-level hashed grid: a value of radius `r` lives at the level
//! whose cell size is the smallest power-of-four multiple of the base size that is at least
//! twice its reach (`aa·reach·r`), filed (as a shared pointer) in every cell of that level its
//! reach sphere touches — at most 2×2×2. A lookup at point P reads, per level in use, the one
//! cell holding P: every value whose reach covers P is there; per-level occupancy bits let
//! it skip, without a lock or a probe, levels with nothing filed near P. A cell keeps its
//! values in spans of one ambient level each, and per value its position (relative to the
//! cell's corner) and squared reach in single precision, four values to a cache line; a
//! lookup reads only the spans of the levels it may use, tests four values at a time,
//! tests again in double precision those within rounding of their reach (so it sees
//! exactly the values a double-precision test would), prefetches the values in reach
//! together (so that their cache misses overlap), and hands on, in filing order, those
//! whose weight lets the lookup use them.
//! The grid is split into shards, each behind its own lock ([`super::sharded`]): lookups
//! take short read holds on the shards they touch (no global lock; a reader writes only a
//! cache line of its thread's own, so threads looking up in the same shards do not move
//! lines between their cores), inserts take the write lock of each shard their cells lie
//! in, once. A shard holds blocks of 8×8×8 cells of a level.
//!
//! A thread may make its values **privately** ([`begin_private`] … [`end_private`]): they
//! are then kept in a thread-local list that only its own lookups see (after the shared
//! cells), and the caller files them later with [`AmbientCache::commit`], in an order of
//! its choosing. `ttrace` traces each ray so and commits a wave's values in input order,
//! which makes its values independent of the thread count.

use super::sharded::Sharded;
use super::ValueId;
use crate::color::Color;
use crate::hash::fx_mix;
use glam::DVec3;
use std::cell::RefCell;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

#[path = "cache_cell.rs"]
mod cell;
use cell::{At, CellList, Tag};

/// The cells of level `l` from cell `lo` to cell `hi` (corners, in cell units).
fn cells(l: u32, lo: DVec3, hi: DVec3) -> impl Iterator<Item = Key> {
    let (lo, hi) = (lo.as_i64vec3(), hi.as_i64vec3());
    (lo.x..=hi.x).flat_map(move |x| {
        (lo.y..=hi.y).flat_map(move |y| (lo.z..=hi.z).map(move |z| (l, x, y, z)))
    })
}

/// The rounding the single-precision reach test of [`cell::CellList::scan`] allows for, in
/// squared cell sizes: a value nearer to the edge of its reach sphere than this is tested
/// again in double precision. The coordinates it compares lie within two cell sizes of the cell's
/// corner, where single precision is good to about 2·10⁻⁶ of a squared cell size.
const NEAR_MARGIN: f32 = 1e-5;

/// Beyond this many cell sizes from the origin, the single-precision test is not trusted
/// and every value is tested in double precision.
const NEAR_RANGE: f64 = 1e9;

/// `q` (a point in units of the level's cell size, `p / s` as [`AmbientCache::key_at`]
/// divides) relative to the corner of cell `key`, in single precision.
#[inline(always)]
fn local(key: &Key, q: DVec3) -> [f32; 3] {
    [
        (q.x - key.1 as f64) as f32,
        (q.y - key.2 as f64) as f32,
        (q.z - key.3 as f64) as f32,
    ]
}

/// `q` in the cells of level `l` from the base level's: `q · 2^-(l·LEVEL_STEP)`, exactly
/// (for `q` far from the subnormals).
#[inline(always)]
fn scale_down(q: DVec3, l: u32) -> DVec3 {
    q * (1.0 / (1u64 << (l * LEVEL_STEP)) as f64)
}

/// The cell of level `l` holding the point `q` (in cells of that level,
/// [`AmbientCache::in_cells`]), and where the point lies in it ([`cell::CellList::scan`]).
#[inline(always)]
fn cell_of(l: u32, q: DVec3) -> (Key, At) {
    let key = (
        l,
        q.x.floor() as i64,
        q.y.floor() as i64,
        q.z.floor() as i64,
    );
    let at = At {
        q: local(&key, q),
        margin: margin(&key),
    };
    (key, at)
}

/// The margin of the single-precision test in cell `key` ([`NEAR_MARGIN`], or infinite
/// where the cell lies beyond [`NEAR_RANGE`]).
fn margin(key: &Key) -> f32 {
    let far = key
        .1
        .unsigned_abs()
        .max(key.2.unsigned_abs())
        .max(key.3.unsigned_abs());
    if far as f64 > NEAR_RANGE {
        f32::INFINITY
    } else {
        NEAR_MARGIN
    }
}

/// The radius a value is filed with, in units of `-aa`: its largest radius times its reach
/// and share reach (its reach sphere is `aa` times this).
#[inline(always)]
fn filed_radius(v: &CachedValue) -> f64 {
    v.rad[1].max(v.rad[0]) * v.reach.max(1.0) * v.share.max(1.0)
}

/// Whether `p` is inside the reach sphere `r` (centre and squared radius).
#[inline(always)]
fn within(p: DVec3, r: &[f64; 4]) -> bool {
    let d = [p.x - r[0], p.y - r[1], p.z - r[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r[3]
}

/// Values a thread made privately, filed like the shared cells (by level and cell) so
/// that a lookup reads one cell per level.
#[derive(Default)]
struct Private {
    vals: Vec<CachedValue>,
    /// Per cell: the indices in `vals` of the values filed there.
    cells: HashMap<Key, CellList<u32>, BuildHasherDefault<KeyHasher>>,
    /// Levels in use (bit l).
    levels: u64,
}

thread_local! {
    /// The values this thread made privately ([`begin_private`]), None when it is not.
    static PRIVATE: RefCell<Option<Private>> = const { RefCell::new(None) };
}

/// From now on this thread's new values are its own ([`end_private`] hands them over).
pub fn begin_private() {
    PRIVATE.with(|p| *p.borrow_mut() = Some(Private::default()));
}

/// The values this thread made since [`begin_private`], in the order it made them; the
/// thread files values in the shared cells again.
pub fn end_private() -> Vec<CachedValue> {
    PRIVATE.with(|p| p.borrow_mut().take().map(|p| p.vals).unwrap_or_default())
}

/// Receives every value this process computes (e.g. to append it to a shared log).
pub trait ValueSink: Send + Sync {
    /// Called once per new value, from the thread that computed it.
    fn accept(&self, v: &CachedValue);
    /// Called when a lookup found no value, before a new one is computed: a sink that
    /// shares values with other processes may insert theirs now; returns how many it added
    /// (the lookup is then retried).
    fn refresh(&self) -> u64 {
        0
    }
}

/// Largest interpolation reach of a value ([`CachedValue::reach`]), in units of `-aa`.
pub const REACH_MAX: f64 = 2.0;

const SHARDS: usize = 64;
/// Levels of the grid: each one's cells are `2^LEVEL_STEP` times as wide as the one's
/// below (four times: a lookup reads one cell of each level in use, half as many as with
/// levels twice apart, each holding about 2.5 times the values).
const LEVEL_STEP: u32 = 2;
const MAX_LEVELS: u32 = 30;
const _: () = assert!(MAX_LEVELS * LEVEL_STEP < 64);
/// Words of a level's occupancy bits ([`AmbientCache::occupied`]): 32,768 bits, 4 KiB.
const OCCUPIED_WORDS: usize = 512;

/// The word and bit of cell `key` in the occupancy bits.
#[inline(always)]
fn occupancy(key: &Key) -> (usize, u64) {
    let h = fx_mix(fx_mix(fx_mix(0, key.1 as u64), key.2 as u64), key.3 as u64);
    let bits = (h >> 49) as usize; // 15 bits
    (
        key.0 as usize * OCCUPIED_WORDS + bits / 64,
        1u64 << (bits % 64),
    )
}

/// One cached value in the renderer's frame (relative to the scene origin).
#[derive(Clone, Copy, Debug)]
pub struct CachedValue {
    /// Identity.
    pub id: ValueId,
    /// Position (relative frame).
    pub pos: DVec3,
    /// Unit normal.
    pub n: DVec3,
    /// Unit first tangent (second is `n × u`).
    pub u: DVec3,
    /// Ambient level.
    pub lvl: u32,
    /// Parent ray weight.
    pub weight: f64,
    /// Radii along u and v.
    pub rad: [f64; 2],
    /// Positional gradient along u and v (per channel-independent scale: relative to `val`).
    pub gpos: [f64; 2],
    /// Rotational gradient about u and v (relative to `val`).
    pub gdir: [f64; 2],
    /// Light-leak flags: bit s set when a wall stands inside the value's reach in azimuth
    /// sector s (32 sectors of the (u, n × u) frame; see `compute::corral_sector`).
    pub corral: u32,
    /// Value (mean incoming radiance over the cosine-weighted hemisphere).
    pub val: Color,
    /// Interpolation reach (≥ 1, at most [`REACH_MAX`]): the value serves
    /// lookups out to `reach · aa` in its normalised distance, not only `aa`. It is the room
    /// the Hessian's radii leave beyond the radii used (which `-ar`'s largest radius and the
    /// 1:2 aspect limit may have shrunk); 1 for values from Radiance files.
    pub reach: f64,
    /// Share reach (≥ 1, at most [`super::settings::SHARE_LIMIT`]): how much farther than its
    /// reach the value may serve a lookup where the indirect light is a small part of what
    /// the surface sends (see `compute::share_factor`); 1 in Radiance's own rule.
    pub share: f64,
}

type Key = (u32, i64, i64, i64);

/// A fast hasher for grid keys (a multiply–rotate mix of the four integers, as FxHash): the
/// standard SipHash took a sixth of an `-ab 2` render's time in lookups. The keys are cell
/// coordinates, not input an adversary chooses.
#[derive(Default)]
struct KeyHasher(u64);

impl KeyHasher {
    #[inline]
    fn mix(&mut self, x: u64) {
        self.0 = fx_mix(self.0, x);
    }
}

impl Hasher for KeyHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.mix(b as u64);
        }
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.mix(i as u64);
    }
    #[inline]
    fn write_i64(&mut self, i: i64) {
        self.mix(i as u64);
    }
}

type Grid = HashMap<Key, CellList<Arc<CachedValue>>, BuildHasherDefault<KeyHasher>>;

/// Counters written at every insert, kept off the line the lookups read.
#[derive(Default)]
#[repr(align(128))]
struct Written {
    count: AtomicU64,
    seq: AtomicU64,
    refused: AtomicU64,
}

/// The shared cache.
pub struct AmbientCache {
    base: f64,
    /// `1 / base`: a point's coordinates in cells of level `l` are `p · inv_base · 2^-l`
    /// (multiplications, the last exact), the same for filing and for lookups.
    inv_base: f64,
    aa: f64,
    shards: Sharded<Grid>,
    levels_used: AtomicU64,
    /// Per level, a bit per hash of a cell's coordinates, set when a value is filed in a
    /// cell of that hash: a lookup skips a level whose bit is clear without taking a lock
    /// or reading the grid (most levels hold nothing near a given point).
    occupied: Box<[AtomicU64]>,
    origin_id: u64,
    max_level_seen: AtomicU32,
    sink: OnceLock<Box<dyn ValueSink>>,
    /// Values held, ids handed out and values refused by [`AmbientCache::insert`].
    written: Written,
    /// Largest radius accepted ([`AmbientCache::with_max_radius`]).
    max_rad: f64,
}

/// The shard of a grid cell: cells of a level are grouped in blocks of 8×8×8 per shard, so
/// the 2×2×2 cells of a lookup usually share one shard (one read lock instead of eight).
fn shard_of(k: &Key) -> usize {
    let h = (k.0 as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(((k.1 >> 3) as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add(((k.2 >> 3) as u64).wrapping_mul(0x1656_67B1_9E37_79F9))
        .wrapping_add(((k.3 >> 3) as u64).wrapping_mul(0x27D4_EB2F_1656_67C5));
    ((h >> 32) as usize) % SHARDS
}

impl AmbientCache {
    /// A cache for values with radii of at least `minrad`, accuracy `aa`; `origin_id`
    /// identifies this process in value ids.
    pub fn new(minrad: f64, aa: f64, origin_id: u64) -> AmbientCache {
        let base = (2.0 * aa * minrad).max(1e-9);
        AmbientCache {
            base,
            inv_base: 1.0 / base,
            aa,
            shards: Sharded::new(SHARDS, Grid::default),
            levels_used: AtomicU64::new(0),
            occupied: crate::zeroed::atomic_u64s(MAX_LEVELS as usize * OCCUPIED_WORDS),
            origin_id,
            max_level_seen: AtomicU32::new(0),
            sink: OnceLock::new(),
            written: Written::default(),
            max_rad: f64::INFINITY,
        }
    }

    /// Refuse values with a radius above `r` (the calculation passes a bound from the scene's
    /// size: no renderer makes larger radii, so a larger one comes from a damaged store).
    pub fn with_max_radius(mut self, r: f64) -> AmbientCache {
        self.max_rad = r;
        self
    }

    /// Send every value this process computes from now on to `sink` (set once).
    pub fn set_sink(&self, sink: Box<dyn ValueSink>) -> bool {
        self.sink.set(sink).is_ok()
    }

    /// Ask the sink for values other processes made (see [`ValueSink::refresh`]).
    pub fn refresh(&self) -> u64 {
        self.sink.get().map(|s| s.refresh()).unwrap_or(0)
    }

    /// The id origin of values computed by this process.
    pub fn origin_id(&self) -> u64 {
        self.origin_id
    }

    /// Values refused by [`AmbientCache::insert`] (non-finite or absurd).
    pub fn refused(&self) -> u64 {
        self.written.refused.load(Ordering::Relaxed)
    }

    /// Number of values held.
    pub fn len(&self) -> u64 {
        self.written.count.load(Ordering::Relaxed)
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A fresh value id of this process.
    pub fn next_id(&self) -> ValueId {
        ValueId {
            origin: self.origin_id,
            seq: self.written.seq.fetch_add(1, Ordering::Relaxed),
        }
    }

    fn level_for(&self, rad1: f64) -> u32 {
        let reach = 2.0 * self.aa * rad1;
        let mut l = 0;
        let mut size = self.base;
        while size < reach && l < MAX_LEVELS - 1 {
            size *= (1u64 << LEVEL_STEP) as f64;
            l += 1;
        }
        l
    }

    fn cell_size(&self, level: u32) -> f64 {
        self.base * (1u64 << (level * LEVEL_STEP)) as f64
    }

    /// `p` in units of the cells of level `l`. Monotone in each coordinate (a product by a
    /// constant, correctly rounded, then by an exact power of two), so the cell of a point
    /// inside a padded sphere lies among the cells the sphere's bounds give.
    #[inline(always)]
    fn in_cells(&self, l: u32, p: DVec3) -> DVec3 {
        scale_down(p * self.inv_base, l)
    }

    /// Insert a value: it is filed in every cell of its level that its reach sphere
    /// touches (at most 2×2×2, as the cells are at least twice the reach), so a lookup reads
    /// one cell per level.
    ///
    /// A value whose reach is not finite or exceeds the largest level's cells, whose radius
    /// exceeds the bound of [`AmbientCache::with_max_radius`] (radii a renderer never makes:
    /// a damaged or crafted store's) or whose position or light is not finite is refused and
    /// counted ([`AmbientCache::refused`]): filing it would touch
    /// unboundedly many cells.
    pub fn insert(&self, v: CachedValue) {
        let r = filed_radius(&v);
        let l = self.level_for(r);
        let rr = self.aa * r;
        let s = self.cell_size(l);
        let sane = rr.is_finite()
            && rr > 0.0
            && v.rad[0].max(v.rad[1]) <= self.max_rad
            && rr <= 0.5 * s
            && v.pos.is_finite()
            && v.val.is_finite()
            && v.val.min_element() >= 0.0;
        if !sane {
            self.written.refused.fetch_add(1, Ordering::Relaxed);
            return;
        }
        // Padded so that rounding never leaves out a cell the sphere touches.
        let pad = rr * (1.0 + 1e-6) + 1e-9 * s;
        let lo = self.in_cells(l, v.pos - DVec3::splat(pad)).floor();
        let hi = self.in_cells(l, v.pos + DVec3::splat(pad)).floor();
        let tag = Tag { lvl: v.lvl };
        let (c, r2) = (self.in_cells(l, v.pos), ((rr / s) * (rr / s)) as f32);
        let near = |key: &Key| {
            let [x, y, z] = local(key, c);
            [x, y, z, r2]
        };
        let kept = PRIVATE.with(|p| match p.try_borrow_mut().ok().as_deref_mut() {
            Some(Some(own)) => {
                let k = own.vals.len() as u32;
                own.vals.push(v);
                own.levels |= 1u64 << l;
                for key in cells(l, lo, hi) {
                    own.cells.entry(key).or_default().push(near(&key), tag, k);
                }
                true
            }
            _ => false,
        });
        if kept {
            return;
        }
        let shared = Arc::new(v);
        // Usually 2×2×2 cells or fewer, in one shard: each shard's lock is taken once.
        let mut keys: Vec<(usize, Key)> = cells(l, lo, hi)
            .map(|key| {
                let (w, bit) = occupancy(&key);
                if self.occupied[w].load(Ordering::Relaxed) & bit == 0 {
                    self.occupied[w].fetch_or(bit, Ordering::Relaxed);
                }
                (shard_of(&key), key)
            })
            .collect();
        keys.sort_by_key(|&(sh, _)| sh);
        for group in keys.chunk_by(|a, b| a.0 == b.0) {
            let mut shard = self.shards.write(group[0].0);
            for (_, key) in group {
                shard
                    .entry(*key)
                    .or_default()
                    .push(near(key), tag, Arc::clone(&shared));
            }
        }
        // Written only when they change: every lookup reads them.
        if self.levels_used.load(Ordering::Relaxed) & (1u64 << l) == 0 {
            self.levels_used.fetch_or(1u64 << l, Ordering::Relaxed);
        }
        if self.max_level_seen.load(Ordering::Relaxed) < l {
            self.max_level_seen.fetch_max(l, Ordering::Relaxed);
        }
        self.written.count.fetch_add(1, Ordering::Relaxed);
        if v.id.origin == self.origin_id {
            if let Some(s) = self.sink.get() {
                s.accept(&v);
            }
        }
    }

    /// Whether `p` lies inside value `v`'s reach sphere, in double precision (the radius
    /// [`AmbientCache::insert`] files it with).
    fn within(&self, p: DVec3, v: &CachedValue) -> bool {
        let rr = self.aa * filed_radius(v);
        within(p, &[v.pos.x, v.pos.y, v.pos.z, rr * rr])
    }

    /// The cell of level `l` holding `p`.
    fn key_at(&self, l: u32, p: DVec3) -> Key {
        cell_of(l, self.in_cells(l, p)).0
    }

    /// Call `f` for every value whose reach sphere (radius `aa·reach·max(rad)`) holds `p`
    /// and whose level and weight `usable` accepts, in the order of their levels and, within
    /// a level, of their filing.
    #[inline]
    pub fn for_each_near(
        &self,
        p: DVec3,
        usable: impl Fn(u32, f64) -> bool,
        mut f: impl FnMut(&CachedValue),
    ) {
        let used = self.levels_used.load(Ordering::Relaxed);
        let highest = self.max_level_seen.load(Ordering::Relaxed);
        let q0 = p * self.inv_base;
        // The levels in use, finest first.
        let mut levels = used & (u64::MAX >> (63 - highest.min(63)));
        while levels != 0 {
            let l = levels.trailing_zeros();
            levels &= levels - 1;
            let (key, at) = cell_of(l, scale_down(q0, l));
            let (w, bit) = occupancy(&key);
            if self.occupied[w].load(Ordering::Relaxed) & bit == 0 {
                continue;
            }
            let grid = self.shards.read(shard_of(&key));
            if let Some(cell) = grid.get(&key) {
                cell.scan(
                    at,
                    &usable,
                    (
                        |v: &Arc<CachedValue>| self.within(p, v),
                        |v: &Arc<CachedValue>| v.weight,
                    ),
                    |v| crate::prefetch::prefetch::<CachedValue>(&**v),
                    |v| f(v),
                );
            }
        }
        // This thread's private values, filed and tested the same way.
        PRIVATE.with(|pv| {
            let Ok(own) = pv.try_borrow() else { return };
            let Some(own) = own.as_ref() else { return };
            let mut levels = own.levels;
            while levels != 0 {
                let l = levels.trailing_zeros();
                levels &= levels - 1;
                let (key, at) = cell_of(l, scale_down(q0, l));
                if let Some(cell) = own.cells.get(&key) {
                    cell.scan(
                        at,
                        &usable,
                        (
                            |&k: &u32| self.within(p, &own.vals[k as usize]),
                            |&k: &u32| own.vals[k as usize].weight,
                        ),
                        |&k| crate::prefetch::prefetch::<CachedValue>(&own.vals[k as usize]),
                        |&k| f(&own.vals[k as usize]),
                    );
                }
            }
        });
    }

    /// File values made privately ([`end_private`]) in the shared cells, in the order given.
    pub fn commit(&self, values: Vec<CachedValue>) {
        for v in values {
            self.insert(v);
        }
    }

    /// Every value (for saving), in no particular order.
    pub fn all(&self) -> Vec<CachedValue> {
        let mut out = Vec::with_capacity(self.len() as usize);
        for i in 0..self.shards.len() {
            let shard = self.shards.read(i);
            // Each value once: from the cell holding its position.
            for (key, cell) in shard.iter() {
                for v in cell.values() {
                    if self.key_at(key.0, v.pos) == *key {
                        out.push(**v);
                    }
                }
            }
        }
        out
    }
}

impl CachedValue {
    /// The portable record of this value (absolute coordinates: `origin` is added).
    pub fn to_record(&self, origin: DVec3) -> super::AmbRecord {
        let f = |v: f64| v as f32;
        super::AmbRecord {
            id: self.id,
            pos: self.pos + origin,
            ndir: self.n,
            udir: self.u,
            lvl: self.lvl.min(255) as u8,
            weight: f(self.weight.clamp(1e-6, 1.0)),
            rad: [f(self.rad[0]), f(self.rad[1])],
            gpos: [f(self.gpos[0]), f(self.gpos[1])],
            gdir: [f(self.gdir[0]), f(self.gdir[1])],
            corral: self.corral,
            val: [f(self.val.x), f(self.val.y), f(self.val.z)],
            reach: f(self.reach),
            share: f(self.share),
        }
    }

    /// A cached value from a record (relative coordinates: `origin` is subtracted).
    pub fn from_record(r: &super::AmbRecord, origin: DVec3) -> CachedValue {
        let n = r.ndir.normalize_or_zero();
        let u = (r.udir - r.udir.dot(n) * n).normalize_or_zero();
        CachedValue {
            id: r.id,
            pos: r.pos - origin,
            n,
            u,
            lvl: r.lvl as u32,
            weight: r.weight as f64,
            rad: [r.rad[0] as f64, r.rad[1] as f64],
            gpos: [r.gpos[0] as f64, r.gpos[1] as f64],
            gdir: [r.gdir[0] as f64, r.gdir[1] as f64],
            corral: r.corral,
            val: Color::new(r.val[0] as f64, r.val[1] as f64, r.val[2] as f64),
            reach: if r.reach.is_finite() {
                (r.reach as f64).clamp(1.0, REACH_MAX)
            } else {
                1.0
            },
            share: if r.share.is_finite() {
                (r.share as f64).clamp(1.0, super::settings::SHARE_LIMIT)
            } else {
                1.0
            },
        }
    }
}

#[cfg(test)]
#[path = "cache_tests.rs"]
mod tests;
