//! Bidirectional path tracing (Veach's thesis, chapter 10; Veach and Guibas 1995; the
//! structure follows pbrt-v4's `BDPTIntegrator`, written anew for kalos).
//!
//! One sample of a pixel traces a camera subpath y_0 .. y_{t-1} (y_0 the pinhole) and a
//! light subpath z_0 .. z_{s-1} (z_0 on an emitter, chosen by power, a cosine direction),
//! then evaluates every connection strategy (s, t):
//! - s = 0: the camera subpath itself ends on an emitter (y_{t-1} emits towards y_{t-2});
//! - s = 1: next-event estimation, a fresh light point connected to y_{t-1};
//! - t = 1: light tracing, z_{s-1} connected to the pinhole and splatted to the film
//!   position it lands on;
//! - otherwise z_{s-1} and y_{t-1} are joined by a visibility-tested edge.
//!
//! The strategies of one path length are combined by multiple importance sampling: the
//! balance heuristic (or the power heuristic, `MisHeuristic`) evaluated with Veach's ratio
//! recurrence (thesis 10.2.1) over the per-vertex area densities p_fwd (in the direction
//! the subpath was generated) and p_rev (in the opposite direction); Dirac vertices are
//! remapped as pbrt does (a density 0 counts as 1, strategies that would connect at a
//! Dirac vertex are left out of the sum).
//!
//! Adjoint transport (Veach 5.3): on the light subpath the BSDF sample weight is corrected
//! for shading normals, |w_o . n_s| |w_i . n_g| / (|w_o . n_g| |w_i . n_s|), and the
//! dielectrics' radiance scaling (eta_t / eta_i)^2 is undone on refractions (importance is
//! not scaled): the BSDFs' `sample` always carries radiance, `Bsdf::adjoint_scale` turns
//! a smooth or rough refraction's weight into importance. Connections evaluate f with the
//! radiance-side direction first, which is the path's own value (no correction there).
//! Rough dielectrics transmit (`Bsdf::transmits`): their vertices connect through the
//! surface too.
//!
//! Depth follows Mitsuba's max_depth on the full path: a path of s + t vertices has
//! s + t - 1 segments, allowed if <= max_depth. Russian roulette is `integrator::rr`'s on
//! both subpaths (F = beta of the subpath); the MIS densities leave the roulette out,
//! which keeps the weights of the strategies of a path summing to 1. The estimate roulette
//! is played here as its classic (or spectral) base: its L~ term has no meaning on a
//! bidirectional path.
//!
//! Cost: a sample evaluates O(s t) strategies of O(s + t) each, so without roulette and
//! without a max depth (subpaths of up to `HARD_MAX_DEPTH` vertices in a closed room) it
//! is impractical: use a roulette or `--max-depth` with `--rr off`.
//!
//! Every decision uses fixed dimensions of the `SampleStream` (see `dims`), so the result
//! is a pure function of the inputs: the same on any number of threads.

use super::rr::{RrMode, Step};
use super::{Counters, IntegratorSettings};
use crate::material::Bsdf;
use crate::math::{offset_origin, Frame, Ray, Vec2, Vec3};
use crate::sampling::SampleStream;
use crate::scene::{Camera, Scene, Shading};
use crate::spectrum::Spectrum;
use std::f32::consts::FRAC_1_PI;

/// Dimensions of the random stream: 0-1 the pixel jitter, 2-6 the light subpath's origin
/// (light choice, position, direction), then a block of `DIMS_PER_DEPTH` per vertex index
/// i >= 1: the camera subpath's reflection at y_i (lobe, 2 for the direction, roulette),
/// next-event estimation at y_i (light choice, position), the light subpath's reflection
/// at z_i (lobe, direction, roulette).
pub mod dims {
    pub const PIXEL: u32 = 0;
    pub const LIGHT_ORIGIN: u32 = 2;
    pub const BASE: u32 = 7;
    pub const PER_DEPTH: u32 = 12;
    pub const CAMERA_BOUNCE: u32 = 0;
    pub const NEE: u32 = 4;
    pub const LIGHT_BOUNCE: u32 = 8;
    #[inline]
    pub fn block(i: usize) -> u32 {
        BASE + (i as u32).saturating_sub(1).min(1 << 20) * PER_DEPTH
    }
}

