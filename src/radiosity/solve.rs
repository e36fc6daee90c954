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
//! kernel, so middle-distance pairs (within sqrt(MID_FACTOR A_s) of the source centroid)
//! use 4^MID_LEVEL points instead of 4^source_level. Near pairs (within
//! sqrt(NEAR_FACTOR A_s)) use the exact unoccluded point-to-polygon factor (Lambert's
//! formula, F = 1/(2 pi) sum_i beta_i n . g_i over the polygon's edges, the source
//! clipped to the receiver's half-space; Baum, Rushmeier and Winget 1989) times the
//! visible share of 4^NEAR_LEVEL shadow rays: a sum of discs would exceed 1 where a
//! receiver almost touches a source (cornell's light hangs 0.01 below the ceiling) and
//! the iteration would diverge.
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
/// How far a source's row sum of form factors may exceed 1 before it is normalised.
pub const ROW_SLACK: f64 = 0.02;
/// Source points of middle-distance pairs: 4^MID_LEVEL. Measured (`kalos radiosity
/// cornell --threads 1 --radiosity-source-level 0`, AMD EPYC with AVX2/FMA): level 2
/// cast 26.1M rays in 5.8 s,
/// level 1 13.1M in 4.1 s with the preview within 0.00025 rms of level 2's and the
/// gather's 1024-spp error unchanged (RMSE 0.00185 / 0.00192 against 0.00188 / 0.00195,
/// seeds 0 and 1); level 0 (9.2M, 3.0 s) moved the preview's mean by 0.07%.
pub const MID_LEVEL: u32 = 1;
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

/// F(receiver -> source) split by the receiver's side (0: the side its normal points to,
/// 1: the other), and the number of shadow rays cast. `src_n` is the source's emitting
/// normal. Far pairs are evaluated at the receiver's centroid; near pairs (closer than a
/// few sizes of the larger element) are averaged over 4^MID_LEVEL receiver points, each
/// with Lambert's exact factor: a centroid stands badly for a receiver much larger than
/// its distance to the source (cornell's boxes go 0.01 through the floor), and the
/// reciprocity A_j F_ji = A_i F_ij then overshoots so far that the iteration diverges.
#[inline]
pub fn element_to_element(
    bvh: &Bvh,
    rcv: &Element,
    src: &Element,
    src_n: Vec3,
    pat: &Patterns,
) -> ([f32; 2], u32) {
    let d2 = (rcv.c - src.c).length_squared();
    if d2 < NEAR_FACTOR * src.area.max(rcv.area) {
        let mut f = [0.0f32; 2];
        let mut rays = 0;
        for &(a, b) in &pat.mid {
            let x = rcv.p0 + rcv.e1 * a + rcv.e2 * b;
            let (g, r) = near_factor(bvh, x, rcv.n, src, src_n, &pat.far);
            f[0] += g[0];
            f[1] += g[1];
            rays += r;
        }
        let k = pat.mid.len() as f32;
        return ([f[0] / k, f[1] / k], rays);
    }
    point_to_element(bvh, rcv.c, rcv.n, src, src_n, pat)
}

/// F(x -> source) at one receiving point (far and middle pairs).
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
    if d2 < NEAR_FACTOR * src.area {
        return near_factor(bvh, x, n_x, src, src_n, &pat.near);
    }
    let pattern = if d2 < MID_FACTOR * src.area {
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

/// A planar ideal mirror of the scene (a `Bsdf::Mirror` triangle, both sides reflect):
/// the emitters' first shots also reach receivers through it.
#[derive(Clone, Debug)]
pub struct MirrorTri {
    pub p0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    /// Unit normal of its plane.
    pub n: Vec3,
    /// Its reflectance per band.
    pub ks: Vec<f64>,
}

impl MirrorTri {
    /// Whether point `h` of the mirror's plane lies in the triangle: edge functions in f64,
    /// a point on an edge belongs to the triangle whose edge runs in the positive
    /// direction (first non-zero coordinate), so each point of an edge two consistently
    /// wound mirror triangles share counts once (the regular grids of receivers and
    /// source points put many of them exactly on a quad's diagonal).
    fn contains(&self, h: Vec3) -> bool {
        let d = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let a = self.p0;
        let (b, c) = (a + self.e1, a + self.e2);
        let n = d(self.n);
        let hp = d(h);
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let (p, q) = (d(p), d(q));
            let e = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let r = [hp[0] - p[0], hp[1] - p[1], hp[2] - p[2]];
            let w = (e[1] * r[2] - e[2] * r[1]) * n[0]
                + (e[2] * r[0] - e[0] * r[2]) * n[1]
                + (e[0] * r[1] - e[1] * r[0]) * n[2];
            let owner = e.iter().find(|&&x| x != 0.0).is_some_and(|&x| x > 0.0);
            if w < 0.0 || (w == 0.0 && !owner) {
                return false;
            }
        }
        true
    }
}

