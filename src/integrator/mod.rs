//! Estimators of the radiance along camera rays, behind one interface. They see an
//! immutable scene, random streams and a `film::Sink`, never a film or the CLI.
//!
//! The interface (pbrt-v4's `RayIntegrator::EvaluatePixelSample` + `Film::AddSplat`):
//! `Integrator::prepare(&Scene, settings)` does each estimator's own precomputation once
//! per render (the estimate roulette's L~ photon walk, the radiosity solution); then the
//! pixel loop calls `Integrator::sample` with a row's camera samples and a sink, which
//! gets each sample's value for its own pixel, any number of splats to other pixels, and
//! the layers it asks for (the light seen directly, each pixel's rays, BDPT's strategies).
//! `Integrator::light_sample` is BDPT's light path traced for light tracing alone, whose
//! splats go to a sink as well.

pub mod bdpt;
pub mod gather;
pub mod lanes;
pub mod path;
pub mod phases;
pub mod rr;
pub mod step;
pub mod visible;

use crate::film::{Layer, Sink, StrategySample};
use crate::math::{Ray, Vec2, Vec3};
use crate::sampling::{SampleStream, SamplerConfig};
use crate::scene::{Camera, Scene};

pub use bdpt::MisHeuristic;
pub use gather::Gather;
pub use rr::{BsdfSelect, LTilde, RadianceEstimate, Roulette, RrEstimate, RrMode, RrWeight};

use crate::radiosity::{RadiositySettings, Solution};
use std::sync::Arc;

/// Paths deeper than this end regardless (a guard for unlimited depth without roulette
/// in closed glass or white rooms; the throughput left there is below f32 precision).
pub const HARD_MAX_DEPTH: u32 = 1024;

/// Which estimator (named in `options`, below the scene that may name it).
pub use crate::options::IntegratorKind;

/// Settings of an estimator (filled from `RenderJob`, where the options are named).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntegratorSettings {
    pub kind: IntegratorKind,
    /// Mitsuba's max_depth: 1 = emitters seen directly, 2 = direct light, -1 = unlimited.
    pub max_depth: i32,
    pub roulette: Roulette,
    /// The path tracer's diffuse indirect light: traced, or from a radiosity solution.
    pub gather: Gather,
    /// Diffuse reflections traced before the gather looks up (1: the paper's first bounce);
    /// None: `--method rw` chooses it from a pilot (`pipeline::rw_depth`), else
    /// `gather::DEFAULT_GATHER_DEPTH`.
    pub gather_depth: Option<u32>,
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
            gather_depth: None,
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

/// One camera sample to evaluate: pixel (x, y), its row-major number and its sample index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraSample {
    pub x: u32,
    pub y: u32,
    pub pixel: u32,
    pub index: u64,
}

/// What the camera samples of a pass share: the scene, the camera and their random
/// streams (sample k of pixel p draws from `SampleStream::new(sampler, stream, p, k)`).
#[derive(Clone, Copy)]
pub struct SampleCtx<'a> {
    pub scene: &'a Scene,
    pub cam: &'a Camera,
    pub sampler: &'a SamplerConfig,
    pub stream: u32,
}

