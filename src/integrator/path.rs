//! Unidirectional path tracer with next-event estimation and multiple importance sampling
//! (power heuristic) between light sampling and BSDF sampling.
//!
//! Depth follows Mitsuba's max_depth: a path of k segments is allowed if k <= max_depth,
//! so 1 gives emitters seen directly and 2 direct lighting. Random dimensions are fixed
//! per bounce (2 for the pixel, then `DIMS_PER_BOUNCE` each), so a dimension means the
//! same decision in every sample, which dependent tests and Sobol both rely on.
//!
//! Every roulette and lobe-selection decision is `integrator::rr`'s: at each reflection the
//! path asks it for a `Selection` (from the throughput F so far), weighs next-event
//! estimation against the selection's density, and lets it decide the continuation.
//!
//! Lights: area lights and the environment are reached both ways (next-event estimation
//! and BSDF sampling, MIS-weighted; a ray that leaves the scene sees the environment);
//! point lights are Dirac, reached by next-event estimation alone.

use super::rr::{LTilde, Step};
use super::{Counters, IntegratorSettings};
use crate::math::{offset_origin, Frame, Ray};
use crate::sampling::{power_heuristic, SampleStream};
use crate::scene::Scene;
use crate::spectrum::Spectrum;

pub const DIMS_CAMERA: u32 = 2;
pub const DIMS_PER_BOUNCE: u32 = 8;

/// Radiance arriving along `ray` (one sample).
pub fn radiance<const N: usize>(
    scene: &Scene,
    mut ray: Ray,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    l_tilde: &LTilde<N>,
    c: &mut Counters,
) -> Spectrum<N> {
    let mut l = Spectrum::<N>::ZERO;
    let mut beta = Spectrum::<N>::ONE;
    // Solid-angle pdf of the last BSDF sample, and whether it was a delta lobe
    // (the camera ray counts as delta: emitters seen directly get full weight).
    let mut prev_pdf = 0.0f32;
    let mut prev_delta = true;
    let max_segments = set.max_segments();
    let mut segments = 0u32;
    let rr = &set.roulette;
    c.paths += 1;
    loop {
        c.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            if let Some(env) = scene.lights.env() {
                l += beta * escaped::<N>(scene, env, ray.d, prev_pdf, prev_delta);
            }
            break;
        };
        segments += 1;
        let mat = scene.material_of(hit.prim);
        let wo = -ray.d;

        // Emission (one-sided: the counter-clockwise side), MIS-weighted against NEE.
        if let Some((le, w)) = emission::<N>(scene, mat, &hit, wo, prev_pdf, prev_delta) {
            l += beta * le * w;
        }
        if segments >= max_segments {
            break;
        }

        // The BSDF at the hit, textured, in a frame facing wo for two-sided materials.
        let bsdf = scene.bsdf_at(mat, &hit);
        let (ng, ns) = if bsdf.is_two_sided() && wo.dot(hit.ng) < 0.0 {
            (-hit.ng, -hit.ns)
        } else {
            (hit.ng, hit.ns)
        };
        let frame = Frame::from_normal(ns);
        let wo_l = frame.to_local(wo);

        s.set_dimension(DIMS_CAMERA + (segments - 1) * DIMS_PER_BOUNCE);
        let u_sel = s.next_1d();
        let u_light = s.next_2d();
        let u_lobe = s.next_1d();
        let u_bsdf = s.next_2d();
        let u_rr = s.next_1d();

        // The roulette's selection at this reflection, from the throughput F = beta.
        let sel = rr.select::<N>(segments - 1, &beta, &bsdf);

        // Next-event estimation.
        if !bsdf.is_delta() {
            l += next_event::<N>(
                scene, hit.p, ng, &frame, wo_l, &bsdf, &sel, u_sel, u_light, &beta, c,
            );
        }

        // Roulette and continuation (integrator/rr.rs).
        let step = sel.sample::<N>(&bsdf, wo_l, u_lobe, u_bsdf, u_rr);
        let terminated = matches!(step, Step::Terminated);
        let lt = || l_tilde.at(hit.prim, hit.p, wo.dot(hit.ng) > 0.0);
        if let Some(e) = rr.estimate_term(&sel, &bsdf, terminated, &beta, lt) {
            l += e;
        }
        let Step::Continue { sample: bs, scale } = step else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        // Shading normals must not let light through the geometric surface.
        if (wi.dot(ng) > 0.0) != (bs.wi.z > 0.0) {
            break;
        }
        beta *= bs.weight;
        if scale != 1.0 {
            beta *= scale;
        }
        if beta.is_black() {
            break;
        }
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        ray = Ray::new(offset_origin(hit.p, ng, wi), wi);
    }
    l
}

