//! How open a scene is, for the estimate roulette's L~ (`RadianceEstimate`): the paper's
//! L~ = (1/(pi S)) a~ Phi_e / (1 - a~) assumes a closed scene, where every photon is
//! reflected again and again until absorbed. In an open one (Mitsuba's Cornell box has no
//! front wall) part of the emitted and of the reflected power leaves for good:
//!
//! - e_L: the probability that an emitted photon escapes before it hits anything;
//! - e_s: the probability that a reflected photon escapes (leaves the scene from the point
//!   where it was reflected, cosine-distributed, without hitting anything).
//!
//! Both come from one deterministic photon walk: `PHOTONS` photons sampled as the light
//! sampler samples emission (a light by power, a point uniformly on it, a cosine
//! direction), followed through up to `MAX_REFLECTIONS` reflections, each a cosine-
//! distributed direction about the side of the surface the photon arrived on (opaque
//! surfaces are two-sided in kalos: the side that reflects is the side light reaches).
//! A reflection counts with the photon's power at that point (the product of the
//! luminance albedos it met), so e_s is the escaping share of the reflected power.
//!
//! Why a photon walk rather than rays from area-weighted surface points: every opaque
//! surface reflects on both sides, and which side matters depends on where light lands.
//! Rays from the outer side of a closed room's walls would all "escape" and give a closed
//! scene e_s = 1/2; photons never reach that side, so a closed scene gets e_s = e_L = 0
//! exactly, and the paper's formula unchanged.
//!
//! The walk treats every surface as a diffuse reflector of its albedo bound (glass and
//! mirrors included): it is a rough guess of openness, as L~ is a rough guess of radiance;
//! the estimate roulette is unbiased for any L~.
//!
//! Reproducible: the photons are split into fixed chunks with their own seeds, the chunks
//! run in parallel (rayon) and their sums are added in chunk order, so the result does not
//! depend on the number of threads.

use crate::accel::Bvh;
use crate::light::Lights;
use crate::math::{offset_origin, Frame, Ray, Vec3};
use crate::sampling::rng::mix64;
use crate::sampling::{square_to_cosine_hemisphere, SeqRng};
use rayon::prelude::*;

/// Photons of the walk (2^16).
pub const PHOTONS: u32 = 1 << 16;
/// Photons per chunk (one seed each).
const CHUNK: u32 = 1 << 10;
/// Reflections followed per photon (0.7^16 ~ 0.3% of the power is left after them).
pub const MAX_REFLECTIONS: u32 = 16;
const SEED: u64 = 0x6b61_6c6f_735f_6573;

/// e_s and e_L of a scene (see the module comment).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Escape {
    /// e_s: the share of the reflected power that escapes after a reflection.
    pub e_s: f64,
    /// e_L: the share of the emitted photons that escape before hitting anything.
    pub e_l: f64,
}

#[derive(Clone, Copy, Default)]
struct Sums {
    emitted: u64,
    escaped_emitted: u64,
    reflected: f64,
    escaped_reflected: f64,
}

/// e_s and e_L by the photon walk over triangles `tris` (indexed as `bvh` was built) with
/// luminance albedo `albedo[prim]` per triangle. No lights: zero (nothing to estimate).
pub fn escape_probabilities(
    tris: &[[Vec3; 3]],
    bvh: &Bvh,
    lights: &Lights,
    albedo: &[f32],
) -> Escape {
    escape_probabilities_n(tris, bvh, lights, albedo, PHOTONS)
}

/// `escape_probabilities` with `photons` photons (rounded up to whole chunks).
pub fn escape_probabilities_n(
    tris: &[[Vec3; 3]],
    bvh: &Bvh,
    lights: &Lights,
    albedo: &[f32],
    photons: u32,
) -> Escape {
    if lights.is_empty() {
        return Escape::default();
    }
    let chunks = photons.div_ceil(CHUNK);
    let parts: Vec<Sums> = (0..chunks)
        .into_par_iter()
        .map(|c| walk_chunk(tris, bvh, lights, albedo, c))
        .collect();
    let mut t = Sums::default();
    for p in &parts {
        t.emitted += p.emitted;
        t.escaped_emitted += p.escaped_emitted;
        t.reflected += p.reflected;
        t.escaped_reflected += p.escaped_reflected;
    }
    Escape {
        e_s: if t.reflected > 0.0 {
            t.escaped_reflected / t.reflected
        } else {
            0.0
        },
        e_l: if t.emitted > 0 {
            t.escaped_emitted as f64 / t.emitted as f64
        } else {
            0.0
        },
    }
}

