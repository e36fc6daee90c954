//! `kalos render`: options, the render itself, image and statistics output.

use crate::film::Film;
use crate::image_io::{write_image, ExtraLayer, LayerData, RgbImage};
use crate::integrator::{
    BsdfSelect, IntegratorKind, IntegratorSettings, Roulette, RrMode, RrWeight,
};
use crate::pipeline::{render, Budget, RenderSettings};
use crate::sampling::{SamplerConfig, SamplerKind};
use crate::scene::CameraDesc;
use crate::spectrum::SpectralMode;
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Built-in scene name (see `kalos scenes`), .obj or .toml file.
    pub scene: String,
    /// Output image: .exr (linear), .pfm (linear) or .png (sRGB).
    #[arg(short, long, default_value = "out.exr")]
    pub output: PathBuf,
    /// Samples per pixel (default 64, or the scene file's).
    #[arg(long, conflicts_with = "time")]
    pub spp: Option<u32>,
    /// Render for this many seconds (whole passes) instead of a fixed spp.
    #[arg(long, value_parser = parse_seconds)]
    pub time: Option<f64>,
    /// Resolution WxH (default: the scene's).
    #[arg(long, value_parser = parse_res)]
    pub res: Option<(u32, u32)>,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// random | sobol (Owen-scrambled).
    #[arg(long, default_value = "random", value_parser = parse_sampler)]
    pub sampler: SamplerKind,
    /// All pixels use the same random numbers per sample index (dependent tests).
    #[arg(long)]
    pub dependent: bool,
    /// rgb | 8 | 16 spectral bands.
    #[arg(long, default_value = "rgb", value_parser = parse_spectral)]
    pub spectral: SpectralMode,
    /// Estimator: path.
    #[arg(long, default_value = "path", value_parser = parse_integrator)]
    pub integrator: IntegratorKind,
    /// Mitsuba's max_depth: 1 = emitters seen directly, 2 = direct light, -1 = unlimited.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_depth)]
    pub max_depth: Option<i32>,
    /// Russian roulette: classic | spectral | estimate | spectral-estimate | off.
    #[arg(long, default_value = "classic", value_parser = parse_rr)]
    pub rr: RrMode,
    /// Wavelength weights h of the roulette: luminance | flat.
    #[arg(long, default_value = "luminance", value_parser = parse_rr_weight)]
    pub rr_weight: RrWeight,
    /// Reflections before roulette starts (0: at every reflection).
    #[arg(long, default_value_t = 0)]
    pub rr_min_depth: u32,
    /// Lobe selection of combined BRDFs: mixture | decompose | static | mis (the roulette
    /// paper's methods 1, 2, 3, with termination folded in).
    #[arg(long, default_value = "mixture", value_parser = parse_bsdf_select)]
    pub bsdf_select: BsdfSelect,
    /// Camera "ox,oy,oz,tx,ty,tz,ux,uy,uz,fov" (overrides the scene's).
    #[arg(long, allow_hyphen_values = true, value_parser = CameraDesc::parse)]
    pub camera: Option<CameraDesc>,
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Write per-pixel variance and sample count as extra EXR layers.
    #[arg(long)]
    pub aovs: bool,
    /// Write render statistics as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// No progress bar or summary.
    #[arg(short, long)]
    pub quiet: bool,
    /// Rendering method: plain (same spp everywhere) or dtf (dependent-tests driven filtering).
    #[arg(long, default_value = "plain", value_parser = ["plain", "dtf"])]
    pub method: String,
    /// DTF: dependent samples per pixel n in phase 1.
    #[arg(long, default_value_t = 50)]
    pub dtf_n: u32,
    /// DTF: prescribed relative error eps_r (used when neither --spp nor --time is given).
    #[arg(long, default_value_t = 0.03)]
    pub dtf_eps: f32,
    /// DTF: largest region side m_max.
    #[arg(long, default_value_t = 4)]
    pub dtf_mmax: u32,
    /// DTF: minimal decrease Delta f[0]_min of the primary weight to grow a region.
    #[arg(long, default_value_t = 0.01)]
    pub dtf_df0: f32,
    /// DTF: distance kernel d: pyramid (the paper's) or gaussian.
    #[arg(long, default_value = "pyramid", value_parser = ["pyramid", "gaussian"])]
    pub dtf_kernel: String,
    /// DTF: negative-weight removal: active-set (exact, vanishes as N grows) or paper (as printed).
    #[arg(long, default_value = "active-set", value_parser = ["active-set", "paper"])]
    pub dtf_clamp: String,
    /// DTF: sample categories for N, comma-separated, increasing.
    #[arg(long, value_delimiter = ',')]
    pub dtf_categories: Option<Vec<u32>>,
    /// DTF: floors of sigma and ||C_d|| for the allocation, as shares of their image means
    /// (0 = the paper's raw formula, which can starve pixels whose dependent samples agreed).
    #[arg(long, default_value_t = 0.05)]
    pub dtf_floor: f32,
    /// DTF with --dtf-eps: floor of sigma as a share of the pixel's own ||C_d|| (0 = none),
    /// i.e. at least (3 F / eps_r)^2 samples per pixel: a pixel whose samples all agreed may
    /// have missed a thin feature (a sliver of the light) in every one of them.
    #[arg(long, default_value_t = 0.1)]
    pub dtf_rel_floor: f32,
    /// DTF budget mode: clip the allocation weights at this multiple of their median (0 = no
    /// clipping).
    #[arg(long, default_value_t = 16.0)]
    pub dtf_max_ratio: f32,
    /// DTF budget mode: share of the budget per pixel: mse (N ∝ sigma, least squared
    /// error), paper (N ∝ sigma^2/||C_d||, the paper's) or relmse (N ∝ sigma/||C_d||).
    #[arg(long, default_value = "mse", value_parser = ["mse", "paper", "relmse"])]
    pub dtf_alloc: String,
    /// DTF budget mode: ignore the per-pixel sample cost (rays per sample, measured in
    /// phase 1) in the mse/relmse allocations.
    #[arg(long)]
    pub dtf_no_cost: bool,
    /// DTF: a region stops growing at a neighbour whose N exceeds this multiple of the
    /// pixel's own (1 = the paper's rule "N[p] < N[q]"; 2.5 tolerates one category step).
    #[arg(long, default_value_t = 2.5)]
    pub dtf_stop_ratio: f32,
    /// DTF: a neighbour's colour difference Delta_q is at least what phase 2 shows beyond
    /// this many standard errors (0 = off: Delta from the dependent phase alone, as printed).
    #[arg(long, default_value_t = 3.0)]
    pub dtf_guard: f32,
    /// DTF: top-up rounds from the statistics of all samples so far (both phases): with
    /// --dtf-eps for pixels that miss eps_r; with --spp/--time one round that shares
    /// --dtf-topup of phase 2's budget again (0 = the paper's single allocation).
    #[arg(long, default_value_t = 2)]
    pub dtf_rounds: u32,
    /// DTF budget modes: share of phase 2's samples held back for the top-up round.
    #[arg(long, default_value_t = 0.25)]
    pub dtf_topup: f32,
    /// DTF: write the intermediate images beside the output (dependent, independent,
    /// filtered, combined, N and M maps).
    #[arg(long)]
    pub dtf_layers: bool,
}

