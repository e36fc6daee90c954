//! `kalos._kalos`: the native half of the Python package `kalos` (the pure-Python half in
//! `python/kalos/` turns these into numpy arrays, dicts and exceptions users see).
//!
//! Options go through the CLI's own parser: the Python keyword arguments become an argument
//! vector (`--spp 64 --rr classic`) parsed by `RenderJob`'s clap definition, so names,
//! defaults, choices and error messages are `kalos render`'s. A render runs on its own
//! thread with the GIL released; the calling thread checks Python's signals every 100 ms
//! and turns a KeyboardInterrupt into `Progress::cancelled`, so the render stops at the
//! next row and the interrupt is raised.

use kalos::film::{film_from_bytes, film_to_bytes, merge_files, read_film, write_film, FilmFile};
use kalos::image_io::RgbImage;
use kalos::progress::Progress;
use kalos::render::{default_spp, RenderJob, DEFAULT_SPP};
use kalos::scene::Scene;
use pyo3::exceptions::{PyException, PyFileNotFoundError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::Duration;

pyo3::create_exception!(
    _kalos,
    SceneError,
    PyException,
    "A scene file that cannot be read: the message names the file, line and what is wrong."
);

fn value_error(e: String) -> PyErr {
    PyValueError::new_err(e)
}

/// `RenderJob`'s options as a clap command (no binary name: the vector holds options only).
fn job_command() -> clap::Command {
    use clap::Args;
    RenderJob::augment_args(clap::Command::new("kalos render").no_binary_name(true))
}

/// Parse an argument vector with the CLI's definition; errors are the CLI's one line
/// (`invalid value 'abc' for '--res <RES>': "abc" is not WxH`).
fn parse_job(scene: &str, argv: &[String]) -> Result<RenderJob, String> {
    use clap::FromArgMatches;
    let first_line = |e: clap::Error| kalos::cli::one_line(&e.render().to_string());
    let m = job_command()
        .try_get_matches_from(argv)
        .map_err(first_line)?;
    let mut job = RenderJob::from_arg_matches(&m).map_err(first_line)?;
    job.scene = scene.to_string();
    job.validate()?;
    Ok(job)
}

/// The option table (JSON): per option its Python name, flag, kind, default, choices and
/// help, read from the clap definition the CLI uses.
#[pyfunction]
fn options() -> String {
    let cmd = job_command();
    let rows: Vec<serde_json::Value> = cmd
        .get_arguments()
        .filter_map(|a| {
            let long = a.get_long()?;
            let flag = !a.get_action().takes_values();
            let defaults: Vec<String> = a
                .get_default_values()
                .iter()
                .map(|v| v.to_string_lossy().into_owned())
                .collect();
            let choices: Vec<String> = a
                .get_possible_values()
                .iter()
                .map(|p| p.get_name().to_string())
                .collect();
            Some(serde_json::json!({
                "name": long.replace('-', "_"),
                "flag": format!("--{long}"),
                "takes_value": !flag,
                "sets_false": matches!(a.get_action(), clap::ArgAction::SetFalse),
                "default": if flag || defaults.is_empty() {
                    serde_json::Value::Null
                } else {
                    serde_json::json!(defaults.join(","))
                },
                "choices": if flag { vec![] } else { choices },
                "multiple": a.get_value_delimiter().is_some(),
                "value_name": a.get_value_names().and_then(|v| v.first()).map(|s| s.to_string()),
                "help": a.get_help().map(|h| h.to_string()).unwrap_or_default(),
            }))
        })
        .collect();
    serde_json::to_string(&rows).unwrap_or_default()
}

/// The job an argument vector describes, as JSON (what `--stats` and film files record).
#[pyfunction]
#[pyo3(signature = (scene, argv))]
fn parse(scene: &str, argv: Vec<String>) -> PyResult<String> {
    let job = parse_job(scene, &argv).map_err(value_error)?;
    serde_json::to_string(&job).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The built-in scenes: (name, description) pairs.
#[pyfunction]
fn scenes() -> Vec<(String, String)> {
    kalos::scene::builtin::describe()
        .into_iter()
        .map(|(n, d)| (n.to_string(), d.to_string()))
        .collect()
}

/// A loaded scene (immutable; shared by the renders that use it).
#[pyclass(module = "kalos._kalos", frozen)]
struct NativeScene {
    scene: Arc<Scene>,
    spec: String,
}

#[pymethods]
impl NativeScene {
    /// What the scene was loaded from (a built-in name or a path).
    #[getter]
    fn spec(&self) -> String {
        self.spec.clone()
    }
    /// `kalos info --json` plus the scene's render defaults and warnings, as JSON.
    fn info_json(&self) -> String {
        let s = &self.scene;
        // (through text: f32 fields keep their short spelling, as `kalos info --json`'s)
        let mut v: serde_json::Value = serde_json::to_string(&s.info)
            .and_then(|t| serde_json::from_str(&t))
            .unwrap_or_default();
        v["spec"] = serde_json::json!(self.spec);
        v["default_spp"] = serde_json::json!(default_spp(s));
        v["default_res"] = serde_json::json!(s.defaults.res);
        v["default_max_depth"] = serde_json::json!(s.defaults.max_depth);
        v["warnings"] = serde_json::json!(s.warnings_for(false));
        serde_json::to_string(&v).unwrap_or_default()
    }
    /// The scene's warnings (unsupported materials, no emitter, ...).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings_for(false)
    }
    /// Samples per pixel when a render gives none (the scene file's, else 64).
    #[getter]
    fn default_spp(&self) -> u32 {
        default_spp(&self.scene)
    }
}

/// Load a scene: a built-in name, an .obj or a .toml file. FileNotFoundError for a missing
/// file, ValueError for a name that is neither, SceneError for a file kalos cannot read.
/// `defines`: a Mitsuba .xml file's parameters (`mi.load_file(path, spp=64)`), as strings.
#[pyfunction]
#[pyo3(signature = (spec, defines = Vec::new()))]
fn load(py: Python<'_>, spec: &str, defines: Vec<(String, String)>) -> PyResult<NativeScene> {
    if !kalos::scene::is_scene_spec(spec) {
        return Err(PyValueError::new_err(kalos::scene::not_a_scene(spec)));
    }
    if !kalos::scene::builtin::NAMES.contains(&spec) && !Path::new(spec).exists() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{spec}: no such file"
        )));
    }
    let s = spec.to_string();
    let scene = py
        .detach(move || kalos::scene::load_with(&s, &defines))
        .map_err(PyErr::new::<SceneError, _>)?;
    Ok(NativeScene {
        scene: Arc::new(scene),
        spec: spec.to_string(),
    })
}

