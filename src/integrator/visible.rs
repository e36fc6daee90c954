//! Light seen directly: the emission a camera ray reaches through ideal mirrors and smooth
//! glass only, as an expectation (both branches of a glass interface, weighted by their
//! Fresnel probabilities), so it is a deterministic function f(ray).
//!
//! Rushmeier and Ward's noise test and filter are about transport noise. A pixel on an
//! emitter's edge varies from sample to sample only because its footprint straddles the
//! edge, and its excess is real image structure, not noise to be spread.
//! `Integrator::sample` gives a sink that asks for `film::Layer::Visible` the value L and
//! f(ray) from one evaluation of the sample; the film's row sink keeps L - f(ray) (a
//! control variate: any f keeps the estimate unbiased) and f(ray) apart, and
//! `pipeline::render_pass_split` writes them to two films, so a method can test and filter
//! the transport and add the light seen directly back unfiltered. (The radiosity
//! gather's path gives its own f, the emission its camera ray reached through mirrors and
//! glass along the branches it took: the same mean, without tracing the camera ray twice.)

use crate::material::{dielectric::fresnel_dielectric, Bsdf};
use crate::math::{offset_origin, Ray};
use crate::scene::{Scene, Shading};
use crate::spectrum::Spectrum;

use super::Counters;

/// Branches of a glass tree deeper than this are dropped (their weight is below F^8).
const MAX_BRANCH_DEPTH: u32 = 8;

/// f(ray): emission reached through mirrors and smooth glass, at most `max_segments`
/// segments (Mitsuba's max_depth, as the path tracer counts them).
pub fn emission<const N: usize>(
    scene: &Scene,
    ray: Ray,
    max_segments: u32,
    c: &mut Counters,
) -> Spectrum<N> {
    trace(scene, ray, Spectrum::ONE, 1, max_segments, 0, c)
}

