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

use super::lanes::Lanes;
use super::phases::{Phase, Timer};
use super::rr::{LTilde, Step};
use super::step::facing;
pub use super::step::{continuation, continued, ToPoint, BATCH_PATHS, SHADOW_T_MAX};
use super::{Counters, IntegratorSettings};
use crate::light::Chosen;
use crate::material::Bsdf;
use crate::math::{offset_origin, Frame, Ray, Vec3};
use crate::sampling::{power_heuristic, SampleStream};
use crate::scene::{Scene, Shading, SurfaceHit};
use crate::spectrum::Spectrum;

pub const DIMS_CAMERA: u32 = 2;
pub const DIMS_PER_BOUNCE: u32 = 8;

/// Radiance arriving along `ray` (one sample).
pub fn radiance<const N: usize>(
    scene: &Scene,
    ray: Ray,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    l_tilde: &LTilde<N>,
    c: &mut Counters,
) -> Spectrum<N> {
    let mut p = PathState::<N>::new(ray, c);
    while let Some(ray) = p.ray {
        c.rays += 1;
        let hit = scene.intersect(&ray, f32::INFINITY);
        p.advance::<false>(scene, &ray, hit, s, set, l_tilde, c, None);
        let occluded = p.waiting && scene.occluded(&p.shadow.0, p.shadow.1);
        p.resolve(occluded);
    }
    p.l
}

/// [`radiance`] of up to [`BATCH_PATHS`] camera rays at once, each with its own sample
/// stream, into `out`: the same paths, operation for operation, but each step's ray
/// queries of all paths are answered together by `Bvh::trace`, which overlaps their
/// memory loads on scenes larger than the caches and keeps the traversal's code and
/// branch history warm on the others.
///
/// `PLAIN`: the caller has checked that the scene's hits are all its own triangles without
/// normal or bump maps ([`Scene::plain_hits`]), and the paths take code without the
/// instances', grids' and maps' work per hit, as before those features.
pub fn radiance_batch<const N: usize, const PLAIN: bool>(
    scene: &Scene,
    rays: &[Ray],
    streams: &mut [SampleStream],
    set: &IntegratorSettings,
    l_tilde: &LTilde<N>,
    c: &mut Counters,
    out: &mut [Spectrum<N>],
) {
    use crate::accel::{RayAnswer, RayQuery};
    assert!(
        !PLAIN || scene.plain_hits(),
        "a plain batch of a scene with instances or maps"
    );
    let n = rays.len();
    assert!(n <= BATCH_PATHS && streams.len() == n && out.len() == n);
    let mut st = [PathState::<N>::DONE; BATCH_PATHS];
    for (p, &r) in st.iter_mut().zip(rays) {
        *p = PathState::new(r, c);
    }
    let mut qs = [RayQuery::Occluded(Ray::new(Vec3::ZERO, Vec3::ZERO), 0.0); 2 * BATCH_PATHS];
    let mut ans = [RayAnswer::Occluded(false); 2 * BATCH_PATHS];
    // (Only RGB paths end in lanes: see `Lanes::takes`.)
    let mut lanes = (N == 3).then(Lanes::<N>::default);
    let mut timer = Timer::start();
    loop {
        let mut k = 0;
        for p in &st[..n] {
            // (written whether or not the path waits on it, and kept by moving k past it)
            qs[k] = RayQuery::Occluded(p.shadow.0, p.shadow.1);
            k += p.waiting as usize;
            if let Some(r) = p.ray {
                c.rays += 1;
                qs[k] = RayQuery::Closest(r, f32::INFINITY);
                k += 1;
            }
        }
        timer.lap(Phase::Gather);
        if k == 0 {
            break;
        }
        scene.trace(&qs[..k], &mut ans[..k]);
        timer.lap(Phase::Trace);
        // The hits' triangle data is asked for before the paths read it, where the scene
        // is too large for the caches (as the BVH, `Bvh::interleaves`). On smaller scenes
        // it is in the caches already and the loop only costs time: without it the Cornell
        // box 1.027x and 1.042x (8 rounds each, two threads), the room 1.006x (2026-12-05, b4ac6ed,
        // `docs/results/throughput/ab-hit-prefetch-2026-12-04-477fc55.txt`).
        if scene.bvh.interleaves() {
            for a in &ans[..k] {
                if let RayAnswer::Closest(Some(h)) = a {
                    scene.prefetch_hit(h.prim);
                }
            }
        }
        // The answers follow the queries: the j-th is a path's shadow ray's if it waits
        // on one (read whether or not it does, as the gather wrote it), then its segment's.
        let mut j = 0;
        for (i, (p, s)) in st[..n].iter_mut().zip(streams.iter_mut()).enumerate() {
            debug_assert!(!p.waiting || matches!(ans[j], RayAnswer::Occluded(_)));
            let occluded = matches!(ans.get(j), Some(RayAnswer::Occluded(true)));
            j += p.waiting as usize;
            p.resolve(occluded);
            if let Some(ray) = p.ray {
                let RayAnswer::Closest(h) = &ans[j] else {
                    unreachable!("answers follow the queries")
                };
                j += 1;
                let hit = h.map(|h| scene.surface_hit_of::<PLAIN>(h, -ray.d));
                let lane = lanes.as_mut().map(|l| (l, i as u8));
                p.advance::<PLAIN>(scene, &ray, hit, s, set, l_tilde, c, lane);
            }
        }
        timer.lap(Phase::Advance);
        // The diffuse vertices handed to the lanes end together.
        if let Some(lanes) = lanes.as_mut().filter(|l| l.k > 0) {
            lanes.finish(scene.bvh.isa());
            timer.lap(Phase::Lanes);
            for i in 0..lanes.k {
                let (waiting, shadow, next) = lanes.ending(i);
                let p = &mut st[lanes.path[i] as usize];
                c.rays += waiting as u64;
                (p.waiting, p.shadow) = (waiting, shadow);
                p.continue_with(next);
            }
            lanes.k = 0;
            timer.lap(Phase::Ending);
        }
    }
    timer.finish();
    for (o, p) in out.iter_mut().zip(st[..n].iter_mut()) {
        // A last estimate term (the path ended with no shadow ray) is still to add.
        p.resolve(false);
        *o = p.l;
    }
}

