//! Signed-distance grids (Mitsuba's `sdfgrid`), traced analytically as Mitsuba traces them.
//!
//! A grid of `nx x ny x nz` distance samples (x fastest) spans the unit cube [0, 1]^3 of
//! its own space; between samples the distance is the trilinear interpolant of a voxel's
//! eight corners. Only voxels whose corners are not all of one sign (some >= 0 and some
//! <= 0) hold surface: a binary BVH over those voxels' boxes (the instances' median-split
//! builder) finds the voxels a ray crosses, and in each the ray meets the surface where the
//! trilinear interpolant along it, a cubic in `t`, vanishes (Hansson-Söderlund, Evans and
//! Akenine-Möller 2022): the interval is split at the roots of the cubic's derivative so
//! that the bracket is monotonic, then safeguarded Newton iterations refine the first root
//! (Marmitt et al. 2004), stopping at a step below 1e-5 in ray units, as Mitsuba does. The
//! values where the ray enters and leaves a voxel are taken on the crossed face, where two
//! neighbouring voxels agree bit for bit, so that no hit is lost between them.
//!
//! The geometric normal is the interpolant's gradient; the shading normal is either that
//! (`analytic`) or Mitsuba's default `smooth` one: the finite-difference gradients of the
//! eight voxels around the nearest sample, blended trilinearly (continuous across voxels).
//! A grid is placed by a `to_world` (an instance's and the shape's own); hits are
//! returned in world space with `prim` numbered from [`SDF_FIRST_PRIM`]: one number per
//! occupied voxel of each placed grid.

use super::instance::{build_top, TopNode};
use super::Hit;
use crate::math::{Bounds3, Ray, Vec3};
use glam::{Affine3A, Mat3, Mat4, Vec3A};
use std::cmp::Ordering::{Equal, Greater, Less};
use std::sync::Arc;

/// The first hit number (`Hit::prim`) of the grids' voxels: the scene's own and instanced
/// triangles are numbered below `u32::MAX / 2`.
pub const SDF_FIRST_PRIM: u32 = 1 << 31;
/// The root finder stops at a step below this, in ray parameter units (Mitsuba's).
const SOLVE_EPSILON: f32 = 1e-5;
/// Newton steps at most (Mitsuba's).
const SOLVE_MAX_ITER: u32 = 50;
/// Traversal stack of the voxel BVH (median splits: depth near log2(voxels)).
const STACK: usize = 64;

/// A distance grid and the BVH over its occupied voxels, in the grid's space [0, 1]^3.
#[derive(Clone, Debug)]
pub struct SdfGrid {
    res: [u32; 3],
    values: Vec<f32>,
    /// Sample index of each occupied voxel's lower corner.
    voxels: Vec<u32>,
    nodes: Vec<TopNode>,
    /// Voxel indices in the BVH leaves' order.
    order: Vec<u32>,
}

/// Linear interpolation that returns `a` at 0 and `b` at 1 exactly.
#[inline(always)]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a - a * t + b * t
}

/// Bilinear interpolant of `f` (indexed u + 2v) at (u, v).
#[inline(always)]
fn bilerp(f: [f32; 4], u: f32, v: f32) -> f32 {
    lerp(lerp(f[0], f[1], u), lerp(f[2], f[3], u), v)
}

/// Trilinear interpolant of the corners `f` (indexed x + 2y + 4z) at `p` in [0, 1]^3.
#[inline(always)]
fn trilerp(f: &[f32; 8], p: Vec3) -> f32 {
    lerp(
        bilerp([f[0], f[1], f[2], f[3]], p.x, p.y),
        bilerp([f[4], f[5], f[6], f[7]], p.x, p.y),
        p.z,
    )
}

/// Gradient of [`trilerp`] (per unit of the voxel).
fn trilerp_grad(f: &[f32; 8], p: Vec3) -> Vec3 {
    let dx = [f[1] - f[0], f[3] - f[2], f[5] - f[4], f[7] - f[6]];
    let dy = [f[2] - f[0], f[3] - f[1], f[6] - f[4], f[7] - f[5]];
    let dz = [f[4] - f[0], f[5] - f[1], f[6] - f[2], f[7] - f[3]];
    Vec3::new(
        bilerp(dx, p.y, p.z),
        bilerp(dy, p.x, p.z),
        bilerp(dz, p.x, p.y),
    )
}

