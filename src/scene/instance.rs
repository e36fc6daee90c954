//! Instanced geometry: shape groups (triangles in their own space, stored once) and the
//! instances placing them (Mitsuba's `shapegroup` and `instance`), the scene-side half of
//! [`crate::accel::Instances`].
//!
//! An instanced triangle's number (`prim`) comes after the scene's own triangles (see
//! `Instances::locate`): [`Scene::material_of`] and [`Scene::surface_hit`] look numbers
//! past `Scene::tris` up here. Instanced triangles never emit (Mitsuba refuses emitters in
//! a shape group, and so does the loader), so the lights, the radiosity mesh and the
//! roulette's escape estimate, which read the scene's own triangles, see them only as
//! occluders of the rays they trace through the scene.

use super::hit::SurfaceHit;
use super::tri_attr::TriAttr;
use super::Scene;
use crate::accel::{Hit, Instances};
use crate::math::{Bounds3, Ray, Vec2, Vec3};
use glam::Mat4;

pub mod sdf;

/// A shape group's triangles, in the group's space.
#[derive(Clone, Debug, Default)]
pub struct GroupDesc {
    /// Where the group is defined (for messages).
    pub name: String,
    pub positions: Vec<[Vec3; 3]>,
    pub normals: Vec<Option<[Vec3; 3]>>,
    pub uvs: Vec<Option<[Vec2; 3]>>,
    pub material: Vec<u32>,
    /// Signed-distance grids (see [`sdf`]).
    pub sdfs: Vec<sdf::SdfDesc>,
}

/// One placement of a group.
#[derive(Clone, Debug)]
pub struct InstanceDesc {
    /// Index into `SceneDesc::groups`.
    pub group: u32,
    pub to_world: Mat4,
}

/// A group's per-triangle data, as `Scene` keeps its own.
struct GroupAttrs {
    tris: Vec<[Vec3; 3]>,
    normals: TriAttr<[Vec3; 3]>,
    uvs: TriAttr<[Vec2; 3]>,
    material: Vec<u32>,
}

/// The instanced part of a scene: the acceleration structure and the groups' data.
pub struct Instanced {
    pub accel: Instances,
    groups: Vec<GroupAttrs>,
    sdf: Option<sdf::SdfPart>,
}

impl Instanced {
    /// `None` when there are no instances; triangles are numbered from `base`.
    pub fn build(
        groups: Vec<GroupDesc>,
        instances: &[InstanceDesc],
        base: u32,
    ) -> Result<Option<Instanced>, String> {
        if instances.is_empty() {
            return Ok(None);
        }
        let tris: Vec<&[[Vec3; 3]]> = groups.iter().map(|g| g.positions.as_slice()).collect();
        let placed: Vec<(u32, Mat4)> = instances.iter().map(|i| (i.group, i.to_world)).collect();
        let accel = Instances::build(&tris, &placed, base)?;
        let sdf = sdf::SdfPart::build(&groups, instances)?;
        let groups = groups
            .into_iter()
            .map(|g| GroupAttrs {
                tris: g.positions,
                normals: TriAttr::from_options(g.normals),
                uvs: TriAttr::from_options(g.uvs),
                material: g.material,
            })
            .collect();
        Ok(Some(Instanced { accel, groups, sdf }))
    }

    /// The closest hit of the scene's own triangles (`bvh`) and the instances.
    #[inline]
    pub fn closest(&self, bvh: &crate::accel::Bvh, ray: &Ray, t_max: f32) -> Option<Hit> {
        let own = bvh.intersect(ray, t_max);
        let best = self
            .accel
            .intersect(ray, own.map_or(t_max, |h| h.t))
            .or(own);
        match &self.sdf {
            None => best,
            Some(s) => s.accel.intersect(ray, best.map_or(t_max, |h| h.t)).or(best),
        }
    }

    /// Whether the scene's own triangles or an instance stop `ray` before `t_max`.
    #[inline]
    pub fn occluded(&self, bvh: &crate::accel::Bvh, ray: &Ray, t_max: f32) -> bool {
        bvh.occluded(ray, t_max)
            || self.accel.occluded(ray, t_max)
            || self
                .sdf
                .as_ref()
                .is_some_and(|s| s.accel.occluded(ray, t_max))
    }
}

/// World bounds of `instances` of `groups`.
pub fn instance_bounds(groups: &[GroupDesc], instances: &[InstanceDesc]) -> Bounds3 {
    let local: Vec<Bounds3> = groups
        .iter()
        .map(|g| {
            let mut b = Bounds3::EMPTY;
            g.positions.iter().flatten().for_each(|p| b.grow(*p));
            b.union(&sdf::group_bounds(g))
        })
        .collect();
    let mut b = Bounds3::EMPTY;
    for i in instances {
        if let Some(l) = local.get(i.group as usize) {
            let m = glam::Affine3A::from_mat4(i.to_world);
            b = b.union(&crate::accel::transformed_bounds(l, &m));
        }
    }
    b
}

impl Scene {
    fn instanced(&self, prim: u32) -> (&Instanced, u32, &GroupAttrs, usize) {
        let ins = self
            .instances
            .as_ref()
            .expect("a triangle number past the scene's own is instanced");
        let (i, g, local) = ins
            .accel
            .locate(prim)
            .expect("instanced triangle numbers come from the instances");
        (ins, i, &ins.groups[g as usize], local as usize)
    }

    /// The material index of an instanced triangle.
    #[cold]
    #[inline(never)]
    pub(super) fn instanced_material(&self, prim: u32) -> u32 {
        if sdf::is_sdf(prim) {
            return self.sdf_material(prim);
        }
        let (_, _, g, k) = self.instanced(prim);
        g.material[k]
    }

    /// An instanced triangle in world space.
    pub(super) fn instanced_triangle(&self, prim: u32) -> [Vec3; 3] {
        if sdf::is_sdf(prim) {
            return [Vec3::ZERO; 3];
        }
        let (ins, i, g, k) = self.instanced(prim);
        let m = ins.accel.to_world(i);
        g.tris[k].map(|p| m.transform_point3(p))
    }

    /// An instanced triangle's texture coordinates.
    pub(super) fn instanced_uvs(&self, prim: u32) -> Option<[Vec2; 3]> {
        if sdf::is_sdf(prim) {
            return None;
        }
        let (_, _, g, k) = self.instanced(prim);
        g.uvs.get(k).copied()
    }

    /// [`Scene::surface_hit`] of a signed-distance grid's hit, None for a triangle's.
    #[cold]
    #[inline(never)]
    pub(super) fn grid_hit(&self, h: Hit) -> Option<SurfaceHit> {
        sdf::is_sdf(h.prim).then(|| self.sdf_hit(h))
    }

    /// The shading normals (moved to world space by the instance's normal matrix) and
    /// uvs of an instanced triangle, for [`Scene::surface_hit`].
    #[cold]
    #[inline(never)]
    pub(super) fn instanced_attrs(&self, prim: u32) -> (Option<[Vec3; 3]>, Option<[Vec2; 3]>) {
        let (ins, i, g, k) = self.instanced(prim);
        let nm = ins.accel.normal_matrix(i);
        (
            g.normals.get(k).map(|n| n.map(|v| nm * v)),
            g.uvs.get(k).copied(),
        )
    }
}
