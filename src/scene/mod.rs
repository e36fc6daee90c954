//! Scenes: files (OBJ/MTL, TOML) and built-ins are read into a plain `SceneDesc`, which
//! `Scene::build` turns into the immutable scene the estimators see (triangles, materials,
//! textures, lights and the BVH).

pub mod builtin;
pub mod camera;
mod emitter_names;
pub mod hit;
pub mod instance;
pub mod mesh_attr;
pub mod mitsuba;
pub mod mtl;
pub mod obj;
pub mod ply;
pub mod serialized;

pub mod toml_scene;
pub mod tri_attr;
mod varying;

pub use crate::texture::Texture;
use crate::texture::{self, normal as texture_normal};
pub use camera::{Camera, CameraDesc, FovAxis};
pub use hit::{Shading, SurfaceHit};

use crate::accel::Bvh;
use crate::light::Lights;
use crate::material::dielectric::Tint;
use crate::material::{AlbedoTable, Bsdf, Distribution, Material};
use crate::math::{Bounds3, Vec2, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// A material as files describe it (MTL vocabulary).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    pub name: String,
    pub kd: [f32; 3],
    pub ks: [f32; 3],
    pub ns: f32,
    pub ni: f32,
    pub ke: [f32; 3],
    /// A texture of emitted radiance (Mitsuba's area emitter), `ke` its mean.
    pub ke_texture: Option<Arc<Texture>>,
    pub illum: u8,
    pub map_kd: Option<PathBuf>,
    /// How `map_kd` is looked up (Mitsuba's bitmap `filter_type`, `wrap_mode`, `to_uv`).
    pub kd_sampling: texture::Sampling,
    /// A diffuse-reflectance texture the scene reader made (Mitsuba's `checkerboard`),
    /// used instead of `map_kd`.
    pub kd_procedural: Option<Arc<Texture>>,
    /// A shading normal from a texture (Mitsuba's `normalmap` and `bumpmap`).
    pub normal_map: Option<texture_normal::NormalMap>,
    /// A rough conductor's anisotropic or textured roughness (Mitsuba's `alpha_u`,
    /// `alpha_v`); None: the model's one `alpha`.
    pub roughness: Option<crate::material::roughness::Roughness>,
    /// The diffuse reflectance from a mesh attribute (Mitsuba's `mesh_attribute`), used
    /// instead of `kd`.
    pub kd_attribute: Option<texture::mesh_attribute::MeshAttribute>,
    /// The share of light the surface stops (Mitsuba's `mask`, MTL's `d`); the rest
    /// passes straight through, as if the surface were not there (a cut-out).
    pub opacity: f32,
    /// A map of opacity (times `opacity`): its file, lookup and channel.
    pub map_opacity: Option<(PathBuf, texture::Sampling, texture::OpacityFrom)>,
    /// Emit L_e(w) = 1 - a(w) instead of `ke`, a the directional albedo of the material's
    /// BSDF (tabulated when the scene is built): the radiance of a closed room of such
    /// surfaces is exactly 1 (`furnace-glossy`). No file format sets it.
    pub emit_one_minus_albedo: bool,
    /// Where the material was defined (`file:line` of its `newmtl`), for warnings.
    pub source: Option<String>,
    /// What kalos renders differently from what the file asks (one warning per material
    /// when the scene is built).
    pub notes: Vec<String>,
    /// A surface model beyond MTL's vocabulary (Mitsuba's BSDF plugins); None: the MTL
    /// fields above describe the surface. `kd`/`map_kd` stay the diffuse reflectance.
    pub model: Option<SurfaceModel>,
    /// Reflects on its front side only (counter-clockwise winding) and absorbs on its
    /// back, as Mitsuba's BSDFs do outside a `twosided`; OBJ and kalos' own scenes are
    /// two-sided. Dielectrics have two sides of their own and ignore it.
    pub one_sided: bool,
}

