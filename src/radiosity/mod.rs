//! The radiosity preprocess of Rushmeier and Ward's Monte Carlo path tracer ("Energy
//! preserving non-linear filters", SIGGRAPH 1994, section 4.1: "values from a radiosity
//! preprocess are used" for the incident radiance of diffuse-like surfaces; the
//! progressive multi-pass method of Chen et al. 1991).
//!
//! - `mesh`: the diffuse-like and emissive triangles split 4-way to a maximum element
//!   area, vertices welded.
//! - `solve`: form factors by ray casting with visibility, progressive refinement by
//!   shooting, on every spectral band of the render.
//! - `Solution`: per-vertex radiosity B on both sides of every element (nodal averages of
//!   the element values, area-weighted), interpolated with barycentrics; for a hit point
//!   on a scene triangle the reflected radiance (B - E) / pi, or B / pi.
//! - `ply`: the meshed solution as a vertex-coloured PLY (MeshLab, Blender).
//!
//! Only materials with a diffuse lobe take part, with the diffuse reflectance (Kd, a texture
//! by its mean) plus, for a diffuse + Phong material, the Phong lobe's hemispherical albedo
//! carried as if diffuse (`diffuse_kd`); other glossy materials,
//! mirrors and glass are not meshed and only block diffuse transfer (the path tracer
//! follows them), except that an emitter's shot also reaches receivers through the
//! scene's planar ideal mirrors (`Bsdf::Mirror` triangles; first order, mirror-image
//! form factors in `solve`): the caustics the mirrors throw then light the surfaces the
//! gather looks up (on `rw-room`, without them, every gather image was 0.5% too dark and
//! the ceiling's top rows by 2.4-3.6%, median signed relative error). Emitters keep their
//! exact emission E = pi L_e (the cosine-weighted average for directional emission) on
//! their front side; an emitter whose radiance is a texture (Mitsuba's textured area
//! light) emits its texture's mean over the whole element here, while the estimators
//! that gather from the solution read the texture at each point they see or sample.

pub mod mesh;
pub mod ply;
pub mod solve;
#[cfg(test)]
mod tests;

use crate::material::{AlbedoTable, Bsdf};
use crate::math::Vec3;
use crate::progress::Progress;
use crate::scene::Scene;
use crate::spectrum::Spectrum;
use mesh::Mesh;
use std::sync::Arc;
use std::time::Instant;

/// A point found in the mesh: its triangle's meshing, its element's cell index there and
/// the element's three grid corners with their interpolation weights.
type Located<'a> = (&'a mesh::TriMesh, u32, [(u32, u32, f32); 3]);

/// Largest mesh kalos agrees to allocate (element and vertex arrays together).
pub const MAX_MESH_BYTES: u64 = 4 << 30;

/// Settings of the preprocess: each option's name, help and default written once here.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct RadiositySettings {
    /// Radiosity: largest element area in scene units^2 (default: the meshed area / 1500, a
    /// few thousand elements on cornell; / 100 when only --rr-estimate radiosity reads the
    /// solution).
    #[arg(long = "radiosity-max-area")]
    pub max_area: Option<f32>,
    /// Radiosity: stop when the unshot power is below this fraction of the emitted.
    #[arg(long = "radiosity-tolerance", default_value_t = 1e-3)]
    pub tolerance: f64,
    /// Radiosity: 4^level points on a source element (1: four points).
    #[arg(long = "radiosity-source-level", default_value_t = 1)]
    pub source_level: u32,
    /// Radiosity: at most this many elements (the solver's time grows as elements^2).
    #[arg(long = "radiosity-max-elements", default_value_t = 1 << 21)]
    pub max_elements: u64,
    /// Radiosity: at most this many shots (default: 200 per patch).
    #[arg(long = "radiosity-max-shots")]
    pub max_shots: Option<u64>,
    /// The meshed area over the default largest element area: `DEFAULT_ELEMENTS`, or
    /// `ROULETTE_ELEMENTS` for a solution that only the estimate roulette reads (not an
    /// option: the estimator sets it).
    #[arg(skip = DEFAULT_ELEMENTS)]
    #[serde(skip, default = "default_elements")]
    pub default_elements: f64,
    /// The seconds of a `--time` budget (not an option: the job sets it): the default mesh
    /// is then made as fine as `PREPROCESS_SHARE` of them allows (`Solution::compute`).
    #[arg(skip)]
    #[serde(skip)]
    pub time_budget: Option<f64>,
    /// Whether only the estimate roulette reads the solution (not an option: the
    /// estimator sets it): the solve then stops after `ROULETTE_RAYS` shadow rays unless
    /// `--radiosity-max-shots` is given, and the power left unshot is spread as an
    /// ambient term over the L~ of every element (`Solution::element_indirect`).
    #[arg(skip)]
    #[serde(skip)]
    pub roulette_only: bool,
}

