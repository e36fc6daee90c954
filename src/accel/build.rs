//! Binned-SAH BVH2 construction (parallel with rayon), producing a flattened,
//! depth-first node array in which the two children of an interior node are
//! always adjacent.
//!
//! Each node costs two passes over its primitives: one binning pass (which
//! also yields the children's bounds and centroid bounds) and one partition.

use super::Node;
use crate::math::{Bounds3, Vec3};
use glam::Vec3A;

/// Largest leaf the SAH may choose; larger ranges are always split.
pub(super) const MAX_LEAF: usize = 4;
/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Ranges larger than this build their two subtrees with `rayon::join`.
const PAR_THRESHOLD: usize = 4096;
/// Below this depth the SAH is used; deeper, object-median splits guarantee
/// that the tree depth stays below `SAH_DEPTH + 32` (the traversal stack size
/// relies on this).
const SAH_DEPTH: u32 = 28;
/// SAH cost of traversing an interior node, relative to one 4-wide triangle
/// packet test. Measured (examples/bvh_bench.rs): 0.1–0.25 is ~25% faster
/// than 1.0 on the Cornell box and makes no measurable difference on the
/// 1M-triangle mesh, where 0.1 costs 15% more memory.
const C_TRAV: f32 = 0.25;

/// Triangles are tested four at a time: SAH cost of `n` triangles.
#[inline(always)]
fn blocks(n: u32) -> f32 {
    n.div_ceil(4) as f32
}

/// A primitive's bounding box (its input index is kept in a parallel array).
#[derive(Clone, Copy, Debug)]
pub(super) struct PrimRef {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl PrimRef {
    /// Twice the centroid (the factor does not matter for binning).
    #[inline(always)]
    fn c(&self) -> Vec3A {
        self.min + self.max
    }
}

/// Axis-aligned box on SIMD vectors.
#[derive(Clone, Copy, Debug)]
struct Box3 {
    min: Vec3A,
    max: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };
    #[inline(always)]
    fn grow(&mut self, min: Vec3A, max: Vec3A) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
    }
    #[inline(always)]
    fn union(&self, o: &Box3) -> Box3 {
        Box3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
    fn to_bounds(self) -> Bounds3 {
        Bounds3 {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }
}

/// Bounds and centroid bounds of a range.
#[derive(Clone, Copy, Debug)]
struct RangeInfo {
    b: Box3,
    cb: Box3,
}

fn range_info(refs: &[PrimRef]) -> RangeInfo {
    let mut r = RangeInfo {
        b: Box3::EMPTY,
        cb: Box3::EMPTY,
    };
    for p in refs {
        r.b.grow(p.min, p.max);
        let c = p.c();
        r.cb.grow(c, c);
    }
    r
}

#[derive(Clone, Copy)]
struct Bin {
    b: Box3,
    cb: Box3,
    n: u32,
}

struct Split {
    axis: usize,
    bin: usize,
    /// SAH cost of the split, scaled by the node's half area (as is the leaf
    /// cost it is compared with).
    cost: f32,
    left: RangeInfo,
    right: RangeInfo,
}

/// Builds the tree over `refs`/`ids` (which it reorders into leaf order).
/// Returns the flattened nodes; node 0 is the root. `refs` must be non-empty.
pub(super) fn build(refs: &mut [PrimRef], ids: &mut [u32]) -> Vec<Node> {
    debug_assert!(!refs.is_empty() && refs.len() == ids.len());
    let n = refs.len();
    let info = range_info(refs);
    // A subtree over k primitives uses at most 2k - 1 nodes; slots are
    // pre-assigned that way so subtrees can be built in parallel into disjoint
    // slices. Unused slots are squeezed out afterwards.
    let mut slots = vec![Node::default(); 2 * n - 1];
    let (root, desc) = slots.split_at_mut(1);
    let task = Task {
        refs,
        ids,
        first: 0,
        info,
        depth: 0,
    };
    root[0] = task.run(desc, 1);
    compact(&slots)
}

struct Task<'a> {
    refs: &'a mut [PrimRef],
    ids: &'a mut [u32],
    /// Index of `refs[0]` in the whole array.
    first: u32,
    info: RangeInfo,
    depth: u32,
}