/// F(x -> A_s through mirror m), split by the receiver's side, and the shadow rays cast:
/// the source's mirror image y' = y - 2 ((y - p0).n) n, each source point seen from x
/// through the mirror triangle (the point h where x -> y' crosses its plane lies in it),
/// with the image's normal, the same disc kernel as `point_to_element`, and visibility on
/// both legs, x -> h and h -> y (Wallace, Cohen and Greenberg's mirror form factors for a
/// planar specular reflector, first order). The reflectance is applied by the caller.
pub fn mirror_factor(
    bvh: &Bvh,
    x: Vec3,
    n_x: Vec3,
    src: &Element,
    src_n: Vec3,
    m: &MirrorTri,
    pattern: &[(f32, f32)],
) -> ([f32; 2], u32) {
    let mut f = [0.0f32; 2];
    let mut rays = 0;
    let dx = (x - m.p0).dot(m.n);
    if dx == 0.0 {
        return (f, 0);
    }
    let img_n = src_n - m.n * (2.0 * src_n.dot(m.n));
    let da = src.area / pattern.len() as f32;
    for &(a, b) in pattern {
        let y = src.p0 + src.e1 * a + src.e2 * b;
        let dy = (y - m.p0).dot(m.n);
        // the source and the receiver on the same, reflecting side of the plane
        if dy * dx <= 0.0 {
            continue;
        }
        let y_img = y - m.n * (2.0 * dy);
        let d = x - y_img; // from the image to the receiver
        let r2 = d.length_squared();
        if r2 <= 0.0 {
            continue;
        }
        let r = r2.sqrt();
        let cos_y = img_n.dot(d) / r;
        let cos_x = n_x.dot(d) / r;
        if cos_y <= 0.0 || cos_x == 0.0 {
            continue;
        }
        // where x -> y' crosses the mirror's plane, inside the triangle?
        let h = x + (y_img - x) * (dx / (dx + dy));
        if !m.contains(h) {
            continue;
        }
        let side = if cos_x < 0.0 { 0 } else { 1 };
        let o = offset_origin(x, n_x, h - x);
        rays += 2;
        if bvh.occluded(&Ray::new(o, h - o), 1.0 - 1e-3) {
            continue;
        }
        let nh = if dx > 0.0 { m.n } else { -m.n };
        let oh = offset_origin(h, nh, y - h);
        if bvh.occluded(&Ray::new(oh, y - oh), 1.0 - 1e-4) {
            continue;
        }
        f[side] += cos_y * cos_x.abs() * da / (std::f32::consts::PI * r2 + da);
    }
    (f, rays)
}

