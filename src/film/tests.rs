use super::*;

#[test]
fn moments_match_two_pass() {
    let xs = [1.0f32, 2.0, 4.0, 8.0, -3.0, 0.5];
    let mut p = PixelStats::default();
    for &x in &xs {
        p.push([x, 2.0 * x, 0.0]);
    }
    let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / xs.len() as f64;
    let var = xs.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
    assert!((p.mean()[0] - mean).abs() < 1e-12);
    assert!((p.variance()[0] - var).abs() < 1e-9);
    assert!((p.variance()[1] - 4.0 * var).abs() < 1e-8);
    assert_eq!(p.variance()[2], 0.0);
}

#[test]
fn merge_is_exact_in_any_order() {
    let vals: Vec<[f32; 3]> = (0..50)
        .map(|i| {
            [
                (i * i) as f32 * 0.013,
                (i as f32).sin() * 7.0,
                1e-3 / (1.0 + i as f32),
            ]
        })
        .collect();
    let mut all = PixelStats::default();
    vals.iter().for_each(|&v| all.push(v));
    let mut a = PixelStats::default();
    let mut b = PixelStats::default();
    for (i, &v) in vals.iter().enumerate().rev() {
        if i % 3 == 0 {
            a.push(v)
        } else {
            b.push(v)
        }
    }
    assert_eq!(b.merge(&a), all);
    assert_eq!(a.merge(&b), all);
}

#[test]
fn from_moments_round_trips() {
    let p = PixelStats::from_moments(16, [0.5, 0.25, 2.0], [0.6, 0.0, 3.0]);
    let m = p.mean();
    assert!((m[0] - 0.5).abs() < 1e-9 && (m[2] - 2.0).abs() < 1e-9);
    let m2 = p.m2();
    assert!((m2[0] - 0.6).abs() < 1e-6 && m2[1].abs() < 1e-6 && (m2[2] - 3.0).abs() < 1e-6);
}

#[test]
fn rejects_non_finite_samples() {
    let mut r = Rejections::default();
    assert!(r.check(&[1.0, 2.0, 3.0]));
    assert!(!r.check(&[f32::NAN, 2.0, 3.0]));
    assert!(!r.check(&[f32::INFINITY, 2.0, 3.0]));
    assert_eq!(
        r,
        Rejections {
            nan: 1,
            infinite: 1
        }
    );
}

#[test]
fn resolution_limits() {
    assert!(Film::new(0, 0).is_err());
    assert!(Film::new(4, 0).is_err());
    assert!(check_resolution(100_000, 100_000).is_err());
    assert!(Film::new(3, 2).is_ok());
}

#[test]
fn splats_and_batches() {
    // 2 x 1 film, 8 samples per pixel of value 1, and one light path per sample that
    // splats 4 into pixel 1: splat image = 4 x 16 / 16 ... per pixel 4 * 8 / (16 / 2).
    let mut f = Film::with_splats(2, 1).unwrap();
    for k in 0..8u32 {
        for p in 0..2 {
            f.add_sample(p, k, [1.0; 3]);
            let s = f.splats.as_mut().unwrap();
            s.add_light_path(k);
            if p == 1 {
                s.add_splat(1, k, [4.0, 0.0, 2.0]);
            }
        }
    }
    // 16 light paths, 2 pixels: pixel 1 gets 8 x 4 x 2 / 16 = 4.
    assert_eq!(f.value(0), [1.0, 1.0, 1.0]);
    assert_eq!(f.value(1), [5.0, 1.0, 3.0]);
    // Every batch sees the same image: batch variance 0.
    assert_eq!(f.variance_of_value(1), [0.0; 3]);
}

#[test]
fn film_file_round_trip_and_refusals() {
    let dir = std::env::temp_dir().join(format!("kalos-film-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut f = Film::with_splats(3, 2).unwrap();
    for k in 0..5 {
        f.add_sample(k % 6, k as u32, [k as f32, 0.5, -1.0]);
        f.splats.as_mut().unwrap().add_splat(2, k as u32, [0.25; 3]);
        f.splats.as_mut().unwrap().add_light_path(k as u32);
    }
    let ff = FilmFile {
        job: "{}".into(),
        key: "k".into(),
        ranges: vec![(0, 5)],
        film: f,
    };
    let p = dir.join("a.kfilm");
    write_film(&p, &ff).unwrap();
    let back = read_film(&p).unwrap();
    assert_eq!(back, ff);
    // truncated
    let bytes = std::fs::read(&p).unwrap();
    let t = dir.join("t.kfilm");
    for cut in [5, 20, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(&t, &bytes[..cut]).unwrap();
        let e = read_film(&t).unwrap_err();
        assert!(e.contains("t.kfilm"), "{e}");
    }
    // another version
    let mut v = bytes.clone();
    v[10] = 99;
    std::fs::write(&t, &v).unwrap();
    assert!(read_film(&t).unwrap_err().contains("version 99"));
    // another job, overlapping ranges
    let mut other = ff.clone();
    other.key = "other".into();
    other.ranges = vec![(5, 9)];
    let e = merge_files(&[("a".into(), ff.clone()), ("b".into(), other)]).unwrap_err();
    assert!(e.contains("another render"), "{e}");
    let mut over = ff.clone();
    over.ranges = vec![(3, 9)];
    let e = merge_files(&[("a".into(), ff.clone()), ("b".into(), over)]).unwrap_err();
    assert!(e.contains("overlap"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A film part in memory is the file's bytes: the same bytes, the same film back, and the
/// same refusals (truncated, another version, trailing bytes), named by the given name.
#[test]
fn film_bytes_are_the_file_and_refused_alike() {
    let dir = std::env::temp_dir().join(format!("kalos-film-bytes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for splats in [false, true] {
        let mut f = if splats {
            Film::with_splats(4, 3).unwrap()
        } else {
            Film::new(4, 3).unwrap()
        };
        for k in 0..7u32 {
            f.add_sample(k as usize % 12, k, [k as f32 * 0.3, 0.5, -1.0]);
            if let Some(s) = f.splats.as_mut() {
                s.add_splat(5, k, [0.125; 3]);
                s.add_light_path(k);
            }
        }
        let ff = FilmFile {
            job: r#"{"scene":"cornell"}"#.into(),
            key: "k".into(),
            ranges: vec![(8, 15)],
            film: f,
        };
        let bytes = film_to_bytes(&ff);
        let p = dir.join("b.kfilm");
        write_film(&p, &ff).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), bytes);
        assert_eq!(film_from_bytes(&bytes, "part 3").unwrap(), ff);
        for cut in [0, 5, 20, bytes.len() / 2, bytes.len() - 1] {
            let e = film_from_bytes(&bytes[..cut], "part 3").unwrap_err();
            assert!(e.starts_with("part 3: "), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let mut v = bytes.clone();
        v[10] = 99;
        assert!(film_from_bytes(&v, "p").unwrap_err().contains("version 99"));
        let mut long = bytes.clone();
        long.extend_from_slice(b"xy");
        let e = film_from_bytes(&long, "p").unwrap_err();
        assert!(e.contains("2 bytes after"), "{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
