//! Region forming and the error-optimal filter weights f* (paper §4), the filtered C_i and
//! the displayed C = (C_d n + C_i,f N) / (n + N).

use super::*;
use crate::film::{Film, BATCHES};
use crate::image_io::RgbImage;
use rayon::prelude::*;
use std::time::Instant;

// ---------------------------------------------------------------------------------------
// Region forming and filter weights
// ---------------------------------------------------------------------------------------

/// The neighbourhood of one pixel and its normalised weights f*.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Accepted window side m (1: only the primary pixel, no filtering).
    pub m: u32,
    /// (x, y, f*[q - p]) for every pixel q of the accepted window that has independent
    /// samples, the primary pixel first. Non-negative, summing to 1.
    pub weights: Vec<(u32, u32, f64)>,
}

impl Region {
    /// M: number of pixels in the neighbourhood.
    pub fn count(&self) -> u32 {
        self.weights.len() as u32
    }
    /// f*[0], the weight of the primary pixel.
    pub fn primary_weight(&self) -> f64 {
        self.weights[0].2
    }
}

/// Result of [`Dtf::run`].
#[derive(Clone, Debug)]
pub struct DtfOutput {
    pub width: u32,
    pub height: u32,
    /// N[p]: the sample category used for region forming (the allocation).
    pub n: Vec<u32>,
    /// Accepted window side m per pixel (1 = unfiltered).
    pub m: Vec<u32>,
    /// M[p]: pixels in the accepted neighbourhood (m^2 inside the image, fewer at the
    /// border or next to pixels without independent samples).
    pub region: Vec<u32>,
    /// f*[0] per pixel, for diagnostics.
    pub primary_weight: Vec<f32>,
    /// C_i filtered: sum_q f*[q - p] C_i[q]; black where the pixel has no independent
    /// samples.
    pub filtered: RgbImage,
    /// Displayed colour C = (C_d n + C_i,filtered N) / (n + N).
    pub combined: RgbImage,
    /// Wall-clock seconds of the region forming, filtering and combination.
    pub seconds: f64,
}

/// A candidate neighbour: pixel index, offset from p and Delta_q.
#[derive(Clone, Copy, Debug)]
struct Cand {
    idx: usize,
    dx: i32,
    dy: i32,
    /// ||q - p||, computed once (the kernel reads it for every window side m).
    r: f64,
    delta: f64,
}

#[derive(Default)]
struct Scratch {
    cand: Vec<Cand>,
    /// Accepted f*, aligned with the first entries of `cand`.
    w: Vec<f64>,
    tmp: Vec<f64>,
    /// Every candidate's Delta, ascending; kept sorted as the window grows (each new
    /// strip is sorted and merged in), so no window is sorted from scratch.
    sorted: Vec<f64>,
    /// The new strip's Delta, then the merge buffer.
    strip: Vec<f64>,
    merged: Vec<f64>,
}

/// Per-pixel result of [`Dtf::run`]: m, M, f*[0], filtered C_i, displayed C.
type PixelOut = (u32, u32, f32, [f32; 3], [f32; 3]);

/// The tables DTF reads, taken from the two films and the allocation.
/// Half-width of the window over which C_d's brightness is matched to phase 2's.
const SCALE_RADIUS: usize = 8;

