//! Per-triangle attributes that many triangles lack (shading normals, texture
//! coordinates), stored without a slot per triangle when they are absent.
//!
//! `Vec<Option<[Vec3; 3]>>` costs 40 bytes a triangle whether or not the triangle
//! has normals, and a hit reads that slot: on a 1M-triangle mesh without normals
//! or uvs that was 68 MB and two cache misses per hit spent on `None`. Here a
//! scene where no triangle has the attribute stores nothing, one where every
//! triangle has it stores the values densely (no index), and a mixed one stores an
//! index per triangle into the values of the triangles that have it.

use crate::math::{Vec2, Vec3};

/// Index of a triangle without the attribute, in [`TriAttr`]'s sparse form.
const NONE: u32 = u32::MAX;

/// An optional attribute per triangle (see the module docs).
#[derive(Clone, Debug, Default)]
pub enum TriAttr<T> {
    /// No triangle has it.
    #[default]
    Absent,
    /// Every triangle has it: `values[i]` is triangle i's.
    Dense(Vec<T>),
    /// Some triangles have it: `values[index[i]]`, or none where `index[i]` is `NONE`.
    Sparse { index: Vec<u32>, values: Vec<T> },
}

impl<T: Copy> TriAttr<T> {
    /// The compact form of one `Option` per triangle.
    pub fn from_options(per_tri: Vec<Option<T>>) -> Self {
        let present = per_tri.iter().filter(|a| a.is_some()).count();
        if present == 0 {
            TriAttr::Absent
        } else if present == per_tri.len() {
            TriAttr::Dense(per_tri.into_iter().flatten().collect())
        } else {
            let mut values = Vec::with_capacity(present);
            let index = per_tri
                .into_iter()
                .map(|a| match a {
                    Some(v) => {
                        values.push(v);
                        (values.len() - 1) as u32
                    }
                    None => NONE,
                })
                .collect();
            TriAttr::Sparse { index, values }
        }
    }

    /// Triangle `i`'s attribute, if it has one.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Option<&T> {
        match self {
            TriAttr::Absent => None,
            TriAttr::Dense(v) => v.get(i),
            TriAttr::Sparse { index, values } => match index[i] {
                NONE => None,
                k => Some(&values[k as usize]),
            },
        }
    }

    /// The address a hit on triangle `i` will read first (for prefetching), if any.
    #[inline(always)]
    pub fn first_read(&self, i: usize) -> Option<*const u8> {
        match self {
            TriAttr::Absent => None,
            TriAttr::Dense(v) => Some(v.as_ptr().wrapping_add(i) as *const u8),
            TriAttr::Sparse { index, .. } => Some(index.as_ptr().wrapping_add(i) as *const u8),
        }
    }
}

impl super::SceneDesc {
    /// The shading normals and texture coordinates in their compact form, taken out of
    /// the description before the BVH build, the peak of a large mesh's memory: one
    /// `Option` per triangle costs 40 and 28 bytes where absent too (68 MB on a
    /// 1M-triangle mesh without them, held through the build until 2026-12-06).
    pub fn take_tri_attrs(&mut self) -> (TriAttr<[Vec3; 3]>, TriAttr<[Vec2; 3]>) {
        let normals = TriAttr::from_options(std::mem::take(&mut self.normals));
        (
            normals,
            TriAttr::from_options(std::mem::take(&mut self.uvs)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_form_answers_what_the_options_said() {
        for opts in [
            vec![None, None, None],
            vec![Some(1u8), Some(2), Some(3)],
            vec![None, Some(7u8), None, Some(9)],
            vec![],
        ] {
            let a = TriAttr::from_options(opts.clone());
            for (i, o) in opts.iter().enumerate() {
                assert_eq!(a.get(i), o.as_ref(), "{a:?} at {i}");
            }
        }
        assert!(matches!(
            TriAttr::<u8>::from_options(vec![None; 4]),
            TriAttr::Absent
        ));
        assert!(matches!(
            TriAttr::from_options(vec![Some(1u8); 4]),
            TriAttr::Dense(_)
        ));
    }
}