impl RenderArgs {
    /// The DTF parameters these options give.
    pub fn dtf_params(&self) -> crate::filter::dtf::DtfParams {
        use crate::filter::dtf::{Allocation, Clamp, DtfParams, Kernel};
        let d = DtfParams::default();
        DtfParams {
            n: self.dtf_n,
            eps_r: self.dtf_eps,
            categories: self.dtf_categories.clone().unwrap_or(d.categories),
            m_max: self.dtf_mmax,
            df0_min: self.dtf_df0,
            kernel: if self.dtf_kernel == "gaussian" {
                Kernel::Gaussian
            } else {
                Kernel::Pyramid
            },
            clamp: if self.dtf_clamp == "paper" {
                Clamp::Paper
            } else {
                Clamp::ActiveSet
            },
            sigma_floor: self.dtf_floor,
            norm_floor: self.dtf_floor,
            relative_sigma_floor: self.dtf_rel_floor,
            max_weight_ratio: self.dtf_max_ratio,
            allocation: match self.dtf_alloc.as_str() {
                "paper" => Allocation::Paper,
                "relmse" => Allocation::RelMse,
                _ => Allocation::Mse,
            },
            cost_aware: !self.dtf_no_cost,
            stop_ratio: self.dtf_stop_ratio,
            guard: self.dtf_guard,
            top_up_rounds: self.dtf_rounds,
            top_up_share: self.dtf_topup,
        }
    }
}