/// g_c[p] = sum_q a_q C_i[q]_c / sum_q a_q C_d[q]_c over the pixels q phase 2 sampled in
/// the (2 R + 1)^2 window around p, with a_q = n_q / (n_q + N_q) the weight C_d gets in
/// the display (1 where either sum is zero or not finite). Phase 2's pixels are
/// independent, so its window sums are nearly free of the error that phase 1's shared
/// random numbers leave in every pixel at once; g C_d keeps C_d's detail and takes phase
/// 2's local brightness where the display leans on C_d. Local, not one factor for the
/// image: the shared error differs between the walls and an emitter seen directly (whose
/// C_d is exact). As N grows, g C_d's weight vanishes as C_d's did.
fn shared_error_scale(
    cd: &[[f64; 3]],
    dep: &Film,
    indep: &Film,
    w: usize,
    h: usize,
) -> Vec<[f64; 3]> {
    // summed-area tables of a C_i and a C_d, per channel
    let (sw, sh) = (w + 1, h + 1);
    let mut num = vec![[0.0f64; 3]; sw * sh];
    let mut den = vec![[0.0f64; 3]; sw * sh];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let px = &indep.pixels[i];
            let (mut vn, mut vd) = ([0.0; 3], [0.0; 3]);
            if px.n > 0 {
                let ci = film_value(indep, i);
                let n = dep.pixels[i].n as f64;
                let k = n / (n + px.n as f64);
                for c in 0..3 {
                    vn[c] = k * ci[c];
                    vd[c] = k * cd[i][c];
                }
            }
            let (j, up, left, diag) = (
                (y + 1) * sw + x + 1,
                y * sw + x + 1,
                (y + 1) * sw + x,
                y * sw + x,
            );
            for c in 0..3 {
                num[j][c] = vn[c] + num[up][c] + num[left][c] - num[diag][c];
                den[j][c] = vd[c] + den[up][c] + den[left][c] - den[diag][c];
            }
        }
    }
    let r = SCALE_RADIUS;
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (x0, y0, x1, y1) = (
                x.saturating_sub(r),
                y.saturating_sub(r),
                (x + r + 1).min(w),
                (y + r + 1).min(h),
            );
            let mut g = [1.0; 3];
            for c in 0..3 {
                let box_sum = |t: &[[f64; 3]]| {
                    t[y1 * sw + x1][c] - t[y0 * sw + x1][c] - t[y1 * sw + x0][c]
                        + t[y0 * sw + x0][c]
                };
                let q = box_sum(&num) / box_sum(&den);
                if q.is_finite() && q > 0.0 {
                    g[c] = q;
                }
            }
            g
        })
        .collect()
}

pub struct Dtf {
    params: DtfParams,
    width: usize,
    height: usize,
    /// C_d per pixel.
    cd: Vec<[f64; 3]>,
    /// g per pixel and channel: C_d's display scale (empty with `paper_display`).
    cd_scale: Vec<[f64; 3]>,
    /// sigma per pixel (phase 1).
    sigma: Vec<f64>,
    /// n per pixel (phase 1 count).
    n_dep: Vec<u32>,
    /// N per pixel, the category (for the "N[q] > N[p]" stopping rule).
    alloc: Vec<u32>,
    /// C_i per pixel.
    ci: Vec<[f64; 3]>,
    /// Actual phase-2 count per pixel.
    n_ind: Vec<u32>,
    /// N_eff[p] for the filter's and the display's weights (`super::effective_counts`,
    /// over BDPT with `--dtf-light auto`), else N[p].
    n_eff: Vec<f64>,
    /// sigma for the filter's weights: `sigma`, or with light paths of their own
    /// `super::smoothed_sigma`.
    sigma_f: Vec<f64>,
    /// Variance of C_i per channel (phase 2), for the independent guard.
    ci_var: Vec<[f64; 3]>,
    /// Phase 1's batch images per pixel (`DtfParams::dep_noise`; empty without splats or
    /// with dep_noise 0; NaN where a batch has no sample).
    cd_batches: Vec<[[f64; 3]; BATCHES]>,
}

impl Dtf {
    /// `dep`: phase-1 film (dependent tests); `indep`: phase-2 film (independent tests);
    /// `alloc`: N[p] as returned by [`allocate_relative`] or [`allocate_budget`].
    pub fn new(dep: &Film, indep: &Film, alloc: &[u32], params: &DtfParams) -> Result<Dtf, String> {
        params.validate()?;
        if (dep.width, dep.height) != (indep.width, indep.height) {
            return Err(format!(
                "dtf: the dependent film is {}x{} but the independent film is {}x{}",
                dep.width, dep.height, indep.width, indep.height
            ));
        }
        if alloc.len() != dep.pixels.len() || indep.pixels.len() != dep.pixels.len() {
            return Err(format!(
                "dtf: {} sample counts for a {}x{} film ({} pixels)",
                alloc.len(),
                dep.width,
                dep.height,
                dep.pixels.len()
            ));
        }
        let cd: Vec<[f64; 3]> = (0..dep.pixels.len()).map(|i| film_value(dep, i)).collect();
        let cd_scale = if params.paper_display {
            Vec::new()
        } else {
            shared_error_scale(&cd, dep, indep, dep.width as usize, dep.height as usize)
        };
        // over BDPT with light paths of their own (`super::light`)
        let n_eff =
            super::effective_counts(dep, indep).filter(|_| params.light == super::LightMode::Auto);
        let smooth = n_eff.is_some();
        let mut d = Dtf {
            params: params.clone(),
            width: dep.width as usize,
            height: dep.height as usize,
            cd,
            cd_scale,
            sigma: (0..dep.pixels.len())
                .into_par_iter()
                .map(|i| film_sigma(dep, i))
                .collect(),
            n_dep: dep.pixels.iter().map(|s| s.n).collect(),
            alloc: alloc.to_vec(),
            // A pixel without samples has no C_i (whatever its stored mean says).
            ci: (0..indep.pixels.len())
                .map(|i| {
                    if indep.pixels[i].n > 0 {
                        film_value(indep, i)
                    } else {
                        [0.0; 3]
                    }
                })
                .collect(),
            n_ind: indep.pixels.iter().map(|s| s.n).collect(),
            n_eff: n_eff.unwrap_or_else(|| indep.pixels.iter().map(|s| s.n as f64).collect()),
            sigma_f: Vec::new(),
            ci_var: (0..indep.pixels.len())
                .into_par_iter()
                .map(|i| film_variance_of_value(indep, i))
                .collect(),
            cd_batches: match &dep.splats {
                Some(sp) if params.dep_noise > 0.0 => (0..dep.pixels.len())
                    .map(|i| {
                        std::array::from_fn(|b| {
                            sp.batch_value(i, b, dep.pixels.len())
                                .unwrap_or([f64::NAN; 3])
                        })
                    })
                    .collect(),
                _ => Vec::new(),
            },
        };
        if smooth {
            d.sigma_f = super::smoothed_sigma(&d.sigma, d.width, d.height);
        }
        Ok(d)
    }

