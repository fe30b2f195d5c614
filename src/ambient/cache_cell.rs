//! The values of one cell of the ambient cache's grid ([`super::AmbientCache`]), kept for
//! the lookup's scan: per ambient level a span of single-precision positions and reaches,
//! four to a cache line, and beside them each value's weight and filing number.

use glam::Vec4;

/// A value's ambient level, which decides (with its weight) whether a lookup may use it at
/// all: a cell keeps its values in spans of one level, and a lookup skips the spans of
/// levels it may not use without reading them.
#[derive(Clone, Copy)]
pub(super) struct Tag {
    pub(super) lvl: u32,
}

/// The values of one grid cell (`V`: a shared pointer to each, or an index), with a
/// compact copy of what the lookup's first tests need, in arrays scanned in order. The
/// values are kept in spans of one ambient level each, so that a lookup scans only the
/// levels it may use (at `-ab 5` a lookup may use about a third of the values in reach).
pub(super) struct CellList<V> {
    /// One span per ambient level present, in increasing level; spans lie in the arrays
    /// below in the same order.
    spans: Vec<Span>,
    /// Each value's position relative to the cell's corner and its squared reach
    /// (`(aa·reach·max(rad))²`), in cell sizes and single precision, four values to a
    /// cache line (16 bytes a value), tested four at a time; a span starts a new quad.
    quads: Vec<Quad>,
    /// Each value with its weight and filing number, read only for values in reach.
    entries: Vec<Entry<V>>,
    /// Values filed in this cell so far (the next value's filing number).
    filed: u32,
}

/// The values of one ambient level in a cell ([`CellList`]), in filing order: `len`
/// entries from `entry`, their quads from `quad`.
#[derive(Clone, Copy)]
struct Span {
    lvl: u32,
    quad: u32,
    entry: u32,
    len: u32,
}

/// A value of a cell: its filing number in the cell (a lookup hands on the values of
/// several spans in filing order, so that its sums do not depend on the grouping) and the
/// value. (Its weight is read from the value, and only for values in reach: those a lookup
/// reads anyway. 16 bytes a filing instead of 24 with the weight beside it.)
struct Entry<V> {
    filed: u32,
    val: V,
}

/// Four values' positions and squared reaches ([`CellList::quads`]); an unused lane's
/// squared reach is −∞, which no test passes.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Quad {
    x: [f32; 4],
    y: [f32; 4],
    z: [f32; 4],
    r2: [f32; 4],
}

const EMPTY_QUAD: Quad = Quad {
    x: [0.0; 4],
    y: [0.0; 4],
    z: [0.0; 4],
    r2: [f32::NEG_INFINITY; 4],
};

impl<V> Default for CellList<V> {
    fn default() -> Self {
        CellList {
            spans: Vec::new(),
            quads: Vec::new(),
            entries: Vec::new(),
            filed: 0,
        }
    }
}

/// Where a lookup is in one cell: the point relative to the cell's corner in cell sizes,
/// and the margin of the single-precision test.
#[derive(Clone, Copy)]
pub(super) struct At {
    pub(super) q: [f32; 3],
    pub(super) margin: f32,
}

/// Values one cell hands on without a heap allocation; a cell with more in reach hands
/// on the rest from a list it allocates. A cell has about one value in reach at a lookup
/// (the office of `bench/realscenes.sh` at `-ab 2`: 4.7 million in 4.9 million cells
/// scanned); the array is zeroed at every scan, which at 64 entries was a `memset` call
/// (1% of that render's instructions).
const HITS_INLINE: usize = 16;

/// Make room for one more element: one at a time up to `small` elements, then doubling.
/// Most cells hold a few values (a value is filed in about seven), and a vector's first
/// growth would otherwise reserve four quads (256 bytes) for a single value.
fn room_for_one<T>(v: &mut Vec<T>, small: usize) {
    if v.len() == v.capacity() {
        if v.len() < small {
            v.reserve_exact(1);
        } else {
            v.reserve(1);
        }
    }
}

