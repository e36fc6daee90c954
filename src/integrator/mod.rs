//! Estimators of the radiance along camera rays, behind one interface. They see an
//! immutable scene and a random stream, never the CLI.
//!
//! The interface (pbrt-v4's `RayIntegrator::EvaluatePixelSample` + `Film::AddSplat`):
//! `Integrator::prepare(&Scene, settings)` does each estimator's own precomputation once
//! per render (the estimate roulette's L~ photon walk today; a radiosity solution or a
//! light sampler tomorrow); then the pixel loop calls `Integrator::sample` once per camera
//! sample, which returns the value of that sample for its own pixel and may send any
//! number of splats to other pixels through a `SplatSink`.

pub mod bdpt;
pub mod gather;
pub mod lanes;
pub mod path;
pub mod phases;
pub mod rr;
pub mod visible;

use crate::math::{Ray, Vec2, Vec3};
use crate::sampling::SampleStream;
use crate::scene::{Camera, Scene};

pub use bdpt::MisHeuristic;
pub use gather::Gather;
pub use rr::{BsdfSelect, LTilde, RadianceEstimate, Roulette, RrEstimate, RrMode, RrWeight};

use crate::radiosity::{RadiositySettings, Solution};
use std::sync::Arc;

/// Paths deeper than this end regardless (a guard for unlimited depth without roulette
/// in closed glass or white rooms; the throughput left there is below f32 precision).
pub const HARD_MAX_DEPTH: u32 = 1024;

/// Which estimator.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorKind {
    /// Unidirectional path tracing, next-event estimation + MIS (with `--gather
    /// radiosity`: Rushmeier and Ward's path tracer reading a radiosity solution).
    #[default]
    Path,
    /// Bidirectional path tracing: every (s, t) strategy, MIS, light-tracing splats.
    Bdpt,
    /// The radiosity solution seen directly (a preview): emitters plus B / pi at the first
    /// non-specular hit, mirrors and glass followed.
    Radiosity,
    /// Test only: every sample returns 0 and splats (x, y, 1) into the pixel to its right
    /// (wrapping), so the image is known exactly.
    #[cfg(test)]
    #[value(skip)]
    #[serde(skip)]
    SplatTest,
}

/// Settings of an estimator (filled from `RenderJob`, where the options are named).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorSettings {
    pub kind: IntegratorKind,
    /// Mitsuba's max_depth: 1 = emitters seen directly, 2 = direct light, -1 = unlimited.
    pub max_depth: i32,
    pub roulette: Roulette,
    /// The path tracer's diffuse indirect light: traced, or from a radiosity solution.
    pub gather: Gather,
    /// Diffuse reflections traced before the gather looks up (1: the paper's first bounce).
    pub gather_depth: u32,
    /// Rays per gather vertex for the diffuse lookup (1: the paper's one path per trial).
    pub gather_rays: u32,
    /// The radiosity preprocess (for `--gather radiosity` and `--integrator radiosity`).
    pub radiosity: RadiositySettings,
    /// BDPT's weighting of the strategies.
    pub mis: MisHeuristic,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        IntegratorSettings {
            kind: IntegratorKind::Path,
            max_depth: -1,
            roulette: Roulette::default(),
            gather: Gather::Off,
            gather_depth: 1,
            gather_rays: gather::DEFAULT_GATHER_RAYS,
            radiosity: RadiositySettings::default(),
            mis: MisHeuristic::Balance,
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
    /// Of `rays`, those that extended BDPT's light subpaths (what a light path traced for
    /// light tracing alone costs, besides its connections to the camera).
    pub light_rays: u64,
}

impl Counters {
    pub fn add(&mut self, o: &Counters) {
        self.paths += o.paths;
        self.rays += o.rays;
        self.light_rays += o.light_rays;
    }
}

/// One splat: a contribution to pixel `pixel` by the sample of index `index`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    pub pixel: u32,
    pub index: u32,
    pub rgb: [f32; 3],
}

/// Where an estimator sends contributions to other pixels: a per-chunk buffer that the
/// pipeline adds to the film in a fixed order (the film's sums are exact, so the order
/// does not change the image either).
#[derive(Clone, Debug, Default)]
pub struct SplatSink {
    pub width: u32,
    pub height: u32,
    /// Sample index of the camera sample being evaluated (its batch).
    pub index: u32,
    pub splats: Vec<Splat>,
}

impl SplatSink {
    pub fn new(width: u32, height: u32) -> Self {
        SplatSink {
            width,
            height,
            index: 0,
            splats: Vec::new(),
        }
    }

