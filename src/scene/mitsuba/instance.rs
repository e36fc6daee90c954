//! Mitsuba's `shapegroup` (shapes defined once, in their own space, invisible by
//! themselves) and `instance` (a group placed by its `to_world`), read into
//! `SceneDesc::groups` and `SceneDesc::instances`: instanced, not copied (see
//! `accel::Instances`). As Mitsuba, a group may not hold another group, an instance or
//! an emitter.

use super::*;
use crate::scene::instance::{GroupDesc, InstanceDesc};

impl<'a> Loader<'a> {
    /// The group of a `shapegroup` element, read on first use.
    pub(super) fn shape_group(&mut self, el: &'a El) -> R<u32> {
        if let Some(&g) = self.groups.get(&(el as *const El)) {
            return Ok(g);
        }
        if self.in_group {
            return Err(format!(
                "{}: a shapegroup inside a shapegroup: nested instancing is not permitted (as in Mitsuba)",
                el.at
            ));
        }
        let d = &mut self.desc;
        let saved = (
            std::mem::take(&mut d.positions),
            std::mem::take(&mut d.normals),
            std::mem::take(&mut d.uvs),
            std::mem::take(&mut d.material),
        );
        self.in_group = true;
        let read = self.group_shapes(el);
        self.in_group = false;
        let d = &mut self.desc;
        let group = GroupDesc {
            name: el.at.clone(),
            positions: std::mem::replace(&mut d.positions, saved.0),
            normals: std::mem::replace(&mut d.normals, saved.1),
            uvs: std::mem::replace(&mut d.uvs, saved.2),
            material: std::mem::replace(&mut d.material, saved.3),
            sdfs: std::mem::take(&mut self.group_sdfs),
        };
        read?;
        d.groups.push(group);
        let g = d.groups.len() as u32 - 1;
        self.groups.insert(el as *const El, g);
        Ok(g)
    }

    fn group_shapes(&mut self, el: &'a El) -> R<()> {
        for c in &el.children {
            c.used.set(true);
            if c.tag != "shape" {
                continue;
            }
            if c.kind() == "instance" {
                return Err(format!(
                    "{}: an instance inside a shapegroup: nested instancing is not permitted (as in Mitsuba)",
                    c.at
                ));
            }
            for e in &c.children {
                if self.resolve(e)?.tag == "emitter" {
                    return Err(format!(
                        "{}: an emitter on a shape inside a shapegroup: instanced emitters are not supported (as in Mitsuba)",
                        e.at
                    ));
                }
            }
            self.shape(c)?;
        }
        Ok(())
    }

    /// An `instance`: its group (a `<ref>` to a shapegroup, or one nested) and `to_world`.
    pub(super) fn instance(&mut self, el: &'a El) -> R<()> {
        if self.in_group {
            return Err(format!(
                "{}: an instance inside a shapegroup: nested instancing is not permitted (as in Mitsuba)",
                el.at
            ));
        }
        let mut group = None;
        for c in &el.children {
            let t = self.resolve(c)?;
            if t.tag != "shape" {
                continue;
            }
            c.used.set(true);
            if t.kind() != "shapegroup" {
                return Err(format!(
                    "{}: an instance takes a shapegroup, not a shape of type '{}'",
                    c.at,
                    t.kind()
                ));
            }
            if group.is_some() {
                return Err(format!("{}: an instance takes one shapegroup", c.at));
            }
            group = Some(self.shape_group(t)?);
        }
        let group = group.ok_or_else(|| {
            format!(
                "{}: an instance without a shapegroup (<ref id=\"...\"/>)",
                el.at
            )
        })?;
        let to_world = self.transform(el, "to_world")?;
        self.unused(el, "shape 'instance'");
        self.desc.instances.push(InstanceDesc { group, to_world });
        Ok(())
    }
}