impl SampleCtx<'_> {
    #[inline]
    fn stream_of(&self, cs: &CameraSample) -> SampleStream {
        SampleStream::new(self.sampler, self.stream, cs.pixel, cs.index)
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
        if set.gather_depth == Some(0) {
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
        // (the radiosity L~ falls back on the solution's mean, not on the scene's photon walk)
        let estimate = (set.roulette.mode.uses_estimate() && !reads_radiosity_l_tilde)
            .then(|| RadianceEstimate::of_scene(scene));
        let gathers = set.gather.reads_solution() || set.kind == IntegratorKind::Radiosity;
        let radiosity = if gathers || reads_radiosity_l_tilde {
            let mut rset = set.radiosity;
            if !gathers {
                rset.default_elements = crate::radiosity::ROULETTE_ELEMENTS;
                rset.roulette_only = true;
            }
            Some(Arc::new(Solution::compute(scene, &rset, bands, progress)?))
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

    /// One light subpath for light tracing alone (BDPT), the light path of index `index`:
    /// its (s, 1) connections go to `sink` as splats; no camera sample. Other estimators
    /// do nothing.
    pub fn light_sample<const N: usize>(
        &self,
        ctx: &SampleCtx,
        s: &mut SampleStream,
        index: u64,
        sink: &mut impl Sink,
        c: &mut Counters,
    ) {
        if self.set.kind == IntegratorKind::Bdpt {
            let mut to_sink = |p: Vec2, rgb: [f32; 3]| sink.splat(index, p, rgb);
            let (scene, cam) = (ctx.scene, ctx.cam);
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
            (Some(sol), RrEstimate::Radiosity) => LTilde::Radiosity(sol, sol.mean_indirect()),
            _ => LTilde::Scene(scene_l),
        }
    }

    /// Whether the path tracer's batches serve this estimator: the path tracer without
    /// the radiosity gather (on any scene: `Bvh::trace` answers a batch's queries the way
    /// the tree's size favours).
    pub fn batches(&self) -> bool {
        matches!(self.set.kind, IntegratorKind::Path)
            && !(self.radiosity.is_some() && self.set.gather.reads_solution())
    }

    /// Whether the path tracer's samples are the radiosity gather's lookups
    /// (`--gather radiosity` with its solution).
    fn gathers(&self) -> bool {
        self.set.kind == IntegratorKind::Path
            && self.radiosity.is_some()
            && self.set.gather == Gather::Radiosity
    }

    /// The gather's depth (`--gather-depth`, or the paper's first diffuse bounce).
    fn gather_depth(&self) -> u32 {
        self.set
            .gather_depth
            .unwrap_or(gather::DEFAULT_GATHER_DEPTH)
    }

    /// Whether [`Layer::Direct`] means anything here: BDPT, whose camera subpath already
    /// carries the emission seen directly (its s = 0 strategies through Dirac vertices
    /// only), so the split costs no ray.
    pub fn splits_direct(&self) -> bool {
        self.set.kind == IntegratorKind::Bdpt
    }

    /// The one entry point of the pixel loop: the camera samples `samples`, in order, each
    /// written to `sink` (its value and the part of it that [`Sink::layer`] asks for), with
    /// any splats, rays ([`Sink::counts_rays`]) and strategies ([`Sink::wants_strategies`])
    /// the sink reads. The path tracer takes up to [`path::BATCH_PATHS`] samples at a time
    /// when the sink reads their values only: the same values as one at a time.
    pub fn sample<const N: usize>(
        &self,
        ctx: &SampleCtx,
        samples: impl IntoIterator<Item = CameraSample>,
        sink: &mut impl Sink,
        c: &mut Counters,
    ) {
        let layer = sink.layer();
        let samples = samples.into_iter();
        if self.batches() && layer == Layer::None && !sink.counts_rays() && !sink.wants_strategies()
        {
            // (scenes without instances or maps take the plain batch, checked once here:
            // see path::radiance_batch)
            return match ctx.scene.plain_hits() {
                true => self.sample_batches::<N, true>(ctx, samples, sink, c),
                false => self.sample_batches::<N, false>(ctx, samples, sink, c),
            };
        }
        let counts_rays = sink.counts_rays();
        for cs in samples {
            let rays_before = c.rays;
            let mut s = ctx.stream_of(&cs);
            let (v, part) = match layer {
                Layer::None if !sink.wants_strategies() => {
                    (self.one::<N>(ctx, &cs, &mut s, sink, c), [0.0; 3])
                }
                Layer::Visible if self.gathers() => {
                    // the lookup's path gives the light it sees directly
                    let ray = camera_ray(ctx.cam, cs.x, cs.y, &mut s);
                    let (sol, depth) = (self.radiosity.as_ref().unwrap(), self.gather_depth());
                    let (l, f) = gather::radiance_split::<N>(
                        ctx.scene,
                        sol,
                        ray,
                        &mut s,
                        &self.set,
                        depth,
                        &self.l_tilde::<N>(),
                        c,
                    );
                    (l.to_rgb(), f.to_rgb())
                }
                Layer::Visible => {
                    // f(ray) from a copy of the stream: the sample itself draws the same
                    // numbers
                    let ray = camera_ray(ctx.cam, cs.x, cs.y, &mut s.clone());
                    let f = visible::emission::<N>(ctx.scene, ray, self.set.max_segments(), c);
                    let mut no_splats = NoSplats;
                    let l = self.one::<N>(ctx, &cs, &mut s, &mut no_splats, c);
                    (l, f.to_rgb())
                }
                Layer::None | Layer::Direct => self.with_strategies::<N>(ctx, &cs, &mut s, sink, c),
            };
            sink.sample(cs.pixel, cs.index, v, part);
            if counts_rays {
                sink.rays(cs.pixel, c.rays - rays_before);
            }
        }
    }

    /// The path tracer's samples, [`path::BATCH_PATHS`] at a time through `Bvh::trace`;
    /// `PLAIN` when the scene's hits are plain ([`Scene::plain_hits`]).
    fn sample_batches<const N: usize, const PLAIN: bool>(
        &self,
        ctx: &SampleCtx,
        mut samples: impl Iterator<Item = CameraSample>,
        sink: &mut impl Sink,
        c: &mut Counters,
    ) {
        debug_assert!(matches!(self.set.kind, IntegratorKind::Path));
        let lt = self.l_tilde::<N>();
        let mut todo = [CameraSample {
            x: 0,
            y: 0,
            pixel: 0,
            index: 0,
        }; path::BATCH_PATHS];
        let mut streams = Vec::with_capacity(path::BATCH_PATHS);
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::ZERO); path::BATCH_PATHS];
        loop {
            let mut n = 0;
            for (t, cs) in todo.iter_mut().zip(samples.by_ref()) {
                *t = cs;
                n += 1;
            }
            if n == 0 {
                return;
            }
            streams.clear();
            streams.extend(todo[..n].iter().map(|cs| ctx.stream_of(cs)));
            for ((r, cs), s) in rays.iter_mut().zip(&todo[..n]).zip(streams.iter_mut()) {
                *r = camera_ray(ctx.cam, cs.x, cs.y, s);
            }
            let mut l = [crate::spectrum::Spectrum::<N>::ZERO; path::BATCH_PATHS];
            path::radiance_batch::<N, PLAIN>(
                ctx.scene,
                &rays[..n],
                &mut streams,
                &self.set,
                &lt,
                c,
                &mut l[..n],
            );
            for (cs, v) in todo[..n].iter().zip(&l[..n]) {
                sink.sample(cs.pixel, cs.index, v.to_rgb(), [0.0; 3]);
            }
            if n < path::BATCH_PATHS {
                return;
            }
        }
    }

    /// One BDPT sample whose strategies the sink reads, or whose emission seen directly
    /// it keeps apart ([`Layer::Direct`]): (value, emission seen directly). Other
    /// estimators: their sample and 0.
    fn with_strategies<const N: usize>(
        &self,
        ctx: &SampleCtx,
        cs: &CameraSample,
        s: &mut SampleStream,
        sink: &mut impl Sink,
        c: &mut Counters,
    ) -> ([f32; 3], [f32; 3]) {
        if self.set.kind != IntegratorKind::Bdpt {
            return (self.one::<N>(ctx, cs, s, sink, c), [0.0; 3]);
        }
        let wants = sink.wants_strategies();
        let mut direct = [0.0f32; 3];
        // (the strategies reach the sink after the sample: the splats hold it meanwhile)
        let mut strategies = Vec::new();
        let mut on_strategy = |st: StrategySample| {
            if st.direct {
                for (d, v) in direct.iter_mut().zip(st.weighted) {
                    *d += v;
                }
            }
            if wants {
                strategies.push(st);
            }
        };
        let index = cs.index;
        let mut to_sink = |p: Vec2, rgb: [f32; 3]| sink.splat(index, p, rgb);
        let l = bdpt::sample_pixel_with::<N>(
            ctx.scene,
            ctx.cam,
            cs.x,
            cs.y,
            s,
            &self.set,
            &self.bdpt,
            c,
            &mut to_sink,
            Some(&mut on_strategy),
        );
        for st in &strategies {
            sink.strategy(cs.pixel, st);
        }
        (l, direct)
    }

    /// One camera sample's value; its splats go to `sink`.
    #[inline]
    fn one<const N: usize>(
        &self,
        ctx: &SampleCtx,
        cs: &CameraSample,
        s: &mut SampleStream,
        sink: &mut impl Sink,
        c: &mut Counters,
    ) -> [f32; 3] {
        let (scene, cam, x, y) = (ctx.scene, ctx.cam, cs.x, cs.y);
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
                        self.gather_depth(),
                        &l_tilde(),
                        c,
                    )
                    .to_rgb(),
                    _ => path::radiance::<N>(scene, ray, s, &self.set, &l_tilde(), c).to_rgb(),
                }
            }
            IntegratorKind::Bdpt => {
                let index = cs.index;
                let mut to_sink = |p: Vec2, rgb: [f32; 3]| sink.splat(index, p, rgb);
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
                let _ = (scene, s, c);
                let to = Vec2::new(((x + 1) % cam.width) as f32 + 0.5, y as f32 + 0.5);
                sink.splat(cs.index, to, [x as f32, y as f32, 1.0]);
                [0.0; 3]
            }
        }
    }
}