fn default_elements() -> f64 {
    DEFAULT_ELEMENTS
}

/// The default max area is the meshed area divided by this.
pub const DEFAULT_ELEMENTS: f64 = 1500.0;

/// ... and by this when the solution serves only the estimate roulette's L~, a smooth
/// average of the indirect light that needs no fine mesh: on the Cornell box (256x256, 64
/// spp, 2026-12-06, Xeon with AVX-512, two threads, `--stats` prepare_seconds on an idle
/// machine) 210 elements solve in 0.05 s against 3,360 in 2.2 s, with the same error (RMSE
/// 0.0391 against 0.0391 on seed 0).
pub const ROULETTE_ELEMENTS: f64 = 100.0;

/// Shadow rays after which a solution that only the roulette reads stops (once every
/// emitting patch has shot), the power left unshot then spread as Cohen et al.'s ambient
/// term: the roulette is unbiased for any L~, and a rough local one is what pays. A shot
/// casts rays to every element the first time a patch shoots (its row is then cached):
/// on rw-room (2,354 elements, one per triangle) the tolerance's 11,952 shots cast 18.9M
/// rays in 1.2-2.3 s against 0.29 s of rendering (128x128, 64 spp); the Cornell box's
/// 210 elements converge within 0.34M rays.
pub const ROULETTE_RAYS: u64 = 500_000;

/// The share of a `--time` budget the preprocess may take with the default mesh. The solver's
/// time grows about as the square of the elements (shots to reach the tolerance times rays
/// per shot; on the Cornell box, 2026-12-06, Xeon, a loaded machine: 258 elements 0.06 s, 840
/// 0.45 s, 1,032 0.67 s, 3,360 5.3 s). At 5 s the default mesh's 2.2-5 s solve left
/// `--method rw` 2 to 75 trials per pixel; with a tenth of the budget (840 elements) its RMSE
/// was 0.60x plain path tracing's (0.00255 against 0.00425, 128x128, seed 1).
pub const PREPROCESS_SHARE: f64 = 0.1;

impl Default for RadiositySettings {
    fn default() -> Self {
        crate::options::defaults::<RadiositySettings>()
    }
}

impl RadiositySettings {
    pub fn validate(&self) -> Result<(), String> {
        if let Some(a) = self.max_area {
            if !(a.is_finite() && a > 0.0) {
                return Err(format!("--radiosity-max-area {a}: must be a positive area"));
            }
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(format!(
                "--radiosity-tolerance {}: must be between 0 and 1 (a fraction of the emitted power)",
                self.tolerance
            ));
        }
        if self.source_level > 4 {
            return Err(format!(
                "radiosity source_level {}: at most 4 (256 points per element)",
                self.source_level
            ));
        }
        Ok(())
    }
}

/// What the preprocess did (`--stats`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RadiosityStats {
    pub elements: u64,
    pub vertices: u64,
    pub bands: usize,
    pub max_area: f64,
    pub tolerance: f64,
    pub shots: u64,
    pub rays: u64,
    pub mesh_seconds: f64,
    pub solve_seconds: f64,
    pub seconds: f64,
    /// Emitted power (band average of E x A).
    pub emitted_power: f64,
    /// Unshot power left, as a fraction of the emitted.
    pub residual_unshot: f64,
    /// False if `max_shots` stopped the solver before the tolerance.
    pub converged: bool,
}