/// Progress of a render driven from Python: counts, messages, and the stop flag the
/// watching thread sets on a KeyboardInterrupt.
#[derive(Default)]
struct PyProgress {
    stop: AtomicBool,
    total: AtomicU64,
    done: AtomicU64,
    messages: Mutex<Vec<String>>,
}

impl Progress for PyProgress {
    fn begin(&self, _unit: &str, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.done.store(0, Ordering::Relaxed);
    }
    fn set_total(&self, samples: u64) {
        self.total.store(samples, Ordering::Relaxed);
    }
    fn advance(&self, samples: u64) {
        self.done.fetch_add(samples, Ordering::Relaxed);
    }
    fn message(&self, text: &str) {
        if let Ok(mut m) = self.messages.lock() {
            m.push(text.to_string());
        }
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Run `work` on its own thread with the GIL released, checking Python's signals (and
/// calling `callback(done, total)`) every 100 ms on this thread. A KeyboardInterrupt (or
/// any exception a signal handler raises) sets the stop flag and is returned beside the
/// work's result once the work has stopped.
fn run_watched<T: Send>(
    py: Python<'_>,
    progress: &PyProgress,
    callback: Option<&Py<PyAny>>,
    work: impl FnOnce() -> T + Send,
) -> PyResult<(T, Option<PyErr>)> {
    let mut interrupt: Option<PyErr> = None;
    let mut callback_error: Option<PyErr> = None;
    let out = py.detach(|| {
        let (tx, rx) = mpsc::channel::<()>();
        std::thread::scope(|s| {
            let h = s.spawn(move || {
                let r = work();
                let _ = tx.send(());
                r
            });
            // (a sent value or a dropped sender both mean the work is over)
            while let Err(mpsc::RecvTimeoutError::Timeout) =
                rx.recv_timeout(Duration::from_millis(100))
            {
                Python::attach(|py| {
                    if interrupt.is_none() {
                        if let Err(e) = py.check_signals() {
                            progress.stop.store(true, Ordering::Relaxed);
                            interrupt = Some(e);
                        }
                    }
                    if let (Some(cb), None) = (callback, &callback_error) {
                        let done = progress.done.load(Ordering::Relaxed);
                        let total = progress.total.load(Ordering::Relaxed);
                        if let Err(e) = cb.call1(py, (done, total)) {
                            progress.stop.store(true, Ordering::Relaxed);
                            callback_error = Some(e);
                        }
                    }
                });
            }
            h.join()
        })
    });
    let out = out.map_err(|p| {
        let what = p
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        PyRuntimeError::new_err(format!("kalos: the render panicked: {what}"))
    })?;
    Ok((out, interrupt.or(callback_error)))
}

/// A film part: a film with the job that made it and its sample ranges (a `.kfilm` file).
#[pyclass(module = "kalos._kalos", frozen)]
struct NativeFilm {
    f: FilmFile,
}

fn f32_bytes<'py>(py: Python<'py>, v: impl Iterator<Item = f32>) -> Bound<'py, PyBytes> {
    let b: Vec<u8> = v.flat_map(|x| x.to_le_bytes()).collect();
    PyBytes::new(py, &b)
}

