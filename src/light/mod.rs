//! Emitters: every triangle whose material has emission Ke > 0 is a one-sided area light
//! on the side its counter-clockwise winding faces. Lights are chosen in proportion to
//! their power (luminance of Le x area x pi). Emission sampling is split into a position
//! (density per area) and a direction (cosine-weighted, per solid angle), as light
//! tracing, BDPT and radiosity shooting need.
//!
//! Besides the area lights a scene may have point lights (Dirac in position: reached by
//! next-event estimation only; isotropic, spots, or directional: Dirac in direction) and one environment (`env`: light from infinitely far
//! away, seen by rays that leave the scene). Next-event estimation first chooses among
//! the kinds (`Lights::choose`) in proportion to their power: the area lights together
//! (sum of pi A L), each point light (4 pi I, a spot too; a directional light pi R^2 E)
//! and the environment (pi^2 R^2 times its mean
//! radiance, R the radius of the scene's bounding sphere, the power it sends through a
//! disk of the scene's size). With area lights only the choice is skipped, so such scenes
//! render as before.
//!
//! An area light's radiance may be a texture (Mitsuba's area emitter with a textured
//! `radiance`): `le` is then the texture's mean (for the choice by power and for the
//! radiosity solution), and every estimator reads the texture at the point's uv: a
//! sampled point's (`sample_position`), a hit's (`Material::emitted_at`) and a BDPT
//! vertex's (`emitted_at`). Points are still sampled uniformly by area (Mitsuba samples
//! the texture's image and maps it through the shape's uv parametrization; both are
//! unbiased, kalos' without a second distribution per light).

pub mod env;
pub use env::EnvLight;

use crate::material::AlbedoTable;
use crate::material::Material;
use crate::math::{Frame, Vec3};
use crate::sampling::{square_to_cosine_hemisphere, square_to_uniform_triangle, Distribution1D};
use glam::Vec2;
use std::sync::Arc;

/// One emissive triangle.
#[derive(Clone, Debug)]
pub struct AreaLight {
    pub tri: u32,
    pub v0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    /// Unit normal of the emitting side.
    pub n: Vec3,
    pub area: f32,
    /// Emitted radiance, linear RGB (the cosine-weighted average if `table` is set).
    pub le: [f32; 3],
    /// Directional emission L_e(w) = 1 - a(cos theta) (see `Material::emission_table`).
    pub table: Option<Arc<AlbedoTable>>,
}

/// A textured area light's texture and its triangle's uvs at the three corners
/// (barycentrics for a triangle without texture coordinates, as hits have them).
#[derive(Clone, Debug)]
pub struct LightTexture {
    pub texture: Arc<crate::texture::Texture>,
    pub uv: [Vec2; 3],
}

impl LightTexture {
    /// The texture's radiance at barycentrics (b1, b2) (p = v0 + b1 e1 + b2 e2).
    #[inline]
    fn radiance_at(&self, b1: f32, b2: f32) -> [f32; 3] {
        let uv = self.uv[0] * (1.0 - b1 - b2) + self.uv[1] * b1 + self.uv[2] * b2;
        self.texture.lookup(uv.x, uv.y)
    }
}

impl AreaLight {
    /// Barycentrics (b1, b2) of a point `p` of the triangle's plane.
    fn barycentrics(&self, p: Vec3) -> (f32, f32) {
        let d = p - self.v0;
        let (d00, d01, d11) = (
            self.e1.dot(self.e1),
            self.e1.dot(self.e2),
            self.e2.dot(self.e2),
        );
        let (d20, d21) = (d.dot(self.e1), d.dot(self.e2));
        let den = d00 * d11 - d01 * d01;
        ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den)
    }
}

/// A point sampled on an emitter.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub p: Vec3,
    pub n: Vec3,
    /// Emitted radiance; if `directional`, its cosine-weighted average (`emitted` gives
    /// it per direction).
    pub le: [f32; 3],
    pub directional: bool,
    /// Density per unit area, including the choice of the light.
    pub pdf_area: f32,
    pub light: u32,
}

impl LightSample {
    /// Radiance the sampled point emits towards a direction at cosine `cos` to its normal.
    #[inline(always)]
    pub fn emitted(&self, lights: &Lights, cos: f32) -> [f32; 3] {
        if self.directional {
            lights.emitted(self.light, cos)
        } else {
            self.le
        }
    }
}