/// Near pairs: Lambert's exact factor per receiver side, times the visible share.
fn near_factor(
    bvh: &Bvh,
    x: Vec3,
    n_x: Vec3,
    src: &Element,
    src_n: Vec3,
    pattern: &[(f32, f32)],
) -> ([f32; 2], u32) {
    // the receiver must be in front of the (planar) source, not in its plane
    if src_n.dot(x - src.c) <= 1e-6 * (1.0 + x.abs().max_element()) {
        return ([0.0; 2], 0);
    }
    let poly = [src.p0 - x, src.p0 + src.e1 - x, src.p0 + src.e2 - x];
    let mut f = [0.0f32; 2];
    let mut rays = 0;
    for (side, n) in [n_x, -n_x].into_iter().enumerate() {
        let clipped = clip(&poly, n);
        if clipped.len() < 3 {
            continue;
        }
        let exact = polygon_factor(n, &clipped);
        if exact <= 0.0 {
            continue;
        }
        let (mut seen, mut all) = (0u32, 0u32);
        for &(a, b) in pattern {
            let y = src.p0 + src.e1 * a + src.e2 * b;
            if n.dot(y - x) <= 0.0 {
                continue;
            }
            all += 1;
            let o = offset_origin(x, n, y - x);
            if !bvh.occluded(&Ray::new(o, y - o), 1.0 - 1e-4) {
                seen += 1;
            }
        }
        rays += all;
        if all == 0 {
            // the polygon grazes the receiver's plane: one ray to its clipped centroid
            let c = clipped.iter().fold(Vec3::ZERO, |s, &v| s + v) / clipped.len() as f32 + x;
            let o = offset_origin(x, n, c - x);
            rays += 1;
            if !bvh.occluded(&Ray::new(o, c - o), 1.0 - 1e-4) {
                f[side] = exact.min(1.0);
            }
            continue;
        }
        f[side] = exact.min(1.0) * seen as f32 / all as f32;
    }
    (f, rays)
}

/// The part of a convex polygon (relative to the receiver) in the half-space n . v >= 0.
fn clip(poly: &[Vec3], n: Vec3) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            out.push(a + (b - a) * t);
        }
    }
    out
}

/// Lambert's point-to-polygon form factor: 1/(2 pi) |sum_i angle(v_i, v_i+1) n . g_i|,
/// g_i the unit normal of the plane through the receiver and edge i.
pub fn polygon_factor(n: Vec3, poly: &[Vec3]) -> f32 {
    let mut s = 0.0f64;
    for i in 0..poly.len() {
        let a = poly[i].as_dvec3().normalize_or_zero();
        let b = poly[(i + 1) % poly.len()].as_dvec3().normalize_or_zero();
        let c = a.cross(b);
        let cl = c.length();
        if cl > 1e-15 {
            let ang = cl.atan2(a.dot(b));
            s += n.as_dvec3().dot(c / cl) * ang;
        }
    }
    (s.abs() / (2.0 * std::f64::consts::PI)) as f32
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
    /// The part of dB that is emission not yet shot (E until the patch first shoots), and
    /// per patch and band the radiosity received from those shots: the direct light.
    pub de: Vec<f64>,
    pub direct: Vec<f64>,
    /// The scene's planar mirrors: emission shots also go through them.
    pub mirrors: Vec<MirrorTri>,
    pub patterns: Patterns,
    pub emitted_power: f64,
    pub shots: u64,
    pub rays: u64,
    /// Form-factor rows of the patches shot so far (F_ij of patch i = p / 2 to every
    /// element j, both receiving sides, and the row's normalisation): a patch shot again
    /// (it keeps receiving while others shoot) reuses its row instead of casting its rays
    /// again. Rows are kept while they fit in ROW_CACHE_BYTES.
    /// Rows are sparse: (element j, [F to its two sides]) where either is positive.
    pub rows: Vec<Option<(SparseRow, f64)>>,
    pub row_bytes: usize,
    /// Unshot power per patch (`unshot`), kept up to date by `shoot` so that choosing the
    /// next shooter is one scan of a flat array (empty until the first `most_unshot` or
    /// `shoot` fills it).
    pub unshot_power: Vec<f64>,
}

/// Unshot power of a patch from its dB per band and its area.
#[inline]
fn unshot_of(db: &[f64], area: f32) -> f64 {
    let s: f64 = db.iter().sum();
    s / db.len() as f64 * area as f64
}

/// Receivers per parallel task of a shot's update (in parallel when the mesh has more
/// elements than one task holds and the pool more than one thread).
pub const UPDATE_CHUNK: usize = 512;

/// What one shot passes on: rho_j dB_s F_sj to each receiver patch of its row.
struct Shot<'a> {
    rho: &'a [f64],
    elems: &'a [Element],
    /// The shooter's dB and its emission part, per band (normalised).
    shot: &'a [f64],
    shot_e: &'a [f64],
    emits: bool,
    nb: usize,
}

