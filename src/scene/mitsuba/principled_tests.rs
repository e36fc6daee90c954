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

/// Every parameter a checkerboard, evaluated where a ray hits the rectangle: Mitsuba reads
/// base_color with the texture's `eval` and every scalar with `eval_1`, whose checks are
/// the colour's shifted by one square (bench/mitsuba-principled-lookup.py prints these
/// values from Mitsuba 3.9.1: hit point, direction towards the viewer, scattered
/// direction, f |cos| in RGB).
#[test]
#[allow(clippy::excessive_precision)]
fn checkered_principled_agrees_with_mitsuba() {
    type Hit = ([f32; 2], [f32; 3], [f32; 3], [f32; 3]);
    let (up, down) = ([0.3, 0.2, 0.9], [-0.3, -0.2, -0.8]);
    let (slant, slant_down) = ([-0.2, 0.5, 0.7], [0.2, -0.3, -0.9]);
    let principled: [Hit; 4] = [
        (
            [-0.5, -0.5],
            up,
            [-0.4, 0.1, 0.8],
            [2.7016412e-02, 9.3482114e-02, 1.5938792e-02],
        ),
        (
            [0.5, -0.5],
            up,
            [-0.4, 0.1, 0.8],
            [8.5248388e-02, 3.6814101e-02, 5.2958861e-02],
        ),
        (
            [-0.5, -0.5],
            up,
            down,
            [1.0882136e-01, 2.1764272e-01, 7.6948330e-02],
        ),
        (
            [0.5, 0.5],
            slant,
            slant_down,
            [8.2547909e-01, 1.6509582e+00, 5.8370191e-01],
        ),
    ];
    let thin: [Hit; 4] = [
        (
            [-0.5, -0.5],
            up,
            [-0.4, 0.1, 0.8],
            [1.6831543e-02, 3.5129972e-03, 3.5129972e-03],
        ),
        (
            [0.5, -0.5],
            up,
            [-0.4, 0.1, 0.8],
            [3.6414772e-02, 7.1648851e-02, 1.5973407e-01],
        ),
        (
            [-0.5, -0.5],
            up,
            down,
            [4.5973926e+00, 6.5677041e-01, 6.5677041e-01],
        ),
        (
            [0.5, 0.5],
            slant,
            slant_down,
            [9.5425054e-02, 1.3632152e-02, 1.3632152e-02],
        ),
    ];
    let checker = |name: &str, c0: &str, c1: &str, tag: &str| {
        format!(
            "<texture name=\"{name}\" type=\"checkerboard\"><{tag} name=\"color0\" value=\"{c0}\"/>\
             <{tag} name=\"color1\" value=\"{c1}\"/></texture>"
        )
    };
    let scalars = |v: &[(&str, &str, &str)]| -> String {
        v.iter()
            .map(|(n, a, b)| checker(n, a, b, "float"))
            .collect()
    };
    let principled_xml = format!(
        "<bsdf type=\"principled\" id=\"b\">{}{}<float name=\"specular\" value=\"0.7\"/></bsdf>",
        checker("base_color", "0.2,0.8,0.1", "0.9,0.3,0.5", "rgb"),
        scalars(&[
            ("roughness", "0.15", "0.5"),
            ("anisotropic", "0.05", "0.8"),
            ("metallic", "0.7", "0.1"),
            ("spec_tint", "0.2", "0.6"),
            ("sheen", "0.2", "0.9"),
            ("sheen_tint", "0.3", "0.7"),
            ("flatness", "0.1", "0.6"),
            ("clearcoat", "0.9", "0.1"),
            ("clearcoat_gloss", "0.2", "0.8"),
            ("spec_trans", "0.3", "0.6"),
        ])
    );
    let thin_xml = format!(
        "<bsdf type=\"principledthin\" id=\"b\">{}{}<float name=\"eta\" value=\"1.33\"/></bsdf>",
        checker("base_color", "0.7,0.1,0.1", "0.2,0.4,0.9", "rgb"),
        scalars(&[
            ("roughness", "0.3", "0.6"),
            ("anisotropic", "0.05", "0.8"),
            ("spec_tint", "0.2", "0.6"),
            ("sheen", "0.1", "0.8"),
            ("sheen_tint", "0.3", "0.7"),
            ("flatness", "0.1", "0.6"),
            ("spec_trans", "0.2", "0.8"),
            ("diff_trans", "0.4", "1.4"),
        ])
    );
    for (xml, hits) in [(principled_xml, principled), (thin_xml, thin)] {
        let d = scene(&xml).unwrap();
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        let s = crate::scene::Scene::build(d, 0.0).unwrap();
        for (k, (p, wi, wo, f)) in hits.into_iter().enumerate() {
            let (wi, wo) = (Vec3::from(wi).normalize(), Vec3::from(wo).normalize());
            let ray = Ray::new(Vec3::new(p[0], p[1], 0.0) + 2.0 * wi, -wi);
            let hit = s.intersect(&ray, f32::INFINITY).unwrap();
            let b = s.bsdf_at(s.material_of(hit.prim), &hit, wi);
            let frame = hit.shading(wi, b.is_two_sided()).frame;
            let (wi, wo) = (frame.to_local(wi), frame.to_local(wo));
            let v = b.eval::<3>(wi, wo);
            for c in 0..3 {
                let v = v[c] * wo.z.abs();
                assert!(
                    (v - f[c]).abs() <= 2e-4 * f[c].abs().max(1e-2),
                    "{xml}: hit {k}: channel {c}: kalos {v}, Mitsuba {}",
                    f[c]
                );
            }
        }
    }
}
