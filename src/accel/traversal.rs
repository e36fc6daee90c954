//! Traversal: closest-hit and any-hit queries one ray at a time, and `Bvh::trace`
//! answering a batch of queries (interleaved on large trees), each compiled for baseline
//! x86-64 and for AVX2 + FMA.

use super::*;

/// Slack on the far slab distance that makes the box test conservative
/// despite rounding (1 + 2γ₃, Ize 2013).
pub(super) const ROBUST: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Per-ray precomputation for the slab and triangle tests.
#[derive(Clone, Copy)]
pub(super) struct RayData {
    /// Origin, direction and (fixed) reciprocal direction, each component splatted over
    /// four lanes (the 8-wide AVX2 slab test doubles them: reading them back as
    /// written, whole, keeps the loads out of store-forwarding stalls).
    pub(super) ox: Vec4,
    pub(super) oy: Vec4,
    pub(super) oz: Vec4,
    pub(super) dx: Vec4,
    pub(super) dy: Vec4,
    pub(super) dz: Vec4,
    pub(super) ix: Vec4,
    pub(super) iy: Vec4,
    pub(super) iz: Vec4,
    /// Octant: index into `Node8::b` of the near plane per axis (0..3 for
    /// the min planes when the direction is positive, 3..6 for the max
    /// planes when it is negative), and of the far plane.
    pub(super) near: [usize; 3],
    pub(super) far: [usize; 3],
}