fn parse_res(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{s:?} is not WxH"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("{s:?}: width is not a whole number"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("{s:?}: height is not a whole number"))?;
    crate::film::check_resolution(w, h)?;
    Ok((w, h))
}
fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a number of seconds"))?;
    if !(v > 0.0 && v.is_finite()) {
        return Err("must be a positive number of seconds".into());
    }
    Ok(v)
}
fn parse_sampler(s: &str) -> Result<SamplerKind, String> {
    SamplerKind::parse(s).ok_or_else(|| format!("{s:?}: expected random or sobol"))
}
fn parse_spectral(s: &str) -> Result<SpectralMode, String> {
    SpectralMode::parse(s).ok_or_else(|| format!("{s:?}: expected rgb, 8 or 16"))
}
fn parse_integrator(s: &str) -> Result<IntegratorKind, String> {
    IntegratorKind::parse(s).ok_or_else(|| format!("{s:?}: expected path"))
}
fn parse_rr(s: &str) -> Result<RrMode, String> {
    RrMode::parse(s).ok_or_else(|| {
        format!("{s:?}: expected classic, spectral, estimate, spectral-estimate or off")
    })
}
fn parse_rr_weight(s: &str) -> Result<RrWeight, String> {
    RrWeight::parse(s).ok_or_else(|| format!("{s:?}: expected luminance or flat"))
}
fn parse_bsdf_select(s: &str) -> Result<BsdfSelect, String> {
    BsdfSelect::parse(s).ok_or_else(|| format!("{s:?}: expected mixture, decompose, static or mis"))
}
fn parse_depth(s: &str) -> Result<i32, String> {
    let d: i32 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a whole number"))?;
    if d < -1 || d == 0 {
        return Err("must be -1 (unlimited) or at least 1".into());
    }
    Ok(d)
}

/// Statistics written by `--stats`.
#[derive(serde::Serialize)]
pub struct RenderStats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seconds: f64,
    pub paths: u64,
    pub rays: u64,
    pub paths_per_second: f64,
    pub rays_per_second: f64,
    pub bvh_build_seconds: f64,
    pub load_seconds: f64,
    pub rejected_samples: u64,
    pub rejected_nan: u64,
    pub rejected_infinite: u64,
    pub threads: usize,
    pub spectral: &'static str,
    pub sampler: SamplerKind,
    pub dependent: bool,
    pub max_depth: i32,
    pub rr: RrMode,
    pub rr_weight: RrWeight,
    pub rr_min_depth: u32,
    pub bsdf_select: BsdfSelect,
    pub seed: u64,
    pub method: String,
    pub mean_rgb: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dtf: Option<DtfStats>,
}

/// DTF's share of the statistics.
#[derive(serde::Serialize)]
pub struct DtfStats {
    pub n: u32,
    pub average_n: f64,
    pub phase1_seconds: f64,
    pub phase2_seconds: f64,
    pub filter_seconds: f64,
    pub filter_share: f64,
    pub average_region: f64,
    pub params: crate::filter::dtf::DtfParams,
}

pub fn progress_bar(quiet: bool) -> ProgressBar {
    let pb = ProgressBar::new(1);
    if quiet || !std::io::stderr().is_terminal() {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    } else {
        pb.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% ETA {eta} {per_sec}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
    }
    pb
}

/// A thread pool of the requested size.
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    if threads == Some(0) {
        return Err("--threads: must be at least 1".into());
    }
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        b = b.num_threads(t);
    }
    b.build().map_err(|e| format!("--threads: {e}"))
}

/// A finished render, before anything is written.
pub struct Rendered {
    /// The displayed image (plain: the film's mean; dtf: the combined image).
    pub image: RgbImage,
    /// All samples taken (for dtf: both phases merged), for the AOV layers.
    pub film: Film,
    pub stats: RenderStats,
    pub dtf: Option<crate::pipeline::DtfRun>,
}

