//! The library's entry point: a serde-(de)serialisable `RenderJob` (what to render and
//! how) and `render(&job, &progress) -> Rendered` (film, image, statistics). The CLI,
//! `kalos experiment`, the examples, the tests and the Python module all go through it.
//!
//! ```text
//! RenderJob -> scene::load -> Integrator::prepare(&Scene, settings)
//!           -> pipeline (plain passes | dtf phases) -> Film -> image + stats
//! ```

use crate::film::Film;
use crate::filter::dtf::DtfParams;
use crate::image_io::RgbImage;
use crate::integrator::{Gather, IntegratorKind, IntegratorSettings, MisHeuristic, Roulette};
use crate::options::{
    name, parse_define, parse_depth, parse_res, parse_seconds, parse_spp, parse_threads,
};
use crate::pipeline::{self, DtfRun, Progress, RenderSettings, RwParams, RwRun};
use crate::radiosity::RadiositySettings;
use crate::sampling::{SamplerConfig, SamplerKind};
use crate::scene::{CameraDesc, Scene};
use crate::spectrum::SpectralMode;
use serde::{Deserialize, Serialize};

mod run;
mod stats;
pub use run::{default_spp, render_dtf_part, render_dtf_with, render_scene, JobBudget};
pub use stats::{DtfStats, RenderStats, RunFigures};

/// Rendering method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Chosen for the scene and budget: a short pilot measures each estimator's
    /// efficiency, then dependent-tests driven filtering over the better one, or plain
    /// rendering where the budget is too small for it (or the output is a film file).
    /// Naming an estimator (here, in the scene file or in Python) renders plainly with it.
    #[default]
    Auto,
    /// The same number of samples in every pixel.
    Plain,
    /// Dependent-tests driven filtering (Csonka et al.).
    Dtf,
    /// Rushmeier and Ward: pilot sample, trials until convergence, energy-preserving filter.
    Rw,
}

/// Samples per pixel of a plain render when neither the job nor the scene file says.
pub const DEFAULT_SPP: u32 = 64;
/// Resolution when neither the job nor the scene file says.
pub const DEFAULT_RES: (u32, u32) = (256, 256);
/// Renders planned with at least this many samples say so before they start.
pub const LARGE_RENDER_SAMPLES: u64 = 1 << 30;
/// Worker threads are capped at this multiple of the logical CPUs.
pub const MAX_THREADS_PER_CPU: usize = 4;