/// The immutable radiosity solution the estimators read.
#[derive(Clone, Debug)]
pub struct Solution {
    pub bands: usize,
    pub mesh: Mesh,
    /// B per vertex, side and band: index ((2 v + side) * bands + band).
    pub vertex_b: Vec<f32>,
    /// B per element, side and band (the solver's values).
    pub element_b: Vec<f32>,
    /// Unshot radiosity dB per element, side and band when the solver stopped.
    pub element_unshot: Vec<f32>,
    /// Mean indirect radiance arriving per element, side and band, (B - E - B_direct) /
    /// (pi rho) (0 where rho is 0): the roulette's L~ for `--rr-estimate radiosity`.
    pub element_indirect: Vec<f32>,
    /// Its area-weighted mean over the elements' front sides, per band.
    pub mean_indirect: Vec<f32>,
    /// Emitted radiosity E = pi L_e (front side) per scene triangle and band (empty for
    /// triangles that are not meshed).
    pub tri_e: Vec<Vec<f32>>,
    pub stats: RadiosityStats,
    /// The coarse solution `compute` solved first (`ROULETTE_ELEMENTS`) when it then
    /// refined the mesh: the gather's depth is chosen from how the two differ
    /// (`pipeline::rw_depth`).
    pub coarser: Option<Arc<Solution>>,
}

/// Uplift a linear RGB triple to `bands` bands as the path tracer does.
fn uplift(rgb: [f32; 3], bands: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f32> = match bands {
        3 => Spectrum::<3>::from_rgb(rgb).0.to_vec(),
        8 => Spectrum::<8>::from_rgb(rgb).0.to_vec(),
        16 => Spectrum::<16>::from_rgb(rgb).0.to_vec(),
        _ => {
            return Err(format!(
                "radiosity: {bands} spectral bands (expected 3, 8 or 16)"
            ))
        }
    };
    Ok(v.into_iter().map(|x| x as f64).collect())
}

/// The reflectance rho the solution gives a material with a diffuse lobe (Kd, a texture by
/// its mean), None if it has none. A diffuse + Phong material also reflects its glossy
/// lobe's hemispherical albedo, carried as if diffuse: the power it reflects is then right
/// (a closed room of such walls emitting 1 - a(w) solves to radiance 1, as the path tracer
/// renders it), only its direction is averaged. Left out, as before 2026-12-06, it darkened
/// every lookup lit through a glossy floor (the Blender living room's lookup 4.7% dark).
fn diffuse_kd(scene: &Scene, m: u32) -> Option<[f32; 3]> {
    let mat = &scene.materials[m as usize];
    let (kd, glossy) = match mat.bsdf {
        Bsdf::Diffuse(l) => (l.kd, [0.0; 3]),
        Bsdf::DiffuseGlossy(l, p) => {
            let lobe = Bsdf::DiffuseGlossy(crate::material::Lambert { kd: [0.0; 3] }, p);
            (l.kd, AlbedoTable::new(&lobe).hemispherical(false))
        }
        _ => return None,
    };
    let kd = match mat.kd_texture {
        Some(t) => scene.textures[t as usize].mean(),
        None => kd,
    };
    (kd.iter().any(|&v| v > 0.0)).then(|| std::array::from_fn(|c| kd[c] + glossy[c]))
}

/// The scene's planar ideal mirrors (`Bsdf::Mirror` triangles) with their reflectance per
/// band: the solver's emission shots also reach receivers through them.
fn mirrors_of(scene: &Scene, bands: usize) -> Result<Vec<solve::MirrorTri>, String> {
    let mut out = Vec::new();
    for (t, tri) in scene.tris.iter().enumerate() {
        let mat = &scene.materials[scene.tri_material[t] as usize];
        let Bsdf::Mirror(m) = mat.bsdf else {
            continue;
        };
        let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
        let n = e1.cross(e2);
        if n.length_squared() <= 0.0 {
            continue;
        }
        out.push(solve::MirrorTri {
            p0: tri[0],
            e1,
            e2,
            n: n.normalize(),
            ks: uplift(m.ks, bands)?,
        });
    }
    Ok(out)
}

/// The triangles the solution meshes: their reflectance (None: not diffuse-like) and area
/// (None: not meshed), the meshed area, and whether any is diffuse-like.
struct Meshed {
    kd: Vec<Option<[f32; 3]>>,
    areas: Vec<Option<f64>>,
    area_total: f64,
    any_diffuse: bool,
}

