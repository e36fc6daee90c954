//! Ray–triangle acceleration structure.
//!
//! Build: binned SAH (16 bins, all three axes, costs counted in 4-triangle
//! blocks) into a flattened BVH2 of 32-byte nodes, subtrees built in parallel
//! with rayon; the BVH2 is then collapsed into an 8-wide BVH (`Node8`, 256
//! bytes: SoA child boxes + child references) whose leaves are one or two
//! consecutive packets of up to four triangles in SoA Möller–Trumbore form
//! (`Tri4`, v0/e1/e2). The collapse is SAH-driven (the dynamic programme of
//! Ylitie, Karras & Laine 2017): which BVH2 nodes become 8-wide nodes, which
//! become leaves (a BVH2 subtree of up to eight triangles may become one
//! leaf) and how a node's eight child slots are shared out are chosen for the
//! least SAH cost, which fills the nodes (about 7.3 children on average on a
//! 1M-triangle mesh, against 4.1 for opening the largest child greedily).
//!
//! Traversal: one ray at a time, the 8 boxes of a node per slab test (one
//! AVX2 test, or two 4-wide glam `Vec4` ones: SSE2 on x86-64, NEON on
//! aarch64) and 4 triangles per SIMD triangle test (a leaf's two packets in one
//! AVX2 test: room 1.015x, Cornell box 1.012x, 2026-12-05 (b4ac6ed)), no
//! heap allocation, a fixed-size uninitialised stack sized from the tree at
//! build time, and children visited nearest-first for closest-hit queries.
//! The slab test reads each axis' near and far planes by the ray's octant
//! (Williams et al. 2005), so it needs no per-axis min/max.
//!
//! On large trees traversal waits on memory: the children a node query will
//! visit later are prefetched when they are pushed, and on Linux the node and
//! triangle arrays are copied onto transparent huge pages (`madvise`): fewer pages
//! to translate (random rays on a 1M-triangle height field 1.00-1.12x as fast, 2026-12-04 (4a6faaf);
//! this VM's `perf` has no TLB counters to show the misses themselves).
//!
//! Run-time dispatch ([`Isa`]): the same traversal code is compiled twice, for
//! baseline x86-64 (SSE2) and with AVX2 + FMA enabled (`#[target_feature]`),
//! and each BVH picks the best the CPU has when it is built, so one binary (the
//! Python wheel, a render shard) runs at the speed of the machine it lands on.
//! Rust never contracts `a * b + c` into an FMA on its own, so both versions do
//! the same IEEE operations and return bit-identical hits (tested).
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
use glam::{Vec3A, Vec4};
use rayon::prelude::*;

/// Instruction set a BVH's queries run with (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Baseline of the target (SSE2 on x86-64, NEON on aarch64).
    Base,
    /// AVX2 + FMA (x86-64 only; chosen when the CPU has both).
    Avx2,
}

impl Isa {
    /// Short name, as printed by `kalos info` and in render statistics.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Base if cfg!(target_arch = "x86_64") => "sse2",
            Isa::Base => "base",
            Isa::Avx2 => "avx2",
        }
    }

    /// Whether this CPU can run `self`.
    pub fn is_available(self) -> bool {
        match self {
            Isa::Base => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Avx2 => false,
        }
    }

    /// Every instruction set this CPU can run, baseline first.
    pub fn available() -> Vec<Isa> {
        [Isa::Base, Isa::Avx2]
            .into_iter()
            .filter(|i| i.is_available())
            .collect()
    }

    /// The one new BVHs use: the best this CPU has, unless the environment
    /// variable `KALOS_SIMD` names another available one (`sse2`/`base`, `avx2`;
    /// for benchmarks). Decided once per process.
    pub fn chosen() -> Isa {
        static CHOSEN: std::sync::OnceLock<Isa> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let best = *Isa::available()
                .last()
                .expect("baseline is always available");
            match std::env::var("KALOS_SIMD") {
                Err(_) => best,
                Ok(v) => match Isa::from_name(&v) {
                    Some(i) if i.is_available() => i,
                    _ => {
                        eprintln!(
                            "kalos: warning: KALOS_SIMD={v:?} is not one of this CPU's \
                             instruction sets ({}); using {}",
                            Isa::available()
                                .iter()
                                .map(|i| i.name())
                                .collect::<Vec<_>>()
                                .join(", "),
                            best.name()
                        );
                        best
                    }
                },
            }
        })
    }

    fn from_name(s: &str) -> Option<Isa> {
        match s.trim().to_ascii_lowercase().as_str() {
            "sse2" | "base" | "neon" => Some(Isa::Base),
            "avx2" => Some(Isa::Avx2),
            _ => None,
        }
    }
}

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
    /// The hit point v0 + b1 e1 + b2 e2 (e1 = v1 - v0, e2 = v2 - v0), and the
    /// geometric normal e1 × e2 (not normalised), from the BVH's own copy of the
    /// triangle: the hit record then reads nothing more of the triangle, whose
    /// packet the traversal has just loaded (on large meshes the scene's own
    /// vertex arrays are another cache and TLB miss per hit).
    pub p: Vec3,
    pub n: Vec3,
}

/// Flattened BVH2 node (32 bytes), the builder's output. Interior nodes
/// (`count == 0`) have their children at `a` and `a + 1`; leaves hold
/// primitives `a .. a + count` of the builder's leaf order.
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

    /// The hit at `t` with barycentrics `b1, b2` on this triangle, input index `prim`.
    #[inline(always)]
    fn hit(&self, prim: u32, t: f32, b1: f32, b2: f32) -> Hit {
        Hit {
            t,
            prim,
            b1,
            b2,
            p: self.v0 + self.e1 * b1 + self.e2 * b2,
            n: self.e1.cross(self.e2),
        }
    }

    /// Zero-area or non-finite triangles are never hit.
    #[inline]
    fn is_degenerate(&self) -> bool {
        let finite = self.v0.is_finite() && self.e1.is_finite() && self.e2.is_finite();
        !(finite && self.e1.cross(self.e2).length_squared() > 0.0)
    }

    /// Möller–Trumbore, double-sided, with the division deferred to the hit (the
    /// scalar reference for [`Tri4`], used by the tests' brute force). Returns
    /// `(t, b1, b2)` for a hit with `0 < t < t_max`.
    #[cfg(test)]
    fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
        let p = d.cross(self.e2);
        let det = self.e1.dot(p);
        let (sign, abs_det) = (det.to_bits() & SIGN, det.abs());
        let flip = |x: f32| f32::from_bits(x.to_bits() ^ sign);
        let s = o - self.v0;
        let u = flip(s.dot(p));
        let q = s.cross(self.e1);
        let v = flip(d.dot(q));
        let t = flip(self.e2.dot(q));
        if !(det != 0.0
            && u >= 0.0
            && v >= 0.0
            && u + v <= abs_det
            && t > 0.0
            && t < abs_det * t_max)
        {
            return None;
        }
        let inv = 1.0 / abs_det;
        let t = t * inv;
        if t > 0.0 && t < t_max {
            Some((t, u * inv, v * inv))
        } else {
            None
        }
    }
}