/// Render the scene `a.scene` (already loaded) as the options say.
pub fn execute(a: &RenderArgs, scene: &crate::scene::Scene) -> Result<Rendered, String> {
    if a.spp == Some(0) {
        return Err("--spp: must be at least 1".into());
    }
    if !a.exposure.is_finite() {
        return Err(format!(
            "--exposure: {} is not a finite number of stops",
            a.exposure
        ));
    }
    let (width, height) = a.res.or(scene.defaults.res).unwrap_or((256, 256));
    let set = RenderSettings {
        width,
        height,
        camera: a.camera.unwrap_or(scene.camera),
        spectral: a.spectral,
        sampler: SamplerConfig {
            kind: a.sampler,
            seed: a.seed,
            dependent: a.dependent,
        },
        integrator: IntegratorSettings {
            kind: a.integrator,
            max_depth: a.max_depth.or(scene.defaults.max_depth).unwrap_or(-1),
            roulette: Roulette {
                mode: a.rr,
                weight: a.rr_weight,
                select: a.bsdf_select,
                min_depth: a.rr_min_depth,
            },
        },
    };
    let pool = thread_pool(a.threads)?;
    let pb = progress_bar(a.quiet);
    let (film, image, counters, seconds, spp, dtf, dtf_run) = if a.method == "dtf" {
        use crate::pipeline::{render_dtf, DtfBudget};
        let params = a.dtf_params();
        let budget = match (a.time, a.spp) {
            (Some(t), _) => DtfBudget::Time(t),
            (None, Some(n)) => DtfBudget::Spp(n as f64),
            (None, None) => DtfBudget::RelativeError,
        };
        let run = pool.install(|| render_dtf(scene, &set, &params, budget, Some(&pb)))?;
        let mut film = run.independent.clone();
        film.merge(&run.dependent);
        let stats = DtfStats {
            n: params.n,
            average_n: run.average_n(),
            phase1_seconds: run.phase1_seconds,
            phase2_seconds: run.phase2_seconds,
            filter_seconds: run.filter_seconds,
            filter_share: run.filter_seconds / run.seconds,
            average_region: run.out.region.iter().map(|&m| m as f64).sum::<f64>()
                / run.out.region.len() as f64,
            params,
        };
        let spp = (film.total_samples() as f64 / (width as f64 * height as f64)).round() as u32;
        let image = run.out.combined.clone();
        (
            film,
            image,
            run.counters,
            run.seconds,
            spp,
            Some(stats),
            Some(run),
        )
    } else {
        let budget = match (a.time, a.spp) {
            (Some(t), _) => Budget::Time(t),
            (None, Some(n)) => Budget::Spp(n),
            (None, None) => Budget::Spp(scene.defaults.spp.unwrap_or(64)),
        };
        let out = pool.install(|| render(scene, &set, budget, Some(&pb)))?;
        let img = RgbImage::new(width, height, out.film.mean_rgb());
        (
            out.film,
            img,
            out.counters,
            out.seconds,
            out.spp,
            None,
            None,
        )
    };
    let rej = film.rejected;
    if rej.total() > 0 {
        eprintln!(
            "kalos: warning: rejected {} samples ({} NaN, {} infinite); they are not in the image",
            rej.total(),
            rej.nan,
            rej.infinite
        );
    }
    let stats = RenderStats {
        scene: scene.info.name.clone(),
        width,
        height,
        spp,
        seconds,
        paths: counters.paths,
        rays: counters.rays,
        paths_per_second: counters.paths as f64 / seconds,
        rays_per_second: counters.rays as f64 / seconds,
        bvh_build_seconds: scene.info.bvh_seconds,
        load_seconds: scene.info.load_seconds,
        rejected_samples: rej.total(),
        rejected_nan: rej.nan,
        rejected_infinite: rej.infinite,
        threads: pool.current_num_threads(),
        spectral: set.spectral.name(),
        sampler: a.sampler,
        dependent: a.dependent,
        max_depth: set.integrator.max_depth,
        rr: a.rr,
        rr_weight: a.rr_weight,
        rr_min_depth: a.rr_min_depth,
        bsdf_select: a.bsdf_select,
        seed: a.seed,
        method: a.method.clone(),
        mean_rgb: image.mean(),
        dtf,
    };
    Ok(Rendered {
        image,
        film,
        stats,
        dtf: dtf_run,
    })
}

