//! Running a job: its budget, the method's pipeline on the job's thread pool, and what
//! every render ends with (the post filter, the warnings, the statistics), in one place
//! for a render in one process and for DTF's passes run elsewhere (`render_dtf_with`).

use super::stats::{DtfStats, RenderStats, RunFigures};
use super::{choose_method, thread_pool, Method, PostFilter, RenderJob, Rendered};
use super::{DEFAULT_SPP, LARGE_RENDER_SAMPLES};
use crate::film::{Film, FilmFile};
use crate::image_io::RgbImage;
use crate::integrator::{Counters, Integrator, IntegratorKind};
use crate::pipeline::{
    self, Budget, DtfBudget, DtfPass, DtfPasses, DtfRun, Progress, RenderSettings, RwBudget,
    RwParams, RwRun,
};
use crate::scene::Scene;

/// What a job spends: its `--time` or `--spp`, else what its method does without one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JobBudget {
    /// Wall-clock seconds, the preprocess counted.
    Time(f64),
    /// Samples (trials) per pixel.
    Spp(u32),
    /// DTF's prescribed relative error (`--dtf-eps-r` without a budget).
    RelativeError,
    /// Rushmeier and Ward's trials until convergence (`--method rw` without a budget).
    Convergence,
}

/// Samples per pixel of a render that gives no budget: the scene file's, else
/// `DEFAULT_SPP` (the one place it applies).
pub fn default_spp(scene: &Scene) -> u32 {
    scene.defaults.spp.unwrap_or(DEFAULT_SPP)
}

impl RenderJob {
    /// The job's budget on `scene` (the one place the default applies).
    pub fn budget(&self, scene: &Scene) -> JobBudget {
        match (self.time, self.spp, self.method) {
            (Some(t), _, _) => JobBudget::Time(t),
            (None, Some(n), _) => JobBudget::Spp(n),
            (None, None, Method::Dtf) if self.dtf.eps_r.is_some() => JobBudget::RelativeError,
            (None, None, Method::Rw) => JobBudget::Convergence,
            (None, None, _) => JobBudget::Spp(default_spp(scene)),
        }
    }
}

impl JobBudget {
    /// Samples per pixel, if the budget is a number of them.
    pub fn spp(self) -> Option<u32> {
        match self {
            JobBudget::Spp(n) => Some(n),
            _ => None,
        }
    }

    /// The budget with `time_left` for the pipeline (the preprocess has taken the rest).
    fn after(self, time_left: Option<f64>) -> JobBudget {
        match (self, time_left) {
            (JobBudget::Time(_), Some(t)) => JobBudget::Time(t),
            (b, _) => b,
        }
    }

    fn dtf(self) -> DtfBudget {
        match self {
            JobBudget::Time(t) => DtfBudget::Time(t),
            JobBudget::Spp(n) => DtfBudget::Spp(n as f64),
            JobBudget::RelativeError | JobBudget::Convergence => DtfBudget::RelativeError,
        }
    }

    fn rw(self) -> RwBudget {
        match self {
            JobBudget::Time(t) => RwBudget::Time(t),
            JobBudget::Spp(n) => RwBudget::Spp(n as f64),
            JobBudget::RelativeError | JobBudget::Convergence => RwBudget::Convergence,
        }
    }

    fn plain(self, default_spp: u32) -> Budget {
        match self {
            JobBudget::Time(t) => Budget::Time(t),
            JobBudget::Spp(n) => Budget::Spp(n),
            JobBudget::RelativeError | JobBudget::Convergence => Budget::Spp(default_spp),
        }
    }
}

/// What a method's pipeline leaves.
struct Outcome {
    film: Film,
    image: RgbImage,
    counters: Counters,
    seconds: f64,
    spp: u32,
    interrupted: bool,
    dtf: Option<(DtfStats, DtfRun)>,
    rw: Option<RwRun>,
}

