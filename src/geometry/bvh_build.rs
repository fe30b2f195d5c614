//! Building the BVH's trees ([`super::bvh`]): obvhs's PLOC builder over `f32` boxes
//! rounded outward, the chunked build of large inputs along a Morton curve, and the
//! flattening of the trees into the plain node and slot arrays a [`super::bvh::Bvh`] (and
//! a scene image) holds.

use glam::DVec3;
use obvhs::aabb::Aabb;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::{Boundable, BvhBuildParams};

/// Boxes per chunk of a large BVH: above this many boxes, they are sorted along a Morton
/// curve and cut into groups of this size, each built into its own tree, with a small tree
/// over the groups. The build's temporary binary tree then has the size of one group, not
/// of the whole set (a 10⁶-triangle mesh builds in half the memory and less time).
pub(super) const CHUNK: usize = 1 << 16;

/// A box as an obvhs primitive.
pub(super) struct BoxPrim(pub(super) Aabb);

impl Boundable for BoxPrim {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// How carefully a tree is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Quality {
    /// obvhs's `slow_build` settings (a wider PLOC search and more reinsertion than
    /// `medium_build`) and one surface per leaf: a surface's f64 test costs more than a
    /// node's eight f32 boxes. For inputs of one [`CHUNK`] at most. Against `Fast`, the
    /// render's instructions (callgrind, `-ab 1`, the build's own subtracted) fell 3.3% on
    /// the office of `bench/realscenes.sh`, 6.4% on its park (2,000 instances) and 0.5% on
    /// its hall (40,357 polygons), whose build took 21% more (0.74 → 0.89 G instructions,
    /// about 0.04 s); pictures are bit-identical (ties are resolved whatever the tree).
    Fine,
    /// `medium_build` with up to three surfaces per leaf, for the chunks of larger inputs:
    /// on a 1,008,200-triangle mesh `Fine` took its load and build from 0.9 to 1.45 s and
    /// its peak memory from 109 to 127 MB.
    Fast,
}

/// Build the wide BVH (PLOC, reinsertion, conversion to CwBvh) without obvhs's debug-build
/// validation, which asserts on trees deeper than its fixed traversal stack.
fn build_cw(prims: &[BoxPrim], quality: Quality) -> CwBvh {
    let (p, leaf) = match quality {
        Quality::Fine => (BvhBuildParams::slow_build(), 1),
        Quality::Fast => (BvhBuildParams::medium_build(), 3),
    };
    let mut bvh2 = PlocBuilder::with_capacity(prims.len()).build(
        p.ploc_search_distance,
        prims,
        (0..prims.len() as u32).collect(),
        p.sort_precision,
        p.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, p.reinsertion_batch_ratio, None);
    let mut cw = bvh2_to_cwbvh(&bvh2, p.max_prims_per_leaf.clamp(1, leaf), true, false);
    // The conversion reserves a node per box; a tree needs far fewer.
    cw.nodes.shrink_to_fit();
    cw.primitive_indices.shrink_to_fit();
    cw
}

/// [`build_cw`] on a thread with a large stack (the conversion recurses once per tree
/// level, and degenerate inputs make very deep trees); inline if no thread can be started.
pub(super) fn build_cw_big_stack(prims: &[BoxPrim], quality: Quality) -> CwBvh {
    let res = std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(s, || build_cw(prims, quality))
            .map(|h| h.join())
    });
    match res {
        Ok(Ok(cw)) => cw,
        Ok(Err(e)) => std::panic::resume_unwind(e),
        Err(_) => build_cw(prims, quality),
    }
}

/// Morton code (21 bits per axis) of a box's centre in the bounds `(lo, hi)`.
fn morton(b: &Aabb, lo: DVec3, hi: DVec3) -> u64 {
    let c = (b.min + b.max).as_dvec3() * 0.5;
    let q = ((c - lo) / (hi - lo).max(DVec3::splat(f64::MIN_POSITIVE)) * 2097151.0)
        .clamp(DVec3::ZERO, DVec3::splat(2097151.0));
    let spread = |v: f64| -> u64 {
        let mut x = v as u64 & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    spread(q.x) | spread(q.y) << 1 | spread(q.z) << 2
}

/// The tree of many boxes ([`CHUNK`]): the boxes sorted along a Morton curve, cut into
/// chunks each built alone, and a tree over the chunks' boxes. Returns the top tree (whose
/// primitives are the chunks) and each chunk's tree with the ids of its boxes.
pub(super) fn build_chunked(
    ids: Vec<u32>,
    boxed: impl Fn(u32) -> BoxPrim,
    lo: DVec3,
    hi: DVec3,
) -> (Option<CwBvh>, Vec<(CwBvh, Vec<u32>)>) {
    let mut order: Vec<(u64, u32)> = ids
        .iter()
        .map(|&i| (morton(&boxed(i).0, lo, hi), i))
        .collect();
    drop(ids);
    order.sort_unstable();
    let mut chunks = Vec::new();
    let mut tops = Vec::new();
    for group in order.chunks(CHUNK) {
        let prims: Vec<BoxPrim> = group.iter().map(|&(_, i)| boxed(i)).collect();
        let cw = build_cw_big_stack(&prims, Quality::Fast);
        if cw.nodes.is_empty() {
            continue;
        }
        let bounds = prims.iter().fold(Aabb::empty(), |acc, b| acc.union(&b.0));
        tops.push(BoxPrim(bounds));
        chunks.push((cw, group.iter().map(|&(_, i)| i).collect()));
    }
    drop(order);
    let top = Some(build_cw_big_stack(&tops, Quality::Fine)).filter(|cw| !cw.nodes.is_empty());
    (top, chunks)
}

/// Round an `f64` to the nearest `f32` that is `>= x`.
pub(super) fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// Round an `f64` to the nearest `f32` that is `<= x`.
pub(super) fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x {
        f.next_down()
    } else {
        f
    }
}

/// Append `cw`'s nodes and leaf slots to the arrays, mapping each slot through `ids`;
/// returns the index of its root.
pub(super) fn append(
    nodes: &mut Vec<CwBvhNode>,
    slots: &mut Vec<u32>,
    cw: &CwBvh,
    ids: &[u32],
) -> u32 {
    let (n0, s0) = (nodes.len() as u32, slots.len() as u32);
    nodes.extend(cw.nodes.iter().map(|n| CwBvhNode {
        child_base_idx: n.child_base_idx + n0,
        primitive_base_idx: n.primitive_base_idx + s0,
        ..*n
    }));
    slots.extend(
        cw.primitive_indices
            .iter()
            .map(|&k| ids.get(k as usize).copied().unwrap_or(u32::MAX)),
    );
    n0
}

/// Whether the trees in `nodes` can be walked without an index leaving the array and
/// without a cycle: every node's internal children lie in it after the node itself. (Leaf
/// slots are looked up with a bounds check; a scene image's BVH is checked with this before
/// use.)
pub(crate) fn tree_in_bounds(nodes: &[CwBvhNode]) -> bool {
    nodes.iter().enumerate().all(|(k, n)| {
        n.imask == 0
            || (u64::from(n.child_base_idx) > k as u64
                && u64::from(n.child_base_idx) + u64::from(n.imask.count_ones())
                    <= nodes.len() as u64)
    })
}
