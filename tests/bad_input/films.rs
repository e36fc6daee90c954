//! Film parts and their merges: 64-bit sample ranges, the job key's scene content, the
//! film file's checksum and its outputs' options.

use super::{assert_one_line_error, kalos, temp_dir, write};
use std::path::Path;

/// Render `scene` at 4x4, 1 thread, into film part `out` with more options.
fn part(scene: &str, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args = vec![
        "render",
        scene,
        "--res",
        "4x4",
        "--threads",
        "1",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = kalos(&args);
    (code, err)
}

/// `--first-sample` past 2^32 renders those samples (it wrapped onto sample 0 when the
/// option was 32-bit, and 2^32 itself was refused), and a range past 2^64 is refused.
#[test]
fn first_sample_is_64_bit_and_never_wraps() {
    let d = temp_dir("first-sample");
    let (a, b) = (d.join("a.kfilm"), d.join("b.kfilm"));
    let (code, err) = part("cornell", &a, &["--spp", "1"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = part(
        "cornell",
        &b,
        &["--spp", "1", "--first-sample", "4294967296"],
    );
    assert_eq!(code, 0, "{err}");
    let fa = kalos::film::read_film(&a).unwrap();
    let fb = kalos::film::read_film(&b).unwrap();
    assert_eq!(fb.ranges, vec![(1 << 32, (1 << 32) + 1)]);
    assert_ne!(
        fa.film.pixels, fb.film.pixels,
        "sample 2^32 is not sample 0"
    );
    let out = d.join("ab.kfilm");
    let (code, _, err) = kalos(&[
        "merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        kalos::film::read_film(&out).unwrap().ranges,
        vec![(0, 1), (1 << 32, (1 << 32) + 1)]
    );
    for first in ["18446744073709551615", "18446744073709551614"] {
        let (code, err) = part(
            "cornell",
            &d.join("c.kfilm"),
            &["--spp", "2", "--first-sample", first],
        );
        assert_one_line_error(first, code, &err, 1, &["--first-sample", first]);
    }
}

/// The merge key holds the content of the scene's files, not their path: `s.obj` and
/// `./s.obj` merge, a part of the scene edited in between is refused.
#[test]
fn merge_key_is_the_scene_content_not_its_path() {
    let d = temp_dir("merge-key");
    let mtl = "newmtl l\nKe 5 5 5\nnewmtl w\nKd 0.5 0.5 0.5\n";
    write(&d, "s.mtl", mtl);
    let obj = "mtllib s.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl w\nf 1 2 3 4\n\
               v -1 -1 2\nv -1 1 2\nv 1 1 2\nusemtl l\nf 5 6 7\n";
    write(&d, "s.obj", obj);
    let run = |scene: &str, first: &str, out: &str| {
        let out = d.join(out);
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_kalos"));
        c.current_dir(&d).args([
            "render",
            scene,
            "--res",
            "4x4",
            "--spp",
            "1",
            "--threads",
            "1",
            "-q",
            "--first-sample",
            first,
            "-o",
        ]);
        let o = c.arg(&out).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out.to_str().unwrap().to_string()
    };
    let a = run("s.obj", "0", "a.kfilm");
    let b = run("./s.obj", "1", "b.kfilm");
    let merged = d.join("ab.exr");
    let (code, _, err) = kalos(&["merge", &a, &b, "-o", merged.to_str().unwrap()]);
    assert_eq!(code, 0, "s.obj and ./s.obj are one scene: {err}");
    // the material library edited: another scene
    write(&d, "s.mtl", mtl.replace("Kd 0.5", "Kd 0.25"));
    let c = run("s.obj", "2", "c.kfilm");
    let (code, _, err) = kalos(&["merge", &a, &c, "-o", merged.to_str().unwrap()]);
    assert_one_line_error(
        "edited scene",
        code,
        &err,
        1,
        &["c.kfilm", "another render"],
    );
}

/// Film files checked whole: a flipped bit, bytes after the end, an old version; and the
/// options a film part cannot hold are named.
#[test]
fn damaged_films_and_film_outputs_are_refused() {
    let d = temp_dir("film-damage");
    let a = d.join("a.kfilm");
    let (code, err) = part("cornell", &a, &["--spp", "2"]);
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(&a).unwrap();
    let out = d.join("m.exr");
    let merge = |p: &Path| kalos(&["merge", p.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    // a bit of a pixel sum (the last pixel's, 100 bytes per pixel before the splat flag,
    // the end mark and the checksum)
    let mut flipped = bytes.clone();
    let at = bytes.len() - 8 - 4 - 1 - 50;
    flipped[at] ^= 0x10;
    let f = d.join("flipped.kfilm");
    std::fs::write(&f, &flipped).unwrap();
    let (code, _, err) = merge(&f);
    assert_one_line_error("bit flip", code, &err, 1, &["flipped.kfilm", "checksum"]);
    // bytes after the end, from a file as from memory
    let mut long = bytes.clone();
    long.extend_from_slice(b"xy");
    let l = d.join("long.kfilm");
    std::fs::write(&l, &long).unwrap();
    let (code, _, err) = merge(&l);
    assert_one_line_error("trailing", code, &err, 1, &["long.kfilm", "2 bytes after"]);
    // version 1 (no checksum): refused with the version
    let mut old = bytes.clone();
    old[10..14].copy_from_slice(&1u32.to_le_bytes());
    let o = d.join("old.kfilm");
    std::fs::write(&o, &old).unwrap();
    let (code, _, err) = merge(&o);
    assert_one_line_error("old version", code, &err, 1, &["old.kfilm", "version 1"]);
    // options a film part cannot hold
    let x = d.join("x.kfilm");
    let (code, err) = part("cornell", &x, &["--spp", "1", "--filter", "energy"]);
    assert_one_line_error("filter", code, &err, 1, &["--filter energy", ".kfilm"]);
    let (code, err) = part("cornell", &x, &["--spp", "1", "--method", "rw"]);
    assert_one_line_error("rw", code, &err, 1, &["--method rw", ".kfilm"]);
    assert!(!err.contains("dtf"), "{err}");
}