/// DTF's run as an outcome: both phases' samples in the film, the combined image (with
/// converged pixels keeping their own mean where `--dtf-keep-converged` says).
fn dtf_outcome(
    run: DtfRun,
    params: &crate::filter::dtf::DtfParams,
    set: &RenderSettings,
) -> Outcome {
    let mut film = run.independent.clone();
    film.merge(&run.dependent);
    let spp = (film.total_samples() as f64 / (set.width as f64 * set.height as f64)).round() as u32;
    let mut image = run.out.combined.clone();
    if let (Some(tau), None) = (params.keep_converged, &run.direct) {
        crate::filter::dtf::keep_converged(&mut image, &run.independent, tau as f64);
    }
    Outcome {
        film,
        image,
        counters: run.counters,
        seconds: run.seconds,
        spp,
        interrupted: false,
        dtf: Some((DtfStats::of(&run, params), run)),
        rw: None,
    }
}

/// Render an already loaded scene as the job says (the job's `scene` only names it).
pub fn render_scene(
    scene: &Scene,
    job: &RenderJob,
    progress: &dyn Progress,
) -> Result<Rendered, String> {
    job.validate()?;
    let set = job.settings(scene);
    crate::film::check_resolution(set.width, set.height)?;
    let (pool, thread_warning) = thread_pool(job.threads)?;
    let mut warnings: Vec<String> = thread_warning.into_iter().collect();
    // (the pilot of `--method auto` is part of the preprocess: `--time` counts it)
    let t_prep = std::time::Instant::now();
    let (job, choice) = pool.install(|| choose_method(scene, job, &set, progress))?;
    let job = &job;
    let set = job.settings(scene);
    let budget = job.budget(scene);
    // DTF's spp budget is the average over both phases: phase 1's n must fit in it
    // (checked before any work, with the scene's default spp known)
    if let (Method::Dtf, Some(spp)) = (job.method, budget.spp()) {
        let n = job.dtf.n_for(Some(spp as f64), false);
        if spp < n {
            return Err(format!(
                "--spp {spp}: in DTF budget mode it is the average over both phases and must be at least --dtf-n {n}"
            ));
        }
    }
    if job.integrator_for(scene) == IntegratorKind::Bdpt {
        warnings.extend(set.camera.for_light_paths()?);
    }
    // Say what a large render will cost before it starts.
    let pixels = set.width as u64 * set.height as u64;
    if let Some(total) = budget
        .spp()
        .map(|n| n as u64 * pixels)
        .filter(|&t| t >= LARGE_RENDER_SAMPLES)
    {
        progress.message(&format!(
            "{total} samples planned ({pixels} pixels): about {:.1} hours at 1 M samples/s; \
             Ctrl-C writes what is done",
            total as f64 / 1e6 / 3600.0
        ));
    }
    if let (Method::Dtf, JobBudget::RelativeError) = (job.method, budget) {
        progress.message(&format!(
            "dtf with eps_r = {}: the work depends on phase 1 and is known after it",
            job.dtf.eps_r.unwrap_or_default()
        ));
    }
    // a preprocess with its default mesh follows a --time budget (what is left of it)
    let mut integ_set = set.integrator;
    if let JobBudget::Time(t) = budget {
        integ_set.radiosity.time_budget = Some((t - t_prep.elapsed().as_secs_f64()).max(0.0));
    }
    let integrator =
        pool.install(|| Integrator::prepare(scene, integ_set, set.spectral.bands(), progress))?;
    let prepare_seconds = t_prep.elapsed().as_secs_f64();
    // --time covers the preprocess too (equal-time comparisons count it).
    let time_left = job.time.map(|t| {
        if prepare_seconds >= t {
            warnings.push(format!(
                "--time {t}: the preprocess took {prepare_seconds:.2} s of it; rendering one pass"
            ));
        }
        (t - prepare_seconds).max(0.0)
    });
    let budget = budget.after(time_left);

    let outcome = match job.method {
        Method::Dtf => {
            let run = pool.install(|| {
                pipeline::render_dtf(scene, &integrator, &set, &job.dtf, budget.dtf(), progress)
            })?;
            dtf_outcome(run, &job.dtf, &set)
        }
        Method::Rw => {
            let run = pool.install(|| {
                pipeline::render_rw(scene, &integrator, &set, &job.rw, budget.rw(), progress)
            })?;
            let data: Vec<[f32; 3]> = run.out.image.iter().map(|c| c.map(|v| v as f32)).collect();
            Outcome {
                film: run.film.clone(),
                image: RgbImage::new(set.width, set.height, data),
                counters: run.counters,
                seconds: run.seconds,
                spp: run.stats.average_trials.round() as u32,
                interrupted: progress.cancelled(),
                dtf: None,
                rw: Some(run),
            }
        }
        // (`choose_method` has made auto concrete)
        Method::Plain | Method::Auto => {
            let b = budget.plain(default_spp(scene));
            let out = pool.install(|| {
                pipeline::render(scene, &integrator, &set, b, job.first_sample, progress)
            })?;
            Outcome {
                image: RgbImage::new(set.width, set.height, out.film.mean_rgb()),
                film: out.film,
                counters: out.counters,
                seconds: out.seconds,
                spp: out.spp,
                interrupted: out.interrupted,
                dtf: None,
                rw: None,
            }
        }
    };
    let ran = Ran {
        prepare_seconds,
        threads: pool.current_num_threads(),
        method_choice: choice,
        warnings,
    };
    finish(scene, job, &set, outcome, ran)
}

