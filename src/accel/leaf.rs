//! The leaves' triangles: `Tri` in Möller–Trumbore form and `Tri4`, four of them in
//! SoA form tested together.

use super::*;

/// Triangle in Möller–Trumbore form.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    pub(super) v0: Vec3,
    pub(super) e1: Vec3,
    pub(super) e2: Vec3,
}

impl Tri {
    #[inline(always)]
    pub(super) fn new(t: &[Vec3; 3]) -> Tri {
        Tri {
            v0: t[0],
            e1: t[1] - t[0],
            e2: t[2] - t[0],
        }
    }

    /// The hit at `t` with barycentrics `b1, b2` on this triangle, input index `prim`.
    #[inline(always)]
    pub(super) fn hit(&self, prim: u32, t: f32, b1: f32, b2: f32) -> Hit {
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
    pub(super) fn is_degenerate(&self) -> bool {
        let finite = self.v0.is_finite() && self.e1.is_finite() && self.e2.is_finite();
        !(finite && self.e1.cross(self.e2).length_squared() > 0.0)
    }

    /// Möller–Trumbore, double-sided, with the division deferred to the hit (the
    /// scalar reference for [`Tri4`], used by the tests' brute force). Returns
    /// `(t, b1, b2)` for a hit with `0 < t < t_max`.
    #[cfg(test)]
    pub(super) fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
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
pub(super) const SIGN: u32 = 1 << 31;

/// `x` with each lane's sign flipped where `by`'s lane is negative (sign bit
/// set): x * sign(by) without rounding.
#[inline(always)]
pub(super) fn xor_sign(x: Vec4, by: Vec4) -> Vec4 {
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
pub(super) struct Tri4 {
    pub(super) v0: [Vec4; 3],
    pub(super) e1: [Vec4; 3],
    pub(super) e2: [Vec4; 3],
    /// Input index of each lane's triangle (`u32::MAX` for unused lanes): beside
    /// the triangles, so that a hit costs no further cache miss.
    pub(super) ids: [u32; 4],
}

impl Tri4 {
    pub(super) fn new(tris: &[Tri], ids: &[u32]) -> Tri4 {
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
    pub(super) fn lane(&self, lane: usize) -> Tri {
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
    pub(super) fn intersect(&self, r: &RayData, t_max: f32, valid: u32) -> (u32, Vec4, Vec4, Vec4) {
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
    pub(super) unsafe fn intersect_pair_avx2(
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