    /// Region and weights f* of pixel (x, y) (for inspection and tests; [`Dtf::run`] uses
    /// the same code).
    pub fn weights(&self, x: u32, y: u32) -> Region {
        assert!((x as usize) < self.width && (y as usize) < self.height);
        let mut s = Scratch::default();
        let m = self.region_into(x as usize, y as usize, &mut s);
        Region {
            m,
            weights: s
                .w
                .iter()
                .zip(&s.cand)
                .map(|(&w, c)| ((c.idx % self.width) as u32, (c.idx / self.width) as u32, w))
                .collect(),
        }
    }

    /// The independent guard (`DtfParams::guard`, k): the true colour difference of p and q
    /// is at least sum_c (|C_i[p] - C_i[q]|_c - k SE_c)^+, SE_c from the phase-2 variances.
    /// Phase 1 shares its jitters among all pixels, so a light's thin edge can be missed in
    /// every pixel of a row alike: C_d then calls two rows homogeneous that phase 2 shows
    /// are not (Cornell, the light's lower edge: 0.94 against 0.26, averaged to 0.63). As N
    /// grows the SE vanishes and any real difference is seen, so the filter vanishes too.
    #[inline]
    fn guard_delta(&self, p: usize, q: usize) -> f64 {
        let k = self.params.guard as f64;
        if k <= 0.0 || self.n_ind[p] < 2 || self.n_ind[q] < 2 {
            return 0.0;
        }
        let (a, b, va, vb) = (self.ci[p], self.ci[q], self.ci_var[p], self.ci_var[q]);
        (0..3)
            .map(|c| ((a[c] - b[c]).abs() - k * (va[c] + vb[c]).sqrt()).max(0.0))
            .sum::<f64>()
    }

    /// Delta_q from phase 1: ||C_d[p] - C_d[q]||, or with `dep_noise` k and batch images
    /// (an estimator that splats) per channel sqrt((D^2 - k^2 SE^2)^+), SE^2 the batch-means
    /// variance of the difference D = C_d[p] - C_d[q]: the part of D that the two pixels'
    /// own (unshared) noise explains is taken out, as E[D^2] = true^2 + SE^2.
    #[inline]
    fn dep_delta(&self, p: usize, q: usize) -> f64 {
        let (a, b) = (self.cd[p], self.cd[q]);
        if self.cd_batches.is_empty() {
            return diff_norm(a, b);
        }
        let k2 = (self.params.dep_noise as f64).powi(2);
        let (bp, bq) = (&self.cd_batches[p], &self.cd_batches[q]);
        let nb = BATCHES as f64;
        (0..3)
            .map(|c| {
                let d = a[c] - b[c];
                // the batch differences once (the same values, summed in the same order)
                let diff: [f64; BATCHES] = std::array::from_fn(|j| bp[j][c] - bq[j][c]);
                let mean = diff.iter().sum::<f64>() / nb;
                let ss = diff.iter().map(|x| (x - mean).powi(2)).sum::<f64>();
                let se2 = ss / (nb * (nb - 1.0));
                if se2.is_finite() {
                    (d * d - k2 * se2).max(0.0).sqrt()
                } else {
                    d.abs()
                }
            })
            .sum()
    }