/// Real roots of a t^2 + b t + c (ascending; a linear equation's one root twice), as
/// Mitsuba's `solve_quadratic`.
fn solve_quadratic(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    if a == 0.0 {
        return (b != 0.0).then(|| (-c / b, -c / b));
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || disc.is_nan() {
        return None;
    }
    let temp = -0.5 * (b + disc.sqrt().copysign(b));
    let (x0, x1) = (temp / a, c / temp);
    Some((x0.min(x1), x0.max(x1)))
}

/// The first root in [0, t_end] of the cubic `c` (c[k] the coefficient of t^k), whose
/// values at the ends are `f_beg` and `f_end`, as Mitsuba's `sdf_solve_cubic`.
fn solve_cubic(t_end: f32, f_beg: f32, f_end: f32, c: [f32; 4]) -> Option<f32> {
    let [c0, c1, c2, c3] = c;
    let (d2, d1) = (3.0 * c3, 2.0 * c2);
    let eval = |t: f32| ((c3 * t + c2) * t + c1) * t + c0;
    let (mut t_near, mut t_far, mut f_near, mut f_far) = (0.0f32, t_end, f_beg, f_end);
    if let Some((r0, r1)) = solve_quadratic(d2, d1, c1) {
        for root in [r0, r1] {
            if t_near <= root && root <= t_far {
                let f_root = eval(root);
                if f_near * f_root <= 0.0 {
                    (t_far, f_far) = (root, f_root);
                } else {
                    (t_near, f_near) = (root, f_root);
                }
            }
        }
    }
    // (a NaN product fails too)
    if !matches!((f_near * f_far).partial_cmp(&0.0), Some(Less | Equal)) {
        return None;
    }
    let mut t = t_near + (t_far - t_near) * (-f_near / (f_far - f_near));
    if !(t >= t_near && t <= t_far) {
        t = 0.5 * (t_near + t_far);
    }
    for _ in 0..=SOLVE_MAX_ITER {
        let f_t = eval(t);
        if f_t * f_near <= 0.0 {
            t_far = t;
        } else {
            t_near = t;
        }
        let t_next = t - f_t / ((d2 * t + d1) * t + c1);
        let t_next = if f_t == 0.0 {
            t
        } else if t_next > t_near && t_next < t_far {
            t_next
        } else {
            0.5 * (t_near + t_far)
        };
        // (NaN ends the iteration)
        let done = !matches!(
            (t_next - t).abs().partial_cmp(&SOLVE_EPSILON),
            Some(Greater | Equal)
        );
        t = t_next;
        if done {
            break;
        }
    }
    t.is_finite().then_some(t)
}

impl SdfGrid {
    /// A grid of `res` samples (x fastest); an error names what is wrong: fewer than two
    /// samples along an axis, a count that does not match, a distance that is not finite,
    /// or no voxel where the distance changes sign.
    pub fn new(res: [u32; 3], values: Vec<f32>) -> Result<SdfGrid, String> {
        let [nx, ny, nz] = res;
        if res.iter().any(|&r| r < 2) {
            return Err(format!(
                "a grid of {nx} x {ny} x {nz} samples: needs at least 2 along each axis"
            ));
        }
        let n = res.iter().map(|&r| r as u64).product::<u64>();
        if n != values.len() as u64 || n > u32::MAX as u64 {
            return Err(format!(
                "{} distances for a grid of {nx} x {ny} x {nz} samples",
                values.len()
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "distance {i} is {}: distances must be finite",
                values[i]
            ));
        }
        let mut g = SdfGrid {
            res,
            values,
            voxels: Vec::new(),
            nodes: Vec::new(),
            order: Vec::new(),
        };
        let size = g.voxel_size();
        let mut boxes = Vec::new();
        for z in 0..nz - 1 {
            for y in 0..ny - 1 {
                for x in 0..nx - 1 {
                    let base = (z * ny + y) * nx + x;
                    let f = g.corners(base);
                    if f.iter().any(|&v| v >= 0.0) && f.iter().any(|&v| v <= 0.0) {
                        let lo = Vec3A::new(x as f32, y as f32, z as f32) * size;
                        let pad = size * 1e-3;
                        g.voxels.push(base);
                        boxes.push((lo - pad, lo + size + pad));
                    }
                }
            }
        }
        if g.voxels.is_empty() {
            return Err(format!(
                "a grid of {nx} x {ny} x {nz} distances that never change sign: no surface"
            ));
        }
        g.order = (0..g.voxels.len() as u32).collect();
        let n = g.order.len();
        build_top(&boxes, &mut g.order, 0, n, &mut g.nodes);
        Ok(g)
    }

    /// Samples along each axis.
    pub fn resolution(&self) -> [u32; 3] {
        self.res
    }

    /// Voxels that hold surface.
    pub fn occupied(&self) -> usize {
        self.voxels.len()
    }

    fn voxel_size(&self) -> Vec3A {
        Vec3A::ONE / self.scale()
    }

    /// Voxels along each axis.
    fn scale(&self) -> Vec3A {
        Vec3A::new(
            (self.res[0] - 1) as f32,
            (self.res[1] - 1) as f32,
            (self.res[2] - 1) as f32,
        )
    }

    /// The eight samples of the voxel whose lower corner is sample `base` (x + 2y + 4z).
    #[inline]
    fn corners(&self, base: u32) -> [f32; 8] {
        let [nx, ny, _] = self.res;
        std::array::from_fn(|i| {
            let i = i as u32;
            self.values[(base + ((i >> 2) * ny + ((i >> 1) & 1)) * nx + (i & 1)) as usize]
        })
    }

    /// The voxel position (integer coordinates) of sample `base`.
    fn position(&self, base: u32) -> Vec3 {
        let [nx, ny, _] = self.res;
        let yz = base / nx;
        Vec3::new((base % nx) as f32, (yz % ny) as f32, (yz / ny) as f32)
    }

    /// The ray parameter in (0, t_max) where the ray `o + t d` (grid space) meets the
    /// surface in occupied voxel `slot`, as Mitsuba's voxel intersection.
    fn intersect_voxel(&self, slot: u32, o: Vec3, d: Vec3, t_max: f32) -> Option<f32> {
        let base = self.voxels[slot as usize];
        let pos = self.position(base);
        let s = self.corners(base);
        let size = Vec3::from(self.voxel_size());
        let (lo, hi) = (pos * size, (pos + 1.0) * size);
        let rcp = d.recip();
        let up = rcp.cmpge(Vec3::ZERO);
        let near = Vec3::select(up, lo, hi);
        let far = Vec3::select(up, hi, lo);
        let t0 = (near - o) * rcp;
        let t1 = (far - o) * rcp;
        let t0 = Vec3::select(t0.is_nan_mask(), Vec3::NEG_INFINITY, t0);
        let t1 = Vec3::select(t1.is_nan_mask(), Vec3::INFINITY, t1);
        let t_beg = t0.max_element().max(0.0);
        let t_end = t1.min_element();
        if !(t_beg < t_end && t_beg <= t_max) {
            return None;
        }
        // in the voxel's own units, the direction scaled (t unchanged)
        let scale = Vec3::from(self.scale());
        let (o, d) = (o * scale - pos, d * scale);
        let (p_beg, p_end) = (o + d * t_beg, o + d * t_end);
        // the crossed faces snapped to 0 or 1, where neighbours agree bit for bit
        let on_beg = t0.cmpeq(Vec3::splat(t_beg));
        let on_end = t1.cmpeq(Vec3::splat(t_end));
        let face_beg = Vec3::select(up, Vec3::ZERO, Vec3::ONE);
        let q_beg = Vec3::select(on_beg, face_beg, p_beg).clamp(Vec3::ZERO, Vec3::ONE);
        let q_end = Vec3::select(on_end, Vec3::ONE - face_beg, p_end).clamp(Vec3::ZERO, Vec3::ONE);
        let (f_beg, f_end) = (trilerp(&s, q_beg), trilerp(&s, q_end));
        // the trilinear interpolant along the ray from p_beg: c0 + c1 t + c2 t^2 + c3 t^3
        let (ox, oy, oz) = (p_beg.x, p_beg.y, p_beg.z);
        let (dx, dy, dz) = (d.x, d.y, d.z);
        let a = s[5] - s[4];
        let k0 = s[0];
        let k1 = s[1] - s[0];
        let k2 = s[2] - s[0];
        let k3 = s[3] - s[2] - k1;
        let k4 = s[4] - k0;
        let k5 = a - k1;
        let k6 = (s[6] - s[4]) - k2;
        let k7 = (s[7] - s[6] - a) - k3;
        let m0 = ox * oy;
        let m1 = dx * dy;
        let m2 = ox * dy + oy * dx;
        let m3 = k5 * oz + k1;
        let m4 = k6 * oz + k2;
        let m5 = k7 * oz + k3;
        let c0 = (k4 * oz + k0) + (ox * m3 + (oy * m4 + m0 * m5));
        let c1 = (dx * m3 + dy * m4) + m2 * m5 + dz * (k4 + (k5 * ox + (k6 * oy + k7 * m0)));
        let c2 = m1 * m5 + dz * (k5 * dx + (k6 * dy + k7 * m2));
        let c3 = k7 * m1 * dz;
        let t = solve_cubic(t_end - t_beg, f_beg, f_end, [c0, c1, c2, c3])? + t_beg;
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// The closest hit of the ray `o + t d` (grid space) with `t` in (0, t_max): its `t`
    /// and occupied voxel; with `any`, the first found.
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32, any: bool) -> Option<(f32, u32)> {
        let oa = Vec3A::from(o);
        let inv = Vec3A::ONE / Vec3A::from(d);
        let inv = Vec3A::select(inv.is_finite_mask(), inv, inv.signum() * f32::MAX);
        let entry = |n: &TopNode, t_max: f32| {
            let (a, b) = ((n.min - oa) * inv, (n.max - oa) * inv);
            let t0 = a.min(b).max_element().max(0.0);
            let t1 = a.max(b).min_element().min(t_max);
            (t1 * (1.0 + 4.0 * f32::EPSILON) >= t0).then_some(t0)
        };
        let mut best: Option<(f32, u32)> = None;
        let mut t_best = t_max;
        let mut stack = [(0u32, 0.0f32); STACK];
        let mut sp = 0;
        if entry(&self.nodes[0], t_best).is_some() {
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            let (at, t_in) = stack[sp];
            if t_in > t_best {
                continue;
            }
            let n = &self.nodes[at as usize];
            if n.count > 0 {
                for &v in &self.order[n.index as usize..(n.index + n.count) as usize] {
                    if let Some(t) = self.intersect_voxel(v, o, d, t_best) {
                        t_best = t;
                        best = Some((t, v));
                        if any {
                            return best;
                        }
                    }
                }
                continue;
            }
            let (l, r) = (at + 1, n.index);
            let tl = entry(&self.nodes[l as usize], t_best);
            let tr = entry(&self.nodes[r as usize], t_best);
            // the nearer child on top
            let mut push = |c: u32, t: Option<f32>| {
                if let Some(t) = t {
                    if sp < STACK {
                        stack[sp] = (c, t);
                        sp += 1;
                    }
                }
            };
            if tl.unwrap_or(f32::INFINITY) <= tr.unwrap_or(f32::INFINITY) {
                push(r, tr);
                push(l, tl);
            } else {
                push(l, tl);
                push(r, tr);
            }
        }
        best
    }

    /// The interpolant's value and gradient (per unit of grid space) at `p` in occupied
    /// voxel `slot` (`p` clamped to the voxel), as Mitsuba's `sdf_eval`.
    pub fn eval(&self, slot: u32, p: Vec3) -> (f32, Vec3) {
        let base = self.voxels[slot as usize];
        let scale = Vec3::from(self.scale());
        let w = (p * scale - self.position(base)).clamp(Vec3::ZERO, Vec3::ONE);
        let f = self.corners(base);
        (trilerp(&f, w), trilerp_grad(&f, w) * scale)
    }

    /// Mitsuba's `smooth` shading normal at `p` (grid space, not normalised): the
    /// finite-difference gradients of the eight voxels around the sample nearest to `p`,
    /// blended trilinearly; voxels outside the grid do not contribute.
    pub fn smooth_normal(&self, p: Vec3) -> Vec3 {
        let n = self.res.map(|r| r as i32);
        let scale = Vec3::from(self.scale());
        let sp = p * scale;
        let v: [i32; 3] = std::array::from_fn(|a| sp[a].round_ties_even() as i32 - 1);
        let mut uvw: [f32; 3] = std::array::from_fn(|a| sp[a] - v[a] as f32 - 0.5);
        let cell: [i32; 3] = std::array::from_fn(|a| (sp[a].floor() as i32).clamp(0, n[a] - 2));
        let w: [f32; 3] = std::array::from_fn(|a| sp[a] - cell[a] as f32);
        let sample = |q: [i32; 3]| {
            let q: [i32; 3] = std::array::from_fn(|a| q[a].clamp(0, n[a] - 1));
            self.values[((q[2] * n[1] + q[1]) * n[0] + q[0]) as usize]
        };
        // the interpolant on the sample plane `q` of axis `a`, at p along the other two
        let plane = |a: usize, q: i32| {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let f = std::array::from_fn(|i| {
                let mut idx = [0; 3];
                idx[a] = q;
                idx[b] = cell[b] + (i as i32 & 1);
                idx[c] = cell[c] + (i as i32 >> 1);
                sample(idx)
            });
            bilerp(f, w[b], w[c])
        };
        let (mut d0, mut d1) = ([0.0f32; 3], [0.0f32; 3]);
        for a in 0..3 {
            let upper = cell[a] != v[a];
            let g0 = plane(a, cell[a]);
            let g1 = plane(a, cell[a] + 1);
            let gq = plane(a, cell[a] + if upper { -1 } else { 2 });
            let dc = g1 - g0;
            let dq = if upper { g0 - gq } else { gq - g1 };
            d0[a] = if upper { dq } else { dc } * scale[a];
            d1[a] = if upper { dc } else { dq } * scale[a];
        }
        let inside: [bool; 3] = std::array::from_fn(|a| v[a] >= 0);
        for a in 0..3 {
            if !inside[a] {
                uvw[a] = 1.0;
            }
        }
        let corner = |i: usize| {
            let hi = [i & 1 != 0, i & 2 != 0, i & 4 != 0];
            if (0..3).all(|a| hi[a] || inside[a]) {
                Vec3::from_array(std::array::from_fn(|a| if hi[a] { d1[a] } else { d0[a] }))
                    .normalize_or_zero()
            } else {
                Vec3::ZERO
            }
        };
        let lerp3 = |a: Vec3, b: Vec3, t: f32| a - a * t + b * t;
        let [u, v, w] = uvw;
        lerp3(
            lerp3(
                lerp3(corner(0), corner(1), u),
                lerp3(corner(2), corner(3), u),
                v,
            ),
            lerp3(
                lerp3(corner(4), corner(5), u),
                lerp3(corner(6), corner(7), u),
                v,
            ),
            w,
        )
    }

    /// Heap and inline memory, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + 4 * (self.values.capacity() + self.voxels.capacity() + self.order.capacity())
            + self.nodes.capacity() * std::mem::size_of::<TopNode>()
    }
}