/// Sign bit of an f32.
const SIGN: u32 = 1 << 31;

/// `x` with each lane's sign flipped where `by`'s lane is negative (sign bit
/// set): x * sign(by) without rounding.
#[inline(always)]
fn xor_sign(x: Vec4, by: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE is part of x86-64.
        unsafe {
            let m = _mm_and_ps(by.into(), _mm_set1_ps(f32::from_bits(SIGN)));
            _mm_xor_ps(x.into(), m).into()
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let (a, b) = (x.to_array(), by.to_array());
        Vec4::from_array(std::array::from_fn(|i| {
            f32::from_bits(a[i].to_bits() ^ (b[i].to_bits() & SIGN))
        }))
    }
}

/// Up to four triangles in SoA form (lanes), for a 4-wide Möller–Trumbore
/// test. Unused lanes are masked out by the leaf's count.
/// 160 bytes aligned to 32: always within three cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Tri4 {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    /// Input index of each lane's triangle (`u32::MAX` for unused lanes): beside
    /// the triangles, so that a hit costs no further cache miss.
    ids: [u32; 4],
}

impl Tri4 {
    fn new(tris: &[Tri], ids: &[u32]) -> Tri4 {
        debug_assert!(tris.len() <= 4 && ids.len() == tris.len());
        let mut a = [[[0.0f32; 4]; 3]; 3];
        for (lane, t) in tris.iter().enumerate() {
            for (k, v) in [t.v0, t.e1, t.e2].iter().enumerate() {
                for axis in 0..3 {
                    a[k][axis][lane] = v[axis];
                }
            }
        }
        let v = |k: usize| a[k].map(Vec4::from_array);
        let mut lanes = [u32::MAX; 4];
        lanes[..ids.len()].copy_from_slice(ids);
        Tri4 {
            v0: v(0),
            e1: v(1),
            e2: v(2),
            ids: lanes,
        }
    }

    /// The triangle in `lane`.
    #[inline(always)]
    fn lane(&self, lane: usize) -> Tri {
        // Through the lanes' array: glam's `Vec4` index is a `match`, which compiles to a
        // jump table whose indirect branch the CPU mispredicts for a random lane.
        let get = |v: &[Vec4; 3]| {
            let a = v.map(|x| *x.as_ref());
            Vec3::new(a[0][lane], a[1][lane], a[2][lane])
        };
        Tri {
            v0: get(&self.v0),
            e1: get(&self.e1),
            e2: get(&self.e2),
        }
    }

    /// Mask (bit = lane) of the lanes in `valid` hit with `0 < t < t_max`,
    /// and their `t, b1, b2` (computed only when some lane is hit).
    /// Operation for operation the same as [`Tri::intersect`], so results
    /// agree bit for bit.
    ///
    /// The division is deferred (as in Embree): u, v and t are compared
    /// unnormalised, their signs flipped by the determinant's, against |det|
    /// and |det| t_max, which takes the division off the chain of dependent
    /// operations a traversal step waits on; only a packet with a hit divides,
    /// and then t is checked again against (0, t_max) so that rounding cannot
    /// let a hit out of the interval.
    #[inline(always)]
    fn intersect(&self, r: &RayData, t_max: f32, valid: u32) -> (u32, Vec4, Vec4, Vec4) {
        let [e1x, e1y, e1z] = self.e1;
        let [e2x, e2y, e2z] = self.e2;
        let (dx, dy, dz) = (r.dx, r.dy, r.dz);
        // p = d × e2
        let px = dy * e2z - e2y * dz;
        let py = dz * e2x - e2z * dx;
        let pz = dx * e2y - e2x * dy;
        let det = e1x * px + e1y * py + e1z * pz;
        let flip = |x: Vec4| xor_sign(x, det);
        let abs_det = det.abs();
        let sx = r.ox - self.v0[0];
        let sy = r.oy - self.v0[1];
        let sz = r.oz - self.v0[2];
        let u = flip(sx * px + sy * py + sz * pz);
        // q = s × e1
        let qx = sy * e1z - e1y * sz;
        let qy = sz * e1x - e1z * sx;
        let qz = sx * e1y - e1x * sy;
        let v = flip(dx * qx + dy * qy + dz * qz);
        let t = flip(e2x * qx + e2y * qy + e2z * qz);
        let ok = det.cmpne(Vec4::ZERO)
            & u.cmpge(Vec4::ZERO)
            & v.cmpge(Vec4::ZERO)
            & (u + v).cmple(abs_det)
            & t.cmpgt(Vec4::ZERO)
            & t.cmplt(abs_det * Vec4::splat(t_max));
        let m = ok.bitmask() & valid;
        if m == 0 {
            return (0, Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
        }
        let inv = Vec4::ONE / abs_det;
        let t = t * inv;
        let ok = t.cmpgt(Vec4::ZERO) & t.cmplt(Vec4::splat(t_max));
        (ok.bitmask() & m, t, u * inv, v * inv)
    }

    /// [`Self::intersect`] of two packets (`pair[0]` in lanes 0..4, `pair[1]` in 4..8)
    /// in one AVX2 test of eight lanes, operation for operation the same; the first
    /// `count` lanes are valid.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    unsafe fn intersect_pair_avx2(
        pair: &[Tri4],
        r: &RayData,
        t_max: f32,
        count: u32,
    ) -> (u32, [f32; 8], [f32; 8], [f32; 8]) {
        use std::arch::x86_64::*;
        let (a, b) = (&pair[0], &pair[1]);
        let both = |x: &Vec4, y: &Vec4| _mm256_set_m128((*y).into(), (*x).into());
        let row = |x: &[Vec4; 3], y: &[Vec4; 3]| {
            [both(&x[0], &y[0]), both(&x[1], &y[1]), both(&x[2], &y[2])]
        };
        let [v0x, v0y, v0z] = row(&a.v0, &b.v0);
        let [e1x, e1y, e1z] = row(&a.e1, &b.e1);
        let [e2x, e2y, e2z] = row(&a.e2, &b.e2);
        let w = |v: &Vec4| both(v, v);
        let (ox, oy, oz) = (w(&r.ox), w(&r.oy), w(&r.oz));
        let (dx, dy, dz) = (w(&r.dx), w(&r.dy), w(&r.dz));
        let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
        // p = d × e2
        let px = sub(mul(dy, e2z), mul(e2y, dz));
        let py = sub(mul(dz, e2x), mul(e2z, dx));
        let pz = sub(mul(dx, e2y), mul(e2x, dy));
        let det = add(add(mul(e1x, px), mul(e1y, py)), mul(e1z, pz));
        let sign = _mm256_and_ps(det, _mm256_set1_ps(f32::from_bits(SIGN)));
        let flip = |x: __m256| _mm256_xor_ps(x, sign);
        let abs_det = _mm256_andnot_ps(_mm256_set1_ps(f32::from_bits(SIGN)), det);
        let sx = sub(ox, v0x);
        let sy = sub(oy, v0y);
        let sz = sub(oz, v0z);
        let u = flip(add(add(mul(sx, px), mul(sy, py)), mul(sz, pz)));
        // q = s × e1
        let qx = sub(mul(sy, e1z), mul(e1y, sz));
        let qy = sub(mul(sz, e1x), mul(e1z, sx));
        let qz = sub(mul(sx, e1y), mul(e1x, sy));
        let v = flip(add(add(mul(dx, qx), mul(dy, qy)), mul(dz, qz)));
        let t = flip(add(add(mul(e2x, qx), mul(e2y, qy)), mul(e2z, qz)));
        let zero = _mm256_setzero_ps();
        let tm = _mm256_set1_ps(t_max);
        let ok = _mm256_and_ps(
            _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_NEQ_UQ>(det, zero),
                    _mm256_cmp_ps::<_CMP_GE_OS>(u, zero),
                ),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GE_OS>(v, zero),
                    _mm256_cmp_ps::<_CMP_LE_OS>(add(u, v), abs_det),
                ),
            ),
            _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OS>(t, zero),
                _mm256_cmp_ps::<_CMP_LT_OS>(t, mul(abs_det, tm)),
            ),
        );
        let m = _mm256_movemask_ps(ok) as u32 & ((1u32 << count) - 1);
        let mut out = (0, [0.0f32; 8], [0.0f32; 8], [0.0f32; 8]);
        if m == 0 {
            return out;
        }
        let inv = _mm256_div_ps(_mm256_set1_ps(1.0), abs_det);
        let t = mul(t, inv);
        let ok = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OS>(t, zero),
            _mm256_cmp_ps::<_CMP_LT_OS>(t, tm),
        );
        out.0 = _mm256_movemask_ps(ok) as u32 & m;
        // SAFETY: each array holds eight floats.
        unsafe {
            _mm256_storeu_ps(out.1.as_mut_ptr(), t);
            _mm256_storeu_ps(out.2.as_mut_ptr(), mul(u, inv));
            _mm256_storeu_ps(out.3.as_mut_ptr(), mul(v, inv));
        }
        out
    }
}

