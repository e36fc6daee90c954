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
            vec!["tex.mtl:1: material 'a'".into(), "gone.png".into()],
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
        (
            "gather rays 0",
            &["--gather", "radiosity", "--gather-rays", "0"],
            &["--gather-rays 0"],
        ),
        (
            "gather depth 0",
            &["--gather", "radiosity", "--gather-depth", "0"],
            &["--gather-depth"],
        ),
        (
            "gather rays too many",
            &["--gather", "radiosity", "--gather-rays", "5000"],
            &["--gather-rays 5000"],
        ),
        (
            "dtf light share out of range",
            &[
                "--method",
                "dtf",
                "--integrator",
                "bdpt",
                "--spp",
                "16",
                "--dtf-light-share",
                "1.5",
            ],
            &["--dtf-light-share 1.5"],
        ),
        (
            "dtf stop ratio below 1",
            &["--method", "dtf", "--spp", "16", "--dtf-stop-ratio", "0.5"],
            &["--dtf-stop-ratio 0.5"],
        ),
        (
            "radiosity L~ without the estimate roulette",
            &["--rr-estimate", "radiosity"],
            &["--rr-estimate radiosity", "--rr estimate"],
        ),
        (
            "radiosity L~ under bdpt",
            &[
                "--rr",
                "estimate",
                "--rr-estimate",
                "radiosity",
                "--integrator",
                "bdpt",
            ],
            &["--rr-estimate radiosity", "bdpt"],
        ),
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
        (
            "dtf direct mode",
            &["--method", "dtf", "--dtf-direct", "maybe"],
            &["--dtf-direct"],
        ),
        (
            "rr estimate source",
            &["--rr-estimate", "photons"],
            &["--rr-estimate"],
        ),
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
    // --quiet hides the progress and the summary, never a warning
    for quiet in [&["--quiet"][..], &[]] {
        let (code, err) = render(&d, &scene, quiet);
        assert_eq!(code, 0, "{err}");
        assert!(!err.contains("panicked"), "{err}");
        let warnings: Vec<&str> = err
            .lines()
            .filter(|l| l.starts_with("kalos: warning:"))
            .collect();
        assert_eq!(warnings.len(), 1, "{quiet:?}: {err}");
        assert!(warnings[0].contains("no emitter"), "{err}");
        assert_eq!(
            err.lines().count(),
            if quiet.is_empty() { 2 } else { 1 },
            "{err}"
        );
    }
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

// ---- hostile and careless input ------------------------------------------------------

/// A little-endian PFM (negative scale) of `w` x `h` RGB pixels, all of value `v` except
/// the first, which is `first`.
fn pfm(w: u32, h: u32, v: f32, first: f32) -> Vec<u8> {
    let mut out = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for i in 0..w * h * 3 {
        let x = if i < 3 { first } else { v };
        out.extend_from_slice(&x.to_le_bytes());
    }
    out
}

#[test]
fn compare_refuses_nan_infinite_and_empty_images_naming_the_file() {
    let d = temp_dir("compare");
    let good = write(&d, "good.pfm", pfm(2, 2, 0.5, 0.5));
    let also = write(&d, "also.pfm", pfm(2, 2, 0.5, 0.25));
    let (code, out, err) = kalos(&["compare", &also, &good]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("rmse"), "{out}");
    let bad = [
        ("nan.pfm", pfm(2, 2, 0.5, f32::NAN), "NaN"),
        ("allnan.pfm", pfm(2, 2, f32::NAN, f32::NAN), "NaN"),
        ("inf.pfm", pfm(2, 2, 0.5, f32::INFINITY), "infinite"),
        ("empty.pfm", pfm(0, 0, 0.0, 0.0), "0x0"),
    ];
    for (name, bytes, what) in bad {
        let p = write(&d, name, bytes);
        for args in [["compare", &p, &good], ["compare", &good, &p]] {
            let (code, _, err) = kalos(&args);
            assert_one_line_error(name, code, &err, 1, &[name, what]);
        }
    }
}