impl Meshed {
    fn of(scene: &Scene) -> Meshed {
        let nt = scene.tris.len();
        let mut m = Meshed {
            kd: Vec::with_capacity(nt),
            areas: Vec::with_capacity(nt),
            area_total: 0.0,
            any_diffuse: false,
        };
        let rho_of: Vec<Option<[f32; 3]>> = (0..scene.materials.len() as u32)
            .map(|k| diffuse_kd(scene, k))
            .collect();
        for (t, tri) in scene.tris.iter().enumerate() {
            let mat = scene.tri_material[t];
            let d = rho_of[mat as usize];
            m.any_diffuse |= d.is_some();
            let meshed = d.is_some() || scene.materials[mat as usize].is_emissive();
            let a = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length() as f64;
            if meshed {
                m.area_total += a;
            }
            m.areas.push(meshed.then_some(a));
            m.kd.push(d);
        }
        m
    }

    /// Elements of the mesh whose largest element is the meshed area / `default_elements`.
    fn elements(&self, default_elements: f64) -> u64 {
        mesh::count(&levels_for(&self.areas, self.area_total / default_elements)).0
    }
}

/// Each meshed triangle's subdivision level for elements of at most `max_area`.
fn levels_for(areas: &[Option<f64>], max_area: f64) -> Vec<Option<u32>> {
    areas
        .iter()
        .map(|a| a.map(|a| mesh::level_for(a, max_area)))
        .collect()
}

/// A solution is refined (and keeps its coarse one, `Solution::coarser`) only with at least
/// this many times the coarse one's elements: meshes almost alike (a scene of many small
/// triangles, one element each) are not worth a second solve, and the gather's depth,
/// chosen from how the two differ, would learn little from them.
pub const MIN_REFINEMENT: f64 = 1.5;

/// The solver's time grows about as the elements to this power (shots to reach the
/// tolerance times the rays per shot; on the Cornell box, 2026-12-06, Xeon: 66 elements
/// 0.01 s, 738 0.24 s, 2,952 1.84 s, 4,128 3.11 s, `kalos radiosity cornell
/// --radiosity-max-area A`: 1.3-1.6; on a loaded machine 258 elements 0.06 s, 840 0.45 s,
/// 3,360 5.3 s: 1.7-1.8).
const SOLVE_EXPONENT: f64 = 1.75;

/// The steps of the area divisor in which a budget's mesh is searched.
const REFINE_STEP: f64 = 1.25;

