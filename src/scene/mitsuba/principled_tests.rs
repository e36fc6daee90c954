//! The `principled` and `principledthin` readers: parameters read, anisotropy looked up with
//! the surface's tangent per hit, bad input refused on one line.

use super::*;
use crate::material::Bsdf;
use crate::math::{Ray, Vec3};

fn scene(body: &str) -> Result<SceneDesc, String> {
    parse(
        &format!("<scene version=\"3.0.0\">\n{body}\n<shape type=\"rectangle\"><ref id=\"b\"/></shape>\n</scene>"),
        "t.xml",
        Path::new("."),
    )
}

/// principledthin's parameters are read (none warned), textured anisotropy included.
#[test]
fn principledthin_is_read() {
    let d = scene(
        "<bsdf type=\"principledthin\" id=\"b\"><rgb name=\"base_color\" value=\"0.7,0.1,0.1\"/>\
         <texture name=\"anisotropic\" type=\"checkerboard\"><float name=\"color0\" value=\"0.05\"/>\
         <float name=\"color1\" value=\"0.8\"/></texture>\
         <float name=\"spec_trans\" value=\"0.4\"/><float name=\"diff_trans\" value=\"1.4\"/>\
         <float name=\"eta\" value=\"1.33\"/>\
         <float name=\"diffuse_transmittance_sampling_rate\" value=\"0.5\"/></bsdf>",
    )
    .unwrap();
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    let Some(SurfaceModel::Principled(p)) = &d.materials[0].model else {
        panic!("{:?}", d.materials[0].model)
    };
    assert!(p.thin && p.is_anisotropic() && !p.is_const());
    assert_eq!((p.eta, p.rates), (1.33, [1.0, 1.0, 1.0, 0.5]));
    let s = crate::scene::Scene::build(d, 0.0).unwrap();
    let Bsdf::PrincipledThin(b) = &s.materials[0].bsdf else {
        panic!("{:?}", s.materials[0].bsdf)
    };
    // scalars are read as Mitsuba's eval_1, the luminance of the value
    assert!((b.spec_trans - 0.4).abs() < 1e-6 && (b.diff_trans - 1.4).abs() < 1e-6);
    assert_eq!(b.base_color, [0.7, 0.1, 0.1]);
}

/// An anisotropic principled gets the tangent of Mitsuba's shading frame where a ray hits
/// (the rectangle's dp/du is +x): its (cos, sin) in the local frame is +x's.
#[test]
fn anisotropic_principled_takes_the_tangent_per_hit() {
    for thin in ["", "thin"] {
        let d = scene(&format!(
            "<bsdf type=\"principled{thin}\" id=\"b\"><float name=\"anisotropic\" value=\"0.5\"/></bsdf>"
        ))
        .unwrap();
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        let s = crate::scene::Scene::build(d, 0.0).unwrap();
        let ray = Ray::new(Vec3::new(0.2, 0.3, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let hit = s.intersect(&ray, f32::INFINITY).unwrap();
        let mat = s.material_of(hit.prim);
        let b = s.bsdf_at(mat, &hit, -ray.d);
        let ([c, t], two_sided) = match &b {
            Bsdf::Principled(p) => (p.tangent, false),
            Bsdf::PrincipledThin(p) => (p.tangent, true),
            b => panic!("{b:?}"),
        };
        assert_eq!(b.is_two_sided(), two_sided);
        let f = hit.shading(-ray.d, two_sided).frame;
        let world = f.s * c + f.t * t;
        assert!((world - Vec3::X).length() < 1e-5, "{thin}: {world}");
    }
}

/// Bad input: one line naming the place and what is wrong.
#[test]
fn bad_principledthin_is_refused() {
    let e =
        scene("<bsdf type=\"principledthin\" id=\"b\"><float name=\"eta\" value=\"-1\"/></bsdf>")
            .unwrap_err();
    assert!(
        e.starts_with("t.xml:")
            && e.contains("principledthin: eta -1: must be a positive number")
            && !e.contains('\n'),
        "{e}"
    );
}
