//! Signed-distance grids in a scene (Mitsuba's `sdfgrid`, traced by `accel::SdfShapes`):
//! each lives in a shape group and is placed by its instances (a grid outside a group is
//! read as a group of its own placed once). Their hits are numbered from
//! `accel::SDF_FIRST_PRIM`, past every triangle, and have no texture coordinates: as in
//! Mitsuba, uv is (0, 0) (kalos' (0, 1)).

use super::{GroupDesc, InstanceDesc};
use crate::accel::{Hit, SdfGrid, SdfShapes, SDF_FIRST_PRIM};
use crate::math::{Bounds3, Vec2, Vec3};
use crate::scene::hit::SurfaceHit;
use crate::scene::Scene;
use glam::{Affine3A, Mat4};
use std::sync::Arc;

/// A grid in its group: its distances, its `to_world` within the group, whether its
/// shading normals are Mitsuba's `smooth` ones (else the geometric ones), its material.
#[derive(Clone, Debug)]
pub struct SdfDesc {
    pub grid: Arc<SdfGrid>,
    pub to_world: Mat4,
    pub smooth: bool,
    pub material: u32,
}

/// The scene's placed grids and the material of each.
pub(super) struct SdfPart {
    pub(super) accel: SdfShapes,
    material: Vec<u32>,
}

impl SdfPart {
    /// The grids of `groups` as `instances` place them (`None` when there are none).
    pub(super) fn build(
        groups: &[GroupDesc],
        instances: &[InstanceDesc],
    ) -> Result<Option<SdfPart>, String> {
        let mut grids = Vec::new();
        let mut material = Vec::new();
        for i in instances {
            for s in groups.get(i.group as usize).map_or(&[][..], |g| &g.sdfs) {
                grids.push((s.grid.clone(), i.to_world * s.to_world, s.smooth));
                material.push(s.material);
            }
        }
        if grids.is_empty() {
            return Ok(None);
        }
        Ok(Some(SdfPart {
            accel: SdfShapes::build(&grids)?,
            material,
        }))
    }
}

/// Whether hit number `prim` is a grid's.
#[inline(always)]
pub(super) fn is_sdf(prim: u32) -> bool {
    prim >= SDF_FIRST_PRIM
}

/// The group-space bounds of `g`'s grids.
pub(super) fn group_bounds(g: &GroupDesc) -> Bounds3 {
    let unit = Bounds3 {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    g.sdfs.iter().fold(Bounds3::EMPTY, |b, s| {
        b.union(&crate::accel::transformed_bounds(
            &unit,
            &Affine3A::from_mat4(s.to_world),
        ))
    })
}

impl Scene {
    fn sdf_part(&self) -> &SdfPart {
        self.instances
            .as_ref()
            .and_then(|i| i.sdf.as_ref())
            .expect("grid hit numbers come from the grids")
    }

    /// The material index of a grid's hit.
    pub(super) fn sdf_material(&self, prim: u32) -> u32 {
        let s = self.sdf_part();
        let i = s.accel.locate(prim).expect("grid hit numbers are located");
        s.material[i]
    }

    /// [`Scene::surface_hit`] of a grid's hit: the gradient as the geometric normal, the
    /// shading normal turned to its side.
    pub(super) fn sdf_hit(&self, h: Hit) -> SurfaceHit {
        let ng = h.n.try_normalize().unwrap_or(Vec3::Z);
        let ns = self.sdf_part().accel.shading_normal(&h);
        let ns = if ns.dot(ng) < 0.0 { -ns } else { ns };
        SurfaceHit {
            p: h.p,
            ng,
            ns,
            uv: Vec2::new(0.0, 1.0),
            b1: 0.0,
            b2: 0.0,
            prim: h.prim,
            t: h.t,
        }
    }
}