impl Solution {
    /// Mesh the scene and solve on `bands` bands (3, 8 or 16). With a time budget and the
    /// default mesh, a coarse solution (`ROULETTE_ELEMENTS`) is solved first and timed; the
    /// mesh is then refined as far as `PREPROCESS_SHARE` of the budget allows at the
    /// solver's measured rate (time ~ elements^1.75, `SOLVE_EXPONENT`), never past the default mesh; the coarse
    /// solution is kept when refining would not give half as many elements again. Without a
    /// budget the default mesh is solved after the coarse one (a few thousandths of its
    /// time). The refined solution keeps the coarse one (`coarser`).
    pub fn compute(
        scene: &Scene,
        set: &RadiositySettings,
        bands: usize,
        progress: &dyn Progress,
    ) -> Result<Solution, String> {
        let budget = set.time_budget.filter(|t| t.is_finite() && *t > 0.0);
        let meshed = Meshed::of(scene);
        if set.max_area.is_some() || set.default_elements <= ROULETTE_ELEMENTS {
            return Self::compute_mesh(scene, set, &meshed, bands, progress);
        }
        // element counts are cheap (no solve): a coarse solve that the default mesh would
        // hardly refine is not made without a budget
        let n_coarse = meshed.elements(ROULETTE_ELEMENTS) as f64;
        let refines = |default_elements: f64| {
            meshed.elements(default_elements) as f64 >= MIN_REFINEMENT * n_coarse
        };
        if budget.is_none() && !refines(set.default_elements) {
            return Self::compute_mesh(scene, set, &meshed, bands, progress);
        }
        let coarse_set = RadiositySettings {
            default_elements: ROULETTE_ELEMENTS,
            ..*set
        };
        let coarse = Self::compute_mesh(scene, &coarse_set, &meshed, bands, progress)?;
        let elements = match budget {
            Some(seconds) => {
                // the finest mesh whose solve, predicted from the coarse one's as time ~
                // elements^SOLVE_EXPONENT, fits what is left (counted, not assumed proportional to the
                // area divisor: small triangles keep one element whatever the divisor)
                let t0 = coarse.stats.seconds.max(1e-3);
                let left = PREPROCESS_SHARE * seconds - t0;
                let fits = |d: f64| {
                    t0 * (meshed.elements(d) as f64 / n_coarse).powf(SOLVE_EXPONENT) <= left
                };
                // the divisor's own rule (time ~ divisor^2: elements in proportion to the
                // divisor, as on a scene of large triangles, where it was measured), or the
                // counted one where the elements grow more slowly than the divisor
                let mut d = ROULETTE_ELEMENTS * (left.max(0.0) / t0).sqrt();
                if d < ROULETTE_ELEMENTS {
                    d = ROULETTE_ELEMENTS;
                }
                while d < set.default_elements && fits((d * REFINE_STEP).min(set.default_elements))
                {
                    d = (d * REFINE_STEP).min(set.default_elements);
                }
                d
            }
            None => set.default_elements,
        }
        .min(set.default_elements);
        if !refines(elements) {
            return Ok(coarse);
        }
        let fine_set = RadiositySettings {
            default_elements: elements,
            ..*set
        };
        let mut fine = Self::compute_mesh(scene, &fine_set, &meshed, bands, progress)?;
        fine.coarser = Some(Arc::new(coarse));
        Ok(fine)
    }