/// Children per BVH node.
const WIDTH: usize = 8;

/// Eight-wide BVH node (256 bytes, four cache lines): the boxes of up to
/// eight children in SoA form, lanes = children, and their references. One
/// AVX2 slab test covers the eight boxes (two SSE ones on the baseline).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node8 {
    /// min.x, min.y, min.z, max.x, max.y, max.z of the eight children.
    b: [[f32; WIDTH]; 6],
    /// Child references (see [`LEAF`]); unused slots have empty boxes.
    child: [u32; WIDTH],
}

/// Child reference flag: a leaf, encoded as `LEAF | packet << 3 | (count - 1)`
/// (its `count <= 8` triangles fill `Tri4` packets `packet ..` in order, four
/// to a packet but the last). Otherwise a `Node8` index.
const LEAF: u32 = 1 << 31;
/// Most triangles a leaf holds (two packets).
const MAX_LEAF_TRIS: u32 = 8;
const _: () = assert!(build::MAX_LEAF as u32 <= MAX_LEAF_TRIS);
const _: () = assert!(std::mem::size_of::<Tri4>() == 160);

#[inline(always)]
fn leaf_ref(first: u32, count: u32) -> u32 {
    debug_assert!((1..=MAX_LEAF_TRIS).contains(&count) && first < 1 << 28);
    LEAF | first << 3 | (count - 1)
}

/// First packet and triangle count of a leaf reference.
#[inline(always)]
fn leaf_packets(r: u32) -> (usize, u32) {
    (((r & !LEAF) >> 3) as usize, (r & 7) + 1)
}

/// Lane mask of a packet holding the next `left` (>= 1) triangles of a leaf.
#[inline(always)]
fn lane_mask(left: u32) -> u32 {
    (1u32 << left.min(4)) - 1
}

/// Bounding volume hierarchy over a triangle soup.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node8>,
    /// Reference to the root (a `Node8` index or a leaf); unused if empty.
    root: u32,
    bounds: Bounds3,
    /// Traversal stack entries a query may need (computed at build time).
    stack_needed: usize,
    leaf_count: usize,
    /// Triangle packets (one or two per leaf), in traversal order.
    tris: Vec<Tri4>,
    /// Instruction set the queries run with.
    isa: Isa,
    /// [`Bvh::interleaves`] forced (tests, benchmarks); `None`: by size.
    interleave: Option<bool>,
}

/// Slack on the far slab distance that makes the box test conservative
/// despite rounding (1 + 2γ₃, Ize 2013).
const ROBUST: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Per-ray precomputation for the slab and triangle tests.
#[derive(Clone, Copy)]
struct RayData {
    /// Origin, direction and (fixed) reciprocal direction, each component splatted over
    /// four lanes (the 8-wide AVX2 slab test doubles them: reading them back as
    /// written, whole, keeps the loads out of store-forwarding stalls).
    ox: Vec4,
    oy: Vec4,
    oz: Vec4,
    dx: Vec4,
    dy: Vec4,
    dz: Vec4,
    ix: Vec4,
    iy: Vec4,
    iz: Vec4,
    /// Octant: index into `Node8::b` of the near plane per axis (0..3 for
    /// the min planes when the direction is positive, 3..6 for the max
    /// planes when it is negative), and of the far plane.
    near: [usize; 3],
    far: [usize; 3],
}

