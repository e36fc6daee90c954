//! Film file bytes (`.kfilm`): random bit flips, every truncation and forged fields
//! must be refused with an error, never merged into an image and never a panic.

use super::Rng;
use kalos::film::{film_from_bytes, film_to_bytes, merge_files, Film, FilmFile};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// A film part as a render writes it: `w` x `h`, `spp` samples per pixel from `first`,
/// with splats if asked.
fn part(w: u32, h: u32, first: u64, spp: u32, splats: bool, rng: &mut Rng) -> FilmFile {
    let mut f = if splats {
        Film::with_splats(w, h).unwrap()
    } else {
        Film::new(w, h).unwrap()
    };
    for k in 0..spp {
        for p in 0..(w * h) as usize {
            let v = (rng.next() % 1000) as f32 / 250.0;
            f.add_sample(p, (first + k as u64) as u32, [v, 0.5 * v, 0.25]);
            if let Some(s) = f.splats.as_mut() {
                s.add_splat((rng.next() % (w * h) as u64) as usize, k, [0.125; 3]);
                s.add_light_path(k);
            }
        }
    }
    FilmFile {
        job: r#"{"scene":"cornell"}"#.into(),
        key: "k".into(),
        ranges: vec![(first, first + spp as u64)],
        film: f,
    }
}

fn decode(bytes: &[u8], what: &str) -> Result<FilmFile, String> {
    catch_unwind(AssertUnwindSafe(|| film_from_bytes(bytes, "part")))
        .unwrap_or_else(|_| panic!("{what}: film_from_bytes panicked"))
}

/// Every single-bit flip anywhere in a film file is refused (the CRC-64 detects all of
/// them; 26 of 40 flips in the sums merged with exit 0 before it). Seed 0x6b66_696c_6d01,
/// 3000 flips over two films (with and without splats), and every truncation.
#[test]
fn flipped_bits_and_truncations_of_a_film_are_refused() {
    let mut rng = Rng(0x6b66_696c_6d01);
    for splats in [false, true] {
        let ff = part(3, 2, 4, 3, splats, &mut rng);
        let bytes = film_to_bytes(&ff);
        assert_eq!(decode(&bytes, "intact").unwrap(), ff);
        for run in 0..1500 {
            let mut b = bytes.clone();
            let bit = rng.below(b.len() * 8);
            b[bit / 8] ^= 1 << (bit % 8);
            let e = decode(&b, &format!("flip {run} (bit {bit})"));
            assert!(
                e.is_err(),
                "flip {run}: bit {bit} of {} accepted",
                bytes.len()
            );
            let e = e.unwrap_err();
            assert!(e.starts_with("part: ") && !e.contains('\n'), "{e}");
        }
        for cut in 0..bytes.len() {
            assert!(
                decode(&bytes[..cut], "cut").is_err(),
                "cut at {cut} accepted"
            );
        }
    }
}

/// A change to a film's fields.
type Forgery = Box<dyn Fn(&mut FilmFile)>;

/// Fields no render writes, re-encoded with a valid checksum (what a buggy or hostile
/// writer could produce): refused when read or when merged.
#[test]
fn forged_film_fields_are_refused() {
    let mut rng = Rng(0x6b66_696c_6d02);
    let base = part(2, 2, 10, 4, false, &mut rng);
    let forged = |f: &dyn Fn(&mut FilmFile)| {
        let mut x = base.clone();
        f(&mut x);
        decode(&film_to_bytes(&x), "forged")
    };
    let cases: Vec<(&str, Forgery)> = vec![
        ("reversed range", Box::new(|x| x.ranges = vec![(14, 10)])),
        ("empty range", Box::new(|x| x.ranges = vec![(10, 10)])),
        ("no range", Box::new(|x| x.ranges.clear())),
        (
            "overlapping ranges",
            Box::new(|x| x.ranges = vec![(10, 14), (12, 20)]),
        ),
        (
            "count near 2^32",
            Box::new(|x| x.film.pixels[1].n = u32::MAX - 1),
        ),
        (
            "sum near the i128 limit",
            Box::new(|x| x.film.pixels[0].sum[0] = i128::MAX - 5),
        ),
        (
            "negative sum of squares",
            Box::new(|x| x.film.pixels[3].sum_sq[2] = -1),
        ),
        ("sums without samples", Box::new(|x| x.film.pixels[2].n = 0)),
    ];
    for (what, f) in &cases {
        let e = forged(f.as_ref());
        assert!(e.is_err(), "{what}: accepted");
        assert!(e.unwrap_err().contains("damaged"), "{what}");
    }
    // 200 random forgeries of a count, a sum or a range (seed above): none panics, and
    // those read are merged without overflow or refused
    for run in 0..200 {
        let mut x = base.clone();
        let p = rng.below(4);
        let big = |r: &mut Rng| (r.next() as i128) << rng_shift(r);
        match rng.below(4) {
            0 => x.film.pixels[p].n = rng.next() as u32,
            1 => x.film.pixels[p].sum[rng.below(3)] = big(&mut rng),
            2 => x.film.pixels[p].sum_sq[rng.below(3)] = big(&mut rng),
            _ => x.ranges = vec![(rng.next() % 64, rng.next() % 64)],
        }
        if let Ok(f) = decode(&film_to_bytes(&x), &format!("random {run}")) {
            let mut y = f.clone();
            y.ranges = vec![(1000, 1000 + 64)];
            let r = catch_unwind(AssertUnwindSafe(|| {
                merge_files(&[("a".into(), f), ("b".into(), y)])
            }));
            assert!(r.is_ok(), "random {run}: merge panicked");
        }
    }
    // two valid parts whose counts together pass 2^32 - 1: refused, not wrapped
    let mut a = base.clone();
    a.ranges = vec![(0, 3_000_000_000)];
    a.film.pixels[0].n = 3_000_000_000;
    let mut b = a.clone();
    b.ranges = vec![(3_000_000_000, 6_000_000_000)];
    let (a, b) = (
        decode(&film_to_bytes(&a), "a").unwrap(),
        decode(&film_to_bytes(&b), "b").unwrap(),
    );
    let e = merge_files(&[("a".into(), a), ("b".into(), b)]).unwrap_err();
    assert!(e.contains("overflow"), "{e}");
}

/// A shift of 0..=64 bits for forged sums (small to near the i128 limit).
fn rng_shift(r: &mut Rng) -> u32 {
    (r.next() % 65) as u32
}