/// Run kalos, killing it (and failing) if it takes more than `secs` seconds.
fn kalos_within(secs: u64, args: &[&str]) -> (i32, String, String) {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run kalos");
    let t0 = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let (mut out, mut err) = (String::new(), String::new());
            child
                .stdout
                .take()
                .unwrap()
                .read_to_string(&mut out)
                .unwrap();
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            return (status.code().expect("killed by a signal"), out, err);
        }
        if t0.elapsed().as_secs() >= secs {
            child.kill().ok();
            child.wait().ok();
            panic!("kalos {args:?} did not finish within {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[cfg(unix)]
#[test]
fn special_files_are_named_for_what_they_are_and_never_read() {
    use std::os::unix::fs::symlink;
    let d = temp_dir("special");
    let mkfifo = |name: &str| {
        let p = d.join(name);
        let ok = Command::new("mkfifo").arg(&p).status().unwrap().success();
        assert!(ok, "mkfifo {}", p.display());
        p.to_str().unwrap().to_string()
    };
    let fifo_toml = mkfifo("fifo.toml");
    let fifo_obj = mkfifo("fifo.obj");
    mkfifo("fifo.mtl");
    mkfifo("fifo.png");
    let fifo_exr = mkfifo("fifo.exr");
    std::fs::create_dir(d.join("dir.obj")).unwrap();
    std::fs::create_dir(d.join("dir.toml")).unwrap();
    symlink("/dev/zero", d.join("zero.toml")).unwrap();
    symlink("/dev/zero", d.join("zero.obj")).unwrap();
    symlink("/dev/zero", d.join("zero.pfm")).unwrap();
    let s = |n: &str| d.join(n).to_str().unwrap().to_string();
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\n";
    let mtl_zero = write(&d, "mz.obj", format!("mtllib /dev/zero\n{tri}"));
    let mtl_fifo = write(&d, "mf.obj", format!("mtllib fifo.mtl\n{tri}"));
    write(&d, "t.mtl", "newmtl t\nmap_Kd fifo.png\n");
    let tex_fifo = write(&d, "tf.obj", format!("mtllib t.mtl\n{tri}"));
    let toml_obj =
        |name: &str, obj: &str| write(&d, name, format!("[[objects]]\nfile = \"{obj}\"\n"));
    let toml_fifo = toml_obj("of.toml", "fifo.obj");
    let toml_dir = toml_obj("od.toml", "dir.obj");
    let toml_zero = toml_obj("oz.toml", "zero.obj");
    let good = write(&d, "good.pfm", pfm(2, 2, 0.5, 0.5));
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (
            vec!["info".into(), fifo_toml.clone()],
            vec!["fifo.toml", "FIFO"],
        ),
        (vec!["info".into(), fifo_obj], vec!["fifo.obj", "FIFO"]),
        (
            vec!["info".into(), s("dir.obj")],
            vec!["dir.obj", "directory"],
        ),
        (
            vec!["info".into(), s("dir.toml")],
            vec!["dir.toml", "directory"],
        ),
        (
            vec!["info".into(), s("zero.toml")],
            vec!["zero.toml", "character device"],
        ),
        (
            vec!["info".into(), s("zero.obj")],
            vec!["zero.obj", "character device"],
        ),
        (
            vec!["info".into(), mtl_zero],
            vec!["/dev/zero", "character device"],
        ),
        (vec!["info".into(), mtl_fifo], vec!["fifo.mtl", "FIFO"]),
        (vec!["info".into(), tex_fifo], vec!["fifo.png", "FIFO"]),
        (vec!["info".into(), toml_fifo], vec!["fifo.obj", "FIFO"]),
        (vec!["info".into(), toml_dir], vec!["dir.obj", "directory"]),
        (
            vec!["info".into(), toml_zero],
            vec!["zero.obj", "character device"],
        ),
        (
            vec!["compare".into(), fifo_exr, good.clone()],
            vec!["fifo.exr", "FIFO"],
        ),
        (
            vec!["compare".into(), good, s("zero.pfm")],
            vec!["zero.pfm", "character device"],
        ),
        (
            vec!["experiment".into(), fifo_toml],
            vec!["fifo.toml", "FIFO"],
        ),
    ];
    for (args, needles) in cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = kalos_within(30, &a);
        assert_one_line_error(&args.join(" "), code, &err, 1, &needles);
    }
}

#[test]
fn two_outputs_on_one_path_are_refused() {
    let d = temp_dir("same");
    let out = d.join("same.pfm").display().to_string();
    let (code, err) = render(&d, "cornell", &["-o", &out, "--stats", &out]);
    assert_one_line_error(
        "--stats = -o",
        code,
        &err,
        1,
        &["--stats", "same.pfm", "two outputs"],
    );
    assert!(!Path::new(&out).exists(), "nothing is written");
    // an output folder that does not exist is refused before the work
    let (code, err) = render(&d, "cornell", &["-o", "/nonexistent-kalos-dir/x.exr"]);
    assert_one_line_error("missing folder", code, &err, 1, &["does not exist"]);
}