impl RayData {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        // Zero components give ±inf; replace them with ±MAX so that
        // `0 * inv` is 0 (never NaN).
        let inv = 1.0 / ray.d;
        let fix = |x: f32| {
            if x.is_finite() {
                x
            } else {
                f32::MAX.copysign(x)
            }
        };
        let inv = Vec3::new(fix(inv.x), fix(inv.y), fix(inv.z));
        RayData {
            ox: Vec4::splat(ray.o.x),
            oy: Vec4::splat(ray.o.y),
            oz: Vec4::splat(ray.o.z),
            dx: Vec4::splat(ray.d.x),
            dy: Vec4::splat(ray.d.y),
            dz: Vec4::splat(ray.d.z),
            ix: Vec4::splat(inv.x),
            iy: Vec4::splat(inv.y),
            iz: Vec4::splat(inv.z),
            near: [
                if inv.x < 0.0 { 3 } else { 0 },
                if inv.y < 0.0 { 4 } else { 1 },
                if inv.z < 0.0 { 5 } else { 2 },
            ],
            far: [
                if inv.x < 0.0 { 0 } else { 3 },
                if inv.y < 0.0 { 1 } else { 4 },
                if inv.z < 0.0 { 2 } else { 5 },
            ],
        }
    }

    /// Entry distances of the eight child boxes and the mask (bit i = lane i)
    /// of those the ray overlaps within `(0, t_max)`: one AVX2 test when
    /// `AVX`, else two 4-wide SSE ones. Both do the same IEEE operations in the
    /// same order, so they agree bit for bit.
    #[inline(always)]
    fn slab8<const AVX: bool>(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: `AVX` is only instantiated by the `*_avx2` queries, which
            // run only where the CPU has AVX2 and FMA.
            return unsafe { self.slab8_avx2(n, t_max) };
        }
        let (t0, m0) = self.slab4(n, 0, t_max);
        let (t1, m1) = self.slab4(n, 4, t_max);
        let mut tn = [0.0; WIDTH];
        tn[..4].copy_from_slice(&t0.to_array());
        tn[4..].copy_from_slice(&t1.to_array());
        (tn, m0 | m1 << 4)
    }

    /// The slab test of lanes `off .. off + 4` of `n`.
    ///
    /// Per axis, t = (plane - o) / d for the near and far planes picked by the
    /// ray's octant. This is bit for bit the min and max of the two planes'
    /// distances (the product with a positive `inv` is monotone in the plane,
    /// with a negative one antitone; equal values may differ only in the sign
    /// of a zero, which no comparison below sees), so hits do not change.
    #[inline(always)]
    fn slab4(&self, n: &Node8, off: usize, t_max: f32) -> (Vec4, u32) {
        let b = |row: usize| Vec4::from_slice(&n.b[row][off..off + 4]);
        let [nx, ny, nz] = self.near;
        let [fx, fy, fz] = self.far;
        let x0 = (b(nx) - self.ox) * self.ix;
        let y0 = (b(ny) - self.oy) * self.iy;
        let z0 = (b(nz) - self.oz) * self.iz;
        let x1 = (b(fx) - self.ox) * self.ix;
        let y1 = (b(fy) - self.oy) * self.iy;
        let z1 = (b(fz) - self.oz) * self.iz;
        let tn = x0.max(y0).max(z0.max(Vec4::ZERO));
        // Clamping t_max to MAX makes unused lanes ([+inf, +inf] boxes, tn =
        // +inf) fail the test below even for an infinite t_max.
        let tf = x1.min(y1).min(z1.min(Vec4::splat(t_max.min(f32::MAX))));
        (tn, (tn * (1.0 / ROBUST)).cmple(tf).bitmask())
    }

    /// [`Self::slab4`] over all eight lanes at once (AVX), operation for
    /// operation the same (`maxps`/`minps` keep their operand order).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    unsafe fn slab8_avx2(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
        use std::arch::x86_64::*;
        let [nx, ny, nz] = self.near;
        let [fx, fy, fz] = self.far;
        let b = n.b.as_ptr() as *const f32;
        // SAFETY: rows are 32 bytes inside a 64-byte aligned node.
        let (bnx, bny, bnz) = unsafe {
            (
                _mm256_load_ps(b.add(WIDTH * nx)),
                _mm256_load_ps(b.add(WIDTH * ny)),
                _mm256_load_ps(b.add(WIDTH * nz)),
            )
        };
        let (bfx, bfy, bfz) = unsafe {
            (
                _mm256_load_ps(b.add(WIDTH * fx)),
                _mm256_load_ps(b.add(WIDTH * fy)),
                _mm256_load_ps(b.add(WIDTH * fz)),
            )
        };
        let w = |v: Vec4| {
            let v: __m128 = v.into();
            _mm256_set_m128(v, v)
        };
        let (ox, oy, oz) = (w(self.ox), w(self.oy), w(self.oz));
        let (ix, iy, iz) = (w(self.ix), w(self.iy), w(self.iz));
        let x0 = _mm256_mul_ps(_mm256_sub_ps(bnx, ox), ix);
        let y0 = _mm256_mul_ps(_mm256_sub_ps(bny, oy), iy);
        let z0 = _mm256_mul_ps(_mm256_sub_ps(bnz, oz), iz);
        let x1 = _mm256_mul_ps(_mm256_sub_ps(bfx, ox), ix);
        let y1 = _mm256_mul_ps(_mm256_sub_ps(bfy, oy), iy);
        let z1 = _mm256_mul_ps(_mm256_sub_ps(bfz, oz), iz);
        let tn = _mm256_max_ps(
            _mm256_max_ps(x0, y0),
            _mm256_max_ps(z0, _mm256_setzero_ps()),
        );
        let tf = _mm256_min_ps(
            _mm256_min_ps(x1, y1),
            _mm256_min_ps(z1, _mm256_set1_ps(t_max.min(f32::MAX))),
        );
        let ok = _mm256_cmp_ps::<_CMP_LE_OS>(_mm256_mul_ps(tn, _mm256_set1_ps(1.0 / ROBUST)), tf);
        let mut out = [0.0f32; WIDTH];
        // SAFETY: `out` holds eight floats.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), tn) };
        (out, _mm256_movemask_ps(ok) as u32)
    }
}

/// Traversal stack (node reference, entry distance), left uninitialised (a
/// query on a large tree would otherwise clear 1.5 KiB per ray).
#[derive(Clone, Copy)]
struct Stack<const N: usize> {
    r: [std::mem::MaybeUninit<u32>; N],
    t: [std::mem::MaybeUninit<f32>; N],
    sp: usize,
}

impl<const N: usize> Stack<N> {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            r: [std::mem::MaybeUninit::uninit(); N],
            t: [std::mem::MaybeUninit::uninit(); N],
            sp: 0,
        }
    }
    #[inline(always)]
    fn push(&mut self, r: u32, t: f32) {
        self.r[self.sp].write(r);
        self.t[self.sp].write(t);
        self.sp += 1;
    }
    /// Pops the top entry; `None` if the stack is empty.
    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        if self.sp == 0 {
            return None;
        }
        self.sp -= 1;
        // SAFETY: entries below `sp` were all written by `push`.
        unsafe { Some((self.r[self.sp].assume_init(), self.t[self.sp].assume_init())) }
    }
}

/// One query of [`Bvh::trace`]: a ray and its `t_max`.
#[derive(Clone, Copy, Debug)]
pub enum RayQuery {
    /// The closest hit, as [`Bvh::intersect`].
    Closest(Ray, f32),
    /// Whether anything is hit, as [`Bvh::occluded`].
    Occluded(Ray, f32),
}

/// The answer to a [`RayQuery`].
#[derive(Clone, Copy, Debug)]
pub enum RayAnswer {
    Closest(Option<Hit>),
    Occluded(bool),
}

/// Queries [`Bvh::trace`] keeps in flight at once. On the 1M-triangle room at two
/// threads (2026-12-03, c7f9453, after the hit record moved to the BVH's packets), 64 against 32:
/// 1.079x, every round above 1.05; 96: 1.02x (noise); 128: 0.94x.
pub const BATCH: usize = 64;

/// Trees larger than this answer [`Bvh::trace`]'s queries faster with their steps
/// interleaved ([`Bvh::interleaves`]).
pub const BATCH_MIN_BYTES: usize = 8 << 20;

/// A query's traversal state.
#[derive(Clone, Copy)]
struct Query<const N: usize> {
    r: RayData,
    /// The closest hit so far (closest-hit queries) or `t_max`.
    t_best: f32,
    /// Packet lane, b1, b2 of the closest hit so far; `u32::MAX` for none. Any-hit
    /// queries set the lane to 0 when they hit.
    best: (u32, f32, f32),
    stack: Stack<N>,
    /// The node or leaf the next step visits.
    cur: u32,
    any: bool,
}