impl Task<'_> {
    /// Builds this subtree; its descendants go to `desc` (which will be node
    /// indices `desc_base..`). Returns the subtree's root node.
    fn run(self, desc: &mut [Node], desc_base: u32) -> Node {
        let n = self.refs.len();
        let bounds = self.info.b.to_bounds();
        let leaf = Node::leaf(bounds, self.first, n as u32);
        if n == 1 {
            return leaf;
        }
        let cb = &self.info.cb;
        // (A NaN extent counts as degenerate too.)
        let ext = (cb.max - cb.min).max_element();
        let degenerate = ext.is_nan() || ext <= 0.0;

        let mut split = None;
        if !degenerate && self.depth < SAH_DEPTH {
            if let Some(s) = find_split(self.refs, cb, self.info.b.half_area()) {
                // Leaf cost (also scaled by the half area).
                let leaf_cost = blocks(n as u32) * self.info.b.half_area();
                if n <= MAX_LEAF && leaf_cost <= s.cost {
                    return leaf;
                }
                let (lo, scale) = bin_params(cb, s.axis);
                let nl = partition(self.refs, self.ids, |r| {
                    bin_index(r.c()[s.axis], lo, scale) < s.bin
                });
                split = Some((nl, s.left, s.right));
            }
        } else if n <= MAX_LEAF {
            return leaf;
        }
        let (nl, linfo, rinfo) = match split {
            Some(s) if s.0 > 0 && s.0 < n => s,
            _ => {
                // Object median along the widest centroid axis.
                let axis = if degenerate {
                    0
                } else {
                    (cb.max - cb.min).max_position()
                };
                let nl = n / 2;
                median_split(self.refs, self.ids, nl, axis);
                (
                    nl,
                    range_info(&self.refs[..nl]),
                    range_info(&self.refs[nl..]),
                )
            }
        };

        let (lrefs, rrefs) = self.refs.split_at_mut(nl);
        let (lids, rids) = self.ids.split_at_mut(nl);
        let (pair, rest) = desc.split_at_mut(2);
        let (ldesc, rdesc) = rest.split_at_mut(2 * nl - 2);
        let left = Task {
            refs: lrefs,
            ids: lids,
            first: self.first,
            info: linfo,
            depth: self.depth + 1,
        };
        let right = Task {
            refs: rrefs,
            ids: rids,
            first: self.first + nl as u32,
            info: rinfo,
            depth: self.depth + 1,
        };
        let lbase = desc_base + 2;
        let rbase = desc_base + 2 * nl as u32;
        let (lnode, rnode) = if n > PAR_THRESHOLD {
            rayon::join(|| left.run(ldesc, lbase), || right.run(rdesc, rbase))
        } else {
            (left.run(ldesc, lbase), right.run(rdesc, rbase))
        };
        pair[0] = lnode;
        pair[1] = rnode;
        Node::interior(bounds, desc_base)
    }
}

#[inline(always)]
fn bin_params(cb: &Box3, axis: usize) -> (f32, f32) {
    let lo = cb.min[axis];
    let e = cb.max[axis] - lo;
    (lo, BINS as f32 * (1.0 - 1e-5) / e)
}