    /// Mesh the scene at the settings' element area and solve.
    fn compute_mesh(
        scene: &Scene,
        set: &RadiositySettings,
        meshed: &Meshed,
        bands: usize,
        progress: &dyn Progress,
    ) -> Result<Solution, String> {
        set.validate()?;
        let t0 = Instant::now();
        // errors name the scene as the user gave it (its path)
        let name = &scene.info.source;
        // --- which triangles take part, at which level
        let Meshed {
            kd,
            areas,
            area_total,
            any_diffuse,
        } = meshed;
        let (area_total, any_diffuse) = (*area_total, *any_diffuse);
        let nt = scene.tris.len();
        if !any_diffuse {
            return Err(format!(
                "scene {name}: no diffuse surface, the radiosity preprocess has nothing to solve"
            ));
        }
        if scene.lights.is_empty() {
            return Err(format!(
                "scene {name}: no emitter, the radiosity preprocess has nothing to shoot"
            ));
        }
        let max_area = match set.max_area {
            Some(a) => a as f64,
            None => area_total / set.default_elements,
        };
        let levels = levels_for(areas, max_area);
        // --- refuse a mesh too fine before allocating it
        let (ne, nv) = mesh::count(&levels);
        let bytes = ne as f64 * (std::mem::size_of::<mesh::Element>() + 48 * bands) as f64
            + nv as f64 * (12.0 + 4.0 + 8.0 * bands as f64 + 48.0);
        if levels.iter().flatten().any(|&l| l > mesh::MAX_LEVEL)
            || ne > set.max_elements
            || bytes > MAX_MESH_BYTES as f64
        {
            return Err(format!(
                "--radiosity-max-area {max_area:.3e}: the mesh would have {ne} elements ({:.1} GiB); kalos allows {} elements and {} GiB",
                bytes / (1u64 << 30) as f64,
                set.max_elements,
                MAX_MESH_BYTES >> 30
            ));
        }
        let weld_key: Vec<u32> = scene.tri_material.clone();
        let scale = scene.bvh.bounds().diagonal();
        let mesh = mesh::build(&scene.tris, &levels, &weld_key, scale);
        let mesh_seconds = t0.elapsed().as_secs_f64();

        // --- rho and E per element and band
        let nb = bands;
        let mut tri_e: Vec<Vec<f32>> = vec![Vec::new(); nt];
        let mut tri_rho: Vec<Vec<f64>> = vec![Vec::new(); nt];
        for t in 0..nt {
            if levels[t].is_none() {
                continue;
            }
            let mat = &scene.materials[scene.tri_material[t] as usize];
            let e = uplift(mat.emission, nb)?;
            tri_e[t] = e
                .iter()
                .map(|&v| (v * std::f64::consts::PI) as f32)
                .collect();
            tri_rho[t] = uplift(kd[t].unwrap_or([0.0; 3]), nb)?;
        }
        let ne = mesh.elems.len();
        let mut rho = vec![0.0f64; ne * nb];
        let mut b = vec![0.0f64; 2 * ne * nb];
        let mut emitted = 0.0;
        for (i, e) in mesh.elems.iter().enumerate() {
            let t = e.prim as usize;
            rho[i * nb..(i + 1) * nb].copy_from_slice(&tri_rho[t]);
            for k in 0..nb {
                let ev = tri_e[t][k] as f64;
                b[2 * i * nb + k] = ev; // front side only
                emitted += ev * e.area as f64 / nb as f64;
            }
        }
        let db = b.clone();
        let de = b.clone();
        let mut sh = solve::Shooter {
            bvh: &scene.bvh,
            elems: &mesh.elems,
            bands: nb,
            rho,
            b,
            db,
            de,
            direct: vec![0.0; 2 * ne * nb],
            mirrors: mirrors_of(scene, nb)?,
            patterns: solve::Patterns::new(set.source_level),
            emitted_power: emitted,
            shots: 0,
            rays: 0,
            rows: vec![None; 2 * ne],
            row_bytes: 0,
            unshot_power: Vec::new(),
        };

        // --- shoot until the unshot power is below tolerance x emitted
        let emitter_patches = mesh
            .elems
            .iter()
            .filter(|e| tri_e[e.prim as usize].iter().any(|&v| v > 0.0))
            .count() as u64;
        let max_shots = set.max_shots.unwrap_or(200 * 2 * ne as u64);
        let ray_budget = (set.roulette_only && set.max_shots.is_none()).then_some(ROULETTE_RAYS);
        progress.message(&format!("radiosity: solving {ne} elements"));
        // progress in thousandths of the way from log(1) to log(tolerance)
        progress.begin("permille", 1000);
        let mut shown = 0u64;
        let t1 = Instant::now();
        let mut residual;
        loop {
            let (p, total) = sh.most_unshot();
            residual = if emitted > 0.0 { total / emitted } else { 0.0 };
            if residual <= set.tolerance || sh.shots >= max_shots {
                break;
            }
            if ray_budget.is_some_and(|r| sh.rays >= r && sh.shots >= emitter_patches) {
                break;
            }
            if !residual.is_finite() || residual > 100.0 {
                return Err(format!(
                    "scene {name}: the radiosity iteration diverged after {} shots (unshot power {residual:.3e} x the emitted): reflectances above 1?",
                    sh.shots
                ));
            }
            sh.shoot(p);
            if sh.shots.is_multiple_of(16) {
                if progress.cancelled() {
                    return Err(format!(
                        "scene {name}: the radiosity preprocess was interrupted"
                    ));
                }
                // progress: how far log(residual) has come towards log(tolerance)
                let f = (residual.ln() / set.tolerance.ln()).clamp(0.0, 1.0);
                let now = (f * 1000.0) as u64;
                if now > shown {
                    progress.advance(now - shown);
                    shown = now;
                }
            }
        }
        progress.advance(1000 - shown.min(1000));
        progress.finish();
        let solve_seconds = t1.elapsed().as_secs_f64();

        // --- nodal averages: B at a vertex is the area-weighted mean of its elements'
        let nvtx = mesh.verts.len();
        let mut acc = vec![0.0f64; 2 * nvtx * nb];
        let mut wsum = vec![0.0f64; nvtx];
        for (i, e) in mesh.elems.iter().enumerate() {
            let a = e.area as f64;
            for &v in &e.v {
                let v = v as usize;
                wsum[v] += a;
                for k in 0..2 * nb {
                    acc[2 * v * nb + k] += a * sh.b[2 * i * nb + k];
                }
            }
        }
        let vertex_b: Vec<f32> = acc
            .iter()
            .enumerate()
            .map(|(k, &s)| {
                let w = wsum[k / (2 * nb)];
                if w > 0.0 {
                    (s / w) as f32
                } else {
                    0.0
                }
            })
            .collect();
        let element_b: Vec<f32> = sh.b.iter().map(|&v| v as f32).collect();
        let element_unshot: Vec<f32> = sh.db.iter().map(|&v| v as f32).collect();
        // The roulette's L~ (`--rr-estimate radiosity`): the mean indirect radiance
        // arriving at each patch, (B - E - B_direct) / (pi rho), the irradiance over pi
        // without what came straight from the emitters (next-event estimation's part).
        let ambient = if set.roulette_only {
            ambient_irradiance(&mesh.elems, &sh, nb)
        } else {
            vec![0.0; nb]
        };
        let mut element_indirect = vec![0.0f32; 2 * ne * nb];
        for i in 0..ne {
            for side in 0..2 {
                let q = (2 * i + side) * nb;
                for k in 0..nb {
                    let r = sh.rho[i * nb + k];
                    if r <= 0.0 {
                        continue;
                    }
                    let e = if side == 0 {
                        tri_e[mesh.elems[i].prim as usize][k] as f64
                    } else {
                        0.0
                    };
                    let ind = (sh.b[q + k] - e - sh.direct[q + k]).max(0.0);
                    element_indirect[q + k] =
                        ((ind / r + ambient[k]) / std::f64::consts::PI) as f32;
                }
            }
        }
        let mut mean_indirect = vec![0.0f64; nb];
        let mut area_sum = 0.0f64;
        for (i, e) in mesh.elems.iter().enumerate() {
            area_sum += e.area as f64;
            for (k, m) in mean_indirect.iter_mut().enumerate() {
                *m += e.area as f64 * element_indirect[2 * i * nb + k] as f64;
            }
        }
        let mean_indirect: Vec<f32> = mean_indirect
            .iter()
            .map(|&m| {
                if area_sum > 0.0 {
                    (m / area_sum) as f32
                } else {
                    0.0
                }
            })
            .collect();
        let stats = RadiosityStats {
            elements: ne as u64,
            vertices: nvtx as u64,
            bands: nb,
            max_area,
            tolerance: set.tolerance,
            shots: sh.shots,
            rays: sh.rays,
            mesh_seconds,
            solve_seconds,
            seconds: t0.elapsed().as_secs_f64(),
            emitted_power: emitted,
            residual_unshot: residual,
            converged: residual <= set.tolerance,
        };
        Ok(Solution {
            bands: nb,
            mesh,
            vertex_b,
            element_b,
            element_unshot,
            element_indirect,
            mean_indirect,
            tri_e,
            stats,
            coarser: None,
        })
    }

