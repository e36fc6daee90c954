//! Monte Carlo path tracing with a radiosity preprocess (Rushmeier and Ward 1994,
//! section 4.1; the progressive multi-pass method of Chen et al. 1991 without its light
//! ray pass): camera paths are traced as in `path.rs` (NEE + MIS, roulette from `rr`),
//! but where a path leaves a diffuse-like surface for indirect light, the incident
//! radiance of the diffuse lobe is looked up in the radiosity solution at the next
//! diffuse-like hit instead of recursing. Specular and glossy lobes keep tracing, so
//! caustic paths (diffuse -> mirror/glass -> emitter) are followed in the indirect
//! integral: the noise the energy-preserving filter (`filter::energy`) is for.
//!
//! Where the lookup starts (`gather_depth`, the paper's default 1): at the
//! `gather_depth`-th diffuse-like vertex of the path (one with a diffuse lobe, Kd > 0),
//! counted from the camera. Before it, diffuse bounces are traced as in `path.rs`.
//!
//! At a gather vertex x the BSDF-sampled direction wi (one sample of the mixture, weight
//! W = f cos / p) is split by lobe: W_d = W f_d / f (diffuse) and W_g = W - W_d (glossy).
//! The path goes on with the throughput beta W_g, and beta W_d waits (`beta_d`) for the
//! next hit y along wi, through any chain of mirrors and glass:
//!
//! - Direct light at x is counted once, by the path tracer's own MIS: NEE at x with the
//!   power heuristic against the full BSDF's density, and the emission of y (if wi hits an
//!   emitter) with the complementary weight, for both beta and beta_d. After a mirror or
//!   glass (a delta bounce) the emission gets weight 1: the caustic paths.
//! - The lookup at y adds beta_d (B(y) - E(y)) / pi: only the radiance y reflects, never
//!   its emission E (already counted above), so an emitter hit by the diffuse bounce does
//!   not add its emission again. B - E includes y's direct light: that is indirect light
//!   for x, which NEE at x does not give.
//! - y must have a solution (a meshed, diffuse-like triangle). A purely glossy y (Kd = 0)
//!   has none: the waiting part joins the traced path there. A black y reflects nothing.
//!
//! The lookup stands for paths of more segments than the one reaching y, so it is made
//! only while the segment count is below `max_depth`.
//!
//! Gather rays (`gather_rays` K, default [`DEFAULT_GATHER_RAYS`]; 1 is the paper's one
//! path per trial, as above). With K > 1 the diffuse lobe at the gather vertex x is
//! estimated on its own by K rays, as the final gather of Chen et al.'s multi-pass method:
//! (1/K) sum_j beta f_d cos / p_d L_in(wi_j), wi_j cosine-distributed over a randomly
//! shifted lattice ((u + j/K), (v + j phi) mod 1, phi the golden ratio's conjugate), each
//! ray followed through mirrors and glass to its lookup (`incident`). Emitters those rays
//! hit directly get the weight 1 - w_NEE, w_NEE the power heuristic NEE at x gave that
//! direction (against the full BSDF's density), so the weights of the two strategies still
//! sum to 1 for every direction. The traced path goes on with the glossy part W_g only
//! (a purely diffuse x ends there), and the roulette plays on that continuation: the
//! gather's rays are never rouletted at x. Why K > 1: on `rw-room` the gather's noise is
//! almost all in the first-bounce hemisphere (direct light from NEE has 0.3% of its
//! variance, 128x128, 256 spp), and a gather ray costs one ray and one lookup against the
//! camera ray, shadow ray and sampler work every trial pays (docs/results/rushmeier-ward.md).
//!
//! The control variate (`Gather::Correction` returns it less the lookup, for
//! `pipeline::rw_bias`): the path goes on whole from the gather vertex x as in `path.rs`
//! (its throughput beta W, emission and NEE as there), the gather rays bring only the
//! solution's lookups (their emission and glossy continuations left to the path), and the
//! path's own lookup at the first diffuse-like hit y along its direction, beta W_d (B - E)/pi
//! with W_d = W f_d / f, is taken out. The rays' lookups estimate the integral of the
//! solution's reflected light over x's diffuse lobe, the path's lookup the same integral
//! with the path's density: they cancel in the mean, so the estimate is the path tracer's,
//! unbiased whatever the solution's error. It gathers at the `gather_depth`-th diffuse
//! vertex only.
//!
//! Known approximations of the lookup, both of the radiosity solution: B reflects a receiver
//! y's light as if diffusely (a diffuse + Phong y carries its Phong lobe's albedo, so the
//! power is right and only its direction is averaged; other glossy materials are not
//! meshed); and B is the mesh's interpolation. Both biases fall with glossiness and element
//! size. BRDF lobe selection
//! must be `Mixture`, `Static` or `Mis` (their weights are proportional to f, so the split
//! by f_d / f is exact); `Decompose` (W_i = w_i / p_i) is not split correctly.
//!
//! `preview` renders the solution directly: emitters, plus B/pi (precisely L_e + (B-E)/pi)
//! at the first non-specular hit, mirrors and glass followed.