#[test]
fn dask_renders_without_python_or_the_module_are_refused() {
    let d = temp_dir("dask");
    let out = d.join("x.exr").display().to_string();
    let run = |python: &str, extra: &[&str]| {
        let mut args = vec![
            "render",
            "cornell",
            "-o",
            &out,
            "--dask",
            "tcp://127.0.0.1:9",
        ];
        args.extend_from_slice(extra);
        let o = Command::new(env!("CARGO_BIN_EXE_kalos"))
            .args(&args)
            .env("KALOS_PYTHON", python)
            .output()
            .unwrap();
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = run("/nonexistent/python3", &[]);
    assert_one_line_error(
        "no python",
        code,
        &err,
        1,
        &["--dask", "cannot run", "KALOS_PYTHON"],
    );
    // an interpreter that cannot import the module (`false` exits 1 at once)
    let (code, err) = run("/bin/false", &[]);
    assert_one_line_error(
        "no module",
        code,
        &err,
        1,
        &["--dask", "cannot import the kalos module", "pip install"],
    );
    assert!(!Path::new(&out).exists(), "nothing is written");
    // (what cannot be distributed, --time, --method rw or one-process layers, is refused
    // by the module: python/tests/test_distributed.py)
}

#[test]
fn black_images_and_ignored_options_are_warned() {
    let d = temp_dir("warn");
    // a camera looking away from the Cornell box: all black
    let (code, err) = render(&d, "cornell", &["--camera", "0,1,20,0,1,40,0,1,0,30"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning: the image is all black"), "{err}");
    // the box seen: no such warning
    let (code, err) = render(&d, "cornell", &[]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("all black"), "{err}");
    // --aovs with a PNG
    let png = d.join("o.png").display().to_string();
    let (code, err) = render(&d, "cornell", &["--aovs", "-o", &png]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning: --aovs"), "{err}");
    // absurd thread counts are capped, with a warning, and the render ends
    let (code, _, err) = kalos_within(
        60,
        &[
            "render",
            "cornell",
            "--res",
            "4x4",
            "--spp",
            "1",
            "--threads",
            "100000",
            "-o",
            &png,
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("--threads 100000: capped"), "{err}");
}

/// SIGTERM (as Ctrl-C) writes the passes rendered so far, says so, exits non-zero; a
/// render with stderr on a pipe prints progress lines; a huge render says what it plans.
#[test]
fn an_interrupted_render_writes_what_it_has() {
    let d = temp_dir("interrupt");
    let out = d.join("part.exr");
    let child = Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args([
            "render",
            "cornell",
            "--method",
            "plain",
            "--res",
            "32x32",
            "--spp",
            "4294967295",
            "--threads",
            "1",
        ])
        .arg("-o")
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(3500));
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("samples planned"), "{err}");
    assert!(
        err.contains("samples/s") && err.contains('%'),
        "no progress lines: {err}"
    );
    assert!(err.contains("interrupted"), "{err}");
    let img = kalos::image_io::read_image(&out).unwrap();
    assert!(
        img.mean().iter().all(|&m| m > 0.05),
        "the image is not rendered"
    );
}

/// `--method rw` with a D that is not a positive number, and `kalos filter energy` on an
/// EXR without the `--aovs` layers (or on no EXR at all): one-line errors.
#[test]
fn rw_bad_d_and_filter_energy_without_layers() {
    let d = temp_dir("rw");
    for v in ["0", "-1", "nan"] {
        let (code, err) = render(&d, "cornell", &["--method", "rw", "--rw-d", v]);
        assert_one_line_error(&format!("--rw-d {v}"), code, &err, 1, &["--rw-d"]);
    }
    let plain = d.join("plain.exr");
    let (code, err) = render(&d, "cornell", &["-o", plain.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let out = d.join("f.exr");
    let (code, _, err) = kalos(&[
        "filter",
        "energy",
        plain.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_one_line_error(
        "filter energy without layers",
        code,
        &err,
        1,
        &["plain.exr", "--aovs"],
    );
    let (code, _, err) = kalos(&[
        "filter",
        "energy",
        plain.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--rw-d",
        "-2",
    ]);
    assert_one_line_error("filter energy --rw-d -2", code, &err, 1, &["--rw-d"]);
    // with the layers it works
    let aov = d.join("aov.exr");
    let (code, err) = render(
        &d,
        "cornell",
        &["--spp", "8", "--aovs", "-o", aov.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = kalos(&[
        "filter",
        "energy",
        aov.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.is_file());
}

/// The radiosity preprocess (`--gather radiosity`, `--method rw`, `kalos radiosity`): a
/// mesh too fine for memory and a scene with no diffuse surface give one-line errors
/// naming the option or the scene, before anything is allocated or rendered.
#[test]
fn radiosity_too_fine_a_mesh_and_no_diffuse_surface() {
    let d = temp_dir("radiosity");
    let ply = d.join("r.ply");
    let ply = ply.to_str().unwrap();
    for area in ["1e-9", "1e-12"] {
        let (code, err) = render(
            &d,
            "cornell",
            &["--gather", "radiosity", "--radiosity-max-area", area],
        );
        assert_one_line_error(
            &format!("--radiosity-max-area {area}"),
            code,
            &err,
            1,
            &["--radiosity-max-area", "elements", "GiB"],
        );
    }
    // more elements allowed than memory holds: the byte limit still refuses it
    let (code, _, err) = kalos(&[
        "radiosity",
        "cornell",
        "-o",
        ply,
        "--radiosity-max-area",
        "1e-7",
        "--radiosity-max-elements",
        "100000000000",
    ]);
    assert_one_line_error("radiosity 1e-7", code, &err, 1, &["GiB"]);
    // a mirror and an emitter: nothing for the solver to solve
    write(
        &d,
        "nd.mtl",
        "newmtl m\nKd 0 0 0\nKs 1 1 1\nillum 3\nnewmtl l\nKd 0 0 0\nKe 5 5 5\n",
    );
    let obj = write(
        &d,
        "nd.obj",
        "mtllib nd.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nusemtl m\nf 1 2 3\nusemtl l\nf 4 6 5\n",
    );
    for extra in [
        vec!["--gather", "radiosity"],
        vec!["--integrator", "radiosity"],
        vec!["--method", "rw", "--gather", "radiosity"],
    ] {
        let (code, err) = render(&d, &obj, &extra);
        assert_one_line_error(
            &format!("no diffuse surface, {extra:?}"),
            code,
            &err,
            1,
            &["nd", "no diffuse surface"],
        );
    }
    let (code, _, err) = kalos(&["radiosity", &obj, "-o", ply]);
    assert_one_line_error(
        "kalos radiosity nd.obj",
        code,
        &err,
        1,
        &["no diffuse surface"],
    );
    assert!(!std::path::Path::new(ply).exists());
}

#[test]
fn bad_mitsuba_xml_and_ply_give_one_line_errors() {
    let d = temp_dir("xml");
    let head = "<scene version=\"3.0.0\">\n";
    let ply_ok = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    write(
        &d,
        "bad-header.ply",
        ply_ok.replace("element vertex 3", "element vertex three"),
    );
    write(&d, "short.ply", &ply_ok[..ply_ok.len() - 10]);
    write(&d, "sky.exr", "this is not an image");
    let shape = |f: &str| {
        format!("<shape type=\"ply\"><string name=\"filename\" value=\"{f}\"/></shape>\n")
    };
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "malformed.xml",
            format!("{head}<shape type=\"cube\">\n  <bsdf type=\"diffuse\"\n</scene>\n"),
            vec!["malformed.xml:4:", "malformed XML"],
        ),
        (
            "ref.xml",
            format!("{head}<shape type=\"cube\">\n<ref id=\"nope\"/></shape></scene>"),
            vec!["ref.xml:3:", "<ref id=\"nope\">", "no element has that id"],
        ),
        (
            "plugin.xml",
            format!("{head}<shape type=\"cube\"><bsdf type=\"velvet\"/></shape></scene>"),
            vec!["plugin.xml:2:", "unknown bsdf plugin 'velvet'"],
        ),
        (
            "plyhead.xml",
            format!("{head}{}</scene>", shape("bad-header.ply")),
            vec!["plyhead.xml:2:", "bad-header.ply:3: bad PLY header"],
        ),
        (
            "plyshort.xml",
            format!("{head}{}</scene>", shape("short.ply")),
            vec!["plyshort.xml:2:", "short.ply:12: PLY element"],
        ),
        (
            "env.xml",
            format!(
                "{head}<shape type=\"cube\"/>\n<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/></emitter></scene>"
            ),
            vec!["env.xml:3:", "sky.exr: not an image"],
        ),
    ];
    for (name, text, needles) in cases {
        let scene = write(&d, name, text);
        let (code, err) = render(&d, &scene, &[]);
        assert_one_line_error(name, code, &err, 1, &needles);
    }
}

#[path = "bad_input/experiments.rs"]
mod experiments;
#[path = "bad_input/films.rs"]
mod films;
#[path = "bad_input/limits.rs"]
mod limits;
