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
//!
//! Then, as Mitsuba's `flip_invalid_normals` (on by default, after Schuessler et al.
//! 2017): a normal on the other side from the direction w the surface is seen from than
//! n_s is ((w . n_s) (w . n) <= 0) is mirrored about n_s (its tangent part negated), so
//! that the viewer is not below the perturbed surface where it is above the smooth one.
//!
//! And as Mitsuba's `use_shadowing_function` (on by default), the BSDF's value towards a
//! direction wi is weighted by [`Terminator::factor`]: the microfacet shadowing term of
//! Conty Estevez, Lecocq and Stein (2019), G = 2 / (1 + sqrt(1 + a2 tan^2 theta_i)) with
//! a2 = min(tan^2(theta_n) / 8, 1), both angles to the smooth shading normal (theta_n
//! the map's normal's), and 0 where wi is on different sides of the two normals. The path
//! tracer applies it (`Scene::terminator`, to its light samples and continuations); the
//! other estimators shade with the mapped normal alone.

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
    /// geometric normal `ng` and shading normal `ns` seen from direction `wo` (towards
    /// the ray's origin), with the tangents `dp_du`, `dp_dv` of [`tangents`]; `ns` itself
    /// where the texture gives no direction.
    pub fn perturb(
        &self,
        uv: Vec2,
        ng: Vec3,
        ns: Vec3,
        dp_du: Vec3,
        dp_dv: Vec3,
        wo: Vec3,
    ) -> Vec3 {
        let n = match self {
            NormalMap::Normals(t) => {
                let c = t.lookup(uv.x, uv.y);
                let local = Vec3::new(2.0 * c[0] - 1.0, 2.0 * c[1] - 1.0, 2.0 * c[2] - 1.0);
                let mut s = (dp_du - ns * ns.dot(dp_du)).normalize_or_zero();
                if s == Vec3::ZERO {
                    s = ns.any_orthonormal_pair().0;
                }
                let t = ns.cross(s);
                s * local.x + t * local.y + ns * local.z
            }
            NormalMap::Bumps { heights, scale } => {
                let [gu, gv] = heights.gradient(uv.x, uv.y);
                let du = dp_du + ns * (scale * gu - ns.dot(dp_du));
                let dv = dp_dv + ns * (scale * gv - ns.dot(dp_dv));
                let n = du.cross(dv);
                if n.dot(ng) < 0.0 {
                    -n
                } else {
                    n
                }
            }
        };
        // seen from below the perturbed surface but not the smooth one: mirrored about ns
        let n = if wo.dot(ns) * wo.dot(n) <= 0.0 {
            ns * (2.0 * ns.dot(n)) - n
        } else {
            n
        };
        let n = n.normalize_or_zero();
        if !n.is_finite() || n == Vec3::ZERO {
            ns
        } else {
            n
        }
    }
}

/// Mitsuba's shadowing term of a normal- or bump-mapped hit: the smooth shading normal
/// and the map's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Terminator {
    smooth: Vec3,
    mapped: Vec3,
    alpha2: f32,
}

/// tan^2 of the angle between unit `n` and `w` (of any length).
fn tan2(n: Vec3, w: Vec3) -> f32 {
    let c2 = n.dot(w).powi(2) / w.length_squared();
    (1.0 - c2).max(0.0) / c2
}

impl Terminator {
    /// The term of unit shading normals `smooth` (the vertex normals') and `mapped`.
    pub fn new(smooth: Vec3, mapped: Vec3) -> Terminator {
        Terminator {
            smooth,
            mapped,
            alpha2: (0.125 * tan2(smooth, mapped)).min(1.0),
        }
    }

    /// `dp_du` made orthogonal to the smooth shading normal (the tangent of Mitsuba's
    /// shading frame before the map, which it then makes orthogonal to the map's normal).
    pub fn smooth_tangent(&self, dp_du: Vec3) -> Vec3 {
        dp_du - self.smooth * self.smooth.dot(dp_du)
    }

