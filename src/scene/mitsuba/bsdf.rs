//! Mitsuba's BSDF plugins as kalos materials (`MaterialDesc` with a `SurfaceModel`).

use super::*;
use crate::material::conductor::fresnel_conductor;
use crate::material::dielectric::{fresnel_dielectric, Tint};
use crate::texture::normal::NormalMap;
use crate::texture::{OpacityFrom, Texture};

/// A normalized-Phong exponent with about the spread of a GGX lobe of roughness alpha.
pub(super) fn phong_exponent(alpha: f32) -> f32 {
    (2.0 / (alpha * alpha).max(1e-4) - 2.0).clamp(1.0, 10000.0)
}

impl<'a> Loader<'a> {
    pub(super) fn ior(&self, el: &'a El, name: &str, default: &str) -> R<f32> {
        let Some(p) = self.prop(el, name) else {
            return Ok(IORS.iter().find(|(n, _)| *n == default).unwrap().1);
        };
        let v = self.value(p)?;
        if p.tag == "string" {
            return IORS
                .iter()
                .find(|(n, _)| n.eq_ignore_ascii_case(v.trim()))
                .map(|(_, x)| *x)
                .ok_or_else(|| {
                    format!(
                        "{}: {name} \"{v}\": not a number nor one of Mitsuba's named indices ({})",
                        p.at,
                        IORS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                    )
                });
        }
        let x: f32 = v
            .trim()
            .parse()
            .ok()
            .filter(|x: &f32| x.is_finite() && *x > 0.0)
            .ok_or_else(|| format!("{}: {name} \"{v}\": not a positive number", p.at))?;
        Ok(x)
    }

