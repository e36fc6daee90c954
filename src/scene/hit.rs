//! The hit record: a ray's closest hit with everything shading needs (position, geometric
//! and shading normals, texture coordinates, barycentrics), from `Scene::intersect`.
//!
//! Cut-outs (materials of opacity below 1, `Material::is_cutout`): a ray passes through
//! such a surface with probability 1 - opacity, decided by a hash of the ray and the
//! triangle (as pbrt-v4's alpha test), for closest hits and shadow rays alike, so that
//! every estimator sees the surface as a stochastic cut-out, unbiased on average over its
//! rays. Scenes without cut-outs take the BVH's answers unchanged.

use super::Scene;
use crate::accel::{prefetch_line, Hit, RayAnswer, RayQuery};
use crate::math::{offset_origin, Frame, Ray, Vec2, Vec3};

/// Cut-out surfaces a ray crosses at most; beyond, it is taken to pass (a bound on the
/// work of a pathological stack of layers).
const MAX_CROSSINGS: usize = 1024;

/// A uniform number in [0, 1) from a ray and a triangle (its bits hashed).
#[inline]
fn cutout_u(ray: &Ray, prim: u32) -> f32 {
    let mut h: u64 = 0x9E37_79B9_7F4A_7C15 ^ prim as u64;
    for v in [ray.o.x, ray.o.y, ray.o.z, ray.d.x, ray.d.y, ray.d.z] {
        h = (h ^ v.to_bits() as u64).wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
    }
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^= h >> 33;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

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

/// The local shading frame at a surface point (normal = +z), with the geometric and
/// shading normals it was built from: the one place where an estimator turns a hit's
/// normals towards the side it is seen from (opaque BSDFs are two-sided) and builds the
/// frame its BSDF is evaluated in.
#[derive(Clone, Copy, Debug)]
pub struct Shading {
    pub ng: Vec3,
    pub ns: Vec3,
    pub frame: Frame,
}

impl Shading {
    /// The normals as given, or both flipped when `flip` (a two-sided BSDF seen from
    /// behind), and the frame around the shading normal.
    #[inline(always)]
    pub fn new(ng: Vec3, ns: Vec3, flip: bool) -> Shading {
        let (ng, ns) = if flip { (-ng, -ns) } else { (ng, ns) };
        Shading {
            ng,
            ns,
            frame: Frame::from_normal(ns),
        }
    }

    /// [`Shading::new`] facing `w` for a two-sided BSDF: flipped when `w` is behind the
    /// geometric normal `ng`.
    #[inline(always)]
    pub fn toward(ng: Vec3, ns: Vec3, w: Vec3, two_sided: bool) -> Shading {
        Shading::new(ng, ns, two_sided && w.dot(ng) < 0.0)
    }
}

impl SurfaceHit {
    /// The hit's [`Shading`] facing `wo` for a two-sided BSDF.
    #[inline(always)]
    pub fn shading(&self, wo: Vec3, two_sided: bool) -> Shading {
        Shading::toward(self.ng, self.ns, wo, two_sided)
    }
}

impl Scene {
    /// The closest hit along `ray` before `t_max`, with the surface information.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let h = if self.cutouts {
            self.intersect_cutouts(ray, t_max)
        } else {
            self.closest(ray, t_max)
        };
        Some(self.surface_hit(h?, -ray.d))
    }

    /// The BVH's closest hit, instances included.
    #[inline(always)]
    fn closest(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        match &self.instances {
            None => self.bvh.intersect(ray, t_max),
            Some(i) => i.closest(&self.bvh, ray, t_max),
        }
    }

    /// Whether a surface stops light along `ray` before `t_max` (shadow rays).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.cutouts {
            self.intersect_cutouts(ray, t_max).is_some()
        } else if let Some(i) = &self.instances {
            i.occluded(&self.bvh, ray, t_max)
        } else {
            self.bvh.occluded(ray, t_max)
        }
    }

    /// Answers a batch of queries as `Bvh::trace`, cut-outs included.
    pub fn trace(&self, queries: &[RayQuery], answers: &mut [RayAnswer]) {
        if !self.cutouts && self.instances.is_none() {
            return self.bvh.trace(queries, answers);
        }
        for (q, a) in queries.iter().zip(answers.iter_mut()) {
            *a = match *q {
                RayQuery::Closest(r, t) if self.cutouts => {
                    RayAnswer::Closest(self.intersect_cutouts(&r, t))
                }
                RayQuery::Closest(r, t) => RayAnswer::Closest(self.closest(&r, t)),
                RayQuery::Occluded(r, t) => RayAnswer::Occluded(self.occluded(&r, t)),
            };
        }
    }

    /// Whether `ray` passes through the surface of hit `h` (its material's opacity).
    #[inline]
    fn passes(&self, ray: &Ray, h: &Hit) -> bool {
        let m = self.material_of(h.prim);
        if !m.is_cutout() {
            return false;
        }
        let mut alpha = m.opacity;
        if let Some(t) = m.opacity_texture {
            let uv = self.smooth_hit(*h).uv;
            alpha *= self.textures[t as usize].lookup(uv.x, uv.y)[0];
        }
        cutout_u(ray, h.prim) >= alpha
    }

    /// The closest hit along `ray` before `t_max` that does not let the ray through.
    fn intersect_cutouts(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut r = *ray;
        let mut t_base = 0.0;
        for _ in 0..MAX_CROSSINGS {
            let mut h = self.closest(&r, t_max - t_base)?;
            h.t += t_base;
            if !self.passes(ray, &h) {
                return Some(h);
            }
            // on through the surface: from just behind it, along the same direction
            let o = offset_origin(h.p, h.n.normalize_or_zero(), ray.d);
            t_base = (o - ray.o).dot(ray.d) / ray.d.length_squared();
            // (a NaN from a zero direction ends the ray too)
            if t_base >= t_max || t_base.is_nan() {
                return None;
            }
            r = Ray::new(o, ray.d);
        }
        None
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

    /// The shading normal of triangle `prim` at `uv` from its material's normal or bump
    /// map (`ns` if it has none), seen from `wo`. (Out of line: scenes without such maps
    /// never call it.)
    #[inline(never)]
    fn mapped_normal(&self, prim: u32, uv: Vec2, ng: Vec3, ns: Vec3, wo: Vec3) -> Vec3 {
        let Some(map) = &self.material_of(prim).normal_map else {
            return ns;
        };
        let (dp_du, dp_dv) = self.dp_duv(prim, ng);
        map.perturb(uv, ng, ns, dp_du, dp_dv, wo)
    }

    /// dp/du and dp/dv of triangle `prim` in Mitsuba's uv, or, without texture coordinates
    /// (or with degenerate ones), the pair Mitsuba's `coordinate_system` builds around the
    /// geometric normal `ng`.
    fn dp_duv(&self, prim: u32, ng: Vec3) -> (Vec3, Vec3) {
        let i = prim as usize;
        let (tri, uvs) = match self.tris.get(i) {
            Some(t) => (*t, self.uvs.get(i).copied()),
            None => (self.instanced_triangle(prim), self.instanced_uvs(prim)),
        };
        let tangents = uvs.and_then(|uvs| crate::texture::normal::tangents(&tri, &uvs));
        tangents.unwrap_or_else(|| ng.any_orthonormal_pair())
    }

    /// `bsdf` with roughness `r` at `hit` seen from `wo`: an anisotropic one turned to the
    /// tangent of Mitsuba's shading frame (dp/du made orthogonal to the shading normal;
    /// under a normal or bump map, to the smooth one first, then to the mapped one),
    /// given in the local frame [`Shading`] builds for `wo`. (Out of line: materials
    /// without such roughness never call it.)
    #[inline(never)]
    pub(super) fn rough_bsdf(
        &self,
        r: &crate::material::roughness::Roughness,
        bsdf: crate::material::Bsdf,
        hit: &SurfaceHit,
        wo: Vec3,
    ) -> crate::material::Bsdf {
        let two_sided = bsdf.is_two_sided();
        r.apply(bsdf, hit.uv, || self.tangent_at(hit, wo, two_sided))
    }

    /// The (cos, sin) of the tangent of Mitsuba's shading frame at `hit` (dp/du made
    /// orthogonal to the shading normal) in the local frame [`Shading`] builds for `wo`
    /// (flipped for a two-sided BSDF seen from behind): where anisotropic roughness lies.
    pub(super) fn tangent_at(&self, hit: &SurfaceHit, wo: Vec3, two_sided: bool) -> [f32; 2] {
        let frame = hit.shading(wo, two_sided).frame;
        let mut dp_du = self.dp_duv(hit.prim, hit.ng).0;
        if let Some(t) = self.terminator(self.material_of(hit.prim), hit) {
            // under a normal or bump map: the smooth frame's tangent (Mitsuba's
            // sh_frame.s), made orthogonal to the mapped normal below
            dp_du = t.smooth_tangent(dp_du);
        }
        let t = dp_du - frame.n * frame.n.dot(dp_du);
        let (c, s) = (t.dot(frame.s), t.dot(frame.t));
        let len = (c * c + s * s).sqrt();
        if len > 0.0 && len.is_finite() {
            [c / len, s / len]
        } else {
            [1.0, 0.0]
        }
    }

    /// The surface information of a BVH hit seen from direction `wo` (towards the ray's
    /// origin: normal and bump maps turn the shading normal to face it).
    ///
    /// A hit on an instance (numbered past the scene's own triangles) asks the instance
    /// for its shading normals and uvs alone, out of line: a call returning the whole
    /// record made the compiler build every hit's record in memory, 24 instructions a
    /// hit more on scenes without instances (callgrind, the furnished room, 2026-12-06).
    #[inline(always)]
    pub fn surface_hit(&self, h: Hit, wo: Vec3) -> SurfaceHit {
        self.surface_hit_of::<false>(h, wo)
    }

    /// Whether every hit is on one of the scene's own triangles (no instances, no
    /// signed-distance grids) and no material has a normal or bump map: what a caller
    /// that checks it once may pass to [`Scene::surface_hit_of`] as `PLAIN`.
    #[inline]
    pub fn plain_hits(&self) -> bool {
        !self.normal_maps && self.instances.is_none()
    }

    /// [`Scene::surface_hit`]; with `PLAIN` (the caller has checked
    /// [`Scene::plain_hits`]) the record of the scene's own triangle alone, with none of
    /// the instances', grids' or maps' branches and calls. Their calls take parts of the
    /// record by reference or return one through memory, and in a per-hit loop that kept
    /// the record in memory, read back in other widths than it was written (the store
    /// not forwarded to the load): the furnished room's paths were 0.91x e91aa28's until
    /// the path tracer took this (2026-12-06).
    #[inline(always)]
    pub fn surface_hit_of<const PLAIN: bool>(&self, h: Hit, wo: Vec3) -> SurfaceHit {
        if PLAIN {
            debug_assert!(self.plain_hits());
            let i = h.prim as usize;
            return self.hit_with(h, self.normals.get(i), self.uvs.get(i));
        }
        let mut s = self.smooth_hit(h);
        if self.normal_maps {
            s.ns = self.mapped_normal(s.prim, s.uv, s.ng, s.ns, wo);
        }
        s
    }

    /// [`Scene::surface_hit`] before a normal or bump map: the shading normal of the
    /// triangle's vertex normals.
    #[inline(always)]
    fn smooth_hit(&self, h: Hit) -> SurfaceHit {
        let i = h.prim as usize;
        if i < self.tris.len() {
            self.hit_with(h, self.normals.get(i), self.uvs.get(i))
        } else if let Some(grid) = self.grid_hit(h) {
            grid
        } else {
            let (normals, uvs) = self.instanced_attrs(h.prim);
            self.hit_with(h, normals.as_ref(), uvs.as_ref())
        }
    }

    /// Mitsuba's shadowing term of a normal- or bump-mapped `hit` of material `mat` (None
    /// for other materials): the smooth shading normal under the map's. (Out of line:
    /// scenes without such maps never call it.)
    #[inline(never)]
    pub fn terminator(
        &self,
        mat: &crate::material::Material,
        hit: &SurfaceHit,
    ) -> Option<crate::texture::normal::Terminator> {
        mat.normal_map.as_ref()?;
        let h = Hit {
            t: hit.t,
            prim: hit.prim,
            b1: hit.b1,
            b2: hit.b2,
            p: hit.p,
            n: hit.ng,
        };
        let smooth = self.smooth_hit(h).ns;
        Some(crate::texture::normal::Terminator::new(smooth, hit.ns))
    }

    /// [`Scene::surface_hit`] with the hit triangle's shading normals and uvs (in world
    /// space).
    #[inline(always)]
    fn hit_with(&self, h: Hit, normals: Option<&[Vec3; 3]>, uvs: Option<&[Vec2; 3]>) -> SurfaceHit {
        let b0 = 1.0 - h.b1 - h.b2;
        // Position and normal come with the hit, from the BVH's copy of the triangle.
        let p = h.p;
        let ng = h.n.normalize();
        let ns = match normals {
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
        let uv = match uvs {
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