impl Shot<'_> {
    /// Apply the row entries `row` (elements from `j0` on) to the per-patch slices that
    /// start at element `j0`.
    fn apply(
        &self,
        row: &[(u32, [f32; 2])],
        j0: usize,
        b: &mut [f64],
        db: &mut [f64],
        direct: &mut [f64],
        unshot: &mut [f64],
    ) {
        let nb = self.nb;
        for &(j, ref f) in row {
            let j = j as usize;
            let rho = &self.rho[j * nb..(j + 1) * nb];
            for (side, &fs) in f.iter().enumerate() {
                if fs <= 0.0 {
                    continue;
                }
                let pl = 2 * (j - j0) + side;
                let q = pl * nb;
                for k in 0..nb {
                    let d = rho[k] * self.shot[k] * fs as f64;
                    b[q + k] += d;
                    db[q + k] += d;
                }
                if self.emits {
                    for k in 0..nb {
                        direct[q + k] += rho[k] * self.shot_e[k] * fs as f64;
                    }
                }
                unshot[pl] = unshot_of(&db[q..q + nb], self.elems[j].area);
            }
        }
    }
}

/// A form-factor row: (element j, [F to its two sides]) where either is positive.
pub type SparseRow = Vec<(u32, [f32; 2])>;

/// Memory the cached form-factor rows may take.
pub const ROW_CACHE_BYTES: usize = 1 << 30;