/// `kalos render`: load, render, write the image, layers and statistics.
pub fn run(a: RenderArgs) -> Result<(), String> {
    crate::image_io::format_of(&a.output).map_err(|e| format!("-o/--output: {e}"))?;
    let scene = crate::scene::load(&a.scene)?;
    if !a.quiet {
        for w in &scene.warnings {
            eprintln!("kalos: warning: {w}");
        }
    }
    let r = execute(&a, &scene)?;
    write_output(&a.output, &r.image, &r.film, a.exposure, a.aovs)?;
    if let (true, Some(run)) = (a.dtf_layers, &r.dtf) {
        write_dtf_layers(&a.output, run, a.exposure)?;
    }
    let stats = &r.stats;
    if let Some(p) = &a.stats {
        let json = serde_json::to_string_pretty(stats).map_err(|e| e.to_string())?;
        std::fs::write(p, json + "\n").map_err(|e| format!("--stats {}: {e}", p.display()))?;
    }
    if !a.quiet {
        eprintln!(
            "kalos: {} {}x{} {} spp in {:.2} s: {:.3} M paths/s, {:.2} M rays/s -> {}",
            stats.scene,
            stats.width,
            stats.height,
            stats.spp,
            stats.seconds,
            stats.paths_per_second * 1e-6,
            stats.rays_per_second * 1e-6,
            a.output.display()
        );
    }
    Ok(())
}

/// Write the displayed image, with the film's variance and count layers when asked.
pub fn write_output(
    path: &Path,
    img: &RgbImage,
    film: &Film,
    exposure: f32,
    aovs: bool,
) -> Result<(), String> {
    let var = film.variance_rgb();
    let cnt = film.counts();
    // 1 where a channel of the pixel's estimate is negative (the estimate roulette can
    // make it so; the roulette paper's figure 4, right).
    let neg: Vec<f32> = if aovs {
        img.data
            .iter()
            .map(|p| if p.iter().any(|&v| v < 0.0) { 1.0 } else { 0.0 })
            .collect()
    } else {
        vec![]
    };
    let extra = if aovs {
        vec![
            ExtraLayer {
                name: "variance",
                channels: LayerData::Rgb(&var),
            },
            ExtraLayer {
                name: "count",
                channels: LayerData::Mono(&cnt),
            },
            ExtraLayer {
                name: "negative",
                channels: LayerData::Mono(&neg),
            },
        ]
    } else {
        vec![]
    };
    write_image(path, img, exposure, &extra)
}

/// `out.exr` -> `out-NAME.exr` (same folder and extension).
pub fn sibling(path: &Path, name: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("out");
    let ext = path.extension().and_then(|s| s.to_str()).unwrap_or("exr");
    path.with_file_name(format!("{stem}-{name}.{ext}"))
}

/// The paper's figure 2 as files: dependent, independent, filtered, combined, and maps of
/// N and of the region size M (maps are normalised to their maximum in PNG output).
fn write_dtf_layers(
    path: &Path,
    run: &crate::pipeline::DtfRun,
    exposure: f32,
) -> Result<(), String> {
    let (w, h) = (run.out.width, run.out.height);
    let images = [
        ("dependent", RgbImage::new(w, h, run.dependent.mean_rgb())),
        (
            "independent",
            RgbImage::new(w, h, run.independent.mean_rgb()),
        ),
        ("filtered", run.out.filtered.clone()),
        ("combined", run.out.combined.clone()),
    ];
    for (name, img) in &images {
        write_image(&sibling(path, name), img, exposure, &[])?;
    }
    let png = crate::image_io::format_of(path)? == crate::image_io::Format::Png;
    let map = |v: Vec<f32>| {
        let k = if png {
            1.0 / v.iter().cloned().fold(1e-9f32, f32::max)
        } else {
            1.0
        };
        RgbImage::new(w, h, v.iter().map(|&x| [x * k; 3]).collect())
    };
    write_image(
        &sibling(path, "N"),
        &map(run.alloc.iter().map(|&n| n as f32).collect()),
        0.0,
        &[],
    )?;
    write_image(
        &sibling(path, "M"),
        &map(run.out.region.iter().map(|&m| m as f32).collect()),
        0.0,
        &[],
    )?;
    Ok(())
}
