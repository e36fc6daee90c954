//! Mitsuba XML render set-up, sensors and lights, by known answers: `<path>` search
//! folders and `-D` defines, the film's reconstruction filter, the orthographic sensor's
//! extent, a directional light's irradiance and a spot light's cone.

use kalos::image_io::RgbImage;
use kalos::pipeline::Silent;
use kalos::scene;
use kalos::RenderJob;
use std::f64::consts::PI;
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-mlights-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Render `xml` (written to a temporary file) as the file asks, at `spp`.
fn render_xml(name: &str, xml: &str, spp: u32) -> RgbImage {
    render_xml_threads(name, xml, spp, None)
}

fn render_xml_threads(name: &str, xml: &str, spp: u32, threads: Option<usize>) -> RgbImage {
    let d = temp_dir(name);
    let f = d.join("scene.xml");
    std::fs::write(&f, xml).unwrap();
    let spec = f.to_str().unwrap();
    let s = scene::load(spec).unwrap();
    let mut job = RenderJob::new(spec);
    job.spp = Some(spp);
    job.threads = threads;
    kalos::render_scene(&s, &job, &Silent).unwrap().image
}

/// An orthographic sensor 40x20 pixels over world x in [-2, 2], y in [-1, 1] (0.1 per
/// pixel), looking down -z at an emitting rectangle of radiance 1 over x in [0, 1],
/// y in [-0.5, 0.5]: pixel columns 20..30 and rows 5..15 on the pixel grid.
fn ortho_scene(rfilter: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
  <integrator type="direct"/>
  <sensor type="orthographic">
    <transform name="to_world"><scale x="2" y="2"/>
      <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="20"/>
      {rfilter}</film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale x="0.5" y="0.5"/><translate x="0.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="1"/></emitter>
  </shape>
</scene>"#
    )
}

