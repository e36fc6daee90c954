//! A render's statistics (`--stats`, Python's `result.stats`), built in one place for
//! every way a render runs (one process, or DTF's passes spread over a cluster).

use super::{Method, RenderJob};
use crate::filter::dtf::DtfParams;
use crate::integrator::{Counters, IntegratorKind};
use crate::options::name;
use crate::pipeline::{DtfRun, RenderSettings, RwStats};
use crate::sampling::SamplerKind;
use crate::scene::Scene;
use serde::Serialize;

/// Statistics of a render (`--stats`, Python's `result.stats`).
#[derive(Clone, Debug, Serialize)]
pub struct RenderStats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub first_sample: u64,
    pub seconds: f64,
    pub paths: u64,
    pub rays: u64,
    pub paths_per_second: f64,
    pub rays_per_second: f64,
    pub bvh_build_seconds: f64,
    pub load_seconds: f64,
    pub prepare_seconds: f64,
    pub rejected_samples: u64,
    pub rejected_nan: u64,
    pub rejected_infinite: u64,
    pub threads: usize,
    pub spectral: String,
    pub sampler: SamplerKind,
    pub dependent: bool,
    pub max_depth: i32,
    pub integrator: IntegratorKind,
    pub rr: crate::integrator::RrMode,
    pub rr_weight: crate::integrator::RrWeight,
    pub rr_min_depth: u32,
    pub bsdf_select: crate::integrator::BsdfSelect,
    pub seed: u64,
    pub method: Method,
    /// What `--method auto` chose and why, in one line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method_choice: Option<String>,
    pub interrupted: bool,
    /// Instruction set of the BVH traversal (`accel::Isa`: sse2, avx2).
    pub simd: &'static str,
    pub mean_rgb: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dtf: Option<DtfStats>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rw: Option<RwStats>,
}

/// DTF's share of the statistics.
#[derive(Clone, Debug, Serialize)]
pub struct DtfStats {
    pub n: u32,
    pub average_n: f64,
    pub phase1_seconds: f64,
    pub phase2_seconds: f64,
    pub filter_seconds: f64,
    pub filter_share: f64,
    pub average_region: f64,
    /// Over BDPT with `--dtf-light auto`: light paths traced for light tracing alone, the
    /// share of phase 2 they took, and phase 1's share of the variance in the splats.
    pub light_paths: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light_share: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub splat_variance_share: Option<f64>,
    pub params: DtfParams,
}

impl DtfStats {
    pub fn of(run: &DtfRun, params: &DtfParams) -> DtfStats {
        DtfStats {
            n: run.n,
            average_n: run.average_n(),
            phase1_seconds: run.phase1_seconds,
            phase2_seconds: run.phase2_seconds,
            filter_seconds: run.filter_seconds,
            filter_share: run.filter_seconds / run.seconds,
            average_region: run.out.region.iter().map(|&m| m as f64).sum::<f64>()
                / run.out.region.len().max(1) as f64,
            light_paths: run.light_paths,
            light_share: run.light_plan.map(|p| p.share),
            splat_variance_share: run.light_plan.map(|p| p.splat_variance_share),
            params: params.clone(),
        }
    }
}

/// What a method's run leaves for the statistics, beside the scene, job and settings.
pub struct RunFigures {
    pub counters: Counters,
    pub seconds: f64,
    pub spp: u32,
    pub interrupted: bool,
    pub prepare_seconds: f64,
    pub threads: usize,
    pub rejected: crate::film::Rejections,
    pub mean_rgb: [f64; 3],
    pub method_choice: Option<String>,
}

impl RenderStats {
    /// The statistics of `job` (its method made concrete) rendered on `scene` with `set`.
    pub fn new(
        scene: &Scene,
        job: &RenderJob,
        set: &RenderSettings,
        run: RunFigures,
        dtf: Option<DtfStats>,
        rw: Option<RwStats>,
    ) -> RenderStats {
        let (counters, seconds) = (run.counters, run.seconds);
        RenderStats {
            scene: scene.info.name.clone(),
            width: set.width,
            height: set.height,
            spp: run.spp,
            first_sample: job.first_sample,
            seconds,
            paths: counters.paths,
            rays: counters.rays,
            paths_per_second: counters.paths as f64 / seconds,
            rays_per_second: counters.rays as f64 / seconds,
            bvh_build_seconds: scene.info.bvh_seconds,
            load_seconds: scene.info.load_seconds,
            prepare_seconds: run.prepare_seconds,
            rejected_samples: run.rejected.total(),
            rejected_nan: run.rejected.nan,
            rejected_infinite: run.rejected.infinite,
            threads: run.threads,
            spectral: name(&set.spectral),
            sampler: job.sampler,
            dependent: job.dependent,
            max_depth: set.integrator.max_depth,
            integrator: set.integrator.kind,
            rr: job.roulette.mode,
            rr_weight: job.roulette.weight,
            rr_min_depth: set.integrator.roulette.min_depth.unwrap_or(0),
            bsdf_select: job.roulette.select,
            seed: job.seed,
            method: job.method,
            method_choice: run.method_choice,
            interrupted: run.interrupted,
            simd: scene.bvh.isa().name(),
            mean_rgb: run.mean_rgb,
            dtf,
            rw,
        }
    }
}