impl<const N: usize> Query<N> {
    #[inline(always)]
    fn new(ray: &Ray, t_max: f32, any: bool, root: u32) -> Self {
        Query {
            r: RayData::new(ray),
            t_best: t_max,
            best: (u32::MAX, 0.0, 0.0),
            stack: Stack::new(),
            cur: root,
            any,
        }
    }
}

/// Traversal stack sizes: the smallest one the tree allows is used (8 bytes
/// per entry, on the query's stack frame); the large one always suffices
/// (see `Bvh::build`).
const TINY_STACK: usize = 16;
const SMALL_STACK: usize = 64;
const LARGE_STACK: usize = (WIDTH - 1) * 64;

impl Bvh {
    /// Builds the BVH with binned SAH (parallel with rayon on large inputs),
    /// then collapses it into an 8-wide BVH.
    pub fn build(tris: &[[Vec3; 3]]) -> Bvh {
        let (mut refs, mut ids): (Vec<build::PrimRef>, Vec<u32>) = tris
            .par_iter()
            .with_min_len(4096)
            .enumerate()
            .filter_map(|(i, t)| {
                if Tri::new(t).is_degenerate() {
                    return None;
                }
                let [a, b, c] = t.map(Vec3A::from);
                let r = build::PrimRef {
                    min: a.min(b).min(c),
                    max: a.max(b).max(c),
                };
                Some((r, i as u32))
            })
            .unzip();
        if refs.is_empty() {
            return Bvh {
                nodes: Vec::new(),
                root: 0,
                bounds: Bounds3::EMPTY,
                stack_needed: 0,
                leaf_count: 0,
                tris: Vec::new(),
                isa: Isa::chosen(),
                interleave: None,
            };
        }
        assert!(refs.len() < 1 << 28, "too many triangles for one BVH");
        let nodes2 = build::build(&mut refs, &mut ids);
        drop(refs);
        let bounds = Bounds3 {
            min: nodes2[0].min,
            max: nodes2[0].max,
        };
        let plan = plan(&nodes2);
        let mut c = Collapse {
            n2: &nodes2,
            plan: &plan,
            ids: &ids,
            input: tris,
            nodes: Vec::with_capacity(nodes2.len() / 4 + 1),
            packets: Vec::with_capacity(nodes2.len() / 2 + 1),
            leaves: 0,
        };
        let (root, stack_needed) = c.slot(0);
        let Collapse {
            nodes,
            packets,
            leaves,
            ..
        } = c;
        drop(plan);
        // Every 8-wide node spans at least one BVH2 level on every path and
        // the BVH2 depth is bounded by the builder, so this always holds.
        assert!(stack_needed <= LARGE_STACK);
        let (nodes, packets) = (on_huge_pages(nodes), on_huge_pages(packets));
        Bvh {
            nodes,
            root,
            bounds,
            stack_needed,
            leaf_count: leaves,
            tris: packets,
            isa: Isa::chosen(),
            interleave: None,
        }
    }

    /// Whether [`Bvh::trace`] interleaves its queries' traversal steps rather than
    /// answering them one after another: when the tree is larger than
    /// [`BATCH_MIN_BYTES`], so that queries wait on memory (interleaving costs a fifth of
    /// the speed of a tree that sits in the caches).
    pub fn interleaves(&self) -> bool {
        self.interleave
            .unwrap_or(self.memory_bytes() > BATCH_MIN_BYTES)
    }

    /// Forces [`Bvh::interleaves`] (`None`: decided by the tree's size again), for
    /// tests and benchmarks that compare the two ways of answering queries.
    pub fn set_interleaving(&mut self, interleave: Option<bool>) {
        self.interleave = interleave;
    }

    /// Instruction set the queries run with.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// Run the queries with `isa` instead (for tests and benchmarks that compare the
    /// paths). Returns false, changing nothing, if this CPU cannot run it.
    pub fn set_isa(&mut self, isa: Isa) -> bool {
        if isa.is_available() {
            self.isa = isa;
        }
        isa.is_available()
    }