/// One sample of pixel (x, y), linear RGB, with no radiance estimate (L~ = 0): for tests
/// and tools that compare estimators; renders go through `Integrator::sample`.
#[inline]
pub fn sample_pixel<const N: usize>(
    scene: &Scene,
    cam: &crate::scene::Camera,
    x: u32,
    y: u32,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    c: &mut Counters,
) -> [f32; 3] {
    let ray = super::camera_ray(cam, x, y, s);
    radiance::<N>(scene, ray, s, set, &LTilde::Scene(Spectrum::ZERO), c).to_rgb()
}

/// The environment's radiance along an escaping ray of direction `d`, MIS-weighted
/// (power heuristic) against its own sampling if the ray came from a non-Dirac sample of
/// density `prev_pdf`. (Out of line: scenes without an environment never call it.)
#[inline(never)]
pub fn escaped<const N: usize>(
    scene: &Scene,
    env: &crate::light::EnvLight,
    d: crate::math::Vec3,
    prev_pdf: f32,
    prev_delta: bool,
) -> Spectrum<N> {
    let le = Spectrum::<N>::from_rgb(env.eval(d));
    if prev_delta {
        return le;
    }
    let pdf_light = env.pdf(d) * scene.lights.pmf_env();
    le * power_heuristic(prev_pdf, pdf_light)
}

/// The emission a segment reaches at `hit` (the front of an emitter seen along -`wo`) and
/// its MIS weight against NEE at the previous vertex: 1 after a delta bounce (and from the
/// camera), else the power heuristic of the BSDF density `prev_pdf` against the light's.
#[inline]
pub fn emission<const N: usize>(
    scene: &Scene,
    mat: &crate::material::Material,
    hit: &crate::scene::SurfaceHit,
    wo: crate::math::Vec3,
    prev_pdf: f32,
    prev_delta: bool,
) -> Option<(Spectrum<N>, f32)> {
    let cos_o = wo.dot(hit.ng);
    if !(mat.is_emissive() && cos_o > 0.0) {
        return None;
    }
    let le = Spectrum::<N>::from_rgb(mat.emitted(cos_o));
    let w = if prev_delta {
        1.0
    } else {
        let li = scene.lights.light_of(hit.prim).unwrap_or(0);
        let pdf_light = scene.lights.pdf_position(li) * hit.t * hit.t / cos_o;
        power_heuristic(prev_pdf, pdf_light)
    };
    Some((le, w))
}

/// Next-event estimation at a non-delta vertex: a point sampled on the lights, its
/// visibility, MIS-weighted (power heuristic) against the roulette's selection density.
/// Returns beta f Le w / p_light (zero if the point is not seen). Shared by the path
/// tracer and the radiosity gather.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn next_event<const N: usize>(
    scene: &Scene,
    p: crate::math::Vec3,
    ng: crate::math::Vec3,
    frame: &Frame,
    wo_l: crate::math::Vec3,
    bsdf: &crate::material::Bsdf,
    sel: &super::rr::Selection,
    u_sel: f32,
    u_light: glam::Vec2,
    beta: &Spectrum<N>,
    c: &mut Counters,
) -> Spectrum<N> {
    let u_area = match scene.lights.choose(u_sel) {
        None => return Spectrum::ZERO,
        Some(crate::light::Chosen::Area(u)) => u,
        Some(k) => {
            return next_event_distant(scene, p, ng, frame, wo_l, bsdf, sel, k, u_light, beta, c)
        }
    };
    let Some(ls) = scene.lights.sample_position(u_area, u_light) else {
        return Spectrum::ZERO;
    };
    let d = ls.p - p;
    let dist2 = d.length_squared();
    let dist = dist2.sqrt();
    let wi = d / dist;
    let cos_l = -wi.dot(ls.n);
    let wi_l = frame.to_local(wi);
    if !(cos_l > 0.0 && facing(bsdf, wi, wi_l, ng)) {
        return Spectrum::ZERO;
    }
    let f = bsdf.eval::<N>(wo_l, wi_l) * wi_l.z.abs();
    if f.is_black() {
        return Spectrum::ZERO;
    }
    let o = offset_origin(p, ng, wi);
    let to = ls.p - o;
    c.rays += 1;
    if scene.bvh.occluded(&Ray::new(o, to), 1.0 - 1e-4) {
        return Spectrum::ZERO;
    }
    let pdf_light = ls.pdf_area * dist2 / cos_l;
    let w = power_heuristic(pdf_light, sel.pdf(bsdf, wo_l, wi_l));
    let le = ls.emitted(&scene.lights, cos_l);
    *beta * f * Spectrum::from_rgb(le) * (w / pdf_light)
}