/// A path between its ray queries: what [`radiance`] keeps from one vertex to the next,
/// so that [`radiance_batch`] can answer many paths' queries together. Per vertex,
/// `advance` takes the segment's hit (adding the emission it reaches) and prepares the
/// shadow ray and the next segment; `resolve` takes the shadow ray's answer (adding the
/// next-event estimate, then the roulette's estimate term).
#[derive(Clone, Copy)]
struct PathState<const N: usize> {
    l: Spectrum<N>,
    beta: Spectrum<N>,
    /// Solid-angle pdf of the last BSDF sample, and whether it was a delta lobe
    /// (the camera ray counts as delta: emitters seen directly get full weight).
    prev_pdf: f32,
    prev_delta: bool,
    segments: u32,
    /// The next segment, while the path goes on.
    ray: Option<Ray>,
    /// Next-event estimation waiting for its shadow ray (if `waiting`): the ray, its
    /// t_max, and what it adds if nothing is in the way. A flag beside the values rather
    /// than an `Option`, so that a batch gathers, answers and resolves it without a branch
    /// on it: whether a vertex has a shadow ray is close to random (the light point
    /// faces it or not), and the branches on it in the gather and the answers' walk were
    /// mispredicted about one time in four (the furnished room, 2026-12-06).
    shadow: (Ray, f32, Spectrum<N>),
    waiting: bool,
    /// The roulette's estimate term at the last vertex (added after the NEE).
    est: Option<Spectrum<N>>,
}

impl<const N: usize> PathState<N> {
    /// A path with nothing left to do (and nothing gathered).
    const DONE: Self = PathState {
        l: Spectrum::ZERO,
        beta: Spectrum::ONE,
        prev_pdf: 0.0,
        prev_delta: true,
        segments: 0,
        ray: None,
        shadow: (
            Ray {
                o: Vec3::ZERO,
                d: Vec3::ZERO,
            },
            0.0,
            Spectrum::ZERO,
        ),
        waiting: false,
        est: None,
    };

