//! Shadow-ray reuse at the hits of ambient sample rays (a Tessera addition to Radiance).
//!
//! A new ambient value traces one ray per hemisphere cell, and each ray's hit is lit
//! directly: one or more shadow rays per hit, which is most of an `-ab 1` render's rays. Yet
//! the ray stands for its whole cell: its hit is one random point of the cell's footprint on
//! the surface it reaches (a cell of about 2π/cells steradians, so a footprint of radius
//! about `t·√(2π/cells)/2` at distance `t`, more on oblique surfaces). A shadow ray's answer
//! is as good for any point of that footprint as for the one it was traced from, and the
//! footprints of many values' rays overlap.
//!
//! So, per render thread, the answers of those shadow rays are kept on a grid: a key is the
//! hit object, its side, the light source, and a cube whose side is the power of two at or
//! above the footprint's radius, holding the hit point. A cube whose first `trust` shadow
//! rays agree (all blocked, or all reaching the source; `--amb-shadow-trust`, [`TRUST`] by
//! default) answers later queries with their mean transmission, without a ray; every
//! [`RECHECK`]-th query still traces one, and any disagreement marks the cube as a shadow
//! edge, where every query traces its own ray from then on. What remains is a cube whose
//! small lit (or shadowed) part none of its rays found: a blur of shadow edges within less
//! than the footprint's diameter, which shrinks with the footprint as `-ad` grows. A sample
//! ray's specular descendants (through glass, off a mirror) keep its spread: their
//! footprint is the spread times the whole path's length.
//! Other rays (eye rays and their specular rays, every ray of the uncached `-aa 0`
//! calculation) always trace their shadow rays.
//!
//! The grid lives in a table of 2^[`SLOTS_LOG2`] slots ([`VisTable`]) that the render
//! threads of one calculation share: a process holds one table however many threads render
//! (a worker's tile loops, `tpict -n`), and a cube one thread learnt answers the others. A
//! slot is one word (8 bytes: part of the cube's tag, its counts and its mean transmission)
//! updated with relaxed atomic loads and stores, no locks: two threads updating one slot at
//! once may lose one shadow ray's answer from the running mean, which a single store writes
//! whole with its tag (so a reader always gets a mean of answers the cube saw).
//!
//! The table is set-associative: a cube may sit in any of the [`WAYS`] slots of its set (one
//! 64-byte cache line), and a cube new to a full set takes the slot of the cube that traced
//! the fewest shadow rays (which starts afresh if it comes back). Most cubes are asked about
//! once or twice (a footprint's cube at one of several levels, on a surface few rays reach);
//! a few are asked about hundreds of times (the ceiling above a desk, at the level of the
//! values beside it). With one slot per cube, as before, the rare ones kept evicting the
//! common ones, which then traced their first `trust` rays again: on the office of
//! `bench/realscenes.sh` (`-ab 1`, 256²) 978,532 of 1.74 million queries were such learning
//! rays, against 640,000 had no cube ever been evicted.
//! `ttrace`'s per-ray epochs ([`new_epoch`]) read the shared table but learn in a private
//! table per thread, whose answers go to the shared table in a fixed order ([`end_epoch`],
//! [`learn`]), so that no other thread's rays can evict a ray's cubes and its values stay
//! the same whatever `-n`.

use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use glam::DVec3;

use crate::color::{bright, Color};
use crate::hash::fx_mix;

/// Shadow rays a cube must have traced, all agreeing, before it answers without one, by
/// default (`--amb-shadow-trust`). 4 traces 5% fewer rays on the office of
/// `bench/realscenes.sh` at `-ab 1` with the same errors over the equal-error sweeps, but
/// moves the daylit sensor grid of `tests/ttrace.rs` at `-ab 2` away from rtrace's values
/// (mean per-point difference 0.0033–0.0051 against 0.0011–0.0013 at 8, one point 12%
/// off): 8 stays (docs/ambient.md).
pub const TRUST: u16 = 8;