/// A light reached by next-event estimation only (Dirac in position or direction): an
/// isotropic point light, a spot light or a directional light.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    pub p: Vec3,
    /// Radiant intensity (W/sr), linear RGB; for a directional light its irradiance (W/m^2
    /// on a surface facing it).
    pub intensity: [f32; 3],
    pub shape: PointShape,
}

/// How a [`PointLight`] sends its light.
#[derive(Clone, Debug, PartialEq)]
pub enum PointShape {
    /// The same intensity in every direction.
    Isotropic,
    /// Mitsuba's spot light.
    Spot(Spot),
    /// Parallel light travelling along this unit direction, from infinitely far away.
    Directional(Vec3),
}

/// Mitsuba's spot light: full intensity within `beam_width` of its axis (+z of its frame),
/// falling off linearly in angle to zero at `cutoff`; a texture, if any, is projected over
/// the cone (u, v = 0.5 + 0.5 x / (z tan cutoff), 0.5 + 0.5 y / (z tan cutoff), v
/// downwards as Mitsuba's bitmaps).
///
/// With a `frustum`, Mitsuba's projector: the reciprocal of a perspective camera, whose
/// irradiance image lies on the plane z = 1 of its frame over
/// u, v = 0.5 - 0.5 x / (z tan_x), 0.5 - 0.5 y / (z tan_y) in [0, 1]. Its intensity
/// towards a direction at angle theta from the axis is pi E(u, v) / cos^3 theta, so
/// that a plane facing it at distance z receives pi E / z^2 everywhere in the frustum
/// (Mitsuba's `projector.cpp`); the cone angles are 90 degrees.
#[derive(Clone, Debug)]
pub struct Spot {
    /// World to the light's frame (the inverse of its `to_world` rotation and scale).
    pub to_local: glam::Mat3,
    /// Angles in radians.
    pub cutoff: f32,
    pub beam_width: f32,
    pub texture: Option<Arc<crate::texture::Texture>>,
    /// A projector's tan of half its field of view along x and y.
    pub frustum: Option<[f32; 2]>,
}

impl PartialEq for Spot {
    fn eq(&self, o: &Spot) -> bool {
        let same_texture = match (&self.texture, &o.texture) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            (a, b) => a.is_none() && b.is_none(),
        };
        self.to_local == o.to_local
            && self.cutoff == o.cutoff
            && self.beam_width == o.beam_width
            && self.frustum == o.frustum
            && same_texture
    }
}

impl Spot {
    /// The factor of the intensity towards world direction `d` (from the light).
    pub fn falloff(&self, d: Vec3) -> [f32; 3] {
        if let Some([tx, ty]) = self.frustum {
            return self.projected(d, tx, ty);
        }
        let l = (self.to_local * d).normalize_or_zero();
        let cos = l.z;
        if cos.partial_cmp(&self.cutoff.cos()) != Some(std::cmp::Ordering::Greater) {
            return [0.0; 3];
        }
        let k = if cos >= self.beam_width.cos() {
            1.0
        } else {
            (self.cutoff - cos.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width)
        };
        match &self.texture {
            None => [k; 3],
            Some(t) => {
                let f = 1.0 / (l.z * self.cutoff.tan());
                let (u, v) = (0.5 + 0.5 * l.x * f, 0.5 + 0.5 * l.y * f);
                t.lookup(u, 1.0 - v).map(|c| c * k)
            }
        }
    }

    /// A projector's factor towards world direction `d`: pi E(u, v) / cos^3 theta inside
    /// its frustum, 0 outside.
    fn projected(&self, d: Vec3, tx: f32, ty: f32) -> [f32; 3] {
        let l = self.to_local * d;
        let cos = l.z / l.length();
        if !(l.z > 0.0 && cos.is_finite()) {
            return [0.0; 3];
        }
        let (u, v) = (0.5 - 0.5 * l.x / (l.z * tx), 0.5 - 0.5 * l.y / (l.z * ty));
        if !((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)) {
            return [0.0; 3];
        }
        let k = std::f32::consts::PI / (cos * cos * cos);
        match &self.texture {
            None => [k; 3],
            Some(t) => t.lookup(u, 1.0 - v).map(|c| c * k),
        }
    }

    /// Mitsuba's defaults: a 20 degree cutoff, the beam 3/4 of it.
    pub const DEFAULT_CUTOFF_DEGREES: f32 = 20.0;
    pub const DEFAULT_BEAM_SHARE: f32 = 0.75;
}

