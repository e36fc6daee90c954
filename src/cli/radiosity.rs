//! `kalos radiosity SCENE -o out.ply`: the radiosity preprocess alone, its
//! meshed solution written as a vertex-coloured PLY, its figures as JSON (`--stats`).

use crate::radiosity::{ply, RadiositySettings, RadiosityStats, Solution};
use crate::spectrum::SpectralMode;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct RadiosityArgs {
    /// Built-in scene name, .obj, .toml or Mitsuba .xml file.
    pub scene: String,
    /// The meshed solution (.ply, vertex colours: MeshLab, Blender).
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub settings: RadiositySettings,
    /// Spectral bands: rgb | 8 | 16.
    #[arg(long, value_enum, default_value_t = SpectralMode::Rgb)]
    pub spectral: SpectralMode,
    /// Write the figures (elements, shots, rays, seconds, residual) as JSON here.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = crate::options::parse_threads)]
    pub threads: Option<usize>,
    /// No progress bar and no summary (warnings and errors still print).
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(serde::Serialize)]
struct StatsFile<'a> {
    scene: &'a str,
    settings: &'a RadiositySettings,
    stats: &'a RadiosityStats,
}

pub fn run(a: RadiosityArgs) -> Result<(), String> {
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() != Some("ply") {
        return Err(format!(
            "-o {}: the radiosity solution is written as .ply",
            a.output.display()
        ));
    }
    let set = a.settings;
    set.validate()?;
    let scene = crate::scene::load(&a.scene)?;
    // The solution has no camera: the default camera's warning does not apply.
    for w in &scene.warnings_for(true) {
        eprintln!("kalos: warning: {w}");
    }
    let (pool, warning) = crate::render::thread_pool(a.threads)?;
    if let Some(w) = warning {
        eprintln!("kalos: warning: {w}");
    }
    super::progress::install_interrupt_handler();
    let pb = super::progress::CliProgress::new(a.quiet);
    let sol = pool.install(|| Solution::compute(&scene, &set, a.spectral.bands(), &pb))?;
    ply::write_ply(&sol, &a.output)?;
    let s = &sol.stats;
    if !s.converged {
        eprintln!(
            "kalos: warning: radiosity stopped after {} shots with {:.2e} of the emitted power unshot",
            s.shots, s.residual_unshot
        );
    }
    if !a.quiet {
        println!(
            "radiosity    {} elements, {} vertices (max area {:.4}), {} shots, {} rays",
            s.elements, s.vertices, s.max_area, s.shots, s.rays
        );
        println!(
            "time         {:.2} s (mesh {:.3} s, solve {:.2} s), unshot {:.2e} of the emitted",
            s.seconds, s.mesh_seconds, s.solve_seconds, s.residual_unshot
        );
        println!("wrote        {}", a.output.display());
    }
    if let Some(path) = &a.stats {
        let f = StatsFile {
            scene: &scene.info.name,
            settings: &set,
            stats: s,
        };
        let text = serde_json::to_string_pretty(&f).map_err(|e| e.to_string())?;
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}