use super::camera_ray;
use super::path::{emission, DIMS_CAMERA, DIMS_PER_BOUNCE};
use super::rr::{LTilde, Selection, Step};
use super::{Counters, IntegratorSettings};
use crate::material::Bsdf;
use crate::math::{offset_origin, Frame, Ray, Vec3};
use crate::radiosity::Solution;
use crate::sampling::SampleStream;
use crate::scene::{Scene, Shading};
use crate::spectrum::Spectrum;
use glam::Vec2;

/// The gather's depth unless `--gather-depth` says or `--method rw` chooses it (the paper's
/// first diffuse bounce).
pub const DEFAULT_GATHER_DEPTH: u32 = 1;
/// Gather rays per gather vertex unless `--gather-rays` says (measured: docs/results/rushmeier-ward.md).
pub const DEFAULT_GATHER_RAYS: u32 = 2;
/// More gather rays than this are refused.
pub const MAX_GATHER_RAYS: u32 = 4096;
/// The conjugate of the golden ratio: the second coordinate of the gather's lattice.
const PHI_CONJUGATE: f32 = 0.618_034;
/// Salt of the gather rays' own random streams.
const GATHER_SALT: u64 = 0x6761_7468_6572_0000;

/// Indirect diffuse light from a radiosity solution (`--gather`).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Gather {
    /// Trace every bounce (plain path tracing).
    #[default]
    Off,
    /// Rushmeier and Ward: look up the diffuse indirect light in the radiosity solution.
    Radiosity,
    /// The lookup's error, sample by sample (the pipeline's bias correction, not a
    /// user's choice): the control-variate estimate (module doc) less the lookup's, both
    /// from the same random numbers. Its mean is minus the lookup's bias.
    #[value(skip)]
    #[serde(skip)]
    Correction,
}

impl Gather {
    /// Whether the gather reads a radiosity solution.
    #[inline]
    pub fn reads_solution(self) -> bool {
        self != Gather::Off
    }

    /// The gather a method takes when no `--gather` is given: the radiosity gather for
    /// Rushmeier and Ward's method (`rw`) where the solution can be made (the path tracer,
    /// area lights only, a selection the gather can split), else off.
    pub fn default_for(rw: bool, set: &IntegratorSettings, scene: &Scene) -> Gather {
        let usable = set.kind == super::IntegratorKind::Path
            && !scene.lights.has_distant()
            && set.roulette.select != super::BsdfSelect::Decompose;
        if rw && usable {
            Gather::Radiosity
        } else {
            Gather::Off
        }
    }
}

/// Whether a BSDF has a diffuse lobe that reflects anything.
#[inline]
fn has_diffuse(bsdf: &Bsdf) -> bool {
    match bsdf {
        Bsdf::Diffuse(l) | Bsdf::DiffuseGlossy(l, _) => l.kd.iter().any(|&k| k > 0.0),
        _ => false,
    }
}