/// Surface models of Mitsuba 3's BSDF plugins (parameters in RGB; roughness is the alpha of
/// the microfacet `distribution`, isotropic; alpha 0 is the smooth interface, whose
/// distribution is unused).
#[derive(Clone, Debug, PartialEq)]
pub enum SurfaceModel {
    /// `conductor` / `roughconductor`: complex index of refraction eta + i k per channel,
    /// relative to the outside medium, times a specular reflectance.
    Conductor {
        eta: [f32; 3],
        k: [f32; 3],
        specular: [f32; 3],
        alpha: f32,
        distribution: Distribution,
    },
    /// `plastic` / `roughplastic`: a diffuse base (`kd`, `map_kd`) under a dielectric coat of
    /// relative index `eta`; `nonlinear` is Mitsuba's parameter of that name.
    Plastic {
        eta: f32,
        specular: [f32; 3],
        alpha: f32,
        distribution: Distribution,
        nonlinear: bool,
    },
    /// `dielectric` / `roughdielectric`: an interface of relative index `eta` (inside over
    /// outside), its reflection and transmission scaled by `tint`.
    Dielectric {
        eta: f32,
        alpha: f32,
        distribution: Distribution,
        tint: Tint,
    },
    /// `thindielectric`: a thin slab of index `eta` (no refraction of the direction).
    ThinDielectric { eta: f32, tint: Tint },
    /// `principled`: Burley's BSDF as Mitsuba has it.
    Principled(Box<crate::material::varying::PrincipledParams>),
    /// `blendbsdf`: (1 - weight) times the first plus weight times the second.
    Blend {
        weight: texture::mesh_attribute::Param,
        bsdfs: Box<[MaterialDesc; 2]>,
    },
}

impl SurfaceModel {
    /// Mitsuba's plugin name, for messages.
    pub fn plugin(&self) -> &'static str {
        match self {
            SurfaceModel::Conductor { alpha, .. } if *alpha > 0.0 => "roughconductor",
            SurfaceModel::Conductor { .. } => "conductor",
            SurfaceModel::Plastic { alpha, .. } if *alpha > 0.0 => "roughplastic",
            SurfaceModel::Plastic { .. } => "plastic",
            SurfaceModel::Dielectric { alpha, .. } if *alpha > 0.0 => "roughdielectric",
            SurfaceModel::Dielectric { .. } => "dielectric",
            SurfaceModel::ThinDielectric { .. } => "thindielectric",
            SurfaceModel::Blend { .. } => "blendbsdf",
            SurfaceModel::Principled(p) if p.thin => "principledthin",
            SurfaceModel::Principled(_) => "principled",
        }
    }
}

/// Light from infinitely far away (Mitsuba's `constant` and `envmap` emitters).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentDesc {
    /// Constant radiance (linear RGB), or the scale of `map`.
    pub radiance: [f32; 3],
    /// An equirectangular image (EXR, HDR or PNG) in Mitsuba's convention.
    pub map: Option<PathBuf>,
    /// Rotation from the map's frame to world space (Mitsuba's `to_world`, columns).
    pub to_world: glam::Mat3,
    /// Where it was defined (`file:line`), for messages.
    pub source: Option<String>,
}

/// An isotropic point light (Mitsuba's `point` emitter).
#[derive(Clone, Debug, PartialEq)]
pub struct PointLightDesc {
    pub position: Vec3,
    /// Radiant intensity (W/sr, linear RGB); a directional light's irradiance (W/m^2).
    pub intensity: [f32; 3],
    pub shape: PointLightShape,
    pub source: Option<String>,
}

/// How a point light sends its light (see `light::PointShape`).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum PointLightShape {
    #[default]
    Isotropic,
    /// Mitsuba's spot: axis +z of `to_world` (rotation and scale), angles in degrees, an
    /// optional image projected over the cone.
    Spot {
        to_world: glam::Mat3,
        cutoff: f32,
        beam_width: f32,
        texture: Option<PathBuf>,
        /// Mitsuba's projector instead: tan of half its field of view along x and y (see
        /// `light::Spot::frustum`); the cone angles are then 90 degrees.
        frustum: Option<[f32; 2]>,
    },
    /// Light travelling along this direction from infinitely far away.
    Directional(Vec3),
}

impl MaterialDesc {
    /// "file:line: material 'name'" (without the place when it has none), for its
    /// warnings and errors.
    pub fn described(&self) -> String {
        match &self.source {
            Some(at) => format!("{at}: material '{}'", self.name),
            None => format!("material '{}'", self.name),
        }
    }

    /// MTL defaults: grey diffuse, no specular, no emission.
    pub fn named(name: &str) -> Self {
        MaterialDesc {
            name: name.to_string(),
            kd: [0.5; 3],
            ks: [0.0; 3],
            ns: 1.0,
            ni: 1.5,
            ke: [0.0; 3],
            ke_texture: None,
            illum: 2,
            map_kd: None,
            kd_sampling: texture::Sampling::default(),
            kd_procedural: None,
            normal_map: None,
            roughness: None,
            kd_attribute: None,
            opacity: 1.0,
            map_opacity: None,
            emit_one_minus_albedo: false,
            source: None,
            notes: Vec::new(),
            model: None,
            one_sided: false,
        }
    }
}