/// Everything that decides a render: scene, camera and resolution overrides, method,
/// estimator, sampler, roulette, budget, seed, first sample index and threads. Each
/// option's name, help and default is written here once (clap attributes); `Default`
/// parses an empty command line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct RenderJob {
    /// Built-in scene name (see `kalos scenes`), .obj, .toml or Mitsuba .xml file (the CLI's positional
    /// argument).
    #[arg(skip)]
    pub scene: String,
    /// A parameter of a Mitsuba .xml scene, as Mitsuba's `-D key=value`: it replaces the
    /// file's `<default name="key">` (repeatable; a name the file does not use is an error).
    #[arg(short = 'D', long = "define", value_name = "KEY=VALUE", value_parser = parse_define)]
    pub defines: Vec<(String, String)>,
    /// Samples per pixel (default 64, or the scene file's).
    #[arg(long, conflicts_with = "time", value_parser = parse_spp)]
    pub spp: Option<u32>,
    /// Render for this many seconds instead of a fixed spp: the estimator's preprocess
    /// (radiosity solve, L~ walk) included, then whole passes.
    #[arg(long, value_parser = parse_seconds)]
    pub time: Option<f64>,
    /// Resolution WxH (default: the scene's, else 256x256).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_res)]
    pub res: Option<(u32, u32)>,
    /// Camera "ox,oy,oz,tx,ty,tz,ux,uy,uz,fov" (overrides the scene's).
    #[arg(long, allow_hyphen_values = true, value_parser = CameraDesc::parse)]
    pub camera: Option<CameraDesc>,
    /// Rendering method: auto (chosen from a pilot), plain (same spp everywhere), dtf
    /// (dependent-tests driven filtering) or rw (Rushmeier and Ward).
    #[arg(long, value_enum, default_value_t = Method::Auto)]
    pub method: Method,
    /// Estimator (default: the scene file's, e.g. a Mitsuba `<integrator type="bdpt">`,
    /// else path).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorKind>,
    /// A filter on the finished image: energy (Rushmeier and Ward's energy-preserving
    /// filter, with --rw-d and --rw-t; Lt_vis from the image's mean, S_p and M from the
    /// film). `--method rw` ends with it already.
    #[arg(long = "filter", value_enum)]
    pub post_filter: Option<PostFilter>,
    /// BDPT: weighting of the strategies: balance (Veach's) or power (exponent 2).
    #[arg(long, value_enum, default_value_t = MisHeuristic::Balance)]
    pub bdpt_mis: MisHeuristic,
    /// The path tracer's diffuse indirect light: off (traced) or radiosity (Rushmeier and
    /// Ward: looked up in a radiosity solution computed before the render). Default:
    /// radiosity with --method rw (where the scene allows a solution), else off.
    #[arg(long, value_enum)]
    pub gather: Option<Gather>,
    /// Diffuse reflections before the gather looks up (1: the paper's first diffuse
    /// bounce). Default: chosen by a pilot under --method rw (the depth whose predicted
    /// error at the budget is least), else 1.
    #[arg(long)]
    pub gather_depth: Option<u32>,
    /// Rays each gather point casts for its diffuse lookup (Chen et al.'s final gather; 1:
    /// the paper's one path per trial).
    #[arg(long, default_value_t = crate::integrator::gather::DEFAULT_GATHER_RAYS)]
    pub gather_rays: u32,
    #[command(flatten)]
    pub radiosity: RadiositySettings,
    /// Mitsuba's max_depth: 1 = emitters seen directly, 2 = direct light, -1 = unlimited
    /// (default: the scene file's, else -1).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_depth)]
    pub max_depth: Option<i32>,
    /// Spectral bands: rgb | 8 | 16.
    #[arg(long, value_enum, default_value_t = SpectralMode::Rgb)]
    pub spectral: SpectralMode,
    /// Sampler: sobol (Owen-scrambled) | random.
    #[arg(long, value_enum, default_value_t = SamplerKind::default())]
    pub sampler: SamplerKind,
    /// All pixels use the same random numbers per sample index (dependent tests).
    #[arg(long)]
    pub dependent: bool,
    #[command(flatten)]
    pub roulette: Roulette,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Index of the first sample (a shard of a render takes samples first..first+spp).
    #[arg(long, default_value_t = 0)]
    pub first_sample: u64,
    /// Worker threads (default: all cores; capped at 4x the logical CPUs).
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub dtf: DtfParams,
    #[command(flatten)]
    pub rw: RwParams,
}

impl Default for RenderJob {
    fn default() -> Self {
        crate::options::defaults::<RenderJob>()
    }
}

impl RenderJob {
    /// A job for `scene` with every other option at its default.
    pub fn new(scene: &str) -> RenderJob {
        RenderJob {
            scene: scene.to_string(),
            ..Default::default()
        }
    }

    /// What two film parts must share to merge: the job without its sample range,
    /// budget and threads, as JSON, its scene named by the hash of the files it was read
    /// from (`Scene::content_hash`), not by their path: `s.xml` and `./s.xml` merge, the
    /// parts of a scene edited between them do not.
    pub fn key(&self, content_hash: u64) -> String {
        let mut j = self.clone();
        j.scene = format!("content {content_hash:016x}");
        j.first_sample = 0;
        j.spp = None;
        j.time = None;
        j.threads = None;
        serde_json::to_string(&j).unwrap_or_default()
    }

    /// The estimator: the job's, else the scene file's, else the path tracer.
    pub fn integrator_for(&self, scene: &Scene) -> IntegratorKind {
        self.integrator
            .or(scene.defaults.integrator)
            .unwrap_or_default()
    }

