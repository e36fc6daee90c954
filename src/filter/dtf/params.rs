//! DTF's parameters: each option's name, help and default, written once.

use serde::{Deserialize, Serialize};

// ---------------------------------------------------------------------------------------
// Parameters
// ---------------------------------------------------------------------------------------

/// Distance kernel d(q - p) that lowers the confidence in distant pixels (paper §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Kernel {
    /// d = max(R - ||q - p||, 0) with R = m / sqrt(2), the half diagonal of the m x m
    /// window. The paper prints M/sqrt(2) with M = m^2, but then d would be almost flat
    /// (for m = 4: 11.3 at the centre, 8.5 at the farthest pixel), contradicting its
    /// purpose of "decreasing the weight of distant pixels"; with m/sqrt(2) it is a real
    /// pyramid that falls to (nearly) zero at the window's corner. On even windows the
    /// farthest pixel (offset (m/2, m/2)) sits exactly at R and gets weight 0.
    #[default]
    Pyramid,
    /// The "better solution" the paper mentions: d = exp(-||q - p||^2 / (2 s^2)) with
    /// s = m / (2 sqrt(2)) = R / 2, so d(R) = e^-2.
    Gaussian,
}

/// How negative filter coefficients are removed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Clamp {
    /// As printed: f = 1/M + sqrt(N)/(3 sigma sqrt(M)) (sum_r Delta_r / M - Delta_q),
    /// f^+ = max(f, 0). Caveat: the mean of Delta is taken over all pixels, including the
    /// clipped ones, so as N -> infinity the weights tend to (mean Delta - Delta_q)^+,
    /// not to the primary pixel alone: on a colour gradient the filter does not vanish.
    Paper,
    /// The exact minimiser of the paper's linearised error under f >= 0 and sum f = 1
    /// (its KKT conditions): f_q = k (lambda - Delta_q)^+ with k = sqrt(N)/(3 sigma
    /// sqrt(M)) and lambda chosen so the positive part sums to 1 (water filling over the
    /// sorted Delta). Equal to `Paper` whenever no coefficient is clipped; as N grows all
    /// weight goes to pixels with Delta_q = 0, so the filter vanishes as the paper intends.
    #[default]
    ActiveSet,
}

/// How a sample budget is shared among pixels (budget mode, [`allocate_budget`]): N[p]
/// proportional to a weight w[p] from phase 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Allocation {
    /// w = sigma^2 / ||C_d||, as the paper prescribes for a given time or sample budget
    /// (§3). It sits between the two optima below and concentrates samples on high-sigma
    /// pixels (light edges) more than either.
    Paper,
    /// w = sigma: minimises the summed squared error sum_p sigma^2 / N[p] for a fixed total
    /// sum_p N[p] (Lagrange: N ∝ sigma). The default: on cornell and room it gave both a
    /// lower RMSE and a lower perceptual error than `Paper` at every budget measured.
    #[default]
    Mse,
    /// w = sigma / ||C_d||: minimises the summed squared *relative* error.
    RelMse,
}

impl Allocation {
    /// The weight w[p] for sigma > 0 and ||C_d|| > 0.
    #[inline]
    pub fn weight(self, sigma: f64, cd_norm: f64) -> f64 {
        match self {
            Allocation::Paper => sigma * sigma / cd_norm,
            Allocation::Mse => sigma,
            Allocation::RelMse => sigma / cd_norm,
        }
    }
}

/// How the display C = (C_d' n + C_i,f N) / (n + N) takes C_d' from phase 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum CdDisplay {
    /// C_d' = g C_d: the pixel's own C_d at phase 2's local brightness g.
    Scaled,
    /// C_d' = sum_q f*[q - p] g_q C_d[q]: g C_d averaged with the same region weights f*
    /// as C_i, so a flat region's display is smooth in both terms. The weights tend to the
    /// primary pixel alone as N grows, and C_d's share n / (n + N) vanishes, so the image
    /// stays asymptotically unbiased.
    Filtered,
    /// C_d' left out of the display (C = C_i,f where N > 0): phase 1 serves only the
    /// statistics, the allocation and the region forming.
    None,
    /// C_d' as `Filtered`, weighed by the errors of the two terms instead of by sample
    /// counts: C = a C_d' + (1 - a) C_i,f with a = V_i / (V_d + V_i), at most the paper's
    /// n / (n + N). V_i = sum_q f*_q^2 sigma_q^2 / N_q is the filtered C_i's variance
    /// (phase 2's pixels are independent, so averaging divides it); V_d = (sum_q f*_q
    /// sigma_q)^2 / n is C_d''s, taken as fully shared by the region (phase 1 gives every
    /// pixel the same random numbers, so averaging does not divide it). Both use phase 1's
    /// sigma, which phase 2's samples do not steer. In a flat region a = n / (n + M_eff N)
    /// with M_eff = 1 / sum f*^2: C_d's weight falls as the region grows, and as N grows
    /// a <= n / (n + N) vanishes as the paper's does.
    #[default]
    Mse,
}