/// The largest `--amb-shadow-trust` (a slot counts up to 31 traced rays).
pub const TRUST_MAX: u16 = 31;

/// A trusted cube still traces every `RECHECK`-th query it answers.
pub const RECHECK: u16 = 8;

/// Slots of a table (a power of two; 8 bytes each, so 512 KiB).
pub const SLOTS_LOG2: u32 = 16;

/// Slots of a set: the slots one cube may take (one 64-byte cache line).
pub const WAYS: usize = 8;

/// Sets of a table.
const SETS_LOG2: u32 = SLOTS_LOG2 - WAYS.trailing_zeros();

/// Where a shadow query comes from: the cube around the hit of an ambient sample ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VisQuery {
    /// The calculation the answers belong to (answers of another are never reused).
    owner: u64,
    /// Hash of the hit object, its side, the cube's level and coordinates.
    cube: u64,
    /// Agreeing shadow rays a cube needs before it answers without one (1 to
    /// [`TRUST_MAX`]; [`TRUST`] unless [`VisQuery::with_trust`] says otherwise).
    trust: u16,
}

impl VisQuery {
    /// The query for a hit on object `obj` (its back side when `back`) at `point` (relative
    /// frame) by a sample whose footprint has radius `footprint`; None when no cube fits
    /// (zero, subnormal or non-finite footprint or point, coordinates beyond 1e15 cubes).
    ///
    /// The cube's side is the power of two at or above the footprint's radius, found from
    /// the float's exponent bits.
    pub fn new(owner: u64, obj: usize, back: bool, footprint: f64, point: DVec3) -> Option<Self> {
        if !(footprint > 0.0 && footprint.is_finite() && point.is_finite()) {
            return None;
        }
        let bits = footprint.to_bits();
        let exp = ((bits >> 52) & 0x7FF) as i64;
        if exp == 0 {
            return None; // subnormal: no scene is that small
        }
        // 2^(exp-1023) <= footprint < 2^(exp-1022): round up unless an exact power of two.
        let level = exp - 1023 + i64::from(bits & ((1u64 << 52) - 1) != 0);
        if !(-1000..=1000).contains(&level) {
            return None;
        }
        let inv = f64::from_bits(((1023 - level) as u64) << 52);
        let c = point * inv;
        // Far beyond any scene's coordinates: no reuse rather than a saturated key.
        if c.abs().max_element() > 1e15 {
            return None;
        }
        let mut h = fx_mix(owner, obj as u64);
        h = fx_mix(h, (level as u64) << 1 | u64::from(back));
        for x in [c.x, c.y, c.z] {
            h = fx_mix(h, floor_i64(x) as u64);
        }
        Some(VisQuery {
            owner,
            cube: h,
            trust: TRUST,
        })
    }

    /// This query with cubes trusted after `trust` agreeing shadow rays (clamped to 1 ..=
    /// [`TRUST_MAX`]).
    pub fn with_trust(self, trust: u16) -> Self {
        VisQuery {
            trust: trust.clamp(1, TRUST_MAX),
            ..self
        }
    }

    /// The slot tag of this cube toward source `src` (never 0, which marks an empty slot).
    fn tag(&self, src: usize) -> u64 {
        fx_mix(self.cube, src as u64).max(1)
    }
}

/// ⌊x⌋ for |x| <= 1e15 (no libm call on targets without a rounding instruction).
#[inline]
fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i - 1
    } else {
        i
    }
}

