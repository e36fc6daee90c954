//! Ray–triangle acceleration structure: a binned-SAH BVH2 over a triangle
//! soup, flattened into 32-byte nodes, with triangles stored in leaf order as
//! precomputed Möller–Trumbore edges.
//!
//! Queries are double-sided and report hits with `t` strictly inside
//! `(0, t_max)`, in units of the (not necessarily normalised) ray direction.
//! Degenerate (zero-area or non-finite) triangles are dropped at build time and
//! are never hit.
//!
//! Like Embree's, the slab test maps a zero direction component to a huge
//! reciprocal. A ray with such a component whose origin lies *exactly* in a
//! face plane of a node's box (for that axis) may therefore miss triangle edges
//! or vertices lying on that face; interiors are never missed.

mod build;

use crate::math::{Bounds3, Ray, Vec3};
use rayon::prelude::*;

/// Closest-hit record.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the hit, in units of `ray.d`.
    pub t: f32,
    /// Index of the triangle in the slice given to [`Bvh::build`].
    pub prim: u32,
    /// Barycentric coordinate of `v1`.
    pub b1: f32,
    /// Barycentric coordinate of `v2`.
    pub b2: f32,
}

/// Flattened BVH node (32 bytes). Interior nodes (`count == 0`) have their
/// children at `a` and `a + 1`; leaves hold triangles `a .. a + count`.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
struct Node {
    min: Vec3,
    a: u32,
    max: Vec3,
    count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    #[inline(always)]
    fn leaf(b: Bounds3, first: u32, count: u32) -> Node {
        Node {
            min: b.min,
            a: first,
            max: b.max,
            count,
        }
    }
    #[inline(always)]
    fn interior(b: Bounds3, first_child: u32) -> Node {
        Node {
            min: b.min,
            a: first_child,
            max: b.max,
            count: 0,
        }
    }
    #[inline(always)]
    fn is_leaf(&self) -> bool {
        self.count != 0
    }
}

/// Triangle in Möller–Trumbore form.
#[derive(Clone, Copy, Debug)]
struct Tri {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
}

impl Tri {
    #[inline(always)]
    fn new(t: &[Vec3; 3]) -> Tri {
        Tri {
            v0: t[0],
            e1: t[1] - t[0],
            e2: t[2] - t[0],
        }
    }

    /// Zero-area or non-finite triangles are never hit.
    #[inline]
    fn is_degenerate(&self) -> bool {
        let finite = self.v0.is_finite() && self.e1.is_finite() && self.e2.is_finite();
        !(finite && self.e1.cross(self.e2).length_squared() > 0.0)
    }

    /// Möller–Trumbore, double-sided. Returns `(t, b1, b2)` for a hit with
    /// `0 < t < t_max`.
    #[inline(always)]
    fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
        let p = d.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - self.v0;
        let u = s.dot(p) * inv;
        if !(u >= 0.0 && u <= 1.0) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = d.dot(q) * inv;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        if t > 0.0 && t < t_max {
            Some((t, u, v))
        } else {
            None
        }
    }
}

/// Bounding volume hierarchy over a triangle soup.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangles in leaf order.
    tris: Vec<Tri>,
    /// Input index of each triangle in `tris`.
    prim_ids: Vec<u32>,
}

/// Traversal stack size; the builder bounds the tree depth below this.
const STACK: usize = 64;
/// Slack on the far slab distance that makes the box test conservative
/// despite rounding (1 + 2γ₃, Ize 2013).
const ROBUST: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// Per-ray precomputation for the slab test.
#[derive(Clone, Copy)]
struct RayData {
    o: Vec3,
    d: Vec3,
    inv: Vec3,
}

impl RayData {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        // Zero components give ±inf; replace them with ±MAX so that
        // `0 * inv` is 0 (never NaN) and the slab test stays conservative.
        let inv = 1.0 / ray.d;
        let fix = |x: f32| if x.is_finite() { x } else { f32::MAX.copysign(x) };
        RayData {
            o: ray.o,
            d: ray.d,
            inv: Vec3::new(fix(inv.x), fix(inv.y), fix(inv.z)),
        }
    }

    /// Entry distance into the node's box if the ray overlaps it within
    /// `(0, t_max)`, else `f32::INFINITY`.
    #[inline(always)]
    fn slab(&self, n: &Node, t_max: f32) -> f32 {
        let x0 = (n.min.x - self.o.x) * self.inv.x;
        let x1 = (n.max.x - self.o.x) * self.inv.x;
        let y0 = (n.min.y - self.o.y) * self.inv.y;
        let y1 = (n.max.y - self.o.y) * self.inv.y;
        let z0 = (n.min.z - self.o.z) * self.inv.z;
        let z1 = (n.max.z - self.o.z) * self.inv.z;
        let tn = fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmax(fmin(z0, z1), 0.0));
        let tf = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmin(fmax(z0, z1), t_max));
        if tn <= tf * ROBUST {
            tn
        } else {
            f32::INFINITY
        }
    }
}

impl Bvh {
    /// Builds the BVH with binned SAH (parallel with rayon on large inputs).
    pub fn build(tris: &[[Vec3; 3]]) -> Bvh {
        let mut refs: Vec<build::PrimRef> = tris
            .par_iter()
            .with_min_len(4096)
            .enumerate()
            .filter_map(|(i, t)| {
                if Tri::new(t).is_degenerate() {
                    return None;
                }
                Some(build::PrimRef {
                    min: t[0].min(t[1]).min(t[2]),
                    idx: i as u32,
                    max: t[0].max(t[1]).max(t[2]),
                })
            })
            .collect();
        if refs.is_empty() {
            return Bvh {
                nodes: Vec::new(),
                tris: Vec::new(),
                prim_ids: Vec::new(),
            };
        }
        let nodes = build::build(&mut refs);
        let leaf_tris = refs
            .par_iter()
            .with_min_len(4096)
            .map(|r| Tri::new(&tris[r.idx as usize]))
            .collect();
        let prim_ids = refs.iter().map(|r| r.idx).collect();
        Bvh {
            nodes,
            tris: leaf_tris,
            prim_ids,
        }
    }