type Arrays<'py> = (
    u32,
    u32,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
);

fn film_arrays<'py>(py: Python<'py>, f: &kalos::film::Film, image: &RgbImage) -> Arrays<'py> {
    let var = f.variance_rgb();
    let cnt = f.counts();
    (
        image.width,
        image.height,
        f32_bytes(py, image.data.iter().flatten().copied()),
        f32_bytes(py, var.iter().flatten().copied()),
        f32_bytes(py, cnt.into_iter()),
    )
}

#[pymethods]
impl NativeFilm {
    /// Read a `.kfilm` file.
    #[staticmethod]
    fn read(py: Python<'_>, path: std::path::PathBuf) -> PyResult<NativeFilm> {
        if !path.exists() {
            return Err(PyFileNotFoundError::new_err(format!(
                "{}: no such file",
                path.display()
            )));
        }
        let f = py.detach(|| read_film(&path)).map_err(value_error)?;
        Ok(NativeFilm { f })
    }
    /// A film part from its bytes (`to_bytes`); `name` starts error messages.
    #[staticmethod]
    #[pyo3(signature = (data, name = "film"))]
    fn from_bytes(py: Python<'_>, data: &[u8], name: &str) -> PyResult<NativeFilm> {
        let f = py
            .detach(|| film_from_bytes(data, name))
            .map_err(value_error)?;
        Ok(NativeFilm { f })
    }
    /// The part's bytes: exactly what `write` puts in a `.kfilm` file.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let b = py.detach(|| film_to_bytes(&self.f));
        PyBytes::new(py, &b)
    }
    /// Write a `.kfilm` file.
    fn write(&self, py: Python<'_>, path: std::path::PathBuf) -> PyResult<()> {
        py.detach(|| write_film(&path, &self.f))
            .map_err(value_error)
    }
    /// Merge parts of one render exactly (integer sums: any order, the same bits). Refuses
    /// parts of other jobs, other sizes and overlapping sample ranges.
    #[staticmethod]
    fn merge(py: Python<'_>, parts: Vec<PyRef<'_, NativeFilm>>) -> PyResult<NativeFilm> {
        let named: Vec<(String, FilmFile)> = parts
            .iter()
            .enumerate()
            .map(|(i, p)| (format!("part {i}"), p.f.clone()))
            .collect();
        let f = py.detach(|| merge_files(&named)).map_err(value_error)?;
        Ok(NativeFilm { f })
    }
    /// The job that made the part, as JSON.
    #[getter]
    fn job(&self) -> String {
        self.f.job.clone()
    }
    /// What parts must share to merge (the job without sample range and threads).
    #[getter]
    fn key(&self) -> String {
        self.f.key.clone()
    }
    /// Sample index ranges [first, end) the part holds.
    #[getter]
    fn ranges(&self) -> Vec<(u64, u64)> {
        self.f.ranges.clone()
    }
    /// (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.f.film.width, self.f.film.height)
    }
    /// (width, height, mean RGB, variance RGB, count) as little-endian float32 bytes.
    fn arrays<'py>(&self, py: Python<'py>) -> Arrays<'py> {
        let f = &self.f.film;
        let img = RgbImage::new(f.width, f.height, f.mean_rgb());
        film_arrays(py, f, &img)
    }
}

