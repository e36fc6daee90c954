//! `kalos filter energy IN.exr -o OUT.exr --rw-d 5`: Rushmeier and Ward's energy-preserving
//! filter (section 4.1; `filter::energy`) alone, on an EXR written with `--aovs`: the
//! image's RGB are the pixel means, the `variance` layer the per-sample variances (so
//! S_p = sum_c w_c sigma_c) and the `count` layer the trials M. Lt_vis = L_ave / N_MID of
//! the image itself (the image stands in for the pilot).

use crate::filter::energy::{self, EnergyParams};
use crate::image_io::{read_exr_channels, write_image, RgbImage};
use clap::{Args, Subcommand};
use std::path::PathBuf;

#[derive(Subcommand, Debug, Clone)]
pub enum FilterCommand {
    /// Rushmeier and Ward's energy-preserving filter on an EXR written with `--aovs`.
    Energy(EnergyArgs),
}

#[derive(Args, Debug, Clone)]
pub struct EnergyArgs {
    /// The input: an EXR with the `variance` and `count` layers (`kalos render --aovs`).
    pub input: PathBuf,
    /// Output image (.exr, .pfm or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// D, the visible difference in display units of 255 (paper: 5).
    #[arg(long = "rw-d", default_value_t = energy::DEFAULT_D, allow_hyphen_values = true)]
    pub d: f64,
    /// t of the convergence test t S_p / sqrt(M) <= D Lt_vis.
    #[arg(long = "rw-t", default_value_t = energy::DEFAULT_T, allow_hyphen_values = true)]
    pub t: f64,
}

pub fn run(cmd: FilterCommand) -> Result<(), String> {
    match cmd {
        FilterCommand::Energy(a) => energy_cmd(&a),
    }
}

fn energy_cmd(a: &EnergyArgs) -> Result<(), String> {
    energy::check_d(a.d)?;
    if !(a.t.is_finite() && a.t > 0.0) {
        return Err(format!("--rw-t {}: must be a positive number", a.t));
    }
    crate::image_io::format_of(&a.output).map_err(|e| format!("-o/--output: {e}"))?;
    let names = [
        "R",
        "G",
        "B",
        "variance.R",
        "variance.G",
        "variance.B",
        "count.Y",
    ];
    let (w, h, ch) = read_exr_channels(&a.input, &names).map_err(|e| {
        if e.contains("no channel") {
            format!(
                "{}: no variance and count layers (render it with --aovs to an .exr)",
                a.input.display()
            )
        } else {
            e
        }
    })?;
    let n = (w as usize) * (h as usize);
    let w_l = crate::spectrum::LUMINANCE_RGB;
    let mut mean = Vec::with_capacity(n);
    let mut s = Vec::with_capacity(n);
    let mut m = Vec::with_capacity(n);
    #[allow(clippy::needless_range_loop)] // seven planes read at one pixel
    for i in 0..n {
        mean.push([ch[0][i] as f64, ch[1][i] as f64, ch[2][i] as f64]);
        s.push(
            (0..3)
                .map(|c| w_l[c] as f64 * (ch[3 + c][i].max(0.0) as f64).sqrt())
                .sum(),
        );
        let k = ch[6][i];
        if !(k.is_finite() && k >= 0.0) {
            return Err(format!(
                "{}: count layer at pixel ({}, {}) is {k}, not a trial count",
                a.input.display(),
                i % w as usize,
                i / w as usize
            ));
        }
        m.push(k.round() as u32);
    }
    let l_ave = energy::l_ave(&mean);
    let p = EnergyParams {
        d: a.d,
        lt_vis: energy::lt_vis(l_ave),
        t: a.t,
    };
    let out = energy::energy_filter(w, h, &mean, &s, &m, &p)
        .map_err(|e| format!("{}: {e}", a.input.display()))?;
    let data = out.image.iter().map(|c| c.map(|v| v as f32)).collect();
    write_image(&a.output, &RgbImage::new(w, h, data), 0.0, &[])?;
    eprintln!(
        "kalos: energy filter: {} noise pixels of {}, {} spread, {} passes -> {}",
        out.noise_pixels,
        n,
        out.spread_pixels,
        out.passes,
        a.output.display()
    );
    Ok(())
}