    /// Splat linear RGB at raster position `p` (pixel (x, y) covers [x, x+1) x [y, y+1));
    /// positions outside the image are dropped.
    #[inline]
    pub fn splat(&mut self, p: Vec2, rgb: [f32; 3]) {
        if !(p.x >= 0.0 && p.y >= 0.0) {
            return;
        }
        let (x, y) = (p.x as u32, p.y as u32);
        if x < self.width && y < self.height {
            self.splats.push(Splat {
                pixel: y * self.width + x,
                index: self.index,
                rgb,
            });
        }
    }
}

/// An estimator prepared for one scene and render.
#[derive(Clone)]
pub struct Integrator {
    pub set: IntegratorSettings,
    /// The estimate roulette's L~ (None unless the roulette uses it).
    pub estimate: Option<RadianceEstimate>,
    /// The radiosity solution (None unless the gather or the preview reads it).
    pub radiosity: Option<Arc<Solution>>,
    bdpt: bdpt::BdptOptions,
}

impl Integrator {
    /// Each estimator's own precomputation for this scene: the L~ photon walk when the
    /// roulette uses it, the radiosity solution (on `bands` spectral bands) when the gather
    /// or the preview reads it.
    pub fn prepare(
        scene: &Scene,
        set: IntegratorSettings,
        bands: usize,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Integrator, String> {
        if set.gather.reads_solution() && set.kind != IntegratorKind::Path {
            return Err(format!(
                "--gather radiosity: the gather belongs to the path tracer, not to --integrator {}",
                crate::options::name(&set.kind)
            ));
        }
        if set.gather.reads_solution() && set.roulette.select == BsdfSelect::Decompose {
            return Err(
                "--gather radiosity with --bsdf-select decompose: the gather splits the \
                        diffuse lobe itself; use mixture, static or mis"
                    .into(),
            );
        }
        if set.kind == IntegratorKind::Bdpt && set.roulette.mode == RrMode::Off && set.max_depth < 0
        {
            return Err(format!(
                "--integrator bdpt with --rr off and --max-depth -1: subpaths run to {HARD_MAX_DEPTH} \
                 vertices and each sample costs the cube of that; give --max-depth D or a roulette \
                 (--rr classic|spectral)"
            ));
        }
        if scene.lights.has_distant() {
            let what = match (
                scene.lights.env().is_some(),
                scene.lights.points().is_empty(),
            ) {
                (true, true) => "an environment light",
                (true, false) => "an environment and point lights",
                _ => "point lights",
            };
            if set.kind == IntegratorKind::Bdpt {
                return Err(format!(
                    "--integrator bdpt: the scene has {what}, which BDPT does not support yet; use --integrator path"
                ));
            }
            if set.kind == IntegratorKind::Radiosity || set.gather.reads_solution() {
                return Err(format!(
                    "--integrator radiosity / --gather radiosity: the scene has {what}, which the radiosity solution does not support; use --integrator path with --gather off"
                ));
            }
            if set.roulette.mode.uses_estimate() {
                return Err(format!(
                    "--rr {}: the radiance estimate L~ counts area lights only and the scene has {what}; use --rr classic or --rr spectral",
                    crate::options::name(&set.roulette.mode)
                ));
            }
        }
        if set.gather_depth == 0 {
            return Err("--gather-depth: must be at least 1 (the first diffuse bounce)".into());
        }
        if !(1..=gather::MAX_GATHER_RAYS).contains(&set.gather_rays) {
            return Err(format!(
                "--gather-rays {}: must be between 1 (the paper's one path per trial) and {}",
                set.gather_rays,
                gather::MAX_GATHER_RAYS
            ));
        }
        let reads_radiosity_l_tilde = set.roulette.estimate == RrEstimate::Radiosity;
        if reads_radiosity_l_tilde {
            if !set.roulette.mode.uses_estimate() {
                return Err(format!(
                    "--rr-estimate radiosity: --rr {} reads no L~; use --rr estimate or spectral-estimate",
                    crate::options::name(&set.roulette.mode)
                ));
            }
            if set.kind != IntegratorKind::Path {
                return Err(format!(
                    "--rr-estimate radiosity: only --integrator path reads L~ (not {})",
                    crate::options::name(&set.kind)
                ));
            }
        }
        let estimate = set
            .roulette
            .mode
            .uses_estimate()
            .then(|| RadianceEstimate::of_scene(scene));
        let radiosity = if set.gather.reads_solution()
            || set.kind == IntegratorKind::Radiosity
            || reads_radiosity_l_tilde
        {
            Some(Arc::new(Solution::compute(
                scene,
                &set.radiosity,
                bands,
                progress,
            )?))
        } else {
            None
        };
        Ok(Integrator {
            set,
            estimate,
            radiosity,
            bdpt: bdpt::BdptOptions {
                heuristic: set.mis,
                strategies: bdpt::Strategies::All,
                light_per_pixel: false,
                lt_ratio: None,
            },
        })
    }

    /// The estimator for DTF's dependent phase: BDPT draws each pixel's light subpath
    /// from its own stream (`bdpt::BdptOptions::light_per_pixel`); the others unchanged.
    pub fn for_dependent_phase(&self) -> Integrator {
        let mut i = self.clone();
        i.bdpt.light_per_pixel = true;
        i
    }

    /// The estimator with K[p] light-tracing paths per camera sample in its MIS weights
    /// (BDPT with light paths traced for light tracing alone: `bdpt::LtRatio`); the
    /// others unchanged.
    pub fn with_lt_ratio(&self, k: Option<Arc<bdpt::LtRatio>>) -> Integrator {
        let mut i = self.clone();
        i.bdpt.lt_ratio = k;
        i
    }

    /// Whether [`Integrator::light_sample`] means anything here (BDPT).
    pub fn traces_light_paths(&self) -> bool {
        self.set.kind == IntegratorKind::Bdpt
    }

    /// One light subpath for light tracing alone (BDPT): its (s, 1) connections go to
    /// `sink`; no camera sample. Other estimators do nothing.
    pub fn light_sample<const N: usize>(
        &self,
        scene: &Scene,
        cam: &Camera,
        s: &mut SampleStream,
        sink: &mut SplatSink,
        c: &mut Counters,
    ) {
        if self.set.kind == IntegratorKind::Bdpt {
            let mut to_sink = |p: Vec2, rgb: [f32; 3]| sink.splat(p, rgb);
            bdpt::light_path_sample::<N>(scene, cam, s, &self.set, &self.bdpt, c, &mut to_sink);
        }
    }

    /// Whether this estimator sends splats (the film then keeps splat and batch sums).
    pub fn splats(&self) -> bool {
        match self.set.kind {
            IntegratorKind::Path | IntegratorKind::Radiosity => false,
            IntegratorKind::Bdpt => true,
            #[cfg(test)]
            IntegratorKind::SplatTest => true,
        }
    }

    /// L~ of the estimate roulette: the scene's, or read from the radiosity solution.
    fn l_tilde<const N: usize>(&self) -> LTilde<'_, N> {
        let scene_l = match &self.estimate {
            Some(e) => e.l_tilde::<N>(),
            None => crate::spectrum::Spectrum::ZERO,
        };
        match (&self.radiosity, self.set.roulette.estimate) {
            (Some(sol), RrEstimate::Radiosity) => LTilde::Radiosity(sol, scene_l),
            _ => LTilde::Scene(scene_l),
        }
    }

