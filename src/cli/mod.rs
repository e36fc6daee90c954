//! The command line: `kalos render|scenes|info`. Parsing lives here; the work is done
//! by the library. Every error is one line naming the file, line or option at fault.

pub mod experiment;
pub mod filter;
pub mod progress;
pub mod radiosity;
pub mod reference;
pub mod render;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(name = "kalos", version, about = "A Monte-Carlo global illumination renderer", long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
#[allow(clippy::large_enum_variant)] // parsed once per process
pub enum Command {
    /// Render a scene (built-in name, .obj, .toml or Mitsuba .xml) to an image.
    Render(render::RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Error metrics of an image against a reference: RMSE, relMSE, perceptual error
    /// (pixels whose relative colour error exceeds 5%) and the ratio of mean luminances.
    Compare {
        /// The image to judge (.exr, .pfm or .png).
        image: std::path::PathBuf,
        /// The reference image.
        reference: std::path::PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Run named configurations at equal budgets against a reference: CSV, JSON, plots.
    Experiment {
        /// The experiment file (.toml).
        file: std::path::PathBuf,
        /// Output folder (default: FILE-results beside the file).
        #[arg(long)]
        out: Option<std::path::PathBuf>,
        /// No per-run lines.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Merge film files (.kfilm) of one render's sample ranges into one image or film.
    Merge {
        /// The parts (rendered with `-o part.kfilm --first-sample K --spp N`).
        #[arg(required = true)]
        parts: Vec<std::path::PathBuf>,
        /// Output: .exr, .pfm, .png or .kfilm.
        #[arg(short, long)]
        output: std::path::PathBuf,
        /// Write per-pixel variance and sample count as extra EXR layers.
        #[arg(long)]
        aovs: bool,
    },
    /// Solve the scene's radiosity (the preprocess of Rushmeier and Ward's path tracer)
    /// and write the meshed solution as a vertex-coloured PLY.
    Radiosity(radiosity::RadiosityArgs),
    /// Filters on images written before (`energy`: Rushmeier and Ward's).
    #[command(subcommand)]
    Filter(filter::FilterCommand),
    /// Print triangles, materials, emitters, bounds and load/BVH times of a scene.
    Info {
        /// Built-in scene name, .obj, .toml or Mitsuba .xml file.
        scene: String,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

/// Parse the command line. A bad option value (`--res abc`, `--max-depth 0`) is reported
/// on one line, `kalos: error: invalid value 'abc' for '--res <RES>': ...`, exit code 2;
/// other usage errors (unknown options, with clap's tip), help and version are clap's own.
pub fn parse_args() -> Cli {
    use clap::error::ErrorKind;
    match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e)
            if matches!(
                e.kind(),
                ErrorKind::InvalidValue | ErrorKind::ValueValidation
            ) =>
        {
            let text = e.render().to_string();
            let first = text.lines().next().unwrap_or_default();
            eprintln!("kalos: error: {}", first.trim_start_matches("error: "));
            std::process::exit(2);
        }
        Err(e) => e.exit(),
    }
}

/// Run the CLI; Err is a one-line message for stderr.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.command {
        Command::Render(args) => render::run(args),
        Command::Scenes => {
            for (name, what) in crate::scene::builtin::describe() {
                println!("{name:<15} {what}");
            }
            Ok(())
        }
        Command::Compare {
            image,
            reference,
            json,
        } => {
            let x = crate::image_io::read_image(&image)?;
            let y = crate::image_io::read_image(&reference)?;
            // NaN metrics, or a 0x0 "perfect match", would tell the user nothing
            crate::metrics::check_comparable(&x, &image.display().to_string())?;
            crate::metrics::check_comparable(&y, &reference.display().to_string())?;
            let m = crate::metrics::Metrics::compute(&x, &y)
                .map_err(|e| format!("{} vs {}: {e}", image.display(), reference.display()))?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&m).map_err(|e| e.to_string())?
                );
            } else {
                println!("rmse              {:.6}", m.rmse);
                println!("relmse            {:.6}", m.relmse);
                println!(
                    "perceptual error  {} pixels ({:.2}%) above 5% relative error",
                    m.perceptual_count,
                    m.perceptual_share * 100.0
                );
                println!("luminance ratio   {:.5}", m.luminance_ratio);
            }
            Ok(())
        }
        Command::Experiment { file, out, quiet } => experiment::run(&file, out, quiet),
        Command::Merge {
            parts,
            output,
            aovs,
        } => merge(&parts, &output, aovs),
        Command::Radiosity(args) => radiosity::run(args),
        Command::Filter(cmd) => filter::run(cmd),
        Command::Info { scene, json } => {
            let s = crate::scene::load(&scene)?;
            for w in &s.warnings_for(false) {
                eprintln!("kalos: warning: {w}");
            }
            let i = &s.info;
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(i).map_err(|e| e.to_string())?
                );
            } else {
                println!("scene        {}", i.name);
                println!("triangles    {}", i.triangles);
                println!("materials    {}", i.materials);
                println!("emitters     {} triangles", i.emitters);
                println!("skipped      {} zero-area faces", i.skipped_degenerate);
                println!(
                    "bounds       [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}]",
                    i.bounds_min[0],
                    i.bounds_min[1],
                    i.bounds_min[2],
                    i.bounds_max[0],
                    i.bounds_max[1],
                    i.bounds_max[2]
                );
                if let Some(c) = &i.camera {
                    // a Mitsuba sensor's fov along x (or another axis) given vertically
                    // at the scene's resolution, as --camera takes it
                    let (w, h) = s.defaults.res.unwrap_or(crate::render::DEFAULT_RES);
                    let at = if c.fov_axis == crate::scene::FovAxis::Y {
                        String::new()
                    } else {
                        format!("; its field of view vertical at {w}x{h}")
                    };
                    let arg = c.vertical(w, h).to_arg();
                    println!("camera       --camera {arg} ({}{at})", i.camera_from);
                }
                println!("load         {:.3} s", i.load_seconds);
                let (nodes8, leaves, packets) = s.bvh.shape();
                println!(
                    "bvh          {:.3} s, {} nodes ({nodes8} 8-wide with {:.2} children on \
                     average, {leaves} leaves in {packets} triangle packets), {:.1} MiB, \
                     traversal {}",
                    i.bvh_seconds,
                    i.bvh_nodes,
                    (nodes8.max(1) - 1 + leaves) as f64 / nodes8.max(1) as f64,
                    i.bvh_bytes as f64 / 1048576.0,
                    s.bvh.isa().name()
                );
                let e = &crate::integrator::RadianceEstimate::of_scene(&s);
                let l = e.l_tilde::<3>();
                println!(
                    "L~           [{:.4}, {:.4}, {:.4}] (estimate roulette; a~ [{:.3}, {:.3}, {:.3}], \
                     S {:.4}, e_s {:.4}, e_L {:.4})",
                    l[0],
                    l[1],
                    l[2],
                    e.albedo[0],
                    e.albedo[1],
                    e.albedo[2],
                    e.area,
                    e.e_s,
                    e.e_l
                );
            }
            Ok(())
        }
    }
}

/// `kalos merge`: read the parts, check they belong together, merge exactly, write.
fn merge(parts: &[std::path::PathBuf], output: &std::path::Path, aovs: bool) -> Result<(), String> {
    if !render::is_film_path(output) {
        crate::image_io::format_of(output).map_err(|e| format!("-o/--output: {e}"))?;
    }
    let files = parts
        .iter()
        .map(|p| Ok((p.display().to_string(), crate::film::read_film(p)?)))
        .collect::<Result<Vec<_>, String>>()?;
    let m = crate::film::merge_files(&files)?;
    if render::is_film_path(output) {
        return crate::film::write_film(output, &m);
    }
    let img = crate::image_io::RgbImage::new(m.film.width, m.film.height, m.film.mean_rgb());
    render::write_output(output, &img, &m.film, 0.0, aovs)
}
