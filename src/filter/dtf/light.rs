//! DTF over an estimator that splats (BDPT): light tracing as work of its own.
//!
//! A pixel's value is the mean of its camera samples plus the splat image, whose noise is
//! set by the light paths of the whole film, not by the pixel's own N: on `caustic` 1% of
//! the pixels (the caustic and its reflection) held 80% of plain BDPT's squared error, and
//! DTF's per-pixel allocation could not reach them. Phase 1 (n samples per pixel, one
//! light subpath each) keeps both parts of every pixel's batch images, so the variance of
//! each part can be read separately (`SplatFilm::batch_variance_parts`):
//! - per camera sample, v[p] = n x Var(camera mean) (falls with N[p]);
//! - per light path per pixel, s[p] = (L1 / P) x Var(splat image) (falls with L / P, L the
//!   light paths of the whole film).
//!
//! Phase 2 then spends a share f of its budget (in rays) on light subpaths traced for light
//! tracing alone and the rest on camera samples (each with its own light subpath), with f
//! minimising the model error E(f) = (sum sqrt v)^2 / N_cam + P sum s / L
//! (N_cam = (1 - f) N0 camera samples allocated by sigma, L = N_cam + f N0 c_cam / c_lt
//! light paths): [`plan_light`]. The camera samples are shared from the camera part's
//! sigma alone ([`camera_part`]): more camera samples in a pixel do not lower its splats'
//! noise.

use crate::film::Film;

/// `--dtf-light`.
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
pub enum LightMode {
    /// Light paths of their own, camera samples from the camera part's sigma, MIS with
    /// each pixel's K.
    #[default]
    Auto,
    /// One light subpath per camera sample, as plain BDPT.
    Off,
}

/// The light work of phase 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPlan {
    /// Share of phase 2's budget (rays) for light paths of their own.
    pub share: f64,
    /// Rays per camera sample and per light path of its own (estimated from phase 1).
    pub cost_camera: f64,
    pub cost_light: f64,
    /// Phase 1's variance split: sum over pixels of the splat image's variance over the
    /// whole variance of the values (for `--stats`).
    pub splat_variance_share: f64,
}

impl LightPlan {
    /// Light paths of their own for an average of `spp` phase-2 samples per pixel over
    /// `pixels` pixels (before the camera samples get their (1 - share)).
    pub fn light_paths(&self, spp: f64, pixels: usize) -> u64 {
        let r = self.cost_camera / self.cost_light.max(1e-9);
        (self.share * spp * pixels as f64 * r).round().max(0.0) as u64
    }
}

/// The cost of a light path of its own per ray of its subpath, in the rays of a camera
/// sample: measured on `caustic` 96x96 at 64 spp, one thread (a camera sample 0.70 us, a
/// light path 0.19 us, with 2.6 subpath rays per light path and 8.3 rays per camera sample).
pub const LIGHT_PATH_COST: f64 = 1.4;

/// The most of phase 2 light paths of their own may take.
pub const MAX_LIGHT_SHARE: f64 = 0.95;

/// Phase 2's light work from phase 1 (`dep`, n samples per pixel, one light subpath each)
/// and its work counters: rays per camera sample `rays / samples`, of which `light_rays`
/// extended light subpaths. `fixed` overrides the model's share. None when the film does
/// not splat.
pub fn plan_light(
    dep: &Film,
    samples: u64,
    rays: u64,
    light_rays: u64,
    fixed: Option<f64>,
) -> Option<LightPlan> {
    dep.splats.as_ref()?;
    let pixels = dep.pixels.len();
    if samples == 0 || pixels == 0 {
        return None;
    }
    let cost_camera = (rays as f64 / samples as f64).max(1.0);
    // a light path of its own: its subpath, then one shadow ray to the camera per vertex;
    // those are cheap (an any-hit query, no MIS over s + t strategies), so the path counts
    // LIGHT_PATH_COST rays per subpath ray
    let cost_light = (LIGHT_PATH_COST * light_rays as f64 / samples as f64).max(1.0);
    let (mut sqrt_v, mut s_sum, mut var_splat, mut var_all) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for i in 0..pixels {
        if let Some(p) = sample_variances(dep, i) {
            sqrt_v += p.v.max(0.0).sqrt();
            s_sum += p.s.max(0.0);
            var_splat += p.var_splat;
            var_all += p.var_splat + p.var_camera;
        }
    }
    let rho = cost_camera / cost_light;
    let a = sqrt_v * sqrt_v;
    let b = pixels as f64 * s_sum;
    // E(f) N0 = a / (1 - f) + b / (1 - f + f rho)
    let err = |f: f64| a / (1.0 - f) + b / (1.0 - f + f * rho);
    let share = match fixed {
        Some(f) => f.clamp(0.0, MAX_LIGHT_SHARE),
        None => {
            let mut best = (err(0.0), 0.0);
            for k in 1..=95 {
                let f = k as f64 / 100.0;
                let e = err(f);
                if e < best.0 {
                    best = (e, f);
                }
            }
            best.1
        }
    };
    Some(LightPlan {
        share,
        cost_camera,
        cost_light,
        splat_variance_share: if var_all > 0.0 {
            var_splat / var_all
        } else {
            0.0
        },
    })
}

/// The film of phase 1 without its splats: what the camera samples' allocation reads
/// (their sigma is the spread of the pixel's own samples, which more samples there lower).
pub fn camera_part(dep: &Film) -> Film {
    Film {
        width: dep.width,
        height: dep.height,
        pixels: dep.pixels.clone(),
        rejected: dep.rejected,
        splats: None,
    }
}

