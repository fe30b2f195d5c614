//! Bounding volume hierarchy over the scene's finite surfaces (an obvhs `CwBvh`).
//!
//! The BVH works in `f32`, the surfaces in `f64`. To make the `f32` box tests conservative:
//! - every box is padded by `pad = 4e-6 · S + 4·FTINY` (S = largest coordinate magnitude of
//!   the scene bounds) and rounded outward to `f32`;
//! - the ray origin handed to obvhs is first moved (in `f64`) to just before the entry point
//!   of the padded scene box, so its magnitude is at most about S whatever the caller's
//!   origin, and obvhs's internal `tmin = 1e-4` can never cull a box holding a hit at
//!   `t > FTINY`;
//! - pruning distances are rounded up and slackened, and the true closest hit is kept in
//!   `f64`.
//!
//! Tie rule of [`Bvh::closest`] (independent of the order candidates are visited in, as long
//! as `prefer` is consistent, i.e. a strict weak order): let `tmin` be the smallest hit
//! distance. Every hit with `t <= tmin + FTINY` is eligible, and the winner among the eligible
//! hits is the one that no other beats, where `a` beats `b` when `prefer(a, b) && !prefer(b,
//! a)`, and when neither (or both) prefer, the smaller `(t, index)` wins. At most
//! [`WINDOW`] eligible hits are kept; beyond that (more than 16 surfaces within `FTINY`) the
//! farthest ones are dropped.
//!
//! Degenerate inputs (thousands of identical or nested boxes) build deep trees; traversal
//! stays correct (the traversal stack spills to the heap beyond 16 entries) but obvhs's PLOC
//! builder becomes slow on them (about 1 s for 1000 identical boxes in a debug build).

