//! Mitsuba's `sdfgrid`: a signed-distance grid from a single-channel grid volume
//! (`filename`, see `vol.rs`) spanning the unit cube of its `to_world`, traced
//! analytically (`accel::SdfGrid`), with `normals` `smooth` (Mitsuba's default) or
//! `analytic`. As Mitsuba's, the volume's bounding box is not used, the grid has no
//! texture coordinates and cannot emit, and a rotating `to_world` is warned (Mitsuba
//! asks for an instance instead) but applied.

use super::*;
use crate::accel::SdfGrid;
use crate::scene::instance::sdf::SdfDesc;
use crate::scene::instance::{GroupDesc, InstanceDesc};
use std::sync::Arc;

impl<'a> Loader<'a> {
    /// Reads the `sdfgrid` shape `el` of material `mat`: into the shapegroup being read,
    /// or, outside one, as a group of its own placed once.
    pub(super) fn sdfgrid(&mut self, el: &'a El, mat: u32) -> R<()> {
        let smooth = match self.string(el, "normals")?.as_deref() {
            None | Some("smooth") => true,
            Some("analytic") => false,
            Some(o) => {
                return Err(format!(
                    "{}: sdfgrid normals '{o}': expected 'smooth' or 'analytic'",
                    el.at
                ))
            }
        };
        let f = self
            .string(el, "filename")?
            .ok_or_else(|| format!("{}: sdfgrid without a filename (a grid volume)", el.at))?;
        let path = self.path(&f);
        let vol = vol::load_vol(&path).map_err(|e| format!("{}: {e}", el.at))?;
        if vol.channels != 1 {
            return Err(format!(
                "{}: {}: {} channels: an sdfgrid takes 1",
                el.at,
                path.display(),
                vol.channels
            ));
        }
        let grid = SdfGrid::new(vol.res, vol.data)
            .map_err(|e| format!("{}: {}: {e}", el.at, path.display()))?;
        let to_world = self.transform(el, "to_world")?;
        let (_, rotation, _) = to_world.to_scale_rotation_translation();
        if (rotation.w.abs() - 1.0).abs() > 1e-6 {
            self.warn(
                "sdfgrid rotation",
                format!(
                    "{}: sdfgrid: to_world rotates (Mitsuba warns and asks for an instance): applied",
                    el.at
                ),
            );
        }
        self.unused(el, "shape 'sdfgrid'");
        let sdf = SdfDesc {
            grid: Arc::new(grid),
            to_world,
            smooth,
            material: mat,
        };
        if self.in_group {
            self.group_sdfs.push(sdf);
            return Ok(());
        }
        self.desc.groups.push(GroupDesc {
            name: el.at.clone(),
            sdfs: vec![sdf],
            ..Default::default()
        });
        self.desc.instances.push(InstanceDesc {
            group: self.desc.groups.len() as u32 - 1,
            to_world: Mat4::IDENTITY,
        });
        Ok(())
    }
}
