//! `kalos render`: a thin translation of the command line into a `RenderJob`, then the
//! output: image (or film file), AOV layers, DTF layers and statistics.

use super::progress::{install_handler, install_interrupt_handler, interrupted, rate, CliProgress};
use crate::film::{write_film, Film};
use crate::image_io::{write_image, write_image_aovs, RgbImage};
use crate::render::{Method, RenderJob};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Built-in scene name (see `kalos scenes`), .obj, .toml or Mitsuba .xml file.
    pub scene: String,
    #[command(flatten)]
    pub job: RenderJob,
    /// Output: .exr (linear), .pfm (linear), .png (sRGB) or .kfilm (the film, for `kalos
    /// merge`).
    #[arg(short, long, default_value = "out.exr")]
    pub output: PathBuf,
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Write per-pixel variance and sample count as extra EXR layers.
    #[arg(long)]
    pub aovs: bool,
    /// Write render statistics as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// No progress bar or summary (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
    /// DTF: write the intermediate images beside the output (dependent, independent,
    /// filtered, combined, N and M maps).
    #[arg(long)]
    pub dtf_layers: bool,
    /// RW: write the unfiltered and filtered images, the noise-pixel mask and the map of
    /// trials per pixel beside the output (the paper's figure 4 as files).
    #[arg(long)]
    pub rw_layers: bool,
    /// BDPT: also write one image per strategy (s, t) of the path lengths up to 4 (or
    /// --max-depth) beside the output, MIS-weighted (`out-s1-t2.exr`) and unweighted
    /// (`out-s1-t2-unweighted.exr`): which strategy carries which light.
    #[arg(long)]
    pub bdpt_strategies: bool,
    /// Render on a Dask cluster: the scheduler's address (`tcp://host:8786`). The samples
    /// are split into tasks, rendered by the workers and merged exactly (the same image as
    /// without --dask). Runs `python3 -m kalos render ...`: needs the kalos Python module
    /// with dask and distributed (`KALOS_PYTHON` names another interpreter).
    #[arg(long, value_name = "ADDRESS")]
    pub dask: Option<String>,
    /// Stream the image to a running tev viewer as passes finish (tev's address, default
    /// 127.0.0.1:14158). A viewer that does not answer costs a warning; the render goes on.
    #[arg(long, value_name = "HOST:PORT", num_args = 0..=1, require_equals = false,
          default_missing_value = super::tev::DEFAULT_ADDRESS, value_parser = super::tev::parse_address)]
    pub tev: Option<String>,
    /// With --dask: samples per task (default: two tasks per worker thread).
    #[arg(long, value_name = "N", requires = "dask", value_parser = clap::value_parser!(u32).range(1..))]
    pub dask_chunk_spp: Option<u32>,
}

impl RenderArgs {
    /// The job these options describe.
    pub fn job(&self) -> RenderJob {
        let mut j = self.job.clone();
        j.scene = self.scene.clone();
        // a film file, BDPT's strategy images and a render on Dask are plain renders'
        if j.method == Method::Auto
            && (is_film_path(&self.output) || self.bdpt_strategies || self.dask.is_some())
        {
            j.method = Method::Plain;
        }
        j
    }
}

/// Whether a path is a film file.
pub fn is_film_path(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("kfilm"))
}

/// Check every output before the work starts: a known format, an existing folder, no two
/// outputs on one path. Returns warnings.
pub fn check_outputs(a: &RenderArgs) -> Result<Vec<String>, String> {
    let mut warnings = Vec::new();
    if !is_film_path(&a.output) {
        crate::image_io::format_of(&a.output).map_err(|e| format!("-o/--output: {e}"))?;
    } else if !matches!(a.job.method, Method::Plain | Method::Auto) {
        return Err(format!(
            "-o/--output: a .kfilm film file holds a plain render's samples; --method {} writes images only",
            crate::options::name(&a.job.method)
        ));
    } else if let Some(f) = a.job.post_filter {
        return Err(format!(
            "--filter {}: a .kfilm film file holds the unfiltered samples; write an image, or filter the merged image with `kalos filter {}`",
            crate::options::name(&f),
            crate::options::name(&f)
        ));
    }
    if !a.exposure.is_finite() {
        return Err(format!(
            "--exposure: {} is not a finite number of stops",
            a.exposure
        ));
    }
    let mut outs: Vec<(&str, PathBuf)> = vec![("-o/--output", a.output.clone())];
    if let Some(s) = &a.stats {
        outs.push(("--stats", s.clone()));
    }
    for (what, p) in &outs {
        let dir = p.parent().filter(|d| !d.as_os_str().is_empty());
        if let Some(d) = dir {
            if !d.is_dir() {
                return Err(format!(
                    "{what} {}: the folder {} does not exist",
                    p.display(),
                    d.display()
                ));
            }
        }
        if p.is_dir() {
            return Err(format!("{what} {}: is a directory", p.display()));
        }
    }
    if let Some(s) = &a.stats {
        if same_file(s, &a.output) {
            return Err(format!(
                "--stats {} and -o/--output {}: two outputs on one path",
                s.display(),
                a.output.display()
            ));
        }
    }
    if a.aovs
        && !is_film_path(&a.output)
        && crate::image_io::format_of(&a.output)? != crate::image_io::Format::Exr
    {
        warnings.push(format!(
            "--aovs: {} is not an EXR file, so the variance and count layers are not written (use .exr)",
            a.output.display()
        ));
    }
    Ok(warnings)
}