    /// The weight of the BSDF's value towards `wi` (world, any length).
    pub fn factor(&self, wi: Vec3) -> f32 {
        if self.smooth.dot(wi) * self.mapped.dot(wi) <= 0.0 {
            return 0.0;
        }
        2.0 / (1.0 + (1.0 + self.alpha2 * tan2(self.smooth, wi)).sqrt())
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
    /// (n = (1, 0, 0)) turns it to dp/du (seen from that side); a bump map of slope k
    /// along u tilts the normal to (-k, 0, 1) / |..| (a height h = k u over a plane).
    #[test]
    fn normals_and_bumps_turn_the_frame() {
        let (ng, du, dv) = (Vec3::Z, Vec3::X, Vec3::Y);
        let id = NormalMap::Normals(flat([0.5, 0.5, 1.0]));
        assert!((id.perturb(Vec2::splat(0.3), ng, ng, du, dv, ng) - ng).length() < 1e-6);
        let side = NormalMap::Normals(flat([1.0, 0.5, 0.5]));
        let view = Vec3::new(1.0, 0.0, 1.0).normalize();
        let n = side.perturb(Vec2::splat(0.3), ng, ng, du * 4.0, dv, view);
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
        let n = bump.perturb(Vec2::new(0.5, 0.5), ng, ng, du, dv, ng);
        let want = Vec3::new(-k, 0.0, 1.0).normalize();
        assert!((n - want).length() < 1e-5, "{n} vs {want}");
    }

    /// Mitsuba 3.9.1's `normalmap` around a diffuse of reflectance 0.5 (eval with the
    /// cosine; from bench/mitsuba-normalmap-values.py): the normal as the map gives it or
    /// mirrored towards the viewer wi (`flip_invalid_normals`), the value without and with
    /// the shadowing term (`use_shadowing_function`), in the identity frame.
    #[test]
    // (the values as the script prints them, 8 digits, not rounded to f32's)
    #[allow(
        clippy::excessive_precision,
        clippy::approx_constant,
        clippy::type_complexity
    )]
    fn normal_map_agrees_with_mitsuba() {
        use crate::material::Lambert;
        use crate::math::Frame;
        #[rustfmt::skip]
        let cases: [([f32; 3], [f32; 3], [f32; 3], f32, f32); 5] = [
            ([5.7735027e-01, 5.7735027e-01, 5.7735027e-01], [-6.6666667e-01, -6.6666667e-01, 3.3333333e-01], [0.0000000e+00, 0.0000000e+00, 1.0000000e+00], 9.1888152e-02, 9.1888152e-02),
            ([5.7735027e-01, 5.7735027e-01, 5.7735027e-01], [8.1649658e-01, 4.0824829e-01, 4.0824829e-01], [-2.8221626e-01, 1.8814417e-01, 9.4072087e-01], 7.7796996e-02, 7.7174969e-02),
            ([6.0000000e-01, 0.0000000e+00, 8.0000000e-01], [-9.1287093e-01, 1.8257419e-01, 3.6514837e-01], [6.3500064e-01, 1.2700013e-01, 7.6200076e-01], 3.6382854e-02, 3.5932329e-02),
            ([6.0000000e-01, 0.0000000e+00, 8.0000000e-01], [1.9245009e-01, 1.9245009e-01, 9.6225045e-01], [-9.4868330e-01, 0.0000000e+00, 3.1622777e-01], 0.0000000e+00, 0.0000000e+00),
            ([4.2426407e-01, -5.6568542e-01, 7.0710678e-01], [1.0482848e-01, 9.4345635e-01, 3.1448545e-01], [3.9801488e-01, -1.9900744e-01, 8.9553347e-01], 5.5990521e-02, 5.5565037e-02),
        ];
        let (z, x, y) = (Vec3::Z, Vec3::X, Vec3::Y);
        for (n, view, out, plain, shadowed) in cases {
            let map = NormalMap::Normals(flat(n.map(|c| (c + 1.0) / 2.0)));
            // Mitsuba's wi is kalos' wo (towards the viewer), its wo kalos' wi
            let (wo, wi) = (Vec3::from(view), Vec3::from(out));
            let np = map.perturb(Vec2::splat(0.5), z, z, x, y, wo);
            let frame = Frame::from_normal(np);
            let (wo_l, wi_l) = (frame.to_local(wo), frame.to_local(wi));
            let f = Lambert { kd: [0.5; 3] }.eval::<3>(wo_l, wi_l)[0] * wi_l.z.abs();
            let t = Terminator::new(z, np);
            let mask = if t.factor(wi) > 0.0 { 1.0 } else { 0.0 };
            assert!(
                (f * mask - plain).abs() < 1e-6,
                "{n:?} {view:?}: {} vs {plain}",
                f * mask
            );
            let g = f * t.factor(wi);
            assert!(
                (g - shadowed).abs() < 1e-6,
                "{n:?} {view:?}: {g} vs {shadowed}"
            );
        }
    }

    /// Under a map, an anisotropic lobe's tangent is dp/du made orthogonal to the smooth
    /// normal first (Mitsuba's sh_frame.s): dp/du = (1, 0, 0.5) over the normal z gives
    /// (1, 0, 0), whatever the map's normal; the shadowing term is 1 towards the smooth
    /// normal with an unmapped normal, and 0 below the mapped one.
    #[test]
    fn terminator_tangent_and_mask() {
        let t = Terminator::new(Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        let s = t.smooth_tangent(Vec3::new(1.0, 0.0, 0.5));
        assert!((s - Vec3::X).length() < 1e-6, "{s}");
        assert_eq!(Terminator::new(Vec3::Z, Vec3::Z).factor(Vec3::Z), 1.0);
        assert_eq!(t.factor(Vec3::new(-0.9, 0.0, 0.3)), 0.0);
    }
}