/// Radiance arriving along `ray` (one sample), diffuse indirect light from `sol`; with
/// [`Gather::Correction`] the control variate's estimate less the lookup's.
#[allow(clippy::too_many_arguments)]
pub fn radiance<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    ray: Ray,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    gather_depth: u32,
    l_tilde: &LTilde<N>,
    c: &mut Counters,
) -> Spectrum<N> {
    // (the light seen directly is not asked for here)
    let mut seen = Spectrum::ZERO;
    let mut one = |s: &mut SampleStream, cv: bool, c: &mut Counters| {
        estimate(
            scene,
            sol,
            ray,
            s,
            set,
            gather_depth,
            l_tilde,
            cv,
            &mut seen,
            c,
        )
    };
    if set.gather != Gather::Correction {
        return one(s, false, c);
    }
    let mut s_lookup = *s;
    let lookup = one(&mut s_lookup, false, c);
    c.paths -= 1;
    one(s, true, c) - lookup
}

/// One sample of the lookup and, from the same path, the light it sees directly: the
/// emission its camera ray reaches through mirrors and glass only (the branch the path
/// took at glass, so its mean is `visible::emission`'s, which the split needs no more: the
/// two parts sum to the sample whatever the second is). Saves tracing the camera ray twice.
#[allow(clippy::too_many_arguments)]
pub fn radiance_split<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    ray: Ray,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    gather_depth: u32,
    l_tilde: &LTilde<N>,
    c: &mut Counters,
) -> (Spectrum<N>, Spectrum<N>) {
    debug_assert!(
        set.gather == Gather::Radiosity,
        "the split is of the lookup's samples"
    );
    let mut seen = Spectrum::ZERO;
    let l = estimate(
        scene,
        sol,
        ray,
        s,
        set,
        gather_depth,
        l_tilde,
        false,
        &mut seen,
        c,
    );
    (l, seen)
}