/// May light arrive from `wi` (world; `wi_l` in the shading frame)? On the side of the
/// geometric and the shading normal alike, and on the front unless the BSDF transmits.
#[inline(always)]
fn facing(
    bsdf: &crate::material::Bsdf,
    wi: crate::math::Vec3,
    wi_l: crate::math::Vec3,
    ng: crate::math::Vec3,
) -> bool {
    if wi_l.z > 0.0 {
        wi.dot(ng) > 0.0
    } else {
        bsdf.transmits() && wi_l.z < 0.0 && wi.dot(ng) < 0.0
    }
}

/// Next-event estimation to a point light (Dirac: no MIS) or the environment (MIS against
/// the roulette's selection density). `kind` is what `Lights::choose` picked.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn next_event_distant<const N: usize>(
    scene: &Scene,
    p: crate::math::Vec3,
    ng: crate::math::Vec3,
    frame: &Frame,
    wo_l: crate::math::Vec3,
    bsdf: &crate::material::Bsdf,
    sel: &super::rr::Selection,
    kind: crate::light::Chosen,
    u_light: glam::Vec2,
    beta: &Spectrum<N>,
    c: &mut Counters,
) -> Spectrum<N> {
    use crate::light::Chosen;
    match kind {
        Chosen::Area(_) => Spectrum::ZERO,
        Chosen::Point(i, pmf) => {
            let pl = scene.lights.points()[i];
            let d = pl.p - p;
            let dist2 = d.length_squared();
            if dist2 <= 0.0 || pmf <= 0.0 {
                return Spectrum::ZERO;
            }
            let wi = d / dist2.sqrt();
            let wi_l = frame.to_local(wi);
            if !facing(bsdf, wi, wi_l, ng) {
                return Spectrum::ZERO;
            }
            let f = bsdf.eval::<N>(wo_l, wi_l) * wi_l.z.abs();
            if f.is_black() {
                return Spectrum::ZERO;
            }
            let o = offset_origin(p, ng, wi);
            c.rays += 1;
            if scene.bvh.occluded(&Ray::new(o, pl.p - o), 1.0 - 1e-4) {
                return Spectrum::ZERO;
            }
            *beta * f * Spectrum::from_rgb(pl.intensity) * (1.0 / (dist2 * pmf))
        }
        Chosen::Env(pmf) => {
            let Some(env) = scene.lights.env() else {
                return Spectrum::ZERO;
            };
            let Some((wi, pdf, le)) = env.sample(u_light) else {
                return Spectrum::ZERO;
            };
            let pdf_light = pdf * pmf;
            let wi_l = frame.to_local(wi);
            if !(pdf_light > 0.0 && facing(bsdf, wi, wi_l, ng)) {
                return Spectrum::ZERO;
            }
            let f = bsdf.eval::<N>(wo_l, wi_l) * wi_l.z.abs();
            if f.is_black() {
                return Spectrum::ZERO;
            }
            c.rays += 1;
            if scene
                .bvh
                .occluded(&Ray::new(offset_origin(p, ng, wi), wi), f32::INFINITY)
            {
                return Spectrum::ZERO;
            }
            let w = power_heuristic(pdf_light, sel.pdf(bsdf, wo_l, wi_l));
            *beta * f * Spectrum::from_rgb(le) * (w / pdf_light)
        }
    }
}
