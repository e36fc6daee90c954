//! The tree's nodes: the builder's 32-byte BVH2 `Node` and the 8-wide `Node8` the
//! traversal walks (SoA child boxes and references), with the leaf reference encoding.

use super::*;

/// Flattened BVH2 node (32 bytes), the builder's output. Interior nodes
/// (`count == 0`) have their children at `a` and `a + 1`; leaves hold
/// primitives `a .. a + count` of the builder's leaf order.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
pub(super) struct Node {
    pub(super) min: Vec3,
    pub(super) a: u32,
    pub(super) max: Vec3,
    pub(super) count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    #[inline(always)]
    pub(super) fn leaf(b: Bounds3, first: u32, count: u32) -> Node {
        Node {
            min: b.min,
            a: first,
            max: b.max,
            count,
        }
    }
    #[inline(always)]
    pub(super) fn interior(b: Bounds3, first_child: u32) -> Node {
        Node {
            min: b.min,
            a: first_child,
            max: b.max,
            count: 0,
        }
    }
    #[inline(always)]
    pub(super) fn is_leaf(&self) -> bool {
        self.count != 0
    }
}

/// Children per BVH node.
pub(super) const WIDTH: usize = 8;

/// Eight-wide BVH node (256 bytes, four cache lines): the boxes of up to
/// eight children in SoA form, lanes = children, and their references. One
/// AVX2 slab test covers the eight boxes (two SSE ones on the baseline).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node8 {
    /// min.x, min.y, min.z, max.x, max.y, max.z of the eight children.
    pub(super) b: [[f32; WIDTH]; 6],
    /// Child references (see [`LEAF`]); unused slots have empty boxes.
    pub(super) child: [u32; WIDTH],
}

/// Child reference flag: a leaf, encoded as `LEAF | packet << 3 | (count - 1)`
/// (its `count <= 8` triangles fill `Tri4` packets `packet ..` in order, four
/// to a packet but the last). Otherwise a `Node8` index.
pub(super) const LEAF: u32 = 1 << 31;
/// Most triangles a leaf holds (two packets).
pub(super) const MAX_LEAF_TRIS: u32 = 8;
const _: () = assert!(build::MAX_LEAF as u32 <= MAX_LEAF_TRIS);
const _: () = assert!(std::mem::size_of::<Tri4>() == 160);

#[inline(always)]
pub(super) fn leaf_ref(first: u32, count: u32) -> u32 {
    debug_assert!((1..=MAX_LEAF_TRIS).contains(&count) && first < 1 << 28);
    LEAF | first << 3 | (count - 1)
}

/// First packet and triangle count of a leaf reference.
#[inline(always)]
pub(super) fn leaf_packets(r: u32) -> (usize, u32) {
    (((r & !LEAF) >> 3) as usize, (r & 7) + 1)
}

/// Lane mask of a packet holding the next `left` (>= 1) triangles of a leaf.
#[inline(always)]
pub(super) fn lane_mask(left: u32) -> u32 {
    (1u32 << left.min(4)) - 1
}
