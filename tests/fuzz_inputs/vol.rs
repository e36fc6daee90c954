//! Mitsuba grid volumes (`.vol`, the `sdfgrid` shape's distances) with flipped and
//! truncated bytes: a grid, or a one-line error; never a panic or an allocation the
//! file's length does not justify; a grid that reads is traced without a panic.

use super::*;
use kalos::accel::{SdfGrid, SdfShapes};
use kalos::math::{Ray, Vec3};
use kalos::scene::mitsuba::vol::parse_vol;

/// A 4 x 3 x 3 grid of the distance to a plane across it.
fn seed() -> Vec<u8> {
    let mut b = b"VOL\x03".to_vec();
    for v in [1i32, 4, 3, 3, 1] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for i in 0..36 {
        b.extend_from_slice(&((i % 4) as f32 - 1.5).to_le_bytes());
    }
    b
}

#[test]
fn mutated_vol_never_panics() {
    let seed = seed();
    let g = parse_vol(&seed).unwrap();
    assert_eq!(g.res, [4, 3, 3]);
    let mut rng = Rng(0x7012_7012_0000_0001);
    let mut traced = 0;
    for k in 0..400 {
        let mut b = seed.clone();
        if k % 2 == 0 {
            for _ in 0..1 + rng.below(4) {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
            }
        } else {
            b.truncate(rng.below(b.len()));
        }
        let input = format!("{b:?}");
        no_panic("vol", &input, || match parse_vol(&b) {
            Err(e) => assert!(!e.contains('\n'), "{e}"),
            Ok(v) => {
                assert_eq!(
                    v.data.len() as u64,
                    v.res.iter().map(|&r| r as u64).product::<u64>() * v.channels as u64
                );
                if v.channels != 1 {
                    return;
                }
                match SdfGrid::new(v.res, v.data) {
                    Err(e) => assert!(!e.contains('\n'), "{e}"),
                    Ok(g) => {
                        let s = SdfShapes::build(&[(
                            std::sync::Arc::new(g),
                            glam::Mat4::IDENTITY,
                            true,
                        )])
                        .unwrap();
                        for i in 0..16 {
                            let o = Vec3::new(-1.0, 0.1 * i as f32, 0.5);
                            let r = Ray::new(o, Vec3::new(1.0, 0.03 * i as f32, 0.01));
                            if let Some(h) = s.intersect(&r, f32::INFINITY) {
                                let _ = s.shading_normal(&h);
                            }
                        }
                        traced += 1;
                    }
                }
            }
        });
    }
    assert!(traced >= 20, "{traced} of 400 traced");
}