fn walk_chunk(tris: &[[Vec3; 3]], bvh: &Bvh, lights: &Lights, albedo: &[f32], chunk: u32) -> Sums {
    let mut rng = SeqRng::new(mix64(SEED ^ chunk as u64));
    let mut s = Sums::default();
    for _ in 0..CHUNK {
        let Some(ls) = lights.sample_position(rng.next_f32(), rng.next_2d()) else {
            continue;
        };
        let (d, _) = lights.sample_direction(ls.light, rng.next_2d());
        s.emitted += 1;
        let mut ray = Ray::new(offset_origin(ls.p, ls.n, d), d);
        let mut power = 1.0f64;
        for bounce in 0..=MAX_REFLECTIONS {
            let Some(h) = bvh.intersect(&ray, f32::INFINITY) else {
                if bounce == 0 {
                    s.escaped_emitted += 1;
                } else {
                    s.escaped_reflected += power;
                }
                break;
            };
            if bounce == MAX_REFLECTIONS {
                break;
            }
            let t = &tris[h.prim as usize];
            let p = ray.o + ray.d * h.t;
            // The side the photon arrived on reflects it.
            let mut n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            if n.dot(ray.d) > 0.0 {
                n = -n;
            }
            power *= albedo[h.prim as usize] as f64;
            if power <= 0.0 {
                break;
            }
            s.reflected += power;
            let wi = Frame::from_normal(n).to_world(square_to_cosine_hemisphere(rng.next_2d()));
            ray = Ray::new(offset_origin(p, n, wi), wi);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::square_to_uniform_triangle;
    use crate::scene::builtin::push_quad;
    use crate::scene::{MaterialDesc, Scene, SceneDesc};

    /// A 2 x 2 floor (albedo 1/2) and, at height `h` above its centre, a small square
    /// emitter facing down, black on its back.
    fn floor_and_lamp(h: f32) -> Scene {
        let mut d = SceneDesc {
            name: "floor".into(),
            ..Default::default()
        };
        let mut floor = MaterialDesc::named("floor");
        floor.kd = [0.5; 3];
        let mut lamp = MaterialDesc::named("lamp");
        lamp.kd = [0.0; 3];
        lamp.ke = [1.0; 3];
        d.materials = vec![floor, lamp];
        let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        push_quad(
            &mut d,
            [
                v(-1.0, 0.0, -1.0),
                v(-1.0, 0.0, 1.0),
                v(1.0, 0.0, 1.0),
                v(1.0, 0.0, -1.0),
            ],
            0,
        );
        let s = 0.01;
        push_quad(
            &mut d,
            [v(-s, h, -s), v(s, h, -s), v(s, h, s), v(-s, h, s)],
            1,
        );
        Scene::build(d, 0.0).unwrap()
    }

    #[test]
    fn closed_furnace_loses_nothing() {
        for name in ["furnace", "furnace-glossy"] {
            let e =
                &crate::integrator::RadianceEstimate::of_scene(&crate::scene::load(name).unwrap());
            assert!(e.e_s < 1e-3 && e.e_l < 1e-3, "{name}: {e:?}");
        }
    }

    #[test]
    fn floor_under_a_lamp() {
        // e_L: 1 - the view factor from a small emitter at height 1 facing down to the
        // 2 x 2 floor centred below it, 4 corner rectangles of X = Y = a/h = 1:
        // F = 4 (1/(2 pi)) 2 X/sqrt(1+X^2) atan(X/sqrt(1+X^2)) (Howell's catalogue, B-3).
        let x = 1.0f64;
        let r = (1.0 + x * x).sqrt();
        let f = 4.0 / (2.0 * std::f64::consts::PI) * 2.0 * (x / r) * (x / r).atan();
        let scene = floor_and_lamp(1.0);
        let e = &crate::integrator::RadianceEstimate::of_scene(&scene);
        assert!(
            (e.e_l - (1.0 - f)).abs() < 0.01,
            "e_L {} want {}",
            e.e_l,
            1.0 - f
        );
        // Every reflection off the lone floor leaves, save the few that hit the lamp.
        assert!(e.e_s > 0.995, "e_s {}", e.e_s);
    }

    #[test]
    fn independent_of_thread_count() {
        let scene = crate::scene::load("cornell").unwrap();
        let albedo: Vec<f32> = scene
            .tri_material
            .iter()
            .map(|&m| scene.materials[m as usize].bsdf.albedo::<3>().luminance())
            .collect();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| escape_probabilities(&scene.tris, &scene.bvh, &scene.lights, &albedo))
        };
        let one = run(1);
        assert_eq!(one, run(3));
        assert_eq!(
            one.e_s,
            crate::integrator::RadianceEstimate::of_scene(&scene).e_s
        );
        assert_eq!(
            one.e_l,
            crate::integrator::RadianceEstimate::of_scene(&scene).e_l
        );
    }

    #[test]
    fn cornell_e_l_by_a_different_estimator() {
        // e_L again with uniform directions over the sphere, weighted (cos / pi) / (1 / (4 pi))
        // = 4 cos on the emitting side and 0 behind it, and points chosen
        // by area, all from another generator: the Cornell box's lamp is one uniform
        // quad, so power-proportional and area-proportional choices agree.
        let scene = crate::scene::load("cornell").unwrap();
        let mut rng = SeqRng::new(12345);
        let lights = scene.lights.all();
        let total: f32 = lights.iter().map(|l| l.area).sum();
        let n = 1 << 18;
        let mut esc = 0.0f64;
        for _ in 0..n {
            let mut u = rng.next_f32() * total;
            let mut l = &lights[0];
            for cand in lights {
                l = cand;
                if u < cand.area {
                    break;
                }
                u -= cand.area;
            }
            let b = square_to_uniform_triangle(rng.next_2d());
            let p = l.v0 + l.e1 * b.x + l.e2 * b.y;
            let w = crate::sampling::square_to_uniform_sphere(rng.next_2d());
            let cos = w.dot(l.n);
            if cos <= 0.0 {
                continue;
            }
            let ray = Ray::new(offset_origin(p, l.n, w), w);
            if scene.bvh.intersect(&ray, f32::INFINITY).is_none() {
                esc += 4.0 * cos as f64;
            }
        }
        let e_l = esc / n as f64;
        let got = crate::integrator::RadianceEstimate::of_scene(&scene).e_l;
        assert!((got - e_l).abs() < 0.01, "walk {got} vs brute force {e_l}");
        assert!(got > 0.05, "the Cornell box is open at the front: {got}");
    }
}