/// A table of cubes: per slot, one word.
/// - bits 0–15: the low 16 bits of the cube's tag ([`VisQuery::tag`]);
/// - bits 16–20: the shadow rays traced, up to 31 (past that the mean weighs the last ones
///   most, as a running average of 31);
/// - bits 21–23: the answers given since the last check (modulo [`RECHECK`]);
/// - bits 24–25: [`LIT`] | [`DARK`];
/// - bits 26–63: the running mean of the traced transmissions ([`pack_mean`]: an exponent
///   shared by the three numbers and a 10-bit mantissa each, as a Radiance picture's
///   pixels, rounded to nearest: within 2⁻¹⁰ of the largest of the three).
///
/// One word, so that a slot is read and written whole (its tag and its mean always belong
/// together) in 8 bytes; a fresh slot's state is that of an empty one (all zero), so tag 0
/// needs no meaning of its own. A slot whose cube has traced no ray counts as empty. The
/// set's index is the tag's top bits, so two cubes share a slot unnoticed only when 29 bits
/// of their tags agree.
pub struct VisTable {
    /// The slots, [`WAYS`] more than the sets hold, so that the sets can start on a 64-byte
    /// boundary (`base`): an allocation of that alignment would be zeroed by writing it,
    /// making every page resident, where a plain zeroed one leaves the pages no query
    /// reaches untouched.
    slots: Box<[AtomicU64]>,
    /// The index of the first set's first slot.
    base: usize,
}

/// A shadow ray of the cube reached the source.
const LIT: u64 = 1;
/// A shadow ray of the cube was blocked.
const DARK: u64 = 2;
/// The most shadow rays a slot counts.
const MAX_TRACED: u64 = 31;

/// Whether slot word `w` holds the cube of `tag` (its low 16 bits).
#[inline]
fn holds(w: u64, tag: u64) -> bool {
    w & 0xFFFF == tag & 0xFFFF
}

/// Slot word `w` with its tag bits those of `tag`.
#[inline]
fn retag(w: u64, tag: u64) -> u64 {
    (w & !0xFFFF) | (tag & 0xFFFF)
}

/// The shadow rays slot word `w` counts.
#[inline]
fn traced_in(w: u64) -> u64 {
    (w >> 16) & 0x1F
}
/// Where the mean starts in a slot's word.
const MEAN_SHIFT: u32 = 26;

impl Default for VisTable {
    fn default() -> Self {
        let slots = crate::zeroed::atomic_u64s((1 << SLOTS_LOG2) + WAYS);
        // Slots are 8-byte aligned: 0 to 7 of them lie before the first 64-byte boundary.
        let base = (slots.as_ptr() as usize).wrapping_neg() % 64 / 8;
        VisTable { slots, base }
    }
}

/// Three non-negative finite numbers in 38 bits: a biased exponent `e` (8 bits, 0 for
/// zero) shared by the three, so that the largest lies in [2^(e−127), 2^(e−126)), and a
/// 10-bit mantissa each, `x · 2^(136−e)` rounded to nearest (a negative or NaN number is
/// stored as 0; anything above 2^125 as 2^125).
fn pack_mean(m: [f32; 3]) -> u64 {
    let m = m.map(|x| if x > 0.0 { x.min(2f32.powi(125)) } else { 0.0 });
    let largest = m[0].max(m[1]).max(m[2]);
    let mut e = u64::from((largest.to_bits() >> 23) & 0xFF);
    if e < 10 {
        return 0; // below 2^-117: no transmission
    }
    let scaled = |e: u64| -> [u64; 3] {
        // 2^(136 - e) as an f32: biased exponent 263 - e (e <= 253).
        let f = f32::from_bits(((263 - e) as u32) << 23);
        m.map(|x| (x * f).round() as u64)
    };
    let mut q = scaled(e);
    if q.iter().any(|&v| v > 1023) {
        e += 1;
        q = scaled(e);
    }
    e | q[0] << 8 | q[1] << 18 | q[2] << 28
}

/// The three numbers of [`pack_mean`].
fn unpack_mean(w: u64) -> [f32; 3] {
    let e = w & 0xFF;
    if e < 10 {
        return [0.0; 3];
    }
    // 2^(e - 136) as an f32: biased exponent e - 9.
    let f = f32::from_bits(((e - 9) as u32) << 23);
    [8, 18, 28].map(|s| ((w >> s) & 0x3FF) as f32 * f)
}

