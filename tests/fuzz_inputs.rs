//! Hand-rolled fuzzing: randomly mutated OBJ, MTL and TOML text (lines deleted,
//! duplicated, swapped, numbers replaced by huge/negative/NaN/garbage tokens, truncated)
//! must load or fail with an error, never panic.

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
    let sep = if rng.below(4) == 0 { "\r\n" } else { "\n" };
    lines.join(sep)
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
    let seed = format!("{MTL}map_Kd -s 1 1 1 -o 0 0 0 t\\x.png\n");
    assert_eq!(mtl::parse_mtl(&seed, "fuzz.mtl", dir).unwrap().len(), 3);
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