/// One sample of the lookup (`cv` false) or of the control variate (`cv` true): the
/// traced path goes on whole from the gather vertex, its own lookup along its direction
/// is taken out and the gather rays' lookups (the solution's integral there, without
/// emission) put in; unbiased whatever the solution's error.
#[allow(clippy::too_many_arguments)]
fn estimate<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    mut ray: Ray,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    gather_depth: u32,
    l_tilde: &LTilde<N>,
    cv: bool,
    seen: &mut Spectrum<N>,
    c: &mut Counters,
) -> Spectrum<N> {
    let mut l = Spectrum::<N>::ZERO;
    // whether every vertex so far was a mirror or glass: emission now is seen directly
    let mut direct = true;
    // traced throughput, and the diffuse part waiting for its lookup
    let mut beta = Spectrum::<N>::ONE;
    let mut beta_d = Spectrum::<N>::ZERO;
    let mut prev_pdf = 0.0f32;
    let mut prev_delta = true;
    let max_segments = set.max_segments();
    let mut segments = 0u32;
    let mut diffuse_vertices = 0u32;
    let rr = &set.roulette;
    // (with the control variate beta_d is minus the lookup's weight)
    c.paths += 1;
    loop {
        c.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            break;
        };
        segments += 1;
        let mat = scene.material_of(hit.prim);
        let wo = -ray.d;
        let front = wo.dot(hit.ng) > 0.0;

        // Emission, MIS-weighted against NEE, for the traced and the waiting parts.
        // (with the control variate only the traced part: the lookup is reflected light)
        if let Some((le, w)) = emission::<N>(scene, mat, &hit, wo, prev_pdf, prev_delta) {
            let e = if cv { beta } else { beta + beta_d } * le * w;
            l += e;
            if direct {
                *seen += e;
            }
        }

        let bsdf = scene.bsdf_at(mat, &hit, wo);
        direct &= bsdf.is_delta();

        // The waiting diffuse part: (B - E)/pi at the first diffuse-like hit.
        if !beta_d.is_black() && !bsdf.is_delta() {
            if sol.covers(hit.prim) && has_diffuse(&bsdf) {
                if segments < max_segments {
                    if let Some(r) = sol.reflected::<N>(hit.prim, hit.p, front) {
                        l += beta_d * r;
                    }
                }
            } else if !cv {
                // purely glossy: trace its reflection with the rest of the path
                beta += beta_d;
            }
            beta_d = Spectrum::ZERO;
        } else if bsdf == Bsdf::Black {
            beta_d = Spectrum::ZERO;
        }
        if segments >= max_segments || (beta.is_black() && beta_d.is_black()) {
            break;
        }

        let Shading { ng, frame, .. } = Shading::new(hit.ng, hit.ns, bsdf.is_two_sided() && !front);
        let wo_l = frame.to_local(wo);

        s.set_dimension(DIMS_CAMERA + (segments - 1) * DIMS_PER_BOUNCE);
        let u_sel = s.next_1d();
        let u_light = s.next_2d();
        let u_lobe = s.next_1d();
        let u_bsdf = s.next_2d();
        let u_rr = s.next_1d();

        // Is this the vertex where the diffuse lobe switches to the lookup?
        let diffuse = has_diffuse(&bsdf);
        if diffuse {
            diffuse_vertices += 1;
        }
        // (the control variate's path goes on whole: it gathers at that vertex only)
        let gather = diffuse
            && if cv {
                diffuse_vertices == gather_depth.max(1)
            } else {
                diffuse_vertices >= gather_depth.max(1)
            };

        // The roulette sees the whole throughput (beta_d is carried only through delta
        // vertices, where it is not black; with the control variate the traced path).
        let f_total = if cv { beta } else { beta + beta_d };
        let sel = rr.select::<N>(segments - 1, &f_total, &bsdf);

        // Next-event estimation (beta_d is black at non-delta vertices).
        if !bsdf.is_delta() {
            if let Some((r, t_max, e)) = super::path::next_event::<N>(
                scene, hit.p, ng, &frame, wo_l, &bsdf, &sel, u_sel, u_light, &beta, c,
            ) {
                if !scene.occluded(&r, t_max) {
                    l += e;
                }
            }
        }

        // K gather rays: the diffuse lobe estimated on its own, never rouletted (with the
        // control variate: the lookups only, the solution's integral)
        let split = gather && (cv || set.gather_rays > 1);
        if split {
            l += gather_rays::<N>(
                scene, sol, hit.p, ng, &frame, wo_l, &bsdf, &sel, &f_total, u_bsdf, segments, set,
                cv, s, c,
            );
            if !cv && bsdf.lobe_array().1 < 2 {
                break;
            }
        }

        let step = sel.sample::<N>(&bsdf, wo_l, u_lobe, u_bsdf, u_rr);
        let terminated = matches!(step, Step::Terminated);
        let lt = || l_tilde.at_hit(&hit, front);
        if let Some(e) = rr.estimate_term(&sel, &bsdf, terminated, &f_total, lt) {
            l += e;
        }
        let Step::Continue { sample: bs, scale } = step else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        if (wi.dot(ng) > 0.0) != (bs.wi.z > 0.0) {
            break;
        }
        let mut w = bs.weight;
        if scale != 1.0 {
            w *= scale;
        }
        if gather {
            // split W by lobe: W_d = W f_d / f waits for the lookup, W_g goes on
            let (lobes, _) = bsdf.lobe_array();
            let f_d = lobes[0].eval::<N>(wo_l, bs.wi);
            let f = bsdf.eval::<N>(wo_l, bs.wi);
            let mut wd = Spectrum::<N>::ZERO;
            for k in 0..N {
                if f[k] > 0.0 {
                    wd[k] = w[k] * (f_d[k] / f[k]).min(1.0);
                }
            }
            if cv {
                // the path goes on whole; its own lookup waits to be taken out
                beta_d = f_total * wd * -1.0;
                beta = f_total * w;
            } else {
                // (with K gather rays the diffuse part was estimated above)
                beta_d = if split { Spectrum::ZERO } else { f_total * wd };
                beta = f_total * (w - wd);
            }
        } else {
            beta *= w;
            beta_d *= w;
        }
        if beta.is_black() && beta_d.is_black() {
            break;
        }
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        ray = Ray::new(offset_origin(hit.p, ng, wi), wi);
    }
    l
}

