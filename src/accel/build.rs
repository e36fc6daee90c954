//! Binned-SAH BVH2 construction (parallel with rayon), producing a flattened,
//! depth-first node array in which the two children of an interior node are
//! always adjacent.

use super::Node;
use crate::math::{Bounds3, Vec3};

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

/// A primitive reference: its bounding box and its index in the input.
#[derive(Clone, Copy, Debug)]
pub(super) struct PrimRef {
    pub min: Vec3,
    pub idx: u32,
    pub max: Vec3,
}

impl PrimRef {
    /// Twice the centroid (the factor does not matter for binning).
    #[inline(always)]
    fn c(&self) -> Vec3 {
        self.min + self.max
    }
}

#[inline(always)]
fn bounds_of(refs: &[PrimRef]) -> Bounds3 {
    let mut b = Bounds3::EMPTY;
    for r in refs {
        b.min = b.min.min(r.min);
        b.max = b.max.max(r.max);
    }
    b
}

#[derive(Clone, Copy)]
struct Bin {
    b: Bounds3,
    n: u32,
}

struct Split {
    axis: usize,
    bin: usize,
    /// SAH cost of the split, scaled by the node's half area (as is the leaf
    /// cost it is compared with).
    cost: f32,
}

/// Builds the tree over `refs` (which it reorders into leaf order).
/// Returns the flattened nodes; node 0 is the root. `refs` must be non-empty.
pub(super) fn build(refs: &mut [PrimRef]) -> Vec<Node> {
    debug_assert!(!refs.is_empty());
    let n = refs.len();
    let bounds = bounds_of(refs);
    // A subtree over k primitives uses at most 2k - 1 nodes; slots are
    // pre-assigned that way so subtrees can be built in parallel into disjoint
    // slices. Unused slots are squeezed out afterwards.
    let mut slots = vec![Node::default(); 2 * n - 1];
    let (root, desc) = slots.split_at_mut(1);
    root[0] = build_rec(refs, 0, bounds, 0, desc, 1);
    compact(&slots)
}

fn build_rec(
    refs: &mut [PrimRef],
    first: u32,
    bounds: Bounds3,
    depth: u32,
    desc: &mut [Node],
    desc_base: u32,
) -> Node {
    let n = refs.len();
    let leaf = Node::leaf(bounds, first, n as u32);
    if n == 1 {
        return leaf;
    }
    let mut cb = Bounds3::EMPTY;
    for r in refs.iter() {
        cb.grow(r.c());
    }
    let ext = cb.extent();
    let degenerate = !(ext.max_element() > 0.0);

    let mut nl = 0;
    if !degenerate && depth < SAH_DEPTH {
        if let Some(s) = find_split(refs, &cb, bounds.half_area()) {
            // Leaf cost (also scaled by the half area).
            let leaf_cost = blocks(n as u32) * bounds.half_area();
            if n <= MAX_LEAF && leaf_cost <= s.cost {
                return leaf;
            }
            let (lo, scale) = bin_params(&cb, s.axis);
            nl = partition(refs, |r| bin_index(r.c()[s.axis], lo, scale) < s.bin);
        }
    } else if n <= MAX_LEAF {
        return leaf;
    }
    if nl == 0 || nl == n {
        // Object median along the widest centroid axis.
        let axis = if degenerate { 0 } else { ext.max_position() };
        nl = n / 2;
        refs.select_nth_unstable_by(nl, |a, b| a.c()[axis].total_cmp(&b.c()[axis]));
    }
    let nr = n - nl;

    let (lrefs, rrefs) = refs.split_at_mut(nl);
    let lb = bounds_of(lrefs);
    let rb = bounds_of(rrefs);
    let (pair, rest) = desc.split_at_mut(2);
    let (ldesc, rdesc) = rest.split_at_mut(2 * nl - 2);
    let lbase = desc_base + 2;
    let rbase = desc_base + 2 * nl as u32;
    let (lnode, rnode) = if n > PAR_THRESHOLD {
        rayon::join(
            || build_rec(lrefs, first, lb, depth + 1, ldesc, lbase),
            || build_rec(rrefs, first + nl as u32, rb, depth + 1, rdesc, rbase),
        )
    } else {
        (
            build_rec(lrefs, first, lb, depth + 1, ldesc, lbase),
            build_rec(rrefs, first + nl as u32, rb, depth + 1, rdesc, rbase),
        )
    };
    debug_assert_eq!(nl + nr, n);
    pair[0] = lnode;
    pair[1] = rnode;
    Node::interior(bounds, desc_base)
}

#[inline(always)]
fn bin_params(cb: &Bounds3, axis: usize) -> (f32, f32) {
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
fn find_split(refs: &[PrimRef], cb: &Bounds3, node_area: f32) -> Option<Split> {
    let empty = Bin {
        b: Bounds3::EMPTY,
        n: 0,
    };
    let mut bins = [[empty; BINS]; 3];
    let mut params = [(0.0f32, 0.0f32); 3];
    let ext = cb.extent();
    for (axis, p) in params.iter_mut().enumerate() {
        *p = if ext[axis] > 0.0 {
            bin_params(cb, axis)
        } else {
            (cb.min[axis], 0.0)
        };
    }
    for r in refs {
        let c = r.c();
        for axis in 0..3 {
            let (lo, scale) = params[axis];
            let bin = &mut bins[axis][bin_index(c[axis], lo, scale)];
            bin.n += 1;
            bin.b.min = bin.b.min.min(r.min);
            bin.b.max = bin.b.max.max(r.max);
        }
    }
    let mut best: Option<Split> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if !(ext[axis] > 0.0) {
            continue;
        }
        // Right-to-left sweep: cost contribution of the right part.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Bounds3::EMPTY;
        let mut cnt = 0u32;
        for i in (1..BINS).rev() {
            acc = acc.union(&bins[i].b);
            cnt += bins[i].n;
            right_cost[i] = acc.half_area() * blocks(cnt);
        }
        let mut acc = Bounds3::EMPTY;
        let mut cnt = 0u32;
        let total = refs.len() as u32;
        for i in 1..BINS {
            acc = acc.union(&bins[i - 1].b);
            cnt += bins[i - 1].n;
            if cnt == 0 || cnt == total {
                continue;
            }
            let cost = acc.half_area() * blocks(cnt) + right_cost[i];
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    bin: i,
                    cost,
                });
            }
        }
    }
    best.map(|mut s| {
        s.cost += C_TRAV * node_area;
        s
    })
}

/// In-place partition; returns the number of elements satisfying `pred`
/// (which end up first).
fn partition(refs: &mut [PrimRef], pred: impl Fn(&PrimRef) -> bool) -> usize {
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if pred(&refs[i]) {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    i
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
