//! Shading normals from textures, as Mitsuba 3's `normalmap` and `bumpmap` BSDF wrappers
//! make them: the nested BSDF is shaded in a frame whose normal comes from a texture.
//! kalos applies the normal where a ray hits a surface of such a material
//! (`Scene::surface_hit`), so that every estimator shades in the perturbed frame.
//!
//! Both use the triangle's tangents dp/du and dp/dv, taken in Mitsuba's uv (v down the
//! image: kalos' v is 1 - Mitsuba's), or, without texture coordinates (or with degenerate
//! ones), the pair Mitsuba's `coordinate_system` builds around the geometric normal.
//!
//! - normal map: the texel's raw colour c gives n = 2 c - 1 in the frame (s, t, n_s),
//!   s = dp/du made orthogonal to the shading normal n_s, t = n_s x s;
//! - bump map: with the scaled height gradient (g_u, g_v), dp/du' = dp/du + n_s (g_u -
//!   n_s . dp/du), dp/dv' likewise, and n = dp/du' x dp/dv' turned to the geometric
//!   normal's side.

use super::Texture;
use crate::math::{Vec2, Vec3};
use std::sync::Arc;

/// How a material's shading normal comes from a texture.
#[derive(Clone, Debug, PartialEq)]
pub enum NormalMap {
    /// Mitsuba's `normalmap`: tangent-space normals (raw colours, 2 c - 1).
    Normals(Arc<Texture>),
    /// Mitsuba's `bumpmap`: a height field (its first channel) times `scale`.
    Bumps { heights: Arc<Texture>, scale: f32 },
}

/// dp/du and dp/dv of triangle `p` with texture coordinates `uv` (kalos' convention), in
/// Mitsuba's uv; None where the uvs span no area.
pub fn tangents(p: &[Vec3; 3], uv: &[Vec2; 3]) -> Option<(Vec3, Vec3)> {
    let m = |t: Vec2| Vec2::new(t.x, 1.0 - t.y);
    let (uv0, uv1, uv2) = (m(uv[0]), m(uv[1]), m(uv[2]));
    let (duv0, duv1) = (uv1 - uv0, uv2 - uv0);
    let (dp0, dp1) = (p[1] - p[0], p[2] - p[0]);
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let dp_du = (dp0 * duv1.y - dp1 * duv0.y) * inv;
    let dp_dv = (dp1 * duv0.x - dp0 * duv1.x) * inv;
    (dp_du.is_finite() && dp_dv.is_finite()).then_some((dp_du, dp_dv))
}

impl NormalMap {
    /// The shading normal at texture coordinates `uv` (kalos' convention) of a point of
    /// geometric normal `ng` and shading normal `ns`, with the tangents `dp_du`, `dp_dv`
    /// of [`tangents`]; `ns` itself where the texture gives no direction.
    pub fn perturb(&self, uv: Vec2, ng: Vec3, ns: Vec3, dp_du: Vec3, dp_dv: Vec3) -> Vec3 {
        let n = match self {
            NormalMap::Normals(t) => {
                let c = t.lookup(uv.x, uv.y);
                let local = Vec3::new(2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0);
                let mut s = (dp_du - ns * ns.dot(dp_du)).normalize_or_zero();
                if s == Vec3::ZERO {
                    s = ns.any_orthonormal_pair().0;
                }
                let t = ns.cross(s);
                (s * local.x + t * local.y + ns * local.z).normalize_or_zero()
            }
            NormalMap::Bumps { heights, scale } => {
                let [gu, gv] = heights.gradient(uv.x, uv.y);
                let du = dp_du + ns * (scale * gu - ns.dot(dp_du));
                let dv = dp_dv + ns * (scale * gv - ns.dot(dp_dv));
                du.cross(dv).normalize_or_zero()
            }
        };
        if !n.is_finite() || n == Vec3::ZERO {
            ns
        } else if n.dot(ng) < 0.0 {
            -n
        } else {
            n
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::Sampling;

    fn flat(c: [f32; 3]) -> Arc<Texture> {
        Arc::new(Texture {
            width: 1,
            height: 1,
            texels: vec![c],
            sampling: Sampling::default(),
        })
    }

    /// A unit quad in the xy plane with u along x and kalos' v along y: dp/du = x,
    /// dp/dv = -y (Mitsuba's v runs the other way).
    #[test]
    fn tangents_follow_the_uvs() {
        let p = [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
        ];
        let uv = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        let (du, dv) = tangents(&p, &uv).unwrap();
        assert!((du - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6, "{du}");
        assert!((dv - Vec3::new(0.0, -3.0, 0.0)).length() < 1e-6, "{dv}");
        assert!(tangents(&p, &[Vec2::ZERO; 3]).is_none());
    }

    /// The normal map's identity colour (0.5, 0.5, 1) keeps the normal; (1, 0.5, 0.5)
    /// (n = (1, 0, 0)) turns it to dp/du; a bump map of slope k along u tilts the normal
    /// to (-k, 0, 1) / |..| (a height h = k u over a plane).
    #[test]
    fn normals_and_bumps_turn_the_frame() {
        let (ng, du, dv) = (Vec3::Z, Vec3::X, Vec3::Y);
        let id = NormalMap::Normals(flat([0.5, 0.5, 1.0]));
        assert!((id.perturb(Vec2::splat(0.3), ng, ng, du, dv) - ng).length() < 1e-6);
        let side = NormalMap::Normals(flat([1.0, 0.5, 0.5]));
        let n = side.perturb(Vec2::splat(0.3), ng, ng, du * 4.0, dv);
        assert!((n - Vec3::X).length() < 1e-6, "{n}");
        let k = 0.5;
        let ramp = Texture {
            width: 4,
            height: 1,
            texels: (0..4).map(|x| [x as f32 / 4.0; 3]).collect(),
            sampling: Sampling::default(),
        };
        // f rises 1/4 per texel, 4 texels per unit u: df/du = 1; scale k
        let bump = NormalMap::Bumps {
            heights: Arc::new(ramp),
            scale: k,
        };
        let n = bump.perturb(Vec2::new(0.5, 0.5), ng, ng, du, dv);
        let want = Vec3::new(-k, 0.0, 1.0).normalize();
        assert!((n - want).length() < 1e-5, "{n} vs {want}");
    }
}
