//! One vocabulary of options. Each option's name, help and default is written once, as a
//! clap attribute on the library's settings type that holds it (`render::RenderJob`,
//! `integrator::Roulette`, `filter::dtf::DtfParams`); fixed choices are enums deriving
//! `clap::ValueEnum` and serde with the same spellings. `Default` of those types parses an
//! empty command line, so the CLI's defaults and the library's are the same by
//! construction (and the Python module reads them from here too).

use clap::{Args, FromArgMatches, ValueEnum};

/// The defaults of an option group: what an empty command line gives.
pub fn defaults<T: Args + FromArgMatches>() -> T {
    let cmd = T::augment_args(clap::Command::new("kalos").no_binary_name(true));
    let m = cmd
        .try_get_matches_from(std::iter::empty::<String>())
        .expect("every option has a default");
    T::from_arg_matches(&m).expect("defaults parse")
}

/// The command-line spelling of a choice (`RrMode::SpectralEstimate` -> "spectral-estimate").
pub fn name<T: ValueEnum>(v: &T) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// `--res WxH`.
pub fn parse_res(s: &str) -> Result<(u32, u32), String> {
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

/// `--time SECONDS`.
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a number of seconds"))?;
    if !(v > 0.0 && v.is_finite()) {
        return Err("must be a positive number of seconds".into());
    }
    Ok(v)
}

/// `--max-depth D`: -1 (unlimited) or at least 1.
pub fn parse_depth(s: &str) -> Result<i32, String> {
    let d: i32 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a whole number"))?;
    if d < -1 || d == 0 {
        return Err("must be -1 (unlimited) or at least 1".into());
    }
    Ok(d)
}

/// `--spp N`: at least 1.
pub fn parse_spp(s: &str) -> Result<u32, String> {
    let n: u32 = s
        .parse()
        .map_err(|_| format!("{s:?} is not a whole number of samples"))?;
    if n == 0 {
        return Err("must be at least 1".into());
    }
    Ok(n)
}

/// `-D key=value`: a Mitsuba scene parameter (a name of letters, digits and `_`).
pub fn parse_define(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("{s:?}: expected key=value"))?;
    let k = k.trim();
    if k.is_empty() || !k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!("{s:?}: the name {k:?} is not a parameter name"));
    }
    Ok((k.to_string(), v.to_string()))
}

/// `--threads N`: at least 1.
pub fn parse_threads(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|_| format!("{s:?} is not a whole number"))?;
    if n == 0 {
        return Err("must be at least 1".into());
    }
    Ok(n)
}

/// Which estimator (`integrator/`): here, below the scene, because a scene file may
/// name its own.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorKind {
    /// Unidirectional path tracing, next-event estimation + MIS (with `--gather
    /// radiosity`: Rushmeier and Ward's path tracer reading a radiosity solution).
    #[default]
    Path,
    /// Bidirectional path tracing: every (s, t) strategy, MIS, light-tracing splats.
    Bdpt,
    /// The radiosity solution seen directly (a preview): emitters plus B / pi at the first
    /// non-specular hit, mirrors and glass followed.
    Radiosity,
    /// Test only: every sample returns 0 and splats (x, y, 1) into the pixel to its right
    /// (wrapping), so the image is known exactly.
    #[cfg(test)]
    #[value(skip)]
    #[serde(skip)]
    SplatTest,
}