    /// d(q - p) for window side m; `r` = ||q - p|| (the square root of dx^2 + dy^2).
    #[inline]
    fn kernel(&self, dx: i32, dy: i32, r: f64, m: u32) -> f64 {
        let m = m as f64;
        match self.params.kernel {
            Kernel::Pyramid => (m * std::f64::consts::FRAC_1_SQRT_2 - r).max(0.0),
            Kernel::Gaussian => (-4.0 * ((dx * dx + dy * dy) as f64) / (m * m)).exp(),
        }
    }

    /// C_d''s share a of the display C = a C_d' + (1 - a) C_i,f under `CdDisplay::Mse`
    /// for pixel p with region weights (q, f*_q): a = V_i / (V_d + V_i), at most the
    /// paper's n / (n + N), with
    ///   V_i = sum_q f*_q^2 sigma_q^2 / N_q   (phase 2's pixels are independent),
    ///   V_d = (sum_q f*_q sigma_q / sqrt(n_q))^2   (phase 1's errors shared by the region),
    /// sigma from phase 1 (not from phase 2's samples, so a pixel whose samples came out
    /// low is not trusted more for it). Without a usable variance the paper's share.
    pub(super) fn cd_share(&self, p: usize, region: impl Iterator<Item = (usize, f64)>) -> f64 {
        let (n, big_n) = (self.n_dep[p] as f64, self.n_eff[p]);
        let cap = n / (n + big_n);
        let (mut vi, mut sd) = (0.0, 0.0);
        for (q, f) in region {
            let (sg, nq, big_nq) = (self.sigma[q], self.n_dep[q] as f64, self.n_eff[q]);
            vi += f * f * sg * sg / big_nq;
            sd += f * sg / nq.sqrt();
        }
        let a = vi / (sd * sd + vi);
        if a.is_finite() {
            a.min(cap)
        } else {
            cap
        }
    }

    /// Region forming for pixel p = (x, y) (paper §5, third step). On return the first
    /// `s.w.len()` candidates carry the accepted weights f*; returns the accepted m.
    fn region_into(&self, x: usize, y: usize, s: &mut Scratch) -> u32 {
        // `grow` leaves the accepted window's unnormalised f^+ d in `s.w` and 1 / its sum.
        let (m, inv) = self.grow(x, y, s);
        if inv != 1.0 {
            s.w.iter_mut().for_each(|f| *f *= inv);
        }
        m
    }