    #[inline]
    fn new(ray: Ray, c: &mut Counters) -> Self {
        c.paths += 1;
        PathState {
            ray: Some(ray),
            ..Self::DONE
        }
    }

    /// The shadow ray's answer: the waiting next-event estimate (unless `occluded`),
    /// then the estimate term.
    #[inline(always)]
    fn resolve(&mut self, occluded: bool) {
        // l + e, or l, chosen per band without a branch
        let add = self.waiting && !occluded;
        for (l, e) in self.l.0.iter_mut().zip(self.shadow.2 .0) {
            *l = std::hint::select_unpredictable(add, *l + e, *l);
        }
        self.waiting = false;
        if let Some(e) = self.est.take() {
            self.l += e;
        }
    }

    /// The segment along `ray` reached `hit` (`None`: it left the scene); `PLAIN` as
    /// [`Scene::surface_hit_of`]'s.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn advance<const PLAIN: bool>(
        &mut self,
        scene: &Scene,
        ray: &Ray,
        hit: Option<SurfaceHit>,
        s: &mut SampleStream,
        set: &IntegratorSettings,
        l_tilde: &LTilde<N>,
        c: &mut Counters,
        lanes: Option<(&mut Lanes<N>, u8)>,
    ) {
        self.ray = None;
        let beta = self.beta;
        let Some(hit) = hit else {
            if let Some(env) = scene.lights.env() {
                self.l += beta * escaped::<N>(scene, env, ray.d, self.prev_pdf, self.prev_delta);
            }
            return;
        };
        self.segments += 1;
        let segments = self.segments;
        let mat = scene.material_of(hit.prim);
        let wo = -ray.d;

        // Emission (one-sided: the counter-clockwise side), MIS-weighted against NEE.
        if let Some((le, w)) = emission::<N>(scene, mat, &hit, wo, self.prev_pdf, self.prev_delta) {
            self.l += beta * le * w;
        }
        if segments >= set.max_segments() {
            return;
        }

        // The BSDF at the hit, textured, in a frame facing wo for two-sided materials.
        let bsdf = scene.bsdf_at(mat, &hit, wo);
        let Shading { ng, ns, frame } = hit.shading(wo, bsdf.is_two_sided());
        // a normal or bump map's shadowing term (texture/normal.rs)
        let term = if !PLAIN && scene.normal_maps {
            scene.terminator(mat, &hit)
        } else {
            None
        };

        s.set_dimension(DIMS_CAMERA + (segments - 1) * DIMS_PER_BOUNCE);
        let u_sel = s.next_1d();
        let u_light = s.next_2d();
        let u_lobe = s.next_1d();
        let u_bsdf = s.next_2d();
        let u_rr = s.next_1d();

        // The roulette's selection at this reflection, from the throughput F = beta.
        let rr = &set.roulette;
        let sel = rr.select::<N>(segments - 1, &beta, &bsdf);

        // A diffuse vertex under the BSDF's own sampling ends in the batch's SIMD lanes
        // (one whose light point has an emission table draws it again in `next_event`:
        // the same point, from the same numbers).
        if let (Some((lanes, path)), Bsdf::Diffuse(lam), None) = (lanes, &bsdf, term) {
            if Lanes::<N>::takes(&sel, rr.mode.uses_estimate()) {
                if let Some(Chosen::Area(u_area)) = scene.lights.choose(u_sel) {
                    if let Some(ls) = scene.lights.sample_position(u_area, u_light) {
                        if !ls.directional {
                            let (p, kd) = (hit.p, lam.kd);
                            lanes.push(path, p, ng, ns, wo, kd, &sel, u_bsdf, u_rr, &ls, &beta);
                            return;
                        }
                    }
                }
            }
        }
        let wo_l = frame.to_local(wo);

        // Next-event estimation (its shadow ray is answered by `resolve`).
        if !bsdf.is_delta() {
            let shadow = next_event::<N>(
                scene, hit.p, ng, &frame, wo_l, &bsdf, &sel, u_sel, u_light, &beta, c,
            );
            if let Some((r, t_max, e)) = shadow {
                let e = match term {
                    Some(t) => e * t.factor(r.d),
                    None => e,
                };
                (self.waiting, self.shadow) = (true, (r, t_max, e));
            }
        }

        // Roulette and continuation (integrator/rr.rs).
        let step = sel.sample::<N>(&bsdf, wo_l, u_lobe, u_bsdf, u_rr);
        let terminated = matches!(step, Step::Terminated);
        let lt = || l_tilde.at_hit(&hit, wo.dot(hit.ng) > 0.0);
        self.est = rr.estimate_term(&sel, &bsdf, terminated, &beta, lt);
        let next = continuation(hit.p, ng, &frame, step, &beta);
        self.continue_with(match term {
            None => next,
            Some(t) => next.and_then(|(r, b, pdf, delta)| {
                let g = t.factor(r.d);
                (g > 0.0).then_some((r, b * g, pdf, delta))
            }),
        });
    }

    /// Takes [`continuation`]'s answer: the next segment, or the end of the walk.
    #[inline(always)]
    fn continue_with(&mut self, next: Option<(Ray, Spectrum<N>, f32, bool)>) {
        if let Some((ray, beta, pdf, delta)) = next {
            self.beta = beta;
            self.prev_pdf = pdf;
            self.prev_delta = delta;
            self.ray = Some(ray);
        }
    }
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
    let le = Spectrum::<N>::from_rgb(mat.emitted_at(cos_o, hit.uv));
    let w = if prev_delta {
        1.0
    } else {
        let li = scene.lights.light_of(hit.prim).unwrap_or(0);
        let pdf_light = scene.lights.pdf_position(li) * hit.t * hit.t / cos_o;
        power_heuristic(prev_pdf, pdf_light)
    };
    Some((le, w))
}