    /// Closest hit with `t` in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.tris.is_empty() {
            return None;
        }
        match self.isa {
            // SAFETY: `isa` is only ever set to an available instruction set.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.intersect_avx2(ray, t_max) },
            _ => self.intersect_base(ray, t_max),
        }
    }

    /// Whether anything is hit with `t` in `(0, t_max)` (stops at the first hit).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.tris.is_empty() {
            return false;
        }
        match self.isa {
            // SAFETY: as in `intersect`.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.occluded_avx2(ray, t_max) },
            _ => self.occluded_base(ray, t_max),
        }
    }

    #[inline(never)]
    fn intersect_base(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_sized::<false>(ray, t_max)
    }

    #[inline(never)]
    fn occluded_base(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_sized::<false>(ray, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn intersect_avx2(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_sized::<true>(ray, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn occluded_avx2(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_sized::<true>(ray, t_max)
    }

    /// The traversal with the smallest stack the tree allows.
    #[inline(always)]
    fn intersect_sized<const AVX: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.stack_needed <= TINY_STACK {
            self.intersect_impl::<TINY_STACK, AVX>(ray, t_max)
        } else if self.stack_needed <= SMALL_STACK {
            self.intersect_impl::<SMALL_STACK, AVX>(ray, t_max)
        } else {
            self.intersect_impl::<LARGE_STACK, AVX>(ray, t_max)
        }
    }

    #[inline(always)]
    fn occluded_sized<const AVX: bool>(&self, ray: &Ray, t_max: f32) -> bool {
        if self.stack_needed <= TINY_STACK {
            self.occluded_impl::<TINY_STACK, AVX>(ray, t_max)
        } else if self.stack_needed <= SMALL_STACK {
            self.occluded_impl::<SMALL_STACK, AVX>(ray, t_max)
        } else {
            self.occluded_impl::<LARGE_STACK, AVX>(ray, t_max)
        }
    }

    #[inline(always)]
    fn intersect_impl<const N: usize, const AVX: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
    ) -> Option<Hit> {
        let mut q = Query::<N>::new(ray, t_max, false, self.root);
        while !self.step::<N, AVX, false>(&mut q) {}
        self.closest_of(&q)
    }

    #[inline(always)]
    fn occluded_impl<const N: usize, const AVX: bool>(&self, ray: &Ray, t_max: f32) -> bool {
        let mut q = Query::<N>::new(ray, t_max, true, self.root);
        while !self.step::<N, AVX, false>(&mut q) {}
        q.best.0 != u32::MAX
    }

    /// The closest hit a finished closest-hit query found.
    #[inline(always)]
    fn closest_of<const N: usize>(&self, q: &Query<N>) -> Option<Hit> {
        if q.best.0 == u32::MAX {
            return None;
        }
        let (packet, lane) = (q.best.0 as usize / 4, q.best.0 as usize % 4);
        let p = &self.tris[packet];
        Some(p.lane(lane).hit(p.ids[lane], q.t_best, q.best.1, q.best.2))
    }

    /// One traversal step of `q`: the node or leaf `q.cur` is visited and the
    /// next one chosen (and, interleaved, prefetched). Returns true when the query is done.
    /// A single query loops over it; [`Bvh::trace`] interleaves the steps of
    /// many, so that one query's memory loads overlap the others' work.
    #[inline(always)]
    fn step<const N: usize, const AVX: bool, const IL: bool>(&self, q: &mut Query<N>) -> bool {
        let cur = q.cur;
        if cur & LEAF == 0 {
            let node = &self.nodes[cur as usize];
            let (tn, mask) = q.r.slab8::<AVX>(node, q.t_best);
            if mask != 0 {
                if mask & (mask - 1) == 0 {
                    // Exactly one child hit.
                    q.cur = node.child[mask.trailing_zeros() as usize];
                    self.prefetch_next::<IL>(q.cur);
                    return false;
                }
                if q.any {
                    // Any order will do; push all but the first.
                    let mut m = mask;
                    let first = m.trailing_zeros() as usize;
                    m &= m - 1;
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        m &= m - 1;
                        self.prefetch(node.child[i]);
                        q.stack.push(node.child[i], 0.0);
                    }
                    q.cur = node.child[first];
                    self.prefetch_next::<IL>(q.cur);
                    return false;
                }
                let i0 = mask.trailing_zeros() as usize;
                let rest = mask & (mask - 1);
                if rest & (rest - 1) == 0 {
                    // Exactly two: the nearer goes on (the later lane on a tie, as the
                    // sort below), the other on the stack, chosen without a branch: a
                    // branch on the comparison of two children's distances is a coin
                    // toss for the predictor (the room's rays 1.02-1.04x one at a time).
                    let i1 = rest.trailing_zeros() as usize;
                    let second = tn[i0] >= tn[i1];
                    let (near, far) = (
                        std::hint::select_unpredictable(second, i1, i0),
                        std::hint::select_unpredictable(second, i0, i1),
                    );
                    self.prefetch(node.child[far]);
                    q.stack.push(node.child[far], tn[far]);
                    q.cur = node.child[near];
                    self.prefetch_next::<IL>(q.cur);
                    return false;
                }
                // Three or more: push all but the nearest, farthest first.
                let mut m = mask;
                let mut ids = [0usize; WIDTH];
                let mut k = 0;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    // Insertion sort by decreasing distance.
                    let mut j = k;
                    while j > 0 && tn[ids[j - 1]] < tn[i] {
                        ids[j] = ids[j - 1];
                        j -= 1;
                    }
                    ids[j] = i;
                    k += 1;
                }
                for &i in &ids[..k - 1] {
                    self.prefetch(node.child[i]);
                    q.stack.push(node.child[i], tn[i]);
                }
                q.cur = node.child[ids[k - 1]];
                self.prefetch_next::<IL>(q.cur);
                return false;
            }
        } else {
            let (p, count) = leaf_packets(cur);
            let (mut m, t, u, v) = self.leaf_hits::<AVX>(p, count, &q.r, q.t_best);
            if m != 0 {
                if q.any {
                    q.best.0 = 0;
                    return true;
                }
                // The nearest hit; on a tie the earlier lane (and packet).
                let mut lane = m.trailing_zeros() as usize;
                m &= m - 1;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if t[i] < t[lane] {
                        lane = i;
                    }
                }
                q.t_best = t[lane];
                q.best = ((4 * p + lane) as u32, u[lane], v[lane]);
            }
        }
        // Pop the next node that may still hold a closer hit.
        loop {
            let Some((r, t)) = q.stack.pop() else {
                return true;
            };
            if q.any || t <= q.t_best * ROBUST {
                q.cur = r;
                self.prefetch_next::<IL>(r);
                return false;
            }
        }
    }

    /// The hits of a leaf's `count` triangles (packets `p ..`) within `(0, t_max)`: a mask
    /// over eight lanes (lane 4k + j is packet k's lane j) and their `t, b1, b2` (read
    /// only where the mask is set). A leaf of two packets tests both against the same
    /// `t_max`: in one AVX2 test when `AVX`, else in two SSE ones, the same operations
    /// lane by lane, so both agree bit for bit.
    #[inline(always)]
    fn leaf_hits<const AVX: bool>(
        &self,
        p: usize,
        count: u32,
        r: &RayData,
        t_max: f32,
    ) -> (u32, [f32; 8], [f32; 8], [f32; 8]) {
        #[cfg(target_arch = "x86_64")]
        if AVX && count > 4 {
            // SAFETY: `AVX` is only instantiated by the `*_avx2` queries, which run only
            // where the CPU has AVX2 and FMA; a leaf of more than four triangles has two
            // packets.
            return unsafe { Tri4::intersect_pair_avx2(&self.tris[p..p + 2], r, t_max, count) };
        }
        let mut out = (0, [0.0; 8], [0.0; 8], [0.0; 8]);
        for k in 0..count.div_ceil(4) as usize {
            let (m, t, u, v) =
                self.tris[p + k].intersect(r, t_max, lane_mask(count - 4 * k as u32));
            if m != 0 {
                out.0 |= m << (4 * k);
                out.1[4 * k..4 * k + 4].copy_from_slice(&t.to_array());
                out.2[4 * k..4 * k + 4].copy_from_slice(&u.to_array());
                out.3[4 * k..4 * k + 4].copy_from_slice(&v.to_array());
            }
        }
        out
    }

    /// Answers many queries at once: the answers of [`Bvh::intersect`] and
    /// [`Bvh::occluded`], bit for bit. On trees larger than the caches
    /// ([`Bvh::interleaves`]) their traversal steps are interleaved (see [`Bvh::step`]):
    /// each query waits on memory, and another's step runs meanwhile. Smaller trees
    /// answer them one after another, which still pays over queries spread among the
    /// shading of their paths: the traversal's code and branch history stay warm (stop
    /// 29, two threads: the room of `bench/compare-mitsuba.sh` 1.08x paths/s, the
    /// Cornell box 1.08x; `docs/results/throughput/ab-*-2threads-seq-2026-12-04-6d98280.txt`). Both
    /// ways set up every query's state first, in one loop (then one after another:
    /// Cornell box 1.03x, room 1.02x, `ab-*-2threads-setup-first-2026-12-04-2e0c719.txt`).
    pub fn trace(&self, queries: &[RayQuery], answers: &mut [RayAnswer]) {
        assert_eq!(queries.len(), answers.len(), "one answer per query");
        if self.tris.is_empty() {
            for (q, a) in queries.iter().zip(answers.iter_mut()) {
                *a = match q {
                    RayQuery::Closest(..) => RayAnswer::Closest(None),
                    RayQuery::Occluded(..) => RayAnswer::Occluded(false),
                };
            }
            return;
        }
        let il = self.interleaves();
        for (q, a) in queries.chunks(BATCH).zip(answers.chunks_mut(BATCH)) {
            self.trace_sized(q, a, il);
        }
    }

    /// The queries with the smallest traversal stack the tree allows (as
    /// `intersect_sized`). Each stack size is a function of its own, so that a small
    /// tree's call does not reserve, and probe page by page, the frame of a large one: 64
    /// queries' 448-entry stacks made a 236 KiB frame (2026-12-05, b4ac6ed: the Cornell box 1.060x).
    #[inline(always)]
    fn trace_sized(&self, q: &[RayQuery], a: &mut [RayAnswer], il: bool) {
        if self.stack_needed <= TINY_STACK {
            self.trace_n::<TINY_STACK>(q, a, il)
        } else if self.stack_needed <= SMALL_STACK {
            self.trace_n::<SMALL_STACK>(q, a, il)
        } else {
            self.trace_n::<LARGE_STACK>(q, a, il)
        }
    }

    /// [`Self::trace_impl`] with stack size `N`, on this BVH's instruction set.
    #[inline(always)]
    fn trace_n<const N: usize>(&self, q: &[RayQuery], a: &mut [RayAnswer], il: bool) {
        match (self.isa, il) {
            // SAFETY: as in `intersect`.
            #[cfg(target_arch = "x86_64")]
            (Isa::Avx2, true) => unsafe { self.trace_avx2::<N, true>(q, a) },
            #[cfg(target_arch = "x86_64")]
            (Isa::Avx2, false) => unsafe { self.trace_avx2::<N, false>(q, a) },
            (_, true) => self.trace_base::<N, true>(q, a),
            (_, false) => self.trace_base::<N, false>(q, a),
        }
    }

    #[inline(never)]
    fn trace_base<const N: usize, const IL: bool>(&self, q: &[RayQuery], a: &mut [RayAnswer]) {
        self.trace_impl::<N, false, IL>(q, a)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    unsafe fn trace_avx2<const N: usize, const IL: bool>(
        &self,
        q: &[RayQuery],
        a: &mut [RayAnswer],
    ) {
        self.trace_impl::<N, true, IL>(q, a)
    }

    /// Up to [`BATCH`] queries, their states set up first, then stepped round-robin
    /// until all are done (`IL`) or each to its answer in turn.
    #[inline(always)]
    fn trace_impl<const N: usize, const AVX: bool, const IL: bool>(
        &self,
        qs: &[RayQuery],
        out: &mut [RayAnswer],
    ) {
        debug_assert!(qs.len() <= BATCH);
        let mut st: [std::mem::MaybeUninit<Query<N>>; BATCH] =
            [const { std::mem::MaybeUninit::uninit() }; BATCH];
        let n = qs.len();
        for (s, q) in st.iter_mut().zip(qs) {
            let (ray, t_max, any) = match *q {
                RayQuery::Closest(r, t) => (r, t, false),
                RayQuery::Occluded(r, t) => (r, t, true),
            };
            s.write(Query::new(&ray, t_max, any, self.root));
        }
        // SAFETY: the first `n` entries were written above.
        let st = unsafe { &mut *(&mut st[..n] as *mut [_] as *mut [Query<N>]) };
        if !IL {
            for (q, a) in st.iter_mut().zip(out.iter_mut()) {
                while !self.step::<N, AVX, false>(q) {}
                *a = if q.any {
                    RayAnswer::Occluded(q.best.0 != u32::MAX)
                } else {
                    RayAnswer::Closest(self.closest_of(q))
                };
            }
            return;
        }
        self.prefetch(self.root);
        let mut live = [false; BATCH];
        live[..n].fill(true);
        let mut left = n;
        while left > 0 {
            for ((q, alive), a) in st.iter_mut().zip(live.iter_mut()).zip(out.iter_mut()) {
                if *alive && self.step::<N, AVX, true>(q) {
                    *alive = false;
                    left -= 1;
                    // Answered at once, while the hit's packet is in the cache.
                    *a = if q.any {
                        RayAnswer::Occluded(q.best.0 != u32::MAX)
                    } else {
                        RayAnswer::Closest(self.closest_of(q))
                    };
                }
            }
        }
    }

    /// Prefetches the node or leaf a query visits next when other queries'
    /// steps run before it (`IL`, interleaved); a lone query loads it at once.
    #[inline(always)]
    fn prefetch_next<const IL: bool>(&self, r: u32) {
        if IL {
            self.prefetch(r);
        }
    }

    /// Asks the CPU to start loading the node or triangle packet `r` refers to
    /// (both span several cache lines).
    #[inline(always)]
    fn prefetch(&self, r: u32) {
        #[cfg(target_arch = "x86_64")]
        {
            let (p, lines) = if r & LEAF == 0 {
                (self.nodes.as_ptr().wrapping_add(r as usize) as *const i8, 4)
            } else {
                // 160 bytes aligned to 32 span three lines, 320 six.
                let (first, count) = leaf_packets(r);
                (
                    self.tris.as_ptr().wrapping_add(first) as *const i8,
                    if count > 4 { 6 } else { 3 },
                )
            };
            for l in 0..lines {
                prefetch_line(p.wrapping_add(64 * l));
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = r;
    }

    /// Bounds of all non-degenerate triangles (empty for an empty BVH).
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// Shape of the tree: (8-wide nodes, leaves, triangle packets). The
    /// nodes hold `nodes - 1 + leaves` children.
    pub fn shape(&self) -> (usize, usize, usize) {
        (self.nodes.len(), self.leaf_count, self.tris.len())
    }

    /// Number of nodes: 8-wide interior nodes plus leaves (leaves are stored
    /// inline in their parents' child references, so only the former take
    /// node memory).
    pub fn node_count(&self) -> usize {
        self.nodes.len() + self.leaf_count
    }

    /// Heap plus inline memory used by the structure, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + self.nodes.capacity() * std::mem::size_of::<Node8>()
            + self.tris.capacity() * std::mem::size_of::<Tri4>()
    }
}

/// Asks the CPU to start loading the cache line at `p` into all cache levels (a hint:
/// no effect off x86-64).
#[inline(always)]
pub fn prefetch_line<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of x86-64, and a prefetch never faults whatever the address.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(p as *const i8)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// `v` copied into a new allocation of its exact size whose whole 2 MiB pages Linux is
/// asked to back with transparent huge pages (arrays of 4 MiB or more; smaller ones are
/// returned as they are), for fewer page translations in the traversal of large trees.
///
/// The hint must come before the pages are first touched: memory that is already
/// mapped keeps its 4 KiB pages. The allocator may hand out such memory (glibc's
/// per-thread arenas reuse what the build freed: the work of 2026-12-04 (4a6faaf) found the old hint, given to
/// the build's own vectors, never took effect), so the new allocation's pages are
/// also released (`MADV_DONTNEED`) before the copy writes them, and the copy's first
/// touch then maps huge pages. A hint only: failures are ignored.
fn on_huge_pages<T: Copy>(mut v: Vec<T>) -> Vec<T> {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let bytes = std::mem::size_of_val(v.as_slice());
        if bytes < 2 * HUGE {
            v.shrink_to_fit();
            return v;
        }
        let mut out: Vec<T> = Vec::with_capacity(v.len());
        let start = out.as_ptr() as usize;
        let (a, b) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
        if b > a {
            // SAFETY: both calls only change how the kernel backs pages inside `out`'s
            // own allocation, none of which has been written yet (its length is 0):
            // MADV_DONTNEED drops whatever the allocator left there (reads would see
            // zeros; nothing reads them before the copy below writes them).
            unsafe {
                libc::madvise(a as *mut libc::c_void, b - a, libc::MADV_HUGEPAGE);
                libc::madvise(a as *mut libc::c_void, b - a, libc::MADV_DONTNEED);
            }
        }
        out.extend_from_slice(&v);
        out
    }
    #[cfg(not(target_os = "linux"))]
    {
        v.shrink_to_fit();
        v
    }
}