/// How the strategies of a path length are weighed (`--bdpt-mis`).
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
pub enum MisHeuristic {
    /// Veach's balance heuristic.
    #[default]
    Balance,
    /// Exponent 2.
    Power,
}

/// Which strategies contribute (all, weighted, for rendering; the others for tests and
/// debugging).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Strategies {
    #[default]
    All,
    /// Light tracing alone: every (s, 1) unweighted, plus emitters seen directly (0, 2).
    LightTracing,
}

#[derive(Clone, Debug, PartialEq, Default)]
pub struct BdptOptions {
    pub heuristic: MisHeuristic,
    pub strategies: Strategies,
    /// Draw the light subpath from a stream of its own per pixel (`SampleStream::
    /// decorrelated` with the pixel), even when the sampler is dependent: DTF's dependent
    /// phase over BDPT shares only the camera subpath (and next-event points) between
    /// pixels. With the whole path shared, every pixel splats the same n light subpaths to
    /// the same n x (path length) pixels, and C_d's light-tracing share is n bright dots.
    pub light_per_pixel: bool,
    /// Light-tracing paths per camera sample, per pixel (K; None = 1 everywhere): the
    /// sample counts of Veach's multi-sample MIS when light subpaths are traced for light
    /// tracing alone besides the camera samples' own (`light_path_sample`).
    pub lt_ratio: Option<std::sync::Arc<LtRatio>>,
}

/// K[p], the light-tracing paths per camera sample in pixel p, for the MIS weights.
///
/// With L light paths splatting over a film of P pixels and N_p camera samples in pixel p,
/// the balance heuristic of a path through p weighs its light-tracing strategy (s, 1) with
/// n = L / P and every other strategy with n = N_p: relative to the camera strategies,
/// K_p = L / (P N_p) (1 when each camera sample brings one light subpath). Any K > 0 keeps
/// the weights of a path summing to 1, so the estimator is unbiased whatever K; the right
/// K only lowers its variance. Both kinds of samples must read the same K_p.
#[derive(Clone, Debug, PartialEq)]
pub struct LtRatio {
    pub width: u32,
    pub height: u32,
    pub k: Vec<f32>,
}

impl LtRatio {
    /// K of the pixel containing film position `r` (1 outside the film).
    #[inline]
    pub fn at(&self, r: Vec2) -> f32 {
        if !(r.x >= 0.0 && r.y >= 0.0) {
            return 1.0;
        }
        let (x, y) = (r.x as u32, r.y as u32);
        if x < self.width && y < self.height {
            self.k[(y * self.width + x) as usize]
        } else {
            1.0
        }
    }
}

/// Bounds of K (a pixel without camera samples would have K = infinity).
pub const LT_RATIO_MIN: f32 = 1.0 / 64.0;
pub const LT_RATIO_MAX: f32 = 64.0;

/// One strategy's contribution (the film's record of it: a sink's strategy layer).
pub use crate::film::StrategySample;

const NO_LIGHT: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Camera,
    Light,
    Surface,
}

/// A subpath vertex. Densities are per unit area (solid angle converted with the
/// geometric cosine at the vertex and the squared distance), 0 for Dirac samples.
#[derive(Clone, Debug)]
pub(crate) struct Vertex<const N: usize> {
    pub kind: Kind,
    pub p: Vec3,
    /// Geometric normal: a surface's from its winding (not flipped), an emitter's emitting
    /// side, the camera's view direction.
    pub ng: Vec3,
    /// Shading normal, in the hemisphere of `ng`.
    pub ns: Vec3,
    /// The (textured) BSDF of a surface vertex.
    pub bsdf: Bsdf,
    /// The light index if the vertex lies on an emitter.
    pub light: u32,
    /// Throughput of the subpath up to and including this vertex (Veach's alpha).
    pub beta: Spectrum<N>,
    /// The direction leaving this vertex was sampled from a Dirac lobe.
    pub delta: bool,
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
}

impl<const N: usize> Vertex<N> {
    fn camera(cam: &Camera) -> Self {
        Vertex {
            kind: Kind::Camera,
            p: cam.position(),
            ng: cam.forward(),
            ns: cam.forward(),
            bsdf: Bsdf::Black,
            light: NO_LIGHT,
            beta: Spectrum::ONE,
            delta: false,
            pdf_fwd: 1.0,
            pdf_rev: 0.0,
        }
    }