fn trace<const N: usize>(
    scene: &Scene,
    mut ray: Ray,
    mut beta: Spectrum<N>,
    mut segments: u32,
    max_segments: u32,
    branches: u32,
    c: &mut Counters,
) -> Spectrum<N> {
    let mut l = Spectrum::<N>::ZERO;
    loop {
        c.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            return l;
        };
        let mat = scene.material_of(hit.prim);
        let wo = -ray.d;
        let cos_o = wo.dot(hit.ng);
        if mat.is_emissive() && cos_o > 0.0 {
            l += beta * Spectrum::<N>::from_rgb(mat.emitted_at(cos_o, hit.uv));
        }
        if segments >= max_segments {
            return l;
        }
        let bsdf = &mat.bsdf;
        let Shading { ng, frame, .. } = hit.shading(wo, bsdf.is_two_sided());
        let wo_l = frame.to_local(wo);
        // The next segment's ray from a local direction, if it leaves on the side the
        // geometric normal says (as the path tracer requires).
        let next = |wi_l: glam::Vec3| {
            let wi = frame.to_world(wi_l);
            ((wi.dot(ng) > 0.0) == (wi_l.z > 0.0))
                .then(|| Ray::new(offset_origin(hit.p, ng, wi), wi))
        };
        match bsdf {
            Bsdf::Mirror(m) => {
                let Some(bs) = m.sample::<N>(wo_l) else {
                    return l;
                };
                let Some(r) = next(bs.wi) else {
                    return l;
                };
                beta *= bs.weight;
                ray = r;
            }
            Bsdf::Dielectric(d) => {
                // E over the Fresnel choice: F x (reflection, weight 1) +
                // (1 - F) x (refraction, weight eta_r^2).
                let (f, _, _) = fresnel_dielectric(wo_l.z, d.eta);
                let refl = d.sample::<N>(wo_l, 0.0).filter(|_| f > 0.0);
                let refr = d
                    .sample::<N>(wo_l, 1.0)
                    .filter(|b| f < 1.0 && b.wi.z * wo_l.z < 0.0);
                // Both branches: the reflection recursively, the refraction in this loop.
                let (bs, p) = match (refl, refr) {
                    (Some(a), Some(b)) if branches < MAX_BRANCH_DEPTH => {
                        if let Some(r) = next(a.wi) {
                            let w = beta * (a.weight * f);
                            l += trace(scene, r, w, segments + 1, max_segments, branches + 1, c);
                        }
                        (b, 1.0 - f)
                    }
                    (Some(a), _) => (a, f),
                    (None, Some(b)) => (b, 1.0 - f),
                    (None, None) => return l,
                };
                let Some(r) = next(bs.wi) else {
                    return l;
                };
                beta *= bs.weight * p;
                ray = r;
            }
            _ => return l,
        }
        segments += 1;
        if beta.is_black() {
            return l;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::{Layer, Sink};
    use crate::integrator::{CameraSample, Gather, Integrator, IntegratorSettings, SampleCtx};
    use crate::sampling::SamplerConfig;
    use crate::scene::Camera;

    /// The last sample's value and layer part, with the layer asked for.
    struct Last(Layer, [[f32; 3]; 2]);

    impl Sink for Last {
        fn layer(&self) -> Layer {
            self.0
        }
        fn sample(&mut self, _: u32, _: u64, value: [f32; 3], part: [f32; 3]) {
            self.1 = [value, part];
        }
        fn splat(&mut self, _: u64, _: crate::math::Vec2, _: [f32; 3]) {
            panic!("the path tracer splatted");
        }
    }

    /// Sample by sample, the transport (L - f) plus the light seen directly (f) is the
    /// plain estimate, and f is the whole of a sample that sees only an emitter: on
    /// `caustic` (glass and mirror: f has glass branches) and `rw-room` (mirror boxes).
    /// The same for the radiosity gather, whose path gives its own f (the branch it took
    /// at glass): without glass that f is this module's.
    #[test]
    fn transport_plus_visible_is_the_plain_sample() {
        for (name, gather) in [
            ("caustic", Gather::Off),
            ("rw-room", Gather::Off),
            ("cornell", Gather::Off),
            ("caustic", Gather::Radiosity),
            ("rw-room", Gather::Radiosity),
            ("cornell", Gather::Radiosity),
        ] {
            let scene = crate::scene::load(name).unwrap();
            let (w, h) = (12, 12);
            let cam = Camera::new(scene.camera, w, h);
            let mut set = IntegratorSettings {
                gather,
                ..Default::default()
            };
            // (the split is tested, not the solution: one shot solves enough)
            set.radiosity.max_shots = Some(1);
            let it = Integrator::prepare(&scene, set, 3, &crate::progress::Silent).unwrap();
            let without_glass = name != "caustic";
            let cfg = SamplerConfig::default();
            let ctx = SampleCtx {
                scene: &scene,
                cam: &cam,
                sampler: &cfg,
                stream: 0,
            };
            let mut c = Counters::default();
            let mut nonzero_f = 0;
            for y in 0..h {
                for x in 0..w {
                    for k in 0..4 {
                        let cs = CameraSample {
                            x,
                            y,
                            pixel: y * w + x,
                            index: k,
                        };
                        let mut whole = Last(Layer::None, [[0.0; 3]; 2]);
                        it.sample::<3>(&ctx, [cs], &mut whole, &mut c);
                        let mut split = Last(Layer::Visible, [[0.0; 3]; 2]);
                        it.sample::<3>(&ctx, [cs], &mut split, &mut c);
                        let [l, f] = split.1;
                        let t = [l[0] - f[0], l[1] - f[1], l[2] - f[2]];
                        let v = [whole.1[0], t, f];
                        for ch in 0..3 {
                            let sum = v[1][ch] + v[2][ch];
                            assert!(
                                (sum - v[0][ch]).abs() <= 1e-4 * (1.0 + v[0][ch].abs()),
                                "{name} ({x}, {y}) #{k}: {:?} + {:?} != {:?}",
                                v[1],
                                v[2],
                                v[0]
                            );
                        }
                        if without_glass {
                            let ray =
                                crate::integrator::camera_ray(&cam, x, y, &mut ctx.stream_of(&cs));
                            let f = emission::<3>(&scene, ray, set.max_segments(), &mut c);
                            assert_eq!(f.to_rgb(), v[2], "{name} ({x}, {y}) #{k} {gather:?}");
                        }
                        nonzero_f += (v[2] != [0.0; 3]) as u32;
                    }
                }
            }
            // (on `caustic` the camera sees the light through glass only by deep internal
            // reflections: their expectation is not 0, a sampled path misses them)
            assert!(
                nonzero_f > 0 || !without_glass && gather == Gather::Radiosity,
                "{name} {gather:?}: the camera sees no emitter"
            );
        }
    }
}
