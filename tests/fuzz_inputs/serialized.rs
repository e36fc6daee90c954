//! Mitsuba `.serialized` meshes with flipped, truncated and re-compressed bytes: a mesh
//! whose indices are in range, or a one-line error; never a panic or an allocation the
//! file's length does not justify.

use super::*;
use kalos::scene::serialized::parse_serialized;
use std::io::{Read, Write};

/// Two shapes (version 4): a quad with normals and uvs, and a triangle in double precision.
fn seed() -> Vec<u8> {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for (flags, nv, nf) in [(0x1003u32, 4u64, 2u64), (0x2000, 3, 1)] {
        let mut raw = flags.to_le_bytes().to_vec();
        raw.extend_from_slice(b"fuzz\0");
        raw.extend_from_slice(&nv.to_le_bytes());
        raw.extend_from_slice(&nf.to_le_bytes());
        let dims = if flags & 3 == 3 { 8 } else { 3 };
        for i in 0..nv * dims {
            let v = (i % 5) as f32 * 0.5;
            if flags & 0x2000 != 0 {
                raw.extend_from_slice(&(v as f64).to_le_bytes());
            } else {
                raw.extend_from_slice(&v.to_le_bytes());
            }
        }
        for i in [0u32, 1, 2, 0, 2, 3].iter().take(nf as usize * 3) {
            raw.extend_from_slice(&i.to_le_bytes());
        }
        offsets.push(out.len() as u64);
        out.extend_from_slice(&0x041Cu16.to_le_bytes());
        out.extend_from_slice(&4u16.to_le_bytes());
        out.extend(compress(&raw));
    }
    for o in &offsets {
        out.extend_from_slice(&o.to_le_bytes());
    }
    out.extend_from_slice(&(offsets.len() as u32).to_le_bytes());
    out
}

fn compress(raw: &[u8]) -> Vec<u8> {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(raw).unwrap();
    z.finish().unwrap()
}

#[test]
fn mutated_serialized_never_panics() {
    let seed = seed();
    assert_eq!(parse_serialized(&seed, 0).unwrap().triangles.len(), 2);
    assert_eq!(parse_serialized(&seed, 1).unwrap().triangles.len(), 1);
    let first_end = seed.len() - 8 * 2 - 4;
    let mut rng = Rng(0x5e71_a112_ed00_0001);
    let mut loaded = 0;
    for k in 0..400 {
        let mut b = seed.clone();
        match k % 4 {
            // flip bytes anywhere (header, stream, dictionary)
            0 => {
                for _ in 0..1 + rng.below(4) {
                    let i = rng.below(b.len());
                    b[i] = rng.next() as u8;
                }
            }
            // truncate
            1 => b.truncate(rng.below(b.len())),
            // flip bytes of the first shape's payload and compress it again (counts,
            // flags and indices that lie, in a valid stream)
            2 => {
                let mut raw = Vec::new();
                flate2::read::ZlibDecoder::new(&b[4..first_end])
                    .read_to_end(&mut raw)
                    .unwrap();
                for _ in 0..1 + rng.below(3) {
                    let i = rng.below(raw.len().min(40));
                    raw[i] = rng.next() as u8;
                }
                let mut m = b[..4].to_vec();
                m.extend(compress(&raw));
                b = m;
            }
            _ => {}
        }
        let index = [0, 1, 2, -1][rng.below(4)];
        let text = format!("{b:?} shape {index}");
        no_panic("serialized", &text, || match parse_serialized(&b, index) {
            Ok(m) => {
                loaded += 1;
                let n = m.positions.len() as u32;
                assert!(m.triangles.iter().flatten().all(|&i| i < n));
            }
            Err(e) => assert!(!e.contains('\n'), "{e}"),
        });
    }
    assert!((20..=380).contains(&loaded), "{loaded} of 400 loaded");
}