    /// The window growth of [`Dtf::region_into`]: returns the accepted m and the factor
    /// that normalises the accepted coefficients left in `s.w`.
    fn grow(&self, x: usize, y: usize, s: &mut Scratch) -> (u32, f64) {
        let (w, h) = (self.width as isize, self.height as isize);
        let p = y * self.width + x;
        s.cand.clear();
        s.w.clear();
        s.sorted.clear();
        // f*[0] = 1: the primary pixel alone.
        s.cand.push(Cand {
            idx: p,
            dx: 0,
            dy: 0,
            r: 0.0,
            delta: 0.0,
        });
        s.w.push(1.0);
        s.sorted.push(0.0);
        let mut inv_acc = 1.0;

        // N = 0 (no independent samples): C_i[p] does not exist and the display gives C_d.
        // sigma = 0: no Monte-Carlo error to trade for bias, so filtering can only hurt
        // (and sqrt(N) / (3 sigma) would divide by zero).
        let big_n = self.n_ind[p];
        let sg = self.sigma_f.get(p).copied().unwrap_or(self.sigma[p]);
        if big_n == 0 || !(sg > 0.0 && sg.is_finite()) {
            return (1, inv_acc);
        }
        let np_stop = match self.params.stop_ratio {
            Some(r) => self.alloc[p] as f64 * r as f64,
            None => f64::INFINITY,
        };
        // (N_eff: with light paths of their own C_i's noise is below sigma / sqrt(N))
        let sqrt_n = self.n_eff[p].sqrt();
        let active_set = self.params.clamp == Clamp::ActiveSet;

        // Current (clipped, inclusive) window and sum_r Delta_r, both grown incrementally:
        // with p at offset floor((m-1)/2) the m-window contains the (m-1)-window, so only
        // the new L-shaped strip of pixels is visited.
        let (px, py) = (x as isize, y as isize);
        let (mut x0, mut x1, mut y0, mut y1) = (px, px, py, py);
        let mut sum_delta = 0.0;
        let mut f0_old = 1.0;
        let mut m_acc = 1;

        for m in 2..=self.params.m_max {
            let off = ((m - 1) / 2) as isize;
            let nx0 = (px - off).max(0);
            let nx1 = (px - off + m as isize - 1).min(w - 1);
            let ny0 = (py - off).max(0);
            let ny1 = (py - off + m as isize - 1).min(h - 1);
            s.strip.clear();
            for qy in ny0..=ny1 {
                for qx in nx0..=nx1 {
                    if (x0..=x1).contains(&qx) && (y0..=y1).contains(&qy) {
                        continue;
                    }
                    let q = qy as usize * self.width + qx as usize;
                    // "if N[p] < N[q] then stop for pixel p": keep the (m-1)-window. With
                    // a tolerance of `stop_ratio` (1: the paper's rule; none by default).
                    if self.alloc[q] as f64 > np_stop {
                        return (m_acc, inv_acc);
                    }
                    // A pixel without independent samples has no C_i to average: it is
                    // left out of the neighbourhood (as if outside the image).
                    if self.n_ind[q] == 0 {
                        continue;
                    }
                    // Delta_q = ||C_d[p] - C_d[q]||.
                    let delta = self.dep_delta(p, q).max(self.guard_delta(p, q));
                    sum_delta += delta;
                    let (dx, dy) = ((qx - px) as i32, (qy - py) as i32);
                    s.cand.push(Cand {
                        idx: q,
                        dx,
                        dy,
                        r: ((dx * dx + dy * dy) as f64).sqrt(),
                        delta,
                    });
                    s.strip.push(delta);
                }
            }
            (x0, x1, y0, y1) = (nx0, nx1, ny0, ny1);
            if active_set && !s.strip.is_empty() {
                // Merge the strip's sorted Delta into the window's: the same ascending
                // sequence as sorting the whole window (total_cmp is a total order).
                s.strip.sort_unstable_by(f64::total_cmp);
                s.merged.clear();
                let (a, b) = (&s.sorted, &s.strip);
                let (mut i, mut j) = (0, 0);
                while i < a.len() && j < b.len() {
                    if a[i].total_cmp(&b[j]).is_le() {
                        s.merged.push(a[i]);
                        i += 1;
                    } else {
                        s.merged.push(b[j]);
                        j += 1;
                    }
                }
                s.merged.extend_from_slice(&a[i..]);
                s.merged.extend_from_slice(&b[j..]);
                std::mem::swap(&mut s.sorted, &mut s.merged);
            }

            // Unnormalised coefficients f, clipped to f^+. M is the number of pixels
            // actually in the window, so that sum f = 1 holds at the image border too.
            let big_m = s.cand.len() as f64;
            let k = sqrt_n / (self.params.z as f64 * sg * big_m.sqrt());
            if !k.is_finite() {
                return (m_acc, inv_acc);
            }
            s.tmp.clear();
            match self.params.clamp {
                Clamp::Paper => {
                    // f = 1/M + sqrt(N)/(3 sigma sqrt(M)) (sum_r Delta_r / M - Delta_q).
                    let mean = sum_delta / big_m;
                    s.tmp.extend(
                        s.cand
                            .iter()
                            .map(|c| (1.0 / big_m + k * (mean - c.delta)).max(0.0)),
                    );
                }
                Clamp::ActiveSet => {
                    // f = k (lambda - Delta_q)^+, lambda from the sorted Delta: the largest
                    // active set {j smallest} with lambda_j = (1/k + sum_j Delta)/j > Delta_j.
                    let inv_k = 1.0 / k;
                    let (mut prefix, mut lambda) = (0.0, 0.0);
                    for (j, &d) in s.sorted.iter().enumerate() {
                        prefix += d;
                        let l = (inv_k + prefix) / (j + 1) as f64;
                        if l > d {
                            lambda = l;
                        } else {
                            break;
                        }
                    }
                    s.tmp
                        .extend(s.cand.iter().map(|c| k * (lambda - c.delta).max(0.0)));
                }
            }
            // f^+ d and its sum. (Not incremental: f and d both change with M.)
            let mut sum = 0.0;
            for (f, c) in s.tmp.iter_mut().zip(&s.cand) {
                *f *= self.kernel(c.dx, c.dy, c.r, m);
                sum += *f;
            }
            if !(sum > 0.0 && sum.is_finite()) {
                return (m_acc, inv_acc);
            }
            // f*_new[0] = f^+[0] d(0) / sum_r f^+[r-p] d(r-p): accept the m-window only if
            // the primary weight drops by at least Delta f[0]_min.
            let f0_new = s.tmp[0] / sum;
            if f0_old - f0_new < self.params.df0_min as f64 {
                return (m_acc, inv_acc);
            }
            // Keep the accepted coefficients unnormalised (normalised once, at the end).
            inv_acc = 1.0 / sum;
            std::mem::swap(&mut s.w, &mut s.tmp);
            f0_old = f0_new;
            m_acc = m;
        }
        (m_acc, inv_acc)
    }

