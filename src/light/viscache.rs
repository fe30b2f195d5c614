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
//! above the footprint's radius, holding the hit point. A cube whose first [`TRUST`] shadow
//! rays agree (all blocked, or all reaching the source) answers later queries with their
//! mean transmission, without a ray; every [`RECHECK`]-th query still traces one, and any
//! disagreement marks the cube as a shadow edge, where every query traces its own ray from
//! then on. What remains is a cube whose small lit (or shadowed) part none of its rays found:
//! a blur of shadow edges within less than the footprint's diameter, which shrinks with the
//! footprint as `-ad` grows. A sample ray's specular descendants (through glass, off a
//! mirror) keep its spread: their footprint is the spread times the whole path's length.
//! Other rays (eye rays and their specular rays, every ray of the uncached `-aa 0`
//! calculation) always trace their shadow rays.
//!
//! The grid lives in a thread-local, direct-mapped table of 2^[`SLOTS_LOG2`] slots tied to
//! one calculation (an owner id) and cleared when another calculation uses the thread; a cube
//! whose slot another cube takes over starts afresh.

use std::cell::RefCell;

use glam::DVec3;

use crate::color::{bright, Color};
use crate::hash::fx_mix;

/// Shadow rays a cube must have traced, all agreeing, before it answers without one.
pub const TRUST: u16 = 8;

/// A trusted cube still traces every `RECHECK`-th query it answers.
pub const RECHECK: u16 = 8;

/// Slots of the per-thread table (a power of two; 24 bytes each, so 1.5 MiB per thread). The
/// table is direct-mapped: a cube whose slot another cube takes starts afresh. 2^16 rather
/// than 2^18: the same pictures within their noise (means within 0.02% on the three scenes
/// of `bench/realscenes.sh`), the same CPU within the runs' spread and 6 MiB less a thread.
pub const SLOTS_LOG2: u32 = 16;

/// Where a shadow query comes from: the cube around the hit of an ambient sample ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VisQuery {
    /// The calculation the answers belong to (answers of another are never reused).
    owner: u64,
    /// Hash of the hit object, its side, the cube's level and coordinates.
    cube: u64,
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
        Some(VisQuery { owner, cube: h })
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

/// One cube's answers: 24 bytes. The slot's index is the tag's top bits and the slot keeps
/// its low 32 bits, so two cubes share a slot unnoticed only when 48 bits of their tags
/// agree.
#[derive(Clone, Copy, Default)]
struct Slot {
    /// The low bits of the cube's tag ([`VisQuery::tag`]; a fresh slot's state is that of an
    /// empty one, so 0 needs no meaning of its own).
    tag: u32,
    sum: [f32; 3],
    traced: u16,
    uses: u16,
    /// [`LIT`] | [`DARK`]: what its shadow rays found.
    seen: u8,
}

/// A shadow ray of the cube reached the source.
const LIT: u8 = 1;
/// A shadow ray of the cube was blocked.
const DARK: u8 = 2;

const _: () = assert!(std::mem::size_of::<Slot>() == 24);

#[derive(Default)]
struct VisCache {
    owner: u64,
    slots: Vec<Slot>,
}

thread_local! {
    static VIS: RefCell<VisCache> = RefCell::default();
    /// The current epoch of this thread's table (0: none, the tags as they are).
    static EPOCH: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Start a new epoch of this thread's table: no cube learnt before answers after (the
/// tags of a new epoch differ), without clearing its 1.5 MiB. `ttrace` starts one per ray, so
/// that a ray's shadow answers do not depend on which rays its thread traced before.
pub fn new_epoch(epoch: u64) {
    EPOCH.with(|e| e.set(epoch));
}

/// The transmission toward source `src` for a query: reused from its cube when the cube is
/// trusted, else `trace()` (a real shadow ray), whose answer the cube learns. Returns the
/// transmission and whether a ray was traced.
pub fn shadow(q: &VisQuery, src: usize, trace: impl FnOnce() -> Color) -> (Color, bool) {
    let epoch = EPOCH.with(|e| e.get());
    let tag = if epoch == 0 {
        q.tag(src)
    } else {
        fx_mix(q.tag(src), epoch).max(1)
    };
    VIS.with(|v| {
        // A shadow ray never shades, so it never comes back here; if it ever did, the
        // nested query would simply trace.
        let Ok(mut v) = v.try_borrow_mut() else {
            return (trace(), true);
        };
        if v.owner != q.owner || v.slots.is_empty() {
            v.owner = q.owner;
            v.slots.clear();
            v.slots.resize(1 << SLOTS_LOG2, Slot::default());
        }
        let e = &mut v.slots[(tag >> (64 - SLOTS_LOG2)) as usize];
        let low = tag as u32;
        if e.tag != low {
            *e = Slot {
                tag: low,
                ..Slot::default()
            };
        }
        if e.traced >= TRUST && e.seen != LIT | DARK {
            e.uses = e.uses.wrapping_add(1);
            if e.uses % RECHECK != 0 {
                let n = e.traced as f32;
                return (
                    Color::new(
                        (e.sum[0] / n) as f64,
                        (e.sum[1] / n) as f64,
                        (e.sum[2] / n) as f64,
                    ),
                    false,
                );
            }
        }
        let t = trace();
        e.seen |= if bright(t) > 0.0 { LIT } else { DARK };
        if e.traced < u16::MAX && t.is_finite() {
            e.sum[0] += t.x as f32;
            e.sum[1] += t.y as f32;
            e.sum[2] += t.z as f32;
            e.traced += 1;
        }
        (t, true)
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
        let p = DVec3::new(0.51, 0.52, 0.53);
        let mut traced = 0;
        for i in 0..(TRUST + RECHECK) {
            let (c, did) = shadow(&q(1, p), 0, || {
                traced += 1;
                Color::splat(0.8)
            });
            // The mean is kept in f32.
            assert!(
                (c - Color::splat(0.8)).abs().max_element() < 1e-6,
                "query {i}"
            );
            assert_eq!(
                did,
                i < TRUST || (i - TRUST + 1).is_multiple_of(RECHECK),
                "query {i}"
            );
        }
        assert_eq!(traced, TRUST as usize + 1);
        // Another source, another side, or another calculation: nothing reused.
        let (_, did) = shadow(&q(1, p), 1, || Color::ONE);
        assert!(did);
        let back = VisQuery::new(1, 3, true, 0.1, p).unwrap();
        let (_, did) = shadow(&back, 0, || Color::ONE);
        assert!(did);
        let (_, did) = shadow(&q(2, p), 0, || Color::ONE);
        assert!(did);
    }

    #[test]
    fn shadow_edge_always_traces() {
        let p = DVec3::new(-3.2, 0.0, 7.0);
        for i in 0..40 {
            let lit = i % 5 != 0;
            let want = if lit { Color::ONE } else { Color::ZERO };
            let (c, did) = shadow(&q(7, p), 2, || want);
            assert!(did, "query {i} of a mixed cube must trace");
            assert_eq!(c, want);
        }
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