    fn light(p: Vec3, n: Vec3, light: u32, pdf_area: f32, beta: Spectrum<N>) -> Self {
        Vertex {
            kind: Kind::Light,
            p,
            ng: n,
            ns: n,
            bsdf: Bsdf::Black,
            light,
            beta,
            delta: false,
            pdf_fwd: pdf_area,
            pdf_rev: 0.0,
        }
    }

    #[inline]
    fn on_surface(&self) -> bool {
        self.kind != Kind::Camera
    }

    /// Can a connection edge end here (not a Dirac or black surface)?
    #[inline]
    fn connectible(&self) -> bool {
        match self.kind {
            Kind::Camera | Kind::Light => true,
            Kind::Surface => !self.bsdf.is_delta(),
        }
    }

    /// Solid-angle density `pdf` of leaving this vertex towards `next`, per unit area at
    /// `next`.
    #[inline]
    fn convert(&self, pdf: f32, next: &Vertex<N>) -> f32 {
        let d = next.p - self.p;
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let mut pdf = pdf / d2;
        if next.on_surface() {
            pdf *= next.ng.dot(d).abs() / d2.sqrt();
        }
        pdf
    }

    /// Normals (n_g, n_s) of a surface vertex, flipped towards `w` for two-sided BSDFs,
    /// and the shading frame.
    #[inline]
    fn oriented(&self, w: Vec3) -> (Vec3, Vec3, Frame) {
        let sh = Shading::toward(self.ng, self.ns, w, self.bsdf.is_two_sided());
        (sh.ng, sh.ns, sh.frame)
    }

    /// f(w_o, w_i) of a surface vertex, w_o towards the camera side, w_i towards the light
    /// side (unit vectors). As in the path tracer, both directions must be on the same side
    /// of the surface for its geometric and its shading normal.
    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3) -> Spectrum<N> {
        let (ng, _, frame) = self.oriented(wo);
        let (wo_l, wi_l) = (frame.to_local(wo), frame.to_local(wi));
        if self.bsdf.transmits() {
            // each direction on one side for both normals, either side of the surface
            let side = |w: Vec3, l: Vec3| (w.dot(ng) > 0.0) == (l.z > 0.0) && l.z != 0.0;
            if !(side(wo, wo_l) && side(wi, wi_l)) {
                return Spectrum::ZERO;
            }
            return self.bsdf.eval::<N>(wo_l, wi_l);
        }
        if wo.dot(ng) <= 0.0 || wi.dot(ng) <= 0.0 || wo_l.z <= 0.0 || wi_l.z <= 0.0 {
            return Spectrum::ZERO;
        }
        self.bsdf.eval::<N>(wo_l, wi_l)
    }

    /// Solid-angle density of the BSDF sampling `w_to` given the walk arrived from `w_from`.
    #[inline]
    fn pdf_dir(&self, w_from: Vec3, w_to: Vec3) -> f32 {
        if self.bsdf.is_delta() {
            return 0.0;
        }
        let (ng, _, frame) = self.oriented(w_from);
        if w_to.dot(ng) <= 0.0 && !self.bsdf.transmits() {
            return 0.0;
        }
        self.bsdf.pdf(frame.to_local(w_from), frame.to_local(w_to))
    }

    /// Area density at `next` of this vertex's sampling (pbrt's `Vertex::Pdf`): the camera
    /// ray's, the emission's, or the BSDF's given the walk came from `prev`.
    fn pdf(&self, cam: &Camera, prev: Option<&Vertex<N>>, next: &Vertex<N>) -> f32 {
        let wn = (next.p - self.p).normalize_or_zero();
        let pdf = match self.kind {
            Kind::Light => return self.pdf_light(next),
            Kind::Camera => cam.pdf_we(wn).1,
            Kind::Surface => {
                let Some(prev) = prev else {
                    return 0.0;
                };
                let wp = (prev.p - self.p).normalize_or_zero();
                self.pdf_dir(wp, wn)
            }
        };
        self.convert(pdf, next)
    }

    /// Area density at `next` of emission sampling from this point of an emitter: the
    /// cosine-weighted direction of `Lights::sample_direction`.
    fn pdf_light(&self, next: &Vertex<N>) -> f32 {
        let w = (next.p - self.p).normalize_or_zero();
        let cos = w.dot(self.ng);
        if cos <= 0.0 {
            return 0.0;
        }
        self.convert(cos * FRAC_1_PI, next)
    }

    /// Area density of choosing this point as a light subpath's origin.
    fn pdf_light_origin(&self, scene: &Scene) -> f32 {
        if self.light == NO_LIGHT {
            return 0.0;
        }
        scene.lights.pdf_position(self.light)
    }
}