/// Render settings a scene file may suggest (the CLI overrides them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderDefaults {
    pub res: Option<(u32, u32)>,
    pub spp: Option<u32>,
    pub max_depth: Option<i32>,
    /// Reflections before Russian roulette starts (`--rr-min-depth`).
    pub rr_min_depth: Option<u32>,
    /// The estimator the file asks for (`--integrator`).
    pub integrator: Option<crate::options::IntegratorKind>,
}

/// A scene as plain data, before acceleration structures are built.
#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    pub name: String,
    pub positions: Vec<[Vec3; 3]>,
    pub normals: Vec<Option<[Vec3; 3]>>,
    pub uvs: Vec<Option<[Vec2; 3]>>,
    pub material: Vec<u32>,
    pub materials: Vec<MaterialDesc>,
    pub camera: Option<CameraDesc>,
    pub defaults: RenderDefaults,
    /// Light from far away (at most one).
    pub environment: Option<EnvironmentDesc>,
    pub point_lights: Vec<PointLightDesc>,
    /// Shape groups (triangles stored once, in their own space) and their instances.
    pub groups: Vec<instance::GroupDesc>,
    pub instances: Vec<instance::InstanceDesc>,
    /// Zero-area faces skipped while loading.
    pub skipped_degenerate: usize,
    /// Faces skipped because a coordinate or the face's normal overflows (not finite
    /// in single precision).
    pub skipped_nonfinite: usize,
    pub warnings: Vec<String>,
    /// Mesh attributes (Mitsuba's `vertex_*`, `face_*`) of the triangles that have them.
    pub attributes: Vec<mesh_attr::AttributeDesc>,
}

impl SceneDesc {
    /// Add a triangle unless it has zero area or coordinates that overflow (then it is
    /// counted as such and skipped).
    pub fn push_triangle(
        &mut self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
        material: u32,
    ) {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        let scale = (v[1] - v[0]).length_squared() + (v[2] - v[0]).length_squared();
        if !c.is_finite() || !scale.is_finite() || !c.length_squared().is_finite() {
            self.skipped_nonfinite += 1;
            return;
        }
        if c.length_squared() <= 1e-14 * scale * scale || scale == 0.0 {
            self.skipped_degenerate += 1;
            return;
        }
        self.positions.push(v);
        self.normals.push(n);
        self.uvs.push(uv);
        self.material.push(material);
    }

    pub fn bounds(&self) -> Bounds3 {
        let mut b = Bounds3::EMPTY;
        for t in &self.positions {
            for v in t {
                b.grow(*v);
            }
        }
        if self.instances.is_empty() {
            return b;
        }
        b.union(&instance::instance_bounds(&self.groups, &self.instances))
    }
}

/// What `kalos info` and the stats report about a scene.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SceneInfo {
    pub name: String,
    /// The scene as the user named it: its file's path, or a built-in name ([`load`];
    /// the description's name when built from one).
    pub source: String,
    pub triangles: usize,
    pub materials: usize,
    pub emitters: usize,
    pub skipped_degenerate: usize,
    /// Faces skipped because their coordinates or area are not finite.
    pub skipped_nonfinite: usize,
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    pub load_seconds: f64,
    pub bvh_seconds: f64,
    pub bvh_nodes: usize,
    pub bvh_bytes: usize,
    /// The camera used when the command line gives none, and where it came from.
    pub camera: Option<CameraDesc>,
    pub camera_from: String,
}

/// The immutable scene the estimators render.
pub struct Scene {
    pub tris: Vec<[Vec3; 3]>,
    /// Per triangle: shading normals (none: flat shading).
    pub normals: tri_attr::TriAttr<[Vec3; 3]>,
    /// Per triangle: texture coordinates (none: the barycentrics).
    pub uvs: tri_attr::TriAttr<[Vec2; 3]>,
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    /// Mesh attributes (none: nothing stored), read by materials that vary with them.
    pub attributes: mesh_attr::Attributes,
    pub textures: Vec<Texture>,
    pub bvh: Bvh,
    /// Instances of shape groups (`None`: the scene has none, and `bvh` is all of it).
    pub instances: Option<instance::Instanced>,
    pub lights: Lights,
    pub camera: CameraDesc,
    pub defaults: RenderDefaults,
    pub info: SceneInfo,
    /// Things a user of the scene should know (unsupported materials, no emitter, ...),
    /// whatever the camera; see [`Scene::warnings_for`].
    pub warnings: Vec<String>,
    /// The default camera's warning (placed inside a closed room, or seeing no light),
    /// which holds only for renders that use that camera.
    pub camera_warning: Option<String>,
    /// A hash of the contents of the files the scene was read from ([`load`]; 0 when
    /// built from a description): film parts of one render share it.
    pub content_hash: u64,
    /// Some material lets light through where it is not opaque (see `hit.rs`).
    pub cutouts: bool,
    /// Some material takes its shading normal from a texture (see `texture_normal`).
    pub normal_maps: bool,
}