impl PointLight {
    /// Power-like weight for the choice among lights (`radius`: the scene's bounding sphere).
    fn weight(&self, radius: f32) -> f32 {
        let lum = crate::spectrum::Spectrum::<3>(self.intensity)
            .luminance()
            .max(0.0);
        match &self.shape {
            // a spot weighs as the point light of its intensity: its cone's power alone
            // would starve it beside an environment lighting the same surfaces
            PointShape::Isotropic | PointShape::Spot(_) => 4.0 * std::f32::consts::PI * lum,
            PointShape::Directional(_) => std::f32::consts::PI * radius * radius * lum,
        }
    }
}

/// What `Lights::choose` picked for next-event estimation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chosen {
    /// The area lights; `sample_position` with this rescaled number picks one of them
    /// (its `pdf_area` includes the choice of the kind).
    Area(f32),
    /// Point light i, chosen with probability `pmf`.
    Point(usize, f32),
    /// The environment, chosen with probability `pmf`.
    Env(f32),
}

/// An emitter whose power (radiance x area x pi for an area light, 4 pi x intensity for
/// a point light, the environment's share) is not a finite single-precision number: the
/// choice among lights by power would be undefined (an infinite weight leaves every
/// other light unchosen), so the scene is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TooBright {
    /// The area light of material `material`, with its power (f64).
    Area { material: u32, power: f64 },
    /// Point light `index` of the scene's list.
    Point { index: usize, power: f64 },
    /// The environment.
    Env { power: f64 },
    /// All area lights together.
    Total { power: f64 },
}

impl TooBright {
    /// What is wrong, for a message that names the emitter in front of it.
    pub fn describe(&self) -> String {
        let p = match self {
            TooBright::Area { power, .. }
            | TooBright::Point { power, .. }
            | TooBright::Env { power }
            | TooBright::Total { power } => *power,
        };
        let what = match self {
            TooBright::Area { .. } => "its emitted power (radiance x area x pi)",
            TooBright::Point { .. } => "its emitted power (4 pi x intensity)",
            TooBright::Env { .. } => "its power through the scene",
            TooBright::Total { .. } => "the area lights' total power",
        };
        format!(
            "{what} is {p:.3e}, beyond the single-precision range ({:.3e}): scale the emission down",
            f32::MAX
        )
    }
}

/// Luminance in double precision (no overflow), at least 0.
fn luminance64(c: [f32; 3]) -> f64 {
    let w = crate::spectrum::LUMINANCE_RGB;
    (w[0] as f64 * c[0] as f64 + w[1] as f64 * c[1] as f64 + w[2] as f64 * c[2] as f64).max(0.0)
}

/// A light's power must be a finite f32 (`TooBright`).
fn finite_power(p: f64) -> bool {
    p.is_finite() && p <= f32::MAX as f64
}

pub struct Lights {
    lights: Vec<AreaLight>,
    dist: Distribution1D,
    /// For each scene triangle, its light index or u32::MAX.
    light_of_tri: Vec<u32>,
    /// Each area light's texture of radiance, if any; empty if no light has one, so that
    /// the untextured scenes' light samples check this once and read lights of the size
    /// they had without textures.
    textures: Vec<Option<LightTexture>>,
    points: Vec<PointLight>,
    env: Option<EnvLight>,
    /// The choice among the kinds: entry 0 the area lights, 1..=points.len() the point
    /// lights, then the environment. None with area lights only.
    kinds: Option<Distribution1D>,
    /// Probability of choosing the area lights (1 with area lights only).
    p_area: f32,
}