/// Next-event estimation at a non-delta vertex: a point sampled on the lights,
/// MIS-weighted (power heuristic) against the roulette's selection density, before its
/// visibility: the shadow ray, its t_max, and beta f Le w / p_light to add if nothing is
/// in the way (`None`: nothing to add whatever the visibility). Shared by the path tracer
/// (which answers the shadow ray in `PathState::resolve`) and the radiosity gather.
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
) -> Option<(Ray, f32, Spectrum<N>)> {
    let u_area = match scene.lights.choose(u_sel) {
        None => return None,
        Some(crate::light::Chosen::Area(u)) => u,
        Some(k) => {
            return next_event_distant(scene, p, ng, frame, wo_l, bsdf, sel, k, u_light, beta, c)
        }
    };
    let ls = scene.lights.sample_position(u_area, u_light)?;
    let shadow = toward_point(
        p,
        ng,
        frame,
        bsdf.transmits(),
        |wi_l| bsdf.eval::<N>(wo_l, wi_l),
        |wi_l| sel.pdf(bsdf, wo_l, wi_l),
        (ls.p, ls.n, ls.pdf_area),
        |cos_l| ls.emitted(&scene.lights, cos_l),
        beta,
    );
    c.rays += shadow.is_some() as u64;
    shadow
}

/// Next-event estimation toward a sampled point `lp` of an area light (normal `ln`,
/// density `pdf_area` per unit area, radiance `le(cos)` at cosine cos to its normal): the
/// shadow ray, its t_max, and beta f Le w / p_light with p_light the point's density
/// in solid angle, if anything is to add (as [`next_event`]). `f(wi_l)` and `pdf(wi_l)`
/// are the BSDF's value and the continuation's density toward wi_l (shading frame), and
/// `transmits` whether it lets light through.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn toward_point<const N: usize>(
    p: Vec3,
    ng: Vec3,
    frame: &Frame,
    transmits: bool,
    f: impl FnOnce(Vec3) -> Spectrum<N>,
    pdf: impl FnOnce(Vec3) -> f32,
    light: (Vec3, Vec3, f32),
    le: impl FnOnce(f32) -> [f32; 3],
    beta: &Spectrum<N>,
) -> Option<(Ray, f32, Spectrum<N>)> {
    let to = ToPoint::new(p, frame, light);
    if !to.reaches(ng, transmits) {
        return None;
    }
    let f = f(to.wi_l) * to.wi_l.z.abs();
    if f.is_black() {
        return None;
    }
    Some(to.estimate(p, ng, f, pdf(to.wi_l), le(to.cos_l), beta))
}