/// How the run went, beside its outcome.
struct Ran {
    prepare_seconds: f64,
    threads: usize,
    method_choice: Option<String>,
    warnings: Vec<String>,
}

/// What every render ends with: the post filter, the warnings (rejected samples, an
/// all-black image) and the statistics.
fn finish(
    scene: &Scene,
    job: &RenderJob,
    set: &RenderSettings,
    outcome: Outcome,
    ran: Ran,
) -> Result<Rendered, String> {
    let Outcome {
        film,
        mut image,
        counters,
        seconds,
        spp,
        interrupted,
        dtf,
        rw,
    } = outcome;
    let mut warnings = ran.warnings;
    if let Some(PostFilter::Energy) = job.post_filter {
        image = energy_post_filter(&film, &image, &job.rw)?;
    }
    let rej = film.rejected;
    if rej.total() > 0 {
        warnings.push(format!(
            "rejected {} samples ({} NaN, {} infinite or above {:e}); they are not in the image",
            rej.total(),
            rej.nan,
            rej.infinite,
            crate::film::SAMPLE_MAX
        ));
    }
    // (a scene without emitters has said so when it was loaded)
    if !interrupted
        && !scene.lights.is_empty()
        && film.total_samples() > 0
        && image.data.iter().all(|p| *p == [0.0; 3])
    {
        let camera = if job.camera.is_some() {
            "the camera given with --camera".to_string()
        } else {
            format!(
                "the camera ({}: `kalos info` prints it)",
                scene.info.camera_from
            )
        };
        warnings.push(format!(
            "the image is all black: check that {camera} looks at the lit side of the scene \
             (inside a closed room, not at its outer walls) and that the emitters face what \
             it sees (an emitter shines only on its counter-clockwise side)"
        ));
    }
    let (dtf_stats, dtf_run) = dtf.map_or((None, None), |(s, r)| (Some(s), Some(r)));
    let figures = RunFigures {
        counters,
        seconds,
        spp,
        interrupted,
        prepare_seconds: ran.prepare_seconds,
        threads: ran.threads,
        rejected: rej,
        mean_rgb: image.mean(),
        method_choice: ran.method_choice,
    };
    let rw_stats = rw.as_ref().map(|r| r.stats.clone());
    let stats = RenderStats::new(scene, job, set, figures, dtf_stats, rw_stats);
    Ok(Rendered {
        image,
        film,
        stats,
        dtf: dtf_run,
        rw,
        warnings,
        key: job.key(scene.content_hash),
    })
}

/// DTF with its passes run by `passes` (a cluster's workers, each rendering parts with
/// [`render_dtf_part`]): the allocation, K[p], top-ups and the filter run here, so the
/// image is the one-process image of the same job, bit for bit. The budget is a number
/// of samples (a time cannot be split over workers).
pub fn render_dtf_with(
    scene: &Scene,
    job: &RenderJob,
    passes: &mut dyn DtfPasses,
    progress: &dyn Progress,
) -> Result<Rendered, String> {
    job.validate()?;
    if job.method != Method::Dtf {
        return Err("a distributed DTF render needs --method dtf".into());
    }
    if job.time.is_some() {
        return Err("--time: a distributed render splits a sample budget: give --spp".into());
    }
    let set = job.settings(scene);
    crate::film::check_resolution(set.width, set.height)?;
    let run = pipeline::render_dtf_with(&set, &job.dtf, job.budget(scene).dtf(), progress, passes)?;
    let outcome = dtf_outcome(run, &job.dtf, &set);
    let ran = Ran {
        prepare_seconds: 0.0,
        threads: rayon::current_num_threads(),
        method_choice: None,
        warnings: scene.warnings_for(job.camera.is_some()),
    };
    finish(scene, job, &set, outcome, ran)
}