/// The sink of a sample that must not splat ([`Layer::Visible`]: estimators that do not
/// splat).
struct NoSplats;

impl Sink for NoSplats {
    fn sample(&mut self, _: u32, _: u64, _: [f32; 3], _: [f32; 3]) {}
    fn splat(&mut self, _: u64, _: Vec2, _: [f32; 3]) {
        debug_assert!(false, "a split sample splatted");
    }
}

/// The camera ray of a sample of pixel (x, y): dimensions 0 and 1 place it on the film,
/// in the pixel (box filter) or drawn from the film's reconstruction filter around it.
#[inline]
pub fn camera_ray(cam: &Camera, x: u32, y: u32, s: &mut SampleStream) -> Ray {
    s.set_dimension(0);
    let p = cam.film_position(x, y, s.next_2d());
    cam.ray(p.x, p.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A solution that only the estimate roulette reads is meshed coarsely
    /// (`ROULETTE_ELEMENTS`); the gather's keeps the fine default; an explicit
    /// `--radiosity-max-area` wins over both.
    #[test]
    fn the_roulette_alone_reads_a_coarse_solution() {
        let scene = crate::scene::load("cornell").unwrap();
        let elements = |gather: Gather, max_area: Option<f32>| {
            let mut set = IntegratorSettings {
                gather,
                ..Default::default()
            };
            set.roulette.mode = RrMode::Estimate;
            set.roulette.estimate = RrEstimate::Radiosity;
            set.radiosity.max_area = max_area;
            // the mesh is what is tested: one shot solves enough
            set.radiosity.max_shots = Some(1);
            let i = Integrator::prepare(&scene, set, 3, &crate::progress::Silent).unwrap();
            i.radiosity.unwrap().stats.elements
        };
        let coarse = elements(Gather::Off, None);
        let fine = elements(Gather::Radiosity, None);
        assert!((100..400).contains(&coarse), "{coarse} elements");
        assert!(fine > 8 * coarse, "{fine} against {coarse} elements");
        assert_eq!(
            elements(Gather::Off, Some(0.02)),
            elements(Gather::Radiosity, Some(0.02))
        );
    }
}