impl VisTable {
    /// The set of `tag`: the tag's top bits.
    #[inline]
    fn set(&self, tag: u64) -> &[AtomicU64; WAYS] {
        let first = self.base + (tag >> (64 - SETS_LOG2)) as usize * WAYS;
        self.slots[first..first + WAYS]
            .try_into()
            .expect("a set is WAYS slots")
    }

    /// The slot holding the cube of `tag` and its word; else, with word 0, the slot a new
    /// cube of `tag` takes: the first empty one of its set, or the one whose cube traced the
    /// fewest rays (the first of those).
    #[inline]
    fn place(&self, tag: u64) -> (&AtomicU64, u64) {
        let set = self.set(tag);
        let mut victim = 0;
        let mut fewest = u64::MAX;
        for (i, slot) in set.iter().enumerate() {
            let w = slot.load(Relaxed);
            let traced = traced_in(w);
            if traced > 0 && holds(w, tag) {
                return (slot, w);
            }
            if traced < fewest {
                fewest = traced;
                victim = i;
            }
        }
        (&set[victim], 0)
    }

    /// The transmission toward the source of `tag`: the cube's mean when it is trusted
    /// (`trust` agreeing rays traced), else `trace()`, whose answer the cube learns; and
    /// whether a ray was traced.
    fn query(&self, tag: u64, trust: u16, trace: impl FnOnce() -> Color) -> (Color, bool) {
        let (slot, w) = self.place(tag);
        let low = tag & 0xFFFF;
        let (traced, mut uses, seen, mean) = if w != 0 {
            (
                traced_in(w),
                (w >> 21) & 0x7,
                (w >> 24) & 0x3,
                w >> MEAN_SHIFT,
            )
        } else {
            (0, 0, 0, 0)
        };
        let word = |traced: u64, uses: u64, seen: u64, mean: u64| {
            low | traced << 16 | uses << 21 | seen << 24 | mean << MEAN_SHIFT
        };
        if traced >= u64::from(trust) && seen != LIT | DARK {
            uses = (uses + 1) % u64::from(RECHECK);
            if uses != 0 {
                slot.store(word(traced, uses, seen, mean), Relaxed);
                let m = unpack_mean(mean);
                return (Color::new(m[0] as f64, m[1] as f64, m[2] as f64), false);
            }
        }
        let t = trace();
        let seen = seen | if bright(t) > 0.0 { LIT } else { DARK };
        let (mut traced, mut mean) = (traced, mean);
        if t.is_finite() {
            traced = (traced + 1).min(MAX_TRACED);
            let old = if traced == 1 {
                [0.0; 3]
            } else {
                unpack_mean(mean)
            };
            let n = traced as f32;
            let m: [f32; 3] = std::array::from_fn(|i| {
                let v = t.to_array()[i] as f32;
                old[i] + (v - old[i]) / n
            });
            mean = pack_mean(m);
        }
        slot.store(word(traced, uses, seen, mean), Relaxed);
        (t, true)
    }
}

/// A thread's private table ([`new_epoch`]), tied to one calculation (an owner id).
#[derive(Default)]
struct Private {
    owner: u64,
    table: Option<VisTable>,
}

thread_local! {
    static PRIVATE: RefCell<Private> = RefCell::default();
    /// The current epoch of this thread's queries (0: none, the tags as they are).
    static EPOCH: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    /// The tags (as the shared table knows them) this epoch's queries asked for.
    static TOUCHED: RefCell<Vec<u64>> = const { RefCell::new(Vec::new()) };
}

/// Start a new epoch of this thread's queries: no cube learnt before answers after (the tags
/// of a new epoch differ), and they go to the thread's private table. `ttrace` starts one
/// per ray, so that a ray's shadow answers do not depend on which rays its thread, or any
/// other, traced before; epoch 0 goes back to the shared table.
pub fn new_epoch(epoch: u64) {
    EPOCH.with(|e| e.set(epoch));
    TOUCHED.with(|t| t.borrow_mut().clear());
}