/// One part of a DTF pass (samples `first..end` of the pass, or light paths with
/// `pass.light_paths`) on the job's thread pool, as film files that merge into the
/// pass's (with `pass.rest`, also the film of the samples less their emission seen
/// directly), the rays per pixel (with `pass.rays`) and the counters.
pub fn render_dtf_part(
    scene: &Scene,
    job: &RenderJob,
    pass: &DtfPass<'_>,
    first: u64,
    end: u64,
) -> Result<(FilmFile, Option<FilmFile>, Vec<u64>, Counters), String> {
    let set = job.settings(scene);
    let (pool, _) = thread_pool(job.threads)?;
    let silent = crate::progress::Silent;
    let (film, rest, rays, c) = pool.install(|| {
        let integ = Integrator::prepare(scene, set.integrator, set.spectral.bands(), &silent)?;
        if pass.rest {
            let (f, rf, r, c) =
                pipeline::run_dtf_pass_rest(scene, &integ, &set, pass, first, &silent)?;
            Ok::<_, String>((f, Some(rf), r, c))
        } else {
            let (f, r, c) = pipeline::run_dtf_pass(scene, &integ, &set, pass, first, &silent)?;
            Ok((f, None, r, c))
        }
    })?;
    let file = |film| FilmFile {
        job: serde_json::to_string(job).unwrap_or_default(),
        key: job.key(scene.content_hash),
        ranges: vec![(first, end)],
        film,
    };
    Ok((file(film), rest.map(file), rays, c))
}

/// The energy-preserving filter on a finished image: each pixel's value from the image,
/// its deviation S_p and trial count M from the film, Lt_vis from the image's mean.
fn energy_post_filter(film: &Film, image: &RgbImage, rw: &RwParams) -> Result<RgbImage, String> {
    use crate::filter::energy;
    let mean: Vec<[f64; 3]> = image.data.iter().map(|c| c.map(|v| v as f64)).collect();
    let s: Vec<f64> = film.pixels.iter().map(energy::deviation).collect();
    let m: Vec<u32> = film.pixels.iter().map(|p| p.n).collect();
    let p = energy::EnergyParams {
        d: rw.d,
        lt_vis: energy::lt_vis(energy::l_ave(&mean)),
        t: rw.t,
    };
    let out = energy::energy_filter(image.width, image.height, &mean, &s, &m, &p)
        .map_err(|e| format!("--filter energy: {e}"))?;
    let data = out.image.iter().map(|c| c.map(|v| v as f32)).collect();
    Ok(RgbImage::new(image.width, image.height, data))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Passes that must not run: the job is refused before any.
    struct NoPasses;
    impl DtfPasses for NoPasses {
        fn run(&mut self, _: DtfPass<'_>) -> Result<(Film, Vec<u64>, Counters), String> {
            panic!("a pass ran for a refused job")
        }
    }

    /// A distributed DTF render refuses, in one line and before any pass, a job that is
    /// not DTF's and a budget in seconds.
    #[test]
    fn distributed_dtf_refuses_other_methods_and_time() {
        let scene = crate::scene::load("cornell").unwrap();
        let silent = crate::progress::Silent;
        let mut j = RenderJob::new("cornell");
        j.method = Method::Plain;
        let Err(e) = render_dtf_with(&scene, &j, &mut NoPasses, &silent) else {
            panic!("a plain job was accepted")
        };
        assert!(e.contains("--method dtf") && !e.contains('\n'), "{e}");
        j.method = Method::Dtf;
        j.time = Some(3.0);
        let Err(e) = render_dtf_with(&scene, &j, &mut NoPasses, &silent) else {
            panic!("a time budget was accepted")
        };
        assert!(e.starts_with("--time") && e.contains("--spp"), "{e}");
    }
}
