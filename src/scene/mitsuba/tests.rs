use super::*;

pub(super) fn scene(body: &str) -> Result<SceneDesc, String> {
    parse(
        &format!("<scene version=\"3.0.0\">\n{body}\n</scene>"),
        "t.xml",
        Path::new("."),
    )
}

/// Mitsuba's path integrator starts its roulette at depth rr_depth (5 by default, the
/// first hit counting 1): kalos' --rr-min-depth default becomes rr_depth - 1.
#[test]
fn rr_depth_becomes_the_roulette_default() {
    let shape = r#"<shape type="rectangle"><bsdf type="diffuse"/></shape>"#;
    assert_eq!(scene(shape).unwrap().defaults.rr_min_depth, Some(4));
    let d = scene(&format!(
        r#"<integrator type="path"><integer name="rr_depth" value="3"/></integrator>{shape}"#
    ))
    .unwrap();
    assert_eq!(d.defaults.rr_min_depth, Some(2));
    assert!(
        d.warnings.iter().all(|w| !w.contains("rr_depth")),
        "{:?}",
        d.warnings
    );
    let d = scene(&format!(r#"<integrator type="path"/>{shape}"#)).unwrap();
    assert_eq!(d.defaults.rr_min_depth, Some(4));
}

/// Mitsuba 0.6's diffuse reads `diffuseReflectance` before `reflectance`; a 3.x file
/// has no such alias (the parameter is warned as unused).
#[test]
fn diffuse_reflectance_is_the_06_alias_of_reflectance() {
    let body = r#"<shape type="rectangle"><bsdf type="diffuse">
        <rgb name="diffuseReflectance" value="0.2 0.4 0.6"/>
        <rgb name="reflectance" value="0.9 0.9 0.9"/></bsdf></shape>"#;
    let old = parse(
        &format!("<scene version=\"0.5.0\">{body}</scene>"),
        "t.xml",
        Path::new("."),
    )
    .unwrap();
    assert_eq!(old.materials.last().unwrap().kd, [0.2, 0.4, 0.6]);
    assert!(
        old.warnings
            .iter()
            .any(|w| w.contains("overridden by diffuseReflectance")),
        "{:?}",
        old.warnings
    );
    let new = scene(&body.replace("diffuseReflectance", "diffuse_reflectance")).unwrap();
    assert_eq!(new.materials.last().unwrap().kd, [0.9; 3]);
    assert!(
        new.warnings
            .iter()
            .any(|w| w.contains("'diffuse_reflectance'")),
        "{:?}",
        new.warnings
    );
}

#[test]
fn snake_case_matches_mitsuba() {
    assert_eq!(snake_case("intIOR"), "int_ior");
    assert_eq!(snake_case("toWorld"), "to_world");
    assert_eq!(snake_case("specularReflectance"), "specular_reflectance");
    assert_eq!(snake_case("max_depth"), "max_depth");
}

#[test]
fn spectra_match_mitsuba_rgb_mode() {
    // values printed by Mitsuba 3.9.1 scalar_rgb (mi.traverse) for the same spectra
    let wl = [400.0, 500.0, 600.0, 700.0];
    let v = [0.1, 0.8, 0.2, 0.1];
    let r = spectrum_to_rgb(&wl, &v, true);
    let e = spectrum_to_rgb(&wl, &v, false);
    let want_r = [0.0139056, 0.584234, 0.47694];
    let want_e = [0.071468, 0.551986, 0.424139];
    for c in 0..3 {
        assert!((r[c] - want_r[c]).abs() < 0.02, "{r:?}");
        assert!((e[c] - want_e[c]).abs() < 0.02, "{e:?}");
    }
    let white = spectrum_to_rgb(&[360.0, 830.0], &[1.0, 1.0], true);
    assert!(white.iter().all(|w| (w - 1.0).abs() < 0.01), "{white:?}");
    let ee = spectrum_to_rgb(&[360.0, 830.0], &[0.3, 0.3], false);
    let want = [0.361438, 0.284487, 0.272675];
    for c in 0..3 {
        assert!((ee[c] - want[c]).abs() < 0.005, "{ee:?}");
    }
}

#[test]
fn transforms_compose_in_mitsuba_order() {
    let d = scene(
        r#"<shape type="rectangle"><transform name="to_world">
             <scale value="2"/><rotate x="1" angle="90"/><translate y="1"/>
           </transform></shape>"#,
    )
    .unwrap();
    // scale, then rotate the z=0 plane about x (to y = 0), then lift to y = 1
    let b = d.bounds();
    assert!(
        (b.min - Vec3::new(-2.0, 1.0, -2.0)).length() < 1e-5,
        "{b:?}"
    );
    assert!((b.max - Vec3::new(2.0, 1.0, 2.0)).length() < 1e-5, "{b:?}");
    // normal +z rotated by +90 degrees about x is -y
    let t = d.positions[0];
    let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
    assert!((n - Vec3::NEG_Y).length() < 1e-5, "{n}");
}

#[test]
fn defaults_refs_and_materials() {
    let d = scene(
        r#"<default name="r" value="0.25"/>
           <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/>
             <float name="alpha" value="$r"/><string name="distribution" value="ggx"/></bsdf>
           <bsdf type="twosided" id="glassy"><bsdf type="dielectric">
             <string name="int_ior" value="water"/></bsdf></bsdf>
           <shape type="cube"><ref id="gold"/></shape>
           <shape type="sphere"><ref name="bsdf" id="glassy"/>
             <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>"#,
    )
    .unwrap();
    let gold = &d.materials[d.material[0] as usize];
    match gold.model {
        Some(SurfaceModel::Conductor {
            alpha,
            eta,
            distribution,
            ..
        }) => {
            assert_eq!(alpha, 0.25);
            assert_eq!(distribution, Distribution::Ggx);
            assert_eq!(eta[0], 0.143036);
        }
        ref m => panic!("{m:?}"),
    }
    assert_eq!(gold.illum, 2);
    let last = &d.materials[*d.material.last().unwrap() as usize];
    assert_eq!(last.ke, [1.0, 2.0, 3.0]);
    match last.model {
        Some(SurfaceModel::Dielectric { eta, alpha, .. }) => {
            assert!((eta - 1.333 / 1.000277).abs() < 1e-5);
            assert_eq!(alpha, 0.0);
        }
        ref m => panic!("{m:?}"),
    }
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn errors_are_one_line_with_position() {
    for (body, needle) in [
        ("<shape type=\"cube\"", "t.xml:"),
        ("<shape type=\"cube\"><ref id=\"nope\"/></shape>", "t.xml:2: <ref id=\"nope\">"),
        ("<shape type=\"teapot\"/>", "unknown shape plugin 'teapot'"),
        ("<bsdf type=\"fancy\" id=\"a\"/><shape type=\"cube\"/>", "unknown bsdf plugin 'fancy'"),
        ("<shape type=\"cube\"><float name=\"x\" value=\"$nope\"/></shape>", "undefined parameter $nope"),
        ("<shape type=\"sphere\"><float name=\"radius\" value=\"abc\"/></shape>", "not a number"),
        ("<sensor type=\"perspective\"><float name=\"fov\" value=\"200\"/></sensor><shape type=\"cube\"/>", "fov 200"),
        ("<shape type=\"cube\"><bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"phong\"/></bsdf></shape>",
         "t.xml:2: roughconductor distribution \"phong\": must be \"beckmann\" or \"ggx\""),
    ] {
        let e = scene(body).unwrap_err();
        assert!(e.contains(needle) && !e.contains('\n'), "{body}: {e}");
    }
    let e = parse(
        "<scene version=\"3.0.0\">\n  <shape>\n</scene>",
        "m.xml",
        Path::new("."),
    )
    .unwrap_err();
    assert!(e.starts_with("m.xml:3:"), "{e}");
}

#[test]
fn unsupported_things_are_warned_once_with_the_line() {
    let d = scene(
        r#"<bsdf type="hair" id="h"/>
           <shape type="cube"><ref id="h"/></shape>
           <shape type="cube"><ref id="h"/><float name="wobble" value="1"/></shape>
           <shape type="linearcurve"><string name="filename" value="x.txt"/></shape>"#,
    )
    .unwrap();
    let w = d.warnings.join("\n");
    assert!(w.contains("t.xml:2: unsupported bsdf 'hair'"), "{w}");
    assert!(w.contains("t.xml:4: parameter 'wobble'"), "{w}");
    assert!(
        w.contains("t.xml:5: unsupported shape 'linearcurve'"),
        "{w}"
    );
    assert_eq!(d.warnings.len(), 3, "{w}");
}

/// Forms real files use that Mitsuba reads: a texture as a roughness, spectra split by
/// spaces, Python's booleans, Palik's conductor names, a lookat without up.
#[test]
fn mitsubas_lenient_forms_are_read() {
    let d = scene(
        r#"<bsdf type="roughconductor" id="m"><texture type="bitmap" name="alpha">
             <string name="filename" value="scenes/mitsuba/textures/floor.png"/></texture>
             <string name="material" value="Ni_palik"/></bsdf>
           <shape type="rectangle"><ref id="m"/></shape>
           <shape type="rectangle"><bsdf type="diffuse"><spectrum name="reflectance"
             value="400:0.5 500:0.5  600:0.5,700:0.5"/></bsdf></shape>
           <shape type="rectangle"><boolean name="flip_normals" value="True"/>
             <bsdf type="diffuse"/></shape>"#,
    )
    .unwrap();
    let m = &d.materials[d.materials.len() - 3];
    let ni = METALS.iter().find(|(n, _, _)| *n == "Ni").unwrap();
    match &m.model {
        Some(SurfaceModel::Conductor { eta, alpha, .. }) => {
            assert_eq!(*eta, ni.1);
            // the texture's mean
            assert!(*alpha > 0.0 && *alpha < 1.0, "{alpha}");
        }
        other => panic!("{other:?}"),
    }
    let w = d.warnings.join("\n");
    assert!(w.contains("\"Ni_palik\": rendered with \"Ni\""), "{w}");
    let kd = d.materials[d.materials.len() - 2].kd;
    assert!(kd.iter().all(|c| (c - 0.5).abs() < 0.02), "{kd:?}");
    let e = scene(
        r#"<shape type="cube"><bsdf type="conductor">
             <string name="material" value="Xx_palik"/></bsdf></shape>"#,
    )
    .unwrap_err();
    assert!(e.contains("\"Xx_palik\": not one of"), "{e}");
    // lookat without up: Mitsuba's coordinate_system(dir).first, +x looking down -z
    let d = scene(
        r#"<sensor type="perspective"><transform name="to_world">
             <lookat origin="0, 0, 5" target="0, 0, 0"/></transform></sensor>
           <shape type="cube"/>"#,
    )
    .unwrap();
    assert!((Vec3::from(d.camera.unwrap().up) - Vec3::X).length() < 1e-6);
    // an aov integrator's radiance is its nested integrator's, with its max_depth
    let d = scene(
        r#"<integrator type="aov"><string name="aovs" value="nn:sh_normal"/>
             <integrator type="path" name="radiance"><integer name="max_depth" value="2"/>
             <boolean name="hide_emitters" value="False"/></integrator></integrator>
           <shape type="cube"/>"#,
    )
    .unwrap();
    assert_eq!(d.defaults.max_depth, Some(2));
    assert!(d.warnings.iter().any(|w| w.contains("integrator 'aov'")));
    // one of alpha_u, alpha_v alone, or with alpha: refused as Mitsuba does
    for p in [
        r#"<float name="alpha_u" value="0.4"/>"#,
        r#"<float name="alpha" value="0.4"/><float name="alpha_v" value="0.4"/>"#,
    ] {
        let e = scene(&format!(
            r#"<shape type="cube"><bsdf type="roughconductor">{p}</bsdf></shape>"#
        ))
        .unwrap_err();
        assert!(e.contains("t.xml:2: roughconductor: "), "{e}");
    }
}

#[test]
fn camera_follows_mitsuba_conventions() {
    let d = scene(
        r#"<sensor type="perspective"><float name="fov" value="90"/>
             <transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform>
             <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film>
           </sensor><shape type="cube"/>"#,
    )
    .unwrap();
    let c = d.camera.unwrap();
    assert_eq!(c.origin, [1.0, 2.0, 3.0]);
    assert!((Vec3::from(c.target) - Vec3::new(1.0, 2.0, 2.0)).length() < 1e-6);
    assert!((Vec3::from(c.up) - Vec3::Y).length() < 1e-6);
    // fov_axis x (Mitsuba's default): 90 degrees across 200 pixels, so tan(v/2) = 1/2
    assert_eq!((c.fov, c.fov_axis), (90.0, FovAxis::X));
    assert!((c.tan_half_vertical(200, 100) - 0.5).abs() < 1e-6);
    let v = c.vertical(200, 100);
    assert!(
        (v.fov - 2.0 * 0.5f32.atan().to_degrees()).abs() < 1e-3,
        "{}",
        v.fov
    );
    // another resolution (--res) keeps the 90 degrees across, as Mitsuba's -D resx/resy
    assert!((c.tan_half_vertical(100, 300) - 3.0).abs() < 1e-5);
    assert_eq!(d.defaults.res, Some((200, 100)));
    // the other axes, resolved at the render's resolution
    let axis = |a: &str| {
        let d = scene(&format!(
            r#"<sensor type="perspective"><float name="fov" value="90"/>
                 <string name="fov_axis" value="{a}"/></sensor><shape type="cube"/>"#
        ))
        .unwrap();
        let c = d.camera.unwrap();
        [(200, 100), (100, 200)].map(|(w, h)| c.tan_half_vertical(w, h))
    };
    let near = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 1e-5;
    assert!(near(axis("y"), [1.0, 1.0]));
    assert!(near(axis("x"), [0.5, 2.0]));
    assert!(near(axis("smaller"), [1.0, 2.0]));
    assert!(near(axis("larger"), [0.5, 1.0]));
    let d = 5f32.sqrt();
    assert!(near(axis("diagonal"), [1.0 / d, 2.0 / d]));
    let e = scene(
        r#"<sensor type="perspective"><float name="fov" value="45"/><string name="fov_axis" value="z"/></sensor>"#,
    );
    assert!(e.unwrap_err().contains("fov_axis \"z\""));
}

/// hdrfilm's reconstruction filter: Mitsuba's Gaussian (stddev 0.5) when the film names
/// none, box, tent and Gaussian with their parameters; the negative-lobed ones warned and
/// rendered as the box; a bad parameter is one line naming the file and line.
#[test]
fn film_filter_is_mitsubas() {
    use crate::scene::camera::PixelFilter;
    let filter = |rf: &str| {
        scene(&format!(
            r#"<sensor type="perspective"><float name="fov" value="45"/>
                 <film type="hdrfilm">{rf}</film></sensor><shape type="cube"/>"#
        ))
        .map(|d| (d.camera.unwrap().filter, d.warnings))
    };
    assert_eq!(filter("").unwrap().0, PixelFilter::Gaussian { stddev: 0.5 });
    assert_eq!(
        filter(r#"<rfilter type="box"/>"#).unwrap().0,
        PixelFilter::Box
    );
    assert_eq!(
        filter(r#"<rfilter type="tent"/>"#).unwrap().0,
        PixelFilter::Tent { radius: 1.0 }
    );
    assert_eq!(
        filter(r#"<rfilter type="tent"><float name="radius" value="2"/></rfilter>"#)
            .unwrap()
            .0,
        PixelFilter::Tent { radius: 2.0 }
    );
    let (g, w) =
        filter(r#"<rfilter type="gaussian"><float name="stddev" value="0.3"/></rfilter>"#).unwrap();
    assert_eq!(g, PixelFilter::Gaussian { stddev: 0.3 });
    assert!(w.iter().all(|w| !w.contains("filter")), "{w:?}");
    let (m, w) = filter(r#"<rfilter type="mitchell"/>"#).unwrap();
    assert_eq!(m, PixelFilter::Box);
    assert!(
        w.iter()
            .any(|w| w.contains("'mitchell' has negative lobes")),
        "{w:?}"
    );
    let e =
        filter(r#"<rfilter type="tent"><float name="radius" value="-1"/></rfilter>"#).unwrap_err();
    assert!(
        e.starts_with("t.xml:") && e.contains("tent radius -1"),
        "{e}"
    );
    assert!(!e.contains('\n'));
    // kalos' own scenes keep the box
    assert_eq!(crate::scene::CameraDesc::default().filter, PixelFilter::Box);
}

/// Mitsuba 3.9.1 (scalar_rgb) evaluates `plastic` (diffuse_reflectance 0.5, int_ior 1.9)
/// at normal incidence, wo = wi = n, to f cos = 0.152383: the reader keeps the diffuse
/// reflectance as given and the Plastic model applies the coat once (it was applied
/// twice: 0.96x at this index, 1.02x at 1.5).
#[test]
fn plastic_base_agrees_with_mitsuba() {
    let d = scene(
        r#"<shape type="rectangle"><bsdf type="plastic">
        <rgb name="diffuse_reflectance" value="0.5"/><float name="int_ior" value="1.9"/>
        </bsdf></shape>"#,
    )
    .unwrap();
    let m = d.materials.last().unwrap();
    assert_eq!(m.kd, [0.5; 3]);
    let b = crate::scene::bsdf_of_model(m.model.as_ref().unwrap(), m.kd).unwrap();
    let z = Vec3::Z;
    let f = b.eval::<3>(z, z).0[0];
    assert!((f - 0.152383).abs() < 2e-3 * 0.152383, "{f}");
}

/// A `mask` is a cut-out that rays pass: behind a quad of opacity 0.25, 3/4 of the rays
/// (closest hits and shadow rays alike) reach the quad behind; with a bitmap of opacity,
/// rays stop where it is white and pass where it is black (a known answer each).
#[test]
fn masked_quads_let_rays_through() {
    use crate::math::Ray;
    let dir = std::env::temp_dir().join(format!("kalos-mask-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // left half black (opacity 0), right half white (1)
    image::GrayImage::from_fn(8, 8, |x, _| image::Luma([if x < 4 { 0 } else { 255 }]))
        .save(dir.join("m.png"))
        .unwrap();
    let body = |opacity: &str| {
        format!(
            r#"<shape type="rectangle"><bsdf type="mask">{opacity}<bsdf type="diffuse"/></bsdf></shape>
            <shape type="rectangle"><transform name="to_world"><translate z="-1"/></transform>
            <bsdf type="diffuse"/></shape>"#
        )
    };
    let build = |b: &str| {
        let d = parse(
            &format!("<scene version=\"3.0.0\">{b}</scene>"),
            "t.xml",
            &dir,
        )
        .unwrap();
        crate::scene::Scene::build(d, 0.0).unwrap()
    };
    let s = build(&body(r#"<float name="opacity" value="0.25"/>"#));
    assert!(s.cutouts);
    let n = 40000;
    let (mut front, mut blocked) = (0, 0);
    for i in 0..n {
        let x = (i % 200) as f32 / 200.0 * 1.6 - 0.8;
        let y = (i / 200) as f32 / 200.0 * 1.6 - 0.8;
        let r = Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let h = s
            .intersect(&r, f32::INFINITY)
            .expect("the back quad is behind");
        front += (h.p.z.abs() < 1e-3) as usize;
        blocked += s.occluded(&r, 1.5) as usize;
    }
    let (f, b) = (front as f32 / n as f32, blocked as f32 / n as f32);
    assert!((f - 0.25).abs() < 0.01, "closest hits on the mask: {f}");
    assert!(
        (b - 0.25).abs() < 0.01,
        "shadow rays stopped by the mask: {b}"
    );
    let s = build(&body(
        r#"<texture type="bitmap" name="opacity"><string name="filename" value="m.png"/>
           <string name="filter_type" value="nearest"/></texture>"#,
    ));
    for (x, on_mask) in [(-0.5, false), (0.5, true)] {
        for k in 0..50 {
            let y = k as f32 / 50.0 - 0.5;
            let r = Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
            let h = s.intersect(&r, f32::INFINITY).unwrap();
            assert_eq!(h.p.z.abs() < 1e-3, on_mask, "x {x} y {y}");
            assert_eq!(s.occluded(&r, 1.5), on_mask, "x {x} y {y}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba 3.9.1 (scalar_rgb) samples a `dielectric` of int_ior 1.5 with
/// specular_reflectance (0.2, 0.4, 0.6) and specular_transmittance (0.9, 0.5, 0.1) at
/// normal incidence to weights (0.2, 0.4, 0.6) reflected and (0.400222, 0.222345,
/// 0.0444691) = (0.9, 0.5, 0.1) / eta^2 refracted (radiance mode); the rough and thin ones scale their lobes the same way
/// (the tints were warned and rendered as 1).
#[test]
fn dielectric_tints_scale_reflection_and_transmission() {
    let tints = r#"<rgb name="specular_reflectance" value="0.2 0.4 0.6"/>
        <rgb name="specular_transmittance" value="0.9 0.5 0.1"/>"#;
    let bsdf = |kind: &str, extra: &str| {
        let d = scene(&format!(
            r#"<shape type="rectangle"><bsdf type="{kind}">{tints}{extra}</bsdf></shape>"#
        ))
        .unwrap();
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        let m = d.materials.last().unwrap();
        crate::scene::bsdf_of_model(m.model.as_ref().unwrap(), m.kd).unwrap()
    };
    let wo = Vec3::Z;
    let b = bsdf("dielectric", r#"<float name="int_ior" value="1.5"/>"#);
    let r = b.sample::<3>(wo, 0.0, Vec2::ZERO).unwrap();
    assert!(r.wi.z > 0.0);
    assert_eq!(r.weight.0, [0.2, 0.4, 0.6]);
    let t = b.sample::<3>(wo, 0.99, Vec2::ZERO).unwrap();
    assert!(t.wi.z < 0.0);
    // Mitsuba's weights (eta = 1.5 / 1.000277, the index of air)
    for (w, m) in t.weight.0.iter().zip([0.400222, 0.222345, 0.0444691]) {
        assert!((w - m).abs() < 2e-6, "{w}");
    }
    let b = bsdf("thindielectric", "");
    assert_eq!(
        b.sample::<3>(wo, 0.0, Vec2::ZERO).unwrap().weight.0,
        [0.2, 0.4, 0.6]
    );
    assert_eq!(
        b.sample::<3>(wo, 0.99, Vec2::ZERO).unwrap().weight.0,
        [0.9, 0.5, 0.1]
    );
    // rough: the same lobes as without tints, each scaled by its tint
    let rough = bsdf("roughdielectric", r#"<float name="alpha" value="0.3"/>"#);
    let plain = scene(r#"<shape type="rectangle"><bsdf type="roughdielectric"><float name="alpha" value="0.3"/></bsdf></shape>"#).unwrap();
    let pm = plain.materials.last().unwrap();
    let plain = crate::scene::bsdf_of_model(pm.model.as_ref().unwrap(), pm.kd).unwrap();
    let wo = Vec3::new(0.3, 0.0, 0.9).normalize();
    for (wi, tint) in [
        (Vec3::new(-0.2, 0.1, 0.95).normalize(), [0.2, 0.4, 0.6]),
        (Vec3::new(-0.2, 0.1, -0.95).normalize(), [0.9, 0.5, 0.1]),
    ] {
        let (f, g) = (rough.eval::<3>(wo, wi).0, plain.eval::<3>(wo, wi).0);
        assert!(g[0] > 0.0);
        for c in 0..3 {
            assert!((f[c] - g[c] * tint[c]).abs() <= 1e-6 * g[c], "{f:?} {g:?}");
        }
    }
}

// ----------------------------------------------------------------------------------------
// Hostile input: each of these crashed, hung or rendered a wrong image before its limit
// (a reference cycle and deep nesting overflowed the stack and aborted the test runner)
// ----------------------------------------------------------------------------------------

#[test]
fn reference_cycles_are_an_error_not_a_stack_overflow() {
    let one = r#"<bsdf type="twosided" id="a"><ref id="a"/></bsdf><shape type="rectangle"><ref id="a"/></shape>"#;
    let two = r#"<bsdf type="twosided" id="a"><ref id="b"/></bsdf><bsdf type="twosided" id="b"><ref id="a"/></bsdf><shape type="rectangle"><ref id="a"/></shape>"#;
    let tex = r#"<texture type="checkerboard" id="t"><ref name="color0" id="t"/></texture><shape type="rectangle"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>"#;
    for body in [one, two, tex] {
        let e = scene(body).unwrap_err();
        assert!(e.contains("a cycle") && !e.contains('\n'), "{body}: {e}");
    }
    // a long chain of references without a cycle is bounded too
    let mut chain = String::new();
    for i in 0..5000 {
        chain += &format!(
            r#"<bsdf type="twosided" id="b{i}"><ref id="b{}"/></bsdf>"#,
            i + 1
        );
    }
    chain += r#"<bsdf type="diffuse" id="b5000"/><shape type="rectangle"><ref id="b0"/></shape>"#;
    let e = scene(&chain).unwrap_err();
    assert!(e.contains("more than 64 deep"), "{e}");
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let n = 20_000;
    let body = "<shape type=\"rectangle\">".repeat(n) + &"</shape>".repeat(n);
    let e = scene(&body).unwrap_err();
    assert!(e.contains("nested more than 64 deep"), "{e}");
}

/// N rectangles with area emitters: reading took time N^2 (each element's line number was
/// counted from the start of the text); now 8 times the shapes take about 8 times as long.
#[test]
fn loading_is_linear_in_the_number_of_shapes() {
    let text = |n: usize| {
        let mut s = String::from("<scene version=\"3.0.0\">\n");
        for i in 0..n {
            s += &format!("<shape type=\"rectangle\"><transform name=\"to_world\"><translate x=\"{i}\"/></transform><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>\n");
        }
        s + "</scene>"
    };
    let time = |n: usize, runs: usize| {
        let t = text(n);
        (0..runs)
            .map(|_| {
                let start = std::time::Instant::now();
                let d = parse(&t, "big.xml", Path::new(".")).unwrap();
                assert_eq!(d.positions.len(), 2 * n);
                start.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let (small, large) = (time(12_500, 3), time(100_000, 2));
    // linear: about 8; quadratic: about 64. The bound leaves room for a busy machine.
    assert!(
        large / small < 24.0,
        "12,500 shapes {small:.3} s, 100,000 {large:.3} s"
    );
}

#[test]
fn an_element_with_too_many_attributes_is_refused_before_parsing() {
    let attrs: Vec<String> = (0..200_000).map(|i| format!("a{i}=\"1\"")).collect();
    let e = scene(&format!("<shape type=\"rectangle\" {}/>", attrs.join(" "))).unwrap_err();
    assert!(
        e.contains("t.xml:2: an element with 200001 attributes"),
        "{e}"
    );
    // quotes, comments and '>' inside values do not confuse the count
    let fine =
        r#"<!-- a="1" b='2' --><shape type="rectangle"><string name="x" value="a>b='c'"/></shape>"#;
    assert!(scene(fine).is_ok());
}

/// A folder of its own for include tests.
fn include_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-xml-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn include_cycles_and_fan_out_are_bounded() {
    let d = include_dir("includes");
    let write = |f: &str, body: &str| {
        std::fs::write(
            d.join(f),
            format!("<scene version=\"3.0.0\">{body}</scene>"),
        )
        .unwrap()
    };
    // a self-include is named once, as a cycle (the include chain was repeated 15 times)
    write("self.xml", r#"<include filename="self.xml"/>"#);
    let e = load(&d.join("self.xml")).unwrap_err();
    assert!(e.contains("includes itself (self.xml -> self.xml)"), "{e}");
    assert_eq!(e.matches("<include").count(), 1, "{e}");
    // each file including the next four times: 4^13 reads, refused at the total
    for i in 0..13 {
        write(
            &format!("f{i}.xml"),
            &format!(r#"<include filename="f{}.xml"/>"#, i + 1).repeat(4),
        );
    }
    write("f13.xml", r#"<shape type="rectangle"/>"#);
    let start = std::time::Instant::now();
    let e = load(&d.join("f0.xml")).unwrap_err();
    assert!(e.contains("more than 4096 includes"), "{e}");
    assert!(start.elapsed().as_secs_f64() < 10.0);
    // a modest fan-out still loads: 4^3 rectangles
    write("g.xml", r#"<include filename="f11.xml"/>"#);
    let d3 = load(&d.join("g.xml")).unwrap();
    assert_eq!(d3.positions.len(), 2 * 16);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn negative_colours_and_projective_matrices_are_refused() {
    for (body, needle) in [
        (
            r#"<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="-1"/></bsdf></shape>"#,
            "a negative value",
        ),
        (
            r#"<shape type="rectangle"><bsdf type="diffuse"><float name="reflectance" value="-0.5"/></bsdf></shape>"#,
            "a negative value",
        ),
        (
            r#"<shape type="rectangle"><bsdf type="diffuse"><spectrum name="reflectance" value="400:0.5, 700:-0.1"/></bsdf></shape>"#,
            "a negative value",
        ),
        (
            r#"<shape type="rectangle"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0.5 1"/></transform></shape>"#,
            "projective",
        ),
    ] {
        let e = scene(body).unwrap_err();
        assert!(
            e.contains(needle) && e.starts_with("t.xml:2:"),
            "{body}: {e}"
        );
    }
}

/// Random scenes of nested and referencing BSDFs and textures (ids drawn from a few, so
/// that references often form cycles; nesting up to 100 deep; includes of files that
/// include each other): every one loads or fails with one line naming the file, and none
/// panics or recurses without end. Seed 0x6b616c6f73 ("kalos"), 2,000 scenes.
#[test]
fn fuzzed_structure_loads_or_fails_in_one_line() {
    let mut x = 0x006b_616c_6f73_u64;
    let mut below = |n: u64| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x % n
    };
    let d = include_dir("fuzz");
    for i in 0..4 {
        let body: String = (0..1 + i)
            .map(|k| format!(r#"<include filename="i{}.xml"/>"#, (i + k) % 4))
            .collect();
        std::fs::write(
            d.join(format!("i{i}.xml")),
            format!("<scene version=\"3.0.0\">{body}<shape type=\"cube\"/></scene>"),
        )
        .unwrap();
    }
    let (mut loaded, mut failed) = (0, 0);
    for _ in 0..2000 {
        let mut body = String::new();
        for _ in 0..1 + below(6) {
            let depth = 1 + below(100) as usize;
            let mut open = Vec::new();
            for level in 0..depth {
                let id = below(5);
                match below(5) {
                    0 => body += &format!(r#"<ref id="e{id}"/>"#),
                    1 => {
                        body += &format!(r#"<texture type="checkerboard" id="e{id}{level}">"#);
                        open.push("</texture>");
                    }
                    2 if level == 0 => body += &format!(r#"<include filename="i{id}.xml"/>"#),
                    _ => {
                        let kind = ["twosided", "mask", "diffuse"][below(3) as usize];
                        let id = if below(2) == 0 {
                            format!(r#" id="e{id}""#)
                        } else {
                            String::new()
                        };
                        body += &format!(r#"<bsdf type="{kind}"{id}>"#);
                        open.push("</bsdf>");
                    }
                }
            }
            while let Some(c) = open.pop() {
                body += c;
            }
        }
        body += r#"<shape type="rectangle"><ref id="e0"/></shape>"#;
        let text = format!("<scene version=\"3.0.0\">{body}</scene>");
        let r = std::panic::catch_unwind(|| parse(&text, "f.xml", &d));
        match r.unwrap_or_else(|_| panic!("panicked on {text}")) {
            Ok(_) => loaded += 1,
            Err(e) => {
                assert!(!e.contains('\n') && e.len() < 2000, "{e}");
                failed += 1;
            }
        }
    }
    assert!(loaded > 0 && failed > 0, "{loaded} loaded, {failed} failed");
    let _ = std::fs::remove_dir_all(&d);
}

/// Emission whose power overflows single precision is refused by the lights, naming the
/// emitter's line (an area light of 1e38 panicked in the light choice; a point light of
/// 1e38 vanished from the image).
#[test]
fn emitters_beyond_single_precision_are_named() {
    for (body, needle) in [
        (
            r#"<shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1e38"/></emitter></shape>"#,
            "t.xml:2: material",
        ),
        (
            r#"<shape type="rectangle"/><emitter type="point"><rgb name="intensity" value="1e38"/></emitter>"#,
            "t.xml:2: point light",
        ),
    ] {
        let e = crate::scene::Scene::build(scene(body).unwrap(), 0.0)
            .err()
            .unwrap();
        assert!(
            e.contains(needle) && e.contains("single-precision"),
            "{body}: {e}"
        );
    }
}

/// A scene whose every shape is left out says which and where, not only that it is empty.
#[test]
fn an_empty_scene_names_what_was_left_out() {
    let e = scene(r#"<shape type="hair"/>"#).unwrap_err();
    assert!(
        e.starts_with(
            "t.xml: the scene has no shapes kalos can render (t.xml:2: unsupported shape 'hair'"
        ),
        "{e}"
    );
}

/// A `checkerboard` reflectance is a texture of its two colours (not their mean, which
/// was rendered before), with its `to_uv`; a colour that is no number is one line.
#[test]
fn checkerboard_reflectance_is_a_texture() {
    let d = scene(
        r#"<shape type="rectangle"><bsdf type="diffuse">
           <texture name="reflectance" type="checkerboard">
             <rgb name="color0" value="1 0 0"/><float name="color1" value="0.25"/>
             <transform name="to_uv"><scale x="5" y="5"/></transform>
           </texture></bsdf></shape>"#,
    )
    .unwrap();
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    let t = d.materials[0].kd_procedural.as_deref().expect("a texture");
    assert_eq!(t.lookup(0.05, 0.95), [1.0, 0.0, 0.0]);
    assert_eq!(t.lookup(0.15, 0.95), [0.25; 3]);
    assert_eq!(t.sampling.to_uv, [5.0, 0.0, 0.0, 0.0, 5.0, 0.0]);
    let s = crate::scene::Scene::build(d, 0.0).unwrap();
    assert_eq!(s.materials[0].kd_texture, Some(0));
    // Mitsuba's defaults: 0.4 and 0.2
    let d = scene(r#"<shape type="rectangle"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf></shape>"#).unwrap();
    let t = d.materials[0].kd_procedural.as_deref().unwrap();
    assert_eq!(t.texels, vec![[0.4; 3], [0.2; 3], [0.2; 3], [0.4; 3]]);
    let e = scene(
        r#"<shape type="rectangle"><bsdf type="diffuse">
           <texture name="reflectance" type="checkerboard"><float name="color0" value="red"/>
           </texture></bsdf></shape>"#,
    )
    .unwrap_err();
    assert!(
        e.contains("t.xml:3") && e.contains("color0") && !e.contains('\n'),
        "{e}"
    );
}

/// `normalmap` and `bumpmap` shade the nested BSDF with the texture's normal: on
/// Mitsuba's rectangle (dp/du along +x) a normal map of raw colour (0.8, 0.5, 0.9)
/// (n = (0.6, 0, 0.8) in the tangent frame) turns the hit's shading normal to
/// (0.6, 0, 0.8); a PNG's 8-bit values are read raw (204 / 255 = 0.8, not decoded
/// from sRGB); a bump map of constant height leaves it. A missing bitmap, a scale that is no
/// number and a wrapper without a texture are one line each.
#[test]
fn normal_and_bump_maps_turn_the_shading_normal() {
    use crate::math::Ray;
    let dir = std::env::temp_dir().join(format!("kalos-nmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    image::RgbImage::from_fn(4, 4, |_, _| image::Rgb([204, 128, 230]))
        .save(dir.join("n.png"))
        .unwrap();
    let load = |bsdf: &str| {
        parse(
            &format!(
                "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">{bsdf}</shape>\n</scene>"
            ),
            "t.xml",
            &dir,
        )
    };
    let normal_at_centre = |bsdf: &str| {
        let d = load(bsdf).unwrap();
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        let s = crate::scene::Scene::build(d, 0.0).unwrap();
        assert!(s.normal_maps);
        let r = Ray::new(Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
        s.intersect(&r, f32::INFINITY).unwrap().ns
    };
    let want = Vec3::new(0.6, 0.0, 0.8);
    let n = normal_at_centre(
        r#"<bsdf type="normalmap"><texture name="normalmap" type="rawconstant">
           <vector name="value" value="0.8, 0.5, 0.9"/></texture><bsdf type="diffuse"/></bsdf>"#,
    );
    assert!((n - want).length() < 1e-5, "{n}");
    let n = normal_at_centre(
        r#"<bsdf type="normalmap"><texture name="normalmap" type="bitmap">
           <boolean name="raw" value="true"/><string name="filename" value="n.png"/></texture>
           <bsdf type="diffuse"/></bsdf>"#,
    );
    assert!((n - want).length() < 1e-2, "{n}");
    let n = normal_at_centre(
        r#"<bsdf type="bumpmap"><float name="scale" value="3"/>
           <texture type="bitmap"><boolean name="raw" value="true"/>
           <string name="filename" value="n.png"/></texture><bsdf type="diffuse"/></bsdf>"#,
    );
    assert!((n - Vec3::Z).length() < 1e-6, "{n}");
    for (bsdf, needle) in [
        (
            r#"<bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="none.png"/></texture><bsdf type="diffuse"/></bsdf>"#,
            "t.xml:2: bitmap texture",
        ),
        (
            r#"<bsdf type="bumpmap"><float name="scale" value="big"/><texture type="bitmap"><string name="filename" value="n.png"/></texture><bsdf type="diffuse"/></bsdf>"#,
            "not a number",
        ),
        (
            r#"<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>"#,
            "t.xml:2: normalmap needs a <texture>",
        ),
    ] {
        let e = load(bsdf).unwrap_err();
        assert!(e.contains(needle) && !e.contains('\n'), "{bsdf}: {e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
