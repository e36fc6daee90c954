//! `kalos render`: options, the render itself, image and statistics output.

use crate::film::Film;
use crate::image_io::{write_image, ExtraLayer, LayerData, RgbImage};
use crate::integrator::{IntegratorKind, IntegratorSettings, Roulette, RrMode};
use crate::pipeline::{render, Budget, RenderSettings};
use crate::sampling::{SamplerConfig, SamplerKind};
use crate::scene::CameraDesc;
use crate::spectrum::SpectralMode;
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;

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
    /// Russian roulette: classic | off.
    #[arg(long, default_value = "classic", value_parser = parse_rr)]
    pub rr: RrMode,
    /// Reflections before roulette starts (0: at every reflection).
    #[arg(long, default_value_t = 0)]
    pub rr_min_depth: u32,
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
    RrMode::parse(s).ok_or_else(|| format!("{s:?}: expected classic or off"))
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
    pub seed: u64,
    pub mean_rgb: [f64; 3],
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

pub fn run(a: RenderArgs) -> Result<(), String> {
    if a.spp == Some(0) {
        return Err("--spp: must be at least 1".into());
    }
    if !a.exposure.is_finite() {
        return Err(format!(
            "--exposure: {} is not a finite number of stops",
            a.exposure
        ));
    }
    crate::image_io::format_of(&a.output).map_err(|e| format!("-o/--output: {e}"))?;
    let scene = crate::scene::load(&a.scene)?;
    if !a.quiet {
        for w in &scene.warnings {
            eprintln!("kalos: warning: {w}");
        }
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
                min_depth: a.rr_min_depth,
            },
        },
    };
    let budget = match (a.time, a.spp) {
        (Some(t), _) => Budget::Time(t),
        (None, Some(n)) => Budget::Spp(n),
        (None, None) => Budget::Spp(scene.defaults.spp.unwrap_or(64)),
    };
    let pool = thread_pool(a.threads)?;
    let pb = progress_bar(a.quiet);
    let out = pool.install(|| render(&scene, &set, budget, Some(&pb)))?;
    write_film(&a.output, &out.film, a.exposure, a.aovs)?;
    let rej = out.film.rejected;
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
        spp: out.spp,
        seconds: out.seconds,
        paths: out.counters.paths,
        rays: out.counters.rays,
        paths_per_second: out.counters.paths as f64 / out.seconds,
        rays_per_second: out.counters.rays as f64 / out.seconds,
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
        seed: a.seed,
        mean_rgb: RgbImage::new(width, height, out.film.mean_rgb()).mean(),
    };
    if let Some(p) = &a.stats {
        let json = serde_json::to_string_pretty(&stats).map_err(|e| e.to_string())?;
        std::fs::write(p, json + "\n").map_err(|e| format!("--stats {}: {e}", p.display()))?;
    }
    if !a.quiet {
        eprintln!(
            "kalos: {} {}x{} {} spp in {:.2} s: {:.3} M paths/s, {:.2} M rays/s -> {}",
            stats.scene,
            width,
            height,
            stats.spp,
            stats.seconds,
            stats.paths_per_second * 1e-6,
            stats.rays_per_second * 1e-6,
            a.output.display()
        );
    }
    Ok(())
}

/// Write the film's mean image, with variance and count layers when asked.
pub fn write_film(
    path: &std::path::Path,
    film: &Film,
    exposure: f32,
    aovs: bool,
) -> Result<(), String> {
    let img = RgbImage::new(film.width, film.height, film.mean_rgb());
    let var = film.variance_rgb();
    let cnt = film.counts();
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
        ]
    } else {
        vec![]
    };
    write_image(path, &img, exposure, &extra)
}
