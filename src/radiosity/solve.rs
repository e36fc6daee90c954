//! Form factors by ray casting and the progressive-refinement shooting solver.
//!
//! Form factor (Wallace, Elmquist and Haines 1989): from a receiving point x with normal
//! n_x to a source element A_s sampled at points y_k, each standing for dA = A_s / K,
//!
//!   F(x -> A_s) = sum_k V(x, y_k) cos th_x cos th_y dA / (pi r^2 + dA),
//!
//! the cos cos / (pi r^2) kernel with the disc approximation (a disc of area dA seen
//! on axis gives exactly dA / (pi r^2 + dA)), which stays bounded as r -> 0. V is an
//! any-hit shadow ray through the scene's BVH. The midpoint rule underestimates a convex
//! kernel, so pairs closer than a few element sizes use more points: 4^NEAR_LEVEL within
//! sqrt(NEAR_FACTOR A_s) of the source centroid, 4^MID_LEVEL within sqrt(MID_FACTOR A_s),
//! 4^source_level beyond.
//!
//! Solver (Cohen, Chen, Wallace and Greenberg 1988; RenderPark's "progressive
//! refinement"): every (element, side) patch keeps its radiosity B and its unshot
//! radiosity dB on each band. The patch with the most unshot power dB A shoots: every
//! receiver j gets dB_j += rho_j dB_s F(j -> s) (reciprocity: A_s F_sj = A_j F_js), the
//! source's dB is zeroed. It stops when the unshot power is below `tolerance` times the
//! emitted power. Each receiver's form factor is computed on its own (rayon, no
//! reduction), the updates are applied in index order: identical for any thread count.

use super::mesh::Element;
use crate::accel::Bvh;
use crate::math::{offset_origin, Ray, Vec3};
use rayon::prelude::*;

/// Source points of near pairs: 4^NEAR_LEVEL.
pub const NEAR_LEVEL: u32 = 3;
/// A pair is near when the receiver is closer to the source centroid than
/// sqrt(NEAR_FACTOR x A_s).
pub const NEAR_FACTOR: f32 = 16.0;
/// Source points of middle-distance pairs: 4^MID_LEVEL.
pub const MID_LEVEL: u32 = 2;
pub const MID_FACTOR: f32 = 100.0;

/// The source patterns by distance: far, middle, near.
#[derive(Clone, Debug)]
pub struct Patterns {
    pub far: Vec<(f32, f32)>,
    pub mid: Vec<(f32, f32)>,
    pub near: Vec<(f32, f32)>,
}

impl Patterns {
    pub fn new(source_level: u32) -> Patterns {
        Patterns {
            far: source_pattern(source_level),
            mid: source_pattern(MID_LEVEL.max(source_level)),
            near: source_pattern(NEAR_LEVEL.max(source_level)),
        }
    }
}

/// Barycentric centroids (a, b) of the 4^level sub-triangles of the unit triangle
/// (a e1 + b e2), the same regular grid the mesh uses.
pub fn source_pattern(level: u32) -> Vec<(f32, f32)> {
    let n = 1u32 << level;
    let nf = n as f32;
    let mut v = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..(n - j) {
            v.push(((i as f32 + 1.0 / 3.0) / nf, (j as f32 + 1.0 / 3.0) / nf));
        }
    }
    for j in 0..n.saturating_sub(1) {
        for i in 0..(n - 1 - j) {
            v.push(((i as f32 + 2.0 / 3.0) / nf, (j as f32 + 2.0 / 3.0) / nf));
        }
    }
    v
}

