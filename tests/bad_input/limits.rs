//! Input that would overflow, hang or take the machine's memory (emitters beyond single
//! precision, images that declare billions of bytes, DTF options without end, an
//! interrupt while a scene loads), and messages that named the wrong thing.

use super::experiments::{assert_experiment_refused, experiment_text, ONE_CONFIG};
use super::{assert_one_line_error, kalos, kalos_within, render, temp_dir, write};
use std::process::Command;

const QUAD: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n";

/// An emitter whose power overflows (MTL Ke, a TOML ke override, a TOML point light):
/// one line naming where it is defined (it panicked in the light choice, or the point
/// light vanished from a black image).
#[test]
fn emitters_beyond_single_precision_are_named() {
    let d = temp_dir("too-bright");
    write(
        &d,
        "l.mtl",
        "newmtl light\nKd 0 0 0\nKe 3e38 3e38 3e38\nnewmtl w\nKd 0.5 0.5 0.5\n",
    );
    let obj = format!("mtllib l.mtl\n{QUAD}usemtl light\nf 1 2 3 4\nusemtl w\nf 1 3 2\n");
    write(&d, "mtl.obj", obj);
    write(&d, "w.mtl", "newmtl w\nKd 0.5 0.5 0.5\n");
    write(
        &d,
        "w.obj",
        format!("mtllib w.mtl\n{QUAD}usemtl w\nf 1 2 3 4\n"),
    );
    let objects = "[[objects]]\nfile = \"w.obj\"\n\n";
    let ke = format!("{objects}[materials.w]\nke = [1e38, 1e38, 1e38]\n");
    let point = format!(
        "{objects}[[point_lights]]\nposition = [0, 0, 1]\nintensity = [1e38, 1e38, 1e38]\n"
    );
    let cases = [
        ("mtl.obj", None, ["l.mtl:1", "'light'"]),
        ("ke.toml", Some(ke), ["ke.toml:4", "materials.w"]),
        ("point.toml", Some(point), ["point.toml:4", "point light"]),
    ];
    for (name, text, needles) in cases {
        let scene = match text {
            Some(t) => write(&d, name, t),
            None => d.join(name).to_str().unwrap().to_string(),
        };
        let (code, err) = render(&d, &scene, &[]);
        assert_one_line_error(name, code, &err, 1, &[needles[0], needles[1], "power"]);
    }
}

/// CRC-32 (PNG's chunk checksum).
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A PNG that declares `w` x `h` RGB pixels and holds one empty compressed row: a few
/// dozen bytes whose header asks for gigabytes.
fn png_declaring(w: u32, h: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |kind: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    // zlib: a stored empty block
    chunk(
        b"IDAT",
        &[
            0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0x00, 0x00, 0x00, 0x01,
        ],
    );
    chunk(b"IEND", &[]);
    out
}

/// Images whose header declares more pixels than the input limit allows are refused
/// from the header, before decoding (13000 x 13000 panicked in `compare` under a 4 GB
/// address-space limit; 12000 x 12000 took 2 GB as a texture).
#[test]
fn images_declaring_too_many_pixels_are_refused_before_decoding() {
    let d = temp_dir("huge-image");
    let big = write(&d, "big.png", png_declaring(13000, 13000));
    let (code, _, err) = kalos_within(20, &["compare", &big, &big]);
    assert_one_line_error(
        "compare",
        code,
        &err,
        1,
        &["big.png", "13000x13000", "limit"],
    );
    write(&d, "tex.png", png_declaring(12000, 12000));
    write(&d, "t.mtl", "newmtl t\nKd 1 1 1\nmap_Kd tex.png\n");
    let obj = write(
        &d,
        "t.obj",
        format!("mtllib t.mtl\n{QUAD}vt 0 0\nusemtl t\nf 1/1 2/1 3/1\n"),
    );
    let (code, _, err) = kalos_within(20, &["info", &obj]);
    assert_one_line_error(
        "map_Kd",
        code,
        &err,
        1,
        &["tex.png", "12000x12000", "limit"],
    );
}