/// Two paths naming one file (or, when neither exists yet, one spelling).
fn same_file(a: &Path, b: &Path) -> bool {
    let canon = |p: &Path| {
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::canonicalize(dir)
            .ok()
            .map(|d| d.join(p.file_name().unwrap_or_default()))
    };
    match (canon(a), canon(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// `kalos render`: check the outputs, render, write the image, layers and statistics.
pub fn run(a: RenderArgs) -> Result<(), String> {
    // warnings print under --quiet too: a scene's dropped feature must never go unsaid
    let say = |w: &str| eprintln!("kalos: warning: {w}");
    for w in check_outputs(&a)? {
        say(&w);
    }
    let job = a.job();
    job.validate()?;
    if a.bdpt_strategies {
        if job.integrator != Some(crate::integrator::IntegratorKind::Bdpt) {
            return Err(
                "--bdpt-strategies: the strategy images are BDPT's; add --integrator bdpt".into(),
            );
        }
        if job.method != Method::Plain || is_film_path(&a.output) || job.time.is_some() {
            return Err("--bdpt-strategies: needs a plain render to an image with --spp (not --method dtf, --time or a .kfilm output)".into());
        }
    }
    if let Some(addr) = &a.dask {
        return run_on_dask(addr);
    }
    install_interrupt_handler();
    let progress = CliProgress::new(a.quiet);
    // DTF's phases do not stop part-way: an interrupt ends the process
    let progress = if matches!(job.method, Method::Dtf | Method::Auto) {
        progress.not_stoppable()
    } else {
        progress
    };
    let name = a
        .output
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| a.scene.clone());
    let tev = a
        .tev
        .as_deref()
        .map(|addr| super::tev::TevProgress::connect(&progress, addr, &name));
    let p: &dyn crate::progress::Progress = match &tev {
        Some(t) => t,
        None => &progress,
    };
    let r = crate::render::render(&job, p)?;
    if let Some(t) = &tev {
        // the finished image (filtered, for the methods that filter)
        t.send(r.image.width, r.image.height, &r.image.data);
    }
    for w in &r.warnings {
        say(w);
    }
    if is_film_path(&a.output) {
        write_film(&a.output, &r.film_file(&job))?;
    } else {
        write_output(&a.output, &r.image, &r.film, a.exposure, a.aovs)?;
    }
    if let (true, Some(run)) = (a.dtf_layers, &r.dtf) {
        write_dtf_layers(&a.output, run, a.exposure)?;
    }
    if let (true, Some(run)) = (a.rw_layers, &r.rw) {
        write_rw_layers(&a.output, run, a.exposure)?;
    }
    if a.bdpt_strategies {
        write_bdpt_strategies(&a, &job, &progress)?;
    }
    let stats = &r.stats;
    if let Some(p) = &a.stats {
        let json = serde_json::to_string_pretty(stats).map_err(|e| e.to_string())?;
        std::fs::write(p, json + "\n").map_err(|e| format!("--stats {}: {e}", p.display()))?;
    }
    if stats.interrupted {
        return Err(format!(
            "interrupted: wrote the {} spp rendered before the stop to {}",
            stats.spp,
            a.output.display()
        ));
    }
    if !a.quiet {
        eprintln!(
            "kalos: {} {}x{} {} spp in {:.2} s: {}, {} -> {}",
            stats.scene,
            stats.width,
            stats.height,
            stats.spp,
            stats.seconds,
            rate(stats.paths_per_second, "paths"),
            rate(stats.rays_per_second, "rays"),
            a.output.display()
        );
    }
    if let Some(phases) = crate::integrator::phases::report() {
        eprintln!("kalos: {phases}");
    }
    Ok(())
}

/// `kalos render --dask ADDRESS ...`: the same command line (its job and outputs checked
/// here), run by the Python module's Dask front end (`python3 -m kalos render ...`,
/// `python/kalos/distributed.py`), which says what can be distributed, splits the
/// samples into tasks and merges their film parts exactly.
fn run_on_dask(addr: &str) -> Result<(), String> {
    let python = std::env::var_os("KALOS_PYTHON").unwrap_or_else(|| "python3".into());
    let shown = Path::new(&python).display().to_string();
    let check = std::process::Command::new(&python)
        .args(["-c", "import kalos.distributed"])
        .output()
        .map_err(|e| format!("--dask {addr}: cannot run {shown} ({e}): install Python 3 with the kalos module (pip install ./python dask distributed) or set KALOS_PYTHON"))?;
    if !check.status.success() {
        let err = String::from_utf8_lossy(&check.stderr);
        let last = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("")
            .trim();
        return Err(format!("--dask {addr}: {shown} cannot import the kalos module ({last}): pip install ./python dask distributed, or set KALOS_PYTHON"));
    }
    // Ctrl-C reaches the Python process too (one process group) and it cancels the
    // tasks; a SIGTERM sent to kalos alone ends the Python process after a grace period
    // (the scheduler then drops the tasks of the lost client).
    install_handler("cancelling the distributed render");
    let mut child = std::process::Command::new(&python)
        .args(["-m", "kalos"])
        .args(std::env::args_os().skip(1))
        .spawn()
        .map_err(|e| format!("--dask {addr}: cannot run {shown}: {e}"))?;
    let mut stop_seen: Option<std::time::Instant> = None;
    let status = loop {
        match child.try_wait() {
            Ok(Some(st)) => break st,
            Ok(None) => {}
            Err(e) => return Err(format!("--dask {addr}: {shown}: {e}")),
        }
        if interrupted() {
            let t = *stop_seen.get_or_insert_with(std::time::Instant::now);
            if t.elapsed().as_secs_f64() > 5.0 {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "--dask {addr}: interrupted: the distributed render was cancelled, nothing written"
                ));
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    if status.success() {
        Ok(())
    } else {
        // the Python side printed its one-line error
        std::process::exit(status.code().unwrap_or(1));
    }
}

/// Write the displayed image, with the film's variance and count layers when asked.
pub fn write_output(
    path: &Path,
    img: &RgbImage,
    film: &Film,
    exposure: f32,
    aovs: bool,
) -> Result<(), String> {
    if aovs {
        let (var, cnt) = (film.variance_rgb(), film.counts());
        write_image_aovs(path, img, exposure, Some((&var, &cnt)))
    } else {
        write_image_aovs(path, img, exposure, None)
    }
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

/// RW's layers: `-unfiltered`, `-filtered`, `-noise` (1 where a pixel had not converged)
/// and `-trials` (trials per pixel; normalised to its maximum in PNG output).
fn write_rw_layers(path: &Path, run: &crate::pipeline::RwRun, exposure: f32) -> Result<(), String> {
    let (w, h) = (run.film.width, run.film.height);
    let f32s = |v: &[[f64; 3]]| v.iter().map(|c| c.map(|x| x as f32)).collect::<Vec<_>>();
    write_image(
        &sibling(path, "unfiltered"),
        &RgbImage::new(w, h, f32s(&run.unfiltered)),
        exposure,
        &[],
    )?;
    write_image(
        &sibling(path, "filtered"),
        &RgbImage::new(w, h, f32s(&run.out.image)),
        exposure,
        &[],
    )?;
    let png = crate::image_io::format_of(path)? == crate::image_io::Format::Png;
    let noise: Vec<[f32; 3]> = run
        .out
        .noise
        .iter()
        .map(|&n| [if n { 1.0 } else { 0.0 }; 3])
        .collect();
    write_image(
        &sibling(path, "noise"),
        &RgbImage::new(w, h, noise),
        0.0,
        &[],
    )?;
    let k = if png {
        1.0 / run.trials.iter().copied().max().unwrap_or(1).max(1) as f32
    } else {
        1.0
    };
    let trials: Vec<[f32; 3]> = run.trials.iter().map(|&t| [t as f32 * k; 3]).collect();
    write_image(
        &sibling(path, "trials"),
        &RgbImage::new(w, h, trials),
        0.0,
        &[],
    )
}

/// BDPT's strategy images beside the output (`pipeline::strategies`).
fn write_bdpt_strategies(
    a: &RenderArgs,
    job: &crate::render::RenderJob,
    progress: &dyn crate::progress::Progress,
) -> Result<(), String> {
    use crate::pipeline::strategies::DEFAULT_MAX_LENGTH;
    use crate::render::render_strategies;
    let scene = crate::scene::load_with(&job.scene, &job.defines)?;
    let images = render_strategies(&scene, job, DEFAULT_MAX_LENGTH, progress)?;
    let set = job.settings(&scene);
    for im in &images {
        for (suffix, data) in [("", &im.weighted), ("-unweighted", &im.unweighted)] {
            let img = RgbImage::new(set.width, set.height, data.clone());
            write_image(
                &sibling(&a.output, &format!("{}{suffix}", im.name())),
                &img,
                a.exposure,
                &[],
            )?;
        }
    }
    if !a.quiet {
        eprintln!(
            "kalos: {} strategy images ({} weighted + unweighted) beside {}",
            2 * images.len(),
            images.len(),
            a.output.display()
        );
    }
    Ok(())
}