impl Scene {
    /// Build textures, materials, lights and the BVH from a description.
    pub fn build(mut desc: SceneDesc, load_seconds: f64) -> Result<Scene, String> {
        let mut textures: Vec<Texture> = Vec::new();
        let mut tex_paths: Vec<TexKey> = Vec::new();
        let mut materials = Vec::with_capacity(desc.materials.len());
        let mut material_warnings: Vec<String> = Vec::new();
        let attributes = mesh_attr::Attributes::new(&desc.attributes, desc.positions.len());
        for m in &desc.materials {
            let kd_texture = match (&m.kd_procedural, &m.map_kd) {
                (Some(t), _) => {
                    textures.push(Texture::clone(t));
                    // never matches a file's key: not shared
                    tex_paths.push((PathBuf::new(), t.sampling, None));
                    Some(textures.len() as u32 - 1)
                }
                (None, Some(p)) => Some(texture_index(
                    (p.clone(), m.kd_sampling, None),
                    m,
                    &mut textures,
                    &mut tex_paths,
                )?),
                (None, None) => None,
            };
            let opacity_texture = match &m.map_opacity {
                Some((p, s, from)) => Some(texture_index(
                    (p.clone(), *s, Some(*from)),
                    m,
                    &mut textures,
                    &mut tex_paths,
                )?),
                None => None,
            };
            if !(m.opacity.is_finite() && m.opacity >= 0.0) {
                return Err(format!(
                    "{}: opacity {}: must be a number in [0, 1]",
                    m.described(),
                    m.opacity
                ));
            }
            let (kd, ks, kd_texture, w) = if m.model.is_some() {
                // a surface model reads kd alone (plastic's base): Ks and illum are not its
                let mut only_kd = m.clone();
                only_kd.ks = [0.0; 3];
                only_kd.illum = 2;
                conserve_energy(&only_kd, kd_texture, &mut textures, &mut tex_paths)
            } else {
                conserve_energy(m, kd_texture, &mut textures, &mut tex_paths)
            };
            if let Some(w) = w.filter(|w| !material_warnings.contains(w)) {
                material_warnings.push(w);
            }
            let bsdf = match &m.model {
                Some(model) => bsdf_of_model(model, kd)
                    .map_err(|e| format!("{} ({}): {e}", m.described(), model.plugin()))?,
                None => Bsdf::from_mtl(kd, ks, m.ns, m.ni, m.illum),
            };
            let varying = varying::varying_of(m, &attributes)
                .map_err(|e| format!("{}: {e}", m.described()))?;
            let (emission, emission_table) = if m.emit_one_minus_albedo {
                let t = AlbedoTable::new(&bsdf);
                (t.hemispherical(true), Some(Arc::new(t)))
            } else {
                (m.ke, None)
            };
            let one_sided = m.one_sided && bsdf.is_two_sided();
            materials.push(Material {
                name: m.name.clone(),
                bsdf,
                emission,
                emission_table,
                emission_texture: m.ke_texture.clone(),
                kd_texture,
                one_sided,
                opacity: m.opacity.min(1.0),
                opacity_texture,
                normal_map: m.normal_map.clone(),
                roughness: m.roughness.clone(),
                varying,
            });
        }
        let cutouts = materials.iter().any(Material::is_cutout);
        let normal_maps = materials.iter().any(|m| m.normal_map.is_some());
        let t0 = Instant::now();
        let bounds = desc.bounds();
        let (normals, uvs) = desc.take_tri_attrs();
        let bvh = Bvh::build(&desc.positions);
        let instances = instance::Instanced::build(
            std::mem::take(&mut desc.groups),
            &desc.instances,
            desc.positions.len() as u32,
        )
        .map_err(|e| format!("scene {}: {e}", desc.name))?;
        let bvh_seconds = t0.elapsed().as_secs_f64();
        let uv_of = |i: usize| uvs.get(i).copied();
        let mut lights = Lights::new(&desc.positions, &desc.material, &materials, uv_of)
            .map_err(|e| desc.too_bright(e))?;
        let env = match &desc.environment {
            Some(e) => Some(environment_light(e)?),
            None => None,
        };
        let points = desc
            .point_lights
            .iter()
            .map(|p| {
                if p.position.is_finite()
                    && p.intensity.iter().all(|v| v.is_finite() && *v >= 0.0)
                {
                    Ok(crate::light::PointLight {
                        p: p.position,
                        intensity: p.intensity,
                        shape: point_shape(&p.shape, p.source.as_deref())?,
                    })
                } else {
                    Err(format!(
                        "{}point light: position and intensity must be finite, intensity non-negative",
                        p.source.as_deref().map(|s| format!("{s}: ")).unwrap_or_default()
                    ))
                }
            })
            .collect::<Result<Vec<_>, String>>()?;
        let radius = if bounds.is_empty() {
            1.0
        } else {
            bounds.diagonal() * 0.5
        };
        lights
            .add_distant(points, env, radius)
            .map_err(|e| desc.too_bright(e))?;
        let mut warnings = desc.warnings;
        let mut camera_warning = None;
        let (camera, camera_how) = match desc.camera {
            Some(c) => (c, "scene file".to_string()),
            None => {
                let emits: Vec<bool> = desc
                    .materials
                    .iter()
                    .map(|m| m.ke != [0.0; 3] || m.emit_one_minus_albedo)
                    .collect();
                let mut lights: Vec<Vec3> = desc
                    .positions
                    .iter()
                    .zip(&desc.material)
                    .filter(|(_, &m)| emits[m as usize])
                    .map(|(t, _)| (t[0] + t[1] + t[2]) / 3.0)
                    .collect();
                lights.extend(desc.point_lights.iter().map(|l| l.position));
                let surfaces = camera::Surfaces {
                    material: &desc.material,
                    emits: &emits,
                };
                let d = camera::default_camera(
                    &bvh,
                    &bounds,
                    &lights,
                    desc.environment.is_some(),
                    &surfaces,
                );
                camera_warning = d.warning.map(|w| format!("scene {}: {w}", desc.name));
                (d.desc, d.how)
            }
        };
        warnings.extend(material_warnings);
        if lights.is_dark() {
            warnings.push(format!(
                "scene {} has no emitter: the image will be black",
                desc.name
            ));
        }
        if desc.skipped_degenerate > 0 {
            warnings.push(format!(
                "scene {}: skipped {} zero-area faces",
                desc.name, desc.skipped_degenerate
            ));
        }
        if desc.skipped_nonfinite > 0 {
            warnings.push(format!(
                "scene {}: skipped {} faces whose coordinates or area are not finite (beyond single precision)",
                desc.name, desc.skipped_nonfinite
            ));
        }
        let info = SceneInfo {
            name: desc.name.clone(),
            source: desc.name.clone(),
            triangles: desc.positions.len(),
            materials: materials.len(),
            emitters: lights.len(),
            skipped_degenerate: desc.skipped_degenerate,
            skipped_nonfinite: desc.skipped_nonfinite,
            bounds_min: if bounds.is_empty() {
                [0.0; 3]
            } else {
                bounds.min.into()
            },
            bounds_max: if bounds.is_empty() {
                [0.0; 3]
            } else {
                bounds.max.into()
            },
            load_seconds,
            bvh_seconds,
            bvh_nodes: bvh.node_count(),
            bvh_bytes: bvh.memory_bytes()
                + instances.as_ref().map_or(0, |i| i.accel.memory_bytes()),
            camera: Some(camera),
            camera_from: camera_how,
        };
        Ok(Scene {
            tris: desc.positions,
            normals,
            uvs,
            tri_material: desc.material,
            materials,
            attributes,
            textures,
            bvh,
            instances,
            lights,
            camera,
            defaults: desc.defaults,
            info,
            warnings,
            camera_warning,
            content_hash: 0,
            cutouts,
            normal_maps,
        })
    }