/// What DTF does with the emission seen directly (`--dtf-direct`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum DirectMode {
    /// The emission seen directly (an emitter at the first camera vertex, or reached from
    /// it through mirrors and smooth glass only) is kept out of the tests, the regions and
    /// the filter, and added back per pixel as the mean of all its samples, both phases:
    /// C = DTF(L - E) + mean(E). A pixel half covering a light varies only because its
    /// footprint straddles the light's edge; that is image structure, not noise, and
    /// averaging it with the ceiling beside it is bias. Each part is an unbiased estimate
    /// of its own, so the sum stays (asymptotically) unbiased as the paper's display
    /// does. Only over an estimator that splits the term off without extra rays (BDPT,
    /// its s = 0 strategies); the path tracer is unchanged.
    #[default]
    Split,
    /// Everything filtered together, as the paper does.
    Filter,
}

/// Parameters of DTF (paper §6 names n, eps_r, m_max and Delta f[0]_min as the four
/// critical ones). Each option's name, help and default are written here once: the CLI
/// flattens this struct, `Default` parses an empty command line, serde reads the same.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct DtfParams {
    /// DTF: dependent samples per pixel n in phase 1 (paper: 45..70; default: 2 sqrt(spp)
    /// of an spp budget within 8..50, i.e. 16 at 64 spp, 32 at 256, 50 from 625 on; 16 for
    /// a time budget, 50 with --dtf-eps: the paper's experiments spent most samples in
    /// phase 2). The functions here read the actual
    /// per-pixel counts from the films (they differ only where non-finite samples were
    /// rejected).
    #[arg(long = "dtf-n")]
    pub n: Option<u32>,
    /// DTF: render until the prescribed relative error eps_r (the paper's mode; its Fig. 2
    /// uses 0.03) instead of a sample budget; without it, and without --spp/--time, DTF
    /// spends the same budget as a plain render of the scene.
    #[arg(long = "dtf-eps")]
    pub eps_r: Option<f32>,
    /// DTF: sample categories for N, comma-separated, strictly increasing (paper: "1, 10,
    /// 20, 50, 100"; the default fills its steps in at ratios of 1.4-1.7: N is rounded up
    /// to a category, and at low budgets the paper's 1 -> 10 step rounded most pixels up
    /// to 10 and starved the rest: on the room over BDPT at 16 spp, 6857 of 9216 pixels
    /// at 10 and the lights' edges at 20, with these categories 5-7 and 100; RMSE 0.066
    /// -> 0.035, see docs/results/dtf.md).
    #[arg(long = "dtf-categories", value_delimiter = ',', default_values_t = [0u32, 1, 2, 3, 5, 7, 10, 14, 20, 30, 50, 70, 100, 140, 200, 300, 500])]
    pub categories: Vec<u32>,
    /// DTF: largest region side m_max (paper: 4 is enough; 8 lets flat regions average
    /// more neighbours at low N, where the weights f* allow it: cornell 128x128, 64 and 256
    /// spp, perceptual error 0.76x -> 0.72x and 0.67x -> 0.61x of plain, see docs/results/dtf.md).
    #[arg(long = "dtf-mmax", default_value_t = 8)]
    pub m_max: u32,
    /// DTF: minimal decrease Delta f[0]_min of the primary weight f*[0] to grow a region
    /// (paper: 0.01). With 0.01 a flat region of equal weights stops between 6x6 and 7x7
    /// whatever --dtf-mmax (1/36 - 1/49 < 0.01); 0 lets the weights f* alone bound it, which
    /// pays at high resolution (caustic 288x288 at 64 spp with --dtf-mmax 16: perceptual error
    /// 0.70x -> 0.53x of BDPT, see docs/results/bdpt.md) and costs RMSE at low resolution.
    #[arg(long = "dtf-df0", default_value_t = 0.01, allow_hyphen_values = true)]
    pub df0_min: f32,
    /// DTF: display C = (C_d n + C_i N)/(n + N) with C_d as phase 1 gave it (the
    /// paper's). By default C_d is first rescaled per channel to phase 2's local
    /// brightness (all pixels share phase 1's random numbers, so its error is shared by
    /// the whole image and otherwise sets the image's brightness) and then filtered as
    /// --dtf-cd says.
    #[arg(long = "dtf-paper-display")]
    pub paper_display: bool,
    /// DTF: how the display takes phase 1's C_d (unless --dtf-paper-display): mse (g C_d
    /// averaged with the region's weights f*, weighed against C_i,f by the two terms'
    /// variances, C_d's taken as shared by the region, at most n / (n + N)), filtered (the
    /// same average at the paper's weight n / (n + N)), scaled (the pixel's own g C_d at
    /// n / (n + N)) or none (C_i,f alone where N > 0).
    #[arg(long = "dtf-cd", value_enum, default_value_t = CdDisplay::Mse)]
    pub cd_display: CdDisplay,
    /// DTF: distance kernel d: pyramid (the paper's) or gaussian.
    #[arg(long = "dtf-kernel", value_enum, default_value_t = Kernel::Pyramid)]
    pub kernel: Kernel,
    /// DTF: negative-weight removal: active-set (the exact minimiser of the paper's own
    /// error formula under f >= 0; equal to the printed form when nothing is clipped and,
    /// unlike it, vanishes as N grows) or paper (as printed).
    #[arg(long = "dtf-clamp", value_enum, default_value_t = Clamp::ActiveSet)]
    pub clamp: Clamp,
    /// DTF: floors of sigma and ||C_d|| for the allocation, as shares of their image means
    /// (0 = the paper's raw formula, which can starve pixels whose dependent samples
    /// agreed). See [`robust_stats`].
    #[arg(long = "dtf-floor", default_value_t = 0.05)]
    pub floor: f32,
    /// DTF with --dtf-eps: floor of sigma as a share of the pixel's own ||C_d|| (0 = none),
    /// i.e. at least (3 F / eps_r)^2 samples per pixel: all pixels share the n dependent
    /// jitters, so a pixel can miss a thin feature (a sliver of a light) in every one of
    /// them and show sigma ~ 0. At eps_r = 0.01 the Cornell light's own pixels otherwise
    /// kept a 0.8% error and the RMSE stalled (0.0086 at 0.03, 0.0082 at 0.01).
    #[arg(long = "dtf-rel-floor", default_value_t = 0.1)]
    pub relative_sigma_floor: f32,
    /// DTF: pixels whose own phase-2 mean has a relative standard error below this keep it
    /// instead of the filtered value (off unless given; the automatic method sets
    /// `AUTO_KEEP_CONVERGED`): at large budgets filtering only adds bias there.
    #[arg(long = "dtf-keep-converged")]
    pub keep_converged: Option<f32>,
    /// DTF budget mode: clip the allocation weights at this multiple of their median (0 =
    /// no clipping).
    #[arg(long = "dtf-max-ratio", default_value_t = 16.0)]
    pub max_weight_ratio: f32,
    /// DTF budget mode: share of the budget per pixel: mse (N ∝ sigma, least squared
    /// error), paper (N ∝ sigma^2/||C_d||, the paper's) or relmse (N ∝ sigma/||C_d||).
    #[arg(long = "dtf-alloc", value_enum, default_value_t = Allocation::Mse)]
    pub allocation: Allocation,
    /// DTF budget mode: weigh the allocation by the pixels' sample costs measured in phase
    /// 1 (rays per sample), N ∝ sigma / sqrt(c): least error for the time spent.
    /// `--dtf-no-cost` turns it off.
    #[arg(long = "dtf-no-cost", action = clap::ArgAction::SetFalse)]
    pub cost_aware: bool,
    /// DTF: top-up rounds from the statistics of all samples so far (both phases): with
    /// --dtf-eps for pixels that miss eps_r; with --spp/--time one round that shares
    /// --dtf-topup of phase 2's budget again (0 = the paper's single allocation).
    #[arg(long = "dtf-rounds", default_value_t = 2)]
    pub top_up_rounds: u32,
    /// DTF: top-up rounds decide from each pixel's own phase-2 statistics (biased: a
    /// pixel whose samples came out low looks converged and stays low). By default a
    /// pixel's top-up reads its phase-1 samples and its 8 neighbours' phase-2 samples.
    #[arg(long = "dtf-topup-own")]
    pub top_up_own: bool,
    /// DTF budget modes: share of phase 2's samples held back for the top-up round.
    #[arg(long = "dtf-topup", default_value_t = 0.25)]
    pub top_up_share: f32,
    /// DTF: a region stops growing at a neighbour whose N exceeds this multiple of the
    /// pixel's own (1 = the paper's rule "N[p] < N[q]"; without it, the default, no such
    /// stop).
    /// Measured without it (docs/results/dtf.md): over BDPT the caustic's image mean at 64 spp went from
    /// 0.964-0.973 of the reference to 0.988-0.997 (seeds 1-2) and its pixels more than 5%
    /// off from 81% to 73%; cornell (path tracing, 64 spp) had 1 point fewer of them. sigma from n samples is
    /// noisy, so neighbours on one flat surface land categories apart, and the rule cut
    /// their regions; regions of different colour are kept apart by Delta_q and the
    /// phase-2 guard (--dtf-guard).
    #[arg(long = "dtf-stop-ratio")]
    pub stop_ratio: Option<f32>,
    /// DTF: a neighbour's colour difference Delta_q is at least what phase 2 shows beyond
    /// this many standard errors (0 = off: Delta from the dependent phase alone, as printed).
    #[arg(long = "dtf-guard", default_value_t = 3.0)]
    pub guard: f32,
    /// DTF over an estimator that splats (BDPT): Delta_q = ||C_d[p] - C_d[q]|| less the
    /// noise the two pixels do not share, per channel sqrt((D^2 - k^2 SE^2)^+) with SE the
    /// batch-means standard error of the difference D (0 = the paper's Delta). Over BDPT
    /// each pixel's dependent samples have their own light subpath, so C_d's differences
    /// between neighbours carry independent noise the paper's shared random numbers would
    /// cancel, and regions stop growing where the image is flat. No effect without splats.
    #[arg(long = "dtf-dep-noise", default_value_t = 2.0)]
    pub dep_noise: f32,
    /// DTF: the multiple of the noise's standard deviation in the filter's error bound
    /// |sum f Delta| + z sigma sqrt(sum f^2 / N) that the weights f* minimise (paper: 3,
    /// a 3-sigma bound; smaller values filter less).
    #[arg(long = "dtf-z", default_value_t = 3.0)]
    pub z: f32,
    /// DTF over BDPT: light tracing as work of its own (auto): phase 2 shares its budget
    /// between camera samples, allocated per pixel from the variance of the camera
    /// samples alone, and light subpaths traced for light tracing alone, whose number
    /// follows phase 1's share of the variance in the splats; the MIS weights count K[p],
    /// the light paths per camera sample of each pixel. off: one light subpath per camera
    /// sample, as plain BDPT. No effect on estimators that do not splat.
    #[arg(long = "dtf-light", value_enum, default_value_t = super::LightMode::Auto)]
    pub light: super::LightMode,
    /// DTF over BDPT with --dtf-light auto: the share of phase 2's budget (rays) spent on
    /// light subpaths for light tracing alone, 0..0.95 (`MAX_LIGHT_SHARE`), instead of the share phase 1's
    /// statistics suggest.
    #[arg(long = "dtf-light-share")]
    pub light_share: Option<f32>,
    /// DTF over BDPT: split (emission seen directly, through mirrors and glass at most,
    /// kept out of the filter and added back per pixel unfiltered) or filter (the paper's:
    /// filtered with the rest). No effect on the path tracer.
    #[arg(long = "dtf-direct", value_enum, default_value_t = DirectMode::Split)]
    pub direct: DirectMode,
}