/// SAH cost of visiting an 8-wide node, relative to testing one triangle
/// packet (both per unit of half area), for the collapse's dynamic programme.
/// A node is four cache lines and a packet three, and a node also sorts the
/// children it pushes. Render A/Bs on a shared machine (noise of several
/// percent; docs/results/throughput/bvh-bench-fill.txt): 1.5 and 2 alike, 1
/// and 3 no better on the 1M-triangle mesh; 3 (one node of 8 children, two
/// two-packet leaves) made the Cornell box 2% slower.
const C_NODE: f32 = 2.0;

/// Per BVH2 node, the least SAH cost of its subtree as at most `j + 1` child
/// slots of an 8-wide node (`cost[j]`, each slot a leaf or an 8-wide node),
/// and its triangle count. Costs are in units of one packet test over the
/// box's half area: a leaf of `n` triangles costs `ceil(n / 4)` times its
/// half area, an 8-wide node `C_NODE` times its half area plus its children.
#[derive(Clone, Copy)]
struct Plan {
    cost: [f32; WIDTH],
    tris: u32,
    /// Whether the subtree as one slot is best a leaf.
    leaf: bool,
}

/// Half area of a BVH2 node's box.
#[inline(always)]
fn area2(n: &Node) -> f32 {
    Bounds3 {
        min: n.min,
        max: n.max,
    }
    .half_area()
}