/// The roulette both subpaths play: the estimate roulettes as their base.
fn roulette(set: &IntegratorSettings) -> super::Roulette {
    let mut rr = set.roulette;
    rr.mode = match rr.mode {
        RrMode::Estimate => RrMode::Classic,
        RrMode::SpectralEstimate => RrMode::Spectral,
        m => m,
    };
    rr
}

/// Continue a subpath from `path`'s last vertex along `ray` until it leaves the scene, the
/// roulette ends it or it has `max_len` vertices. `pdf_dir` is the solid-angle density of
/// `ray`'s direction; `importance` marks a light subpath (adjoint BSDF).
#[allow(clippy::too_many_arguments)]
fn random_walk<const N: usize>(
    scene: &Scene,
    mut ray: Ray,
    mut beta: Spectrum<N>,
    mut pdf_dir: f32,
    max_len: usize,
    importance: bool,
    path: &mut Vec<Vertex<N>>,
    s: &mut SampleStream,
    rr: &super::Roulette,
    c: &mut Counters,
) {
    let dim_offset = if importance {
        dims::LIGHT_BOUNCE
    } else {
        dims::CAMERA_BOUNCE
    };
    while path.len() < max_len {
        c.rays += 1;
        c.light_rays += importance as u64;
        let Some(hit) = scene.intersect(&ray, f32::INFINITY) else {
            break;
        };
        let mat = scene.material_of(hit.prim);
        let mut v = Vertex {
            kind: Kind::Surface,
            p: hit.p,
            ng: hit.ng,
            ns: hit.ns,
            bsdf: scene.bsdf_at(mat, &hit, -ray.d),
            light: scene.lights.light_of(hit.prim).unwrap_or(NO_LIGHT),
            beta,
            delta: false,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        };
        v.pdf_fwd = path.last().unwrap().convert(pdf_dir, &v);
        path.push(v);
        let i = path.len() - 1;
        let v = &path[i];
        let bsdf = &v.bsdf;
        if path.len() >= max_len {
            break;
        }

        // Sample the continuation at y_i (or z_i).
        let wo = -ray.d;
        let (ng, ns, frame) = v.oriented(wo);
        let wo_l = frame.to_local(wo);
        s.set_dimension(dims::block(i) + dim_offset);
        let u_lobe = s.next_1d();
        let u_bsdf = s.next_2d();
        let u_rr = s.next_1d();
        let sel = rr.select::<N>(i as u32 - 1, &beta, bsdf);
        let Step::Continue { sample: bs, scale } =
            sel.sample::<N>(bsdf, wo_l, u_lobe, u_bsdf, u_rr)
        else {
            break;
        };
        let wi = frame.to_world(bs.wi);
        // Shading normals must not let light through the geometric surface.
        if (wi.dot(ng) > 0.0) != (bs.wi.z > 0.0) {
            break;
        }
        let mut weight = bs.weight * scale;
        if importance {
            // Adjoint BSDF with shading normals (Veach 5.3.2): w_o = wo (towards the light
            // side), w_i = wi (sampled, towards the camera side).
            let den = wo.dot(ng).abs() * wi.dot(ns).abs();
            if den <= 0.0 {
                break;
            }
            weight *= wo.dot(ns).abs() * wi.dot(ng).abs() / den;
            // Importance is not scaled by (eta_t / eta_i)^2: undo the radiance scaling
            // the dielectrics' `sample` applies on refraction.
            if matches!(
                bsdf,
                Bsdf::Dielectric(_)
                    | Bsdf::RoughDielectric(_)
                    | Bsdf::Principled(_)
                    | Bsdf::Blend(_)
            ) {
                weight *= bsdf.adjoint_scale(wo_l, bs.wi);
            }
        }
        beta *= weight;
        let (pdf_fwd, pdf_rev) = if bs.delta {
            (0.0, 0.0)
        } else {
            (
                bsdf.pdf(wo_l, bs.wi),
                if wo.dot(ng) > 0.0 || bsdf.transmits() {
                    bsdf.pdf(bs.wi, wo_l)
                } else {
                    0.0
                },
            )
        };
        let rev = v.convert(pdf_rev, &path[i - 1]);
        path[i].delta = bs.delta;
        path[i - 1].pdf_rev = rev;
        if beta.is_black() || !beta.is_finite() {
            break;
        }
        pdf_dir = pdf_fwd;
        ray = Ray::new(offset_origin(hit.p, ng, wi), wi);
    }
}