    /// What a user of this scene should be told: [`Scene::warnings`], and the default
    /// camera's warning unless the render gives its own camera (`camera_given`), where it
    /// would describe a camera that is not used.
    pub fn warnings_for(&self, camera_given: bool) -> Vec<String> {
        let camera = self.camera_warning.iter().filter(|_| !camera_given);
        camera.chain(&self.warnings).cloned().collect()
    }

    /// The material of triangle `prim`.
    #[inline]
    pub fn material_of(&self, prim: u32) -> &Material {
        let m = self.tri_material.get(prim as usize).copied();
        &self.materials[m.unwrap_or_else(|| self.instanced_material(prim)) as usize]
    }

    /// The BSDF of material `mat` at a hit seen from direction `wo`: its Kd from its texture
    /// at `hit`'s uv, its roughness there (`Material::roughness`); black on the back of a
    /// one-sided material.
    #[inline]
    pub fn bsdf_at(&self, mat: &Material, hit: &SurfaceHit, wo: Vec3) -> crate::material::Bsdf {
        if mat.one_sided && wo.dot(hit.ng) <= 0.0 {
            return crate::material::Bsdf::Black;
        }
        if let Some(v) = &mat.varying {
            let attr = |slot| self.attributes.eval(slot, hit.prim, hit.b1, hit.b2);
            let tangent = || self.tangent_at(hit, wo, mat.bsdf.is_two_sided());
            return v.bsdf(&mat.bsdf, (hit.uv.x, hit.uv.y), &attr, &tangent);
        }
        let bsdf = match mat.kd_texture {
            Some(t) => mat
                .bsdf
                .clone()
                .with_kd(self.textures[t as usize].lookup(hit.uv.x, hit.uv.y)),
            None => mat.bsdf.clone(),
        };
        match &mat.roughness {
            None => bsdf,
            Some(r) => self.rough_bsdf(r, bsdf, hit, wo),
        }
    }
}

