//! Mitsuba's `cylinder` (no caps) as a fine tessellation with its exact normals and uvs.
//!
//! As Mitsuba: the axis runs from `p0` (default origin) to `p1` (default +z) with
//! `radius` (default 1), and `to_world` keeps only its rotation and translation, its scale
//! giving the radius (x) and length (z): a non-uniform x/y scale is warned and the x scale
//! used, as Mitsuba does. uv: u = phi / 2 pi around the axis, v = the height along it;
//! normals point outwards (`flip_normals`, or a negative radius, inwards).
//!
//! A tessellation, not an analytic primitive (the BVH holds triangles only): 512
//! segments round, so the silhouette is off by at most radius x 1.9e-5 and the
//! shading normals are the analytic ones at the vertices.

use super::*;

/// Segments around the axis.
pub(super) const SEGMENTS: u32 = 512;

impl<'a> Loader<'a> {
    /// The cylinder's mesh in its own frame, the rigid `to_world` placing it and whether
    /// its normals point inwards.
    pub(super) fn cylinder(
        &self,
        el: &'a El,
        to_world: Mat4,
        flip: bool,
    ) -> R<(crate::scene::ply::PlyMesh, Mat4, bool)> {
        let r = self.float(el, "radius")?.unwrap_or(1.0);
        let p0 = self.point(el, "p0")?.unwrap_or(Vec3::ZERO);
        let p1 = self.point(el, "p1")?.unwrap_or(Vec3::Z);
        let d = p1 - p0;
        let len = d.length();
        if !(len > 0.0 && len.is_finite() && r.is_finite() && r != 0.0) {
            return Err(format!(
                "{}: cylinder with radius {r} from {p0} to {p1}: needs a non-zero radius and two distinct end points",
                el.at
            ));
        }
        let (s, t) = duff_frame(d / len);
        let frame = Mat4::from_cols(
            s.extend(0.0),
            t.extend(0.0),
            (d / len).extend(0.0),
            Vec3::ZERO.extend(1.0),
        );
        let m =
            to_world * Mat4::from_translation(p0) * frame * Mat4::from_scale(Vec3::new(r, r, len));
        let a = Mat3::from_mat4(m);
        let q = polar_rotation(a);
        let sc = q.transpose() * a;
        let off = [
            sc.x_axis.y,
            sc.x_axis.z,
            sc.y_axis.x,
            sc.y_axis.z,
            sc.z_axis.x,
            sc.z_axis.y,
        ];
        if off.iter().any(|v| v.abs() > 1e-6) {
            self.warn(
                "cylinder shear",
                format!(
                    "{}: cylinder: to_world shears: the shear is dropped (as in Mitsuba)",
                    el.at
                ),
            );
        }
        if (sc.x_axis.x - sc.y_axis.y).abs() >= 1e-6 {
            self.warn(
                "cylinder scale",
                format!(
                    "{}: cylinder: to_world scales x and y differently: the radius is the x scale (as in Mitsuba)",
                    el.at
                ),
            );
        }
        let (mut radius, length) = (sc.x_axis.x, sc.z_axis.z);
        let mut flip = flip;
        if radius <= 0.0 {
            radius = radius.abs();
            flip = !flip;
        }
        let place = Mat4::from_translation(m.w_axis.truncate()) * Mat4::from_mat3(q);
        Ok((tube(radius, length, SEGMENTS), place, flip))
    }
}

/// An open tube of `radius` from z = 0 to `length`, `n` segments round, outward normals
/// and Mitsuba's uv (in kalos' v convention, 1 - v).
pub(super) fn tube(radius: f32, length: f32, n: u32) -> crate::scene::ply::PlyMesh {
    let mut m = crate::scene::ply::PlyMesh {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    for i in 0..=n {
        let phi = std::f64::consts::TAU * i as f64 / n as f64;
        let (y, x) = (phi.sin() as f32, phi.cos() as f32);
        for z in [0.0, 1.0] {
            m.positions
                .push(Vec3::new(x * radius, y * radius, z * length));
            m.normals.as_mut().unwrap().push(Vec3::new(x, y, 0.0));
            m.uvs
                .as_mut()
                .unwrap()
                .push(Vec2::new(i as f32 / n as f32, 1.0 - z));
        }
    }
    for i in 0..n {
        let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
        // counter-clockwise seen from outside
        m.triangles.push([a, b, c]);
        m.triangles.push([a, c, d]);
    }
    m
}

/// The frame Mitsuba builds around a unit `n` (Duff et al. 2017).
fn duff_frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The rotation of `a`'s polar decomposition a = q s (25 averaging steps of q with its
/// inverse transpose, as Mitsuba's `transform_decompose`).
fn polar_rotation(a: Mat3) -> Mat3 {
    let mut q = a;
    for _ in 0..25 {
        let next = (q + q.inverse().transpose()) * 0.5;
        let diff = (next - q)
            .to_cols_array()
            .iter()
            .map(|v| v.abs())
            .fold(0.0, f32::max);
        q = next;
        if diff < 1e-7 {
            break;
        }
    }
    q
}