/// The MIS weight of strategy (s, t) for the path made of `light[..s]` and `cam[..t]`
/// (`sampled` replaces z_0 when s = 1 and y_0 when t = 1): Veach's ratio recurrence, with
/// the reverse densities of the four vertices next to the connection computed for it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn mis_weight<const N: usize>(
    scene: &Scene,
    cam: &Camera,
    light: &[Vertex<N>],
    camp: &[Vertex<N>],
    sampled: Option<&Vertex<N>>,
    s: usize,
    t: usize,
    heuristic: MisHeuristic,
    lt_ratio: f32,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let lv = |i: usize| -> &Vertex<N> {
        match sampled {
            Some(v) if s == 1 && i == 0 => v,
            _ => &light[i],
        }
    };
    let cv = |i: usize| -> &Vertex<N> {
        match sampled {
            Some(v) if t == 1 && i == 0 => v,
            _ => &camp[i],
        }
    };
    let pt = cv(t - 1);
    let qs = (s > 0).then(|| lv(s - 1));
    let pt_m = (t > 1).then(|| cv(t - 2));
    let qs_m = (s > 1).then(|| lv(s - 2));
    // p_rev of y_{t-1}, y_{t-2}, z_{s-1}, z_{s-2} under this strategy.
    let pt_rev = match qs {
        Some(q) => q.pdf(cam, qs_m, pt),
        None => pt.pdf_light_origin(scene),
    };
    let pt_m_rev = pt_m.map(|pm| match qs {
        Some(q) => pt.pdf(cam, Some(q), pm),
        None => pt.pdf_light(pm),
    });
    let qs_rev = qs.map(|q| pt.pdf(cam, pt_m, q));
    let qs_m_rev = qs_m.map(|qm| qs.unwrap().pdf(cam, Some(pt), qm));

    let remap = |f: f32| if f != 0.0 { f } else { 1.0 };
    let power = heuristic == MisHeuristic::Power;
    // Multi-sample MIS: the light-tracing strategy (s + t - 1, 1) has K times the samples
    // of the others (n_i p_i in the balance heuristic, (n_i p_i)^2 in the power one).
    let k = if power { lt_ratio * lt_ratio } else { lt_ratio };
    let mut sum = 0.0f32;
    // Camera side: strategies (s + t - i, i) for i = t - 1 .. 1.
    let mut ri = 1.0f32;
    for i in (1..t).rev() {
        let v = cv(i);
        let rev = if i == t - 1 {
            pt_rev
        } else if i + 2 == t {
            pt_m_rev.unwrap()
        } else {
            v.pdf_rev
        };
        let r = remap(rev) / remap(v.pdf_fwd);
        ri *= if power { r * r } else { r };
        let delta_i = i != t - 1 && v.delta;
        if !delta_i && !cv(i - 1).delta {
            sum += if i == 1 { ri * k } else { ri };
        }
    }
    // Light side: strategies (i, s + t - i) for i = s - 1 .. 0.
    ri = 1.0;
    for i in (0..s).rev() {
        let v = lv(i);
        let rev = if i == s - 1 {
            qs_rev.unwrap()
        } else if i + 2 == s {
            qs_m_rev.unwrap()
        } else {
            v.pdf_rev
        };
        let r = remap(rev) / remap(v.pdf_fwd);
        ri *= if power { r * r } else { r };
        let delta_i = i != s - 1 && v.delta;
        // area lights are never Dirac
        let delta_prev = i > 0 && lv(i - 1).delta;
        if !delta_i && !delta_prev {
            sum += ri;
        }
    }
    if t == 1 {
        // this strategy is the light tracing one: the others relative to K of it
        sum /= k;
    }
    let w = 1.0 / (1.0 + sum);
    if w.is_finite() {
        w
    } else {
        0.0
    }
}

/// A connection's unweighted contribution.
struct Connection<const N: usize> {
    l: Spectrum<N>,
    /// The vertex sampled for the strategy (s = 1: the light point; t = 1: the camera).
    sampled: Option<Vertex<N>>,
    /// Where a t = 1 contribution lands.
    raster: Option<Vec2>,
}