/// The diffuse lobe at gather vertex `p` estimated by K = `set.gather_rays` rays:
/// (1/K) sum_j beta f_d cos / p_d L_in(wi_j) (module doc), `u0` the lattice's shift.
#[allow(clippy::too_many_arguments)]
fn gather_rays<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    p: Vec3,
    ng: Vec3,
    frame: &Frame,
    wo_l: Vec3,
    bsdf: &Bsdf,
    sel: &Selection,
    beta: &Spectrum<N>,
    u0: Vec2,
    segments: u32,
    set: &IntegratorSettings,
    cv: bool,
    s: &SampleStream,
    c: &mut Counters,
) -> Spectrum<N> {
    let k = set.gather_rays.max(1);
    let inv_k = 1.0 / k as f32;
    let diffuse = bsdf.lobe_array().0[0];
    let mut l = Spectrum::<N>::ZERO;
    for j in 0..k {
        let u = Vec2::new(
            (u0.x + j as f32 * inv_k).fract(),
            (u0.y + j as f32 * PHI_CONJUGATE).fract(),
        );
        let Some(wi_l) = diffuse.sample_dir(wo_l, u) else {
            continue;
        };
        let wi = frame.to_world(wi_l);
        let pdf_d = diffuse.pdf(wo_l, wi_l);
        if (wi.dot(ng) > 0.0) != (wi_l.z > 0.0) || pdf_d <= 0.0 {
            continue;
        }
        let w = diffuse.eval::<N>(wo_l, wi_l) * (wi_l.z.abs() / pdf_d);
        let mut sj = s.decorrelated(GATHER_SALT ^ ((segments as u64) << 32 | j as u64));
        let ray = Ray::new(offset_origin(p, ng, wi), wi);
        let pdf_mis = sel.pdf(bsdf, wo_l, wi_l);
        l += incident::<N>(
            scene,
            sol,
            ray,
            *beta * w,
            pdf_mis,
            segments,
            set,
            cv,
            &mut sj,
            c,
        );
    }
    l * inv_k
}

