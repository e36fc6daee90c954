//! Known answers for the microfacet materials and the distant lights: a convex
//! object under a constant environment of radiance 1 sees nothing but the environment, so
//! each pixel is the object's directional albedo there: exactly 1 for glass, a thin slab
//! and a perfect mirror (whatever the path), about 1 for a white plastic, below 1 for a
//! rough interface (single scattering loses energy). A point light over a diffuse plane
//! gives kd I cos / (pi d^2). Estimators that do not support these lights refuse them.

mod common;
use common::*;
use kalos::integrator::{BsdfSelect, Integrator, IntegratorKind, RrMode};
use kalos::material::dielectric::Tint;
use kalos::material::Distribution;
use kalos::math::Vec3;
use kalos::pipeline::Silent;
use kalos::scene::{
    builtin::push_sphere, CameraDesc, EnvironmentDesc, FovAxis, MaterialDesc, PointLightDesc,
    Scene, SceneDesc, SurfaceModel,
};

fn camera() -> CameraDesc {
    CameraDesc {
        origin: [0.0, 0.5, 4.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fov: 30.0,
        fov_axis: FovAxis::Y,
        ..Default::default()
    }
}

fn env(radiance: f32) -> EnvironmentDesc {
    EnvironmentDesc {
        radiance: [radiance; 3],
        map: None,
        to_world: glam::Mat3::IDENTITY,
        source: None,
    }
}

/// A unit sphere of material `m` under a constant environment of radiance 1.
fn sphere_scene(m: MaterialDesc) -> Scene {
    let mut d = SceneDesc {
        name: "sphere".into(),
        materials: vec![m],
        camera: Some(camera()),
        environment: Some(env(1.0)),
        ..Default::default()
    };
    push_sphere(&mut d, Vec3::ZERO, 1.0, 48, 96, 0);
    Scene::build(d, 0.0).unwrap()
}

fn model(m: SurfaceModel, kd: f32) -> MaterialDesc {
    let mut d = MaterialDesc::named("ball");
    d.kd = [kd; 3];
    d.model = Some(m);
    d
}

/// Mean over the pixels whose centre sees the sphere well inside its rim, and the
/// largest deviation from `expect` there.
fn sphere_pixels(film: &kalos::film::Film, w: u32) -> Vec<[f64; 3]> {
    let c = w as f64 / 2.0;
    // the sphere's image has radius atan(1 / 4.03) / tan(15 deg) of the half-width
    let r = (1.0f64 / 0.5f64.hypot(4.0)).asin().tan() / 15f64.to_radians().tan() * c * 0.9;
    let mut v = Vec::new();
    for y in 0..w {
        for x in 0..w {
            let (dx, dy) = (x as f64 + 0.5 - c, y as f64 + 0.5 - c);
            if dx * dx + dy * dy < r * r {
                v.push(film.pixels[(y * w + x) as usize].mean());
            }
        }
    }
    assert!(v.len() > 100);
    v
}

#[test]
fn lossless_interfaces_under_a_white_sky_are_white() {
    let perfect_mirror = SurfaceModel::Conductor {
        eta: [0.0; 3],
        k: [1.0; 3],
        specular: [1.0; 3],
        alpha: 0.0,
        distribution: Distribution::Ggx,
    };
    for (name, m) in [
        (
            "dielectric",
            SurfaceModel::Dielectric {
                eta: 1.5,
                alpha: 0.0,
                distribution: Distribution::Ggx,
                tint: Tint::NONE,
            },
        ),
        (
            "thindielectric",
            SurfaceModel::ThinDielectric {
                eta: 1.5,
                tint: Tint::NONE,
            },
        ),
        ("perfect conductor", perfect_mirror),
    ] {
        let scene = sphere_scene(model(m, 0.5));
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let mut set = settings(&scene, 32, 32);
        set.integrator.max_depth = 64;
        let film = render_spp(&scene, &set, 4);
        // (at the rim, refraction of the smooth shading normal can point through the
        // tessellated surface, which ends the path: only pixels well inside are exact)
        for p in sphere_pixels(&film, 32) {
            for c in 0..3 {
                assert!((p[c] - 1.0).abs() < 1e-3, "{name}: pixel {p:?}");
            }
        }
        let (m, _) = mean_and_se(&film);
        assert!(
            m.iter().all(|&v| (v - 1.0).abs() < 0.01),
            "{name}: image mean {m:?}"
        );
    }
}

#[test]
fn white_plastic_and_rough_interfaces_under_a_white_sky() {
    let cases = [
        // smooth white plastic: F + (1 - F) = 1 up to Mitsuba's Fdr fits
        (
            "plastic",
            SurfaceModel::Plastic {
                eta: 1.5,
                specular: [1.0; 3],
                alpha: 0.0,
                distribution: Distribution::Ggx,
                nonlinear: false,
            },
            0.99,
            1.005,
        ),
        // rough ones lose what single scattering does not return: a few percent, and for
        // Mitsuba's rough plastic much more (its internal reflectance r_int is the rough
        // coat's single scattering, 0.41 instead of 0.60 at alpha 0.3, so a white base
        // returns about 0.68; bench/bsdf-vs-mitsuba.py shows Mitsuba does the same)
        (
            "roughplastic",
            SurfaceModel::Plastic {
                eta: 1.5,
                specular: [1.0; 3],
                alpha: 0.3,
                distribution: Distribution::Ggx,
                nonlinear: false,
            },
            0.6,
            0.75,
        ),
        (
            "roughdielectric",
            // two rough crossings (bench/bsdf-vs-mitsuba.py: 0.84 at alpha 0.2 in both)
            SurfaceModel::Dielectric {
                eta: 1.5,
                alpha: 0.3,
                distribution: Distribution::Ggx,
                tint: Tint::NONE,
            },
            0.65,
            1.005,
        ),
        // Beckmann, Mitsuba's default distribution: the same bounds
        (
            "roughdielectric (Beckmann)",
            SurfaceModel::Dielectric {
                eta: 1.5,
                alpha: 0.3,
                distribution: Distribution::Beckmann,
                tint: Tint::NONE,
            },
            0.65,
            1.005,
        ),
        (
            "roughconductor (perfect, Beckmann)",
            SurfaceModel::Conductor {
                eta: [0.0; 3],
                k: [1.0; 3],
                specular: [1.0; 3],
                alpha: 0.3,
                distribution: Distribution::Beckmann,
            },
            0.8,
            1.005,
        ),
        (
            "roughconductor (perfect)",
            SurfaceModel::Conductor {
                eta: [0.0; 3],
                k: [1.0; 3],
                specular: [1.0; 3],
                alpha: 0.3,
                distribution: Distribution::Ggx,
            },
            0.8,
            1.005,
        ),
    ];
    for (name, m, lo, hi) in cases {
        let scene = sphere_scene(model(m, 1.0));
        let mut set = settings(&scene, 32, 32);
        set.integrator.max_depth = 64;
        let film = render_spp(&scene, &set, 256);
        let px = sphere_pixels(&film, 32);
        let mean: f64 =
            px.iter().map(|p| (p[0] + p[1] + p[2]) / 3.0).sum::<f64>() / px.len() as f64;
        assert!(
            mean > lo && mean < hi,
            "{name}: sphere mean {mean} outside [{lo}, {hi}]"
        );
    }
}

#[test]
fn lobe_selection_methods_agree_on_rough_plastic_and_conductor() {
    // The rough plastic is the roulette paper's combined BRDF (diffuse base + glossy coat):
    // methods 1-3 must give the mixture's image.
    for m in [
        SurfaceModel::Plastic {
            eta: 1.5,
            specular: [1.0; 3],
            alpha: 0.2,
            distribution: Distribution::Ggx,
            nonlinear: false,
        },
        SurfaceModel::Conductor {
            eta: [0.2, 0.9, 1.1],
            k: [3.9, 2.4, 2.1],
            specular: [1.0; 3],
            alpha: 0.3,
            distribution: Distribution::Ggx,
        },
        SurfaceModel::Plastic {
            eta: 1.5,
            specular: [1.0; 3],
            alpha: 0.2,
            distribution: Distribution::Beckmann,
            nonlinear: false,
        },
    ] {
        // Method 2 (static) divides the whole BRDF by the density of the lobe it sampled;
        // a Beckmann coat's density falls as exp(-tan^2 / alpha^2) under a base that does
        // not, so its weights have no finite variance and a 256-spp mean is no test (it
        // came out 2.9% low): methods 1 and 3 only there.
        let beckmann = matches!(
            m,
            SurfaceModel::Plastic {
                distribution: Distribution::Beckmann,
                ..
            }
        );
        let mut mat = model(m, 0.7);
        mat.kd = [0.7, 0.4, 0.2];
        let scene = sphere_scene(mat);
        let mut set = settings(&scene, 24, 24);
        set.integrator.max_depth = 16;
        let base = render_spp(&scene, &set, 256);
        let (m0, se0) = mean_and_se(&base);
        for select in [BsdfSelect::Decompose, BsdfSelect::Static, BsdfSelect::Mis] {
            if beckmann && select == BsdfSelect::Static {
                continue;
            }
            for rr in [RrMode::Classic, RrMode::Spectral] {
                set.integrator.roulette.select = select;
                set.integrator.roulette.mode = rr;
                let film = render_spp(&scene, &set, 256);
                let (m1, se1) = mean_and_se(&film);
                for c in 0..3 {
                    let tol = 4.0 * (se0[c] * se0[c] + se1[c] * se1[c]).sqrt() + 1e-5;
                    assert!(
                        (m1[c] - m0[c]).abs() < tol,
                        "{select:?} {rr:?} channel {c}: {} vs mixture {}",
                        m1[c],
                        m0[c]
                    );
                }
            }
        }
    }
}

#[test]
fn point_light_over_a_diffuse_plane() {
    // L = kd / pi * I cos(theta) / d^2 at the point under the light (cos = 1, d = 1).
    let mut d = SceneDesc {
        name: "plane".into(),
        materials: vec![{
            let mut m = MaterialDesc::named("floor");
            m.kd = [0.5, 0.25, 0.8];
            m
        }],
        camera: Some(CameraDesc {
            origin: [0.0, 0.0, 3.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov: 2.0,
            fov_axis: FovAxis::Y,
            ..Default::default()
        }),
        point_lights: vec![PointLightDesc {
            position: Vec3::new(0.0, 0.0, 1.0),
            intensity: [2.0, 2.0, 2.0],
            shape: Default::default(),
            source: None,
        }],
        ..Default::default()
    };
    push_floor(&mut d, 0);
    let scene = Scene::build(d, 0.0).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let set = settings(&scene, 8, 8);
    let film = render_spp(&scene, &set, 16);
    // the 2-degree view covers |x| < 0.035 around the centre: cos^3 / d^2 varies < 0.2%
    let m = film.pixels[4 * 8 + 4].mean();
    for (c, kd) in [0.5, 0.25, 0.8].iter().enumerate() {
        let want = kd / std::f64::consts::PI * 2.0;
        assert!(
            (m[c] - want).abs() < 0.003 * want,
            "channel {c}: {} vs {want}",
            m[c]
        );
    }
}

#[test]
fn white_lambert_sphere_under_a_white_sky_is_white() {
    // next-event estimation to the environment MIS-weighted against BSDF sampling
    let mut m = MaterialDesc::named("white");
    m.kd = [1.0; 3];
    let scene = sphere_scene(m);
    let mut set = settings(&scene, 16, 16);
    set.integrator.roulette.mode = RrMode::Off;
    set.integrator.max_depth = 8;
    let film = render_spp(&scene, &set, 64);
    assert_mean(&film, [1.0; 3], 4.0, "white sphere");
}

#[test]
fn estimators_without_distant_lights_refuse_them() {
    let scene = sphere_scene(MaterialDesc::named("grey"));
    let base = settings(&scene, 8, 8).integrator;
    let try_ = |f: &dyn Fn(&mut kalos::integrator::IntegratorSettings)| {
        let mut s = base;
        f(&mut s);
        Integrator::prepare(&scene, s, 3, &Silent).err()
    };
    let e = try_(&|s| s.kind = IntegratorKind::Bdpt).expect("bdpt refuses");
    assert!(
        e.contains("--integrator bdpt") && e.contains("environment"),
        "{e}"
    );
    let e = try_(&|s| s.kind = IntegratorKind::Radiosity).expect("radiosity refuses");
    assert!(e.contains("radiosity"), "{e}");
    let e = try_(&|s| s.roulette.mode = RrMode::Estimate).expect("estimate refuses");
    assert!(e.contains("--rr estimate"), "{e}");
    assert!(!e.contains('\n'));
    assert!(try_(&|_| ()).is_none());
}

#[test]
fn toml_models_and_lights_parse_and_bad_ones_are_one_line_errors() {
    let dir = std::env::temp_dir().join(format!("kalos-toml-models-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("t.obj"),
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.join("t.mtl"), "newmtl m\nKd 0.5 0.5 0.5\n").unwrap();
    let parse = |body: &str| {
        let text = format!("[[objects]]\nfile = \"t.obj\"\n{body}");
        kalos::scene::toml_scene::parse(&text, "s.toml", &dir)
    };
    let d = parse(
        "[materials.m]\nmodel = { type = \"roughconductor\", eta = [0.2, 0.9, 1.1], k = [3.9, 2.4, 2.1], alpha = 0.3 }\n\
         [environment]\nradiance = [0.5, 0.5, 0.5]\nrotate = [0, 90, 0]\n\
         [[point_lights]]\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n",
    )
    .unwrap();
    assert!(matches!(
        d.materials[0].model,
        Some(SurfaceModel::Conductor { alpha, .. }) if alpha == 0.3
    ));
    assert_eq!(d.point_lights.len(), 1);
    assert!(d.environment.is_some());
    let scene = Scene::build(d, 0.0).unwrap();
    assert!(scene.lights.env().is_some());
    for (body, want) in [
        ("[materials.m]\nmodel = { type = \"hair\" }\n", "s.toml:"),
        (
            "[materials.m]\nmodel = { type = \"plastic\", eta = 1.0 }\n",
            "eta 1",
        ),
        (
            "[materials.m]\nmodel = { type = \"roughdielectric\", alpha = 0 }\n",
            "alpha",
        ),
        ("[environment]\nmap = \"missing.exr\"\n", "missing.exr"),
        ("[environment]\nradiance = [1, -1, 1]\n", "radiance"),
        ("[[point_lights]]\nposition = [0, 0, 0]\n", "s.toml:"),
    ] {
        let e = parse(body)
            .err()
            .unwrap_or_else(|| panic!("{body}: accepted"));
        assert!(e.contains(want) && !e.contains('\n'), "{body}: {e}");
    }
    // an environment map that is not an image: a one-line error when the scene is built
    std::fs::write(dir.join("sky.exr"), "not an image").unwrap();
    let d = parse("[environment]\nmap = \"sky.exr\"\n").unwrap();
    let e = Scene::build(d, 0.0).err().expect("bad map refused");
    assert!(e.contains("sky.exr") && !e.contains('\n'), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