/// Is the segment between the two points free (each end offset off its surface)?
#[inline]
fn visible(
    scene: &Scene,
    a: Vec3,
    na: Option<Vec3>,
    b: Vec3,
    nb: Option<Vec3>,
    c: &mut Counters,
) -> bool {
    let d = b - a;
    let o = match na {
        Some(n) => offset_origin(a, n, d),
        None => a,
    };
    let e = match nb {
        Some(n) => offset_origin(b, n, -d),
        None => b,
    };
    c.rays += 1;
    !scene.occluded(&Ray::new(o, e - o), 1.0 - 1e-4)
}

/// The unweighted contribution of strategy (s, t) (pbrt's `ConnectBDPT` without the MIS
/// weight). For s = 1 the light point is sampled afresh at dimensions of y_{t-1}.
#[allow(clippy::too_many_arguments)]
fn connect<const N: usize>(
    scene: &Scene,
    cam: &Camera,
    light: &[Vertex<N>],
    camp: &[Vertex<N>],
    s: usize,
    t: usize,
    rs: &mut SampleStream,
    c: &mut Counters,
) -> Option<Connection<N>> {
    if s == 0 {
        // The camera subpath ends on an emitter (one-sided).
        let pt = &camp[t - 1];
        if pt.light == NO_LIGHT || pt.kind != Kind::Surface {
            return None;
        }
        let w = (camp[t - 2].p - pt.p).normalize_or_zero();
        let cos = w.dot(pt.ng);
        if cos <= 0.0 {
            return None;
        }
        let le = Spectrum::<N>::from_rgb(scene.lights.emitted_at(pt.light, cos, pt.p));
        return Some(Connection {
            l: pt.beta * le,
            sampled: None,
            raster: None,
        });
    }
    if t == 1 {
        // Light tracing: z_{s-1} to the pinhole.
        let qs = &light[s - 1];
        if !qs.connectible() || s < 2 {
            return None;
        }
        let cw = cam.sample_wi(qs.p)?;
        let w = cw.wi;
        let w_prev = (light[s - 2].p - qs.p).normalize_or_zero();
        let l = qs.beta * qs.f(w, w_prev) * adjoint_cos(qs, w_prev, w) * (cw.we / cw.pdf);
        if l.is_black() || !visible(scene, qs.p, Some(qs.ng), cam.position(), None, c) {
            return None;
        }
        return Some(Connection {
            l,
            sampled: Some(Vertex::camera(cam)),
            raster: Some(cw.raster),
        });
    }
    let pt = &camp[t - 1];
    if !pt.connectible() {
        return None;
    }
    let wo_t = (camp[t - 2].p - pt.p).normalize_or_zero();
    if s == 1 {
        // Next-event estimation.
        rs.set_dimension(dims::block(t - 1) + dims::NEE);
        let u_sel = rs.next_1d();
        let u_pos = rs.next_2d();
        let ls = scene.lights.sample_position(u_sel, u_pos)?;
        let d = ls.p - pt.p;
        let dist2 = d.length_squared();
        let w = d / dist2.sqrt();
        let cos_l = -w.dot(ls.n);
        if cos_l <= 0.0 || dist2 == 0.0 {
            return None;
        }
        let le = Spectrum::<N>::from_rgb(ls.emitted(&scene.lights, cos_l));
        let l = pt.beta * pt.f(wo_t, w) * le * (w.dot(pt.ns).abs() * cos_l / (dist2 * ls.pdf_area));
        if l.is_black() || !visible(scene, pt.p, Some(pt.ng), ls.p, None, c) {
            return None;
        }
        return Some(Connection {
            l,
            sampled: Some(Vertex::light(
                ls.p,
                ls.n,
                ls.light,
                ls.pdf_area,
                Spectrum::ZERO,
            )),
            raster: None,
        });
    }
    // A connection edge z_{s-1} -> y_{t-1}.
    let qs = &light[s - 1];
    if !qs.connectible() {
        return None;
    }
    let d = pt.p - qs.p;
    let dist2 = d.length_squared();
    if dist2 == 0.0 {
        return None;
    }
    let w = d / dist2.sqrt();
    let w_prev = (light[s - 2].p - qs.p).normalize_or_zero();
    let lq = qs.beta * qs.f(w, w_prev) * adjoint_cos(qs, w_prev, w);
    if lq.is_black() {
        return None;
    }
    let l = lq * pt.f(wo_t, -w) * pt.beta * (w.dot(pt.ns).abs() / dist2);
    if l.is_black() || !visible(scene, qs.p, Some(qs.ng), pt.p, Some(pt.ng), c) {
        return None;
    }
    Some(Connection {
        l,
        sampled: None,
        raster: None,
    })
}