/// What a render gives back: the image, variance and count as float32 bytes, the stats as
/// JSON, the warnings, and (for plain renders) the film part.
#[pyclass(module = "kalos._kalos", frozen)]
struct NativeRendered {
    #[pyo3(get)]
    width: u32,
    #[pyo3(get)]
    height: u32,
    #[pyo3(get)]
    image: Py<PyBytes>,
    #[pyo3(get)]
    variance: Py<PyBytes>,
    #[pyo3(get)]
    count: Py<PyBytes>,
    #[pyo3(get)]
    stats: String,
    #[pyo3(get)]
    job: String,
    #[pyo3(get)]
    warnings: Vec<String>,
    #[pyo3(get)]
    messages: Vec<String>,
    #[pyo3(get)]
    film: Option<Py<NativeFilm>>,
}

/// Render a loaded scene with the options of an argument vector (`kalos render`'s).
/// `callback(done, total)` is called every 100 ms while it runs. Raises ValueError for
/// bad options and KeyboardInterrupt when interrupted (the render stops at the next row).
#[pyfunction]
#[pyo3(signature = (scene, argv, callback = None))]
fn render(
    py: Python<'_>,
    scene: &NativeScene,
    argv: Vec<String>,
    callback: Option<Py<PyAny>>,
) -> PyResult<NativeRendered> {
    let job = parse_job(&scene.spec, &argv).map_err(value_error)?;
    let progress = PyProgress::default();
    let sc = scene.scene.clone();
    let (r, interrupt) = run_watched(py, &progress, callback.as_ref(), || {
        kalos::render_scene(&sc, &job, &progress)
    })?;
    if let Some(e) = interrupt {
        return Err(e);
    }
    let r = r.map_err(value_error)?;
    let mut warnings = scene.scene.warnings_for(job.camera.is_some());
    warnings.extend(r.warnings.iter().cloned());
    native_rendered(py, &job, r, warnings, &progress)
}