impl RayData {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
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
    pub(super) fn slab8<const AVX: bool>(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
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
    pub(super) fn slab4(&self, n: &Node8, off: usize, t_max: f32) -> (Vec4, u32) {
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
    pub(super) unsafe fn slab8_avx2(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
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
pub(super) struct Stack<const N: usize> {
    pub(super) r: [std::mem::MaybeUninit<u32>; N],
    pub(super) t: [std::mem::MaybeUninit<f32>; N],
    pub(super) sp: usize,
}

impl<const N: usize> Stack<N> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Stack {
            r: [std::mem::MaybeUninit::uninit(); N],
            t: [std::mem::MaybeUninit::uninit(); N],
            sp: 0,
        }
    }
    #[inline(always)]
    pub(super) fn push(&mut self, r: u32, t: f32) {
        self.r[self.sp].write(r);
        self.t[self.sp].write(t);
        self.sp += 1;
    }
    /// Pops the top entry; `None` if the stack is empty.
    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<(u32, f32)> {
        if self.sp == 0 {
            return None;
        }
        self.sp -= 1;
        // SAFETY: entries below `sp` were all written by `push`.
        unsafe { Some((self.r[self.sp].assume_init(), self.t[self.sp].assume_init())) }
    }
}

/// A query's traversal state.
#[derive(Clone, Copy)]
pub(super) struct Query<const N: usize> {
    pub(super) r: RayData,
    /// The closest hit so far (closest-hit queries) or `t_max`.
    pub(super) t_best: f32,
    /// Packet lane, b1, b2 of the closest hit so far; `u32::MAX` for none. Any-hit
    /// queries set the lane to 0 when they hit.
    pub(super) best: (u32, f32, f32),
    pub(super) stack: Stack<N>,
    /// The node or leaf the next step visits.
    pub(super) cur: u32,
    pub(super) any: bool,
}

impl<const N: usize> Query<N> {
    #[inline(always)]
    pub(super) fn new(ray: &Ray, t_max: f32, any: bool, root: u32) -> Self {
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
pub(super) const TINY_STACK: usize = 16;
// `Bvh::trace_impl` lists its live queries by u8 index.
const _: () = assert!(BATCH <= 256);
pub(super) const SMALL_STACK: usize = 64;
pub(super) const LARGE_STACK: usize = (WIDTH - 1) * 64;

impl Bvh {
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
    pub(super) fn intersect_base(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_sized::<false>(ray, t_max)
    }

    #[inline(never)]
    pub(super) fn occluded_base(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_sized::<false>(ray, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn intersect_avx2(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.intersect_sized::<true>(ray, t_max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn occluded_avx2(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_sized::<true>(ray, t_max)
    }

    /// The traversal with the smallest stack the tree allows.
    #[inline(always)]
    pub(super) fn intersect_sized<const AVX: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.stack_needed <= TINY_STACK {
            self.intersect_impl::<TINY_STACK, AVX>(ray, t_max)
        } else if self.stack_needed <= SMALL_STACK {
            self.intersect_impl::<SMALL_STACK, AVX>(ray, t_max)
        } else {
            self.intersect_impl::<LARGE_STACK, AVX>(ray, t_max)
        }
    }

    #[inline(always)]
    pub(super) fn occluded_sized<const AVX: bool>(&self, ray: &Ray, t_max: f32) -> bool {
        if self.stack_needed <= TINY_STACK {
            self.occluded_impl::<TINY_STACK, AVX>(ray, t_max)
        } else if self.stack_needed <= SMALL_STACK {
            self.occluded_impl::<SMALL_STACK, AVX>(ray, t_max)
        } else {
            self.occluded_impl::<LARGE_STACK, AVX>(ray, t_max)
        }
    }

    #[inline(always)]
    pub(super) fn intersect_impl<const N: usize, const AVX: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
    ) -> Option<Hit> {
        let mut q = Query::<N>::new(ray, t_max, false, self.root);
        while !self.step::<N, AVX, false>(&mut q) {}
        self.closest_of(&q)
    }

    #[inline(always)]
    pub(super) fn occluded_impl<const N: usize, const AVX: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
    ) -> bool {
        let mut q = Query::<N>::new(ray, t_max, true, self.root);
        while !self.step::<N, AVX, false>(&mut q) {}
        q.best.0 != u32::MAX
    }

    /// The closest hit a finished closest-hit query found.
    #[inline(always)]
    pub(super) fn closest_of<const N: usize>(&self, q: &Query<N>) -> Option<Hit> {
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
    pub(super) fn step<const N: usize, const AVX: bool, const IL: bool>(
        &self,
        q: &mut Query<N>,
    ) -> bool {
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
    pub(super) fn leaf_hits<const AVX: bool>(
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
    pub(super) fn trace_sized(&self, q: &[RayQuery], a: &mut [RayAnswer], il: bool) {
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
    pub(super) fn trace_n<const N: usize>(&self, q: &[RayQuery], a: &mut [RayAnswer], il: bool) {
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
    pub(super) fn trace_base<const N: usize, const IL: bool>(
        &self,
        q: &[RayQuery],
        a: &mut [RayAnswer],
    ) {
        self.trace_impl::<N, false, IL>(q, a)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn trace_avx2<const N: usize, const IL: bool>(
        &self,
        q: &[RayQuery],
        a: &mut [RayAnswer],
    ) {
        self.trace_impl::<N, true, IL>(q, a)
    }

    /// Up to [`BATCH`] queries, their states set up first, then stepped round-robin
    /// until all are done (`IL`) or each to its answer in turn.
    #[inline(always)]
    pub(super) fn trace_impl<const N: usize, const AVX: bool, const IL: bool>(
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
        // The queries still walking, in a list from which an answered one is taken out
        // (the last one takes its place), so that a round steps only those: the rays of
        // a batch end at very different depths (on an open scene most leave after a few
        // steps), and a round over every slot spent its time skipping answered ones.
        let mut live = [0u8; BATCH];
        for (i, l) in live[..n].iter_mut().enumerate() {
            *l = i as u8;
        }
        let mut left = n;
        while left > 0 {
            let mut i = 0;
            while i < left {
                let j = live[i] as usize;
                let q = &mut st[j];
                if self.step::<N, AVX, true>(q) {
                    // Answered at once, while the hit's packet is in the cache.
                    out[j] = if q.any {
                        RayAnswer::Occluded(q.best.0 != u32::MAX)
                    } else {
                        RayAnswer::Closest(self.closest_of(q))
                    };
                    left -= 1;
                    live[i] = live[left];
                } else {
                    i += 1;
                }
            }
        }
    }

    /// Prefetches the node or leaf a query visits next when other queries'
    /// steps run before it (`IL`, interleaved); a lone query loads it at once.
    #[inline(always)]
    pub(super) fn prefetch_next<const IL: bool>(&self, r: u32) {
        if IL {
            self.prefetch(r);
        }
    }

    /// Asks the CPU to start loading the node or triangle packet `r` refers to
    /// (both span several cache lines).
    #[inline(always)]
    pub(super) fn prefetch(&self, r: u32) {
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
}