/// One placed grid.
#[derive(Clone, Debug)]
struct Placed {
    grid: Arc<SdfGrid>,
    to_world: Affine3A,
    to_local: Affine3A,
    /// Inverse transpose of `to_world`'s linear part.
    normal: Mat3,
    smooth: bool,
    /// Number of this grid's first voxel after [`SDF_FIRST_PRIM`].
    first: u32,
    min: Vec3A,
    max: Vec3A,
}

/// The scene's placed grids (see the module docs).
#[derive(Clone, Debug)]
pub struct SdfShapes {
    placed: Vec<Placed>,
}

impl SdfShapes {
    /// The grids `(grid, to_world, smooth normals)`; an error names a grid whose
    /// `to_world` is not invertible, or too many voxels to number.
    pub fn build(grids: &[(Arc<SdfGrid>, Mat4, bool)]) -> Result<SdfShapes, String> {
        let mut placed = Vec::with_capacity(grids.len());
        let mut first: u64 = 0;
        for (i, (grid, m, smooth)) in grids.iter().enumerate() {
            let to_world = Affine3A::from_mat4(*m);
            let det = to_world.matrix3.determinant();
            if !(det.is_finite() && det.abs() > 1e-30 && m.is_finite()) {
                return Err(format!(
                    "sdfgrid {i}: its to_world is not invertible (determinant {det})"
                ));
            }
            let unit = Bounds3 {
                min: Vec3::ZERO,
                max: Vec3::ONE,
            };
            let b = super::transformed_bounds(&unit, &to_world);
            placed.push(Placed {
                grid: grid.clone(),
                to_world,
                to_local: to_world.inverse(),
                normal: Mat3::from(to_world.matrix3).inverse().transpose(),
                smooth: *smooth,
                first: first as u32,
                min: b.min.into(),
                max: b.max.into(),
            });
            first += grid.occupied() as u64;
        }
        if first >= (u32::MAX - SDF_FIRST_PRIM) as u64 {
            return Err(format!(
                "{first} voxels in signed-distance grids: more than kalos numbers"
            ));
        }
        Ok(SdfShapes { placed })
    }