/// K[p] for the MIS weights of phase 2: the light paths per camera sample in each pixel,
/// L / (P N[p]), with N[p] the camera samples a pixel is expected to take (`expected`)
/// and L the light paths of the whole phase, clamped to `lo..=hi`.
pub fn lt_ratio(expected: &[f64], light_paths: f64, lo: f32, hi: f32) -> Vec<f32> {
    let p = expected.len().max(1) as f64;
    expected
        .iter()
        .map(|&n| {
            if n > 0.0 {
                ((light_paths / (p * n)) as f32).clamp(lo, hi)
            } else {
                hi
            }
        })
        .collect()
}

/// The camera samples N_eff[p] that would give phase 2's value of pixel p the variance it
/// has (phase 1's model): its camera part falls with its own N[p], its splats with the
/// light paths of the whole phase, L2 / P per pixel, which with light paths of their own
/// exceed N[p] (and in a pixel with N[p] above the average, fall short of it):
/// N_eff = 1 / ((1 - r) / N + r / (L2 / P)), r the splats' share of a sample's variance.
/// The filter and the display weigh by it (`Dtf::cd_share`), so C_d's few light paths do
/// not weigh as if phase 2 had as few.
///
/// r is read from phase 1's two parts (`plan_light`: v and s per sample) summed over a
/// (2 `EFFECTIVE_RADIUS` + 1)^2 window, not from the pixel alone, so that the weights do
/// not follow a pixel's own noise (8 batches per pixel). None unless both films splat.
pub fn effective_counts(dep: &Film, indep: &Film) -> Option<Vec<f64>> {
    dep.splats.as_ref()?;
    let si = indep.splats.as_ref()?;
    let p = dep.pixels.len();
    if p == 0 || si.light_paths == 0 {
        return None;
    }
    let l2 = si.light_paths as f64 / p as f64;
    let (mut v, mut s): (Vec<f64>, Vec<f64>) = (0..p)
        .map(|i| match sample_variances(dep, i) {
            Some(q) => (q.v.max(0.0), q.s.max(0.0)),
            None => (0.0, 0.0),
        })
        .unzip();
    let (w, h) = (dep.width as usize, dep.height as usize);
    box_sum(&mut v, w, h, EFFECTIVE_RADIUS);
    box_sum(&mut s, w, h, EFFECTIVE_RADIUS);
    Some(
        (0..p)
            .map(|i| {
                let n = indep.pixels[i].n as f64;
                if n == 0.0 {
                    return 0.0;
                }
                let r = s[i] / (v[i] + s[i]);
                let e = 1.0 / ((1.0 - r) / n + r / l2);
                if e.is_finite() && e > 0.0 {
                    e
                } else {
                    n
                }
            })
            .collect(),
    )
}

/// Phase 1's variance of pixel i in its two parts, per sample (module docs).
struct SampleVariances {
    /// v[p] = n x Var(camera mean): per camera sample.
    v: f64,
    /// s[p] = (L1 / P) x Var(splat image): per light path per pixel.
    s: f64,
    /// The two variances of the value, summed over the channels.
    var_camera: f64,
    var_splat: f64,
}

/// [`SampleVariances`] of pixel i of phase 1's film; None without splats or where either
/// part is not finite.
fn sample_variances(dep: &Film, i: usize) -> Option<SampleVariances> {
    let sf = dep.splats.as_ref()?;
    let pixels = dep.pixels.len();
    let (vc, vs) = sf.batch_variance_parts(i, pixels);
    let (var_camera, var_splat) = (vc.iter().sum::<f64>(), vs.iter().sum::<f64>());
    let v = dep.pixels[i].n as f64 * var_camera;
    let s = sf.light_paths as f64 / pixels as f64 * var_splat;
    (v.is_finite() && s.is_finite()).then_some(SampleVariances {
        v,
        s,
        var_camera,
        var_splat,
    })
}

/// Half the side of `effective_counts`'s window.
pub const EFFECTIVE_RADIUS: usize = 8;

/// In place: each value becomes the sum over the (2 r + 1)^2 window around it (clipped to
/// the image), rows then columns.
fn box_sum(a: &mut [f64], w: usize, h: usize, r: usize) {
    let mut tmp = vec![0.0; a.len()];
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x.saturating_sub(r), (x + r).min(w - 1));
            tmp[y * w + x] = a[y * w + x0..=y * w + x1].iter().sum();
        }
    }
    for y in 0..h {
        let (y0, y1) = (y.saturating_sub(r), (y + r).min(h - 1));
        for x in 0..w {
            a[y * w + x] = (y0..=y1).map(|yy| tmp[yy * w + x]).sum();
        }
    }
}

/// sigma[p] for the filter's weights over BDPT with light paths of their own: the root
/// mean square of phase 1's sigma over the (2 `EFFECTIVE_RADIUS` + 1)^2 window. Phase 1's
/// C_d is filtered with the same weights as C_i, and a pixel whose dependent samples caught
/// a bright splat has a large sigma of its own, so the filter averaged exactly that pixel's
/// bright C_d away with its neighbours (whose small sigma kept them to themselves): C_d' and
/// the image came out dark (caustic 16 spp, seeds 1 and 2: 0.931 and 0.938 of the
/// reference; with the window's sigma 0.988 and 1.001, RMSE 2.5% lower, 3 points fewer
/// pixels more than 5% off).
pub fn smoothed_sigma(sigma: &[f64], w: usize, h: usize) -> Vec<f64> {
    let mut s2: Vec<f64> = sigma.iter().map(|s| s * s).collect();
    let mut k = vec![1.0; sigma.len()];
    box_sum(&mut s2, w, h, EFFECTIVE_RADIUS);
    box_sum(&mut k, w, h, EFFECTIVE_RADIUS);
    s2.iter().zip(&k).map(|(s, k)| (s / k).sqrt()).collect()
}
