//! The end of many paths' diffuse vertices at once, in SIMD lanes: a wavefront stage of
//! the path tracer.
//!
//! [`super::path::radiance_batch`] advances up to [`L`] paths per step. At a Lambertian
//! vertex, under the BSDF's own sampling (`BsdfSelect::Mixture`, with or without classic
//! roulette) and lit by an area light of constant radiance, what is left once the light
//! point is chosen is the same arithmetic for every path: next-event estimation toward
//! that point (geometry, f, the MIS weight, the shadow ray) and the cosine-weighted
//! continuation. Such vertices are put into structure-of-arrays lanes and finished by one
//! loop over all [`L`] lanes, which the compiler runs in SIMD registers (eight paths per
//! AVX2 instruction where the CPU has it, chosen at run time; SSE2 elsewhere). Each lane
//! calls the one-path code's parts (`step::ToPoint`, `Lambert::sample_any`,
//! `Selection::roulette`, `step::continued`) on its own values, with their tests kept as
//! flags instead of early returns, so a path's numbers are the same bit for bit whichever
//! way it goes.

use super::rr::Selection;
use super::step::{continued, ToPoint, BATCH_PATHS, SHADOW_T_MAX};
use crate::material::Lambert;
use crate::math::{Ray, Vec3};
use crate::scene::Shading;
use crate::spectrum::Spectrum;

/// Lanes of one batch: one per path of a step.
pub const L: usize = BATCH_PATHS;

/// Lanes in use up to which they are finished one by one rather than all [`L`] at once
/// (the Cornell box with roulette, whose batches thin out fast: 1.024x against none; 8
/// gave the same, 2 0.992x).
const FEW: usize = 4;

/// Inputs of a lane, one row each (structure of arrays).
#[derive(Clone, Copy)]
enum In {
    Px,
    Py,
    Pz,
    Ngx,
    Ngy,
    Ngz,
    /// The shading normal and wo (world).
    Nsx,
    Nsy,
    Nsz,
    Wox,
    Woy,
    Woz,
    U0,
    U1,
    URr,
    /// s, the probability that the walk goes on.
    S,
    Lpx,
    Lpy,
    Lpz,
    Lnx,
    Lny,
    Lnz,
    PdfArea,
    KdR,
    KdG,
    KdB,
    LeR,
    LeG,
    LeB,
}
const INPUTS: usize = In::LeB as usize + 1;

/// Outputs of a lane: the shadow ray (origin, direction), the next segment (origin,
/// direction) and its density.
const OUT_RAYS: usize = 13;

/// Diffuse vertices waiting for their end, and what it gave.
pub struct Lanes<const N: usize> {
    /// Lanes in use.
    pub k: usize,
    /// The path (its index in the batch) of each lane.
    pub path: [u8; L],
    v: [[f32; L]; INPUTS],
    beta: [[f32; L]; N],
    out: [[f32; L]; OUT_RAYS],
    e: [[f32; L]; N],
    beta_next: [[f32; L]; N],
    /// Whether a lane has a shadow ray, and whether it goes on.
    has_shadow: [bool; L],
    goes_on: [bool; L],
}

/// What a finished lane gives its path: whether it has a shadow ray, the shadow ray with
/// its t_max and estimate (whether or not it has one), and the next segment with its
/// throughput and density.
pub type Ending<const N: usize> = (
    bool,
    (Ray, f32, Spectrum<N>),
    Option<(Ray, Spectrum<N>, f32, bool)>,
);

impl<const N: usize> Default for Lanes<N> {
    fn default() -> Self {
        // Unused lanes compute on these harmless values (their results are never read).
        Lanes {
            k: 0,
            path: [0; L],
            v: [[0.5; L]; INPUTS],
            beta: [[0.0; L]; N],
            out: [[0.0; L]; OUT_RAYS],
            e: [[0.0; L]; N],
            beta_next: [[0.0; L]; N],
            has_shadow: [false; L],
            goes_on: [false; L],
        }
    }
}

impl<const N: usize> Lanes<N> {
    /// Whether a Lambertian vertex can end here, before its light is sampled: in RGB
    /// (spectral bands' uplift reads tables that the loop does not vectorise: 0.65x
    /// measured with 8 bands), sampled by mixture selection without the estimate
    /// roulette's term. Its light point must then be of constant radiance
    /// (`!LightSample::directional`).
    #[inline(always)]
    pub fn takes(sel: &Selection, estimate: bool) -> bool {
        N == 3 && sel.is_mixture() && !(estimate && sel.s_total < 1.0)
    }