impl<V> CellList<V> {
    pub(super) fn push(&mut self, near: [f32; 4], tag: Tag, v: V) {
        let g = match self.spans.binary_search_by_key(&tag.lvl, |s| s.lvl) {
            Ok(g) => g,
            Err(g) => {
                let (quad, entry) = match self.spans.get(g) {
                    Some(next) => (next.quad, next.entry),
                    None => (self.quads.len() as u32, self.entries.len() as u32),
                };
                let span = Span {
                    lvl: tag.lvl,
                    quad,
                    entry,
                    len: 0,
                };
                room_for_one(&mut self.spans, 2);
                self.spans.insert(g, span);
                g
            }
        };
        let span = self.spans[g];
        let lane = (span.len % 4) as usize;
        let q = (span.quad + span.len / 4) as usize;
        if lane == 0 {
            room_for_one(&mut self.quads, 2);
            self.quads.insert(q, EMPTY_QUAD);
            self.spans[g + 1..].iter_mut().for_each(|s| s.quad += 1);
        }
        let quad = &mut self.quads[q];
        (quad.x[lane], quad.y[lane], quad.z[lane], quad.r2[lane]) =
            (near[0], near[1], near[2], near[3]);
        let entry = Entry {
            filed: self.filed,
            val: v,
        };
        room_for_one(&mut self.entries, 4);
        self.entries.insert((span.entry + span.len) as usize, entry);
        self.spans[g + 1..].iter_mut().for_each(|s| s.entry += 1);
        self.spans[g].len += 1;
        self.filed = self.filed.wrapping_add(1);
    }

    /// Every value of the cell, in no particular order.
    pub(super) fn values(&self) -> impl Iterator<Item = &V> {
        self.entries.iter().map(|e| &e.val)
    }

    /// Hand on, in filing order, the values whose reach sphere holds the lookup's point and
    /// whose level and weight (`weight_of`) `usable` accepts. A span whose level `usable`
    /// refuses at any weight is not read. The reach is tested in single precision, four
    /// values at a time, and again by `exact` (in double precision) for a value whose test
    /// falls within the margin of rounding, so that the values handed on are exactly those
    /// `exact` accepts. `prefetch` is called for each value in reach before any weight is
    /// read or value handed on, so that their cache misses overlap.
    #[inline(always)]
    pub(super) fn scan(
        &self,
        at: At,
        usable: &impl Fn(u32, f64) -> bool,
        (exact, weight_of): (impl Fn(&V) -> bool, impl Fn(&V) -> f64),
        prefetch: impl Fn(&V),
        mut hand_on: impl FnMut(&V),
    ) {
        let (qx, qy, qz) = (
            Vec4::splat(at.q[0]),
            Vec4::splat(at.q[1]),
            Vec4::splat(at.q[2]),
        );
        let margin = Vec4::splat(at.margin);
        // Each hit: its entry's index, and its span's level in the high half.
        let mut inline = [0u64; HITS_INLINE];
        let mut n = 0;
        let mut more = Vec::new();
        let mut spans_hit = 0;
        for span in &self.spans {
            if !usable(span.lvl, f64::INFINITY) {
                continue;
            }
            let before = n + more.len();
            let (q0, e0, len) = (span.quad as usize, span.entry as usize, span.len as usize);
            let quads = self.quads.get(q0..q0 + len.div_ceil(4)).unwrap_or(&[]);
            let entries = self.entries.get(e0..e0 + len).unwrap_or(&[]);
            for (b, quad) in quads.iter().enumerate() {
                let (dx, dy, dz) = (
                    Vec4::from_array(quad.x) - qx,
                    Vec4::from_array(quad.y) - qy,
                    Vec4::from_array(quad.z) - qz,
                );
                let d2 = dx * dx + dy * dy + dz * dz;
                let r2 = Vec4::from_array(quad.r2);
                let mut maybe = d2.cmplt(r2 + margin).bitmask();
                if maybe == 0 {
                    continue;
                }
                // Lanes inside by more than the margin need no exact test.
                let sure = d2.cmplt(r2 - margin).bitmask();
                while maybe != 0 {
                    let lane = maybe.trailing_zeros();
                    maybe &= maybe - 1;
                    let i = b * 4 + lane as usize;
                    let Some(e) = entries.get(i) else { continue };
                    if sure & (1 << lane) == 0 && !exact(&e.val) {
                        continue;
                    }
                    prefetch(&e.val);
                    let hit = (e0 + i) as u64 | (u64::from(span.lvl) << 32);
                    if n < HITS_INLINE {
                        inline[n] = hit;
                        n += 1;
                    } else {
                        more.push(hit);
                    }
                }
            }
            spans_hit += usize::from(n + more.len() > before);
        }
        let entry = |h: u64| &self.entries[(h & 0xffff_ffff) as usize];
        let mut hand = |hits: &mut [u64]| {
            if spans_hit > 1 {
                hits.sort_unstable_by_key(|&h| entry(h).filed);
            }
            for &h in hits.iter() {
                let val = &entry(h).val;
                if usable((h >> 32) as u32, weight_of(val)) {
                    hand_on(val);
                }
            }
        };
        if more.is_empty() {
            hand(&mut inline[..n]);
        } else {
            let mut all = inline[..n].to_vec();
            all.append(&mut more);
            hand(&mut all);
        }
    }
}