    /// The settings that decide a sample's value, for this scene.
    pub fn settings(&self, scene: &Scene) -> RenderSettings {
        let (width, height) = self.res.or(scene.defaults.res).unwrap_or(DEFAULT_RES);
        let mut set = RenderSettings {
            width,
            height,
            camera: self
                .camera
                .map_or(scene.camera, |c| c.on_film_of(&scene.camera)),
            spectral: self.spectral,
            sampler: SamplerConfig {
                kind: self.sampler,
                seed: self.seed,
                dependent: self.dependent,
            },
            integrator: IntegratorSettings {
                kind: self.integrator_for(scene),
                max_depth: self.max_depth.or(scene.defaults.max_depth).unwrap_or(-1),
                roulette: Roulette {
                    min_depth: Some(
                        self.roulette
                            .min_depth
                            .or(scene.defaults.rr_min_depth)
                            .unwrap_or(crate::integrator::rr::DEFAULT_MIN_DEPTH),
                    ),
                    ..self.roulette
                },
                gather: Gather::Off,
                gather_depth: self.gather_depth,
                gather_rays: self.gather_rays,
                radiosity: self.radiosity,
                mis: self.bdpt_mis,
            },
        };
        set.integrator.gather = self.gather.unwrap_or_else(|| {
            Gather::default_for(self.method == Method::Rw, &set.integrator, scene)
        });
        set
    }

    /// Refuse contradictory or unusable settings.
    pub fn validate(&self) -> Result<(), String> {
        if self.spp == Some(0) {
            return Err("--spp: must be at least 1".into());
        }
        if self.threads == Some(0) {
            return Err("--threads: must be at least 1".into());
        }
        if self.post_filter == Some(PostFilter::Energy) && self.method == Method::Rw {
            return Err("--filter energy: --method rw ends with the energy filter already".into());
        }
        if self.spp.is_some() && self.time.is_some() {
            return Err("--spp and --time: give one budget, not both".into());
        }
        if let Some(t) = self.time {
            if !(t > 0.0 && t.is_finite()) {
                return Err(format!("--time {t}: must be a positive number of seconds"));
            }
        }
        // the film's sample range first..first + spp is 64-bit; it must not wrap
        let most = self.spp.unwrap_or(u32::MAX) as u64;
        if self.first_sample.checked_add(most).is_none() {
            return Err(format!(
                "--first-sample {}: samples {}..+{most} would pass the last sample index (2^64 - 1)",
                self.first_sample, self.first_sample
            ));
        }
        // (checked whatever the method or estimator, so a bad --rw-d, --dtf-z or
        // --radiosity-tolerance is never silently ignored)
        self.dtf.validate()?;
        self.rw.validate()?;
        self.radiosity.validate()?;
        Ok(())
    }
}

/// A finished render.
pub struct Rendered {
    /// The displayed image (plain: the film's values; dtf: the combined image).
    pub image: RgbImage,
    /// All samples taken (for dtf: both phases merged), for AOVs and film files.
    pub film: Film,
    pub stats: RenderStats,
    /// DTF's phases and maps (`--dtf-layers`).
    pub dtf: Option<DtfRun>,
    /// RW's trials, filter output and maps (`--rw-layers`).
    pub rw: Option<RwRun>,
    /// Things the user should know (the scene's warnings, capped threads, a black image).
    pub warnings: Vec<String>,
    /// The film's merge key (`RenderJob::key` of the job and the scene's content).
    pub key: String,
}

impl Rendered {
    /// The film file of a plain render of `job`: its film, job, key and sample range.
    /// With a time budget the last, partial pass gave some pixels one sample more than
    /// `stats.spp`; the range holds it.
    pub fn film_file(&self, job: &RenderJob) -> crate::film::FilmFile {
        let first = job.first_sample;
        let most = self.film.pixels.iter().map(|p| p.n).max().unwrap_or(0);
        let spp = self.stats.spp.max(most) as u64;
        crate::film::FilmFile {
            job: serde_json::to_string(job).unwrap_or_default(),
            key: self.key.clone(),
            ranges: vec![(first, first + spp)],
            film: self.film.clone(),
        }
    }
}

/// A thread pool of the requested size, capped at `MAX_THREADS_PER_CPU` x the CPUs.
pub fn thread_pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, Option<String>), String> {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut warning = None;
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        if t == 0 {
            return Err("--threads: must be at least 1".into());
        }
        let cap = MAX_THREADS_PER_CPU * cpus;
        let t = if t > cap {
            warning = Some(format!(
                "--threads {t}: capped at {cap} ({MAX_THREADS_PER_CPU} x the {cpus} logical CPUs)"
            ));
            cap
        } else {
            t
        };
        b = b.num_threads(t);
    }
    let pool = b.build().map_err(|e| format!("--threads: {e}"))?;
    Ok((pool, warning))
}