/// What one gather ray brings, with its throughput `thr`: the emission of what it hits
/// (MIS-weighted against NEE at its origin with the BSDF density `pdf_x` there, weight 1
/// after a mirror or glass), then (B - E)/pi at the first diffuse-like hit; at a purely
/// glossy hit the rest is traced as in `path.rs`. Mirrors and glass are followed, with
/// the roulette. `segments`: the path's segments before this ray.
#[allow(clippy::too_many_arguments)]
fn incident<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    mut ray: Ray,
    mut thr: Spectrum<N>,
    pdf_x: f32,
    mut segments: u32,
    set: &IntegratorSettings,
    cv: bool,
    s: &mut SampleStream,
    c: &mut Counters,
) -> Spectrum<N> {
    let mut l = Spectrum::<N>::ZERO;
    let mut prev_delta = false;
    let max_segments = set.max_segments();
    loop {
        c.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            break;
        };
        segments += 1;
        let mat = scene.material_of(hit.prim);
        let wo = -ray.d;
        let front = wo.dot(hit.ng) > 0.0;
        let mut le = Spectrum::<N>::ZERO;
        if let Some((e, w)) = emission::<N>(scene, mat, &hit, wo, pdf_x, prev_delta) {
            le = e;
            // (the control variate's rays bring the lookup only: the path brings light)
            if !cv {
                l += thr * le * w;
            }
        }
        let bsdf = scene.bsdf_at(mat, &hit, wo);
        if !bsdf.is_delta() {
            if segments < max_segments {
                if sol.covers(hit.prim) && has_diffuse(&bsdf) {
                    if let Some(r) = sol.reflected::<N>(hit.prim, hit.p, front) {
                        l += thr * r;
                    }
                } else if !cv && bsdf != Bsdf::Black {
                    // purely glossy: traced from here (its emission, counted above, taken out)
                    let mut rest = *set;
                    if rest.max_depth >= 0 {
                        rest.max_depth -= segments as i32 - 1;
                    }
                    let lp = super::path::radiance::<N>(
                        scene,
                        ray,
                        s,
                        &rest,
                        &LTilde::Scene(Spectrum::ZERO),
                        c,
                    );
                    l += thr * (lp - le);
                }
            }
            break;
        }
        if segments >= max_segments {
            break;
        }
        // a mirror or glass: follow the sampled specular direction
        let Shading { ng, frame, .. } = Shading::new(hit.ng, hit.ns, bsdf.is_two_sided() && !front);
        let wo_l = frame.to_local(wo);
        let sel = set.roulette.select::<N>(segments - 1, &thr, &bsdf);
        let u_lobe = s.next_1d();
        let u = s.next_2d();
        let u_rr = s.next_1d();
        let Step::Continue { sample: bs, scale } = sel.sample::<N>(&bsdf, wo_l, u_lobe, u, u_rr)
        else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        if (wi.dot(ng) > 0.0) != (bs.wi.z > 0.0) {
            break;
        }
        thr *= bs.weight * scale;
        if thr.is_black() {
            break;
        }
        prev_delta = bs.delta;
        ray = Ray::new(offset_origin(hit.p, ng, wi), wi);
    }
    l
}

/// The solution rendered directly: L_e + (B - E)/pi at the first non-specular hit
/// (B/pi on a Lambertian emitter), mirrors and glass followed (at most `max_segments`).
pub fn preview<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    mut ray: Ray,
    s: &mut SampleStream,
    max_segments: u32,
    c: &mut Counters,
) -> Spectrum<N> {
    let mut l = Spectrum::<N>::ZERO;
    let mut beta = Spectrum::<N>::ONE;
    c.paths += 1;
    for segment in 0..max_segments.max(1) {
        c.rays += 1;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            break;
        };
        let mat = scene.material_of(hit.prim);
        let wo = -ray.d;
        let front = wo.dot(hit.ng) > 0.0;
        if mat.is_emissive() && front {
            l += beta * Spectrum::<N>::from_rgb(mat.emitted_at(wo.dot(hit.ng), hit.uv));
        }
        let bsdf = &mat.bsdf;
        if !bsdf.is_delta() || *bsdf == Bsdf::Black {
            if let Some(r) = sol.reflected::<N>(hit.prim, hit.p, front) {
                l += beta * r;
            }
            break;
        }
        // mirror or glass: follow the sampled specular direction
        let Shading { ng, frame, .. } = Shading::new(hit.ng, hit.ns, bsdf.is_two_sided() && !front);
        s.set_dimension(DIMS_CAMERA + segment * DIMS_PER_BOUNCE + 3);
        let u_lobe = s.next_1d();
        let u = s.next_2d();
        let Some(bs) = bsdf.sample::<N>(frame.to_local(wo), u_lobe, u) else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        beta *= bs.weight;
        if beta.is_black() {
            break;
        }
        ray = Ray::new(offset_origin(hit.p, ng, wi), wi);
    }
    l
}