    /// Closest hit with `t` in `(0, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let Some(root) = self.nodes.first() else {
            return None;
        };
        let r = RayData::new(ray);
        let mut t_best = t_max;
        if !(r.slab(root, t_best) < f32::INFINITY) {
            return None;
        }
        let mut best = (u32::MAX, 0.0f32, 0.0f32);
        let mut stack = [(0u32, 0.0f32); STACK];
        let mut sp = 0usize;
        let mut ni = 0usize;
        'outer: loop {
            let node = &self.nodes[ni];
            if node.is_leaf() {
                let first = node.a as usize;
                let last = first + node.count as usize;
                for (i, tri) in self.tris[first..last].iter().enumerate() {
                    if let Some((t, u, v)) = tri.intersect(r.o, r.d, t_best) {
                        t_best = t;
                        best = ((first + i) as u32, u, v);
                    }
                }
            } else {
                let c = node.a as usize;
                let t0 = r.slab(&self.nodes[c], t_best);
                let t1 = r.slab(&self.nodes[c + 1], t_best);
                if t0 <= t1 {
                    if t0 < f32::INFINITY {
                        ni = c;
                        if t1 < f32::INFINITY {
                            stack[sp] = ((c + 1) as u32, t1);
                            sp += 1;
                        }
                        continue;
                    }
                } else {
                    ni = c + 1;
                    if t0 < f32::INFINITY {
                        stack[sp] = (c as u32, t0);
                        sp += 1;
                    }
                    continue;
                }
            }
            // Pop the next node that may still hold a closer hit.
            loop {
                if sp == 0 {
                    break 'outer;
                }
                sp -= 1;
                let (n, tn) = stack[sp];
                if tn <= t_best * ROBUST {
                    ni = n as usize;
                    break;
                }
            }
        }
        if best.0 == u32::MAX {
            return None;
        }
        Some(Hit {
            t: t_best,
            prim: self.prim_ids[best.0 as usize],
            b1: best.1,
            b2: best.2,
        })
    }

    /// Whether anything is hit with `t` in `(0, t_max)` (stops at the first hit).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let Some(root) = self.nodes.first() else {
            return false;
        };
        let r = RayData::new(ray);
        if !(r.slab(root, t_max) < f32::INFINITY) {
            return false;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 0usize;
        let mut ni = 0usize;
        loop {
            let node = &self.nodes[ni];
            if node.is_leaf() {
                let first = node.a as usize;
                let last = first + node.count as usize;
                for tri in &self.tris[first..last] {
                    if tri.intersect(r.o, r.d, t_max).is_some() {
                        return true;
                    }
                }
            } else {
                let c = node.a as usize;
                let t0 = r.slab(&self.nodes[c], t_max);
                let t1 = r.slab(&self.nodes[c + 1], t_max);
                if t0 <= t1 {
                    if t0 < f32::INFINITY {
                        ni = c;
                        if t1 < f32::INFINITY {
                            stack[sp] = (c + 1) as u32;
                            sp += 1;
                        }
                        continue;
                    }
                } else {
                    ni = c + 1;
                    if t0 < f32::INFINITY {
                        stack[sp] = c as u32;
                        sp += 1;
                    }
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            ni = stack[sp] as usize;
        }
    }

    #[doc(hidden)]
    pub fn debug_stats(&self, ray: &Ray, t_max: f32) -> (u32, u32) {
        let r = RayData::new(ray);
        let mut t_best = t_max;
        let (mut nodes, mut tris) = (0u32, 0u32);
        let mut stack = vec![(0usize, 0.0f32)];
        let mut order = Vec::new();
        if self.nodes.is_empty() || r.slab(&self.nodes[0], t_best) == f32::INFINITY { return (0,0); }
        while let Some((ni, tn)) = stack.pop() {
            if tn > t_best * ROBUST { continue; }
            let node = &self.nodes[ni];
            nodes += 1;
            if node.is_leaf() {
                for tri in &self.tris[node.a as usize..(node.a + node.count) as usize] {
                    tris += 1;
                    if let Some((t, _, _)) = tri.intersect(r.o, r.d, t_best) { t_best = t; }
                }
            } else {
                order.clear();
                for c in [node.a as usize, node.a as usize + 1] {
                    let t = r.slab(&self.nodes[c], t_best);
                    if t < f32::INFINITY { order.push((c, t)); }
                }
                order.sort_by(|a, b| b.1.total_cmp(&a.1));
                stack.extend(order.iter().copied());
            }
        }
        (nodes, tris)
    }

    /// Bounds of all non-degenerate triangles (empty for an empty BVH).
    pub fn bounds(&self) -> Bounds3 {
        self.nodes.first().map_or(Bounds3::EMPTY, |n| Bounds3 {
            min: n.min,
            max: n.max,
        })
    }

    /// Number of BVH nodes (interior and leaves).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Heap plus inline memory used by the structure, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.nodes.capacity() * std::mem::size_of::<Node>()
            + self.tris.capacity() * std::mem::size_of::<Tri>()
            + self.prim_ids.capacity() * std::mem::size_of::<u32>()
    }
}

#[cfg(test)]
mod tests;