/// The BSDF of a Mitsuba surface model; `kd` is the diffuse reflectance (plastic's base).
pub fn bsdf_of_model(model: &SurfaceModel, kd: [f32; 3]) -> Result<Bsdf, String> {
    use crate::material::{Conductor, Dielectric, Plastic, RoughDielectric, ThinDielectric};
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite() && *x >= 0.0);
    let alpha_ok = |a: f32| a.is_finite() && (0.0..=4.0).contains(&a);
    let eta_ok = |e: f32| e.is_finite() && e > 0.0 && e != 1.0;
    Ok(match *model {
        SurfaceModel::Conductor {
            eta,
            k,
            specular,
            alpha,
            distribution,
        } => {
            if !(finite(&eta) && finite(&k) && finite(&specular)) {
                return Err(
                    "eta, k and specular_reflectance must be finite and non-negative".into(),
                );
            }
            if !alpha_ok(alpha) {
                return Err(format!("alpha {alpha}: must be in [0, 4]"));
            }
            Bsdf::Conductor(Conductor::new(eta, k, specular, alpha, distribution))
        }
        SurfaceModel::Plastic {
            eta,
            specular,
            alpha,
            distribution,
            nonlinear,
        } => {
            if !eta_ok(eta) {
                return Err(format!(
                    "eta {eta}: the indices inside and outside must be positive and differ"
                ));
            }
            if !(finite(&specular) && finite(&kd)) {
                return Err(
                    "diffuse and specular reflectance must be finite and non-negative".into(),
                );
            }
            if !alpha_ok(alpha) {
                return Err(format!("alpha {alpha}: must be in [0, 4]"));
            }
            Bsdf::Plastic(Plastic::new(
                kd,
                specular,
                eta,
                alpha,
                distribution,
                nonlinear,
            ))
        }
        SurfaceModel::Dielectric {
            eta,
            alpha,
            distribution,
            tint,
        } => {
            if !eta_ok(eta) {
                return Err(format!(
                    "eta {eta}: the indices inside and outside must be positive and differ"
                ));
            }
            if !alpha_ok(alpha) {
                return Err(format!("alpha {alpha}: must be in [0, 4]"));
            }
            if !(finite(&tint.reflect) && finite(&tint.transmit)) {
                return Err(
                    "specular_reflectance and specular_transmittance must be finite and non-negative"
                        .into(),
                );
            }
            if alpha > 0.0 {
                Bsdf::RoughDielectric(RoughDielectric {
                    eta,
                    alpha,
                    dist: distribution,
                    tint,
                })
            } else {
                Bsdf::Dielectric(Dielectric { eta, tint })
            }
        }
        SurfaceModel::ThinDielectric { eta, tint } => {
            if !(eta.is_finite() && eta > 0.0) {
                return Err(format!("eta {eta}: must be positive"));
            }
            if !(finite(&tint.reflect) && finite(&tint.transmit)) {
                return Err(
                    "specular_reflectance and specular_transmittance must be finite and non-negative"
                        .into(),
                );
            }
            Bsdf::ThinDielectric(ThinDielectric { eta, tint })
        }
        SurfaceModel::Blend {
            ref weight,
            ref bsdfs,
        } => varying::blend_bsdf(weight, bsdfs)?,
        SurfaceModel::Principled(ref p) => varying::principled_bsdf(p)?,
    })
}

