//! Materials that vary over a surface, from their descriptions: mesh attributes resolved
//! to the scene's slots, `blendbsdf`'s nested BSDFs built and shared.

use super::mesh_attr::Attributes;
use super::{bsdf_of_model, MaterialDesc, SurfaceModel};
use crate::material::varying::{PrincipledParams, Varying};
use crate::material::{Blend, Bsdf};
use crate::texture::mesh_attribute::{luminance, Param};
use std::sync::Arc;

/// `p` with its mesh attribute's slot in `attrs`; an error if no mesh has it.
fn resolve(p: &Param, attrs: &Attributes) -> Result<Param, String> {
    match p {
        Param::Attribute(a) => {
            let slot = attrs.slot(&a.name).ok_or_else(|| {
                format!(
                    "mesh_attribute \"{}\": no mesh of the scene has this attribute{}",
                    a.name,
                    if attrs.names.is_empty() {
                        String::new()
                    } else {
                        format!(" (they have {})", attrs.names.join(", "))
                    }
                )
            })?;
            let mut a = a.clone();
            a.slot = slot;
            Ok(Param::Attribute(a))
        }
        p => Ok(p.clone()),
    }
}

/// What of material `m` varies over its surface beyond `kd_texture` (None: nothing).
pub(super) fn varying_of(
    m: &MaterialDesc,
    attrs: &Attributes,
) -> Result<Option<Arc<Varying>>, String> {
    let v = match (&m.model, &m.kd_attribute) {
        (Some(SurfaceModel::Blend { weight, .. }), _) if !weight.is_const() => {
            Varying::BlendWeight(resolve(weight, attrs)?)
        }
        (Some(SurfaceModel::Principled(p)), _) if !p.is_const() || p.is_anisotropic() => {
            Varying::Principled(Box::new(p.try_map(|x| resolve(x, attrs))?))
        }
        (_, Some(a)) => Varying::Kd(resolve(&Param::Attribute(a.clone()), attrs)?),
        _ => return Ok(None),
    };
    Ok(Some(Arc::new(v)))
}

/// The BSDF of a nested material (a `blendbsdf`'s): its constants (the reader has put
/// textures' means in them).
fn nested_bsdf(d: &MaterialDesc) -> Result<Bsdf, String> {
    match &d.model {
        Some(model) => bsdf_of_model(model, d.kd),
        None => Ok(Bsdf::from_mtl(d.kd, d.ks, d.ns, d.ni, d.illum)),
    }
}

/// A `blendbsdf` with its weight's mean (a varying weight is looked up per hit).
pub(super) fn blend_bsdf(weight: &Param, bsdfs: &[MaterialDesc; 2]) -> Result<Bsdf, String> {
    let pair = [nested_bsdf(&bsdfs[0])?, nested_bsdf(&bsdfs[1])?];
    let w = luminance(weight.mean());
    if !w.is_finite() {
        return Err(format!("weight {w}: must be a number in [0, 1]"));
    }
    Ok(Bsdf::Blend(Blend::new(Blend::intern(pair), w)))
}

/// A `principled` material with its textures' means (varying ones are looked up per hit).
pub(super) fn principled_bsdf(p: &PrincipledParams) -> Result<Bsdf, String> {
    if !(p.eta.is_finite() && p.eta > 0.0) {
        return Err(format!("eta {}: must be a positive number", p.eta));
    }
    if !p.rates.iter().all(|r| r.is_finite() && *r >= 0.0) {
        return Err("sampling rates must be finite and non-negative".into());
    }
    Ok(p.mean())
}
