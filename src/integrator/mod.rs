//! Estimators of the radiance along camera rays. They see an immutable scene and a
//! random stream, never the CLI.

pub mod gather;
pub mod path;
pub mod rr;

use crate::math::{Ray, Vec2, Vec3};
use crate::scene::Scene;

pub use rr::{BsdfSelect, Roulette, RrMode, RrWeight};

/// Paths deeper than this end regardless (a guard for unlimited depth without roulette
/// in closed glass or white rooms; the throughput left there is below f32 precision).
pub const HARD_MAX_DEPTH: u32 = 1024;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorKind {
    Path,
}

impl IntegratorKind {
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "path" => Some(IntegratorKind::Path),
            _ => None,
        }
    }
}

/// Settings of an estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorSettings {
    pub kind: IntegratorKind,
    /// Mitsuba's max_depth: 1 = emitters seen directly, 2 = direct light, -1 = unlimited.
    pub max_depth: i32,
    pub roulette: Roulette,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        IntegratorSettings {
            kind: IntegratorKind::Path,
            max_depth: -1,
            roulette: Roulette::default(),
        }
    }
}

impl IntegratorSettings {
    /// The number of path segments allowed.
    #[inline]
    pub fn max_segments(&self) -> u32 {
        if self.max_depth < 0 {
            HARD_MAX_DEPTH
        } else {
            (self.max_depth as u32).min(HARD_MAX_DEPTH)
        }
    }
}

/// Work counters, summed over threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub paths: u64,
    pub rays: u64,
}

impl Counters {
    pub fn add(&mut self, o: &Counters) {
        self.paths += o.paths;
        self.rays += o.rays;
    }
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
    pub prim: u32,
    pub t: f32,
}

/// Intersect and fill in the surface information.
#[inline]
pub fn intersect(scene: &Scene, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
    let h = scene.bvh.intersect(ray, t_max)?;
    let i = h.prim as usize;
    let t = &scene.tris[i];
    let b0 = 1.0 - h.b1 - h.b2;
    let p = t[0] * b0 + t[1] * h.b1 + t[2] * h.b2;
    let ng = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
    let ns = match &scene.normals[i] {
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
    let uv = match &scene.uvs[i] {
        Some(uv) => uv[0] * b0 + uv[1] * h.b1 + uv[2] * h.b2,
        None => Vec2::new(h.b1, h.b2),
    };
    Some(SurfaceHit {
        p,
        ng,
        ns,
        uv,
        prim: h.prim,
        t: h.t,
    })
}

/// The camera ray of a sample of pixel (x, y): dimensions 0 and 1 jitter it in the pixel.
#[inline]
pub fn camera_ray(
    cam: &crate::scene::Camera,
    x: u32,
    y: u32,
    s: &mut crate::sampling::SampleStream,
) -> Ray {
    s.set_dimension(0);
    let u = s.next_2d();
    cam.ray(x as f32 + u.x, y as f32 + u.y)
}