/// What this thread's current epoch learnt: for each cube and source its queries asked
/// about, the tag the shared table knows it by and the slot's word as the epoch left it
/// (in the order of the tags). The epoch ends (back to epoch 0, the shared table).
///
/// An epoch reads the shared table but never writes it: a cube it does not know yet starts
/// from what the shared table knew when it began (`shadow`), and what it learns goes to
/// the shared table only through [`learn`], which the caller runs for its epochs in a
/// fixed order once they are all done. So `ttrace`'s rays share shadow answers across its
/// waves while each ray's values depend only on the waves before it.
pub fn end_epoch() -> Vec<(u64, u64)> {
    let epoch = EPOCH.with(|e| e.replace(0));
    let mut tags = TOUCHED.with(|t| std::mem::take(&mut *t.borrow_mut()));
    if epoch == 0 {
        return Vec::new();
    }
    tags.sort_unstable();
    tags.dedup();
    PRIVATE.with(|p| {
        let Ok(p) = p.try_borrow() else {
            return Vec::new();
        };
        let Some(table) = &p.table else {
            return Vec::new();
        };
        tags.into_iter()
            .filter_map(|tag| {
                let w = table.place(epoch_tag(tag, epoch)).1;
                (w != 0).then_some((tag, w))
            })
            .collect()
    })
}

/// Put what epochs learnt ([`end_epoch`]) into the shared table, in the order given: a
/// cube's slot takes the state its last epoch left it in.
pub fn learn(shared: &VisTable, learnt: &[(u64, u64)]) {
    for &(tag, w) in learnt {
        shared.place(tag).0.store(retag(w, tag), Relaxed);
    }
}

/// The tag of a query's `tag` in epoch `epoch` (never 0).
fn epoch_tag(tag: u64, epoch: u64) -> u64 {
    fx_mix(tag, epoch).max(1)
}

/// Bring in the set of the shared table that [`shadow`] will read for `q` toward `src` (the
/// sets are spread over 512 KiB, so a query's first read is usually a cache miss); nothing
/// in an epoch, whose queries go to the thread's private table.
pub fn prefetch(shared: &VisTable, q: &VisQuery, src: usize) {
    if EPOCH.with(|e| e.get()) == 0 {
        crate::prefetch::prefetch(shared.set(q.tag(src)));
    }
}