    /// Whether the ray enters the world box of grid `p` before `t_max`.
    fn enters(p: &Placed, ray: &Ray, t_max: f32) -> bool {
        let inv = Vec3A::ONE / Vec3A::from(ray.d);
        let o = Vec3A::from(ray.o);
        let (a, b) = ((p.min - o) * inv, (p.max - o) * inv);
        let t0 = a.min(b).max_element().max(0.0);
        let t1 = a.max(b).min_element().min(t_max);
        // (NaN from a zero direction in a face plane counts as entering)
        (t1 * (1.0 + 4.0 * f32::EPSILON)).partial_cmp(&t0) != Some(Less)
    }

    fn query(&self, ray: &Ray, t_max: f32, any: bool) -> Option<(f32, usize, u32)> {
        let mut best = None;
        let mut t_best = t_max;
        for (i, p) in self.placed.iter().enumerate() {
            if !Self::enters(p, ray, t_best) {
                continue;
            }
            let o = p.to_local.transform_point3(ray.o);
            let d = p.to_local.transform_vector3(ray.d);
            if let Some((t, v)) = p.grid.intersect(o, d, t_best, any) {
                t_best = t;
                best = Some((t, i, v));
                if any {
                    break;
                }
            }
        }
        best
    }

    /// The closest hit with `t` in (0, t_max), in world space: `n` the interpolant's
    /// gradient (the geometric normal, not normalised), `b1 = b2 = 0`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let (t, i, v) = self.query(ray, t_max, false)?;
        let p = &self.placed[i];
        let local = p.to_local.transform_point3(ray.o) + p.to_local.transform_vector3(ray.d) * t;
        let grad = p.grid.eval(v, local).1;
        Some(Hit {
            t,
            prim: SDF_FIRST_PRIM + p.first + v,
            b1: 0.0,
            b2: 0.0,
            p: p.to_world.transform_point3(local),
            n: p.normal * grad,
        })
    }

    /// Whether a grid is hit with `t` in (0, t_max).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.query(ray, t_max, true).is_some()
    }

    /// The placed grid (its index in the order given to [`SdfShapes::build`]) of hit
    /// number `prim`.
    pub fn locate(&self, prim: u32) -> Option<usize> {
        let k = prim.checked_sub(SDF_FIRST_PRIM)?;
        let i = self
            .placed
            .partition_point(|p| p.first <= k)
            .checked_sub(1)?;
        (k - self.placed[i].first < self.placed[i].grid.occupied() as u32).then_some(i)
    }

    /// The unit shading normal at hit `h` (world space): the smooth one or the
    /// geometric one, as the grid was placed.
    pub fn shading_normal(&self, h: &Hit) -> Vec3 {
        let ng = h.n.normalize_or_zero();
        let Some(i) = self.locate(h.prim) else {
            return ng;
        };
        let p = &self.placed[i];
        if !p.smooth {
            return ng;
        }
        let local = p.to_local.transform_point3(h.p);
        let ns = (p.normal * p.grid.smooth_normal(local)).normalize_or_zero();
        if ns == Vec3::ZERO {
            ng
        } else {
            ns
        }
    }

    /// World bounds of all grids.
    pub fn bounds(&self) -> Bounds3 {
        let mut b = Bounds3::EMPTY;
        for p in &self.placed {
            b.grow(p.min.into());
            b.grow(p.max.into());
        }
        b
    }

    /// Heap and inline memory, in bytes (a grid placed twice counted twice).
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self
                .placed
                .iter()
                .map(|p| std::mem::size_of::<Placed>() + p.grid.memory_bytes())
                .sum::<usize>()
    }
}

#[cfg(test)]
#[path = "sdf_tests.rs"]
mod tests;
