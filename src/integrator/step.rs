//! One step of a path at a reflection, shared by the path tracer's one-path code
//! (`path`) and its SIMD lanes (`lanes`): the shadow ray toward a light point and the
//! continuation after a BSDF sample. Both call these, so a path's numbers are the same bits
//! whichever way it goes; neither imports the other's internals.

use super::rr::Step;
use crate::math::{offset_origin, Frame, Ray, Vec3};
use crate::sampling::power_heuristic;
use crate::spectrum::Spectrum;

/// t_max of a shadow ray toward a light point at `o + d` (the point itself not counted).
pub const SHADOW_T_MAX: f32 = 1.0 - 1e-4;

/// Paths [`super::path::radiance_batch`] keeps in flight at once (each asks for up to two rays per
/// step: its shadow ray and its next segment).
pub const BATCH_PATHS: usize = crate::accel::BATCH / 2;

/// The direction and distance from a vertex to a light point (the part of
/// [`super::path::toward_point`] before the BSDF).
#[derive(Clone, Copy)]
pub struct ToPoint {
    pub wi: Vec3,
    /// wi in the shading frame.
    pub wi_l: Vec3,
    /// Cosine at the light, squared distance, the light point and its density per area.
    pub cos_l: f32,
    dist2: f32,
    lp: Vec3,
    pdf_area: f32,
}

impl ToPoint {
    #[inline(always)]
    pub fn new(p: Vec3, frame: &Frame, (lp, ln, pdf_area): (Vec3, Vec3, f32)) -> Self {
        let d = lp - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        ToPoint {
            wi,
            wi_l: frame.to_local(wi),
            cos_l: -wi.dot(ln),
            dist2,
            lp,
            pdf_area,
        }
    }

    /// Whether light from the point may arrive here: the point faces the vertex, and wi
    /// is on the side of the geometric and the shading normal alike (or below both, for
    /// a BSDF that `transmits`).
    #[inline(always)]
    pub fn reaches(&self, ng: Vec3, transmits: bool) -> bool {
        self.cos_l > 0.0 && facing(transmits, self.wi, self.wi_l, ng)
    }

    /// The shadow ray, its t_max, and beta f Le w / p_light, given f |cos| and the
    /// continuation's density `pdf_bsdf` toward wi (the MIS weight w is the power
    /// heuristic of p_light against it).
    #[inline(always)]
    pub fn estimate<const N: usize>(
        &self,
        p: Vec3,
        ng: Vec3,
        f: Spectrum<N>,
        pdf_bsdf: f32,
        le: [f32; 3],
        beta: &Spectrum<N>,
    ) -> (Ray, f32, Spectrum<N>) {
        let o = offset_origin(p, ng, self.wi);
        let to = self.lp - o;
        let pdf_light = self.pdf_area * self.dist2 / self.cos_l;
        let w = power_heuristic(pdf_light, pdf_bsdf);
        let e = *beta * f * Spectrum::from_rgb(le) * (w / pdf_light);
        (Ray::new(o, to), SHADOW_T_MAX, e)
    }
}

/// The path's next segment after the reflection `step` at `p` (geometric normal `ng`,
/// shading frame `frame`) reached with throughput `beta`: the ray, the new throughput,
/// and the sample's density and delta flag; `None` if the path ends here.
#[inline(always)]
pub fn continuation<const N: usize>(
    p: Vec3,
    ng: Vec3,
    frame: &Frame,
    step: Step<N>,
    beta: &Spectrum<N>,
) -> Option<(Ray, Spectrum<N>, f32, bool)> {
    let Step::Continue { sample: bs, scale } = step else {
        return None;
    };
    let (ok, ray, beta) = continued(p, ng, frame, &bs, scale, beta);
    ok.then_some((ray, beta, bs.pdf, bs.delta))
}

/// [`continuation`] after a sample `bs` (and its roulette `scale`), without a branch:
/// whether the path goes on (the direction is on the side of the geometric normal that
/// the sample's is of the shading normal, and the throughput is not black), the ray, the
/// new throughput.
#[inline(always)]
pub fn continued<const N: usize>(
    p: Vec3,
    ng: Vec3,
    frame: &Frame,
    bs: &crate::material::BsdfSample<N>,
    scale: f32,
    beta: &Spectrum<N>,
) -> (bool, Ray, Spectrum<N>) {
    let wi = frame.to_world(bs.wi);
    // Shading normals must not let light through the geometric surface.
    let side = (wi.dot(ng) > 0.0) == (bs.wi.z > 0.0);
    let mut beta = *beta * bs.weight;
    if scale != 1.0 {
        beta *= scale;
    }
    let ray = Ray::new(offset_origin(p, ng, wi), wi);
    (side && !beta.is_black(), ray, beta)
}

/// May light arrive from `wi` (world; `wi_l` in the shading frame)? On the side of the
/// geometric and the shading normal alike, and on the front unless the BSDF transmits.
#[inline(always)]
pub fn facing(
    transmits: bool,
    wi: crate::math::Vec3,
    wi_l: crate::math::Vec3,
    ng: crate::math::Vec3,
) -> bool {
    if wi_l.z > 0.0 {
        wi.dot(ng) > 0.0
    } else {
        transmits && wi_l.z < 0.0 && wi.dot(ng) < 0.0
    }
}
