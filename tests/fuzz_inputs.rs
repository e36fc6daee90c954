//! Hand-rolled fuzzing: randomly mutated OBJ, MTL and TOML text (lines deleted,
//! duplicated, swapped, numbers replaced by huge/negative/NaN/garbage tokens, truncated,
//! a byte-order mark, CRLF or CR-only line ends) must load or fail with an error, never
//! panic. And the shapes of input real tools write: byte-order marks and any line ends
//! load as the plain file does, names with spaces load, random mirroring transforms keep
//! every front side, and special files (FIFOs, directories, devices) are refused at once.

use glam::Mat4;
use kalos::scene::obj::{load_obj_text, MtlSource};
use kalos::scene::{mtl, toml_scene, Scene, SceneDesc};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// xorshift64*: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const TOKENS: &[&str] = &[
    "1e38",
    "-1e38",
    "3.4e39",
    "-0",
    "0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "-1",
    "-99",
    "99",
    "4294967296",
    "99999999999999999999",
    "abc",
    "",
    "/",
    "//",
    "1//",
    "/1",
    "1/2/3/4",
    "-1/-1/-1",
    "0/0/0",
    "1e-45",
    "#",
    "\\",
    "\"",
    "'",
    "[",
    "]",
    "=",
    "f",
    "v",
    "usemtl",
    "newmtl",
    "\u{0}",
    "\u{fffd}",
    "é",
    "\t",
    "\r",
    "\u{feff}",
    "-s",
    "-o 1 2",
    "-clamp",
    "my tex.png",
];

/// Apply 1..4 random mutations to `text`.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.below(4) {
        let n = lines.len();
        match rng.below(7) {
            0 if n > 0 => {
                lines.remove(rng.below(n));
            }
            1 if n > 0 => {
                let l = lines[rng.below(n)].clone();
                lines.insert(rng.below(n + 1), l);
            }
            2 if n > 1 => {
                let (a, b) = (rng.below(n), rng.below(n));
                lines.swap(a, b);
            }
            3 | 4 if n > 0 => {
                // replace one word (often a number) by a nasty token
                let i = rng.below(n);
                let mut words: Vec<String> =
                    lines[i].split_whitespace().map(str::to_string).collect();
                if !words.is_empty() {
                    let w = rng.below(words.len());
                    words[w] = TOKENS[rng.below(TOKENS.len())].to_string();
                    lines[i] = words.join(" ");
                }
            }
            5 => {
                // truncate anywhere (on a char boundary)
                let joined = lines.join("\n");
                let mut cut = rng.below(joined.len() + 1);
                while !joined.is_char_boundary(cut) {
                    cut -= 1;
                }
                lines = joined[..cut].lines().map(str::to_string).collect();
            }
            _ if n > 0 => {
                // append a token to a line
                let i = rng.below(n);
                let t = TOKENS[rng.below(TOKENS.len())];
                lines[i].push(' ');
                lines[i].push_str(t);
            }
            _ => {}
        }
    }
    let sep = match rng.below(6) {
        0 => "\r\n",
        1 => "\r",
        _ => "\n",
    };
    let bom = if rng.below(5) == 0 { "\u{feff}" } else { "" };
    format!("{bom}{}", lines.join(sep))
}

const OBJ: &str =
    "# fuzz seed\nmtllib m.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1 1\n\
vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvn 0 1 0\ng top\nusemtl white\nf 1/1/1 2/2/1 3/3/1 4/1/1\n\
f -5 -4 -1\ns 1\nusemtl light\nf 1//2 2//2 5//2\nl 1 2 3\nf 2 3 5 1\n";
const MTL: &str = "# fuzz seed\nnewmtl white\nKd 0.8 0.8 0.8\nKs 0.1 0.1 0.1\nNs 20\nillum 2\n\
newmtl light\nKd 0 0 0\nKe 5 5 5\nNi 1.5\nillum 7\nnewmtl mirror\nillum 5\nd 1\n";

/// Run `f`; on a panic, fail naming the input.
fn no_panic(what: &str, input: &str, f: impl FnOnce()) {
    if catch_unwind(AssertUnwindSafe(f)).is_err() {
        panic!("{what} panicked on input:\n{input:?}");
    }
}

