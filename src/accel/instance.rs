//! Instancing: a top-level BVH over placed copies (instances) of shared triangle groups.
//!
//! Each group has one bottom-level [`Bvh`] in its own (local) coordinates; an instance is
//! a group and its `to_world`. A query walks a binary BVH over the instances' world
//! bounds and, at each instance it reaches, moves the ray into the group's space (the
//! direction by the linear part alone and left unnormalised, so that the ray parameter
//! `t` is the same in both spaces) and asks the group's BVH. The triangles are stored
//! once per group whatever the number of instances: a thousand instances of a group
//! cost a thousand transforms and top-level nodes, not a thousand copies.
//!
//! A hit on an instance is returned in world space (point by `to_world`, normal by its
//! inverse transpose), with `prim` numbered after the scene's own triangles: instance
//! `i`'s triangle `k` is `base + first[i] + k` (see [`Instances::locate`]).

use super::{Bvh, Hit};
use crate::math::{Bounds3, Ray, Vec3};
use glam::{Affine3A, Mat3, Mat4, Vec3A};
use std::cell::Cell;

/// One placed group.
#[derive(Clone, Debug)]
struct Placed {
    group: u32,
    to_world: Affine3A,
    to_local: Affine3A,
    /// Inverse transpose of `to_world`'s linear part (normals to world space).
    normal: Mat3,
    /// Number of this instance's first triangle after `base`.
    first: u32,
}

/// A node of the top-level BVH: a leaf holds `count > 0` instances from `index` (in
/// `order`); an interior node's left child follows it and its right child is `index`.
#[derive(Clone, Copy, Debug)]
pub(super) struct TopNode {
    pub(super) min: Vec3A,
    pub(super) max: Vec3A,
    pub(super) index: u32,
    pub(super) count: u32,
}

/// The groups' BVHs and the instances placing them (see the module docs).
#[derive(Clone, Debug)]
pub struct Instances {
    groups: Vec<Bvh>,
    /// Triangles per group (degenerate ones included: they keep their numbers).
    group_tris: Vec<u32>,
    placed: Vec<Placed>,
    /// Instance indices in the top-level leaves' order.
    order: Vec<u32>,
    nodes: Vec<TopNode>,
    base: u32,
    bounds: Bounds3,
}

/// Instances per top-level leaf at most.
const LEAF: usize = 2;
/// Top-level traversal stack: the median split keeps the depth near log2(instances).
const STACK: usize = 64;

impl Instances {
    /// Builds one BVH per group (`groups[g]`: its local triangles) and the top level over
    /// `instances` (group index, `to_world`). Instanced triangles are numbered from
    /// `base`. An instance whose transform is not invertible or whose group index is out
    /// of range is an error naming it.
    pub fn build(
        groups: &[&[[Vec3; 3]]],
        instances: &[(u32, Mat4)],
        base: u32,
    ) -> Result<Instances, String> {
        let bvhs: Vec<Bvh> = groups.iter().map(|g| Bvh::build(g)).collect();
        let group_tris: Vec<u32> = groups.iter().map(|g| g.len() as u32).collect();
        let mut placed = Vec::with_capacity(instances.len());
        let mut first: u64 = 0;
        let mut boxes: Vec<(Vec3A, Vec3A)> = Vec::with_capacity(instances.len());
        for (i, &(g, m)) in instances.iter().enumerate() {
            let Some(bvh) = bvhs.get(g as usize) else {
                return Err(format!("instance {i}: no group {g}"));
            };
            let to_world = Affine3A::from_mat4(m);
            let det = to_world.matrix3.determinant();
            if !(det.is_finite() && det.abs() > 1e-30 && m.is_finite()) {
                return Err(format!(
                    "instance {i}: its to_world is not invertible (determinant {det})"
                ));
            }
            let lin = Mat3::from(to_world.matrix3);
            placed.push(Placed {
                group: g,
                to_world,
                to_local: to_world.inverse(),
                normal: lin.inverse().transpose(),
                first: first as u32,
            });
            first += group_tris[g as usize] as u64;
            let b = transformed_bounds(&bvh.bounds(), &to_world);
            boxes.push((b.min.into(), b.max.into()));
        }
        if base as u64 + first > u32::MAX as u64 / 2 {
            return Err(format!(
                "{} instanced triangles: more than kalos numbers ({})",
                first,
                u32::MAX / 2
            ));
        }
        let mut order: Vec<u32> = (0..instances.len() as u32)
            .filter(|&i| boxes[i as usize].0.cmple(boxes[i as usize].1).all())
            .collect();
        let mut nodes = Vec::with_capacity(2 * order.len() / LEAF + 1);
        let mut bounds = Bounds3::EMPTY;
        if !order.is_empty() {
            let n = order.len();
            build_top(&boxes, &mut order, 0, n, &mut nodes);
            bounds.grow(nodes[0].min.into());
            bounds.grow(nodes[0].max.into());
        }
        Ok(Instances {
            groups: bvhs,
            group_tris,
            placed,
            order,
            nodes,
            base,
            bounds,
        })
    }

    /// World bounds of all instances.
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// Number of instances.
    pub fn len(&self) -> usize {
        self.placed.len()
    }

    /// Whether there are no instances.
    pub fn is_empty(&self) -> bool {
        self.placed.is_empty()
    }