/// DTF options that would run without end are refused before any work, naming the flag.
#[test]
fn dtf_options_without_end_are_refused_at_once() {
    let cases: &[(&[&str], &[&str])] = &[
        (&["--dtf-eps", "1e-9"], &["--dtf-eps 1e-9"]),
        (
            &["--spp", "4", "--dtf-n", "4294967295"],
            &["--dtf-n 4294967295"],
        ),
        (
            &["--spp", "4", "--dtf-n", "16", "--res", "4096x4096"],
            &["--spp 4", "--dtf-n 16"],
        ),
        (&["--dtf-mmax", "99"], &["--dtf-mmax 99"]),
    ];
    let d = temp_dir("dtf-limits");
    let out = d.join("o.exr");
    for (opts, needles) in cases {
        let mut args = vec![
            "render",
            "cornell",
            "--method",
            "dtf",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(opts);
        let (code, _, err) = kalos_within(10, &args);
        assert_one_line_error(&format!("{opts:?}"), code, &err, 1, needles);
        assert!(!err.contains("m_max") && !err.contains("eps_r ="), "{err}");
    }
}

/// SIGTERM while a scene loads, or during DTF's phases (which cannot stop part-way):
/// the process ends at once with a message (it went on loading, and DTF ran to its end).
#[test]
fn sigterm_ends_loading_and_dtf_at_once() {
    let d = temp_dir("sigterm");
    // a mesh that takes seconds to load: 600k triangles
    let mut obj = String::with_capacity(40 << 20);
    let n = 775;
    for y in 0..n {
        for x in 0..n {
            obj.push_str(&format!("v {x} {y} {}\n", (x * y) % 7));
        }
    }
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let i = y * n + x + 1;
            obj.push_str(&format!("f {i} {} {}\n", i + 1, i + n));
        }
    }
    let big = write(&d, "big.obj", obj);
    let out = d.join("o.exr");
    let runs: [Vec<&str>; 2] = [
        vec!["render", &big, "--spp", "1", "--res", "8x8"],
        vec![
            "render", "cornell", "--method", "dtf", "--spp", "100000", "--res", "64x64",
        ],
    ];
    for (args, wait_ms) in runs.iter().zip([300u64, 1500]) {
        let child = Command::new(env!("CARGO_BIN_EXE_kalos"))
            .args(args)
            .args(["-q", "-o", out.to_str().unwrap()])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(wait_ms));
        let mut child = child;
        assert!(
            child.try_wait().unwrap().is_none(),
            "{args:?} ended before the signal"
        );
        let t0 = std::time::Instant::now();
        let ok = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
        while child.try_wait().unwrap().is_none() && t0.elapsed().as_secs() < 5 {
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let secs = t0.elapsed().as_secs_f64();
        if child.try_wait().unwrap().is_none() {
            child.kill().ok();
        }
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            secs < 1.0,
            "{args:?}: still running {secs:.1} s after SIGTERM: {err}"
        );
        assert_eq!(o.status.code(), Some(130), "{args:?}: {err}");
        assert!(err.contains("interrupted"), "{err}");
    }
}

/// clap's usage errors are one line each, like every other error (they spanned four to
/// five lines, with a usage and a tip).
#[test]
fn usage_errors_are_one_line() {
    let cases: &[(&[&str], &str)] = &[
        (&["--spp", "-1"], "--spp"),
        (&["--time", "-1"], "--time"),
        (&["--res", "-16x16"], "--res"),
        (&["--first-sample", "-1"], "--first-sample"),
        (&["--dtf-topup", "-1"], "--dtf-topup"),
        (&["--dtf-z", "-3"], "--dtf-z"),
        (&["--radiosity-tolerance", "-1"], "--radiosity-tolerance"),
        (&["--time", "1", "--spp", "4"], "--spp"),
        (&["--spp", "8", "--spp", "4"], "--spp"),
    ];
    let d = temp_dir("usage");
    let out = d.join("x.exr");
    for (opts, needle) in cases {
        let mut args = vec!["render", "cornell", "-o", out.to_str().unwrap()];
        args.extend_from_slice(opts);
        let (code, _, err) = kalos(&args);
        assert!(code == 1 || code == 2, "{opts:?}: {err}");
        assert_one_line_error(&format!("{opts:?}"), code, &err, code, &[needle]);
    }
}

