//! Mitsuba's `shapegroup` / `instance` and `cylinder`, read by kalos: an instance renders
//! as the mesh it places, bad instancing input is a one-line error, and the tessellated
//! cylinder is where Mitsuba's analytic one is, with its uv.

use kalos::math::{Ray, Vec3};
use kalos::pipeline::Silent;
use kalos::scene::{mitsuba, Scene};
use kalos::RenderJob;
use std::path::Path;

/// Mitsuba's `sdfgrid`, a shape that lives in shape groups like instanced meshes.
#[path = "instancing/sdfgrid.rs"]
mod sdfgrid;

const HEAD: &str = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, -6, 2" target="0, 0, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
    </sensor>
    <emitter type="point"><point name="position" x="2" y="-4" z="4"/><rgb name="intensity" value="40"/></emitter>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>"#;

const SHAPES: &str = r#"
    <shape type="sphere"><float name="radius" value="0.8"/><bsdf type="diffuse"><rgb name="reflectance" value="0.7 0.3 0.2"/></bsdf></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><translate z="-0.8"/></transform>
        <bsdf type="roughconductor"/>
    </shape>"#;

fn scene(body: &str) -> Result<Scene, String> {
    let text = format!("{HEAD}{body}</scene>");
    Scene::build(mitsuba::parse(&text, "t.xml", Path::new("."))?, 0.0)
}

fn render(s: &Scene) -> Vec<[f32; 3]> {
    let mut job = RenderJob::new("t.xml");
    job.spp = Some(8);
    job.seed = 3;
    kalos::render_scene(s, &job, &Silent).unwrap().image.data
}

/// Shapes placed by an identity instance render bit for bit as the shapes themselves (the
/// ray moved into the group's space by the identity is the same ray), and an instance
/// moved away leaves the picture with its shapes.
#[test]
fn an_instance_renders_as_the_shapes_it_places() {
    let flat = scene(SHAPES).unwrap();
    assert!(flat.instances.is_none());
    let group = format!(r#"<shape type="shapegroup" id="g">{SHAPES}</shape>"#);
    let inst = scene(&format!(
        r#"{group}<shape type="instance"><ref id="g"/></shape>"#
    ))
    .unwrap();
    assert_eq!(inst.tris.len(), 0);
    assert_eq!(inst.instances.as_ref().unwrap().accel.len(), 1);
    let (a, b) = (render(&flat), render(&inst));
    assert!(a.iter().any(|p| p[0] > 0.0));
    assert!(
        a.iter()
            .zip(&b)
            .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)),
        "the identity instance's image differs"
    );
    let away = scene(&format!(
        r#"{group}<shape type="instance"><ref id="g"/>
            <transform name="to_world"><translate z="100"/></transform></shape>
            <shape type="rectangle"><transform name="to_world"><translate z="-50"/></transform></shape>"#
    ))
    .unwrap();
    let c = render(&away);
    let lit = |img: &[[f32; 3]]| img.iter().filter(|p| p[0] > 0.25).count();
    assert!(lit(&c) < lit(&a) / 4, "{} {}", lit(&c), lit(&a));
}

#[test]
fn bad_instancing_is_a_one_line_error() {
    let cases = [
        (
            r#"<shape type="instance"><ref id="nope"/></shape>"#,
            "no element has that id",
        ),
        (r#"<shape type="instance"/>"#, "without a shapegroup"),
        (
            r#"<shape type="shapegroup" id="a"><shape type="shapegroup" id="b">
                <shape type="sphere"/></shape></shape>
               <shape type="instance"><ref id="a"/></shape>"#,
            "nested instancing is not permitted",
        ),
        (
            r#"<shape type="shapegroup" id="a"><shape type="sphere">
                <emitter type="area"/></shape></shape>
               <shape type="instance"><ref id="a"/></shape>"#,
            "instanced emitters are not supported",
        ),
        (
            r#"<shape type="sphere" id="s"/><shape type="instance"><ref id="s"/></shape>"#,
            "takes a shapegroup",
        ),
        (
            r#"<shape type="shapegroup" id="a"><shape type="sphere"/></shape>
               <shape type="instance"><ref id="a"/>
               <transform name="to_world"><scale x="0"/></transform></shape>"#,
            "is singular",
        ),
    ];
    for (body, want) in cases {
        let e = scene(body)
            .err()
            .unwrap_or_else(|| panic!("{body}: accepted"));
        assert!(e.contains(want) && !e.contains('\n'), "{body}: {e}");
    }
}

/// Mitsuba's cylinder (radius from the x scale of a rigid-plus-scale `to_world`, axis +z
/// from 0 to the z scale, uv = (phi / 2 pi, z / length)): rays aimed at its axis hit it at
/// the analytic distance, with the analytic normal and uv (kalos stores v as 1 - v).
#[test]
fn the_cylinder_is_where_mitsubas_is() {
    let s = scene(
        r#"<shape type="cylinder"><transform name="to_world">
            <scale x="1.5" y="1.5" z="2"/><rotate x="1" angle="90"/><translate x="1"/>
        </transform></shape>"#,
    )
    .unwrap();
    // to_world: (x, y, z) -> (1.5 x + 1, -2 z, 1.5 y): the axis runs from (1, 0, 0) to (1, -2, 0)
    for k in 0..40 {
        let phi = k as f32 * 0.157 + 0.05;
        let h = 0.05 + 0.9 * (k as f32 / 40.0);
        let dir_out = Vec3::new(phi.cos(), 0.0, phi.sin());
        let on_axis = Vec3::new(1.0, -2.0 * h, 0.0);
        let ray = Ray::new(on_axis + dir_out * 5.0, -dir_out);
        let hit = s
            .intersect(&ray, f32::INFINITY)
            .expect("the cylinder is hit");
        assert!((hit.t - 3.5).abs() < 1e-3, "t {} at phi {phi}", hit.t);
        assert!(hit.ns.dot(dir_out) > 0.9999, "normal {:?}", hit.ns);
        // local frame: x = world x, y = world z, so phi_local = phi
        let u = phi / std::f32::consts::TAU;
        assert!((hit.uv.x - u).abs() < 1e-3, "u {} want {u}", hit.uv.x);
        assert!(
            (hit.uv.y - (1.0 - h)).abs() < 1e-3,
            "v {} want {}",
            hit.uv.y,
            1.0 - h
        );
    }
    // no caps: along the axis, nothing
    let ray = Ray::new(Vec3::new(1.0, 5.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
    assert!(s.intersect(&ray, f32::INFINITY).is_none());
    let e = scene(r#"<shape type="cylinder"><float name="radius" value="0"/></shape>"#)
        .err()
        .unwrap();
    assert!(e.contains("non-zero radius"), "{e}");
}