    /// Region forming, filtering and display for every pixel (in parallel).
    pub fn run(&self) -> DtfOutput {
        let t0 = Instant::now();
        let per_pixel: Vec<PixelOut> = (0..self.width * self.height)
            .into_par_iter()
            .map_init(Scratch::default, |s, p| {
                let (x, y) = (p % self.width, p / self.width);
                let m = self.region_into(x, y, s);
                // C_i,filtered = sum_q f*[q-p] C_i[q]  (C_i[p] = 0 when N[p] = 0).
                let mut c = [0.0f64; 3];
                for (&wq, cq) in s.w.iter().zip(&s.cand) {
                    for (ch, v) in c.iter_mut().enumerate() {
                        *v += wq * self.ci[cq.idx][ch];
                    }
                }
                // C = (C_d' n + C_i N) / (n + N), C_d' as `DtfParams::cd_display` says
                // (the paper's C_d with `paper_display`).
                let scaled = |q: usize| {
                    let g = self.cd_scale.get(q).copied().unwrap_or([1.0; 3]);
                    let cd = self.cd[q];
                    [cd[0] * g[0], cd[1] * g[1], cd[2] * g[2]]
                };
                let mode = if self.params.paper_display {
                    CdDisplay::Scaled
                } else {
                    self.params.cd_display
                };
                let disp = match mode {
                    CdDisplay::Scaled => combine(scaled(p), self.n_dep[p], c, self.n_ind[p]),
                    CdDisplay::Filtered | CdDisplay::Mse => {
                        let mut cdf = [0.0f64; 3];
                        for (&wq, cq) in s.w.iter().zip(&s.cand) {
                            let v = scaled(cq.idx);
                            for (ch, o) in cdf.iter_mut().enumerate() {
                                *o += wq * v[ch];
                            }
                        }
                        if mode == CdDisplay::Mse && self.n_ind[p] > 0 {
                            let a =
                                self.cd_share(p, s.w.iter().zip(&s.cand).map(|(&f, q)| (q.idx, f)));
                            std::array::from_fn(|ch| a * cdf[ch] + (1.0 - a) * c[ch])
                        } else {
                            combine(cdf, self.n_dep[p], c, self.n_ind[p])
                        }
                    }
                    CdDisplay::None if self.n_ind[p] > 0 => c,
                    CdDisplay::None => combine(scaled(p), self.n_dep[p], c, 0),
                };
                let f32s = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32];
                (m, s.w.len() as u32, s.w[0] as f32, f32s(c), f32s(disp))
            })
            .collect();
        let (w, h) = (self.width as u32, self.height as u32);
        let out = DtfOutput {
            width: w,
            height: h,
            n: self.alloc.clone(),
            m: per_pixel.iter().map(|r| r.0).collect(),
            region: per_pixel.iter().map(|r| r.1).collect(),
            primary_weight: per_pixel.iter().map(|r| r.2).collect(),
            filtered: RgbImage::new(w, h, per_pixel.iter().map(|r| r.3).collect()),
            combined: RgbImage::new(w, h, per_pixel.iter().map(|r| r.4).collect()),
            seconds: 0.0,
        };
        DtfOutput {
            seconds: t0.elapsed().as_secs_f64(),
            ..out
        }
    }
}

/// DTF in one call: [`Dtf::new`] then [`Dtf::run`]; `seconds` includes building the tables.
pub fn dtf_filter(
    dep: &Film,
    indep: &Film,
    alloc: &[u32],
    params: &DtfParams,
) -> Result<DtfOutput, String> {
    let t0 = Instant::now();
    let out = Dtf::new(dep, indep, alloc, params)?.run();
    Ok(DtfOutput {
        seconds: t0.elapsed().as_secs_f64(),
        ..out
    })
}