/// The cosine a light-subpath vertex contributes towards `w` (the camera side) with the
/// shading-normal correction of the adjoint BSDF: |w_prev . n_s| |w . n_g| / |w_prev . n_g|,
/// w_prev towards the light side. (The radiance side's factor is |w . n_s|.)
#[inline]
fn adjoint_cos<const N: usize>(q: &Vertex<N>, w_prev: Vec3, w: Vec3) -> f32 {
    let den = w_prev.dot(q.ng).abs();
    if den <= 0.0 {
        return 0.0;
    }
    w_prev.dot(q.ns).abs() * w.dot(q.ng).abs() / den
}

/// Generate the light subpath z_0 ..: a point on an emitter by power, a cosine direction.
fn light_subpath<const N: usize>(
    scene: &Scene,
    max_len: usize,
    s: &mut SampleStream,
    rr: &super::Roulette,
    c: &mut Counters,
    path: &mut Vec<Vertex<N>>,
) {
    if max_len == 0 {
        return;
    }
    s.set_dimension(dims::LIGHT_ORIGIN);
    let u_sel = s.next_1d();
    let u_pos = s.next_2d();
    let u_dir = s.next_2d();
    let Some(ls) = scene.lights.sample_position(u_sel, u_pos) else {
        return;
    };
    let (d, pdf_dir) = scene.lights.sample_direction(ls.light, u_dir);
    let cos = d.dot(ls.n);
    let le = Spectrum::<N>::from_rgb(ls.emitted(&scene.lights, cos));
    path.push(Vertex::light(
        ls.p,
        ls.n,
        ls.light,
        ls.pdf_area,
        le * (1.0 / ls.pdf_area),
    ));
    if cos <= 0.0 || pdf_dir <= 0.0 || le.is_black() {
        return;
    }
    let beta = le * (cos / (ls.pdf_area * pdf_dir));
    let ray = Ray::new(offset_origin(ls.p, ls.n, d), d);
    random_walk(scene, ray, beta, pdf_dir, max_len, true, path, s, rr, c);
}

/// The camera subpath y_0 (the pinhole) .. through film position `raster`.
#[allow(clippy::too_many_arguments)]
fn camera_subpath<const N: usize>(
    scene: &Scene,
    cam: &Camera,
    raster: Vec2,
    max_len: usize,
    s: &mut SampleStream,
    rr: &super::Roulette,
    c: &mut Counters,
    path: &mut Vec<Vertex<N>>,
) {
    path.push(Vertex::camera(cam));
    let ray = cam.ray(raster.x, raster.y);
    let pdf_dir = cam.pdf_we(ray.d).1;
    random_walk(
        scene,
        ray,
        Spectrum::ONE,
        pdf_dir,
        max_len,
        false,
        path,
        s,
        rr,
        c,
    );
}

/// One sample of pixel (x, y) by bidirectional path tracing: the value of the camera-side
/// strategies (t >= 2), linear RGB; the light-tracing strategies (t = 1) go to `splat`
/// (film position, linear RGB). The film's pixel value is the mean of the returned
/// samples plus the sum of the splats landing in the pixel divided by the samples per
/// pixel (one light subpath per camera sample).
#[allow(clippy::too_many_arguments)]
pub fn sample_pixel<const N: usize>(
    scene: &Scene,
    cam: &Camera,
    x: u32,
    y: u32,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    c: &mut Counters,
    splat: &mut dyn FnMut(glam::Vec2, [f32; 3]),
) -> [f32; 3] {
    sample_pixel_with::<N>(
        scene,
        cam,
        x,
        y,
        s,
        set,
        &BdptOptions::default(),
        c,
        splat,
        None,
    )
}

