//! Placeholder brute-force intersector with the BVH's API (replaced by the SAH BVH).
use crate::math::{Bounds3, Ray, Vec3};

pub struct Bvh {
    tris: Vec<[Vec3; 3]>,
    bounds: Bounds3,
}

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub b1: f32,
    pub b2: f32,
}

fn hit_tri(ray: &Ray, t: &[Vec3; 3], tmax: f32) -> Option<(f32, f32, f32)> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let pv = ray.d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.o - t[0];
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = ray.d.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let th = e2.dot(qv) * inv;
    (th > 0.0 && th < tmax).then_some((th, u, v))
}

impl Bvh {
    pub fn build(tris: &[[Vec3; 3]]) -> Bvh {
        let mut bounds = Bounds3::EMPTY;
        for t in tris {
            for v in t {
                bounds.grow(*v);
            }
        }
        Bvh {
            tris: tris.to_vec(),
            bounds,
        }
    }
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut tm = t_max;
        for (i, t) in self.tris.iter().enumerate() {
            if let Some((th, b1, b2)) = hit_tri(ray, t, tm) {
                tm = th;
                best = Some(Hit {
                    t: th,
                    prim: i as u32,
                    b1,
                    b2,
                });
            }
        }
        best
    }
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.tris.iter().any(|t| hit_tri(ray, t, t_max).is_some())
    }
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }
    pub fn node_count(&self) -> usize {
        1
    }
    pub fn memory_bytes(&self) -> usize {
        self.tris.len() * 36
    }
}