/// Load the job's scene and render it.
pub fn render(job: &RenderJob, progress: &dyn Progress) -> Result<Rendered, String> {
    job.validate()?;
    let scene = crate::scene::load_with(&job.scene, &job.defines)?;
    let mut r = render_scene(&scene, job, progress)?;
    let mut w = scene.warnings_for(job.camera.is_some());
    w.append(&mut r.warnings);
    r.warnings = w;
    Ok(r)
}

/// Least samples per pixel a budget must allow for `--method auto` to choose DTF (its
/// dependent phase takes n = 8 of them at 16: `DtfParams::n_for`).
pub const AUTO_DTF_MIN_SPP: f64 = 16.0;

/// The relative standard error below which `--method auto`'s DTF keeps a pixel's own mean
/// (`DtfParams::keep_converged`): well under the 5% a perceptual error counts, so a kept
/// pixel is rarely off by that much.
pub const AUTO_KEEP_CONVERGED: f32 = 0.02;

/// `--method auto` made concrete: the job to render (its method and estimator named) and
/// the line that says what was chosen and why; a job that names its method is returned as
/// it is, with no line. The estimator comes from the pilot (`pipeline::auto`) unless the
/// job or the scene file names one; DTF is chosen over it where the budget allows
/// `AUTO_DTF_MIN_SPP` samples per pixel and the pilot predicts that plain rendering would
/// leave enough pixels perceptibly off (`pipeline::auto::dtf_helps`), plain rendering
/// elsewhere.
pub fn choose_method(
    scene: &Scene,
    job: &RenderJob,
    set: &RenderSettings,
    progress: &dyn Progress,
) -> Result<(RenderJob, Option<String>), String> {
    if job.method != Method::Auto {
        return Ok((job.clone(), None));
    }
    let mut j = job.clone();
    j.method = Method::Plain;
    let named = if job.integrator.is_some() {
        Some("--integrator names the estimator")
    } else if scene.defaults.integrator.is_some() {
        Some("the scene file names its integrator")
    } else if job.gather.is_some() {
        Some("--gather names the path tracer's gather")
    } else if job.post_filter.is_some() {
        Some("--filter filters a plain render")
    } else if job.first_sample != 0 {
        Some("--first-sample renders a shard of a plain render")
    } else if scene.lights.is_empty() {
        Some("the scene has no emitter")
    } else {
        None
    };
    if let Some(why) = named {
        let kind = name(&job.integrator_for(scene));
        return Ok((j, Some(format!("plain {kind}: {why}"))));
    }
    // (a candidate that cannot render with the job's other options is left out: BDPT
    // without a roulette or a depth; the path tracer's error, if it has one, is the job's)
    let mut pilots = vec![pipeline::auto::pilot(scene, set, IntegratorKind::Path)?];
    // (and BDPT with a camera its light paths cannot reach: an orthographic sensor)
    if set.camera.for_light_paths().is_ok() {
        if let Ok(p) = pipeline::auto::pilot(scene, set, IntegratorKind::Bdpt) {
            pilots.push(p);
        }
    }
    let (kind, why) = pipeline::auto::choose(&pilots);
    let chosen = pilots.iter().find(|p| p.kind == kind).expect("a candidate");
    let (noise, second_seconds) = pipeline::auto::thresholds_over_sd(scene, set, chosen)?;
    let pilot_seconds: f64 = pilots.iter().map(|p| p.seconds).sum::<f64>() + second_seconds;
    let spp = match job.budget(scene) {
        JobBudget::Time(t) => (t - pilot_seconds).max(0.0) / chosen.seconds_per_spp.max(1e-12),
        b => b.spp().unwrap_or_else(|| default_spp(scene)) as f64,
    };
    // (named only where it differs from what no name gives: a plain render's film key is
    // then the same as that of the same render asked for with `--method plain`)
    if kind != job.integrator_for(scene) {
        j.integrator = Some(kind);
    }
    let (helps, off, rel_rmse) = pipeline::auto::dtf_helps(&noise, spp);
    let off = format!(
        "{:.1}% of the pixels predicted more than 5% off plain and its RMSE {:.1}% of the mean at about {spp:.0} spp",
        100.0 * off,
        100.0 * rel_rmse
    );
    let line = if spp < AUTO_DTF_MIN_SPP {
        format!(
            "plain {} (about {spp:.0} spp fit the budget; dtf needs {AUTO_DTF_MIN_SPP}); {why}",
            name(&kind)
        )
    } else if !helps {
        format!(
            "plain {}; {why}; plain: {off}, dtf needs {}% or {}%",
            name(&kind),
            100.0 * pipeline::auto::DTF_MIN_OFF,
            100.0 * pipeline::auto::DTF_MIN_REL_RMSE
        )
    } else {
        j.method = Method::Dtf;
        j.dtf.keep_converged = j.dtf.keep_converged.or(Some(AUTO_KEEP_CONVERGED));
        format!("dtf over {}; {why}; dtf: {off}", name(&kind))
    };
    progress.message(&format!("method: {line}"));
    Ok((j, Some(line)))
}