#[inline(always)]
fn bin_index(c: f32, lo: f32, scale: f32) -> usize {
    // `as` saturates (and maps NaN to 0), so this is always in range.
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// Best binned-SAH split over the three axes, if any splits the range into two
/// non-empty parts.
fn find_split(refs: &[PrimRef], cb: &Box3, node_area: f32) -> Option<Split> {
    let empty = Bin {
        b: Box3::EMPTY,
        cb: Box3::EMPTY,
        n: 0,
    };
    let mut bins = [[empty; BINS]; 3];
    let ext = cb.max - cb.min;
    let mut lo = [0.0f32; 3];
    let mut scale = [0.0f32; 3];
    for axis in 0..3 {
        if ext[axis] > 0.0 {
            (lo[axis], scale[axis]) = bin_params(cb, axis);
        }
    }
    let lo_v = Vec3A::from_array(lo);
    let scale_v = Vec3A::from_array(scale);
    for r in refs {
        let c = r.c();
        let f = (c - lo_v) * scale_v;
        for axis in 0..3 {
            let bin = &mut bins[axis][(f[axis] as usize).min(BINS - 1)];
            bin.n += 1;
            bin.b.grow(r.min, r.max);
            bin.cb.grow(c, c);
        }
    }
    let total = refs.len() as u32;
    let mut best: Option<(usize, usize, f32)> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if ext[axis].is_nan() || ext[axis] <= 0.0 {
            continue;
        }
        // Right-to-left sweep: cost contribution of the right part.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Box3::EMPTY;
        let mut cnt = 0u32;
        for i in (1..BINS).rev() {
            acc = acc.union(&bins[i].b);
            cnt += bins[i].n;
            right_cost[i] = acc.half_area() * blocks(cnt);
        }
        let mut acc = Box3::EMPTY;
        let mut cnt = 0u32;
        for i in 1..BINS {
            acc = acc.union(&bins[i - 1].b);
            cnt += bins[i - 1].n;
            if cnt == 0 || cnt == total {
                continue;
            }
            let cost = acc.half_area() * blocks(cnt) + right_cost[i];
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, i, cost));
            }
        }
    }
    let (axis, bin, cost) = best?;
    let side = |range: std::ops::Range<usize>| {
        bins[axis][range].iter().fold(
            RangeInfo {
                b: Box3::EMPTY,
                cb: Box3::EMPTY,
            },
            |a, b| RangeInfo {
                b: a.b.union(&b.b),
                cb: a.cb.union(&b.cb),
            },
        )
    };
    Some(Split {
        axis,
        bin,
        cost: cost + C_TRAV * node_area,
        left: side(0..bin),
        right: side(bin..BINS),
    })
}

/// In-place partition of `refs` (and `ids` alongside); returns the number of
/// elements satisfying `pred` (which end up first).
fn partition(refs: &mut [PrimRef], ids: &mut [u32], pred: impl Fn(&PrimRef) -> bool) -> usize {
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if pred(&refs[i]) {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
            ids.swap(i, j);
        }
    }
    i
}

/// Puts the `nl` primitives with the smallest centroids along `axis` first.
fn median_split(refs: &mut [PrimRef], ids: &mut [u32], nl: usize, axis: usize) {
    let mut order: Vec<(PrimRef, u32)> = refs.iter().copied().zip(ids.iter().copied()).collect();
    order.select_nth_unstable_by(nl, |a, b| a.0.c()[axis].total_cmp(&b.0.c()[axis]));
    for (k, (r, id)) in order.into_iter().enumerate() {
        refs[k] = r;
        ids[k] = id;
    }
}

/// Removes the unused slots, laying the tree out depth-first (left subtree
/// right after its sibling pair) with sibling pairs adjacent.
fn compact(slots: &[Node]) -> Vec<Node> {
    let mut out: Vec<Node> = Vec::with_capacity(slots.len());
    out.push(slots[0]);
    // (slot index of the old node, index of its copy in `out`)
    let mut stack: Vec<(usize, usize)> = vec![(0, 0)];
    while let Some((old, new)) = stack.pop() {
        let node = slots[old];
        if node.is_leaf() {
            continue;
        }
        let c = node.a as usize;
        let nc = out.len();
        out.push(slots[c]);
        out.push(slots[c + 1]);
        out[new].a = nc as u32;
        // Right pushed first so the left subtree is laid out first.
        stack.push((c + 1, nc + 1));
        stack.push((c, nc));
    }
    out.shrink_to_fit();
    out
}