/// Load (and build, when loading works); true when loading worked.
fn load_and_build(obj: &str, mtl: &'static str) -> bool {
    let lib = move |name: &str| (name == "m.mtl").then_some(mtl);
    let mut d = SceneDesc::default();
    let r = load_obj_text(
        obj,
        "fuzz.obj",
        MtlSource::Embedded(&lib),
        Mat4::IDENTITY,
        &mut d,
    );
    if let Err(e) = &r {
        // every error is kalos' own: one line naming the file; tobj never sees bad input
        assert!(e.starts_with("fuzz.obj") || e.starts_with("m.mtl"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        assert!(
            !e.contains("cannot parse OBJ") && !e.contains("gave up"),
            "{e}"
        );
    } else {
        // invariants the renderer relies on
        let n = d.positions.len();
        assert!(d.normals.len() == n && d.uvs.len() == n && d.material.len() == n);
        assert!(d.material.iter().all(|&m| (m as usize) < d.materials.len()));
        assert!(d.positions.iter().flatten().all(|v| v.is_finite()));
        let _ = Scene::build(d, 0.0);
    }
    r.is_ok()
}

#[test]
fn mutated_obj_never_panics() {
    assert!(load_and_build(OBJ, MTL), "the seed loads");
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut loaded = 0;
    for _ in 0..200 {
        let obj = mutate(OBJ, &mut rng);
        no_panic("OBJ", &obj, || loaded += load_and_build(&obj, MTL) as usize);
    }
    // the mutations are neither all harmless nor all fatal
    assert!((20..=180).contains(&loaded), "{loaded} of 200 loaded");
}

#[test]
fn mutated_mtl_never_panics() {
    let dir = Path::new("/nonexistent-kalos-dir");
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let seed = format!("{MTL}map_Kd -s 1 1 1 -o 0 0 0 t\\x.png\nd 0.4\nmap_d -imfchan m a.png\n");
    assert_eq!(mtl::parse_mtl(&seed, "fuzz.mtl", dir).unwrap().0.len(), 3);
    for _ in 0..200 {
        let text = mutate(&seed, &mut rng);
        no_panic("MTL", &text, || {
            if let Err(e) = mtl::parse_mtl(&text, "fuzz.mtl", dir) {
                assert!(e.starts_with("fuzz.mtl:") && !e.contains('\n'), "{e}");
            }
        });
        // and through an OBJ into a built scene (leaked: Embedded wants 'static text)
        let leaked: &'static str = Box::leak(text.clone().into_boxed_str());
        no_panic("OBJ+MTL", &text, || {
            load_and_build(OBJ, leaked);
        });
    }
}

#[test]
fn mutated_toml_never_panics() {
    let dir = std::env::temp_dir().join(format!("kalos-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a.obj"), OBJ).unwrap();
    std::fs::write(dir.join("m.mtl"), MTL).unwrap();
    let seed = "# fuzz seed\n[camera]\norigin = [0, 0, 3.9]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\n\
fov = 39.3\n\n[render]\nres = [16, 16]\nspp = 4\nmax_depth = -1\n\n[[objects]]\nfile = \"a.obj\"\n\
translate = [0, 1, 0]\nrotate = [0, 30, 0]\nscale = [1, 2, 1]\n\n[[objects]]\nfile = 'a.obj'\n\
scale = 0.5\n\n[materials.white]\nkd = [0.8, 0.8, 0.8]\nillum = 2\n";
    let d = toml_scene::parse(seed, "fuzz.toml", &dir).unwrap();
    assert_eq!(d.defaults.spp, Some(4));
    let mut rng = Rng(0xdead_beef_cafe_f00d);
    for _ in 0..200 {
        let text = mutate(seed, &mut rng);
        no_panic("TOML", &text, || {
            if let Ok(d) = toml_scene::parse(&text, "fuzz.toml", &dir) {
                let _ = Scene::build(d, 0.0);
            }
        });
    }
}

/// The seed OBJ loaded with `mtl`, as (positions, normals, uvs, material names).
type Loaded = (
    Vec<[glam::Vec3; 3]>,
    Vec<Option<[glam::Vec3; 3]>>,
    Vec<Option<[glam::Vec2; 3]>>,
    Vec<String>,
);

fn load_plain(obj: &str, mtl: &'static str, xf: Mat4) -> Result<Loaded, String> {
    let lib = move |name: &str| (name == "m.mtl").then_some(mtl);
    let mut d = SceneDesc::default();
    load_obj_text(obj, "fuzz.obj", MtlSource::Embedded(&lib), xf, &mut d)?;
    let names = d
        .material
        .iter()
        .map(|&m| d.materials[m as usize].name.clone())
        .collect();
    Ok((d.positions, d.normals, d.uvs, names))
}

/// The text with a byte-order mark and/or other line ends.
fn variants(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for sep in ["\n", "\r\n", "\r"] {
        for bom in ["", "\u{feff}"] {
            out.push(format!(
                "{bom}{}",
                text.lines().collect::<Vec<_>>().join(sep)
            ));
        }
    }
    out
}

#[test]
fn boms_and_any_line_ends_load_as_the_plain_file() {
    let plain = load_plain(OBJ, MTL, Mat4::IDENTITY).unwrap();
    assert!(plain.0.len() >= 5, "{}", plain.0.len());
    for obj in variants(OBJ) {
        for mtl in variants(MTL) {
            let mtl: &'static str = Box::leak(mtl.into_boxed_str());
            let got = load_plain(&obj, mtl, Mat4::IDENTITY)
                .unwrap_or_else(|e| panic!("{obj:?} with {mtl:?}: {e}"));
            assert!(got == plain, "{obj:?} with {mtl:?} loads differently");
        }
    }
    // and the mutated files: BOM / line ends never change what a mutation does
    let mut rng = Rng(0x1234_5678_9abc_def1);
    for _ in 0..100 {
        let m = mutate(OBJ, &mut rng);
        let base = m
            .trim_start_matches('\u{feff}')
            .replace("\r\n", "\n")
            .replace('\r', "\n");
        let a = load_plain(&base, MTL, Mat4::IDENTITY);
        for v in variants(&base) {
            let b = load_plain(&v, MTL, Mat4::IDENTITY);
            match (&a, &b) {
                (Ok(x), Ok(y)) => assert!(x == y, "{v:?}"),
                (Err(x), Err(y)) => assert_eq!(x, y, "{v:?}"),
                _ => panic!("{v:?}: {a:?} vs {b:?}", a = a.is_ok(), b = b.is_ok()),
            }
        }
    }
}

#[test]
fn random_mirroring_transforms_keep_every_front_side() {
    let plain = load_plain(OBJ, MTL, Mat4::IDENTITY).unwrap();
    let mut rng = Rng(0x0bad_cafe_dead_f00d);
    let mut u = || (rng.next() >> 11) as f32 / (1u64 << 53) as f32;
    let mut mirrored = 0;
    for _ in 0..200 {
        let sign = |x: f32| if x < 0.5 { -1.0 } else { 1.0 };
        let s = glam::Vec3::new(
            sign(u()) * (0.1 + 3.0 * u()),
            sign(u()) * (0.1 + 3.0 * u()),
            sign(u()) * (0.1 + 3.0 * u()),
        );
        let q = glam::Quat::from_euler(glam::EulerRot::ZYX, 6.3 * u(), 6.3 * u(), 6.3 * u());
        let t = glam::Vec3::new(u(), u(), u()) * 10.0 - 5.0;
        let xf = Mat4::from_scale_rotation_translation(s, q, t);
        let det = glam::Mat3::from_mat4(xf).determinant();
        mirrored += (det < 0.0) as usize;
        let nxf = glam::Mat3::from_mat4(xf).inverse().transpose();
        let got = load_plain(OBJ, MTL, xf).unwrap();
        assert_eq!(got.0.len(), plain.0.len());
        for (k, (a, b)) in plain.0.iter().zip(&got.0).enumerate() {
            let front = |t: &[glam::Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            // the front side follows the transformed normal
            let want = (nxf * front(a)).normalize();
            assert!(front(b).dot(want) > 0.99, "det {det}: triangle {k}");
            // the same corners, in some order
            for v in a {
                let p = xf.transform_point3(*v);
                assert!(b
                    .iter()
                    .any(|w| (p - *w).length() < 1e-3 * (1.0 + p.length())));
            }
            // shading normals stay on the side of the front they were on
            if let (Some(pn), Some(gn)) = (plain.1[k], got.1[k]) {
                let pos = |ns: [glam::Vec3; 3], f: glam::Vec3| {
                    ns.iter().filter(|n| n.dot(f) > 0.0).count()
                };
                assert_eq!(
                    pos(pn, front(a)),
                    pos(gn, front(b)),
                    "det {det}: triangle {k}"
                );
            }
        }
    }
    assert!((60..=140).contains(&mirrored), "{mirrored} of 200 mirrored");
}

#[test]
fn names_with_spaces_load() {
    let dir = std::env::temp_dir().join(format!("kalos-fuzz-spaces-{}", std::process::id()));
    let sub = dir.join("a dir");
    std::fs::create_dir_all(&sub).unwrap();
    let png = [255u8, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
    image::RgbImage::from_raw(2, 2, png.to_vec())
        .unwrap()
        .save(sub.join("my  tex.png"))
        .unwrap();
    std::fs::write(
        sub.join("my mats.mtl"),
        "\u{feff}newmtl wood grain\r\nKd 0.5 0.5 0.5\r\nmap_Kd -s 1 1 1 -clamp on my  tex.png\r\n",
    )
    .unwrap();
    std::fs::write(
        sub.join("my scene.obj"),
        "mtllib my mats.mtl\rv 0 0 0\rv 1 0 0\rv 0 1 0\rvt 0 0\rvt 1 0\rvt 0 1\r\
         usemtl wood grain\rf 1/1 2/2 3/3\r",
    )
    .unwrap();
    std::fs::write(
        dir.join("my scene.toml"),
        "[[objects]]\nfile = \"a dir/my scene.obj\"\nscale = [-1, 1, 1]\n",
    )
    .unwrap();
    let s = kalos::scene::load(dir.join("my scene.toml").to_str().unwrap()).unwrap();
    assert_eq!(s.tris.len(), 1);
    assert_eq!(s.textures.len(), 1);
    assert_eq!(s.materials[s.tri_material[0] as usize].name, "wood grain");
    std::fs::remove_dir_all(&dir).ok();
}

/// Run `f` on another thread; fail if it takes more than `secs` seconds (a blocking read).
fn within<T: Send + 'static>(secs: u64, what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(std::time::Duration::from_secs(secs))
        .unwrap_or_else(|_| panic!("{what}: did not return within {secs} s"))
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_without_reading() {
    use std::os::unix::fs::symlink;
    let dir = std::env::temp_dir().join(format!("kalos-fuzz-special-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let kinds: [(&str, &str); 4] = [
        ("fifo", "FIFO"),
        ("dir", "directory"),
        ("zero", "character device"),
        ("null", "character device"),
    ];
    for ext in ["obj", "toml", "mtl", "png", "exr", "pfm"] {
        for (kind, what) in kinds {
            let p = dir.join(format!("{kind}.{ext}"));
            match kind {
                "fifo" => assert!(std::process::Command::new("mkfifo")
                    .arg(&p)
                    .status()
                    .unwrap()
                    .success()),
                "dir" => std::fs::create_dir(&p).unwrap(),
                k => symlink(format!("/dev/{k}"), &p).unwrap(),
            }
            let name = p.file_name().unwrap().to_str().unwrap().to_string();
            // every reader: scene files, MTL through an OBJ, textures, images
            let e = match ext {
                "obj" | "toml" => {
                    let spec = p.to_str().unwrap().to_string();
                    within(10, &name, move || kalos::scene::load_desc(&spec).err())
                }
                "mtl" => {
                    let obj = dir.join(format!("uses-{kind}.obj"));
                    std::fs::write(&obj, format!("mtllib {name}\nv 0 0 0\n")).unwrap();
                    let spec = obj.to_str().unwrap().to_string();
                    within(10, &name, move || kalos::scene::load_desc(&spec).err())
                }
                "png" => {
                    let q = p.clone();
                    within(10, &name, move || kalos::scene::Texture::load(&q).err())
                }
                _ => {
                    let q = p.clone();
                    within(10, &name, move || kalos::image_io::read_image(&q).err())
                }
            };
            let e = e.unwrap_or_else(|| panic!("{name}: read without an error"));
            assert!(e.contains(&name) && e.contains(what), "{name}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

const XML: &str = r#"<scene version="3.0.0">
<default name="r" value="0.5"/>
<bsdf type="roughplastic" id="p"><float name="alpha" value="$r"/><string name="distribution" value="ggx"/>
<rgb name="diffuse_reflectance" value="0.2, 0.3, 0.4"/></bsdf>
<bsdf type="twosided" id="d"><bsdf type="diffuse">
<spectrum name="reflectance" value="400:0.1, 700:0.9"/></bsdf></bsdf>
<shape type="rectangle"><transform name="to_world"><scale x="2" y="3"/>
<rotate x="1" angle="90"/><translate z="1"/></transform><ref id="p"/></shape>
<shape type="cube"><transform name="to_world">
<matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"/></transform><ref id="d"/>
<emitter type="area"><rgb name="radiance" value="1 2 3"/></emitter></shape>
<shape type="sphere"><point name="center" x="0" y="1" z="0"/><float name="radius" value="0.5"/>
<bsdf type="conductor"><string name="material" value="Au"/></bsdf></shape>
<shape type="sphere"><float name="radius" value="0.2"/><bsdf type="principledthin">
<float name="anisotropic" value="0.4"/><float name="spec_trans" value="0.5"/><float name="diff_trans" value="0.8"/></bsdf></shape>
<shape type="disk"><boolean name="flip_normals" value="true"/>
<bsdf type="mask"><float name="opacity" value="0.3"/><bsdf type="roughdielectric">
<rgb name="specular_reflectance" value="0.5"/><rgb name="specular_transmittance" value="0.2 0.4 0.6"/>
</bsdf></bsdf></shape>
<emitter type="point"><point name="position" value="0, 1, 0"/></emitter>
<emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>
<emitter type="spot"><float name="cutoff_angle" value="25"/><rgb name="intensity" value="3"/>
<transform name="to_world"><lookat origin="0,2,0" target="0,0,0" up="0,0,1"/></transform></emitter>
<emitter type="directional"><vector name="direction" value="0,-1,0"/><rgb name="irradiance" value="2"/></emitter>
<sensor type="perspective"><float name="fov" value="45"/><string name="fov_axis" value="smaller"/>
<transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
<film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="8"/><rfilter type="box"/></film>
<sampler type="independent"><integer name="sample_count" value="4"/></sampler></sensor>
<integrator type="moment"><integrator type="path"><integer name="max_depth" value="5"/></integrator></integrator>
</scene>"#;

/// XML-specific damage on top of `mutate`: a character deleted or one of the markup
/// characters inserted.
fn mutate_xml(text: &str, rng: &mut Rng) -> String {
    let mut s: Vec<char> = mutate(text, rng).chars().collect();
    for _ in 0..rng.below(3) {
        let i = rng.below(s.len() + 1);
        if rng.below(2) == 0 && i < s.len() {
            s.remove(i);
        } else {
            let c = [
                '<', '>', '/', '=', '"', '\'', '$', '&', ';', '!', '-', '?', '0',
            ];
            s.insert(i, c[rng.below(c.len())]);
        }
    }
    s.into_iter().collect()
}

#[test]
fn mutated_mitsuba_xml_never_panics() {
    use kalos::scene::mitsuba as xml;
    let dir = Path::new("/nonexistent-kalos-dir");
    let d = xml::parse(XML, "fuzz.xml", dir).unwrap();
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    assert!(Scene::build(d, 0.0).is_ok());
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let mut loaded = 0;
    // the seed holds every plugin the reader knows, so most mutations break it: 1,000
    // keep enough that load for the loaded path to be fuzzed too
    for _ in 0..1000 {
        let text = mutate_xml(XML, &mut rng);
        no_panic("XML", &text, || match xml::parse(&text, "fuzz.xml", dir) {
            Ok(d) => {
                loaded += 1;
                let n = d.positions.len();
                assert!(d.normals.len() == n && d.uvs.len() == n && d.material.len() == n);
                assert!(d.material.iter().all(|&m| (m as usize) < d.materials.len()));
                assert!(d.positions.iter().flatten().all(|v| v.is_finite()));
                let _ = Scene::build(d, 0.0);
            }
            Err(e) => assert!(e.starts_with("fuzz.xml") && !e.contains('\n'), "{e}"),
        });
    }
    assert!((10..=990).contains(&loaded), "{loaded} of 1000 loaded");
}

/// A binary little-endian PLY: a quad with normals and UVs, a colour per vertex and a
/// weight per face (Mitsuba's mesh attributes `vertex_color`, `face_weight`).
fn ply_seed() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\ncomment fuzz\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 2\nproperty list uchar int vertex_indices\nproperty float weight_0\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n".to_vec();
    for (x, y) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for v in [x, y, 0.0, 0.0, 0.0, 1.0, x, y] {
            b.extend(v.to_le_bytes());
        }
        b.extend([255, 128, 0]);
    }
    for f in [[0i32, 1, 2], [0, 2, 3]] {
        b.push(3);
        for i in f {
            b.extend(i.to_le_bytes());
        }
        b.extend(0.5f32.to_le_bytes());
    }
    b.extend(0i32.to_le_bytes());
    b.extend(1i32.to_le_bytes());
    b
}

#[test]
fn mutated_ply_never_panics() {
    use kalos::scene::ply::parse_ply;
    let seed = ply_seed();
    let m = parse_ply(&seed, "fuzz.ply").unwrap();
    assert_eq!(m.triangles.len(), 2);
    assert_eq!(m.attributes.len(), 2, "vertex_color and face_weight");
    let ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    assert_eq!(
        parse_ply(ascii.as_bytes(), "fuzz.ply")
            .unwrap()
            .triangles
            .len(),
        1
    );
    let header_end = seed.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let mut rng = Rng(0x0ddb_a11c_0ffe_e123);
    let mut loaded = 0;
    for k in 0..400 {
        let mut b = if k % 4 == 3 {
            mutate(ascii, &mut rng).into_bytes()
        } else {
            seed.clone()
        };
        match rng.below(4) {
            // the header as text
            0 if k % 4 != 3 => {
                let head = String::from_utf8_lossy(&b[..header_end]).into_owned();
                let mut m = mutate(&head, &mut rng).into_bytes();
                m.extend_from_slice(b"\n");
                m.extend_from_slice(&b[header_end..]);
                b = m;
            }
            // flip bytes of the payload (counts, indices, floats)
            1 => {
                for _ in 0..1 + rng.below(4) {
                    let i = rng.below(b.len());
                    b[i] = rng.next() as u8;
                }
            }
            // truncate
            2 => {
                let n = rng.below(b.len());
                b.truncate(n);
            }
            _ => {}
        }
        let text = String::from_utf8_lossy(&b).into_owned();
        no_panic("PLY", &text, || match parse_ply(&b, "fuzz.ply") {
            Ok(m) => {
                loaded += 1;
                let n = m.positions.len() as u32;
                assert!(m.triangles.iter().flatten().all(|&i| i < n));
                assert!(m.positions.iter().all(|p| p.is_finite()));
                for a in &m.attributes {
                    let n = if a.per_face {
                        m.triangles.len()
                    } else {
                        m.positions.len()
                    };
                    assert_eq!(a.values.len(), n, "{}", a.name);
                }
            }
            Err(e) => {
                assert!(e.starts_with("fuzz.ply") && !e.contains('\n'), "{e}");
                assert!(!e.contains("gave up"), "the PLY crate panicked: {e}");
            }
        });
    }
    assert!((20..=380).contains(&loaded), "{loaded} of 400 loaded");
}

#[path = "fuzz_inputs/films.rs"]
mod films;

#[path = "fuzz_inputs/serialized.rs"]
mod serialized;

#[path = "fuzz_inputs/vol.rs"]
mod vol;