/// The transmission toward source `src` for a query: reused from its cube when the cube is
/// trusted, else `trace()` (a real shadow ray), whose answer the cube learns. `shared` is
/// the calculation's table (None: this thread's private one). Returns the transmission and
/// whether a ray was traced.
pub fn shadow(
    shared: Option<&VisTable>,
    q: &VisQuery,
    src: usize,
    trace: impl FnOnce() -> Color,
) -> (Color, bool) {
    let epoch = EPOCH.with(|e| e.get());
    if epoch == 0 {
        if let Some(t) = shared {
            return t.query(q.tag(src), q.trust, trace);
        }
    }
    let shared_tag = q.tag(src);
    let tag = if epoch == 0 {
        shared_tag
    } else {
        epoch_tag(shared_tag, epoch)
    };
    PRIVATE.with(|p| {
        // A shadow ray never shades, so it never comes back here; if it ever did, the
        // nested query would simply trace.
        let Ok(mut p) = p.try_borrow_mut() else {
            return (trace(), true);
        };
        if p.owner != q.owner || p.table.is_none() {
            p.owner = q.owner;
            p.table = Some(VisTable::default());
        }
        let Some(t) = &p.table else {
            return (trace(), true);
        };
        if epoch != 0 {
            // A cube new to this epoch starts from what the shared table knew of it.
            let (slot, w) = t.place(tag);
            if w == 0 {
                let known = shared.map_or(0, |s| s.place(shared_tag).1);
                slot.store(if known != 0 { retag(known, tag) } else { 0 }, Relaxed);
                TOUCHED.with(|v| v.borrow_mut().push(shared_tag));
            }
        }
        t.query(tag, q.trust, trace)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(owner: u64, p: DVec3) -> VisQuery {
        VisQuery::new(owner, 3, false, 0.1, p).unwrap()
    }

    #[test]
    fn agreeing_cube_is_reused_and_rechecked() {
        let table = VisTable::default();
        let p = DVec3::new(0.51, 0.52, 0.53);
        let mut traced = 0;
        for i in 0..(TRUST + 3 * RECHECK) {
            let (c, did) = shadow(Some(&table), &q(1, p), 0, || {
                traced += 1;
                Color::splat(0.8)
            });
            // The mean is kept in 10-bit mantissas.
            assert!(
                (c - Color::splat(0.8)).abs().max_element() < 1e-3,
                "query {i}"
            );
            assert_eq!(
                did,
                i < TRUST || (i - TRUST + 1).is_multiple_of(RECHECK),
                "query {i}"
            );
        }
        assert_eq!(traced, TRUST as usize + 3);
        // Another trust: answered from the cube after that many agreeing rays.
        for trust in [1, 2, 8, TRUST_MAX] {
            let owner = 100 + u64::from(trust);
            let tq = q(owner, p).with_trust(trust);
            let mut traced = 0;
            for i in 0..(trust + 2 * RECHECK) {
                let (_, did) = shadow(Some(&table), &tq, 0, || {
                    traced += 1;
                    Color::ONE
                });
                let want = i < trust || (i - trust + 1).is_multiple_of(RECHECK);
                assert_eq!(did, want, "trust {trust}, query {i}");
            }
            assert_eq!(traced, trust as usize + 2, "trust {trust}");
        }
        assert_eq!(q(1, p).with_trust(0), q(1, p).with_trust(1));
        assert_eq!(q(1, p).with_trust(99), q(1, p).with_trust(TRUST_MAX));
        // Another source, another side, or another calculation: nothing reused.
        let (_, did) = shadow(Some(&table), &q(1, p), 1, || Color::ONE);
        assert!(did);
        let back = VisQuery::new(1, 3, true, 0.1, p).unwrap();
        let (_, did) = shadow(Some(&table), &back, 0, || Color::ONE);
        assert!(did);
        let (_, did) = shadow(Some(&table), &q(2, p), 0, || Color::ONE);
        assert!(did);
    }

    #[test]
    fn means_pack_into_38_bits() {
        for v in [0.0f32, 1e-30, 0.2, 0.25, 0.8, 0.86, 1.0, 3.5, 1e6] {
            let want = [v, v * 0.5, 1.0 - v.min(1.0)];
            let w = pack_mean(want);
            assert_eq!(w >> 38, 0, "{w:x}");
            let got = unpack_mean(w);
            let largest = want.iter().fold(0f32, |a, &b| a.max(b));
            for (g, x) in got.iter().zip(want) {
                assert!((g - x).abs() <= largest * 2f32.powi(-10), "{g} vs {x}");
            }
        }
        // Exact where 10 bits hold the numbers; the fields stay apart.
        assert_eq!(unpack_mean(pack_mean([0.5, 0.25, 1.0])), [0.5, 0.25, 1.0]);
        assert_eq!(unpack_mean(pack_mean([1.0, 0.0, 1.0])), [1.0, 0.0, 1.0]);
        assert_eq!(
            unpack_mean(pack_mean([-1.0, f32::NAN, 0.0])),
            [0.0, 0.0, 0.0]
        );
        // Rounding to nearest, not down: the mean of many answers of 1 stays 1.
        let below_one = f32::from_bits(1.0f32.to_bits() - 1);
        assert_eq!(unpack_mean(pack_mean([below_one; 3])), [1.0; 3]);
        assert_eq!(unpack_mean(pack_mean([0.9996; 3])), [1.0; 3]);
        // Huge or infinite numbers saturate, never wrap.
        let big = unpack_mean(pack_mean([f32::INFINITY, 1.0, 0.0]));
        assert_eq!(big[0], 2f32.powi(125));
    }

    #[test]
    fn a_slot_counts_to_31_and_keeps_a_running_mean() {
        let table = VisTable::default();
        let p = DVec3::new(2.5, 0.5, 0.5);
        // 300 queries of a cube whose rays all pass 0.5: trusted after TRUST, then traced
        // every RECHECK-th (8 + 292 / 8 = 44 rays), and the counter stops at 31 without
        // spilling into the other fields.
        for _ in 0..300 {
            shadow(Some(&table), &q(4, p), 1, || Color::splat(0.5));
        }
        let w = table.place(q(4, p).tag(1)).1;
        assert_eq!((w >> 16) & 0x1F, MAX_TRACED);
        assert_eq!((w >> 24) & 0x3, LIT);
        assert_eq!(unpack_mean(w >> MEAN_SHIFT), [0.5; 3]);
    }

    #[test]
    fn a_set_keeps_the_cubes_that_traced_most() {
        let table = VisTable::default();
        // Tags of one set (the same top bits), told apart by their low bits.
        let tag = |k: u64| (0x0ABC << (64 - SETS_LOG2)) | k;
        let busy: Vec<u64> = (1..WAYS as u64).map(tag).collect();
        for &b in &busy {
            for _ in 0..TRUST {
                table.query(b, TRUST, || Color::ONE);
            }
        }
        // A thousand cubes asked about once each take turns in the one slot left ...
        for k in 0..1000 {
            let (_, traced) = table.query(tag(100 + k), TRUST, || Color::ZERO);
            assert!(traced);
        }
        // ... and the busy cubes still answer without a ray.
        for &b in &busy {
            let (c, traced) = table.query(b, TRUST, || Color::ZERO);
            assert!(!traced, "cube {b:x} was evicted");
            assert_eq!(c, Color::ONE);
        }
        // A cube of another set is not among them.
        let (_, traced) = table.query(busy[0] ^ (1 << 63), TRUST, || Color::ONE);
        assert!(traced);
        // Every set is one cache line, the last one included.
        for t in [0, tag(0), busy[0] ^ (1 << 63), u64::MAX] {
            assert_eq!(table.set(t).as_ptr() as usize % 64, 0);
        }
    }

    #[test]
    fn shadow_edge_always_traces() {
        let p = DVec3::new(-3.2, 0.0, 7.0);
        for i in 0..40 {
            let lit = i % 5 != 0;
            let want = if lit { Color::ONE } else { Color::ZERO };
            let (c, did) = shadow(None, &q(7, p), 2, || want);
            assert!(did, "query {i} of a mixed cube must trace");
            assert_eq!(c, want);
        }
    }

    #[test]
    fn threads_share_a_table_and_its_means_stay_within_the_answers() {
        let table = VisTable::default();
        let p = DVec3::new(1.5, 2.5, -0.5);
        // One thread teaches the cube; another is answered without a ray.
        std::thread::scope(|s| {
            s.spawn(|| {
                for _ in 0..TRUST {
                    shadow(Some(&table), &q(3, p), 4, || Color::new(0.5, 0.25, 1.0));
                }
            });
        });
        let (c, did) = std::thread::scope(|s| {
            s.spawn(|| shadow(Some(&table), &q(3, p), 4, || Color::ZERO))
                .join()
                .unwrap()
        });
        assert!(!did);
        assert!((c - Color::new(0.5, 0.25, 1.0)).abs().max_element() < 1e-4);
        // Four threads at once on a few cubes, each answer a transmission of 0.2-0.8 on
        // every channel (all lit): every answer, reused or traced, stays within them.
        std::thread::scope(|s| {
            for k in 0..4u64 {
                let table = &table;
                s.spawn(move || {
                    for i in 0..20_000u64 {
                        let v = 0.2 + 0.6 * ((i * 7 + k * 13) % 97) as f64 / 96.0;
                        let at = DVec3::new(0.1 + (i % 3) as f64, 0.3, 0.7);
                        let (c, _) =
                            shadow(Some(table), &q(5, at), (i % 2) as usize, || Color::splat(v));
                        assert!(
                            c.min_element() >= 0.2 - 1e-4 && c.max_element() <= 0.8 + 1e-4,
                            "{c:?}"
                        );
                    }
                });
            }
        });
    }

    #[test]
    fn epochs_read_the_shared_table_and_teach_it_only_through_learn() {
        let table = VisTable::default();
        let p = DVec3::new(4.5, 0.5, 0.5);
        for _ in 0..TRUST {
            shadow(Some(&table), &q(9, p), 0, || Color::ONE);
        }
        // In an epoch, the shared table's trusted cube answers.
        new_epoch(77);
        let (_, did) = shadow(Some(&table), &q(9, p), 0, || Color::ONE);
        assert!(!did);
        // A cube the epoch learns stays out of the shared table ...
        let other = DVec3::new(-7.5, 0.5, 0.5);
        for _ in 0..TRUST {
            shadow(Some(&table), &q(9, other), 0, || Color::splat(0.5));
        }
        let (c, did) = shadow(Some(&table), &q(9, other), 0, || Color::ZERO);
        assert!(!did);
        assert_eq!(c, Color::splat(0.5));
        let learnt = end_epoch();
        assert_eq!(learnt.len(), 2, "{learnt:?}");
        let (_, did) = shadow(Some(&table), &q(9, other), 0, || Color::ONE);
        assert!(did, "an epoch wrote the shared table");
        // ... until `learn` puts it there (the query above traced a ray the epoch did not
        // see; learning overwrites the slot with the epoch's state).
        learn(&table, &learnt);
        let (c, did) = shadow(Some(&table), &q(9, other), 0, || Color::ZERO);
        assert!(!did);
        assert_eq!(c, Color::splat(0.5));
        // Another epoch starts afresh where the shared table knows nothing, whatever an
        // earlier epoch of this thread learnt privately.
        new_epoch(78);
        let fresh = DVec3::new(30.5, 0.5, 0.5);
        let (_, did) = shadow(Some(&table), &q(9, fresh), 0, || Color::ONE);
        assert!(did);
        assert_eq!(end_epoch().len(), 1);
    }

    #[test]
    fn cubes_follow_the_footprint() {
        let at = |x: f64, f: f64| VisQuery::new(1, 0, false, f, DVec3::new(x, -0.2, 0.0));
        // Footprint 0.1 -> cubes of 0.125.
        assert_ne!(at(0.05, 0.1), at(0.3, 0.1));
        assert_eq!(at(0.01, 0.1), at(0.12, 0.1));
        assert_ne!(at(-0.01, 0.1), at(0.01, 0.1));
        // Footprint 0.4 -> cubes of 0.5; exactly 0.5 stays 0.5.
        assert_eq!(at(0.05, 0.4), at(0.3, 0.4));
        assert_eq!(at(0.05, 0.5), at(0.3, 0.5));
        assert_ne!(at(0.05, 0.4), at(0.05, 0.1));
        assert!(at(0.0, 0.0).is_none());
        assert!(at(0.0, f64::NAN).is_none());
        assert!(at(f64::INFINITY, 0.1).is_none());
        assert!(at(1e20, 1e-6).is_none());
        assert_eq!(floor_i64(-0.5), -1);
        assert_eq!(floor_i64(-1.0), -1);
        assert_eq!(floor_i64(2.7), 2);
    }
}
