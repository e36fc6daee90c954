//! The hit record: a ray's closest hit with everything shading needs (position, geometric
//! and shading normals, texture coordinates, barycentrics), from `Scene::intersect`.

use super::Scene;
use crate::accel::{prefetch_line, Hit};
use crate::math::{Ray, Vec2, Vec3};

/// A ray's hit with everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Unit geometric normal from the winding (counter-clockwise side).
    pub ng: Vec3,
    /// Unit shading normal, in the hemisphere of `ng`.
    pub ns: Vec3,
    pub uv: Vec2,
    /// Barycentrics of the hit in its triangle: p = (1 - b1 - b2) v0 + b1 v1 + b2 v2.
    pub b1: f32,
    pub b2: f32,
    pub prim: u32,
    pub t: f32,
}

impl Scene {
    /// The closest hit along `ray` before `t_max`, with the surface information.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        Some(self.surface_hit(self.bvh.intersect(ray, t_max)?))
    }

    /// Starts loading what [`Scene::surface_hit`] and [`Scene::material_of`] read of
    /// triangle `prim` (for batches of hits, whose loads then overlap).
    #[inline(always)]
    pub fn prefetch_hit(&self, prim: u32) {
        let i = prim as usize;
        if let Some(a) = self.normals.first_read(i) {
            prefetch_line(a);
        }
        if let Some(a) = self.uvs.first_read(i) {
            prefetch_line(a);
        }
        prefetch_line(self.tri_material.as_ptr().wrapping_add(i));
    }

    /// The surface information of a BVH hit.
    #[inline(always)]
    pub fn surface_hit(&self, h: Hit) -> SurfaceHit {
        let i = h.prim as usize;
        let b0 = 1.0 - h.b1 - h.b2;
        // Position and normal come with the hit, from the BVH's copy of the triangle.
        let p = h.p;
        let ng = h.n.normalize();
        let ns = match self.normals.get(i) {
            Some(n) => {
                let s = (n[0] * b0 + n[1] * h.b1 + n[2] * h.b2).normalize_or_zero();
                if s == Vec3::ZERO {
                    ng
                } else if s.dot(ng) < 0.0 {
                    -s
                } else {
                    s
                }
            }
            None => ng,
        };
        let uv = match self.uvs.get(i) {
            Some(uv) => uv[0] * b0 + uv[1] * h.b1 + uv[2] * h.b2,
            None => Vec2::new(h.b1, h.b2),
        };
        SurfaceHit {
            p,
            ng,
            ns,
            uv,
            b1: h.b1,
            b2: h.b2,
            prim: h.prim,
            t: h.t,
        }
    }
}