/// A finished render as the module returns it: arrays, statistics (the library's, as
/// `--stats` prints them), the job, warnings, messages and, for a plain render, its film.
fn native_rendered(
    py: Python<'_>,
    job: &RenderJob,
    r: kalos::Rendered,
    warnings: Vec<String>,
    progress: &PyProgress,
) -> PyResult<NativeRendered> {
    let (width, height, image, variance, count) = film_arrays(py, &r.film, &r.image);
    let stats = serde_json::to_string(&r.stats).unwrap_or_default();
    let job_json = serde_json::to_string(job).unwrap_or_default();
    // (the method rendered: `--method auto` may have chosen plain)
    let film = if r.stats.method == kalos::render::Method::Plain {
        // the film holds the job as rendered: the same as `--method plain` asks for
        let mut rendered = job.clone();
        rendered.method = r.stats.method;
        let f = r.film_file(&rendered);
        Some(Py::new(py, NativeFilm { f })?)
    } else {
        None
    };
    Ok(NativeRendered {
        width,
        height,
        image: image.unbind(),
        variance: variance.unbind(),
        count: count.unbind(),
        stats,
        job: job_json,
        warnings,
        messages: progress
            .messages
            .lock()
            .map(|m| m.clone())
            .unwrap_or_default(),
        film,
    })
}

fn rgb_from_bytes(width: u32, height: u32, data: &[u8], what: &str) -> PyResult<RgbImage> {
    let n = width as usize * height as usize;
    if data.len() != n * 12 {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes, a {width}x{height} RGB float32 image has {}",
            data.len(),
            n * 12
        )));
    }
    let px: Vec<[f32; 3]> = data
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            [f(0), f(4), f(8)]
        })
        .collect();
    Ok(RgbImage::new(width, height, px))
}

/// Write an image by the path's extension (.exr, .pfm linear; .png sRGB with `exposure`
/// stops). With `variance` and `count` (EXR only) they are written as extra layers.
#[pyfunction]
#[pyo3(signature = (path, width, height, data, exposure = 0.0, variance = None, count = None))]
#[allow(clippy::too_many_arguments)]
fn write(
    py: Python<'_>,
    path: std::path::PathBuf,
    width: u32,
    height: u32,
    data: &[u8],
    exposure: f32,
    variance: Option<&[u8]>,
    count: Option<&[u8]>,
) -> PyResult<()> {
    let img = rgb_from_bytes(width, height, data, "image")?;
    if !exposure.is_finite() {
        return Err(PyValueError::new_err(format!(
            "exposure: {exposure} is not a finite number of stops"
        )));
    }
    let var = variance
        .map(|v| rgb_from_bytes(width, height, v, "variance"))
        .transpose()?;
    let cnt: Option<Vec<f32>> = count
        .map(|c| {
            if c.len() != width as usize * height as usize * 4 {
                return Err(PyValueError::new_err(format!(
                    "count: {} bytes, a {width}x{height} float32 map has {}",
                    c.len(),
                    width as usize * height as usize * 4
                )));
            }
            Ok(c.chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect())
        })
        .transpose()?;
    let aovs = match (&var, &cnt) {
        (Some(v), Some(c)) => Some((&v.data[..], &c[..])),
        (None, None) => None,
        _ => {
            return Err(PyValueError::new_err(
                "variance and count: give both (the --aovs layers) or neither",
            ))
        }
    };
    py.detach(|| kalos::image_io::write_image_aovs(&path, &img, exposure, aovs))
        .map_err(value_error)
}

/// Read an image (.exr, .pfm, .png): (width, height, linear RGB float32 bytes).
#[pyfunction]
fn read_image<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<(u32, u32, Bound<'py, PyBytes>)> {
    if !path.exists() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{}: no such file",
            path.display()
        )));
    }
    let img = py
        .detach(|| kalos::image_io::read_image(&path))
        .map_err(value_error)?;
    let b = f32_bytes(py, img.data.iter().flatten().copied());
    Ok((img.width, img.height, b))
}