impl Lights {
    /// The area lights of a scene: one per emissive triangle of positive area (`uv_of`:
    /// a triangle's texture coordinates, if it has them). An emitter whose power
    /// overflows is refused (`TooBright`).
    pub fn new(
        tris: &[[Vec3; 3]],
        tri_material: &[u32],
        materials: &[Material],
        uv_of: impl Fn(usize) -> Option<[Vec2; 3]>,
    ) -> Result<Lights, TooBright> {
        let mut lights = Vec::new();
        let mut textures = Vec::new();
        let mut light_of_tri = vec![u32::MAX; tris.len()];
        for (i, t) in tris.iter().enumerate() {
            let m = &materials[tri_material[i] as usize];
            if !m.is_emissive() {
                continue;
            }
            let e1 = t[1] - t[0];
            let e2 = t[2] - t[0];
            let c = e1.cross(e2);
            let area = 0.5 * c.length();
            if area <= 0.0 || !area.is_finite() {
                continue;
            }
            light_of_tri[i] = lights.len() as u32;
            lights.push(AreaLight {
                tri: i as u32,
                v0: t[0],
                e1,
                e2,
                n: c.normalize(),
                area,
                le: m.emission,
                table: m.emission_table.clone(),
            });
            textures.push(m.emission_texture.as_ref().map(|t| LightTexture {
                texture: t.clone(),
                uv: uv_of(i).unwrap_or([Vec2::ZERO, Vec2::X, Vec2::Y]),
            }));
        }
        let mut power: Vec<f32> = Vec::with_capacity(lights.len());
        let mut total = 0.0f64;
        for l in &lights {
            // in f64, so that an overflow is seen rather than taken as infinity
            let p = luminance64(l.le) * l.area as f64 * std::f64::consts::PI;
            if !finite_power(p) {
                let material = tri_material[l.tri as usize];
                return Err(TooBright::Area { material, power: p });
            }
            total += p;
            power.push(
                crate::spectrum::Spectrum::<3>(l.le).luminance().max(1e-9)
                    * l.area
                    * std::f32::consts::PI,
            );
        }
        if !finite_power(total) {
            return Err(TooBright::Total { power: total });
        }
        if textures.iter().all(Option::is_none) {
            textures = Vec::new();
        }
        Ok(Lights {
            dist: Distribution1D::new(&power),
            lights,
            light_of_tri,
            textures,
            points: Vec::new(),
            env: None,
            kinds: None,
            p_area: 1.0,
        })
    }

    /// Add point lights and an environment to the area lights; `radius` is the radius of
    /// the scene's bounding sphere (for the environment's share of the choice).
    /// A light whose power overflows is refused (`TooBright`), as are the lights together.
    pub fn add_distant(
        &mut self,
        points: Vec<PointLight>,
        env: Option<EnvLight>,
        radius: f32,
    ) -> Result<(), TooBright> {
        let mut total = self.dist.total();
        for (index, p) in points.iter().enumerate() {
            let power = 4.0 * std::f64::consts::PI * luminance64(p.intensity);
            if !finite_power(power) {
                return Err(TooBright::Point { index, power });
            }
            total += power;
        }
        if let Some(e) = &env {
            let r = radius.max(1e-3) as f64;
            let power = std::f64::consts::PI.powi(2) * r * r * e.mean_luminance as f64;
            if !finite_power(power) {
                return Err(TooBright::Env { power });
            }
            total += power;
        }
        if !finite_power(total) {
            return Err(TooBright::Total { power: total });
        }
        self.points = points;
        self.env = env;
        if self.points.is_empty() && self.env.is_none() {
            self.kinds = None;
            self.p_area = 1.0;
            return Ok(());
        }
        let mut w = vec![self.dist.total() as f32];
        let r = radius.max(1e-3);
        for p in &self.points {
            w.push(p.weight(r));
        }
        if let Some(e) = &self.env {
            w.push(std::f32::consts::PI.powi(2) * r * r * e.mean_luminance);
        }
        let kinds = Distribution1D::new(&w);
        self.p_area = if kinds.is_empty() { 0.0 } else { kinds.pmf(0) };
        self.kinds = Some(kinds);
        Ok(())
    }

    /// Point lights.
    pub fn points(&self) -> &[PointLight] {
        &self.points
    }

    /// The environment, if any.
    pub fn env(&self) -> Option<&EnvLight> {
        self.env.as_ref()
    }

    /// Whether the scene has lights other than area lights (which BDPT, the radiosity
    /// solution and the estimate roulette's L~ do not know).
    pub fn has_distant(&self) -> bool {
        self.kinds.is_some()
    }

    /// No light of any kind.
    pub fn is_dark(&self) -> bool {
        self.lights.is_empty() && self.points.is_empty() && self.env.is_none()
    }

    /// Choose a kind of light for next-event estimation with `u` (None: no lights).
    #[inline(always)]
    pub fn choose(&self, u: f32) -> Option<Chosen> {
        let Some(k) = &self.kinds else {
            return (!self.lights.is_empty()).then_some(Chosen::Area(u));
        };
        if k.is_empty() {
            return None;
        }
        let (i, pmf, ur) = k.sample(u);
        Some(if i == 0 {
            Chosen::Area(ur)
        } else if i <= self.points.len() {
            Chosen::Point(i - 1, pmf)
        } else {
            Chosen::Env(pmf)
        })
    }