/// `sample_pixel` with options, and every strategy's contribution reported to `strategy`
/// if given (the debug layers; pbrt's visualizestrategies).
#[allow(clippy::too_many_arguments)]
pub fn sample_pixel_with<const N: usize>(
    scene: &Scene,
    cam: &Camera,
    x: u32,
    y: u32,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    opts: &BdptOptions,
    c: &mut Counters,
    splat: &mut dyn FnMut(glam::Vec2, [f32; 3]),
    mut strategy: Option<&mut dyn FnMut(StrategySample)>,
) -> [f32; 3] {
    c.paths += 1;
    let rr = roulette(set);
    let max_segments = set.max_segments() as usize;
    s.set_dimension(dims::PIXEL);
    let u = s.next_2d();
    let raster = Vec2::new(x as f32 + u.x, y as f32 + u.y);
    let mut camp: Vec<Vertex<N>> = Vec::with_capacity(8);
    let mut light: Vec<Vertex<N>> = Vec::with_capacity(8);
    camera_subpath(scene, cam, raster, max_segments + 1, s, &rr, c, &mut camp);
    if opts.light_per_pixel {
        let mut ls = s.decorrelated(((y as u64) << 32) | x as u64);
        light_subpath(scene, max_segments, &mut ls, &rr, c, &mut light);
    } else {
        light_subpath(scene, max_segments, s, &rr, c, &mut light);
    }

    let mut l = Spectrum::<N>::ZERO;
    for t in 1..=camp.len() {
        for s_len in 0..=light.len() {
            if (s_len == 1 && t == 1) || s_len + t < 2 || s_len + t - 1 > max_segments {
                continue;
            }
            let only_lt = opts.strategies == Strategies::LightTracing;
            if only_lt && t != 1 && !(s_len == 0 && t == 2) {
                continue;
            }
            let Some(conn) = connect(scene, cam, &light, &camp, s_len, t, s, c) else {
                continue;
            };
            if conn.l.is_black() || !conn.l.is_finite() {
                continue;
            }
            let w = if only_lt {
                1.0
            } else {
                let k = match &opts.lt_ratio {
                    Some(m) => m.at(conn.raster.unwrap_or(raster)),
                    None => 1.0,
                };
                mis_weight(
                    scene,
                    cam,
                    &light,
                    &camp,
                    conn.sampled.as_ref(),
                    s_len,
                    t,
                    opts.heuristic,
                    k,
                )
            };
            let lw = conn.l * w;
            if let Some(cb) = strategy.as_mut() {
                cb(StrategySample {
                    s: s_len as u32,
                    t: t as u32,
                    raster: conn.raster.unwrap_or(raster),
                    weighted: lw.to_rgb(),
                    unweighted: conn.l.to_rgb(),
                    direct: s_len == 0 && camp[1..t - 1].iter().all(|v| v.delta),
                });
            }
            match conn.raster {
                Some(r) => {
                    if w > 0.0 {
                        splat(r, lw.to_rgb())
                    }
                }
                None => l += lw,
            }
        }
    }
    l.to_rgb()
}

/// One light subpath traced for light tracing alone (no camera sample): every (s, 1)
/// connection splatted, MIS-weighted with the K of the pixel it lands in (`LtRatio`; the
/// film counts the path as one more light path). The light subpath uses the dimensions of
/// a camera sample's (`dims::LIGHT_ORIGIN`, the light blocks), so a stream of its own per
/// path keeps it independent of the camera samples.
pub fn light_path_sample<const N: usize>(
    scene: &Scene,
    cam: &Camera,
    s: &mut SampleStream,
    set: &IntegratorSettings,
    opts: &BdptOptions,
    c: &mut Counters,
    splat: &mut dyn FnMut(glam::Vec2, [f32; 3]),
) {
    let rr = roulette(set);
    let max_segments = set.max_segments() as usize;
    let mut light: Vec<Vertex<N>> = Vec::with_capacity(8);
    light_subpath(scene, max_segments, s, &rr, c, &mut light);
    for s_len in 2..=light.len().min(max_segments) {
        let Some(conn) = connect(scene, cam, &light, &[], s_len, 1, s, c) else {
            continue;
        };
        if conn.l.is_black() || !conn.l.is_finite() {
            continue;
        }
        let Some(r) = conn.raster else {
            continue;
        };
        let k = match &opts.lt_ratio {
            Some(m) => m.at(r),
            None => 1.0,
        };
        let w = mis_weight(
            scene,
            cam,
            &light,
            &[],
            conn.sampled.as_ref(),
            s_len,
            1,
            opts.heuristic,
            k,
        );
        if w > 0.0 {
            splat(r, (conn.l * w).to_rgb());
        }
    }
}

pub mod passes;
#[cfg(test)]
mod tests;