    /// Adds a vertex of path `path` (see [`Self::takes`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        path: u8,
        p: Vec3,
        ng: Vec3,
        ns: Vec3,
        wo: Vec3,
        kd: [f32; 3],
        sel: &Selection,
        u_bsdf: glam::Vec2,
        u_rr: f32,
        ls: &crate::light::LightSample,
        beta: &Spectrum<N>,
    ) {
        let i = self.k;
        self.k += 1;
        self.path[i] = path;
        let row = [
            p.x,
            p.y,
            p.z,
            ng.x,
            ng.y,
            ng.z,
            ns.x,
            ns.y,
            ns.z,
            wo.x,
            wo.y,
            wo.z,
            u_bsdf.x,
            u_bsdf.y,
            u_rr,
            sel.s_total,
            ls.p.x,
            ls.p.y,
            ls.p.z,
            ls.n.x,
            ls.n.y,
            ls.n.z,
            ls.pdf_area,
            kd[0],
            kd[1],
            kd[2],
            ls.le[0],
            ls.le[1],
            ls.le[2],
        ];
        for (r, x) in self.v.iter_mut().zip(row) {
            r[i] = x;
        }
        for (r, x) in self.beta.iter_mut().zip(beta.0) {
            r[i] = x;
        }
    }

    /// Finishes every lane in use, with the instruction set `isa` (the scene's BVH's, so
    /// that `KALOS_SIMD` and the tests choose both).
    pub fn finish(&mut self, isa: crate::accel::Isa) {
        if self.k <= FEW {
            // Too few for the loop over all lanes: each alone (the same operations).
            for i in 0..self.k {
                self.finish_lane(i);
            }
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if isa == crate::accel::Isa::Avx2 && isa.is_available() {
            // SAFETY: this CPU has AVX2 and FMA.
            #[allow(unsafe_code)]
            unsafe {
                self.finish_avx2()
            };
            return;
        }
        self.finish_all();
    }

    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn finish_avx2(&mut self) {
        self.finish_all();
    }

    /// All [`L`] lanes in one loop with no early exit, so that it runs in SIMD registers.
    #[inline(always)]
    fn finish_all(&mut self) {
        for i in 0..L {
            self.finish_lane(i);
        }
    }

    /// Lane `i` (inlined into [`Self::finish_all`]'s loop).
    #[inline(always)]
    fn finish_lane(&mut self, i: usize) {
        let v = &self.v;
        {
            let x = |r: In| v[r as usize][i];
            let v3 = |a: In, b: In, c: In| Vec3::new(x(a), x(b), x(c));
            let p = v3(In::Px, In::Py, In::Pz);
            let ng = v3(In::Ngx, In::Ngy, In::Ngz);
            // (the normals as the path oriented them when it pushed the vertex)
            let Shading { frame, .. } = Shading::new(ng, v3(In::Nsx, In::Nsy, In::Nsz), false);
            let wo_l = frame.to_local(v3(In::Wox, In::Woy, In::Woz));
            let lam = Lambert {
                kd: [x(In::KdR), x(In::KdG), x(In::KdB)],
            };
            let sel = Selection::mixture(x(In::S));
            let mut beta = Spectrum::<N>::ZERO;
            for (b, r) in beta.0.iter_mut().zip(&self.beta) {
                *b = r[i];
            }
            let le = [x(In::LeR), x(In::LeG), x(In::LeB)];
            // Next-event estimation, as `path::toward_point` with this BSDF (the
            // mixture's density is the BSDF's, `Selection::pdf`), every value computed
            // and the tests kept as a flag.
            let light = (
                v3(In::Lpx, In::Lpy, In::Lpz),
                v3(In::Lnx, In::Lny, In::Lnz),
                x(In::PdfArea),
            );
            let to = ToPoint::new(p, &frame, light);
            let f = lam.eval::<N>(wo_l, to.wi_l) * to.wi_l.z.abs();
            let (sr, _, e) = to.estimate(p, ng, f, lam.pdf(wo_l, to.wi_l), le, &beta);
            let has_shadow = to.reaches(ng, false) && !f.is_black();
            // The continuation, as `Selection::sample` (its mixture) with `Lambert::sample`,
            // then `path::continuation`.
            let (rr_on, scale) = sel.roulette(x(In::URr));
            let bs = lam.sample_any::<N>(glam::Vec2::new(x(In::U0), x(In::U1)));
            let (ok, nr, nb) = continued(p, ng, &frame, &bs, scale, &beta);
            let goes_on = rr_on && Lambert::takes_sample(wo_l, &bs) && ok;
            let pdf = bs.pdf;
            self.has_shadow[i] = has_shadow;
            self.goes_on[i] = goes_on;
            let o = [
                sr.o.x, sr.o.y, sr.o.z, sr.d.x, sr.d.y, sr.d.z, nr.o.x, nr.o.y, nr.o.z, nr.d.x,
                nr.d.y, nr.d.z, pdf,
            ];
            for (r, y) in self.out.iter_mut().zip(o) {
                r[i] = y;
            }
            for b in 0..N {
                self.e[b][i] = e.0[b];
                self.beta_next[b][i] = nb.0[b];
            }
        }
    }

    /// What lane `i` gave its path (after [`Self::finish`]).
    #[inline(always)]
    pub fn ending(&self, i: usize) -> Ending<N> {
        let o = |r: usize| self.out[r][i];
        let ray = |a: usize| {
            Ray::new(
                Vec3::new(o(a), o(a + 1), o(a + 2)),
                Vec3::new(o(a + 3), o(a + 4), o(a + 5)),
            )
        };
        let mut e = Spectrum::<N>::ZERO;
        let mut beta = Spectrum::<N>::ZERO;
        for b in 0..N {
            e.0[b] = self.e[b][i];
            beta.0[b] = self.beta_next[b][i];
        }
        (
            self.has_shadow[i],
            (ray(0), SHADOW_T_MAX, e),
            // Lambertian samples are never Dirac.
            self.goes_on[i].then(|| (ray(6), beta, o(12), false)),
        )
    }
}