/// F(x -> source) split by the receiver's side (0: the side its normal points to, 1: the
/// other), and the number of shadow rays cast. `src_n` is the source's emitting normal.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn point_to_element(
    bvh: &Bvh,
    x: Vec3,
    n_x: Vec3,
    src: &Element,
    src_n: Vec3,
    pat: &Patterns,
) -> ([f32; 2], u32) {
    let d2 = (x - src.c).length_squared();
    let pattern = if d2 < NEAR_FACTOR * src.area {
        &pat.near
    } else if d2 < MID_FACTOR * src.area {
        &pat.mid
    } else {
        &pat.far
    };
    let da = src.area / pattern.len() as f32;
    let mut f = [0.0f32; 2];
    let mut rays = 0;
    for &(a, b) in pattern {
        let y = src.p0 + src.e1 * a + src.e2 * b;
        let d = x - y; // from the source point to the receiver
        let r2 = d.length_squared();
        if r2 <= 0.0 {
            continue;
        }
        let r = r2.sqrt();
        let cos_y = src_n.dot(d) / r;
        let cos_x = n_x.dot(d) / r; // < 0: the source is on the receiver's front side
        if cos_y <= 0.0 || cos_x == 0.0 {
            continue;
        }
        let side = if cos_x < 0.0 { 0 } else { 1 };
        let toward = -d;
        let o = offset_origin(x, n_x, toward);
        rays += 1;
        if bvh.occluded(&Ray::new(o, y - o), 1.0 - 1e-4) {
            continue;
        }
        f[side] += cos_y * cos_x.abs() * da / (std::f32::consts::PI * r2 + da);
    }
    (f, rays)
}

/// The state of a solve: patches are (element, side) pairs, index 2 e + side.
pub struct Shooter<'a> {
    pub bvh: &'a Bvh,
    pub elems: &'a [Element],
    pub bands: usize,
    /// rho per element and band (the diffuse reflectance, both sides).
    pub rho: Vec<f64>,
    /// B and dB per patch and band.
    pub b: Vec<f64>,
    pub db: Vec<f64>,
    pub patterns: Patterns,
    pub emitted_power: f64,
    pub shots: u64,
    pub rays: u64,
}

impl Shooter<'_> {
    /// Unshot power of patch p (band average of dB x A).
    #[inline]
    fn unshot(&self, p: usize) -> f64 {
        let nb = self.bands;
        let s: f64 = self.db[p * nb..(p + 1) * nb].iter().sum();
        s / nb as f64 * self.elems[p / 2].area as f64
    }

    /// The patch with the most unshot power (lowest index on ties) and the total.
    pub fn most_unshot(&self) -> (usize, f64) {
        let mut best = (0usize, -1.0f64);
        let mut total = 0.0;
        for p in 0..self.elems.len() * 2 {
            let u = self.unshot(p);
            total += u;
            if u > best.1 {
                best = (p, u);
            }
        }
        (best.0, total)
    }

    /// Shoot patch `p`'s unshot radiosity to every element.
    pub fn shoot(&mut self, p: usize) {
        let nb = self.bands;
        let si = p / 2;
        let src = self.elems[si];
        let src_n = if p % 2 == 0 { src.n } else { -src.n };
        let bvh = self.bvh;
        let pat = &self.patterns;
        let rho = &self.rho;
        let ff: Vec<([f32; 2], u32)> = self
            .elems
            .par_iter()
            .enumerate()
            .with_min_len(64)
            .map(|(j, e)| {
                if j == si || rho[j * nb..(j + 1) * nb].iter().all(|&r| r <= 0.0) {
                    return ([0.0; 2], 0);
                }
                point_to_element(bvh, e.c, e.n, &src, src_n, pat)
            })
            .collect();
        let shot: Vec<f64> = self.db[p * nb..(p + 1) * nb].to_vec();
        for b in &mut self.db[p * nb..(p + 1) * nb] {
            *b = 0.0;
        }
        for (j, (f, rays)) in ff.iter().enumerate() {
            self.rays += *rays as u64;
            for (side, &fs) in f.iter().enumerate() {
                if fs <= 0.0 {
                    continue;
                }
                let q = (2 * j + side) * nb;
                for k in 0..nb {
                    let d = rho[j * nb + k] * shot[k] * fs as f64;
                    self.b[q + k] += d;
                    self.db[q + k] += d;
                }
            }
        }
        self.shots += 1;
    }
}