    /// Probability that `choose` picks the environment.
    #[inline]
    pub fn pmf_env(&self) -> f32 {
        match (&self.kinds, &self.env) {
            (Some(k), Some(_)) => k.pmf(k.len() - 1),
            _ => 0.0,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }
    pub fn len(&self) -> usize {
        self.lights.len()
    }
    pub fn get(&self, i: u32) -> &AreaLight {
        &self.lights[i as usize]
    }
    pub fn all(&self) -> &[AreaLight] {
        &self.lights
    }
    /// Total emitted power (sum of Le x area x pi), per RGB channel.
    #[allow(clippy::needless_range_loop)]
    pub fn total_power_rgb(&self) -> [f64; 3] {
        let mut p = [0.0f64; 3];
        for l in &self.lights {
            for c in 0..3 {
                p[c] += l.le[c] as f64 * l.area as f64 * std::f64::consts::PI;
            }
        }
        p
    }

    /// Radiance light `i` emits towards a direction at cosine `cos` to its normal.
    /// (Out of line: the path tracer's loop runs faster without it; `LightSample::emitted`
    /// calls it only for directional emitters.)
    #[inline(never)]
    pub fn emitted(&self, i: u32, cos: f32) -> [f32; 3] {
        let l = &self.lights[i as usize];
        match &l.table {
            None => l.le,
            Some(t) => t.complement(cos),
        }
    }

    /// [`Lights::emitted`] at point `p` of light `i` (a textured light's texture there).
    #[inline(never)]
    pub fn emitted_at(&self, i: u32, cos: f32, p: Vec3) -> [f32; 3] {
        let Some(t) = self.texture(i as usize) else {
            return self.emitted(i, cos);
        };
        let (b1, b2) = self.lights[i as usize].barycentrics(p);
        t.radiance_at(b1, b2)
    }

    /// Light `i`'s texture of radiance, if it has one.
    #[inline]
    fn texture(&self, i: usize) -> Option<&LightTexture> {
        self.textures.get(i).and_then(Option::as_ref)
    }

    /// Light index of scene triangle `prim`, if it emits.
    #[inline]
    pub fn light_of(&self, prim: u32) -> Option<u32> {
        // (instanced triangles, numbered past the scene's own, never emit)
        let l = self
            .light_of_tri
            .get(prim as usize)
            .copied()
            .unwrap_or(u32::MAX);
        (l != u32::MAX).then_some(l)
    }

    /// Sample a light by power, then a point uniformly on it.
    #[inline(always)]
    pub fn sample_position(&self, u_sel: f32, u: Vec2) -> Option<LightSample> {
        if self.textures.is_empty() {
            self.sample_position_of::<false>(u_sel, u)
        } else {
            self.sample_position_textured(u_sel, u)
        }
    }

    /// [`Lights::sample_position`] in a scene with a textured light (out of line, so that
    /// the texture's lookup and its call leave the untextured scenes' code as it was).
    #[cold]
    #[inline(never)]
    fn sample_position_textured(&self, u_sel: f32, u: Vec2) -> Option<LightSample> {
        self.sample_position_of::<true>(u_sel, u)
    }

    /// [`Lights::sample_position`], reading the lights' textures if `TEXTURED`.
    #[inline(always)]
    fn sample_position_of<const TEXTURED: bool>(&self, u_sel: f32, u: Vec2) -> Option<LightSample> {
        if self.lights.is_empty() {
            return None;
        }
        let (i, pmf, _) = self.dist.sample(u_sel);
        let l = &self.lights[i];
        let b = square_to_uniform_triangle(u);
        let p = l.v0 + l.e1 * b.x + l.e2 * b.y;
        Some(LightSample {
            p,
            n: l.n,
            le: match self.texture(i) {
                Some(t) if TEXTURED => t.radiance_at(b.x, b.y),
                _ => l.le,
            },
            directional: l.table.is_some(),
            pdf_area: pmf * self.p_area / l.area,
            light: i as u32,
        })
    }

    /// Density per unit area with which `sample_position` produces a point on light `i`.
    #[inline]
    pub fn pdf_position(&self, i: u32) -> f32 {
        let l = &self.lights[i as usize];
        self.dist.pmf(i as usize) * self.p_area / l.area
    }

    /// An emission direction from light `i` (cosine-weighted about its normal) and its
    /// solid-angle density.
    #[inline]
    pub fn sample_direction(&self, i: u32, u: Vec2) -> (Vec3, f32) {
        let l = &self.lights[i as usize];
        let local = square_to_cosine_hemisphere(u);
        let d = Frame::from_normal(l.n).to_world(local);
        (d, local.z * std::f32::consts::FRAC_1_PI)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Bsdf;
    use crate::sampling::chi2::{assert_chi2, chi2_sphere};

    fn mat(le: [f32; 3]) -> Material {
        Material {
            name: "l".into(),
            bsdf: Bsdf::Black,
            emission: le,
            emission_table: None,
            emission_texture: None,
            kd_texture: None,
            one_sided: false,
            opacity: 1.0,
            opacity_texture: None,
            normal_map: None,
            roughness: None,
            varying: None,
        }
    }

    #[test]
    fn chi2_light_sampling_in_solid_angle() {
        // Two emitters of different power and size, seen from the origin.
        let tris = [
            [
                Vec3::new(-1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            [
                Vec3::new(2.0, -1.0, 0.5),
                Vec3::new(2.0, 1.0, 0.0),
                Vec3::new(2.0, 0.0, 1.5),
            ],
            [
                Vec3::new(0.0, -3.0, 0.0),
                Vec3::new(1.0, -3.0, 0.0),
                Vec3::new(0.0, -3.0, 1.0),
            ],
        ];
        let mats = [mat([1.0, 2.0, 3.0]), mat([5.0; 3]), mat([0.0; 3])];
        let lights = Lights::new(&tris, &[0, 1, 2], &mats, |_| None).unwrap();
        assert_eq!(lights.len(), 2);
        assert_eq!(lights.light_of(2), None);
        let pdf = |w: Vec3| -> f32 {
            // sum over lights hit by the ray from the origin (no occlusion between them here)
            let mut p = 0.0;
            for (i, l) in lights.all().iter().enumerate() {
                let r = crate::math::Ray::new(Vec3::ZERO, w);
                let bvh = crate::accel::Bvh::build(&[[l.v0, l.v0 + l.e1, l.v0 + l.e2]]);
                if let Some(h) = bvh.intersect(&r, f32::INFINITY) {
                    let cos = w.dot(l.n).abs();
                    p += lights.pdf_position(i as u32) * h.t * h.t / cos;
                }
            }
            p
        };
        let r = chi2_sphere(
            |u1, u2| lights.sample_position(u1, u2).map(|s| s.p.normalize()),
            pdf,
            200_000,
            42,
        );
        assert_chi2("light sampling", &r);
        assert!((r.pdf_integral - 1.0).abs() < 5e-3, "{}", r.pdf_integral);
    }

    #[test]
    fn untextured_lights_sample_without_textures() {
        // An area light is as large as before textured emission (its texture is kept
        // beside it): light sampling reads no more memory per light.
        assert!(std::mem::size_of::<AreaLight>() <= 80);
        let tris = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::Z, Vec3::Z + Vec3::X, Vec3::Z + Vec3::Y],
        ];
        let plain = Lights::new(&tris, &[0, 0], &[mat([1.0; 3])], |_| None).unwrap();
        assert!(plain.textures.is_empty());
        // One textured light among untextured ones: each light's own radiance.
        let mut textured = mat([0.5; 3]);
        let checker = crate::texture::Texture::checkerboard(
            [0.0; 3],
            [1.0; 3],
            [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        );
        let texture = Arc::new(checker);
        textured.emission_texture = Some(texture.clone());
        let mats = [mat([2.0, 3.0, 4.0]), textured];
        let lights = Lights::new(&tris, &[0, 1], &mats, |_| None).unwrap();
        let mut seen = Vec::new();
        for u_sel in [0.1, 0.95] {
            let u = Vec2::new(0.3, 0.6);
            let ls = lights.sample_position(u_sel, u).unwrap();
            let b = square_to_uniform_triangle(u);
            let le = match ls.light {
                0 => [2.0, 3.0, 4.0],
                _ => texture.lookup(b.x, b.y),
            };
            assert_eq!(ls.le, le, "light {}", ls.light);
            assert_eq!(lights.emitted_at(ls.light, 1.0, ls.p), le);
            seen.push(ls.light);
        }
        assert_eq!(seen, [0, 1]);
    }

    #[test]
    fn chi2_emission_direction() {
        let tris = [[Vec3::ZERO, Vec3::X, Vec3::Y]];
        let lights = Lights::new(&tris, &[0], &[mat([1.0; 3])], |_| None).unwrap();
        let n = lights.get(0).n;
        let r = chi2_sphere(
            |_, u| Some(lights.sample_direction(0, u).0),
            |w| (w.dot(n).max(0.0)) * std::f32::consts::FRAC_1_PI,
            200_000,
            43,
        );
        assert_chi2("emission direction", &r);
    }
}