    /// The meshing of triangle `prim` and, for its point `p`, the element (cell index
    /// within the triangle) and its three grid corners with their weights. None if the
    /// triangle is not meshed.
    #[inline]
    fn locate(&self, prim: u32, p: Vec3) -> Option<Located<'_>> {
        let tm = self.mesh.tris.get(prim as usize)?.as_ref()?;
        let (b1, b2) = mesh::barycentrics(tm.v0, tm.e1, tm.e2, p);
        let (cell, corners) = mesh::locate(tm.level, b1, b2);
        Some((tm, cell, corners))
    }

    /// Interpolated B (per band, into `out`) at point `p` of scene triangle `prim`, on
    /// the front (`front`: the side its winding faces) or back side. False if the
    /// triangle is not meshed (mirror, glass, black).
    #[inline]
    pub fn radiosity_into(&self, prim: u32, p: Vec3, front: bool, out: &mut [f32]) -> bool {
        let Some((tm, _, corners)) = self.locate(prim, p) else {
            return false;
        };
        let nb = self.bands;
        let n = 1u32 << tm.level;
        let side = if front { 0 } else { 1 };
        for o in out.iter_mut() {
            *o = 0.0;
        }
        for (i, j, w) in corners {
            let v = self.mesh.grid[(tm.first_grid + mesh::grid_index(n, i, j)) as usize] as usize;
            let base = (2 * v + side) * nb;
            for (k, o) in out.iter_mut().enumerate().take(nb) {
                *o += w * self.vertex_b[base + k];
            }
        }
        true
    }

    /// B / pi: the radiance a diffuse surface sends, emission included (the preview).
    #[inline]
    pub fn radiance<const N: usize>(&self, prim: u32, p: Vec3, front: bool) -> Option<Spectrum<N>> {
        debug_assert_eq!(N, self.bands);
        let mut s = [0.0f32; N];
        if !self.radiosity_into(prim, p, front, &mut s) {
            return None;
        }
        Some(Spectrum(s) * std::f32::consts::FRAC_1_PI)
    }

    /// (B - E) / pi: the reflected radiance only (what the gather looks up), clamped at 0.
    #[inline]
    pub fn reflected<const N: usize>(
        &self,
        prim: u32,
        p: Vec3,
        front: bool,
    ) -> Option<Spectrum<N>> {
        debug_assert_eq!(N, self.bands);
        let mut s = [0.0f32; N];
        if !self.radiosity_into(prim, p, front, &mut s) {
            return None;
        }
        if front {
            let e = &self.tri_e[prim as usize];
            for (v, ev) in s.iter_mut().zip(e) {
                *v -= ev;
            }
        }
        Some(Spectrum(s).map(|v| v.max(0.0) * std::f32::consts::FRAC_1_PI))
    }

    /// The roulette's L~ at the point of triangle `prim` with barycentrics (`b1`, `b2`)
    /// (the hit's, the mesh's own parametrisation: no projection) on side `front`: its
    /// element's mean indirect radiance arriving. None if the triangle is not meshed.
    #[inline]
    pub fn indirect_at<const N: usize>(
        &self,
        prim: u32,
        b1: f32,
        b2: f32,
        front: bool,
    ) -> Option<Spectrum<N>> {
        debug_assert_eq!(N, self.bands);
        let tm = self.mesh.tris.get(prim as usize)?.as_ref()?;
        let cell = mesh::cell_of(tm.level, b1, b2);
        let q = (2 * (tm.first_elem + cell) as usize + usize::from(!front)) * N;
        let mut s = [0.0f32; N];
        s.copy_from_slice(self.element_indirect.get(q..q + N)?);
        Some(Spectrum(s))
    }

    /// The area-weighted mean of the roulette's L~ over the elements' front sides
    /// (`mean_indirect`): the L~ of what the solution does not cover (mirrors, glass).
    #[inline]
    pub fn mean_indirect<const N: usize>(&self) -> Spectrum<N> {
        let mut s = [0.0f32; N];
        for (o, v) in s.iter_mut().zip(&self.mean_indirect) {
            *o = *v;
        }
        Spectrum(s)
    }

    /// Whether triangle `prim` has a solution (it is diffuse-like or emissive).
    #[inline]
    pub fn covers(&self, prim: u32) -> bool {
        matches!(self.mesh.tris.get(prim as usize), Some(Some(_)))
    }
}