/// Careless input that was accepted in silence or named the wrong thing.
#[test]
fn careless_input_is_named() {
    let d = temp_dir("careless");
    // a PLY header declaring 1 face with 2 in the data (rendered half the mesh)
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
               property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    write(&d, "m.ply", ply);
    let xml = r#"<scene version="3.0.0"><shape type="ply"><string name="filename" value="m.ply"/></shape></scene>"#;
    let scene = write(&d, "m.xml", xml);
    let (code, _, err) = kalos(&["info", &scene]);
    assert_one_line_error("ply count", code, &err, 1, &["m.ply", "1 face", "header"]);
    // a PLY value that is not a number: no parser debug text
    write(
        &d,
        "m.ply",
        ply.replace("1 1 0\n", "1 1 x\n").replace("3 0 2 3\n", ""),
    );
    let (code, _, err) = kalos(&["info", &scene]);
    assert_one_line_error("ply value", code, &err, 1, &["m.ply:12", "vertex"]);
    assert!(
        !err.contains("Error") && !err.contains("String:") && !err.contains('{'),
        "{err}"
    );
    // a TOML [[objects]] file that is a scene, not an OBJ (read as an empty OBJ: black)
    let toml = write(&d, "t.toml", "# scene\n\n[[objects]]\nfile = \"m.xml\"\n");
    let (code, _, err) = kalos(&["info", &toml]);
    assert_one_line_error(
        "toml object",
        code,
        &err,
        1,
        &["t.toml:3", "m.xml", "not an OBJ"],
    );
    // TOML content errors name the line
    write(&d, "w.obj", format!("{QUAD}f 1 2 3 4\n"));
    let toml = write(
        &d,
        "r.toml",
        "[[objects]]\nfile = \"w.obj\"\n\n[render]\nspp = 0\n",
    );
    let (code, _, err) = kalos(&["info", &toml]);
    assert_one_line_error("toml render", code, &err, 1, &["r.toml:4", "spp"]);
    // radiosity errors name the scene's path
    let obj = write(&d, "dark.obj", format!("{QUAD}f 1 2 3 4\n"));
    let (code, _, err) = kalos(&["radiosity", &obj, "-o", d.join("r.ply").to_str().unwrap()]);
    assert!(err.lines().count() <= 2, "{err}");
    let last = err.lines().last().unwrap_or_default();
    assert_one_line_error("radiosity", code, last, 1, &[obj.as_str(), "no emitter"]);
    // coordinates that overflow are not "zero-area"
    let obj = write(
        &d,
        "far.obj",
        "v 0 0 0\nv 1e20 0 0\nv 0 1e20 0\nf 1 2 3\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n",
    );
    let (code, out, err) = kalos(&["info", &obj, "--json"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("\"skipped_degenerate\": 0") && out.contains("\"skipped_nonfinite\": 1"),
        "{out}"
    );
    assert!(
        err.contains("not finite") && !err.contains("zero-area"),
        "{err}"
    );
}

/// An experiment's `exposure = nan` (blank crops), and options of a single render that an
/// experiment does not honour (`-o`, `--stats`, `--dask`: ignored without a word).
#[test]
fn experiment_exposure_and_single_render_options_are_refused() {
    let d = temp_dir("experiment-careless");
    let text = experiment_text("exposure = nan", "constant = 0.5", ONE_CONFIG);
    assert_experiment_refused(&d, "nan", &text, &["exposure"]);
    for (opt, name) in [
        ("-o x.exr", "-o"),
        ("--output=x.exr", "--output"),
        ("--stats s.json", "--stats"),
        ("--dask tcp://h:1", "--dask"),
    ] {
        let cfgs = format!("[[config]]\nname = \"a\"\noptions = \"{opt}\"\n");
        let text = experiment_text("", "constant = 0.5", &cfgs);
        assert_experiment_refused(&d, "opt", &text, &[name, "the experiment"]);
    }
}