/// The environment light of a description: its map read through `image_io` (EXR, HDR or
/// PNG), errors naming the file.
fn environment_light(e: &EnvironmentDesc) -> Result<crate::light::EnvLight, String> {
    let at = e
        .source
        .as_deref()
        .map(|s| format!("{s}: "))
        .unwrap_or_default();
    let img = match &e.map {
        Some(p) => Some(
            crate::image_io::read_image(p).map_err(|err| format!("{at}environment map: {err}"))?,
        ),
        None => None,
    };
    crate::light::EnvLight::new(e.radiance, img.as_ref(), e.to_world).map_err(|err| match &e.map {
        Some(p) => format!("{at}environment map {}: {err}", p.display()),
        None => format!("{at}environment: {err}"),
    })
}

/// A point light's shape for rendering: a spot's texture loaded, its frame inverted.
fn point_shape(
    shape: &PointLightShape,
    source: Option<&str>,
) -> Result<crate::light::PointShape, String> {
    use crate::light::{PointShape, Spot};
    let at = source.map(|s| format!("{s}: ")).unwrap_or_default();
    Ok(match shape {
        PointLightShape::Isotropic => PointShape::Isotropic,
        PointLightShape::Directional(d) => {
            let d = d.normalize_or_zero();
            if d == Vec3::ZERO || !d.is_finite() {
                return Err(format!("{at}directional light: its direction is zero"));
            }
            PointShape::Directional(d)
        }
        PointLightShape::Spot {
            to_world,
            cutoff,
            beam_width,
            texture,
            frustum,
        } => {
            let ok = |a: f32| a > 0.0 && a <= 90.0;
            if !(ok(*cutoff) && ok(*beam_width)) || to_world.determinant().abs() < 1e-12 {
                return Err(format!(
                    "{at}spot light: cutoff_angle {cutoff} and beam_width {beam_width} must be in (0, 90] degrees, its to_world invertible"
                ));
            }
            let texture = match texture {
                Some(p) => Some(std::sync::Arc::new(
                    Texture::load(p).map_err(|e| format!("{at}spot light: {e}"))?,
                )),
                None => None,
            };
            PointShape::Spot(Spot {
                to_local: to_world.inverse(),
                cutoff: cutoff.to_radians(),
                beam_width: beam_width.min(*cutoff).to_radians(),
                texture,
                frustum: *frustum,
            })
        }
    })
}

/// A camera on +z looking at the centre of the bounds (see `camera::framing_camera`).
pub fn default_camera(b: &Bounds3) -> CameraDesc {
    camera::framing_camera(b)
}

/// Load a scene named on the command line: a built-in name, an `.obj`, a `.toml` or a
/// Mitsuba `.xml` file.
pub fn load(spec: &str) -> Result<Scene, String> {
    load_with(spec, &[])
}

/// [`load`] with Mitsuba's defines (`-D key=value`: each replaces the scene file's
/// `<default>` of that name); only Mitsuba .xml scenes take them.
pub fn load_with(spec: &str, defines: &[(String, String)]) -> Result<Scene, String> {
    let t0 = Instant::now();
    let (scene, hash) = crate::input::content_hash_of_reads(|| {
        let desc = load_desc_with(spec, defines)?;
        Scene::build(desc, t0.elapsed().as_secs_f64())
    });
    let mut scene = scene?;
    scene.info.source = spec.to_string();
    // a built-in scene reads no file: its name is its content
    scene.content_hash = hash.unwrap_or_else(|| crate::input::CRC64.checksum(spec.as_bytes()));
    Ok(scene)
}

/// Read a scene description without building it.
pub fn load_desc(spec: &str) -> Result<SceneDesc, String> {
    load_desc_with(spec, &[])
}