impl Shooter<'_> {
    /// Unshot power of patch p (band average of dB x A).
    #[inline]
    fn unshot(&self, p: usize) -> f64 {
        let nb = self.bands;
        unshot_of(&self.db[p * nb..(p + 1) * nb], self.elems[p / 2].area)
    }

    /// Fill `unshot_power` if it is not yet.
    fn track_unshot(&mut self) {
        let np = self.elems.len() * 2;
        if self.unshot_power.len() != np {
            self.unshot_power = (0..np).map(|p| self.unshot(p)).collect();
        }
    }

    /// The patch with the most unshot power (lowest index on ties) and the total.
    pub fn most_unshot(&mut self) -> (usize, f64) {
        self.track_unshot();
        let mut best = (0usize, -1.0f64);
        let mut total = 0.0;
        for (p, &u) in self.unshot_power.iter().enumerate() {
            total += u;
            if u > best.1 {
                best = (p, u);
            }
        }
        (best.0, total)
    }

    /// Shoot patch `p`'s unshot radiosity to every element.
    pub fn shoot(&mut self, p: usize) {
        self.track_unshot();
        let nb = self.bands;
        let si = p / 2;
        let src = self.elems[si];
        let src_n = if p.is_multiple_of(2) { src.n } else { -src.n };
        let bvh = self.bvh;
        let pat = &self.patterns;
        let rho = &self.rho;
        let cached = self.rows.get_mut(p).and_then(|r| r.take());
        let was_cached = cached.is_some();
        let (ff, norm) = match cached {
            Some(row) => row,
            None => {
                let ff: Vec<([f32; 2], u32)> = self
                    .elems
                    .par_iter()
                    .enumerate()
                    .with_min_len(64)
                    .map(|(j, e)| {
                        if j == si || rho[j * nb..(j + 1) * nb].iter().all(|&r| r <= 0.0) {
                            return ([0.0; 2], 0);
                        }
                        element_to_element(bvh, e, &src, src_n, pat)
                    })
                    .collect();
                self.rays += ff.iter().map(|&(_, r)| r as u64).sum::<u64>();
                // Normalisation: the receivers' share of the source's power, sum_j A_j
                // F_ji / A_i = sum_j F_ij by reciprocity, cannot exceed 1. Where point
                // estimates overshoot (receivers nearly touching the source) by more than
                // ROW_SLACK the row is scaled back to 1, so every shot passes on at most
                // rho (1 + ROW_SLACK) times its power and the iteration converges; below
                // it the estimates are left as they are (the quadrature's own error, some
                // 1% in the corners of a room).
                let row: f64 = ff
                    .iter()
                    .zip(self.elems)
                    .map(|((f, _), e)| (f[0] + f[1]) as f64 * e.area as f64)
                    .sum::<f64>()
                    / src.area as f64;
                let norm = if row > 1.0 + ROW_SLACK {
                    1.0 / row
                } else {
                    1.0
                };
                let sparse: SparseRow = ff
                    .into_iter()
                    .enumerate()
                    .filter(|(_, (f, _))| f[0] > 0.0 || f[1] > 0.0)
                    .map(|(j, (f, _))| (j as u32, f))
                    .collect();
                (sparse, norm)
            }
        };
        let shot: Vec<f64> = self.db[p * nb..(p + 1) * nb]
            .iter()
            .map(|&v| v * norm)
            .collect();
        let shot_e: Vec<f64> = self.de[p * nb..(p + 1) * nb]
            .iter()
            .map(|&v| v * norm)
            .collect();
        for b in &mut self.db[p * nb..(p + 1) * nb] {
            *b = 0.0;
        }
        for e in &mut self.de[p * nb..(p + 1) * nb] {
            *e = 0.0;
        }
        self.unshot_power[p] = self.unshot(p);
        // The receivers' updates, each independent of the others: in parallel over ranges
        // of UPDATE_CHUNK elements (the same bits as one loop).
        let shot = Shot {
            rho,
            elems: self.elems,
            shot: &shot,
            shot_e: &shot_e,
            // only the emitters' first shots carry direct light
            emits: shot_e.iter().any(|&e| e != 0.0),
            nb,
        };
        let ch = UPDATE_CHUNK;
        if rayon::current_num_threads() > 1 && self.elems.len() > ch {
            self.b
                .par_chunks_mut(2 * nb * ch)
                .zip(self.db.par_chunks_mut(2 * nb * ch))
                .zip(self.direct.par_chunks_mut(2 * nb * ch))
                .zip(self.unshot_power.par_chunks_mut(2 * ch))
                .enumerate()
                .for_each(|(c, (((b, db), direct), unshot))| {
                    let j0 = c * ch;
                    let lo = ff.partition_point(|e| (e.0 as usize) < j0);
                    let hi = ff.partition_point(|e| (e.0 as usize) < j0 + ch);
                    shot.apply(&ff[lo..hi], j0, b, db, direct, unshot);
                });
        } else {
            shot.apply(
                &ff,
                0,
                &mut self.b,
                &mut self.db,
                &mut self.direct,
                &mut self.unshot_power,
            );
        }
        // Emission also reaches receivers through the mirrors (light -> mirror ->
        // receiver, first order): the caustics the mirrors throw, which the diffuse
        // transport above cannot carry. It is not direct light for next-event estimation
        // (`direct`): a path gets it through its BSDF-sampled continuation.
        if !self.mirrors.is_empty() && shot_e.iter().any(|&e| e > 0.0) {
            let mirrors = &self.mirrors;
            let via: Vec<(Vec<f64>, u64)> = self
                .elems
                .par_iter()
                .enumerate()
                .with_min_len(64)
                .map(|(j, e)| {
                    let mut g = vec![0.0f64; 2 * nb];
                    if j == si || rho[j * nb..(j + 1) * nb].iter().all(|&r| r <= 0.0) {
                        return (g, 0);
                    }
                    let mut rays = 0u64;
                    for m in mirrors {
                        let (fm, r) = mirror_factor(bvh, e.c, e.n, &src, src_n, m, &pat.far);
                        rays += r as u64;
                        for (side, &fs) in fm.iter().enumerate() {
                            for k in 0..nb {
                                g[side * nb + k] += fs as f64 * m.ks[k];
                            }
                        }
                    }
                    (g, rays)
                })
                .collect();
            for (j, (g, rays)) in via.iter().enumerate() {
                self.rays += rays;
                for side in 0..2 {
                    let q = (2 * j + side) * nb;
                    for k in 0..nb {
                        let d = rho[j * nb + k] * shot_e[k] * g[side * nb + k];
                        self.b[q + k] += d;
                        self.db[q + k] += d;
                    }
                    self.unshot_power[2 * j + side] = self.unshot(2 * j + side);
                }
            }
        }
        self.shots += 1;
        let bytes = ff.len() * std::mem::size_of::<(u32, [f32; 2])>();
        if was_cached {
            self.rows[p] = Some((ff, norm));
        } else if p < self.rows.len() && self.row_bytes + bytes <= ROW_CACHE_BYTES {
            self.row_bytes += bytes;
            self.rows[p] = Some((ff, norm));
        }
    }
}