/// `kalos compare`'s metrics of an image against a reference, as JSON.
#[pyfunction]
#[pyo3(signature = (width, height, image, ref_width, ref_height, reference, ldr=false))]
#[allow(clippy::too_many_arguments)]
fn compare(
    width: u32,
    height: u32,
    image: &[u8],
    ref_width: u32,
    ref_height: u32,
    reference: &[u8],
    ldr: bool,
) -> PyResult<String> {
    let x = rgb_from_bytes(width, height, image, "image")?;
    let y = rgb_from_bytes(ref_width, ref_height, reference, "reference")?;
    kalos::metrics::check_comparable(&x, "image").map_err(value_error)?;
    kalos::metrics::check_comparable(&y, "reference").map_err(value_error)?;
    let range = if ldr {
        kalos::metrics::flip::Range::Ldr
    } else {
        kalos::metrics::flip::Range::Hdr
    };
    let m = kalos::metrics::Metrics::compute_range(&x, &y, range)
        .map_err(|e| value_error(format!("image vs reference: {e}")))?;
    serde_json::to_string(&m).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// One little-endian 4-byte word per pixel (`counts` as u32, K[p] as f32), checked for
/// the film's pixel count.
fn words<T>(
    data: &[u8],
    pixels: usize,
    what: &str,
    from: fn([u8; 4]) -> T,
) -> Result<Vec<T>, String> {
    if data.len() != pixels * 4 {
        return Err(format!(
            "{what}: {} bytes, {pixels} pixels need {}",
            data.len(),
            pixels * 4
        ));
    }
    Ok(data
        .chunks_exact(4)
        .map(|b| from([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// What a task of a DTF pass returns: its film bytes, its rest film's bytes (passes with
/// `rest`), rays per pixel (u64 bytes, when asked), paths, rays and light rays.
type PartOut = (Vec<u8>, Option<Vec<u8>>, Vec<u8>, u64, u64, u64);
/// [`PartOut`] as Python bytes.
type PartBytes<'py> = (
    Bound<'py, PyBytes>,
    Option<Bound<'py, PyBytes>>,
    Bound<'py, PyBytes>,
    u64,
    u64,
    u64,
);

/// One part of a DTF pass (a Dask task of `kalos.distributed`): samples `first..first+n`
/// of every pixel (or `first..first+counts[p]`, counts as u32 bytes) of the phase with
/// dependent tests or not, on `stream`; or, with `light_paths` > 0, light paths
/// `first..first+light_paths` (phase 2's light pass over BDPT). `k`: the pass's K[p]
/// (BDPT's light-tracing ratio, f32 bytes), read by its camera samples and light paths
/// alike. With `rest`, also the film of the samples less their emission seen directly
/// (`--dtf-direct split`). Returns (film bytes, rest film bytes or None, rays per pixel
/// as u64 bytes (when `rays`), paths, rays, light rays).
#[pyfunction]
#[pyo3(signature = (scene, argv, dependent, stream, first, n, counts, rays, k = None, light_paths = 0, rest = false))]
#[allow(clippy::too_many_arguments)]
fn render_dtf_part<'py>(
    py: Python<'py>,
    scene: &NativeScene,
    argv: Vec<String>,
    dependent: bool,
    stream: u32,
    first: u64,
    n: u32,
    counts: Option<Vec<u8>>,
    rays: bool,
    k: Option<Vec<u8>>,
    light_paths: u64,
    rest: bool,
) -> PyResult<PartBytes<'py>> {
    use kalos::integrator::bdpt::LtRatio;
    use kalos::pipeline::{Counts, DtfPass};
    let job = parse_job(&scene.spec, &argv).map_err(value_error)?;
    let sc = scene.scene.clone();
    let out = py.detach(move || -> Result<PartOut, String> {
        let set = job.settings(&sc);
        let pixels = set.width as usize * set.height as usize;
        let per_pixel = match &counts {
            Some(c) => Some(words(c, pixels, "counts", u32::from_le_bytes)?),
            None => None,
        };
        let k = match &k {
            Some(b) => Some(Arc::new(LtRatio {
                width: set.width,
                height: set.height,
                k: words(b, pixels, "k", f32::from_le_bytes)?,
            })),
            None => None,
        };
        let pass = DtfPass {
            lt_ratio: k.as_ref(),
            light_paths,
            rest,
            ..DtfPass::samples(
                dependent,
                stream,
                match &per_pixel {
                    Some(v) => Counts::PerPixel(v),
                    None => Counts::Uniform(n),
                },
                rays,
            )
        };
        // the part's range: sample indices, or light-path numbers of a light pass
        let end = first
            + if light_paths > 0 {
                light_paths
            } else {
                per_pixel
                    .as_ref()
                    .map_or(n, |v| v.iter().copied().max().unwrap_or(0)) as u64
            };
        let (film, rest_film, r, c) = kalos::render::render_dtf_part(&sc, &job, &pass, first, end)?;
        let rb: Vec<u8> = r.iter().flat_map(|x| x.to_le_bytes()).collect();
        Ok((
            film_to_bytes(&film),
            rest_film.map(|f| film_to_bytes(&f)),
            rb,
            c.paths,
            c.rays,
            c.light_rays,
        ))
    });
    let (fb, restb, rb, paths, nrays, light_rays) = out.map_err(value_error)?;
    Ok((
        PyBytes::new(py, &fb),
        restb.map(|b| PyBytes::new(py, &b)),
        PyBytes::new(py, &rb),
        paths,
        nrays,
        light_rays,
    ))
}

/// DTF's passes handed to a Python function that splits each into parts and returns
/// them [(film bytes, rest film bytes or None, rays bytes, paths, rays, light rays), ...]
/// (`render_dtf_part`'s); merged here exactly.
struct PyPasses<'a> {
    run_pass: &'a Bound<'a, PyAny>,
    error: Option<PyErr>,
    width: u32,
    height: u32,
}

/// A pass's films (the rest film with `rest`), rays per pixel and counters.
type Merged = (
    kalos::film::Film,
    Option<kalos::film::Film>,
    Vec<u64>,
    kalos::integrator::Counters,
);

impl PyPasses<'_> {
    /// `run_pass(dependent, stream, n, counts, rays, k, light_paths, rest)`: the pass's
    /// parts, merged in their order (integer sums: any order gives the same bits).
    fn parts(&mut self, pass: &kalos::pipeline::DtfPass<'_>) -> Result<Merged, String> {
        use kalos::pipeline::Counts;
        let py = self.run_pass.py();
        let (n, counts) = match pass.counts {
            Counts::Uniform(n) => (n, None),
            Counts::PerPixel(v) => {
                let b: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
                (0, Some(PyBytes::new(py, &b)))
            }
        };
        // K[p] as f32 bytes: every part's camera samples and light paths read these bits
        let k = pass.lt_ratio.map(|k| {
            let b: Vec<u8> = k.k.iter().flat_map(|x| x.to_le_bytes()).collect();
            PyBytes::new(py, &b)
        });
        let r = self
            .run_pass
            .call1((
                pass.dependent,
                pass.stream,
                n,
                counts,
                pass.rays,
                k,
                pass.light_paths,
                pass.rest,
            ))
            .and_then(|r| r.extract::<Vec<PartOut>>());
        let parts = match r {
            Ok(p) => p,
            Err(e) => {
                self.error = Some(e);
                return Err("interrupted".into());
            }
        };
        let pixels = self.width as usize * self.height as usize;
        let mut film: Option<kalos::film::Film> = None;
        let mut rest: Option<kalos::film::Film> = None;
        let mut rays = vec![0u64; if pass.rays { pixels } else { 0 }];
        let mut c = kalos::integrator::Counters::default();
        let read = |b: &[u8], what: &str| -> Result<kalos::film::Film, String> {
            let f = film_from_bytes(b, what)?;
            if (f.film.width, f.film.height) != (self.width, self.height) {
                return Err(format!("{what}: another film size"));
            }
            Ok(f.film)
        };
        // (the first part's film, splats and all, then exact sums of the others)
        let add = |into: &mut Option<kalos::film::Film>, f: kalos::film::Film| match into {
            None => *into = Some(f),
            Some(m) => m.merge(&f),
        };
        for (i, (fb, restb, rb, paths, nrays, light_rays)) in parts.iter().enumerate() {
            add(&mut film, read(fb, &format!("dtf pass part {i}"))?);
            match (pass.rest, restb) {
                (true, Some(b)) => add(&mut rest, read(b, &format!("dtf pass part {i}'s rest"))?),
                (true, None) => return Err(format!("dtf pass part {i}: no rest film")),
                _ => {}
            }
            if pass.rays {
                if rb.len() != pixels * 8 {
                    return Err(format!("dtf pass part {i}: no rays per pixel"));
                }
                for (r, b) in rays.iter_mut().zip(rb.chunks_exact(8)) {
                    *r += u64::from_le_bytes(b.try_into().unwrap_or_default());
                }
            }
            c.add(&kalos::integrator::Counters {
                paths: *paths,
                rays: *nrays,
                light_rays: *light_rays,
            });
        }
        let film = match film {
            Some(f) => f,
            None => kalos::film::Film::new(self.width, self.height)?,
        };
        let rest = match (pass.rest, rest) {
            (true, None) => Some(kalos::film::Film::new(self.width, self.height)?),
            (_, r) => r,
        };
        Ok((film, rest, rays, c))
    }
}

impl kalos::pipeline::DtfPasses for PyPasses<'_> {
    fn run(
        &mut self,
        pass: kalos::pipeline::DtfPass<'_>,
    ) -> Result<(kalos::film::Film, Vec<u64>, kalos::integrator::Counters), String> {
        let (film, _, rays, c) = self.parts(&pass)?;
        Ok((film, rays, c))
    }

    fn run_rest(
        &mut self,
        pass: kalos::pipeline::DtfPass<'_>,
    ) -> Result<
        (
            kalos::film::Film,
            kalos::film::Film,
            Vec<u64>,
            kalos::integrator::Counters,
        ),
        String,
    > {
        let (film, rest, rays, c) = self.parts(&pass)?;
        let rest = rest.ok_or("dtf: run_rest was given a pass without `rest`")?;
        Ok((film, rest, rays, c))
    }
}