/// The largest `--dtf-n`: phase 1 is a fixed cost before any budget is shared, and
/// the paper's n is 45..70.
pub const MAX_N: u32 = 1 << 16;

/// The smallest `--dtf-eps`: a pixel whose standard deviation equals its value needs
/// (3 / eps_r)^2 samples, 9e8 at this bound.
pub const MIN_EPS: f64 = 1e-4;

impl Default for DtfParams {
    fn default() -> Self {
        crate::options::defaults::<DtfParams>()
    }
}

impl DtfParams {
    /// n for a budget: `--dtf-n` if given; else 2 sqrt(spp) of an average spp budget within
    /// 8..50 (cornell 128x128 at 256 spp: n = 16, 32, 50 gave perceptual errors 0.58x,
    /// 0.60x, 0.66x of plain and RMSE 0.29x, 0.27x, 0.29x; docs/results/dtf.md), 16 for a time
    /// budget, the paper's 50 for a relative error.
    pub fn n_for(&self, spp_budget: Option<f64>, relative: bool) -> u32 {
        match (self.n, spp_budget) {
            (Some(n), _) => n,
            (None, Some(spp)) => ((2.0 * spp.max(0.0).sqrt()).round() as u32).clamp(8, 50),
            (None, None) if relative => 50,
            (None, None) => 16,
        }
    }