    /// Whether [`Integrator::sample_batch`] serves this estimator: the path tracer without
    /// the radiosity gather (on any scene: `Bvh::trace` answers a batch's queries the way
    /// the tree's size favours).
    pub fn batches(&self) -> bool {
        matches!(self.set.kind, IntegratorKind::Path)
            && !(self.radiosity.is_some() && self.set.gather.reads_solution())
    }

    /// [`Integrator::sample`] of up to [`path::BATCH_PATHS`] samples at once (for an
    /// estimator that [`Integrator::batches`]): sample `i` is of pixel `pixels[i]` with
    /// stream `streams[i]`; the same values as one at a time, into `out`.
    pub fn sample_batch<const N: usize>(
        &self,
        scene: &Scene,
        cam: &Camera,
        pixels: &[(u32, u32)],
        streams: &mut [SampleStream],
        c: &mut Counters,
        out: &mut [[f32; 3]],
    ) {
        debug_assert!(matches!(self.set.kind, IntegratorKind::Path));
        let n = pixels.len();
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::ZERO); path::BATCH_PATHS];
        for ((r, &(x, y)), s) in rays.iter_mut().zip(pixels).zip(streams.iter_mut()) {
            *r = camera_ray(cam, x, y, s);
        }
        let mut l = [crate::spectrum::Spectrum::<N>::ZERO; path::BATCH_PATHS];
        let lt = self.l_tilde::<N>();
        path::radiance_batch::<N>(scene, &rays[..n], streams, &self.set, &lt, c, &mut l[..n]);
        for (o, v) in out.iter_mut().zip(&l[..n]) {
            *o = v.to_rgb();
        }
    }

    /// One camera sample of pixel (x, y): its value (linear RGB); splats go to `sink`.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn sample<const N: usize>(
        &self,
        scene: &Scene,
        cam: &Camera,
        x: u32,
        y: u32,
        s: &mut SampleStream,
        sink: &mut SplatSink,
        c: &mut Counters,
    ) -> [f32; 3] {
        self.sample_all::<N>(scene, cam, x, y, s, sink, c)
    }

    /// One camera sample of a non-splatting estimator split in two (`visible.rs`): the
    /// transport L - f(ray) and the light seen directly f(ray), whose sum is `sample`'s
    /// value.
    #[inline]
    pub fn sample_split<const N: usize>(
        &self,
        scene: &Scene,
        cam: &Camera,
        x: u32,
        y: u32,
        s: &mut SampleStream,
        c: &mut Counters,
    ) -> ([f32; 3], [f32; 3]) {
        let ray = camera_ray(cam, x, y, &mut s.clone());
        let f = visible::emission::<N>(scene, ray, self.set.max_segments(), c).to_rgb();
        let mut sink = SplatSink::new(1, 1);
        let l = self.sample_all::<N>(scene, cam, x, y, s, &mut sink, c);
        debug_assert!(sink.splats.is_empty(), "a split sample splatted");
        ([l[0] - f[0], l[1] - f[1], l[2] - f[2]], f)
    }

    /// Whether [`Integrator::sample_direct`] serves this estimator: BDPT, whose camera
    /// subpath already carries the emission seen directly (its s = 0 strategies through
    /// Dirac vertices only), so the split costs no ray.
    pub fn splits_direct(&self) -> bool {
        self.set.kind == IntegratorKind::Bdpt
    }

    /// One camera sample of pixel (x, y) as [`Integrator::sample`], and the part of its
    /// value that is emission seen directly (`bdpt::StrategySample::direct`: the MIS-weighted
    /// s = 0 contributions whose camera vertices before the emitter are all Dirac). Splats
    /// go to `sink` as usual; they never hold emission seen directly. Only for an
    /// estimator that [`Integrator::splits_direct`] (others: a direct part of 0).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn sample_direct<const N: usize>(
        &self,
        scene: &Scene,
        cam: &Camera,
        x: u32,
        y: u32,
        s: &mut SampleStream,
        sink: &mut SplatSink,
        c: &mut Counters,
    ) -> ([f32; 3], [f32; 3]) {
        if self.set.kind != IntegratorKind::Bdpt {
            return (self.sample_all::<N>(scene, cam, x, y, s, sink, c), [0.0; 3]);
        }
        let mut direct = [0.0f32; 3];
        let mut to_sink = |p: Vec2, rgb: [f32; 3]| sink.splat(p, rgb);
        let mut on_strategy = |st: bdpt::StrategySample| {
            if st.direct {
                for (d, v) in direct.iter_mut().zip(st.weighted) {
                    *d += v;
                }
            }
        };
        let l = bdpt::sample_pixel_with::<N>(
            scene,
            cam,
            x,
            y,
            s,
            &self.set,
            &self.bdpt,
            c,
            &mut to_sink,
            Some(&mut on_strategy),
        );
        (l, direct)
    }

    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn sample_all<const N: usize>(
        &self,
        scene: &Scene,
        cam: &Camera,
        x: u32,
        y: u32,
        s: &mut SampleStream,
        sink: &mut SplatSink,
        c: &mut Counters,
    ) -> [f32; 3] {
        let l_tilde = || self.l_tilde::<N>();
        match self.set.kind {
            IntegratorKind::Path => {
                let ray = camera_ray(cam, x, y, s);
                match (&self.radiosity, self.set.gather) {
                    (Some(sol), g) if g.reads_solution() => gather::radiance::<N>(
                        scene,
                        sol,
                        ray,
                        s,
                        &self.set,
                        self.set.gather_depth,
                        &l_tilde(),
                        c,
                    )
                    .to_rgb(),
                    _ => path::radiance::<N>(scene, ray, s, &self.set, &l_tilde(), c).to_rgb(),
                }
            }
            IntegratorKind::Bdpt => {
                let mut to_sink = |p: Vec2, rgb: [f32; 3]| sink.splat(p, rgb);
                bdpt::sample_pixel_with::<N>(
                    scene,
                    cam,
                    x,
                    y,
                    s,
                    &self.set,
                    &self.bdpt,
                    c,
                    &mut to_sink,
                    None,
                )
            }
            IntegratorKind::Radiosity => {
                let ray = camera_ray(cam, x, y, s);
                match &self.radiosity {
                    Some(sol) => {
                        gather::preview::<N>(scene, sol, ray, s, self.set.max_segments(), c)
                            .to_rgb()
                    }
                    None => [0.0; 3],
                }
            }
            #[cfg(test)]
            IntegratorKind::SplatTest => {
                let _ = (scene, cam, s, c);
                let to = Vec2::new(((x + 1) % sink.width) as f32 + 0.5, y as f32 + 0.5);
                sink.splat(to, [x as f32, y as f32, 1.0]);
                [0.0; 3]
            }
        }
    }
}

/// The camera ray of a sample of pixel (x, y): dimensions 0 and 1 jitter it in the pixel.
#[inline]
pub fn camera_ray(cam: &Camera, x: u32, y: u32, s: &mut SampleStream) -> Ray {
    s.set_dimension(0);
    let u = s.next_2d();
    cam.ray(x as f32 + u.x, y as f32 + u.y)
}