/// The best split of `j` slots (2 <= j <= 8) between the two children of an
/// interior BVH2 node: (slots of the left child, cost); the first on ties.
#[inline(always)]
fn best_split(plan: &[Plan], left: usize, j: usize) -> (usize, f32) {
    let (l, r) = (&plan[left].cost, &plan[left + 1].cost);
    let mut best = (1, l[0] + r[j - 2]);
    for k in 2..j {
        let c = l[k - 1] + r[j - k - 1];
        if c < best.1 {
            best = (k, c);
        }
    }
    best
}

/// The dynamic programme of Ylitie, Karras & Laine (2017, "Efficient
/// incoherent ray traversal on GPUs through compressed wide BVHs"), bottom-up
/// over the BVH2 (children always follow their parent in `n2`).
fn plan(n2: &[Node]) -> Vec<Plan> {
    let mut plan = vec![
        Plan {
            cost: [0.0; WIDTH],
            tris: 0,
            leaf: false,
        };
        n2.len()
    ];
    for i in (0..n2.len()).rev() {
        let n = &n2[i];
        let a = area2(n);
        let tris = if n.is_leaf() {
            n.count
        } else {
            plan[n.a as usize].tris + plan[n.a as usize + 1].tris
        };
        let leaf = if tris <= MAX_LEAF_TRIS {
            a * tris.div_ceil(4) as f32
        } else {
            f32::INFINITY
        };
        let mut cost = [leaf; WIDTH];
        let mut is_leaf = true;
        if !n.is_leaf() {
            let node = a * C_NODE + best_split(&plan, n.a as usize, WIDTH).1;
            // (Infinite or NaN areas must not make a leaf of too many triangles.)
            is_leaf = tris <= MAX_LEAF_TRIS && leaf <= node;
            cost[0] = leaf.min(node);
            for j in 2..=WIDTH {
                cost[j - 1] = cost[0].min(best_split(&plan, n.a as usize, j).1);
            }
        }
        plan[i] = Plan {
            cost,
            tris,
            leaf: is_leaf,
        };
    }
    plan
}

/// BVH2 → 8-wide BVH conversion state.
struct Collapse<'a> {
    n2: &'a [Node],
    plan: &'a [Plan],
    /// Input triangle indices in BVH2 leaf order.
    ids: &'a [u32],
    input: &'a [[Vec3; 3]],
    nodes: Vec<Node8>,
    packets: Vec<Tri4>,
    leaves: usize,
}

impl Collapse<'_> {
    /// Appends to `out` the BVH2 nodes that, as at most `j` child slots, cover
    /// the subtree at `i` at least cost.
    fn distribute(&self, i: usize, j: usize, out: &mut Vec<usize>) {
        let n = &self.n2[i];
        let p = &self.plan[i];
        if j == 1 || n.is_leaf() || p.cost[j - 1] == p.cost[0] {
            out.push(i);
            return;
        }
        let (k, _) = best_split(self.plan, n.a as usize, j);
        self.distribute(n.a as usize, k, out);
        self.distribute(n.a as usize + 1, j - k, out);
    }

    /// Turns the BVH2 subtree at `i` into one child slot: a leaf of its
    /// triangles or an 8-wide node, whichever the plan found cheaper; nodes
    /// and packets are laid out depth-first. Returns its reference and the
    /// number of traversal stack entries a query below it may need.
    fn slot(&mut self, i: usize) -> (u32, usize) {
        let n2 = self.n2;
        let n = &n2[i];
        let p = self.plan[i];
        if p.leaf {
            // The subtree's triangles are contiguous in leaf order.
            let mut first = i;
            while !n2[first].is_leaf() {
                first = n2[first].a as usize;
            }
            let first = n2[first].a as usize;
            let ids = &self.ids[first..first + p.tris as usize];
            let r = leaf_ref(self.packets.len() as u32, p.tris);
            for chunk in ids.chunks(4) {
                let mut tris = [Tri::new(&[Vec3::ZERO; 3]); 4];
                for (t, &i) in tris.iter_mut().zip(chunk) {
                    *t = Tri::new(&self.input[i as usize]);
                }
                self.packets.push(Tri4::new(&tris[..chunk.len()], chunk));
            }
            self.leaves += 1;
            return (r, 0);
        }
        let mut kids = Vec::with_capacity(WIDTH);
        let (k, _) = best_split(self.plan, n.a as usize, WIDTH);
        self.distribute(n.a as usize, k, &mut kids);
        self.distribute(n.a as usize + 1, WIDTH - k, &mut kids);
        debug_assert!((2..=WIDTH).contains(&kids.len()));
        let idx = self.nodes.len();
        // Unused lanes get the box [+inf, +inf], which no ray overlaps.
        let mut b = [[f32::INFINITY; WIDTH]; 6];
        for (lane, &k) in kids.iter().enumerate() {
            for a in 0..3 {
                b[a][lane] = n2[k].min[a];
                b[a + 3][lane] = n2[k].max[a];
            }
        }
        self.nodes.push(Node8 {
            b,
            child: [0; WIDTH],
        });
        let mut stack_needed = 0;
        for (lane, &k) in kids.iter().enumerate() {
            let (r, s) = self.slot(k);
            self.nodes[idx].child[lane] = r;
            stack_needed = stack_needed.max(s);
        }
        (idx as u32, stack_needed + kids.len() - 1)
    }
}

#[cfg(test)]
mod tests;