    /// Roughness and microfacet distribution of a rough plugin (alpha, or alpha_u / alpha_v:
    /// their geometric mean; `distribution` Beckmann unless it says ggx, as in Mitsuba).
    pub(super) fn alpha(&self, el: &'a El, plugin: &str) -> R<(f32, Distribution)> {
        let dist = match self.string(el, "distribution")? {
            None => Distribution::Beckmann,
            Some(d) => Distribution::from_name(d.trim()).ok_or_else(|| {
                format!(
                    "{}: {plugin} distribution \"{d}\": must be \"beckmann\" or \"ggx\"",
                    el.at
                )
            })?,
        };
        // Mitsuba's switch between visible-normal and plain D sampling: the same image
        // (kalos always samples visible normals)
        let _ = self.boolean(el, "sample_visible")?;
        let a = self.float(el, "alpha")?;
        let (u, v) = (self.float(el, "alpha_u")?, self.float(el, "alpha_v")?);
        let alpha = match (a, u, v) {
            // Mitsuba refuses both forms at once, and one of alpha_u, alpha_v alone
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                return Err(format!(
                    "{}: {plugin}: give either alpha or alpha_u and alpha_v, not both",
                    el.at
                ))
            }
            (None, Some(_), None) | (None, None, Some(_)) => {
                return Err(format!(
                    "{}: {plugin}: alpha_u and alpha_v must be given together",
                    el.at
                ))
            }
            (Some(a), None, None) => a,
            (None, Some(u), Some(v)) => {
                // (a rough conductor renders it: `conductor_roughness`)
                if u != v && plugin != "roughconductor" {
                    self.warn(
                        "anisotropic",
                        format!(
                            "{}: anisotropic roughness (alpha_u {u}, alpha_v {v}): rendered isotropic with alpha {}",
                            el.at,
                            (u * v).sqrt()
                        ),
                    );
                }
                (u * v).sqrt()
            }
            _ => 0.1,
        };
        if !(0.0..=10.0).contains(&alpha) {
            return Err(format!(
                "{}: {plugin} alpha {alpha}: must be in [0, 10]",
                el.at
            ));
        }
        Ok((alpha.max(1e-4), dist))
    }

    /// Set `kd`/`map_kd` from a diffuse reflectance.
    pub(super) fn set_diffuse(&self, m: &mut MaterialDesc, c: Option<Color>, default: f32) {
        match c {
            None => m.kd = [default; 3],
            Some(Color::Rgb(v)) => m.kd = v,
            Some(Color::Bitmap(p, sampling)) => {
                m.kd = [1.0; 3];
                m.map_kd = Some(p);
                m.kd_sampling = sampling;
            }
            Some(Color::Procedural(t)) => {
                m.kd = [1.0; 3];
                m.kd_procedural = Some(std::sync::Arc::new(t));
            }
            Some(Color::Attribute(a)) => {
                m.kd = [1.0; 3];
                m.kd_attribute = Some(a);
            }
        }
    }

    /// A BSDF element (inline or referenced) as a material description.
    pub(super) fn bsdf(&self, el: &'a El) -> R<MaterialDesc> {
        let target = self.resolve(el)?;
        self.building(el, target, || self.bsdf_of(target))
    }

    fn bsdf_of(&self, el: &'a El) -> R<MaterialDesc> {
        if el.tag != "bsdf" {
            return Err(format!(
                "{}: <{}> where a <bsdf> was expected",
                el.at, el.tag
            ));
        }
        let kind = el.kind();
        if !known_plugin("bsdf", kind) {
            return Err(format!("{}: unknown bsdf plugin '{kind}'", el.at));
        }
        let name = el
            .attr("id")
            .map(str::to_string)
            .unwrap_or_else(|| format!("{kind}@{}", el.at.rsplit(':').next().unwrap_or("")));
        let mut m = MaterialDesc::named(&name);
        m.source = Some(el.at.clone());
        let nested = || -> R<Option<&'a El>> {
            let mut it = el.children.iter().filter(|c| {
                c.tag == "bsdf"
                    || (c.tag == "ref" && self.resolve(c).map(|r| r.tag == "bsdf").unwrap_or(false))
            });
            let first = it.next();
            if let Some(f) = first {
                f.used.set(true);
            }
            for extra in it {
                extra.used.set(true);
                if kind == "twosided" {
                    self.warn(
                        "twosided two bsdfs",
                        format!(
                            "{}: twosided with a different bsdf per side: kalos renders the first on both sides",
                            extra.at
                        ),
                    );
                }
            }
            Ok(first)
        };
        match kind {
            "diffuse" | "roughdiffuse" => {
                let c = self.color(el, "reflectance", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                if kind == "roughdiffuse" {
                    self.mark_all(el);
                    self.warn(
                        "bsdf roughdiffuse",
                        format!(
                            "{}: roughdiffuse (Oren-Nayar) is rendered as Lambertian diffuse",
                            el.at
                        ),
                    );
                }
            }
            "conductor" | "roughconductor" => {
                let (alpha, distribution) = if kind == "roughconductor" {
                    self.alpha(el, kind)?
                } else {
                    (0.0, Distribution::default())
                };
                let material = self.string(el, "material")?;
                let (mut eta, mut k) = match &material {
                    Some(n) => {
                        let find = |n: &str| METALS.iter().find(|(m, _, _)| *m == n);
                        // Mitsuba's documented list (and 0.6's files) also name Palik's
                        // measurements, "Cu_palik", "Ni_palik": the element's data stands in
                        let palik = n.strip_suffix("_palik").and_then(find);
                        let f = find(n).or(palik).ok_or_else(|| {
                            format!(
                                "{}: conductor material \"{n}\": not one of Mitsuba's named conductors ({})",
                                el.at,
                                METALS.iter().map(|(m, _, _)| *m).collect::<Vec<_>>().join(", ")
                            )
                        })?;
                        if find(n).is_none() {
                            self.warn(
                                &format!("palik {n}"),
                                format!(
                                    "{}: conductor material \"{n}\": rendered with \"{}\" (Palik's tables are not bundled; the two differ by a few percent)",
                                    el.at, f.0
                                ),
                            );
                        }
                        (f.1, f.2)
                    }
                    None => ([0.0; 3], [1.0; 3]),
                };
                if let Some(e) = self.constant(el, "eta", Use::Ior, kind)? {
                    eta = e;
                }
                if let Some(x) = self.constant(el, "k", Use::Ior, kind)? {
                    k = x;
                }
                let specular = self
                    .constant(el, "specular_reflectance", Use::Reflectance, kind)?
                    .unwrap_or([1.0; 3]);
                let r0: [f32; 3] =
                    [0, 1, 2].map(|i| fresnel_conductor(1.0, eta[i], k[i]) * specular[i]);
                m.kd = [0.0; 3];
                m.ks = r0;
                if alpha == 0.0 {
                    m.illum = 5;
                } else {
                    m.illum = 2;
                    m.ns = phong_exponent(alpha);
                }
                m.model = Some(SurfaceModel::Conductor {
                    eta,
                    k,
                    specular,
                    alpha: if kind == "conductor" { 0.0 } else { alpha },
                    distribution,
                });
                if kind == "roughconductor" {
                    m.roughness = self.conductor_roughness(el)?;
                }
            }
            "plastic" | "roughplastic" => {
                let (alpha, distribution) = if kind == "roughplastic" {
                    self.alpha(el, kind)?
                } else {
                    (0.0, Distribution::default())
                };
                let eta =
                    self.ior(el, "int_ior", "polypropylene")? / self.ior(el, "ext_ior", "air")?;
                let c = self.color(el, "diffuse_reflectance", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                let specular = self
                    .constant(el, "specular_reflectance", Use::Reflectance, kind)?
                    .unwrap_or([1.0; 3]);
                let nonlinear = self.boolean(el, "nonlinear")?.unwrap_or(false);
                // kd stays the diffuse reflectance: the Plastic model applies the coat's
                // transmittance and internal reflections (Mitsuba's diffuse term)
                let f0 = fresnel_dielectric(1.0, eta).0;
                m.ks = specular.map(|s| s * f0);
                m.ns = if alpha == 0.0 {
                    10000.0
                } else {
                    phong_exponent(alpha)
                };
                m.model = Some(SurfaceModel::Plastic {
                    eta,
                    specular,
                    alpha: if kind == "plastic" { 0.0 } else { alpha },
                    distribution,
                    nonlinear,
                });
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                let (alpha, distribution) = if kind == "roughdielectric" {
                    self.alpha(el, kind)?
                } else {
                    (0.0, Distribution::default())
                };
                let eta = self.ior(el, "int_ior", "bk7")? / self.ior(el, "ext_ior", "air")?;
                let mut tint = Tint::NONE;
                for (k, v) in [
                    ("specular_reflectance", &mut tint.reflect),
                    ("specular_transmittance", &mut tint.transmit),
                ] {
                    if let Some(c) = self.constant(el, k, Use::Reflectance, kind)? {
                        *v = c;
                    }
                }
                m.kd = [0.0; 3];
                m.illum = 7;
                if kind == "thindielectric" {
                    // no refraction of the direction: an index of 1 (see-through) is closest
                    m.ni = 1.0;
                    m.model = Some(SurfaceModel::ThinDielectric { eta, tint });
                } else {
                    m.ni = eta;
                    m.model = Some(SurfaceModel::Dielectric {
                        eta,
                        alpha,
                        distribution,
                        tint,
                    });
                }
            }
            "phong" => {
                let c = self.color(el, "diffuse_reflectance", Use::Reflectance)?;
                self.set_diffuse(&mut m, c, 0.5);
                m.ks = self
                    .constant(el, "specular_reflectance", Use::Reflectance, kind)?
                    .unwrap_or([0.2; 3]);
                m.ns = self.float(el, "exponent")?.unwrap_or(30.0);
            }
            "twosided" | "mask" | "bumpmap" | "normalmap" => {
                let inner =
                    nested()?.ok_or_else(|| format!("{}: {kind} needs a nested <bsdf>", el.at))?;
                let mut inner_m = self.bsdf(inner)?;
                match kind {
                    "mask" => {
                        // a cut-out: the opacity's share of light meets the nested BSDF,
                        // the rest passes (Mitsuba's default opacity 0.5)
                        match self.color(el, "opacity", Use::Reflectance)? {
                            None => inner_m.opacity *= 0.5,
                            Some(Color::Rgb(v)) => inner_m.opacity *= (v[0] + v[1] + v[2]) / 3.0,
                            Some(Color::Bitmap(p, sampling)) => {
                                inner_m.map_opacity = Some((p, sampling, OpacityFrom::Luminance));
                            }
                            Some(c @ (Color::Procedural(_) | Color::Attribute(_))) => {
                                self.warn(
                                    "mask procedural",
                                    format!("{}: a checkerboard as mask opacity is not supported: rendered with its mean", el.at),
                                );
                                let v = self.mean_rgb(c, &el.at)?;
                                inner_m.opacity *= (v[0] + v[1] + v[2]) / 3.0;
                            }
                        }
                    }
                    "bumpmap" | "normalmap" => {
                        inner_m.normal_map = Some(self.normal_map(el, kind)?)
                    }
                    _ => {}
                }
                if el.attr("id").is_some() {
                    inner_m.name = name;
                }
                if kind == "twosided" {
                    inner_m.one_sided = false;
                }
                self.unused(el, &format!("bsdf '{kind}'"));
                return Ok(inner_m);
            }
            "blendbsdf" => return self.blend(el, name),
            "mixturebsdf" => {
                let inner = nested()?;
                self.mark_all(el);
                self.warn(
                    &format!("bsdf {kind}"),
                    format!(
                        "{}: {kind} is not supported: rendered as its first bsdf",
                        el.at
                    ),
                );
                if let Some(i) = inner {
                    let mut im = self.bsdf(i)?;
                    if el.attr("id").is_some() {
                        im.name = name;
                    }
                    return Ok(im);
                }
            }
            "principled" => self.principled(el, &mut m, false)?,
            "principledthin" => self.principled(el, &mut m, true)?,
            "null" => {
                m.kd = [0.0; 3];
                m.notes
                    .push("null bsdf: kalos renders it black (it should let light through)".into());
            }
            k => {
                self.mark_all(el);
                self.warn(
                    &format!("bsdf {k}"),
                    format!(
                        "{}: unsupported bsdf '{k}': rendered as diffuse grey (0.5)",
                        el.at
                    ),
                );
            }
        }
        // Mitsuba's BSDFs reflect on the front only, unless wrapped in `twosided` (above);
        // a thin slab is symmetric
        m.one_sided = !matches!(kind, "thindielectric" | "null");
        self.unused(el, &format!("bsdf '{kind}'"));
        Ok(m)
    }

    /// The texture of a `normalmap` or `bumpmap` (its one texture child, whatever its
    /// name, as Mitsuba takes it): a raw bitmap, or a constant.
    fn normal_map(&self, el: &'a El, kind: &str) -> R<NormalMap> {
        let mut textures = el.children.iter().filter(|c| {
            c.tag == "texture"
                || (c.tag == "ref" && self.resolve(c).map(|r| r.tag == "texture").unwrap_or(false))
        });
        let p = textures
            .next()
            .ok_or_else(|| format!("{}: {kind} needs a <texture>", el.at))?;
        if let Some(extra) = textures.next() {
            return Err(format!(
                "{}: {kind} takes one texture, a second is at {}",
                el.at, extra.at
            ));
        }
        p.used.set(true);
        let t = self.resolve(p)?;
        let texture = match t.kind() {
            "bitmap" => {
                let (path, sampling, raw) = self.bitmap(t, true)?;
                let mut tex = Texture::load_as(&path, raw)
                    .map_err(|e| format!("{}: {kind} texture: {e}", t.at))?;
                tex.sampling = sampling;
                tex
            }
            _ => {
                // a constant (Mitsuba's rawconstant, rgb, ...): one texel, not decoded
                let v = match t.kind() {
                    "rawconstant" => {
                        let v = self
                            .prop(t, "value")
                            .ok_or_else(|| format!("{}: rawconstant needs a value", t.at))?;
                        let c = self.vec3_attr(v, "value")?;
                        self.unused(t, "texture 'rawconstant'");
                        [c.x, c.y, c.z]
                    }
                    _ => match self.color_of(p, Use::Unbounded)? {
                        Color::Rgb(v) => v,
                        c => self.mean_rgb(c, &t.at)?,
                    },
                };
                Texture {
                    width: 1,
                    height: 1,
                    texels: vec![v],
                    sampling: Default::default(),
                }
            }
        };
        Ok(match kind {
            "normalmap" => NormalMap::Normals(std::sync::Arc::new(texture)),
            _ => {
                let scale = self.float(el, "scale")?.unwrap_or(1.0);
                // a scalar height: the luminance, as Mitsuba's eval_1 of a colour bitmap
                let mut heights = texture;
                for t in &mut heights.texels {
                    *t = [0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2]; 3];
                }
                NormalMap::Bumps {
                    heights: std::sync::Arc::new(heights),
                    scale,
                }
            }
        })
    }

    /// The material index of a BSDF element (a referenced one is built once).
    pub(super) fn material(&mut self, el: &'a El) -> R<u32> {
        let target = self.resolve(el)?;
        let key = target as *const El;
        if let Some(&i) = self.materials.get(&key) {
            return Ok(i);
        }
        let m = self.bsdf(target)?;
        self.desc.materials.push(m);
        let i = self.desc.materials.len() as u32 - 1;
        self.materials.insert(key, i);
        Ok(i)
    }

    pub(super) fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default_material {
            return i;
        }
        // Mitsuba's default: a one-sided diffuse of reflectance 0.5
        let mut m = MaterialDesc::named("mitsuba-default-diffuse");
        m.one_sided = true;
        self.desc.materials.push(m);
        let i = self.desc.materials.len() as u32 - 1;
        self.default_material = Some(i);
        i
    }
}