    /// eps_r, or an error saying how to give it.
    pub fn eps(&self) -> Result<f64, String> {
        self.eps_r
            .map(|e| e as f64)
            .ok_or_else(|| "--dtf-eps: no relative error given".to_string())
    }

    /// A clear error for parameters the algorithm cannot use.
    pub fn validate(&self) -> Result<(), String> {
        if let Some(t) = self.keep_converged.filter(|t| !(*t > 0.0 && *t < 1.0)) {
            return Err(format!(
                "--dtf-keep-converged {t}: a relative standard error between 0 and 1 (e.g. 0.02)"
            ));
        }
        if let Some(n) = self.n.filter(|&n| n < 2) {
            return Err(format!(
                "--dtf-n {n}: the dependent phase needs at least 2 samples per pixel to estimate sigma"
            ));
        }
        if let Some(n) = self.n.filter(|&n| n > MAX_N) {
            return Err(format!(
                "--dtf-n {n}: at most {MAX_N} dependent samples per pixel (the paper uses 45..70)"
            ));
        }
        if let Some(e) = self.eps_r.filter(|e| !(e.is_finite() && *e > 0.0)) {
            return Err(format!(
                "--dtf-eps {e:e}: the relative error must be positive"
            ));
        }
        if let Some(e) = self.eps_r.filter(|&e| (e as f64) < MIN_EPS) {
            return Err(format!(
                "--dtf-eps {e:e}: below {MIN_EPS:e} a pixel whose noise is as large as its value needs more than (3 / eps_r)^2 = {:.0e} samples (the paper uses 0.03)",
                (3.0 / MIN_EPS).powi(2)
            ));
        }
        if self.categories.is_empty() {
            return Err("--dtf-categories: the list of sample categories is empty".into());
        }
        if self.categories.windows(2).any(|w| w[0] >= w[1]) {
            return Err(format!(
                "--dtf-categories {:?}: must be strictly increasing",
                self.categories
            ));
        }
        if !(1..=32).contains(&self.m_max) {
            return Err(format!(
                "--dtf-mmax {}: the window side must be 1..=32",
                self.m_max
            ));
        }
        if let Some(r) = self.stop_ratio.filter(|r| !(r.is_finite() && *r >= 1.0)) {
            return Err(format!(
                "--dtf-stop-ratio {r}: must be a number >= 1 (1 is the paper's rule)"
            ));
        }
        if !(0.0..=1.0).contains(&self.top_up_share) {
            return Err(format!(
                "--dtf-topup {}: must be between 0 and 1",
                self.top_up_share
            ));
        }
        if !(self.z.is_finite() && self.z > 0.0) {
            return Err(format!("--dtf-z {}: must be a positive number", self.z));
        }
        if !(self.dep_noise.is_finite() && self.dep_noise >= 0.0) {
            return Err(format!(
                "--dtf-dep-noise {}: must be a number >= 0",
                self.dep_noise
            ));
        }
        for (flag, v) in [
            ("--dtf-floor", self.floor),
            ("--dtf-rel-floor", self.relative_sigma_floor),
            ("--dtf-max-ratio", self.max_weight_ratio),
            ("--dtf-guard", self.guard),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{flag} {v}: must be a number >= 0"));
            }
        }
        if let Some(f) = self
            .light_share
            .filter(|f| !(0.0..=super::MAX_LIGHT_SHARE as f32).contains(f))
        {
            return Err(format!(
                "--dtf-light-share {f}: must be between 0 and {}",
                super::MAX_LIGHT_SHARE
            ));
        }
        if !self.df0_min.is_finite() {
            return Err(format!("--dtf-df0 {}: is not finite", self.df0_min));
        }
        Ok(())
    }
}