/// One gather sample of pixel (x, y): linear RGB.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn sample_pixel<const N: usize>(
    scene: &Scene,
    sol: &Solution,
    cam: &crate::scene::Camera,
    x: u32,
    y: u32,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    gather_depth: u32,
    c: &mut Counters,
) -> [f32; 3] {
    let ray = camera_ray(cam, x, y, s);
    radiance::<N>(
        scene,
        sol,
        ray,
        s,
        set,
        gather_depth,
        &LTilde::Scene(Spectrum::ZERO),
        c,
    )
    .to_rgb()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::PixelStats;
    use crate::radiosity::RadiositySettings;
    use crate::sampling::SamplerConfig;
    use crate::scene::Camera;

    /// A tiny image: per-pixel statistics of `spp` samples of `f`.
    fn render(
        scene: &Scene,
        w: u32,
        h: u32,
        spp: u32,
        f: &dyn Fn(Ray, &mut SampleStream, &mut Counters) -> [f32; 3],
    ) -> Vec<PixelStats> {
        let cam = Camera::new(scene.camera, w, h);
        let cfg = SamplerConfig {
            seed: 3,
            ..Default::default()
        };
        let mut px = vec![PixelStats::default(); (w * h) as usize];
        let mut c = Counters::default();
        for y in 0..h {
            for x in 0..w {
                let p = y * w + x;
                for i in 0..spp {
                    let mut s = SampleStream::new(&cfg, 0, p, i as u64);
                    let ray = camera_ray(&cam, x, y, &mut s);
                    px[p as usize].push(f(ray, &mut s, &mut c));
                }
            }
        }
        px
    }

    /// One gather sample along `ray` (no roulette estimate), linear RGB.
    fn gather_rgb(
        scene: &Scene,
        sol: &Solution,
        ray: Ray,
        s: &mut SampleStream,
        set: &IntegratorSettings,
        depth: u32,
        c: &mut Counters,
    ) -> [f32; 3] {
        radiance::<3>(
            scene,
            sol,
            ray,
            s,
            set,
            depth,
            &LTilde::Scene(Spectrum::ZERO),
            c,
        )
        .to_rgb()
    }

    /// Image mean per channel and its standard error (pixels independent).
    fn mean_se(px: &[PixelStats]) -> ([f64; 3], [f64; 3]) {
        let n = px.len() as f64;
        let mut m = [0.0; 3];
        let mut v = [0.0; 3];
        for p in px {
            let vm = p.variance_of_mean();
            for c in 0..3 {
                m[c] += p.mean()[c] / n;
                v[c] += vm[c] / (n * n);
            }
        }
        (m, v.map(f64::sqrt))
    }

    fn furnace_solution(scene: &Scene) -> Solution {
        let set = RadiositySettings {
            max_area: Some(2.0 / 64.0),
            ..Default::default()
        };
        Solution::compute(scene, &set, 3, &crate::progress::Silent).unwrap()
    }

    #[test]
    fn gather_on_furnace_is_one() {
        let scene = crate::scene::load("furnace").unwrap();
        let sol = furnace_solution(&scene);
        for (depth, rays) in [(1, 1), (2, 1), (1, 8), (2, 3)] {
            let set = IntegratorSettings {
                gather_rays: rays,
                ..Default::default()
            };
            let px = render(&scene, 16, 16, 64, &|ray, s, c| {
                gather_rgb(&scene, &sol, ray, s, &set, depth, c)
            });
            let (m, se) = mean_se(&px);
            println!("gather depth {depth}, {rays} rays: mean {m:?} se {se:?}");
            for c in 0..3 {
                // 4 standard errors plus the solution's own 0.5%
                assert!(
                    (m[c] - 1.0).abs() <= 4.0 * se[c] + 0.005,
                    "depth {depth} channel {c}: {} (se {})",
                    m[c],
                    se[c]
                );
            }
        }
    }

    #[test]
    fn preview_on_furnace_is_one() {
        let scene = crate::scene::load("furnace").unwrap();
        let sol = furnace_solution(&scene);
        let px = render(&scene, 16, 16, 1, &|ray, s, c| {
            preview::<3>(&scene, &sol, ray, s, 16, c).to_rgb()
        });
        for p in &px {
            for c in 0..3 {
                assert!((p.mean()[c] - 1.0).abs() < 0.005, "{:?}", p.mean());
            }
        }
    }

    /// Per block of 4x4 pixels and channel: the mean and its variance (pixels independent).
    fn block_means(px: &[PixelStats], w: usize) -> Vec<(f64, f64)> {
        let h = px.len() / w;
        let mut out = Vec::new();
        for by in (0..h).step_by(4) {
            for bx in (0..w).step_by(4) {
                for c in 0..3 {
                    let (mut m, mut v) = (0.0, 0.0);
                    for y in by..by + 4 {
                        for x in bx..bx + 4 {
                            let p = &px[y * w + x];
                            m += p.mean()[c] / 16.0;
                            v += p.variance_of_mean()[c] / 256.0;
                        }
                    }
                    out.push((m, v));
                }
            }
        }
        out
    }

    /// K gather rays and the paper's one estimate the same image: block means of K = 1
    /// and K = 8 agree (z-test) on scenes whose gather rays go through glass and mirrors
    /// (`caustic`) and reach glossy surfaces (`cornell-glossy`).
    #[test]
    fn gather_rays_agree_with_one_ray() {
        for name in ["caustic", "cornell-glossy"] {
            let scene = crate::scene::load(name).unwrap();
            let rset = RadiositySettings {
                max_area: Some(0.2),
                tolerance: 1e-2,
                source_level: 0,
                ..Default::default()
            };
            let sol = Solution::compute(&scene, &rset, 3, &crate::progress::Silent).unwrap();
            let run = |rays: u32| {
                let set = IntegratorSettings {
                    gather_rays: rays,
                    ..Default::default()
                };
                let px = render(&scene, 16, 16, 96, &|ray, s, c| {
                    gather_rgb(&scene, &sol, ray, s, &set, 1, c)
                });
                block_means(&px, 16)
            };
            let (a, b) = (run(1), run(8));
            let worst = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x.0 - y.0).abs() / (x.1 + y.1).sqrt().max(1e-12))
                .fold(0.0f64, f64::max);
            println!(
                "{name}: largest |z| over {} block means: {worst:.2}",
                a.len()
            );
            assert!(
                worst < 4.5,
                "{name}: K = 1 and K = 8 differ, |z| = {worst:.2}"
            );
        }
    }

    /// Cornell: the gather's image mean agrees with plain path tracing within a few
    /// percent (a double count of direct light would add tens of percent).
    #[test]
    fn gather_on_cornell_counts_direct_light_once() {
        let scene = crate::scene::load("cornell").unwrap();
        let rset = RadiositySettings {
            max_area: Some(0.1),
            tolerance: 1e-2,
            ..Default::default()
        };
        let sol = Solution::compute(&scene, &rset, 3, &crate::progress::Silent).unwrap();
        let set = IntegratorSettings::default();
        let p = render(&scene, 24, 24, 64, &|ray, s, c| {
            super::super::path::radiance::<3>(
                &scene,
                ray,
                s,
                &set,
                &LTilde::Scene(Spectrum::ZERO),
                c,
            )
            .to_rgb()
        });
        let (mp, sp) = mean_se(&p);
        for rays in [1, 8] {
            let set = IntegratorSettings {
                gather_rays: rays,
                ..Default::default()
            };
            let g = render(&scene, 24, 24, 64, &|ray, s, c| {
                gather_rgb(&scene, &sol, ray, s, &set, 1, c)
            });
            let (mg, sg) = mean_se(&g);
            println!("cornell gather ({rays} rays) {mg:?} se {sg:?}; path {mp:?} se {sp:?}");
            for c in 0..3 {
                let rel = (mg[c] - mp[c]).abs() / mp[c];
                assert!(rel < 0.05, "channel {c}: gather {} path {}", mg[c], mp[c]);
            }
        }
    }
}