use glam::{uvec2, DVec3, UVec2, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::Ray;

pub(crate) use super::bvh_build::tree_in_bounds;
use super::bvh_build::{
    append, build_chunked, build_cw_big_stack, f32_down, f32_up, BoxPrim, Quality, CHUNK,
};
use super::plain::Slab;

/// Relative box padding (times the largest coordinate magnitude).
const PAD_REL: f64 = 4e-6;
/// Box padding in the scene's length tolerance (covers the polygon edge tolerance).
const PAD_EPS: f64 = 4.0;
/// How far before the scene-box entry the `f32` ray starts (obvhs culls boxes exiting before
/// `t = 1e-4`).
const MARGIN: f64 = 1e-3;
/// Largest magnitude of a box coordinate (relative to the scene origin): boxes are clamped
/// to it. It keeps the `f32` boxes' surface areas, and obvhs's sums of them, finite: boxes
/// of about 1e19 and more made its CWBVH conversion index out of bounds (a panic). A ray
/// starts inside the clamped region, so a surface beyond it is still found: its clamped box
/// holds the ray's start and the exact f64 intersection has no such limit.
const COORD_LIMIT: f64 = 1e15;
/// [`Bvh::closest_sub`] packs a candidate and a surface index into one `usize`.
const _: () = assert!(usize::BITS >= 64);

use super::bvh_window::Window;
pub use super::bvh_window::{select_closest, WINDOW};

/// Entries of the traversal stack kept inline ([`DeepStack`]): a wide tree's traversal
/// holds one node group per level it descends, so a balanced tree of a million leaves
/// needs about eight. 16 entries are zeroed with a few stores, where 32 (256 bytes) took a
/// `memset` call at every traversal.
const STACK_INLINE: usize = 16;

/// Traversal stack: [`STACK_INLINE`] entries inline, spilling to the heap for (degenerate)
/// deeper trees. obvhs's own fixed stack silently drops entries beyond 32 levels, so it is
/// not used.
struct DeepStack {
    inline: [UVec2; STACK_INLINE],
    len: usize,
    spill: Vec<UVec2>,
}

impl DeepStack {
    fn new() -> Self {
        DeepStack {
            inline: [UVec2::ZERO; STACK_INLINE],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline(always)]
    fn push(&mut self, v: UVec2) {
        if self.len < STACK_INLINE {
            self.inline[self.len] = v;
        } else {
            self.spill.push(v);
        }
        self.len += 1;
    }

    #[inline(always)]
    fn pop_fast(&mut self) -> UVec2 {
        if self.len == 0 {
            return UVec2::ZERO;
        }
        self.len -= 1;
        if self.len >= STACK_INLINE {
            self.spill.pop().unwrap_or(UVec2::ZERO)
        } else {
            self.inline[self.len]
        }
    }

    #[inline(always)]
    fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// State for obvhs's `traverse!` macro (same field names as `obvhs::cwbvh::Traversal`).
struct TravState {
    stack: DeepStack,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl TravState {
    fn new(dir: Vec3A) -> Self {
        // Octant code as the CwBvh node layout expects it (one byte per child slot).
        let oct_inv4 = (if dir.x < 0.0 { 0 } else { 0x0404_0404 })
            | (if dir.y < 0.0 { 0 } else { 0x0202_0202 })
            | (if dir.z < 0.0 { 0 } else { 0x0101_0101 });
        TravState {
            stack: DeepStack::new(),
            current_group: uvec2(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// The f32 ray handed to obvhs.
#[inline]
fn ray32(o: DVec3, dir: DVec3, tmax32: f32) -> Ray {
    Ray::new(
        Vec3A::new(o.x as f32, o.y as f32, o.z as f32),
        // `+ 0.0` turns -0.0 (also from f32 underflow) into +0.0: obvhs picks the slab side
        // from `d < 0` but the reciprocal from the sign bit.
        Vec3A::new(dir.x as f32 + 0.0, dir.y as f32 + 0.0, dir.z as f32 + 0.0),
        0.0,
        tmax32,
    )
}

/// Bounding volume hierarchy over the scene's finite surfaces (obvhs CwBvh, f32 boxes rounded
/// OUTWARD and padded so that f32 rounding of the ray origin can never make a box test miss a
/// true f64 hit).
///
/// Its trees lie in two plain arrays (which a scene image lends to every process that maps
/// it): the nodes of the top tree (its root first) and then those of each chunk's tree, with
/// child and leaf offsets made absolute; and the leaves' slots, each holding the caller's
/// index (in the top tree of a chunked BVH, the chunk's).
#[derive(Clone)]
pub struct Bvh {
    /// Every tree's nodes (empty when there is no usable box).
    pub(crate) nodes: Slab<CwBvhNode>,
    /// What each leaf slot refers to.
    pub(crate) slots: Slab<u32>,
    /// For large inputs, the root node of each chunk's tree (empty: the top tree holds the
    /// boxes).
    pub(crate) chunks: Slab<u32>,
    /// Padded scene bounds (f64).
    pub(crate) lo: DVec3,
    pub(crate) hi: DVec3,
    /// Padding applied to every box.
    pub(crate) pad: f64,
    /// The scene's length tolerance (minimum hit distance, tie window).
    pub(crate) eps: f64,
    /// Number of input boxes.
    pub(crate) count: usize,
}

/// A tree's nodes, as obvhs's traversal macro reads them.
struct Nodes<'a> {
    nodes: &'a [CwBvhNode],
}

impl Bvh {
    /// Build from f64 bounds (relative frame). Empty input is fine (every query misses).
    /// Boxes with non-finite coordinates are never candidates; `min > max` is reordered.
    pub fn build(bounds: &[(DVec3, DVec3)], eps: f64) -> Bvh {
        Bvh::build_from(bounds.len(), |i| bounds[i], eps)
    }

    /// [`Bvh::build`] over `n` boxes given by `bound(i)` (called two or three times per
    /// box, giving the same box each time), without a list of them: large meshes build with
    /// less memory.
    pub fn build_from(n: usize, bound: impl Fn(usize) -> (DVec3, DVec3), eps: f64) -> Bvh {
        let clamped = |i: usize| -> Option<(DVec3, DVec3)> {
            let (a, b) = bound(i);
            if !(a.is_finite() && b.is_finite()) || i > u32::MAX as usize {
                return None;
            }
            let lim = DVec3::splat(COORD_LIMIT);
            Some((a.min(b).clamp(-lim, lim), a.max(b).clamp(-lim, lim)))
        };
        let mut s: f64 = 0.0;
        let mut ids = Vec::new();
        let mut blo = DVec3::splat(f64::INFINITY);
        let mut bhi = DVec3::splat(f64::NEG_INFINITY);
        for i in 0..n {
            if let Some((lo, hi)) = clamped(i) {
                s = s.max(lo.abs().max_element()).max(hi.abs().max_element());
                blo = blo.min(lo);
                bhi = bhi.max(hi);
                ids.push(i as u32);
            }
        }
        let pad = PAD_REL * (s + MARGIN) + PAD_EPS * eps;
        // The union of the padded boxes (rounding is monotonic: padding the union's bounds
        // gives the same numbers as padding every box).
        let tlo = blo - DVec3::splat(pad);
        let thi = bhi + DVec3::splat(pad);
        let boxed = |i: u32| -> BoxPrim {
            // `bound` gives the same box each time: every listed box is finite.
            let (lo, hi) = clamped(i as usize).unwrap_or((DVec3::ZERO, DVec3::ZERO));
            let lo = lo - DVec3::splat(pad);
            let hi = hi + DVec3::splat(pad);
            BoxPrim(Aabb::new(
                Vec3A::new(f32_down(lo.x), f32_down(lo.y), f32_down(lo.z)),
                Vec3A::new(f32_up(hi.x), f32_up(hi.y), f32_up(hi.z)),
            ))
        };
        let (mut nodes, mut slots, mut roots) = (Vec::new(), Vec::new(), Vec::new());
        if ids.is_empty() {
            // No usable box: every query misses.
        } else if ids.len() <= CHUNK {
            let prims: Vec<BoxPrim> = ids.iter().map(|&i| boxed(i)).collect();
            let cw = build_cw_big_stack(&prims, Quality::Fine);
            drop(prims);
            if !cw.nodes.is_empty() {
                append(&mut nodes, &mut slots, &cw, &ids);
            }
        } else {
            let (top, chunks) = build_chunked(ids, boxed, tlo, thi);
            if let Some(top) = top {
                let order: Vec<u32> = (0..chunks.len() as u32).collect();
                append(&mut nodes, &mut slots, &top, &order);
                drop(top);
                for (cw, ids) in &chunks {
                    roots.push(append(&mut nodes, &mut slots, cw, ids));
                }
            }
        }
        Bvh {
            nodes: nodes.into(),
            slots: slots.into(),
            chunks: roots.into(),
            lo: tlo,
            hi: thi,
            pad,
            eps,
            count: n,
        }
    }

    /// Boxes whose union holds every box of the tree: those of the nodes `depth` levels
    /// below the root (or of the leaves met before), in the tree's own coordinates, as its
    /// traversal tests them (padded and rounded outward). Empty for an empty tree; a
    /// chunked tree gives its chunks' boxes at most.
    pub fn cover(&self, depth: u32) -> Vec<(DVec3, DVec3)> {
        let mut out = Vec::new();
        let mut todo = vec![(0u32, 1u32)];
        while let Some((n, d)) = todo.pop() {
            let Some(node) = self.nodes.get(n as usize) else {
                return Vec::new();
            };
            for c in 0..8 {
                if node.is_child_empty(c) {
                    continue;
                }
                if !node.is_leaf(c) && d < depth {
                    todo.push((node.child_node_index(c), d + 1));
                    continue;
                }
                let b = node.child_aabb(c);
                out.push((b.min.as_dvec3(), b.max.as_dvec3()));
            }
        }
        out
    }

    /// Number of boxes the BVH was built from.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when built from no boxes.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The padding added to every box.
    pub fn pad(&self) -> f64 {
        self.pad
    }

    /// The f32 ray for a query, and the shift `s` such that f32 distance = f64 distance − s.
    fn setup(&self, org: DVec3, dir: DVec3, tmax: f64) -> Option<(Ray, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        if !(org.is_finite() && dir.is_finite())
            || dir == DVec3::ZERO
            || tmax.is_nan()
            || tmax <= self.eps
        {
            return None;
        }
        let inside = org.cmpge(self.lo).all() && org.cmple(self.hi).all();
        if inside {
            // Every box lies inside the scene box, so clipping the ray to it would prune
            // nothing: only obvhs's minimum distance needs the origin moved back.
            let shift = -MARGIN;
            let o = org + dir * shift;
            let tmax32 = if tmax.is_finite() {
                f32_up((tmax - shift) * (1.0 + 1e-6) + 2.0 * self.pad)
            } else {
                f32::INFINITY
            };
            return Some((ray32(o, dir, tmax32), shift));
        }
        let mut t_in: f64 = 0.0;
        let mut t_out = tmax;
        for i in 0..3 {
            if dir[i] == 0.0 {
                if org[i] < self.lo[i] || org[i] > self.hi[i] {
                    return None;
                }
            } else {
                let inv = 1.0 / dir[i];
                let ta = (self.lo[i] - org[i]) * inv;
                let tb = (self.hi[i] - org[i]) * inv;
                let (ta, tb) = if ta <= tb { (ta, tb) } else { (tb, ta) };
                t_in = t_in.max(ta);
                t_out = t_out.min(tb);
            }
        }
        if t_in.is_nan() || t_out.is_nan() || t_in > t_out {
            return None;
        }
        let shift = t_in - MARGIN;
        let o = org + dir * shift;
        let tmax32 = f32_up((t_out - shift) * (1.0 + 1e-6) + 2.0 * self.pad);
        Some((ray32(o, dir, tmax32), shift))
    }

    /// Closest hit: calls `intersect(i)` -> Option<f64 t> for candidate surfaces i in f64 and
    /// keeps the closest t in (FTINY, tmax).
    ///
    /// When a candidate's t is within FTINY of the closest, `prefer(new, old)` decides
    /// (true = take new); the caller implements Radiance's coincident-surface rules there. See
    /// the module documentation for the exact, visiting-order-independent rule (and
    /// [`select_closest`] for a reference implementation). Returns (index, t). The f32 tmax is
    /// used for pruning conservatively (rounded up) and the true best is kept in f64.
    pub fn closest(
        &self,
        org: DVec3,
        dir: DVec3,
        tmax: f64,
        mut intersect: impl FnMut(usize) -> Option<f64>,
        prefer: impl Fn(usize, usize) -> bool,
    ) -> Option<(usize, f64)> {
        self.closest_sub(
            org,
            dir,
            tmax,
            |i, _| intersect(i).map(|t| (t, 0)),
            |a, b| prefer(a.0, b.0),
        )
        .map(|(i, _, t)| (i, t))
    }

    /// [`Bvh::closest`] for candidates that hold several surfaces (a two-level BVH's
    /// instances): `intersect(i, reach)` returns the distance and which surface `j` of
    /// candidate `i` was hit; ties compare `(t, i, j)`. Returns `(i, j, t)`.
    ///
    /// `reach` (at most `tmax`) is the closest distance found so far plus the tie window:
    /// a hit beyond it can neither win nor tie, so a candidate may search no farther (an
    /// instance's own tree prunes with it). The candidate must still choose among its own
    /// surfaces as it would with `tmax`: where its choice looks past its closest hit (a
    /// window of its own), it searches that much farther.
    pub fn closest_sub(
        &self,
        org: DVec3,
        dir: DVec3,
        tmax: f64,
        mut intersect: impl FnMut(usize, f64) -> Option<(f64, u32)>,
        prefer: impl Fn((usize, u32), (usize, u32)) -> bool,
    ) -> Option<(usize, u32, f64)> {
        let (ray, shift) = self.setup(org, dir, tmax)?;
        let mut win = Window::new(self.eps);
        let pad2 = 2.0 * self.pad;
        // Candidate and surface in one key: (i, 0) is i itself, so ties between plain
        // candidates order exactly as by index.
        let key = |i: usize, j: u32| i | ((j as usize) << 32);
        let split = |k: usize| (k & 0xffff_ffff, (k >> 32) as u32);
        self.traverse(ray, |i| {
            match intersect(i, (win.tmin + self.eps).min(tmax)) {
                Some((t, j)) if t > self.eps && t < tmax && win.push(key(i, j), t) => {
                    // A new closest distance: prune (conservatively) beyond it plus eps.
                    f32_up((t + self.eps - shift) * (1.0 + 1e-6) + pad2)
                }
                _ => f32::INFINITY,
            }
        });
        win.select(&|a, b| prefer(split(a), split(b)))
            .map(|(k, t)| (split(k).0, split(k).1, t))
    }

    /// Every candidate whose box the ray touches (for tests/diagnostics), in any order.
    pub fn candidates(&self, org: DVec3, dir: DVec3, tmax: f64, mut f: impl FnMut(usize)) {
        let Some((ray, _)) = self.setup(org, dir, tmax) else {
            return;
        };
        self.traverse(ray, |i| {
            f(i);
            f32::INFINITY
        });
    }

    /// Visit every primitive whose box the f32 ray reaches, calling `prim(caller index)`;
    /// the returned value lowers the ray's (f32) tmax when smaller.
    fn traverse(&self, ray: Ray, mut prim: impl FnMut(usize) -> f32) {
        if self.nodes.is_empty() {
            return;
        }
        let tree = Nodes { nodes: &self.nodes };
        if self.chunks.is_empty() {
            walk(&tree, &self.slots, 0, ray, &mut |i, _| prim(i));
        } else {
            // The top tree's primitives are the chunks: each is walked with the ray as far
            // as it reaches now.
            walk(
                &tree,
                &self.slots,
                0,
                ray,
                &mut |c, tmax| match self.chunks.get(c) {
                    Some(&root) => walk(
                        &tree,
                        &self.slots,
                        root,
                        Ray { tmax, ..ray },
                        &mut |i, _| prim(i),
                    ),
                    None => tmax,
                },
            );
        }
    }
}

/// Walk the tree whose root is node `root` of `tree` along `ray`, calling `prim(slot's
/// value, tmax)` for every leaf slot whose box the ray reaches within its current `tmax`;
/// the returned value lowers `tmax` when smaller. Returns the final `tmax`.
fn walk(
    tree: &Nodes,
    slots: &[u32],
    root: u32,
    mut ray: Ray,
    prim: &mut impl FnMut(usize, f32) -> f32,
) -> f32 {
    let mut state = TravState::new(ray.direction);
    state.current_group.x = root;
    let mut node;
    obvhs::traverse!(
        tree,
        node,
        state,
        node.intersect_ray(&ray, state.oct_inv4),
        {
            if let Some(&i) = slots.get(state.primitive_id as usize) {
                if i != u32::MAX {
                    let t = prim(i as usize, ray.tmax);
                    if t < ray.tmax {
                        ray.tmax = t;
                    }
                }
            }
        }
    );
    ray.tmax
}

#[cfg(test)]
mod tests {
    use super::super::bvh_window::beats;
    use super::*;
    use crate::FTINY;

    #[test]
    fn rounding_helpers() {
        let x = 0.1f64;
        assert!(f32_up(x) as f64 >= x && f32_down(x) as f64 <= x);
        assert_eq!(f32_up(1.0), 1.0);
        assert_eq!(f32_down(1.0), 1.0);
        assert!(f32_up(-0.1) as f64 >= -0.1 && f32_down(-0.1) as f64 <= -0.1);
    }

    #[test]
    fn empty_and_bad_input() {
        let b = Bvh::build(&[], FTINY);
        assert!(b.is_empty());
        assert!(b
            .closest(DVec3::ZERO, DVec3::X, 1e10, |_| Some(1.0), |_, _| false)
            .is_none());
        let b = Bvh::build(&[(DVec3::splat(f64::NAN), DVec3::ONE)], FTINY);
        assert_eq!(b.len(), 1);
        let mut n = 0;
        b.candidates(DVec3::ZERO, DVec3::X, 1e10, |_| n += 1);
        assert_eq!(n, 0);
    }

    #[test]
    fn cover_holds_every_box() {
        // Boxes of random sizes scattered over a region, a wide tree of them and a deep one.
        let mut rnd = crate::hash::test_uniform(7);
        let scattered: Vec<_> = (0..500)
            .map(|_| {
                let c = DVec3::new(rnd(), rnd(), rnd()) * 40.0 - 20.0;
                let h = DVec3::new(rnd(), rnd(), rnd()) * 0.5;
                (c - h, c + h)
            })
            .collect();
        let nested: Vec<_> = (0..100)
            .map(|i| (DVec3::splat(-1.1f64.powi(i)), DVec3::splat(1.1f64.powi(i))))
            .collect();
        for input in [&scattered, &nested] {
            let bvh = Bvh::build(input, FTINY);
            for depth in 1..=3 {
                let cover = bvh.cover(depth);
                assert!(!cover.is_empty() && cover.len() <= 8usize.pow(depth));
                for &(lo, hi) in input.iter() {
                    assert!(
                        cover
                            .iter()
                            .any(|&(a, b)| a.cmple(lo).all() && b.cmpge(hi).all()),
                        "depth {depth}: no cover box holds {lo}..{hi}"
                    );
                }
            }
        }
        assert!(Bvh::build(&[], FTINY).cover(2).is_empty());
    }

    #[test]
    fn deep_tree_traversal_finds_everything() {
        // Nested boxes make a chain-like tree deeper than obvhs's 32-entry stack.
        let nested: Vec<_> = (0..600)
            .map(|i| {
                let s = 1.01f64.powi(i);
                (DVec3::splat(-s), DVec3::splat(s))
            })
            .collect();
        let bvh = Bvh::build(&nested, FTINY);
        assert!(tree_in_bounds(&bvh.nodes));
        let mut parents = vec![0usize; bvh.nodes.len()];
        for (k, n) in bvh.nodes.iter().enumerate() {
            for c in 0..n.imask.count_ones() as usize {
                parents[n.child_base_idx as usize + c] = k;
            }
        }
        let depth = (0..parents.len())
            .map(|mut n| {
                let mut d = 0;
                while n != 0 && d < 100_000 {
                    n = parents[n] as usize;
                    d += 1;
                }
                d
            })
            .max()
            .unwrap();
        assert!(depth > 40, "depth {depth}");
        let mut seen = vec![false; nested.len()];
        bvh.candidates(DVec3::ZERO, DVec3::Y, 1e10, |i| seen[i] = true);
        assert!(seen.iter().all(|&b| b));
        let got = bvh.closest(
            DVec3::ZERO,
            DVec3::Y,
            1e10,
            |i| Some(1.0 + i as f64),
            |_, _| false,
        );
        assert_eq!(got, Some((0, 1.0)));
    }

    #[test]
    fn chunked_tree_finds_the_same_closest_hits() {
        // More boxes than a chunk: the chunks and the tree over them find what a brute-force
        // search finds.
        let mut rnd = crate::hash::test_uniform(12345);
        let n = CHUNK * 2 + 1000;
        let boxes: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| {
                let c = DVec3::new(rnd(), rnd(), rnd()) * 100.0;
                let h = DVec3::new(rnd(), rnd(), rnd()) * 0.5 + DVec3::splat(0.01);
                (c - h, c + h)
            })
            .collect();
        let bvh = Bvh::build(&boxes, FTINY);
        assert_eq!(bvh.chunks.len(), 3);
        assert!(tree_in_bounds(&bvh.nodes));
        // A child index that points back (a cycle) or out of the array is refused.
        let mut bad = bvh.nodes.to_vec();
        let k = bad.iter().position(|n| n.imask != 0).unwrap();
        bad[k].child_base_idx = k as u32;
        assert!(!tree_in_bounds(&bad));
        bad[k].child_base_idx = bad.len() as u32;
        assert!(!tree_in_bounds(&bad));
        let slab = |b: &(DVec3, DVec3), o: DVec3, d: DVec3| -> Option<f64> {
            let (t0, t1) = ((b.0 - o) / d, (b.1 - o) / d);
            let (near, far) = (t0.min(t1).max_element(), t0.max(t1).min_element());
            (near <= far && near > FTINY).then_some(near)
        };
        for _ in 0..300 {
            let o = DVec3::new(
                rnd() * 140.0 - 20.0,
                rnd() * 140.0 - 20.0,
                rnd() * 140.0 - 20.0,
            );
            let d = (DVec3::new(rnd(), rnd(), rnd()) - DVec3::splat(0.5)).normalize();
            let got = bvh.closest(o, d, 1e30, |i| slab(&boxes[i], o, d), |_, _| false);
            let want = select_closest(
                (0..n).filter_map(|i| slab(&boxes[i], o, d).map(|t| (i, t))),
                1e30,
                |_, _| false,
            );
            assert_eq!(got, want);
        }
    }

    #[test]
    fn window_rules() {
        // Closest wins when nothing is preferred.
        assert_eq!(
            select_closest([(0, 2.0), (1, 1.0)], 10.0, |_, _| false),
            Some((1, 1.0))
        );
        // Within FTINY, prefer decides.
        let t = 1.0 + 0.5 * FTINY;
        assert_eq!(
            select_closest([(0, 1.0), (1, t)], 10.0, |a, _| a == 1),
            Some((1, t))
        );
        assert_eq!(
            select_closest([(1, t), (0, 1.0)], 10.0, |a, _| a == 1),
            Some((1, t))
        );
        // Outside the window the preferred one loses.
        assert_eq!(
            select_closest([(1, 1.0 + 3.0 * FTINY), (0, 1.0)], 10.0, |a, _| a == 1),
            Some((0, 1.0))
        );
        // Eviction when a nearer hit arrives later.
        assert_eq!(
            select_closest(
                [
                    (1, 1.0 + 0.9 * FTINY),
                    (2, 1.0 + 0.5 * FTINY),
                    (3, 1.0 - 0.2 * FTINY)
                ],
                10.0,
                |a, b| a < b
            ),
            Some((2, 1.0 + 0.5 * FTINY))
        );
        // Range limits.
        assert_eq!(select_closest([(0, 0.5 * FTINY)], 10.0, |_, _| false), None);
        assert_eq!(select_closest([(0, 10.0)], 10.0, |_, _| false), None);
    }

    #[test]
    fn window_keeps_many_coincident_hits() {
        // Sequences of up to WINDOW hits within FTINY of each other, with far hits mixed
        // in: the winner is the one the rule picks among all eligible hits.
        let prefer = |a: usize, b: usize| a % 3 < b % 3;
        let mut next = crate::hash::test_uniform(12345);
        for case in 0..200 {
            let n = 1 + case % WINDOW;
            let base = 1.0 + next();
            let hits: Vec<(usize, f64)> = (0..n + 4)
                .map(|i| {
                    let t = if i % 5 == 4 {
                        base + 1.0 + next() // never eligible
                    } else {
                        base + 0.4 * FTINY * next()
                    };
                    (i, t)
                })
                .collect();
            let tmin = hits.iter().map(|h| h.1).fold(f64::INFINITY, f64::min);
            let eligible: Vec<_> = hits
                .iter()
                .copied()
                .filter(|h| h.1 <= tmin + FTINY)
                .collect();
            assert!(eligible.len() <= WINDOW);
            let mut want = eligible[0];
            for &c in &eligible[1..] {
                if beats(c, want, &prefer) {
                    want = c;
                }
            }
            assert_eq!(
                select_closest(hits.clone(), 10.0, prefer),
                Some(want),
                "case {case}"
            );
        }
        // More coincident hits than the window holds: the farthest are dropped, never the
        // closest.
        let hits: Vec<(usize, f64)> = (0..3 * WINDOW)
            .map(|i| (i, 1.0 + FTINY * (0.9 - 0.02 * i as f64)))
            .collect();
        let last = hits[hits.len() - 1];
        assert_eq!(select_closest(hits, 10.0, |_, _| false), Some(last));
    }
}