/// Cohen, Chen, Wallace and Greenberg's ambient term per band, as irradiance: the
/// reflected power the solve left unshot (dB less the emission not yet shot, which
/// next-event estimation carries), U = sum dB A, arrives at the surfaces again and again
/// as U / (1 - rho~), spread over their area S: U / ((1 - rho~) S), rho~ the area-weighted
/// reflectance (0 where it reaches 1: no finite ambient).
fn ambient_irradiance(elems: &[mesh::Element], sh: &solve::Shooter, nb: usize) -> Vec<f64> {
    let (mut unshot, mut rho_a) = (vec![0.0f64; nb], vec![0.0f64; nb]);
    let mut area = 0.0f64;
    for (i, e) in elems.iter().enumerate() {
        let a = e.area as f64;
        area += a;
        for k in 0..nb {
            rho_a[k] += a * sh.rho[i * nb + k];
            for side in 0..2 {
                let q = (2 * i + side) * nb + k;
                unshot[k] += a * (sh.db[q] - sh.de[q]).max(0.0);
            }
        }
    }
    (0..nb)
        .map(|k| {
            let rho = if area > 0.0 { rho_a[k] / area } else { 1.0 };
            if rho < 1.0 && area > 0.0 {
                unshot[k] / ((1.0 - rho) * area)
            } else {
                0.0
            }
        })
        .collect()
}