/// [`load_desc`] with defines (see [`load_with`]).
pub fn load_desc_with(spec: &str, defines: &[(String, String)]) -> Result<SceneDesc, String> {
    let is_xml = Path::new(spec)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    if let (Some((k, v)), false) = (defines.first(), is_xml) {
        return Err(format!(
            "-D {k}={v}: {spec}: only Mitsuba .xml scenes take defines"
        ));
    }
    if is_xml {
        return mitsuba::load_with(Path::new(spec), defines);
    }
    if let Some(desc) = builtin::load(spec)? {
        return Ok(desc);
    }
    let path = Path::new(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("obj") => {
            // read through `input`: a directory, FIFO or device is named as such
            let mut desc = SceneDesc {
                name: path
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or(spec)
                    .to_string(),
                ..Default::default()
            };
            obj::load_obj_file(path, glam::Mat4::IDENTITY, &mut desc)?;
            Ok(desc)
        }
        Some("toml") => toml_scene::load(path),
        Some("xml") => mitsuba::load(path),
        _ => Err(not_a_scene(spec)),
    }
}

/// The scene files [`load`] reads, by extension (lower case).
pub const FILE_EXTENSIONS: [&str; 3] = ["obj", "toml", "xml"];

/// Whether `spec` names a built-in scene or a file of a kind [`load`] reads (not whether
/// the file exists).
pub fn is_scene_spec(spec: &str) -> bool {
    builtin::NAMES.contains(&spec)
        || Path::new(spec)
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| FILE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

/// The error for a `spec` that is neither a built-in scene nor a scene file.
pub fn not_a_scene(spec: &str) -> String {
    format!(
        "{spec}: not a built-in scene ({}) nor an .obj, .toml or Mitsuba .xml file",
        builtin::NAMES.join(", ")
    )
}

/// What identifies a loaded texture: its file, its lookup, and for a scalar opacity map
/// where its value comes from (a file used as colour and as opacity is two textures).
type TexKey = (PathBuf, texture::Sampling, Option<texture::OpacityFrom>);

/// The index of the texture `key` asks for, loaded the first time (errors name the
/// material `m` that asks for it).
fn texture_index(
    key: TexKey,
    m: &MaterialDesc,
    textures: &mut Vec<Texture>,
    keys: &mut Vec<TexKey>,
) -> Result<u32, String> {
    if let Some(i) = keys.iter().position(|k| *k == key) {
        return Ok(i as u32);
    }
    let mut t = match key.2 {
        None => Texture::load(&key.0),
        Some(from) => Texture::load_opacity(&key.0, from),
    }
    .map_err(|e| format!("{}: texture {e}", m.described()))?;
    t.sampling = key.1;
    textures.push(t);
    keys.push(key);
    Ok(textures.len() as u32 - 1)
}

/// Kd + Ks of a material brought to at most 1 on every band ([`mtl::energy_scale`]; a
/// textured Kd counts as its mean texel and is scaled by a scaled copy of the texture),
/// and the material's one warning: its notes from loading plus the scaling, if any.
/// Returns (Kd, Ks, the Kd texture, the warning).
fn conserve_energy(
    m: &MaterialDesc,
    kd_texture: Option<u32>,
    textures: &mut Vec<Texture>,
    tex_paths: &mut Vec<TexKey>,
) -> ([f32; 3], [f32; 3], Option<u32>, Option<String>) {
    let mut notes = m.notes.clone();
    let (mut kd, mut ks, mut tex) = (m.kd, m.ks, kd_texture);
    let mean = kd_texture.map(|t| textures[t as usize].mean());
    if let Some((s, max)) = mtl::energy_scale(m, mean) {
        let f = |c: [f32; 3]| format!("{} {} {}", c[0], c[1], c[2]);
        let what = match (m.illum, mean) {
            (5, _) => format!("mirror Ks {}", f(m.ks)),
            (_, Some(t)) => format!("Kd (texture mean) {} + Ks {}", f(t), f(m.ks)),
            _ => format!("Kd {} + Ks {}", f(m.kd), f(m.ks)),
        };
        notes.push(format!(
            "{what} reflects up to {max} on a band, more than it receives: Kd and Ks scaled by {s} to conserve energy"
        ));
        kd = kd.map(|v| v * s);
        ks = ks.map(|v| v * s);
        if let Some(t) = kd_texture {
            let mut scaled = textures[t as usize].clone();
            for texel in &mut scaled.texels {
                *texel = texel.map(|v| v * s);
            }
            textures.push(scaled);
            // never matches a map_Kd path: not shared
            tex_paths.push((PathBuf::new(), texture::Sampling::default(), None));
            tex = Some(textures.len() as u32 - 1);
        }
    }
    let warning = (!notes.is_empty()).then(|| format!("{}: {}", m.described(), notes.join("; ")));
    (kd, ks, tex, warning)
}
