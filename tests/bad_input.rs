//! Bad input to the `kalos` binary: every case exits non-zero with a one-line error
//! naming the file and line or the option, and nothing panics. A scene without emitters
//! is the exception: a warning, a black image and exit code 0.

use std::path::{Path, PathBuf};
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-bad-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p.to_str().unwrap().to_string()
}

/// Run kalos; returns (exit code, stdout, stderr).
fn kalos(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args(args)
        .output()
        .expect("run kalos");
    let code = out.status.code().expect("kalos was killed by a signal");
    (
        code,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Render `scene` tiny (8x8, 1 spp, 1 thread unless `extra` says otherwise) into `dir`.
fn render(dir: &Path, scene: &str, extra: &[&str]) -> (i32, String) {
    let out = dir.join("out.exr");
    let mut args = vec!["render", scene];
    let given = |opt: &str| extra.iter().any(|a| a.starts_with(opt));
    if !given("--res") {
        args.extend(["--res", "8x8"]);
    }
    if !given("--spp") && !given("--time") {
        args.extend(["--spp", "1"]);
    }
    if !given("--threads") {
        args.extend(["--threads", "1"]);
    }
    if !given("-o") {
        args.extend(["-o", out.to_str().unwrap()]);
    }
    args.extend_from_slice(extra);
    let (code, _, err) = kalos(&args);
    (code, err)
}

/// A kalos error: exit `code`, one line `kalos: error: ...` containing every needle.
#[track_caller]
fn assert_one_line_error(what: &str, code: i32, stderr: &str, want_code: i32, needles: &[&str]) {
    assert!(!stderr.contains("panicked"), "{what}: panic: {stderr}");
    assert_eq!(code, want_code, "{what}: exit code; stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{what}: not one line: {stderr}");
    assert!(stderr.starts_with("kalos: error: "), "{what}: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{what}: {stderr:?} does not name {n:?}");
    }
}

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn bad_scene_files_give_one_line_errors_with_file_and_line() {
    let d = temp_dir("files");
    let nothing = d.join("nothing.obj");
    let cases: Vec<(&str, String, Vec<String>)> = vec![
        (
            "nonexistent scene",
            nothing.to_str().unwrap().into(),
            vec!["nothing.obj".into()],
        ),
        (
            "nonexistent toml",
            d.join("nothing.toml").to_str().unwrap().into(),
            vec!["nothing.toml".into()],
        ),
        ("unknown scene name", "cornel".into(), vec!["cornel".into()]),
        ("directory", d.to_str().unwrap().into(), vec![]),
        (
            "directory named .obj",
            {
                let p = d.join("dir.obj");
                std::fs::create_dir_all(&p).unwrap();
                p.to_str().unwrap().into()
            },
            vec!["dir.obj".into()],
        ),
        (
            "garbage binary",
            write(
                &d,
                "x.obj",
                [0x7fu8, b'E', b'L', b'F', 2, 1, 1, 0, 0, 0, 0xff, 0xfe],
            ),
            vec!["x.obj:1".into()],
        ),
        (
            "face references vertex 99",
            write(&d, "bad.obj", format!("# a triangle\n\n{TRI}\nf 1 2 99\n")),
            vec!["bad.obj:7".into(), "99".into()],
        ),
        (
            "face with 2 vertices",
            write(&d, "two.obj", format!("{TRI}f 1 2\n")),
            vec!["two.obj:4".into()],
        ),
        (
            "nan vertex",
            write(&d, "nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
            vec!["nan.obj:2".into()],
        ),
        (
            "crlf relative index out of range",
            write(&d, "crlf.obj", "v 0 0 0\r\nv 1 0 0\r\n\r\nf -1 -2 -3\r\n"),
            vec!["crlf.obj:4".into()],
        ),
        (
            "mtl nan",
            {
                write(&d, "nan.mtl", "newmtl a\nKd 0.5 nan 0.2\n");
                write(
                    &d,
                    "mtlnan.obj",
                    format!("mtllib nan.mtl\n{TRI}usemtl a\nf 1 2 3\n"),
                )
            },
            vec!["nan.mtl:2".into(), "Kd".into()],
        ),
        (
            "mtl negative",
            {
                write(&d, "neg.mtl", "# c\nnewmtl a\nKs -1 0 0\n");
                write(
                    &d,
                    "mtlneg.obj",
                    format!("mtllib neg.mtl\n{TRI}usemtl a\nf 1 2 3\n"),
                )
            },
            vec!["neg.mtl:3".into(), "Ks".into()],
        ),
        (
            "missing mtllib",
            write(&d, "nomtl.obj", format!("mtllib gone.mtl\n{TRI}f 1 2 3\n")),
            vec!["nomtl.obj:1".into(), "gone.mtl".into()],
        ),
        (
            "missing map_Kd",
            {
                write(
                    &d,
                    "tex.mtl",
                    "newmtl a\nKe 1 1 1\nmap_Kd textures\\gone.png\n",
                );
                write(
                    &d,
                    "tex.obj",
                    format!("mtllib tex.mtl\n{TRI}usemtl a\nf 1 2 3\n"),
                )
            },
            vec!["gone.png".into()],
        ),
        (
            "toml syntax error",
            write(&d, "syntax.toml", "[[objects]]\nfile = \"a.obj\n"),
            vec!["syntax.toml:2".into()],
        ),
        (
            "toml unknown key",
            {
                write(&d, "a.obj", format!("{TRI}f 1 2 3\n"));
                write(
                    &d,
                    "key.toml",
                    "[[objects]]\nfile = \"a.obj\"\n\n[render]\nsamples = 4\n",
                )
            },
            vec!["key.toml:5".into(), "samples".into()],
        ),
        (
            "toml missing object file",
            write(&d, "missing.toml", "[[objects]]\nfile = \"nope.obj\"\n"),
            vec!["missing.toml".into(), "nope.obj".into()],
        ),
        (
            "toml override of a missing material",
            write(
                &d,
                "ovr.toml",
                "[[objects]]\nfile = \"a.obj\"\n[materials.gold]\nks = [1, 1, 1]\n",
            ),
            vec!["ovr.toml".into(), "gold".into()],
        ),
    ];
    for (what, scene, needles) in &cases {
        let (code, err) = render(&d, scene, &[]);
        let needles: Vec<&str> = needles.iter().map(|s| s.as_str()).collect();
        assert_one_line_error(what, code, &err, 1, &needles);
        // `kalos info` reports the same errors
        let (code, _, err) = kalos(&["info", scene]);
        assert_one_line_error(what, code, &err, 1, &needles);
    }
}

#[test]
fn bad_options_give_one_line_errors_naming_the_option() {
    let d = temp_dir("options");
    // checked by kalos after parsing: exit 1
    for (what, extra, needles) in [
        (
            "unknown extension",
            &["-o", "out.tga"][..],
            &["out.tga"][..],
        ),
        ("exposure nan", &["--exposure", "nan"], &["--exposure"]),
    ] {
        let (code, err) = render(&d, "cornell", extra);
        assert_one_line_error(what, code, &err, 1, needles);
    }
    // rejected by the option parsers: usage errors, exit 2, still one line
    for (what, extra, needles) in [
        ("spp 0", &["--spp", "0"][..], &["--spp"][..]),
        ("threads 0", &["--threads", "0"], &["--threads"]),
        ("res 0x0", &["--res", "0x0"], &["--res", "0x0"]),
        (
            "res too large",
            &["--res", "100000x100000"],
            &["--res", "GiB"],
        ),
        ("res abc", &["--res", "abc"], &["--res", "abc"]),
        ("res overflow", &["--res", "99999999999x2"], &["--res"]),
        ("max depth 0", &["--max-depth", "0"], &["--max-depth"]),
        ("spp negative", &["--spp=-1"], &["--spp"]),
        (
            "bad camera",
            &["--camera", "0,0,1,0,0,1,0,1,0,40"],
            &["--camera"],
        ),
        ("time 0", &["--time", "0"], &["--time"]),
        ("sampler", &["--sampler", "halton"], &["--sampler"]),
    ] {
        let (code, err) = render(&d, "cornell", extra);
        assert_one_line_error(what, code, &err, 2, needles);
    }
    // unknown options: clap's own message (with a tip), exit 2
    let (code, _, err) = kalos(&["render", "cornell", "--frobnicate"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--frobnicate"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let (code, _, err) = kalos(&["render"]);
    assert_eq!(code, 2, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!d.join("out.exr").exists(), "an image was written");
}

#[test]
fn a_scene_without_emitters_warns_and_renders_black() {
    let d = temp_dir("dark");
    let scene = write(&d, "dark.obj", format!("{TRI}f 1 2 3\n"));
    let (code, err) = render(&d, &scene, &["--quiet"]);
    // --quiet hides warnings; render again without it
    assert_eq!(code, 0, "{err}");
    let (code, err) = render(&d, &scene, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("kalos: warning:"))
        .collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(warnings[0].contains("no emitter"), "{err}");
    let img = kalos::image_io::read_image(&d.join("out.exr")).unwrap();
    assert_eq!((img.width, img.height), (8, 8));
    assert!(img.data.iter().all(|p| *p == [0.0; 3]), "not black");
}

#[test]
fn info_counts_skipped_zero_area_faces() {
    let d = temp_dir("info");
    let scene = write(
        &d,
        "flat.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nf 4 4 4\n",
    );
    let (code, out, err) = kalos(&["info", &scene]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("skipped      2 zero-area faces"), "{out}");
    assert!(err.contains("skipped 2 zero-area faces"), "{err}");
    let (code, out, _) = kalos(&["info", "--json", &scene]);
    assert_eq!(code, 0);
    assert!(out.contains("\"skipped_degenerate\": 2"), "{out}");
}