/// Next-event estimation to a point light (Dirac: no MIS) or the environment (MIS against
/// the roulette's selection density), before its shadow ray (as
/// [`next_event`]). `kind` is what `Lights::choose` picked.
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
) -> Option<(Ray, f32, Spectrum<N>)> {
    use crate::light::Chosen;
    match kind {
        Chosen::Area(_) => None,
        Chosen::Point(i, pmf) => {
            use crate::light::PointShape;
            let pl = &scene.lights.points()[i];
            if pmf <= 0.0 {
                return None;
            }
            // direction to the light, 1 / distance^2 (1 for a directional light) and the
            // intensity towards p
            let (wi, inv_d2, intensity) = match &pl.shape {
                PointShape::Directional(dir) => (-*dir, 1.0, pl.intensity),
                shape => {
                    let d = pl.p - p;
                    let dist2 = d.length_squared();
                    if dist2 <= 0.0 {
                        return None;
                    }
                    let wi = d / dist2.sqrt();
                    let i = match shape {
                        PointShape::Spot(s) => {
                            let k = s.falloff(-wi);
                            [0, 1, 2].map(|c| pl.intensity[c] * k[c])
                        }
                        _ => pl.intensity,
                    };
                    (wi, 1.0 / dist2, i)
                }
            };
            if intensity.iter().all(|&v| v <= 0.0) {
                return None;
            }
            let wi_l = frame.to_local(wi);
            if !facing(bsdf.transmits(), wi, wi_l, ng) {
                return None;
            }
            let f = bsdf.eval::<N>(wo_l, wi_l) * wi_l.z.abs();
            if f.is_black() {
                return None;
            }
            let o = offset_origin(p, ng, wi);
            c.rays += 1;
            let e = *beta * f * Spectrum::from_rgb(intensity) * (inv_d2 / pmf);
            Some(match pl.shape {
                PointShape::Directional(_) => (Ray::new(o, wi), f32::INFINITY, e),
                _ => (Ray::new(o, pl.p - o), SHADOW_T_MAX, e),
            })
        }
        Chosen::Env(pmf) => {
            let env = scene.lights.env()?;
            let (wi, pdf, le) = env.sample(u_light)?;
            let pdf_light = pdf * pmf;
            let wi_l = frame.to_local(wi);
            if !(pdf_light > 0.0 && facing(bsdf.transmits(), wi, wi_l, ng)) {
                return None;
            }
            let f = bsdf.eval::<N>(wo_l, wi_l) * wi_l.z.abs();
            if f.is_black() {
                return None;
            }
            c.rays += 1;
            let w = power_heuristic(pdf_light, sel.pdf(bsdf, wo_l, wi_l));
            let e = *beta * f * Spectrum::from_rgb(le) * (w / pdf_light);
            Some((Ray::new(offset_origin(p, ng, wi), wi), f32::INFINITY, e))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::camera_ray;
    use crate::sampling::SamplerConfig;
    use crate::scene::Camera;

    /// Every sample of a small image, one path at a time and in batches of every length up
    /// to `BATCH_PATHS`, as bits.
    fn both_ways<const N: usize>(scene: &Scene, set: &IntegratorSettings) -> (Vec<u32>, Vec<u32>) {
        let (w, h, spp) = (12u32, 12u32, 4u32);
        let cam = Camera::new(scene.camera, w, h);
        let cfg = SamplerConfig {
            seed: 5,
            ..Default::default()
        };
        let lt = LTilde::Scene(Spectrum::<N>::splat(0.05));
        let jobs: Vec<(u32, u32, u32)> = (0..w * h)
            .flat_map(|p| (0..spp).map(move |i| (p % w, p / w, i)))
            .collect();
        let stream = |&(x, y, i): &(u32, u32, u32)| SampleStream::new(&cfg, 0, y * w + x, i as u64);
        let bits = |v: Spectrum<N>| v.to_rgb().map(f32::to_bits);
        let mut c = Counters::default();
        let one: Vec<u32> = jobs
            .iter()
            .flat_map(|j| {
                let mut s = stream(j);
                let ray = camera_ray(&cam, j.0, j.1, &mut s);
                bits(radiance::<N>(scene, ray, &mut s, set, &lt, &mut c))
            })
            .collect();
        let mut c2 = Counters::default();
        let mut batched = Vec::new();
        let (mut at, mut len) = (0, 1);
        while at < jobs.len() {
            let chunk = &jobs[at..(at + len).min(jobs.len())];
            let mut streams: Vec<SampleStream> = chunk.iter().map(stream).collect();
            let rays: Vec<Ray> = chunk
                .iter()
                .zip(streams.iter_mut())
                .map(|(j, s)| camera_ray(&cam, j.0, j.1, s))
                .collect();
            let mut out = vec![Spectrum::<N>::ZERO; chunk.len()];
            let (r, s, o) = (&rays[..], &mut streams[..], &mut out[..]);
            if scene.plain_hits() {
                radiance_batch::<N, true>(scene, r, s, set, &lt, &mut c2, o);
            } else {
                radiance_batch::<N, false>(scene, r, s, set, &lt, &mut c2, o);
            }
            batched.extend(out.into_iter().flat_map(bits));
            at += chunk.len();
            len = len % BATCH_PATHS + 1;
        }
        assert_eq!((c.paths, c.rays), (c2.paths, c2.rays), "the same rays");
        (one, batched)
    }

    /// A Mitsuba scene of a lit diffuse sphere over a rough conductor, with `extra`
    /// shapes after them and the floor's BSDF wrapped by `wrap` (`{}`: the BSDF).
    fn xml_scene(wrap: &str, extra: &str) -> Scene {
        let floor = wrap.replace("{}", r#"<bsdf type="roughconductor"/>"#);
        let text = format!(
            r#"<scene version="3.0.0">
            <sensor type="perspective"><float name="fov" value="40"/>
                <transform name="to_world"><lookat origin="0, -6, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
                <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/></film></sensor>
            <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="180"/><translate z="3"/></transform>
                <emitter type="area"><rgb name="radiance" value="20"/></emitter></shape>
            <shape type="sphere"><float name="radius" value="0.8"/><bsdf type="diffuse"/></shape>
            <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-0.8"/></transform>{floor}</shape>
            {extra}</scene>"#
        );
        let desc = crate::scene::mitsuba::parse(&text, "t.xml", std::path::Path::new(".")).unwrap();
        Scene::build(desc, 0.0).unwrap()
    }

    /// Which scenes take the batch without the instances', grids' and maps' work: those
    /// of their own triangles without normal or bump maps, not one with a normal map or
    /// with an instance.
    #[test]
    fn plain_hits_are_the_scenes_without_instances_or_maps() {
        assert!(crate::scene::load("cornell").unwrap().plain_hits());
        assert!(xml_scene("{}", "").plain_hits());
        let map = r#"<bsdf type="normalmap"><texture name="normalmap" type="rawconstant">
            <vector name="value" value="0.8, 0.5, 0.9"/></texture>{}</bsdf>"#;
        assert!(!xml_scene(map, "").plain_hits());
        let group = r#"<shape type="shapegroup" id="g"><shape type="cube">
            <transform name="to_world"><scale value="0.3"/><translate x="1.5"/></transform></shape></shape>
            <shape type="instance"><ref id="g"/></shape>"#;
        assert!(!xml_scene("{}", group).plain_hits());
    }

    /// The batch of a plain scene (`PLAIN`) is the general batch, bit for bit, and the
    /// general batch of scenes with a normal map or an instance is their paths one at a
    /// time.
    #[test]
    fn the_plain_batch_is_the_general_batch_bit_for_bit() {
        let set = IntegratorSettings {
            max_depth: 8,
            ..Default::default()
        };
        let image = |scene: &Scene, plain: bool| {
            let (w, h) = (12u32, 12u32);
            let cam = Camera::new(scene.camera, w, h);
            let cfg = SamplerConfig::default();
            let lt = LTilde::Scene(Spectrum::<3>::splat(0.05));
            let mut c = Counters::default();
            let mut bits = Vec::new();
            for y in 0..h {
                for x0 in (0..w).step_by(4) {
                    let mut streams: Vec<SampleStream> = (0..BATCH_PATHS as u32)
                        .map(|i| SampleStream::new(&cfg, 0, y * w + x0 + i % 4, (i / 4) as u64))
                        .collect();
                    let rays: Vec<Ray> = streams
                        .iter_mut()
                        .enumerate()
                        .map(|(i, s)| camera_ray(&cam, x0 + i as u32 % 4, y, s))
                        .collect();
                    let mut out = vec![Spectrum::<3>::ZERO; rays.len()];
                    let (r, s, o) = (&rays[..], &mut streams[..], &mut out[..]);
                    if plain {
                        radiance_batch::<3, true>(scene, r, s, &set, &lt, &mut c, o);
                    } else {
                        radiance_batch::<3, false>(scene, r, s, &set, &lt, &mut c, o);
                    }
                    bits.extend(out.iter().flat_map(|v| v.to_rgb().map(f32::to_bits)));
                }
            }
            bits
        };
        for scene in [crate::scene::load("cornell").unwrap(), xml_scene("{}", "")] {
            let general = image(&scene, false);
            assert!(general.iter().any(|&v| v != 0), "a black image");
            assert!(image(&scene, true) == general, "the plain batch differs");
        }
        let map = r#"<bsdf type="normalmap"><texture name="normalmap" type="rawconstant">
            <vector name="value" value="0.8, 0.5, 0.9"/></texture>{}</bsdf>"#;
        let group = r#"<shape type="shapegroup" id="g"><shape type="cube">
            <transform name="to_world"><scale value="0.3"/><translate x="1.5"/></transform></shape></shape>
            <shape type="instance"><ref id="g"/></shape>"#;
        for scene in [xml_scene(map, ""), xml_scene("{}", group)] {
            assert!(!scene.plain_hits());
            for n in [3, 8] {
                let (a, b) = if n == 3 {
                    both_ways::<3>(&scene, &set)
                } else {
                    both_ways::<8>(&scene, &set)
                };
                assert!(a.iter().any(|&v| v != 0), "a black image");
                assert!(a == b, "batched paths differ ({n} bands)");
            }
        }
    }

    #[test]
    fn batched_paths_are_the_paths_one_at_a_time_bit_for_bit() {
        let xml = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/mitsuba/spheres-envmap.xml"
        );
        for (name, interleaved) in [
            ("cornell-glossy", false),
            ("cornell-glossy", true),
            ("caustic", false),
            ("furnace-glossy", true),
            (xml, false),
        ] {
            let mut scene = crate::scene::load(name).unwrap();
            // A batch's queries one after another or interleaved (small trees answer them
            // the first way, large ones the second).
            scene.bvh.set_interleaving(Some(interleaved));
            use crate::integrator::rr::RrMode;
            for rr in [RrMode::Off, RrMode::Classic, RrMode::SpectralEstimate] {
                let mut set = IntegratorSettings::default();
                set.roulette.mode = rr;
                if rr == RrMode::Off {
                    set.max_depth = 8;
                }
                let (a, b) = both_ways::<3>(&scene, &set);
                assert!(a.iter().any(|&v| v != 0), "{name}: a black image");
                assert!(
                    a == b,
                    "{name}, roulette {rr:?}: batched paths differ (RGB)"
                );
                let (a, b) = both_ways::<8>(&scene, &set);
                assert!(
                    a == b,
                    "{name}, roulette {rr:?}: batched paths differ (8 bands)"
                );
            }
        }
    }
}