    /// Heap plus inline memory of the groups' BVHs and the top level, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.groups.iter().map(Bvh::memory_bytes).sum::<usize>()
            + self.placed.capacity() * std::mem::size_of::<Placed>()
            + self.order.capacity() * 4
            + self.nodes.capacity() * std::mem::size_of::<TopNode>()
    }

    /// The instance, its group and the group's triangle of an instanced `prim` (`None`
    /// for the scene's own triangles, below `base`, and numbers beyond the last).
    pub fn locate(&self, prim: u32) -> Option<(u32, u32, u32)> {
        let k = prim.checked_sub(self.base)?;
        let i = self
            .placed
            .partition_point(|p| p.first <= k)
            .checked_sub(1)?;
        let p = &self.placed[i];
        let local = k - p.first;
        (local < self.group_tris[p.group as usize]).then_some((i as u32, p.group, local))
    }

    /// Instance `i`'s `to_world`.
    pub fn to_world(&self, i: u32) -> Affine3A {
        self.placed[i as usize].to_world
    }

    /// Instance `i`'s normal transform (the inverse transpose of `to_world`'s linear part).
    pub fn normal_matrix(&self, i: u32) -> Mat3 {
        self.placed[i as usize].normal
    }

    /// The closest instanced hit with `t` in `(0, t_max)`, in world space.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut best: Option<(Hit, u32)> = None;
        let t_best = Cell::new(t_max);
        self.walk(ray, &t_best, |r, i, p| {
            if let Some(h) = self.groups[p.group as usize].intersect(r, t_best.get()) {
                t_best.set(h.t);
                best = Some((h, i));
            }
            false
        });
        let (mut h, i) = best?;
        let p = &self.placed[i as usize];
        h.p = p.to_world.transform_point3(h.p);
        h.n = p.normal * h.n;
        h.prim += self.base + p.first;
        Some(h)
    }

    /// Whether an instance is hit with `t` in `(0, t_max)`.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut hit = false;
        self.walk(ray, &Cell::new(t_max), |r, _, p| {
            hit = self.groups[p.group as usize].occluded(r, t_max);
            hit
        });
        hit
    }

    /// Calls `visit` with the ray in the space of each instance whose box the ray enters
    /// before `t_max` (which `visit` may shorten), until it returns true.
    fn walk(
        &self,
        ray: &Ray,
        t_max: &Cell<f32>,
        mut visit: impl FnMut(&Ray, u32, &Placed) -> bool,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let o = Vec3A::from(ray.o);
        let inv = Vec3A::ONE / Vec3A::from(ray.d);
        let inv = Vec3A::select(inv.is_finite_mask(), inv, inv.signum() * f32::MAX);
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = &self.nodes[stack[sp] as usize];
            let (a, b) = ((n.min - o) * inv, (n.max - o) * inv);
            let (t0, t1) = (
                a.min(b).max_element().max(0.0),
                a.max(b).min_element().min(t_max.get()),
            );
            // (conservative by a few ulps, as the triangle BVH's slab test)
            if t1 * (1.0 + 4.0 * f32::EPSILON) < t0 {
                continue;
            }
            if n.count > 0 {
                for &i in &self.order[n.index as usize..(n.index + n.count) as usize] {
                    let p = &self.placed[i as usize];
                    let local = Ray::new(
                        p.to_local.transform_point3(ray.o),
                        p.to_local.transform_vector3(ray.d),
                    );
                    if visit(&local, i, p) {
                        return;
                    }
                }
            } else if sp + 2 <= STACK {
                let me = stack[sp] as usize;
                stack[sp] = n.index;
                stack[sp + 1] = me as u32 + 1;
                sp += 2;
            }
        }
    }
}

/// The box holding `b` moved by `m` (its eight corners); empty stays empty.
pub fn transformed_bounds(b: &Bounds3, m: &Affine3A) -> Bounds3 {
    let mut out = Bounds3::EMPTY;
    if b.is_empty() {
        return out;
    }
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { b.min.x } else { b.max.x },
            if k & 2 == 0 { b.min.y } else { b.max.y },
            if k & 4 == 0 { b.min.z } else { b.max.z },
        );
        out.grow(m.transform_point3(c));
    }
    out
}

/// Builds the top-level node over `order[lo..hi]` (median split of the centroids on the
/// widest axis) and its subtree, depth first; returns its index.
pub(super) fn build_top(
    boxes: &[(Vec3A, Vec3A)],
    order: &mut [u32],
    lo: usize,
    hi: usize,
    nodes: &mut Vec<TopNode>,
) -> usize {
    let (mut min, mut max) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    let (mut cmin, mut cmax) = (min, max);
    for &i in &order[lo..hi] {
        let (a, b) = boxes[i as usize];
        min = min.min(a);
        max = max.max(b);
        cmin = cmin.min(a + b);
        cmax = cmax.max(a + b);
    }
    let me = nodes.len();
    nodes.push(TopNode {
        min,
        max,
        index: lo as u32,
        count: (hi - lo) as u32,
    });
    if hi - lo <= LEAF {
        return me;
    }
    let ext = cmax - cmin;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = (lo + hi) / 2;
    let key = |i: &u32| {
        let (a, b) = boxes[*i as usize];
        (a + b)[axis]
    };
    order[lo..hi].select_nth_unstable_by(mid - lo, |x, y| key(x).total_cmp(&key(y)));
    build_top(boxes, order, lo, mid, nodes);
    let right = build_top(boxes, order, mid, hi, nodes);
    nodes[me].index = right as u32;
    nodes[me].count = 0;
    me
}

#[cfg(test)]
#[path = "instance_tests.rs"]
mod tests;