/// DTF on the client with its passes run by `run_pass(dependent, stream, n, counts,
/// rays, k, light_paths, rest)` (kalos.distributed: Dask tasks of `render_dtf_part`): the
/// allocation, K[p], top-ups and the filter run here, so the image is the one-process DTF
/// image, bit for bit (over BDPT too: its light pass and `--dtf-direct split`).
#[pyfunction]
fn render_dtf_with(
    py: Python<'_>,
    scene: &NativeScene,
    argv: Vec<String>,
    run_pass: Bound<'_, PyAny>,
) -> PyResult<NativeRendered> {
    let job = parse_job(&scene.spec, &argv).map_err(value_error)?;
    let sc = &scene.scene;
    let set = job.settings(sc);
    let mut passes = PyPasses {
        run_pass: &run_pass,
        error: None,
        width: set.width,
        height: set.height,
    };
    let progress = PyProgress::default();
    let r = kalos::render::render_dtf_with(sc, &job, &mut passes, &progress);
    if let Some(e) = passes.error.take() {
        return Err(e);
    }
    let r = r.map_err(value_error)?;
    let warnings = r.warnings.clone();
    native_rendered(py, &job, r, warnings, &progress)
}

/// The native module.
#[pymodule]
fn _kalos(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(options, m)?)?;
    m.add_function(wrap_pyfunction!(parse, m)?)?;
    m.add_function(wrap_pyfunction!(scenes, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(render_dtf_part, m)?)?;
    m.add_function(wrap_pyfunction!(render_dtf_with, m)?)?;
    m.add_class::<NativeScene>()?;
    m.add_class::<NativeFilm>()?;
    m.add_class::<NativeRendered>()?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("DEFAULT_SPP", DEFAULT_SPP)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