/// BDPT's strategy images of `job` (`pipeline::strategies`: an `--integrator bdpt` job,
/// a fixed number of samples) for the path lengths up to `max_length` (and the job's
/// --max-depth, if smaller), on the job's thread pool.
pub fn render_strategies(
    scene: &Scene,
    job: &RenderJob,
    max_length: u32,
    progress: &dyn Progress,
) -> Result<Vec<pipeline::strategies::StrategyImage>, String> {
    pipeline::strategies::check_estimator(job.integrator_for(scene))?;
    job.validate()?;
    let set = job.settings(scene);
    crate::film::check_resolution(set.width, set.height)?;
    let spp = match job.budget(scene) {
        JobBudget::Time(_) => {
            return Err("--bdpt-strategies: give --spp (the strategy images are a fixed number of samples, not --time)".into())
        }
        b => b.spp().unwrap_or_else(|| default_spp(scene)),
    };
    let (pool, _) = thread_pool(job.threads)?;
    pool.install(|| {
        pipeline::strategies::render_strategies(
            scene,
            &set,
            job.first_sample,
            spp,
            max_length,
            progress,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::{BsdfSelect, RrMode, RrWeight};

    /// The defaults, as documented in docs/guide/cli.md and `--help`: written once (clap
    /// attributes), read by the CLI, the library's `Default` and serde alike.
    #[test]
    fn defaults_are_the_documented_ones_everywhere() {
        let j = RenderJob::default();
        assert_eq!(j.method, Method::Auto);
        assert_eq!(j.integrator, None);
        assert_eq!(j.spectral, SpectralMode::Rgb);
        assert_eq!(j.sampler, SamplerKind::Sobol);
        assert_eq!(
            (j.seed, j.first_sample, j.spp, j.time, j.res),
            (0, 0, None, None, None)
        );
        assert_eq!(j.roulette.mode, RrMode::Spectral);
        assert_eq!(j.roulette.weight, RrWeight::Luminance);
        assert_eq!(j.roulette.select, BsdfSelect::Mixture);
        assert_eq!(j.roulette.min_depth, None);
        assert_eq!(j.dtf.n, None);
        assert_eq!(j.dtf.eps_r, None);
        assert_eq!(
            j.dtf.categories,
            vec![0, 1, 2, 3, 5, 7, 10, 14, 20, 30, 50, 70, 100, 140, 200, 300, 500]
        );
        assert_eq!(
            (j.dtf.stop_ratio, j.dtf.direct),
            (None, crate::filter::dtf::DirectMode::Split)
        );
        assert!(j.dtf.cost_aware);
        assert_eq!(j.dtf, DtfParams::default());
        assert_eq!(j.roulette, Roulette::default());
        // the CLI: `kalos render cornell` is the library's job for cornell
        use clap::Parser;
        let cli = crate::cli::Cli::try_parse_from(["kalos", "render", "cornell"]).unwrap();
        let crate::cli::Command::Render(a) = cli.command else {
            panic!("not a render")
        };
        assert_eq!(a.job(), RenderJob::new("cornell"));
        // serde: an empty object is the default job; a round trip is the identity
        let empty: RenderJob = serde_json::from_str("{}").unwrap();
        assert_eq!(empty, RenderJob::default());
        let mut k = RenderJob::new("room");
        k.roulette.mode = RrMode::SpectralEstimate;
        k.spectral = SpectralMode::Bands16;
        k.dtf.allocation = crate::filter::dtf::Allocation::RelMse;
        k.res = Some((3, 4));
        let back: RenderJob = serde_json::from_str(&serde_json::to_string(&k).unwrap()).unwrap();
        assert_eq!(back, k);
        // serde spells choices as the CLI does
        let v = serde_json::to_value(&k).unwrap();
        assert_eq!(v["roulette"]["mode"], "spectral-estimate");
        assert_eq!(v["spectral"], "16");
        assert!(serde_json::from_str::<RenderJob>(r#"{"sppp": 3}"#).is_err());
    }

    /// `--filter energy` after a plain render moves no energy (sum of luminance kept to
    /// 1e-9), changes a noisy image, and is refused after `--method rw`.
    #[test]
    fn energy_post_filter_keeps_energy() {
        let scene = crate::scene::load("cornell").unwrap();
        let mut j = RenderJob::new("cornell");
        j.res = Some((24, 24));
        j.spp = Some(8);
        let plain = render_scene(&scene, &j, &crate::progress::Silent).unwrap();
        j.post_filter = Some(PostFilter::Energy);
        let f = render_scene(&scene, &j, &crate::progress::Silent).unwrap();
        let lum = |i: &RgbImage| {
            i.data
                .iter()
                .map(|c| crate::filter::energy::luminance(c.map(|v| v as f64)))
                .sum::<f64>()
        };
        let (a, b) = (lum(&plain.image), lum(&f.image));
        assert!((a - b).abs() <= 1e-6 * a, "energy moved: {a} vs {b}");
        assert_ne!(
            plain.image.data, f.image.data,
            "8 spp on cornell has noise pixels"
        );
        j.method = Method::Rw;
        let Err(e) = render_scene(&scene, &j, &crate::progress::Silent) else {
            panic!("--filter energy with --method rw was accepted")
        };
        assert!(e.contains("--filter energy"), "{e}");
    }

    /// `--time` covers the preprocess: a budget the radiosity solve alone exceeds is said,
    /// and one pass is rendered.
    #[test]
    fn time_budget_counts_the_preprocess() {
        let scene = crate::scene::load("cornell").unwrap();
        let mut j = RenderJob::new("cornell");
        j.res = Some((8, 8));
        j.time = Some(1e-6);
        j.gather = Some(Gather::Radiosity);
        j.radiosity.max_area = Some(0.5);
        let r = render_scene(&scene, &j, &crate::progress::Silent).unwrap();
        assert!(
            r.warnings.iter().any(|w| w.contains("the preprocess took")),
            "{:?}",
            r.warnings
        );
        assert!(r.film.total_samples() >= 64, "one pass is rendered");
    }

    /// The budget of each method without one, and the one default samples per pixel.
    #[test]
    fn each_method_spends_its_own_budget_without_one() {
        let scene = crate::scene::load("cornell").unwrap();
        let mut j = RenderJob::new("cornell");
        assert_eq!(j.budget(&scene), JobBudget::Spp(DEFAULT_SPP));
        j.method = Method::Rw;
        assert_eq!(j.budget(&scene), JobBudget::Convergence);
        j.method = Method::Dtf;
        assert_eq!(j.budget(&scene), JobBudget::Spp(DEFAULT_SPP));
        j.dtf.eps_r = Some(0.1);
        assert_eq!(j.budget(&scene), JobBudget::RelativeError);
        j.spp = Some(7);
        assert_eq!(j.budget(&scene), JobBudget::Spp(7));
        j.spp = None;
        j.time = Some(2.5);
        assert_eq!(j.budget(&scene), JobBudget::Time(2.5));
        let mut s4 = crate::scene::load("cornell").unwrap();
        s4.defaults.spp = Some(4);
        assert_eq!(RenderJob::new("cornell").budget(&s4), JobBudget::Spp(4));
        assert_eq!(default_spp(&s4), 4);
    }

    #[test]
    fn key_ignores_the_sample_range_only() {
        let mut a = RenderJob::new("cornell");
        let mut b = a.clone();
        a.first_sample = 32;
        b.spp = Some(7);
        b.threads = Some(3);
        assert_eq!(a.key(7), b.key(7));
        assert_ne!(a.key(7), b.key(8), "another scene content");
        b.scene = "./cornell".into();
        assert_eq!(a.key(7), b.key(7), "the path is not the content");
        b.seed = 1;
        assert_ne!(a.key(7), b.key(7));
    }
}
/// A filter on a finished image (`--filter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum PostFilter {
    /// Rushmeier and Ward's energy-preserving filter.
    Energy,
}