#[test]
fn orthographic_sensor_extent() {
    let img = render_xml("ortho", &ortho_scene(r#"<rfilter type="box"/>"#), 16);
    for y in 0..20 {
        for x in 0..40 {
            let v = img.data[(y * 40 + x) as usize][1];
            let lit = (20..30).contains(&x) && (5..15).contains(&y);
            assert!(
                (v - lit as u8 as f32).abs() < 1e-4,
                "pixel ({x}, {y}) = {v}, expected {}",
                lit as u8
            );
        }
    }
}

/// Without <rfilter>, Mitsuba's Gaussian (stddev 0.5 pixels, cut at 2): the column whose
/// centre lies half a pixel outside the rectangle's edge receives the filter's mass
/// beyond one standard deviation, about 0.159; one and a half pixels out, 0.001. The image
/// is the same on any number of threads.
#[test]
fn default_film_filter_is_mitsubas_gaussian() {
    let w = |x: f64| ((-2.0 * x * x).exp() - (-8.0f64).exp()).max(0.0);
    let integral = |lo: f64, hi: f64| {
        let h = (hi - lo) / 20_000.0;
        (0..20_000)
            .map(|i| w(lo + (i as f64 + 0.5) * h) * h)
            .sum::<f64>()
    };
    let mass = |a: f64| integral(a, 2.0) / integral(-2.0, 2.0);
    let spp = 4096;
    let img = render_xml_threads("gauss", &ortho_scene(""), spp, Some(1));
    let col = |x: u32| {
        (8..12)
            .map(|y| img.data[(y * 40 + x) as usize][1] as f64)
            .sum::<f64>()
            / 4.0
    };
    for (x, d) in [(19, 0.5), (18, 1.5), (20, -0.5)] {
        let want = if d > 0.0 { mass(d) } else { 1.0 - mass(-d) };
        assert!(
            (col(x) - want).abs() < 0.01,
            "column {x}: {} where the Gaussian gives {want}",
            col(x)
        );
    }
    // a box would leave column 19 black
    assert!(mass(0.5) > 0.15);
    let three = render_xml_threads("gauss3", &ortho_scene(""), spp, Some(3));
    assert!(
        img.data == three.data,
        "the image depends on the thread count"
    );
}

/// A camera at `origin` looking at `target`, `n`x`n` pixels, the direct integrator.
fn setup(origin: &str, target: &str, fov: f32, n: u32) -> String {
    format!(
        r#"<integrator type="moment"><integrator type="direct"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="{fov}"/>
    <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{n}"/><integer name="height" value="{n}"/>
      <rfilter type="box"/></film>
  </sensor>"#
    )
}

#[test]
fn path_folders_and_defines_as_mitsuba_resolves_them() {
    let d = temp_dir("paths");
    std::fs::create_dir_all(d.join("common/meshes")).unwrap();
    std::fs::create_dir_all(d.join("scenes/a")).unwrap();
    std::fs::write(
        d.join("common/meshes/tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let scene_xml = |path: &str| {
        format!(
            r#"<scene version="3.0.0">
  <path value="{path}"/>
  <default name="spp" value="4"/>
  <default name="depth" value="3"/>
  <integrator type="path"><integer name="max_depth" value="$depth"/></integrator>
  <sensor type="perspective"><sampler type="independent">
    <integer name="sample_count" value="$spp"/></sampler></sensor>
  <shape type="obj"><string name="filename" value="meshes/tri.obj"/></shape>
</scene>"#
        )
    };
    let f = d.join("scenes/a/scene.xml");
    std::fs::write(&f, scene_xml("../../common")).unwrap();
    let spec = f.to_str().unwrap();
    // the mesh is found through <path>, relative to the scene's folder
    let desc = scene::load_desc(spec).unwrap();
    assert_eq!(desc.positions.len(), 1);
    assert_eq!(desc.defaults.spp, Some(4));
    assert_eq!(desc.defaults.max_depth, Some(3));
    let def = |k: &str, v: &str| vec![(k.to_string(), v.to_string())];
    let desc = scene::load_desc_with(spec, &def("spp", "64")).unwrap();
    assert_eq!(desc.defaults.spp, Some(64));
    let desc = scene::load_desc_with(spec, &def("depth", "2")).unwrap();
    assert_eq!(desc.defaults.max_depth, Some(2));
    // a define the file never names is an error on one line, naming it
    let e = scene::load_desc_with(spec, &def("sp", "64")).unwrap_err();
    assert!(e.starts_with("-D sp=64: ") && !e.contains('\n'), "{e}");
    // defines only for Mitsuba files
    let e = scene::load_desc_with("cornell", &def("spp", "64")).unwrap_err();
    assert!(e.contains("only Mitsuba .xml scenes"), "{e}");
    // without the <path>, the mesh is missing; a <path> that is not a folder is refused
    std::fs::write(&f, scene_xml(".")).unwrap();
    let e = scene::load_desc(spec).unwrap_err();
    assert!(e.contains("tri.obj"), "{e}");
    std::fs::write(&f, scene_xml("../nowhere")).unwrap();
    let e = scene::load_desc(spec).unwrap_err();
    assert!(
        e.contains("<path value=\"../nowhere\">") && e.contains("not a folder"),
        "{e}"
    );
    assert!(!e.contains('\n'));
}

#[test]
fn directional_light_irradiance() {
    // a diffuse plane (albedo 0.5) under irradiance 2 along -z, tilted 60 degrees to it:
    // radiance 0.5 * 2 * cos 60 / pi everywhere on it
    let (rho, e) = (0.5f64, 2.0f64);
    for (dir, cos) in [("0, 0, -1", 1.0f64), ("0, 0.8660254, -0.5", 0.5)] {
        let xml = format!(
            r#"<scene version="3.0.0">{}
  <emitter type="directional"><vector name="direction" value="{dir}"/>
    <rgb name="irradiance" value="{e}"/></emitter>
  <shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="{rho}"/></bsdf></shape>
</scene>"#,
            setup("0, 0, 5", "0, 0, 0", 20.0, 8)
        );
        let img = render_xml("directional", &xml, 4);
        let want = rho * e * cos / PI;
        for p in &img.data {
            for c in p {
                assert!(
                    (*c as f64 - want).abs() < 1e-4 * want,
                    "direction {dir}: {c} vs {want}"
                );
            }
        }
    }
}

#[test]
fn spot_light_cone() {
    // Mitsuba's spot at the origin along +z, intensity 5, beam 15, cutoff 20 degrees, a
    // white diffuse plane at z = 1 facing it, seen from the light's place: a pixel at angle
    // t from the axis has radiance I f(t) cos^3 t / pi, f = 1 within the beam, 0 beyond
    // the cutoff, linear in angle between
    let n = 48u32;
    let fov = 60.0f64;
    let xml = format!(
        r#"<scene version="3.0.0">{}
  <emitter type="spot"><rgb name="intensity" value="5"/>
    <float name="cutoff_angle" value="20"/><float name="beam_width" value="15"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
  </emitter>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/>
    <rotate y="1" angle="180"/><translate z="1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>
</scene>"#,
        setup("0, 0, 0", "0, 0, 1", fov as f32, n)
    );
    let img = render_xml("spot", &xml, 1024);
    let tan_half = (fov.to_radians() / 2.0).tan();
    let half_pixel = (tan_half / n as f64).atan().to_degrees() * 1.5;
    let (mut inside, mut outside, mut between) = (0, 0, 0);
    for y in 0..n {
        for x in 0..n {
            let sx = (2.0 * (x as f64 + 0.5) / n as f64 - 1.0) * tan_half;
            let sy = (2.0 * (y as f64 + 0.5) / n as f64 - 1.0) * tan_half;
            let t = sx.hypot(sy).atan();
            let deg = t.to_degrees();
            let v = img.get(x, y)[1] as f64;
            if deg < 15.0 - half_pixel {
                let want = 5.0 * t.cos().powi(3) / PI;
                assert!((v - want).abs() < 0.01 * want, "{deg} deg: {v} vs {want}");
                inside += 1;
            } else if deg > 20.0 + half_pixel {
                assert_eq!(v, 0.0, "{deg} deg: outside the cone");
                outside += 1;
            } else if (deg - 17.5).abs() < 0.5 {
                let want = 5.0 * (20.0 - deg) / 5.0 * t.cos().powi(3) / PI;
                assert!((v - want).abs() < 0.05 * want, "{deg} deg: {v} vs {want}");
                between += 1;
            }
        }
    }
    assert!(
        inside > 100 && outside > 100 && between > 4,
        "{inside} {outside} {between}"
    );
}

/// Mitsuba's projector 1 above a white diffuse floor, looking down with a 90 degree field
/// of view (its frustum meets the floor over x, y in [-1, 1]): irradiance 0.5 at scale 2
/// gives the floor pi E = pi, so its radiance is 1 everywhere inside and 0 outside. Seen
/// by an orthographic sensor over [-2, 2]^2 (40x40 pixels): columns and rows 10..30.
#[test]
fn projector_irradiance_and_frustum() {
    let xml = r#"<scene version="3.0.0">
  <integrator type="direct"/>
  <sensor type="orthographic">
    <transform name="to_world"><scale x="2" y="2"/>
      <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="40"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale value="10"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf>
  </shape>
  <emitter type="projector">
    <float name="fov" value="90"/>
    <float name="scale" value="2"/>
    <rgb name="irradiance" value="0.5"/>
    <transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform>
  </emitter>
</scene>"#;
    let img = render_xml("projector", xml, 4);
    for y in 0..40 {
        for x in 0..40 {
            let v = img.data[(y * 40 + x) as usize][1];
            let lit = (10..30).contains(&x) && (10..30).contains(&y);
            // the frustum's edges fall on pixel edges; allow their samples to round
            let edge = [9, 10, 29, 30].contains(&x) || [9, 10, 29, 30].contains(&y);
            if !edge {
                assert!(
                    (v - lit as u8 as f32).abs() < 1e-3,
                    "pixel ({x}, {y}) = {v}, expected {}",
                    lit as u8
                );
            }
        }
    }
}
